"""Command-line interface: ``bldclab <command> [options]``.

Every subcommand is a :class:`Command`: a name, a one-line help, a function that declares its arguments
and a function that runs it and returns the exit code. They are registered in :data:`COMMANDS`, the one place
to add a new one. :func:`main` owns the error handling for all of them: a bad argument or a
:class:`BldclabError` prints one line ``bldclab: error: <message>`` on stderr and exits with status 2, without
a traceback.

Files are written atomically (a temporary file in the target directory, then :func:`os.replace`), after every
result has been computed, so an error leaves no half-written output.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import os
import sys
import tempfile
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import __version__, analytic
from . import report as _report
from . import sweep as _sweep
from .catalog import load, names
from .cli_sim import (
    configure_compare,
    configure_faults,
    configure_simulate,
    configure_torque_control,
    run_compare,
    run_faults,
    run_simulate,
    run_torque_control,
)
from .errors import BldclabError, PlausibilityWarning
from .identify import configure_cli as _configure_identify
from .identify import run_cli as _run_identify

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["COMMANDS", "Command", "build_parser", "main", "table1_text", "write_files"]

PROG = "bldclab"


class _UsageError(Exception):
    """A command-line argument is wrong (raised instead of argparse's print-usage-and-exit)."""


class _Parser(argparse.ArgumentParser):
    """Argument parser that raises :class:`_UsageError` instead of printing the usage and exiting."""

    def error(self, message: str) -> None:  # type: ignore[override]
        """Raise the parsing error for :func:`main` to report on one line."""
        raise _UsageError(message)


@dataclass(frozen=True)
class Command:
    """One subcommand.

    Parameters
    ----------
    name : str
        What the user types after ``bldclab``.
    help : str
        One line for ``bldclab --help``.
    configure : callable
        ``configure(parser)`` adds the subcommand's arguments to its parser.
    run : callable
        ``run(args) -> int`` does the work and returns the exit status.

    """

    name: str
    help: str
    configure: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


# ------------------------------------------------------------------------------------------------------------
# shared helpers


def _int_at_least(lo: int) -> Callable[[str], int]:
    """Return an argparse type: an integer >= ``lo``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < lo:
            raise argparse.ArgumentTypeError(f"must be >= {lo}, got {value}")
        return value

    return parse


def write_files(out_dir: Path, files: dict[str, bytes]) -> list[Path]:
    """Write files into a directory, each atomically (temporary file in the directory, then rename).

    Parameters
    ----------
    out_dir : Path
        Target directory, created (with parents) if missing.
    files : dict of str to bytes
        File name (no directory part) to content.

    Returns
    -------
    list of Path
        The written paths, in the order given.

    Raises
    ------
    BldclabError
        If the directory cannot be created or a file cannot be written (field ``--out``); a file that failed
        is not left behind, neither complete nor partial.

    """
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BldclabError("--out", f"cannot create directory {str(out_dir)!r}: {exc.strerror or exc}"
                           ) from None
    umask = os.umask(0o022)
    os.umask(umask)
    mode = 0o666 & ~umask
    written = []
    for name, content in files.items():
        target = out_dir / name
        tmp_name = None
        try:
            fd, tmp_name = tempfile.mkstemp(dir=out_dir, prefix=f".{name}.", suffix=".tmp")
            os.chmod(tmp_name, mode)  # mkstemp makes 0600 files; give the usual permissions
            with os.fdopen(fd, "wb") as fh:
                fh.write(content)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp_name, target)
            tmp_name = None
        except OSError as exc:
            raise BldclabError("--out", f"cannot write {str(target)!r}: {exc.strerror or exc}") from None
        finally:
            if tmp_name is not None and os.path.exists(tmp_name):
                os.unlink(tmp_name)
        written.append(target)
    return written


# ------------------------------------------------------------------------------------------------------------
# analyze


def _fmt_value(value: float | bool) -> str:
    """Format a table value for people: yes/no for flags, n/a for NaN, 6 significant digits otherwise."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if math.isnan(value):
        return "n/a"
    return f"{value:.6g}"


def _json_value(value: float | bool) -> float | bool | None:
    """Return a JSON-safe value: NaN (a quantity undefined for this motor) becomes null."""
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def table1_text(t: analytic.Table1, fmt: str, not_applicable: Sequence[str] = ()) -> str:
    """Render a :class:`~bldclab.analytic.Table1` as ``table`` (aligned text), ``csv`` or ``json``.

    Parameters
    ----------
    t : Table1
        The quantities.
    fmt : {"table", "csv", "json"}
        Output format.
    not_applicable : sequence of str
        Why the closed forms do not describe the drive (:func:`bldclab.analytic.applicability`): one line each
        under the table, a ``not_applicable`` list in JSON (CSV: not written, the file stays one table).

    Returns
    -------
    str
        The text, ending with a newline.

    """
    rows = t.rows()  # NaN marks a quantity that is undefined for this motor (e.g. (40) above its base speed)
    if fmt == "json":
        doc = {"motor": t.name,
               "quantities": [{"key": k, "description": d, "value": _json_value(v), "unit": u, "source": s}
                              for k, d, v, u, s in rows],
               "not_applicable": list(not_applicable)}
        return json.dumps(doc, indent=2, allow_nan=False) + "\n"
    if fmt == "csv":
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["key", "description", "value", "unit", "source"])
        for k, d, v, u, s in rows:
            w.writerow([k, d, repr(v) if not isinstance(v, bool) else str(v).lower(), u, s])
        return buf.getvalue()
    if fmt != "table":
        raise BldclabError("--format", f"unknown format {fmt!r}")
    head = ("key", "quantity", "value", "unit", "source")
    body = [(k, d, _fmt_value(v), u, s) for k, d, v, u, s in rows]
    widths = [max(len(r[j]) for r in [head, *body]) for j in range(len(head))]
    lines = [f"Paper 1 Table I and derived quantities: {t.name or '(unnamed drive)'}"]
    for r in [head, *body]:
        lines.append("  ".join(c.rjust(widths[j]) if j == 2 else c.ljust(widths[j])
                               for j, c in enumerate(r)).rstrip())
    if not_applicable:
        lines.append("The closed forms (sources (13) to (44)) are outside paper 1's premises for this drive:")
        lines += [f"  - {reason}" for reason in not_applicable]
    return "\n".join(lines) + "\n"


def _figure_bytes(fig: Figure, fmt: str) -> bytes:
    """Render a matplotlib figure to PNG or SVG bytes (SVG without a date, so reruns give equal files)."""
    buf = io.BytesIO()
    meta = {"Date": None} if fmt == "svg" else {}
    fig.savefig(buf, format=fmt, dpi=150, metadata=meta)
    return buf.getvalue()


def _configure_analyze(p: argparse.ArgumentParser) -> None:
    p.add_argument("motor", metavar="MOTOR",
                   help=f"built-in drive ({', '.join(names())}) or path of a TOML motor file")
    p.add_argument("--out", metavar="DIR", type=Path,
                   help="also write table1.csv, table1.json, characteristic.csv and the Fig 7/8 plots "
                   "(PNG and SVG) into DIR (created if missing)")
    p.add_argument("--format", choices=("table", "csv", "json"), default="table",
                   help="format of Table I on stdout (default: table)")
    p.add_argument("--speeds", metavar="N", type=_int_at_least(2), default=101,
                   help="evenly spaced speeds in [0, 1] Omega_0 for the characteristic, to which the region "
                   "boundaries 0.5, Omega_sB and Omega_qB are added (default: 101)")


def _run_analyze(args: argparse.Namespace) -> int:
    if args.out is not None and args.out.exists() and not args.out.is_dir():
        raise BldclabError("--out", f"{str(args.out)!r} exists and is not a directory")
    drive = load(args.motor)
    t = analytic.table1(drive)
    reasons = analytic.applicability(drive)
    text = table1_text(t, args.format, reasons)
    if args.out is not None:
        from . import plots  # matplotlib only when figures are asked for

        speeds = np.unique(np.concatenate([np.linspace(0.0, 1.0, args.speeds),
                                           [0.5, t.Omega_sB_pu, t.Omega_qB_pu]]))
        df = analytic.characteristic(drive, speeds)
        files: dict[str, bytes] = {
            "table1.csv": table1_text(t, "csv").encode(),
            "table1.json": table1_text(t, "json", reasons).encode(),
            "characteristic.csv": df.to_csv(index=False, lineterminator="\n").encode(),
        }
        title = f" - {drive.name}" if drive.name else ""
        fig7, _ = plots.plot_torque_speed(df, title=f"Torque-speed characteristic (paper 1 Fig. 7){title}")
        fig8, _ = plots.plot_ripple(df, title=f"Torque ripple (paper 1 Fig. 8){title}")
        for stem, fig in (("fig7_torque_speed", fig7), ("fig8_ripple", fig8)):
            for ext in ("png", "svg"):
                files[f"{stem}.{ext}"] = _figure_bytes(fig, ext)
        write_files(args.out, files)
    sys.stdout.write(text)
    return 0


# ------------------------------------------------------------------------------------------------------------
# registry and entry point

#: The subcommands, in the order ``bldclab --help`` lists them. Add new ones here.
COMMANDS: tuple[Command, ...] = (
    Command("analyze", "paper 1 closed forms for a motor: Table I, characteristics, Figs 7-8",
            _configure_analyze, _run_analyze),
    Command("sweep", "run many simulations (grid or list of cases) on processes or Dask into a resumable store",
            _sweep.configure_command, _sweep.run_command),
    Command("identify", "back-EMF tables from a constant-speed waveform (paper 2)", _configure_identify, _run_identify),
    Command("simulate", "one switching-level simulation: square, sine, sixv, lu, lu-no-do or rect control",
            configure_simulate, run_simulate),
    Command("compare", "square-wave vs sinusoidal supply: closed forms and simulation over speed (paper 1)",
            configure_compare, run_compare),
    Command("torque-control", "paper 2's torque control vs its baselines over a load x speed grid",
            configure_torque_control, run_torque_control),
    Command("faults", "inject sensor, bus and phase faults: detection, time to safe state, peak current",
            configure_faults, run_faults),
    Command("report", "one self-contained HTML report of a comparison (a results directory, or a motor to run)",
            _report.configure_command, _report.run_command),
)


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser with every subcommand of :data:`COMMANDS`.

    Returns
    -------
    argparse.ArgumentParser

    """
    parser = _Parser(prog=PROG, description="Simulate, analyse and control PM brushless DC motor drives.")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for cmd in COMMANDS:
        p = sub.add_parser(cmd.name, help=cmd.help, description=cmd.help)
        cmd.configure(p)
        p.set_defaults(run=cmd.run)
    return parser


def _one_line(text: str) -> str:
    """Collapse a message onto one line."""
    return " ".join(str(text).split())


def _show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                  file: object = None, line: str | None = None) -> None:
    """Show a plausibility warning as one line ``bldclab: warning: <message>`` on stderr; others as usual."""
    if issubclass(category, PlausibilityWarning):
        sys.stderr.write(f"{PROG}: warning: {_one_line(str(message))}\n")
    else:
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        Exit status: 0 on success, 2 for a bad argument or bad input (one line on stderr), including a simulation
        whose result would be physically meaningless (:class:`~bldclab.errors.PlausibilityError`), 130 if
        interrupted. Plausibility warnings go to stderr, one line each.

    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        with warnings.catch_warnings():
            warnings.simplefilter("always", PlausibilityWarning)
            warnings.showwarning = _show_warning
            return int(args.run(args))
    except SystemExit as exc:  # --help, --version
        return exc.code if isinstance(exc.code, int) else 0  # argparse exits 0 after printing help
    except (_UsageError, BldclabError) as exc:
        sys.stderr.write(f"{PROG}: error: {_one_line(str(exc))}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write(f"{PROG}: interrupted\n")
        return 130


if __name__ == "__main__":
    raise SystemExit(main())

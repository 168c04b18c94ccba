"""``bldclab report``: the self-contained HTML report of a results directory, or of a motor it runs."""

from __future__ import annotations

import argparse
import math
import shlex
import sys
from pathlib import Path

from .._files import write_files
from ..analysis.compare import speed_grid
from ..errors import BldclabError
from ..model.catalog import load
from ..model.limits import TOP_SPEED_PU
from ..report.bundle import motor_results, read_results
from ..report.html import REPORT, WAVEFORM_SPEEDS, Results, render
from .common import check_speed_range, positive_int
from .paths import check_out_file

__all__ = [
    "configure_command",
    "run_command",
]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab report``."""
    p.add_argument("source", metavar="RESULTS_DIR|MOTOR",
                   help="a directory written by bldclab compare, or a motor (built-in name or TOML file): then the "
                   "comparison is run first")
    p.add_argument("--out", type=Path, help="the HTML file (default: RESULTS_DIR/report.html, or "
                   "out/<motor>/report.html for a motor)")
    p.add_argument("--speeds", type=int, help="motor only: speeds per supply (default 32)")
    p.add_argument("--min-speed", type=float, help="motor only: lowest speed, p.u. of Omega_0 (default 0.05)")
    p.add_argument("--max-speed", type=float,
                   help=f"motor only: highest speed, p.u. of Omega_0 (default {TOP_SPEED_PU:g})")
    p.add_argument("--waveform-speeds", help='motor only: per-unit speeds of the waveform panels (default "0.3,0.8")')
    p.add_argument("--torque-control", action="store_true",
                   help="motor only: also compare paper 2's torque control methods (table and torque traces)")
    p.add_argument("--workers", type=positive_int, help="motor only: processes, >= 1 (default: all cores; 1: serial)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _speeds_list(text: str) -> list[float]:
    try:
        values = [float(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise BldclabError("--waveform-speeds", f"expected per-unit speeds separated by commas, got {text!r}") from None
    if not values or any(not math.isfinite(v) or not 0 < v < 1.5 for v in values):
        raise BldclabError("--waveform-speeds", f"needs per-unit speeds in (0, 1.5), got {text!r}")
    return values


def _motor_only(args: argparse.Namespace) -> list[str]:
    given = [("--speeds", args.speeds), ("--min-speed", args.min_speed), ("--max-speed", args.max_speed),
             ("--waveform-speeds", args.waveform_speeds)]
    out = [name for name, v in given if v is not None]
    if args.torque_control:
        out.append("--torque-control")
    if args.workers is not None:
        out.append("--workers")
    return out


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab report``: read or run a comparison, write one HTML file."""
    src = Path(args.source)
    if src.is_dir():
        extra = _motor_only(args)
        if extra:
            raise BldclabError(extra[0], "applies to a motor; a results directory is reported as it is")
        out = args.out if args.out is not None else src / REPORT
        results = Results.from_files(read_results(src), source=str(src))
        parts = ["bldclab", "report", str(src), "--out", str(out)]
    else:
        drive = load(args.source)
        n = 32 if args.speeds is None else args.speeds
        lo = 0.05 if args.min_speed is None else args.min_speed
        hi = TOP_SPEED_PU if args.max_speed is None else args.max_speed
        if n < 2:
            raise BldclabError("--speeds", f"needs at least 2, got {n}")
        check_speed_range(lo, hi)
        wspeeds = _speeds_list(args.waveform_speeds) if args.waveform_speeds is not None else list(WAVEFORM_SPEEDS)
        out = args.out if args.out is not None else Path("out") / drive.name / REPORT
        check_out_file(out / REPORT if out.is_dir() else out)  # before the simulations
        parts = ["bldclab", "report", str(args.source), "--out", str(out), "--speeds", str(n), "--min-speed",
                 f"{lo:g}", "--max-speed", f"{hi:g}", "--waveform-speeds", ",".join(f"{v:g}" for v in wspeeds)]
        if args.torque_control:
            parts.append("--torque-control")
        command = shlex.join(parts)
        files = motor_results(drive, speed_grid(n, lo, hi), command=command, motor_source=str(args.source),
                              workers=args.workers, waveform_speeds=wspeeds,
                              torque_control=args.torque_control,
                              progress=not args.no_progress and sys.stderr.isatty())
        results = Results.from_files(files, source=f"a comparison run by this command ({drive.name})")
    if out.exists() and out.is_dir():
        out = out / REPORT
    text = render(results, report_command=shlex.join(parts))
    (path,) = write_files(out.parent, {out.name: text.encode()})
    print(f"wrote {path} ({len(text.encode()) / 1024:.0f} kB)")
    return 0

"""``bldclab analyze``: paper 1's closed forms for a motor (Table I, characteristics, Figs 7-8)."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .._files import write_files
from ..model import analytic
from ..model.analytic.table import table1_text
from ..model.catalog import load, names
from ..model.motor import Drive
from ..report import plots
from .paths import check_out_dir

__all__ = [
    "configure_command",
    "run_command",
]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab analyze``."""
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


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab analyze``: print Table I, write the tables and figures with ``--out``."""
    check_out_dir(args.out)
    drive = load(args.motor)
    t = analytic.table1(drive)
    reasons = analytic.applicability(drive)
    text = table1_text(t, args.format, reasons)
    if args.out is not None:

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
                files[f"{stem}.{ext}"] = plots.figure_bytes(fig, ext, dpi=150, dated=False)
        write_files(args.out, files)
    sys.stdout.write(text)
    if args.format == "table":  # csv and json stay machine-readable
        sys.stdout.write(analytic.commutation_premise(drive)[0] + "\n")
        sys.stdout.write(_speeds_in_rpm(drive, t) + "\n")
    return 0


def _speeds_in_rpm(drive: Drive, t: analytic.Table1) -> str:
    """Return one line with the table's speeds in rad/s and rpm."""
    w0 = drive.Omega_0

    def both(pu: float) -> str:
        return f"{pu * w0:.4g} rad/s = {pu * w0 * 30.0 / math.pi:.4g} rpm"

    return (f"speeds: Omega_0 {both(1.0)}; base speed sinusoidal (21) {both(t.Omega_sB_pu)}, square-wave (30) "
            f"{both(t.Omega_qB_pu)}; with R {both(t.Omega_sB_R_pu)} / {both(t.Omega_qB_R_pu)}")


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

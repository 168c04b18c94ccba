"""``bldclab torque-control``: paper 2's torque control against its baselines over a load x speed grid."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from .._files import write_files
from ..analysis import paper2
from ..errors import BldclabError
from ..model.units import to_si
from ..report import plots
from ..sim import plausibility as _plaus
from .common import add_inverter_option, load_drive, parse_speed, summarise
from .paths import check_out_dir

__all__ = ["configure_command", "run_command"]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab torque-control``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file (e.g. lu-4kw)")
    p.add_argument("--torques", default="25%,50%,100%",
                   help='torque references: percentages of T_N or torques, comma separated (default "25%%,50%%,100%%")')
    p.add_argument("--speeds", default="",
                   help='imposed speeds, comma separated ("1000 rpm,3000 rpm" or "0.5 pu"); default 1/3, 2/3, 1 of '
                        "the rated speed")
    p.add_argument("--methods", default="rect,lu-no-do,lu", help="methods among rect, lu-no-do, lu")
    p.add_argument("--out", type=Path, help="write methods.csv and paper 2's Figs 10-12 here")
    add_inverter_option(p)


def _list(text: str, parse: Any, field: str) -> list[float]:
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        raise BldclabError(field, "needs at least one value")
    return [parse(t) for t in items]


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab torque-control``: paper 2's methods compared over a load x speed grid."""
    drive = load_drive(args)
    check_out_dir(args.out)  # before the simulations

    def torque(t: str) -> float:
        if t.endswith("%"):
            try:
                return float(t[:-1]) / 100.0 * drive.T_N
            except ValueError:
                raise BldclabError("--torques", f"cannot read {t!r}") from None
        return to_si(t, "torque", "--torques")

    torques = _list(args.torques, torque, "--torques")
    if args.speeds:
        speeds = _list(args.speeds, lambda t: parse_speed(t, drive, "--speeds"), "--speeds")
    else:
        speeds = list(paper2.default_grid(drive)[1])
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    for method in methods:
        if method not in paper2.METHODS:
            raise BldclabError("--methods", f"unknown method {method!r}; choose from {', '.join(paper2.METHODS)}")
    if not methods:
        raise BldclabError("--methods", "needs at least one method")
    for option, values in (("--torques", torques), ("--speeds", speeds)):
        for v in values:
            if not (math.isfinite(v) and v > 0):
                raise BldclabError(option, f"needs values > 0, got {v:g} (SI)")
    with _plaus.collect() as caught:
        table = paper2.compare_methods(drive, torques, speeds, methods)
    summarise(caught, len(table))
    print(f"{drive.name}: torque control methods (paper 2); ripple in % of the mean torque, dip of the "
          "non-commutated current")
    cols = ["method", "torque_pct", "speed_rad_s", "speed_rpm", "tau_mean_pct_ref", "dcm_pct", "ripple_pp",
            "ripple_rms", "ripple_ma_pp", "ripple_ma_rms", "dip_A", "dip_pct"]
    shown = table.assign(dcm_pct=100.0 * table["dcm_share"], speed_rad_s=table["speed"])
    print(shown[cols].to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    print("  (speed_rad_s, speed_rpm: the imposed speed; "
          "tau_mean_pct_ref: mean torque in % of the reference; dcm_pct: % of the time without phase current, "
          "discontinuous conduction within the PWM period)")
    for _, row in table.iterrows():
        cause = paper2.shortfall_cause(row)
        if cause is not None:
            print(f"bldclab: warning: {row['method']} at {row['torque_pct']:.0f} % of T_N, {row['speed_rpm']:.0f} rpm: "
                  f"{cause}", file=sys.stderr)
    if args.out is not None:
        files = {"methods.csv": table.to_csv(index=False).encode()}
        tq, om = max(torques), max(speeds)
        for name, fn in (("fig10_rect", paper2.fig10), ("fig11_lu_no_do", paper2.fig11), ("fig12_lu", paper2.fig12),
                         ("methods_compared", paper2.fig_compare)):
            fig = fn(drive, tq, om)
            files[f"{name}.png"] = plots.figure_bytes(fig, "png")
            files[f"{name}.svg"] = plots.figure_bytes(fig, "svg")
        for path in write_files(args.out, files):
            print(f"wrote {path}")
    return 0

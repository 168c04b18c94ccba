"""``bldclab hall``: mean torque, ripple and efficiency of each supply against the Hall sensors' placement error."""

from __future__ import annotations

import argparse
import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from .._files import write_files
from ..analysis.hall import CASES, DEFAULT_ERRORS_DEG, hall_study
from ..errors import BldclabError
from ..model.units import to_si
from ..report.hall_plots import plot_hall_study
from ..report.plots import figure_bytes
from ..sim import plausibility as _plaus
from .common import add_inverter_option, load_drive, parse_speed, positive_int
from .paths import check_out_dir

__all__ = ["configure_command", "run_command"]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab hall``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--out", type=Path, help="directory for hall.csv and hall.png/svg (default out/<motor>-hall)")
    p.add_argument("--errors", default=",".join(f"{e:g}" for e in DEFAULT_ERRORS_DEG),
                   help="placement errors, degrees electrical, comma separated, each in [0, 30) (default "
                        "%(default)s)")
    p.add_argument("--cases", default=",".join(CASES),
                   help="error patterns: one (sensor a), common (all, same sign), alternating (+, -, +) "
                        "(default %(default)s)")
    p.add_argument("--speed", default="0.5 pu", help='imposed speed ("0.5 pu" of Omega_0, "300 rpm", rad/s; '
                                                     "default 0.5 pu)")
    p.add_argument("--torque", default="100%", help='torque reference: percentage of T_N or a torque ("20 N m"); '
                                                    "default 100%%")
    p.add_argument("--workers", type=positive_int, default=1, help="processes, >= 1 (default 1: serial)")
    add_inverter_option(p)


def _torque(text: str, T_N: float) -> float:
    t = text.strip()
    if t.endswith("%"):
        try:
            return float(t[:-1]) / 100.0 * T_N
        except ValueError:
            raise BldclabError("--torque", f"cannot read {text!r}") from None
    return to_si(t, "torque", "--torque")


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab hall``."""
    drive = load_drive(args)
    try:
        errors = [float(e) for e in args.errors.split(",") if e.strip()]
    except ValueError:
        raise BldclabError("--errors", f"cannot read {args.errors!r}: numbers in degrees, comma separated") from None
    if not errors or not all(0.0 <= e < 30.0 for e in errors):
        raise BldclabError("--errors", f"needs numbers in [0, 30) degrees, got {args.errors!r}")
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    bad = [c for c in cases if c not in CASES]
    if not cases or bad:
        raise BldclabError("--cases", f"must be from {', '.join(CASES)}, got {args.cases!r}")
    speed = parse_speed(args.speed, drive)
    if not math.isfinite(speed) or speed == 0.0:
        raise BldclabError("--speed", f"must be a finite non-zero speed, got {args.speed!r}")
    torque = _torque(args.torque, drive.T_N)
    if not math.isfinite(torque) or torque == 0.0:
        raise BldclabError("--torque", f"must be a finite non-zero torque, got {args.torque!r}")
    out = args.out if args.out is not None else Path("out") / f"{drive.name}-hall"
    check_out_dir(out)  # before the simulations
    rad = [math.radians(e) for e in errors]
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as ex:
            res = hall_study(drive, errors=rad, cases=cases, speed=speed, torque=torque, executor=ex)
    else:
        res = hall_study(drive, errors=rad, cases=cases, speed=speed, torque=torque)
    print(f"{drive.name}: Hall placement error study at {torque:.4g} N m ({torque / drive.T_N:.3g} T_N), "
          f"{speed * 30.0 / math.pi:.4g} rpm ({speed / drive.Omega_0:.3g} Omega_0), {len(res.points)} points in "
          f"{res.seconds:.1f} s")
    print("  tau/tau0: mean torque over the controller's at zero error; ripple: max - min of the torque at the "
          "controller samples, p.u. of T_N; eff: shaft over DC power")
    for line in res.table().splitlines():
        print(f"  {line}")
    for note in res.points.note[res.points.note != ""].unique():
        print(f"  note: {note}")
    summary = _plaus.summary(res.warnings, len(res.points))
    if summary:
        print(f"  {summary}")
    fig = plot_hall_study(res)
    files = {"hall.csv": res.points.to_csv(index=False).encode(), "hall.png": figure_bytes(fig, "png", dated=False),
             "hall.svg": figure_bytes(fig, "svg", dated=False)}
    for path in write_files(out, files):
        print(f"wrote {path}")
    return 0

"""``bldclab effmap``: efficiency and loss maps of both supplies over the torque-speed plane."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from .._files import write_files
from ..analysis.effmap import COMPARISON, FEASIBLE_TOL_PU, efficiency_map, map_controls
from ..control.sixstep import CHOPPINGS
from ..errors import BldclabError
from ..model.motor import Drive
from ..model.units import to_si
from ..report.effmap_plots import effmap_figures
from ..report.plots import load_matplotlib
from ..sweep.effmap_store import EffMapStore
from ..sweep.store import Store
from .common import (
    add_inverter_option,
    add_verbose_option,
    check_speed_range,
    load_drive,
    positive_int,
    summarise,
    worker_pool,
    workers_of,
)
from .paths import check_out_dir

__all__ = ["configure_command", "run_command"]

RPM_PER_RAD_S = 30.0 / math.pi


def configure_command(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab effmap``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--out", type=Path, help="directory for effmap.csv and the figures (default out/<motor>-effmap)")
    p.add_argument("--torques", type=positive_int, default=12, help="torque references, >= 2 (default 12)")
    p.add_argument("--speeds", type=positive_int, default=12, help="speeds, >= 2 (default 12)")
    p.add_argument("--min-torque", type=float, default=0.1, help="lowest torque, p.u. of T_N (default 0.1)")
    p.add_argument("--max-torque", type=float, default=1.0, help="highest torque, p.u. of T_N (default 1.0)")
    p.add_argument("--min-speed", type=float, default=0.05, help="lowest speed, p.u. of Omega_0 (default 0.05)")
    p.add_argument("--max-speed", type=float, default=0.95, help="highest speed, p.u. of Omega_0 (default 0.95)")
    p.add_argument("--generating", action="store_true",
                   help="map braking (negative torque references) instead of motoring")
    p.add_argument("--workers", type=positive_int, help="processes, >= 1 (default: all cores; 1: serial)")
    store = p.add_mutually_exclusive_group()
    store.add_argument("--store", metavar="DIR|FILE", type=Path,
                       help="results store (a sweep store: SQLite file, or a directory to hold effmap.sqlite; "
                            "default: effmap.sqlite in --out): points in it are not simulated again")
    store.add_argument("--no-store", action="store_true", help="keep no store: simulate every point")
    p.add_argument("--chopping", choices=CHOPPINGS, default="pwm-on-pwm",
                   help="square-wave supply's chopping pattern (default pwm-on-pwm; sync: the positive leg "
                        "complementary, no freewheeling through a diode in the off-time)")
    p.add_argument("--temperature", metavar="T",
                   help="map the drive hot: winding, magnets and switches at T (\"120 degC\", \"393 K\"; a number "
                        "is degC), R, the back-EMF and R_on by the [thermal] coefficients of the motor file "
                        "(docs/thermal.md); the controllers know the hot values")
    add_inverter_option(p)
    add_verbose_option(p)


def _store_path(out: Path, store: Path | None) -> Path:
    if store is None:
        return out / "effmap.sqlite"
    if store.is_dir():
        return store / "effmap.sqlite"
    if not store.parent.is_dir():
        raise BldclabError("--store", f"directory {str(store.parent)!r} does not exist")
    return store


def hot(drive: Drive, text: str) -> Drive:
    """Return ``drive`` with every part at the ``--temperature`` given (``Drive.at_temperature``)."""
    T = to_si(text, "temperature", "--temperature")
    if not math.isfinite(T) or T <= -273.15:
        raise BldclabError("--temperature", f"must be a finite temperature above absolute zero, got {text!r}")
    if drive.thermal is None:
        raise BldclabError("--temperature", f"drive {drive.name!r} has no [thermal] table in its motor file: no "
                           "temperature coefficients (docs/motor-files.md)")
    try:
        return drive.at_temperature(winding=T, magnets=T, switches=T)
    except BldclabError as exc:
        raise BldclabError("--temperature", f"{text!r}: {exc.problem}") from None


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab effmap``."""
    drive = load_drive(args)
    name, T_N, Omega_0 = drive.name, drive.T_N, drive.Omega_0  # the grid: the drive's bases at T_ref
    suffix = ""
    if args.temperature is not None:
        drive = hot(drive, args.temperature)
        suffix = f"-{to_si(args.temperature, 'temperature', '--temperature'):g}C"
    for name, n in (("--torques", args.torques), ("--speeds", args.speeds)):
        if n < 2:
            raise BldclabError(name, f"needs at least 2, got {n}")
    check_speed_range(args.min_speed, args.max_speed)
    if not 0 < args.min_torque < args.max_torque <= 5:
        raise BldclabError("--max-torque" if args.min_torque > 0 else "--min-torque",
                           f"needs 0 < --min-torque < --max-torque <= 5 p.u. of T_N, got {args.min_torque:g}, "
                           f"{args.max_torque:g}")
    out = args.out if args.out is not None else Path("out") / f"{name}-effmap{suffix}"
    check_out_dir(out)  # before the simulations: a bad --out fails in a second, not after the whole run
    sign = -1.0 if args.generating else 1.0
    torques = sign * np.linspace(args.min_torque, args.max_torque, args.torques) * T_N
    speeds = np.linspace(args.min_speed, args.max_speed, args.speeds) * Omega_0
    controls = map_controls(drive, float(np.min(speeds)), args.chopping)
    workers = workers_of(args.workers)
    load_matplotlib()  # before the pool starts: its workers draw the figures with it already loaded
    with worker_pool(workers) as pool:  # the points, then the figures
        if args.no_store:
            res = efficiency_map(drive, torques, speeds, workers=workers, executor=pool, controls=controls,
                                 summarise=False)
        else:
            path = _store_path(out, args.store)
            path.parent.mkdir(parents=True, exist_ok=True)
            with Store(path) as st:
                res = efficiency_map(drive, torques, speeds, workers=workers, executor=pool, controls=controls,
                                     cache=EffMapStore(st), summarise=False)
            print(f"store {path}: {res.cached} of {len(res.points)} points found there, "
                  f"{len(res.points) - res.cached} simulated")
        mode = "generating (braking)" if args.generating else "motoring"
        print(f"{drive.name}: efficiency map, {mode}, {args.torques} torques x {args.speeds} speeds x 2 supplies "
              f"(square wave: {args.chopping} chopping) in "
              f"{res.seconds:.1f} s (T_N = {drive.T_N:.4g} N m, Omega_0 = {drive.Omega_0 * RPM_PER_RAD_S:.4g} rpm; "
              f"a point is feasible when its mean torque is within {FEASIBLE_TOL_PU:g} T_N of the reference)")
        print(f"  {COMPARISON}")
        for line in res.summary():
            print(f"  {line}")
        print(f"  loss buckets: {', '.join(res.buckets)}")
        files: dict[str, bytes] = {"effmap.csv": res.points.to_csv(index=False).encode(),
                                   "effmap_difference.csv": res.difference.to_csv(index=False).encode()}
        files.update(effmap_figures(res, pool))
    for path in write_files(out, files):
        print(f"wrote {path}")
    summarise(res.warnings, len(res.points), args.verbose)  # one line for every point (--verbose: each one)
    return 0

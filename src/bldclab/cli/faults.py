"""``bldclab faults``: inject sensor, bus and phase faults; detection, time to safe state, peak current."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from .._files import write_files
from ..analysis.faults import detection_notes, fault_table
from ..control import SixStep
from ..errors import BldclabError
from ..model.catalog import load
from ..sim import plausibility as _plaus
from .common import control_of, parse_speed, summarise
from .paths import check_out_dir

__all__ = ["configure_command", "run_command"]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab faults``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--control", choices=("square", "sine", "lu"), default="square", help="controller")
    p.add_argument("--speed", default="0.5 pu", help='imposed speed (default "0.5 pu")')
    p.add_argument("--open-detect", type=float, default=0.1, metavar="F",
                   help="square: the controller's no-current-path test, a fraction of the reference (SixStep."
                        "open_detect; default 0.1, 0 for off)")
    p.add_argument("--out", type=Path, help="write faults.csv here")


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab faults``: each injected fault, detection, time to the safe state, peak current."""
    drive = load(args.motor)
    check_out_dir(args.out)  # before the simulations
    speed = parse_speed(args.speed, drive)
    ctl, ref, _ = control_of(args.control, drive, handoff=0.02 * drive.Omega_0)
    open_detect = 0.0
    if isinstance(ctl, SixStep):
        if not (args.open_detect == 0.0 or 0.0 < args.open_detect < 0.5):
            raise BldclabError("--open-detect", f"must be 0 (off) or a fraction in (0, 0.5), got {args.open_detect:g}")
        open_detect = args.open_detect
        ctl = dataclasses.replace(ctl, open_detect=open_detect)
    i_max = float(getattr(ctl, "i_max", None) or 2.0 * drive.motor.I_N)
    if args.control == "lu" and getattr(ctl, "i_max", None) is None:
        i_max = 3.0 * drive.motor.I_N
    with _plaus.collect() as caught:
        table = fault_table(drive, ctl, ref, speed, i_max=i_max)
    summarise(caught, len(table))
    trip = f", hardware trip {drive.inverter.i_trip:g} A" if drive.inverter.i_trip > 0 else ", no hardware trip"
    print(f"{drive.name}, {args.control} control at {speed / drive.Omega_0:.2f} p.u.: firmware over-current trip "
          f"{i_max:g} A{trip}; times from the fault in ms")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    for note in detection_notes(drive, i_max, open_detect):
        print(f"note: {note}")
    if args.out is not None:
        for path in write_files(args.out, {"faults.csv": table.to_csv(index=False).encode()}):
            print(f"wrote {path}")
    return 0

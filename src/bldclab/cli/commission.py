"""``bldclab commission MOTOR``: self-commissioning ("motor detection") on the plant.

R, L and the flux linkage the controller measures, against the motor file's values, with the time it takes
(docs/sensorless-sine.md).
"""

from __future__ import annotations

import argparse

from .._files import json_text
from ..analysis.commission import commission
from ..control.sine import fundamental_k1
from ..model.analytic import r_total
from .common import add_inverter_option, load_drive

__all__ = ["configure_command", "run_command"]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab commission``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--format", choices=("table", "json"), default="table", help="terminal output")
    add_inverter_option(p)


def run_command(args: argparse.Namespace) -> int:
    """Run the routine; exit 0 when it measured everything, 1 with its failure status named."""
    drive = load_drive(args)
    e = commission(drive)
    true = {"R": r_total(drive), "L": drive.motor.L, "psi_f": fundamental_k1(drive) / drive.motor.p}
    if args.format == "json":
        out = e.to_dict() | {"true": true}
        print(json_text(out))
    else:
        print(f"status        {e.status}")
        for key, unit in (("R", "Ohm"), ("L", "H"), ("psi_f", "V s")):
            v = getattr(e, key)
            err = f"{(v / true[key] - 1) * 100:+.3f} %" if v else "not measured"
            print(f"{key:6s} {unit:4s}  {v:.6g}  (motor file {true[key]:.6g}: {err})")
        print(f"time          {e.t_test:.3f} s on the drive, {e.wall_time:.2f} s to simulate")
    return 0 if e.ok else 1

"""``bldclab commission MOTOR``: self-commissioning ("motor detection") on the plant.

R, L and the flux linkage the controller measures, against the motor file's values, with the time it takes
(docs/sensorless-sine.md). ``--nominal`` configures the routine from other data than the plant's (a datasheet that
may be wrong); ``--out`` writes the estimated drive as a motor file, for ``bldclab simulate --estimate``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._files import json_text, write_atomic
from ..analysis.commission import commission
from ..control.sine import fundamental_k1
from ..model.analytic import r_total
from .common import add_inverter_option, load_drive, load_estimate
from .paths import check_out_file

__all__ = ["configure_command", "run_command"]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab commission``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--format", choices=("table", "json"), default="table", help="terminal output")
    p.add_argument("--nominal", metavar="DATA",
                   help="the data the routine is configured from (built-in name or motor TOML file: test currents, "
                        "timing, gains), e.g. a datasheet's; the plant stays MOTOR (default: MOTOR's own)")
    p.add_argument("--out", type=Path, metavar="FILE.toml",
                   help="write the estimated drive (DATA with the measured R, L and back-EMF amplitude) as a motor "
                        "file, for `bldclab simulate --estimate`; only when the routine ends DONE")
    add_inverter_option(p)


def run_command(args: argparse.Namespace) -> int:
    """Run the routine; exit 0 when it measured everything, 1 with its failure status named (no file written)."""
    check_out_file(args.out)  # before the run: a bad --out fails at once
    drive = load_drive(args)
    nominal = load_estimate(args.nominal, drive, "--nominal")
    e = commission(drive, nominal)
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
    if args.out is not None:
        if not e.ok:
            print(f"not written: {args.out} (the routine ended {e.status})", file=sys.stderr)
            return 1
        est = e.drive.replace(name=f"{e.nominal.name}-commissioned", description=(
            f"{e.nominal.name} with R, L and the back-EMF amplitude measured by bldclab commission on {drive.name} "
            f"(status {e.status}, {e.t_test:.3f} s on the drive); everything else from {e.nominal.name}"))
        args.out.parent.mkdir(parents=True, exist_ok=True)
        write_atomic(args.out, est.to_toml().encode())
        print(f"wrote {args.out}", file=sys.stderr if args.format == "json" else sys.stdout)
    return 0 if e.ok else 1

"""``bldclab identify``: back-EMF tables from a measured constant-speed waveform, written as a motor file."""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
import tomllib
from pathlib import Path

from .._files import write_atomic, write_files
from ..analysis.identify import Identification, identify, sample_path
from ..errors import BldclabError
from ..model.catalog import load
from ..model.motor import Drive
from .paths import check_out_file

__all__ = [
    "configure_command",
    "run_command",
]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab identify``."""
    p.add_argument("waveform", metavar="WAVEFORM.csv", nargs="?",
                   help="constant-speed open-circuit record: t or theta; v_a, v_b, v_c or two of v_ab, v_bc, v_ca; "
                   "optional h_a, h_b, h_c (docs/identify.md)")
    p.add_argument("--write-sample", metavar="FILE.csv", type=Path,
                   help="write the sample record shipped with bldclab (lu-4kw's back-EMF at 1300 rpm) to FILE.csv, "
                   "print the command that identifies it, and stop")
    p.add_argument("--speed", metavar="SPEED",
                   help="mechanical speed of the test with a unit ('1300 rpm', '136 rad/s'; a plain number is "
                   "rad/s) or 'auto' (from the measured period and the pole pairs)")
    p.add_argument("--base", metavar="MOTOR",
                   help="drive the motor belongs to (built-in name or TOML file): needed for --out, gives p")
    p.add_argument("--pole-pairs", type=int, metavar="P", help="pole pairs (default: from --base)")
    p.add_argument("--out", type=Path, metavar="motor.toml",
                   help="write BASE with its back-EMF replaced by the identified tables (needs --base)")
    p.add_argument("--points", type=int, default=360, metavar="N",
                   help="table points per phase, a multiple of 3 (default: 360, every degree)")
    p.add_argument("--smooth", metavar="ANGLE",
                   help="half-width of the regression window, e.g. '1 deg' (default: 0.5 deg)")
    p.add_argument("--set-hall-error", action="store_true",
                   help="also write the measured Hall placement errors into [sensors] hall_error of --out")
    p.add_argument("--name", help="name of the written drive (default: the --out file name without .toml)")
    p.add_argument("--tables", metavar="FILE.csv", type=Path,
                   help="write the identified shape tables (theta_deg, k_a, k_b, k_c in V s/rad) to FILE.csv")
    p.add_argument("--format", choices=("table", "json"), default="table",
                   help="report on stdout: the text summary (the tables go to --tables), or JSON with everything "
                   "(default: table)")


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab identify``: identify, check, write the motor file atomically, print the report."""
    if args.write_sample is not None:
        return _write_sample(args)
    if args.waveform is None:
        raise BldclabError("WAVEFORM.csv", "is required (or --write-sample FILE.csv to get the sample record)")
    if args.speed is None:
        raise BldclabError("--speed", "is required: the test's speed with a unit ('1300 rpm') or 'auto'")
    check_out_file(args.tables, "--tables")
    out: Path | None = args.out
    if out is not None:
        if args.base is None:
            raise BldclabError("--out", "needs --base: a motor file describes a whole drive (R, L, inverter, "
                               "sensors); the shape tables alone are in the --format json report")
        check_out_file(out)
    if args.set_hall_error and out is None:
        raise BldclabError("--set-hall-error", "only applies to the file written with --out")
    base = load(args.base) if args.base is not None else None
    p = args.pole_pairs
    if base is not None:
        if p is not None and p != base.motor.p:
            raise BldclabError("--pole-pairs", f"{p} contradicts the base drive's p = {base.motor.p}")
        p = base.motor.p
    smooth = args.smooth
    result = identify(args.waveform, args.speed, pole_pairs=p, points=args.points, smooth=smooth)
    files: dict[str, bytes] = {}
    if out is not None and base is not None:
        name = args.name if args.name is not None else (out.stem if out.suffix == ".toml" else out.name)
        drive = result.drive(base, name=name, hall_error=args.set_hall_error)
        text = (f"# Written by bldclab identify from {Path(args.waveform).name} (base drive {base.name}).\n"
                "# Numbers in SI units (V, A, Ohm, H, rad, rad/s, V s/rad, kg m^2, N m s/rad, N m, Hz, s).\n\n"
                + drive.to_toml())
        Drive.from_dict(tomllib.loads(text), source=str(out), default_name=name)  # it must read back
        files[out.name] = text.encode()
    if files and out is not None:
        write_files(out.parent, files)
    if args.tables is not None:
        write_atomic(args.tables, _tables_csv(result).encode(), "--tables")
    for w in result.warnings:
        sys.stderr.write(f"bldclab: warning: {' '.join(w.split())}\n")
    if args.format == "json":
        sys.stdout.write(json.dumps(result.to_dict(), indent=2, allow_nan=False) + "\n")
    else:
        sys.stdout.write(result.report(tables=False))
        n = result.theta.size
        wrote = [] if args.tables is None else [f"wrote {args.tables} ({n} points per phase)"]
        if args.tables is None:
            sys.stdout.write(f"  shape tables       {n} points per phase: --tables FILE.csv writes them, "
                             "--format json prints them\n")
        if out is not None:
            wrote.append(f"wrote {out}")
        if wrote:
            sys.stdout.write("\n" + "\n".join(wrote) + "\n")
    return 0


def _tables_csv(result: Identification) -> str:
    """Return the shape tables as CSV: electrical angle of each phase's own axis (deg) and k_a, k_b, k_c (V s/rad)."""
    lines = ["theta_deg,k_a,k_b,k_c"]
    for j, th in enumerate(result.theta):
        lines.append(f"{math.degrees(th):.10g},{result.k[0, j]:.10g},{result.k[1, j]:.10g},{result.k[2, j]:.10g}")
    return "\n".join(lines) + "\n"


def _write_sample(args: argparse.Namespace) -> int:
    """``--write-sample FILE``: copy the shipped sample record there and say how to identify it."""
    if args.waveform is not None:
        raise BldclabError("--write-sample", "takes no WAVEFORM.csv: it writes the sample record and stops")
    target: Path = args.write_sample
    check_out_file(target, "--write-sample")
    write_atomic(target, sample_path().read_bytes(), "--write-sample")
    sys.stdout.write(f"wrote {target} (lu-4kw's open-circuit back-EMF at 1300 rpm, with Hall signals)\n"
                     f"identify it: bldclab identify {shlex.quote(str(target))} --speed auto --base lu-4kw "
                     "--out identified.toml\n")
    return 0

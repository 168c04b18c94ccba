"""``bldclab thermal MOTOR --profile FILE``: a load profile through the drive and its thermal network.

Prints the peak temperature of every node against its limit, the energies and the wall time; ``--out FILE.csv``
writes the trace at the thermal time scale (temperatures, losses, factors, speed, torque, derating).
``bldclab thermal MOTOR --envelope``: the continuous and time-limited torque-speed envelopes of both supplies.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from .._files import write_atomic
from ..analysis.thermal import Derating, envelope, read_profile, run_profile
from ..errors import BldclabError
from ..model.catalog import load
from ..model.units import per_unit, to_si
from .paths import check_out_file

__all__ = ["configure_command", "run_command"]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab thermal``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive (bldclab drives) or motor file with [thermal]")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--profile", type=Path, metavar="FILE.toml",
                      help="load profile: time, speed, torque arrays (docs/thermal.md, 'Long runs')")
    what.add_argument("--envelope", action="store_true",
                      help="continuous and time-limited torque-speed envelopes of both supplies instead")
    p.add_argument("--speeds", metavar="LIST", default="0.15 pu,0.3 pu,0.45 pu,0.6 pu,0.75 pu",
                   help="envelope speeds, comma-separated ('300 rpm' or per unit of Omega_0; default 0.15-0.75 pu)")
    p.add_argument("--durations", metavar="LIST", default="10 s,60 s",
                   help="time-limited envelopes from the ambient, comma-separated (default '10 s,60 s')")
    p.add_argument("--current-limit", metavar="CURRENT",
                   help="envelopes: peak phase current limit of both controllers ('100 A'; default 2 I_N)")
    p.add_argument("--supply", choices=("sine", "square"), default="sine", help="the controller (default: sine)")
    p.add_argument("--mode", choices=("fast", "switching"), default="fast",
                   help="fast: cycle-averaged steady points per thermal step (default); switching: every PWM period")
    p.add_argument("--step", metavar="TIME", help="thermal step (default 1 s fast, 50 ms switching)")
    p.add_argument("--ambient", metavar="TEMP", help="ambient temperature (default: the motor file's)")
    p.add_argument("--derate", metavar="NODE:T_START:T_END",
                   help="torque derating with a node's temperature, e.g. winding:130:155 (fast mode)")
    p.add_argument("--out", type=Path, metavar="FILE.csv", help="write the thermal trace (or the envelopes) here")


def _derating(text: str) -> Derating:
    parts = text.split(":")
    if len(parts) != 3:
        raise BldclabError("--derate", f"expected NODE:T_START:T_END (e.g. winding:130:155), got {text!r}")
    return Derating(parts[0], to_si(parts[1], "temperature", "--derate"), to_si(parts[2], "temperature", "--derate"))


def _speeds(text: str, omega_0: float) -> list[float]:
    out = []
    for j, v in enumerate(text.split(",")):
        pu = per_unit(v)
        w = pu * omega_0 if pu is not None else to_si(v, "speed", f"--speeds (value {j + 1})")
        if not w > 0.0:
            raise BldclabError("--speeds", f"speeds must be > 0, got {v.strip()!r}")
        out.append(w)
    return out


def _envelopes(args: argparse.Namespace) -> int:
    drive = load(args.motor)
    ambient = None if args.ambient is None else to_si(args.ambient, "temperature", "--ambient")
    speeds = _speeds(args.speeds, drive.Omega_0)
    durations: list[float | None] = [None]
    for j, v in enumerate(args.durations.split(",")):
        d = to_si(v, "time", f"--durations (value {j + 1})")
        if not d > 0.0:
            raise BldclabError("--durations", f"durations must be > 0, got {v.strip()!r}")
        durations.append(d)
    i_limit = None
    if args.current_limit is not None:
        i_limit = to_si(args.current_limit, "current", "--current-limit")
        if not (math.isfinite(i_limit) and i_limit > 0.0):
            raise BldclabError("--current-limit", f"must be a current > 0, got {args.current_limit!r}")
    cols = [(s, d) for d in durations for s in ("square", "sine")]
    env = {c: envelope(drive, speeds, supply=c[0], duration=c[1], ambient=ambient, i_limit=i_limit) for c in cols}
    print(f"{drive.name}: torque (N m) that keeps every node below its T_max"
          + (f", ambient {ambient:g} degC" if ambient is not None else "")
          + f"; both supplies limited to {env[cols[0]].i_limit:.4g} A peak")
    print("after each: what limits it (a node; delivery: the bus voltage or the controller's current limit)")
    head = [f"{s} {'cont' if d is None else f'{d:g} s'}" for s, d in cols]
    print(f"{'rpm':>7} " + " ".join(f"{h:>22}" for h in head))
    rows = []
    for j, w in enumerate(speeds):
        cells = [f"{env[c].torque[j]:8.2f} {env[c].limiting[j]:<13}" for c in cols]
        print(f"{w * 30 / 3.141592653589793:7.0f} " + " ".join(f"{x:>22}" for x in cells))
        rows.append({"speed": w, **{f"{h}": float(env[c].torque[j]) for h, c in zip(head, cols, strict=True)},
                     **{f"{h} limit": env[c].limiting[j] for h, c in zip(head, cols, strict=True)}})
    if args.out is not None:
        import pandas as pd

        write_atomic(args.out, pd.DataFrame(rows).to_csv(index=False).encode(), "--out")
        print(f"wrote {args.out}")
    return 0


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab thermal``."""
    check_out_file(args.out)
    if args.current_limit is not None and not args.envelope:
        raise BldclabError("--current-limit", "is an option of --envelope")
    if args.envelope:
        return _envelopes(args)
    drive = load(args.motor)
    profile = read_profile(args.profile)
    h = None if args.step is None else to_si(args.step, "time", "--step")
    ambient = None if args.ambient is None else to_si(args.ambient, "temperature", "--ambient")
    derate = None if args.derate is None else _derating(args.derate)
    res = run_profile(drive, profile, supply=args.supply, mode=args.mode, h=h, ambient=ambient, derate=derate)
    tr = res.trace
    print(f"{drive.name}: {profile.name or args.profile}, {profile.duration:g} s, {args.supply} supply, {res.mode} "
          f"mode, thermal step {tr.t[1] - tr.t[0]:g} s")
    print(f"wall time {res.wall:.2f} s" + (f" ({res.points} steady-state points)" if res.mode == "fast" else ""))
    print(f"{'node':<12} {'start':>8} {'peak':>8} {'end':>8} {'T_max':>8} {'margin':>8}")
    for name, T in tr.T.items():
        lim = res.limits.get(name)
        peak = float(np.max(T))
        tail = f" {lim:8.1f} {lim - peak:8.1f}" if lim is not None else ""
        print(f"{name:<12} {T[0]:8.1f} {peak:8.1f} {T[-1]:8.1f}{tail}")
    over = [n for n, m in res.margins().items() if m < 0]
    print(f"losses {tr.E_loss / 3.6e3:.4g} Wh: stored {tr.E_stored / 3.6e3:.4g} Wh, to ambient "
          f"{tr.E_out / 3.6e3:.4g} Wh (balance {tr.balance:.1e})")
    if "derate" in tr.extra and float(np.min(tr.extra["derate"])) < 1.0:
        print(f"derating: torque down to {100 * float(np.min(tr.extra['derate'])):.0f} % of the profile's")
    if over:
        print("over its limit: " + ", ".join(over))
    if args.out is not None:
        df = res.to_pandas()
        write_atomic(args.out, df.to_csv(index=False).encode(), "--out")
        print(f"wrote {args.out}")
    return 0

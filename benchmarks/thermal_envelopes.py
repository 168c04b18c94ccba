"""Continuous and 60 s torque-speed envelopes of htm-48v, htm-48v-losses and servo-2k2, both supplies; one hour.

Prints tables (docs/thermal.md quotes them). Run: PYTHONPATH=src python benchmarks/thermal_envelopes.py [--no-hour]
[DRIVE ...]. Both controllers are limited to the same peak phase current, 2 I_N (envelope_controls).
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from bldclab.analysis.thermal import Envelope, envelope, read_profile, run_profile
from bldclab.model import catalog

ABBREV = {"winding": "w", "rotor": "r", "junction": "j", "delivery": "d", "T_peak": "p"}
#: Speeds of each drive's table (rpm): up to about its rated speed.
RPM = {"htm-48v": [100.0, 200.0, 300.0, 400.0, 500.0, 600.0],
       "htm-48v-losses": [100.0, 200.0, 300.0, 400.0, 500.0, 600.0],
       "servo-2k2": [250.0, 500.0, 750.0, 1000.0, 1250.0, 1500.0]}


def cell(e: Envelope, j: int) -> str:
    """Return an envelope's torque at speed index ``j`` and what limits it."""
    return f"{e.torque[j]:8.2f} {ABBREV.get(e.limiting[j], e.limiting[j][:1])}"


def main() -> None:
    """Print the envelopes, the sine supply's gain, hot vs cold characteristic, and the one-hour profile."""
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    for name in args or list(RPM):
        d = catalog.load(name)
        rpm = np.array(RPM[name])
        speeds = rpm * math.pi / 30.0
        print(f"\n{name}: ambient 25 degC, torque (N m) that keeps every node below its T_max; current limit "
              f"{2 * d.motor.I_N:.4g} A (2 I_N) for both supplies")
        print("(after each torque what limits it: w winding, r rotor/magnets, j junction, d delivery: the bus "
              "voltage or the controller's current limit)")
        print(f"{'rpm':>6} {'cont sq':>10} {'cont sin':>10} {'gain %':>7} {'60s sq':>10} {'60s sin':>10}")
        t0 = time.perf_counter()
        env = {(s, dur): envelope(d, speeds, supply=s, duration=dur, tol=0.002)
               for s in ("square", "sine") for dur in (None, 60.0)}
        for j, r in enumerate(rpm):
            cs, cn = env[("square", None)].torque[j], env[("sine", None)].torque[j]
            gain = 100 * (cn / cs - 1)
            print(f"{r:6.0f} {cell(env[('square', None)], j)} {cell(env[('sine', None)], j)} {gain:7.1f} "
                  f"{cell(env[('square', 60.0)], j)} {cell(env[('sine', 60.0)], j)}")
        print(f"  ({time.perf_counter() - t0:.1f} s)")
    if "--no-hour" in sys.argv:
        return
    d = catalog.load("htm-48v-losses")
    prof = read_profile("examples/profiles/hill-climb.toml")
    print("\none-hour hill climb (examples/profiles/hill-climb.toml) on htm-48v-losses, fast mode, h = 1 s")
    for s in ("square", "sine"):
        r = run_profile(d, prof, supply=s, h=1.0)
        peaks = {k: float(np.max(v)) for k, v in r.trace.T.items() if k in r.limits}
        print(f"  {s:6s} wall {r.wall:5.1f} s, {r.points} points, peaks " +
              ", ".join(f"{k} {v:.1f}" for k, v in peaks.items()) + f" degC, balance {r.trace.balance:.1e}")


if __name__ == "__main__":
    main()

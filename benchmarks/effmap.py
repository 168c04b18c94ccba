"""Wall time of a 20 x 20 efficiency map of both supplies on htm-48v, serial and on 2 processes.

Target (issue 14): under 30 s on 2 cores. Run: ``python benchmarks/effmap.py [--n N] [--workers W]``.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from bldclab.analysis.effmap import efficiency_map
from bldclab.errors import PlausibilityWarning
from bldclab.model.catalog import load

TARGET = 30.0


def measure(n: int, workers: int) -> float:
    """Return the wall time (s) of an n x n map of both supplies on htm-48v with ``workers`` processes."""
    drive = load("htm-48v")
    torques = np.linspace(0.1, 1.0, n) * drive.T_N
    speeds = np.linspace(0.05, 0.95, n) * drive.Omega_0
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        efficiency_map(drive, torques, speeds, workers=workers)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20, help="torques and speeds per axis (default 20)")
    ap.add_argument("--workers", type=int, default=2, help="processes of the parallel run (default 2)")
    args = ap.parse_args()
    serial = measure(args.n, 1)
    par = measure(args.n, args.workers)
    print(f"efficiency map htm-48v, {args.n} x {args.n} x 2 supplies")
    print(f"{'serial [s]':>11} {f'{args.workers} proc [s]':>11} {'target [s]':>11} {'ok':>4}")
    print(f"{serial:>11.2f} {par:>11.2f} {TARGET:>11.1f} {'yes' if par <= TARGET else 'NO':>4}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

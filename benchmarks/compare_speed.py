"""Wall time of ``bldclab compare htm-48v`` end to end (process start, simulations, figures, files).

Target (issue 3): under 10 s on the 2-core CI machine with at least 30 speeds per supply.
Run: ``python benchmarks/compare_speed.py [--speeds N] [--repeats R]``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time

TARGET = 10.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", type=int, default=32, help="speeds per supply (default 32)")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    walls = []
    with tempfile.TemporaryDirectory() as d:
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "bldclab.cli", "compare", "htm-48v", "--out", d, "--speeds",
                            str(args.speeds), "--no-progress"], check=True, capture_output=True)
            walls.append(time.perf_counter() - t0)
    med = statistics.median(walls)
    print(f"bldclab compare htm-48v, {args.speeds} speeds x 2 supplies, {args.repeats} runs")
    print(f"{'median [s]':>11} {'min [s]':>8} {'max [s]':>8} {'target [s]':>11} {'ok':>4}")
    print(f"{med:>11.2f} {min(walls):>8.2f} {max(walls):>8.2f} {TARGET:>11.1f} {'yes' if med <= TARGET else 'NO':>4}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

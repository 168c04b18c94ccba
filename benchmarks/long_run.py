"""Long runs in bounded memory: peak RSS and wall time of ``bldclab simulate`` for growing durations.

Issue 13: ``simulate htm-48v --duration "1000 s"`` used to allocate its whole trace (34 GiB) and die. The runner now
calls C in pieces of ``bldclab.sim.CHUNK`` samples with the state carried over, so without a trace (``--no-trace``)
or with a thinned one (``--trace-every N``) memory does not grow with the duration (a thinned trace grows by one
row per N samples: 328 bytes per 1000 samples with the default N below). Target: 1000 simulated seconds in
bounded memory. Each row is one fresh process (``bldclab simulate``, htm-48v, square control, imposed 0.5
``Omega_0``, 14 kHz PWM), measured with ``os.wait4``: peak resident set (the interpreter, numpy and the library
included) and wall time. Run: ``python benchmarks/long_run.py [--durations 10 100 1000]``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

TRACE_EVERY = 1000


def one(duration: float, trace: list[str]) -> tuple[float, float]:
    """Return (wall s, peak RSS MB) of one ``bldclab simulate`` process."""
    cmd = [sys.executable, "-c", "import sys; from bldclab.cli import main; sys.exit(main())", "simulate",
           "htm-48v", "--duration", f"{duration:g} s", "--format", "json", *trace]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    err = proc.stderr.read().decode() if proc.stderr else ""
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}): {err}")
    return wall, usage.ru_maxrss / 1024.0  # ru_maxrss is in kB on Linux


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--durations", type=float, nargs="+", default=[10.0, 100.0, 1000.0], help="simulated s")
    args = ap.parse_args()
    print("| duration (s) | trace | wall (s) | wall per simulated s | peak RSS (MB) |")
    print("|---:|---|---:|---:|---:|")
    for d in args.durations:
        for label, opts in (("none (--no-trace)", ["--no-trace"]),
                            (f"--trace-every {TRACE_EVERY}", ["--trace-every", str(TRACE_EVERY)])):
            wall, rss = one(d, opts)
            print(f"| {d:g} | {label} | {wall:.1f} | {wall / d:.4f} | {rss:.0f} |", flush=True)


if __name__ == "__main__":
    main()

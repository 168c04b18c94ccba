"""Start-up time of the command line, and the fixed cost of ``bldclab effmap`` and ``bldclab compare`` by phase.

1. The light commands (``bldclab --help``, ``drives``, ``check MOTOR``, ``template --out F``, ``analyze MOTOR``):
   wall time from process start to exit, best of ``--repeats`` runs, each in a fresh process; target 0.3 s
   (issue 22).
2. The fixed cost of ``bldclab effmap htm-48v --torques 2 --speeds 2 --no-store`` and ``bldclab compare htm-48v
   --speeds 2`` (8 operating points: what the commands cost besides simulating) with ``--workers 1`` and ``2``, best
   of ``--repeats`` by wall time, cut into phases by timestamps taken in the child process around the command's own
   functions (wrapped by this script, not instrumented in the library): interpreter start, imports, set-up
   (arguments, drive; matplotlib loaded before the pool), simulations (pool start and the points), figures and
   report (compare: paper 1's Figs 9, 11, 12, the waveforms, the manifest and report.html; the CSV tables), the
   files (after the pool's shutdown), interpreter exit.
3. The process pool alone: start of 2 workers and a first round trip, forked from a process that has imported what
   ``bldclab effmap`` imports (as the command does), and spawned (each worker imports the map's modules itself:
   what the fork saves).

Every command runs as the ``bldclab`` console script does (``from bldclab.cli import main; sys.exit(main())``) in a
fresh interpreter, in this environment: with ``PYTHONDONTWRITEBYTECODE`` set and no bytecode cache (the test VM's
setting), bldclab's modules are compiled at every start; the header says which. On a shared machine the parallel
phases need free cores: the load average is printed.
Run: ``python benchmarks/cli_startup.py [--repeats N] [--workers 1,2] [--skip-fixed]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

#: Wall-time target of a light command (issue 22), s.
TARGET = 0.3

#: What the console script runs.
ENTRY = "import sys; from bldclab.cli import main; sys.exit(main())"


def light_commands(tmp: Path) -> list[list[str]]:
    """Return the light commands' arguments (``template`` writes into ``tmp``)."""
    return [["--help"], ["drives"], ["check", "htm-48v"], ["template", "--force", "--out", str(tmp / "motor.toml")],
            ["analyze", "htm-48v"]]


def wall(args: list[str], repeats: int, cwd: Path) -> float:
    """Return the best wall time (s) of ``bldclab ARGS`` over ``repeats`` fresh processes (output discarded)."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", ENTRY, *args], cwd=cwd, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True)
        best = min(best, time.perf_counter() - t0)
        if proc.returncode != 0:
            raise RuntimeError(f"bldclab {' '.join(args)} exited with {proc.returncode}: {proc.stderr.strip()}")
    return best


def startup(repeats: int) -> list[tuple[str, float]]:
    """Return ``(command, best wall time in s)`` for each light command."""
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        wall(["drives"], 1, tmp)  # warm the file cache
        return [("bldclab " + " ".join(a).replace(str(tmp) + os.sep, ""), wall(a, repeats, tmp))
                for a in light_commands(tmp)]


def bytecode() -> str:
    """Say whether bldclab's modules start from a bytecode cache in the child processes."""
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        return "PYTHONDONTWRITEBYTECODE set: bldclab's modules compiled at every start unless a cache exists"
    return "bytecode cached after the first run"


# ------------------------------------------------------------------------------------------------------------
# fixed cost by phase

#: The child: timestamps (time.time(), comparable with the parent's) around the command's functions, written as
#: JSON to the file named by BLDCLAB_BENCH_EVENTS. Functions are wrapped where the command module looks them up.
CHILD = r"""
import json, os, sys, time
t_first = time.time()
events = {"start": t_first}
import importlib
import bldclab.cli as cli
command = sys.argv[1]
mod = importlib.import_module("bldclab.cli." + command.replace("-", "_"))
events["imports"] = time.time()

def wrap(owner, attr, first, last):
    f = getattr(owner, attr)
    def timed(*a, **k):
        if first:
            events.setdefault(first, time.time())
        try:
            return f(*a, **k)
        finally:
            if last:
                events[last] = time.time()
    setattr(owner, attr, timed)

for spec in json.loads(os.environ["BLDCLAB_BENCH_WRAP"]):
    owner = importlib.import_module(spec[0])
    if hasattr(owner, spec[1]):
        wrap(owner, spec[1], spec[2], spec[3])
try:
    code = cli.main()  # as the console script: sys.argv[1:] (python -c CODE ARGS)
finally:
    events["end"] = time.time()
    with open(os.environ["BLDCLAB_BENCH_EVENTS"], "w") as fh:
        json.dump(events, fh)
sys.exit(code)
"""

#: Per command: (module, function, event at its first entry, event at its last exit); functions a version of the
#: command does not have are skipped (the figures were drawn by figure_bytes, the files made by compare_files and
#: compare_outputs before compare_directory).
WRAP = {
    "effmap": [("bldclab.cli.effmap", "efficiency_map", "sims_start", "sims_end"),
               ("bldclab.cli.effmap", "figure_bytes", None, "outputs_end"),
               ("bldclab.cli.effmap", "effmap_figures", None, "outputs_end"),
               ("bldclab.cli.effmap", "write_files", None, "files_end")],
    "compare": [("bldclab.cli.compare", "compare", "sims_start", "sims_end"),
                ("bldclab.cli.compare", "compare_outputs", None, "outputs_end"),
                ("bldclab.cli.compare", "compare_directory", None, "outputs_end"),
                ("bldclab.cli.compare", "write_files", None, "files_end")],
}

#: Phases: (name, from event, to event).
PHASES = [("interpreter start", "spawn", "start"), ("imports", "start", "imports"),
          ("set-up", "imports", "sims_start"), ("simulations", "sims_start", "sims_end"),
          ("figures, report", "sims_end", "outputs_end"), ("files", "outputs_end", "files_end"),
          ("exit", "files_end", "exit")]


@dataclass
class Fixed:
    """One fixed-cost run: the command, its wall time and its phases (s)."""

    label: str
    wall: float
    phases: dict[str, float]


def fixed_args(command: str, out: Path, workers: int) -> list[str]:
    """Return the arguments of the tiny run of ``command`` (8 operating points)."""
    if command == "effmap":
        return ["effmap", "htm-48v", "--torques", "2", "--speeds", "2", "--no-store", "--out", str(out),
                "--workers", str(workers)]
    return ["compare", "htm-48v", "--speeds", "2", "--out", str(out), "--workers", str(workers), "--no-progress"]


def phases_of(events: dict[str, float]) -> dict[str, float]:
    """Cut a run's timestamps into :data:`PHASES`."""
    return {name: events[b] - events[a] for name, a, b in PHASES if a in events and b in events}


def fixed_once(command: str, workers: int, tmp: Path) -> Fixed:
    """Run the tiny ``command`` once in a fresh process; return its wall time and phases."""
    ev_file = tmp / "events.json"
    env = {**os.environ, "BLDCLAB_BENCH_EVENTS": str(ev_file), "BLDCLAB_BENCH_WRAP": json.dumps(WRAP[command])}
    args = fixed_args(command, tmp / f"{command}-{workers}", workers)
    spawn = time.time()
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", CHILD, *args], cwd=tmp, env=env, stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True)
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"bldclab {' '.join(args)} exited with {proc.returncode}: {proc.stderr.strip()}")
    events = {**json.loads(ev_file.read_text()), "spawn": spawn, "exit": spawn + elapsed}
    return Fixed(f"{command} --workers {workers}", elapsed, phases_of(events))


def fixed(repeats: int, workers: list[int]) -> list[Fixed]:
    """Return the best of ``repeats`` (by wall time) of each tiny command and worker count."""
    out = []
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for command in ("effmap", "compare"):
            for w in workers:
                out.append(min((fixed_once(command, w, tmp) for _ in range(repeats)), key=lambda f: f.wall))
    return out


#: The pool alone, in a fresh process that imported what ``bldclab effmap`` imports: start and a first round trip
#: of 2 workers (a job that imports the map's module, as the first point does), by start method.
POOL = r"""
import json, multiprocessing, sys, time
from concurrent.futures import ProcessPoolExecutor
import bldclab.cli.effmap
from bldclab.report.plots import load_matplotlib
load_matplotlib()
from bldclab.analysis.effmap import loss_buckets
out = {}
for method in ("fork", "spawn"):
    t0 = time.perf_counter()
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context(method)) as pool:
        [f.result() for f in [pool.submit(loss_buckets) for _ in range(2)]]
        out[method] = time.perf_counter() - t0
print(json.dumps(out))
"""


def pool_start(repeats: int) -> dict[str, float]:
    """Return the best start-plus-first-round-trip time (s) of a 2-worker pool, forked and spawned."""
    best: dict[str, float] = {}
    for _ in range(repeats):
        proc = subprocess.run([sys.executable, "-c", POOL], capture_output=True, text=True, check=True)
        for method, t in json.loads(proc.stdout.strip().splitlines()[-1]).items():
            best[method] = min(best.get(method, float("inf")), t)
    return best


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="fresh-process runs of each command (the best counts)")
    ap.add_argument("--workers", default="1,2", help="worker counts of the fixed-cost runs (default 1,2)")
    ap.add_argument("--skip-fixed", action="store_true", help="only the light commands")
    args = ap.parse_args()
    print(f"bldclab start-up on {os.cpu_count()} CPUs, Python {sys.version.split()[0]}, load average "
          f"{os.getloadavg()[0]:.2f}; {bytecode()}")
    rows = startup(args.repeats)
    width = max(len(c) for c, _ in rows)
    print(f"{'command':<{width}}  {'wall [s]':>8}  {'target [s]':>10}  ok")
    for c, t in rows:
        print(f"{c:<{width}}  {t:>8.3f}  {TARGET:>10.1f}  {'yes' if t <= TARGET else 'NO'}")
    if args.skip_fixed:
        return 0
    runs = fixed(args.repeats, [int(w) for w in args.workers.split(",")])
    names = [p for p, _, _ in PHASES if any(p in r.phases for r in runs)]
    print()
    print("fixed cost [s]: effmap htm-48v --torques 2 --speeds 2 --no-store, compare htm-48v --speeds 2 (8 points "
          f"each); best of {args.repeats} by wall time")
    width = max(len(n) for n in [*names, "wall"])
    print(f"{'phase':<{width}}" + "".join(f"  {r.label:>20}" for r in runs))
    for n in names:
        print(f"{n:<{width}}" + "".join(f"  {r.phases[n]:>20.3f}" if n in r.phases else f"  {'-':>20}"
                                        for r in runs))
    print(f"{'wall':<{width}}" + "".join(f"  {r.wall:>20.3f}" for r in runs))
    pool = pool_start(args.repeats)
    print(f"process pool, 2 workers, start + first round trip: {pool['fork'] * 1e3:.0f} ms forked (as the commands "
          f"do: nothing to import), {pool['spawn'] * 1e3:.0f} ms spawned (each worker imports the map's modules)")
    print(f"load average at end {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

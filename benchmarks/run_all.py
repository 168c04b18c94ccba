"""All benchmarks in one table: plant speed, sweep scale and memory, compare end to end, firmware, motulator.

One row per measurement: the result, its unit, the target where the issues set one, and notes. Each group reuses
the benchmark script that owns it (``plant_speed.py``, ``sweep_scale.py``, ``compare_speed.py``, ``firmware.py``,
``motulator_case.py``, ``cost.py``); what each row measures is in ``docs/benchmarks.md``. A group that cannot run (a
missing tool, motulator not installable) gets a row saying why and the table is still printed. The exit code is 1
when a row misses its target (ok = "NO"; the rows are listed after the table) or a bldclab measurement failed;
``--allow-miss`` (exploring) ignores the misses.

Run: ``python benchmarks/run_all.py [--skip GROUP,...] [--seconds S] [--repeats R] [--allow-miss]`` with groups
``plant``, ``sine``, ``sweep``, ``memory``, ``compare``, ``firmware``, ``cost``, ``motulator``, ``sensorless`` (the
sensorless case beside motulator, ``sensorless_case.py``). The default run takes about four minutes on 2 cores (plus
about 20 s once, to install motulator).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

HERE = Path(__file__).resolve().parent
GROUPS = ("plant", "sine", "sweep", "memory", "compare", "effmap", "cli", "firmware", "cost", "motulator",
          "sensorless")


def load(name: str) -> ModuleType:
    """Import a sibling benchmark script as a module (``benchmarks`` is not a package)."""
    key = f"bench_{name}"
    if key in sys.modules:
        return sys.modules[key]
    spec = importlib.util.spec_from_file_location(key, HERE / f"{name}.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[key] = mod
    spec.loader.exec_module(mod)
    return mod


@dataclass
class Row:
    """One line of the table."""

    name: str
    result: str
    unit: str = ""
    target: str = ""
    ok: str = ""
    notes: str = ""


def verdict(good: bool) -> str:
    return "yes" if good else "NO"


# ------------------------------------------------------------------------------------------------------------
# groups


def plant_rows(seconds: float, repeats: int) -> list[Row]:
    """Six-step at 0.5 Omega_0 through ``plant_speed.one`` (open-loop voltage mode at rated current)."""
    import bldclab as bl

    ps = load("plant_speed")
    drive = bl.load("htm-48v")
    rows = []
    walls = {}
    for trace in (False, True):
        r, info = ps.one(drive, 0.5, seconds, trace, repeats)
        walls[trace] = (r, info)
        rows.append(Row(f"plant: htm-48v six-step 14 kHz, {'trace' if trace else 'no trace'}", f"{r:.4f}",
                        "s per sim s", f"<= {ps.TARGET:g}", verdict(r <= ps.TARGET),
                        f"0.5 Omega_0 imposed, {info['steps']:.0f} steps/s, {info['events']:.0f} events/s"))
    r_sw, i_sw = walls[False]
    r, info = ps.one(drive, 0.5, seconds, False, repeats, "average")
    rows.append(Row("plant: htm-48v six-step 14 kHz, average inverter", f"{r:.4f}", "s per sim s", "", "",
                    f"{info['steps']:.0f} steps/s, {info['events']:.0f} events/s, tau {info['tau']:.2f} N m "
                    f"(switching {i_sw['tau']:.2f})"))
    rows.append(Row("plant: six-step switching / average", f"{r_sw / r:.1f}", "x", f">= {ps.SPEEDUP_TARGET:g}",
                    verdict(r_sw / r >= ps.SPEEDUP_TARGET), "no trace; docs/benchmarks.md says why"))
    return rows


def sine_rows(seconds: float, repeats: int) -> list[Row]:
    """``Sine`` (paper 1's sinusoidal supply) on htm-48v at 0.5 Omega_0 imposed, nominal torque ``T_s,N``."""
    import bldclab as bl
    from bldclab.model import analytic as an

    drive = bl.load("htm-48v")
    ctl = bl.Sine()
    rows = []
    per_s = {}
    for trace, model in ((False, "switching"), (True, "switching"), (False, "average")):
        d = drive.replace(inverter__model=model)
        sc = bl.Scenario(duration=seconds, speed=0.5 * d.Omega_0, ref=an.T_SN_PU * d.T_N, trace=trace)
        bl.simulate(d, ctl, sc)
        walls = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            res = bl.simulate(d, ctl, sc)
            walls.append(time.perf_counter() - t0)
        r = min(walls) / seconds
        per_s[model, trace] = r
        what = "average inverter" if model == "average" else ("trace" if trace else "no trace")
        rows.append(Row(f"plant: htm-48v Sine control 14 kHz, {what}", f"{r:.4f}",
                        "s per sim s", "", "",
                        f"0.5 Omega_0 imposed, T_s,N, {res.meta['stats']['steps'] / seconds:.0f} steps/s"))
    rows.append(Row("plant: Sine switching / average", f"{per_s['switching', False] / per_s['average', False]:.1f}",
                    "x", "", "", "no trace"))
    return rows


def sweep_child(mode: str, points: int, workers: int, periods: int, trace: bool) -> dict[str, Any]:
    """``sweep_scale.child`` in this (fresh) process, plus the largest resident set of a worker."""
    out = load("sweep_scale").child(mode, points, workers, periods, trace)
    out["worker_rss"] = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024  # joined pool workers
    return out


def sweep_measure(mode: str, points: int, workers: int, periods: int, trace: bool) -> dict[str, Any]:
    cmd = [sys.executable, __file__, "--sweep-child", mode, str(points), str(workers), str(periods), str(int(trace))]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def sweep_rows(points: int, workers: int, periods: int, repeats: int, memory: bool, timed: bool) -> list[Row]:
    """Serial and parallel 1000-point sweeps (best of ``repeats``, fresh process each) and the memory run."""
    ss = load("sweep_scale")
    rows = []
    if timed:
        ser = min((sweep_measure("serial", points, 1, periods, False) for _ in range(repeats)),
                  key=lambda r: r["wall"])
        par = min((sweep_measure("processes", points, workers, periods, False) for _ in range(repeats)),
                  key=lambda r: r["wall"])
        speedup = ser["wall"] / par["wall"]
        same = "identical" if ser["sum_tau"] == par["sum_tau"] else "DIFFERENT"
        rows.append(Row(f"sweep: {points} points, 1 process", f"{ser['wall']:.2f}", "s wall", "", "",
                        f"{points / ser['wall']:.0f} cases/s, {periods} periods per case"))
        rows.append(Row(f"sweep: {points} points, {workers} processes", f"{par['wall']:.2f}", "s wall",
                        f"speed-up >= {ss.TARGET_SPEEDUP:g}", verdict(speedup >= ss.TARGET_SPEEDUP),
                        f"speed-up {speedup:.2f}, {par['cores']:.2f} cores used, results {same} to serial"))
    if memory:
        m = sweep_measure("processes", points, workers, periods, True)
        rows.append(Row(f"memory: parent, {points}-point sweep", f"{m['peak'] / 2**20:.2f}", "MiB peak", "", "",
                        f"tracemalloc peak of the parent; its max RSS {m['rss'] / 2**20:.0f} MiB (imports included)"))
        rows.append(Row(f"memory: per worker, {points}-point sweep", f"{m['worker_rss'] / 2**20:.0f}", "MiB RSS",
                        "", "", f"largest max RSS of the {workers} worker processes"))
    return rows


def compare_rows(repeats: int) -> list[Row]:
    """``bldclab compare htm-48v`` end to end, as ``compare_speed.py`` runs it."""
    cs = load("compare_speed")
    walls = []
    with tempfile.TemporaryDirectory() as d:
        for _ in range(repeats):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "bldclab.cli", "compare", "htm-48v", "--out", d, "--speeds", "32",
                            "--no-progress"], check=True, capture_output=True)
            walls.append(time.perf_counter() - t0)
    med = statistics.median(walls)
    return [Row("bldclab compare htm-48v, end to end", f"{med:.2f}", "s wall", f"<= {cs.TARGET:g}",
                verdict(med <= cs.TARGET), f"32 speeds x 2 supplies, process start to files, median of {repeats}")]


def effmap_rows(n: int, workers: int) -> list[Row]:
    """``effmap.py``: an n x n efficiency map of both supplies on htm-48v, serial and on ``workers`` processes."""
    em = load("effmap")
    serial = em.measure(n, 1)
    par = em.measure(n, workers)
    note = f"{n} x {n} torque x speed x 2 supplies"
    return [Row(f"effmap: htm-48v {n} x {n}, 1 process", f"{serial:.2f}", "s wall", "", "", note),
            Row(f"effmap: htm-48v {n} x {n}, {workers} processes", f"{par:.2f}", "s wall", f"<= {em.TARGET:g}",
                verdict(par <= em.TARGET), note)]


def cli_rows(repeats: int) -> list[Row]:
    """``cli_startup.py``: the light commands (target 0.3 s each) and the fixed cost of effmap and compare."""
    cs = load("cli_startup")
    rows = [Row(f"cli: {cmd}", f"{t:.3f}", "s wall", f"<= {cs.TARGET:g}", verdict(t <= cs.TARGET),
                f"best of {repeats} fresh processes")
            for cmd, t in cs.startup(repeats)]
    for run in cs.fixed(repeats, [1, 2]):
        phases = ", ".join(f"{name} {t:.2f}" for name, t in run.phases.items() if t >= 0.005)
        rows.append(Row(f"cli: {run.label}, 8 points", f"{run.wall:.2f}", "s wall", "", "", phases))
    return rows


def firmware_rows() -> list[Row]:
    """Summary of ``firmware.py``: the sine controller and the costliest controller, in closed loop."""
    fw = load("firmware")
    missing = [t for t in ("arm-none-eabi-gcc", "arm-none-eabi-size", "valgrind", "cc") if shutil.which(t) is None]
    if missing:
        return [Row("firmware (Cortex-M4F)", "skipped", "", "", "", f"missing: {', '.join(missing)}")]
    closed = fw.closed_loop_counts(list(fw.CLOSED_LOOP))
    with tempfile.TemporaryDirectory() as d:
        sizes = fw.arm_sizes(Path(d))
    base_flash, base_ram = sizes.pop("none")
    share = fw.M4F_CYCLES_PER_SAMPLE
    rows = []
    if "sine" in closed and "sine" in sizes:
        flash, ram = sizes["sine"]
        s = closed["sine"]
        rows.append(Row("firmware: sine controller, worst step", f"{s.worst:.0f}", "instr/step", "", "",
                        f"mean {s.mean:.0f}; {s.worst / share:.0%} of {share:,.0f} M4F cycles (host -O2 as proxy); "
                        f"{flash - base_flash} B flash, {ram - base_ram} B RAM on Cortex-M4F; closed loop"))
    name = max(closed, key=lambda k: closed[k].worst)
    big = max(sizes, key=lambda k: sizes[k][0])
    c = closed[name]
    rows.append(Row("firmware: costliest controller, worst step", f"{c.worst:.0f}", "instr/step", "", "",
                    f"{name} ({c.worst_run.label}), mean {c.mean:.0f}; largest flash: {big} "
                    f"{sizes[big][0] - base_flash} B ({len(closed)} controllers in closed loop)"))
    return rows


def cost_rows() -> list[Row]:
    """The cost gate (``cost.py``): one row per scenario, its core instructions against the budget."""
    cost = load("cost")
    missing = [t for t in ("valgrind", "cc") if shutil.which(t) is None]
    if missing:
        return [Row("cost gate (callgrind)", "skipped", "", "", "", f"missing: {', '.join(missing)}")]
    with tempfile.TemporaryDirectory() as d:
        ms = cost.measure(cost.prepare(cost.ROOT, Path(d)), [(n, 1.0) for n in cost.SCENARIOS])
    budgets = cost.read_budgets()
    rows = []
    for m in ms:
        checked = cost.check([m], budgets)
        instr = checked[0]
        others = "; ".join(f"{r.quantity} {r.measured:,.0f}/{r.budget or 0:,.0f}" for r in checked[1:])
        notes = [r.note for r in checked if r.note]
        rows.append(Row(f"cost: {m.scenario}", f"{m.instructions / 1e6:.2f}", "M instr",
                        f"<= {cost.TOLERANCE:g} x {(instr.budget or 0) / 1e6:.2f}", verdict(all(r.ok for r in checked)),
                        "; ".join([others, *notes])))
    return rows


def motulator_rows(repeats: int, venv: Path, python: str | None, out: Path) -> list[Row]:
    """The shared case (``motulator_case.py``): speeds, ratio and agreement."""
    mc = load("motulator_case")
    cmp = mc.compare(repeats, venv, python, out)
    c, bt = cmp.case, cmp.bl_time
    bl_s = bt["trace"] / c.t_stop
    setup_ms = bt["setup"] * 1e3
    rows = [Row("shared case: bldclab", f"{bl_s:.4f}", "s per sim s", "", "",
                f"trace; {bt['no_trace'] / c.t_stop:.4f} without; {setup_ms:.1f} ms of it fixed Python setup")]
    if cmp.reason:
        rows.append(Row("shared case: motulator", "not available", "", "", "", cmp.reason))
        return rows
    mi = cmp.mot_info
    rows.append(Row("shared case: motulator", f"{cmp.mot_per_s:.2f}", "s per sim s", "", "",
                    f"motulator {mi['version']}, Python {mi['python']}, {mi['solver_points']} solver points"))
    rows.append(Row("shared case: motulator / bldclab", f"{cmp.ratio:.0f}", "x", f">= {mc.TARGET_RATIO:g}",
                    verdict(cmp.ratio >= mc.TARGET_RATIO),
                    f"wall, bldclab with trace; {cmp.ratio_no_trace:.0f}x without; CPU time {cmp.ratio_cpu:.0f}x"))
    for ch in cmp.checks:
        rows.append(Row(f"  agreement: {ch.name}", f"{ch.value:+.4f}", ch.unit, f"|.| <= {ch.tol:g}",
                        verdict(ch.ok), ch.why))
    return rows


def sensorless_rows(venv: Path, python: str | None, out: Path) -> list[Row]:
    """The sensorless case (``sensorless_case.py``): servo-2k2 on the reduced-order observer beside motulator."""
    sc = load("sensorless_case")
    cmp = sc.compare(3, venv, python, out)
    bt, bi = cmp.bl_time, cmp.bl_info
    rows = [Row("sensorless case: bldclab", f"{bt['trace']:.4f}", "s per sim s", "", "",
                f"trace; {bt['no_trace']:.4f} without; I/f start, hand-off at {bi['t_handoff']:.2f} s")]
    if cmp.reason:
        rows.append(Row("sensorless case: motulator", "not available", "", "", "", cmp.reason))
        return rows
    mi = cmp.mot_info
    rows.append(Row("sensorless case: motulator", f"{cmp.mot_per_s:.2f}", "s per sim s", "", "",
                    f"motulator {mi['version']}, {mi['solver_points']} solver points"))
    rows.append(Row("sensorless case: motulator / bldclab", f"{cmp.ratio:.0f}", "x", "", "",
                    "wall, bldclab with trace"))
    for ch in cmp.checks:
        rows.append(Row(f"  agreement: {ch.name}", f"{ch.value:+.4f}", ch.unit, f"|.| <= {ch.tol:g}",
                        verdict(ch.ok), ch.why))
    return rows


# ------------------------------------------------------------------------------------------------------------


def machine() -> str:
    model = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} CPUs ({model}), Python {platform.python_version()}, load average " \
           f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}"


def print_table(rows: list[Row]) -> None:
    head = Row("benchmark", "result", "unit", "target", "ok", "notes")
    cols = ("name", "result", "unit", "target", "ok")
    widths = {c: max(len(getattr(r, c)) for r in (head, *rows)) for c in cols}

    def line(r: Row) -> str:
        cells = [r.name.ljust(widths["name"]), r.result.rjust(widths["result"]), r.unit.ljust(widths["unit"]),
                 r.target.ljust(widths["target"]), r.ok.ljust(widths["ok"]), r.notes]
        return "  ".join(cells).rstrip()

    print(line(head))
    print("-" * len(line(head)))
    for r in rows:
        print(line(r))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skip", default="", help=f"comma-separated groups to leave out: {', '.join(GROUPS)}")
    ap.add_argument("--seconds", type=float, default=1.0, help="simulated seconds of the plant rows")
    ap.add_argument("--repeats", type=int, default=10, help="timed runs of the plant rows (the best counts)")
    ap.add_argument("--points", type=int, default=1000, help="sweep points (multiple of 100)")
    ap.add_argument("--workers", type=int, default=2, help="sweep worker processes")
    ap.add_argument("--periods", type=int, default=30, help="measured electrical periods per sweep case")
    ap.add_argument("--sweep-repeats", type=int, default=2, help="timed sweep runs of each kind (the best counts)")
    ap.add_argument("--compare-repeats", type=int, default=1, help="runs of bldclab compare (median)")
    ap.add_argument("--motulator-venv", type=Path, default=None, help="motulator's virtual environment "
                    "(default benchmarks/.venv-motulator)")
    ap.add_argument("--python", help="Python >= 3.12 for motulator's environment (default: found)")
    ap.add_argument("--out", type=Path, default=None, help="directory for saved trajectories (default out/benchmarks)")
    ap.add_argument("--allow-miss", action="store_true", help="exit 0 even when rows miss their target (exploring)")
    ap.add_argument("--sweep-child", nargs=5, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.sweep_child:
        mode, points, workers, periods, trace = args.sweep_child
        print(json.dumps(sweep_child(mode, int(points), int(workers), int(periods), trace == "1")))
        return 0
    skip = {s.strip() for s in args.skip.split(",") if s.strip()}
    unknown = skip - set(GROUPS)
    if unknown:
        ap.error(f"unknown group(s) {', '.join(sorted(unknown))}; groups: {', '.join(GROUPS)}")
    if args.points < 100 or args.points % 100:
        ap.error("--points must be a multiple of 100")
    mc_defaults = load("motulator_case")
    venv = args.motulator_venv or mc_defaults.DEFAULT_VENV
    out = args.out or mc_defaults.DEFAULT_OUT
    out.mkdir(parents=True, exist_ok=True)

    print(f"bldclab benchmarks on {machine()}")
    t_start = time.perf_counter()
    groups: list[tuple[str, Callable[[], list[Row]]]] = [
        ("plant", lambda: plant_rows(args.seconds, args.repeats)),
        ("sine", lambda: sine_rows(args.seconds, args.repeats)),
        ("compare", lambda: compare_rows(args.compare_repeats)),
        ("effmap", lambda: effmap_rows(20, args.workers)),
        ("cli", lambda: cli_rows(5)),
        ("sweep", lambda: sweep_rows(args.points, args.workers, args.periods, args.sweep_repeats,
                                     "memory" not in skip, True)),
        ("firmware", firmware_rows),
        ("cost", cost_rows),
        ("motulator", lambda: motulator_rows(5, venv, args.python, out)),
        ("sensorless", lambda: sensorless_rows(venv, args.python, out)),
    ]
    if "sweep" in skip and "memory" not in skip:
        groups.append(("memory", lambda: sweep_rows(args.points, args.workers, args.periods, 1, True, False)))
    rows: list[Row] = []
    failed = False
    for name, fn in groups:
        if name in skip:
            continue
        try:
            rows += fn()
        except Exception as exc:  # one broken group must not hide the others
            failed = True
            rows.append(Row(f"{name}", "error", "", "", "", f"{type(exc).__name__}: {str(exc)[:100]}"))
            traceback.print_exc(file=sys.stderr)
    print_table(rows)
    print(f"total {time.perf_counter() - t_start:.0f} s; load average at end "
          f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    return exit_code(rows, failed, args.allow_miss)


def exit_code(rows: list[Row], failed: bool, allow_miss: bool) -> int:
    """1 if a measurement failed or (unless ``allow_miss``) a row missed its target; the missed rows go to stderr."""
    missed = [r for r in rows if r.ok == "NO"]
    if missed:
        print(f"{len(missed)} row(s) missed their target{' (--allow-miss: exit code 0)' if allow_miss else ''}:",
              file=sys.stderr)
        for r in missed:
            print(f"  {r.name}: {r.result} {r.unit}, target {r.target}", file=sys.stderr)
    return 1 if failed or (missed and not allow_miss) else 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Side by side with an earlier build: wall time per simulated second of two builds of the C core, and instructions.

``python benchmarks/versus.py REV`` builds the core of git revision REV (a ``git archive`` of it, compiled by that
revision's own ``setup.py build_ext``, as pip builds it) and of the working tree into a temporary directory, each
beside its own copy of the Python package; nothing in the working tree or its git state changes. It then measures
both, alternating between them in fresh processes, and prints a table: controller, REV s/s, HEAD s/s, ratio.

The measure is the marginal wall time per simulated second: the time of a long run minus that of a short one, over
the difference of their durations (each the best of two in the process), after a warm-up run, so that imports, the
core's loading and the fixed Python setup of a ``simulate`` call cancel; the best (smallest) of ``--repeats``
processes per build counts, since other load only ever slows a run down. The scenarios: htm-48v at 0.5 ``Omega_0``
imposed, rated current, no trace: ``SixStep`` (torque reference ``T_N``) and ``Sine`` (``T_s,N = 18 / (sqrt(3)
pi^2) T_N``, paper 1 (12)). The measuring processes use only ``bldclab.load``, ``simulate``, ``Scenario``,
``SixStep`` and ``Sine``, so that an old package layout works. The thread's CPU time is measured alongside (less
sensitive to other load, not to everything).

``--instructions`` also counts, under callgrind, the core's instructions and calls out of one short run of each
scenario on both builds (``cost.py``'s parser): deterministic, where wall times on a shared machine are not.

Run: ``python benchmarks/versus.py REV [--controllers sixstep,sine] [--repeats 3] [--new REV2] [--instructions]``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CONTROLLERS = ("sixstep", "sine")
T_SN_PU = 18.0 / (math.sqrt(3.0) * math.pi**2)  # T_s,N / T_N, paper 1 (12)
INNER = 2  # short and long runs per process (each the best of these)


def _cost() -> Any:
    key = "bench_cost"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, HERE / "cost.py")
        assert spec is not None and spec.loader is not None
        mod = importlib.util.module_from_spec(spec)
        sys.modules[key] = mod
        spec.loader.exec_module(mod)
    return sys.modules[key]


# ------------------------------------------------------------------------------------------------------------
# in the measuring processes: public API only


def _scenario(name: str, duration: float) -> tuple[Any, Any, Any]:
    import bldclab as bl

    drive = bl.load("htm-48v")
    om = 0.5 * drive.Omega_0
    if name == "sixstep":
        ctl, ref = bl.SixStep(reference="torque"), drive.T_N  # I = T_N / (2 k_phi) = I_N
    elif name == "sine":
        ctl, ref = bl.Sine(), T_SN_PU * drive.T_N
    else:
        raise ValueError(f"no scenario {name!r}")
    return drive, ctl, bl.Scenario(duration=duration, speed=om, ref=ref, trace=False)


def time_child(names: Sequence[str], short: float, long: float) -> dict[str, Any]:
    """Marginal wall and CPU seconds per simulated second of each scenario, in this process."""
    import bldclab as bl

    out: dict[str, Any] = {"bldclab": bl.__file__}
    for name in names:
        drive, ctl, _ = _scenario(name, short)

        def run(duration: float, drive: Any = drive, ctl: Any = ctl, name: str = name) -> tuple[float, float]:
            sc = _scenario(name, duration)[2]
            w0, c0 = time.perf_counter(), time.thread_time()
            bl.simulate(drive, ctl, sc)
            return time.perf_counter() - w0, time.thread_time() - c0

        run(0.05)  # warm-up: the core loaded, caches and lazy bindings done
        shorts, longs = [], []
        for _ in range(INNER):  # the best short and the best long run of the process
            shorts.append(run(short))
            longs.append(run(long))
        (ws, cs), (wl, cl) = (tuple(map(min, zip(*shorts, strict=True))), tuple(map(min, zip(*longs, strict=True))))
        out[name] = {"wall": (wl - ws) / (long - short), "cpu": (cl - cs) / (long - short)}
    return out


def count_child(name: str, duration: float, marks: str) -> dict[str, Any]:
    """One simulate call under callgrind's instrumentation (``cost.py``'s runner, public API only)."""
    import ctypes

    import bldclab as bl

    drive, ctl, sc = _scenario(name, duration)
    bl.simulate(drive, ctl, _scenario(name, 0.5 / drive.inverter.f_pwm)[2])  # warm-up: one sample
    lib = ctypes.CDLL(marks)
    lib.cg_start()
    res = bl.simulate(drive, ctl, sc)
    lib.cg_stop()
    return {"bldclab": bl.__file__, "samples": res.meta["samples"]}


# ------------------------------------------------------------------------------------------------------------
# builds


@dataclass
class Side:
    """One build: its key ("old", "new"), its label for the table, and the directory to put on PYTHONPATH."""

    key: str
    label: str
    what: str
    pythonpath: Path
    marks: Path | None = None


def git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, check=True, capture_output=True, text=True).stdout.strip()


def export(rev: str, dest: Path) -> str:
    """Extract the tree of ``rev`` into ``dest`` (``git archive``: no worktree, no checkout); return its full hash."""
    sha = git("rev-parse", "--verify", f"{rev}^{{commit}}")
    dest.mkdir(parents=True)
    tar = dest.parent / f"{dest.name}.tar"
    subprocess.run(["git", "archive", "--format=tar", "-o", str(tar), sha], cwd=ROOT, check=True)
    subprocess.run(["tar", "-x", "-f", str(tar), "-C", str(dest)], check=True)
    tar.unlink()
    return sha


def prepare_side(rev: str | None, tmp: Path, name: str) -> Side:
    """Build REV (or, for None, the working tree) into ``tmp/name``."""
    cost = _cost()
    out = tmp / name
    if rev is None:
        head = git("rev-parse", "--short", "HEAD")
        dirty = git("status", "--porcelain", "--", "core", "src", "setup.py")
        label = "HEAD" + ("+" if dirty else "")
        what = f"working tree at {head}" + (" with uncommitted changes to core/, src/ or setup.py" if dirty else "")
        src = ROOT
    else:
        src = tmp / f"{name}-src"
        sha = export(rev, src)
        label, what = rev, f"{sha[:10]} ({git('log', '-1', '--format=%cs %s', sha)[:70]})"
    out.mkdir(parents=True)
    return Side(name, label, what, cost.build_tree(src, out))


# ------------------------------------------------------------------------------------------------------------
# measuring


def _child(side: Side, args: list[str], valgrind: list[str] | None = None) -> dict[str, Any]:
    cost = _cost()
    cmd = [*(valgrind or []), sys.executable, str(Path(__file__).resolve()), *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=cost.child_env(side.pythonpath))
    if proc.returncode != 0:
        raise RuntimeError(f"{side.label}: {' '.join(args)} failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    if not Path(info["bldclab"]).resolve().is_relative_to(side.pythonpath.resolve()):
        raise RuntimeError(f"{side.label}: imported bldclab from {info['bldclab']}, not from {side.pythonpath}")
    return info


def time_sides(sides: Sequence[Side], names: Sequence[str], repeats: int, short: float,
               long: float) -> dict[str, dict[str, dict[str, float]]]:
    """Best of ``repeats`` fresh processes per side, the sides alternating (ABBA...); side -> name -> wall, cpu."""
    best: dict[str, dict[str, dict[str, float]]] = {s.key: {} for s in sides}
    for r in range(repeats):
        for side in (sides if r % 2 == 0 else list(reversed(sides))):
            info = _child(side, ["--time-child", ",".join(names), "--short", repr(short), "--long", repr(long)])
            for n in names:
                b = best[side.key].setdefault(n, {"wall": math.inf, "cpu": math.inf})
                b["wall"] = min(b["wall"], info[n]["wall"])
                b["cpu"] = min(b["cpu"], info[n]["cpu"])
    return best


def count_sides(sides: Sequence[Side], names: Sequence[str], duration: float,
                tmp: Path) -> dict[tuple[str, str], Any]:
    """Core instructions and calls out of one run of each scenario on each side (valgrind processes in parallel)."""
    cost = _cost()
    marks = cost.build_marks(tmp)

    def one(side: Side, name: str) -> Any:
        cg = tmp / f"callgrind.{side.key}.{name}"
        _child(side, ["--count-child", name, "--duration", repr(duration), "--marks", str(marks)],
               cost.valgrind_cmd(cg))
        return cost.parse(cg).core_cost()

    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as ex:
        futures = {(s.key, n): ex.submit(one, s, n) for s in sides for n in names}
        return {k: f.result() for k, f in futures.items()}


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rev", nargs="?", help="the earlier git revision (any name git knows: 0ea318a, main~3, a tag)")
    ap.add_argument("--new", help="compare against this revision instead of the working tree")
    ap.add_argument("--controllers", default=",".join(CONTROLLERS), help=f"among {', '.join(CONTROLLERS)}")
    ap.add_argument("--repeats", type=int, default=3, help="fresh processes per build (the best counts)")
    ap.add_argument("--short", type=float, default=0.1, help="simulated seconds of the short run")
    ap.add_argument("--long", type=float, default=1.1, help="simulated seconds of the long run")
    ap.add_argument("--instructions", action="store_true", help="also count instructions under callgrind")
    ap.add_argument("--count-seconds", type=float, default=0.1, help="simulated seconds of the counted run")
    ap.add_argument("--time-child", help=argparse.SUPPRESS)
    ap.add_argument("--count-child", help=argparse.SUPPRESS)
    ap.add_argument("--duration", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--marks", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.time_child:
        print(json.dumps(time_child(args.time_child.split(","), args.short, args.long)))
        return 0
    if args.count_child:
        print(json.dumps(count_child(args.count_child, args.duration, args.marks)))
        return 0
    if not args.rev:
        ap.error("give the earlier revision, e.g. python benchmarks/versus.py 0ea318a")
    names = [n.strip() for n in args.controllers.split(",") if n.strip()]
    bad = [n for n in names if n not in CONTROLLERS]
    if bad or not names:
        ap.error(f"--controllers: among {', '.join(CONTROLLERS)}, got {args.controllers!r}")
    if not 0 < args.short < args.long or args.repeats < 1:
        ap.error("needs 0 < --short < --long and --repeats >= 1")
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="bldclab-versus-") as d:
        tmp = Path(d)
        try:
            old = prepare_side(args.rev, tmp, "old")
            new = prepare_side(args.new, tmp, "new")
        except (subprocess.CalledProcessError, RuntimeError) as exc:
            print(f"cannot build: {exc}", file=sys.stderr)
            return 2
        if new.label == old.label:
            new.label += "'"
        print(f"old: {old.label} = {old.what}")
        print(f"new: {new.label} = {new.what}")
        print(f"htm-48v, 0.5 Omega_0 imposed, I_N (SixStep: torque T_N; Sine: T_s,N), no trace; marginal time per "
              f"simulated second ({args.long:g} s run minus {args.short:g} s run), best of {args.repeats} fresh "
              "processes per build, alternating; load average "
              + " ".join(f"{v:.2f}" for v in os.getloadavg()))
        best = time_sides([old, new], names, args.repeats, args.short, args.long)
        w = max(len(old.label), len(new.label), 8)
        print(f"{'controller':<10}  {old.label + ' s/s':>{w + 4}}  {new.label + ' s/s':>{w + 4}}  {'ratio':>6}    "
              f"{'CPU ' + old.label:>{w + 4}}  {'CPU ' + new.label:>{w + 4}}  {'ratio':>6}")
        for n in names:
            a, b = best["old"][n], best["new"][n]
            print(f"{n:<10}  {a['wall']:>{w + 4}.4f}  {b['wall']:>{w + 4}.4f}  {b['wall'] / a['wall']:>6.2f}    "
                  f"{a['cpu']:>{w + 4}.4f}  {b['cpu']:>{w + 4}.4f}  {b['cpu'] / a['cpu']:>6.2f}")
        print(f"(ratio = {new.label} / {old.label}: above 1, {new.label} is slower; load average at end "
              + " ".join(f"{v:.2f}" for v in os.getloadavg()) + ")")
        if any(best[k][n][q] <= 0 for k in best for n in names for q in ("wall", "cpu")):
            print("a marginal time <= 0: the noise exceeds the difference of the runs; use a longer --long or more "
                  "--repeats")
        if args.instructions:
            counts = count_sides([old, new], names, args.count_seconds, tmp)
            print(f"\ninstructions in the core under callgrind, one {args.count_seconds:g} s run (calls out: "
                  "their number; their instructions depend on the CPU's libm variants)")
            print(f"{'controller':<10}  {old.label:>{w + 6}}  {new.label:>{w + 6}}  {'ratio':>6}  "
                  f"{'calls out ' + old.label:>{w + 10}}  {'calls out ' + new.label:>{w + 10}}")
            for n in names:
                a, b = counts["old", n], counts["new", n]
                print(f"{n:<10}  {a.instructions:>{w + 6},}  {b.instructions:>{w + 6},}  "
                      f"{b.instructions / a.instructions:>6.3f}  {a.calls_out_count:>{w + 10},}  "
                      f"{b.calls_out_count:>{w + 10},}")
    print(f"({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

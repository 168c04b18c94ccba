"""Firmware table: each controller cross-compiled for a Cortex-M4F, and its cost per step in closed loop.

- Flash and RAM per controller: the controllers (``core/ctrl/src/*.c``, exactly what ``make -C core firmware``
  cross-compiles; never the plant side in ``core/host``) are built with Debian's gcc-arm-none-eabi and
  newlib (``-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard``, C99, the project's warnings as errors), linked
  into the bare-metal harness ``core/firmware/harness.c`` one controller at a time with ``--gc-sections``; the cost
  is the image size minus the empty harness (libm functions a controller pulls in are included).
- Instructions per step in closed loop, mean and worst: each controller runs against the switching-level plant
  (``bldclab.simulate``) in three scenarios, start-up from standstill with rotor dynamics and steady state at 0.5
  and 0.95 ``Omega_0`` imposed; every controller input (``bc_ctrl_in``) and output is recorded, then replayed into
  the controller built on the host at ``-O2`` (``core/firmware/replay.c``) under ``valgrind --tool=callgrind`` with
  one profile dump per step. The worst step is exact (every step is counted), and the replayed outputs must equal
  the recorded ones bit for bit, so the replay is the closed loop. Host x86-64 instructions at ``-O2`` are a proxy
  for Cortex-M4F cycles, not a measurement of them (single-precision FPU, no FMA contraction in the host build,
  newlib's libm there, glibc's here); the share of a 14 kHz double-update period (28 kHz sampling: 168 MHz /
  28 kHz = 6,000 cycles) is that proxy over 6,000.
- Synthetic scenarios (``core/firmware/cost.c``: a turning motor, an edge at every step, invalid Hall codes,
  non-finite measurements; worst of the four), kept as an extra column: the only measure of the blocks that are not
  controllers (``hall``, ``pi``), and of the safe-state paths a closed loop does not reach.

Run: ``python benchmarks/firmware.py`` (needs arm-none-eabi-gcc, libnewlib-arm-none-eabi, valgrind with callgrind.h,
cc); about two minutes on 2 cores. ``--controllers sine,lu`` measures some controllers only.
"""

from __future__ import annotations

import argparse
import ctypes
import dataclasses
import importlib.util
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "core"
WARN = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wdouble-promotion", "-Werror"]
ARM = ["-mcpu=cortex-m4", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-mthumb", "-Os", "-ffunction-sections",
       "-fdata-sections"]
CTRL = CORE / "ctrl"
SCENARIOS = ("run", "edge", "invalid", "nan")

#: Cortex-M4F cycles in one sample: 168 MHz core clock, 14 kHz PWM updated at valley and peak (28 kHz)
M4F_CYCLES_PER_SAMPLE = 168e6 / 28e3


def _cost_module() -> Any:
    """``cost.py`` (the build of the tree, the callgrind parser), imported as a module."""
    key = "bench_cost"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, ROOT / "benchmarks" / "cost.py")
        assert spec is not None and spec.loader is not None
        mod = importlib.util.module_from_spec(spec)
        sys.modules[key] = mod
        spec.loader.exec_module(mod)
    return sys.modules[key]


def controller_sources() -> list[Path]:
    """Core sources that run on the MCU: the ctrl half of the core (the host half is plant, runner, binding)."""
    return sorted((CTRL / "src").glob("*.c"))


def _targets(kind: str) -> list[str]:
    """Names of ``core/firmware/targets.txt`` built as ``kind`` ("harness" or "cost")."""
    out = []
    for line in (CORE / "firmware" / "targets.txt").read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if words and kind in words[1:]:
            out.append(words[0])
    return out


def harness_names() -> list[str]:
    """Controllers of the bare-metal harness (core/firmware/harness.c), as listed in targets.txt."""
    return _targets("harness")


def cost_names() -> list[str]:
    """Targets of the host tools (core/firmware/targets.c), as listed in targets.txt."""
    return _targets("cost")


def arm_sizes(tmp: Path) -> dict[str, tuple[int, int]]:
    """(flash, ram) bytes of each harness image: text + data, data + bss."""
    out = {}
    for name in ["none", *harness_names()]:
        elf = tmp / f"{name}.elf"
        cmd = ["arm-none-eabi-gcc", *ARM, *WARN, f"-DBC_FW_{name.upper()}", f"-I{CTRL / 'include'}",
               str(CORE / "firmware" / "harness.c"), *map(str, controller_sources()), "-Wl,--gc-sections",
               "--specs=nosys.specs", "-lm", "-o", str(elf)]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        line = subprocess.run(["arm-none-eabi-size", str(elf)], check=True, capture_output=True,
                              text=True).stdout.splitlines()[-1].split()
        text, data, bss = int(line[0]), int(line[1]), int(line[2])
        out[name] = (text + data, data + bss)
    return out


# ------------------------------------------------------------------------------------------------------------
# synthetic inputs (core/firmware/cost.c)


def instruction_counts(tmp: Path, n: int) -> dict[str, dict[str, float]]:
    """Inclusive instructions per step of each cost target in each synthetic scenario (``cost.c``)."""
    cost = _cost_module()
    exe = tmp / "cost"
    subprocess.run(["cc", "-O2", "-g", *WARN[:1], f"-I{CTRL / 'include'}", str(CORE / "firmware" / "cost.c"),
                    str(CORE / "firmware" / "targets.c"), *map(str, controller_sources()), "-lm", "-o", str(exe)],
                   check=True)
    out: dict[str, dict[str, float]] = {}
    for name in cost_names():
        out[name] = {}
        for sc in SCENARIOS:
            cg = tmp / f"cg.{name}.{sc}"
            subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={cg}", str(exe), name, sc, str(n)],
                           check=True, capture_output=True)
            prof = cost.parse(cg, core_object=lambda ob, exe=exe: ob == str(exe))
            fc = prof.function_cost(f"{name}_step")  # the static wrapper in targets.c
            if fc.calls != n:
                raise RuntimeError(f"{name} {sc}: {fc.calls} calls of {name}_step in the profile, expected {n}")
            out[name][sc] = fc.inclusive_per_call
    return out


# ------------------------------------------------------------------------------------------------------------
# closed loop: record the controller's inputs against the plant, replay them with one dump per step


@dataclass(frozen=True)
class ClosedLoop:
    """A controller measured in closed loop: its registry name, step function, and the runs it is measured in."""

    name: str  # row of the table
    registry: str  # bldclab core registry name (and replay.c's target)
    step: str  # the C function whose inclusive instructions per call are measured
    runs: Callable[[float], list[tuple[str, Any, Any, Any]]]  # scale of durations -> [(label, drive, control, sc)]


START, HALF, FULL = "start", "0.5 Omega_0", "0.95 Omega_0"
#: simulated time of the runs (s): the start-up from standstill, and each steady state (from the first sample)
T_START, T_STEADY = 0.15, 0.05


def _torque_runs(drive_name: str, make: Callable[[], Any], ref: Callable[[Any], float]):
    """Start-up from standstill (rotor dynamics, no load) and steady state at 0.5 and 0.95 Omega_0 imposed."""
    def runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
        import bldclab as bl

        d = bl.load(drive_name)
        r = ref(d)
        t0, t1 = scale * T_START, scale * T_STEADY
        return [(START, d, make(), bl.Scenario(duration=t0, ref=r, trace=False)),
                (HALF, d, make(), bl.Scenario(duration=t1, speed=0.5 * d.Omega_0, ref=r, trace=False)),
                (FULL, d, make(), bl.Scenario(duration=t1, speed=0.95 * d.Omega_0, ref=r, trace=False))]
    return runs


def _lu_runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
    """Lu's torque runs at T_N, and light load (T_N / 4 at 0.2 Omega_0): there the current stops in every PWM
    period and the mean law solves a whole period's mean at every period's start, its costliest steady state."""
    import bldclab as bl

    d = bl.load("lu-4kw")
    light = ("0.2 Omega_0, T_N/4", d, _lu(), bl.Scenario(duration=scale * T_STEADY, speed=0.2 * d.Omega_0,
                                                         ref=0.25 * d.T_N, trace=False))
    return [*_torque_runs("lu-4kw", _lu, lambda dd: dd.T_N)(scale), light]


def _sixv_runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
    import bldclab as bl

    d = bl.load("htm-48v")
    m = d.motor

    def duty(om: float) -> float:  # about I_N at that speed (plant_speed.py)
        return min(1.0, (2 * m.k_phi * om + 2 * m.R * m.I_N) / d.inverter.V_dc)

    ctl = bl.SixStepVoltage("high")
    t0, t1 = scale * T_START, scale * T_STEADY
    return [(START, d, ctl, bl.Scenario(duration=t0, ref=duty(0.0), trace=False)),
            (HALF, d, ctl, bl.Scenario(duration=t1, speed=0.5 * d.Omega_0, ref=duty(0.5 * d.Omega_0), trace=False)),
            (FULL, d, ctl, bl.Scenario(duration=t1, speed=0.95 * d.Omega_0, ref=duty(0.95 * d.Omega_0),
                                       trace=False))]


def _hallcal_runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
    """The open-loop calibration from standstill (rotor free), the whole routine with one revolution each way."""
    import bldclab as bl

    d = bl.load("htm-48v")
    ctl = bl.HallCal(method="open-loop", revolutions=1)
    return [(START, d, ctl, bl.Scenario(duration=scale * (ctl.duration() + 0.01), theta0=0.3, trace=False))]


def _hallcal_speed_runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
    """The constant-speed calibration (legs off) at 0.5 and 0.95 Omega_0 imposed, to its end."""
    import bldclab as bl

    d = bl.load("htm-48v")
    out = []
    for label, pu in ((HALF, 0.5), (FULL, 0.95)):
        w = pu * d.Omega_0
        t = (1 + 2.5) * 2 * math.pi / (w * d.motor.p)
        ctl = bl.HallCal(method="constant-speed", revolutions=1, timeout=t)
        out.append((label, d, ctl, bl.Scenario(duration=scale * t, speed=w, theta0=0.3, trace=False)))
    return out


def _bemf_runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
    """The sensorless six-step from standstill (rotor free, duty 0.5) on the plant's back-EMF sensing: alignment, the
    forced ramp, the handover at about 0.49 s and closed loop on the comparators' crossings to 0.6 s."""
    import bldclab as bl

    d = bl.load("htm-48v")
    return [(START, d, bl.SixStepSensorless(), bl.Scenario(duration=scale * 0.6, ref=0.5, trace=False))]


def _bemf_drone_runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
    """The sensorless six-step on the 5-inch drone motor with its propeller (f60prov-2550kv, 48 kHz, 1.6 samples per
    30 degrees at Omega_0): from standstill at throttle 0.5 through the start (closed loop after about 80 ms) into
    the steady state at about 0.5 Omega_0, and a step to full throttle at 0.25 s (the fast demagnetisation and the
    demagnetisation limiter at work), to 0.4 s."""
    import numpy as np

    import bldclab as bl

    d = bl.load("f60prov-2550kv")
    dur = scale * 0.4
    t = np.arange(bl.sim.samples_of(d, dur)) * 0.5 / d.inverter.f_pwm
    ref = np.where(t < scale * 0.25, 0.5, 1.0)
    return [(START, d, bl.SixStepSensorless(), bl.Scenario(duration=dur, ref=ref, trace=False))]


def _sine_obs_runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
    """The sensorless Sine (flux observer) from standstill (rotor free) on its speed loop to 0.5 Omega_0: alignment,
    the I/f ramp, the hand-off and the observer's closed loop."""
    import bldclab as bl

    d = bl.load("htm-48v")
    ctl = bl.Sine(angle="observer", speed_loop=True)
    return [(START, d, ctl, bl.Scenario(duration=scale * 1.0, omega_ref=0.5 * d.Omega_0, trace=False))]


def _commission_runs(scale: float) -> list[tuple[str, Any, Any, Any]]:
    """The whole self-commissioning routine on htm-48v (rotor free at rest)."""
    import bldclab as bl

    d = bl.load("htm-48v")
    ctl = bl.control.Commission()
    return [(START, d, ctl, bl.Scenario(duration=scale * 1.02 * ctl.duration(d), trace=False))]


def _sine_ref(d: Any) -> float:
    return 18.0 / (math.sqrt(3.0) * math.pi**2) * d.T_N  # T_s,N, paper 1 (12)


def _sixstep() -> Any:
    import bldclab as bl

    return bl.SixStep(reference="torque")


def _sine() -> Any:
    import bldclab as bl

    return bl.Sine()


def _lu() -> Any:
    import bldclab as bl

    return bl.Lu()


CLOSED_LOOP: dict[str, ClosedLoop] = {c.name: c for c in (
    ClosedLoop("sixstep", "sixstep", "bc_sixstep_step", _torque_runs("htm-48v", _sixstep, lambda d: d.T_N)),
    ClosedLoop("sine", "sine", "bc_sine_step", _torque_runs("htm-48v", _sine, _sine_ref)),
    ClosedLoop("lu", "lu", "bc_lu_step", _lu_runs),
    ClosedLoop("sixv", "sixv", "bc_sixv_step", _sixv_runs),
    ClosedLoop("hallcal", "hallcal", "bc_hallcal_step", _hallcal_runs),
    ClosedLoop("hallcal_speed", "hallcal", "bc_hallcal_step", _hallcal_speed_runs),
    ClosedLoop("bemf", "bemf", "bc_bemf_step", _bemf_runs),
    ClosedLoop("bemf_drone", "bemf", "bc_bemf_step", _bemf_drone_runs),
    ClosedLoop("sine_obs", "sine", "bc_sine_step", _sine_obs_runs),
    ClosedLoop("commission", "commission", "bc_commission_step", _commission_runs),
)}


def replay_library(out: Path) -> Path:
    """Build ``core/firmware/replay.c`` with the controllers (``-O2``, like the cost harness) as a shared library."""
    so = out / "replay.so"
    proc = subprocess.run(["cc", "-O2", "-g", "-fPIC", "-shared", *WARN[:1], f"-I{CTRL / 'include'}",
                           str(CORE / "firmware" / "replay.c"), *map(str, controller_sources()), "-lm", "-o", str(so)],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"cannot build replay.c (valgrind's callgrind.h missing?):\n{proc.stderr[-2000:]}")
    return so


def closed_loop_child(name: str, replay: str, scale: float = 1.0, save: str | None = None) -> dict[str, Any]:
    """In the measuring process (under valgrind, instrumentation off): record each run, replay it with dumps (and
    keep the recorded inputs and outputs in ``save``/rec.NAME.J.npz)."""
    import numpy as np

    import bldclab as bl
    from bldclab._core import core

    spec = CLOSED_LOOP[name]
    c = core()
    info = c.controllers[spec.registry]
    lib = ctypes.CDLL(replay)
    sizes = (ctypes.c_int64 * 4)()
    if lib.bc_fw_sizes(spec.registry.encode(), sizes) != 0:
        raise RuntimeError(f"replay.c has no target {spec.registry}")
    want = (c.sizes[info.params], c.sizes[info.state], c.sizes["bc_ctrl_in"], c.sizes["bc_ctrl_out"])
    if tuple(sizes) != want:
        raise RuntimeError(f"{spec.registry}: replay.c's struct sizes {tuple(sizes)} differ from the core's {want}")
    lib.bc_fw_record_begin.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int64)
    lib.bc_fw_record_count.restype = ctypes.c_int64
    lib.bc_fw_replay.argtypes = (ctypes.c_char_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                                 ctypes.c_int64, ctypes.c_int)
    recorder = ctypes.cast(lib.bc_fw_record_step, ctypes.c_void_p).value
    out = []
    for label, drive, ctl, sc in spec.runs(scale):
        cap = math.ceil(sc.duration * 2.0 * drive.inverter.f_pwm) + 2
        rec_in = np.zeros(cap, dtype=c.dtypes["bc_ctrl_in"])
        rec_out = np.zeros(cap, dtype=c.dtypes["bc_ctrl_out"])
        lib.bc_fw_record_begin(info.step_ptr, rec_in.ctypes.data, rec_out.ctypes.data, cap)
        c.controllers[spec.registry] = dataclasses.replace(info, step_ptr=recorder)
        try:
            res = bl.simulate(drive, ctl, sc, check="warn")
        finally:
            c.controllers[spec.registry] = info
        n = int(lib.bc_fw_record_count())
        if n != res.meta["samples"] or n > cap:
            raise RuntimeError(f"{name} {label}: recorded {n} steps of {res.meta['samples']} samples")
        delay = int(res.meta["scenario"]["delay"])  # the delay simulate applied
        cp = ctl.with_delay(delay).c_record(drive, c, n)  # the record simulate built (it is deterministic)
        state = c.opaque(info.state)
        replayed = np.zeros(n, dtype=c.dtypes["bc_ctrl_out"])
        rc = lib.bc_fw_replay(spec.registry.encode(), cp.address, state.ctypes.data, rec_in.ctypes.data,
                              replayed.ctypes.data, n, 1)
        if rc != 0:
            raise RuntimeError(f"{name} {label}: replay init returned {rc}")
        same = replayed.tobytes() == rec_out[:n].tobytes()
        differ = int(np.count_nonzero(replayed.view(np.uint8).reshape(n, -1)
                                      != rec_out[:n].view(np.uint8).reshape(n, -1), axis=None)) if not same else 0
        if save:
            np.savez(Path(save) / f"rec.{name}.{len(out)}.npz", inp=rec_in[:n], out=rec_out[:n])
        out.append({"label": label, "steps": n, "t_sample": 0.5 / drive.inverter.f_pwm, "identical": same,
                    "bytes_differing": differ, "drive": drive.name, "final_omega": res.meta["final"]["omega_m"],
                    "flags": int(res.meta["controller_flags"])})
    return {"bldclab": bl.__file__, "runs": out}


@dataclass
class RunCost:
    """One closed-loop run of a controller: instructions of every step."""

    label: str
    steps: list[int]
    t_sample: float
    identical: bool
    info: dict[str, Any]
    context: list[str] = dataclasses.field(default_factory=list)  # what happened at each step (see step_context)

    @property
    def mean(self) -> float:
        return sum(self.steps) / len(self.steps)

    @property
    def worst(self) -> int:
        return max(self.steps)

    @property
    def worst_at(self) -> float:
        """Time of the worst step (s)."""
        return self.steps.index(self.worst) * self.t_sample


@dataclass
class ControllerCost:
    """A controller's closed-loop runs."""

    name: str
    runs: list[RunCost]
    seconds: float

    @property
    def mean(self) -> float:
        n = sum(len(r.steps) for r in self.runs)
        return sum(sum(r.steps) for r in self.runs) / n

    @property
    def worst_run(self) -> RunCost:
        return max(self.runs, key=lambda r: r.worst)

    @property
    def worst(self) -> int:
        return self.worst_run.worst

    def run(self, label: str) -> RunCost | None:
        return next((r for r in self.runs if r.label == label), None)


def measure_closed_loop(build: Any, replay: Path, name: str, tmp: Path, scale: float = 1.0) -> ControllerCost:
    """One controller's runs in one valgrind process; per-step instructions from its combined dumps."""
    cost = _cost_module()
    spec = CLOSED_LOOP[name]
    cg = tmp / f"callgrind.replay.{name}"
    t0 = time.perf_counter()
    proc = subprocess.run([*cost.valgrind_cmd(cg, ["--combine-dumps=yes"]), sys.executable, __file__, "--child", name,
                           "--replay", str(replay), "--scale", repr(scale), "--save", str(tmp)], capture_output=True,
                          text=True, env=cost.child_env(build.pythonpath))
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"closed loop {name} failed ({proc.returncode}):\n{proc.stdout[-1500:]}"
                           f"{proc.stderr[-3000:]}")
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    if not Path(info["bldclab"]).resolve().is_relative_to(build.pythonpath.resolve()):
        raise RuntimeError(f"closed loop {name} imported bldclab from {info['bldclab']}, not from the build")
    per_step = []
    for trigger, calls, inclusive in cost.calls_per_part(cg, spec.step):
        if "bc_fw_step" not in trigger:
            continue
        if calls != 1:
            raise RuntimeError(f"closed loop {name}: a dump with {calls} calls of {spec.step}, expected 1")
        per_step.append(inclusive)
    cg.unlink()  # up to a few hundred MB
    runs, k = [], 0
    for j, r in enumerate(info["runs"]):
        n = r["steps"]
        rec = tmp / f"rec.{name}.{j}.npz"
        runs.append(RunCost(r["label"], per_step[k:k + n], r["t_sample"], r["identical"], r, step_context(rec)))
        rec.unlink()
        k += n
    if k != len(per_step):
        raise RuntimeError(f"closed loop {name}: {len(per_step)} step dumps for {k} recorded steps")
    return ControllerCost(name, runs, seconds)


def step_context(npz: Path) -> list[str]:
    """For each recorded step: "first" (the run's first sample), "edge" (a Hall edge since the last sample), and the
    controller's flags (SAT = saturated, SAFE, ...)."""
    import numpy as np

    from bldclab._core import decode_flags

    rec = np.load(npz)
    edges = rec["inp"]["n_edges"]
    flags = rec["out"]["flags"]
    out = []
    for k in range(len(edges)):
        what = ["first"] if k == 0 else (["edge"] if edges[k] != edges[k - 1] else [])
        if flags[k]:
            what.append(decode_flags(int(flags[k])))
        out.append(" ".join(what))
    return out


def closed_loop_counts(names: Sequence[str], jobs: int | None = None, scale: float = 1.0) -> dict[str, ControllerCost]:
    """Build the tree and the replay library, then measure each controller in its own valgrind process (``scale``:
    of the runs' durations)."""
    cost = _cost_module()
    with tempfile.TemporaryDirectory(prefix="bldclab-fw-") as d:
        tmp = Path(d)
        build = cost.prepare(cost.ROOT, tmp)
        replay = replay_library(tmp)
        with ThreadPoolExecutor(max_workers=jobs or os.cpu_count() or 1) as ex:
            futures = {n: ex.submit(measure_closed_loop, build, replay, n, tmp, scale) for n in names}
            return {n: f.result() for n, f in futures.items()}


# ------------------------------------------------------------------------------------------------------------


def table(sizes: dict[str, tuple[int, int]], closed: dict[str, ControllerCost],
          synthetic: dict[str, dict[str, float]]) -> list[str]:
    """One row per controller or block: flash, RAM, closed-loop mean and worst per step, M4F share, synthetic."""
    base_flash, base_ram = sizes["none"]
    lines = ["controllers on a Cortex-M4F (arm-none-eabi-gcc -Os, hard float); instructions per step on the host "
             "(-O2) in closed loop",
             f"{'controller':<14} {'flash [B]':>9} {'RAM [B]':>8} {'mean':>6} {'worst':>6} {'M4F share':>9}  "
             f"{'worst in':<24} {'synthetic':>9}"]
    names = [n for n in sorted(set(sizes) | set(closed) | set(synthetic)) if n != "none"]
    for name in names:
        flash, ram = sizes.get(name, (base_flash, base_ram))
        cc = closed.get(name)
        syn = synthetic.get(name)
        cells = [f"{name:<14}", f"{flash - base_flash:>9d}", f"{ram - base_ram:>8d}"]
        if cc is not None:
            w = cc.worst_run
            cells += [f"{cc.mean:>6.0f}", f"{cc.worst:>6d}", f"{cc.worst / M4F_CYCLES_PER_SAMPLE:>9.0%}",
                      f" {w.label + f' at {1e3 * w.worst_at:.1f} ms':<24}"]
        else:
            cells += [f"{'-':>6}", f"{'-':>6}", f"{'-':>9}", f" {'':<24}"]
        cells.append(f"{max(syn.values()):>9.0f}" if syn else f"{'-':>9}")
        lines.append(" ".join(cells).rstrip())
    lines += [f"(baseline harness: {base_flash} B flash, {base_ram} B RAM; RAM includes the static params and state)",
              "(mean, worst: every step of the closed-loop runs below; M4F share: worst / "
              f"{M4F_CYCLES_PER_SAMPLE:,.0f} cycles, the 168 MHz core's budget at 28 kHz sampling; host instructions "
              "are a proxy for M4F cycles, not a measurement of them; synthetic: worst of cost.c's four input "
              "scenarios)"]
    return lines


def run_lines(closed: dict[str, ControllerCost]) -> list[str]:
    """Per run: steps, mean, worst and where, and the replay check."""
    lines = [f"{'controller':<14} {'run':<13} {'drive':<8} {'steps':>6} {'mean':>6} {'worst':>6} {'at [ms]':>8} "
             f"{'worst step':<14} {'worst after 5 ms':>16} {'replay':>9}"]
    for name, cc in closed.items():
        for r in cc.runs:
            ok = "identical" if r.identical else f"DIFFERS ({r.info['bytes_differing']} B)"
            k = r.steps.index(r.worst)
            late = r.steps[round(5e-3 / r.t_sample):]
            lines.append(f"{name:<14} {r.label:<13} {r.info['drive']:<8} {len(r.steps):>6d} {r.mean:>6.0f} "
                         f"{r.worst:>6d} {1e3 * r.worst_at:>8.2f} {(r.context[k] if r.context else '') or '-':<14} "
                         f"{max(late) if late else '-':>16} {ok:>9}")
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000, help="steps per synthetic scenario")
    ap.add_argument("--controllers", default="",
                    help=f"closed-loop controllers (default all: {', '.join(CLOSED_LOOP)})")
    ap.add_argument("--jobs", type=int, default=None, help="valgrind processes at a time (default: CPUs)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--replay", help=argparse.SUPPRESS)
    ap.add_argument("--scale", type=float, default=1.0, help=argparse.SUPPRESS)
    ap.add_argument("--save", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(closed_loop_child(args.child, args.replay, args.scale, args.save)))
        return 0
    names = [s.strip() for s in args.controllers.split(",") if s.strip()] or list(CLOSED_LOOP)
    unknown = [n for n in names if n not in CLOSED_LOOP]
    if unknown:
        ap.error(f"unknown controller(s) {', '.join(unknown)}; closed-loop controllers: {', '.join(CLOSED_LOOP)}")
    for tool in ("arm-none-eabi-gcc", "valgrind", "cc"):
        if shutil.which(tool) is None:
            print(f"missing tool: {tool} (tools/install-system-deps installs it)", file=sys.stderr)
            return 1
    t0 = time.perf_counter()
    closed = closed_loop_counts(names, args.jobs)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        sizes = arm_sizes(tmp)
        synthetic = instruction_counts(tmp, args.steps)
    print("\n".join(table(sizes, closed, synthetic)))
    print()
    print("\n".join(run_lines(closed)))
    print(f"({time.perf_counter() - t0:.0f} s)")
    bad = [f"{n} {r.label}" for n, cc in closed.items() for r in cc.runs if not r.identical]
    if bad:
        print(f"replayed outputs differ from the closed loop: {', '.join(bad)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

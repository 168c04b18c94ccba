"""Cost gate: instructions of the C core per scenario under callgrind, against the budgets in cost_budget.toml.

Instruction counts are deterministic for one build and one input (unlike wall time), so they can be gated:
``tests/test_cost_gate.py`` fails when a scenario needs more than 3 % above its budget. What is counted, per
scenario (one ``bldclab.simulate`` call, run in its own ``valgrind --tool=callgrind`` process):

- ``instructions``: the instructions executed in the core library's own code (``_bccore``), the gated number;
- ``calls out``: the calls from the core into other objects (libm, libc), gated by their number; their
  instructions are reported only, because glibc picks FMA or SSE variants of ``sin``/``cos``/``memcpy`` by CPU;
- ``<fn>/call``: for scenarios with a controller, the core's own instructions of one controller step
  (``bc_sine_step`` ...: inclusive, minus the library calls inside it), mean over the run; where the link-time
  optimisation inlined the step into its binding's wrapper (``sine_step`` in ``bc_bind_sine.c``, called through a
  pointer), the wrapper's calls, which add its call overhead (a few instructions).

The core is built fresh from this tree's sources exactly as ``pip install`` builds it (``setup.py build_ext``: the
setuptools compiler flags plus the project's), into a temporary directory beside a copy of the Python package, so
the numbers belong to the sources, not to whichever library happens to be installed. Each run imports bldclab
uninstrumented (``--instr-atstart=no``), simulates a one-sample warm-up (core loaded, lazy symbol binding done),
then turns the instrumentation on for the measured call only (``cg_marks.c``).

The budget file holds each number and a one-line reason per scenario. Changing a budget is a deliberate commit:
``--update --why "..."`` rewrites the numbers from a run, prints every old -> new, and keeps the other reasons.

Run: ``python benchmarks/cost.py [--scenarios a,b] [--jobs N] [--update --why TEXT]``; ``--list`` names the
scenarios. The whole set takes about a minute on 2 cores (valgrind, cc and valgrind's callgrind.h needed).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
BUDGET_FILE = HERE / "cost_budget.toml"
MARKS_SOURCE = HERE / "cg_marks.c"

#: A scenario fails above this ratio of measured to budget
TOLERANCE = 1.03
#: ... and is reported stale ("lower it") below this one
STALE = 0.90


# ============================================================================================================
# callgrind output: a parser of the format (valgrind's "Callgrind Format Specification", version 1)
#
# Body lines: ``ob=``/``fl=``/``fn=`` set the object, file and function of the cost lines that follow (``fi=`` and
# ``fe=`` switch the file inside a function: inlined code); a cost line is positions then event counts; a call is
# ``cob=`` (callee object, only when it differs from the caller's; for this call only), ``cfi=`` (callee file),
# ``cfn=`` (callee function), ``calls=COUNT TARGET`` and one cost line whose counts are the calls' inclusive cost.
# Names are compressed: ``(id) name`` on first use, ``(id)`` after, one id space per kind (objects; files; functions)
# for the whole file, also across the parts of a file written with --combine-dumps=yes.
#
# A function entered from libffi (every ctypes call: bc_sim_run, bc_sim_init, a controller's init) is not seen as
# entered: callgrind books its instructions under the libffi function that called it, with the core's source file
# in ``fi=`` lines. A file belongs to one object, so those lines are found by their file: a file is the core's
# when it appears as the file of a core function (``fl=``/``fe=`` under a core ``ob=``, ``cfi=`` of a call into
# the core) or, never seen so, when its path is a core source (the core is built with -g).


_KIND = {"ob": "ob", "cob": "ob", "fl": "fl", "fi": "fl", "fe": "fl", "cfi": "fl", "cfl": "fl", "fn": "fn", "cfn": "fn"}
_NAME = re.compile(r"\((\d+)\)(?: (.*))?$")


@dataclass
class Part:
    """One dump of a callgrind file (one per file unless dumps are combined)."""

    number: int
    trigger: str = ""
    #: (object, function, file) -> instructions (self cost)
    self_cost: dict[tuple[str, str, str], int] = field(default_factory=lambda: defaultdict(int))
    #: (caller object, caller function, file of the call site, callee object, callee function) -> [calls, inclusive]
    arcs: dict[tuple[str, str, str, str, str], list[int]] = field(default_factory=dict)


@dataclass
class FunctionCost:
    """Calls of one core function: count, inclusive instructions, and the part of them in other objects."""

    calls: int
    inclusive: int
    external: float

    @property
    def own_per_call(self) -> float:
        """Instructions of the core's own code per call (library calls inside removed)."""
        return (self.inclusive - self.external) / self.calls if self.calls else math.nan

    @property
    def inclusive_per_call(self) -> float:
        return self.inclusive / self.calls if self.calls else math.nan


@dataclass
class CoreCost:
    """What a profile says about the core: its own instructions and its calls into other objects."""

    instructions: int
    #: (object file name, function) -> [calls, inclusive instructions]
    calls_out: dict[tuple[str, str], list[int]]
    #: core function -> own instructions
    by_function: dict[str, int]
    #: own instructions booked under a foreign function (the libffi entry, see above)
    via_foreign: int

    @property
    def calls_out_count(self) -> int:
        return sum(v[0] for v in self.calls_out.values())

    @property
    def calls_out_inclusive(self) -> int:
        return sum(v[1] for v in self.calls_out.values())


def is_core_object(name: str) -> bool:
    """The bldclab core library (``_bccore*.so``)."""
    return Path(name).name.startswith("_bccore")


def is_core_source(path: str) -> bool:
    """A source file of the C core (both halves), by its path."""
    return bool(re.search(r"/core/(ctrl|host)/(src|include)/", path))


class Profile:
    """A parsed callgrind file: names, the object each file belongs to, and the parts.

    Parameters
    ----------
    path : Path
        A callgrind out file (``--callgrind-out-file``).
    core_object, core_source : callable, optional
        What counts as the core: its object file (by name) and, for code booked under a foreign function, its
        source files (by path). Default: ``_bccore*`` and ``core/{ctrl,host}/{src,include}/``.
    """

    def __init__(self, path: Path | str, core_object: Callable[[str], bool] = is_core_object,
                 core_source: Callable[[str], bool] = is_core_source) -> None:
        self.names: dict[str, dict[str, str]] = {"ob": {}, "fl": {}, "fn": {}}
        self.file_object: dict[str, str] = {}  # file key -> object key
        self.parts: list[Part] = []
        self.events: list[str] = []
        self._core_object = core_object
        self._core_source = core_source
        self._read(Path(path))

    # --- reading ---------------------------------------------------------------------------------------------

    def _key(self, kind: str, text: str) -> str:
        """The key of a compressed (``(id) name``, ``(id)``) or plain name; records the name."""
        m = _NAME.match(text)
        if not m:
            self.names[kind].setdefault(text, text)
            return text
        key = m.group(1)
        if m.group(2) is not None:
            self.names[kind][key] = m.group(2)
        elif key not in self.names[kind]:
            raise ValueError(f"callgrind file uses {kind} id ({key}) before defining it")
        return key

    def _read(self, path: Path) -> None:
        part: Part | None = None
        n_pos = 1
        ob = fn = fl = cur = ""
        cob: str | None = None
        cfn = ""
        pending: int | None = None
        skip_line = False
        with path.open() as fh:
            for lineno, raw in enumerate(fh, 1):
                line = raw.rstrip("\n")
                if not line or line[0] == "#":
                    continue
                c0 = line[0]
                if c0.isdigit() or c0 in "+-*":
                    if skip_line:  # the source line of a jump: positions only
                        skip_line = False
                        continue
                    if part is None:
                        part = self._new_part(1)
                    toks = line.split()
                    ir = int(toks[n_pos]) if len(toks) > n_pos else 0
                    if pending is not None:
                        callee_ob = cob if cob is not None else ob
                        a = part.arcs.setdefault((ob, fn, cur, callee_ob, cfn), [0, 0])
                        a[0] += pending
                        a[1] += ir
                        pending, cob = None, None
                    else:
                        part.self_cost[ob, fn, cur] += ir
                    continue
                key, eq, val = line.partition("=")
                if eq and key in _KIND:
                    ident = self._key(_KIND[key], val)
                    if key == "ob":
                        ob = ident
                    elif key == "fl":
                        fl = cur = ident
                        self.file_object.setdefault(ident, ob)
                    elif key == "fe":
                        cur = ident
                        self.file_object.setdefault(ident, ob)
                    elif key == "fi":
                        cur = ident
                    elif key == "fn":
                        fn, cur = ident, fl
                    elif key == "cob":
                        cob = ident
                    elif key in ("cfi", "cfl"):
                        self.file_object.setdefault(ident, cob if cob is not None else ob)
                    else:  # cfn
                        cfn = ident
                    continue
                if eq and key == "calls":
                    pending = int(val.split()[0])
                    continue
                if eq and key in ("jump", "jcnd"):
                    skip_line = True
                    continue
                if eq and key in ("jfi", "jfn"):
                    self._key("fl" if key == "jfi" else "fn", val)
                    continue
                head, colon, rest = line.partition(":")
                if not colon:
                    raise ValueError(f"{path}:{lineno}: cannot read {line[:60]!r}")
                rest = rest.strip()
                if head == "part":
                    part = self._new_part(int(rest))
                    ob = fn = fl = cur = ""
                elif head == "positions":
                    n_pos = len(rest.split())
                elif head == "events":
                    self.events = rest.split()
                    if self.events[0] != "Ir":
                        raise ValueError(f"{path}: first event is {self.events[0]}, not Ir")
                elif head == "desc" and rest.startswith("Trigger:") and part is not None:
                    part.trigger = rest.removeprefix("Trigger:").strip()
                # version, creator, pid, cmd, summary, totals and other desc lines: not needed

    def _new_part(self, number: int) -> Part:
        p = Part(number)
        self.parts.append(p)
        return p

    # --- what the core did -----------------------------------------------------------------------------------

    def name(self, kind: str, key: str) -> str:
        return self.names[kind].get(key, key)

    def _is_core_ob(self, ob: str) -> bool:
        return bool(ob) and self._core_object(self.name("ob", ob))

    def core_files(self) -> set[str]:
        """Files of the core: of a core object where known, else by their path."""
        out = set()
        for f, name in self.names["fl"].items():
            ob = self.file_object.get(f)
            if (ob is not None and self._is_core_ob(ob)) or (ob is None and self._core_source(name)):
                out.add(f)
        return out

    def _parts(self, parts: Iterable[Part] | None) -> list[Part]:
        return list(self.parts if parts is None else parts)

    def core_cost(self, parts: Iterable[Part] | None = None) -> CoreCost:
        """The core's own instructions and its calls out, summed over ``parts`` (default: all)."""
        files = self.core_files()
        parts = self._parts(parts)
        # an object that calls into the core (libffi for ctypes): a "call" into it from core code is the return
        # to it of a function whose entry callgrind did not see, not a call the core makes
        entering = {ob for p in parts for (ob, _fn, f, cob, _cfn) in p.arcs
                    if self._is_core_ob(cob) and not self._is_core_ob(ob)}
        total = foreign = 0
        by_fn: dict[str, int] = defaultdict(int)
        out: dict[tuple[str, str], list[int]] = {}
        for p in parts:
            for (ob, fn, f), ir in p.self_cost.items():
                if self._is_core_ob(ob):
                    total += ir
                    by_fn[self.name("fn", fn)] += ir
                elif f in files:
                    total += ir
                    foreign += ir
                    where = f"{_base(self.name('fl', f))} (entered from {_base(self.name('ob', ob))})"
                    by_fn[where] += ir
            for (ob, _fn, f, cob, cfn), (n, incl) in p.arcs.items():
                from_core = self._is_core_ob(ob) or f in files
                if from_core and not self._is_core_ob(cob) and cob not in entering:
                    a = out.setdefault((_base(self.name("ob", cob)), self.name("fn", cfn)), [0, 0])
                    a[0] += n
                    a[1] += incl
        return CoreCost(total, out, dict(by_fn), foreign)

    def function_cost(self, function: str, parts: Iterable[Part] | None = None) -> FunctionCost:
        """Calls of the core function named ``function``: count, inclusive, and how much of it ran in other objects.

        The external part is exact for calls the function makes itself; for a callee shared with other callers,
        its library instructions are split in proportion to the calls (exact when they do not depend on the
        caller).
        """
        calls_in: dict[str, int] = defaultdict(int)
        incl_in: dict[str, int] = defaultdict(int)
        callees: dict[str, list[tuple[str, int]]] = defaultdict(list)  # core fn -> [(core callee, calls)]
        ext_direct: dict[str, int] = defaultdict(int)
        for p in self._parts(parts):
            for (ob, fn, _f, cob, cfn), (n, incl) in p.arcs.items():
                if self._is_core_ob(cob):
                    calls_in[cfn] += n
                    incl_in[cfn] += incl
                if self._is_core_ob(ob):
                    if self._is_core_ob(cob):
                        callees[fn].append((cfn, n))
                    else:
                        ext_direct[fn] += incl
        memo: dict[str, float] = {}

        def external(g: str, stack: frozenset[str]) -> float:
            if g in memo:
                return memo[g]
            if g in stack:  # recursion: its library calls are counted at the outer level
                return 0.0
            v = float(ext_direct[g])
            for h, n in callees[g]:
                if calls_in[h]:
                    v += n / calls_in[h] * external(h, stack | {g})
            memo[g] = v
            return v

        targets = [k for k, v in self.names["fn"].items() if v == function and calls_in.get(k)]
        return FunctionCost(sum(calls_in[k] for k in targets), sum(incl_in[k] for k in targets),
                            sum(external(k, frozenset()) for k in targets))


def calls_per_part(path: Path | str, function: str) -> list[tuple[str, int, int]]:
    """(trigger, calls, inclusive instructions) of the calls to ``function`` in each part of a callgrind file.

    A fast scan for files with many dumps (one per controller step): only call arcs are read, by callee name.
    """
    fn_names: dict[str, str] = {}
    out: list[tuple[str, int, int]] = []
    trigger, calls, incl = "", 0, 0
    started = False
    cfn = ""
    pending = False
    with Path(path).open() as fh:
        for line in fh:
            if pending:
                if line[0].isdigit() or line[0] in "+-*":
                    if fn_names.get(cfn) == function:
                        incl += int(line.split()[1])  # positions: line (one column), then Ir
                    pending = False
                continue
            if line.startswith(("fn=", "cfn=")):
                m = _NAME.match(line.split("=", 1)[1].rstrip("\n"))
                key = m.group(1) if m else line.split("=", 1)[1].rstrip("\n")
                if m and m.group(2) is not None:
                    fn_names[key] = m.group(2)
                elif not m:
                    fn_names[key] = key
                if line[0] == "c":
                    cfn = key
            elif line.startswith("calls="):
                if fn_names.get(cfn) == function:
                    calls += int(line[6:].split()[0])
                pending = True
            elif line.startswith("part:"):
                if started:
                    out.append((trigger, calls, incl))
                started, trigger, calls, incl = True, "", 0, 0
            elif line.startswith("desc: Trigger:"):
                trigger = line.split(":", 2)[2].strip()
    if started:
        out.append((trigger, calls, incl))
    return out


def _base(path: str) -> str:
    return path.rsplit("/", 1)[-1]


def parse(path: Path | str, **kw: Callable[[str], bool]) -> Profile:
    """Read a callgrind out file (see :class:`Profile`)."""
    return Profile(path, **kw)


# ============================================================================================================
# scenarios: one bldclab.simulate call each (built in the measuring process, where bldclab is the fresh build)


@dataclass(frozen=True)
class Scenario:
    """A gated run: what it simulates and, for a controller, the step function whose cost per call is gated."""

    name: str
    what: str
    build: Callable[[float], tuple[Any, Any, Any]]  # scale of the duration -> (drive, control, bldclab.Scenario)
    step: str | None = None


def _htm(model: str = "switching", name: str = "htm-48v") -> Any:
    import bldclab as bl

    return bl.load(name).replace(inverter__model=model)


def _sixstep(seconds: float, trace: bool, model: str = "switching", drive: str = "htm-48v"):
    def build(scale: float) -> tuple[Any, Any, Any]:
        import bldclab as bl

        d = _htm(model, drive)
        return d, bl.SixStep(reference="torque"), bl.Scenario(duration=seconds * scale, speed=0.5 * d.Omega_0,
                                                              ref=d.T_N, trace=trace)
    return build


def _sine(seconds: float, trace: bool, model: str = "switching"):
    def build(scale: float) -> tuple[Any, Any, Any]:
        import bldclab as bl
        from bldclab.model import analytic as an

        d = _htm(model)
        return d, bl.Sine(), bl.Scenario(duration=seconds * scale, speed=0.5 * d.Omega_0, ref=an.T_SN_PU * d.T_N,
                                         trace=trace)
    return build


def _lu(seconds: float, trace: bool):
    def build(scale: float) -> tuple[Any, Any, Any]:
        import bldclab as bl

        d = bl.load("lu-4kw")  # paper 2's motor at the middle of its grid: 2000 rpm, T_N
        return d, bl.Lu(), bl.Scenario(duration=seconds * scale, speed=2.0 / 3.0 * d.motor.Omega_nominal,
                                       ref=d.T_N, trace=trace)
    return build


def _sixv(seconds: float, trace: bool):
    def build(scale: float) -> tuple[Any, Any, Any]:
        import bldclab as bl

        d = _htm()
        om = 0.5 * d.Omega_0
        m = d.motor
        duty = min(1.0, (2 * m.k_phi * om + 2 * m.R * m.I_N) / d.inverter.V_dc)  # about I_N (plant_speed.py)
        return d, bl.SixStepVoltage("high"), bl.Scenario(duration=seconds * scale, speed=om, ref=duty, trace=trace)
    return build


def _sensorless(seconds: float):
    def build(scale: float) -> tuple[Any, Any, Any]:
        import bldclab as bl

        d = _htm()  # rotor free from standstill: alignment, forced ramp, handover, closed loop on the crossings
        return d, bl.SixStepSensorless(), bl.Scenario(duration=seconds * scale, ref=0.5)
    return build


def _sine_observer(seconds: float):
    def build(scale: float) -> tuple[Any, Any, Any]:
        import bldclab as bl

        d = _htm()  # rotor free from standstill: I/f start, hand-off to the flux observer at about 0.61 s
        return d, bl.Sine(angle="observer"), bl.Scenario(duration=seconds * scale, ref=0.5 * d.T_N)
    return build


def _speed_loop(seconds: float):
    def build(scale: float) -> tuple[Any, Any, Any]:
        mc = _sibling("motulator_case")
        case = mc.shared_case(t_stop=seconds * scale)
        return mc.shared_drive(), mc.shared_control(case), mc.bldclab_scenario(case, trace=False)
    return build


def _sibling(name: str) -> Any:
    """Import a sibling benchmark script as a module (``benchmarks`` is not a package)."""
    import importlib.util

    key = f"bench_{name}"
    if key not in sys.modules:
        spec = importlib.util.spec_from_file_location(key, HERE / f"{name}.py")
        assert spec is not None and spec.loader is not None
        mod = importlib.util.module_from_spec(spec)
        sys.modules[key] = mod
        spec.loader.exec_module(mod)
    return sys.modules[key]


_HTM = "htm-48v, 0.5 Omega_0 imposed"
SCENARIOS: dict[str, Scenario] = {s.name: s for s in (
    Scenario("sixstep", f"SixStep, T_N, {_HTM}, 0.2 s", _sixstep(0.2, False), "bc_sixstep_step"),
    Scenario("sixstep-trace", "the same with a trace", _sixstep(0.2, True)),
    Scenario("sine", f"Sine, T_s,N, {_HTM}, 0.2 s", _sine(0.2, False), "bc_sine_step"),
    Scenario("sine-trace", "the same with a trace", _sine(0.2, True)),
    Scenario("sixstep-avg", "sixstep on the averaged inverter", _sixstep(0.2, False, "average")),
    Scenario("sixstep-avg-trace", "the same with a trace", _sixstep(0.2, True, "average")),
    Scenario("sine-avg", "sine on the averaged inverter", _sine(0.2, False, "average")),
    Scenario("sine-avg-trace", "the same with a trace", _sine(0.2, True, "average")),
    Scenario("lu", "Lu, lu-4kw, T_N, 2000 rpm imposed, 0.2 s", _lu(0.2, False), "bc_lu_step"),
    Scenario("lu-trace", "the same with a trace", _lu(0.2, True)),
    Scenario("sixv", f"SixStepVoltage high, duty for I_N, {_HTM}, 0.2 s", _sixv(0.2, False), "bc_sixv_step"),
    Scenario("sixv-trace", "the same with a trace", _sixv(0.2, True)),
    Scenario("losses", f"SixStep, T_N, htm-48v-losses (switching, recovery, iron), {_HTM[9:]}, 0.2 s",
             _sixstep(0.2, False, drive="htm-48v-losses")),
    Scenario("speed-loop", "motulator's shared case: sinusoidal EMF, rotor dynamics, Sine speed loop, 0.2 s",
             _speed_loop(0.2), "bc_sine_step"),
    Scenario("sensorless", "SixStepSensorless, duty 0.5, htm-48v from standstill (start-up and closed loop), 0.6 s",
             _sensorless(0.6), "bc_bemf_step"),
    Scenario("sine-observer", "Sine on the flux observer, T_N/2, htm-48v from standstill (I/f, hand-off), 1 s",
             _sine_observer(1.0), "bc_sine_step"),
)}


def run_child(name: str, scale: float, marks: str) -> dict[str, Any]:
    """In the measuring process (under valgrind): a one-sample warm-up, then the counted simulate call."""
    import ctypes

    import bldclab as bl

    drive, ctl, sc = SCENARIOS[name].build(scale)
    warm = dataclasses.replace(sc, duration=0.5 / drive.inverter.f_pwm, window=None)
    bl.simulate(drive, ctl, warm, check="off")  # loads the core, binds its library calls, warms numpy's paths
    lib = ctypes.CDLL(marks)
    lib.cg_start()
    res = bl.simulate(drive, ctl, sc)
    lib.cg_stop()
    return {"bldclab": bl.__file__, "samples": res.meta["samples"], "steps": res.meta["stats"]["steps"],
            "events": res.meta["stats"]["events"], "final_omega": res.meta["final"]["omega_m"]}


# ============================================================================================================
# building and measuring


def compiler_version() -> str:
    out = subprocess.run(["cc", "--version"], capture_output=True, text=True)
    return out.stdout.splitlines()[0] if out.returncode == 0 and out.stdout else "cc ?"


def build_tree(root: Path, out: Path, python: str = sys.executable) -> Path:
    """Build the C core of the source tree ``root`` as pip does and put it beside a copy of its Python package.

    ``root/setup.py build_ext`` (that tree's own recipe: the setuptools flags of ``python`` plus the project's;
    -g added if missing) writes the library under ``out/lib``; ``root/src/bldclab`` is copied beside it and compiled
    to bytecode. Returns the directory to put on ``PYTHONPATH``. Nothing is written into ``root``.
    """
    lib = out / "lib"
    env = dict(os.environ)
    env["CFLAGS"] = (env.get("CFLAGS", "") + " -g").strip()  # source files for cost.py's parser; -g changes no code
    proc = subprocess.run([python, "setup.py", "-q", "build_ext", "--build-lib", str(lib), "--build-temp",
                           str(out / "obj"), "-j", str(os.cpu_count() or 1)], cwd=root, capture_output=True, text=True,
                          env=env)
    if proc.returncode != 0:
        raise RuntimeError(f"building the core of {root} failed:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    if not list((lib / "bldclab").glob("_bccore*")):
        raise RuntimeError(f"building the core of {root} left no _bccore library in {lib / 'bldclab'}")
    shutil.copytree(root / "src" / "bldclab", lib / "bldclab", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("_bccore*", "__pycache__"))
    subprocess.run([python, "-m", "compileall", "-q", str(lib / "bldclab")], check=True, capture_output=True)
    return lib


def build_marks(out: Path) -> Path:
    """Compile ``cg_marks.c`` (callgrind client requests) into a shared library."""
    so = out / "cg_marks.so"
    proc = subprocess.run(["cc", "-O2", "-shared", "-fPIC", str(MARKS_SOURCE), "-o", str(so)], capture_output=True,
                          text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"cannot build {MARKS_SOURCE.name} (valgrind's callgrind.h missing?):\n{proc.stderr}")
    return so


@dataclass
class Build:
    """A built tree (``build_tree``) and the marks library, ready for measurements."""

    pythonpath: Path
    marks: Path
    root: Path


def prepare(root: Path, out: Path) -> Build:
    return Build(build_tree(root, out), build_marks(out), root)


@dataclass
class Measurement:
    """One scenario measured."""

    scenario: str
    scale: float
    instructions: int
    calls_out: int
    calls_out_instructions: int
    step: float | None  # own instructions per controller step
    step_inclusive: float | None
    step_calls: int
    seconds: float  # wall time of the valgrind process
    info: dict[str, Any]
    top: list[tuple[str, int]]
    calls_detail: dict[tuple[str, str], list[int]]


def valgrind_cmd(out_file: Path, extra: Sequence[str] = ()) -> list[str]:
    return ["valgrind", "--tool=callgrind", "--instr-atstart=no", f"--callgrind-out-file={out_file}", *extra]


def child_env(pythonpath: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(pythonpath) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env["PYTHONHASHSEED"] = "0"
    return env


def measure_one(build: Build, name: str, scale: float, tmp: Path) -> Measurement:
    """Run one scenario in its own valgrind process and read its profile."""
    sc = SCENARIOS[name]
    cg = tmp / f"callgrind.{name}.{scale:g}"
    t0 = time.perf_counter()
    proc = subprocess.run([*valgrind_cmd(cg), sys.executable, str(Path(__file__).resolve()), "--run", name,
                           "--scale", repr(scale), "--marks", str(build.marks)], capture_output=True, text=True,
                          env=child_env(build.pythonpath))
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"cost run {name} failed ({proc.returncode}):\n{proc.stdout[-1500:]}{proc.stderr[-3000:]}")
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    if not Path(info["bldclab"]).resolve().is_relative_to(build.pythonpath.resolve()):
        raise RuntimeError(f"cost run {name} imported bldclab from {info['bldclab']}, not from the build "
                           f"{build.pythonpath}")
    prof = parse(cg)
    cost = prof.core_cost()
    step = prof.function_cost(sc.step) if sc.step else None
    if step is not None and step.calls == 0 and sc.step is not None:
        # link-time optimisation may inline the step into its binding's wrapper (bc_bind_*.c: bc_X_step -> X_step),
        # which the runner calls through a pointer: the wrapper's calls are the step's (plus its own call overhead)
        step = prof.function_cost(sc.step.removeprefix("bc_"))
    if step is not None and step.calls == 0:
        raise RuntimeError(f"cost run {name}: no call of {sc.step} in the profile")
    top = sorted(cost.by_function.items(), key=lambda kv: -kv[1])[:12]
    return Measurement(name, scale, cost.instructions, cost.calls_out_count, cost.calls_out_inclusive,
                       step.own_per_call if step else None, step.inclusive_per_call if step else None,
                       step.calls if step else 0, seconds, info, top, cost.calls_out)


def measure(build: Build, runs: Sequence[tuple[str, float]], jobs: int | None = None,
            tmp: Path | None = None) -> list[Measurement]:
    """Measure (scenario, duration scale) pairs, ``jobs`` valgrind processes at a time (default: one per CPU)."""
    for name, _ in runs:
        if name not in SCENARIOS:
            raise KeyError(f"no cost scenario {name!r}; scenarios: {', '.join(SCENARIOS)}")
    with tempfile.TemporaryDirectory(prefix="bldclab-cost-") as d:
        where = tmp or Path(d)
        with ThreadPoolExecutor(max_workers=jobs or os.cpu_count() or 1) as ex:
            futures = [ex.submit(measure_one, build, n, s, where) for n, s in runs]
            return [f.result() for f in futures]


# ============================================================================================================
# budgets and the check


#: gated quantities of a scenario: (key in the budget file, label, attribute of Measurement)
QUANTITIES = (("instructions", "instructions", "instructions"), ("calls_out", "calls out", "calls_out"),
              ("step", "step", "step"))


@dataclass
class Row:
    """One line of the gate's table."""

    scenario: str
    quantity: str
    measured: float
    budget: float | None
    note: str = ""

    @property
    def ratio(self) -> float:
        return self.measured / self.budget if self.budget else math.inf

    @property
    def ok(self) -> bool:
        return self.budget is not None and self.ratio <= TOLERANCE

    @property
    def stale(self) -> bool:
        return self.ok and self.ratio < STALE

    def message(self) -> str:
        b = "no budget" if self.budget is None else f"budget {self.budget:,.0f}"
        return (f"{self.scenario}: {self.quantity} {self.measured:,.0f} against {b} "
                f"(ratio {self.ratio:.3f}, limit {TOLERANCE:g})")


def toolchain(python: str = sys.executable) -> str:
    """What the instruction counts depend on besides the sources: compiler, Python's compiler flags, valgrind."""
    cflags = subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_config_var('CFLAGS'))"],
                            capture_output=True, text=True).stdout.strip()
    return f"{compiler_version()}; CFLAGS {cflags}; {valgrind_version()}"


def read_budgets(path: Path = BUDGET_FILE) -> dict[str, Any]:
    """The budget file: ``measured_with`` (the toolchain of the last update) and one table per scenario."""
    if not path.exists():
        return {}
    with path.open("rb") as fh:
        return tomllib.load(fh)


def quantities(m: Measurement) -> list[tuple[str, str, float]]:
    """(budget key, label, value) of a measurement."""
    out = []
    for key, label, attr in QUANTITIES:
        v = getattr(m, attr)
        if v is None:
            continue
        if key == "step":
            label = f"{SCENARIOS[m.scenario].step}/call"
        out.append((key, label, float(v)))
    return out


def check(measurements: Iterable[Measurement], budgets: dict[str, Any]) -> list[Row]:
    """Rows of the gate: each measured quantity against its scenario's budget (a run with a scaled duration is
    checked against the unchanged budget of its scenario)."""
    rows = []
    for m in measurements:
        b = budgets.get(m.scenario, {})
        for key, label, v in quantities(m):
            row = Row(m.scenario if m.scale == 1.0 else f"{m.scenario} x{m.scale:g}", label, v, b.get(key))
            if row.budget is None:
                row.note = "no budget: python benchmarks/cost.py --update --why ..."
            elif not row.ok:
                row.note = f"over budget by {100 * (row.ratio - 1):.1f} %"
            elif row.stale:
                row.note = f"budget stale, lower it ({100 * (1 - row.ratio):.0f} % under)"
            rows.append(row)
    return rows


def toolchain_note(budgets: dict[str, Any]) -> str:
    """Where the budgets were measured, and whether this machine's toolchain is the same."""
    was, now = budgets.get("measured_with", "?"), toolchain()
    return f"budgets measured with: {was}" + ("" if was == now else f"\nthis run's toolchain differs: {now}")


def _num(v: float) -> str:
    return f"{v:,.0f}" if abs(v) >= 100 else f"{v:,.1f}"


def table(rows: Sequence[Row], measurements: Sequence[Measurement] = ()) -> str:
    head = ("scenario", "quantity", "measured", "budget", "ratio", "ok", "note")
    cells = [head] + [(r.scenario, r.quantity, _num(r.measured), "-" if r.budget is None else _num(r.budget),
                       f"{r.ratio:.3f}" if r.budget else "-", "yes" if r.ok else "NO", r.note) for r in rows]
    w = [max(len(c[j]) for c in cells) for j in range(6)]
    lines = []
    for j, c in enumerate(cells):
        lines.append("  ".join([c[0].ljust(w[0]), c[1].ljust(w[1]), c[2].rjust(w[2]), c[3].rjust(w[3]),
                                c[4].rjust(w[4]), c[5].ljust(w[5]), c[6]]).rstrip())
        if j == 0:
            lines.append("-" * len(lines[0]))
    for m in measurements:
        if m.calls_out:
            by_count = sorted(m.calls_detail.items(), key=lambda kv: -kv[1][0])
            lib = ", ".join(f"{fn} {n}" for (_ob, fn), (n, _) in by_count)
            lines.append(f"  {m.scenario}: calls out {m.calls_out} ({m.calls_out_instructions:,} instructions, "
                         f"not gated): {lib}")
    return "\n".join(lines)


def _toml_value(v: Any) -> str:
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return f"{v:.1f}"
    return str(v)


def write_budgets(budgets: dict[str, Any], path: Path = BUDGET_FILE) -> None:
    """Write the budget file (scenarios in the order of ``SCENARIOS``, then any others)."""
    lines = [
        "# Budgets of the cost gate (benchmarks/cost.py measures, tests/test_cost_gate.py checks): per scenario the",
        "# core's own instructions, its calls into other libraries, and a controller's own instructions per step",
        f"# (a measurement above {TOLERANCE:g} x its budget fails; below {STALE:g} x the budget is reported stale).",
        "# Change a budget only in a commit that says why: python benchmarks/cost.py --update --why \"...\" rewrites",
        "# the numbers from a run and prints every old -> new. Each scenario's 'why' is the reason of its last change.",
        "# The counts belong to a toolchain (measured_with): another compiler or other flags give other numbers.",
        "",
        f"measured_with = {json.dumps(toolchain())}",
    ]
    tables = {k: v for k, v in budgets.items() if isinstance(v, dict)}
    order = [n for n in SCENARIOS if n in tables] + [n for n in tables if n not in SCENARIOS]
    for name in order:
        lines.append("")
        lines.append(f"[{name}]")
        for k, v in budgets[name].items():
            lines.append(f"{k} = {_toml_value(v)}")
    path.write_text("\n".join(lines) + "\n")


def valgrind_version() -> str:
    out = subprocess.run(["valgrind", "--version"], capture_output=True, text=True)
    return out.stdout.strip() or "valgrind ?"


def update(measurements: Sequence[Measurement], why: str | None, path: Path = BUDGET_FILE) -> list[str]:
    """Rewrite the budgets of the measured scenarios; return the changes (old -> new) as lines."""
    budgets = read_budgets(path) if path.exists() else {}
    changes = []
    for m in measurements:
        old = budgets.get(m.scenario, {})
        new: dict[str, Any] = {}
        for key, label, v in quantities(m):
            value: Any = round(v, 1) if key == "step" else int(v)
            new[key] = value
            if old.get(key) != value:
                was = old.get(key)
                rel = f" ({100 * (value / was - 1):+.1f} %)" if was else ""
                changes.append(f"{m.scenario}: {label} {'-' if was is None else _num(was)} -> {_num(value)}{rel}")
        for key in old:
            if key not in new and key != "why":
                changes.append(f"{m.scenario}: {key} {old[key]} -> removed")
        changed = any(line.startswith(f"{m.scenario}:") for line in changes)
        if changed and not why:
            raise ValueError("--update changes budgets: say why with --why \"...\" (one line, kept in the file)")
        new["why"] = why if changed else old.get("why", "")
        budgets[m.scenario] = new
    if changes:
        write_budgets(budgets, path)
    return changes


# ============================================================================================================


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", default="", help=f"comma-separated scenarios (default all: {', '.join(SCENARIOS)})")
    ap.add_argument("--jobs", type=int, default=None, help="valgrind processes at a time (default: CPUs)")
    ap.add_argument("--update", action="store_true", help="rewrite the budgets of the measured scenarios")
    ap.add_argument("--why", help="with --update: the one-line reason recorded for the changed budgets")
    ap.add_argument("--list", action="store_true", help="list the scenarios and exit")
    ap.add_argument("--top", action="store_true", help="also print each scenario's costliest core functions")
    ap.add_argument("--run", help=argparse.SUPPRESS)  # the measuring process, under valgrind
    ap.add_argument("--scale", type=float, default=1.0, help=argparse.SUPPRESS)
    ap.add_argument("--marks", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.run:
        print(json.dumps(run_child(args.run, args.scale, args.marks)))
        return 0
    if args.list:
        for s in SCENARIOS.values():
            print(f"{s.name:<18} {s.what}" + (f"; gated step: {s.step}" if s.step else ""))
        return 0
    names = [s.strip() for s in args.scenarios.split(",") if s.strip()] or list(SCENARIOS)
    unknown = [n for n in names if n not in SCENARIOS]
    if unknown:
        ap.error(f"unknown scenario(s) {', '.join(unknown)}; --list names them")
    if args.update and not args.why:
        ap.error("--update needs --why \"...\": the reason recorded beside the new budgets")
    for tool in ("valgrind", "cc"):
        if shutil.which(tool) is None:
            print(f"missing tool: {tool} (tools/install-system-deps installs it)", file=sys.stderr)
            return 2
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="bldclab-cost-") as d:
        build = prepare(ROOT, Path(d))
        ms = measure(build, [(n, 1.0) for n in names], args.jobs)
    print(f"cost gate: instructions of the C core under callgrind ({len(ms)} scenarios, {compiler_version()}, "
          f"{valgrind_version()}), {time.perf_counter() - t0:.0f} s")
    if args.update:
        changes = update(ms, args.why)
        print("\n".join(changes) if changes else "budgets unchanged")
    rows = check(ms, read_budgets())
    print(table(rows, ms))
    if args.top:
        for m in ms:
            print(f"{m.scenario}: " + ", ".join(f"{fn} {v / 1e6:.2f} M" for fn, v in m.top))
    bad = [r for r in rows if not r.ok]
    if bad:
        print(f"{len(bad)} over budget:", file=sys.stderr)
        for r in bad:
            print("  " + r.message(), file=sys.stderr)
        print(toolchain_note(read_budgets()), file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())

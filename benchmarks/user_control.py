"""Cost of a user controller (issue 25): the example six-step against the built-in, and the Python prototype.

1. ``examples/user_controller/sixstep_pi.c`` (the built-in six-step with PI regulation, rewritten as a user
   controller) against ``bl.SixStep(regulation="pi")`` on htm-48v at 0.5 p.u., switching inverter, one trace row
   per sample: wall time per simulated second, best of ``--repeats``; the user controller in this process
   (``isolate=False``: the guard's checks, a copy of the inputs and outputs per sample) and in a watched child
   process (the default: plus a fork and the result's pickle), and whether each trace is identical to the
   built-in's.
2. ``examples/user_controller/prototype.py`` (a Python ``bl.PythonControl``) against its C translation
   ``sixstep_voltage.c``: microseconds per sample, best of ``--repeats``; the Python controller's cost per sample
   is its time less the C run's, divided by the samples.

Run: ``python benchmarks/user_control.py [--repeats N] [--seconds S]`` (builds the two libraries into a temporary
directory first; needs a C compiler).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import bldclab as bl
from bldclab.control.user import build

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "examples" / "user_controller"


def _module(name: str):
    spec = importlib.util.spec_from_file_location(f"_bench_{name}", EX / f"{name}.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def _best(fn, repeats: int) -> tuple[float, bl.SimResult]:
    best, res = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = fn()
        best = min(best, time.perf_counter() - t0)
    assert res is not None
    return best, res


def main() -> None:
    """Print the two tables."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=0.5, help="simulated time of table 1 (s)")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bldclab-bench-user-"))
    pi_lib = str(build([EX / "sixstep_pi.c"], tmp / "sixstep_pi.so"))
    sv_lib = str(build([EX / "sixstep_voltage.c"], tmp / "sixstep_voltage.so"))
    drive = bl.load("htm-48v")
    builtin = bl.SixStep(regulation="pi")
    params = _module("run_sixstep_pi").user_params(drive, builtin)
    sc = bl.Scenario(duration=args.seconds, speed="0.5 pu", ref=drive.motor.I_N, trace_sub=1)
    print(f"1. six-step PI on htm-48v, 0.5 p.u., switching inverter, {args.seconds:g} s simulated, best of "
          f"{args.repeats}")
    print(f"   {'controller':<28} {'wall s':>8} {'s per sim. s':>13} {'identical':>10}")
    t_ref, ref = _best(lambda: bl.simulate(drive, builtin, sc), args.repeats)
    for name, ctl in (("built-in SixStep", builtin),
                      ("user, in process", bl.UserControl(pi_lib, params, isolate=False)),
                      ("user, isolated (default)", bl.UserControl(pi_lib, params))):
        t, res = (t_ref, ref) if ctl is builtin else _best(lambda c=ctl: bl.simulate(drive, c, sc), args.repeats)
        same = all(np.array_equal(res.signals[k], ref.signals[k]) for k in ref.signals)
        print(f"   {name:<28} {t:8.3f} {t / args.seconds:13.3f} {'yes' if same else 'NO':>10}")
    proto = _module("prototype")
    sc2 = bl.Scenario(duration=0.1, speed="0.5 pu", ref=0.4, trace_sub=1)
    t_py, py = _best(lambda: bl.simulate(drive, proto.SixStepVoltage(1.0), sc2), args.repeats)
    t_c, c = _best(lambda: bl.simulate(drive, bl.UserControl(sv_lib, {"gain": 1.0}, isolate=False), sc2),
                   args.repeats)
    n = int(py.meta["samples"])
    same = all(np.array_equal(py.signals[k], c.signals[k]) for k in c.signals)
    print(f"2. six-step voltage, Python prototype vs its C translation, {n} samples, best of {args.repeats}")
    print(f"   Python {t_py / n * 1e6:.2f} us/sample, C {t_c / n * 1e6:.2f} us/sample (plant included); the Python "
          f"controller costs {(t_py - t_c) / n * 1e6:.2f} us per sample; traces identical: {'yes' if same else 'NO'}")


if __name__ == "__main__":
    main()

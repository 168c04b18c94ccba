"""The built-in six-step (PI regulation) against its rewrite as a user controller (sixstep_pi.c): the same trace.

Builds ``sixstep_pi.c`` with ``bldclab.control.user.build`` (what ``bldclab controller build`` does) into a
temporary directory, fills its
parameters from the built-in controller's own record (the same numbers the built-in receives), runs both on the same
scenario, and prints whether every trace column is identical and the cost per simulated second of each. Run from
the repository root::

    python examples/user_controller/run_sixstep_pi.py
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

import bldclab as bl
from bldclab._core import core
from bldclab.control.user import build

#: The members of sixstep_pi.c's ss_params, filled from the built-in's bc_sixstep_params of the same names.
MEMBERS = ("chop", "delay", "advance", "emf_ff", "regen", "ref_torque", "timed", "adv_angle", "adv_time", "p", "ts",
           "R", "L", "k_e", "kp", "ki", "i_max", "v_max", "f_tick", "omega_min")


def user_params(drive: bl.Drive, builtin: bl.SixStep) -> dict[str, float]:
    """Return sixstep_pi.c's parameters: the built-in controller's values for ``drive``."""
    rec = builtin.c_record(drive, core(), 1).record
    return {k: rec[k][0].item() for k in MEMBERS}


def main() -> None:
    """Build, run both, compare."""
    here = Path(__file__).parent
    lib = build([here / "sixstep_pi.c"], Path(tempfile.mkdtemp(prefix="bldclab-example-")) / "sixstep_pi.so")
    drive = bl.load("htm-48v")
    builtin = bl.SixStep(regulation="pi", chopping="pwm-on-pwm")
    sc = bl.Scenario(duration=0.2, speed="0.5 pu", ref=drive.motor.I_N, trace_sub=1)
    runs = {}
    for name, ctl in (("built-in", builtin),
                      ("user, in process", bl.UserControl(str(lib), user_params(drive, builtin), isolate=False)),
                      ("user, isolated", bl.UserControl(str(lib), user_params(drive, builtin)))):
        t0 = time.perf_counter()
        runs[name] = bl.simulate(drive, ctl, sc)
        dt = time.perf_counter() - t0
        print(f"{name:<18} {dt:7.3f} s wall, {dt / sc.duration:6.3f} s per simulated second")
    ref = runs["built-in"]
    for name, res in runs.items():
        same = sorted(res.signals) == sorted(ref.signals) and all(
            np.array_equal(res.signals[k], ref.signals[k]) for k in ref.signals)
        print(f"{name:<18} trace identical to the built-in: {same}")


if __name__ == "__main__":
    main()

"""A six-step voltage controller prototyped in Python, and its C translation (sixstep_voltage.c): the same trace.

The law: the Hall code gives the sector, the sector the conducting pair; the positive phase's upper switch chops
with the duty ``gain * ref`` (limited to [0, 1]), the negative phase's lower switch is on, the third leg is off.
Arithmetic in float32 (``numpy.float32``), as the C controller computes, so the two traces are identical bit for bit
(tests/test_user_control.py). Run from the repository root (it builds the C translation into a temporary
directory, as ``bldclab controller build examples/user_controller/sixstep_voltage.c -o /tmp/sv.so`` would)::

    python examples/user_controller/prototype.py
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

import bldclab as bl

SECTOR = {1: 0, 3: 1, 2: 2, 6: 3, 4: 4, 5: 5}  # Hall code -> sector (bc_commutation.h)
POS = (0, 0, 1, 1, 2, 2)  # sector -> phase driven positive
NEG = (1, 2, 2, 0, 0, 1)  # ... and negative


class SixStepVoltage(bl.PythonControl):
    """Six-step voltage control: duty ``gain * ref`` on the Hall sector's pair."""

    diag = ("sector",)
    ref_meaning = "duty per unit gain"

    def __init__(self, gain: float = 1.0) -> None:
        self.gain = np.float32(gain)

    def init(self, drive: bl.Drive) -> None:
        """Nothing to derive from the drive."""

    def step(self, inputs):
        """One sample: the legs for the next half period."""
        sector = SECTOR.get(inputs.hall, -1)
        self.out.diag[0] = sector
        if sector < 0:  # 000 or 111: a broken sensor; all legs off
            self.out.flags = bl.flag("SAFE") | bl.flag("HALL_INVALID")
            return ((self.OFF, 0.0), (self.OFF, 0.0), (self.OFF, 0.0))
        d = min(max(self.gain * np.float32(inputs.ref), np.float32(0.0)), np.float32(1.0))
        legs = [(self.OFF, 0.0)] * 3
        legs[POS[sector]] = (self.HIGH, float(d))
        legs[NEG[sector]] = (self.LOW, 1.0)
        return legs


def main() -> None:
    """Run the Python prototype and the C translation on the same scenario; compare traces and timings."""
    here = Path(__file__).parent
    lib = bl.control.user.build([here / "sixstep_voltage.c"],
                                Path(tempfile.mkdtemp(prefix="bldclab-example-")) / "sixstep_voltage.so")
    drive = bl.load("htm-48v")
    sc = bl.Scenario(duration=0.05, speed="0.5 pu", ref=0.4)
    t0 = time.perf_counter()
    py = bl.simulate(drive, SixStepVoltage(1.0), sc)
    t1 = time.perf_counter()
    c = bl.simulate(drive, bl.UserControl(str(lib), {"gain": 1.0}, isolate=False), sc)
    t2 = time.perf_counter()
    same = all(np.array_equal(py.signals[k], c.signals[k]) for k in c.signals)
    n = py.meta["samples"]
    print(f"{n} samples: Python {t1 - t0:.3f} s ({(t1 - t0) / n * 1e6:.1f} us/sample), C {t2 - t1:.3f} s; "
          f"traces identical: {same}")


if __name__ == "__main__":
    main()

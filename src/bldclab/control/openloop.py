"""Open-loop drivers: replay of precomputed leg commands, and six-step voltage mode (``core/.../bc_openloop.h``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike

from .._core import Core, CParams
from .._core import core as load_core
from ..errors import BldclabError
from ..model.motor import Drive
from .base import Control

__all__ = ["OpenLoop", "SixStepVoltage"]


@dataclass(frozen=True, eq=False)
class OpenLoop(Control):
    """Replay precomputed leg commands, one triple per sample (half PWM period); all legs off afterwards.

    Parameters
    ----------
    modes : array_like of int, shape (N, 3)
        Leg modes per sample: 0 off, 1 complementary PWM, 2 upper chops, 3 lower chops.
    duties : array_like of float, shape (N, 3)
        Duties in [0, 1].
    """

    modes: ArrayLike
    duties: ArrayLike
    c_name: ClassVar[str] = "table"
    ref_meaning: ClassVar[str] = "unused"

    def __post_init__(self) -> None:
        m = np.asarray(self.modes)
        d = np.asarray(self.duties, dtype=float)
        if m.ndim != 2 or m.shape[1] != 3 or d.shape != m.shape:
            raise BldclabError("control.modes", f"modes and duties need shape (N, 3), got {m.shape} and {d.shape}")
        if not np.all(np.isin(m, list(load_core().groups["leg"].values()))):  # BC_LEG_*, from the library
            raise BldclabError("control.modes", "modes must be 0 (off), 1 (pwm), 2 (high) or 3 (low)")
        if not np.all(np.isfinite(d)) or np.any(d < 0.0) or np.any(d > 1.0):
            raise BldclabError("control.duties", "duties must be finite and within [0, 1]")
        object.__setattr__(self, "modes", m.astype(np.int32))
        object.__setattr__(self, "duties", d)

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        cmd = np.zeros((np.shape(self.modes)[0], 3), dtype=core.dtypes["bc_leg_cmd"])
        cmd["mode"] = self.modes
        cmd["duty"] = self.duties
        return CParams(core.filled("bc_table_params", cmd=cmd.ctypes.data, n=cmd.shape[0]), [cmd])

    def describe(self) -> dict[str, object]:  # noqa: D102
        return {"controller": self.c_name, "samples": int(np.shape(self.modes)[0])}


_CHOP = {"high": "BC_SIXV_HIGH", "low": "BC_SIXV_LOW", "bipolar": "BC_SIXV_BIPOLAR", "sync": "BC_SIXV_SYNC"}


@dataclass(frozen=True)
class SixStepVoltage(Control):
    """Six-step voltage mode: Hall sector to the two conducting legs, duty = reference (no current control).

    The reference (``Scenario.ref``) is the duty in [-1, 1]; its sign is the direction.

    Parameters
    ----------
    chopping : {"high", "low", "bipolar", "sync"}
        ``high``: the positive phase's upper switch chops, the negative phase's lower switch stays on; ``low``: the
        reverse; ``bipolar``: both chop together; ``sync``: the positive leg is complementary (synchronous
        rectification) and the negative leg's lower switch stays on.
    """

    chopping: Literal["high", "low", "bipolar", "sync"] = "high"
    c_name: ClassVar[str] = "sixv"
    ref_meaning: ClassVar[str] = "duty in [-1, 1]"

    def __post_init__(self) -> None:
        if self.chopping not in _CHOP:
            raise BldclabError("control.chopping", f"must be one of {', '.join(_CHOP)}, got {self.chopping!r}")

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        return CParams(core.filled("bc_sixv_params", chop=core.const(_CHOP[self.chopping])))

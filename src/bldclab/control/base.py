"""The base of every controller choice."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from ..errors import BldclabError

if TYPE_CHECKING:
    from .._core import Core
    from ..model.motor import Drive

__all__ = ["Control", "check_number"]


def check_number(name: str, v: object, *, allow_zero: bool = False, allow_none: bool = False) -> None:
    """Check a controller setting: a finite number > 0 (>= 0 with ``allow_zero``; ``None`` with ``allow_none``).

    Raises
    ------
    BldclabError
        Naming the field as ``control.<name>``.
    """
    if v is None and allow_none:
        return
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or v < 0 or (
            v == 0 and not allow_zero):
        raise BldclabError(f"control.{name}", f"must be a finite number {'>=' if allow_zero else '>'} 0, got {v!r}")


class Control(ABC):
    """Base class: the C registry name and how to fill the parameter struct."""

    c_name: ClassVar[str] = ""
    ref_meaning: ClassVar[str] = ""

    @abstractmethod
    def c_params(self, drive: Drive, core: Core, keep: list[object], n_samples: int) -> np.ndarray:
        """Return the filled C parameter record; arrays it points to are appended to ``keep``."""

    def with_delay(self, delay: int) -> Control:
        """Return the controller configured for the runner's computation delay (samples, 0 or 1).

        :func:`bldclab.simulate` calls this with ``Scenario.delay``, so a controller that predicts across the delay
        always knows the delay actually applied. Controllers without such a setting return themselves.
        """
        return self

    def describe(self) -> dict[str, object]:
        """Return the settings as plain values (for result metadata)."""
        out: dict[str, object] = {"controller": self.c_name}
        for k, v in self.__dict__.items():
            out[k] = v.tolist() if isinstance(v, np.ndarray) else v
        return out

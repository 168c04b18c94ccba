"""The base of every controller choice."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from .._core import Core, CParams
from ..errors import BldclabError
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


class Control:
    """Base class: the C registry name and how to fill the parameter struct.

    A subclass implements :meth:`c_record` (``core.filled`` of its params struct, so every C member is set).
    """

    c_name: ClassVar[str] = ""
    ref_meaning: ClassVar[str] = ""
    #: The controller reads the back-EMF sensing (bc_ctrl_in's zc_*, v_term, v_neutral): the runner turns it on.
    needs_bemf_sensing: ClassVar[bool] = False

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:
        """Return the filled C parameter record, owning the arrays it points to.

        Parameters
        ----------
        drive : Drive
            The drive the controller is configured for.
        core : Core
            The loaded C library (dtypes, constants).
        n_samples : int
            Samples the run will take (controllers that replay a table check its length).

        Returns
        -------
        CParams
            The record (``.record``) and the arrays it points to, alive as long as it is.
        """
        raise NotImplementedError(f"{type(self).__name__} does not implement c_record")

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

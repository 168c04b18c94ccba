"""The base of every controller choice."""

from __future__ import annotations

import ctypes
import math
from collections.abc import Iterable
from typing import Any, ClassVar

import numpy as np

from .._core import Core, CParams
from ..errors import BldclabError
from ..model.motor import Drive

__all__ = ["CSlot", "Control", "check_number"]


class CSlot:
    """A controller ready to run: what the runner's controller slot (``bc_ctrl``) receives, and the C loop's call.

    Built by :meth:`Control.c_slot` after the controller's init succeeded. :func:`bldclab.simulate` puts
    ``step``, ``params`` and ``state`` into the runner's configuration and calls :meth:`run` for each piece of the
    run; a guarded slot (a user's controller, :mod:`bldclab.control.user`) runs through the guard instead and
    raises :class:`~bldclab.errors.ControllerError` at the first bad sample.

    Parameters
    ----------
    step, params, state : int
        Addresses of the step function (``bc_ctrl_step_fn``), the params record and the state.
    record : CParams
        The filled params record (the plausibility guards read its ``i_max``, if it has one).
    diag : tuple of str
        Names of the eight diagnostic channels ("" unused).
    units : tuple of str, optional
        Their units ("" : the name's usual unit, else "-").
    keep : iterable of object
        Memory the addresses point into, kept alive with the slot.
    """

    def __init__(self, step: int, params: int, state: int, record: CParams, diag: tuple[str, ...],
                 units: tuple[str, ...] = ("",) * 8, keep: Iterable[object] = ()) -> None:
        self.step, self.params, self.state = step, params, state
        self.record = record
        self.diag, self.units = diag, units
        self._keep = tuple(keep)

    def run(self, core: Core, cfg: np.ndarray, state: np.ndarray, inputs: np.ndarray, n: int, rows: Any,
            cap: int, written: Any) -> int:
        """Run ``n`` samples (``bc_sim_run``): the runner's configuration, state, inputs, trace rows and count."""
        return int(core.lib.bc_sim_run(cfg.ctypes.data, state.ctypes.data, inputs.ctypes.data, n, rows, cap,
                                       ctypes.byref(written)))



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

    @property
    def isolated(self) -> bool:
        """Return whether :func:`bldclab.simulate` runs it in a watched child process (a user's code may crash)."""
        return False

    @property
    def label(self) -> str:
        """Return how messages name the controller (its class name)."""
        return type(self).__name__

    def c_slot(self, drive: Drive, core: Core, n_samples: int, watch: Any = None) -> CSlot:
        """Return the controller initialised and ready to run.

        Parameters
        ----------
        drive : Drive
            The drive the controller is configured for.
        core : Core
            The loaded C library.
        n_samples : int
            Samples the run will take.
        watch : optional
            The shared progress record of an isolated run (:class:`bldclab.control.user.Watch`); built-in
            controllers ignore it.

        Returns
        -------
        CSlot

        Raises
        ------
        BldclabError
            If the C init rejects the parameters.
        """
        info = core.controllers[self.c_name]
        cp = self.c_record(drive, core, n_samples)
        state = core.opaque(info.state)
        if core.controller_init(info, cp.record, state) != 0:
            raise BldclabError(f"control ({self.label})", "the C controller rejected its parameters")
        return CSlot(info.step_ptr, cp.address, int(state.ctypes.data), cp, info.diag, keep=(state,))

    @property
    def own_delay(self) -> int:
        """The computation delay (samples) this controller runs with where the Scenario leaves it (``delay=None``).

        Its ``delay`` setting where it has one, else 1 (a sampled controller's output applies from the next sample).
        """
        d = getattr(self, "delay", 1)
        return 1 if isinstance(d, bool) or d not in (0, 1) else int(d)

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

"""Six-edge Hall calibration as a controller (``core/ctrl/include/bldc/bc_hallcal.h``).

:class:`HallCal` runs the C routine in the simulation loop like any controller; :func:`read_calibration` takes its
result from the trace. :func:`bldclab.sim.hallcal.calibrate` does both (the simulation layer sits above this one).
Methods, assumptions and measured accuracy: ``docs/hall-calibration.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from .._core import Core, CParams
from .._core import core as load_core
from ..errors import BldclabError
from ..model.analytic import r_total
from ..model.motor import Drive
from .base import Control, check_number
from .hall import NOMINAL_EDGES
from .sine import fundamental_k1

__all__ = ["HallCal", "HallCalibration", "read_calibration"]

_METHOD = {"constant-speed": "BC_HALLCAL_SPEED", "open-loop": "BC_HALLCAL_OPENLOOP"}


@dataclass(frozen=True)
class HallCal(Control):
    """Hall edge calibration routine (no reference; the run's trace carries the table and the status).

    Parameters
    ----------
    method : {"constant-speed", "open-loop"}
        ``constant-speed``: legs off, the edge times at a constant speed (run it with an imposed speed); the
        absolute angle assumes the six edge errors have zero mean. ``open-loop``: a d-axis voltage vector turned
        slowly forward then backward (run it with the rotor free), the commanded angle at each edge averaged over
        both directions.
    revolutions : int
        Electrical revolutions averaged (per direction for ``open-loop``), 1 .. 1000.
    speed_tolerance : float
        ``constant-speed``: largest spread (max - min) / mean of the revolution times, in (0, 1).
    timeout : float
        ``constant-speed``: give up after this long (s).
    align_current : float, optional
        ``open-loop``: current the vector drives (A); default ``I_N``: a d-axis voltage ``I (R + R_on)``, and a q-axis
        voltage ``k_phi w / p`` at the vector's speed ``w`` (the back-EMF of a rotor that follows; proportional to
        the vector's speed while it ramps up).
    vector_speed : float
        ``open-loop``: speed of the vector (electrical rad/s).
    align_time : float
        ``open-loop``: hold at the start angle (s).
    lag_max : float
        ``open-loop``: largest forward-minus-backward difference of an edge accepted (rad, electrical): a rotor
        lagging more does not follow the vector.
    """

    method: Literal["constant-speed", "open-loop"] = "constant-speed"
    revolutions: int = 3
    speed_tolerance: float = 0.02
    timeout: float = 1.0
    align_current: float | None = None
    vector_speed: float = 4.0 * math.pi
    align_time: float = 0.1
    lag_max: float = math.pi / 2
    c_name: ClassVar[str] = "hallcal"
    ref_meaning: ClassVar[str] = "unused"

    def __post_init__(self) -> None:
        if self.method not in _METHOD:
            raise BldclabError("control.method", f"must be one of {', '.join(_METHOD)}, got {self.method!r}")
        r = self.revolutions
        if isinstance(r, bool) or not isinstance(r, int) or not 1 <= r <= 1000:
            raise BldclabError("control.revolutions", f"must be an integer in [1, 1000], got {r!r}")
        check_number("speed_tolerance", self.speed_tolerance)
        if self.speed_tolerance >= 1:
            raise BldclabError("control.speed_tolerance", f"must be in (0, 1), got {self.speed_tolerance!r}")
        check_number("timeout", self.timeout)
        check_number("align_current", self.align_current, allow_none=True)
        check_number("vector_speed", self.vector_speed)
        check_number("align_time", self.align_time, allow_zero=True)
        check_number("lag_max", self.lag_max)
        if self.lag_max > math.pi / 2:
            raise BldclabError("control.lag_max", f"must be in (0, pi/2] rad, got {self.lag_max!r}")

    def duration(self) -> float:
        """Return the time the ``open-loop`` routine takes (s): align, then both sweeps."""
        return self.align_time + 2.0 * ((self.revolutions + 1) * 2.0 * math.pi + math.pi / 2) / self.vector_speed

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        m, inv = drive.motor, drive.inverter
        i_align = m.I_N if self.align_current is None else float(self.align_current)
        return CParams(core.filled(
            "bc_hallcal_params",
            method=core.const(_METHOD[self.method]),
            n_rev=self.revolutions,
            f_tick=drive.sensors.f_tick,
            ts=0.5 / inv.f_pwm,
            t_max=self.timeout,
            speed_tol=self.speed_tolerance,
            v_align=i_align * r_total(drive),
            v_emf=fundamental_k1(drive) * self.vector_speed / m.p,
            omega_ol=self.vector_speed,
            t_align=self.align_time,
            lag_max=self.lag_max,
            i_max=max(2.0 * m.I_N, 3.0 * i_align),
            v_max=2.0 * inv.V_dc,
        ))


@dataclass(frozen=True)
class HallCalibration:
    """Result of a Hall calibration.

    Attributes
    ----------
    table : tuple of float
        Edge angles (rad, electrical), edge ``j`` between sectors ``j-1`` and ``j``; the nominal angles
        ``pi/6 + j pi/3`` unless ``ok``. Pass it as ``hall_table=`` to a controller.
    ok : bool
        The routine finished with a valid table.
    status : int
        The C status word (``BC_HALLCAL_*``).
    reasons : tuple of str
        The status bits set, by name (e.g. ``("BC_HALLCAL_FAIL", "BC_HALLCAL_E_INVALID")``).
    method : str
        The method used.
    """

    table: tuple[float, ...]
    ok: bool
    status: int
    reasons: tuple[str, ...]
    method: str

    def errors_deg(self) -> NDArray[np.float64]:
        """Return ``table - nominal`` per edge (electrical degrees, wrapped to (-180, 180])."""
        d = np.asarray(self.table) - np.asarray(NOMINAL_EDGES)
        return np.degrees((d + math.pi) % (2 * math.pi) - math.pi)


class _Trace(Protocol):
    def __getitem__(self, name: str) -> NDArray[np.float64]: ...


def read_calibration(trace: _Trace, method: str) -> HallCalibration:
    """Return the calibration a :class:`HallCal` run ended with, from its trace (the last row).

    Parameters
    ----------
    trace : SimResult
        The run's result (its ``edge0`` .. ``edge5`` and ``cal_status`` channels).
    method : str
        The method, for the record.
    """
    status = round(float(trace["cal_status"][-1]))
    groups = load_core().groups["hallcal_flag"]
    reasons = tuple(name for name, bit in groups.items() if status & bit)
    ok = bool(status & groups["BC_HALLCAL_DONE"])
    table = tuple(float(trace[f"edge{j}"][-1]) for j in range(6)) if ok else NOMINAL_EDGES
    return HallCalibration(table=table, ok=ok, status=status, reasons=reasons, method=method)

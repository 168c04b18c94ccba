"""Temperature derating of a controller's current limit (``core/ctrl/include/bldc/bc_derate.h``).

:class:`TemperatureDerating` fills the ``derate`` member of :class:`~bldclab.control.SixStep` and
:class:`~bldclab.control.Sine`: the controller multiplies its current limit (six-step: ``i_max``, the reference's
clamp; sine: ``I_s,N`` and its speed limit) by the derating factor of its temperature inputs (``bc_ctrl_in.temp``,
[0] the winding's sensor, [1] the switches'), which a thermal run feeds from the network's sensor nodes
(``[thermal]``'s ``sensor_winding``, ``sensor_switch``; docs/thermal.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import BldclabError
from ..model._checks import check_number

__all__ = ["ResistanceEstimate", "TemperatureDerating", "derate_record", "rest_record"]


def _band(name: str, v: object) -> tuple[float, float] | None:
    if v is None:
        return None
    if not (isinstance(v, tuple | list) and len(v) == 2):
        raise BldclabError(f"derate.{name}", f"must be (T_start, T_end) in degC, got {v!r}")
    a, b = (float(x) for x in v)
    check_number(f"derate.{name}[0]", a, lo=-273.15, lo_open=True)
    check_number(f"derate.{name}[1]", b, lo=a, lo_open=True)
    return (a, b)


@dataclass(frozen=True)
class TemperatureDerating:
    """The firmware's derating of the current limit with the winding or switch temperature.

    Parameters
    ----------
    winding, switches : (float, float), optional
        ``(T_start, T_end)`` (degC) of each channel: full current up to ``T_start``, falling linearly to ``f_min``
        of it at ``T_end``; ``None``: the channel is not fitted.
    f_min : float
        Factor at and above ``T_end``, in [0, 1).
    f_fault : float, optional
        Factor of a channel whose reading is implausible (no sensor, open or shorted NTC); default ``f_min``.
    tau : float
        Time constant of the readings' first-order filter (s), >= 0.
    T_lo, T_hi : float
        Plausible readings (degC).
    """

    winding: tuple[float, float] | None = None
    switches: tuple[float, float] | None = None
    f_min: float = 0.0
    f_fault: float | None = None
    tau: float = 0.05
    T_lo: float = -40.0
    T_hi: float = 250.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "winding", _band("winding", self.winding))
        object.__setattr__(self, "switches", _band("switches", self.switches))
        if self.winding is None and self.switches is None:
            raise BldclabError("derate", "needs a winding or a switches band (T_start, T_end)")
        check_number("derate.f_min", self.f_min, lo=0.0, hi=1.0, hi_open=True)
        check_number("derate.f_fault", self.f_fault, lo=0.0, hi=1.0, allow_none=True)
        check_number("derate.tau", self.tau, lo=0.0)
        check_number("derate.T_lo", self.T_lo)
        check_number("derate.T_hi", self.T_hi, lo=self.T_lo, lo_open=True)


def derate_record(core: Any, derate: TemperatureDerating | None, ts: float) -> np.void:
    """Return the ``bc_derate_params`` record of ``derate`` for a controller sampling every ``ts`` seconds.

    ``None``: all zero (no channel: the controller does not derate).
    """
    if derate is None:
        return core.record("bc_derate_params")[0]
    w, s = derate.winding, derate.switches
    rec = core.filled("bc_derate_params", enabled=[int(w is not None), int(s is not None)],
                      T_start=[w[0] if w else 0.0, s[0] if s else 0.0], T_end=[w[1] if w else 0.0, s[1] if s else 0.0],
                      f_min=derate.f_min, f_fault=derate.f_min if derate.f_fault is None else derate.f_fault,
                      T_lo=derate.T_lo, T_hi=derate.T_hi, tau=derate.tau, ts=ts)
    return rec[0]


@dataclass(frozen=True)
class ResistanceEstimate:
    """The winding resistance measured during operation by a square wave of d-axis current (``bc_rest.h``).

    In the sine mode the controller's ``i_d,ref`` alternates ``+current`` and ``-current`` every half ``period``;
    over the second half of each half period the means of the applied ``v_d`` and the measured ``i_d`` give
    ``R = delta v_d / delta i_d``, in which the back-EMF (so the magnets' flux and a constant angle error), the
    ``omega_e L i_q`` term and a constant voltage error cancel. Each period's value, if plausible (0.5 to 3 times the
    controller's ``R``), moves the estimate by ``filter`` of the difference. Its temperature by the resistance
    method (copper, :func:`bldclab.analysis.thermal.temperature_from_resistance`) is the derating's winding input
    when the winding has no sensor (``bc_ctrl_in.temp[0]`` NaN). The estimate is of the whole series resistance the
    voltage sees, ``R + R_on`` when the switches' drops are not compensated, referred to the controller's
    ``R + R_on`` at ``T_ref``.

    Parameters
    ----------
    current : float
        Injection amplitude (A), > 0, at most the controller's current limit. The copper loss grows by
        ``1.5 R current^2``; the torque does not change (non-salient motor).
    period : float
        Injection period (s), > 0, at least 8 control samples.
    filter : float
        Gain per valid period, in (0, 1]: the estimate's time constant is about ``period / filter``.
    """

    current: float
    period: float = 0.02
    filter: float = 0.05

    def __post_init__(self) -> None:
        check_number("r_estimate.current", self.current, lo=0.0, lo_open=True)
        check_number("r_estimate.period", self.period, lo=0.0, lo_open=True)
        check_number("r_estimate.filter", self.filter, lo=0.0, lo_open=True, hi=1.0)


def rest_record(core: Any, est: ResistanceEstimate | None, ts: float, R: float, T_ref: float,
                i_limit: float) -> np.void:
    """Return the ``bc_rest_params`` record of ``est`` for a controller sampling every ``ts`` seconds.

    ``R`` is the controller's series resistance at ``T_ref`` (Ohm, degC). ``None``: all zero (off).

    Raises
    ------
    BldclabError
        ``control.r_estimate.current`` above ``i_limit``, ``control.r_estimate.period`` shorter than 8 samples.
    """
    if est is None:
        return core.record("bc_rest_params")[0]
    if est.current > i_limit:
        raise BldclabError("control.r_estimate.current", f"must be at most the current limit {i_limit:.4g} A, got "
                           f"{est.current:.4g} A")
    n_half = round(0.5 * est.period / ts)
    if n_half < 4:
        raise BldclabError("control.r_estimate.period", f"must be at least 8 control samples ({8 * ts:.3g} s), "
                           f"got {est.period:.3g} s")
    if not R > 0.0:
        raise BldclabError("control.r_estimate", "needs a controller resistance R + R_on > 0")
    rec = core.filled("bc_rest_params", i_inj=est.current, n_half=n_half, n_skip=n_half // 2, r_lo=0.5 * R,
                      r_hi=3.0 * R, a=est.filter, r_ref=R, T_ref=T_ref)
    return rec[0]

"""Paper 1 section IV.C: efficiency of both supplies, (34)-(44).

With the paper's loss count (36) and, not in the paper, a consistent one.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import BldclabError
from ..motor import Drive
from ._common import FloatOrArray, _out, _speed, _theta
from .bases import omega_0, r_total
from .sine import (
    T_SN_PU,
    omega_sB_pu,
)
from .square import omega_qB_pu, t_q_high_pu, t_q_low_pu

__all__ = [
    "eta_34",
    "eta_q",
    "eta_ratio",
    "eta_ratio_coefficients",
    "eta_s",
    "p_R_pu",
    "p_lCu_consistent_pu",
    "p_lCu_pu",
    "p_q_m_pu",
    "p_s_m_pu",
]


def eta_34(P_m: ArrayLike, P_lm: ArrayLike, P_lB: ArrayLike, P_lCu: ArrayLike) -> FloatOrArray:
    """Efficiency ``(P_m - P_lm) / (P_m + P_lB + P_lCu)``, paper 1 (34).

    Parameters
    ----------
    P_m : array_like
        Electromagnetic power (W or per unit).
    P_lm : array_like
        Mechanical losses (same unit).
    P_lB : array_like
        Magnetic losses (same unit).
    P_lCu : array_like
        Copper losses (same unit).

    Returns
    -------
    float or ndarray
        Efficiency (-).

    """
    pm = np.asarray(P_m, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _out((pm - np.asarray(P_lm, dtype=float))
                    / (pm + np.asarray(P_lB, dtype=float) + np.asarray(P_lCu, dtype=float)))


def p_R_pu(drive: Drive) -> float:
    """Resistive parameter ``P_R,pu = R I_N / (2 k_phi Omega_N)``, paper 1 (36) (0.058 for ``htm-48v``).

    From (36), ``3 I_N^2 R / (2 k_phi I_N Omega_N) = 3 P_R,pu``. ``Omega_N`` is the motor's conventional
    nominal speed (``drive.motor.Omega_nominal``: the rating in the file, else (2)); R is :func:`r_total`.

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Dimensionless.

    """
    m = drive.motor
    return float(r_total(drive) * m.I_N / (2.0 * m.k_phi * m.Omega_nominal))


def p_lCu_pu(drive: Drive) -> float:
    """Copper losses at nominal rms current as counted by paper 1 (36): ``3 P_R,pu`` (both supplies).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Losses (per unit of ``T_N Omega_N``, the base of (36)).

    """
    return 3.0 * p_R_pu(drive)


def p_lCu_consistent_pu(drive: Drive) -> float:
    """Copper losses at nominal rms current counted physically, on the power base of ``T_pu Omega_pu``.

    Both supplies carry the same rms current ``sqrt(2/3) I_N`` in three phases: ``2 R I_N^2`` (the ideal
    square wave has two phases at ``I_N``). On the base ``T_N Omega_0`` of ``P_m,pu = T_pu Omega_pu`` (35),
    (37) this is ``2 R I_N^2 / (2 k_phi I_N Omega_0) = R I_N / (k_phi Omega_0)``. Not in the paper: see
    ``docs/theory-paper1.md`` for how it differs from (36).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Losses (per unit of ``T_N Omega_0``).

    """
    m = drive.motor
    return float(r_total(drive) * m.I_N / (m.k_phi * omega_0(drive)))


def _t_q_eff(w: NDArray[np.float64], th: float) -> NDArray[np.float64]:
    """Square-wave torque of (35)/(38): (26) below 0.5, (28) up to (30), NaN above."""
    wb = omega_qB_pu(th)
    tq = np.where(w < 0.5, np.asarray(t_q_low_pu(w, th)), np.asarray(t_q_high_pu(w, th)))
    return np.where(w <= wb, tq, np.nan)


def p_q_m_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Electromagnetic power with square-wave supply at nominal current, paper 1 (35).

    ``T_q,l,pu W`` below 0.5, ``T_q,h,pu W`` from 0.5 to the base speed (30); NaN above (outside the paper's
    range).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Power (per unit of ``T_N Omega_0``).

    """
    w = _speed(omega_pu)
    return _out(_t_q_eff(w, _theta(Theta_m)) * w)


def p_s_m_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Electromagnetic power with sinusoidal supply at nominal rms current ``T_s,N,pu W``, paper 1 (37).

    NaN above the base speed (21) (outside the paper's range).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Power (per unit of ``T_N Omega_0``).

    """
    w = _speed(omega_pu)
    return _out(np.where(w <= omega_sB_pu(_theta(Theta_m)), T_SN_PU * w, np.nan))


def eta_q(omega_pu: ArrayLike, Theta_m: float, P_lCu_pu: float) -> FloatOrArray:
    """Efficiency with square-wave supply ``T_q W / (T_q W + P_lCu)``, paper 1 (38).

    ``T_q`` is (26) below 0.5 and (28) from 0.5 to the base speed (30); NaN above it (the paper's formula
    assumes nominal current, which the drive can no longer impress).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).
    P_lCu_pu : float
        Copper losses per unit: ``3 P_R,pu`` in the paper ((36), :func:`p_lCu_pu`).

    Returns
    -------
    float or ndarray
        Efficiency (-).

    """
    w = _speed(omega_pu)
    pm = _t_q_eff(w, _theta(Theta_m)) * w
    return _out(np.asarray(eta_34(pm, 0.0, 0.0, P_lCu_pu), dtype=float))


def eta_s(omega_pu: ArrayLike, Theta_m: float, P_lCu_pu: float) -> FloatOrArray:
    """Efficiency with sinusoidal supply ``T_s,N W / (T_s,N W + P_lCu)``, paper 1 (39).

    NaN above the base speed (21).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).
    P_lCu_pu : float
        Copper losses per unit: ``3 P_R,pu`` in the paper ((36), :func:`p_lCu_pu`).

    Returns
    -------
    float or ndarray
        Efficiency (-).

    """
    pm = np.asarray(p_s_m_pu(omega_pu, Theta_m), dtype=float)
    return _out(np.asarray(eta_34(pm, 0.0, 0.0, P_lCu_pu), dtype=float))


def eta_ratio(omega_pu: ArrayLike, Theta_m: float, P_lCu_pu: float) -> FloatOrArray:
    """Efficiency ratio ``eta_s / eta_q = T_s (T_q W + P_lCu) / (T_q (T_s W + P_lCu))``, paper 1 (40).

    The printed (40) is garbled; this is the ratio of (39) to (38). Written this way it is finite at W = 0
    (the limit ``T_s / T_q``) when ``P_lCu > 0``. NaN above either base speed.

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).
    P_lCu_pu : float
        Copper losses per unit: ``3 P_R,pu`` in the paper ((36), :func:`p_lCu_pu`).

    Returns
    -------
    float or ndarray
        Ratio (-): 1.052 at W = 0.955 and 1.014 at W = 0.455 for ``htm-48v`` ((43), (44)).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    tq = _t_q_eff(w, th)
    ts = np.where(w <= omega_sB_pu(th), T_SN_PU, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _out(ts * (tq * w + P_lCu_pu) / (tq * (ts * w + P_lCu_pu)))


def eta_ratio_coefficients(omega_pu: float, Theta_m: float,
                           form: Literal["41", "42"] = "42") -> tuple[float, float, float]:
    """Return ``(a, b_s, b_q)`` with ``eta_s/eta_q = (a + b_s P_R,pu) / (a + b_q P_R,pu)``, paper 1 (41)-(42).

    The ratio of (40) with ``P_lCu = 3 P_R,pu`` is
    ``(T_s T_q W + 3 T_s P_R) / (T_s T_q W + 3 T_q P_R)``. The paper normalises (41) and (42) differently:

    - ``form="41"`` divides by ``T_s W``: ``a = T_q``, ``b_s = 3 / W``, ``b_q = 3 T_q / (T_s W)``
      (printed at W = 0.955: 0.78, 3.16, 2.34);
    - ``form="42"`` divides by ``T_q``: ``a = T_s W``, ``b_s = 3 T_s / T_q``, ``b_q = 3``
      (printed at W = 0.455: 0.48, 3.16, 3.00).

    Parameters
    ----------
    omega_pu : float
        Speed W (per unit of Omega_0), > 0, up to the lower of the base speeds (21), (30).
    Theta_m : float
        Motor-specific parameter (22) (rad).
    form : {"41", "42"}
        Normalisation, as in the paper's equation of that number.

    Returns
    -------
    tuple of float
        ``(a, b_s, b_q)``.

    """
    w = _speed(omega_pu)
    if w.ndim != 0 or float(w) <= 0.0:
        raise BldclabError("omega_pu", "must be one speed > 0")
    th = _theta(Theta_m)
    tq = float(_t_q_eff(w, th))
    if not math.isfinite(tq) or float(w) > omega_sB_pu(th):
        raise BldclabError("omega_pu", f"{float(w):g} is above a base speed: (38)-(40) do not apply")
    ts, wf = T_SN_PU, float(w)
    if form == "41":
        return tq, 3.0 / wf, 3.0 * tq / (ts * wf)
    if form == "42":
        return ts * wf, 3.0 * ts / tq, 3.0
    raise BldclabError("form", f"must be '41' or '42', got {form!r}")

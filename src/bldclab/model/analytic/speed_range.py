"""The characteristics over the whole speed range.

Each supply's torque and ripple, piecewise from paper 1's equations, and the name of the equations used at each
speed.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._common import FloatOrArray, _out, _speed, _theta
from .sine import (
    T_SN_PU,
    TR_SN_PU,
    omega_sB_pu,
    t_s_sat_pu,
    tr_s_sat_pu,
)
from .square import omega_qB_pu, t_q_high_pu, t_q_low_pu, t_q_sat_pu, tr_q_high_pu, tr_q_low_pu, tr_q_sat_pu

__all__ = [
    "REGION_Q_HIGH",
    "REGION_Q_LOW",
    "REGION_Q_SAT",
    "REGION_STOP",
    "REGION_S_BASE",
    "REGION_S_SAT",
    "region_q",
    "region_s",
    "t_q_pu",
    "t_s_pu",
    "tr_q_pu",
    "tr_s_pu",
]


#: Region labels: the equations used for (torque)/(ripple) in each speed range.
REGION_S_BASE = "(13)/(15)"
REGION_S_SAT = "(24)/(25)"
REGION_Q_LOW = "(26)/(27)"
REGION_Q_HIGH = "(28)/(29)"
REGION_Q_SAT = "(32)/(33)"
REGION_STOP = "zero (W >= 1)"


def _regions_s(w: NDArray[np.float64], th: float) -> NDArray[np.int_]:
    """Region index per speed, sinusoidal supply: 0 up to (21), 1 above, 2 at/above W = 1."""
    wb = omega_sB_pu(th)
    return np.where(w >= 1.0, 2, np.where(w <= wb, 0, 1))


def _regions_q(w: NDArray[np.float64], th: float) -> NDArray[np.int_]:
    """Region index per speed, square-wave supply: 0 below 0.5, 1 up to (30), 2 above, 3 at/above W = 1."""
    wb = omega_qB_pu(th)
    r = np.where(w > wb, 2, np.where(w < 0.5, 0, 1))
    return np.where(w >= 1.0, 3, r)


def _piecewise(w: NDArray[np.float64], idx: NDArray[np.int_],
               funcs: list[Callable[[NDArray[np.float64]], FloatOrArray]]) -> NDArray[np.float64]:
    """Return ``funcs[k](w)`` on the speeds where ``idx == k``, for every k."""
    out = np.zeros(w.shape)
    for k, f in enumerate(funcs):
        mask = idx == k
        if np.any(mask):
            out[mask] = np.asarray(f(w[mask]), dtype=float)
    return out


def t_s_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Torque-speed characteristic with sinusoidal supply at nominal current, paper 1 (13) and (24).

    (13) up to the base speed (21), (24) above it, zero at and above ``Omega_0``.

    Parameters
    ----------
    omega_pu : array_like
        Speed (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Torque (per unit of T_N).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    return _out(_piecewise(w, _regions_s(w, th), [lambda x: np.full(x.shape, T_SN_PU),
                                                  lambda x: t_s_sat_pu(x, th), lambda x: np.zeros(x.shape)]))


def tr_s_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Torque ripple with sinusoidal supply, paper 1 (15) and (25).

    Parameters
    ----------
    omega_pu : array_like
        Speed (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Peak-to-peak ripple (per unit of T_N).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    return _out(_piecewise(w, _regions_s(w, th), [lambda x: np.full(x.shape, TR_SN_PU),
                                                  lambda x: tr_s_sat_pu(x, th), lambda x: np.zeros(x.shape)]))


def t_q_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Torque-speed characteristic with real square-wave supply at nominal current, paper 1 (26), (28), (32).

    (26) below 0.5, (28) from 0.5 to the base speed (30), (32) above it, zero at and above ``Omega_0``.

    Parameters
    ----------
    omega_pu : array_like
        Speed (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Torque (per unit of T_N).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    return _out(_piecewise(w, _regions_q(w, th), [lambda x: t_q_low_pu(x, th), lambda x: t_q_high_pu(x, th),
                                                  lambda x: t_q_sat_pu(x, th), lambda x: np.zeros(x.shape)]))


def tr_q_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Torque ripple with real square-wave supply, paper 1 (27), (29), (33).

    Parameters
    ----------
    omega_pu : array_like
        Speed (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Peak-to-peak ripple (per unit of T_N).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    return _out(_piecewise(w, _regions_q(w, th), [tr_q_low_pu, tr_q_high_pu, lambda x: tr_q_sat_pu(x, th),
                                                  lambda x: np.zeros(x.shape)]))


def region_s(omega_pu: ArrayLike, Theta_m: float) -> NDArray[np.str_]:
    """Name the equations that give the sinusoidal-supply torque/ripple at each speed.

    Parameters
    ----------
    omega_pu : array_like
        Speed (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    ndarray of str
        ``"(13)/(15)"``, ``"(24)/(25)"`` or ``"zero (W >= 1)"`` per speed.

    """
    w = _speed(omega_pu)
    names = np.array([REGION_S_BASE, REGION_S_SAT, REGION_STOP])
    return names[_regions_s(w, _theta(Theta_m))]


def region_q(omega_pu: ArrayLike, Theta_m: float) -> NDArray[np.str_]:
    """Name the equations that give the square-wave torque/ripple at each speed.

    Parameters
    ----------
    omega_pu : array_like
        Speed (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    ndarray of str
        ``"(26)/(27)"``, ``"(28)/(29)"``, ``"(32)/(33)"`` or ``"zero (W >= 1)"`` per speed.

    """
    w = _speed(omega_pu)
    names = np.array([REGION_Q_LOW, REGION_Q_HIGH, REGION_Q_SAT, REGION_STOP])
    return names[_regions_q(w, _theta(Theta_m))]

"""Paper 1 section IV.A: real square-wave supply.

Torque and ripple below half the no-load speed (26)-(27) and above it (28)-(29), base speed (30)-(31), voltage
saturation (32)-(33).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ._common import FloatOrArray, _out, _speed, _theta

__all__ = [
    "omega_qB_pu",
    "t_qB_pu",
    "t_q_high_pu",
    "t_q_low_pu",
    "t_q_sat_pu",
    "tr_q_high_pu",
    "tr_q_low_pu",
    "tr_q_sat_pu",
]


def t_q_low_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Square-wave torque, low-speed commutation: ``1 + 3 Theta_m/(2 pi) (1 - 2W)/(2 - W)``, paper 1 (26).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), valid below 0.5.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Torque (per unit of T_N).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    return _out(1.0 + 3.0 * th / (2.0 * math.pi) * (1.0 - 2.0 * w) / (2.0 - w))


def tr_q_low_pu(omega_pu: ArrayLike) -> FloatOrArray:
    """Square-wave torque ripple, low-speed commutation: ``(1 - 2W)/(2 - W)``, paper 1 (27).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), valid below 0.5.

    Returns
    -------
    float or ndarray
        Peak-to-peak ripple (per unit of T_N).

    """
    w = _speed(omega_pu)
    return _out((1.0 - 2.0 * w) / (2.0 - w))


def t_q_high_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Square-wave torque, high-speed commutation: ``1 - 3 Theta_m/(2 pi) (2W - 1) W / (1 - W^2)``, (28).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), valid from 0.5 to the base speed (30).
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Torque (per unit of T_N); infinite at W = 1.

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _out(1.0 - 3.0 * th / (2.0 * math.pi) * (2.0 * w - 1.0) * w / (1.0 - w**2))


def tr_q_high_pu(omega_pu: ArrayLike) -> FloatOrArray:
    """Square-wave torque ripple, high-speed commutation: ``1 - (2 - W)/(1 + W)``, paper 1 (29).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), valid from 0.5 to the base speed (30).

    Returns
    -------
    float or ndarray
        Peak-to-peak ripple (per unit of T_N).

    """
    w = _speed(omega_pu)
    return _out(1.0 - (2.0 - w) / (1.0 + w))


def omega_qB_pu(Theta_m: float) -> float:
    """Return the base speed with real square-wave supply ``1 / (1 + 3 Theta_m / pi)``, paper 1 (30).

    The largest speed at which the injected current reaches ``I_N`` by half of its 2 pi/3 conduction interval
    (the text also calls it ``Omega_q,N``).

    Parameters
    ----------
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float
        Speed (per unit of Omega_0).

    """
    return 1.0 / (1.0 + 3.0 * _theta(Theta_m) / math.pi)


def t_qB_pu(Theta_m: float) -> float:
    """Square-wave torque at the base speed ``3/2 (1 + 3 Theta_m/pi) / (2 + 3 Theta_m/pi)``, paper 1 (31).

    Parameters
    ----------
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float
        Torque (per unit of T_N).

    """
    a = 3.0 * _theta(Theta_m) / math.pi
    return 1.5 * (1.0 + a) / (2.0 + a)


def t_q_sat_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Square-wave torque under voltage saturation ``pi/(2 Theta_m) (1 - W) / (W (1 + W))``, paper 1 (32).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), valid from the base speed (30) to 1.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Torque (per unit of T_N); infinite at W = 0.

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _out(math.pi / (2.0 * th) * (1.0 - w) / (w * (1.0 + w)))


def tr_q_sat_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Square-wave ripple under voltage saturation ``pi/(3 Theta_m) (1 - W)(2W - 1) / (W (1 + W))``, (33).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), valid from the base speed (30) to 1.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Peak-to-peak ripple (per unit of T_N); infinite at W = 0.

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _out(math.pi / (3.0 * th) * (1.0 - w) * (2.0 * w - 1.0) / (w * (1.0 + w)))

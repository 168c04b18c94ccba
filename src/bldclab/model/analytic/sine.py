"""Paper 1 section III: sinusoidal supply.

Nominal torque and ripple (10)-(15), line-to-line voltage (16)-(20), base speed (21), motor-specific parameter
(22) and voltage saturation (23)-(25).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ..motor import Drive
from ._common import SQRT3, FloatOrArray, _out, _speed, _theta
from .bases import e_N, i_sN, t_N

__all__ = [
    "TR_SN_PU",
    "T_SN_PU",
    "condition_18",
    "e_1",
    "i_s_sat",
    "omega_sB_pu",
    "p_sN",
    "t_sN",
    "t_sN_pu",
    "t_s_sat",
    "t_s_sat_pu",
    "theta_m",
    "tr_sN",
    "tr_sN_pu",
    "tr_s_sat_pu",
    "v_ab_17",
    "v_ab_peak",
]


#: Nominal torque with sinusoidal supply, per unit of T_N: ``18 / (sqrt(3) pi^2)`` ~ 1.053, paper 1 (13).
T_SN_PU = 18.0 / (SQRT3 * math.pi**2)

#: Torque ripple with sinusoidal supply at nominal current, per unit: ``2/sqrt(3) - 1`` ~ 0.155, paper 1 (15).
TR_SN_PU = 2.0 / SQRT3 - 1.0




def e_1(E: ArrayLike) -> FloatOrArray:
    """Peak of the back-EMF fundamental ``E_1 = 12/pi^2 E`` (V), paper 1 (10).

    Parameters
    ----------
    E : array_like
        Flat-top value of the ideal 120-degree trapezoid (V).

    Returns
    -------
    float or ndarray
        Fundamental peak (V).

    """
    return _out(12.0 / math.pi**2 * np.asarray(E, dtype=float))


def p_sN(drive: Drive) -> float:
    """Nominal active power with sinusoidal supply ``P_s,N = 18/pi^2 E_N I_s,N`` (W), paper 1 (11).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Power (W).

    """
    return float(18.0 / math.pi**2 * e_N(drive) * i_sN(drive))


def t_sN(drive: Drive) -> float:
    """Nominal torque with sinusoidal supply ``T_s,N = 18 k_phi I_s,N / pi^2`` (N m), paper 1 (12).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Torque (N m).

    """
    return float(18.0 * drive.motor.k_phi / math.pi**2 * i_sN(drive))


def t_sN_pu() -> float:
    """Per-unit nominal torque with sinusoidal supply ``18 / (sqrt(3) pi^2)`` ~ 1.053, paper 1 (13).

    Returns
    -------
    float
        Torque (per unit of T_N).

    """
    return T_SN_PU


def tr_sN_pu() -> float:
    """Per-unit torque ripple with sinusoidal supply ``2/sqrt(3) - 1`` ~ 0.155, paper 1 (15).

    Returns
    -------
    float
        Peak-to-peak ripple (per unit of T_N).

    """
    return TR_SN_PU


def tr_sN(drive: Drive) -> float:
    """Torque ripple with sinusoidal supply ``TR_s,N = tau(pi/6) - tau(0)`` (N m), paper 1 (14)-(15).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Peak-to-peak ripple (N m).

    """
    return TR_SN_PU * t_N(drive)


def v_ab_17(theta_e: ArrayLike, omega: float, drive: Drive) -> FloatOrArray:
    """Line-to-line voltage under nominal sinusoidal current, R neglected, paper 1 (16)-(17).

    ``v_ab = sqrt(3) p Omega L I_s,N cos(theta_e + pi/6) + k_phi Omega (1 + 6 theta_e / pi)``, valid for
    ``theta_e`` in [0, pi/6].

    Parameters
    ----------
    theta_e : array_like
        Electrical angle (rad), in [0, pi/6].
    omega : float
        Mechanical speed (rad/s).
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float or ndarray
        Voltage (V).

    """
    m = drive.motor
    th = np.asarray(theta_e, dtype=float)
    v = SQRT3 * m.p * omega * m.L * i_sN(drive) * np.cos(th + math.pi / 6) + m.k_phi * omega * (
        1.0 + 6.0 / math.pi * th)
    return _out(v)


def condition_18(drive: Drive) -> bool:
    """Return True if ``4 k_phi / (pi p L I_s,N) > 1``, paper 1 (18); equivalently (19) ``E_N > pi/4 V_L,N``.

    When it holds, ``v_ab`` rises monotonically on [0, pi/6] and peaks at ``pi/6``, so (20)-(21) are exact
    (R = 0).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    bool

    """
    m = drive.motor
    return bool(4.0 * m.k_phi / (math.pi * m.p * m.L * i_sN(drive)) > 1.0)


def v_ab_peak(omega: ArrayLike, drive: Drive) -> FloatOrArray:
    """Peak line-to-line voltage ``sqrt(3)/2 p Omega L I_s,N + 2 k_phi Omega`` (V), paper 1 (20).

    Parameters
    ----------
    omega : array_like
        Mechanical speed (rad/s).
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float or ndarray
        Voltage (V).

    """
    m = drive.motor
    w = np.asarray(omega, dtype=float)
    return _out(SQRT3 / 2.0 * m.p * w * m.L * i_sN(drive) + 2.0 * m.k_phi * w)


def theta_m(drive: Drive) -> float:
    """Motor-specific parameter ``Theta_m = p L I_N / (2 k_phi)`` (rad), paper 1 (22).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Angle (rad, electrical); a few hundredths for most motors (0.046875 for ``htm-48v``).

    """
    m = drive.motor
    return float(m.p * m.L * m.I_N / (2.0 * m.k_phi))


def omega_sB_pu(Theta_m: float) -> float:
    """Return the base speed with sinusoidal supply ``Omega_s,B,pu = 1 / (1 + Theta_m)``, paper 1 (21).

    Parameters
    ----------
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float
        Speed (per unit of Omega_0).

    """
    return 1.0 / (1.0 + _theta(Theta_m))


def i_s_sat(omega: ArrayLike, drive: Drive) -> FloatOrArray:
    """Peak sinusoidal current in voltage saturation ``2/sqrt(3) (V_N - 2 k_phi Omega)/(p Omega L)``, (23).

    Parameters
    ----------
    omega : array_like
        Mechanical speed (rad/s), > 0, between the base speed (21) and Omega_0.
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float or ndarray
        Current (A).

    """
    m = drive.motor
    w = np.asarray(omega, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _out(2.0 / SQRT3 * (drive.inverter.V_dc - 2.0 * m.k_phi * w) / (m.p * w * m.L))


def t_s_sat(omega: ArrayLike, drive: Drive) -> FloatOrArray:
    """Torque under voltage saturation with sinusoidal supply (N m), paper 1 (A.4).

    ``T_s,sat = 18 * 2 k_phi / (sqrt(3) pi^2) * (V_N - 2 k_phi Omega) / (p Omega L)``: (12) with ``I_s,N``
    replaced by (23). The printed denominator ``sqrt(3 pi^2)`` is a typo for ``sqrt(3) pi^2`` (consistent with
    (A.5), (A.6) and (24)).

    Parameters
    ----------
    omega : array_like
        Mechanical speed (rad/s), > 0.
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float or ndarray
        Torque (N m).

    """
    m = drive.motor
    w = np.asarray(omega, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _out(18.0 * 2.0 * m.k_phi / (SQRT3 * math.pi**2)
                    * (drive.inverter.V_dc - 2.0 * m.k_phi * w) / (m.p * w * m.L))


def t_s_sat_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Torque in voltage saturation, sinusoidal supply, ``18/(sqrt(3) pi^2 Theta_m) (1 - W)/W``, (24), (A.6).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), valid from (21) to 1.
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
        return _out(T_SN_PU / th * (1.0 - w) / w)


def tr_s_sat_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Torque ripple under voltage saturation, sinusoidal supply, ``(2/sqrt(3) - 1)/Theta_m (1 - W)/W``, (25).

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), valid from (21) to 1.
    Theta_m : float
        Motor-specific parameter (22) (rad).

    Returns
    -------
    float or ndarray
        Peak-to-peak ripple (per unit of T_N).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        return _out(TR_SN_PU / th * (1.0 - w) / w)

"""Paper 1's closed forms: torque, ripple, base speed and efficiency of a PM BLDC drive, for any motor.

Bertoluzzo, Buja, Keshri, Menis, *Sinusoidal vs. square-wave current supply of PM BLDC drives: a convenience
analysis* (IEEE, 2015). Every function names the equation it implements, numbered as in the paper. The theory,
the conventions and the places where the printed text is garbled are in ``docs/theory-paper1.md``.

Premises of the closed forms (paper section II.B): ideal 120-degree trapezoidal back-EMF of flat top
``E = k_phi Omega``, equal peak voltage (the DC bus ``V_N``, here ``drive.inverter.V_dc``) and equal rms
current for both supplies (``I_s,N = 2/sqrt(3) I_N``), phase resistance neglected. The R-aware base speeds
(:func:`omega_sB_numeric_pu`, :func:`omega_qB_numeric_pu`) drop the last premise and are computed numerically
from the drive's own back-EMF shapes.

Per-unit bases: speed ``Omega_0 = V_dc / (2 k_phi)`` (2), torque ``T_N = 2 k_phi I_N`` (6). The per-unit
functions take the per-unit speed ``omega_pu`` (scalar or array) and the motor-specific parameter
``theta_m`` (22) and are vectorised; a scalar input gives a ``float``, an array input an array of its shape.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import BldclabError
from .motor import TWO_PI, Drive, Trapezoid

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "CHARACTERISTIC_COLUMNS",
    "REGION_Q_HIGH",
    "REGION_Q_LOW",
    "REGION_Q_SAT",
    "REGION_STOP",
    "REGION_S_BASE",
    "REGION_S_SAT",
    "R_DROP_MAX",
    "SHAPE_DEVIATION_MAX",
    "SINUSOIDAL_THD_MAX",
    "SQRT3",
    "TABLE1_ROWS",
    "TR_SN_PU",
    "T_BLAC_N_PU",
    "T_SN_PU",
    "VDC_MISMATCH_MAX",
    "Table1",
    "applicability",
    "characteristic",
    "condition_18",
    "e_1",
    "e_N",
    "eta_34",
    "eta_q",
    "eta_ratio",
    "eta_ratio_coefficients",
    "eta_s",
    "harmonic_ratio",
    "i_sN",
    "i_s_sat",
    "omega_0",
    "omega_N",
    "omega_blac_B_pu",
    "omega_qB_numeric_pu",
    "omega_qB_pu",
    "omega_sB_numeric_pu",
    "omega_sB_pu",
    "p_R_pu",
    "p_lCu_consistent_pu",
    "p_lCu_pu",
    "p_q_m_pu",
    "p_sN",
    "p_s_m_pu",
    "r_total",
    "region_q",
    "region_s",
    "shape_deviation",
    "sine_torque_pu",
    "t_N",
    "t_blac_pu",
    "t_qB_pu",
    "t_q_high_pu",
    "t_q_low_pu",
    "t_q_pu",
    "t_q_sat_pu",
    "t_sN",
    "t_sN_pu",
    "t_s_pu",
    "t_s_sat",
    "t_s_sat_pu",
    "table1",
    "theta_m",
    "tr_q_high_pu",
    "tr_q_low_pu",
    "tr_q_pu",
    "tr_q_sat_pu",
    "tr_sN",
    "tr_sN_pu",
    "tr_s_pu",
    "tr_s_sat_pu",
    "v_ab_17",
    "v_ab_peak",
]

FloatOrArray = float | NDArray[np.float64]

SQRT3 = math.sqrt(3.0)

#: Nominal torque with sinusoidal supply, per unit of T_N: ``18 / (sqrt(3) pi^2)`` ~ 1.053, paper 1 (13).
T_SN_PU = 18.0 / (SQRT3 * math.pi**2)

#: Torque ripple with sinusoidal supply at nominal current, per unit: ``2/sqrt(3) - 1`` ~ 0.155, paper 1 (15).
TR_SN_PU = 2.0 / SQRT3 - 1.0

#: Nominal torque of the equivalent PM BLAC motor, per unit of T_N: ``sqrt(3)/2`` ~ 0.866, paper 1 IV.B.
T_BLAC_N_PU = SQRT3 / 2.0


# ------------------------------------------------------------------------------------------------------------
# helpers


def _speed(omega_pu: ArrayLike, name: str = "omega_pu") -> NDArray[np.float64]:
    """Return ``omega_pu`` as a float array, rejecting NaN, infinite or negative speeds."""
    w = np.asarray(omega_pu, dtype=float)
    if not np.all(np.isfinite(w)):
        raise BldclabError(name, "must be finite (no NaN or infinity)")
    if np.any(w < 0.0):
        raise BldclabError(name, f"must be >= 0 (motoring), got {float(np.min(w)):g}")
    return w


def _out(x: NDArray[np.float64]) -> FloatOrArray:
    """Return a 0-d array as ``float``, any other array unchanged."""
    return float(x) if np.ndim(x) == 0 else x


def _theta(Theta_m: float) -> float:
    """Check the motor-specific parameter (22): finite and > 0."""
    if isinstance(Theta_m, bool) or not isinstance(Theta_m, int | float | np.floating):
        raise BldclabError("theta_m", f"expected a number, got {type(Theta_m).__name__}")
    if not math.isfinite(Theta_m) or Theta_m <= 0.0:
        raise BldclabError("theta_m", f"must be finite and > 0 rad, got {Theta_m!r}")
    return float(Theta_m)


def r_total(drive: Drive) -> float:
    """Resistance in series with a conducting phase: ``R + R_on`` (Ohm).

    Paper 1's R is "inclusive of the transistor on-resistance" (Table II); a motor file that states the switch
    resistance separately (``inverter.R_on``) gets it added here. Diode drops and dead time are neglected.

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Resistance (Ohm).

    """
    return float(drive.motor.R + drive.inverter.R_on)


# ------------------------------------------------------------------------------------------------------------
# section II: bases and ratings


def omega_0(drive: Drive) -> float:
    """No-load speed ``Omega_0 = V_N / (2 k_phi)`` (rad/s), paper 1 (2): the speed base.

    Parameters
    ----------
    drive : Drive
        ``drive.inverter.V_dc`` plays the paper's ``V_N`` (the DC bus is set at the nominal motor voltage).

    Returns
    -------
    float
        Speed (rad/s, mechanical).

    """
    return float(drive.inverter.V_dc / (2.0 * drive.motor.k_phi))


def omega_N(drive: Drive) -> float:
    """Conventional nominal speed ``Omega_N = (V_N - 2 R I_N) / (2 k_phi)`` (rad/s), paper 1 (2).

    Computed from the formula (with ``V_N = V_dc`` and the resistance of :func:`r_total`); the rating stored
    in the motor file, ``drive.motor.Omega_nominal``, may differ slightly (Table II gives 640 rpm, (2) gives
    641.6).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Speed (rad/s, mechanical).

    """
    m = drive.motor
    return float((drive.inverter.V_dc - 2.0 * r_total(drive) * m.I_N) / (2.0 * m.k_phi))


def e_N(drive: Drive) -> float:
    """Nominal flat-top back-EMF ``E_N = k_phi Omega_N`` (V), paper 1 (3), with ``Omega_N`` from (2).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Voltage (V).

    """
    return float(drive.motor.k_phi * omega_N(drive))


def t_N(drive: Drive) -> float:
    """Nominal torque ``T_N = 2 k_phi I_N`` (N m), paper 1 (6): the torque base.

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Torque (N m).

    """
    return float(2.0 * drive.motor.k_phi * drive.motor.I_N)


def i_sN(drive: Drive) -> float:
    """Peak sinusoidal current of equal rms value ``I_s,N = 2/sqrt(3) I_N`` (A), paper 1 (7)-(8).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    float
        Current (A).

    """
    return float(2.0 / SQRT3 * drive.motor.I_N)


# ------------------------------------------------------------------------------------------------------------
# section III: sinusoidal supply


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


# ------------------------------------------------------------------------------------------------------------
# section IV.A: real square-wave supply


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


# ------------------------------------------------------------------------------------------------------------
# the characteristics over the whole speed range

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


# ------------------------------------------------------------------------------------------------------------
# section IV.B: the equivalent PM BLAC motor


def omega_blac_B_pu(Theta_m: float) -> float:
    """Return the base speed of the equivalent PM BLAC motor (per unit of Omega_0), paper 1 section IV.B.

    The equivalent BLAC motor has a sinusoidal back-EMF of peak ``k_phi Omega`` (the BLDC flat top) and
    carries ``I_s,N`` in phase with it. Its peak line-to-line voltage is
    ``sqrt(3) Omega sqrt(k_phi^2 + (p L I_s,N)^2)``; equating it to ``V_N`` gives
    ``W_B = 2 / (sqrt(3) sqrt(1 + 16 Theta_m^2 / 3))``, above 1: it outruns the BLDC motor, whose line-to-line
    back-EMF is ``2 k_phi Omega`` instead of ``sqrt(3) k_phi Omega``.

    Parameters
    ----------
    Theta_m : float
        Motor-specific parameter (22) of the BLDC motor (rad).

    Returns
    -------
    float
        Speed (per unit of Omega_0).

    """
    th = _theta(Theta_m)
    return 2.0 / (SQRT3 * math.sqrt(1.0 + 16.0 * th**2 / 3.0))


def t_blac_pu(omega_pu: ArrayLike, Theta_m: float) -> FloatOrArray:
    """Torque of the equivalent PM BLAC motor at nominal rms current, paper 1 section IV.B.

    ``sqrt(3)/2`` (0.866 of the BLDC nominal torque, [5] in the paper) up to :func:`omega_blac_B_pu`; above it
    the current in phase with the back-EMF is reduced to keep the peak line-to-line voltage at ``V_N`` (no
    flux weakening): ``T_pu = 3/4 sqrt(4 / (3 W^2) - 1) / (2 Theta_m)``, zero from ``W = 2/sqrt(3)``.

    Parameters
    ----------
    omega_pu : array_like
        Speed W (per unit of Omega_0), >= 0.
    Theta_m : float
        Motor-specific parameter (22) of the BLDC motor (rad).

    Returns
    -------
    float or ndarray
        Torque (per unit of T_N).

    """
    w = _speed(omega_pu)
    th = _theta(Theta_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        i_pu = np.sqrt(np.clip(4.0 / (3.0 * w**2) - 1.0, 0.0, None)) / (2.0 * th)  # current / I_N
    i_pu = np.where(w == 0.0, 2.0 / SQRT3, np.minimum(i_pu, 2.0 / SQRT3))
    return _out(0.75 * i_pu)


# ------------------------------------------------------------------------------------------------------------
# section IV.C: efficiency


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


# ------------------------------------------------------------------------------------------------------------
# R-aware base speeds (numeric; paper 1 section IV.B, "a numerical computation has been executed ...")


def _bisect(f: Callable[[float], float], lo: float, hi: float, xtol: float) -> float:
    """Return the last point with ``f >= 0`` in [lo, hi] by bisection, given ``f(lo) >= 0 > f(hi)``."""
    for _ in range(200):
        if hi - lo <= xtol:
            break
        mid = 0.5 * (lo + hi)
        if f(mid) >= 0.0:
            lo = mid
        else:
            hi = mid
    return lo


def _golden_argmax(f: Callable[[float], float], lo: float, hi: float, iters: int = 80) -> float:
    """Return the argument of the maximum of a unimodal ``f`` on [lo, hi] (golden-section search)."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    c1, c2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = f(c1), f(c2)
    for _ in range(iters):
        if f1 >= f2:
            hi, c2, f2 = c2, c1, f1
            c1 = hi - g * (hi - lo)
            f1 = f(c1)
        else:
            lo, c1, f1 = c1, c2, f2
            c2 = lo + g * (hi - lo)
            f2 = f(c2)
    return c1 if f1 >= f2 else c2


def _resistance(drive: Drive, R: float | None) -> float:
    """Return the resistance to use: ``R`` if given (checked), else :func:`r_total`."""
    if R is None:
        return r_total(drive)
    if isinstance(R, bool) or not isinstance(R, int | float | np.floating) or not math.isfinite(R) or R < 0.0:
        raise BldclabError("R", f"must be a finite resistance >= 0 Ohm, got {R!r}")
    return float(R)


_PAIRS = ((0, 1), (1, 2), (2, 0))


def _fundamental_phase(drive: Drive) -> float:
    """Return ``phi`` of phase a's back-EMF fundamental ``K sin(theta + phi)`` (rad; 0 for a trapezoid)."""
    a1, b1 = (float(c[1]) for c in drive.motor.emf.shapes[0].fourier(1))
    return math.atan2(a1, b1)


def _line_voltage_parts(drive: Drive, r: float, phi: float, theta: NDArray[np.float64]
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Split the line-to-line voltages at nominal sinusoidal current as ``v = A + Omega B``.

    ``A = R (i_x - i_y)`` (V) and ``B = p L d(i_x - i_y)/dtheta + k_x - k_y`` (V s/rad) for the pairs ab, bc,
    ca; balanced currents ``I_s,N sin(theta + phi - x 2 pi/3)`` in phase with the back-EMF fundamental.
    Shape (3, n).
    """
    m = drive.motor
    i_s = i_sN(drive)
    ph = theta + phi
    k = m.emf.k_abc(theta)
    A, B = [], []
    for x, y in _PAIRS:
        di = i_s * (np.sin(ph - x * TWO_PI / 3.0) - np.sin(ph - y * TWO_PI / 3.0))
        ddi = i_s * (np.cos(ph - x * TWO_PI / 3.0) - np.cos(ph - y * TWO_PI / 3.0))
        A.append(r * di)
        B.append(m.p * m.L * ddi + (k[x] - k[y]))
    return np.array(A), np.array(B)


def omega_sB_numeric_pu(drive: Drive, R: float | None = None, n_grid: int = 2048) -> float:
    """Return the R-aware base speed with sinusoidal supply, computed numerically (per unit of Omega_0).

    The largest speed at which the inverter (linear modulation: peak line-to-line voltage ``<= V_dc``) can
    impress balanced sinusoidal currents of peak ``I_s,N`` (8) in phase with the fundamental of phase a's
    back-EMF:

    ``v_xy(theta) = R (i_x - i_y) + p Omega L d(i_x - i_y)/dtheta + Omega (k_x(theta) - k_y(theta))``

    (paper 1 (16) with R). Its peak over a period and the three line pairs is taken on an angle grid that
    holds every corner of the back-EMF shapes; the speed where it equals ``V_dc`` is found by bisection (the
    peak is convex in the speed, so the root is unique). Smooth maxima between grid points are then located by
    golden-section search, added to the grid, and the bisection repeated. With ``R = 0`` and an ideal
    trapezoid the result equals (21) whenever (18) holds; otherwise (21) is only an approximation and this is
    exact. It is not capped at 1: a back-EMF whose line-to-line peak is reached at isolated angles (rounded or
    sinusoidal shapes) can keep the required voltage below ``V_dc`` slightly above ``Omega_0``.

    Parameters
    ----------
    drive : Drive
        Uses the drive's own back-EMF shapes, ``p``, ``L``, ``I_N`` and ``V_dc``.
    R : float, optional
        Series resistance (Ohm); default :func:`r_total`.
    n_grid : int
        Angle grid points per electrical period (before adding the shape corners).

    Returns
    -------
    float
        Speed (per unit of Omega_0).

    Raises
    ------
    BldclabError
        If the resistive drop alone reaches the DC bus.

    """
    m = drive.motor
    r = _resistance(drive, R)
    V = drive.inverter.V_dc
    w0 = omega_0(drive)
    pts = [np.linspace(0.0, TWO_PI, n_grid, endpoint=False)]
    for x, s in enumerate(m.emf.shapes):
        pts.append(np.mod(s.breakpoints() + x * TWO_PI / 3.0, TWO_PI))
    grid = np.unique(np.concatenate(pts))
    phi = _fundamental_phase(drive)
    A, B = _line_voltage_parts(drive, r, phi, grid)
    if float(np.max(np.abs(A))) >= V:
        raise BldclabError("motor.R", f"the resistive drop {float(np.max(np.abs(A))):g} V alone reaches the "
                           f"DC bus {V:g} V")

    def margin(omega: float) -> float:
        return V - float(np.max(np.abs(A + omega * B)))

    hi = w0
    while margin(hi) >= 0.0:
        hi *= 2.0
    omega = _bisect(margin, 0.0, hi, 1e-14 * w0)
    for _ in range(2):
        # locate the smooth maxima near the grid maxima at this speed and add them to the grid
        extra = []
        v = np.abs(A + omega * B)
        for row in range(3):
            j = int(np.argmax(v[row]))
            lo = grid[j - 1] if j > 0 else grid[-1] - TWO_PI
            hi_t = grid[j + 1] if j + 1 < grid.size else grid[0] + TWO_PI

            def fv(t: float, row: int = row, om: float = omega) -> float:
                a, b = _line_voltage_parts(drive, r, phi, np.array([t]))
                return float(abs(a[row, 0] + om * b[row, 0]))

            extra.append(np.mod(_golden_argmax(fv, float(lo), float(hi_t)), TWO_PI))
        grid = np.unique(np.concatenate([grid, extra]))
        A, B = _line_voltage_parts(drive, r, phi, grid)
        omega = _bisect(margin, 0.0, omega * (1.0 + 1e-9), 1e-14 * w0)
    return omega / w0


#: 120-degree conduction per sector s = 0..5 (conventions.md): (phase tied to +, phase tied to -).
_CONDUCTION = ((0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1))


def _phi(z: float) -> tuple[float, float, float]:
    """Return ``phi_n(z) = integral of exp(-z (1 - u)) u^(n-1) du`` on [0, 1] for n = 1, 2, 3.

    They weigh a forcing ``f0 + f1 u + f2 u^2`` (``u = s/h``) in the exact step of ``L di/dt = f - R i``:
    ``i(h) = i(0) exp(-z) + h/L (f0 phi_1 + f1 phi_2 + f2 phi_3)`` with ``z = R h / L``. Series near z = 0.
    """
    if z < 1e-2:
        z2, z3 = z * z, z * z * z
        return (1.0 - z / 2.0 + z2 / 6.0 - z3 / 24.0, 0.5 - z / 6.0 + z2 / 24.0 - z3 / 120.0,
                1.0 / 3.0 - z / 12.0 + z2 / 60.0 - z3 / 360.0)
    em = math.expm1(-z)  # exp(-z) - 1
    return -em / z, (z + em) / (z * z), (z * z - 2.0 * z - 2.0 * em) / (z * z * z)


def _commutation_margin(drive: Drive, r: float, omega: float, sector: int, n_grid: int) -> float:
    """Return ``max_t (x + w) - 2 I_N`` over the sector after the commutation into ``sector`` at ``omega``.

    Normalised currents (sign ``s = +1`` if the continuing phase y is tied to +, else -1):
    ``x = s (i_y - i_z)`` (continuing minus incoming, from I_N to 2 I_N) and ``w = s i_w`` (outgoing, from
    -I_N up to 0, then 0: its diode blocks). The incoming current reaches I_N when ``x + w = 2 I_N``. With y
    and z tied to opposite rails and w freewheeling to y's rail (``v_n`` from the three phases):

        L dx/dt = V_dc - s (e_y - e_z) - R x
        L dw/dt = V_dc/3 - s (2 e_w - e_y - e_z)/3 - R w

    Both are linear. Each step integrates them exactly for a forcing quadratic in time through the values at
    the step's ends and middle: exact for piecewise-linear shapes on a grid that holds their corners, fourth
    order for smooth shapes.
    """
    m = drive.motor
    V, i_n, L, p = drive.inverter.V_dc, m.I_N, m.L, m.p
    prev, new = _CONDUCTION[(sector - 1) % 6], _CONDUCTION[sector]
    if new[0] == prev[0]:
        y, z, w_ph, s = new[0], new[1], prev[1], 1.0
    else:
        y, z, w_ph, s = new[1], new[0], prev[0], -1.0
    th0 = math.pi / 6.0 + sector * math.pi / 3.0
    pts = [np.linspace(0.0, math.pi / 3.0, n_grid + 1)]
    for ph, sh in enumerate(m.emf.shapes):
        bp = np.mod(sh.breakpoints() + ph * TWO_PI / 3.0 - th0, TWO_PI)
        pts.append(bp[bp < math.pi / 3.0])
    nodes = np.unique(np.concatenate(pts))
    # nodes and step midpoints interleaved: f[2j] at node j, f[2j + 1] in the middle of step j
    dth = np.empty(2 * nodes.size - 1)
    dth[0::2] = nodes
    dth[1::2] = 0.5 * (nodes[:-1] + nodes[1:])
    k = m.emf.k_abc(th0 + dth)
    fx = V - s * omega * (k[y] - k[z])
    fw = V / 3.0 - s * omega * (2.0 * k[w_ph] - k[y] - k[z]) / 3.0
    h = np.diff(nodes) / (p * omega)
    lam = r / L
    x, w, best = i_n, -i_n, -2.0 * i_n
    extinct = False
    for j in range(h.size):
        zj = lam * h[j]
        decay = math.exp(-zj)
        p1, p2, p3 = _phi(zj)
        hl = h[j] / L
        # forcing f0 + (4 fm - 3 f0 - f1) u + (2 f0 - 4 fm + 2 f1) u^2 through the step's ends and middle
        f0, fm, f1 = fx[2 * j], fx[2 * j + 1], fx[2 * j + 2]
        x = x * decay + hl * (f0 * p1 + (4.0 * fm - 3.0 * f0 - f1) * p2 + 2.0 * (f0 - 2.0 * fm + f1) * p3)
        if not extinct:
            f0, fm, f1 = fw[2 * j], fw[2 * j + 1], fw[2 * j + 2]
            w = w * decay + hl * (f0 * p1 + (4.0 * fm - 3.0 * f0 - f1) * p2 + 2.0 * (f0 - 2.0 * fm + f1) * p3)
            if w >= 0.0:
                w, extinct = 0.0, True
        best = max(best, x + w)
    return best - 2.0 * i_n


def omega_qB_numeric_pu(drive: Drive, R: float | None = None, n_grid: int = 64) -> float:
    """R-aware base speed with real square-wave supply, computed numerically (per unit of Omega_0).

    Paper 1's definition (30): the largest speed at which the injected current reaches ``I_N`` by half of its
    2 pi/3 conduction interval, i.e. within the pi/3 sector that follows its commutation. During the
    commutation the incoming and the continuing phase are tied to opposite rails (full voltage: the current
    controller cannot do better) and the outgoing phase freewheels in its diode; R sits in every phase and the
    back-EMFs follow the drive's shapes (the outgoing phase is on its ramp). See :func:`_commutation_margin`
    for the circuit. The six commutations of a period are checked (one for a symmetric motor); the base speed
    is where the worst one just makes it, found by a scan and bisection. With ``R = 0`` and an ideal trapezoid
    it equals (30) exactly: ``L d(i_y - i_z)/dt = V - 2 k_phi Omega`` does not involve the outgoing phase
    (as long as the outgoing current dies within the sector, which (30) assumes).

    The result is capped at 1: at ``Omega_0`` the line-to-line back-EMF reaches the DC bus, and above it the
    120-degree conduction model (the open phase floating inside the bus) no longer holds. Only a back-EMF
    whose line-to-line peak is reached at isolated angles (rounded or sinusoidal shapes) with a small ``L``
    gets there.

    Parameters
    ----------
    drive : Drive
        Uses the drive's own back-EMF shapes, ``p``, ``L``, ``I_N`` and ``V_dc``.
    R : float, optional
        Series resistance (Ohm); default :func:`r_total`.
    n_grid : int
        Time steps per sector (before adding the shape corners).

    Returns
    -------
    float
        Speed (per unit of Omega_0), in (0, 1].

    Raises
    ------
    BldclabError
        If the current cannot reach ``I_N`` within a sector even at the lowest scanned speed.

    """
    r = _resistance(drive, R)
    sectors = range(1) if drive.motor.emf.is_symmetric else range(6)
    w0 = omega_0(drive)

    def margin(omega: float) -> float:
        return min(_commutation_margin(drive, r, omega, s, n_grid) for s in sectors)

    n_scan = 64
    speeds = w0 * np.arange(1, n_scan + 1) / n_scan
    ok = [margin(float(w)) >= 0.0 for w in speeds]
    if not ok[0]:
        raise BldclabError("motor", "the injected current cannot reach I_N within a sector even at "
                           f"{speeds[0] / w0:g} Omega_0 (resistance or inductance too large for V_dc)")
    last = max(j for j, good in enumerate(ok) if good)
    if last == n_scan - 1:  # still reached at Omega_0: capped (see the docstring)
        return 1.0
    omega = _bisect(margin, float(speeds[last]), float(speeds[last + 1]), 1e-14 * w0)
    return omega / w0


# ------------------------------------------------------------------------------------------------------------
# applicability: where the closed forms' premises hold


#: Largest deviation of the normalised back-EMF shape ``k_x / k_phi`` from the ideal 120-degree trapezoid (of flat
#: top 1) accepted as "the ideal trapezoid": 2 % of the flat top, the size of a flat top tilted by 2 % or corners
#: rounded over about 1.2 electrical degrees. A sinusoid deviates by ``1 - 1/sqrt(3) = 0.42``.
SHAPE_DEVIATION_MAX = 0.02

#: Largest resistive voltage fraction ``2 R I_N / V_dc`` (= ``1 - Omega_N / Omega_0`` by (2)) accepted as "R
#: neglected": 0.15. Paper 1 itself neglects R on its drive (Table II) at 0.104, where R already lowers the base
#: speeds by 8 to 9 % (the numeric R-aware base speeds); above 0.15 it lowers them by more than about 13 %.
R_DROP_MAX = 0.15

#: Largest relative difference between the DC bus ``V_dc`` and the motor's nominal voltage ``V_N`` accepted as
#: paper 1's "DC bus at the nominal voltage": 1 %.
VDC_MISMATCH_MAX = 0.01

#: A back-EMF whose harmonics (rms over orders 2 to 49) are below this fraction of its fundamental is called
#: sinusoidal in :func:`applicability`'s reasons.
SINUSOIDAL_THD_MAX = 0.01


def shape_deviation(drive: Drive, n_grid: int = 7200) -> float:
    """Largest deviation of the back-EMF shapes from paper 1's ideal 120-degree trapezoid, per unit of ``k_phi``.

    ``max over theta and phases x of |k_x(theta) / k_phi - trap(theta)|``, with ``trap`` the ideal trapezoid of flat
    top 1 and 120-degree flat tops in bldclab's angle convention (zero crossing rising at 0): 0 for the ideal
    trapezoid, ``1 - 1/sqrt(3)`` = 0.423 for a sinusoid (at the trapezoid's corners, 30 degrees).

    Parameters
    ----------
    drive : Drive
        The drive: its back-EMF shapes.
    n_grid : int
        Grid points per electrical period (the shapes' own corners are added).

    Returns
    -------
    float
        Deviation (per unit of ``k_phi``), >= 0.

    """
    ideal = Trapezoid(1.0)
    pts = [np.linspace(0.0, TWO_PI, n_grid, endpoint=False), ideal.breakpoints()]
    pts += [s.breakpoints() for s in drive.motor.emf.shapes]
    th = np.unique(np.concatenate(pts))
    ref = ideal(th)
    k_phi = drive.motor.k_phi
    return float(max(np.max(np.abs(s(th) / k_phi - ref)) for s in drive.motor.emf.shapes))


def harmonic_ratio(drive: Drive, n_max: int = 49) -> float:
    """Harmonic content of the back-EMF: rms of orders 0 and 2..n_max over the fundamental, worst phase (-).

    Parameters
    ----------
    drive : Drive
        The drive: its back-EMF shapes.
    n_max : int
        Highest harmonic order counted.

    Returns
    -------
    float
        0 for a sinusoid, 0.229 for the ideal 120-degree trapezoid (orders up to 49).

    """
    worst = 0.0
    for s in drive.motor.emf.shapes:
        a, b = s.fourier(n_max)
        amp2 = a**2 + b**2
        h = math.sqrt(float(a[0] ** 2 + 0.5 * np.sum(amp2[2:])))
        worst = max(worst, h / math.sqrt(0.5 * float(amp2[1])))
    return worst


def sine_torque_pu(drive: Drive) -> float:
    """Mean torque of the sinusoidal supply at ``I_s,N``, R neglected, per unit of ``T_N``: any back-EMF.

    Sinusoidal phase currents of peak ``I_s,N = 2/sqrt(3) I_N`` in phase with each phase's back-EMF fundamental (of
    peak ``k_1,x``) give the mean torque ``sum_x k_1,x I_s,N / 2`` (the harmonics give no mean torque with a
    sinusoidal current), i.e. ``sum_x k_1,x / (2 sqrt(3) k_phi)`` per unit: (13)'s ``18/(sqrt(3) pi^2)`` = 1.053 for
    the ideal trapezoid, exactly 1 for a sinusoid.

    Parameters
    ----------
    drive : Drive
        The drive: its back-EMF shapes.

    Returns
    -------
    float
        Torque (per unit of T_N).

    """
    k1 = 0.0
    for s in drive.motor.emf.shapes:
        a, b = s.fourier(1)
        k1 += math.hypot(float(a[1]), float(b[1]))
    return k1 / (2.0 * SQRT3 * drive.motor.k_phi)


def applicability(drive: Drive) -> list[str]:
    """Reasons why paper 1's closed forms do not describe this drive; empty where their premises hold.

    The closed forms ((13), (15), (21), (24)-(33), (36)-(44)) assume the ideal 120-degree trapezoidal back-EMF, the
    DC bus at the nominal voltage ``V_N`` and the resistance neglected (paper 1 section II.B). One reason per premise
    the drive leaves, each naming the measure and its threshold:

    - the back-EMF shape deviates from the ideal trapezoid by more than :data:`SHAPE_DEVIATION_MAX` of ``k_phi``
      (:func:`shape_deviation`); the reason gives the sinusoidal supply's torque of this shape
      (:func:`sine_torque_pu`) against (13)'s and says when the shape is sinusoidal (:func:`harmonic_ratio` below
      :data:`SINUSOIDAL_THD_MAX`);
    - the resistive voltage fraction ``2 (R + R_on) I_N / V_dc`` exceeds :data:`R_DROP_MAX` (the numeric R-aware base
      speeds of :func:`table1` then apply rather than (21) and (30));
    - ``V_dc`` differs from ``V_N`` by more than :data:`VDC_MISMATCH_MAX` (the closed forms are then evaluated with
      ``V_dc`` in the role of ``V_N``: speeds in per unit of ``V_dc / (2 k_phi)``, not of the rating).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    list of str
        One sentence per premise left, in the order above.

    """
    out: list[str] = []
    dev = shape_deviation(drive)
    if dev > SHAPE_DEVIATION_MAX:
        thd = harmonic_ratio(drive)
        kind = (f"sinusoidal back-EMF (harmonics {100.0 * thd:.2g} % of the fundamental)" if thd < SINUSOIDAL_THD_MAX
                else "back-EMF not the ideal 120-degree trapezoid")
        out.append(f"{kind}: it deviates from the ideal trapezoid by up to {dev:.3f} k_phi (limit "
                   f"{SHAPE_DEVIATION_MAX:g}); the sinusoidal supply gives {sine_torque_pu(drive):.3f} p.u. at I_s,N, "
                   f"not (13)'s {T_SN_PU:.3f}, and (15), (24)-(33) assume the trapezoid too")
    r_drop = 2.0 * r_total(drive) * drive.motor.I_N / drive.inverter.V_dc
    if r_drop > R_DROP_MAX:
        out.append(f"resistance not negligible: 2 R I_N / V_dc = {r_drop:.3f} (limit {R_DROP_MAX:g}); use the "
                   "R-aware numeric base speeds, not (21) and (30)")
    mismatch = drive.inverter.V_dc / drive.motor.V_N - 1.0
    if abs(mismatch) > VDC_MISMATCH_MAX:
        out.append(f"DC bus V_dc = {drive.inverter.V_dc:g} V differs from the nominal voltage V_N = "
                   f"{drive.motor.V_N:g} V by {100.0 * mismatch:+.1f} % (limit {100.0 * VDC_MISMATCH_MAX:g} %): the "
                   "closed forms use V_dc as V_N (per unit of V_dc / (2 k_phi)), not the motor's rating")
    return out


# ------------------------------------------------------------------------------------------------------------
# Table I and the characteristic


@dataclass(frozen=True)
class Table1:
    """Paper 1 Table I and the other derived quantities of section IV, for one drive.

    Parameters
    ----------
    name : str
        Drive name.
    Omega_0 : float
        Speed base (2) (rad/s).
    T_N : float
        Torque base (6) (N m).
    Theta_m : float
        Motor-specific parameter (22) (rad).
    cond_18 : bool
        Whether (18)/(19) holds (``v_ab`` peaks at pi/6, so (20)-(21) are exact for R = 0).
    Omega_sB_pu : float
        Base speed with sinusoidal supply (21) (per unit).
    Omega_qB_pu : float
        Base speed with real square-wave supply (30) (per unit).
    T_qB_pu : float
        Square-wave torque at its base speed (31) (per unit).
    T_sN_pu : float
        Nominal torque with sinusoidal supply (13) (per unit).
    TR_sN_pu : float
        Torque ripple with sinusoidal supply (15) (per unit).
    T_blac_N_pu : float
        Nominal torque of the equivalent PM BLAC motor, section IV.B (per unit).
    P_R_pu : float
        Resistive parameter of (36) (-).
    eta_ratio_0955 : float
        ``eta_s / eta_q`` at ``Omega_pu = 0.955``, (40) with (36): (43).
    eta_ratio_0455 : float
        ``eta_s / eta_q`` at ``Omega_pu = 0.455``, (40) with (36): (44).
    eta_ratio_0955_consistent : float
        The same with the consistent loss count :func:`p_lCu_consistent_pu` (not in the paper).
    eta_ratio_0455_consistent : float
        The same with the consistent loss count :func:`p_lCu_consistent_pu` (not in the paper).
    Omega_sB_R_pu : float
        R-aware numeric base speed, sinusoidal supply (per unit).
    Omega_qB_R_pu : float
        R-aware numeric base speed, square-wave supply (per unit).
    ratio_sB_R : float
        ``Omega_sB_R_pu`` over the numeric base speed with R = 0 (equal to (21) for the ideal trapezoid).
    ratio_qB_R : float
        ``Omega_qB_R_pu`` over the numeric base speed with R = 0 (equal to (30) for the ideal trapezoid).

    """

    name: str
    Omega_0: float
    T_N: float
    Theta_m: float
    cond_18: bool
    Omega_sB_pu: float
    Omega_qB_pu: float
    T_qB_pu: float
    T_sN_pu: float
    TR_sN_pu: float
    T_blac_N_pu: float
    P_R_pu: float
    eta_ratio_0955: float
    eta_ratio_0455: float
    eta_ratio_0955_consistent: float
    eta_ratio_0455_consistent: float
    Omega_sB_R_pu: float
    Omega_qB_R_pu: float
    ratio_sB_R: float
    ratio_qB_R: float

    def to_dict(self) -> dict[str, float | str | bool]:
        """Return the fields as a plain dict (JSON-ready)."""
        return asdict(self)

    def rows(self) -> list[tuple[str, str, float | bool, str, str]]:
        """Return one row per quantity: ``(key, description, value, unit, source)``."""
        out: list[tuple[str, str, float | bool, str, str]] = []
        for key, (desc, unit, src) in TABLE1_ROWS.items():
            out.append((key, desc, getattr(self, key), unit, src))
        return out


#: Description, unit and source of each numeric :class:`Table1` field, in print order.
TABLE1_ROWS: dict[str, tuple[str, str, str]] = {
    "Omega_0": ("speed base (no-load speed)", "rad/s", "(2)"),
    "T_N": ("torque base (nominal torque)", "N m", "(6)"),
    "Theta_m": ("motor-specific parameter", "rad", "(22)"),
    "cond_18": ("v_ab peaks at pi/6 (R = 0)", "-", "(18)"),
    "Omega_sB_pu": ("base speed, sinusoidal supply", "pu", "(21)"),
    "Omega_qB_pu": ("base speed, square-wave supply", "pu", "(30)"),
    "T_qB_pu": ("torque at base speed, square-wave supply", "pu", "(31)"),
    "T_sN_pu": ("nominal torque, sinusoidal supply", "pu", "(13)"),
    "TR_sN_pu": ("torque ripple, sinusoidal supply", "pu", "(15)"),
    "T_blac_N_pu": ("nominal torque, equivalent BLAC motor", "pu", "IV.B"),
    "P_R_pu": ("resistive parameter P_R,pu", "-", "(36)"),
    "eta_ratio_0955": ("eta_s/eta_q at Omega_pu = 0.955", "-", "(40),(43)"),
    "eta_ratio_0455": ("eta_s/eta_q at Omega_pu = 0.455", "-", "(40),(44)"),
    "eta_ratio_0955_consistent": ("eta_s/eta_q at 0.955, losses 2 R I_N^2", "-", "docs"),
    "eta_ratio_0455_consistent": ("eta_s/eta_q at 0.455, losses 2 R I_N^2", "-", "docs"),
    "Omega_sB_R_pu": ("base speed with R, sinusoidal supply", "pu", "numeric"),
    "Omega_qB_R_pu": ("base speed with R, square-wave supply", "pu", "numeric"),
    "ratio_sB_R": ("base speed with R / without, sinusoidal", "-", "numeric"),
    "ratio_qB_R": ("base speed with R / without, square-wave", "-", "numeric"),
}


def table1(drive: Drive) -> Table1:
    """Compute paper 1 Table I and the related quantities of section IV for a drive.

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    Table1

    """
    th = theta_m(drive)
    pcu = p_lCu_pu(drive)
    pcu_c = p_lCu_consistent_pu(drive)
    sB_R = omega_sB_numeric_pu(drive)
    qB_R = omega_qB_numeric_pu(drive)
    sB_0 = omega_sB_numeric_pu(drive, R=0.0)
    qB_0 = omega_qB_numeric_pu(drive, R=0.0)
    return Table1(
        name=drive.name,
        Omega_0=omega_0(drive),
        T_N=t_N(drive),
        Theta_m=th,
        cond_18=condition_18(drive),
        Omega_sB_pu=omega_sB_pu(th),
        Omega_qB_pu=omega_qB_pu(th),
        T_qB_pu=t_qB_pu(th),
        T_sN_pu=T_SN_PU,
        TR_sN_pu=TR_SN_PU,
        T_blac_N_pu=T_BLAC_N_PU,
        P_R_pu=p_R_pu(drive),
        eta_ratio_0955=float(eta_ratio(0.955, th, pcu)),
        eta_ratio_0455=float(eta_ratio(0.455, th, pcu)),
        eta_ratio_0955_consistent=float(eta_ratio(0.955, th, pcu_c)),
        eta_ratio_0455_consistent=float(eta_ratio(0.455, th, pcu_c)),
        Omega_sB_R_pu=sB_R,
        Omega_qB_R_pu=qB_R,
        ratio_sB_R=sB_R / sB_0,
        ratio_qB_R=qB_R / qB_0,
    )


#: Columns of :func:`characteristic`, in order.
CHARACTERISTIC_COLUMNS = ("Omega_pu", "Omega", "Omega_rpm", "T_s_pu", "T_q_pu", "TR_s_pu", "TR_q_pu", "T_s",
                          "T_q", "TR_s", "TR_q", "eta_s", "eta_q", "eta_ratio", "region_s", "region_q",
                          "T_blac_pu")


def characteristic(drive: Drive, speeds_pu: ArrayLike) -> pd.DataFrame:
    """Return the torque and ripple characteristics of both supplies at nominal current (paper 1 Figs 7-8).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.
    speeds_pu : array_like
        Speeds (per unit of Omega_0), >= 0, one-dimensional.

    Returns
    -------
    pandas.DataFrame
        One row per speed; columns ``Omega_pu``, ``Omega`` (rad/s), ``Omega_rpm``, ``T_s_pu``, ``T_q_pu``,
        ``TR_s_pu``, ``TR_q_pu`` (per unit), ``T_s``, ``T_q``, ``TR_s``, ``TR_q`` (N m), ``eta_s``, ``eta_q``,
        ``eta_ratio`` ((38)-(40) with the paper's losses (36); NaN above the base speeds), ``region_s``,
        ``region_q`` (the equations used) and ``T_blac_pu`` (the equivalent BLAC motor).

    """
    w = _speed(speeds_pu, "speeds_pu")
    if w.ndim != 1:
        raise BldclabError("speeds_pu", "must be a one-dimensional list of speeds")
    th = theta_m(drive)
    w0, tn = omega_0(drive), t_N(drive)
    pcu = p_lCu_pu(drive)
    ts = np.asarray(t_s_pu(w, th))
    tq = np.asarray(t_q_pu(w, th))
    rs = np.asarray(tr_s_pu(w, th))
    rq = np.asarray(tr_q_pu(w, th))
    data = {
        "Omega_pu": w,
        "Omega": w * w0,
        "Omega_rpm": w * w0 * 60.0 / TWO_PI,
        "T_s_pu": ts,
        "T_q_pu": tq,
        "TR_s_pu": rs,
        "TR_q_pu": rq,
        "T_s": ts * tn,
        "T_q": tq * tn,
        "TR_s": rs * tn,
        "TR_q": rq * tn,
        "eta_s": np.asarray(eta_s(w, th, pcu)),
        "eta_q": np.asarray(eta_q(w, th, pcu)),
        "eta_ratio": np.asarray(eta_ratio(w, th, pcu)),
        "region_s": region_s(w, th),
        "region_q": region_q(w, th),
        "T_blac_pu": np.asarray(t_blac_pu(w, th)),
    }
    import pandas as pd  # imported here: `import bldclab` (and every sweep worker) starts 0.3 s faster without it

    return pd.DataFrame(data, columns=list(CHARACTERISTIC_COLUMNS))

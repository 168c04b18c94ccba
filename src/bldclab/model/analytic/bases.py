"""Paper 1 section II: the bases and ratings.

No-load speed (2), nominal speed (2), back-EMF (3), torque (6) and sinusoidal current (7)-(8); and
:func:`r_total`, the resistance in series with a conducting phase (paper 1's R includes the switch).
"""

from __future__ import annotations

from ..motor import Drive
from ._common import SQRT3

__all__ = [
    "e_N",
    "i_sN",
    "omega_0",
    "omega_N",
    "r_total",
    "t_N",
]


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

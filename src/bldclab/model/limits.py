"""Premises of a simulation that follow from the drive alone: PWM against ``L/R``, electrical frequency, no-load speed.

:func:`bldclab.simulate` checks them before every run (:mod:`bldclab.sim.plausibility`, which re-exports this
module's names and documents the thresholds and their reasons), ``bldclab compare`` and ``bldclab effmap`` collect the
warnings of their runs, and ``bldclab check`` states them for a motor file at the speeds ``compare`` runs
(:data:`TOP_SPEED_PU`), in the same words: one code for all of them, in the model layer so that ``check`` needs no
simulator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from .motor import Drive

__all__ = ["PWM_PER_PERIOD_ERROR", "PWM_PER_PERIOD_WARN", "PWM_TAU_ERROR", "PWM_TAU_WARN", "SPEED_ERROR_PU",
           "TOP_SPEED_PU", "Finding", "check_pwm", "check_speed", "grade"]

PWM_TAU_WARN = 1.0
PWM_TAU_ERROR = 10.0
PWM_PER_PERIOD_WARN = 12.0
PWM_PER_PERIOD_ERROR = 3.0
SPEED_ERROR_PU = 10.0

#: The highest speed ``bldclab compare`` runs by default (p.u. of ``Omega_0``): ``bldclab check`` states the premises
#: of the comparison at it.
TOP_SPEED_PU = 0.98


@dataclass(frozen=True)
class Finding:
    """One plausibility finding.

    Attributes
    ----------
    level : {"warning", "error"}
        ``error``: the result would be physically meaningless.
    cause : str
        What is implausible, as a dotted name (``"inverter.f_pwm"``, ``"scenario.speed"``, ``"scenario.ref"``,
        ``"result.energy_balance"``, ``"result.currents"``, ``"result.finite"``, ``"scenario.window"``).
    message : str
        The numbers and the threshold crossed.
    """

    level: Literal["warning", "error"]
    cause: str
    message: str

    def __str__(self) -> str:
        """``cause: message``."""
        return f"{self.cause}: {self.message}"


def grade(value: float, warn: float, error: float, above: bool = True) -> Literal["warning", "error"] | None:
    """Return ``"error"``, ``"warning"`` or None for a value against its thresholds (beyond them: ``above``)."""
    if above:
        return "error" if value > error else "warning" if value > warn else None
    return "error" if value < error else "warning" if value < warn else None


def check_pwm(drive: Drive, omega_max: float | None, time_constant: bool = True) -> list[Finding]:
    """Check the PWM frequency against the electrical time constant and the electrical frequency.

    Parameters
    ----------
    drive : Drive
    omega_max : float or None
        Highest mechanical speed of the run (rad/s); ``None``: only the time-constant check.
    time_constant : bool
        Also check the PWM period against ``L / R``.

    Returns
    -------
    list of Finding
    """
    out = []
    f_pwm = drive.inverter.f_pwm
    m = drive.motor
    if time_constant and m.R > 0:
        tau_el = m.L / m.R
        ratio = 1.0 / f_pwm / tau_el
        level = grade(ratio, PWM_TAU_WARN, PWM_TAU_ERROR)
        if level:
            out.append(Finding(level, "inverter.f_pwm",
                               f"the PWM period 1/f_pwm = {1 / f_pwm:.4g} s is {ratio:.3g} times the electrical time "
                               f"constant L/R = {tau_el:.4g} s (limit {PWM_TAU_WARN:g} for a warning, "
                               f"{PWM_TAU_ERROR:g} for an error): the current is no PWM average with a ripple"))
    if omega_max is not None and omega_max > 0:
        f_e = m.p * omega_max / (2.0 * math.pi)
        n = f_pwm / f_e
        level = grade(n, PWM_PER_PERIOD_WARN, PWM_PER_PERIOD_ERROR, above=False)
        if level:
            out.append(Finding(level, "inverter.f_pwm",
                               f"f_pwm = {f_pwm:.4g} Hz gives {n:.3g} PWM periods per electrical period at "
                               f"{omega_max:.4g} rad/s (f_e = {f_e:.4g} Hz; at least {PWM_PER_PERIOD_WARN:g} "
                               f"wanted, below {PWM_PER_PERIOD_ERROR:g} the controller misses commutation sectors)"))
    return out


def check_speed(drive: Drive, omega_max: float, v_dc_max: float | None = None) -> list[Finding]:
    """Check an imposed speed against the no-load speed ``Omega_0`` at the highest bus voltage.

    Parameters
    ----------
    drive : Drive
    omega_max : float
        Highest imposed mechanical speed (rad/s, magnitude).
    v_dc_max : float, optional
        Highest DC source voltage of the run (V); default the inverter's ``V_dc``.

    Returns
    -------
    list of Finding
    """
    v = drive.inverter.V_dc if v_dc_max is None else v_dc_max
    omega_0 = v / (2.0 * drive.motor.k_phi)
    pu = omega_max / omega_0
    level = grade(pu, 1.0 + 1e-9, SPEED_ERROR_PU)
    if not level:
        return []
    return [Finding(level, "scenario.speed",
                    f"{omega_max:.4g} rad/s ({omega_max * 30 / math.pi:.4g} rpm) is {pu:.4g} times the no-load speed "
                    f"Omega_0 = V_dc / (2 k_phi) = {omega_0:.4g} rad/s at V_dc = {v:.4g} V: the back-EMF exceeds the "
                    f"bus (error above {SPEED_ERROR_PU:g} Omega_0)")]

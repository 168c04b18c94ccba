"""Applicability: where the premises of paper 1's closed forms hold.

The ideal 120-degree trapezoidal back-EMF, the resistance neglected, the DC bus at the nominal voltage: the
measures and thresholds behind :func:`applicability`.
"""

from __future__ import annotations

import math

import numpy as np

from ..emf import TWO_PI, Trapezoid
from ..motor import Drive
from ._common import SQRT3
from .bases import r_total
from .sine import (
    T_SN_PU,
)

__all__ = [
    "COMMUTATION_PERIODS_MIN",
    "R_DROP_MAX",
    "SHAPE_DEVIATION_MAX",
    "SINUSOIDAL_THD_MAX",
    "VDC_MISMATCH_MAX",
    "applicability",
    "commutation_periods",
    "commutation_premise",
    "harmonic_ratio",
    "shape_applies",
    "shape_deviation",
    "sine_torque_pu",
]


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


def shape_applies(drive: Drive) -> bool:
    """Whether the back-EMF is paper 1's ideal trapezoid (:func:`shape_deviation` within :data:`SHAPE_DEVIATION_MAX`).

    Every closed form of paper 1 assumes it: where it does not hold (a sinusoidal back-EMF), ``compare``'s figures
    leave the closed-form curves out rather than draw them as a reference they are not.
    """
    return shape_deviation(drive) <= SHAPE_DEVIATION_MAX


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


#: Fewest PWM periods a square-wave commutation may last for a sampled current controller to shape it: below about
#: three the commutation spike is shorter than the controller's reaction (two samples with its computation delay),
#: and the switching drive's ripple departs from (27)-(33) by several hundredths of T_N (a fan motor at one PWM period
#: per commutation: 0.05-0.08 p.u.). :func:`commutation_premise` warns below it.
COMMUTATION_PERIODS_MIN = 3.0


def commutation_periods(drive: Drive, omega_pu: float) -> float:
    """PWM periods the square wave's commutation lasts at a speed: ``f_pwm 3 L I_N / (V_dc (1 + W))``.

    The time the outgoing phase's current takes to fall from ``I_N`` to zero through its diode (paper 1, IV.A; R
    neglected): the first part of every commutation, at any speed ``W`` (per unit of ``Omega_0``).

    Parameters
    ----------
    drive : Drive
    omega_pu : float
        Speed (per unit of ``Omega_0``), >= 0.

    Returns
    -------
    float
        PWM periods (-).
    """
    t_c = 3.0 * drive.motor.L * drive.motor.I_N / (drive.inverter.V_dc * (1.0 + omega_pu))
    return t_c * drive.inverter.f_pwm


def commutation_premise(drive: Drive) -> tuple[str, bool]:
    """One line stating how many PWM periods the square-wave commutation lasts, and whether that is too few.

    Paper 1's square-wave closed forms (26)-(33) assume an ideal current limiter, infinitely faster than the
    commutation; a sampled controller approaches it only while a commutation spans several PWM periods
    (:data:`COMMUTATION_PERIODS_MIN`). bldclab's ideal limiter (``SixStep(regulation="ideal")``, compare's averaged
    column) holds the premise at any rate.

    Returns
    -------
    tuple of (str, bool)
        The line, and True when the commutation lasts fewer than :data:`COMMUTATION_PERIODS_MIN` periods at the
        no-load speed.
    """
    n0, n1 = commutation_periods(drive, 0.0), commutation_periods(drive, 1.0)
    line = (f"square-wave commutation lasts {n0:.3g} PWM periods at standstill, {n1:.3g} at Omega_0 "
            f"(3 L I_N / (V_dc (1 + W)) at {drive.inverter.f_pwm:g} Hz)")
    few = n1 < COMMUTATION_PERIODS_MIN
    if few:
        # n(W) = n0 / (1 + W) falls below the minimum above W = n0 / min - 1
        w_lo = n0 / COMMUTATION_PERIODS_MIN - 1.0
        where = "at every speed" if w_lo <= 0.0 else f"above {w_lo:.2f} Omega_0"
        line += (f"; fewer than {COMMUTATION_PERIODS_MIN:g} {where}: there a sampled current controller cannot shape "
                 "it and the switching drive's square-wave ripple departs from (27)-(33) (compare's averaged column, "
                 "the ideal current limiter, keeps paper 1's premise)")
    return line, few


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
      speeds of :func:`~bldclab.model.analytic.table.table1` then apply rather than (21) and (30));
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

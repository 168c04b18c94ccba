"""Sensorless six-step (square-wave) drive from the floating phase's back-EMF, as a drone or RC ESC runs it.

The C controller is ``core/ctrl/include/bldc/bc_bemf.h`` (every law in its header); the laws, the parameters and the
physics of demagnetisation and desync as the controller sees them are in ``docs/sensorless.md``.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np

from .._core import Core, CParams
from ..errors import BldclabError
from ..model.analytic import r_total
from ..model.motor import Drive
from ..model.units import to_si
from .base import Control, check_number

__all__ = [
    "SixStepSensorless", "brake_tau", "fast_demag_after", "integral_to_30", "inverter_share", "ramp_excess_speed",
    "throttle_rate",
]

# the settings' C constants (values read from the library: bldclab._core)
_METHOD = {"comparator": "BC_BEMF_COMPARATOR", "adc": "BC_BEMF_ADC", "integration": "BC_BEMF_INTEGRATE"}
_BLANK = {"fixed": "BC_BEMF_BLANK_FIXED", "demag": "BC_BEMF_BLANK_DEMAG"}
_CHOP = {"bipolar": "BC_CHOP_BIPOLAR", "high": "BC_CHOP_HIGH", "pwm-on-pwm": "BC_CHOP_PWMPWM", "sync": "BC_CHOP_SYNC"}
_REFS = ("star", "half")  # the spelling of Sensors.bemf_reference

#: fields with a unit (dimension of :func:`bldclab.model.units.to_si`); speeds are mechanical
_UNITS = {"blank": "angle", "blank_time": "time", "min_pulse": "time", "filter_tau": "time",
          "comparator_delay": "time", "timing": "angle", "timing_time": "time", "timing_max": "angle",
          "stall_speed": "speed", "align_time": "time", "ramp_start_speed": "speed", "ramp_end_speed": "speed",
          "ramp_time": "time", "ramp_tau": "time", "restart_wait": "time", "restart_max": "time",
          "current_limit_time": "time",
          "align_current": "current", "i_max": "current", "current_limit": "current",
          "duty_limit_current": "current", "start_current_limit": "current"}

_RATE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*%\s*/\s*(ms|s)\s*$")


def throttle_rate(value: float | str, field: str = "control.throttle_rate") -> float:
    """Return a throttle ramp limit in 1/s (duty per second) from a number (1/s) or ``"<x> %/ms"``, ``"<x> %/s"``.

    ``"1 %/ms"`` is 10 /s: the duty may change by 0.01 per millisecond.

    Raises
    ------
    BldclabError
        Naming ``field`` if the value is not a finite number >= 0 or such a string.
    """
    if isinstance(value, str):
        m = _RATE.match(value)
        if not m:
            raise BldclabError(field, f"expected a number (1/s) or '<x> %/ms', got {value!r}")
        v = float(m.group(1)) * 0.01 / (1e-3 if m.group(2) == "ms" else 1.0)
    elif isinstance(value, bool) or not isinstance(value, int | float):
        raise BldclabError(field, f"expected a number (1/s) or '<x> %/ms', got {value!r}")
    else:
        v = float(value)
    if not math.isfinite(v) or v < 0.0:
        raise BldclabError(field, f"must be a finite rate >= 0, got {value!r}")
    return v


def fast_demag_after(drive: Drive, share: float = 0.45, min_samples: float = 4.0) -> float:
    """Return the default share of the window after which the fast demagnetisation engages.

    Parameters
    ----------
    drive : Drive
    share : float
        Share of the window from the commutation to the expected crossing (``30 deg + timing``) after which the fast
        pattern engages: 0.45, below the demagnetisation limiter's default set point (0.6), so that a clamp growing
        with the current meets the fast pattern first and the duty limit only if that is not enough.
    min_samples : float
        See below.

    Returns
    -------
    float
        ``share``; 0 (from the commutation) where the comparators have an offset (``drive.sensors.bemf_offset``:
        the fast pattern's sectors read the comparator in the pair's on-time only, which keeps the offset's effect
        on the slowest closed-loop speed to its closed form; htm-48v with 0.3 V: 0.057 p.u. against 0.056, with the
        plain pattern 0.074), and where the inverter's diodes are ideal (``V_f = 0``) and the window at ``Omega_0``
        spans fewer than ``min_samples`` samples: an ideal diode lets the floating phase conduct in the PWM
        off-times before a rising crossing, and on such a drive (f60prov-2550kv: 1.6 samples) only the fast
        pattern from the commutation keeps the crossing at 0.9 ``Omega_0`` (docs/sensorless.md section 6).
    """
    if drive.sensors.bemf_offset != 0.0:
        return 0.0
    window = math.pi / (6.0 * drive.motor.p * drive.Omega_0)
    if drive.inverter.V_f == 0.0 and window * 2.0 * drive.inverter.f_pwm < min_samples:
        return 0.0
    return share


def inverter_share(drive: Drive, chopping: str, current: float) -> float:
    """Return the duty the inverter's diodes and dead time take from a start-up duty (``d_diode``, docs/sensorless.md).

    The start-up duties (alignment, forced ramp) and the closed loop's speed-dependent limit are computed for an
    ideal inverter, ``d_s = u / V_dc`` for the pair voltage ``u`` they need (the drop of the current on ``2 (R +
    R_on)`` and the back-EMF); the controller applies ``d = q + (1 - q) d_s`` with ``q`` this share:

    - ``high``, ``pwm-on-pwm``, ``bipolar``: in the off-time the chopping leg's current flows through a diode, so the
      leg sits at ``-V_d``, ``V_d = V_f + (r_d - R_on) I``, instead of near 0 (bipolar: the pair at ``-(V_dc + 2
      V_d)`` instead of ``-V_dc``), and ``u = d (V_dc + V_d) - V_d``: ``q = V_d / (V_dc + V_d)``;
    - ``sync``: the diode carries the current only in the dead time before each turn-on and after each turn-off of
      the chopping switch: ``q = t_dead f_pwm (V_dc + 2 V_f) / V_dc`` (to first order).

    It presumes the current in the chopping leg continuous over the PWM period (the start-up's current through
    ``L``; true on every catalog drive). On f60prov-2550kv (16.8 V, alignment duty 0.034) a 0.7 V diode alone takes
    more than the whole alignment voltage in the off-time: uncounted, the high-side pattern drives no current.

    Parameters
    ----------
    drive : Drive
    chopping : {"sync", "high", "pwm-on-pwm", "bipolar"}
    current : float
        The chopping leg's current (A); the start-up's alignment current.

    Returns
    -------
    float
        ``q``, at most 0.5 (a diode drop above the bus voltage is no inverter).
    """
    inv = drive.inverter
    v = inv.V_dc
    if chopping == "sync":
        q = inv.t_dead * inv.f_pwm * (v + 2.0 * inv.V_f) / v
    else:
        v_d = max(inv.V_f + (inv.r_d - inv.R_on) * abs(current), 0.0)
        q = v_d / (v + v_d)
    return min(max(q, 0.0), 0.5)


def brake_tau(drive: Drive) -> float:
    """Return the time constant of the fastest fall of the rotor's speed the six-step drive can cause (s).

    The inverter brakes hardest with the driven pair shorted (duty 0, synchronous chopping): the pair's back-EMF
    drives ``-k_pair omega / (2 (R + R_on))`` round it, a braking torque ``D omega`` with ``D = (2 k_phi)^2 / (2 (R +
    R_on))``, so with the viscous friction the speed falls at most as ``exp(-t / tau)``, ``tau = J / (D + B)`` (the
    Coulomb friction adds ``tau_c / J``, the propeller's drag ``k_q omega`` per rad/s, at most ``k_q omega_0`` below
    a speed ``omega_0``: the controller adds both). The crossing timeout (law 9) waits at least as long as such a
    rotor takes to its next crossing.

    Parameters
    ----------
    drive : Drive

    Returns
    -------
    float
        ``J / (D + B)``, s.
    """
    m = drive.motor
    damp = (2.0 * m.k_phi) ** 2 / (2.0 * r_total(drive))
    return drive.mechanics.J / (damp + drive.mechanics.B)


def ramp_excess_speed(drive: Drive, current: float) -> float:
    """Return how much faster than the forced ramp a rotor in step at its end runs free (mechanical rad/s).

    At the ramp's end speed ``w`` the ramp drives the current ``I`` (``current``: the alignment current) in step,
    and the rotor no longer accelerates: the torque ``2 k_phi I`` less the drive's loads at ``w`` (``tau_c + B w +
    k_q w^2``) is left over and pulls it ahead of the forced field, which it follows (the crossings commutate it).
    Its back-EMF then takes the current down, by ``2 k_phi / (2 (R + R_on))`` per rad/s, until the torque balances
    the loads: at ``w + D(w)`` with

        D(w) = 2 (R + R_on) (2 k_phi I - tau_c - B w - k_q w^2) / (2 k_phi)^2.

    Returns the smallest ``w >= 0`` with ``w >= D(w)`` (bisection; ``D`` falls with ``w``): from there on a rotor
    running ahead at most doubles the forced speed. Where the back-EMF dominates the ramp's duty it is below
    ``0.1 Omega_0`` (lu-4kw 0.003, f60prov-2550kv 0.048, htm-48v 0.05, outrunner-24v 0.086; mn3110-780kv 0.122);
    on a high-resistance motor (a 12 V, 10-ohm gimbal motor: 0.39 ``Omega_0``) the ramp's duty is mostly the
    resistive drop, and an end speed of ``0.1 Omega_0`` left the rotor free to run at four times it, swinging
    through the forced sectors (docs/sensorless.md, law 5).
    """
    m, mech = drive.motor, drive.mechanics
    k = 2.0 * m.k_phi
    r = r_total(drive)

    def excess(w: float) -> float:
        return 2.0 * r * (k * current - mech.tau_c - mech.B * w - mech.k_q * w * w) / (k * k)

    lo, hi = 0.0, max(excess(0.0), 0.0)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if mid >= excess(mid):
            hi = mid
        else:
            lo = mid
    return hi


def integral_to_30(drive: Drive, reference: str | None = None, n: int = 721) -> float:
    """Back-EMF integral from the floating phase's zero crossing to 30 degrees after it (V s), per sector, averaged.

    What the back-EMF integration method (``method="integration"``) compares its integral with. The sampled signal is
    the floating phase's terminal voltage minus the comparators' reference: against a virtual star point of the three
    terminals it is ``(2 e_F - e_p - e_n) / 3``, against half the bus (sampled in the on-time) ``e_F - (e_p + e_n) / 2``
    (``e_p``, ``e_n``: the phases driven positive and negative). Its integral over time from the crossing to an angle
    does not depend on the speed: ``int e dt = int k(theta) dtheta_m = (1/p) int k dtheta_e``. For the ideal
    120-degree trapezoid of flat top ``k_phi``: ``(2/3) k_phi pi / (12 p)`` (star), ``k_phi pi / (12 p)`` (half bus).

    Parameters
    ----------
    drive : Drive
        Its back-EMF shapes (``drive.motor.emf``) and pole pairs.
    reference : {"star", "half"}, optional
        The comparators' and the ADC's reference; default the drive's hardware, ``drive.sensors.bemf_reference``.
    n : int
        Points of the numerical integration per 60 degrees.

    Returns
    -------
    float
        The mean over the six sectors of the integral from the crossing (the zero of the signal near the sector's
        middle) to 30 electrical degrees after it, V s.
    """
    if reference is None:
        reference = drive.sensors.bemf_reference
    if reference not in _REFS:
        raise BldclabError("reference", f"must be one of {', '.join(_REFS)} (as Sensors.bemf_reference), "
                           f"got {reference!r}")
    m = drive.motor
    pos = (0, 0, 1, 1, 2, 2)
    neg = (1, 2, 2, 0, 0, 1)
    out = []
    for s in range(6):
        start = math.pi / 6.0 + s * math.pi / 3.0
        th = np.linspace(start, start + math.pi / 3.0, n)
        k = m.emf.k_abc(th)
        p, q = pos[s], neg[s]
        f = 3 - p - q
        u = (2.0 * k[f] - k[p] - k[q]) / 3.0 if reference == "star" else k[f] - 0.5 * (k[p] + k[q])
        post = 1.0 if s % 2 else -1.0  # odd sectors cross upward (forward)
        u = post * u
        j = int(np.argmax(u > 0.0))  # the first sample after the crossing
        if j == 0 or not np.any(u > 0.0):
            raise BldclabError("control.int_limit", f"the back-EMF of {drive.name or 'the drive'} has no crossing "
                               f"in sector {s}: give int_limit")
        th0 = th[j - 1] - u[j - 1] * (th[j] - th[j - 1]) / (u[j] - u[j - 1])
        t2 = np.linspace(th0, th0 + math.pi / 6.0, n)
        k2 = m.emf.k_abc(t2)
        u2 = post * ((2.0 * k2[f] - k2[p] - k2[q]) / 3.0 if reference == "star" else k2[f] - 0.5 * (k2[p] + k2[q]))
        out.append(float(np.sum(0.5 * (u2[1:] + u2[:-1]) * np.diff(t2))) / m.p)
    return float(np.mean(out))


@dataclass(frozen=True)
class SixStepSensorless(Control):
    """Sensorless six-step drive: commutation from the floating phase's back-EMF zero crossing, as an ESC does it.

    The reference (``Scenario.ref``) is the duty (throttle) in [-1, 1]; its sign is the direction of rotation (a
    change of sign stops the drive and starts it the other way); 0 stops it (all legs off). The C controller
    (``bc_bemf``) aligns the rotor, ramps it up with forced commutation, hands over to closed loop after
    ``handover`` valid crossings, commutates ``30 deg - timing`` after each crossing at the instant its commutation
    timer computes (``bc_ctrl_out.has_at``), detects a loss of synchronisation and restarts.

    Angles accept strings such as ``"15 deg"``, times ``"20 us"``, speeds ``"3000 rpm"`` (speeds are mechanical,
    rad/s), currents ``"10 A"``.

    The sensing is the drive's hardware (``drive.sensors.bemf_*``, docs/sensing.md): the comparators' reference
    (virtual star point or half the bus, ``bemf_reference``) is not a setting here (the default ``int_limit`` is
    computed against it), and the filter time constant and comparator delay the firmware compensates default to
    ``bemf_tau`` and ``bemf_delay``.

    Parameters
    ----------
    method : {"comparator", "adc", "integration"}
        ``comparator``: the crossing is the comparator's edge (``bc_ctrl_in.zc_*``, time-stamped by the capture
        timer); ``adc``: from the ADC samples of the terminal voltage against the reference (once per PWM period),
        interpolated between the last sample before and the first after it; ``integration``: the ADC crossing, then
        the commutation when the back-EMF integral from it reaches ``int_limit`` (VESC's BLDC mode). The comparator
        method needs the virtual star reference (``drive.sensors.bemf_reference = "star"``); against half the bus
        it is refused (the comparator would see the PWM), the ADC methods sample in the on-time and run with both.
    chopping : {"sync", "high", "pwm-on-pwm", "bipolar"}
        ``sync``: the positive leg complementary (synchronous rectification, as AM32 and BLHeli_32), the negative
        leg's lower switch on; ``high``: the positive leg's upper switch chops; ``pwm-on-pwm``: the incoming phase
        chops in the first half of the sector, the continuing one in the second; ``bipolar``: both legs chop.
    fast_demag : bool
        From each commutation until the floating phase shows the demagnetisation over, the phase that stays in the
        pair (the continuing one) chops instead of the incoming one (default True; ``sync``, ``high``,
        ``pwm-on-pwm``): the outgoing current then falls with about ``(2 - d) V_dc / 3`` instead of ``d V_dc / 3``,
        which keeps the crossing visible at low duty and high current (a throttle step). The closed forms are in
        docs/sensorless.md. When it chops the negative leg and the drive's comparators have an offset
        (``drive.sensors.bemf_offset``), the comparator is read in the pair's on-time only until the crossing: the
        floating phase can clamp to the bus in the off-time, which a comparator with an offset reads as a crossing.
    fast_demag_after : float, optional
        The fast pattern engages once the clamp has lasted this share of the window from the commutation to the
        expected crossing (``30 deg + timing``), at the output whose interval reaches it; 0: from the commutation.
        A clamp that ends sooner never sees the pattern change, so at light load the drive's torque is that of the
        plain pattern (the fast fall of the outgoing current dips the torque in every commutation: 1-2 % of the mean
        on the catalog's servo and outrunner motors at 0.2 ``Omega_0``). Default :func:`fast_demag_after`: 0.45, or 0
        where the comparators have an offset or where ideal diodes meet a window of under four samples.
    blanking : {"demag", "fixed"}
        ``demag``: after the fixed blanking the window for the crossing opens at the measured end of the
        demagnetisation (the floating phase shows the pre-crossing level, held at least ``min_pulse``); ``fixed``:
        the first edge into the post-crossing level after the fixed blanking. With both, a post level already there
        when the window opens is not a crossing (it is the diode clamp, or a crossing already past).
    blank : float or str
        Fixed blanking after each commutation, electrical angle (default ``"5 deg"``); the larger of it (at the
        speed estimate) and ``blank_time`` applies.
    blank_time : float or str, optional
        Fixed blanking in time; default ``2 filter_tau + comparator_delay + 1 us``: the comparator's view of the
        clamp's onset must fall inside it.
    min_pulse : float or str
        Comparator: the post level must be held this long after its edge (default ``"1 us"``).
    n_samples : int
        ADC methods: consecutive samples on the post side for a crossing (default 2).
    filter_tau : float or str, optional
        Time constant of the terminal voltages' RC filter that the firmware compensates, as ``atan(Omega tau) /
        Omega``; default the drive's hardware, ``drive.sensors.bemf_tau`` (give it only to study a firmware that
        believes another value).
    comparator_delay : float or str, optional
        The comparators' propagation delay the firmware compensates; default ``drive.sensors.bemf_delay``.
    comparator_blind : bool, optional
        Comparator with ``sync`` or ``high`` chopping: True takes the comparator as blind in the pair's PWM
        off-time, where both driven terminals sit at the negative rail and a floating terminal clamped there by an
        ideal diode reads exactly the star reference, so a crossing in the off-time shows late (at most at the next
        on-time's start). An edge in the off-time, or at the start of the on-time after it, is then taken at the
        off-time's middle, the carrier valley (unbiased: the crossing lies uniformly in the off-time), an edge in an
        on-time as seen (docs/sensorless.md, law 6). Default :meth:`blind`: True where the drive's diodes are ideal
        (``V_f = 0`` and ``r_d = 0``); with any forward voltage the floating terminal is not clamped near its
        crossing and the comparator reads the off-time exactly.
    timing : float or str
        Timing advance (electrical angle, default 0).
    timing_time : float or str
        Timing advance per speed (s): ``+ Omega_e timing_time``.
    timing_demag : float
        Automatic advance from the measured demagnetisation: ``+ timing_demag x`` its electrical angle.
    timing_max : float or str
        Cap of the total advance (default ``"30 deg"``, the largest).
    interval_gain : float
        Gain in (0, 1] of the crossing-interval filter ``T60 <- T60 + g (T - T60)`` (default 0.5; 1: the last one).
    grid_gain : float
        0 (default): commutate ``30 deg - timing`` after each crossing. In (0, 1]: commutate on the uniform
        60-degree grid phase-locked to the mean of the six crossings (the Hall drive's symmetric placement), each
        sector's crossing interval filtered with this gain (0.1: about ten electrical periods), applied from the
        twelfth interval after the handover, the correction at most 10 degrees; for a motor whose phases'
        back-EMFs differ (shifted, scaled), whose crossings lie off the magnet's grid (docs/sensorless.md, section
        9). A grid point later than 30 degrees after the crossing is bounded by the measured demagnetisation: never
        so late that the next crossing's window holds the longest clamp of the last six sectors as more than
        ``demag_limit`` of it (docs/sensorless.md, law 7). Comparator and ADC methods (the integration method
        ignores it).
    int_limit : float, optional
        Integration method: the back-EMF integral from the crossing to 30 degrees (V s); default from the drive's
        back-EMF (:func:`integral_to_30`).
    timeout : float
        A crossing missing ``timeout`` crossing intervals after the previous one (default 1.5, when the next
        commutation would be due without advance) is missed.
    jump : float
        Largest ratio of successive crossing intervals (default 2); beyond it a desync (a false crossing).
    misses : int
        Blind commutations allowed in a row for a missed crossing before a desync (default 0).
    stall_speed : float or str, optional
        Slowest closed-loop speed (mechanical); default ``0.03 Omega_0``.
    align_time : float or str, optional
        Rotor alignment before the ramp; 0: a direct start (no alignment), as drone firmware does. Default three
        periods of the rotor's oscillation about the aligned position, ``3 x 2 pi sqrt(J / K)`` with the stiffness
        of the aligning pair ``K = (6/pi) p k_phi align_current`` (the 120-degree trapezoid's slope; J from
        ``drive.mechanics``), or, if longer, twelve time constants ``D / K`` of an overdamped rotor, ``D = 2
        k_phi^2 / (R + R_on)`` the damping of the loop the motion drives through the two phases in parallel: six
        unloaded, twice that against a load up to half the static torque, the most the default ramp leaves for a
        load, or the time ``2.5 x 2 J / (D + B)`` in which a lightly damped swing's envelope falls by 12 (from half
        a turn to 15 degrees), within [10 ms, 6 s]: the first (2/7 of it) and the last (4/7) of the alignment's
        three steps; the middle step (1/7) adds a sixth (lu-4kw: 6.2 s, mn3110-780kv: 0.61 s; docs/sensorless.md,
        law 4).
    align_current : float or str, optional
        Current the alignment duty drives through the line resistance at standstill, and the forced ramp's current;
        default ``0.5 I_N``.
    align_duty : float, optional
        Alignment duty of an ideal inverter; default ``1.5 (R + R_on) align_current / V_dc`` (two phases in
        parallel against the third). This, ``ramp_duty``, ``ramp_vf`` and ``duty_limit_current``'s limit are duties
        of an ideal inverter; the controller applies ``q + (1 - q) d`` with ``q`` the share of the inverter's diode
        drop and dead time for the chopping pattern (:func:`inverter_share`; 0 for the ideal inverter).
    ramp_start_speed, ramp_end_speed : float or str, optional
        Forced commutation's speeds (mechanical); defaults 0 (from standstill at the ramp's acceleration: a start speed
        above what the rotor reaches in the first sector leaves a light rotor behind) and ``0.1 Omega_0`` or, if
        higher, :func:`ramp_excess_speed` (a high-resistance motor: the speed excess the ramp's unused torque gives
        a rotor running ahead of it at its end, so that it runs at most twice as fast as the ramp).
    ramp_time : float or str, optional
        Time of the ramp from start to end speed: the acceleration. Default: the acceleration half the alignment
        current's torque ``2 k_phi align_current`` gives the inertia J, within [10 ms, 10 s].
    ramp_duty : float, optional
        Duty of the forced commutation at standstill; default ``2 (R + R_on) align_current / V_dc``.
    ramp_vf : float, optional
        Added ramp duty per electrical rad/s of the speed (V/f), so that the current stays near ``align_current``
        as the back-EMF grows; default ``2 k_phi / (p V_dc)``.
    ramp_tau : float or str, optional
        The ramp's first term is ``ramp_duty sqrt(1 + (Omega_e ramp_tau)^2)`` at the forced electrical speed
        ``Omega_e``: the drop of the ramp current on the pair's impedance ``|R + j Omega_e L|``, so that the
        inductance does not take the current (and the torque) as the ramp speeds up. Default ``L / (R + R_on)``;
        0: the resistive drop only.
    ramp_hold : int
        Forced sectors at the end speed before the start fails (default 12).
    handover : int
        Consecutive valid crossings for the handover to closed loop (default 6).
    duty_min : float
        Smallest closed-loop duty (default 0).
    throttle_rate : float or str, optional
        Throttle ramp limit: 1/s or ``"5 %/ms"``; ``None`` (default): none.
    stop_below : float
        ``|ref| <= stop_below`` stops the drive (default 0).
    restart_wait, restart_max : float or str
        After a stop or a desync, a restart waits until the comparators have been quiet for ``restart_wait``
        (default ``"50 ms"``), at most ``restart_max`` (default ``"1 s"``).
    current_sensing : bool
        The drive measures phase currents (default True): the input guard and ``i_max`` trip use them; without it
        currents are ignored (most ESCs measure the bus current only).
    i_max : float or str, optional
        Over-current trip; default ``2 I_N``.
    current_limit : float or str, optional
        Current limit (an integrating limiter on the duty); ``None`` (default): none.
    duty_limit_current : float or str, optional
        Speed-dependent duty limit in closed loop, as an ESC limits its throttle at low speed without a current
        sensor: ``d <= 2 (R + R_on) I sqrt(1 + (Omega_e L / (R + R_on))^2) / V_dc + 2 k_phi Omega_e / (p V_dc)`` (the
        drop of the current ``I`` on the pair's impedance plus the back-EMF's duty at the estimated speed), so that a
        throttle step at low speed cannot drive the pair's current far beyond ``I`` (an over-current trip). Default
        ``I_N``; 0: none.
    demag_limit : float
        Demagnetisation limiter: the largest share of the window from a commutation to the expected crossing
        (``30 deg + timing``) that the diode clamp may take before the controller lowers the duty (default 0.6; 0:
        off). The clamp's length is measured every sector; while it takes more than this share, the duty cap falls
        (and the current, and the clamp, with it), and it recovers while it takes less: a throttle step then cannot
        hide the crossing whatever the load does.
    start_current_limit : float or str, optional
        Start-up current limit, cycle by cycle, as an ESC's (with ``current_sensing``): in the alignment and the
        forced ramp an output interval after a sample whose largest phase current exceeds it applies duty 0. The
        ramp's V/f duty assumes a rotor that follows it; a rotor held by its load or left behind would draw the
        current of a back-EMF it does not have up to the over-current trip, and with the limit the start fails by
        its hold (``START_FAIL``) instead, or the field pulls the rotor round. Default ``2 align_current``; 0: none.
    current_limit_time : float or str
        Time constant of the limiter at standstill (default ``"1 ms"``): gain ``2 (R + R_on) / (V_dc t)``.
    delay : int
        Samples between computing and applying an output (0 or 1). Default 0: an ESC's firmware commutates in its
        comparator's and commutation timer's interrupts, at the instant it computes (and its throttle's duty moves
        far slower than a sample); 1: a controller that writes its outputs for the next PWM update, whose
        commutation waits for the sample after the one that computed it (at a few samples a sector and a large
        advance that alone loses synchronisation: docs/desync.md, "The controller's delay").
        :func:`bldclab.simulate` sets it from ``Scenario.delay`` where that is given.
    """

    method: Literal["comparator", "adc", "integration"] = "comparator"
    chopping: Literal["sync", "high", "pwm-on-pwm", "bipolar"] = "sync"
    fast_demag: bool = True
    fast_demag_after: float | None = None
    blanking: Literal["demag", "fixed"] = "demag"
    blank: float | str = "5 deg"
    blank_time: float | str | None = None
    min_pulse: float | str = "1 us"
    n_samples: int = 2
    filter_tau: float | str | None = None
    comparator_delay: float | str | None = None
    comparator_blind: bool | None = None
    timing: float | str = 0.0
    timing_time: float | str = 0.0
    timing_demag: float = 0.0
    timing_max: float | str = "30 deg"
    interval_gain: float = 0.5
    grid_gain: float = 0.0
    int_limit: float | None = None
    timeout: float = 1.5
    jump: float = 2.0
    misses: int = 0
    stall_speed: float | str | None = None
    align_time: float | str | None = None
    align_current: float | str | None = None
    align_duty: float | None = None
    ramp_start_speed: float | str | None = None
    ramp_end_speed: float | str | None = None
    ramp_time: float | str | None = None
    ramp_duty: float | None = None
    ramp_vf: float | None = None
    ramp_tau: float | str | None = None
    ramp_hold: int = 12
    handover: int = 6
    duty_min: float = 0.0
    throttle_rate: float | str | None = None
    stop_below: float = 0.0
    restart_wait: float | str = "50 ms"
    restart_max: float | str = "1 s"
    current_sensing: bool = True
    i_max: float | str | None = None
    current_limit: float | str | None = None
    current_limit_time: float | str = "1 ms"
    duty_limit_current: float | str | None = None
    start_current_limit: float | str | None = None
    demag_limit: float = 0.6
    delay: int = 0
    c_name: ClassVar[str] = "bemf"
    needs_bemf_sensing: ClassVar[bool] = True
    ref_meaning: ClassVar[str] = "duty (throttle) in [-1, 1], its sign the direction of rotation"

    def __post_init__(self) -> None:
        for name, dim in _UNITS.items():
            v = getattr(self, name)
            if isinstance(v, str):
                object.__setattr__(self, name, to_si(v, dim, f"control.{name}"))
        for name, table in (("method", _METHOD), ("chopping", _CHOP), ("blanking", _BLANK)):
            if getattr(self, name) not in table:
                raise BldclabError(f"control.{name}", f"must be one of {', '.join(table)}, got {getattr(self, name)!r}")
        for name in ("blank", "min_pulse", "timing", "timing_time", "timing_demag",
                     "timing_max", "duty_min", "stop_below", "restart_wait", "restart_max"):
            check_number(name, getattr(self, name), allow_zero=True)
        check_number("align_time", self.align_time, allow_zero=True, allow_none=True)
        check_number("ramp_time", self.ramp_time, allow_none=True)
        check_number("ramp_vf", self.ramp_vf, allow_zero=True, allow_none=True)
        check_number("ramp_tau", self.ramp_tau, allow_zero=True, allow_none=True)
        for name in ("filter_tau", "comparator_delay", "blank_time", "int_limit", "stall_speed", "align_current",
                     "ramp_start_speed", "ramp_end_speed", "i_max", "current_limit"):
            check_number(name, getattr(self, name), allow_none=True, allow_zero=name in (
                "filter_tau", "comparator_delay", "blank_time", "ramp_start_speed"))
        check_number("duty_limit_current", self.duty_limit_current, allow_zero=True, allow_none=True)
        check_number("start_current_limit", self.start_current_limit, allow_zero=True, allow_none=True)
        check_number("demag_limit", self.demag_limit, allow_zero=True)
        if self.demag_limit >= 1.0:
            raise BldclabError("control.demag_limit", f"must be in [0, 1), got {self.demag_limit!r}")
        check_number("fast_demag_after", self.fast_demag_after, allow_zero=True, allow_none=True)
        if self.fast_demag_after is not None and self.fast_demag_after >= 1.0:
            raise BldclabError("control.fast_demag_after", f"must be in [0, 1), got {self.fast_demag_after!r}")
        for name in ("current_limit_time", "interval_gain", "timeout", "jump"):
            check_number(name, getattr(self, name))
        for name in ("align_duty", "ramp_duty"):
            check_number(name, getattr(self, name), allow_zero=True, allow_none=True)
        blank, timing, timing_max = float(self.blank), float(self.timing), float(self.timing_max)  # numbers now
        if blank >= math.pi / 3.0:
            raise BldclabError("control.blank", f"must be below 60 deg (pi/3 rad), got {blank:.4g} rad")
        if timing_max > math.pi / 6.0 + 1e-12:
            raise BldclabError("control.timing_max", f"must be at most 30 deg (pi/6 rad), got {timing_max:.4g} rad")
        if timing > math.pi / 6.0 + 1e-12:
            raise BldclabError("control.timing", f"must be at most 30 deg (pi/6 rad), got {timing:.4g} rad")
        if self.interval_gain > 1.0:
            raise BldclabError("control.interval_gain", f"must be in (0, 1], got {self.interval_gain!r}")
        check_number("grid_gain", self.grid_gain, allow_zero=True)
        if self.grid_gain > 1.0:
            raise BldclabError("control.grid_gain", f"must be in [0, 1] (0: off), got {self.grid_gain!r}")
        if not 1.05 <= self.timeout <= 4.0:
            raise BldclabError("control.timeout", f"must be in [1.05, 4] crossing intervals, got {self.timeout!r}")
        if self.jump <= 1.0:
            raise BldclabError("control.jump", f"must be above 1, got {self.jump!r}")
        for name in ("align_duty", "ramp_duty", "duty_min"):
            v = getattr(self, name)
            if v is not None and v > 1.0:
                raise BldclabError(f"control.{name}", f"must be a duty in [0, 1], got {v!r}")
        if self.stop_below >= 1.0:
            raise BldclabError("control.stop_below", f"must be below 1, got {self.stop_below!r}")
        for name, lo, hi in (("n_samples", 1, 16), ("misses", 0, 100), ("ramp_hold", 1, 1_000_000),
                             ("handover", 2, 1000)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise BldclabError(f"control.{name}", f"must be an integer in [{lo}, {hi}], got {v!r}")
        if self.delay not in (0, 1) or isinstance(self.delay, bool):
            raise BldclabError("control.delay", f"must be 0 or 1 sample, got {self.delay!r}")
        if self.comparator_blind is not None and not isinstance(self.comparator_blind, bool):
            raise BldclabError("control.comparator_blind",
                               f"must be True, False or None (from the drive), got {self.comparator_blind!r}")
        if not isinstance(self.fast_demag, bool):
            raise BldclabError("control.fast_demag", f"must be True or False, got {self.fast_demag!r}")
        if not isinstance(self.current_sensing, bool):
            raise BldclabError("control.current_sensing", f"must be True or False, got {self.current_sensing!r}")
        wait, wait_max = float(self.restart_wait), float(self.restart_max)
        if wait_max < wait:
            raise BldclabError("control.restart_max", f"must be at least restart_wait ({wait:g} s), got {wait_max:g} s")
        if self.throttle_rate is not None:
            object.__setattr__(self, "throttle_rate", throttle_rate(self.throttle_rate))

    def with_delay(self, delay: int) -> SixStepSensorless:  # noqa: D102 - Control.with_delay
        return self if delay == self.delay else dataclasses.replace(self, delay=delay)

    def speeds(self, drive: Drive) -> tuple[float, float, float]:
        """Return the stall speed, the ramp's start and end speeds (mechanical rad/s) for ``drive``.

        Defaults: ``0.03 Omega_0``, 0 and ``0.1 Omega_0`` or, if higher, the ramp's free-running excess
        :func:`ramp_excess_speed`; the end speed must be at least 1.5 times the stall speed (the controller hands
        over only above 1.5 times it).
        """
        w0 = drive.Omega_0
        stall = 0.03 * w0 if self.stall_speed is None else float(self.stall_speed)
        start = 0.0 if self.ramp_start_speed is None else float(self.ramp_start_speed)
        i_al = 0.5 * drive.motor.I_N if self.align_current is None else float(self.align_current)
        end = (max(0.1 * w0, ramp_excess_speed(drive, i_al)) if self.ramp_end_speed is None
               else float(self.ramp_end_speed))
        if end < start:
            raise BldclabError("control.ramp_end_speed", f"must be at least ramp_start_speed ({start:.4g} rad/s), "
                               f"got {end:.4g} rad/s")
        if end < 1.5 * stall:
            raise BldclabError("control.ramp_end_speed", f"must be at least 1.5 stall_speed ({1.5 * stall:.4g} rad/s: "
                               f"the handover needs it), got {end:.4g} rad/s")
        return stall, start, end

    def delays(self, drive: Drive) -> tuple[float, float]:
        """Return the filter time constant and the comparator delay (s) the controller compensates for ``drive``.

        The given ``filter_tau`` and ``comparator_delay``, else the drive's sensing hardware, ``drive.sensors``'s
        ``bemf_tau`` and ``bemf_delay``.
        """
        sen = drive.sensors
        tau = sen.bemf_tau if self.filter_tau is None else float(self.filter_tau)
        t_comp = sen.bemf_delay if self.comparator_delay is None else float(self.comparator_delay)
        return tau, t_comp

    def blind(self, drive: Drive) -> bool:
        """Return whether the comparator is taken as blind in the pair's PWM off-time on ``drive`` (law 6).

        The given ``comparator_blind``, else True for the comparator method with ``sync`` or ``high`` chopping
        (the off-time holds both driven terminals at the negative rail) on an inverter with ideal diodes (``V_f =
        0`` and ``r_d = 0``: a floating terminal clamped in the off-time reads exactly the star reference).
        """
        if self.method != "comparator" or self.chopping not in ("sync", "high"):
            return False
        if self.comparator_blind is not None:
            return self.comparator_blind
        return drive.inverter.V_f == 0.0 and drive.inverter.r_d == 0.0

    def start_up(self, drive: Drive) -> dict[str, float]:
        """Return the start-up settings for ``drive``: the given ones, else the defaults derived from it.

        Returns
        -------
        dict
            ``align_current`` (A), ``align_duty``, ``align_time`` (s), ``ramp_duty``, ``ramp_vf`` (per electrical
            rad/s), ``ramp_tau`` (s), ``ramp_time`` (s), ``start_current_limit`` (A), ``diode_duty`` (the
            inverter's share :func:`inverter_share`: the duties applied are ``diode_duty + (1 - diode_duty) x`` the
            ideal inverter's duties here), and the speeds of
            :meth:`speeds` (mechanical rad/s): ``stall_speed``, ``ramp_start_speed``, ``ramp_end_speed``.
        """
        m, v, j = drive.motor, drive.inverter.V_dc, drive.mechanics.J
        i_al = 0.5 * m.I_N if self.align_current is None else float(self.align_current)
        r = r_total(drive)
        stall, start, end = self.speeds(drive)
        k = 6.0 / math.pi * m.p * m.k_phi * i_al  # stiffness of the aligning pair, N m/rad (mechanical)
        damp = 2.0 * m.k_phi ** 2 / r  # the parallel pair's loop: (2 k_phi)^2 / (2 (R + R_on)), N m s/rad
        # overdamped: the rotor creeps at (torque - load) / D; against a load up to half the static torque (the most
        # the default ramp leaves for a load) twice as slowly as unloaded: 2 x 6 time constants D / K
        # underdamped: the swing's envelope decays as exp(-(D + B) t / (2 J)); a swing of up to pi to within 15 deg
        # (a factor 12, ln 12 = 2.5)
        decay = 2.5 * 2.0 * j / (damp + drive.mechanics.B)
        t_align = 7.0 / 6.0 * min(max(3.0 * 2.0 * math.pi * math.sqrt(j / k), 12.0 * damp / k, decay, 0.01), 6.0)
        accel = 0.5 * 2.0 * m.k_phi * i_al / j  # mechanical rad/s^2
        t_ramp = min(max((end - start) / accel, 0.01), 10.0)
        return {
            "align_current": i_al,
            "align_duty": min(1.5 * r * i_al / v if self.align_duty is None else float(self.align_duty), 1.0),
            "align_time": t_align if self.align_time is None else float(self.align_time),
            "ramp_duty": min(2.0 * r * i_al / v if self.ramp_duty is None else float(self.ramp_duty), 1.0),
            "ramp_vf": 2.0 * m.k_phi / (m.p * v) if self.ramp_vf is None else float(self.ramp_vf),
            "ramp_tau": m.L / r if self.ramp_tau is None else float(self.ramp_tau),
            "start_current_limit": (2.0 * i_al if self.start_current_limit is None
                                    else float(self.start_current_limit)),
            "ramp_time": t_ramp if self.ramp_time is None else float(self.ramp_time),
            "stall_speed": stall, "ramp_start_speed": start, "ramp_end_speed": end,
            "diode_duty": inverter_share(drive, self.chopping, i_al),
        }

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        m, inv = drive.motor, drive.inverter
        p = m.p
        su = self.start_up(drive)
        stall, start, end = su["stall_speed"], su["ramp_start_speed"], su["ramp_end_speed"]
        if self.method == "comparator" and drive.sensors.bemf_reference == "half":
            raise BldclabError("control.method", "the comparator method needs the virtual star reference "
                               "(sensors.bemf_reference = 'star'): against half the bus the comparator sees the PWM "
                               "and toggles every off-time; use method='adc' or 'integration', which sample in the "
                               "on-time")
        tau, t_comp = self.delays(drive)
        blank_time = 2.0 * tau + t_comp + 1e-6 if self.blank_time is None else float(self.blank_time)
        int_limit = (integral_to_30(drive) if self.int_limit is None and
                     self.method == "integration" else float(self.int_limit or 0.0))
        i_max = 2.0 * m.I_N if self.i_max is None else float(self.i_max)
        i_limit = 0.0 if self.current_limit is None else float(self.current_limit)
        k_limit = 2.0 * r_total(drive) / (inv.V_dc * float(self.current_limit_time))
        i_dlim = m.I_N if self.duty_limit_current is None else float(self.duty_limit_current)
        return CParams(core.filled(
            "bc_bemf_params",
            method=core.const(_METHOD[self.method]),
            chop=core.const(_CHOP[self.chopping]),
            delay=self.delay,
            blanking=core.const(_BLANK[self.blanking]),
            ts=0.5 / inv.f_pwm,
            f_tick=drive.sensors.f_tick,
            blank_angle=self.blank,
            blank_time=blank_time,
            min_pulse=self.min_pulse,
            n_samples=self.n_samples,
            tau_filter=tau,
            t_comp=t_comp,
            adv_angle=self.timing,
            adv_time=self.timing_time,
            adv_demag=self.timing_demag,
            adv_max=min(float(self.timing_max), math.pi / 6.0 * (1.0 - 1e-6)),  # the C cap, below float pi/6
            t60_gain=self.interval_gain,
            grid_gain=self.grid_gain,
            int_limit=int_limit,
            zc_timeout=self.timeout,
            jump_max=self.jump,
            miss_max=self.misses,
            omega_stall=p * stall,
            align_time=su["align_time"],
            align_duty=su["align_duty"],
            ramp_w0=p * start,
            ramp_w1=p * end,
            ramp_accel=p * (end - start) / su["ramp_time"],
            ramp_duty=su["ramp_duty"],
            ramp_vf=su["ramp_vf"],
            ramp_tau=su["ramp_tau"],
            ramp_hold=self.ramp_hold,
            n_handover=self.handover,
            duty_min=self.duty_min,
            duty_rate=0.0 if self.throttle_rate is None else self.throttle_rate,
            ref_stop=self.stop_below,
            restart_wait=self.restart_wait,
            restart_max=self.restart_max,
            use_current=int(self.current_sensing),
            i_max=i_max,
            i_limit=i_limit,
            k_limit=k_limit,
            v_max=2.0 * inv.V_dc,
            fast_demag=int(self.fast_demag),
            fd_after=fast_demag_after(drive) if self.fast_demag_after is None else self.fast_demag_after,
            dlim_d0=min(2.0 * r_total(drive) * i_dlim / inv.V_dc, 1.0),
            dlim_vf=2.0 * m.k_phi / (p * inv.V_dc) if i_dlim > 0.0 else 0.0,
            dlim_tau=m.L / r_total(drive),
            demag_max=self.demag_limit,
            cmp_gate=int(drive.sensors.bemf_offset != 0.0 and self.fast_demag),
            cmp_blind=int(self.blind(drive)),
            i_start=su["start_current_limit"] if self.current_sensing else 0.0,
            d_diode=su["diode_duty"],
            brake_tau=brake_tau(drive),
            brake_acc=p * drive.mechanics.tau_c / drive.mechanics.J,
            brake_q=drive.mechanics.k_q / (p * drive.mechanics.J),
        ))

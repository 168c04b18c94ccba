"""Sinusoidal current supply of a PM BLDC motor, paper 1 section V (``core/ctrl/include/bldc/bc_sine.h``).

d,q current control on the Hall-interpolated angle (paper 1 (46)), torque reference to current by (45), current
limits that keep the modulation linear ((8), and above the base speed the largest current whose voltage fits, from
the motor's own back-EMF shapes), min-max SVM, optional back-EMF feed-forward from the
motor's shapes, square-wave start below a hand-off speed. The theory and the measurements are in ``docs/sine.md``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import ClassVar, Literal

import numpy as np

from .._core import Core, CParams
from ..errors import BldclabError
from ..model.analytic import i_sN, r_total
from ..model.design import pi_gains
from ..model.motor import Drive
from .base import Control, check_number
from .derate import ResistanceEstimate, TemperatureDerating, derate_record, rest_record
from .hall import check_hall_options, hall_record, normalize_table
from .sixstep import SixStep

__all__ = ["Sine", "fundamental_k1"]

# the settings' C constants (values read from the library: bldclab._core)
_ANGLE = {"hall": "BC_SINE_ANGLE_HALL", "pll": "BC_SINE_ANGLE_HALL", "encoder": "BC_SINE_ANGLE_ENCODER",
          "observer": "BC_SINE_ANGLE_OBSERVER"}
_OBSERVER = {"flux": "BC_SINE_OBS_FLUX", "reduced": "BC_SINE_OBS_REDUCED"}
OBSERVER_ANGLE_ERROR = math.radians(1.0)  # the PLL's lag at the rated acceleration the default bandwidth allows
ALIGN_SWEEP_K = 0.2  # bc_sine.h BC_SINE_SWEEP_K: the alignment's closing sweep speed over its swing frequency
ALIGN_RHO_HI = 0.95  # bc_sine.h BC_SINE_RHO_HI: the sweep's angle 2 asin(RHO_HI if_current / if_align_current)
_LIMIT = {"hexagon": "BC_SINE_LIMIT_HEX", "circle": "BC_SINE_LIMIT_CIRCLE"}
PAPER1_BANDWIDTH_HZ = 1000.0  # paper 1's current-loop crossover (Hz)


def fundamental_k1(drive: Drive) -> float:
    """Return the amplitude ``k_1`` of the back-EMF fundamental (V s/rad), mean over the three phases.

    For the ideal 120-degree trapezoid ``k_1 = 12/pi^2 k_phi`` (paper 1 (10)).

    Parameters
    ----------
    drive : Drive
        The drive whose back-EMF shapes are used.

    Returns
    -------
    float
        Amplitude (V s/rad).
    """
    amps = []
    for shape in drive.motor.emf.shapes:
        a, b = shape.fourier(1)
        amps.append(math.hypot(float(a[1]), float(b[1])))
    return float(np.mean(amps))


@dataclass(frozen=True)
class Sine(Control):
    """Sinusoidal current supply (paper 1): d,q PI current loops, SVM, square-wave start.

    The reference (``Scenario.ref``) is the torque in N m (or, with ``speed_loop``, ``Scenario.omega_ref`` is the
    mechanical speed in rad/s). Torque to current: ``i_q,ref = tau / (1.5 k_1)`` with ``k_1`` the back-EMF
    fundamental (paper 1 (45)); the current is limited to ``I_s,N = 2/sqrt(3) I_N`` (8) and, above the base speed,
    to the amplitude the bus can impress in linear modulation, computed by the controller from the motor's back-EMF
    shapes (the feed-forward's tables): paper 1's (23) with R on the ideal trapezoid, the quadrature sum on a
    sinusoidal back-EMF (``docs/sine.md``, section 4).

    Parameters
    ----------
    angle : {"hall", "pll", "encoder", "observer"}
        Angle for the d,q transforms: the Hall-interpolated angle (paper 1 (46)), a tracking loop on the Hall edges
        (``pll``: averages the edge errors of misplaced sensors, time constant ``pll_edges`` edges; its speed is
        used too, ``docs/hall-calibration.md``), the encoder (an ideal reference for comparison; the speed then
        comes from the Hall sensors), or a rotor-angle observer without any position sensor (``observer``: angle
        and speed from the voltages and currents, I/f start-up instead of the square wave, ``docs/sensorless-sine.md``).
    observer : {"flux", "reduced"}
        With ``angle="observer"``: the nonlinear flux observer with a PLL of Lee, Hong, Nam, Ortega, Praly and
        Astolfi (IEEE TPEL 2010; ``bc_fluxobs.h``), or the reduced-order observer of Hinkkanen et al. (IEEE TIA
        2018; ``bc_redobs.h``).
    observer_gain : float, optional
        Flux observer: radial convergence rate ``lambda`` (rad/s). Default ``2 omega_on`` (twice the electrical
        hand-off speed, at most ``0.05 / T_s``).
    observer_bandwidth : float, optional
        Bandwidth of the observer's speed tracking (the flux observer's PLL ``omega_p``, the reduced observer's
        ``alpha_o``), rad/s. Default: the angle lags a constant acceleration by ``a / omega_p^2``; the bandwidth that
        keeps this lag at 1 deg electrical for the rated torque accelerating the drive's inertia alone,
        ``sqrt(p T_s,N / (J 1 deg))``, within ``[4 omega_on, 0.05 / T_s]``.
    if_current : float, optional
        Current amplitude of the I/f start-up (A), default ``0.5 I_s,N``; at most ``I_s,N``.
    if_accel : float, optional
        Mechanical acceleration of the I/f ramp (rad/s^2). Default: half the I/f torque ``1.5 k_1 if_current``
        accelerating the inertia ``J``, but at most the acceleration whose start and end excite a swing of the rotor
        about the current vector of 10 % of the hand-off speed (``0.1 omega_on omega_n``, ``omega_n`` below). The
        ramp's largest acceleration: the ramp adapts to the load (``bc_sine.h``, RAMP), full while the rotor's
        torque (read from the observer) is at most 60 % of the I/f torque, none at 95 %, the vector waiting for the
        rotor above that.
    if_accel_min : float, optional
        The load-adaptive ramp's slowest mean acceleration (rad/s^2, mechanical), at most ``if_accel``; default
        ``if_accel / 20``: a ramp that takes longer than ``omega_on / if_accel_min + t_sw`` (from its lowest speed,
        if it followed a rotor pushed back: ``(omega_on - omega_low) / if_accel_min + t_sw``; ``t_sw = (pi / 2) /
        w_cr`` the creep's sweep to the breakaway angle of a rotor held at rest, at the creep speed ``w_cr =
        min(0.05 omega_on, sqrt(2 p if_accel_min))`` (electrical: a rotor breaking away against a load at the
        design bound catches the vector, whatever its inertia); whatever that lowest
        speed, one that has turned backwards for ``omega_on / if_accel_min`` in all or been below ``omega_on`` for
        ``2 omega_on / if_accel_min + t_sw``) ends in ``START_FAIL``. The
        start is designed for a load ``tau_L / tau_if <= 0.95 - 0.35 if_accel_min / if_accel - J if_accel_min /
        tau_if`` (``tau_if = 1.5 k_1 if_current``; docs/sensorless-sine.md). ``if_accel_min = if_accel``: the
        fixed ramp at ``if_accel``, no adaptation.
    if_align_current : float, optional
        Current amplitude of the alignment before the ramp (A), default ``0.9 I_s,N`` (at least ``if_current``, at
        most ``i_s_max``); at most the current limit ``i_s_max``. A load that holds the rotor (friction) leaves it
        within ``asin(tau_L / (1.5 k_1 if_align_current))`` of the angle the observer is seeded with; the rest of the
        current limit brakes the swing.
    if_align : float, optional
        Time the I/f current vector is held still before the ramp (s). Default three periods of the rotor's
        oscillation about the vector, ``2 pi / sqrt(p 1.5 k_1 if_current / J)`` each.
    if_r_estimate : bool
        The observers use the resistance the alignment measures (``sum u.i / sum i.i`` over its last quarter, the
        rotor at rest: the voltage is ``R i``), not the drive data's; kept from the ramp until the next alignment,
        the configured R where the measurement is implausible (outside ``[R/4, 4 R]``). A wrong R biases the
        observer most at low speed, where the load-adaptive ramp reads it. Default ``False`` (the drive data's R):
        measured on the catalog drives to 0.002-2 % with the rotor at rest, it mends R off by 50 % on every catalog
        drive, but a rotor that moves in the window (an active load, a heavy rotor's swing) biases it and the
        start-up map loses starts within its design bound (docs/sensorless-sine.md, "The resistance measured at the
        alignment").
    if_flux_estimate : bool
        The flux observer's flux linkage read at zero current: when, at the top of the I/f ramp, the observer is
        consistent (tracking error and speed) but its flux is off the configured ``psi_f`` by more than half the lock
        band for two lock times, the current loops hold ``i = 0`` for about a lock time and a whole turn (the
        vector turning on), and the flux linkage is the back-EMF they then apply over the angle it turns, ``psi =
        sum |u| T_s / angle`` (``R i`` and ``L di/dt`` are zero: neither a wrong R nor a wrong L enters it); taken
        within ``[psi_f / 2, 2 psi_f]`` when it differs from the one in use by more than half the lock band, once a
        start, kept until the next alignment; the lock then checks against it. With the current on, a wrong L alone
        moves the observer's flux by ``(L_c - L) i_d`` (the I/f current of an unloaded rotor lies on its d axis),
        which the reading confirms as no flux error. Default ``True``; ``False``: a flux out of band ends the start in
        ``START_FAIL``. No effect with ``observer="reduced"`` (docs/sensorless-sine.md, "Wrong parameters at the
        start").
    catch_zero_current : bool
        Each alignment (until a turning rotor is caught) starts with ``3 lock_time`` at zero current: the current
        loops in the observer's frame hold ``i = 0`` (with the back-EMF feed-forward), so that the voltage is the
        back-EMF of a rotor already turning and the observer locks on it without the alignment current's torque
        pulsating on the slipping rotor (a flying start); no catch in that time, the alignment as usual. Default
        ``False`` (the catch with the alignment's current on): on the flying-start map it catches rotors at about
        twice the hand-off speed that the alignment's current holds, but at the no-load speed, with no voltage to
        spare while the observer pulls in, it can trip the over-current guard (docs/sensorless-sine.md, "Catch",
        "Flying-start map").
    catch_pulse : bool
        Each alignment starts with two zero-vector pulses read by the current sensors, legs off before and after
        (6 samples): a pulse of length ``tau = L (I_s,N / 3) / e_top`` (``e_top`` the back-EMF at 1.25 times the
        no-load speed) ending at a sample; the current it drives, ``L di/dt = -(e + R i)``, gives the back-EMF vector,
        its turn over the ``3 T_s`` between the pulses the speed. A rotor found turning at least at the hand-off
        speed seeds the observer (angle, speed) and is caught at zero current (as ``catch_zero_current``), so the
        first voltage applied balances its back-EMF instead of short-circuiting it; otherwise the start goes on as
        without. Default ``True`` (docs/sensorless-sine.md, "Catch", "Zero-vector pulses").
    lock_tolerance : float
        Band of the lock criterion (-), in (0, 1): the observer's flux within it of ``psi_f`` (relative) and its
        tracking error within it (rad) for the hand-off; its flux out of it too long is a lost lock.
    restart_wait : float
        Legs off after a failed start or a lost lock before the next start (s).
    pll_edges : float
        Time constant of the tracking loop in Hall edges (1 .. 1000).
    hall_table : sequence of float, optional
        Calibrated Hall edge angles (rad, electrical): 6 (both directions) or 12 (forward, then backward), e.g.
        from :func:`bldclab.sim.hallcal.calibrate`; also passed to the square-wave start unless it has its own.
        ``None``: the nominal edges ``pi/6 + j pi/3``.
    emf_feedforward : bool
        Add the back-EMF ``omega_m k_x(theta)`` from the motor's own shapes (tables of ``emf_points`` points) to the
        phase voltage references, so the trapezoid's harmonics do not distort the currents.
    advance : float
        Voltage angle advance in samples (half PWM periods): 1.5 compensates one sample of computation delay and
        half a sample of PWM; 0 switches the compensation off.
    limit : {"hexagon", "circle"}
        Linear-modulation limit: the whole linear range of min-max SVM (line voltages <= ``V_dc``), or its
        inscribed circle ``|v_alpha,beta| <= V_dc / sqrt(3)``.
    overmodulation : bool
        Explicit overmodulation: no linear limit, the duties clip.
    speed_limit : bool
        Reduce the current amplitude above the base speed to the largest whose steady-state voltage
        ``R i + L di/dt + e`` stays in the linear range over the whole period, from the drive's back-EMF shapes
        (paper 1's (23) with R on the ideal trapezoid). The C controller computes, at init, the voltage this current
        needs from 96 angles of the shapes on a grid of speeds and currents, and each sample interpolates it
        (never above the 96-angle scan; ``docs/sine.md``, section 4). Off: the current stays at the reference and
        the voltage limit does the rest (for measuring the base speed).
    decoupling : bool
        Add the R-L voltages ``R i_ref + omega_e L J i`` to the PI outputs, the rotational part from the *measured*
        currents: it cancels the d,q cross-coupling of the motor, so each PI sees ``R + s L`` at any speed. Off, a
        PI whose ``k_p`` is small against ``omega_e L`` leaves a slow, lightly damped mode (``docs/sine.md``).
    bandwidth_hz : float, optional
        Current-loop crossover (Hz). Default: paper 1's 1 kHz, lowered to ``f_pwm / 10`` on a drive whose carrier
        is slower than 10 kHz (the loop delay of 1.5 samples then costs 27 deg of phase margin at most). Given,
        it is used as is.
    phase_margin_deg : float
        Current-loop phase margin (paper 1: 90 deg), :func:`bldclab.model.design.pi_gains` without delay.
    R_design : float, optional
        Resistance (Ohm) the PI gains are designed for. Default: the drive's ``R + R_on``, but at least
        ``omega_c L / 10``: the 90-degree design cancels the R-L pole (``k_i = omega_c R``), so with a small R
        the integral action would vanish (R = 0: none at all, and a steady error of about 1 % of the current
        remains); the floor puts the PI zero a decade below the crossover (phase margin 84 deg). Given
        explicitly, it is used as is. The controller's model (limits, decoupling, hand-off) always uses the
        drive's ``R + R_on``.
    handoff_speed : float, optional
        Mechanical speed (rad/s) above which the sinusoidal supply takes over from the square-wave start; default
        ``0.1 Omega_N`` (paper 1, V.B).
    handoff_hysteresis : float
        Fraction of ``handoff_speed`` below it at which the drive returns to the square-wave start (-), in [0, 1).
    i_max : float, optional
        Over-current trip (A); default ``2 I_N``.
    i_s_max : float, optional
        Current limit: the largest current amplitude the controller asks for (A), default paper 1's
        ``I_s,N = 2/sqrt(3) I_N`` (8), the amplitude of a sinusoid with the rated square wave's rms. A drive's short-
        time rating (a 60 s envelope, :func:`bldclab.analysis.thermal.envelope`) raises it; at most ``i_max`` (the
        trip would cut it off). The speed limit, the speed loop's default ``tau_max`` and the square-wave start's
        torque clamp follow it.
    emf_points : int
        Points per back-EMF table (uniform over one electrical period; a multiple of 12 holds the corners of a
        120-degree trapezoid).
    speed_loop : bool
        Outer speed PI on the Hall speed; the torque reference becomes its output.
    speed_bandwidth_hz : float
        Crossover of the speed loop (Hz) for the default gains: ``k_p = J omega_b``, ``k_i = k_p omega_b / 4``
        (``omega_b = 2 pi speed_bandwidth_hz``, ``J`` of the drive's mechanics; phase margin 76 deg).
    speed_kp, speed_ki : float, optional
        Speed PI gains (N m s/rad, N m/rad), overriding the defaults.
    tau_max : float, optional
        Torque limit of the speed loop (N m); default ``T_s,N`` (12).
    start : SixStep
        The square-wave start below the hand-off speed (:class:`~bldclab.control.SixStep`, composed: its own
        settings; its ``reference`` is set to ``"torque"``, since the sine supply passes it the torque reference).
    flying_start : bool
        Coast (legs off) in the start mode until the rotor is known to be slower than the hand-off speed (a valid
        Hall speed below it, or no Hall edge for the time the rotor takes for 60 electrical degrees at that
        speed). For runs that enable the drive on a rotor already turning fast (a dynamometer at imposed speed),
        so that the sine mode takes over after two Hall edges without square-wave braking at high speed.
    derate : TemperatureDerating, optional
        Derate the current limit ``I_s,N`` with the temperature inputs (firmware derating,
        :mod:`bldclab.control.derate`; the square-wave start too, unless ``start`` has its own); ``None``: none.
    r_estimate : ResistanceEstimate, optional
        Measure the winding resistance during operation by a square wave of d-axis current in the sine mode
        (:class:`~bldclab.control.derate.ResistanceEstimate`, ``bc_rest.h``); without a winding sensor its
        temperature is the derating's winding input. ``None``: no injection (``i_d,ref = 0``).
    """

    angle: Literal["hall", "pll", "encoder", "observer"] = "hall"
    pll_edges: float = 3.0
    hall_table: tuple[float, ...] | None = None
    emf_feedforward: bool = True
    decoupling: bool = True
    advance: float = 1.5
    limit: Literal["hexagon", "circle"] = "hexagon"
    overmodulation: bool = False
    speed_limit: bool = True
    bandwidth_hz: float | None = None
    phase_margin_deg: float = 90.0
    R_design: float | None = None
    handoff_speed: float | None = None
    handoff_hysteresis: float = 0.2
    i_max: float | None = None
    i_s_max: float | None = None
    emf_points: int = 360
    speed_loop: bool = False
    speed_bandwidth_hz: float = 5.0
    speed_kp: float | None = None
    speed_ki: float | None = None
    tau_max: float | None = None
    start: SixStep = field(default_factory=lambda: SixStep(reference="torque"))
    flying_start: bool = False
    observer: Literal["flux", "reduced"] = "flux"
    observer_gain: float | None = None
    observer_bandwidth: float | None = None
    if_current: float | None = None
    if_accel: float | None = None
    if_accel_min: float | None = None
    if_align: float | None = None
    if_align_current: float | None = None
    if_r_estimate: bool = False
    if_flux_estimate: bool = True
    catch_zero_current: bool = False
    catch_pulse: bool = True
    lock_tolerance: float = 0.2
    restart_wait: float = 0.1
    derate: TemperatureDerating | None = None
    r_estimate: ResistanceEstimate | None = None
    c_name: ClassVar[str] = "sine"
    ref_meaning: ClassVar[str] = "torque, N m"

    def __post_init__(self) -> None:
        if self.derate is not None and not isinstance(self.derate, TemperatureDerating):
            raise BldclabError("control.derate", f"must be a TemperatureDerating, got {type(self.derate).__name__}")
        if self.r_estimate is not None and not isinstance(self.r_estimate, ResistanceEstimate):
            raise BldclabError("control.r_estimate", f"must be a ResistanceEstimate, got "
                               f"{type(self.r_estimate).__name__}")
        if self.angle not in _ANGLE:
            raise BldclabError("control.angle", f"must be one of {', '.join(_ANGLE)}, got {self.angle!r}")
        check_hall_options(self.pll_edges)
        object.__setattr__(self, "hall_table", normalize_table(self.hall_table))
        if self.limit not in _LIMIT:
            raise BldclabError("control.limit", f"must be one of {', '.join(_LIMIT)}, got {self.limit!r}")
        for name in ("emf_feedforward", "decoupling", "overmodulation", "speed_limit", "speed_loop", "flying_start"):
            if not isinstance(getattr(self, name), bool):
                raise BldclabError(f"control.{name}", f"must be True or False, got {getattr(self, name)!r}")
        check_number("advance", self.advance, allow_zero=True)
        if self.advance > 4:
            raise BldclabError("control.advance", f"must be within [0, 4] samples, got {self.advance!r}")
        if self.bandwidth_hz is not None:
            check_number("bandwidth_hz", self.bandwidth_hz)
        check_number("phase_margin_deg", self.phase_margin_deg)
        for name in ("R_design", "handoff_speed", "i_max", "i_s_max", "tau_max"):
            v = getattr(self, name)
            if v is not None:
                check_number(name, v, allow_zero=name == "R_design")
        check_number("handoff_hysteresis", self.handoff_hysteresis, allow_zero=True)
        if self.handoff_hysteresis >= 1:
            raise BldclabError("control.handoff_hysteresis", f"must be in [0, 1), got {self.handoff_hysteresis!r}")
        if isinstance(self.emf_points, bool) or not isinstance(self.emf_points, int) or not 3 <= self.emf_points \
                <= 4096:
            raise BldclabError("control.emf_points", f"must be an integer in [3, 4096], got {self.emf_points!r}")
        if not isinstance(self.start, SixStep):
            raise BldclabError("control.start", f"must be a bldclab.SixStep, got {type(self.start).__name__}")
        check_number("speed_bandwidth_hz", self.speed_bandwidth_hz)
        if self.observer not in _OBSERVER:
            raise BldclabError("control.observer", f"must be one of {', '.join(_OBSERVER)}, got {self.observer!r}")
        for name in ("observer_gain", "observer_bandwidth", "if_current", "if_accel", "if_accel_min", "if_align",
                     "if_align_current"):
            if getattr(self, name) is not None:
                check_number(name, getattr(self, name), allow_zero=name == "if_align")
        if not isinstance(self.if_r_estimate, bool):
            raise BldclabError("control.if_r_estimate", f"must be True or False, got {self.if_r_estimate!r}")
        if not isinstance(self.if_flux_estimate, bool):
            raise BldclabError("control.if_flux_estimate", f"must be True or False, got {self.if_flux_estimate!r}")
        if not isinstance(self.catch_zero_current, bool):
            raise BldclabError("control.catch_zero_current",
                               f"must be True or False, got {self.catch_zero_current!r}")
        if not isinstance(self.catch_pulse, bool):
            raise BldclabError("control.catch_pulse", f"must be True or False, got {self.catch_pulse!r}")
        check_number("lock_tolerance", self.lock_tolerance)
        if self.lock_tolerance >= 1:
            raise BldclabError("control.lock_tolerance", f"must be in (0, 1), got {self.lock_tolerance!r}")
        check_number("restart_wait", self.restart_wait, allow_zero=True)
        for name in ("speed_kp", "speed_ki"):
            if getattr(self, name) is not None:
                check_number(name, getattr(self, name), allow_zero=True)

    def gains(self, drive: Drive) -> tuple[float, float]:
        """Return the d,q current PI gains ``(k_p, k_i)`` (V/A, V/(A s)) for a drive.

        Parameters
        ----------
        drive : Drive
            Uses its inductance and resistance (or ``R_design``).

        Returns
        -------
        tuple of float
            ``k_p`` (V/A) and ``k_i`` (V/(A s)).
        """
        return pi_gains(self._r_design(drive, 1.0), drive.motor.L, self.bandwidth(drive), self.phase_margin_deg)

    def bandwidth(self, drive: Drive) -> float:
        """Return the current-loop crossover (Hz) for a drive.

        Parameters
        ----------
        drive : Drive
            Uses its carrier frequency when ``bandwidth_hz`` is not given.

        Returns
        -------
        float
            ``bandwidth_hz`` if given, else ``min(1000, f_pwm / 10)`` (Hz).
        """
        if self.bandwidth_hz is not None:
            return float(self.bandwidth_hz)
        return min(PAPER1_BANDWIDTH_HZ, drive.inverter.f_pwm / 10.0)

    def torque_limit(self, drive: Drive) -> float:
        """Return the speed loop's torque limit (N m): ``tau_max``, default ``1.5 k_1 i_s_max`` (paper 1 (12)).

        Parameters
        ----------
        drive : Drive
        """
        return 1.5 * fundamental_k1(drive) * self.current_limit(drive) if self.tau_max is None else float(self.tau_max)

    def current_limit(self, drive: Drive) -> float:
        """Return the current limit (A): ``i_s_max``, default ``I_s,N = 2/sqrt(3) I_N`` (paper 1 (8)).

        Parameters
        ----------
        drive : Drive

        Raises
        ------
        BldclabError
            ``control.i_s_max`` above the over-current trip ``i_max``.
        """
        i_s = i_sN(drive) if self.i_s_max is None else float(self.i_s_max)
        trip = 2.0 * drive.motor.I_N if self.i_max is None else float(self.i_max)
        if i_s > trip:
            raise BldclabError("control.i_s_max", f"must be at most the over-current trip i_max = {trip:.4g} A "
                               f"(raise i_max with it), got {i_s:.4g} A")
        return i_s

    def handoff(self, drive: Drive) -> float:
        """Return the hand-off speed (mechanical rad/s): ``handoff_speed``, default ``0.1 Omega_N``."""
        return 0.1 * drive.motor.Omega_nominal if self.handoff_speed is None else float(self.handoff_speed)

    def sensorless_settings(self, drive: Drive) -> dict[str, float]:
        """Return the observer's and the I/f start-up's settings for a drive, defaults filled in.

        Parameters
        ----------
        drive : Drive
            The drive the controller believes in (its estimate): its R, L, back-EMF fundamental, inertia, rated
            current and carrier.

        Returns
        -------
        dict of str to float
            ``psi`` (V s, ``k_1 / p``), ``gain`` (``lambda``, rad/s), ``bandwidth`` (rad/s), ``sigma0`` (rad/s),
            ``if_current`` and ``if_align_current`` (A), ``if_accel`` and ``if_accel_min`` (electrical rad/s^2),
            ``if_align`` (s), ``if_damp`` (A/V, the swing damping ``omega_n J / (1.5 p^2 psi_f^2)``), ``lock_time``
            (s), ``if_hold`` (s) and ``if_sweep`` (s, the alignment's closing sweep: the vector turned forwards by
            ``2 asin(min(0.95 if_current / if_align_current, 1))`` at a fifth of the swing frequency at
            ``if_align_current``, ``w_a = (6 pi / if_align) sqrt(if_align_current / if_current)``; 0 without an
            alignment).
        """
        m = drive.motor
        ts = 0.5 / drive.inverter.f_pwm
        k1 = fundamental_k1(drive)
        w_on = m.p * self.handoff(drive)
        w_hi = 0.05 / ts
        gain = min(2.0 * w_on, w_hi) if self.observer_gain is None else float(self.observer_gain)
        accel = m.p * 1.5 * k1 * i_sN(drive) / drive.mechanics.J  # electrical rad/s^2 at T_s,N
        bw = (min(max(math.sqrt(accel / OBSERVER_ANGLE_ERROR), 4.0 * w_on), w_hi)
              if self.observer_bandwidth is None else float(self.observer_bandwidth))
        i_if = 0.5 * i_sN(drive) if self.if_current is None else float(self.if_current)
        tau_if = 1.5 * k1 * i_if
        w_n = math.sqrt(m.p * tau_if / drive.mechanics.J)
        a_if = (min(m.p * 0.5 * tau_if / drive.mechanics.J, 0.1 * w_on * w_n) if self.if_accel is None
                else m.p * float(self.if_accel))
        i_al = max(0.9 * i_sN(drive), i_if) if self.if_align_current is None else float(self.if_align_current)
        a_min = a_if / 20.0 if self.if_accel_min is None else m.p * float(self.if_accel_min)
        align = 3.0 * 2.0 * math.pi / w_n if self.if_align is None else float(self.if_align)
        lock_time = 5.0 / min(gain, bw)
        # i_d = -k u_d brakes the alignment swing at the rate 1.5 p^2 psi^2 k / J: made w_n (near critical damping)
        damp = w_n * drive.mechanics.J / (1.5 * m.p**2 * (k1 / m.p) ** 2)
        # bc_sine.h, ALIGN: the closing sweep, beta at w_s = BC_SINE_SWEEP_K w_a
        w_a = 6.0 * math.pi / align * math.sqrt(i_al / i_if) if align > 0.0 else 0.0
        beta = 2.0 * math.asin(min(ALIGN_RHO_HI * i_if / i_al, 1.0))
        sweep = beta / (ALIGN_SWEEP_K * w_a) if w_a > 0.0 else 0.0
        return {"psi": k1 / m.p, "gain": gain, "bandwidth": bw,
                "sigma0": min(r_total(drive) / (2.0 * m.L), 0.2 / ts), "if_current": i_if, "if_accel": a_if,
                "if_accel_min": a_min, "if_align_current": i_al,
                "if_align": align, "if_damp": damp, "lock_time": lock_time,
                "if_hold": max(20.0 * lock_time, 10.0 * 2 * math.pi / w_on), "if_sweep": sweep}

    def _observer_records(self, drive: Drive, core: Core, i_max: float) -> dict[str, object]:
        """Return the sensorless members of ``bc_sine_params``."""
        m, inv = drive.motor, drive.inverter
        ts = 0.5 / inv.f_pwm
        st = self.sensorless_settings(drive)
        i_lim = self.current_limit(drive)
        if self.angle == "observer" and st["if_accel_min"] > st["if_accel"] * (1.0 + 1e-9):
            raise BldclabError("control.if_accel_min", f"must be at most if_accel = {st['if_accel'] / m.p:.4g} "
                               f"rad/s^2, got {st['if_accel_min'] / m.p:.4g} rad/s^2")
        if self.angle == "observer" and st["if_current"] > i_lim:
            raise BldclabError("control.if_current", f"must be at most the current limit i_s_max = "
                               f"{i_lim:.4g} A, got {st['if_current']:.4g} A")
        if self.angle == "observer" and self.if_align_current is not None and st["if_align_current"] > i_lim:
            raise BldclabError("control.if_align_current", f"must be at most the current limit i_s_max = "
                               f"{i_lim:.4g} A, got {st['if_align_current']:.4g} A")
        common = {"R": r_total(drive), "L": m.L, "psi": st["psi"], "ts": ts, "i_max": i_max, "v_max": 2.0 * inv.V_dc}
        fobs = core.filled("bc_fluxobs_params", gain=st["gain"], pll_bw=st["bandwidth"], **common)
        robs = core.filled("bc_redobs_params", alpha_o=st["bandwidth"], sigma0=st["sigma0"], zeta_inf=0.2, **common)
        return {"observer": core.const(_OBSERVER[self.observer]), "fobs": fobs[0], "robs": robs[0],
                "if_current": st["if_current"], "if_align": st["if_align"],
                "if_align_current": min(st["if_align_current"], i_lim),
                "if_accel": st["if_accel"], "if_accel_min": min(st["if_accel_min"], st["if_accel"]),
                "if_hold": st["if_hold"], "lock_time": st["lock_time"],
                "lock_tol": self.lock_tolerance, "restart_wait": self.restart_wait, "if_damp": st["if_damp"],
                "t_dead": inv.t_dead, "if_r_est": int(self.if_r_estimate),
                "if_psi_est": int(self.if_flux_estimate), "zc_catch": int(self.catch_zero_current),
                "catch_pulse": int(self.catch_pulse)}

    def _r_design(self, drive: Drive, scale: float) -> float:
        """Design resistance of a loop of ``scale`` phases in series (Ohm)."""
        if self.R_design is not None:
            return scale * float(self.R_design)
        wc = 2.0 * math.pi * self.bandwidth(drive)
        return scale * max(r_total(drive), wc * drive.motor.L / 10.0)

    def describe(self) -> dict[str, object]:  # noqa: D102
        out = super().describe()
        out["start"] = self.start.describe()
        return out

    def with_delay(self, delay: int) -> Control:  # noqa: D102 - Control.with_delay: the square-wave start's delay
        return self if delay == self.start.delay else dataclasses.replace(self, start=self.start.with_delay(delay))

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        m, inv, sen = drive.motor, drive.inverter, drive.sensors
        kp, ki = self.gains(drive)
        k1 = fundamental_k1(drive)
        th = np.arange(self.emf_points) * (2.0 * math.pi / self.emf_points)
        tabs = [np.ascontiguousarray(shape(th), dtype=np.float32) for shape in m.emf.shapes]
        on = self.handoff(drive)
        i_max = 2.0 * m.I_N if self.i_max is None else self.i_max
        start = self.start if self.start.reference == "torque" else dataclasses.replace(self.start, reference="torque")
        if start.hall_table is None and self.hall_table is not None:
            start = dataclasses.replace(start, hall_table=self.hall_table)
        if self.derate is not None and start.derate is None:
            start = dataclasses.replace(start, derate=self.derate)  # the square-wave start derates alike
        six = start.c_record(drive, core, n_samples)
        wb = 2.0 * math.pi * self.speed_bandwidth_hz
        kp_w = drive.mechanics.J * wb if self.speed_kp is None else self.speed_kp
        rec = core.filled(
            "bc_sine_params",
            p=m.p,
            R=r_total(drive),
            L=m.L,
            k_phi=m.k_phi,
            k_1=k1,
            ts=0.5 / inv.f_pwm,
            kp=kp,
            ki=ki,
            v_max=2.0 * inv.V_dc,
            i_s_max=self.current_limit(drive),
            i_max=i_max,
            speed_limit=int(self.speed_limit),
            decouple=int(self.decoupling),
            advance=self.advance,
            limit=core.const(_LIMIT[self.limit]),
            overmod=int(self.overmodulation),
            emf_ff=int(self.emf_feedforward),
            emf_n=self.emf_points,
            emf_k=[t.ctypes.data for t in tabs],
            angle=core.const(_ANGLE[self.angle]),
            f_tick=sen.f_tick,
            omega_on=m.p * on,
            omega_off=m.p * on * (1.0 - self.handoff_hysteresis),
            omega_min=0.25 * m.p * on * (1.0 - self.handoff_hysteresis),  # Hall speed valid well below omega_off
            theta_offset=0.0,
            **hall_record(core, self.angle == "pll", self.pll_edges, self.hall_table),
            derate=derate_record(core, self.derate, 0.5 / inv.f_pwm),
            rest=rest_record(core, self.r_estimate, 0.5 / inv.f_pwm, r_total(drive),
                             drive.thermal.T_ref if drive.thermal is not None else 25.0, self.current_limit(drive)),
            six=six.record[0],
            flying_start=int(self.flying_start),
            speed_loop=int(self.speed_loop),
            kp_w=kp_w,
            ki_w=kp_w * wb / 4.0 if self.speed_ki is None else self.speed_ki,
            tau_max=self.torque_limit(drive),
            **self._observer_records(drive, core, i_max),
        )
        return CParams(rec, [*tabs, six])

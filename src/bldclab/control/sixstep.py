"""Real square-wave (120-degree) current-controlled supply, paper 1 section IV.A (``bc_sixstep.h``).

The C controller is ``core/ctrl/include/bldc/bc_sixstep.h``.

Hall commutation with the outgoing phase left to freewheel through its diode, the current of the incoming phase
regulated by a PI, a hysteresis band or a predictive ("deadbeat") law, with a selectable chopping pattern. The
theory, the design of the predictive law and the measurements against paper 1 are in ``docs/sixstep.md``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar, Literal

from .._core import Core, CParams
from ..errors import BldclabError
from ..model.analytic import r_total
from ..model.design import pi_gains
from ..model.motor import Drive
from ..model.units import to_si
from .base import Control, check_number
from .derate import TemperatureDerating, derate_record
from .hall import check_hall_options, hall_record, normalize_table

__all__ = ["CHOPPINGS", "COMMUTATIONS", "REGULATIONS", "SixStep"]

# the settings' C constants (values read from the library: bldclab._core)
_REG = {"pi": "BC_SIXSTEP_PI", "hysteresis": "BC_SIXSTEP_HYST", "predictive": "BC_SIXSTEP_PRED",
        "duty": "BC_SIXSTEP_DUTY", "ideal": "BC_SIXSTEP_IDEAL"}
_COMM = {"hall": "BC_SIXSTEP_COMM_HALL", "encoder": "BC_SIXSTEP_COMM_ENCODER"}
_CHOP = {"bipolar": "BC_SIXSTEP_BIPOLAR", "high": "BC_SIXSTEP_HIGH", "pwm-on-pwm": "BC_SIXSTEP_PWMPWM",
         "sync": "BC_SIXSTEP_SYNC"}
_REF = {"current": 0, "torque": 1}  # ref_torque, a 0/1 switch

#: The chopping patterns of :class:`SixStep` (its ``chopping`` field).
CHOPPINGS: tuple[str, ...] = tuple(_CHOP)
#: The regulations of :class:`SixStep` (its ``regulation`` field).
REGULATIONS: tuple[str, ...] = ("predictive", "pi", "hysteresis", "duty", "ideal")
#: Where :class:`SixStep` takes its commutation instants from (its ``commutation`` field).
COMMUTATIONS: tuple[str, ...] = tuple(_COMM)


@dataclass(frozen=True)
class SixStep(Control):
    """Real square-wave current supply: Hall commutation, 120-degree conduction, current regulation.

    The reference (``Scenario.ref``) is the current amplitude ``I`` in A (``reference="current"``) or the torque in
    N m (``reference="torque"``, converted to ``I = tau / (2 k_phi)``, paper 1 (6)); with ``regulation="duty"`` it
    is the duty in [-1, 1] (an ESC's throttle). A negative reference reverses the torque (the two conducting phases
    swap roles).

    Parameters
    ----------
    regulation : {"predictive", "pi", "hysteresis", "duty", "ideal"}
        ``predictive``: the duty that brings the incoming phase's current to the reference at the sample after next,
        from an average model of the inverter and motor (full voltage when it cannot: paper 1's idealisation);
        ``pi``: PI on the line current with back-EMF feed-forward, gains from :func:`bldclab.model.design.pi_gains` for
        the line ``2 R``, ``2 L``; ``hysteresis``: on below ``I - band/2``, off above ``I + band/2`` at the samples;
        ``duty``: no current loop, the reference is the duty (voltage mode, as a hobby ESC's throttle); ``ideal``:
        paper 1's ideal current limiter, a reference model on the averaged inverter (``Inverter(model="average")``,
        no source resistance): the incoming phase's current is held at the reference in continuous time while a
        duty in [0, 1] can hold it, driven at full voltage toward it otherwise (docs/sixstep.md, "The ideal current
        limiter"). Use it with ``commutation="encoder", timed=True`` for commutation at the exact angles.
    chopping : {"pwm-on-pwm", "bipolar", "high", "sync"}
        ``pwm-on-pwm``: a phase chops in the first and last 30 degrees of its conduction and is fully on in the
        middle 60 (the pattern that realises paper 1's commutation); ``bipolar``: both conducting legs chop;
        ``high``: the positive phase's upper switch chops, the negative phase's lower switch stays on; ``sync``: as
        ``high`` with a complementary (synchronous) positive leg.
    reference : {"current", "torque"}
        Meaning of ``Scenario.ref``.
    delay : int
        Samples between computing and applying an output, 0 or 1 (the predictive law predicts over it);
        :func:`bldclab.simulate` sets it from ``Scenario.delay``.
    advance : bool
        Commutate at the sample nearest the Hall edge predicted from the Hall speed, instead of on the edge seen
        (which is on average 1.5 samples late with ``delay = 1``).
    timed : bool
        Commutate at the predicted instant itself, inside the PWM period, as an ESC's commutation timer does
        (``bc_ctrl_out.has_at``), instead of at the sample nearest it. At a few PWM periods per commutation (a drone
        motor at 30,000 rpm) the sample grid alone commutates up to half a sample late or early.
    timing : float or str
        Timing advance at any speed (electrical rad, or a string such as ``"15 deg"``): every commutation this much
        earlier than the nominal sector boundary.
    timing_time : float or str
        Timing advance per speed (s, or ``"20 us"``): the advance angle grows by ``|Omega_e| timing_time``,
        compensating a fixed delay. The total advance is capped at 30 degrees.
    commutation : {"hall", "encoder"}
        Where the commutation instants come from: the Hall sensors, or the encoder's exact angle and speed (the
        ideal instant, a reference to measure the Hall drive against).
    bandwidth_hz, phase_margin_deg : float
        PI design (paper 1: 1 kHz, 90 deg) for the line R-L ``(2 R, 2 L)``, used when ``kp``/``ki`` are not given.
    kp, ki : float, optional
        PI gains (V/A, V/(A s)) overriding the design.
    emf_feedforward : bool
        PI: add the line back-EMF estimate and ``2 R I`` to the PI output.
    regen : bool
        Let the unipolar patterns (``pwm-on-pwm``, ``high``, ``sync``) reach negative pair voltages by switching
        both legs as ``bipolar`` does, when the regulation asks for one. Without it their lowest voltage is 0
        (freewheeling, which short-circuits the line back-EMF): a braking current cannot be held once the line
        back-EMF exceeds ``2 R I``, and the hysteresis "off" state freewheels instead of returning the current to
        the bus.
    band : float, optional
        Hysteresis band, total width (A); default ``0.1 I_N``.
    i_max : float, optional
        Over-current trip and reference limit (A); default ``2 I_N``.
    omega_min : float, optional
        Slowest speed the Hall estimate reports (electrical rad/s); default ``0.01 p Omega_0``.
    theta_offset : float
        Hall angle correction (electrical rad).
    hall_angle : {"interp", "pll"}
        Hall angle estimator: ``interp`` is paper 1's (46), ``pll`` a tracking loop on the edges
        (``core/ctrl/include/bldc/bc_hall.h``) that averages the edge errors of misplaced sensors.
    pll_edges : float
        Time constant of the tracking loop in Hall edges (1 .. 1000).
    hall_table : sequence of float, optional
        Calibrated Hall edge angles (rad, electrical): 6 (both directions) or 12 (forward, then backward), e.g.
        from :func:`bldclab.sim.hallcal.calibrate`; used for the angle, the speed and (six-step with ``advance``)
        the commutation instant. ``None``: the nominal edges ``pi/6 + j pi/3``.
    derate : TemperatureDerating, optional
        Derate the reference's current limit ``i_max`` with the temperature inputs (firmware derating,
        :mod:`bldclab.control.derate`); ``None``: none.
    open_detect : float
        Detect a missing current path (an open phase, a lost current sensor reading zero), 0 (default) for off,
        else a fraction ``f`` in (0, 0.5): a current loop at full voltage whose regulated current stays below
        ``f I_ref`` for twice the time the pair's R-L circuit needs, with the back-EMF estimate's voltage margin, to
        reach ``2 f I_ref`` from zero (plus four samples) goes to the safe state with ``BC_FLAG_BAD_INPUT``, latched
        (``bc_sixstep.h``; docs/sixstep.md, "Detecting a missing current path"). It needs no over-current, so it
        works on high-resistance motors whose windings keep every current below the trip.
    """

    regulation: Literal["predictive", "pi", "hysteresis", "duty", "ideal"] = "predictive"
    chopping: Literal["pwm-on-pwm", "bipolar", "high", "sync"] = "pwm-on-pwm"
    reference: Literal["current", "torque"] = "current"
    delay: int = 1
    advance: bool = True
    timed: bool = False
    timing: float | str = 0.0
    timing_time: float | str = 0.0
    commutation: Literal["hall", "encoder"] = "hall"
    bandwidth_hz: float = 1000.0
    phase_margin_deg: float = 90.0
    kp: float | None = None
    ki: float | None = None
    emf_feedforward: bool = True
    regen: bool = True
    band: float | None = None
    i_max: float | None = None
    omega_min: float | None = None
    theta_offset: float = 0.0
    hall_angle: Literal["interp", "pll"] = "interp"
    pll_edges: float = 3.0
    hall_table: tuple[float, ...] | None = None
    derate: TemperatureDerating | None = None
    open_detect: float = 0.0
    c_name: ClassVar[str] = "sixstep"
    ref_meaning: ClassVar[str] = "current amplitude, A (or torque, N m)"

    def __post_init__(self) -> None:
        for name, dim in (("timing", "angle"), ("timing_time", "time")):
            v = getattr(self, name)
            if isinstance(v, str):
                object.__setattr__(self, name, to_si(v, dim, f"control.{name}"))
            check_number(name, getattr(self, name), allow_zero=True)
        timing = float(self.timing)  # a number now: read from its string above
        if timing > math.pi / 6:
            raise BldclabError("control.timing", f"must be at most 30 deg (pi/6 rad), got {timing:.4g} rad")
        for name, table in (("regulation", _REG), ("chopping", _CHOP), ("reference", _REF), ("commutation", _COMM)):
            if getattr(self, name) not in table:
                raise BldclabError(f"control.{name}", f"must be one of {', '.join(table)}, got {getattr(self, name)!r}")
        if self.delay not in (0, 1) or isinstance(self.delay, bool):
            raise BldclabError("control.delay", f"must be 0 or 1 sample, got {self.delay!r}")
        for name in ("advance", "timed", "emf_feedforward", "regen"):
            if not isinstance(getattr(self, name), bool):
                raise BldclabError(f"control.{name}", f"must be True or False, got {getattr(self, name)!r}")
        check_number("bandwidth_hz", self.bandwidth_hz)
        check_number("phase_margin_deg", self.phase_margin_deg)
        check_number("kp", self.kp, allow_zero=True, allow_none=True)
        check_number("ki", self.ki, allow_zero=True, allow_none=True)
        for name in ("band", "i_max", "omega_min"):
            check_number(name, getattr(self, name), allow_none=True)
        if isinstance(self.theta_offset, bool) or not isinstance(self.theta_offset, int | float) or not math.isfinite(
                self.theta_offset):
            raise BldclabError("control.theta_offset", f"must be a finite number, got {self.theta_offset!r}")
        check_hall_options(self.pll_edges, self.hall_angle)
        object.__setattr__(self, "hall_table", normalize_table(self.hall_table))
        if (isinstance(self.open_detect, bool) or not isinstance(self.open_detect, int | float)
                or not 0.0 <= self.open_detect < 0.5):
            raise BldclabError("control.open_detect", f"must be 0 (off) or a fraction in (0, 0.5), got "
                               f"{self.open_detect!r}")
        if self.derate is not None and not isinstance(self.derate, TemperatureDerating):
            raise BldclabError("control.derate", f"must be a TemperatureDerating, got {type(self.derate).__name__}")

    def gains(self, drive: Drive) -> tuple[float, float]:
        """Return the PI gains ``(k_p, k_i)`` of the line current loop (V/A, V/(A s)).

        Parameters
        ----------
        drive : Drive
            Its ``R + R_on`` and ``L`` give the line plant ``1 / (2 R + s 2 L)``.

        Returns
        -------
        tuple of float
            ``k_p`` (V/A) and ``k_i`` (V/(A s)): the given ones, else :func:`bldclab.model.design.pi_gains`.
        """
        kp, ki = pi_gains(2.0 * r_total(drive), 2.0 * drive.motor.L, self.bandwidth_hz, self.phase_margin_deg)
        return (kp if self.kp is None else float(self.kp)), (ki if self.ki is None else float(self.ki))

    def with_delay(self, delay: int) -> SixStep:  # noqa: D102 - Control.with_delay
        return self if delay == self.delay else dataclasses.replace(self, delay=delay)

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        m, inv = drive.motor, drive.inverter
        if self.regulation == "ideal" and (inv.model != "average" or inv.R_src > 0.0):
            raise BldclabError("control.regulation", "'ideal' (paper 1's ideal current limiter) holds the current in "
                               "continuous time on the averaged inverter: needs inverter.model = 'average' and "
                               f"R_src = 0 (got model {inv.model!r}, R_src {inv.R_src:g} Ohm)")
        kp, ki = self.gains(drive)
        return CParams(core.filled(
            "bc_sixstep_params",
            reg=core.const(_REG[self.regulation]),
            chop=core.const(_CHOP[self.chopping]),
            ref_torque=_REF[self.reference],
            delay=self.delay,
            advance=int(self.advance),
            timed=int(self.timed),
            adv_angle=self.timing,
            adv_time=self.timing_time,
            comm=core.const(_COMM[self.commutation]),
            emf_ff=int(self.emf_feedforward),
            regen=int(self.regen),
            p=m.p,
            ts=0.5 / inv.f_pwm,
            R=r_total(drive),
            L=m.L,
            k_e=2.0 * m.k_phi,
            kp=kp,
            ki=ki,
            band=0.1 * m.I_N if self.band is None else self.band,
            i_max=2.0 * m.I_N if self.i_max is None else self.i_max,
            v_max=2.0 * inv.V_dc,
            f_tick=drive.sensors.f_tick,
            omega_min=0.01 * m.p * drive.Omega_0 if self.omega_min is None else self.omega_min,
            theta_offset=self.theta_offset,
            **hall_record(core, self.hall_angle == "pll", self.pll_edges, self.hall_table),
            derate=derate_record(core, self.derate, 0.5 / inv.f_pwm),
            open_frac=float(self.open_detect),
        ))

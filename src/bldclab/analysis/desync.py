"""The desync map of a sensorless six-step drive: where a throttle step (or a start-up) keeps or loses synchronisation.

Each point of a grid (two of :data:`AXES`: timing advance, throttle ramp rate, final throttle, propeller ``k_q``,
inertia, blanking, PWM frequency, bus voltage, chopping pattern, initial rotor angle) runs
:class:`~bldclab.control.SixStepSensorless` on the switching plant, with the drive's mechanics (its propeller load
``k_q omega^2``) and its back-EMF sensing, through one :class:`ThrottleStep`:

- ``start > 0``: the drive starts from rest at throttle ``start``; once it has run in closed loop there for
  ``settle`` (found by a first run at ``start``, :func:`steady_since`; a drive that never gets there is
  ``no start``), the throttle jumps to ``end`` (the controller's ``throttle_rate`` limits how fast its duty
  follows), and the run goes on for ``observe``: long enough for a drive that lost synchronisation to restart and
  settle again. The second run repeats the first up to the step bit for bit.
- ``start == 0``: a start-up from rest at throttle ``end`` (alignment or direct start, forced ramp, handover).

Each point is classified (:func:`classify`, on a :class:`Observation` of the run) into one of :data:`OUTCOMES`:

``sync``
    no desync after the step, and the plant's truth agrees (every closed-loop commutation within ``bound`` of its
    ideal angle).
``recovered``
    the controller flagged a desync after the step (its reason: :data:`REASONS`), restarted, and is back in
    closed loop, in sync, at the end of the run.
``desync``
    a desync after the step, not back in sync at the end (restarts failing, or still restarting).
``undetected``
    the controller flagged nothing, but the plant's truth shows a commutation more than ``bound`` away from its
    ideal angle: the controller's self-diagnosis missed a real loss of synchronisation.
``no start``
    the drive was not in closed loop, in sync, at the step (for ``start == 0``: it never reached it); the reason is
    the controller's last (``START_FAIL``: the forced ramp saw no crossings for a handover).
``refused``
    the point did not run: the simulation refused its drive or scenario (its ``note`` says why, e.g. a run too
    long to keep its per-sample trace, where a large inertia makes the settling time minutes).

**The plant's truth.** The controller's flags are its own diagnosis; the map also measures the real loss of
synchronisation. At every closed-loop commutation (a change of the driven pair in the applied leg modes) the true
electrical angle of the rotor is compared with the angle where that commutation belongs: forward into sector ``s``
at ``pi/6 + s pi/3 - adv`` (``docs/conventions.md``; ``adv`` the controller's advance), backward at
``pi/2 + s pi/3 + adv``. The error is positive when the commutation came early, like the controller's
``comm_error``. The trace gives the applied legs at every sample (half PWM period ``T_s``) and the instant of
the commutation timer's leg change (``t_at``), so each commutation's instant and true angle are exact. A commutation
is *out of sync* when its error is beyond ``bound`` (default 30 degrees electrical, half a sector: the drive then
feeds the pair of the neighbouring sector for more than half of it).

**The physics check.** The crossing is hidden when the demagnetisation (the outgoing phase's diode conduction after
a commutation, paper 1's commutation interval) lasts past the expected crossing. The controller commutates
``30 deg - adv`` after a crossing and the next crossing comes 60 degrees after that one, so it is expected
``30 deg + adv`` after the commutation: an advance widens the window (which is why raising the timing is the usual
cure of a desync on a throttle punch). Each point reports the largest demagnetisation angle ``omega_e t_demag`` the
controller measured after the step (``demag_deg``) beside the narrowest window ``window_deg = 30 + adv``: where
``demag_deg`` reaches ``window_deg`` the crossings are hidden. The controller measures a demagnetisation only when it
ends inside the window, so on a point where it hid the crossing ``demag_deg`` is the last one it saw, a lower
bound.

The points run on local processes or any :class:`concurrent.futures.Executor` (a Dask client's
``get_executor()``), as :func:`bldclab.analysis.effmap.efficiency_map` does; each point is one deterministic
simulation, so the map does not depend on where or in how many processes it ran.
"""

from __future__ import annotations

import math
import os
import time
import warnings
from collections.abc import Callable
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from ..control.sensorless import SixStepSensorless, throttle_rate
from ..errors import BldclabError, PlausibilityError, PlausibilityWarning
from ..model.motor import Drive
from ..sim import Scenario, simulate
from ..sim import plausibility as _plaus
from .experiments import map_points

__all__ = [
    "AXES",
    "DEFAULT_BOUND",
    "OUTCOMES",
    "REASONS",
    "SHORT_REASONS",
    "Axis",
    "DesyncMapResult",
    "Observation",
    "ThrottleStep",
    "classify",
    "commutation_errors",
    "desync_map",
    "observe",
    "out_of_sync",
    "steady_since",
]

#: The outcomes of a point, in the order the map's legend lists them.
OUTCOMES = ("sync", "recovered", "desync", "undetected", "no start", "refused")

#: The controller's reasons for giving up (flag names of ``bc_types.h``), as the map names them.
REASONS = {
    "ZC_HIDDEN": "the floating phase never left the clamp: the demagnetisation hid the crossing (or it came before "
                 "the window)",
    "ZC_TIMEOUT": "no crossing within the timeout after the clamp ended: the rotor slowed or stopped",
    "ZC_JUMP": "successive crossing intervals out of ratio: a false crossing",
    "STALL": "speed from the crossings below the slowest closed-loop speed",
    "START_FAIL": "the forced ramp ended without the crossings for a handover",
    "OVERCURRENT": "a phase current above the controller's trip (all legs off, then a restart)",
    "SAFE": "an invalid measurement: the safe state",
}

#: Default bound of the true commutation angle error beyond which a commutation is out of sync (rad, electrical).
DEFAULT_BOUND = math.pi / 6.0

_DEG = 180.0 / math.pi
_RPM = 30.0 / math.pi
_CLOSED = 3  # diag state of bc_bemf: 0 STOP, 1 ALIGN, 2 RAMP, 3 CLOSED
# bc_types.h flag bits
_FLAG_BITS = {"SAFE": 0x1, "OVERCURRENT": 0x4, "BAD_INPUT": 0x8, "DESYNC": 0x20, "ZC_TIMEOUT": 0x40,
              "ZC_HIDDEN": 0x80, "ZC_JUMP": 0x100, "STALL": 0x200, "START_FAIL": 0x400, "COMM_LATE": 0x1000}
_REASON_ORDER = ("ZC_HIDDEN", "ZC_TIMEOUT", "ZC_JUMP", "STALL", "START_FAIL")
# leg modes of the trace: 0 off, 1 pwm, 2 high, 3 low, 4 hold; the (pos, neg) pair of each sector
_PAIRS = {(0, 1): 0, (0, 2): 1, (1, 2): 2, (1, 0): 3, (2, 0): 4, (2, 1): 5}


# ------------------------------------------------------------------------------------------------------------
# the disturbance


@dataclass(frozen=True)
class ThrottleStep:
    """The disturbance of every point: a throttle step from a steady point, or a start-up.

    Parameters
    ----------
    start : float
        Throttle (duty) before the step, in [0, 1); 0: a start-up from rest at ``end``.
    end : float
        Throttle after the step, in (0, 1].
    settle : float, optional
        Time at ``start`` before the step, s (after the start-up); default from the drive (:meth:`times`).
    observe : float, optional
        Time after the step, s; default from the drive (:meth:`times`): the throttle ramp, the mechanical
        settling, and a restart with its settling.
    theta0 : float
        Initial rotor angle, electrical rad (the rotor starts at rest there).
    """

    start: float = 0.25
    end: float = 0.8
    settle: float | None = None
    observe: float | None = None
    theta0: float = 0.0

    def __post_init__(self) -> None:
        for name, v in (("start", self.start), ("end", self.end), ("theta0", self.theta0)):
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                raise BldclabError(f"step.{name}", f"must be a finite number, got {v!r}")
        if not 0.0 <= self.start < 1.0:
            raise BldclabError("step.start", f"must be in [0, 1) (0: a start-up), got {self.start!r}")
        if not 0.0 < self.end <= 1.0:
            raise BldclabError("step.end", f"must be in (0, 1], got {self.end!r}")
        for name, t in (("settle", self.settle), ("observe", self.observe)):
            if t is not None and (isinstance(t, bool) or not isinstance(t, int | float) or not math.isfinite(t)
                                  or not 0.0 < t <= 10.0):
                raise BldclabError(f"step.{name}", f"must be a time in (0, 10] s, got {t!r}")

    @property
    def is_start(self) -> bool:
        """True for a start-up from rest (``start == 0``)."""
        return self.start == 0.0

    def settle_time(self, drive: Drive) -> float:
        """Return how long the drive must have run in closed loop at ``start`` before the step (s).

        ``settle`` if given, else five mechanical time constants at ``start`` (at least 20 ms). The mechanical time
        constant at a throttle ``d`` is ``J / (k^2 / (2 R) + 2 k_q w + B)`` with ``k = 2 k_phi`` and
        ``w = d Omega_0`` (the linearised balance of the six-step torque ``k (d V - k w) / (2 R)`` against the
        propeller's ``k_q w^2``).
        """
        return self.settle if self.settle is not None else max(5.0 * _tau_mech(drive, self.start), 0.02)

    def start_time(self, drive: Drive, control: SixStepSensorless) -> float:
        """Return the longest time the search for the step's instant runs at ``start`` (s).

        Two start-ups (alignment, forced ramp, 12 sectors at its end speed, the throttle ramp to ``start``) with a
        restart between them (the controller's longest wait ``restart_max``), then :meth:`settle_time`.
        """
        return 2.0 * _start_up_time(drive, control, self.start) + float(control.restart_max) + self.settle_time(drive)

    def observe_time(self, drive: Drive, control: SixStepSensorless) -> float:
        """Return how long the run goes on after the step (s).

        ``observe`` if given, else the throttle ramp to ``end``, five mechanical time constants at ``end`` and a
        restart (the controller's longest wait ``restart_max``: it restarts once the comparators are quiet, and a
        propeller-loaded rotor coasts long; its start-up and five time constants), so that a recovered drive is
        seen settled. A start-up (``start == 0``) lasts such a restart after its first start-up.
        """
        if self.observe is not None:
            return self.observe
        rate = control.throttle_rate
        ramp = abs(self.end - self.start) / float(rate) if rate and not self.is_start else 0.0
        return (ramp + max(5.0 * _tau_mech(drive, self.end), 0.02) + float(control.restart_max)
                + _start_up_time(drive, control, self.end) + max(5.0 * _tau_mech(drive, self.end), 0.02))


def _tau_mech(drive: Drive, duty: float) -> float:
    m, mech = drive.motor, drive.mechanics
    k = 2.0 * m.k_phi
    w = max(duty, 0.05) * drive.Omega_0
    return mech.J / (k * k / (2.0 * m.R) + 2.0 * mech.k_q * w + mech.B)


def _start_up_time(drive: Drive, control: SixStepSensorless, duty: float) -> float:
    su = control.start_up(drive)
    t_start = su["align_time"] + su["ramp_time"] + 12.0 * math.pi / 3.0 / (drive.motor.p * su["ramp_end_speed"])
    rate = control.throttle_rate
    return t_start + (abs(duty - su["ramp_duty"]) / float(rate) if rate else 0.0)


def steady_since(signals: dict[str, np.ndarray], settle: float) -> float | None:
    """Return the first time the controller has been in closed loop, without a flagged desync, for ``settle`` (s).

    None if it never was in the trace (``SimResult.signals`` of a :class:`~bldclab.control.SixStepSensorless`
    run).
    """
    t = signals["t"]
    closed = (signals["state"] == _CLOSED) & ((signals["ctrl_flags"].astype(np.int64) & (
        _FLAG_BITS["DESYNC"] | _FLAG_BITS["SAFE"])) == 0)
    edges = np.flatnonzero(np.diff(np.concatenate(([0], closed.astype(np.int8), [0]))))
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if t[b - 1] - t[a] >= settle:
            return float(t[a] + settle)
    return None


# ------------------------------------------------------------------------------------------------------------
# the axes


@dataclass(frozen=True)
class _AxisKind:
    unit: str  # the unit the values are given and shown in
    label: str
    apply: Callable[[Drive, SixStepSensorless, ThrottleStep, Any], tuple[Drive, SixStepSensorless, ThrottleStep]]
    numeric: bool = True


def _rate(v: float) -> float | None:
    return None if math.isinf(v) else throttle_rate(v * 10.0, "rate")  # %/ms -> 1/s


#: The parameters a map can vary: name -> (unit of the values, label, how a value changes the point).
AXES: dict[str, _AxisKind] = {
    "timing": _AxisKind("deg", "timing advance (deg electrical)",
                        lambda d, c, s, v: (d, replace(c, timing=math.radians(v)), s)),
    "rate": _AxisKind("%/ms", "throttle ramp limit (%/ms; inf: none)",
                      lambda d, c, s, v: (d, replace(c, throttle_rate=_rate(v)), s)),
    "end": _AxisKind("-", "throttle after the step", lambda d, c, s, v: (d, c, replace(s, end=v))),
    "start": _AxisKind("-", "throttle before the step", lambda d, c, s, v: (d, c, replace(s, start=v))),
    "k_q": _AxisKind("N m s^2/rad^2", "propeller k_q (N m s^2/rad^2)",
                     lambda d, c, s, v: (d.replace(mechanics__k_q=v), c, s)),
    "J": _AxisKind("kg m^2", "inertia J (kg m^2)", lambda d, c, s, v: (d.replace(mechanics__J=v), c, s)),
    "blank": _AxisKind("deg", "fixed blanking (deg electrical)",
                       lambda d, c, s, v: (d, replace(c, blank=math.radians(v)), s)),
    "f_pwm": _AxisKind("kHz", "PWM frequency (kHz)", lambda d, c, s, v: (d.replace(inverter__f_pwm=1e3 * v), c, s)),
    "v_dc": _AxisKind("V", "DC bus (V)", lambda d, c, s, v: (d.replace(inverter__V_dc=v), c, s)),
    "chopping": _AxisKind("", "chopping pattern", lambda d, c, s, v: (d, replace(c, chopping=v), s), numeric=False),
    "theta0": _AxisKind("deg", "initial rotor angle (deg electrical)",
                        lambda d, c, s, v: (d, c, replace(s, theta0=math.radians(v)))),
    "fast_demag": _AxisKind("", "fast demagnetisation (on, off)",
                            lambda d, c, s, v: (d, replace(c, fast_demag=v == "on"), s), numeric=False),
    "demag_limit": _AxisKind("-", "demagnetisation limiter (share of the window; 0: off)",
                             lambda d, c, s, v: (d, replace(c, demag_limit=v), s)),
    "duty_limit": _AxisKind("A", "speed-dependent duty limit's current (A; 0: off)",
                            lambda d, c, s, v: (d, replace(c, duty_limit_current=v), s)),
    "delay": _AxisKind("samples", "controller delay (samples: 1 next sample, 0 within it)",
                       lambda d, c, s, v: (d, replace(c, delay=int(v)), s)),
}
_CHOICES = {"chopping": ("sync", "high", "pwm-on-pwm", "bipolar"), "fast_demag": ("on", "off")}
#: Range of each numeric axis: (low, high, low included, high included); the others: positive.
_LIMITS = {"timing": (0.0, 30.0, True, True), "end": (0.0, 1.0, False, True), "start": (0.0, 1.0, True, False),
           "blank": (0.0, 60.0, True, True), "theta0": (-360.0, 360.0, True, True),
           "demag_limit": (0.0, 1.0, True, False), "duty_limit": (0.0, math.inf, True, False),
           "delay": (0.0, 1.0, True, True)}


@dataclass(frozen=True)
class Axis:
    """One axis of the map: a parameter of :data:`AXES` and its values, in that parameter's unit.

    Parameters
    ----------
    name : str
        A key of :data:`AXES`: ``timing`` (deg), ``rate`` (throttle ramp limit, %/ms; ``inf``: none), ``end``,
        ``start`` (throttle), ``k_q`` (N m s^2/rad^2), ``J`` (kg m^2), ``blank`` (deg), ``f_pwm`` (kHz), ``v_dc``
        (V), ``chopping`` (``sync``, ``high``, ``pwm-on-pwm``, ``bipolar``), ``theta0`` (deg), ``fast_demag``
        (``on``, ``off``), ``demag_limit`` (share of the window in [0, 1); 0: the limiter off), ``duty_limit``
        (the current of the controller's speed-dependent duty limit, A; 0: off), ``delay`` (samples between the
        controller's computing and applying an output: 1, a sampled controller, or 0, within the sample).
    values : sequence
        Distinct values (numbers in the unit above; names for ``chopping``).
    """

    name: str
    values: tuple[Any, ...]

    def __post_init__(self) -> None:
        if self.name not in AXES:
            raise BldclabError("axis", f"must be one of {', '.join(AXES)}, got {self.name!r}")
        vals = tuple(self.values) if not isinstance(self.values, str) else (self.values,)
        if not vals:
            raise BldclabError(self.name, "needs at least one value")
        if AXES[self.name].numeric:
            try:
                nums = tuple(float(v) for v in vals)
            except (TypeError, ValueError):
                raise BldclabError(self.name, f"values must be numbers ({AXES[self.name].unit}), got "
                                   f"{list(vals)!r}") from None
            for v in nums:
                if math.isnan(v) or (math.isinf(v) and self.name != "rate"):
                    raise BldclabError(self.name, f"values must be finite, got {v!r}")
                if self.name == "delay" and v not in (0.0, 1.0):
                    raise BldclabError(self.name, f"values must be 0 or 1 sample, got {v:g}")
                lo, hi, lo_in, hi_in = _LIMITS.get(self.name, (0.0, math.inf, False, True))
                inside = (lo < v or (lo_in and v == lo)) and (v < hi or (hi_in and v == hi))
                if not inside and not (self.name == "rate" and math.isinf(v)):
                    where = (("at least 0" if lo_in else "positive") if math.isinf(hi) else
                             f"in {'[' if lo_in else '('}{lo:g}, {hi:g}{']' if hi_in else ')'}")
                    unit = AXES[self.name].unit
                    raise BldclabError(self.name, f"values must be {where}{'' if unit == '-' else f' ({unit})'}, "
                                       f"got {v:g}")
            vals = nums
        else:
            bad = [v for v in vals if v not in _CHOICES[self.name]]
            if bad:
                raise BldclabError(self.name, f"must be from {', '.join(_CHOICES[self.name])}, got {bad[0]!r}")
        if len(set(vals)) != len(vals):
            raise BldclabError(self.name, "values must be distinct")
        object.__setattr__(self, "values", vals)

    @property
    def unit(self) -> str:
        """The unit of the values."""
        return AXES[self.name].unit

    @property
    def label(self) -> str:
        """Axis label with its unit."""
        return AXES[self.name].label


# ------------------------------------------------------------------------------------------------------------
# the truth: commutation angles from the plant's rotor angle


def _legs(modes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Floating leg and driven pair (sector index of the forward table) of each trace row; -1 where there is none.

    The floating leg is the one leg OFF. Of the other two, the one chopping or held LOW is the negative one; with
    none LOW (the continuing phase chopping complementary while the incoming one is held HIGH, as a drive that
    speeds up the demagnetisation does) the HIGH one is the positive one.
    """
    off = modes == 0
    one = off.sum(axis=0) == 1
    f = np.where(one, np.argmax(off, axis=0), -1)
    x, y = (f + 1) % 3, (f + 2) % 3
    cols = np.arange(modes.shape[1])
    mx, my = modes[x, cols], modes[y, cols]
    neg = np.where((mx == 3) & (my != 3), x, np.where((my == 3) & (mx != 3), y,
                   np.where((mx == 1) & (my == 2), x, np.where((my == 1) & (mx == 2), y, -1))))
    neg = np.where(one, neg, -1)
    table = np.full((3, 3), -1, dtype=int)
    for (p, q), k in _PAIRS.items():
        table[p, q] = k
    pos = 3 - f - neg
    pair = np.where(neg >= 0, table[np.clip(pos, 0, 2), np.clip(neg, 0, 2)], -1)
    return f, pair


def commutation_errors(signals: dict[str, np.ndarray], direction: int = 0) -> pd.DataFrame:
    """Locate the closed-loop commutations in a trace, their true angle error and the true demagnetisation.

    Parameters
    ----------
    signals : dict of numpy.ndarray
        ``SimResult.signals`` of a :class:`~bldclab.control.SixStepSensorless` run with one trace row per sample:
        ``t``, ``theta_e``, ``mode_a`` .. ``mode_c``, ``i_a`` .. ``i_c``, ``state``, ``omega_e``, ``advance``, and
        ``t_at`` if there is one (else a commutation is located within its sample only), ``t_iz_a`` .. ``t_iz_c`` if
        there are (else the currents' ends are read from the rows).
    direction : int
        +1 or -1 for a known direction; 0: the sign of the controller's ``omega_e`` at each commutation.

    Returns
    -------
    pandas.DataFrame
        One row per commutation (a change of the floating leg between two rows both in closed loop): ``t`` (s, the
        row where the new legs show; the commutation happened in the sample before), ``sector`` (entered),
        ``direction``, ``err_lo``, ``err_hi`` (rad: the true error at the start and the end of that sample,
        positive = early; both the error at the commutation's instant when the trace has ``t_at``, the commutation
        timer's instant, or the sample's start for a change applied there), ``err`` (their middle), ``certain``
        (the smallest ``|error|`` over the sample: 0 if it changes sign), ``adv`` (rad: the controller's advance
        there); the demagnetisation of the phase switched
        off (now floating) from the plant's currents:
        ``demag`` (rad: the rotor's travel from the commutation, ``err``'s instant, to the end of its current),
        ``margin`` (rad: from the end of that current to the zero crossing of the floating phase's back-EMF at the
        sector's middle, ``pi/3 + s pi/3``; negative: the demagnetisation hid the crossing), ``margin_time`` (s: the
        same at the rotor's speed over the commutation's sample) and ``ended`` (False:
        the current still flowed at the next commutation or the end of the closed loop, and ``margin`` is an upper
        bound). The end is the plant's own instant of it (``t_iz_a`` .. ``t_iz_c``: the first end of the phase's
        current after the commutation, its diode turning off, an event the plant locates), the rotor's angle there
        interpolated between the rows. A trace without those signals is read from its rows: where the current has
        fallen below 2 % of its value at the commutation (a floating phase clamped in the off-time carries a
        little), located on the straight line through the two points before it (the commutation instant with the
        current of the row before it, then the rows): exact to the curvature over one row.
    """
    t = signals["t"]
    modes = np.vstack([signals["mode_a"], signals["mode_b"], signals["mode_c"]]).astype(int)
    cur = np.vstack([signals["i_a"], signals["i_b"], signals["i_c"]])
    f, pair = _legs(modes)
    closed = signals["state"] == _CLOSED
    k = np.flatnonzero((f[:-1] >= 0) & (f[1:] >= 0) & (f[:-1] != f[1:]) & closed[:-1] & closed[1:])
    theta = signals["theta_e"]
    thu = np.unwrap(theta)
    t_at = signals.get("t_at")
    t_iz = (np.vstack([signals["t_iz_a"], signals["t_iz_b"], signals["t_iz_c"]])
            if all(f"t_iz_{x}" in signals for x in "abc") else None)
    at = 0.5
    n = t.size
    ends = np.append(k[1:] + 1, n) if k.size else k  # each sector's rows: from its commutation row to the next one's
    rows = []
    for j, stop in zip(k, ends, strict=True):
        dirn = direction if direction else int(np.sign(signals["omega_e"][j]))
        if dirn == 0:
            continue
        r = j + 1
        last = r
        while last + 1 < min(stop, n) and f[last + 1] == f[r] and closed[last + 1]:
            last += 1
        known = [q for q in range(r, last + 1) if pair[q] >= 0]
        if not known:
            continue
        p = int(pair[known[0]])
        s = p if dirn > 0 else (p + 3) % 6  # backward: the pair of sector s is swapped (docs/sensorless.md)
        adv = float(signals["advance"][j])
        ideal = math.pi / 3.0 + s * math.pi / 3.0 - dirn * (math.pi / 6.0 + adv)
        e0 = _wrap(dirn * (ideal - theta[j]))
        travel = dirn * (thu[r] - thu[j])  # over the sample (forward positive)
        e1 = e0 - travel
        if t_at is not None:  # the instant is known: the timer's, or the sample's where the change was applied
            tc = float(t_at[j]) if t[j] <= t_at[j] < t[r] else float(t[r])
            at = (tc - t[j]) / (t[r] - t[j])
            e0 = e1 = e0 - at * travel
        certain = 0.0 if e0 * e1 <= 0.0 else min(abs(e0), abs(e1))
        th_comm = thu[j] + (at if t_at is not None else 0.5) * (thu[r] - thu[j])
        i_f = cur[f[r], r:last + 1]
        demag = margin = math.nan
        ended = False
        i0 = float(i_f[0]) if i_f.size else 0.0
        i_pre = float(cur[f[r], j])  # the phase's current while it was still driven, the row before the change
        if t_iz is not None and (abs(i0) > 0.0 or abs(i_pre) > 0.0):
            # the plant's own instant of the current's end (its diode turning off, an event it located): the first
            # after the commutation, in the commutation's row or a later one of the sector
            tc = float(t_at[j]) if t_at is not None and t[j] <= t_at[j] < t[r] else float(t[r])
            ends = t_iz[f[r], j:last + 1]
            after = np.flatnonzero(ends >= tc)
            if after.size:
                ended = True
                th_end = float(np.interp(ends[after[0]], t[j:last + 2], thu[j:last + 2]))
            else:
                th_end = thu[last]
            crossing = math.pi / 3.0 + s * math.pi / 3.0
            demag = dirn * (th_end - th_comm)
            margin = dirn * _wrap(crossing - th_end)
        elif abs(i0) > 0.0 or abs(i_pre) > 0.0:
            # the current's magnitude from the commutation on: at the commutation instant about i_pre (when the
            # first row after it shows less: the fall began inside that sample), then the rows
            ref = i_pre if abs(i_pre) > abs(i0) else i0
            g = np.sign(ref) * i_f
            ths = thu[r:last + 1]
            if abs(i_pre) > abs(i0):
                g = np.concatenate(([abs(i_pre)], g))
                ths = np.concatenate(([th_comm], ths))
            low = np.flatnonzero(g <= 0.02 * abs(ref))
            if low.size:
                q = int(low[0])
                ended = True
                if q >= 1 and g[q] > 0.0:  # still a little current: the zero of the line through q - 1, q, ahead
                    frac = min(g[q] / (g[q - 1] - g[q]), 1.0) if g[q - 1] > g[q] else 0.0
                    th_end = ths[q] + frac * (ths[q] - ths[q - 1])
                elif q >= 2 and g[q - 2] > g[q - 1]:  # ended before row q: along the slope of the two before
                    frac = min(g[q - 1] * (ths[q - 1] - ths[q - 2]) / ((g[q - 2] - g[q - 1]) * (ths[q] - ths[q - 1])),
                               1.0)
                    th_end = ths[q - 1] + frac * (ths[q] - ths[q - 1])
                elif q >= 1:  # the line through q - 1 and q (q at or below zero)
                    th_end = ths[q - 1] + (ths[q] - ths[q - 1]) * g[q - 1] / (g[q - 1] - g[q])
                else:
                    th_end = ths[0]
            else:
                th_end = thu[last]
            crossing = math.pi / 3.0 + s * math.pi / 3.0
            demag = dirn * (th_end - th_comm)
            margin = dirn * _wrap(crossing - th_end)
        speed = abs(thu[r] - thu[j]) / (t[r] - t[j])
        rows.append((t[r], s, dirn, e0, e1, 0.5 * (e0 + e1), certain, adv, demag, margin,
                     margin / speed if speed > 0.0 else math.nan, ended))
    types = {"t": float, "sector": int, "direction": int, "err_lo": float, "err_hi": float, "err": float,
             "certain": float, "adv": float, "demag": float, "margin": float, "margin_time": float, "ended": bool}
    return pd.DataFrame(rows, columns=list(types)).astype(types)


def out_of_sync(comms: pd.DataFrame, bound: float = DEFAULT_BOUND) -> np.ndarray:
    """Which commutations of :func:`commutation_errors` are certainly out of sync.

    A commutation is out of sync when its whole sample lies more than ``bound`` *earlier* than the angle the
    controller meant (its advance included), or more than ``bound`` *later* than the rotor's own sector boundary
    (the Hall-exact angle, ``adv`` after the meant one). A late commutation that only loses part of a meant advance
    (``COMM_LATE`` with a large timing at few samples per sector) still feeds the pair of the rotor's sector: it
    costs torque, not synchronisation. With no advance both sides are the same angle.

    Parameters
    ----------
    comms : pandas.DataFrame
        From :func:`commutation_errors` (``err_lo``, ``err_hi``, ``adv``; rad, positive = early).
    bound : float
        Half-width of the band, rad (default 30 deg: half a sector).

    Returns
    -------
    numpy.ndarray of bool
    """
    lo = np.minimum(comms.err_lo.to_numpy(), comms.err_hi.to_numpy())
    hi = np.maximum(comms.err_lo.to_numpy(), comms.err_hi.to_numpy())
    return (lo > bound) | (hi < -(bound + np.maximum(comms.adv.to_numpy(), 0.0)))


def _wrap(x: float) -> float:
    return float((x + math.pi) % (2.0 * math.pi) - math.pi)


# ------------------------------------------------------------------------------------------------------------
# observation and classification


@dataclass(frozen=True)
class Observation:
    """What a run showed, in the terms :func:`classify` decides on (built by :func:`observe`, or by hand).

    Parameters
    ----------
    t_step, t_end : float
        Time of the step and end of the run (s); ``t_step = 0`` for a start-up.
    desyncs : tuple of (float, str)
        Every desync (or trip) the controller flagged: its time and reason (a key of :data:`REASONS`).
    closed : tuple of (float, float)
        The intervals (s) the controller spent in closed loop.
    out_of_sync : tuple of float
        Times of the closed-loop commutations the plant's truth puts certainly beyond the bound.
    commutations : tuple of float
        Times of every closed-loop commutation located.
    settle : float
        Length (s) before the step over which the drive must have been in closed loop, in sync, for the step to
        count as taken from a steady point.
    """

    t_step: float
    t_end: float
    desyncs: tuple[tuple[float, str], ...] = ()
    closed: tuple[tuple[float, float], ...] = ()
    out_of_sync: tuple[float, ...] = ()
    commutations: tuple[float, ...] = ()
    settle: float = 0.0

    @property
    def start_up(self) -> bool:
        """True for a start-up (``t_step == 0``)."""
        return self.t_step == 0.0


def _closed_over(obs: Observation, t0: float, t1: float) -> bool:
    eps = 1e-9  # s: a step placed `settle` after the start of a closed-loop stretch, to rounding
    return any(a <= t0 + eps and b >= t1 - eps for a, b in obs.closed)


def classify(obs: Observation, *, tail: int = 12) -> tuple[str, str]:
    """Classify one run: its outcome (:data:`OUTCOMES`) and the reason (a key of :data:`REASONS`, or ``""``).

    Parameters
    ----------
    obs : Observation
    tail : int
        Closed-loop commutations at the end of the run (two electrical turns by default) that must all be in sync,
        with the drive in closed loop from the first of them to the end, for it to count as (back) in sync.

    Returns
    -------
    tuple of str
        ``(outcome, reason)``: for ``desync`` and ``recovered`` the reason of the first desync after the step; for
        ``no start`` the controller's last reason before the step (``""`` if it flagged none); ``""`` for
        ``sync`` and ``undetected``.
    """
    before = [(t, r) for t, r in obs.desyncs if t <= obs.t_step]
    after = [(t, r) for t, r in obs.desyncs if t > obs.t_step]
    if not obs.start_up:
        t0 = obs.t_step - obs.settle
        steady = (_closed_over(obs, t0, obs.t_step) and not any(t0 < t <= obs.t_step for t, _ in before)
                  and not any(t0 < t <= obs.t_step for t in obs.out_of_sync))
        if not steady:
            return "no start", before[-1][1] if before else ""
    t_flag, reason = after[0] if after else (math.inf, "")
    if any(obs.t_step < t < t_flag for t in obs.out_of_sync):
        return "undetected", ""
    t_last = after[-1][0] if after else obs.t_step
    tail_comms = [t for t in obs.commutations if t > t_last][-tail:]
    back = (len(tail_comms) == tail and _closed_over(obs, tail_comms[0], obs.t_end)
            and not any(t >= tail_comms[0] for t in obs.out_of_sync))
    if not after:
        return ("sync", "") if back or not obs.start_up else ("no start", "")
    if obs.start_up and all(r == "START_FAIL" for _, r in after):
        return ("recovered" if back else "no start"), reason
    return ("recovered" if back else "desync"), reason


def _reason(flags: int) -> str:
    for name in _REASON_ORDER:
        if flags & _FLAG_BITS[name]:
            return name
    if flags & _FLAG_BITS["OVERCURRENT"]:
        return "OVERCURRENT"
    return "SAFE"


def observe(signals: dict[str, np.ndarray], t_step: float, *, settle: float = 0.0, bound: float = DEFAULT_BOUND,
            direction: int = 0) -> tuple[Observation, pd.DataFrame]:
    """Read a :class:`~bldclab.control.SixStepSensorless` run's trace into an :class:`Observation`.

    Parameters
    ----------
    signals : dict of numpy.ndarray
        ``SimResult.signals`` with one trace row per sample.
    t_step : float
        Time of the step (s; 0 for a start-up).
    settle : float
        The steady interval required before the step (s), :attr:`Observation.settle`.
    bound : float
        Largest true commutation angle error in sync (rad, electrical).
    direction : int
        Direction of rotation (+1, -1), or 0: from the controller's speed estimate.

    Returns
    -------
    Observation
    pandas.DataFrame
        The commutations (:func:`commutation_errors`).
    """
    t = signals["t"]
    t_half = float(t[1] - t[0]) if t.size > 1 else 0.0
    flags = signals["ctrl_flags"].astype(np.int64)
    gave_up = (flags & (_FLAG_BITS["DESYNC"] | _FLAG_BITS["SAFE"])) != 0
    rise = np.flatnonzero(gave_up & ~np.concatenate(([False], gave_up[:-1])))
    desyncs = tuple((float(t[j]), _reason(int(flags[j]))) for j in rise)
    closed = signals["state"] == _CLOSED
    edges = np.flatnonzero(np.diff(np.concatenate(([0], closed.astype(np.int8), [0]))))
    spans = tuple((float(t[a]), float(t[b - 1]) + t_half) for a, b in zip(edges[::2], edges[1::2], strict=True))
    comms = commutation_errors(signals, direction)
    out = tuple(float(x) for x in comms.t[out_of_sync(comms, bound)])
    return Observation(t_step=t_step, t_end=float(t[-1]) + t_half, desyncs=desyncs, closed=spans, out_of_sync=out,
                       commutations=tuple(float(x) for x in comms.t), settle=settle), comms


# ------------------------------------------------------------------------------------------------------------
# one point


#: One point: drive, controller, step, the two axes' (name, value) and the bound (rad).
DesyncJob = tuple[Drive, SixStepSensorless, ThrottleStep, tuple[tuple[str, Any], ...], float]


def _point(drive: Drive, control: SixStepSensorless, step: ThrottleStep,
           values: tuple[tuple[str, Any], ...]) -> tuple[Drive, SixStepSensorless, ThrottleStep]:
    for name, v in values:
        drive, control, step = AXES[name].apply(drive, control, step, v)
    return drive, control, step


def _run_point(job: DesyncJob) -> dict[str, Any]:
    drive, control, step, values, bound = job
    row: dict[str, Any] = {name: v for name, v in values}
    nan = math.nan
    empty = {"outcome": "no start", "reason": "", "truth_lost": False, "t_desync_ms": nan, "restarts": 0,
             "angle_mean_deg": nan, "angle_max_deg": nan, "demag_deg": nan, "window_deg": nan,
             "demag_true_deg": nan, "margin_deg": nan, "margin_us": nan,
             "speed_step_rpm": nan, "speed_end_rpm": nan, "i_peak": nan, "t_closed_ms": nan, "comm_late": 0,
             "t_step": nan, "t_end": nan, "note": "", "_warnings": []}
    row.update(empty)
    try:
        drive, control, step = _point(drive, control, step, values)
        settle = 0.0 if step.is_start else step.settle_time(drive)
        with _plaus.collect() as caught:
            t_step = 0.0
            if not step.is_start:  # where the drive has been steady at `start` for `settle`: the step's instant
                pre = simulate(drive, control, Scenario(duration=step.start_time(drive, control), ref=step.start,
                                                        theta0=step.theta0), check="warn")
                found = steady_since(pre.signals, settle)
                if found is None:
                    obs, _ = observe(pre.signals, float(pre.signals["t"][-1]), settle=settle, bound=bound,
                                     direction=1)
                    row["outcome"], row["reason"] = classify(obs)
                    row["note"] = "never steady in closed loop at the throttle before the step"
                    row["_warnings"] = _tagged(values, caught)
                    return row
                t_step = found
            t_end = t_step + step.observe_time(drive, control)
            ref: Any = (step.end if step.is_start else
                        (lambda tt, a=step.start, b=step.end, ts=t_step: np.where(tt < ts, a, b)))
            res = simulate(drive, control, Scenario(duration=t_end, ref=ref, theta0=step.theta0),
                           check="warn")
    except (PlausibilityError, BldclabError) as exc:
        row["outcome"] = "refused"
        row["note"] = f"refused: {exc}"
        return row
    sig = res.signals
    obs, comms = observe(sig, t_step, settle=settle, bound=bound, direction=1)
    outcome, reason = classify(obs)
    t = sig["t"]
    after = t > t_step
    flagged = [tf for tf, _ in obs.desyncs if tf > t_step]
    t_flag = flagged[0] if flagged else math.inf
    win = after & (t < t_flag) & (sig["state"] == _CLOSED)
    cw = comms[(comms.t > t_step) & (comms.t < t_flag)]
    cm = cw[np.isfinite(cw.margin)]
    demag = np.abs(sig["demag"] * sig["omega_e"])[win]
    i_abs = np.max(np.abs(np.vstack([sig["i_a"], sig["i_b"], sig["i_c"]]))[:, after], axis=0) if after.any() else []
    closed_t = t[sig["state"] == _CLOSED]
    n_tail = max(1, t.size // 20)
    row.update({
        "outcome": outcome, "reason": reason,
        "truth_lost": bool(any(t_step < x for x in obs.out_of_sync)),
        "t_desync_ms": (t_flag - t_step) * 1e3 if flagged else nan,
        "restarts": len(flagged),
        "angle_mean_deg": float(cw.err.mean()) * _DEG if len(cw) else nan,
        "angle_max_deg": float(cw.err.abs().max()) * _DEG if len(cw) else nan,
        "demag_deg": float(demag.max()) * _DEG if demag.size else nan,
        "window_deg": float(30.0 + np.min(sig["advance"][win]) * _DEG) if win.any() else nan,
        "demag_true_deg": float(cm.demag.max()) * _DEG if len(cm) else nan,
        "margin_deg": float(cm.margin.min()) * _DEG if len(cm) else nan,
        "margin_us": float(cm.margin_time.min()) * 1e6 if len(cm) else nan,
        "speed_step_rpm": float(np.interp(t_step, t, sig["omega_m"])) * _RPM,
        "speed_end_rpm": float(np.mean(sig["omega_m"][-n_tail:])) * _RPM,
        "i_peak": float(np.max(i_abs)) if len(i_abs) else nan,
        "t_closed_ms": float(closed_t[0]) * 1e3 if closed_t.size else nan,
        "comm_late": int(np.count_nonzero(sig["ctrl_flags"][after].astype(np.int64) & _FLAG_BITS["COMM_LATE"])),
        "t_step": t_step, "t_end": t_end,
        "_warnings": _tagged(values, caught),
    })
    return row


def _tagged(values: tuple[tuple[str, Any], ...], caught: list[str]) -> list[str]:
    return [f"{', '.join(f'{k}={v}' for k, v in values)}: {text}" for text in caught]


# ------------------------------------------------------------------------------------------------------------
# the map

#: Short cell texts of the table (:meth:`DesyncMapResult.table`).
_SHORT = {"sync": "sync", "recovered": "rec", "desync": "LOST", "undetected": "UNDET", "no start": "nostart",
          "refused": "REFUSED"}
SHORT_REASONS = {"ZC_HIDDEN": "hidden", "ZC_TIMEOUT": "timeout", "ZC_JUMP": "jump", "STALL": "stall",
                 "START_FAIL": "startfail", "OVERCURRENT": "trip", "SAFE": "safe"}


@dataclass
class DesyncMapResult:
    """Outcome of :func:`desync_map`.

    Attributes
    ----------
    drive : Drive
        The drive as given (before the axes' changes).
    control : SixStepSensorless
        The controller as given.
    step : ThrottleStep
    x, y : Axis
        The map's axes (``y`` None for a one-axis map).
    bound : float
        The true commutation angle error bound (rad).
    points : pandas.DataFrame
        One row per point: the axes' values (columns named after them, in their units), ``outcome``
        (:data:`OUTCOMES`), ``reason`` (:data:`REASONS` key or ``""``), ``truth_lost`` (the plant's truth saw a
        commutation out of sync after the step), ``t_desync_ms`` (first desync after the step), ``restarts``
        (desyncs after the step), ``angle_mean_deg``, ``angle_max_deg`` (true commutation angle error after the
        step, until a desync: mean and largest magnitude, deg electrical, positive = early), ``demag_deg`` (largest
        demagnetisation angle the controller measured after the step, deg electrical), ``demag_true_deg`` and
        ``margin_deg`` (the same from the plant's currents, :func:`commutation_errors`: the largest
        demagnetisation angle and the smallest margin from its end to the back-EMF's zero crossing after the step,
        until a desync, deg electrical; a negative margin: a crossing the demagnetisation hid), ``margin_us`` (the
        smallest margin in time, us: what the comparator's filter and the detection had to see the crossing) and
        ``window_deg``
        (``30 +
        advance``: the angle from a commutation to its expected crossing), ``speed_step_rpm``, ``speed_end_rpm``
        (at the step; mean over the last 5 % of the run), ``i_peak`` (largest phase current after the step, A),
        ``t_closed_ms`` (first closed loop: the start-up time), ``comm_late`` (late commutations after the step),
        ``t_step``, ``t_end`` (s) and ``note`` (why a point did not run).
    seconds : float
        Wall time of the simulations.
    warnings : list of str
        Plausibility warnings of the runs, each prefixed by its point.
    """

    drive: Drive
    control: SixStepSensorless
    step: ThrottleStep
    x: Axis
    y: Axis | None
    bound: float
    points: pd.DataFrame
    seconds: float = 0.0
    warnings: list[str] = field(default_factory=list)

    @property
    def disturbance(self) -> str:
        """The disturbance in words, ``"throttle step 0.25 -> 0.8"`` (an axis named where it varies the step)."""
        names = {a.name for a in (self.x, self.y) if a is not None}
        a = "each start" if "start" in names else f"{self.step.start:g}"
        b = "each end" if "end" in names else f"{self.step.end:g}"
        if self.step.is_start and "start" not in names:
            return f"start-up from rest at throttle {b}"
        return f"throttle step {a} -> {b}"

    def to_pandas(self) -> pd.DataFrame:
        """Return the points (a copy)."""
        return self.points.copy()

    def grid(self, column: str) -> np.ndarray:
        """Return a column as a ``(len(y), len(x))`` array (one row for a one-axis map)."""
        if column not in self.points.columns:
            raise BldclabError("column", f"{column!r} is not a column of the map")
        ny = len(self.y.values) if self.y is not None else 1
        return self.points[column].to_numpy().reshape(ny, len(self.x.values))

    def cell(self, outcome: str, reason: str) -> str:
        """Return the table's short text for an outcome and its reason (``"LOST:hidden"``, ``"sync"``)."""
        short = _SHORT.get(outcome, outcome)
        return f"{short}:{SHORT_REASONS.get(reason, reason)}" if reason else short

    def table(self) -> str:
        """Return the map as a text table: one row per ``y`` value, one column per ``x`` value."""
        xs = [_fmt(v) for v in self.x.values]
        cells = [[self.cell(o, r) for o, r in zip(row_o, row_r, strict=True)]
                 for row_o, row_r in zip(self.grid("outcome"), self.grid("reason"), strict=True)]
        ylab = [f"{self.y.name} {_fmt(v)}" for v in self.y.values] if self.y is not None else [""]
        w0 = max(len(s) for s in [f"{self.x.name} ({self.x.unit})", *ylab])
        widths = [max(len(h), *(len(r[k]) for r in cells)) for k, h in enumerate(xs)]
        lines = [" ".join([f"{self.x.name} ({self.x.unit})".ljust(w0),
                           *(h.rjust(w) for h, w in zip(xs, widths, strict=True))])]
        for lab, r in zip(ylab, cells, strict=True):
            lines.append(" ".join([lab.ljust(w0), *(c.rjust(w) for c, w in zip(r, widths, strict=True))]))
        return "\n".join(lines)

    def summary(self) -> list[str]:
        """Return short lines: outcomes counted, reasons counted, the controller against the plant's truth."""
        p = self.points
        n = len(p)
        lines = ["outcomes: " + ", ".join(f"{o} {int((p.outcome == o).sum())}" for o in OUTCOMES
                                          if (p.outcome == o).any()) + f" (of {n} points)"]
        lost = p[p.outcome.isin(["desync", "recovered"])]
        if len(lost):
            counts = lost.reason.value_counts()
            lines.append("reasons of the desyncs after the step: " + ", ".join(
                f"{r} {int(c)}" for r, c in counts.items()))
        ran = p[~p.outcome.isin(["no start", "refused"])]
        if len(ran):
            agree = int(((ran.outcome == "sync") & ~ran.truth_lost).sum())
            flagged_true = int((ran.outcome.isin(["desync", "recovered"]) & ran.truth_lost).sum())
            flagged_only = int((ran.outcome.isin(["desync", "recovered"]) & ~ran.truth_lost).sum())
            undetected = int((ran.outcome == "undetected").sum())
            lines.append(f"plant's truth (commutation angle error beyond {self.bound * _DEG:.0f} deg): in sync "
                         f"{agree}; desync flagged and the angle out of sync before the flag {flagged_true}, the "
                         f"controller gave up first {flagged_only}; out of sync without a flag (undetected) "
                         f"{undetected}")
        hid = p[p.outcome.isin(["desync", "recovered"]) & (p.reason == "ZC_HIDDEN")]
        ok = p[p.outcome == "sync"]
        if len(hid) or len(ok):
            def span(g: pd.DataFrame) -> str:
                g = g[np.isfinite(g.margin_deg)]
                if g.empty:
                    return "none measured"
                return (f"{g.margin_deg.min():.1f} to {g.margin_deg.max():.1f} deg ({g.margin_us.min():.1f} to "
                        f"{g.margin_us.max():.1f} us)")

            lines.append("physics check, the plant's margin from the end of the demagnetisation to the back-EMF's "
                         f"zero crossing (smallest after the step, until a desync): ZC_HIDDEN points {span(hid)}, "
                         f"sync points {span(ok)} (negative: the crossing was hidden)")
        if self.y is not None:
            bd = self.boundary()
            if bd:
                lines.append("boundary (first " + self.x.name + " without sync, per " + self.y.name + "): "
                             + ", ".join(f"{_fmt(yv)}: {_fmt(xv) if xv is not None else 'none'}"
                                         for yv, xv in bd))
        return lines

    def boundary(self) -> list[tuple[Any, Any]]:
        """Return, per ``y`` value, the first ``x`` value (in axis order) whose point did not stay in sync."""
        if self.y is None:
            return []
        g = self.grid("outcome")
        out = []
        for k, yv in enumerate(self.y.values):
            bad = [self.x.values[j] for j in range(len(self.x.values)) if g[k, j] != "sync"]
            out.append((yv, bad[0] if bad else None))
        return out


def _fmt(v: Any) -> str:
    return f"{v:g}" if isinstance(v, float | int) else str(v)


def desync_map(drive: Drive, x: Axis, y: Axis | None = None, *, step: ThrottleStep | None = None,
               control: SixStepSensorless | None = None, bound: float = DEFAULT_BOUND, workers: int | None = None,
               executor: Executor | None = None, summarise: bool = True) -> DesyncMapResult:
    """Map where a sensorless six-step drive keeps or loses synchronisation through a throttle step or a start-up.

    Parameters
    ----------
    drive : Drive
        The drive with its mechanics (propeller ``k_q``, inertia) and its back-EMF sensing (``drive.sensors``: the
        controller turns it on).
    x, y : Axis
        The grid: ``x`` across, ``y`` (optional) down; each a parameter of :data:`AXES` with its values.
    step : ThrottleStep, optional
        The disturbance (default ``ThrottleStep()``: 0.25 to 0.8).
    control : SixStepSensorless, optional
        The controller the axes change (default ``SixStepSensorless()``).
    bound : float
        True commutation angle error beyond which a commutation is out of sync (rad, electrical; default 30 deg).
    workers : int, optional
        Local processes (default: all cores; 1: in this process).
    executor : concurrent.futures.Executor, optional
        Where the points run instead (a pool the caller keeps, a Dask client's ``get_executor()``).
    summarise : bool
        Issue one :class:`~bldclab.errors.PlausibilityWarning` summarising the points' warnings.

    Returns
    -------
    DesyncMapResult
        Its points are in the order ``y`` major, ``x`` minor, whatever ran them.
    """
    if not isinstance(drive, Drive):
        raise BldclabError("drive", f"expected a Drive, got {type(drive).__name__}")
    for name, ax in (("x", x), ("y", y)):
        if ax is not None and not isinstance(ax, Axis):
            raise BldclabError(name, f"expected an Axis, got {type(ax).__name__}")
    if y is not None and y.name == x.name:
        raise BldclabError("y", f"must vary another parameter than x ({x.name!r})")
    step = ThrottleStep() if step is None else step
    if not isinstance(step, ThrottleStep):
        raise BldclabError("step", f"expected a ThrottleStep, got {type(step).__name__}")
    control = SixStepSensorless() if control is None else control
    if not isinstance(control, SixStepSensorless):
        raise BldclabError("control", f"expected a SixStepSensorless, got {type(control).__name__}")
    if isinstance(bound, bool) or not isinstance(bound, int | float) or not 0.0 < bound < math.pi:
        raise BldclabError("bound", f"must be an angle in (0, pi) rad, got {bound!r}")
    if isinstance(workers, bool) or (workers is not None and (not isinstance(workers, int) or workers < 1)):
        raise BldclabError("workers", f"must be an integer >= 1, got {workers!r}")
    base = drive
    ys: tuple[Any, ...] = y.values if y is not None else (None,)
    jobs: list[DesyncJob] = []
    for yv in ys:
        for xv in x.values:
            vals = ((x.name, xv),) if y is None else ((x.name, xv), (y.name, yv))
            _point(base, control, step, vals)  # a bad combination fails here, before any simulation
            jobs.append((base, control, step, vals, float(bound)))
    t0 = time.perf_counter()
    n_workers = workers or os.cpu_count() or 1
    if executor is not None:
        rows = map_points(_run_point, jobs, executor)
    elif n_workers <= 1 or len(jobs) <= 1:
        rows = map_points(_run_point, jobs)
    else:
        with ProcessPoolExecutor(max_workers=min(n_workers, len(jobs))) as pool:
            rows = map_points(_run_point, jobs, pool)
    caught = [text for row in rows for text in row.pop("_warnings")]
    res = DesyncMapResult(drive=drive, control=control, step=step, x=x, y=y, bound=float(bound),
                          points=pd.DataFrame(rows), seconds=time.perf_counter() - t0, warnings=caught)
    line = _plaus.summary(caught, len(jobs))
    if line and summarise:
        warnings.warn(line, PlausibilityWarning, stacklevel=2)
    return res

"""Sensorless six-step studies: angle error, slowest speed, Hall comparison, demagnetisation time.

The commutation angle error, the slowest closed-loop speed, the drive against Hall six-step, and the
demagnetisation time against its closed forms.
Every study runs :class:`~bldclab.control.sensorless.SixStepSensorless` on the plant with its back-EMF sensing, at an
imposed speed (the dynamometer of paper 1), started *locked*: a direct start whose forced commutation runs at the
imposed speed from the instant the rotor enters sector 2, so the crossings hand over to closed loop within one
electrical period and everything after it is the closed loop's. The commutation instants are the plant's (the
trace's ``t_at``, the commutation timer's switching instant, or a row's start for a commutation applied at a sample)
and the angles the plant's true ``theta_e`` there; the Hall-exact instant of a commutation into sector ``s`` (forward)
is ``theta_e = pi/6 + s pi/3``, 30 electrical degrees after the floating phase's back-EMF zero crossing. Theory,
closed forms and results: docs/sensorless.md. The functions take and return plain values and result objects with
``to_pandas()``; none of them depends on the command line or the report.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from ..control import Control, SixStep
from ..control.sensorless import SixStepSensorless
from ..errors import BldclabError
from ..model.analytic import r_total
from ..model.motor import Drive
from ..sim import Scenario, SimResult, simulate
from .experiments import map_points

__all__ = [
    "START_FAILURES",
    "AngleErrorResult",
    "DemagResult",
    "MinSpeedResult",
    "StartupGridResult",
    "VersusHallResult",
    "angle_error",
    "commutations",
    "demag_closed_form",
    "demag_times",
    "demag_voltage",
    "fixed_start",
    "locked",
    "min_sensorless_speed",
    "offset_limit_speed",
    "pair_torque_constant",
    "ramp_current",
    "ramp_duty_at",
    "run_locked",
    "startup_grid",
    "startup_load_bound",
    "versus_hall",
]

_POS = (0, 0, 1, 1, 2, 2)  # phase driven positive in sector s (bc_commutation.h)
_NEG = (1, 2, 2, 0, 0, 1)
_SECTOR = {(_POS[s], _NEG[s]): s for s in range(6)}
_PATTERNS = ("sync", "high", "pwm-on-pwm", "bipolar")


def _wrap(x: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """Angle(s) wrapped to (-pi, pi]."""
    return -((math.pi - np.asarray(x, dtype=float)) % (2.0 * math.pi) - math.pi)


def _pairs(res: SimResult) -> NDArray[np.int64]:
    """Per trace row, the sector of the driven pair at the row's start (-1: not a pair).

    The phase driven positive is the one of the higher mean terminal voltage (PWM, HIGH: the duty; LOW: one minus
    it), so a pair whose continuing leg chops (fast demagnetisation) is the same pair.
    """
    s = res.signals
    modes = np.stack([s["mode_a"], s["mode_b"], s["mode_c"]]).astype(int)
    duty = np.stack([s["duty_a"], s["duty_b"], s["duty_c"]])
    mean = np.where(modes == 3, 1.0 - duty, duty)
    out = np.full(modes.shape[1], -1, dtype=np.int64)
    on = modes != 0
    two = on.sum(axis=0) == 2
    for j in np.nonzero(two)[0]:
        x = np.nonzero(on[:, j])[0]
        a, b = int(x[0]), int(x[1])
        if mean[a, j] == mean[b, j]:
            continue
        pos, neg = (a, b) if mean[a, j] > mean[b, j] else (b, a)
        out[j] = _SECTOR.get((pos, neg), -1)
    return out


def commutations(res: SimResult) -> pd.DataFrame:
    """Return the commutations of a run (forward rotation) from its trace, with the plant's angle at each.

    Parameters
    ----------
    res : SimResult
        A run with a full trace (``trace_every = 1``, any ``trace_sub``); the trace's ``t_at`` locates a commutation
        made by the commutation timer inside a row, one applied at a sample is at its row's start.

    Returns
    -------
    pandas.DataFrame
        One row per commutation from one sector to the next forward: ``t`` (s), ``sector`` (the sector entered),
        ``theta_e`` (the plant's electrical angle there, rad, in [0, 2 pi)), ``error`` (rad, wrapped: the angle
        minus the Hall-exact one ``pi/6 + sector pi/3``; positive: late), ``outgoing`` (the phase that left the
        pair, 0..2), ``i_out`` (its current at the commutation, A), ``timed`` (made by the commutation timer).
    """
    s = res.signals
    t = np.asarray(res.t, dtype=float)
    if len(t) < 3:
        raise BldclabError("result", "needs a trace of at least three rows")
    if np.any(np.diff(t) <= 0.0):
        raise BldclabError("result", "needs a trace whose rows are in time order (trace_every = 1)")
    pair = _pairs(res)
    t_at = np.asarray(s["t_at"], dtype=float)
    th = np.unwrap(np.asarray(s["theta_e"], dtype=float))
    cur = np.stack([s["i_a"], s["i_b"], s["i_c"]])
    rows = []
    for j in range(1, len(t)):
        a, b = int(pair[j - 1]), int(pair[j])
        if a < 0 or b < 0 or b == a:
            continue
        if b != (a + 1) % 6:
            continue  # not a forward commutation (a restart, a stop)
        timed = bool(t_at[j - 1] >= t[j - 1])
        tc = float(t_at[j - 1]) if timed else float(t[j])
        out_phase = ({_POS[a], _NEG[a]} - {_POS[b], _NEG[b]}).pop()
        theta = float(np.interp(tc, t, th))
        i_out = float(np.interp(tc, t, cur[out_phase]))
        err = float(_wrap(theta - (math.pi / 6.0 + b * math.pi / 3.0)))
        rows.append((tc, b, theta % (2.0 * math.pi), err, out_phase, i_out, timed))
    return pd.DataFrame(rows, columns=["t", "sector", "theta_e", "error", "outgoing", "i_out", "timed"])


def locked(drive: Drive, speed: float, **kw: Any) -> SixStepSensorless:
    """Return the sensorless controller started locked at an imposed mechanical speed (rad/s).

    A direct start (no alignment) whose forced commutation runs at ``speed`` from the start; the stall limit at a
    fifth of it. Further keywords are :class:`~bldclab.control.sensorless.SixStepSensorless` settings (they win).
    """
    base: dict[str, Any] = {"align_time": 0.0, "ramp_start_speed": speed, "ramp_end_speed": speed,
                            "stall_speed": 0.2 * speed}
    base.update(kw)
    return SixStepSensorless(**base)


def _duty(drive: Drive, speed_pu: float, duty: float | None) -> float:
    """Default duty at ``speed_pu``: the pair's back-EMF plus the resistive drop of half the rated current.

    The pair's back-EMF is its sector mean, ``k_pair omega_m`` (:func:`pair_torque_constant`): ``speed_pu`` of the
    bus for the ideal trapezoid (``k_pair = 2 k_phi``), 4.5 % less for the catalog's rounded shapes, whose difference
    would otherwise drive ``0.045 speed_pu V_dc / (2 (R + R_on))`` more current (lu-4kw at 0.5 ``Omega_0``: 55 A,
    above its over-current trip).
    """
    if duty is not None:
        return float(duty)
    emf = pair_torque_constant(drive) * speed_pu * drive.Omega_0 / drive.inverter.V_dc
    return min(1.0, emf + r_total(drive) * drive.motor.I_N / drive.inverter.V_dc)


def run_locked(drive: Drive, speed_pu: float, duty: float, *, periods: float = 20.0, settle: float = 6.0,
               trace_sub: int = 1, control: Control | None = None, **control_kw: Any) -> tuple[SimResult, float]:
    """Run the sensorless drive locked at an imposed speed; return the run and the time the measurement starts.

    Above four PWM periods per sector the forced start locks at that speed and the imposed speed ramps up to
    ``speed_pu`` over the first half of the settling time, the throttle with it in proportion (``duty`` at
    ``speed_pu``), as the back-EMF rises: the current on the way stays near the measured point's.

    Parameters
    ----------
    drive : Drive
    speed_pu : float
        Imposed speed, p.u. of ``Omega_0`` (mechanical), > 0.
    duty : float
        The throttle (duty) in (0, 1].
    periods, settle : float
        Electrical periods measured, and run before (start-up, handover, settling).
    trace_sub : int
        Trace rows per sample.
    control : Control, optional
        A controller to run instead of the locked sensorless one (e.g. Hall six-step, for the comparison).
    **control_kw
        :class:`~bldclab.control.sensorless.SixStepSensorless` settings.

    Returns
    -------
    SimResult
        The run, its metric window the measured periods.
    float
        The start of the measured periods (s).
    """
    if not speed_pu > 0.0:
        raise BldclabError("speed", f"must be > 0 p.u., got {speed_pu!r}")
    if not 0.0 < duty <= 1.0:
        raise BldclabError("duty", f"must be in (0, 1], got {duty!r}")
    w_m = speed_pu * drive.Omega_0
    p = drive.motor.p
    w_e = p * w_m
    period = 2.0 * math.pi / w_e
    ts = 0.5 / drive.inverter.f_pwm
    # the forced start locks at most at four PWM periods per sector; faster, the imposed speed then ramps up to the
    # speed over half the settling time (the closed loop follows, the locked start would not hand over)
    w_lock = min(w_e, (math.pi / 3.0) / (8.0 * ts))
    ctl = control if control is not None else locked(drive, w_lock / p, **control_kw)
    t0 = settle * period
    dur = (settle + periods) * period
    th0 = 5.0 * math.pi / 6.0 - w_lock * ts + 1e-3  # the rotor enters sector 2 when the first output applies
    speed: Any = w_m
    ref: Any = duty
    if w_lock < w_e:
        t_up = 0.5 * t0
        speed = lambda t: (w_lock + (w_e - w_lock) * np.clip(t / t_up, 0.0, 1.0)) / p  # noqa: E731
        # the throttle rises with the speed (as the back-EMF does), so the current on the way stays near the
        # measured point's: the full throttle at the lock speed drives the current of a back-EMF at less than half
        # the speed, and its clamp hides the crossing (f60prov-2550kv at 0.9 Omega_0, full duty: ZC_HIDDEN 0.6 ms
        # after the lock, where the point itself holds with its clamp at 0.4 of the window)
        ref = lambda t: duty * (w_lock + (w_e - w_lock) * np.clip(t / t_up, 0.0, 1.0)) / w_e  # noqa: E731
    res = simulate(drive, ctl, Scenario(duration=dur, speed=speed, ref=ref, theta0=th0, trace_sub=trace_sub,
                                        window=(t0, dur)), check="warn")
    return res, t0


@dataclass(frozen=True)
class AngleErrorResult:
    """Commutation angle error against the intended instant, per speed (:func:`angle_error`).

    Attributes
    ----------
    speeds : tuple of float
        Imposed speeds, p.u. of ``Omega_0``.
    advance : float
        The advance the controller means (rad): the intended instant is the Hall-exact one minus it.
    mean, rms, worst : tuple of float
        Mean, root-mean-square and largest magnitude of the error (electrical degrees; positive: late).
    count : tuple of int
        Commutations measured.
    in_sync : tuple of bool
        The drive stayed in closed loop over the measured periods.
    """

    speeds: tuple[float, ...]
    advance: float
    mean: tuple[float, ...]
    rms: tuple[float, ...]
    worst: tuple[float, ...]
    count: tuple[int, ...]
    in_sync: tuple[bool, ...]

    def to_pandas(self) -> pd.DataFrame:
        """Return one row per speed."""
        return pd.DataFrame({"speed_pu": self.speeds, "mean_deg": self.mean, "rms_deg": self.rms,
                             "worst_deg": self.worst, "count": self.count, "in_sync": self.in_sync})


def _in_sync(res: SimResult, t0: float) -> bool:
    st = res.signals["state"][res.t >= t0]
    return bool(len(st) > 0 and np.all(st == 3) and "DESYNC" not in res.meta["flags"] and
                "SAFE" not in res.meta["flags"])


def angle_error(drive: Drive, speeds: Sequence[float], *, duty: float | None = None, periods: float = 20.0,
                **control_kw: Any) -> AngleErrorResult:
    """Commutation angle error of the sensorless drive against the intended instant, at imposed speeds.

    The intended instant is the Hall-exact one (30 electrical degrees after the floating phase's true back-EMF zero
    crossing, ``theta_e = pi/6 + s pi/3``) minus the advance the controller is set to (``timing``; 0 by default).
    The error is the plant's angle at each commutation minus that, over ``periods`` electrical periods after the
    handover and settling.

    Parameters
    ----------
    drive : Drive
    speeds : sequence of float
        Imposed speeds, p.u. of ``Omega_0``.
    duty : float, optional
        The throttle; default the back-EMF's duty at the speed plus the resistive drop of half ``I_N``.
    periods : float
        Electrical periods measured per speed.
    **control_kw
        :class:`~bldclab.control.sensorless.SixStepSensorless` settings (``method``, ``chopping``, ``timing``...).

    Returns
    -------
    AngleErrorResult
    """
    adv = float(SixStepSensorless(**{k: v for k, v in control_kw.items() if k == "timing"}).timing)
    if control_kw.get("timing_time") or control_kw.get("timing_demag"):
        raise BldclabError("control", "angle_error measures against a fixed advance: give timing only")
    out: dict[str, list[Any]] = {k: [] for k in ("mean", "rms", "worst", "count", "in_sync")}
    for sp in speeds:
        res, t0 = run_locked(drive, float(sp), _duty(drive, float(sp), duty), periods=periods, **control_kw)
        c = commutations(res)
        e = np.degrees(c["error"].to_numpy()[c["t"].to_numpy() >= t0] + adv)
        out["mean"].append(float(np.mean(e)) if len(e) else math.nan)
        out["rms"].append(float(np.sqrt(np.mean(e * e))) if len(e) else math.nan)
        out["worst"].append(float(np.max(np.abs(e))) if len(e) else math.nan)
        out["count"].append(len(e))
        out["in_sync"].append(_in_sync(res, t0))
    return AngleErrorResult(tuple(float(x) for x in speeds), adv, tuple(out["mean"]), tuple(out["rms"]),
                            tuple(out["worst"]), tuple(out["count"]), tuple(out["in_sync"]))


@dataclass(frozen=True)
class VersusHallResult:
    """The sensorless drive beside Hall six-step at equal duty and speed (:func:`versus_hall`).

    Attributes
    ----------
    speeds : tuple of float
        Imposed speeds, p.u. of ``Omega_0``.
    duties : tuple of float
        The duty of both drives at each speed.
    torque_sl, torque_hall : tuple of float
        Mean torque (N m).
    efficiency_sl, efficiency_hall : tuple of float
        Mechanical power over source power.
    ripple_sl, ripple_hall : tuple of float
        Current ripple: the rms deviation of the largest phase current magnitude from its mean, over its mean.
    in_sync : tuple of bool
        The sensorless drive stayed in closed loop over the measured periods.
    duty_applied : tuple of float
        The sensorless drive's mean applied duty over the measured periods: below ``duties`` where its limits
        (the speed-dependent duty limit, the demagnetisation limiter) acted, and the comparison is then not at equal
        duty.
    torque_target : tuple of float
        The torque the duty was sought for, ``k_pair I_N / 2`` (N m); nan where the duty was given. Where Hall
        six-step cannot reach it (``duties`` 1; e.g. the drone motors at 0.9 ``Omega_0``, whose inductance takes the
        current) the comparison is at full duty: :meth:`to_pandas`'s ``hall_share``, the Hall drive's torque over
        it, says so.
    """

    speeds: tuple[float, ...]
    duties: tuple[float, ...]
    torque_sl: tuple[float, ...]
    torque_hall: tuple[float, ...]
    efficiency_sl: tuple[float, ...]
    efficiency_hall: tuple[float, ...]
    ripple_sl: tuple[float, ...]
    ripple_hall: tuple[float, ...]
    in_sync: tuple[bool, ...]
    duty_applied: tuple[float, ...]
    torque_target: tuple[float, ...] = ()

    def to_pandas(self) -> pd.DataFrame:
        """Return one row per speed, with ``torque_rel`` and ``hall_share``.

        ``torque_rel``: the relative torque difference (sensorless over Hall, minus one); ``hall_share``: Hall
        six-step's torque over the target torque (nan without one).
        """
        d = dataclasses.asdict(self)
        if not d["torque_target"]:
            d["torque_target"] = (math.nan,) * len(self.speeds)
        df = pd.DataFrame(d)
        df.insert(0, "speed_pu", df.pop("speeds"))
        df["torque_rel"] = df["torque_sl"] / df["torque_hall"] - 1.0
        df["hall_share"] = df["torque_hall"] / df["torque_target"]
        return df


def _ripple(res: SimResult, t0: float) -> float:
    s = res.signals
    keep = res.t >= t0
    ipk = np.max(np.abs(np.stack([s["i_a"][keep], s["i_b"][keep], s["i_c"][keep]])), axis=0)
    m = float(np.mean(ipk))
    return float(np.std(ipk) / m) if m > 0.0 else math.nan


def _hall_duty(drive: Drive, speed_pu: float, periods: float, control: SixStep, rel_tol: float = 0.02,
               runs: int = 5) -> tuple[float, SimResult]:
    """Return the duty at which Hall six-step gives half the rated current's torque, and that Hall run.

    The torque is ``k_pair I_N / 2`` at the imposed speed (full duty where it cannot be reached). A secant on the
    duty from :func:`_duty`'s estimate, its first slope ``k_pair V_dc / (2 |R + R_on + j omega_e L|)``; at most
    ``runs`` Hall runs, the first within ``rel_tol`` of the torque ending it.
    """
    target = 0.5 * pair_torque_constant(drive) * drive.motor.I_N
    w_e = drive.motor.p * speed_pu * drive.Omega_0
    slope = pair_torque_constant(drive) * drive.inverter.V_dc / (
        2.0 * math.hypot(r_total(drive), w_e * drive.motor.L))
    d = _duty(drive, speed_pu, None)
    best: tuple[float, float, SimResult] | None = None
    prev: tuple[float, float] | None = None
    for _ in range(runs):
        hall, _t0 = run_locked(drive, speed_pu, d, periods=periods, control=control)
        tau = hall.metrics.tau_mean if hall.metrics is not None else 0.0
        if best is None or abs(tau - target) < abs(best[1] - target):
            best = (d, tau, hall)
        if abs(tau - target) <= rel_tol * target or (d >= 1.0 and tau < target):
            break
        if prev is not None and tau != prev[1]:
            slope = (tau - prev[1]) / (d - prev[0])
        prev = (d, tau)
        d = min(1.0, max(0.0, d + (target - tau) / slope)) if slope > 0.0 else d
        if d == prev[0]:
            break
    assert best is not None
    return best[0], best[2]


def versus_hall(drive: Drive, speeds: Sequence[float], *, duty: float | None = None, periods: float = 20.0,
                chopping: Literal["sync", "high", "pwm-on-pwm", "bipolar"] = "sync", **control_kw: Any
                ) -> VersusHallResult:
    """Torque, efficiency and current ripple of the sensorless drive and of Hall six-step at equal duty and speed.

    Hall six-step is :class:`~bldclab.control.SixStep` with ``regulation="duty"`` (an ESC's throttle), the same
    chopping pattern, commutating at the Hall edges' predicted instants with the commutation timer (``timed``).

    Parameters
    ----------
    drive : Drive
    speeds : sequence of float
        Imposed speeds, p.u. of ``Omega_0``.
    duty : float, optional
        The duty of both; default the duty at which Hall six-step gives the torque of half the rated current,
        ``k_pair I_N / 2`` (a secant over at most five Hall runs, from the back-EMF's duty plus the drop of half
        ``I_N``; full duty where that torque is out of reach), so that every drive is compared at a comparable load
        (a duty estimated from the back-EMF alone leaves a drive whose ``omega_e L`` exceeds its resistance, or
        whose back-EMF is a few percent off the estimate, at a small fraction of that current).
    periods : float
        Electrical periods measured.
    chopping : {"sync", "high", "pwm-on-pwm", "bipolar"}
        Chopping pattern of both drives.
    **control_kw
        Further :class:`~bldclab.control.sensorless.SixStepSensorless` settings.

    Returns
    -------
    VersusHallResult
    """
    if chopping not in _PATTERNS:
        raise BldclabError("chopping", f"must be one of {', '.join(_PATTERNS)}, got {chopping!r}")
    out: dict[str, list[Any]] = {k: [] for k in ("duties", "torque_sl", "torque_hall", "efficiency_sl",
                                                 "efficiency_hall", "ripple_sl", "ripple_hall", "in_sync",
                                                 "duty_applied")}
    for sp in speeds:
        hall_ctl = SixStep(regulation="duty", chopping=chopping, timed=True)
        if duty is None:
            d, hall = _hall_duty(drive, float(sp), periods, hall_ctl)
        else:
            d = float(duty)
            hall, _ = run_locked(drive, float(sp), d, periods=periods, control=hall_ctl)
        res, t0 = run_locked(drive, float(sp), d, periods=periods, chopping=chopping, **control_kw)
        ms, mh = res.metrics, hall.metrics
        if ms is None or mh is None:
            raise BldclabError("speeds", f"no metric window at {sp} p.u.")  # pragma: no cover - window always set
        out["duties"].append(d)
        out["torque_sl"].append(ms.tau_mean)
        out["torque_hall"].append(mh.tau_mean)
        out["efficiency_sl"].append(ms.efficiency)
        out["efficiency_hall"].append(mh.efficiency)
        out["ripple_sl"].append(_ripple(res, t0))
        out["ripple_hall"].append(_ripple(hall, t0))
        out["in_sync"].append(_in_sync(res, t0))
        out["duty_applied"].append(float(np.mean(res.signals["duty"][res.t >= t0])))
    target = 0.5 * pair_torque_constant(drive) * drive.motor.I_N if duty is None else math.nan
    return VersusHallResult(
        speeds=tuple(float(x) for x in speeds), duties=tuple(out["duties"]), torque_sl=tuple(out["torque_sl"]),
        torque_hall=tuple(out["torque_hall"]), efficiency_sl=tuple(out["efficiency_sl"]),
        efficiency_hall=tuple(out["efficiency_hall"]), ripple_sl=tuple(out["ripple_sl"]),
        ripple_hall=tuple(out["ripple_hall"]), in_sync=tuple(out["in_sync"]), duty_applied=tuple(out["duty_applied"]),
        torque_target=(target,) * len(speeds))


@dataclass(frozen=True)
class MinSpeedResult:
    """The slowest imposed speed at which the sensorless closed loop holds (:func:`min_sensorless_speed`).

    Attributes
    ----------
    speed : float
        The slowest speed found to hold, p.u. of ``Omega_0`` (``lo`` if it held there).
    lost : float
        The fastest speed found to lose the loop (nan if none did).
    tried : tuple of tuple of (float, bool)
        Every speed run and whether it held, in order.
    """

    speed: float
    lost: float
    tried: tuple[tuple[float, bool], ...]

    def to_pandas(self) -> pd.DataFrame:
        """Return the runs (speed p.u., held)."""
        return pd.DataFrame(list(self.tried), columns=["speed_pu", "held"])


def min_sensorless_speed(drive: Drive, *, lo: float = 0.005, hi: float = 0.3, rel_tol: float = 0.03,
                         periods: float = 8.0, duty: float | None = None, **control_kw: Any) -> MinSpeedResult:
    """Slowest imposed speed at which the sensorless closed loop holds, by bisection on the speed.

    A speed holds when the locked start hands over and the drive stays in closed loop, without a desync, for
    ``periods`` electrical periods after settling. The controller's own stall limit is a fifth of the speed tried,
    so the limit found is the sensing's and the detection's (comparator offset and hysteresis, ADC step, noise), not
    a setting. The bisection assumes one boundary between ``lo`` and ``hi``.

    Parameters
    ----------
    drive : Drive
    lo, hi : float
        The range searched, p.u. of ``Omega_0``; ``hi`` must hold.
    rel_tol : float
        Relative width of the final bracket.
    periods : float
        Electrical periods a speed must hold.
    duty : float, optional
        The throttle; default the back-EMF's duty plus the resistive drop of half ``I_N``.
    **control_kw
        :class:`~bldclab.control.sensorless.SixStepSensorless` settings.

    Returns
    -------
    MinSpeedResult
    """
    if not 0.0 < lo < hi:
        raise BldclabError("lo", f"must satisfy 0 < lo < hi, got lo={lo!r}, hi={hi!r}")
    tried: list[tuple[float, bool]] = []

    def holds(sp: float) -> bool:
        res, t0 = run_locked(drive, sp, _duty(drive, sp, duty), periods=periods, settle=4.0, **control_kw)
        ok = _in_sync(res, t0)
        tried.append((sp, ok))
        return ok

    if not holds(hi):
        raise BldclabError("hi", f"the closed loop does not hold at hi = {hi} p.u.: nothing to search")
    if holds(lo):
        return MinSpeedResult(lo, math.nan, tuple(tried))
    a, b = lo, hi  # a loses, b holds
    while b / a - 1.0 > rel_tol:
        mid = math.sqrt(a * b)
        if holds(mid):
            b = mid
        else:
            a = mid
    return MinSpeedResult(b, a, tuple(tried))


def offset_limit_speed(drive: Drive, offset: float, jump: float = 2.0, n: int = 3601) -> float:
    """Return the speed (p.u. of ``Omega_0``) below which a comparator offset loses the loop (a closed form).

    A comparator offset ``V_off`` (terminal volts) moves the crossings it sees by ``delta = V_off / (du/dtheta)``,
    late for one direction of crossing and early for the other (``u`` the comparator's input, the floating phase's
    terminal against the virtual star point, ``(2 e_F - e_p - e_n) / 3`` in a sector, its slope at the crossing
    proportional to the speed). The crossing intervals alternate ``(60 deg +- 2 delta) / Omega_e``, and the
    controller declares a false crossing (``ZC_JUMP``) once their ratio exceeds ``jump``: at ``delta = 30 deg (jump
    - 1) / (jump + 1)`` (10 deg for 2). Solved for the speed with the slope of the drive's back-EMF shape
    (``4 k_phi / pi`` per electrical radian and unit mechanical speed for the ideal trapezoid).

    Parameters
    ----------
    drive : Drive
    offset : float
        Comparator offset, V at the terminal (> 0).
    jump : float
        The controller's largest ratio of successive intervals.
    n : int
        Points per 60 degrees for the slope.

    Returns
    -------
    float
        The speed, p.u. of ``Omega_0``.
    """
    if not offset > 0.0:
        raise BldclabError("offset", f"must be > 0 V, got {offset!r}")
    if drive.sensors.bemf_reference != "star":
        raise BldclabError("sensors.bemf_reference", "the closed form is for the virtual star point")
    m = drive.motor
    slopes = []
    for s in range(6):
        mid = math.pi / 6.0 + s * math.pi / 3.0 + math.pi / 6.0  # the crossing: the sector's middle
        th = np.linspace(mid - 0.05, mid + 0.05, n)
        k = m.emf.k_abc(th)
        f = 3 - _POS[s] - _NEG[s]
        u = (2.0 * k[f] - k[_POS[s]] - k[_NEG[s]]) / 3.0
        slopes.append(abs(float(np.polyfit(th - mid, u, 1)[0])))  # V per (rad/s mech) per electrical rad
    slope = min(slopes)
    delta = math.radians(30.0 * (jump - 1.0) / (jump + 1.0))
    return offset / (slope * delta) / drive.Omega_0


@dataclass(frozen=True)
class DemagResult:
    """Measured demagnetisation times beside their closed forms (:func:`demag_times`).

    Attributes
    ----------
    table : pandas.DataFrame
        One row per commutation: ``t`` (s), ``outgoing`` (phase), ``i_out`` (A), ``sign`` (+1: the outgoing current
        was positive, clamped to 0 V), ``measured`` (s, from the commutation to the outgoing current's zero),
        ``simple`` (s, ``3 L |I| / (S + B)``), ``closed`` (s, the outgoing phase's law integrated with ``R`` and the
        back-EMF's motion), ``tau_ratio`` (measured time over ``L / (R + R_on)``).
    """

    table: pd.DataFrame

    def to_pandas(self) -> pd.DataFrame:
        """Return the table."""
        return self.table.copy()


def demag_voltage(pattern: str, duty: float, sign: int, fast_demag: bool) -> float:
    """Return the demagnetisation voltage ``S`` of a chopping pattern, per volt of bus (``S / V_dc``).

    During the clamp the outgoing phase ``F``'s current obeys (averaged over the PWM, all three phases conducting,
    ``v_n`` from the three terminals)

        L di_F/dt = (2 v_F - v_p - v_n) / 3 - (2 e_F - e_p - e_n) / 3 - R i_F

    with ``v_F`` its clamp (0 V for a positive current, ``V_dc`` for a negative one) and ``v_p``, ``v_n`` the means
    of the pair's legs. The current falls to zero against ``S = v_p + v_n`` (positive) or ``2 V_dc - v_p - v_n``
    (negative). The pair's duty ``d`` is ``(v_p - v_n) / V_dc``; the leg that chops sets the sum: the positive leg
    chopping (``sync``, ``high``) gives ``v_p + v_n = d V_dc``, the negative one ``(2 - d) V_dc``, both
    (``bipolar``) ``V_dc``. With ``fast_demag`` the continuing phase chops during the clamp, which is the negative
    leg after a positive outgoing current and the positive leg after a negative one: ``S = (2 - d) V_dc`` either way.
    ``pwm-on-pwm`` chops the incoming phase in the first half of the sector: ``S = d V_dc`` either way.

    Parameters
    ----------
    pattern : {"sync", "high", "pwm-on-pwm", "bipolar"}
    duty : float
        The pair's duty ``d`` (the bipolar pattern's ``m``).
    sign : {1, -1}
        Sign of the outgoing current.
    fast_demag : bool
        The sensorless controller's fast demagnetisation (not with ``bipolar``).

    Returns
    -------
    float
        ``S / V_dc``.
    """
    if pattern not in _PATTERNS:
        raise BldclabError("chopping", f"must be one of {', '.join(_PATTERNS)}, got {pattern!r}")
    if pattern == "bipolar":
        return 1.0
    if fast_demag:
        return 2.0 - duty
    if pattern == "pwm-on-pwm":
        return duty
    return duty if sign > 0 else 2.0 - duty  # the positive leg chops


def demag_closed_form(drive: Drive, i_out: float, sign: int, theta_c: float, outgoing: int, sector: int,
                      omega_e: float, s_volts: float, n: int = 4000) -> tuple[float, float]:
    """Return the outgoing current's fall time after a commutation, in two closed forms.

    ``simple = 3 L |I| / (S + B)``, ``B = s (2 e_F - e_p - e_n)`` at the commutation (``s`` the current's sign; the
    ideal trapezoid at the Hall-exact instant: ``B = 2 E``, ``E = k_phi omega_m``; with R and the back-EMF's motion
    neglected). ``closed``: the law of :func:`demag_voltage` with ``R = R + R_on`` and the back-EMF's shapes moving
    with the rotor integrated from ``|I|`` to zero (trapezoidal rule on ``n`` steps over the first 60 degrees).

    Parameters
    ----------
    drive : Drive
    i_out : float
        The outgoing current at the commutation (A).
    sign : {1, -1}
        Its sign.
    theta_c : float
        The electrical angle at the commutation (rad).
    outgoing : int
        The outgoing phase (0..2).
    sector : int
        The sector entered (its pair: ``p``, ``n``).
    omega_e : float
        Electrical speed (rad/s).
    s_volts : float
        The demagnetisation voltage ``S`` (V).
    n : int
        Integration steps.

    Returns
    -------
    tuple of float
        ``simple`` and ``closed`` (s); ``inf`` when the current does not reach zero within 60 degrees.
    """
    m = drive.motor
    w_m = omega_e / m.p
    r = r_total(drive)
    p, q, f = _POS[sector], _NEG[sector], outgoing

    def b_of(theta: NDArray[np.float64]) -> NDArray[np.float64]:
        k = m.emf.k_abc(theta)
        return sign * w_m * (2.0 * k[f] - k[p] - k[q])

    b0 = float(b_of(np.array([theta_c]))[0])
    i0 = abs(i_out)
    simple = 3.0 * m.L * i0 / (s_volts + b0) if s_volts + b0 > 0.0 else math.inf
    t_end = (math.pi / 3.0) / omega_e
    tt = np.linspace(0.0, t_end, n + 1)
    h = tt[1]
    bb = b_of(theta_c + omega_e * tt)
    i = i0
    a = r / m.L
    for j in range(n):  # L di/dt = -(S + B)/3 - R i on the current's magnitude, exact for B linear over a step
        g0, g1 = (s_volts + bb[j]) / (3.0 * m.L), (s_volts + bb[j + 1]) / (3.0 * m.L)
        e = math.exp(-a * h)
        if a * h > 1e-12:
            # i(h) = e i - integral of g(s) exp(-a (h - s)) ds, g linear from g0 to g1
            c1 = (1.0 - e) / a
            c2 = (h - c1) / a  # integral of (s / h) exp(-a (h - s)) ds, times h
            i_new = e * i - (g0 * c1 + (g1 - g0) / h * c2)
        else:
            i_new = i - 0.5 * (g0 + g1) * h
        if i_new <= 0.0:
            # the zero inside the step, linearly
            return simple, float(tt[j] + h * i / (i - i_new))
        i = i_new
    return simple, math.inf


def demag_times(res: SimResult, drive: Drive, *, chopping: str, fast_demag: bool, after: float = 0.0
                ) -> DemagResult:
    """Measure the demagnetisation time after each commutation of a run and put the closed forms beside it.

    The measured time runs from the commutation (:func:`commutations`) to the end of the outgoing current: the
    plant's own instant of it (trace signals ``t_iz_a`` .. ``t_iz_c``: the diode turning off, an event the plant
    locates), or on a trace without them the first row where that current is exactly zero, located inside the row
    before by extrapolating the last two rows' currents linearly to zero. The duty is the controller's (diag
    ``duty``) at the commutation, the speed the plant's.

    Parameters
    ----------
    res : SimResult
        A sensorless run with a full trace (one row per sample is enough: the end is the plant's event).
    drive : Drive
        The drive of the run.
    chopping : {"sync", "high", "pwm-on-pwm", "bipolar"}
        The run's chopping pattern.
    fast_demag : bool
        Whether the run's controller used fast demagnetisation.
    after : float
        Only commutations after this time (s).

    Returns
    -------
    DemagResult
    """
    c = commutations(res)
    c = c[c["t"] >= after]
    s = res.signals
    t = np.asarray(res.t, dtype=float)
    cur = np.stack([s["i_a"], s["i_b"], s["i_c"]])
    t_iz = np.stack([s["t_iz_a"], s["t_iz_b"], s["t_iz_c"]]) if "t_iz_a" in s else None
    duty = np.asarray(s["duty"], dtype=float)
    w_e = drive.motor.p * np.asarray(s["omega_m"], dtype=float)
    tau = drive.motor.L / r_total(drive)
    rows = []
    for tc, sec, th, out, i0 in zip(c["t"], c["sector"], c["theta_e"], c["outgoing"], c["i_out"], strict=True):
        if abs(i0) < 1e-6:
            continue
        j = int(np.searchsorted(t, tc, side="right"))
        if t_iz is not None:  # the plant's own instant: the first end of the outgoing current after the commutation
            ends = t_iz[int(out), max(j - 1, 0):]
            hit = np.flatnonzero(ends >= tc)
            if not hit.size:
                continue
            t_zero = float(ends[hit[0]])
        else:
            ii = cur[int(out)]
            k = j
            while k < len(t) and ii[k] != 0.0:
                k += 1
            if k >= len(t) or k < j + 1:
                continue
            # last two nonzero rows before the zero: extrapolate to zero
            x0, x1, y0, y1 = t[k - 2], t[k - 1], ii[k - 2], ii[k - 1]
            if k - 2 < j - 1 or y0 == y1:
                t_zero = t[k]
            else:
                t_zero = float(x1 - y1 * (x1 - x0) / (y1 - y0))
                t_zero = min(max(t_zero, x1), t[k])
        sign = 1 if i0 > 0 else -1
        jd = max(0, min(len(t) - 1, int(np.searchsorted(t, tc)) - 1))
        d = float(duty[jd])
        w = float(np.interp(tc, t, w_e))
        s_v = demag_voltage(chopping, d, sign, fast_demag) * drive.inverter.V_dc
        simple, closed = demag_closed_form(drive, i0, sign, th, int(out), int(sec), w, s_v)
        meas = t_zero - tc
        rows.append((tc, int(out), i0, sign, d, meas, simple, closed, meas / tau))
    table = pd.DataFrame(rows, columns=["t", "outgoing", "i_out", "sign", "duty", "measured", "simple", "closed",
                                        "tau_ratio"])
    return DemagResult(table)


# ------------------------------------------------------------------------------------------------------------
# start-up over load torque x inertia x initial rotor angle

#: The controller's flags that name a failed start (bc_types.h), in the order a tie is named: a desync's reason
#: (raised at the same sample as ``DESYNC``) before ``DESYNC`` itself.
START_FAILURES = ("START_FAIL", "STALL", "ZC_TIMEOUT", "ZC_JUMP", "ZC_HIDDEN", "DESYNC", "OVERCURRENT", "SAFE")
_START_KEYS = ("align_current", "align_duty", "align_time", "ramp_duty", "ramp_vf", "ramp_tau", "ramp_time",
               "start_current_limit", "stall_speed", "ramp_start_speed", "ramp_end_speed")


def fixed_start(drive: Drive, control: SixStepSensorless | None = None) -> SixStepSensorless:
    """Return ``control`` with its start-up settings fixed to those it derives for ``drive``.

    An ESC's start-up is set once for its motor; a heavier load or propeller does not change it. Fixed, the settings
    stay those of ``drive`` when a study changes the plant's inertia or load.
    """
    ctl = SixStepSensorless() if control is None else control
    su = ctl.start_up(drive)
    fixed: dict[str, Any] = {k: su[k] for k in _START_KEYS}
    return dataclasses.replace(ctl, **fixed)


def pair_torque_constant(drive: Drive, n: int = 721) -> float:
    """Return the largest sector-mean torque per ampere of a six-step pair (N m/A), from the back-EMF's shapes.

    Forced commutation holds the current ``I`` in the pair ``p``, ``n`` for 60 electrical degrees; the rotor takes
    the lag at which the pair's torque ``(k_p - k_n) I`` balances the load. The largest torque it can find is the
    maximum over the commutation angle of the sector-mean of ``k_p - k_n`` (``2 k_phi`` for the ideal trapezoid
    with a flat top of 120 degrees or more; ``3 sqrt(3) / pi k_phi``-like values for a sinusoid).
    """
    m = drive.motor
    best = 0.0
    for c in np.linspace(0.0, math.pi / 3.0, 61):
        th = np.linspace(c, c + math.pi / 3.0, n)
        k = m.emf.k_abc(th)
        best = max(best, float(np.mean(k[_POS[0]] - k[_NEG[0]])))
    return best


def ramp_duty_at(start_up: dict[str, float], omega_e: float) -> float:
    """Return the forced ramp's duty at the electrical speed ``omega_e`` (rad/s) for the settings ``start_up``.

    ``ramp_duty sqrt(1 + (omega_e ramp_tau)^2) + ramp_vf omega_e``, at most 1 (``bc_bemf.h``, law 2), with the
    settings of :meth:`~bldclab.control.sensorless.SixStepSensorless.start_up`.
    """
    x = omega_e * start_up["ramp_tau"]
    return min(1.0, start_up["ramp_duty"] * math.sqrt(1.0 + x * x) + start_up["ramp_vf"] * omega_e)


def ramp_current(drive: Drive, control: SixStepSensorless, omega_m: float) -> float:
    """Return the current (A) the forced ramp's duty drives in the pair at the mechanical speed ``omega_m``, in step.

    The rotor in step with the forced commutation at ``omega_m``: the pair's back-EMF is ``k_pair omega_m``
    (:func:`pair_torque_constant`), and the duty's excess over it drives the current through the pair's impedance at
    the electrical speed ``omega_e = p omega_m`` (its fundamental, ``2 |R + R_on + j omega_e L|``)::

        I = (d(omega_e) V_dc - k_pair omega_m) / (2 (R + R_on) sqrt(1 + (omega_e L / (R + R_on))^2))

    with ``d`` :func:`ramp_duty_at`. With the defaults (``ramp_vf = 2 k_phi / (p V_dc)``, ``ramp_tau = L / (R +
    R_on)``) the back-EMF and the impedance cancel for the trapezoid and ``I`` is the alignment current at every
    speed; with ``ramp_tau = 0`` it falls as ``1 / sqrt(1 + (omega_e L / (R + R_on))^2)``.
    """
    su = control.start_up(drive)
    m, r = drive.motor, r_total(drive)
    w_e = m.p * omega_m
    x = w_e * m.L / r
    v = ramp_duty_at(su, w_e) * drive.inverter.V_dc - pair_torque_constant(drive) * omega_m
    return max(v, 0.0) / (2.0 * r * math.sqrt(1.0 + x * x))


def startup_load_bound(drive: Drive, control: SixStepSensorless, inertia: float | None = None) -> float:
    """Return the largest added load torque (N m) the forced start-up can carry (a closed form).

    The forced pair's torque, averaged over a sector, is largest when the rotor is in step with the forced
    commutation (the Hall-exact instant), ``k_pair I`` (:func:`pair_torque_constant`; ``2 k_phi I`` for the ideal
    trapezoid), and falls on either side; for the trapezoid with a rotor lagging ``delta`` (electrical) it is ``k_pair
    I (1 - delta^2 / (2 (pi/3)^2))``. A rotor that lags therefore gets less torque and lags more: it must follow the
    ramp's acceleration ``a = (Omega_end - Omega_start) / t_ramp`` in step, which takes ``J a``; friction and
    propeller take ``tau_c + B Omega_end + k_q Omega_end^2`` (their largest, at the end speed). A Coulomb load
    ``tau_L`` (with the drive's ``tau_c``) stops the aligning rotor where the alignment's torque ``K delta_m`` meets
    it, ``K = (6/pi) p k_phi I_align`` (the trapezoid's slope): the ramp starts with the rotor up to ``delta = p
    (tau_L + tau_c) / K`` (electrical, at most a sector) behind. The current is the smaller of :func:`ramp_current`
    at the ramp's start and end speeds (the inductance counted: ``|R + j Omega_e L|``). The bound is the load that
    leaves nothing over::

        k_pair I (1 - delta(tau_L)^2 / (2 (pi/3)^2)) - J a - tau_c - B Omega_end - k_q Omega_end^2 = tau_L

    (``delta`` grows with the load: solved by bisection). It neglects the extra current the V/f term drives while
    the rotor lags (which helps) and the current's dip at each commutation (the commutation interval, which takes
    some of the torque).

    Parameters
    ----------
    drive : Drive
        The drive (its friction and propeller; its inertia unless ``inertia`` is given).
    control : SixStepSensorless
        The controller (its start-up settings, :meth:`~bldclab.control.sensorless.SixStepSensorless.start_up`).
    inertia : float, optional
        The plant's inertia (kg m^2), if not the drive's.

    Returns
    -------
    float
        The bound (N m); negative: the ramp cannot be followed even unloaded.
    """
    su = control.start_up(drive)
    mech, m = drive.mechanics, drive.motor
    j = mech.J if inertia is None else float(inertia)
    w0, w_end = su["ramp_start_speed"], su["ramp_end_speed"]
    i_min = min(ramp_current(drive, control, w0), ramp_current(drive, control, w_end))
    accel = (w_end - w0) / su["ramp_time"]
    rest = j * accel + mech.tau_c + mech.B * w_end + mech.k_q * w_end * w_end
    top = pair_torque_constant(drive) * i_min
    k_align = 6.0 / math.pi * m.p * m.k_phi * su["align_current"]  # N m per mechanical rad
    sector = math.pi / 3.0

    def spare(load: float) -> float:
        """Return the torque left over with ``load`` added (N m).

        The pair's, less for a rotor the load leaves behind the aligned angle, minus what the ramp and the drive
        take and the load itself.
        """
        lag = min(m.p * (load + mech.tau_c) / k_align, sector) if k_align > 0.0 else sector
        return top * (1.0 - lag * lag / (2.0 * sector * sector)) - rest - load

    if spare(0.0) <= 0.0:
        return spare(0.0)
    lo, hi = 0.0, top
    for _ in range(60):  # spare() falls with the load: bisection to its zero
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if spare(mid) > 0.0 else (lo, mid)
    return lo


@dataclass(frozen=True)
class StartupGridResult:
    """Start-up attempts over load torque x inertia x initial rotor angle (:func:`startup_grid`).

    Attributes
    ----------
    points : pandas.DataFrame
        One row per attempt: ``load`` (added load torque, N m, Coulomb: against the motion, none at rest),
        ``inertia`` (kg m^2), ``angle`` (initial electrical angle, rad), ``bound`` (:func:`startup_load_bound` at
        that inertia, N m), ``success`` (closed loop reached and held to the end with no failure flag),
        ``failure`` (the first failure flag the controller raised, a name of :data:`START_FAILURES`, ``"NO_HANDOVER"``
        if it raised none and never reached closed loop, ``""`` on success), ``t_closed`` (time from the start to
        the first closed-loop sample, s; nan if never), ``speed_end`` (the rotor's mean mechanical speed over the
        last 5 % of the run, rad/s: a failed start with the rotor turning is the controller's miss, not the load's),
        ``duration`` (s, the run).
    """

    points: pd.DataFrame

    def to_pandas(self) -> pd.DataFrame:
        """Return the attempts."""
        return self.points.copy()

    @property
    def successes(self) -> int:
        """Number of successful starts."""
        return int(self.points["success"].sum())

    @property
    def attempts(self) -> int:
        """Number of attempts."""
        return len(self.points)

    def median_time(self) -> float:
        """Median time to closed loop over the successes (s; nan if none)."""
        ok = self.points[self.points["success"]]
        return float(np.median(ok["t_closed"])) if len(ok) else math.nan

    def within_bound(self) -> tuple[int, int]:
        """Successes and attempts among the points whose load is within their bound."""
        p = self.points[self.points["load"] <= self.points["bound"]]
        return int(p["success"].sum()), len(p)


#: One start-up attempt: drive (load and inertia applied), controller, throttle, angle, duration.
_StartJob = tuple[Drive, SixStepSensorless, float, float, float]


def _run_start(job: _StartJob) -> dict[str, Any]:
    drive, ctl, throttle, angle, duration = job
    res = simulate(drive, ctl, Scenario(duration=duration, ref=throttle, theta0=angle, trace_every=4),
                   check="warn")
    st = np.asarray(res.signals["state"])
    t = np.asarray(res.t)
    closed = st == 3
    t_closed = float(t[int(np.argmax(closed))]) if closed.any() else math.nan
    flags = res.meta["flags"]
    raised = sorted((float(flags[k]["run"]["first"]), START_FAILURES.index(k), k) for k in START_FAILURES
                    if k in flags)
    success = bool(not raised and closed.any() and closed[-1])
    failure = "" if success else (raised[0][2] if raised else "NO_HANDOVER")
    w = np.asarray(res.signals["omega_m"])
    return {"success": success, "failure": failure, "t_closed": t_closed,
            "speed_end": float(np.mean(w[-max(1, len(w) // 20):]))}


def startup_grid(drive: Drive, load_torques: Sequence[float], inertias: Sequence[float], angles: Sequence[float],
                 control: SixStepSensorless | None = None, *, throttle: float | None = None,
                 workers: int | None = 1, executor: Executor | None = None) -> StartupGridResult:
    """Start the sensorless drive over a grid of load torque x inertia x initial rotor angle.

    The controller's start-up settings are fixed to those it derives for ``drive`` (:func:`fixed_start`), as an
    ESC's are; each point changes the plant only: its inertia ``J`` and an added Coulomb load (the mechanics'
    ``tau_c``: a torque against the motion that does not turn the rotor at rest). The run lasts the alignment, the
    ramp and ``ramp_hold + 24`` sectors at the ramp's end speed; a start succeeds when the controller reaches closed
    loop, is in it at the end, and raised no failure flag (:data:`START_FAILURES`). The points are independent runs
    and come back in grid order: the result does not depend on ``workers``.

    Parameters
    ----------
    drive : Drive
    load_torques : sequence of float
        Added load torques (N m), >= 0.
    inertias : sequence of float
        Plant inertias (kg m^2), > 0.
    angles : sequence of float
        Initial electrical rotor angles (rad).
    control : SixStepSensorless, optional
        The controller (default settings if omitted).
    throttle : float, optional
        The duty reference in (0, 1]; default the ramp's duty at its end speed, so the closed loop goes on with the
        current the ramp had.
    workers : int, optional
        Local processes (``None``: one per CPU; 1: in this process).
    executor : concurrent.futures.Executor, optional
        Where the points run instead (a pool the caller keeps, a Dask client's ``get_executor()``).

    Returns
    -------
    StartupGridResult
    """
    if isinstance(workers, bool) or (workers is not None and (not isinstance(workers, int) or workers < 1)):
        raise BldclabError("workers", f"must be an integer >= 1, got {workers!r}")
    if control is not None and not isinstance(control, SixStepSensorless):
        raise BldclabError("control", f"expected a SixStepSensorless, got {type(control).__name__}")
    for name, vals, lo_open in (("load_torques", load_torques, False), ("inertias", inertias, True),
                                ("angles", angles, None)):
        if len(vals) == 0:
            raise BldclabError(name, "needs at least one value")
        for v in vals:
            if not math.isfinite(float(v)) or (lo_open is False and v < 0.0) or (lo_open is True and v <= 0.0):
                raise BldclabError(name, f"must be finite and {'> 0' if lo_open else '>= 0'}, got {v!r}")
    ctl = fixed_start(drive, control)
    su = ctl.start_up(drive)
    if throttle is None:
        throttle = ramp_duty_at(su, drive.motor.p * su["ramp_end_speed"])
    if not 0.0 < throttle <= 1.0:
        raise BldclabError("throttle", f"must be in (0, 1], got {throttle!r}")
    sector = (math.pi / 3.0) / (drive.motor.p * su["ramp_end_speed"])
    duration = su["align_time"] + su["ramp_time"] + (ctl.ramp_hold + 24) * sector
    jobs: list[_StartJob] = []
    keys: list[tuple[float, float, float, float]] = []
    for load in load_torques:
        for j in inertias:
            mech = dataclasses.replace(drive.mechanics, J=float(j), tau_c=drive.mechanics.tau_c + float(load))
            d = dataclasses.replace(drive, mechanics=mech)
            bound = startup_load_bound(drive, ctl, inertia=float(j))
            for a in angles:
                jobs.append((d, ctl, float(throttle), float(a), duration))
                keys.append((float(load), float(j), float(a), bound))
    n_workers = workers or os.cpu_count() or 1
    if executor is not None:
        rows = map_points(_run_start, jobs, executor)
    elif n_workers <= 1 or len(jobs) <= 1:
        rows = map_points(_run_start, jobs)
    else:
        with ProcessPoolExecutor(max_workers=min(n_workers, len(jobs))) as pool:
            rows = map_points(_run_start, jobs, pool)
    df = pd.DataFrame([{"load": k[0], "inertia": k[1], "angle": k[2], "bound": k[3], **r, "duration": duration}
                       for k, r in zip(keys, rows, strict=True)])
    return StartupGridResult(df)

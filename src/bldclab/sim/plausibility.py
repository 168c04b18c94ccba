"""Plausibility guards: checks that a simulation's result is physically meaningful.

:func:`bldclab.simulate` runs these checks before the run (drive, scenario, reference) and after it (the result).
Each check is a pure function returning :class:`Finding` objects (those that need only the drive,
:func:`check_pwm` and :func:`check_speed`, are :mod:`bldclab.model.limits`'s, re-exported here: ``bldclab check``
states them for a motor file in the same words); :func:`apply` turns them into
:class:`~bldclab.errors.PlausibilityWarning` warnings (the run is questionable) or a
:class:`~bldclab.errors.PlausibilityError` (the result would be physically meaningless). Every message names the
cause, the number and the threshold.

Thresholds and why (``T_pwm = 1 / f_pwm``, ``tau_el = L / R``, ``f_e = p |Omega| / (2 pi)``):

* PWM period vs electrical time constant, ``T_pwm / tau_el``: every current controller here (and the paper-1 and
  paper-2 analyses) treats the current as its PWM-period average plus a small ripple, which needs the current to
  change almost linearly within a period, ``T_pwm << tau_el``. Warning above 1 (the current settles within a
  period: a chain of exponentials, not an average with ripple); error above 10 (it settles ten times over: the
  PWM no longer sets a current at all). The catalog drives are at 0.004 to 0.05.
* PWM periods per electrical period, ``f_pwm / f_e``: the controller samples twice per PWM period and applies its
  output one sample later, a lag of ``pi f_e / f_pwm`` electrical radians. Warning below 12 (a lag above
  15 degrees, fewer than four samples per 60-degree commutation sector); error below 3 (fewer than one sample per
  sector: whole commutation steps are missed).
* Imposed speed vs the no-load speed ``Omega_0 = V_dc / (2 k_phi)`` (at the highest bus voltage of the run): above
  it the line back-EMF peak exceeds the bus, the diodes conduct and no controller here (none weakens the field)
  can drive motoring current: warning above ``Omega_0``; error above ``10 Omega_0``, beyond the constant-power
  speed range of any practical permanent-magnet drive (3 to 5, rarely 10). (With a sinusoidal back-EMF, six-step
  voltage, whose fundamental is ``2 sqrt(3) / pi = 1.10`` times the bus, can still motor up to ``1.10 Omega_0``:
  there the warning flags a regime outside the paper-1 comparison rather than a wrong result.)
* With rotor dynamics, the peak speed vs ``Omega_0`` (``check_driven_speed``): the drive alone reaches about
  ``1.05 Omega_0``; a rotor beyond ``1.5 Omega_0`` was driven by its load (a load torque above the drive's spins it
  backwards) or started there: a warning on ``scenario.load_torque``; above ``10 Omega_0`` an error, raised before the
  consequences (too few PWM periods per electrical period at that speed) that would otherwise name ``inverter.f_pwm``.
* Reference vs the drive's limit: the controller's over-current trip ``i_max`` (its default is a multiple of
  ``I_N``), for a torque reference also the motor's ``T_peak`` if larger: warning above the limit (the reference
  cannot be reached without tripping; a reference above the continuous rating ``I_N`` alone is a legitimate short
  test and is not flagged); error above 10 times the limit.
* Energy balance ``Metrics.balance_electrical`` (and ``balance_mechanical`` with rotor dynamics): the plant closes
  it to 1e-9 to 1e-7 on the catalog drives; the residue grows with the electrical frequency per integration step
  (about as ``(omega_e h)^4``), the largest measured on a legitimate run being 4.6e-5 (sinusoidal supply at
  0.995 ``Omega_0`` of a drive with 28 PWM periods per electrical period). Warning above 1e-4 (the energy
  bookkeeping is off by more than 0.01 %); error above 1e-2 (efficiencies wrong by a percent, the size of the
  differences the comparisons resolve: the integration did not resolve the run). A residue whose power is below
  ``BALANCE_FLOOR`` (1e-6) of the drive's rated power ``V_dc I_N`` is not graded: where almost nothing flows (six-step
  at zero duty below the no-load speed, milliamps through the open switches; a frictionless motor at no load, whose
  PWM ripple exchanges far more energy than the net flow) a residue of 1e-8 to 1e-6 W is a large share of the net
  flow but moves no reported power by more than a millionth of the drive's rating.
* Non-finite metrics, states or traced currents/torques/speeds: error.
* Currents after the inverter's hardware trip ``Inverter.i_trip`` (all legs off): they can only decay unless the
  back-EMF drives them through the diodes. Warning above 1.01 ``i_trip``; error above 2 ``i_trip`` (beyond the
  level the trip protects the switches at: a real inverter would fail). Without a hardware trip: error above
  100 ``I_N`` (ten thousand times the rated copper loss).
* A drive without a current loop (a duty, an open-loop voltage) whose phase current exceeds ``RATED_CURRENT_WARN``
  (2) times ``I_N``, or the motor's peak current ``T_peak / (2 k_phi)`` if larger: warning ``result.current_rating``
  (at stall and full duty only ``2 (R + R_on)`` limits it, ``V_dc / (2 R)``: 10 ``I_N`` on f60prov-2550kv). A
  hardware trip (``Inverter.i_trip``) that switched the legs off: warning ``result.hardware_trip`` with its time (the
  run's rest, and the metrics after it, are of a drive switched off).
* Discontinuous conduction of a six-step current loop (``SixStep``, predictive, PI or hysteresis regulation):
  every phase current zero for more than ``ZERO_CURRENT_WARN`` (0.1 %) of the metric window
  (``Metrics.zero_current_share``, integrated by the plant) in intervals shorter than a PWM period on average (longer
  ones are a drive switched off): warning ``result.discontinuous_conduction``. Without it, the estimated PWM ripple of
  the pair current (:func:`pwm_ripple`, ``V_dc d (1 - d) / (2 L f_pwm)``) above the reference current: warning
  ``result.current_ripple``. The regulators sample the current at the carrier extremes, its period mean only while
  the ripple is small against it; below that the mean torque misses the reference (a 30 uH, 16 kHz drive at half
  its no-load speed: 3.1 times the reference's torque at 0.5 A, 1.08 at 2 A, within 4 % from 3 A, the ripple being
  4.4 A peak-to-peak).
* Steady state of the metric window with rotor dynamics: the relative speed change across the window,
  ``|dW_kin| / (J Omega_mean^2)``, above 1 %, or the mean torques of the window's two halves differing by more
  than 5 % of ``max(|tau_mean|, 0.1 T_N)``: warning (the window still holds a run-up).
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ..control import Control
from ..errors import PlausibilityError, PlausibilityWarning
from ..model.limits import (
    PWM_PER_PERIOD_ERROR,
    PWM_PER_PERIOD_WARN,
    PWM_TAU_ERROR,
    PWM_TAU_WARN,
    SPEED_ERROR_PU,
    Finding,
    check_pwm,
    check_speed,
)
from ..model.limits import grade as _grade
from ..model.motor import Drive
from .results import SimResult

__all__ = [
    "BALANCE_ERROR",
    "BALANCE_FLOOR",
    "BALANCE_WARN",
    "CHECK_MODES",
    "PWM_PER_PERIOD_ERROR",
    "PWM_PER_PERIOD_WARN",
    "PWM_TAU_ERROR",
    "PWM_TAU_WARN",
    "RATED_CURRENT_WARN",
    "SPEED_ERROR_PU",
    "ZERO_CURRENT_WARN",
    "Finding",
    "RowSummary",
    "apply",
    "cause_first",
    "cause_of",
    "check_conduction",
    "check_current_rating",
    "check_driven_speed",
    "check_pwm",
    "check_reference",
    "check_result",
    "check_speed",
    "check_steady",
    "collect",
    "distinct",
    "peak_current",
    "pwm_ripple",
    "summary",
]

@dataclass(frozen=True)
class RowSummary:
    """What the C runner gathered over the trace rows it wrote (``bc_sim_state.row_peak``, ``row_nonfinite``).

    It spares :func:`check_result` the strided passes over the record array (one per signal) that would find the
    same: while ``nonfinite`` is false, every traced ``i_x``, ``tau_e`` and ``omega_m`` is finite and ``peak`` holds
    their largest magnitudes, exactly what ``np.max(np.abs(signal))`` gives.

    Attributes
    ----------
    peak : tuple of float
        Largest ``|i_a|``, ``|i_b|``, ``|i_c|`` (A) and ``|omega_m|`` (rad/s) of the rows.
    nonfinite : bool
        A row holds a non-finite ``i_x``, ``tau_e`` or ``omega_m`` (then the checks scan the signals themselves, to
        name the first).
    """

    peak: tuple[float, float, float, float]
    nonfinite: bool


#: Accepted values of ``simulate(..., check=)``.
CHECK_MODES = ("error", "warn", "off")

REF_ERROR_FACTOR = 10.0
BALANCE_WARN = 1e-4
BALANCE_ERROR = 1e-2
BALANCE_FLOOR = 1e-6
TRIP_WARN = 1.01
TRIP_ERROR = 2.0
CURRENT_ERROR_IN = 100.0
STEADY_SPEED = 0.01
STEADY_TORQUE = 0.05
#: Share of the metric window with every phase current zero above which a current-regulated run is reported as
#: discontinuous conduction (``Metrics.zero_current_share``; 0 in continuous conduction, whatever the drive).
ZERO_CURRENT_WARN = 1e-3


def _reference_kind(control: Control) -> str | None:
    """Return ``"current"``, ``"torque"`` or ``None`` (a duty, an open-loop command or a speed loop's output)."""
    if getattr(control, "speed_loop", False) or getattr(control, "regulation", None) == "duty":
        return None  # the output of a speed loop, or a duty (six-step without a current loop)
    if control.ref_meaning.startswith("current"):
        return str(getattr(control, "reference", "current"))
    if control.ref_meaning.startswith("torque"):
        return "torque"
    return None


def check_reference(drive: Drive, control: Control, ref_max: float, i_limit: float | None) -> list[Finding]:
    """Check a current or torque reference against the drive's limit.

    Parameters
    ----------
    drive : Drive
    control : Control
        The controller (its ``ref_meaning`` says what the reference is).
    ref_max : float
        Largest magnitude of the reference over the run (A or N m).
    i_limit : float or None
        The controller's over-current trip (A), ``None`` if it has none (then ``2 I_N``).

    Returns
    -------
    list of Finding
    """
    kind = _reference_kind(control)
    if kind is None or not math.isfinite(ref_max):
        return []
    m = drive.motor
    i_lim = i_limit if i_limit is not None and i_limit > 0 else 2.0 * m.I_N
    if kind == "current":
        limit, unit, what = i_lim, "A", f"the controller's current limit i_max = {i_lim:.4g} A"
    else:
        limit = 2.0 * m.k_phi * i_lim
        what = f"the torque at the controller's current limit, 2 k_phi i_max = {limit:.4g} N m"
        if m.T_peak is not None and m.T_peak > limit:
            limit, what = m.T_peak, f"the motor's peak torque T_peak = {m.T_peak:.4g} N m"
        unit = "N m"
    level = _grade(ref_max / limit, 1.0 + 1e-9, REF_ERROR_FACTOR)
    if not level:
        return []
    return [Finding(level, "scenario.ref",
                    f"the {kind} reference {ref_max:.4g} {unit} is {ref_max / limit:.3g} times {what} (rated "
                    f"I_N = {m.I_N:.4g} A; error above {REF_ERROR_FACTOR:g} times the limit)")]


def _nonfinite(res: SimResult, rows: RowSummary | None = None) -> list[str]:
    bad = []
    m = res.metrics
    if m is not None:
        for name in ("tau_mean", "tau_min", "tau_max", "omega_mean", "p_src", "p_cu", "p_emf", "dW_L", "dW_kin",
                     "balance_electrical", "balance_mechanical"):
            if not math.isfinite(getattr(m, name)):
                bad.append(f"metrics.{name} = {getattr(m, name)}")
        for name in ("i_rms", "i_peak"):
            if not all(math.isfinite(v) for v in getattr(m, name)):
                bad.append(f"metrics.{name} = {getattr(m, name)}")
    final = res.meta.get("final", {})
    for key in ("i", "omega_m", "theta_e"):
        vals = np.atleast_1d(np.asarray(final.get(key, 0.0), dtype=float))
        if not np.all(np.isfinite(vals)):
            bad.append(f"final {key} = {final[key]}")
    if rows is not None and not rows.nonfinite:
        return bad  # the runner saw every traced value finite
    for name in ("i_a", "i_b", "i_c", "tau_e", "omega_m"):
        sig = res.signals.get(name)
        if sig is not None and sig.size and not np.all(np.isfinite(sig)):
            j = int(np.nonzero(~np.isfinite(sig))[0][0])
            bad.append(f"{name} at t = {float(res.t[j]):.6g} s is {sig[j]}")
    return bad


def peak_current(res: SimResult, rows: RowSummary | None = None) -> float:
    """Return the largest phase current magnitude of a run (A): its traced rows, metric window and final state."""
    peaks = [abs(v) for v in res.meta.get("final", {}).get("i", [])]
    if res.metrics is not None:
        peaks += list(res.metrics.i_peak)
    if rows is not None and not rows.nonfinite:
        peaks += [rows.peak[x] for x, name in enumerate(("i_a", "i_b", "i_c"))
                  if name in res.signals and res.signals[name].size]
    else:
        for name in ("i_a", "i_b", "i_c"):
            sig = res.signals.get(name)
            if sig is not None and sig.size:
                peaks.append(float(np.max(np.abs(sig))))
    return max(peaks, default=0.0)


#: A drive without a current loop whose phase current exceeds this many times the rated current ``I_N`` (or the
#: motor's peak current ``T_peak / (2 k_phi)`` when larger) is warned about: the limit of :func:`check_reference`'s
#: default current trip, the short-time rating of a typical motor.
RATED_CURRENT_WARN = 2.0


def check_current_rating(drive: Drive, control: Control, res: SimResult,
                         rows: RowSummary | None = None) -> list[Finding]:
    """Check the currents of a drive without a current loop against its rating, and name a hardware trip.

    A duty (an ESC's throttle, :class:`~bldclab.control.SixStepVoltage`, ``SixStep(regulation="duty")``) or an
    open-loop voltage leaves the current to the winding resistance and the back-EMF: at stall and full duty
    ``V_dc / (2 R)``, several times the rating (f60prov-2550kv: 522 A, 10 ``I_N``), which a real drive survives only
    by a current limit or a trip. A current controller trips at its own ``i_max`` instead (:func:`check_reference`).

    Parameters
    ----------
    drive : Drive
    control : Control
    res : SimResult
    rows : RowSummary, optional
        The runner's summary of the trace rows (else the signals are scanned).

    Returns
    -------
    list of Finding
        A warning on ``result.hardware_trip`` when the inverter's trip ``i_trip`` switched every leg off (the rest
        of the run is a drive switched off), else one on ``result.current_rating`` when a drive without a current
        loop reached more than ``RATED_CURRENT_WARN`` times ``I_N`` (or more than ``T_peak / (2 k_phi)``).
    """
    t_trip = res.meta.get("stats", {}).get("hw_trip")
    i_trip = drive.inverter.i_trip
    if t_trip is not None:
        return [Finding("warning", "result.hardware_trip",
                        f"the inverter's hardware trip (i_trip = {i_trip:.4g} A, {i_trip / drive.motor.I_N:.3g} times "
                        f"I_N = {drive.motor.I_N:.4g} A) switched every leg off at t = {t_trip:.4g} s: from then on "
                        f"the run is a drive switched off and its metrics describe that")]
    if _reference_kind(control) is not None or getattr(control, "speed_loop", False):
        return []
    m = drive.motor
    limit, what = RATED_CURRENT_WARN * m.I_N, f"{RATED_CURRENT_WARN:g} I_N"
    if m.T_peak is not None and m.T_peak / (2.0 * m.k_phi) > limit:
        limit, what = m.T_peak / (2.0 * m.k_phi), "the motor's peak current T_peak / (2 k_phi)"
    i_pk = peak_current(res, rows)
    if i_pk <= limit:
        return []
    if hasattr(control, "i_max") and "OVERCURRENT" in res.flags_raised.split("|"):
        # A controller with a trip of its own (the sensorless ESC's ``i_max``): the current above the rating is the
        # sample before that trip; the run names it by its flag (OVERCURRENT), not by this warning.
        return []
    return [Finding("warning", "result.current_rating",
                    f"a phase current reached {i_pk:.4g} A, {i_pk / m.I_N:.3g} times the rated current I_N = "
                    f"{m.I_N:.4g} A (warning above {what} = {limit:.4g} A): the drive has no current loop, so only "
                    f"the winding resistance and the back-EMF limit the current (at stall V_dc / (2 R) = "
                    f"{drive.inverter.V_dc / (2.0 * (m.R + drive.inverter.R_on)):.4g} A at full duty); a real drive "
                    f"needs a current limit or a trip (Inverter.i_trip) there")]


def check_result(drive: Drive, res: SimResult, rows: RowSummary | None = None) -> list[Finding]:
    """Check a finished run: finite values, energy balance, currents after a hardware trip.

    Parameters
    ----------
    drive : Drive
    res : SimResult
    rows : RowSummary, optional
        The runner's summary of ``res``'s trace rows (:func:`bldclab.simulate` passes it); without it the signals are
        scanned.

    Returns
    -------
    list of Finding
    """
    bad = _nonfinite(res, rows)
    if bad:
        return [Finding("error", "result.finite", f"non-finite values ({'; '.join(bad[:3])}): the integration "
                        "diverged")]
    out = []
    m = res.metrics
    if m is not None:
        flow = dict(zip(("balance_electrical", "balance_mechanical"), m.balance_flows(), strict=True))
        floor = BALANCE_FLOOR * drive.inverter.V_dc * drive.motor.I_N
        for name in ("balance_electrical", "balance_mechanical"):
            r = abs(getattr(m, name))
            level = _grade(r, BALANCE_WARN, BALANCE_ERROR) if r * flow[name] >= floor else None
            if level:
                out.append(Finding(level, "result.energy_balance",
                                   f"{name} residue {getattr(m, name):.3g} over the window [{m.t0:.4g}, {m.t1:.4g}] "
                                   f"s (limit {BALANCE_WARN:g} for a warning, {BALANCE_ERROR:g} for an error; the "
                                   f"plant closes it to 1e-7 or better when the PWM resolves the electrical "
                                   f"period): the integration did not resolve the run"))
    i_pk = peak_current(res, rows)
    i_trip = drive.inverter.i_trip
    tripped = res.meta.get("stats", {}).get("hw_trip") is not None
    if tripped and i_trip > 0:
        level = _grade(i_pk / i_trip, TRIP_WARN, TRIP_ERROR)
        if level:
            out.append(Finding(level, "result.currents",
                               f"a phase current reached {i_pk:.4g} A, {i_pk / i_trip:.3g} times the hardware trip "
                               f"i_trip = {i_trip:.4g} A, with every leg off since the trip: the back-EMF drives it "
                               f"through the diodes (error above {TRIP_ERROR:g} i_trip)"))
    elif i_pk > CURRENT_ERROR_IN * drive.motor.I_N:
        out.append(Finding("error", "result.currents",
                           f"a phase current reached {i_pk:.4g} A, {i_pk / drive.motor.I_N:.3g} times I_N = "
                           f"{drive.motor.I_N:.4g} A (error above {CURRENT_ERROR_IN:g} I_N)"))
    return out


def pwm_ripple(drive: Drive, omega: float, i_ref: float, chopping: str,
               v_dc: float | None = None) -> tuple[float, float]:
    """Estimate the peak-to-peak PWM ripple of a six-step drive's pair current in steady two-phase conduction.

    The pair (two phases in series, ``2 R``, ``2 L``) sees ``V_dc`` for ``d T_pwm`` and the freewheel's 0 V (the
    unipolar patterns ``high``, ``pwm-on-pwm``, ``sync``) or ``-V_dc`` (``bipolar``) for the rest of the period,
    against the line back-EMF ``E = 2 k_phi |omega|``; the average holds ``u = E + 2 R I``. Then
    ``Delta I_pp = (V_dc - u) d T_pwm / (2 L)``: ``V_dc d (1 - d) / (2 L f_pwm)`` with ``d = u / V_dc`` (unipolar),
    twice that with ``d = (1 + u / V_dc) / 2`` (bipolar). The commutation and a non-flat back-EMF are left out.

    Parameters
    ----------
    drive : Drive
    omega : float
        Mechanical speed (rad/s).
    i_ref : float
        The pair current (A).
    chopping : str
        The chopping pattern (:class:`~bldclab.control.SixStep`'s ``chopping``).
    v_dc : float, optional
        Bus voltage (V); default the inverter's.

    Returns
    -------
    tuple of float
        ``(Delta I_pp, d)``: the ripple (A) and the duty it was evaluated at.
    """
    v = drive.inverter.V_dc if v_dc is None else v_dc
    m = drive.motor
    u = 2.0 * m.k_phi * abs(omega) + 2.0 * (m.R + drive.inverter.R_on) * abs(i_ref)
    t_pwm = 1.0 / drive.inverter.f_pwm
    if chopping == "bipolar":
        d = min(max(0.5 * (1.0 + u / v), 0.0), 1.0)
        return 2.0 * v * d * (1.0 - d) * t_pwm / (2.0 * m.L), d
    d = min(max(u / v, 0.0), 1.0)
    return v * d * (1.0 - d) * t_pwm / (2.0 * m.L), d


def check_conduction(drive: Drive, control: Control, res: SimResult, ref_max: float) -> list[Finding]:
    """Check a current-regulated run for discontinuous conduction and a PWM ripple larger than the reference.

    Every current controller here samples the current at the carrier's valleys and peaks, where a current that is its
    PWM-period mean plus a small linear ripple crosses that mean. When the ripple is as large as the current that no
    longer holds: with a diode freewheel (``pwm-on-pwm``, ``high``, ``bipolar``) the current falls to zero and
    stays there for part of each period (discontinuous conduction, measured: ``Metrics.zero_current_share``), with
    complementary chopping (``sync``) it reverses; either way the mean current and torque are not what the
    reference asked for (f60prov-2550kv at 0.5 ``Omega_0``: 1.1 to 6 times the reference's torque below 5 A).

    Parameters
    ----------
    drive : Drive
    control : Control
    res : SimResult
        The run, with its metrics.
    ref_max : float
        Largest magnitude of the reference over the run (A or N m).

    Returns
    -------
    list of Finding
        A warning on ``result.discontinuous_conduction`` when every phase current is zero for more than
        ``ZERO_CURRENT_WARN`` of the metric window in intervals shorter than a PWM period on average (longer ones
        are a drive switched off: a safe state, a fault); otherwise one on ``result.current_ripple`` when
        :func:`pwm_ripple` at the window's mean speed exceeds the reference current. Only for a controller that
        regulates its sampled current (:class:`~bldclab.control.SixStep` with ``regulation`` predictive, pi or
        hysteresis; paper 2's :class:`~bldclab.control.Lu` controls the torque from a model of the discontinuous
        current and holds it there, ``tests/test_lu.py``).
    """
    m = res.metrics
    kind = _reference_kind(control)
    if (m is None or kind is None or not math.isfinite(ref_max)
            or getattr(control, "regulation", None) not in ("predictive", "pi", "hysteresis")):
        return []
    k_phi = drive.motor.k_phi
    i_ref = ref_max if kind == "current" else ref_max / (2.0 * k_phi)
    chopping = getattr(control, "chopping", None)
    ripple = None
    if isinstance(chopping, str) and math.isfinite(m.omega_mean):
        ripple = pwm_ripple(drive, m.omega_mean, i_ref, chopping)
    tau_ref = 2.0 * k_phi * i_ref
    torque = (f"; mean torque {m.tau_mean:.4g} N m, {100 * m.tau_mean / tau_ref:.3g} % of 2 k_phi I_ref = "
              f"{tau_ref:.4g} N m" if tau_ref > 0 else "")
    est = ""
    if ripple is not None:
        est = (f"; estimated PWM ripple {ripple[0]:.3g} A peak-to-peak (V_dc d (1 - d) / (2 L f_pwm) for the pair, "
               f"d = {ripple[1]:.3g}, L = {drive.motor.L:.3g} H, f_pwm = {drive.inverter.f_pwm:g} Hz)")
    share = m.zero_current_share
    mean_gap = share * (m.t1 - m.t0) / max(m.zero_current_intervals, 1)
    if math.isfinite(share) and share > ZERO_CURRENT_WARN and mean_gap < 1.0 / drive.inverter.f_pwm:
        return [Finding("warning", "result.discontinuous_conduction",
                        f"every phase current is zero for {100 * share:.3g} % of the metric window (discontinuous "
                        f"conduction: the PWM ripple reaches the {i_ref:.4g} A reference{est}): the controller "
                        f"samples the current at the carrier extremes, which are no longer its mean, so the mean "
                        f"current and torque are not the reference's{torque}; raise f_pwm or L (a series choke), or "
                        f"run above about half the ripple (warning above {100 * ZERO_CURRENT_WARN:g} % of the window)")]
    if ripple is not None and ripple[0] > i_ref:
        return [Finding("warning", "result.current_ripple",
                        f"the PWM current ripple exceeds the reference current {i_ref:.4g} A{est}: the current is not "
                        f"its mean plus a small ripple (with chopping '{chopping}' it "
                        f"{'reverses' if chopping == 'sync' else 'nearly reaches zero'} within PWM periods) and the "
                        f"regulation of its mean is approximate{torque}; raise f_pwm or L, or the current")]
    return []


#: With rotor dynamics, a peak speed above this many ``Omega_0`` is a warning (the drive alone reaches about 1.05:
#: a sinusoidal back-EMF's six-step no-load speed; no controller weakens the field), above ``SPEED_ERROR_PU`` an
#: error: the load torque (or the initial speed) drove the rotor, the drive did not.
DRIVEN_SPEED_WARN_PU = 1.5


def check_driven_speed(drive: Drive, omega_max: float, omega_final: float) -> list[Finding]:
    """Check the peak speed of a run with rotor dynamics against the no-load speed ``Omega_0``.

    A rotor far beyond ``Omega_0`` was driven there by its load (a load torque above the drive's torque spins it
    backwards) or started there: that is the cause to name, before the consequences (too few PWM periods per
    electrical period, diode currents) that other checks report.

    Parameters
    ----------
    drive : Drive
    omega_max : float
        Highest mechanical speed magnitude of the run (rad/s).
    omega_final : float
        Mechanical speed at the end of the run (rad/s), for its direction.

    Returns
    -------
    list of Finding
    """
    omega_0 = drive.Omega_0
    pu = omega_max / omega_0
    level = _grade(pu, DRIVEN_SPEED_WARN_PU, SPEED_ERROR_PU)
    if not level:
        return []
    direction = "backwards" if omega_final < 0.0 else "forwards"
    return [Finding(level, "scenario.load_torque",
                    f"the rotor reached {omega_max:.4g} rad/s ({omega_max * 30 / math.pi:.4g} rpm, ending "
                    f"{direction}), {pu:.4g} times the no-load speed Omega_0 = V_dc / (2 k_phi) = {omega_0:.4g} "
                    f"rad/s: the drive cannot reach that, so the load torque (above the drive's torque, T_N = "
                    f"{drive.T_N:.4g} N m) or the initial speed drove it (warning above {DRIVEN_SPEED_WARN_PU:g} "
                    f"Omega_0, error above {SPEED_ERROR_PU:g})")]


def check_steady(drive: Drive, res: SimResult) -> list[Finding]:
    """Check that the metric window of a run with rotor dynamics is in steady state.

    Parameters
    ----------
    drive : Drive
    res : SimResult
        A run with rotor dynamics (``Scenario.speed`` is ``None``) and a metric window.

    Returns
    -------
    list of Finding
    """
    m = res.metrics
    if m is None:
        return []
    out = []
    J = drive.mechanics.J
    w2 = m.omega_mean**2
    rel = abs(m.dW_kin) / (J * w2) if w2 > 0 else (math.inf if m.dW_kin != 0 else 0.0)
    if rel > STEADY_SPEED:
        dw = math.copysign(math.sqrt(2.0 * abs(m.dW_kin) / J), m.dW_kin) if w2 == 0 else m.dW_kin / (J * m.omega_mean)
        out.append(Finding("warning", "scenario.window",
                           f"the speed changes by {dw:.4g} rad/s ({100 * rel:.3g} % of its mean {m.omega_mean:.4g} "
                           f"rad/s) across the metric window [{m.t0:.4g}, {m.t1:.4g}] s (limit {100 * STEADY_SPEED:g} "
                           f"%): not a steady state, the window still holds a run-up"))
    t = res.signals.get("t")
    tau = res.signals.get("tau_mean")
    if t is not None and tau is not None and t.size:
        mid = 0.5 * (m.t0 + m.t1)
        first = tau[(t >= m.t0) & (t < mid)]
        second = tau[(t >= mid) & (t < m.t1)]
        if first.size >= 2 and second.size >= 2:
            a, b = float(np.mean(first)), float(np.mean(second))
            scale = max(abs(m.tau_mean), 0.1 * drive.T_N)
            if abs(a - b) > STEADY_TORQUE * scale:
                out.append(Finding("warning", "scenario.window",
                                   f"the mean torque of the window's first half ({a:.4g} N m) and second half "
                                   f"({b:.4g} N m) differ by {abs(a - b):.4g} N m, more than {100 * STEADY_TORQUE:g} % "
                                   f"of {scale:.4g} N m: not a steady state, the window still holds a run-up"))
    return out


def apply(findings: Iterable[Finding], check: str, stacklevel: int = 3) -> list[str]:
    """Issue the findings: warnings through :mod:`warnings`, errors raised (``check="error"``) or warned.

    Parameters
    ----------
    findings : iterable of Finding
    check : {"error", "warn", "off"}
        ``error``: raise the first error as :class:`~bldclab.errors.PlausibilityError` (after issuing the
        warnings); ``warn``: issue errors as warnings too; ``off``: nothing.
    stacklevel : int
        Passed to :func:`warnings.warn`.

    Returns
    -------
    list of str
        The messages issued as warnings.

    Raises
    ------
    PlausibilityError
        For the first error finding with ``check="error"``.
    """
    if check == "off":
        return []
    found = list(findings)
    issued = []
    for f in found:
        if f.level == "warning" or check == "warn":
            text = str(f) if f.level == "warning" else f"{f} [error ignored: check='warn']"
            warnings.warn(text, PlausibilityWarning, stacklevel=stacklevel)
            issued.append(text)
    if check == "error":
        for f in found:
            if f.level == "error":
                raise PlausibilityError(f.cause, f.message)
    return issued


def cause_first(error: PlausibilityError, before: Sequence[str]) -> PlausibilityError:
    """Return the error of a finished run led by the warnings its inputs raised before it ran: the cause first.

    A run that failed after warnings on its inputs (``--speed 300`` on ``htm-48v``: 4 times the no-load speed, so
    the back-EMF drives the currents through the diodes past the hardware trip) is reported as
    ``scenario.speed: 300 rad/s ... is 4 times the no-load speed ...; the run then failed: result.currents: ...``,
    naming the input as the field; without such warnings the error is returned as it is.

    Parameters
    ----------
    error : PlausibilityError
        What the finished run's check found.
    before : sequence of str
        The warnings the inputs raised (``"cause: message"``), in order.

    Returns
    -------
    PlausibilityError
    """
    if not before:
        return error
    cause = cause_of(before[0]) or error.field
    first = before[0].removeprefix(f"{cause}: ")
    rest = "".join(f"; {text}" for text in before[1:])
    return PlausibilityError(cause, f"{first}{rest}; the run then failed: {error.field}: {error.problem}",
                             error.source)


@contextmanager
def collect() -> Iterator[list[str]]:
    """Record plausibility warnings instead of showing them (for experiments that run many points).

    Yields
    ------
    list of str
        Filled with each warning's message as it is issued; other warnings pass through unchanged.
    """
    caught: list[str] = []
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always", PlausibilityWarning)
        try:
            yield caught
        finally:
            for w in rec:
                if issubclass(w.category, PlausibilityWarning):
                    caught.append(str(w.message))
                else:
                    warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    # the list is complete once the block has ended


_CAUSE = re.compile(r"(?:^|: )((?:inverter|scenario|result|motor|control)\.[A-Za-z_]+)(?=: )")


def distinct(messages: Iterable[str]) -> list[str]:
    """Return the messages with repeats left out, in the order of their first appearance."""
    return list(dict.fromkeys(messages))


def cause_of(message: str) -> str | None:
    """Return the cause of a warning's message (``"inverter.f_pwm"``: :attr:`Finding.cause`), None if it names none.

    The message may carry a prefix saying where it came from (``"square at 0.74 p.u.: inverter.f_pwm: ..."``).
    """
    m = _CAUSE.search(message)
    return m.group(1) if m else None


def summary(messages: Sequence[str], runs: int | str) -> str | None:
    """One line for many warnings: how many distinct ones, where from, their causes and the first (``None`` if none).

    Identical messages (the same finding at the same point, from two runs of it) count once, and the line says how
    many repeats there were: ``"12 plausibility warnings in 64 runs (7 repeats counted once); cause: inverter.f_pwm;
    first: square at 0.74 p.u.: inverter.f_pwm: ..."``.

    Parameters
    ----------
    messages : sequence of str
        Every warning's message, repeats included.
    runs : int or str
        Simulations run (``"in 64 runs"``), or what ran, as text (``"in 64 points and 4 waveforms"``).
    """
    if not messages:
        return None
    uniq = distinct(messages)
    causes = distinct(c for c in map(cause_of, uniq) if c)
    repeats = len(messages) - len(uniq)
    where = f"{runs} runs" if isinstance(runs, int) else runs
    return (f"{len(uniq)} plausibility warning{'s' if len(uniq) != 1 else ''} in {where}"
            + (f" ({repeats} repeat{'s' if repeats != 1 else ''} counted once)" if repeats else "")
            + (f"; cause{'s' if len(causes) != 1 else ''}: {', '.join(causes)}" if causes else "")
            + f"; first: {uniq[0]}")

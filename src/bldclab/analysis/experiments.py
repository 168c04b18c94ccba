"""Experiments on a drive: steady-state operating points at imposed speed, speed sweeps, the simulated base speed.

An operating point is measured as on a dynamometer test bench: the speed is imposed, the controller runs from
rest until the transients have died out, then the torque is averaged over whole electrical periods. Ripple is
reported three ways (:class:`~bldclab.sim.results.Metrics`): max - min of the exact instantaneous torque; of its
moving average over one PWM period, evaluated continuously; and of its values at the controller samples (carrier
valleys and peaks, where the currents cross their PWM-period averages). The last removes the PWM component without
flattening commutation spikes a few PWM periods wide and is the one to compare with closed forms that assume ideal
current regulation, as long as the commutation lasts several PWM periods; when it lasts one or two, the spike can
fall between samples and the moving average is the safer measure.

The PWM grid is fixed in time and the rotor starts at angle ``theta0``: where the carrier falls relative to the
rotor is an arbitrary choice of the run, and with few PWM periods per commutation it moves the results.
:func:`steady_state` with ``pwm_phases = N`` runs N evenly spaced offsets of the initial angle within one PWM
period's rotor travel and reports their mean and range.
"""

from __future__ import annotations

import dataclasses
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .._core import core
from ..control import Control, Sine, SixStep
from ..control.sine import fundamental_k1
from ..errors import BldclabError, PlausibilityError
from ..model import analytic
from ..model.motor import Drive
from ..model.units import to_si
from ..sim import Profile, Scenario, plausibility, simulate
from ..sim.results import Metrics, SimResult

__all__ = ["EXPERIMENTS", "Experiment", "PointResult", "Simulate", "SteadyState", "base_speed", "base_speed_margin",
           "map_points",
           "steady_state"]


@dataclass(frozen=True)
class PointResult:
    """One steady-state operating point at imposed speed.

    Attributes
    ----------
    speed : float
        Mechanical speed (rad/s).
    speed_pu : float
        Speed in per unit of ``Omega_0`` (-).
    tau_mean, ripple, ripple_ma, ripple_sampled : float
        Mean torque, max - min of the torque, of its one-PWM-period moving average, and of its values at the
        controller samples (PWM-free: :class:`~bldclab.sim.results.Metrics`) (N m).
    tau_mean_pu, ripple_pu, ripple_ma_pu, ripple_sampled_pu : float
        The same in per unit of ``T_N`` (-).
    efficiency : float
        Shaft power over DC power (-).
    metrics : Metrics
        Everything measured over the window (energies, currents, ...), of the first PWM-grid phase (offset 0).
    pwm_phases : int
        PWM-grid phases run (1: one run; the scalar fields above are then means over the phases).
    tau_mean_range, ripple_range, ripple_ma_range, ripple_sampled_range : tuple of float
        ``(min, max)`` over the PWM-grid phases of the mean torque and of the three ripples (N m); both equal to the
        value when ``pwm_phases == 1``.
    """

    speed: float
    speed_pu: float
    tau_mean: float
    ripple: float
    ripple_ma: float
    ripple_sampled: float
    tau_mean_pu: float
    ripple_pu: float
    ripple_ma_pu: float
    ripple_sampled_pu: float
    efficiency: float
    metrics: Metrics
    pwm_phases: int = 1
    tau_mean_range: tuple[float, float] = (math.nan, math.nan)
    ripple_range: tuple[float, float] = (math.nan, math.nan)
    ripple_ma_range: tuple[float, float] = (math.nan, math.nan)
    ripple_sampled_range: tuple[float, float] = (math.nan, math.nan)

    def spread_pu(self, name: str, T_N: float) -> float:
        """Return ``max - min`` over the PWM-grid phases of ``tau_mean`` or a ripple (``name``), in p.u. of ``T_N``."""
        lo, hi = getattr(self, f"{name}_range")
        return (hi - lo) / T_N


def map_points(fn: Callable[[Any], Any], jobs: Sequence[Any], executor: Executor | None = None, *,
               chunksize: int = 1, progress: Callable[[int], None] | None = None,
               each: Callable[[int, Any], None] | None = None) -> list[Any]:
    """Run ``fn`` over ``jobs`` and return the results in the order of the jobs.

    The one way the analyses (``compare``, ``effmap``) run their operating points: serially without an executor,
    else on it (a process pool, or any :class:`concurrent.futures.Executor`, e.g. a Dask client's).

    Parameters
    ----------
    fn : callable
        A module-level function of one job (picklable for a process pool).
    jobs : sequence
        The jobs.
    executor : concurrent.futures.Executor, optional
        Where to run them; serially in this process if omitted.
    chunksize : int
        Jobs sent to a process-pool worker at a time (> 1 only for a :class:`~concurrent.futures.ProcessPoolExecutor`).
    progress : callable, optional
        Called with the number of results done after each one.
    each : callable, optional
        Called with each job's index and result as it arrives, in order (while the executor runs the next ones):
        e.g. to keep it in a store.

    Returns
    -------
    list
        ``[fn(job) for job in jobs]``.
    """
    if executor is None:
        results: Iterable[Any] = map(fn, jobs)
    elif chunksize > 1:
        results = executor.map(fn, jobs, chunksize=chunksize)
    else:
        results = executor.map(fn, jobs)
    out = []
    for j, r in enumerate(results):
        out.append(r)
        if each is not None:
            each(j, r)
        if progress is not None:
            progress(j + 1)
    return out


def electrical_period(drive: Drive, speed: float) -> float:
    """Return the electrical period (s) at a mechanical speed (rad/s)."""
    if speed == 0:
        raise BldclabError("speed", "is zero: no electrical period")
    return 2.0 * math.pi / (drive.motor.p * abs(speed))


def steady_state(drive: Drive, control: Control, speed: float, ref: Profile, *, settle_periods: int = 3,
                 measure_periods: int = 2, settle_time: float = 0.01, trace: bool = False, pwm_phases: int = 1,
                 estimate: Drive | None = None, **scenario: Any) -> tuple[PointResult, SimResult]:
    """Run the drive at an imposed speed until steady state and measure whole electrical periods.

    Parameters
    ----------
    drive : Drive
    control : Control
    speed : float
        Imposed mechanical speed (rad/s), non-zero.
    ref : profile
        The controller's reference (for current or torque control: a constant).
    settle_periods : int
        Electrical periods discarded before measuring (at least ``settle_time`` is discarded too).
    measure_periods : int
        Whole electrical periods measured.
    settle_time : float
        Minimum settling time (s).
    trace : bool
        Keep the trace (for waveforms).
    pwm_phases : int
        PWM-grid phases (>= 1): run with the rotor's initial angle ``theta0 + j p |speed| T / N``, ``j = 0 .. N-1``
        (``T = 1/f_pwm``, ``N = pwm_phases``): N evenly spaced positions of the PWM carrier relative to the rotor
        within one PWM period. The point's scalars are the means over the phases, the ``*_range`` fields their
        extremes; the returned simulation is the first phase's.
    estimate : Drive, optional
        The drive the controller is configured from, when it differs from the plant (see
        :func:`bldclab.simulate`).
    **scenario
        Further :class:`~bldclab.sim.Scenario` fields (``delay``, ``trace_sub``, ``omega_ref``, ``theta0``, ...).

    Returns
    -------
    PointResult
        The measured point.
    SimResult
        The simulation (its trace if ``trace``).
    """
    if not isinstance(pwm_phases, int) or isinstance(pwm_phases, bool) or pwm_phases < 1:
        raise BldclabError("pwm_phases", f"must be an integer >= 1, got {pwm_phases!r}")
    Te = electrical_period(drive, speed)
    t_settle = max(settle_periods * Te, math.ceil(settle_time / Te) * Te)
    t_end = t_settle + measure_periods * Te
    theta0 = float(scenario.pop("theta0", 0.0))
    travel = drive.motor.p * abs(speed) / drive.inverter.f_pwm  # electrical angle over one PWM period, rad
    runs: list[tuple[Metrics, SimResult]] = []
    for j in range(pwm_phases):
        sc = Scenario(duration=t_end, speed=speed, ref=ref, trace=trace and j == 0, window=(t_settle, t_end),
                      theta0=theta0 + travel * j / pwm_phases, **scenario)
        res = simulate(drive, control, sc, estimate=estimate)
        assert res.metrics is not None
        runs.append((res.metrics, res))
    ms = [m for m, _ in runs]
    T_N = drive.T_N

    def mean(name: str) -> float:
        return float(np.mean([getattr(m, name) for m in ms]))

    def span(name: str) -> tuple[float, float]:
        v = [getattr(m, name) for m in ms]
        return (float(min(v)), float(max(v)))

    tau, rip, rma, rs = mean("tau_mean"), mean("ripple"), mean("ripple_ma"), mean("ripple_sampled")
    point = PointResult(speed=speed, speed_pu=speed / drive.Omega_0, tau_mean=tau, ripple=rip, ripple_ma=rma,
                        ripple_sampled=rs, tau_mean_pu=tau / T_N, ripple_pu=rip / T_N, ripple_ma_pu=rma / T_N,
                        ripple_sampled_pu=rs / T_N, efficiency=mean("efficiency"), metrics=ms[0],
                        pwm_phases=pwm_phases, tau_mean_range=span("tau_mean"), ripple_range=span("ripple"),
                        ripple_ma_range=span("ripple_ma"), ripple_sampled_range=span("ripple_sampled"))
    return point, runs[0][1]


# ---------------------------------------------------------------------------------------------------------------
# the simulated base speed (paper 1's definitions, with the drive's R)

#: Incoming phase (0 = a) and the sign of its current when forward rotation enters sector s (docs/conventions.md).
_INCOMING = ((0, 1), (2, -1), (1, 1), (0, -1), (2, 1), (1, -1))
#: Highest speed :func:`base_speed` searches (p.u. of Omega_0): returned when the condition holds up to it. A
#: rounded back-EMF reaches its line-to-line peak at isolated angles only, so a drive can hold its current slightly
#: above ``Omega_0``.
W_MAX = 1.1


def _square_margin(drive: Drive, w_pu: float, control: Control) -> float:
    """Worst (largest incoming current within its sector) - 0.999 I_N over one electrical period, p.u. of I_N."""
    I_N = drive.motor.I_N
    om = w_pu * drive.Omega_0
    pt, res = steady_state(drive, control, om, I_N, settle_periods=3, measure_periods=1, trace=True, trace_sub=4)
    t, m = res.t, pt.metrics
    th = np.unwrap(res.theta_e)
    cur = np.stack([res.i_a, res.i_b, res.i_c])
    we = drive.motor.p * om
    worst = math.inf
    n = math.ceil((th[t >= m.t0][0] - math.pi / 6) / (math.pi / 3))
    while True:
        tc = float(np.interp(math.pi / 6 + n * math.pi / 3, th, t))  # the sector's commutation (its Hall corner)
        te = tc + (math.pi / 3) / we  # the next commutation
        if te > m.t1:
            return worst / I_N + 1e-3  # 0.1 %: the regulation's own steady error near I_N
        x, sg = _INCOMING[n % 6]
        sel = (t >= tc) & (t <= te)
        peak = max(float(np.max(sg * cur[x][sel])), sg * float(np.interp(te, t, cur[x])))
        worst = min(worst, peak - I_N)
        n += 1


def _sine_margin(drive: Drive, w_pu: float, control: Control) -> float:
    """Return minus the fraction of samples with the voltage demand beyond linear SVM, currents of peak I_s,N.

    A sample in the controller's safe state (an over-current trip: the currents ran away) counts as beyond it too.
    """
    ref = 1.5 * fundamental_k1(drive) * analytic.i_sN(drive)  # (45): the torque of i_q = I_s,N
    pt, res = steady_state(drive, control, w_pu * drive.Omega_0, ref, trace=True)
    sel = res.t >= pt.metrics.t0
    # BC_FLAG_SATURATED: the voltage demand left the linear range; BC_FLAG_SAFE: all legs off (a trip)
    lost = core().const("BC_FLAG_SATURATED") | core().const("BC_FLAG_SAFE")
    return -float(np.mean((res["ctrl_flags"][sel].astype(int) & lost) > 0))


def base_speed_margin(drive: Drive, supply: str, w_pu: float, control: Control | None = None) -> float:
    """Return how far a supply is from its base-speed condition at one speed (>= 0: at or below the base speed).

    Parameters
    ----------
    drive : Drive
    supply : {"square", "sine"}
        ``"square"``: :class:`~bldclab.control.SixStep` regulating ``I_N``; the margin is the smallest, over the six
        commutations of an electrical period, of the largest incoming-phase current within its sector (before the
        next commutation) minus ``0.999 I_N``, in p.u. of ``I_N``, read from a trace of 4 rows per sample (paper 1's
        definition: the injected current reaches ``I_N`` by half of its 120-degree conduction interval).
        ``"sine"``: :class:`~bldclab.control.Sine` asked for the current ``I_s,N`` (the torque ``1.5 k_1 I_s,N``
        of (45)) with its speed limit off; the margin is minus the fraction of the measured samples at which its
        voltage demand left the linear SVM range (0: the currents are held with linear modulation).
    w_pu : float
        Speed, p.u. of ``Omega_0``.
    control : Control, optional
        The controller (default: ``SixStep()`` or ``Sine(speed_limit=False, handoff_speed=0.02 Omega_0)``).

    Returns
    -------
    float
        The margin (-).
    """
    if supply == "square":
        return _square_margin(drive, w_pu, control or SixStep())
    if supply == "sine":
        return _sine_margin(drive, w_pu, control or Sine(speed_limit=False, handoff_speed=0.02 * drive.Omega_0))
    raise BldclabError("supply", f"must be 'square' or 'sine', got {supply!r}")


def base_speed(drive: Drive, supply: str, control: Control | None = None, *, lo: float | None = None,
               hi: float | None = None, tol: float = 1e-3) -> float:
    """Return the simulated base speed of a supply: paper 1's definitions, the drive's R (p.u. of Omega_0).

    Square wave: the highest speed at which the incoming phase current still reaches ``I_N`` within its sector,
    i.e. before the next commutation (paper 1, IV.A; the closed form is (30) with R = 0). Sinusoidal: the highest
    speed at which the controller still holds the current ``I_s,N`` with its voltage demand inside the linear SVM
    range (the linear-modulation limit) (paper 1, IV.B; (21) with R = 0). Both by bisection on
    :func:`base_speed_margin`: the whole switching-level drive (PWM, commutation, controller delay), where
    :func:`bldclab.model.analytic.omega_sB_numeric_pu` and :func:`~bldclab.model.analytic.omega_qB_numeric_pu` solve the
    circuit with ideal regulation.

    Parameters
    ----------
    drive : Drive
    supply : {"square", "sine"}
    control : Control, optional
        As in :func:`base_speed_margin`.
    lo, hi : float, optional
        A bracket (p.u.) with the condition met at ``lo`` and not at ``hi``; default the R-aware numeric base speed
        -0.03 / +0.02, widened by 0.05 steps until it brackets (up to :data:`W_MAX`).
    tol : float
        Width of the final bracket (p.u.); the midpoint is returned.

    Returns
    -------
    float
        Base speed (p.u. of ``Omega_0``); :data:`W_MAX` if the condition holds up to it.
    """
    if supply not in ("square", "sine"):
        raise BldclabError("supply", f"must be 'square' or 'sine', got {supply!r}")
    if not tol > 0:
        raise BldclabError("tol", f"must be positive, got {tol}")

    def ok(w: float) -> bool:
        # the bracket may reach beyond the no-load speed on purpose: the speed warnings it raises there are part of
        # the search, not a questionable result, and are not shown; a run the guards refuse as meaningless (the
        # back-EMF driving current through the diodes past the hardware trip) is a speed where the drive cannot
        # hold its current: the condition fails there
        try:
            with plausibility.collect():
                return base_speed_margin(drive, supply, w, control) >= 0.0
        except PlausibilityError:
            return False

    guess = analytic.omega_qB_numeric_pu(drive) if supply == "square" else analytic.omega_sB_numeric_pu(drive)
    a = guess - 0.03 if lo is None else lo
    b = min(guess + 0.02, W_MAX) if hi is None else hi
    if not 0 < a < b:
        raise BldclabError("lo", f"needs 0 < lo < hi, got {a}, {b}")
    while not ok(a):
        if a <= 0.05:
            raise BldclabError("supply", f"{supply}: no base speed above 0.05 p.u. (the condition fails there)")
        a, b = max(a - 0.05, 0.05), a
    while ok(b):
        if b >= W_MAX:
            return W_MAX  # the condition still holds there
        a, b = b, min(b + 0.05, W_MAX)
    while b - a > tol:
        mid = 0.5 * (a + b)
        a, b = (mid, b) if ok(mid) else (a, mid)
    return 0.5 * (a + b)


_SPEEDS = ("speed", "speed_rpm", "speed_pu")


_RPM = 2.0 * math.pi / 60.0


def _real(name: str, v: object, *, lo: float | None = None, lo_open: bool = False, nonzero: bool = False) -> None:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise BldclabError(name, f"expected a number, got {type(v).__name__} ({v!r})")
    if not math.isfinite(v):
        raise BldclabError(name, f"must be finite, got {v}")
    if nonzero and v == 0:
        raise BldclabError(name, "must not be zero")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        raise BldclabError(name, f"must be {'>' if lo_open else '>='} {lo:g}, got {v!r}")


def _integer(name: str, v: object, lo: int) -> None:
    if isinstance(v, bool) or not isinstance(v, int) or v < lo:
        raise BldclabError(name, f"must be an integer >= {lo}, got {v!r}")


def _numbers(name: str, v: object, n: int) -> tuple[float, ...]:
    if isinstance(v, str | bytes) or not isinstance(v, Sequence) or len(v) != n:
        raise BldclabError(name, f"needs a list of {n} numbers, got {v!r}")
    for j, x in enumerate(v):
        _real(f"{name}[{j}]", x)
    return tuple(float(x) for x in v)


class Experiment(ABC):
    """Base of what one case measures: a frozen dataclass of plain settings (SI) with :meth:`run`.

    Subclasses set :attr:`kind` (the name used by the ``experiment`` setting) and :attr:`dimensions` (the unit
    dimension of fields that accept a string with a unit, see :mod:`bldclab.model.units`), and are listed in
    :data:`EXPERIMENTS`.
    """

    kind: ClassVar[str] = ""
    dimensions: ClassVar[dict[str, str]] = {}

    @abstractmethod
    def run(self, drive: Drive, control: Control) -> dict[str, float | int]:
        """Run the experiment and return its result row (names to numbers)."""

    @classmethod
    def from_settings(cls, settings: Mapping[str, Any], Omega_0: float) -> Experiment:
        """Build from a case's settings (speed as ``speed``/``speed_rpm``/``speed_pu``, unit strings allowed).

        Parameters
        ----------
        settings : mapping
            Field names to values.
        Omega_0 : float
            The case's speed base (rad/s), for ``speed_pu``.

        Raises
        ------
        BldclabError
            Naming the setting that is unknown, missing or invalid.
        """
        names = [f.name for f in dataclasses.fields(cls) if f.init]  # type: ignore[arg-type]  # cls: an Experiment subclass, each a dataclass
        speeds = [k for k in _SPEEDS if k in settings]
        if len(speeds) > 1:
            raise BldclabError(speeds[1], f"give one of speed, speed_rpm, speed_pu; {speeds[0]} is also set")
        kw: dict[str, Any] = {}
        for key, value in settings.items():
            if key in _SPEEDS and "speed" in names:
                kw["speed"] = _speed_si(key, value, Omega_0)
            elif key not in names:
                extra = ", speed_rpm, speed_pu" if "speed" in names else ""
                raise BldclabError(key, f"unknown setting of experiment {cls.kind!r} (settings: "
                                   f"{', '.join(names)}{extra})")
            else:
                kw[key] = _si(key, value, cls.dimensions.get(key))
        for f in dataclasses.fields(cls):  # type: ignore[arg-type]  # cls: an Experiment subclass, each a dataclass
            if f.init and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING \
                    and f.name not in kw:
                raise BldclabError(f.name, f"missing (experiment {cls.kind!r} needs it)")
        return cls(**kw)


def _si(key: str, value: Any, dimension: str | None) -> Any:
    if dimension is None:
        return value
    if isinstance(value, str):
        return to_si(value, dimension, key)
    if isinstance(value, list | tuple):
        return [to_si(v, dimension, f"{key}[{j}]") if isinstance(v, str) else v for j, v in enumerate(value)]
    return value


def _speed_si(key: str, value: Any, Omega_0: float) -> float:
    if key == "speed":
        v = to_si(value, "speed", key) if isinstance(value, str) else value
        _real(key, v)
        return float(v)
    _real(key, value)
    return float(value) * (_RPM if key == "speed_rpm" else Omega_0)


def _metrics_row(m: Metrics, row: dict[str, float | int]) -> None:
    """Add every numeric metric not yet in ``row``; per-phase tuples become ``name_a``, ``name_b``, ``name_c``.

    ``power_flow`` (text) is left out: the signs of ``p_src_total`` and the shaft power in the row give it.
    """
    for f in dataclasses.fields(m):
        v = getattr(m, f.name)
        if isinstance(v, str):
            continue
        if isinstance(v, tuple):
            for x, comp in zip("abc", v, strict=True):
                row.setdefault(f"{f.name}_{x}", float(comp))
        else:
            row.setdefault(f.name, float(v))


@dataclass(frozen=True)
class SteadyState(Experiment):
    """A steady-state operating point at imposed speed (:func:`bldclab.analysis.experiments.steady_state`).

    Result row: ``speed`` (rad/s), ``speed_pu``, ``tau_mean``, ``ripple``, ``ripple_ma`` (N m) and their ``_pu``
    values, ``efficiency``, then every :class:`~bldclab.sim.results.Metrics` value (mean powers ``p_*`` in W, rms and
    peak currents ``i_rms_a`` ... in A, energy balance residue ``balance_electrical``, ...), and the integrator's
    ``steps`` and ``events``.

    Parameters
    ----------
    speed : float
        Imposed mechanical speed (rad/s), non-zero.
    ref : float
        The controller's reference (its meaning depends on the controller).
    settle_periods : int
        Electrical periods discarded before measuring.
    measure_periods : int
        Whole electrical periods measured.
    settle_time : float
        Minimum settling time (s).
    delay : int
        Controller computation delay (samples, 0 or 1).
    h_max : float
        Longest integration step (s); 0: half a PWM period.
    """

    speed: float
    ref: float
    settle_periods: int = 3
    measure_periods: int = 2
    settle_time: float = 0.01
    delay: int = 1
    h_max: float = 0.0
    kind: ClassVar[str] = "steady_state"
    dimensions: ClassVar[dict[str, str]] = {"settle_time": "time", "h_max": "time"}

    def __post_init__(self) -> None:
        _real("speed", self.speed, nonzero=True)
        _real("ref", self.ref)
        _integer("settle_periods", self.settle_periods, 0)
        _integer("measure_periods", self.measure_periods, 1)
        _real("settle_time", self.settle_time, lo=0.0)
        if self.delay not in (0, 1) or isinstance(self.delay, bool):
            raise BldclabError("delay", f"must be 0 or 1 sample, got {self.delay!r}")
        _real("h_max", self.h_max, lo=0.0)
        for name in ("speed", "ref", "settle_time", "h_max"):
            object.__setattr__(self, name, float(getattr(self, name)))

    def run(self, drive: Drive, control: Control) -> dict[str, float | int]:
        """Run :func:`steady_state` at this point and return the result row."""
        point, res = steady_state(drive, control, self.speed, self.ref, settle_periods=self.settle_periods,
                                  measure_periods=self.measure_periods, settle_time=self.settle_time,
                                  delay=self.delay, h_max=self.h_max)
        row: dict[str, float | int] = {
            "speed": point.speed, "speed_pu": point.speed_pu, "tau_mean": point.tau_mean, "ripple": point.ripple,
            "ripple_ma": point.ripple_ma, "tau_mean_pu": point.tau_mean_pu, "ripple_pu": point.ripple_pu,
            "ripple_ma_pu": point.ripple_ma_pu, "efficiency": point.efficiency}
        _metrics_row(point.metrics, row)
        row["steps"] = int(res.meta["stats"]["steps"])
        row["events"] = int(res.meta["stats"]["events"])
        return row


@dataclass(frozen=True)
class Simulate(Experiment):
    """A raw :func:`bldclab.simulate` run with constant inputs; the result row is its :class:`Metrics`.

    Result row: every :class:`~bldclab.sim.results.Metrics` value over ``window`` (per-phase values as ``_a``, ``_b``,
    ``_c``), the integrator's ``steps``, ``events`` and ``plant_flags``, and the final state ``t_final`` (s),
    ``theta_e_final`` (rad), ``omega_m_final`` (rad/s).

    Parameters
    ----------
    duration : float
        Simulated time (s).
    speed : float, optional
        Imposed mechanical speed (rad/s); ``None``: the rotor follows the drive's mechanics.
    ref, omega_ref, load_torque : float
        Controller reference, speed reference (rad/s), load torque (N m).
    v_dc : float, optional
        DC source voltage (V); default the inverter's.
    theta0 : float
        Initial electrical angle (rad).
    omega0 : float, optional
        Initial speed (rad/s).
    i0 : tuple of float
        Initial phase currents (A).
    delay : int
        Controller computation delay (samples, 0 or 1).
    window : tuple of float, optional
        Metric window (t0, t1) in s; default the whole run.
    h_max : float
        Longest integration step (s).
    """

    duration: float
    speed: float | None = None
    ref: float = 0.0
    omega_ref: float = 0.0
    load_torque: float = 0.0
    v_dc: float | None = None
    theta0: float = 0.0
    omega0: float | None = None
    i0: tuple[float, float, float] = (0.0, 0.0, 0.0)
    delay: int = 1
    window: tuple[float, float] | None = None
    h_max: float = 0.0
    kind: ClassVar[str] = "simulate"
    dimensions: ClassVar[dict[str, str]] = {
        "duration": "time", "omega_ref": "speed", "load_torque": "torque", "v_dc": "voltage", "theta0": "angle",
        "omega0": "speed", "i0": "current", "window": "time", "h_max": "time"}

    def __post_init__(self) -> None:
        _real("duration", self.duration, lo=0.0, lo_open=True)
        for name in ("speed", "v_dc", "omega0"):
            if getattr(self, name) is not None:
                _real(name, getattr(self, name))
        for name in ("ref", "omega_ref", "load_torque", "theta0", "h_max", "duration"):
            _real(name, getattr(self, name))
        if self.v_dc is not None and self.v_dc <= 0:
            raise BldclabError("v_dc", f"must be > 0, got {self.v_dc!r}")
        if self.delay not in (0, 1) or isinstance(self.delay, bool):
            raise BldclabError("delay", f"must be 0 or 1 sample, got {self.delay!r}")
        object.__setattr__(self, "i0", _numbers("i0", self.i0, 3))
        window = (0.0, self.duration) if self.window is None else _numbers("window", self.window, 2)
        object.__setattr__(self, "window", window)
        for name in ("duration", "speed", "ref", "omega_ref", "load_torque", "v_dc", "theta0", "omega0", "h_max"):
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, float(v))
        try:
            self.scenario()
        except BldclabError as exc:
            raise BldclabError(exc.field.removeprefix("scenario."), exc.problem) from None

    def scenario(self) -> Scenario:
        """Return the :class:`~bldclab.sim.Scenario` (no trace, metrics over ``window``)."""
        return Scenario(duration=self.duration, speed=self.speed, ref=self.ref, omega_ref=self.omega_ref,
                        load_torque=self.load_torque, v_dc=self.v_dc, theta0=self.theta0, omega0=self.omega0,
                        i0=self.i0, delay=self.delay, trace=False, window=self.window, h_max=self.h_max)

    def run(self, drive: Drive, control: Control) -> dict[str, float | int]:
        """Run :func:`~bldclab.sim.simulate` with :meth:`scenario` and return the result row."""
        res = simulate(drive, control, self.scenario())
        if res.metrics is None:
            raise RuntimeError(f"the metric window {self.window} was not completed")
        row: dict[str, float | int] = {}
        _metrics_row(res.metrics, row)
        stats, final = res.meta["stats"], res.meta["final"]
        row.update({"steps": int(stats["steps"]), "events": int(stats["events"]),
                    "plant_flags": int(stats["plant_flags"]), "t_final": float(final["t"]),
                    "theta_e_final": float(final["theta_e"]), "omega_m_final": float(final["omega_m"])})
        return row


#: Experiments by the name the ``experiment`` setting uses. Adding one: an :class:`Experiment` subclass and a line.
EXPERIMENTS: dict[str, type[Experiment]] = {
    SteadyState.kind: SteadyState,
    Simulate.kind: Simulate,
}

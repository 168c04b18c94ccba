"""Long runs at the thermal time scale: load profiles, derating, torque-speed envelopes (docs/thermal.md).

Two ways to run a profile (speed and torque over minutes to hours) through the drive and its thermal network:

- ``mode="switching"``: the closed loop on the plant for the whole profile, coupled with the network chunk by chunk
  (:func:`bldclab.simulate` with ``thermal=``, :mod:`bldclab.sim.thermal`). Every PWM period is simulated: about
  0.05 s of wall time per simulated second on htm-48v.
- ``mode="fast"`` (cycle-averaged, quasi-static): the electrical time constants (milliseconds) are far below the
  thermal ones (seconds to hours), so over each thermal step ``h`` the drive is taken in the steady state of the
  step's operating point (the profile's speed and torque at the step's middle) at the step's starting temperatures:
  its losses are measured on the plant at imposed speed over whole electrical periods
  (:func:`~bldclab.analysis.experiments.steady_state`, switching or averaged inverter), with ``R``, the back-EMF
  and ``R_on`` at the temperatures, and the network advances exactly over ``h`` with them. Points are cached on a
  grid (speed and torque to :data:`GRID_PU` of the drive's bases, the temperature factors to :data:`GRID_SCALE`),
  so an hour at a few operating points costs a few hundred short runs (two electrical periods settling, one
  measured): seconds.

The fast mode leaves out what happens within a step: the electrical transients after a step of the profile (a
few milliseconds of extra current) and the rotor's acceleration (the speed is imposed). ``tests/test_thermal.py``
measures its difference from the switching run on a short profile.
"""

from __future__ import annotations

import ctypes
import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._core import core
from .._files import read_toml
from ..control import Control, Sine, SixStep
from ..errors import BldclabError, PlausibilityError
from ..model._checks import check_number
from ..model.motor import Drive
from ..model.thermal import Thermal, ThermalNetwork
from ..model.units import to_si
from ..sim import Piecewise, Scenario, plausibility, simulate
from ..sim.thermal import ThermalCoupling, ThermalTrace
from .effmap import FEASIBLE_TOL_PU, map_controls
from .experiments import steady_state

__all__ = ["GRID_PU", "GRID_SCALE", "Derating", "Envelope", "LoadProfile", "ProfileResult", "envelope",
           "envelope_controls", "hot_drive", "read_profile", "run_profile", "temperature_from_resistance"]

#: Grid of the fast mode's operating points: speed and torque rounded to this share of ``Omega_0`` and ``T_N``.
GRID_PU = 0.002
#: Grid of the temperature factors (``R``, back-EMF, ``R_on``) of the fast mode's points: 0.4 % (about 1 K of
#: copper), so the copper loss of a point is within 0.2 % of its value at the exact temperature.
GRID_SCALE = 0.004
#: Lowest speed of a fast-mode point (p.u. of ``Omega_0``): a standstill with torque is taken at this speed (the
#: losses of a turning rotor: a stalled rotor's current stays in two phases, which the network's nodes do not see).
MIN_SPEED_PU = 0.02


@dataclass(frozen=True)
class LoadProfile:
    """A speed and torque profile: piecewise linear in time, repeated ``repeat`` times.

    Parameters
    ----------
    times : tuple of float
        Non-decreasing times (s), from 0; a repeated time makes a step.
    speed : tuple of float
        Mechanical speed at those times (rad/s).
    torque : tuple of float
        Torque reference at those times (N m).
    repeat : int
        Times the table is run one after the other (a duty cycle), >= 1.
    name : str
        What the profile is.
    """

    times: tuple[float, ...]
    speed: tuple[float, ...]
    torque: tuple[float, ...]
    repeat: int = 1
    name: str = ""

    def __post_init__(self) -> None:
        n = len(self.times)
        if n < 1 or len(self.speed) != n or len(self.torque) != n:
            raise BldclabError("profile", f"needs as many times, speeds and torques, at least one (got {n}, "
                               f"{len(self.speed)}, {len(self.torque)})")
        for key in ("times", "speed", "torque"):
            for j, v in enumerate(getattr(self, key)):
                check_number(f"profile.{key}[{j}]", v)
        if self.times[0] != 0.0:
            raise BldclabError("profile.times[0]", f"must be 0 (the profile starts at t = 0), got {self.times[0]}")
        for j in range(1, n):
            if self.times[j] < self.times[j - 1]:
                raise BldclabError(f"profile.times[{j}]", f"must not be before the previous time "
                                   f"({self.times[j]:g} < {self.times[j - 1]:g} s)")
        if self.times[-1] <= 0.0:
            raise BldclabError("profile.times", "the last time must be after 0")
        if not isinstance(self.repeat, int) or isinstance(self.repeat, bool) or self.repeat < 1:
            raise BldclabError("profile.repeat", f"must be an integer >= 1, got {self.repeat!r}")

    @property
    def period(self) -> float:
        """One pass of the table (s)."""
        return float(self.times[-1])

    @property
    def duration(self) -> float:
        """The whole profile (s): ``repeat`` passes."""
        return self.period * self.repeat

    def _local(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.repeat == 1:
            return np.asarray(t, dtype=float)
        t = np.asarray(t, dtype=float)
        return np.where(t >= self.duration, self.period, np.mod(t, self.period))

    def speed_at(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return the speed (rad/s) at times ``t`` (s)."""
        return np.interp(self._local(t), self.times, self.speed)

    def torque_at(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return the torque reference (N m) at times ``t`` (s)."""
        return np.interp(self._local(t), self.times, self.torque)

    def unrolled(self) -> tuple[Piecewise, Piecewise]:
        """Return the speed and torque over the whole profile as :class:`~bldclab.sim.Piecewise` profiles."""
        ts: list[float] = []
        ws: list[float] = []
        qs: list[float] = []
        for k in range(self.repeat):
            off = k * self.period
            ts += [off + t for t in self.times]
            ws += list(self.speed)
            qs += list(self.torque)
        return Piecewise(tuple(ts), tuple(ws)), Piecewise(tuple(ts), tuple(qs))


def read_profile(path: str | Path) -> LoadProfile:
    """Read a load profile from a TOML file (docs/thermal.md, "Profile files").

    The file holds ``time``, ``speed`` and ``torque`` arrays of equal length, each value a number (SI) or a string
    with a unit (``"10 min"`` is not a unit: ``"600 s"``; ``"300 rpm"``; ``"20 N m"``), and optionally ``repeat``
    and ``name``/``description``.

    Raises
    ------
    BldclabError
        Naming the field and the problem (``profile.speed[3]: unit 'V' is not a unit of speed``).
    """
    p = Path(path)
    data = read_toml(p, "profile")
    src = str(p)
    known = {"time", "speed", "torque", "repeat", "name", "description"}
    for key in data:
        if key not in known:
            raise BldclabError(f"profile.{key}", f"is not a profile field (use {', '.join(sorted(known))})", src)
    cols = {}
    for key, dim in (("time", "time"), ("speed", "speed"), ("torque", "torque")):
        v = data.get(key)
        if not isinstance(v, list) or not v:
            raise BldclabError(f"profile.{key}", "is missing or not a list of values", src)
        cols[key] = tuple(to_si(x, dim, f"profile.{key}[{j}]", src) for j, x in enumerate(v))
    repeat = data.get("repeat", 1)
    name = data.get("name", p.stem)
    try:
        return LoadProfile(times=cols["time"], speed=cols["speed"], torque=cols["torque"], repeat=repeat,
                           name=str(name))
    except BldclabError as exc:
        raise BldclabError(exc.field.replace("profile.times", "profile.time"), exc.problem, src) from None


@dataclass(frozen=True)
class Derating:
    """A current (torque) limit that falls with a node's temperature, as drive firmware derates.

    The torque reference is multiplied by the factor of the firmware's own derating (``bc_derate.h``, one channel,
    no filter): 1 up to ``T_start``, falling linearly to ``f_min`` at ``T_end`` and held there; ``T`` the node's
    temperature at the start of each thermal step (a sensor read at the thermal rate).

    Parameters
    ----------
    node : str
        The node read (``"winding"``, ``"junction"``, the sensor's node).
    T_start, T_end : float
        Full torque up to ``T_start``, ``f_min`` of it from ``T_end`` (degC).
    f_min : float
        Factor at and above ``T_end``, in [0, 1) (0: the drive stops; a small value: limp home).
    """

    node: str
    T_start: float
    T_end: float
    f_min: float = 0.0

    def __post_init__(self) -> None:
        check_number("derating.T_start", self.T_start, lo=-273.15, lo_open=True)
        check_number("derating.T_end", self.T_end, lo=self.T_start, lo_open=True)
        check_number("derating.f_min", self.f_min, lo=0.0, hi=1.0, hi_open=True)

    def factor(self, T: float) -> float:
        """Return the torque factor at temperature ``T`` (degC), in [0, 1]: ``bc_derate_step``'s."""
        c = core()
        p = c.filled("bc_derate_params", enabled=[1, 0], T_start=[self.T_start, 0.0], T_end=[self.T_end, 0.0],
                     f_min=self.f_min, f_fault=self.f_min, T_lo=-273.15, T_hi=1e4, tau=0.0, ts=1.0)
        st = c.opaque("bc_derate_state")
        if c.lib.bc_derate_init(p.ctypes.data, st.ctypes.data) != 0:
            raise BldclabError("derating", f"bc_derate_init refused {self}")
        temps = np.array([T, 0.0], dtype=np.float32)
        return float(c.lib.bc_derate_step(p.ctypes.data, st.ctypes.data, temps.ctypes.data))


def temperature_from_resistance(R: float, R_ref: float, T_ref: float = 25.0, k: float = 234.5) -> float:
    """Return the winding temperature (degC) from its measured resistance: the firmware's estimate without a sensor.

    IEC 60034-1's resistance method, ``T = (R / R_ref) (k + T_ref) - k`` (``k`` = 234.5 degC for copper), computed
    by the controllers' C (``bc_derate_r_to_temp``, single precision as on the MCU).

    Parameters
    ----------
    R : float
        Measured resistance (Ohm), e.g. a commissioning test's or one identified during operation.
    R_ref : float
        The resistance at ``T_ref`` (Ohm).
    T_ref : float
        Its temperature (degC).
    k : float
        The conductor's inferred zero-resistance temperature below 0 degC, as a positive number (degC): 234.5 for
        copper, 225 for aluminium.

    Raises
    ------
    BldclabError
        For a resistance that is not positive and finite, or ``k + T_ref <= 0``.
    """
    out = ctypes.c_float(0.0)
    rc = core().lib.bc_derate_r_to_temp(ctypes.c_float(R), ctypes.c_float(R_ref), ctypes.c_float(T_ref),
                                        ctypes.c_float(k), ctypes.byref(out))
    if rc != 0:
        raise BldclabError("R", f"no temperature from R = {R!r} Ohm, R_ref = {R_ref!r} Ohm, T_ref = {T_ref!r} degC, "
                           f"k = {k!r} (positive, finite resistances and k + T_ref > 0)")
    return float(out.value)


def hot_drive(drive: Drive, r: float, k: float, ron: float) -> Drive:
    """Return ``drive`` with ``R`` times ``r``, the back-EMF times ``k`` and ``R_on`` times ``ron``."""
    m = drive.motor
    motor = dataclasses.replace(m, R=m.R * r, emf=m.emf.scaled(k) if k != 1.0 else m.emf)
    return dataclasses.replace(drive, motor=motor, inverter=dataclasses.replace(drive.inverter,
                                                                               R_on=drive.inverter.R_on * ron))


class _Points:
    """Steady-state losses of operating points at temperature factors, cached on the grid."""

    def __init__(self, drive: Drive, control: Control, compensated: bool, inverter: str | None) -> None:
        self.drive = drive if inverter is None else dataclasses.replace(
            drive, inverter=dataclasses.replace(drive.inverter, model=inverter))
        self.control = control
        self.compensated = compensated
        self.cache: dict[tuple[int, ...], dict[str, float]] = {}
        self.runs = 0
        self.w_grid = GRID_PU * drive.Omega_0
        self.q_grid = GRID_PU * drive.T_N

    def losses(self, speed: float, torque: float, scales: tuple[float, float, float],
               sources: Sequence[str]) -> dict[str, float]:
        """Return each source's power (W) and ``tau`` (mean torque, N m) at the point."""
        w_min = MIN_SPEED_PU * self.drive.Omega_0
        if abs(speed) < w_min:
            speed = math.copysign(w_min, speed if speed != 0 else 1.0)
        key = (round(speed / self.w_grid), round(torque / self.q_grid),
               *(round((s - 1.0) / GRID_SCALE) for s in scales))
        hit = self.cache.get(key)
        if hit is not None:
            return hit
        w, q = key[0] * self.w_grid, key[1] * self.q_grid
        r, k, ron = (1.0 + j * GRID_SCALE for j in key[2:])
        plant = hot_drive(self.drive, r, k, ron)
        est = plant if self.compensated else self.drive
        out: dict[str, float] = {}
        try:
            with plausibility.collect():
                point, _ = steady_state(plant, self.control, w, q, estimate=est, settle_periods=2,
                                        measure_periods=1)
        except PlausibilityError as exc:
            raise BldclabError("profile", f"the operating point {w:.4g} rad/s, {q:.4g} N m cannot be run: "
                               f"{exc}") from None
        m = point.metrics
        self.runs += 1
        for b in sources:
            if b in ("cu_a", "cu_b", "cu_c"):
                out[b] = plant.motor.R * m.i_rms["abc".index(b[-1])] ** 2
            else:
                out[b] = float(getattr(m, f"p_{b}"))
        out["tau"] = point.tau_mean
        self.cache[key] = out
        return out


@dataclass
class ProfileResult:
    """Outcome of :func:`run_profile`.

    Attributes
    ----------
    trace : ThermalTrace
        Temperatures, losses and factors per thermal step; ``trace.extra`` holds ``speed`` (rad/s), ``torque_ref``
        (N m, after derating), ``derate`` (-) and ``tau`` (mean torque delivered, N m) per step (fast mode; the
        switching mode fills ``tau`` from the plant).
    mode : str
        ``"fast"`` or ``"switching"``.
    wall : float
        Wall-clock time of the run (s).
    points : int
        Steady-state runs the fast mode made (0 for the switching mode).
    limits : dict of str to float
        ``T_max`` of the nodes that have one (degC).
    """

    trace: ThermalTrace
    mode: str
    wall: float
    points: int
    limits: dict[str, float]

    def margins(self) -> dict[str, float]:
        """Return ``T_max - peak temperature`` of each limited node (K): negative where the profile overheats it."""
        return {n: lim - float(np.max(self.trace.T[n])) for n, lim in self.limits.items()}

    def to_pandas(self) -> Any:
        """Return the trace as a DataFrame (:meth:`ThermalTrace.to_pandas`)."""
        return self.trace.to_pandas()


def _fast(drive: Drive, th: Thermal, net: ThermalNetwork, T: NDArray[np.float64], profile: LoadProfile,
          control: Control, h: float, compensated: bool, inverter: str | None, derate: Derating | None,
          follow: bool) -> tuple[ThermalTrace, int]:
    pts = _Points(drive, control, compensated, inverter)
    sources = [b for b, _ in th.losses]
    n = max(1, math.ceil(profile.duration / h - 1e-9))
    T0 = T.copy()
    rows_T = [T.copy()]
    rows_P = [np.zeros(len(sources))]
    s0 = th.scales(net.temps(T)) if follow else (1.0, 1.0, 1.0)
    rows_s = [s0]
    extra: dict[str, list[float]] = {"speed": [float(profile.speed_at(np.array([0.0]))[0])],
                                     "torque_ref": [float(profile.torque_at(np.array([0.0]))[0])],
                                     "derate": [1.0], "tau": [math.nan]}
    ts = [0.0]
    E_loss = E_out = 0.0
    if derate is not None and derate.node not in net.names:
        raise BldclabError("derating.node", f"is not a node with a heat capacity ({', '.join(net.names)})")
    for j in range(n):
        t0 = j * h
        t1 = min(profile.duration, t0 + h)
        hh = t1 - t0
        mid = np.array([0.5 * (t0 + t1)])
        temps = net.temps(T)
        scales = th.scales(temps) if follow else (1.0, 1.0, 1.0)
        f = 1.0 if derate is None else derate.factor(temps[derate.node])
        w = float(profile.speed_at(mid)[0])
        q = float(profile.torque_at(mid)[0]) * f
        loss = pts.losses(w, q, scales, sources) if q != 0.0 or w != 0.0 else dict.fromkeys([*sources, "tau"], 0.0)
        P, direct = net.heat({b: loss[b] for b in sources})
        T, qout = net.step(T, P, hh)
        E_loss += (float(np.sum(P)) + direct) * hh
        E_out += qout + direct * hh
        ts.append(t1)
        rows_T.append(T.copy())
        rows_P.append(np.array([loss[b] for b in sources]))
        rows_s.append(scales)
        for key, v in (("speed", w), ("torque_ref", q), ("derate", f), ("tau", loss["tau"])):
            extra[key].append(v)
    Ta = np.array(rows_T)
    temps_out = {nm: Ta[:, i] for i, nm in enumerate(net.names)}
    temps_out.update({nm: np.full(Ta.shape[0], v) for nm, v in zip(net.boundary, net.Tb, strict=True)})
    Pa = np.array(rows_P)
    sa = np.array(rows_s)
    tr = ThermalTrace(t=np.array(ts), T=temps_out, P={b: Pa[:, i] for i, b in enumerate(sources)},
                      r_scale=sa[:, 0], k_scale=sa[:, 1], ron_scale=sa[:, 2], E_loss=E_loss,
                      E_stored=float(np.sum(net.C * (T - T0))), E_out=E_out,
                      extra={k: np.array(v) for k, v in extra.items()})
    return tr, pts.runs


def run_profile(drive: Drive, profile: LoadProfile, *, supply: str = "sine", control: Control | None = None,
                mode: str = "fast", h: float | None = None, ambient: float | None = None,
                T0: Mapping[str, float] | None = None, derate: Derating | None = None, compensated: bool = False,
                inverter: str | None = None, follow: bool = True,
                progress: Callable[[int, int], None] | None = None) -> ProfileResult:
    """Run a load profile through the drive and its thermal network.

    Parameters
    ----------
    drive : Drive
        With a thermal model (``[thermal]``).
    profile : LoadProfile
        Speed (imposed, as on a dynamometer or a vehicle whose speed the profile gives) and torque reference.
    supply : {"sine", "square"}
        The controller, both taking a torque reference (:func:`bldclab.analysis.effmap.map_controls`); ignored if
        ``control`` is given.
    control : Control, optional
        A controller taking a torque reference (N m).
    mode : {"fast", "switching"}
        Cycle-averaged quasi-static points, or the closed loop at every PWM period (module docstring).
    h : float, optional
        Thermal step (s); default 1 s (fast), 0.05 s (switching).
    ambient : float, optional
        Boundary temperature (degC) instead of the file's.
    T0 : mapping, optional
        Initial node temperatures (degC).
    derate : Derating, optional
        Torque derating with a node's temperature (fast mode).
    compensated : bool
        The firmware knows ``R`` and the flux at temperature (configured from the hot drive: it delivers the torque
        asked for); default False: configured at ``T_ref``, the torque per amp falls as the magnets warm.
    inverter : {"switching", "average"}, optional
        The inverter model of the fast mode's points (default: the drive's).
    follow : bool
        Parameters follow temperature (default); False: held at ``T_ref``.
    progress : callable, optional
        ``progress(done, total)`` (switching mode: samples).

    Returns
    -------
    ProfileResult
    """
    if mode not in ("fast", "switching"):
        raise BldclabError("mode", f"must be 'fast' or 'switching', got {mode!r}")
    if control is None:
        if supply not in ("sine", "square"):
            raise BldclabError("supply", f"must be 'sine' or 'square', got {supply!r}")
        low = min((abs(w) for w in profile.speed if w != 0.0), default=drive.Omega_0)
        control = map_controls(drive, max(low, MIN_SPEED_PU * drive.Omega_0))[supply]
    coupling = ThermalCoupling(h=h if h is not None else (1.0 if mode == "fast" else 0.05), T0=T0, ambient=ambient,
                               follow=follow)
    th = coupling.model(drive)
    limits = {n.name: float(n.T_max) for n in th.nodes if n.T_max is not None}
    t_start = time.perf_counter()
    if mode == "switching":
        if derate is not None:
            raise BldclabError("derate", "is applied by the fast mode only (the switching mode runs the profile's "
                               "torque as given)")
        w, q = profile.unrolled()
        est = None
        if compensated:
            raise BldclabError("compensated", "is available in the fast mode only")
        res = simulate(drive, control, Scenario(duration=profile.duration, speed=w, ref=q, trace=False),
                       thermal=coupling, estimate=est, progress=progress)
        tr: ThermalTrace = res.thermal
        t = tr.t
        mid = np.concatenate(([0.0], 0.5 * (t[1:] + t[:-1])))
        tr.extra.update({"speed": profile.speed_at(mid), "torque_ref": profile.torque_at(mid),
                         "derate": np.ones(t.size)})
        return ProfileResult(tr, mode, time.perf_counter() - t_start, 0, limits)
    if getattr(control, "derate", None) is not None:
        raise BldclabError("control.derate", "the fast mode's steady points have no temperature inputs: derate "
                           "with derate=Derating(...) here, or run the controller's own derating in mode='switching'")
    net = th.network()
    tr, runs = _fast(drive, th, net, coupling.initial(net), profile, control, coupling.h, compensated, inverter,
                     derate, follow)
    return ProfileResult(tr, mode, time.perf_counter() - t_start, runs, limits)


# ---------------------------------------------------------------------------------------------------------------
# envelopes


@dataclass
class Envelope:
    """Outcome of :func:`envelope`: the highest torque per speed that keeps every limited node below its ``T_max``.

    Attributes
    ----------
    speeds : ndarray
        Mechanical speeds (rad/s).
    torque : ndarray
        The mean torque (N m) the drive delivers at the highest allowed reference at each speed, at the envelope's
        temperatures (the steady state, or the end of ``duration``); 0 where even the lightest load overheats a node.
    limiting : list of str
        What sets it at each speed: a node's name; ``"delivery"`` where the drive under its controller does not
        deliver more (the bus voltage, or the controller's current limit ``i_limit``); ``"T_peak"`` at the
        search's top.
    duration : float or None
        ``None``: continuous (the steady state); else the time (s) from ``T0`` the torque is held.
    supply : str
    reference : ndarray
        The highest allowed torque reference (N m) at each speed.
    i_limit : float
        The controllers' current limit (A, peak phase current).
    """

    speeds: NDArray[np.float64]
    torque: NDArray[np.float64]
    limiting: list[str]
    duration: float | None
    supply: str
    reference: NDArray[np.float64] = dataclasses.field(default_factory=lambda: np.zeros(0))
    i_limit: float = math.nan

    def to_pandas(self) -> Any:
        """Return ``speed``, ``speed_rpm``, ``torque``, ``reference``, ``limiting`` as a DataFrame."""
        import pandas as pd

        return pd.DataFrame({"speed": self.speeds, "speed_rpm": self.speeds * 30.0 / math.pi, "torque": self.torque,
                             "reference": self.reference, "limiting": self.limiting})


def envelope_controls(drive: Drive, lowest_speed: float, i_limit: float | None = None) -> dict[str, Control]:
    """Return the envelope's controllers: both supplies limited to the same peak phase current.

    Parameters
    ----------
    drive : Drive
    lowest_speed : float
        Lowest speed (rad/s): the sinusoidal controller hands off from its square-wave start at half of it.
    i_limit : float, optional
        Peak phase current limit (A), default ``2 I_N`` (the square wave's default ``i_max``). The square wave
        clamps its current amplitude to it (``SixStep(i_max=...)``), the sinusoidal supply its amplitude
        (``Sine(i_s_max=...)``, with its over-current trip 25 % above, for the ripple).

    Returns
    -------
    dict
        ``{"square": SixStep, "sine": Sine}``, both taking a torque reference (N m).
    """
    i_lim = 2.0 * drive.motor.I_N if i_limit is None else i_limit
    check_number("i_limit", i_lim)
    return {"square": SixStep(reference="torque", i_max=i_lim),
            "sine": Sine(handoff_speed=0.5 * abs(lowest_speed), i_s_max=i_lim, i_max=1.25 * i_lim)}


def envelope(drive: Drive, speeds: Sequence[float], *, supply: str = "sine", duration: float | None = None,
             ambient: float | None = None, h: float = 5.0, tol: float = 0.005, compensated: bool = True,
             follow: bool = True, i_limit: float | None = None) -> Envelope:
    """Return the continuous (``duration=None``) or time-limited torque-speed envelope at an ambient.

    For each speed the torque reference is bisected (to ``tol`` of ``T_N``) between 0 and the motor's ``T_peak``:
    a reference is allowed when the drive delivers it (its steady mean torque not below ``g`` times it by more than
    :data:`bldclab.analysis.effmap.FEASIBLE_TOL_PU` of ``T_N``, ``g <= 1`` the controller's torque per unit of
    reference at a quarter of ``T_N`` and the ambient: a square wave on a sinusoidal back-EMF delivers about 4.5 %
    less than its ``k_e = 2 k_phi`` promises, which is its torque constant, not a limit) and no node with a
    ``T_max`` exceeds it: in the steady state (continuous: the fixed point ``T = T_ss(P(T))`` of the losses at
    temperature, iterated to 0.01 K) or during ``duration`` seconds from the ambient (exact steps of ``h`` s, the
    losses at each step's starting temperatures). The envelope's torque is the mean torque delivered there.

    Parameters
    ----------
    drive : Drive
    speeds : sequence of float
        Mechanical speeds (rad/s), non-zero.
    supply : {"sine", "square"}
    duration : float, optional
        Seconds from the ambient; None: continuous.
    ambient : float, optional
        Boundary temperature (degC).
    h : float
        Thermal step (s) of a time-limited envelope.
    tol : float
        Torque resolution (p.u. of ``T_N``).
    compensated : bool
        The controller knows the hot ``R`` and flux (default: the torque asked for is delivered, the envelope is
        the drive's, not its firmware's).
    follow : bool
        Parameters follow temperature (default); False: the envelope at ``T_ref`` parameters.
    i_limit : float, optional
        Peak phase current limit of both controllers (A), default ``2 I_N`` (:func:`envelope_controls`): the
        supplies are compared at the same peak current, the inverter's stress.

    Returns
    -------
    Envelope
    """
    if supply not in ("sine", "square"):
        raise BldclabError("supply", f"must be 'sine' or 'square', got {supply!r}")
    coupling = ThermalCoupling(ambient=ambient, follow=follow)
    th = coupling.model(drive)
    net = th.network()
    limits = {n.name: float(n.T_max) for n in th.nodes if n.T_max is not None and not n.boundary}
    if not limits:
        raise BldclabError("thermal", "no node has a T_max: an envelope needs a temperature limit")
    idx = {n: net.names.index(n) for n in limits}
    sources = [b for b, _ in th.losses]
    ws = [float(w) for w in speeds]
    control = envelope_controls(drive, min(abs(w) for w in ws), i_limit)[supply]
    i_lim = 2.0 * drive.motor.I_N if i_limit is None else float(i_limit)
    pts = _Points(drive, control, compensated, None)
    T_init = coupling.initial(net)

    def scales(T: NDArray[np.float64]) -> tuple[float, float, float]:
        return th.scales(net.temps(T)) if follow else (1.0, 1.0, 1.0)

    def verdict(w: float, q: float, g: float) -> tuple[str | None, float]:
        """(None if allowed, else what stops it; the mean torque delivered at the final temperatures)."""
        T = T_init.copy()
        tau = math.nan
        if duration is None:
            for _ in range(60):
                loss = pts.losses(w, q, scales(T), sources)
                tau = loss["tau"]
                if tau < g * q - FEASIBLE_TOL_PU * drive.T_N:
                    return "delivery", tau
                T_new = net.steady(net.heat({b: loss[b] for b in sources})[0])
                if any(T_new[i] > lim + 50.0 for n, i in idx.items() for lim in (limits[n],)):
                    T = T_new
                    break
                done = float(np.max(np.abs(T_new - T))) < 0.01
                T = T_new
                if done:
                    break
            worst = [(T[i] - limits[n], n) for n, i in idx.items()]
        else:
            worst_t = {n: -math.inf for n in idx}
            t = 0.0
            while t < duration - 1e-9:
                hh = min(h, duration - t)
                loss = pts.losses(w, q, scales(T), sources)
                tau = loss["tau"]
                if tau < g * q - FEASIBLE_TOL_PU * drive.T_N:
                    return "delivery", tau
                T, _ = net.step(T, net.heat({b: loss[b] for b in sources})[0], hh)
                t += hh
                for n, i in idx.items():
                    worst_t[n] = max(worst_t[n], T[i])
            worst = [(worst_t[n] - limits[n], n) for n in idx]
        over = max(worst)
        return (over[1] if over[0] > 0.0 else None), tau

    top = drive.motor.T_peak if drive.motor.T_peak is not None else 3.0 * drive.T_N
    torque = np.full(len(ws), math.nan)
    ref = np.full(len(ws), math.nan)
    limiting: list[str] = []
    q_g = 0.25 * drive.T_N
    for j, w in enumerate(ws):
        g = min(1.0, pts.losses(w, q_g, scales(T_init), sources)["tau"] / q_g)
        why_top, tau_top = verdict(w, top, g)
        if why_top is None:
            torque[j], ref[j] = tau_top, top
            limiting.append("T_peak")
            continue
        lo, hi, why, tau_lo = 0.0, top, why_top, 0.0
        while hi - lo > tol * drive.T_N:
            mid = 0.5 * (lo + hi)
            v, tau = verdict(w, mid, g)
            if v is None:
                lo, tau_lo = mid, tau
            else:
                hi, why = mid, v
        torque[j], ref[j] = tau_lo, lo
        limiting.append(why)
    return Envelope(np.array(ws), torque, limiting, duration, supply, ref, i_lim)

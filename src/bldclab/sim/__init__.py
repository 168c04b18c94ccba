"""Run the C closed loop: :func:`simulate` (drive, control, scenario) -> :class:`~bldclab.sim.results.SimResult`.

Python prepares the parameter structs and per-sample input arrays once; one call into C runs the whole simulation
(plant, sensors, controller, sample by sample) and fills the trace. Nothing in Python runs per time step.
"""

from __future__ import annotations

import ctypes
import dataclasses
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._core import core
from .._version import __version__
from ..control import Control
from ..control.user import run_isolated
from ..errors import BldclabError, PlausibilityError
from ..model.motor import Drive
from ..model.units import per_unit, to_si
from . import plausibility as _plaus
from .results import Metrics, SimResult
from .thermal import Coupler, ThermalCoupling

__all__ = ["TRACE_LIMIT", "Fault", "PerUnit", "Piecewise", "Scenario", "check_estimate", "parse_profile", "simulate",
           "trace_bytes", "trace_rows"]

Profile = float | ArrayLike | Callable[[NDArray[np.float64]], ArrayLike] | None  # or a PerUnit speed

#: Fault kind -> (C constant ``BC_FAULT_*``, whose record holds it)
_FAULT_KINDS = {"phase_open": ("BC_FAULT_PHASE_OPEN", "plant"), "hall_stuck": ("BC_FAULT_HALL_STUCK", "plant"),
                "hall_glitch": ("BC_FAULT_HALL_GLITCH", "plant"),
                "current_offset": ("BC_FAULT_CURRENT_OFFSET", "sensors"),
                "current_loss": ("BC_FAULT_CURRENT_LOSS", "sensors")}
_MAX_FAULTS = 4

#: Trace fields renamed in results: ``flags`` would collide with pandas' ``DataFrame.flags``
_RENAMED = {"flags": "ctrl_flags"}

#: Units of the controllers' diagnostic channels, by their label (``Controller.diag``); others are "-"
_DIAG_UNITS = {"i_d": "A", "i_q": "A", "i_q_ref": "A", "i_reg": "A", "i_ref": "A", "i_out": "A", "i_off": "A",
               "v_d": "V", "v_q": "V", "theta": "rad", "theta_est": "rad", "omega_e": "rad/s",
               "omega_est": "rad/s", "tau_est": "N m", "tau_pred": "N m"}

#: Scenario inputs that also take a unit string or a profile string (:func:`parse_profile`), and their dimension
_UNIT_FIELDS = {"speed": "speed", "omega_ref": "speed", "load_torque": "torque", "v_dc": "voltage"}
#: Scenario inputs that also take speeds in per unit of the drive's Omega_0 (``"0.5 pu"``, :class:`PerUnit`)
_PU_FIELDS = ("speed", "omega_ref")


@dataclass(frozen=True)
class Piecewise:
    """A piecewise-linear profile through points ``(t_j, y_j)``: constant before the first and after the last.

    Repeat a time for a step: ``Piecewise((0, 0.1, 0.1, 1), (0, 0, 10, 10))`` is 0 until 0.1 s, then 10.

    Parameters
    ----------
    times : tuple of float
        Non-decreasing times (s).
    values : tuple of float
        Values at those times (SI unit of the input).
    """

    times: tuple[float, ...]
    values: tuple[float, ...]

    def __post_init__(self) -> None:
        if not self.times or len(self.times) != len(self.values):
            raise BldclabError("profile", "needs as many times as values, at least one")
        if any(b < a for a, b in itertools.pairwise(self.times)):
            raise BldclabError("profile", f"times must not decrease, got {list(self.times)}")

    def __call__(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return the profile at times ``t`` (s)."""
        return np.interp(t, self.times, self.values)

    def __str__(self) -> str:
        """Return the profile in the syntax :func:`parse_profile` reads (SI units)."""
        return ", ".join(f"{a:g} s: {b:g}" for a, b in zip(self.times, self.values, strict=True))


@dataclass(frozen=True)
class PerUnit:
    """A speed given in per unit of the drive's no-load speed ``Omega_0`` (``"0.5 pu"``), resolved by :func:`simulate`.

    A :class:`Scenario` does not know the drive: ``Scenario(speed="0.5 pu")`` holds this, and :func:`simulate` (or
    :meth:`Scenario.resolved`) multiplies the per-unit values by the drive's ``Omega_0 = V_dc / (2 k_phi)`` (at the
    inverter's ``V_dc``), as ``bldclab simulate --speed "0.5 pu"`` does.

    Parameters
    ----------
    values : tuple of float
        The values: per unit where ``per_unit`` says so, else rad/s.
    per_unit : tuple of bool
        Which values are per unit (a profile may mix ``"0 rpm"`` and ``"0.5 pu"`` points).
    times : tuple of float, optional
        The profile's times (s); None for a constant (one value).
    """

    values: tuple[float, ...]
    per_unit: tuple[bool, ...]
    times: tuple[float, ...] | None = None

    def resolve(self, omega_0: float) -> float | Piecewise:
        """Return the speed in rad/s: a number, or a :class:`Piecewise` profile.

        Parameters
        ----------
        omega_0 : float
            The drive's no-load speed (rad/s), the per-unit base.
        """
        v = tuple(x * omega_0 if pu else x for x, pu in zip(self.values, self.per_unit, strict=True))
        return v[0] if self.times is None else Piecewise(self.times, v)

    def __str__(self) -> str:
        """Return the speed as typed, in the syntax :func:`parse_profile` reads (SI values without a unit)."""
        text = [f"{x:g} pu" if pu else f"{x:g}" for x, pu in zip(self.values, self.per_unit, strict=True)]
        if self.times is None:
            return text[0]
        return ", ".join(f"{t:g} s: {v}" for t, v in zip(self.times, text, strict=True))


@overload
def parse_profile(text: str, dimension: str, field: str, convert: Callable[[str], float] | None = None, *,
                  per_unit_base: Literal[False] = False) -> float | Piecewise: ...


@overload
def parse_profile(text: str, dimension: str, field: str, convert: Callable[[str], float] | None = None, *,
                  per_unit_base: bool) -> float | Piecewise | PerUnit: ...


def parse_profile(text: str, dimension: str, field: str, convert: Callable[[str], float] | None = None, *,
                  per_unit_base: bool = False) -> float | Piecewise | PerUnit:
    """Read a constant (``"300 rpm"``) or a piecewise-linear profile (``"0 s: 0 rpm, 0.1 s: 1000 rpm"``).

    A profile is a comma-separated list of ``time: value`` points, times non-decreasing (a time without a unit is
    in seconds, a value without a unit in SI); the input is linear between points, constant before the first and
    after the last; a repeated time makes a step (``"0.2 s: 0 N m, 0.2 s: 5 N m"``).

    Parameters
    ----------
    text : str
        The constant or the profile.
    dimension : str
        Dimension of the values (a key of :data:`bldclab.model.units.DIMENSIONS`, e.g. ``"speed"``).
    field : str
        Name for error messages (an option such as ``--load`` or a field such as ``scenario.speed``).
    convert : callable, optional
        Reads one value (default :func:`bldclab.model.units.to_si` with ``dimension``), e.g. to accept per-unit
        speeds.
    per_unit_base : bool
        Also accept values in per unit (``"0.5 pu"``) of a base the caller applies later: then a text holding any
        returns a :class:`PerUnit` (the speeds of a :class:`Scenario`, in p.u. of the drive's ``Omega_0``).

    Returns
    -------
    float or Piecewise or PerUnit

    Raises
    ------
    BldclabError
        Naming ``field`` and the point that could not be read.
    """
    flags: list[bool] = []

    def value(v: str, where: str) -> float:
        pu = per_unit(v) if per_unit_base else None
        flags.append(pu is not None)
        if pu is not None:
            return pu
        return convert(v) if convert is not None else to_si(v, dimension, where)

    if ":" not in text:
        x = value(text, field)
        if not math.isfinite(x):
            raise BldclabError(field, f"must be finite, got {text!r}")
        return PerUnit((x,), (True,)) if flags[0] else x
    times, values = [], []
    for j, point in enumerate(text.split(",")):
        if point.count(":") != 1:
            raise BldclabError(field, f"point {j + 1} {point.strip()!r} is not 'time: value' "
                               "(e.g. '0 s: 0 rpm, 0.1 s: 1000 rpm')")
        t_text, v_text = point.split(":")
        times.append(to_si(t_text, "time", f"{field} (time of point {j + 1})"))
        values.append(value(v_text, f"{field} (value of point {j + 1})"))
    for j, (ta, tb) in enumerate(itertools.pairwise(times)):
        if tb < ta:
            raise BldclabError(field, f"times must not decrease: point {j + 2} ({tb:g} s) is before point {j + 1} "
                               f"({ta:g} s)")
    if not all(math.isfinite(v) for v in times + values):
        raise BldclabError(field, f"every time and value must be finite, got {text!r}")
    if any(flags):
        return PerUnit(tuple(values), tuple(flags), tuple(times))
    return Piecewise(tuple(times), tuple(values))


@dataclass(frozen=True)
class Fault:
    """A fault injected during a run, active on ``[t_on, t_off)``.

    Parameters
    ----------
    kind : {"phase_open", "hall_stuck", "hall_glitch", "current_offset", "current_loss"}
        ``phase_open``: the phase's wire breaks (no current through switch or diode; a current flowing at ``t_on``
        is lost in an arc, booked as ``meta["stats"]["e_fault"]``); ``hall_stuck``: the phase's Hall sensor reads
        ``value`` (0 or 1); ``hall_glitch``: it reads inverted; ``current_offset``: the phase's current sensor reads
        ``value`` A more; ``current_loss``: it reads 0. A DC-bus sag is a ``Scenario.v_dc`` profile; a misplaced
        Hall edge is ``Sensors.hall_error``.
    phase : {"a", "b", "c"}
        Phase (or its sensor).
    t_on, t_off : float
        Start and end (s); ``t_off`` defaults to never.
    value : float
        Stuck level (0/1) or offset (A).
    """

    kind: str
    phase: str
    t_on: float
    t_off: float = math.inf
    value: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in _FAULT_KINDS:
            raise BldclabError("fault.kind", f"must be one of {', '.join(_FAULT_KINDS)}, got {self.kind!r}")
        if self.phase not in ("a", "b", "c"):
            raise BldclabError("fault.phase", f"must be 'a', 'b' or 'c', got {self.phase!r}")
        _check_scalar("fault.t_on", self.t_on)
        if not (isinstance(self.t_off, int | float) and not math.isnan(self.t_off) and self.t_off > self.t_on):
            raise BldclabError("fault.t_off", f"must be after t_on ({self.t_on}), got {self.t_off}")
        _check_scalar("fault.value", self.value)
        if self.kind == "hall_stuck" and self.value not in (0.0, 1.0):
            raise BldclabError("fault.value", f"a stuck Hall sensor reads 0 or 1, got {self.value}")


@dataclass(frozen=True, eq=False)
class Scenario:
    """What to simulate.

    Every time-varying input (a profile) is a number, an array with one value per sample (half PWM period), or a
    function of the sample times (s, array) returning one value per time. A long run calls the function on
    pieces of the run (:data:`CHUNK` samples), so it must work elementwise (as ``np.interp`` or ``np.where`` do).

    Parameters
    ----------
    duration : float or str
        Simulated time (s, or a string such as ``"200 ms"``); rounded up to whole samples of ``1/(2 f_pwm)``.
    speed : profile, optional
        Imposed mechanical speed (rad/s); also a string, ``"300 rpm"``, ``"0.5 pu"`` (per unit of the drive's
        no-load speed ``Omega_0``: a :class:`PerUnit`, which :func:`simulate` resolves with the drive it runs), or a
        piecewise-linear profile such as ``"0 s: 0 rpm, 0.1 s: 1000 rpm"`` (see :func:`parse_profile`). The rotor is
        held by a dynamometer.
        ``None`` (default): the rotor follows ``J dw/dt = tau_e - tau_L - B w - tau_c sign(w)`` with the drive's
        mechanics.
    ref : profile
        The controller's reference (what it means depends on the controller, e.g. a duty or a torque in N m), in
        SI numbers (its unit depends on the controller, so no unit strings).
    omega_ref : profile
        Speed reference (rad/s, or a unit, per-unit or profile string as for ``speed``) for controllers with a speed
        loop.
    load_torque : profile
        Load torque ``tau_L`` (N m, or ``"10 N m"``, or a profile string), rotor dynamics only.
    v_dc : profile, optional
        DC source voltage (V, or ``"48 V"``, or a profile string); default the inverter's ``V_dc``.
    theta0 : float
        Initial electrical angle (rad).
    omega0 : float, optional
        Initial speed (rad/s); default the imposed speed at t = 0, or 0.
    i0 : tuple of float
        Initial phase currents (A), projected to sum zero.
    delay : int, optional
        Controller computation delay in samples (1: output applied from the next sample, as on a DSP; 0: within the
        sample). ``None`` (default): the controller's own, its ``delay`` setting (1 for every built-in controller
        but :class:`~bldclab.control.sensorless.SixStepSensorless`, an ESC's firmware that commutates in its
        interrupts: 0), 1 for a controller without one.
    trace_every : int
        Samples per trace row (>= 1); larger values thin long traces (means and extremes still cover every row).
    trace_sub : int
        Trace rows per sample (>= 1, with ``trace_every == 1``) to see the PWM ripple.
    trace : bool
        Keep a trace at all (False: metrics only, least memory).
    window : tuple of float or str, optional
        Metric window (t0, t1) in s (numbers or unit strings such as ``"20 ms"``); ``None`` (default): the whole
        run, start included (the plausibility guards on metrics, energy balance and steady state, check only a
        window you chose).
    h_max : float
        Longest integration step (s); 0: half a PWM period (events set the steps anyway).
    faults : tuple of Fault
        Faults injected during the run (at most four in the plant and four in the sensors).
    """

    duration: float
    speed: Profile = None
    ref: Profile = 0.0
    omega_ref: Profile = 0.0
    load_torque: Profile = 0.0
    v_dc: Profile = None
    theta0: float = 0.0
    omega0: float | None = None
    i0: tuple[float, float, float] = (0.0, 0.0, 0.0)
    delay: int | None = None
    trace_every: int = 1
    trace_sub: int = 1
    trace: bool = True
    window: tuple[float, float] | None = None
    h_max: float = 0.0
    faults: tuple[Fault, ...] = ()

    def __post_init__(self) -> None:
        # unit strings where the dimension is fixed; ref's unit depends on the controller, so it takes numbers
        if isinstance(self.duration, str):
            object.__setattr__(self, "duration", to_si(self.duration, "time", "scenario.duration"))
        for name, dim in _UNIT_FIELDS.items():
            v = getattr(self, name)
            if isinstance(v, str):
                object.__setattr__(self, name, parse_profile(v, dim, f"scenario.{name}",
                                                             per_unit_base=name in _PU_FIELDS))
        if self.window is not None and any(isinstance(v, str) for v in self.window):
            object.__setattr__(self, "window", tuple(to_si(v, "time", "scenario.window") for v in self.window))
        _check_scalar("scenario.duration", self.duration, positive=True)
        _check_scalar("scenario.theta0", self.theta0)
        if self.omega0 is not None:
            _check_scalar("scenario.omega0", self.omega0)
        if len(self.i0) != 3:
            raise BldclabError("scenario.i0", "needs three currents (a, b, c)")
        for j, v in enumerate(self.i0):
            _check_scalar(f"scenario.i0[{j}]", v)
        if self.delay is not None and (isinstance(self.delay, bool) or self.delay not in (0, 1)):
            raise BldclabError("scenario.delay", f"must be 0 or 1 sample (or None: the controller's own), got "
                                                 f"{self.delay!r}")
        for name in ("trace_every", "trace_sub"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise BldclabError(f"scenario.{name}", f"must be an integer >= 1, got {v!r}")
        if self.trace_sub > 1 and self.trace_every != 1:
            raise BldclabError("scenario.trace_sub", "needs trace_every = 1")
        _check_scalar("scenario.h_max", self.h_max)
        if self.h_max < 0:
            raise BldclabError("scenario.h_max", "must be >= 0")
        if not all(isinstance(f, Fault) for f in self.faults):
            raise BldclabError("scenario.faults", "must be a tuple of bldclab.Fault")
        for where in ("plant", "sensors"):
            if sum(_FAULT_KINDS[f.kind][1] == where for f in self.faults) > _MAX_FAULTS:
                raise BldclabError("scenario.faults", f"at most {_MAX_FAULTS} faults in the {where}")
        if self.window is not None:
            if len(self.window) != 2:
                raise BldclabError("scenario.window", "must be (t0, t1) in seconds")
            t0, t1 = self.window
            _check_scalar("scenario.window", t0)
            _check_scalar("scenario.window", t1)
            if not 0.0 <= t0 < t1 <= self.duration * (1 + 1e-12) + 1e-15:
                raise BldclabError("scenario.window", f"needs 0 <= t0 < t1 <= duration, got ({t0}, {t1})")


    def resolved(self, drive: Drive) -> Scenario:
        """Return the scenario with its per-unit speeds (:class:`PerUnit`) in rad/s for ``drive`` (itself if none).

        Parameters
        ----------
        drive : Drive
            The drive whose no-load speed ``Omega_0`` is the per-unit base.

        Returns
        -------
        Scenario
        """
        changes = {name: getattr(self, name).resolve(drive.Omega_0) for name in _PU_FIELDS
                   if isinstance(getattr(self, name), PerUnit)}
        return dataclasses.replace(self, **changes) if changes else self


def _check_scalar(name: str, v: object, positive: bool = False) -> None:
    if isinstance(v, bool) or not isinstance(v, int | float | np.integer | np.floating):
        raise BldclabError(name, f"expected a number, got {type(v).__name__}")
    if not math.isfinite(float(v)):
        raise BldclabError(name, f"must be finite, got {v}")
    if positive and float(v) <= 0.0:
        raise BldclabError(name, f"must be > 0, got {v}")


#: Samples per call into the C runner: the runner's state carries over between calls, so a long run needs the
#: memory of one piece of its inputs (and of the trace it keeps), whatever its duration.
CHUNK = 1 << 17


def _times(j0: int, j1: int, t_half: float) -> NDArray[np.float64]:
    """Sample times of samples ``j0 .. j1 - 1`` (s); the same values as ``np.arange(n)[j0:j1] * t_half``."""
    return np.arange(j0, j1, dtype=np.float64) * t_half


class _Profile:
    """One per-sample input: a constant, a whole array, or a function evaluated on the run's pieces.

    ``first`` is the value at t = 0 and ``peak`` the largest magnitude over the run (for the guards).
    """

    def __init__(self, name: str, value: Profile, n: int, t_half: float) -> None:
        self.name, self.n, self.t_half = name, n, t_half
        self.const = 0.0
        self.arr: NDArray[np.float64] | None = None
        self.fn: Callable[[NDArray[np.float64]], ArrayLike] | None = None
        if value is None:
            self.first = self.peak = 0.0
        elif isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool):
            _check_scalar(name, value)
            self.const = float(value)
            self.first, self.peak = self.const, abs(self.const)
        elif callable(value):
            self.fn = value
            self.first, self.peak = math.nan, 0.0
            for j0, j1 in _chunks(n):
                a = self._eval(j0, j1)
                if j0 == 0:
                    self.first = float(a[0])
                self.peak = max(self.peak, float(np.max(np.abs(a))))
                if j1 - j0 == n:  # one piece: keep it rather than call the function again
                    self.arr, self.fn = a, None
        else:
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise BldclabError(name, f"expected a number, an array or a function, got {type(value).__name__}"
                                   ) from None
            if arr.shape != (n,):
                raise BldclabError(name, f"needs one value per sample ({n}), got shape {arr.shape}")
            self._check_finite(arr, 0)
            self.arr = np.ascontiguousarray(arr)
            self.first, self.peak = float(arr[0]), float(np.max(np.abs(arr)))

    def _eval(self, j0: int, j1: int) -> NDArray[np.float64]:
        assert self.fn is not None
        t = _times(j0, j1, self.t_half)
        try:
            arr = np.asarray(self.fn(t), dtype=float)
        except Exception as exc:
            raise BldclabError(self.name, f"the function failed on the sample times: {exc}") from None
        if arr.ndim == 0:
            arr = np.full(t.shape, float(arr))
        if arr.shape != t.shape:
            raise BldclabError(self.name, f"needs one value per sample ({t.size}), got shape {arr.shape}")
        self._check_finite(arr, j0)
        return np.ascontiguousarray(arr)

    def _check_finite(self, arr: NDArray[np.float64], j0: int) -> None:
        bad = np.nonzero(~np.isfinite(arr))[0]
        if bad.size:
            k = j0 + int(bad[0])
            raise BldclabError(self.name, f"value at sample {k} (t = {k * self.t_half:.6g} s) is {arr[bad[0]]}")

    def piece(self, j0: int, j1: int) -> NDArray[np.float64] | None:
        """Return the values of samples ``j0 .. j1 - 1`` (None for a constant)."""
        if self.fn is not None:
            return self._eval(j0, j1)
        if self.arr is not None:
            return self.arr[j0:j1]
        return None


def _chunks(n: int) -> list[tuple[int, int]]:
    return [(j0, min(n, j0 + CHUNK)) for j0 in range(0, n, CHUNK)]


#: Default bound on a run's trace (bytes): :func:`simulate` refuses a scenario whose trace would be larger
TRACE_LIMIT = 2_000_000_000


def trace_rows(drive: Drive, scenario: Scenario) -> int:
    """Return the number of trace rows a run of ``scenario`` keeps (0 with ``trace=False``)."""
    if not scenario.trace:
        return 0
    n = samples_of(drive, scenario.duration)
    return n // scenario.trace_every if scenario.trace_sub == 1 else n * scenario.trace_sub


def trace_bytes(drive: Drive, scenario: Scenario) -> int:
    """Return the memory (bytes) the trace of a run of ``scenario`` takes; the rest of a run is bounded.

    Use it to choose ``trace_every`` (or ``trace=False``) before a long run: the trace is the only part of a run
    whose size grows with the duration (inputs given as numbers or functions are evaluated piece by piece).
    """
    return trace_rows(drive, scenario) * core().trace_dtype.itemsize


def _plant_params(drive: Drive, imposed: bool, h_max: float, keep: list[object]) -> np.ndarray:
    c = core()
    rec = c.record("bc_plant_params")
    m, inv, mech_p, sen = drive.motor, drive.inverter, drive.mechanics, drive.sensors
    rec["p"] = m.p
    rec["R"] = m.R
    rec["L"] = m.L
    for x, shape in enumerate(m.emf.shapes):
        kind, xa, ya = shape.c_form()
        xa = np.ascontiguousarray(xa, dtype=float)
        ya = np.ascontiguousarray(ya, dtype=float)
        keep += [xa, ya]
        rec["emf"]["kind"][0, x] = kind
        rec["emf"]["n"][0, x] = xa.size
        rec["emf"]["x"][0, x] = xa.ctypes.data
        rec["emf"]["y"][0, x] = ya.ctypes.data
    if m.cogging is not None:
        arrs = [np.ascontiguousarray(np.asarray(v, dtype=float)) for v in (m.cogging.orders, m.cogging.amplitudes,
                                                                           m.cogging.phases)]
        keep += arrs
        rec["n_cog"] = arrs[0].size
        rec["cog_order"], rec["cog_amp"], rec["cog_phase"] = (a.ctypes.data for a in arrs)
    rec["k_fe_e"] = m.k_fe_eddy  # iron loss: the coefficients reproducing P_fe_* at speed_fe_ref
    rec["k_fe_h"] = m.k_fe_hyst
    rec["k_fe_x"] = m.k_fe_ex
    rec["f_pwm"] = inv.f_pwm
    rec["t_dead"] = inv.t_dead
    rec["R_on"] = inv.R_on
    rec["V_f"] = inv.V_f
    rec["r_d"] = inv.r_d
    rec["R_src"] = inv.R_src
    rec["i_trip"] = inv.i_trip
    rec["inverter"] = c.const("BC_INV_AVERAGE" if inv.model == "average" else "BC_INV_SWITCHING")
    for name in inv.SWITCHING_LOSS_FIELDS:
        rec[name] = getattr(inv, name)
    rec["mech"] = c.const("BC_MECH_IMPOSED" if imposed else "BC_MECH_DYNAMIC")
    rec["J"] = mech_p.J
    rec["B"] = mech_p.B
    rec["tau_c"] = mech_p.tau_c
    rec["k_q"] = mech_p.k_q
    rec["hall_error"] = sen.hall_error
    rec["hall_hyst"] = sen.hall_hysteresis
    rec["hall_delay"] = sen.hall_delay
    rec["hall_tau"] = sen.hall_tau
    rec["h_max"] = h_max
    return rec


def _sensor_params(drive: Drive) -> np.ndarray:
    rec = core().record("bc_sensor_params")
    s = drive.sensors
    rec["i_mask"] = s.current_mask
    rec["i_gain"] = s.current_gain
    rec["i_offset"] = s.current_offset
    rec["i_noise"] = s.current_noise
    rec["i_lsb"] = s.current_lsb
    rec["i_fs"] = s.current_full_scale
    rec["v_gain"] = s.vdc_gain
    rec["v_offset"] = s.vdc_offset
    rec["v_noise"] = s.vdc_noise
    rec["v_lsb"] = s.vdc_lsb
    rec["f_tick"] = s.f_tick
    rec["seed"] = s.seed
    return rec


def _sense_params(drive: Drive, on: bool) -> np.ndarray:
    """Return the back-EMF sensing record (``on``: the drive asks for it or the controller needs it)."""
    c = core()
    rec = c.record("bc_sense_params")
    s = drive.sensors
    rec["on"] = 1 if on else 0
    rec["tau"] = s.bemf_tau
    rec["ref"] = c.const("BC_SENSE_REF_HALF" if s.bemf_reference == "half" else "BC_SENSE_REF_STAR")
    rec["offset"] = s.bemf_offset
    rec["hyst"] = s.bemf_hysteresis
    rec["delay"] = s.bemf_delay
    rec["adc_at"] = s.bemf_adc_at
    rec["adc_lsb"] = s.bemf_adc_lsb
    rec["adc_max"] = s.bemf_adc_max
    rec["adc_noise"] = s.bemf_adc_noise
    rec["f_pwm"] = drive.inverter.f_pwm
    rec["f_tick"] = s.f_tick
    rec["seed"] = s.seed + 1  # a stream apart from the current and voltage sensors'
    return rec


def samples_of(drive: Drive, duration: float) -> int:
    """Return the number of controller samples (half PWM periods) covering ``duration`` seconds."""
    n = duration * 2.0 * drive.inverter.f_pwm
    return max(1, math.ceil(n - 1e-9))


def simulate(drive: Drive, control: Control, scenario: Scenario, *, check: str = "error",
             estimate: Drive | None = None, progress: Callable[[int, int], None] | None = None,
             max_trace_bytes: int | None = TRACE_LIMIT, thermal: ThermalCoupling | None = None) -> SimResult:
    """Simulate the drive in closed loop with a C controller.

    Plausibility guards (:mod:`bldclab.sim.plausibility`) run before the run (PWM frequency against ``L/R`` and the
    electrical frequency, imposed speed against the no-load speed, reference against the controller's current
    limit) and after it (finite values, energy balance, currents after a hardware trip, steady state of the metric
    window with rotor dynamics). A questionable run issues a :class:`~bldclab.errors.PlausibilityWarning`; a
    physically meaningless one raises :class:`~bldclab.errors.PlausibilityError` unless ``check`` says otherwise.
    The warnings issued are kept in ``result.meta["warnings"]``.

    Parameters
    ----------
    drive : Drive
        Motor, inverter, mechanics, sensors.
    control : Control
        The controller (e.g. :class:`~bldclab.control.SixStepVoltage`).
    scenario : Scenario
        Duration, speed or mechanics, references, trace and metric window.
    check : {"error", "warn", "off"}
        ``"error"`` (default): warnings for questionable runs, an exception for meaningless ones; ``"warn"``: only
        warnings (for runs that go there on purpose, e.g. a fault driving hundreds of amps); ``"off"``: no guards.
    estimate : Drive, optional
        The drive the controller is configured from (its gains, models and limits), when it differs from the plant:
        parameter-mismatch studies, e.g. ``estimate=drive.scaled(L=1.2, emf=0.95)``. Default: the plant's own
        ``drive``. Pole pairs and PWM frequency must match the plant's (they are not estimates but the hardware the
        controller runs on).
    progress : callable, optional
        Called as ``progress(done, total)`` (samples) after each piece of :data:`CHUNK` samples the C runner
        completes, e.g. to draw a progress bar.
    max_trace_bytes : int or None
        Refuse (before running) a scenario whose trace would take more memory than this (bytes; default
        :data:`TRACE_LIMIT`, 2 GB; ``None``: no bound). Everything but the trace is bounded whatever the duration.
    thermal : ThermalCoupling, optional
        Couple the plant with the drive's thermal network (``[thermal]`` of its motor file): the plant runs in
        chunks of ``thermal.h`` seconds, each chunk's losses heat the network, the temperatures set ``R``, the
        back-EMF and ``R_on`` for the next (:mod:`bldclab.sim.thermal`). The result's ``thermal`` attribute holds
        the :class:`~bldclab.sim.thermal.ThermalTrace`; ``meta["thermal"]`` its summary. The controller is
        configured from the drive at ``T_ref`` (``estimate`` if given), as a firmware that does not know the
        temperature.

    Returns
    -------
    SimResult

    Raises
    ------
    BldclabError
        For invalid scenario inputs (NaN in a profile, wrong length) or parameters the C core rejects.
    PlausibilityError
        With ``check="error"``, for a run whose result would be physically meaningless (a subclass of
        :class:`~bldclab.errors.BldclabError` naming the cause and the numbers). When its inputs raised warnings
        before the run, the error leads with them as the cause (:func:`bldclab.sim.plausibility.cause_first`).
    """
    if check not in _plaus.CHECK_MODES:
        raise BldclabError("check", f"must be one of {', '.join(_plaus.CHECK_MODES)}, got {check!r}")
    if not isinstance(drive, Drive):
        raise BldclabError("drive", f"expected a Drive, got {type(drive).__name__}")
    if not isinstance(control, Control):
        raise BldclabError("control", f"expected a bldclab.control controller, got {type(control).__name__}")
    check_estimate(drive, estimate)
    if not isinstance(scenario, Scenario):
        raise BldclabError("scenario", f"expected a bldclab.Scenario, got {type(scenario).__name__}")
    scenario = scenario.resolved(drive)
    if thermal is not None:
        if not isinstance(thermal, ThermalCoupling):
            raise BldclabError("thermal", f"expected a bldclab.sim.thermal.ThermalCoupling, got "
                               f"{type(thermal).__name__}")
        if scenario.window is not None and not scenario.trace:
            raise BldclabError("scenario.window", "a thermal run reads the losses of every chunk, which a run "
                               "without a trace integrates only inside its metric window: leave window unset")
    need = trace_bytes(drive, scenario)
    if max_trace_bytes is not None and need > max_trace_bytes:
        raise BldclabError("scenario.trace", f"a run of {scenario.duration:.4g} s keeps {trace_rows(drive, scenario)} "
                           f"trace rows, {need / 1e9:.3g} GB (max_trace_bytes {max_trace_bytes / 1e9:.3g} GB): thin "
                           "it with trace_every=N, drop it with trace=False, or raise max_trace_bytes")
    if control.isolated:  # user code: in a watched child process (bldclab.control.user)
        result: SimResult = run_isolated(
            control, lambda watch: _run(drive, control, scenario, check, estimate, None, watch, thermal),
            0.5 / drive.inverter.f_pwm, progress, samples_of(drive, scenario.duration))
        return result
    return _run(drive, control, scenario, check, estimate, progress, None, thermal)


def _run(drive: Drive, control: Control, scenario: Scenario, check: str, estimate: Drive | None,
         progress: Callable[[int, int], None] | None, watch: Any, thermal: ThermalCoupling | None = None) -> SimResult:
    """Run the simulation of :func:`simulate` after its checks.

    ``watch``: the progress record of an isolated run; ``thermal``: the coupling with the thermal network.
    """
    c = core()
    delay = control.own_delay if scenario.delay is None else scenario.delay
    control = control.with_delay(delay)
    keep: list[object] = []
    n = samples_of(drive, scenario.duration)
    t_half = 0.5 / drive.inverter.f_pwm
    imposed = scenario.speed is not None

    plant = _plant_params(drive, imposed, scenario.h_max, keep)
    sensors = _sensor_params(drive)
    sense = _sense_params(drive, drive.sensors.bemf or control.needs_bemf_sensing)
    slots = {"plant": 0, "sensors": 0}
    for f in scenario.faults:
        name, where = _FAULT_KINDS[f.kind]
        code = c.const(name)
        rec = plant if where == "plant" else sensors
        j = slots[where]
        slots[where] += 1
        rec["fault"]["kind"][0, j] = code
        rec["fault"]["phase"][0, j] = "abc".index(f.phase)
        rec["fault"]["t_on"][0, j] = f.t_on
        rec["fault"]["t_off"][0, j] = f.t_off
        rec["fault"]["value"][0, j] = f.value
    slot = control.c_slot(drive if estimate is None else estimate, c, n, watch=watch)
    keep.append(slot)
    cparams = slot.record.record

    inputs = c.record("bc_sim_inputs")
    v_dc = drive.inverter.V_dc if scenario.v_dc is None else scenario.v_dc
    profiles: dict[str, _Profile] = {}
    for field, name, value in (("ref", "scenario.ref", scenario.ref),
                               ("omega_ref", "scenario.omega_ref", scenario.omega_ref),
                               ("omega", "scenario.speed", scenario.speed),
                               ("tau_load", "scenario.load_torque", scenario.load_torque),
                               ("v_src", "scenario.v_dc", v_dc)):
        profiles[field] = prof = _Profile(name, value, n, t_half)
        inputs[f"{field}_c"] = prof.const
    first = {k: v.first for k, v in profiles.items()}
    peak = {k: v.peak for k, v in profiles.items()}
    omega0 = scenario.omega0 if scenario.omega0 is not None else (first["omega"] if imposed else 0.0)
    v0 = first["v_src"]
    issued = _guards_before(drive, control, cparams, imposed, peak, check)

    cfg = c.record("bc_sim_config")
    cfg["plant"] = plant.ctypes.data
    cfg["sensors"] = sensors.ctypes.data
    cfg["sense"] = sense.ctypes.data
    cfg["ctrl"]["step"] = slot.step
    cfg["ctrl"]["params"] = slot.params
    cfg["ctrl"]["state"] = slot.state
    cfg["delay"] = delay
    cfg["trace_every"] = scenario.trace_every
    cfg["trace_sub"] = scenario.trace_sub
    # the run ends at the last whole sample; a window ending within rounding of it closes there
    t0w, t1w = scenario.window if scenario.window is not None else (0.0, n * t_half)
    cfg["metric_t0"], cfg["metric_t1"] = t0w, min(t1w, n * t_half)

    state = c.opaque("bc_sim_state")
    i0 = np.ascontiguousarray(scenario.i0, dtype=float)
    rc = c.lib.bc_sim_init(cfg.ctypes.data, state.ctypes.data, float(scenario.theta0), float(omega0),
                           i0.ctypes.data, v0)
    if rc != 0:
        raise BldclabError("drive", "the C plant rejected the parameters (a value out of its physical range)")

    n_rows = trace_rows(drive, scenario)
    # np.empty, not zeros: the runner writes every field of every row it reports and the rest is cut off below; calloc
    # would clear the 344-byte records (10 MB a simulated second) that the last run's freed buffer gives back
    rows = np.empty(n_rows, dtype=c.trace_dtype)
    n_written = 0
    chunks = _chunks(n)
    coupler = None
    if thermal is not None:
        coupler = Coupler(thermal, drive, c.acc_names)
        m = max(1, round(thermal.h / t_half))
        chunks = [(j0, min(n, j0 + m)) for j0 in range(0, n, m)]
        coupler.start(c.view(state, "bc_sim_state")[0]["plant"]["acc"])
        coupler.apply(c.lib, cfg, state)
    for j0, j1 in chunks:
        pieces = []
        for field, prof in profiles.items():
            a = prof.piece(j0, j1)
            pieces.append(a)  # alive until C has read it
            inputs[field] = 0 if a is None else a.ctypes.data
        written = ctypes.c_int64(0)
        ptr = rows.ctypes.data + n_written * rows.itemsize if n_rows else None
        rc = slot.run(c, cfg, state, inputs, j1 - j0, ptr, n_rows - n_written, written)
        if rc != 0:
            raise RuntimeError(f"bc_sim_run failed with code {rc}")  # a bug, not bad input: inputs were validated
        n_written += written.value
        if coupler is not None:
            pst = c.view(state, "bc_sim_state")[0]["plant"]
            coupler.chunk(float(pst["t"]), pst["acc"])
            coupler.apply(c.lib, cfg, state)
        if progress is not None and (coupler is None or j1 == n or j1 % CHUNK < j1 - j0):
            progress(j1, n)
    rows = rows[:n_written]

    st = c.view(state, "bc_sim_state")[0]
    metrics = None
    if int(st["m"]["state"]) == 2:
        metrics = Metrics.from_c(st["m"], c.acc_names, imposed, _omega_integral(st, scenario, imposed, drive.motor.p))

    signals: dict[str, NDArray[np.float64]] = {}
    units: dict[str, str] = {}
    docs: dict[str, str] = {}
    for name, unit, doc in zip(c.trace_names, c.trace_units, c.trace_docs, strict=True):
        out_name = _RENAMED.get(name, name)
        if name.startswith("d") and name[1:].isdigit():
            label = slot.diag[int(name[1:])]
            if not label:
                continue
            out_name = label
            unit = slot.units[int(name[1:])] or _DIAG_UNITS.get(label, "-")
        signals[out_name] = rows[name]  # a strided view of the record array: no copy
        units[out_name] = unit
        docs[out_name] = doc
    plant_st = st["plant"]
    meta: dict[str, Any] = {
        "version": __version__,
        "drive": {"name": drive.name, "toml": drive.to_toml()},
        "control": control.describe(),
        "estimate": None if estimate is None else {"name": estimate.name, "toml": estimate.to_toml()},
        "scenario": _describe_scenario(dataclasses.replace(scenario, delay=delay)),  # the delay applied
        "samples": n,
        "controller_flags": int(st["flags_seen"]),
        "flags": _flag_stats(c, st, n, t_half),
        "bemf": _bemf_stats(st) if int(sense["on"][0]) else None,
        "stats": {"steps": int(plant_st["n_steps"]), "events": int(plant_st["n_events"]),
                  "plant_flags": int(plant_st["flags"]), "e_fault": float(plant_st["e_fault"]),
                  "hw_trip": float(plant_st["t_trip"]) if int(plant_st["tripped"]) else None},
        "final": {"t": float(plant_st["t"]), "i": [float(v) for v in plant_st["i"]],
                  "theta_e": float(plant_st["theta"]), "omega_m": float(plant_st["omega"])},
    }
    chosen = scenario.window is not None
    # the default window (the whole run) is not checked as a measurement: guards see the run as before it existed
    res = SimResult(signals, units, docs, metrics if chosen else None, meta)
    pk = st["row_peak"]
    rows_summary = _plaus.RowSummary((float(pk[0]), float(pk[1]), float(pk[2]), float(pk[3])),
                                     bool(int(st["row_nonfinite"])))
    try:
        meta["warnings"] = issued + _guards_after(drive, res, imposed, check, rows_summary, control, peak["ref"])
    except PlausibilityError as exc:  # the inputs' warnings are its cause: they lead the message
        raise _plaus.cause_first(exc, issued) from None
    res.metrics = metrics
    if coupler is not None:
        res.thermal = coupler.trace()
        meta["thermal"] = res.thermal.summary()
    return res


def _bemf_stats(st: np.void) -> dict[str, Any]:
    """Return the back-EMF sensing's counts at the end of the run.

    Comparator edges located at the inputs, and seen by the MCU per phase; ADC conversions; whether edges closer
    than the delay overflowed its queue.
    """
    se = st["sense"]
    return {"edges": int(se["n_edges"]), "seen": [int(v) for v in se["count"]], "conversions": int(se["n_adc"]),
            "overrun": bool(int(se["overrun"]))}


def _flag_stats(c: Any, st: np.void, n: int, t_half: float) -> dict[str, dict[str, dict[str, float]]]:
    """Return, per controller flag raised, how often and when: over the run and inside the metric window.

    ``{"SATURATED": {"run": {"samples": 12, "share": 0.002, "first": 0.0, "last": 5e-4}, "window": {...}}}``: the
    samples (half PWM periods) at which the controller raised it, their share of the run's (the window's) samples,
    and the first and last of them (s). A flag raised only outside the window has no "window" entry.
    """
    out: dict[str, dict[str, dict[str, float]]] = {}
    m = st["m"]
    n_win = int(m["n_samples"])
    for name, bit in sorted(c.groups["flag"].items(), key=lambda kv: kv[1]):
        j = int(bit).bit_length() - 1
        if bit != 1 << j or int(st["flag_run_n"][j]) == 0:
            continue
        entry = {"run": {"samples": int(st["flag_run_n"][j]), "share": int(st["flag_run_n"][j]) / max(n, 1),
                         "first": float(st["flag_run_t0"][j]), "last": float(st["flag_run_t1"][j])}}
        if int(m["flag_n"][j]) > 0:
            entry["window"] = {"samples": int(m["flag_n"][j]), "share": int(m["flag_n"][j]) / max(n_win, 1),
                               "first": float(m["flag_t0"][j]), "last": float(m["flag_t1"][j])}
        out[name.removeprefix("BC_FLAG_")] = entry
    return out


def check_estimate(drive: Drive, estimate: Drive | None) -> None:
    """Refuse an estimate that is not a drive, or that differs from the plant in what is hardware, not an estimate.

    Parameters
    ----------
    drive : Drive
        The plant.
    estimate : Drive or None
        The data the controller is configured from (``simulate(..., estimate=)``); None: nothing to check.

    Raises
    ------
    BldclabError
        ``estimate``: not a Drive; ``estimate.motor.p``, ``estimate.inverter.f_pwm``: other pole pairs or PWM
        frequency (the controller's sample rate) than the plant's.
    """
    if estimate is None:
        return
    if not isinstance(estimate, Drive):
        raise BldclabError("estimate", f"expected a Drive, got {type(estimate).__name__}")
    if estimate.motor.p != drive.motor.p:
        raise BldclabError("estimate.motor.p", f"must equal the plant's pole pairs {drive.motor.p}, got "
                           f"{estimate.motor.p}")
    if estimate.inverter.f_pwm != drive.inverter.f_pwm:
        raise BldclabError("estimate.inverter.f_pwm", f"must equal the plant's PWM frequency "
                           f"{drive.inverter.f_pwm:g} Hz (the controller's sample rate), got "
                           f"{estimate.inverter.f_pwm:g} Hz")


def _guards_before(drive: Drive, control: Control, cparams: np.ndarray, imposed: bool, peak: dict[str, float],
                   check: str) -> list[str]:
    """Plausibility checks on the inputs (:mod:`bldclab.sim.plausibility`); return the warnings issued."""
    if check == "off":
        return []
    findings = _plaus.check_speed(drive, peak["omega"], peak["v_src"]) if imposed else []
    findings += _plaus.check_pwm(drive, peak["omega"] if imposed else None)
    names = cparams.dtype.names or ()
    i_limit = float(np.ravel(cparams["i_max"])[0]) if "i_max" in names else None
    findings += _plaus.check_reference(drive, control, peak["ref"], i_limit)
    return _plaus.apply(findings, check, stacklevel=5)


def _guards_after(drive: Drive, res: SimResult, imposed: bool, check: str,
                  rows: _plaus.RowSummary | None = None, control: Control | None = None,
                  ref_max: float = math.nan) -> list[str]:
    """Plausibility checks on the result; return the warnings.

    ``rows``: the runner's summary of its trace rows; ``control`` and ``ref_max`` (its largest reference
    magnitude): for the conduction check.
    """
    if check == "off":
        return []
    findings = _plaus.check_result(drive, res, rows)
    if control is not None:
        findings += _plaus.check_conduction(drive, control, res, ref_max)
        findings += _plaus.check_current_rating(drive, control, res, rows)
    if not imposed:
        w = [abs(res.meta["final"]["omega_m"])]
        if "omega_m" in res.signals and len(res):
            w.append(rows.peak[3] if rows is not None and not rows.nonfinite
                     else float(np.max(np.abs(res.signals["omega_m"]))))
        findings += _plaus.check_driven_speed(drive, max(w), float(res.meta["final"]["omega_m"]))
        findings += _plaus.check_pwm(drive, max(w), time_constant=False)
        if res.metrics is not None:
            findings += _plaus.check_steady(drive, res)
    return _plaus.apply(findings, check, stacklevel=5)


def _omega_integral(st: np.void, scenario: Scenario, imposed: bool, p: int) -> float:
    """Integral of the mechanical speed over the metric window (rad): the electrical angle travelled over p."""
    m = st["m"]
    if imposed and isinstance(scenario.speed, int | float) and not isinstance(scenario.speed, bool):
        return float(scenario.speed) * float(m["t1"] - m["t0"])
    return float(m["th1"] - m["th0"]) / p


def _describe_scenario(s: Scenario) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for f in dataclasses.fields(s):
        v = getattr(s, f.name)
        if isinstance(v, Piecewise | PerUnit):
            out[f.name] = f"profile {v}"
        elif callable(v):
            out[f.name] = f"function {getattr(v, '__name__', '')}"
        elif isinstance(v, np.ndarray) or (isinstance(v, list | tuple) and len(v) > 8):
            out[f.name] = f"array of {len(v)} values"
        else:
            out[f.name] = v
    return out

"""Run the C closed loop: :func:`simulate` (drive, control, scenario) -> :class:`~bldclab.sim.results.SimResult`.

Python prepares the parameter structs and per-sample input arrays once; one call into C runs the whole simulation
(plant, sensors, controller, sample by sample) and fills the trace. Nothing in Python runs per time step.
"""

from __future__ import annotations

import ctypes
import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._core import core
from .._version import __version__
from ..control import Control
from ..errors import BldclabError
from ..model.motor import Drive
from . import plausibility as _plaus
from .results import Metrics, SimResult

__all__ = ["Fault", "Scenario", "simulate"]

Profile = float | ArrayLike | Callable[[NDArray[np.float64]], ArrayLike] | None

#: Fault kind -> (C constant ``BC_FAULT_*``, whose record holds it)
_FAULT_KINDS = {"phase_open": ("BC_FAULT_PHASE_OPEN", "plant"), "hall_stuck": ("BC_FAULT_HALL_STUCK", "plant"),
                "hall_glitch": ("BC_FAULT_HALL_GLITCH", "plant"),
                "current_offset": ("BC_FAULT_CURRENT_OFFSET", "sensors"),
                "current_loss": ("BC_FAULT_CURRENT_LOSS", "sensors")}
_MAX_FAULTS = 4


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
    function of the sample times (s, array) returning such an array.

    Parameters
    ----------
    duration : float
        Simulated time (s); rounded up to whole samples of ``1/(2 f_pwm)``.
    speed : profile, optional
        Imposed mechanical speed (rad/s): the rotor is held by a dynamometer. ``None`` (default): the rotor
        follows ``J dw/dt = tau_e - tau_L - B w - tau_c sign(w)`` with the drive's mechanics.
    ref : profile
        The controller's reference (what it means depends on the controller, e.g. a duty or a torque in N m).
    omega_ref : profile
        Speed reference (rad/s) for controllers with a speed loop.
    load_torque : profile
        Load torque ``tau_L`` (N m), rotor dynamics only.
    v_dc : profile, optional
        DC source voltage (V); default the inverter's ``V_dc``.
    theta0 : float
        Initial electrical angle (rad).
    omega0 : float, optional
        Initial speed (rad/s); default the imposed speed at t = 0, or 0.
    i0 : tuple of float
        Initial phase currents (A), projected to sum zero.
    delay : int
        Controller computation delay in samples (1: output applied from the next sample, as on a DSP; 0: ideal).
    trace_every : int
        Samples per trace row (>= 1); larger values thin long traces (means and extremes still cover every row).
    trace_sub : int
        Trace rows per sample (>= 1, with ``trace_every == 1``) to see the PWM ripple.
    trace : bool
        Keep a trace at all (False: metrics only, least memory).
    window : tuple of float, optional
        Metric window (t0, t1) in s; ``None``: no metrics.
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
    delay: int = 1
    trace_every: int = 1
    trace_sub: int = 1
    trace: bool = True
    window: tuple[float, float] | None = None
    h_max: float = 0.0
    faults: tuple[Fault, ...] = ()

    def __post_init__(self) -> None:
        _check_scalar("scenario.duration", self.duration, positive=True)
        _check_scalar("scenario.theta0", self.theta0)
        if self.omega0 is not None:
            _check_scalar("scenario.omega0", self.omega0)
        if len(self.i0) != 3:
            raise BldclabError("scenario.i0", "needs three currents (a, b, c)")
        for j, v in enumerate(self.i0):
            _check_scalar(f"scenario.i0[{j}]", v)
        if self.delay not in (0, 1):
            raise BldclabError("scenario.delay", f"must be 0 or 1 sample, got {self.delay!r}")
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


def _check_scalar(name: str, v: object, positive: bool = False) -> None:
    if isinstance(v, bool) or not isinstance(v, int | float | np.integer | np.floating):
        raise BldclabError(name, f"expected a number, got {type(v).__name__}")
    if not math.isfinite(float(v)):
        raise BldclabError(name, f"must be finite, got {v}")
    if positive and float(v) <= 0.0:
        raise BldclabError(name, f"must be > 0, got {v}")


def _profile(name: str, value: Profile, t: NDArray[np.float64]) -> tuple[NDArray[np.float64] | None, float]:
    """Return (per-sample array, None-constant) for a profile: ``(None, c)`` for a constant, ``(array, nan)``."""
    if value is None:
        return None, 0.0
    if isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool):
        _check_scalar(name, value)
        return None, float(value)
    if callable(value):
        try:
            arr = np.asarray(value(t), dtype=float)
        except Exception as exc:
            raise BldclabError(name, f"the function failed on the sample times: {exc}") from None
        if arr.ndim == 0:
            arr = np.full(t.shape, float(arr))
    else:
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise BldclabError(name, f"expected a number, an array or a function, got {type(value).__name__}"
                               ) from None
    if arr.shape != t.shape:
        raise BldclabError(name, f"needs one value per sample ({t.size}), got shape {arr.shape}")
    bad = np.nonzero(~np.isfinite(arr))[0]
    if bad.size:
        raise BldclabError(name, f"value at sample {int(bad[0])} (t = {t[bad[0]]:.6g} s) is {arr[bad[0]]}")
    return np.ascontiguousarray(arr), math.nan


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
    rec["hall_error"] = sen.hall_error
    rec["hall_delay"] = sen.hall_delay
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
    rec["v_gain"] = s.vdc_gain
    rec["v_offset"] = s.vdc_offset
    rec["v_noise"] = s.vdc_noise
    rec["v_lsb"] = s.vdc_lsb
    rec["f_tick"] = s.f_tick
    rec["seed"] = s.seed
    return rec


def samples_of(drive: Drive, duration: float) -> int:
    """Return the number of controller samples (half PWM periods) covering ``duration`` seconds."""
    n = duration * 2.0 * drive.inverter.f_pwm
    return max(1, math.ceil(n - 1e-9))


def simulate(drive: Drive, control: Control, scenario: Scenario, *, check: str = "error",
             estimate: Drive | None = None) -> SimResult:
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

    Returns
    -------
    SimResult

    Raises
    ------
    BldclabError
        For invalid scenario inputs (NaN in a profile, wrong length) or parameters the C core rejects.
    PlausibilityError
        With ``check="error"``, for a run whose result would be physically meaningless (a subclass of
        :class:`~bldclab.errors.BldclabError` naming the cause and the numbers).
    """
    if check not in _plaus.CHECK_MODES:
        raise BldclabError("check", f"must be one of {', '.join(_plaus.CHECK_MODES)}, got {check!r}")
    if not isinstance(drive, Drive):
        raise BldclabError("drive", f"expected a Drive, got {type(drive).__name__}")
    if not isinstance(control, Control):
        raise BldclabError("control", f"expected a bldclab.control controller, got {type(control).__name__}")
    _check_estimate(drive, estimate)
    c = core()
    control = control.with_delay(scenario.delay)
    keep: list[object] = []
    n = samples_of(drive, scenario.duration)
    t_half = 0.5 / drive.inverter.f_pwm
    t_samples = np.arange(n, dtype=np.float64) * t_half
    imposed = scenario.speed is not None

    plant = _plant_params(drive, imposed, scenario.h_max, keep)
    sensors = _sensor_params(drive)
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
    info = c.controllers[control.c_name]
    cp = control.c_record(drive if estimate is None else estimate, c, n)
    keep.append(cp)
    cparams = cp.record
    cstate = c.opaque(info.state)
    rc = c.controller_init(info, cparams, cstate)
    if rc != 0:
        raise BldclabError(f"control ({type(control).__name__})", "the C controller rejected its parameters")

    inputs = c.record("bc_sim_inputs")
    v_dc = drive.inverter.V_dc if scenario.v_dc is None else scenario.v_dc
    first: dict[str, float] = {}
    peak: dict[str, float] = {}
    for field, name, value in (("ref", "scenario.ref", scenario.ref),
                               ("omega_ref", "scenario.omega_ref", scenario.omega_ref),
                               ("omega", "scenario.speed", scenario.speed),
                               ("tau_load", "scenario.load_torque", scenario.load_torque),
                               ("v_src", "scenario.v_dc", v_dc)):
        arr, const = _profile(name, value, t_samples)
        if arr is None:
            inputs[f"{field}_c"] = const
            first[field] = const
            peak[field] = abs(const)
        else:
            keep.append(arr)
            inputs[field] = arr.ctypes.data
            first[field] = float(arr[0])
            peak[field] = float(np.max(np.abs(arr)))
    omega0 = scenario.omega0 if scenario.omega0 is not None else (first["omega"] if imposed else 0.0)
    v0 = first["v_src"]
    issued = _guards_before(drive, control, cparams, imposed, peak, check)

    cfg = c.record("bc_sim_config")
    cfg["plant"] = plant.ctypes.data
    cfg["sensors"] = sensors.ctypes.data
    cfg["ctrl"]["step"] = info.step_ptr
    cfg["ctrl"]["params"] = cparams.ctypes.data
    cfg["ctrl"]["state"] = cstate.ctypes.data
    cfg["delay"] = scenario.delay
    cfg["trace_every"] = scenario.trace_every
    cfg["trace_sub"] = scenario.trace_sub
    if scenario.window is not None:
        # the run ends at the last whole sample; a window ending within rounding of it closes there
        t0w, t1w = scenario.window
        cfg["metric_t0"], cfg["metric_t1"] = t0w, min(t1w, n * t_half)

    state = c.opaque("bc_sim_state")
    i0 = np.ascontiguousarray(scenario.i0, dtype=float)
    rc = c.lib.bc_sim_init(cfg.ctypes.data, state.ctypes.data, float(scenario.theta0), float(omega0),
                           i0.ctypes.data, v0)
    if rc != 0:
        raise BldclabError("drive", "the C plant rejected the parameters (a value out of its physical range)")

    if scenario.trace:
        n_rows = n // scenario.trace_every if scenario.trace_sub == 1 else n * scenario.trace_sub
    else:
        n_rows = 0
    rows = np.zeros(n_rows, dtype=c.trace_dtype)
    written = ctypes.c_int64(0)
    rc = c.lib.bc_sim_run(cfg.ctypes.data, state.ctypes.data, inputs.ctypes.data, n,
                          rows.ctypes.data if n_rows else None, n_rows, ctypes.byref(written))
    if rc != 0:
        raise RuntimeError(f"bc_sim_run failed with code {rc}")  # a bug, not bad input: inputs were validated
    rows = rows[: written.value]

    st = c.view(state, "bc_sim_state")[0]
    metrics = None
    if scenario.window is not None and int(st["m"]["state"]) == 2:
        metrics = Metrics.from_c(st["m"], c.acc_names, imposed, _omega_integral(st, rows, scenario, imposed))

    signals: dict[str, NDArray[np.float64]] = {}
    units: dict[str, str] = {}
    docs: dict[str, str] = {}
    for name, unit, doc in zip(c.trace_names, c.trace_units, c.trace_docs, strict=True):
        out_name = name
        if name.startswith("d") and name[1:].isdigit():
            label = info.diag[int(name[1:])]
            if not label:
                continue
            out_name = label
        signals[out_name] = rows[name]  # a strided view of the record array: no copy
        units[out_name] = unit
        docs[out_name] = doc
    plant_st = st["plant"]
    meta: dict[str, Any] = {
        "version": __version__,
        "drive": {"name": drive.name, "toml": drive.to_toml()},
        "control": control.describe(),
        "estimate": None if estimate is None else {"name": estimate.name, "toml": estimate.to_toml()},
        "scenario": _describe_scenario(scenario),
        "samples": n,
        "stats": {"steps": int(plant_st["n_steps"]), "events": int(plant_st["n_events"]),
                  "plant_flags": int(plant_st["flags"]), "e_fault": float(plant_st["e_fault"]),
                  "hw_trip": float(plant_st["t_trip"]) if int(plant_st["tripped"]) else None},
        "final": {"t": float(plant_st["t"]), "i": [float(v) for v in plant_st["i"]],
                  "theta_e": float(plant_st["theta"]), "omega_m": float(plant_st["omega"])},
    }
    res = SimResult(signals, units, docs, metrics, meta)
    meta["warnings"] = issued + _guards_after(drive, res, imposed, check)
    return res


def _check_estimate(drive: Drive, estimate: Drive | None) -> None:
    """Refuse an estimate that is not a drive, or that differs in what the controller cannot estimate."""
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
    return _plaus.apply(findings, check, stacklevel=4)


def _guards_after(drive: Drive, res: SimResult, imposed: bool, check: str) -> list[str]:
    """Plausibility checks on the result; return the warnings issued."""
    if check == "off":
        return []
    findings = _plaus.check_result(drive, res)
    if not imposed:
        w = [abs(res.meta["final"]["omega_m"])]
        if "omega_m" in res.signals and len(res):
            w.append(float(np.max(np.abs(res.signals["omega_m"]))))
        findings += _plaus.check_pwm(drive, max(w), time_constant=False)
        if res.metrics is not None:
            findings += _plaus.check_steady(drive, res)
    return _plaus.apply(findings, check, stacklevel=4)


def _omega_integral(st: np.void, rows: np.ndarray, scenario: Scenario, imposed: bool) -> float:
    """Integral of the speed over the metric window: from the angle travelled (exact)."""
    m = st["m"]
    dt = float(m["t1"] - m["t0"])
    if imposed and isinstance(scenario.speed, int | float) and not isinstance(scenario.speed, bool):
        return float(scenario.speed) * dt
    if rows.size:
        sel = (rows["t"] >= m["t0"]) & (rows["t"] < m["t1"])
        if np.any(sel):
            return float(np.mean(rows["omega_m"][sel])) * dt
    return float(st["plant"]["omega"]) * dt


def _describe_scenario(s: Scenario) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for f in dataclasses.fields(s):
        v = getattr(s, f.name)
        if callable(v):
            out[f.name] = f"function {getattr(v, '__name__', '')}"
        elif isinstance(v, np.ndarray) or (isinstance(v, list | tuple) and len(v) > 8):
            out[f.name] = f"array of {len(v)} values"
        else:
            out[f.name] = v
    return out

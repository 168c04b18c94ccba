"""Many independent simulations: a declarative sweep run serially, on local processes or on Dask, into a store.

A sweep is a *base* case, a *grid* (the product of named axes) and/or a list of explicit *cases*. Every setting of a
case has one flat name, the same in Python, in a sweep file and as a DataFrame column:

``drive``
    A catalog name (``"htm-48v"``), a motor-file path (relative to the sweep file), or a :class:`~bldclab.Drive`.
``motor.<field>``, ``inverter.<field>``, ``mechanics.<field>``, ``sensors.<field>``
    An override of a motor-file field, with the motor file's syntax (``"motor.L" = "80 uH"``, ``"motor.emf.k_phi"``).
``controller``, ``control.<parameter>``
    A controller registered by name (:func:`controllers`: every :class:`~bldclab.control.Control` subclass that
    :mod:`bldclab.control` exports, plus :func:`register_control`) and its keyword arguments.
``experiment`` and its settings
    ``"steady_state"`` (:class:`SteadyState`, the default) or ``"simulate"`` (:class:`Simulate`); the settings are
    the bare names of their fields. A speed is given as ``speed`` (rad/s, or a string with a unit such as
    ``"600 rpm"``), ``speed_rpm`` or ``speed_pu`` (per unit of the case's own ``Omega_0``).

A case is resolved to plain data (the drive's motor-file text after overrides, the controller's class and every
parameter, the experiment with SI numbers) whose canonical JSON, hashed with sha256, is its key in the
:class:`~bldclab.sweep.store.Store`. Workers rebuild the objects from that data, so every executor runs exactly the same
inputs and gives the same bits. See ``docs/sweeps.md``.
"""

from __future__ import annotations

import concurrent.futures
import copy
import dataclasses
import hashlib
import importlib
import itertools
import json
import math
import multiprocessing
import os
import shutil
import signal
import sqlite3
import sys
import threading
import time
import tomllib
import types
import typing
from abc import ABC, abstractmethod
from collections import OrderedDict
from collections.abc import Collection, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, ClassVar, Literal, NamedTuple, TextIO

import numpy as np

from .. import control as package
from .._files import read_toml
from .._version import __version__
from ..analysis.experiments import steady_state
from ..control import Control
from ..errors import BldclabError
from ..model import catalog
from ..model.motor import Drive
from ..model.units import to_si
from ..sim import Scenario, simulate
from ..sim.results import Metrics
from ..svg import Series, svg_plot
from .store import Store

__all__ = [
    "EXPERIMENTS",
    "Dask",
    "Executor",
    "Experiment",
    "Processes",
    "Progress",
    "ResolvedCase",
    "Serial",
    "Simulate",
    "SteadyState",
    "Sweep",
    "SweepRun",
    "case_key",
    "configure_command",
    "controllers",
    "load_results",
    "register_control",
    "run",
    "run_case",
    "run_command",
]

_PARTS = ("motor", "inverter", "mechanics", "sensors")
_TOP = ("drive", "controller", "experiment")
_SPEEDS = ("speed", "speed_rpm", "speed_pu")
_RPM = 2.0 * math.pi / 60.0
_CACHE = 256  # resolved drives and controllers kept by the parent (bounded: memory independent of the sweep size)


# ------------------------------------------------------------------------------------------------------------
# plain data


class _NotPlainError(Exception):
    """A value that is not plain data; ``path`` locates it inside the value being converted."""

    def __init__(self, path: str, problem: str) -> None:
        super().__init__(problem)
        self.path = path
        self.problem = problem


def _plain(value: Any, where: str) -> Any:
    """Return ``value`` as JSON data (dataclass -> dict of its init fields, tuple/array -> list, finite floats).

    Raises
    ------
    BldclabError
        Naming ``where`` (and the position inside ``value``) for a non-finite number or a non-data object.
    """
    try:
        return _to_plain(value)
    except _NotPlainError as exc:
        raise BldclabError(where + exc.path, exc.problem) from None


def _to_plain(value: Any) -> Any:
    t = type(value)
    if t is str or t is int or t is bool or value is None:
        return value
    if t is float or isinstance(value, float | np.floating):
        v = float(value)
        if not math.isfinite(v):
            raise _NotPlainError("", f"must be finite, got {v}")
        return v
    if isinstance(value, bool | str | np.bool_):
        return bool(value) if isinstance(value, np.bool_) else value
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, np.ndarray):
        return _to_plain(value.tolist())
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        items: Iterable[tuple[Any, Any]] = ((f.name, getattr(value, f.name))
                                            for f in dataclasses.fields(value) if f.init)
    elif isinstance(value, Mapping):
        items = value.items()
    elif isinstance(value, list | tuple):
        out = []
        for j, v in enumerate(value):
            try:
                out.append(_to_plain(v))
            except _NotPlainError as exc:
                raise _NotPlainError(f"[{j}]{exc.path}", exc.problem) from None
        return out
    else:
        raise _NotPlainError("", f"cannot be written as plain data (a {type(value).__name__})")
    table = {}
    for k, v in items:
        try:
            table[str(k)] = _to_plain(v)
        except _NotPlainError as exc:
            raise _NotPlainError(f".{k}{exc.path}", exc.problem) from None
    return table


def _canonical(data: Any) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


def case_key(inputs: Mapping[str, Any]) -> str:
    """Return the key of a case: sha256 (hex) of the canonical JSON of its full inputs.

    Parameters
    ----------
    inputs : mapping
        ``{"bldclab": version, "drive": motor-file text, "control": {"class", "params"}, "experiment": {...}}``
        (:attr:`ResolvedCase.inputs`).

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    return hashlib.sha256(_canonical(inputs).encode("utf-8")).hexdigest()


def _show(value: Any) -> Any:
    """Return a setting's value for a table column or a message (objects by name)."""
    t = type(value)
    if t is str or t is int or t is float or t is bool or value is None:
        return value
    if isinstance(value, Drive):
        return value.name or "<Drive>"
    if isinstance(value, Control):
        return type(value).__name__
    if isinstance(value, type):
        return value.__name__
    try:
        return _to_plain(value)
    except _NotPlainError:
        return repr(value)


# ------------------------------------------------------------------------------------------------------------
# controllers by name


_REGISTERED: dict[str, type[Control]] = {}


def register_control(cls: type[Control], name: str | None = None) -> None:
    """Make a :class:`~bldclab.control.Control` subclass available to sweeps by name.

    Subclasses exported by :mod:`bldclab.control` are available without registration. Workers find a class by
    its module and qualified name, so it must be importable there (defined in a module, not in ``__main__``).

    Parameters
    ----------
    cls : type
        A frozen dataclass subclass of :class:`~bldclab.control.Control`.
    name : str, optional
        The name sweeps use; default the class name.
    """
    if not (isinstance(cls, type) and issubclass(cls, Control) and dataclasses.is_dataclass(cls)):
        raise BldclabError("controller", f"{cls!r} is not a dataclass subclass of bldclab.control.Control")
    _REGISTERED[name or cls.__name__] = cls


def controllers() -> dict[str, type[Control]]:
    """Return the controllers sweeps know by name: ``{name: class}``.

    Every dataclass subclass of :class:`~bldclab.control.Control` in ``bldclab.control.__all__`` under its class
    name, and those added with :func:`register_control`.
    """
    out: dict[str, type[Control]] = {}
    for name in getattr(package, "__all__", ()):
        obj = getattr(package, name, None)
        if isinstance(obj, type) and issubclass(obj, Control) and obj is not Control and dataclasses.is_dataclass(obj):
            out[name] = obj
    out.update(_REGISTERED)
    return out


def _dataclass_in(hint: Any) -> type | None:
    """Return the dataclass a type hint names (directly or inside a union), if any."""
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return hint
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        for arg in typing.get_args(hint):
            if isinstance(arg, type) and dataclasses.is_dataclass(arg):
                return arg
    return None


def _build(cls: type, params: Mapping[str, Any], where: str) -> Any:
    """Construct a dataclass from plain keyword arguments; a table for a dataclass-typed field builds that class."""
    init = [f.name for f in dataclasses.fields(cls) if f.init]
    for name in params:
        if name not in init:
            raise BldclabError(f"{where}.{name}", f"no such parameter of {cls.__name__} "
                               f"(parameters: {', '.join(init) or 'none'})")
    try:
        hints = typing.get_type_hints(cls)
    except Exception:  # unresolvable annotations: no nested construction
        hints = {}
    kw: dict[str, Any] = {}
    for name, value in params.items():
        sub = _dataclass_in(hints.get(name))
        kw[name] = _build(sub, value, f"{where}.{name}") if sub is not None and isinstance(value, Mapping) else value
    try:
        return cls(**kw)
    except TypeError as exc:
        raise BldclabError(where, f"{cls.__name__}: {exc}") from None


# ------------------------------------------------------------------------------------------------------------
# experiments


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
        names = [f.name for f in dataclasses.fields(cls) if f.init]  # type: ignore[arg-type]
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
        for f in dataclasses.fields(cls):  # type: ignore[arg-type]
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
    """Add every metric not yet in ``row``; per-phase tuples become ``name_a``, ``name_b``, ``name_c``."""
    for f in dataclasses.fields(m):
        v = getattr(m, f.name)
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

    def run(self, drive: Drive, control: Control) -> dict[str, float | int]:  # noqa: D102
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

    def run(self, drive: Drive, control: Control) -> dict[str, float | int]:  # noqa: D102
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


# ------------------------------------------------------------------------------------------------------------
# the sweep


def _check_name(name: str, where: str, source: str | None) -> None:
    head, dot, rest = name.partition(".")
    if name in _TOP:
        return
    if name == "control":
        raise BldclabError(f"{where}.control", "name the controller with 'controller = NAME' and set its "
                           "parameters as 'control.<parameter>'", source)
    if dot:
        if head in (*_PARTS, "control") and rest and all(rest.split(".")):
            return
    elif name.isidentifier():
        return
    raise BldclabError(f"{where}.{name}", "unknown setting: use drive, controller, control.<parameter>, "
                       "motor.<field> (likewise inverter, mechanics, sensors), experiment or an experiment "
                       "setting", source)


def _flatten(data: object, where: str, source: str | None) -> dict[str, Any]:
    """Flatten nested tables to dotted names (``{"motor": {"R": 0}}`` -> ``{"motor.R": 0}``)."""
    if not isinstance(data, Mapping):
        raise BldclabError(where, f"must be a table, got {type(data).__name__}", source)
    out: dict[str, Any] = {}

    def walk(node: Mapping[Any, Any], prefix: str) -> None:
        for k, v in node.items():
            if not isinstance(k, str) or not k:
                raise BldclabError(f"{where}.{prefix}{k!r}", "setting names must be non-empty strings", source)
            name = prefix + k
            if isinstance(v, Mapping):
                walk(v, name + ".")
                continue
            if name in out:
                raise BldclabError(f"{where}.{name}", "is given twice", source)
            out[name] = v

    walk(data, "")
    return out


class ResolvedCase(NamedTuple):
    """One case resolved to plain data.

    Attributes
    ----------
    index : int
        Position in the sweep (the order of results).
    key : str
        sha256 of the canonical inputs (:func:`case_key`).
    inputs : dict
        Everything that determines the result: ``bldclab`` version, ``drive`` (motor-file text after overrides),
        ``control`` (``class`` as ``module:qualname``, every ``params``), ``experiment`` (``kind`` and SI fields).
    axes : dict
        The values of the sweep's axes for this case (table columns).
    spec : dict
        Every setting of the case as written (JSON-able).
    """

    index: int
    key: str
    inputs: dict[str, Any]
    axes: dict[str, Any]
    spec: dict[str, Any]


@dataclass(frozen=True, eq=False)
class Sweep:
    """A set of independent cases: a base, a grid of axes (their product) and/or explicit cases.

    Case ``i`` is the base updated with the ``i``-th assignment: explicit cases outermost, then the grid in
    ``itertools.product`` order (last axis fastest). Setting one of ``speed``, ``speed_rpm``, ``speed_pu`` in an
    assignment replaces whichever the base sets. Names are listed in the module docstring.

    Parameters
    ----------
    base : mapping
        Settings shared by every case (nested tables are flattened: ``{"motor": {"R": 0}}`` is ``motor.R``).
    grid : mapping of str to sequence
        Axes: name to a non-empty list of values.
    cases : sequence of mapping
        Explicit assignments; with a grid, each is combined with every grid point.
    name, description : str
        Free text.
    root : Path, optional
        Directory for relative motor-file paths (the sweep file's directory); default the working directory.
    source : str, optional
        Where the sweep came from, for error messages.

    Raises
    ------
    BldclabError
        Naming the offending setting (``base.motor.L``, ``grid.speed_pu``, ``cases[2].ref``).
    """

    base: Mapping[str, Any] = field(default_factory=dict)
    grid: Mapping[str, Sequence[Any]] = field(default_factory=dict)
    cases: Sequence[Mapping[str, Any]] = ()
    name: str = ""
    description: str = ""
    root: Path | None = None
    source: str | None = None

    def __post_init__(self) -> None:
        src = self.source
        base = {k: v for k, v in _flatten(self.base, "base", src).items() if v is not None}
        for k in base:
            _check_name(k, "base", src)
        grid = _flatten(self.grid, "grid", src)
        for k, values in grid.items():
            _check_name(k, "grid", src)
            if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray) or len(values) == 0:
                raise BldclabError(f"grid.{k}", "must be a non-empty list of values", src)
            grid[k] = tuple(values.tolist() if isinstance(values, np.ndarray) else values)
        if isinstance(self.cases, str | bytes | Mapping) or not isinstance(self.cases, Sequence):
            raise BldclabError("cases", "must be a list of tables ([[cases]] in a sweep file)", src)
        cases = []
        for j, c in enumerate(self.cases):
            flat = _flatten(c, f"cases[{j}]", src)
            for k in flat:
                _check_name(k, f"cases[{j}]", src)
                if k in grid:
                    raise BldclabError(f"cases[{j}].{k}", "is also a grid axis", src)
            cases.append(flat)
        for name in ("name", "description"):
            if not isinstance(getattr(self, name), str):
                raise BldclabError(name, "must be a string", src)
        object.__setattr__(self, "base", base)
        object.__setattr__(self, "grid", grid)
        object.__setattr__(self, "cases", tuple(cases))
        if self.root is not None:
            object.__setattr__(self, "root", Path(self.root))

    # ---------------------------------------------------------------------------------------------------------
    # files

    @classmethod
    def from_toml(cls, path: str | Path) -> Sweep:
        """Read a sweep file (format: ``docs/sweeps.md``).

        Raises
        ------
        BldclabError
            For an unreadable file, a TOML syntax error, or an unknown or malformed setting (named).
        """
        p = Path(path)
        data = read_toml(p, "sweep file")
        return cls.from_dict(data, source=str(p), root=p.parent, default_name=p.stem)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str | None = None, root: str | Path | None = None,
                  default_name: str = "") -> Sweep:
        """Build a sweep from a parsed sweep file (``name``, ``description``, ``[base]``, ``[grid]``, ``[[cases]]``)."""
        allowed = ("name", "description", "base", "grid", "cases")
        for k in data:
            if k not in allowed:
                raise BldclabError(str(k), "unknown top-level key (a sweep file has name, description, [base], "
                                   "[grid] and [[cases]]; settings go inside those tables)", source)
        if "base" not in data and "grid" not in data and "cases" not in data:
            raise BldclabError("base", "missing: a sweep needs [base], [grid] or [[cases]]", source)
        return cls(base=data.get("base", {}), grid=data.get("grid", {}), cases=data.get("cases", ()),
                   name=data.get("name", default_name), description=data.get("description", ""),
                   root=Path(root) if root is not None else None, source=source)

    # ---------------------------------------------------------------------------------------------------------
    # cases

    def __len__(self) -> int:
        """Return the number of cases."""
        return max(1, len(self.cases)) * math.prod(len(v) for v in self.grid.values())

    @property
    def axes(self) -> list[str]:
        """Names that vary between cases: the explicit cases' settings (first appearance), then the grid axes."""
        out: dict[str, None] = {}
        for c in self.cases:
            out.update(dict.fromkeys(c))
        out.update(dict.fromkeys(self.grid))
        return list(out)

    def assignments(self) -> Iterator[tuple[int | None, dict[str, Any]]]:
        """Yield ``(explicit case number or None, settings that vary)`` for every case, in case order."""
        explicit: Sequence[tuple[int | None, Mapping[str, Any]]] = (
            list(enumerate(self.cases)) if self.cases else [(None, {})])
        names = list(self.grid)
        for j, case in explicit:
            for combo in itertools.product(*self.grid.values()):
                a = dict(case)
                a.update(zip(names, combo, strict=True))
                yield j, a

    def spec(self, assignment: Mapping[str, Any]) -> dict[str, Any]:
        """Return every setting of the case with this assignment (base updated, speed settings replaced)."""
        s = dict(self.base)
        if any(k in assignment for k in _SPEEDS):
            for k in _SPEEDS:
                s.pop(k, None)
        s.update(assignment)
        return s

    def resolve(self) -> Iterator[ResolvedCase]:
        """Yield every case resolved to plain data, in case order (lazily: memory independent of the size).

        Raises
        ------
        BldclabError
            Naming the setting of the first invalid case and where it is written.
        """
        return _Resolver(self).cases()

    def validate(self) -> int:
        """Check every case (as :meth:`resolve` does, without computing keys) and return the number of cases.

        Raises
        ------
        BldclabError
            Naming the setting of the first invalid case and where it is written.
        """
        return _Resolver(self).validate()


class _Resolver:
    """Resolves a sweep's cases, with bounded caches of built drives and controllers."""

    def __init__(self, sweep: Sweep) -> None:
        self.sweep = sweep
        self._bases: dict[Any, dict[str, Any]] = {}
        self._drives: OrderedDict[Any, tuple[str, float]] = OrderedDict()
        self._controls: OrderedDict[Any, dict[str, Any]] = OrderedDict()
        self._names = catalog.names()
        self._known: dict[str, type[Control]] | None = None

    def cases(self) -> Iterator[ResolvedCase]:
        axes = self.sweep.axes
        for index, (j, assignment) in enumerate(self.sweep.assignments()):
            case = self.case(index, j, assignment, axes)
            assert case is not None
            yield case

    def validate(self) -> int:
        n = 0
        for index, (j, assignment) in enumerate(self.sweep.assignments()):
            self.case(index, j, assignment, (), full=False)
            n += 1
        return n

    def case(self, index: int, j: int | None, assignment: Mapping[str, Any], axes: Sequence[str],
             full: bool = True) -> ResolvedCase | None:
        """Resolve one case; ``full=False`` only validates it (no key, no displayed settings)."""
        sw = self.sweep
        spec = sw.spec(assignment)
        try:
            text, omega_0 = self._drive(spec)
            ctl = self._control(spec)
            kind = spec.get("experiment", "steady_state")
            if not isinstance(kind, str) or kind not in EXPERIMENTS:
                raise BldclabError("experiment", f"unknown experiment {kind!r} (one of {', '.join(EXPERIMENTS)})")
            settings = {k: v for k, v in spec.items() if "." not in k and k not in _TOP}
            exp = EXPERIMENTS[kind].from_settings(settings, omega_0)
        except BldclabError as exc:
            problem = exc.problem + (f" (in {exc.source})" if exc.source else "")
            shown = ", ".join(f"{k} = {_show(v)!r}" for k, v in assignment.items())
            if len(shown) > 160:
                shown = shown[:157] + "..."
            where = f"case {index} of {len(sw)}" + (f": {shown}" if shown else "")
            raise BldclabError(self._locate(exc.field, j), f"{problem} ({where})", sw.source) from None
        if not full:
            return None
        inputs = {"bldclab": __version__, "drive": text, "control": ctl,
                  "experiment": {"kind": kind, **_plain(exp, "experiment")}}
        return ResolvedCase(index, case_key(inputs), inputs, {a: _show(spec.get(a)) for a in axes},
                            {k: _show(v) for k, v in spec.items()})

    def _locate(self, name: str, j: int | None) -> str:
        """Return where a setting is written: ``grid.X``, ``cases[j].X``, ``base.X`` (or the bare name)."""
        sw = self.sweep
        group = [name[:k] for k in range(len(name), 0, -1) if k == len(name) or name[k] in ".["]
        for candidate in group:  # the setting itself, or the setting that holds it ("inverter.V_dc" for "...[1]")
            rest = name[len(candidate):]
            if candidate in sw.grid:
                return f"grid.{candidate}{rest}"
            if j is not None and candidate in sw.cases[j]:
                return f"cases[{j}].{candidate}{rest}"
            if candidate in sw.base:
                return f"base.{candidate}{rest}"
        return name

    # drive ---------------------------------------------------------------------------------------------------

    def _base_dict(self, src: Any) -> dict[str, Any]:
        ident = ("obj", id(src)) if isinstance(src, Drive) else ("name", str(src))
        if ident in self._bases:
            return self._bases[ident]
        if isinstance(src, Drive):
            drive = src
        elif isinstance(src, str | Path):
            name = str(src)
            if name in self._names:
                drive = catalog.load(name)
            else:
                p = Path(name)
                if not p.is_absolute() and self.sweep.root is not None:
                    p = self.sweep.root / p
                if not p.is_file():
                    raise BldclabError("drive", f"{name!r} is neither a built-in drive ({', '.join(self._names)}) "
                                       "nor a motor file")
                drive = Drive.from_toml(p)
        else:
            raise BldclabError("drive", f"expected a catalog name, a motor-file path or a Drive, got "
                               f"{type(src).__name__}")
        data = tomllib.loads(drive.to_toml())
        self._bases[ident] = data
        return data

    def _drive(self, spec: Mapping[str, Any]) -> tuple[str, float]:
        """Return the motor-file text of the case's drive after overrides, and its ``Omega_0`` (rad/s)."""
        src = spec.get("drive")
        if src is None:
            raise BldclabError("drive", f"missing: a built-in drive ({', '.join(self._names)}) or a motor-file path")
        overrides = sorted((k, v) for k, v in spec.items() if k.partition(".")[0] in _PARTS)
        ident = (("obj", id(src)) if isinstance(src, Drive) else ("name", str(src)),
                 _canonical([[k, _plain(v, k)] for k, v in overrides]))
        hit = self._drives.get(ident)
        if hit is not None:
            self._drives.move_to_end(ident)
            return hit
        data = copy.deepcopy(self._base_dict(src))
        for path, value in overrides:
            parts = path.split(".")
            node = data
            for depth, part in enumerate(parts[:-1]):
                nxt = node.setdefault(part, {})
                if not isinstance(nxt, dict):
                    raise BldclabError(path, f"{'.'.join(parts[:depth + 1])} is a value, not a table")
                node = nxt
            node[parts[-1]] = _plain(value, path)
        drive = Drive.from_dict(data)
        out = (drive.to_toml(), drive.Omega_0)
        self._drives[ident] = out
        if len(self._drives) > _CACHE:
            self._drives.popitem(last=False)
        return out

    # control -------------------------------------------------------------------------------------------------

    def _control(self, spec: Mapping[str, Any]) -> dict[str, Any]:
        """Return ``{"class": "module:qualname", "params": every init field as plain data}``."""
        c = spec.get("controller")
        params: dict[str, Any] = {}
        for k, v in spec.items():
            if k.startswith("control."):
                node = params
                parts = k.split(".")[1:]
                for part in parts[:-1]:
                    node = node.setdefault(part, {})
                node[parts[-1]] = v
        if self._known is None:
            self._known = controllers()
        known = self._known
        if c is None:
            raise BldclabError("controller", f"missing: one of {', '.join(known)}")
        start: dict[str, Any] = {}
        if isinstance(c, Control):
            cls: type = type(c)
            start = _plain(c, "control")
        elif isinstance(c, type) and issubclass(c, Control):
            cls = c
        elif isinstance(c, str):
            if c not in known:
                raise BldclabError("controller", f"unknown controller {c!r} (one of {', '.join(known)})")
            cls = known[c]
        else:
            raise BldclabError("controller", f"expected a controller name, class or instance, got {c!r}")
        if not dataclasses.is_dataclass(cls):
            raise BldclabError("controller", f"{cls.__name__} is not a dataclass: its settings cannot be plain data")
        start.update(params)
        ident = (cls, _canonical(_plain(start, "control")))
        hit = self._controls.get(ident)
        if hit is not None:
            self._controls.move_to_end(ident)
            return hit
        canon = _plain(_build(cls, start, "control"), "control")
        if _plain(_build(cls, canon, "control"), "control") != canon:
            raise BldclabError("controller", f"{cls.__name__}'s parameters change when rebuilt from plain data")
        out = {"class": f"{cls.__module__}:{cls.__qualname__}", "params": canon}
        self._controls[ident] = out
        if len(self._controls) > _CACHE:
            self._controls.popitem(last=False)
        return out


# ------------------------------------------------------------------------------------------------------------
# running one case (what the workers do)


@lru_cache(maxsize=32)
def _drive_of(text: str) -> Drive:
    return Drive.from_dict(tomllib.loads(text))


@lru_cache(maxsize=64)
def _control_of(spec: str) -> Control:
    data = json.loads(spec)
    module, _, qualname = data["class"].partition(":")
    obj: Any = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return _build(obj, data["params"], "control")  # type: ignore[no-any-return]


def run_case(inputs: Mapping[str, Any]) -> dict[str, float | int]:
    """Run one case from its canonical inputs (:attr:`ResolvedCase.inputs`) and return its result row.

    This is what every executor calls, in a worker or in this process.

    Raises
    ------
    RuntimeError
        If the inputs were resolved by another bldclab version (a cluster with mixed installations).
    """
    if inputs.get("bldclab") != __version__:
        raise RuntimeError(f"case resolved by bldclab {inputs.get('bldclab')}, this worker runs {__version__}")
    drive = _drive_of(inputs["drive"])
    control = _control_of(_canonical(inputs["control"]))
    settings = dict(inputs["experiment"])
    experiment = EXPERIMENTS[settings.pop("kind")](**settings)
    return experiment.run(drive, control)


class _Outcome(NamedTuple):
    index: int
    key: str
    row: dict[str, float | int] | None
    error: str | None
    elapsed: float


def _run_chunk(chunk: Sequence[tuple[int, str, dict[str, Any]]]) -> list[_Outcome]:
    """Run cases ``(index, key, inputs)``; an exception becomes the case's error (the others still run)."""
    out = []
    for index, key, inputs in chunk:
        t0 = time.perf_counter()
        try:
            row, error = run_case(inputs), None
        except Exception as exc:
            row, error = None, f"{type(exc).__name__}: {exc}"
        out.append(_Outcome(index, key, row, error, time.perf_counter() - t0))
    return out


def _worker_init() -> None:
    """Worker process setup: Ctrl-C is the parent's business; exit when orphaned (parent killed with -9)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    parent = os.getppid()

    def watch() -> None:
        while True:
            time.sleep(0.5)
            if os.getppid() != parent:
                os._exit(1)

    threading.Thread(target=watch, name="bldclab-orphan-watch", daemon=True).start()


# ------------------------------------------------------------------------------------------------------------
# executors


class _ChunkLostError(Exception):
    """A chunk's cases could not be run (worker lost); they are recorded as failed and retried on a rerun."""


class _Backend(ABC):
    """An open executor: submit chunks, wait for some, fetch their outcomes."""

    slots = 1

    @abstractmethod
    def submit(self, chunk: list[tuple[int, str, dict[str, Any]]]) -> Any:
        """Start a chunk of cases; return a handle."""

    @abstractmethod
    def wait(self, handles: Collection[Any]) -> Iterable[Any]:
        """Block until some of the handles are done; return those."""

    @abstractmethod
    def result(self, handle: Any) -> list[_Outcome]:
        """Return the outcomes of a finished chunk."""

    def close(self, abort: bool) -> None:  # noqa: B027 - a backend without workers has nothing to release
        """Release the workers; ``abort``: stop running work as soon as possible."""


class Executor(ABC):
    """Where the cases run: :class:`Serial`, :class:`Processes` or :class:`Dask`."""

    @abstractmethod
    def _open(self) -> _Backend:
        """Start the workers and return the open backend."""

    def describe(self) -> str:
        """Return a short description for messages."""
        return type(self).__name__.lower()


class _Done:
    """A chunk already run (the serial executor's handle)."""

    def __init__(self, outcomes: list[_Outcome]) -> None:
        self.outcomes = outcomes


class _SerialBackend(_Backend):
    def submit(self, chunk: list[tuple[int, str, dict[str, Any]]]) -> Any:
        return _Done(_run_chunk(chunk))

    def wait(self, handles: Collection[Any]) -> Iterable[Any]:
        return list(handles)

    def result(self, handle: Any) -> list[_Outcome]:
        return handle.outcomes  # type: ignore[no-any-return]


@dataclass(frozen=True)
class Serial(Executor):
    """Run the cases one after the other in this process."""

    def _open(self) -> _Backend:
        return _SerialBackend()


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class _PoolBackend(_Backend):
    def __init__(self, workers: int, context: str) -> None:
        self.slots = workers
        self.pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=workers, mp_context=multiprocessing.get_context(context), initializer=_worker_init)

    def submit(self, chunk: list[tuple[int, str, dict[str, Any]]]) -> Any:
        return self.pool.submit(_run_chunk, chunk)

    def wait(self, handles: Collection[Any]) -> Iterable[Any]:
        return concurrent.futures.wait(handles, return_when=concurrent.futures.FIRST_COMPLETED).done

    def result(self, handle: Any) -> list[_Outcome]:
        return handle.result()  # type: ignore[no-any-return]  # BrokenProcessPool: fatal, propagates

    def close(self, abort: bool) -> None:
        if not abort:
            self.pool.shutdown(wait=True)
            return
        self.pool.shutdown(wait=False, cancel_futures=True)
        # Stop the cases still running instead of waiting for them: Python >= 3.14 has a public method for it;
        # before, the pool's process table is the only handle on its workers.
        terminate = getattr(self.pool, "terminate_workers", None)
        if terminate is not None:
            terminate()
            return
        procs = list((getattr(self.pool, "_processes", None) or {}).values())
        for p in procs:
            p.terminate()
        for p in procs:
            p.join(timeout=5.0)


@dataclass(frozen=True)
class Processes(Executor):
    """Run the cases on local worker processes (each loads the C library once).

    Parameters
    ----------
    workers : int, optional
        Number of processes; default one per core available to this process.
    context : {"spawn", "forkserver"}
        How workers start (never ``fork``: the parent may hold threads and an open database).
    """

    workers: int | None = None
    context: Literal["spawn", "forkserver"] = "spawn"

    def __post_init__(self) -> None:
        if self.workers is not None and (isinstance(self.workers, bool) or not isinstance(self.workers, int)
                                         or self.workers < 1):
            raise BldclabError("workers", f"must be an integer >= 1, got {self.workers!r}")
        if self.context not in ("spawn", "forkserver"):
            raise BldclabError("context", f"must be 'spawn' or 'forkserver', got {self.context!r}")

    @property
    def n(self) -> int:
        """The number of worker processes."""
        return self.workers if self.workers is not None else _cores()

    def _open(self) -> _Backend:
        return _PoolBackend(self.n, self.context)

    def describe(self) -> str:  # noqa: D102
        return f"{self.n} processes"


class _DaskBackend(_Backend):
    def __init__(self, address: str, timeout: float) -> None:
        try:
            import distributed
        except ImportError:
            raise BldclabError("scheduler", "needs dask.distributed: pip install 'bldclab[dask]'") from None
        self._distributed = distributed
        try:
            self.client = distributed.Client(address, timeout=timeout, set_as_default=False)
        except Exception as exc:  # OSError, TimeoutError, ValueError for a malformed address
            raise BldclabError("scheduler", f"cannot connect to {address!r}: {exc}") from None
        self.slots = max(1, sum(self.client.nthreads().values()))
        self._pending: set[Any] = set()
        # this client's own event loop: no process-wide default client is set or needed
        self._completed = distributed.as_completed(loop=self.client.loop)

    def submit(self, chunk: list[tuple[int, str, dict[str, Any]]]) -> Any:
        fut = self.client.submit(_run_chunk, chunk, pure=False)
        self._pending.add(fut)
        self._completed.add(fut)
        return fut

    def wait(self, handles: Collection[Any]) -> Iterable[Any]:
        return self._completed.next_batch(block=True)  # type: ignore[no-any-return]

    def result(self, handle: Any) -> list[_Outcome]:
        self._pending.discard(handle)
        try:
            return handle.result()  # type: ignore[no-any-return]
        except Exception as exc:  # KilledWorker, CancelledError: the scheduler gave up on the chunk
            raise _ChunkLostError(f"{type(exc).__name__}: {exc}") from None

    def close(self, abort: bool) -> None:
        try:
            if abort and self._pending:
                self.client.cancel(list(self._pending))
        finally:
            self.client.close()


@dataclass(frozen=True)
class Dask(Executor):
    """Run the cases on a Dask cluster (``dask.distributed``), given its scheduler's address.

    Workers need the same bldclab version installed (a case carries its version and a worker refuses another).

    Parameters
    ----------
    address : str
        Scheduler address, ``tcp://HOST:PORT``.
    timeout : float
        Connection timeout (s).
    """

    address: str
    timeout: float = 10.0

    def __post_init__(self) -> None:
        if not isinstance(self.address, str) or not self.address:
            raise BldclabError("scheduler", f"expected an address like tcp://HOST:PORT, got {self.address!r}")

    def _open(self) -> _Backend:
        return _DaskBackend(self.address, self.timeout)

    def describe(self) -> str:  # noqa: D102
        return f"dask {self.address}"


# ------------------------------------------------------------------------------------------------------------
# progress


def _clock(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "--:--"
    s = round(seconds)
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m:02d}:{s:02d}"


class Progress:
    """A one-line progress bar with rate and ETA on a terminal stream.

    Parameters
    ----------
    total : int
        Number of cases.
    done : int
        Cases already finished (in the store) at the start; they do not count for the rate.
    stream : text stream, optional
        Default ``sys.stderr``.
    enabled : bool, optional
        Default: only if ``stream`` is a terminal.
    label : str
        Text before the bar.
    """

    def __init__(self, total: int, done: int = 0, *, stream: TextIO | None = None, enabled: bool | None = None,
                 label: str = "sweep") -> None:
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.total = total
        self.done = done
        self.start_done = done
        self.failed = 0
        self.label = label
        self.t0 = time.perf_counter()
        self._last = -math.inf
        self._width = 0
        self._render(force=True)

    def advance(self, n: int = 1, *, failed: bool = False, computed: bool = True) -> None:
        """Count ``n`` finished cases (``computed=False``: found in the store, not run)."""
        self.done += n
        if not computed:
            self.start_done += n
        if failed:
            self.failed += n
        self._render()

    def line(self) -> str:
        """Return the current text of the bar."""
        elapsed = time.perf_counter() - self.t0
        run = self.done - self.start_done
        rate = run / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else math.inf
        frac = self.done / self.total if self.total else 1.0
        cols = shutil.get_terminal_size((100, 20)).columns
        fail = f" {self.failed} failed" if self.failed else ""
        tail = f" {self.done}/{self.total}{fail} {rate:.1f}/s {_clock(elapsed)} ETA {_clock(eta)}"
        width = max(10, min(40, cols - len(self.label) - len(tail) - 9))
        fill = int(frac * width)
        return f"{self.label} {100 * frac:3.0f}% |{'#' * fill}{'.' * (width - fill)}|{tail}"

    def _render(self, force: bool = False) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self._last < 0.1 and self.done < self.total:
            return
        self._last = now
        text = self.line()
        self.stream.write("\r" + text + " " * max(0, self._width - len(text)))
        self.stream.flush()
        self._width = len(text)

    def close(self) -> None:
        """Draw the final state and end the line."""
        if self.enabled:
            self._render(force=True)
            self.stream.write("\n")
            self.stream.flush()


# ------------------------------------------------------------------------------------------------------------
# running a sweep


@dataclass
class SweepRun:
    """What :func:`run` did; the results are in :attr:`store` (:meth:`to_pandas`).

    Attributes
    ----------
    sweep : Sweep
    store : Store
    total : int
        Cases in the sweep.
    computed : int
        Cases run and stored by this call.
    skipped : int
        Cases found in the store (finished earlier).
    failed : int
        Cases whose run raised an error (recorded in the store's failures; retried by the next run).
    errors : list of (int, str)
        Case index and message of the first failures (at most 20).
    wall : float
        Wall time (s).
    executor : str
        Where the cases ran.
    """

    sweep: Sweep
    store: Store
    total: int = 0
    computed: int = 0
    skipped: int = 0
    failed: int = 0
    errors: list[tuple[int, str]] = field(default_factory=list)
    wall: float = 0.0
    executor: str = ""

    def to_pandas(self) -> Any:
        """Return the sweep's results (:func:`load_results`)."""
        return load_results(self.sweep, self.store)

    def summary(self) -> str:
        """Return one line describing the run."""
        name = f" {self.sweep.name}" if self.sweep.name else ""
        return (f"sweep{name}: {self.total} cases: {self.computed} computed, {self.skipped} already in the store, "
                f"{self.failed} failed; {self.wall:.1f} s on {self.executor}; store {self.store.path}")

    def _repr_html_(self) -> str:
        """Jupyter: the summary, the results as a table (first rows) and a small plot.

        The plot shows the first numeric result that varies (speeds echoing the case's inputs skipped) against the
        first axis, one line per value of the second axis (up to eight); a non-numeric first axis is plotted at
        positions 0, 1, ... named in the axis label.
        """
        import html


        parts = [f"<p><b>{html.escape(self.summary())}</b></p>"]
        try:
            df = self.to_pandas()
        except (BldclabError, sqlite3.Error) as exc:
            return parts[0] + f"<p>(results not readable: {html.escape(' '.join(str(exc).split()))})</p>"
        if len(df) == 0:
            return parts[0] + "<p>(no results stored yet)</p>"
        axes = [a for a in self.sweep.axes if a in df.columns]
        plot = _sweep_plot(df, axes)
        if plot is not None:
            series, xlabel, ylabel = plot
            svg = svg_plot(series, title=f"{ylabel} vs {xlabel}", xlabel=xlabel, ylabel=ylabel, width=560,
                           height=320)
            parts.append(f'<div style="max-width: 560px">{svg}</div>')
        shown = df.drop(columns=["key"], errors="ignore")
        parts.append(shown.head(20).to_html(index=False, float_format=lambda v: f"{v:.6g}"))
        if len(df) > 20:
            parts.append(f"<p>(first 20 of {len(df)} rows; <code>.to_pandas()</code> for all)</p>")
        return "".join(parts)


def _sweep_plot(df: Any, axes: Sequence[str]) -> tuple[list[Any], str, str] | None:
    """Return the series and labels of a sweep's notebook plot: first varying numeric result vs the first axis."""
    import pandas as pd


    echo = {*axes, *_SPEEDS}
    skip = {"case", "key", *echo, *(f"{n}_result" for n in echo)}
    results = [c for c in df.columns if c not in skip and pd.api.types.is_numeric_dtype(df[c])
               and not pd.api.types.is_bool_dtype(df[c]) and df[c].nunique(dropna=True) > 1]
    if not results:
        return None
    y_name = results[0]
    if axes:
        x_raw = df[axes[0]]
        if pd.api.types.is_numeric_dtype(x_raw) and not pd.api.types.is_bool_dtype(x_raw):
            x, xlabel = x_raw.to_numpy(dtype=float), axes[0]
        else:
            labels = list(dict.fromkeys(str(v) for v in x_raw))
            x = np.array([labels.index(str(v)) for v in x_raw], dtype=float)
            names = ", ".join(f"{j}: {v}" for j, v in enumerate(labels[:6]))
            xlabel = f"{axes[0]} ({names}{', ...' if len(labels) > 6 else ''})"
    else:
        x, xlabel = df["case"].to_numpy(dtype=float), "case"
    y = df[y_name].to_numpy(dtype=float)
    colors = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f")
    groups = list(dict.fromkeys(str(v) for v in df[axes[1]])) if len(axes) > 1 else []
    if len(axes) > 1 and len(groups) <= len(colors):
        key = df[axes[1]].astype(str).to_numpy()
        series = []
        for g, color in zip(groups, colors, strict=False):
            sel = key == g
            order = np.argsort(x[sel], kind="stable")
            series.append(Series(f"{axes[1]} = {g}", x[sel][order], y[sel][order], color, marker="o"))
        return series, xlabel, y_name
    order = np.argsort(x, kind="stable")
    line = len(axes) == 1
    return [Series(y_name, x[order], y[order], colors[0], line=line, marker="o")], xlabel, y_name


class _Chunker:
    """Chunk sizes aiming at ~0.1 s of work per chunk (IPC amortised), small enough to balance the tail."""

    target = 0.1

    def __init__(self, slots: int, remaining: int, adaptive: bool) -> None:
        self.slots = slots
        self.remaining = remaining
        self.adaptive = adaptive
        self.n = 0
        self.seconds = 0.0

    def record(self, elapsed: float) -> None:
        self.n += 1
        self.seconds += elapsed

    def size(self) -> int:
        if not self.adaptive or self.n == 0:
            return 1
        size = int(self.target / max(self.seconds / self.n, 1e-6))
        size = min(size, 256, self.remaining // (4 * self.slots))
        return max(1, size)


def run(sweep: Sweep | str | Path, store: Store | str | Path | None = None, *, executor: Executor | None = None,
        progress: bool | None = None, stream: TextIO | None = None) -> SweepRun:
    """Run every case of a sweep that the store does not hold yet, storing each result as it arrives.

    The parent process resolves every case first (an invalid case fails before anything runs or any store file is
    created), then resolves them again one by one, skips those in the store, sends the others to the executor (its
    workers start with the first such case) in small chunks with a bounded number in flight, and writes each
    finished case in its own transaction. Its memory does not grow with the number of cases. Interrupted (Ctrl-C,
    ``kill -9``) and rerun, it computes exactly the cases that were not stored.

    Parameters
    ----------
    sweep : Sweep or path
        The sweep, or a sweep file.
    store : Store or path, optional
        Results store: a :class:`~bldclab.sweep.store.Store`, or the path of an SQLite file (created if missing; opened
        after the cases are validated and left open in :attr:`SweepRun.store`); default an in-memory store.
    executor : Executor, optional
        :class:`Serial`, :class:`Processes` (default: one process per core) or :class:`Dask`.
    progress : bool, optional
        Progress bar on ``stream``; default only if it is a terminal.
    stream : text stream, optional
        For the progress bar; default ``sys.stderr``.

    Returns
    -------
    SweepRun
        Counts and the store; ``.to_pandas()`` for the results.

    Raises
    ------
    BldclabError
        For an invalid case (naming its setting) or an unusable store or scheduler; nothing has run then.
    """
    sw = sweep if isinstance(sweep, Sweep) else Sweep.from_toml(sweep)
    ex = executor if executor is not None else Processes()
    if not isinstance(ex, Executor):
        raise BldclabError("executor", f"expected Serial(), Processes() or Dask(address), got {ex!r}")
    t_start = time.perf_counter()
    total = sw.validate()  # every case checked before anything runs (and before a store file is created)
    st = store if isinstance(store, Store) else Store(":memory:" if store is None else store)
    result = SweepRun(sw, st, total=total, executor=ex.describe())
    bar = Progress(total, stream=stream, enabled=progress)
    try:
        _dispatch(sw, st, ex, bar, result)
    finally:
        bar.close()
        result.wall = time.perf_counter() - t_start
    return result


def _dispatch(sw: Sweep, st: Store, ex: Executor, bar: Progress, result: SweepRun) -> None:
    """Send the cases missing from the store to the executor (opened at the first one) and store the outcomes."""
    backend: _Backend | None = None
    inflight: dict[Any, list[ResolvedCase]] = {}
    inflight_keys: set[str] = set()
    chunker = _Chunker(1, result.total, adaptive=not isinstance(ex, Serial))
    todo = sw.resolve()
    exhausted = False
    aborted = True
    try:
        while True:
            while not exhausted and (backend is None or len(inflight) < 2 * backend.slots):
                chunk: list[ResolvedCase] = []
                want = chunker.size()
                for case in todo:
                    if case.key in inflight_keys or case.key in st:  # finished earlier, or a duplicate case
                        result.skipped += 1
                        chunker.remaining -= 1
                        bar.advance(computed=False)
                        continue
                    chunk.append(case)
                    if len(chunk) == want:
                        break
                else:
                    exhausted = True
                if not chunk:
                    break
                if backend is None:  # no pool to start when everything is stored already
                    backend = ex._open()
                    chunker.slots = backend.slots
                chunker.remaining -= len(chunk)
                inflight_keys.update(c.key for c in chunk)
                inflight[backend.submit([(c.index, c.key, c.inputs) for c in chunk])] = chunk
            if backend is None or not inflight:
                break
            for handle in backend.wait(list(inflight)):
                chunk = inflight.pop(handle)
                try:
                    outcomes = backend.result(handle)
                except _ChunkLostError as exc:
                    outcomes = [_Outcome(c.index, c.key, None, str(exc), 0.0) for c in chunk]
                cases = {c.index: c for c in chunk}
                for out in outcomes:
                    case = cases[out.index]
                    inflight_keys.discard(case.key)
                    if out.row is not None:
                        st.add(case.key, case.inputs, case.spec, out.row, out.elapsed)
                        chunker.record(out.elapsed)
                        result.computed += 1
                    else:
                        st.add_failure(case.key, case.spec, out.error or "unknown error")
                        result.failed += 1
                        if len(result.errors) < 20:
                            result.errors.append((case.index, out.error or "unknown error"))
                    bar.advance(failed=out.row is None)
        aborted = False
    finally:
        if backend is not None:
            backend.close(abort=aborted)


def load_results(sweep: Sweep | str | Path, store: Store | str | Path) -> Any:
    """Return a sweep's stored results as a DataFrame, one row per finished case, in case order.

    Columns: ``case`` (index), the sweep's axes (:attr:`Sweep.axes`, values as written), the experiment's result
    values (a result named like an axis gets the suffix ``_result``), ``key``. Cases not stored (not run yet, or
    failed) have no row.

    Parameters
    ----------
    sweep : Sweep or path
    store : Store or path

    Returns
    -------
    pandas.DataFrame
    """
    import pandas as pd

    sw = sweep if isinstance(sweep, Sweep) else Sweep.from_toml(sweep)
    if not isinstance(store, Store):
        with Store(store, create=False) as opened:
            return load_results(sw, opened)
    st = store
    rows: list[dict[str, Any]] = []
    batch: list[ResolvedCase] = []

    def flush() -> None:
        found = st.results(c.key for c in batch)
        for c in batch:
            values = found.get(c.key)
            if values is None:
                continue
            row: dict[str, Any] = {"case": c.index, **c.axes}
            for name, v in values.items():
                row[name if name not in row and name != "key" else f"{name}_result"] = v
            row["key"] = c.key
            rows.append(row)
        batch.clear()

    for case in sw.resolve():
        batch.append(case)
        if len(batch) == 500:
            flush()
    flush()
    if not rows:
        return pd.DataFrame(columns=["case", *sw.axes, "key"])
    return pd.DataFrame(rows)


# ------------------------------------------------------------------------------------------------------------
# command line (registered in bldclab.cli)



"""Many independent simulations: a declarative sweep run serially, on local processes or on Dask, into a store.

A sweep is a *base* case, a *grid* (the product of named axes) and/or a list of explicit *cases*. Every setting of a
case has one flat name, the same in Python, in a sweep file and as a DataFrame column:

``drive``
    A catalog name (``"htm-48v"``), a motor-file path (relative to the sweep file), or a :class:`~bldclab.Drive`.
``motor.<field>``, ``inverter.<field>``, ``mechanics.<field>``, ``sensors.<field>``
    An override of a motor-file field, with the motor file's syntax (``"motor.L" = "80 uH"``, ``"motor.emf.k_phi"``).
``controller``, ``control.<parameter>``
    A controller registered by name (:func:`~bldclab.sweep.registry.controllers`: every
    :class:`~bldclab.control.Control` subclass that
    :mod:`bldclab.control` exports, plus :func:`~bldclab.sweep.registry.register_control`) and its keyword arguments.
``experiment`` and its settings
    ``"steady_state"`` (:class:`~bldclab.analysis.experiments.SteadyState`, the default) or ``"simulate"``
    (:class:`~bldclab.analysis.experiments.Simulate`); the settings are
    the bare names of their fields. A speed is given as ``speed`` (rad/s, or a string with a unit such as
    ``"600 rpm"``), ``speed_rpm`` or ``speed_pu`` (per unit of the case's own ``Omega_0``).

A case is resolved to plain data (the drive's motor-file text after overrides, the controller's class and every
parameter, the experiment with SI numbers) whose canonical JSON, hashed with sha256, is its key in the
:class:`~bldclab.sweep.store.Store`. Workers rebuild the objects from that data, so every executor runs exactly the same
inputs and gives the same bits. See ``docs/sweeps.md``.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
import math
import sqlite3
import time
import tomllib
from collections import OrderedDict
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple, TextIO

import numpy as np

from .._files import read_toml
from .._version import __version__
from ..analysis.experiments import _SPEEDS, EXPERIMENTS, Experiment, Simulate, SteadyState
from ..control import Control
from ..errors import BldclabError
from ..model import catalog
from ..model.motor import Drive
from ..svg import Series, svg_plot
from .executors import Dask, Executor, Processes, Serial, _Backend, _ChunkLostError, _Outcome, run_case
from .keys import _canonical, _plain, _show, case_key
from .progress import Progress
from .progress import _clock as _clock  # re-exported: the tests format times through bldclab.sweep
from .registry import _build, controllers, register_control
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
    "controllers",
    "load_results",
    "register_control",
    "run",
    "run_case",
]

_PARTS = ("motor", "inverter", "mechanics", "sensors")
_TOP = ("drive", "controller", "experiment")
_CACHE = 256  # resolved drives and controllers kept by the parent (bounded: memory independent of the sweep size)


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
        sha256 of the canonical inputs (:func:`~bldclab.sweep.keys.case_key`).
    inputs : dict
        Everything that determines the result: ``bldclab`` version, ``drive`` (motor-file text after overrides),
        ``control`` (``class`` as ``module:qualname``, every ``params``), ``experiment`` (``kind`` and SI fields).
    axes : dict
        The values of the sweep's axes for this case (table columns).
    spec : dict
        Every setting of the case as written (JSON-able).
    """

    index: int  # type: ignore[assignment]  # the case number; a NamedTuple field may shadow tuple.index
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
        :class:`~bldclab.sweep.executors.Serial`, :class:`~bldclab.sweep.executors.Processes` (default: one process
        per core) or :class:`~bldclab.sweep.executors.Dask`.
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



"""Motor-file machinery: the TOML tables of a motor file read with field names in every error, and written back.

:meth:`Drive.from_toml <bldclab.model.motor.Drive.from_toml>` and :meth:`~bldclab.model.motor.Drive.to_toml` use it
(the format: ``docs/motor-files.md``): :class:`Section` reads one table (typed accessors that name the field and
reject unknown keys), :func:`read_emf` and :func:`read_cogging` the back-EMF and cogging tables, :func:`toml_table`
writes a table, :func:`emf_tables` and :func:`cogging_table` the back-EMF and cogging ones. The drive's own tables
(motor, inverter, mechanics, sensors) are read and written in :mod:`bldclab.model.motor`, beside their dataclasses.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import BldclabError
from ._checks import check_array
from .emf import PHASES, SHAPES, TWO_PI, BackEmf, Cogging, Fourier, Shape, Sinusoid, Table, Trapezoid
from .units import to_si

__all__ = ["Section", "cogging_table", "emf_tables", "read_cogging", "read_emf", "read_form", "toml_table",
           "toml_value", "wrap"]


class Section:
    """A TOML table being read: typed accessors that name the field and reject unknown keys."""

    def __init__(self, data: object, prefix: str) -> None:
        if not isinstance(data, Mapping):
            raise BldclabError(prefix or "file", f"must be a table, got {type(data).__name__}")
        self.data = data
        self.prefix = prefix
        self.used: set[str] = set()

    def name(self, key: str) -> str:
        """Return the dotted field name of ``key`` in the file (``motor.emf.k_phi``), for error messages."""
        return f"{self.prefix}.{key}" if self.prefix else key

    def has(self, key: str) -> bool:
        """Return whether the table has ``key``."""
        return key in self.data

    def raw(self, key: str, default: object = ...) -> object:
        """Return the value of ``key`` as parsed (``default`` if absent; without a default, absent is an error)."""
        self.used.add(key)
        if key not in self.data:
            if default is ...:
                raise BldclabError(self.name(key), "is missing")
            return default
        return self.data[key]

    def quantity(self, key: str, dim: str, default: object = ...) -> Any:
        """Return ``key`` as a quantity of dimension ``dim`` in SI units (a number or a string with its unit)."""
        v = self.raw(key, default)
        if v is None or (v is default and default is not ...):
            return v
        return to_si(v, dim, self.name(key))

    def integer(self, key: str, default: object = ...) -> Any:
        """Return ``key`` as an integer."""
        v = self.raw(key, default)
        if v is default and default is not ...:
            return v
        if isinstance(v, bool) or not isinstance(v, int):
            raise BldclabError(self.name(key), f"expected an integer, got {v!r}")
        return v

    def string(self, key: str, default: object = ...) -> Any:
        """Return ``key`` as a string."""
        v = self.raw(key, default)
        if v is default and default is not ...:
            return v
        if not isinstance(v, str):
            raise BldclabError(self.name(key), f"expected a string, got {v!r}")
        return v

    def boolean(self, key: str, default: object = ...) -> Any:
        """Return ``key`` as a boolean (``true`` or ``false``)."""
        v = self.raw(key, default)
        if v is default and default is not ...:
            return v
        if not isinstance(v, bool):
            raise BldclabError(self.name(key), f"expected true or false, got {v!r}")
        return v

    def numbers(self, key: str, scale: float = 1.0) -> list[float]:
        """Return ``key`` as a list of finite numbers, each times ``scale``."""
        v = self.raw(key)
        arr = check_array(self.name(key), v)
        return [float(x) * scale for x in arr]

    def sub(self, key: str) -> Section | None:
        """Return the sub-table ``key`` (None if absent)."""
        if key not in self.data:
            self.used.add(key)
            return None
        return Section(self.raw(key), self.name(key))

    def finish(self) -> None:
        """Reject the keys no accessor has asked for (misspelt fields)."""
        extra = sorted(set(self.data) - self.used)
        if extra:
            raise BldclabError(self.name(extra[0]), "unknown field (misspelt?)")


def wrap(prefix: str, fn: Any, *args: Any, **kw: Any) -> Any:
    """Call a dataclass constructor, prefixing the field name of its validation error."""
    try:
        return fn(*args, **kw)
    except BldclabError as exc:
        raise BldclabError(f"{prefix}.{exc.field}", exc.problem) from None
    except TypeError as exc:
        raise BldclabError(prefix, str(exc)) from None


def _unit_scale(sec: Section, key: str, default: str, dim: str) -> float:
    """Read a unit-name field (``unit``, ``theta_unit``) and return its factor to SI."""
    unit = sec.string(key, default)
    return to_si(f"1 {unit}", dim, sec.name(key))


def _check_theta_as_written(sec: Section, theta: tuple[float, ...], scale: float) -> None:
    """Check a table's angles for range and order in the file's own ``theta_unit`` (``Table`` speaks radians).

    A file in degrees with an angle of 480 was told ``got [0, 8.37758] (write degrees with theta_unit = "deg")``,
    which it did; the error names the values as written and the range in that unit.
    """
    unit = sec.string("theta_unit", "rad")
    th = [t / scale for t in theta]
    if len(th) < 3:
        return  # Table names the length
    period = TWO_PI / scale
    if min(th) < 0.0 or max(th) >= period:
        hint = (f"{period:g} {unit} is 0 again (the table is periodic): drop the last point" if min(th) >= 0.0
                and th[-1] == period and max(th[:-1]) < period else "give one electrical period")
        raise BldclabError(sec.name("theta"), f"angles must lie in [0, {period:g}) {unit}, one electrical period "
                           f"(theta_e = p theta_m), got [{min(th):g}, {max(th):g}] {unit}: {hint}")
    for j in range(1, len(th)):
        if not th[j] > th[j - 1]:
            raise BldclabError(sec.name("theta"), f"angles must be strictly increasing: entry {j} ({th[j]:g} "
                               f"{unit}) follows {th[j - 1]:g} {unit}")


def _magnitude(sec: Section, key: str, sizeless: str | None) -> float:
    """Read the size of an analytic shape (``k_phi``, ``k_1``); 1 when a speed constant gives it (``sizeless``)."""
    if sizeless is not None:
        if sec.has(key):
            raise BldclabError(sec.name(key), f"cannot be given with {sizeless}: the back-EMF's size is given once "
                               f"(a speed constant in [motor], or {key} here)")
        return 1.0
    try:
        value: float = sec.quantity(key, "emf_constant")
    except BldclabError:
        raw = sec.data.get(key)
        if not _is_speed_constant(raw):
            raise
        raise BldclabError(sec.name(key), f"{raw!r} is a speed constant (KV), not V s/rad: write KV = \"{raw}\" in "
                           f"[motor] and leave {key} out (docs/motor-files.md, \"Catalogue ratings\")") from None
    return value


def _is_speed_constant(raw: object) -> bool:
    """Whether ``raw`` is a string with a speed-constant unit (``"1950 rpm/V"``)."""
    if not isinstance(raw, str):
        return False
    try:
        to_si(raw, "speed_constant", "")
    except BldclabError:
        return False
    return True


def _shape_from(sec: Section, phase: int | None, sizeless: str | None = None) -> Shape:
    """Read one shape; ``phase`` (0, 1, 2) reads the per-phase table column ``k_a``/``k_b``/``k_c``.

    ``sizeless`` (the field that gives the size instead, e.g. ``motor.KV``): a trapezoid or sinusoid of size 1,
    without its ``k_phi`` or ``k_1``.
    """
    kind = sec.string("kind")
    if kind not in SHAPES:
        raise BldclabError(sec.name("kind"), f"unknown shape {kind!r} (use one of {', '.join(SHAPES)})")
    if sizeless is not None and kind not in ("trapezoid", "sinusoid"):
        raise BldclabError(sec.name("kind"), f"must be trapezoid or sinusoid with {sizeless}: a {kind}'s values "
                           f"give its size in V s/rad (drop {sizeless})")
    if kind == "trapezoid":
        shape: Shape = wrap(sec.prefix, Trapezoid, _magnitude(sec, "k_phi", sizeless),
                             sec.quantity("flat_top", "angle", TWO_PI / 3.0))
    elif kind == "sinusoid":
        shape = wrap(sec.prefix, Sinusoid, _magnitude(sec, "k_1", sizeless))
    elif kind == "fourier":
        k_scale = _unit_scale(sec, "unit", "V s/rad", "emf_constant")
        shape = wrap(sec.prefix, Fourier, tuple(sec.numbers("a", k_scale)), tuple(sec.numbers("b", k_scale)))
    else:
        k_scale = _unit_scale(sec, "unit", "V s/rad", "emf_constant")
        th_scale = _unit_scale(sec, "theta_unit", "rad", "angle")
        theta = tuple(sec.numbers("theta", th_scale))
        if th_scale != 1.0:
            _check_theta_as_written(sec, theta, th_scale)
        key = "k" if phase is None else "k_" + PHASES[phase]
        k = tuple(sec.numbers(key, k_scale))
        try:
            shape = Table(theta, k)
        except BldclabError as exc:
            field_ = key if exc.field == "k" else exc.field  # name the column the file has (k_a, k_b, k_c)
            raise BldclabError(sec.name(field_), exc.problem) from None
    return shape


def read_form(sec: Section, sizeless: str) -> Shape:
    """Read the ``[motor.emf]`` table of a motor whose back-EMF size is a speed constant (``sizeless``: its field).

    One trapezoid or sinusoid for the three phases, without ``k_phi`` or ``k_1``: the form the size is applied to.
    """
    if sec.has("phase") or (sec.data.get("kind") == "table" and not sec.has("k")):
        raise BldclabError(sec.name("phase" if sec.has("phase") else "kind"), f"{sizeless} gives one size to one "
                           "shape for the three phases: kind = \"trapezoid\" or \"sinusoid\" (per-phase shapes give "
                           f"their own sizes in V s/rad: drop {sizeless})")
    shape = _shape_from(sec, None, sizeless)
    sec.finish()
    return shape


def read_emf(sec: Section) -> BackEmf:
    """Read the ``[motor.emf]`` table: one shape for the three phases, per-phase table columns, or three phases."""
    if sec.has("phase"):
        phases = sec.raw("phase")
        if not isinstance(phases, list) or len(phases) != 3:
            raise BldclabError(sec.name("phase"), "needs exactly three [[motor.emf.phase]] tables (a, b, c)")
        others = sorted(set(sec.data) - {"phase"})
        if others:
            raise BldclabError(sec.name(others[0]), "not allowed next to [[motor.emf.phase]]: give each "
                               "phase's shape in its own [[motor.emf.phase]] table")
        shapes = []
        for j, ph in enumerate(phases):
            s = Section(ph, f"{sec.name('phase')}[{j}]")
            shapes.append(_shape_from(s, None))
            s.finish()
        sec.finish()
        return BackEmf((shapes[0], shapes[1], shapes[2]))
    if sec.data.get("kind") == "table" and not sec.has("k") and any(sec.has(f"k_{x}") for x in PHASES):
        shapes = [_shape_from(sec, j) for j in range(3)]
        sec.finish()
        return BackEmf((shapes[0], shapes[1], shapes[2]))
    shape = _shape_from(sec, None)
    sec.finish()
    return BackEmf.symmetric(shape)


def read_cogging(sec: Section) -> Cogging:
    """Read the ``[motor.cogging]`` table."""
    orders = sec.raw("orders")
    if not isinstance(orders, list):
        raise BldclabError(sec.name("orders"), "expected a list of integers")
    cog: Cogging = wrap(sec.prefix, Cogging, tuple(orders), tuple(sec.numbers("amplitudes")),
                        tuple(sec.numbers("phases")))
    sec.finish()
    return cog


def toml_string(v: str) -> str:
    """Return ``v`` as a TOML basic string: backslash, quote and every control character escaped."""
    out = []
    for ch in v:
        if ch in ('"', "\\"):
            out.append("\\" + ch)
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def toml_value(v: object) -> str:
    """Return a value as TOML: bool, integer, float (shortest repr), string, or a list of them."""
    if isinstance(v, bool | np.bool_):
        return "true" if v else "false"
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        return repr(float(v))  # shortest repr: reads back to the same double (numpy's repr is not TOML)
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, list | tuple):
        items = [toml_value(x) for x in v]
        if len(items) <= 8:
            return "[" + ", ".join(items) + "]"
        lines = [", ".join(items[j:j + 8]) for j in range(0, len(items), 8)]
        return "[\n    " + ",\n    ".join(lines) + ",\n]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def toml_table(header: str, items: Mapping[str, object]) -> str:
    """Return ``[header]`` and one ``key = value`` line per item that is not None (no header line for ``""``)."""
    lines = [f"[{header}]"] if header else []
    lines += [f"{k} = {toml_value(v)}" for k, v in items.items() if v is not None]
    return "\n".join(lines) + "\n"


def emf_tables(emf: BackEmf) -> list[str]:
    """Return the ``[motor.emf]`` table (or three ``[[motor.emf.phase]]`` tables) of a back-EMF."""
    shapes = emf.shapes
    if emf.is_symmetric:
        return [toml_table("motor.emf", shapes[0].to_toml_dict())]
    if len(tables := [s for s in shapes if isinstance(s, Table)]) == len(shapes) \
            and len({t.theta for t in tables}) == 1:
        items: dict[str, object] = {"kind": "table", "theta": list(tables[0].theta)}
        for j, t in enumerate(tables):
            items["k_" + PHASES[j]] = list(t.k)
        return [toml_table("motor.emf", items)]
    return ["[[motor.emf.phase]]\n" + toml_table("", s.to_toml_dict()) for s in shapes]


def cogging_table(c: Cogging) -> str:
    """Return the ``[motor.cogging]`` table."""
    return toml_table("motor.cogging", {"orders": list(c.orders), "amplitudes": list(c.amplitudes),
                                        "phases": list(c.phases)})

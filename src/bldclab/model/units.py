"""Quantities written with a unit in motor files ("640 rpm", "75 uH") converted to SI.

A field declares its dimension; a value is either a plain number (already SI) or a string
``"<number> <unit>"`` whose unit must belong to that dimension.

How a unit is read (docs/motor-files.md, "Numbers and units"):

- a spelling of :data:`DIMENSIONS`, or an SI symbol of :data:`PREFIXED` with any SI prefix (:data:`PREFIXES`):
  ``"mV s/rad"``, ``"kHz"``, ``"nH"``;
- the case of a symbol is free (``"mohm"``, ``"khz"``, ``"uh"``, ``"OHM"``, ``"RPM"``) but for ``s`` (second),
  which is not ``S`` (siemens); a prefix is read as typed (``m`` milli, ``M`` mega; ``K`` and ``U`` also stand for
  kilo and micro). A spelling that is another unit as typed (``"mS"``: millisiemens; ``"nm"``: nanometre in a
  torque) or written wholly in capitals after a prefix whose case matters (``"MOHM"``, ``"MW"``: mega or milli) is
  refused with both readings named;
- the plurals ``ohms``, ``degs``/``degrees``, ``rads``/``radians``.

The number is scaled by a power of ten exactly (``"30 uH"`` is the double nearest 3e-05, not ``30 * 1e-6``), so a
file written back shows the digits that were typed.
"""

from __future__ import annotations

import math
import re
from decimal import Decimal, InvalidOperation

from ..errors import BldclabError

__all__ = ["ALIASES", "CASE_PAIRED", "DIMENSIONS", "KELVIN", "PREFIXED", "PREFIXES", "per_unit", "to_si",
           "unit_factor"]

_RPM = 2.0 * math.pi / 60.0

#: Accepted units per dimension, as factor to SI (the spellings documented in docs/motor-files.md). The symbols of
#: :data:`PREFIXED` take any SI prefix besides.
DIMENSIONS: dict[str, dict[str, float]] = {
    "voltage": {"V": 1.0, "mV": 1e-3, "kV": 1e3},
    "current": {"A": 1.0, "mA": 1e-3, "kA": 1e3},
    "resistance": {"Ohm": 1.0, "mOhm": 1e-3, "uOhm": 1e-6, "kOhm": 1e3},
    "inductance": {"H": 1.0, "mH": 1e-3, "uH": 1e-6, "nH": 1e-9},
    "angle": {"rad": 1.0, "mrad": 1e-3, "deg": math.pi / 180.0},
    "speed": {"rad/s": 1.0, "rpm": _RPM, "r/min": _RPM, "krpm": 1e3 * _RPM},
    "frequency": {"Hz": 1.0, "kHz": 1e3, "MHz": 1e6},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "min": 60.0, "h": 3600.0},
    "torque": {"N m": 1.0, "Nm": 1.0, "N*m": 1.0, "mN m": 1e-3},
    "inertia": {"kg m^2": 1.0, "kg m2": 1.0, "kg*m^2": 1.0, "g cm^2": 1e-7},
    "emf_constant": {"V s/rad": 1.0, "Vs/rad": 1.0, "mV s/rad": 1e-3, "N m/A": 1.0, "Nm/A": 1.0},
    "speed_constant": {"rad/s/V": 1.0, "rpm/V": _RPM, "krpm/V": 1e3 * _RPM},
    "damping": {"N m s/rad": 1.0, "Nms/rad": 1.0},
    "propeller": {"N m s^2/rad^2": 1.0, "N m s^2": 1.0, "Nms^2": 1.0, "N m/(rad/s)^2": 1.0},
    "power": {"W": 1.0, "kW": 1e3},
    "energy": {"J": 1.0, "mJ": 1e-3, "uJ": 1e-6, "nJ": 1e-9},
    "charge": {"C": 1.0, "mC": 1e-3, "uC": 1e-6, "nC": 1e-9},
    "mass": {"kg": 1.0, "g": 1e-3},
    "length": {"m": 1.0, "mm": 1e-3, "um": 1e-6},
    "flux_density": {"T": 1.0, "mT": 1e-3},
    "density": {"kg/m^3": 1.0, "kg/dm^3": 1e3, "g/cm^3": 1e3},
    "resistivity": {"Ohm m": 1.0, "uOhm m": 1e-6, "uOhm cm": 1e-8, "Ohm mm^2/m": 1e-6},
    "specific_power": {"W/kg": 1.0},
    # thermal (docs/thermal.md): absolute temperatures in degC (the datasheets' unit; kelvin through KELVIN below),
    # differences in K, so a thermal resistance in K/W and in degC/W is the same number
    "temperature": {"degC": 1.0, "\u00b0C": 1.0},
    "thermal_resistance": {"K/W": 1.0, "degC/W": 1.0, "\u00b0C/W": 1.0, "mK/W": 1e-3},
    "heat_capacity": {"J/K": 1.0, "kJ/K": 1e3, "J/degC": 1.0, "W s/K": 1.0, "Ws/K": 1.0},
    "temperature_coefficient": {"1/K": 1.0, "%/K": 1e-2, "ppm/K": 1e-6, "1/degC": 1.0, "%/degC": 1e-2},
    "dimensionless": {"": 1.0},
}

#: Absolute temperature in kelvin, the one unit with an offset: ``"298.15 K"`` is 25 degC. Temperatures are held in
#: degC (the canonical unit of the ``temperature`` dimension: a plain number is degC), so to_si subtracts this.
KELVIN = 273.15

#: SI prefixes and their powers of ten (``u`` for micro; ``µ`` and ``μ`` are read as ``u``).
PREFIXES: dict[str, int] = {"Q": 30, "R": 27, "Y": 24, "Z": 21, "E": 18, "P": 15, "T": 12, "G": 9, "M": 6, "k": 3,
                            "h": 2, "da": 1, "d": -1, "c": -2, "m": -3, "u": -6, "n": -9, "p": -12, "f": -15,
                            "a": -18, "z": -21, "y": -24, "r": -27, "q": -30}

#: Prefix letters whose other case is another prefix: read as typed (``m`` is milli, ``M`` mega).
CASE_PAIRED: frozenset[str] = frozenset(p for p in PREFIXES if len(p) == 1 and p.swapcase() in PREFIXES)

#: Unit symbols that take any SI prefix, per dimension, with the power of ten of the unprefixed symbol (``g`` is
#: 1e-3 kg): ``"mV s/rad"``, ``"GHz"``, ``"nH"``, ``"kN m"``.
PREFIXED: dict[str, dict[str, int]] = {
    "voltage": {"V": 0}, "current": {"A": 0}, "resistance": {"Ohm": 0}, "inductance": {"H": 0},
    "angle": {"rad": 0}, "frequency": {"Hz": 0}, "time": {"s": 0}, "torque": {"N m": 0, "Nm": 0, "N*m": 0},
    "emf_constant": {"V s/rad": 0, "Vs/rad": 0, "N m/A": 0, "Nm/A": 0}, "power": {"W": 0}, "energy": {"J": 0},
    "charge": {"C": 0}, "mass": {"g": -3}, "length": {"m": 0}, "flux_density": {"T": 0},
}

#: Spellings accepted inside a unit and what they stand for ("75 µH", "50 mΩ", "0.32 V·s/rad", "kg·m²").
ALIASES: dict[str, str] = {"\u00b5": "u", "\u03bc": "u", "\u2126": "Ohm", "\u03a9": "Ohm", "\u00b7": " ",
                           "\u22c5": " ", "\u00b2": "^2", "\u00b3": "^3"}

#: Word forms read as the symbol (any case): plurals and spelled-out names.
_WORDS = ((re.compile(r"(?i)ohms(?![a-z])"), "Ohm"), (re.compile(r"(?i)deg(?:ree)?s(?![a-z])"), "deg"),
          (re.compile(r"(?i)degree(?![a-z])"), "deg"), (re.compile(r"(?i)radians?(?![a-z])"), "rad"),
          (re.compile(r"(?i)rads(?![a-z/])"), "rad"))

#: Prefixes written in the other case that still read as one prefix: ``K`` (kelvin is no prefix) for kilo, ``U`` for
#: micro, ``g`` for giga. Every other prefix is read as typed.
_LAZY_PREFIX = {"K": "k", "U": "u", "g": "G"}

#: Units of other quantities whose symbol differs only in case from one bldclab reads: as typed, they are those.
_OTHER_SYMBOLS = {"S": "siemens"}

_PREFIX_NAMES = {"Q": "quetta", "R": "ronna", "Y": "yotta", "Z": "zetta", "E": "exa", "P": "peta", "T": "tera",
                 "G": "giga", "M": "mega", "k": "kilo", "h": "hecto", "da": "deca", "d": "deci", "c": "centi",
                 "m": "milli", "u": "micro", "n": "nano", "p": "pico", "f": "femto", "a": "atto", "z": "zepto",
                 "y": "yocto", "r": "ronto", "q": "quecto"}

_NUM = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")
_PU = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(?:pu|p\.u\.)\s*$", re.IGNORECASE)

#: A factor to SI as (mantissa, power of ten): the number is scaled by the power of ten exactly (decimal), then
#: multiplied by the mantissa (1 for every decimal unit).
Factor = tuple[float, int]


def _split(factor: float) -> Factor:
    """Return ``factor`` as (mantissa, power of ten): ``(1, e)`` when it is the double of ``1e<e>``."""
    if factor > 0:
        e = round(math.log10(factor))
        if float(f"1e{e}") == factor:
            return 1.0, e
        if factor == 1e3 * _RPM:  # krpm (krpm/V): a thousand times the rpm
            return _RPM, 3
    return factor, 0


def _prefixed(unit: str, dimension: str, exact: bool) -> list[tuple[str, Factor]]:
    """Return the readings of ``unit`` as an SI prefix on a symbol of :data:`PREFIXED` (canonical spelling, factor).

    ``exact``: the case as typed; otherwise the symbol's case is free but for the second's ``s``, and the prefix is
    as typed (or ``K``, ``U``, ``g`` for kilo, micro, giga).
    """
    out = []
    for base, e0 in PREFIXED.get(dimension, {}).items():
        for prefix in ("", *PREFIXES):
            typed_p, typed_b = unit[:len(prefix)], unit[len(prefix):]
            if len(typed_b) != len(base):
                continue
            if exact:
                ok = typed_p == prefix and typed_b == base
            else:
                ok = (typed_p == prefix or _LAZY_PREFIX.get(typed_p) == prefix) \
                    and typed_b.lower() == base.lower() and (base != "s" or typed_b == "s")
            if ok:
                out.append((prefix + base, (1.0, PREFIXES.get(prefix, 0) + e0)))
    return out


def _reading(unit: str, dimension: str) -> str:
    """Name what a spelling is as typed when it is a unit of something else (``"mS"``: millisiemens), else ``""``."""
    for prefix in ("", *PREFIXES):
        if unit.startswith(prefix) and unit[len(prefix):] in _OTHER_SYMBOLS:
            return _PREFIX_NAMES.get(prefix, "") + _OTHER_SYMBOLS[unit[len(prefix):]]
    for other in DIMENSIONS:
        if other != dimension and (unit in DIMENSIONS[other] or _prefixed(unit, other, exact=True)):
            return f"a unit of {other.replace('_', ' ')}"
    return ""


def _case_changes(a: str, b: str) -> int:
    return sum(x != y for x, y in zip(a, b, strict=False))


def unit_factor(unit: str, dimension: str, field: str, source: str | None = None) -> Factor:
    """Return the factor to SI of a unit spelling, as (mantissa, power of ten).

    Parameters
    ----------
    unit : str
        The unit as written (aliases such as ``µ`` and ``Ω`` allowed).
    dimension : str
        Key of :data:`DIMENSIONS`.
    field : str
        Dotted field name, for the error message.
    source : str, optional
        File the value came from, for the error message.

    Returns
    -------
    tuple of (float, int)
        The value in SI is the number times ``10**e`` (exactly, decimal) times the mantissa.

    Raises
    ------
    BldclabError
        If the unit is not one of ``dimension``, or is ambiguous (both readings named).
    """
    for alias, plain in ALIASES.items():
        unit = unit.replace(alias, plain)
    unit = " ".join(unit.split())
    letters = [c for c in unit if c.isalpha()]
    capitals = len(letters) > 1 and all(c.isupper() for c in letters) and unit[0] in CASE_PAIRED
    for pattern, word in _WORDS:
        unit = pattern.sub(word, unit)
    units = DIMENSIONS[dimension]
    if unit in units:
        return _split(units[unit])
    exact = _prefixed(unit, dimension, exact=True)
    if exact and not capitals:
        return exact[0][1]
    # the case is free: the documented spellings that are no prefixed symbol (rpm, deg, kg m^2) in any case, the
    # prefixed symbols with the case of a CASE_PAIRED prefix and of the second's s kept
    readings = {u: _split(f) for u, f in units.items()
                if u and u.lower() == unit.lower() and not _prefixed(u, dimension, exact=True)}
    readings.update(_prefixed(unit, dimension, exact=False))
    spellings = {*units, *(p + b for b in PREFIXED.get(dimension, {}) for p in ("", *PREFIXES))}
    near = sorted((u for u in spellings if u and u.lower() == unit.lower() and u not in readings),
                  key=lambda u: (_case_changes(u, unit), u))
    other = _reading(unit, dimension)
    if other and (readings or near):  # "mS": millisiemens as typed
        cands = sorted({*readings, *near}, key=lambda u: (_case_changes(u, unit), u))[:1 if not capitals else None]
        named = " or ".join(repr(u) for u in cands)
        raise BldclabError(field, f"unit {unit!r} is {other} as written, not {named}: write {named} (the case of "
                           "s and S, and of the prefixes m and M, p and P, is read as typed)", source)
    if capitals:
        # typed in capitals ("MOHM"): the prefix's case says nothing, so both of its readings are candidates
        both = dict(readings)
        both.update(_prefixed(unit[0].swapcase() + unit[1:], dimension, exact=False))
        if len(set(both.values())) > 1:
            names = " or ".join(f"{u!r} ({_PREFIX_NAMES.get(u[0], '')})" for u in sorted(both))
            raise BldclabError(field, f"unit {unit!r} is ambiguous in capitals: {names}; write the prefix's case",
                               source)
    factors = set(readings.values())
    if len(factors) == 1:
        return factors.pop()
    if len(factors) > 1:
        raise BldclabError(field, f"unit {unit!r} is ambiguous: {' or '.join(repr(u) for u in sorted(readings))}; "
                           "write the case of the prefix", source)
    if near:
        raise BldclabError(field, f"unit {unit!r} is not {near[0]!r}: the case of s and S, and of the prefixes m "
                           f"and M, p and P, is read as typed (write {near[0]!r})", source)
    known = ", ".join(repr(u) for u in units if u)
    raise BldclabError(field, f"unit {unit!r} is not a unit of {dimension.replace('_', ' ')} "
                       f"(use one of {known} or a plain SI number)", source)


def _scaled(number: str, factor: Factor) -> float:
    """Return ``number`` (decimal text) times the factor: the power of ten applied exactly, then the mantissa."""
    mantissa, e = factor
    try:
        value = float(Decimal(number).scaleb(e)) if e else float(number)
    except InvalidOperation:  # pragma: no cover - the pattern only lets decimal numbers through
        value = float(number) * 10.0**e
    return value * mantissa if mantissa != 1.0 else value


def per_unit(value: object) -> float | None:
    """Return the number of a per-unit string (``"0.5 pu"``, ``"0.5 p.u."``, any case), else None.

    Parameters
    ----------
    value : object
        A value as typed.

    Returns
    -------
    float or None
        The per-unit number; None if ``value`` is not a per-unit string.
    """
    if not isinstance(value, str):
        return None
    m = _PU.match(value)
    return float(m.group(1)) if m else None


def to_si(value: object, dimension: str, field: str, source: str | None = None) -> float:
    """Convert a number or a ``"<number> <unit>"`` string to SI.

    Parameters
    ----------
    value : object
        A TOML value: int, float or string with a unit.
    dimension : str
        Key of :data:`DIMENSIONS` the field belongs to.
    field : str
        Dotted field name, for the error message.
    source : str, optional
        File the value came from, for the error message.

    Returns
    -------
    float
        The value in SI units, temperatures in degC (may be non-finite only if the input was; callers check
        ranges).

    Raises
    ------
    BldclabError
        If the value is not a number, has no parseable number, or its unit is not of ``dimension`` (or is
        ambiguous: both readings named).

    """
    units = DIMENSIONS[dimension]
    if isinstance(value, bool):
        raise BldclabError(field, f"expected a number, got a boolean ({value})", source)
    if isinstance(value, int | float):
        return float(value)
    if isinstance(value, str):
        m = _NUM.match(value)
        if not m:
            raise BldclabError(field, f"cannot read a number in {value!r}", source)
        number, unit = m.group(1), m.group(2)
        if " ".join(unit.split()) == "" and dimension != "dimensionless":
            return float(number)
        if dimension == "temperature" and " ".join(unit.split()) == "K":
            return float(number) - KELVIN
        return _scaled(number, unit_factor(unit, dimension, field, source))
    raise BldclabError(field, f"expected a number or a string like '1.5 {next(iter(units))}', "
                       f"got {type(value).__name__}", source)

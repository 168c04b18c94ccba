"""Quantities written with a unit in motor files ("640 rpm", "75 uH") converted to SI.

A field declares its dimension; a value is either a plain number (already SI) or a string
``"<number> <unit>"`` whose unit must belong to that dimension.
"""

from __future__ import annotations

import math
import re

from ..errors import BldclabError

__all__ = ["ALIASES", "DIMENSIONS", "KELVIN", "to_si"]

_RPM = 2.0 * math.pi / 60.0

#: Accepted units per dimension, as factor to SI.
DIMENSIONS: dict[str, dict[str, float]] = {
    "voltage": {"V": 1.0, "mV": 1e-3, "kV": 1e3},
    "current": {"A": 1.0, "mA": 1e-3, "kA": 1e3},
    "resistance": {"Ohm": 1.0, "mOhm": 1e-3, "uOhm": 1e-6, "kOhm": 1e3},
    "inductance": {"H": 1.0, "mH": 1e-3, "uH": 1e-6, "nH": 1e-9},
    "angle": {"rad": 1.0, "mrad": 1e-3, "deg": math.pi / 180.0},
    "speed": {"rad/s": 1.0, "rpm": _RPM, "r/min": _RPM, "krpm": 1e3 * _RPM},
    "frequency": {"Hz": 1.0, "kHz": 1e3, "MHz": 1e6},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9},
    "torque": {"N m": 1.0, "Nm": 1.0, "N*m": 1.0, "mN m": 1e-3},
    "inertia": {"kg m^2": 1.0, "kg m2": 1.0, "kg*m^2": 1.0, "g cm^2": 1e-7},
    "emf_constant": {"V s/rad": 1.0, "Vs/rad": 1.0, "N m/A": 1.0, "Nm/A": 1.0},
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

#: Spellings accepted inside a unit and what they stand for ("75 µH", "50 mΩ", "0.32 V·s/rad", "kg·m²").
ALIASES: dict[str, str] = {"\u00b5": "u", "\u03bc": "u", "\u2126": "Ohm", "\u03a9": "Ohm", "\u00b7": " ",
                           "\u22c5": " ", "\u00b2": "^2", "\u00b3": "^3"}

_NUM = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


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
        If the value is not a number, has no parseable number, or its unit is not of ``dimension``.

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
        number, unit = float(m.group(1)), m.group(2)
        for alias, plain in ALIASES.items():
            unit = unit.replace(alias, plain)
        unit = " ".join(unit.split())
        if unit == "" and dimension != "dimensionless":
            return number
        if dimension == "temperature" and unit == "K":
            return number - KELVIN
        if unit not in units:
            known = ", ".join(repr(u) for u in [*units, *(["K"] if dimension == "temperature" else [])] if u)
            raise BldclabError(field, f"unit {unit!r} is not a unit of {dimension.replace('_', ' ')} "
                               f"(use one of {known} or a plain SI number)", source)
        return number * units[unit]
    raise BldclabError(field, f"expected a number or a string like '1.5 {next(iter(units))}', "
                       f"got {type(value).__name__}", source)

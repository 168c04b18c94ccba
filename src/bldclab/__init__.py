"""bldclab: simulate, analyse and control PM brushless DC motor drives."""

from __future__ import annotations

from .catalog import load
from .errors import BldclabError
from .motor import (
    BackEmf,
    Cogging,
    Drive,
    Fourier,
    Inverter,
    Mechanics,
    Motor,
    Sensors,
    Sinusoid,
    Table,
    Trapezoid,
)

__version__ = "0.1.0"

__all__ = [
    "BackEmf",
    "BldclabError",
    "Cogging",
    "Drive",
    "Fourier",
    "Inverter",
    "Mechanics",
    "Motor",
    "Sensors",
    "Sinusoid",
    "Table",
    "Trapezoid",
    "__version__",
    "load",
]

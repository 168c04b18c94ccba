"""bldclab: simulate, analyse and control PM brushless DC motor drives."""

from __future__ import annotations

__version__ = "0.1.0"

from .catalog import load
from .control import Control, Lu, OpenLoop, Sine, SixStep, SixStepVoltage
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
from .results import Metrics, SimResult
from .sim import Fault, Scenario, simulate

__all__ = [
    "BackEmf",
    "BldclabError",
    "Cogging",
    "Control",
    "Drive",
    "Fault",
    "Fourier",
    "Inverter",
    "Lu",
    "Mechanics",
    "Metrics",
    "Motor",
    "OpenLoop",
    "Scenario",
    "Sensors",
    "SimResult",
    "Sine",
    "Sinusoid",
    "SixStep",
    "SixStepVoltage",
    "Table",
    "Trapezoid",
    "__version__",
    "load",
    "simulate",
]

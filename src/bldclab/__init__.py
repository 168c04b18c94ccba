"""bldclab: simulate, analyse and control PM brushless DC motor drives.

The public names: ``import bldclab as bl`` then ``bl.load``, ``bl.simulate``, the drive and controller classes, and
the modules ``bl.catalog`` (:mod:`bldclab.model.catalog`) and ``bl.experiments``
(:mod:`bldclab.analysis.experiments`). The package is layered (base, model, binding, control,
sim, analysis, sweep, report, cli); this module is the top, the only one that imports from all of them.
"""

from __future__ import annotations

from ._core import decode_flags, flag
from ._version import __version__
from .analysis import experiments
from .control import Control, HallCal, HallCalibration, Lu, OpenLoop, Sine, SixStep, SixStepVoltage
from .errors import BldclabError
from .model import catalog
from .model.catalog import load
from .model.emf import BackEmf, Cogging, Fourier, Sinusoid, Table, Trapezoid
from .model.motor import Drive, Inverter, Mechanics, Motor, Sensors
from .sim import Fault, Scenario, simulate
from .sim.hallcal import calibrate as calibrate_hall
from .sim.results import Metrics, SimResult

__all__ = [
    "BackEmf",
    "BldclabError",
    "Cogging",
    "Control",
    "Drive",
    "Fault",
    "Fourier",
    "HallCal",
    "HallCalibration",
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
    "calibrate_hall",
    "catalog",
    "decode_flags",
    "experiments",
    "flag",
    "load",
    "simulate",
]

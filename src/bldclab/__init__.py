"""bldclab: simulate, analyse and control PM brushless DC motor drives.

The public names: ``import bldclab as bl`` then ``bl.load``, ``bl.simulate``, the drive and controller classes, and
the modules ``bl.catalog`` (:mod:`bldclab.model.catalog`) and ``bl.experiments``
(:mod:`bldclab.analysis.experiments`). The package is layered (base, model, binding, control,
sim, analysis, sweep, report, cli); this module is the top, the only one that imports from all of them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._lazy import Lazy, attach
from ._version import __version__
from .errors import BldclabError

if TYPE_CHECKING:  # the same names, for type checkers and readers; at run time they are imported on first use
    from ._core import decode_flags, flag
    from .analysis import experiments
    from .analysis.commission import Estimate, commission
    from .control import (
        Control,
        HallCal,
        HallCalibration,
        Lu,
        OpenLoop,
        Sine,
        SixStep,
        SixStepSensorless,
        SixStepVoltage,
        UserControl,
    )
    from .control.user import PythonControl
    from .model import catalog
    from .model.catalog import load
    from .model.emf import BackEmf, Cogging, Fourier, Sinusoid, Table, Trapezoid
    from .model.motor import Drive, Inverter, Mechanics, Motor, Sensors
    from .sim import Fault, Scenario, simulate
    from .sim.hallcal import calibrate as calibrate_hall
    from .sim.results import Metrics, SimResult

#: Public name -> (module that defines it, its name there; None: the module itself), imported on first use
#: (:mod:`bldclab._lazy`): ``import bldclab``, and the command line that lives in this package, load numpy, the C
#: library and the controllers only when a name needs them.
LAZY: Lazy = {
    "decode_flags": ("bldclab._core", "decode_flags"),
    "flag": ("bldclab._core", "flag"),
    "experiments": ("bldclab.analysis.experiments", None),
    **{name: ("bldclab.analysis.commission", name) for name in ("Estimate", "commission")},
    **{name: ("bldclab.control", name) for name in ("Control", "HallCal", "HallCalibration", "Lu", "OpenLoop",
                                                    "Sine", "SixStep", "SixStepSensorless", "SixStepVoltage",
                                                    "UserControl")},
    "PythonControl": ("bldclab.control.user", "PythonControl"),
    "catalog": ("bldclab.model.catalog", None),
    "load": ("bldclab.model.catalog", "load"),
    **{name: ("bldclab.model.emf", name) for name in ("BackEmf", "Cogging", "Fourier", "Sinusoid", "Table",
                                                      "Trapezoid")},
    **{name: ("bldclab.model.motor", name) for name in ("Drive", "Inverter", "Mechanics", "Motor", "Sensors")},
    **{name: ("bldclab.sim", name) for name in ("Fault", "Scenario", "simulate")},
    "calibrate_hall": ("bldclab.sim.hallcal", "calibrate"),
    **{name: ("bldclab.sim.results", name) for name in ("Metrics", "SimResult")},
}

# the modules reachable as attributes after ``import bldclab`` alone (``bl.sim.samples_of``, ``bl._core.core()``),
# as when this module imported them all at once
__getattr__, __dir__ = attach(globals(), LAZY, ("_core", "_files", "analysis", "control", "model", "sim", "svg"))

__all__ = [
    "BackEmf",
    "BldclabError",
    "Cogging",
    "Control",
    "Drive",
    "Estimate",
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
    "PythonControl",
    "Scenario",
    "Sensors",
    "SimResult",
    "Sine",
    "Sinusoid",
    "SixStep",
    "SixStepSensorless",
    "SixStepVoltage",
    "Table",
    "Trapezoid",
    "UserControl",
    "__version__",
    "calibrate_hall",
    "catalog",
    "commission",
    "decode_flags",
    "experiments",
    "flag",
    "load",
    "simulate",
]

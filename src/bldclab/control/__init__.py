"""Controller choices for :func:`bldclab.simulate`: each names a C controller and fills its parameters.

The C code is what runs (``core/ctrl/include/bldc/``); these frozen dataclasses only choose it and its settings.
What the per-sample reference ``Scenario.ref`` means depends on the controller (see each class). One module per
controller family; adding one: a module here with a :class:`Control` subclass, and its import below.
"""

from __future__ import annotations

from .base import Control
from .commission import Commission
from .derate import ResistanceEstimate, TemperatureDerating
from .hallcal import HallCal, HallCalibration
from .lu import Lu
from .openloop import OpenLoop, SixStepVoltage
from .sensorless import SixStepSensorless
from .sine import Sine
from .sixstep import SixStep
from .user import UserControl

__all__ = ["Commission", "Control", "HallCal", "HallCalibration", "Lu", "OpenLoop", "ResistanceEstimate", "Sine",
           "SixStep", "SixStepSensorless", "SixStepVoltage", "TemperatureDerating", "UserControl"]

"""Back-EMF identification from a constant-speed waveform (paper 2).

Back-EMF identification from a constant-speed waveform (paper 2): the measured record, the algorithm and the
synthetic measurements that test it.

See :mod:`.algorithm` for the method; ``bldclab identify`` (:mod:`bldclab.cli.identify`) is its command.
"""

from __future__ import annotations

from .algorithm import (
    ASYMMETRY_WARN,
    DEFAULT_WINDOW,
    MIN_SAMPLES_PER_PERIOD,
    OFFSET_WARN,
    SPACING_ERROR,
    SPACING_WARN,
    SPEED_ERROR,
    SPEED_WARN,
    HallEdges,
    Identification,
    identify,
    observable_emf,
)
from .scope import SAMPLE_FILE, sample_path, synthetic_measurement
from .waveform import Waveform, read_waveform, waveform_csv, waveform_from_columns

__all__ = [
    "ASYMMETRY_WARN",
    "DEFAULT_WINDOW",
    "MIN_SAMPLES_PER_PERIOD",
    "OFFSET_WARN",
    "SAMPLE_FILE",
    "SPACING_ERROR",
    "SPACING_WARN",
    "SPEED_ERROR",
    "SPEED_WARN",
    "HallEdges",
    "Identification",
    "Waveform",
    "identify",
    "observable_emf",
    "read_waveform",
    "sample_path",
    "synthetic_measurement",
    "waveform_csv",
    "waveform_from_columns",
]

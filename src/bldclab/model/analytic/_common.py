"""Helpers shared by the sections of :mod:`bldclab.model.analytic`: argument checks and the scalar/array return."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import BldclabError

__all__ = ["SQRT3"]


FloatOrArray = float | NDArray[np.float64]

SQRT3 = math.sqrt(3.0)


def _speed(omega_pu: ArrayLike, name: str = "omega_pu") -> NDArray[np.float64]:
    """Return ``omega_pu`` as a float array, rejecting NaN, infinite or negative speeds."""
    w = np.asarray(omega_pu, dtype=float)
    if not np.all(np.isfinite(w)):
        raise BldclabError(name, "must be finite (no NaN or infinity)")
    if np.any(w < 0.0):
        raise BldclabError(name, f"must be >= 0 (motoring), got {float(np.min(w)):g}")
    return w


def _out(x: NDArray[np.float64]) -> FloatOrArray:
    """Return a 0-d array as ``float``, any other array unchanged."""
    return float(x) if np.ndim(x) == 0 else x


def _theta(Theta_m: float) -> float:
    """Check the motor-specific parameter (22): finite and > 0."""
    if isinstance(Theta_m, bool) or not isinstance(Theta_m, int | float | np.floating):
        raise BldclabError("theta_m", f"expected a number, got {type(Theta_m).__name__}")
    if not math.isfinite(Theta_m) or Theta_m <= 0.0:
        raise BldclabError("theta_m", f"must be finite and > 0 rad, got {Theta_m!r}")
    return float(Theta_m)

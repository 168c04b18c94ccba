"""Field checks shared by the model's dataclasses: one clear error naming the field."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..errors import BldclabError

__all__ = ["check_array", "check_number"]


def check_number(name: str, value: object, *, lo: float | None = None, lo_open: bool = False,
         hi: float | None = None, hi_open: bool = False, allow_none: bool = False) -> None:
    """Check one scalar field: a real, finite number within bounds, else raise naming ``name``."""
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise BldclabError(name, f"expected a number, got {type(value).__name__} ({value!r})")
    v = float(value)
    if math.isnan(v):
        raise BldclabError(name, "is NaN")
    if math.isinf(v):
        raise BldclabError(name, "is infinite")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        rel = ">" if lo_open else ">="
        raise BldclabError(name, f"must be {rel} {lo:g}, got {v:g}")
    if hi is not None and (v > hi or (hi_open and v == hi)):
        rel = "<" if hi_open else "<="
        raise BldclabError(name, f"must be {rel} {hi:g}, got {v:g}")


def check_array(name: str, values: object, *, min_len: int = 1) -> NDArray[np.float64]:
    """Check a sequence of finite numbers (no holes) and return it as a float array."""
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray):
        raise BldclabError(name, f"expected a list of numbers, got {type(values).__name__}")
    for j, v in enumerate(values):
        if v is None:
            raise BldclabError(name, f"entry {j} is missing (hole in the data)")
        if isinstance(v, bool) or not isinstance(v, int | float | np.floating | np.integer):
            raise BldclabError(name, f"entry {j} is not a number ({v!r})")
        if not math.isfinite(float(v)):
            raise BldclabError(name, f"entry {j} is {float(v)} (NaN or infinite; hole in the data?)")
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1:
        raise BldclabError(name, "must be a one-dimensional list")
    if arr.size < min_len:
        raise BldclabError(name, f"needs at least {min_len} entries, got {arr.size}")
    return arr

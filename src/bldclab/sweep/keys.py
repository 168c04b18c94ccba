"""Case keys: a sweep case's inputs as canonical plain data (JSON) and its SHA-256 key.

Plain data is what a TOML or JSON file can hold; dataclasses (drives, controllers) become dictionaries. The key of
a case is the hash of its canonical JSON, so equal inputs give equal keys on any machine.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from ..control import Control
from ..errors import BldclabError
from ..model.motor import Drive

__all__ = [
    "case_key",
]


class _NotPlainError(Exception):
    """A value that is not plain data; ``path`` locates it inside the value being converted."""

    def __init__(self, path: str, problem: str) -> None:
        super().__init__(problem)
        self.path = path
        self.problem = problem


def _plain(value: Any, where: str) -> Any:
    """Return ``value`` as JSON data (dataclass -> dict of its init fields, tuple/array -> list, finite floats).

    Raises
    ------
    BldclabError
        Naming ``where`` (and the position inside ``value``) for a non-finite number or a non-data object.
    """
    try:
        return _to_plain(value)
    except _NotPlainError as exc:
        raise BldclabError(where + exc.path, exc.problem) from None


def _to_plain(value: Any) -> Any:
    t = type(value)
    if t is str or t is int or t is bool or value is None:
        return value
    if t is float or isinstance(value, float | np.floating):
        v = float(value)
        if not math.isfinite(v):
            raise _NotPlainError("", f"must be finite, got {v}")
        return v
    if isinstance(value, bool | str | np.bool_):
        return bool(value) if isinstance(value, np.bool_) else value
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, np.ndarray):
        return _to_plain(value.tolist())
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        items: Iterable[tuple[Any, Any]] = ((f.name, getattr(value, f.name))
                                            for f in dataclasses.fields(value) if f.init)
    elif isinstance(value, Mapping):
        items = value.items()
    elif isinstance(value, list | tuple):
        out = []
        for j, v in enumerate(value):
            try:
                out.append(_to_plain(v))
            except _NotPlainError as exc:
                raise _NotPlainError(f"[{j}]{exc.path}", exc.problem) from None
        return out
    else:
        raise _NotPlainError("", f"cannot be written as plain data (a {type(value).__name__})")
    table = {}
    for k, v in items:
        try:
            table[str(k)] = _to_plain(v)
        except _NotPlainError as exc:
            raise _NotPlainError(f".{k}{exc.path}", exc.problem) from None
    return table


def _canonical(data: Any) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


def case_key(inputs: Mapping[str, Any]) -> str:
    """Return the key of a case: sha256 (hex) of the canonical JSON of its full inputs.

    Parameters
    ----------
    inputs : mapping
        ``{"bldclab": version, "drive": motor-file text, "control": {"class", "params"}, "experiment": {...}}``
        (:attr:`ResolvedCase.inputs`).

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    return hashlib.sha256(_canonical(inputs).encode("utf-8")).hexdigest()


def _show(value: Any) -> Any:
    """Return a setting's value for a table column or a message (objects by name)."""
    t = type(value)
    if t is str or t is int or t is float or t is bool or value is None:
        return value
    if isinstance(value, Drive):
        return value.name or "<Drive>"
    if isinstance(value, Control):
        return type(value).__name__
    if isinstance(value, type):
        return value.__name__
    try:
        return _to_plain(value)
    except _NotPlainError:
        return repr(value)

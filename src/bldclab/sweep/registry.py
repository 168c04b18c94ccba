"""Controllers by name for sweep files: every controller class of :mod:`bldclab.control`, plus those registered."""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Mapping
from typing import Any

from .. import control as package
from ..control import Control
from ..errors import BldclabError

__all__ = [
    "controllers",
    "register_control",
]

_REGISTERED: dict[str, type[Control]] = {}


def register_control(cls: type[Control], name: str | None = None) -> None:
    """Make a :class:`~bldclab.control.Control` subclass available to sweeps by name.

    Subclasses exported by :mod:`bldclab.control` are available without registration. Workers find a class by
    its module and qualified name, so it must be importable there (defined in a module, not in ``__main__``).

    Parameters
    ----------
    cls : type
        A frozen dataclass subclass of :class:`~bldclab.control.Control`.
    name : str, optional
        The name sweeps use; default the class name.
    """
    if not (isinstance(cls, type) and issubclass(cls, Control) and dataclasses.is_dataclass(cls)):
        raise BldclabError("controller", f"{cls!r} is not a dataclass subclass of bldclab.control.Control")
    _REGISTERED[name or cls.__name__] = cls


def controllers() -> dict[str, type[Control]]:
    """Return the controllers sweeps know by name: ``{name: class}``.

    Every dataclass subclass of :class:`~bldclab.control.Control` in ``bldclab.control.__all__`` under its class
    name, and those added with :func:`register_control`.
    """
    out: dict[str, type[Control]] = {}
    for name in getattr(package, "__all__", ()):
        obj = getattr(package, name, None)
        if isinstance(obj, type) and issubclass(obj, Control) and obj is not Control and dataclasses.is_dataclass(obj):
            out[name] = obj
    out.update(_REGISTERED)
    return out


def _dataclass_in(hint: Any) -> type | None:
    """Return the dataclass a type hint names (directly or inside a union), if any."""
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return hint
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        for arg in typing.get_args(hint):
            if isinstance(arg, type) and dataclasses.is_dataclass(arg):
                return arg
    return None


def _build(cls: type, params: Mapping[str, Any], where: str) -> Any:
    """Construct a dataclass from plain keyword arguments; a table for a dataclass-typed field builds that class."""
    init = [f.name for f in dataclasses.fields(cls) if f.init]
    for name in params:
        if name not in init:
            raise BldclabError(f"{where}.{name}", f"no such parameter of {cls.__name__} "
                               f"(parameters: {', '.join(init) or 'none'})")
    try:
        hints = typing.get_type_hints(cls)
    except Exception:  # unresolvable annotations: no nested construction
        hints = {}
    kw: dict[str, Any] = {}
    for name, value in params.items():
        sub = _dataclass_in(hints.get(name))
        kw[name] = _build(sub, value, f"{where}.{name}") if sub is not None and isinstance(value, Mapping) else value
    try:
        return cls(**kw)
    except TypeError as exc:
        raise BldclabError(where, f"{cls.__name__}: {exc}") from None

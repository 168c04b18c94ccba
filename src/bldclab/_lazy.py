"""Names of a package imported on first use: the one place where bldclab imports a module by name.

A package whose ``__init__`` re-exports names from heavy modules (the C binding, pandas, matplotlib) declares them in
a module-level table ``LAZY`` (public name -> defining module and its name there) and gets its module
``__getattr__`` and ``__dir__`` from :func:`attach`: ``import bldclab`` then costs almost nothing, and
``bldclab.simulate`` imports :mod:`bldclab.sim` when it is first used. The command line's registry
(:data:`bldclab.cli.COMMANDS`) imports a command's module through :func:`load` when that command runs.

``tests/test_layers.py`` reads these tables as imports of the package that declares them (the layer rule applies
to them as to any import) and fails on a by-name import anywhere else.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Mapping, MutableMapping
from types import ModuleType
from typing import Any

__all__ = ["Lazy", "attach", "load"]

#: A table of lazy names: public name -> (module that defines it, its name there; None: the module itself).
Lazy = Mapping[str, tuple[str, str | None]]


def load(module: str) -> ModuleType:
    """Import a bldclab module by its absolute name and return it.

    Parameters
    ----------
    module : str
        E.g. ``"bldclab.cli.effmap"``.

    Returns
    -------
    types.ModuleType
    """
    return importlib.import_module(module)


def attach(namespace: MutableMapping[str, Any], table: Lazy, modules: Iterable[str] = ()
           ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Return ``__getattr__`` and ``__dir__`` for a package that imports ``table``'s names on first use.

    Parameters
    ----------
    namespace : dict
        The package's ``globals()``: a name, once imported, is kept there (later uses do not come back here).
    table : mapping
        Public name -> (absolute module name, name in that module or None for the module itself).
    modules : iterable of str
        Submodules (relative names) also reachable as attributes before anything imported them
        (``bldclab.sim`` after ``import bldclab``).

    Returns
    -------
    tuple of callable
        The package's ``__getattr__(name)`` and ``__dir__()``.
    """
    package = namespace["__name__"]
    subs = tuple(modules)

    def lazy_getattr(name: str) -> Any:
        if name in table:
            module, attr = table[name]
            mod = load(module)
            value = mod if attr is None else getattr(mod, attr)
        elif name in subs:
            value = load(f"{package}.{name}")
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        namespace[name] = value
        return value

    def lazy_dir() -> list[str]:
        return sorted({*namespace, *table, *subs})

    return lazy_getattr, lazy_dir

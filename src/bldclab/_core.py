"""The binding to the C core: one shared library, loaded with ctypes.

Nothing here restates a C struct by hand. At import the library describes itself (``core/host/src/bc_bind.c``): every
struct the host fills or reads, with member offsets and sizes taken from the compiler, the trace fields of
``BC_TRACE_FIELDS``, the named constants (enum values and flag bits, by group) and the registry of controllers.
numpy structured dtypes are built from that description and checked against the C ``sizeof`` of each struct, so a
stale or mismatched library fails loudly at import.

The contract in the other direction: :meth:`Core.filled` returns a parameter record only when every member the C
library lists was given (and nothing else), so a member added in C and forgotten in Python fails at once; the C
constants are read from the library (``BC_FLAG_SAFE`` etc. as attributes of this module, :func:`decode_flags`), never
restated; :class:`CParams` owns the arrays a record points to, so no caller handles ctypes lifetimes.
"""

from __future__ import annotations

import ctypes
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from ._version import __version__
from .errors import BldclabError

__all__ = ["CParams", "Controller", "Core", "core", "decode_flags", "flag"]

_BASE = {"f8": np.float64, "f4": np.float32, "i4": np.int32, "u4": np.uint32, "i8": np.int64, "u8": np.uint64,
         "ptr": np.uintp}


class _FieldDesc(ctypes.Structure):
    _fields_ = (("strct", ctypes.c_char_p), ("field", ctypes.c_char_p), ("type", ctypes.c_char_p),
                ("offset", ctypes.c_uint32), ("size", ctypes.c_uint32))


class _StructDesc(ctypes.Structure):
    _fields_ = (("name", ctypes.c_char_p), ("size", ctypes.c_uint32))


class _ConstDesc(ctypes.Structure):
    _fields_ = (("group", ctypes.c_char_p), ("name", ctypes.c_char_p), ("value", ctypes.c_int64))


class _CtrlInfo(ctypes.Structure):
    _fields_ = (("name", ctypes.c_char_p), ("params", ctypes.c_char_p), ("state", ctypes.c_char_p),
                ("init", ctypes.c_void_p), ("step", ctypes.c_void_p), ("diag", ctypes.c_char_p * 8))


_INIT = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p)
_STEP = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)


@dataclass(frozen=True)
class Controller:
    """A controller registered in the C core.

    Attributes
    ----------
    name : str
        Registry name (``"sixv"``, ...).
    params, state : str
        C struct names of its parameters and state.
    init_ptr, step_ptr : int
        Addresses of its ``init`` and ``step`` functions.
    diag : tuple of str
        Meaning of the eight diagnostic channels (empty string: unused).
    """

    name: str
    params: str
    state: str
    init_ptr: int
    step_ptr: int
    diag: tuple[str, ...]


class CParams:
    """A filled C parameter record and the arrays its pointers refer to, kept alive as long as this object.

    Parameters
    ----------
    record : numpy.ndarray
        One-element record of the controller's params struct (what C reads).
    buffers : iterable of object
        Arrays (or other :class:`CParams`) whose memory the record points to.
    """

    def __init__(self, record: np.ndarray, buffers: Iterable[object] = ()) -> None:
        self.record = record
        self._buffers = tuple(buffers)

    @property
    def address(self) -> int:
        """Address of the record (what a C ``const void *params`` receives)."""
        return int(self.record.ctypes.data)


def _library_path() -> Path:
    here = Path(__file__).parent
    found = sorted(here.glob("_bccore*.so")) + sorted(here.glob("_bccore*.pyd")) + sorted(here.glob("_bccore*.dylib"))
    if not found:
        raise ImportError(f"bldclab's compiled core (_bccore*.so) is missing from {here}: install the package with "
                          "'pip install .' so that core/ is compiled")
    return found[0]


class Core:
    """The loaded C library with numpy dtypes for its structs.

    Parameters
    ----------
    path : Path
        The shared library.
    """

    def __init__(self, path: Path) -> None:
        lib = ctypes.CDLL(str(path))
        self.lib = lib
        lib.bc_layout_count.restype = ctypes.c_int32
        lib.bc_layout_get.restype = ctypes.POINTER(_FieldDesc)
        lib.bc_layout_get.argtypes = (ctypes.c_int32,)
        lib.bc_struct_count.restype = ctypes.c_int32
        lib.bc_struct_get.restype = ctypes.POINTER(_StructDesc)
        lib.bc_struct_get.argtypes = (ctypes.c_int32,)
        lib.bc_trace_count.restype = ctypes.c_int32
        for fn in (lib.bc_trace_name, lib.bc_trace_unit, lib.bc_trace_doc):
            fn.restype = ctypes.c_char_p
            fn.argtypes = (ctypes.c_int32,)
        lib.bc_acc_count.restype = ctypes.c_int32
        lib.bc_acc_name.restype = ctypes.c_char_p
        lib.bc_acc_name.argtypes = (ctypes.c_int32,)
        lib.bc_const_count.restype = ctypes.c_int32
        lib.bc_const_get.restype = ctypes.POINTER(_ConstDesc)
        lib.bc_const_get.argtypes = (ctypes.c_int32,)
        lib.bc_ctrl_count.restype = ctypes.c_int32
        lib.bc_ctrl_get.restype = ctypes.POINTER(_CtrlInfo)
        lib.bc_ctrl_get.argtypes = (ctypes.c_int32,)
        lib.bc_version.restype = ctypes.c_char_p
        lib.bc_sim_init.restype = ctypes.c_int
        lib.bc_sim_init.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                    ctypes.c_void_p, ctypes.c_double)
        lib.bc_sim_set_thermal.restype = ctypes.c_int
        lib.bc_sim_set_thermal.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                           ctypes.c_double)
        lib.bc_sim_set_temperatures.restype = ctypes.c_int
        lib.bc_sim_set_temperatures.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_double)
        lib.bc_derate_init.restype = ctypes.c_int
        lib.bc_derate_init.argtypes = (ctypes.c_void_p, ctypes.c_void_p)
        lib.bc_derate_step.restype = ctypes.c_float
        lib.bc_derate_step.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
        lib.bc_derate_r_to_temp.restype = ctypes.c_int
        lib.bc_derate_r_to_temp.argtypes = (ctypes.c_float, ctypes.c_float, ctypes.c_float, ctypes.c_float,
                                            ctypes.POINTER(ctypes.c_float))
        lib.bc_sim_run.restype = ctypes.c_int
        lib.bc_sim_run.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int64,
                                   ctypes.c_void_p, ctypes.c_int64, ctypes.POINTER(ctypes.c_int64))
        self.version = lib.bc_version().decode()

        self.sizes: dict[str, int] = {}
        for j in range(lib.bc_struct_count()):
            d = lib.bc_struct_get(j).contents
            self.sizes[d.name.decode()] = int(d.size)
        fields: dict[str, list[tuple[str, str, int, int]]] = {}
        for j in range(lib.bc_layout_count()):
            f = lib.bc_layout_get(j).contents
            fields.setdefault(f.strct.decode(), []).append((f.field.decode(), f.type.decode(), int(f.offset),
                                                            int(f.size)))
        self._fields = fields
        self.dtypes: dict[str, np.dtype] = {}
        for name in fields:
            self._dtype(name)

        n = lib.bc_trace_count()
        self.trace_names = tuple(lib.bc_trace_name(j).decode() for j in range(n))
        self.trace_units = tuple(lib.bc_trace_unit(j).decode() for j in range(n))
        self.trace_docs = tuple(lib.bc_trace_doc(j).decode() for j in range(n))
        self.trace_dtype = np.dtype([(nm, np.float64) for nm in self.trace_names])
        if self.trace_dtype.itemsize != self.sizes["bc_trace_row"]:
            raise ImportError("bldclab core: trace row size does not match BC_TRACE_FIELDS")

        self.acc_names = tuple(lib.bc_acc_name(j).decode() for j in range(lib.bc_acc_count()))
        self.constants: dict[str, int] = {}
        self.groups: dict[str, dict[str, int]] = {}
        for j in range(lib.bc_const_count()):
            k = lib.bc_const_get(j).contents
            name = k.name.decode()
            self.constants[name] = int(k.value)
            self.groups.setdefault(k.group.decode(), {})[name] = int(k.value)
        self.controllers: dict[str, Controller] = {}
        for j in range(lib.bc_ctrl_count()):
            c = lib.bc_ctrl_get(j).contents
            diag = tuple((c.diag[k] or b"").decode() for k in range(8))
            self.controllers[c.name.decode()] = Controller(c.name.decode(), c.params.decode(), c.state.decode(),
                                                           int(c.init), int(c.step), diag)

    def _dtype(self, name: str) -> np.dtype:
        if name in self.dtypes:
            return self.dtypes[name]
        names, formats, offsets = [], [], []
        for field, typ, offset, size in self._fields[name]:
            base = np.dtype(_BASE[typ]) if typ in _BASE else self._dtype(typ)
            count, rem = divmod(size, base.itemsize)
            if rem or count < 1:
                raise ImportError(f"bldclab core: member {name}.{field} has size {size}, not a multiple of {typ}")
            names.append(field)
            formats.append(base if count == 1 else (base, (count,)))
            offsets.append(offset)
        dt = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": self.sizes[name]})
        if dt.itemsize != self.sizes[name]:
            raise ImportError(f"bldclab core: {name} layout does not match sizeof")
        self.dtypes[name] = dt
        return dt

    def record(self, name: str) -> np.ndarray:
        """Return a zeroed one-element record of C struct ``name`` (its memory is what C sees)."""
        return np.zeros(1, dtype=self.dtypes[name])

    def filled(self, name: str, **fields: object) -> np.ndarray:
        """Return a one-element record of C struct ``name`` with every member set from ``fields``.

        Parameters
        ----------
        name : str
            C struct name, e.g. ``"bc_sixstep_params"``.
        **fields
            One value per member the library lists (arrays for array members, a record for a nested struct).

        Raises
        ------
        BldclabError
            Naming the struct and every member left unset and every name that is not a member: a member added
            in C and not filled here fails instead of being passed as zero.
        """
        dt = self.dtypes[name]
        members = dt.names or ()
        missing = [m for m in members if m not in fields]
        unknown = sorted(set(fields) - set(members))
        if missing or unknown:
            parts = ([f"members left unset: {', '.join(missing)}"] if missing else []) + (
                [f"not members: {', '.join(unknown)}"] if unknown else [])
            raise BldclabError(f"core.{name}", "; ".join(parts))
        rec = np.zeros(1, dtype=dt)
        for m in members:
            rec[m] = fields[m]
        return rec

    def const(self, name: str) -> int:
        """Return the value of the C constant ``name`` (e.g. ``"BC_FLAG_SAFE"``), read from the library."""
        try:
            return self.constants[name]
        except KeyError:
            raise KeyError(f"bldclab core: no constant {name!r} in the library's table") from None

    def decode_flags(self, value: int) -> str:
        """Return the controller flags in ``value`` as names, e.g. ``"SAFE|OVERCURRENT"`` ("" for none).

        Bits the library does not name are shown in hex (``"0x40"``).
        """
        v = int(value)
        names = []
        for name, bit in sorted(self.groups["flag"].items(), key=lambda kv: kv[1]):
            if v & bit:
                names.append(name.removeprefix("BC_FLAG_"))
                v &= ~bit
        if v:
            names.append(hex(v))
        return "|".join(names)

    def opaque(self, name: str) -> np.ndarray:
        """Return zeroed, 8-byte aligned memory of ``sizeof(name)`` bytes for a struct the host does not read."""
        n = (self.sizes[name] + 7) // 8
        return np.zeros(n, dtype=np.float64)

    def view(self, buf: np.ndarray, name: str) -> np.ndarray:
        """Return a record view of struct ``name`` at the start of ``buf``."""
        return np.frombuffer(buf, dtype=self.dtypes[name], count=1)

    def controller_init(self, ctrl: Controller, params: np.ndarray, state: np.ndarray) -> int:
        """Call a controller's C init; returns its error code (0 = OK)."""
        fn = _INIT(ctrl.init_ptr)
        return int(fn(params.ctypes.data, state.ctypes.data))

    def controller_step(self, ctrl: Controller, params: np.ndarray, state: np.ndarray, inp: np.ndarray,
                        out: np.ndarray) -> None:
        """Call a controller's C step once (for tests of the C code from Python)."""
        fn = _STEP(ctrl.step_ptr)
        fn(params.ctypes.data, state.ctypes.data, inp.ctypes.data, out.ctypes.data)


def decode_flags(value: int) -> str:
    """Return the controller flags in ``value`` as names, e.g. ``"SAFE|OVERCURRENT"`` (:meth:`Core.decode_flags`)."""
    return core().decode_flags(value)


def flag(name: str) -> int:
    """Return the bit of controller flag ``name`` (``"SAFE"``, ``"SATURATED"``, ...; ``BC_FLAG_<name>`` in C).

    Raises
    ------
    KeyError
        For a name the library's table does not have.
    """
    return core().const("BC_FLAG_" + name.upper())


def __getattr__(name: str) -> int:
    """Return a C constant as a module attribute (``_core.BC_FLAG_SAFE``), read from the library on first use."""
    if name.startswith("BC_"):
        try:
            return core().constants[name]
        except KeyError:
            pass
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@cache
def core() -> Core:
    """Return the loaded core (loaded once per process)."""
    c = Core(_library_path())
    if c.version != __version__:
        raise ImportError(f"bldclab core library is version {c.version}, the package {__version__}: reinstall")
    return c

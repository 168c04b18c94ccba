"""Your own controller in the loop: a C control step built from your files, or a Python class (docs/user-controller.md).

A **C controller** is the contract of ``bc_types.h`` over your own structs, described once with ``bc_user.h``'s
``BC_USER_CONTROLLER`` (the parameter members by name, type, offset and size, as the compiler gives them) and built
by :func:`build` (``bldclab controller build my.c``) into a shared library. :class:`UserControl` loads it, fills the
parameters by name (every member set, none unknown) and runs the step through the core's guard
(``bc_userguard.h``): every output is checked against the contract at every sample and the run ends at the first
violation with a :class:`~bldclab.errors.ControllerError` naming the controller and the sample. By default the run
happens in a child process watched by this one (POSIX ``fork``), so a crash or a hang in user code ends the child,
not the caller: the same error, no result.

A **Python controller** (:class:`PythonControl`) is a class with ``init(drive)`` and ``step(inputs) -> legs``, called
once per sample from the C runner through the same guard: the same inputs (``bc_ctrl_in``, as a ``ctypes`` struct
with the C member names) and outputs as the C contract, so a law prototyped in Python moves to C by translation.
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import math
import mmap
import os
import pickle
import re
import select
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from .._core import Core, CParams, _ConstDesc, _FieldDesc, _StructDesc, core
from .._version import __version__
from ..errors import BldclabError, ControllerError, PlausibilityWarning
from ..model.motor import Drive
from .base import Control, CSlot

__all__ = ["WARNINGS", "PythonControl", "UserControl", "build", "core_dir", "describe_header", "describe_library"]

#: The core's warnings, errors here too (core/Makefile's WARN): what ``bldclab controller build`` compiles with
WARNINGS = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wdouble-promotion", "-Werror")
_OPT = ("-O3", "-fPIC")  # as the package's core (setup.py, tools/build_core.sh): the same floating-point results

_NUM = {"f8": np.float64, "f4": np.float32, "i4": np.int32, "u4": np.uint32, "i8": np.int64, "u8": np.uint64,
        "i2": np.int16, "u2": np.uint16, "i1": np.int8, "u1": np.uint8, "ptr": np.uintp}
_CTYPES = {"f8": ctypes.c_double, "f4": ctypes.c_float, "i4": ctypes.c_int32, "u4": ctypes.c_uint32,
           "i8": ctypes.c_int64, "u8": ctypes.c_uint64, "ptr": ctypes.c_void_p}
_SIGNALS = {int(getattr(signal, n)): n for n in ("SIGSEGV", "SIGBUS", "SIGFPE", "SIGILL", "SIGABRT", "SIGKILL")
            if hasattr(signal, n)}
_SLOTS = ("params", "state", "inputs (bc_ctrl_in)", "outputs (bc_ctrl_out)")


# ------------------------------------------------------------------------------------------------------------------
# building


def core_dir() -> Path:
    """Return the directory of bldclab's C sources (``core/``: the headers and the controller blocks to link).

    ``$BLDCLAB_CORE`` if set, else the copy installed with the package (``bldclab/_csrc``, written by the wheel's
    build), else the ``core/`` of the repository this package runs from (an editable install).

    Raises
    ------
    BldclabError
        If neither holds ``ctrl/include/bldc/bc_types.h``.
    """
    env = os.environ.get("BLDCLAB_CORE")
    if env:
        where = Path(env)
    else:
        here = Path(__file__).resolve()
        installed = here.parents[1] / "_csrc"
        where = installed if (installed / "ctrl" / "include" / "bldc" / "bc_types.h").is_file() else \
            here.parents[3] / "core"
    if not (where / "ctrl" / "include" / "bldc" / "bc_types.h").is_file():
        raise BldclabError("BLDCLAB_CORE", f"bldclab's C sources are not at {where}: set BLDCLAB_CORE to the core/ "
                           "directory of a bldclab checkout (the headers and controller blocks the build links)")
    return where


def build(sources: Sequence[str | Path], output: str | Path | None = None, include: Iterable[str | Path] = (),
          defines: Iterable[str] = (), cc: str | None = None, params_header: str | Path | None = None,
          diag: Sequence[str] = (), ref: str = "") -> Path:
    """Compile a user controller into a shared library, with the core's warnings as errors.

    The user's files are compiled with bldclab's controller blocks (``core/ctrl/src/*.c``: ``bc_hall``, ``bc_pi``,
    ``bc_guard``, ...), the headers of ``core/ctrl/include`` and ``core/host/include`` (``bldc/bc_user.h``), the
    flags of :data:`WARNINGS` and the core's optimisation (``-O3``, no fast-math: the same floating-point results
    as the built-in controllers). The library appears at ``output`` only when the build succeeded.

    Parameters
    ----------
    sources : sequence of path
        The user's ``.c`` files (one of them uses ``BC_USER_CONTROLLER``).
    output : path, optional
        The library (default: the first source with the suffix ``.so``).
    include : iterable of path
        More include directories (``-I``).
    defines : iterable of str
        Macros (``-D``), ``NAME`` or ``NAME=VALUE``.
    cc : str, optional
        The C compiler (default ``$CC``, else ``cc``).
    params_header : path, optional
        A header declaring ``X_params``, ``X_state``, ``X_init`` and ``X_step``: the description is generated from
        it (:func:`describe_header`), so the sources need no ``BC_USER_CONTROLLER``.
    diag : sequence of str
        With ``params_header``: the diagnostics' names ("name" or "name unit").
    ref : str
        With ``params_header``: what ``in->ref`` means.

    Returns
    -------
    Path
        The library.

    Raises
    ------
    BldclabError
        For a missing source, a missing compiler, the compiler's errors (its messages in the problem), or a library
        that lacks the description (``BC_USER_CONTROLLER``); nothing is written then.
    """
    if not sources:
        raise BldclabError("sources", "give at least one .c file")
    srcs = [Path(s) for s in sources]
    for s in srcs:
        if not s.is_file():
            raise BldclabError("sources", f"no such file: {s}")
    out = Path(output) if output is not None else srcs[0].with_suffix(".so")
    if not out.parent.resolve().is_dir():
        raise BldclabError("output", f"the directory of {out} does not exist")
    if out.is_dir():
        raise BldclabError("output", f"{out} is a directory: name the library file")
    root = core_dir()
    blocks = sorted((root / "ctrl" / "src").glob("*.c"))
    compiler = cc or os.environ.get("CC") or "cc"
    gen: list[str] = []
    extra_inc: list[str] = []
    if params_header is not None:
        _x, text = describe_header(params_header, diag=diag, ref=ref)
        fd, name = tempfile.mkstemp(prefix="bldclab-desc-", suffix=".c")
        with os.fdopen(fd, "w") as f:
            f.write(text)
        gen.append(name)
        extra_inc.append(str(Path(params_header).resolve().parent))
    fd, tmp = tempfile.mkstemp(prefix=".bldclab-", suffix=".so", dir=out.parent if str(out.parent) else ".")
    os.close(fd)
    cmd = [compiler, *WARNINGS, *_OPT, "-shared", f'-DBC_USER_BUILT_BY="bldclab {__version__}"',
           *(f"-D{d}" for d in defines), *(f"-I{i}" for i in (*include, *extra_inc)),
           f"-I{root / 'ctrl' / 'include'}", f"-I{root / 'host' / 'include'}",
           *map(str, srcs), *gen, *map(str, blocks), "-lm", "-o", tmp]
    try:
        try:
            done = subprocess.run(cmd, capture_output=True, text=True, check=False)
        except OSError as exc:
            raise BldclabError("cc", f"cannot run the C compiler {compiler!r}: {exc}") from None
        if done.returncode != 0:
            msg = (done.stderr or done.stdout).strip()
            raise BldclabError("sources", f"the build failed ({compiler}, the core's warnings as errors):\n{msg}")
        try:  # a library bldclab cannot run is no result: it is not written
            describe_library(tmp)
        except BldclabError as exc:
            raise BldclabError("sources", f"built, but not usable: {exc.problem}") from None
        os.replace(tmp, out)
    finally:
        for name in (tmp, *gen):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(name)
    return out


# C type names of a header's struct members -> the description's type codes (bc_bind.h)
_C_TYPES = {"float": "f4", "double": "f8", "int32_t": "i4", "int": "i4", "signed": "i4", "signed int": "i4",
            "uint32_t": "u4", "unsigned": "u4", "unsigned int": "u4", "int16_t": "i2", "short": "i2",
            "short int": "i2", "uint16_t": "u2", "unsigned short": "u2", "unsigned short int": "u2", "int8_t": "i1",
            "signed char": "i1", "uint8_t": "u1", "unsigned char": "u1", "_Bool": "u1", "bool": "u1",
            "int64_t": "i8", "long long": "i8", "long long int": "i8", "uint64_t": "u8",
            "unsigned long long": "u8", "unsigned long long int": "u8"}


def _structs_of(text: str) -> dict[str, list[tuple[str, str, int | None]]]:
    """Return the ``typedef struct {...} NAME;`` of a C header: members (C type, name, -1 for an array or None)."""
    code = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    code = re.sub(r"//[^\n]*", " ", code)
    code = re.sub(r"^\s*#.*$", " ", code, flags=re.M)
    out: dict[str, list[tuple[str, str, int | None]]] = {}
    for body, name in re.findall(r"typedef\s+struct\s*\w*\s*\{([^{}]*)\}\s*(\w+)\s*;", code):
        members: list[tuple[str, str, int | None]] = []
        for decl in body.split(";"):
            decl = " ".join(decl.replace("const ", " ").replace("volatile ", " ").split())
            if not decl:
                continue
            m = re.fullmatch(r"((?:\w+\s+)*?\w+)\s+(\w+(?:\s*\[\s*\w+\s*\])*(?:\s*,\s*\w+(?:\s*\[\s*\w+\s*\])*)*)",
                             decl)
            if m is None:
                raise BldclabError(f"--params-header ({name})", f"cannot read the member declaration {decl!r}: "
                                   "write the description yourself (BC_USER_CONTROLLER, docs/user-controller.md)")
            ctype = m.group(1)
            for item in m.group(2).split(","):
                dims = re.findall(r"\[\s*(\w+)\s*\]", item)
                member = item.split("[")[0].strip()
                if len(dims) > 1:
                    raise BldclabError(f"--params-header ({name}.{member})", "arrays of more than one dimension are "
                                       "not read: write the description yourself (BC_USER_CONTROLLER)")
                members.append((ctype, member, None if not dims else -1))
        out[name] = members
    return out


def describe_header(header: str | Path, *, diag: Sequence[str] = (), ref: str = "") -> tuple[str, str]:
    """Return the prefix and the C source of a description generated from a header (``--params-header``).

    The header declares ``X_params`` and ``X_state`` (``typedef struct {...} X_params;``) and the functions
    ``X_init`` and ``X_step`` of the contract; the generated file includes it, describes every member of
    ``X_params`` (numbers, one-dimensional arrays, and structs the header defines or bldclab describes), checks each
    member's type at compile time (a pointer of the described type to it: a mismatch is an error) and exports
    ``BC_USER_CONTROLLER`` with the name ``X``.

    Raises
    ------
    BldclabError
        For a header without exactly one ``*_params`` struct, without ``X_state``, ``X_init`` or ``X_step``, or with a
        member it cannot read (then write the description by hand).
    """
    path = Path(header)
    if not path.is_file():
        raise BldclabError("--params-header", f"no such file: {header}")
    text = path.read_text()
    structs = _structs_of(text)
    prefixes = [n.removesuffix("_params") for n in structs if n.endswith("_params")]
    if len(prefixes) != 1:
        raise BldclabError("--params-header", f"{header} must define one 'typedef struct {{...}} X_params;', found "
                           f"{len(prefixes)} ({', '.join(p + '_params' for p in prefixes) or 'none'})")
    x = prefixes[0]
    code = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    missing = [] if f"{x}_state" in structs or re.search(rf"\b{x}_state\s*;", code) else [f"{x}_state"]
    missing += [f for f in (f"{x}_init", f"{x}_step") if not re.search(rf"\b{f}\s*\(", code)]
    if missing:
        raise BldclabError("--params-header", f"{header} declares {x}_params but not {', '.join(missing)} (the "
                           f"contract: int {x}_init(const {x}_params *, {x}_state *); void {x}_step(const "
                           f"{x}_params *, {x}_state *, const bc_ctrl_in *, bc_ctrl_out *))")
    fields: list[str] = []
    checks: list[str] = []
    nested: list[str] = []

    def walk(sname: str, var: str) -> None:
        for ctype, member, dims in structs[sname]:
            code_ = _C_TYPES.get(ctype)
            typ = code_ if code_ is not None else ctype
            if code_ is None and ctype in structs:
                if ctype not in nested:
                    nested.append(ctype)
                    walk(ctype, f"s_{ctype}")
            elif code_ is None and not re.fullmatch(r"bc_\w+", ctype):
                raise BldclabError(f"--params-header ({sname}.{member})", f"type {ctype!r} is not a number type "
                                   f"({', '.join(sorted(set(_C_TYPES)))}), nor a struct of the header or of bldclab")
            fields.append(f'    BC_BIND_FIELD({sname}, {member}, "{typ}"),')
            ref_ = f"{var}->{member}" if dims is not None else f"&{var}->{member}"
            checks.append(f"    {{ {ctype} *c = {ref_}; (void)c; }}")

    checks.append(f"    /* {x}_params */")
    walk(f"{x}_params", "p")
    args = ", ".join([f"{x}_params *p"] + [f"{n} *s_{n}" for n in nested])
    diag_items = ", ".join('"' + d.replace('"', "") + '"' for d in list(diag)[:8])
    src = f"""/* generated by bldclab from {path.name} (bldclab controller build --params-header): the description of
 * {x}_params for bc_user.h. Do not edit: build again. */
#include "{path.name}"
#include "bldc/bc_user.h"

static const bc_field_desc BC_GEN_FIELDS[] = {{
{chr(10).join(fields)}
}};
static const bc_struct_desc BC_GEN_STRUCTS[] = {{
    {{"{x}_params", (uint32_t)sizeof({x}_params)}},
{chr(10).join(f'    {{"{n}", (uint32_t)sizeof({n})}},' for n in nested)}
}};
static const bc_user_desc BC_GEN_DESC = {{
    .name = "{x}",
    .fields = BC_GEN_FIELDS,
    .n_fields = BC_USER_COUNT(BC_GEN_FIELDS),
    .structs = BC_GEN_STRUCTS,
    .n_structs = BC_USER_COUNT(BC_GEN_STRUCTS),
    .diag = {{{diag_items or '""'}}},
    .ref = "{ref.replace('"', '')}",
}};

/* each member's type as described: a mismatch is a compile error (-Werror) */
void bc_gen_typecheck({args});
void bc_gen_typecheck({args})
{{
{chr(10).join(checks)}
}}

BC_USER_CONTROLLER(BC_GEN_DESC, {x}_params, {x}_state, {x}_init, {x}_step);
"""
    return x, src


# ------------------------------------------------------------------------------------------------------------------
# loading a library and reading its description


def _string(ptr: int) -> str:
    return ctypes.string_at(ptr).decode() if ptr else ""


def _read(c: Core, name: str, address: int) -> np.void:
    size = c.sizes[name]
    raw = memoryview((ctypes.c_char * size).from_address(address)).cast("B")
    return np.frombuffer(raw, dtype=c.dtypes[name], count=1)[0]


@dataclass(eq=False)
class _Library:
    """A loaded user library and its description."""

    path: str
    sha: str
    handle: ctypes.CDLL
    name: str
    params: str
    state: str
    params_size: int
    state_size: int
    init_ptr: int
    step_ptr: int
    dtype: np.dtype
    leaves: dict[str, tuple[tuple[str, ...], np.dtype, tuple[int, ...]]]
    consts: dict[str, int]
    defaults: bytes | None
    diag: tuple[str, ...]
    units: tuple[str, ...]
    ref: str
    bemf: bool
    built_by: str


_LIBS: dict[str, _Library] = {}


def _cache_dir() -> Path:
    d = Path(tempfile.gettempdir()) / f"bldclab-user-{os.getuid() if hasattr(os, 'getuid') else 0}"
    d.mkdir(mode=0o700, exist_ok=True)
    return d


def _leaves(dt: np.dtype, prefix: tuple[str, ...] = ()) -> Iterable[tuple[tuple[str, ...], np.dtype, tuple[int, ...]]]:
    for name in dt.names or ():
        sub = dt.fields[name][0] if dt.fields else dt
        base, shape = (sub.subdtype if sub.subdtype is not None else (sub, ()))
        if base.names and not shape:
            yield from _leaves(base, (*prefix, name))
        else:
            yield (*prefix, name), base, tuple(shape)


def describe_library(path: str | Path) -> _Library:
    """Load a user controller library and read its description (``bc_user_controller``, ``bc_user.h``).

    The library is loaded from a private copy named by its content's SHA-256, so a library rebuilt at the same
    path is loaded again rather than served from the first load.

    Raises
    ------
    BldclabError
        Field ``control.library``: no such file, not a loadable library, no ``bc_user_controller`` symbol (not
        built with ``BC_USER_CONTROLLER``), built against another contract (``BC_USER_ABI``, the size of
        ``bc_ctrl_in`` or ``bc_ctrl_out``, ``BC_DIAG_N``), or a description that does not cover its params struct.
    """
    p = Path(path)
    if not p.is_file():
        raise BldclabError("control.library", f"no such file: {path}")
    data = p.read_bytes()
    sha = hashlib.sha256(data).hexdigest()
    if sha in _LIBS:
        return _LIBS[sha]
    copy = _cache_dir() / f"{sha[:32]}{p.suffix or '.so'}"
    if not copy.is_file():
        fd, tmp = tempfile.mkstemp(dir=copy.parent)
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, copy)
    where = f"control.library ({path})"
    try:
        handle = ctypes.CDLL(str(copy))
    except OSError as exc:
        raise BldclabError(where, f"cannot be loaded as a shared library: {exc}") from None
    try:
        address = ctypes.addressof(ctypes.c_char.in_dll(handle, "bc_user_controller"))
    except ValueError:
        raise BldclabError(where, "missing symbol bc_user_controller: the library was not built with "
                           "BC_USER_CONTROLLER (bldc/bc_user.h); see docs/user-controller.md") from None
    c = core()
    e = _read(c, "bc_user_entry", address)
    got = {"BC_USER_ABI": int(e["abi"]), "sizeof(bc_ctrl_in)": int(e["size_in"]),
           "sizeof(bc_ctrl_out)": int(e["size_out"]), "BC_DIAG_N": int(e["diag_n"])}
    want = {"BC_USER_ABI": c.const("BC_USER_ABI"), "sizeof(bc_ctrl_in)": c.sizes["bc_ctrl_in"],
            "sizeof(bc_ctrl_out)": c.sizes["bc_ctrl_out"], "BC_DIAG_N": 8}
    bad = [f"{k} {got[k]} (this bldclab: {want[k]})" for k in got if got[k] != want[k]]
    if bad:
        raise BldclabError(where, f"built against another controller contract: wrong struct size or version, "
                           f"{'; '.join(bad)}: rebuild it with 'bldclab controller build'")
    if not e["desc"] or not e["init"] or not e["step"]:
        raise BldclabError(where, "bc_user_controller lacks its description, init or step")
    d = _read(c, "bc_user_desc", int(e["desc"]))
    params, state = _string(int(e["params"])), _string(int(e["state"]))
    sizes = {params: int(e["params_size"]), state: int(e["state_size"])}
    fields: dict[str, list[tuple[str, str, int, int]]] = {}
    n_f = int(d["n_fields"])
    if n_f < 0 or (n_f and not d["fields"]):
        raise BldclabError(where, f"its description lists {n_f} fields without a table")
    table: Iterable[_FieldDesc] = (_FieldDesc * n_f).from_address(int(d["fields"])) if n_f else []
    for fd_ in table:
        fields.setdefault(fd_.strct.decode(), []).append((fd_.field.decode(), fd_.type.decode(), int(fd_.offset),
                                                          int(fd_.size)))
    n_s = int(d["n_structs"])
    for s in (_StructDesc * n_s).from_address(int(d["structs"])) if n_s > 0 and d["structs"] else []:
        sizes[s.name.decode()] = int(s.size)
    consts: dict[str, int] = {}
    n_k = int(d["n_consts"])
    for k in (_ConstDesc * n_k).from_address(int(d["consts"])) if n_k > 0 and d["consts"] else []:
        consts[k.name.decode()] = int(k.value)
    if params not in fields and sizes[params] > 0:
        raise BldclabError(where, f"its description has no fields of {params} (BC_BIND_FIELD({params}, ...) for "
                           "every member)")
    dtypes: dict[str, np.dtype] = {}

    def dtype_of(name: str) -> np.dtype:
        if name in dtypes:
            return dtypes[name]
        if name not in fields:
            if name in c.dtypes:
                return c.dtypes[name]
            raise BldclabError(where, f"member type {name!r} is neither a number type ({', '.join(_NUM)}) nor a "
                               "struct the description or bldclab describes")
        if name not in sizes:
            raise BldclabError(where, f"struct {name} is described without its size (bc_user_desc.structs)")
        names, formats, offsets, end = [], [], [], 0
        for member, typ, offset, size in sorted(fields[name], key=lambda m: m[2]):
            base = np.dtype(_NUM[typ]) if typ in _NUM else dtype_of(typ)
            count, rem = divmod(size, base.itemsize)
            if rem or count < 1:
                raise BldclabError(where, f"{name}.{member} has {size} bytes, not a whole number of {typ}")
            if offset - end >= 8:
                raise BldclabError(where, f"{name}: bytes {end}..{offset - 1} are no described member (every member "
                                   "needs its BC_BIND_FIELD)")
            names.append(member)
            formats.append(base if count == 1 else (base, (count,)))
            offsets.append(offset)
            end = offset + size
        if end > sizes[name] or sizes[name] - end >= 8:
            raise BldclabError(where, f"{name}: {end} of its {sizes[name]} bytes described (every member needs its "
                               "BC_BIND_FIELD)")
        dt = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": sizes[name]})
        dtypes[name] = dt
        return dt

    dt = dtype_of(params) if params in fields else np.dtype({"names": [], "formats": [], "itemsize": 0})
    leaves = {".".join(path): (path, base, shape) for path, base, shape in _leaves(dt)}
    diag, units = [], []
    for j in range(8):
        text = _string(int(d["diag"][j]))
        label, _, unit = text.partition(" ")
        diag.append(label)
        units.append(unit.strip())
    defaults = ctypes.string_at(int(d["defaults"]), sizes[params]) if d["defaults"] and sizes[params] else None
    lib = _Library(str(path), sha, handle, _string(int(d["name"])) or p.stem, params, state, sizes[params],
                   sizes[state], int(e["init"]), int(e["step"]), dt, leaves, consts, defaults, tuple(diag),
                   tuple(units), _string(int(d["ref"])), bool(int(d["bemf_sensing"])), _string(int(e["built_by"])))
    _LIBS[sha] = lib
    return lib


def _flatten(params: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in params.items():
        if isinstance(v, Mapping):
            out.update(_flatten(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def _value(lib: _Library, name: str, v: Any, base: np.dtype, shape: tuple[int, ...]) -> np.ndarray:
    """One parameter member's value as an array of its C type (checked)."""
    where = f"control.params.{name}"
    c = core()

    def one(x: Any) -> Any:
        if isinstance(x, str):
            s = x.strip()
            if s in lib.consts:
                return lib.consts[s]
            if s in c.constants:
                return c.constants[s]
            try:
                return int(s) if base.kind in "iu" else float(s)
            except ValueError:
                raise BldclabError(where, f"{x!r} is neither a number nor a named constant of {lib.name} "
                                   f"({', '.join(sorted(lib.consts)) or 'it names none'}) or bldclab") from None
        if isinstance(x, bool):
            return int(x)
        if not isinstance(x, int | float | np.integer | np.floating):
            raise BldclabError(where, f"expected a number, got {x!r}")
        return x

    arr = np.asarray([one(x) for x in v] if isinstance(v, list | tuple | np.ndarray) else one(v), dtype=float)
    if arr.shape != shape:
        want = "one number" if not shape else f"{shape[0]} numbers" if len(shape) == 1 else f"an array {shape}"
        raise BldclabError(where, f"expected {want} (member of C type {base.name}), got {v!r}")
    if np.isnan(arr).any():
        raise BldclabError(where, f"must not be NaN, got {v!r}")
    if base.kind in "iu":
        info = np.iinfo(base)
        if not (np.all(arr == np.round(arr)) and np.all(arr >= info.min) and np.all(arr <= info.max)):
            raise BldclabError(where, f"must be a whole number in [{info.min}, {info.max}] ({base.name}), got {v!r}")
    return arr.astype(base)


def _fill(lib: _Library, params: Mapping[str, Any]) -> np.ndarray:
    given = _flatten(params)
    unknown = sorted(set(given) - set(lib.leaves))
    rec = np.zeros(1, dtype=lib.dtype)
    if lib.defaults is not None:
        rec = np.frombuffer(bytearray(lib.defaults), dtype=lib.dtype, count=1).copy()
    missing = [] if lib.defaults is not None else [k for k in lib.leaves if k not in given]
    where = f"control.params ({lib.name}: {lib.params})"
    if unknown or missing:
        parts = ([f"not members: {', '.join(unknown)} (members: {', '.join(lib.leaves)})"] if unknown else []) + (
            [f"members left unset: {', '.join(missing)}"] if missing else [])
        raise BldclabError(where, "; ".join(parts))
    for key, v in given.items():
        path, base, shape = lib.leaves[key]
        view = rec[path[0]]
        for part in path[1:]:
            view = view[part]
        view[...] = _value(lib, key, v, base, shape)
    return rec


# ------------------------------------------------------------------------------------------------------------------
# the guarded slot


class _Buffers:
    """Memory for the guard's copies of params, state, in and out.

    Plain, or (``fenced``, in a child process) each ending against a page the process may not touch: a read or
    write past its end faults.
    """

    def __init__(self, sizes: Sequence[int], fenced: bool) -> None:
        self.addr: list[int] = []
        self._keep: list[object] = []
        page = int(core().lib.bc_user_page()) if fenced else 0
        for size in sizes:
            if page:
                room = ((size + 15) // 16) * 16
                pages = (room + page - 1) // page + 1
                mem = mmap.mmap(-1, pages * page)
                base = ctypes.addressof(ctypes.c_char.from_buffer(mem))
                self._keep.append(mem)
                fence = base + (pages - 1) * page
                if core().lib.bc_user_protect(ctypes.c_void_p(fence), page, 0) != 0:
                    raise OSError("mprotect failed")
                self.addr.append(fence - room)
            else:
                buf = np.zeros(max(1, (size + 7) // 8), dtype=np.float64)
                self._keep.append(buf)
                self.addr.append(int(buf.ctypes.data))


class GuardedSlot(CSlot):
    """A controller slot running through the core's guard (``bc_user_run``).

    :meth:`run` raises :class:`ControllerError` at the first bad sample.
    """

    def __init__(self, guard: np.ndarray, watch: np.ndarray, label: str, t_half: float, record: CParams,
                 diag: tuple[str, ...], units: tuple[str, ...], keep: Iterable[object],
                 failure: Callable[[], BaseException | None] = lambda: None) -> None:
        c = core()
        step = ctypes.cast(c.lib.bc_user_step, ctypes.c_void_p).value or 0
        super().__init__(step, 0, int(guard.ctypes.data), record, diag, units, (guard, watch, *keep))
        self.guard, self.watch, self.label, self.t_half = guard, watch, label, t_half
        self.failure = failure

    def run(self, core: Core, cfg: np.ndarray, state: np.ndarray, inputs: np.ndarray, n: int, rows: Any,
            cap: int, written: Any) -> int:
        """Run ``n`` samples through the guard; raise :class:`ControllerError` if it ended the run."""
        rc = int(core.lib.bc_user_run(ctypes.c_void_p(cfg.ctypes.data), ctypes.c_void_p(state.ctypes.data),
                                      ctypes.c_void_p(inputs.ctypes.data), ctypes.c_int64(n), ctypes.c_void_p(rows),
                                      ctypes.c_int64(cap), ctypes.byref(written),
                                      ctypes.c_void_p(self.guard.ctypes.data)))
        if rc == core.const("BC_USER_STOPPED"):
            cause = self.failure()
            raise fault_error(self.label, self.watch[0], self.t_half) from cause
        return rc


def _member_at(name: str, offset: int) -> str:
    dt = core().dtypes[name]
    for m in dt.names or ():
        sub, at = dt.fields[m][:2]  # type: ignore[index]  # fields: None only for a dtype without names
        if at <= offset < at + sub.itemsize:
            return m
    return f"byte {offset}"


def _at_sample(k: int, t_half: float) -> str:
    return "in its init" if k < 0 else f"at sample {k} (t = {k * t_half * 1e3:.6g} ms)"


def fault_error(label: str, w: np.void, t_half: float) -> ControllerError:
    """Return the error a guard's watch record describes (``bc_userguard.h``)."""
    c = core()
    k = int(w["k"])
    where = f"control ({label})"
    fault = int(w["fault"])
    if fault == c.const("BC_USER_FAULT_OUTPUT"):
        at = {v: n.removeprefix("BC_USER_AT_") for n, v in c.groups["user_at"].items()}.get(int(w["where"]), "?")
        j, value = int(w["index"]), float(w["value"])
        what = {"MODE": f"leg[{j}].mode", "DUTY": f"leg[{j}].duty", "HAS_AT": "has_at", "T_AT": "t_at",
                "MODE_AT": f"leg_at[{j}].mode", "DUTY_AT": f"leg_at[{j}].duty", "DIAG": f"diag[{j}]",
                "HOLD": "i_hold_at" if j else "i_hold"}.get(at, at)
        modes = "a leg mode must be OFF, PWM, HIGH or LOW"
        duty = "a duty must be in [0, 1]"
        rule = {"MODE": modes, "MODE_AT": modes, "DUTY": duty, "DUTY_AT": duty,
                "HAS_AT": "has_at must be 0 or 1", "T_AT": "t_at must be finite and >= 0"}.get(at, "must be finite")
        return ControllerError(where, f"wrote {what} = {value:g} {_at_sample(k, t_half)}: {rule}")
    if fault == c.const("BC_USER_FAULT_INPUT"):
        member = _member_at("bc_ctrl_in", int(w["index"]))
        return ControllerError(where, f"wrote to its const inputs (bc_ctrl_in.{member}) {_at_sample(k, t_half)}")
    if fault == c.const("BC_USER_FAULT_STOP"):
        return ControllerError(where, f"raised an exception {_at_sample(k, t_half)} (the cause below)")
    if fault == c.const("BC_USER_FAULT_SIGNAL"):
        signo, addr = int(w["signo"]), int(w["addr"])
        beyond = ""
        page = int(c.lib.bc_user_page()) or 4096
        for j, name in enumerate(_SLOTS):
            start, size = int(w["at"][j]), int(w["size"][j])
            if start and start + size <= addr < start + size + page + 16:
                beyond = f", beyond the end of its {name}"
            elif start and start <= addr < start + size:
                beyond = f", inside its {name}"
        return ControllerError(where, f"crashed with {_SIGNALS.get(signo, f'signal {signo}')} (address {addr:#x}"
                               f"{beyond}) {_at_sample(k, t_half)}")
    return ControllerError(where, f"failed {_at_sample(k, t_half)}")


def _guard(c: Core, init: int, step: int, sizes: Sequence[int], watch: np.ndarray | None,
           fenced: bool) -> tuple[np.ndarray, np.ndarray, _Buffers]:
    """Return the guard record over fresh buffers (params, state, in, out); the watch is the given one or a new one."""
    w = watch if watch is not None else c.record("bc_user_watch")
    bufs = _Buffers(sizes, fenced)
    g = c.record("bc_user_guard")
    g["init"], g["step"] = init, step
    g["params"], g["state"], g["in"], g["out"] = bufs.addr
    g["watch"] = w.ctypes.data
    if fenced:
        w["at"][0] = bufs.addr
        w["size"][0] = list(sizes)
    return g, w, bufs


# ------------------------------------------------------------------------------------------------------------------
# the C user controller


def _elsewhere(path: Path, sha: str) -> Path | None:
    """Return a file with the content ``sha`` where ``path`` is missing.

    This machine's private copy of it (loaded before), or a Dask worker's uploaded file of the same name
    (``client.upload_file("my.so", load=False)``).
    """
    copy = _cache_dir() / f"{sha[:32]}{path.suffix or '.so'}"
    found = [copy]
    dist = sys.modules.get("distributed")
    if dist is not None:
        with contextlib.suppress(Exception):  # not in a worker
            found.append(Path(dist.get_worker().local_directory) / path.name)
    for f in found:
        if f.is_file() and hashlib.sha256(f.read_bytes()).hexdigest() == sha:
            return f
    return None


@dataclass(frozen=True, eq=False)
class UserControl(Control):
    """A controller from a user's shared library (built by :func:`build`, ``bldclab controller build``).

    The library's parameters are filled by name from ``params``: every member of its params struct (nested
    structs as ``"outer.inner"`` or a nested mapping), numbers or the names of constants the description lists
    (or bldclab's, e.g. ``"BC_CHOP_HIGH"``); a member left unset (unless the description gives defaults) or a name
    that is no member is refused. What ``Scenario.ref`` means is the description's ``ref``.

    Parameters
    ----------
    library : str
        Path of the shared library.
    params : mapping
        The parameter values by member name.
    isolate : bool
        Run in a watched child process (default): a crash or a hang in the controller ends the child, and
        :func:`bldclab.simulate` raises :class:`~bldclab.errors.ControllerError` naming the controller and the
        sample. ``False``: in this process (faster to start, a crash takes the process with it; the output checks
        still apply).
    budget : float
        Step-time budget (s): an isolated controller still inside one call (init or a step) after this long is
        killed and reported as hung.
    sha256 : str
        The library's content hash; default the file's now. Given (a sweep's case rebuilt in a worker), the file
        must still have it: a library rebuilt since is refused rather than run in its place. Where the path does not
        exist, a file of that content is used: the private copy this machine loaded before (a temporary directory,
        by hash), or, on a Dask worker, the file of the same name uploaded with ``client.upload_file(path,
        load=False)``.
    """

    library: str
    params: Mapping[str, Any] = field(default_factory=dict)
    isolate: bool = True
    budget: float = 1.0
    sha256: str = ""
    c_name: ClassVar[str] = "user"

    def __post_init__(self) -> None:
        if not isinstance(self.library, str | Path):
            raise BldclabError("control.library", f"expected a path, got {self.library!r}")
        object.__setattr__(self, "library", str(self.library))
        if not isinstance(self.params, Mapping):
            raise BldclabError("control.params", f"expected a mapping of member names to values, got {self.params!r}")
        object.__setattr__(self, "params", dict(self.params))
        if not isinstance(self.isolate, bool):
            raise BldclabError("control.isolate", f"must be True or False, got {self.isolate!r}")
        if isinstance(self.budget, bool) or not isinstance(self.budget, int | float) or not (
                math.isfinite(self.budget) and self.budget > 0):
            raise BldclabError("control.budget", f"must be a finite number of seconds > 0, got {self.budget!r}")
        source: str | Path = self.library
        sha = str(self.sha256)
        if sha and not Path(self.library).is_file():  # a worker without the file: the same content elsewhere
            lib = _LIBS[sha] if sha in _LIBS else describe_library(_elsewhere(Path(self.library), sha) or source)
        else:
            lib = describe_library(source)
        object.__setattr__(self, "_lib", lib)
        if not self.sha256:
            object.__setattr__(self, "sha256", lib.sha)
        elif self.sha256 != lib.sha:
            raise BldclabError("control.sha256", f"the library at {self.library} has changed (sha256 "
                               f"{lib.sha[:12]}..., "
                               f"not {str(self.sha256)[:12]}...): it was rebuilt after this controller was made")
        _fill(lib, self.params)  # refuse bad parameters now, not in the run

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle as the path and the settings (a worker loads the library again and checks its hash)."""
        return (UserControl, (self.library, dict(self.params), self.isolate, self.budget, self.sha256))

    @property
    def lib(self) -> _Library:
        """The loaded library and its description (the library this controller was made with)."""
        lib: _Library = self.__dict__["_lib"]
        return lib

    @property
    def ref_meaning(self) -> str:  # type: ignore[override]  # a ClassVar of the built-in controllers
        """What ``Scenario.ref`` means, from the library's description."""
        return self.lib.ref

    @property
    def needs_bemf_sensing(self) -> bool:  # type: ignore[override]  # a ClassVar of the built-in controllers
        """Whether the description asks for the back-EMF sensing inputs (``bemf_sensing = 1``)."""
        return self.lib.bemf

    @property
    def isolated(self) -> bool:  # noqa: D102 - Control.isolated
        return self.isolate

    @property
    def label(self) -> str:  # noqa: D102 - Control.label
        return f"{self.lib.name}, {self.library}"

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        return CParams(_fill(self.lib, self.params))

    def c_slot(self, drive: Drive, core: Core, n_samples: int, watch: Any = None) -> CSlot:  # noqa: D102
        lib = self.lib
        cp = self.c_record(drive, core, n_samples)
        sizes = (max(lib.params_size, 1), max(lib.state_size, 1), core.sizes["bc_ctrl_in"], core.sizes["bc_ctrl_out"])
        g, w, bufs = _guard(core, lib.init_ptr, lib.step_ptr, sizes, watch, watch is not None)
        ctypes.memmove(bufs.addr[0], cp.record.ctypes.data, lib.params_size)
        t_half = 0.5 / drive.inverter.f_pwm
        rc = int(core.lib.bc_user_init(ctypes.c_void_p(g.ctypes.data)))
        if rc != 0:
            raise ControllerError(f"control ({self.label})", f"its init returned {rc}: it rejected its parameters "
                                  f"{dict(self.params)}")
        return GuardedSlot(g, w, self.label, t_half, cp, lib.diag, lib.units, (bufs,))

    def describe(self) -> dict[str, object]:  # noqa: D102
        lib = self.lib
        params = {k: (v if isinstance(v, str) else np.asarray(v).tolist()) for k, v in _flatten(self.params).items()}
        return {"controller": "user", "name": lib.name, "library": self.library, "sha256": self.sha256,
                "built_by": lib.built_by, "params": params, "isolate": self.isolate,
                "budget": self.budget}


# ------------------------------------------------------------------------------------------------------------------
# the Python controller


_STRUCTS: dict[str, type[ctypes.Structure]] = {}


def _ctypes_struct(c: Core, name: str) -> type[ctypes.Structure]:
    """Return a ctypes Structure of the core's struct ``name``, built from its description (offsets checked)."""
    if name in _STRUCTS:
        return _STRUCTS[name]
    members = sorted(c._fields[name], key=lambda m: m[2])
    fields: list[tuple[str, Any]] = []
    for member, typ, _offset, size in members:
        base: Any = _CTYPES[typ] if typ in _CTYPES else _ctypes_struct(c, typ)
        count = size // ctypes.sizeof(base)
        fields.append((member, base if count == 1 else base * count))
    cls = type(name, (ctypes.Structure,), {"_fields_": fields})
    if ctypes.sizeof(cls) != c.sizes[name] or any(getattr(cls, m).offset != off for m, _t, off, _s in members):
        raise ImportError(f"bldclab: the ctypes layout of {name} does not match the C library's")
    _STRUCTS[name] = cls
    return cls


_INIT_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p)
_STEP_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)


class PythonControl(Control):
    """A controller written in Python, for prototyping: subclass it and write :meth:`init` and :meth:`step`.

    :func:`bldclab.simulate` calls ``init(drive)`` once, then ``step(inputs)`` once per sample from the C runner,
    through the same guard as a C user controller: ``inputs`` is ``bc_ctrl_in`` (a ``ctypes`` struct with the C
    members: ``inputs.i_abc[0]``, ``inputs.hall``, ``inputs.tick_edge``, ...), ``step`` returns the three legs
    ``((mode, duty), (mode, duty), (mode, duty))`` with the modes :attr:`OFF`, :attr:`PWM`, :attr:`HIGH`,
    :attr:`LOW`, or None after writing ``self.out`` (``bc_ctrl_out``: ``leg``, ``diag``, ``flags``, ``has_at``,
    ...; cleared before every call) itself. A duty outside [0, 1], NaN or an exception ends the run with a
    :class:`~bldclab.errors.ControllerError` naming the sample (the exception as its cause).

    Slow by design: 4 to 9 us per sample for a six-step law (docs/user-controller.md; ``benchmarks/user_control.py``),
    against about 1 us for a whole simulation step with the C translation: prototype in Python, translate to C for
    long runs.

    Attributes
    ----------
    diag : tuple of str
        Meaning of ``out.diag[0..7]`` ("name" or "name unit"; "" unused).
    ref_meaning : str
        What ``Scenario.ref`` means.
    """

    diag: ClassVar[tuple[str, ...]] = ("",) * 8
    c_name: ClassVar[str] = "python"
    OFF: int
    PWM: int
    HIGH: int
    LOW: int
    out: Any

    def init(self, drive: Drive) -> None:
        """Prepare a run (drive: the drive the controller is configured for; the estimate if one is given)."""

    def step(self, inputs: Any) -> Sequence[tuple[int, float]] | None:
        """Return the three legs for the next half period from one sample's measurements."""
        raise NotImplementedError(f"{type(self).__name__} does not implement step")

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        return CParams(np.zeros(1, dtype=np.dtype({"names": [], "formats": [], "itemsize": 8})))

    def c_slot(self, drive: Drive, core: Core, n_samples: int, watch: Any = None) -> CSlot:  # noqa: D102
        for mode in ("OFF", "PWM", "HIGH", "LOW"):
            setattr(self, mode, core.const(f"BC_LEG_{mode}"))
        sizes = (8, 8, core.sizes["bc_ctrl_in"], core.sizes["bc_ctrl_out"])
        box: list[BaseException] = []
        init_cb = _INIT_FN(lambda p, s: 0)
        g, w, bufs = _guard(core, ctypes.cast(init_cb, ctypes.c_void_p).value or 0, 0, sizes, watch, False)
        inputs = _ctypes_struct(core, "bc_ctrl_in").from_address(bufs.addr[2])
        out = _ctypes_struct(core, "bc_ctrl_out").from_address(bufs.addr[3])
        stop_at = int(g.ctypes.data) + int(g.dtype.fields["stop"][1])  # type: ignore[index]  # a struct: has fields
        stop = ctypes.c_int32.from_address(stop_at)
        self.out = out
        step = self.step
        legs_out = out.leg

        def call(p: int, s: int, i: int, o: int) -> None:
            try:
                legs = step(inputs)
                if legs is not None:
                    for j in range(3):
                        legs_out[j].mode, legs_out[j].duty = legs[j]
            except BaseException as exc:
                box.append(exc)
                stop.value = 1

        step_cb = _STEP_FN(call)
        g["step"] = ctypes.cast(step_cb, ctypes.c_void_p).value
        self.init(drive)
        if int(core.lib.bc_user_init(ctypes.c_void_p(g.ctypes.data))) != 0:
            raise ControllerError(f"control ({self.label})", "init failed")
        diag, units = [], []
        for text in tuple(self.diag) + ("",) * (8 - len(self.diag)):
            label, _, unit = text.partition(" ")
            diag.append(label)
            units.append(unit.strip())
        t_half = 0.5 / drive.inverter.f_pwm
        return GuardedSlot(g, w, self.label, t_half, self.c_record(drive, core, n_samples), tuple(diag), tuple(units),
                           (bufs, init_cb, step_cb, inputs, out), failure=lambda: box[0] if box else None)

    def describe(self) -> dict[str, object]:  # noqa: D102
        def plain(v: object) -> object:
            if isinstance(v, str | bool | int | float) or v is None:
                return v
            if isinstance(v, np.generic | np.ndarray):
                return v.tolist()
            return repr(v)

        return {"controller": "python", "class": f"{type(self).__module__}:{type(self).__qualname__}",
                **{k: plain(v) for k, v in vars(self).items() if k not in ("out", "OFF", "PWM", "HIGH", "LOW")}}


# ------------------------------------------------------------------------------------------------------------------
# the child process


def run_isolated(control: Control, fn: Callable[[np.ndarray], Any], t_half: float,
                 progress: Callable[[int, int], None] | None = None, n: int = 0) -> Any:
    """Run ``fn(watch)`` in a forked child that runs user code, and return its result.

    The parent watches the shared progress record (``bc_user_watch``): a call into user code that has not returned
    after ``control.budget`` seconds gets the child killed (a hang); a child that died of a signal is a crash. Both
    raise :class:`ControllerError` naming the controller and the sample. The child's own exceptions (a bad output,
    a plausibility error) are raised here as they were there. Warnings the child issued are issued again here.
    """
    if not hasattr(os, "fork"):
        raise BldclabError("control.isolate", "needs a POSIX system (fork); use isolate=False here")
    c = core()
    page = int(c.lib.bc_user_page()) or 4096
    mem = mmap.mmap(-1, ((c.sizes["bc_user_watch"] + page - 1) // page) * page)
    watch = np.frombuffer(mem, dtype=c.dtypes["bc_user_watch"], count=1)
    watch["k"] = -1
    label = getattr(control, "label", type(control).__name__)
    budget = float(getattr(control, "budget", 1.0))
    r, w = os.pipe()
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # the child: run, send the pickled outcome, leave without the parent's exit handlers
        status = 0
        try:
            os.close(r)
            c.lib.bc_user_arm(ctypes.c_void_p(watch.ctypes.data))
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    outcome: tuple[str, Any, list[Any]] = ("ok", fn(watch), [])
                except BaseException as exc:
                    outcome = ("err", exc, [])
            outcome = (outcome[0], outcome[1], [(str(x.message), x.category) for x in caught])
            try:
                data = pickle.dumps(outcome, protocol=pickle.HIGHEST_PROTOCOL)
            except Exception as exc:
                data = pickle.dumps(("err", RuntimeError(f"{type(outcome[1]).__name__}: {outcome[1]} ({exc})"), []))
            with os.fdopen(w, "wb") as f:
                f.write(data)
        except BaseException:
            status = 1
        finally:
            os._exit(status)
    os.close(w)
    chunks: list[bytes] = []
    last, since = -1, time.monotonic()
    shown = -1
    try:
        while True:
            ready, _, _ = select.select([r], [], [], 0.02)
            if ready:
                b = os.read(r, 1 << 20)
                if not b:
                    break
                chunks.append(b)
                continue
            now = time.monotonic()
            entered, busy = int(watch["entered"][0]), int(watch["busy"][0])
            if entered != last:
                last, since = entered, now
            elif busy and now - since > budget:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                pid = 0
                k = int(watch["k"][0])
                raise ControllerError(f"control ({label})", f"did not return within its step-time budget of "
                                      f"{budget:g} s {_at_sample(k, t_half)} (a hang: the child process was killed)")
            k = int(watch["k"][0])
            if progress is not None and k > shown:
                shown = k
                progress(min(k, n), n)
    except BaseException:  # Ctrl-C, a progress callback that raised: the child must not outlive the call
        if pid:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        raise
    finally:
        os.close(r)
        status = os.waitpid(pid, 0)[1] if pid else 0
    if os.WIFSIGNALED(status):
        w0 = watch[0]
        if int(w0["fault"]) == c.const("BC_USER_FAULT_SIGNAL"):
            raise fault_error(label, w0, t_half)
        sig = os.WTERMSIG(status)
        raise ControllerError(f"control ({label})", f"its process died of {_SIGNALS.get(sig, f'signal {sig}')} "
                              f"{_at_sample(int(w0['k']), t_half)}")
    if not chunks:
        raise ControllerError(f"control ({label})", f"its process ended (status {status}) without a result "
                              f"{_at_sample(int(watch['k'][0]), t_half)}")
    kind, value, caught = pickle.loads(b"".join(chunks))
    for message, category in caught:
        warnings.warn(message, category if isinstance(category, type) else PlausibilityWarning, stacklevel=3)
    if kind == "err":
        raise value
    if progress is not None:
        progress(n, n)
    return value

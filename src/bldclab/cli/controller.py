"""``bldclab controller``: build a user controller from C files, and describe a built one (docs/user-controller.md)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from ..control.user import WARNINGS, build, describe_library
from ..errors import BldclabError

__all__ = ["configure_command", "run_command"]


def configure_command(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab controller``."""
    sub = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    b = sub.add_parser("build", help="compile C files into a user controller library (the core's warnings as errors)",
                       description="Compile a user controller (C files, one of them with BC_USER_CONTROLLER from "
                                   "bldc/bc_user.h) with bldclab's controller blocks into a shared library, with "
                                   f"the core's flags: {' '.join(WARNINGS)} -O3. Run it with 'bldclab simulate "
                                   "MOTOR --control ./my.so --param key=value'.")
    b.add_argument("sources", nargs="+", type=Path, metavar="FILE.c", help="the controller's C files")
    b.add_argument("-o", "--output", type=Path, help="the library (default: the first file with .so)")
    b.add_argument("-I", dest="include", action="append", default=[], metavar="DIR", help="include directory")
    b.add_argument("-D", dest="define", action="append", default=[], metavar="NAME[=VALUE]", help="macro")
    b.add_argument("--cc", help="C compiler (default $CC, else cc)")
    b.add_argument("--params-header", type=Path, metavar="X.h",
                   help="write the description from this header (it declares X_params, X_state, X_init, X_step): "
                        "the sources need no BC_USER_CONTROLLER")
    b.add_argument("--diag", default="", metavar="NAMES",
                   help='with --params-header: the diagnostics diag[0..7], comma-separated ("sector,i_reg A")')
    b.add_argument("--ref-meaning", default="", metavar="TEXT",
                   help='with --params-header: what the reference means ("current amplitude, A")')
    d = sub.add_parser("describe", help="list a user controller library's parameters, diagnostics and reference",
                       description="Read a user controller library's description (bc_user_controller): its "
                                   "parameter members with their C types (and defaults), named constants, "
                                   "diagnostic channels and what the reference means.")
    d.add_argument("library", type=Path, help="the library (.so)")
    d.add_argument("--format", choices=("table", "json"), default="table", help="output")


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab controller``."""
    if args.action == "build":
        if args.params_header is None and (args.diag or args.ref_meaning):
            raise BldclabError("--diag" if args.diag else "--ref-meaning", "needs --params-header (otherwise your "
                               "BC_USER_CONTROLLER description says it)")
        diag = [d.strip() for d in args.diag.split(",")] if args.diag else []
        if len(diag) > 8:
            raise BldclabError("--diag", f"at most 8 diagnostics, got {len(diag)}")
        try:
            out = build(args.sources, args.output, include=args.include, defines=args.define, cc=args.cc,
                        params_header=args.params_header, diag=diag, ref=args.ref_meaning)
        except BldclabError as exc:  # name the option typed
            option = {"output": "--output", "cc": "--cc", "sources": "FILE.c"}.get(exc.field, exc.field)
            raise BldclabError(option, exc.problem) from None
        lib = describe_library(out)
        print(f"built {out}: controller {lib.name!r}, parameters {lib.params} ({len(lib.leaves)} members"
              f"{', with defaults' if lib.defaults is not None else ''})")
        return 0
    lib = describe_library(args.library)
    info: dict[str, Any] = {
        "name": lib.name, "library": str(args.library), "built_by": lib.built_by, "sha256": lib.sha,
        "params": lib.params, "state": lib.state, "params_bytes": lib.params_size, "state_bytes": lib.state_size,
        "members": {k: {"type": base.name, **({"shape": list(shape)} if shape else {})}
                    for k, (_p, base, shape) in lib.leaves.items()},
        "constants": lib.consts, "diag": [f"{n} {u}".strip() for n, u in zip(lib.diag, lib.units, strict=True) if n],
        "ref": lib.ref, "bemf_sensing": lib.bemf,
    }
    if lib.defaults is not None:
        rec = np.frombuffer(bytearray(lib.defaults), dtype=lib.dtype, count=1)
        for key, (path, _b, _s) in lib.leaves.items():
            v: Any = rec[path[0]]
            for part in path[1:]:
                v = v[part]
            info["members"][key]["default"] = np.asarray(v)[0].tolist()
    if args.format == "json":
        print(json.dumps(info, indent=2))
        return 0
    print(f"{lib.name}: {args.library} ({lib.built_by or 'built by hand'})")
    print(f"  params {lib.params} ({lib.params_size} bytes), state {lib.state} ({lib.state_size} bytes)")
    for key, m in info["members"].items():
        extra = (f"[{', '.join(map(str, m['shape']))}]" if "shape" in m else "") + (
            f"  default {m['default']}" if "default" in m else "")
        print(f"  --param {key}=...  {m['type']}{extra}")
    if lib.consts:
        print(f"  constants: {', '.join(f'{k}={v}' for k, v in lib.consts.items())}")
    print(f"  diag: {', '.join(info['diag']) or 'none'}")
    print(f"  ref: {lib.ref or 'unstated'}")
    return 0

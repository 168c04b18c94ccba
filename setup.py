"""Build the C core into the package: one shared library, loaded with ctypes by ``bldclab._core``."""

import shutil
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

HERE = Path(__file__).parent
# core/ctrl: the controllers (what runs on an MCU); core/host: plant, sensors, runner, binding (docs/design.md)
SOURCES = sorted(str(p.relative_to(HERE)) for half in ("ctrl", "host")
                 for p in (HERE / "core" / half / "src").glob("*.c"))
# -flto (compile and link) and -fno-semantic-interposition: the runner, plant, sensors and controllers are separate
# translation units whose small functions are called per sample (bc_plant_vbus, bc_hall_step, bc_pair_legs, ...); with
# link-time optimisation they are inlined across files as within one. -fno-tree-slp-vectorize: the core's many
# three-phase expressions are not packed two into a vector plus one scalar (with shuffles): 2 % fewer instructions,
# the same time (docs/developer/speed.md). The numbers do not change: no flag here allows reassociating or
# contracting floating-point operations.
FLAGS = ["-std=c99", "-O3", "-fno-semantic-interposition", "-fno-tree-slp-vectorize", "-Wall", "-Wextra", "-Wpedantic",
         "-Wconversion", "-Wdouble-promotion"]


class BuildCoreLib(build_ext):
    """Build the core as a plain shared library (no CPython module init, no Python headers needed)."""

    def get_export_symbols(self, ext):  # noqa: D102 - setuptools hook
        return []


#: What a user controller is built with (``bldclab controller build``): the headers of both halves and the controller
#: blocks it links, copied into the package as ``bldclab/_csrc`` (an installed package has no repository beside it).
CSRC = (("ctrl", "include"), ("ctrl", "src"), ("host", "include"))


class BuildPyWithCore(build_py):
    """Copy the C sources a user controller needs into the built package (``bldclab/_csrc/...``)."""

    def run(self):  # noqa: D102 - setuptools hook
        super().run()
        dest = Path(self.build_lib) / "bldclab" / "_csrc"
        for half, kind in CSRC:
            src = HERE / "core" / half / kind
            target = dest / half / kind
            if target.exists():
                shutil.rmtree(target)
            shutil.copytree(src, target, ignore=shutil.ignore_patterns("*.o", "*.so"))


setup(
    ext_modules=[
        Extension(
            "bldclab._bccore",
            sources=SOURCES,
            include_dirs=["core/ctrl/include", "core/host/include"],
            extra_compile_args=[*FLAGS, "-flto"],
            extra_link_args=["-flto", "-O3"],
            libraries=["m"],
            py_limited_api=False,
        )
    ],
    cmdclass={"build_ext": BuildCoreLib, "build_py": BuildPyWithCore},
)

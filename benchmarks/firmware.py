"""Firmware table: each controller cross-compiled for a Cortex-M4F and its cost per step.

- Flash and RAM per controller: the controllers (``core/ctrl/src/*.c``, exactly what ``make -C core firmware``
  cross-compiles; never the plant side in ``core/host``) are built with Debian's gcc-arm-none-eabi and
  newlib (``-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard``, C99, the project's warnings as errors), linked
  into the bare-metal harness ``core/firmware/harness.c`` one controller at a time with ``--gc-sections``; the cost
  is the image size minus the empty harness (libm functions a controller pulls in are included).
- Instructions per step: ``core/firmware/cost.c`` on the host (``-O2``) under ``valgrind --tool=callgrind``
  (instruction counts are repeatable, unlike time), per input scenario; the worst scenario is reported.

Run: ``python benchmarks/firmware.py`` (needs arm-none-eabi-gcc, libnewlib-arm-none-eabi, valgrind, cc).
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "core"
WARN = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Wconversion", "-Wdouble-promotion", "-Werror"]
ARM = ["-mcpu=cortex-m4", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-mthumb", "-Os", "-ffunction-sections",
       "-fdata-sections"]
CTRL = CORE / "ctrl"
SCENARIOS = ("run", "edge", "invalid", "nan")


def controller_sources() -> list[Path]:
    """Core sources that run on the MCU: the ctrl half of the core (the host half is plant, runner, binding)."""
    return sorted((CTRL / "src").glob("*.c"))


def _targets(kind: str) -> list[str]:
    """Names of ``core/firmware/targets.txt`` built as ``kind`` ("harness" or "cost")."""
    out = []
    for line in (CORE / "firmware" / "targets.txt").read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if words and kind in words[1:]:
            out.append(words[0])
    return out


def harness_names() -> list[str]:
    """Controllers of the bare-metal harness (core/firmware/harness.c), as listed in targets.txt."""
    return _targets("harness")


def cost_names() -> list[str]:
    """Targets of the host tools (core/firmware/targets.c), as listed in targets.txt."""
    return _targets("cost")


def arm_sizes(tmp: Path) -> dict[str, tuple[int, int]]:
    """(flash, ram) bytes of each harness image: text + data, data + bss."""
    out = {}
    for name in ["none", *harness_names()]:
        elf = tmp / f"{name}.elf"
        cmd = ["arm-none-eabi-gcc", *ARM, *WARN, f"-DBC_FW_{name.upper()}", f"-I{CTRL / 'include'}",
               str(CORE / "firmware" / "harness.c"), *map(str, controller_sources()), "-Wl,--gc-sections",
               "--specs=nosys.specs", "-lm", "-o", str(elf)]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        line = subprocess.run(["arm-none-eabi-size", str(elf)], check=True, capture_output=True,
                              text=True).stdout.splitlines()[-1].split()
        text, data, bss = int(line[0]), int(line[1]), int(line[2])
        out[name] = (text + data, data + bss)
    return out


def instruction_counts(tmp: Path, n: int) -> dict[str, dict[str, float]]:
    exe = tmp / "cost"
    subprocess.run(["cc", "-O2", "-g", *WARN[:1], f"-I{CTRL / 'include'}", str(CORE / "firmware" / "cost.c"),
                    str(CORE / "firmware" / "targets.c"), *map(str, controller_sources()), "-lm", "-o", str(exe)],
                   check=True)
    out: dict[str, dict[str, float]] = {}
    for name in cost_names():
        out[name] = {}
        for sc in SCENARIOS:
            cg = tmp / f"cg.{name}.{sc}"
            subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={cg}", str(exe), name, sc, str(n)],
                           check=True, capture_output=True)
            ann = subprocess.run(["callgrind_annotate", "--inclusive=yes", str(cg)], check=True, capture_output=True,
                                 text=True).stdout
            m = re.search(rf"^\s*([\d,]+)\s+\([^)]*\)\s+\S*targets\.c:{name}_step\b", ann, flags=re.M)
            if not m:
                raise RuntimeError(f"no callgrind line for {name}_step")
            out[name][sc] = int(m.group(1).replace(",", "")) / n
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000, help="steps per scenario for the instruction counts")
    args = ap.parse_args()
    for tool in ("arm-none-eabi-gcc", "valgrind", "cc"):
        if shutil.which(tool) is None:
            print(f"missing tool: {tool} (tools/install-system-deps installs it)", file=sys.stderr)
            return 1
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        sizes = arm_sizes(tmp)
        counts = instruction_counts(tmp, args.steps)
    base_flash, base_ram = sizes.pop("none")
    print("controllers on a Cortex-M4F (arm-none-eabi-gcc -Os, hard float), cost per step on the host (-O2)")
    print(f"{'controller':<12} {'flash [B]':>10} {'RAM [B]':>8} "
          + " ".join(f"{'instr/' + s:>13}" for s in SCENARIOS) + f" {'worst':>8}")
    for name in sorted(set(sizes) | set(counts)):
        flash, ram = sizes.get(name, (base_flash, base_ram))
        c = counts.get(name, {})
        cells = " ".join(f"{c[s]:>13.0f}" if s in c else f"{'-':>13}" for s in SCENARIOS)
        worst = f"{max(c.values()):>8.0f}" if c else f"{'-':>8}"
        print(f"{name:<12} {flash - base_flash:>10d} {ram - base_ram:>8d} {cells} {worst}")
    print(f"(baseline harness: {base_flash} B flash, {base_ram} B RAM; RAM includes the static params and state)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Fuzz every controller with libFuzzer (clang, ASan + UBSan) for a bounded time and print the inputs tried.

One binary per target of ``core/firmware/targets.c`` (``-DBC_FUZZ_ONLY``), built from ``core/firmware/fuzz.c``; the
properties checked after every step are in that file's header. Run: ``python benchmarks/fuzz.py [--seconds S]``.
"""

from __future__ import annotations

import argparse
import importlib.util
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("firmware_bench", ROOT / "benchmarks" / "firmware.py")
fw = importlib.util.module_from_spec(_spec)
sys.modules.setdefault("firmware_bench", fw)
_spec.loader.exec_module(fw)  # type: ignore[union-attr]


def build(name: str, tmp: Path) -> Path:
    """Build the fuzz binary of one target."""
    exe = tmp / f"fuzz_{name}"
    cmd = ["clang", "-O1", "-g", "-fsanitize=fuzzer,address,undefined", "-fno-sanitize-recover=all",
           f'-DBC_FUZZ_ONLY="{name}"', f"-I{fw.CTRL / 'include'}", str(fw.CORE / "firmware" / "fuzz.c"),
           str(fw.CORE / "firmware" / "targets.c"), *map(str, fw.controller_sources()), "-lm", "-o", str(exe)]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return exe


def run(exe: Path, seconds: int, tmp: Path, inputs: int | None = None) -> tuple[int, bool, str]:
    """Run for a bounded time, or until ``inputs`` inputs ran (the time then a cap); return (inputs executed,
    finding?, tail of the log)."""
    corpus = tmp / f"corpus_{exe.name}"
    corpus.mkdir(exist_ok=True)
    count = [] if inputs is None else [f"-runs={inputs}"]
    proc = subprocess.run([str(exe), f"-max_total_time={seconds}", *count, "-seed=1", "-max_len=4096",
                           "-print_final_stats=1", f"-artifact_prefix={tmp}/", str(corpus)], capture_output=True,
                          text=True)
    log = proc.stdout + proc.stderr
    m = re.search(r"stat::number_of_executed_units:\s*(\d+)", log)
    runs = int(m.group(1)) if m else 0
    finding = proc.returncode != 0
    return runs, finding, log[-3000:]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=int, default=30, help="fuzzing time per controller")
    args = ap.parse_args()
    print(f"libFuzzer + ASan + UBSan, {args.seconds} s per target")
    print(f"{'target':<10} {'inputs':>12} {'findings':>9}")
    bad = 0
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for name in fw.cost_names():
            runs, finding, log = run(build(name, tmp), args.seconds, tmp)
            bad += finding
            print(f"{name:<10} {runs:>12d} {int(finding):>9d}")
            if finding:
                print(log, file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Fuzz every controller for a bounded time (libFuzzer, ASan + UBSan): no finding; and the checks can fail."""

from __future__ import annotations

import importlib.util
import subprocess
from pathlib import Path

import pytest

from conftest import require_tool

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("fuzz_bench", ROOT / "benchmarks" / "fuzz.py")
fz = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fz)

INPUTS = 10_000  # inputs per target: a fixed amount of work, not of time
CAP = 300  # s: a bound for a loaded machine (the inputs, not the time, end a run)

pytestmark = pytest.mark.slow  # libFuzzer builds and runs: ~12 s a target


@pytest.mark.parametrize("name", fz.fw.cost_names())
def test_fuzz_target_finds_nothing(name, tmp_path):
    require_tool("clang")
    runs, finding, log = fz.run(fz.build(name, tmp_path), CAP, tmp_path, inputs=INPUTS)
    assert not finding, log
    assert runs >= INPUTS, f"only {runs} inputs before the {CAP} s cap"


def test_fuzz_checks_catch_a_wrong_controller(tmp_path):
    require_tool("clang")
    exe = tmp_path / "fuzz_canary"
    cmd = ["clang", "-O1", "-g", "-fsanitize=fuzzer,address,undefined", "-DBC_FUZZ_CANARY", '-DBC_FUZZ_ONLY="canary"',
           f"-I{fz.fw.CTRL / 'include'}", str(fz.fw.CORE / "firmware" / "fuzz.c"),
           str(fz.fw.CORE / "firmware" / "targets.c"), *map(str, fz.fw.controller_sources()), "-lm", "-o", str(exe)]
    subprocess.run(cmd, check=True, capture_output=True)
    _, finding, log = fz.run(exe, 60, tmp_path)
    assert finding, "the fuzzer did not find a duty of 2 on a NaN bus"
    assert "deadly signal" in log or "ERROR" in log

"""Build and run the host C tests of core/ (strict warnings as errors) from the Python suite, plain and under
AddressSanitizer + UndefinedBehaviorSanitizer (any finding aborts the test binary: -fno-sanitize-recover=all)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

CORE = Path(__file__).resolve().parents[1] / "core"

pytestmark = pytest.mark.slow  # make + run every C test: ~25 s plain, ~75 s under the sanitizers


@pytest.mark.parametrize("sanitize", [False, True], ids=["plain", "asan-ubsan"])
def test_c_core_tests_pass(tmp_path, sanitize):
    args = ["make", "-C", str(CORE), "test", f"BUILD={tmp_path}"] + (["SAN=1"] if sanitize else [])
    proc = subprocess.run(args, capture_output=True, text=True, timeout=900)
    out = proc.stdout + proc.stderr
    summaries = re.findall(r"^(\w+): (\d+) passed, (\d+) failed$", out, flags=re.M)
    assert proc.returncode == 0, out[-4000:]
    names = {s[0] for s in summaries}
    expected = {p.stem for p in (CORE / "tests").glob("test_*.c")}
    assert names == expected, f"missing summaries: {expected - names}"
    assert all(int(f) == 0 and int(p) > 0 for _, p, f in summaries), summaries

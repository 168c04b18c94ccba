"""Build and run the host C tests of core/ (strict warnings as errors) from the Python suite."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

CORE = Path(__file__).resolve().parents[1] / "core"


def test_c_core_tests_pass(tmp_path):
    proc = subprocess.run(["make", "-C", str(CORE), "test", f"BUILD={tmp_path}"], capture_output=True, text=True,
                          timeout=600)
    out = proc.stdout + proc.stderr
    summaries = re.findall(r"^(\w+): (\d+) passed, (\d+) failed$", out, flags=re.M)
    assert proc.returncode == 0, out[-4000:]
    names = {s[0] for s in summaries}
    expected = {p.stem for p in (CORE / "tests").glob("test_*.c")}
    assert names == expected, f"missing summaries: {expected - names}"
    assert all(int(f) == 0 and int(p) > 0 for _, p, f in summaries), summaries

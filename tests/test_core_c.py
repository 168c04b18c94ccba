"""Build and run the host C tests of core/ (strict warnings as errors) from the Python suite, plain and under
AddressSanitizer + UndefinedBehaviorSanitizer (any finding aborts the test binary: -fno-sanitize-recover=all)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

CORE = Path(__file__).resolve().parents[1] / "core"

pytestmark = pytest.mark.slow  # make + run every C test: ~15 s each, plain and under the sanitizers


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


def _quoted_includes(path: Path) -> list[str]:
    return re.findall(r'^\s*#\s*include\s+"([^"]+)"', path.read_text(), flags=re.M)


def test_ctrl_half_never_includes_a_host_header():
    """core/ctrl is what a user copies into firmware: it must build from its own headers alone."""
    ctrl = {p.name for p in (CORE / "ctrl" / "include" / "bldc").glob("*.h")}
    host = {p.name for p in (CORE / "host" / "include" / "bldc").glob("*.h")}
    assert ctrl and host and not ctrl & host, "a header is in both halves"
    files = [*(CORE / "ctrl" / "src").glob("*.c"), *(CORE / "ctrl" / "include" / "bldc").glob("*.h")]
    assert len(files) > 10
    for f in files:
        for inc in _quoted_includes(f):
            name = Path(inc).name
            assert name in ctrl, f"{f.relative_to(CORE)} includes {inc}, which is not a ctrl header"


def test_include_scan_sees_a_host_include(tmp_path):
    """The scan above can fail: a file including bc_plant.h is seen."""
    f = tmp_path / "x.c"
    f.write_text('#include <math.h>\n  #  include "bldc/bc_plant.h"\n')
    assert _quoted_includes(f) == ["bldc/bc_plant.h"]

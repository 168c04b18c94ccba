"""Static checks that belong to the suite: ruff on the Python tree, mypy over the package."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_ruff_clean():
    ruff = str(Path(sys.executable).parent / "ruff")
    proc = subprocess.run([ruff, "check", "src", "tests", "tools", "benchmarks", "examples"], cwd=ROOT,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


_IGNORE = re.compile(r"#\s*type:\s*ignore(\[[^\]]*\])?(.*)$")


def unexplained_ignores(text: str) -> list[int]:
    """Line numbers of ``# type: ignore`` comments without an error code and a ``# reason`` after it."""
    bad = []
    for n, line in enumerate(text.splitlines(), 1):
        m = _IGNORE.search(line)
        if m and (not m.group(1) or not m.group(2).strip().startswith("#") or len(m.group(2).strip()) < 8):
            bad.append(n)
    return bad


def test_unexplained_ignore_is_found():
    assert unexplained_ignores("x = f()  # type: ignore[arg-type]\n") == [1]
    assert unexplained_ignores("x = f()  # type: ignore\n") == [1]
    assert unexplained_ignores("x = f()  # type: ignore[arg-type]  # f accepts any number here\n") == []


def test_every_type_ignore_says_why():
    bad = [f"{p.relative_to(ROOT)}:{n}" for p in sorted((ROOT / "src").rglob("*.py"))
           for n in unexplained_ignores(p.read_text())]
    assert not bad, "type: ignore without an error code and a reason: " + ", ".join(bad)


@pytest.mark.slow
def test_mypy_clean():
    """mypy over src/ with the settings in pyproject.toml (strict optional, unused ignores reported)."""
    proc = subprocess.run([sys.executable, "-m", "mypy", "--no-incremental"], cwd=ROOT, capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr

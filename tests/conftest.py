"""Shared test helpers, the session fixtures that several test files read, and the grouping of tests for
pytest-xdist.

Tests that take more than about a second are marked ``slow`` (``pytest -m "not slow"`` is the development subset;
CI runs everything); see docs/developer/testing.md.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
from pathlib import Path

import pytest

from bldclab.cli import main


def require_tool(name: str) -> str:
    """Return the path of a system tool; skip (with the reason) if it is missing, fail instead under CI.

    ``tools/install-system-deps`` installs every tool the suite uses; ``.ci/run`` runs it and sets BLDCLAB_CI=1 so
    that no test can be skipped silently there.
    """
    path = shutil.which(name)
    if path:
        return path
    _missing(f"{name} is not installed (tools/install-system-deps installs it)")
    raise AssertionError("unreachable")


def require_module(*names: str, install: str = 'pip install ".[test]"') -> None:
    """Skip (with the reason) if a Python module is missing, fail instead under CI (BLDCLAB_CI=1)."""
    missing = [n for n in names if importlib.util.find_spec(n) is None]
    if missing:
        _missing(f"{', '.join(missing)} not installed ({install})")


def _missing(msg: str) -> None:
    """Skip a test for a missing tool, or fail it under CI, where nothing may be skipped."""
    if os.environ.get("BLDCLAB_CI") == "1":
        pytest.fail(msg)
    pytest.skip(msg)


# ---------------------------------------------------------------------------------------------------------------
# one bldclab compare run, read by test_compare.py and test_report.py

#: The arguments of the shared run (its manifest's command starts with ``bldclab compare htm-48v --out``).
COMPARE_HTM48V_ARGS = ("--speeds", "6", "--workers", "2", "--no-progress")


@pytest.fixture(scope="session")
def compare_htm48v(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``bldclab compare htm-48v --speeds 6 --workers 2`` (through ``main``), once per session: every file compare
    writes, report.html included. Tests only read it; a test that adds files copies the directory first."""
    out = tmp_path_factory.mktemp("compare") / "htm-48v"
    assert main(["compare", "htm-48v", "--out", str(out), *COMPARE_HTM48V_ARGS]) == 0
    return out


# ---------------------------------------------------------------------------------------------------------------
# pytest-xdist: tests that share an expensive fixture run on the same worker (with ``--dist loadgroup``), so the
# fixture is computed once, not once per worker

#: fixture name -> xdist group
XDIST_GROUPS = {
    "compare_htm48v": "compare-htm48v",  # session fixture above (~5 s)
    "site": "docs-site",  # test_docs.py: mkdocs build --strict (~25 s)
    "built": "report-browser",  # test_report_browser.py: the report the browser opens
    "slow_reference": "sweep-interrupt",  # test_sweep.py: the 80-case serial reference of the kill/Ctrl-C tests
    "cost_runs": "cost-gate",  # test_cost_gate.py: every cost scenario under valgrind (~1 min)
}


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        groups = {XDIST_GROUPS[f] for f in getattr(item, "fixturenames", ()) if f in XDIST_GROUPS}
        if len(groups) > 1:
            raise pytest.UsageError(f"{item.nodeid} uses fixtures of several xdist groups: {sorted(groups)}")
        if groups:
            item.add_marker(pytest.mark.xdist_group(groups.pop()))

"""Shared test helpers."""

from __future__ import annotations

import importlib.util
import os
import shutil

import pytest


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

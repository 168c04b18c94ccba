"""Shared test helpers."""

from __future__ import annotations

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
    msg = f"{name} is not installed (tools/install-system-deps installs it)"
    if os.environ.get("BLDCLAB_CI") == "1":
        pytest.fail(msg)
    pytest.skip(msg)

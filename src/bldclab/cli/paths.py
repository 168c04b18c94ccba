"""Where a command may write: output directories and files checked before any work.

Apart from :mod:`bldclab.cli.common` so that the light commands (``template``, ``analyze``) check their ``--out``
without importing the controllers and the simulator.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import BldclabError

__all__ = ["check_out_dir", "check_out_file"]


def check_out_dir(path: Path | None, option: str = "--out") -> None:
    """Check before any work that ``path`` can be used as an output directory.

    The directory need not exist: its nearest existing ancestor must be a writable directory (it is created when
    the results are written). Nothing is created here, so a rejected option leaves nothing behind.

    Parameters
    ----------
    path : Path or None
        The directory the command will write into; None: nothing to check.
    option : str
        The option the user typed, named in the error.

    Raises
    ------
    BldclabError
        ``option``: the path is an existing file, or its existing ancestor is not a writable directory.
    """
    if path is None:
        return
    if path.exists() and not path.is_dir():
        raise BldclabError(option, f"{str(path)!r} exists and is not a directory")
    _check_writable(path, option)


def check_out_file(path: Path | None, option: str = "--out") -> None:
    """Check before any work that the file ``path`` can be written (its directory created if missing).

    Parameters
    ----------
    path : Path or None
        The file the command will write; None: nothing to check.
    option : str
        The option the user typed, named in the error.

    Raises
    ------
    BldclabError
        ``option``: the path is a directory, or its directory cannot be created or written.
    """
    if path is None:
        return
    if path.is_dir():
        raise BldclabError(option, f"{str(path)!r} is a directory; give a file name")
    _check_writable(path.parent if str(path.parent) else Path("."), option)


def _check_writable(path: Path, option: str) -> None:
    """Raise unless the nearest existing ancestor of ``path`` (itself included) is a writable directory."""
    probe = path.absolute()
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise BldclabError(option, f"cannot create {str(path)!r}: {str(probe)!r} is not a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise BldclabError(option, f"cannot write {str(path)!r}: directory {str(probe)!r} is not writable")

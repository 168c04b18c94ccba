"""File helpers shared by the readers of motor files and sweep files."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from .errors import BldclabError

__all__ = ["read_toml"]


def read_toml(path: str | Path, what: str) -> dict[str, Any]:
    """Read a TOML file.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What kind of file it should be (for the message), e.g. ``"motor file"``.

    Returns
    -------
    dict
        The parsed document.

    Raises
    ------
    BldclabError
        One error naming the file: unreadable, not UTF-8 text, or not valid TOML.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise BldclabError("file", f"cannot read: {exc.strerror or exc}", str(p)) from None
    except UnicodeDecodeError:
        raise BldclabError("file", f"not a text (UTF-8) file, so not a TOML {what}", str(p)) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise BldclabError("file", f"not valid TOML ({exc})", str(p)) from None

"""File helpers of every layer: reading TOML (motor files, sweep files) and the one atomic writer.

Every file bldclab writes goes through :func:`write_atomic`: a temporary file in the target directory, flushed
and synced, then :func:`os.replace` onto the target, so a reader never sees a half-written file and a failed
write leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from .errors import BldclabError

__all__ = ["json_text", "read_toml", "write_atomic", "write_files"]


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


def write_atomic(path: str | Path, data: bytes | Callable[[IO[bytes]], None], option: str | None = "--out") -> Path:
    """Write one file atomically: a temporary file in the same directory, synced, then renamed onto ``path``.

    Parameters
    ----------
    path : str or Path
        The target file; its directory must exist.
    data : bytes or callable
        The content, or a function writing it to the open binary file it is given.
    option : str or None
        The option or field named in the error when the write fails; ``None`` re-raises the :class:`OSError`.

    Returns
    -------
    Path
        The written path.

    Raises
    ------
    BldclabError
        If the file cannot be written (field ``option``); neither a partial file nor a temporary is left behind.
    """
    target = Path(path)
    umask = os.umask(0o022)
    os.umask(umask)
    tmp: str | None = None
    try:
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600 files; give the usual permissions
        with os.fdopen(fd, "wb") as fh:
            if callable(data):
                data(fh)
            else:
                fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
        tmp = None
    except OSError as exc:
        if option is None:
            raise
        raise BldclabError(option, f"cannot write {str(target)!r}: {exc.strerror or exc}") from None
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
    return target


def write_files(out_dir: Path, files: dict[str, bytes]) -> list[Path]:
    """Write files into a directory, each atomically (:func:`write_atomic`).

    Parameters
    ----------
    out_dir : Path
        Target directory, created (with parents) if missing.
    files : dict of str to bytes
        File name (no directory part) to content.

    Returns
    -------
    list of Path
        The written paths, in the order given.

    Raises
    ------
    BldclabError
        If the directory cannot be created or a file cannot be written (field ``--out``); a file that failed
        is not left behind, neither complete nor partial.

    """
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BldclabError("--out", f"cannot create directory {str(out_dir)!r}: {exc.strerror or exc}"
                           ) from None
    return [write_atomic(out_dir / name, content, "--out") for name, content in files.items()]


def _finite_or_none(obj: Any) -> Any:
    """Return ``obj`` with every non-finite float (NaN, +-inf) replaced by ``None``, recursively."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite_or_none(v) for v in obj]
    return obj


def json_text(obj: Any, indent: int | None = 2) -> str:
    """Return ``obj`` as standard JSON (RFC 8259), an undefined number (NaN, +-inf) written as ``null``.

    Python's :func:`json.dumps` writes ``NaN`` and ``Infinity``, which no other JSON reader accepts (``jq``,
    JavaScript's ``JSON.parse``); a quantity that is undefined for a run (an efficiency without input power) is
    ``null`` instead.

    Parameters
    ----------
    obj : Any
        Dicts, lists, tuples, strings, numbers (NumPy floats are floats), booleans, None.
    indent : int or None
        As :func:`json.dumps`.

    Returns
    -------
    str
        The JSON text, without a trailing newline.
    """
    return json.dumps(_finite_or_none(obj), indent=indent, allow_nan=False)

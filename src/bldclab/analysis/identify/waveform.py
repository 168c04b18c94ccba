"""The measured record of :func:`~bldclab.analysis.identify.algorithm.identify`: a constant-speed waveform.

:func:`read_waveform` reads a CSV (time or angle, phase or line-to-line voltages, optional Hall signals; units in
the headers), :func:`waveform_from_columns` takes arrays, :func:`waveform_csv` writes one; all give a
:class:`Waveform` with the common mode removed. Pure Python (numpy only).
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import BldclabError
from ...model.units import to_si

__all__ = [
    "Waveform",
    "read_waveform",
    "waveform_csv",
    "waveform_from_columns",
]

_PHASES = "abc"


_TIME = ("t", "time")


_ANGLE = ("theta", "thetae", "angle")


_PHASE_ALIASES: dict[str, tuple[str, ...]] = {
    "a": ("va", "ea", "van", "vu", "eu", "vun"),
    "b": ("vb", "eb", "vbn", "vv", "ev", "vvn"),
    "c": ("vc", "ec", "vcn", "vw", "ew", "vwn"),
}


_LINE_ALIASES: dict[str, tuple[str, ...]] = {
    "ab": ("vab", "eab", "vuv", "euv"),
    "bc": ("vbc", "ebc", "vvw", "evw"),
    "ca": ("vca", "eca", "vwu", "ewu"),
}


_LINE_REVERSED: dict[str, tuple[str, ...]] = {  # written the other way round: the column is minus the line voltage
    "ab": ("vba", "eba", "vvu", "evu"),
    "bc": ("vcb", "ecb", "vwv", "ewv"),
    "ca": ("vac", "eac", "vuw", "euw"),
}


_HALL_ALIASES = {
    "a": ("ha", "halla", "hu", "hallu", "h1", "hall1"),
    "b": ("hb", "hallb", "hv", "hallv", "h2", "hall2"),
    "c": ("hc", "hallc", "hw", "hallw", "h3", "hall3"),
}


_HEADER_UNIT = re.compile(r"^(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$")


def _norm(name: str) -> str:
    """Return a column name reduced for alias matching (lower case, no spaces, '_', '-', '.')."""
    return re.sub(r"[\s_.\-]", "", name.lower())


@dataclass(frozen=True, eq=False)
class Waveform:
    """A measured constant-speed record, validated, with the common mode removed.

    Build one with :func:`read_waveform` (a CSV file) or :func:`waveform_from_columns` (arrays).

    Parameters
    ----------
    v : ndarray, shape (3, M)
        Phase voltages of phases a, b, c (V) with the common mode removed (they sum to zero per sample).
    t : ndarray, shape (M,), optional
        Time of each sample (s), strictly increasing.
    theta : ndarray, shape (M,), optional
        Electrical angle of each sample (rad), unwrapped, strictly increasing.
    hall : ndarray of bool, shape (3, M), optional
        Hall sensor states of phases a, b, c.
    hall_level : ndarray, shape (3, M), optional
        The Hall columns as read, scaled to [0, 1] (0 low, 1 high), for locating edges between samples.
    voltages : {"phase", "line"}
        Which kind of voltage columns the record had.
    columns : dict of str to str
        The file's column used for each quantity (``t``, ``theta``, ``v_a``, ``v_ab``, ``h_a``, ...).
    ignored : tuple of str
        Columns of the file that were not used.
    rows : ndarray of int, shape (M,)
        Where each sample came from: the file line (CSV) or the row index (arrays), for messages.
    row_word : str
        ``"line"`` (CSV) or ``"row"`` (arrays).
    source : str
        The file name, or a label for arrays.
    closure : float
        With all three line-to-line columns: the rms of ``v_ab + v_bc + v_ca`` over the rms of the three
        (0 for a consistent record); NaN otherwise.

    """

    v: NDArray[np.float64]
    t: NDArray[np.float64] | None = None
    theta: NDArray[np.float64] | None = None
    hall: NDArray[np.bool_] | None = None
    hall_level: NDArray[np.float64] | None = None
    voltages: str = "phase"
    columns: dict[str, str] = field(default_factory=dict)
    ignored: tuple[str, ...] = ()
    rows: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    row_word: str = "row"
    source: str = "data"
    closure: float = math.nan

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.v.shape[1])

    def where(self, j: int) -> str:
        """Return ``"line 57"`` (CSV) or ``"row 55"`` (arrays) for sample index ``j``."""
        return f"{self.row_word} {int(self.rows[j])}"


def _resolve_columns(names: Sequence[str], source: str) -> tuple[dict[str, tuple[int, float]], list[str]]:
    """Map the header names to quantities.

    Returns
    -------
    dict
        Quantity key (``t``, ``theta``, ``v_a``, ``v_ab``, ``h_a``, ...) to (column index, factor to SI,
        including the sign of a reversed line voltage).
    list of str
        Columns not used.

    """
    lookup: dict[str, tuple[str, str, float]] = {}  # alias -> (key, dimension, sign)
    for a in _TIME:
        lookup[a] = ("t", "time", 1.0)
    for a in _ANGLE:
        lookup[a] = ("theta", "angle", 1.0)
    for ph, aliases in _PHASE_ALIASES.items():
        for a in aliases:
            lookup[a] = (f"v_{ph}", "voltage", 1.0)
    for pair, aliases in _LINE_ALIASES.items():
        for a in aliases:
            lookup[a] = (f"v_{pair}", "voltage", 1.0)
    for pair, aliases in _LINE_REVERSED.items():
        for a in aliases:
            lookup[a] = (f"v_{pair}", "voltage", -1.0)
    for ph, aliases in _HALL_ALIASES.items():
        for a in aliases:
            lookup[a] = (f"h_{ph}", "", 1.0)
    found: dict[str, tuple[int, float]] = {}
    first_name: dict[str, str] = {}
    ignored: list[str] = []
    for j, raw in enumerate(names):
        text = raw.strip()
        unit = ""
        m = _HEADER_UNIT.match(text)
        if m:
            text, unit = m.group(1), m.group(2)
        key = lookup.get(_norm(text))
        if key is None:
            ignored.append(raw)
            continue
        name, dim, sign = key
        if name in found:
            raise BldclabError(f"column {raw.strip()}", f"gives the same quantity ({name}) as column "
                               f"{first_name[name]}: keep one of them", source)
        scale = 1.0
        if unit and dim:
            scale = to_si(f"1 {unit}", dim, f"column {raw.strip()}", source)
        found[name] = (j, sign * scale)
        first_name[name] = raw.strip()
    return found, ignored


def _bad_cell(source: str, column: str, where: str, text: str) -> BldclabError:
    """Return the error for one unreadable cell."""
    stripped = text.strip()
    if stripped == "":
        problem = "empty cell: missing sample (holes are not filled in; cut the record before or after it)"
    elif stripped.lower() in ("nan", "-nan", "+nan", "na", "n/a", "null", "none"):
        problem = f"is {stripped!r}: missing sample (holes are not filled in; cut the record before or after it)"
    elif stripped.lower().lstrip("+-") in ("inf", "infinity"):
        problem = f"is {stripped!r}: not a finite number (an overrange sample?)"
    else:
        problem = f"cannot read a number in {stripped!r}"
    return BldclabError(f"column {column}, {where}", problem, source)


def read_waveform(path: str | Path) -> Waveform:
    """Read a measured constant-speed record from a CSV file.

    Format (``docs/identify.md``): optional comment lines starting with ``#``, a header row, then one row
    per sample. Separator: comma, semicolon or tab. Column names are case-insensitive, with aliases; a
    unit in brackets is converted to SI (``t [ms]``, ``v_ab (mV)``). Needed: ``t`` (s) or ``theta``
    (rad, electrical); ``v_a, v_b, v_c`` (to any common reference) or two or three of ``v_ab, v_bc,
    v_ca``. Optional: Hall signals ``h_a, h_b, h_c`` (0/1 or logic levels). Other columns are ignored.

    Parameters
    ----------
    path : str or Path
        The CSV file.

    Returns
    -------
    Waveform

    Raises
    ------
    BldclabError
        For an unreadable file, a missing column, an empty, NaN or unreadable cell (naming the column and
        the file line), or a record failing the checks of :func:`waveform_from_columns`.

    """
    p = Path(path)
    source = str(p)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise BldclabError("file", f"cannot read: {exc.strerror or exc}", source) from None
    except UnicodeDecodeError:
        raise BldclabError("file", "not a text (UTF-8) file, so not a CSV record", source) from None
    lines = text.splitlines()
    start = 0
    while start < len(lines) and (not lines[start].strip() or lines[start].lstrip().startswith("#")):
        start += 1
    if start == len(lines):
        raise BldclabError("file", "has no header row (and no data)", source)
    header = lines[start]
    delimiter = max((",", ";", "\t"), key=header.count)
    if header.count(delimiter) == 0:
        delimiter = ","
    reader = csv.reader(io.StringIO("\n".join(lines[start:])), delimiter=delimiter)
    names = next(reader)
    found, ignored = _resolve_columns(names, source)
    _require_columns(found, names, source)
    keys = list(found)
    values: dict[str, list[float]] = {k: [] for k in keys}
    rows: list[int] = []
    for cells in reader:
        line = start + reader.line_num
        if not cells or all(not c.strip() for c in cells):
            continue  # a blank line holds no sample
        if cells[0].lstrip().startswith("#"):
            continue
        for k in keys:
            j, _ = found[k]
            cell = cells[j] if j < len(cells) else ""
            try:
                x = float(cell)
            except ValueError:
                raise _bad_cell(source, names[j].strip(), f"line {line}", cell) from None
            if not math.isfinite(x):
                raise _bad_cell(source, names[j].strip(), f"line {line}", cell)
            values[k].append(x)
        rows.append(line)
    columns = {k: np.asarray(values[k], dtype=float) * found[k][1] for k in keys}
    used = {k: names[found[k][0]].strip() for k in keys}
    return _build(columns, used, tuple(n.strip() for n in ignored), np.asarray(rows, dtype=np.int64), "line",
                  source)


def _require_columns(found: Mapping[str, object], names: Sequence[str], source: str) -> None:
    """Raise if the header lacks the time/angle column or a usable set of voltage columns."""
    have = ", ".join(n.strip() for n in names) or "(none)"
    if "t" not in found and "theta" not in found:
        raise BldclabError("columns", f"needs a time column 't' (s) or an electrical angle column 'theta' (rad); "
                           f"the header has: {have}", source)
    phases = [f"v_{x}" for x in _PHASES]
    lines = [f"v_{pq}" for pq in _LINE_ALIASES]
    if all(k in found for k in phases):
        return
    if sum(k in found for k in lines) >= 2:
        return
    raise BldclabError("columns", "needs the phase voltages v_a, v_b, v_c or two of the line-to-line voltages "
                       f"v_ab, v_bc, v_ca; the header has: {have}", source)


def waveform_from_columns(columns: Mapping[str, ArrayLike], source: str = "data") -> Waveform:
    """Build a :class:`Waveform` from named arrays (a dict, or a pandas DataFrame).

    The names follow the CSV rules of :func:`read_waveform` (case-insensitive, aliases, a unit in brackets).

    Parameters
    ----------
    columns : mapping of str to array_like
        One array per column, all of the same length.
    source : str
        Label used in messages.

    Returns
    -------
    Waveform

    Raises
    ------
    BldclabError
        For a missing column, a NaN or infinite value (naming the column and the row index), unequal
        lengths, a time or angle that does not increase, or a Hall column that never changes.

    """
    names = [str(k) for k in columns]
    found, ignored = _resolve_columns(names, source)
    _require_columns(found, names, source)
    data: dict[str, NDArray[np.float64]] = {}
    used: dict[str, str] = {}
    length = None
    for key, (j, scale) in found.items():
        name = names[j]
        raw = columns[list(columns)[j]]
        try:
            arr = np.asarray(raw, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            obj = np.asarray(raw, dtype=object).reshape(-1)
            for i, cell in enumerate(obj):
                try:
                    float(cell)
                except (TypeError, ValueError):
                    raise _bad_cell(source, name, f"row {i}", "" if cell is None else str(cell)) from None
            raise BldclabError(f"column {name}", "cannot read the values as numbers", source) from None
        bad = np.nonzero(~np.isfinite(arr))[0]
        if bad.size:
            raise _bad_cell(source, name, f"row {int(bad[0])}", str(arr[bad[0]]))
        if length is None:
            length = arr.size
        elif arr.size != length:
            raise BldclabError(f"column {name}", f"has {arr.size} values, the others {length}", source)
        data[key] = arr * scale
        used[key] = name
    rows = np.arange(length or 0, dtype=np.int64)
    return _build(data, used, tuple(ignored), rows, "row", source)


def _build(data: dict[str, NDArray[np.float64]], used: dict[str, str], ignored: tuple[str, ...],
           rows: NDArray[np.int64], row_word: str, source: str) -> Waveform:
    """Check the columns read and assemble the :class:`Waveform` (common mode removed)."""
    m = rows.size
    if m < 3:
        raise BldclabError("file" if row_word == "line" else "columns", f"has {m} samples: a record needs at "
                           "least one whole electrical period", source)

    def where(j: int) -> str:
        return f"{row_word} {int(rows[j])}"

    t = data.get("t")
    if t is not None:
        bad = np.nonzero(np.diff(t) <= 0.0)[0]
        if bad.size:
            j = int(bad[0]) + 1
            raise BldclabError(f"column {used['t']}, {where(j)}", f"time does not increase: {t[j]:.9g} s after "
                               f"{t[j - 1]:.9g} s (rows must be in time order, without repeated times)", source)
    theta = data.get("theta")
    if theta is not None:
        theta = np.unwrap(theta)
        bad = np.nonzero(np.diff(theta) <= 0.0)[0]
        if bad.size:
            j = int(bad[0]) + 1
            deg = 180.0 / math.pi  # a column in degrees reads its own numbers too
            raise BldclabError(f"column {used['theta']}, {where(j)}", f"the angle does not increase: "
                               f"{theta[j]:.9g} rad ({theta[j] * deg:.6g} deg) after {theta[j - 1]:.9g} rad "
                               f"({theta[j - 1] * deg:.6g} deg) (unwrapped): the test must turn forwards at "
                               "constant speed", source)
    phase_keys = [f"v_{x}" for x in _PHASES]
    closure = math.nan
    if all(k in data for k in phase_keys):
        v = np.stack([data[k] for k in phase_keys])
        v = v - v.mean(axis=0)
        kind = "phase"
        line_keys = [k for k in used if k in ("v_ab", "v_bc", "v_ca")]  # phase voltages take precedence
        ignored = (*ignored, *(used.pop(k) for k in line_keys))
    else:
        ab, bc, ca = data.get("v_ab"), data.get("v_bc"), data.get("v_ca")
        if ab is not None and bc is not None and ca is not None:
            rms = math.sqrt(float(np.mean(ab * ab + bc * bc + ca * ca)) / 3.0)
            closure = math.sqrt(float(np.mean((ab + bc + ca) ** 2))) / rms if rms > 0.0 else math.nan
        if ab is None:
            ab = -(bc + ca)  # type: ignore[operator]  # two of the three are given (checked above)
        if bc is None:
            bc = -(ab + ca)  # type: ignore[operator]  # two of the three are given (checked above)
        if ca is None:
            ca = -(ab + bc)
        # zero-sequence-free phase voltages; with three columns this is the least-squares fit
        v = np.stack([(ab - ca) / 3.0, (bc - ab) / 3.0, (ca - bc) / 3.0])
        kind = "line"
    hall = level = None
    if any(f"h_{x}" in data for x in _PHASES):
        missing = [f"h_{x}" for x in _PHASES if f"h_{x}" not in data]
        if missing:
            raise BldclabError("columns", f"has Hall columns but not {', '.join(missing)}: give all three Hall "
                               "signals or none", source)
        level = np.empty((3, m))
        for x, ph in enumerate(_PHASES):
            h = data[f"h_{ph}"]
            lo, hi = float(np.min(h)), float(np.max(h))
            if hi - lo <= 0.0:
                raise BldclabError(f"column {used[f'h_{ph}']}", f"never changes (always {lo:g}): a stuck or "
                                   "disconnected Hall sensor; drop the Hall columns to identify the back-EMF "
                                   "alone", source)
            level[x] = (h - lo) / (hi - lo)
        hall = _schmitt(level)
    return Waveform(v=v, t=t, theta=theta, hall=hall, hall_level=level, voltages=kind, columns=used,
                    ignored=tuple(ignored), rows=rows, row_word=row_word, source=source, closure=closure)


def _schmitt(level: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Threshold levels in [0, 1] with hysteresis (0.3 / 0.7), so noise on a logic level gives no edges."""
    out = np.empty(level.shape, dtype=bool)
    for x in range(level.shape[0]):
        lx = level[x]
        decisive = (lx > 0.7) | (lx < 0.3)  # the state changes only when the level passes the far threshold
        last = np.maximum.accumulate(np.where(decisive, np.arange(lx.size), -1))
        out[x] = np.where(last >= 0, lx[np.maximum(last, 0)] > 0.7, lx[0] >= 0.5)
    return out


def waveform_csv(columns: Mapping[str, ArrayLike], comments: Sequence[str] = ()) -> str:
    """Return columns as CSV text in the format :func:`read_waveform` reads.

    Parameters
    ----------
    columns : mapping of str to array_like
        Column name to values (equal lengths). ``t`` is written with 10 significant digits, the others with
        7 (beyond a 16-bit scope's resolution).
    comments : sequence of str
        Lines written first, each prefixed with ``# ``.

    Returns
    -------
    str

    """
    out = io.StringIO()
    for c in comments:
        out.write(f"# {c}\n" if c else "#\n")
    names = list(columns)
    arrs = [np.asarray(columns[n], dtype=float) for n in names]
    out.write(",".join(names) + "\n")
    fmts = ["{:.10g}" if n == "t" else "{:.7g}" for n in names]
    for row in zip(*arrs, strict=True):
        out.write(",".join(f.format(v) for f, v in zip(fmts, row, strict=True)) + "\n")
    return out.getvalue()

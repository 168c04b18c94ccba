"""The resumable results store of :mod:`bldclab.sweep`: one SQLite file, one row per finished case.

A case is stored under its key, the sha256 of the canonical JSON of its full inputs (the drive's motor file after
overrides, the controller's class and parameters, the experiment, the bldclab version). The key is the table's
PRIMARY KEY and every row is written in its own transaction, so a case is either fully stored or absent, never
half-written and never twice, whatever happens to the writing process (Ctrl-C, ``kill -9``). The database runs in
WAL mode: readers (a second shell watching a sweep, a notebook) never block the writer. Only the process that runs
the sweep writes; workers return their rows to it.

Tables (schema version :data:`SCHEMA_VERSION`):

``results(key, inputs, case_spec, result, elapsed, finished)``
    ``inputs``: the canonical inputs as JSON with the drive's text replaced by its sha256 (the text is stored once
    in ``drives``); ``case_spec``: the case's settings as written in the sweep (JSON); ``result``: the experiment's
    values (JSON object; ``NaN`` is written as the bare token ``NaN``, as Python's :mod:`json` does);
    ``elapsed``: worker wall time (s); ``finished``: UTC time stamp (ISO 8601).
``drives(sha256, toml)``
    Motor-file texts, deduplicated.
``failures(key, case_spec, error, finished)``
    The last error of cases that failed; a later success removes the entry. Failed cases are retried on a rerun.
``meta(name, value)``
    ``schema`` version.
"""

from __future__ import annotations

import hashlib
import json
import sqlite3
from collections.abc import Iterable, Iterator, Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ..errors import BldclabError

__all__ = ["SCHEMA_VERSION", "Store"]

#: Version of the table layout; a store written with another layout is refused, not silently misread.
SCHEMA_VERSION = 1

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS drives (sha256 TEXT PRIMARY KEY, toml TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS results (
    key TEXT PRIMARY KEY,
    inputs TEXT NOT NULL,
    case_spec TEXT NOT NULL,
    result TEXT NOT NULL,
    elapsed REAL NOT NULL,
    finished TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS failures (
    key TEXT PRIMARY KEY,
    case_spec TEXT NOT NULL,
    error TEXT NOT NULL,
    finished TEXT NOT NULL
);
"""

_BATCH = 500  # keys per SELECT ... IN (...) (SQLite allows at least 999 parameters)


def _rollback(db: sqlite3.Connection) -> None:
    """Undo the open transaction, if any: an interrupt (Ctrl-C) can arrive just after COMMIT has completed."""
    if db.in_transaction:
        db.execute("ROLLBACK")


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="milliseconds")


class Store:
    """Finished cases of sweeps, keyed by the sha256 of their inputs, in one SQLite database.

    One store can serve many sweeps: a case already computed by any sweep (same inputs, same bldclab version) is
    not computed again.

    Parameters
    ----------
    path : str or Path
        Database file (created if missing; its directory must exist), or ``":memory:"`` for a store that lives
        only as long as this object (nothing to resume from).
    timeout : float
        How long (s) to wait for another process's write lock before failing.
    create : bool
        Create the file if it does not exist (False: it must exist).

    Raises
    ------
    BldclabError
        If the file cannot be opened or created, is not a SQLite database, or holds another schema version.
    """

    def __init__(self, path: str | Path = ":memory:", *, timeout: float = 60.0, create: bool = True) -> None:
        self.path = str(path)
        if not create and self.path != ":memory:" and not Path(self.path).is_file():
            raise BldclabError("store", f"{self.path!r} does not exist")
        try:
            self._db = sqlite3.connect(self.path, timeout=timeout, isolation_level=None)
        except sqlite3.Error as exc:
            raise BldclabError("store", f"cannot open {self.path!r}: {exc}") from None
        try:
            if self.path != ":memory:":
                mode = self._db.execute("PRAGMA journal_mode=WAL").fetchone()[0]
                if str(mode).lower() != "wal":
                    raise BldclabError("store", f"{self.path!r}: cannot switch to WAL mode (got {mode!r})")
            # NORMAL in WAL mode: a commit survives the death of this process (kill -9); only an OS crash or power
            # cut can lose the last commits, and then they are recomputed. The database is never corrupted.
            self._db.execute("PRAGMA synchronous=NORMAL")
            self._db.execute("BEGIN IMMEDIATE")
            try:
                for statement in _SCHEMA.split(";"):
                    if statement.strip():
                        self._db.execute(statement)
                row = self._db.execute("SELECT value FROM meta WHERE name = 'schema'").fetchone()
                if row is None:
                    self._db.execute("INSERT INTO meta VALUES ('schema', ?)", (str(SCHEMA_VERSION),))
                elif row[0] != str(SCHEMA_VERSION):
                    raise BldclabError("store", f"{self.path!r} has store schema {row[0]}, this bldclab reads "
                                       f"schema {SCHEMA_VERSION}")
                self._db.execute("COMMIT")
            except BaseException:
                _rollback(self._db)
                raise
        except sqlite3.Error as exc:
            self._db.close()
            raise BldclabError("store", f"{self.path!r} is not a usable results store: {exc}") from None
        except BaseException:
            self._db.close()
            raise

    # ---------------------------------------------------------------------------------------------------------
    # life cycle

    def close(self) -> None:
        """Close the database connection."""
        self._db.close()

    def __enter__(self) -> Store:
        """Return the store (context manager)."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Close the store."""
        self.close()

    def __repr__(self) -> str:
        """Short description."""
        return f"<Store {self.path!r}: {len(self)} results>"

    # ---------------------------------------------------------------------------------------------------------
    # writing (one transaction per case)

    def add(self, key: str, inputs: Mapping[str, Any], case_spec: Mapping[str, Any], result: Mapping[str, Any],
            elapsed: float) -> bool:
        """Store one finished case, atomically.

        Parameters
        ----------
        key : str
            sha256 (hex) of the canonical inputs.
        inputs : mapping
            The canonical inputs (with the drive's TOML text under ``"drive"``).
        case_spec : mapping
            The case's settings as written (JSON-able).
        result : mapping
            The experiment's values (numbers).
        elapsed : float
            Worker wall time (s).

        Returns
        -------
        bool
            True if the row was added, False if the key was already stored (the store is left unchanged).
        """
        text = str(inputs["drive"])
        digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
        packed = dict(inputs)
        packed["drive"] = {"sha256": digest}
        db = self._db
        db.execute("BEGIN IMMEDIATE")
        try:
            db.execute("INSERT OR IGNORE INTO drives VALUES (?, ?)", (digest, text))
            cur = db.execute("INSERT OR IGNORE INTO results VALUES (?, ?, ?, ?, ?, ?)",
                             (key, json.dumps(packed, sort_keys=True), json.dumps(case_spec),
                              json.dumps(result), float(elapsed), _now()))
            db.execute("DELETE FROM failures WHERE key = ?", (key,))
            db.execute("COMMIT")
        except BaseException:
            _rollback(db)
            raise
        return cur.rowcount == 1

    def add_failure(self, key: str, case_spec: Mapping[str, Any], error: str) -> None:
        """Record the error of a case that failed (replacing an earlier one), atomically."""
        db = self._db
        db.execute("BEGIN IMMEDIATE")
        try:
            db.execute("INSERT OR REPLACE INTO failures VALUES (?, ?, ?, ?)",
                       (key, json.dumps(case_spec), error, _now()))
            db.execute("COMMIT")
        except BaseException:
            _rollback(db)
            raise

    # ---------------------------------------------------------------------------------------------------------
    # reading

    def __len__(self) -> int:
        """Return the number of stored results."""
        return int(self._db.execute("SELECT COUNT(*) FROM results").fetchone()[0])

    def __contains__(self, key: object) -> bool:
        """Return whether the case with this key is stored."""
        return self._db.execute("SELECT 1 FROM results WHERE key = ?", (key,)).fetchone() is not None

    def keys(self) -> list[str]:
        """Return every stored key (sorted)."""
        return [r[0] for r in self._db.execute("SELECT key FROM results ORDER BY key")]

    def results(self, keys: Iterable[str]) -> dict[str, dict[str, Any]]:
        """Return the stored result values of the given keys (keys not stored are absent from the answer)."""
        out: dict[str, dict[str, Any]] = {}
        batch: list[str] = []
        for k in keys:
            batch.append(k)
            if len(batch) == _BATCH:
                out.update(self._fetch(batch))
                batch = []
        if batch:
            out.update(self._fetch(batch))
        return out

    def _fetch(self, keys: list[str]) -> Iterator[tuple[str, dict[str, Any]]]:
        marks = ",".join("?" * len(keys))
        for key, text in self._db.execute(f"SELECT key, result FROM results WHERE key IN ({marks})", keys):
            yield key, json.loads(text)

    def inputs(self, key: str) -> dict[str, Any]:
        """Return the full canonical inputs of a stored case (the drive's motor-file text included).

        ``sha256`` of their canonical JSON (:func:`bldclab.sweep.case_key`) is ``key``.

        Raises
        ------
        KeyError
            If the key is not stored.
        """
        row = self._db.execute("SELECT inputs FROM results WHERE key = ?", (key,)).fetchone()
        if row is None:
            raise KeyError(key)
        data = json.loads(row[0])
        text = self._db.execute("SELECT toml FROM drives WHERE sha256 = ?", (data["drive"]["sha256"],)).fetchone()
        data["drive"] = text[0]
        return data

    def failures(self) -> list[tuple[str, dict[str, Any], str]]:
        """Return ``(key, case_spec, error)`` of the cases whose last run failed."""
        return [(k, json.loads(c), e) for k, c, e in
                self._db.execute("SELECT key, case_spec, error FROM failures ORDER BY finished")]

    def to_pandas(self) -> Any:
        """Return every stored case as a DataFrame: ``key``, the case's settings, the results, ``elapsed``.

        Rows are in the order the cases finished. To get one sweep's cases in case order with its axes as
        columns, use :func:`bldclab.sweep.load_results`.

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd

        rows = []
        for key, spec, result, elapsed, finished in self._db.execute(
                "SELECT key, case_spec, result, elapsed, finished FROM results ORDER BY finished, key"):
            row: dict[str, Any] = {"key": key}
            row.update(json.loads(spec))
            for name, value in json.loads(result).items():
                row[name if name not in row else f"{name}_result"] = value
            row["elapsed"] = elapsed
            row["finished"] = finished
            rows.append(row)
        return pd.DataFrame(rows)

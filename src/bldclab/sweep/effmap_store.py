"""Efficiency-map points in a sweep store: a second identical map reuses them instead of simulating.

:class:`EffMapStore` is the :class:`~bldclab.analysis.effmap.PointCache` of
:func:`~bldclab.analysis.effmap.efficiency_map` backed by a :class:`~bldclab.sweep.store.Store`. Each point is one
row of the store, keyed as a sweep case is (:func:`~bldclab.sweep.keys.case_key`): the sha256 of the canonical
JSON of its full inputs, ``{"bldclab": version, "drive": motor-file text, "control": {"class", "params"},
"experiment": {"kind": "effmap_point", "supply", "torque", "speed", "buckets"}}``. The stored result is the map's
row for the point (JSON; its floats read back bit for bit), so a map built from stored points is the map that was
computed. Like a sweep's, the key holds the bldclab version, not the C core's build: rebuild with another version
string (or use a new store) after changing the plant.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .._version import __version__
from ..analysis.effmap import FEASIBLE_TOL_PU, EffMapJob
from .keys import _plain, case_key
from .store import Store

__all__ = ["EXPERIMENT", "EffMapStore"]

#: The ``experiment.kind`` of an efficiency-map point in a store.
EXPERIMENT = "effmap_point"


class EffMapStore:
    """Efficiency-map points kept in a sweep store (:class:`~bldclab.analysis.effmap.PointCache`).

    Parameters
    ----------
    store : Store
        The store (shared with sweeps if you like: the keys cannot collide, the experiment differs).

    Attributes
    ----------
    saved : int
        Points this object wrote to the store.
    """

    def __init__(self, store: Store) -> None:
        self.store = store
        self.saved = 0
        self._texts: dict[int, str] = {}

    def _drive_text(self, job: EffMapJob) -> str:
        drive = job[0]
        text = self._texts.get(id(drive))
        if text is None:  # one map has one drive: its motor file is written once
            text = drive.to_toml()
            self._texts[id(drive)] = text
        return text

    def inputs(self, job: EffMapJob) -> dict[str, Any]:
        """Return the canonical inputs of a point (the drive's motor-file text under ``"drive"``)."""
        _, supply, control, torque, speed, buckets = job
        return {"bldclab": __version__, "drive": self._drive_text(job),
                "control": {"class": f"{type(control).__module__}:{type(control).__qualname__}",
                            "params": _plain(control, "control")},
                "experiment": {"kind": EXPERIMENT, "supply": supply, "torque": float(torque), "speed": float(speed),
                               "buckets": list(buckets), "feasible_tol_pu": FEASIBLE_TOL_PU}}

    def key(self, job: EffMapJob) -> str:
        """Return the store key of a point."""
        return case_key(self.inputs(job))

    def lookup(self, jobs: Sequence[EffMapJob]) -> list[dict[str, Any] | None]:
        """Return the stored row of each point, None where the store has none."""
        keys = [self.key(j) for j in jobs]
        found = self.store.results(keys)
        return [found.get(k) for k in keys]

    def save(self, job: EffMapJob, row: dict[str, Any]) -> None:
        """Store the row of one computed point (atomically; a point already stored is left as it is)."""
        inputs = self.inputs(job)
        spec = {"experiment": EXPERIMENT, "drive": job[0].name, "controller": type(job[2]).__name__,
                "supply": job[1], "torque_ref": float(job[3]), "speed": float(job[4])}
        if self.store.add(case_key(inputs), inputs, spec, row, 0.0):
            self.saved += 1

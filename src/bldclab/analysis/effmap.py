"""Efficiency maps over the torque-speed plane: both supplies, every loss bucket, where each supply wins.

An operating point is a torque reference ``T`` at an imposed speed ``Omega``, measured as
:func:`bldclab.analysis.experiments.steady_state` measures it (dynamometer: settle, then whole electrical periods).
Square-wave supply: :class:`~bldclab.control.SixStep` with ``reference="torque"`` (it regulates the current
``I = T / (2 k_phi)``, paper 1 (6)); sinusoidal supply: :class:`~bldclab.control.Sine` asked for ``T`` (``i_q = T /
(1.5 k_1)``, paper 1 (45)), as :func:`bldclab.analysis.compare.compare` runs them. A negative ``T`` is braking
(generating).

A point is *feasible* when the drive holds the torque asked for: ``|tau_mean - T| <= FEASIBLE_TOL_PU T_N``.
Above the drive's envelope (the current limit, or the voltage the bus can impress at that speed) it delivers less;
such points are kept in the table with ``feasible = False`` and left out of the maps and the comparison.

The loss buckets are the mean powers of :class:`~bldclab.sim.results.Metrics` named in :data:`LOSS_BUCKETS`
(:mod:`bldclab.analysis.losses`, the one place to add a new one; re-exported here); the accounting of each point
is ``p_src_total = p_shaft + sum(buckets) + p_stored + residue`` (``p_src_total``: the DC source's power with the
switching and recovery energies it supplies) with ``p_shaft = p_emf + p_cog - p_fric - p_fe``, ``p_stored`` the change
of the windings' magnetic energy over the window divided by its length (zero in an exactly periodic steady state)
and a residue of the order of the integration's energy balance
(:attr:`~bldclab.sim.results.Metrics.balance_electrical`, 1e-9 to 1e-7).

The efficiency is ``p_shaft / (p_src_total - p_stored)`` motoring and ``(p_src_total - p_stored) / p_shaft``
generating: the power the cycle takes from (gives to) the source once the window's left-over change of stored energy
is set aside. It differs from :attr:`Metrics.efficiency <bldclab.sim.results.Metrics>` (``p_shaft / p_src_total``)
by ``p_stored / p_src_total``, a few 1e-4 on the catalog drives, below the :data:`RESOLUTION` of the comparison;
with no losses it is 1 to the integration's accuracy.
"""

from __future__ import annotations

import math
import os
import time
import warnings
from collections.abc import Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import pandas as pd

from ..control import Control, Sine, SixStep
from ..errors import BldclabError, PlausibilityError, PlausibilityWarning
from ..model.motor import Drive
from ..sim import plausibility as _plaus
from .compare import VERDICT_TOLERANCE
from .experiments import map_points, steady_state
from .losses import LOSS_BUCKETS, NOT_LOSSES, loss_buckets, point_losses

__all__ = [
    "COMPARISON",
    "FEASIBLE_TOL_PU",
    "LOSS_BUCKETS",
    "NOT_LOSSES",
    "RESOLUTION",
    "EffMapJob",
    "EffMapResult",
    "PointCache",
    "efficiency_map",
    "loss_buckets",
    "map_controls",
]

#: A point is feasible when its mean torque is within this of the reference (p.u. of ``T_N``). Four times the
#: largest PWM-grid spread of the mean torque measured for :data:`bldclab.analysis.compare.VERDICT_TOLERANCE`
#: (0.005 p.u.): a point outside it misses its torque because of the drive, not of the simulation.
FEASIBLE_TOL_PU = 0.02
#: Smallest efficiency difference the comparison calls a win (absolute): the one
#: :func:`bldclab.analysis.compare.compare` resolves.
RESOLUTION = VERDICT_TOLERANCE["eta"]

SUPPLIES = ("square", "sine")
_RPM = 30.0 / math.pi

#: The comparison :func:`efficiency_map` makes, in one sentence (printed by ``bldclab effmap`` and in the report).
COMPARISON = ("Comparison at equal torque: at every point both supplies are asked for the same torque, each drawing "
              "the current it needs, so the efficiencies are at the same output (bldclab compare compares at equal "
              "current).")


def map_controls(drive: Drive, lowest_speed: float, chopping: str = "pwm-on-pwm") -> dict[str, Control]:
    """Return the controllers of the map, both taking a torque reference (N m).

    Parameters
    ----------
    drive : Drive
    lowest_speed : float
        Lowest speed of the map (rad/s): the sinusoidal controller hands off from its square-wave start at half of
        it, so every point measures the sinusoidal supply (as :func:`bldclab.analysis.compare.default_controls`).
    chopping : str
        The square wave's chopping pattern (:data:`bldclab.control.sixstep.CHOPPINGS`).

    Returns
    -------
    dict
        ``{"square": SixStep(reference="torque", chopping=...), "sine": Sine(handoff_speed=...)}``.
    """
    del drive  # the controllers configure themselves from the drive when they run
    return {"square": SixStep(reference="torque", chopping=chopping),  # type: ignore[arg-type]  # checked by SixStep
            "sine": Sine(handoff_speed=0.5 * abs(lowest_speed))}


#: One operating point of a map: drive, supply, controller, torque reference (N m), speed (rad/s), loss buckets.
EffMapJob = tuple[Drive, str, Control, float, float, tuple[str, ...]]


class PointCache(Protocol):
    """Where :func:`efficiency_map` finds points computed before and keeps new ones.

    :class:`bldclab.sweep.effmap_store.EffMapStore` keeps them in a sweep store (:class:`bldclab.sweep.store.Store`).
    """

    def lookup(self, jobs: Sequence[EffMapJob]) -> list[dict[str, Any] | None]:
        """Return the stored row of each job, None where there is none."""

    def save(self, job: EffMapJob, row: dict[str, Any]) -> None:
        """Keep the row of one computed job."""


def _run_point(job: EffMapJob) -> dict[str, Any]:
    drive, supply, control, torque, speed, buckets = job
    row: dict[str, Any] = {"supply": supply, "torque_ref": torque, "torque_ref_pu": torque / drive.T_N,
                           "speed": speed, "speed_pu": speed / drive.Omega_0, "speed_rpm": speed * _RPM}
    try:
        with _plaus.collect() as caught:  # summarised once by efficiency_map()
            point, _ = steady_state(drive, control, speed, torque)
    except PlausibilityError as exc:  # a run the guards refuse: no measurement, the point is outside the envelope
        row.update({"tau_mean": math.nan, "tau_mean_pu": math.nan, "p_in": math.nan, "p_shaft": math.nan,
                    **{b: math.nan for b in buckets}, "p_loss": math.nan, "p_stored": math.nan,
                    "residue": math.nan,
                    "efficiency": math.nan, "balance_electrical": math.nan,
                    "i_rms_a": math.nan, "i_rms_b": math.nan, "i_rms_c": math.nan, "feasible": False,
                    "note": f"refused: {exc}", "_warnings": []})
        return row
    m = point.metrics
    acc = point_losses(m, buckets)
    tol = FEASIBLE_TOL_PU * drive.T_N
    feasible = bool(abs(point.tau_mean - torque) <= tol)
    # an infeasible point says what it delivered: below the torque asked for is the envelope (current or voltage
    # limit) or a regulation that misses its reference; above it is never the envelope
    note = "" if feasible else (f"delivers {100.0 * point.tau_mean / torque:.3g} % of the torque asked for "
                                f"({point.tau_mean:.4g} of {torque:.4g} N m; tolerance {tol:.3g} N m)")
    row.update({"tau_mean": point.tau_mean, "tau_mean_pu": point.tau_mean_pu, **acc,
                "balance_electrical": m.balance_electrical,
                "i_rms_a": m.i_rms[0], "i_rms_b": m.i_rms[1], "i_rms_c": m.i_rms[2],
                "feasible": feasible, "note": note,
                "_warnings": [f"{supply} at {torque:.4g} N m, {speed:.4g} rad/s: {text}" for text in caught]})
    return row


@dataclass
class EffMapResult:
    """Outcome of :func:`efficiency_map`.

    Attributes
    ----------
    drive : Drive
    points : pandas.DataFrame
        One row per supply, torque and speed: ``supply``, ``torque_ref`` (N m), ``torque_ref_pu``, ``speed``
        (rad/s), ``speed_pu``, ``speed_rpm``, ``tau_mean`` (N m), ``tau_mean_pu``, ``p_in`` (DC source power
        with the switching energies, ``Metrics.p_src_total``, W),
        ``p_shaft`` (W), each bucket of :attr:`buckets` (W), ``p_loss`` (their sum, W), ``p_stored`` (change of
        magnetic energy over the window per second, W), ``residue`` (``p_in - p_shaft - p_loss - p_stored``, W),
        ``efficiency``, ``balance_electrical``, ``i_rms_a`` ... (A), ``feasible`` and ``note`` (why a point has no
        measurement, or what an infeasible one delivered: ``delivers 61.1 % of the torque asked for ...``).
    difference : pandas.DataFrame
        The points feasible for both supplies: ``torque_ref``, ``torque_ref_pu``, ``speed``, ``speed_pu``,
        ``speed_rpm``, ``eta_square``, ``eta_sine``, ``d_eta`` (``eta_sine - eta_square``) and ``winner``
        (``"sine"``, ``"square"`` or ``"equal"`` within :attr:`resolution`).
    torques, speeds : numpy.ndarray
        The grid (N m, rad/s).
    buckets : tuple of str
        The loss buckets in the table.
    resolution : float
        Smallest efficiency difference called a win.
    seconds : float
        Wall time of the simulations.
    cached : int
        Points taken from the cache (:class:`PointCache`) instead of simulated.
    warnings : list of str
        Plausibility warnings of the runs, each prefixed by its supply and point.
    """

    drive: Drive
    points: pd.DataFrame
    difference: pd.DataFrame
    torques: np.ndarray
    speeds: np.ndarray
    buckets: tuple[str, ...]
    resolution: float = RESOLUTION
    seconds: float = 0.0
    warnings: list[str] = field(default_factory=list)
    cached: int = 0

    def grid(self, supply: str, column: str, *, feasible_only: bool = True) -> np.ndarray:
        """Return a column of one supply as a ``(len(torques), len(speeds))`` array (nan where infeasible).

        ``supply`` may be ``"difference"`` for a column of :attr:`difference` (nan off the common feasible points).
        """
        z = np.full((self.torques.size, self.speeds.size), np.nan)
        if supply == "difference":
            df = self.difference
        elif supply in SUPPLIES:
            df = self.points[self.points.supply == supply]
            if feasible_only:
                df = df[df.feasible]
        else:
            raise BldclabError("supply", f"must be 'square', 'sine' or 'difference', got {supply!r}")
        if column not in df.columns:
            raise BldclabError("column", f"{column!r} is not a column of the map")
        ti = {float(t): j for j, t in enumerate(self.torques)}
        si = {float(s): k for k, s in enumerate(self.speeds)}
        for t, s, v in zip(df.torque_ref, df.speed, df[column], strict=True):
            z[ti[float(t)], si[float(s)]] = v
        return z

    def summary(self) -> list[str]:
        """Return short lines: best efficiency of each supply and where, feasible share, where each one wins."""
        names = {"square": "square-wave", "sine": "sinusoidal"}
        n = self.torques.size * self.speeds.size
        lines = []
        for s in SUPPLIES:
            df = self.points[(self.points.supply == s) & self.points.feasible & self.points.efficiency.notna()]
            if df.empty:
                lines.append(f"{names[s]}: no feasible point")
                continue
            best = df.loc[df.efficiency.idxmax()]
            lines.append(f"{names[s]}: best efficiency {best.efficiency:.4f} at {best.torque_ref:.3g} N m "
                         f"({best.torque_ref_pu:.2f} T_N), {best.speed_rpm:.0f} rpm ({best.speed_pu:.2f} p.u.); "
                         f"{len(df)}/{n} points feasible")
        d = self.difference
        if d.empty:
            lines.append("no point feasible for both supplies: nothing to compare")
            return lines
        for who in ("sine", "square"):
            sel = d[d.winner == who]
            by = f", by {float(np.mean(np.abs(sel.d_eta))):.4f} on average" if len(sel) else ""
            lines.append(f"{names[who]} more efficient on {len(sel) / len(d):.0%} of the common feasible plane "
                         f"({len(sel)}/{len(d)} points{by})")
        eq = int((d.winner == "equal").sum())
        lines.append(f"equal within {self.resolution:g} (the resolved difference) on {eq / len(d):.0%} "
                     f"({eq}/{len(d)} points)")
        return lines


def _difference(points: pd.DataFrame, resolution: float) -> pd.DataFrame:
    keys = ["torque_ref", "torque_ref_pu", "speed", "speed_pu", "speed_rpm"]
    ok = points[points.feasible & points.efficiency.notna()]
    sq = ok[ok.supply == "square"][[*keys, "efficiency"]].rename(columns={"efficiency": "eta_square"})
    si = ok[ok.supply == "sine"][[*keys, "efficiency"]].rename(columns={"efficiency": "eta_sine"})
    d = sq.merge(si, on=keys, how="inner").sort_values(["torque_ref", "speed"]).reset_index(drop=True)
    d["d_eta"] = d.eta_sine - d.eta_square
    d["winner"] = np.where(d.d_eta > resolution, "sine", np.where(d.d_eta < -resolution, "square", "equal"))
    return d


def _axis(name: str, values: Sequence[float] | np.ndarray) -> np.ndarray:
    a = np.asarray(values, dtype=float)
    if a.ndim != 1 or a.size < 1:
        raise BldclabError(name, "needs at least one value")
    if not np.all(np.isfinite(a)) or np.any(a == 0):
        raise BldclabError(name, "values must be finite and non-zero")
    if np.unique(a).size != a.size:
        raise BldclabError(name, "values must be distinct")
    return a


#: Largest number of points sent to a worker at a time when they go to a cache: an interrupted map keeps every
#: chunk that finished.
_SAVE_CHUNK = 32


def _compute(jobs: list[EffMapJob], executor: Executor | None, n_pool: int,
             cache: PointCache | None) -> list[dict[str, Any]]:
    """Run the points (``n_pool`` > 0: on a process pool of that many, in chunks).

    With a cache, each point is saved as its result arrives, while the workers run the next ones.
    """
    chunksize = max(1, len(jobs) // (4 * n_pool)) if n_pool > 0 else 1
    if cache is None:
        return map_points(_run_point, jobs, executor, chunksize=chunksize)
    return map_points(_run_point, jobs, executor, chunksize=min(chunksize, _SAVE_CHUNK),
                      each=lambda k, row: cache.save(jobs[k], row))


def efficiency_map(drive: Drive, torques: Sequence[float] | np.ndarray, speeds: Sequence[float] | np.ndarray,
                   supplies: Sequence[str] = SUPPLIES, workers: int | None = None, *,
                   executor: Executor | None = None, controls: dict[str, Control] | None = None,
                   resolution: float = RESOLUTION, cache: PointCache | None = None, summarise: bool = True
                   ) -> EffMapResult:
    """Map efficiency and losses of the supplies over a torque x speed grid.

    Parameters
    ----------
    drive : Drive
    torques : sequence of float
        Torque references (N m), non-zero; negative: braking (generating).
    speeds : sequence of float
        Imposed mechanical speeds (rad/s), positive.
    supplies : sequence of {"square", "sine"}
        The supplies mapped; the difference map needs both.
    workers : int, optional
        Local processes (default: all cores; 1: in this process). With a
        :class:`~concurrent.futures.ProcessPoolExecutor` as ``executor``: its number of processes, for which the points
        are sent in chunks (else one at a time).
    executor : concurrent.futures.Executor, optional
        Where the points run instead: any executor with ``map`` (a Dask cluster's ``Client.get_executor()``, a
        pool the caller keeps to draw the figures on it next). Results do not depend on where the points run.
    controls : dict, optional
        ``{"square": control, "sine": control}`` taking a torque reference; default :func:`map_controls`.
    resolution : float
        Smallest efficiency difference called a win (default :data:`RESOLUTION`).
    cache : PointCache, optional
        Points found there are not simulated again; new points are saved to it as they arrive, while the next ones
        run (e.g. :class:`bldclab.sweep.effmap_store.EffMapStore`, a sweep store). The result is the same either way.
    summarise : bool
        Issue one :class:`~bldclab.errors.PlausibilityWarning` summarising the points' warnings
        (:func:`bldclab.sim.plausibility.summary`); False leaves that to the caller (``bldclab effmap`` does it last,
        or lists them all with ``--verbose``).

    Returns
    -------
    EffMapResult
    """
    T = _axis("torques", torques)
    W = _axis("speeds", speeds)
    if np.any(W < 0):
        raise BldclabError("speeds", "must be positive (a braking point is a negative torque)")
    for s in supplies:
        if s not in SUPPLIES:
            raise BldclabError("supplies", f"must be 'square' or 'sine', got {s!r}")
    if isinstance(workers, bool) or (workers is not None and (not isinstance(workers, int) or workers < 1)):
        raise BldclabError("workers", f"must be an integer >= 1, got {workers!r}")
    ctl = controls or map_controls(drive, float(np.min(W)))
    buckets = loss_buckets()
    jobs = [(drive, s, ctl[s], float(t), float(w), buckets) for s in supplies for t in T for w in W]
    t0 = time.perf_counter()
    n_workers = workers or os.cpu_count() or 1
    found = cache.lookup(jobs) if cache is not None else [None] * len(jobs)
    todo = [jobs[k] for k, row in enumerate(found) if row is None]
    if executor is not None:
        new = _compute(todo, executor, n_workers if isinstance(executor, ProcessPoolExecutor) and workers else 0, cache)
    elif n_workers <= 1 or len(todo) <= 1:
        new = _compute(todo, None, 0, cache)
    else:
        with ProcessPoolExecutor(max_workers=n_workers) as pool:
            new = _compute(todo, pool, n_workers, cache)
    fresh = iter(new)
    rows = [row if row is not None else next(fresh) for row in found]
    seconds = time.perf_counter() - t0
    caught = [text for row in rows for text in row.pop("_warnings")]
    points = pd.DataFrame(rows)
    res = EffMapResult(drive=drive, points=points, difference=_difference(points, resolution), torques=T, speeds=W,
                       buckets=buckets, resolution=resolution, seconds=seconds, warnings=caught,
                       cached=len(jobs) - len(todo))
    line = _plaus.summary(caught, len(jobs))
    if line and summarise:
        warnings.warn(line, PlausibilityWarning, stacklevel=2)
    return res

"""The Hall study: mean torque, torque ripple and efficiency of each supply against the Hall sensors' placement error.

Every point is a :func:`~bldclab.analysis.experiments.steady_state` run at one operating point (default: the rated
torque ``T_N`` at half the no-load speed ``Omega_0``) of the drive with ``Sensors.hall_error`` set to an error
pattern; everything else of the drive (its Hall hysteresis, delays and filters included) stays as it is. Three
patterns of an error ``delta`` (electrical):

- ``one``: sensor a misplaced by ``delta``, b and c in place (unequal sectors: two of the six edges move);
- ``common``: all three by ``delta`` (equal sectors, the whole Hall frame turned: a pure angle offset);
- ``alternating``: ``(+delta, -delta, +delta)``, a fixed sign pattern standing for a random one (sectors of
  ``60 +- 2 delta`` degrees: the unequal-sector case with the largest spread for a given ``|delta|``).

The controllers are a list of ``(label, factory)`` pairs (:data:`VARIANTS`); a factory takes the drive and the speed
and returns a :class:`~bldclab.control.Control`. Adding a variant is one more pair; a third element, a mapping of
:func:`~bldclab.analysis.experiments.steady_state` keywords (e.g. ``{"settle_periods": 20}`` for a controller that
learns during its first revolutions), changes how that variant's points are run. Theory and how to read the
results: docs/hall.md.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from ..control import Control, Lu, Sine, SixStep
from ..errors import BldclabError, PlausibilityError
from ..model.motor import Drive
from ..sim import plausibility as _plaus
from ..sim.hallcal import calibrate
from .experiments import map_points, steady_state

__all__ = ["CASES", "DEFAULT_ERRORS_DEG", "VARIANTS", "CalibrationError", "Factory", "HallStudyResult", "Variant",
           "calibrated_table", "error_pattern", "hall_study"]

#: Makes a variant's controller for the drive (its Hall errors set) and the speed (rad/s).
Factory = Callable[[Drive, float], Control]
#: A controller variant of the study: its label, its factory and, optionally, steady_state keywords for its runs.
Variant = tuple[str, Factory] | tuple[str, Factory, Mapping[str, Any]]

#: Error patterns (see the module docstring).
CASES = ("one", "common", "alternating")

#: Default placement errors, electrical degrees.
DEFAULT_ERRORS_DEG = (0.0, 2.0, 4.0, 6.0, 8.0, 10.0)


def square_wave(drive: Drive, speed: float) -> Control:
    """Square-wave supply: six-step, commutating on the Hall edges, torque reference."""
    del drive, speed
    return SixStep(reference="torque")


def sine_46(drive: Drive, speed: float) -> Control:
    """Sinusoidal supply with paper 1's interpolated Hall angle (46)."""
    del drive
    return Sine(handoff_speed=0.25 * abs(speed))


def sine_pll(drive: Drive, speed: float) -> Control:
    """Sinusoidal supply with the tracking angle estimator on the Hall edges (``Sine(angle="pll")``)."""
    del drive
    return Sine(angle="pll", handoff_speed=0.25 * abs(speed))


def lu(drive: Drive, speed: float) -> Control:
    """Paper 2's torque controller (Lu, Zhang, Qu)."""
    del drive, speed
    return Lu()


class CalibrationError(Exception):
    """The open-loop Hall calibration of a drive did not give a table (its reasons in the message)."""


@functools.lru_cache(maxsize=64)
def calibrated_table(drive: Drive) -> tuple[float, ...]:
    """Return the Hall edge table the C routine learns on this drive (open loop, as firmware does at start-up).

    The routine runs on the drive's own sensors (placement errors, hysteresis, delays, filters): what a controller
    would carry into its run. Cached per drive and process.

    Raises
    ------
    CalibrationError
        If the routine flags its result (no table).
    """
    cal = calibrate(drive, "open-loop")
    if not cal.ok:
        raise CalibrationError(f"calibration failed: {'|'.join(cal.reasons)}")
    return cal.table


def square_wave_cal(drive: Drive, speed: float) -> Control:
    """Square-wave supply with the calibrated edge table (commutation at the nominal angles)."""
    del speed
    return SixStep(reference="torque", hall_table=calibrated_table(drive))


def sine_46_cal(drive: Drive, speed: float) -> Control:
    """Sinusoidal supply, (46) on the calibrated edge table."""
    return Sine(handoff_speed=0.25 * abs(speed), hall_table=calibrated_table(drive))


def sine_pll_cal(drive: Drive, speed: float) -> Control:
    """Sinusoidal supply, tracking estimator on the calibrated edge table."""
    return Sine(angle="pll", handoff_speed=0.25 * abs(speed), hall_table=calibrated_table(drive))


def lu_cal(drive: Drive, speed: float) -> Control:
    """Paper 2's torque controller on the calibrated edge table (commutation at the nominal angles)."""
    del speed
    return Lu(hall_table=calibrated_table(drive))


#: The controllers of the study, in table order: each supply as is, then after the open-loop calibration
#: (:func:`calibrated_table`).
VARIANTS: tuple[Variant, ...] = (
    ("square-wave", square_wave),
    ("sine (46)", sine_46),
    ("sine (pll)", sine_pll),
    ("lu", lu),
    ("square-wave, cal.", square_wave_cal),
    ("sine (46), cal.", sine_46_cal),
    ("sine (pll), cal.", sine_pll_cal),
    ("lu, cal.", lu_cal),
)


def error_pattern(case: str, delta: float) -> tuple[float, float, float]:
    """Return the per-sensor placement errors (a, b, c) of a pattern (rad).

    Parameters
    ----------
    case : {"one", "common", "alternating"}
        The pattern.
    delta : float
        The error (rad, electrical).

    Returns
    -------
    tuple of float
        ``Sensors.hall_error``.
    """
    if case == "one":
        return (delta, 0.0, 0.0)
    if case == "common":
        return (delta, delta, delta)
    if case == "alternating":
        return (delta, -delta, delta)
    raise BldclabError("case", f"must be one of {', '.join(CASES)}, got {case!r}")


_NAN_ROW = {"tau_mean": math.nan, "tau_mean_pu": math.nan, "ripple_sampled": math.nan, "ripple_sampled_pu": math.nan,
            "ripple_ma_pu": math.nan, "efficiency": math.nan}


def _run(job: tuple[Drive, str, Factory, float, float, Mapping[str, Any]]) -> dict[str, Any]:
    drive, label, factory, speed, torque, opts = job
    try:
        with _plaus.collect() as caught:
            point, _ = steady_state(drive, factory(drive, speed), speed, torque, **opts)
    except PlausibilityError as exc:  # refused by the guards: no measurement
        return {**_NAN_ROW, "note": f"refused: {exc}", "_warnings": []}
    except CalibrationError as exc:  # no table to run with
        return {**_NAN_ROW, "note": str(exc), "_warnings": []}
    return {"tau_mean": point.tau_mean, "tau_mean_pu": point.tau_mean_pu, "ripple_sampled": point.ripple_sampled,
            "ripple_sampled_pu": point.ripple_sampled_pu, "ripple_ma_pu": point.ripple_ma_pu,
            "efficiency": point.efficiency, "note": "",
            "_warnings": [f"{label}, hall_error {drive.sensors.hall_error}: {w}" for w in caught]}


@dataclass
class HallStudyResult:
    """Outcome of :func:`hall_study`.

    Attributes
    ----------
    drive : str
        Drive name.
    speed : float
        Imposed mechanical speed (rad/s).
    torque : float
        Torque reference (N m).
    T_N : float
        The drive's torque base (N m).
    points : pandas.DataFrame
        One row per variant, case and error: ``variant, case, error_deg, hall_error_a/b/c`` (rad), ``tau_mean``
        (N m), ``tau_mean_pu``, ``tau_rel`` (mean torque over the variant's at zero error), ``ripple_sampled``
        (N m, max - min of the torque at the controller samples), ``ripple_sampled_pu``, ``ripple_ma_pu`` (of the
        PWM-period moving average), ``efficiency`` (-), ``note`` (why a point has no values).
    seconds : float
        Wall time of the simulations (s).
    warnings : list of str
        Plausibility warnings of the runs.
    """

    drive: str
    speed: float
    torque: float
    T_N: float
    points: pd.DataFrame
    seconds: float
    warnings: list[str] = field(default_factory=list)

    def table(self) -> str:
        """Return the study as a text table: one line per variant and case, one column group per error."""
        errs = sorted(self.points.error_deg.unique())
        wv = max([len("variant"), *(len(str(v)) for v in self.points.variant)]) + 2
        head = f"{'variant':<{wv}}{'case':<12}{'error (deg)':>11}" + "".join(f" {e:>9.3g}" for e in errs)
        lines = [head]
        for (var, case), g in self.points.groupby(["variant", "case"], sort=False):
            g = g.set_index("error_deg")
            for name, col, scale in (("tau/tau0", "tau_rel", 1.0), ("ripple pu", "ripple_sampled_pu", 1.0),
                                     ("eff %", "efficiency", 100.0)):
                vals = "".join(f" {scale * g.loc[e, col]:>9.4g}" if e in g.index else f" {'':>9}" for e in errs)
                lines.append(f"{var if name == 'tau/tau0' else '':<{wv}}{case if name == 'tau/tau0' else '':<12}"
                             f"{name:>11}{vals}")
        return "\n".join(lines)


def hall_study(drive: Drive, *, errors: Sequence[float] | None = None, cases: Sequence[str] = CASES,
               variants: Sequence[Variant] = VARIANTS, speed: float | None = None, torque: float | None = None,
               executor: Executor | None = None) -> HallStudyResult:
    """Run every controller variant at one operating point against the Hall placement error.

    Parameters
    ----------
    drive : Drive
        The drive; its ``sensors.hall_error`` is replaced by each pattern, the rest kept.
    errors : sequence of float, optional
        Placement errors (rad, electrical), each in [0, pi/6) (default :data:`DEFAULT_ERRORS_DEG`).
    cases : sequence of str
        Error patterns (:data:`CASES`, :func:`error_pattern`).
    variants : sequence of (str, callable) or (str, callable, mapping)
        ``(label, factory)`` pairs, ``factory(drive, speed) -> Control`` (module-level functions for a process
        pool), optionally with a mapping of :func:`~bldclab.analysis.experiments.steady_state` keywords for that
        variant's runs. Default :data:`VARIANTS`.
    speed : float, optional
        Imposed mechanical speed (rad/s), default ``0.5 Omega_0``.
    torque : float, optional
        Torque reference (N m), default ``T_N``.
    executor : concurrent.futures.Executor, optional
        Where the runs go (:func:`~bldclab.analysis.experiments.map_points`); serial if omitted.

    Returns
    -------
    HallStudyResult
        The points (the zero-error point is run once per variant, always, and shared by the cases).

    Raises
    ------
    BldclabError
        On a bad error list, case, variant, speed or torque (before any simulation).
    """
    errs = [math.radians(e) for e in DEFAULT_ERRORS_DEG] if errors is None else list(errors)
    if not errs:
        raise BldclabError("errors", "is empty")
    for j, e in enumerate(errs):
        if isinstance(e, bool) or not isinstance(e, int | float | np.floating | np.integer) or \
                not 0.0 <= float(e) < math.pi / 6.0:
            raise BldclabError(f"errors[{j}]", f"must be a number in [0, 30) deg electrical, got {e!r}")
    if not cases:
        raise BldclabError("cases", "is empty")
    for c in cases:
        error_pattern(c, 0.0)
    if not variants:
        raise BldclabError("variants", "is empty")
    if not all(isinstance(v, tuple) and len(v) in (2, 3) for v in variants):
        raise BldclabError("variants", "needs (label, factory) or (label, factory, steady_state keywords) tuples")
    labels = [v[0] for v in variants]
    opts: list[Mapping[str, Any]] = [v[2] if len(v) == 3 else {} for v in variants]
    if len(set(labels)) != len(labels) or not all(isinstance(lb, str) and lb for lb in labels) or \
            not all(callable(v[1]) for v in variants) or not all(isinstance(o, Mapping) for o in opts):
        raise BldclabError("variants", "needs (label, factory[, keywords]) tuples with distinct non-empty labels, "
                           "callable factories and a mapping of keywords")
    w = 0.5 * drive.Omega_0 if speed is None else speed
    tq = drive.T_N if torque is None else torque
    for name, v in (("speed", w), ("torque", tq)):
        if isinstance(v, bool) or not isinstance(v, int | float | np.floating | np.integer) or not math.isfinite(v) \
                or v == 0.0:
            raise BldclabError(name, f"must be a finite non-zero number, got {v!r}")
    w, tq = float(w), float(tq)
    keys: list[tuple[str, str, float]] = []
    jobs: list[tuple[Drive, str, Factory, float, float, Mapping[str, Any]]] = []
    index: dict[tuple[str, tuple[float, float, float]], int] = {}
    zero = (0.0, 0.0, 0.0)
    for (label, factory, *_), opt in zip(variants, opts, strict=True):
        index[(label, zero)] = len(jobs)  # the reference of tau_rel, run even when 0 is not among the errors
        jobs.append((drive.replace(sensors__hall_error=zero), label, factory, w, tq, dict(opt)))
        for case in cases:
            for e in errs:
                pattern = error_pattern(case, float(e))
                if (label, pattern) not in index:
                    index[(label, pattern)] = len(jobs)
                    jobs.append((drive.replace(sensors__hall_error=pattern), label, factory, w, tq, dict(opt)))
                keys.append((label, case, float(e)))
    t0 = time.perf_counter()
    results = map_points(_run, jobs, executor)
    seconds = time.perf_counter() - t0
    rows = []
    warnings: list[str] = []
    for r in results:
        warnings += r["_warnings"]
    for label, case, e in keys:
        pattern = error_pattern(case, e)
        r = results[index[(label, pattern)]]
        tau0 = results[index[(label, zero)]]["tau_mean"]
        rows.append({"variant": label, "case": case, "error_deg": math.degrees(e), "hall_error_a": pattern[0],
                     "hall_error_b": pattern[1], "hall_error_c": pattern[2],
                     **{k: v for k, v in r.items() if k != "_warnings"},
                     "tau_rel": r["tau_mean"] / tau0 if tau0 and math.isfinite(tau0) else math.nan})
    cols = ["variant", "case", "error_deg", "hall_error_a", "hall_error_b", "hall_error_c", "tau_mean", "tau_mean_pu",
            "tau_rel", "ripple_sampled", "ripple_sampled_pu", "ripple_ma_pu", "efficiency", "note"]
    return HallStudyResult(drive=drive.name, speed=w, torque=tq, T_N=drive.T_N, points=pd.DataFrame(rows)[cols],
                           seconds=seconds, warnings=warnings)

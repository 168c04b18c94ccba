"""Square-wave vs sinusoidal supply of one drive, by closed form and by switching-level simulation (paper 1).

:func:`compare` runs both supplies at the same current limits on an imposed-speed grid (the paper's
dynamometer), measures mean torque, ripple and efficiency over whole electrical periods, puts paper 1's closed
forms beside them, and writes a short verdict per speed range.

Square-wave supply: :class:`~bldclab.control.SixStep` regulating the injected current at ``I_N`` (the paper's
premise, section II.B). Sinusoidal supply: :class:`~bldclab.control.Sine` asked for the nominal torque ``T_sN``
(13); above its base speed it lowers the current so the modulation stays linear, (23)-(25). Both see the same DC
bus and the same rms current ``sqrt(2/3) I_N`` below base speed, (7)-(8).
"""

from __future__ import annotations

import dataclasses
import os
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from ..control import Control, Sine, SixStep
from ..errors import BldclabError, PlausibilityWarning
from ..model import analytic
from ..model.limits import TOP_SPEED_PU
from ..model.motor import Drive
from ..sim import plausibility as _plaus
from .experiments import base_speed, map_points, steady_state
from .losses import copper_only_efficiency, loss_buckets, point_losses

__all__ = ["COMPARISON", "EFFICIENCY_COUNTS", "IDEAL_LIMITER", "VERDICT_TOLERANCE", "CompareResult",
           "base_speed_table", "bottom_line",
           "compare", "default_controls", "efficiency_table", "speed_grid"]

SUPPLIES = ("square", "sine")

#: The comparison :func:`compare` makes, in one sentence (printed by ``bldclab compare`` and in the report).
COMPARISON = ("Comparison at equal current (paper 1): the square wave carries I_N and the sinusoid the same rms "
              "current (peak 2/sqrt(3) I_N, lowered above its base speed), each giving its own torque, so the "
              "efficiencies are at different torques (bldclab effmap compares at equal torque).")


#: Paper 1's ideal current limiter: the square wave's paper-comparable point (``TR_avg_pu``) on the averaged inverter.
IDEAL_LIMITER = SixStep(regulation="ideal", commutation="encoder", timed=True)


def default_controls(drive: Drive, lowest_speed_pu: float = 0.05,
                     chopping: str = "pwm-on-pwm") -> dict[str, tuple[Control, float]]:
    """Return the two supplies as paper 1 compares them: controller and its reference.

    The sinusoidal controller's hand-off from its square-wave start is set below the lowest speed compared (paper 1
    hands off at 0.1 Omega_N because its Hall-based angle needs speed; at an imposed constant speed the angle is
    accurate lower too), so every point measures the sinusoidal supply.

    Parameters
    ----------
    drive : Drive
    lowest_speed_pu : float
        Lowest speed compared (p.u. of ``Omega_0``).
    chopping : str
        The square wave's chopping pattern (:data:`bldclab.control.sixstep.CHOPPINGS`; default PWM-on-PWM).

    Returns
    -------
    dict
        ``{"square": (SixStep(chopping=...), I_N [A]), "sine": (Sine(...), T_sN [N m])}``.
    """
    T_sN = analytic.t_sN(drive)
    handoff = 0.5 * lowest_speed_pu * drive.Omega_0
    square = SixStep(chopping=chopping)  # type: ignore[arg-type]  # a str checked by SixStep against CHOPPINGS
    return {"square": (square, drive.motor.I_N), "sine": (Sine(handoff_speed=handoff), T_sN)}


def speed_grid(n: int, lo: float = 0.05, hi: float = TOP_SPEED_PU) -> list[float]:
    """Return ``n`` equally spaced per-unit speeds from ``lo`` to ``hi``."""
    if n < 2:
        raise BldclabError("--speeds", f"needs at least 2 speeds, got {n}")
    return [float(w) for w in np.linspace(lo, hi, n)]


def _run_point(args: tuple[Drive, str, Control, float, float, int]) -> dict[str, Any]:
    drive, supply, control, ref, w_pu, pwm_phases = args
    with _plaus.collect() as caught:  # recorded here, in the worker, and summarised once by compare()
        point, _ = steady_state(drive, control, w_pu * drive.Omega_0, ref, pwm_phases=pwm_phases)
    m = point.metrics
    T_N = drive.T_N
    row: dict[str, Any] = {"supply": supply, "Omega_pu": w_pu, "Omega": point.speed, "T_pu": point.tau_mean_pu,
           "TR_pu": point.ripple_sampled_pu, "TR_inst_pu": point.ripple_pu, "TR_ma_pu": point.ripple_ma_pu,
           "T": point.tau_mean, "TR": point.ripple_sampled, "tau_std_pu": m.tau_std / T_N,
           "eta": point.efficiency,
           "p_src": m.p_src_total, "p_cu": m.p_cu, "p_inv": m.p_sw + m.p_diode + m.p_Rsrc + m.p_swloss + m.p_rr,
           "i_rms": float(np.mean(m.i_rms)),
           "i_peak": float(max(m.i_peak)), "balance": m.balance_electrical,
           "_warnings": [f"{supply} at {w_pu:.3g} p.u.: {text}" for text in caught]}
    acc = point_losses(m, loss_buckets())
    row["_eff"] = {"eta_sim_copper": copper_only_efficiency(m), "eta_sim_full": acc.pop("efficiency"),
                   "p_m": m.p_emf + m.p_cog, **acc}
    if pwm_phases > 1:
        for key, rng in (("T_pu", point.tau_mean_range), ("TR_pu", point.ripple_sampled_range),
                         ("TR_ma_pu", point.ripple_ma_range)):
            row[f"{key}_min"], row[f"{key}_max"] = rng[0] / T_N, rng[1] / T_N
    # the paper-comparable point, its exact instantaneous extremes on the averaged inverter (no PWM ripple): the
    # sinusoidal supply's controller, and for the square wave paper 1's ideal current limiter (commutation at the
    # exact angles, the incoming current held in continuous time), which a sampled controller approaches only while
    # a commutation spans several PWM periods; that one's averaged point is kept as T_avg_ctrl_pu, TR_avg_ctrl_pu
    drive_avg = drive if drive.inverter.model == "average" else dataclasses.replace(
        drive, inverter=dataclasses.replace(drive.inverter, model="average"))
    runs = [("ctrl", control)]
    if supply == "square":
        runs.append(("ideal", IDEAL_LIMITER))
    for kind, ctl in runs:
        if kind == "ctrl" and drive.inverter.model == "average":
            avg = point
        else:
            d_run = drive_avg
            if kind == "ideal" and d_run.inverter.R_src > 0.0:  # the limiter holds the current on an ideal source
                d_run = dataclasses.replace(d_run, inverter=dataclasses.replace(d_run.inverter, R_src=0.0))
            with _plaus.collect() as caught_avg:
                avg, _ = steady_state(d_run, ctl, w_pu * drive.Omega_0, ref)
            # the same operating point: only what the switching run did not already say
            label = "averaged inverter" if kind == "ctrl" else "ideal current limiter"
            row["_warnings"] += [f"{supply} at {w_pu:.3g} p.u., {label}: {text}" for text in caught_avg
                                 if text not in caught]
        row[f"T_avg_{kind}_pu"], row[f"TR_avg_{kind}_pu"] = avg.tau_mean_pu, avg.ripple_pu
    key = "ideal" if supply == "square" else "ctrl"
    row["T_avg_pu"], row["TR_avg_pu"] = row[f"T_avg_{key}_pu"], row[f"TR_avg_{key}_pu"]
    row.pop("T_avg_ideal_pu", None)
    row.pop("TR_avg_ideal_pu", None)
    return row


def _run_base_speed(args: tuple[Drive, str]) -> float:
    drive, supply = args
    try:
        return base_speed(drive, supply)
    except BldclabError:
        return float("nan")  # the condition fails down to 0.05 p.u.: no base speed in the searched range


def base_speed_table(drive: Drive, simulated: dict[str, float], table1: Any) -> pd.DataFrame:
    """Return the base speeds side by side: closed form (R = 0), numeric with R, simulated (p.u. of Omega_0).

    Parameters
    ----------
    drive : Drive
    simulated : dict
        ``{"square": ..., "sine": ...}`` from :func:`bldclab.analysis.experiments.base_speed`.
    table1 : analytic.Table1
        The drive's Table I (:func:`bldclab.model.analytic.table1`).

    Returns
    -------
    pandas.DataFrame
        Columns ``supply``, ``closed_form_pu`` ((21) sinusoidal, (30) square wave), ``equation``, ``numeric_R_pu``
        (:func:`bldclab.model.analytic.omega_sB_numeric_pu` / :func:`~bldclab.model.analytic.omega_qB_numeric_pu`),
        ``simulated_pu`` and ``simulated_rpm`` (nan where the search found none).
    """
    rows = []
    for supply, eq, cf, num in (("sine", "(21)", table1.Omega_sB_pu, table1.Omega_sB_R_pu),
                                ("square", "(30)", table1.Omega_qB_pu, table1.Omega_qB_R_pu)):
        w = simulated[supply]
        rows.append({"supply": supply, "equation": eq, "closed_form_pu": cf, "numeric_R_pu": num,
                     "simulated_pu": w, "simulated_rpm": w * drive.Omega_0 * 60.0 / (2.0 * np.pi)})
    return pd.DataFrame(rows)


@dataclass
class CompareResult:
    """Outcome of :func:`compare`.

    Attributes
    ----------
    drive : Drive
    simulated : pandas.DataFrame
        One row per supply and speed: per-unit and SI mean torque; ripple of the switching drive at the controller
        samples ``TR``, instantaneous (exact extremes, with PWM) ``TR_inst`` and of its continuous one-PWM-period
        average ``TR_ma``; the paper-comparable point on the averaged inverter, ``T_avg_pu`` and ``TR_avg_pu``
        (exact extremes, no PWM: the ripple paper 1's closed forms describe, and the one the verdict compares; for
        the square wave with paper 1's ideal current limiter, :data:`IDEAL_LIMITER`), and the compared controller on
        the averaged inverter, ``T_avg_ctrl_pu`` and ``TR_avg_ctrl_pu`` (the same for the sinusoidal supply);
        efficiency; powers; currents; energy-balance residue.
    analytic : pandas.DataFrame
        Paper 1's closed forms on the same speeds (:func:`bldclab.model.analytic.characteristic`).
    table1 : analytic.Table1
        Paper 1's Table I for the drive (with the R-aware numeric base speeds).
    base_speeds : pandas.DataFrame or None
        :func:`base_speed_table`: (21)/(30), the numeric values with R and the simulated base speeds
        (:func:`bldclab.analysis.experiments.base_speed`); None if not asked for.
    pwm_phases : int
        PWM-grid phases per point (:func:`bldclab.analysis.experiments.steady_state`); with more than one,
        ``simulated`` has
        ``T_pu_min``, ``T_pu_max``, ``TR_pu_min``, ``TR_pu_max``, ``TR_ma_pu_min``, ``TR_ma_pu_max`` too.
    verdict : list of str
        First the bottom line (:func:`bottom_line`), then where each supply wins and by how much (speeds in p.u.
        and rpm), and where they are equal (difference below
        :data:`VERDICT_TOLERANCE`, or the PWM-phase spread if larger); notes where the ripple at the samples misses
        part of the commutation (``TR_ma_pu`` above ``TR_pu`` by more than :data:`SAMPLING_GAP_PU` and 20 %); the
        base speeds.
    seconds : float
        Wall time of the simulations.
    warnings : list of str
        Plausibility warnings of the runs (:mod:`bldclab.sim.plausibility`), each prefixed by its supply and speed
        (repeats kept); :func:`compare` issues one :class:`~bldclab.errors.PlausibilityWarning` summarising them.
        :func:`bldclab.report.bundle.compare_files` and :func:`~bldclab.report.bundle.compare_outputs` add those of
        the waveforms and paper 1's figures they run.
    not_applicable : list of str
        Why paper 1's closed forms (the ``analytic`` columns) do not describe this drive
        (:func:`bldclab.model.analytic.applicability`); empty where their premises hold.
    efficiency : pandas.DataFrame or None
        :func:`efficiency_table`: per supply and speed the efficiency by each loss count of
        :data:`EFFICIENCY_COUNTS` (paper 1's copper-only closed forms with 3 P_R and with the consistent 2 R I_N^2,
        the simulated copper-only and the simulated full-loss efficiency) and the loss buckets (W).
    commutation : str
        How many PWM periods the square-wave commutation lasts (:func:`bldclab.model.analytic.commutation_premise`);
        below about three the verdict repeats it as a premise.
    controls : dict
        The controllers and references compared, ``{"square": (control, ref), "sine": (control, ref)}``: the
        waveforms and the manifest of the results (:func:`bldclab.report.bundle.compare_outputs`) use the same.
    comparison : str
        Which comparison this is, in one sentence (:data:`COMPARISON`: equal current).
    """

    drive: Drive
    simulated: pd.DataFrame
    analytic: pd.DataFrame
    table1: Any
    base_speeds: pd.DataFrame | None = None
    pwm_phases: int = 1
    verdict: list[str] = field(default_factory=list)
    seconds: float = 0.0
    warnings: list[str] = field(default_factory=list)
    not_applicable: list[str] = field(default_factory=list)
    efficiency: pd.DataFrame | None = None
    controls: dict[str, tuple[Control, float]] = field(default_factory=dict)
    commutation: str = ""
    comparison: str = COMPARISON


#: The efficiency columns of :attr:`CompareResult.efficiency`, each with the loss count it uses.
EFFICIENCY_COUNTS: dict[str, str] = {
    "eta_paper_3PR": "paper 1 (38)/(39), copper loss 3 P_R,pu as printed in (36)",
    "eta_consistent_2PR": "(38)/(39) with the consistent copper loss 2 R I_N^2 (two phases conduct I_N)",
    "eta_sim_copper": "simulated, copper loss only (the actual currents: commutation and PWM ripple)",
    "eta_sim_full": "simulated, every loss bucket",
}


def efficiency_table(drive: Drive, simulated: pd.DataFrame) -> pd.DataFrame:
    """Return paper 1's efficiency comparison extended: closed forms beside the simulated copper-only and full losses.

    Parameters
    ----------
    drive : Drive
    simulated : pandas.DataFrame
        One row per supply and speed with ``supply``, ``Omega_pu``, ``eta_sim_copper``
        (:func:`bldclab.analysis.losses.copper_only_efficiency`), ``eta_sim_full`` (the efficiency of
        :func:`bldclab.analysis.losses.point_losses`) and the powers of
        :func:`~bldclab.analysis.losses.point_losses` (W).

    Returns
    -------
    pandas.DataFrame
        ``supply``, ``Omega_pu``, the four columns of :data:`EFFICIENCY_COUNTS` (``eta_paper_3PR``: (38) square
        wave, (39) sinusoidal with (36)'s ``3 P_R,pu``, :func:`bldclab.model.analytic.p_lCu_pu`;
        ``eta_consistent_2PR``: the same with ``2 R I_N^2`` on the base ``T_N Omega_0``,
        :func:`bldclab.model.analytic.p_lCu_consistent_pu`; both NaN above the base speeds (21), (30)), then
        ``p_in``, ``p_shaft``, ``p_m`` (electromagnetic power), each loss bucket, ``p_loss``, ``p_stored`` and
        ``residue`` (W).
    """
    df = simulated.copy()
    th = analytic.theta_m(drive)
    w = df["Omega_pu"].to_numpy(dtype=float)
    square = (df["supply"] == "square").to_numpy()
    for col, pcu in (("eta_paper_3PR", analytic.p_lCu_pu(drive)),
                     ("eta_consistent_2PR", analytic.p_lCu_consistent_pu(drive))):
        df[col] = np.where(square, np.asarray(analytic.eta_q(w, th, pcu)), np.asarray(analytic.eta_s(w, th, pcu)))
    first = ["supply", "Omega_pu", *EFFICIENCY_COUNTS]
    return df[first + [c for c in df.columns if c not in first]]


def _progress(total: int, enabled: bool) -> Callable[[int], None]:
    start = time.perf_counter()
    if not enabled:
        return lambda done: None

    def show(done: int) -> None:
        el = time.perf_counter() - start
        eta = el / done * (total - done) if done else float("nan")
        bar = "#" * int(30 * done / total)
        sys.stderr.write(f"\r  simulating [{bar:<30}] {done}/{total}  {el:5.1f} s  eta {eta:4.1f} s")
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


def compare(drive: Drive, speeds_pu: Sequence[float] | None = None, *, controls: dict[str, tuple[Control, float]]
            | None = None, workers: int | None = None, progress: bool = False, pwm_phases: int = 1,
            base_speeds: bool = True, executor: Executor | None = None, summarise: bool = True) -> CompareResult:
    """Compare square-wave and sinusoidal supply of a drive over speed.

    Parameters
    ----------
    drive : Drive
    speeds_pu : sequence of float, optional
        Per-unit speeds (of ``Omega_0``); default 32 speeds from 0.05 to 0.98.
    controls : dict, optional
        ``{"square": (control, ref), "sine": (control, ref)}``; default :func:`default_controls`.
    workers : int, optional
        Processes; default all cores (1: in this process). With a :class:`~concurrent.futures.ProcessPoolExecutor`
        as ``executor``: its number of processes, for which the points are sent in chunks (else one at a time).
    progress : bool
        Show a progress bar on stderr.
    pwm_phases : int
        PWM-grid phases per point (>= 1): each point is the mean over that many offsets of the rotor's initial
        angle within one PWM period's travel, with its range (:func:`bldclab.analysis.experiments.steady_state`).
    base_speeds : bool
        Also search the simulated base speed of each supply (:func:`bldclab.analysis.experiments.base_speed`, with the
        default controllers of paper 1's definitions).
    executor : concurrent.futures.Executor, optional
        Where the points run instead of a pool of ``workers`` processes: e.g. a pool the caller keeps to draw the
        figures on it next. Results do not depend on where the points run.
    summarise : bool
        Issue one :class:`~bldclab.errors.PlausibilityWarning` summarising the runs' warnings
        (:func:`bldclab.sim.plausibility.summary`); False leaves that to the caller, which runs more (the waveforms
        and figures of :func:`bldclab.report.bundle.compare_directory`) and summarises them all in one line.

    Returns
    -------
    CompareResult
    """
    w = np.asarray(speed_grid(32) if speeds_pu is None else speeds_pu, dtype=float)
    if w.ndim != 1 or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise BldclabError("speeds", "per-unit speeds must be positive and finite")
    if not isinstance(pwm_phases, int) or isinstance(pwm_phases, bool) or pwm_phases < 1:
        raise BldclabError("pwm_phases", f"must be an integer >= 1, got {pwm_phases!r}")
    controls = controls or default_controls(drive, float(np.min(w)))
    jobs = [(drive, s, controls[s][0], controls[s][1], float(x), pwm_phases) for s in SUPPLIES for x in w]
    bs_jobs = [(drive, s) for s in SUPPLIES] if base_speeds else []
    show = _progress(len(jobs), progress)
    t0 = time.perf_counter()
    rows: list[dict[str, Any]]
    bs: list[float]
    n_workers = workers or os.cpu_count() or 1

    def run_on(pool: Executor, n_pool: int) -> tuple[list[dict[str, Any]], list[float]]:
        bs_futures = [pool.submit(_run_base_speed, job) for job in bs_jobs]  # the longest jobs first
        chunk = max(1, len(jobs) // (4 * n_pool)) if n_pool > 0 else 1
        return map_points(_run_point, jobs, pool, chunksize=chunk, progress=show), [f.result() for f in bs_futures]

    if executor is not None:
        rows, bs = run_on(executor, n_workers if isinstance(executor, ProcessPoolExecutor) and workers else 0)
    elif n_workers <= 1:
        rows = map_points(_run_point, jobs, progress=show)
        bs = map_points(_run_base_speed, bs_jobs)
    else:
        with ProcessPoolExecutor(max_workers=n_workers) as pool:
            rows, bs = run_on(pool, n_workers)
    seconds = time.perf_counter() - t0
    caught = [text for row in rows for text in row.pop("_warnings")]
    eff = efficiency_table(drive, pd.DataFrame([{"supply": row["supply"], "Omega_pu": row["Omega_pu"],
                                                 **row.pop("_eff")} for row in rows]))
    sim = pd.DataFrame(rows)
    an = analytic.characteristic(drive, w)
    t1 = analytic.table1(drive)
    bst = base_speed_table(drive, dict(zip(SUPPLIES, bs, strict=True)), t1) if base_speeds else None
    res = CompareResult(drive=drive, simulated=sim, analytic=an, table1=t1, base_speeds=bst,
                        pwm_phases=pwm_phases, seconds=seconds, efficiency=eff, controls=dict(controls))
    rpm = drive.Omega_0 * 30.0 / np.pi
    res.verdict = ([bottom_line(drive, sim)] + _verdict(sim, rpm) + _efficiency_verdict(eff, rpm)
                   + _sampling_notes(sim, rpm) + (_base_speed_verdict(bst) if bst is not None else []))
    res.warnings = caught
    res.not_applicable = analytic.applicability(drive)
    res.commutation, few = analytic.commutation_premise(drive)
    if few:
        res.verdict.append(f"premise: {res.commutation}")
    line = _plaus.summary(caught, len(jobs))
    if line and summarise:
        warnings.warn(line, PlausibilityWarning, stacklevel=2)
    return res


#: A point's ripple at the samples is flagged as missing part of the commutation when the continuous one-PWM-period
#: average's ripple exceeds it by more than this (p.u. of T_N) and by more than 20 %.
SAMPLING_GAP_PU = 0.02


def bottom_line(drive: Drive, sim: pd.DataFrame) -> str:
    """Say in one line what the comparison comes to in the drive's rated range: torque and efficiency, which supply.

    Over the simulated speeds up to the rated speed ``Omega_N`` (all of them if none is), the mean relative torque
    difference ``T_sine / T_square - 1`` and the mean efficiency difference ``eta_sine - eta_square`` (percentage
    points), each named for the supply it favours, or "the same" within :data:`VERDICT_TOLERANCE` (mean absolute
    difference: 0.005 p.u. of torque, 0.005 of efficiency).

    Parameters
    ----------
    drive : Drive
    sim : pandas.DataFrame
        :attr:`CompareResult.simulated` (``supply``, ``Omega_pu``, ``T_pu``, ``eta``).

    Returns
    -------
    str
        ``"bottom line: in its rated range (up to 0.90 p.u., 42120 rpm: 27 speeds) this drive gives 5.1 % more
        torque with sinusoidal supply at equal rms current, at 0.6 percentage points better efficiency"``.
    """
    sq = sim[sim.supply == "square"].sort_values("Omega_pu").reset_index(drop=True)
    si = sim[sim.supply == "sine"].sort_values("Omega_pu").reset_index(drop=True)
    w_n = drive.motor.Omega_nominal / drive.Omega_0
    sel = (sq.Omega_pu <= w_n + 1e-9).to_numpy()
    rpm = drive.Omega_0 * 30.0 / np.pi
    if sel.any():
        where = f"in its rated range (up to {w_n:.2f} p.u., {w_n * rpm:.0f} rpm: {int(sel.sum())} speeds)"
    else:
        sel = np.ones(len(sq), dtype=bool)
        where = f"over the speeds compared (all above the rated speed {w_n:.2f} p.u.)"
    t_si, t_sq = si.T_pu.to_numpy()[sel], sq.T_pu.to_numpy()[sel]
    d_eta = float(np.mean(si.eta.to_numpy()[sel] - sq.eta.to_numpy()[sel]))  # > 0: the sinusoid is more efficient
    tol_t, tol_e = VERDICT_TOLERANCE["T_pu"], VERDICT_TOLERANCE["eta"]
    eff_same = abs(d_eta) <= tol_e
    same_eff = f"the same efficiency (within {100 * tol_e:g} percentage points)"
    if float(np.mean(np.abs(t_si - t_sq))) <= tol_t:
        who = "sinusoidal" if d_eta > 0 else "square-wave"
        eff = same_eff if eff_same else (f"{100.0 * abs(d_eta):.1f} percentage points better efficiency with {who} "
                                         "supply")
        return (f"bottom line: {where} this drive gives the same torque with either supply (within {tol_t:g} p.u.) at "
                f"equal rms current, and {eff}")
    rel = float(np.mean(t_si / t_sq - 1.0))
    winner = "sinusoidal" if rel > 0 else "square-wave"
    gain = rel if rel > 0 else float(np.mean(t_sq / t_si - 1.0))
    d = d_eta if rel > 0 else -d_eta  # in favour of the supply named
    eff = same_eff if eff_same else f"{100.0 * abs(d):.1f} percentage points {'better' if d > 0 else 'worse'} " \
        "efficiency"
    return (f"bottom line: {where} this drive gives {100.0 * gain:.1f} % more torque with {winner} supply at equal rms "
            f"current, at {eff}")


def _rpm_range(lo: float, hi: float, rpm: float | None) -> str:
    """Return `` = 2340-16380 rpm`` for a speed range in p.u., or nothing without the base ``rpm`` (Omega_0)."""
    if rpm is None:
        return ""
    return f" = {lo * rpm:.0f}-{hi * rpm:.0f} rpm" if hi > lo else f" = {lo * rpm:.0f} rpm"


def _sampling_notes(sim: pd.DataFrame, rpm: float | None = None) -> list[str]:
    names = {"sine": "sinusoidal", "square": "square-wave"}
    lines = []
    for supply in SUPPLIES:
        s = sim[sim.supply == supply].sort_values("Omega_pu")
        gap = (s.TR_ma_pu - s.TR_pu).to_numpy()
        mask = (gap > SAMPLING_GAP_PU) & (s.TR_ma_pu.to_numpy() > 1.2 * s.TR_pu.to_numpy())
        w = s.Omega_pu.to_numpy()
        for lo, hi in _ranges(mask, w):
            sel = (w >= lo) & (w <= hi)
            lines.append(f"note, {names[supply]}: for Omega in [{lo:.2f}, {hi:.2f}] p.u.{_rpm_range(lo, hi, rpm)} the "
                         f"commutation falls between "
                         f"controller samples: the torque ripple at the samples (TR) is below the continuous "
                         f"one-PWM-period average's (TR_ma) by up to {float(np.max(gap[sel])):.3f} p.u.")
    return lines


def _base_speed_verdict(bst: pd.DataFrame) -> list[str]:
    names = {"sine": "sinusoidal", "square": "square-wave"}
    return [f"base speed, {names[r.supply]}: {r.simulated_pu:.3f} p.u. simulated, {r.numeric_R_pu:.3f} numeric with "
            f"R, {r.closed_form_pu:.3f} by {r.equation} (R neglected)" for r in bst.itertuples()]


def _ranges(mask: np.ndarray, w: np.ndarray) -> list[tuple[float, float]]:
    out, start = [], None
    for j, flag in enumerate(mask):
        if flag and start is None:
            start = j
        if (not flag or j == len(mask) - 1) and start is not None:
            end = j if flag else j - 1
            out.append((float(w[start]), float(w[end])))
            start = None
    return out


#: Smallest difference between the supplies the verdict calls a difference, per measure (p.u. of T_N for torque and
#: ripple, absolute for efficiency); below it the verdict says "equal". Measured on htm-48v and lu-4kw at 0.2, 0.5,
#: 0.8 and 0.95 p.u. with 4 PWM-grid phases, a point's mean torque moves by up to 0.0011 p.u. with the phase of the
#: PWM grid and differs by up to 0.0016 p.u. between the switching and averaged inverters, the ripple at the samples
#: by up to 0.0034 p.u.: the tolerances are about three times that, so a difference above them is the supplies', not
#: the simulation's. With ``pwm_phases > 1`` the measured spread widens them where it is larger.
VERDICT_TOLERANCE: dict[str, float] = {"T_pu": 0.005, "TR_avg_pu": 0.01, "eta": 0.005}


def _verdict(sim: pd.DataFrame, rpm: float | None = None) -> list[str]:
    """Say per measure where each supply is better, and where the difference is below :data:`VERDICT_TOLERANCE`.

    With several PWM-grid phases the tolerance is widened to the largest spread measured over the phases.
    """
    sq = sim[sim.supply == "square"].sort_values("Omega_pu").reset_index(drop=True)
    si = sim[sim.supply == "sine"].sort_values("Omega_pu").reset_index(drop=True)
    w = sq["Omega_pu"].to_numpy()
    lines = []
    for key, name, better_high in (("T_pu", "mean torque", True),
                                   ("TR_avg_pu", "torque ripple (averaged inverter)", False),
                                   ("eta", "efficiency", True)):
        tol = VERDICT_TOLERANCE[key]
        if f"{key}_max" in sim:
            tol = max(tol, float((sim[f"{key}_max"] - sim[f"{key}_min"]).max()))
        unit = " p.u." if key != "eta" else ""
        a, b = si[key].to_numpy(), sq[key].to_numpy()
        diff = a - b if better_high else b - a  # > 0: the sinusoidal supply is better
        state = np.where(diff > tol, 1, np.where(diff < -tol, -1, 0))
        for value, who in ((1, "sinusoidal better"), (-1, "square-wave better"), (0, "equal")):
            for lo, hi in _ranges(state == value, w):
                sel = (w >= lo) & (w <= hi)
                gap = float(np.mean(np.abs(a[sel] - b[sel])))
                where = _where(lo, hi, rpm)
                if value == 0:
                    lines.append(f"{name}: equal for {where} (differences below {tol:g}{unit}, what the simulation "
                                 f"resolves; {gap:.3f} on average)")
                else:
                    lines.append(f"{name}: {who} for {where} (by {gap:.3f}{unit} on average, above the {tol:g}"
                                 f"{unit} resolved)")
    return lines


_WINNER = {1: "sinusoidal better", -1: "square-wave better", 0: "equal"}
_NA = 2  # a closed form outside its range (above a base speed)


def _winner_states(eff: pd.DataFrame, col: str, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Return speeds and per speed 1 (sinusoidal more efficient), -1 (square wave), 0 (within tol), 2 (n/a)."""
    sq = eff[eff.supply == "square"].sort_values("Omega_pu")
    si = eff[eff.supply == "sine"].sort_values("Omega_pu")
    diff = si[col].to_numpy(dtype=float) - sq[col].to_numpy(dtype=float)
    state = np.where(np.isnan(diff), _NA, np.where(diff > tol, 1, np.where(diff < -tol, -1, 0)))
    return sq["Omega_pu"].to_numpy(dtype=float), state


def _where(lo: float, hi: float, rpm: float | None = None) -> str:
    where = f"Omega in [{lo:.2f}, {hi:.2f}] p.u." if hi > lo else f"Omega = {lo:.2f} p.u."
    return where + _rpm_range(lo, hi, rpm)


def _efficiency_verdict(eff: pd.DataFrame, rpm: float | None = None) -> list[str]:
    """Say who wins on efficiency by each loss count, and where the full-loss winner differs from a copper-only one.

    The same tolerance as the simulated efficiency's verdict (:data:`VERDICT_TOLERANCE`) for every count.
    """
    tol = VERDICT_TOLERANCE["eta"]
    states = {col: _winner_states(eff, col, tol) for col in EFFICIENCY_COUNTS}
    lines = []
    for col, text in EFFICIENCY_COUNTS.items():
        w, state = states[col]
        parts = [f"{who} for {_where(lo, hi, rpm)}" for value, who in _WINNER.items()
                 for lo, hi in _ranges(state == value, w)]
        parts += [f"not defined for {_where(lo, hi, rpm)} (above the base speed)"
                  for lo, hi in _ranges(state == _NA, w)]
        lines.append(f"efficiency by loss count, {text}: " + "; ".join(parts)
                     + f" (a difference within {tol:g} is equal: the one resolved)")
    w, full = states["eta_sim_full"]
    for col, name in (("eta_paper_3PR", "paper 1's (38)/(39) with 3 P_R"),
                      ("eta_consistent_2PR", "(38)/(39) with 2 R I_N^2"),
                      ("eta_sim_copper", "the simulated copper-only efficiency")):
        _, cu = states[col]
        both = (cu != _NA) & (full != _NA)
        changed = both & (cu != full)
        if not np.any(both):
            continue
        if not np.any(changed):
            lines.append(f"efficiency, full losses against {name}: the same winner at every speed compared"
                         + ("" if np.all(both) else " where both are defined") + f" (above the {tol:g} resolved)")
            continue
        for a in (1, -1, 0):
            for b in (1, -1, 0):
                for lo, hi in _ranges(changed & (cu == a) & (full == b), w):
                    lines.append(f"efficiency, full losses against {name}: the verdict changes for "
                                 f"{_where(lo, hi, rpm)}: "
                                 f"{_WINNER[a]} with copper loss only, {_WINNER[b]} with every loss (above the "
                                 f"{tol:g} resolved)")
    return lines

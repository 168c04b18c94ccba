"""The results directory of ``bldclab compare``: the one producer of its file set.

``waveforms.csv`` (:func:`waveforms`), ``manifest.json`` (what was run and which files are there:
:func:`make_manifest`) and ``report.html`` (:func:`compare_outputs`) are built here, beside the CSV files and
figures of the comparison; :func:`motor_results` builds the same files in memory from a motor, and
:func:`read_results` reads them back from a directory, so both ways give the same page.
"""

from __future__ import annotations

import argparse
import dataclasses
import inspect
import json
import math
import platform
import shlex
import warnings
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from .. import _core
from .._version import __version__
from ..analysis import paper1, paper2
from ..analysis.compare import SUPPLIES, CompareResult, compare, default_controls
from ..analysis.experiments import electrical_period, map_points, steady_state
from ..control import Control, Lu
from ..errors import BldclabError, PlausibilityWarning
from ..model import analytic
from ..model.analytic.table import table1_text
from ..model.motor import Drive
from ..sim import Scenario
from ..sim import plausibility as _plaus
from . import plots
from .html import _KNOWN, FORMAT, FORMAT_VERSION, MANIFEST, REPORT, WAVEFORM_SPEEDS, WAVEFORM_SUB, Results, _now, render
from .plots import FigureJob

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "compare_command",
    "compare_directory",
    "compare_files",
    "compare_outputs",
    "comparison_figures",
    "efficiency_figure",
    "make_manifest",
    "methods_traces",
    "motor_results",
    "read_results",
    "ripple_figure",
    "runs_text",
    "torque_figure",
    "waveforms",
]


def _waveform(job: tuple[Drive, str, Control, float, float, int]
              ) -> tuple[pd.DataFrame, dict[str, Any], list[str]]:
    """Run one supply at one speed for :func:`waveforms`: the window's first period, the point, its warnings.

    The plausibility warnings of the run are prefixed as :func:`~bldclab.analysis.compare.compare`'s: the same point
    gives the same message, counted once.
    """
    drive, supply, ctl, ref, s, trace_sub = job
    om = s * drive.Omega_0
    with _plaus.collect() as caught:  # recorded (on a worker they would reach its stderr one by one), summarised once
        point, res = steady_state(drive, ctl, om, ref, trace=True, trace_sub=trace_sub)
    m = point.metrics
    te = electrical_period(drive, om)
    sel = (res.t >= m.t0) & (res.t < m.t0 + te)
    th = np.degrees(np.unwrap(res["theta_e"][sel]))
    th -= 360.0 * math.floor(th[0] / 360.0 + 1e-9) if th.size else 0.0
    frame = pd.DataFrame({
        "supply": supply, "speed_pu": s, "theta_e_deg": th, "t_ms": (res.t[sel] - m.t0) * 1e3,
        "i_a": res["i_a"][sel], "i_b": res["i_b"][sel], "i_c": res["i_c"][sel], "tau_e": res["tau_e"][sel],
        "tau_e_pu": res["tau_e"][sel] / drive.T_N})
    return frame, {"supply": supply, "speed_pu": s, "tau_mean_pu": point.tau_mean_pu,
                   "ripple_pu": point.ripple_sampled_pu, "ripple_inst_pu": point.ripple_pu,
                   "efficiency": point.efficiency}, [f"{supply} at {s:.3g} p.u.: {text}" for text in caught]


def waveforms(drive: Drive, speeds_pu: Sequence[float] = WAVEFORM_SPEEDS, *,
              controls: Mapping[str, tuple[Control, float]] | None = None, trace_sub: int = WAVEFORM_SUB,
              executor: Executor | None = None) -> tuple[pd.DataFrame, list[dict[str, Any]]]:
    """Simulate phase currents and torque over one electrical period at each speed, both supplies, in steady state.

    Each point runs as in :func:`bldclab.analysis.compare.compare`
    (:func:`bldclab.analysis.experiments.steady_state`: imposed speed,
    the same controllers and references) with a trace; the period shown is the first of the measuring window.

    Parameters
    ----------
    drive : Drive
    speeds_pu : sequence of float
        Per-unit speeds (of ``Omega_0``), > 0.
    controls : mapping, optional
        ``{"square": (control, ref), "sine": (control, ref)}``; default
        :func:`bldclab.analysis.compare.default_controls` for the lowest speed.
    trace_sub : int
        Trace rows per controller sample.
    executor : concurrent.futures.Executor, optional
        Run the points on it (in parallel); in this process if omitted. The result is the same.

    Returns
    -------
    pandas.DataFrame
        Columns ``supply``, ``speed_pu``, ``theta_e_deg`` (electrical angle, degrees, from the window's start),
        ``t_ms`` (ms from the window's start), ``i_a``, ``i_b``, ``i_c`` (A), ``tau_e`` (N m), ``tau_e_pu``.
    list of dict
        Per supply and speed: ``supply``, ``speed_pu``, ``tau_mean_pu``, ``ripple_pu`` (without PWM),
        ``ripple_inst_pu`` (instantaneous), ``efficiency`` over the measuring window.

    The runs' plausibility warnings are issued as one :class:`~bldclab.errors.PlausibilityWarning`
    (:func:`bldclab.sim.plausibility.summary`).
    """
    jobs = _waveform_jobs(drive, speeds_pu, controls, trace_sub)
    done = map_points(_waveform, jobs, executor)
    line = _plaus.summary(_waveform_warnings(done), len(jobs))
    if line:
        warnings.warn(line, PlausibilityWarning, stacklevel=2)
    return _waveform_table(done)


def _waveform_jobs(drive: Drive, speeds_pu: Sequence[float], controls: Mapping[str, tuple[Control, float]] | None,
                   trace_sub: int) -> list[tuple[Drive, str, Control, float, float, int]]:
    """Return the points of :func:`waveforms`: each supply at each speed."""
    w = [float(s) for s in speeds_pu]
    if not w or any(not math.isfinite(s) or s <= 0 for s in w):
        raise BldclabError("--waveform-speeds", f"must be positive per-unit speeds, got {list(speeds_pu)!r}")
    controls = controls or default_controls(drive, min(w))
    return [(drive, supply, *controls[supply], s, trace_sub) for supply in SUPPLIES for s in w]


def _waveform_table(done: Sequence[tuple[pd.DataFrame, dict[str, Any], list[str]]]
                    ) -> tuple[pd.DataFrame, list[dict[str, Any]]]:
    """Return :func:`waveforms`' table and points from the results of its points, in order."""
    return pd.concat([frame for frame, _, _ in done], ignore_index=True), [point for _, point, _ in done]


def _waveform_warnings(done: Sequence[tuple[pd.DataFrame, dict[str, Any], list[str]]]) -> list[str]:
    """Return the plausibility warnings of :func:`waveforms`' runs, in order, each prefixed by its point."""
    return [text for _, _, caught in done for text in caught]


def methods_traces(drive: Drive, torque: float | None = None, speed: float | None = None,
                   methods: Sequence[str] = ("rect", "lu-no-do", "lu")) -> pd.DataFrame:
    """Run paper 2's methods; return torque and largest current over the last half period (one-PWM-period means).

    The same runs and traces as :func:`bldclab.analysis.paper2.fig_compare`
    (:func:`~bldclab.analysis.paper2.method_trace`), as data.

    Parameters
    ----------
    drive : Drive
    torque : float, optional
        Torque reference (N m); default ``T_N``.
    speed : float, optional
        Imposed speed (rad/s); default the rated speed.
    methods : sequence of str
        Among ``rect``, ``lu-no-do``, ``lu``.

    Returns
    -------
    pandas.DataFrame
        Columns ``method``, ``t_ms`` (from the start of the span shown), ``tau_ma`` (N m), ``i_max_ma`` (A).
    """
    tq = drive.T_N if torque is None else torque
    om = drive.motor.Omega_nominal if speed is None else speed
    span = math.pi / (drive.motor.p * om)
    frames = []
    for mth in methods:
        res = paper2.operating_point(drive, mth, tq, om, trace_sub=8)
        t_ms, tau, i_big = paper2.method_trace(res, span)
        frames.append(pd.DataFrame({"method": mth, "t_ms": t_ms, "tau_ma": tau, "i_max_ma": i_big}))
    return pd.concat(frames, ignore_index=True)


def _plain(value: Any) -> Any:
    """JSON-ready copy: dataclasses to dicts (with their class), NaN to None, numpy scalars to Python."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        out: dict[str, Any] = {"class": type(value).__name__}
        for f in dataclasses.fields(value):
            out[f.name] = _plain(getattr(value, f.name))
        return out
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return _plain(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)


def _scenario(controls: Mapping[str, tuple[Control, float]]) -> dict[str, Any]:
    """Return the measuring scenario of :func:`~bldclab.analysis.experiments.steady_state` as ``compare`` runs it."""
    par = inspect.signature(steady_state).parameters
    delay = next(f.default for f in dataclasses.fields(Scenario) if f.name == "delay")
    if delay is None:  # each controller's own
        own = sorted({ctl.own_delay for ctl, _ in controls.values()})
        delay = own[0] if len(own) == 1 else "/".join(map(str, own))
    return {"speed": "imposed (dynamometer), constant", "settle_periods": par["settle_periods"].default,
            "settle_time_s": par["settle_time"].default, "measure_periods": par["measure_periods"].default,
            "delay_samples": delay, "start": "from rest: zero currents, electrical angle 0"}


def _supplies(drive: Drive, controls: Mapping[str, tuple[Control, float]]) -> dict[str, Any]:
    meaning = {"square": ("A", "injected current I_N (paper 1 premise, II.B)"),
               "sine": ("N m", "torque T_s,N of (12)/(13); lowered above the base speed, (23)-(25)")}
    out = {}
    for supply, (ctl, ref) in controls.items():
        unit, text = meaning.get(supply, ("", ""))
        out[supply] = {"controller": type(ctl).__name__, "reference": float(ref), "reference_unit": unit,
                       "reference_meaning": text, "settings": _plain(ctl)}
    return out


def _environment() -> dict[str, str]:

    return {"python": platform.python_version(), "numpy": np.__version__, "pandas": pd.__version__,
            "platform": platform.platform(), "core": _core.core().version}


def make_manifest(res: CompareResult, controls: Mapping[str, tuple[Control, float]], *, command: str,
                  files: Sequence[str], motor_source: str, waveform_points: Sequence[Mapping[str, Any]] = (),
                  waveform_sub: int = WAVEFORM_SUB, extra: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Describe a comparison's results directory: what was run, how, and which files hold what.

    Parameters
    ----------
    res : CompareResult
        The comparison.
    controls : mapping
        The controllers and references it ran (``{"square": (control, ref), "sine": ...}``).
    command : str
        The command line that reproduces it.
    files : sequence of str
        Names of the files in the directory (the manifest included).
    motor_source : str
        What the user named: a catalog name or a motor-file path.
    waveform_points : sequence of mapping
        The operating points of the waveforms (:func:`waveforms`' second value).
    waveform_sub : int
        Trace rows per sample of the waveforms.
    extra : mapping, optional
        Further entries (e.g. ``torque_control``: how paper 2's methods were run).

    Returns
    -------
    dict
        JSON-ready; ``format`` is :data:`FORMAT`, ``format_version`` :data:`FORMAT_VERSION`.
    """
    speeds = [float(v) for v in res.analytic["Omega_pu"]]
    return {**_plain(dict(extra or {})),
        "format": FORMAT, "format_version": FORMAT_VERSION, "command": command, "bldclab_version": __version__,
        "created": _now(), "environment": _environment(), "wall_time_s": round(float(res.seconds), 3),
        "motor": {"name": res.drive.name, "source": motor_source, "toml": res.drive.to_toml()},
        "speeds_pu": speeds, "supplies": _supplies(res.drive, controls), "scenario": _scenario(controls),
        "waveforms": {"speeds_pu": sorted({float(p["speed_pu"]) for p in waveform_points}),
                      "trace_sub": waveform_sub, "periods_shown": 1, "points": _plain(list(waveform_points))},
        "verdict": list(res.verdict), "warnings": _plaus.distinct(res.warnings), "files": sorted(set(files)),
    }


def compare_command(args: argparse.Namespace, out: Path) -> str:
    """Return the ``bldclab compare`` command line that reproduces a run (process count aside: results are equal).

    Options left at their defaults are not written; ``--pwm-phases``, ``--chopping`` and ``--inverter`` are when set.
    """
    argv = ["bldclab", "compare", str(args.motor), "--out", str(out), "--speeds", str(args.speeds),
            "--min-speed", f"{args.min_speed:g}", "--max-speed", f"{args.max_speed:g}"]
    if args.pwm_phases != 1:
        argv += ["--pwm-phases", str(args.pwm_phases)]
    if args.chopping != "pwm-on-pwm":
        argv += ["--chopping", str(args.chopping)]
    if args.inverter is not None:
        argv += ["--inverter", str(args.inverter)]
    return shlex.join(argv)


def compare_files(res: CompareResult, *, figures: bool = True, executor: Executor | None = None) -> dict[str, bytes]:
    """Return the result files of a comparison, in the order ``bldclab compare`` writes them.

    The one producer of a results directory's data files: ``simulated.csv``, ``analytic.csv``, ``base_speeds.csv``,
    ``table1.csv``, ``table1.json``, ``verdict.txt``, ``efficiency.csv`` (paper 1's efficiency by loss count
    beside the simulated ones, :func:`bldclab.analysis.compare.efficiency_table`), ``dynamometer.csv`` and, with
    ``figures``, the PNG and SVG of the torque, ripple and efficiency characteristics and of paper 1's Figs 9, 11
    and 12.
    :func:`compare_outputs` adds ``waveforms.csv``, ``manifest.json`` and ``report.html``; :func:`compare_directory`
    makes both. The plausibility warnings of the figures' simulations are added to ``res.warnings``, prefixed by
    the figure (not shown: the caller summarises them, :func:`bldclab.sim.plausibility.summary`).

    Parameters
    ----------
    res : CompareResult
        The comparison (:func:`bldclab.analysis.compare.compare`).
    figures : bool
        Also draw the figures (matplotlib).
    executor : concurrent.futures.Executor, optional
        Run paper 1's Figs 9, 11 and 12 (their simulations) and draw the figures on its workers, in parallel (the
        pool that ran the comparison); in this process if omitted. The files are the same.

    Returns
    -------
    dict of str to bytes
    """
    files = _data_files(res)
    drawn = plots.render_figures(_figure_jobs(res, figures), executor)
    res.warnings += _figure_warnings(drawn)
    files.update(_figure_files(drawn, figures))
    return files


def _data_files(res: CompareResult) -> dict[str, bytes]:
    """Return the data files of :func:`compare_files` but ``dynamometer.csv``."""
    t1 = res.table1
    return {
        "simulated.csv": res.simulated.to_csv(index=False).encode(),
        "analytic.csv": res.analytic.to_csv(index=False).encode(),
        # compare(..., base_speeds=False) leaves them out
        **({} if res.base_speeds is None else {"base_speeds.csv": res.base_speeds.to_csv(index=False).encode()}),
        "table1.csv": table1_text(t1, "csv").encode(),
        "table1.json": table1_text(t1, "json", res.not_applicable).encode(),
        "verdict.txt": ("\n".join(res.verdict) + "\n").encode(),
        # compare() results made before the efficiency table existed have none
        **({} if res.efficiency is None else {"efficiency.csv": res.efficiency.to_csv(index=False).encode()}),
    }


#: paper 1's figure behind ``dynamometer.csv``: drawn, or only run (its measurements), without figures
_DYNAMOMETER = "fig12_dynamometer"


def _figure_jobs(res: CompareResult, figures: bool) -> dict[str, FigureJob]:
    """Return the figures of :func:`compare_files`, the costliest first (on an executor they start first)."""
    drive = res.drive
    jobs = {_DYNAMOMETER: FigureJob(paper1.fig12, (drive,), ("png", "svg") if figures else ())}
    if figures:
        jobs["fig11_currents"] = FigureJob(paper1.fig11, (drive,))
        jobs["fig9_torque_0.8pu"] = FigureJob(paper1.fig9, (drive,))
        jobs.update({name: FigureJob(make, (res,)) for name, make in _COMPARISON_FIGURES.items()})
    return jobs


def _figure_names(figures: bool) -> list[str]:
    """Return the names of the files :func:`_figure_files` returns, in order."""
    stems = (*_COMPARISON_FIGURES, "fig9_torque_0.8pu", "fig11_currents", _DYNAMOMETER) if figures else ()
    return ["dynamometer.csv", *(f"{stem}.{fmt}" for stem in stems for fmt in ("png", "svg"))]


#: What the figures that simulate are called in a warning's prefix.
_FIGURE_LABELS = {_DYNAMOMETER: "paper 1 Fig 12 (dynamometer)", "fig11_currents": "paper 1 Fig 11",
                  "fig9_torque_0.8pu": "paper 1 Fig 9"}


def _figure_warnings(drawn: Mapping[str, tuple[dict[str, bytes], Any, list[str]]]) -> list[str]:
    """Return the plausibility warnings the figures' simulations raised, each prefixed by its figure."""
    return [f"{_FIGURE_LABELS.get(name, name)}: {text}" for name, (_, _, caught) in drawn.items() for text in caught]


def _figure_files(drawn: Mapping[str, tuple[dict[str, bytes], Any, list[str]]], figures: bool) -> dict[str, bytes]:
    """Return ``dynamometer.csv`` and the figure files from the drawn :func:`_figure_jobs`."""
    files = {"dynamometer.csv": drawn[_DYNAMOMETER][1].to_csv(index=False).encode()}
    for name in _figure_names(figures)[1:]:
        stem, _, fmt = name.rpartition(".")
        files[name] = drawn[stem][0][fmt]
    return files


def compare_outputs(res: CompareResult, files: Mapping[str, bytes], *, command: str, motor_source: str | None = None,
                    report: bool = True, waveform_speeds: Sequence[float] = WAVEFORM_SPEEDS,
                    extra: Mapping[str, Any] | None = None, executor: Executor | None = None) -> dict[str, bytes]:
    """Return the files ``bldclab compare`` adds to its results: waveforms, manifest and (by default) the report.

    Parameters
    ----------
    res : CompareResult
        The comparison (:func:`bldclab.analysis.compare.compare`); the waveforms run its controllers.
    files : mapping of str to bytes
        The other files of the results directory (``simulated.csv``, ``table1.json``, ...).
    command : str
        The command line that reproduces the run.
    motor_source : str, optional
        The motor as the user named it; default the drive's name.
    report : bool
        Also render ``report.html``.
    waveform_speeds : sequence of float
        Per-unit speeds of the waveform panels.
    extra : mapping, optional
        Further manifest entries (:func:`make_manifest`).
    executor : concurrent.futures.Executor, optional
        Run the waveforms' simulations on it (:func:`waveforms`).

    Returns
    -------
    dict of str to bytes
        ``waveforms.csv``, ``manifest.json`` and, with ``report``, ``report.html``.

    The waveforms' plausibility warnings are added to ``res.warnings`` (prefixed by their point: where a waveform
    repeats a point of the comparison its message is the same, counted once by the summary); the manifest lists
    every distinct one.
    """
    controls = _controls_of(res)
    done = map_points(_waveform, _waveform_jobs(res.drive, waveform_speeds, controls, WAVEFORM_SUB), executor)
    res.warnings += _waveform_warnings(done)
    return _outputs(res, files, list(files), controls, _waveform_table(done), command=command,
                    motor_source=motor_source, report=report, extra=extra)


def _controls_of(res: CompareResult) -> Mapping[str, tuple[Control, float]]:
    """Return the controllers a comparison ran (its defaults for results that do not say)."""
    return res.controls or default_controls(res.drive, float(np.min(res.analytic["Omega_pu"])))


def _outputs(res: CompareResult, files: Mapping[str, bytes], names: Sequence[str],
             controls: Mapping[str, tuple[Control, float]], wf: tuple[pd.DataFrame, list[dict[str, Any]]], *,
             command: str, motor_source: str | None, report: bool, extra: Mapping[str, Any] | None
             ) -> dict[str, bytes]:
    """Return :func:`compare_outputs` from the waveforms; ``names``: every file before (``files``: the data ones)."""
    table, points = wf
    new: dict[str, bytes] = {"waveforms.csv": table.to_csv(index=False, float_format="%.6g").encode()}
    names = [*names, "waveforms.csv", MANIFEST, *([REPORT] if report else [])]
    manifest = make_manifest(res, controls, command=command, files=names,
                             motor_source=motor_source or res.drive.name, waveform_points=points, extra=extra)
    new[MANIFEST] = (json.dumps(manifest, indent=2, allow_nan=False) + "\n").encode()
    if report:
        results = Results.from_files({**files, **new}, source="the run itself (bldclab compare)")
        results.files = sorted(set(names))
        new[REPORT] = render(results, report_command=command).encode()
    return new


def compare_directory(res: CompareResult, *, command: str, motor_source: str | None = None, report: bool = True,
                      executor: Executor | None = None) -> dict[str, bytes]:
    """Return every file of ``bldclab compare``'s results directory, in the order it writes them.

    :func:`compare_files` then :func:`compare_outputs`: the same files. On an executor (the pool that ran the
    comparison), paper 1's Figs 9, 11 and 12 and the waveforms run and the figures are drawn on its workers, while
    this process writes the data files; the manifest and the report follow (they need Fig 12's measurements, the
    waveforms and every run's warnings). The warnings of the figures' and waveforms' runs are added to
    ``res.warnings`` in the order of :func:`compare_files` then :func:`compare_outputs`.

    Parameters
    ----------
    res : CompareResult
        The comparison (:func:`bldclab.analysis.compare.compare`).
    command : str
        The command line that reproduces the run.
    motor_source : str, optional
        The motor as the user named it; default the drive's name.
    report : bool
        Also render ``report.html``.
    executor : concurrent.futures.Executor, optional
        Where the simulations of the figures and waveforms run and the figures are drawn; in this process if omitted.

    Returns
    -------
    dict of str to bytes
    """
    if executor is None:
        files = compare_files(res)
        files.update(compare_outputs(res, files, command=command, motor_source=motor_source, report=report))
        return files
    controls = _controls_of(res)
    jobs = _figure_jobs(res, True)
    drawing = {_DYNAMOMETER: executor.submit(plots.render_figure, jobs.pop(_DYNAMOMETER))}
    running = [executor.submit(_waveform, job) for job in _waveform_jobs(res.drive, WAVEFORM_SPEEDS, controls,
                                                                         WAVEFORM_SUB)]
    drawing.update({name: executor.submit(plots.render_figure, job) for name, job in jobs.items()})
    files = _data_files(res)
    done = [f.result() for f in running]
    drawn = {name: f.result() for name, f in drawing.items()}  # their warnings belong in the manifest
    res.warnings += _figure_warnings(drawn) + _waveform_warnings(done)
    files["dynamometer.csv"] = drawn[_DYNAMOMETER][1].to_csv(index=False).encode()
    outputs = _outputs(res, files, [*files, *_figure_names(True)[1:]], controls, _waveform_table(done),
                       command=command, motor_source=motor_source, report=report, extra=None)
    files.update(_figure_files(drawn, True))
    files.update(outputs)
    return files


def motor_results(drive: Drive, speeds_pu: Sequence[float], *, command: str, motor_source: str,
                  workers: int | None = None, waveform_speeds: Sequence[float] = WAVEFORM_SPEEDS,
                  torque_control: bool = False, progress: bool = False) -> dict[str, bytes]:
    """Run a comparison and return the files of its results directory (in memory), as ``bldclab compare`` would.

    Parameters
    ----------
    drive : Drive
    speeds_pu : sequence of float
        Per-unit speeds.
    command : str
        The command line that reproduces this.
    motor_source : str
        The motor as the user named it.
    workers : int, optional
        Processes for the comparison (default all cores).
    waveform_speeds : sequence of float
        Per-unit speeds of the waveform panels.
    torque_control : bool
        Also run paper 2's methods (:func:`bldclab.analysis.paper2.compare_methods` on its default grid and
        :func:`methods_traces`).
    progress : bool
        Progress bar on stderr.

    Returns
    -------
    dict of str to bytes
        ``simulated.csv``, ``analytic.csv``, ``table1.json``, ``verdict.txt``, ``efficiency.csv``, ``dynamometer.csv``,
        ``waveforms.csv``, ``manifest.json`` and, with ``torque_control``, ``methods.csv`` and
        ``methods_traces.csv``.
    """
    res = compare(drive, speeds_pu, workers=workers, progress=progress, summarise=False)
    files = compare_files(res, figures=False)
    extra: dict[str, Any] = {}
    if torque_control:

        torques, speeds = paper2.default_grid(drive)
        files["methods.csv"] = paper2.compare_methods(drive, torques, speeds).to_csv(index=False).encode()
        files["methods_traces.csv"] = methods_traces(drive).to_csv(index=False, float_format="%.6g").encode()
        extra["torque_control"] = {
            "run": ("bldclab.analysis.paper2.compare_methods on its default grid, then methods_traces at T_N and the "
                    "rated speed"),
            "torques_N_m": list(torques), "speeds_rad_s": list(speeds), "trace_sub": 8,
            "controller": _plain(Lu()), "scenario": "paper2.operating_point: imposed speed, 3 electrical periods "
            "(at least 10 ms) settling, 2 measured; computation delay 1 sample"}
    files.update(compare_outputs(res, files, command=command, motor_source=motor_source, report=False,
                                 waveform_speeds=waveform_speeds, extra=extra))
    line = _plaus.summary(res.warnings, runs_text(res, len(waveform_speeds)))
    if line:  # one line for the comparison's points, paper 1's Fig 12 and the waveforms
        warnings.warn(line, PlausibilityWarning, stacklevel=2)
    return files


def runs_text(res: CompareResult, waveform_speeds: int = len(WAVEFORM_SPEEDS), figures: bool = False) -> str:
    """Say what a comparison's files ran, for its warnings' summary line: ``"64 points, 4 waveforms and ..."``."""
    figs = "paper 1's Figs 9, 11 and 12" if figures else "paper 1's Fig 12"
    return f"{len(res.simulated)} points, {2 * waveform_speeds} waveforms and {figs}"


def read_results(path: Path) -> dict[str, bytes]:
    """Read the files of a results directory that a report uses, and list the names of all the others.

    Parameters
    ----------
    path : Path
        A directory written by ``bldclab compare`` (it holds ``manifest.json``).

    Returns
    -------
    dict of str to bytes
        File name to content for :data:`MANIFEST` and the known result files present; other files map to ``b""``
        (listed, not read).

    Raises
    ------
    BldclabError
        If the directory has no manifest or a file cannot be read.
    """
    if not (path / MANIFEST).is_file():
        raise BldclabError(MANIFEST, "is missing: not a results directory written by bldclab compare (run "
                           f"'bldclab compare MOTOR --out {path}', or give a motor)", str(path))
    files: dict[str, bytes] = {}
    try:
        for entry in sorted(path.iterdir()):
            if not entry.is_file() or entry.name.startswith("."):
                continue
            files[entry.name] = entry.read_bytes() if entry.name in (MANIFEST, *_KNOWN) else b""
    except OSError as exc:
        raise BldclabError("results directory", f"cannot read: {exc.strerror or exc}", str(path)) from None
    return files


def _split(res: CompareResult) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Return the simulated points of the sinusoidal and of the square-wave supply."""
    sim = res.simulated
    return sim[sim.supply == "sine"], sim[sim.supply == "square"]


def _physical(res: CompareResult, torque: bool) -> plots.Physical:
    """Return how the comparison's figures are drawn: rpm (and N m), per unit on the opposite axes.

    The closed forms are left out where the back-EMF is not paper 1's trapezoid
    (:func:`bldclab.model.analytic.shape_applies`), with a note saying so.
    """
    d = res.drive
    closed = analytic.shape_applies(d)
    note = ("paper 1's closed forms not drawn: they assume the ideal trapezoidal back-EMF, which this drive does not "
            "have (bldclab check)") if not closed else ""
    return plots.Physical(rpm=d.Omega_0 * 30.0 / math.pi, y_base=d.T_N if torque else None,
                          y_unit="N m" if torque else "", closed_forms=closed, note=note)


def torque_figure(res: CompareResult) -> Figure:
    """Torque vs speed in rpm and N m (p.u. on the opposite axes): paper 1's closed forms (Fig 7), simulated points."""
    si, sq = _split(res)
    over_t = {"simulated, sinusoidal": si.rename(columns={"T_pu": "T_s_pu"})[["Omega_pu", "T_s_pu"]],
              "simulated, square-wave": sq.rename(columns={"T_pu": "T_q_pu"})[["Omega_pu", "T_q_pu"]]}
    fig, _ = plots.plot_torque_speed(res.analytic, overlays=over_t, title=f"{res.drive.name}: torque vs speed",
                                     physical=_physical(res, True))
    return fig


def ripple_figure(res: CompareResult) -> Figure:
    """Torque ripple vs speed in rpm and N m: paper 1's closed forms (Fig 8), the points on the averaged inverter."""
    si, sq = _split(res)
    # one point set (one marker) for the averaged inverter; each supply's points carry their own column
    avg = si.rename(columns={"TR_avg_pu": "TR_s_pu"})[["Omega_pu", "TR_s_pu"]].merge(
        sq.rename(columns={"TR_avg_pu": "TR_q_pu"})[["Omega_pu", "TR_q_pu"]], on="Omega_pu", how="outer")
    fig, _ = plots.plot_ripple(res.analytic, overlays={"simulated, averaged inverter": avg},
                               title=f"{res.drive.name}: torque ripple vs speed", physical=_physical(res, True))
    return fig


def efficiency_figure(res: CompareResult) -> Figure:
    """Efficiency vs speed in rpm: paper 1's closed forms (38)/(39) and the simulated points of both supplies."""
    si, sq = _split(res)
    fig, _ = plots.plot_efficiency(res.analytic, {"sinusoidal": si, "square-wave": sq},
                                   title=f"{res.drive.name}: efficiency vs speed", physical=_physical(res, False))
    return fig


#: The characteristics of a comparison, by file stem.
_COMPARISON_FIGURES = {"torque_speed": torque_figure, "ripple_speed": ripple_figure,
                       "efficiency_speed": efficiency_figure}


def comparison_figures(res: CompareResult) -> dict[str, Figure]:
    """Torque, ripple and efficiency vs speed: analytic curves of paper 1 and simulated points, both supplies."""
    return {name: make(res) for name, make in _COMPARISON_FIGURES.items()}

"""Paper 2's experiment: torque ripple of rectangular current control, torque control without and with ``D_o``.

H. Lu, L. Zhang, W. Qu, *A New Torque Control Method for Torque Ripple Minimization of BLDC Motors With Un-Ideal
Back EMF*, IEEE Trans. Power Electron. 2008. The three methods (:class:`~bldclab.control.Lu`) run the same drive at
an imposed speed (a dynamometer), from rest until the transients have died out, and are measured over whole
electrical periods:

- torque ripple, peak-to-peak and rms of the instantaneous torque, and of its one-PWM-period moving average
  (the PWM component removed), in % of the mean torque;
- the current dip of the non-commutated phase at each commutation (A and % of its level before the commutation),
  from the one-PWM-period moving average of its current;
- the share of samples in ``D_o`` mode, the share of time with no phase current at all (discontinuous
  conduction) and the share of samples whose duty saturated; :func:`shortfall_cause` names the likely cause when a
  method misses its reference.

:func:`compare_methods` returns the table (a ``DataFrame``), :func:`fig10`, :func:`fig11` and :func:`fig12`
reproduce the paper's simulation figures (phase currents, the duty computed, the torque), :func:`fig_compare`
overlays the three torques. Figures are :class:`matplotlib.figure.Figure` objects, never ``pyplot`` state.
Results and discussion: ``docs/theory-paper2.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from numpy.typing import NDArray

from .._core import core
from ..control import Lu
from ..errors import BldclabError
from ..model.emf import BackEmf, Trapezoid
from ..model.motor import Drive
from ..sim import Scenario, simulate
from ..sim.results import SimResult
from .experiments import electrical_period

__all__ = [
    "METHODS",
    "RippleStats",
    "compare_methods",
    "default_grid",
    "fig10",
    "fig11",
    "fig12",
    "fig_compare",
    "fig_method",
    "method_trace",
    "operating_point",
    "prediction_error",
    "ripple_stats",
    "shortfall_cause",
    "trapezoid_drive",
]

#: The three methods, in the paper's order of presentation (Figs 10, 11, 12).
METHODS = ("rect", "lu-no-do", "lu")

_SECTOR = {1: 0, 3: 1, 2: 2, 6: 3, 4: 4, 5: 5}  # Hall code -> sector (docs/conventions.md)
_POS = (0, 0, 1, 1, 2, 2)
_NEG = (1, 2, 2, 0, 0, 1)
_TITLES = {"rect": "conventional rectangular current control", "lu-no-do": "torque control neglecting finite DC bus",
           "lu": "torque control considering finite DC bus (D_o)"}


@dataclass(frozen=True)
class RippleStats:
    """Torque ripple and commutation figures of one run over its metric window.

    Attributes
    ----------
    tau_mean : float
        Mean torque (N m).
    ripple_pp, ripple_rms : float
        Peak-to-peak and rms deviation of the instantaneous torque, in % of ``tau_mean``.
    ripple_ma_pp, ripple_ma_rms : float
        The same for the torque's moving average over one PWM period (%).
    dip_A : float
        Mean current dip of the non-commutated phase over the commutations in the window (A): its level before the
        commutation minus the smallest value in the first third of the new sector, both from the one-PWM-period
        moving average of its current magnitude. Negative: it rose.
    dip_pct : float
        The dip in % of the level before (mean over the commutations).
    n_commutations : int
        Commutations measured.
    do_share : float
        Share of samples in ``D_o`` mode (-).
    dcm_share : float
        Share of the window with every phase current zero (discontinuous conduction) (-): the plant's exact
        ``Metrics.zero_current_share``, integrated between its events, not read from the trace.
    sat_share : float
        Share of samples whose duty was clamped to [0, 1] (``BC_FLAG_SATURATED``: the DC bus cannot drive what the
        law asks) (-).
    """

    tau_mean: float
    ripple_pp: float
    ripple_rms: float
    ripple_ma_pp: float
    ripple_ma_rms: float
    dip_A: float
    dip_pct: float
    n_commutations: int
    do_share: float
    dcm_share: float
    sat_share: float


def trapezoid_drive(drive: Drive) -> Drive:
    """Return the drive with an ideal 120-degree trapezoidal back-EMF of the same ``k_phi`` on all three phases.

    Parameters
    ----------
    drive : Drive
        Any drive (e.g. ``lu-4kw``).

    Returns
    -------
    Drive
        Same ratings, inverter, sensors; ``motor.emf`` replaced.
    """
    return drive.replace(motor__emf=BackEmf.symmetric(Trapezoid(drive.motor.k_phi)),
                         name=f"{drive.name} (ideal trapezoid)" if drive.name else "ideal trapezoid")


def default_grid(drive: Drive) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Return the load x speed grid of the comparison: 25/50/100 % of ``T_N`` x 1/3, 2/3, 1 of the rated speed.

    Parameters
    ----------
    drive : Drive
        Its ``T_N`` and ``motor.Omega_nominal`` (for ``lu-4kw``: 12.73 N m, 1000/2000/3000 rpm).

    Returns
    -------
    torques : tuple of float
        N m.
    speeds : tuple of float
        rad/s (mechanical).
    """
    T_N, Om = drive.T_N, drive.motor.Omega_nominal
    return tuple(f * T_N for f in (0.25, 0.5, 1.0)), tuple(f * Om for f in (1 / 3, 2 / 3, 1.0))


def operating_point(drive: Drive, method: str, torque: float, speed: float, *, delay: int = 1, trace_sub: int = 8,
                    settle_periods: int = 3, measure_periods: int = 2, settle_time: float = 0.01,
                    **control: Any) -> SimResult:
    """Run one method at an imposed speed and torque reference until steady state, with a fine trace.

    As :func:`bldclab.analysis.experiments.steady_state`: the first ``settle_periods`` electrical periods (at least
    ``settle_time``) are discarded and the next ``measure_periods`` whole periods are the metric window; the run
    lasts half a sample longer than the window so that the window's end is inside it whatever the rounding.

    Parameters
    ----------
    drive : Drive
    method : {"rect", "lu-no-do", "lu"}
    torque : float
        Torque reference (N m).
    speed : float
        Imposed mechanical speed (rad/s), non-zero.
    delay : int
        Computation delay (samples) of both the scenario and the controller.
    trace_sub : int
        Trace rows per sample (the PWM ripple and the commutations resolved).
    settle_periods, measure_periods : int
        Electrical periods discarded and measured.
    settle_time : float
        Minimum settling time (s).
    **control
        Further :class:`~bldclab.control.Lu` settings (``model_R``, ``bandwidth_hz``, ...).

    Returns
    -------
    SimResult
        With the trace over the whole run and metrics over the measured periods.
    """
    ctrl = Lu(method=method, delay=delay, **control)  # type: ignore[arg-type]  # Lu checks method against its names
    Te = electrical_period(drive, speed)
    t_settle = max(settle_periods * Te, math.ceil(settle_time / Te) * Te)
    t_end = t_settle + measure_periods * Te
    sc = Scenario(duration=t_end + 0.25 / drive.inverter.f_pwm, speed=speed, ref=torque, delay=delay,
                  trace_sub=trace_sub, window=(t_settle, t_end))
    return simulate(drive, ctrl, sc)


def _sub(res: SimResult) -> int:
    """Trace rows per sample of a result."""
    sub = int(res.meta["scenario"]["trace_sub"])
    if res.meta["scenario"]["trace_every"] != 1:
        raise BldclabError("result", "needs a trace with one row per sample or finer (trace_every = 1)")
    return sub


def _half_means(res: SimResult, name: str, sub: int, instantaneous: bool) -> NDArray[np.float64]:
    """Mean of a signal over each sample (half PWM period) from the sub-rows.

    Window means (``tau_mean``) are exact; instantaneous signals (currents) use the trapezoid rule over the
    sub-rows' start values.
    """
    v = np.asarray(res[name], dtype=float)
    n = len(v) // sub
    if not instantaneous:
        return v[: n * sub].reshape(n, sub).mean(axis=1)
    ext = np.append(v, v[-1])
    blocks = ext[: n * sub].reshape(n, sub)
    ends = ext[sub: n * sub + 1: sub]
    return (blocks.sum(axis=1) - 0.5 * blocks[:, 0] + 0.5 * ends) / sub


def ripple_stats(res: SimResult, drive: Drive) -> RippleStats:
    """Measure torque ripple and the non-commutated current dip of a run (metric window, fine trace).

    Parameters
    ----------
    res : SimResult
        From :func:`operating_point` (``trace_every = 1``, a metric window, a positive torque reference).
    drive : Drive
        The drive simulated (its ``I_N``).

    Returns
    -------
    RippleStats
    """
    m = res.metrics
    if m is None:
        raise BldclabError("result", "has no metric window")
    sub = _sub(res)
    t = res.t
    ts = 0.5 / drive.inverter.f_pwm
    n = len(t) // sub
    tk = t[: n * sub: sub]
    inside = (tk >= m.t0 - 1e-12) & (tk + ts <= m.t1 + 1e-12)
    h_tau = _half_means(res, "tau_mean", sub, instantaneous=False)
    ma = 0.5 * (h_tau[1:] + h_tau[:-1])
    ma_in = ma[inside[1:] & inside[:-1]]
    tau_mean = m.tau_mean
    scale = 100.0 / abs(tau_mean) if tau_mean != 0.0 else math.nan

    # the non-commutated phase at each Hall sector change
    hall = np.asarray(res["hall"][: n * sub: sub]).astype(int)
    sector = np.array([_SECTOR.get(int(c), -1) for c in hall])
    h_i = np.stack([_half_means(res, f"i_{x}", sub, instantaneous=True) for x in "abc"])
    ma_i = np.abs(0.5 * (h_i[:, 1:] + h_i[:, :-1]))
    per_sector = max(round((math.pi / 3) / (abs(m.omega_mean) * drive.motor.p * ts)), 6)
    after = max(6, per_sector // 3)
    dips, rel = [], []
    for k in (int(j) + 1 for j in np.nonzero((sector[1:] != sector[:-1]) & (sector[1:] >= 0) & (sector[:-1] >= 0))[0]):
        if k - 6 < 0 or k + after >= len(ma_i[0]) or not (inside[k - 6] and inside[min(k + after + 1, n - 1)]):
            continue
        s0, s1 = sector[k - 1], sector[k]
        nc = _POS[s0] if _POS[s0] == _POS[s1] else (_NEG[s0] if _NEG[s0] == _NEG[s1] else -1)
        if nc < 0:
            continue
        level = float(np.mean(ma_i[nc, k - 6: k - 2]))
        low = float(np.min(ma_i[nc, k - 1: k + after]))
        dips.append(level - low)
        rel.append((level - low) / level if level > 0 else math.nan)
    mode = np.asarray(res["mode"][: n * sub: sub]) if "mode" in res.signals else np.zeros(n)
    flags = np.asarray(res["ctrl_flags"][: n * sub: sub]).astype(np.int64)
    saturated = core().const("BC_FLAG_SATURATED")  # the duty was clamped to [0, 1]
    return RippleStats(
        tau_mean=tau_mean,
        ripple_pp=m.ripple * scale,
        ripple_rms=m.tau_std * scale,
        ripple_ma_pp=float(np.ptp(ma_in)) * scale if ma_in.size else math.nan,
        ripple_ma_rms=float(np.std(ma_in)) * scale if ma_in.size else math.nan,
        dip_A=float(np.mean(dips)) if dips else math.nan,
        dip_pct=100.0 * float(np.nanmean(rel)) if rel else math.nan,
        n_commutations=len(dips),
        do_share=float(np.mean(mode[inside] == 2.0)) if np.any(inside) else math.nan,
        dcm_share=m.zero_current_share,
        sat_share=float(np.mean((flags[inside] & saturated) != 0)) if np.any(inside) else math.nan,
    )


def shortfall_cause(row: Mapping[str, Any], tolerance: float = 0.03) -> str | None:
    """Name the likely cause when a row of :func:`compare_methods` misses its reference by more than ``tolerance``.

    Parameters
    ----------
    row : mapping
        A row of the table (``method``, ``tau_mean_pct_ref``, ``sat_share``, ``dcm_share``).
    tolerance : float
        Allowed relative error of the mean torque (-).

    Returns
    -------
    str or None
        None within the tolerance; else a sentence: the duty saturated (the DC bus cannot drive the reference),
        discontinuous conduction (the method regulates the sampled current or torque, not its mean), the
        rectangular baseline regulating current rather than torque, or none of these (a model error).
    """
    pct = float(row["tau_mean_pct_ref"])
    if abs(pct - 100.0) <= 100.0 * tolerance:
        return None
    sat, dcm = float(row["sat_share"]), float(row["dcm_share"])
    what = f"mean torque {pct:.1f} % of the reference"
    if sat > 0.01:
        return (f"{what}: the duty saturated in {100 * sat:.0f} % of the samples, the DC bus cannot drive the "
                "reference")
    if dcm > 0.01:
        return (f"{what}: the current is discontinuous ({100 * dcm:.0f} % of the time without current) and "
                f"{row['method']} regulates the current or torque at the samples, not its mean")
    if row["method"] == "rect":
        return (f"{what}: rect regulates the current, not the torque: its current of T* / (2 k_phi) gives T* only "
                "with a flat back-EMF, and this motor's shape and the commutations differ from that")
    return f"{what}: neither duty saturation nor discontinuous conduction (model error)"


def compare_methods(drive: Drive, torques: Sequence[float], speeds: Sequence[float],
                    methods: Sequence[str] = METHODS, *, delay: int = 1, trace_sub: int = 8,
                    **control: Any) -> pd.DataFrame:
    """Run every method at every torque x speed and tabulate torque ripple and current dip.

    Parameters
    ----------
    drive : Drive
        E.g. ``bldclab.load("lu-4kw")``.
    torques : sequence of float
        Torque references (N m), > 0.
    speeds : sequence of float
        Imposed mechanical speeds (rad/s), > 0.
    methods : sequence of str
        Among ``"rect"``, ``"lu-no-do"``, ``"lu"``.
    delay : int
        Computation delay (samples) of scenario and controller: 1 (a DSP, default) or 0 (the paper's assumption).
    trace_sub : int
        Trace rows per sample.
    **control
        Further :class:`~bldclab.control.Lu` settings, the same for every method.

    Returns
    -------
    pandas.DataFrame
        One row per (method, torque, speed): ``method``, ``torque_ref`` (N m), ``torque_pct`` (% of ``T_N``),
        ``speed`` (rad/s), ``speed_rpm``, ``tau_mean`` (N m), ``tau_mean_pct_ref`` (% of the reference), the
        :class:`RippleStats` fields ``ripple_pp``, ``ripple_rms``, ``ripple_ma_pp``, ``ripple_ma_rms`` (% of the
        mean torque), ``dip_A``, ``dip_pct``, ``n_commutations``, ``do_share``, ``dcm_share``, ``sat_share``.

    Raises
    ------
    BldclabError
        For an unknown method or a non-positive torque or speed.
    """
    for mth in methods:
        if mth not in METHODS:
            raise BldclabError("methods", f"unknown method {mth!r}; choose from {', '.join(METHODS)}")
    for name, values in (("torques", torques), ("speeds", speeds)):
        for v in values:
            if not (isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and v > 0):
                raise BldclabError(name, f"must be finite numbers > 0, got {v!r}")
    rows = []
    for mth in methods:
        for tq in torques:
            for om in speeds:
                res = operating_point(drive, mth, float(tq), float(om), delay=delay, trace_sub=trace_sub,
                                         **control)
                st = ripple_stats(res, drive)
                row: dict[str, object] = {"method": mth, "torque_ref": float(tq), "torque_pct": 100.0 * tq / drive.T_N,
                                          "speed": float(om), "speed_rpm": om * 60.0 / (2.0 * math.pi)}
                row.update(asdict(st))
                row["tau_mean_pct_ref"] = 100.0 * st.tau_mean / tq
                rows.append(row)
    return pd.DataFrame(rows)


def prediction_error(res: SimResult, scale: float) -> tuple[float, int]:
    """Compare the controller's one-step torque prediction with the plant's torque at the next sample.

    The prediction ``tau_pred`` made at sample k is compared with the plant's torque ``tau_e`` at the start of
    sample k+1, over the samples of the metric window in normal conduction (mode 0 at k-1, k and k+1, no Hall edge
    between them).

    Parameters
    ----------
    res : SimResult
        A run of :class:`~bldclab.control.Lu` with a metric window.
    scale : float
        The torque the error is relative to (N m), e.g. the reference.

    Returns
    -------
    float
        Largest ``|tau_pred(k) - tau_e(k+1)| / scale`` (-).
    int
        Samples compared.
    """
    sub = _sub(res)
    m = res.metrics
    if m is None:
        raise BldclabError("result", "has no metric window")
    t = res.t[::sub]
    pred, tau, mode, hall = (np.asarray(res[s][::sub]) for s in ("tau_pred", "tau_e", "mode", "hall"))
    k = np.arange(1, len(t) - 1)
    ok = ((t[k] >= m.t0) & (t[k + 1] <= m.t1) & (mode[k - 1] == 0) & (mode[k] == 0) & (mode[k + 1] == 0)
          & (hall[k - 1] == hall[k]) & (hall[k] == hall[k + 1]))
    k = k[ok]
    if k.size == 0:
        return math.nan, 0
    return float(np.max(np.abs(pred[k] - tau[k + 1])) / scale), int(k.size)


# ------------------------------------------------------------------------------------------------------------
# figures


def _window_slice(res: SimResult, span: float | None) -> NDArray[np.bool_]:
    """Rows in the last ``span`` seconds of the metric window (all of it if None)."""
    m = res.metrics
    t = res.t
    t1 = m.t1 if m is not None else float(t[-1])
    t0 = m.t0 if m is not None else float(t[0])
    if span is not None:
        t0 = max(t0, t1 - span)
    return (t >= t0) & (t <= t1)


def fig_method(res: SimResult, *, title: str = "", span: float | None = None, fig: Figure | None = None) -> Figure:
    """Draw a run as paper 2's Figs 11-12: (a) three phase currents, (b) the duty computed, (c) the torque.

    Parameters
    ----------
    res : SimResult
        A run of :class:`~bldclab.control.Lu` (ideally with ``trace_sub > 1``).
    title : str
        Figure title.
    span : float, optional
        Show only the last ``span`` seconds of the metric window (default: the whole window).
    fig : Figure, optional
        Figure to draw into.

    Returns
    -------
    Figure
    """
    fig = fig or Figure(figsize=(8.0, 7.0), layout="constrained")
    ax = fig.subplots(3, 1, sharex=True)
    sel = _window_slice(res, span)
    t = res.t[sel] * 1e3
    for x in "abc":
        ax[0].plot(t, res[f"i_{x}"][sel], lw=0.8, label=f"i_{x}")
    ax[0].set_ylabel("(a) current [A]")
    ax[0].legend(loc="upper right", fontsize=8, ncols=3)
    ax[1].plot(t, res["duty"][sel], lw=0.9, color="tab:blue", label="duty computed")
    mode = res["mode"][sel]
    for val, color, label in ((1.0, "tab:orange", "commutation (D_c)"), (2.0, "tab:red", "D_o mode")):
        on = mode == val
        if np.any(on):
            ax[1].fill_between(t, 0.0, 1.0, where=on, color=color, alpha=0.25, lw=0, label=label)
    ax[1].set_ylim(-0.02, 1.05)
    ax[1].set_ylabel("(b) duty [-]")
    ax[1].legend(loc="lower right", fontsize=8)
    ax[2].plot(t, res["tau_e"][sel], lw=0.6, color="0.6", label="tau_e")
    sub = _sub(res)
    h = _half_means(res, "tau_mean", sub, instantaneous=False)
    tk = res.t[: len(h) * sub: sub]
    ma = 0.5 * (h[1:] + h[:-1])
    in_ma = (tk[1:] >= res.t[sel][0]) & (tk[1:] <= res.t[sel][-1])
    ax[2].plot(tk[1:][in_ma] * 1e3, ma[in_ma], lw=1.2, color="k", label="one-PWM-period mean")
    ax[2].set_ylabel("(c) torque [N m]")
    ax[2].set_xlabel("t [ms]")
    ax[2].legend(loc="lower right", fontsize=8)
    for a in ax:
        a.grid(True, lw=0.3)
    if title:
        fig.suptitle(title)
    return fig


def _fig_for(method: str, number: int, drive: Drive, torque: float | None, speed: float | None, delay: int,
             span: float | None) -> Figure:
    tq = drive.T_N if torque is None else torque
    om = drive.motor.Omega_nominal if speed is None else speed
    res = operating_point(drive, method, tq, om, delay=delay, trace_sub=8)
    if span is None:
        span = 2.0 * math.pi / (drive.motor.p * om) / 2.0
    rpm = om * 60.0 / (2.0 * math.pi)
    return fig_method(res, span=span, title=f"Fig. {number}: {_TITLES[method]} ({drive.name}, {tq:.3g} N m, "
                      f"{rpm:.0f} rpm)")


def fig10(drive: Drive, torque: float | None = None, speed: float | None = None, *, delay: int = 1,
          span: float | None = None) -> Figure:
    """Paper 2's Fig. 10: conventional rectangular current control (currents, duty, torque).

    Parameters
    ----------
    drive : Drive
    torque : float, optional
        Torque reference (N m); default ``T_N``.
    speed : float, optional
        Imposed speed (rad/s); default the rated speed ``motor.Omega_nominal``.
    delay : int
        Computation delay (samples).
    span : float, optional
        Time shown (s); default half an electrical period.

    Returns
    -------
    Figure
    """
    return _fig_for("rect", 10, drive, torque, speed, delay, span)


def fig11(drive: Drive, torque: float | None = None, speed: float | None = None, *, delay: int = 1,
          span: float | None = None) -> Figure:
    """Paper 2's Fig. 11: torque control neglecting the finite DC bus (no ``D_o``). Parameters as :func:`fig10`."""
    return _fig_for("lu-no-do", 11, drive, torque, speed, delay, span)


def fig12(drive: Drive, torque: float | None = None, speed: float | None = None, *, delay: int = 1,
          span: float | None = None) -> Figure:
    """Paper 2's Fig. 12: torque control considering the finite DC bus (``D_o``). Parameters as :func:`fig10`."""
    return _fig_for("lu", 12, drive, torque, speed, delay, span)


def method_trace(res: SimResult, span: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Torque and largest phase current of a run as one-PWM-period means over its last ``span`` seconds.

    During a commutation the largest current is the non-commutated phase's (it carries the incoming and the outgoing
    currents); in two-phase conduction it is the pair current. :func:`fig_compare` draws these traces and
    :func:`bldclab.report.bundle.methods_traces` tabulates them.

    Parameters
    ----------
    res : SimResult
        A run of :func:`operating_point` (with its metrics window).
    span : float
        Time shown (s), ending at the end of the metrics window.

    Returns
    -------
    tuple of numpy.ndarray
        Time from the start of the span (ms), mean torque (N m), mean largest ``|i_x|`` (A).
    """
    sub = _sub(res)
    h = _half_means(res, "tau_mean", sub, instantaneous=False)
    tk = res.t[: len(h) * sub: sub]
    ma = 0.5 * (h[1:] + h[:-1])
    hi = np.stack([_half_means(res, f"i_{x}", sub, instantaneous=True) for x in "abc"])
    big = np.max(np.abs(0.5 * (hi[:, 1:] + hi[:, :-1])), axis=0)
    m = res.metrics
    assert m is not None
    t0 = m.t1 - span
    sel = (tk[1:] >= t0) & (tk[1:] <= m.t1)
    return (tk[1:][sel] - t0) * 1e3, ma[sel], big[sel]


def fig_compare(drive: Drive, torque: float | None = None, speed: float | None = None, *, delay: int = 1,
                span: float | None = None) -> Figure:
    """Overlay the three methods: torque and the largest phase current, both as one-PWM-period means.

    During a commutation the largest current is the non-commutated phase's (it carries the incoming and the outgoing
    currents), so its dip shows there; in two-phase conduction it is the pair current.

    Parameters
    ----------
    drive : Drive
    torque, speed : float, optional
        Torque reference (N m) and imposed speed (rad/s); default ``T_N`` and the rated speed.
    delay : int
        Computation delay (samples).
    span : float, optional
        Time shown (s); default half an electrical period.

    Returns
    -------
    Figure
    """
    tq = drive.T_N if torque is None else torque
    om = drive.motor.Omega_nominal if speed is None else speed
    span = 2.0 * math.pi / (drive.motor.p * om) / 2.0 if span is None else span
    fig = Figure(figsize=(8.0, 5.5), layout="constrained")
    ax = fig.subplots(2, 1, sharex=True)
    for mth, color in zip(METHODS, ("tab:gray", "tab:blue", "tab:red"), strict=True):
        res = operating_point(drive, mth, tq, om, delay=delay, trace_sub=8)
        st = ripple_stats(res, drive)
        t_ms, tau, i_big = method_trace(res, span)
        ax[0].plot(t_ms, tau, color=color, lw=1.1, label=f"{mth}: ripple {st.ripple_ma_pp:.1f} % p-p")
        ax[1].plot(t_ms, i_big, color=color, lw=1.1, label=mth)
    ax[0].set_ylabel("torque [N m]")
    ax[1].set_ylabel("largest |i_x| [A]")
    ax[1].set_xlabel("t [ms]")
    for a in ax:
        a.grid(True, lw=0.3)
        a.legend(loc="lower right", fontsize=8)
    rpm = om * 60.0 / (2.0 * math.pi)
    fig.suptitle(f"Paper 2 methods compared, one-PWM-period means ({drive.name}, {tq:.3g} N m, {rpm:.0f} rpm)")
    return fig

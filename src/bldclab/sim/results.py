"""Results of a simulation: named signals, window metrics, plots, files."""

from __future__ import annotations

import json
import math
import textwrap
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._core import decode_flags
from .._files import write_atomic
from ..errors import BldclabError
from ..svg import Series, svg_plot

__all__ = ["Metrics", "SimResult", "efficiency_of"]

#: Old signal names still accepted by ``res[...]`` / ``res.<name>``
_ALIASES = {"flags": "ctrl_flags", "ctrl_flags": "flags"}


def balance_scales(src: float, emf: float, fric: float, fe: float, load: float, kin: float,
                   gross: float) -> tuple[float, float]:
    """Return the scales the energy-balance residues are divided by, in the unit of the flows given (J or W).

    Parameters
    ----------
    src, emf, fric, fe, load : float
        The DC source's total energy (with the booked switching energies), the back-EMF's, friction's, iron loss's
        and the load's, over the window (J; or their mean powers, W).
    kin : float
        Change of kinetic energy (J; or its rate, W).
    gross : float
        The shaft's gross flow, rms torque times the mean speed (times the window's length for J).

    Returns
    -------
    tuple of float
        ``(electrical, mechanical)``: ``max(|src|, |emf|)`` and ``max(|emf|, |fric|, |fe|, |load|, |kin|,
        gross)`` (:class:`Metrics`, ``balance_electrical`` and ``balance_mechanical``).
    """
    return max(abs(src), abs(emf)), max(abs(emf), abs(fric), abs(fe), abs(load), abs(kin), gross)


def efficiency_of(p_src: float, p_shaft: float) -> tuple[str, float]:
    """Return the direction of the power flow and the efficiency in that direction.

    Parameters
    ----------
    p_src : float
        Mean power out of the DC bus into the drive (W; negative: the drive feeds the bus).
    p_shaft : float
        Mean shaft power out of the machine (W; negative: the load drives the shaft).

    Returns
    -------
    tuple of (str, float)
        ``("motoring", p_shaft / p_src)`` when the bus supplies and the shaft delivers; ``("generating",
        p_src / p_shaft)`` (the bus's received power over the shaft's input, 0 when the losses take it all) when
        the shaft supplies; ``("dissipating", nan)`` when both feed the machine (there is no output, every watt in is
        lost); ``("none", nan)`` when neither feeds it.
    """
    if p_src > 0.0 and p_shaft >= 0.0:
        return "motoring", p_shaft / p_src
    if p_shaft < 0.0 and p_src <= 0.0:
        return "generating", p_src / p_shaft
    if p_src > 0.0:
        return "dissipating", math.nan
    return "none", math.nan


@dataclass(frozen=True)
class Metrics:
    """What happened over a metric window [t0, t1] of a run (computed in C from integrated power flows).

    Attributes
    ----------
    t0, t1 : float
        Window (s).
    tau_mean : float
        Mean electromagnetic torque (N m).
    tau_min, tau_max : float
        Extremes of the instantaneous torque (N m) over every integration step and event of the window: the step
        ends and, inside each step, the turning points of the cubic Hermite interpolant of the torque through its
        end values and exact time derivatives (the interpolant's error is of the order of the RK4 step's, h^4;
        the step is at most half a PWM period and lands on every gate edge and diode event). Includes the PWM
        ripple.
    ripple : float
        ``tau_max - tau_min`` (N m): the peak-to-peak instantaneous torque, PWM ripple included.
    tau_ma_min, tau_ma_max : float
        Extremes of the torque's moving average over one PWM period ``T = 1/f_pwm`` (N m), evaluated continuously:
        ``MA(t) = (A(t) - A(t - T)) / T`` with ``A`` the torque's integral, for every ``t`` in ``[t0 + T, t1]``
        that is an integration step end or a step end shifted by ``T`` (between those nodes ``MA`` is smooth; a
        cubic Hermite of ``A`` gives its values off the nodes). nan if the window is shorter than one PWM period.
    ripple_ma : float
        ``tau_ma_max - tau_ma_min`` (N m): the torque ripple with the PWM component averaged out exactly (a
        one-period average of a periodic PWM ripple is its mean), wherever it falls relative to the samples. It
        also flattens features shorter than a PWM period: a commutation spike of width ``w < T`` is reduced to
        about ``w/T`` of its height.
    tau_ma_grid_min, tau_ma_grid_max : float
        The same moving average evaluated only at the controller samples (the mean of two consecutive half
        periods), N m; always inside ``[tau_ma_min, tau_ma_max]``. nan if the window is under two samples.
    ripple_ma_grid : float
        ``tau_ma_grid_max - tau_ma_grid_min`` (N m).
    ma_lost : int
        Continuous moving-average evaluations skipped because one PWM period held more integration steps than the
        runner's history (``BC_SIM_HIST`` = 1024 step ends; ``h_max`` below about 1/500 of a PWM period); 0 in
        every run bldclab makes by default. When positive the moving-average extremes cover only part of the window
        (nan if no evaluation was left).
    tau_s_min, tau_s_max : float
        Extremes of the torque at the controller samples (carrier valleys and peaks), N m. There the phase currents
        cross their PWM-period averages, so these samples carry no PWM ripple while keeping the sampling
        resolution ``1/(2 f_pwm)``: a feature narrower than a half period (a commutation spike lasting one or two
        PWM periods) can fall between samples and be missed.
    ripple_sampled : float
        ``tau_s_max - tau_s_min`` (N m): the torque ripple without its PWM component (the measure to compare with
        closed forms that assume ideal current regulation, as long as the commutation lasts several PWM periods).
    tau_std : float
        Root-mean-square deviation of the torque from its mean (N m).
    omega_mean : float
        Mean mechanical speed (rad/s): the angle the rotor travelled over the window (tracked in C at every step)
        over the window's length; independent of the trace.
    p_src, p_Rsrc, p_cu, p_sw, p_diode, p_emf, p_cog, p_fric, p_load : float
        Mean powers (W): from the DC source into the circuit (``V_src i_dc``); lost in the source resistance, the
        windings, the switches' and the diodes' conduction; converted to mechanical (``sum e i``); cogging;
        friction; to the load.
    p_swloss, p_rr : float
        Mean switching loss (``E_on``, ``E_off`` booked at hard gate edges) and diode reverse-recovery loss
        (``E_rr`` at hard turn-ons), W (0 with the default inverter, which has no switching-loss data). The plant
        switches ideally: these are an accounting on top of the circuit, drawn from the DC source in addition to
        ``p_src`` (docs/plant.md, "Switching losses").
    p_fe : float
        Mean stator iron loss (W): eddy, hysteresis and excess terms evaluated from the back-EMF
        (``Motor.P_fe_eddy`` ...; 0 by default). It acts as a drag torque on the rotor, so it is taken from the
        shaft (the dynamometer at an imposed speed) like friction (docs/plant.md, "Iron losses").
    p_src_total : float
        Total power from the DC source, ``p_src + p_swloss + p_rr`` (W): the input of :attr:`efficiency`.
    dW_L, dW_kin : float
        Change of magnetic and kinetic energy over the window (J).
    balance_electrical : float
        ``(E_src_total - E_Rsrc - E_cu - E_sw - E_diode - E_swloss - E_rr - E_emf - dW_L) / max(|E_src_total|,
        |E_emf|)`` with ``E_src_total = E_src + E_swloss + E_rr``: the integration's energy residue
        (dimensionless). The booked switching energies enter both sides, so the residue measures the circuit's
        integration; the booking itself is checked against hand calculations (tests/test_losses.py).
    balance_mechanical : float
        ``(E_emf + E_cog - E_fric - E_fe - E_load - dW_kin) / max(|E_emf|, |E_fric|, |E_fe|, |E_load|, |dW_kin|,
        tau_rms |omega_mean| (t1 - t0))`` (dynamic mechanics; 0 otherwise). The last term, the shaft's gross energy
        flow, keeps a frictionless drive at no load (every net term near zero) from reading as unresolved.
    i_rms, i_peak : tuple of float
        Per-phase rms and peak current (A).
    efficiency : float
        Output over input power in the direction the power flows (:func:`efficiency_of`), with the shaft power
        ``p_shaft = p_emf + p_cog - p_fric - p_fe`` (positive out of the shaft) and the bus power ``p_src_total``
        (positive out of the bus): motoring ``p_shaft / p_src_total``, generating ``p_src_total / p_shaft`` (both
        between 0 and 1); nan where neither side is an output (:attr:`power_flow` says why).
    power_flow : str
        Which way the power flows over the window: ``"motoring"`` (the bus supplies, the shaft delivers:
        ``p_src_total > 0``, ``p_shaft >= 0``), ``"generating"`` (the shaft supplies, the bus receives, or nothing
        when the losses take it all: ``p_shaft < 0``, ``p_src_total <= 0``), ``"dissipating"`` (both the bus and the
        shaft feed the machine, ``p_src_total > 0``, ``p_shaft < 0``: plugging, or a motor whose electromagnetic
        power does not cover its own friction at an imposed speed; every watt in ends as loss, so no efficiency is
        defined) or ``"none"`` (no input: ``p_src_total <= 0`` and ``p_shaft >= 0``, a run in which nothing flows
        or stored energy pays the output).
    zero_current_share : float
        Share of the window during which every phase current is zero (all three phases open: the diodes that
        freewheeled the current have turned off), 0 to 1, from the plant's conduction state integrated in C. Above
        zero in a PWM-period-sized pattern it is discontinuous conduction: the PWM ripple reaches the current's
        mean, so the current is no longer its period average plus a small ripple and a regulator that samples it
        at the carrier extremes (every current controller here) does not see its mean
        (:func:`bldclab.sim.plausibility.check_conduction`). nan for a result saved before it existed.
    zero_current_intervals : int
        Intervals of the window with every phase current zero (one running at ``t0`` included): their mean length
        ``zero_current_share (t1 - t0) / zero_current_intervals`` is under a PWM period in discontinuous conduction,
        and long when the drive is off (a safe state, zero duty, a fault). 0 for a result saved before it existed.
    """

    t0: float
    t1: float
    tau_mean: float
    tau_min: float
    tau_max: float
    ripple: float
    tau_ma_min: float
    tau_ma_max: float
    ripple_ma: float
    tau_ma_grid_min: float
    tau_ma_grid_max: float
    ripple_ma_grid: float
    ma_lost: int
    tau_s_min: float
    tau_s_max: float
    ripple_sampled: float
    tau_std: float
    omega_mean: float
    p_src: float
    p_src_total: float
    p_Rsrc: float
    p_cu: float
    p_sw: float
    p_diode: float
    p_swloss: float
    p_rr: float
    p_emf: float
    p_cog: float
    p_fric: float
    p_fe: float
    p_load: float
    dW_L: float
    dW_kin: float
    balance_electrical: float
    balance_mechanical: float
    i_rms: tuple[float, float, float]
    i_peak: tuple[float, float, float]
    efficiency: float
    power_flow: str = "motoring"
    zero_current_share: float = math.nan
    zero_current_intervals: int = 0

    @classmethod
    def from_c(cls, m: np.void, acc_names: tuple[str, ...], imposed: bool, omega_integral: float) -> Metrics:
        """Build from a ``bc_sim_metrics`` record."""
        dt = float(m["t1"] - m["t0"])
        E = {name: float(v) for name, v in zip(acc_names, m["E"], strict=True)}
        p = {k: v / dt for k, v in E.items()}
        dW_L = float(m["w_l1"] - m["w_l0"])
        dW_kin = float(m["w_kin1"] - m["w_kin0"])
        E_src_total = E["src"] + E["swloss"] + E["rr"]
        # The shaft's gross energy flow, rms torque times the mean speed over the window: without friction or load
        # in a steady state every net term is ~0 and would divide a round-off residue into a large ratio.
        gross = math.sqrt(max(E["tau2"], 0.0) * dt) * abs(omega_integral) / dt
        scale_e, scale_m = balance_scales(E_src_total, E["emf"], E["fric"], E["fe"], E["load"], dW_kin, gross)
        bal_e = (E_src_total - E["Rsrc"] - E["cu"] - E["sw"] - E["diode"] - E["swloss"] - E["rr"] - E["emf"]
                 - dW_L) / max(scale_e, 1e-300)
        if imposed:
            bal_m = 0.0
        else:
            bal_m = (E["emf"] + E["cog"] - E["fric"] - E["fe"] - E["load"] - dW_kin) / max(scale_m, 1e-300)
        tau_mean = E["tau"] / dt
        ma_min, ma_max = float(m["tau_ma_min"]), float(m["tau_ma_max"])
        if int(m["n_ma"]) == 0:
            ma_min = ma_max = math.nan
        mg_min, mg_max = float(m["tau_ma_grid_min"]), float(m["tau_ma_grid_max"])
        if int(m["n_ma_grid"]) == 0:
            mg_min = mg_max = math.nan
        shaft = p["emf"] + p["cog"] - p["fric"] - p["fe"]
        p_src_total = E_src_total / dt
        return cls(
            t0=float(m["t0"]), t1=float(m["t1"]), tau_mean=tau_mean, tau_min=float(m["tau_min"]),
            tau_max=float(m["tau_max"]), ripple=float(m["tau_max"] - m["tau_min"]), tau_ma_min=ma_min,
            tau_ma_max=ma_max, ripple_ma=ma_max - ma_min, tau_ma_grid_min=mg_min, tau_ma_grid_max=mg_max,
            ripple_ma_grid=mg_max - mg_min, ma_lost=int(m["ma_lost"]), tau_s_min=float(m["tau_s_min"]),
            tau_s_max=float(m["tau_s_max"]), ripple_sampled=float(m["tau_s_max"] - m["tau_s_min"]),
            tau_std=math.sqrt(max(E["tau2"] / dt - tau_mean**2, 0.0)), omega_mean=omega_integral / dt,
            p_src=p["src"], p_src_total=p_src_total, p_Rsrc=p["Rsrc"], p_cu=p["cu"], p_sw=p["sw"],
            p_diode=p["diode"], p_swloss=p["swloss"], p_rr=p["rr"], p_emf=p["emf"],
            p_cog=p["cog"], p_fric=p["fric"], p_fe=p["fe"], p_load=p["load"], dW_L=dW_L, dW_kin=dW_kin,
            balance_electrical=bal_e, balance_mechanical=bal_m,
            i_rms=(math.sqrt(E["i2a"] / dt), math.sqrt(E["i2b"] / dt), math.sqrt(E["i2c"] / dt)),
            i_peak=(float(m["i_peak"][0]), float(m["i_peak"][1]), float(m["i_peak"][2])),
            efficiency=efficiency_of(p_src_total, shaft)[1], power_flow=efficiency_of(p_src_total, shaft)[0],
            zero_current_share=float(m["t_zero_i1"] - m["t_zero_i0"]) / dt if dt > 0 else math.nan,
            zero_current_intervals=int(m["n_zero_i1"] - m["n_zero_i0"]))

    @property
    def p_shaft(self) -> float:
        """Shaft power ``p_emf + p_cog - p_fric - p_fe`` (W), positive out of the shaft (motoring)."""
        return self.p_emf + self.p_cog - self.p_fric - self.p_fe

    def balance_flows(self) -> tuple[float, float]:
        """Return the flows the two energy-balance residues are relative to, as mean powers (W).

        See :func:`balance_scales`; ``residue * flow`` is the unbalanced power.
        """
        dt = self.t1 - self.t0
        gross = math.sqrt(self.tau_std**2 + self.tau_mean**2) * abs(self.omega_mean)
        return balance_scales(self.p_src_total, self.p_emf, self.p_fric, self.p_fe, self.p_load,
                              self.dW_kin / dt if dt > 0 else 0.0, gross)



class SimResult:
    """The outcome of :func:`bldclab.simulate`: named signals over time, window metrics, metadata.

    Signals are numpy arrays of equal length, one value per trace row; ``units`` and ``docs`` describe them.
    Instantaneous signals (``i_a``, ``tau_e``, ...) hold the value at the start of the row's window, mean signals
    (``tau_mean``, ``p_src``, ``v_a``, ...) the mean over the window (see ``docs``). Access a signal as
    ``res["i_a"]`` or ``res.i_a``.

    Parameters
    ----------
    signals : dict of str to ndarray
        Signals, including the time ``t`` (s).
    units, docs : dict of str to str
        Unit and description of each signal.
    metrics : Metrics or None
        Metrics over the scenario's metric window.
    meta : dict
        How the result was produced (drive, control, scenario, version, statistics).
    """

    def __init__(self, signals: dict[str, NDArray[np.float64]], units: dict[str, str], docs: dict[str, str],
                 metrics: Metrics | None, meta: dict[str, Any]) -> None:
        self.signals = signals
        self.units = units
        self.docs = docs
        self.metrics = metrics
        self.meta = meta
        self.thermal: Any = None  # the ThermalTrace of a run coupled with its thermal network (bldclab.sim.thermal)

    def __getitem__(self, name: str) -> NDArray[np.float64]:
        """Return the signal ``name`` (``"flags"``: the controller flags ``ctrl_flags``, the name before 0.x)."""
        name = _ALIASES.get(name, name) if name not in self.signals else name
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; signals: {', '.join(self.signals)}") from None

    def __getattr__(self, name: str) -> NDArray[np.float64]:
        """Return the signal ``name`` as an attribute."""
        if name.startswith("_") or name in ("signals", "units", "docs", "metrics", "meta", "thermal"):
            raise AttributeError(name)
        try:
            return self[name]
        except KeyError:
            raise AttributeError(f"SimResult has no signal {name!r}") from None

    def __len__(self) -> int:
        """Return the number of trace rows."""
        return len(self.signals["t"])

    @property
    def flags_raised(self) -> str:
        """The controller flags raised at any sample of the run, decoded: ``"SATURATED"``, ``"SAFE|OVERCURRENT"``.

        Empty when the controller raised none. Covers every sample, also with a thinned trace or none (the C
        runner ORs them); the per-row values are the signal ``ctrl_flags`` (decode with
        :func:`bldclab.decode_flags`).
        """
        bits = self.meta.get("controller_flags")
        if bits is None:  # a result saved before the runner kept them: from the trace
            bits = int(np.bitwise_or.reduce(self["ctrl_flags"].astype(np.int64))) if len(self) else 0
        return decode_flags(int(bits))

    def flags_summary(self) -> str:
        """Say when and how often each controller flag was raised: a finding inside the metric window, or start-up.

        From ``meta["flags"]`` (per flag, its samples, their share and first and last time over the run and inside
        the metric window): a flag raised inside the window is reported with its share of the window's samples and
        its first and last time (``"SATURATED in 1.4 % of the window's samples (0.0203-0.0495 s)"``: the operating
        point is voltage-limited that often); one raised only before the window is start-up
        (``"at start-up only (before the window): SATURATED (12 samples, 0-5e-05 s)"``), not a finding about the
        measured operating point; one raised only after it is said so.

        Returns
        -------
        str
            ``"none"`` when no flag was raised; the decoded flags (:attr:`flags_raised`) for a result saved before
            the runner kept the statistics.
        """
        stats = self.meta.get("flags")
        if stats is None:
            return self.flags_raised or "none"
        inside: list[str] = []
        before: list[str] = []
        after: list[str] = []
        t0 = self.metrics.t0 if self.metrics is not None else -math.inf
        for name, entry in stats.items():
            w = entry.get("window")
            if w:
                inside.append(f"{name} in {100.0 * w['share']:.3g} % of the window's samples "
                              f"({w['first']:.4g}-{w['last']:.4g} s)")
                continue
            r = entry["run"]
            when = f"at {r['first']:.4g} s" if r["samples"] == 1 else f"{r['first']:.4g}-{r['last']:.4g} s"
            text = f"{name} ({r['samples']} sample{'s' if r['samples'] != 1 else ''}, {when})"
            (before if r["last"] < t0 else after).append(text)
        parts = inside
        if before:
            parts.append("at start-up only (before the window): " + ", ".join(before))
        if after:
            parts.append("outside the window only: " + ", ".join(after))
        return "; ".join(parts) or "none"

    @property
    def t(self) -> NDArray[np.float64]:
        """Time of each row (s)."""
        return self.signals["t"]

    def __repr__(self) -> str:
        """Short description."""
        m = f", tau_mean={self.metrics.tau_mean:.4g} N m" if self.metrics else ""
        ctrl = self.meta.get("control", {}).get("controller", "?")
        return f"<SimResult {self.meta.get('drive', {}).get('name', '')} {ctrl}: {len(self)} rows{m}>"

    def _repr_html_(self) -> str:
        """Jupyter: the description, currents and torque as small inline SVG plots, and the metrics with units.

        The plots show the metric window (the whole run if there is none); nothing is fetched, so the notebook
        displays offline and keeps the plots when saved.
        """
        import html


        parts = [f"<p><b>{html.escape(repr(self))}</b></p>"]
        t = self.signals.get("t")
        if t is not None and len(t) > 1:
            sel = np.ones(len(t), dtype=bool)
            if self.metrics is not None:
                sel = (t >= self.metrics.t0) & (t <= self.metrics.t1)
                sel = sel if np.count_nonzero(sel) > 1 else np.ones(len(t), dtype=bool)
            t_ms = t[sel] * 1e3
            plots = []
            for names, colors, ylabel in ((("i_a", "i_b", "i_c"), ("#1f77b4", "#ff7f0e", "#2ca02c"), "current [A]"),
                                          (("tau_e",), ("#d62728",), "torque [N m]")):
                present = [(n, c) for n, c in zip(names, colors, strict=True) if n in self.signals]
                if present:
                    svg = svg_plot([Series(n, t_ms, self.signals[n][sel], c) for n, c in present], title=ylabel,
                                   xlabel="t [ms]", ylabel=ylabel, width=520, height=280, max_points=700)
                    plots.append(f'<div style="flex: 0 1 460px; min-width: 280px">{svg}</div>')
            if plots:
                parts.append(f'<div style="display: flex; flex-wrap: wrap; gap: 8px">{"".join(plots)}</div>')
        if self.metrics is not None:
            rows = []
            for k, v in asdict(self.metrics).items():
                text = (", ".join(f"{x:.6g}" for x in v) if isinstance(v, list | tuple)
                        else v if isinstance(v, str) else f"{v:.6g}")
                rows.append(f"<tr><td>{k}</td><td style=\"text-align: right\">{text}</td><td>{_metric_unit(k)}</td>"
                            "</tr>")
            parts.append("<table><thead><tr><th>metric</th><th>value</th><th>unit</th></tr></thead><tbody>"
                         + "".join(rows) + "</tbody></table>")
        return "".join(parts)

    def to_pandas(self) -> Any:
        """Return the signals as a pandas DataFrame indexed by time ``t`` (s)."""
        import pandas as pd

        df = pd.DataFrame({k: v for k, v in self.signals.items() if k != "t"}, index=pd.Index(self.t, name="t"))
        df.attrs["units"] = dict(self.units)
        return df

    def plot(self, signals: tuple[str, ...] | list[str] | None = None, *, fig: Any = None) -> Any:
        """Plot signals against time, one axis per group.

        The default figure has a title naming the drive, controller, operating point (the speed reference of a speed
        loop, else the reference) and the flags (:meth:`flags_summary`), wrapped to the figure's width, and panels
        for the phase currents, the torque (instantaneous ``tau_e`` and its mean over the metric window as a dashed
        line), the back-EMFs and, for a run with rotor dynamics, the speed (rad/s and rpm; a speed loop's reference
        dashed). The metric window is shaded on every panel.

        Parameters
        ----------
        signals : sequence of str, optional
            Signals to plot, one axis each; default: the panels above.
        fig : matplotlib.figure.Figure, optional
            Figure to draw into.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from matplotlib.figure import Figure  # deferred: matplotlib is heavy and only plots need it

        groups: list[tuple[str, ...]]
        labels: list[str]
        if signals is None:
            groups = [("i_a", "i_b", "i_c"), ("tau_e",), ("e_a", "e_b", "e_c")]
            labels = ["phase current", "torque", "back-EMF"]
            if self.meta.get("scenario", {}).get("speed", 0) is None and "omega_m" in self.signals:
                groups.append(("omega_m",))
                labels.append("speed")
        else:
            groups = [(s,) for s in signals]
            labels = list(signals)
        fig = fig or Figure(figsize=(9, 2.2 * len(groups) + 0.9), layout="constrained")
        axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0]
        m = self.metrics
        t_ms = self.t * 1e3
        for ax, group, label in zip(axes, groups, labels, strict=True):
            for name in group:
                ax.plot(t_ms, self[name], lw=0.9, label=name)
            if m is not None:
                ax.axvspan(m.t0 * 1e3, m.t1 * 1e3, color="0.9", zorder=0,
                           label="metric window" if ax is axes[0] else None)
                if group == ("tau_e",) and signals is None:
                    ax.hlines(m.tau_mean, m.t0 * 1e3, m.t1 * 1e3, colors="k", linestyles="--", lw=1.2,
                              label=f"mean {m.tau_mean:.4g} N m")
            if group == ("omega_m",):
                ref = self._speed_reference()
                if ref is not None:
                    ax.plot(ref[0] * 1e3, ref[1], color="k", ls="--", lw=1.0, label="speed reference")
                sec = ax.secondary_yaxis("right", functions=(lambda w: w * 60.0 / (2 * math.pi),
                                                             lambda n: n * 2 * math.pi / 60.0))
                sec.set_ylabel("[rpm]")
            ax.set_ylabel(f"{label} [{self.units.get(group[0], '')}]")
            ax.legend(loc="upper right", fontsize=8, ncols=len(group) + 2)
            ax.grid(True, lw=0.3)
        axes[-1].set_xlabel("t [ms]")
        width = fig.get_figwidth() * 72.0 / (10 * 0.6)  # characters of a 10-point title across the figure
        fig.suptitle(textwrap.fill(self._title(), max(40, int(width))), fontsize=10)
        return fig

    def _speed_loop(self) -> bool:
        """Whether the controller ran a speed loop (its reference is ``Scenario.omega_ref``)."""
        return bool(self.meta.get("control", {}).get("speed_loop"))

    def _speed_reference(self) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """Return the speed loop's reference as (times s, rad/s) over the run, None without a speed loop.

        From the scenario's description: a number or a piecewise-linear profile; None for a function or an array.
        """
        if not self._speed_loop() or not len(self):
            return None
        ref = self.meta.get("scenario", {}).get("omega_ref")
        t = self.t
        if isinstance(ref, int | float):
            return np.array([t[0], t[-1]]), np.array([float(ref), float(ref)])
        points = _profile_points(ref)
        if points is None:
            return None
        times = np.concatenate([[t[0]], points[0], [t[-1]]])
        values = np.concatenate([[points[1][0]], points[1], [points[1][-1]]])
        keep = (times >= t[0]) & (times <= t[-1])
        return times[keep], values[keep]

    def _title(self) -> str:
        """Drive, controller and operating point, for plot titles."""
        meta = self.meta
        parts = [str(meta.get("drive", {}).get("name", "")),
                 str(meta.get("control", {}).get("controller", ""))]
        sc = meta.get("scenario", {})
        speed = sc.get("speed")
        m = self.metrics
        if speed is None:
            parts.append("rotor dynamics")
        if m is not None:
            parts.append(f"{m.omega_mean:.4g} rad/s ({m.omega_mean * 60 / (2 * math.pi):.4g} rpm)")
            parts.append(f"tau_mean {m.tau_mean:.4g} N m over [{m.t0 * 1e3:.4g}, {m.t1 * 1e3:.4g}] ms")
        ref = sc.get("ref")
        if self._speed_loop():
            parts.append(f"speed reference {_speed_text(sc.get('omega_ref'))}")
        elif isinstance(ref, int | float):
            parts.append(f"ref {ref:.4g}")
        if "flags" in meta:
            summary = self.flags_summary()
            if summary != "none":
                parts.append(f"flags: {summary}")
        else:
            flags = self.flags_raised if ("controller_flags" in meta or "ctrl_flags" in self.signals
                                          or "flags" in self.signals) else ""
            if flags:
                parts.append(f"flags {flags}")
        return ", ".join(p for p in parts if p)

    # ---------------------------------------------------------------------------------------------------------
    # files

    def save(self, path: str | Path) -> Path:
        """Write the result to a ``.npz`` file (signals, units, metrics and metadata as JSON), atomically.

        Parameters
        ----------
        path : str or Path
            Target file; ``.npz`` is appended if missing.

        Returns
        -------
        Path
            The file written.
        """
        p = Path(path)
        if p.suffix != ".npz":
            p = p.with_suffix(p.suffix + ".npz")
        header = {"units": self.units, "docs": self.docs, "meta": self.meta,
                  "metrics": asdict(self.metrics) if self.metrics else None}
        arrays: dict[str, Any] = {"__header__": np.array(json.dumps(header, default=_json_default)), **self.signals}
        write_atomic(p, lambda fh: np.savez_compressed(fh, **arrays), None)
        return p

    @classmethod
    def load(cls, path: str | Path) -> SimResult:
        """Read a result written by :meth:`save`.

        Raises
        ------
        BldclabError
            If the file is missing or not a bldclab result.
        """
        p = Path(path)
        try:
            with np.load(p, allow_pickle=False) as z:
                header = json.loads(str(z["__header__"]))
                signals = {k: z[k] for k in z.files if k != "__header__"}
        except (OSError, KeyError, ValueError) as exc:
            raise BldclabError("result file", f"cannot read a bldclab result ({exc})", str(p)) from None
        metrics = None
        if header.get("metrics"):
            kw = header["metrics"]
            # results saved before the switching losses existed: none were booked
            kw.setdefault("p_swloss", 0.0)
            kw.setdefault("p_rr", 0.0)
            kw.setdefault("p_src_total", kw.get("p_src"))
            kw.setdefault("p_fe", 0.0)  # ... and before the iron loss
            if "power_flow" not in kw:  # ... and before the efficiency took the power flow's direction
                kw["power_flow"], kw["efficiency"] = efficiency_of(
                    kw["p_src_total"], kw["p_emf"] + kw["p_cog"] - kw["p_fric"] - kw["p_fe"])
            for f in fields(Metrics):
                if f.name in ("i_rms", "i_peak"):
                    kw[f.name] = tuple(kw[f.name])
            metrics = Metrics(**kw)
        return cls(signals, header["units"], header["docs"], metrics, header["meta"])


def _profile_points(text: object) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """Return the (times, values) of a scenario's profile description ``"profile 0 s: 0, 0.1 s: 31.4"`` (SI)."""
    if not isinstance(text, str) or not text.startswith("profile "):
        return None
    times, values = [], []
    try:
        for point in text.removeprefix("profile ").split(","):
            t_text, v_text = point.split(":")
            times.append(float(t_text.strip().removesuffix("s")))
            values.append(float(v_text))
    except ValueError:
        return None
    return np.asarray(times), np.asarray(values)


def _speed_text(ref: object) -> str:
    """Return a speed reference from the scenario's description in rpm: ``"300 rpm"``, ``"0 s: 0 rpm, 1 s: 9 rpm"``."""
    rpm = 60.0 / (2.0 * math.pi)
    if isinstance(ref, int | float):
        return f"{ref * rpm:.4g} rpm"
    points = _profile_points(ref)
    if points is None:
        return str(ref)
    return ", ".join(f"{t:g} s: {v * rpm:.4g} rpm" for t, v in zip(*points, strict=True))


def _metric_unit(name: str) -> str:
    """Return the SI unit of a :class:`Metrics` field."""
    if name in ("t0", "t1"):
        return "s"
    if name.startswith(("tau_", "ripple")):
        return "N m"
    if name == "omega_mean":
        return "rad/s"
    if name.startswith("p_"):
        return "W"
    if name.startswith("dW_"):
        return "J"
    if name.startswith("i_"):
        return "A"
    return "" if name == "power_flow" else "-"


def _json_default(obj: object) -> object:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    return str(obj)

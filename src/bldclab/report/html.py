"""The report users read: one self-contained HTML page of a square-wave vs sinusoidal comparison.

``bldclab report RESULTS_DIR|MOTOR [--out report.html]`` writes one HTML file that opens offline: its style, its
script and every number it plots are inside the file, the fonts are the system's, nothing is fetched. It shows the
drive's data with units, paper 1's Table I with equation numbers and the R-aware base speeds, torque, ripple and
efficiency against speed (closed forms and simulation overlaid, both supplies), current and torque waveforms over
an electrical period at chosen speeds, paper 2's method comparison and the fault table when they are there, and
how every number was produced (command line, version, date, drive, controllers, scenario, verdict).

Where the numbers come from:

- ``bldclab compare`` writes, beside its CSV files and figures, ``waveforms.csv`` (:func:`waveforms`),
  ``manifest.json`` (what was run and which files are there: :func:`make_manifest`) and, unless ``--no-report``,
  ``report.html`` (:func:`compare_outputs`).
- Given a results directory, the report reads those files (:func:`read_results`), plus ``methods.csv`` and
  ``methods_compared.svg`` of ``bldclab torque-control`` and ``faults.csv`` of ``bldclab faults`` if they were
  written into the same directory.
- Given a motor (catalog name or TOML file), it runs the comparison itself (:func:`motor_results`) and builds the
  same files in memory, so both ways give the same page.

The plots are drawn in the browser by a small dependency-free script shipped in ``bldclab/report_assets``
(axes, ticks, lines and markers, legend toggles, hover values, zoom and pan). Without JavaScript every plot shows
a static SVG drawn by :func:`svg_plot`, which also serves the notebook displays of
:class:`~bldclab.results.SimResult` and :class:`~bldclab.sweep.SweepRun`. Contents: ``docs/report.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import hashlib
import html
import inspect
import io
import json
import math
import platform
import re
import shlex
import sys
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from . import __version__
from .errors import BldclabError

if TYPE_CHECKING:
    from .compare import CompareResult
    from .control import Control
    from .motor import Drive

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "MANIFEST",
    "PARAMETERS",
    "REPORT",
    "WAVEFORM_SPEEDS",
    "Results",
    "Series",
    "compare_command",
    "compare_outputs",
    "configure_command",
    "make_manifest",
    "methods_traces",
    "motor_results",
    "read_results",
    "render",
    "run_command",
    "svg_plot",
    "waveforms",
]

#: Name of the manifest a results directory carries.
MANIFEST = "manifest.json"
#: Name of the report ``bldclab compare`` writes.
REPORT = "report.html"
#: ``format`` of the manifest, and its version (increased when a reader could misread a newer manifest).
FORMAT = "bldclab-results"
FORMAT_VERSION = 1
#: Per-unit speeds of the waveform panels (paper 1 discusses about 0.3 and 0.8 p.u.).
WAVEFORM_SPEEDS = (0.3, 0.8)
#: Trace rows per controller sample in the waveforms (the PWM ripple is visible).
WAVEFORM_SUB = 4

#: Files of a results directory the report reads; the others it lists.
_KNOWN = ("simulated.csv", "analytic.csv", "table1.json", "verdict.txt", "waveforms.csv", "dynamometer.csv",
          "methods.csv", "methods_traces.csv", "methods_compared.svg", "faults.csv")

_SINE, _SQUARE, _GRAY = "#1f77b4", "#d62728", "#7f7f7f"
_PHASE = {"a": "#1f77b4", "b": "#ff7f0e", "c": "#2ca02c"}
_METHOD = {"rect": "#7f7f7f", "lu-no-do": "#1f77b4", "lu": "#d62728"}
_SUPPLY = {"sine": "sinusoidal", "square": "square-wave"}

#: Every field of the drive's parts with a description and its SI unit, in display order.
PARAMETERS: dict[str, tuple[tuple[str, str, str], ...]] = {
    "motor": (
        ("p", "pole pairs", "-"),
        ("R", "phase resistance", "Ohm"),
        ("L", "phase inductance L_self - M", "H"),
        ("V_N", "nominal voltage", "V"),
        ("I_N", "nominal current (square-wave amplitude)", "A"),
        ("Omega_N", "nominal speed (rating)", "rad/s"),
        ("T_peak", "peak torque", "N m"),
        ("emf", "back-EMF shapes k_a, k_b, k_c", "V s/rad"),
        ("cogging", "cogging torque", "N m"),
    ),
    "inverter": (
        ("V_dc", "DC bus voltage", "V"),
        ("f_pwm", "PWM carrier frequency (controller sampled at 2 f_pwm)", "Hz"),
        ("t_dead", "dead time", "s"),
        ("R_on", "switch on-resistance", "Ohm"),
        ("V_f", "diode forward voltage", "V"),
        ("r_d", "diode slope resistance", "Ohm"),
        ("R_src", "DC source resistance", "Ohm"),
        ("i_trip", "hardware over-current trip (0: none)", "A"),
        ("model", "inverter model: switching (every gate edge) or average (half-period averages)", "-"),
    ),
    "mechanics": (
        ("J", "inertia of rotor and load", "kg m^2"),
        ("B", "viscous friction", "N m s/rad"),
        ("tau_c", "Coulomb friction", "N m"),
    ),
    "sensors": (
        ("current_phases", "measured phase currents", "-"),
        ("current_gain", "current sensor gains a, b, c", "-"),
        ("current_offset", "current sensor offsets a, b, c", "A"),
        ("current_noise", "current noise (standard deviation)", "A"),
        ("current_lsb", "current quantisation step", "A"),
        ("vdc_gain", "DC bus sensor gain", "-"),
        ("vdc_offset", "DC bus sensor offset", "V"),
        ("vdc_noise", "DC bus noise (standard deviation)", "V"),
        ("vdc_lsb", "DC bus quantisation step", "V"),
        ("hall_error", "Hall sensor angle errors a, b, c (electrical)", "rad"),
        ("hall_delay", "Hall edge delay", "s"),
        ("f_tick", "capture-timer frequency (Hall edge time stamps)", "Hz"),
        ("seed", "noise generator seed", "-"),
    ),
}

_RPM = 60.0 / (2.0 * math.pi)
_PREFIX = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "\u00b5"), (1e-9, "n"))


# ------------------------------------------------------------------------------------------------------------
# formatting


def _e(text: object) -> str:
    """Escape text for HTML."""
    return html.escape(str(text), quote=True)


def _num(value: object) -> str:
    """Format a value for a table: 6 significant digits, yes/no, n/a for NaN or None."""
    if value is None:
        return "n/a"
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        v = float(value)
        return "n/a" if math.isnan(v) else f"{v:.6g}"
    if isinstance(value, tuple | list):
        return ", ".join(_num(v) for v in value)
    return str(value)


def _readable(value: object, unit: str) -> str:
    """Return the value in a friendlier unit (rpm, degrees, engineering prefix), or '' if SI reads well already."""
    if not isinstance(value, float | int) or isinstance(value, bool) or not math.isfinite(value) or value == 0:
        return ""
    v = float(value)
    if unit == "rad/s":
        return f"{v * _RPM:.5g} rpm"
    if unit == "rad":
        return f"{math.degrees(v):.5g}\u00b0"
    if unit in ("Ohm", "H", "s", "A", "V", "Hz"):
        sym = "\u03a9" if unit == "Ohm" else unit
        for scale, prefix in _PREFIX:
            if abs(v) >= scale * 0.9999999:
                if scale == 1.0:
                    return ""
                return f"{v / scale:.5g} {prefix}{sym}"
        return f"{v / 1e-9:.5g} n{sym}"
    return ""


def _html_table(head: Sequence[str], rows: Sequence[Sequence[object]], numeric: Sequence[bool] | None = None,
                cls: str = "") -> str:
    """Return an HTML table; cells are escaped, numbers formatted with 6 significant digits."""
    numeric = numeric or [False] * len(head)
    out = [f'<table class="{_e(cls)}">' if cls else "<table>", "<thead><tr>"]
    out += [f'<th class="num">{_e(h)}</th>' if n else f"<th>{_e(h)}</th>" for h, n in zip(head, numeric, strict=True)]
    out.append("</tr></thead><tbody>")
    for row in rows:
        out.append("<tr>")
        for cell, n in zip(row, numeric, strict=True):
            text = _num(cell) if not isinstance(cell, str) else cell
            short = not isinstance(cell, str) or len(cell) <= 16  # a long text in a number column wraps
            out.append(f'<td class="num">{_e(text)}</td>' if n and short else f"<td>{_e(text)}</td>")
        out.append("</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def _frame_table(df: pd.DataFrame, columns: Sequence[str] | None = None) -> str:
    """Return a DataFrame as an HTML table (numeric columns right-aligned)."""
    cols = [c for c in (columns or list(df.columns)) if c in df.columns]
    numeric = [pd.api.types.is_numeric_dtype(df[c]) and not pd.api.types.is_bool_dtype(df[c]) for c in cols]
    rows = [[row[c] for c in cols] for row in df.to_dict("records")]
    return _html_table(cols, rows, numeric)


# ------------------------------------------------------------------------------------------------------------
# static SVG plots (no-JavaScript fallback, notebook displays)


@dataclass
class Series:
    """One line or point set of :func:`svg_plot`.

    Parameters
    ----------
    name : str
        Legend text.
    x, y : array_like
        Coordinates (NaN breaks a line).
    color : str
        CSS colour.
    line : bool
        Draw a line through the points.
    marker : {None, "o", "x", "s"}
        Marker drawn at every point.
    dash : str, optional
        SVG dash pattern, e.g. ``"5 4"``.
    """

    name: str
    x: Any
    y: Any
    color: str = "#333333"
    line: bool = True
    marker: str | None = None
    dash: str | None = None


def _ticks(lo: float, hi: float, n: int) -> list[tuple[float, str]]:
    """Nice tick values (1, 2, 5 times a power of ten) in [lo, hi] and their labels; as the page's script."""
    raw = (hi - lo) / n
    mag = 10.0 ** math.floor(math.log10(raw))
    r = raw / mag
    step = (1 if r < 1.5 else 2 if r < 3 else 5 if r < 7 else 10) * mag
    decimals = max(0, min(10, -math.floor(math.log10(step) + 1e-9)))
    out = []
    k = math.ceil(lo / step - 1e-9)
    while k * step <= hi + step * 1e-9 and len(out) < 50:
        v = k * step
        out.append((v, f"{0.0 if abs(v) < step * 1e-9 else v:.{decimals}f}"))
        k += 1
    return out


def _decimate(x: np.ndarray, y: np.ndarray, n_max: int) -> tuple[np.ndarray, np.ndarray]:
    """Keep at most about ``n_max`` points: the extremes of each bucket, in order (spikes survive)."""
    if x.size <= n_max:
        return x, y
    size = math.ceil(2 * x.size / n_max)
    keep: list[int] = []
    for start in range(0, x.size, size):
        seg = y[start:start + size]
        finite = np.isfinite(seg)
        if not finite.any():
            keep.append(start)
            continue
        lo = int(np.nanargmin(seg)) + start
        hi = int(np.nanargmax(seg)) + start
        keep.extend(sorted({lo, hi}))
        if not finite.all():
            keep.append(start + int(np.argmin(finite)))
    idx = np.array(sorted(set(keep)))
    return x[idx], y[idx]


def _marker_d(kind: str, px: float, py: float, r: float = 3.6) -> str:
    if kind == "x":
        return f"M{px - r:.1f} {py - r:.1f}l{2 * r} {2 * r}m0 {-2 * r}l{-2 * r} {2 * r}"
    if kind == "s":
        return f"M{px - r:.1f} {py - r:.1f}h{2 * r}v{2 * r}h{-2 * r}z"
    return f"M{px - r:.1f} {py:.1f}a{r} {r} 0 1 0 {2 * r} 0a{r} {r} 0 1 0 {-2 * r} 0"


def svg_plot(series: Sequence[Series], *, title: str = "", xlabel: str = "", ylabel: str = "",
             xlim: tuple[float | None, float | None] = (None, None),
             ylim: tuple[float | None, float | None] = (None, None),
             vlines: Sequence[Mapping[str, Any]] = (), width: int = 640, height: int = 400,
             max_points: int = 800) -> str:
    """Draw a static line/marker plot as an inline SVG string (no JavaScript, no external resources).

    Parameters
    ----------
    series : sequence of Series
        What to draw.
    title, xlabel, ylabel : str
        Texts (the title is the SVG's accessible label).
    xlim, ylim : pair of float or None
        Axis limits; None: from the data (y with 5 % margins).
    vlines : sequence of mapping
        Vertical marks: ``{"x": float, "label": str, "color": str, "dash": str}``.
    width, height : int
        Size of the plot area's viewBox (px); the legend adds rows below.
    max_points : int
        Points kept per series (extremes per bucket).

    Returns
    -------
    str
        ``<svg ...>...</svg>``, scalable (``viewBox``), without an ``xmlns`` (inline HTML needs none).
    """
    ml, mr, mt, mb = 66, 18, 14, 50
    pw, ph = width - ml - mr, height - mt - mb
    data = []
    for s in series:
        x = np.asarray(s.x, dtype=float).ravel()
        y = np.asarray(s.y, dtype=float).ravel()
        if x.shape != y.shape:
            raise BldclabError(f"series {s.name!r}", f"x and y differ in length ({x.size} and {y.size})")
        data.append((s, *_decimate(x, y, max_points)))
    fin = [(x[np.isfinite(x) & np.isfinite(y)], y[np.isfinite(x) & np.isfinite(y)]) for _, x, y in data]
    xs = np.concatenate([f[0] for f in fin]) if fin else np.zeros(0)
    ys = np.concatenate([f[1] for f in fin]) if fin else np.zeros(0)
    x0, x1 = (float(xs.min()), float(xs.max())) if xs.size else (0.0, 1.0)
    y0, y1 = (float(ys.min()), float(ys.max())) if ys.size else (0.0, 1.0)
    pad = (y1 - y0) * 0.05 or abs(y1) * 0.05 or 1.0
    y0, y1 = y0 - pad, y1 + pad
    x0 = x0 if xlim[0] is None else float(xlim[0])
    x1 = x1 if xlim[1] is None else float(xlim[1])
    y0 = y0 if ylim[0] is None else float(ylim[0])
    y1 = y1 if ylim[1] is None else float(ylim[1])
    x1 = x1 if x1 > x0 else x0 + 1.0
    y1 = y1 if y1 > y0 else y0 + 1.0

    def sx(v: float) -> float:
        return ml + (v - x0) / (x1 - x0) * pw

    def sy(v: float) -> float:
        return mt + ph - (v - y0) / (y1 - y0) * ph

    rows = math.ceil(len(series) / 2)
    total_h = height + 16 * rows + (4 if rows else 0)
    clip = "sc" + hashlib.sha1(repr((title, xlabel, ylabel, [s.name for s in series], x0, x1, y0, y1)).encode()
                               ).hexdigest()[:10]
    out = [f'<svg class="static-chart" viewBox="0 0 {width} {total_h}" role="img" aria-label="{_e(title)}" '
           f'font-family="system-ui, sans-serif" font-size="12">',
           f'<defs><clipPath id="{clip}"><rect x="{ml}" y="{mt}" width="{pw}" height="{ph}"/></clipPath></defs>',
           f'<rect x="0" y="0" width="{width}" height="{total_h}" fill="#fff"/>']
    grid, labels = [], []
    for v, label in _ticks(x0, x1, 7):
        grid.append(f"M{sx(v):.1f} {mt}V{mt + ph}")
        labels.append(f'<text x="{sx(v):.1f}" y="{mt + ph + 16}" text-anchor="middle" fill="#4b555e">{label}</text>')
    for v, label in _ticks(y0, y1, 6):
        grid.append(f"M{ml} {sy(v):.1f}H{ml + pw}")
        labels.append(f'<text x="{ml - 6}" y="{sy(v):.1f}" dy="0.32em" text-anchor="end" fill="#4b555e">{label}</text>')
    out.append(f'<path d="{"".join(grid)}" stroke="#e6eaee" fill="none"/>')
    out.extend(labels)
    out.append(f'<g clip-path="url(#{clip})">')
    for vl in vlines:
        px = sx(float(vl["x"]))
        color = _e(vl.get("color", "#888"))
        dash = f' stroke-dasharray="{_e(vl["dash"])}"' if vl.get("dash") else ""
        out.append(f'<path d="M{px:.1f} {mt}V{mt + ph}" stroke="{color}" fill="none"{dash}/>')
    for s, x, y in data:
        ok = np.isfinite(x) & np.isfinite(y)
        px = np.clip(ml + (x - x0) / (x1 - x0) * pw, -5000, 5000)
        py = np.clip(mt + ph - (y - y0) / (y1 - y0) * ph, -5000, 5000)
        if s.line:
            d, pen = [], False
            for j in range(x.size):
                if not ok[j]:
                    pen = False
                    continue
                d.append(f"{'L' if pen else 'M'}{px[j]:.1f} {py[j]:.1f}")
                pen = True
            if d:
                dash = f' stroke-dasharray="{_e(s.dash)}"' if s.dash else ""
                out.append(f'<path d="{"".join(d)}" stroke="{_e(s.color)}" stroke-width="1.6" fill="none"{dash}/>')
        if s.marker:
            m = "".join(_marker_d(s.marker, float(px[j]), float(py[j])) for j in range(x.size) if ok[j])
            if m:
                out.append(f'<path d="{m}" stroke="{_e(s.color)}" stroke-width="1.4" fill="none"/>')
    out.append("</g>")
    out.append(f'<rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="none" stroke="#8a949d"/>')
    out.append(f'<text x="{ml + pw / 2}" y="{height - 8}" text-anchor="middle" font-size="13">{_e(xlabel)}</text>')
    out.append(f'<text transform="translate(14 {mt + ph / 2}) rotate(-90)" text-anchor="middle" font-size="13">'
               f'{_e(ylabel)}</text>')
    for j, s in enumerate(series):
        lx = ml + (j % 2) * (pw / 2)
        ly = height + 6 + 16 * (j // 2)
        if s.line:
            dash = f' stroke-dasharray="{_e(s.dash)}"' if s.dash else ""
            out.append(f'<path d="M{lx:.1f} {ly + 6}h26" stroke="{_e(s.color)}" stroke-width="2"{dash}/>')
        if s.marker:
            out.append(f'<path d="{_marker_d(s.marker, lx + 13, ly + 6)}" stroke="{_e(s.color)}" fill="none"/>')
        out.append(f'<text x="{lx + 32:.1f}" y="{ly + 10}" font-size="11">{_e(s.name)}</text>')
    out.append("</svg>")
    return "".join(out)


# ------------------------------------------------------------------------------------------------------------
# producing the data


def waveforms(drive: Drive, speeds_pu: Sequence[float] = WAVEFORM_SPEEDS, *,
              controls: Mapping[str, tuple[Control, float]] | None = None, trace_sub: int = WAVEFORM_SUB
              ) -> tuple[pd.DataFrame, list[dict[str, Any]]]:
    """Simulate phase currents and torque over one electrical period at each speed, both supplies, in steady state.

    Each point runs as in :func:`bldclab.compare.compare` (:func:`bldclab.experiments.steady_state`: imposed speed,
    the same controllers and references) with a trace; the period shown is the first of the measuring window.

    Parameters
    ----------
    drive : Drive
    speeds_pu : sequence of float
        Per-unit speeds (of ``Omega_0``), > 0.
    controls : mapping, optional
        ``{"square": (control, ref), "sine": (control, ref)}``; default
        :func:`bldclab.compare.default_controls` for the lowest speed.
    trace_sub : int
        Trace rows per controller sample.

    Returns
    -------
    pandas.DataFrame
        Columns ``supply``, ``speed_pu``, ``theta_e_deg`` (electrical angle, degrees, from the window's start),
        ``t_ms`` (ms from the window's start), ``i_a``, ``i_b``, ``i_c`` (A), ``tau_e`` (N m), ``tau_e_pu``.
    list of dict
        Per supply and speed: ``supply``, ``speed_pu``, ``tau_mean_pu``, ``ripple_pu`` (without PWM),
        ``ripple_inst_pu`` (instantaneous), ``efficiency`` over the measuring window.
    """
    from .compare import SUPPLIES, default_controls
    from .experiments import electrical_period, steady_state

    w = [float(s) for s in speeds_pu]
    if not w or any(not math.isfinite(s) or s <= 0 for s in w):
        raise BldclabError("--waveform-speeds", f"must be positive per-unit speeds, got {list(speeds_pu)!r}")
    controls = controls or default_controls(drive, min(w))
    frames, points = [], []
    for supply in SUPPLIES:
        ctl, ref = controls[supply]
        for s in w:
            om = s * drive.Omega_0
            point, res = steady_state(drive, ctl, om, ref, trace=True, trace_sub=trace_sub)
            m = point.metrics
            te = electrical_period(drive, om)
            sel = (res.t >= m.t0) & (res.t < m.t0 + te)
            th = np.degrees(np.unwrap(res["theta_e"][sel]))
            th -= 360.0 * math.floor(th[0] / 360.0 + 1e-9) if th.size else 0.0
            frames.append(pd.DataFrame({
                "supply": supply, "speed_pu": s, "theta_e_deg": th, "t_ms": (res.t[sel] - m.t0) * 1e3,
                "i_a": res["i_a"][sel], "i_b": res["i_b"][sel], "i_c": res["i_c"][sel], "tau_e": res["tau_e"][sel],
                "tau_e_pu": res["tau_e"][sel] / drive.T_N}))
            points.append({"supply": supply, "speed_pu": s, "tau_mean_pu": point.tau_mean_pu,
                           "ripple_pu": point.ripple_sampled_pu, "ripple_inst_pu": point.ripple_pu,
                           "efficiency": point.efficiency})
    return pd.concat(frames, ignore_index=True), points


def methods_traces(drive: Drive, torque: float | None = None, speed: float | None = None,
                   methods: Sequence[str] = ("rect", "lu-no-do", "lu")) -> pd.DataFrame:
    """Run paper 2's methods; return torque and largest current over the last half period (one-PWM-period means).

    The same runs and quantities as :func:`bldclab.paper2.fig_compare`, as data.

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
    from . import paper2

    tq = drive.T_N if torque is None else torque
    om = drive.motor.Omega_nominal if speed is None else speed
    span = math.pi / (drive.motor.p * om)
    frames = []
    for mth in methods:
        res = paper2.operating_point(drive, mth, tq, om, trace_sub=8)
        sub = paper2._sub(res)
        h = paper2._half_means(res, "tau_mean", sub, instantaneous=False)
        tk = res.t[: len(h) * sub: sub]
        ma = 0.5 * (h[1:] + h[:-1])
        hi = np.stack([paper2._half_means(res, f"i_{x}", sub, instantaneous=True) for x in "abc"])
        big = np.max(np.abs(0.5 * (hi[:, 1:] + hi[:, :-1])), axis=0)
        m = res.metrics
        assert m is not None
        t0 = m.t1 - span
        sel = (tk[1:] >= t0) & (tk[1:] <= m.t1)
        frames.append(pd.DataFrame({"method": mth, "t_ms": (tk[1:][sel] - t0) * 1e3, "tau_ma": ma[sel],
                                    "i_max_ma": big[sel]}))
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


def _scenario() -> dict[str, Any]:
    """Return the measuring scenario of :func:`~bldclab.experiments.steady_state` as ``compare`` runs it."""
    from .experiments import steady_state
    from .sim import Scenario

    par = inspect.signature(steady_state).parameters
    delay = next(f.default for f in dataclasses.fields(Scenario) if f.name == "delay")
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


def _now() -> str:
    return datetime.datetime.now(datetime.UTC).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def _environment() -> dict[str, str]:
    from . import _core

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
        "speeds_pu": speeds, "supplies": _supplies(res.drive, controls), "scenario": _scenario(),
        "waveforms": {"speeds_pu": sorted({float(p["speed_pu"]) for p in waveform_points}),
                      "trace_sub": waveform_sub, "periods_shown": 1, "points": _plain(list(waveform_points))},
        "verdict": list(res.verdict), "files": sorted(set(files)),
    }


def compare_command(args: argparse.Namespace, out: Path) -> str:
    """Return the ``bldclab compare`` command line that reproduces a run (process count aside: results are equal)."""
    return shlex.join(["bldclab", "compare", str(args.motor), "--out", str(out), "--speeds", str(args.speeds),
                       "--min-speed", f"{args.min_speed:g}", "--max-speed", f"{args.max_speed:g}"])


def compare_outputs(res: CompareResult, files: Mapping[str, bytes], *, command: str, motor_source: str | None = None,
                    report: bool = True, waveform_speeds: Sequence[float] = WAVEFORM_SPEEDS,
                    extra: Mapping[str, Any] | None = None) -> dict[str, bytes]:
    """Return the files ``bldclab compare`` adds to its results: waveforms, manifest and (by default) the report.

    Parameters
    ----------
    res : CompareResult
        The comparison (:func:`bldclab.compare.compare` with its default controllers).
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

    Returns
    -------
    dict of str to bytes
        ``waveforms.csv``, ``manifest.json`` and, with ``report``, ``report.html``.
    """
    from .compare import default_controls

    drive = res.drive
    controls = default_controls(drive, float(np.min(res.analytic["Omega_pu"])))
    wf, points = waveforms(drive, waveform_speeds, controls=controls)
    new: dict[str, bytes] = {"waveforms.csv": wf.to_csv(index=False, float_format="%.6g").encode()}
    names = [*files, "waveforms.csv", MANIFEST, *([REPORT] if report else [])]
    manifest = make_manifest(res, controls, command=command, files=names, motor_source=motor_source or drive.name,
                             waveform_points=points, extra=extra)
    new[MANIFEST] = (json.dumps(manifest, indent=2, allow_nan=False) + "\n").encode()
    if report:
        results = Results.from_files({**files, **new}, source="the run itself (bldclab compare)")
        results.files = sorted(set(names))
        new[REPORT] = render(results, report_command=command).encode()
    return new


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
        Also run paper 2's methods (:func:`bldclab.paper2.compare_methods` on its default grid and
        :func:`methods_traces`).
    progress : bool
        Progress bar on stderr.

    Returns
    -------
    dict of str to bytes
        ``simulated.csv``, ``analytic.csv``, ``table1.json``, ``verdict.txt``, ``dynamometer.csv``,
        ``waveforms.csv``, ``manifest.json`` and, with ``torque_control``, ``methods.csv`` and
        ``methods_traces.csv``.
    """
    from . import paper1
    from .cli import table1_text
    from .compare import compare

    res = compare(drive, speeds_pu, workers=workers, progress=progress)
    files: dict[str, bytes] = {
        "simulated.csv": res.simulated.to_csv(index=False).encode(),
        "analytic.csv": res.analytic.to_csv(index=False).encode(),
        "table1.json": table1_text(res.table1, "json", res.not_applicable).encode(),
        "verdict.txt": ("\n".join(res.verdict) + "\n").encode(),
        "dynamometer.csv": paper1.fig12(drive)[1].to_csv(index=False).encode(),
    }
    extra: dict[str, Any] = {}
    if torque_control:
        from . import paper2
        from .control import Lu

        torques, speeds = paper2.default_grid(drive)
        files["methods.csv"] = paper2.compare_methods(drive, torques, speeds).to_csv(index=False).encode()
        files["methods_traces.csv"] = methods_traces(drive).to_csv(index=False, float_format="%.6g").encode()
        extra["torque_control"] = {
            "run": "bldclab.paper2.compare_methods on its default grid, then methods_traces at T_N and the rated speed",
            "torques_N_m": list(torques), "speeds_rad_s": list(speeds), "trace_sub": 8,
            "controller": _plain(Lu()), "scenario": "paper2.operating_point: imposed speed, 3 electrical periods "
            "(at least 10 ms) settling, 2 measured; computation delay 1 sample"}
    files.update(compare_outputs(res, files, command=command, motor_source=motor_source, report=False,
                                 waveform_speeds=waveform_speeds, extra=extra))
    return files


# ------------------------------------------------------------------------------------------------------------
# reading the results


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


def _csv(files: Mapping[str, bytes], name: str, columns: Sequence[str], source: str,
         required: bool = True) -> pd.DataFrame | None:
    """Parse a CSV of the results, checking its columns; None if optional and absent."""
    if name not in files:
        if required:
            raise BldclabError(name, "is missing from the results directory", source)
        return None
    try:
        df = pd.read_csv(io.BytesIO(files[name]))
    except (ValueError, UnicodeDecodeError, pd.errors.ParserError) as exc:
        raise BldclabError(name, f"is not a readable CSV file ({' '.join(str(exc).split())})", source) from None
    for c in columns:
        if c not in df.columns:
            raise BldclabError(f"{name}: column {c}", "is missing", source)
    return df


def _numeric(df: pd.DataFrame, name: str, columns: Sequence[str], source: str) -> None:
    for c in columns:
        if not pd.api.types.is_numeric_dtype(df[c]):
            raise BldclabError(f"{name}: column {c}", "must hold numbers", source)


def _clean_svg(text: str) -> str | None:
    """Return a matplotlib SVG made inline-safe (no XML prolog, metadata, namespaces); None if anything is active."""
    text = re.sub(r"<\?xml[^>]*\?>", "", text)
    text = re.sub(r"<!DOCTYPE[^>]*>", "", text)
    text = re.sub(r"<metadata>.*?</metadata>", "", text, flags=re.S)
    text = re.sub(r'\s+xmlns(:[\w-]+)?="[^"]*"', "", text).strip()
    lowered = text.lower()
    if not lowered.startswith("<svg") or "<script" in lowered or "<foreignobject" in lowered:
        return None
    if re.search(r"<[^>]*\son\w+\s*=", lowered):
        return None
    if re.search(r"https?://|url\((?!#)", text):
        return None
    return text


@dataclass
class Results:
    """What a report shows: the files of a comparison's results directory, parsed and checked.

    Attributes
    ----------
    manifest : dict
        The manifest (:func:`make_manifest`).
    drive : Drive
        The drive, rebuilt from the motor file in the manifest.
    simulated : pandas.DataFrame
        ``simulated.csv``.
    analytic : pandas.DataFrame or None
        ``analytic.csv`` (closed forms at the simulated speeds).
    table1 : list of dict
        ``table1.json``'s quantities: ``key``, ``description``, ``value``, ``unit``, ``source``.
    verdict : list of str
        ``verdict.txt`` (or the manifest's).
    waveforms, dynamometer, methods, methods_traces, faults : pandas.DataFrame or None
        The optional CSV files.
    methods_svg : str or None
        ``methods_compared.svg`` of ``bldclab torque-control``, made inline-safe.
    files : list of str
        Every file of the directory.
    source : str
        Where the files came from.
    """

    manifest: dict[str, Any]
    drive: Drive
    simulated: pd.DataFrame
    analytic: pd.DataFrame | None
    table1: list[dict[str, Any]]
    verdict: list[str]
    waveforms: pd.DataFrame | None = None
    dynamometer: pd.DataFrame | None = None
    methods: pd.DataFrame | None = None
    methods_traces: pd.DataFrame | None = None
    methods_svg: str | None = None
    faults: pd.DataFrame | None = None
    files: list[str] = dataclasses.field(default_factory=list)
    source: str = ""

    @classmethod
    def from_files(cls, files: Mapping[str, bytes], source: str) -> Results:
        """Parse and check the files of a results directory.

        Parameters
        ----------
        files : mapping of str to bytes
            File name to content (:func:`read_results`).
        source : str
            The directory, for messages.

        Returns
        -------
        Results

        Raises
        ------
        BldclabError
            Naming the file (and column or key) that is missing or wrong.
        """
        from .motor import Drive

        if MANIFEST not in files:
            raise BldclabError(MANIFEST, "is missing", source)
        try:
            manifest = json.loads(files[MANIFEST].decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise BldclabError(MANIFEST, f"is not valid JSON ({exc})", source) from None
        if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
            raise BldclabError(f"{MANIFEST}: format", f"must be {FORMAT!r} (a bldclab compare manifest)", source)
        version = manifest.get("format_version")
        if not isinstance(version, int) or not 1 <= version <= FORMAT_VERSION:
            raise BldclabError(f"{MANIFEST}: format_version", f"{version!r} is not readable by bldclab "
                               f"{__version__} (reads up to {FORMAT_VERSION})", source)
        for key in ("command", "created", "bldclab_version", "motor", "supplies", "scenario"):
            if key not in manifest:
                raise BldclabError(f"{MANIFEST}: {key}", "is missing", source)
        motor = manifest["motor"]
        if not isinstance(motor, dict) or not isinstance(motor.get("toml"), str):
            raise BldclabError(f"{MANIFEST}: motor.toml", "must hold the motor file as text", source)
        try:
            data = tomllib.loads(motor["toml"])
        except tomllib.TOMLDecodeError as exc:
            raise BldclabError(f"{MANIFEST}: motor.toml", f"is not valid TOML ({exc})", source) from None
        drive = Drive.from_dict(data, source=f"{source}: {MANIFEST}: motor.toml",
                                default_name=str(motor.get("name", "")))

        sim = _csv(files, "simulated.csv", ("supply", "Omega_pu", "T_pu", "TR_pu", "eta"), source)
        assert sim is not None
        _numeric(sim, "simulated.csv", ("Omega_pu", "T_pu", "TR_pu", "eta"), source)
        bad = sorted(set(sim["supply"].astype(str)) - set(_SUPPLY))
        if bad:
            raise BldclabError("simulated.csv: column supply", f"unknown supply {bad[0]!r} (square or sine)", source)
        an = _csv(files, "analytic.csv", ("Omega_pu", "T_s_pu", "T_q_pu"), source, required=False)
        if "table1.json" not in files:
            raise BldclabError("table1.json", "is missing from the results directory", source)
        try:
            t1 = json.loads(files["table1.json"].decode("utf-8"))
            quantities = [dict(q) for q in t1["quantities"]]
            for q in quantities:
                for k in ("key", "description", "value", "unit", "source"):
                    if k not in q:
                        raise KeyError(k)
        except (UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
            raise BldclabError("table1.json", f"is not a Table I file of bldclab ({exc!r})", source) from None
        verdict = ([v for v in files["verdict.txt"].decode("utf-8", "replace").splitlines() if v.strip()]
                   if files.get("verdict.txt") else [str(v) for v in manifest.get("verdict", [])])
        wf = _csv(files, "waveforms.csv", ("supply", "speed_pu", "theta_e_deg", "i_a", "i_b", "i_c", "tau_e_pu"),
                  source, required=False)
        if wf is not None:
            _numeric(wf, "waveforms.csv", ("speed_pu", "theta_e_deg", "i_a", "i_b", "i_c", "tau_e_pu"), source)
        dyno = _csv(files, "dynamometer.csv", ("supply", "Omega_pu", "T_motor"), source, required=False)
        methods = _csv(files, "methods.csv", ("method", "torque_pct", "speed_rpm", "ripple_pp"), source,
                       required=False)
        traces = _csv(files, "methods_traces.csv", ("method", "t_ms", "tau_ma", "i_max_ma"), source, required=False)
        faults = _csv(files, "faults.csv", ("fault",), source, required=False)
        svg = None
        if files.get("methods_compared.svg"):
            svg = _clean_svg(files["methods_compared.svg"].decode("utf-8", "replace"))
        return cls(manifest=manifest, drive=drive, simulated=sim, analytic=an, table1=quantities, verdict=verdict,
                   waveforms=wf, dynamometer=dyno, methods=methods, methods_traces=traces, methods_svg=svg,
                   faults=faults, files=sorted(files), source=source)


# ------------------------------------------------------------------------------------------------------------
# the page


class _Page:
    """Collects the tables (embedded once as JSON), the plot specs and their figures."""

    def __init__(self) -> None:
        self.tables: dict[str, pd.DataFrame] = {}
        self.plots: dict[str, dict[str, Any]] = {}

    def table(self, name: str, df: pd.DataFrame) -> str:
        self.tables[name] = df.reset_index(drop=True)
        return name

    def figure(self, pid: str, spec: dict[str, Any], caption: str) -> str:
        """Register a plot and return its ``<figure>`` with the static fallback."""
        self.plots[pid] = spec
        series = []
        for s in spec["series"]:
            df = self.tables[s["table"]]
            sel = np.ones(len(df), dtype=bool)
            for col, val in s.get("where", {}).items():
                sel &= (df[col] == val).to_numpy()
            y = df[s["y"]].to_numpy(dtype=float)[sel] * s.get("scale", 1.0)
            series.append(Series(s["name"], df[s["x"]].to_numpy(dtype=float)[sel], y, s.get("color", "#333"),
                                 s.get("line", True), s.get("marker"), s.get("dash")))
        static = svg_plot(series, title=spec.get("title", ""), xlabel=spec.get("xlabel", ""),
                          ylabel=spec.get("ylabel", ""), xlim=(spec.get("xmin"), spec.get("xmax")),
                          ylim=(spec.get("ymin"), spec.get("ymax")), vlines=spec.get("vlines", ()), max_points=600)
        return (f'<figure class="plot" id="fig-{_e(pid)}" data-plot="{_e(pid)}"><noscript>{static}</noscript>'
                f"<figcaption>{caption}</figcaption></figure>")

    def json(self) -> str:
        tables = {}
        for name, df in self.tables.items():
            data = {}
            for c in df.columns:
                col = df[c]
                if pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col):
                    data[str(c)] = [None if not math.isfinite(v) else v for v in col.to_numpy(dtype=float).tolist()]
                else:
                    data[str(c)] = [str(v) for v in col.tolist()]
            tables[name] = {"data": data}
        text = json.dumps({"tables": tables, "plots": self.plots}, separators=(",", ":"), allow_nan=False)
        return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def _asset(name: str) -> str:
    return resources.files("bldclab").joinpath("report_assets", name).read_text(encoding="utf-8")


def _t1(results: Results) -> dict[str, Any]:
    return {q["key"]: q["value"] for q in results.table1}


def _section_motor(r: Results, page: _Page) -> str:
    d = r.drive
    parts = []
    for part, rows in PARAMETERS.items():
        obj = getattr(d, part)
        body = []
        for key, desc, unit in rows:
            value = getattr(obj, key)
            if key == "emf":
                value = _emf_text(d)
            elif key == "cogging":
                value = "none" if value is None else ", ".join(
                    f"order {n}: {a:.4g} N m at {math.degrees(ph):.4g} deg"
                    for n, a, ph in zip(value.orders, value.amplitudes, value.phases, strict=True))
            text = value if isinstance(value, str) else _num(value)
            body.append([f"{part}.{key}", desc, text, unit, _readable(value, unit)])
        parts.append(f"<div><h3>{_e(part)}</h3>"
                     + _html_table(["field", "quantity", "value", "unit", "reads"], body,
                                   [False, False, True, False, True]) + "</div>")
    from . import analytic

    derived = [["k_phi", "motor constant: half the peak line-to-line shape", d.motor.k_phi, "V s/rad", ""],
               ["Omega_0", "speed base V_dc / (2 k_phi), (2)", d.Omega_0, "rad/s", _readable(d.Omega_0, "rad/s")],
               ["T_N", "torque base 2 k_phi I_N, (6)", d.T_N, "N m", ""],
               ["Omega_nominal", "rated speed used for P_R,pu, (36)", d.motor.Omega_nominal, "rad/s",
                _readable(d.motor.Omega_nominal, "rad/s")],
               ["Theta_m", "p L I_N / (2 k_phi), (22)", analytic.theta_m(d), "rad", ""],
               ["R_total", "R + R_on, used by the R-aware base speeds", analytic.r_total(d), "Ohm",
                _readable(analytic.r_total(d), "Ohm")]]
    parts.insert(1, "<div><h3>derived</h3>" + _html_table(["quantity", "meaning", "value", "unit", "reads"], derived,
                                                          [False, False, True, False, True]) + "</div>")
    th = np.linspace(0.0, 360.0, 361)
    k = d.motor.emf.k_abc(np.radians(th))
    page.table("emf", pd.DataFrame({"theta_e_deg": th, "k_a": k[0], "k_b": k[1], "k_c": k[2]}))
    emf_fig = page.figure("emf", {
        "title": "back-EMF shapes", "xlabel": "electrical angle \u03b8e [deg]", "ylabel": "k_x [V s/rad]",
        "xname": "\u03b8e [deg]", "yname": "k [V s/rad]", "xmin": 0, "xmax": 360,
        "series": [{"name": f"k_{x}", "table": "emf", "x": "theta_e_deg", "y": f"k_{x}", "color": _PHASE[x],
                    "width": 1.6} for x in "abc"]},
        "<b>Back-EMF shapes</b> of the three phases (V s/rad: back-EMF per mechanical rad/s) over an electrical "
        "period; angle 0 is where phase a's fundamental crosses zero rising.")
    desc = f"<p>{_e(d.description)}</p>" if d.description else ""
    return (f'<section id="motor"><h2>1. Motor and drive data: {_e(d.name)}</h2>{desc}'
            f'<div class="tables">{"".join(parts)}</div><div class="grid">{emf_fig}</div>'
            "<details><summary>The motor file (TOML, SI units) these data come from</summary>"
            f"<pre>{_e(r.manifest['motor']['toml'])}</pre></details></section>")


def _emf_text(d: Drive) -> str:
    shapes = d.motor.emf.shapes

    def one(s: Any) -> str:
        kind = getattr(s, "kind", type(s).__name__)
        if kind == "trapezoid":
            return f"trapezoid, flat top {s.k_phi:.6g} V s/rad over {math.degrees(s.flat_top):.4g} deg"
        if kind == "sinusoid":
            return f"sinusoid, amplitude {s.k_1:.6g} V s/rad"
        if kind == "fourier":
            return f"Fourier series, {len(s.a)} harmonics"
        if kind == "table":
            return f"table of {len(s.theta)} points, peak {max(abs(v) for v in s.k):.6g} V s/rad"
        return str(kind)

    if d.motor.emf.is_symmetric:
        return f"{one(shapes[0])}, the same on a, b, c"
    return "; ".join(f"{x}: {one(s)}" for x, s in zip("abc", shapes, strict=True))


def _not_applicable(r: Results) -> list[str]:
    """Why paper 1's closed forms do not describe the report's drive (:func:`bldclab.analytic.applicability`)."""
    from . import analytic

    return analytic.applicability(r.drive)


def _section_table1(r: Results) -> str:
    rows = [[q["key"], q["description"], q["value"], q["unit"], q["source"]] for q in r.table1]
    reasons = _not_applicable(r)
    note = ""
    if reasons:
        note = ('<p class="warning"><b>Not applicable to this drive:</b> the closed forms below are outside paper 1\'s '
                "premises here (shown for reference, labelled <i>not applicable</i> in the figures):</p><ul>"
                + "".join(f"<li>{html.escape(x)}</li>" for x in reasons) + "</ul>")
    return ('<section id="table1"><h2>2. Paper 1 Table I and derived quantities</h2>'
            "<p>Closed forms of paper 1 (R neglected; equation numbers as in the paper) and, marked <i>numeric</i>, "
            "the base speeds with the winding resistance R computed by bldclab from the drive's own back-EMF "
            "(docs/theory-paper1.md, section 6). <i>docs</i>: the consistent loss count of the same document.</p>"
            + note
            + _html_table(["key", "quantity", "value", "unit", "equation"], rows, [False, False, True, False, False])
            + "</section>")


def _base_lines(t1: Mapping[str, Any]) -> list[dict[str, Any]]:
    lines = []
    for key, label, color, dash in (("Omega_sB_pu", "\u03a9s,B (21)", _SINE, "5 4"),
                                    ("Omega_qB_pu", "\u03a9q,B (30)", _SQUARE, "5 4"),
                                    ("Omega_sB_R_pu", "\u03a9s,B with R (numeric)", _SINE, "2 3"),
                                    ("Omega_qB_R_pu", "\u03a9q,B with R (numeric)", _SQUARE, "2 3")):
        v = t1.get(key)
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v):
            lines.append({"x": float(v), "label": label, "color": color, "dash": dash})
    return lines


def _base_caption(t1: Mapping[str, Any]) -> str:
    def v(key: str) -> str:
        x = t1.get(key)
        return f"{x:.4g}" if isinstance(x, float) else "n/a"

    return (f"Vertical lines: base speeds (21) {v('Omega_sB_pu')} and (30) {v('Omega_qB_pu')} p.u. (dashed), with R "
            f"{v('Omega_sB_R_pu')} and {v('Omega_qB_R_pu')} p.u. (dotted); blue sinusoidal, red square-wave.")


def _section_characteristics(r: Results, page: _Page) -> str:
    from . import analytic

    t1 = _t1(r)
    d = r.drive
    grid = np.linspace(0.0, 1.0, 201)
    extra = [t1.get(k) for k in ("Omega_sB_pu", "Omega_qB_pu")]
    grid = np.unique(np.concatenate([grid, [0.5], [float(v) for v in extra if isinstance(v, float) and 0 < v < 1]]))
    page.table("closed_forms", analytic.characteristic(d, grid)[
        ["Omega_pu", "T_s_pu", "T_q_pu", "TR_s_pu", "TR_q_pu", "eta_s", "eta_q", "T_blac_pu"]])
    sim_cols = [c for c in r.simulated.columns if c == "supply" or pd.api.types.is_numeric_dtype(r.simulated[c])]
    page.table("simulated", r.simulated[sim_cols])
    vl = _base_lines(t1)
    x = {"xlabel": "speed \u03a9 [p.u. of \u03a90]", "xname": "\u03a9 [p.u.]", "xmin": 0, "xmax": 1}

    na = " (not applicable)" if _not_applicable(r) else ""  # outside paper 1's premises: labelled, kept

    def an(name: str, col: str, color: str, dash: str | None = None) -> dict[str, Any]:
        return {"name": name + na, "table": "closed_forms", "x": "Omega_pu", "y": col, "color": color, "dash": dash}

    def sim(name: str, col: str, supply: str, marker: str, hidden: bool = False) -> dict[str, Any]:
        return {"name": name, "table": "simulated", "x": "Omega_pu", "y": col, "where": {"supply": supply},
                "color": _SINE if supply == "sine" else _SQUARE, "line": False, "marker": marker, "hidden": hidden}

    # results written before the averaged-inverter columns existed show the ripple at the samples first
    has_avg = "TR_avg_pu" in r.simulated.columns
    ripple_series = ([sim("simulated, averaged inverter, sinusoidal", "TR_avg_pu", "sine", "x"),
                      sim("simulated, averaged inverter, square-wave", "TR_avg_pu", "square", "o")] if has_avg else [])
    ripple_series += [sim("switching, PWM-period average, sinusoidal", "TR_ma_pu", "sine", "s", has_avg),
                      sim("switching, PWM-period average, square-wave", "TR_ma_pu", "square", "s", has_avg),
                      sim("switching, at the samples, sinusoidal", "TR_pu", "sine", "s", has_avg),
                      sim("switching, at the samples, square-wave", "TR_pu", "square", "s", has_avg),
                      sim("switching, with PWM, sinusoidal", "TR_inst_pu", "sine", "s", True),
                      sim("switching, with PWM, square-wave", "TR_inst_pu", "square", "s", True)]
    figs = [
        page.figure("torque", {**x, "title": "torque vs speed", "ylabel": "mean torque [p.u. of T_N]",
                               "yname": "T [p.u.]", "ymin": 0, "vlines": vl, "series": [
                                   an("(13)/(24) sinusoidal, closed form", "T_s_pu", _SINE),
                                   an("(26)-(32) square-wave, closed form", "T_q_pu", _SQUARE),
                                   an("equivalent PM BLAC motor (IV.B)", "T_blac_pu", _GRAY, "6 4"),
                                   sim("simulated, sinusoidal", "T_pu", "sine", "x"),
                                   sim("simulated, square-wave", "T_pu", "square", "o")]},
                    "<b>Torque-speed characteristic</b> (paper 1 Fig. 7): mean electromagnetic torque over whole "
                    "electrical periods at imposed speed, against the closed forms (R neglected). "
                    + _base_caption(t1)),
        page.figure("ripple", {**x, "title": "torque ripple vs speed", "ylabel": "torque ripple [p.u. of T_N]",
                               "yname": "TR [p.u.]", "ymin": 0, "vlines": vl, "series": [
                                   an("(15)/(25) sinusoidal, closed form", "TR_s_pu", _SINE),
                                   an("(27)/(29)/(33) square-wave, closed form", "TR_q_pu", _SQUARE),
                                   *ripple_series]},
                    "<b>Torque ripple</b> (paper 1 Fig. 8), peak to peak. <i>Averaged inverter</i>: the same drive "
                    "and controller with each leg at its PWM-period average voltage, exact extremes of the "
                    "instantaneous torque: no PWM ripple, the measure the closed forms describe. The switching "
                    "drive's ripple (of its one-PWM-period average, at the controller samples, and with PWM) is in "
                    "the legend (hidden at first)."),
        page.figure("efficiency", {**x, "title": "efficiency vs speed", "ylabel": "efficiency [-]",
                                   "yname": "\u03b7", "vlines": vl, "series": [
                                       an("(39) sinusoidal, loss count (36)", "eta_s", _SINE),
                                       an("(38) square-wave, loss count (36)", "eta_q", _SQUARE),
                                       sim("simulated, sinusoidal", "eta", "sine", "x"),
                                       sim("simulated, square-wave", "eta", "square", "o")]},
                    "<b>Efficiency</b>: simulated shaft power over DC power (copper, switch and diode losses from "
                    "the actual currents); closed forms (38)/(39) with paper 1's loss count (36), defined up to the "
                    "base speed."),
    ]
    if r.dynamometer is not None and len(r.dynamometer):
        dy = r.dynamometer
        page.table("dynamometer", dy[[c for c in dy.columns if c == "supply" or
                                      pd.api.types.is_numeric_dtype(dy[c])]])
        figs.append(page.figure("dynamometer", {**x, "title": "dynamometer test", "ylabel": "torque [p.u. of T_N]",
                                                "yname": "T [p.u.]", "ymin": 0, "series": [
                                                    an("(13)/(24) sinusoidal", "T_s_pu", _SINE),
                                                    an("(26)-(32) square-wave", "T_q_pu", _SQUARE),
                                                    {**sim("measured, sinusoidal", "T_motor", "sine", "x"),
                                                     "table": "dynamometer", "scale": 1.0 / d.T_N},
                                                    {**sim("measured, square-wave", "T_motor", "square", "o"),
                                                     "table": "dynamometer", "scale": 1.0 / d.T_N}]},
                                "<b>Dynamometer test</b> (paper 1 Fig. 12): load-machine torque with the friction of "
                                "the friction test added back."))
    return ('<section id="characteristics"><h2>3. Torque, ripple and efficiency against speed</h2>'
            '<p class="hint js-only">Hover for values; drag to zoom a box, Shift+drag to pan, Ctrl+wheel to zoom, '
            "double-click to reset; click a legend entry to hide or show it.</p>"
            f'<div class="grid">{"".join(figs)}</div>{_points_table(r)}</section>')


def _points_table(r: Results) -> str:
    sim = r.simulated
    si = sim[sim.supply == "sine"].set_index("Omega_pu")
    sq = sim[sim.supply == "square"].set_index("Omega_pu")
    an = r.analytic.set_index("Omega_pu") if r.analytic is not None else None
    rows = []
    for w in sorted(set(sim["Omega_pu"])):
        a = an.loc[w] if an is not None and w in an.index else None
        rows.append([w, si["T_pu"].get(w), None if a is None else a["T_s_pu"], sq["T_pu"].get(w),
                     None if a is None else a["T_q_pu"], si["TR_pu"].get(w), sq["TR_pu"].get(w), si["eta"].get(w),
                     sq["eta"].get(w)])
    head = ["\u03a9 [p.u.]", "T sine", "(13)/(24)", "T square", "(26)-(32)", "TR sine", "TR square", "\u03b7 sine",
            "\u03b7 square"]
    return ("<details><summary>Every simulated point: the table (torque and ripple in p.u. of T_N; all columns "
            "in the data of the page and in simulated.csv)</summary><div class=\"scroll\">"
            + _html_table(head, rows, [True] * len(head)) + "</div></details>")


def _section_waveforms(r: Results, page: _Page) -> str:
    wf = r.waveforms
    head = '<section id="waveforms"><h2>4. Waveforms over an electrical period</h2>'
    if wf is None or not len(wf):
        return head + "<p class=\"note\">No waveforms.csv in these results (written by bldclab compare).</p></section>"
    speeds = sorted({float(v) for v in wf["speed_pu"]})
    points = {(p.get("supply"), float(p.get("speed_pu", -1))): p
              for p in r.manifest.get("waveforms", {}).get("points", []) if isinstance(p, dict)}
    radios, groups = [], []
    for j, s in enumerate(speeds):
        key = f"{s:g}"
        radios.append(f'<label><input type="radio" name="wave-speed" value="{key}"{" checked" if j == 0 else ""}> '
                      f"{key} p.u.</label>")
        figs = []
        for supply in ("square", "sine"):
            part = wf[(wf.supply == supply) & (wf.speed_pu == s)]
            page.table(f"wave_{supply}_{key}", part[["theta_e_deg", "i_a", "i_b", "i_c", "tau_e_pu"]])
            p = points.get((supply, s))
            stats = (f" Mean torque {p['tau_mean_pu']:.4g} p.u., ripple {p['ripple_pu']:.4g} p.u. without PWM "
                     f"({p['ripple_inst_pu']:.4g} with), efficiency {p['efficiency']:.4g}." if p else "")
            figs.append(page.figure(f"wave-{key}-currents-{supply}", {
                "title": f"phase currents, {_SUPPLY[supply]} supply, {key} p.u.",
                "xlabel": "electrical angle \u03b8e [deg]", "ylabel": "phase current [A]", "xname": "\u03b8e [deg]",
                "yname": "i [A]", "xmin": 0, "xmax": 360,
                "series": [{"name": f"i_{x}", "table": f"wave_{supply}_{key}", "x": "theta_e_deg", "y": f"i_{x}",
                            "color": _PHASE[x], "width": 1.0} for x in "abc"]},
                f"<b>Phase currents, {_SUPPLY[supply]} supply at {key} p.u.</b>{_e(stats)}"))
        series = [{"name": f"{_SUPPLY[supply]}", "table": f"wave_{supply}_{key}", "x": "theta_e_deg",
                   "y": "tau_e_pu", "color": _SINE if supply == "sine" else _SQUARE, "width": 0.9}
                  for supply in ("square", "sine")]
        figs.append(page.figure(f"wave-{key}-torque", {
            "title": f"torque, both supplies, {key} p.u.", "xlabel": "electrical angle \u03b8e [deg]",
            "ylabel": "torque [p.u. of T_N]", "xname": "\u03b8e [deg]", "yname": "\u03c4 [p.u.]", "xmin": 0,
            "xmax": 360, "series": series},
            f"<b>Instantaneous torque at {key} p.u.</b>, both supplies (PWM ripple included)."))
        groups.append(f'<div class="wave-group" data-group="wave" data-value="{key}"><h3>{key} p.u. '
                      f'({s * r.drive.Omega_0 * _RPM:.4g} rpm)</h3><div class="grid">{"".join(figs)}</div></div>')
    sub = r.manifest.get("waveforms", {}).get("trace_sub", "?")
    return (head + "<p>Steady state at imposed speed, the first electrical period of the measuring window, "
            f"{_e(sub)} trace rows per controller sample (the PWM ripple shows). Same controllers and references "
            "as the comparison.</p>"
            f'<div class="selector" data-selector="wave" role="radiogroup" hidden>Speed: {"".join(radios)}</div>'
            + "".join(groups) + "</section>")


def _section_paper2(r: Results, page: _Page) -> str:
    if r.methods is None and r.methods_traces is None and r.methods_svg is None:
        return ""
    out = ['<section id="paper2"><h2>5. Paper 2: torque control methods compared</h2>'
           "<p>Conventional rectangular current control (<i>rect</i>), torque control neglecting the finite DC bus "
           "(<i>lu-no-do</i>) and considering it (<i>lu</i>, with D_o), at imposed speed. Ripple in % of the mean "
           "torque; <i>ma</i>: of the one-PWM-period moving average; dip: of the non-commutated current; "
           "<i>tau_mean_pct_ref</i>: the mean torque in % of the reference; <i>dcm_share</i>: the share of the time "
           "without phase current (discontinuous conduction within the PWM period, at light load: there a law that "
           "holds the torque at the samples gives more than the reference on average, and <i>lu</i>'s mean law "
           "holds the mean instead; theory page of paper 2, section 5.1).</p>"]
    tc = r.manifest.get("torque_control")
    if isinstance(tc, dict):
        rows = [["how", str(tc.get("run", ""))], ["scenario", str(tc.get("scenario", ""))],
                ["torques [N m]", _num(tc.get("torques_N_m", []))],
                ["speeds [rad/s]", _num(tc.get("speeds_rad_s", []))]]
        rows += _settings_rows("controller.", tc.get("controller", {}))
        out.append("<details><summary>How these were run (controller settings)</summary>"
                   + _html_table(["setting", "value"], rows) + "</details>")
    else:
        out.append("<p class=\"note\">From the files <code>bldclab torque-control ... --out</code> wrote into this "
                   "directory (methods.csv, methods_compared.svg); their command line is not recorded here.</p>")
    if r.methods is not None:
        cols = ["method", "torque_pct", "speed_rpm", "tau_mean_pct_ref", "ripple_pp", "ripple_rms", "ripple_ma_pp",
                "ripple_ma_rms", "dip_A", "dip_pct", "do_share", "dcm_share"]
        out.append('<div class="scroll">' + _frame_table(r.methods, cols) + "</div>")
    if r.methods_traces is not None and len(r.methods_traces):
        tr = r.methods_traces
        page.table("methods_traces", tr[["method", "t_ms", "tau_ma", "i_max_ma"]])
        methods = [m for m in ("rect", "lu-no-do", "lu") if m in set(tr["method"])]
        figs = [page.figure(pid, {"title": title, "xlabel": "t [ms]", "ylabel": ylabel, "xname": "t [ms]",
                                  "yname": yname, "series": [
                                      {"name": m, "table": "methods_traces", "x": "t_ms", "y": col,
                                       "where": {"method": m}, "color": _METHOD[m]} for m in methods]}, caption)
                for pid, title, col, ylabel, yname, caption in (
                    ("methods-torque", "torque, one-PWM-period mean", "tau_ma", "torque [N m]", "\u03c4 [N m]",
                     "<b>Torque</b> of the three methods over half an electrical period (one-PWM-period means)."),
                    ("methods-current", "largest phase current", "i_max_ma", "largest |i_x| [A]", "|i| [A]",
                     "<b>Largest phase current</b>: during a commutation, the non-commutated phase's (its dip)."))]
        out.append(f'<div class="grid">{"".join(figs)}</div>')
    elif r.methods_svg is not None:
        out.append(f'<figure class="static">{r.methods_svg}<figcaption><b>Torque and largest current of the three '
                   "methods</b> (methods_compared.svg of bldclab torque-control, a static figure).</figcaption>"
                   "</figure>")
    out.append("</section>")
    return "".join(out)


def _section_faults(r: Results) -> str:
    if r.faults is None:
        return ""
    return ('<section id="faults"><h2>6. Faults</h2><p>Each injected fault (bldclab faults): whether the controller '
            "detected it, time to detection and to the safe state (ms), hardware trip, peak current and the mean "
            'torque after it.</p><div class="scroll">' + _frame_table(r.faults) + "</div></section>")


def _settings_rows(prefix: str, settings: Any) -> list[list[str]]:
    rows: list[list[str]] = []
    if isinstance(settings, dict):
        for k, v in settings.items():
            if k == "class":
                continue
            if isinstance(v, dict):
                rows.append([f"{prefix}{k}", str(v.get("class", ""))])
                rows.extend(_settings_rows(f"{prefix}{k}.", v))
            else:
                rows.append([f"{prefix}{k}", "None" if v is None else _num(v) if not isinstance(v, str) else v])
    return rows


def _section_provenance(r: Results, report_command: str, created: str) -> str:
    m = r.manifest
    env = m.get("environment", {})
    sc = m.get("scenario", {})
    d = r.drive
    speeds = [float(v) for v in m.get("speeds_pu", sorted(set(r.simulated["Omega_pu"])))]
    fpwm = d.inverter.f_pwm

    def dl(items: Sequence[tuple[str, str]]) -> str:
        return '<dl class="prov">' + "".join(f"<dt>{_e(k)}</dt><dd>{v}</dd>" for k, v in items) + "</dl>"

    runs = dl([
        ("command", f"<code>{_e(m['command'])}</code>"),
        ("bldclab", _e(m["bldclab_version"]) + (f" (C core {_e(env['core'])})" if env.get("core") else "")),
        ("date", _e(m["created"])),
        ("environment", _e(", ".join(f"{k} {v}" for k, v in env.items() if k != "core"))),
        ("wall time", _e(f"{m.get('wall_time_s', float('nan')):.3g} s for the comparison's simulations")),
        ("motor", _e(f"{m['motor'].get('name', '')} (given as {m['motor'].get('source', '?')}); the motor file is "
                     "in section 1")),
        ("speeds", _e(f"{len(speeds)} per supply, {min(speeds):.4g} to {max(speeds):.4g} p.u. of Omega_0 = "
                      f"{d.Omega_0:.6g} rad/s" if speeds else "none")),
    ])
    supplies = []
    for supply, info in m.get("supplies", {}).items():
        rows = [["controller", str(info.get("controller", ""))],
                ["set-point", f"{_num(info.get('reference'))} {info.get('reference_unit', '')}: "
                              f"{info.get('reference_meaning', '')}"]]
        rows += _settings_rows("", info.get("settings", {}))
        supplies.append(f"<div><h3>{_e(_SUPPLY.get(supply, supply))} supply</h3>"
                        + _html_table(["setting", "value"], rows) + "</div>")
    scen = dl([
        ("speed", _e(sc.get("speed", ""))),
        ("start", _e(sc.get("start", ""))),
        ("settling", _e(f"the first max({sc.get('settle_periods')} electrical periods, {sc.get('settle_time_s')} s "
                        "rounded up to whole periods) are discarded")),
        ("measuring", _e(f"the next {sc.get('measure_periods')} whole electrical periods")),
        ("sampling", _e(f"controller at every carrier valley and peak, 2 f_pwm = {2 * fpwm:.6g} Hz; output applied "
                        f"after {sc.get('delay_samples')} sample(s)")),
        ("mean torque", "mean electromagnetic torque over the measuring window"),
        ("torque ripple", "max - min of the torque at the controller samples (without the PWM component); the "
                          "instantaneous one in TR_inst_pu"),
        ("efficiency", "shaft power (electromechanical minus friction) over the DC source's power"),
        ("closed forms", "paper 1's equations (bldclab.analytic), R neglected, evaluated at 201 speeds and the region "
                         "boundaries for the curves, at the simulated speeds in analytic.csv"),
    ])
    files = ", ".join(f"<code>{_e(f)}</code>" for f in r.files)
    return ('<section id="provenance"><h2>How every number was produced</h2>'
            f"<h3>The run</h3>{runs}<h3>This report</h3>"
            + dl([("command", f"<code>{_e(report_command)}</code>"), ("bldclab", _e(__version__)),
                  ("date", _e(created)), ("read from", _e(r.source))])
            + f'<h3>Supplies and controllers</h3><div class="tables">{"".join(supplies)}</div>'
            f"<h3>Scenario</h3>{scen}<h3>Verdict</h3>{_verdict_list(r.verdict)}"
            f"<h3>Files of the results</h3><p>{files}</p></section>")


def _verdict_list(verdict: Sequence[str]) -> str:
    if not verdict:
        return "<p>(no verdict)</p>"
    return "<ul>" + "".join(f"<li>{_e(v)}</li>" for v in verdict) + "</ul>"


def render(results: Results, *, report_command: str, created: str | None = None) -> str:
    """Render the report page.

    Parameters
    ----------
    results : Results
        What to show.
    report_command : str
        The command line that made the report (shown with the run's own).
    created : str, optional
        Date of the report (ISO 8601); default now.

    Returns
    -------
    str
        One HTML document: style, script and data inline, no external resource.
    """
    created = created or _now()
    page = _Page()
    r = results
    name = r.drive.name or "(unnamed drive)"
    body = [_section_motor(r, page), _section_table1(r), _section_characteristics(r, page),
            _section_waveforms(r, page), _section_paper2(r, page), _section_faults(r),
            _section_provenance(r, report_command, created)]
    toc = [("verdict", "Verdict"), ("motor", "Motor"), ("table1", "Table I"), ("characteristics", "Characteristics"),
           ("waveforms", "Waveforms")]
    if r.methods is not None or r.methods_traces is not None or r.methods_svg is not None:
        toc.append(("paper2", "Paper 2"))
    if r.faults is not None:
        toc.append(("faults", "Faults"))
    toc.append(("provenance", "How it was produced"))
    nav = "".join(f'<a href="#{k}">{_e(v)}</a>' for k, v in toc)
    n = len(set(r.simulated["Omega_pu"]))
    head = (f'<header class="top"><div class="wrap"><h1>bldclab report: {_e(name)}</h1>'
            "<p>Square-wave vs sinusoidal supply (paper 1): switching-level simulation beside the closed forms, "
            f"{n} speeds per supply.</p><p>Results of <code>{_e(r.manifest['command'])}</code>, "
            f"{_e(r.manifest['created'])}; bldclab {_e(r.manifest['bldclab_version'])}.</p></div></header>")
    verdict = (f'<section id="verdict"><h2>Verdict</h2><div class="verdict">{_verdict_list(r.verdict)}'
               "<p class=\"muted\">Which supply gives more mean torque, less ripple (without PWM) and more efficiency, "
               "speed range by speed range, from the simulation.</p></div></section>")
    data = page.json()
    return "\n".join([
        "<!DOCTYPE html>",
        '<html lang="en" data-js-errors="0">',
        "<head>",
        '<meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f'<meta name="generator" content="bldclab {_e(__version__)}">',
        f"<title>bldclab report: {_e(name)}</title>",
        f"<style>\n{_asset('report.css')}</style>",
        f"<script>\n{_asset('errors.js')}</script>",
        "</head>",
        "<body>",
        head,
        f'<nav class="toc"><div class="wrap">{nav}</div></nav>',
        '<main class="wrap">',
        '<noscript><p class="noscript">JavaScript is off: the plots are static pictures of the same data (no hover '
        "values, zoom or legend toggles), and every waveform speed is shown.</p></noscript>",
        verdict,
        *body,
        "</main>",
        '<footer><div class="wrap">Made by bldclab ' + _e(__version__) + " on " + _e(created) + ". One self-contained "
        "file: its style, plotting script (bldclab's own, MIT licence) and data are inside it; nothing is fetched "
        "from the network and the fonts are your system's.</div></footer>",
        f'<script type="application/json" id="bldclab-data">{data}</script>',
        f"<script>\n{_asset('report.js')}</script>",
        "</body>",
        "</html>",
        "",
    ])


# ------------------------------------------------------------------------------------------------------------
# command line (registered in bldclab.cli)


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab report``."""
    p.add_argument("source", metavar="RESULTS_DIR|MOTOR",
                   help="a directory written by bldclab compare, or a motor (built-in name or TOML file): then the "
                   "comparison is run first")
    p.add_argument("--out", type=Path, help="the HTML file (default: RESULTS_DIR/report.html, or "
                   "out/<motor>/report.html for a motor)")
    p.add_argument("--speeds", type=int, help="motor only: speeds per supply (default 32)")
    p.add_argument("--min-speed", type=float, help="motor only: lowest speed, p.u. of Omega_0 (default 0.05)")
    p.add_argument("--max-speed", type=float, help="motor only: highest speed, p.u. of Omega_0 (default 0.98)")
    p.add_argument("--waveform-speeds", help='motor only: per-unit speeds of the waveform panels (default "0.3,0.8")')
    p.add_argument("--torque-control", action="store_true",
                   help="motor only: also compare paper 2's torque control methods (table and torque traces)")
    p.add_argument("--workers", type=int, default=0, help="motor only: processes (default: all cores; 1: serial)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _speeds_list(text: str) -> list[float]:
    try:
        values = [float(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise BldclabError("--waveform-speeds", f"expected per-unit speeds separated by commas, got {text!r}") from None
    if not values or any(not math.isfinite(v) or not 0 < v < 1.5 for v in values):
        raise BldclabError("--waveform-speeds", f"needs per-unit speeds in (0, 1.5), got {text!r}")
    return values


def _motor_only(args: argparse.Namespace) -> list[str]:
    given = [("--speeds", args.speeds), ("--min-speed", args.min_speed), ("--max-speed", args.max_speed),
             ("--waveform-speeds", args.waveform_speeds)]
    out = [name for name, v in given if v is not None]
    if args.torque_control:
        out.append("--torque-control")
    if args.workers:
        out.append("--workers")
    return out


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab report``: read or run a comparison, write one HTML file."""
    from .catalog import load
    from .cli import write_files
    from .compare import speed_grid

    src = Path(args.source)
    if src.is_dir():
        extra = _motor_only(args)
        if extra:
            raise BldclabError(extra[0], "applies to a motor; a results directory is reported as it is")
        out = args.out if args.out is not None else src / REPORT
        results = Results.from_files(read_results(src), source=str(src))
        parts = ["bldclab", "report", str(src), "--out", str(out)]
    else:
        drive = load(args.source)
        n = 32 if args.speeds is None else args.speeds
        lo = 0.05 if args.min_speed is None else args.min_speed
        hi = 0.98 if args.max_speed is None else args.max_speed
        if n < 2:
            raise BldclabError("--speeds", f"needs at least 2, got {n}")
        if not 0 < lo < hi < 1.5:
            raise BldclabError("--min-speed", "needs 0 < min-speed < max-speed < 1.5 (p.u. of Omega_0)")
        if args.workers < 0:
            raise BldclabError("--workers", f"must be >= 0, got {args.workers}")
        wspeeds = _speeds_list(args.waveform_speeds) if args.waveform_speeds is not None else list(WAVEFORM_SPEEDS)
        out = args.out if args.out is not None else Path("out") / drive.name / REPORT
        parts = ["bldclab", "report", str(args.source), "--out", str(out), "--speeds", str(n), "--min-speed",
                 f"{lo:g}", "--max-speed", f"{hi:g}", "--waveform-speeds", ",".join(f"{v:g}" for v in wspeeds)]
        if args.torque_control:
            parts.append("--torque-control")
        command = shlex.join(parts)
        files = motor_results(drive, speed_grid(n, lo, hi), command=command, motor_source=str(args.source),
                              workers=args.workers or None, waveform_speeds=wspeeds,
                              torque_control=args.torque_control,
                              progress=not args.no_progress and sys.stderr.isatty())
        results = Results.from_files(files, source=f"a comparison run by this command ({drive.name})")
    if out.exists() and out.is_dir():
        out = out / REPORT
    text = render(results, report_command=shlex.join(parts))
    (path,) = write_files(out.parent, {out.name: text.encode()})
    print(f"wrote {path} ({len(text.encode()) / 1024:.0f} kB)")
    return 0

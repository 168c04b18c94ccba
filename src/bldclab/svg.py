"""Static SVG line and marker plots, dependency-free (numpy only).

:func:`svg_plot` draws the no-JavaScript fallback of every plot of the HTML report and the notebook displays of
:class:`~bldclab.sim.results.SimResult` and :class:`~bldclab.sweep.SweepRun`. It sits in the base layer, so any
layer may draw with it.
"""

from __future__ import annotations

import hashlib
import html
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import BldclabError

__all__ = [
    "Series",
    "svg_plot",
]


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
    out: list[tuple[float, str]] = []
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
        vx = sx(float(vl["x"]))
        color = _e(vl.get("color", "#888"))
        dash = f' stroke-dasharray="{_e(vl["dash"])}"' if vl.get("dash") else ""
        out.append(f'<path d="M{vx:.1f} {mt}V{mt + ph}" stroke="{color}" fill="none"{dash}/>')
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


def _e(text: object) -> str:
    """Escape text for HTML."""
    return html.escape(str(text), quote=True)

"""Contour plots of an efficiency map (:func:`bldclab.analysis.effmap.efficiency_map`).

As in :mod:`bldclab.report.plots`: :class:`matplotlib.figure.Figure` directly, never ``pyplot`` state; each function
returns a new figure. Axes: speed (rpm) across, torque reference (N m) up; points outside a supply's envelope
(``feasible`` False) are left blank.
"""

from __future__ import annotations

from concurrent.futures import Executor
from typing import TYPE_CHECKING

import numpy as np

from ..analysis.effmap import EffMapResult
from .plots import FigureJob, render_figures

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["effmap_figures", "plot_difference", "plot_efficiency_maps", "plot_losses"]

_NAMES = {"square": "square-wave supply", "sine": "sinusoidal supply"}
_BUCKET_NAMES = {"p_Rsrc": "source resistance", "p_cu": "copper (windings)", "p_sw": "switch conduction",
                 "p_diode": "diodes", "p_fric": "friction", "p_swloss": "switching", "p_rr": "reverse recovery",
                 "p_fe": "iron (stator core)"}


def _figure(rows: int, cols: int) -> Figure:
    from matplotlib.figure import Figure  # deferred: matplotlib loads when a figure is drawn, not with the CLI

    return Figure(figsize=(5.2 * cols, 4.0 * rows), layout="constrained")


def _contour(fig: Figure, ax: Axes, res: EffMapResult, z: np.ndarray, label: str, *, cmap: str = "viridis",
             levels: int | np.ndarray = 12) -> None:
    """Draw filled contours of ``z`` (torques x speeds), or markers when the grid is too small to contour."""
    x = res.speeds * 30.0 / np.pi
    y = res.torques
    ok = np.isfinite(z)
    if ok.sum() >= 4 and x.size >= 2 and y.size >= 2 and np.nanmax(z) > np.nanmin(z):
        filled = ax.contourf(x, y, np.ma.masked_invalid(z), levels=levels, cmap=cmap)
        ax.contour(filled, colors="k", linewidths=0.3)
        fig.colorbar(filled, ax=ax, label=label, format="%.3g")
    else:
        xx, yy = np.meshgrid(x, y)
        fig.colorbar(ax.scatter(xx[ok], yy[ok], c=z[ok], cmap=cmap, marker="s"), ax=ax, label=label)
    xx, yy = np.meshgrid(x, y)
    ax.plot(xx[~ok], yy[~ok], linestyle="none", marker="x", color="0.6", markersize=3)
    ax.set_xlabel("speed (rpm)")
    ax.set_ylabel("torque reference (N m)")


def plot_efficiency_maps(res: EffMapResult) -> Figure:
    """Efficiency of each supply over the plane, one panel each (grey x: outside the supply's envelope)."""
    supplies = [s for s in ("square", "sine") if (res.points.supply == s).any()]
    fig = _figure(1, len(supplies))
    zs = [res.grid(s, "efficiency") for s in supplies]
    finite = np.concatenate([z[np.isfinite(z)] for z in zs]) if zs else np.array([])
    # levels at quantiles of the values (rounded to 0.001): equal areas per colour band, so the wide region of
    # high efficiency is resolved instead of falling into one band of a linear scale
    levels: int | np.ndarray = 12
    if finite.size:
        q = np.quantile(finite, np.linspace(0.0, 1.0, 13))
        q[0], q[-1] = np.floor(q[0] * 1e3) / 1e3, np.ceil(q[-1] * 1e3) / 1e3
        q = np.unique(np.round(q, 3))
        levels = q if q.size >= 3 else 12
    for j, (s, z) in enumerate(zip(supplies, zs, strict=True)):
        ax = fig.add_subplot(1, len(supplies), j + 1)
        _contour(fig, ax, res, z, "efficiency", levels=levels)
        ax.set_title(f"{res.drive.name}: {_NAMES[s]}")
    return fig


def plot_difference(res: EffMapResult) -> Figure:
    """``eta_sine - eta_square`` on the common feasible points: diverging colours, the zero contour in black."""
    fig = _figure(1, 1)
    ax = fig.add_subplot()
    z = res.grid("difference", "d_eta")
    span = float(np.nanmax(np.abs(z))) if np.isfinite(z).any() else 0.0
    span = max(span, res.resolution)
    _contour(fig, ax, res, z, "eta_sine - eta_square", cmap="RdBu_r", levels=np.linspace(-span, span, 17))
    rpm, zm = res.speeds * 30.0 / np.pi, np.ma.masked_invalid(z)
    if np.isfinite(z).sum() >= 4 and res.speeds.size >= 2 and res.torques.size >= 2:
        if np.nanmin(z) < 0.0 < np.nanmax(z):
            ax.contour(rpm, res.torques, zm, levels=[0.0], colors="k", linewidths=1.5)
        bounds = [b for b in (-res.resolution, res.resolution) if np.nanmin(z) < b < np.nanmax(z)]
        if bounds:
            ax.contour(rpm, res.torques, zm, levels=bounds, colors="k", linewidths=1.0, linestyles="dashed")
    ax.set_title(f"{res.drive.name}: eta_sine - eta_square (red: sine better)\nsolid: equal; dashed: "
                 f"+-{res.resolution:g}, the resolved difference", fontsize=9)
    return fig


def plot_losses(res: EffMapResult) -> Figure:
    """One panel per loss bucket and supply (W); buckets zero everywhere are listed in the title, not drawn."""
    supplies = [s for s in ("square", "sine") if (res.points.supply == s).any()]
    shown = [b for b in res.buckets if float(np.nanmax(np.abs(res.points[b].to_numpy(dtype=float)), initial=0.0)) > 0]
    zero = [b for b in res.buckets if b not in shown]
    fig = _figure(max(1, len(shown)), len(supplies))
    for i, b in enumerate(shown):
        for j, s in enumerate(supplies):
            ax = fig.add_subplot(len(shown), len(supplies), i * len(supplies) + j + 1)
            _contour(fig, ax, res, res.grid(s, b), f"{b} (W)", cmap="magma")
            ax.set_title(f"{_BUCKET_NAMES.get(b, b)}, {_NAMES[s]}", fontsize=9)
    if zero:
        fig.suptitle(f"{res.drive.name}: zero everywhere: {', '.join(zero)}", fontsize=9)
    return fig


def effmap_figures(res: EffMapResult, executor: Executor | None = None) -> dict[str, bytes]:
    """Return the figure files of ``bldclab effmap``: efficiency, difference and loss maps, PNG and SVG each.

    Parameters
    ----------
    res : EffMapResult
    executor : concurrent.futures.Executor, optional
        Draw the three figures on its workers, in parallel (the pool that ran the map); in this process if omitted.

    Returns
    -------
    dict of str to bytes
        ``effmap_efficiency.png``, ``effmap_efficiency.svg``, ``effmap_difference.png``, ... (undated SVG: reruns
        give equal files).
    """
    jobs = {"effmap_losses": FigureJob(plot_losses, (res,), dated=False),  # the costliest first
            "effmap_efficiency": FigureJob(plot_efficiency_maps, (res,), dated=False),
            "effmap_difference": FigureJob(plot_difference, (res,), dated=False)}
    drawn = render_figures(jobs, executor)
    return {f"{stem}.{fmt}": drawn[stem][0][fmt]
            for stem in ("effmap_efficiency", "effmap_difference", "effmap_losses") for fmt in ("png", "svg")}

"""The desync map's figure (:func:`bldclab.analysis.desync.desync_map`).

As in :mod:`bldclab.report.plots`: :class:`matplotlib.figure.Figure` directly, never ``pyplot`` state; the function
returns a new figure. Left: the outcome of each point (colour) with the controller's reason (text); right: the
plant's smallest margin from the end of the demagnetisation to the floating phase's back-EMF zero crossing after the
step, ``margin_deg`` (deg electrical; below zero the demagnetisation outlasted the crossing and hid it), with the
points where the plant's truth saw a commutation out of sync circled.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..analysis.desync import OUTCOMES, SHORT_REASONS, DesyncMapResult
from .plots import figure_bytes

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["OUTCOME_COLOURS", "desync_figures", "plot_desync_map"]

#: Colour of each outcome on the map.
OUTCOME_COLOURS = {"sync": "#4caf50", "recovered": "#ffc107", "desync": "#e53935", "undetected": "#8e24aa",
                   "no start": "#9e9e9e", "refused": "#212121"}


def _ticks(ax: Axes, res: DesyncMapResult) -> None:
    ax.set_xticks(range(len(res.x.values)), [f"{v:g}" if not isinstance(v, str) else v for v in res.x.values])
    ax.set_xlabel(res.x.label)
    if res.y is not None:
        ax.set_yticks(range(len(res.y.values)), [f"{v:g}" if not isinstance(v, str) else v for v in res.y.values])
        ax.set_ylabel(res.y.label)
    else:
        ax.set_yticks([])


def plot_desync_map(res: DesyncMapResult) -> Figure:
    """Draw the outcome map with the reasons, and the demagnetisation margin beside it."""
    from matplotlib.colors import ListedColormap  # deferred: matplotlib loads when a figure is drawn
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    nx = len(res.x.values)
    ny = len(res.y.values) if res.y is not None else 1
    fig = Figure(figsize=(max(9.0, 1.1 * nx * 2 + 3.0), max(3.2, 0.55 * ny + 2.4)), layout="constrained")
    ax, ax2 = fig.subplots(1, 2)
    outcome = res.grid("outcome")
    reason = res.grid("reason")
    code = np.vectorize(lambda o: OUTCOMES.index(o) if o in OUTCOMES else len(OUTCOMES) - 1)(outcome)
    cmap = ListedColormap([OUTCOME_COLOURS[o] for o in OUTCOMES])
    ax.imshow(code, cmap=cmap, vmin=-0.5, vmax=len(OUTCOMES) - 0.5, origin="lower", aspect="auto")
    for k in range(ny):
        for j in range(nx):
            r = str(reason[k, j])
            if r:
                ax.text(j, k, SHORT_REASONS.get(r, r), ha="center", va="center", fontsize=7)
    _ticks(ax, res)
    used = [o for o in OUTCOMES if (outcome == o).any()]
    ax.legend(handles=[Patch(color=OUTCOME_COLOURS[o], label=o) for o in used], fontsize=7, loc="upper left",
              bbox_to_anchor=(0.0, -0.18), ncol=len(used), frameon=False)
    ax.set_title(f"{res.drive.name}: {res.disturbance}\ncolour: outcome; text: the controller's reason", fontsize=9)

    margin = np.asarray(res.grid("margin_deg"), dtype=float)
    span = float(np.nanmax(np.abs(margin))) if np.isfinite(margin).any() else 1.0
    im = ax2.imshow(np.ma.masked_invalid(margin), cmap="RdBu", vmin=-span, vmax=span, origin="lower", aspect="auto")
    fig.colorbar(im, ax=ax2, label="crossing - end of demagnetisation (deg)")
    for k in range(ny):
        for j in range(nx):
            if np.isfinite(margin[k, j]):
                ax2.text(j, k, f"{margin[k, j]:.1f}", ha="center", va="center", fontsize=7)
    lost = np.asarray(res.grid("truth_lost"), dtype=bool)
    kk, jj = np.nonzero(lost)
    if kk.size:
        ax2.scatter(jj, kk, s=160, facecolors="none", edgecolors="k", linewidths=1.2,
                    label=f"truth: a commutation > {np.degrees(res.bound):.0f} deg off")
        ax2.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.18), frameon=False)
    _ticks(ax2, res)
    ax2.set_title("plant: smallest margin from the end of the demagnetisation\nto the back-EMF zero crossing "
                  "after the step (red: hidden)", fontsize=9)
    return fig


def desync_figures(res: DesyncMapResult) -> dict[str, bytes]:
    """Return the figure files of ``bldclab sensorless``: ``desync.png`` and ``desync.svg`` (undated SVG)."""
    fig: Any = plot_desync_map(res)
    return {"desync.png": figure_bytes(fig, "png", dated=False), "desync.svg": figure_bytes(fig, "svg", dated=False)}

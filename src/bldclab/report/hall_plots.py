"""Plots of the Hall study (:func:`bldclab.analysis.hall.hall_study`).

As in :mod:`bldclab.report.plots`: :class:`matplotlib.figure.Figure` directly, never ``pyplot`` state; the function
returns a new figure.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..analysis.hall import HallStudyResult

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot_hall_study"]

_ROWS = (("tau_rel", "mean torque / at zero error"), ("ripple_sampled_pu", "torque ripple (p.u. of T_N)"),
         ("efficiency", "efficiency"))
_CASE_TITLES = {"one": "one sensor (a) misplaced", "common": "all three: common offset",
                "alternating": "all three: +, -, + pattern"}


def plot_hall_study(res: HallStudyResult) -> Figure:
    """Plot mean torque (relative to zero error), ripple and efficiency against the placement error.

    One column per error pattern, one line per controller variant.
    """
    from matplotlib.figure import Figure  # deferred: matplotlib loads when a figure is drawn, not with the CLI

    cases = list(dict.fromkeys(res.points.case))
    fig = Figure(figsize=(4.4 * len(cases), 9.0), layout="constrained")
    axes = fig.subplots(len(_ROWS), len(cases), squeeze=False, sharex=True)
    for j, case in enumerate(cases):
        for i, (col, label) in enumerate(_ROWS):
            ax = axes[i][j]
            for var, g in res.points[res.points.case == case].groupby("variant", sort=False):
                g = g.sort_values("error_deg")
                ax.plot(g.error_deg, g[col], marker="o", markersize=3, label=str(var))
            ax.grid(True, alpha=0.3)
            if j == 0:
                ax.set_ylabel(label)
            if i == 0:
                ax.set_title(_CASE_TITLES.get(case, case), fontsize=10)
            if i == len(_ROWS) - 1:
                ax.set_xlabel("Hall placement error (deg electrical)")
    axes[0][0].legend(fontsize=8)
    rpm = res.speed * 30.0 / math.pi
    fig.suptitle(f"{res.drive}: Hall placement error at {res.torque:.4g} N m, {rpm:.4g} rpm", fontsize=11)
    return fig

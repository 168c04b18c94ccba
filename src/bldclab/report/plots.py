"""Figures of paper 1's analysis: torque-speed (Fig 7) and ripple-speed (Fig 8) characteristics.

Figures are made with :class:`matplotlib.figure.Figure` directly, never through ``pyplot`` state, so library
code opens no window and works with any backend (saving to PNG or SVG needs none). Each function draws into a
given ``Axes`` or a new figure and returns ``(figure, axes)``.

Simulated or measured points go on top of the analytic curves through ``overlays``: a mapping from a label to
a ``DataFrame`` with an ``Omega_pu`` column and any of the characteristic's columns (``T_s_pu``, ``T_q_pu``
for Fig 7, ``TR_s_pu``, ``TR_q_pu`` for Fig 8); missing columns are skipped.

The figures of a command's results are drawn to files through :func:`render_figures`: each :class:`FigureJob` (a
function that makes the figure, its arguments, the formats) runs in this process or on an executor's worker
processes, which draw a command's figures in parallel.
"""

from __future__ import annotations

import io
import re
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import BldclabError, PlausibilityWarning

if TYPE_CHECKING:
    from concurrent.futures import Executor

    import pandas as pd
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["CLOSED_FORM", "FigureJob", "Physical", "figure_bytes", "load_matplotlib", "plot_efficiency", "plot_ripple",
           "plot_torque_speed", "render_figure", "render_figures"]

#: Marker style per supply, as in paper 1: x for sinusoidal, o for real square-wave.
_STYLE = {
    "s": {"marker": "x", "color": "tab:blue", "label": "sinusoidal supply"},
    "q": {"marker": "o", "color": "tab:red", "label": "real square-wave supply"},
}
_OVERLAY_MARKERS = ("s", "^", "D", "v", "P", "*")
_MAX_MARKS = 30


def _axes(ax: Axes | None) -> tuple[Figure, Axes]:
    """Return the figure and axes to draw into: those of ``ax``, or a new 6.4 x 4.4 in figure."""
    from matplotlib.figure import Figure  # deferred: matplotlib loads when a figure is drawn, not with the CLI

    if ax is not None:
        fig = ax.figure
        if not isinstance(fig, Figure):  # a SubFigure: hand back its root figure
            fig = fig.figure
        if not isinstance(fig, Figure):
            raise BldclabError("ax", "is not attached to a matplotlib Figure")
        return fig, ax
    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    return fig, fig.add_subplot()


def _check(df: pd.DataFrame, columns: tuple[str, ...], what: str) -> None:
    """Raise a :class:`BldclabError` naming the first missing column."""
    for c in ("Omega_pu", *columns):
        if c not in df.columns:
            raise BldclabError(f"{what}: column {c}", "is missing")


@dataclass(frozen=True)
class Physical:
    """How to draw a per-unit characteristic in physical units (rpm, N m), per unit on the opposite axes.

    The closed forms are labelled as paper 1's (:data:`CLOSED_FORM`), or left out where its premises do not hold.

    Parameters
    ----------
    rpm : float
        The speed base ``Omega_0`` in rpm.
    y_base : float or None
        The base of the y quantity (``T_N`` in N m for torque and ripple); None: the y axis is not scaled (efficiency).
    y_unit : str
        Its unit, for the label.
    closed_forms : bool
        Draw paper 1's closed forms (False where the drive leaves their premises: they would be no reference).
    note : str
        Said in the figure when the closed forms are left out.
    """

    rpm: float
    y_base: float | None = None
    y_unit: str = ""
    closed_forms: bool = True
    note: str = ""

    @property
    def sy(self) -> float:
        """Factor on the y values."""
        return 1.0 if self.y_base is None else self.y_base


def _curve(ax: Axes, df: pd.DataFrame, column: str, supply: str, physical: Physical | None = None,
           prefix: str = "") -> None:
    """Draw one analytic curve: a line with the supply's markers at most ``_MAX_MARKS`` times."""
    style = _STYLE[supply]
    sx, sy = (physical.rpm, physical.sy) if physical is not None else (1.0, 1.0)
    x = df["Omega_pu"].to_numpy(dtype=float) * sx
    y = df[column].to_numpy(dtype=float) * sy
    order = np.argsort(x)
    every = max(1, int(np.ceil(x.size / _MAX_MARKS)))
    ax.plot(x[order], y[order], marker=style["marker"], markevery=every, color=style["color"],
            label=prefix + style["label"], linewidth=1.2, markersize=6, fillstyle="none")


def _overlay(ax: Axes, overlays: Mapping[str, pd.DataFrame] | None, columns: dict[str, str],
             physical: Physical | None = None) -> None:
    """Draw the extra point sets: one marker shape per label, the supply's colour per column."""
    if not overlays:
        return
    sx, sy = (physical.rpm, physical.sy) if physical is not None else (1.0, 1.0)
    for j, (label, odf) in enumerate(overlays.items()):
        if "Omega_pu" not in odf.columns:
            raise BldclabError(f"overlay {label!r}: column Omega_pu", "is missing")
        marker = _OVERLAY_MARKERS[j % len(_OVERLAY_MARKERS)]
        for column, supply in columns.items():
            if column in odf.columns:
                ax.plot(odf["Omega_pu"].to_numpy(dtype=float) * sx, odf[column].to_numpy(dtype=float) * sy,
                        linestyle="none", marker=marker, color=_STYLE[supply]["color"], markersize=7,
                        label=f"{label}: {_STYLE[supply]['label']}")


#: The label of paper 1's closed-form curves in a figure that also has simulated points.
CLOSED_FORM = "paper 1 closed form, "


def _finish(ax: Axes, ylabel: str, title: str | None, physical: Physical | None = None) -> None:
    if physical is None:
        ax.set_xlabel(r"speed $\Omega_{pu}$ (per unit of $\Omega_0$)")
        ax.set_ylabel(ylabel)
        ax.set_xlim(0.0, 1.0)
    else:
        rpm = physical.rpm
        ax.set_xlabel("speed (rpm)")
        ax.set_xlim(0.0, rpm)
        top = ax.secondary_xaxis("top", functions=(lambda n: np.divide(n, rpm), lambda w: np.multiply(w, rpm)))
        top.set_xlabel(r"speed (per unit of $\Omega_0$)", fontsize="small")
        if physical.y_base is None:
            ax.set_ylabel(ylabel)
        else:
            base = physical.y_base
            ax.set_ylabel(f"{re.sub(r'[ ]*[$][^$]*[$]', '', ylabel.split(' (')[0])} ({physical.y_unit})")
            right = ax.secondary_yaxis("right", functions=(lambda v: np.divide(v, base),
                                                           lambda u: np.multiply(u, base)))
            right.set_ylabel(ylabel, fontsize="small")
        if not physical.closed_forms and physical.note:
            ax.text(0.01, 0.01, physical.note, transform=ax.transAxes, fontsize="x-small", va="bottom",
                    ha="left", color="0.35", wrap=True)
    ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.4)
    ax.legend(loc="best", fontsize="small")
    if title:
        ax.set_title(title)


def plot_torque_speed(df: pd.DataFrame, ax: Axes | None = None, *,
                      overlays: Mapping[str, pd.DataFrame] | None = None, blac: bool = True,
                      title: str | None = "Torque-speed characteristic (paper 1 Fig. 7)",
                      physical: Physical | None = None) -> tuple[Figure, Axes]:
    """Plot the per-unit torque against speed for both supplies, paper 1 Fig. 7.

    Parameters
    ----------
    df : pandas.DataFrame
        Output of :func:`bldclab.model.analytic.characteristic`: columns ``Omega_pu``, ``T_s_pu``, ``T_q_pu`` and,
        with ``blac``, ``T_blac_pu``.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new figure if omitted.
    overlays : mapping of str to pandas.DataFrame, optional
        Extra points (e.g. simulations) by label, with ``Omega_pu`` and ``T_s_pu`` and/or ``T_q_pu``.
    blac : bool
        Also draw the equivalent PM BLAC motor (paper 1 section IV.B).
    title : str or None
        Axes title.
    physical : Physical, optional
        Draw in rpm and N m (per unit on the opposite axes), the closed forms labelled as paper 1's or left out
        (``bldclab compare``'s figure); default per unit, as paper 1's Fig. 7.

    Returns
    -------
    tuple of (matplotlib.figure.Figure, matplotlib.axes.Axes)

    Raises
    ------
    BldclabError
        If a needed column is missing.

    """
    _check(df, ("T_s_pu", "T_q_pu", *(("T_blac_pu",) if blac else ())), "characteristic")
    fig, ax = _axes(ax)
    closed = physical is None or physical.closed_forms
    prefix = CLOSED_FORM if physical is not None else ""
    if closed:
        _curve(ax, df, "T_s_pu", "s", physical, prefix)
        _curve(ax, df, "T_q_pu", "q", physical, prefix)
    if blac and closed:
        sx, sy = (physical.rpm, physical.sy) if physical is not None else (1.0, 1.0)
        order = np.argsort(df["Omega_pu"].to_numpy(dtype=float))
        ax.plot(df["Omega_pu"].to_numpy(dtype=float)[order] * sx, df["T_blac_pu"].to_numpy(dtype=float)[order] * sy,
                color="tab:gray", linestyle="--", linewidth=1.2, label=prefix + "equivalent PM BLAC motor")
    _overlay(ax, overlays, {"T_s_pu": "s", "T_q_pu": "q"}, physical)
    _finish(ax, r"torque $T_{pu}$ (per unit of $T_N$)", title, physical)
    return fig, ax


def plot_ripple(df: pd.DataFrame, ax: Axes | None = None, *,
                overlays: Mapping[str, pd.DataFrame] | None = None,
                title: str | None = "Torque ripple (paper 1 Fig. 8)",
                physical: Physical | None = None) -> tuple[Figure, Axes]:
    """Plot the per-unit peak-to-peak torque ripple against speed for both supplies, paper 1 Fig. 8.

    Parameters
    ----------
    df : pandas.DataFrame
        Output of :func:`bldclab.model.analytic.characteristic`: columns ``Omega_pu``, ``TR_s_pu``, ``TR_q_pu``.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new figure if omitted.
    overlays : mapping of str to pandas.DataFrame, optional
        Extra points (e.g. simulations) by label, with ``Omega_pu`` and ``TR_s_pu`` and/or ``TR_q_pu``.
    title : str or None
        Axes title.
    physical : Physical, optional
        Draw in rpm and N m, as :func:`plot_torque_speed`.

    Returns
    -------
    tuple of (matplotlib.figure.Figure, matplotlib.axes.Axes)

    Raises
    ------
    BldclabError
        If a needed column is missing.

    """
    _check(df, ("TR_s_pu", "TR_q_pu"), "characteristic")
    fig, ax = _axes(ax)
    if physical is None or physical.closed_forms:
        prefix = CLOSED_FORM if physical is not None else ""
        _curve(ax, df, "TR_s_pu", "s", physical, prefix)
        _curve(ax, df, "TR_q_pu", "q", physical, prefix)
    _overlay(ax, overlays, {"TR_s_pu": "s", "TR_q_pu": "q"}, physical)
    _finish(ax, r"torque ripple $TR_{pu}$ (per unit of $T_N$)", title, physical)
    return fig, ax


def plot_efficiency(df: pd.DataFrame, simulated: Mapping[str, pd.DataFrame] | None = None, ax: Axes | None = None, *,
                    title: str | None = "Efficiency", physical: Physical | None = None) -> tuple[Figure, Axes]:
    """Plot efficiency against speed: paper 1's (38)/(39) and simulated points (shaft power over DC power).

    Parameters
    ----------
    df : pandas.DataFrame
        Output of :func:`bldclab.model.analytic.characteristic`: columns ``Omega_pu``, ``eta_s``, ``eta_q``.
    simulated : mapping of str to pandas.DataFrame, optional
        Simulated points by supply label (``"sinusoidal"``, ``"square-wave"``), with ``Omega_pu`` and ``eta``.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; a new figure if omitted.
    title : str or None
        Axes title.
    physical : Physical, optional
        Speed in rpm (per unit on top), the closed forms labelled as paper 1's or left out, as
        :func:`plot_torque_speed`.

    Returns
    -------
    tuple of (matplotlib.figure.Figure, matplotlib.axes.Axes)
    """
    _check(df, ("eta_s", "eta_q"), "characteristic")
    fig, ax = _axes(ax)
    if physical is None or physical.closed_forms:
        prefix = CLOSED_FORM if physical is not None else ""
        _curve(ax, df, "eta_s", "s", physical, prefix)
        _curve(ax, df, "eta_q", "q", physical, prefix)
    sx = physical.rpm if physical is not None else 1.0
    for j, (label, d) in enumerate((simulated or {}).items()):
        if "eta" not in d.columns:
            raise BldclabError(f"simulated {label}: column eta", "is missing")
        supply = "s" if label.startswith("sin") else "q"
        ax.plot(d["Omega_pu"].to_numpy(dtype=float) * sx, d["eta"].to_numpy(dtype=float), linestyle="none",
                marker=_OVERLAY_MARKERS[j % len(_OVERLAY_MARKERS)], markerfacecolor="none",
                color=_STYLE[supply]["color"], label=f"simulated, {label}")
    _finish(ax, "efficiency (shaft / DC power)", title, physical)
    ax.set_ylim(bottom=0.0, top=1.0)
    return fig, ax


def figure_bytes(fig: Figure, fmt: str, *, dpi: int = 120, dated: bool = True) -> bytes:
    """Render a matplotlib figure to PNG or SVG bytes.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    fmt : str
        ``"png"`` or ``"svg"``.
    dpi : int
        Resolution of the PNG (dots per inch).
    dated : bool
        Keep matplotlib's creation date in an SVG; ``False`` leaves it out, so reruns give equal files.

    Returns
    -------
    bytes
    """
    buf = io.BytesIO()
    meta = {} if dated or fmt != "svg" else {"Date": None}
    fig.savefig(buf, format=fmt, dpi=dpi, metadata=meta)
    return buf.getvalue()


def load_matplotlib() -> None:
    """Import matplotlib's figures and its PNG and SVG backends now, not at the first figure.

    A command that draws its figures on a process pool calls this before the pool starts: the workers, forked from
    this process (the default on Linux), then draw without importing matplotlib each (0.3 s a process).
    """
    # deferred (as in _axes): only the commands that draw load matplotlib
    import matplotlib.backends.backend_agg  # PNG
    import matplotlib.backends.backend_svg  # SVG
    import matplotlib.figure  # noqa: F401


@dataclass(frozen=True)
class FigureJob:
    """A figure to draw to files: what makes it and how it is saved. Picklable, to run on a worker process.

    Parameters
    ----------
    make : callable
        A module-level function: ``make(*args)`` returns a :class:`~matplotlib.figure.Figure`, or ``(figure, data)``
        when it also computes data the caller keeps (paper 1's Fig 12 and its measurements).
    args : tuple
        Its arguments (picklable: a result, a drive).
    formats : tuple of str
        ``"png"``, ``"svg"``: saved in this order.
    dpi : int
        Resolution of the PNG (dots per inch).
    dated : bool
        Keep matplotlib's creation date in an SVG (:func:`figure_bytes`).
    """

    make: Callable[..., Any]
    args: tuple[Any, ...] = ()
    formats: tuple[str, ...] = ("png", "svg")
    dpi: int = 120
    dated: bool = True


def render_figure(job: FigureJob) -> tuple[dict[str, bytes], Any, list[str]]:
    """Make a figure and save it in each format of the job.

    The layout (matplotlib's constrained layout: text extents, colour bars) is computed once, for the first format,
    and kept for the others instead of being computed again. The plausibility warnings of the simulations the
    figure runs (paper 1's Figs 9, 11, 12) are recorded and returned, not shown: on a worker process they would go
    to its stderr one by one, past the command's one summary line.

    Parameters
    ----------
    job : FigureJob

    Returns
    -------
    dict of str to bytes
        The file content per format.
    object
        The data the job's function returned beside the figure, else None.
    list of str
        The messages of the :class:`~bldclab.errors.PlausibilityWarning` raised while making it.
    """
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always", PlausibilityWarning)
        made = job.make(*job.args)
    caught = [str(w.message) for w in rec if issubclass(w.category, PlausibilityWarning)]
    for w in rec:
        if not issubclass(w.category, PlausibilityWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    fig, data = made if isinstance(made, tuple) else (made, None)
    out: dict[str, bytes] = {}
    for fmt in job.formats:
        out[fmt] = figure_bytes(fig, fmt, dpi=job.dpi, dated=job.dated)
        if fig.get_layout_engine() is not None:
            fig.set_layout_engine("none")  # the axes keep the positions the first format's drawing gave them
    return out, data, caught


def render_figures(jobs: Mapping[str, FigureJob], executor: Executor | None = None
                   ) -> dict[str, tuple[dict[str, bytes], Any, list[str]]]:
    """Draw several figures to files, in this process or on an executor (its workers draw them in parallel).

    Parameters
    ----------
    jobs : mapping of str to FigureJob
        By name; put the costliest first (they start first on an executor).
    executor : concurrent.futures.Executor, optional
        Where the figures are drawn, e.g. the process pool that ran the simulations; in this process if omitted.

    Returns
    -------
    dict
        Name -> :func:`render_figure`'s ``(files by format, data, warnings)``, in the order of ``jobs``.
    """
    if executor is None:
        return {name: render_figure(job) for name, job in jobs.items()}
    futures = {name: executor.submit(render_figure, job) for name, job in jobs.items()}
    return {name: f.result() for name, f in futures.items()}

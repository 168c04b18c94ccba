"""The report users read: one self-contained HTML page of a square-wave vs sinusoidal comparison.

``bldclab report RESULTS_DIR|MOTOR [--out report.html]`` writes one HTML file that opens offline: its style, its
script and every number it plots are inside the file, the fonts are the system's, nothing is fetched. It shows the
drive's data with units, paper 1's Table I with equation numbers and the R-aware base speeds, torque, ripple and
efficiency against speed (closed forms and simulation overlaid, both supplies), current and torque waveforms over
an electrical period at chosen speeds, paper 2's method comparison and the fault table when they are there, and
how every number was produced (command line, version, date, drive, controllers, scenario, verdict).

Where the numbers come from:

- ``bldclab compare`` writes, beside its CSV files and figures, ``waveforms.csv``
  (:func:`~bldclab.report.bundle.waveforms`),
  ``manifest.json`` (what was run and which files are there: :func:`~bldclab.report.bundle.make_manifest`) and, unless
  ``--no-report``,
  ``report.html`` (:func:`~bldclab.report.bundle.compare_outputs`).
- Given a results directory, the report reads those files (:func:`~bldclab.report.bundle.read_results`), plus
  ``methods.csv`` and
  ``methods_compared.svg`` of ``bldclab torque-control`` and ``faults.csv`` of ``bldclab faults`` if they were
  written into the same directory.
- Given a motor (catalog name or TOML file), it runs the comparison itself
  (:func:`~bldclab.report.bundle.motor_results`) and builds the
  same files in memory, so both ways give the same page.

The plots are drawn in the browser by a small dependency-free script shipped in ``bldclab/report_assets``
(axes, ticks, lines and markers, legend toggles, hover values, zoom and pan). Without JavaScript every plot shows
a static SVG drawn by :func:`~bldclab.svg.svg_plot`, which also serves the notebook displays of
:class:`~bldclab.sim.results.SimResult` and :class:`~bldclab.sweep.SweepRun`. Contents: ``docs/report.md``.
"""

from __future__ import annotations

import dataclasses
import datetime
import html
import io
import json
import math
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from typing import Any

import numpy as np
import pandas as pd

from .._version import __version__
from ..analysis.compare import COMPARISON, EFFICIENCY_COUNTS
from ..analysis.effmap import COMPARISON as EFFMAP_COMPARISON
from ..analysis.effmap import EffMapResult
from ..analysis.losses import loss_buckets
from ..errors import BldclabError
from ..model import analytic
from ..model.motor import Drive
from ..svg import Series, _e, svg_plot

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "MANIFEST",
    "PARAMETERS",
    "REPORT",
    "WAVEFORM_SPEEDS",
    "Results",
    "render",
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
          "methods.csv", "methods_traces.csv", "methods_compared.svg", "faults.csv", "effmap.csv",
          "effmap_difference.csv", "effmap_difference.svg", "efficiency.csv", "hall.csv", "hall.svg", "desync.csv",
          "desync.json", "desync.svg", "thermal_envelope.csv")

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
        ("P_fe_eddy", "iron loss, eddy-current part at speed_fe_ref (0: no iron loss)", "W"),
        ("P_fe_hyst", "iron loss, hysteresis part at speed_fe_ref", "W"),
        ("P_fe_ex", "iron loss, excess part at speed_fe_ref", "W"),
        ("speed_fe_ref", "speed of the iron-loss data", "rad/s"),
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
        ("E_on", "switch turn-on energy at V_test, I_test (0: no switching losses)", "J"),
        ("E_off", "switch turn-off energy at V_test, I_test", "J"),
        ("E_rr", "diode reverse-recovery energy at V_test, I_test", "J"),
        ("V_test", "test voltage of the switching energies", "V"),
        ("I_test", "test current of the switching energies", "A"),
    ),
    "mechanics": (
        ("J", "inertia of rotor and load", "kg m^2"),
        ("B", "viscous friction", "N m s/rad"),
        ("tau_c", "Coulomb friction", "N m"),
        ("k_q", "propeller or fan load k_q w^2", "N m s^2/rad^2"),
    ),
    "sensors": (
        ("current_phases", "measured phase currents", "-"),
        ("current_gain", "current sensor gains a, b, c", "-"),
        ("current_offset", "current sensor offsets a, b, c", "A"),
        ("current_noise", "current noise (standard deviation)", "A"),
        ("current_lsb", "current quantisation step", "A"),
        ("current_full_scale", "current measurement full scale", "A"),
        ("vdc_gain", "DC bus sensor gain", "-"),
        ("vdc_offset", "DC bus sensor offset", "V"),
        ("vdc_noise", "DC bus noise (standard deviation)", "V"),
        ("vdc_lsb", "DC bus quantisation step", "V"),
        ("hall_error", "Hall sensor angle errors a, b, c (electrical)", "rad"),
        ("hall_hysteresis", "Hall sensor hysteresis a, b, c (electrical)", "rad"),
        ("hall_delay", "Hall edge propagation delays a, b, c", "s"),
        ("hall_tau", "Hall line RC filter time constants a, b, c", "s"),
        ("f_tick", "capture-timer frequency (Hall edge time stamps)", "Hz"),
        ("seed", "noise generator seed", "-"),
        ("bemf", "back-EMF sensing fitted (also without a sensorless controller)", "-"),
        ("bemf_tau", "back-EMF sensing: RC filter time constant", "s"),
        ("bemf_reference", "back-EMF comparators' reference (star point or half bus)", "-"),
        ("bemf_offset", "back-EMF comparator offset (at the terminal)", "V"),
        ("bemf_hysteresis", "back-EMF comparator hysteresis (at the terminal)", "V"),
        ("bemf_delay", "back-EMF comparator propagation delay", "s"),
        ("bemf_adc_at", "back-EMF ADC sampling instant after the carrier peak", "s"),
        ("bemf_adc_lsb", "back-EMF ADC step (at the terminal)", "V"),
        ("bemf_adc_max", "back-EMF ADC full scale (at the terminal)", "V"),
        ("bemf_adc_noise", "back-EMF ADC noise (standard deviation)", "V"),
    ),
}

_RPM = 60.0 / (2.0 * math.pi)
_PREFIX = ((1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "\u00b5"), (1e-9, "n"))


# ------------------------------------------------------------------------------------------------------------
# formatting


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


# ------------------------------------------------------------------------------------------------------------
# producing the data


# ------------------------------------------------------------------------------------------------------------
# reading the results


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
        The manifest (:func:`~bldclab.report.bundle.make_manifest`).
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
    effmap, effmap_difference : pandas.DataFrame or None
        ``effmap.csv`` and ``effmap_difference.csv`` of ``bldclab effmap`` written into the same directory.
    effmap_svg : str or None
        ``effmap_difference.svg`` of ``bldclab effmap``, made inline-safe.
    efficiency : pandas.DataFrame or None
        ``efficiency.csv``: the efficiency by loss count (:func:`bldclab.analysis.compare.efficiency_table`);
        None in results written before it existed.
    hall : pandas.DataFrame or None
        ``hall.csv`` of ``bldclab hall`` written into the same directory.
    hall_svg : str or None
        ``hall.svg`` of ``bldclab hall``, made inline-safe.
    desync : pandas.DataFrame or None
        ``desync.csv`` of ``bldclab sensorless`` written into the same directory (the desync map's points).
    desync_summary : dict or None
        ``desync.json`` of ``bldclab sensorless``: the disturbance, the axes, the table and the summary lines.
    desync_svg : str or None
        ``desync.svg`` of ``bldclab sensorless``, made inline-safe.
    thermal_envelope : pandas.DataFrame or None
        ``thermal_envelope.csv`` of ``bldclab thermal MOTOR --envelope --out`` written into the same directory.
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
    effmap: pd.DataFrame | None = None
    effmap_difference: pd.DataFrame | None = None
    effmap_svg: str | None = None
    efficiency: pd.DataFrame | None = None
    hall: pd.DataFrame | None = None
    hall_svg: str | None = None
    desync: pd.DataFrame | None = None
    desync_summary: dict[str, Any] | None = None
    desync_svg: str | None = None
    thermal_envelope: pd.DataFrame | None = None
    files: list[str] = dataclasses.field(default_factory=list)
    source: str = ""

    @classmethod
    def from_files(cls, files: Mapping[str, bytes], source: str) -> Results:
        """Parse and check the files of a results directory.

        Parameters
        ----------
        files : mapping of str to bytes
            File name to content (:func:`~bldclab.report.bundle.read_results`).
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
        emap = _csv(files, "effmap.csv", ("supply", "torque_ref", "speed", "efficiency", "feasible"), source,
                    required=False)
        ediff = _csv(files, "effmap_difference.csv", ("torque_ref", "speed", "d_eta", "winner"), source,
                     required=False)
        esvg = None
        if files.get("effmap_difference.svg"):
            esvg = _clean_svg(files["effmap_difference.svg"].decode("utf-8", "replace"))
        eff = _csv(files, "efficiency.csv", ("supply", "Omega_pu", *EFFICIENCY_COUNTS), source, required=False)
        if eff is not None:
            _numeric(eff, "efficiency.csv", ("Omega_pu", *EFFICIENCY_COUNTS), source)
        hall = _csv(files, "hall.csv", ("variant", "case", "error_deg", "tau_rel", "ripple_sampled_pu", "efficiency"),
                    source, required=False)
        if hall is not None:
            _numeric(hall, "hall.csv", ("error_deg", "tau_rel", "ripple_sampled_pu", "efficiency"), source)
        hsvg = None
        if hall is not None and files.get("hall.svg"):
            hsvg = _clean_svg(files["hall.svg"].decode("utf-8", "replace"))
        dsync = _csv(files, "desync.csv", ("outcome", "reason", "truth_lost"), source, required=False)
        dsum: dict[str, Any] | None = None
        dsvg = None
        if dsync is not None:
            dsync["reason"] = dsync["reason"].fillna("")
            if files.get("desync.json"):
                try:
                    dsum = json.loads(files["desync.json"].decode("utf-8"))
                    if not isinstance(dsum, dict) or not all(isinstance(dsum.get(k), list) for k in ("summary",
                                                                                                      "table")):
                        raise ValueError("no summary and table lists")
                except (UnicodeDecodeError, ValueError) as exc:
                    raise BldclabError("desync.json", f"is not a desync map summary of bldclab ({exc})",
                                       source) from None
            if files.get("desync.svg"):
                dsvg = _clean_svg(files["desync.svg"].decode("utf-8", "replace"))
        tenv = _csv(files, "thermal_envelope.csv", ("speed",), source, required=False)
        if tenv is not None:
            _numeric(tenv, "thermal_envelope.csv", ("speed",), source)
        return cls(manifest=manifest, drive=drive, simulated=sim, analytic=an, table1=quantities, verdict=verdict,
                   waveforms=wf, dynamometer=dyno, methods=methods, methods_traces=traces, methods_svg=svg,
                   faults=faults, effmap=emap, effmap_difference=ediff if emap is not None else None,
                   effmap_svg=esvg if emap is not None else None, efficiency=eff, hall=hall, hall_svg=hsvg,
                   desync=dsync, desync_summary=dsum, desync_svg=dsvg, thermal_envelope=tenv,
                   files=sorted(files), source=source)


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
    """Why paper 1's closed forms do not describe the report's drive (:func:`bldclab.model.analytic.applicability`)."""
    return analytic.applicability(r.drive)


def _section_table1(r: Results) -> str:
    rows = [[q["key"], q["description"], q["value"], q["unit"], q["source"]] for q in r.table1]
    reasons = _not_applicable(r)
    note = ""
    if reasons:
        note = ('<p class="warning"><b>Not applicable to this drive:</b> the closed forms below are outside paper 1\'s '
                "premises here (labelled <i>not applicable</i> in the figures, and hidden there at first where the "
                "back-EMF is not the trapezoid they assume; click the legend to show them):</p><ul>"
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
    off = not analytic.shape_applies(d)  # not the trapezoid they assume: hidden at first (the legend shows them)

    def an(name: str, col: str, color: str, dash: str | None = None) -> dict[str, Any]:
        return {"name": name + na, "table": "closed_forms", "x": "Omega_pu", "y": col, "color": color, "dash": dash,
                "hidden": off}

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


def _section_efficiency(r: Results) -> str:
    if r.efficiency is None:
        return ""
    eff = r.efficiency
    si = eff[eff.supply == "sine"].set_index("Omega_pu")
    sq = eff[eff.supply == "square"].set_index("Omega_pu")
    cols = list(EFFICIENCY_COUNTS)
    rows = [[w, *[si[c].get(w) for c in cols], *[sq[c].get(w) for c in cols]] for w in sorted(set(eff["Omega_pu"]))]
    short = ("3 P_R (36)", "2 R I_N\u00b2", "sim., copper", "sim., all losses")
    head = ["\u03a9 [p.u.]", *[f"sine {h}" for h in short], *[f"square {h}" for h in short]]
    lines = [v for v in r.verdict if v.startswith("efficiency")]
    return ('<section id="efficiency"><h2>3b. Efficiency by loss count (paper 1 IV.C extended)</h2>'
            "<p>Paper 1's copper-only efficiency (38)/(39) with the copper loss as "
            "printed in (36), <code>3 P_R,pu</code>; the same closed forms with the consistent count <code>2 R "
            "I_N\u00b2</code> (two phases conduct <code>I_N</code>, on the base <code>T_N \u03a9_0</code>); the "
            "simulation counting the copper loss of its actual currents only (<code>P_m / (P_m + p_cu)</code>); and "
            "the simulation with every loss it books (" + ", ".join(f"<code>{_e(b)}</code>" for b in loss_buckets())
            + "). Closed forms: n/a above the base speeds (21), (30). All columns and the loss buckets in W are in "
            "efficiency.csv.</p>" + _verdict_list(lines) + '<div class="scroll">'
            + _html_table(head, rows, [True] * len(head)) + "</div></section>")


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


def _section_effmap(r: Results) -> str:
    if r.effmap is None:
        return ""
    pts = r.effmap
    diff = r.effmap_difference if r.effmap_difference is not None else pd.DataFrame(
        columns=["torque_ref", "speed", "d_eta", "winner"])
    buckets = tuple(c for c in pts.columns if c.startswith("p_") and c not in ("p_in", "p_shaft", "p_loss",
                                                                                 "p_stored"))
    res = EffMapResult(drive=r.drive, points=pts, difference=diff, torques=np.unique(pts.torque_ref),
                       speeds=np.unique(pts.speed), buckets=buckets)
    out = ['<section id="effmap"><h2>7. Efficiency maps over torque and speed</h2>'
           "<p>From the files <code>bldclab effmap ... --out</code> wrote into this directory (effmap.csv, "
           "effmap_difference.csv and its figures): both supplies on a torque x speed grid of imposed-speed steady "
           "states; points the drive cannot reach are marked infeasible and left out of the comparison. "
           f"{_e(EFFMAP_COMPARISON)}</p>",
           _verdict_list(res.summary())]
    if r.effmap_svg is not None:
        out.append(f'<figure class="static">{r.effmap_svg}<figcaption><b>Sinusoidal minus square-wave '
                   "efficiency</b> on the points both supplies reach (effmap_difference.svg, a static figure); the "
                   "black line is where they trade places.</figcaption></figure>")
    out.append("</section>")
    return "".join(out)


def _section_hall(r: Results) -> str:
    if r.hall is None:
        return ""
    h = r.hall
    errs = sorted(set(float(e) for e in h.error_deg))
    rows: list[list[Any]] = []
    for (var, case), g in h.groupby(["variant", "case"], sort=False):
        by = {float(e): row for e, row in zip(g.error_deg, g.to_dict("records"), strict=True)}
        for label, col in (("mean torque / at 0", "tau_rel"), ("ripple (p.u. of T_N)", "ripple_sampled_pu"),
                           ("efficiency", "efficiency")):
            rows.append([var, case, label, *(by[e][col] if e in by else math.nan for e in errs)])
    cols = ["controller", "error pattern", "quantity", *(f"{e:g} deg" for e in errs)]
    table = _html_table(cols, rows, [False, False, False, *([True] * len(errs))])
    out = ['<section id="hall"><h2>8. Hall sensor placement error</h2>'
           "<p>From the files <code>bldclab hall ... --out</code> wrote into this directory (hall.csv, hall.svg): "
           "each controller at one operating point with the Hall sensors misplaced by the given electrical angle: "
           "<i>one</i> sensor (a), all three by a <i>common</i> offset, or all three <i>alternating</i> "
           "(+, -, +). Mean torque relative to the same controller's at zero error; ripple max - min of the torque "
           "at the controller samples.</p>", f'<div class="scroll">{table}</div>']
    if r.hall_svg is not None:
        out.append(f'<figure class="static">{r.hall_svg}<figcaption><b>Torque, ripple and efficiency against the '
                   "Hall placement error</b> (hall.svg, a static figure).</figcaption></figure>")
    out.append("</section>")
    return "".join(out)


def _section_desync(r: Results) -> str:
    if r.desync is None:
        return ""
    sm = r.desync_summary or {}
    what = f" ({_e(str(sm['motor']))}: {_e(str(sm.get('disturbance', '')))})" if "motor" in sm else ""
    out = ['<section id="desync"><h2>9. Sensorless drive: the desync map</h2>'
           "<p>From the files <code>bldclab sensorless ... --out</code> wrote into this directory (desync.csv, "
           f"desync.json, desync.svg){what}: the sensorless six-step drive (SixStepSensorless) on the switching plant "
           "with its propeller load, one throttle step (or start-up) per point. <i>sync</i>: held; <i>rec</i>: the "
           "controller flagged a desync, restarted and is in sync at the end; <i>LOST</i>: not back; <i>UNDET</i>: "
           "the plant's true rotor angle put a commutation out of sync and the controller flagged nothing; "
           "<i>nostart</i>: not in closed loop at the step. After the colon the controller's reason (hidden: the "
           "demagnetisation hid the crossing; timeout, jump, stall, startfail, trip).</p>"]
    if sm.get("table"):
        out.append("<pre>" + _e("\n".join(str(x) for x in sm["table"])) + "</pre>")
    out.append(_verdict_list([str(x) for x in sm.get("summary", [])]))
    cols = [c for c in ("outcome", "reason", "truth_lost", "t_desync_ms", "angle_max_deg", "demag_deg", "window_deg",
                        "speed_step_rpm", "speed_end_rpm", "i_peak") if c in r.desync.columns]
    axes = [str(a["name"]) for a in (sm.get("x"), sm.get("y")) if isinstance(a, dict) and a.get("name") in
            r.desync.columns]
    out.append('<details><summary>Every point</summary><div class="scroll">'
               + _frame_table(r.desync, [*axes, *cols]) + "</div></details>")
    if r.desync_svg is not None:
        out.append(f'<figure class="static">{r.desync_svg}<figcaption><b>The desync map</b> (desync.svg, a static '
                   "figure): the outcome and reason of each point, and the margin between the expected crossing and "
                   "the end of the demagnetisation after the step.</figcaption></figure>")
    out.append("</section>")
    return "".join(out)


def _section_heat(r: Results) -> str:
    th = r.drive.thermal
    if th is None:
        return ""
    net = th.network()
    taus = net.time_constants
    nodes = [[n.name, "boundary" if n.boundary else "capacity", n.C if n.C is not None else "",
              n.T if n.T is not None else "", n.T_max if n.T_max is not None else "",
              ", ".join(k for k, v in (("winding", n.name in th.winding), ("magnets", n.name == th.magnets),
                                        ("switches", n.name in th.switches)) if v)] for n in th.nodes]
    links = [[x.a, x.b, x.R] for x in th.links]
    routes = [[b, ", ".join(f"{n} {f:g}" for n, f in route)] for b, route in th.losses]
    P1, _ = net.heat({b: 1.0 for b, _ in th.losses})
    rise = net.temps(net.steady(P1))
    out = ['<section id="heat"><h2>10. Heat: the thermal network</h2>'
           "<p>The motor file's <code>[thermal]</code> table (docs/thermal.md): a lumped network whose nodes the "
           "plant's losses heat; the winding's <code>R</code>, the magnets' flux and the switches' "
           f"<code>R_on</code> follow its temperatures, linear about T_ref = {th.T_ref:g} degC (alpha_R "
           f"{100 * th.alpha_R_value:.3g} %/K, alpha_k {100 * th.alpha_k:.3g} %/K, alpha_Ron "
           f"{100 * th.alpha_Ron:.3g} %/K). Time constants of the network: "
           + ", ".join(_num(t) for t in taus[:4]) + " s (the longest sets how long a load takes to reach its "
           "steady temperature). The results above are at T_ref.</p>",
           _html_table(["node", "kind", "C (J/K)", "T (degC)", "T_max (degC)", "sets"], nodes,
                       [False, False, True, True, True, False]),
           _html_table(["between", "and", "R (K/W)"], links, [False, False, True]),
           _html_table(["loss", "heats (fraction)"], routes, [False, False]),
           "<p>Steady temperatures with every routed loss source at 1 W (a sensitivity, degC): "
           + ", ".join(f"{_e(k)} {v:.4g}" for k, v in rise.items()) + ".</p>"]
    if r.thermal_envelope is not None:
        env = r.thermal_envelope.copy()
        env.insert(1, "speed_rpm", env["speed"] * 30.0 / math.pi)
        out.append("<p>From the file <code>bldclab thermal MOTOR --envelope --out thermal_envelope.csv</code> wrote "
                   "into this directory: per speed, the torque (N m) each supply delivers continuously (the steady "
                   "state) and for the given times from the ambient with every node below its T_max, and what "
                   "limits it (a node; <i>delivery</i>: the bus voltage or the controller's current limit).</p>"
                   f'<div class="scroll">{_frame_table(env)}</div>')
    else:
        out.append("<p>The torque-speed envelopes (continuous and time-limited) are not in this directory: "
                   "<code>bldclab thermal MOTOR --envelope --out DIR/thermal_envelope.csv</code> writes them, and "
                   "the next report shows them here.</p>")
    out.append("</section>")
    return "".join(out)


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
        ("closed forms", "paper 1's equations (bldclab.model.analytic), R neglected, evaluated at 201 speeds and the "
                         "region boundaries for the curves, at the simulated speeds in analytic.csv"),
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
    body = [_section_motor(r, page), _section_table1(r), _section_characteristics(r, page), _section_efficiency(r),
            _section_waveforms(r, page), _section_paper2(r, page), _section_faults(r), _section_effmap(r),
            _section_hall(r), _section_desync(r), _section_heat(r), _section_provenance(r, report_command, created)]
    toc = [("verdict", "Verdict"), ("motor", "Motor"), ("table1", "Table I"), ("characteristics", "Characteristics"),
           *([("efficiency", "Efficiency counts")] if r.efficiency is not None else []), ("waveforms", "Waveforms")]
    if r.methods is not None or r.methods_traces is not None or r.methods_svg is not None:
        toc.append(("paper2", "Paper 2"))
    if r.faults is not None:
        toc.append(("faults", "Faults"))
    if r.effmap is not None:
        toc.append(("effmap", "Efficiency maps"))
    if r.hall is not None:
        toc.append(("hall", "Hall errors"))
    if r.desync is not None:
        toc.append(("desync", "Desync map"))
    toc.append(("provenance", "How it was produced"))
    nav = "".join(f'<a href="#{k}">{_e(v)}</a>' for k, v in toc)
    n = len(set(r.simulated["Omega_pu"]))
    head = (f'<header class="top"><div class="wrap"><h1>bldclab report: {_e(name)}</h1>'
            "<p>Square-wave vs sinusoidal supply (paper 1): switching-level simulation beside the closed forms, "
            f"{n} speeds per supply.</p><p>Results of <code>{_e(r.manifest['command'])}</code>, "
            f"{_e(r.manifest['created'])}; bldclab {_e(r.manifest['bldclab_version'])}.</p></div></header>")
    tops = [v for v in r.verdict if v.startswith("bottom line")]
    bottom = f'<p class="bottom-line"><b>{_e(tops[0])}</b></p>' if tops else ""
    verdict = (f'<section id="verdict"><h2>Verdict</h2><div class="verdict">{bottom}<p>{_e(COMPARISON)}</p>'
               f"{_verdict_list([v for v in r.verdict if not v.startswith('bottom line')])}"
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


def _now() -> str:
    return datetime.datetime.now(datetime.UTC).replace(microsecond=0).isoformat().replace("+00:00", "Z")

"""The HTML report (bldclab report, written by bldclab compare): structure, content, provenance, errors; the
notebook displays of SimResult and SweepRun."""

from __future__ import annotations

import dataclasses
import json
import math
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import bldclab as bl
from bldclab import __version__, sweep
from bldclab.cli import main
from bldclab.model.motor import Inverter, Mechanics, Motor, Sensors
from bldclab.report import html as report


class Page(HTMLParser):
    """The parts of a report the tests look at: attributes of every element, table rows by section, data, text."""

    def __init__(self, text: str) -> None:
        super().__init__(convert_charrefs=True)
        self.elements: list[tuple[str, dict[str, str]]] = []
        self.rows: dict[str, list[list[str]]] = {}
        self.figures: list[dict[str, str]] = []
        self.scripts: list[tuple[dict[str, str], str]] = []
        self.text: list[str] = []
        self._section = ""
        self._row: list[str] | None = None
        self._cell: list[str] | None = None
        self._script: tuple[dict[str, str], list[str]] | None = None
        # (Python's parser reads the content of <noscript> as markup: take the static plots from the source)
        self.noscript = dict(re.findall(r'<figure class="plot" id="fig-[^"]*" data-plot="([^"]+)"><noscript>(.*?)'
                                        r"</noscript>", text, flags=re.S))
        self.feed(text)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        self.elements.append((tag, a))
        if tag == "section":
            self._section = a.get("id", "")
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = []
        elif tag == "script":
            self._script = (a, [])
        elif tag == "figure" and "plot" in a.get("class", "").split():
            self.figures.append(a)

    def handle_endtag(self, tag: str) -> None:
        if tag in ("td", "th") and self._cell is not None and self._row is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.rows.setdefault(self._section, []).append(self._row)
            self._row = None
        elif tag == "script" and self._script is not None:
            self.scripts.append((self._script[0], "".join(self._script[1])))
            self._script = None

    def handle_data(self, data: str) -> None:
        if self._script is not None:
            self._script[1].append(data)
            return
        if self._cell is not None:
            self._cell.append(data)
        self.text.append(data)

    @property
    def data(self) -> dict:
        (body,) = [t for a, t in self.scripts if a.get("id") == "bldclab-data"]
        return json.loads(body)

    @property
    def all_text(self) -> str:
        return " ".join(" ".join(self.text).split())


def _embedded_equals(column: list, values: pd.Series) -> bool:
    """An embedded column (NaN as null) holds exactly the CSV's values."""
    if len(column) != len(values):
        return False
    for a, b in zip(column, values.tolist(), strict=True):
        if isinstance(b, float) and math.isnan(b):
            if a is not None:
                return False
        elif a != b:
            return False
    return True


@pytest.fixture(scope="module")
def results_dir(compare_htm48v: Path) -> Path:
    """The session's bldclab compare run on htm-48v (tests/conftest.py): read only; tests that add files copy it."""
    return compare_htm48v


@pytest.fixture(scope="module")
def page(results_dir: Path) -> Page:
    return Page((results_dir / "report.html").read_text(encoding="utf-8"))


def test_compare_writes_manifest_waveforms_and_report(results_dir: Path) -> None:
    manifest = json.loads((results_dir / "manifest.json").read_text())
    assert manifest["format"] == report.FORMAT and manifest["format_version"] == report.FORMAT_VERSION
    assert manifest["command"].startswith("bldclab compare htm-48v --out ")
    assert manifest["bldclab_version"] == __version__
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", manifest["created"])
    # the manifest lists exactly the files compare wrote
    on_disk = sorted(p.name for p in results_dir.iterdir())
    assert manifest["files"] == on_disk
    sim = pd.read_csv(results_dir / "simulated.csv")
    assert manifest["speeds_pu"] == sorted(set(sim["Omega_pu"]))
    assert set(manifest["supplies"]) == {"square", "sine"}
    assert manifest["supplies"]["square"]["controller"] == "SixStep"
    assert manifest["supplies"]["sine"]["settings"]["class"] == "Sine"
    assert manifest["scenario"]["settle_periods"] == 3 and manifest["scenario"]["measure_periods"] == 2
    assert manifest["verdict"] == (results_dir / "verdict.txt").read_text().splitlines()
    # the motor file in the manifest rebuilds the same drive
    assert bl.Drive.from_dict(__import__("tomllib").loads(manifest["motor"]["toml"])) == bl.load("htm-48v")
    wf = pd.read_csv(results_dir / "waveforms.csv")
    assert sorted(set(wf["speed_pu"])) == list(report.WAVEFORM_SPEEDS)
    assert set(wf["supply"]) == {"square", "sine"}
    for _, part in wf.groupby(["supply", "speed_pu"]):
        # one electrical period of steady-state currents: the angle covers [0, 360) degrees, currents sum to zero
        assert part["theta_e_deg"].min() < 1.0 and 359.0 < part["theta_e_deg"].max() < 360.0
        assert np.all(np.diff(part["theta_e_deg"]) > 0)
        assert np.max(np.abs(part[["i_a", "i_b", "i_c"]].sum(axis=1))) < 1e-3
        assert 40 < part["i_a"].abs().max() < 70
    assert (results_dir / "report.html").stat().st_size > 10_000


def test_report_is_one_html_page_with_every_section(page: Page, results_dir: Path) -> None:
    ids = {a.get("id") for t, a in page.elements if t == "section"}
    assert {"verdict", "motor", "table1", "characteristics", "waveforms", "provenance"} <= ids
    assert "paper2" not in ids and "faults" not in ids  # not in this directory
    plots = {f["data-plot"] for f in page.figures}
    assert {"emf", "torque", "ripple", "efficiency", "dynamometer"} <= plots
    for w in report.WAVEFORM_SPEEDS:
        for kind in ("currents-square", "currents-sine", "torque"):
            assert f"wave-{w:g}-{kind}" in plots
    # one spec per figure, and every series refers to an embedded table and columns (the script cannot miss data)
    data = page.data
    assert set(data["plots"]) == plots
    for pid, spec in data["plots"].items():
        assert spec["series"], pid
        for s in spec["series"]:
            table = data["tables"][s["table"]]["data"]
            for col in (s["x"], s["y"], *s.get("where", {})):
                assert col in table, (pid, s["name"], col)
            n = sum(1 for j in range(len(table[s["x"]]))
                    if all(table[k][j] == v for k, v in s.get("where", {}).items()))
            assert n > 0, (pid, s["name"])
    # without JavaScript every plot is a static SVG with drawn paths
    for pid in plots:
        assert page.noscript[pid].lstrip().startswith("<svg") and page.noscript[pid].count("<path d=\"M") >= 2, pid


def test_table1_numbers_and_equations_appear(page: Page, results_dir: Path) -> None:
    quantities = json.loads((results_dir / "table1.json").read_text())["quantities"]
    rows = {r[0]: r for r in page.rows["table1"][1:]}
    assert len(quantities) == len(rows) >= 19
    for q in quantities:
        _, desc, value, unit, source = rows[q["key"]]
        expected = ("yes" if q["value"] else "no") if isinstance(q["value"], bool) else f"{q['value']:.6g}"
        assert value == expected and unit == q["unit"] and source == q["source"] and desc == q["description"]
    # the R-aware base speeds and the paper's equation numbers are there
    assert rows["Omega_sB_R_pu"][4] == "numeric" and rows["Omega_qB_R_pu"][4] == "numeric"
    assert rows["Omega_sB_pu"][4] == "(21)" and rows["Omega_qB_pu"][4] == "(30)"
    assert float(rows["Omega_sB_R_pu"][2]) == pytest.approx(0.869052, abs=1e-6)


def test_every_drive_parameter_is_listed_with_its_unit(page: Page) -> None:
    drive = bl.load("htm-48v")
    rows = {r[0]: r for r in page.rows["motor"] if r and "." in r[0]}
    for part, cls in (("motor", Motor), ("inverter", Inverter), ("mechanics", Mechanics), ("sensors", Sensors)):
        listed = [f for f, _, _ in report.PARAMETERS[part]]
        assert sorted(listed) == sorted(f.name for f in dataclasses.fields(cls)), part
        for name, _, unit in report.PARAMETERS[part]:
            row = rows[f"{part}.{name}"]
            assert row[3] == unit
            value = getattr(getattr(drive, part), name)
            if isinstance(value, float):
                assert row[2] == f"{value:.6g}"
    assert rows["motor.L"][4] == "75 \u00b5H" and rows["motor.Omega_N"][4] == "640 rpm"
    assert "trapezoid" in rows["motor.emf"][2]


def test_every_simulated_point_is_in_the_embedded_data(page: Page, results_dir: Path) -> None:
    sim = pd.read_csv(results_dir / "simulated.csv")
    table = page.data["tables"]["simulated"]["data"]
    assert set(table) == set(sim.columns)
    for col in sim.columns:
        assert _embedded_equals(table[col], sim[col]), col
    # and in the table of points (formatted), every speed with both supplies' torque
    rows = page.rows["characteristics"][1:]
    assert len(rows) == sim["Omega_pu"].nunique()
    for r in rows:
        w = float(r[0])
        si = sim[(sim.supply == "sine") & np.isclose(sim.Omega_pu, w)].iloc[0]
        sq = sim[(sim.supply == "square") & np.isclose(sim.Omega_pu, w)].iloc[0]
        assert r[1] == f"{si.T_pu:.6g}" and r[3] == f"{sq.T_pu:.6g}" and r[6] == f"{sq.TR_pu:.6g}"
    wf = pd.read_csv(results_dir / "waveforms.csv")
    for (supply, speed), part in wf.groupby(["supply", "speed_pu"]):
        emb = page.data["tables"][f"wave_{supply}_{speed:g}"]["data"]
        for col in ("theta_e_deg", "i_a", "i_b", "i_c", "tau_e_pu"):
            assert _embedded_equals(emb[col], part[col]), (supply, speed, col)


def test_provenance_is_in_the_page(page: Page, results_dir: Path) -> None:
    manifest = json.loads((results_dir / "manifest.json").read_text())
    text = page.all_text
    assert manifest["command"] in text
    assert f"bldclab {__version__}" in text and manifest["created"] in text
    assert "SixStep" in text and "Sine" in text and "handoff_speed" in text
    assert "the next 2 whole electrical periods" in text and "3 electrical periods" in text
    for line in manifest["verdict"]:
        assert text.count(line) >= 2  # at the top and in the provenance
    for name in manifest["files"]:
        assert name in text
    assert manifest["environment"]["numpy"] in text


def test_page_needs_no_network(page: Page, results_dir: Path) -> None:
    text = (results_dir / "report.html").read_text(encoding="utf-8")
    for tag, attrs in page.elements:
        for name in ("src", "href", "action", "data", "poster"):
            value = attrs.get(name)
            if value is not None:
                assert value.startswith("#"), (tag, name, value)
        assert tag not in ("link", "iframe", "img", "object", "embed"), tag
    assert all("src" not in a for a, _ in page.scripts)
    assert not re.search(r"https?://", text)  # no URL at all, not even a namespace
    assert "@import" not in text and not re.search(r"url\((?!#)", text)
    assert not re.search(r"\b(fetch|XMLHttpRequest|WebSocket|importScripts)\b", text)
    assert page.elements[0][0] == "html" and text.startswith("<!DOCTYPE html>")
    assert len(text.encode()) < 2_000_000


@pytest.mark.slow
def test_report_command_on_the_directory_adds_faults_and_methods(results_dir: Path, tmp_path: Path) -> None:
    d = tmp_path / "res"
    d.mkdir()
    for p in results_dir.iterdir():
        (d / p.name).write_bytes(p.read_bytes())
    assert main(["faults", "htm-48v", "--out", str(d)]) == 0
    assert main(["torque-control", "htm-48v", "--torques", "100%", "--speeds", "0.5 pu", "--methods", "rect,lu",
                 "--out", str(d)]) == 0
    out = tmp_path / "r" / "page.html"
    assert main(["report", str(d), "--out", str(out)]) == 0
    pg = Page(out.read_text(encoding="utf-8"))
    ids = {a.get("id") for t, a in pg.elements if t == "section"}
    assert {"paper2", "faults"} <= ids
    faults = pd.read_csv(d / "faults.csv")
    fault_rows = pg.rows["faults"][1:]
    assert [r[0] for r in fault_rows] == list(faults["fault"])
    methods = pd.read_csv(d / "methods.csv")
    assert [r[0] for r in pg.rows["paper2"][1:]][-len(methods):] == list(methods["method"])
    # torque-control's own figure is inline, stripped of everything that could reach out
    text = out.read_text(encoding="utf-8")
    assert "Paper 2 methods compared" in text and not re.search(r"https?://", text)
    assert f"bldclab report {d} --out {out}" in pg.all_text


def test_report_from_a_motor_runs_the_comparison(tmp_path: Path) -> None:
    out = tmp_path / "m.html"
    assert main(["report", "htm-48v", "--speeds", "2", "--waveform-speeds", "0.5", "--torque-control", "--workers",
                 "1", "--out", str(out)]) == 0
    pg = Page(out.read_text(encoding="utf-8"))
    data = pg.data
    sim = pd.DataFrame(data["tables"]["simulated"]["data"])
    assert sorted(set(sim["Omega_pu"])) == [0.05, 0.98] and len(sim) == 4
    assert {f["data-plot"] for f in pg.figures} >= {"wave-0.5-torque", "methods-torque", "methods-current"}
    assert set(pd.DataFrame(data["tables"]["methods_traces"]["data"])["method"]) == {"rect", "lu-no-do", "lu"}
    assert len(pg.rows["paper2"]) > 27  # the 3 x 3 x 3 methods table (and the settings of how it was run)
    cmd = f"bldclab report htm-48v --out {out} --speeds 2 --min-speed 0.05 --max-speed 0.98 --waveform-speeds 0.5 " \
          "--torque-control"
    assert pg.all_text.count(cmd) >= 2  # the run and this report


@pytest.mark.slow
def test_compare_without_report(tmp_path: Path) -> None:
    out = tmp_path / "c"
    assert main(["compare", "htm-48v", "--out", str(out), "--speeds", "2", "--workers", "1", "--no-report"]) == 0
    assert not (out / "report.html").exists()
    manifest = json.loads((out / "manifest.json").read_text())
    assert "report.html" not in manifest["files"] and "waveforms.csv" in manifest["files"]
    # the directory still makes a report afterwards
    assert main(["report", str(out)]) == 0
    assert (out / "report.html").stat().st_size > 10_000


def _broken_dir(tmp: Path, results_dir: Path, kind: str) -> Path:
    d = tmp / "bad"
    d.mkdir()
    if kind == "empty":
        return d
    for p in results_dir.iterdir():
        if p.suffix in (".csv", ".json", ".txt"):
            (d / p.name).write_bytes(p.read_bytes())
    if kind == "manifest":
        (d / "manifest.json").write_text("{not json")
    elif kind == "format":
        (d / "manifest.json").write_text(json.dumps({"format": "other"}))
    elif kind == "column":
        sim = pd.read_csv(d / "simulated.csv").drop(columns=["T_pu"])
        (d / "simulated.csv").write_text(sim.to_csv(index=False))
    elif kind == "missing":
        (d / "simulated.csv").unlink()
    return d


@pytest.mark.parametrize("kind, extra, field", [
    ("empty", [], "manifest.json"),
    ("manifest", [], "manifest.json"),
    ("format", [], "manifest.json: format"),
    ("column", [], "simulated.csv: column T_pu"),
    ("missing", [], "simulated.csv"),
    ("ok", ["--speeds", "4"], "--speeds"),
])
def test_bad_results_directory_exits_2_and_writes_nothing(kind, extra, field, results_dir, tmp_path, capsys):
    d = _broken_dir(tmp_path, results_dir, kind)
    before = sorted(p.name for p in d.iterdir())
    out = tmp_path / "o" / "r.html"
    assert main(["report", str(d), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("bldclab: error:") and field in err[0], err
    assert not out.exists() and not out.parent.exists()
    assert sorted(p.name for p in d.iterdir()) == before


@pytest.mark.parametrize("argv, field", [
    pytest.param(["nosuch-motor"], "nosuch-motor", marks=pytest.mark.slow),  # a process each: ~1 s
    pytest.param(["htm-48v", "--speeds", "1"], "--speeds", marks=pytest.mark.slow),
    pytest.param(["htm-48v", "--waveform-speeds", "fast"], "--waveform-speeds", marks=pytest.mark.slow),
    pytest.param(["htm-48v", "--min-speed", "0.9", "--max-speed", "0.2"], "--min-speed", marks=pytest.mark.slow),
])
def test_bad_motor_arguments_exit_2_with_one_line(argv, field, tmp_path):
    out = tmp_path / "o" / "r.html"
    proc = subprocess.run([sys.executable, "-m", "bldclab.cli", "report", *argv, "--out", str(out)],
                          capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0] and "Traceback" not in proc.stderr
    assert not (tmp_path / "o").exists() and not (tmp_path / "out").exists()


def test_clean_svg_refuses_active_content() -> None:
    good = ('<?xml version="1.0"?>\n<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" "http://www.w3.org/x.dtd">'
            '<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" viewBox="0 0 1 1">'
            '<metadata><a>http://example.org</a></metadata><use xlink:href="#p"/></svg>')
    cleaned = report._clean_svg(good)
    assert cleaned is not None and cleaned.startswith("<svg") and "http" not in cleaned and "#p" in cleaned
    for bad in ('<svg><script>alert(1)</script></svg>', '<svg><rect onclick="x()"/></svg>',
                '<svg><image href="https://example.org/a.png"/></svg>', '<svg><rect fill="url(http://x/y)"/></svg>'):
        assert report._clean_svg(bad) is None, bad


def test_svg_plot_draws_lines_markers_and_keeps_spikes() -> None:
    x = np.linspace(0.0, 1.0, 5001)
    y = np.sin(2 * np.pi * x)
    y[2500] = 40.0  # a one-sample spike survives the decimation
    y[100:110] = np.nan  # a gap breaks the line
    svg = report.svg_plot([report.Series("s", x, y, "#123456"), report.Series("m", [0.2, 0.4], [1.0, 2.0], "#654321",
                                                                             line=False, marker="x")],
                          title="t", xlabel="x [s]", ylabel="y [V]", max_points=400)
    assert svg.startswith("<svg") and svg.endswith("</svg>") and "xmlns" not in svg
    line = re.search(r'<path d="([^"]+)" stroke="#123456"', svg).group(1)
    assert line.count("M") == 2  # one break at the gap
    assert 150 < line.count("L") < 600
    ys = [float(v) for v in re.findall(r"[ML][\d.-]+ ([\d.-]+)", line)]
    assert min(ys) < 40  # the spike is drawn: it reaches the top of the plot area (y grows downwards from 14)
    assert svg.count('stroke="#654321"') >= 2 and "x [s]" in svg and "y [V]" in svg
    with pytest.raises(bl.BldclabError, match="differ in length"):
        report.svg_plot([report.Series("bad", [1, 2], [1], "#000")])


def test_simresult_displays_plots_and_metrics_in_a_notebook() -> None:
    drive = bl.load("htm-48v")
    om = 0.5 * drive.Omega_0
    te = 2 * math.pi / (drive.motor.p * om)
    res = bl.simulate(drive, bl.SixStepVoltage("high"),
                      bl.Scenario(duration=4 * te, speed=om, ref=0.6, window=(2 * te, 4 * te)))
    h = res._repr_html_()
    assert h.count("<svg") == 2 and "i_a" in h and "tau_e" in h and "current [A]" in h
    m = res.metrics
    assert f"<td>tau_mean</td><td style=\"text-align: right\">{m.tau_mean:.6g}</td><td>N m</td>" in h
    assert "<td>p_src</td>" in h and "<td>W</td>" in h and "<td>i_rms</td>" in h
    assert "http" not in h
    untraced = bl.simulate(drive, bl.SixStepVoltage("high"),
                           bl.Scenario(duration=2 * te, speed=om, ref=0.6, window=(te, 2 * te), trace=False))
    h2 = untraced._repr_html_()
    assert "<table>" in h2 and "tau_mean" in h2


def test_sweep_run_displays_table_and_plot_in_a_notebook() -> None:
    sw = sweep.Sweep(base={"drive": "htm-48v", "controller": "SixStepVoltage", "control.chopping": "high"},
                     grid={"speed_pu": [0.3, 0.6], "ref": [0.4, 0.8]})
    run = sweep.run(sw, executor=sweep.Serial(), progress=False)
    h = run._repr_html_()
    df = run.to_pandas()
    assert run.summary().replace(":", "") in h.replace(":", "")
    assert "<table" in h and "speed_pu" in h and "tau_mean" in h and h.count("<tr>") >= len(df)
    assert "<svg" in h and "ref = 0.4" in h and "ref = 0.8" in h  # tau_mean vs speed_pu, a line per ref
    assert f"{df['tau_mean'].iloc[0]:.6g}" in h
    run.store.close()
    assert "results not readable" in run._repr_html_()


def test_sweep_plot_picks_a_varying_result_and_names_a_text_axis() -> None:
    df = pd.DataFrame({"case": [0, 1, 2, 3], "motor.L": ["70 uH", "80 uH", "70 uH", "80 uH"],
                       "ref": [0.4, 0.4, 0.8, 0.8],
                       "speed_pu_result": [0.3, 0.3, 0.3, 0.3], "speed": [22.5, 22.5, 22.5, 22.5],
                       "steps": [10, 10, 10, 10], "tau_mean": [1.0, 2.0, 3.0, 4.0], "key": list("abcd")})
    series, xlabel, ylabel = sweep._sweep_plot(df, ["motor.L", "ref"])
    assert ylabel == "tau_mean" and xlabel == "motor.L (0: 70 uH, 1: 80 uH)"
    assert [s.name for s in series] == ["ref = 0.4", "ref = 0.8"]
    assert list(series[0].x) == [0.0, 1.0] and list(series[1].y) == [3.0, 4.0]
    assert sweep._sweep_plot(df.drop(columns=["tau_mean", "ref"]), ["motor.L"]) is None  # no result varies


def test_heat_section_with_the_motor_files_network_and_the_envelope_file(results_dir: Path, tmp_path: Path) -> None:
    """htm-48v has [thermal]: section 10 lists its nodes and links; thermal_envelope.csv of ``bldclab thermal
    --envelope`` in the directory adds its rows; a drive without [thermal] has no heat section."""
    th = bl.load("htm-48v").thermal
    assert th is not None
    page = Page((results_dir / "report.html").read_text(encoding="utf-8"))
    rows = page.rows["heat"]
    names = [r[0] for r in rows if len(r) == 6][1:]
    assert names == [n.name for n in th.nodes]
    assert sum(1 for r in rows if len(r) == 3) == len(th.links) + 1  # header and one row per link
    assert "bldclab thermal MOTOR --envelope --out" in page.all_text
    d = tmp_path / "res"
    d.mkdir()
    for p in results_dir.iterdir():
        (d / p.name).write_bytes(p.read_bytes())
    assert main(["thermal", "htm-48v", "--envelope", "--speeds", "200 rpm", "--durations", "60 s",
                 "--out", str(d / "thermal_envelope.csv")]) == 0
    out = tmp_path / "r.html"
    assert main(["report", str(d), "--out", str(out)]) == 0
    env = pd.read_csv(d / "thermal_envelope.csv")
    pg = Page(out.read_text(encoding="utf-8"))
    (row,) = [r for r in pg.rows["heat"] if len(r) == len(env.columns) + 1 and r[0] != "speed"]
    assert float(row[1]) == pytest.approx(200.0, rel=1e-3)
    assert float(row[env.columns.get_loc("sine cont") + 1]) == pytest.approx(float(env["sine cont"][0]), rel=1e-3)
    # without [thermal]: no section
    files = {p.name: p.read_bytes() for p in results_dir.iterdir()}
    res = report.Results.from_files(files, str(results_dir))
    cold = dataclasses.replace(res, drive=dataclasses.replace(res.drive, thermal=None))
    text = report.render(cold, report_command="test")
    assert 'id="heat"' not in text and 'id="heat"' in report.render(res, report_command="test")

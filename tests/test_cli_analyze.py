"""``bldclab analyze``: output formats, written files, and the one-line error frame of all subcommands."""

from __future__ import annotations

import csv
import io
import json
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd
import pytest

import bldclab
from bldclab import cli
from bldclab.model import analytic as an

SRC = Path(__file__).resolve().parents[1] / "src"
OUT_FILES = {"table1.csv", "table1.json", "characteristic.csv", "fig7_torque_speed.png",
             "fig7_torque_speed.svg", "fig8_ripple.png", "fig8_ripple.svg"}

# the paper's numbers as the table prints them (6 significant digits)
PAPER_VALUES = {
    "Theta_m": "0.046875",
    "Omega_sB_pu": "0.955224",
    "Omega_qB_pu": "0.957155",
    "T_qB_pu": "0.766418",
    "T_sN_pu": "1.05296",
    "TR_sN_pu": "0.154701",
    "eta_ratio_0955": "1.05212",
    "eta_ratio_0455": "1.01379",
}


def run_main(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    rc = cli.main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def run_subprocess(*argv: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=str(SRC), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "bldclab.cli", *argv], capture_output=True, text=True,
                          env=env, cwd=cwd, timeout=300, check=False)


def assert_one_line_error(rc: int, err: str, *needles: str) -> None:
    assert rc == 2
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("bldclab: error: ")
    for n in needles:
        assert n in lines[0], lines[0]


# ------------------------------------------------------------------------------------------------------------
# successful runs


def test_analyze_table_in_process(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = run_main(capsys, "analyze", "htm-48v")
    assert rc == 0 and err == ""
    assert "htm-48v" in out.splitlines()[0]
    rows = {line.split()[0]: line.split() for line in out.splitlines()[2:]}
    for key, value in PAPER_VALUES.items():
        assert value in rows[key], (key, rows[key])
    # the R-aware base speeds are printed, below the R = 0 ones
    assert float(rows["Omega_sB_R_pu"][-3]) < 0.955 and float(rows["Omega_qB_R_pu"][-3]) < 0.957


def test_analyze_json_and_csv_match_the_library(capsys: pytest.CaptureFixture[str]) -> None:
    ref = an.table1(bldclab.load("htm-48v")).to_dict()
    rc, out, _ = run_main(capsys, "analyze", "htm-48v", "--format", "json")
    assert rc == 0
    doc = json.loads(out)
    assert doc["motor"] == "htm-48v"
    values = {q["key"]: q["value"] for q in doc["quantities"]}
    for key, value in values.items():
        assert value == pytest.approx(ref[key], rel=1e-15)
    assert round(values["eta_ratio_0955"], 3) == 1.052 and round(values["eta_ratio_0455"], 3) == 1.014
    rc, out, _ = run_main(capsys, "analyze", "htm-48v", "--format", "csv")
    assert rc == 0
    rows = list(csv.DictReader(io.StringIO(out)))
    assert {r["key"] for r in rows} == set(values)
    by_key = {r["key"]: r for r in rows}
    assert float(by_key["Omega_qB_pu"]["value"]) == pytest.approx(ref["Omega_qB_pu"], rel=1e-15)
    assert by_key["Omega_qB_pu"]["source"] == "(30)"


def test_analyze_out_writes_parseable_files(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out_dir = tmp_path / "a" / "b"
    rc, _, err = run_main(capsys, "analyze", "htm-48v", "--out", str(out_dir), "--speeds", "41")
    assert rc == 0 and err == ""
    assert {p.name for p in out_dir.iterdir()} == OUT_FILES  # no temporary files left
    doc = json.loads((out_dir / "table1.json").read_text())
    values = {q["key"]: q["value"] for q in doc["quantities"]}
    assert round(values["Omega_sB_pu"], 3) == 0.955
    t1 = pd.read_csv(out_dir / "table1.csv")
    assert set(t1["key"]) == set(values)
    df = pd.read_csv(out_dir / "characteristic.csv")
    assert list(df.columns) == list(an.CHARACTERISTIC_COLUMNS)
    assert len(df) == 41 + 2  # plus Omega_sB and Omega_qB (0.5 is on the grid already)
    assert df["Omega_pu"].is_monotonic_increasing
    assert df["Omega_pu"].iloc[0] == 0.0 and df["Omega_pu"].iloc[-1] == 1.0
    assert (df["Omega_pu"] - values["Omega_qB_pu"]).abs().min() < 1e-12
    assert set(df["region_q"]) == {an.REGION_Q_LOW, an.REGION_Q_HIGH, an.REGION_Q_SAT, an.REGION_STOP}
    for name in ("fig7_torque_speed.png", "fig8_ripple.png"):
        assert (out_dir / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for name in ("fig7_torque_speed.svg", "fig8_ripple.svg"):
        root = ET.parse(out_dir / name).getroot()
        assert root.tag.endswith("svg")


@pytest.mark.slow
def test_analyze_len_of_speeds_without_duplicates(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    rc, _, _ = run_main(capsys, "analyze", "htm-48v", "--out", str(tmp_path), "--speeds", "3")
    assert rc == 0
    df = pd.read_csv(tmp_path / "characteristic.csv")
    assert len(df) == 5  # 0, 0.5, 1 and the two base speeds: 0.5 appears once


def test_analyze_toml_path(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "other.toml"
    text = bldclab.load("htm-48v").to_toml()
    text = re.sub(r"(?m)^L = .*$", "L = 1.5e-04", text).replace('name = "htm-48v"', 'name = "other"')
    path.write_text(text)
    rc, out, _ = run_main(capsys, "analyze", str(path), "--format", "json")
    assert rc == 0
    doc = json.loads(out)
    assert doc["motor"] == "other"
    values = {q["key"]: q["value"] for q in doc["quantities"]}
    assert values["Theta_m"] == pytest.approx(2 * 0.046875)
    assert values["Omega_sB_pu"] == pytest.approx(1 / (1 + 2 * 0.046875))
    # 0.955 is above this motor's base speed (0.914): the efficiency ratio of (40) is undefined there
    assert values["eta_ratio_0955"] is None and values["eta_ratio_0455"] > 1.0
    rc, out, _ = run_main(capsys, "analyze", str(path))
    assert rc == 0
    assert re.search(r"(?m)^eta_ratio_0955 .* n/a ", out)


@pytest.mark.slow
def test_subprocess_module_entry_point(tmp_path: Path) -> None:
    res = run_subprocess("analyze", "htm-48v", "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    for value in PAPER_VALUES.values():
        assert value in res.stdout
    assert {p.name for p in (tmp_path / "out").iterdir()} == OUT_FILES


def test_help_and_version(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = run_main(capsys, "--help")
    assert rc == 0 and "analyze" in out
    rc, out, _ = run_main(capsys, "analyze", "--help")
    assert rc == 0 and "--speeds" in out
    rc, out, _ = run_main(capsys, "--version")
    assert rc == 0 and bldclab.__version__ in out


# ------------------------------------------------------------------------------------------------------------
# errors: one line, exit 2, no traceback, nothing written


@pytest.mark.parametrize("argv, needle", [
    (["analyze", "no-such-motor"], "no-such-motor"),
    (["analyze", "htm-48v", "--format", "xml"], "--format"),
    (["analyze", "htm-48v", "--speeds", "1"], "--speeds"),
    (["analyze", "htm-48v", "--speeds", "many"], "--speeds"),
    (["analyze"], "MOTOR"),
    ([], "COMMAND"),
    (["frobnicate"], "frobnicate"),
])
def test_bad_arguments(capsys: pytest.CaptureFixture[str], argv: list[str], needle: str) -> None:
    rc, out, err = run_main(capsys, *argv)
    assert out == ""
    assert_one_line_error(rc, err, needle)


def test_bad_motor_name_subprocess() -> None:
    res = run_subprocess("analyze", "no-such-motor")
    assert res.stdout == ""
    assert_one_line_error(res.returncode, res.stderr, "no-such-motor", "htm-48v")


def _motor_file(tmp_path: Path, l_line: str | None) -> Path:
    text = bldclab.load("htm-48v").to_toml()
    text = re.sub(r"(?m)^L = .*\n", "" if l_line is None else l_line + "\n", text)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("l_line, needle", [
    (None, "is missing"),
    ("L = -7.5e-05", "must be > 0"),
    ("L = nan", "NaN"),
    ('L = "abc"', "abc"),
    ('L = "75 V"', "unit"),
])
def test_malformed_motor_file(capsys: pytest.CaptureFixture[str], tmp_path: Path, l_line: str | None,
                              needle: str) -> None:
    path = _motor_file(tmp_path, l_line)
    out_dir = tmp_path / "out"
    rc, out, err = run_main(capsys, "analyze", str(path), "--out", str(out_dir))
    assert out == ""
    assert_one_line_error(rc, err, "motor.L", needle)
    assert not out_dir.exists()


@pytest.mark.slow
def test_malformed_motor_file_subprocess(tmp_path: Path) -> None:
    path = _motor_file(tmp_path, "L = nan")
    res = run_subprocess("analyze", str(path), "--out", str(tmp_path / "out"))
    assert_one_line_error(res.returncode, res.stderr, "motor.L", "bad.toml")
    assert not (tmp_path / "out").exists()


def test_toml_syntax_error(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "broken.toml"
    path.write_text("[motor\np = 8\n")
    rc, _, err = run_main(capsys, "analyze", str(path))
    assert_one_line_error(rc, err, "broken.toml", "TOML")


def test_out_is_a_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    target = tmp_path / "taken"
    target.write_text("keep me")
    rc, out, err = run_main(capsys, "analyze", "htm-48v", "--out", str(target))
    assert out == ""
    assert_one_line_error(rc, err, "--out")
    assert target.read_text() == "keep me"


def test_write_files_leaves_nothing_half_written(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    real_replace = os.replace
    calls: list[str] = []

    def failing_replace(src: str, dst: str | Path) -> None:
        calls.append(str(dst))
        if len(calls) == 2:
            raise OSError(28, "No space left on device")
        real_replace(src, dst)

    monkeypatch.setattr(cli.os, "replace", failing_replace)
    with pytest.raises(bldclab.BldclabError, match="No space left"):
        cli.write_files(tmp_path, {"one.txt": b"1" * 1000, "two.txt": b"2" * 1000, "three.txt": b"3"})
    # the first file is complete, the failed one is absent (no temporary left), the third never started
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.txt"]
    assert (tmp_path / "one.txt").read_bytes() == b"1" * 1000


def test_commands_registry_drives_the_parser() -> None:
    names = [c.name for c in cli.COMMANDS]
    assert "analyze" in names and len(set(names)) == len(names)
    parser = cli.build_parser()
    args = parser.parse_args(["analyze", "htm-48v"])
    assert args.run is cli.COMMANDS[names.index("analyze")].run


# ------------------------------------------------------------------------------------------------------------
# the figures behind --out


def test_plots_overlays_and_given_axes() -> None:
    from matplotlib.figure import Figure

    from bldclab.report import plots

    drive = bldclab.load("htm-48v")
    df = an.characteristic(drive, [0.0, 0.25, 0.5, 0.75, 0.9, 1.0])
    sim = pd.DataFrame({"Omega_pu": [0.3, 0.8], "T_q_pu": [0.99, 0.93], "T_s_pu": [1.05, 1.04]})
    fig, ax = plots.plot_torque_speed(df, overlays={"simulation": sim})
    assert isinstance(fig, Figure)
    labels = [line.get_label() for line in ax.get_lines()]
    assert labels == ["sinusoidal supply", "real square-wave supply", "equivalent PM BLAC motor",
                      "simulation: sinusoidal supply", "simulation: real square-wave supply"]
    assert list(ax.get_lines()[0].get_xdata()) == list(df["Omega_pu"])
    assert ax.get_lines()[0].get_marker() == "x" and ax.get_lines()[1].get_marker() == "o"
    # drawing into given axes returns them and their figure
    fig2 = Figure()
    ax2 = fig2.add_subplot()
    ripple = sim.rename(columns={"T_q_pu": "TR_q_pu"})
    got_fig, got_ax = plots.plot_ripple(df, ax=ax2, overlays={"run": ripple})
    assert got_fig is fig2 and got_ax is ax2
    assert [line.get_label() for line in ax2.get_lines()][-1] == "run: real square-wave supply"
    with pytest.raises(bldclab.BldclabError, match="TR_s_pu"):
        plots.plot_ripple(df.drop(columns="TR_s_pu"))


def test_plots_do_not_touch_pyplot() -> None:
    code = ("import sys, bldclab, bldclab.report.plots as p, bldclab.model.analytic as a\n"
            "df = a.characteristic(bldclab.load('htm-48v'), [0.0, 0.5, 1.0])\n"
            "p.plot_torque_speed(df); p.plot_ripple(df)\n"
            "assert 'matplotlib.pyplot' not in sys.modules\n")
    env = dict(os.environ, PYTHONPATH=str(SRC))
    env.pop("MPLBACKEND", None)
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120,
                         check=False)
    assert res.returncode == 0, res.stderr


def _fig7_with_data(drive: bldclab.Drive) -> tuple[object, int]:
    """A figure job's function that also returns data (as paper 1's Fig 12 does)."""
    from bldclab.report import plots

    fig, _ = plots.plot_torque_speed(an.characteristic(drive, [0.0, 0.5, 1.0]))
    return fig, 42


def test_figures_drawn_on_a_pool_are_those_drawn_here() -> None:
    from concurrent.futures import ProcessPoolExecutor

    from bldclab.report import plots

    jobs = {"fig7": plots.FigureJob(_fig7_with_data, (bldclab.load("htm-48v"),), dated=False)}
    here = plots.render_figures(jobs)
    with ProcessPoolExecutor(max_workers=1) as pool:
        there = plots.render_figures(jobs, pool)
    assert here["fig7"][1] == there["fig7"][1] == 42
    assert here["fig7"][0]["png"] == there["fig7"][0]["png"]  # the SVG's element ids are random
    assert set(here["fig7"][0]) == {"png", "svg"} and b"<svg" in there["fig7"][0]["svg"][:2000]


def test_a_figure_is_laid_out_once_for_all_its_formats() -> None:
    """render_figure keeps the first format's layout for the next ones: a PNG drawn after the SVG with the kept
    layout is the PNG drawn with the layout engine."""
    from bldclab.report import plots

    drive = bldclab.load("htm-48v")
    files, data, caught = plots.render_figure(plots.FigureJob(_fig7_with_data, (drive,), formats=("png", "svg", "png")))
    fig, _ = _fig7_with_data(drive)
    assert data == 42 and caught == [] and files["png"] == plots.figure_bytes(fig, "png")

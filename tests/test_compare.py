"""bldclab compare and bldclab simulate: paper 1 end to end through the CLI and the Python API."""

from __future__ import annotations

import json
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import bldclab as bl
from bldclab.analysis.compare import compare
from bldclab.cli import main
from bldclab.model import analytic as an
from bldclab.report.bundle import compare_directory, compare_files, compare_outputs


def test_compare_ideal_drive_follows_the_closed_forms():
    """With R = 0 the simulated characteristics follow paper 1 within the issue's tolerances."""
    drive = bl.load("htm-48v").replace(motor__R=0.0)
    w = np.array([0.1, 0.3, 0.6, 0.9])
    res = compare(drive, w, workers=1)
    th = an.theta_m(drive)
    sq = res.simulated[res.simulated.supply == "square"].set_index("Omega_pu")
    si = res.simulated[res.simulated.supply == "sine"].set_index("Omega_pu")
    for x in w:
        assert sq.loc[x, "T_pu"] == pytest.approx(an.t_q_pu(x, th), abs=0.005)
        assert si.loc[x, "T_pu"] == pytest.approx(an.t_s_pu(x, th), abs=0.005)
        assert sq.loc[x, "TR_pu"] == pytest.approx(an.tr_q_pu(x, th), abs=0.02)
        assert si.loc[x, "TR_pu"] == pytest.approx(an.tr_s_pu(x, th), abs=0.02)
        # the paper-comparable ripple: exact extremes on the averaged inverter
        assert sq.loc[x, "TR_avg_pu"] == pytest.approx(an.tr_q_pu(x, th), abs=0.02)
        assert si.loc[x, "TR_avg_pu"] == pytest.approx(an.tr_s_pu(x, th), abs=0.02)
        assert sq.loc[x, "T_avg_pu"] == pytest.approx(sq.loc[x, "T_pu"], abs=0.01)
        assert abs(sq.loc[x, "balance"]) < 1e-5 and abs(si.loc[x, "balance"]) < 1e-5
    # the verdict names the speed ranges: sinusoidal torque higher everywhere, ripple higher around half speed
    assert any(v.startswith("mean torque: sinusoidal better for Omega in [0.10, 0.90]") for v in res.verdict)
    assert any(v.startswith("torque ripple (averaged inverter): square-wave better") for v in res.verdict)


@pytest.mark.slow
def test_the_results_directory_made_on_a_pool_is_the_one_made_here():
    """compare_directory on a pool (figures, waveforms on the workers, report meanwhile) writes the files of
    compare_files + compare_outputs in this process, in the same order; only dates and SVG ids differ."""
    res = compare(bl.load("htm-48v"), [0.3, 0.8], workers=1, base_speeds=False)
    here = compare_files(res)
    here.update(compare_outputs(res, here, command="bldclab compare htm-48v"))
    with ProcessPoolExecutor(max_workers=2) as pool:
        there = compare_directory(res, command="bldclab compare htm-48v", executor=pool)
    assert list(there) == list(here)
    for name in here:
        if name.endswith((".csv", ".txt", ".png")) or name == "table1.json":
            assert there[name] == here[name], name
    a, b = (json.loads(files["manifest.json"]) for files in (here, there))
    assert {k: v for k, v in a.items() if k != "created"} == {k: v for k, v in b.items() if k != "created"}
    assert "report.html" in there and there["fig12_dynamometer.svg"].startswith(b"<?xml")


def test_compare_verdict_states_its_resolution(compare_htm48v):
    """Every comparison in verdict.txt names the smallest difference it counts (VERDICT_TOLERANCE)."""
    lines = (compare_htm48v / "verdict.txt").read_text().splitlines()
    measures = [v for v in lines if v.startswith(("mean torque", "torque ripple", "efficiency"))]
    assert measures
    for v in measures:
        assert " resolved)" in v or "what the simulation resolves" in v, v


def test_compare_cli_writes_everything(compare_htm48v):
    """The session's run (tests/conftest.py): ``bldclab compare htm-48v --speeds 6 --workers 2``."""
    out = compare_htm48v
    for name in ("simulated.csv", "analytic.csv", "table1.csv", "table1.json", "verdict.txt",
                 "torque_speed.png", "torque_speed.svg", "ripple_speed.png", "efficiency_speed.svg"):
        assert (out / name).stat().st_size > 100, name
    sim = pd.read_csv(out / "simulated.csv")
    assert len(sim) == 12 and set(sim.supply) == {"square", "sine"}
    assert np.all(sim.eta.between(0.2, 1.0))
    t1 = json.loads((out / "table1.json").read_text())
    assert "quantities" in t1


@pytest.mark.slow
def test_compare_pwm_phases_and_base_speeds(tmp_path, capsys):
    """--pwm-phases adds each point's range over the PWM-grid phases; the simulated base speeds stand beside (21),
    (30) and the numeric values with R in the terminal, the verdict and base_speeds.csv."""
    out = tmp_path / "cmp"
    rc = main(["compare", "htm-48v", "--out", str(out), "--speeds", "3", "--pwm-phases", "2", "--workers", "1",
               "--no-report"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "simulated: 0.869 / 0.877 p.u." in text and "over 2 PWM-grid phases" in text
    # the table has one row per speed of the heading ("3 speeds"), each with its rpm
    rows = [line.split() for line in text.splitlines() if line.lstrip().startswith(("0.", "1."))]
    assert "3 speeds x 2 supplies" in text and len(rows) == 3
    omega_0 = bl.load("htm-48v").Omega_0
    assert [float(r[1]) for r in rows] == pytest.approx([w * omega_0 * 30 / np.pi for w in (0.05, 0.515, 0.98)],
                                                        abs=0.5)
    sim = pd.read_csv(out / "simulated.csv")
    for key in ("T_pu", "TR_pu", "TR_ma_pu"):
        assert np.all(sim[f"{key}_min"] <= sim[key] + 1e-12) and np.all(sim[key] <= sim[f"{key}_max"] + 1e-12)
    bs = pd.read_csv(out / "base_speeds.csv").set_index("supply")
    t1 = an.table1(bl.load("htm-48v"))
    assert bs.loc["sine", "closed_form_pu"] == pytest.approx(t1.Omega_sB_pu)
    assert bs.loc["square", "numeric_R_pu"] == pytest.approx(t1.Omega_qB_R_pu)
    assert bs.loc["square", "simulated_pu"] == pytest.approx(t1.Omega_qB_R_pu, abs=0.003)
    assert bs.loc["sine", "simulated_pu"] == pytest.approx(t1.Omega_sB_R_pu, abs=0.003)
    verdict = (out / "verdict.txt").read_text()
    assert "base speed, square-wave: 0.877 p.u. simulated" in verdict


@pytest.mark.slow
def test_compare_notes_where_the_samples_miss_the_commutation():
    """lu-4kw's square-wave commutation lasts under one PWM period mid-range: the verdict says the ripple at the samples
    misses it there; the sinusoidal supply and htm-48v get no such note."""
    res = compare(bl.load("lu-4kw"), [0.1, 0.5, 0.68], workers=1, base_speeds=False)
    notes = [v for v in res.verdict if v.startswith("note")]
    assert len(notes) == 1 and notes[0].startswith("note, square-wave: for Omega in [0.50, 0.68] p.u.")
    sq = res.simulated[res.simulated.supply == "square"].set_index("Omega_pu")
    assert sq.loc[0.68, "TR_ma_pu"] - sq.loc[0.68, "TR_pu"] > 0.05
    res = compare(bl.load("htm-48v"), [0.2, 0.5, 0.8], workers=1, base_speeds=False)
    assert not any(v.startswith("note") for v in res.verdict)
    assert res.base_speeds is None


def test_compare_uses_processes_deterministically():
    drive = bl.load("htm-48v")
    w = [0.2, 0.7]
    a = compare(drive, w, workers=1).simulated
    b = compare(drive, w, workers=2).simulated
    pd.testing.assert_frame_equal(a, b)


@pytest.mark.parametrize("argv, field", [
    pytest.param(["compare", "nosuch"], "MOTOR", marks=pytest.mark.slow),  # a process each: ~1 s
    pytest.param(["compare", "htm-48v", "--speeds", "1"], "--speeds", marks=pytest.mark.slow),
    pytest.param(["compare", "htm-48v", "--min-speed", "0.9", "--max-speed", "0.5"], "--min-speed",
                 marks=pytest.mark.slow),
    pytest.param(["compare", "htm-48v", "--pwm-phases", "0"], "--pwm-phases", marks=pytest.mark.slow),
    pytest.param(["simulate", "htm-48v", "--control", "square", "--torque", "10 N m"], "--torque",
                 marks=pytest.mark.slow),
    (["simulate", "htm-48v", "--speed", "12 V"], "--speed"),
    pytest.param(["simulate", "htm-48v", "--speed", "0 rpm"], "--speed", marks=pytest.mark.slow),
])
def test_bad_arguments_exit_2_with_one_line(argv, field, tmp_path):
    proc = subprocess.run([sys.executable, "-m", "bldclab.cli", *argv, "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0] and "Traceback" not in proc.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.slow
@pytest.mark.parametrize("control, extra", [("square", []), ("sine", ["--torque", "20 N m"]),
                                            ("sixv", ["--duty", "0.4"]), ("lu", [])])
def test_simulate_cli(control, extra, tmp_path):
    motor = "lu-4kw" if control == "lu" else "htm-48v"
    out = tmp_path / control
    rc = main(["simulate", motor, "--control", control, "--speed", "0.4 pu", *extra, "--out", str(out), "--plot",
               "--format", "json"])
    assert rc == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["tau_mean_N_m"] > 0 and abs(metrics["energy_balance_residue"]) < 1e-5
    assert (out / "waveforms.png").stat().st_size > 10_000
    res = bl.SimResult.load(out / "result.npz")
    assert res.metrics is not None and len(res) > 100


@pytest.mark.slow
def test_torque_control_cli(tmp_path, capsys):
    rc = main(["torque-control", "lu-4kw", "--torques", "100%", "--speeds", "3000 rpm", "--out", str(tmp_path)])
    assert rc == 0
    table = pd.read_csv(tmp_path / "methods.csv").set_index("method")
    assert table.loc["rect", "ripple_ma_pp"] > table.loc["lu-no-do", "ripple_ma_pp"] > table.loc["lu", "ripple_ma_pp"]
    assert table.loc["lu", "dip_A"] < table.loc["lu-no-do", "dip_A"] < table.loc["rect", "dip_A"]
    assert (tmp_path / "methods_compared.svg").exists()
    out = capsys.readouterr().out
    assert "lu-no-do" in out


@pytest.mark.slow
def test_torque_control_cli_bad_torque(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "bldclab.cli", "torque-control", "lu-4kw", "--torques", "x%"],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and "--torques" in proc.stderr


@pytest.mark.slow
@pytest.mark.parametrize("workers", ["1", "2"])
def test_compare_folds_every_runs_warnings_into_one_line(tmp_path, capsys, workers):
    """Issue 23, item 1: the points', the waveforms' and paper 1's figures' warnings in one summary line (identical
    ones once), also from worker processes; --verbose lists each distinct one; the manifest lists them all."""
    drone = str(Path(__file__).resolve().parent / "data" / "drone-2207.toml")
    out = tmp_path / "o"
    assert main(["compare", drone, "--speeds", "4", "--workers", workers, "--no-report", "--out", str(out)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1, err
    line = err[0]
    assert line.startswith("bldclab: warning: ") and "plausibility warnings in 8 points, 4 waveforms and paper 1's " \
        "Figs 9, 11 and 12" in line and "repeats counted once" in line and "causes: inverter.f_pwm" in line
    listed = json.loads((out / "manifest.json").read_text())["warnings"]
    assert len(listed) == len(set(listed)) and int(line.split()[2]) == len(listed)
    assert any(w.startswith("paper 1 Fig 12 (dynamometer): ") for w in listed)
    assert main(["compare", drone, "--speeds", "4", "--workers", workers, "--no-report", "--out", str(out),
                 "--verbose"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert [e.removeprefix("bldclab: warning: ") for e in err[:-1]] == listed and err[-1] == line


@pytest.mark.slow
def test_effmap_folds_its_warnings_into_one_line(tmp_path, capsys):
    drone = str(Path(__file__).resolve().parent / "data" / "drone-2207.toml")
    argv = ["effmap", drone, "--torques", "2", "--speeds", "3", "--workers", "1", "--no-store", "--out",
            str(tmp_path / "m")]
    assert main(argv) == 0
    err = capsys.readouterr().err.splitlines()
    # the drone motor's 12 runs: too few PWM periods per electrical period at speed, and (20 uH) discontinuous
    # conduction of the square wave's current at the low torque: two causes, one line
    assert len(err) == 1 and "plausibility warnings in 12 runs" in err[0], err
    assert "causes: result.discontinuous_conduction, inverter.f_pwm" in err[0], err
    assert main([*argv, "--verbose"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 + int(err[-1].split()[2])

"""The benchmarks' bldclab side: the shared motulator case runs and its trajectories obey the physics; the table
runner prints one table and survives a missing motulator. motulator itself is not run here (its side takes about
30 s and needs its own Python 3.12 environment: ``python benchmarks/motulator_case.py``)."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import bldclab as bl
from bldclab.control.sine import fundamental_k1
from conftest import require_tool

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("motulator_case_bench", ROOT / "benchmarks" / "motulator_case.py")
mc = importlib.util.module_from_spec(_spec)
sys.modules["motulator_case_bench"] = mc
_spec.loader.exec_module(mc)


@pytest.fixture(scope="module")
def case():
    return mc.shared_case()


@pytest.fixture(scope="module")
def run(case):
    return mc.run_bldclab(case)


def test_case_is_htm48v_with_a_sinusoidal_emf_and_sines_own_design(case):
    htm = bl.load("htm-48v")
    drive = mc.shared_drive()
    assert isinstance(drive.motor.emf.shapes[0], bl.Sinusoid)
    assert case.psi_f == pytest.approx(htm.motor.k_phi / htm.motor.p)  # 40 mV s: k_1 = p psi_f = 0.32 V s/rad
    assert fundamental_k1(drive) == pytest.approx(case.n_p * case.psi_f)
    assert (case.R_s, case.L, case.u_dc, case.f_pwm) == (htm.motor.R, htm.motor.L, 48.0, 14e3)
    assert (case.J, case.B, case.tau_c) == (htm.mechanics.J, htm.mechanics.B, htm.mechanics.tau_c)
    assert (case.k_p, case.k_i) == bl.Sine().gains(drive)
    # what motulator is given: tracking bandwidth 1 kHz, integral bandwidth R / L (the cancelled pole)
    assert case.k_p / case.L == pytest.approx(2 * math.pi * 1000.0)
    assert case.k_i / case.k_p == pytest.approx(case.R_s / case.L)
    # the speed controller's torque limit is the torque of the current limit
    assert case.tau_max == pytest.approx(1.5 * case.n_p * case.psi_f * case.i_s_max)
    assert case.i_s_max == pytest.approx(2 / math.sqrt(3) * htm.motor.I_N)
    # the motulator subprocess receives the case as JSON
    assert mc.Case(**json.loads(json.dumps(dataclasses.asdict(case)))) == case


def test_trajectories_are_on_the_common_grid(case, run):
    sig, _ = run
    assert set(sig) >= {"t", "w_M", "i_d", "i_q", "tau_M", "w_M_fbk", "i_q_ref"}
    assert all(v.shape == (case.n_samples,) for v in sig.values())
    assert np.allclose(sig["t"], np.arange(case.n_samples) * case.T_s, rtol=0, atol=1e-12)
    assert all(np.all(np.isfinite(v)) for v in sig.values())


def test_sinusoidal_mode_takes_over_at_the_first_hall_speed(run):
    _, t_handoff = run
    assert 0.0 < t_handoff < 0.03  # two Hall edges: pi/3 electrical from just before an edge at ~550 rad/s^2


def test_speed_reaches_and_holds_the_reference(case, run):
    sig, _ = run
    t, w = sig["t"], sig["w_M"]
    assert abs(w[-1] - case.w_M_ref) < 0.01
    assert np.max(np.abs(w[t >= mc.SETTLED] - case.w_M_ref)) < 0.5
    # 1DOF PI with its zero at omega_b / 4 after a saturated ramp: about 12 % overshoot, then a slow approach
    # from above without undershoot (the zero dominates)
    k = int(np.argmax(w))
    assert case.w_M_ref < w[k] < 1.15 * case.w_M_ref
    assert np.min(w[k:]) > case.w_M_ref - 0.01


def test_torque_is_the_q_current_times_the_flux(case, run):
    sig, _ = run
    # sinusoidal back-EMF, L_d = L_q: only i_q makes torque, tau = 1.5 p psi_f i_q at every instant
    expected = 1.5 * case.n_p * case.psi_f * sig["i_q"]
    assert np.max(np.abs(sig["tau_M"] - expected)) < 1e-9 * case.tau_max


def test_momentum_balance(case, run):
    sig, _ = run
    t, w = sig["t"], sig["w_M"]
    sel = t >= 0.03  # moving: sign(w) = 1
    assert np.all(w[sel] > 0)
    # J (w1 - w0) = integral of tau_e - B w - tau_c (exact torque means per sample; speed by trapezoids)
    drive_torque = np.sum(sig["tau_mean"][sel][:-1]) * case.T_s
    friction = np.trapezoid(case.B * w[sel] + case.tau_c, t[sel])
    assert case.J * (w[sel][-1] - w[sel][0]) == pytest.approx(drive_torque - friction, abs=1e-5)


def test_ramp_runs_at_the_current_limit_with_the_pi_ramp_lag(case, run):
    sig, t_handoff = run
    t = sig["t"]
    ramp = (t >= t_handoff + 0.005) & (t < 0.08)
    assert np.all(sig["i_q_ref"][ramp] == pytest.approx(case.i_s_max, rel=1e-6))  # the speed PI is at its limit
    assert np.sqrt(np.mean(sig["i_d"][ramp] ** 2)) < 0.2
    # no back-EMF feed-forward: the q integrator follows a back-EMF ramp p psi_f dw/dt, so the current lags by
    # p psi_f a / k_i (0.55 A)
    a = np.polyfit(t[ramp], sig["w_M"][ramp], 1)[0]
    assert a == pytest.approx((case.tau_max - case.tau_c - case.B * 30) / case.J, rel=0.03)
    lag = case.i_s_max - np.mean(sig["i_q"][ramp])
    assert lag == pytest.approx(case.n_p * case.psi_f * a / case.k_i, rel=0.05)


def test_steady_torque_is_the_friction(case, run):
    sig, _ = run
    t, w = sig["t"], sig["w_M"]
    sel = t >= 0.8
    dwdt = (w[sel][-1] - w[sel][0]) / (t[sel][-1] - t[sel][0])
    expected = case.B * np.mean(w[sel]) + case.tau_c + case.J * dwdt
    assert np.mean(sig["tau_mean"][sel]) == pytest.approx(expected, abs=2e-4)


def test_agreement_of_a_run_with_itself_is_exact(case, run):
    sig, t_handoff = run
    checks = mc.agreement(case, sig, sig, t_handoff)
    assert checks and all(ch.ok and ch.value == 0.0 for ch in checks)


def test_agreement_flags_a_settled_speed_offset(case, run):
    sig, t_handoff = run
    other = dict(sig)
    other["w_M"] = sig["w_M"] + np.where(sig["t"] >= mc.SETTLED, 0.2, 0.0)
    bad = [ch.name for ch in mc.agreement(case, sig, other, t_handoff) if not ch.ok]
    assert bad == [f"max |dw|, t >= {mc.SETTLED:g} s"]


def test_run_all_exit_code_is_1_when_a_row_misses_its_target(capsys):
    ra = _load("run_all")
    ok, miss = ra.Row("a", "1", target="<= 2", ok="yes"), ra.Row("b", "3", "x", "<= 2", "NO")
    assert ra.exit_code([ok, ra.Row("c", "skipped")], failed=False, allow_miss=False) == 0
    assert ra.exit_code([ok, miss], failed=False, allow_miss=False) == 1
    assert "1 row(s) missed their target" in capsys.readouterr().err
    assert ra.exit_code([ok, miss], failed=False, allow_miss=True) == 0
    assert "b: 3 x, target <= 2" in capsys.readouterr().err  # still listed
    assert ra.exit_code([ok], failed=True, allow_miss=True) == 1  # a failed measurement is never allowed


def _load(name):
    spec = importlib.util.spec_from_file_location(f"{name}_bench", ROOT / "benchmarks" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
def test_run_all_prints_one_table_and_survives_a_missing_motulator(tmp_path):
    cmd = [sys.executable, str(ROOT / "benchmarks" / "run_all.py"),
           "--skip", "sine,sweep,memory,compare,effmap,cli,firmware,cost",
           "--seconds", "0.05", "--repeats", "1", "--python", str(tmp_path / "no-python"), "--motulator-venv",
           str(tmp_path / "venv"), "--out", str(tmp_path / "out")]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=300)
    missed = [line for line in proc.stdout.splitlines() if "  NO  " in line]
    # a row that misses its target is an error (exit 1), named on stderr; a missing motulator is not
    assert proc.returncode == (1 if missed else 0), proc.stderr
    for line in missed:
        assert line.split("  ")[0].strip() in proc.stderr
    lines = proc.stdout.splitlines()
    head = [j for j, line in enumerate(lines) if line.startswith("benchmark ")]
    assert len(head) == 1  # one table
    body = "\n".join(lines[head[0]:])
    assert "plant: htm-48v six-step 14 kHz, no trace" in body
    assert "plant: htm-48v six-step 14 kHz, trace" in body
    assert "shared case: bldclab" in body
    motulator = [line for line in lines if line.startswith("shared case: motulator")]
    assert len(motulator) == 1 and "not available" in motulator[0] and "Python >= 3.12" in motulator[0]
    assert not (tmp_path / "venv").exists()


@pytest.mark.slow
def test_versus_builds_two_revisions_apart_and_counts_the_same_instructions_for_the_same_sources(tmp_path):
    if subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True).returncode != 0:
        pytest.skip("not a git checkout")
    require_tool("valgrind")
    before = subprocess.run(["git", "status", "--porcelain"], cwd=ROOT, capture_output=True, text=True).stdout
    cmd = [sys.executable, str(ROOT / "benchmarks" / "versus.py"), "HEAD", "--new", "HEAD", "--repeats", "1",
           "--short", "0.02", "--long", "0.06", "--instructions", "--count-seconds", "0.01"]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "old: HEAD = " in proc.stdout and "new: HEAD' = " in proc.stdout  # two builds, told apart
    lines = [line for line in proc.stdout.splitlines() if line.startswith(("sixstep ", "sine "))]
    assert len(lines) == 4, proc.stdout  # the timing table, then the instruction table
    timed, rows = lines[:2], {line.split()[0]: line.split() for line in lines[2:]}
    for r in timed:  # each build timed in its own processes (wall times too short here to compare)
        _, wa, wb, ratio, *_ = r.split()
        assert math.isfinite(float(wa)) and math.isfinite(float(wb)), r
    # the same sources built twice: exactly the same instructions and calls (the last table's rows)
    for name in ("sixstep", "sine"):
        _, a, b, ratio, ca, cb = rows[name]
        assert a == b and ratio == "1.000" and ca == cb, rows[name]
        assert int(a.replace(",", "")) > 100_000
    assert subprocess.run(["git", "status", "--porcelain"], cwd=ROOT, capture_output=True,
                          text=True).stdout == before  # nothing written into the working tree


def test_versus_keeps_the_two_builds_apart_even_with_one_label(monkeypatch, tmp_path):
    vs = _load("versus")
    old = vs.Side("old", "HEAD", "a", tmp_path / "a")
    new = vs.Side("new", "HEAD", "b", tmp_path / "b")
    calls = []

    def child(side, args, valgrind=None):
        calls.append(side.key)
        k = {"old": 1.0, "new": 2.0}[side.key] * (1 + 0.1 * len(calls))  # later processes slower
        return {"bldclab": "x", "sine": {"wall": 0.01 * k, "cpu": 0.009 * k}}

    monkeypatch.setattr(vs, "_child", child)
    best = vs.time_sides([old, new], ["sine"], 3, 0.1, 1.1)
    assert calls == ["old", "new", "new", "old", "old", "new"]  # alternating, A B B A A B
    assert best["old"]["sine"]["wall"] == pytest.approx(0.011) and best["new"]["sine"]["wall"] == pytest.approx(0.024)
    assert best["new"]["sine"]["cpu"] == pytest.approx(0.009 * 2 * 1.2)  # the best of its three processes


def _cli_startup():
    spec = importlib.util.spec_from_file_location("cli_startup_bench", ROOT / "benchmarks" / "cli_startup.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["cli_startup_bench"] = mod
    spec.loader.exec_module(mod)
    return mod


def test_cli_startup_cuts_a_run_into_its_phases():
    cs = _cli_startup()
    events = {"spawn": 0.0, "start": 0.02, "imports": 0.3, "sims_start": 0.31, "sims_end": 0.5, "outputs_end": 1.5,
              "files_end": 1.6, "exit": 1.65}
    phases = cs.phases_of(events)
    assert list(phases) == [name for name, _, _ in cs.PHASES]
    assert math.isclose(sum(phases.values()), 1.65)
    del events["sims_start"]  # a phase whose timestamps are missing is left out
    assert "set-up" not in cs.phases_of(events) and "simulations" not in cs.phases_of(events)


@pytest.mark.slow
def test_cli_startup_prints_both_tables(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "cli_startup.py"), "--repeats", "1"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    for command in ("bldclab --help", "bldclab drives", "bldclab check htm-48v",
                    "bldclab template --force --out motor.toml", "bldclab analyze htm-48v"):
        assert any(line.startswith(command + " ") for line in out.splitlines()), command
    for phase in ("imports", "simulations", "figures, report", "exit", "wall"):
        assert any(line.startswith(phase + " ") for line in out.splitlines()), phase
    assert "effmap --workers 2" in out and "compare --workers 1" in out and "ms forked" in out

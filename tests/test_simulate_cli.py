"""``bldclab simulate``: options checked before the run, memory refused up front, decoded flags, rpm, profiles."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import bldclab as bl
from bldclab.cli import main


@pytest.mark.parametrize("argv, option, words", [
    (["--plot"], "--plot", "--out"),
    (["--plot", "--no-trace", "--out", "OUT"], "--plot", "--no-trace"),
    (["--load", "3 N m"], "--load", "--mechanics"),
    (["--mechanics", "--speed", "300 rpm"], "--speed", "--mechanics"),
    (["--mechanics", "--periods", "4"], "--periods", "--duration"),
    (["--periods", "0"], "--periods", "positive"),
    (["--duration", "0 s"], "--duration", "positive"),
    (["--trace-every", "0"], "--trace-every", ">= 1"),
    (["--duration", "1000 s"], "--duration", "--trace-every"),
    (["--speed", "0 s: 100 rpm, 1 s: 0 rpm"], "--speed", "--mechanics"),
    (["--speed", "0 s: 100 rpm, 1 s 3 rpm"], "--speed", "point 2"),
    (["--mechanics", "--load", "0.1 s: 3 V"], "--load", "torque"),
    (["--speed-ref", "300 rpm"], "--speed-ref", "--mechanics"),
    (["--control", "sine", "--mechanics", "--speed-ref", "0 s: 3 N m"], "--speed-ref", "speed"),
    (["--control", "sine", "--mechanics", "--speed-ref", "300 rpm", "--torque", "3 N m"], "--speed-ref", "drop"),
])
def test_option_errors_name_the_option_and_come_before_the_run(argv, option, words, tmp_path, capsys, monkeypatch):
    def no_run(*a, **k):
        raise AssertionError("simulate ran")

    monkeypatch.setattr("bldclab.cli.simulate.simulate", no_run)
    argv = [str(tmp_path / "o") if a == "OUT" else a for a in argv]
    assert main(["simulate", "htm-48v", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"bldclab: error: {option}") and words in err[0], err
    assert not (tmp_path / "o").exists()


def test_an_unusable_out_is_refused_before_the_run(tmp_path, capsys, monkeypatch):
    """Issue 23, item 2: --out an existing file (or below one) fails at once, as compare and effmap do."""
    def no_run(*a, **k):
        raise AssertionError("simulate ran")

    monkeypatch.setattr("bldclab.cli.simulate.simulate", no_run)
    existing = tmp_path / "existing"
    existing.write_text("keep")
    for out in (existing, existing / "below"):
        assert main(["simulate", "htm-48v", "--duration", "200 s", "--no-trace", "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("bldclab: error: --out:") and "is not a directory" in err[0], err
    assert existing.read_text() == "keep"


def test_long_run_refusal_states_the_bytes(capsys):
    assert main(["simulate", "htm-48v", "--duration", "1000 s"]) == 2
    err = capsys.readouterr().err
    # 1000 s at 14 kHz, 4 rows per sample, one row of doubles per trace field
    rows = 1000 * 2 * bl.load("htm-48v").inverter.f_pwm * 4
    assert f"{rows:.0f} rows" in err and "GB" in err and "--no-trace" in err


def test_table_shows_rpm_and_decoded_flags(capsys):
    assert main(["simulate", "htm-48v", "--speed", "300 rpm", "--periods", "3"]) == 0
    out = capsys.readouterr().out
    lines = {ln.split()[0]: ln.split()[1:] for ln in out.splitlines()[1:]}
    assert float(lines["speed_rpm"][0]) == pytest.approx(300, rel=1e-4)
    assert float(lines["speed_rad_s"][0]) == pytest.approx(10 * math.pi, rel=1e-4)
    assert lines["flags"][:2] == ["SATURATED", "in"]  # current-regulated six-step at rated current: in the window


def test_profiles_and_thinned_trace(tmp_path, capsys):
    """A load step with rotor dynamics, trace every 5 samples, written and plotted; the flags in JSON are names."""
    out = tmp_path / "o"
    rc = main(["simulate", "htm-48v", "--mechanics", "--load", "0 s: 0 N m, 0.05 s: 0 N m, 0.05 s: 5 N m",
               "--duration", "0.1 s", "--trace-every", "5", "--out", str(out), "--plot", "--format", "json"])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out.split("\nwrote")[0])
    assert isinstance(summary["controller_flags"], str) and summary["duration_s"] == 0.1
    n = 0.1 * 2 * bl.load("htm-48v").inverter.f_pwm
    assert summary["trace_rows"] == round(n) // 5
    res = bl.SimResult.load(out / "result.npz")
    assert res.meta["scenario"]["load_torque"].startswith("profile 0 s: 0")
    assert "ctrl_flags" in (out / "trace.csv").read_text().splitlines()[0].split(",")
    assert (out / "waveforms.svg").stat().st_size > 10_000


def test_no_trace_writes_no_trace_file(tmp_path, capsys):
    out = tmp_path / "o"
    assert main(["simulate", "htm-48v", "--periods", "2", "--no-trace", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "result.npz"]
    assert "trace_rows                   0" in capsys.readouterr().out


@pytest.mark.filterwarnings("ignore:scenario.window")
def test_speed_ref_profile_drives_the_speed_loop(capsys):
    """A ramp to 300 rpm through the sine controller's speed loop: the window's mean speed is near the reference
    (the 5 Hz loop still settles: 10 % band), far from the 0 rpm a torque reference of 0 would give."""
    rc = main(["simulate", "htm-48v", "--control", "sine", "--mechanics", "--speed-ref",
               "0 s: 0 rpm, 0.1 s: 300 rpm", "--duration", "0.3 s", "--no-trace", "--format", "json"])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["speed_rpm"] == pytest.approx(300, rel=0.1)


def test_progress_line_on_request(capsys):
    assert main(["simulate", "htm-48v", "--periods", "2", "--no-trace", "--progress"]) == 0
    err = capsys.readouterr().err
    assert err.startswith("\rsimulating") and "100.0 %" in err and err.endswith("s elapsed)\n")


@pytest.mark.slow
def test_flags_say_when_they_were_raised(tmp_path, capsys):
    """Issue 23, item 5: a flag inside the metric window is a finding (share of the window's samples, first and last
    time); one raised only at start-up says so. Terminal, JSON and the plot's title."""
    assert main(["simulate", "htm-48v", "--control", "sine", "--torque", "10 N m"]) == 0
    lines = {ln.split()[0]: ln.split(None, 1)[1] for ln in capsys.readouterr().out.splitlines()[1:]}
    assert lines["flags"].startswith("at start-up only (before the window): SATURATED (")
    out = tmp_path / "o"
    assert main(["simulate", "htm-48v", "--format", "json", "--out", str(out), "--plot"]) == 0
    summary = json.loads(capsys.readouterr().out.split("\nwrote")[0])
    win = summary["flags"]["SATURATED"]["window"]  # predictive six-step at rated current: full voltage at commutation
    assert win["first"] >= summary["window_s"][0] and win["last"] <= summary["window_s"][1]
    assert summary["flags_summary"] == (f"SATURATED in {100 * win['share']:.3g} % of the window's samples "
                                        f"({win['first']:.4g}-{win['last']:.4g} s)")
    res = bl.SimResult.load(out / "result.npz")
    assert summary["flags_summary"] in " ".join(res.plot().get_suptitle().split())


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:scenario.window")
def test_speed_ref_is_the_reference_shown_and_drawn(tmp_path, capsys):
    """Issue 23, item 6: with --speed-ref the heading and the title name the speed reference (the torque reference
    is the loop's limit), and the speed panel draws it."""
    out = tmp_path / "o"
    rc = main(["simulate", "htm-48v", "--control", "sine", "--mechanics", "--speed-ref", "0 s: 0 rpm, 0.1 s: 300 rpm",
               "--duration", "0.3 s", "--trace-every", "4", "--out", str(out), "--plot"])
    assert rc == 0
    heading = capsys.readouterr().out.splitlines()[0]
    assert "speed reference 0 s: 0 rpm, 0.1 s: 300 rpm (final 31.42 rad/s = 300 rpm = " in heading
    assert "pu; speed loop; torque up to 33.69 N m)" in heading
    assert "reference 33.69" not in heading
    res = bl.SimResult.load(out / "result.npz")
    fig = res.plot()
    assert "speed reference 0 s: 0 rpm, 0.1 s: 300 rpm" in " ".join(fig.get_suptitle().split())
    ref = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_label() == "speed reference"]
    assert len(ref) == 1
    t_ms, w = ref[0].get_data()
    assert w[0] == 0.0 and w[-1] == pytest.approx(300 * math.pi / 30, rel=1e-5) and t_ms[-1] == pytest.approx(300, 0.01)


def test_a_long_drive_name_keeps_the_title_inside_the_figure():
    """Issue 23, item 7: the title wraps instead of running off both edges."""
    drive = bl.load("htm-48v").replace(name="a very long drive name for a 2207 drone motor, 1950 KV, 14 poles, on 24 V")
    res = bl.simulate(drive, bl.SixStep(), bl.Scenario(duration=0.02, speed="0.5 pu", ref=50.0, window=(0.01, 0.02)))
    fig = res.plot()
    fig.canvas.draw()
    box = fig._suptitle.get_window_extent()
    assert box.x0 >= 0 and box.x1 <= fig.bbox.x1
    assert fig.get_suptitle().count("\n") >= 1


def test_six_step_settings_reach_the_controller(tmp_path, capsys):
    """Issue 23, item 14: --regulation, --timed, --timing, --timing-time, --commutation set SixStep's fields."""
    out = tmp_path / "o"
    assert main(["simulate", "htm-48v", "--regulation", "duty", "--timed", "--timing", "15 deg", "--timing-time",
                 "20 us", "--commutation", "encoder", "--no-trace", "--out", str(out)]) == 0
    heading = capsys.readouterr().out.splitlines()[0]
    assert "reference 0.5 duty" in heading  # without a current loop the reference is the duty (default 0.5)
    ctl = bl.SimResult.load(out / "result.npz").meta["control"]
    assert (ctl["regulation"], ctl["timed"], ctl["commutation"]) == ("duty", True, "encoder")
    assert ctl["timing"] == pytest.approx(math.radians(15)) and ctl["timing_time"] == pytest.approx(20e-6)


def test_timing_advance_raises_the_drone_motors_torque_at_full_duty(capsys):
    """At 35,000 rpm (1.5 PWM periods per commutation) and full duty, 15 deg of advance gives more torque."""
    drone = str(Path(__file__).resolve().parent / "data" / "drone-2207.toml")
    torque = {}
    for timing in ("0 deg", "15 deg"):
        assert main(["simulate", drone, "--speed", "35000 rpm", "--regulation", "duty", "--duty", "1", "--timed",
                     "--timing", timing, "--format", "json", "--no-trace"]) == 0
        torque[timing] = json.loads(capsys.readouterr().out)["tau_mean_N_m"]
    assert torque["15 deg"] > 1.05 * torque["0 deg"] > 0


@pytest.mark.parametrize("argv, option, words", [
    (["--control", "sine", "--timed"], "--timed", "--control square"),
    (["--control", "sixv", "--timing", "10 deg"], "--timing", "--control square"),
    (["--timing", "40 deg"], "--timing", "30 deg"),
    (["--timing", "15 V"], "--timing", "not a unit of angle"),
    (["--timing-time", "-2 us"], "--timing-time", ""),
    (["--regulation", "duty", "--current", "10 A"], "--current", "duty"),
])
def test_six_step_settings_are_checked_before_the_run(argv, option, words, capsys, monkeypatch):
    def no_run(*a, **k):
        raise AssertionError("simulate ran")

    monkeypatch.setattr("bldclab.cli.simulate.simulate", no_run)
    assert main(["simulate", "htm-48v", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"bldclab: error: {option}") and words in err[0], err


def _strict_json(text: str) -> dict:
    def refuse(name: str) -> None:
        raise ValueError(f"not standard JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def test_json_output_is_standard_json_when_a_quantity_is_undefined(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """Duty 0.05 at 0.2 Omega_0: the bus (1.1 W) and the shaft (2.3 W, the dynamometer covering the friction the
    weak torque does not) both feed the machine, so the efficiency is undefined. Python's json wrote it as NaN, which
    jq and JavaScript refuse; it must be null, on stdout and in metrics.json."""
    rc = main(["simulate", "htm-48v", "--control", "sixv", "--duty", "0.05", "--speed", "0.2 pu", "--periods", "2",
               "--no-trace", "--format", "json", "--out", str(tmp_path / "o")])
    assert rc == 0
    out = _strict_json(capsys.readouterr().out)
    assert out["p_dc_W"] > 0 and out["p_shaft_W"] < 0 and out["power_flow"] == "dissipating"
    assert out["efficiency"] is None
    saved = _strict_json((tmp_path / "o" / "metrics.json").read_text())
    assert saved["efficiency"] is None and saved["metrics"]["efficiency"] is None


def test_a_long_run_off_a_terminal_says_how_long_once(capsys: pytest.CaptureFixture[str]) -> None:
    """`--duration "1e6 s"` in a log or CI ran silently for hours (the progress line is for terminals): one note on
    stderr with the extrapolated wall time, not repeated."""
    from bldclab.cli.simulate import _Progress

    prog = _Progress(False, 1e6)
    prog.start -= 10.0  # 10 s for the first 1/1000: 1e4 s, 2.8 h
    prog(1, 1000)
    prog(2, 1000)
    err = capsys.readouterr().err
    assert err.count("bldclab: note:") == 1
    assert "1e+06 s to simulate will take about 2.8 h" in err and "--progress" in err
    quick = _Progress(False, 1.0)
    quick(1, 1000)  # a run of milliseconds: nothing
    assert capsys.readouterr().err == ""

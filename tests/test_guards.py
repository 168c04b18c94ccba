"""Plausibility guards (bldclab.plausibility): nonsense runs fail or warn with their cause; normal runs stay quiet."""

from __future__ import annotations

import dataclasses
import math
import pickle
import warnings

import numpy as np
import pytest

import bldclab as bl
from bldclab.analysis import paper2
from bldclab.analysis.compare import compare
from bldclab.analysis.experiments import electrical_period, steady_state
from bldclab.cli import main
from bldclab.errors import BldclabError, PlausibilityError, PlausibilityWarning
from bldclab.sim import plausibility

HTM = bl.load("htm-48v")
LU = bl.load("lu-4kw")
RPM = 2 * math.pi / 60


def _imposed(drive, speed, ref, periods=6, **kw):
    Te = electrical_period(drive, speed)
    return bl.Scenario(duration=periods * Te, speed=speed, ref=ref, window=((periods - 2) * Te, periods * Te), **kw)


# ---------------------------------------------------------------------------------------------------------------
# the cases of the issue, through the API


def test_pwm_far_too_slow_for_l_over_r_is_an_error():
    drive = HTM.replace(inverter__f_pwm=16.0)
    with pytest.raises(PlausibilityError, match=r"inverter\.f_pwm: the PWM period .* 41\.7 times .* L/R") as exc:
        bl.simulate(drive, bl.SixStep(), _imposed(drive, 0.5 * drive.Omega_0, drive.motor.I_N))
    assert exc.value.field == "inverter.f_pwm"


def test_pwm_too_slow_with_check_warn_runs_and_names_the_broken_energy_balance():
    drive = HTM.replace(inverter__f_pwm=16.0, inverter__i_trip=0.0)
    with pytest.warns(PlausibilityWarning) as rec:
        res = bl.simulate(drive, bl.SixStep(), _imposed(drive, 0.5 * drive.Omega_0, drive.motor.I_N), check="warn")
    texts = [str(w.message) for w in rec]
    assert any(t.startswith("inverter.f_pwm") for t in texts)
    assert abs(res.metrics.balance_electrical) > plausibility.BALANCE_ERROR  # the nonsense the guard stops
    assert any(t.startswith("result.energy_balance") and "[error ignored" in t for t in texts)
    assert res.meta["warnings"] == texts  # the result carries what it warned


def test_check_off_is_silent_and_bad_check_value_rejected():
    drive = HTM.replace(inverter__f_pwm=16.0)
    sc = _imposed(drive, 0.5 * drive.Omega_0, drive.motor.I_N)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        res = bl.simulate(drive, bl.SixStep(), sc, check="off")
    assert res.meta["warnings"] == []
    with pytest.raises(BldclabError, match="check"):
        bl.simulate(HTM, bl.SixStep(), sc, check="maybe")


def test_speed_four_times_no_load_warns_and_diode_currents_beyond_the_trip_are_an_error():
    sc = _imposed(HTM, 300.0, HTM.motor.I_N)
    with pytest.warns(PlausibilityWarning, match=r"scenario\.speed: 300 rad/s .* 4 times the no-load speed"), \
            pytest.raises(PlausibilityError, match=r"result\.currents: .* hardware trip i_trip = 150 A"):
        bl.simulate(HTM, bl.SixStep(), sc)


def test_absurd_speed_is_an_error():
    sc = _imposed(HTM, 1e9 * RPM, HTM.motor.I_N)
    with pytest.raises(PlausibilityError, match=r"scenario\.speed: .* times the no-load speed") as exc:
        bl.simulate(HTM, bl.SixStep(), sc)
    assert exc.value.field == "scenario.speed"


def test_few_pwm_periods_per_electrical_period_warn():
    speed = 0.9 * LU.Omega_0  # 107 Hz electrical; 1 kHz PWM gives 9.3 periods
    drive = LU.replace(inverter__f_pwm=1000.0)
    with pytest.warns(PlausibilityWarning, match=r"inverter\.f_pwm: f_pwm = 1000 Hz gives 9\.3\d* PWM periods"):
        bl.simulate(drive, bl.SixStepVoltage("high"), _imposed(drive, speed, 0.5), check="warn")


@pytest.mark.parametrize(("ref", "level"), [(5000.0, "error"), (150.0, "warning")])
def test_current_reference_beyond_the_limit(ref, level):
    sc = _imposed(HTM, 0.5 * HTM.Omega_0, ref)
    pattern = rf"scenario\.ref: the current reference {ref:g} A is .* i_max = 100 A"
    if level == "error":
        with pytest.raises(PlausibilityError, match=pattern):
            bl.simulate(HTM, bl.SixStep(), sc)
    else:
        with pytest.warns(PlausibilityWarning, match=pattern):
            bl.simulate(HTM, bl.SixStep(), sc)


def test_torque_reference_beyond_peak_torque_is_an_error():
    sc = _imposed(LU, 0.5 * LU.Omega_0, 50 * LU.T_N)
    with pytest.raises(PlausibilityError, match=r"scenario\.ref: the torque reference"):
        bl.simulate(LU, bl.Lu(), sc)


def test_metric_window_in_the_run_up_warns():
    sc = bl.Scenario(duration=0.1, ref=HTM.motor.I_N, window=(0.05, 0.1))
    with pytest.warns(PlausibilityWarning, match=r"scenario\.window: the speed changes by .* run-up") as rec:
        res = bl.simulate(HTM, bl.SixStep(), sc)
    assert len(res.meta["warnings"]) == len(rec)


def test_steady_window_of_a_settled_run_is_quiet():
    sc = bl.Scenario(duration=0.5, ref=HTM.motor.I_N, window=(0.4, 0.5))
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        bl.simulate(HTM, bl.SixStep(), sc)


# ---------------------------------------------------------------------------------------------------------------
# the result checks as pure functions


@pytest.fixture(scope="module")
def normal_result():
    _, res = steady_state(HTM, bl.SixStep(), 0.5 * HTM.Omega_0, HTM.motor.I_N, trace=True)
    return res


def _with_metrics(res, **changes):
    return bl.SimResult(res.signals, res.units, res.docs, dataclasses.replace(res.metrics, **changes), res.meta)


def test_normal_result_has_no_finding(normal_result):
    assert abs(normal_result.metrics.balance_electrical) < 1e-7
    assert plausibility.check_result(HTM, normal_result) == []


@pytest.mark.parametrize(("residue", "level"), [(3e-4, "warning"), (0.05, "error"), (-0.13, "error")])
def test_energy_residue_graded(normal_result, residue, level):
    (f,) = plausibility.check_result(HTM, _with_metrics(normal_result, balance_electrical=residue))
    assert (f.level, f.cause) == (level, "result.energy_balance")
    assert f"{residue:.3g}" in f.message


def test_non_finite_values_are_an_error(normal_result):
    (f,) = plausibility.check_result(HTM, _with_metrics(normal_result, tau_mean=math.nan))
    assert (f.level, f.cause) == ("error", "result.finite")
    assert "tau_mean = nan" in f.message
    signals = dict(normal_result.signals, i_a=np.where(np.arange(len(normal_result)) == 5, 1e308 * 10, 0.0))
    bad = bl.SimResult(signals, normal_result.units, normal_result.docs, normal_result.metrics, normal_result.meta)
    (f,) = plausibility.check_result(HTM, bad)
    assert "i_a at t =" in f.message


def test_runner_row_summary_is_what_the_signals_give(monkeypatch):
    """The C runner's summary of the trace rows (peaks, finiteness) equals numpy's scan of the signals."""
    seen = []
    check = plausibility.check_result

    def spy(drive, res, rows=None):
        seen.append((res, rows))
        return check(drive, res, rows)

    monkeypatch.setattr(plausibility, "check_result", spy)
    sc = bl.Scenario(duration=0.02, omega_ref=30.0, trace=True)  # rotor dynamics: omega_m's peak is read too
    bl.simulate(HTM, bl.Sine(speed_loop=True), sc)
    ((res, rows),) = seen
    assert rows is not None and not rows.nonfinite and len(res) > 100
    assert rows.peak == tuple(float(np.max(np.abs(res[n]))) for n in ("i_a", "i_b", "i_c", "omega_m"))
    assert rows.peak[0] > 0.0 and rows.peak[3] > 0.0


def test_row_summary_gives_the_findings_of_the_scan(normal_result):
    signals = dict(normal_result.signals, i_a=np.where(np.arange(len(normal_result)) == 5, np.inf, 0.0))
    bad = bl.SimResult(signals, normal_result.units, normal_result.docs, normal_result.metrics, normal_result.meta)
    peak = tuple(float(np.max(np.abs(normal_result[n]))) for n in ("i_a", "i_b", "i_c", "omega_m"))
    assert plausibility.check_result(HTM, normal_result, plausibility.RowSummary(peak, False)) == []
    # a summary that saw a non-finite row defers to the scan, which names the signal and the instant
    (f,) = plausibility.check_result(HTM, bad, plausibility.RowSummary(peak, True))
    assert (f.cause, "i_a at t =" in f.message) == ("result.finite", True)
    # huge peaks from the summary reach the current check as the scanned ones do
    drive = HTM.replace(inverter__i_trip=0.0)
    (f,) = plausibility.check_result(drive, normal_result, plausibility.RowSummary((1e35, 0.0, 0.0, 0.0), False))
    assert (f.level, f.cause) == ("error", "result.currents")


def test_currents_without_hardware_trip_beyond_100_in_are_an_error(normal_result):
    drive = HTM.replace(inverter__i_trip=0.0)
    (f,) = plausibility.check_result(drive, _with_metrics(normal_result, i_peak=(1e35, 0.0, 0.0)))
    assert (f.level, f.cause) == ("error", "result.currents")


def test_plausibility_error_survives_pickling():
    err = PlausibilityError("scenario.speed", "too fast")
    back = pickle.loads(pickle.dumps(err))
    assert isinstance(back, PlausibilityError) and str(back) == str(err) and back.field == "scenario.speed"


def test_collect_and_summary():
    with plausibility.collect() as caught:
        warnings.warn("a", PlausibilityWarning, stacklevel=1)
        warnings.warn("b", PlausibilityWarning, stacklevel=1)
    assert caught == ["a", "b"]
    assert plausibility.summary(caught, 7) == "2 plausibility warnings in 7 runs; first: a"
    assert plausibility.summary([], 7) is None
    # identical messages count once, the causes are named (issue 23, item 1)
    same = "square at 0.8 p.u.: inverter.f_pwm: f_pwm = 48 kHz gives 11 PWM periods"
    msgs = [same, "sine at 0.9 p.u., averaged inverter: result.energy_balance: residue 2e-4", same, same]
    assert plausibility.summary(msgs, "4 points") == (
        "2 plausibility warnings in 4 points (2 repeats counted once); causes: inverter.f_pwm, result.energy_balance; "
        f"first: {same}")


# ---------------------------------------------------------------------------------------------------------------
# no crying wolf: normal runs of both catalog drives


@pytest.mark.parametrize("drive", [HTM, LU], ids=["htm-48v", "lu-4kw"])
def test_normal_runs_raise_no_plausibility_warning(drive):
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        for w in (0.05, 0.5, 0.98):
            for ctl, ref in ((bl.SixStep(), drive.motor.I_N), (bl.Sine(handoff_speed=0.02 * drive.Omega_0),
                                                              drive.T_N), (bl.Lu(), drive.T_N)):
                _, res = steady_state(drive, ctl, w * drive.Omega_0, ref)
                assert res.meta["warnings"] == []


@pytest.mark.parametrize("drive", [HTM, pytest.param(LU, marks=pytest.mark.slow)], ids=["htm-48v", "lu-4kw"])
def test_compare_and_torque_control_raise_no_plausibility_warning(drive):
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        res = compare(drive, [0.1, 0.6, 0.95], workers=1)
        assert res.warnings == []
        paper2.compare_methods(drive, [0.5 * drive.T_N, drive.T_N], [0.5 * drive.motor.Omega_nominal], ["rect", "lu"])


def test_compare_collects_warnings_into_one():
    with pytest.warns(PlausibilityWarning, match=r"^2 plausibility warnings in 4 runs; cause: scenario\.speed; first: "
                      r"square at 1\.2 p\.u\."):
        res = compare(HTM, [0.5, 1.2], workers=1)
    assert len(res.warnings) == 2 and all("no-load speed" in t for t in res.warnings)


# ---------------------------------------------------------------------------------------------------------------
# command line: one line each, exit 2 on errors, nothing written


@pytest.fixture(scope="module")
def slow_pwm_file(tmp_path_factory):
    text = (bl.catalog.load("htm-48v").to_toml().replace("f_pwm = 14000.0", "f_pwm = 16.0"))
    assert "f_pwm = 16.0" in text
    path = tmp_path_factory.mktemp("guards") / "slow-pwm.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(("args", "cause"), [
    (["{slow}"], "inverter.f_pwm"),
    (["htm-48v", "--speed", "300"], "scenario.speed"),  # 4 Omega_0 leads: "...; the run then failed: result.currents"
    (["htm-48v", "--speed", "1e9 rpm"], "scenario.speed"),
    (["htm-48v", "--current", "5000 A"], "scenario.ref"),
])
def test_cli_nonsense_exits_2_with_the_cause_and_writes_nothing(args, cause, slow_pwm_file, tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["simulate", *[a.format(slow=slow_pwm_file) for a in args], "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    errors = [line for line in err.splitlines() if line.startswith("bldclab: error:")]
    assert len(errors) == 1 and f"bldclab: error: {cause}:" in errors[0]
    assert all(line.startswith(("bldclab: error:", "bldclab: warning:")) for line in err.splitlines())
    assert not out.exists()


def test_cli_warning_is_one_line_and_run_completes(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["simulate", "htm-48v", "--mechanics", "--duration", "0.1 s", "--out", str(out)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("bldclab: warning: scenario.window: the speed changes by")
    assert (out / "metrics.json").exists()
    assert "scenario.window" in (out / "metrics.json").read_text()


def test_cli_normal_simulate_is_quiet(capsys):
    assert main(["simulate", "lu-4kw", "--control", "lu", "--speed", "0.9 pu"]) == 0
    assert capsys.readouterr().err == ""


def test_frictionless_drive_at_no_load_is_not_refused_for_its_mechanical_balance():
    """A gimbal-like motor (12 V, 5 Ohm, sinusoidal, no friction, no load) at full six-step duty settles where every
    net shaft energy term of the window is ~1e-6 J; the round-off residue (~4e-7 W) divided by that read as a
    residue of 0.26 and the run was refused as unresolved. Against the shaft's gross flow (rms torque times speed,
    ~0.35 W) it is ~1e-6. The settled speed is six-step's on a sinusoid (docs/motor-files.md, "What KV means"):
    above Omega_0, below pi/3 Omega_0 where the mean of the conducting line's back-EMF equals the bus."""
    motor = bl.Motor.from_ratings(poles=14, R_ll="10 Ohm", L_ll="2 mH", KV="100 rpm/V", shape="sinusoid",
                                  V_N=12.0, I_N=0.5)
    drive = bl.Drive(motor=motor, inverter=bl.Inverter(V_dc=12.0, f_pwm=20e3), mechanics=bl.Mechanics(J=2e-5))
    res = bl.simulate(drive, bl.SixStepVoltage("high"), bl.Scenario(duration=2.0, ref=1.0, window=(1.0, 2.0)))
    m = res.metrics
    assert abs(m.balance_mechanical) < 1e-4
    assert abs(m.p_emf) < 1e-3 * m.tau_std * m.omega_mean  # the net terms really are tiny: the case of the fix
    assert 1.0 < m.omega_mean / drive.Omega_0 < math.pi / 3


def test_residue_of_a_run_where_almost_nothing_flows_is_not_graded():
    """Six-step at zero duty at half speed: the back-EMF stays below the bus, milliamps flow, the bus delivers
    -5e-5 W; a round-off of 2.5e-8 W is 5e-4 of that flow and was warned as an unresolved integration. It is 1e-11
    of the rated power V_dc I_N = 2400 W, below BALANCE_FLOOR: no finding. The same relative residue on a flow of
    the drive's size is still graded (test_energy_residue_graded)."""
    om = 0.5 * HTM.Omega_0
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        res = bl.simulate(HTM, bl.SixStepVoltage("high"), _imposed(HTM, om, 0.0))
    m = res.metrics
    assert abs(m.p_src_total) < 1e-3 and max(m.i_rms) < 0.01  # the case: almost nothing flows
    assert plausibility.check_result(HTM, res) == []
    small = plausibility.check_result(HTM.replace(motor__I_N=1e-6), res)  # a rating that small: graded again
    assert [f.level for f in small if f.cause == "result.energy_balance"] == ["warning"]


def test_frictionless_motor_at_its_no_load_speed_gives_no_balance_warning():
    """A 12 V, 5 Ohm gimbal motor without friction on the sinusoidal speed loop asked for 2 Omega_0 settles at
    Omega_0 (the modulator's limit V_dc / sqrt(3) = k_1 Omega_0) drawing 4.5 mW; its residue of 1.6e-6 W (3.7e-4 of
    that) was warned as an unresolved integration. It is 2.7e-7 of the rated 6 W: below BALANCE_FLOOR."""
    motor = bl.Motor.from_ratings(poles=14, R_ll="10 Ohm", L_ll="2 mH", KV="100 rpm/V", shape="sinusoid",
                                  V_N=12.0, I_N=0.5)
    drive = bl.Drive(motor=motor, inverter=bl.Inverter(V_dc=12.0, f_pwm=20e3), mechanics=bl.Mechanics(J=2e-5))
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        res = bl.simulate(drive, bl.Sine(speed_loop=True),
                          bl.Scenario(duration=0.5, ref=0.0, omega_ref=2 * drive.Omega_0, window=(0.25, 0.5),
                                      trace=False))
    m = res.metrics
    assert m.omega_mean == pytest.approx(drive.Omega_0, rel=2e-3)
    assert m.p_src_total < 0.01


def test_rotor_driven_far_beyond_no_load_speed_by_the_load_names_the_load():
    # servo-2k2 with rotor dynamics and a load of 100 T_N: the load spins the rotor backwards to tens of times
    # Omega_0 within 0.05 s; the cause is the load, not the PWM frequency the rotor's speed then outruns
    drive = bl.load("servo-2k2")
    sc = bl.Scenario(duration=0.05, ref=drive.T_N, load_torque=100 * drive.T_N, window=(0.025, 0.05))
    with pytest.raises(PlausibilityError, match=r"scenario\.load_torque: the rotor reached .* times the no-load "
                                                r"speed") as exc:
        bl.simulate(drive, bl.Sine(), sc)
    assert exc.value.field == "scenario.load_torque"


def test_rotor_driven_somewhat_beyond_no_load_speed_warns():
    # 3 T_N against the sinusoidal controller's 1.05 T_N: the rotor runs backwards past Omega_0, a warning
    drive = bl.load("servo-2k2")
    sc = bl.Scenario(duration=0.3, ref=drive.T_N, load_torque=3 * drive.T_N, window=(0.25, 0.3))
    with pytest.warns(PlausibilityWarning, match=r"scenario\.load_torque: the rotor reached"):
        bl.simulate(drive, bl.Sine(), sc, check="warn")


# ---------------------------------------------------------------------------------------------------------------
# currents of a drive without a current loop against its rating; the hardware trip named


def _warned(drive: bl.Drive, control: bl.Control, sc: bl.Scenario) -> tuple[bl.SimResult, list[str]]:
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always", PlausibilityWarning)
        res = bl.simulate(drive, control, sc)
    return res, [str(w.message) for w in rec]


def test_full_duty_at_stall_warns_of_the_current_rating_and_a_fraction_of_it_does_not(capsys):
    """Full duty, rotor held (1 rpm): only 2 (R + R_on) limits the pair current, V_dc / (2 (R + R_on)) = 522 A on
    f60prov-2550kv (10 I_N; it has no hardware trip), reached to 1e-3 within the window and named
    `result.current_rating` with the multiple of I_N; at a duty whose stall current d V_dc / (2 R) is I_N nothing is
    said. The CLI prints the warning."""
    drive = bl.load("f60prov-2550kv")
    m = drive.motor
    i_stall = drive.inverter.V_dc / (2.0 * (m.R + drive.inverter.R_on))
    assert drive.inverter.i_trip == 0 and i_stall > 2 * m.I_N
    sc = bl.Scenario(duration=0.02, speed=2 * math.pi / 60, window=(0.015, 0.02), trace=False)
    res, caught = _warned(drive, bl.SixStepVoltage(), dataclasses.replace(sc, ref=1.0))
    assert max(res.metrics.i_peak) == pytest.approx(i_stall, rel=1e-3)
    named = [w for w in caught if w.startswith("result.current_rating")]
    assert len(named) == 1 and f"{max(res.metrics.i_peak) / m.I_N:.3g} times the rated current" in named[0]
    assert named[0] in res.meta["warnings"]
    res, caught = _warned(drive, bl.SixStepVoltage(), dataclasses.replace(sc, ref=m.I_N / i_stall))
    assert max(res.metrics.i_peak) < 1.1 * m.I_N
    assert not [w for w in caught if w.startswith("result.")]
    assert main(["simulate", "f60prov-2550kv", "--control", "sixv", "--duty", "1", "--speed", "1 rpm",
                 "--duration", "0.02 s", "--no-trace"]) == 0
    assert "bldclab: warning: result.current_rating: a phase current reached" in capsys.readouterr().err


def test_a_hardware_trip_is_named():
    """htm-48v trips at 150 A: full duty at stall switches every leg off within a millisecond, and the run says so
    (its metrics then describe a drive switched off: zero current), with the trip's time."""
    sc = bl.Scenario(duration=0.005, speed=2 * math.pi / 60, ref=1.0, window=(0.004, 0.005), trace=False)
    res, caught = _warned(HTM, bl.SixStepVoltage(), sc)
    assert res.meta["stats"]["hw_trip"] is not None and max(res.metrics.i_peak) == 0.0
    named = [w for w in caught if w.startswith("result.hardware_trip")]
    assert len(named) == 1 and f"t = {res.meta['stats']['hw_trip']:.4g} s" in named[0]

"""The switching-level plant through the public API: physics checks and the cross-check against the independent
scipy reference model (tests/reference_model.py), open loop."""

from __future__ import annotations

import contextlib
import math

import numpy as np
import pytest

import bldclab as bl
from bldclab.errors import BldclabError, PlausibilityWarning
from reference_model import simulate_reference

HTM = bl.load("htm-48v")
LU = bl.load("lu-4kw")
HTM_NO_TRIP = HTM.replace(inverter__i_trip=0.0)  # circuit tests that drive hundreds of amps on purpose


def six_step_table(drive: bl.Drive, omega: float, theta0: float, n: int, duty: float, chop: str = "high"):
    """Six-step leg commands per sample from the known angle trajectory (sector of the angle at the sample)."""
    t = np.arange(n) / (2 * drive.inverter.f_pwm)
    th = np.mod(theta0 + drive.motor.p * omega * t, 2 * np.pi)
    sector = np.floor(np.mod(th - np.pi / 6, 2 * np.pi) / (np.pi / 3)).astype(int)
    pos = np.array([0, 0, 1, 1, 2, 2])[sector]
    neg = np.array([1, 2, 2, 0, 0, 1])[sector]
    modes = np.zeros((n, 3), dtype=np.int32)
    duties = np.zeros((n, 3))
    rows = np.arange(n)
    modes[rows, pos] = 2
    modes[rows, neg] = 3
    duties[rows, pos] = duty
    duties[rows, neg] = 1.0 if chop == "high" else duty
    return modes, duties


def run_c(drive: bl.Drive, omega: float, modes, duties, theta0: float, h_max: float = 0.0) -> bl.SimResult:
    n = len(modes)
    dur = n / (2 * drive.inverter.f_pwm)
    sc = bl.Scenario(duration=dur, speed=omega, theta0=theta0, delay=0, window=(0.0, dur), h_max=h_max)
    return bl.simulate(drive, bl.OpenLoop(modes, duties), sc)


# ---------------------------------------------------------------------------------------------------------------
# cross-check with the independent reference model

def _cases():
    om = 0.4 * HTM.Omega_0
    m1, d1 = six_step_table(HTM, om, 0.3, 400, 0.55)
    yield "htm six-step high-side", HTM.replace(inverter__R_on=0.003, inverter__V_f=0.8), om, m1, d1, 0.3
    m2, d2 = six_step_table(HTM, 0.15 * HTM.Omega_0, 1.0, 300, 0.2, chop="bipolar")
    yield "htm bipolar, discontinuous", HTM, 0.15 * HTM.Omega_0, m2, d2, 1.0
    # lu-4kw (per-phase measured-style tables), complementary sinusoidal PWM with dead time and real devices
    n = 600
    t = np.arange(n) / (2 * LU.inverter.f_pwm)
    om3 = 0.5 * LU.Omega_0
    th = 0.2 + LU.motor.p * om3 * t
    d3 = 0.5 + 0.42 * np.stack([np.sin(th - x * 2 * np.pi / 3 + 0.3) for x in range(3)], axis=1)
    lu = LU.replace(inverter__t_dead=2e-6, inverter__R_on=0.05, inverter__V_f=1.2, inverter__r_d=0.02,
                    inverter__i_trip=0.0)  # open loop at ~300 A: the reference model has no hardware trip
    yield "lu-4kw complementary + dead time", lu, om3, np.ones((n, 3), dtype=np.int32), d3, 0.2
    # all legs off above the no-load speed: the diodes rectify into the source
    yield ("htm rectifier above no-load speed", HTM.replace(inverter__V_f=0.7, inverter__R_src=0.05),
           1.25 * HTM.Omega_0, np.zeros((400, 3), dtype=np.int32), np.zeros((400, 3)), 0.0)


@pytest.mark.slow  # the reference model is slow on purpose: 2 to 20 s a case
@pytest.mark.parametrize("case", list(_cases()), ids=lambda c: c[0])
def test_c_plant_matches_reference(case):
    name, drive, om, modes, duties, th0 = case
    ref = simulate_reference(drive, om, modes, duties, theta0=th0)
    above = "above no-load" in name  # on purpose: the guards say so
    with pytest.warns(PlausibilityWarning, match="no-load speed") if above else contextlib.nullcontext():
        res = run_c(drive, om, modes, duties, th0)
    i_c = np.stack([res.i_a, res.i_b, res.i_c], axis=1)
    scale = max(np.max(np.abs(ref.i)), 1.0)
    err = np.max(np.abs(i_c - ref.i[: len(i_c)]))
    assert np.max(np.abs(ref.i)) > 1.0, "the case must carry current"
    assert err < 1e-6 * scale, f"currents differ by {err:.3g} A (peak {scale:.3g} A)"
    m = res.metrics
    dur = m.t1 - m.t0
    assert m.tau_mean == pytest.approx(ref.tau_mean, rel=1e-7, abs=1e-9 * drive.T_N)
    for key, mine in (("src", m.p_src), ("cu", m.p_cu), ("emf", m.p_emf), ("diode", m.p_diode), ("sw", m.p_sw),
                      ("Rsrc", m.p_Rsrc)):
        # measured: <= 3e-6 relative (copper energy of short discontinuous pulses at the default step, which the
        # C plant's step halving shows is its quadrature error); currents agree to 3e-8 A
        assert mine * dur == pytest.approx(ref.E[key], rel=1e-5, abs=1e-6 * abs(ref.E["src"]) + 1e-12), key


# ---------------------------------------------------------------------------------------------------------------
# physics


def test_standstill_dc_current_reaches_v_over_2r():
    n = int(2 * HTM.inverter.f_pwm * 30 * HTM.motor.L / HTM.motor.R)  # 30 time constants
    modes = np.tile([2, 3, 0], (n, 1))
    duties = np.tile([1.0, 1.0, 0.0], (n, 1))
    res = run_c(HTM_NO_TRIP, 0.0, modes, duties, 0.4)
    tau = HTM.motor.L / HTM.motor.R
    i_final = HTM.inverter.V_dc / (2 * HTM.motor.R)
    exact = i_final * (1 - np.exp(-res.t / tau))
    assert np.max(np.abs(res.i_a - exact)) < 1e-8 * i_final
    assert res.i_a[-1] == pytest.approx(i_final, rel=1e-10)
    assert np.all(res.i_c == 0.0)


def test_open_circuit_terminal_voltages_follow_back_emf():
    om = 0.7 * LU.Omega_0
    n = 2000
    res = bl.simulate(LU, bl.OpenLoop(np.zeros((n, 3), int), np.zeros((n, 3))),
                      bl.Scenario(duration=n / (2 * LU.inverter.f_pwm), speed=om, delay=0))
    assert np.all(res.i_a == 0) and np.all(res.i_b == 0)
    # the window means of the line voltages equal the window means of the line back-EMF: compare against the
    # shapes themselves, integrated over each window
    th0 = res.theta_e
    dth = LU.motor.p * om / (2 * LU.inverter.f_pwm)
    sub = np.linspace(0, 1, 41)
    k = np.mean([LU.motor.emf.k_abc(th0 + s * dth) for s in sub], axis=0)  # (3, n), mean over each window
    for x, y, vx, vy in ((0, 1, res.v_a, res.v_b), (1, 2, res.v_b, res.v_c)):
        line = vx - vy
        want = om * (k[x] - k[y])
        assert np.max(np.abs(line - want)) < 2e-3 * np.max(np.abs(want))


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_hall_codes_follow_six_step_sequence(direction):
    om = direction * 0.3 * HTM.Omega_0
    res = bl.simulate(HTM, bl.SixStepVoltage(), bl.Scenario(duration=0.1, speed=om, ref=0.0, theta0=0.05))
    codes = res.hall.astype(int)
    changes = codes[np.nonzero(np.diff(codes))[0] + 1]
    seq = [1, 3, 2, 6, 4, 5] if direction > 0 else [5, 4, 6, 2, 3, 1]
    start = seq.index(int(changes[0]))
    expect = [seq[(start + j) % 6] for j in range(len(changes))]
    assert len(changes) >= 12
    assert list(changes) == expect
    # sector angle at each change is the edge angle pi/6 + n pi/3 (to one sample of travel)
    idx = np.nonzero(np.diff(codes))[0] + 1
    th = res.theta_e[idx]
    frac = np.mod(th - np.pi / 6 + 0.5 * np.pi / 3, np.pi / 3) - 0.5 * np.pi / 3
    assert np.max(np.abs(frac)) <= abs(HTM.motor.p * om) / (2 * HTM.inverter.f_pwm) + 1e-9


def _six_step_period_metrics(drive, h_max):
    om = 0.5 * drive.Omega_0
    Te = 2 * np.pi / (drive.motor.p * om)
    sc = bl.Scenario(duration=4 * Te, speed=om, ref=0.6, window=(3 * Te, 4 * Te), h_max=h_max, trace=False)
    return bl.simulate(drive, bl.SixStepVoltage("high"), sc).metrics


def test_energy_balance_six_step_with_freewheeling_and_open_phase():
    drive = HTM.replace(inverter__R_on=0.004, inverter__V_f=0.7, inverter__r_d=0.003, inverter__R_src=0.01)
    m = _six_step_period_metrics(drive, 0.0)
    assert m.p_diode > 0 and m.p_sw > 0 and m.p_Rsrc > 0  # freewheeling diodes and switches carried current
    assert abs(m.balance_electrical) < 1e-6  # target of the issue: 1e-4


def test_halving_the_step_changes_mean_torque_below_1e_4_pu():
    th = 0.5 / HTM.inverter.f_pwm
    taus = [_six_step_period_metrics(HTM, h).tau_mean for h in (th, th / 2, th / 4)]
    assert abs(taus[0] - taus[1]) / HTM.T_N < 1e-6
    assert abs(taus[1] - taus[2]) / HTM.T_N < 1e-6


def test_dynamic_mechanics_accelerates_and_balances_energy():
    drive = HTM_NO_TRIP.replace(mechanics__J=0.01)
    sc = bl.Scenario(duration=0.3, ref=0.5, window=(0.0, 0.3))
    with pytest.warns(PlausibilityWarning, match="run-up"):  # the window holds the run-up on purpose
        res = bl.simulate(drive, bl.SixStepVoltage("sync"), sc)
    m = res.metrics
    assert res.omega_m[-1] > 20.0
    assert abs(m.balance_mechanical) < 1e-6
    assert abs(m.balance_electrical) < 1e-6


# ---------------------------------------------------------------------------------------------------------------
# API, results and bad input


def test_result_roundtrip_pandas_plot(tmp_path):
    res = bl.simulate(HTM, bl.SixStepVoltage(), bl.Scenario(duration=0.01, speed=30.0, ref=0.4, window=(0.0, 0.01)))
    p = res.save(tmp_path / "run")
    back = bl.SimResult.load(p)
    assert back.metrics == res.metrics
    np.testing.assert_array_equal(back.i_a, res.i_a)
    df = res.to_pandas()
    assert list(df.columns)[:3] == ["theta_e", "omega_m", "i_a"] and len(df) == len(res)
    fig = res.plot()
    assert len(fig.axes) == 3
    assert "sector" in res.signals and "duty" in res.signals
    assert not list(tmp_path.glob("*.tmp"))


@pytest.mark.parametrize("kw, field", [
    ({"duration": -1.0}, "scenario.duration"),
    ({"duration": math.nan}, "scenario.duration"),
    ({"duration": 0.01, "speed": np.full(5, 30.0)}, "scenario.speed"),
    ({"duration": 0.01, "ref": lambda t: np.where(t > 0.005, np.nan, 0.5)}, "scenario.ref"),
    ({"duration": 0.01, "window": (0.0, 0.02)}, "scenario.window"),
    ({"duration": 0.01, "delay": 2}, "scenario.delay"),
    ({"duration": 0.01, "trace_every": 0}, "scenario.trace_every"),
])
def test_bad_scenarios_name_the_field(kw, field):
    with pytest.raises(BldclabError) as exc:
        bl.simulate(HTM, bl.SixStepVoltage(), bl.Scenario(**kw))
    assert exc.value.field == field


def test_bad_open_loop_commands_rejected():
    with pytest.raises(BldclabError, match="duties"):
        bl.OpenLoop(np.ones((3, 3), int), np.full((3, 3), 1.5))
    with pytest.raises(BldclabError, match="modes"):
        bl.OpenLoop(np.full((3, 3), 7), np.zeros((3, 3)))


def test_profiles_arrays_and_functions_agree():
    n = bl.sim.samples_of(HTM, 0.01)
    t = np.arange(n) / (2 * HTM.inverter.f_pwm)
    a = bl.simulate(HTM, bl.SixStepVoltage(), bl.Scenario(duration=0.01, speed=20.0 + 100 * t, ref=0.3))
    b = bl.simulate(HTM, bl.SixStepVoltage(), bl.Scenario(duration=0.01, speed=lambda t: 20.0 + 100 * t, ref=0.3))
    np.testing.assert_allclose(a.i_a, b.i_a, rtol=0, atol=1e-9)  # t from arange/(2f) vs arange*T/2: rounding
    assert a.omega_m[-1] == pytest.approx(20.0 + 100 * t[-1])


def test_faults_reach_plant_and_sensors():
    om = 0.4 * HTM.Omega_0
    sc = bl.Scenario(duration=0.05, speed=om, ref=0.6, theta0=0.3,
                     faults=(bl.Fault("phase_open", "b", t_on=0.0105), bl.Fault("hall_stuck", "a", 0.02, value=1)))
    res = bl.simulate(HTM, bl.SixStepVoltage(), sc)
    after = res.t > 0.0105 + 1e-6
    assert np.all(res.i_b[after] == 0.0) and np.any(np.abs(res.i_b[~after]) > 10)
    assert res.meta["stats"]["e_fault"] > 0
    codes = res.hall.astype(int)[res.t > 0.02 + 1e-6]
    assert np.all(codes & 1) and np.any(codes == 7)
    with pytest.raises(BldclabError, match=r"fault\.kind"):
        bl.Fault("melt", "a", 0.0)
    with pytest.raises(BldclabError, match=r"fault\.t_off"):
        bl.Fault("hall_glitch", "a", 0.1, t_off=0.05)


def test_scenario_takes_speeds_in_per_unit_as_the_cli_does() -> None:
    """Scenario(speed="0.5 pu") (issue 23, item 4): per unit of the drive's Omega_0, resolved by simulate."""
    sc = bl.Scenario(duration=0.04, speed="0.5 pu", ref=30.0, window=(0.02, 0.04))
    assert isinstance(sc.speed, bl.sim.PerUnit) and str(sc.speed) == "0.5 pu"
    assert sc.resolved(HTM).speed == pytest.approx(0.5 * HTM.Omega_0)
    res = bl.simulate(HTM, bl.SixStep(), sc)
    assert res.metrics.omega_mean == pytest.approx(0.5 * HTM.Omega_0, rel=1e-9)
    prof = bl.Scenario(duration=0.04, speed="0 s: 100 rpm, 0.01 s: 0.25 pu").resolved(LU).speed
    assert prof.times == (0.0, 0.01)
    assert prof.values == pytest.approx((100 * math.pi / 30, 0.25 * LU.Omega_0), rel=1e-15)
    with pytest.raises(BldclabError) as info:
        bl.Scenario(duration=0.04, speed="0.5 pp")
    assert info.value.field == "scenario.speed"

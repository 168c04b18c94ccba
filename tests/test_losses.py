"""Inverter switching and reverse-recovery losses (issue 14): booking rules against hand calculations, the
per-bucket energy balance, zero-loss defaults, field validation, averaged vs switching inverter."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

import bldclab as bl
from bldclab.cli import main
from bldclab.errors import BldclabError
from bldclab.model.motor import switching_energies

HTM = bl.load("htm-48v").replace(inverter__i_trip=0.0)
# illustrative device data (not a catalog part): energies at 48 V, 50 A
LOSS = {"inverter__E_on": 40e-6, "inverter__E_off": 60e-6, "inverter__E_rr": 10e-6, "inverter__V_test": 48.0,
        "inverter__I_test": 50.0}


def _chop(drive: bl.Drive, duty: float, n: int) -> bl.SimResult:
    """Upper switch of phase a chops at ``duty`` (HIGH), lower switch of b held on, c off; low imposed speed."""
    modes = np.tile(np.array([[2, 3, 0]], dtype=np.int32), (n, 1))
    duties = np.tile(np.array([[duty, 1.0, 0.0]]), (n, 1))
    dur = n / (2 * drive.inverter.f_pwm)
    sc = bl.Scenario(duration=dur, speed=2.0, theta0=0.4, delay=0, window=(0.75 * dur, dur))
    return bl.simulate(drive, bl.OpenLoop(modes, duties), sc)


def test_switching_loss_at_fixed_duty_matches_E_f_pwm():
    """One leg chops at duty d with a nearly constant current i: p_swloss = (E_on + E_off) f_pwm (i/I_test)
    (V/V_test) within 1 %, p_rr = E_rr f_pwm (i/I_test)(V/V_test) within 4 % (the turn-on, and so the recovery,
    falls at the bottom of the current ripple). With the ripple's ends i -/+ di/2, di = (V - 2 R i) d T / (2 L),
    the turn-on at the bottom and the turn-off at the top: within 0.3 %."""
    drive = HTM.replace(**LOSS)
    m = _chop(drive, 0.1, 2400).metrics
    assert m is not None
    inv, mot = drive.inverter, drive.motor
    i = m.i_rms[0]
    assert 30.0 < i < 60.0
    k = inv.f_pwm * (inv.V_dc / inv.V_test) / inv.I_test
    assert m.p_swloss == pytest.approx((inv.E_on + inv.E_off) * k * i, rel=0.01)
    assert m.p_rr == pytest.approx(inv.E_rr * k * i, rel=0.04)
    di = (inv.V_dc - 2 * mot.R * i) * 0.1 / inv.f_pwm / (2 * mot.L)
    i_lo, i_hi = i - di / 2, i + di / 2
    assert m.p_swloss == pytest.approx(k * (inv.E_on * i_lo + inv.E_off * i_hi), rel=3e-3)
    assert m.p_rr == pytest.approx(k * inv.E_rr * i_lo, rel=3e-3)
    assert m.p_src_total == pytest.approx(m.p_src + m.p_swloss + m.p_rr, rel=1e-12)


def test_recovery_only_on_hard_turn_on():
    """Chopping the lower switch of a phase whose current is positive is soft (the switch's own diode carries the
    current in the off time): nothing is booked. Only E_rr set: booked when the chopping leg switches hard."""
    drive = HTM.replace(inverter__E_rr=10e-6, inverter__V_test=48.0, inverter__I_test=50.0)
    hard = _chop(drive, 0.1, 1200).metrics
    assert hard is not None and hard.p_rr > 0.0 and hard.p_swloss == 0.0
    # phase a carries i > 0 (upper held on), phase b's lower switch carries i_b < 0: chopping b low is hard,
    # chopping a's lower switch while a conducts i > 0 is soft
    n = 1200
    modes = np.tile(np.array([[3, 3, 0]], dtype=np.int32), (n, 1))
    duties = np.tile(np.array([[0.5, 1.0, 0.0]]), (n, 1))
    dur = n / (2 * drive.inverter.f_pwm)
    # start with current flowing a -> b (freewheeling decay through a's lower side); the window starts after the
    # first sample: at t = 0 b's lower switch turns on while b's upper diode carries i_b < 0, a hard turn-on that a
    # window from 0 holds ([t0, t1) holds the edges at t0)
    sc = bl.Scenario(duration=dur, speed=2.0, theta0=0.4, delay=0, window=(0.5 / drive.inverter.f_pwm, dur),
                     i0=(40.0, -40.0, 0.0))
    soft = bl.simulate(drive, bl.OpenLoop(modes, duties), sc).metrics
    assert soft is not None and soft.i_rms[0] > 1.0
    assert soft.p_rr == 0.0 and soft.p_swloss == 0.0


def _six_step(drive: bl.Drive, ctl: bl.Control, w_pu: float, ref_pu: float) -> bl.Metrics:
    """Closed loop at an imposed speed (p.u. of Omega_0) and torque reference (p.u. of T_N), last of 4 periods."""
    om = w_pu * drive.Omega_0
    Te = 2 * np.pi / (drive.motor.p * om)
    sc = bl.Scenario(duration=4 * Te, speed=om, ref=ref_pu * drive.T_N, window=(3 * Te, 4 * Te), trace=False)
    m = bl.simulate(drive, ctl, sc).metrics
    assert m is not None
    return m


def test_zero_loss_fields_give_the_old_results_bitwise():
    """Explicit zero switching-loss data changes nothing: every metric equal, bit for bit."""
    zero = HTM.replace(inverter__E_on=0.0, inverter__E_off=0.0, inverter__E_rr=0.0, inverter__V_test=0.0,
                       inverter__I_test=0.0)
    for ctl, ref in ((bl.SixStep(), 0.6), (bl.Sine(), 0.6)):
        a = dataclasses.asdict(_six_step(HTM, ctl, 0.5, ref))
        b = dataclasses.asdict(_six_step(zero, ctl, 0.5, ref))
        assert a == b
        assert a["p_swloss"] == 0.0 and a["p_rr"] == 0.0 and a["p_src_total"] == a["p_src"]


@pytest.mark.parametrize("model", ["switching", "average"])
@pytest.mark.parametrize("ctl_name", ["SixStep", "Sine"])
@pytest.mark.parametrize("w_pu", [0.3, 0.7])
def test_per_bucket_energy_balance(model: str, ctl_name: str, w_pu: float):
    """Source energy (circuit plus booked switching energies) = copper + conduction (switches, diodes, source
    resistance) + switching + recovery + shaft (imposed speed: the dynamometer; no iron loss in the model)
    + stored magnetic energy, over one electrical period, to 1e-4."""
    drive = HTM.replace(inverter__R_on=0.004, inverter__V_f=0.7, inverter__r_d=0.003, inverter__R_src=0.01,
                        inverter__model=model, mechanics__B=1e-4, **LOSS)
    ctl = bl.SixStep() if ctl_name == "SixStep" else bl.Sine()
    m = _six_step(drive, ctl, w_pu, 0.6)
    dt = m.t1 - m.t0
    shaft = m.p_emf + m.p_cog - m.p_fric
    buckets = {"copper": m.p_cu, "conduction": m.p_sw + m.p_diode + m.p_Rsrc, "switching": m.p_swloss,
               "recovery": m.p_rr, "friction": m.p_fric, "shaft": shaft, "stored": m.dW_L / dt}
    assert m.p_swloss > 0.0 and m.p_rr > 0.0
    residue = (m.p_src_total - sum(buckets.values())) / m.p_src_total
    assert abs(residue) < 1e-4, buckets
    assert abs(m.balance_electrical) < 1e-4
    assert m.efficiency == pytest.approx(shaft / m.p_src_total)


def test_averaged_switching_loss_agrees_with_switching_model():
    """The averaged inverter books the period expectation f_pwm (E_on + E_off) |i| v_bus / (V_test I_test) per
    switching leg at the mean current; at one operating point it agrees with the edge-by-edge booking within 3 %.
    E_rr is booked at the turn-on only, at the bottom of the current ripple, which the mean current does not
    see: 10 % (E_on + E_off mixes the ripple's top and bottom, which largely cancel)."""
    drive = HTM.replace(**LOSS)
    sw = _six_step(drive, bl.Sine(), 0.5, 0.6)
    av = _six_step(drive.replace(inverter__model="average"), bl.Sine(), 0.5, 0.6)
    assert av.p_swloss == pytest.approx(sw.p_swloss, rel=0.03)
    assert av.p_rr == pytest.approx(sw.p_rr, rel=0.10)


def test_efficiency_without_losses_is_copper_only():
    """With every inverter loss zero the source feeds only the windings: the efficiency equals the copper-only
    value shaft / (p_emf + p_cu + dW_L/T) (the input the circuit's balance leaves after copper)."""
    m = _six_step(HTM, bl.Sine(), 0.5, 0.6)
    assert m.p_sw == m.p_diode == m.p_Rsrc == m.p_swloss == m.p_rr == 0.0
    dt = m.t1 - m.t0
    shaft = m.p_emf + m.p_cog - m.p_fric
    assert m.efficiency == pytest.approx(shaft / (m.p_emf + m.p_cu + m.dW_L / dt), rel=1e-6)


@pytest.mark.parametrize(("kw", "field"), [
    ({"inverter__E_on": -1e-6}, "E_on"),
    ({"inverter__E_off": math.nan}, "E_off"),
    ({"inverter__E_rr": math.inf}, "E_rr"),
    ({"inverter__E_on": 1e-6, "inverter__I_test": 10.0}, "V_test"),
    ({"inverter__E_rr": 1e-6, "inverter__V_test": 48.0}, "I_test"),
    ({"inverter__V_test": -1.0}, "V_test"),
])
def test_bad_loss_fields_rejected_naming_the_field(kw: dict[str, float], field: str):
    with pytest.raises(BldclabError, match=field):
        HTM.replace(**kw)


def test_motor_file_round_trip_and_units(tmp_path):
    drive = HTM.replace(**LOSS)
    path = tmp_path / "m.toml"
    path.write_text(drive.to_toml())
    text = path.read_text()
    assert "E_on" in text and "I_test" in text
    back = bl.load(path)
    assert back.inverter == drive.inverter
    # zero losses: the keys are not written (files as before)
    assert "E_on" not in HTM.to_toml()
    src = text.replace("E_on = 4e-05", 'E_on = "40 uJ"')
    p2 = tmp_path / "m2.toml"
    p2.write_text(src)
    assert bl.load(p2).inverter.E_on == pytest.approx(40e-6)
    p2.write_text(text.replace("E_on = 4e-05", 'E_on = "-1 mJ"'))
    with pytest.raises(BldclabError, match="E_on"):
        bl.load(p2)


@pytest.mark.parametrize("trace_sub", [1, 4])
def test_trace_powers_integrate_to_the_metrics_with_the_switching_energies(trace_sub):
    """The trace's p_swloss is the gate-edge energies booked inside each row over the row's length, and p_inv
    includes it: summing p dt over the rows of the metric window gives the metrics' switching plus recovery loss and
    inverter loss to rounding, and the rows' p_src + p_swloss - p_cu - p_inv - p_emf sums to the change of magnetic
    energy (the integration's residue)."""
    drive = HTM.replace(inverter__R_on=0.005, inverter__V_f=0.8, inverter__t_dead=5e-7, **LOSS)
    om = 0.5 * drive.Omega_0
    ts = 0.5 / drive.inverter.f_pwm
    k0, k1 = 400, 1000  # window on controller samples: the trace rows tile it
    sc = bl.Scenario(duration=(k1 + 4) * ts, speed=om, ref=0.6 * drive.T_N, window=(k0 * ts, k1 * ts),
                     trace_sub=trace_sub)
    res = bl.simulate(drive, bl.SixStep(reference="torque"), sc)
    m = res.metrics
    assert m is not None and m.p_swloss > 0.5 and m.p_rr > 0.05
    t = res.t
    dt = np.diff(t)
    sel = (t[:-1] >= m.t0 - 1e-12) & (t[:-1] < m.t1 - 1e-12)
    assert dt[sel].sum() == pytest.approx(m.t1 - m.t0, rel=1e-12)
    span = m.t1 - m.t0
    e_sw = float(np.sum(res["p_swloss"][:-1][sel] * dt[sel]))
    assert e_sw == pytest.approx((m.p_swloss + m.p_rr) * span, rel=1e-9)
    e_inv = float(np.sum(res["p_inv"][:-1][sel] * dt[sel]))
    assert e_inv == pytest.approx((m.p_sw + m.p_diode + m.p_Rsrc + m.p_swloss + m.p_rr) * span, rel=1e-9)
    resid = res["p_src"] + res["p_swloss"] - res["p_cu"] - res["p_inv"] - res["p_emf"]
    assert float(np.sum(resid[:-1][sel] * dt[sel])) == pytest.approx(m.dW_L, abs=1e-6 * m.p_src_total * span)
    # impulses: with several rows per sample only the rows holding a gate edge carry energy
    if trace_sub > 1:
        assert np.mean(res["p_swloss"][:-1][sel] == 0.0) > 0.2


def _with_inverter_keys(tmp_path, **keys: str) -> Path:
    """htm-48v's motor file with extra ``[inverter]`` keys (values as written in the file)."""
    text = HTM.to_toml()
    extra = "".join(f"{k} = {v}\n" for k, v in keys.items())
    text = text.replace("[inverter]\n", "[inverter]\n" + extra, 1)
    path = tmp_path / "m.toml"
    path.write_text(text)
    return path


def test_energies_from_rise_and_fall_times_by_hand(tmp_path):
    """``t_rise``, ``t_fall``, ``Q_rr`` instead of energies: E_on = V I t_rise / 2 = 48 V 50 A 20 ns / 2 = 24 uJ,
    E_off = 48 V 50 A 15 ns / 2 = 18 uJ, E_rr = Q_rr V = 100 nC 48 V = 4.8 uJ; V_test, I_test default to the bus
    voltage and the rated current (48 V, 50 A on htm-48v); given, they are used."""
    inv = bl.load(_with_inverter_keys(tmp_path, t_rise='"20 ns"', t_fall='"15 ns"', Q_rr='"100 nC"')).inverter
    assert (inv.V_test, inv.I_test) == (48.0, 50.0)
    assert inv.E_on == pytest.approx(24e-6, rel=1e-12)
    assert inv.E_off == pytest.approx(18e-6, rel=1e-12)
    assert inv.E_rr == pytest.approx(4.8e-6, rel=1e-12)
    inv2 = bl.load(_with_inverter_keys(tmp_path, t_rise="2e-8", V_test='"60 V"', I_test='"30 A"')).inverter
    assert inv2.E_on == pytest.approx(0.5 * 60 * 30 * 20e-9, rel=1e-12) and inv2.E_off == inv2.E_rr == 0.0
    assert (inv2.V_test, inv2.I_test) == (60.0, 30.0)
    assert switching_energies(48.0, 50.0, 20e-9, 15e-9, 100e-9) == pytest.approx((24e-6, 18e-6, 4.8e-6))


def test_switching_loss_from_rise_and_fall_times_at_fixed_duty(tmp_path):
    """The converted energies drive the plant like datasheet energies: one leg chopping at duty 0.1 books
    p_swloss = (E_on + E_off) f_pwm (i/I_test)(V/V_test) within 1 % (as for given energies)."""
    drive = bl.load(_with_inverter_keys(tmp_path, t_rise='"40 ns"', t_fall='"30 ns"', Q_rr='"80 nC"'))
    drive = drive.replace(inverter__i_trip=0.0)
    m = _chop(drive, 0.1, 2400).metrics
    assert m is not None
    inv = drive.inverter
    i = m.i_rms[0]
    k = inv.f_pwm * (inv.V_dc / inv.V_test) / inv.I_test
    expected = 0.5 * 48.0 * 50.0 * (40e-9 + 30e-9) * k * i  # (E_on + E_off) f_pwm (i / I_test), V = V_test
    assert m.p_swloss == pytest.approx(expected, rel=0.01)
    assert m.p_rr == pytest.approx(80e-9 * 48.0 * k * i, rel=0.04)


@pytest.mark.parametrize(("keys", "field"), [
    ({"t_rise": '"20 ns"', "E_on": '"10 uJ"'}, "inverter.t_rise"),
    ({"Q_rr": '"50 nC"', "E_rr": '"1 uJ"'}, "inverter.Q_rr"),
    ({"t_fall": '"-5 ns"'}, "inverter.t_fall"),
    ({"Q_rr": '"5 uH"'}, "inverter.Q_rr"),
    ({"t_rr": '"20 ns"'}, "inverter.t_rr"),
])
def test_rise_fall_times_and_energies_are_exclusive_and_checked(tmp_path, keys, field, capsys):
    path = _with_inverter_keys(tmp_path, **keys)
    with pytest.raises(BldclabError, match=field.replace(".", r"\.")) as exc:
        bl.load(path)
    if "E_on" in keys:
        assert "E_on" in str(exc.value) and "not both" in str(exc.value)
    assert main(["check", str(path)]) == 2
    assert field in capsys.readouterr().err


def test_conduction_losses_at_a_dc_operating_point_by_hand():
    """Locked rotor (no back-EMF), phase a's upper switch chopping at duty d into phase b's lower switch: the DC
    current solves d V = I (2 R + R_on) + d I R_on + (1 - d) (V_f + r_d I) (on: two switches; off: a's lower diode
    and b's switch), and the buckets are p_cu = 2 R I^2, p_sw = (1 + d) R_on I^2, p_diode = (1 - d) (V_f I + r_d I^2).
    The PWM ripple (3.7 A p-p on 84 A here) adds (dI^2/12)/I^2 ~ 1.6e-4 to the squares: 1e-3 tolerance."""
    d, r_on, v_f, r_d = 0.2, 0.004, 0.8, 0.003
    drive = HTM.replace(inverter__R_on=r_on, inverter__V_f=v_f, inverter__r_d=r_d)
    n = 2 * int(0.03 * drive.inverter.f_pwm)  # 30 ms: 25 L/R time constants
    modes = np.tile(np.array([[2, 3, 0]], dtype=np.int32), (n, 1))
    duties = np.tile(np.array([[d, 1.0, 0.0]]), (n, 1))
    dur = n / (2 * drive.inverter.f_pwm)
    m = bl.simulate(drive, bl.OpenLoop(modes, duties),
                    bl.Scenario(duration=dur, speed=0.0, delay=0, window=(0.75 * dur, dur))).metrics
    R, V = drive.motor.R, drive.inverter.V_dc
    i = (d * V - (1 - d) * v_f) / (2 * R + r_on + d * r_on + (1 - d) * r_d)
    assert m.p_cu == pytest.approx(2 * R * i * i, rel=1e-3)
    assert m.p_sw == pytest.approx((1 + d) * r_on * i * i, rel=1e-3)
    assert m.p_diode == pytest.approx((1 - d) * (v_f * i + r_d * i * i), rel=1e-3)

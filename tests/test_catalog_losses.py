"""The catalog drive ``htm-48v-losses`` and the steel-grade route (issue 14, loss data with sources).

Every number of the drive is recomputed here from its sources (the MOSFET datasheet's typical values, the steel
grade's specified losses, paper 1's drive) and the assumptions its file states; the grade's loss separation is
checked against the lamination's own physics and, through the plant, against the grade's specified losses.
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import bldclab as bl
from bldclab import cli
from bldclab.analysis.experiments import steady_state
from bldclab.analysis.losses import point_losses
from bldclab.errors import BldclabError, PlausibilityWarning
from bldclab.model.emf import BackEmf, Sinusoid
from bldclab.model.iron import GRADES, M270_35A, SteelGrade

# onsemi NTB5860NL datasheet, typical at 25 C (the motor file's header)
R_DS_ON = 2.4e-3
V_SD = 0.76
T_R, T_F, T_D_ON, T_D_OFF = 58e-9, 144e-9, 25e-9, 98e-9
Q_RR = 71e-9
V_TEST, I_TEST = 48.0, 100.0
# the file's assumptions
CORE_MASS, B_PEAK = 2.0, 1.4


def test_every_number_follows_its_source() -> None:
    """Paper 1's drive, the datasheet's conversion to energies, R split off the transistors, iron from the grade."""
    base, d = bl.load("htm-48v"), bl.load("htm-48v-losses")
    assert d.name == "htm-48v-losses" and "NTB5860NL" in d.description and "M270-35A" in d.description
    # everything that is not a loss is htm-48v's
    assert d.motor.emf == base.motor.emf and d.mechanics == base.mechanics and d.sensors == base.sensors
    for f in ("p", "L", "V_N", "I_N", "Omega_N", "T_peak"):
        assert getattr(d.motor, f) == getattr(base.motor, f), f
    assert (d.inverter.V_dc, d.inverter.f_pwm, d.inverter.i_trip) == (48.0, 14e3, base.inverter.i_trip)
    # paper 1's R includes two conducting switches
    assert d.motor.R + 2 * d.inverter.R_on == pytest.approx(base.motor.R, rel=1e-12)
    inv = d.inverter
    assert (inv.R_on, inv.V_f, inv.r_d) == (R_DS_ON, V_SD, 0.0)
    assert (inv.V_test, inv.I_test) == (V_TEST, I_TEST)
    assert inv.E_on == pytest.approx(V_TEST * I_TEST * T_R / 2, rel=1e-12)
    assert inv.E_off == pytest.approx(V_TEST * I_TEST * T_F / 2, rel=1e-12)
    assert inv.E_rr == pytest.approx(Q_RR * V_TEST, rel=1e-12)
    assert T_D_OFF + T_F - T_D_ON < inv.t_dead <= 300e-9 + 1e-15
    # the iron fields are the grade's, at the stated mass and flux density, at the rated speed
    want = base.motor.with_iron_from_grade(M270_35A, mass=CORE_MASS, B_peak=B_PEAK)
    assert d.motor.speed_fe_ref == pytest.approx(base.motor.Omega_nominal, rel=1e-12)
    for f in ("P_fe_eddy", "P_fe_hyst", "P_fe_ex"):
        assert getattr(d.motor, f) == pytest.approx(getattr(want, f), rel=1e-12, abs=1e-15), f
    assert d.motor.P_fe_hyst > 0.0 and d.motor.P_fe_eddy > 0.0
    # the ideal drive stays paper 1's idealisation
    assert (base.inverter.R_on, base.inverter.E_on, base.motor.P_fe_hyst) == (0.0, 0.0, 0.0)


def test_grade_separation_reproduces_the_grade_and_the_lamination_physics() -> None:
    """The terms give the grade's 1.0 T and 1.5 T losses at 50 Hz; the eddy term is the thin-sheet classical loss
    written out by hand; the split depends little on the assumed resistivity (+-20 %: under 3 % of the total)."""
    g = M270_35A
    t = g.terms()
    assert GRADES["M270-35A"] is g
    assert t["p_hyst"] + t["p_eddy"] + t["p_ex"] == pytest.approx(1.10, rel=1e-12)
    assert t["p_hyst"] * 1.5 ** t["alpha"] + t["p_eddy"] * 2.25 == pytest.approx(2.70, rel=1e-12)
    # pi^2 (0.35 mm)^2 (50 Hz)^2 (1 T)^2 / (6 x 0.52e-6 Ohm m x 7650 kg/m^3), by hand: 0.12664 W/kg
    hand = 9.8696044 * 1.225e-7 * 2500.0 / (6 * 0.52e-6 * 7650.0)
    assert t["p_eddy"] == pytest.approx(hand, rel=1e-7)
    assert 1.5 < t["alpha"] < 2.5  # the usual range of the hysteresis exponent of silicon steel at 1-1.5 T
    for k in (0.8, 1.2):
        tk = dataclasses.replace(g, resistivity=g.resistivity * k).terms()
        assert abs(tk["p_eddy"] - t["p_eddy"]) / g.P10 < 0.03
        assert tk["p_hyst"] + tk["p_eddy"] == pytest.approx(g.P10, rel=1e-12)


def test_grade_through_the_plant_gives_the_grades_losses() -> None:
    """End to end: a sinusoidal back-EMF at 50 Hz electrical with 1 kg of M270-35A at a peak of 1.0 T, then 1.5 T,
    books the grade's specified 1.10 and 2.70 W/kg in the simulation (the model's flux follows the magnets')."""
    base = bl.load("htm-48v").replace(inverter__i_trip=0.0)
    k1 = 2.0 * base.motor.k_phi / math.sqrt(3.0)
    sine = base.replace(motor__emf=BackEmf.symmetric(Sinusoid(k1)))
    om = 2 * math.pi * 50.0 / sine.motor.p
    for B, P in ((1.0, 1.10), (1.5, 2.70)):
        drive = sine.replace(motor=sine.motor.with_iron_from_grade(M270_35A, mass=1.0, B_peak=B, speed_ref=om))
        assert drive.motor.iron_loss(om) == pytest.approx(P, rel=1e-9)
        Te = 2 * math.pi / (drive.motor.p * om)
        sc = bl.Scenario(duration=3 * Te, speed=om, ref=0.3 * drive.T_N, window=(2 * Te, 3 * Te), trace=False)
        m = bl.simulate(drive, bl.Sine(), sc).metrics
        assert m is not None and m.p_fe == pytest.approx(P, rel=1e-6)


@pytest.mark.parametrize(("kw", "field"), [
    ({"resistivity": 0.05e-6}, "grade.resistivity"),   # the classical term alone exceeds the grade's loss
    ({"P15": 1.2}, "grade.alpha"),                      # 1.5 T hardly above 1.0 T: not a steel's hysteresis
    ({"thickness": float("nan")}, "grade.thickness"),
    ({"density": -7650.0}, "grade.density"),
])
def test_bad_grade_data_rejected_naming_the_field(kw: dict[str, float], field: str) -> None:
    with pytest.raises(BldclabError, match=field.replace(".", r"\.")):
        dataclasses.replace(M270_35A, **kw).terms()


def test_a_user_grade() -> None:
    """Any grade the user describes: a 0.50 mm sheet has four times the classical term per T^2 of a 0.35 mm one
    at the same resistivity and density (d^2)."""
    thick = SteelGrade("M400-50A-like", P10=1.70, P15=4.00, thickness=0.50e-3, density=7650.0,
                       resistivity=0.52e-6, source="illustrative")
    assert thick.p_eddy() / M270_35A.p_eddy() == pytest.approx((0.50 / 0.35) ** 2, rel=1e-12)
    t = thick.terms()
    assert t["p_hyst"] * 1.5 ** t["alpha"] + t["p_eddy"] * 2.25 == pytest.approx(4.00, rel=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("supply", ["square", "sine"])
def test_every_loss_bucket_of_the_real_drive_is_booked_and_balances(supply: str) -> None:
    """At 0.5 Omega_0 and T_N: every bucket (copper, switches, diodes, switching, recovery, iron, friction) is
    positive, the energy balance closes to 1e-4 of the input, and the full-loss efficiency is below the ideal
    drive's copper-only one at the same point."""
    ctl = bl.SixStep() if supply == "square" else bl.Sine()
    real, ideal = bl.load("htm-48v-losses"), bl.load("htm-48v")
    w = 0.5 * real.Omega_0
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        m = steady_state(real, ctl, w, real.T_N)[1].metrics
        m0 = steady_state(ideal, ctl, w, ideal.T_N)[1].metrics
    assert m is not None and m0 is not None
    acc = point_losses(m)
    for b in ("p_cu", "p_sw", "p_diode", "p_swloss", "p_rr", "p_fe", "p_fric"):
        assert acc[b] > 0.0, b
    assert abs(acc["residue"]) < 1e-4 * acc["p_in"], acc
    assert acc["efficiency"] < point_losses(m0)["efficiency"]


@pytest.mark.slow
def test_synchronous_chopping_removes_the_square_waves_diode_loss() -> None:
    """PWM-on-PWM chopping freewheels through a body diode in every off-time: at I_N and 0.2 Omega_0 the diode
    loss is about V_f I_N (1 - d); synchronous chopping leaves only the dead times (under a tenth of it), and the
    square wave's efficiency rises; the torque is the same."""
    d = bl.load("htm-48v-losses")
    w = 0.2 * d.Omega_0
    pt, sim = steady_state(d, bl.SixStep(), w, d.motor.I_N)
    pt_s, sim_s = steady_state(d, bl.SixStep(chopping="sync"), w, d.motor.I_N)
    assert sim.metrics is not None and sim_s.metrics is not None
    a, b = point_losses(sim.metrics), point_losses(sim_s.metrics)
    assert 0.3 * d.inverter.V_f * d.motor.I_N < a["p_diode"] < d.inverter.V_f * d.motor.I_N
    assert b["p_diode"] < 0.1 * a["p_diode"]
    assert b["efficiency"] > a["efficiency"] + 0.01
    assert pt_s.tau_mean_pu == pytest.approx(pt.tau_mean_pu, abs=0.01)


IRON_FILE = """\
[motor]
p = 8
R = "45.2 mOhm"
L = "75 uH"
V_N = "48 V"
I_N = "50 A"
Omega_N = "640 rpm"
{extra_motor}
[motor.emf]
kind = "trapezoid"
k_phi = "0.32 V s/rad"

[motor.iron]
{iron}

[inverter]
V_dc = "48 V"
f_pwm = "14 kHz"
"""
DATA = ('P10 = "1.10 W/kg"\nP15 = "2.70 W/kg"\nthickness = "0.35 mm"\ndensity = "7.65 kg/dm^3"\n'
        'resistivity = "0.52 uOhm m"\nmass = "2 kg"\nB_peak = "1.4 T"')


def _iron_file(tmp_path: Path, iron: str, extra_motor: str = "") -> Path:
    f = tmp_path / "iron.toml"
    f.write_text(IRON_FILE.format(iron=iron, extra_motor=extra_motor))
    return f


def test_motor_iron_table_by_name_and_by_data(tmp_path: Path) -> None:
    """``[motor.iron]`` with the built-in grade's name and with the same grade's data give the same drive; it is
    written back as the P_fe_* powers, which load to the same drive."""
    by_name = bl.load(_iron_file(tmp_path, 'grade = "M270-35A"\nmass = "2 kg"\nB_peak = "1.4 T"'))
    by_data = bl.load(_iron_file(tmp_path, DATA))
    assert by_name.motor.P_fe_hyst > 0.0 and by_name == by_data
    back = tmp_path / "back.toml"
    back.write_text(by_name.to_toml())
    assert "[motor.iron]" not in back.read_text() and bl.load(back) == by_name


@pytest.mark.parametrize(("iron", "extra", "field"), [
    (DATA.replace('"2.70 W/kg"', '"1.2 W/kg"'), "", "motor.iron.P15"),
    (DATA.replace('"0.52 uOhm m"', '"0.02 uOhm m"'), "", "motor.iron.resistivity"),
    (DATA.replace('"2 kg"', '"-2 kg"'), "", "motor.iron.mass"),
    (DATA.replace('"1.4 T"', '"1.4 V"'), "", "motor.iron.B_peak"),
    (DATA.replace('thickness = "0.35 mm"\n', ""), "", "motor.iron.thickness"),
    ('grade = "M270-35A"\n' + DATA, "", "motor.iron.P10"),
    ('grade = "M999-35A"\nmass = "2 kg"\nB_peak = "1.4 T"', "", "motor.iron.grade"),
    ('grade = "M270-35A"\nmass = "2 kg"\nB_peak = "1.4 T"\nB_pk = "1 T"', "", "motor.iron.B_pk"),
    ('grade = "M270-35A"\nmass = "2 kg"\nB_peak = "1.4 T"', "P_fe_hyst = 1.0", "motor.P_fe_hyst"),
])
def test_bad_motor_iron_table_exits_2_naming_the_field(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                        iron: str, extra: str, field: str) -> None:
    f = _iron_file(tmp_path, iron, extra)
    assert cli.main(["check", str(f)]) == 2
    err = capsys.readouterr().err
    assert f"{field}:" in err and err.count("\n") == 1, err


@given(P10=st.floats(0.3, 10.0), ratio=st.floats(1.0, 4.0), d_mm=st.floats(0.05, 1.0),
       density=st.floats(6500.0, 8200.0), rho_uohm=st.floats(0.1, 1.0))
@settings(max_examples=300, deadline=None)
def test_any_grade_either_reproduces_its_losses_or_names_the_field(P10: float, ratio: float, d_mm: float,
                                                                     density: float, rho_uohm: float) -> None:
    """Grades drawn at random: the separation reproduces both specified losses with finite, non-negative terms,
    or it is one error naming the grade field at fault; never a NaN."""
    g = SteelGrade("random", P10=P10, P15=P10 * ratio, thickness=d_mm * 1e-3, density=density,
                   resistivity=rho_uohm * 1e-6)
    try:
        t = g.terms()
    except BldclabError as exc:
        assert exc.field in ("grade.resistivity", "grade.alpha")
        return
    assert all(math.isfinite(v) and v >= 0.0 for v in t.values())
    assert 1.0 <= t["alpha"] <= 3.0
    assert t["p_hyst"] + t["p_eddy"] == pytest.approx(P10, rel=1e-9)
    assert t["p_hyst"] * 1.5 ** t["alpha"] + 2.25 * t["p_eddy"] == pytest.approx(P10 * ratio, rel=1e-9)


@pytest.mark.slow
def test_compare_chopping_runs_the_square_wave_so_and_says_so(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    """``compare --chopping sync``: the square wave's diode loss falls, the sinusoidal rows are unchanged, and the
    manifest (its controllers and the command that reproduces the run) says which chopping ran."""
    def run(*extra: str) -> tuple[pd.DataFrame, dict[str, Any]]:
        out = tmp_path / ("sync" if extra else "default")
        argv = ["compare", "htm-48v-losses", "--speeds", "2", "--min-speed", "0.2", "--max-speed", "0.5",
                "--workers", "1", "--no-report", "--out", str(out), *extra]
        assert cli.main(argv) == 0
        capsys.readouterr()
        return pd.read_csv(out / "efficiency.csv"), json.loads((out / "manifest.json").read_text())

    e0, m0 = run()
    e1, m1 = run("--chopping", "sync", "--pwm-phases", "2", "--inverter", "switching")
    sq0, sq1 = e0[e0.supply == "square"], e1[e1.supply == "square"]
    assert sq1.p_diode.sum() < 0.2 * sq0.p_diode.sum()
    assert (sq1.eta_sim_full.to_numpy() > sq0.eta_sim_full.to_numpy()).all()
    assert m0["supplies"]["square"]["settings"]["chopping"] == "pwm-on-pwm"
    assert m1["supplies"]["square"]["settings"]["chopping"] == "sync"
    assert "--chopping" not in str(m0["command"])
    assert str(m1["command"]).endswith("--pwm-phases 2 --chopping sync --inverter switching")


@pytest.mark.slow
def test_inverter_losses_of_the_real_drive_by_hand() -> None:
    """Six-step at I_N and 0.5 Omega_0 on the datasheet inverter, by hand: the pair needs ``2 R I + 2 k_phi w``;
    on-time two switches (``V_dc - 2 R_on I``), off-time one switch and the freewheeling body diode
    (``-V_f - R_on I``), so ``d`` from the average; conduction ``R_on I^2 (1 + d)``, diode ``V_f I (1 - d)``,
    switching ``(E_on + E_off) (I / I_test) f_pwm`` for the one chopping switch. Within 3 % (commutations and
    the PWM ripple are left out of the hand count)."""
    dr = bl.load("htm-48v-losses")
    inv, i_n = dr.inverter, dr.motor.I_N
    w = 0.5 * dr.Omega_0
    need = 2 * dr.motor.R * i_n + 2 * dr.motor.k_phi * w
    on, off = inv.V_dc - 2 * inv.R_on * i_n, -inv.V_f - inv.R_on * i_n
    d = (need - off) / (on - off)
    m = steady_state(dr, bl.SixStep(), w, i_n)[1].metrics
    assert m is not None
    assert m.p_sw == pytest.approx(inv.R_on * i_n**2 * (1 + d), rel=0.03)
    assert m.p_diode == pytest.approx(inv.V_f * i_n * (1 - d), rel=0.03)
    assert m.p_swloss == pytest.approx((inv.E_on + inv.E_off) * i_n / inv.I_test * inv.f_pwm, rel=0.03)

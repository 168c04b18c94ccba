"""The averaged-inverter plant (Inverter.model = "average", docs/plant.md "Averaged inverter").

Checked against physics, not against numbers: the energy balance closes with every loss present; the switching
plant converges to the averaged one as the PWM frequency rises (mean torque, PWM ripple, switch and diode losses);
at low speed the averaged plant meets paper 1's closed forms with the instantaneous torque, which the switching
plant cannot (its PWM ripple adds to it).
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import bldclab as bl
from bldclab.analysis.compare import default_controls
from bldclab.analysis.experiments import PointResult, steady_state
from bldclab.cli import main
from bldclab.errors import BldclabError
from bldclab.model import analytic as an

DRIVES = ("htm-48v", "lu-4kw")
SUPPLIES = ("square", "sine")
LOSSY = {"inverter__R_on": 0.01, "inverter__V_f": 0.8, "inverter__r_d": 0.005}


def run(drive: bl.Drive, supply: str, w: float, model: str, f_pwm: float | None = None) -> PointResult:
    """Steady state of paper 1's supply ``supply`` at ``w`` p.u. of Omega_0 with the inverter model ``model``."""
    changes: dict[str, object] = {"inverter__model": model}
    if f_pwm is not None:
        changes["inverter__f_pwm"] = f_pwm
    d = drive.replace(**changes)
    control, ref = default_controls(d)[supply]
    pt, _ = steady_state(d, control, w * d.Omega_0, ref)
    return pt


# ---------------------------------------------------------------------------------------------------------------
# energy


@pytest.mark.parametrize("supply", SUPPLIES)
@pytest.mark.parametrize("name", DRIVES)
def test_energy_balance_closes_with_every_loss(name, supply):
    """Switch, diode, source-resistance losses and dead time present: the averaged sources and loss terms are one
    circuit, so the electrical balance closes to the integration accuracy."""
    drive = bl.load(name).replace(inverter__R_src=0.02, inverter__t_dead=5e-7, **LOSSY)
    pt = run(drive, supply, 0.5, "average")
    m = pt.metrics
    assert abs(m.balance_electrical) < 1e-6
    assert m.p_sw > 0 and m.p_Rsrc > 0
    if supply == "square":
        assert m.p_diode > 0  # freewheeling in the chopper's off fraction


@pytest.mark.parametrize("supply", SUPPLIES)
@pytest.mark.parametrize("name", DRIVES)
def test_losses_converge_to_the_switching_ones(name, supply):
    """The averaged switch, diode and source-resistance losses are the switching plant's in the limit (the
    pulsed DC current's R_src loss too: the averaged plant uses the overlap of the legs' intervals)."""
    drive = bl.load(name).replace(inverter__R_src=0.02, **LOSSY)
    sw, av = (run(drive, supply, 0.5, model, 80e3).metrics for model in ("switching", "average"))
    assert av.p_sw == pytest.approx(sw.p_sw, rel=0.005)
    assert av.p_diode == pytest.approx(sw.p_diode, rel=0.005, abs=1e-9)
    assert av.p_Rsrc == pytest.approx(sw.p_Rsrc, rel=0.005)
    # not the mean current's loss: R_src mean(i_dc)^2 is far below R_src mean(i_dc^2)
    assert av.p_Rsrc > 1.2 * 0.02 * (av.p_src / drive.inverter.V_dc) ** 2


# ---------------------------------------------------------------------------------------------------------------
# convergence with the PWM frequency

F_PWM = (10e3, 20e3, 40e3, 80e3)


@pytest.mark.parametrize("w", [0.2, 0.8])
@pytest.mark.parametrize("supply", SUPPLIES)
@pytest.mark.parametrize("name", DRIVES)
def test_switching_converges_to_average_with_pwm_frequency(name, supply, w):
    drive = bl.load(name)
    dT, dTR = [], []
    for f in F_PWM:
        sw, av = (run(drive, supply, w, model, f) for model in ("switching", "average"))
        dT.append(abs(sw.tau_mean_pu - av.tau_mean_pu))
        dTR.append(sw.ripple_pu - av.ripple_pu)
        assert sw.ripple_pu > av.ripple_pu - 0.01  # the switching torque carries the PWM ripple on top
    # mean torque: falls roughly as 1/f_pwm or faster (least-squares slope; mostly about 1/f_pwm^2, lu-4kw square
    # at 0.8 p.u. is -0.99 because its 10 -> 20 kHz step does not fall) and vanishes
    slope = np.polyfit(np.log(F_PWM), np.log(dT), 1)[0]
    assert slope < -0.9, dT
    assert dT[-1] < dT[0] / 5 and dT[-1] < 1e-5  # 1/f_pwm: / 8; lu-4kw square 0.8 p.u.: / 6.6
    # the PWM ripple of the instantaneous torque: about 1/f_pwm
    assert dTR[-1] < dTR[0] / 4, dTR


def test_discontinuous_conduction_pulses_vanish_as_1_over_f_pwm():
    """At no load (duty = back-EMF / V_dc) the chopped phase conducts in pulses that die within each PWM period.
    The averaged plant takes them as an open phase (no torque); the switching plant's torque from them falls as
    1/f_pwm toward it."""
    drive = bl.load("htm-48v")
    om = 0.5 * drive.Omega_0
    duty = 2 * drive.motor.k_phi * om / drive.inverter.V_dc
    tau = {}
    for model in ("switching", "average"):
        for f in (20e3, 80e3):
            d = drive.replace(inverter__model=model, inverter__f_pwm=f)
            sc = bl.Scenario(duration=0.03, speed=om, ref=duty, window=(0.01, 0.03))
            m = bl.simulate(d, bl.SixStepVoltage("high"), sc).metrics
            assert abs(m.balance_electrical) < 1e-5
            tau[model, f] = m.tau_mean
    assert abs(tau["average", 20e3]) < 0.01 and abs(tau["average", 80e3]) < 0.01
    assert tau["switching", 20e3] > 0.5  # 1.4 N m of pulses at 20 kHz
    ratio = tau["switching", 20e3] / tau["switching", 80e3]
    assert 3.0 < ratio < 5.0, ratio


# ---------------------------------------------------------------------------------------------------------------
# paper 1's closed forms (R = 0)

HTM0 = bl.load("htm-48v").replace(motor__R=0.0)
TH = an.theta_m(HTM0)


@pytest.mark.parametrize("supply, w", [("square", 0.05), ("square", 0.2), ("square", 0.45), ("sine", 0.05),
                                       ("sine", 0.3)])
def test_low_speed_meets_paper1_with_the_instantaneous_torque(supply, w):
    """(26)-(29) / (13), (15): mean torque within 0.005 p.u.; ripple read from tau_max - tau_min (no PWM ripple in
    the averaged plant) within 0.02 p.u., and closer than the switching plant's instantaneous ripple."""
    if supply == "square":
        T, TR = an.t_q_pu(w, TH), an.tr_q_pu(w, TH)
    else:
        T, TR = an.t_s_pu(w, TH), an.tr_s_pu(w, TH)
    sw, av = (run(HTM0, supply, w, model) for model in ("switching", "average"))
    assert av.tau_mean_pu == pytest.approx(T, abs=0.005)
    assert abs(av.tau_mean_pu - T) <= abs(sw.tau_mean_pu - T) + 1e-4
    assert av.ripple_pu == pytest.approx(TR, abs=0.02)
    assert abs(av.ripple_pu - TR) < abs(sw.ripple_pu - TR)


# ---------------------------------------------------------------------------------------------------------------
# the model's mechanics: fewer steps, same events, the trip


def test_no_gate_edges_inside_a_half_period():
    """About one step per half period (plus back-EMF corners and Hall edges) instead of one per gate edge."""
    drive = bl.load("htm-48v")
    stats = {}
    for model in ("switching", "average"):
        d = drive.replace(inverter__model=model)
        sc = bl.Scenario(duration=0.02, speed=0.5 * d.Omega_0, ref=d.motor.I_N)
        stats[model] = bl.simulate(d, bl.SixStep(), sc).meta["stats"]
    halves = 0.02 * 2 * drive.inverter.f_pwm
    assert stats["average"]["steps"] < 1.1 * halves
    assert stats["switching"]["steps"] > 1.8 * halves


def test_hardware_trip_as_in_the_switching_model():
    """An open-loop duty far above the rated current trips the inverter; the diodes then carry the currents to zero
    in both models."""
    drive = bl.load("htm-48v").replace(inverter__i_trip=80.0)
    res = {}
    for model in ("switching", "average"):
        d = drive.replace(inverter__model=model)
        sc = bl.Scenario(duration=0.01, speed=0.1 * d.Omega_0, ref=0.6)
        res[model] = bl.simulate(d, bl.SixStepVoltage("high"), sc)
    for r in res.values():
        assert r.meta["stats"]["hw_trip"] is not None
        assert max(abs(float(r[f"i_{x}"][-1])) for x in "abc") == 0.0
    t_sw, t_av = (r.meta["stats"]["hw_trip"] for r in res.values())
    assert t_av == pytest.approx(t_sw, abs=2.0 / drive.inverter.f_pwm)


# ---------------------------------------------------------------------------------------------------------------
# the option: Python, motor file, CLI


def test_model_is_validated():
    with pytest.raises(BldclabError) as e:
        bl.load("htm-48v").replace(inverter__model="averaged")
    assert e.value.field.endswith("model") and "switching, average" in str(e.value)


def test_motor_file_key_round_trips(tmp_path: Path):
    drive = bl.load("htm-48v").replace(inverter__model="average")
    path = tmp_path / "m.toml"
    path.write_text(drive.to_toml())
    assert 'model = "average"' in path.read_text()
    assert bl.load(str(path)).inverter.model == "average"
    path.write_text(drive.to_toml().replace('model = "average"', 'model = "mean"'))
    with pytest.raises(BldclabError) as e:
        bl.load(str(path))
    assert e.value.field == "inverter.model"


@pytest.mark.slow
def test_cli_inverter_option(tmp_path, capsys):
    assert main(["simulate", "htm-48v", "--inverter", "average", "--periods", "3"]) == 0
    assert "average inverter" in capsys.readouterr().out
    assert main(["torque-control", "lu-4kw", "--torques", "50%", "--speeds", "0.5 pu", "--methods", "rect",
                 "--inverter", "average", "--out", str(tmp_path / "tc")]) == 0
    assert (tmp_path / "tc" / "methods.csv").exists()


@pytest.mark.parametrize("command", ["simulate", pytest.param("compare", marks=pytest.mark.slow),
                                     pytest.param("torque-control", marks=pytest.mark.slow)])
def test_cli_bad_inverter_exits_2_with_one_line(command, tmp_path):
    proc = subprocess.run([sys.executable, "-m", "bldclab.cli", command, "htm-48v", "--inverter", "avg", "--out",
                           str(tmp_path / "o")], capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "--inverter" in lines[0] and "Traceback" not in proc.stderr
    assert not (tmp_path / "o").exists()


def test_switching_is_unchanged_by_default():
    assert bl.load("htm-48v").inverter.model == "switching"
    assert math.isfinite(run(bl.load("htm-48v"), "square", 0.5, "switching").tau_mean_pu)

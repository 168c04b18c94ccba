"""Stator iron losses (issue 14): the time-domain model against its closed forms, the reference-speed
parametrisation, the speed scaling of each term, the energy balance with the iron's drag on the rotor, zero-loss
defaults, field validation and the motor file."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

import bldclab as bl
from bldclab.analysis.effmap import efficiency_map, loss_buckets
from bldclab.cli import main
from bldclab.errors import BldclabError
from bldclab.model.emf import BackEmf, Sinusoid, Trapezoid
from bldclab.sim.plausibility import BALANCE_WARN

DRIVES = ("htm-48v", "lu-4kw", "outrunner-24v", "servo-2k2")


def _catalog(name: str) -> bl.Drive:
    return bl.load(name).replace(inverter__i_trip=0.0)


def _with_iron(drive: bl.Drive, eddy: float = 0.5, hyst: float = 0.35, ex: float = 0.15,
               w_ref_pu: float = 0.7) -> bl.Drive:
    """Illustrative iron loss (not data of the catalog motors): 2 % of T_N Omega_0 at 0.7 Omega_0, split
    eddy / hysteresis / excess."""
    P = 0.02 * drive.T_N * drive.Omega_0
    return drive.replace(motor__P_fe_eddy=eddy * P, motor__P_fe_hyst=hyst * P, motor__P_fe_ex=ex * P,
                         motor__speed_fe_ref=w_ref_pu * drive.Omega_0)


def _imposed(drive: bl.Drive, ctl: bl.Control, w_pu: float, ref_pu: float, periods: int = 3) -> bl.Metrics:
    """Closed loop at an imposed speed (p.u. of Omega_0), torque reference in p.u. of T_N; the last period."""
    om = w_pu * drive.Omega_0
    Te = 2 * math.pi / (drive.motor.p * om)
    sc = bl.Scenario(duration=periods * Te, speed=om, ref=ref_pu * drive.T_N,
                     window=((periods - 1) * Te, periods * Te), trace=False)
    m = bl.simulate(drive, ctl, sc).metrics
    assert m is not None
    return m


def _ctl(name: str) -> bl.Control:
    return bl.SixStep() if name == "SixStep" else bl.Sine()


def test_sinusoidal_emf_matches_the_closed_form():
    """A sinusoidal back-EMF of peak E = k_1 omega at a constant speed, under load (the model does not depend on
    the current): p_fe = 3 k_e E^2 / 2 + k_h omega_e + 3 k_x E^1.5 mean|sin|^1.5, mean|sin|^1.5 =
    Gamma(1.25) / (sqrt(pi) Gamma(1.75)), to 1e-6 relative; each term alone too."""
    base = _catalog("htm-48v")
    k1 = 2.0 * base.motor.k_phi / math.sqrt(3.0)
    drive = _with_iron(base.replace(motor__emf=BackEmf.symmetric(Sinusoid(k1))))
    mot = drive.motor
    om = 0.5 * drive.Omega_0
    E, w_e = k1 * om, mot.p * om
    msin = math.gamma(1.25) / (math.sqrt(math.pi) * math.gamma(1.75))
    terms = {"eddy": 1.5 * mot.k_fe_eddy * E**2, "hyst": mot.k_fe_hyst * w_e, "ex": 3 * mot.k_fe_ex * E**1.5 * msin}
    m = _imposed(drive, bl.Sine(), 0.5, 0.5)
    assert m.i_rms[0] > 0.2 * drive.motor.I_N  # loaded
    assert m.p_fe == pytest.approx(sum(terms.values()), rel=1e-6)
    for name in terms:
        only = {"eddy": 0.0, "hyst": 0.0, "ex": 0.0, name: 1.0}
        m1 = _imposed(_with_iron(drive, **only), bl.Sine(), 0.5, 0.5)
        ref = {"eddy": 1.5 * E**2, "hyst": w_e, "ex": 3 * E**1.5 * msin}[name]
        k = {"eddy": "k_fe_eddy", "hyst": "k_fe_hyst", "ex": "k_fe_ex"}[name]
        assert m1.p_fe == pytest.approx(getattr(_with_iron(drive, **only).motor, k) * ref, rel=1e-6), name
    assert terms["eddy"] > 0 and terms["hyst"] > 0 and terms["ex"] > 0


@pytest.mark.parametrize("ctl_name", ["SixStep", "Sine"])
def test_reference_speed_reproduces_the_given_losses_on_a_trapezoid(ctl_name: str):
    """htm-48v (ideal 120-degree trapezoid, its harmonics count in sum e^2): at speed_fe_ref the simulation books
    P_fe_eddy + P_fe_hyst + P_fe_ex, whatever the supply and the load, to 1e-6."""
    drive = _with_iron(_catalog("htm-48v"), w_ref_pu=0.6)
    mot = drive.motor
    for ref_pu in (0.2, 0.7):
        m = _imposed(drive, _ctl(ctl_name), 0.6, ref_pu)
        assert m.omega_mean == pytest.approx(mot.speed_fe_ref, rel=1e-12)
        assert m.p_fe == pytest.approx(mot.P_fe_eddy + mot.P_fe_hyst + mot.P_fe_ex, rel=1e-6)


@pytest.mark.parametrize(("term", "power"), [("eddy", 2.0), ("hyst", 1.0), ("ex", 1.5)])
def test_each_term_scales_with_its_power_of_speed(term: str, power: float):
    """Eddy ~ speed^2, hysteresis ~ speed, excess ~ speed^1.5 (constant speed, whole electrical periods)."""
    only = {"eddy": 0.0, "hyst": 0.0, "ex": 0.0, term: 1.0}
    drive = _with_iron(_catalog("lu-4kw"), **only)
    lo = _imposed(drive, bl.SixStep(), 0.3, 0.3).p_fe
    hi = _imposed(drive, bl.SixStep(), 0.6, 0.3).p_fe
    assert lo > 0
    assert hi / lo == pytest.approx(2.0**power, rel=1e-6)


@pytest.mark.parametrize("name", DRIVES)
@pytest.mark.parametrize("ctl_name", ["SixStep", "Sine"])
def test_energy_balance_with_iron_losses_imposed_speed(name: str, ctl_name: str):
    """Imposed speed: the iron loss is the model's closed form (Motor.iron_loss) at two operating points, the
    circuit's balance closes to 1e-4 and the efficiency counts the iron: shaft = p_emf + p_cog - p_fric - p_fe."""
    drive = _with_iron(_catalog(name))
    for w_pu, ref_pu in ((0.35, 0.6), (0.7, 0.3)):
        m = _imposed(drive, _ctl(ctl_name), w_pu, ref_pu)
        assert m.p_fe == pytest.approx(drive.motor.iron_loss(w_pu * drive.Omega_0), rel=1e-6)
        assert abs(m.balance_electrical) < 1e-4
        shaft = m.p_emf + m.p_cog - m.p_fric - m.p_fe
        assert m.p_shaft == shaft
        if shaft >= 0:
            assert m.power_flow == "motoring"
            assert m.efficiency == pytest.approx(shaft / m.p_src_total, rel=1e-12)
        else:  # the iron loss takes more than the electromagnetic power: the dynamometer feeds it too
            assert m.power_flow == "dissipating" and math.isnan(m.efficiency)


@pytest.mark.filterwarnings("ignore:.*not a steady state:bldclab.errors.PlausibilityWarning")
@pytest.mark.parametrize("name", DRIVES)
def test_energy_balance_with_iron_losses_rotor_dynamics(name: str):
    """Rotor dynamics, iron drag braking the rotor: source = copper + inverter + iron + friction + load + stored
    (magnetic, kinetic, cogging) over the window, each bucket from its own integral, to 1e-4 of the source
    energy."""
    base = _catalog(name)
    drive = _with_iron(base).replace(inverter__R_on=0.004, inverter__V_f=0.7, inverter__r_d=0.003,
                                     inverter__E_on=20e-6, inverter__E_off=30e-6, inverter__E_rr=5e-6,
                                     inverter__V_test=base.inverter.V_dc, inverter__I_test=20.0)
    om = 0.5 * drive.Omega_0
    Te = 2 * math.pi / (drive.motor.p * om)
    sc = bl.Scenario(duration=6 * Te, speed=None, omega0=om, ref=0.5 * drive.T_N, load_torque=0.3 * drive.T_N,
                     window=(4 * Te, 6 * Te), trace=False)
    m = bl.simulate(drive, bl.SixStep(), sc).metrics
    assert m is not None and m.p_fe > 0
    dt = m.t1 - m.t0
    buckets = {"copper": m.p_cu, "inverter": m.p_sw + m.p_diode + m.p_Rsrc + m.p_swloss + m.p_rr,
               "iron": m.p_fe, "friction": m.p_fric, "load": m.p_load,
               "stored": (m.dW_L + m.dW_kin) / dt - m.p_cog}
    residue = (m.p_src_total - sum(buckets.values())) / m.p_src_total
    assert abs(residue) < 1e-4, buckets
    assert abs(m.balance_mechanical) < 1e-6


@pytest.mark.filterwarnings("ignore:.*not a steady state:bldclab.errors.PlausibilityWarning")
def test_iron_drag_brakes_the_rotor():
    """With rotor dynamics the same torque reference and load settle at a lower speed when the iron's drag is
    added (the loss comes from the shaft)."""
    base = _catalog("htm-48v")
    drive = _with_iron(base).replace(motor__P_fe_eddy=0.2 * base.T_N * base.Omega_0)
    om = 0.5 * base.Omega_0
    Te = 2 * math.pi / (base.motor.p * om)
    sc = bl.Scenario(duration=8 * Te, speed=None, omega0=om, ref=0.3 * base.T_N, load_torque=0.1 * base.T_N,
                     window=(7 * Te, 8 * Te), trace=False)
    free, braked = (bl.simulate(d, bl.SixStep(), sc).metrics for d in (base, drive))
    assert free is not None and braked is not None
    assert braked.omega_mean < free.omega_mean
    assert free.p_fe == 0.0 and braked.p_fe > 0.0


def test_zero_iron_fields_change_nothing_bitwise():
    """Explicit zero iron losses (with or without a reference speed) give the default drive's metrics bit for bit,
    with p_fe exactly 0."""
    base = _catalog("htm-48v")
    for zero in (base.replace(motor__P_fe_eddy=0.0, motor__P_fe_hyst=0.0, motor__P_fe_ex=0.0),
                 base.replace(motor__speed_fe_ref=50.0)):
        for ctl in (bl.SixStep(), bl.Sine()):
            a = dataclasses.asdict(_imposed(base, ctl, 0.5, 0.6))
            b = dataclasses.asdict(_imposed(zero, ctl, 0.5, 0.6))
            assert a == b
            assert a["p_fe"] == 0.0


def test_mean_abs_power_of_shapes():
    """The period means the coefficients come from, against a dense sampling."""
    th = np.linspace(0.0, 2 * np.pi, 1 << 18, endpoint=False)
    for name in DRIVES:
        emf = _catalog(name).motor.emf
        k = emf.k_abc(th)
        for q in (2.0, 1.5):
            dense = float(np.sum(np.mean(np.abs(k) ** q, axis=1)))
            assert emf.mean_abs_power(q) == pytest.approx(dense, rel=1e-7), (name, q)


def test_coefficients_and_loss_formula():
    drive = _with_iron(_catalog("htm-48v"))
    mot = drive.motor
    w = mot.speed_fe_ref
    assert mot.k_fe_eddy * w**2 * mot.emf.mean_abs_power(2.0) == pytest.approx(mot.P_fe_eddy, rel=1e-14)
    assert mot.k_fe_hyst * mot.p * w == pytest.approx(mot.P_fe_hyst, rel=1e-14)
    assert mot.k_fe_ex * w**1.5 * mot.emf.mean_abs_power(1.5) == pytest.approx(mot.P_fe_ex, rel=1e-14)
    assert mot.iron_loss(w) == pytest.approx(mot.P_fe_eddy + mot.P_fe_hyst + mot.P_fe_ex)
    assert mot.iron_loss(-2 * w) == pytest.approx(4 * mot.P_fe_eddy + 2 * mot.P_fe_hyst + 2**1.5 * mot.P_fe_ex)
    plain = _catalog("htm-48v").motor
    assert not plain.has_iron_losses and plain.k_fe_eddy == plain.k_fe_hyst == plain.k_fe_ex == 0.0
    assert plain.iron_loss(100.0) == 0.0


@pytest.mark.parametrize(("kw", "field"), [
    ({"motor__P_fe_eddy": -1.0, "motor__speed_fe_ref": 50.0}, "P_fe_eddy"),
    ({"motor__P_fe_hyst": math.nan, "motor__speed_fe_ref": 50.0}, "P_fe_hyst"),
    ({"motor__P_fe_ex": math.inf, "motor__speed_fe_ref": 50.0}, "P_fe_ex"),
    ({"motor__P_fe_eddy": 10.0}, "speed_fe_ref"),
    ({"motor__P_fe_hyst": 10.0, "motor__speed_fe_ref": 0.0}, "speed_fe_ref"),
    ({"motor__P_fe_ex": 10.0, "motor__speed_fe_ref": -5.0}, "speed_fe_ref"),
    ({"motor__speed_fe_ref": math.nan}, "speed_fe_ref"),
])
def test_bad_iron_fields_rejected_naming_the_field(kw: dict[str, float], field: str):
    with pytest.raises(BldclabError, match=field) as err:
        _catalog("htm-48v").replace(**kw)
    assert err.value.field == field


def test_motor_file_round_trip_units_and_cli_errors(tmp_path, capsys):
    drive = _with_iron(_catalog("htm-48v"))
    text = drive.to_toml()
    assert "P_fe_eddy" in text and "speed_fe_ref" in text
    assert "P_fe" not in _catalog("htm-48v").to_toml() and "speed_fe_ref" not in _catalog("htm-48v").to_toml()
    path = tmp_path / "m.toml"
    path.write_text(text)
    assert bl.load(path).motor == drive.motor
    # units: a power in kW and a reference speed in rpm
    lines = [ln for ln in text.splitlines() if not ln.startswith(("P_fe_eddy =", "speed_fe_ref ="))]
    j = lines.index("[motor]") + 1
    lines[j:j] = ['P_fe_eddy = "0.05 kW"', 'speed_fe_ref = "500 rpm"']
    path.write_text("\n".join(lines) + "\n")
    back = bl.load(path).motor
    assert back.P_fe_eddy == pytest.approx(50.0) and back.speed_fe_ref == pytest.approx(500 * math.pi / 30)
    # a loss without its reference speed: one error naming the field, exit 2 from the CLI
    bad = [ln for ln in lines if not ln.startswith("speed_fe_ref =")]
    path.write_text("\n".join(bad) + "\n")
    with pytest.raises(BldclabError, match="speed_fe_ref"):
        bl.load(path)
    capsys.readouterr()
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert "speed_fe_ref" in err and err.count("\n") == 1
    path.write_text("\n".join(lines).replace('P_fe_eddy = "0.05 kW"', 'P_fe_eddy = "-5 W"') + "\n")
    assert main(["check", str(path)]) == 2
    assert "P_fe_eddy" in capsys.readouterr().err


def test_iron_loss_is_an_efficiency_map_bucket():
    """p_fe is a bucket of the map; with iron loss on, input = shaft + losses + stored still holds, the bucket equals
    the model's closed form at the point's speed for both supplies, and the efficiency drops."""
    base = _catalog("htm-48v")
    drive = _with_iron(base)
    assert "p_fe" in loss_buckets()
    args = ([0.5 * base.T_N], [0.5 * base.Omega_0])
    res, ref = efficiency_map(drive, *args, workers=1), efficiency_map(base, *args, workers=1)
    for (_, r), (_, r0) in zip(res.points.iterrows(), ref.points.iterrows(), strict=True):
        assert r.p_fe == pytest.approx(drive.motor.iron_loss(r.speed), rel=1e-6), r.supply
        losses = sum(r[b] for b in res.buckets)
        assert abs(r.p_in - r.p_shaft - losses - r.p_stored) <= BALANCE_WARN * abs(r.p_in)
        assert r0.p_fe == 0.0 and r.efficiency < r0.efficiency


def test_cli_reports_the_iron_loss(tmp_path, capsys):
    """``bldclab check`` names the model's iron loss at Omega_0; ``bldclab simulate`` reports p_iron_W, which at
    speed_fe_ref is the sum of the given parts."""
    drive = _with_iron(_catalog("htm-48v"), ex=0.0, w_ref_pu=0.5)
    path = tmp_path / "iron.toml"
    path.write_text(drive.to_toml())
    assert main(["check", str(path)]) == 0
    assert f"{drive.motor.iron_loss(drive.Omega_0):.4g} W" in capsys.readouterr().out
    assert main(["simulate", str(path), "--control", "sine", "--speed", str(drive.motor.speed_fe_ref), "--torque",
                 str(0.4 * drive.T_N), "--no-trace", "--format", "json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["p_iron_W"] == pytest.approx(drive.motor.P_fe_eddy + drive.motor.P_fe_hyst, rel=1e-6)


def test_material_route_reproduces_steinmetz_bertotti_for_a_sinusoid():
    """From material data (W/kg at 1 T, 50 Hz by term, core mass, peak flux density): a sinusoidal back-EMF gets
    the material's formula mass (p_h (f/50) B^alpha + p_e (f/50)^2 B^2 + p_ex (f/50)^1.5 B^1.5) at any speed, the
    simulation books it (1e-6). The flux of an ideal 120-degree trapezoidal back-EMF with the same peak has the same
    hysteresis and mean (dpsi/dtheta)^2 = k^2 7/9 against psi_pk^2 / 2 for the sine, psi_pk = k 5 pi / 12: its eddy
    loss is (7/9) / ((5 pi/12)^2 / 2) = 0.908 of the sine's (a flatter flux, as a triangle's 8/pi^2). The data are
    illustrative (the order of a 0.35 mm non-oriented steel), not a cited grade."""
    base = _catalog("htm-48v")
    k1 = 2.0 * base.motor.k_phi / math.sqrt(3.0)
    sine = base.replace(motor__emf=BackEmf.symmetric(Sinusoid(k1)))
    data = {"mass": 2.0, "B_peak": 1.5, "p_hyst": 1.2, "p_eddy": 0.5, "p_ex": 0.3, "alpha": 1.8}
    mot = sine.motor.with_iron_from_material(**data, speed_ref=0.5 * sine.Omega_0)
    drive = sine.replace(motor=mot)
    for w_pu in (0.3, 0.6):
        om = w_pu * drive.Omega_0
        f = mot.p * om / (2 * math.pi) / 50.0
        B = data["B_peak"]
        steinmetz = data["mass"] * (data["p_hyst"] * f * B ** data["alpha"] + data["p_eddy"] * f**2 * B**2
                                    + data["p_ex"] * f**1.5 * B**1.5)
        assert mot.iron_loss(om) == pytest.approx(steinmetz, rel=1e-7)
        assert _imposed(drive, bl.Sine(), w_pu, 0.4).p_fe == pytest.approx(steinmetz, rel=1e-6)
    # a trapezoid with the same peak flux linkage: psi_pk = k_phi 5 pi / (12 p) for the 120-degree flat top
    k_phi = k1 * 12 / (5 * math.pi)
    trap = base.replace(motor__emf=BackEmf.symmetric(Trapezoid(k_phi))).motor
    tm = trap.with_iron_from_material(**data, speed_ref=mot.speed_fe_ref)
    assert tm.P_fe_hyst == pytest.approx(mot.P_fe_hyst, rel=1e-12)
    assert tm.P_fe_eddy / mot.P_fe_eddy == pytest.approx((7 / 9) / ((5 * math.pi / 12) ** 2 / 2), rel=1e-7)
    assert tm.P_fe_ex < mot.P_fe_ex
    with pytest.raises(BldclabError, match=r"material\.B_peak"):
        sine.motor.with_iron_from_material(**{**data, "B_peak": -1.0})
    with pytest.raises(BldclabError, match=r"material\.alpha"):
        sine.motor.with_iron_from_material(**{**data, "alpha": 5.0})

"""The commissioning workflow on the command line: ``bldclab commission MOTOR --nominal DATA --out EST.toml``, then
``bldclab simulate MOTOR --estimate EST.toml`` (docs/cli.md, docs/sensorless-sine.md).

The plant is a catalog drive; the data the routine starts from is that drive with R, L and the back-EMF wrong (a
datasheet that is off). What the routine writes must be the plant's values, and ``simulate --estimate`` must hand
that file to the controller (the torque of a flux-linkage-scaled estimate is the closed form's ``1 / scale``).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import bldclab as bl
from bldclab.analysis.commission import Estimate
from bldclab.cli import main
from bldclab.control.sine import fundamental_k1
from bldclab.model.analytic import r_total

PLANT = "outrunner-24v"


def datasheet(tmp_path: Path, **scale: float) -> Path:
    """Write the plant's data scaled by ``scale`` (R, L, emf) as a motor file; return its path."""
    path = tmp_path / "datasheet.toml"
    path.write_text(bl.load(PLANT).scaled(**scale).replace(name="datasheet").to_toml())
    return path


def test_commission_writes_the_plants_values_from_wrong_data(tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    """Started from R +50 %, L +30 %, flux +25 %, the written file holds the plant's R, L and flux linkage (the
    Python API's tolerances: 0.5 %, 1 %, 1 %) and the datasheet's name and everything else."""
    ds = datasheet(tmp_path, R=1.5, L=1.3, emf=1.25)
    out = tmp_path / "sub" / "est.toml"
    assert main(["commission", PLANT, "--nominal", str(ds), "--out", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    est, plant = bl.load(str(out)), bl.load(PLANT)
    assert est.name == "datasheet-commissioned"
    assert r_total(est) == pytest.approx(r_total(plant), rel=0.005)
    assert est.motor.L == pytest.approx(plant.motor.L, rel=0.01)
    assert fundamental_k1(est) == pytest.approx(fundamental_k1(plant), rel=0.01)
    assert est.mechanics == plant.mechanics and est.inverter == plant.inverter


def sine_torque(capsys: pytest.CaptureFixture[str], estimate: Path | None) -> float:
    """Mean torque (N m) of the encoder-based Sine at 0.3 Omega_0 imposed, half the rated torque asked."""
    args = ["simulate", PLANT, "--control", "sine", "--angle", "encoder", "--speed", "0.3 pu", "--torque",
            f"{0.5 * bl.load(PLANT).T_N} N m", "--periods", "20", "--no-trace", "--format", "json"]
    capsys.readouterr()
    assert main(args + ([] if estimate is None else ["--estimate", str(estimate)])) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["estimate"] == (None if estimate is None else bl.load(str(estimate)).name)
    return float(summary["tau_mean_N_m"])


def test_simulate_hands_the_estimate_to_the_controller(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    """A controller told a back-EMF 25 % high asks for 1 / 1.25 of the current, so the plant gives 0.8 of the
    torque (the current loop's reference is tau / (1.5 k_1)); the commissioned file gives the plant's own torque."""
    tau = sine_torque(capsys, None)
    ds = datasheet(tmp_path, emf=1.25)
    assert sine_torque(capsys, ds) / tau == pytest.approx(1 / 1.25, rel=0.01)
    est = tmp_path / "est.toml"
    assert main(["commission", PLANT, "--nominal", str(ds), "--out", str(est)]) == 0
    assert sine_torque(capsys, est) == pytest.approx(tau, rel=0.005)


def test_bad_options_name_themselves_and_write_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Other pole pairs or PWM frequency in --nominal / --estimate (the hardware, not an estimate), --out a
    directory: exit 2 with the option named, nothing written."""
    other = tmp_path / "other.toml"
    other.write_text(bl.load(PLANT).replace(motor__p=7).to_toml())
    out = tmp_path / "est.toml"
    assert main(["commission", PLANT, "--nominal", str(other), "--out", str(out)]) == 2
    assert "--nominal" in capsys.readouterr().err and not out.exists()
    assert main(["commission", PLANT, "--out", str(tmp_path)]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["simulate", PLANT, "--control", "sine", "--estimate", str(other)]) == 2
    assert "--estimate" in capsys.readouterr().err
    pwm = tmp_path / "pwm.toml"
    pwm.write_text(bl.load(PLANT).replace(inverter__f_pwm=2 * bl.load(PLANT).inverter.f_pwm).to_toml())
    assert main(["simulate", PLANT, "--control", "sine", "--estimate", str(pwm)]) == 2
    assert "inverter.f_pwm" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["other.toml", "pwm.toml"]


def test_a_failed_routine_writes_no_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    """A routine that ends in a failure status exits 1, names the status, and leaves no estimate behind."""
    plant = bl.load(PLANT)

    def failed(drive: bl.Drive, nominal: bl.Drive | None = None) -> Estimate:
        return Estimate("ROTOR_MOVING", 0.0, 0.0, 0.0, 0.1, 0.0, plant)

    monkeypatch.setattr("bldclab.cli.commission.commission", failed)
    out = tmp_path / "est.toml"
    assert main(["commission", PLANT, "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert "ROTOR_MOVING" in captured.out and "not written" in captured.err
    assert not out.exists() and list(tmp_path.iterdir()) == []

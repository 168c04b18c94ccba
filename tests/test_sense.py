"""Back-EMF sensing from Python: the drive's settings (motor file, errors), and in the loop.

The model's accuracy (closed-form filter, edge instants, ADC) is tested in C (core/tests/test_sense.c); here: what
the settings reach, that sensing observes without disturbing the run, and the counts a run reports.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import bldclab as bl
from bldclab.errors import BldclabError

HTM = bl.load("htm-48v")


def _with_sensing(drive: bl.Drive, **kw: object) -> bl.Drive:
    return drive.replace(sensors=dataclasses.replace(drive.sensors, **kw))


def _run(drive: bl.Drive, duration: float = 0.02) -> bl.SimResult:
    om = 0.4 * drive.Omega_0
    return bl.simulate(drive, bl.SixStepVoltage("high"),
                       bl.Scenario(duration=duration, speed=om, ref=0.5, theta0=0.3))


def test_sensing_observes_without_disturbing_the_run() -> None:
    """The same run with sensing on is the same run, bit for bit; the counts are those of its length."""
    off = _run(HTM, 0.1)
    on = _run(_with_sensing(HTM, bemf=True, bemf_tau=20e-6), 0.1)
    assert off.meta["bemf"] is None
    for name in ("i_a", "i_b", "theta_e", "tau_e", "v_a"):
        np.testing.assert_array_equal(on[name], off[name])
    b = on.meta["bemf"]
    # one conversion per PWM period: at t = (m + 1/2) T for m = 0 .. n - 1 inside the run
    n_periods = on.meta["samples"] // 2
    assert b["conversions"] == n_periods
    # 20 us filter: each comparator switches at least twice per electrical period (the run covers several)
    periods = 0.4 * HTM.Omega_0 * HTM.motor.p * 0.1 / (2.0 * math.pi)
    assert periods > 3
    assert all(k >= 2 * math.floor(periods) for k in b["seen"])
    assert b["edges"] >= sum(b["seen"]) and not b["overrun"]


def test_delay_holds_edges_in_flight() -> None:
    """A propagation delay only shifts the edges: what is located at the inputs is the same."""
    a = _run(_with_sensing(HTM, bemf=True, bemf_tau=20e-6)).meta["bemf"]
    b = _run(_with_sensing(HTM, bemf=True, bemf_tau=20e-6, bemf_delay=3e-6)).meta["bemf"]
    assert a["edges"] == b["edges"]
    assert all(0 <= x - y <= 1 for x, y in zip(a["seen"], b["seen"], strict=True))


def test_motor_file_round_trip(tmp_path: object) -> None:
    d = _with_sensing(HTM, bemf=True, bemf_tau=4.7e-6, bemf_reference="half", bemf_offset=0.02,
                      bemf_hysteresis=0.05, bemf_delay=0.3e-6, bemf_adc_at=-5e-6, bemf_adc_lsb=48 / 4096,
                      bemf_adc_max=52.8, bemf_adc_noise=0.01)
    back = bl.Drive.from_dict(__import__("tomllib").loads(d.to_toml()))
    assert back.sensors == d.sensors
    # the defaults are not written: files without sensing stay as they were
    assert "bemf" not in HTM.to_toml()
    assert "current_full_scale" not in HTM.to_toml()
    fs = HTM.replace(sensors__current_full_scale=100.0)
    assert bl.Drive.from_dict(__import__("tomllib").loads(fs.to_toml())).sensors.current_full_scale == 100.0


def test_motor_file_units() -> None:
    data = __import__("tomllib").loads(HTM.to_toml())
    data["sensors"].update({"bemf_tau": "10 us", "bemf_adc_lsb": "12 mV", "bemf_reference": "star", "bemf": True})
    d = bl.Drive.from_dict(data)
    assert d.sensors.bemf_tau == pytest.approx(10e-6)
    assert d.sensors.bemf_adc_lsb == pytest.approx(12e-3)
    assert d.sensors.bemf is True


@pytest.mark.parametrize(("key", "value", "field", "words"), [
    ("bemf_tau", "-1 us", "sensors.bemf_tau", ">= 0"),
    ("bemf_tau", "10 V", "sensors.bemf_tau", "unit"),
    ("bemf_reference", "neutral", "sensors.bemf_reference", "star"),
    ("bemf", "yes", "sensors.bemf", "true or false"),
    ("bemf_hysteresis", float("nan"), "sensors.bemf_hysteresis", ""),
    ("bemf_adc_max", "0 V", "sensors.bemf_adc_max", "> 0"),
    ("current_full_scale", "0 A", "sensors.current_full_scale", "> 0"),
    ("current_full_scale", "-40 A", "sensors.current_full_scale", "> 0"),
    ("current_full_scale", float("nan"), "sensors.current_full_scale", ""),
    ("current_full_scale", "40 V", "sensors.current_full_scale", "unit"),
    ("current_full_scale", "40 A", None, None),
    ("bemf_adc_at", "40 us", "sensors.bemf_adc_at", "T/2"),
    ("bemf_delay", "1 ms", None, None),  # long but valid
    ("bemf_filter", "1 us", "sensors.bemf_filter", "unknown field"),
])
def test_motor_file_errors(key: str, value: object, field: str | None, words: str | None) -> None:
    data = __import__("tomllib").loads(HTM.to_toml())
    data["sensors"][key] = value
    if field is None:
        bl.Drive.from_dict(data)
        return
    with pytest.raises(BldclabError) as exc:
        bl.Drive.from_dict(data)
    assert exc.value.field == field
    assert words in exc.value.problem


def test_sensing_from_the_cli(tmp_path: object) -> None:
    """A motor file with sensing settings passes `bldclab check` (exit 0) and a bad one fails with exit 2."""
    from bldclab.cli import main

    good = _with_sensing(HTM, bemf=True, bemf_tau=10e-6)
    p = tmp_path / "good.toml"  # type: ignore[operator]
    p.write_text(good.to_toml())
    assert main(["check", str(p)]) == 0
    bad = p.read_text().replace("bemf_tau = 1e-05", "bemf_tau = -1e-05")
    assert bad != p.read_text()
    q = tmp_path / "bad.toml"  # type: ignore[operator]
    q.write_text(bad)
    assert main(["check", str(q)]) == 2

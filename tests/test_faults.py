"""Fault injection report: detection, time to the safe state, peak current against the trips."""

from __future__ import annotations

import math

import pytest

import bldclab as bl
from bldclab.analysis.faults import fault_table
from bldclab.cli import main
from bldclab.model import analytic as an

HTM = bl.load("htm-48v")
LU = bl.load("lu-4kw")


@pytest.mark.parametrize("name", ["square", "sine", "lu"])
def test_fault_report(name):
    if name == "lu":
        drive, ctl, ref, i_max = LU, bl.Lu(), LU.T_N, 3 * LU.motor.I_N
    elif name == "sine":
        drive, ctl, ref, i_max = HTM, bl.Sine(handoff_speed=0.02 * HTM.Omega_0), an.t_sN(HTM), 2 * HTM.motor.I_N
    else:
        drive, ctl, ref, i_max = HTM, bl.SixStep(), HTM.motor.I_N, 2 * HTM.motor.I_N
    t = fault_table(drive, ctl, ref, 0.5 * drive.Omega_0, i_max=i_max).set_index("fault")
    assert not t.loc["none", "detected"]
    # every Hall fault that produces an invalid code or a large current is caught and the legs go off
    for f in ("hall a stuck at 0", "hall a stuck at 1", "hall b glitch 50 us"):
        assert t.loc[f, "detected"], f
        assert t.loc[f, "t_safe_ms"] < 15.0, f
        assert t.loc[f, "i_peak"] <= 1.1 * i_max, f
    # a lost current sensor: stopped by the firmware or, at the latest, by the inverter's hardware trip
    lost = t.loc["current sensor a lost"]
    assert lost.detected and lost.i_peak <= drive.inverter.i_trip * (1 + 1e-6)
    # faults the measurements cannot reveal leave the drive running (reported as not detected)
    for f in ("current a offset +20 % I_N", "DC bus sag to 60 %"):
        assert not t.loc[f, "detected"] and math.isnan(t.loc[f, "t_safe_ms"])


def test_faults_cli(tmp_path, capsys):
    assert main(["faults", "htm-48v", "--control", "square", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "faults.csv").exists()
    assert "hall a stuck at 1" in capsys.readouterr().out

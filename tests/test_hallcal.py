"""Six-edge Hall calibration (``bc_hallcal.h``), the edge table and the tracking estimator (``bc_hall.h``), run with
the plant: accuracy against the true edges of misplaced sensors (``Sensors.hall_error``), bad input ends flagged
with no table, the tracking loop against paper 1's (46) in steady state and on a speed ramp, and the calibrated
table in the controllers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import bldclab as bl
from bldclab.control.hall import NOMINAL_EDGES
from bldclab.control.hallcal import read_calibration

DRIVES = ["htm-48v", "lu-4kw", "outrunner-24v", "servo-2k2"]
errors = st.tuples(*[st.floats(-10.0, 10.0) for _ in range(3)])  # electrical degrees per sensor (a, b, c)


def true_edges(err_rad: tuple[float, float, float]) -> np.ndarray:
    """Edge j (sectors j-1 | j) belongs to sensor 2 - j % 3 (docs/conventions.md); a sensor's error moves both."""
    return np.array([NOMINAL_EDGES[j] + err_rad[2 - j % 3] for j in range(6)])


def wrap_deg(x: np.ndarray) -> np.ndarray:
    return np.degrees((x + np.pi) % (2 * np.pi) - np.pi)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(DRIVES), err=errors)
def test_constant_speed_finds_the_edges_up_to_their_mean(name, err):
    """At constant speed the sector widths come out exact and the absolute angle is off by the mean edge error
    (the stated assumption): both to 0.01 electrical degrees after one revolution."""
    e = tuple(math.radians(v) for v in err)
    drive = bl.load(name).replace(sensors__hall_error=e)
    cal = bl.calibrate_hall(drive, "constant-speed", revolutions=1)
    assert cal.ok, cal.reasons
    d = wrap_deg(np.array(cal.table) - true_edges(e))
    assert np.max(np.abs(d - d.mean())) < 0.01, d
    assert abs(d.mean() + np.degrees(np.mean(true_edges(e) - NOMINAL_EDGES))) < 0.01, d


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=st.sampled_from(DRIVES), err=errors)
def test_open_loop_finds_the_absolute_edges(name, err):
    """The start-up sweep (forward and backward, lag cancelled) finds every edge within 1.5 electrical degrees
    after 2 revolutions per direction (measured worst: 0.9 on lu-4kw, whose cogging-free but high-inertia rotor
    lags most; 0.5 on htm-48v; < 0.01 on the others)."""
    e = tuple(math.radians(v) for v in err)
    drive = bl.load(name).replace(sensors__hall_error=e)
    cal = bl.calibrate_hall(drive, "open-loop", revolutions=2)
    assert cal.ok, cal.reasons
    d = wrap_deg(np.array(cal.table) - true_edges(e))
    assert np.max(np.abs(d)) < 1.5, d



@pytest.mark.parametrize("name", DRIVES)
def test_open_loop_cancels_hysteresis_and_delay(name):
    """Sensors with 4 deg of hysteresis and 20 us of delay each switch h/2 (plus the delay's angle) late in the
    direction of travel; the forward and backward sweeps see opposite shifts and their average is the placement
    error alone: the table moves by < 0.1 deg against the same sensors without them, and stays within 1.5 deg of
    the true edges (measured: 0.55 deg worst, lu-4kw)."""
    e = (math.radians(5.0), math.radians(-3.0), math.radians(2.0))
    base = bl.load(name).replace(sensors__hall_error=e)
    h = math.radians(4.0)
    lagged = base.replace(sensors__hall_hysteresis=(h, h, h), sensors__hall_delay=(20e-6, 20e-6, 20e-6))
    a, b = bl.calibrate_hall(base, "open-loop"), bl.calibrate_hall(lagged, "open-loop")
    assert a.ok and b.ok, (a.reasons, b.reasons)
    assert np.max(np.abs(wrap_deg(np.array(b.table) - np.array(a.table)))) < 0.1
    assert np.max(np.abs(wrap_deg(np.array(b.table) - true_edges(e)))) < 1.5

def _run(drive, routine, scenario):
    res = bl.simulate(drive, routine, scenario, check="off")
    return read_calibration(res, routine.method)


@pytest.mark.parametrize("case", ["stuck", "reversal", "ramp", "too-slow", "open-loop-stuck"])
def test_bad_input_is_flagged_and_gives_no_table(case):
    drive = bl.load("htm-48v").replace(sensors__hall_error=(0.05, -0.03, 0.02))
    w = 0.3 * drive.Omega_0
    t_rev = 2 * math.pi / (w * drive.motor.p)
    why = {"stuck": "E_INVALID", "reversal": "E_REVERSAL", "ramp": "E_SPEED", "too-slow": "E_FEW",
           "open-loop-stuck": "E_INVALID"}[case]
    if case == "open-loop-stuck":
        routine = bl.HallCal(method="open-loop", revolutions=1)
        sc = bl.Scenario(duration=routine.duration(), faults=(bl.Fault("hall_stuck", "b", 0.3, value=1.0),))
    else:
        routine = bl.HallCal(revolutions=3, timeout=2.5 * t_rev if case == "too-slow" else 1.0)
        speed: object = w
        faults: tuple = ()
        if case == "stuck":
            faults = (bl.Fault("hall_stuck", "a", 1.5 * t_rev, value=0.0),)
        elif case == "reversal":
            speed = f"0 s: {w} rad/s, {2 * t_rev} s: {-w} rad/s"
        elif case == "ramp":
            speed = f"0 s: {w} rad/s, {6 * t_rev} s: {1.5 * w} rad/s"
        sc = bl.Scenario(duration=6 * t_rev, speed=speed, faults=faults)
    cal = _run(drive, routine, sc)
    assert not cal.ok and "BC_HALLCAL_FAIL" in cal.reasons and f"BC_HALLCAL_{why}" in cal.reasons, cal.reasons
    assert cal.table == NOMINAL_EDGES


def _angle_error_deg(res, t0):
    m = (res.t >= t0) & (res["mode"] == 1)  # the sine mode, where the angle is used
    e = wrap_deg(res["theta"][m] - res["theta_e"][m])
    return float(np.sqrt(np.mean(e**2))), float(np.max(np.abs(e)))


def test_pll_beats_46_with_misplaced_sensors_and_stays_bounded_on_a_ramp():
    """Misplaced sensors (5, -3, 2 electrical degrees), htm-48v at half the no-load speed: the tracking loop's rms
    angle error is below 60 % of (46)'s in steady state (measured 2.4 vs 6.0 deg); on a ramp from 0.3 to 1 times
    that speed in 0.2 s (after 0.1 s at 0.3) it stays within 30 deg and 1.5 times (46)'s rms (measured 5.1 vs
    6.2 deg rms, 17 vs 16 deg max: the loop averages the edge errors over ~3 edges, so at a few hundred rad/s it
    lags a change of acceleration)."""
    drive = bl.load("htm-48v")
    de = drive.replace(sensors__hall_error=tuple(math.radians(v) for v in (5, -3, 2)))
    w = 0.5 * drive.Omega_0
    steady = bl.Scenario(duration=0.15, speed=w, ref=5.0)
    ramp = bl.Scenario(duration=0.3, speed=f"0 s: {0.3 * w} rad/s, 0.1 s: {0.3 * w} rad/s, 0.3 s: {w} rad/s",
                       ref=5.0)
    out = {}
    for angle in ("hall", "pll"):
        ctl = bl.Sine(angle=angle)
        out[angle, "steady"] = _angle_error_deg(bl.simulate(de, ctl, steady, check="off"), 0.08)
        out[angle, "ramp"] = _angle_error_deg(bl.simulate(de, ctl, ramp, check="off"), 0.1)
    assert out["pll", "steady"][0] < 0.6 * out["hall", "steady"][0], out
    assert out["pll", "ramp"][1] < 30.0 and out["pll", "ramp"][0] < 1.5 * out["hall", "ramp"][0], out


def test_calibrated_table_removes_the_ripple_of_misplaced_sensors():
    """Six-step (its commutation instant from the table) and sine ((46) on the table): with sensors misplaced by
    (8, -5, 3) degrees the torque ripple (std / mean) falls to within 2x of the ideal sensors' once calibrated."""
    drive = bl.load("htm-48v")
    de = drive.replace(sensors__hall_error=tuple(math.radians(v) for v in (8, -5, 3)))
    cal = bl.calibrate_hall(de, "open-loop", revolutions=2)
    assert cal.ok
    w = 0.5 * drive.Omega_0

    def ripple(d, ctl, ref):
        r = bl.simulate(d, ctl, bl.Scenario(duration=0.1, speed=w, ref=ref), check="off")
        tau = r["tau_e"][r.t >= 0.05]
        return float(np.std(tau) / abs(np.mean(tau)))

    for ctl, cal_ctl, ref in ((bl.SixStep(), bl.SixStep(hall_table=cal.table), 20.0),
                              (bl.Sine(), bl.Sine(hall_table=cal.table), 5.0)):
        ideal, bad, fixed = ripple(drive, ctl, ref), ripple(de, ctl, ref), ripple(de, cal_ctl, ref)
        assert bad > 5 * ideal and fixed < 2 * ideal + 0.005, (type(ctl).__name__, ideal, bad, fixed)


@pytest.mark.parametrize(("make", "field"), [
    (lambda: bl.SixStep(hall_table=(0.5,) * 5), "control.hall_table"),
    (lambda: bl.Sine(hall_table=[NOMINAL_EDGES[0] + 0.6, *NOMINAL_EDGES[1:]]), "control.hall_table[0]"),
    (lambda: bl.Lu(hall_table=(*NOMINAL_EDGES[:5], math.nan)), "control.hall_table[5]"),
    (lambda: bl.Sine(angle="pll", pll_edges=0.5), "control.pll_edges"),
    (lambda: bl.Lu(hall_angle="kalman"), "control.hall_angle"),
    (lambda: bl.HallCal(revolutions=0), "control.revolutions"),
    (lambda: bl.HallCal(method="hope"), "control.method"),
    (lambda: bl.calibrate_hall(bl.load("htm-48v"), "hope"), "method"),  # type: ignore[arg-type]  # bad on purpose
])
def test_bad_options_name_the_field(make, field):
    with pytest.raises(bl.BldclabError) as exc:
        make()
    assert exc.value.field == field

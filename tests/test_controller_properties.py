"""Every controller, with the parameters Python builds for each catalog drive, under random and extreme
measurements (NaN, inf, huge currents, zero or negative bus, invalid Hall codes, capture-timer jumps): legs in a valid
mode, duties finite and in [0, 1], diagnostics finite, and the safe state where the input is invalid.
(core/firmware/fuzz.c checks the same properties with libFuzzer on fixed C parameters.)"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import bldclab as bl
from bldclab._core import core
from bldclab.errors import PlausibilityWarning

FLAG_SAFE = bl.flag("SAFE")
FLAG_OVERCURRENT = bl.flag("OVERCURRENT")
# a calibrated Hall table (edges up to 25 electrical degrees off nominal) for the Hall options
TABLE = tuple(math.pi / 6 + j * math.pi / 3 + math.radians(d) for j, d in enumerate((25, -25, 10, 0, -7, 3)))
CONTROLS = {"sixv": bl.SixStepVoltage(), "sixstep": bl.SixStep(), "sine": bl.Sine(), "lu": bl.Lu(),
            "rect": bl.Lu(method="rect"), "sixstep-pi": bl.SixStep(regulation="pi", chopping="bipolar"),
            "sine-pll": bl.Sine(angle="pll", pll_edges=1.0, hall_table=TABLE),
            "sixstep-cal": bl.SixStep(hall_angle="pll", hall_table=TABLE + TABLE),
            "lu-pll": bl.Lu(hall_angle="pll", pll_edges=20.0, hall_table=TABLE),
            "hallcal-ol": bl.HallCal(method="open-loop", align_time=0.0), "hallcal-speed": bl.HallCal(),
            "sixstep-timed": bl.SixStep(timed=True, timing="20 deg", timing_time="30 us"),
            "sixstep-enc": bl.SixStep(regulation="duty", timed=True, commutation="encoder", timing="10 deg"),
            "bemf": bl.SixStepSensorless(), "bemf-adc": bl.SixStepSensorless(method="adc", blanking="fixed"),
            "bemf-int": bl.SixStepSensorless(method="integration", chopping="pwm-on-pwm", timing="10 deg",
                                             timing_demag=0.5, misses=2, align_time=0.0, throttle_rate="5 %/ms"),
            "bemf-nocur": bl.SixStepSensorless(current_sensing=False, current_limit="10 A")}
USES_CURRENT = {"sixstep", "sine", "lu", "rect", "sixstep-pi", "sine-pll", "sixstep-cal", "lu-pll", "hallcal-ol",
                "sixstep-timed", "sixstep-enc", "bemf", "bemf-adc", "bemf-int"}
NO_HALL = {"bemf", "bemf-adc", "bemf-int", "bemf-nocur"}  # sensorless: the Hall code is not read
USES_BUS = {"bemf-nocur"}  # the bus is checked without current sensing too

floats = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=32),
                   st.sampled_from([0.0, -0.0, 1e30, -1e30, 50.0, -50.0, 48.0, 300.0, 1e-30]))
ticks = st.integers(min_value=0, max_value=2**32 - 1)
record = st.fixed_dictionaries({
    "i": st.lists(floats, min_size=3, max_size=3), "v_dc": floats, "hall": st.integers(0, 9),
    "n_edges": ticks, "tick_edge": ticks, "tick_now": ticks, "theta": floats, "omega": floats, "ref": floats,
    "omega_ref": floats, "mask": st.sampled_from([3, 5, 6, 7]),
    # back-EMF sensing (read by the sensorless controllers only)
    "zc_state": st.integers(0, 2**32 - 1), "zc_count": st.lists(ticks, min_size=3, max_size=3),
    "zc_tick": st.lists(ticks, min_size=3, max_size=3), "v_term": st.lists(floats, min_size=3, max_size=3),
    "v_neutral": floats, "n_adc": ticks, "tick_adc": ticks})


def _setup(name: str, drive: bl.Drive):
    c = core()
    ctl = CONTROLS[name]
    info = c.controllers[ctl.c_name]
    owner = ctl.c_record(drive, c, 0)  # keeps the arrays the record points to alive
    params = owner.record
    state = c.opaque(info.state)
    assert c.controller_init(info, params, state) == 0
    return c, info, params, state, owner


NAMES = st.sampled_from(sorted(CONTROLS))
MOTORS = st.sampled_from(["htm-48v", "lu-4kw"])
STEPS = st.lists(record, min_size=1, max_size=40)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=NAMES, motor=MOTORS, steps=STEPS)
def test_outputs_finite_bounded_and_safe(name, motor, steps):
    check_outputs(name, motor, steps)


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=NAMES, motor=MOTORS, steps=STEPS)
def test_outputs_finite_bounded_and_safe_many(name, motor, steps):
    check_outputs(name, motor, steps)


def check_outputs(name: str, motor: str, steps: list[dict]) -> None:
    """One controller, fresh from its init, stepped through ``steps``: the properties of the module docstring."""
    drive = bl.load(motor)
    c, info, params, state, _keep = _setup(name, drive)
    inp = c.record("bc_ctrl_in")
    out = c.record("bc_ctrl_out")
    for r in steps:
        inp["i_abc"] = r["i"]
        inp["i_mask"] = r["mask"]
        inp["v_dc"] = r["v_dc"]
        inp["hall"] = r["hall"]
        inp["n_edges"] = r["n_edges"]
        inp["tick_edge"] = r["tick_edge"]
        inp["tick_now"] = r["tick_now"]
        inp["theta_enc"] = r["theta"]
        inp["omega_enc"] = r["omega"]
        inp["ref"] = r["ref"]
        inp["omega_ref"] = r["omega_ref"]
        inp["zc_state"] = r["zc_state"]
        inp["zc_count"] = r["zc_count"]
        inp["zc_tick"] = r["zc_tick"]
        inp["v_term"] = r["v_term"]
        inp["v_neutral"] = r["v_neutral"]
        inp["n_adc"] = r["n_adc"]
        inp["tick_adc"] = r["tick_adc"]
        out[...] = 0
        c.controller_step(info, params, state, inp, out)
        modes = out["leg"]["mode"][0]
        duties = out["leg"]["duty"][0]
        assert np.all((modes >= 0) & (modes <= 3)), modes
        assert np.all(np.isfinite(duties)) and np.all((duties >= 0) & (duties <= 1)), duties
        assert np.all(np.isfinite(out["diag"][0]))
        has_at = int(out["has_at"][0])
        assert has_at in (0, 1), has_at
        if has_at:  # a timed change inside the half period: legs as valid, its time inside it
            modes_at, duties_at = out["leg_at"]["mode"][0], out["leg_at"]["duty"][0]
            assert np.all((modes_at >= 0) & (modes_at <= 3)), modes_at
            assert np.all(np.isfinite(duties_at)) and np.all((duties_at >= 0) & (duties_at <= 1)), duties_at
            t_at = float(out["t_at"][0])
            assert 0.0 <= t_at < 0.5 / drive.inverter.f_pwm, t_at
        hall_bad = r["hall"] in (0, 7, 8, 9)
        bus_bad = not (math.isfinite(r["v_dc"]) and r["v_dc"] > 0)
        cur_bad = any(not math.isfinite(r["i"][x]) for x in range(3) if r["mask"] & (1 << x))
        must_stop = ((hall_bad and name not in NO_HALL) or (name in USES_CURRENT and (bus_bad or cur_bad))
                     or (name in USES_BUS and bus_bad))
        if must_stop:
            assert int(out["flags"][0]) & FLAG_SAFE, (name, r)
            assert np.all(modes == 0) and has_at == 0, (name, r)


@pytest.mark.parametrize("name", ["sixstep", "sine", "lu", "sixstep-pi", "bemf", "hallcal-ol"])
def test_clipped_current_readings_trip_the_software_guard(name: str) -> None:
    """Current sensors whose full scale (``Sensors.current_full_scale``, told to the controller as ``bc_ctrl_in.i_fs``)
    is a quarter of the current asked for: a reading at the full scale trips the input guard (``bc_guard.h`` rule 4:
    the current beyond it is unknown), so the true current stays within what can build up between the sample that
    read the full scale and the legs going off (two samples at most, the runner's one-sample delay: ``2 V_dc T_s /
    L`` above the full scale), far below the inverter's hardware trip that it reached before (3 ``I_N``); duties
    finite and in [0, 1] on every sample."""
    d = bl.load("htm-48v")
    fs = 0.25 * d.motor.I_N
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlausibilityWarning)
        r = bl.simulate(d.replace(sensors__current_full_scale=fs), CONTROLS[name],
                        bl.Scenario(duration=0.05, speed=0.3 * d.Omega_0, ref=d.motor.I_N, trace_every=1))
    for leg in "abc":
        duty = np.asarray(r[f"duty_{leg}"])
        assert np.all(np.isfinite(duty)) and np.all((duty >= 0) & (duty <= 1)), name
    assert int(r.meta["controller_flags"]) & FLAG_OVERCURRENT, name
    assert not any("hardware_trip" in str(w.message) for w in caught), name
    i_true = np.abs(np.stack([np.asarray(r[f"i_{x}"]) for x in "abc"]))
    t_s = 0.5 / d.inverter.f_pwm
    assert fs < np.max(i_true) < fs + 2 * d.inverter.V_dc * t_s / d.motor.L, name

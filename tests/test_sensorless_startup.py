"""Start-up of the sensorless drive over load torque x inertia x initial rotor angle (``startup_grid``).

The physics: in step with the forced commutation the ramp's current gives at most ``k_pair I`` (``2 k_phi I`` for
the trapezoid) and the rotor must be pulled to the ramp's end speed before the hold ends; below the closed-form
bound every start succeeds, above the static torque the ramp's current can give none does and each failure is named.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

import bldclab as bl
from bldclab.analysis.sensorless import (
    START_FAILURES,
    fixed_start,
    pair_torque_constant,
    startup_grid,
    startup_load_bound,
)
from bldclab.errors import BldclabError
from bldclab.model.analytic import r_total


def test_pair_torque_constant_of_the_trapezoid_is_two_k_phi():
    d = bl.load("htm-48v")
    assert pair_torque_constant(d) == pytest.approx(2.0 * d.motor.k_phi, rel=1e-9)


def test_start_succeeds_within_the_bound_and_fails_named_beyond_it():
    d = bl.load("htm-48v")
    ctl = fixed_start(d)
    su = ctl.start_up(d)
    i_ramp = su["ramp_duty"] * d.inverter.V_dc / (2.0 * r_total(d))
    static = pair_torque_constant(d) * i_ramp - d.mechanics.tau_c  # the J -> 0 bound, friction at rest
    inertias = (0.025, 0.05)  # up to the inertia the start-up is set for (see docs/sensorless.md beyond it)
    bounds = [startup_load_bound(d, ctl, inertia=j) for j in inertias]
    assert bounds[1] < bounds[0] < static  # a heavier rotor needs more of the torque to accelerate
    loads = (0.0, 0.75 * min(bounds), 1.2 * static)
    angles = (0.3, 2.5, 4.4)
    res = startup_grid(d, loads, inertias, angles, workers=1)
    df = res.to_pandas()
    assert res.attempts == len(loads) * len(inertias) * len(angles) == len(df)
    within = df[df.load <= df.bound]
    beyond = df[df.load > static]
    assert len(within) == 12 and within.success.all(), within
    assert res.within_bound() == (12, 12)
    assert len(beyond) == 6 and not beyond.success.any()
    assert set(beyond.failure) <= set(START_FAILURES), beyond.failure
    assert beyond.t_closed.isna().all()
    assert (beyond.speed_end < su["ramp_end_speed"]).all()  # the rotor did not follow the ramp
    ok = df[df.success]
    assert (ok.failure == "").all()
    # closed loop after the alignment and within the run
    assert (ok.t_closed > su["align_time"]).all() and (ok.t_closed < ok.duration).all()
    assert su["align_time"] < res.median_time() < df.duration.iloc[0]


def test_grid_does_not_depend_on_the_workers():
    d = bl.load("htm-48v")
    args = (d, (0.0, 20.0), (0.05,), (0.3, 3.0))
    a = startup_grid(*args, workers=1).to_pandas()
    b = startup_grid(*args, workers=2).to_pandas()
    pd.testing.assert_frame_equal(a, b)
    assert list(a.load) == [0.0, 0.0, 20.0, 20.0] and list(a.angle) == [0.3, 3.0, 0.3, 3.0]


@pytest.mark.parametrize(("kw", "field"), [
    ({"load_torques": (-1.0,)}, "load_torques"), ({"inertias": (0.0,)}, "inertias"),
    ({"angles": ()}, "angles"), ({"angles": (math.nan,)}, "angles"), ({"workers": 0}, "workers"),
    ({"throttle": 1.5}, "throttle"), ({"control": bl.SixStep()}, "control"),
])
def test_bad_grid_input_names_the_field(kw, field):
    args = {"load_torques": (0.0,), "inertias": (0.05,), "angles": (0.0,)}
    args.update(kw)
    with pytest.raises(BldclabError) as e:
        startup_grid(bl.load("htm-48v"), **args)
    assert e.value.field == field


def test_fixed_start_keeps_the_settings_of_the_base_drive():
    d = bl.load("htm-48v")
    ctl = fixed_start(d)
    heavy = bl.load("htm-48v")
    heavy = dataclasses.replace(heavy, mechanics=dataclasses.replace(heavy.mechanics, J=4 * d.mechanics.J))
    assert ctl.start_up(heavy) == pytest.approx(ctl.start_up(d))
    assert bl.SixStepSensorless().start_up(heavy)["ramp_time"] > ctl.start_up(heavy)["ramp_time"]
    assert np.isfinite(startup_load_bound(d, ctl))

"""The propeller or fan load ``k_q omega |omega|`` (``Mechanics.k_q``).

The closed-form coast-down and the load's energy are tested in C (core/tests/test_plant.c); here a drone at full
throttle: it settles where the mean electromagnetic torque meets the propeller and the friction, and the energy
taken by the propeller is the load's.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib

import pytest

import bldclab as bl
from bldclab.errors import BldclabError


def test_drone_settles_where_the_propeller_takes_the_torque() -> None:
    d = bl.load("f60prov-2550kv")
    assert d.mechanics.k_q > 0.0
    res = bl.simulate(d, bl.SixStep(regulation="duty", timed=True, timing="20 deg"),
                      bl.Scenario(duration=0.4, ref=1.0, window=(0.35, 0.4), trace=False), check="off")
    m = res.metrics
    om = m.omega_mean
    # steady state: mean torque = k_q omega^2 + B omega (the speed ripple is 1e-4, its second-order effect less)
    load = d.mechanics.k_q * om**2 + d.mechanics.B * om
    assert m.tau_mean == pytest.approx(load, rel=2e-3)
    # the propeller's power is the load's: E_load / window = k_q omega^3 (speed constant to 1e-4)
    assert m.p_load == pytest.approx(d.mechanics.k_q * om**3, rel=2e-3)
    assert 2000.0 < om < d.Omega_0  # a drone's propeller speed, below no-load


def test_motor_file_field_and_errors() -> None:
    d = bl.load("mn3110-780kv")
    data = tomllib.loads(d.to_toml())
    assert data["mechanics"]["k_q"] == pytest.approx(3.15e-7)
    data["mechanics"]["k_q"] = "3.15e-7 N m/(rad/s)^2"
    assert bl.Drive.from_dict(data).mechanics.k_q == pytest.approx(3.15e-7)
    for bad, words in (("-1e-7 N m s^2", ">= 0"), ("1 N m", "unit")):
        data["mechanics"]["k_q"] = bad
        with pytest.raises(BldclabError) as exc:
            bl.Drive.from_dict(data)
        assert exc.value.field == "mechanics.k_q" and words in exc.value.problem
    # without a propeller, files are written as before
    assert "k_q" not in bl.load("htm-48v").to_toml()


def test_imposed_speed_ignores_the_propeller() -> None:
    """At an imposed speed the dynamometer is the load: the same run with and without k_q."""
    d = bl.load("htm-48v")
    om = 0.5 * d.Omega_0
    sc = bl.Scenario(duration=0.02, speed=om, ref=d.motor.I_N, trace=False)
    a = bl.simulate(d, bl.SixStep(), sc)
    b = bl.simulate(d.replace(mechanics=dataclasses.replace(d.mechanics, k_q=1e-3)), bl.SixStep(), sc)
    assert a.metrics.tau_mean == b.metrics.tau_mean
    assert math.isclose(a.metrics.p_load, b.metrics.p_load, abs_tol=1e-12)

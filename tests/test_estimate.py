"""Controllers configured from an estimated drive (parameter mismatch): ``simulate(..., estimate=...)``."""

from __future__ import annotations

import numpy as np
import pytest

import bldclab as bl
from bldclab.analysis.experiments import steady_state
from bldclab.errors import BldclabError


def test_the_plant_as_its_own_estimate_changes_nothing():
    d = bl.load("htm-48v")
    sc = bl.Scenario(duration=0.01, speed=0.4 * d.Omega_0, ref=0.5 * d.T_N, trace=True)
    a = bl.simulate(d, bl.Sine(), sc)
    b = bl.simulate(d, bl.Sine(), sc, estimate=d)
    for name in ("i_a", "i_b", "tau_e", "v_a"):
        np.testing.assert_array_equal(a.signals[name], b.signals[name])
    assert b.meta["estimate"]["name"] == "htm-48v" and a.meta["estimate"] is None


@pytest.mark.parametrize("name", ["htm-48v", "servo-2k2", "outrunner-24v"])
def test_sine_torque_scales_with_the_inverse_back_emf_estimate(name):
    """The d,q controller sets i_q = T_ref / (1.5 p psi_est) and its PI integral removes every steady error of the
    current, so the torque, linear in the back-EMF at given currents, is T_ref psi / psi_est: an estimate k times
    too large gives 1/k of the torque. Resistance and inductance errors (feed-forward and gains only) leave the mean
    torque unchanged."""
    d = bl.load(name)
    w, ref = 0.3 * d.Omega_0, 0.5 * d.T_N
    base, _ = steady_state(d, bl.Sine(), w, ref)
    for k in (0.9, 1.1):
        p, _ = steady_state(d, bl.Sine(), w, ref, estimate=d.scaled(emf=k))
        assert p.tau_mean * k / base.tau_mean == pytest.approx(1.0, abs=2e-3), k
    for kw in ({"R": 0.5}, {"R": 2.0}, {"L": 0.5}, {"L": 2.0}):
        p, _ = steady_state(d, bl.Sine(), w, ref, estimate=d.scaled(**kw))
        assert p.tau_mean / base.tau_mean == pytest.approx(1.0, abs=2e-3), kw
    # and the check can fail: a 10 % back-EMF error is far outside that tolerance
    p, _ = steady_state(d, bl.Sine(), w, ref, estimate=d.scaled(emf=1.1))
    assert abs(p.tau_mean / base.tau_mean - 1.0) > 0.05


def test_scaled_scales_what_it_says():
    d = bl.load("lu-4kw")  # table-shaped back-EMF
    e = d.scaled(R=1.5, L=0.8, emf=1.1)
    assert e.motor.R == pytest.approx(1.5 * d.motor.R) and e.motor.L == pytest.approx(0.8 * d.motor.L)
    th = np.linspace(0, 2 * np.pi, 50)
    np.testing.assert_allclose(e.motor.emf.k_abc(th), 1.1 * d.motor.emf.k_abc(th), rtol=1e-12)
    assert e.motor.p == d.motor.p and e.inverter == d.inverter


@pytest.mark.parametrize(("kw", "field"), [({"R": 0.0}, "scaled.R"), ({"L": -1.0}, "scaled.L"),
                                           ({"emf": float("nan")}, "scaled.emf")])
def test_scaled_refuses_bad_factors(kw, field):
    with pytest.raises(BldclabError) as e:
        bl.load("htm-48v").scaled(**kw)
    assert e.value.field == field


def test_estimate_must_share_pole_pairs_and_pwm_frequency():
    d = bl.load("htm-48v")
    sc = bl.Scenario(duration=0.002, speed=0.3 * d.Omega_0, ref=0.5 * d.T_N)
    for est, field in ((d.replace(motor__p=d.motor.p + 1), "estimate.motor.p"),
                       (d.replace(inverter__f_pwm=2 * d.inverter.f_pwm), "estimate.inverter.f_pwm")):
        with pytest.raises(BldclabError) as e:
            bl.simulate(d, bl.Sine(), sc, estimate=est)
        assert e.value.field == field
    with pytest.raises(BldclabError) as e:
        bl.simulate(d, bl.Sine(), sc, estimate="htm-48v")  # type: ignore[arg-type]
    assert e.value.field == "estimate"

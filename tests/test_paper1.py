"""Paper 1's experiments: friction test, dynamometer measurement (Fig 12), Figs 9 and 11."""

from __future__ import annotations

import math

import numpy as np
import pytest

import bldclab as bl
from bldclab.analysis import paper1
from bldclab.model import analytic as an

HTM = bl.load("htm-48v")


def test_friction_test_measures_the_friction_of_the_set_up():
    speeds = [5.0, 20.0, 60.0]
    fr = paper1.friction_test(HTM, speeds)
    mech = HTM.mechanics
    np.testing.assert_allclose(fr.T_friction, [mech.tau_c + mech.B * w for w in speeds], rtol=1e-9)


def test_dynamometer_with_friction_added_back_measures_the_motor_torque():
    speeds = [0.3 * HTM.Omega_0, 0.8 * HTM.Omega_0]
    d = paper1.dynamometer_test(HTM, bl.SixStep(), HTM.motor.I_N, speeds)
    assert np.all(d.T_dyno < d.T_e)  # the load machine sees less than the motor makes: friction
    np.testing.assert_allclose(d.T_motor, d.T_e, rtol=1e-9)


def test_equivalent_blac_motor_develops_0866_of_the_bldc_nominal_torque():
    blac = paper1.blac_equivalent(HTM)
    k = blac.motor.emf.k_abc(np.linspace(0, 2 * np.pi, 3601))
    assert np.max(np.abs(k)) == pytest.approx(HTM.motor.k_phi, rel=1e-3)  # same peak back-EMF
    point, _ = bl.experiments.steady_state(blac, bl.Sine(handoff_speed=0.05 * HTM.Omega_0), 0.8 * HTM.Omega_0,
                                           math.sqrt(3) / 2 * HTM.T_N)
    assert point.tau_mean / HTM.T_N == pytest.approx(math.sqrt(3) / 2, abs=0.005)
    assert point.ripple_sampled / HTM.T_N < 0.01  # sinusoidal back-EMF and current: no ripple but PWM
    assert point.metrics.i_peak[0] == pytest.approx(2 / math.sqrt(3) * HTM.motor.I_N, rel=0.03)


@pytest.mark.slow
def test_figures_draw(tmp_path):
    for name, fig in (("fig9", paper1.fig9(HTM)), ("fig11", paper1.fig11(HTM))):
        fig.savefig(tmp_path / f"{name}.png")
        assert (tmp_path / f"{name}.png").stat().st_size > 20_000
    fig, data = paper1.fig12(HTM, (0.3, 0.9))
    assert set(data.supply) == {"sine", "square"}
    sine = data[data.supply == "sine"].set_index("Omega_pu")
    # below the sinusoidal base speed the measured torque is the nominal (13) less the R effect (< 1 %)
    assert sine.loc[0.3, "T_motor"] / HTM.T_N == pytest.approx(an.T_SN_PU, rel=0.01)

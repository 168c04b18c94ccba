"""Paper 1's ideal current limiter (``SixStep(regulation="ideal")`` on the averaged inverter).

Paper 1's square-wave closed forms (26)-(33) assume a current limiter infinitely faster than the commutation: the
incoming phase's current driven at full voltage until it reaches the reference, then held there while the voltage
allows. The plant realises it in continuous time (``BC_LEG_HOLD``), so on a back-EMF that meets the closed forms'
premise (a trapezoid whose flat top holds the commutation, R = 0) the simulated torque must equal them to the
integration error, however few PWM periods a commutation spans: the property a sampled controller only approaches.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import bldclab as bl
from bldclab.errors import BldclabError
from bldclab.model import analytic
from bldclab.model.catalog.synthetic import paper1_drive
from bldclab.model.emf import BackEmf, Trapezoid

IDEAL = bl.SixStep(regulation="ideal", commutation="encoder", timed=True)
FLAT_160 = math.radians(160.0)


def premise_drive(theta_m: float, p: int, f_pwm: float, R: float = 0.0) -> bl.Drive:
    """A drive on (26)-(33)'s premise: 160-degree flat top (the commutation on the flat tops), averaged inverter."""
    d = paper1_drive(theta_m, p=p, V_N=48.0, I_N=20.0, Omega_0=300.0, R=R, f_pwm=f_pwm)
    return dataclasses.replace(d, motor=dataclasses.replace(d.motor, emf=BackEmf.symmetric(Trapezoid(d.motor.k_phi,
                                                                                                     FLAT_160))),
                               inverter=dataclasses.replace(d.inverter, model="average"))


def run_ideal(d: bl.Drive, w: float, periods: int = 3, **kw: object) -> bl.SimResult:
    om = w * d.Omega_0
    te = 2.0 * math.pi / (d.motor.p * om)
    sc = bl.Scenario(duration=(periods + 2) * te, speed=om, ref=d.motor.I_N, window=(2 * te, (periods + 2) * te),
                     theta0=0.3, **kw)
    return bl.simulate(d, IDEAL, sc, check="off")


def pu(d: bl.Drive, res: bl.SimResult) -> tuple[float, float]:
    m = res.metrics
    return m.tau_mean / d.T_N, (m.tau_max - m.tau_min) / d.T_N


@settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(theta_m=st.floats(0.01, 0.2), p=st.integers(1, 12), w=st.floats(0.05, 0.97),
       pwm_per_commutation=st.floats(0.2, 50.0))
def test_meets_26_to_33_at_any_pwm_rate(theta_m: float, p: int, w: float, pwm_per_commutation: float) -> None:
    """Mean torque and ripple equal (26)-(33) to 1e-4 p.u. (saturation: 5e-4), 0.2 to 50 PWM periods/commutation."""
    t_c = 3.0 * theta_m / (p * 300.0 * (1.0 + w))  # the outgoing current's fall (paper 1, IV.A)
    d = premise_drive(theta_m, p, pwm_per_commutation / t_c)
    wb = analytic.omega_qB_pu(theta_m)
    if min(abs(w - 0.5), abs(w - wb)) < 0.01:
        return  # a kink of the closed forms: the period-mean torque there is continuous, its extremes are not
    T, TR = pu(d, run_ideal(d, w))
    T_cf, TR_cf = float(analytic.t_q_pu(w, theta_m)), float(analytic.tr_q_pu(w, theta_m))
    tol = 1e-4 if w < wb else 5e-4
    assert T == pytest.approx(T_cf, abs=tol)
    assert TR == pytest.approx(TR_cf, abs=tol)


def test_a_sampled_controller_misses_what_the_limiter_holds() -> None:
    """One PWM period per commutation: the predictive controller is 0.02+ p.u. off (27), the limiter is not."""
    theta_m, w = 0.1, 0.3
    t_c = 3.0 * theta_m / (4 * 300.0 * (1.0 + w))
    d = premise_drive(theta_m, 4, 1.0 / t_c)
    _, tr_ideal = pu(d, run_ideal(d, w))
    om = w * d.Omega_0
    te = 2.0 * math.pi / (d.motor.p * om)
    res = bl.simulate(d, bl.SixStep(commutation="encoder", timed=True),
                      bl.Scenario(duration=5 * te, speed=om, ref=d.motor.I_N, window=(2 * te, 5 * te), theta0=0.3),
                      check="off")
    _, tr_pred = pu(d, res)
    tr_cf = float(analytic.tr_q_pu(w, theta_m))
    assert tr_ideal == pytest.approx(tr_cf, abs=1e-5)
    assert abs(tr_pred - tr_cf) > 0.02


def test_energy_balance_and_step_convergence() -> None:
    """With R, the held duty's power flows close the balance; halving the steps changes nothing visible."""
    d = bl.load("htm-48v")
    d = d.replace(inverter=dataclasses.replace(d.inverter, model="average", R_src=0.0))
    for w in (0.2, 0.6, 0.9):
        a = run_ideal(d, w)
        assert abs(a.metrics.balance_electrical) < 1e-7
        b = run_ideal(d, w, h_max=0.25 / d.inverter.f_pwm)
        assert a.metrics.tau_mean == pytest.approx(b.metrics.tau_mean, rel=1e-8)
        assert a.metrics.tau_max - a.metrics.tau_min == pytest.approx(b.metrics.tau_max - b.metrics.tau_min,
                                                                      abs=1e-6 * d.T_N)


def test_held_current_is_the_reference() -> None:
    """Between commutations the incoming phase's current is the reference exactly; the duty stays in [0, 1]."""
    d = premise_drive(0.05, 4, 20e3)
    res = run_ideal(d, 0.3, periods=1, trace_sub=4)
    i = np.stack([res["i_a"], res["i_b"], res["i_c"]])
    hold = [np.asarray(res[f"mode_{x}"]) == 4 for x in "abc"]
    held = np.concatenate([np.abs(i[x][hold[x]]) for x in range(3)])
    # at the sample instants inside a held stretch the current is within rounding of I_N or below it (driven up)
    assert held.max() <= d.motor.I_N * (1 + 1e-9)
    assert np.mean(np.isclose(held, d.motor.I_N, rtol=1e-9)) > 0.9
    for x in "abc":
        duty = np.asarray(res[f"duty_{x}"])
        assert duty.min() >= 0.0 and duty.max() <= 1.0


@pytest.mark.parametrize(("change", "words"), [
    ({"model": "switching"}, "inverter.model = 'average'"),
    ({"model": "average", "R_src": 0.1}, "R_src = 0"),
])
def test_refused_where_it_has_no_meaning(change: dict[str, object], words: str) -> None:
    d = bl.load("htm-48v")
    d = d.replace(inverter=dataclasses.replace(d.inverter, **change))
    with pytest.raises(BldclabError) as exc:
        bl.simulate(d, IDEAL, bl.Scenario(duration=0.01, speed=30.0, ref=10.0))
    assert exc.value.field == "control.regulation" and words in exc.value.problem


def test_commutation_periods_is_the_outgoing_current_fall() -> None:
    """The premise's count is the simulated fall of the outgoing current, in PWM periods (R = 0).

    Above W = 0.5 the outgoing current falls under full voltage all the way: ``3 L I_N / (V (1 + W))``, the premise's
    count. Below, the incoming current reaches ``I_N`` first and the limiter then slows the fall: in all
    ``L I_N / (2 E)`` with ``E = W V / 2`` (from the three phase equations with the incoming current held).
    """
    d = premise_drive(0.1, 2, 40e3)
    V, L, i_n = d.inverter.V_dc, d.motor.L, d.motor.I_N
    for w, t_expect in ((0.7, 3.0 * L * i_n / (V * 1.7)), (0.4, L * i_n / (0.4 * V))):
        res = run_ideal(d, w, periods=1, trace_sub=16)
        t = np.asarray(res["t"])
        i_b = np.asarray(res["i_b"])
        # a+b- -> a+c- at theta_e = pi/2 (conventions.md): the first such instant in the window, from theta(t)
        pw = d.motor.p * w * d.Omega_0
        n = math.ceil((res.metrics.t0 * pw + 0.3 - math.pi / 2) / (2 * math.pi))
        t_comm = (math.pi / 2 - 0.3 + 2 * math.pi * n) / pw
        k = int(np.argmax((t > t_comm) & (i_b == 0.0)))  # first row with the outgoing current out
        slope = (i_b[k - 1] - i_b[k - 2]) / (t[k - 1] - t[k - 2])
        t_zero = t[k - 1] - i_b[k - 1] / slope
        assert t_zero - t_comm == pytest.approx(t_expect, rel=2e-3), w
    assert analytic.commutation_periods(d, 0.7) == pytest.approx(3.0 * L * i_n / (V * 1.7) * d.inverter.f_pwm)
    line, few = analytic.commutation_premise(d)
    assert not few and f"{analytic.commutation_periods(d, 0.0):.3g} PWM periods" in line
    slow = dataclasses.replace(d, inverter=dataclasses.replace(d.inverter, f_pwm=2e3))
    line, few = analytic.commutation_premise(slow)
    assert few and "at every speed" in line

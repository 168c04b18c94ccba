"""Paper 1's closed forms hold on drives drawn at random, not only on the study case (hypothesis).

In the averaged-inverter model with R = 0 (the closed forms' premises: ideal current limiter, no PWM ripple, R
neglected) the simulated mean torque must be within 0.005 p.u. of (13)/(24) and (26)/(28)/(32), and the
instantaneous torque ripple within 0.02 of (15)/(25) and (27)/(29)/(33); in the switching model the mean torque
must be within 0.01 p.u. of the averaged one. Drives: ``Theta_m`` 0.01 to 0.2 rad, 1 to 20 pole pairs, 12 to
600 V, 1 to 200 A, no-load speeds 20 to 2000 rad/s, 5 to 200 PWM periods per commutation
(``tests/generalisation.py``; the square wave on a trapezoid whose flat top holds the commutation, the premise of
(26)-(33)). The examples are derandomised (CI runs the same ones every time); ``benchmarks/random_drives.py`` runs
many more, also on the 120-degree shape, and prints the worst deviation per quantity.
"""

from __future__ import annotations

import dataclasses
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bldclab.analysis.experiments import base_speed
from bldclab.model import analytic
from generalisation import FLAT_TOP_SQUARE, TWO_PI, Case, cases, describe, mean_torque_switching, run

T_TOL = 0.005
TR_TOL = 0.02
SWITCHING_TOL = 0.01
#: Speeds closer than this to a closed-form corner (a base speed, or W = 0.5 where (27) and (29) meet) are left
#: out: there the closed forms have a kink that a sampled controller rounds off over a few samples.
CORNER = 0.02

#: the development subset (``pytest -m "not slow"``): a few drives; the ``slow`` tests run many more
FEW = settings(max_examples=5, deadline=None, derandomize=True,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
FAST = settings(max_examples=40, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
SLOW = settings(max_examples=150, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


def away_from_corners(case: Case) -> bool:
    """True if the speed is clear of the closed forms' corners for this Theta_m."""
    th = case.Theta_m
    corners = (0.5, analytic.omega_sB_pu(th), analytic.omega_qB_pu(th))
    return all(abs(case.speed_pu - c) > CORNER for c in corners)


def check_closed_forms(case: Case) -> None:
    out = run(case, "average")
    msg = describe(case)
    assert math.isclose(out.T_q, out.T_q_cf, abs_tol=T_TOL), f"square mean torque {out.T_q} vs {out.T_q_cf}: {msg}"
    assert math.isclose(out.T_s, out.T_s_cf, abs_tol=T_TOL), f"sine mean torque {out.T_s} vs {out.T_s_cf}: {msg}"
    assert math.isclose(out.TR_q, out.TR_q_cf, abs_tol=TR_TOL), f"square ripple {out.TR_q} vs {out.TR_q_cf}: {msg}"
    assert math.isclose(out.TR_s, out.TR_s_cf, abs_tol=TR_TOL), f"sine ripple {out.TR_s} vs {out.TR_s_cf}: {msg}"


@FEW
@given(cases().filter(away_from_corners))
def test_averaged_model_meets_paper1_closed_forms_on_random_drives(case: Case) -> None:
    check_closed_forms(case)


@pytest.mark.slow
@SLOW
@given(cases().filter(away_from_corners))
def test_averaged_model_meets_paper1_closed_forms_on_many_random_drives(case: Case) -> None:
    check_closed_forms(case)


@pytest.mark.slow
@FAST
@given(cases(), st.sampled_from(["square", "sine"]))
def test_switching_mean_torque_is_within_a_hundredth_of_the_averaged_one(case: Case, supply: str) -> None:
    avg, sw = mean_torque_switching(case, supply)
    assert math.isclose(sw, avg, abs_tol=SWITCHING_TOL), f"{supply}: switching {sw} vs averaged {avg}: {describe(case)}"


BASE_TOL = 0.003


def check_base_speeds(case: Case) -> None:
    """Simulated base speeds (paper 1's definitions, with R) against the R-aware numeric solution of the circuit,
    and at R = 0 the numeric solution against (21)/(30)."""
    for supply, flat_top, numeric, closed in (
            ("square", FLAT_TOP_SQUARE, analytic.omega_qB_numeric_pu, analytic.omega_qB_pu),
            ("sine", TWO_PI / 3.0, analytic.omega_sB_numeric_pu, analytic.omega_sB_pu)):
        drive = case.drive("average", flat_top)
        w_num = numeric(drive)
        w_sim = base_speed(drive, supply)
        assert abs(w_sim - w_num) <= BASE_TOL, f"{supply}: simulated {w_sim} vs numeric {w_num}: {describe(case)}"
        if case.r_share == 0.0:
            w_cf = closed(case.Theta_m)
            assert abs(w_num - w_cf) <= BASE_TOL, f"{supply}: numeric {w_num} vs closed form {w_cf}: {describe(case)}"


def base_cases(r_max: float) -> st.SearchStrategy[Case]:
    """Drives for the base-speed search: the carrier is set for commutations at 0.9 Omega_0."""
    return cases(r_max=r_max, pwm_max=60.0).map(lambda c: dataclasses.replace(c, speed_pu=0.9))


@pytest.mark.slow
@settings(max_examples=6, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(base_cases(r_max=0.0) | base_cases(r_max=0.08))
def test_simulated_base_speeds_match_the_circuit_solution_on_random_drives(case: Case) -> None:
    check_base_speeds(case)


@pytest.mark.slow
@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(base_cases(r_max=0.0) | base_cases(r_max=0.08))
def test_simulated_base_speeds_match_the_circuit_solution_on_many_random_drives(case: Case) -> None:
    check_base_speeds(case)

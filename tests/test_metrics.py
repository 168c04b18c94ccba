"""Window metrics of the torque: exact instantaneous extremes, the continuous PWM-period moving average, the
controller-sample view; PWM-grid phase; the simulated base speed.

Every check compares the C metrics with something computed independently: a finely sampled trace (whose rows hold
the exact integral of the torque over each row), a step-size refinement, or a case whose answer is known (a DC
operating point whose PWM-period average is constant).
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

import bldclab as bl
from bldclab.analysis.compare import default_controls
from bldclab.analysis.experiments import base_speed, base_speed_margin, steady_state
from bldclab.model import analytic as an

HTM = bl.load("htm-48v")
LU = bl.load("lu-4kw")


def pwm_ma(res: bl.SimResult, sub: int) -> tuple[np.ndarray, np.ndarray]:
    """Brute-force one-PWM-period moving average from a trace of ``sub`` rows per sample (N m), and its times (s).

    The rows' ``tau_mean`` times their length is the exact integral of the torque over each row, so the running sum
    gives the integral ``A`` at every row boundary and ``(A(t) - A(t - T)) / T`` exactly there.
    """
    m = res.metrics
    assert m is not None
    sel = (res.t >= m.t0 - 1e-12) & (res.t < m.t1 - 1e-12)
    dt = float(np.median(np.diff(res.t[sel])))
    A = np.concatenate([[0.0], np.cumsum(res.tau_mean[sel]) * dt])
    t = res.t[sel][0] + dt * np.arange(len(A))
    n_T = 2 * sub  # rows per PWM period: two samples, `sub` rows each
    return (A[n_T:] - A[:-n_T]) / (n_T * dt), t[n_T:]


# ---------------------------------------------------------------------------------------------------------------
# exact extremes of the instantaneous torque


@pytest.mark.parametrize(("drive", "supply", "w"), [(LU, "square", 0.5),
                                                    pytest.param(HTM, "square", 0.3, marks=pytest.mark.slow),
                                                    (HTM, "sine", 0.5),
                                                    pytest.param(LU, "sine", 0.3, marks=pytest.mark.slow)])
def test_extremes_bound_a_fine_trace_within_its_resolution(drive, supply, w):
    """The exact extremes are never inside a 128-rows-per-PWM-period trace's, and beyond them by at most one row's
    torque change; a 4x finer trace closes most of the gap (the extremes sit between its rows)."""
    control, ref = default_controls(drive)[supply]
    gaps = []
    for sub in (64, 256):
        pt, res = steady_state(drive, control, w * drive.Omega_0, ref, trace=True, trace_sub=sub)
        m = pt.metrics
        sel = (res.t >= m.t0) & (res.t <= m.t1)
        tau = res.tau_e[sel]
        step = float(np.max(np.abs(np.diff(tau))))
        assert m.tau_max >= tau.max() - 1e-9 * drive.T_N
        assert m.tau_min <= tau.min() + 1e-9 * drive.T_N
        assert m.tau_max - tau.max() <= step and tau.min() - m.tau_min <= step
        gaps.append(max(m.tau_max - tau.max(), tau.min() - m.tau_min))
    assert gaps[1] < 0.5 * gaps[0]


def shorted_drive() -> tuple[bl.Drive, bl.OpenLoop, bl.Scenario]:
    """htm-48v at 2 kHz with every lower switch on at 0.3 p.u. (trip disabled): the short-circuit currents make a
    smooth braking torque whose extremes fall inside the 250 us RK4 steps, not only on their ends."""
    drive = HTM.replace(inverter__f_pwm=2000.0, inverter__i_trip=0.0)
    om = 0.3 * drive.Omega_0
    Te = 2 * math.pi / (drive.motor.p * om)
    n = math.ceil(8 * Te * 2 * drive.inverter.f_pwm) + 2
    control = bl.OpenLoop(np.ones((n, 3), int), np.zeros((n, 3)))
    return drive, control, bl.Scenario(duration=8 * Te, speed=om, window=(6 * Te, 8 * Te), trace=True)


def test_extremes_converge_at_fourth_order_with_the_step():
    drive, control, sc = shorted_drive()
    th = 0.5 / drive.inverter.f_pwm
    ref = bl.simulate(drive, control, dataclasses.replace(sc, h_max=th / 256)).metrics
    errs = []
    for h in (th, th / 2, th / 4, th / 8):
        m = bl.simulate(drive, control, dataclasses.replace(sc, h_max=h)).metrics
        errs.append(max(abs(m.tau_max - ref.tau_max), abs(m.tau_min - ref.tau_min)))
    ripple = ref.tau_max - ref.tau_min
    assert errs[0] < 1e-5 * ripple
    for a, b in itertools.pairwise(errs[:3]):
        assert b < a / 8.0  # 4th order: 16x per halving
    # the torque at the samples alone (the step ends there) misses the smooth extremes by far more
    res = bl.simulate(drive, control, sc)
    sel = res.t >= ref.t0
    assert ref.tau_min < res.tau_e[sel].min() - 100 * errs[0]


# ---------------------------------------------------------------------------------------------------------------
# continuous PWM-period moving average


def test_moving_average_of_a_pure_pwm_ripple_is_flat():
    """At standstill with constant duties the currents are DC plus PWM ripple: the one-period average is constant at
    every instant, not only on the sample grid."""
    th = 0.5 / HTM.inverter.f_pwm
    n = math.ceil(0.04 / th) + 2
    control = bl.OpenLoop(np.ones((n, 3), int), np.tile([0.55, 0.45, 0.5], (n, 1)))
    m = bl.simulate(HTM, control, bl.Scenario(duration=0.04, speed=0.0, theta0=0.3, window=(0.035, 0.04),
                                              trace=False)).metrics
    assert m.ripple > 0.01 * m.tau_mean  # a real PWM ripple on the instantaneous torque
    assert m.ripple_ma < 1e-6 * m.ripple
    assert m.tau_ma_min <= m.tau_mean <= m.tau_ma_max
    assert m.ma_lost == 0


@pytest.mark.parametrize(("drive", "supply", "w"), [(LU, "square", 0.5), (HTM, "square", 0.2), (HTM, "sine", 0.8),
                                                    (LU, "sine", 0.5)])
def test_continuous_moving_average_is_the_brute_force_one_and_bounds_the_grid(drive, supply, w):
    control, ref = default_controls(drive)[supply]
    pt, res = steady_state(drive, control, w * drive.Omega_0, ref, trace=True, trace_sub=16)
    m = pt.metrics
    ma, _t = pwm_ma(res, 16)
    tol = 1e-9 * drive.T_N
    # every brute-force value lies within the continuous extremes, which it reaches within its resolution
    assert m.tau_ma_min <= ma.min() + tol and ma.max() <= m.tau_ma_max + tol
    res_ma = float(np.max(np.abs(np.diff(ma))))
    assert ma.min() - m.tau_ma_min <= res_ma and m.tau_ma_max - ma.max() <= res_ma
    # the sample-grid average is a subset of the same function
    assert m.tau_ma_min <= m.tau_ma_grid_min + tol and m.tau_ma_grid_max <= m.tau_ma_max + tol
    assert m.ma_lost == 0


def test_history_overflow_is_counted_not_hidden():
    """A step 1/2400 of a PWM period puts more step ends in one period than the runner keeps (BC_SIM_HIST = 1024):
    the evaluations whose past is gone are skipped and counted; with none left the average is nan, not a guess."""
    control, ref = default_controls(HTM)["square"]
    T = 1.0 / HTM.inverter.f_pwm
    sc = {"duration": 0.004, "speed": 0.3 * HTM.Omega_0, "ref": ref, "window": (0.002, 0.004), "trace": False}
    ok = bl.simulate(HTM, control, bl.Scenario(**sc, h_max=T / 400)).metrics
    lost = bl.simulate(HTM, control, bl.Scenario(**sc, h_max=T / 1200)).metrics
    assert ok.ma_lost == 0 and math.isfinite(ok.ripple_ma)
    assert lost.ma_lost > 1000 and math.isnan(lost.ripple_ma)
    assert lost.ripple_ma_grid == pytest.approx(ok.ripple_ma_grid, rel=1e-6)  # the sample-grid average is unaffected


def test_short_commutation_dip_is_caught_by_the_moving_average_and_missed_by_the_samples():
    """lu-4kw (300 V, 0.29 mH, 10 kHz) at 0.5 p.u.: the commutation lasts under one PWM period. Its torque dip falls
    between the controller samples; the continuous average sees it, at a Hall edge, as does the brute force."""
    control, ref = default_controls(LU)["square"]
    pt, res = steady_state(LU, control, 0.5 * LU.Omega_0, ref, trace=True, trace_sub=64)
    m = pt.metrics
    T_N, T = LU.T_N, 1.0 / LU.inverter.f_pwm
    ma, t = pwm_ma(res, 64)
    assert ma.min() < m.tau_s_min - 0.05 * T_N  # the dip is real (brute force) and below every sample
    assert m.tau_ma_min == pytest.approx(ma.min(), abs=1e-6 * T_N)
    assert m.ripple_ma > 1.4 * m.ripple_sampled
    # where: centred within a quarter period of a commutation (a Hall edge seen by the controller)
    edges = res.t[np.nonzero(np.diff(res.hall))[0] + 1]
    centre = t[int(np.argmin(ma))] - T / 2
    assert np.min(np.abs(edges - centre)) < 0.25 * T


# ---------------------------------------------------------------------------------------------------------------
# PWM-grid phase


def locked_speed(drive: bl.Drive, n: int) -> float:
    """Mechanical speed (rad/s) at which an electrical period is exactly n PWM periods (the grid locks to the rotor)."""
    return 2 * math.pi * drive.inverter.f_pwm / (n * drive.motor.p)


def test_pwm_phase_matters_where_the_grid_locks_to_the_rotor():
    """lu-4kw, square wave, an electrical period of exactly 120 PWM periods (commutation shorter than a PWM period):
    where the carrier falls relative to the rotor moves the mean torque and the averaged ripple; the phases' mean is
    reported with the range, and phase 0 is the plain run. On htm-48v, whose commutation spans many PWM periods, the
    same lock moves the mean torque by less than 0.001 p.u. (before the commutation advance stopped stepping back,
    htm-48v at 165 PWM periods showed 0.067 p.u. here: the back-steps, not the grid, made that spread)."""
    control, ref = default_controls(LU)["square"]
    om = locked_speed(LU, 120)
    pt, _ = steady_state(LU, control, om, ref, pwm_phases=4)
    lo, hi = pt.tau_mean_range
    assert pt.pwm_phases == 4
    assert (hi - lo) / LU.T_N > 0.003
    assert (pt.ripple_ma_range[1] - pt.ripple_ma_range[0]) / LU.T_N > 0.02
    assert lo <= pt.tau_mean <= hi
    single, _ = steady_state(LU, control, om, ref)
    assert single.tau_mean_range == (single.tau_mean, single.tau_mean)
    assert pt.metrics.tau_mean == single.tau_mean  # phase 0 is the default run
    sq, ref_h = default_controls(HTM)["square"]
    locked, _ = steady_state(HTM, sq, locked_speed(HTM, 165), ref_h, pwm_phases=4)
    assert locked.spread_pu("tau_mean", HTM.T_N) < 0.001
    # off the locked ratio the measured periods sweep the phase themselves: a small spread
    pt2, _ = steady_state(HTM, sq, 0.89 * HTM.Omega_0, ref_h, pwm_phases=4)
    assert pt2.spread_pu("tau_mean", HTM.T_N) < 0.002


def test_pwm_phases_must_be_a_positive_integer():
    control, ref = default_controls(HTM)["square"]
    for bad in (0, -1, 1.5, True):
        with pytest.raises(bl.BldclabError, match="pwm_phases"):
            steady_state(HTM, control, 0.5 * HTM.Omega_0, ref, pwm_phases=bad)


# ---------------------------------------------------------------------------------------------------------------
# simulated base speed (htm-48v's own checks against (21), (30) and the numeric values are in test_sixstep.py and
# test_sine.py, which use the same function)


@pytest.mark.parametrize("supply", ["square", "sine"])
def test_simulated_base_speed_of_htm_is_the_r_aware_numeric_one(supply):
    num = an.omega_qB_numeric_pu(HTM) if supply == "square" else an.omega_sB_numeric_pu(HTM)
    closed = an.omega_qB_pu(an.theta_m(HTM)) if supply == "square" else an.omega_sB_pu(an.theta_m(HTM))
    wb = base_speed(HTM, supply)
    assert wb == pytest.approx(num, abs=0.003)
    assert closed - wb > 0.07  # R = 50 mOhm costs 0.08 p.u. against (21) / (30)
    # the margin changes sign across it
    assert base_speed_margin(HTM, supply, wb - 0.01) >= 0.0 > base_speed_margin(HTM, supply, wb + 0.01)


@pytest.mark.parametrize("supply", [pytest.param("square", marks=pytest.mark.slow), "sine"])
def test_simulated_base_speed_of_lu4kw_is_at_the_no_load_speed(supply):
    """lu-4kw (0.29 mH, 300 V): Theta_m is small and the rounded back-EMF reaches its line peak at isolated angles,
    so both supplies hold their current up to about Omega_0, as the numeric computation says."""
    num = an.omega_qB_numeric_pu(LU) if supply == "square" else an.omega_sB_numeric_pu(LU)
    assert base_speed(LU, supply) == pytest.approx(num, abs=0.005)


def test_base_speed_bad_supply_is_named():
    with pytest.raises(bl.BldclabError, match="supply"):
        base_speed(HTM, "trapezoid")


# ---------------------------------------------------------------------------------------------------------------
# efficiency in the direction of the power flow


def test_efficiency_follows_the_power_flow_and_is_undefined_when_both_sides_feed_the_machine():
    """Motoring: shaft over bus power; generating (a braking current at speed, the bus receives): bus over shaft
    power, both closing the energy balance with the losses (1 - eta = losses / input); both sides feeding the
    machine (a six-step duty below the line back-EMF's, so the rotor drives current against the bus's pulses: every
    watt ends as loss) has no efficiency: nan and said so, where it read a negative number (-2.1 here, -14 in a
    user's run)."""
    w = 0.5 * HTM.Omega_0
    ctl = bl.SixStep()
    for ref, flow in ((20.0, "motoring"), (-20.0, "generating")):
        m = steady_state(HTM, ctl, w, ref)[0].metrics
        losses = m.p_Rsrc + m.p_cu + m.p_sw + m.p_diode + m.p_swloss + m.p_rr + m.p_fric + m.p_fe
        p_in = m.p_src_total if flow == "motoring" else -m.p_shaft
        assert m.power_flow == flow
        assert 0.5 < m.efficiency < 1.0
        assert abs((1.0 - m.efficiency) - losses / p_in) < 1e-3 * (1.0 + losses / p_in)  # dW_L: a periodic window
    m = steady_state(HTM, bl.SixStepVoltage(), 0.2 * HTM.Omega_0, 0.05)[0].metrics
    assert m.p_src_total > 0.0 and m.p_shaft < 0.0
    assert m.power_flow == "dissipating" and math.isnan(m.efficiency)
    losses = m.p_Rsrc + m.p_cu + m.p_sw + m.p_diode + m.p_swloss + m.p_rr + m.p_fric + m.p_fe
    assert math.isclose(m.p_src_total - m.p_shaft, losses, rel_tol=1e-3)  # every watt in, from both sides, is lost

"""bldclab.analytic: paper 1's numbers, the maths behind the closed forms, the R-aware base speeds."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import solve_ivp

import bldclab
from bldclab import BackEmf, BldclabError, Fourier, Sinusoid, Table, Trapezoid
from bldclab.model import analytic as an
from bldclab.model.emf import TWO_PI


@pytest.fixture(scope="module")
def htm() -> bldclab.Drive:
    return bldclab.load("htm-48v")


@pytest.fixture(scope="module")
def t1(htm: bldclab.Drive) -> an.Table1:
    return an.table1(htm)


# ------------------------------------------------------------------------------------------------------------
# the paper's numbers for the study case, from the formulas (Table I, (13), (15), (36), (43), (44))


def test_table1_paper_numbers(t1: an.Table1) -> None:
    assert t1.Theta_m == pytest.approx(0.046875, abs=1e-15)  # 8 * 75e-6 * 50 / (2 * 0.32)
    assert round(t1.Theta_m * 1e3, 1) == 46.9
    assert round(t1.Omega_sB_pu, 3) == 0.955
    assert round(t1.Omega_qB_pu, 3) == 0.957
    assert round(t1.T_qB_pu, 3) == 0.766
    assert round(t1.T_qB_pu, 2) == 0.77  # as printed in Table I
    assert round(t1.T_sN_pu, 3) == 1.053
    assert round(t1.TR_sN_pu, 3) == 0.155
    assert round(t1.P_R_pu, 3) == 0.058
    assert round(t1.eta_ratio_0955, 3) == 1.052
    assert round(t1.eta_ratio_0455, 3) == 1.014
    assert t1.T_blac_N_pu == pytest.approx(0.866, abs=5e-4)
    assert t1.cond_18
    assert t1.Omega_0 == pytest.approx(75.0)
    assert t1.T_N == pytest.approx(32.0)


def test_bases_and_ratings(htm: bldclab.Drive) -> None:
    # (2), (3), (6), (8) against the motor data of Table II
    assert an.omega_0(htm) == pytest.approx(48.0 / 0.64)
    assert an.omega_N(htm) == pytest.approx((48.0 - 2 * 0.05 * 50.0) / 0.64)
    assert an.omega_N(htm) * 60 / TWO_PI == pytest.approx(640.0, abs=2.0)  # Table II: 640 rpm
    assert an.e_N(htm) == pytest.approx(0.32 * an.omega_N(htm))
    assert an.t_N(htm) == pytest.approx(32.0)  # Table II: rated torque 32 N m
    assert an.i_sN(htm) == pytest.approx(57.735, abs=1e-3)  # "I_s,N (58 A)"
    # (7): equal rms currents
    assert math.sqrt(2 / 3) * 50.0 == pytest.approx(an.i_sN(htm) / math.sqrt(2))


def test_nominal_torque_sinusoidal_si_and_pu(htm: bldclab.Drive) -> None:
    # (11) P = T Omega at nominal speed; (12) over (6) is (13)
    assert an.p_sN(htm) == pytest.approx(an.t_sN(htm) * an.omega_N(htm))
    assert an.t_sN(htm) / an.t_N(htm) == pytest.approx(an.T_SN_PU, rel=1e-14)
    assert an.tr_sN(htm) == pytest.approx(an.TR_SN_PU * 32.0)
    assert an.t_sN_pu() == an.T_SN_PU and an.tr_sN_pu() == an.TR_SN_PU


# ------------------------------------------------------------------------------------------------------------
# the maths behind the closed forms


def test_e1_fourier_of_trapezoid(htm: bldclab.Drive) -> None:
    """(10): the fundamental of the 120-degree trapezoid is 12/pi^2 of its flat top."""
    shape = htm.motor.emf.shapes[0]
    a, b = shape.fourier(5)
    assert b[1] == pytest.approx(float(an.e_1(0.32)), rel=1e-12)
    assert abs(a[1]) < 1e-12
    # independent: quadrature of k(theta) sin(theta) over a period
    th = np.linspace(0.0, TWO_PI, 200_001)
    b1 = np.trapezoid(shape(th) * np.sin(th), th) / math.pi
    assert b1 == pytest.approx(12 / math.pi**2 * 0.32, rel=1e-8)
    # the 5th harmonic is not 0, so a sinusoidal current does produce ripple
    assert abs(b[5]) > 0.01 * b[1]


def _torque_sinusoidal(drive: bldclab.Drive, th: np.ndarray) -> np.ndarray:
    """tau(theta) = sum_x k_x i_x with balanced sinusoidal currents of peak I_s,N (paper 1 (5), (9))."""
    k = drive.motor.emf.k_abc(th)
    i = np.stack([an.i_sN(drive) * np.sin(th - x * TWO_PI / 3) for x in range(3)])
    return np.sum(k * i, axis=0)


def test_torque_and_ripple_sinusoidal_by_direct_evaluation(htm: bldclab.Drive) -> None:
    """(12)-(15) from sum e_x i_x over a period: mean, peak-to-peak, and where the extremes sit."""
    th = np.linspace(0.0, TWO_PI, 72_001)  # holds every multiple of pi/6
    tau = _torque_sinusoidal(htm, th)
    tn = an.t_N(htm)
    assert np.mean(tau[:-1]) / tn == pytest.approx(an.T_SN_PU, rel=1e-9)
    assert (tau.max() - tau.min()) / tn == pytest.approx(2 / math.sqrt(3) - 1, rel=1e-9)
    # (14): maximum at +-pi/6, minimum at 0, period pi/3
    t_at = _torque_sinusoidal(htm, np.array([0.0, math.pi / 6, -math.pi / 6, math.pi / 3]))
    assert t_at[1] == pytest.approx(tau.max(), rel=1e-12)
    assert t_at[2] == pytest.approx(tau.max(), rel=1e-12)
    assert t_at[0] == pytest.approx(tau.min(), rel=1e-12)
    assert t_at[3] == pytest.approx(tau.min(), rel=1e-12)


def test_v_ab_17_and_peak_20(htm: bldclab.Drive) -> None:
    """(17) is L d(i_a - i_b)/dt + e_a - e_b on [0, pi/6]; it rises (18) and peaks at pi/6 with (20)."""
    omega = 0.9 * an.omega_0(htm)
    m = htm.motor
    th = np.linspace(0.0, math.pi / 6, 2001)
    h = 1e-6
    i = lambda t: an.i_sN(htm) * (np.sin(t) - np.sin(t - TWO_PI / 3))  # noqa: E731
    di_dt = (i(th + h) - i(th - h)) / (2 * h) * m.p * omega
    k = m.emf.k_abc(th)
    v16 = m.L * di_dt + omega * (k[0] - k[1])
    v17 = np.asarray(an.v_ab_17(th, omega, htm))
    np.testing.assert_allclose(v17, v16, rtol=1e-8)
    assert np.all(np.diff(v17) > 0.0)
    assert v17[-1] == pytest.approx(float(an.v_ab_peak(omega, htm)), rel=1e-12)
    # (21): at the base speed the peak is the DC bus
    assert float(an.v_ab_peak(an.omega_sB_pu(an.theta_m(htm)) * an.omega_0(htm), htm)) == pytest.approx(48.0)


def test_condition_18_fails_for_a_large_inductance(htm: bldclab.Drive) -> None:
    big = htm.replace(motor__L=htm.motor.L * 20)
    assert an.condition_18(htm) and not an.condition_18(big)


def test_voltage_saturation_sinusoidal(htm: bldclab.Drive) -> None:
    """(23)-(25), (an.4)-(an.6): the saturated current makes the peak voltage (20) equal V_N."""
    th = an.theta_m(htm)
    w = np.array([0.96, 0.98, 0.995])
    omega = w * an.omega_0(htm)
    i_sat = np.asarray(an.i_s_sat(omega, htm))
    m = htm.motor
    v_peak = math.sqrt(3) / 2 * m.p * omega * m.L * i_sat + 2 * m.k_phi * omega
    np.testing.assert_allclose(v_peak, 48.0, rtol=1e-12)
    t_si = np.asarray(an.t_s_sat(omega, htm))
    np.testing.assert_allclose(t_si / an.t_N(htm), an.t_s_sat_pu(w, th), rtol=1e-12)
    # torque proportional to the current, (12) with I_s,sat
    np.testing.assert_allclose(t_si, 18 * m.k_phi / math.pi**2 * i_sat, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(an.tr_s_sat_pu(w, th)) / np.asarray(an.t_s_sat_pu(w, th)),
                               an.TR_SN_PU / an.T_SN_PU, rtol=1e-12)


@pytest.mark.parametrize("theta", [0.01, 0.046875, 0.2, 0.6])
def test_square_wave_continuity(theta: float) -> None:
    """(26) meets (28) at 0.5; (28), (31) and (32) meet at (30); the ripples meet too."""
    assert float(an.t_q_low_pu(0.5, theta)) == pytest.approx(float(an.t_q_high_pu(0.5, theta)), abs=1e-15)
    assert float(an.tr_q_low_pu(0.5)) == pytest.approx(float(an.tr_q_high_pu(0.5)), abs=1e-15)
    wb = an.omega_qB_pu(theta)
    assert float(an.t_q_high_pu(wb, theta)) == pytest.approx(an.t_qB_pu(theta), rel=1e-12)
    assert float(an.t_q_sat_pu(wb, theta)) == pytest.approx(an.t_qB_pu(theta), rel=1e-12)
    assert float(an.tr_q_sat_pu(wb, theta)) == pytest.approx(float(an.tr_q_high_pu(wb)), rel=1e-12)
    # the composed characteristic is continuous across both boundaries
    for w in (0.5, wb):
        left, right = an.t_q_pu(np.array([w - 1e-9, w + 1e-9]), theta)
        assert left == pytest.approx(right, abs=1e-6)


@pytest.mark.parametrize("theta", [0.01, 0.046875, 0.2])
def test_sinusoidal_continuity_at_base_speed(theta: float) -> None:
    wb = an.omega_sB_pu(theta)
    assert float(an.t_s_sat_pu(wb, theta)) == pytest.approx(an.T_SN_PU, rel=1e-12)
    assert float(an.tr_s_sat_pu(wb, theta)) == pytest.approx(an.TR_SN_PU, rel=1e-12)
    left, right = an.t_s_pu(np.array([wb - 1e-9, wb + 1e-9]), theta)
    assert left == pytest.approx(right, abs=1e-6)


def test_composed_characteristics_regions_and_zero_above_no_load(htm: bldclab.Drive) -> None:
    th = an.theta_m(htm)
    w = np.array([0.0, 0.3, 0.5, 0.7, 0.956, 0.9565, 0.98, 1.0, 1.2])
    rq = an.region_q(w, th)
    rs = an.region_s(w, th)
    low, high, sat, stop = an.REGION_Q_LOW, an.REGION_Q_HIGH, an.REGION_Q_SAT, an.REGION_STOP
    assert list(rq) == [low, low, high, high, high, high, sat, stop, stop]
    assert list(rs) == [an.REGION_S_BASE] * 4 + [an.REGION_S_SAT] * 3 + [an.REGION_STOP] * 2  # (21) = 0.9552
    tq = np.asarray(an.t_q_pu(w, th))
    assert tq[1] == pytest.approx(float(an.t_q_low_pu(0.3, th)))
    assert tq[3] == pytest.approx(float(an.t_q_high_pu(0.7, th)))
    assert tq[6] == pytest.approx(float(an.t_q_sat_pu(0.98, th)))
    for f in (an.t_q_pu, an.t_s_pu, an.tr_q_pu, an.tr_s_pu):
        out = np.asarray(f(w, th))
        assert np.all(out[-2:] == 0.0) and np.all(np.isfinite(out)) and np.all(out >= 0.0)
    # the torque with sinusoidal supply is never below the square-wave torque from 0.5 up to no-load speed
    ww = np.linspace(0.5, 1.0, 501)
    assert np.all(np.asarray(an.t_s_pu(ww, th)) >= np.asarray(an.t_q_pu(ww, th)) - 1e-12)


def test_scalar_and_array_inputs() -> None:
    assert isinstance(an.t_q_pu(0.3, 0.05), float)
    out = an.t_q_pu(np.zeros((2, 3)), 0.05)
    assert isinstance(out, np.ndarray) and out.shape == (2, 3)
    assert isinstance(an.region_q([0.1, 0.9], 0.05), np.ndarray)


@pytest.mark.parametrize("bad", [-0.1, float("nan"), float("inf")])
def test_bad_speed_raises(bad: float) -> None:
    with pytest.raises(BldclabError, match="omega_pu"):
        an.t_q_pu([0.2, bad], 0.05)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan")])
def test_bad_theta_raises(bad: float) -> None:
    with pytest.raises(BldclabError, match="theta_m"):
        an.omega_sB_pu(bad)


def test_other_motor_scales_theta_m(htm: bldclab.Drive) -> None:
    other = htm.replace(motor__L=3 * htm.motor.L, motor__R=2 * htm.motor.R, motor__p=4)
    assert an.theta_m(other) == pytest.approx(an.theta_m(htm) * 3 / 2, rel=1e-14)
    t_other = an.table1(other)
    th = 0.046875 * 1.5
    assert t_other.Omega_sB_pu == pytest.approx(1 / (1 + th))
    assert t_other.Omega_qB_pu == pytest.approx(1 / (1 + 3 * th / math.pi))
    assert t_other.P_R_pu == pytest.approx(2 * an.p_R_pu(htm))
    # more resistance: the R-aware base speeds fall further below the R = 0 ones
    assert t_other.ratio_sB_R < an.table1(htm).ratio_sB_R


def test_equivalent_blac(htm: bldclab.Drive) -> None:
    """Section IV.B: a sinusoidal back-EMF of peak k_phi with I_s,N in phase gives sqrt(3)/2 T_N."""
    th = np.linspace(0.0, TWO_PI, 10_001)
    k = 0.32 * np.stack([np.sin(th - x * TWO_PI / 3) for x in range(3)])
    i = an.i_sN(htm) * np.stack([np.sin(th - x * TWO_PI / 3) for x in range(3)])
    tau = np.sum(k * i, axis=0) / an.t_N(htm)
    np.testing.assert_allclose(tau, an.T_BLAC_N_PU, rtol=1e-12)
    theta = an.theta_m(htm)
    assert an.omega_blac_B_pu(theta) > 1.0  # line-to-line back-EMF sqrt(3) k_phi Omega < 2 k_phi Omega
    assert float(an.t_blac_pu(0.9, theta)) == pytest.approx(an.T_BLAC_N_PU)
    # above its base speed the current falls so that the peak line voltage stays at V_N
    big = 0.6
    wb = an.omega_blac_B_pu(big)
    assert wb < 1.0
    w = 0.5 * (wb + 2 / math.sqrt(3))
    i_pu = float(an.t_blac_pu(w, big)) / 0.75
    v_pu = math.sqrt(3) * w * math.sqrt(1 + (2 * big * i_pu) ** 2) / 2  # per unit of V_N
    assert v_pu == pytest.approx(1.0, rel=1e-12)
    assert float(an.t_blac_pu(wb, big)) == pytest.approx(an.T_BLAC_N_PU, rel=1e-9)
    assert float(an.t_blac_pu(1.2, big)) == 0.0


# ------------------------------------------------------------------------------------------------------------
# efficiency (34)-(44)


def test_p_r_pu_matches_36(htm: bldclab.Drive) -> None:
    # (36): 3 I_N^2 R / (2 k I_N Omega_N) = 3 P_R,pu
    m = htm.motor
    assert an.p_lCu_pu(htm) == pytest.approx(3 * m.I_N**2 * m.R / (2 * m.k_phi * m.I_N * m.Omega_nominal))
    assert an.p_R_pu(htm) == pytest.approx(0.05 * 50 / (2 * 0.32 * 67.02), rel=1e-4)


def test_consistent_copper_losses_by_direct_evaluation(htm: bldclab.Drive) -> None:
    """Equal rms currents dissipate 2 R I_N^2 with both supplies; (36) counts 3 (on another base)."""
    th = (np.arange(120_000) + 0.5) * TWO_PI / 120_000  # off the block edges
    R, i_n = htm.motor.R, htm.motor.I_N
    k = htm.motor.emf.k_abc(th) / 0.32
    sq = i_n * np.where(k > 1 - 1e-9, 1.0, np.where(k < -1 + 1e-9, -1.0, 0.0))  # ideal 120-degree blocks
    assert np.all(np.sum(sq, axis=0) == 0.0)
    sine = np.stack([an.i_sN(htm) * np.sin(th - x * TWO_PI / 3) for x in range(3)])
    p_sq = R * np.mean(np.sum(sq**2, axis=0))
    p_sine = R * np.mean(np.sum(sine**2, axis=0))
    assert p_sq == pytest.approx(2 * R * i_n**2, rel=1e-12)
    assert p_sine == pytest.approx(2 * R * i_n**2, rel=1e-12)
    assert an.p_lCu_consistent_pu(htm) == pytest.approx(p_sine / (an.t_N(htm) * an.omega_0(htm)))


def test_efficiency_ratio(htm: bldclab.Drive) -> None:
    th, pcu = an.theta_m(htm), an.p_lCu_pu(htm)
    for w in (0.2, 0.455, 0.7, 0.955):
        ratio = float(an.eta_ratio(w, th, pcu))
        assert ratio == pytest.approx(float(an.eta_s(w, th, pcu)) / float(an.eta_q(w, th, pcu)), rel=1e-12)
        # (41)/(42): both normalisations give the same ratio with P_R,pu
        p_r = an.p_R_pu(htm)
        for form in ("41", "42"):
            a, bs, bq = an.eta_ratio_coefficients(w, th, form)
            assert (a + bs * p_r) / (a + bq * p_r) == pytest.approx(ratio, rel=1e-12)
    # the printed coefficients of (41) and (42), recomputed
    a, bs, bq = an.eta_ratio_coefficients(0.955, th, "41")
    assert round(a, 2) == 0.78 and bs == pytest.approx(3.16, abs=0.03) and bq == pytest.approx(2.34, abs=0.03)
    a, bs, bq = an.eta_ratio_coefficients(0.455, th, "42")
    assert round(a, 2) == 0.48 and bs == pytest.approx(3.16, abs=0.01) and bq == 3.0
    # (38): the low- and high-speed branches
    assert float(an.eta_q(0.3, th, pcu)) == pytest.approx(
        float(an.t_q_low_pu(0.3, th)) * 0.3 / (float(an.t_q_low_pu(0.3, th)) * 0.3 + pcu))
    # outside the constant-current range the paper's efficiency does not apply
    assert math.isnan(float(an.eta_q(0.97, th, pcu))) and math.isnan(float(an.eta_s(0.97, th, pcu)))
    assert math.isnan(float(an.eta_ratio(0.97, th, pcu)))
    with pytest.raises(BldclabError, match="omega_pu"):
        an.eta_ratio_coefficients(0.97, th)
    # (34) in general
    assert float(an.eta_34(10.0, 1.0, 0.5, 0.5)) == pytest.approx(9.0 / 11.0)


# ------------------------------------------------------------------------------------------------------------
# R-aware numeric base speeds


def test_numeric_base_speeds_reduce_to_21_and_30_without_r(htm: bldclab.Drive) -> None:
    for drive in (htm, htm.replace(motor__L=4 * htm.motor.L), htm.replace(motor__p=3, motor__I_N=80.0)):
        th = an.theta_m(drive)
        assert an.omega_sB_numeric_pu(drive, R=0.0) == pytest.approx(an.omega_sB_pu(th), abs=1e-6)
        assert an.omega_qB_numeric_pu(drive, R=0.0) == pytest.approx(an.omega_qB_pu(th), abs=1e-6)
        assert an.omega_sB_numeric_pu(drive, R=0.0) == pytest.approx(an.omega_sB_pu(th), abs=1e-12)
        assert an.omega_qB_numeric_pu(drive, R=0.0) == pytest.approx(an.omega_qB_pu(th), abs=1e-12)


def test_numeric_base_speeds_fall_monotonically_with_r(htm: bldclab.Drive) -> None:
    rs = [0.0, 0.01, 0.03, 0.05, 0.1]
    s = [an.omega_sB_numeric_pu(htm, R=r) for r in rs]
    q = [an.omega_qB_numeric_pu(htm, R=r) for r in rs]
    assert all(b < a for a, b in itertools.pairwise(s))
    assert all(b < a for a, b in itertools.pairwise(q))
    # the default is the drive's R
    assert an.omega_sB_numeric_pu(htm) == s[3] and an.omega_qB_numeric_pu(htm) == q[3]
    with pytest.raises(BldclabError, match="R"):
        an.omega_qB_numeric_pu(htm, R=-1.0)


def test_numeric_sinusoidal_base_speed_by_direct_evaluation(htm: bldclab.Drive) -> None:
    """At the R-aware base speed the peak line voltage, by finite differences, is the DC bus."""
    w = an.omega_sB_numeric_pu(htm) * an.omega_0(htm)
    m = htm.motor
    th = np.linspace(0.0, TWO_PI, 720_001)
    i = an.i_sN(htm) * np.stack([np.sin(th - x * TWO_PI / 3) for x in range(3)])
    di = np.gradient(i, th, axis=1) * m.p * w
    e = w * m.emf.k_abc(th)
    v = m.R * i + m.L * di + e  # phase voltages minus the star point
    peak = max(np.max(np.abs(v[x] - v[y])) for x, y in ((0, 1), (1, 2), (2, 0)))
    assert peak == pytest.approx(48.0, rel=1e-6)


def _incoming_current_at_sector_end(drive: bldclab.Drive, omega: float) -> tuple[float, bool]:
    """Full three-phase circuit of the commutation a+b- -> a+c- (theta_e = pi/2), integrated by scipy.

    a on the + rail, c on the - rail, b freewheeling in its upper diode until its current dies; returns |i_c|
    at the end of the sector (pi/3 later) and whether b's current has died by then.
    """
    m = drive.motor
    V, R, L, k = drive.inverter.V_dc, m.R, m.L, m.emf
    i_n = m.I_N
    th0 = math.pi / 2
    t_end = (math.pi / 3) / (m.p * omega)

    def emf(t: float) -> np.ndarray:
        return omega * k.k_abc(th0 + m.p * omega * t)

    def three(t: float, y: np.ndarray) -> list[float]:
        ia, ib = y
        e = emf(t)
        v = np.array([V, V, 0.0])
        vn = (v.sum() - e.sum()) / 3
        return [(v[0] - R * ia - e[0] - vn) / L, (v[1] - R * ib - e[1] - vn) / L]

    def b_dies(t: float, y: np.ndarray) -> float:
        return y[1]

    b_dies.terminal = True  # type: ignore[attr-defined]
    b_dies.direction = 1  # type: ignore[attr-defined]
    sol = solve_ivp(three, (0.0, t_end), [i_n, -i_n], events=b_dies, rtol=1e-12, atol=1e-10,
                    max_step=t_end / 200)
    ia, ib = sol.y[:, -1]
    if sol.status == 1:  # b extinct: a and c alone
        def two(t: float, y: np.ndarray) -> list[float]:
            e = emf(t)
            return [(V - e[0] + e[2] - 2 * R * y[0]) / (2 * L)]

        sol2 = solve_ivp(two, (sol.t[-1], t_end), [ia], rtol=1e-12, atol=1e-10)
        return float(sol2.y[0, -1]), True
    return float(ia + ib), False


def test_numeric_square_wave_base_speed_against_full_circuit(htm: bldclab.Drive) -> None:
    """At the R-aware base speed the incoming current just reaches I_N at half of its conduction interval."""
    w_b = an.omega_qB_numeric_pu(htm) * an.omega_0(htm)
    i_c, b_died = _incoming_current_at_sector_end(htm, w_b)
    assert i_c == pytest.approx(50.0, rel=1e-7) and b_died
    assert _incoming_current_at_sector_end(htm, 1.01 * w_b)[0] < 50.0
    assert _incoming_current_at_sector_end(htm, 0.99 * w_b)[0] > 50.0


def test_numeric_square_wave_base_speed_outgoing_current_still_flowing(htm: bldclab.Drive) -> None:
    """A large inductance: at the base speed the outgoing phase still conducts, so (30) no longer holds."""
    big = htm.replace(motor__L=13 * htm.motor.L, motor__R=0.0)
    w_b = an.omega_qB_numeric_pu(big) * an.omega_0(big)
    i_c, b_died = _incoming_current_at_sector_end(big, w_b)
    assert i_c == pytest.approx(50.0, rel=1e-7) and not b_died
    assert w_b / an.omega_0(big) < an.omega_qB_pu(an.theta_m(big)) - 0.01


@pytest.mark.parametrize("shape", [Sinusoid(0.37), Trapezoid(0.32, flat_top=math.radians(100))])
def test_numeric_square_wave_base_speed_for_other_shapes(htm: bldclab.Drive, shape: object) -> None:
    """Back-EMFs that are not flat during the sector: the forcing varies in time, checked by scipy."""
    drive = htm.replace(motor__emf=BackEmf.symmetric(shape))
    w_b = an.omega_qB_numeric_pu(drive) * an.omega_0(drive)
    assert _incoming_current_at_sector_end(drive, w_b)[0] == pytest.approx(50.0, rel=1e-6)


def test_numeric_square_wave_base_speed_capped_at_no_load_speed(htm: bldclab.Drive) -> None:
    """A sinusoidal back-EMF and a tiny L: the current still makes it at Omega_0, where the search stops."""
    drive = htm.replace(motor__emf=BackEmf.symmetric(Sinusoid(0.37)), motor__L=1e-7)
    assert an.omega_qB_numeric_pu(drive, R=0.0) == 1.0
    # the flat trapezoid leaves no voltage for the current at Omega_0, however small L is
    assert an.omega_qB_numeric_pu(htm.replace(motor__L=1e-7), R=0.0) < 1.0


def test_numeric_base_speeds_six_commutations_for_non_symmetric_shapes(htm: bldclab.Drive) -> None:
    """The same trapezoid written as a table for one phase takes the general (six-commutation) path."""
    trap = htm.motor.emf.shapes[0]
    x = trap.breakpoints()
    table = Table(tuple(float(v) for v in x), tuple(float(v) for v in trap(x)))
    emf = BackEmf((trap, table, trap))
    assert not emf.is_symmetric
    mixed = htm.replace(motor__emf=emf)
    assert an.omega_qB_numeric_pu(mixed) == pytest.approx(an.omega_qB_numeric_pu(htm), rel=1e-12)
    assert an.omega_sB_numeric_pu(mixed) == pytest.approx(an.omega_sB_numeric_pu(htm), rel=1e-12)
    # the worst of the six commutations sets the base speed (in rad/s: k_phi, hence Omega_0, may move)
    w_sym = an.omega_qB_numeric_pu(htm) * an.omega_0(htm)
    strong = htm.replace(motor__emf=BackEmf((trap, Trapezoid(0.34), trap)))
    assert an.omega_qB_numeric_pu(strong) * an.omega_0(strong) < w_sym * (1 - 1e-3)
    # a weaker phase b leaves the commutations between a and c (where b only freewheels) as the limit
    weak = htm.replace(motor__emf=BackEmf((trap, Trapezoid(0.30), trap)))
    assert an.omega_qB_numeric_pu(weak) * an.omega_0(weak) == pytest.approx(w_sym, rel=1e-9)


def test_numeric_sinusoidal_base_speed_for_a_sinusoidal_motor(htm: bldclab.Drive) -> None:
    """Smooth maximum (no corner): peak line voltage sqrt(3) Omega sqrt(k_1^2 + (p L I)^2) = V_dc, R = 0."""
    k1 = 0.35
    drive = htm.replace(motor__emf=BackEmf.symmetric(Sinusoid(k1)), motor__L=3e-4)
    m = drive.motor
    omega = 48.0 / (math.sqrt(3) * math.hypot(k1, m.p * m.L * an.i_sN(drive)))
    assert an.omega_sB_numeric_pu(drive, R=0.0) * an.omega_0(drive) == pytest.approx(omega, rel=1e-10)
    # a shape whose fundamental is shifted by 0.3 rad: the currents follow it, the result does not change
    shifted = drive.replace(motor__emf=BackEmf.symmetric(Fourier((0.0, k1 * math.sin(0.3)),
                                                                (0.0, k1 * math.cos(0.3)))))
    assert an.omega_sB_numeric_pu(shifted, R=0.0) * an.omega_0(shifted) == pytest.approx(omega, rel=1e-10)


def test_table1_r_aware_fields(t1: an.Table1) -> None:
    assert t1.Omega_sB_R_pu < t1.Omega_sB_pu and t1.Omega_qB_R_pu < t1.Omega_qB_pu
    assert t1.ratio_sB_R == pytest.approx(t1.Omega_sB_R_pu / t1.Omega_sB_pu, rel=1e-10)
    assert t1.ratio_qB_R == pytest.approx(t1.Omega_qB_R_pu / t1.Omega_qB_pu, rel=1e-10)
    # the sinusoidal peak line voltage carries sqrt(3) R I_N at pi/6: a first-order estimate of the reduction
    assert t1.ratio_sB_R == pytest.approx(1 - math.sqrt(3) * 0.05 * 50 / 48, abs=0.01)
    assert set(t1.to_dict()) >= {k for k, *_ in t1.rows()}


# ------------------------------------------------------------------------------------------------------------
# the characteristic table


def test_characteristic(htm: bldclab.Drive) -> None:
    w = np.linspace(0.0, 1.0, 41)
    df = an.characteristic(htm, w)
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == list(an.CHARACTERISTIC_COLUMNS)
    assert len(df) == 41
    np.testing.assert_allclose(df["Omega"], w * 75.0)
    np.testing.assert_allclose(df["Omega_rpm"], w * 75.0 * 60 / TWO_PI)
    for c in ("T_s", "T_q", "TR_s", "TR_q"):
        np.testing.assert_allclose(df[c], df[f"{c}_pu"] * 32.0)
    np.testing.assert_allclose(df["T_q_pu"], an.t_q_pu(w, 0.046875))
    assert df["region_q"].iloc[0] == an.REGION_Q_LOW and df["region_s"].iloc[-1] == an.REGION_STOP
    row = an.characteristic(htm, [0.455])
    assert row["eta_ratio"].iloc[0] == pytest.approx(an.table1(htm).eta_ratio_0455)
    with pytest.raises(BldclabError, match="speeds_pu"):
        an.characteristic(htm, [[0.1, 0.2]])

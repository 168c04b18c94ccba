"""bc_sine, the sinusoidal current supply of paper 1, against paper 1's closed forms (htm-48v).

The paper's premise is R = 0 (drive.replace(motor__R=0.0)). The current PIs follow the paper's design (1 kHz,
90 deg); with R = 0 its integral action would vanish, and the default design floor (PI zero a decade below the
crossover) keeps it. Full tables and the measurements behind them: docs/sine.md.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

import bldclab as bl
from bldclab.analysis.compare import default_controls
from bldclab.analysis.experiments import base_speed, steady_state
from bldclab.control.sine import fundamental_k1
from bldclab.errors import BldclabError
from bldclab.model import analytic as an
from bldclab.model.catalog.synthetic import paper1_drive

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("sine_limit_bench", ROOT / "benchmarks" / "sine_limit.py")
sl = importlib.util.module_from_spec(_spec)
sys.modules["sine_limit_bench"] = sl
_spec.loader.exec_module(sl)

HTM = bl.load("htm-48v")
HTM0 = HTM.replace(motor__R=0.0)
THETA_M = an.theta_m(HTM)
T_SN = an.T_SN_PU * HTM.T_N  # nominal torque with sinusoidal supply (12), N m
SAT = bl.flag("SATURATED")
SAFE = bl.flag("SAFE")


def sine(**kw: object) -> bl.Sine:
    """The controller as validated: defaults, with the hand-off low enough for the 0.05 p.u. point."""
    base: dict[str, object] = {"handoff_speed": 0.02 * HTM.Omega_0}
    base.update(kw)
    return bl.Sine(**base)  # type: ignore[arg-type]


def point(drive: bl.Drive, control: bl.Sine, w_pu: float, ref: float = T_SN):
    pt, res = steady_state(drive, control, w_pu * drive.Omega_0, ref, trace=True)
    sel = res.t >= pt.metrics.t0
    sat = float(np.mean((res["ctrl_flags"][sel].astype(int) & SAT) > 0))
    return pt, res, sel, sat


def harmonic(res: bl.SimResult, sel: np.ndarray, omega_e: float, h: int) -> float:
    """Amplitude (A) of harmonic h of i_a over the window (whole electrical periods)."""
    t = res.t[sel]
    return float(abs(2.0 * np.mean(res["i_a"][sel] * np.exp(-1j * h * omega_e * t))))


# ---------------------------------------------------------------------------------------------------------------
# the controller's parameters


def test_k1_of_the_trapezoid_is_paper_10():
    assert fundamental_k1(HTM) == pytest.approx(12.0 / math.pi**2 * HTM.motor.k_phi, rel=1e-12)
    # (45): 1.5 k_1 i_q = 18 k_phi / pi^2 i_q, so I_s,N gives T_s,N (12)
    assert 1.5 * fundamental_k1(HTM) * an.i_sN(HTM) == pytest.approx(T_SN, rel=1e-12)


def test_gains_are_paper_design():
    wc = 2 * math.pi * 1000
    kp, ki = bl.Sine().gains(HTM)  # pole-zero cancellation: k_p = w_c L, k_i = w_c R
    assert kp == pytest.approx(wc * 75e-6) and ki == pytest.approx(wc * 0.05)
    assert bl.Sine(R_design=0.0).gains(HTM0)[1] == 0.0  # R = 0: no integral action from the 90-degree design
    assert bl.Sine().gains(HTM0)[1] == pytest.approx(wc * wc * 75e-6 / 10)  # the floor: zero at w_c / 10


def test_without_integral_action_a_steady_error_remains():
    """Why the design floor: with R = 0 the exact 90-degree design is P only. The feed-forwards (back-EMF, measured
    decoupling) are then the whole steady-state voltage, exact for an ideal inverter, but whatever the model lacks
    (here 1 us of dead time, 1.4 % of the PWM period) stays as a current error; the floor's integral removes most."""
    assert abs(point(HTM0, sine(R_design=0.0), 0.5)[0].tau_mean_pu - an.T_SN_PU) < 1e-4  # ideal inverter
    dead = HTM0.replace(inverter__t_dead=1e-6)
    assert abs(point(dead, sine(R_design=0.0), 0.5)[0].tau_mean_pu - an.T_SN_PU) > 0.02
    assert abs(point(dead, sine(), 0.5)[0].tau_mean_pu - an.T_SN_PU) < 0.005


@pytest.mark.parametrize("kw", [{"angle": "gyro"}, {"limit": "square"}, {"advance": -1.0}, {"advance": 5.0},
                                {"emf_points": 2}, {"handoff_hysteresis": 1.0}, {"bandwidth_hz": 0.0},
                                {"emf_feedforward": 1}, {"i_max": float("nan")}, {"start": "sixstep"}])
def test_bad_settings_are_named(kw):
    with pytest.raises(BldclabError) as e:
        bl.Sine(**kw)
    assert "control." in str(e.value)


# ---------------------------------------------------------------------------------------------------------------
# paper 1 (13)/(15) below the base speed, (24)/(25) above it, R = 0


SPEEDS = [0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.9, 0.95, 0.96, 0.98]


@pytest.mark.parametrize("w", SPEEDS)
def test_torque_and_ripple_follow_paper(w):
    pt, res, sel, sat = point(HTM0, sine(), w)
    assert pt.tau_mean_pu == pytest.approx(an.t_s_pu(w, THETA_M), abs=0.005)
    assert pt.ripple_ma_pu == pytest.approx(an.tr_s_pu(w, THETA_M), abs=0.02)
    assert np.all(res["mode"][sel] == 1)
    assert sat == 0.0  # the current limits keep the modulation linear: the PIs never saturate
    # sinusoidal currents: the trapezoid's harmonics are cancelled by the feed-forward
    we = HTM.motor.p * w * HTM.Omega_0
    i1 = harmonic(res, sel, we, 1)
    assert max(harmonic(res, sel, we, h) for h in (5, 7, 11, 13)) < 0.005 * i1


@pytest.mark.parametrize("w", [0.3, 0.6, 0.9])
def test_plain_pi_distorts_currents_and_ripple(w):
    """Without feed-forward the PI leaves the back-EMF harmonics in the currents: the mean torque stays close to
    (13), the ripple is no longer (15) (the currents are not sinusoidal, the paper's premise fails)."""
    pt, res, sel, _sat = point(HTM0, sine(emf_feedforward=False, decoupling=False), w)
    assert pt.tau_mean_pu == pytest.approx(an.T_SN_PU, abs=0.005)
    assert pt.ripple_ma_pu < an.TR_SN_PU - 0.04
    we = HTM.motor.p * w * HTM.Omega_0
    assert harmonic(res, sel, we, 5) > 0.01 * harmonic(res, sel, we, 1)


def test_base_speed_R0_is_paper_21():
    w_b = base_speed(HTM0, "sine", sine(speed_limit=False), lo=0.94, hi=0.97, tol=2e-4)
    assert w_b == pytest.approx(an.omega_sB_pu(THETA_M), abs=0.003)


def test_base_speed_with_R_is_the_numeric_one():
    w_b = base_speed(HTM, "sine", sine(speed_limit=False), lo=0.85, hi=0.89, tol=2e-4)
    assert w_b == pytest.approx(an.omega_sB_numeric_pu(HTM), abs=0.003)
    # the drop against Table I: the paper says about 0.9 times
    assert w_b / an.omega_sB_pu(THETA_M) == pytest.approx(0.91, abs=0.005)


def test_above_base_speed_with_R_keeps_linear_modulation():
    for w in (0.9, 0.95):
        pt, res, sel, sat = point(HTM, sine(), w)
        assert sat < 0.01
        iq = float(np.mean(res["i_q_ref"][sel]))
        assert pt.tau_mean_pu == pytest.approx(1.5 * fundamental_k1(HTM) * iq / HTM.T_N, rel=2e-3)
        assert iq < an.i_sN(HTM)


def test_circle_limit_loses_the_top_speeds():
    """The inscribed circle V_dc/sqrt(3) cannot carry the trapezoid's back-EMF (its vector traces the hexagon)."""
    pt_h, *_ = point(HTM0, sine(), 0.9)
    pt_c, _, _, sat_c = point(HTM0, sine(limit="circle"), 0.9)
    assert pt_h.tau_mean_pu == pytest.approx(an.T_SN_PU, abs=0.005)
    assert sat_c > 0.1 and pt_c.tau_mean_pu < pt_h.tau_mean_pu - 0.003


# ---------------------------------------------------------------------------------------------------------------
# angle: encoder (ideal) against the Hall interpolation (46)


@pytest.mark.parametrize("w", [0.1, 0.5, 0.9])
def test_hall_angle_matches_encoder(w):
    pt_h, *_ = point(HTM0, sine(), w)
    pt_e, *_ = point(HTM0, sine(angle="encoder"), w)
    assert abs(pt_h.tau_mean_pu - pt_e.tau_mean_pu) < 1e-4
    assert abs(pt_h.ripple_ma_pu - pt_e.ripple_ma_pu) < 1e-3


# ---------------------------------------------------------------------------------------------------------------
# dynamics: start from standstill, hand-off, four quadrants, speed loop


def test_start_from_standstill_hands_off_without_spike():
    sc = bl.Scenario(duration=0.06, ref=T_SN, load_torque=0.5 * HTM.T_N, theta0=0.3)
    res = bl.simulate(HTM, bl.Sine(), sc)
    mode = res["mode"]
    assert mode[0] == 0 and mode[-1] == 1
    k = int(np.argmax(mode == 1))
    assert np.all(mode[k:] == 1)
    omega_N = HTM.motor.Omega_nominal
    assert res["omega_e"][k] / HTM.motor.p >= 0.1 * omega_N * (1 - 1e-6)  # the Hall speed crossed 0.1 Omega_N
    assert res["omega_m"][k] >= 0.1 * omega_N  # the rotor is at least that fast (the estimate lags)
    dt = res.t[1] - res.t[0]
    win = slice(max(k - int(5e-3 / dt), 0), k + int(10e-3 / dt))
    i_abs = np.abs(np.stack([res["i_a"], res["i_b"], res["i_c"]]))
    assert i_abs[:, win].max() <= 1.2 * HTM.motor.I_N
    assert not np.any(res["ctrl_flags"].astype(int) & SAFE)
    assert res["omega_m"][-1] > res["omega_m"][k]


def test_start_is_a_composed_sixstep_with_its_own_settings():
    """Any bldclab.SixStep starts the drive; its reference is switched to torque."""
    start = bl.SixStep(regulation="pi", chopping="bipolar")  # reference="current" by default
    sc = bl.Scenario(duration=0.05, ref=T_SN, load_torque=0.5 * HTM.T_N, theta0=0.3)
    res = bl.simulate(HTM, bl.Sine(start=start), sc)
    assert res["mode"][-1] == 1 and res["omega_m"][-1] > 0.1 * HTM.motor.Omega_nominal
    sq = res["mode"] == 0
    # the square-wave torque: a current of I_N (the equal-rms counterpart of I_s,N), not the torque read as amperes
    assert np.mean(res["tau_e"][sq][200:]) == pytest.approx(HTM.T_N, rel=0.05)


@pytest.mark.parametrize(("w", "sign"), [(0.5, -1.0), (-0.5, 1.0), (-0.5, -1.0), (0.9, -1.0)])
def test_four_quadrants_with_flying_start(w, sign):
    pt, _res, _sel, sat = point(HTM0, sine(flying_start=True), w, sign * T_SN)
    assert pt.tau_mean_pu == pytest.approx(sign * an.T_SN_PU, abs=0.005)
    assert pt.ripple_ma_pu == pytest.approx(an.TR_SN_PU, abs=0.02)
    assert sat == 0.0


def test_speed_loop_reaches_its_reference():
    wN = HTM.motor.Omega_nominal

    def ref(t):
        return np.where(t < 0.3, 0.5 * wN, 0.8 * wN)

    sc = bl.Scenario(duration=0.6, omega_ref=ref, load_torque=0.3 * HTM.T_N, trace_every=28)
    res = bl.simulate(HTM, bl.Sine(speed_loop=True), sc)
    for t_end, target in ((0.3, 0.5 * wN), (0.6, 0.8 * wN)):
        j = np.searchsorted(res.t, t_end - 0.01)
        assert res["omega_m"][j] == pytest.approx(target, rel=0.03)
    assert np.all(res["i_q_ref"] <= an.i_sN(HTM) + 1e-3)


@pytest.mark.parametrize("w", [0.05, 0.5, 0.9, 0.97])
def test_sampled_ripple_within_002_of_the_paper(w):
    """The PWM-free ripple (torque at the carrier valleys and peaks) follows (15)/(25) to 0.02 p.u."""
    drive = bl.load("htm-48v").replace(motor__R=0.0)
    pt, _ = steady_state(drive, bl.Sine(handoff_speed=0.01 * drive.Omega_0), w * drive.Omega_0, an.t_sN(drive))
    assert pt.ripple_sampled_pu == pytest.approx(an.tr_s_pu(w, an.theta_m(drive)), abs=0.02)


# ---------------------------------------------------------------------------------------------------------------
# any drive on paper 1's premises: the current is regulated, the mean torque is (13)

# the drive of issue 11: a fast 13-pole-pair motor whose omega_e L (1.25 Ohm at 0.78 Omega_0) dwarfs k_p (0.47 V/A)
FAST = {"Theta_m": 0.1071, "p": 13, "V_N": 454.8, "I_N": 30.4, "Omega_0": 1642.9, "ppc": 20.0, "w": 0.782}


def drive_point(Theta_m: float, p: int, V_N: float, I_N: float, Omega_0: float, ppc: float, w: float,
                **control: object) -> tuple[float, float, float]:
    """Sinusoidal supply asked for T_sN at w Omega_0: (mean torque p.u., mean i_q / mean i_q,ref - 1, |(13) error|)."""
    d = paper1_drive(Theta_m, p=p, V_N=V_N, I_N=I_N, Omega_0=Omega_0, pwm_per_commutation=ppc)
    ctl, ref = default_controls(d, 0.05)["sine"]
    ctl = dataclasses.replace(ctl, **control)
    pt, res = steady_state(d, ctl, w * Omega_0, ref, trace=True)
    sel = res.t >= pt.metrics.t0
    iq_err = float(np.mean(res["i_q"][sel]) / np.mean(res["i_q_ref"][sel]) - 1.0)
    return pt.tau_mean_pu, iq_err, abs(pt.tau_mean_pu - an.t_s_pu(w, Theta_m))


drives = st.fixed_dictionaries({
    "Theta_m": st.floats(0.01, 0.2), "p": st.integers(1, 20), "V_N": st.floats(12.0, 600.0),
    "I_N": st.floats(1.0, 200.0), "Omega_0": st.floats(20.0, 2000.0), "ppc": st.floats(5.0, 200.0),
    "w": st.floats(0.05, 0.85)})


def check_drive(case: dict) -> None:
    # below the base speed (21) with a margin: the region of (13)
    assume(case["w"] <= an.omega_sB_pu(case["Theta_m"]) - 0.03)
    # sinusoidal currents need a PWM ripple well below I_N: V_N T_pwm / (L I_N) = pi / (3 ppc Theta_m) <= 1
    # (paper 1's study case: 0.91); coarser PWM trips the square-wave start (ripple over 2 I_N)
    assume(math.pi / (3.0 * case["ppc"] * case["Theta_m"]) <= 1.0)
    tau, iq_err, err = drive_point(**case)
    assert err < 0.005, (case, tau)
    assert abs(iq_err) < 0.01, (case, iq_err)


@settings(max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.filter_too_much])
@given(drives)
@example(FAST)
def test_any_drive_regulates_its_current(case):
    """Drives drawn at random on paper 1's premises (R = 0, ideal trapezoid): the mean torque of the sinusoidal
    supply is (13) to 0.005 p.u. and i_q its reference to 1 %, whatever the motor's size, poles and speed."""
    check_drive(case)


@pytest.mark.slow
@settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.filter_too_much])
@given(drives)
def test_any_drive_regulates_its_current_many(case):
    check_drive(case)


def test_fast_drive_needs_the_measured_decoupling():
    """Issue 11's drive: the cross-coupling omega_e L = 1.25 Ohm against k_p = 0.47 V/A. With the decoupling the
    torque is (13); without it the PI's slow mode k_i / (k_p + j omega_e L) (time constant 13 ms) has not settled
    after the hand-off, and the torque is off by more than 0.1 p.u. (the failure the issue reported, at 0.22)."""
    assert drive_point(**FAST)[2] < 0.001
    assert drive_point(**FAST, decoupling=False)[2] > 0.1


def test_default_bandwidth_is_paper_1_unless_the_pwm_is_slow():
    assert bl.Sine().bandwidth(HTM) == 1000.0  # 14 kHz PWM
    assert bl.Sine().bandwidth(bl.load("lu-4kw")) == 1000.0  # 10 kHz PWM
    slow = paper1_drive(0.05, p=4, Omega_0=50.0, pwm_per_commutation=20.0)  # 764 Hz PWM
    assert bl.Sine().bandwidth(slow) == pytest.approx(slow.inverter.f_pwm / 10.0)
    assert bl.Sine(bandwidth_hz=300.0).bandwidth(slow) == 300.0


# ---------------------------------------------------------------------------------------------------------------
# the speed limit on any back-EMF shape (issue 11)


def sinusoidal_paper1(Theta_m: float, R: float) -> bl.Drive:
    """paper1_drive with a sinusoidal back-EMF of the same peak line-to-line value 2 k_phi."""
    d = paper1_drive(Theta_m, R=R)
    return d.replace(motor__emf=bl.BackEmf.symmetric(bl.Sinusoid(2.0 * d.motor.k_phi / math.sqrt(3.0))))


SINUSOIDAL = {
    "servo-2k2": lambda: bl.load("servo-2k2"),
    "outrunner-24v": lambda: bl.load("outrunner-24v"),
    "paper1-sin-0.3": lambda: sinusoidal_paper1(0.3, 0.0),
    "paper1-sin-0.3-R": lambda: sinusoidal_paper1(0.3, 0.05),
    "paper1-sin-0.6-R": lambda: sinusoidal_paper1(0.6, 0.02),
}


def quadrature_limit(drive: bl.Drive, w_pu: float) -> float:
    """Largest current amplitude (A) of a sinusoidal back-EMF drive in linear modulation at steady state:
    sqrt(3) |omega_m k_1 + (R + j omega_e L) I| = V_dc (currents in phase with the back-EMF)."""
    wm = w_pu * drive.Omega_0
    E, R, X = wm * fundamental_k1(drive), an.r_total(drive), drive.motor.p * wm * drive.motor.L
    a, b, c = R * R + X * X, 2.0 * E * R, E * E - drive.inverter.V_dc ** 2 / 3.0
    return (-b + math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)


@pytest.mark.parametrize("case", list(SINUSOIDAL))
def test_sinusoidal_back_emf_keeps_full_current_up_to_the_base_speed(case):
    """On a sinusoidal back-EMF the back-EMF and the inductive drop add in quadrature: the current stays at I_s,N
    (torque 1.5 k_1 I_s,N) up to 0.01 p.u. below the R-aware numeric base speed, and above it the current is the
    quadrature limit, the modulation stays linear. Paper 1's (23) (linear addition, the trapezoid's law) cut the
    current from about 0.72 p.u. on servo-2k2 and 0.70 on outrunner-24v."""
    drive = SINUSOIDAL[case]()
    control, ref = default_controls(drive)["sine"]
    w_b = an.omega_sB_numeric_pu(drive)
    i_s = an.i_sN(drive)
    full = 1.5 * fundamental_k1(drive) * i_s
    pt, res, sel, sat = point(drive, control, w_b - 0.01, ref)
    assert float(np.mean(res["i_q_ref"][sel])) == pytest.approx(i_s, rel=1e-4)
    assert pt.tau_mean == pytest.approx(full, rel=2e-3)
    assert sat == 0.0
    for w in (w_b + 0.02, min(w_b + 0.08, 0.97)):
        pt, res, sel, sat = point(drive, control, w, ref)
        iq = float(np.mean(res["i_q_ref"][sel]))
        assert sat < 0.01
        # at most the exact limit; below it by the grid margin (peaks between the 96 angles of the controller's
        # scan, 1 - cos(pi/96) = 5.4e-4 of the voltage, about 0.2 % of the current here) and the interpolation of
        # its table (docs/sine.md, section 4)
        i_q = quadrature_limit(drive, w)
        assert i_q * (1.0 - 5e-3) < iq < i_q * (1.0 + 1e-3)
        assert iq < i_s
        assert pt.tau_mean == pytest.approx(1.5 * fundamental_k1(drive) * iq, rel=3e-3)


@pytest.mark.parametrize("w", [0.9, 0.95])
def test_trapezoid_limit_is_paper_23_with_R(w):
    """On the ideal trapezoid (htm-48v) the shape-aware limit is paper 1's (23) with R: the back-EMF's flat top
    and the drop's peak add linearly, I_s,sat = (V_dc - 2 k_phi Omega) / (sqrt(3)/2 omega_e L + 3/2 R)."""
    _pt, res, sel, sat = point(HTM, sine(), w)
    wm = w * HTM.Omega_0
    g = math.sqrt(3.0) / 2.0 * HTM.motor.p * wm * HTM.motor.L + 1.5 * an.r_total(HTM)
    i23 = (HTM.inverter.V_dc - 2.0 * HTM.motor.k_phi * wm) / g
    assert float(np.mean(res["i_q_ref"][sel])) == pytest.approx(i23, rel=2e-3)
    assert sat == 0.0


@pytest.mark.parametrize("name", ["servo-2k2", "outrunner-24v"])
def test_sinusoidal_drive_base_speed_is_the_numeric_one(name):
    """The simulated base speed (speed limit off, I_s,N asked) is the R-aware numeric one. On servo-2k2 it was 0.782
    against 0.816 while the voltage limit scaled d and q together: the hand-off from the square wave at high speed
    (i_d > 0) then locked into a saturated state; fitting the d axis first leaves it."""
    drive = bl.load(name)
    w_b = base_speed(drive, "sine", lo=0.7, hi=0.9, tol=5e-4)
    assert w_b == pytest.approx(an.omega_sB_numeric_pu(drive), abs=0.002)


# ---------------------------------------------------------------------------------------------------------------
# the speed limit's table against the 96-angle scan it tabulates (benchmarks/sine_limit.py; in C:
# core/tests/test_sine.c, test_speed_limit_table): random speeds of both signs up to 1.05 times the no-load speed of
# the bus, buses from 0.3 to 2 V_dc, both torque signs


@pytest.mark.parametrize("limit", ["hexagon", "circle"])
@pytest.mark.parametrize("name", list(sl.CATALOG))
def test_speed_limit_table_on_the_catalog_drives(name, limit):
    """Never above the scan; at most 0.75 % of I_s,N below it where the back-EMF alone needs at most 99.5 % of the
    bus (measured: 0.49 % on servo-2k2, hexagon); at least the scan's limit of a bus 0.1 % lower everywhere."""
    e = sl.table_error(bl.load(name), bl.Sine(limit=limit), n=1500)
    assert e.binding > 100  # samples where the limit is strictly between 0 and I_s,N
    assert e.above <= 1e-5
    assert e.below <= 0.0075
    assert e.bus <= 0.001


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(6))
def test_speed_limit_table_on_random_fourier_drives(seed):
    """Per-phase random shapes (harmonics 1 to 9), drops and resistances: never above the scan; at most 3 % of I_s,N
    below it away from the no-load speed and at least the scan's limit of a bus 1.5 % lower (measured over 16 drives:
    2.2 % and 1.0 %, both on a drive whose resistive drop is 18 % of the bus at I_s,N, at a third of the bus)."""
    drive = sl.random_drive(seed)
    for limit in ("hexagon", "circle"):
        e = sl.table_error(drive, bl.Sine(limit=limit), n=3000, seed=seed + 10)
        assert e.above <= 1e-5, limit
        assert e.below <= 0.03, limit
        assert e.bus <= 0.015, limit

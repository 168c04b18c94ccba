"""Physics tests of the scipy reference model (tests/reference_model.py): closed forms and conservation."""

from __future__ import annotations

import math

import numpy as np
import pytest

import bldclab
from reference_model import HIGH, LOW, OFF, PWM, RefResult, simulate_reference

# 120-degree conduction per Hall sector (docs/conventions.md): (+ leg, - leg)
SECTOR_LEGS = ((0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1))


@pytest.fixture(scope="module")
def htm() -> bldclab.Drive:
    return bldclab.load("htm-48v")


@pytest.fixture(scope="module")
def lossy(htm: bldclab.Drive) -> bldclab.Drive:
    """htm-48v with every loss term of the inverter switched on."""
    return htm.replace(inverter__R_on=0.004, inverter__V_f=0.8, inverter__r_d=0.005, inverter__R_src=0.01,
                       inverter__t_dead=1e-6)


def half_period(drive: bldclab.Drive) -> float:
    return 0.5 / drive.inverter.f_pwm


def sector(theta_e: float) -> int:
    return int(((theta_e - math.pi / 6) % (2 * math.pi)) // (math.pi / 3))


def six_step(drive: bldclab.Drive, omega_m: float, n: int, duty: float, upper_mode: int = HIGH,
             theta0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Six-step commands from the Hall sector at the start of each half period: + leg chops, - leg on."""
    modes = np.full((n, 3), OFF)
    duties = np.zeros((n, 3))
    T2 = half_period(drive)
    for k in range(n):
        hi, lo = SECTOR_LEGS[sector(theta0 + drive.motor.p * omega_m * k * T2)]
        modes[k, hi], duties[k, hi] = upper_mode, duty
        modes[k, lo], duties[k, lo] = LOW, 1.0
    return modes, duties


def balance_error(r: RefResult) -> float:
    """Energy residual relative to the largest flow."""
    scale = max(abs(v) for v in r.E.values())
    return abs(r.energy_residual()) / scale


def rl_step(i: float, v: float, r_loop: float, L_loop: float, dt: float) -> float:
    """Exact current after dt in a series loop L_loop di/dt = v - r_loop i."""
    i_inf = v / r_loop
    return i_inf + (i - i_inf) * math.exp(-dt * r_loop / L_loop)


# ----------------------------------------------------------------------------------------------------------


def test_sample_grid_and_outputs(htm: bldclab.Drive) -> None:
    n = 10
    omega = 0.3 * htm.Omega_0
    r = simulate_reference(htm, omega, np.zeros((n, 3), int), np.zeros((n, 3)), theta0=6.0)
    T2 = half_period(htm)
    assert r.t.shape == (n + 1,) and r.i.shape == (n + 1, 3)
    np.testing.assert_allclose(r.t, np.arange(n + 1) * T2, rtol=0, atol=1e-18)
    np.testing.assert_allclose(r.theta_e, np.mod(6.0 + htm.motor.p * omega * r.t, 2 * math.pi), atol=1e-12)
    assert np.all((r.theta_e >= 0) & (r.theta_e < 2 * math.pi))
    with pytest.raises(ValueError):
        simulate_reference(htm, 0.0, np.zeros((n, 3), int), np.full((n, 3), 1.5))
    with pytest.raises(ValueError):
        simulate_reference(htm, 0.0, np.zeros((n, 3), int), np.zeros((n, 3)), i0=(1.0, 0.0, 0.0))


@pytest.mark.parametrize("lossy_inverter", [False, True])
def test_standstill_dc_step_is_exact_exponential(htm: bldclab.Drive, lossy_inverter: bool) -> None:
    """a HIGH d=1, b LOW d=1, c OFF: i_a = V/R_t (1 - exp(-t/tau)), R_t = 2R + 2R_on + R_src, tau = 2L/R_t.

    With an ideal inverter this is the textbook V/(2R) and tau = L/R.
    """
    drive = htm
    if lossy_inverter:
        drive = htm.replace(inverter__R_on=0.01, inverter__R_src=0.02, inverter__V_f=0.7)
    n = 210  # about 5 time constants
    modes = np.tile([HIGH, LOW, OFF], (n, 1))
    r = simulate_reference(drive, 0.0, modes, np.ones((n, 3)))
    m, inv = drive.motor, drive.inverter
    r_t = 2 * m.R + 2 * inv.R_on + inv.R_src
    i_inf, tau = inv.V_dc / r_t, 2 * m.L / r_t
    if not lossy_inverter:
        assert i_inf == pytest.approx(inv.V_dc / (2 * m.R)) and tau == pytest.approx(m.L / m.R)
    i_exact = i_inf * (1.0 - np.exp(-r.t / tau))
    assert np.max(np.abs(r.i[:, 0] - i_exact)) < 1e-7
    np.testing.assert_allclose(r.i[:, 1], -r.i[:, 0], rtol=0, atol=1e-10)
    np.testing.assert_array_equal(r.i[:, 2], 0.0)  # open phase: exactly no current
    assert r.i[-1, 0] > 0.99 * i_inf
    # time constant measured from the samples
    tau_est = -r.t[1:100] / np.log(1.0 - r.i[1:100, 0] / i_inf)
    np.testing.assert_allclose(tau_est, tau, rtol=1e-8)
    assert balance_error(r) < 1e-10
    assert r.E["emf"] == 0.0 and r.E["diode"] == 0.0


def test_high_side_chopping_timing_and_freewheel_diode(htm: bldclab.Drive) -> None:
    """a HIGH d, b LOW 1 at standstill: on -> V over the whole loop, off -> a freewheels in its lower diode.

    Checked against the exact piecewise solution built from the centre-aligned timing (rising half: off then
    on; falling half: on then off).
    """
    drive = htm.replace(inverter__R_on=0.004, inverter__V_f=0.8, inverter__r_d=0.005, inverter__R_src=0.01,
                        inverter__t_dead=2e-6)
    m, inv = drive.motor, drive.inverter
    d, n = 0.6, 60
    modes = np.tile([HIGH, LOW, OFF], (n, 1))
    duties = np.tile([d, 1.0, 0.0], (n, 1))
    r = simulate_reference(drive, 0.0, modes, duties)
    T2 = half_period(drive)
    on = (inv.V_dc, 2 * m.R + 2 * inv.R_on + inv.R_src)
    off = (-inv.V_f, 2 * m.R + inv.R_on + inv.r_d)
    i = 0.0
    expect = [0.0]
    for k in range(n):
        parts = [(off, (1 - d) * T2), (on, d * T2)] if k % 2 == 0 else [(on, d * T2), (off, (1 - d) * T2)]
        for (v, r_loop), dt in parts:
            if i > 0.0 or v > 0.0:  # a diode cannot carry negative current: at i = 0 the phase stays open
                i = rl_step(i, v, r_loop, 2 * m.L, dt)
                assert i > 0.0
        expect.append(i)
    assert np.max(np.abs(r.i[:, 0] - np.array(expect))) < 1e-7
    assert r.E["diode"] > 0.0 and r.E["sw"] > 0.0
    assert balance_error(r) < 1e-8


@pytest.mark.slow
@pytest.mark.parametrize("upper_mode", [HIGH, PWM])
def test_six_step_energy_balance(lossy: bldclab.Drive, upper_mode: int) -> None:
    """Six-step at 0.5 Omega_0 with chopping, freewheeling, commutation through diodes and an open phase."""
    omega = 0.5 * lossy.Omega_0
    n = 300  # a bit more than half an electrical turn: three commutations
    modes, duties = six_step(lossy, omega, n, 0.7, upper_mode)
    r = simulate_reference(lossy, omega, modes, duties)
    assert balance_error(r) < 1e-10
    for key in ("Rsrc", "cu", "sw", "diode"):
        assert r.E[key] > 0.0, key
    assert r.E["emf"] > 0.0 and r.tau_mean > 0.0  # motoring
    assert r.tau_mean * omega * n * half_period(lossy) == pytest.approx(r.E["emf"], rel=1e-9)
    # the idle phase of a sector (after the outgoing current has died away) stays open, with exactly zero
    # current, while its back-EMF is positive; once its back-EMF is clearly negative its lower diode conducts
    # in the freewheeling intervals (the + leg's lower diode or switch pulls the star point near the - rail).
    T2 = half_period(lossy)
    p, v_f = lossy.motor.p, lossy.inverter.V_f
    n_zero = n_cond = 0
    for k in range(n + 1):
        th = p * omega * k * T2
        s = sector(th)
        if sector(th - p * omega * 12 * T2) != s:
            continue
        idle = 3 - sum(SECTOR_LEGS[s])
        e_idle = omega * float(lossy.motor.emf.k_abc(th)[idle])
        if e_idle > 0.0:
            assert r.i[k, idle] == 0.0, (k, r.i[k])
            n_zero += 1
        elif e_idle < -2 * v_f - 0.5 and k % 2 == 0:  # carrier valley: the + leg freewheels
            assert r.i[k, idle] > 0.0, (k, r.i[k])
            n_cond += 1
    assert n_zero > 50 and n_cond > 20
    # currents sum to zero, torque samples are k . i
    np.testing.assert_allclose(r.i.sum(axis=1), 0.0, atol=1e-9)
    k_abc = lossy.motor.emf.k_abc(r.theta_e)
    np.testing.assert_allclose(r.tau_e, np.sum(k_abc.T * r.i, axis=1), rtol=1e-12, atol=1e-12)


@pytest.mark.slow
def test_all_off_below_no_load_speed_carries_no_current(lossy: bldclab.Drive) -> None:
    n = 200
    for omega in (0.95 * lossy.Omega_0, -0.95 * lossy.Omega_0):
        r = simulate_reference(lossy, omega, np.zeros((n, 3), int), np.zeros((n, 3)), theta0=0.3)
        np.testing.assert_array_equal(r.i, 0.0)
        assert all(v == 0.0 for v in r.E.values())


def line_emf_max(drive: bldclab.Drive, omega: float, theta_e: np.ndarray) -> np.ndarray:
    e = omega * drive.motor.emf.k_abc(theta_e)
    return np.max(e[:, None, :] - e[None, :, :], axis=(0, 1))


@pytest.mark.parametrize(("shape", "speed"), [pytest.param("trapezoid", 1.3, marks=pytest.mark.slow),
                                              pytest.param("trapezoid", -1.3, marks=pytest.mark.slow),
                                              ("sinusoid", 1.1), ("sinusoid", -1.1)])
def test_all_off_above_no_load_speed_rectifies(lossy: bldclab.Drive, shape: str, speed: float) -> None:
    """Legs OFF while the line back-EMF exceeds V_dc + 2 V_f: the diodes rectify into the source.

    A 120-degree trapezoid has a constant peak line EMF 2 k_phi omega (conduction at every angle); a
    sinusoid's peak line EMF varies between 3/2 and sqrt(3) k_1 omega, so at 1.1 Omega_0 the bridge conducts
    only part of the time: no current may flow before the line EMF first crosses the threshold.
    """
    drive = lossy
    if shape == "sinusoid":
        k_1 = 2 * lossy.motor.k_phi / math.sqrt(3)  # same k_phi, same Omega_0
        drive = lossy.replace(motor__emf=bldclab.BackEmf.symmetric(bldclab.Sinusoid(k_1)))
    omega = speed * drive.Omega_0
    inv = drive.inverter
    grid = np.linspace(0, 2 * math.pi, 721)
    theta0 = float(grid[np.argmin(line_emf_max(drive, omega, grid))])
    n = 400
    r = simulate_reference(drive, omega, np.zeros((n, 3), int), np.zeros((n, 3)), theta0=theta0)
    assert np.max(np.abs(r.i)) > 5.0
    assert r.E["src"] < 0.0 and r.E["emf"] < 0.0  # generating into the DC source
    assert r.E["sw"] == 0.0 and r.E["diode"] > 0.0 and r.E["Rsrc"] > 0.0
    assert balance_error(r) < 1e-8
    assert r.tau_mean * speed < 0.0  # braking torque
    threshold = inv.V_dc + 2 * inv.V_f
    line = line_emf_max(drive, omega, r.theta_e)
    # the bridge conducts wherever the line EMF clearly exceeds the threshold ...
    clearly = line > threshold + 1.0
    clearly[0] = False  # the initial state: no current yet
    assert np.count_nonzero(clearly) > n // 4
    assert np.all(np.max(np.abs(r.i[clearly]), axis=1) > 0.0)
    # ... and not at all before the line EMF first reaches it
    first = int(np.argmax(line > threshold))
    if shape == "sinusoid":
        assert first > 5
    np.testing.assert_array_equal(r.i[:first], 0.0)


def test_dead_time_symmetric_pwm_standstill_no_current(lossy: bldclab.Drive) -> None:
    """All legs complementary PWM at 50 % with dead time: equal terminal voltages, no current from rest."""
    n = 100
    r = simulate_reference(lossy, 0.0, np.full((n, 3), PWM), np.full((n, 3), 0.5))
    np.testing.assert_array_equal(r.i, 0.0)
    assert r.E["src"] == 0.0


def test_dead_time_voltage_error_follows_current_sign(htm: bldclab.Drive) -> None:
    """a, b PWM at 50 %, c OFF, i_a > 0: in each dead time a's lower and b's upper diodes give v_ab = -V_dc.

    Mean line voltage -2 V_dc t_d / T: the current decays towards -V t_d f / R instead of 0 (exact piecewise
    solution checked at the samples).
    """
    t_d = 1e-6
    drive = htm.replace(inverter__t_dead=t_d)
    m, inv = drive.motor, drive.inverter
    n, d, i0 = 28, 0.5, 30.0
    modes = np.tile([PWM, PWM, OFF], (n, 1))
    duties = np.tile([d, d, 0.0], (n, 1))
    r = simulate_reference(drive, 0.0, modes, duties, i0=(i0, -i0, 0.0))
    T2 = half_period(drive)
    i = i0
    expect = [i]
    for k in range(n):
        t_edge = (1 - d) * T2 if k % 2 == 0 else d * T2
        for v, dt in ((0.0, t_edge), (-inv.V_dc, t_d), (0.0, T2 - t_edge - t_d)):
            i = rl_step(i, v, 2 * m.R, 2 * m.L, dt)
        expect.append(i)
    assert min(expect) > 1.0
    assert np.max(np.abs(r.i[:, 0] - np.array(expect))) < 1e-7
    np.testing.assert_array_equal(r.i[:, 2], 0.0)
    # without the dead-time error the current would only decay with L/R
    no_dt = i0 * math.exp(-n * T2 * m.R / m.L)
    assert no_dt - r.i[-1, 0] > 5.0
    assert balance_error(r) < 1e-8


def test_opening_phase_beyond_other_rail_goes_straight_to_other_diode(lossy: bldclab.Drive) -> None:
    """Rule 3: a phase whose diode current dies with its terminal beyond the other rail takes the other diode.

    a OFF with i_a > 0 (lower diode), b upper switch on, c OFF, spinning with a, b on their flat tops
    (e_a - e_b = E = 10 V > V_f): the current is driven to zero through a's lower diode; then a floats at
    v_bus + E > v_bus + V_f, so a's upper diode takes over and E drives a negative current round the + rail.
    Both stretches are exponentials, checked exactly; c (EMF on its ramp, below zero) stays open.
    """
    drive = lossy.replace(inverter__t_dead=0.0)
    m, inv = drive.motor, drive.inverter
    E = 10.0
    omega = E / (2 * m.k_phi)
    theta0, i0, n = 1.2, 20.0, 28
    modes = np.tile([OFF, HIGH, OFF], (n, 1))
    duties = np.tile([0.0, 1.0, 0.0], (n, 1))
    r = simulate_reference(drive, omega, modes, duties, theta0=theta0, i0=(i0, -i0, 0.0))
    k = m.emf.k_abc(r.theta_e)
    assert np.allclose(k[0], m.k_phi) and np.allclose(k[1], -m.k_phi) and np.all(k[2] < 0)
    # lower diode a, upper switch b: 2L di/dt = -(V + V_f + E) - (2R + r_d + R_on + R_src) i
    a1, r1 = inv.V_dc + inv.V_f + E, 2 * m.R + inv.r_d + inv.R_on + inv.R_src
    t1 = 2 * m.L / r1 * math.log((i0 + a1 / r1) / (a1 / r1))
    # upper diode a, upper switch b (i_dc = 0): 2L di/dt = V_f - E - (2R + r_d + R_on) i
    b2, r2 = inv.V_f - E, 2 * m.R + inv.r_d + inv.R_on
    expect = np.where(r.t < t1, -a1 / r1 + (i0 + a1 / r1) * np.exp(-r.t * r1 / (2 * m.L)),
                      b2 / r2 * (1 - np.exp(-(r.t - t1) * r2 / (2 * m.L))))
    assert 0 < t1 < r.t[-1] / 4
    assert np.max(np.abs(r.i[:, 0] - expect)) < 1e-7
    assert r.i[-1, 0] < -5.0
    np.testing.assert_array_equal(r.i[:, 2], 0.0)
    assert balance_error(r) < 1e-10


@pytest.mark.slow
@pytest.mark.parametrize("case", ["htm", "fast"])
def test_tolerance_convergence(lossy: bldclab.Drive, case: str) -> None:
    """rtol 1e-8 and 1e-11 give the same currents to 1e-6 A.

    On htm-48v (L/R = 1.5 ms against a 36 us half period) DOP853 is exact to rounding at any tolerance; the
    ``fast`` drive (L/R = 20 us, 2 kHz PWM) makes the step size tolerance-bound: there the comparison bites.
    """
    drive = lossy
    if case == "fast":
        drive = lossy.replace(motor__L=2e-6, motor__R=0.1, inverter__f_pwm=2000.0, inverter__t_dead=2e-6)
    omega = 0.5 * drive.Omega_0
    n = 120
    modes, duties = six_step(drive, omega, n, 0.7, PWM, theta0=0.4)
    runs = {rtol: simulate_reference(drive, omega, modes, duties, theta0=0.4, rtol=rtol, atol=rtol)
            for rtol in (1e-6, 1e-8, 1e-11)}
    coarse, fine = runs[1e-8], runs[1e-11]
    assert np.max(np.abs(fine.i)) > 50.0 and fine.tau_mean > 0.0
    assert np.max(np.abs(coarse.i - fine.i)) < 1e-6
    assert coarse.tau_mean == pytest.approx(fine.tau_mean, rel=1e-7)
    assert balance_error(fine) < 1e-10
    if case == "fast":  # the tolerance does matter here: a loose one is visibly off
        assert np.max(np.abs(runs[1e-6].i - fine.i)) > 1e-7

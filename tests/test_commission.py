"""Self-commissioning (``bc_commission.h``, ``bl.commission``; ``docs/sensorless-sine.md``): R, L and the flux
linkage the controller measures against the plant's true values on every catalog drive, independence from the
nominal data it is configured from, the named failure statuses, the estimated drive in ``estimate=``, and the CLI.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import bldclab as bl
from bldclab.analysis.commission import Estimate, commission
from bldclab.control.commission import Commission
from bldclab.control.sine import fundamental_k1
from bldclab.errors import BldclabError
from bldclab.model.analytic import r_total
from bldclab.model.catalog import names
from bldclab.sim import Fault
from test_sensorless_sine import angle_error, observer, run_point

# Tolerances against the plant (tighter than the goals of 2 %, 5 %, 2 %; measured: 0.04 %, 0.08 %, 0.05 %
# at most on the catalog): the two-level R cancels the inverter's constant errors, L integrates u - R i against the
# held point, the flux divides the back-EMF by the rotor's own travel.
TOL_R, TOL_L, TOL_PSI = 0.005, 0.01, 0.01


def true_values(d: bl.Drive) -> tuple[float, float, float]:
    """The plant's R + R_on (Ohm), L (H) and psi_f = k_1 / p (V s)."""
    return r_total(d), d.motor.L, fundamental_k1(d) / d.motor.p


def assert_commissioned(d: bl.Drive, rel_r: float, rel_l: float, rel_psi: float) -> Estimate:
    """Commission the plant ``d`` on its own data: DONE, and R + R_on, L, psi_f within the relative tolerances."""
    e = commission(d)
    assert e.status == "DONE"
    R, L, psi = true_values(d)
    assert e.R == pytest.approx(R, rel=rel_r)
    assert e.L == pytest.approx(L, rel=rel_l)
    assert e.psi_f == pytest.approx(psi, rel=rel_psi)
    return e


@pytest.mark.slow
@pytest.mark.parametrize("name", names())
def test_catalog_accuracy(name: str) -> None:
    """Every catalog drive, free rotor at rest: DONE, and R, L, psi_f within the stated tolerances."""
    d = bl.load(name)
    e = assert_commissioned(d, TOL_R, TOL_L, TOL_PSI)
    assert 0 < e.t_test < 1.05 * Commission().duration(d)


@pytest.mark.slow
def test_wrong_nominal_data_do_not_enter_the_results() -> None:
    """Configured from nominal data off by R x1.5, L x0.7, flux x1.25 (they set only currents, timing and gains),
    the measurement is still the plant's, within the same tolerances."""
    d = bl.load("servo-2k2")
    e = commission(d, nominal=d.scaled(R=1.5, L=0.7, emf=1.25))
    assert e.status == "DONE"
    R, L, psi = true_values(d)
    assert e.R == pytest.approx(R, rel=TOL_R)
    assert e.L == pytest.approx(L, rel=TOL_L)
    assert e.psi_f == pytest.approx(psi, rel=TOL_PSI)
    est = e.drive
    assert est.motor.R == pytest.approx(d.motor.R, rel=TOL_R)
    assert fundamental_k1(est) == pytest.approx(fundamental_k1(d), rel=TOL_PSI)


def test_statuses_are_named() -> None:
    """Impossible conditions end in a named status, never a table: a dynamometer turning the rotor (ROTOR_MOVING),
    an open phase (NO_CURRENT), a spin whose back-EMF exceeds the bus (SATURATED), a rotor too heavy to follow
    the I/f ramp (NOT_FOLLOWING); the estimated drive of a failed run raises, naming the status."""
    d = bl.load("outrunner-24v")
    assert commission(d, speed=0.05 * d.Omega_0).status == "ROTOR_MOVING"
    assert commission(d, faults=(Fault("phase_open", "a", 0.0),)).status == "NO_CURRENT"
    assert commission(d, control=Commission(spin_speed=1.5 * d.Omega_0)).status == "SATURATED"
    heavy = dataclasses.replace(d, mechanics=dataclasses.replace(d.mechanics, J=1e4 * d.mechanics.J))
    e = commission(heavy, nominal=d)
    assert e.status == "NOT_FOLLOWING"
    with pytest.raises(BldclabError) as err:
        _ = e.drive
    assert err.value.field == "commission.status" and "NOT_FOLLOWING" in err.value.problem


def test_settings_errors() -> None:
    """Settings errors name the field."""
    with pytest.raises(BldclabError) as e:
        Commission(pulses=0)
    assert e.value.field == "control.pulses"
    d = bl.load("outrunner-24v")
    with pytest.raises(BldclabError) as e:
        commission(d, control=Commission(test_current=3 * d.motor.I_N))
    assert e.value.field == "control.test_current"


@pytest.mark.slow
def test_commissioning_restores_the_observer_angle() -> None:
    """htm-48v, flux observer at 0.5 Omega_0 with half the rated load: configured with a flux linkage 25 % high the
    angle error grows (measured several degrees; the controller's own zero-current flux reading off, which would
    correct it at the start); configured from what commissioning measured on the plant (starting from that wrong
    nominal data), it is within 0.1 deg of the true-parameter case (issue goal: 1 deg)."""
    d = bl.load("htm-48v")
    ctl = observer(d, 0.5, if_flux_estimate=False)

    def mean_abs_err(estimate: bl.Drive | None) -> float:
        r, m = run_point(d, ctl, 0.5, periods=10, estimate=estimate)
        assert np.all(r["mode"][m] == 1)
        return float(np.mean(np.abs(np.degrees(angle_error(r, m)))))

    wrong = d.scaled(emf=1.25)
    e_true, e_wrong = mean_abs_err(None), mean_abs_err(wrong)
    e_comm = mean_abs_err(commission(d, nominal=wrong).drive)
    assert e_wrong > e_true + 1.0
    print(f"mean |angle error|: true {e_true:.3f} deg, flux +25 % {e_wrong:.3f} deg, commissioned {e_comm:.3f} deg")
    assert abs(e_comm - e_true) < 0.1, (e_true, e_wrong, e_comm)


def test_cli(capsys: pytest.CaptureFixture[str]) -> None:
    """``bldclab commission MOTOR`` prints the values against the motor file's and exits 0 when DONE."""
    from bldclab.cli import main

    assert main(["commission", "f60prov-2550kv", "--format", "json"]) == 0
    out = capsys.readouterr().out
    assert '"status": "DONE"' in out
    assert main(["commission", "no-such-motor"]) == 2


@pytest.mark.slow
@pytest.mark.parametrize("name", ["htm-48v", "outrunner-24v"])
def test_inverter_errors_within_the_goals(name: str) -> None:
    """With a dead time of 1 % of the PWM period, 0.7 V diodes and switch on-resistance 20 % of R in the plant (the
    routine told the dead time and the diode drop, as firmware knows its own inverter): R + R_on within 2 %, L
    within 5 %, psi_f within 2 % (the issue's goals; measured 0.4 %, 0.02 %, 0.06 %). The two-level R and the pulses
    about a held point cancel the dead time's constant voltage error; the spin takes it off its voltage (before:
    psi_f -0.23 % and +0.81 %)."""
    d = bl.load(name)
    inv = dataclasses.replace(d.inverter, t_dead=0.01 / d.inverter.f_pwm, V_f=0.7, R_on=0.2 * d.motor.R)
    assert_commissioned(dataclasses.replace(d, inverter=inv), 0.02, 0.05, 0.02)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "t_dead"), [("f60prov-2550kv", 0.94e-6), ("mn3110-780kv", 0.94e-6)])
def test_the_spin_takes_the_dead_time_off_its_voltage(name: str, t_dead: float) -> None:
    """The drone motors with an AM32 ESC's dead time (0.94 us: 4.5 % of f60prov-2550kv's 48-kHz period) and their
    catalog body diodes: the spin's back-EMF kept the dead time's voltage loss, psi_f +21.8 % and +8.5 %; the
    routine now takes off each leg's loss or gain at its edges, with the PWM ripple's share of the edge currents
    (bc_commission.h): psi_f within 0.5 % (measured +0.06 %, -0.07 %)."""
    d = bl.load(name)
    assert_commissioned(dataclasses.replace(d, inverter=dataclasses.replace(d.inverter, t_dead=t_dead)), 0.02, 0.05,
                        0.005)

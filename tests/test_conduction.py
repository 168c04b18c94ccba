"""Discontinuous conduction and a PWM ripple larger than the reference: measured on the plant, named to the user.

A six-step current loop at a current below its PWM ripple delivered 1 to 6 times the reference's torque without a
word (a low-inductance drive: a 1-pole-pair high-speed motor, a drone motor). The plant integrates the time during
which every phase current is zero (``Metrics.zero_current_share``); a current-regulated run with any of it, or whose
estimated ripple exceeds the reference, is reported as a named plausibility warning.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import bldclab as bl
from bldclab.analysis.experiments import steady_state
from bldclab.cli import main
from bldclab.sim.plausibility import pwm_ripple

#: A 1-pole-pair high-speed motor of 30 uH at 16 kHz: 42,800 rpm no-load speed, 4.4 A peak-to-peak ripple at half
#: of it, 50.7 A rated
FAST = bl.load("f60prov-2550kv").replace(motor__p=1, motor__L=30e-6, inverter__f_pwm=16e3)
W = 0.5 * FAST.Omega_0


def _run(ctl: bl.SixStep, current: float, **kw: object) -> tuple[bl.SimResult, list[str]]:
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        _, res = steady_state(FAST, ctl, W, current, **kw)
    return res, [str(r.message) for r in rec]


def test_zero_current_share_is_the_plants_and_follows_the_ripple_closed_form():
    """At a reference well below half the ripple (closed form 4.4 A peak-to-peak) the plant's currents are all zero
    for a fifth of the time: the integrated share matches a 32-rows-per-sample trace's share of all-zero rows to its
    resolution, and the current reaches zero in most PWM periods; at twice half the ripple the share is exactly 0."""
    ripple, d = pwm_ripple(FAST, W, 1.0, "pwm-on-pwm")
    assert ripple == pytest.approx(FAST.inverter.V_dc * d * (1 - d) / (2 * FAST.motor.L * FAST.inverter.f_pwm))
    assert 4.0 < ripple < 4.6
    _, res = steady_state(FAST, bl.SixStep(), W, 0.25 * ripple, trace=True, trace_sub=32)
    m = res.metrics
    assert m is not None
    sel = (res.t >= m.t0) & (res.t < m.t1)
    zero = (res.i_a[sel] == 0.0) & (res.i_b[sel] == 0.0) & (res.i_c[sel] == 0.0)
    assert m.zero_current_share > 0.1
    assert abs(zero.mean() - m.zero_current_share) < 0.01
    periods = np.floor((res.t[sel] - m.t0) * FAST.inverter.f_pwm).astype(int)
    touched = np.unique(periods[zero])
    assert touched.size > 0.5 * (periods.max() + 1)  # the current falls to zero within most PWM periods
    m_hi = steady_state(FAST, bl.SixStep(), W, ripple)[0].metrics
    assert m_hi.zero_current_share == 0.0


@pytest.mark.parametrize("regulation", ["predictive", "pi"])
def test_discontinuous_conduction_is_named_and_continuous_conduction_is_not(regulation: str):
    """Below half the ripple both current loops miss the reference's torque (by more than 30 % here) and the run
    warns `result.discontinuous_conduction` with the measured share; at three times the ripple nothing is said."""
    ripple = pwm_ripple(FAST, W, 1.0, "pwm-on-pwm")[0]
    i_low = 0.25 * ripple
    res, caught = _run(bl.SixStep(regulation=regulation), i_low)
    m = res.metrics
    assert m is not None
    tau_ref = 2.0 * FAST.motor.k_phi * i_low
    assert abs(m.tau_mean / tau_ref - 1.0) > 0.3  # the defect the warning is about
    named = [w for w in caught if w.startswith("result.discontinuous_conduction")]
    assert len(named) == 1 and f"{100 * m.zero_current_share:.3g} %" in named[0]
    assert named[0] in res.meta["warnings"]
    res_hi, caught_hi = _run(bl.SixStep(regulation=regulation), 3.0 * ripple)
    assert res_hi.metrics.zero_current_share == 0.0
    assert not [w for w in caught_hi if "conduction" in w or "ripple" in w]


def test_ripple_larger_than_the_reference_is_named_with_complementary_chopping():
    """Sync chopping never opens the phases (the current reverses instead): no zero-current time, but with the
    estimated ripple above the reference the run warns `result.current_ripple`; the mean torque is off by more than
    at a reference above the ripple (the sinusoidal back-EMF's 0.955 of 2 k_phi I is the continuous value)."""
    ripple = pwm_ripple(FAST, W, 1.0, "sync")[0]
    res, caught = _run(bl.SixStep(chopping="sync"), 0.25 * ripple)
    assert res.metrics.zero_current_share == 0.0
    assert [w for w in caught if w.startswith("result.current_ripple")]
    hi, caught_hi = _run(bl.SixStep(chopping="sync"), 3.0 * ripple)
    assert not [w for w in caught_hi if w.startswith("result.")]
    k = 2.0 * FAST.motor.k_phi
    err_lo = abs(res.metrics.tau_mean / (k * 0.25 * ripple) - 3.0 / math.pi)
    err_hi = abs(hi.metrics.tau_mean / (k * 3.0 * ripple) - 3.0 / math.pi)
    assert err_lo > 3 * err_hi


def test_cli_names_discontinuous_conduction(tmp_path, capsys):
    """`bldclab simulate` prints the share and the named warning on stderr; the JSON metrics carry both."""
    path = tmp_path / "fast.toml"
    path.write_text(FAST.to_toml())
    rc = main(["simulate", str(path), "--current", "1 A", "--speed", "0.5 pu", "--no-trace"])
    out, err = capsys.readouterr()
    assert rc == 0
    assert "zero_current_pct" in out and "bldclab: warning: result.discontinuous_conduction:" in err

"""The desync map (bldclab.analysis.desync, bldclab sensorless): the plant's truth on commutation angles, the
classification of a run, the map on a tiny grid (independent of the worker count) and the command's errors."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pandas as pd
import pytest

import bldclab as bl
from bldclab.analysis import desync as ds
from bldclab.analysis import sensorless as sl
from bldclab.analysis.desync import Axis, Observation, ThrottleStep, classify, commutation_errors, desync_map, observe
from bldclab.cli import main
from bldclab.errors import BldclabError
from conftest import require_module

DEG = math.pi / 180.0
_POS_NEG = {0: (0, 1), 1: (0, 2), 2: (1, 2), 3: (1, 0), 4: (2, 0), 5: (2, 1)}  # docs/conventions.md


def synthetic(direction: int = 1, adv_deg: float = 10.0, shift_deg: float = 0.0, t_shift: float = 1.0,
              w_e: float = 2000.0, t_half: float = 10e-6, n: int = 3000, theta0: float = 0.3,
              flags: dict[int, int] | None = None, stop: tuple[int, int] | None = None,
              demag_deg: float = 20.0) -> dict[str, np.ndarray]:
    """A trace of a six-step drive commutating a rotor turning at w_e (electrical rad/s) in direction, each
    commutation at the first sample past its angle pi/6 + s pi/3 - adv (forward; backward at pi/2 + s pi/3 + adv),
    from t_shift on shift_deg earlier; the floating phase's current falling linearly from 50 A at that angle to zero
    demag_deg later; flags {row: bits}; stop (row0, row1): legs off and state 0 between them."""
    t = np.arange(n) * t_half
    theta = (theta0 + direction * w_e * t) % (2.0 * math.pi)
    adv = adv_deg * DEG
    shift = np.where(t >= t_shift, shift_deg * DEG, 0.0)
    s = np.floor((theta + direction * (adv + shift) - math.pi / 6.0) / (math.pi / 3.0)).astype(int) % 6
    pair = s if direction > 0 else (s + 3) % 6
    modes = np.zeros((3, n))
    cur = np.zeros((3, n))
    for j in range(n):
        p, q = _POS_NEG[int(pair[j])]
        modes[p, j], modes[q, j] = 1, 3
        start = math.pi / 3.0 + s[j] * math.pi / 3.0 - direction * (math.pi / 6.0 + adv + shift[j])
        phi = (direction * (theta[j] - start)) % (2.0 * math.pi)
        cur[3 - p - q, j] = 50.0 * min(max(1.0 - phi / (demag_deg * DEG), 0.0), 1.0)
    state = np.full(n, 3.0)
    if stop is not None:
        modes[:, stop[0]:stop[1]] = 0
        state[stop[0]:stop[1]] = 0
    ctrl = np.zeros(n)
    for j, bits in (flags or {}).items():
        ctrl[j] = bits
    return {"t": t, "theta_e": theta, "mode_a": modes[0], "mode_b": modes[1], "mode_c": modes[2], "state": state,
            "omega_e": np.full(n, direction * w_e), "advance": np.full(n, adv), "ctrl_flags": ctrl,
            "demag": np.zeros(n), "omega_m": np.zeros(n), "i_a": cur[0], "i_b": cur[1], "i_c": cur[2]}


# ------------------------------------------------------------------------------------------------------------
# the truth


@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("adv", [0.0, 10.0, 25.0])
def test_commutations_at_their_angle_are_within_one_sample_of_zero_error(direction, adv):
    sig = synthetic(direction, adv)
    c = commutation_errors(sig)
    travel = 2000.0 * 10e-6
    turns = 2000.0 * sig["t"][-1] / (math.pi / 3.0)
    assert len(c) >= math.floor(turns) - 1  # every commutation found
    assert set(c.direction) == {direction}
    assert (c.certain == 0.0).all()  # the sample holding each commutation brackets its ideal angle
    assert (c.err_lo >= -1e-12).all() and (c.err_hi <= 1e-12).all() and (c.err_lo - c.err_hi <= travel + 1e-12).all()
    assert sorted(set(c.sector)) == list(range(6))


@pytest.mark.parametrize("direction", [1, -1])
def test_a_commutation_40_degrees_early_is_out_of_sync_and_20_degrees_is_not(direction):
    c40 = commutation_errors(synthetic(direction, 5.0, shift_deg=40.0, t_shift=0.01))
    after = c40[c40.t > 0.0101]
    assert (after.err > 39.0 * DEG).all() and (after.err < 41.5 * DEG).all()
    assert (after.certain > ds.DEFAULT_BOUND).all()
    assert (c40[c40.t < 0.01].certain == 0.0).all()
    c20 = commutation_errors(synthetic(direction, 5.0, shift_deg=20.0, t_shift=0.01))
    assert (c20.certain < ds.DEFAULT_BOUND).all() and c20.err.max() > 19.0 * DEG
    late = commutation_errors(synthetic(direction, 5.0, shift_deg=-40.0, t_shift=0.01))
    assert (late[late.t > 0.0101].err < -38.0 * DEG).all()


@pytest.mark.parametrize("direction", [1, -1])
def test_a_late_commutation_that_only_loses_its_advance_is_still_in_sync(direction):
    """Out of sync: more than the bound earlier than the advanced angle, or later than the rotor's own sector
    boundary (the Hall-exact angle). 40 degrees late with a 30-degree advance is 10 degrees late for the rotor (in
    sync); with a 5-degree advance 35 (out); 40 degrees early is out whatever the advance."""
    def out(adv, shift):
        c = commutation_errors(synthetic(direction, adv, shift_deg=shift, t_shift=0.01))
        c = c[c.t > 0.0101]
        assert len(c) > 10 and np.allclose(c.adv, adv * DEG)
        return ds.out_of_sync(c)

    assert not out(30.0, -40.0).any()
    assert out(5.0, -40.0).all()
    assert out(30.0, 40.0).all() and out(5.0, 40.0).all()
    assert not out(30.0, -20.0).any() and not out(5.0, 20.0).any()


@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("adv, demag", [(0.0, 20.0), (10.0, 25.0), (0.0, 35.0)])
def test_the_demagnetisation_and_its_margin_to_the_crossing_from_the_currents(direction, adv, demag):
    """The floating phase's current ends demag degrees after the ideal commutation angle: the margin to the
    crossing (30 + adv degrees after it) is exact, the demagnetisation within half a sample, the time at the speed."""
    c = commutation_errors(synthetic(direction, adv, demag_deg=demag))
    c = c.iloc[1:-1]  # the first and last sectors are cut by the trace
    assert c.ended.all()
    assert np.allclose(c.margin, (30.0 + adv - demag) * DEG, atol=1e-9)
    assert np.allclose(c.margin_time, c.margin / 2000.0, rtol=1e-9)
    assert (np.abs(c.demag - demag * DEG) <= 0.5 * 2000.0 * 10e-6 + 1e-9).all()


def test_a_demagnetisation_longer_than_the_sector_has_not_ended():
    c = commutation_errors(synthetic(1, 0.0, demag_deg=80.0)).iloc[1:-1]
    assert not c.ended.any() and (c.margin < -25.0 * DEG).all()


def test_the_demagnetisation_ends_at_the_plants_event_whatever_the_trace():
    """The outgoing current's end is the plant's own event (t_iz_*): with one trace row per sample (f60prov-2550kv
    at 24 kHz and 0.5 Omega_0: 20 degrees a sample) it is the 8-rows-a-sample trace's to 1e-3 degree, and an
    independent reading of the fine trace (its currents' last rows extrapolated to zero, t_iz removed; 2.5 degrees
    a row) agrees within 1 degree; the same reading of the one-row trace was off by up to 12 degrees."""
    drive = bl.load("f60prov-2550kv").replace(inverter__f_pwm=24e3)
    demag = {}
    for sub in (1, 8):
        res, t0 = sl.run_locked(drive, 0.5, 0.6, periods=6, trace_sub=sub)
        sig = dict(res.signals)
        rows_only = {k: v for k, v in sig.items() if not k.startswith("t_iz")}
        ev, ro = commutation_errors(sig, 1), commutation_errors(rows_only, 1)
        demag[sub] = (ev[ev.t > t0].demag.to_numpy()[:24], ro[ro.t > t0].demag.to_numpy()[:24])
    assert demag[1][0].size == 24 and np.isfinite(demag[1][0]).all()
    assert np.max(np.abs(demag[1][0] - demag[8][0])) < 1e-3 * DEG
    assert np.max(np.abs(demag[8][1] - demag[8][0])) < 1.0 * DEG
    assert np.max(np.abs(demag[1][1] - demag[1][0])) > 3.0 * DEG


@pytest.mark.parametrize("timed", [False, True])
def test_hall_six_step_on_the_plant_commutates_where_its_law_says(timed):
    """Real plant, Hall six-step at an imposed speed (the truth measure itself, against drives whose commutation
    instants are known): on the edges seen, every commutation one to two samples after the sector boundary (the edge
    seen at the next sample, applied one later); with the commutation timer at the edge predicted from the Hall speed,
    at the boundary to 0.001 of a sample once the speed is known (after two edges)."""
    drive = bl.load("htm-48v")
    ctl = bl.SixStep(timed=True) if timed else bl.SixStep(advance=False)
    res = bl.simulate(drive, ctl, bl.Scenario(duration=0.05, speed="0.5 pu", ref=drive.motor.I_N))
    sig = dict(res.signals)
    n = sig["t"].size
    sig.update(state=np.full(n, 3.0), advance=np.zeros(n), omega_e=np.ones(n))
    c = commutation_errors(sig)
    travel = drive.motor.p * 0.5 * drive.Omega_0 * 0.5 / drive.inverter.f_pwm  # rad per sample
    assert len(c) >= 12 and (c.err_lo == c.err_hi).all()  # the trace's t_at: the instant is known
    if timed:
        assert (c.err.iloc[2:].abs() < 1e-3 * travel).all()
    else:
        assert (c.err <= -travel + 1e-9).all() and (c.err >= -2.0 * travel - 1e-9).all()


# ------------------------------------------------------------------------------------------------------------
# classification


def obs(**kw):
    base = {"t_step": 0.2, "t_end": 0.6, "closed": ((0.1, 0.6),), "settle": 0.05,
            "commutations": tuple(np.linspace(0.1, 0.6, 200))}
    base.update(kw)
    return Observation(**base)


def test_classify_sync():
    assert classify(obs()) == ("sync", "")


def test_classify_desync_with_its_reason_and_not_back():
    o = obs(desyncs=((0.25, "ZC_HIDDEN"), (0.45, "START_FAIL")), closed=((0.1, 0.25),),
            commutations=tuple(np.linspace(0.1, 0.25, 60)))
    assert classify(o) == ("desync", "ZC_HIDDEN")


def test_classify_recovered_needs_the_tail_in_sync_and_closed_to_the_end():
    comms = tuple(np.linspace(0.1, 0.25, 60)) + tuple(np.linspace(0.4, 0.6, 80))
    o = obs(desyncs=((0.25, "ZC_JUMP"),), closed=((0.1, 0.25), (0.4, 0.6)), commutations=comms)
    assert classify(o) == ("recovered", "ZC_JUMP")
    # back in closed loop but a commutation of the tail out of sync: not recovered
    assert classify(obs(desyncs=((0.25, "ZC_JUMP"),), closed=((0.1, 0.25), (0.4, 0.6)), commutations=comms,
                        out_of_sync=(0.59,))) == ("desync", "ZC_JUMP")
    # too few commutations since the restart
    short = (*np.linspace(0.1, 0.25, 60), 0.59, 0.595)
    assert classify(obs(desyncs=((0.25, "ZC_JUMP"),), closed=((0.1, 0.25), (0.58, 0.6)),
                        commutations=short)) == ("desync", "ZC_JUMP")


def test_classify_undetected_when_the_truth_leaves_sync_before_any_flag():
    assert classify(obs(out_of_sync=(0.3,))) == ("undetected", "")
    # out of sync before the flag came: flagged, the truth agrees (not undetected)
    o = obs(out_of_sync=(0.3,), desyncs=((0.29, "ZC_TIMEOUT"),), closed=((0.1, 0.29),),
            commutations=tuple(np.linspace(0.1, 0.29, 70)))
    assert classify(o) == ("desync", "ZC_TIMEOUT")
    o = obs(out_of_sync=(0.28,), desyncs=((0.29, "ZC_TIMEOUT"),), closed=((0.1, 0.29),),
            commutations=tuple(np.linspace(0.1, 0.29, 70)))
    assert classify(o) == ("undetected", "")


def test_classify_no_start_when_not_steady_at_the_step():
    assert classify(obs(closed=((0.17, 0.6),))) == ("no start", "")  # closed loop only 30 ms of the 50 required
    assert classify(obs(closed=(), desyncs=((0.15, "START_FAIL"),))) == ("no start", "START_FAIL")
    assert classify(obs(desyncs=((0.18, "STALL"),))) == ("no start", "STALL")
    assert classify(obs(out_of_sync=(0.19,))) == ("no start", "")


def test_classify_a_start_up():
    comms = tuple(np.linspace(0.15, 0.6, 100))
    assert classify(obs(t_step=0.0, closed=((0.15, 0.6),), commutations=comms)) == ("sync", "")
    assert classify(obs(t_step=0.0, closed=(), commutations=(), desyncs=((0.1, "START_FAIL"),))) == (
        "no start", "START_FAIL")
    assert classify(obs(t_step=0.0, closed=((0.3, 0.6),), desyncs=((0.1, "START_FAIL"),),
                        commutations=tuple(np.linspace(0.3, 0.6, 50)))) == ("recovered", "START_FAIL")
    assert classify(obs(t_step=0.0, closed=(), commutations=())) == ("no start", "")


def test_observe_reads_flags_states_and_the_truth_from_a_trace():
    hidden = ds._FLAG_BITS["DESYNC"] | ds._FLAG_BITS["ZC_HIDDEN"]
    sig = synthetic(1, 10.0, flags={1500: hidden, 1501: hidden}, stop=(1501, 2000), n=4000)
    o, _ = observe(sig, t_step=0.01, settle=0.005)
    assert o.desyncs == ((pytest.approx(0.015), "ZC_HIDDEN"),)  # one event for the two flagged samples
    assert len(o.closed) == 2 and o.closed[1][0] == pytest.approx(0.02)
    assert o.out_of_sync == ()
    assert classify(o) == ("recovered", "ZC_HIDDEN")
    trip = ds._FLAG_BITS["SAFE"] | ds._FLAG_BITS["OVERCURRENT"]
    o2, _ = observe(synthetic(1, 10.0, flags={1500: trip}, stop=(1501, 4000), n=4000), t_step=0.01, settle=0.005)
    assert classify(o2) == ("desync", "OVERCURRENT")
    # the controller commutating 40 degrees early from 15 ms on without a flag: the truth catches it
    o3, _ = observe(synthetic(1, 10.0, shift_deg=40.0, t_shift=0.015, n=4000), t_step=0.01, settle=0.005)
    assert classify(o3) == ("undetected", "")


def test_steady_since_finds_the_first_closed_loop_stretch_long_enough():
    hidden = ds._FLAG_BITS["DESYNC"] | ds._FLAG_BITS["ZC_HIDDEN"]
    sig = synthetic(1, 10.0, flags={1500: hidden}, stop=(1501, 2000), n=4000)  # 10 us rows
    sig["state"][:300] = 2.0  # the ramp until 3 ms
    assert ds.steady_since(sig, 0.01) == pytest.approx(0.013)
    assert ds.steady_since(sig, 0.015) == pytest.approx(0.035)  # 3-15 ms too short, from 20 ms on
    assert ds.steady_since(sig, 0.03) is None


# ------------------------------------------------------------------------------------------------------------
# the inputs


@pytest.mark.parametrize("kw, field", [
    ({"start": 1.0}, "step.start"), ({"end": 0.0}, "step.end"), ({"end": math.nan}, "step.end"),
    ({"settle": -1.0}, "step.settle"), ({"observe": 20.0}, "step.observe"), ({"theta0": math.inf}, "step.theta0"),
])
def test_throttle_step_errors_name_the_field(kw, field):
    with pytest.raises(BldclabError) as e:
        ThrottleStep(**kw)
    assert e.value.field == field


@pytest.mark.parametrize("name, values", [("nope", (1,)), ("timing", ()), ("timing", (40.0,)), ("timing", (1, 1)),
                                          ("rate", (0.0,)), ("k_q", (-1e-8,)), ("chopping", ("fast",)),
                                          ("f_pwm", (math.nan,)), ("end", ("x",)), ("fast_demag", ("maybe",)),
                                          ("demag_limit", (1.0,)), ("delay", (0.5,)), ("delay", (2,))])
def test_axis_errors(name, values):
    with pytest.raises(BldclabError):
        Axis(name, values)


def test_step_times_follow_the_drive():
    drive = bl.load("f60prov-2550kv")
    ctl = bl.SixStepSensorless(align_time=0.0)
    st = ThrottleStep(0.25, 0.8)
    su = ctl.start_up(drive)
    tau = drive.mechanics.J / ((2 * drive.motor.k_phi) ** 2 / (2 * drive.motor.R) + drive.mechanics.B
                               + 2 * drive.mechanics.k_q * 0.25 * drive.Omega_0)
    assert st.settle_time(drive) == pytest.approx(max(5 * tau, 0.02))
    assert 2 * su["ramp_time"] + float(ctl.restart_max) < st.start_time(drive, ctl) < 3.0
    assert float(ctl.restart_max) < st.observe_time(drive, ctl) < 3.0
    given = ThrottleStep(0.25, 0.8, settle=0.1, observe=0.2)
    assert given.settle_time(drive) == 0.1 and given.observe_time(drive, ctl) == 0.2


# ------------------------------------------------------------------------------------------------------------
# the map


@pytest.fixture(scope="module")
def f60():
    return bl.load("f60prov-2550kv")


def _tiny(drive, workers, control=None):
    return desync_map(drive, Axis("timing", (0.0, 20.0)), Axis("rate", (20.0,)),
                      step=ThrottleStep(0.3, 0.7, settle=0.02, observe=0.05),
                      control=control or bl.SixStepSensorless(), workers=workers)


@pytest.mark.slow  # a process pool
def test_the_map_does_not_depend_on_the_worker_count(f60):
    one = _tiny(f60, 1)
    two = _tiny(f60, 2)
    assert list(one.points.outcome) == ["sync", "sync"]  # points that ran through the step, not empty ones
    pd.testing.assert_frame_equal(one.points, two.points)


@pytest.mark.slow  # a local Dask cluster
def test_a_dask_cluster_gives_the_same_map(f60):
    require_module("distributed")
    import distributed  # optional dependency, imported only when present

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        res = desync_map(f60, Axis("timing", (0.0, 20.0)), Axis("rate", (20.0,)),
                         step=ThrottleStep(0.3, 0.7, settle=0.02, observe=0.05),
                         control=bl.SixStepSensorless(), executor=client.get_executor())
    pd.testing.assert_frame_equal(_tiny(f60, 1).points, res.points)


@pytest.mark.slow  # four steps on the plant
def test_a_punch_on_the_5_inch_motor_holds_sync_with_the_protections_and_loses_it_without():
    """f60prov-2550kv, 0.25 -> 0.9 at once, no advance and 10 degrees, from three initial rotor angles (each start
    leaves the closed loop in another state at the step): the controller's defaults keep every commutation within a
    few degrees of its true angle and the crossing visible at five of the six points (the margin is thin: at the
    sixth the controller takes a crossing the plant shows 4 degrees clear of the clamp for hidden and stops,
    ZC_HIDDEN); without fast demagnetisation and the limiter the crossing is hidden (ZC_HIDDEN) at every point, and
    the plant's demagnetisation ends within a few degrees of the crossing or after it."""
    drive = bl.load("f60prov-2550kv")
    step = ThrottleStep(0.25, 0.9, observe=0.15)
    angles = Axis("theta0", (0.0, 120.0, 240.0))
    ok = desync_map(drive, Axis("timing", (0.0, 10.0)), angles, step=step, workers=1).points
    held = ok[ok.outcome == "sync"]
    assert len(held) >= 5 and set(ok.outcome) <= {"sync", "desync"} and not ok.truth_lost.any(), ok
    assert set(ok[ok.outcome != "sync"].reason) <= {"ZC_HIDDEN"}
    assert (held.angle_max_deg < 15.0).all() and (held.margin_deg > 1.0).all()
    raw = desync_map(drive, Axis("timing", (0.0, 10.0)), angles, step=step, workers=1,
                     control=bl.SixStepSensorless(fast_demag=False, demag_limit=0.0)).points
    assert (raw.outcome == "desync").all() and (raw.reason == "ZC_HIDDEN").all()
    assert (raw.margin_deg < 3.0).all() and not raw.truth_lost.any()  # the controller gave up before any drift


@pytest.mark.slow  # one step through a restart, about 1.4 s of the plant
def test_a_desync_that_the_restart_recovers_is_classified_recovered(f60):
    """f60prov-2550kv on an ideal inverter (its catalog entry before 2026-11-26: no diode drop, no R_on; its margin
    at timing 0 is thin), the default step 0.25 -> 0.8 at once, no advance, with the fast demagnetisation engaged
    only once the clamp has taken 0.45 of the window: the step's clamp hides a crossing (ZC_HIDDEN), the controller
    stops, restarts and is back in closed loop and in sync to the end; the plant's truth never left sync before the
    flag. The default for that drive (engaged from the commutation, 0) keeps the step in sync from the three
    initial rotor angles (margins 3.2 to 4.4 degrees; 2.5 to 2.8 with delay 1). (With delay 0 and the two-step
    alignment before 2026-11-27 the crossing came 1.6-2.1 degrees after the clamp's end, under a fifth of a sample,
    and was hidden at all three: one recovered, two lost by the restart into the propeller's spin-down. The catalog
    entry, with its 0.77 V body diodes, holds the step at every point of its map: docs/desync.md.)"""
    f60 = f60.replace(inverter=dataclasses.replace(f60.inverter, V_f=0.0, R_on=0.0))
    pts = desync_map(f60, Axis("timing", (0.0,)), workers=1,
                     control=bl.SixStepSensorless(fast_demag_after=0.45)).points
    row = pts.iloc[0]
    assert (row.outcome, row.reason, int(row.restarts)) == ("recovered", "ZC_HIDDEN", 1), row
    assert not row.truth_lost and row.t_desync_ms > 0.0
    ok = desync_map(f60, Axis("theta0", (0.0, 120.0, 240.0)), workers=1).points
    assert set(ok.outcome) <= {"sync", "recovered"} and (ok.outcome == "sync").sum() >= 2, ok


def test_the_map_runs_the_controllers_delay():
    """The map's runs take the controller's delay (they took the Scenario's default 1 whatever it was). At 24 kHz
    and 30 degrees of timing f60prov-2550kv's commutation is due at the crossing itself: an output applied a sample
    after the crossing is seen loses most of the advance and the punch desyncs; applied within the sample, as an
    ESC's commutation timer acts, the commutations come later than meant by less and the drive holds."""
    drive = bl.load("f60prov-2550kv").replace(inverter__f_pwm=24e3)
    res = desync_map(drive, Axis("delay", (1.0, 0.0)), Axis("timing", (30.0,)), workers=1, summarise=False)
    late = dict(zip(res.points.delay, res.points.angle_mean_deg, strict=True))
    outcome = dict(zip(res.points.delay, res.points.outcome, strict=True))
    assert late[1.0] < -15.0 and -15.0 < late[0.0] < 0.0, late
    assert outcome == {1.0: "desync", 0.0: "sync"}, outcome


def test_the_map_on_a_tiny_grid(f60):
    res = _tiny(f60, 1, bl.SixStepSensorless(align_time=0.0))
    p = res.points
    assert list(p.timing) == [0.0, 20.0] and list(p.rate) == [20.0, 20.0]
    assert set(p.outcome) <= set(ds.OUTCOMES)
    assert all(r == "" or r in ds.REASONS for r in p.reason)
    assert res.grid("outcome").shape == (1, 2)
    assert len(res.table().splitlines()) == 2
    assert res.summary()[0].startswith("outcomes:")
    assert res.disturbance == "throttle step 0.3 -> 0.7"
    res.x = Axis("end", (0.5, 0.9))
    assert res.disturbance == "throttle step 0.3 -> each end"
    never = p.note == "never steady in closed loop at the throttle before the step"
    assert ((p.t_step < p.t_end) | (never & (p.outcome == "no start"))).all()


def test_bad_map_inputs(f60):
    with pytest.raises(BldclabError, match="y"):
        desync_map(f60, Axis("timing", (0.0,)), Axis("timing", (5.0,)))
    with pytest.raises(BldclabError, match="bound"):
        desync_map(f60, Axis("timing", (0.0,)), bound=4.0)
    with pytest.raises(BldclabError, match="workers"):
        desync_map(f60, Axis("timing", (0.0,)), workers=0)
    with pytest.raises(BldclabError, match="control"):
        desync_map(f60, Axis("timing", (0.0,)), control=bl.SixStep())  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------------------------
# the command


@pytest.mark.slow  # matplotlib
def test_cli_writes_the_table_csv_json_and_figures(tmp_path, capsys):
    out = tmp_path / "m"
    argv = ["sensorless", "f60prov-2550kv", "--timing", "0,20 deg", "--rate", "20", "--start", "0.3", "--end", "0.7",
            "--direct-start", "--settle", "20 ms", "--observe", "50 ms", "--workers", "1", "--grid", "0.1",
            "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "desync map" in text and "timing (deg)" in text and "outcomes:" in text
    assert sorted(p.name for p in out.iterdir()) == ["desync.csv", "desync.json", "desync.png", "desync.svg"]
    summary = json.loads((out / "desync.json").read_text())
    assert summary["x"] == {"name": "timing", "unit": "deg", "values": [0.0, 20.0]}
    assert summary["y"] is None
    assert summary["control"]["grid_gain"] == 0.1 and "--grid=0.1" in summary["command"]
    assert pd.read_csv(out / "desync.csv").shape[0] == 2


@pytest.mark.parametrize("args, option", [
    (["--timing", "0,45"], "--timing"), (["--timing", "x"], "--timing"), (["--rate", "fast"], "--rate"),
    (["--rate", "0,1"], "--rate"), (["--start", "1.2"], "--start"), (["--end", "0"], "--end"),
    (["--end", "0.5,0.9", "--timing", "0,10", "--rate", "5,10"], "--end"),
    (["--k-q", "1e-8,2e-8", "--timing", "0,10", "--rate", "5,10"], "--k-q"), (["--bound", "0"], "--bound"),
    (["--bound", "x"], "--bound"), (["--chopping", "slow"], "--chopping"), (["--f-pwm", "-5"], "--f-pwm"),
    (["--settle", "3 V"], "--settle"), (["--observe", "0 s"], "--observe"), (["--inertia", "2 kg"], "--inertia"),
    (["--workers", "0"], "--workers"), (["--fast-demag", "yes"], "--fast-demag"),
    (["--demag-limit", "-0.1"], "--demag-limit"), (["--duty-limit", "-3 A"], "--duty-limit"),
    (["--duty-limit", "3 V"], "--duty-limit"), (["--grid", "1.5"], "--grid"), (["--grid", "nan"], "--grid"),
    (["--grid", "x"], "--grid"), (["--delay", "2"], "--delay"), (["--delay", "0.5"], "--delay"),
])
def test_cli_bad_input_exits_2_names_the_option_and_writes_nothing(tmp_path, capsys, args, option):
    out = tmp_path / "m"
    assert main(["sensorless", "f60prov-2550kv", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and option in err, err
    assert not out.exists()


def test_cli_out_that_is_a_file_fails_before_running(tmp_path, capsys):
    blocker = tmp_path / "f"
    blocker.write_text("x")
    assert main(["sensorless", "f60prov-2550kv", "--out", str(blocker)]) == 2
    assert "--out" in capsys.readouterr().err


def test_a_point_the_simulation_refuses_is_refused_not_no_start(f60):
    # an inertia 10^5 times the motor's: five mechanical time constants of settling are hours, a per-sample trace
    # of them is beyond the trace limit, and the simulation refuses the run before it starts
    big = f60.mechanics.J * 1e5
    res = desync_map(f60, Axis("J", (big,)), step=ThrottleStep(0.3, 0.7), workers=1, summarise=False)
    (row,) = res.points.itertuples()
    assert row.outcome == "refused" and "scenario.trace" in row.note, (row.outcome, row.note)
    assert res.table().splitlines()[1].split()[-1] == "REFUSED"
    assert "refused 1" in res.summary()[0] and not any(line.startswith("plant's truth") for line in res.summary())


def test_cli_a_map_whose_every_point_is_refused_exits_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(["sensorless", "f60prov-2550kv", "--inertia", "10", "--timing", "0,10", "--rate", "inf",
                 "--workers", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "every point of the map was refused" in err and "--settle" in err, err
    assert not out.exists()


@pytest.mark.slow  # the session's compare run, a map and a report
def test_report_of_the_directory_shows_the_desync_section(compare_htm48v, tmp_path):
    """bldclab sensorless written into a compare results directory adds the desync map section to the report; a
    desync.json that is not a summary is refused with the file named."""
    d = tmp_path / "res"
    d.mkdir()
    for p in compare_htm48v.iterdir():
        (d / p.name).write_bytes(p.read_bytes())
    assert main(["sensorless", "f60prov-2550kv", "--timing", "0,20", "--rate", "20", "--direct-start", "--workers",
                 "1", "--out", str(d)]) == 0
    out = tmp_path / "page.html"
    assert main(["report", str(d), "--out", str(out)]) == 0
    page = out.read_text()
    assert 'id="desync"' in page and "the desync map" in page and "timing (deg)" in page
    assert 'href="#desync"' in page
    (d / "desync.json").write_text("[1, 2]")
    assert main(["report", str(d), "--out", str(tmp_path / "bad.html")]) == 2
    assert not (tmp_path / "bad.html").exists()


@pytest.mark.slow  # a closed-loop run on the plant
def test_the_truth_agrees_with_the_sensorless_studies_commutations():
    """Two independent readings of the same trace: bldclab.analysis.sensorless.commutations (the Hall-exact error,
    positive late) and commutation_errors (against the advanced angle, positive early) give err = -error - adv at
    every commutation, to rounding."""
    from bldclab.analysis.sensorless import commutations

    drive = bl.load("f60prov-2550kv")
    adv = 10.0 * DEG
    res = bl.simulate(drive, bl.SixStepSensorless(timing=adv), bl.Scenario(duration=0.2, ref=0.4))
    mine = commutation_errors(res.signals, 1)
    mine = mine[mine.t > 0.15]
    assert len(mine) > 50
    both = pd.merge_asof(mine.sort_values("t"), commutations(res).sort_values("t").rename(columns={"t": "tc"}),
                         left_on="t", right_on="tc", direction="backward", suffixes=("", "_s"))
    assert (both.sector == both.sector_s).all()
    assert np.allclose(both.err, -both.error - adv, atol=1e-6)
    assert (both.certain == both.err.abs()).all()


def test_a_sensorless_trip_is_named_by_its_flag_not_by_the_current_rating_warning():
    """lu-4kw's default throttle step at 10 degrees of timing trips the ESC's own ``i_max`` (2 ``I_N``; the PWM
    ripple's 13 A on the mean current, docs/sensorless.md section 9): the phase current passes 2 ``I_N`` in the
    sample before the trip, which the run names ``OVERCURRENT``; the plausibility warning for a drive without any
    current limit (``result.current_rating``) must not fire for it."""
    drive = bl.load("lu-4kw")
    res = desync_map(drive, Axis("timing", (10.0,)), Axis("rate", (math.inf,)), control=bl.SixStepSensorless(),
                     workers=1, summarise=False)
    assert res.points.reason.iloc[0] == "OVERCURRENT", res.points.iloc[0].to_dict()
    assert not [w for w in res.warnings if "result.current_rating" in w], res.warnings


def test_the_uniform_grid_is_bounded_by_the_measured_demagnetisation():
    """grid_gain: the grid may place a commutation later than 30 degrees after its crossing only as far as the next
    crossing stays visible: the window from the commutation to it must hold the longest demagnetisation of the last
    six sectors as at most ``demag_limit`` of it (docs/sensorless.md, law 7). servo-2k2's default throttle step at 0
    degrees of timing: the grid starts learning during the step's acceleration, its interval (the mean of the last six)
    lags the rotor, and unbounded it commutated up to 12 degrees late, 0.4 degree of margin short of the crossing
    (`ZC_HIDDEN`, recovered by a restart, at every rate); bounded it holds as after each crossing does, its margin and
    worst angle within a degree of that drive's."""
    d = bl.load("servo-2k2")
    ax = Axis("rate", (2.0, math.inf))
    plain = desync_map(d, ax, control=bl.SixStepSensorless(), workers=1).points
    grid = desync_map(d, ax, control=bl.SixStepSensorless(grid_gain=0.1), workers=1).points
    assert (plain.outcome == "sync").all(), plain
    assert (grid.outcome == "sync").all() and (grid.restarts == 0).all(), grid
    assert (grid.margin_deg > 0.0).all() and (grid.margin_deg > plain.margin_deg - 1.0).all(), (grid, plain)
    assert (grid.angle_max_deg < plain.angle_max_deg + 1.0).all(), (grid, plain)

"""Long runs: the C runner called in pieces (state carried over) gives the single-call result; memory stays bounded.

Also the simulation API's conveniences from issue 13: unit and profile strings in ``Scenario``, the default metric
window, decoded controller flags, units of the controllers' diagnostics, the result file's mode.
"""

from __future__ import annotations

import dataclasses
import math
import os
import stat
import tracemalloc

import numpy as np
import pytest

import bldclab as bl
import bldclab.sim as sm
from bldclab.errors import BldclabError

HTM = bl.load("htm-48v")


def _same(a: bl.SimResult, b: bl.SimResult) -> None:
    assert a.metrics == b.metrics  # every field bitwise (nan == nan is False, so none may be nan here)
    assert a.meta["final"] == b.meta["final"] and a.meta["stats"] == b.meta["stats"]
    assert a.signals.keys() == b.signals.keys()
    for k in a.signals:
        assert np.array_equal(a[k], b[k]), k


@pytest.mark.filterwarnings("ignore:scenario.window")  # the load step is in the window on purpose
@pytest.mark.parametrize("kw", [
    {"speed": 40.0, "ref": 30.0, "trace_sub": 3, "window": (0.05, 0.2)},
    {"ref": 30.0, "load_torque": lambda t: np.where(t < 0.1, 0.0, 5.0), "trace_every": 7, "window": (0.1, 0.2)},
    {"speed": lambda t: 20.0 + 100.0 * t, "ref": 30.0, "trace": False, "window": (0.05, 0.2)},
])
def test_chunked_run_equals_single_call(kw, monkeypatch):
    """0.2 s (5600 samples): one call into C vs pieces of 333 samples; identical metrics, trace and final state."""
    sc = bl.Scenario(duration=0.2, **kw)
    whole = bl.simulate(HTM, bl.SixStep(), sc)
    monkeypatch.setattr(sm, "CHUNK", 333)
    seen: list[tuple[int, int]] = []
    pieces = bl.simulate(HTM, bl.SixStep(), sc, progress=lambda done, total: seen.append((done, total)))
    _same(whole, pieces)
    n = sm.samples_of(HTM, 0.2)
    assert len(seen) == math.ceil(n / 333) and seen[-1] == (n, n)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)


def _peak(duration: float) -> int:
    sc = bl.Scenario(duration=duration, speed=lambda t: 30.0 + 10.0 * t, ref=20.0, trace=False)
    tracemalloc.start()
    bl.simulate(HTM, bl.SixStep(), sc, check="off")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def test_memory_does_not_grow_with_duration(monkeypatch):
    """Without a trace, a run 8x longer peaks at the same memory (pieces of 2000 samples; before: 8 bytes per
    sample for each input and the sample times, 0.45 MB more for the long run)."""
    monkeypatch.setattr(sm, "CHUNK", 2000)
    short, long = _peak(0.05), _peak(0.4)  # 1400 and 11200 samples
    assert long < short + 50_000, (short, long)


def test_trace_bytes_is_what_the_run_keeps():
    sc = bl.Scenario(duration=0.02, speed=40.0, ref=10.0, trace_every=3)
    res = bl.simulate(HTM, bl.SixStep(), sc)
    assert sm.trace_rows(HTM, sc) == len(res) == sm.samples_of(HTM, 0.02) // 3
    assert sm.trace_bytes(HTM, sc) == len(res) * bl._core.core().trace_dtype.itemsize
    assert sm.trace_bytes(HTM, bl.Scenario(duration=1000.0, trace=False)) == 0


def test_unit_and_profile_strings_in_scenario():
    sc = bl.Scenario(duration="20 ms", speed="300 rpm", load_torque="2 N m", v_dc="40 V", window=("5 ms", "20 ms"))
    assert sc.duration == pytest.approx(0.02) and sc.speed == pytest.approx(10 * math.pi)
    assert sc.load_torque == 2.0 and sc.v_dc == 40.0 and sc.window == pytest.approx((0.005, 0.02))
    ramp = bl.Scenario(duration=0.1, speed="0 s: 0 rpm, 0.1 s: 600 rpm, 0.1 s: 300 rpm").speed
    assert isinstance(ramp, sm.Piecewise)
    assert ramp(np.array([0.05, 0.2])) == pytest.approx([10 * math.pi, 10 * math.pi])
    with pytest.raises(BldclabError, match=r"scenario\.speed"):
        bl.Scenario(duration=0.1, speed="300 N m")
    with pytest.raises(BldclabError, match="point 2"):
        bl.Scenario(duration=0.1, load_torque="0 s: 1 N m, 0.2 s 3 N m")
    with pytest.raises(BldclabError, match="must not decrease"):
        bl.Scenario(duration=0.1, load_torque="0.2 s: 1, 0.1 s: 3")


def test_default_window_is_the_whole_run_and_flags_are_decoded():
    res = bl.simulate(HTM, bl.SixStep(), bl.Scenario(duration=0.01, speed="300 rpm", ref=HTM.motor.I_N))
    assert res.metrics is not None and res.metrics.t0 == 0.0 and res.metrics.t1 == pytest.approx(0.01)
    assert res.metrics.omega_mean == pytest.approx(10 * math.pi)
    bits = int(np.bitwise_or.reduce(res["ctrl_flags"].astype(np.int64)))
    assert bits and res.meta["controller_flags"] == bits  # every sample has a row here: the OR in C equals the trace's
    assert res.flags_raised == bl.decode_flags(bits) and "SATURATED" in res.flags_raised.split("|")
    assert np.array_equal(res.flags, res["ctrl_flags"])  # the old name still reads
    df = res.to_pandas()
    assert "ctrl_flags" in df.columns and "flags" not in df.columns


def test_diagnostic_units():
    res = bl.simulate(HTM, bl.Sine(), bl.Scenario(duration=0.005, speed=40.0, ref=10.0))
    assert {k: res.units[k] for k in ("i_d", "i_q", "v_d", "v_q", "theta", "omega_e")} == {
        "i_d": "A", "i_q": "A", "v_d": "V", "v_q": "V", "theta": "rad", "omega_e": "rad/s"}
    assert res.units["ctrl_flags"] == "-"


def test_result_file_follows_the_umask(tmp_path):
    res = bl.simulate(HTM, bl.SixStep(), bl.Scenario(duration=0.002, speed=40.0, ref=10.0))
    old = os.umask(0o022)
    try:
        p = res.save(tmp_path / "r.npz")
    finally:
        os.umask(old)
    assert stat.S_IMODE(p.stat().st_mode) == 0o644
    back = bl.SimResult.load(p)
    assert np.array_equal(back["ctrl_flags"], res["ctrl_flags"]) and back.flags_raised == res.flags_raised


@pytest.mark.filterwarnings("ignore:scenario.window")  # a run-up in the window on purpose
def test_mean_speed_needs_no_trace():
    """The window's mean speed comes from the angle travelled in C: identical with a thinned trace and none (rows
    on sample bounds add no integration points), within the integration error with 4 rows per sample (the sub-rows
    are extra landing points), and it agrees with the mean of the traced speed to the trace's sampling error.
    The window's integrals agree to rounding: without a trace the power flows are not integrated before the window
    (the plant pays only for what is read), so they start from another base value."""
    base = {"duration": 0.1, "ref": 30.0, "load_torque": 2.0, "window": (0.02, 0.1)}
    full = bl.simulate(HTM, bl.SixStep(), bl.Scenario(**base, trace_sub=4))
    none = bl.simulate(HTM, bl.SixStep(), bl.Scenario(**base, trace=False))
    thin = bl.simulate(HTM, bl.SixStep(), bl.Scenario(**base, trace_every=50))
    assert none.metrics.omega_mean == thin.metrics.omega_mean
    assert none.meta["final"] == thin.meta["final"]  # the same path, bit for bit
    a, b = dataclasses.asdict(none.metrics), dataclasses.asdict(thin.metrics)
    for key, va in a.items():
        if isinstance(va, str):
            assert va == b[key], key
            continue
        ref = np.asarray(b[key], dtype=float)
        assert np.allclose(np.asarray(va, dtype=float), ref, rtol=1e-12, atol=1e-12 * (1 + np.max(np.abs(ref)))), key
    m = full.metrics
    assert m.omega_mean == pytest.approx(none.metrics.omega_mean, rel=2e-5)  # 5768 vs 14168 RK4 steps: 7e-6
    sel = (full.t >= m.t0) & (full.t < m.t1)
    w = full.omega_m[sel]
    assert m.omega_mean == pytest.approx(np.mean(w), rel=1e-3)
    assert w.min() < m.omega_mean < w.max()  # a run-up: the mean is a real average, not the final speed


def test_the_api_refuses_a_trace_it_cannot_hold_before_running():
    """1000 s of htm-48v with a full trace would take tens of GB: refused at once, naming the cause and the way out."""
    d = bl.load("htm-48v")
    sc = bl.Scenario(duration=1000.0, speed=0.5 * d.Omega_0, ref=d.motor.I_N)
    with pytest.raises(BldclabError) as e:
        bl.simulate(d, bl.SixStep(), sc)
    assert e.value.field == "scenario.trace" and "trace_every" in e.value.problem and "GB" in e.value.problem
    short = bl.Scenario(duration=0.01, speed=0.5 * d.Omega_0, ref=d.motor.I_N)
    with pytest.raises(BldclabError):
        bl.simulate(d, bl.SixStep(), short, max_trace_bytes=1000)
    assert bl.simulate(d, bl.SixStep(), short, max_trace_bytes=None).metrics is not None


def test_flag_statistics_tell_start_up_from_the_window():
    """Per flag, the runner counts the samples that raised it and the first and last of them, over the run and inside
    the metric window: the sinusoidal supply at 0.95 Omega_0 saturates only while its currents build up (nothing in
    a window after that), the square wave at 0.3 Omega_0 at every commutation (the incoming phase at full voltage)."""
    d = bl.load("htm-48v")
    sine = bl.simulate(d, bl.Sine(), bl.Scenario(duration=0.05, speed=0.95 * d.Omega_0, ref=30.0, trace=False,
                                                 window=(0.02, 0.05)))
    sat = sine.meta["flags"]["SATURATED"]
    assert "window" not in sat and sat["run"]["samples"] > 0 and sat["run"]["last"] < 0.02
    assert sat["run"]["share"] == pytest.approx(sat["run"]["samples"] / sine.meta["samples"])
    sq = bl.simulate(d, bl.SixStep(), bl.Scenario(duration=0.05, speed=0.3 * d.Omega_0, ref=30.0, trace=False,
                                                  window=(0.02, 0.05)))
    run, win = sq.meta["flags"]["SATURATED"]["run"], sq.meta["flags"]["SATURATED"]["window"]
    assert 0 < win["samples"] <= run["samples"] and 0.0 < win["share"] < 0.1
    assert 0.02 <= win["first"] <= win["last"] < 0.05 and run["first"] <= win["first"]
    # the same counts from a trace: one row per sample
    tr = bl.simulate(d, bl.SixStep(), bl.Scenario(duration=0.05, speed=0.3 * d.Omega_0, ref=30.0,
                                                  window=(0.02, 0.05)))
    sat_rows = (tr["ctrl_flags"].astype(int) & bl.flag("SATURATED")) != 0
    in_win = (tr.t >= 0.02) & (tr.t < 0.05)
    assert int(np.sum(sat_rows)) == run["samples"] and int(np.sum(sat_rows & in_win)) == win["samples"]

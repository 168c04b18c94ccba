"""Efficiency maps (bldclab.analysis.effmap, bldclab effmap): energy accounting, envelope, physics, CLI."""

from __future__ import annotations

import dataclasses
import re
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import bldclab as bl
from bldclab.analysis import effmap as effmap_module
from bldclab.analysis.effmap import FEASIBLE_TOL_PU, LOSS_BUCKETS, NOT_LOSSES, efficiency_map, loss_buckets
from bldclab.analysis.experiments import map_points
from bldclab.cli import main
from bldclab.model import analytic
from bldclab.sim.plausibility import BALANCE_WARN
from bldclab.sim.results import Metrics
from bldclab.sweep.effmap_store import EffMapStore
from bldclab.sweep.store import Store
from conftest import require_module


@pytest.fixture(scope="module")
def drive():
    return bl.load("htm-48v")


@pytest.fixture(scope="module")
def small(drive):
    """A 3 x 3 map of both supplies, serial."""
    T = np.array([0.2, 0.6, 1.0]) * drive.T_N
    W = np.array([0.1, 0.5, 0.95]) * drive.Omega_0
    return efficiency_map(drive, T, W, workers=1)


def test_every_power_of_the_plant_is_a_loss_bucket_or_named_as_not_one():
    """A power the plant adds to Metrics must be classified, so that no loss is silently left out of the maps."""
    powers = {f.name for f in dataclasses.fields(Metrics) if f.name.startswith("p_")}
    assert powers - set(NOT_LOSSES) - set(LOSS_BUCKETS) == set()
    assert set(loss_buckets()) == powers - set(NOT_LOSSES)


def test_each_point_accounts_for_its_input_power(small):
    """p_in = p_shaft + sum of the buckets + stored-energy change, to the integration's energy balance."""
    p = small.points
    assert len(p) == 18 and set(small.buckets) <= set(p.columns)
    losses = p[list(small.buckets)].sum(axis=1)
    assert np.allclose(losses, p.p_loss)
    scale = np.maximum(p.p_in.abs(), p.p_shaft.abs())
    assert np.all(np.abs(p.p_in - p.p_shaft - losses - p.p_stored) <= BALANCE_WARN * scale)
    assert np.all(p[list(small.buckets)] >= 0.0)


def test_feasible_motoring_efficiency_is_between_zero_and_one(small, drive):
    ok = small.points[small.points.feasible]
    assert len(ok) >= 10
    assert np.all((ok.efficiency > 0.0) & (ok.efficiency < 1.0))
    assert np.all(np.abs(ok.tau_mean - ok.torque_ref) <= FEASIBLE_TOL_PU * drive.T_N)


def test_points_above_the_envelope_are_flagged_not_dropped(drive):
    """At 0.95 Omega_0 a torque 30 % above the closed-form limit (R = 0, an upper bound) is infeasible."""
    w = 0.95
    ch = analytic.characteristic(drive, np.array([w])).iloc[0]
    res = efficiency_map(drive, [1.3 * ch.T_q, 0.3 * ch.T_q], [w * drive.Omega_0], supplies=("square",), workers=1)
    p = res.points.set_index("torque_ref")
    assert not p.loc[1.3 * ch.T_q, "feasible"] and p.loc[0.3 * ch.T_q, "feasible"]
    assert p.loc[1.3 * ch.T_q, "tau_mean"] < 1.3 * ch.T_q - FEASIBLE_TOL_PU * drive.T_N
    # the note says what the infeasible point delivered (a user sees why it is blank); a feasible one has none
    tau = p.loc[1.3 * ch.T_q, "tau_mean"]
    assert p.loc[1.3 * ch.T_q, "note"].startswith(
        f"delivers {100 * tau / (1.3 * ch.T_q):.3g} % of the torque asked for")
    assert p.loc[0.3 * ch.T_q, "note"] == ""
    assert res.difference.empty  # one supply: nothing to compare
    assert np.isnan(res.grid("square", "efficiency")[0, 0])


def test_difference_map_is_on_the_common_feasible_points(small):
    d = small.difference
    p = small.points
    both = p[p.feasible].groupby(["torque_ref", "speed"]).supply.nunique()
    assert len(d) == int((both == 2).sum())
    sq = p[p.supply == "square"].set_index(["torque_ref", "speed"]).efficiency
    si = p[p.supply == "sine"].set_index(["torque_ref", "speed"]).efficiency
    for r in d.itertuples():
        assert r.d_eta == pytest.approx(si[(r.torque_ref, r.speed)] - sq[(r.torque_ref, r.speed)])
        assert r.winner == ("sine" if r.d_eta > small.resolution else "square" if r.d_eta < -small.resolution
                            else "equal")
    assert any(line.startswith("sinusoidal: best efficiency") for line in small.summary())


def test_results_do_not_depend_on_the_workers(small, drive):
    par = efficiency_map(drive, small.torques, small.speeds, workers=2)
    pd.testing.assert_frame_equal(small.points, par.points)
    pd.testing.assert_frame_equal(small.difference, par.difference)


def test_a_pool_the_caller_keeps_gives_the_same_map_and_stores_every_point(small, drive, tmp_path):
    """The CLI's way: one pool for the points and then the figures; with a store, each point saved as it arrives."""
    with ProcessPoolExecutor(max_workers=2) as pool, Store(tmp_path / "s.sqlite") as st:
        cache = EffMapStore(st)
        res = efficiency_map(drive, small.torques, small.speeds, workers=2, executor=pool, cache=cache)
        assert cache.saved == len(small.points) == len(st)
    pd.testing.assert_frame_equal(small.points, res.points)


def test_map_points_hands_over_each_result_in_order():
    seen: list[tuple[int, int]] = []
    assert map_points(abs, [-3, 1, -2], each=lambda k, r: seen.append((k, r))) == [3, 1, 2]
    assert seen == [(0, 3), (1, 1), (2, 2)]


@pytest.mark.slow
def test_a_dask_cluster_gives_the_same_results(small, drive):
    """The points run on a Dask cluster through its concurrent.futures executor: the same table."""
    require_module("distributed")
    import distributed  # optional dependency, imported only when present

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        res = efficiency_map(drive, small.torques, small.speeds, executor=client.get_executor())
    pd.testing.assert_frame_equal(small.points, res.points)


def test_lossless_drive_has_unit_efficiency(drive):
    """R = 0, no friction, ideal inverter: every watt drawn reaches the shaft."""
    assert drive.inverter.R_on == 0 and drive.inverter.V_f == 0 and drive.inverter.R_src == 0
    ideal = drive.replace(motor__R=0.0, mechanics__B=0.0, mechanics__tau_c=0.0)
    res = efficiency_map(ideal, [0.5 * drive.T_N], [0.5 * drive.Omega_0], workers=1)
    for r in res.points.itertuples():
        assert r.feasible
        assert r.efficiency == pytest.approx(1.0, abs=BALANCE_WARN), r.supply
        assert r.p_loss == pytest.approx(0.0, abs=1e-9 * r.p_in)


def test_copper_loss_is_the_sum_of_the_phase_rms_currents_squared_times_r(small, drive):
    """Sinusoidal supply at 0.6 T_N, 0.5 Omega_0: p_cu = R (I_a^2 + I_b^2 + I_c^2) = 3/2 R I^2 for currents of
    amplitude I = T / (1.5 k_1) (paper 1 (45))."""
    p = small.points
    r = p[(p.supply == "sine") & np.isclose(p.torque_ref, 0.6 * drive.T_N)
          & np.isclose(p.speed, 0.5 * drive.Omega_0)].iloc[0]
    R = drive.motor.R
    assert r.p_cu == pytest.approx(R * (r.i_rms_a**2 + r.i_rms_b**2 + r.i_rms_c**2), rel=1e-6)
    amp = 0.6 * drive.T_N / (1.5 * bl.control.sine.fundamental_k1(drive))
    assert r.p_cu == pytest.approx(1.5 * R * amp**2, rel=0.02)  # the PWM ripple adds a little


def test_cli_writes_the_map_and_refuses_a_bad_out(tmp_path, capsys):
    out = tmp_path / "map"
    assert main(["effmap", "htm-48v", "--torques", "2", "--speeds", "2", "--workers", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "best efficiency" in text and "equal within 0.005" in text
    names = {p.name for p in out.iterdir()}
    assert {"effmap.csv", "effmap_difference.csv"} <= names
    for stem in ("effmap_efficiency", "effmap_difference", "effmap_losses"):
        assert {f"{stem}.png", f"{stem}.svg"} <= names
    df = pd.read_csv(out / "effmap.csv")
    assert len(df) == 8 and {"feasible", "efficiency", *loss_buckets()} <= set(df.columns)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["effmap", "htm-48v", "--out", str(blocker)]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["effmap", "htm-48v", "--torques", "1", "--out", str(tmp_path / "x")]) == 2
    assert not (tmp_path / "x").exists()


def test_braking_points_return_power_to_the_source(drive):
    """A negative torque reference generates: both powers negative, efficiency electrical out / mechanical in."""
    res = efficiency_map(drive, [-0.5 * drive.T_N], [0.5 * drive.Omega_0], workers=1)
    for r in res.points.itertuples():
        assert r.feasible and r.p_in < 0.0 and r.p_shaft < 0.0, r.supply
        assert 0.0 < r.efficiency < 1.0
        assert r.efficiency == pytest.approx((r.p_in - r.p_stored) / r.p_shaft)
        assert abs(r.p_in - r.p_shaft - r.p_loss - r.p_stored) <= BALANCE_WARN * abs(r.p_shaft)


@pytest.mark.slow
def test_report_of_the_directory_shows_the_map_summary(compare_htm48v: Path, tmp_path: Path) -> None:
    """bldclab effmap written into a compare results directory adds the 'Efficiency maps' section to the report."""
    d = tmp_path / "res"
    d.mkdir()
    for p in compare_htm48v.iterdir():
        (d / p.name).write_bytes(p.read_bytes())
    assert main(["effmap", "htm-48v", "--torques", "2", "--speeds", "2", "--workers", "1", "--out", str(d)]) == 0
    out = tmp_path / "page.html"
    assert main(["report", str(d), "--out", str(out)]) == 0
    text = out.read_text(encoding="utf-8")
    section = re.search(r'<section id="effmap">(.*?)</section>', text, re.S)
    assert section is not None and "best efficiency" in section.group(1) and "<svg" in section.group(1)
    assert '<a href="#effmap">' in text and not re.search(r"https?://", text)


def test_switching_losses_enter_the_map_and_the_accounting_still_closes(drive):
    """With datasheet-like switching and recovery energies on the inverter, the map's input is the source power with
    those energies, the two buckets are positive, and input = shaft + losses + stored still holds."""
    lossy = drive.replace(inverter__E_on=40e-6, inverter__E_off=60e-6, inverter__E_rr=10e-6, inverter__V_test=48.0,
                          inverter__I_test=50.0)
    res = efficiency_map(lossy, [0.5 * drive.T_N], [0.5 * drive.Omega_0], workers=1)
    base = efficiency_map(drive, [0.5 * drive.T_N], [0.5 * drive.Omega_0], workers=1)
    for (_, r), (_, r0) in zip(res.points.iterrows(), base.points.iterrows(), strict=True):
        assert r.p_swloss > 0 and r.p_rr > 0, r.supply
        losses = sum(r[b] for b in res.buckets)
        assert abs(r.p_in - r.p_shaft - losses - r.p_stored) <= BALANCE_WARN * abs(r.p_in)
        assert r.efficiency < r0.efficiency  # the same point, more loss


def _no_simulation(job):
    raise AssertionError(f"simulated a point the store holds: {job[1:5]}")


def test_a_second_identical_map_reuses_the_stored_points(drive, tmp_path, monkeypatch):
    """Points are stored in a sweep store under their inputs' key; a second identical map simulates nothing and gives
    the same tables; another drive or grid point misses the store."""
    T, W = np.array([0.3, 0.8]) * drive.T_N, np.array([0.4, 0.9]) * drive.Omega_0
    with Store(tmp_path / "s.sqlite") as st:
        first = EffMapStore(st)
        a = efficiency_map(drive, T, W, workers=1, cache=first)
        assert a.cached == 0 and first.saved == 8 and len(st) == 8
        with monkeypatch.context() as m:
            m.setattr(effmap_module, "_run_point", _no_simulation)
            b = efficiency_map(drive, T, W, workers=1, cache=EffMapStore(st))
        assert b.cached == 8
        assert b.points.to_csv(index=False) == a.points.to_csv(index=False)
        assert b.difference.to_csv(index=False) == a.difference.to_csv(index=False)
        # a changed drive, and a new speed, are simulated; the old points are still found
        c = efficiency_map(drive.replace(motor__R=0.06), T, W, workers=1, cache=EffMapStore(st))
        assert c.cached == 0
        d = efficiency_map(drive, T, [*W, 0.6 * drive.Omega_0], workers=1, cache=EffMapStore(st))
        assert d.cached == 8 and len(d.points) == 12
        assert "effmap_point" in set(st.to_pandas()["experiment"])


@pytest.mark.slow
def test_cli_second_run_uses_its_store(tmp_path, capsys, monkeypatch):
    out = tmp_path / "map"
    argv = ["effmap", "htm-48v", "--torques", "2", "--speeds", "2", "--workers", "1", "--out", str(out)]
    assert main(argv) == 0
    assert "0 of 8 points found there, 8 simulated" in capsys.readouterr().out
    assert (out / "effmap.sqlite").is_file()
    before = {n: (out / n).read_bytes() for n in ("effmap.csv", "effmap_difference.csv")}
    monkeypatch.setattr(effmap_module, "_run_point", _no_simulation)
    assert main(argv) == 0
    assert "8 of 8 points found there, 0 simulated" in capsys.readouterr().out
    assert {n: (out / n).read_bytes() for n in before} == before
    # --no-store simulates (and here fails: nothing was simulated in the second run above)
    with pytest.raises(AssertionError, match="simulated a point"):
        main([*argv, "--no-store"])
    assert main([*argv, "--store", str(tmp_path / "none" / "s.sqlite")]) == 2
    assert "--store" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_on_two_workers_writes_the_serial_files(tmp_path, capsys):
    """The points and then the figures on one pool of two workers: the same tables, every figure."""
    argv = ["effmap", "htm-48v", "--torques", "2", "--speeds", "2", "--no-store"]
    assert main([*argv, "--workers", "1", "--out", str(tmp_path / "one")]) == 0
    assert main([*argv, "--workers", "2", "--out", str(tmp_path / "two")]) == 0
    for name in ("effmap.csv", "effmap_difference.csv"):
        assert (tmp_path / "one" / name).read_bytes() == (tmp_path / "two" / name).read_bytes()
    for stem in ("effmap_efficiency", "effmap_difference", "effmap_losses"):
        assert (tmp_path / "two" / f"{stem}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert b"<svg" in (tmp_path / "two" / f"{stem}.svg").read_bytes()[:2000]


@pytest.mark.slow
def test_cli_chopping_changes_only_the_square_wave_and_its_stored_points(tmp_path, capsys):
    """``--chopping sync`` maps the square wave with a complementary positive leg: on the drive with real diodes its
    diode loss falls (no freewheeling through a diode in the off-time), the sinusoidal points are the same bytes and
    come from the store; the square-wave points are new ones (the chopping is part of the stored point's key)."""
    out = tmp_path / "map"
    argv = ["effmap", "htm-48v-losses", "--torques", "2", "--speeds", "2", "--workers", "1", "--out", str(out),
            "--min-speed", "0.2", "--max-speed", "0.5"]
    assert main(argv) == 0
    default = pd.read_csv(out / "effmap.csv")
    capsys.readouterr()
    assert main([*argv, "--chopping", "sync"]) == 0
    text = capsys.readouterr().out
    assert "4 of 8 points found there, 4 simulated" in text and "sync chopping" in text
    sync = pd.read_csv(out / "effmap.csv")
    sq0, sq1 = default[default.supply == "square"], sync[sync.supply == "square"]
    assert sq1.p_diode.sum() < 0.2 * sq0.p_diode.sum()
    assert (sq1.efficiency.to_numpy() > sq0.efficiency.to_numpy()).all()
    pd.testing.assert_frame_equal(default[default.supply == "sine"], sync[sync.supply == "sine"])

"""Paper 1's efficiency comparison extended (issue 14): copper-only closed forms with 3 P_R and 2 R I_N^2, the
simulated copper-only and full-loss efficiencies, side by side in ``compare``'s table, verdict and report."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import bldclab as bl
from bldclab.analysis import compare as cmp
from bldclab.analysis.losses import loss_buckets
from bldclab.model import analytic as an
from bldclab.report.html import Results

SPEEDS = [0.3, 0.7]


def _eff(drive: bl.Drive) -> pd.DataFrame:
    res = cmp.compare(drive, SPEEDS, workers=1, base_speeds=False)
    assert res.efficiency is not None
    return res.efficiency.set_index(["supply", "Omega_pu"])


def test_zero_losses_full_efficiency_is_the_copper_only_one():
    """With every loss field zero (no friction, ideal switches and diodes, no switching energy) the full-loss
    efficiency (from the DC input) equals the copper-only one (from the EMF power and the copper loss) to the
    integration's energy balance: two different computations of the same thing."""
    drive = bl.load("htm-48v").replace(mechanics__B=0.0, mechanics__tau_c=0.0)
    assert drive.inverter.R_on == drive.inverter.V_f == drive.inverter.R_src == 0.0
    eff = _eff(drive)
    others = [b for b in loss_buckets() if b != "p_cu"]
    assert np.all(eff[others].to_numpy() == 0.0)
    assert np.all(eff["p_cu"] > 10.0)  # the copper loss is there and large
    np.testing.assert_allclose(eff["eta_sim_full"], eff["eta_sim_copper"], rtol=0, atol=1e-6)
    # the efficiency is not trivially 1: the copper loss costs several per cent
    assert np.all(eff["eta_sim_full"] < 0.95)


def test_losses_lower_the_full_efficiency_and_close_the_balance():
    drive = bl.load("htm-48v").replace(inverter__R_on=0.005, inverter__V_f=0.8, inverter__r_d=0.005,
                                       inverter__t_dead=5e-7,
                                       inverter__E_on=30e-6, inverter__E_off=20e-6, inverter__E_rr=5e-6,
                                       inverter__V_test=48.0, inverter__I_test=50.0)
    eff = _eff(drive)
    for b in ("p_sw", "p_diode", "p_swloss", "p_rr", "p_fric"):
        assert np.all(eff[b] > 0.0), b
    assert np.all(eff["eta_sim_full"] < eff["eta_sim_copper"] - 0.005)
    # the full-loss efficiency is shaft power over input (the stored energy aside), the buckets close the balance
    p_net = eff["p_in"] - eff["p_stored"]
    np.testing.assert_allclose(eff["eta_sim_full"], eff["p_shaft"] / p_net, rtol=1e-12)
    assert np.all(np.abs(eff["residue"]) < 1e-5 * eff["p_in"])
    np.testing.assert_allclose(eff["p_loss"], eff[list(loss_buckets())].sum(axis=1), rtol=1e-12)


def test_closed_form_columns_are_paper_1s_formulas_with_both_loss_counts():
    drive = bl.load("htm-48v")
    res = cmp.compare(drive, SPEEDS, workers=1, base_speeds=False)
    eff = res.efficiency.set_index(["supply", "Omega_pu"])
    th = an.theta_m(drive)
    p3, p2 = an.p_lCu_pu(drive), an.p_lCu_consistent_pu(drive)
    assert p3 == pytest.approx(3 * an.p_R_pu(drive))
    for w in SPEEDS:
        assert eff.loc[("square", w), "eta_paper_3PR"] == pytest.approx(an.eta_q(w, th, p3), rel=1e-12)
        assert eff.loc[("sine", w), "eta_paper_3PR"] == pytest.approx(an.eta_s(w, th, p3), rel=1e-12)
        assert eff.loc[("square", w), "eta_consistent_2PR"] == pytest.approx(an.eta_q(w, th, p2), rel=1e-12)
        assert eff.loc[("sine", w), "eta_consistent_2PR"] == pytest.approx(an.eta_s(w, th, p2), rel=1e-12)
        # the analytic table's eta_s/eta_q are the paper's count
        a = res.analytic.set_index("Omega_pu").loc[w]
        assert eff.loc[("sine", w), "eta_paper_3PR"] == pytest.approx(a.eta_s, rel=1e-12)
    # the consistent count is smaller (0.104 against 0.175 p.u. for htm-48v), so its efficiency higher; the simulated
    # copper-only efficiency (the consistent count with the real currents) is close to it below the base speed
    assert np.all(eff["eta_consistent_2PR"] > eff["eta_paper_3PR"])
    for s in ("sine", "square"):
        assert eff.loc[(s, 0.3), "eta_sim_copper"] == pytest.approx(eff.loc[(s, 0.3), "eta_consistent_2PR"], abs=0.01)


def _frame(full: list[float], copper: list[float]) -> pd.DataFrame:
    w = [0.2, 0.4, 0.6, 0.8]
    rows = []
    for i, x in enumerate(w):
        rows.append({"supply": "square", "Omega_pu": x, "eta_paper_3PR": 0.80, "eta_consistent_2PR": 0.85,
                     "eta_sim_copper": 0.85, "eta_sim_full": 0.80})
        rows.append({"supply": "sine", "Omega_pu": x, "eta_paper_3PR": 0.82 if x < 0.7 else np.nan,
                     "eta_consistent_2PR": 0.87 if x < 0.7 else np.nan,
                     "eta_sim_copper": 0.85 + copper[i], "eta_sim_full": 0.80 + full[i]})
    return pd.DataFrame(rows)


def test_verdict_says_where_the_full_loss_winner_differs():
    lines = cmp._efficiency_verdict(_frame(full=[0.01, 0.0, -0.01, 0.01], copper=[0.01, 0.01, 0.01, 0.01]))
    changes = [v for v in lines if "verdict changes" in v]
    text = "\n".join(changes)
    assert ("against the simulated copper-only efficiency: the verdict changes for Omega = 0.40 p.u.: sinusoidal "
            "better with copper loss only, equal with every loss") in text
    assert "Omega = 0.60 p.u.: sinusoidal better with copper loss only, square-wave better with every loss" in text
    assert not any("Omega = 0.20" in v or "Omega = 0.80" in v for v in changes if "copper-only" in v)
    # the closed forms stop at the base speed: n/a is said, and not counted as a change
    assert any("not defined for Omega = 0.80 p.u." in v for v in lines)
    paper = [v for v in changes if "3 P_R" in v]
    assert paper and not any("0.80" in v for v in paper)
    # nothing changes: said so
    same = cmp._efficiency_verdict(_frame(full=[0.01] * 4, copper=[0.01] * 4))
    assert any("simulated copper-only efficiency: the same winner at every speed compared" in v for v in same)


def test_compare_writes_the_efficiency_table_and_the_report_shows_it(compare_htm48v):
    eff = pd.read_csv(compare_htm48v / "efficiency.csv")
    assert list(eff.columns[:6]) == ["supply", "Omega_pu", *cmp.EFFICIENCY_COUNTS]
    assert set(loss_buckets()) <= set(eff.columns)
    assert len(eff) == 12
    verdict = (compare_htm48v / "verdict.txt").read_text()
    assert "efficiency by loss count, paper 1 (38)/(39)" in verdict
    assert "efficiency, full losses against the simulated copper-only efficiency" in verdict
    html = (compare_htm48v / "report.html").read_text(encoding="utf-8")
    assert "Efficiency by loss count" in html and "efficiency.csv" in html
    files = {p.name: p.read_bytes() for p in compare_htm48v.iterdir()}
    r = Results.from_files(files, source="test")
    assert r.efficiency is not None and len(r.efficiency) == 12
    # an older results directory without the file still reads
    del files["efficiency.csv"]
    assert Results.from_files(files, source="test").efficiency is None

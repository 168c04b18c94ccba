"""The cost gate: the C core's instructions per scenario (callgrind) against benchmarks/cost_budget.toml.

The slow tests run every scenario of ``benchmarks/cost.py`` under valgrind (about a minute on 2 cores) and fail a
scenario more than 3 % over its budget; one of them proves the gate can fail (a run doing 5 % more work, checked
against the unchanged budget, is rejected). The fast tests check the callgrind parser on a hand-written profile
with the traps of the format, and the budget file's bookkeeping.
"""

from __future__ import annotations

import importlib.util
import sys
import warnings
from pathlib import Path

import pytest

from conftest import _missing, require_tool

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("cost_bench", ROOT / "benchmarks" / "cost.py")
cost = importlib.util.module_from_spec(_spec)
sys.modules["cost_bench"] = cost
_spec.loader.exec_module(cost)

#: the run that must be rejected: a gated scenario with a 5 % longer duration. Sine: its calls out are per sample
#: (the SVM's fminf/fmaxf, sincosf), so they grow with the run; six-step's loop makes none (only a fixed few remain)
HEAVIER = ("sine", 1.05)


# ---------------------------------------------------------------------------------------------------------------
# the gate


@pytest.fixture(scope="module")
def cost_runs(tmp_path_factory):
    """Every scenario and the 5 % heavier run, measured once (valgrind processes in parallel)."""
    require_tool("valgrind")
    require_tool("cc")
    out = tmp_path_factory.mktemp("cost")
    try:
        build = cost.prepare(ROOT, out)
    except RuntimeError as exc:
        if "callgrind.h" not in str(exc):
            raise
        _missing(f"valgrind's callgrind.h is missing (the valgrind package installs it): {exc}")
    runs = [(name, 1.0) for name in cost.SCENARIOS] + [HEAVIER]
    ms = cost.measure(build, runs, tmp=out)
    return {(m.scenario, m.scale): m for m in ms}


@pytest.mark.slow
def test_every_scenario_within_3_percent_of_its_budget(cost_runs):
    budgets = cost.read_budgets()
    rows = cost.check([m for (_, scale), m in cost_runs.items() if scale == 1.0], budgets)
    print("\n" + cost.table(rows))
    for r in rows:
        if r.stale:
            warnings.warn(f"budget stale, lower it: {r.message()}", stacklevel=1)
    bad = [r.message() for r in rows if not r.ok]
    assert not bad, ("over budget (python benchmarks/cost.py shows the table; a deliberate change is a commit with "
                     "--update --why ...):\n  " + "\n  ".join(bad) + "\n" + cost.toolchain_note(budgets))


@pytest.mark.slow
def test_a_run_doing_5_percent_more_work_is_rejected(cost_runs):
    name, scale = HEAVIER
    base, heavy = cost_runs[name, 1.0], cost_runs[HEAVIER]
    assert heavy.info["samples"] == pytest.approx(scale * base.info["samples"], abs=1)
    rows = {r.quantity: r for r in cost.check([heavy], cost.read_budgets())}
    for quantity in ("instructions", "calls out"):
        r = rows[quantity]
        assert r.ratio > 1.04, r.message()  # about 5 % more work was measured ...
        assert not r.ok, r.message()  # ... and the gate refuses it
    # the same check passes the scenario at its own duration (it is the budget, not the check, that failed above)
    assert all(r.ok for r in cost.check([base], cost.read_budgets()) if r.quantity in rows)


@pytest.mark.slow
def test_the_measured_library_is_the_fresh_build_of_this_tree(cost_runs):
    for m in cost_runs.values():
        assert "/lib/bldclab/" in m.info["bldclab"], m.info
        assert m.instructions > 1e6 and m.seconds > 0


# ---------------------------------------------------------------------------------------------------------------
# the budget file


def test_every_scenario_has_a_budget_and_a_reason():
    budgets = cost.read_budgets()
    assert isinstance(budgets["measured_with"], str) and budgets["measured_with"]
    for name, sc in cost.SCENARIOS.items():
        b = budgets[name]
        assert b["instructions"] > 0 and b["calls_out"] >= 0, name
        assert ("step" in b) == (sc.step is not None), name
        assert isinstance(b["why"], str) and len(b["why"]) > 10 and "\n" not in b["why"], name
    assert set(k for k, v in budgets.items() if isinstance(v, dict)) == set(cost.SCENARIOS)


def _measurement(name="sixstep", instructions=1000, calls_out=10, step=100.0):
    return cost.Measurement(name, 1.0, instructions, calls_out, 0, step, step, 5, 0.0, {}, [], {})


def test_check_fails_above_3_percent_and_calls_a_budget_stale_below_90(monkeypatch):
    budgets = {"sixstep": {"instructions": 1000, "calls_out": 10, "step": 100.0, "why": "x"}}
    rows = {r.quantity: r for r in cost.check([_measurement(instructions=1030, calls_out=10, step=89.0)], budgets)}
    assert rows["instructions"].ok and not rows["instructions"].stale
    assert rows["calls out"].ok
    assert rows["bc_sixstep_step/call"].stale and "stale" in rows["bc_sixstep_step/call"].note
    rows = cost.check([_measurement(instructions=1031)], budgets)
    assert not rows[0].ok and "over budget by 3.1 %" in rows[0].note
    assert "sixstep" in rows[0].message() and "1,031" in rows[0].message() and "1,000" in rows[0].message()
    assert not cost.check([_measurement()], {})[0].ok  # no budget is a failure, not a pass


def test_update_prints_old_and_new_and_needs_a_reason(tmp_path, monkeypatch):
    monkeypatch.setattr(cost, "toolchain", lambda python=None: "test toolchain")
    path = tmp_path / "budget.toml"
    path.write_text('measured_with = "x"\n\n[sixstep]\ninstructions = 1000\ncalls_out = 10\nstep = 100.0\n'
                    'why = "old reason"\n\n[sine]\ninstructions = 5\ncalls_out = 1\nstep = 1.0\nwhy = "kept"\n')
    with pytest.raises(ValueError, match="why"):
        cost.update([_measurement(instructions=1100)], None, path)
    assert "1000" in path.read_text()  # nothing written
    assert cost.update([_measurement()], None, path) == []  # unchanged numbers need no reason
    changes = cost.update([_measurement(instructions=1100)], "the plant got a new lane", path)
    assert changes == ["sixstep: instructions 1,000 -> 1,100 (+10.0 %)"]
    b = cost.read_budgets(path)
    assert b["sixstep"] == {"instructions": 1100, "calls_out": 10, "step": 100.0, "why": "the plant got a new lane"}
    assert b["sine"]["why"] == "kept" and b["measured_with"] == "test toolchain"


# ---------------------------------------------------------------------------------------------------------------
# the parser, on a profile with the format's traps

PROFILE = """\
# callgrind format
version: 1
creator: callgrind-3.19.0
cmd:  python run.py
part: 1

desc: Trigger: Program termination

positions: line
events: Ir
summary: 0

ob=(1) /usr/lib/x86_64-linux-gnu/libffi.so.8
fl=(1) ???
fn=(1) 0x0000000000006250
0 30
fi=(2) /src/core/host/src/bc_sim.c
40 1000
+2 500
cfn=(5) 0x0000000000006f7a
calls=3 0
* 60
cob=(2) /pkg/bldclab/_bccore.cpython-311-x86_64-linux-gnu.so
cfn=(2) bc_sine_step
calls=10 12
* 7000
cob=(3) /usr/lib/x86_64-linux-gnu/libm.so.6
cfi=(3) ./math/fmod.c
cfn=(3) fmod
calls=4 7
* 80
fe=(1)
0 20
cob=(2)
cfi=(2)
cfn=(4) advance
calls=1 0
* 300

ob=(2)
fl=(2)
fn=(4)
5 300
fl=(4) /src/core/ctrl/src/bc_sine.c
fn=(2)
10 5000
fi=(5) /src/core/ctrl/include/bldc/bc_math.h
3 1200
fe=(4)
cob=(3)
cfi=(6) ./math/fmodf.c
cfn=(6) fmodf
calls=20 1
* 800
cfn=(7) bc_wrap
calls=20 1
* 500
fn=(7)
1 400
cob=(3)
cfn=(6)
calls=10 1
* 100

ob=(3)
fl=(3)
fn=(3)
7 80
fl=(6)
fn=(6)
1 900
totals: 8000
"""


def test_parser_counts_the_core_also_where_callgrind_books_it_under_libffi(tmp_path):
    f = tmp_path / "cg.out"
    f.write_text(PROFILE)
    prof = cost.parse(f)
    c = prof.core_cost()
    # own code: advance 300, bc_sine_step 5000 + 1200 (inlined header), bc_wrap 400, and bc_sim.c's 1500 booked
    # under libffi's function (found by its file); not libffi's own 30 + 20, not libm
    assert c.instructions == 300 + 6200 + 400 + 1500
    assert c.via_foreign == 1500
    # calls out: libm only (4 fmod from bc_sim.c's code, 20 + 10 fmodf); the "call" into libffi (the return to the
    # ctypes caller, libffi being an object that calls the core) is not one
    assert c.calls_out == {("libm.so.6", "fmod"): [4, 80], ("libm.so.6", "fmodf"): [30, 900]}
    assert c.calls_out_count == 34 and c.calls_out_inclusive == 980
    fc = prof.function_cost("bc_sine_step")
    assert (fc.calls, fc.inclusive) == (10, 7000)
    # library instructions inside: its own fmodf calls (800) and all of bc_wrap's (it has no other caller: 100)
    assert fc.external == pytest.approx(900)
    assert fc.own_per_call == pytest.approx((7000 - 900) / 10)


def test_parser_keeps_names_across_combined_dumps(tmp_path):
    text = PROFILE.replace("totals: 8000\n", "totals: 8000\n\npart: 2\n\ndesc: Trigger: Client Request\n\n"
                                             "positions: line\nevents: Ir\n\nob=(2)\nfl=(4)\nfn=(2)\n10 77\n"
                                             "totals: 77\n")
    f = tmp_path / "cg.out"
    f.write_text(text)
    prof = cost.parse(f)
    assert [p.number for p in prof.parts] == [1, 2]
    assert prof.parts[1].trigger == "Client Request"
    assert prof.core_cost([prof.parts[1]]).by_function == {"bc_sine_step": 77}
    with pytest.raises(ValueError, match="before defining"):
        bad = tmp_path / "bad.out"
        bad.write_text("events: Ir\nob=(9)\nfn=(1) f\n1 1\n")
        cost.parse(bad)

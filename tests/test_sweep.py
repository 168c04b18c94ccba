"""bldclab.sweep: grid expansion, case keys, executors giving the same bits, the resumable store (kill -9, Ctrl-C),
sweep-file errors, progress bar, CLI."""

from __future__ import annotations

import contextlib
import hashlib
import io
import itertools
import json
import math
import os
import signal
import sqlite3
import subprocess
import sys
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import pandas as pd
import psutil
import pytest

import bldclab as bl
from bldclab import sweep as sw
from bldclab.cli import main
from bldclab.errors import BldclabError
from bldclab.sweep.store import Store
from conftest import require_module

# Short cases: htm-48v at high per-unit speed (electrical period ~12 ms), few periods, six-step voltage mode.
FAST = {"drive": "htm-48v", "controller": "SixStepVoltage", "ref": 0.8, "settle_periods": 2, "measure_periods": 1,
        "settle_time": 0.0}


def fast_sweep(**grid) -> sw.Sweep:
    return sw.Sweep(base=FAST, grid=grid or {"speed_pu": [0.6, 0.9]})


def keys(s: sw.Sweep) -> list[str]:
    return [c.key for c in s.resolve()]


# ---------------------------------------------------------------------------------------------------------------
# grid expansion


def test_grid_is_the_product_in_order_last_axis_fastest():
    s = sw.Sweep(base=FAST, grid={"speed_pu": [0.5, 0.7, 0.9], "motor.L": [70e-6, 80e-6],
                                  "control.chopping": ["high", "low"]})
    assert len(s) == 12
    assert s.axes == ["speed_pu", "motor.L", "control.chopping"]
    got = [a for _, a in s.assignments()]
    want = [dict(zip(s.axes, combo, strict=True))
            for combo in itertools.product([0.5, 0.7, 0.9], [70e-6, 80e-6], ["high", "low"])]
    assert got == want
    cases = list(s.resolve())
    assert [c.index for c in cases] == list(range(12))
    assert cases[5].axes == {"speed_pu": 0.7, "motor.L": 70e-6, "control.chopping": "low"}
    assert len(set(keys(s))) == 12


def test_explicit_cases_times_grid_and_speed_settings_replace_each_other():
    s = sw.Sweep(base={**FAST, "speed_pu": 0.9},
                 grid={"ref": [0.5, 0.6]},
                 cases=[{}, {"speed_rpm": 500}, {"speed": "60 rad/s", "motor.R": 0.0}])
    assert len(s) == 6
    assert s.axes == ["speed_rpm", "speed", "motor.R", "ref"]
    specs = [s.spec(a) for _, a in s.assignments()]
    assert specs[0]["speed_pu"] == 0.9 and "speed_rpm" not in specs[0]
    assert specs[2]["speed_rpm"] == 500 and "speed_pu" not in specs[2]
    assert specs[5]["speed"] == "60 rad/s" and specs[5]["ref"] == 0.6
    speeds = [c.inputs["experiment"]["speed"] for c in s.resolve()]
    om0 = bl.load("htm-48v").Omega_0
    assert speeds[0] == 0.9 * om0
    assert speeds[2] == 500 * 2 * math.pi / 60
    assert speeds[4] == 60.0
    drive = bl.Drive.from_dict(tomllib.loads(list(s.resolve())[4].inputs["drive"]))
    assert drive.motor.R == 0.0


def test_nested_tables_flatten_to_the_same_cases():
    flat = sw.Sweep.from_dict({"base": {**FAST, "speed_pu": 0.9, "motor.R": 0.01, "control.chopping": "low"},
                               "grid": {"motor.L": [70e-6, 80e-6]}})
    nested = sw.Sweep.from_dict({"base": {**FAST, "speed_pu": 0.9, "motor": {"R": 0.01},
                                          "control": {"chopping": "low"}},
                                 "grid": {"motor": {"L": [70e-6, 80e-6]}}})
    assert keys(flat) == keys(nested)


# ---------------------------------------------------------------------------------------------------------------
# keys


def test_same_inputs_same_key_however_written():
    a = keys(fast_sweep())
    assert a == keys(fast_sweep())
    # defaults written out, a unit string equal to the catalog's, a Drive object, a Control instance or class
    same = [
        {"control.chopping": "high"},
        {"motor.L": "75 uH"},
        {"drive": bl.load("htm-48v")},
        {"controller": bl.SixStepVoltage("high")},
        {"controller": bl.SixStepVoltage},
        {"delay": 1, "h_max": 0.0},
    ]
    for extra in same:
        s = sw.Sweep(base={**FAST, **extra}, grid={"speed_pu": [0.6, 0.9]})
        assert keys(s) == a, extra
    rpm = sw.Sweep(base={**FAST, "speed_rpm": 600})
    assert keys(rpm) == keys(sw.Sweep(base={**FAST, "speed": "600 rpm"}))


def test_key_is_sha256_of_the_canonical_inputs():
    case = next(fast_sweep().resolve())
    text = json.dumps(case.inputs, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    assert case.key == hashlib.sha256(text.encode()).hexdigest()
    assert set(case.inputs) == {"bldclab", "drive", "control", "experiment"}
    assert case.inputs["bldclab"] == bl.__version__
    assert case.inputs["control"] == {"class": "bldclab.control.openloop:SixStepVoltage",
                                      "params": {"chopping": "high"}}
    assert case.inputs["drive"] == bl.load("htm-48v").to_toml()


def test_any_input_change_changes_the_key(monkeypatch):
    base = keys(sw.Sweep(base={**FAST, "speed_pu": 0.9}))[0]
    changes = [
        {"motor.R": 0.049},
        {"motor.L": "76 uH"},
        {"motor.emf.k_phi": 0.33},
        {"inverter.f_pwm": "15 kHz"},
        {"mechanics.J": 0.04},
        {"sensors.seed": 2},
        {"control.chopping": "low"},
        {"ref": 0.7},
        {"settle_periods": 3},
        {"measure_periods": 2},
        {"settle_time": 1e-3},
        {"delay": 0},
        {"speed_pu": 0.8},
        {"drive": "lu-4kw"},
    ]
    got = [keys(sw.Sweep(base={**FAST, "speed_pu": 0.9, **c}))[0] for c in changes]
    assert base not in got
    assert len(set(got)) == len(changes)
    monkeypatch.setattr(sw, "__version__", "0.0.0-other")
    assert keys(sw.Sweep(base={**FAST, "speed_pu": 0.9}))[0] != base


# ---------------------------------------------------------------------------------------------------------------
# executors: same bits


MIXED = sw.Sweep(
    base={"drive": "htm-48v", "controller": "SixStepVoltage"},
    grid={"speed_pu": [0.6, 0.9], "motor.L": [70e-6, 80e-6], "control.chopping": ["high", "bipolar"]},
    cases=[{"experiment": "steady_state", "ref": 0.8, "settle_periods": 2, "measure_periods": 1,
            "settle_time": 0.0},
           {"experiment": "simulate", "duration": "20 ms", "window": ["10 ms", "20 ms"], "ref": 0.5}])


@pytest.fixture(scope="module")
def serial_results():
    run = sw.run(MIXED, executor=sw.Serial(), progress=False)
    assert (run.total, run.computed, run.failed) == (16, 16, 0)
    return run.to_pandas()


def test_serial_results_are_physical_and_in_case_order(serial_results):
    df = serial_results
    assert list(df["case"]) == list(range(16))
    steady = df[df["experiment"] == "steady_state"]
    assert (steady["tau_mean"] > 0).all()
    assert (steady["balance_electrical"].abs() < 1e-4).all()
    # at the same speed a larger L lowers the torque (slower current rise after commutation)
    first = steady.set_index(["speed_pu", "motor.L", "control.chopping"])["tau_mean"]
    assert first[(0.6, 70e-6, "high")] > first[(0.6, 80e-6, "high")]
    transient = df[df["experiment"] == "simulate"]
    assert (transient["t1"] == 0.02).all() and (transient["steps"] > 0).all()


def test_processes_give_the_same_bits_as_serial(serial_results, tmp_path):
    run = sw.run(MIXED, tmp_path / "p.sqlite", executor=sw.Processes(2), progress=False)
    assert (run.computed, run.failed) == (16, 0)
    pd.testing.assert_frame_equal(run.to_pandas(), serial_results, check_exact=True)
    run.store.close()


@pytest.mark.slow
def test_dask_gives_the_same_bits_as_serial(serial_results, tmp_path):
    require_module("distributed")
    import distributed
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        run = sw.run(MIXED, tmp_path / "d.sqlite", executor=sw.Dask(cluster.scheduler_address), progress=False)
    assert (run.computed, run.failed) == (16, 0)
    pd.testing.assert_frame_equal(run.to_pandas(), serial_results, check_exact=True)
    run.store.close()


@pytest.mark.slow
def test_unreachable_scheduler_is_a_clear_error():
    require_module("distributed")
    with pytest.raises(BldclabError, match="scheduler: cannot connect"):
        sw.run(fast_sweep(), executor=sw.Dask("tcp://127.0.0.1:9", timeout=1.0), progress=False)


# ---------------------------------------------------------------------------------------------------------------
# store


def test_store_skips_finished_cases_and_reopens(tmp_path):
    path = tmp_path / "s.sqlite"
    s = fast_sweep(speed_pu=[0.6, 0.9], ref=[0.5, 0.8])
    first = sw.run(s, path, executor=sw.Serial(), progress=False)
    assert (first.computed, first.skipped) == (4, 0)
    df1 = first.to_pandas()
    first.store.close()
    with Store(path) as st:
        assert len(st) == 4
        for key in st.keys():
            inputs = st.inputs(key)
            assert sw.case_key(inputs) == key
        again = sw.run(s, st, executor=sw.Serial(), progress=False)
        assert (again.computed, again.skipped) == (0, 4)
        # a bigger sweep reuses the four finished cases
        bigger = sw.run(fast_sweep(speed_pu=[0.6, 0.9], ref=[0.5, 0.8, 1.0]), st, executor=sw.Serial(),
                        progress=False)
        assert (bigger.computed, bigger.skipped) == (2, 4)
        pd.testing.assert_frame_equal(sw.load_results(s, st), df1, check_exact=True)
        case = next(s.resolve())
        assert not st.add(case.key, case.inputs, case.spec, {"tau_mean": 0.0}, 0.0)  # never twice
        assert len(st) == 6
        assert len(st.to_pandas()) == 6


def test_store_refuses_other_files(tmp_path):
    bad = tmp_path / "not.sqlite"
    bad.write_text("hello, not a database\n" * 100)
    with pytest.raises(BldclabError, match="not a usable results store"):
        Store(bad)
    other = tmp_path / "other.sqlite"
    with sqlite3.connect(other) as db:
        db.execute("CREATE TABLE meta (name TEXT PRIMARY KEY, value TEXT NOT NULL)")
        db.execute("INSERT INTO meta VALUES ('schema', '99')")
    with pytest.raises(BldclabError, match="schema 99"):
        Store(other)
    with pytest.raises(BldclabError, match="cannot open"):
        Store(tmp_path / "missing" / "dir.sqlite")
    with pytest.raises(BldclabError, match="does not exist"):
        sw.load_results(fast_sweep(), tmp_path / "typo.sqlite")
    assert not (tmp_path / "typo.sqlite").exists()


@dataclass(frozen=True)
class Exploding(bl.Control):
    """A controller whose parameters cannot be filled (a bug in a case), to test failure handling."""

    at_speed: float = 0.0
    c_name: ClassVar[str] = "sixv"

    def c_record(self, drive, core, n_samples):
        raise RuntimeError(f"boom at {self.at_speed}")


def test_a_failing_case_is_recorded_and_retried_the_others_stored():
    sw.register_control(Exploding)
    s = sw.Sweep(base={**FAST, "speed_pu": 0.9},
                 cases=[{}, {"controller": "Exploding", "control.at_speed": 1.5}, {"ref": 0.5}])
    with Store() as st:
        run = sw.run(s, st, executor=sw.Serial(), progress=False)
        assert (run.computed, run.failed, run.skipped) == (2, 1, 0)
        assert run.errors == [(1, "RuntimeError: boom at 1.5")]
        assert [f[2] for f in st.failures()] == ["RuntimeError: boom at 1.5"]
        assert list(run.to_pandas()["case"]) == [0, 2]
        again = sw.run(s, st, executor=sw.Serial(), progress=False)
        assert (again.computed, again.failed, again.skipped) == (0, 1, 2)


# ---------------------------------------------------------------------------------------------------------------
# interrupted sweeps resume with nothing lost or duplicated

SLOW_TOML = """\
name = "resume"
[base]
drive = "htm-48v"
controller = "SixStepVoltage"
settle_periods = 40
measure_periods = 2
settle_time = 0.0
[grid]
speed_pu = [0.3, 0.4]
ref = [0.4, 0.5, 0.6, 0.7, 0.8]
"motor.L" = ["70 uH", "72.5 uH", "75 uH", "77.5 uH", "80 uH", "82.5 uH", "85 uH", "87.5 uH"]
"""


@pytest.fixture(scope="module")
def slow_reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("slow")
    (d / "slow.toml").write_text(SLOW_TOML)
    s = sw.Sweep.from_toml(d / "slow.toml")
    run = sw.run(s, executor=sw.Serial(), progress=False)
    assert run.computed == 80
    return s, run.to_pandas()


def _default_sigint() -> None:
    # a terminal's foreground job starts with Ctrl-C's default action; a process started from one that ignores it
    # (SIG_IGN is inherited across exec, and Python then installs no KeyboardInterrupt) would ignore it too
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def cli(*args: str, **kw) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "bldclab.cli", "sweep", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, preexec_fn=_default_sigint,
                            **kw)


def stored_rows(db: Path) -> int:
    if not db.exists():
        return 0
    con = sqlite3.connect(db, timeout=5)
    try:
        return int(con.execute("SELECT COUNT(*) FROM results").fetchone()[0])
    except sqlite3.Error:  # tables not created yet
        return 0
    finally:
        con.close()


def wait_rows(db: Path, n: int, proc: subprocess.Popen, timeout: float = 60.0) -> int:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        got = stored_rows(db)
        if got >= n:
            return got
        assert proc.poll() is None, (proc.returncode, proc.communicate())
        time.sleep(0.005)
    raise AssertionError(f"fewer than {n} rows after {timeout} s")


def check_complete(db: Path, s: sw.Sweep, reference: pd.DataFrame) -> None:
    con = sqlite3.connect(db)
    try:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        dup = con.execute("SELECT COUNT(*) FROM (SELECT key FROM results GROUP BY key HAVING COUNT(*) > 1)")
        assert dup.fetchone()[0] == 0
        stored = [r[0] for r in con.execute("SELECT key FROM results")]
    finally:
        con.close()
    assert len(stored) == 80
    assert set(stored) == set(keys(s))
    with Store(db) as st:
        pd.testing.assert_frame_equal(sw.load_results(s, st), reference, check_exact=True)


def rerun_and_check(tmp_path: Path, db: Path, before: int, s: sw.Sweep, reference: pd.DataFrame) -> None:
    proc = cli(str(tmp_path / "slow.toml"), "--workers", "2", "--csv", str(tmp_path / "out.csv"))
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert f"80 cases: {80 - before} computed, {before} already in the store, 0 failed" in out
    check_complete(db, s, reference)
    print(f"resume: {before} rows stored before the rerun, {80 - before} computed by it, 80 stored, 0 duplicates, "
          "results equal to an uninterrupted serial run")
    csv = pd.read_csv(tmp_path / "out.csv")
    assert list(csv["case"]) == list(range(80))
    assert csv["tau_mean"].tolist() == reference["tau_mean"].tolist()


def running(procs: list[psutil.Process]) -> list[psutil.Process]:
    out = []
    for p in procs:
        with contextlib.suppress(psutil.NoSuchProcess):
            if p.status() != psutil.STATUS_ZOMBIE:
                out.append(p)
    return out


@pytest.mark.slow
def test_kill_9_mid_sweep_then_resume(tmp_path, slow_reference):
    s, reference = slow_reference
    (tmp_path / "slow.toml").write_text(SLOW_TOML)
    db = tmp_path / "slow.sqlite"
    proc = cli(str(tmp_path / "slow.toml"), "--workers", "2")
    at_kill = wait_rows(db, 10, proc)
    workers = psutil.Process(proc.pid).children(recursive=True)
    assert len(workers) >= 2, workers
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    # orphaned workers notice their parent is gone and exit by themselves (their watcher polls every 0.5 s; on a
    # loaded 2-core CI machine one took more than 10 s once); then kill -9 whatever is left
    t0 = time.monotonic()
    while running(workers) and time.monotonic() - t0 < 30:
        time.sleep(0.05)
    orphans = []
    for p in running(workers):  # described before the kill below, for the message
        with contextlib.suppress(psutil.Error):
            orphans.append((p.pid, p.status(), " ".join(p.cmdline())[:200]))
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)
    assert not orphans, orphans
    before = stored_rows(db)
    assert 10 <= at_kill <= before < 80, (at_kill, before)
    print(f"kill -9: {at_kill} rows seen before the kill, {before} stored, 80 cases")
    rerun_and_check(tmp_path, db, before, s, reference)


@pytest.mark.slow
def test_ctrl_c_mid_sweep_then_resume(tmp_path, slow_reference):
    s, reference = slow_reference
    (tmp_path / "slow.toml").write_text(SLOW_TOML)
    db = tmp_path / "slow.sqlite"
    proc = cli(str(tmp_path / "slow.toml"), "--workers", "2")
    wait_rows(db, 10, proc)
    os.killpg(proc.pid, signal.SIGINT)  # what a terminal does: the whole foreground process group
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, (proc.returncode, err)
    assert "bldclab: interrupted" in err.splitlines()
    before = stored_rows(db)
    assert 10 <= before < 80
    rerun_and_check(tmp_path, db, before, s, reference)


# ---------------------------------------------------------------------------------------------------------------
# sweep files: errors name the setting, exit 2, nothing written

GOOD_BASE = """\
[base]
drive = "htm-48v"
controller = "SixStepVoltage"
ref = 0.8
settle_periods = 2
measure_periods = 1
settle_time = 0.0
speed_pu = 0.9
"""


@pytest.mark.parametrize(("text", "expect"), [
    ("[base\n", "file: not valid TOML"),
    ('drive = "htm-48v"\n', "drive: unknown top-level key"),
    ('name = "x"\n', "base: missing"),
    (GOOD_BASE + '[grid]\n"motor.L" = [75e-6, -1.0]\n', "grid.motor.L: must be > 0, got -1 (case 1 of 2"),
    (GOOD_BASE + '[grid]\n"motor.Lx" = [1.0]\n', "grid.motor.Lx: unknown field"),
    (GOOD_BASE + "[grid]\nspeed_pu = 0.5\n", "grid.speed_pu: must be a non-empty list"),
    (GOOD_BASE + "[grid]\nspeed_rpm = [300]\nspeed = [30.0]\n",
     "grid.speed_rpm: give one of speed, speed_rpm, speed_pu; speed is also set"),
    (GOOD_BASE + '[grid]\n"control.chopping" = ["high", "diagonal"]\n', "grid.control.chopping: must be one of"),
    (GOOD_BASE + '[grid]\n"control.gain" = [1.0]\n', "grid.control.gain: no such parameter of SixStepVoltage"),
    (GOOD_BASE + '[[cases]]\nref = "x"\n', "cases[0].ref: expected a number"),
    (GOOD_BASE + '[[cases]]\nsettle_periods = 1.5\n', "cases[0].settle_periods: must be an integer >= 0"),
    (GOOD_BASE + "foo = 1\n", "base.foo: unknown setting of experiment 'steady_state'"),
    (GOOD_BASE + '"sensors.current_gain" = [1.0, 2.0]\n', "base.sensors.current_gain: needs three entries"),
    (GOOD_BASE + '"sensors.hall_error" = [0.0, "x", 0.0]\n', "base.sensors.hall_error[1]: cannot read a number"),
    (GOOD_BASE + 'experiment = "transient"\n', "base.experiment: unknown experiment 'transient'"),
    (GOOD_BASE.replace('"SixStepVoltage"', '"Nope"'), "base.controller: unknown controller 'Nope' (one of "),
    (GOOD_BASE.replace('"htm-48v"', '"missing.toml"'), "base.drive: 'missing.toml' is neither a built-in"),
    (GOOD_BASE.replace("speed_pu = 0.9", ""), "speed: missing"),
    (GOOD_BASE.replace("speed_pu = 0.9", 'speed = "5 V"'), "base.speed: unit 'V' is not a unit of speed"),
    (GOOD_BASE.replace('controller = "SixStepVoltage"', 'control = "SixStepVoltage"'),
     "base.control: name the controller with 'controller = NAME'"),
    (GOOD_BASE + '[grid]\n"motor.L" = [75e-6]\n[[cases]]\n"motor.L" = 1e-5\n', "cases[0].motor.L: is also a grid"),
])
def test_bad_sweep_file_is_one_line_naming_the_setting(tmp_path, capsys, text, expect):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    assert main(["sweep", str(f), "--serial", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("bldclab: error: "), err
    assert expect in err, err
    assert str(f) in err
    assert not (tmp_path / "bad.sqlite").exists()


def test_cli_options_are_checked(tmp_path, capsys):
    f = tmp_path / "ok.toml"
    f.write_text(GOOD_BASE)
    assert main(["sweep", str(f), "--serial", "--workers", "2"]) == 2
    assert "not allowed with argument" in capsys.readouterr().err
    assert main(["sweep", str(f), "--workers", "0"]) == 2
    assert "must be >= 1" in capsys.readouterr().err
    assert main(["sweep", str(f), "--store", str(tmp_path / "no" / "s.sqlite")]) == 2
    assert "--store: directory" in capsys.readouterr().err
    assert main(["sweep", str(f), "--csv", str(tmp_path / "no" / "o.csv")]) == 2
    assert "--csv: directory" in capsys.readouterr().err


def test_cli_runs_stores_next_to_the_file_and_skips_on_rerun(tmp_path, capsys):
    f = tmp_path / "ok.toml"
    f.write_text(GOOD_BASE + "[grid]\nref = [0.5, 0.8]\n")
    assert main(["sweep", str(f), "--serial", "--csv", str(tmp_path / "o.csv")]) == 0
    out = capsys.readouterr().out
    assert "2 cases: 2 computed, 0 already in the store" in out
    assert (tmp_path / "ok.sqlite").exists()
    df = pd.read_csv(tmp_path / "o.csv")
    assert list(df["ref"]) == [0.5, 0.8] and "tau_mean_pu" in df
    (tmp_path / "stores").mkdir()
    assert main(["sweep", str(f), "--serial", "--store", str(tmp_path / "stores")]) == 0
    assert (tmp_path / "stores" / "ok.sqlite").exists()
    assert main(["sweep", str(f), "--serial"]) == 0
    assert "0 computed, 2 already in the store" in capsys.readouterr().out


# ---------------------------------------------------------------------------------------------------------------
# controllers and progress


def test_every_exported_control_dataclass_is_a_sweep_controller():
    reg = sw.controllers()
    assert reg["SixStepVoltage"] is bl.SixStepVoltage
    import bldclab.control as pkg

    for name in pkg.__all__:
        obj = getattr(pkg, name)
        if isinstance(obj, type) and issubclass(obj, bl.Control) and obj is not bl.Control:
            assert reg[name] is obj


def test_progress_bar_only_on_a_terminal():
    quiet = io.StringIO()
    p = sw.Progress(10, 2, stream=quiet)
    p.advance()
    p.close()
    assert quiet.getvalue() == ""
    loud = io.StringIO()
    p = sw.Progress(10, 2, stream=loud, enabled=True)
    time.sleep(0.02)
    p.advance(3, failed=False)
    p.close()
    text = loud.getvalue()
    assert text.endswith("\n") and "\r" in text
    last = text.rstrip("\n").split("\r")[-1]
    assert "50%" in last and "5/10" in last and "ETA" in last and "/s" in last
    assert sw._clock(3725) == "1:02:05" and sw._clock(65) == "01:05" and sw._clock(math.inf) == "--:--"

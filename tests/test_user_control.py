"""User controllers in the loop (bldclab.control.user, core bc_user.h/bc_userguard.h).

The built-in six-step rewritten as a user controller (examples/user_controller/sixstep_pi.c) gives the built-in's
trace bit for bit, in process and in a child process; a Python prototype and its C translation give the same trace;
each failure of a user controller (crash, hang, NaN, duty out of range, read past its inputs, write to its inputs,
init rejecting the parameters) ends the run with one ControllerError naming the controller and the sample, and this
process goes on; bad parameters and bad libraries are refused by name.
"""

from __future__ import annotations

import importlib.util
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas.testing as pd_testing
import pytest

import bldclab as bl
from bldclab.control.user import build, describe_library
from bldclab.errors import BldclabError, ControllerError

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "user_controller"
DATA = Path(__file__).parent / "data" / "user"
HTM = bl.load("htm-48v")

pytestmark = pytest.mark.xdist_group("user_control")


def _example(name: str):
    spec = importlib.util.spec_from_file_location(f"_user_example_{name}", EXAMPLES / f"{name}.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def libs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """The test and example libraries, built once."""
    d = tmp_path_factory.mktemp("user")
    return {
        "sixstep_pi": str(build([EXAMPLES / "sixstep_pi.c"], d / "sixstep_pi.so")),
        "sixstep_voltage": str(build([EXAMPLES / "sixstep_voltage.c"], d / "sixstep_voltage.so")),
        "faulty": str(build([DATA / "faulty.c"], d / "faulty.so")),
    }


def _same(a: bl.SimResult, b: bl.SimResult) -> list[str]:
    """Trace columns that differ (or exist in only one)."""
    names = set(a.signals) | set(b.signals)
    return sorted(k for k in names if k not in a.signals or k not in b.signals
                  or not np.array_equal(a.signals[k], b.signals[k]))


# ------------------------------------------------------------------------------------------------------------------
# the example: the built-in six-step as a user controller


@pytest.mark.slow
@pytest.mark.parametrize(("motor", "chopping", "inverter", "speed", "timing"), [
    ("htm-48v", "pwm-on-pwm", "switching", "0.5 pu", None),
    ("htm-48v", "high", "average", "0.8 pu", None),
    # an ESC: commutation timer with 15 deg of advance on a drone motor at 1.5 PWM periods per commutation
    ("f60prov-2550kv", "pwm-on-pwm", "switching", "30000 rpm", "15 deg")])
def test_sixstep_rewritten_as_a_user_controller_gives_the_builtin_trace_bit_for_bit(libs, motor, chopping, inverter,
                                                                                    speed, timing):
    drive = bl.load(motor).replace(inverter__model=inverter)
    builtin = bl.SixStep(regulation="pi", chopping=chopping) if timing is None else bl.SixStep(
        regulation="pi", chopping=chopping, timed=True, timing=timing)
    params = _example("run_sixstep_pi").user_params(drive, builtin)
    # a step of the reference mid-run (saturation, then regulation) and a current at the trip limit's edge
    sc = bl.Scenario(duration=0.03, speed=speed, ref=lambda t: np.where(t < 0.015, 0.5, 1.5) * drive.motor.I_N,
                     trace_sub=2, window=(0.02, 0.03))
    ref = bl.simulate(drive, builtin, sc)
    for isolate in (False, True):
        res = bl.simulate(drive, bl.UserControl(libs["sixstep_pi"], params, isolate=isolate), sc)
        assert _same(res, ref) == [], f"isolate={isolate}"
        assert res.metrics == ref.metrics
        assert res.meta["controller_flags"] == ref.meta["controller_flags"]
    assert np.ptp(ref.signals["sector"]) == 5  # it did commutate through every sector
    if timing is not None:  # the timer and the advance did something: without them the trace differs
        plain = bl.simulate(drive, bl.UserControl(libs["sixstep_pi"], {**params, "timed": 0, "adv_angle": 0.0},
                                                  isolate=False), sc)
        assert "i_a" in _same(plain, ref)


@pytest.mark.slow
def test_python_prototype_and_its_c_translation_give_the_same_trace(libs):
    proto = _example("prototype")
    sc = bl.Scenario(duration=0.02, speed="0.4 pu", ref=lambda t: 0.2 + 10.0 * t, window=(0.01, 0.02))
    py = bl.simulate(HTM, proto.SixStepVoltage(1.0), sc)
    c = bl.simulate(HTM, bl.UserControl(libs["sixstep_voltage"], {"gain": 1.0}), sc)
    assert _same(py, c) == []
    assert py.metrics == c.metrics
    assert py.signals["sector"].min() == 0 and py.signals["sector"].max() == 5


# ------------------------------------------------------------------------------------------------------------------
# failures: one error naming the controller and the sample, and this process goes on

FAILURES = [
    ("F_CRASH", True, "crashed with SIGSEGV (address 0x0) at sample 50 (t = 1.78571 ms)"),
    ("F_HANG", True, "did not return within its step-time budget of 0.3 s at sample 50 (t = 1.78571 ms)"),
    ("F_NAN", False, "wrote leg[0].duty = nan at sample 50 (t = 1.78571 ms): a duty must be in [0, 1]"),
    ("F_RANGE", False, "wrote leg[2].duty = 1.5 at sample 50 (t = 1.78571 ms): a duty must be in [0, 1]"),
    ("F_OVERREAD", True, "beyond the end of its inputs (bc_ctrl_in)) at sample 50"),
    ("F_INWRITE", False, "wrote to its const inputs (bc_ctrl_in.hall) at sample 50"),
    ("F_REJECT", False, "its init returned -1: it rejected its parameters"),
    ("F_INIT_HANG", True, "did not return within its step-time budget of 0.3 s in its init"),
]


@pytest.mark.slow
@pytest.mark.parametrize(("mode", "needs_child", "message"), FAILURES, ids=[f[0] for f in FAILURES])
def test_each_failure_is_one_error_naming_the_controller_and_the_sample(libs, mode, needs_child, message):
    sc = bl.Scenario(duration=0.01, speed="0.5 pu", ref=0.3)
    modes = (True, False) if not needs_child else (True,)
    for isolate in modes:
        ctl = bl.UserControl(libs["faulty"], {"mode": mode, "at": 50}, isolate=isolate, budget=0.3)
        with pytest.raises(ControllerError) as err:
            bl.simulate(HTM, ctl, sc)
        assert err.value.field == f"control (faulty, {libs['faulty']})"
        assert message in err.value.problem, err.value.problem
    # the process survived, and the same controller without the fault runs
    ok = bl.simulate(HTM, bl.UserControl(libs["faulty"], {"mode": "F_OK"}), sc)
    assert len(ok) > 0 and np.isfinite(ok.signals["i_a"]).all()


@pytest.mark.slow
def test_a_guarded_run_stops_at_the_bad_sample_not_after(libs):
    # the same controller failing at two samples: the error names each; without a fault the run is the plain run
    sc = bl.Scenario(duration=0.01, speed="0.5 pu", ref=0.3)
    for at in (0, 200):
        with pytest.raises(ControllerError, match=f"at sample {at} "):
            bl.simulate(HTM, bl.UserControl(libs["faulty"], {"mode": "F_RANGE", "at": at}, isolate=False), sc)
    a = bl.simulate(HTM, bl.UserControl(libs["faulty"], {"mode": "F_OK"}, isolate=False), sc)
    b = bl.simulate(HTM, bl.UserControl(libs["faulty"], {"mode": "F_OK"}, isolate=True), sc)
    assert _same(a, b) == []


# ------------------------------------------------------------------------------------------------------------------
# parameters and libraries


@pytest.mark.slow
def test_parameters_are_filled_by_name_and_bad_ones_refused(libs):
    lib = describe_library(libs["faulty"])
    assert lib.name == "faulty" and list(lib.leaves) == ["mode", "at", "gain"] and lib.ref == "duty"
    assert lib.built_by == f"bldclab {bl.__version__}"
    ctl = bl.UserControl(libs["faulty"], {"mode": "F_NAN", "gain": 0.5})  # named constant; defaults for the rest
    rec = ctl.c_record(HTM, bl._core.core(), 1).record
    assert (int(rec["mode"][0]), int(rec["at"][0]), float(rec["gain"][0])) == (3, -1, 0.5)
    cases = [({"mod": 1}, "control.params (faulty: faulty_params)", "not members: mod (members: mode, at, gain)"),
             ({"mode": "F_X"}, "control.params.mode", "neither a number nor a named constant of faulty"),
             ({"at": 1.5}, "control.params.at", "must be a whole number"),
             ({"at": 2**40}, "control.params.at", "must be a whole number in [-2147483648, 2147483647]"),
             ({"gain": [1, 2]}, "control.params.gain", "expected one number"),
             ({"gain": float("nan")}, "control.params.gain", "must not be NaN")]
    for params, field, problem in cases:
        with pytest.raises(BldclabError) as err:
            bl.UserControl(libs["faulty"], params)
        assert err.value.field == field and problem in err.value.problem, (params, str(err.value))
    # a library without defaults: every member must be given
    with pytest.raises(BldclabError, match=r"members left unset: chop, delay, advance"):
        bl.UserControl(libs["sixstep_pi"], {"p": 8})


@pytest.mark.slow
def test_libraries_without_the_description_or_built_against_another_contract_are_refused(tmp_path):
    with pytest.raises(BldclabError, match="built, but not usable: missing symbol bc_user_controller"):
        build([DATA / "nosymbol.c"], tmp_path / "nosym.so")
    assert not (tmp_path / "nosym.so").exists()
    nosym = tmp_path / "by_hand.so"  # the same file built by hand: refused when loaded
    subprocess.run(["cc", "-shared", "-fPIC", f"-I{ROOT / 'core' / 'ctrl' / 'include'}", str(DATA / "nosymbol.c"),
                    str(ROOT / "core" / "ctrl" / "src" / "bc_types.c"), "-o", str(nosym)], check=True)
    with pytest.raises(BldclabError, match="missing symbol bc_user_controller"):
        bl.UserControl(str(nosym))
    with pytest.raises(BldclabError, match=r"wrong struct size or version, sizeof\(bc_ctrl_in\) \d+ \(this bldclab"):
        build([DATA / "faulty.c"], tmp_path / "wrong.so", defines=["WRONG_SIZE"])
    wrong = tmp_path / "wrong_by_hand.so"
    subprocess.run(["cc", "-shared", "-fPIC", "-DWRONG_SIZE", f"-I{ROOT / 'core' / 'ctrl' / 'include'}",
                    f"-I{ROOT / 'core' / 'host' / 'include'}", str(DATA / "faulty.c"), str(ROOT / "core" / "ctrl" /
                    "src" / "bc_commutation.c"), str(ROOT / "core" / "ctrl" / "src" / "bc_types.c"), "-o", str(wrong)],
                   check=True)
    with pytest.raises(BldclabError, match=r"wrong struct size or version, sizeof\(bc_ctrl_in\) \d+ \(this bldclab"):
        bl.UserControl(str(wrong))
    with pytest.raises(BldclabError, match="no such file"):
        bl.UserControl(str(tmp_path / "none.so"))
    text = tmp_path / "text.so"
    text.write_text("not a library")
    with pytest.raises(BldclabError, match="cannot be loaded as a shared library"):
        bl.UserControl(str(text))


@pytest.mark.slow
def test_build_uses_the_cores_warnings_as_errors_and_writes_nothing_on_failure(tmp_path):
    src = tmp_path / "bad.c"
    src.write_text((DATA / "faulty.c").read_text().replace("int sector = bc_hall_sector(in->hall);",
                                                            "int sector = bc_hall_sector(in->hall);\n"
                                                            "    float lossy = in->ref * 1.0; (void)lossy;"))
    with pytest.raises(BldclabError, match=r"(?s)the build failed .*-Werror=(double-promotion|conversion)"):
        build([src], tmp_path / "bad.so")
    assert not (tmp_path / "bad.so").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["bad.c"]


@pytest.mark.slow
def test_a_rebuilt_library_at_the_same_path_is_loaded_again(tmp_path, libs):
    out = tmp_path / "lib.so"
    build([DATA / "faulty.c"], out)
    a = describe_library(out)
    src = tmp_path / "renamed.c"
    src.write_text((DATA / "faulty.c").read_text().replace('.name = "faulty"', '.name = "renamed"'))
    build([src], out)
    b = describe_library(out)
    assert (a.name, b.name) == ("faulty", "renamed")


@pytest.mark.slow
def test_a_user_controller_pickles_as_its_path_and_settings(libs, tmp_path):
    ctl = bl.UserControl(libs["faulty"], {"mode": "F_OK", "gain": 0.5}, budget=2.0)
    back = pickle.loads(pickle.dumps(ctl))
    assert (back.library, back.params, back.isolate, back.budget) == (ctl.library, ctl.params, True, 2.0)
    # a worker where the path is gone runs the copy of the same content this machine loaded
    out = tmp_path / "gone.so"
    build([DATA / "faulty.c"], out, defines=["GONE_VARIANT=1"])
    data = pickle.dumps(bl.UserControl(str(out), {"gain": 0.5}))
    out.unlink()
    again = pickle.loads(data)
    assert again.library == str(out) and again.lib.name == "faulty"
    res = bl.simulate(HTM, again, bl.Scenario(duration=0.002, speed="0.5 pu", ref=0.5))
    assert len(res) > 0


# ------------------------------------------------------------------------------------------------------------------
# the Python controller (no build needed)


class _Constant(bl.PythonControl):
    """Legs (HIGH d, LOW 1, OFF) whatever the sector; d from the constructor; a fault at sample ``at``."""

    diag = ("k", "v_dc V")

    def __init__(self, d: float, at: int = -1, what: str = "") -> None:
        self.d, self.at, self.what, self.k = d, at, what, 0

    def init(self, drive: bl.Drive) -> None:
        self.k = 0

    def step(self, inputs):
        self.out.diag[0] = self.k
        self.out.diag[1] = inputs.v_dc
        d = self.d
        if self.k == self.at:
            if self.what == "raise":
                raise ZeroDivisionError("the bug")
            d = float("nan") if self.what == "nan" else 1.25
        self.k += 1
        return ((self.HIGH, d), (self.LOW, 1.0), (self.OFF, 0.0))


def test_a_python_controller_runs_once_per_sample_with_the_c_inputs():
    sc = bl.Scenario(duration=0.002, speed="0.3 pu", ref=0.0)
    res = bl.simulate(HTM, _Constant(0.25), sc)
    k = res.signals["k"]
    assert res.units["v_dc"] == "V"
    # trace_sub rows per sample: diag k counts the samples; the delay of one sample applies the legs
    assert k[-1] == res.meta["samples"] - 1 and np.all(np.diff(np.unique(k)) == 1)
    assert np.allclose(res.signals["v_dc"], HTM.inverter.V_dc, rtol=0.02)


@pytest.mark.parametrize(("what", "message"), [("raise", "raised an exception at sample 7"),
                                               ("nan", "wrote leg[0].duty = nan at sample 7"),
                                               ("range", "wrote leg[0].duty = 1.25 at sample 7")])
def test_a_python_controller_that_fails_ends_the_run_with_the_sample(what, message):
    sc = bl.Scenario(duration=0.002, speed="0.3 pu", ref=0.0)
    with pytest.raises(ControllerError) as err:
        bl.simulate(HTM, _Constant(0.25, at=7, what=what), sc)
    assert message in str(err.value) and err.value.field == "control (_Constant)"
    if what == "raise":
        assert isinstance(err.value.__cause__, ZeroDivisionError)


# ------------------------------------------------------------------------------------------------------------------
# the command line


@pytest.mark.slow
def test_command_line_builds_describes_and_simulates_a_user_controller(tmp_path, capsys):
    from bldclab.cli import main

    lib = tmp_path / "faulty.so"
    assert main(["controller", "build", str(DATA / "faulty.c"), "-o", str(lib)]) == 0
    assert "controller 'faulty', parameters faulty_params (3 members, with defaults)" in capsys.readouterr().out
    assert main(["controller", "describe", str(lib)]) == 0
    out = capsys.readouterr().out
    assert "--param mode=...  int32  default 0" in out and "F_CRASH=1" in out and "ref: duty" in out
    assert main(["simulate", "htm-48v", "--control", str(lib), "--param", "gain=0.5", "--ref", "0.6",
                 "--format", "json", "--no-trace"]) == 0
    import json

    summary = json.loads(capsys.readouterr().out)
    assert summary["reference"] == 0.6 and summary["reference_unit"] == "duty" and summary["tau_mean_N_m"] > 0
    for argv, message in [
        (["--param", "mode=F_CRASH", "--param", "at=50"], f"control (faulty, {lib}): crashed with SIGSEGV"),
        (["--param", "mode=F_HANG", "--param", "at=0", "--budget", "0.3"],
         "did not return within its step-time budget of 0.3 s at sample 0 (t = 0 ms)"),
        (["--param", "mode=4", "--param", "at=3"], "wrote leg[2].duty = 1.5 at sample 3"),
        (["--param", "mode=F_RANGE", "--param", "at=3", "--in-process"], "wrote leg[2].duty = 1.5 at sample 3"),
        (["--param", "mod=1"], "--param: not members: mod"),
        (["--param", "mode"], "--param: expected KEY=VALUE"),
        (["--param", "at=x"], "--param at: 'x' is neither a number nor a named constant"),
        (["--current", "5 A"], "--current: your controller takes its reference with --ref"),
    ]:
        assert main(["simulate", "htm-48v", "--control", str(lib), "--no-trace", *argv]) == 2, argv
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, (argv, err)
    assert main(["simulate", "htm-48v", "--control", str(tmp_path / "none.so")]) == 2
    assert "--control: " in capsys.readouterr().err
    assert main(["simulate", "htm-48v", "--param", "a=1"]) == 2
    assert "--param: is a setting of your own controller" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------------------------------
# sweeps: a user controller by name, on processes and Dask, identical to serial


@pytest.mark.slow
def test_a_sweep_of_a_user_controller_on_processes_and_dask_is_identical_to_serial(libs, tmp_path):
    import pandas as pd

    from bldclab import sweep as sw
    from conftest import require_module

    s = sw.Sweep(base={"drive": "htm-48v", "controller": "UserControl", "control.library": libs["faulty"],
                       "control.params": {"gain": 1.0}, "ref": 0.8, "settle_periods": 2, "measure_periods": 1,
                       "settle_time": 0.0},
                 grid={"speed_pu": [0.5, 0.9], "control.params.gain": [0.5, 1.0]})
    serial = sw.run(s, tmp_path / "s.sqlite", executor=sw.Serial(), progress=False)
    assert (serial.computed, serial.failed) == (4, 0)
    ref = serial.to_pandas()
    torque = ref.set_index(["speed_pu", "control.params.gain"])["tau_mean"]
    assert torque[(0.5, 1.0)] > torque[(0.5, 0.5)] > 0  # the parameter reached the C controller
    runs = {"processes": sw.run(s, tmp_path / "p.sqlite", executor=sw.Processes(2), progress=False)}
    require_module("distributed")
    import distributed

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        runs["dask"] = sw.run(s, tmp_path / "d.sqlite", executor=sw.Dask(cluster.scheduler_address), progress=False)
    for name, run in runs.items():
        assert (run.computed, run.failed) == (4, 0), name
        pd.testing.assert_frame_equal(run.to_pandas(), ref, check_exact=True)
        run.store.close()
    serial.store.close()


@pytest.mark.slow
def test_a_library_rebuilt_after_the_controller_was_made_is_refused(tmp_path):
    out = tmp_path / "lib.so"
    build([DATA / "faulty.c"], out)
    ctl = bl.UserControl(str(out))
    src = tmp_path / "changed.c"
    src.write_text((DATA / "faulty.c").read_text().replace('.name = "faulty"', '.name = "changed"'))
    build([src], out)
    with pytest.raises(BldclabError, match=r"control.sha256: the library at .* has changed"):
        pickle.loads(pickle.dumps(ctl))


@pytest.mark.slow
def test_a_description_generated_from_the_params_header_runs_as_a_written_one(libs, tmp_path, capsys):
    from bldclab.cli import main

    out = tmp_path / "plain.so"
    assert main(["controller", "build", str(DATA / "plain.c"), "--params-header", str(DATA / "plain.h"),
                 "--diag", "sector", "--ref-meaning", "duty", "-o", str(out)]) == 0
    assert "controller 'plain', parameters plain_params (7 members)" in capsys.readouterr().out
    lib = describe_library(out)
    assert list(lib.leaves) == ["gain", "limits.lo", "limits.hi", "limits.unused", "order", "spare", "flags"]
    assert lib.leaves["order"][2] == (3,) and lib.dtype.itemsize == 40 and lib.ref == "duty"
    sc = bl.Scenario(duration=0.01, speed="0.4 pu", ref=0.3)
    params = {"gain": 1.0, "limits": {"lo": 0.0, "hi": 1.0}, "limits.unused": 7, "order": [0, 1, 2], "spare": 0.0,
              "flags": 0}  # a nested mapping and a dotted name
    plain = bl.simulate(HTM, bl.UserControl(str(out), params), sc)
    written = bl.simulate(HTM, bl.UserControl(libs["sixstep_voltage"], {"gain": 1.0}), sc)
    assert _same(plain, written) == []
    # a header the generator cannot read, or without the contract's functions: one error, nothing built
    bad = tmp_path / "bad.h"
    bad.write_text("typedef struct { float m[2][2]; } bad_params;\ntypedef struct { int k; } bad_state;\n"
                   "int bad_init(void);\nvoid bad_step(void);\n")
    with pytest.raises(BldclabError, match=r"bad_params.m.*more than one dimension"):
        build([DATA / "plain.c"], tmp_path / "bad.so", params_header=bad)
    bad.write_text("typedef struct { float k; } bad_params;\n")
    with pytest.raises(BldclabError, match="declares bad_params but not bad_state, bad_init, bad_step"):
        build([DATA / "plain.c"], tmp_path / "bad.so", params_header=bad)
    assert not (tmp_path / "bad.so").exists()


class _Sensing(bl.PythonControl):
    """Records the back-EMF sensing inputs (ADC conversions, comparator edges) in its diagnostics."""

    diag = ("n_adc", "zc_edges", "v_term_a V")

    def step(self, inputs):
        self.out.diag[0] = inputs.n_adc
        self.out.diag[1] = sum(inputs.zc_count)
        self.out.diag[2] = inputs.v_term[0]
        return ((self.PWM, 0.5), (self.PWM, 0.5), (self.PWM, 0.5))


def test_a_controller_that_reads_the_back_emf_sensing_gets_it_and_one_that_does_not_sees_zeros():
    class Reading(_Sensing):
        needs_bemf_sensing = True

    sc = bl.Scenario(duration=0.01, speed="0.5 pu", ref=0.0)
    on = bl.simulate(HTM, Reading(), sc)
    off = bl.simulate(HTM, _Sensing(), sc)
    samples = on.meta["samples"]
    # one conversion per PWM period (every other sample); comparator edges
    assert on.signals["n_adc"][-1] >= samples // 2 - 2 and on.signals["zc_edges"][-1] > 0
    assert np.ptp(on.signals["v_term_a"]) > 10.0  # the terminal swings with the back-EMF and the PWM
    assert not np.any(off.signals["n_adc"]) and not np.any(off.signals["zc_edges"])
    assert off.meta["bemf"] is None and on.meta["bemf"]["conversions"] > 0


@pytest.mark.slow
def test_an_efficiency_map_of_a_user_controller_on_processes_is_the_builtins(libs):
    from bldclab.analysis.effmap import efficiency_map

    builtin = bl.SixStep(regulation="pi", reference="torque")
    user = bl.UserControl(libs["sixstep_pi"], _example("run_sixstep_pi").user_params(HTM, builtin))
    torques, speeds = [10.0, 25.0], [0.4 * HTM.Omega_0, 0.7 * HTM.Omega_0]
    kw = {"supplies": ("square",), "summarise": False}
    a = efficiency_map(HTM, torques, speeds, workers=1, controls={"square": builtin}, **kw)
    b = efficiency_map(HTM, torques, speeds, workers=2, controls={"square": user}, **kw)
    cols = [c for c in a.points.columns if c != "wall_s"]
    assert len(a.points) == 4
    pd_testing.assert_frame_equal(a.points[cols], b.points[cols], check_exact=True)


@pytest.mark.slow
@pytest.mark.parametrize("script", ["run_sixstep_pi.py", "prototype.py"])
def test_the_example_scripts_run_and_find_identical_traces(script, tmp_path):
    import os

    import bldclab

    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(bldclab.__file__).parents[1]),
                                                         os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, str(EXAMPLES / script)], capture_output=True, text=True, timeout=600,
                          cwd=tmp_path, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    flags = [line.rsplit(":", 1)[1].strip() for line in proc.stdout.splitlines() if "identical" in line]
    assert flags and all(f == "True" for f in flags), proc.stdout
    assert list(tmp_path.iterdir()) == []  # nothing written where it ran


@pytest.mark.slow
def test_the_command_line_runs_the_example_as_the_builtin_from_its_params_file(libs, capsys):
    import json
    import tomllib

    from bldclab.cli import main

    toml = EXAMPLES / "sixstep_pi_htm48v.toml"
    builtin = bl.SixStep(regulation="pi")
    want = _example("run_sixstep_pi").user_params(HTM, builtin)
    rec = bl.UserControl(libs["sixstep_pi"], tomllib.loads(toml.read_text())).c_record(HTM, bl._core.core(), 1)
    assert {k: rec.record[k][0].item() for k in want} == want  # the file is what the built-in gives itself
    common = ["--speed", "0.6 pu", "--format", "json", "--no-trace"]
    assert main(["simulate", "htm-48v", "--control", libs["sixstep_pi"], "--params", str(toml), "--ref", "50",
                 *common]) == 0
    user = json.loads(capsys.readouterr().out)
    assert main(["simulate", "htm-48v", "--control", "square", "--regulation", "pi", "--current", "50 A",
                 *common]) == 0
    ref = json.loads(capsys.readouterr().out)
    differ = sorted(k for k in ref if ref[k] != user[k])
    assert differ == ["control", "reference_unit"], differ
    # --param overrides the file; a file that is not TOML is one error
    assert main(["simulate", "htm-48v", "--control", libs["sixstep_pi"], "--params", str(toml), "--param", "p=0",
                 *common]) == 2
    assert "its init returned -1" in capsys.readouterr().err
    assert main(["simulate", "htm-48v", "--control", libs["sixstep_pi"], "--params", str(DATA / "faulty.c"),
                 *common]) == 2
    assert "--params: cannot read" in capsys.readouterr().err


@pytest.mark.slow
def test_a_library_uploaded_to_dask_workers_runs_there_without_the_path(tmp_path):
    from conftest import require_module

    require_module("distributed")
    import distributed

    from bldclab import sweep as sw
    from bldclab.control.user import _cache_dir
    from bldclab.sweep.executors import run_case

    out = tmp_path / "travels.so"
    src = tmp_path / "travels.c"
    src.write_text((DATA / "faulty.c").read_text().replace('.name = "faulty"', '.name = "travels"'))
    build([src], out)
    s = sw.Sweep(base={"drive": "htm-48v", "controller": "UserControl", "control.library": str(out),
                       "control.params": {"gain": 0.5}, "ref": 0.8, "speed_pu": 0.7, "settle_periods": 1,
                       "measure_periods": 1, "settle_time": 0.0})
    (case,) = list(s.resolve())
    here = run_case(case.inputs)
    sha = case.inputs["control"]["params"]["sha256"]
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        client.upload_file(str(out), load=False)
        # the worker has neither the path nor this machine's copy: only the uploaded file
        out.unlink()
        (_cache_dir() / f"{sha[:32]}.so").unlink()
        there = client.submit(run_case, case.inputs, pure=False).result()
    assert there == here and here["tau_mean"] > 0

"""The CLI's front: options checked before any work, the discoverability commands (drives, template, check)."""

from __future__ import annotations

import math
import os
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import bldclab as bl
from bldclab import cli
from bldclab.analysis.compare import VERDICT_TOLERANCE, _verdict
from bldclab.analysis.identify import sample_path
from bldclab.cli import analyze as cli_analyze
from bldclab.cli import compare as cli_compare
from bldclab.cli import faults as cli_faults
from bldclab.cli import paths
from bldclab.cli import torque_control as cli_torque
from bldclab.cli.drives import SOURCES
from bldclab.model import analytic as an
from bldclab.model.catalog import names

pytestmark = pytest.mark.xdist_group("cli_front")


def run_main(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    rc = cli.main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.fixture
def locked_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A directory the process may not write into.

    The permission is taken from ``os.access`` as the check does, made to answer "no" for this directory: a chmod
    does not stop root, and CI runs as root, so the test would otherwise never run there.
    """
    d = tmp_path / "locked"
    d.mkdir()
    real_access = os.access

    def access(path: object, mode: int, *args: object, **kw: object) -> bool:
        if Path(str(path)).absolute() == d.absolute() and mode & os.W_OK:
            return False
        return real_access(path, mode, *args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(paths.os, "access", access)
    return d


@pytest.fixture
def no_job(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make every command's job fail loudly if it starts: an option error must come before it."""
    def ran(*args: object, **kw: object) -> None:
        raise AssertionError("the job ran before the option was checked")

    monkeypatch.setattr(cli_compare, "compare", ran)
    monkeypatch.setattr(cli_torque.paper2, "compare_methods", ran)
    monkeypatch.setattr(cli_faults, "fault_table", ran)
    monkeypatch.setattr(cli_analyze, "table1_text", ran)


COMMANDS_WITH_OUT = [
    ["compare", "htm-48v", "--speeds", "2"],
    ["torque-control", "lu-4kw", "--torques", "50%", "--speeds", "0.5 pu", "--methods", "rect"],
    ["faults", "htm-48v"],
    ["analyze", "htm-48v"],
]


@pytest.mark.parametrize("argv", COMMANDS_WITH_OUT)
def test_uncreatable_out_fails_before_the_run(capsys: pytest.CaptureFixture[str], tmp_path: Path, no_job: None,
                                              argv: list[str]) -> None:
    """An --out below a regular file cannot be created: exit 2 at once, one line naming --out."""
    blocker = tmp_path / "a-file"
    blocker.write_text("x")
    target = blocker / "results"
    rc, out, err = run_main(capsys, *argv, "--out", str(target))
    assert rc == 2
    assert err.startswith("bldclab: error: --out:") and "is not a directory" in err and err.count("\n") == 1
    assert out == ""
    assert blocker.read_text() == "x"


@pytest.mark.parametrize("argv", COMMANDS_WITH_OUT)
def test_unwritable_out_fails_before_the_run(capsys: pytest.CaptureFixture[str], locked_dir: Path, no_job: None,
                                             argv: list[str]) -> None:
    """An --out that cannot be created fails at once (exit 2, one line naming --out), before any simulation."""
    target = locked_dir / "results"
    rc, out, err = run_main(capsys, *argv, "--out", str(target))
    assert rc == 2
    assert err.startswith("bldclab: error: --out:") and "not writable" in err and err.count("\n") == 1
    assert out == ""
    assert not target.exists()


def test_out_that_is_a_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    f = tmp_path / "file"
    f.write_text("x")
    rc, _, err = run_main(capsys, "faults", "htm-48v", "--out", str(f))
    assert rc == 2 and "--out" in err and "is not a directory" in err
    assert f.read_text() == "x"


@pytest.mark.parametrize("argv, option", [
    (["compare", "htm-48v", "--workers", "0"], "--workers"),
    (["report", "htm-48v", "--workers", "0"], "--workers"),
    (["compare", "htm-48v", "--max-speed", "5"], "--max-speed"),
    (["compare", "htm-48v", "--min-speed", "0"], "--min-speed"),
    (["compare", "htm-48v", "--min-speed", "0.5", "--max-speed", "0.4"], "--max-speed"),
    (["report", "htm-48v", "--max-speed", "5"], "--max-speed"),
    (["torque-control", "lu-4kw", "--speeds", "3 xx"], "--speeds"),
    (["torque-control", "lu-4kw", "--speeds", "0 pu"], "--speeds"),
    (["torque-control", "lu-4kw", "--torques", "0%"], "--torques"),
    (["torque-control", "lu-4kw", "--methods", "foo"], "--methods"),
    (["faults", "htm-48v", "--speed", "3 xx"], "--speed"),
    (["template", "--from", "no-such-drive"], "--from"),
])
def test_option_errors_name_the_option(capsys: pytest.CaptureFixture[str], tmp_path: Path, argv: list[str],
                                       option: str) -> None:
    rc, out, err = run_main(capsys, *argv, "--out", str(tmp_path / "o"))
    assert rc == 2 and out == ""
    assert err.startswith(f"bldclab: error: {option}:") or err.startswith(f"bldclab: error: argument {option}:")
    assert err.count("\n") == 1
    assert not (tmp_path / "o").exists()


def _sim(t_sine: list[float], t_square: list[float]) -> pd.DataFrame:
    w = np.linspace(0.1, 0.9, len(t_sine))
    rows = []
    for supply, ts in (("sine", t_sine), ("square", t_square)):
        for x, t in zip(w, ts, strict=True):
            rows.append({"supply": supply, "Omega_pu": x, "T_pu": t, "TR_avg_pu": 0.1, "eta": 0.9})
    return pd.DataFrame(rows)


def test_verdict_calls_small_differences_equal() -> None:
    """A difference below the tolerance is "equal", with the tolerance stated; above it the better supply is named."""
    tol = VERDICT_TOLERANCE["T_pu"]
    lines = _verdict(_sim([1.0, 1.0, 1.0, 1.0], [1.0 - 0.4 * tol, 1.0 - 0.4 * tol, 0.9, 0.9]))
    torque = [v for v in lines if v.startswith("mean torque")]
    assert torque == [
        f"mean torque: sinusoidal better for Omega in [0.63, 0.90] p.u. (by 0.100 p.u. on average, above the {tol:g} "
        "p.u. resolved)",
        f"mean torque: equal for Omega in [0.10, 0.37] p.u. (differences below {tol:g} p.u., what the simulation "
        "resolves; 0.002 on average)"]
    assert [v for v in lines if v.startswith("efficiency")] == [
        "efficiency: equal for Omega in [0.10, 0.90] p.u. (differences below 0.005, what the simulation resolves; "
        "0.000 on average)"]
    # a single speed is named as one speed, not as [x, x]
    one = _verdict(_sim([1.0, 1.0, 1.0], [1.0, 0.5, 1.0]))
    assert "mean torque: sinusoidal better for Omega = 0.50 p.u. (by 0.500 p.u. on average, above the 0.005 p.u. " \
           "resolved)" in one


# ---------------------------------------------------------------------------------------------------------------
# identify: the summary on stdout, the tables on request, the sample record discoverable


def test_identify_prints_the_summary_and_writes_the_tables(capsys: pytest.CaptureFixture[str],
                                                            tmp_path: Path) -> None:
    rc, out, err = run_main(capsys, "identify", "--write-sample", str(tmp_path / "s.csv"))
    assert rc == 0 and err == ""
    assert (tmp_path / "s.csv").read_bytes() == sample_path().read_bytes()
    command = out.splitlines()[-1]
    assert command.startswith("identify it: bldclab identify ")
    argv = shlex.split(command.removeprefix("identify it: bldclab "))
    argv[argv.index("--out") + 1] = str(tmp_path / "id.toml")
    rc, out, err = run_main(capsys, *argv, "--tables", str(tmp_path / "t.csv"))
    assert rc == 0, err
    assert len(out.splitlines()) < 40  # the summary, not the 360-row table
    assert f"wrote {tmp_path / 't.csv'} (360 points per phase)" in out and f"wrote {tmp_path / 'id.toml'}" in out
    tables = pd.read_csv(tmp_path / "t.csv")
    assert list(tables.columns) == ["theta_deg", "k_a", "k_b", "k_c"] and len(tables) == 360
    drive = bl.load(tmp_path / "id.toml")
    # the CSV holds the tables the motor file got (the file's per-phase tables in V s/rad)
    np.testing.assert_allclose(drive.motor.emf.shapes[0](np.radians(tables.theta_deg)), tables.k_a, atol=1e-6)
    rc, out, _ = run_main(capsys, *argv[:argv.index("--out")])
    assert rc == 0 and "360 points per phase: --tables FILE.csv writes them" in out


@pytest.mark.parametrize("argv, option", [
    (["identify", "--speed", "auto"], "WAVEFORM.csv"),
    (["identify", "x.csv"], "--speed"),
    (["identify", "x.csv", "--write-sample", "s.csv"], "--write-sample"),
])
def test_identify_usage_errors(capsys: pytest.CaptureFixture[str], argv: list[str], option: str) -> None:
    rc, out, err = run_main(capsys, *argv)
    assert rc == 2 and out == "" and err.startswith(f"bldclab: error: {option}")


# ---------------------------------------------------------------------------------------------------------------
# discoverability: drives, template, check


def test_the_light_commands_load_no_heavy_module(tmp_path: Path) -> None:
    """--help, drives, check, template and analyze (without --out) import neither pandas nor matplotlib nor the C
    binding (issue 22: each answers in a fraction of a second; the times are in benchmarks/cli_startup.py)."""
    out = str(tmp_path / "m.toml")
    code = ("import sys\nfrom bldclab.cli import main\n"
            f"runs = [['--help'], ['drives'], ['check', 'htm-48v'], ['template', '--out', {out!r}],"
            " ['analyze', 'htm-48v']]\n"
            "codes = [main(a) for a in runs]\n"
            "heavy = [m for m in ('pandas', 'matplotlib', 'scipy', 'bldclab._core', 'bldclab.sim', 'bldclab.control',"
            " 'bldclab.analysis') if m in sys.modules]\n"
            "print(codes, heavy, file=sys.stderr)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert proc.stderr.strip().splitlines()[-1] == "[0, 0, 0, 0, 0] []", proc.stderr



def test_python_m_bldclab_runs_the_command(tmp_path: Path) -> None:
    """``python -m bldclab`` is the ``bldclab`` command (it had no ``__main__``: "No module named bldclab.__main__"),
    with the same output and exit codes as ``python -m bldclab.cli``: 0 for a listing, 2 for a bad option."""
    env = {**os.environ, "PYTHONPATH": str(Path(bl.__file__).parent.parent)}
    runs = {}
    for module in ("bldclab", "bldclab.cli"):
        for argv in (["drives"], ["drives", "--no-such-option"]):
            proc = subprocess.run([sys.executable, "-m", module, *argv], capture_output=True, text=True, timeout=120,
                                  check=False, env=env, cwd=tmp_path)
            runs[module, len(argv)] = (proc.returncode, proc.stdout, proc.stderr)
    assert runs["bldclab", 1][0] == 0 and "htm-48v" in runs["bldclab", 1][1]
    assert runs["bldclab", 2][0] == 2 and runs["bldclab", 2][2].startswith("bldclab: error:")
    assert runs["bldclab", 1] == runs["bldclab.cli", 1] and runs["bldclab", 2] == runs["bldclab.cli", 2]


def test_drives_lists_every_built_in_drive(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = run_main(capsys, "drives")
    assert rc == 0 and err == ""
    lines = out.splitlines()
    assert lines[0].split()[:3] == ["name", "back-EMF", "V_dc"]
    for name in names():
        d = bl.load(name)
        row = next(line for line in lines if line.startswith(name + " "))
        # a drive without a SOURCES entry shows its description up to the first colon (cli.drives, run_command)
        assert (SOURCES.get(name) or d.description.split(":")[0][:60]) in row
        cells = row.split()
        assert f"{d.inverter.V_dc:g}" in cells and str(d.motor.p) in cells
        assert f"{d.Omega_0 * 30 / np.pi:.0f}" in cells


@pytest.mark.parametrize("name", names())
def test_template_round_trips(tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str) -> None:
    """The template of a drive loads back to the same drive; every field has a comment with its unit."""
    f = tmp_path / "my.toml"
    rc, out, _ = run_main(capsys, "template", "--from", name, "--out", str(f))
    assert rc == 0 and out.startswith(f"wrote {f}")
    assert bl.load(f) == bl.load(name)
    text = f.read_text()
    assert tomllib.loads(text)  # valid TOML
    lines = text.splitlines()
    for j, line in enumerate(lines):
        key = line.split("=")[0].strip()
        if "=" in line and not line.startswith(("#", " ", "[")) and key.isidentifier():
            assert lines[j - 1].startswith(f"# {key}: "), line  # the comment above names the field


def test_template_to_stdout_loads(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = run_main(capsys, "template")
    assert rc == 0
    f = tmp_path / "t.toml"
    f.write_text(out)
    assert bl.load(f) == bl.load("htm-48v")
    assert "# R: Ohm: phase resistance" in out and "# [motor.cogging]" in out


def test_check_prints_the_derived_quantities(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, err = run_main(capsys, "check", "htm-48v")
    assert rc == 0 and err == ""
    d = bl.load("htm-48v")
    # htm-48v: Omega_0 = 48 V / (2 * 0.32 V s/rad) = 75 rad/s; L/R = 75 uH / 50 mOhm = 1.5 ms;
    # f_e = 8 * 75 / (2 pi) = 95.49 Hz; 14 kHz / (6 f_e) = 24.43 PWM periods per sixth of a period
    assert "75 rad/s = 716.197 rpm" in out and "1.5 ms" in out and "95.493 Hz" in out and "24.43" in out
    assert f"{an.theta_m(d):.6g} rad" in out and "32 N m" in out and "0.32 V s/rad" in out
    assert "closed forms (bldclab analyze) apply" in out
    rc, out, _ = run_main(capsys, "check", "lu-4kw")
    assert rc == 0
    for reason in an.applicability(bl.load("lu-4kw")):
        assert reason in out


@pytest.mark.parametrize("content, field", [
    ("[motor]\np = 0\n", "motor.emf"),
    ('[motor]\np = 2\nR = "1 V"\n', "motor"),
    ("not toml ===", "file"),
])
def test_check_bad_file(tmp_path: Path, capsys: pytest.CaptureFixture[str], content: str, field: str) -> None:
    f = tmp_path / "bad.toml"
    f.write_text(content)
    rc, out, err = run_main(capsys, "check", str(f))
    assert rc == 2 and out == ""
    assert err.startswith("bldclab: error: ") and err.count("\n") == 1 and field in err


def test_analyze_gives_the_speeds_in_rpm(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = run_main(capsys, "analyze", "htm-48v")
    assert rc == 0
    # Omega_0 = 75 rad/s = 716.2 rpm; (21): 0.955224 * 75 = 71.64 rad/s = 684.1 rpm
    assert out.splitlines()[-1].startswith("speeds: Omega_0 75 rad/s = 716.2 rpm; base speed sinusoidal (21) "
                                           "71.64 rad/s = 684.1 rpm")
    rc, out, _ = run_main(capsys, "analyze", "htm-48v", "--format", "json")
    assert rc == 0 and "rpm" not in out.splitlines()[-1]


DRONE = Path(__file__).resolve().parent / "data" / "drone-2207.toml"


def test_check_prints_both_forms_of_the_ratings(capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 23, item 3: pole pairs and poles, phase and line-to-line R and L, KV and k_phi/k_1."""
    rc, out, err = run_main(capsys, "check", str(DRONE))
    assert rc == 0 and "motor.p" not in err
    assert "7 pole pairs = 14 poles" in out
    assert "40 mOhm per phase = 80 mOhm line to line" in out and "7.5 uH per phase = 15 uH line to line" in out
    assert "1950 rpm/V (KV_rms 2757.72 rpm/V)" in out
    assert "0.00244854 V s/rad" in out and "0.00282733 V s/rad" in out  # k_phi, k_1


def test_check_warns_when_pole_pairs_look_like_a_pole_count(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                                            ) -> None:
    f = tmp_path / "p14.toml"
    f.write_text(DRONE.read_text().replace("poles = 14", "p = 14"))
    rc, out, err = run_main(capsys, "check", str(f))
    assert rc == 0 and "14 pole pairs = 28 poles" in out
    first = err.splitlines()[0]  # then what compare would warn about (a 28-pole reading is slow to PWM)
    assert first.startswith("bldclab: warning: ") and all(line.startswith("bldclab: warning: ")
                                                          for line in err.splitlines())
    assert "motor.p: p = 14 pole pairs (28 poles)" in first and "if 14 is the pole count (7 pole pairs" in first


@pytest.mark.parametrize("name", names())
def test_template_examples_are_the_drives_own_and_load_uncommented(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                                   name: str) -> None:
    """Issue 23, item 10: no float noise, no example value of another drive, no comment naming another unit.

    Every commented-out example line, uncommented, still gives a loadable file: its units are those of the field.
    """
    rc, out, _ = run_main(capsys, "template", "--from", name)
    assert rc == 0
    for noise in ("99999999", "00000001"):
        assert noise not in out.replace(bl.load(name).description, "")
    assert "# Omega_N = 67.0" not in out  # htm-48v's rated speed, once shown for every drive
    lines = out.splitlines()
    for line in lines:
        if line.startswith("# ") and " = \"" in line and "rpm\"" in line:
            assert "# rad/s" not in line, line
    uncommented = []
    for line in lines:
        body = line[2:].split("  #")[0] if line.startswith("# ") else line
        if line.startswith("# ") and (re_key(body) or body.startswith("[motor.cogging]")):
            uncommented.append(body)
        else:
            uncommented.append(line)
    f = tmp_path / "all.toml"
    f.write_text("\n".join(uncommented) + "\n")
    d, base = bl.load(f), bl.load(name)
    if base.motor.Omega_N is None:  # the example is this drive's own default rated speed, to 4 digits
        assert d.motor.Omega_N == pytest.approx(base.motor.Omega_nominal, rel=1e-3)
    if base.inverter.E_on == 0:  # the energies' test point is this drive's bus and rated current
        assert (d.inverter.V_test, d.inverter.I_test) == (base.inverter.V_dc, pytest.approx(base.motor.I_N, rel=1e-5))
    if math.isinf(base.sensors.current_full_scale):  # the current sensors' full scale: twice the rated current
        assert d.sensors.current_full_scale == pytest.approx(2.0 * base.motor.I_N, rel=1e-3)


def re_key(text: str) -> bool:
    """Whether ``text`` is a ``key = value`` line."""
    key = text.split("=")[0].strip()
    return "=" in text and key.isidentifier()


def test_check_warns_about_the_premises_compare_warns_about_in_its_words(capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 23, item 11: 1.465 PWM periods per commutation at Omega_0 (8.97 per electrical period at compare's top
    speed, 0.98 Omega_0): check warns with the finding compare's runs give there, word for word."""
    from bldclab.analysis.compare import compare
    from bldclab.errors import PlausibilityWarning

    rc, out, err = run_main(capsys, "check", str(DRONE))
    assert rc == 0
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("bldclab: warning: at 0.98 Omega_0 (bldclab compare's top speed): ")
    finding = lines[0].split("top speed): ", 1)[1]
    assert finding.startswith("inverter.f_pwm: f_pwm = 4.8e+04 Hz gives 8.97 PWM periods per electrical period")
    with pytest.warns(PlausibilityWarning):
        res = compare(bl.load(DRONE), [0.98], workers=1, base_speeds=False)
    assert any(w.endswith(finding) for w in res.warnings), res.warnings
    assert "sinusoidal back-EMF" in out  # paper 1's premises: the lines compare prints under its table
    rc, _, err = run_main(capsys, "check", "htm-48v")
    assert rc == 0 and err == ""  # 24 PWM periods per commutation: nothing to warn about


# ---------------------------------------------------------------------------------------------------------------
# compare's bottom line and figures, the comparison each command makes (issue 23, items 8 and 9)

def _pair(t_sine: float, t_square: float, eta_sine: float, eta_square: float) -> pd.DataFrame:
    rows = []
    for w in (0.2, 0.5, 0.8, 0.95):  # htm-48v: Omega_N = 640 rpm = 0.894 p.u.: three speeds in the rated range
        rows.append({"supply": "sine", "Omega_pu": w, "T_pu": t_sine if w < 0.9 else 0.1, "eta": eta_sine})
        rows.append({"supply": "square", "Omega_pu": w, "T_pu": t_square if w < 0.9 else 0.5, "eta": eta_square})
    return pd.DataFrame(rows)


@pytest.mark.parametrize(("numbers", "line"), [
    ((1.05, 1.0, 0.90, 0.88), "5.0 % more torque with sinusoidal supply at equal rms current, at 2.0 percentage "
                              "points better efficiency"),
    ((1.0, 1.1, 0.90, 0.88), "10.0 % more torque with square-wave supply at equal rms current, at 2.0 percentage "
                             "points worse efficiency"),
    ((1.0, 1.002, 0.90, 0.903), "the same torque with either supply (within 0.005 p.u.) at equal rms current, and "
                                "the same efficiency (within 0.5 percentage points)"),
])
def test_compare_bottom_line_is_computed_over_the_rated_range(numbers: tuple[float, ...], line: str) -> None:
    from bldclab.analysis.compare import bottom_line

    text = bottom_line(bl.load("htm-48v"), _pair(*numbers))
    assert text == f"bottom line: in its rated range (up to 0.89 p.u., 640 rpm: 3 speeds) this drive gives {line}"


def test_compare_prints_its_comparison_and_bottom_line_first(compare_htm48v: Path) -> None:
    from bldclab.analysis.compare import COMPARISON

    verdict = (compare_htm48v / "verdict.txt").read_text().splitlines()
    assert verdict[0].startswith("bottom line: in its rated range (up to 0.89 p.u., 640 rpm")
    assert "% more torque with sinusoidal supply at equal rms current" in verdict[0]
    assert all("rpm" in v for v in verdict if v.startswith("mean torque"))  # the detail names the speeds in rpm too
    page = (compare_htm48v / "report.html").read_text()
    assert "Comparison at equal current" in COMPARISON and COMPARISON in page and f"<b>{verdict[0]}</b>" in page


def test_compare_figures_are_in_rpm_and_n_m_with_closed_forms_named_or_left_out() -> None:
    """rpm and N m, per unit on the opposite axes; paper 1's curves labelled as closed forms, and not drawn for a
    sinusoidal back-EMF (outside their premises), with a note."""
    import warnings

    from bldclab.analysis.compare import compare
    from bldclab.report.bundle import torque_figure

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, closed in (("htm-48v", True), (str(DRONE), False)):
            drive = bl.load(name)
            fig = torque_figure(compare(drive, [0.3, 0.6], workers=1, base_speeds=False))
            ax = fig.axes[0]
            assert ax.get_xlabel() == "speed (rpm)" and ax.get_ylabel() == "torque (N m)"
            assert ax.get_xlim()[1] == pytest.approx(drive.Omega_0 * 30 / np.pi)
            labels = [ln.get_label() for ln in ax.get_lines()]
            points = [ln for ln in ax.get_lines() if ln.get_label().startswith("simulated, sinusoidal")]
            assert points[0].get_xdata()[0] == pytest.approx(0.3 * drive.Omega_0 * 30 / np.pi)
            secondary = ax.child_axes  # matplotlib's secondary axes: speed and torque in per unit
            assert any("per unit of" in a.get_xlabel() for a in secondary)
            assert any("per unit of" in a.get_ylabel() for a in secondary)
            closed_forms = [lab for lab in labels if lab.startswith("paper 1 closed form, ")]
            assert bool(closed_forms) == closed, labels
            notes = [t.get_text() for t in ax.texts]
            assert closed or any("closed forms not drawn" in t for t in notes)


def test_effmap_says_it_compares_at_equal_torque(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from bldclab.analysis.effmap import COMPARISON

    rc, out, _ = run_main(capsys, "effmap", "htm-48v", "--torques", "2", "--speeds", "2", "--workers", "1",
                          "--no-store", "--out", str(tmp_path / "m"))
    assert rc == 0 and out.splitlines()[1] == f"  {COMPARISON}"
    assert COMPARISON.startswith("Comparison at equal torque")


def test_compare_bottom_line_above_the_rated_speed_uses_every_speed() -> None:
    from bldclab.analysis.compare import bottom_line

    sim = _pair(1.05, 1.0, 0.90, 0.88)
    text = bottom_line(bl.load("htm-48v"), sim[sim.Omega_pu > 0.9])
    assert text.startswith("bottom line: over the speeds compared (all above the rated speed 0.89 p.u.) this drive "
                           "gives 400.0 % more torque with square-wave supply")


# ---------------------------------------------------------------------------------------------------------------
# did you mean; the cause first in composed errors (issue 23, item 13)

@pytest.mark.parametrize(("argv", "hint"), [
    (["simulate", "htm-48v", "--contrl", "sine"], "unrecognized arguments: --contrl sine: did you mean --control?"),
    (["simulate", "htm-48v", "--contrl=sine"], "did you mean --control?"),
    (["compare", "htm-48v", "--min-sped", "0.1", "--workrs", "2"],
     "did you mean --min-speed (for --min-sped), --workers (for --workrs)?"),
    (["simulat", "htm-48v"], "invalid choice: 'simulat': did you mean 'simulate'? (choose from"),
    (["torque-contrl", "lu-4kw"], "did you mean 'torque-control'?"),
    (["simulate", "htm-48v", "--control", "sinus"], "invalid choice: 'sinus': did you mean 'sine'?"),
    (["--vesion"], "did you mean --version?"),
])
def test_mistyped_options_and_commands_get_the_nearest_spelling(capsys: pytest.CaptureFixture[str], argv: list[str],
                                                                hint: str) -> None:
    rc, out, err = run_main(capsys, *argv)
    assert rc == 2 and out == "" and err.count("\n") == 1 and err.startswith("bldclab: error: ")
    assert hint in err, err


def test_no_suggestion_without_a_near_spelling(capsys: pytest.CaptureFixture[str]) -> None:
    rc, _, err = run_main(capsys, "simulate", "htm-48v", "--xyzzy", "1")
    assert rc == 2 and err == "bldclab: error: unrecognized arguments: --xyzzy 1\n"


def test_a_failed_run_names_its_cause_first(capsys: pytest.CaptureFixture[str]) -> None:
    """--speed 300 (rad/s) on htm-48v is 4 times Omega_0: the back-EMF drives the currents past the hardware trip.
    One line, the speed first, not a warning then an error about currents."""
    rc, out, err = run_main(capsys, "simulate", "htm-48v", "--speed", "300")
    assert rc == 2 and out == ""
    assert err.count("\n") == 1, err
    assert err.startswith("bldclab: error: scenario.speed: 300 rad/s (2865 rpm) is 4 times the no-load speed")
    assert "; the run then failed: result.currents: a phase current reached" in err
    with pytest.warns(bl.errors.PlausibilityWarning), pytest.raises(bl.errors.PlausibilityError) as info:  # the API
        bl.simulate(bl.load("htm-48v"), bl.SixStep(), bl.Scenario(duration=0.01, speed=300.0, ref=50.0))
    assert info.value.field == "scenario.speed" and "result.currents" in info.value.problem


def test_torque_control_warns_like_the_other_commands(capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 23, item 12: rect misses its torque on lu-4kw at 3000 rpm (96.5 %): the line starts bldclab: warning:."""
    rc, _, err = run_main(capsys, "torque-control", "lu-4kw", "--torques", "100%", "--speeds", "3000 rpm",
                          "--methods", "rect")
    assert rc == 0 and err
    assert all(line.startswith("bldclab: warning: ") for line in err.splitlines()), err
    assert "rect at 100 % of T_N, 3000 rpm: mean torque 96.5 % of the reference" in err


def test_template_keeps_an_existing_file_unless_forced(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`bldclab template --from my.toml --out my.toml` rewrote a user's hand-written file in SI numbers, its comments
    and unit strings gone; any existing --out file is kept (exit 2, untouched) unless --force."""
    mine = tmp_path / "my.toml"
    rc, _, _ = run_main(capsys, "template", "--from", "htm-48v", "--out", str(mine))
    hand = mine.read_text().replace("L = 7.5e-05", 'L = "75 uH"  # measured at 1 kHz')
    mine.write_text(hand)
    rc, out, err = run_main(capsys, "template", "--from", str(mine), "--out", str(mine))
    assert rc == 2 and out == ""
    assert "--out" in err and "exists, and is the --from file" in err and "--force" in err
    assert mine.read_text() == hand
    rc, _, err = run_main(capsys, "template", "--from", "lu-4kw", "--out", str(mine))
    assert rc == 2 and "exists: give another name, or --force" in err and mine.read_text() == hand
    rc, _, _ = run_main(capsys, "template", "--from", "lu-4kw", "--out", str(mine), "--force")
    assert rc == 0 and bl.load(mine) == bl.load("lu-4kw")

"""Back-EMF identification (bldclab.identify, ``bldclab identify``): round trips, checks, Hall errors, CLI."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path
from types import ModuleType

import numpy as np
import pandas as pd
import pytest

import bldclab
from bldclab import cli
from bldclab.analysis.identify import (
    Identification,
    identify,
    observable_emf,
    read_waveform,
    sample_path,
    synthetic_measurement,
    waveform_csv,
)
from bldclab.errors import BldclabError
from bldclab.model.emf import TWO_PI, BackEmf
from bldclab.model.motor import Drive

ROOT = Path(__file__).resolve().parents[1]
DEG = math.pi / 180.0
RPM = TWO_PI / 60.0
LU_SPEED = 1300.0 * RPM
HTM_SPEED = 400.0 * RPM
HEADER_LINES = 4  # comment lines at the top of the sample file


@pytest.fixture(scope="module")
def lu() -> Drive:
    return bldclab.load("lu-4kw")


@pytest.fixture(scope="module")
def sample() -> Identification:
    return identify(sample_path(), "1300 rpm", pole_pairs=2)


@pytest.fixture(scope="module")
def sample_lines() -> list[str]:
    return sample_path().read_text(encoding="utf-8").splitlines()


def errors(res: Identification, emf: BackEmf) -> list[float]:
    """Largest |k_identified - k_true| / max |k_true| per phase, k_true = the observable shapes."""
    ref, _ = observable_emf(emf, res.theta.size)
    out = []
    for x in range(3):
        k_true = np.asarray(ref.shapes[x].k)  # type: ignore[attr-defined]
        out.append(float(np.max(np.abs(res.k[x] - k_true)) / np.max(np.abs(k_true))))
    print("max |k_id - k_true| / peak per phase:", ", ".join(f"{100 * e:.3f} %" for e in out))
    return out


def write(tmp_path: Path, name: str, lines: list[str]) -> Path:
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return p


def edit_cell(lines: list[str], row: int, col: int, text: str) -> list[str]:
    """Return a copy with the cell (data row ``row``, column ``col``) replaced."""
    out = list(lines)
    j = HEADER_LINES + 1 + row
    cells = out[j].split(",")
    cells[col] = text
    out[j] = ",".join(cells)
    return out


def to_line_to_line(lines: list[str], keep: tuple[str, ...] = ("v_ab", "v_bc", "v_ca")) -> list[str]:
    """Return the sample file with its phase voltages replaced by line-to-line ones."""
    data = np.array([[float(c) for c in ln.split(",")] for ln in lines[HEADER_LINES + 1:]])
    t, va, vb, vc = data[:, 0], data[:, 1], data[:, 2], data[:, 3]
    cols = {"t": t, "v_ab": va - vb, "v_bc": vb - vc, "v_ca": vc - va}
    return waveform_csv({k: v for k, v in cols.items() if k == "t" or k in keep}).splitlines()


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_sample_waveform", ROOT / "tools" / "make_sample_waveform.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ----------------------------------------------------------------------------------------------------------
# round trips


def test_sample_file_is_what_the_tool_makes() -> None:
    assert _tool().render() == sample_path().read_text(encoding="utf-8")


def test_sample_file_reproduces_lu4kw(sample: Identification, lu: Drive) -> None:
    err = errors(sample, lu.motor.emf)
    assert max(err) < 0.01
    assert sample.warnings == ()
    assert sample.voltages == "phase"
    assert sample.samples == 3000
    assert sample.periods == pytest.approx(2.6, abs=0.01)
    assert sample.pole_pairs == 2
    assert sample.omega_e == pytest.approx(2 * LU_SPEED, rel=1e-4)
    assert sample.noise == pytest.approx(0.005 * 68.29 * math.sqrt(2 / 3), rel=0.1)  # common mode removed
    # zero common mode on the electrical angle: k_a(th) + k_b(th - 120) + k_c(th - 240) = 0
    n = sample.theta.size
    cm = sample.k[0] + np.roll(sample.k[1], n // 3) + np.roll(sample.k[2], 2 * n // 3)
    np.testing.assert_allclose(cm, 0.0, atol=1e-9)  # exact up to rounding


@pytest.mark.parametrize("points", [12, 72, 720])
def test_other_table_sizes(lu: Drive, points: int) -> None:
    res = identify(sample_path(), "1300 rpm", pole_pairs=2, points=points)
    assert res.k.shape == (3, points)
    assert max(errors(res, lu.motor.emf)) < 0.01


def test_comparison_needs_the_observable_frame(sample: Identification, lu: Drive) -> None:
    """The metric can fail: against the raw shapes (common mode kept, original frame) the error is large."""
    raw = lu.motor.emf.k_abc(sample.theta[None, :] + np.arange(3)[:, None] * TWO_PI / 3)
    raw_local = np.stack([raw[x, x] for x in range(3)])
    err = np.max(np.abs(sample.k - raw_local), axis=1) / np.max(np.abs(raw_local), axis=1)
    assert np.min(err) > 0.05
    _, delta = observable_emf(lu.motor.emf)
    assert delta / DEG == pytest.approx(-0.965, abs=0.01)


def test_identified_k_phi(sample: Identification, lu: Drive) -> None:
    assert sample.k_phi == pytest.approx(lu.motor.k_phi, rel=0.01)
    assert sample.drive(lu).motor.k_phi == pytest.approx(lu.motor.k_phi, rel=0.01)


def test_start_angle_and_perfect_halls(sample: Identification, lu: Drive) -> None:
    _, delta = observable_emf(lu.motor.emf)
    w_e = 2 * LU_SPEED
    expected = 1.0 + w_e * 10e-6 + delta  # theta0 of the simulation, half a 20 us sample later
    assert sample.theta_e0 == pytest.approx(expected, abs=0.1 * DEG)
    assert sample.hall is not None
    np.testing.assert_allclose(sample.hall.error, delta, atol=0.2 * DEG)  # ideal sensors, seen in the new frame
    assert sample.hall.invalid_codes == 0
    assert list(sample.hall.count) == [5, 6, 5]


@pytest.mark.parametrize("keep", [("v_ab", "v_bc", "v_ca"), ("v_ab", "v_bc"), ("v_bc", "v_ca")])
def test_line_to_line_columns_of_the_sample(tmp_path: Path, sample_lines: list[str], lu: Drive,
                                            sample: Identification, keep: tuple[str, ...]) -> None:
    res = identify(write(tmp_path, "ll.csv", to_line_to_line(sample_lines, keep)), "1300 rpm", pole_pairs=2)
    assert res.voltages == "line"
    assert max(errors(res, lu.motor.emf)) < 0.01
    np.testing.assert_allclose(res.k, sample.k, atol=1e-6 * np.max(np.abs(sample.k)))


def test_line_to_line_record_with_its_own_noise(lu: Drive) -> None:
    cols = synthetic_measurement(lu, LU_SPEED, line_to_line=True, seed=7)
    res = identify(cols, "1300 rpm", pole_pairs=2)
    assert max(errors(res, lu.motor.emf)) < 0.01
    assert res.warnings == ()
    bad = dict(cols, v_ca=1.2 * cols["v_ca"])  # a probe gain error: the three no longer sum to zero
    assert any("do not sum to zero" in w for w in identify(bad, "1300 rpm", pole_pairs=2).warnings)
    cols.pop("v_ca")
    res = identify(cols, "1300 rpm", pole_pairs=2)
    assert max(errors(res, lu.motor.emf)) < 0.01


def test_htm48v_ideal_trapezoid() -> None:
    htm = bldclab.load("htm-48v")
    cols = synthetic_measurement(htm, HTM_SPEED, f_sample=56e3, line_to_line=True, theta0=2.5, seed=3)
    res = identify(cols, "400 rpm", pole_pairs=8)
    assert max(errors(res, htm.motor.emf)) < 0.01
    assert res.k_phi == pytest.approx(0.32, rel=0.01)
    _, delta = observable_emf(htm.motor.emf)
    assert delta == pytest.approx(0.0, abs=1e-9)  # symmetric: the frames agree
    assert res.hall is not None
    np.testing.assert_allclose(res.hall.error, 0.0, atol=0.2 * DEG)
    assert res.warnings == ()


def test_analog_hall_levels_wrapped_angle_column_and_dataframe(lu: Drive) -> None:
    cols = synthetic_measurement(lu, LU_SPEED, hall_volts=3.3, seed=11)
    res = identify(pd.DataFrame(cols), "1300 rpm", pole_pairs=2)
    assert max(errors(res, lu.motor.emf)) < 0.01
    assert res.hall is not None and res.hall.spread.max() < 0.2 * DEG
    # an encoder angle instead of time, wrapped to [0, 2 pi), offset: the alignment does not care
    angle = np.mod(2 * LU_SPEED * (cols["t"] - cols["t"][0]) + 0.3, TWO_PI)
    res2 = identify({"Theta_e": angle, "Va": cols["v_a"], "Vb": cols["v_b"], "Vc": cols["v_c"]}, "1300 rpm")
    assert max(errors(res2, lu.motor.emf)) < 0.01
    assert math.isnan(res2.omega_e) and res2.pole_pairs is None


def test_speed_auto_and_units(lu: Drive, sample: Identification) -> None:
    res = identify(sample_path(), "auto", pole_pairs=2)
    assert res.speed_source == "auto"
    assert res.omega_m == pytest.approx(LU_SPEED, rel=1e-4)
    np.testing.assert_allclose(res.k, sample.k * LU_SPEED / res.omega_m, rtol=1e-12)
    res = identify(sample_path(), f"{LU_SPEED} rad/s")
    assert res.pole_pairs == 2  # implied by omega_e / omega_m
    with pytest.raises(BldclabError, match="'auto' needs the pole pairs"):
        identify(sample_path(), "auto")


def test_header_units_aliases_semicolons_and_comments(tmp_path: Path, sample: Identification) -> None:
    data = read_waveform(sample_path())
    assert data.t is not None
    text = ["# exported by a scope", "Time [ms];V_AN (mV);VBN;vcn;Hall1;HALL_2;h3;probe"]
    for j in range(data.n):
        row = [f"{data.t[j] * 1e3:.9g}", f"{data.v[0, j] * 1e3:.9g}", f"{data.v[1, j]:.9g}",
               f"{data.v[2, j]:.9g}", *(str(int(h)) for h in data.hall[:, j]), "x"]  # type: ignore[index]
        text.append(";".join(row))
    res = identify(write(tmp_path, "scope.csv", text), "1300 rpm", pole_pairs=2)
    np.testing.assert_allclose(res.k, sample.k, atol=1e-6)
    assert res.columns["t"] == "Time [ms]"


# ----------------------------------------------------------------------------------------------------------
# Hall placement errors


def test_hall_placement_errors_are_measured(lu: Drive) -> None:
    hall_error = (2.0 * DEG, -1.5 * DEG, 0.5 * DEG)
    cols = synthetic_measurement(lu.replace(sensors__hall_error=hall_error), LU_SPEED, seed=5)
    res = identify(cols, "1300 rpm", pole_pairs=2)
    _, delta = observable_emf(lu.motor.emf)
    assert res.hall is not None
    measured = res.hall.error - delta
    print("Hall errors (deg):", measured / DEG)
    np.testing.assert_allclose(measured, hall_error, atol=0.15 * DEG)
    np.testing.assert_allclose(res.hall.rising - delta, hall_error, atol=0.2 * DEG)
    np.testing.assert_allclose(res.hall.falling - delta, hall_error, atol=0.2 * DEG)
    # written into the drive, the identified model switches where the rig does
    d = res.drive(lu, hall_error=True)
    np.testing.assert_allclose(d.sensors.hall_error, res.hall.error)


def test_miswired_hall_gives_a_warning(lu: Drive) -> None:
    cols = synthetic_measurement(lu, LU_SPEED)
    cols["h_a"], cols["h_b"] = cols["h_b"], cols["h_a"]
    res = identify(cols, "1300 rpm", pole_pairs=2)
    assert any("Hall sensor a" in w and "wiring order" in w for w in res.warnings)
    with pytest.raises(BldclabError, match="30 deg"):
        res.drive(lu, hall_error=True)


# ----------------------------------------------------------------------------------------------------------
# checks: errors


@pytest.mark.parametrize(("cell", "needle"), [("", "empty cell: missing sample"), ("NaN", "is 'NaN': missing"),
                                              ("nan", "is 'nan': missing"), ("inf", "not a finite number"),
                                              ("1.2.3", "cannot read a number")])
def test_hole_names_column_and_line(tmp_path: Path, sample_lines: list[str], cell: str, needle: str) -> None:
    p = write(tmp_path, "hole.csv", edit_cell(sample_lines, 100, 2, cell))
    with pytest.raises(BldclabError) as exc:
        identify(p, "1300 rpm")
    assert exc.value.field == f"column v_b, line {HEADER_LINES + 2 + 100}"
    assert needle in exc.value.problem
    assert str(p) in str(exc.value)


def test_short_row_and_array_holes(tmp_path: Path, sample_lines: list[str]) -> None:
    lines = list(sample_lines)
    lines[HEADER_LINES + 1 + 50] = ",".join(lines[HEADER_LINES + 1 + 50].split(",")[:3])
    with pytest.raises(BldclabError, match=r"column v_c, line 56: empty cell"):
        identify(write(tmp_path, "short.csv", lines), "1300 rpm")
    cols = synthetic_measurement(bldclab.load("lu-4kw"), LU_SPEED)
    cols["v_a"][17] = np.nan
    with pytest.raises(BldclabError, match=r"column v_a, row 17: is 'nan'"):
        identify(cols, "1300 rpm")


def test_wrong_speed_states_both_periods(lu: Drive) -> None:
    with pytest.raises(BldclabError) as exc:
        identify(sample_path(), "1400 rpm", pole_pairs=2)
    msg = str(exc.value)
    assert exc.value.field == "speed"
    assert "23.07" in msg and "21.42" in msg and "1400 rpm" in msg and "differ by -7.1" in msg
    with pytest.raises(BldclabError, match=r"p = 1\.857 pole pairs, not a whole number"):
        identify(sample_path(), "1400 rpm")
    res = identify(sample_path(), "1310 rpm", pole_pairs=2)  # within 2 %: warning, scaled with the given speed
    assert len(res.warnings) == 1 and "differ by -0.76" in res.warnings[0]


@pytest.mark.parametrize("header", ["t,v_a,v_c,v_b,h_a,h_b,h_c", "t,v_b,v_a,v_c,h_a,h_b,h_c"])
def test_swapped_phases(tmp_path: Path, sample_lines: list[str], header: str) -> None:
    lines = list(sample_lines)
    lines[HEADER_LINES] = header
    with pytest.raises(BldclabError) as exc:
        identify(write(tmp_path, "swap.csv", lines), "1300 rpm", pole_pairs=2)
    assert exc.value.field == "phases"
    assert "phases b and c appear swapped" in exc.value.problem


def test_swapped_line_to_line_columns(tmp_path: Path, sample_lines: list[str]) -> None:
    lines = to_line_to_line(sample_lines)
    lines[0] = "t,v_ac,v_cb,v_ba"  # the same columns named the other way round: a reversed sequence
    with pytest.raises(BldclabError, match="phases b and c appear swapped"):
        identify(write(tmp_path, "llswap.csv", lines), "1300 rpm")


def test_non_monotonic_time(tmp_path: Path, sample_lines: list[str]) -> None:
    lines = list(sample_lines)
    j = HEADER_LINES + 1 + 200
    lines[j], lines[j + 1] = lines[j + 1], lines[j]
    with pytest.raises(BldclabError) as exc:
        identify(write(tmp_path, "order.csv", lines), "1300 rpm")
    assert exc.value.field == f"column t, line {j + 2}"
    assert "time does not increase" in exc.value.problem
    lines = list(sample_lines)
    lines[j + 1] = lines[j]
    with pytest.raises(BldclabError, match="time does not increase"):
        identify(write(tmp_path, "repeat.csv", lines), "1300 rpm")


def test_too_short_and_too_sparse(tmp_path: Path, sample_lines: list[str], lu: Drive) -> None:
    with pytest.raises(BldclabError, match=r"covers only 0\.[89]\d* electrical periods"):
        identify(synthetic_measurement(lu, LU_SPEED, periods=0.9), "1300 rpm")
    with pytest.raises(BldclabError, match="covers only"):
        identify(write(tmp_path, "short.csv", sample_lines[:HEADER_LINES + 1 + 1000]), "1300 rpm")
    sparse = sample_lines[:HEADER_LINES + 1] + sample_lines[HEADER_LINES + 1::40]
    with pytest.raises(BldclabError, match=r"only 29\.\d samples per electrical period \(needs at least 36\)"):
        identify(write(tmp_path, "sparse.csv", sparse), "1300 rpm")
    res = identify(synthetic_measurement(lu, LU_SPEED, periods=1.05), "1300 rpm", pole_pairs=2)
    assert max(errors(res, lu.motor.emf)) < 0.01  # one period is enough, just noisier


def test_column_problems(tmp_path: Path, sample_lines: list[str]) -> None:
    def with_header(h: str) -> Path:
        lines = list(sample_lines)
        lines[HEADER_LINES] = h
        return write(tmp_path, "cols.csv", lines)

    with pytest.raises(BldclabError, match="needs the phase voltages v_a, v_b, v_c or two of"):
        identify(with_header("t,v_a,v_b,x,h_a,h_b,h_c"), "1300 rpm")
    with pytest.raises(BldclabError, match="needs a time column 't'"):
        identify(with_header("time_s,v_a,v_b,v_c,h_a,h_b,h_c"), "1300 rpm")
    with pytest.raises(BldclabError, match="column V_A: gives the same quantity"):
        identify(with_header("t,v_a,v_b,V_A,h_a,h_b,h_c"), "1300 rpm")
    with pytest.raises(BldclabError, match="not h_c: give all three Hall signals or none"):
        identify(with_header("t,v_a,v_b,v_c,h_a,h_b,x"), "1300 rpm")
    stuck = list(sample_lines)
    for j in range(HEADER_LINES + 1, len(stuck)):
        cells = stuck[j].split(",")
        cells[5] = "1"
        stuck[j] = ",".join(cells)
    with pytest.raises(BldclabError, match="column h_b: never changes"):
        identify(write(tmp_path, "stuck.csv", stuck), "1300 rpm")
    with pytest.raises(BldclabError, match="points: must be a whole number >= 12 and a multiple of 3"):
        identify(sample_path(), "1300 rpm", points=100)


def test_phase_spacing_warning_and_error(lu: Drive) -> None:
    def shifted(deg: float) -> dict[str, np.ndarray]:
        cols = synthetic_measurement(lu, LU_SPEED, periods=3.0)
        cols["v_b"] = np.interp(cols["t"] + deg * DEG / (2 * LU_SPEED), cols["t"], cols["v_b"])
        return {k: v[:2900] for k, v in cols.items()}

    res = identify(shifted(20.0), "1300 rpm", pole_pairs=2)
    assert any("phase b's fundamental is +1" in w and "more than 5 deg" in w for w in res.warnings)
    with pytest.raises(BldclabError) as exc:
        identify(shifted(45.0), "1300 rpm", pole_pairs=2)
    assert exc.value.field == "phases"
    assert "from its place 120 deg behind phase a (tolerance 20 deg)" in exc.value.problem


def test_half_wave_asymmetry_and_offset_warnings(lu: Drive, sample: Identification) -> None:
    assert np.all(sample.asymmetry < 0.01)
    cols = synthetic_measurement(lu, LU_SPEED)
    cols["v_a"] = cols["v_a"] + 4.0 * np.cos(4 * LU_SPEED * cols["t"]) + 3.0
    res = identify(cols, "1300 rpm", pole_pairs=2)
    assert res.asymmetry[0] > 0.03
    assert any("phase a is not half-wave antisymmetric" in w for w in res.warnings)
    assert any("phase a had a mean of 2" in w and "probe offset" in w for w in res.warnings)
    assert res.offsets[0] == pytest.approx(2.0, abs=0.05)  # the common third went with the common mode


# ----------------------------------------------------------------------------------------------------------
# the command line


def test_cli_writes_a_drive_that_loads_and_simulates(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                     lu: Drive) -> None:
    out = tmp_path / "sub" / "lu-id.toml"
    rc = cli.main(["identify", str(sample_path()), "--speed", "1300 rpm", "--base", "lu-4kw", "--out", str(out),
                   "--set-hall-error"])
    stdout, stderr = capsys.readouterr()
    assert rc == 0, stderr
    assert stderr == ""
    assert "k_phi" in stdout and f"wrote {out}" in stdout
    assert list(out.parent.iterdir()) == [out]  # no temporary file left
    d = Drive.from_toml(out)
    assert d.name == "lu-id"
    assert d.motor.p == 2 and d.motor.R == lu.motor.R and d.inverter == lu.inverter
    assert d.motor.k_phi == pytest.approx(lu.motor.k_phi, rel=0.01)
    assert "kind = \"table\"" in out.read_text() and "k_c = [" in out.read_text()
    _, delta = observable_emf(lu.motor.emf)
    np.testing.assert_allclose(d.sensors.hall_error, delta, atol=0.2 * DEG)
    # the identified drive's line-to-line back-EMF is the original's (same rotor position: frame shift delta)
    T_e = TWO_PI / (2 * LU_SPEED)
    off = bldclab.OpenLoop(np.zeros((1, 3), dtype=int), np.zeros((1, 3)))
    a = bldclab.simulate(lu, off, bldclab.Scenario(duration=T_e, speed=LU_SPEED, theta0=0.3)).signals
    b = bldclab.simulate(d, off, bldclab.Scenario(duration=T_e, speed=LU_SPEED, theta0=0.3 + delta)).signals
    for x, y in (("a", "b"), ("b", "c"), ("c", "a")):
        ea, eb = a[f"e_{x}"] - a[f"e_{y}"], b[f"e_{x}"] - b[f"e_{y}"]
        assert np.max(np.abs(ea - eb)) < 0.01 * np.max(np.abs(ea))
    # and it runs a drive: paper 2's torque control on the identified shapes holds the rated torque
    res = bldclab.simulate(d, bldclab.Lu(),
                           bldclab.Scenario(duration=3 * T_e, speed=LU_SPEED, ref=d.T_N, window=(T_e, 3 * T_e)))
    assert res.metrics is not None and res.metrics.tau_mean == pytest.approx(d.T_N, rel=0.02)


def test_cli_json_and_warnings_on_stderr(capsys: pytest.CaptureFixture[str], sample: Identification) -> None:
    rc = cli.main(["identify", str(sample_path()), "--speed", "1310 rpm", "--pole-pairs", "2", "--format", "json",
                   "--points", "72"])
    stdout, stderr = capsys.readouterr()
    assert rc == 0
    doc = json.loads(stdout)
    assert len(doc["k_a"]) == 72 and doc["pole_pairs"] == 2 and doc["hall"]["count"] == [5, 6, 5]
    assert doc["speed_rpm"] == pytest.approx(1310.0)
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("bldclab: warning: the speed 1310 rpm")


@pytest.mark.parametrize(("argv", "needles"), [
    (["--speed", "1400 rpm", "--base", "lu-4kw"], ["speed:", "differ by -7.1", "1400 rpm"]),
    (["--speed", "1300 rpm"], ["--out: needs --base"]),
    (["--speed", "1300 rpm", "--base", "htm-48v"], ["differ by"]),
    (["--speed", "1300 rpm", "--base", "lu-4kw", "--pole-pairs", "3"], ["--pole-pairs: 3 contradicts"]),
    (["--speed", "fast", "--base", "lu-4kw"], ["speed: cannot read a number in 'fast'"]),
    (["--speed", "1300 rpm", "--base", "lu-4kw", "--points", "100"], ["points: must be"]),
])
def test_cli_errors_write_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str],
                                  needles: list[str]) -> None:
    out = tmp_path / "m.toml"
    rc = cli.main(["identify", str(sample_path()), *argv, "--out", str(out)])
    _, stderr = capsys.readouterr()
    assert rc == 2
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("bldclab: error: "), stderr
    for n in needles:
        assert n in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_cli_bad_file_keeps_an_existing_output(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                               sample_lines: list[str]) -> None:
    out = tmp_path / "m.toml"
    out.write_text("old")
    bad = write(tmp_path, "bad.csv", edit_cell(sample_lines, 2000, 3, "NaN"))
    rc = cli.main(["identify", str(bad), "--speed", "1300 rpm", "--base", "lu-4kw", "--out", str(out)])
    _, stderr = capsys.readouterr()
    assert rc == 2
    assert f"column v_c, line {HEADER_LINES + 2 + 2000}" in stderr
    assert out.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "m.toml"]


def test_unevenly_sampled_noisy_record_has_no_leverage_spikes():
    """A scope export with jittered time stamps (1500 samples at uniform random times over 4 electrical periods),
    0.7 % noise, 5th and 7th harmonics and a common offset. Where the default window's four samples bunched at one
    end, the local line extrapolated the noise (intercept variance up to 59 times one sample's): an 8 % spike of the
    peak and a false half-wave-asymmetry warning. The table must stay within 2 % of the true shape (noise per
    sample 0.6 % of the peak) and raise no warning."""
    rng = np.random.default_rng(3)
    p, wm, k1 = 4, 1500 * math.pi / 30, 0.35
    t = np.sort(rng.uniform(0.0, 4 * TWO_PI / (p * wm), 1500))

    def shape(th):
        return k1 * (np.sin(th) + 0.04 * np.sin(5 * th) + 0.02 * np.sin(7 * th + 0.3))

    cols = {f"v_{x}": wm * shape(p * wm * t - j * TWO_PI / 3) + 1.7 + rng.normal(0.0, 0.4, t.size)
            for j, x in enumerate("abc")}
    res = identify({"t": t, **cols}, "1500 rpm", pole_pairs=p)
    assert not res.warnings
    for j in range(3):  # local grids: phase x's table is the shape of its local angle
        err = np.max(np.abs(res.k[j] - shape(res.theta)))
        assert err < 0.02 * k1, (j, err / k1)


def test_a_mechanical_angle_column_is_named_as_such():
    """A shaft encoder's angle (one revolution, 0-360 deg) given as `theta` for a 4-pole-pair motor: the voltages
    make 4 periods while the column makes one. It was refused as `covers only 1 electrical periods: record at least
    one whole period`; the error must say the column reads as a mechanical angle, with the pole pairs it implies."""
    p = 4
    theta_m = np.linspace(0.0, TWO_PI, 2000, endpoint=False)
    cols = {f"v_{x}": 50.0 * np.sin(p * theta_m - j * TWO_PI / 3) for j, x in enumerate("abc")}
    with pytest.raises(BldclabError) as info:
        identify({"theta": theta_m, **cols}, "1500 rpm", pole_pairs=p)
    assert info.value.field == "column theta"
    assert "go through 4 periods" in info.value.problem and "mechanical angle" in info.value.problem
    assert "4 pole pairs" in info.value.problem and "theta_e = p theta_m" in info.value.problem
    res = identify({"theta": p * theta_m, **cols}, "1500 rpm", pole_pairs=p)  # the electrical angle: accepted
    assert np.max(np.abs(res.k[0] - 50.0 / (1500 * math.pi / 30) * np.sin(res.theta))) < 1e-3


def test_report_shows_a_start_just_before_zero_as_a_small_negative_angle():
    """A record starting a hair before phase a's zero crossing has theta_e0 = 2 pi - 1e-4 rad; the report printed
    `theta_e at start   360 deg`, the same as 0 but read as a full turn. It shows the signed angle."""
    theta = np.linspace(-1e-4, 3 * TWO_PI, 3000)
    cols = {f"v_{x}": 10.0 * np.sin(theta - j * TWO_PI / 3) for j, x in enumerate("abc")}
    res = identify({"theta": theta, **cols}, "1000 rpm", pole_pairs=2)
    assert res.theta_e0 > 6.28
    line = next(ln for ln in res.report().splitlines() if "theta_e at start" in ln)
    assert float(line.split()[-2]) == pytest.approx(-1e-4 / (math.pi / 180), abs=2e-3)


def test_an_angle_column_in_degrees_that_steps_back_is_reported_in_degrees_too(tmp_path: Path):
    """A `theta (deg)` column stepping back from 99 to 0 deg was reported only in radians (1.728 and 0)."""
    f = tmp_path / "rec.csv"
    th = np.arange(0.0, 720.0, 1.0)
    th[100:120] -= 100.0
    rows = "\n".join(f"{t},{10 * math.sin(math.radians(t))},{10 * math.sin(math.radians(t) - 2.0944)}" for t in th)
    f.write_text("theta (deg),v_ab,v_bc\n" + rows + "\n")
    with pytest.raises(BldclabError) as info:
        identify(f, "1000 rpm", pole_pairs=2)
    assert "(0 deg) after" in info.value.problem and "(99 deg)" in info.value.problem

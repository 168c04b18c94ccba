"""The drive data model (bldclab.motor), unit strings (bldclab.units) and TOML motor files.

Physics checks (k_phi, Fourier coefficients, phase shifts) use closed forms; file checks use a valid
base file that the bad-input matrix breaks one field at a time.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bldclab.errors import BldclabError
from bldclab.model import catalog
from bldclab.model.emf import TWO_PI, BackEmf, Cogging, Fourier, Sinusoid, Table, Trapezoid
from bldclab.model.iron import M270_35A
from bldclab.model.motor import Drive, Inverter, Mechanics, Motor, Sensors
from bldclab.model.units import ALIASES, DIMENSIONS, to_si

RPM = TWO_PI / 60.0

# ----------------------------------------------------------------------------------------------------------
# a valid file, and the ways to break it

BASE = """\
name = "matrix"
description = "a valid drive that the bad-input matrix breaks one field at a time"

[motor]
p = 8
R = "50 mOhm"
L = "75 uH"
V_N = "48 V"
I_N = "50 A"
Omega_N = "640 rpm"

[motor.emf]
kind = "trapezoid"
k_phi = "0.32 V s/rad"
flat_top = "120 deg"

[inverter]
V_dc = "48 V"
f_pwm = "14 kHz"
t_dead = "1 us"

[mechanics]
J = "0.05 kg m^2"
B = 0.002
tau_c = 0.2

[sensors]
current_phases = "ab"
current_gain = [1.0, 1.0, 1.0]
"""

TRAPEZOID_EMF = """\
[motor.emf]
kind = "trapezoid"
k_phi = "0.32 V s/rad"
flat_top = "120 deg"
"""

# an ideal 120-degree trapezoid of flat top 0.32 V s/rad, written as a measured table in degrees
TABLE_EMF = """\
[motor.emf]
kind = "table"
theta_unit = "deg"
theta = [0, 30, 150, 180, 210, 330]
k = [0.0, 0.32, 0.32, 0.0, -0.32, -0.32]
"""

PHASE_TABLE_EMF = """\
[motor.emf]
kind = "table"
theta_unit = "deg"
theta = [0, 30, 150, 180, 210, 330]
k_a = [0.0, 0.32, 0.32, 0.0, -0.32, -0.32]
k_b = [0.0, 0.31, 0.31, 0.0, -0.31, -0.31]
k_c = [0.0, 0.33, 0.33, 0.0, -0.33, -0.33]
"""

PHASE_ARRAY_EMF = """\
[[motor.emf.phase]]
kind = "trapezoid"
k_phi = 0.32

[[motor.emf.phase]]
kind = "sinusoid"
k_1 = 0.37

[[motor.emf.phase]]
kind = "fourier"
a = [0.0, 0.0, 0.0, 0.0]
b = [0.0, 0.38, 0.0, 0.02]
"""

FOURIER_EMF = """\
[motor.emf]
kind = "fourier"
unit = "V s/rad"
a = [0.0, 0.0, 0.0, 0.0]
b = [0.0, 0.38, 0.0, 0.02]
"""

COGGING = """
[motor.cogging]
orders = [24, 48]
amplitudes = [0.3, 0.05]
phases = [0.0, 1.0]
"""


def edited(text: str, edits: list[tuple[str, str]]) -> str:
    """Apply exact, single-occurrence replacements (a failing replacement fails the test)."""
    for old, new in edits:
        assert text.count(old) == 1, f"edit target {old!r} occurs {text.count(old)} times"
        text = text.replace(old, new)
    return text


def with_emf(emf: str) -> str:
    return edited(BASE, [(TRAPEZOID_EMF, emf)])


def write(tmp_path: Path, text: str, name: str = "motor.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("emf", [TRAPEZOID_EMF, TABLE_EMF, PHASE_TABLE_EMF, PHASE_ARRAY_EMF, FOURIER_EMF],
                         ids=["trapezoid", "table", "phase-table", "phase-array", "fourier"])
def test_base_files_are_valid(tmp_path: Path, emf: str) -> None:
    drive = Drive.from_toml(write(tmp_path, with_emf(emf) + COGGING))
    assert drive.name == "matrix"
    assert drive.motor.cogging is not None
    assert drive.motor.cogging.orders == (24, 48)


def test_base_file_values_in_si(tmp_path: Path) -> None:
    d = Drive.from_toml(write(tmp_path, BASE))
    assert d.motor.p == 8
    assert d.motor.R == pytest.approx(0.05, rel=1e-15)
    assert d.motor.L == pytest.approx(75e-6, rel=1e-15)
    assert d.motor.Omega_N == pytest.approx(640 * RPM, rel=1e-15)
    assert d.motor.emf.shapes[0] == Trapezoid(0.32, to_si("120 deg", "angle", "x"))
    assert d.inverter.f_pwm == 14e3
    assert d.inverter.t_dead == pytest.approx(1e-6, rel=1e-15)
    assert d.mechanics.J == 0.05
    assert d.sensors == Sensors(current_phases="ab")


def test_table_file_reads_degrees_and_per_phase_columns(tmp_path: Path) -> None:
    d = Drive.from_toml(write(tmp_path, with_emf(PHASE_TABLE_EMF)))
    a, b, c = d.motor.emf.shapes
    assert isinstance(a, Table)
    assert a.theta == pytest.approx(np.radians([0, 30, 150, 180, 210, 330]), rel=1e-15)
    assert (max(a.k), max(b.k), max(c.k)) == (0.32, 0.31, 0.33)  # type: ignore[attr-defined]
    assert not d.motor.emf.is_symmetric


def test_phase_array_file_gives_three_kinds(tmp_path: Path) -> None:
    d = Drive.from_toml(write(tmp_path, with_emf(PHASE_ARRAY_EMF)))
    assert [type(s) for s in d.motor.emf.shapes] == [Trapezoid, Sinusoid, Fourier]
    assert d.motor.emf.shapes[2] == Fourier((0.0, 0.0, 0.0, 0.0), (0.0, 0.38, 0.0, 0.02))


def test_table_units_scale_values(tmp_path: Path) -> None:
    emf = edited(TABLE_EMF, [('theta_unit = "deg"\n', 'theta_unit = "deg"\nunit = "N m/A"\n')])
    d = Drive.from_toml(write(tmp_path, with_emf(emf)))
    assert d.motor.k_phi == pytest.approx(0.32, rel=1e-12)


# (base emf, edits, expected field, words the message must contain)
BAD_FILES = [
    # missing
    pytest.param(None, [('L = "75 uH"\n', "")], "motor.L", "missing", id="missing-L"),
    pytest.param(None, [("p = 8\n", "")], "motor.p", "missing", id="missing-p"),
    pytest.param(None, [('k_phi = "0.32 V s/rad"\n', "")], "motor.emf.k_phi", "missing", id="missing-k_phi"),
    pytest.param(None, [('kind = "trapezoid"\n', "")], "motor.emf.kind", "missing", id="missing-kind"),
    pytest.param(None, [(TRAPEZOID_EMF, "")], "motor.emf", "missing", id="missing-emf"),
    pytest.param(None, [('[inverter]\nV_dc = "48 V"\nf_pwm = "14 kHz"\nt_dead = "1 us"\n', "")], "inverter",
                 "missing", id="missing-inverter"),
    pytest.param(None, [('f_pwm = "14 kHz"\n', "")], "inverter.f_pwm", "missing", id="missing-f_pwm"),
    pytest.param(None, [('J = "0.05 kg m^2"\n', "")], "mechanics.J", "missing", id="missing-J"),
    pytest.param(TABLE_EMF, [("theta = [0, 30, 150, 180, 210, 330]\n", "")], "motor.emf.theta", "missing",
                 id="missing-theta"),
    pytest.param(PHASE_TABLE_EMF, [("k_b = [0.0, 0.31, 0.31, 0.0, -0.31, -0.31]\n", "")], "motor.emf.k_b",
                 "missing", id="missing-k_b"),
    # negative
    pytest.param(None, [('R = "50 mOhm"', "R = -0.05")], "motor.R", ">= 0", id="negative-R"),
    pytest.param(None, [('L = "75 uH"', 'L = "-75 uH"')], "motor.L", "> 0", id="negative-L"),
    pytest.param(None, [('V_dc = "48 V"', "V_dc = -48")], "inverter.V_dc", "> 0", id="negative-V_dc"),
    pytest.param(None, [('J = "0.05 kg m^2"', "J = -1e-3")], "mechanics.J", "> 0", id="negative-J"),
    pytest.param(None, [("B = 0.002", "B = -0.002")], "mechanics.B", ">= 0", id="negative-B"),
    pytest.param(None, [("tau_c = 0.2", "tau_c = -0.2")], "mechanics.tau_c", ">= 0", id="negative-tau_c"),
    pytest.param(None, [('k_phi = "0.32 V s/rad"', "k_phi = -0.32")], "motor.emf.k_phi", "> 0",
                 id="negative-k_phi"),
    pytest.param(None, [('t_dead = "1 us"', 't_dead = "-1 us"')], "inverter.t_dead", ">= 0",
                 id="negative-t_dead"),
    pytest.param(None, [('Omega_N = "640 rpm"', 'Omega_N = "-640 rpm"')], "motor.Omega_N", "> 0",
                 id="negative-Omega_N"),
    pytest.param(None, [('flat_top = "120 deg"', 'flat_top = "-1 deg"')], "motor.emf.flat_top", ">= 0",
                 id="negative-flat_top"),
    # zero
    pytest.param(None, [('L = "75 uH"', "L = 0")], "motor.L", "> 0", id="zero-L"),
    pytest.param(None, [('I_N = "50 A"', "I_N = 0.0")], "motor.I_N", "> 0", id="zero-I_N"),
    pytest.param(None, [('V_N = "48 V"', 'V_N = "0 V"')], "motor.V_N", "> 0", id="zero-V_N"),
    pytest.param(None, [('f_pwm = "14 kHz"', "f_pwm = 0")], "inverter.f_pwm", "> 0", id="zero-f_pwm"),
    pytest.param(None, [('J = "0.05 kg m^2"', "J = 0")], "mechanics.J", "> 0", id="zero-J"),
    pytest.param(None, [('k_phi = "0.32 V s/rad"', "k_phi = 0")], "motor.emf.k_phi", "> 0", id="zero-k_phi"),
    pytest.param(None, [("p = 8", "p = 0")], "motor.p", ">= 1", id="zero-p"),
    # NaN (TOML has nan)
    pytest.param(None, [('L = "75 uH"', "L = nan")], "motor.L", "NaN", id="nan-L"),
    pytest.param(None, [('R = "50 mOhm"', "R = nan")], "motor.R", "NaN", id="nan-R"),
    pytest.param(None, [('V_dc = "48 V"', "V_dc = nan")], "inverter.V_dc", "NaN", id="nan-V_dc"),
    pytest.param(None, [('k_phi = "0.32 V s/rad"', "k_phi = nan")], "motor.emf.k_phi", "NaN", id="nan-k_phi"),
    pytest.param(None, [('flat_top = "120 deg"', "flat_top = nan")], "motor.emf.flat_top", "NaN",
                 id="nan-flat_top"),
    pytest.param(None, [("tau_c = 0.2", "tau_c = nan")], "mechanics.tau_c", "NaN", id="nan-tau_c"),
    pytest.param(None, [("current_gain = [1.0, 1.0, 1.0]", "current_gain = [1.0, nan, 1.0]")],
                 "sensors.current_gain[1]", "NaN", id="nan-current_gain"),
    pytest.param(TABLE_EMF, [("k = [0.0, 0.32,", "k = [0.0, nan,")], "motor.emf.k", "entry 1",
                 id="nan-table"),
    # infinite
    pytest.param(None, [('L = "75 uH"', "L = inf")], "motor.L", "infinite", id="inf-L"),
    pytest.param(None, [('V_N = "48 V"', "V_N = -inf")], "motor.V_N", "infinite", id="inf-V_N"),
    pytest.param(None, [('f_pwm = "14 kHz"', "f_pwm = inf")], "inverter.f_pwm", "infinite", id="inf-f_pwm"),
    pytest.param(None, [('J = "0.05 kg m^2"', "J = inf")], "mechanics.J", "infinite", id="inf-J"),
    pytest.param(None, [('Omega_N = "640 rpm"', 'Omega_N = "1e999 rpm"')], "motor.Omega_N", "infinite",
                 id="inf-overflow"),
    pytest.param(TABLE_EMF, [("k = [0.0, 0.32, 0.32,", "k = [0.0, 0.32, inf,")], "motor.emf.k", "entry 2",
                 id="inf-table"),
    # mistyped
    pytest.param(None, [('L = "75 uH"', 'L = "abc"')], "motor.L", "cannot read a number", id="string-L"),
    pytest.param(None, [('L = "75 uH"', "L = true")], "motor.L", "boolean", id="bool-L"),
    pytest.param(None, [('L = "75 uH"', "L = [75e-6]")], "motor.L", "expected a number", id="list-L"),
    pytest.param(None, [('L = "75 uH"', "L = { value = 75e-6 }")], "motor.L", "expected a number",
                 id="table-L"),
    pytest.param(None, [("p = 8", "p = 8.0")], "motor.p", "integer", id="float-p"),
    pytest.param(None, [("p = 8", 'p = "8"')], "motor.p", "integer", id="string-p"),
    pytest.param(None, [("p = 8", "p = true")], "motor.p", "integer", id="bool-p"),
    pytest.param(None, [('kind = "trapezoid"', "kind = 3")], "motor.emf.kind", "string", id="int-kind"),
    pytest.param(None, [('current_phases = "ab"', "current_phases = 12")], "sensors.current_phases", "string",
                 id="int-current_phases"),
    pytest.param(None, [('current_phases = "ab"', 'current_phases = ["a", "b"]')], "sensors.current_phases",
                 "string", id="list-current_phases"),
    pytest.param(None, [("current_gain = [1.0, 1.0, 1.0]", "current_gain = 1.0")], "sensors.current_gain",
                 "three", id="scalar-current_gain"),
    pytest.param(None, [('name = "matrix"', "name = 5")], "name", "string", id="int-name"),
    pytest.param(TABLE_EMF, [("theta = [0, 30, 150, 180, 210, 330]", 'theta = "0 30 150 180 210 330"')],
                 "motor.emf.theta", "list", id="string-theta"),
    pytest.param(TABLE_EMF, [("theta = [0, 30,", 'theta = [0, "30 deg",')], "motor.emf.theta", "entry 1",
                 id="unit-in-theta-list"),
    pytest.param(TABLE_EMF, [("k = [0.0, 0.32,", "k = [0.0, true,")], "motor.emf.k", "entry 1",
                 id="bool-in-table"),
    pytest.param(None, [("[motor.emf]\n", "[motor.emf]\nphase = 3\n")], "motor.emf.phase", "three",
                 id="scalar-phase"),
    # wrong unit for the field
    pytest.param(None, [('Omega_N = "640 rpm"', 'Omega_N = "640 V"')], "motor.Omega_N", "not a unit of speed",
                 id="unit-speed"),
    pytest.param(None, [('L = "75 uH"', 'L = "75 uOhm"')], "motor.L", "not a unit of inductance",
                 id="unit-inductance"),
    pytest.param(None, [('R = "50 mOhm"', 'R = "50 mH"')], "motor.R", "not a unit of resistance",
                 id="unit-resistance"),
    pytest.param(None, [('flat_top = "120 deg"', 'flat_top = "120 rpm"')], "motor.emf.flat_top",
                 "not a unit of angle", id="unit-angle"),
    pytest.param(None, [('k_phi = "0.32 V s/rad"', 'k_phi = "0.32 V"')], "motor.emf.k_phi",
                 "not a unit of emf constant", id="unit-emf"),
    pytest.param(None, [('f_pwm = "14 kHz"', 'f_pwm = "14 kV"')], "inverter.f_pwm", "not a unit of frequency",
                 id="unit-frequency"),
    pytest.param(None, [('t_dead = "1 us"', 't_dead = "1 uF"')], "inverter.t_dead", "not a unit of time",
                 id="unit-time"),
    pytest.param(None, [('J = "0.05 kg m^2"', 'J = "0.05 kg"')], "mechanics.J", "not a unit of inertia",
                 id="unit-inertia"),
    pytest.param(TABLE_EMF, [('theta_unit = "deg"', 'theta_unit = "V"')], "motor.emf.theta_unit",
                 "not a unit of angle", id="unit-theta_unit"),
    pytest.param(TABLE_EMF, [('theta_unit = "deg"\n', 'theta_unit = "deg"\nunit = "rad"\n')],
                 "motor.emf.unit",
                 "not a unit of emf constant", id="unit-table-unit"),
    pytest.param(None, [('V_N = "48 V"', 'V_N = "48 volts"')], "motor.V_N", "not a unit of voltage",
                 id="unit-unknown"),
    # unknown shape kind
    pytest.param(None, [('kind = "trapezoid"', 'kind = "trapezium"')], "motor.emf.kind", "unknown shape",
                 id="kind-misspelt"),
    pytest.param(None, [('kind = "trapezoid"', 'kind = "Trapezoid"')], "motor.emf.kind", "unknown shape",
                 id="kind-case"),
    pytest.param(PHASE_ARRAY_EMF, [('kind = "sinusoid"', 'kind = "sine"')], "motor.emf.phase[1].kind",
                 "unknown shape", id="kind-in-phase-array"),
    # unknown (misspelt) key
    pytest.param(None, [("p = 8\n", "p = 8\nLl = 1\n")], "motor.Ll", "unknown field", id="key-motor"),
    pytest.param(None, [('flat_top = "120 deg"', 'flat_tops = "120 deg"')], "motor.emf.flat_tops",
                 "unknown field", id="key-emf"),
    pytest.param(None, [('t_dead = "1 us"', 'tdead = "1 us"')], "inverter.tdead", "unknown field",
                 id="key-inverter"),
    pytest.param(None, [("B = 0.002", "b = 0.002")], "mechanics.b", "unknown field", id="key-mechanics"),
    pytest.param(None, [('current_phases = "ab"', 'current_phase = "ab"')], "sensors.current_phase",
                 "unknown field", id="key-sensors"),
    pytest.param(None, [('name = "matrix"', 'nmae = "matrix"')], "nmae", "unknown field", id="key-top"),
    pytest.param(None, [("[mechanics]", "[mechanic]\nJ = 1.0\n\n[mechanics]")], "mechanic", "unknown field",
                 id="key-section"),
    pytest.param(None, [('flat_top = "120 deg"\n', 'flat_top = "120 deg"\nunit = "V s/rad"\n')],
                 "motor.emf.unit", "unknown field", id="key-unit-on-trapezoid"),
    pytest.param(None, [('flat_top = "120 deg"\n', 'flat_top = "120 deg"\nk_a = [1.0, 2.0, 3.0]\n')],
                 "motor.emf.k_a", "unknown field", id="key-k_a-on-trapezoid"),
    pytest.param(TABLE_EMF, [("k = [", "k_a = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]\nk = [")], "motor.emf.k_a",
                 "unknown field", id="key-k-and-k_a"),
    pytest.param(PHASE_ARRAY_EMF, [("k_1 = 0.37\n", "k_1 = 0.37\nk1 = 0.37\n")], "motor.emf.phase[1].k1",
                 "unknown field", id="key-in-phase-array"),
    pytest.param(PHASE_ARRAY_EMF, [("[[motor.emf.phase]]\nkind = \"trapezoid\"",
                                    "[motor.emf]\nkind = \"table\"\n\n"
                                    "[[motor.emf.phase]]\nkind = \"trapezoid\"")],
                 "motor.emf.kind", "not allowed next to", id="key-kind-next-to-phases"),
    # table: angles not strictly increasing
    pytest.param(TABLE_EMF, [("theta = [0, 30, 150,", "theta = [0, 150, 30,")], "motor.emf.theta",
                 "strictly increasing", id="table-unsorted"),
    pytest.param(TABLE_EMF, [("theta = [0, 30, 150,", "theta = [0, 30, 30,")], "motor.emf.theta",
                 "strictly increasing", id="table-duplicate-angle"),
    # table in degrees: the error speaks the file's unit (it said "got [0, 8.37758] (write degrees with theta_unit =
    # \"deg\")" to a file that did, and "(0.523599 rad) follows 2.61799 rad" for 30 after 150)
    pytest.param(TABLE_EMF, [("theta = [0, 30, 150,", "theta = [0, 150, 30,")], "motor.emf.theta",
                 "entry 2 (30 deg) follows 150 deg", id="table-unsorted-in-deg"),
    pytest.param(TABLE_EMF, [("180, 210, 330]", "180, 210, 480]")], "motor.emf.theta",
                 "angles must lie in [0, 360) deg, one electrical period (theta_e = p theta_m), got [0, 480] deg",
                 id="table-beyond-360-deg"),
    pytest.param(TABLE_EMF, [("theta_unit = \"deg\"\ntheta = [0, 30, 150, 180, 210, 330]",
                              "theta = [0, 0.5, 2.6, 3.1, 3.7, 6.5]")], "motor.emf.theta",
                 "write degrees with theta_unit", id="table-beyond-2pi-rad"),
    # table: a hole (TOML has no null: a short column)
    pytest.param(TABLE_EMF, [("k = [0.0, 0.32, 0.32, 0.0, -0.32, -0.32]",
                              "k = [0.0, 0.32, 0.32, 0.0, -0.32]")],
                 "motor.emf.k", "as many entries as theta", id="table-short-k"),
    pytest.param(PHASE_TABLE_EMF, [("k_c = [0.0, 0.33, 0.33, 0.0, -0.33, -0.33]",
                                    "k_c = [0.0, 0.33, 0.33, -0.33, -0.33]")],
                 "motor.emf.k_c", "as many entries as theta", id="table-short-k_c"),
    # mismatched lengths
    pytest.param(TABLE_EMF, [("k = [0.0,", "k = [0.0, 0.1,")], "motor.emf.k", "as many entries as theta",
                 id="table-long-k"),
    pytest.param(FOURIER_EMF, [("a = [0.0, 0.0, 0.0, 0.0]", "a = [0.0, 0.0, 0.0]")], "motor.emf.b",
                 "as many entries as a", id="fourier-lengths"),
    pytest.param(None, [("[inverter]",
                         COGGING.replace("phases = [0.0, 1.0]", "phases = [0.0]") + "\n[inverter]")],
                 "motor.cogging.phases", "as many entries as orders", id="cogging-lengths"),
    pytest.param(None, [("current_gain = [1.0, 1.0, 1.0]", "current_gain = [1.0, 1.0]")],
                 "sensors.current_gain", "three", id="sensor-lengths"),
    pytest.param(TABLE_EMF, [("theta = [0, 30, 150, 180, 210, 330]", "theta = [0, 180]"),
                             ("k = [0.0, 0.32, 0.32, 0.0, -0.32, -0.32]", "k = [0.1, -0.1]")],
                 "motor.emf.theta", "at least 3", id="table-too-short"),
    # angles outside [0, 2 pi)
    pytest.param(TABLE_EMF, [("210, 330]", "210, 360]")], "motor.emf.theta",
                 "got [0, 360] deg: 360 deg is 0 again (the table is periodic): drop the last point",
                 id="table-360deg"),
    pytest.param(TABLE_EMF, [("theta = [0,", "theta = [-10,")], "motor.emf.theta", "[0, 360) deg",
                 id="table-negative-angle"),
    pytest.param(TABLE_EMF, [('theta_unit = "deg"\n', ""),
                             ("theta = [0, 30, 150, 180, 210, 330]", "theta = [0, 1, 2, 3, 4, 7]")],
                 "motor.emf.theta", "theta_unit", id="table-degrees-as-rad"),
    # all-zero shapes
    pytest.param(TABLE_EMF, [("k = [0.0, 0.32, 0.32, 0.0, -0.32, -0.32]", "k = [0, 0, 0, 0, 0, 0]")],
                 "motor.emf.k", "zero", id="table-all-zero"),
    pytest.param(PHASE_TABLE_EMF, [("k_b = [0.0, 0.31, 0.31, 0.0, -0.31, -0.31]",
                                    "k_b = [0, 0, 0, 0, 0, 0.0]")],
                 "motor.emf.k_b", "zero", id="table-phase-zero"),
    pytest.param(FOURIER_EMF, [("b = [0.0, 0.38, 0.0, 0.02]", "b = [1.0, 0.0, 0.0, 0.0]")], "motor.emf.b",
                 "zero", id="fourier-no-harmonics"),
    # shapes whose line-to-line back-EMF is zero (a part common to the three phases only): no torque, k_phi = 0
    pytest.param(TABLE_EMF, [("k = [0.0, 0.32, 0.32, 0.0, -0.32, -0.32]", "k = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1]")],
                 "motor.emf", "line-to-line", id="table-constant"),
    pytest.param(FOURIER_EMF, [("b = [0.0, 0.38, 0.0, 0.02]", "b = [0.0, 0.0, 0.0, 0.02]")], "motor.emf",
                 "line-to-line", id="fourier-triplen-only"),
    # three phases needed
    pytest.param(PHASE_ARRAY_EMF, [("[[motor.emf.phase]]\nkind = \"sinusoid\"\nk_1 = 0.37\n", "")],
                 "motor.emf.phase", "three", id="phase-array-two"),
    # current_phases
    pytest.param(None, [('current_phases = "ab"', 'current_phases = "ad"')], "sensors.current_phases", "abc",
                 id="current_phases-letter"),
    pytest.param(None, [('current_phases = "ab"', 'current_phases = "a"')], "sensors.current_phases",
                 "two phases", id="current_phases-one"),
    pytest.param(None, [('current_phases = "ab"', 'current_phases = "aa"')], "sensors.current_phases",
                 "repeats", id="current_phases-repeat"),
    pytest.param(None, [('current_phases = "ab"', 'current_phases = ""')], "sensors.current_phases", "abc",
                 id="current_phases-empty"),
    pytest.param(None, [('current_phases = "ab"', 'current_phases = "AB"')], "sensors.current_phases", "abc",
                 id="current_phases-case"),
    # dead time
    pytest.param(None, [('f_pwm = "14 kHz"', "f_pwm = 10000.0"), ('t_dead = "1 us"', "t_dead = 2.5e-05")],
                 "inverter.t_dead", "quarter", id="t_dead-quarter"),
    pytest.param(None, [('t_dead = "1 us"', 't_dead = "1 ms"')], "inverter.t_dead", "quarter",
                 id="t_dead-long"),
    # other cross-field and range checks
    pytest.param(None, [('Omega_N = "640 rpm"\n', ""), ('R = "50 mOhm"', 'R = "1 Ohm"')], "motor.R",
                 "exceeds V_N", id="R-too-large"),
    pytest.param(None, [('flat_top = "120 deg"', 'flat_top = "181 deg"')], "motor.emf.flat_top", "< 3.14159",
                 id="flat_top-pi"),
    pytest.param(None, [("[inverter]", COGGING.replace("[24, 48]", "[0, 48]") + "\n[inverter]")],
                 "motor.cogging.orders[0]", ">= 1", id="cogging-order-zero"),
    pytest.param(None, [("[inverter]", COGGING.replace("[24, 48]", "[24, 4.5]") + "\n[inverter]")],
                 "motor.cogging.orders[1]", "integer", id="cogging-order-float"),
    pytest.param(None, [("[inverter]", COGGING.replace("[24, 48]", "24") + "\n[inverter]")],
                 "motor.cogging.orders", "list", id="cogging-orders-scalar"),
    pytest.param(None, [('current_phases = "ab"\n', 'current_phases = "ab"\nseed = -1\n')], "sensors.seed",
                 ">= 0", id="seed-negative"),
    pytest.param(None, [('current_phases = "ab"\n', 'current_phases = "ab"\nf_tick = "1 Hz"\n')],
                 "sensors.f_tick", ">= 1000", id="f_tick-low"),
]


@pytest.mark.parametrize(("emf", "edits", "field", "words"), BAD_FILES)
def test_bad_file_names_field(tmp_path: Path, emf: str | None, edits: list[tuple[str, str]], field: str,
                              words: str) -> None:
    text = edited(with_emf(emf) if emf is not None else BASE, edits)
    tomllib.loads(text)  # each case is valid TOML: the error must come from bldclab's checks
    path = write(tmp_path, text)
    with pytest.raises(BldclabError) as info:
        Drive.from_toml(path)
    err = info.value
    assert type(err) is BldclabError
    assert err.field == field
    assert words in err.problem
    assert err.source == str(path)
    assert str(err) == f"{path}: {field}: {err.problem}"


def test_motor_not_a_table_from_dict() -> None:
    data = tomllib.loads(BASE)
    data["motor"] = 5
    with pytest.raises(BldclabError) as info:
        Drive.from_dict(data, source="memory")
    assert info.value.field == "motor"
    assert "must be a table" in info.value.problem
    assert str(info.value).startswith("memory: motor:")


def test_from_dict_top_level_not_a_table() -> None:
    with pytest.raises(BldclabError) as info:
        Drive.from_dict([1, 2, 3])  # type: ignore[arg-type]
    assert info.value.field == "file"


def test_dead_time_just_below_quarter_period_is_accepted(tmp_path: Path) -> None:
    text = edited(BASE, [('f_pwm = "14 kHz"', "f_pwm = 10000.0"), ('t_dead = "1 us"', "t_dead = 2.4999e-05")])
    assert Drive.from_toml(write(tmp_path, text)).inverter.t_dead == 2.4999e-05


# ----------------------------------------------------------------------------------------------------------
# files that are not motor files


@pytest.mark.parametrize(
    ("content", "words"),
    [
        pytest.param("this is [not TOML = =\n", "not valid TOML", id="syntax"),
        pytest.param("name = 1\nname = 2\n", "not valid TOML", id="duplicate-key"),
        pytest.param(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe", "not a text", id="binary"),
        pytest.param('{"motor": {"p": 8}}', "not valid TOML", id="json"),
    ],
)
def test_non_toml_file(tmp_path: Path, content: str | bytes, words: str) -> None:
    path = tmp_path / "motor.toml"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")
    with pytest.raises(BldclabError) as info:
        Drive.from_toml(path)
    assert info.value.field == "file"
    assert words in info.value.problem
    assert info.value.source == str(path)


def test_empty_file_misses_motor(tmp_path: Path) -> None:
    with pytest.raises(BldclabError) as info:
        Drive.from_toml(write(tmp_path, ""))
    assert info.value.field == "motor"
    assert "missing" in info.value.problem


@pytest.mark.parametrize("kind", ["missing", "directory"])
def test_unreadable_file(tmp_path: Path, kind: str) -> None:
    path = tmp_path / "nothing.toml" if kind == "missing" else tmp_path
    with pytest.raises(BldclabError) as info:
        Drive.from_toml(path)
    assert info.value.field == "file"
    assert "cannot read" in info.value.problem
    assert info.value.source == str(path)


def test_catalog_unknown_name() -> None:
    with pytest.raises(BldclabError) as info:
        catalog.load("no-such-motor")
    assert info.value.field == "MOTOR"
    assert "htm-48v" in info.value.problem


def test_catalog_loads_a_path(tmp_path: Path) -> None:
    path = write(tmp_path, BASE, "custom.toml")
    assert catalog.load(path) == Drive.from_toml(path)
    assert catalog.load(str(path)).name == "matrix"


def test_name_defaults_to_file_stem(tmp_path: Path) -> None:
    text = edited(BASE, [('name = "matrix"\n', "")])
    assert Drive.from_toml(write(tmp_path, text, "my-motor.toml")).name == "my-motor"


# ----------------------------------------------------------------------------------------------------------
# the Python constructors: same checks, field names relative to the object

NAN, INF = float("nan"), float("inf")
TH3 = (0.0, 2.0, 4.0)


def _motor(**kw: object) -> Motor:
    args: dict[str, object] = {"p": 4, "R": 0.1, "L": 1e-4, "emf": BackEmf.symmetric(Trapezoid(0.1)),
                               "V_N": 48.0, "I_N": 10.0}
    args.update(kw)
    return Motor(**args)  # type: ignore[arg-type]


BAD_OBJECTS = [
    pytest.param(lambda: Table((0.0, 1.0, None), (1.0, 2.0, 3.0)), "theta", "missing", id="table-None-theta"),
    pytest.param(lambda: Table(TH3, (1.0, None, 3.0)), "k", "entry 1 is missing", id="table-None-k"),
    pytest.param(lambda: Table(TH3, (1.0, NAN, 3.0)), "k", "entry 1", id="table-NaN-k"),
    pytest.param(lambda: Table((0.0, NAN, 3.0), (1.0, 2.0, 3.0)), "theta", "entry 1", id="table-NaN-theta"),
    pytest.param(lambda: Table(TH3, (1.0, 2.0, INF)), "k", "entry 2", id="table-inf-k"),
    pytest.param(lambda: Table((0.0, 1.0, 2.0, 3.0), (1.0, 2.0, 3.0)), "k", "as many entries",
                 id="table-lengths"),
    pytest.param(lambda: Table((0.0, 3.0, 2.0), (1.0, 2.0, 3.0)), "theta", "strictly increasing",
                 id="table-unsorted"),
    pytest.param(lambda: Table((0.0, 3.0, 7.0), (1.0, 2.0, 3.0)), "theta", "[0, 2 pi)", id="table-range"),
    pytest.param(lambda: Table((0.0, 3.0, TWO_PI), (1.0, 2.0, 3.0)), "theta", "[0, 2 pi)", id="table-2pi"),
    pytest.param(lambda: Table((-0.1, 3.0, 5.0), (1.0, 2.0, 3.0)), "theta", "[0, 2 pi)", id="table-negative"),
    pytest.param(lambda: Table(TH3, (0.0, 0.0, 0.0)), "k", "zero", id="table-zero"),
    pytest.param(lambda: Table((0.0, 1.0), (1.0, -1.0)), "theta", "at least 3", id="table-short"),
    pytest.param(lambda: Table("abc", (1.0, 2.0, 3.0)), "theta", "list", id="table-string"),  # type: ignore[arg-type]
    pytest.param(lambda: Table(((0.0, 1.0), (2.0, 3.0), (4.0, 5.0)), (1.0, 2.0, 3.0)), "theta", "entry 0",
                 id="table-nested"),
    pytest.param(lambda: Trapezoid(-0.1), "k_phi", "> 0", id="trapezoid-negative"),
    pytest.param(lambda: Trapezoid(True), "k_phi", "number", id="trapezoid-bool"),  # type: ignore[arg-type]
    pytest.param(lambda: Trapezoid("0.1"), "k_phi", "number", id="trapezoid-string"),  # type: ignore[arg-type]
    pytest.param(lambda: Trapezoid(0.1, math.pi), "flat_top", "<", id="trapezoid-flat-pi"),
    pytest.param(lambda: Sinusoid(0.0), "k_1", "> 0", id="sinusoid-zero"),
    pytest.param(lambda: Sinusoid(NAN), "k_1", "NaN", id="sinusoid-nan"),
    pytest.param(lambda: Fourier((0.0,), (0.0,)), "a", "at least 2", id="fourier-short"),
    pytest.param(lambda: Fourier((0.0, 0.0, 0.0), (0.0, 1.0)), "b", "as many entries", id="fourier-lengths"),
    pytest.param(lambda: Fourier((0.5, 0.0), (0.0, 0.0)), "b", "zero", id="fourier-dc-only"),
    pytest.param(lambda: BackEmf((Sinusoid(1.0), Sinusoid(1.0))), "emf", "three", id="backemf-two"),
    pytest.param(lambda: BackEmf((Sinusoid(1.0), Sinusoid(1.0), 3.0)), "emf", "three",  # type: ignore[arg-type]
                 id="backemf-not-shape"),
    pytest.param(lambda: _motor(L=NAN), "L", "NaN", id="motor-L-nan"),
    pytest.param(lambda: _motor(L=-1e-4), "L", "> 0", id="motor-L-negative"),
    pytest.param(lambda: _motor(p=1.5), "p", "integer", id="motor-p-float"),
    pytest.param(lambda: _motor(p=True), "p", "integer", id="motor-p-bool"),
    pytest.param(lambda: _motor(emf=Trapezoid(0.1)), "emf", "BackEmf", id="motor-emf-shape"),
    pytest.param(lambda: _motor(T_peak=0.0), "T_peak", "> 0", id="motor-T_peak-zero"),
    pytest.param(lambda: _motor(R=100.0), "R", "exceeds V_N", id="motor-R-large"),
    pytest.param(lambda: _motor(emf=BackEmf.symmetric(Fourier((0.0, 0.0, 0.0, 0.1), (0.0, 0.0, 0.0, 0.0)))), "emf",
                 "line-to-line", id="motor-emf-triplen"),
    pytest.param(lambda: Inverter(48.0, 1e4, t_dead=2.5e-5), "t_dead", "quarter", id="inverter-t_dead"),
    pytest.param(lambda: Inverter(48.0, 0.0), "f_pwm", "> 0", id="inverter-f_pwm-zero"),
    pytest.param(lambda: Inverter(48.0, 1e4, V_f=-0.7), "V_f", ">= 0", id="inverter-V_f"),
    pytest.param(lambda: Mechanics(J=0.0), "J", "> 0", id="mechanics-J"),
    pytest.param(lambda: Mechanics(B=INF), "B", "infinite", id="mechanics-B-inf"),
    pytest.param(lambda: Sensors(current_phases="xy"), "current_phases", "abc", id="sensors-phases"),
    pytest.param(lambda: Sensors(current_phases=None), "current_phases", "abc",  # type: ignore[arg-type]
                 id="sensors-phases-None"),
    pytest.param(lambda: Sensors(current_gain=(1.0, 1.0)), "current_gain", "three", id="sensors-gain-two"),
    pytest.param(lambda: Sensors(current_gain=1.0), "current_gain", "three",  # type: ignore[arg-type]
                 id="sensors-gain-scalar"),
    pytest.param(lambda: Sensors(hall_error=(0.0, NAN, 0.0)), "hall_error[1]", "NaN", id="sensors-hall-nan"),
    pytest.param(lambda: Sensors(seed=1.5), "seed", "integer", id="sensors-seed"),  # type: ignore[arg-type]
    pytest.param(lambda: Cogging((1,), (0.1, 0.2), (0.0,)), "amplitudes", "as many entries",
                 id="cogging-len"),
    pytest.param(lambda: Cogging((0,), (0.1,), (0.0,)), "orders[0]", ">= 1", id="cogging-order"),
    pytest.param(lambda: Cogging((), (), ()), "orders", "at least one", id="cogging-empty"),
    pytest.param(lambda: Cogging((1,), (NAN,), (0.0,)), "amplitudes", "entry 0", id="cogging-nan"),
    pytest.param(lambda: Drive(motor="x", inverter=Inverter(48.0, 1e4)), "motor", "Motor",  # type: ignore[arg-type]
                 id="drive-motor"),
    pytest.param(lambda: Drive(motor=_motor(), inverter=Inverter(48.0, 1e4), name=3), "name",  # type: ignore[arg-type]
                 "string", id="drive-name"),
]


@pytest.mark.parametrize(("make", "field", "words"), BAD_OBJECTS)
def test_bad_object_names_field(make: object, field: str, words: str) -> None:
    with pytest.raises(BldclabError) as info:
        make()  # type: ignore[operator]
    assert type(info.value) is BldclabError
    assert info.value.field == field
    assert words in info.value.problem


def test_replace_changes_a_part_field_and_validates() -> None:
    d = catalog.load("htm-48v")
    d2 = d.replace(motor__R=0.1, inverter__t_dead=1e-6, name="x")
    assert (d2.motor.R, d2.inverter.t_dead, d2.name) == (0.1, 1e-6, "x")
    assert d2.motor.L == d.motor.L and d.motor.R == 0.05
    with pytest.raises(BldclabError) as info:
        d.replace(motor__Rx=0.1)
    assert info.value.field == "motor.Rx"
    with pytest.raises(BldclabError) as info:
        d.replace(rotor__J=0.1)
    assert info.value.field == "rotor__J"
    with pytest.raises(BldclabError) as info:
        d.replace(motor__L=-1.0)
    assert info.value.field == "L"


# ----------------------------------------------------------------------------------------------------------
# round trips: Drive.to_toml -> from_toml gives an equal Drive


def _round_trip(tmp_path: Path, drive: Drive) -> Drive:
    text = drive.to_toml()
    tomllib.loads(text)  # valid TOML on its own
    return Drive.from_toml(write(tmp_path, text, "rt.toml"))


@pytest.mark.parametrize("name", catalog.names())
def test_round_trip_catalog(tmp_path: Path, name: str) -> None:
    drive = catalog.load(name)
    back = _round_trip(tmp_path, drive)
    assert back == drive
    assert back.to_toml() == drive.to_toml()


def test_catalog_names() -> None:
    assert {"htm-48v", "lu-4kw"} <= set(catalog.names())


def _drive(emf: BackEmf, **kw: object) -> Drive:
    return Drive(motor=_motor(emf=emf, **kw), inverter=Inverter(48.0, 2e4))


GRID = tuple(TWO_PI * np.arange(24) / 24)
GRID2 = tuple(TWO_PI * np.arange(10) / 10 + 0.05)
EMFS = {
    "trapezoid": BackEmf.symmetric(Trapezoid(0.123, 2.5)),
    "trapezoid-triangle": BackEmf.symmetric(Trapezoid(0.2, 0.0)),
    "sinusoid": BackEmf.symmetric(Sinusoid(0.321)),
    "fourier": BackEmf.symmetric(Fourier((0.0, 0.001, 0.0), (0.0, 0.3, 1e-17))),
    "table": BackEmf.symmetric(Table(GRID, tuple(0.2 * np.sin(GRID) + 0.01 * np.sin(3 * np.asarray(GRID))))),
    "table-per-phase": BackEmf(tuple(Table(GRID, tuple(s * np.sin(GRID))) for s in (0.2, 0.21, 0.19))),  # type: ignore[arg-type]
    "table-per-phase-grids": BackEmf((Table(GRID, tuple(np.sin(GRID))), Table(GRID2, tuple(np.sin(GRID2))),
                                      Table(GRID, tuple(1.1 * np.sin(GRID))))),
    "phase-analytic": BackEmf((Trapezoid(0.1), Sinusoid(0.12), Fourier((0.0, 0.0), (0.0, 0.11)))),
    "phase-mixed": BackEmf((Trapezoid(0.1), Table(GRID, tuple(0.1 * np.sin(GRID))), Sinusoid(0.1))),
}


@pytest.mark.parametrize("key", list(EMFS))
def test_round_trip_every_shape_kind(tmp_path: Path, key: str) -> None:
    drive = _drive(EMFS[key])
    back = _round_trip(tmp_path, drive)
    assert back == drive
    assert back.motor.emf.shapes == drive.motor.emf.shapes


def test_round_trip_every_field(tmp_path: Path) -> None:
    drive = Drive(
        motor=_motor(Omega_N=123.456, T_peak=7.5,
                     cogging=Cogging((12, 24), (0.01, -0.002), (0.1, 3.0))),
        inverter=Inverter(V_dc=47.5, f_pwm=16e3, t_dead=5e-7, R_on=0.004, V_f=0.8, r_d=0.002, R_src=0.01),
        mechanics=Mechanics(J=2e-3, B=1e-4, tau_c=0.03),
        sensors=Sensors(current_phases="ca", current_gain=(1.01, 0.99, 1.0), current_offset=(0.1, -0.05, 0.0),
                        current_noise=0.02, current_lsb=0.01, vdc_gain=1.02, vdc_offset=-0.3, vdc_noise=0.05,
                        vdc_lsb=0.02, hall_error=(0.01, -0.02, 0.0), hall_delay=2e-6, f_tick=72e6, seed=42),
        name="every field",
        description='quotes " and \\ backslash, newline\nand tab\t, a bell \x07, unicode: Ω µ ü',
    )
    back = _round_trip(tmp_path, drive)
    assert back == drive


def test_round_trip_numpy_scalars(tmp_path: Path) -> None:
    """Parameters computed with numpy (np.float64, np.int64) must still write valid TOML."""
    drive = Drive(
        motor=_motor(p=np.int64(3), R=np.float64(0.1), Omega_N=np.float64(100.0), T_peak=np.float32(2.5)),
        inverter=Inverter(V_dc=np.float64(48.0), f_pwm=np.float64(1e4), t_dead=np.float64(1e-6)),
        mechanics=Mechanics(J=np.float64(1e-3)),
        sensors=Sensors(vdc_gain=np.float64(1.01), seed=3),
    )
    back = _round_trip(tmp_path, drive)
    assert back == drive


def test_writer_layout() -> None:
    """Symmetric shapes write one shape, per-phase tables on one grid k_a/k_b/k_c, others a phase array."""
    sym = tomllib.loads(_drive(EMFS["trapezoid"]).to_toml())["motor"]["emf"]
    assert sym == {"kind": "trapezoid", "k_phi": 0.123, "flat_top": 2.5}
    cols = tomllib.loads(_drive(EMFS["table-per-phase"]).to_toml())["motor"]["emf"]
    assert set(cols) == {"kind", "theta", "k_a", "k_b", "k_c"}
    arr = tomllib.loads(_drive(EMFS["phase-analytic"]).to_toml())["motor"]["emf"]
    assert [p["kind"] for p in arr["phase"]] == ["trapezoid", "sinusoid", "fourier"]


finite = st.floats(min_value=1e-6, max_value=1e6, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(p=st.integers(1, 50), R=st.floats(0.0, 1.0), L=finite, k_phi=finite,
       flat_top=st.floats(0.0, 3.14159), V_N=finite, f_pwm=st.floats(1.0, 1e6), J=finite,
       phases=st.sampled_from(["ab", "ac", "bc", "abc", "cab"]), seed=st.integers(0, 2**31))
def test_round_trip_property(tmp_path_factory: pytest.TempPathFactory, p: int, R: float, L: float,
                             k_phi: float, flat_top: float, V_N: float, f_pwm: float, J: float, phases: str,
                             seed: int) -> None:
    drive = Drive(
        motor=Motor(p=p, R=R, L=L, emf=BackEmf.symmetric(Trapezoid(k_phi, flat_top)), V_N=V_N, I_N=1e-3,
                    Omega_N=1.0),
        inverter=Inverter(V_dc=V_N, f_pwm=f_pwm, t_dead=0.2 / f_pwm),
        mechanics=Mechanics(J=J),
        sensors=Sensors(current_phases=phases, seed=seed),
    )
    back = _round_trip(tmp_path_factory.mktemp("rt"), drive)
    assert back == drive


# ----------------------------------------------------------------------------------------------------------
# units


@pytest.mark.parametrize(
    ("text", "dim", "si"),
    [
        ("640 rpm", "speed", 640 * TWO_PI / 60),
        ("640rpm", "speed", 640 * TWO_PI / 60),
        ("640 r/min", "speed", 640 * TWO_PI / 60),
        ("3 krpm", "speed", 3000 * TWO_PI / 60),
        ("75 uH", "inductance", 75e-6),
        ("0.29 mH", "inductance", 0.29e-3),
        ("120 deg", "angle", TWO_PI / 3),
        ("50 mOhm", "resistance", 0.05),
        ("14 kHz", "frequency", 14e3),
        ("1.5e-6 s", "time", 1.5e-6),
        ("2 us", "time", 2e-6),
        (".5 V", "voltage", 0.5),
        ("-3 A", "current", -3.0),
        ("+3e2 mA", "current", 0.3),
        ("100 N m", "torque", 100.0),
        ("0.05 kg m^2", "inertia", 0.05),
        ("500 g cm^2", "inertia", 5e-5),
        ("0.32 V s/rad", "emf_constant", 0.32),
        ("0.32 Nm/A", "emf_constant", 0.32),
        ("4 kW", "power", 4000.0),
        ("75 µH", "inductance", 75e-6),
        ("75 μH", "inductance", 75e-6),
        ("50 mΩ", "resistance", 0.05),
        ("0.32 V·s/rad", "emf_constant", 0.32),
        ("0.05 kg·m²", "inertia", 0.05),
        ("100  N   m", "torque", 100.0),
        ("67.0", "speed", 67.0),
        ("1.01", "dimensionless", 1.01),
        (67, "speed", 67.0),
        (0.5, "voltage", 0.5),
    ],
)
def test_to_si(text: str | float, dim: str, si: float) -> None:
    assert to_si(text, dim, "x") == pytest.approx(si, rel=1e-14, abs=0.0)


@pytest.mark.parametrize("dim", [d for d in DIMENSIONS if d != "dimensionless"])
def test_every_unit_converts_and_every_foreign_unit_fails(dim: str) -> None:
    for unit, factor in DIMENSIONS[dim].items():
        assert to_si(f"2.5 {unit}", dim, "f") == pytest.approx(2.5 * factor, rel=1e-15)
    foreign = sorted({u for d, us in DIMENSIONS.items() if d != dim for u in us if u} - set(DIMENSIONS[dim]))
    for unit in foreign:
        with pytest.raises(BldclabError) as info:
            to_si(f"1 {unit}", dim, "motor.x", "file.toml")
        assert info.value.field == "motor.x"
        assert info.value.source == "file.toml"
        problem = info.value.problem
        assert f"not a unit of {dim.replace('_', ' ')}" in problem or (" as written, not " in problem), problem


@pytest.mark.parametrize(
    ("value", "words"),
    [("abc", "cannot read a number"), ("nan H", "cannot read a number"), ("", "cannot read a number"),
     (True, "boolean"), ([1.0], "expected a number"), (None, "expected a number"), ("1 HH", "unit 'HH'")],
)
def test_to_si_rejects(value: object, words: str) -> None:
    with pytest.raises(BldclabError) as info:
        to_si(value, "inductance", "motor.L")
    assert info.value.field == "motor.L"
    assert words in info.value.problem


def test_aliases_only_map_to_known_spellings() -> None:
    known = {u for us in DIMENSIONS.values() for u in us}
    assert any("Ohm" in u for u in known) and any(u.startswith("u") for u in known)
    assert set(ALIASES.values()) <= {"u", "Ohm", " ", "^2", "^3"}


def test_htm48v_file_units() -> None:
    m = catalog.load("htm-48v").motor
    assert m.Omega_N == pytest.approx(640 * RPM, rel=1e-15)
    assert m.L == pytest.approx(75e-6, rel=1e-15)
    assert m.emf.shapes[0].flat_top == pytest.approx(TWO_PI / 3, rel=1e-15)  # type: ignore[attr-defined]
    assert m.k_phi == pytest.approx(0.32, rel=1e-15)
    assert m.T_N == pytest.approx(32.0, rel=1e-15)


# ----------------------------------------------------------------------------------------------------------
# k_phi (docs/conventions.md: half the peak line-to-line shape)


@pytest.mark.parametrize("k_phi", [0.01, 0.32, 7.0])
def test_k_phi_of_ideal_trapezoid_is_flat_top(k_phi: float) -> None:
    assert _motor(emf=BackEmf.symmetric(Trapezoid(k_phi))).k_phi == pytest.approx(k_phi, rel=1e-14)
    # also for a wider flat top: two phases sit on their flat tops at once
    assert _motor(emf=BackEmf.symmetric(Trapezoid(k_phi, 2.8))).k_phi == pytest.approx(k_phi, rel=1e-14)


@pytest.mark.parametrize("k_1", [0.05, 0.32, 3.0])
def test_k_phi_of_sinusoid(k_1: float) -> None:
    assert _motor(emf=BackEmf.symmetric(Sinusoid(k_1))).k_phi == pytest.approx(math.sqrt(3) / 2 * k_1,
                                                                                 rel=1e-12)


@pytest.mark.parametrize("phi", [0.1234, 1.0, -2.5])
def test_k_phi_of_shifted_sinusoid_off_the_search_grid(phi: float) -> None:
    """A phase shift moves the line-to-line peaks off any fixed grid: the maximum must still be exact."""
    shape = Fourier((0.0, 0.7 * math.sin(phi)), (0.0, 0.7 * math.cos(phi)))
    assert _motor(emf=BackEmf.symmetric(shape)).k_phi == pytest.approx(math.sqrt(3) / 2 * 0.7, rel=1e-12)


def test_k_phi_of_table_trapezoid_is_flat_top(tmp_path: Path) -> None:
    assert Drive.from_toml(write(tmp_path, with_emf(TABLE_EMF))).motor.k_phi == pytest.approx(0.32, rel=1e-14)


@pytest.mark.parametrize("flat_top", [0.0, 0.7, 1.0, 1.1, 1.6, 2.0])
def test_k_phi_narrow_trapezoid_matches_brute_force(flat_top: float) -> None:
    """Flat tops of a and -b overlap (k_phi = flat top) only when the flat top is at least 60 degrees."""
    emf = BackEmf.symmetric(Trapezoid(1.0, flat_top))
    th = np.linspace(0.0, TWO_PI, 360_001)
    k = emf.k_abc(th)
    brute = max(np.max(np.abs(k[0] - k[1])), np.max(np.abs(k[1] - k[2])), np.max(np.abs(k[2] - k[0])))
    assert emf.line_peak() >= brute - 1e-15
    assert emf.line_peak() == pytest.approx(brute, abs=1e-9)
    if flat_top >= math.pi / 3:
        assert emf.line_peak() == pytest.approx(2.0, rel=1e-14)
    else:
        assert emf.line_peak() < 2.0 - 1e-3


# ----------------------------------------------------------------------------------------------------------
# Fourier coefficients are exact


@pytest.mark.parametrize("flat_top", [TWO_PI / 3, 0.0, 1.0, 2.9])
def test_trapezoid_fourier_closed_form(flat_top: float) -> None:
    k_phi = 0.37
    a, b = Trapezoid(k_phi, flat_top).fourier(31)
    r = 0.5 * (math.pi - flat_top)
    n = np.arange(32)
    expected = np.zeros(32)
    odd = n % 2 == 1
    expected[odd] = 4 * k_phi / (math.pi * n[odd]) * np.sin(n[odd] * r) / (n[odd] * r)
    np.testing.assert_allclose(b, expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(a, 0.0, atol=1e-15)


def test_trapezoid_fundamental_is_12_over_pi_squared() -> None:
    a, b = Trapezoid(0.32).fourier(1)
    assert b[1] == pytest.approx(12 / math.pi**2 * 0.32, rel=1e-14)
    assert abs(a[1]) < 1e-16


@pytest.mark.parametrize("n_points", [3, 12, 360])
def test_table_of_sampled_sinusoid_fourier(n_points: int) -> None:
    """Linear interpolation of samples of k_1 sin: b_1 = k_1 sinc^2(h/2), aliases at N -+ 1, nothing else."""
    k_1 = 0.7
    th = TWO_PI * np.arange(n_points) / n_points
    h = TWO_PI / n_points
    a, b = Table(tuple(th), tuple(k_1 * np.sin(th))).fourier(2 * n_points + 1)  # below the alias at 3N - 1

    def sinc2(n: int) -> float:
        return (math.sin(n * h / 2) / (n * h / 2)) ** 2

    expected = np.zeros(2 * n_points + 2)
    expected[1] = k_1 * sinc2(1)
    expected[n_points - 1] += -k_1 * sinc2(n_points - 1)
    expected[n_points + 1] += k_1 * sinc2(n_points + 1)
    expected[2 * n_points - 1] += -k_1 * sinc2(2 * n_points - 1)
    expected[2 * n_points + 1] += k_1 * sinc2(2 * n_points + 1)
    np.testing.assert_allclose(b, expected, rtol=0, atol=1e-13)
    np.testing.assert_allclose(a, 0.0, atol=1e-13)


def test_table_fourier_matches_fft_of_random_table() -> None:
    rng = np.random.default_rng(7)
    th = np.sort(rng.uniform(0, TWO_PI, 17))
    table = Table(tuple(th), tuple(rng.normal(size=17)))
    m = 2**18
    x = TWO_PI * np.arange(m) / m
    c = np.fft.rfft(table(x)) / m
    a, b = table.fourier(6)
    np.testing.assert_allclose(a[0], c[0].real, atol=1e-8)
    np.testing.assert_allclose(a[1:], 2 * c[1:7].real, atol=1e-8)
    np.testing.assert_allclose(b[1:], -2 * c[1:7].imag, atol=1e-8)


def test_fourier_and_sinusoid_coefficients() -> None:
    f = Fourier((0.1, 0.0, 0.02), (0.0, 0.5, 0.0))
    a, b = f.fourier(4)
    np.testing.assert_array_equal(a, [0.1, 0.0, 0.02, 0.0, 0.0])
    np.testing.assert_array_equal(b, [0.0, 0.5, 0.0, 0.0, 0.0])
    a, b = f.fourier(1)
    np.testing.assert_array_equal(a, [0.1, 0.0])
    th = np.linspace(0, 7, 50)
    np.testing.assert_allclose(f(th), 0.1 + 0.5 * np.sin(th) + 0.02 * np.cos(2 * th), atol=1e-15)
    a, b = Sinusoid(0.3).fourier(3)
    np.testing.assert_array_equal(b, [0.0, 0.3, 0.0, 0.0])
    np.testing.assert_array_equal(a, 0.0)


# ----------------------------------------------------------------------------------------------------------
# shapes on the angle convention, and the phase shifts of BackEmf.k_abc


def test_trapezoid_on_the_convention() -> None:
    """Zero rising at 0, flat top from pi/6 to 5 pi/6 (the Hall edges), half-wave antisymmetric."""
    t = Trapezoid(0.32)
    assert t(0.0) == 0.0 and t(math.pi) == 0.0
    np.testing.assert_allclose(t(np.linspace(math.pi / 6, 5 * math.pi / 6, 9)), 0.32, rtol=1e-14)
    np.testing.assert_allclose(t(np.linspace(7 * math.pi / 6, 11 * math.pi / 6, 9)), -0.32, rtol=1e-14)
    th = np.linspace(-10, 10, 1001)
    np.testing.assert_allclose(t(th + math.pi), -t(th), atol=1e-15)
    np.testing.assert_allclose(t(th + TWO_PI), t(th), atol=1e-14)
    assert t(0.1) > 0.0
    np.testing.assert_allclose(t.breakpoints(), np.array([1, 5, 7, 11]) * math.pi / 6, rtol=1e-15)


def test_k_abc_phase_b_lags_a_by_120_degrees() -> None:
    th = np.linspace(-7.0, 7.0, 301)
    k = BackEmf.symmetric(Sinusoid(0.5)).k_abc(th)
    assert k.shape == (3, 301)
    np.testing.assert_allclose(k[0], 0.5 * np.sin(th), atol=1e-15)
    np.testing.assert_allclose(k[1], 0.5 * np.sin(th - TWO_PI / 3), atol=1e-15)
    np.testing.assert_allclose(k[2], 0.5 * np.sin(th + TWO_PI / 3), atol=1e-15)
    trap = BackEmf.symmetric(Trapezoid(0.32))
    np.testing.assert_allclose(trap.k_abc(th + TWO_PI / 3)[1], trap.k_abc(th)[0], atol=1e-15)
    np.testing.assert_allclose(trap.k_abc(th + 2 * TWO_PI / 3)[2], trap.k_abc(th)[0], atol=1e-15)
    np.testing.assert_allclose(k.sum(axis=0), 0.0, atol=1e-15)  # balanced sinusoids (no triplen harmonics)


def test_k_abc_uses_each_phase_shape_at_its_local_angle() -> None:
    emf = BackEmf((Sinusoid(1.0), Sinusoid(2.0), Sinusoid(3.0)))
    th = np.linspace(0, TWO_PI, 37)
    k = emf.k_abc(th)
    for x in range(3):
        np.testing.assert_allclose(k[x], (x + 1) * np.sin(th - x * TWO_PI / 3), atol=1e-14)
    assert emf.k_abc(0.3).shape == (3,)
    assert not emf.is_symmetric and BackEmf.symmetric(Sinusoid(1.0)).is_symmetric


def test_table_interpolates_linearly_and_periodically() -> None:
    t = Table((0.0, 1.0, 4.0), (0.0, 2.0, -1.0))
    assert t(0.5) == pytest.approx(1.0)
    assert t(2.5) == pytest.approx(0.5)
    wrap = TWO_PI - 4.0  # from (4, -1) back to (2 pi, 0)
    assert t(5.0) == pytest.approx(-1.0 + (5.0 - 4.0) / wrap)
    assert t(-1.0) == pytest.approx(t(TWO_PI - 1.0))
    assert t(1.0 + 3 * TWO_PI) == pytest.approx(2.0)


def test_cogging_evaluates_and_normalises() -> None:
    c = Cogging((2,), (1,), (0,))
    assert c.amplitudes == (1.0,) and isinstance(c.amplitudes[0], float)
    assert c(math.pi / 4) == pytest.approx(1.0)
    assert c(np.array([0.0, math.pi / 4])).shape == (2,)


def test_omega_0_and_torque_base() -> None:
    d = catalog.load("htm-48v")
    assert d.Omega_0 == pytest.approx(48.0 / (2 * 0.32), rel=1e-15)
    assert d.T_N == pytest.approx(2 * 0.32 * 50.0, rel=1e-15)
    m = _motor(R=0.1)
    assert m.Omega_nominal == pytest.approx((48.0 - 2 * 0.1 * 10.0) / (2 * 0.1), rel=1e-14)


# ----------------------------------------------------------------------------------------------------------
# the user documentation stays true

DOC = Path(__file__).resolve().parents[1] / "docs" / "motor-files.md"


def _toml_blocks() -> list[str]:
    text = DOC.read_text(encoding="utf-8")
    return [block.split("```", 1)[0] for block in text.split("```toml\n")[1:]]


def test_doc_examples_load(tmp_path: Path) -> None:
    blocks = _toml_blocks()
    complete = [b for b in blocks if "[motor]" in b and "[inverter]" in b]
    assert len(complete) == 2
    # the catalogue-ratings example ([motor] and [motor.emf] only): the numbers its comments give
    ratings = [b for b in blocks if "poles =" in b]
    assert len(ratings) == 1
    m = Drive.from_toml(write(tmp_path, ratings[0] + BASE[BASE.index("[inverter]"):], "kv.toml")).motor
    assert (m.p, m.R, m.L) == (7, 0.04, 7.5e-6)
    assert round(m.emf.shapes[0].k_1 * 1e3, 3) == 2.827 and round(m.k_phi * 1e3, 3) == 2.449  # type: ignore[attr-defined]
    trapezoid, table = (Drive.from_toml(write(tmp_path, b, f"ex{j}.toml")) for j, b in enumerate(complete))
    assert isinstance(trapezoid.motor.emf.shapes[0], Trapezoid)
    assert trapezoid.sensors.hall_error[1] == pytest.approx(1.5 * math.pi / 180)
    assert all(isinstance(s, Table) and len(s.theta) == 24 for s in table.motor.emf.shapes)
    assert not table.motor.emf.is_symmetric
    snippets = [b for b in blocks if "[motor]" not in b and "[inverter]" not in b and "[motor.iron]" not in b
                and "poles =" not in b and "[thermal]" not in b]
    assert len(snippets) == 1
    # the [thermal] example loads on top of a drive (issue 27)
    thermal = [b for b in blocks if "[thermal]" in b]
    assert len(thermal) == 1
    th = Drive.from_toml(write(tmp_path, BASE + "\n" + thermal[0], "th.toml")).thermal
    assert th is not None and th.magnets == "rotor" and th.switches == ("junction",)
    assert th.alpha_k == pytest.approx(-0.0012) and th.node("junction").T_max == 175.0
    # the [motor.iron] example: a built-in grade, core mass and flux density give with_iron_from_grade's powers
    irons = [b for b in blocks if "[motor.iron]" in b]
    assert len(irons) == 1
    iron = Drive.from_toml(write(tmp_path, BASE + "\n" + irons[0] + "\n", "iron.toml")).motor
    plain = Drive.from_toml(write(tmp_path, BASE, "plain.toml")).motor
    want = plain.with_iron_from_grade(M270_35A, mass=2.0, B_peak=1.4)
    assert (iron.P_fe_eddy, iron.P_fe_hyst, iron.speed_fe_ref) == (want.P_fe_eddy, want.P_fe_hyst, want.speed_fe_ref)
    # the [inverter] example with rise and fall times: 48 V 50 A 20 ns / 2 = 24 uJ at the defaults V_dc, I_N
    inverters = [b for b in blocks if "[inverter]" in b and "[motor]" not in b]
    assert len(inverters) == 1
    base_inverter = BASE[BASE.index("[inverter]"):BASE.index("[mechanics]")]
    inv = Drive.from_toml(write(tmp_path, edited(BASE, [(base_inverter, inverters[0] + "\n")]), "inv.toml")).inverter
    assert (inv.V_test, inv.I_test) == (48.0, 50.0) and inv.E_on == pytest.approx(24e-6)
    drive = Drive.from_toml(write(tmp_path, edited(BASE, [(TRAPEZOID_EMF, snippets[0])])))
    assert [type(s) for s in drive.motor.emf.shapes] == [Trapezoid, Sinusoid, Fourier]


def test_doc_lists_every_unit() -> None:
    text = DOC.read_text(encoding="utf-8")
    for dim, units in DIMENSIONS.items():
        assert f"| {dim} |" in text
        for unit in units:
            if unit:
                assert f"`{unit}`" in text, unit


# ----------------------------------------------------------------------------------------------------------
# units: case, plurals, SI prefixes, ambiguous spellings (issue 23, item 4)

@pytest.mark.parametrize(("text", "dim", "si"), [
    ("50 mohm", "resistance", 0.05), ("0.08 ohm", "resistance", 0.08), ("0.08 ohms", "resistance", 0.08),
    ("80 mOhms", "resistance", 0.08), ("0.08 OHM", "resistance", 0.08), ("48 khz", "frequency", 48e3),
    ("48 KHZ", "frequency", 48e3), ("48 KHz", "frequency", 48e3), ("15 uh", "inductance", 15e-6),
    ("15 UH", "inductance", 15e-6), ("2.4 mV s/rad", "emf_constant", 2.4e-3), ("2.4 mv s/rad", "emf_constant", 2.4e-3),
    ("2.4 uV s/rad", "emf_constant", 2.4e-6), ("1 kV s/rad", "emf_constant", 1e3), ("3 MV s/rad", "emf_constant", 3e6),
    ("90 degrees", "angle", math.pi / 2), ("90 degs", "angle", math.pi / 2), ("1 radians", "angle", 1.0),
    ("3000 RPM", "speed", 3000 * TWO_PI / 60), ("1950 rpm/V", "speed_constant", 1950 * TWO_PI / 60),
    ("2 GHz", "frequency", 2e9), ("5 kN m", "torque", 5e3), ("3 pH", "inductance", 3e-12), ("1 mw", "power", 1e-3),
    ("1 Ms", "time", 1e6), ("20 ms", "time", 0.02),
])
def test_units_case_plurals_and_prefixes(text: str, dim: str, si: float) -> None:
    """Case is free where it does not change the meaning; plurals; any SI prefix on an SI symbol."""
    assert to_si(text, dim, "x") == pytest.approx(si, rel=1e-15)


@pytest.mark.parametrize(("text", "dim", "both"), [
    ("20 mS", "time", ("millisiemens", "'ms'")),  # S is the siemens: millisiemens as typed, not milliseconds
    ("1 S", "time", ("siemens", "'s'")),
    ("1 MW", "power", ("'MW' (mega)", "'mW' (milli)")),  # in capitals: the prefix's case is lost
    ("50 MOHM", "resistance", ("'MOhm' (mega)", "'mOhm' (milli)")),
    ("48 MHZ", "frequency", ("'MHz' (mega)", "'mHz' (milli)")),
    ("5 nm", "torque", ("a unit of length", "'Nm'")),  # nanometre as typed
])
def test_ambiguous_spellings_are_refused_naming_both_readings(text: str, dim: str, both: tuple[str, str]) -> None:
    with pytest.raises(BldclabError) as info:
        to_si(text, dim, "motor.x")
    assert info.value.field == "motor.x"
    for reading in both:
        assert reading in info.value.problem, info.value.problem


def test_a_unit_scales_the_number_by_its_power_of_ten_exactly() -> None:
    """"30 uH" is the double of 3e-05 (30 * 1e-6 is 2.9999999999999997e-05): a file written back shows 3e-05."""
    assert 30 * 1e-6 != 3e-05
    assert to_si("30 uH", "inductance", "x") == 3e-05
    assert repr(to_si("0.1 mOhm", "resistance", "x")) == "0.0001"
    assert repr(to_si("7 ms", "time", "x")) == "0.007"
    assert to_si("3000 rpm", "speed", "x") == 3000 * (2 * math.pi / 60)  # non-decimal: times the factor


# ----------------------------------------------------------------------------------------------------------
# catalogue ratings: KV, poles, line-to-line R and L (issue 23, item 3)

DRONE = Path(__file__).resolve().parent / "data" / "drone-2207.toml"
DRONE_TEXT = DRONE.read_text(encoding="utf-8")


def test_a_catalogue_motor_file_converts_on_load() -> None:
    """poles, R_ll, L_ll and KV = 1950 rpm/V: p = 7, 40 mOhm, 7.5 uH per phase, k_phi = 15 / (pi KV)."""
    d = Drive.from_toml(DRONE)
    m = d.motor
    assert (m.p, m.R, m.L) == (7, 0.04, 7.5e-6)
    assert m.k_phi == pytest.approx(15 / (math.pi * 1950), rel=1e-12)
    assert isinstance(m.emf.shapes[0], Sinusoid)
    assert m.emf.shapes[0].k_1 == pytest.approx(2 * 15 / (math.pi * 1950) / math.sqrt(3), rel=1e-12)
    assert d.Omega_0 * 60 / TWO_PI == pytest.approx(1950 * 24, rel=1e-12)  # KV is Omega_0 / V_dc
    assert (m.poles, m.R_ll, m.L_ll) == (14, 0.08, 1.5e-5)
    assert m.KV == pytest.approx(1950, rel=1e-12) and m.KV_rms == pytest.approx(1950 * math.sqrt(2), rel=1e-6)


def test_the_written_file_is_canonical_with_the_ratings_in_comments(tmp_path: Path) -> None:
    d = Drive.from_toml(DRONE)
    text = d.to_toml()
    motor = tomllib.loads(text)["motor"]
    assert {"p", "R", "L"} <= set(motor) and not {"poles", "R_ll", "L_ll", "KV"} & set(motor)
    assert "p = 7  # pole pairs (14 poles)" in text and "R_ll = 0.08" in text and "L_ll = 1.5e-05" in text
    assert "KV = 1950 rpm/V" in text
    assert Drive.from_toml(write(tmp_path, text)) == d


@pytest.mark.parametrize(("form", "crest"), [("sinusoid", math.sqrt(2)), ("trapezoid", 3 / math.sqrt(5))])
def test_kv_rms_uses_the_shapes_line_to_line_crest_factor(tmp_path: Path, form: str, crest: float) -> None:
    """KV_rms: per volt of rms line-to-line back-EMF; peak / rms of the line shape is sqrt(2) or 3/sqrt(5)."""
    text = DRONE_TEXT.replace('KV = "1950 rpm/V"', 'KV_rms = "2000 rpm/V"').replace('"sinusoid"', f'"{form}"')
    m = Drive.from_toml(write(tmp_path, text)).motor
    assert m.k_phi == pytest.approx(crest / (2 * 2000 * TWO_PI / 60), rel=1e-6)
    assert m.KV_rms == pytest.approx(2000, rel=1e-9)


def test_kv_as_a_plain_number_is_rpm_per_volt(tmp_path: Path) -> None:
    text = DRONE_TEXT.replace('KV = "1950 rpm/V"', "KV = 1950")
    assert Drive.from_toml(write(tmp_path, text)) == Drive.from_toml(DRONE)
    text = DRONE_TEXT.replace('KV = "1950 rpm/V"', 'KV = "204.2035 rad/s/V"')
    assert Drive.from_toml(write(tmp_path, text)).motor.KV == pytest.approx(1950, rel=1e-6)


@pytest.mark.parametrize(("old", "new", "field", "words"), [
    ("poles = 14", "poles = 13", "motor.poles", "for 13 pole pairs write p = 13"),
    ("poles = 14", "poles = 14\np = 7", "motor.poles", "not both"),
    ('R_ll = "0.08 Ohm"', 'R_ll = "0.08 Ohm"\nR = 0.04', "motor.R_ll", "not both"),
    ('R_ll = "0.08 Ohm"', 'R = "0.08 Ohm line-to-line"', "motor.R", 'R_ll = "0.08 Ohm"'),
    ('L_ll = "15 uH"', "", "motor.L", "is missing"),
    # L's rule (> 0) named on the field the file has: L_ll = 0 was "motor.L: must be > 0", L_ll < 0 "must be >= 0"
    ('L_ll = "15 uH"', "L_ll = 0", "motor.L_ll", "must be > 0, got 0"),
    ('L_ll = "15 uH"', 'L_ll = "-15 uH"', "motor.L_ll", "must be > 0, got -1.5e-05"),
    ('R_ll = "0.08 Ohm"', 'R_ll = "-0.08 Ohm"', "motor.R_ll", "must be >= 0, got -0.08"),
    ('KV = "1950 rpm/V"', 'KV = "1950 rpm/V"\nKV_rms = 2700', "motor.KV_rms", "cannot be given with KV"),
    ('kind = "sinusoid"', 'kind = "sinusoid"\nk_1 = 0.0028', "motor.emf.k_1", "cannot be given with motor.KV"),
    ('KV = "1950 rpm/V"', "", "motor.emf.k_1", "is missing"),
    ('kind = "sinusoid"', 'kind = "fourier"\na = [0.0, 0.0]\nb = [0.0, 1.0]', "motor.emf.kind", "drop motor.KV"),
    ('KV = "1950 rpm/V"', "KV = -5", "motor.KV", "must be > 0"),
])
def test_catalogue_forms_are_refused_naming_the_field(tmp_path: Path, old: str, new: str, field: str,
                                                      words: str) -> None:
    with pytest.raises(BldclabError) as info:
        Drive.from_toml(write(tmp_path, DRONE_TEXT.replace(old, new)))
    assert info.value.field == field and words in info.value.problem, str(info.value)


def test_a_kv_typed_as_an_emf_constant_is_refused_with_the_fix(tmp_path: Path) -> None:
    text = DRONE_TEXT.replace('KV = "1950 rpm/V"\n', "").replace('kind = "sinusoid"',
                                                                 'kind = "sinusoid"\nk_1 = "1950 rpm/V"')
    with pytest.raises(BldclabError) as info:
        Drive.from_toml(write(tmp_path, text))
    assert info.value.field == "motor.emf.k_1"
    assert 'write KV = "1950 rpm/V" in [motor]' in info.value.problem


def test_pole_pairs_that_look_like_a_pole_count_warn_naming_both_readings(tmp_path: Path) -> None:
    """p = 14 at 1950 KV: 10.9 kHz electrical at the no-load speed; 7 pole pairs would be 5.46 kHz."""
    from bldclab.errors import PlausibilityWarning

    with pytest.warns(PlausibilityWarning) as rec:
        d = Drive.from_toml(write(tmp_path, DRONE_TEXT.replace("poles = 14", "p = 14")))
    assert d.motor.p == 14  # valid: a warning, not a refusal
    text = str(rec[0].message)
    assert "motor.p: p = 14 pole pairs (28 poles)" in text and "if 14 is the pole count (7 pole pairs" in text
    assert "write poles = 14" in text
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Drive.from_toml(DRONE)  # 7 pole pairs: no warning
        for name in catalog.names():
            catalog.load(name)


def test_motor_from_ratings_is_the_api_of_the_same_conversion() -> None:
    m = Motor.from_ratings(poles=14, R_ll="0.08 Ohm", L_ll="15 uH", KV="1950 rpm/V", shape="sinusoid",
                           V_N=24.0, I_N="30 A")
    assert m == Drive.from_toml(DRONE).motor
    t = Motor.from_ratings(p=7, R=0.04, L=7.5e-6, KV=1950, shape="trapezoid", V_N=24.0, I_N=30.0)
    assert isinstance(t.emf.shapes[0], Trapezoid)
    assert t.emf.shapes[0].k_phi == pytest.approx(15 / (math.pi * 1950), rel=1e-12)
    with pytest.raises(BldclabError) as info:
        Motor.from_ratings(p=7, R=0.04, L=7.5e-6, V_N=24.0, I_N=30.0)
    assert info.value.field == "emf"

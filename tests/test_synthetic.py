"""The synthetic back-EMF generator (bldclab.catalog.synthetic) and the shipped lu-4kw motor file."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from bldclab.errors import BldclabError
from bldclab.model import catalog
from bldclab.model.catalog import synthetic
from bldclab.model.catalog.synthetic import lu4kw_drive, lu4kw_emf, rounded_trapezoid
from bldclab.model.emf import TWO_PI, BackEmf, Table, Trapezoid

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "src" / "bldclab" / "model" / "catalog" / "lu-4kw.toml"
DEG = math.pi / 180.0


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_lu4kw", ROOT / "tools" / "make_lu4kw.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _hann_convolution(shape: Trapezoid, theta: float, corner: float, m: int = 20001) -> float:
    """Brute-force (g * w)(theta), Hann window of width ``corner``, trapezoidal rule on a dense grid."""
    u = np.linspace(-corner / 2, corner / 2, m)
    w = (1.0 + np.cos(TWO_PI * u / corner)) / corner
    return float(np.trapezoid(shape(theta - u) * w, u))


# ----------------------------------------------------------------------------------------------------------
# rounded_trapezoid


def test_no_rounding_no_tilt_is_the_ideal_trapezoid() -> None:
    t = rounded_trapezoid(0.4, n_points=360)
    th = np.asarray(t.theta)
    np.testing.assert_allclose(th, TWO_PI * np.arange(360) / 360, rtol=0, atol=0)
    np.testing.assert_allclose(t.k, Trapezoid(0.4)(th), rtol=0, atol=1e-15)


@pytest.mark.parametrize("corner_deg", [10.0, 40.0, 60.0])
def test_rounding_is_the_hann_convolution(corner_deg: float) -> None:
    """Without tilt there is no realignment, and k_phi keeps its scale: values equal (g * w) exactly."""
    corner = corner_deg * DEG
    t = rounded_trapezoid(1.0, corner=corner, n_points=72)
    ideal = Trapezoid(1.0)
    for theta, k in zip(t.theta, t.k, strict=True):
        assert k == pytest.approx(_hann_convolution(ideal, theta, corner), abs=1e-8)


def test_rounding_only_touches_the_corners() -> None:
    corner = 40 * DEG
    t = rounded_trapezoid(0.4, corner=corner)
    th = np.asarray(t.theta)
    ideal = Trapezoid(0.4)
    offset = np.mod(th[:, None] - ideal.breakpoints()[None, :] + math.pi, TWO_PI) - math.pi
    dist = np.min(np.abs(offset), axis=1)  # to the nearest corner
    far = dist >= corner / 2
    near = dist < corner / 2 - 1e-9
    np.testing.assert_allclose(np.asarray(t.k)[far], ideal(th[far]), rtol=0, atol=1e-15)
    # every corner is convex towards zero: rounding pulls it in
    assert np.all(np.abs(np.asarray(t.k)[near]) < np.abs(ideal(th[near])))


def test_rounded_shape_has_no_kinks() -> None:
    """Second differences: a kink gives h * slope jump, a smooth corner only h^2 * curvature."""
    sharp = np.asarray(rounded_trapezoid(1.0).k)
    smooth = np.asarray(rounded_trapezoid(1.0, corner=40 * DEG).k)

    def d2(k: np.ndarray) -> float:
        return float(np.max(np.abs(np.roll(k, -1) - 2 * k + np.roll(k, 1))))

    assert d2(smooth) < 0.1 * d2(sharp)


@pytest.mark.parametrize(("tilt", "corner_deg"), [(0.08, 40.0), (-0.1, 20.0), (0.3, 0.0)])
def test_tilt_and_convention(tilt: float, corner_deg: float) -> None:
    t = rounded_trapezoid(0.4, corner=corner_deg * DEG, tilt=tilt, n_points=720)
    th, k = np.asarray(t.theta), np.asarray(t.k)
    # motor constant in bldclab's definition
    assert BackEmf.symmetric(t).line_peak() / 2 == pytest.approx(0.4, rel=1e-14)
    # half-wave antisymmetry on the grid
    np.testing.assert_allclose(k[360:], -k[:360], rtol=0, atol=1e-14)
    # fundamental crosses zero rising at theta = 0 (sampling moves it by < 1e-7 rad, sharp corners included)
    a, b = t.fourier(1)
    assert b[1] > 0 and abs(a[1]) < 1e-7 * b[1]
    # the straight middle of the flat top rises by tilt times its mean height over flat_top
    # (the alignment shift phi is the fundamental angle of the unrounded tilted trapezoid, built here anew)
    lo, hi = 1.0 - tilt / 2, 1.0 + tilt / 2
    a, b = Table((30 * DEG, 150 * DEG, 210 * DEG, 330 * DEG), (lo, hi, -lo, -hi)).fourier(1)
    phi = math.atan2(a[1], b[1])
    assert abs(phi) < 10 * DEG  # so [60, 120] deg stays inside the straight part
    mid = (th > 60 * DEG) & (th < 120 * DEG)
    line = np.polyfit(th[mid], k[mid], 1)
    assert np.max(np.abs(k[mid] - np.polyval(line, th[mid]))) < 1e-12
    centre = np.polyval(line, math.pi / 2 + phi)
    assert line[0] * (TWO_PI / 3) / centre == pytest.approx(tilt, rel=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"k_phi": 0.0}, "k_phi"),
        ({"k_phi": float("nan")}, "k_phi"),
        ({"k_phi": True}, "k_phi"),
        ({"flat_top": 0.0}, "flat_top"),
        ({"flat_top": math.pi}, "flat_top"),
        ({"flat_top": "120 deg"}, "flat_top"),
        ({"corner": -0.1}, "corner"),
        ({"corner": 61 * DEG}, "corner"),  # the ramp of a 120-degree trapezoid is 60 degrees wide
        ({"corner": float("inf")}, "corner"),
        ({"tilt": 2.0}, "tilt"),
        ({"tilt": float("nan")}, "tilt"),
        ({"n_points": 2}, "n_points"),
        ({"n_points": 360.0}, "n_points"),
    ],
)
def test_rounded_trapezoid_rejects(kwargs: dict[str, object], field: str) -> None:
    args: dict[str, object] = {"k_phi": 0.4}
    args.update(kwargs)
    with pytest.raises(BldclabError) as info:
        rounded_trapezoid(**args)  # type: ignore[arg-type]
    assert info.value.field == field


# ----------------------------------------------------------------------------------------------------------
# lu4kw_emf and the drive


def test_lu4kw_emf_structure_and_k_phi() -> None:
    emf = lu4kw_emf()
    assert all(isinstance(s, Table) and len(s.theta) == 360 for s in emf.shapes)
    assert emf.shapes[0].theta == emf.shapes[1].theta == emf.shapes[2].theta  # type: ignore[attr-defined]
    assert not emf.is_symmetric
    assert emf.line_peak() / 2 == pytest.approx(synthetic.LU4KW_K_PHI, rel=1e-14)
    for s in emf.shapes:
        k = np.asarray(s.k)  # type: ignore[attr-defined]
        np.testing.assert_allclose(k[180:], -k[:180], rtol=0, atol=1e-14)


def test_lu4kw_phase_mismatch() -> None:
    """Fundamentals: amplitudes in the ratio 1 : 0.97 : 1.025, angles 0, -2 deg (lag), +1.5 deg (lead)."""
    amp, ang = [], []
    for s in lu4kw_emf().shapes:
        a, b = s.fourier(1)
        amp.append(math.hypot(a[1], b[1]))
        ang.append(math.atan2(a[1], b[1]))  # k_1 = A sin(theta + ang)
    np.testing.assert_allclose(np.array(amp) / amp[0], synthetic.LU4KW_AMPLITUDE, rtol=1e-9)
    np.testing.assert_allclose(ang, -np.asarray(synthetic.LU4KW_OFFSET), atol=1e-9)


def test_lu4kw_emf_shape_values() -> None:
    """Rounded, tilted and still a trapezoid: rising flat top, peak a little above k_phi."""
    k = np.asarray(lu4kw_emf().shapes[0].k)  # type: ignore[attr-defined]
    assert k[60] < k[90] < k[120]  # 60, 90, 120 deg: the flat top rises
    assert 0.4 < k.max() < 0.44
    assert k[0] == pytest.approx(0.0, abs=0.02)


def test_lu4kw_drive_numbers() -> None:
    d = lu4kw_drive()
    m = d.motor
    assert (m.p, m.R, m.L, m.V_N) == (2, 0.059, 0.29e-3, 300.0)
    assert m.Omega_N == pytest.approx(3000 * TWO_PI / 60, rel=1e-15)
    assert m.k_phi == pytest.approx(0.4, rel=1e-14)
    assert m.T_N * m.Omega_N == pytest.approx(4000.0, rel=1e-14)  # 4 kW at rated speed and torque
    assert m.I_N == pytest.approx(15.915, abs=1e-3)
    assert d.inverter.V_dc == 300.0 and d.inverter.f_pwm == 10e3
    assert d.sensors.current_phases == "ac"
    # the regime paper 2's D_o mode is for: line back-EMF below the bus, but V_dc < 4 E at rated speed
    E = m.k_phi * m.Omega_N
    assert 2 * E < d.inverter.V_dc < 4 * E
    assert "SYNTHETIC" in d.description


# ----------------------------------------------------------------------------------------------------------
# the shipped file


def test_shipped_file_equals_generator() -> None:
    shipped = catalog.load("lu-4kw")
    generated = lu4kw_drive()
    for s_file, s_gen in zip(shipped.motor.emf.shapes, generated.motor.emf.shapes, strict=True):
        np.testing.assert_allclose(s_file.theta, s_gen.theta, rtol=1e-12, atol=1e-12)  # type: ignore[attr-defined]
        np.testing.assert_allclose(s_file.k, s_gen.k, rtol=1e-12, atol=1e-12)  # type: ignore[attr-defined]
    assert shipped.replace(motor__emf=generated.motor.emf) == generated


def test_shipped_file_is_the_tool_output(tmp_path: Path) -> None:
    tool = _tool()
    assert SHIPPED.read_text(encoding="utf-8") == tool.render()
    assert tool.main(["--check", "-o", str(SHIPPED)]) == 0
    out = tmp_path / "lu.toml"
    assert tool.main(["-o", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == tool.render()
    out.write_text(tool.render().replace("J = 0.005", "J = 0.006"), encoding="utf-8")
    assert tool.main(["--check", "-o", str(out)]) == 1


def test_lu4kw_torque_ripple_under_rectangular_current() -> None:
    """The documented shape ripple: 120-degree rectangular current gives 0.91 .. 1.00 of 2 k_phi I."""
    theta = np.linspace(0.0, TWO_PI, 36_000, endpoint=False)
    k = lu4kw_emf().k_abc(theta)
    # conventions.md: sector s = 0..5 starts at pi/6 + s pi/3 and conducts (a+ b-), (a+ c-), (b+ c-), ...
    pairs = [(0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1)]
    sector = np.floor(np.mod(theta - math.pi / 6, TWO_PI) / (math.pi / 3)).astype(int)
    plus = np.array([pairs[s][0] for s in sector])
    minus = np.array([pairs[s][1] for s in sector])
    j = np.arange(theta.size)
    tau = (k[plus, j] - k[minus, j]) / (2 * synthetic.LU4KW_K_PHI)
    assert tau.max() == pytest.approx(1.0, abs=1e-3)
    assert 0.905 < tau.min() < 0.915
    assert 0.965 < tau.mean() < 0.975

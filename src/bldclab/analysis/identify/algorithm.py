"""Back-EMF identification from a waveform measured at constant speed (paper 2, section III.A).

Paper 2 measures its motor's back-EMF "by the constant speed test" (its Fig. 6, at 1300 rpm) and uses the
shapes ``f_x(theta) = e_x / omega_m`` (its (25)) as tables. :func:`identify` turns such a record (a CSV of
terminal voltages of the open-circuited motor driven at constant speed, optionally with the Hall signals)
into the three per-phase shape tables ``k_x(theta_x)`` in V s/rad of ``docs/conventions.md``, and
:meth:`Identification.drive` puts them into a drive. Pure Python (numpy only); the method, the checks
and their tolerances are in ``docs/identify.md``.

Outline:

1. Read the columns (time ``t`` or electrical angle ``theta``; phase voltages ``v_a, v_b, v_c`` to any
   common reference, or two or three line-to-line voltages; optional Hall signals). Remove the common
   mode: it is unobservable from line-to-line voltages and inert in a star motor without neutral.
2. Find the electrical period from the record itself: the space vector of the three voltages turns by
   exactly 2 pi per period, so ``phi(t + k T) - phi(t) = 2 pi k`` for every ``t``; ``T`` is the root of the
   mean of that residue (no bias from harmonics, any record length of at least one period).
3. Map every sample to its angle ``theta = 2 pi (t - t_0) / T``, pool all periods and estimate each
   phase's periodic mean at any angle by local linear regression over a small angular window (a
   zero-phase smoother that reproduces straight segments exactly; default window +-0.5 deg).
4. Align: electrical angle 0 is where phase a's fundamental crosses zero rising. Evaluate phase x on its
   local angle grid, remove each phase's mean (a back-EMF ``d psi / dt`` of a periodic flux has none) and
   divide by the mechanical speed.
5. Check and report: speed against period, phase sequence and spacing, half-wave asymmetry, offsets,
   noise, and the Hall edges relative to the identified angle (sensor placement errors).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import BldclabError
from ...model.emf import TWO_PI, BackEmf, Table
from ...model.motor import Drive
from ...model.units import to_si
from .smoothing import _Periodic
from .waveform import _PHASES, Waveform, read_waveform, waveform_from_columns

__all__ = [
    "ASYMMETRY_WARN",
    "DEFAULT_WINDOW",
    "MIN_SAMPLES_PER_PERIOD",
    "OFFSET_WARN",
    "SPACING_ERROR",
    "SPACING_WARN",
    "SPEED_ERROR",
    "SPEED_WARN",
    "HallEdges",
    "Identification",
    "identify",
    "observable_emf",
]

DEG = math.pi / 180.0
_RPM = TWO_PI / 60.0

#: Default half-width of the local regression window (rad, electrical): 0.5 deg.
DEFAULT_WINDOW = 0.5 * DEG
#: Fewest samples per electrical period accepted (10 electrical degrees between samples).
MIN_SAMPLES_PER_PERIOD = 36
#: Relative mismatch between the given speed and the measured period that gives a warning.
SPEED_WARN = 0.005
#: Relative mismatch between the given speed and the measured period that is an error.
SPEED_ERROR = 0.02
#: Deviation of a phase's fundamental from its 120-degree place that gives a warning (rad).
SPACING_WARN = 5.0 * DEG
#: Deviation of a phase's fundamental from its 120-degree place that is an error (rad).
SPACING_ERROR = 20.0 * DEG
#: Half-wave asymmetry ``max |k(theta) + k(theta + pi)| / (2 max |k|)`` that gives a warning.
ASYMMETRY_WARN = 0.03
#: A removed per-phase offset (mean voltage) larger than this fraction of the peak gives a warning.
OFFSET_WARN = 0.02
#: Mean Hall edge error beyond which a sensor is reported as misplaced or miswired (rad).
_HALL_WARN = 30.0 * DEG
#: Sum of three line-to-line voltages (rms, relative to theirs) that gives a warning.
_CLOSURE_WARN = 0.05
#: Scatter (standard deviation) of one Hall edge over the periods that gives a warning (rad).
_HALL_JITTER_WARN = 2.0 * DEG


# Column aliases, compared after lower-casing and removing spaces, '_', '-' and '.'.


# ----------------------------------------------------------------------------------------------------------
# the measured record


# ----------------------------------------------------------------------------------------------------------
# periodic local regression


# ----------------------------------------------------------------------------------------------------------
# the result


@dataclass(frozen=True, eq=False)
class HallEdges:
    """Measured Hall edge angles relative to the identified electrical angle.

    Sensor x should switch on at ``theta_e = -pi/6 + x 2 pi/3`` and off half a turn later
    (``docs/conventions.md``); the errors are the measured angles minus those, wrapped to (-pi, pi].

    Attributes
    ----------
    rising, falling : ndarray, shape (3,)
        Mean error of the rising and the falling edges of sensors a, b, c (rad, electrical).
    error : ndarray, shape (3,)
        Placement error of each sensor: the mean of its rising and falling errors (rad). This is what
        ``Sensors.hall_error`` models (it moves both edges of a sensor).
    spread : ndarray, shape (3,)
        Standard deviation of the individual edge errors about their edge's mean (rad): timing jitter and
        the sampling step.
    count : ndarray of int, shape (3,)
        Edges found per sensor.
    invalid_codes : int
        Samples whose code is 0 or 7 (never valid).

    """

    rising: NDArray[np.float64]
    falling: NDArray[np.float64]
    error: NDArray[np.float64]
    spread: NDArray[np.float64]
    count: NDArray[np.int64]
    invalid_codes: int

    def to_dict(self) -> dict[str, Any]:
        """Return the values as JSON-ready lists (rad)."""
        return {"error": _floats(self.error), "rising": _floats(self.rising), "falling": _floats(self.falling),
                "spread": _floats(self.spread), "count": [int(c) for c in self.count],
                "invalid_codes": int(self.invalid_codes)}


def _floats(a: ArrayLike) -> list[float | None]:
    return [None if not math.isfinite(float(x)) else float(x) for x in np.asarray(a, dtype=float).reshape(-1)]


@dataclass(frozen=True, eq=False)
class Identification:
    """Back-EMF shapes identified from a constant-speed record, with what was measured on the way.

    Attributes
    ----------
    theta : ndarray, shape (N,)
        The shared table grid ``2 pi j / N`` (rad): each phase's own local angle.
    k : ndarray, shape (3, N)
        ``k_a, k_b, k_c`` (V s/rad) on their local angles, zero common mode, zero mean.
    omega_m : float
        Mechanical speed the voltages were divided by (rad/s).
    speed_source : str
        ``"given"`` or ``"auto"`` (from the measured period and the pole pairs).
    omega_e : float
        Electrical speed measured from the record (rad/s); NaN for an angle record without time.
    pole_pairs : int or None
        Pole pairs given or implied by ``omega_e / omega_m`` (None if unknown).
    periods : float
        Electrical periods covered by the record.
    samples : int
        Samples in the record.
    samples_per_period : float
        Samples per electrical period.
    window : float
        Half-width of the local regression window (rad, electrical; the median where it was widened).
    theta_e0 : float
        Electrical angle of the first sample in the identified frame (rad, in [0, 2 pi)).
    fundamental : ndarray, shape (3,)
        Amplitude of each phase's fundamental (V s/rad).
    spacing : ndarray, shape (3,)
        Angle of each phase's fundamental minus its ideal place (0, -120, -240 deg behind phase a) (rad);
        0 for phase a by definition.
    offsets : ndarray, shape (3,)
        Mean of each phase's voltage, removed (V): a probe offset (a back-EMF has no mean).
    asymmetry : ndarray, shape (3,)
        Half-wave asymmetry ``max |k(theta) + k(theta + pi)| / (2 max |k|)`` per phase (-).
    noise : float
        RMS scatter of the samples about the identified periodic waveform (V), corrected for the degrees of
        freedom of the regression: the noise of the common-mode-free phase voltages (for independent noise
        on three star-voltage channels, ``sqrt(2/3)`` of a channel's noise).
    peak_voltage : float
        Largest absolute phase voltage of the identified waveform (V).
    hall : HallEdges or None
        Hall edge errors, if the record had Hall columns.
    warnings : tuple of str
        Problems worth knowing that did not stop the identification.
    voltages : str
        ``"phase"`` or ``"line"``: the kind of voltage columns used.
    columns : dict of str to str
        The file's column used for each quantity.
    source : str
        The file (or label) identified.

    """

    theta: NDArray[np.float64]
    k: NDArray[np.float64]
    omega_m: float
    speed_source: str
    omega_e: float
    pole_pairs: int | None
    periods: float
    samples: int
    samples_per_period: float
    window: float
    theta_e0: float
    fundamental: NDArray[np.float64]
    spacing: NDArray[np.float64]
    offsets: NDArray[np.float64]
    asymmetry: NDArray[np.float64]
    noise: float
    peak_voltage: float
    hall: HallEdges | None
    warnings: tuple[str, ...]
    voltages: str
    columns: dict[str, str]
    source: str

    @property
    def emf(self) -> BackEmf:
        """The identified shapes as a :class:`~bldclab.model.emf.BackEmf` of three tables on a shared grid."""
        th = tuple(float(x) for x in self.theta)
        a, b, c = (Table(th, tuple(float(v) for v in kx)) for kx in self.k)
        return BackEmf((a, b, c))

    @property
    def k_phi(self) -> float:
        """Motor constant of the identified shapes (V s/rad): half the peak line-to-line shape."""
        return 0.5 * self.emf.line_peak()

    def drive(self, base: Drive, *, name: str | None = None, description: str | None = None,
              hall_error: bool = False) -> Drive:
        """Return ``base`` with its back-EMF replaced by the identified tables.

        Parameters
        ----------
        base : Drive
            The drive the measured motor belongs to (inverter, mechanics, sensors, R, L, ratings).
        name : str, optional
            Name of the new drive; default ``base.name``.
        description : str, optional
            Its description; default: where the shapes come from and the base drive's name.
        hall_error : bool
            Also set ``sensors.hall_error`` to the measured Hall placement errors (needs Hall columns).

        Returns
        -------
        Drive

        Raises
        ------
        BldclabError
            If the base's pole pairs contradict the record's, or ``hall_error`` is asked without Hall data or
            with an error the plant cannot model (30 degrees or more).

        """
        if not isinstance(base, Drive):
            raise BldclabError("base", f"expected a Drive, got {type(base).__name__}")
        if self.pole_pairs is not None and base.motor.p != self.pole_pairs:
            raise BldclabError("base", f"has p = {base.motor.p} pole pairs, but the record at "
                               f"{self.omega_m:.6g} rad/s has {self.pole_pairs}", self.source)
        if description is None:
            description = (f"Back-EMF identified by bldclab identify from {Path(self.source).name}: "
                           f"{self.samples} samples over {self.periods:.3g} electrical periods at "
                           f"{self.omega_m:.6g} rad/s ({self.omega_m / _RPM:.5g} rpm, {self.speed_source}); "
                           "zero-sequence part removed (unobservable, inert without neutral). Everything else "
                           f"from the base drive {base.name!r}.")
        changes: dict[str, Any] = {"motor__emf": self.emf, "name": base.name if name is None else name,
                                   "description": description}
        if hall_error:
            if self.hall is None:
                raise BldclabError("hall_error", "the record has no Hall columns", self.source)
            bad = np.nonzero(np.abs(self.hall.error) >= math.pi / 6.0)[0]
            if bad.size:
                x = int(bad[0])
                raise BldclabError("hall_error", f"sensor {_PHASES[x]} is {self.hall.error[x] / DEG:.3g} deg off: "
                                   "the plant models errors below 30 deg (check the wiring order)", self.source)
            changes["sensors__hall_error"] = tuple(float(e) for e in self.hall.error)
        return base.replace(**changes)

    def to_dict(self) -> dict[str, Any]:
        """Return everything as JSON-ready values (SI units; angles in rad), tables included."""
        return {
            "source": self.source,
            "voltages": self.voltages,
            "columns": dict(self.columns),
            "samples": self.samples,
            "periods": self.periods,
            "samples_per_period": self.samples_per_period,
            "omega_m": self.omega_m,
            "speed_rpm": self.omega_m / _RPM,
            "speed_source": self.speed_source,
            "omega_e": None if math.isnan(self.omega_e) else self.omega_e,
            "pole_pairs": self.pole_pairs,
            "window": self.window,
            "theta_e0": self.theta_e0,
            "k_phi": self.k_phi,
            "fundamental": _floats(self.fundamental),
            "spacing": _floats(self.spacing),
            "offsets": _floats(self.offsets),
            "asymmetry": _floats(self.asymmetry),
            "noise": self.noise,
            "peak_voltage": self.peak_voltage,
            "hall": None if self.hall is None else self.hall.to_dict(),
            "warnings": list(self.warnings),
            "theta": _floats(self.theta),
            "k_a": _floats(self.k[0]),
            "k_b": _floats(self.k[1]),
            "k_c": _floats(self.k[2]),
        }

    def report(self, tables: bool = True) -> str:
        """Return a plain-text report (and the shape tables in degrees and V s/rad)."""
        out = [f"Back-EMF identified from {self.source}"]
        cols = ", ".join(f"{k}={v}" for k, v in self.columns.items())
        out.append(f"  columns            {self.voltages} voltages ({cols})")
        out.append(f"  samples            {self.samples} over {self.periods:.4g} electrical periods "
                   f"({self.samples_per_period:.4g} per period)")
        out.append(f"  speed              {self.omega_m:.6g} rad/s = {self.omega_m / _RPM:.6g} rpm "
                   f"({self.speed_source})")
        if not math.isnan(self.omega_e):
            pp = f", p = {self.pole_pairs}" if self.pole_pairs is not None else ""
            out.append(f"  electrical period  {TWO_PI / self.omega_e * 1e3:.6g} ms measured "
                       f"(omega_e = {self.omega_e:.6g} rad/s{pp})")
        out.append(f"  k_phi              {self.k_phi:.6g} V s/rad (half the peak line-to-line shape)")
        out.append(f"  window             +-{self.window / DEG:.3g} deg (local linear regression)")
        out.append(f"  noise              {self.noise:.4g} V rms ({100 * self.noise / self.peak_voltage:.3g} % of "
                   f"the {self.peak_voltage:.4g} V peak)")
        start = (self.theta_e0 / DEG + 180.0) % 360.0 - 180.0  # signed: 2 pi - 1e-5 rad printed as 360 deg before
        out.append(f"  theta_e at start   {start:.4g} deg")
        out.append(f"  {'phase':<22}" + "".join(f"{x:>12}" for x in _PHASES))
        out.append("  fundamental (V s/rad) " + "".join(f"{v:12.6g}" for v in self.fundamental))
        out.append("  spacing error (deg)   " + "".join(f"{v / DEG:12.4g}" for v in self.spacing))
        out.append("  offset removed (V)    " + "".join(f"{v:12.4g}" for v in self.offsets))
        out.append("  half-wave asymmetry   " + "".join(f"{v:12.4g}" for v in self.asymmetry))
        if self.hall is not None:
            out.append("  Hall error (deg)      " + "".join(f"{v / DEG:12.4g}" for v in self.hall.error))
            out.append("    rising edges        " + "".join(f"{v / DEG:12.4g}" for v in self.hall.rising))
            out.append("    falling edges       " + "".join(f"{v / DEG:12.4g}" for v in self.hall.falling))
            out.append("    spread (deg)        " + "".join(f"{v / DEG:12.4g}" for v in self.hall.spread))
        for w in self.warnings:
            out.append(f"  warning: {w}")
        if tables:
            out.append("")
            out.append(f"{'theta_x (deg)':>14} {'k_a (V s/rad)':>16} {'k_b (V s/rad)':>16} {'k_c (V s/rad)':>16}")
            for j, th in enumerate(self.theta):
                out.append(f"{th / DEG:14.6g} {self.k[0, j]:16.8g} {self.k[1, j]:16.8g} {self.k[2, j]:16.8g}")
        return "\n".join(out) + "\n"


# ----------------------------------------------------------------------------------------------------------
# identification


def _speed(speed: object) -> float | None:
    """Parse the speed argument: None/"auto" -> None, else rad/s > 0."""
    if speed is None or (isinstance(speed, str) and speed.strip().lower() == "auto"):
        return None
    if isinstance(speed, bool) or not isinstance(speed, str | int | float | np.integer | np.floating):
        raise BldclabError("speed", f"expected a speed such as '1300 rpm', a number in rad/s or 'auto', got "
                           f"{type(speed).__name__}")
    w = to_si(speed if isinstance(speed, str) else float(speed), "speed", "speed")
    if not math.isfinite(w) or w <= 0.0:
        raise BldclabError("speed", f"must be a finite speed > 0 (the test turns forwards), got {speed!r}")
    return w


def _space_angle(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unwrapped angle (rad) of the space vector ``v_a + v_b e^{j 2pi/3} + v_c e^{j 4pi/3}``."""
    a = np.exp(2j * math.pi / 3.0)
    return np.unwrap(np.angle(v[0] + a * v[1] + a * a * v[2]))


def _root(f: Any, lo: float, hi: float, f_lo: float, f_hi: float, xtol: float) -> float:
    """Return a root of ``f`` in [lo, hi] given ``f_lo < 0 < f_hi`` (Illinois false position)."""
    side = 0
    for _ in range(200):
        x = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        fx = f(x)
        if fx == 0.0 or hi - lo <= xtol:
            return x
        if fx < 0.0:
            lo, f_lo = x, fx
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = x, fx
            if side == 1:
                f_lo *= 0.5
            side = 1
    return 0.5 * (lo + hi)


def _period(wf: Waveform) -> tuple[float, float]:
    """Return the electrical period (s) and the periods covered, from the space vector of a time record."""
    t = wf.t
    assert t is not None
    phi = _space_angle(wf.v)
    duration = float(t[-1] - t[0])
    slope = float(np.polyfit(t - t[0], phi, 1)[0])
    if slope == 0.0:
        raise BldclabError("columns", "the voltages do not turn: no back-EMF in the record", wf.source)
    sign = 1.0 if slope > 0 else -1.0
    rough = TWO_PI / abs(slope)
    periods = duration / rough
    if periods < 1.0:
        raise BldclabError(f"column {wf.columns['t']}", f"the record covers only {periods:.3g} electrical "
                           f"periods ({duration:.6g} s of a {rough:.6g} s period): record at least one whole "
                           "period (2-3 recommended)", wf.source)
    spp = wf.n / periods
    if spp < MIN_SAMPLES_PER_PERIOD:
        raise BldclabError(f"column {wf.columns['t']}", f"only {spp:.3g} samples per electrical period (needs at "
                           f"least {MIN_SAMPLES_PER_PERIOD}): sample faster", wf.source)

    def residue(T: float, k: int) -> float:
        sel = t + k * T <= t[-1]
        if not np.any(sel):
            return math.inf
        tt = t[sel]
        return float(np.mean(np.interp(tt + k * T, t, phi) - phi[sel])) - sign * TWO_PI * k

    dt = float(np.median(np.diff(t)))
    lo, hi = 0.8 * rough, min(1.2 * rough, duration - 2.0 * dt)
    f_lo, f_hi = sign * residue(lo, 1), sign * residue(hi, 1) if hi > lo else -math.inf
    if not (hi > lo and f_lo < 0.0 < f_hi):
        raise BldclabError(f"column {wf.columns['t']}", f"cannot find the electrical period: the record covers "
                           f"about {periods:.3g} periods; it needs at least one whole period (2-3 recommended)",
                           wf.source)
    T = _root(lambda T: sign * residue(T, 1), lo, hi, f_lo, f_hi, 1e-12 * rough)
    k = int(duration / (T * 1.0005))
    if k >= 2:  # refine over the longest whole number of periods the record holds
        lo_k, hi_k = T * (1.0 - 0.02 / k), min(T * (1.0 + 0.02 / k), (duration - dt) / k)
        if hi_k > lo_k:
            fk_lo, fk_hi = sign * residue(lo_k, k), sign * residue(hi_k, k)
            if fk_lo < 0.0 < fk_hi:
                T = _root(lambda T: sign * residue(T, k), lo_k, hi_k, fk_lo, fk_hi, 1e-13 * rough)
    return T, duration / T


def _fundamentals(model: _Periodic, h: float) -> tuple[NDArray[np.complex128], NDArray[np.float64]]:
    """Return each phase's mean and fundamental ``c``, ``v(theta) ~ mean + |c| sin(theta + arg c)``.

    From the periodic model on a fine grid (720 points of the measured angle), whatever the table size.
    """
    m = 720
    g = TWO_PI * np.arange(m) / m
    hw = model.window(g, h)
    out = np.empty(3, dtype=complex)
    mean = np.empty(3)
    for x in range(3):
        spec = np.fft.rfft(model(g, hw, x)) / m
        c = 2.0 * spec[1]  # y ~ Re(c e^{j theta}) = |c| cos(theta + arg c)
        out[x] = abs(c) * np.exp(1j * (np.angle(c) + math.pi / 2.0))
        mean[x] = spec[0].real
    return out, mean


def _wrap(a: ArrayLike) -> NDArray[np.float64]:
    """Wrap angles to (-pi, pi]."""
    return -np.mod(-np.asarray(a, dtype=float) + math.pi, TWO_PI) + math.pi


def _hall_edges(wf: Waveform, theta: NDArray[np.float64]) -> tuple[HallEdges, list[str]]:
    """Locate the Hall edges on the identified angle ``theta`` (rad, per sample) and compare to conventions."""
    assert wf.hall is not None and wf.hall_level is not None
    warnings: list[str] = []
    rising = np.full(3, math.nan)
    falling = np.full(3, math.nan)
    spread = np.full(3, math.nan)
    count = np.zeros(3, dtype=np.int64)
    for x in range(3):
        state = wf.hall[x]
        level = wf.hall_level[x]
        idx = np.nonzero(np.diff(state.astype(np.int8)))[0] + 1
        name = wf.columns[f"h_{_PHASES[x]}"]
        if idx.size == 0:
            raise BldclabError(f"column {name}", "never switches over the record: a stuck or disconnected Hall "
                               "sensor; drop the Hall columns to identify the back-EMF alone", wf.source)
        errs: list[list[float]] = [[], []]
        for j in idx:
            # the 50 % crossing between the last sample before the change and the first after it
            i0 = int(j) - 1
            while i0 > 0 and 0.3 <= level[i0] <= 0.7 and state[i0] == state[int(j) - 1]:
                i0 -= 1
            y0, y1 = level[i0], level[j]
            f = (0.5 - y0) / (y1 - y0) if y1 != y0 else 0.5
            f = min(max(f, 0.0), 1.0)
            ang = theta[i0] + f * (theta[j] - theta[i0])
            up = bool(state[j])
            expected = -math.pi / 6.0 + x * TWO_PI / 3.0 + (0.0 if up else math.pi)
            errs[0 if up else 1].append(float(_wrap(ang - expected)))
        count[x] = idx.size
        r = np.asarray(errs[0])
        fl = np.asarray(errs[1])
        rising[x] = float(np.mean(r)) if r.size else math.nan
        falling[x] = float(np.mean(fl)) if fl.size else math.nan
        dev = np.concatenate([r - rising[x] if r.size else r, fl - falling[x] if fl.size else fl])
        spread[x] = float(np.std(dev)) if dev.size > 1 else 0.0
    error = np.array([np.nanmean([rising[x], falling[x]]) for x in range(3)])
    codes = wf.hall[0].astype(int) + 2 * wf.hall[1].astype(int) + 4 * wf.hall[2].astype(int)
    invalid = int(np.count_nonzero((codes == 0) | (codes == 7)))
    for x in range(3):
        name = wf.columns[f"h_{_PHASES[x]}"]
        if abs(error[x]) > _HALL_WARN:
            warnings.append(f"Hall sensor {_PHASES[x]} ({name}) switches {error[x] / DEG:.4g} deg away from its "
                            "place (conventions.md): more than half a sector, so likely another phase's sensor "
                            "(wiring order) or an inverted signal")
        if spread[x] > _HALL_JITTER_WARN:
            warnings.append(f"Hall sensor {_PHASES[x]} ({name}): its edges scatter by {spread[x] / DEG:.3g} deg "
                            "rms over the periods (bouncing signal or speed not constant)")
    if invalid:
        warnings.append(f"{invalid} samples have the invalid Hall code 0 or 7")
    return HallEdges(rising=rising, falling=falling, error=error, spread=spread, count=count,
                     invalid_codes=invalid), warnings


def identify(data: str | Path | Waveform | Mapping[str, ArrayLike], speed: object = "auto", *,
             pole_pairs: int | None = None, points: int = 360, smooth: object = None) -> Identification:
    """Identify the back-EMF shapes from a constant-speed open-circuit record.

    Parameters
    ----------
    data : str, Path, Waveform or mapping
        A CSV file (:func:`~bldclab.analysis.identify.waveform.read_waveform`), a
        :class:`~bldclab.analysis.identify.waveform.Waveform`, or named arrays
        (:func:`~bldclab.analysis.identify.waveform.waveform_from_columns`).
    speed : float, str or None
        Mechanical speed of the test: rad/s, a string with a unit (``"1300 rpm"``, ``"136 rad/s"``), or
        ``"auto"``/None: from the measured electrical period and ``pole_pairs``.
    pole_pairs : int, optional
        Pole pairs ``p``. With a given speed it makes the check of speed against period exact (without it,
        ``omega_e / omega_m`` must be close to a whole number, which becomes ``p``); ``"auto"`` needs it.
    points : int
        Table points per phase, uniform in [0, 2 pi); a multiple of 3, >= 12. Default 360 (1 deg).
    smooth : float or str, optional
        Half-width ``h`` of the local regression window (rad, or a string such as ``"1 deg"``), in
        [0, 30] deg. Default :data:`DEFAULT_WINDOW` (0.5 deg) or 0.75 sample steps if that is wider; any
        window is widened where fewer than 4 samples fall inside. Wider windows average more samples (less
        noise) and round corners more (by at most ``ds h / 4`` for a slope change ``ds``).

    Returns
    -------
    Identification

    Raises
    ------
    BldclabError
        For a file or column problem (naming the column and line), a record shorter than one electrical
        period or with fewer than :data:`MIN_SAMPLES_PER_PERIOD` samples per period, a speed inconsistent
        with the measured period by more than :data:`SPEED_ERROR` (both numbers stated), the phase sequence
        a-c-b ("phases b and c appear swapped"), or a phase more than :data:`SPACING_ERROR` from its
        120-degree place. Lesser problems are returned in ``warnings``.

    """
    if isinstance(data, Waveform):
        wf = data
    elif isinstance(data, str | Path):
        wf = read_waveform(data)
    elif isinstance(data, Mapping) or hasattr(data, "columns"):
        wf = waveform_from_columns(data)
    else:
        raise BldclabError("data", f"expected a CSV path, a Waveform or named columns, got {type(data).__name__}")
    if isinstance(points, bool) or not isinstance(points, int | np.integer) or points < 12 or points % 3:
        raise BldclabError("points", f"must be a whole number >= 12 and a multiple of 3 (the three phases then "
                           f"share their grid angles and the tables sum to zero exactly), got {points!r}")
    points = int(points)
    if pole_pairs is not None and (isinstance(pole_pairs, bool) or not isinstance(pole_pairs, int | np.integer)
                                   or pole_pairs < 1):
        raise BldclabError("pole_pairs", f"must be a whole number >= 1, got {pole_pairs!r}")
    omega_given = _speed(speed)
    h_user: float | None = None
    if smooth is not None:
        h_user = to_si(smooth if isinstance(smooth, str) else float(smooth), "angle", "smooth")  # type: ignore[arg-type]  # to_si rejects a non-number
        if not math.isfinite(h_user) or not 0.0 <= h_user <= math.pi / 6.0:
            raise BldclabError("smooth", f"must be an angle in [0, 30] deg, got {smooth!r}")
    if float(np.max(np.abs(wf.v))) == 0.0:
        raise BldclabError("columns", "all voltages are zero (after removing the common mode): no back-EMF",
                           wf.source)
    warnings: list[str] = []
    if wf.closure > _CLOSURE_WARN:
        warnings.append(f"the three line-to-line voltages do not sum to zero: their sum is {100 * wf.closure:.3g} % "
                        "of their rms (a probe gain, sign or channel mix-up?); they are fitted in the least-squares "
                        "sense")

    # 1. angle of every sample (rad, electrical, starting at 0) and the measured electrical speed
    omega_e = math.nan
    if wf.theta is not None:
        theta = wf.theta - wf.theta[0]
        periods = float(theta[-1] / TWO_PI)
        phi = _space_angle(wf.v)
        turns = abs(float(phi[-1] - phi[0])) / max(float(theta[-1]), 1e-300)
        if turns > 1.5:  # the voltages turn k times per electrical turn of the column: a shaft (mechanical) angle
            raise BldclabError(f"column {wf.columns['theta']}", f"the voltages go through {turns:.3g} periods while "
                               "this angle advances by one: it reads as a mechanical angle (of a motor with "
                               f"{round(turns)} pole pairs?); give the electrical angle theta_e = p theta_m, or a "
                               "time column", wf.source)
        if periods < 1.0:
            raise BldclabError(f"column {wf.columns['theta']}", f"the record covers only {periods:.3g} electrical "
                               "periods: record at least one whole period (2-3 recommended)", wf.source)
        spp = wf.n / periods
        if spp < MIN_SAMPLES_PER_PERIOD:
            raise BldclabError(f"column {wf.columns['theta']}", f"only {spp:.3g} samples per electrical period "
                               f"(needs at least {MIN_SAMPLES_PER_PERIOD}): sample more densely", wf.source)
        if wf.t is not None:
            omega_e = float(np.polyfit(wf.t - wf.t[0], theta, 1)[0])
    else:
        T, periods = _period(wf)
        omega_e = TWO_PI / T
        assert wf.t is not None
        theta = omega_e * (wf.t - wf.t[0])
        spp = wf.n / periods

    # 2. speed and pole pairs
    p = None if pole_pairs is None else int(pole_pairs)
    if omega_given is None:
        if math.isnan(omega_e):
            raise BldclabError("speed", "'auto' needs a time column to measure the period; give the speed",
                               wf.source)
        if p is None:
            raise BldclabError("speed", f"'auto' needs the pole pairs (--pole-pairs or --base) to turn the "
                               f"measured electrical speed {omega_e:.6g} rad/s into a mechanical one", wf.source)
        omega_m = omega_e / p
        speed_source = "auto"
    else:
        omega_m = omega_given
        speed_source = "given"
        if not math.isnan(omega_e):
            period_ms = TWO_PI / omega_e * 1e3
            if p is None:
                ratio = omega_e / omega_m
                near = max(round(ratio), 1)
                if abs(ratio / near - 1.0) > SPEED_ERROR:
                    raise BldclabError("speed", f"the measured electrical period {period_ms:.6g} ms "
                                       f"(omega_e = {omega_e:.6g} rad/s) and the speed {omega_m:.6g} rad/s "
                                       f"({omega_m / _RPM:.6g} rpm) give p = {ratio:.4g} pole pairs, not a whole "
                                       "number: wrong speed? (give the pole pairs for an exact check)", wf.source)
                p = near
            expected_ms = TWO_PI / (p * omega_m) * 1e3
            mismatch = expected_ms / period_ms - 1.0
            if abs(mismatch) > SPEED_ERROR:
                raise BldclabError("speed", f"the measured electrical period is {period_ms:.6g} ms "
                                   f"({omega_e / p / _RPM:.6g} rpm with p = {p}) but the speed {omega_m:.6g} rad/s "
                                   f"({omega_m / _RPM:.6g} rpm) gives {expected_ms:.6g} ms: they differ by "
                                   f"{100 * mismatch:+.3g} % (tolerance {100 * SPEED_ERROR:g} %)", wf.source)
            if abs(mismatch) > SPEED_WARN:
                warnings.append(f"the speed {omega_m / _RPM:.6g} rpm and the measured period {period_ms:.6g} ms "
                                f"({omega_e / p / _RPM:.6g} rpm) differ by {100 * mismatch:+.3g} %: the shapes are "
                                "scaled with the given speed")

    # 3. periodic model: local linear regression over the pooled periods
    step = float(np.median(np.diff(theta)))
    h = h_user if h_user is not None else max(DEFAULT_WINDOW, 0.75 * step)
    h = max(h, 1e-9)
    model = _Periodic(theta, wf.v)
    fund, offsets = _fundamentals(model, h)
    pos = (fund[0] + fund[1] * np.exp(2j * math.pi / 3) + fund[2] * np.exp(4j * math.pi / 3)) / 3.0
    neg = (fund[0] + fund[1] * np.exp(-2j * math.pi / 3) + fund[2] * np.exp(-4j * math.pi / 3)) / 3.0
    if abs(neg) > abs(pos):
        names = ", ".join(wf.columns.get(f"v_{q}", "") for q in (("b", "c") if wf.voltages == "phase"
                                                                  else ("ab", "bc", "ca")) if f"v_{q}" in wf.columns)
        raise BldclabError("phases", "phases b and c appear swapped: phase b leads phase a by 120 deg instead "
                           f"of lagging it (sequence a-c-b); swap the columns {names} (or any two phases), "
                           "or check that the test turned forwards", wf.source)
    phi_a = float(np.angle(fund[0]))
    spacing = np.array([0.0, *(_wrap(np.angle(fund[x]) - phi_a + x * TWO_PI / 3.0) for x in (1, 2))])
    worst = int(np.argmax(np.abs(spacing)))
    if abs(spacing[worst]) > SPACING_ERROR:
        raise BldclabError("phases", f"phase {_PHASES[worst]}'s fundamental is {spacing[worst] / DEG:+.3g} deg from "
                           f"its place {120 * worst} deg behind phase a (tolerance {SPACING_ERROR / DEG:g} deg): "
                           "a wiring or probe mix-up?", wf.source)
    for x in (1, 2):
        if abs(spacing[x]) > SPACING_WARN:
            warnings.append(f"phase {_PHASES[x]}'s fundamental is {spacing[x] / DEG:+.3g} deg from its place "
                            f"{120 * x} deg behind phase a (more than {SPACING_WARN / DEG:g} deg)")

    # 4. tables on each phase's local angle; electrical angle 0 where phase a's fundamental crosses zero rising
    grid = TWO_PI * np.arange(points) / points
    volts = np.empty((3, points))
    widths = []
    for x in range(3):
        g = grid + x * TWO_PI / 3.0 - phi_a  # measured angle of local angle grid[j] of phase x
        hw = model.window(g, h)
        widths.append(hw)
        volts[x] = model(g, hw, x)
    volts = volts - offsets[:, None]  # the waveform's mean (not the grid's: a coarse grid aliases harmonics)
    peak_v = float(np.max(np.abs(volts)))
    for x in range(3):
        if abs(offsets[x]) > OFFSET_WARN * peak_v:
            warnings.append(f"phase {_PHASES[x]} had a mean of {offsets[x]:.4g} V ({100 * offsets[x] / peak_v:+.3g} % "
                            "of the peak), removed: a probe offset? (a back-EMF has no mean)")
    k = volts / omega_m
    asym = np.empty(3)
    for x in range(3):
        shifted = np.interp(np.mod(grid + math.pi, TWO_PI), grid, k[x], period=TWO_PI)
        asym[x] = float(np.max(np.abs(k[x] + shifted)) / (2.0 * np.max(np.abs(k[x]))))
        if asym[x] > ASYMMETRY_WARN:
            warnings.append(f"phase {_PHASES[x]} is not half-wave antisymmetric: max |k(theta) + k(theta + 180 deg)| "
                            f"is {100 * asym[x]:.3g} % of twice its peak (uneven magnets, or a probe problem?)")

    # 5. diagnostics: noise, line-voltage closure, Hall edges
    samp_w = model.window(theta, h)
    resid = np.concatenate([wf.v[x] - model(theta, samp_w, x) for x in range(3)])
    dof = 3.0 * float(np.sum(1.0 - model.self_weight(theta, samp_w)))  # residual degrees of freedom
    noise = float(np.sqrt(np.sum(resid * resid) / max(dof, 1.0)))
    theta_e = theta + phi_a
    hall = None
    if wf.hall is not None:
        hall, hall_warn = _hall_edges(wf, theta_e)
        warnings.extend(hall_warn)
    return Identification(
        theta=grid, k=k, omega_m=float(omega_m), speed_source=speed_source, omega_e=float(omega_e), pole_pairs=p,
        periods=float(periods), samples=wf.n, samples_per_period=float(spp),
        window=float(np.median(np.concatenate(widths))), theta_e0=float(np.mod(phi_a, TWO_PI)),
        fundamental=np.abs(fund) / omega_m, spacing=spacing, offsets=offsets, asymmetry=asym, noise=noise,
        peak_voltage=peak_v, hall=hall, warnings=tuple(warnings), voltages=wf.voltages, columns=dict(wf.columns),
        source=wf.source)


def observable_emf(emf: BackEmf, points: int = 360) -> tuple[BackEmf, float]:
    """Return what a perfect terminal measurement of ``emf`` identifies, and the angle frame shift.

    Terminal voltages of a star motor without neutral see neither the common mode (zero sequence) of the
    three shapes nor a mean; and :func:`identify` puts electrical angle 0 where the fundamental of phase a's
    *observable* (zero-sequence-free) shape crosses zero rising. For an asymmetric motor that frame differs
    from one defined with the full shape by the zero-sequence fundamental's effect on phase a.

    Parameters
    ----------
    emf : BackEmf
        The true shapes.
    points : int
        Table points per phase (a multiple of 3).

    Returns
    -------
    BackEmf
        Tables ``k_x(theta_x)`` on ``points`` uniform angles: zero common mode, zero mean, in the identified
        frame.
    float
        Frame shift ``delta`` (rad): an angle ``theta_e`` of the original frame is ``theta_e + delta`` in the
        identified one (so a Hall sensor with placement error ``err`` is measured at ``err + delta``).

    """
    if isinstance(points, bool) or not isinstance(points, int | np.integer) or points < 12 or points % 3:
        raise BldclabError("points", f"must be a whole number >= 12 and a multiple of 3, got {points!r}")
    m = 7200
    th = TWO_PI * np.arange(m) / m
    k = emf.k_abc(th)
    a0 = k[0] - k.mean(axis=0)
    c = 2.0 * np.fft.rfft(a0)[1] / m
    delta = float(np.angle(c) + math.pi / 2.0)  # a0 ~ A sin(theta + delta)
    grid = TWO_PI * np.arange(points) / points
    means = np.mean(k - k.mean(axis=0), axis=1)  # a mean is the same in any frame
    tables = []
    for x in range(3):
        kk = emf.k_abc(grid + x * TWO_PI / 3.0 - delta)  # all phases at the electrical angles of phase x's grid
        kx = kk[x] - kk.mean(axis=0)
        mean = float(means[x])
        tables.append(Table(tuple(float(g) for g in grid), tuple(float(v) for v in kx - mean)))
    return BackEmf((tables[0], tables[1], tables[2])), delta


# ----------------------------------------------------------------------------------------------------------
# synthetic measurements (the simulator as the test bench) and the shipped sample


# ----------------------------------------------------------------------------------------------------------
# command line (registered in bldclab.cli)



"""Synthetic measurements for :func:`~bldclab.analysis.identify.algorithm.identify`: the simulator as the test bench.

:func:`synthetic_measurement` runs a drive open-circuited at constant speed and samples its terminal voltages
and Hall signals as a scope would (range, resolution, noise); :func:`sample_path` is the shipped sample record.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ...control import OpenLoop
from ...errors import BldclabError
from ...model.emf import TWO_PI
from ...model.motor import Drive
from ...sim import Scenario, simulate
from .waveform import _PHASES

__all__ = [
    "SAMPLE_FILE",
    "sample_path",
    "synthetic_measurement",
]


#: The sample measurement shipped with the package (``bldclab/data``); see :func:`sample_path`.
SAMPLE_FILE = "lu4kw_backemf_1300rpm.csv"


def sample_path() -> Path:
    """Return the path of the shipped sample record :data:`SAMPLE_FILE` (``bldclab/data``)."""
    return Path(str(resources.files("bldclab") / "data" / SAMPLE_FILE))


def _scope_range(peak: float) -> float:
    """Return a scope's full-scale span (V) for a signal of this peak: 8 divisions of a 1-2-5 V/div step."""
    for decade in range(-3, 5):
        for mant in (1.0, 2.0, 5.0):
            per_div = mant * 10.0**decade
            if 8.0 * per_div >= 2.2 * peak:
                return 8.0 * per_div
    return 8.0 * 1e5


def synthetic_measurement(drive: Drive, speed: float, *, periods: float = 2.6, f_sample: float = 50e3,
                          theta0: float = 1.0, t_start: float = 0.0, noise: float = 0.005, bits: int = 12,
                          line_to_line: bool = False, hall: bool = True, hall_volts: float | None = None,
                          seed: int = 1) -> dict[str, NDArray[np.float64]]:
    """Simulate the constant-speed open-circuit test of a drive, as a scope would record it.

    The drive turns at the imposed ``speed`` with every inverter leg off (no current), in bldclab's C
    simulator. The scope samples at ``f_sample`` (rounded to a multiple of the PWM frequency: the trace
    runs on the controller's sample grid). Each voltage sample is the mean over its sampling interval
    (an anti-aliased scope), time-stamped at the interval's centre; the Hall states are those at that
    instant. Voltages are to an artificial star point (``v_x`` minus the mean of the three), or
    line-to-line; then Gaussian noise of ``noise`` times the peak and a ``bits``-bit quantiser over a
    1-2-5 scope range fitting the signal. Hall signals are 0/1 (a mixed-signal scope's digital channels),
    or analog logic levels 0 / ``hall_volts`` with 1 % noise.

    Parameters
    ----------
    drive : Drive
        The drive (its ``sensors.hall_error`` and ``hall_delay`` move the Hall edges).
    speed : float
        Mechanical speed (rad/s), > 0, low enough that the line-to-line back-EMF stays below the DC bus
        (or the diodes conduct and it is no longer an open-circuit test).
    periods : float
        Electrical periods recorded.
    f_sample : float
        Scope sampling frequency (Hz).
    theta0 : float
        Electrical angle at the start (rad).
    t_start : float
        Time stamp of the start of the record (s); a scope's pre-trigger makes it negative.
    noise : float
        Standard deviation of the voltage noise as a fraction of the peak voltage (-).
    bits : int
        Quantiser resolution (0: none).
    line_to_line : bool
        Record ``v_ab, v_bc, v_ca`` instead of the star voltages ``v_a, v_b, v_c``.
    hall : bool
        Record the Hall signals ``h_a, h_b, h_c``.
    hall_volts : float, optional
        Record the Hall signals as analog levels 0 / ``hall_volts`` (V) with noise and quantisation
        instead of 0/1.
    seed : int
        Seed of the noise generator.

    Returns
    -------
    dict of str to ndarray
        Columns ``t`` (s), the voltages (V) and the Hall signals, ready for
        :func:`~bldclab.analysis.identify.waveform.waveform_csv` or
        :func:`~bldclab.analysis.identify.algorithm.identify`.

    Raises
    ------
    BldclabError
        If an argument is out of range, or a current flows (speed too high for an open-circuit test).

    """
    for name, value, lo in (("speed", speed, 0.0), ("periods", periods, 0.0), ("f_sample", f_sample, 0.0),
                            ("noise", noise, -1e-300)):
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= lo:
            raise BldclabError(name, f"must be a finite number > {max(lo, 0.0):g}, got {value!r}")
    sub = max(1, round(f_sample / drive.inverter.f_pwm))
    T_e = TWO_PI / (drive.motor.p * speed)
    off = OpenLoop(np.zeros((1, 3), dtype=int), np.zeros((1, 3)))
    # two trace rows per scope sample: the pair's mean is the voltage, the second row's start its centre
    res = simulate(drive, off, Scenario(duration=periods * T_e, speed=speed, theta0=theta0, trace_sub=sub))
    s = res.signals
    if float(np.max(np.abs(np.stack([s["i_a"], s["i_b"], s["i_c"]])))) > 0.0:
        raise BldclabError("speed", f"{speed:.6g} rad/s drives current through the diodes (peak line-to-line "
                           "back-EMF above the DC bus): not an open-circuit test; choose a lower speed")
    n = s["t"].size // 2
    t = s["t"][1:2 * n:2]
    v = np.stack([0.5 * (s[f"v_{x}"][0:2 * n:2] + s[f"v_{x}"][1:2 * n:2]) for x in _PHASES])
    v = v - v.mean(axis=0)
    rng = np.random.default_rng(seed)
    cols: dict[str, NDArray[np.float64]] = {"t": t - t[0] + t_start}
    if line_to_line:
        names, sig = ("v_ab", "v_bc", "v_ca"), np.stack([v[0] - v[1], v[1] - v[2], v[2] - v[0]])
    else:
        names, sig = ("v_a", "v_b", "v_c"), v
    peak = float(np.max(np.abs(sig)))
    span = _scope_range(peak)
    sig = sig + rng.normal(0.0, noise * peak, sig.shape)
    if bits:
        lsb = span / 2.0**bits
        sig = np.clip(np.round(sig / lsb) * lsb, -span / 2.0, span / 2.0 - lsb)
    for name, y in zip(names, sig, strict=True):
        cols[name] = y
    if hall:
        code = s["hall"][1:2 * n:2].astype(np.int64)
        for x in range(3):
            level = ((code >> x) & 1).astype(float)
            if hall_volts is not None:
                level = hall_volts * level + rng.normal(0.0, 0.01 * hall_volts, code.size)
                if bits:
                    lsb = _scope_range(hall_volts) / 2.0**bits
                    level = np.round(level / lsb) * lsb
            cols[f"h_{_PHASES[x]}"] = level
    return cols

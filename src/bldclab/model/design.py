"""Controller design helpers: PI gains from a bandwidth and a phase margin.

Paper 1 designs its d,q current regulators for a 1 kHz bandwidth and 90 degrees of phase margin on the Bode
diagram, then discretises them with the Euler method. :func:`pi_gains` does that design for the R-L plant of a
current loop, optionally including the loop's dead time (one sample of computation plus half a sample of PWM),
and returns the continuous gains that ``bc_pi`` discretises (``x += k_i T_s e``). :func:`max_bandwidth` gives the
highest bandwidth such a design reaches with a given loop delay (a slow PWM leaves less than 1 kHz).
"""

from __future__ import annotations

import math

from ..errors import BldclabError

__all__ = ["max_bandwidth", "pi_gains"]


def pi_gains(R: float, L: float, bandwidth_hz: float, phase_margin_deg: float = 90.0,
             delay: float = 0.0) -> tuple[float, float]:
    """PI gains placing the crossover of ``C(s) G(s)`` at the bandwidth with the given phase margin.

    Plant ``G(s) = exp(-s delay) / (R + s L)``, controller ``C(s) = k_p + k_i / s``. At the crossover
    ``w_c = 2 pi bandwidth_hz``: ``|C G| = 1`` and ``arg C G = -pi + PM``. With ``delay = 0`` and PM = 90 deg this is
    the pole-zero cancellation design ``k_p = w_c L``, ``k_i = w_c R``.

    Parameters
    ----------
    R : float
        Loop resistance (Ohm), >= 0 (for a line current in square-wave supply: 2 R of a phase).
    L : float
        Loop inductance (H), > 0.
    bandwidth_hz : float
        Crossover frequency (Hz), > 0.
    phase_margin_deg : float
        Phase margin (deg), in (0, 180).
    delay : float
        Loop dead time (s), >= 0; e.g. ``1.5 T_s`` for one-sample computation delay and PWM.

    Returns
    -------
    k_p : float
        Proportional gain (V/A).
    k_i : float
        Integral gain (V/(A s)).

    Raises
    ------
    BldclabError
        For out-of-range arguments, or when a PI cannot give this phase margin at this bandwidth (the plant and delay
        already lag more than allowed).
    """
    for name, v in (("R", R), ("L", L), ("bandwidth_hz", bandwidth_hz), ("phase_margin_deg", phase_margin_deg),
                    ("delay", delay)):
        if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
            raise BldclabError(name, f"must be a finite number, got {v!r}")
    if R < 0 or L <= 0 or bandwidth_hz <= 0 or delay < 0 or not 0 < phase_margin_deg < 180:
        raise BldclabError("pi_gains", "needs R >= 0, L > 0, bandwidth > 0, delay >= 0, 0 < margin < 180 deg")
    wc = 2.0 * math.pi * bandwidth_hz
    pm = math.radians(phase_margin_deg)
    # phase the PI may take away: -atan(k_i / (k_p w_c)) = -pi + pm + atan(w_c L / R) + w_c delay
    phi = math.pi - pm - math.atan2(wc * L, R) - wc * delay
    if phi < -1e-12 or phi >= math.pi / 2:
        raise BldclabError("phase_margin_deg", f"a PI cannot give {phase_margin_deg:g} deg at {bandwidth_hz:g} Hz "
                           f"with {delay * 1e6:.3g} us delay (the plant lags {math.degrees(math.pi - pm - phi):.1f} "
                           "deg there)")
    phi = max(phi, 0.0)
    kp = math.cos(phi) * math.hypot(R, wc * L)
    ki = kp * wc * math.tan(phi)
    return kp, ki


#: :func:`max_bandwidth`'s default ratio of the PI zero ``k_i / k_p`` to the crossover: a tenth, the usual placement
#: a decade below (the PI then lags ``atan(0.1)`` = 5.7 deg at the crossover and still integrates).
PI_ZERO_RATIO = 0.1


def max_bandwidth(R: float, L: float, phase_margin_deg: float, delay: float,
                  zero_ratio: float = PI_ZERO_RATIO) -> float:
    """Highest crossover (Hz) at which :func:`pi_gains` gives the phase margin with integral action left.

    The plant ``exp(-s delay) / (R + s L)`` lags ``atan(w L / R) + w delay``, rising with ``w``; a PI whose zero
    ``k_i / k_p`` sits at ``zero_ratio`` times the crossover lags ``atan(zero_ratio)`` more. The crossover solves
    ``atan(w_c L / R) + w_c delay + atan(zero_ratio) = pi - PM`` (bisection). Above it a PI can only give the margin
    with a zero closer to the crossover, and beyond ``atan(w_c L / R) + w_c delay = pi - PM`` not at all.

    Parameters
    ----------
    R : float
        Loop resistance (Ohm), >= 0.
    L : float
        Loop inductance (H), > 0.
    phase_margin_deg : float
        Phase margin (deg), in (0, 180).
    delay : float
        Loop dead time (s), >= 0.
    zero_ratio : float
        PI zero over crossover, > 0.

    Returns
    -------
    float
        Bandwidth (Hz); infinite without delay when the plant never lags enough (``R = 0`` or large margins aside).

    Raises
    ------
    BldclabError
        If no crossover gives the margin (the margin and the PI's lag alone exceed 180 deg).
    """
    for name, v in (("R", R), ("L", L), ("phase_margin_deg", phase_margin_deg), ("delay", delay),
                    ("zero_ratio", zero_ratio)):
        if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
            raise BldclabError(name, f"must be a finite number, got {v!r}")
    if R < 0 or L <= 0 or delay < 0 or zero_ratio <= 0 or not 0 < phase_margin_deg < 180:
        raise BldclabError("max_bandwidth", "needs R >= 0, L > 0, delay >= 0, zero_ratio > 0, 0 < margin < 180 deg")
    budget = math.pi - math.radians(phase_margin_deg) - math.atan(zero_ratio)

    def lag(w: float) -> float:
        return math.atan2(w * L, R) + w * delay

    if budget <= lag(0.0):
        raise BldclabError("phase_margin_deg", f"a PI cannot give {phase_margin_deg:g} deg at any bandwidth")
    if delay == 0.0 and budget >= math.pi / 2:
        return math.inf
    lo, hi = 0.0, 1.0
    while lag(hi) < budget:
        lo, hi = hi, 2.0 * hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if lag(mid) < budget:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-12 * hi:
            break
    return lo / (2.0 * math.pi)

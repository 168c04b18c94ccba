"""Run the six-edge Hall calibration (:class:`~bldclab.control.HallCal`) in closed loop with the plant.

``calibrate(drive)`` simulates the C routine exactly as firmware would run it and returns the table it learned
(``docs/hall-calibration.md``). It lives in the simulation layer because it runs :func:`bldclab.simulate`; the
controller and the result type are in :mod:`bldclab.control.hallcal`.
"""

from __future__ import annotations

import math
from typing import Literal

from ..control.hallcal import HallCal, HallCalibration, read_calibration
from ..errors import BldclabError
from ..model.motor import Drive
from . import Scenario, simulate

__all__ = ["calibrate"]


def calibrate(drive: Drive, method: Literal["constant-speed", "open-loop"] = "constant-speed", *,
              revolutions: int = 3, speed: float | None = None, routine: HallCal | None = None,
              theta0: float = 0.3) -> HallCalibration:
    """Calibrate the Hall edges of a drive with the C routine, simulated with the plant.

    Parameters
    ----------
    drive : Drive
        The drive (its ``sensors.hall_error`` are the misplacements to find).
    method : {"constant-speed", "open-loop"}
        ``constant-speed``: the rotor is turned at the imposed ``speed`` (a dynamometer), legs off, for
        ``revolutions`` electrical revolutions plus two; ``open-loop``: the rotor is free and follows the
        routine's slowly turning voltage vector (forward, then backward).
    revolutions : int
        Electrical revolutions averaged (per direction for ``open-loop``).
    speed : float, optional
        ``constant-speed``: mechanical speed (rad/s); default ``0.3 Omega_0``.
    routine : HallCal, optional
        The routine's settings (its ``method`` and ``revolutions`` are replaced by the arguments above).
    theta0 : float
        Initial electrical angle of the rotor (rad).

    Returns
    -------
    HallCalibration
        The table (nominal angles unless ``ok``) and the status.

    Raises
    ------
    BldclabError
        For an unknown method or a non-positive speed.
    """
    if method not in ("constant-speed", "open-loop"):
        raise BldclabError("method", f"must be constant-speed or open-loop, got {method!r}")
    base = routine if routine is not None else HallCal()
    w = 0.3 * drive.Omega_0 if speed is None else speed
    if isinstance(w, bool) or not isinstance(w, int | float) or not math.isfinite(w) or w == 0:
        raise BldclabError("speed", f"must be a finite non-zero speed (rad/s), got {w!r}")
    if method == "constant-speed":
        t_rev = 2.0 * math.pi / (abs(w) * drive.motor.p)
        duration = (revolutions + 2.5) * t_rev
        ctl = HallCal(method=method, revolutions=revolutions, speed_tolerance=base.speed_tolerance,
                      timeout=max(base.timeout, duration))
        sc = Scenario(duration=duration, speed=float(w), theta0=theta0)
    else:
        ctl = HallCal(method=method, revolutions=revolutions, align_current=base.align_current,
                      vector_speed=base.vector_speed, align_time=base.align_time, lag_max=base.lag_max)
        sc = Scenario(duration=ctl.duration() + 0.01, theta0=theta0)
    res = simulate(drive, ctl, sc, check="off")
    return read_calibration(res, method)

"""Fault injection: what a controller detects, how fast it reaches its safe state, and the peak current.

Each fault of :func:`default_faults` is injected at ``t_fault`` into a drive running at an imposed speed with its
nominal reference. From the controller's flags (``BC_FLAG_*`` in ``bc_types.h``) the report gives whether and
when it detected something, when its legs went off (safe state), and the largest phase current after the fault
compared with the controller's over-current trip. Faults no controller can see from its measurements (a current
sensor offset, a DC-bus sag within range, a misplaced Hall edge) are reported as not detected: that is the
finding, not a failure of the experiment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .._core import core
from ..control import Control
from ..model.motor import Drive
from ..sim import Fault, Scenario, simulate
from .experiments import electrical_period

__all__ = ["FaultCase", "default_faults", "detection_notes", "fault_table", "stall_current"]

#: The controller flags that mean "fault detected" (``bc_types.h`` names; their values come from the library) and
#: how the table names them
_DETECT = {"BC_FLAG_HALL_INVALID": "hall-invalid", "BC_FLAG_OVERCURRENT": "over-current",
           "BC_FLAG_BAD_INPUT": "bad-input"}


@dataclass(frozen=True)
class FaultCase:
    """One fault experiment.

    Attributes
    ----------
    name : str
        Short name.
    faults : tuple of Fault
        Faults injected (:class:`bldclab.Fault`), relative to ``t_fault``: their ``t_on`` is added to it.
    v_dc_factor : float
        DC source voltage after ``t_fault`` in per unit of the nominal (a sag), 1 for none.
    hall_error_a : float
        Angle error of Hall sensor a from the start (rad), 0 for none (a misplaced edge).
    """

    name: str
    faults: tuple[Fault, ...] = ()
    v_dc_factor: float = 1.0
    hall_error_a: float = 0.0


def default_faults() -> list[FaultCase]:
    """Return the fault list of the report: every kind the simulator injects."""
    return [
        FaultCase("none"),
        FaultCase("hall a stuck at 0", (Fault("hall_stuck", "a", 0.0, value=0.0),)),
        FaultCase("hall a stuck at 1", (Fault("hall_stuck", "a", 0.0, value=1.0),)),
        FaultCase("hall b glitch 50 us", (Fault("hall_glitch", "b", 0.0, t_off=50e-6),)),
        FaultCase("hall a misplaced 20 deg", hall_error_a=math.radians(20.0)),
        FaultCase("current a offset +20 % I_N", (Fault("current_offset", "a", 0.0, value=0.0),)),
        FaultCase("current sensor a lost", (Fault("current_loss", "a", 0.0),)),
        FaultCase("DC bus sag to 60 %", v_dc_factor=0.6),
        FaultCase("phase b open", (Fault("phase_open", "b", 0.0),)),
    ]


def stall_current(drive: Drive) -> float:
    """Return the largest current the bus can drive through the windings of a rotor at rest (A).

    One phase against the other two in parallel (an inverter vector such as 100), ``V_dc / (1.5 (R + R_on))``: no
    back-EMF, so only the resistance limits it (two phases in series, the six-step pair, ``V_dc / (2 (R + R_on))``).
    """
    return drive.inverter.V_dc / (1.5 * (drive.motor.R + drive.inverter.R_on))


def detection_notes(drive: Drive, i_max: float, open_detect: float = 0.0) -> list[str]:
    """Say which faults the controllers cannot detect on this drive, and why, from its data.

    The controllers' general detections are an invalid Hall code, a bad input (non-finite, bus out of range) and an
    over-current on the measured currents (``i_max``); a lost current sensor and an open phase are detected by them
    only through an over-current they cause. Where the windings' resistance keeps every current at or below
    ``i_max`` that cannot happen (a high-resistance gimbal motor: 12 V, 10 Ohm, 0.4 A rated, ``i_max = 2 I_N =
    0.8 A`` = the stall current ``V_dc / (1.5 R)``). The six-step controller's no-current-path test
    (``SixStep(open_detect=f)``) detects both without an over-current, where the bus has a voltage margin over the
    back-EMF.

    Parameters
    ----------
    drive : Drive
    i_max : float
        The controller's over-current trip (A).
    open_detect : float
        The controller's no-current-path test (``SixStep.open_detect``; 0: none).

    Returns
    -------
    list of str
        Notes, each led by its name (``faults.overcurrent_unreachable``, ``faults.lost_sensor``,
        ``faults.open_phase``, or ``faults.open_detect`` with the test on).
    """
    if open_detect > 0.0:
        return [f"faults.open_detect: the six-step controller's no-current-path test (f = {open_detect:g}) detects a "
                f"lost current sensor and an open phase without an over-current: a current below f I_ref at full "
                f"voltage for twice the time the windings need to pass 2 f I_ref; it cannot where the bus has no "
                f"margin over the back-EMF (near Omega_0), before the Hall speed is valid, or where that time "
                f"exceeds a commutation sector"]
    notes = []
    i_stall = stall_current(drive)
    if i_stall <= i_max:
        notes.append(f"faults.overcurrent_unreachable: the windings limit every current the bus can drive at "
                     f"standstill to V_dc / (1.5 (R + R_on)) = {i_stall:.4g} A, {i_stall / i_max:.3g} times the "
                     f"firmware trip i_max = {i_max:.4g} A: a fault whose only symptom is an over-current (a lost "
                     f"current sensor, an open phase) cannot lift a measured current above the trip but by what the "
                     f"back-EMF adds to a misdirected voltage at speed: on this drive it is not detected")
    hw = (f"the hardware trip i_trip = {drive.inverter.i_trip:.4g} A acts on the true currents"
          if drive.inverter.i_trip > 0 else "this drive has no hardware trip (Inverter.i_trip = 0) to end it")
    notes.append(f"faults.lost_sensor: a lost current sensor reads zero, so the firmware trip does not see the "
                 f"current of its phase (i_peak is the true current, it may exceed i_max undetected); {hw}; no "
                 f"controller here checks its sensors' plausibility")
    notes.append("faults.open_phase: an open phase draws no over-current and no controller here tests for a phase "
                 "whose current stays zero while it is driven: not detected on any drive (the torque after it, "
                 "tau_mean_after, shows the loss)")
    return notes


def _shift(f: Fault, t: float, I_N: float) -> Fault:
    value = 0.2 * I_N if f.kind == "current_offset" else f.value
    return Fault(f.kind, f.phase, f.t_on + t, f.t_off + t, value)


def fault_table(drive: Drive, control: Control, ref: float, speed: float, *, i_max: float,
                cases: list[FaultCase] | None = None, periods_before: int = 4, periods_after: int = 6
                ) -> pd.DataFrame:
    """Inject each fault and tabulate detection, time to the safe state and peak current.

    Parameters
    ----------
    drive, control : Drive, Control
    ref : float
        The controller's reference (its unit).
    speed : float
        Imposed mechanical speed (rad/s).
    i_max : float
        The controller's over-current trip (A), for the comparison column.
    cases : list of FaultCase, optional
        Default :func:`default_faults`.
    periods_before, periods_after : int
        Electrical periods before the fault and after it.

    Returns
    -------
    pandas.DataFrame
        One row per case: ``fault``, ``detected`` (bool), ``flags`` (names), ``t_detect_ms`` (from the fault),
        ``t_safe_ms`` (legs off), ``hw_trip_ms`` (the inverter's hardware over-current trip, ``Inverter.i_trip``,
        switched it off; nan if not), ``i_peak`` (A, after the fault, over every integration step: a trip's
        peak is exact), ``i_peak_over_trip`` (``i_peak / i_max``),
        ``tau_mean_after`` (N m, mean torque after the fault).
    """
    Te = electrical_period(drive, speed)
    t_f = periods_before * Te
    duration = t_f + periods_after * Te
    rows = []
    c = core()
    detect_mask = 0
    for name in _DETECT:
        detect_mask |= c.const(name)
    for case in cases if cases is not None else default_faults():
        d = drive
        if case.hall_error_a:
            d = drive.replace(sensors__hall_error=(case.hall_error_a, 0.0, 0.0))
        v = drive.inverter.V_dc
        v_dc = (lambda t, v=v, k=case.v_dc_factor: np.where(t >= t_f, k * v, v)) if case.v_dc_factor != 1 else None
        faults = tuple(_shift(f, t_f, drive.motor.I_N) for f in case.faults)
        sc = Scenario(duration=duration, speed=speed, ref=ref, v_dc=v_dc, faults=faults, trace_sub=1,
                      window=(t_f, duration))
        res = simulate(d, control, sc)
        after = res.t >= t_f
        flags = res.ctrl_flags.astype(np.int64)
        seen = flags[after]
        any_flag = np.bitwise_or.reduce(seen) if seen.size else 0
        detect = np.nonzero(after & ((flags & detect_mask) != 0))[0]
        safe = np.nonzero(after & ((flags & c.const("BC_FLAG_SAFE")) != 0))[0]
        # the plant's peak over every integration step after the fault (events included), not only at the samples
        i_abs = max(res.metrics.i_peak) if res.metrics is not None else math.nan
        t_hw = res.meta["stats"]["hw_trip"]
        tau_after = float(np.mean(res.tau_mean[after])) if np.any(after) else math.nan
        rows.append({
            "fault": case.name,
            "detected": bool(detect.size),
            "flags": ",".join(label for name, label in _DETECT.items() if any_flag & c.const(name)) or "-",
            "t_detect_ms": (res.t[detect[0]] - t_f) * 1e3 if detect.size else math.nan,
            "t_safe_ms": (res.t[safe[0]] - t_f) * 1e3 if safe.size else math.nan,
            "hw_trip_ms": (t_hw - t_f) * 1e3 if t_hw is not None else math.nan,
            "i_peak": float(i_abs),
            "i_peak_over_trip": float(i_abs) / i_max,
            "tau_mean_after": tau_after,
        })
    return pd.DataFrame(rows)

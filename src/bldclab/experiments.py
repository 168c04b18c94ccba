"""Experiments on a drive: steady-state operating points at imposed speed, speed sweeps, paper figures.

An operating point is measured as on a dynamometer test bench: the speed is imposed, the controller runs from
rest until the transients have died out, then the torque is averaged over whole electrical periods. Ripple is
reported three ways: max - min of the instantaneous torque; of its moving average over one PWM period; and of its
values at the controller samples (carrier valleys and peaks, where the currents cross their PWM-period averages):
the last removes the PWM component without flattening commutation spikes a few PWM periods wide, and is the one to
compare with closed forms that assume ideal current regulation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .control import Control
from .errors import BldclabError
from .motor import Drive
from .results import Metrics, SimResult
from .sim import Profile, Scenario, simulate

__all__ = ["PointResult", "steady_state"]


@dataclass(frozen=True)
class PointResult:
    """One steady-state operating point at imposed speed.

    Attributes
    ----------
    speed : float
        Mechanical speed (rad/s).
    speed_pu : float
        Speed in per unit of ``Omega_0`` (-).
    tau_mean, ripple, ripple_ma, ripple_sampled : float
        Mean torque, max - min of the torque, of its one-PWM-period moving average, and of its values at the
        controller samples (PWM-free: :class:`~bldclab.results.Metrics`) (N m).
    tau_mean_pu, ripple_pu, ripple_ma_pu, ripple_sampled_pu : float
        The same in per unit of ``T_N`` (-).
    efficiency : float
        Shaft power over DC power (-).
    metrics : Metrics
        Everything measured over the window (energies, currents, ...).
    """

    speed: float
    speed_pu: float
    tau_mean: float
    ripple: float
    ripple_ma: float
    ripple_sampled: float
    tau_mean_pu: float
    ripple_pu: float
    ripple_ma_pu: float
    ripple_sampled_pu: float
    efficiency: float
    metrics: Metrics


def electrical_period(drive: Drive, speed: float) -> float:
    """Return the electrical period (s) at a mechanical speed (rad/s)."""
    if speed == 0:
        raise BldclabError("speed", "is zero: no electrical period")
    return 2.0 * math.pi / (drive.motor.p * abs(speed))


def steady_state(drive: Drive, control: Control, speed: float, ref: Profile, *, settle_periods: int = 3,
                 measure_periods: int = 2, settle_time: float = 0.01, trace: bool = False,
                 **scenario: object) -> tuple[PointResult, SimResult]:
    """Run the drive at an imposed speed until steady state and measure whole electrical periods.

    Parameters
    ----------
    drive : Drive
    control : Control
    speed : float
        Imposed mechanical speed (rad/s), non-zero.
    ref : profile
        The controller's reference (for current or torque control: a constant).
    settle_periods : int
        Electrical periods discarded before measuring (at least ``settle_time`` is discarded too).
    measure_periods : int
        Whole electrical periods measured.
    settle_time : float
        Minimum settling time (s).
    trace : bool
        Keep the trace (for waveforms).
    **scenario
        Further :class:`~bldclab.sim.Scenario` fields (``delay``, ``trace_sub``, ``omega_ref``, ...).

    Returns
    -------
    PointResult
        The measured point.
    SimResult
        The simulation (its trace if ``trace``).
    """
    Te = electrical_period(drive, speed)
    t_settle = max(settle_periods * Te, math.ceil(settle_time / Te) * Te)
    t_end = t_settle + measure_periods * Te
    sc = Scenario(duration=t_end, speed=speed, ref=ref, trace=trace, window=(t_settle, t_end), **scenario)  # type: ignore[arg-type]
    res = simulate(drive, control, sc)
    m = res.metrics
    assert m is not None
    T_N = drive.T_N
    point = PointResult(speed=speed, speed_pu=speed / drive.Omega_0, tau_mean=m.tau_mean, ripple=m.ripple,
                        ripple_ma=m.ripple_ma, ripple_sampled=m.ripple_sampled, tau_mean_pu=m.tau_mean / T_N,
                        ripple_pu=m.ripple / T_N, ripple_ma_pu=m.ripple_ma / T_N,
                        ripple_sampled_pu=m.ripple_sampled / T_N, efficiency=m.efficiency, metrics=m)
    return point, res

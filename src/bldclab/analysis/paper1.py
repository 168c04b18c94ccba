"""Paper 1's experiments and figures beyond the closed forms: Figs 9, 11 and 12, the friction test.

- :func:`friction_test`: the motor disconnected (all legs off) and spun by the load machine; the torque the load
  machine holds is the friction of the set-up (paper 1, V.C).
- :func:`dynamometer_test`: the drive run at imposed speeds; the load machine's torque plus the friction from the
  friction test is the motor's torque (Fig 12). It equals the simulated electromagnetic mean torque: the procedure
  is checked, not assumed.
- :func:`fig9`: instantaneous torque at about 0.8 p.u. with real square-wave supply, sinusoidal supply, and the
  equivalent PM BLAC motor (sinusoidal back-EMF of the same peak, sinusoidal current of the same rms).
- :func:`fig11`: phase currents with sinusoidal supply at 0.28 p.u. (nominal current) and 0.90 p.u. (about half
  current, voltage-limited) and with square-wave supply at 0.82 p.u.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..control import Control, OpenLoop, Sine, SixStep
from ..model import analytic
from ..model.analytic.table import table1_text as table1_text  # moved there; importable here as before
from ..model.emf import BackEmf, Sinusoid
from ..model.motor import Drive
from ..sim import Scenario, simulate
from .experiments import electrical_period, steady_state

__all__ = ["blac_equivalent", "dynamometer_test", "fig9", "fig11", "fig12", "friction_test"]


def blac_equivalent(drive: Drive) -> Drive:
    """Return paper 1's equivalent PM BLAC drive: sinusoidal back-EMF whose peak equals the BLDC motor's ``k_phi``.

    Supplied with the same rms current (the sinusoidal amplitude ``I_s,N``) it develops ``sqrt(3)/2 T_N``
    (paper 1, IV.B).
    """
    motor = drive.motor
    shape = Sinusoid(k_1=motor.k_phi)

    return drive.replace(motor__emf=BackEmf.symmetric(shape), name=f"{drive.name} (equivalent BLAC)")


def friction_test(drive: Drive, speeds: Sequence[float]) -> pd.DataFrame:
    """Friction test: the motor disconnected and spun at each speed; the load machine holds the friction.

    Parameters
    ----------
    drive : Drive
    speeds : sequence of float
        Mechanical speeds (rad/s), below the no-load speed (so the open-circuit diodes do not rectify).

    Returns
    -------
    pandas.DataFrame
        ``Omega`` (rad/s) and ``T_friction`` (N m): the mean torque the load machine applies.
    """
    rows = []
    for om in speeds:
        Te = electrical_period(drive, om)
        n = math.ceil(2 * Te * 2 * drive.inverter.f_pwm)
        sc = Scenario(duration=2 * Te, speed=om, window=(0.0, 2 * Te), trace=False)
        m = simulate(drive, OpenLoop(np.zeros((n, 3), int), np.zeros((n, 3))), sc).metrics
        assert m is not None
        # the unexcited rotor spun by the load machine: friction and the magnets' iron-loss drag, as measured
        rows.append({"Omega": om, "T_friction": (m.p_fric + m.p_fe) / om})
    return pd.DataFrame(rows)


def dynamometer_test(drive: Drive, control: Control, ref: float, speeds: Sequence[float],
                     friction: pd.DataFrame | None = None) -> pd.DataFrame:
    """Dynamometer measurement (Fig 12): load-machine torque at each imposed speed, friction added back.

    Parameters
    ----------
    drive, control : Drive, Control
    ref : float
        The controller's reference (e.g. ``I_N`` for :class:`SixStep`, ``T_s,N`` for :class:`Sine`).
    speeds : sequence of float
        Mechanical speeds (rad/s).
    friction : pandas.DataFrame, optional
        Result of :func:`friction_test` (interpolated in speed); measured here if omitted.

    Returns
    -------
    pandas.DataFrame
        ``Omega``, ``T_dyno`` (what the load machine holds), ``T_friction``, ``T_motor = T_dyno + T_friction`` and
        ``T_e`` (the simulated electromagnetic mean torque, for checking the procedure), all N m.
    """
    fr = friction if friction is not None else friction_test(drive, speeds)
    rows = []
    for om in speeds:
        point, _ = steady_state(drive, control, om, ref)
        m = point.metrics
        t_dyno = m.tau_mean - (m.p_fric + m.p_fe) / om  # mean shaft torque the load machine balances
        t_fric = float(np.interp(om, fr["Omega"], fr["T_friction"]))
        rows.append({"Omega": om, "Omega_pu": om / drive.Omega_0, "T_dyno": t_dyno, "T_friction": t_fric,
                     "T_motor": t_dyno + t_fric, "T_e": m.tau_mean})
    return pd.DataFrame(rows)


def _torque_trace(drive: Drive, control: Control, ref: float, speed: float) -> tuple[np.ndarray, np.ndarray, Any]:
    point, res = steady_state(drive, control, speed, ref, trace=True, trace_sub=8)
    sel = (res.t >= point.metrics.t0) & (res.t < point.metrics.t1)
    return res.t[sel] - point.metrics.t0, res.tau_e[sel], point


def fig9(drive: Drive, speed_pu: float = 0.8) -> Figure:
    """Instantaneous torque at ``speed_pu``: real square-wave, sinusoidal, equivalent BLAC (paper 1 Fig 9)."""
    om = speed_pu * drive.Omega_0
    handoff = 0.05 * drive.Omega_0
    cases = [("(a) real square-wave supply, I_N", drive, SixStep(), drive.motor.I_N),
             ("(b) sinusoidal supply, I_s,N", drive, Sine(handoff_speed=handoff), analytic.t_sN(drive)),
             ("(c) equivalent PM BLAC motor, I_s,N", blac_equivalent(drive), Sine(handoff_speed=handoff),
              math.sqrt(3) / 2 * drive.T_N)]
    fig = Figure(figsize=(8, 7), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    for ax, (label, d, ctl, ref) in zip(axes, cases, strict=True):
        t, tau, point = _torque_trace(d, ctl, ref, om)
        base = drive.T_N  # all three in per unit of the BLDC motor's T_N
        ax.plot(t * 1e3, tau / base, lw=0.7)
        ax.axhline(point.tau_mean / base, color="k", lw=0.8, ls="--")
        ax.set_title(f"{label}: mean {point.tau_mean / base:.3f} p.u., ripple {point.ripple_sampled / base:.3f} "
                     f"p.u. without PWM ({point.ripple / base:.3f} with)", fontsize=9)
        ax.set_ylabel("torque [p.u.]")
        ax.grid(True, lw=0.3)
    axes[-1].set_xlabel("t [ms]")
    fig.suptitle(f"{drive.name}: instantaneous torque at {speed_pu:.2f} p.u. (paper 1 Fig 9)")
    return fig


def fig11(drive: Drive) -> Figure:
    """Phase currents: sinusoidal supply at 0.28 and 0.90 p.u. (half current), square-wave at 0.82 p.u. (Fig 11)."""
    handoff = 0.05 * drive.Omega_0
    cases = [("(a) sinusoidal supply, 0.28 p.u., nominal current", 0.28, analytic.t_sN(drive), True),
             ("(b) sinusoidal supply, 0.90 p.u., about half the nominal current", 0.90, 0.5 * analytic.t_sN(drive),
              True),
             ("(c) real square-wave supply, 0.82 p.u., nominal current", 0.82, drive.motor.I_N, False)]
    fig = Figure(figsize=(8, 7), layout="constrained")
    axes = fig.subplots(3, 1)
    for ax, (label, w, ref, sine) in zip(axes, cases, strict=True):
        ctl: Control = Sine(handoff_speed=handoff) if sine else SixStep()
        point, res = steady_state(drive, ctl, w * drive.Omega_0, ref, trace=True, trace_sub=8)
        sel = (res.t >= point.metrics.t0) & (res.t < point.metrics.t1)
        t = (res.t[sel] - point.metrics.t0) * 1e3
        for ph in "abc":
            ax.plot(t, res[f"i_{ph}"][sel], lw=0.7, label=f"i_{ph}")
        ax.set_title(label, fontsize=9)
        ax.set_ylabel("[A]")
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=7, loc="upper right", ncols=3)
    axes[-1].set_xlabel("t [ms]")
    fig.suptitle(f"{drive.name}: phase currents (paper 1 Fig 11)")
    return fig


def fig12(drive: Drive, speeds_pu: Sequence[float] = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95)
          ) -> tuple[Figure, pd.DataFrame]:
    """Torque-speed characteristics measured on the dynamometer, friction added back (paper 1 Fig 12).

    Returns
    -------
    Figure
        Measured points for both supplies over paper 1's closed forms.
    pandas.DataFrame
        The measurements (``supply`` column: "sine" or "square") and the friction test.
    """
    speeds = [w * drive.Omega_0 for w in speeds_pu]
    fr = friction_test(drive, speeds)
    handoff = 0.05 * drive.Omega_0
    sq = dynamometer_test(drive, SixStep(), drive.motor.I_N, speeds, fr).assign(supply="square")
    si = dynamometer_test(drive, Sine(handoff_speed=handoff), analytic.t_sN(drive), speeds, fr).assign(supply="sine")
    data = pd.concat([si, sq], ignore_index=True)
    an = analytic.characteristic(drive, np.linspace(0.02, 0.999, 200))
    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(an["Omega_pu"], an["T_s_pu"], color="tab:blue", lw=1, label="(13)/(24), sinusoidal")
    ax.plot(an["Omega_pu"], an["T_q_pu"], color="tab:red", lw=1, label="(26)-(32), square-wave")
    ax.plot(si["Omega_pu"], si["T_motor"] / drive.T_N, "x", color="tab:blue", label="measured, sinusoidal")
    ax.plot(sq["Omega_pu"], sq["T_motor"] / drive.T_N, "o", mfc="none", color="tab:red",
            label="measured, square-wave")
    ax.set_xlabel(r"speed $\Omega_{pu}$")
    ax.set_ylabel(r"torque $T_{pu}$ (load machine + friction)")
    ax.set_xlim(0, 1)
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.4)
    ax.legend(fontsize="small")
    ax.set_title(f"{drive.name}: dynamometer test (paper 1 Fig 12)")
    return fig, data.merge(fr, on=["Omega", "T_friction"], how="left")

"""Sinusoidal supply from standstill: square-wave start, hand-off to sinusoidal currents, rotor mechanics.

Paper 1 (section V.B) starts its sinusoidal drive with square-wave currents, because the Hall-interpolated angle
needs speed, and hands off to the d,q current control at a tenth of the nominal speed. Here the rotor is free: it
follows `J dw/dt = tau_e - tau_L - B w - tau_c sign(w)` with the drive's mechanics, against a load of half the
nominal torque. `Sine` runs its composed `SixStep` start until the Hall speed passes the hand-off speed, then sets
its current integrators so the first sinusoidal output is the voltage already applied (bumpless hand-off).
"""

import sys

import numpy as np
from matplotlib.figure import Figure

import bldclab as bl
from bldclab.model import analytic

# configure the drive: htm-48v with its mechanics (no imposed speed)
drive = bl.load("htm-48v")
torque = analytic.t_sN(drive)  # N m: paper 1's nominal torque with sinusoidal supply, (12)
load = 0.5 * drive.T_N  # N m

# configure the control: sinusoidal supply, square-wave start below the default hand-off speed 0.1 Omega_N
control = bl.Sine()

# simulate 120 ms from standstill (speed=None: the rotor follows the mechanics), a trace row every 4 samples
scenario = bl.Scenario(duration=0.12, ref=torque, load_torque=load, theta0=0.3, trace_every=4)
res = bl.simulate(drive, control, scenario)

mode = res["mode"]  # 0: square-wave start, 1: sinusoidal supply
k = int(np.argmax(mode == 1))
print(f"hand-off at t = {res.t[k] * 1e3:.2f} ms, rotor speed {res.omega_m[k]:.2f} rad/s "
      f"(hand-off speed 0.1 Omega_N = {0.1 * drive.motor.Omega_nominal:.2f} rad/s)")
print(f"largest phase current {np.max(np.abs([res.i_a, res.i_b, res.i_c])):.1f} A (I_N = {drive.motor.I_N:g} A), "
      f"final speed {res.omega_m[-1]:.1f} rad/s")

if len(sys.argv) > 1:
    fig = Figure(figsize=(9, 7), layout="constrained")
    ax = fig.subplots(4, 1, sharex=True)
    t = res.t * 1e3
    for x in "abc":
        ax[0].plot(t, res[f"i_{x}"], lw=0.6, label=f"i_{x}")
    ax[0].set_ylabel("current [A]")
    ax[1].plot(t, res.tau_e, lw=0.5, label="tau_e")
    ax[1].axhline(torque, color="k", ls="--", lw=0.8, label="reference")
    ax[1].set_ylabel("torque [N m]")
    ax[2].plot(t, res.omega_m, label="omega_m")
    ax[2].set_ylabel("speed [rad/s]")
    ax[3].plot(t, mode, drawstyle="steps-post", label="mode (0 start, 1 sine)")
    ax[3].set_ylabel("mode")
    ax[3].set_xlabel("t [ms]")
    for a in ax:
        a.axvline(t[k], color="tab:gray", lw=0.8)
        a.grid(True, lw=0.3)
        a.legend(loc="upper left", fontsize=8, ncols=3)
    fig.suptitle(f"{drive.name}: start from standstill against {load:.1f} N m, hand-off at {t[k]:.1f} ms")
    fig.savefig(sys.argv[1], dpi=110)

"""Fault injection: a Hall sensor stuck high under square-wave current control, and the controller's safe state.

At t_fault the Hall sensor of phase a sticks at 1. In the sector where sensor a should read 0 and the other two read
1, the code becomes 111, which no rotor position produces: `SixStep` flags it (`BC_FLAG_HALL_INVALID`) and switches
every leg off (`BC_FLAG_SAFE`); the currents decay through the diodes into the DC bus within a fraction of a
millisecond (nothing is scripted in the plant). Where the stuck sensor turns a valid code into another valid one
(010 reads 011, 100 reads 101), the controller cannot tell and commutates into the wrong sector: the current
overshoots until its over-current trip (`BC_FLAG_OVERCURRENT`, latched until the currents fall below half the trip)
switches the legs off as well. `bldclab faults htm-48v --control square` tabulates this and the other faults.
"""

import math
import sys

import numpy as np
from matplotlib.figure import Figure

import bldclab as bl

FLAG_SAFE, FLAG_HALL_INVALID, FLAG_OVERCURRENT = (bl.flag(n) for n in ("SAFE", "HALL_INVALID", "OVERCURRENT"))

# configure the drive: htm-48v on a dynamometer at half its no-load speed
drive = bl.load("htm-48v")
speed = 0.5 * drive.Omega_0  # rad/s
T_e = 2 * math.pi / (drive.motor.p * speed)  # electrical period, s

# configure the control: paper 1's real square-wave supply, current reference I_N
control = bl.SixStep()

# simulate: three electrical periods, the Hall sensor of phase a stuck at 1 from the end of the first
t_fault = T_e
fault = bl.Fault("hall_stuck", "a", t_on=t_fault, value=1.0)
res = bl.simulate(drive, control, bl.Scenario(duration=3 * T_e, speed=speed, ref=drive.motor.I_N, faults=(fault,)))

flags = res.ctrl_flags.astype(int)
k_detect = int(np.argmax(flags & FLAG_HALL_INVALID))
k_safe = int(np.argmax(flags & FLAG_SAFE))
i_abs = np.abs(np.stack([res.i_a, res.i_b, res.i_c]))
k_zero = k_safe + int(np.argmax(np.all(i_abs[:, k_safe:] < 0.01 * drive.motor.I_N, axis=0)))
print(f"fault at {t_fault * 1e3:.2f} ms; invalid Hall code {int(res.hall[k_detect])} seen at "
      f"{res.t[k_detect] * 1e3:.2f} ms, safe state from {res.t[k_safe] * 1e3:.2f} ms, "
      f"currents below 1 % of I_N from {res.t[k_zero] * 1e3:.2f} ms")
i_trip = 2 * drive.motor.I_N  # SixStep's default over-current trip
print(f"largest current after the fault {i_abs[:, res.t >= t_fault].max():.1f} A (trip {i_trip:g} A); "
      f"over-current flagged in {np.count_nonzero(flags & FLAG_OVERCURRENT)} samples")

if len(sys.argv) > 1:
    fig = Figure(figsize=(9, 6.5), layout="constrained")
    ax = fig.subplots(3, 1, sharex=True)
    t = res.t * 1e3
    for x in "abc":
        ax[0].plot(t, res[f"i_{x}"], lw=0.7, label=f"i_{x}")
    ax[0].set_ylabel("current [A]")
    ax[1].plot(t, res.hall, drawstyle="steps-post", label="Hall code (c b a)")
    ax[1].set_ylabel("code")
    ax[1].set_yticks(range(8))
    for offset, (flag, name) in enumerate(((FLAG_SAFE, "SAFE"), (FLAG_HALL_INVALID, "HALL_INVALID"),
                                           (FLAG_OVERCURRENT, "OVERCURRENT"))):
        ax[2].plot(t, ((flags & flag) != 0) + 1.5 * offset, drawstyle="steps-post", label=f"BC_FLAG_{name}")
    ax[2].set_yticks([])
    ax[2].set_ylim(-0.3, 5.2)
    ax[2].set_ylabel("flag")
    ax[2].set_xlabel("t [ms]")
    for a in ax:
        a.axvline(t_fault * 1e3, color="tab:red", lw=0.8)
        a.grid(True, lw=0.3)
        a.legend(loc="upper left", fontsize=8, ncols=3)
    fig.suptitle(f"{drive.name}: Hall sensor a stuck at 1 from {t_fault * 1e3:.1f} ms (red line)")
    fig.savefig(sys.argv[1], dpi=110)

"""Six-step voltage mode on the htm-48v drive: commutation seen in the phase currents and the torque.

The drive runs at half its no-load speed, held by a dynamometer, with high-side chopping at a fixed duty. The
outgoing phase freewheels through its diode at every commutation; the floating phase's diode conducts briefly in
the PWM off-times: both come from the circuit, nothing is scripted.
"""

import math
import sys

import bldclab as bl

# configure the drive
drive = bl.load("htm-48v")
omega = 0.5 * drive.Omega_0  # rad/s, imposed
T_e = 2 * math.pi / (drive.motor.p * omega)  # electrical period, s

# configure the control: Hall-commutated six-step, duty 0.6, upper switch chopping
control = bl.SixStepVoltage("high")

# simulate four electrical periods, measure the last two
scenario = bl.Scenario(duration=4 * T_e, speed=omega, ref=0.6, window=(2 * T_e, 4 * T_e), trace_sub=4)
res = bl.simulate(drive, control, scenario)

m = res.metrics
print(f"mean torque {m.tau_mean:.2f} N m, ripple {m.ripple:.2f} N m (PWM-averaged {m.ripple_ma:.2f} N m)")
print(f"efficiency {m.efficiency:.3f}, energy-balance residue {m.balance_electrical:.1e}")
if len(sys.argv) > 1:
    res.plot().savefig(sys.argv[1])

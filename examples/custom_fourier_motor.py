"""A custom motor in Python: a Fourier-series back-EMF, paper 1's Table I, both supplies simulated.

No motor file is needed: `Motor`, `BackEmf`, `Fourier`, `Inverter`, `Mechanics` are frozen dataclasses that check
their fields as a motor file does (a bad value raises `BldclabError` naming the field). The back-EMF here is a
flat-topped wave of a fundamental with 3rd and 5th harmonics; `k_phi` (half the peak line-to-line shape) and the
per-unit bases follow from it. `analytic.table1` gives paper 1's Table I for the drive: its closed forms assume the
ideal trapezoid, while the R-aware base speeds are computed numerically from this drive's own shape. Then
square-wave and sinusoidal current supply run at half the no-load speed. `drive.to_toml()` writes the motor file.
"""

import math
import sys

import numpy as np
from matplotlib.figure import Figure

import bldclab as bl
from bldclab.analysis.experiments import steady_state
from bldclab.cli import table1_text
from bldclab.model import analytic

# configure the drive: 4 pole pairs, 24 V, a flat-topped Fourier back-EMF (V s/rad per harmonic order)
k1 = 0.05
emf = bl.BackEmf.symmetric(bl.Fourier(a=(0.0,) * 6, b=(0.0, k1, 0.0, 0.2 * k1, 0.0, 0.05 * k1)))
motor = bl.Motor(p=4, R=0.08, L=120e-6, emf=emf, V_N=24.0, I_N=15.0)
drive = bl.Drive(motor, bl.Inverter(V_dc=24.0, f_pwm=20e3, R_on=0.005), bl.Mechanics(J=2e-4, B=1e-5),
                 name="fourier-24v")
print(f"k_phi {motor.k_phi:.4f} V s/rad, Omega_0 {drive.Omega_0:.1f} rad/s, T_N {drive.T_N:.3f} N m")
print(table1_text(analytic.table1(drive), "table"))

# configure the control: paper 1's two supplies (current reference I_N; torque reference (12))
supplies = {"square-wave (SixStep)": (bl.SixStep(), motor.I_N),
            "sinusoidal (Sine)": (bl.Sine(handoff_speed=0.05 * drive.Omega_0), analytic.t_sN(drive))}

# simulate: steady state at half the no-load speed, two electrical periods measured, traces kept
speed = 0.5 * drive.Omega_0
points = {}
for name, (control, ref) in supplies.items():
    point, res = steady_state(drive, control, speed, ref, trace=True)
    points[name] = (point, res)
    print(f"{name:>22}: mean torque {point.tau_mean_pu:.3f} p.u., ripple at the samples "
          f"{point.ripple_sampled_pu:.3f} p.u., efficiency {point.efficiency:.3f}")

if len(sys.argv) > 1:
    fig = Figure(figsize=(9, 6.5), layout="constrained")
    ax_k, ax_t = fig.subplots(2, 1)
    theta = np.linspace(0.0, 2 * math.pi, 721)
    k = emf.k_abc(theta)
    ax_k.plot(np.degrees(theta), k[0], label="k_a")
    ax_k.plot(np.degrees(theta), 0.5 * (k[0] - k[1]), label="(k_a - k_b) / 2")
    ax_k.axhline(motor.k_phi, color="k", ls="--", lw=0.8, label=f"k_phi = {motor.k_phi:.4f}")
    ax_k.set_xlabel("electrical angle [deg]")
    ax_k.set_ylabel("[V s/rad]")
    ax_k.set_title("the back-EMF shape", fontsize=10)
    for name, (point, res) in points.items():
        m = point.metrics
        sel = (res.t >= m.t0) & (res.t <= m.t1)
        ax_t.plot((res.t[sel] - m.t0) * 1e3, res.tau_e[sel] / drive.T_N, lw=0.6, label=name)
    ax_t.set_xlabel("t [ms]")
    ax_t.set_ylabel("torque [p.u. of T_N]")
    ax_t.set_title("instantaneous torque at 0.5 Omega_0 over two electrical periods", fontsize=10)
    for a in (ax_k, ax_t):
        a.grid(True, lw=0.3)
        a.legend(fontsize=8, loc="lower left", ncols=3)
    fig.savefig(sys.argv[1], dpi=110)

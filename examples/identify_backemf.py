"""Back-EMF identification: the shipped constant-speed record, then torque control of the identified drive.

Paper 2 measures its motor's back-EMF "by the constant speed test" and drives its torque controller with the shapes
`e_x / omega_m`. The sample file shipped with bldclab is such a record of the `lu-4kw` motor at 1300 rpm (three
terminal voltages with probe noise and offsets, Hall signals; its provenance is in the file's header).
`bldclab.analysis.identify.identify` turns it into three per-phase tables `k_x(theta_x)` in V s/rad on bldclab's angle
convention; `Identification.drive` puts them into a base drive. Terminal voltages cannot see the part common to
the three phases (the triplen harmonics), which is also inert in a star motor without neutral (`docs/identify.md`):
the tables match the catalog motor's observable shapes (`observable_emf`), not its full trapezoids, and the
identified drive, run under paper 2's torque control at 2000 rpm, gives the same torque as the catalog drive.
"""

import math
import sys

import numpy as np
from matplotlib.figure import Figure

import bldclab as bl
from bldclab.analysis.identify import identify, observable_emf, sample_path

# configure the drive: identify the back-EMF from the record, the rest (R, L, inverter, sensors) from lu-4kw
catalog = bl.load("lu-4kw")
ident = identify(sample_path(), "1300 rpm", pole_pairs=catalog.motor.p)
drive = ident.drive(catalog, name="lu-4kw identified")
print(f"{ident.samples} samples over {ident.periods:.2f} electrical periods, noise {ident.noise:.3f} V, "
      f"k_phi {ident.k_phi:.4f} V s/rad (catalog {catalog.motor.k_phi:.4f}), warnings: {list(ident.warnings)}")
observable, _ = observable_emf(catalog.motor.emf)  # what a perfect measurement of the catalog motor gives
expected = np.stack([shape(ident.theta) for shape in observable.shapes])  # k_x on each phase's local angle
error = np.max(np.abs(ident.k - expected))
print(f"largest difference to the catalog motor's observable shapes: {error * 1e3:.1f} mV s/rad")

# configure the control: paper 2's torque control at rated torque
control = bl.Lu()
speed = 2000 * 2 * math.pi / 60  # rad/s
T_e = 2 * math.pi / (catalog.motor.p * speed)  # electrical period, s

# simulate both drives at imposed speed: 3 periods to settle, 2 measured
scenario = bl.Scenario(duration=5 * T_e, speed=speed, ref=catalog.T_N, window=(3 * T_e, 5 * T_e))
runs = {d.name: bl.simulate(d, control, scenario) for d in (catalog, drive)}
for name, res in runs.items():
    m = res.metrics
    print(f"{name:>18}: mean torque {m.tau_mean:.3f} N m, PWM-averaged ripple {m.ripple_ma:.3f} N m")

if len(sys.argv) > 1:
    fig = Figure(figsize=(9, 6.5), layout="constrained")
    ax_k, ax_t = fig.subplots(2, 1)
    deg = np.degrees(ident.theta)
    for j, (x, color) in enumerate(zip("abc", ("tab:blue", "tab:orange", "tab:green"), strict=True)):
        ax_k.plot(deg, ident.k[j], color=color, lw=1.2, label=f"k_{x} identified")
        ax_k.plot(deg, expected[j], color="k", lw=0.6, ls="--")
        ax_k.plot(deg, catalog.motor.emf.shapes[j](ident.theta), color="tab:gray", lw=0.5, ls=":")
    ax_k.plot([], [], color="k", lw=0.6, ls="--", label="catalog, observable")
    ax_k.plot([], [], color="tab:gray", lw=0.5, ls=":", label="catalog, full shape")
    ax_k.set_xlabel("local electrical angle theta_x [deg]")
    ax_k.set_ylabel("k_x [V s/rad]")
    ax_k.set_title("back-EMF shapes from the 1300 rpm record", fontsize=10)
    for name, res in runs.items():
        pwm_mean = 0.5 * (res.tau_mean[1:] + res.tau_mean[:-1])  # mean over one PWM period (two samples)
        sel = res.t[1:] >= 3 * T_e
        ax_t.plot((res.t[1:][sel] - 3 * T_e) * 1e3, pwm_mean[sel], lw=0.8, label=name)
    ax_t.set_xlabel("t [ms]")
    ax_t.set_ylabel("torque, PWM-period mean [N m]")
    ax_t.set_title("paper 2's torque control at 2000 rpm and rated torque", fontsize=10)
    for a in (ax_k, ax_t):
        a.grid(True, lw=0.3)
        a.legend(fontsize=8, ncols=3, loc="lower left")
    fig.savefig(sys.argv[1], dpi=110)

"""Paper 2 at light load: the torque at the samples vs its mean when the current stops within each PWM period.

At a quarter of the rated torque on `lu-4kw` (300 V, 0.29 mH, 10 kHz bipolar chopping) the PWM current ripple
(about 24 A peak-to-peak at 1000 rpm) is several times the 4 A mean, so the current stops within every PWM period.
Paper 2's laws (`Lu(mean_law=False)`) make the torque at every sample (carrier valley and peak, the dots) equal to the
reference: the half period after a valley (off part first) lets the current die and rise back, the half period
after a peak then carries a large pulse, and the mean torque is about 131 % of the reference. The mean law
(`Lu(mean_law=True)`, the default) solves for the duty whose *mean* torque over the PWM period is the reference.
"""

import math
import sys

import numpy as np
from matplotlib.figure import Figure

import bldclab as bl
from bldclab.analysis import paper2

# configure the drive: paper 2's motor at an imposed 1000 rpm, a quarter of the rated torque
drive = bl.load("lu-4kw")
speed = 1000 * 2 * math.pi / 60  # rad/s
torque = 0.25 * drive.T_N  # N m
sub = 16  # trace rows per sample (half PWM period)

# configure the control: paper 2's torque control without and with the mean law; simulate to steady state
runs = {}
for label, mean_law in (("end-value law (paper 2)", False), ("mean law", True)):
    res = paper2.operating_point(drive, "lu", torque, speed, trace_sub=sub, mean_law=mean_law)
    st = paper2.ripple_stats(res, drive)
    tau_k = np.asarray(res["tau_e"][::sub])  # the instantaneous torque at the samples
    t_k = res.t[::sub]
    inside = (t_k >= res.metrics.t0) & (t_k < res.metrics.t1)
    runs[label] = (res, st)
    print(f"{label:>24}: mean torque {100 * st.tau_mean / torque:5.1f} % of the reference, torque at the samples "
          f"{100 * np.mean(tau_k[inside]) / torque:5.1f} %, no current {100 * st.dcm_share:4.1f} % of the time")

if len(sys.argv) > 1:
    fig = Figure(figsize=(9, 6), layout="constrained")
    ax = fig.subplots(2, 1, sharex=True, sharey=True)
    for a, (label, (res, st)) in zip(ax, runs.items(), strict=True):
        m = res.metrics
        sel = (res.t >= m.t1 - 0.4e-3) & (res.t <= m.t1)
        t_ms = (res.t - m.t1) * 1e3
        n = len(res.t) // sub
        half = np.repeat(np.asarray(res["tau_mean"][: n * sub]).reshape(n, sub).mean(axis=1), sub)
        samples = sel.copy()
        samples[np.arange(len(sel)) % sub != 0] = False
        a.plot(t_ms[sel], res.tau_e[sel], lw=0.8, color="tab:gray", label="tau_e")
        a.plot(t_ms[: n * sub][sel[: n * sub]], half[sel[: n * sub]], lw=1.0, color="tab:blue",
               label="half-period mean")
        a.plot(t_ms[samples], res.tau_e[samples], "o", ms=3, color="tab:red", label="at the samples")
        a.axhline(torque, color="k", ls="--", lw=0.8, label="reference")
        a.axhline(st.tau_mean, color="tab:green", lw=1.2, label="mean over two electrical periods")
        a.set_title(f"{label}: mean {100 * st.tau_mean / torque:.1f} % of the reference", fontsize=9)
        a.set_ylabel("torque [N m]")
        a.set_ylim(-0.5, 16.0)
        a.grid(True, lw=0.3)
        a.legend(loc="upper right", fontsize=7, ncols=3)
    ax[-1].set_xlabel("t - end of the window [ms]")
    fig.suptitle(f"{drive.name} at 1000 rpm and {torque:.2f} N m (25 % of T_N): discontinuous current")
    fig.savefig(sys.argv[1], dpi=110)

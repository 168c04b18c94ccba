"""Paper 2 torque control: the duties D_n, D_c, D_o vs rectangular current control on the lu-4kw drive.

The `lu-4kw` motor has a non-ideal back-EMF (rounded corners, tilted flat tops, mismatched phases). Rectangular
current control (`Lu(method="rect")`: 120-degree conduction, bipolar chopping, a PI on the pair current) turns the
back-EMF's shape into torque ripple and dips the torque at every commutation. Paper 2's method computes the duty
from the back-EMF shape functions so the torque follows its reference in normal conduction (`D_n`) and during the
commutation (`D_c`), and slows the outgoing phase when the bus cannot do more (`D_o`). At rated torque and 3000 rpm
the DC bus limits the commutation: the point where `D_o` matters.
"""

import math
import sys

import numpy as np
from matplotlib.figure import Figure

import bldclab as bl
from bldclab.analysis import paper2

# configure the drive: paper 2's motor, imposed speed 3000 rpm, rated torque
drive = bl.load("lu-4kw")
speed = 3000 * 2 * math.pi / 60  # rad/s
torque = drive.T_N  # N m

# configure the control: the three methods of paper 2 (bldclab.Lu(method=...)), one-sample computation delay
# simulate each until steady state, two electrical periods measured, 8 trace rows per sample
results = {}
for method in paper2.METHODS:  # "rect", "lu-no-do", "lu"
    res = paper2.operating_point(drive, method, torque, speed, delay=1, trace_sub=8)
    st = paper2.ripple_stats(res, drive)
    results[method] = (res, st)
    print(f"{method:>8}: mean torque {st.tau_mean:6.2f} N m ({100 * st.tau_mean / torque:5.1f} % of the reference), "
          f"ripple of the one-PWM-period mean {st.ripple_ma_pp:5.1f} % p-p, commutation dip {st.dip_pct:4.1f} %, "
          f"D_o in {100 * st.do_share:.1f} % of the samples")

if len(sys.argv) > 1:
    fig = Figure(figsize=(9, 6), layout="constrained")
    ax = fig.subplots(len(results), 1, sharex=True, sharey=True)
    for a, (method, (res, st)) in zip(ax, results.items(), strict=True):
        m = res.metrics
        sel = (res.t >= m.t1 - 2e-3) & (res.t <= m.t1)
        rows = 2 * 8  # trace rows per PWM period: 2 samples x trace_sub
        mean = np.convolve(res.tau_e, np.ones(rows) / rows, mode="same")  # one-PWM-period moving average
        a.plot((res.t[sel] - m.t1) * 1e3, res.tau_e[sel], lw=0.4, color="tab:gray", label="tau_e")
        a.plot((res.t[sel] - m.t1) * 1e3, mean[sel], lw=1.2, color="tab:red", label="one-PWM-period mean")
        a.axhline(torque, color="k", ls="--", lw=0.8, label="reference")
        a.set_title(f"{method}: one-PWM-period-mean ripple {st.ripple_ma_pp:.1f} % p-p", fontsize=9)
        a.set_ylabel("torque [N m]")
        a.grid(True, lw=0.3)
        a.legend(loc="lower left", fontsize=8, ncols=3)
    ax[-1].set_xlabel("t - end of the window [ms]")
    fig.suptitle(f"{drive.name} at 3000 rpm and {torque:.2f} N m: instantaneous torque over the last 2 ms")
    fig.savefig(sys.argv[1], dpi=110)

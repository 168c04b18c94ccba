"""Which supply is more efficient on a real 48 V drive, and why: the losses bucket by bucket.

`htm-48v-losses` is paper 1's drive with the losses of a real one: an inverter of onsemi NTB5860NL MOSFETs (their
datasheet's on-resistance, body diode, switching times and recovery charge) and a core of M270-35A steel. An
efficiency map of both supplies over the torque-speed plane says where each wins; the mean of each loss bucket over
the map says why. The square wave is mapped twice: with paper 1's PWM-on-PWM chopping, whose off-time current
freewheels through a body diode, and with synchronous chopping, which keeps it in a switch.
"""

import sys

import numpy as np
from matplotlib.figure import Figure

import bldclab as bl
from bldclab.analysis.effmap import efficiency_map, map_controls

# configure the drive: the catalog drive with sourced losses; a 6 x 6 grid of torque (0.2-1 T_N) and speed
drive = bl.load("htm-48v-losses")
torques = np.linspace(0.2, 1.0, 6) * drive.T_N
speeds = np.linspace(0.1, 0.9, 6) * drive.Omega_0
buckets = ["p_cu", "p_sw", "p_diode", "p_swloss", "p_fe", "p_fric"]
names = {"p_cu": "copper", "p_sw": "switches", "p_diode": "diodes", "p_swloss": "switching", "p_fe": "iron",
         "p_fric": "friction"}

# configure the control: both supplies take the torque reference; the square wave with two chopping patterns
maps = {}
for chopping in ("pwm-on-pwm", "sync"):
    controls = map_controls(drive, float(speeds.min()), chopping)
    # simulate: imposed-speed steady states at every grid point, in this process
    res = efficiency_map(drive, torques, speeds, workers=1, controls=controls)
    for line in res.summary()[2:5]:
        print(f"{chopping:>10}: {line}")
    maps[chopping] = res.points.set_index(["supply", "torque_ref", "speed"])

# the mean of each bucket over the points all three reach
runs = {"square, pwm-on-pwm": maps["pwm-on-pwm"].loc["square"], "square, sync": maps["sync"].loc["square"],
        "sinusoidal": maps["sync"].loc["sine"]}
common = np.logical_and.reduce([r.feasible.to_numpy() for r in runs.values()])
means = {label: r[buckets][common].mean() for label, r in runs.items()}
print(f"{int(common.sum())} of {common.size} points reached by all three")
print("mean loss over those points [W]:")
for label, m in means.items():
    print(f"  {label:<22}" + "  ".join(f"{names[b]} {m[b]:6.2f}" for b in buckets) + f"  total {m.sum():6.1f}")

if len(sys.argv) > 1:
    fig = Figure(figsize=(7, 4), layout="constrained")
    ax = fig.subplots()
    x = np.arange(len(buckets))
    for j, (label, m) in enumerate(means.items()):
        ax.bar(x + (j - 1) * 0.27, [m[b] for b in buckets], width=0.27, label=label)
    ax.set_xticks(x, [names[b] for b in buckets])
    ax.set_ylabel("mean loss [W]")
    ax.set_title("htm-48v-losses: mean loss per bucket, 0.2-1 T_N, 0.1-0.9 Omega_0", fontsize=10)
    ax.grid(True, axis="y", lw=0.3)
    ax.legend(fontsize=8)
    fig.savefig(sys.argv[1], dpi=110)

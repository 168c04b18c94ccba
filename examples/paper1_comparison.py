"""Paper 1 comparison: square-wave vs sinusoidal supply of htm-48v at a few speeds, beside the closed forms.

`bldclab.analysis.compare.compare` runs both supplies at each speed on a dynamometer (imposed speed) until steady
state and measures whole electrical periods: the real square-wave (120-degree) current supply with Hall
commutation
(`SixStep`) at the nominal current amplitude, and the sinusoidal supply (`Sine`) at the torque of the same rms
current. Under paper 1's premise (phase resistance neglected) the simulated mean torque and the torque ripple at the
controller samples fall on the paper's closed forms, drawn as lines. `bldclab compare htm-48v` does the same job
at 32 speeds on the drive with its resistance.
"""

import sys

import numpy as np
from matplotlib.figure import Figure

import bldclab as bl
from bldclab.analysis.compare import compare
from bldclab.model import analytic
from bldclab.report import plots

# configure the drive: paper 1's study case (Table II), with the closed forms' premise R = 0
drive = bl.load("htm-48v").replace(motor__R=0.0)
speeds_pu = [0.1, 0.3, 0.5, 0.7, 0.9]  # per unit of the no-load speed Omega_0

# configure the control: paper 1's two supplies with their references (bldclab.analysis.compare.default_controls)
# simulate: 2 supplies x 5 speeds, in this process
res = compare(drive, speeds_pu, workers=1)

sim, paper = res.simulated, res.analytic
print("speed   square: T sim / paper  TR sim / paper   sine: T sim / paper  TR sim / paper   [p.u.]")
for j, w in enumerate(speeds_pu):
    q = sim[(sim.supply == "square") & (sim.Omega_pu == w)].iloc[0]
    s = sim[(sim.supply == "sine") & (sim.Omega_pu == w)].iloc[0]
    print(f"{w:5.2f}   {q.T_pu:14.3f} / {paper.T_q_pu[j]:.3f}  {q.TR_pu:6.3f} / {paper.TR_q_pu[j]:.3f}"
          f"   {s.T_pu:12.3f} / {paper.T_s_pu[j]:.3f}  {s.TR_pu:6.3f} / {paper.TR_s_pu[j]:.3f}")
print(*res.verdict[:4], sep="\n")

if len(sys.argv) > 1:
    curves = analytic.characteristic(drive, np.linspace(0.0, 1.0, 201))
    sq, si = sim[sim.supply == "square"], sim[sim.supply == "sine"]
    fig = Figure(figsize=(10, 4), layout="constrained")
    ax_t, ax_r = fig.subplots(1, 2)
    plots.plot_torque_speed(curves, ax_t, title="mean torque", overlays={
        "simulated, sinusoidal": si.rename(columns={"T_pu": "T_s_pu"})[["Omega_pu", "T_s_pu"]],
        "simulated, square-wave": sq.rename(columns={"T_pu": "T_q_pu"})[["Omega_pu", "T_q_pu"]]})
    plots.plot_ripple(curves, ax_r, title="torque ripple (at the controller samples)", overlays={
        "simulated, sinusoidal": si.rename(columns={"TR_pu": "TR_s_pu"})[["Omega_pu", "TR_s_pu"]],
        "simulated, square-wave": sq.rename(columns={"TR_pu": "TR_q_pu"})[["Omega_pu", "TR_q_pu"]]})
    fig.suptitle(f"{drive.name}, R = 0: paper 1's closed forms (lines) and the switching-level simulation (markers)")
    fig.savefig(sys.argv[1], dpi=110)

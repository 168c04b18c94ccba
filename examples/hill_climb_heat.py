"""Heat on a hill climb: an hour of an e-bike hub motor, winding and switch temperatures for both supplies.

`htm-48v-losses` carries a thermal network (`[thermal]` of its motor file: winding, stator, rotor, covers, the
inverter's junction, case and heat sink). The profile `examples/profiles/hill-climb.toml` climbs for fifteen minutes
twice; `run_profile` in its fast mode takes each second in the steady state of its operating point at its
temperatures (the winding's resistance and the magnets' flux follow), so the hour takes seconds. The square wave
heats the winding about 10 K more than the sinusoidal supply, and its switches (diode conduction, hard switching)
about 20 K more. A second square-wave run derates the torque from 100 degC of the winding, as firmware does
(`bc_derate`), and holds it near 105 degC. docs/thermal.md explains the model and what the fast mode leaves out.
"""

import sys
from pathlib import Path

from matplotlib.figure import Figure

import bldclab as bl
from bldclab.analysis.thermal import Derating, read_profile, run_profile

drive = bl.load("htm-48v-losses")
profile = read_profile(Path(__file__).resolve().parent / "profiles" / "hill-climb.toml")
runs = {"sinusoidal": run_profile(drive, profile, supply="sine"),
        "square wave": run_profile(drive, profile, supply="square"),
        "square, derated 100-130 degC": run_profile(drive, profile, supply="square",
                                                    derate=Derating("winding", 100.0, 130.0))}
for label, r in runs.items():
    tr = r.trace
    print(f"{label:<30} wall {r.wall:4.1f} s  peak winding {tr.T['winding'].max():6.1f} degC  junction "
          f"{tr.T['junction'].max():5.1f} degC  losses {tr.E_loss / 3600:5.1f} Wh  balance {tr.balance:.0e}")

if len(sys.argv) > 1:
    fig = Figure(figsize=(8, 5), layout="constrained")
    ax, ax2 = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1))
    for (label, r), color in zip(runs.items(), ("C0", "C3", "C1"), strict=True):
        t = r.trace.t / 60.0
        ax.plot(t, r.trace.T["winding"], color=color, label=f"winding, {label}")
        ax.plot(t, r.trace.T["junction"], color=color, ls="--", lw=0.9, label=f"junction, {label}")
        ax2.plot(t, r.trace.extra["torque_ref"], color=color, lw=0.9)
    ax.axhline(155.0, color="k", lw=0.6, ls=":")
    ax.set_ylabel("temperature [degC]")
    ax.set_title("htm-48v-losses on a one-hour hill climb (25 degC ambient)", fontsize=10)
    ax.legend(fontsize=7, ncol=2)
    ax.grid(True, lw=0.3)
    ax2.set_ylabel("torque ref [N m]")
    ax2.set_xlabel("time [min]")
    ax2.grid(True, lw=0.3)
    fig.savefig(sys.argv[1], dpi=110)

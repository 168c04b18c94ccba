"""A small sweep: torque ripple of square-wave current control over speed and chopping pattern, into a store.

`bldclab.sweep.Sweep` describes the cases declaratively: a base case and a grid whose axes are any setting by its
flat name (here a controller parameter, `control.chopping`, and the speed in per unit; a motor-file override such
as `"motor.L": ["70 uH", "80 uH"]` is an axis the same way). `sweep.run` validates every case, runs the ones the
store does not hold yet (serially here; `Processes()` or `Dask(address)` give the same bits) and commits each result
as it arrives. Running it again computes nothing: every case is found by its key.
"""

import sys
import tempfile
from pathlib import Path

from matplotlib.figure import Figure

import bldclab as bl
from bldclab import sweep

# configure the drive: htm-48v from the catalog (by name: workers rebuild it from its motor file)
drive = bl.load("htm-48v")
patterns = ["pwm-on-pwm", "high", "bipolar"]

# configure the control: paper 1's square-wave current control (SixStep), current reference I_N, three chopping
# patterns; steady state at imposed speed, 2 electrical periods to settle and 2 measured
s = sweep.Sweep(
    name="ripple vs speed and chopping",
    base={"drive": "htm-48v", "controller": "SixStep", "experiment": "steady_state", "ref": drive.motor.I_N,
          "settle_periods": 2, "measure_periods": 2},
    grid={"control.chopping": patterns, "speed_pu": [0.2, 0.4, 0.6, 0.8]},
)

# simulate: 12 cases, serially, into a store in a temporary directory, then once more
with tempfile.TemporaryDirectory() as tmp:
    store = Path(tmp) / "ripple.sqlite"
    run = sweep.run(s, store, executor=sweep.Serial(), progress=False)
    print(run.summary().replace(str(store), "ripple.sqlite"))
    df = run.to_pandas()
    again = sweep.run(s, store, executor=sweep.Serial(), progress=False)
    print(f"second run: {again.computed} computed, {again.skipped} found in the store")
    run.store.close()
    again.store.close()

# torque ripple at the controller samples (PWM-free), per unit of T_N
df["ripple_sampled_pu"] = (df.tau_s_max - df.tau_s_min) / drive.T_N
table = df.pivot_table(index="speed_pu", columns="control.chopping", values="ripple_sampled_pu")[patterns]
print("torque ripple at the controller samples [p.u. of T_N]:")
print(table.round(3).to_string())

if len(sys.argv) > 1:
    fig = Figure(figsize=(7, 4), layout="constrained")
    ax = fig.subplots()
    for pattern in patterns:
        ax.plot(table.index, table[pattern], "o-", label=pattern)
    ax.set_xlabel("speed [per unit of Omega_0]")
    ax.set_ylabel("torque ripple [per unit of T_N]")
    ax.set_title("htm-48v, square-wave current control at I_N: ripple at the samples")
    ax.grid(True, lw=0.3)
    ax.legend(title="chopping", fontsize=8)
    fig.savefig(sys.argv[1], dpi=110)

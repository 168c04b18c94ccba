"""Sensorless desync map: where a 5-inch drone motor's ESC loses the rotor on a throttle punch.

The T-Motor F60PRO V (KV2550, 4S) with its T5147 propeller runs sensorless six-step (`SixStepSensorless`:
comparator on the floating phase against a virtual star point, synchronous chopping, rotor alignment and a forced
ramp to start) on the switching plant. At every point of a timing advance x throttle ramp limit
grid the drive settles at 25 % throttle and then gets a punch to 50, 70 or 90 %; `bldclab.analysis.desync.desync_map`
classifies each run: in sync, desync with the controller's reason (`ZC_HIDDEN`: the demagnetisation hid the zero
crossing), recovered after a restart, or not started; and checks the controller's own diagnosis against the
plant's truth, the true commutation angle error. The right panel is the physics behind it: the margin between the
expected crossing (30 degrees minus the advance after a commutation) and the end of the demagnetisation the
controller measured. `bldclab sensorless f60prov-2550kv` writes the same map as CSV, JSON and figures.
"""

import sys

import bldclab as bl
from bldclab.analysis.desync import Axis, ThrottleStep, desync_map
from bldclab.report.desync_plots import plot_desync_map

# configure the drive: the catalog's 5-inch racing motor with its propeller load (k_q, inertia in the motor file)
drive = bl.load("f60prov-2550kv")

# configure the control: the controller's defaults; the map varies the timing advance and the throttle ramp limit
control = bl.SixStepSensorless()
timing = Axis("timing", (0.0, 10.0, 20.0, 30.0))  # deg electrical
end = Axis("end", (0.5, 0.7, 0.9))  # throttle after the punch

# simulate: settle at 25 % throttle, punch (no ramp limit), watch 150 ms for a desync (bldclab sensorless watches
# long enough for the restart as well)
res = desync_map(drive, timing, end, step=ThrottleStep(start=0.25, observe=0.15), control=control, workers=2)
print(f"{len(res.points)} points in {res.seconds:.1f} s")
print(res.table())
for line in res.summary():
    print(line)

if len(sys.argv) > 1:
    fig = plot_desync_map(res)
    fig.savefig(sys.argv[1], dpi=90)

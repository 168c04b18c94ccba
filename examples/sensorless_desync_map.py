"""Sensorless desync map: where a 5-inch drone motor's ESC loses the rotor on a throttle punch.

The T-Motor F60PRO V (KV2550, 4S) with its T5147 propeller runs sensorless six-step (`SixStepSensorless`:
comparator on the floating phase against a virtual star point, synchronous chopping, rotor alignment and a forced
ramp to start) on the switching plant, here without the controller's two protections against a hidden crossing
(fast demagnetisation and the demagnetisation limiter). At every point of a timing advance x final throttle grid
the drive settles at 25 % throttle and then gets a punch to 50, 70 or 90 %; `bldclab.analysis.desync.desync_map`
classifies each run: in sync, desync with the controller's reason (`ZC_HIDDEN`: the demagnetisation hid the zero
crossing), recovered after a restart, or not started; and checks the controller's own diagnosis against the
plant's truth, the true commutation angle error. The right panel is the physics behind it, from the plant's
currents: the smallest margin from the end of the demagnetisation to the floating phase's back-EMF zero crossing
after the punch (negative: hidden). More advance widens the window (the crossing comes 30 degrees plus the advance
after a commutation); at 90 % the demagnetisation (near 50 degrees at 100 A) outgrows it, the late commutations of a
large advance narrowing it further. With the controller's defaults
(`fast_demag=True`, `demag_limit=0.6`) every point of this grid holds sync. `bldclab sensorless f60prov-2550kv
--timing 0,10,20,30 --end 0.5,0.7,0.9 --fast-demag off --demag-limit 0` writes the same map as CSV, JSON and figures.
"""

import sys

import bldclab as bl
from bldclab.analysis.desync import Axis, ThrottleStep, desync_map
from bldclab.report.desync_plots import plot_desync_map

# configure the drive: the catalog's 5-inch racing motor with its propeller load (k_q, inertia in the motor file)
drive = bl.load("f60prov-2550kv")

# configure the control: no fast demagnetisation, no demagnetisation limiter; the map varies the timing advance
# and the throttle after the punch
control = bl.SixStepSensorless(fast_demag=False, demag_limit=0.0)
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

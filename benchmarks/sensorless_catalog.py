"""The sensorless six-step drive on every catalog drive: what issue 24's closing note asks, in one table.

Per drive (``bldclab drives``), all with the default :class:`~bldclab.control.sensorless.SixStepSensorless`
(comparator against the virtual star, synchronous chopping, no advance):

- ``min pu``: the slowest imposed speed at which the closed loop holds (:func:`min_sensorless_speed`, p.u. of
  ``Omega_0``; bisection from 0.005 to 0.3 p.u. to 10 %, 6 electrical periods per speed; ``<=0.005``: it held at
  the lowest speed searched);
- ``err@x``: commutation angle error against the Hall-exact instant, mean / worst (electrical degrees, positive
  late) at 0.2, 0.5 and 0.9 ``Omega_0`` (:func:`angle_error`, 8 electrical periods after settling, imposed speed,
  the default duty: back-EMF plus the drop of half ``I_N``);
- ``dT@x``: mean torque of the sensorless drive over Hall six-step's at equal duty and speed, minus one (%; the
  duty at which Hall six-step gives half ``I_N``'s torque; ``*``: out of Hall six-step's reach, compared at full
  duty), and
  ``eta@x`` both efficiencies (sensorless / Hall, %) (:func:`versus_hall`, same points and periods);
- ``start``: successes / attempts over a small start-up grid (:func:`startup_grid`): added load 0, 0.5 and 0.9
  times the closed-form bound at the drive's inertia (:func:`startup_load_bound`) and 1.3 times the static torque
  (the ramp current's best torque, ``k_pair I``), inertia 1 and 2 times the drive's, initial angle 0.3, 2.5 and
  4.4 rad (24 starts); ``in bound``: successes / attempts among the points within their bound (at their inertia);
  ``fail``: the failures' names; ``t_cl``: median time to closed loop (ms).

Short durations and few points, so that it runs in minutes on a loaded 2-core machine; an entry that cannot run
says why. Run: ``PYTHONPATH=src python benchmarks/sensorless_catalog.py [--drives a,b] [--workers N]``.
"""

from __future__ import annotations

import argparse
import math
import time
from collections import Counter
from typing import Any

import bldclab as bl
from bldclab.analysis.sensorless import (
    angle_error,
    fixed_start,
    min_sensorless_speed,
    pair_torque_constant,
    startup_grid,
    startup_load_bound,
    versus_hall,
)
from bldclab.model.catalog import names

SPEEDS = (0.2, 0.5, 0.9)
PERIODS = 8.0


def _f(x: float, fmt: str = "{:.1f}") -> str:
    return "-" if x is None or not math.isfinite(x) else fmt.format(x)


def row(name: str, workers: int) -> dict[str, Any]:
    """Measure one drive; every study in its own ``try`` so one failure does not hide the others."""
    d = bl.load(name)
    out: dict[str, Any] = {"drive": name}
    try:
        ms = min_sensorless_speed(d, rel_tol=0.1, periods=6.0)
        out["min"] = ("<=" if math.isnan(ms.lost) else "") + _f(ms.speed, "{:.3f}")
    except Exception as e:
        out["min"] = f"error: {e}"
    try:
        ae = angle_error(d, SPEEDS, periods=PERIODS)
        out["err"] = [f"{_f(m)}/{_f(w)}" + ("" if ok else "!") for m, w, ok in zip(ae.mean, ae.worst, ae.in_sync,
                                                                                     strict=True)]
    except Exception as e:
        out["err"] = [f"error: {e}"] * 3
    try:
        vh = versus_hall(d, SPEEDS, periods=PERIODS).to_pandas()
        out["dT"] = [_f(100 * x, "{:+.1f}") + ("*" if duty >= 1.0 and share < 0.98 else "") for x, duty, share in
                     zip(vh.torque_rel, vh.duties, vh.hall_share, strict=True)]
        out["eta"] = [f"{_f(100 * a, '{:.0f}')}/{_f(100 * b, '{:.0f}')}" for a, b in
                      zip(vh.efficiency_sl, vh.efficiency_hall, strict=True)]
    except Exception as e:
        out["dT"] = out["eta"] = [f"error: {e}"] * 3
    try:
        ctl = fixed_start(d)
        su = ctl.start_up(d)
        static = pair_torque_constant(d) * su["align_current"]
        b0 = startup_load_bound(d, ctl)
        loads = (0.0, max(0.5 * b0, 0.0), max(0.9 * b0, 0.0), 1.3 * static)
        j = d.mechanics.J
        g = startup_grid(d, loads, (j, 2 * j), (0.3, 2.5, 4.4), workers=workers)
        df = g.to_pandas()
        ok, n = g.within_bound()
        fails = Counter(f for f in df.failure if f)
        out["start"] = f"{g.successes}/{g.attempts}"
        out["inb"] = f"{ok}/{n}"
        out["fail"] = ", ".join(f"{k} x{v}" for k, v in sorted(fails.items())) or "-"
        out["tcl"] = _f(1e3 * g.median_time(), "{:.0f}")
        out["bound"] = f"{b0:.3g}/{static:.3g}"
        miss = df[(df.load <= df.bound) & ~df.success]
        out["miss"] = [f"load {r.load:.3g} N m, J {r.inertia:.3g}, angle {r.angle}: {r.failure} "
                       f"(rotor at {r.speed_end:.3g} rad/s)" for r in miss.itertuples()]
    except Exception as e:
        out.update({"start": f"error: {e}", "inb": "-", "fail": "-", "tcl": "-", "bound": "-", "miss": []})
    return out


def main() -> None:
    """Print the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drives", default="", help="comma-separated drive names (default: the whole catalog)")
    ap.add_argument("--workers", type=int, default=2, help="processes for the start-up grid")
    args = ap.parse_args()
    todo = [x for x in args.drives.split(",") if x] or list(names())
    head = ["drive", "min pu", *(f"err@{s}" for s in SPEEDS), *(f"dT@{s} %" for s in SPEEDS),
            *(f"eta@{s} %" for s in SPEEDS), "start", "in bound", "fail", "t_cl ms", "bound/static N m"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    notes = []
    t0 = time.perf_counter()
    for name in todo:
        r = row(name, args.workers)
        cells = [r["drive"], r["min"], *r["err"], *r["dT"], *r["eta"], r["start"], r["inb"], r["fail"], r["tcl"],
                 r["bound"]]
        print("| " + " | ".join(str(c) for c in cells) + " |", flush=True)
        notes += [f"{name}: start failed within the bound: {m}" for m in r["miss"]]
    for n in notes:
        print(n)
    print(f"({time.perf_counter() - t0:.0f} s; err: mean/worst deg electrical, '!' = the loop did not hold; "
          f"dT '*': half I_N's torque out of Hall six-step's reach, compared at full duty; eta: sensorless/Hall; "
          f"{len(todo)} drives)")


if __name__ == "__main__":
    main()

"""The one-hour hill climb: fast mode against the switching plant over its first seconds; hot vs cold characteristic.

Prints tables (docs/thermal.md quotes them). Run: PYTHONPATH=src python benchmarks/thermal_profile.py; with
``--hour`` also the whole hour in both modes and both supplies (the switching runs take minutes).
"""

from __future__ import annotations

import math
import sys

import numpy as np

from bldclab.analysis.experiments import steady_state
from bldclab.analysis.thermal import LoadProfile, envelope, read_profile, run_profile
from bldclab.control import Sine, SixStep
from bldclab.model import catalog


def first_seconds() -> None:
    """Fast and switching runs of the hill climb's first 30 s; the switching run's wall time per simulated second."""
    d = catalog.load("htm-48v-losses")
    prof = read_profile("examples/profiles/hill-climb.toml")
    short = LoadProfile(times=(0.0, 30.0), speed=(prof.speed[0],) * 2, torque=(prof.torque[0],) * 2)
    print("hill climb, first 30 s on htm-48v-losses (h = 0.5 s): fast against switching")
    print(f"{'supply':>7} {'wall sw':>8} {'wall fast':>9} {'rise w':>7} {'max dT w':>9} {'rise j':>7} {'max dT j':>9}")
    for s in ("square", "sine"):
        sw = run_profile(d, short, supply=s, mode="switching", h=0.5)
        fa = run_profile(d, short, supply=s, mode="fast", h=0.5)
        dw = float(np.max(np.abs(sw.trace.T["winding"] - fa.trace.T["winding"])))
        dj = float(np.max(np.abs(sw.trace.T["junction"] - fa.trace.T["junction"])))
        print(f"{s:>7} {sw.wall:8.2f} {fa.wall:9.2f} {sw.trace.T['winding'][-1] - 25:7.3f} {dw:9.4f} "
              f"{sw.trace.T['junction'][-1] - 25:7.3f} {dj:9.4f}")
    full = run_profile(d, prof, supply="sine", mode="fast", h=1.0)
    print(f"whole hour, fast, sine: wall {full.wall:.1f} s; switching would take about "
          f"{sw.wall / 30.0 * 3600.0:.0f} s")


def hot_and_cold() -> None:
    """Torque at I_N-equivalent reference over speed at 25 degC and at the continuous hot state."""
    d = catalog.load("htm-48v")
    th = d.thermal
    assert th is not None
    w40 = 40.0
    env = envelope(d, [w40], supply="sine", tol=0.002)
    q = float(env.reference[0])
    hot_run = run_profile(d, LoadProfile(times=(0.0, 10000.0), speed=(w40, w40), torque=(q, q)), h=50.0,
                          compensated=True)
    T = hot_run.trace.final()
    hot = d.at_temperature(winding=T["winding"], magnets=T["rotor"])
    print(f"\nhtm-48v hot steady state at the continuous torque {q:.2f} N m, {w40 * 30 / math.pi:.0f} rpm: winding "
          f"{T['winding']:.1f} degC (R x {1 + th.alpha_R_value * (T['winding'] - 25):.3f}), magnets {T['rotor']:.1f} "
          f"degC (k x {1 + th.alpha_k * (T['rotor'] - 25):.4f})")
    print("torque (N m) at reference 30 N m, controller configured from the cold drive (a firmware without a sensor)")
    print(f"{'rpm':>5} {'sq cold':>8} {'sq hot':>8} {'sin cold':>8} {'sin hot':>8}")
    for rpm in (200, 400, 500, 550, 600, 650):
        w = rpm * math.pi / 30
        row = []
        for ctl in (SixStep(reference="torque"), Sine(handoff_speed=5.0)):  # type: ignore[arg-type]
            for plant in (d, hot):
                p, _ = steady_state(plant, ctl, w, 30.0, estimate=d)
                row.append(p.tau_mean)
        print(f"{rpm:5d} " + " ".join(f"{v:8.2f}" for v in row))


def whole_hour() -> None:
    """The whole hill climb in both modes: peaks and losses."""
    d = catalog.load("htm-48v-losses")
    prof = read_profile("examples/profiles/hill-climb.toml")
    print("\nwhole hour on htm-48v-losses, h = 1 s")
    print(f"{'supply':>7} {'mode':>10} {'wall':>7} {'peak w':>7} {'end w':>7} {'peak j':>7} {'losses Wh':>9}")
    for s in ("square", "sine"):
        for mode in ("switching", "fast"):
            r = run_profile(d, prof, supply=s, mode=mode, h=1.0)
            T = r.trace.T
            print(f"{s:>7} {mode:>10} {r.wall:7.1f} {T['winding'].max():7.2f} {T['winding'][-1]:7.2f} "
                  f"{T['junction'].max():7.2f} {r.trace.E_loss / 3600:9.2f}")


if __name__ == "__main__":
    first_seconds()
    hot_and_cold()
    if "--hour" in sys.argv:
        whole_hour()

"""Sensorless sinusoidal supply: the observers' angle error against the plant's true angle (issue 26).

For each catalog drive, observer and speed: the rotor starts from standstill (the drive's inertia, no load), the
sensorless drive starts it (I/f, hand-off to the observer) and its speed loop brings it to the speed; then a load
rises to half the rated torque ``T_s,N / 2`` (at least 0.3 s, slow enough for the speed PI's ramp error
``(dtau/dt) / k_i,w`` to stay below 20 % of the speed), and over the last 20 electrical periods the angle error
``theta^ - theta_e`` (deg electrical, rms and worst) is read against the plant's angle, with the mean torque and
efficiency beside those of the encoder-based ``Sine`` run the same way. The hand-off speed is at most half the
point's, the return to the start mode (loss of lock) at a quarter of it.

Then, on each drive at 0.5 Omega_0 (flux observer), the sensitivity: the controller configured with the flux
linkage off by +-25 %, R by +-50 %, L by +-30 %, and again from what self-commissioning measured starting from that
wrong data; and the commissioning accuracy (R, L, psi_f against the plant's) with the time it takes.

Then the current-sensor errors (``--sensors [DRIVE ...]`` alone): an offset on phase a and white noise on the
measured phases, the controller unaware of them. And the start-up map (``--startup [DRIVE ...]`` alone): load kind x
load x inertia x initial angle, with the design bound of the load-adaptive ramp; ``--kinds passive,brake``,
``--inertias 1,5``, ``--loads 0.75,0.9`` select a part of it, ``--dump FILE`` writes each start to FILE. And the
controller's own estimates (``--estimates
[DRIVE ...]`` alone): each wrong parameter without them, with the zero-current flux reading (``if_flux_estimate``) and
with it and the alignment's resistance (``if_r_estimate``). And the commissioning with current-sensor errors
(``--commission-sensors [DRIVE ...]`` alone): offsets, white noise and a 12-bit ADC, fractions of the full scale
``2 I_N``, each case's R, L, psi_f errors, status and time on the drive. And the flux linkage's residual with the
inverter's dead time (``--commission-deadtime [DRIVE ...]`` alone): 1 % and 3 % of the PWM period, 0.7-V diodes,
``R_on = 0.2 R``, the spin at 0.3, 0.45 and 0.6 ``Omega_N``. And dead time with current noise
(``--commission-deadtime-noise [DRIVE ...]`` alone): no dead time and 1 % of the period, noise 0.2 % and 1 % of
``2 I_N`` on a 12-bit ADC, eight noise seeds each: the runs that end DONE, rms errors of R, L, psi_f, L's worst, the
mean time. And the flying-start map (``--catch [DRIVE ...]`` alone, ``--dump FILE``): the rotor turning at t = 0 (-0.5
to 1.0 ``Omega_0``) x load x initial angle, the catch with the alignment's current on and at zero current
(``catch_zero_current``). And the sensitivity with the alignment's resistance estimate off and on (``--sensitivity
[DRIVE ...]`` alone); ``--startup ... --r-estimate`` (or ``--zc-catch``) runs the start-up map with it.

Run: ``PYTHONPATH=src python benchmarks/sensorless_sine.py [--PART] [DRIVE ...]`` (``--help`` lists the parts and
their options; an unknown drive or a misplaced option: exit 2).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

import bldclab as bl
from bldclab.errors import BldclabError
from bldclab.model.analytic import i_sN, r_total
from bldclab.sim import Scenario, simulate

SPEEDS = (0.05, 0.1, 0.25, 0.5, 0.75, 0.9)  # of Omega_0 (at Omega_0 itself the back-EMF takes the whole bus)


def angle_error(drive: bl.Drive, control: bl.Sine, speed: float, torque: float, t_load: float, t_ramp: float,
                duration: float, estimate: bl.Drive | None = None) -> dict[str, float]:
    """Run one point (speed loop to ``speed``, load ``torque`` from ``t_load``); return the angle error (deg, rms and
    worst over the window, sine mode only), the mean torque (N m), efficiency (-) and the window's share of the sine
    mode (-)."""
    t0 = duration - 20 * 2 * math.pi / (drive.motor.p * speed)
    r = simulate(drive, dataclasses.replace(control, speed_loop=True),
                 Scenario(duration=duration, omega_ref=speed, trace_every=4,
                          load_torque=lambda t: torque * np.clip((t - t_load) / t_ramp, 0.0, 1.0),
                          window=(t0, duration)), estimate=estimate)
    t = r["t"]
    last = t >= t0
    on = last & (r["mode"] > 0.5)
    err = np.degrees(np.angle(np.exp(1j * (r["theta"] - r["theta_e"]))))[on]
    m = r.metrics
    mode = r["mode"] > 0.5
    t_lock = float(t[int(np.argmax(mode))]) if mode.any() else math.nan
    restarts = float(r.meta.get("flags", {}).get("DESYNC", {}).get("run", {}).get("samples", 0))
    return {"rms": float(np.sqrt(np.mean(err**2))) if err.size else math.nan,
            "t_lock": t_lock, "restarts": restarts,
            "mean": float(np.mean(err)) if err.size else math.nan,
            "worst": float(np.max(np.abs(err))) if err.size else math.nan,
            "sine": float(on.sum() / max(last.sum(), 1)), "tau": m.tau_mean, "eff": m.efficiency}


#: The wrong parameters of the sensitivity and estimate tables: label, Drive.scaled factors.
ESTIMATE_CASES = (("true", {}), ("psi +25 %", {"emf": 1.25}), ("psi -25 %", {"emf": 0.75}), ("R +50 %", {"R": 1.5}),
                  ("R -50 %", {"R": 0.5}), ("L +30 %", {"L": 1.3}), ("L -30 %", {"L": 0.7}))


def loaded_point(d: bl.Drive) -> tuple[float, float, bl.Sine, float, float, float]:
    """The sensitivity tables' operating point: half the rated load at 0.5 Omega_0 behind an observer start.

    Returns the torque (N m), the speed (rad/s), the controller (hand-off at 0.1 Omega_N or half the speed), the
    load's instant, its ramp time and the run's duration (s): the start, the load ramp and 20 electrical periods.
    """
    torque = 0.5 * 1.5 * bl.control.sine.fundamental_k1(d) * i_sN(d)
    w = 0.5 * d.Omega_0
    on = min(0.1 * d.motor.Omega_nominal, 0.5 * w)
    ctl = bl.Sine(angle="observer", handoff_speed=on, handoff_hysteresis=0.5)
    st = ctl.sensorless_settings(d)
    t_load = st["if_align"] + d.motor.p * on / st["if_accel"] + 2 * st["lock_time"] + d.mechanics.J * w / torque + 0.3
    wb = 2 * math.pi * ctl.speed_bandwidth_hz
    t_ramp = max(0.3, torque / (d.mechanics.J * wb**2 / 4 * 0.2 * w))
    dur = t_load + t_ramp + 0.3 + 20 * 2 * math.pi / (d.motor.p * w)
    return torque, w, ctl, t_load, t_ramp, dur


def sensitivity(names: list[str], cases: tuple[str, ...] | None = None, **options: object) -> None:
    """Print the angle error and torque with wrong parameters, then after commissioning from them.

    ``cases``: the labels of :data:`ESTIMATE_CASES` to run (default all); ``options``: settings of the controller
    (:class:`bl.Sine`, e.g. ``if_r_estimate=True``), printed in the header. Columns: the time of the first hand-off
    (s), the angle error (deg, rms / worst over the last 20 electrical periods, sine mode only; ``nan``: not in the
    sine mode there), the window's share in the sine mode and the mean torque (N m), then the same after
    commissioning.
    """
    print(f"\n{'drive':16s} {'estimate':12s} {'t_lock':>7s} {'rms deg':>8s} {'worst':>8s} {'sine':>5s} {'tau':>9s} "
          f"{'after comm.':>11s} {'worst':>8s} {'tau':>9s}   {options or ''}")
    for name in names:
        d = bl.load(name)
        torque, w, ctl, t_load, t_ramp, dur = loaded_point(d)
        ctl = dataclasses.replace(ctl, **options)  # type: ignore[arg-type]
        for label, kw in ESTIMATE_CASES:
            if cases is not None and label not in cases:
                continue
            wrong = d.scaled(**kw) if kw else None
            a = angle_error(d, ctl, w, torque, t_load, t_ramp, dur, estimate=wrong)
            e = bl.commission(d, nominal=wrong) if wrong is not None else None
            b = angle_error(d, ctl, w, torque, t_load, t_ramp, dur, estimate=e.drive) if e and e.ok else None
            after = f"{b['rms']:11.3f} {b['worst']:8.3f} {b['tau']:9.4g}" if b else f"{'-':>11s} {'-':>8s} {'-':>9s}"
            print(f"{name:16s} {label:12s} {a['t_lock']:7.2f} {a['rms']:8.3f} {a['worst']:8.3f} {a['sine']:5.2f} "
                  f"{a['tau']:9.4g} {after}", flush=True)


ESTIMATE_VARIANTS = (("none", {"if_flux_estimate": False, "if_r_estimate": False}),
                     ("flux", {"if_flux_estimate": True, "if_r_estimate": False}),
                     ("flux+R", {"if_flux_estimate": True, "if_r_estimate": True}))


def estimates(names: list[str]) -> None:
    """Print, per drive and wrong parameter, the start and the angle error without the controller's own estimates,
    with the flux linkage estimate (``if_flux_estimate``) and with it and the alignment's resistance
    (``if_r_estimate``), at two points: 0.5 Omega_0 under half the rated load (as :func:`sensitivity`, its hand-off
    speed) and 0.3 Omega_0 unloaded (the drive's default hand-off, as the start tests). Columns: the time of the
    first hand-off (s), the restarts (DESYNC), the angle error (deg, rms / worst over the last 20 electrical periods,
    sine mode only), the window's share in the sine mode and the mean torque (N m)."""
    print(f"\n{'drive':16s} {'point':9s} {'case':10s} {'estimates':9s} {'t_lock':>7s} {'restarts':>8s} "
          f"{'rms deg':>8s} {'worst':>8s} {'sine':>5s} {'tau':>9s}")
    for name in names:
        d = bl.load(name)
        torque, w, ctl, t_load, t_ramp, dur = loaded_point(d)
        ctl3 = bl.Sine(angle="observer")
        st3 = ctl3.sensorless_settings(d)
        w3 = 0.3 * d.Omega_0
        dur3 = st3["if_align"] + d.motor.p * ctl3.handoff(d) / st3["if_accel_min"] + st3["if_hold"] \
            + d.mechanics.J * w3 / (0.5 * ctl3.torque_limit(d)) + 0.5
        points = (("0.5 load", ctl, w, torque, t_load, t_ramp, dur), ("0.3 none", ctl3, w3, 0.0, dur3, 1.0, dur3))
        for point, c0, wp, tq, tl, tr, du in points:
            for label, kw in ESTIMATE_CASES:
                wrong = d.scaled(**kw) if kw else None
                for vlabel, vkw in ESTIMATE_VARIANTS:
                    c = dataclasses.replace(c0, **vkw)  # type: ignore[arg-type]
                    a = angle_error(d, c, wp, tq, tl, tr, du, estimate=wrong)
                    print(f"{name:16s} {point:9s} {label:10s} {vlabel:9s} {a['t_lock']:7.2f} {a['restarts']:8.0f} "
                          f"{a['rms']:8.3f} {a['worst']:8.3f} {a['sine']:5.2f} {a['tau']:9.4g}", flush=True)


STARTUP_LOADS = (0.0, 0.5, 0.75, 0.9, 0.95, 1.0)  # of the I/f torque 1.5 k_1 if_current
STARTUP_J = (0.5, 1.0, 2.0, 5.0)  # the plant's inertia over the nominal the controller is configured with
STARTUP_ANGLES = (0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi + 0.05)  # rotor at t = 0 (rad, electrical): the
# vector's own q axis, the aligned rest angle (pi/2 ahead), a quarter turn off, next to the unstable point
STARTUP_KINDS = ("passive", "brake", "active")


SENSOR_CASES = (("none", 0.0, 0.0), ("offset 1 %", 0.01, 0.0), ("offset 2 %", 0.02, 0.0), ("noise 0.5 %", 0.0, 0.005),
                ("noise 1 %", 0.0, 0.01))  # phase a's offset and every phase's noise (std), of I_s,N


def sensor_errors(names: list[str], speeds: tuple[float, ...] = (0.1, 0.5)) -> None:
    """Print the angle error and torque with current-sensor errors: an offset on phase a, white noise on each
    measured phase (``Sensors.current_offset``, ``current_noise``), at a fraction of ``Omega_0`` under half the
    rated load (as :func:`main`), both observers, the controller unaware of them.

    An offset ``D`` on phase a, with phases a and b measured, is the constant vector ``D (1 + j / sqrt(3))`` in
    alpha-beta: the observers integrate ``R D`` as a voltage and subtract ``L D`` from the flux, so the angle error
    gets a ripple at the electrical frequency and the current loops drive the true current off by the offset (a torque
    ripple at the electrical frequency, zero mean). Noise enters the observers' flux through ``L i`` and the PLL.
    """
    print(f"\n{'drive':16s} {'obs':8s} {'speed':>6s} {'sensor error':14s} {'rms deg':>8s} {'worst':>8s} "
          f"{'mean':>8s} {'tau':>9s}")
    for name in names:
        d = bl.load(name)
        torque = 0.5 * 1.5 * bl.control.sine.fundamental_k1(d) * i_sN(d)
        for frac in speeds:
            w = frac * d.Omega_0
            on = min(0.1 * d.motor.Omega_nominal, 0.5 * w)
            ctl = bl.Sine(angle="observer", handoff_speed=on, handoff_hysteresis=0.5)
            st = ctl.sensorless_settings(d)
            t_load = st["if_align"] + d.motor.p * on / st["if_accel"] + 2 * st["lock_time"] \
                + d.mechanics.J * w / torque + 0.3
            wb = 2 * math.pi * ctl.speed_bandwidth_hz
            t_ramp = max(0.3, torque / (d.mechanics.J * wb**2 / 4 * 0.2 * w))
            dur = t_load + t_ramp + 0.3 + 20 * 2 * math.pi / (d.motor.p * w)
            for label, off, noise in SENSOR_CASES:
                plant = d.replace(sensors__current_offset=(off * i_sN(d), 0.0, 0.0),
                                  sensors__current_noise=noise * i_sN(d))
                for obs in ("flux", "reduced"):
                    a = angle_error(plant, dataclasses.replace(ctl, observer=obs), w, torque, t_load, t_ramp, dur,
                                    estimate=d)
                    print(f"{name:16s} {obs:8s} {frac:6.2f} {label:14s} {a['rms']:8.3f} {a['worst']:8.3f} "
                          f"{a['mean']:8.3f} {a['tau']:9.4g}", flush=True)


RHO_LO, RHO_HI = 0.6, 0.95  # bc_sine.h: the load-adaptive ramp's band (BC_SINE_RHO_LO, BC_SINE_RHO_HI)


def startup_bound(st: dict[str, float], J: float, p: int, tau_if: float, tau_f: float = 0.0) -> float:
    """Return the largest load (a fraction of the I/f torque ``tau_if``) the start is designed to carry.

    In the ramp the rotor's torque share ``rho`` (its load angle's cosine) sets the acceleration ``a = a_max (RHO_HI
    - rho) / (RHO_HI - RHO_LO)``, and ``rho tau_if = tau_L + tau_f + J a / p`` with ``tau_f`` the drive's own
    friction at the hand-off speed (``tau_c + B omega_on``, N m); the ramp fails (START_FAIL) when its mean
    acceleration is below ``a_min`` (``omega_on / a_min`` below the top). Equilibrium at ``a = a_min``:
    ``tau_L / tau_if = RHO_HI - (RHO_HI - RHO_LO) a_min / a_max - J a_min / (p tau_if) - tau_f / tau_if``.
    """
    return (RHO_HI - (RHO_HI - RHO_LO) * st["if_accel_min"] / st["if_accel"] - J * st["if_accel_min"] / (p * tau_if)
            - tau_f / tau_if)


def startup_case(d: bl.Drive, fl: float, kj: float, theta0: float, kind: str, **options: object
                 ) -> dict[str, float]:
    """One start: the controller configured from the nominal drive, the plant's inertia ``kj J``, a load of ``fl``
    times the I/f torque, speed loop to 0.3 Omega_0.

    ``kind``: ``passive`` a Coulomb-type load (the plant's friction ``tau_c``: against the motion, holding the
    rotor at rest while the motor's torque is below it), ``brake`` an active constant load released at ``if_align``
    (a brake; the alignment's two steps, then its wait and closing sweep), ``active`` an active constant load from
    t = 0 (the legs still off). Returns ``ok``
    (1: in the sine mode at the end, the speed within 5 %), ``bound`` (the load fraction the start is designed
    for, :func:`startup_bound` with the drive's own friction; ``bound0`` without it), ``t_lock`` (s, the first
    sample in the sine mode), ``restarted`` (1: a DESYNC, a failed start or a lost lock, before the end), ``flags``
    and the I/f torque ``tau_if`` (N m). ``options``: further settings of the controller (:class:`bl.Sine`).
    """
    ctl = bl.Sine(angle="observer", speed_loop=True, **options)  # type: ignore[arg-type]
    st = ctl.sensorless_settings(d)
    tau_if = 1.5 * bl.control.sine.fundamental_k1(d) * st["if_current"]
    w = 0.3 * d.Omega_0
    mech = dataclasses.replace(d.mechanics, J=kj * d.mechanics.J,
                               tau_c=d.mechanics.tau_c + (fl * tau_if if kind == "passive" else 0.0))
    plant = dataclasses.replace(d, mechanics=mech)
    load: float | Callable[[NDArray[np.float64]], NDArray[np.float64]] = 0.0
    if kind == "active":
        load = fl * tau_if
    elif kind == "brake":
        t_rel = st["if_align"]
        load = lambda t: np.where(t >= t_rel, fl * tau_if, 0.0)  # noqa: E731
    p = d.motor.p
    t_ramp = p * ctl.handoff(d) / st["if_accel_min"]  # the slowest ramp
    t_acc = mech.J * w / max(ctl.torque_limit(d) - fl * tau_if, 0.1 * ctl.torque_limit(d))
    t_zc = 3 * st["lock_time"] if ctl.catch_zero_current else 0.0  # the zero-current catch's wait (each alignment)
    dur = 2 * (t_zc + st["if_align"] + t_ramp + 4 * st["lock_time"]) + t_acc + 0.5
    r = simulate(plant, ctl, Scenario(duration=dur, omega_ref=w, load_torque=load, theta0=theta0, trace_every=16),
                 estimate=d)
    on = r["mode"] > 0.5
    ok = bool(on[-1]) and abs(r["omega_m"][-1] / w - 1) < 0.05
    tau_f = d.mechanics.tau_c + d.mechanics.B * ctl.handoff(d)  # the drive's own friction at the hand-off speed
    return {"ok": float(ok), "bound": startup_bound(st, mech.J, p, tau_if, tau_f),
            "bound0": startup_bound(st, mech.J, p, tau_if),
            "t_lock": float(r["t"][on][0]) if on.any() else math.nan, "restarted": float("DESYNC" in r.flags_raised),
            "tau_if": tau_if, "flags": r.flags_raised}


def startup_map(names: list[str], kinds: tuple[str, ...] = STARTUP_KINDS, inertias: tuple[float, ...] = STARTUP_J,
                loads: tuple[float, ...] = STARTUP_LOADS, dump: str | None = None, **options: object) -> None:
    """Print the start-up's success over load torque x inertia x initial angle, per load kind (``startup_case``).

    One line per drive, load kind, inertia and load: the starts that succeeded out of the initial angles, the
    bound (the load fraction within which the start is designed to succeed, counting the drive's own friction),
    the time to the hand-off (s, range) and the starts that restarted at least once (DESYNC); failures are named by
    their flags. Then, per load kind, the starts that succeeded within the bound without and with the drive's own
    friction (``startup_bound``). ``kinds``, ``inertias`` and ``loads`` select a part of the map; ``dump``, a file
    to which each start is written as a line ``drive kind J load angle ok t_lock`` (to compare two versions start by
    start); ``options``, settings of the controller (:class:`bl.Sine`, e.g. ``if_r_estimate=True``).
    """
    if options:
        print(f"\ncontroller options: {options}")
    print(f"\n{'drive':16s} {'load kind':9s} {'J/J_nom':>7s} {'load/tau_if':>11s} {'bound':>6s} {'ok':>5s} "
          f"{'t_lock s':>13s} {'restarts':>8s}  flags of the failures")
    within: dict[tuple[str, str], list[int]] = {}
    t_locks: dict[str, list[float]] = {}
    for name in names:
        d = bl.load(name)
        for kind in kinds:
            for kj in inertias:
                for fl in loads:
                    runs = [startup_case(d, fl, kj, th, kind, **options) for th in STARTUP_ANGLES]
                    if dump:
                        with open(dump, "a", encoding="utf-8") as f:
                            for th, r in zip(STARTUP_ANGLES, runs, strict=True):
                                f.write(f"{name} {kind} {kj:g} {fl:g} {th:.4f} {int(r['ok'])} {r['t_lock']:.6f}\n")
                    for label, b in (("without", runs[0]["bound0"]), ("with", runs[0]["bound"])):
                        if fl <= b:
                            n_ok = within.setdefault((kind, label), [0, 0])
                            n_ok[0] += sum(int(r["ok"]) for r in runs)
                            n_ok[1] += len(runs)
                    good = [r for r in runs if r["ok"]]
                    tl = [r["t_lock"] for r in good]
                    t_locks.setdefault(kind, []).extend(tl)
                    tls = f"{min(tl):.2f}-{max(tl):.2f}" if tl else "-"
                    fails = sorted({r["flags"] for r in runs if not r["ok"]})
                    print(f"{name:16s} {kind:9s} {kj:7.1f} {fl:11.2f} {runs[0]['bound']:6.3f} "
                          f"{len(good):>2d}/{len(runs):<2d} {tls:>13s} {sum(r['restarted'] for r in runs):8.0f}  "
                          f"{'; '.join(fails)}", flush=True)
    print("\nwithin the bound (without / with the drive's own friction), starts that succeeded:")
    for kind in kinds:
        a, b = within.get((kind, "without"), [0, 0]), within.get((kind, "with"), [0, 0])
        print(f"{kind:9s} {a[0]:4d} / {a[1]:<4d} {b[0]:4d} / {b[1]:<4d}")
    every = [t for k in kinds for t in t_locks.get(k, [])]
    print("median time to the first hand-off over the starts that succeeded (s): "
          + ", ".join(f"{k} {np.median(t_locks[k]):.3f}" for k in kinds if t_locks.get(k))
          + (f", all {np.median(every):.3f} ({len(every)} starts)" if every else ""))


CATCH_SPEEDS = (-0.5, -0.2, -0.05, 0.0, 0.05, 0.2, 0.5, 1.0)  # the rotor's speed at t = 0, of Omega_0
CATCH_LOADS = ("none", "passive", "active")  # no load; 0.5 tau_if of Coulomb friction; 0.5 tau_if active from t = 0
CATCH_LOAD = 0.5  # of the I/f torque


def catch_case(d: bl.Drive, w0: float, kind: str, theta0: float, zc: bool, **options: object) -> dict[str, Any]:
    """One flying start: the rotor turning at ``w0 Omega_0`` when the drive starts (``Scenario.omega0``), the
    controller configured from the drive (``catch_zero_current=zc``, ``options`` passed to :class:`bl.Sine`), speed
    loop to 0.3 Omega_0.

    ``kind``: ``none``; ``passive``, the plant's Coulomb friction raised by 0.5 of the I/f torque (against the
    motion: it slows a coasting rotor and holds one at rest); ``active``, a constant load of 0.5 of the I/f torque
    from t = 0, pushing the rotor backwards. Returns ``ok`` (1: in the sine mode at the end, the speed within 5 %),
    ``first`` (``ok`` and neither DESYNC nor OVERCURRENT raised: no restart), ``t_lock`` (s, the first sample in the
    sine mode), ``caught`` (1: that sample came before the alignment's end, a catch rather than a hand-off at the top
    of the I/f ramp), ``i_peak`` (the largest phase current of the run over ``I_s,N``), ``err`` (deg, the worst angle
    error against the plant in the sine mode after the first 2 lock times there) and ``flags``.
    """
    ctl = bl.Sine(angle="observer", speed_loop=True, catch_zero_current=zc, **options)  # type: ignore[arg-type]
    st = ctl.sensorless_settings(d)
    tau_if = 1.5 * bl.control.sine.fundamental_k1(d) * st["if_current"]
    w = 0.3 * d.Omega_0
    tau_l = CATCH_LOAD * tau_if if kind != "none" else 0.0
    mech = dataclasses.replace(d.mechanics, tau_c=d.mechanics.tau_c + (tau_l if kind == "passive" else 0.0))
    plant = dataclasses.replace(d, mechanics=mech)
    p = d.motor.p
    t_ramp = p * ctl.handoff(d) / st["if_accel_min"]  # the slowest ramp
    t_acc = mech.J * (abs(w0) * d.Omega_0 + w) / max(ctl.torque_limit(d) - tau_l, 0.1 * ctl.torque_limit(d))
    t_zc = 3 * st["lock_time"] if zc else 0.0
    dur = 2 * (t_zc + st["if_align"] + t_ramp + 4 * st["lock_time"]) + t_acc + 0.5
    r = simulate(plant, ctl, Scenario(duration=dur, omega_ref=w, omega0=w0 * d.Omega_0, theta0=theta0,
                                      load_torque=tau_l if kind == "active" else 0.0, trace_every=4), estimate=d)
    on = r["mode"] > 0.5
    ok = bool(on[-1]) and abs(r["omega_m"][-1] / w - 1) < 0.05
    flags = r.flags_raised
    t_lock = float(r["t"][on][0]) if on.any() else math.nan
    i_pk = float(np.max(np.abs(np.stack([r["i_a"], r["i_b"], r["i_c"]]))))
    settled = on & (r["t"] >= t_lock + 2 * st["lock_time"]) if on.any() else on
    err = np.degrees(np.abs(np.angle(np.exp(1j * (r["theta"] - r["theta_e"])))))[settled]
    return {"ok": float(ok), "first": float(ok and "DESYNC" not in flags and "OVERCURRENT" not in flags),
            "t_lock": t_lock, "caught": float(t_lock <= t_zc + st["if_align"]), "i_peak": i_pk / i_sN(d),
            "err": float(np.max(err)) if err.size else math.nan, "flags": flags}


def catch_map(names: list[str], speeds: tuple[float, ...] = CATCH_SPEEDS, kinds: tuple[str, ...] = CATCH_LOADS,
              dump: str | None = None, **options: object) -> None:
    """Print the flying start's success over the rotor's initial speed x load, for the catch with the alignment's
    current on and at zero current (``catch_zero_current`` False, True), four initial angles each
    (:func:`catch_case`).

    One line per drive, load and speed: per catch mode the starts that succeeded on their first attempt out of the
    angles (in brackets those that succeeded only after a restart), how many were caught in the alignment, the time
    to the sine mode (s, range), the peak phase current (``I_s,N``, largest over the angles), the worst angle
    error after the lock (deg) and the flags of the failures. Then the totals per catch mode, and the cells where one
    mode succeeded more often than the other. ``dump``: each start written to FILE as a line ``drive load w0 angle
    zc first ok t_lock i_peak``.
    """
    print(f"\n{'drive':16s} {'load':7s} {'w0/O_0':>6s} {'w0/w_on':>7s} | {'current on: ok':>14s} {'caught':>6s} "
          f"{'t_lock s':>11s} {'i_pk':>5s} {'err':>5s} | {'zero current: ok':>16s} {'caught':>6s} {'t_lock s':>11s} "
          f"{'i_pk':>5s} {'err':>5s} | flags of the failures (on; zero)")
    tot = {False: [0, 0, 0], True: [0, 0, 0]}
    diff: list[str] = []
    for name in names:
        d = bl.load(name)
        w_on = bl.Sine(angle="observer").handoff(d)
        for kind in kinds:
            for w0 in speeds:
                cells, fails, firsts = [], [], {}
                for zc in (False, True):
                    runs = [catch_case(d, w0, kind, th, zc, **options) for th in STARTUP_ANGLES]
                    if dump:
                        with open(dump, "a", encoding="utf-8") as f:
                            for th, r in zip(STARTUP_ANGLES, runs, strict=True):
                                f.write(f"{name} {kind} {w0:g} {th:.4f} {int(zc)} {int(r['first'])} {int(r['ok'])} "
                                        f"{r['t_lock']:.6f} {r['i_peak']:.4f}\n")
                    n1 = sum(int(r["first"]) for r in runs)
                    n_ok = sum(int(r["ok"]) for r in runs)
                    tot[zc][0] += n1
                    tot[zc][1] += n_ok
                    tot[zc][2] += len(runs)
                    firsts[zc] = n1
                    tl = [r["t_lock"] for r in runs if r["ok"]]
                    tls = f"{min(tl):.3f}-{max(tl):.3f}" if tl else "-"
                    errs = [r["err"] for r in runs if r["ok"]]
                    oks = f"{n1}/{len(runs)}" + (f" ({n_ok - n1})" if n_ok > n1 else "")
                    cells.append(f"{oks:>{14 if not zc else 16}s} {sum(int(r['caught']) for r in runs):6d} {tls:>11s} "
                                 f"{max(r['i_peak'] for r in runs):5.2f} "
                                 f"{(max(errs) if errs else math.nan):5.1f}")
                    fails.append(",".join(sorted({r["flags"] for r in runs if not r["first"]})) or "-")
                if firsts[False] != firsts[True]:
                    diff.append(f"{name} {kind} {w0:g}: current on {firsts[False]}, zero current {firsts[True]}")
                print(f"{name:16s} {kind:7s} {w0:6.2f} {w0 * d.Omega_0 / w_on:7.2f} | {cells[0]} | {cells[1]} | "
                      f"{fails[0]}; {fails[1]}", flush=True)
    for zc in (False, True):
        a = tot[zc]
        print(f"catch_zero_current={zc}: first attempt {a[0]} / {a[2]}, at the end {a[1]} / {a[2]}")
    print("cells that differ (first attempt):" + ("".join(f"\n  {x}" for x in diff) if diff else " none"))


def commissioning(names: list[str]) -> None:
    """Print the commissioning accuracy and time on each drive."""
    print(f"\n{'drive':16s} {'status':8s} {'R err %':>8s} {'L err %':>8s} {'psi err %':>9s} {'t test s':>9s} "
          f"{'wall s':>7s}")
    for name in names:
        d = bl.load(name)
        e = bl.commission(d)
        k1 = bl.control.sine.fundamental_k1(d)
        print(f"{name:16s} {e.status:8s} {100 * (e.R / r_total(d) - 1):8.3f} {100 * (e.L / d.motor.L - 1):8.3f} "
              f"{100 * (e.psi_f * d.motor.p / k1 - 1):9.3f} {e.t_test:9.3f} {e.wall_time:7.2f}")


# (label, offset, noise, ADC bits): offsets (1, -0.6, 0.8) x offset on a, b, c; all fractions of I_fs = 2 I_N
COMMISSION_SENSOR_CASES = (("none", 0.0, 0.0, 0), ("offset 1 %", 0.01, 0.0, 0), ("offset 2 %", 0.02, 0.0, 0),
                           ("12-bit", 0.0, 0.0, 12), ("noise 0.2 %", 0.0, 0.002, 12), ("noise 1 %", 0.0, 0.01, 12),
                           ("1 % + 0.2 %", 0.01, 0.002, 12), ("1 % + 1 %", 0.01, 0.01, 12),
                           ("noise 2 %", 0.0, 0.02, 12))


def commissioning_sensors(names: list[str]) -> None:
    """Print the commissioning accuracy and time with current-sensor errors (the routine configured from the
    drive's own data, unaware of the errors but for what it measures with the legs off)."""
    print(f"\n{'drive':16s} {'sensors':12s} {'status':8s} {'R err %':>8s} {'L err %':>8s} {'psi err %':>9s} "
          f"{'t test s':>9s} {'wall s':>7s}")
    for name in names:
        d = bl.load(name)
        fs = 2.0 * d.motor.I_N
        k1 = bl.control.sine.fundamental_k1(d)
        for label, off, noise, bits in COMMISSION_SENSOR_CASES:
            plant = d.replace(sensors__current_offset=(off * fs, -0.6 * off * fs, 0.8 * off * fs),
                              sensors__current_noise=noise * fs,
                              sensors__current_lsb=2.0 * fs / 2**bits if bits else 0.0)
            e = bl.commission(plant, nominal=d)
            errs = [100 * (v / t - 1) if v else math.nan
                    for v, t in ((e.R, r_total(d)), (e.L, d.motor.L), (e.psi_f, k1 / d.motor.p))]
            print(f"{name:16s} {label:12s} {e.status:8s} {errs[0]:8.3f} {errs[1]:8.3f} {errs[2]:9.3f} "
                  f"{e.t_test:9.3f} {e.wall_time:7.2f}", flush=True)


def commissioning_deadtime(names: list[str], fractions: tuple[float, ...] = (0.01, 0.03),
                           spins: tuple[float, ...] = (0.3, 0.45, 0.6)) -> None:
    """Print psi_f's error (%) with a dead time (fractions of the PWM period) at spin speeds (fractions of
    ``Omega_N``); the routine told the dead time and the diode drop."""
    print(f"\n{'drive':16s} {'t_dead':>7s} " + " ".join(f"{'spin ' + str(s):>22s}" for s in spins))
    for name in names:
        d = bl.load(name)
        k1 = bl.control.sine.fundamental_k1(d)
        for frac in fractions:
            inv = dataclasses.replace(d.inverter, t_dead=frac / d.inverter.f_pwm, V_f=0.7, R_on=0.2 * d.motor.R)
            plant = dataclasses.replace(d, inverter=inv)
            cells = []
            for sp in spins:
                e = bl.commission(plant, control=bl.control.Commission(spin_speed=sp * d.motor.Omega_nominal))
                err = 100 * (e.psi_f * d.motor.p / k1 - 1) if e.ok else math.nan
                cells.append(f"{e.status[:8]:>8s} {err:7.3f} {e.t_test:5.2f}s")
            print(f"{name:16s} {100 * frac:6.1f}% " + " ".join(f"{c:>22s}" for c in cells), flush=True)


def commissioning_deadtime_noise(names: list[str], fractions: tuple[float, ...] = (0.0, 0.01),
                                 noises: tuple[float, ...] = (0.002, 0.01), seeds: int = 8) -> None:
    """Print, over ``seeds`` noise seeds, how many runs end DONE and the rms errors of R + R_on, L and psi_f (%), L's
    worst, and the mean time: a dead time (fractions of the PWM period, 0.7-V diodes, R_on = 0.2 R; 0: the drive's
    own inverter) with current noise (fractions of ``I_fs = 2 I_N``, a 12-bit ADC over ``+-I_fs``)."""
    print(f"\n{'drive':16s} {'t_dead':>6s} {'noise':>6s} {'DONE':>5s} {'R rms %':>8s} {'L rms %':>8s} {'L worst':>8s} "
          f"{'psi rms %':>9s} {'t mean s':>8s}")
    for name in names:
        d = bl.load(name)
        k1 = bl.control.sine.fundamental_k1(d)
        fs = 2.0 * d.motor.I_N
        for frac in fractions:
            inv = d.inverter if frac == 0.0 else dataclasses.replace(d.inverter, t_dead=frac / d.inverter.f_pwm,
                                                                     V_f=0.7, R_on=0.2 * d.motor.R)
            base = dataclasses.replace(d, inverter=inv)
            for noise in noises:
                errs: list[tuple[float, float, float]] = []
                times = []
                for seed in range(1, seeds + 1):
                    plant = base.replace(sensors__current_noise=noise * fs, sensors__current_lsb=2.0 * fs / 2**12,
                                         sensors__seed=seed)
                    e = bl.commission(plant)
                    times.append(e.t_test)
                    if e.ok:
                        errs.append((e.R / r_total(plant) - 1, e.L / d.motor.L - 1, e.psi_f * d.motor.p / k1 - 1))
                a = np.array(errs).reshape(-1, 3)
                rms = 100 * np.sqrt(np.mean(np.square(a), axis=0)) if len(a) else np.full(3, math.nan)
                worst = 100 * a[np.argmax(np.abs(a[:, 1])), 1] if len(a) else math.nan
                print(f"{name:16s} {100 * frac:5.1f}% {100 * noise:5.1f}% {len(a):5d} {rms[0]:8.3f} {rms[1]:8.3f} "
                      f"{worst:8.3f} {rms[2]:9.3f} {np.mean(times):8.3f}", flush=True)


def main(names: list[str]) -> None:
    print(f"{'drive':16s} {'obs':8s} {'speed':>6s} {'rms deg':>8s} {'worst':>8s} {'sine':>5s} {'tau':>9s} "
          f"{'tau enc':>9s} {'eff':>6s} {'eff enc':>7s}")
    for name in names:
        d = bl.load(name)
        torque = 0.5 * 1.5 * bl.control.sine.fundamental_k1(d) * i_sN(d)
        for frac in SPEEDS:
            w = frac * d.Omega_0
            # long enough for the alignment, the ramp and the lock, then 20 electrical periods
            on = min(0.1 * d.motor.Omega_nominal, 0.5 * w)
            ctl = bl.Sine(angle="observer", handoff_speed=on, handoff_hysteresis=0.5)
            st = ctl.sensorless_settings(d)
            # start, then the speed loop's way up at T_s,N / 2 of acceleration torque, then 0.3 s to settle
            t_load = st["if_align"] + d.motor.p * on / st["if_accel"] + 2 * st["lock_time"] \
                + d.mechanics.J * w / torque + 0.3
            wb = 2 * math.pi * ctl.speed_bandwidth_hz
            t_ramp = max(0.3, torque / (d.mechanics.J * wb**2 / 4 * 0.2 * w))
            dur = t_load + t_ramp + 0.3 + 20 * 2 * math.pi / (d.motor.p * w)
            enc = angle_error(d, bl.Sine(angle="encoder", handoff_speed=on), w, torque, t_load, t_ramp, dur)
            for obs in ("flux", "reduced"):
                a = angle_error(d, dataclasses.replace(ctl, observer=obs), w, torque, t_load, t_ramp, dur)
                print(f"{name:16s} {obs:8s} {frac:6.2f} {a['rms']:8.3f} {a['worst']:8.3f} {a['sine']:5.2f} "
                      f"{a['tau']:9.4g} {enc['tau']:9.4g} {a['eff']:6.3f} {enc['eff']:7.3f}")


ALL_DRIVES = ["htm-48v", "servo-2k2", "outrunner-24v", "lu-4kw", "mn3110-780kv", "f60prov-2550kv"]

#: The parts that run alone: option -> (the function run on the drives given, default every catalog drive; help).
PARTS: dict[str, tuple[Callable[[list[str]], None], str]] = {
    "--sensors": (sensor_errors, "current-sensor offset and noise, the controller unaware (default: three drives)"),
    "--commission-sensors": (commissioning_sensors, "commissioning with offsets, noise and a 12-bit ADC"),
    "--commission-deadtime": (commissioning_deadtime, "commissioning's flux linkage with a dead time"),
    "--commission-deadtime-noise": (commissioning_deadtime_noise, "dead time with current noise, eight seeds"),
    "--estimates": (estimates, "each wrong parameter without and with the controller's own estimates"),
    "--sensitivity": (sensitivity, "the sensitivity with the alignment's resistance estimate off and on"),
    "--catch": (catch_map, "the flying-start map (both catch modes)"),
    "--startup": (startup_map, "the standstill start-up map (default: three drives)"),
}


def parse_args(argv: list[str]) -> argparse.Namespace:
    """Read the command line (the module's docstring says what each part measures)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("drives", nargs="*", metavar="DRIVE", help="built-in drive names or motor files")
    part = ap.add_mutually_exclusive_group()
    for opt, (_, text) in PARTS.items():
        part.add_argument(opt, dest="part", action="store_const", const=opt, help=text)
    ap.add_argument("--kinds", help="--startup: load kinds, comma-separated (passive, brake, active)")
    ap.add_argument("--inertias", help="--startup: inertias in multiples of the drive's, comma-separated")
    ap.add_argument("--loads", help="--startup: loads in fractions of the I/f torque, comma-separated")
    ap.add_argument("--dump", metavar="FILE", help="--startup, --catch: write each start to FILE")
    for flag, key in (("r-estimate", "if_r_estimate"), ("zc-catch", "catch_zero_current")):
        ap.add_argument(f"--{flag}", dest=key, action="store_const", const=True,
                        help=f"--startup: Sine({key}=True)")
        ap.add_argument(f"--no-{flag}", dest=key, action="store_const", const=False,
                        help=f"--startup: Sine({key}=False)")
    args = ap.parse_args(argv)
    startup_only = [o for o in ("kinds", "inertias", "loads", "if_r_estimate", "catch_zero_current")
                    if getattr(args, o) is not None]
    if startup_only and args.part != "--startup":
        ap.error(f"--{startup_only[0].replace('_', '-')} needs --startup")
    if args.dump is not None and args.part not in ("--startup", "--catch"):
        ap.error("--dump needs --startup or --catch")
    return args


def run(args: argparse.Namespace) -> None:
    """Run the part the command line asks for (all of the first four without one)."""
    drives = args.drives or (ALL_DRIVES if args.part not in ("--sensors", "--startup") else ALL_DRIVES[:3])
    if args.part is None:
        main(drives)
        sensitivity(drives)
        commissioning(drives)
        startup_map(drives[:3])
    elif args.part == "--sensitivity":
        for r_est in (False, True):
            sensitivity(drives, if_r_estimate=r_est)
    elif args.part == "--catch":
        catch_map(drives, dump=args.dump)
    elif args.part == "--startup":
        opts = {k: getattr(args, k) for k in ("if_r_estimate", "catch_zero_current") if getattr(args, k) is not None}
        startup_map(drives,
                    kinds=tuple(args.kinds.split(",")) if args.kinds else STARTUP_KINDS,
                    inertias=tuple(float(x) for x in args.inertias.split(",")) if args.inertias else STARTUP_J,
                    loads=tuple(float(x) for x in args.loads.split(",")) if args.loads else STARTUP_LOADS,
                    dump=args.dump, **opts)
    else:
        PARTS[args.part][0](drives)


if __name__ == "__main__":
    try:
        run(parse_args(sys.argv[1:]))
    except BldclabError as exc:
        print(f"sensorless_sine.py: error: {exc}", file=sys.stderr)
        raise SystemExit(2) from None

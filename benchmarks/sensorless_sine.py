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

Run: ``PYTHONPATH=src python benchmarks/sensorless_sine.py [DRIVE ...]``.
"""

from __future__ import annotations

import dataclasses
import math
import sys

import numpy as np

import bldclab as bl
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
    return {"rms": float(np.sqrt(np.mean(err**2))) if err.size else math.nan,
            "worst": float(np.max(np.abs(err))) if err.size else math.nan,
            "sine": float(on.sum() / max(last.sum(), 1)), "tau": m.tau_mean, "eff": m.efficiency}


def sensitivity(names: list[str]) -> None:
    """Print the angle error and torque with wrong parameters, then after commissioning from them."""
    print(f"\n{'drive':16s} {'estimate':12s} {'rms deg':>8s} {'worst':>8s} {'tau':>9s} {'after comm.':>11s} "
          f"{'worst':>8s} {'tau':>9s}")
    for name in names:
        d = bl.load(name)
        torque = 0.5 * 1.5 * bl.control.sine.fundamental_k1(d) * i_sN(d)
        w = 0.5 * d.Omega_0
        on = min(0.1 * d.motor.Omega_nominal, 0.5 * w)
        ctl = bl.Sine(angle="observer", handoff_speed=on, handoff_hysteresis=0.5)
        st = ctl.sensorless_settings(d)
        t_load = st["if_align"] + d.motor.p * on / st["if_accel"] + 2 * st["lock_time"] \
            + d.mechanics.J * w / torque + 0.3
        wb = 2 * math.pi * ctl.speed_bandwidth_hz
        t_ramp = max(0.3, torque / (d.mechanics.J * wb**2 / 4 * 0.2 * w))
        dur = t_load + t_ramp + 0.3 + 20 * 2 * math.pi / (d.motor.p * w)
        for label, kw in (("true", {}), ("psi +25 %", {"emf": 1.25}), ("psi -25 %", {"emf": 0.75}),
                          ("R +50 %", {"R": 1.5}), ("R -50 %", {"R": 0.5}), ("L +30 %", {"L": 1.3}),
                          ("L -30 %", {"L": 0.7})):
            wrong = d.scaled(**kw) if kw else None
            a = angle_error(d, ctl, w, torque, t_load, t_ramp, dur, estimate=wrong)
            e = bl.commission(d, nominal=wrong) if wrong is not None else None
            b = angle_error(d, ctl, w, torque, t_load, t_ramp, dur, estimate=e.drive) if e and e.ok else None
            after = f"{b['rms']:11.3f} {b['worst']:8.3f} {b['tau']:9.4g}" if b else f"{'-':>11s} {'-':>8s} {'-':>9s}"
            print(f"{name:16s} {label:12s} {a['rms']:8.3f} {a['worst']:8.3f} {a['tau']:9.4g} {after}")


def startup_map(names: list[str]) -> None:
    """Print the start-up's success over load torque x inertia and the time to the hand-off.

    The controller is configured from the nominal drive (its I/f ramp from the nominal inertia); the plant's inertia
    is the nominal times a factor and a constant load (a fraction of the I/f current's torque ``1.5 k_1 if_current``)
    acts from t = 0. Speed loop to 0.3 Omega_0. Success: in the sine mode at the end with the speed within 5 % of the
    reference; ``t_lock``: the first sample in the sine mode; ``restarts``: samples flagged DESYNC (0: none).
    """
    print(f"\n{'drive':16s} {'load/tau_if':>11s} {'J/J_nom':>8s} {'ok':>3s} {'t_lock s':>9s} {'DESYNC':>7s}")
    for name in names:
        d = bl.load(name)
        ctl = bl.Sine(angle="observer", speed_loop=True)
        st = ctl.sensorless_settings(d)
        tau_if = 1.5 * bl.control.sine.fundamental_k1(d) * st["if_current"]
        w = 0.3 * d.Omega_0
        for kj in (0.5, 1.0, 2.0, 5.0):
            plant = dataclasses.replace(d, mechanics=dataclasses.replace(d.mechanics, J=kj * d.mechanics.J))
            for fl in (0.0, 0.25, 0.5, 0.75, 0.9, 1.1):
                load = fl * tau_if
                t_acc = plant.mechanics.J * w / max(ctl.torque_limit(d) - load, 0.1 * ctl.torque_limit(d))
                dur = 3 * (st["if_align"] + d.motor.p * ctl.handoff(d) / st["if_accel"] + 4 * st["lock_time"]) \
                    + t_acc + 0.5
                r = simulate(plant, ctl, Scenario(duration=dur, omega_ref=w, load_torque=load, trace_every=8),
                             estimate=d)
                on = r["mode"] > 0.5
                ok = bool(on[-1]) and abs(r["omega_m"][-1] / w - 1) < 0.05
                t_lock = float(r["t"][on][0]) if on.any() else math.nan
                flags = r.flags_raised
                print(f"{name:16s} {fl:11.2f} {kj:8.1f} {'yes' if ok else 'no':>3s} {t_lock:9.3f} "
                      f"{'yes' if 'DESYNC' in flags else 'no':>7s}")


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


if __name__ == "__main__":
    drives = sys.argv[1:] or ["htm-48v", "servo-2k2", "outrunner-24v", "lu-4kw", "mn3110-780kv", "f60prov-2550kv"]
    main(drives)
    sensitivity(drives)
    commissioning(drives)
    startup_map(drives[:3])

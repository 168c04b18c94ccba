"""Switching vs averaged inverter on the catalog drives: mean torque and ripples as the PWM frequency rises.

For each drive and supply at a few speeds, prints the closed forms (paper 1, R neglected), the averaged-inverter point
at the drive's own carrier (mean torque, exact instantaneous ripple), then at 10, 20, 40 and 80 kHz (controller
sampled at the same carrier in both models) the switching-level mean torque minus the averaged one, and the
switching drive's exact ripple (with PWM) and ripple of its continuous one-PWM-period average; last the PWM-grid
phase spread of the switching point at the drive's own carrier (8 phases).

    python benchmarks/inverter_models.py [--drives htm-48v,outrunner-24v,servo-2k2] [--speeds 0.2,0.5,0.8]
"""

from __future__ import annotations

import argparse
import dataclasses
import warnings

import bldclab as bl
from bldclab.analysis.compare import default_controls
from bldclab.analysis.experiments import steady_state
from bldclab.model import analytic

F_PWM = (10e3, 20e3, 40e3, 80e3)


def with_inverter(drive: bl.Drive, model: str, f_pwm: float | None = None) -> bl.Drive:
    inv = dataclasses.replace(drive.inverter, model=model, f_pwm=f_pwm or drive.inverter.f_pwm)
    return dataclasses.replace(drive, inverter=inv)


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--drives", default="htm-48v,outrunner-24v,servo-2k2")
    ap.add_argument("--speeds", default="0.2,0.5,0.8")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    for name in args.drives.split(","):
        drive = bl.load(name)
        th = analytic.theta_m(drive)
        na = " (closed forms not applicable: " + "; ".join(analytic.applicability(drive)) + ")" \
            if analytic.applicability(drive) else ""
        print(f"\n{name}: f_pwm {drive.inverter.f_pwm / 1e3:g} kHz, Theta_m {th:.4f}{na}")
        print(f"{'supply':>6} {'W':>5} | {'T cf':>6} {'TR cf':>6} | {'T avg':>7} {'TR avg':>7} | "
              + " | ".join(f"{f / 1e3:>3g} kHz: dT, TR, TR_ma" for f in F_PWM) + " | phase spread T, TR_ma")
        for supply in ("square", "sine"):
            for w in (float(x) for x in args.speeds.split(",")):
                control, ref = default_controls(drive)[supply]
                om = w * drive.Omega_0
                T_cf = analytic.t_q_pu(w, th) if supply == "square" else analytic.t_s_pu(w, th)
                TR_cf = analytic.tr_q_pu(w, th) if supply == "square" else analytic.tr_s_pu(w, th)
                avg, _ = steady_state(with_inverter(drive, "average"), control, om, ref)
                cells = []
                for f in F_PWM:
                    pt, _ = steady_state(with_inverter(drive, "switching", f), control, om, ref)
                    pa, _ = steady_state(with_inverter(drive, "average", f), control, om, ref)
                    cells.append(f"{pt.tau_mean_pu - pa.tau_mean_pu:+.1e} {pt.ripple_pu:.3f} {pt.ripple_ma_pu:.3f}")
                ph, _ = steady_state(drive, control, om, ref, pwm_phases=8)
                T_N = drive.T_N
                spread = (f"{ph.spread_pu('tau_mean', T_N):.4f} "
                          f"{(ph.ripple_ma_range[1] - ph.ripple_ma_range[0]) / T_N:.4f}")
                print(f"{supply:>6} {w:>5.2f} | {float(T_cf):>6.3f} {float(TR_cf):>6.3f} | {avg.tau_mean_pu:>7.4f} "
                      f"{avg.ripple_pu:>7.3f} | " + " | ".join(f"{c:>21}" for c in cells) + f" | {spread}")
    print("\n(p.u. of T_N; T: mean torque; dT: switching minus averaged mean torque at that carrier; TR: exact "
          "instantaneous ripple; TR_ma: ripple of the continuous one-PWM-period average; cf: paper 1's closed forms, "
          "R neglected; phase spread: max - min over 8 PWM-grid phases at the drive's own carrier)")


if __name__ == "__main__":
    main()

"""Paper 1's ideal current limiter against (26)-(33), and what a sampled controller makes of the same commutation.

For each drive and speed: the square wave's mean torque and instantaneous ripple (p.u. of T_N) by the closed forms,
by the ideal limiter on the averaged inverter (``SixStep(regulation="ideal")``, commutation at the exact angles), and
by the default sampled controller (predictive, PWM-on-PWM, Hall commutation) on the averaged inverter; with the
number of PWM periods the commutation lasts there (``3 L I_N / (V (1 + W))``). Drives: htm-48v with R = 0 on its
120-degree trapezoid (where (26)-(33) carry an error of their own: the outgoing back-EMF ramps during the
commutation) and on a 160-degree flat top (the closed forms' premise), and a 540 V fan-like drive whose commutation
lasts one to two PWM periods at 10 kHz.

    python benchmarks/ideal_limiter.py
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import bldclab as bl
from bldclab.analysis.compare import IDEAL_LIMITER, default_controls
from bldclab.analysis.experiments import steady_state
from bldclab.model import analytic
from bldclab.model.catalog.synthetic import paper1_drive
from bldclab.model.emf import BackEmf, Trapezoid

SPEEDS = (0.1, 0.2, 0.3, 0.45, 0.6, 0.8, 0.9)


def flat(d: bl.Drive, deg: float) -> bl.Drive:
    """The drive on a trapezoid of ``deg`` degrees flat top, averaged inverter, R = 0."""
    m = dataclasses.replace(d.motor, R=0.0, emf=BackEmf.symmetric(Trapezoid(d.motor.k_phi, math.radians(deg))))
    return dataclasses.replace(d, motor=m, inverter=dataclasses.replace(d.inverter, model="average", R_on=0.0,
                                                                         V_f=0.0, r_d=0.0, t_dead=0.0, R_src=0.0))


def table(name: str, d: bl.Drive) -> float:
    """Print one drive's table; return the largest |ideal - closed form| of the ripple."""
    th = analytic.theta_m(d)
    print(f"\n{name}: Theta_m {th:.4f} rad, f_pwm {d.inverter.f_pwm:g} Hz")
    print(f"  {'W':>5} {'PWM/comm':>8} | {'T (26)-(32)':>11} {'ideal':>8} {'ctrl':>8} | "
          f"{'TR (27)-(33)':>12} {'ideal':>8} {'ctrl':>8} {'ctrl-ideal':>10}")
    square, ref = default_controls(d)["square"]
    worst = 0.0
    for w in SPEEDS:
        om = w * d.Omega_0
        ideal, _ = steady_state(d, IDEAL_LIMITER, om, ref)
        ctrl, _ = steady_state(d, square, om, ref)
        t_cf, tr_cf = float(analytic.t_q_pu(w, th)), float(analytic.tr_q_pu(w, th))
        worst = max(worst, abs(ideal.ripple_pu - tr_cf))
        print(f"  {w:>5.2f} {analytic.commutation_periods(d, w):>8.2f} | {t_cf:>11.5f} {ideal.tau_mean_pu:>8.5f} "
              f"{ctrl.tau_mean_pu:>8.5f} | {tr_cf:>12.5f} {ideal.ripple_pu:>8.5f} {ctrl.ripple_pu:>8.5f} "
              f"{ctrl.ripple_pu - ideal.ripple_pu:>+10.4f}")
    return worst


def main() -> None:
    htm = bl.load("htm-48v")
    fan = paper1_drive(0.05, p=4, V_N=540.0, I_N=2.0, Omega_0=330.0, f_pwm=10e3, name="fan-540v")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the sampled controller's premise warnings are the point here
        for name, d in (("htm-48v, R = 0, 120-degree trapezoid", flat(htm, 120.0)),
                        ("htm-48v, R = 0, 160-degree flat top (the closed forms' premise)", flat(htm, 160.0)),
                        ("fan-540v (synthetic), 160-degree flat top", flat(fan, 160.0))):
            worst = table(name, d)
            print(f"  largest |ideal - (27)-(33)|: {worst:.2e} p.u.")


if __name__ == "__main__":
    main()

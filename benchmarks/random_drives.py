"""Paper 1's closed forms against the averaged-inverter simulation on drives drawn at random: worst deviations.

Draws drives as tests/test_generalisation.py does (tests/generalisation.py), runs both supplies at one speed per
drive and prints, per band of PWM periods per commutation, the number of drives and the worst deviation of each
quantity from its closed form: the square wave on the trapezoid whose flat top holds the commutation (the premise of
(26)-(33), what the test asserts) and on paper 1's 120-degree trapezoid (where the closed forms carry an error of
their own: the outgoing phase's back-EMF ramps down during its commutation); then the switching model's mean torque
against the averaged one.

    python benchmarks/random_drives.py [--n 200] [--seed 1] [--switching 40]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from generalisation import MAX_F_PWM, TWO_PI, Case, analytic, describe, mean_torque_switching, run

BANDS = ((5.0, 10.0), (10.0, 20.0), (20.0, 50.0), (50.0, 200.0))
CORNER = 0.02
KEYS = ("T_q", "TR_q", "T_s", "TR_s", "T_q120", "TR_q120")


def draw(rng: np.random.Generator) -> Case:
    """A drive and speed, clear of the closed forms' corners (as the test's filter)."""
    while True:
        c = Case(Theta_m=rng.uniform(0.01, 0.2), p=int(rng.integers(1, 21)), V_N=rng.uniform(12, 600),
                 I_N=rng.uniform(1, 200), Omega_0=rng.uniform(20, 2000),
                 pwm_per_commutation=float(np.exp(rng.uniform(np.log(5), np.log(200)))), r_share=0.0,
                 speed_pu=rng.uniform(0.05, 0.98))
        corners = (0.5, analytic.omega_sB_pu(c.Theta_m), analytic.omega_qB_pu(c.Theta_m))
        if c.f_pwm <= MAX_F_PWM and all(abs(c.speed_pu - x) > CORNER for x in corners):
            return c


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--switching", type=int, default=40, help="drives also run in the switching model")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    worst = {b: dict.fromkeys(KEYS, 0.0) for b in BANDS}
    where = dict.fromkeys(KEYS, (0.0, ""))
    count = dict.fromkeys(BANDS, 0)
    t0 = time.perf_counter()
    cases = [draw(rng) for _ in range(args.n)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for c in cases:
            o = run(c, "average")
            o120 = run(c, "average", square_flat_top=TWO_PI / 3.0)
            dev = {"T_q": o.T_q - o.T_q_cf, "TR_q": o.TR_q - o.TR_q_cf, "T_s": o.T_s - o.T_s_cf,
                   "TR_s": o.TR_s - o.TR_s_cf, "T_q120": o120.T_q - o120.T_q_cf, "TR_q120": o120.TR_q - o120.TR_q_cf}
            band = next(b for b in BANDS if b[0] <= c.pwm_per_commutation <= b[1])
            count[band] += 1
            for k, v in dev.items():
                worst[band][k] = max(worst[band][k], abs(v))
                if abs(v) > abs(where[k][0]):
                    where[k] = (v, describe(c))
        sw = 0.0
        for c in cases[: args.switching]:
            for supply in ("square", "sine"):
                a, s = mean_torque_switching(c, supply)
                sw = max(sw, abs(a - s))
    print(f"{args.n} drives (seed {args.seed}), averaged inverter, R = 0, in {time.perf_counter() - t0:.0f} s")
    print(f"{'PWM per commutation':>20} {'drives':>7} " + " ".join(f"{k:>8}" for k in KEYS))
    for b in BANDS:
        print(f"{f'{b[0]:g}-{b[1]:g}':>20} {count[b]:>7} " + " ".join(f"{worst[b][k]:>8.4f}" for k in KEYS))
    print("(worst |simulated - closed form|, p.u. of T_N; T: mean torque (26)/(28)/(32) square, (13)/(24) sine; TR:")
    print(" ripple (27)/(29)/(33), (15)/(25); _q: square wave with the commutation on the flat top, the closed forms'")
    print(" premise; _q120: square wave on the 120-degree trapezoid, where they neglect the outgoing ramp)")
    for k in KEYS:
        print(f"  worst {k}: {where[k][0]:+.4f} at {where[k][1]}")
    n_sw = min(args.n, args.switching)
    print(f"switching vs averaged mean torque, {n_sw} drives x 2 supplies: worst {sw:.2e} p.u.")


if __name__ == "__main__":
    main()

"""Paper 2's torque control at light load: why the mean torque leaves the reference (issue 16).

Runs ``lu-4kw`` (300 V, 0.29 mH, 10 kHz, bipolar chopping) at an imposed speed with a fine trace and prints, per
operating point, for the method ``lu-no-do`` (``lu`` is identical where ``D_o`` never engages) with delay 1 and the
end-value laws (``Lu(mean_law=False)``, the controller before the fix):

- ``mean``: the mean torque over two electrical periods, % of the reference;
- ``samp V`` / ``samp P``: the mean of the instantaneous torque at the samples taken at carrier valleys / peaks
  (what the deadbeat law regulates), % of the reference;
- ``dcm R`` / ``dcm F``: share of rising (valley -> peak, off part first) and falling (peak -> valley, on part first)
  half periods in normal conduction in which every phase current is zero at some instant (discontinuous conduction);
- ``D R`` / ``D F``: mean applied duty in rising / falling half periods of normal conduction;
- ``D_ol``: the fixed duty (same pairs, bipolar chopping, open loop: ``SixStepVoltage("bipolar")``) whose mean
  torque is the reference, found by bisection;
- ``cf``: closed form of the mean torque the sample law gives (ideal flat-top two-phase conduction, see
  :func:`closed_form`), % of the reference;
- ``pred``: the controller's one-step prediction error, max ``|tau_pred(k) - tau_e(k+1)|`` over normal conduction,
  % of the reference;
- ``w err``: error of the Hall speed estimate, % (mean over the window);
- the mean torque (% of the reference) of the variants, all with the end-value laws: delay 0, ``model_R=False``,
  ideal trapezoidal back-EMF, averaged models (``switching_order=False``), ``lu`` and ``rect``;
- ``mean law``: the mean torque with the fix (``Lu(method, mean_law=True)``, the default), % of the reference.

Run: ``PYTHONPATH=src python benchmarks/light_load.py [--quick] [--method lu]``.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

import bldclab as bl
from bldclab.analysis import paper2
from bldclab.analysis.experiments import electrical_period
from bldclab.control import SixStepVoltage
from bldclab.model.motor import Drive

SUB = 32  # trace rows per sample: the zero-current intervals resolved to T_s / 32


def closed_form(drive: Drive, torque: float, speed: float) -> float:
    """Mean torque (% of the reference) that the sample law gives in discontinuous conduction.

    Ideal two-phase conduction on the flat top (pair current ``i``, line back-EMF ``2E = 2 k_phi w``, ``R = 0``):
    bipolar chopping puts ``+-V`` on ``2L``, so ``i`` rises at ``a = (V - 2E)/(2L)`` and falls at
    ``b = (V + 2E)/(2L)``. The law makes the current ``I = T*/(2 k_phi)`` at every sample. A falling half period
    (on part first) starts and ends at ``I`` and stays above it: mean ``I + a b T_s / (2 (a + b))``. A rising half
    period (off part first) falls from ``I`` to zero, waits, and rises back to ``I``: mean
    ``I^2 (1/a + 1/b) / (2 T_s)`` if it does reach zero, i.e. if ``I/b + I/a < T_s``; else ``I - a b T_s/(2(a+b))``
    (continuous conduction: the two halves cancel). Returns the mean of the two halves over ``I``, in %.
    """
    m = drive.motor
    V, L, ts = drive.inverter.V_dc, m.L, 0.5 / drive.inverter.f_pwm
    E2 = 2.0 * m.k_phi * speed
    a, b = (V - E2) / (2 * L), (V + E2) / (2 * L)
    i = torque / (2 * m.k_phi)
    up = a * b * ts / (2 * (a + b))
    falling = i + up
    rising = i * i * (1 / a + 1 / b) / (2 * ts) if i / a + i / b < ts else i - up
    return 100.0 * 0.5 * (falling + rising) / i


def _mean(drive: Drive, ctrl: bl.Control, torque_or_duty: float, speed: float, delay: int = 1) -> float:
    """Window-mean torque (N m) of a run at an imposed speed (3 periods and 10 ms settling, 2 measured)."""
    Te = electrical_period(drive, speed)
    t0 = max(3 * Te, math.ceil(0.01 / Te) * Te)
    sc = bl.Scenario(duration=t0 + 2 * Te + 0.25 / drive.inverter.f_pwm, speed=speed, ref=torque_or_duty,
                     delay=delay, trace=False, window=(t0, t0 + 2 * Te))
    res = bl.simulate(drive, ctrl, sc)
    assert res.metrics is not None
    return res.metrics.tau_mean


def open_loop_duty(drive: Drive, torque: float, speed: float) -> float:
    """The fixed bipolar duty whose mean torque is ``torque`` (bisection on [0, 1], 18 halvings: 4e-6).

    The pair current cannot reverse through the diodes, so the mean torque rises monotonically from 0 at zero duty
    (in discontinuous conduction even ``D = 1/2`` drives a positive current). A duty that trips the inverter's
    over-current protection on the way up from rest gives exactly 0 N m: it counts as too high.
    """
    ctrl = SixStepVoltage(chopping="bipolar")
    lo, hi = 0.0, 1.0
    for _ in range(18):
        mid = 0.5 * (lo + hi)
        tau = _mean(drive, ctrl, mid, speed)
        if tau != 0.0 and tau < torque:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def diagnose(drive: Drive, torque: float, speed: float, method: str = "lu-no-do",
             **control: object) -> dict[str, float]:
    """Per-half-period measurements of one operating point (see the module docstring)."""
    res = paper2.operating_point(drive, method, torque, speed, trace_sub=SUB, mean_law=False, **control)
    m = res.metrics
    assert m is not None
    ts = 0.5 / drive.inverter.f_pwm
    n = len(res.t) // SUB
    tk = res.t[: n * SUB: SUB]
    k = np.arange(n)
    rising = k % 2 == 0  # sample 0 is a carrier valley: the half period after it rises
    inside = (tk >= m.t0 - 1e-12) & (tk + ts <= m.t1 + 1e-12)
    mode = np.asarray(res["mode"][: n * SUB: SUB])
    # normal conduction over the half period: the output applied over [k, k+1] was computed at k-1 (delay 1)
    normal = np.zeros(n, dtype=bool)
    normal[1:] = mode[:-1] == 0
    normal &= np.asarray(res["sector"][: n * SUB: SUB]) >= 0
    tau_e = np.asarray(res["tau_e"][: n * SUB: SUB])
    i_all = np.stack([np.asarray(res[f"i_{x}"][: n * SUB]).reshape(n, SUB) for x in "abc"])
    zero = np.all(np.abs(i_all) < 1e-3 * drive.motor.I_N, axis=0).any(axis=1)  # some sub-row with no current
    duty = np.max(np.stack([np.asarray(res[f"duty_{x}"][: n * SUB: SUB]) for x in "abc"]), axis=0)
    sel_r, sel_f = inside & normal & rising, inside & normal & ~rising
    err, _ = paper2.prediction_error(res, torque)
    om_true = drive.motor.p * speed
    om_est = np.asarray(res["omega_est"][: n * SUB: SUB])[inside]
    return {
        "mean": 100.0 * m.tau_mean / torque,
        "samp_v": 100.0 * float(np.mean(tau_e[inside & rising])) / torque,
        "samp_p": 100.0 * float(np.mean(tau_e[inside & ~rising])) / torque,
        "dcm_r": float(np.mean(zero[sel_r])) if sel_r.any() else math.nan,
        "dcm_f": float(np.mean(zero[sel_f])) if sel_f.any() else math.nan,
        "d_r": float(np.mean(duty[sel_r])) if sel_r.any() else math.nan,
        "d_f": float(np.mean(duty[sel_f])) if sel_f.any() else math.nan,
        "pred": 100.0 * err,
        "w_err": 100.0 * (float(np.mean(om_est)) - om_true) / om_true,
        "no_current": 100.0 * float(np.mean(zero[inside])),
    }


def main(argv: list[str] | None = None) -> int:
    """Print the diagnosis tables."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="25 %% and 100 %% load at 1000 and 2000 rpm only")
    ap.add_argument("--method", default="lu-no-do", choices=paper2.METHODS)
    args = ap.parse_args(argv)
    drive = bl.load("lu-4kw")
    loads = (0.25, 1.0) if args.quick else (0.10, 0.25, 0.50, 1.00)
    rpms = (1000, 2000) if args.quick else (500, 1000, 2000, 3000)
    ideal = paper2.trapezoid_drive(drive)
    print(f"lu-4kw, method {args.method}, delay 1; torques in % of the reference")
    print(" load   rpm   mean samp V samp P  dcm R  dcm F    D R    D F   D_ol     cf  pred  w err"
          "  delay0    noR  ideal   avg'd     lu   rect mean law")
    for ld in loads:
        for rpm in rpms:
            tq, om = ld * drive.T_N, rpm * 2 * math.pi / 60
            d = diagnose(drive, tq, om, args.method)
            old = {"mean_law": False}
            var = [100 * _mean(drive, bl.Lu(method=args.method, delay=0, **old), tq, om, delay=0) / tq,
                   100 * _mean(drive, bl.Lu(method=args.method, model_R=False, **old), tq, om) / tq,
                   100 * _mean(ideal, bl.Lu(method=args.method, **old), tq, om) / tq,
                   100 * _mean(drive, bl.Lu(method=args.method, switching_order=False), tq, om) / tq,
                   100 * _mean(drive, bl.Lu(method="lu", **old), tq, om) / tq,
                   100 * _mean(drive, bl.Lu(method="rect"), tq, om) / tq,
                   100 * _mean(drive, bl.Lu(method=args.method), tq, om) / tq]
            print(f"{100 * ld:5.0f} {rpm:5d} {d['mean']:6.1f} {d['samp_v']:6.1f} {d['samp_p']:6.1f}"
                  f" {d['dcm_r']:6.2f} {d['dcm_f']:6.2f} {d['d_r']:6.3f} {d['d_f']:6.3f}"
                  f" {open_loop_duty(drive, tq, om):6.3f} {closed_form(drive, tq, om):6.1f} {d['pred']:5.2f}"
                  f" {d['w_err']:6.2f}" + "".join(f" {v:7.1f}" for v in var))
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

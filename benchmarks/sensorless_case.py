"""bldclab beside motulator on a sensorless case: servo-2k2 (motulator's 2.2-kW PMSM), reduced-order observer.

The case (``docs/benchmarks.md``, "The sensorless case"): motulator's sensorless current-vector control example of
its 2.2-kW PMSM, on the numbers of bldclab's ``servo-2k2`` (n_p = 3, R = 3.6 Ohm, L_d = L_q = 51 mH, psi_f =
0.545 V s, 540 V, J = 0.015 kg m^2, 8 kHz carrier sampled twice a period). Both sides run the reduced-order
observer of Hinkkanen et al. (IEEE TIA 2018) with the same design (speed-estimation poles ``alpha_o = 2 pi 100``
rad/s as in motulator's example, ``sigma = R / (2 L) + 0.2 |omega|``), the same d,q current loops and speed PI,
and the same run from the moment both are in steady sensorless operation at ``0.2 Omega_N``: a speed step to
``0.5 Omega_N``, then a load step. What cannot be made equal (the start from standstill above all) is listed in
``docs/benchmarks.md``; the trajectories are compared from the speed step on, on the controllers' sampling grid.

motulator runs in its own virtual environment (``motulator_case.py`` finds or builds it); this file is also its
script there (``--motulator-side``). Saved to ``out/benchmarks/sensorless_case.npz``. If motulator cannot be run
the report says why and the script still exits 0.

Run: ``PYTHONPATH=src python benchmarks/sensorless_case.py [--venv DIR] [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

sys.path.insert(0, str(Path(__file__).resolve().parent))
import motulator_case as mc

ROOT = mc.ROOT
Signals = dict[str, NDArray[np.float64]]


@dataclass(frozen=True)
class SlCase:
    """The sensorless case, SI units; both tools are configured from these numbers only.

    Parameters
    ----------
    n_p, R_s, L, psi_f, u_dc, f_pwm, J : as in :class:`motulator_case.Case`
    i_s_max, tau_max : float
        Current limit (A, peak; bldclab's ``I_s,N``) and the speed PI's torque limit (N m).
    k_p, k_i, k_p_w, k_i_w : float
        d,q current PI gains (V/A, V/(A s)) and speed PI gains (N m s/rad, N m/rad), bldclab's ``Sine`` defaults.
    alpha_o, sigma0, zeta_inf : float
        The observer's speed-estimation bandwidth (rad/s), attenuation at standstill (rad/s) and at speed (-).
    w_1, w_2 : float
        Speed before and after the step (rad/s, mechanical).
    tau_L : float
        Load torque of the load step (N m).
    t_step, t_load, t_stop : float
        motulator's run: speed step, load step and end (s). bldclab's run is the same from its own step time.
    alpha_ref : float
        motulator only: the current-reference tracking bandwidth (rad/s), set well above the speed loop.
    """

    n_p: int
    R_s: float
    L: float
    psi_f: float
    u_dc: float
    f_pwm: float
    J: float
    i_s_max: float
    tau_max: float
    k_p: float
    k_i: float
    k_p_w: float
    k_i_w: float
    alpha_o: float
    sigma0: float
    zeta_inf: float
    w_1: float
    w_2: float
    tau_L: float
    t_step: float = 0.4
    t_load: float = 0.8
    t_stop: float = 1.2
    alpha_ref: float = 2.0 * math.pi * 1000.0

    @property
    def T_s(self) -> float:
        """Sampling period (s): half the carrier period."""
        return 0.5 / self.f_pwm

    @property
    def n_window(self) -> int:
        """Samples compared, from the speed step to the end."""
        return round((self.t_stop - self.t_step) / self.T_s)


# ------------------------------------------------------------------------------------------------------------
# bldclab side


def sl_case() -> SlCase:
    """Return the case built from servo-2k2 and bldclab's default ``Sine`` design."""
    import bldclab as bl
    from bldclab.control.sine import fundamental_k1
    from bldclab.model.analytic import i_sN, r_total

    d = bl.load("servo-2k2")
    m, mech = d.motor, d.mechanics
    k_p, k_i = bl.Sine().gains(d)
    w_b = 2.0 * math.pi * bl.Sine().speed_bandwidth_hz
    k1 = fundamental_k1(d)
    i_s_max = i_sN(d)
    tau_max = 1.5 * k1 * i_s_max
    w_n = m.Omega_nominal
    # motulator's example: load nom.tau = 14 N m against its torque limit at 1.5 I_s,N (the same fraction here)
    return SlCase(n_p=m.p, R_s=r_total(d), L=m.L, psi_f=k1 / m.p, u_dc=d.inverter.V_dc, f_pwm=d.inverter.f_pwm,
                  J=mech.J, i_s_max=i_s_max, tau_max=tau_max, k_p=k_p, k_i=k_i, k_p_w=mech.J * w_b,
                  k_i_w=mech.J * w_b * w_b / 4.0, alpha_o=2.0 * math.pi * 100.0,
                  sigma0=r_total(d) / (2.0 * m.L), zeta_inf=0.2, w_1=0.2 * w_n, w_2=0.5 * w_n,
                  tau_L=14.0 / 1.5)


def bl_control(case: SlCase) -> Any:
    """bldclab's controller: ``Sine`` on the reduced-order observer, speed loop, no back-EMF feed-forward."""
    import bldclab as bl

    return bl.Sine(angle="observer", observer="reduced", observer_bandwidth=case.alpha_o, speed_loop=True,
                   emf_feedforward=False, speed_kp=case.k_p_w, speed_ki=case.k_i_w, tau_max=case.tau_max)


def run_bldclab(case: SlCase) -> tuple[Signals, dict[str, float]]:
    """Run bldclab: its I/f start, the hand-off, the speed loop to ``w_1``; the speed step ``t_pre`` later.

    Returns the signals from the step on (``t`` from 0 at the step) and the start's times (s): ``t_handoff``,
    ``t_step`` (the step in bldclab's run) and ``wall`` (the whole run, trace on).
    """
    import bldclab as bl

    drive = bl.load("servo-2k2")
    ctl = bl_control(case)
    probe = bl.simulate(drive, ctl, bl.Scenario(duration=3.0, omega_ref=case.w_1, trace_every=8))
    on = probe["mode"] > 0.5
    if not on.any():
        raise RuntimeError("bldclab's sensorless start did not reach the sine mode in 3 s")
    t_handoff = float(probe["t"][np.argmax(on)])
    # the step once the speed loop has settled at w_1 after the hand-off (as long as motulator's own settling)
    k_step = math.ceil((t_handoff + case.t_step) / case.T_s)
    t_step = k_step * case.T_s
    dt_load = case.t_load - case.t_step

    def w_ref(t: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.where(t < t_step, case.w_1, case.w_2)

    def load(t: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.where(t >= t_step + dt_load, case.tau_L, 0.0)

    t0 = time.perf_counter()
    res = bl.simulate(drive, ctl, bl.Scenario(duration=t_step + case.t_stop - case.t_step, omega_ref=w_ref,
                                              load_torque=load))
    wall = time.perf_counter() - t0
    a = np.exp(2j * np.pi / 3.0)
    i_ab = (2.0 / 3.0) * (res["i_a"] + a * res["i_b"] + a * a * res["i_c"])
    i_dq = i_ab * np.exp(-1j * (res["theta_e"] - np.pi))  # motulator's d axis: theta_e - pi
    t = np.asarray(res.t, dtype=float)
    k0 = int(np.argmin(np.abs(t - t_step)))
    sl = slice(k0, k0 + case.n_window)
    err = np.angle(np.exp(1j * (res["theta"] - res["theta_e"])))  # the observer's angle against the plant's
    sig = {"t": t[sl] - t[k0], "w_M": res["omega_m"][sl], "i_d": i_dq.real[sl], "i_q": i_dq.imag[sl],
           "tau_M": res["tau_e"][sl], "w_M_est": (res["omega_e"][sl] / case.n_p).astype(float),
           "err": err[sl].astype(float), "mode": res["mode"][sl].astype(float)}
    sig = {k: np.ascontiguousarray(v, dtype=float) for k, v in sig.items()}
    return sig, {"t_handoff": t_handoff, "t_step": t_step, "wall": wall, "t_run": float(t[-1])}


def time_bldclab(case: SlCase, repeats: int, t_run: float) -> dict[str, float]:
    """Best-of-``repeats`` wall time (s) per simulated second of the whole bldclab run, trace on and off."""
    import bldclab as bl

    drive, ctl = bl.load("servo-2k2"), bl_control(case)
    out = {}
    for name, trace in (("trace", True), ("no_trace", False)):
        sc = bl.Scenario(duration=t_run, omega_ref=case.w_1, trace=trace)
        walls = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            bl.simulate(drive, ctl, sc)
            walls.append(time.perf_counter() - t0)
        out[name] = min(walls) / t_run
    return out


# ------------------------------------------------------------------------------------------------------------
# motulator side (runs in the motulator venv: numpy and motulator only)


def motulator_side(case: SlCase, out: Path) -> dict[str, Any]:
    """Build and run motulator's sensorless current-vector control of the case; save the window to ``out``.

    As motulator's example (model: machine, mechanics, converter, ``Drive(pwm=True)``; control:
    ``CurrentVectorController`` with ``sensorless=True`` in a ``VectorControlSystem`` with a speed controller), on
    the numbers of the case: the observer's poles ``alpha_o`` and its default gain schedule, the current PI with
    bldclab's closed-loop poles, a 1DOF speed PI with bldclab's gains.
    """
    from importlib.metadata import version

    import motulator.drive.control.sm as control
    from motulator.drive import model

    t0 = time.perf_counter()
    par = model.SynchronousMachinePars(n_p=case.n_p, R_s=case.R_s, L_d=case.L, L_q=case.L, psi_f=case.psi_f)
    machine = model.SynchronousMachine(par)
    mechanics = model.MechanicalSystem(J=case.J)
    converter = model.VoltageSourceConverter(u_dc=case.u_dc)
    mdl = model.Drive(machine, mechanics, converter, pwm=True, delay=1)
    cfg = control.CurrentVectorControllerCfg(i_s_max=case.i_s_max, alpha_c=case.k_p / case.L,
                                             alpha_i=case.k_i / case.k_p, alpha_o=case.alpha_o,
                                             alpha_ref=case.alpha_ref, sensorless=True, T_s=case.T_s)
    vector_ctrl = control.CurrentVectorController(par, cfg)
    speed_ctrl = control.PIController(case.k_p_w, case.k_i_w, u_max=case.tau_max)
    ctrl = control.VectorControlSystem(vector_ctrl, speed_ctrl)
    ctrl.set_speed_ref(lambda t: case.w_1 if t < case.t_step else case.w_2)
    mdl.mechanics.set_external_load_torque(lambda t: case.tau_L if t >= case.t_load else 0.0)
    sim = model.Simulation(mdl, ctrl, show_progress=False)
    t1, c1 = time.perf_counter(), time.process_time()
    res = sim.simulate(t_stop=case.t_stop)
    t2, c2 = time.perf_counter(), time.process_time()

    k0 = round(case.t_step / case.T_s)
    n = case.n_window
    t = (k0 + np.arange(n)) * case.T_s
    tm = np.asarray(res.mdl.t, dtype=float)
    i_dq = np.asarray(res.mdl.machine.i_s_dq)
    th_true = np.unwrap(np.asarray(res.mdl.machine.theta_m, dtype=float).real)
    th_est = np.asarray(res.ctrl.fbk.theta_m, dtype=float)[k0:k0 + n]
    err = np.angle(np.exp(1j * (th_est - np.interp(t, tm, th_true))))
    sig = {"t": t - t[0], "w_M": np.interp(t, tm, np.asarray(res.mdl.mechanics.w_M, dtype=float)),
           "i_d": np.interp(t, tm, i_dq.real), "i_q": np.interp(t, tm, i_dq.imag),
           "tau_M": np.interp(t, tm, np.asarray(res.mdl.machine.tau_M, dtype=float)),
           "w_M_est": np.asarray(res.ctrl.fbk.w_M, dtype=float)[k0:k0 + n], "err": err}
    info = {"version": version("motulator"), "python": sys.version.split()[0], "wall_build": t1 - t0,
            "wall_sim": t2 - t1, "cpu_sim": c2 - c1, "solver_points": int(tm.size), "success": bool(res.success)}
    np.savez(out, **sig)
    return info


def run_motulator(case: SlCase, python: str, out: Path, timeout: float = 1200.0) -> tuple[Signals, dict[str, Any]]:
    """Run :func:`motulator_side` in the motulator venv; return its signals and run information."""
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(dataclasses.asdict(case), f)
        case_file = f.name
    try:
        proc = subprocess.run([python, str(Path(__file__).resolve()), "--motulator-side", case_file, "--out",
                               str(out)], capture_output=True, text=True, timeout=timeout)
    finally:
        os.unlink(case_file)
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-1:] or ["?"]
        raise RuntimeError(f"motulator run failed: {tail[0][:160]}")
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    if not info["success"]:
        raise RuntimeError("motulator's solver stopped before the end of the run")
    with np.load(out) as z:
        sig = {k: np.asarray(z[k], dtype=float) for k in z.files}
    return sig, info


# ------------------------------------------------------------------------------------------------------------
# agreement


def agreement(case: SlCase, a: Signals, b: Signals) -> list[mc.Check]:
    """Compare the two windows (a: bldclab, b: motulator), time from the speed step; differences are a - b.

    Tolerances from what the set-ups cannot make equal (``docs/benchmarks.md``): the state at the step (each side's
    own start; both settled at ``w_1`` with zero load and no friction, so the same operating point), the current
    controllers' zeros (the same poles), float32 against double, motulator's 12-bit duties. The step itself runs
    at the torque limit on both sides; the load step is taken by the same speed PI.
    """
    n = min(a["t"].size, b["t"].size)
    a = {k: v[:n] for k, v in a.items()}
    b = {k: v[:n] for k, v in b.items()}
    t = a["t"]
    dt_load = case.t_load - case.t_step
    dw = a["w_M"] - b["w_M"]
    di = np.hypot(a["i_d"] - b["i_d"], a["i_q"] - b["i_q"])
    ea, eb = np.degrees(a["err"]), np.degrees(b["err"])
    step = case.w_2 - case.w_1
    settled = (t >= dt_load - 0.05) & (t < dt_load)  # before the load step
    loaded = t >= case.t_stop - case.t_step - 0.1  # the last 0.1 s, under load
    after_load = t >= dt_load

    def dip(s: Signals) -> float:
        return float(case.w_2 - np.min(s["w_M"][after_load]))

    def cross(s: Signals) -> float:
        above = np.nonzero(s["w_M"] >= case.w_1 + 0.9 * step)[0]
        return float(s["t"][above[0]]) if above.size else math.inf

    return [
        mc.Check("bldclab in the sine mode over the window", float(np.mean(a["mode"] < 0.5)), 0.0, "share",
                 "no loss of lock, no restart"),
        mc.Check("max |dw|, whole window", float(np.max(np.abs(dw))), 0.02 * step, "rad/s",
                 "2 % of the step: the same torque limit and PI; the observers' speed lags differ by their zeros"),
        mc.Check("time to 90 % of the step a - b", cross(a) - cross(b), 0.002, "s",
                 "2 ms of a 40 ms torque-limited ramp"),
        mc.Check("speed dip after the load step a - b", dip(a) - dip(b), 0.05 * dip(b), "rad/s",
                 "5 %: the same speed PI on each observer's speed estimate"),
        mc.Check("rms |di_dq|, whole window", float(np.sqrt(np.mean(di**2))), 0.05 * case.i_s_max, "A",
                 "5 % of I_s,N: current-controller zeros, the limit-exit instants"),
        mc.Check("mean i_q under load a - b", float(np.mean(a["i_q"][loaded]) - np.mean(b["i_q"][loaded])),
                 0.01 * case.tau_L / (1.5 * case.n_p * case.psi_f), "A", "1 % of the load's current"),
        mc.Check("mean angle error before the load a - b (deg)", float(np.mean(ea[settled]) - np.mean(eb[settled])),
                 0.2, "deg", "both observers unbiased with the true parameters; 0.2 deg for the discretisations"),
        mc.Check("mean angle error under load a - b (deg)", float(np.mean(ea[loaded]) - np.mean(eb[loaded])), 0.2,
                 "deg", "the same"),
        mc.Check("worst |angle error| over the window a - b (deg)",
                 float(np.max(np.abs(ea)) - np.max(np.abs(eb))), 1.0, "deg",
                 "the transients of the speed and load steps through the same observer design"),
    ]


@dataclass
class SlComparison:
    """Everything the sensorless comparison measured; ``reason`` says why motulator is missing if it is."""

    case: SlCase
    bl_info: dict[str, float]
    bl_time: dict[str, float]
    checks: list[mc.Check] = dataclasses.field(default_factory=list)
    mot_info: dict[str, Any] = dataclasses.field(default_factory=dict)
    reason: str = ""
    saved: Path | None = None
    worst: dict[str, float] = dataclasses.field(default_factory=dict)

    @property
    def mot_per_s(self) -> float:
        """motulator wall seconds per simulated second (model build + simulate)."""
        if not self.mot_info:
            return math.nan
        return (self.mot_info["wall_build"] + self.mot_info["wall_sim"]) / self.case.t_stop

    @property
    def ratio(self) -> float:
        """motulator over bldclab, wall time per simulated second (bldclab with trace)."""
        return self.mot_per_s / self.bl_time["trace"]


def compare(repeats: int = 3, venv: Path = mc.DEFAULT_VENV, python: str | None = None, out: Path = mc.DEFAULT_OUT,
            with_motulator: bool = True) -> SlComparison:
    """Run both sides, time them and compare; motulator problems end up in ``reason``."""
    case = sl_case()
    bl_sig, bl_info = run_bldclab(case)
    cmp = SlComparison(case, bl_info, time_bldclab(case, repeats, bl_info["t_run"]))
    cmp.worst["bldclab"] = float(np.degrees(np.max(np.abs(bl_sig["err"]))))
    if not with_motulator:
        cmp.reason = "skipped"
        return cmp
    py, reason = mc.ensure_motulator(venv, python)
    if py is None:
        cmp.reason = reason
        return cmp
    try:
        mot_sig, cmp.mot_info = run_motulator(case, py, out / "sensorless_motulator_side.npz")
    except (RuntimeError, subprocess.TimeoutExpired, ValueError, OSError, KeyError) as exc:
        cmp.reason = str(exc) or type(exc).__name__
        return cmp
    cmp.worst["motulator"] = float(np.degrees(np.max(np.abs(mot_sig["err"]))))
    cmp.checks = agreement(case, bl_sig, mot_sig)
    cmp.saved = out / "sensorless_case.npz"
    np.savez(cmp.saved, **{f"bldclab_{k}": v for k, v in bl_sig.items()},
             **{f"motulator_{k}": v for k, v in mot_sig.items()})
    return cmp


def report(cmp: SlComparison) -> list[str]:
    """Lines describing the comparison (timing, agreement)."""
    c, bi = cmp.case, cmp.bl_info
    lines = [f"sensorless case: servo-2k2 (L_d = L_q = {c.L * 1e3:g} mH, psi_f = {c.psi_f:.4g} V s), reduced-order "
             f"observer alpha_o = 2 pi {c.alpha_o / (2 * math.pi):g} rad/s, {c.f_pwm / 1e3:g} kHz PWM; speed step "
             f"{c.w_1:.2f} -> {c.w_2:.2f} rad/s, load step {c.tau_L:.3g} N m {c.t_load - c.t_step:g} s later, "
             f"{c.t_stop - c.t_step:g} s compared",
             f"bldclab: I/f start, hand-off to the observer at {bi['t_handoff']:.3f} s, step at {bi['t_step']:.3f} s; "
             f"{cmp.bl_time['trace']:.4f} s per simulated s with trace, {cmp.bl_time['no_trace']:.4f} without; "
             f"worst |angle error| in the window {cmp.worst.get('bldclab', math.nan):.3f} deg"]
    if cmp.reason:
        lines.append(f"motulator: not run ({cmp.reason})")
        return lines
    mi = cmp.mot_info
    lines.append(f"motulator {mi['version']} (Python {mi['python']}): observer from standstill (its own start), "
                 f"step at {c.t_step:g} s; {cmp.mot_per_s:.2f} s per simulated s ({mi['solver_points']} solver "
                 f"points); ratio {cmp.ratio:.0f}x (wall, bldclab with trace); worst |angle error| in the window "
                 f"{cmp.worst.get('motulator', math.nan):.3f} deg")
    return lines + mc.check_lines(cmp.checks, cmp.saved)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="timed bldclab runs (best)")
    ap.add_argument("--venv", type=Path, default=mc.DEFAULT_VENV, help="motulator's virtual environment")
    ap.add_argument("--python", help="Python >= 3.12 to create it with (default: found on PATH or in pyenv)")
    ap.add_argument("--out", type=Path, default=mc.DEFAULT_OUT, help="directory for the saved trajectories")
    ap.add_argument("--no-motulator", action="store_true", help="bldclab side only")
    ap.add_argument("--motulator-side", metavar="CASE_JSON", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.motulator_side:
        case = SlCase(**json.loads(Path(args.motulator_side).read_text()))
        print(json.dumps(motulator_side(case, args.out)))
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    cmp = compare(args.repeats, args.venv, args.python, args.out, not args.no_motulator)
    print("\n".join(report(cmp)))
    failed = [ch for ch in cmp.checks if not ch.ok]
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())

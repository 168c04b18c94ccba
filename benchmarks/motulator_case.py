"""bldclab beside motulator on one shared case: wall time per simulated second and agreement of the trajectories.

The case (``docs/benchmarks.md``, "the shared case"): htm-48v with a sinusoidal back-EMF of the same amplitude
(``psi_f = k_phi / p`` = 40 mV s, ``L_d = L_q = L``), sensored current vector control on the encoder angle with
the d,q PIs of ``bldclab.Sine`` (1 kHz, pole-zero cancellation), a speed PI (5 Hz, ``k_p = J omega_b``,
``k_i = k_p omega_b / 4``, torque limit ``1.5 p psi_f I_s,N``), 14 kHz carrier PWM with double update and one
sample of computation delay, 48 V bus, htm-48v's mechanics, a speed step from standstill to 60 rad/s at t = 0,
1 s simulated. Both sides are configured from the numbers of one :class:`Case`; what the two tools cannot make
equal is listed in ``docs/benchmarks.md``.

motulator (https://github.com/Aalto-Electric-Drives/motulator, MIT) is installed into its own Python >= 3.12
virtual environment (default ``benchmarks/.venv-motulator``, not committed) and run in a subprocess: this file is
also its script there (``--motulator-side``), importing only numpy and motulator. Both trajectories are sampled at
the controller's sampling instants (carrier valleys and peaks, where the currents cross their PWM-period means),
saved to ``out/benchmarks/motulator_case.npz`` and compared. If motulator cannot be installed or run, the report
says why and the script still exits 0.

Run: ``python benchmarks/motulator_case.py [--repeats 7] [--venv DIR] [--python PY312] [--out DIR]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import glob
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    import bldclab as bl

ROOT = Path(__file__).resolve().parents[1]
MOTULATOR_VERSION = "0.18.0"
DEFAULT_VENV = ROOT / "benchmarks" / ".venv-motulator"
DEFAULT_OUT = ROOT / "out" / "benchmarks"
TARGET_RATIO = 500.0
SETTLED = 0.5  # start of the settled window (s): 2.5 speed-loop time constants after the overshoot
Signals = dict[str, NDArray[np.float64]]


@dataclass(frozen=True)
class Case:
    """The shared case, SI units. Both tools are configured from these numbers only.

    Parameters
    ----------
    n_p : int
        Pole pairs.
    R_s, L, psi_f : float
        Phase resistance (Ohm), inductance ``L_d = L_q`` (H), PM flux linkage (V s, electrical; bldclab's
        ``k_1 = n_p psi_f`` in V s/rad).
    u_dc, f_pwm : float
        DC bus (V), carrier frequency (Hz); sampling at carrier valley and peak.
    J, B, tau_c : float
        Inertia (kg m^2), viscous (N m s/rad) and Coulomb (N m) friction.
    i_s_max, tau_max : float
        Current limit (A, peak) and torque limit of the speed controller (N m).
    k_p, k_i : float
        d,q current PI gains (V/A, V/(A s)), bldclab's ``Sine.gains``.
    k_p_w, k_i_w : float
        Speed PI gains (N m s/rad, N m/rad).
    w_M_ref, t_stop : float
        Speed reference from t = 0 (rad/s, mechanical), simulated time (s).
    theta_e0 : float
        Initial electrical angle in bldclab's convention (rad; motulator's d axis is at ``theta_e - pi``).
    coulomb_eps : float
        motulator only: speed (rad/s) over which its Coulomb friction ``tau_c tanh(w / eps)`` reaches full value.
    alpha_ref : float
        motulator only: bandwidth (rad/s) of its current-reference tracking law (a first-order lag from torque to
        current reference that bldclab does not have); set well above the speed loop.
    """

    n_p: int
    R_s: float
    L: float
    psi_f: float
    u_dc: float
    f_pwm: float
    J: float
    B: float
    tau_c: float
    i_s_max: float
    tau_max: float
    k_p: float
    k_i: float
    k_p_w: float
    k_i_w: float
    w_M_ref: float = 60.0
    t_stop: float = 1.0
    theta_e0: float = 7.0 * math.pi / 6.0 - 0.02
    coulomb_eps: float = 1e-3
    alpha_ref: float = 2.0 * math.pi * 1000.0

    @property
    def T_s(self) -> float:
        """Sampling period (s): half the carrier period."""
        return 0.5 / self.f_pwm

    @property
    def n_samples(self) -> int:
        """Samples in the run (the common time grid ``k T_s``)."""
        return round(self.t_stop * 2.0 * self.f_pwm)


# ------------------------------------------------------------------------------------------------------------
# bldclab side


def shared_drive() -> bl.Drive:
    """htm-48v with a sinusoidal back-EMF of peak ``k_1 = k_phi`` (V s/rad), i.e. ``psi_f = k_phi / p``."""
    import bldclab as bl

    base = bl.load("htm-48v")
    k_1 = base.motor.k_phi  # the trapezoid's flat top, 0.32 V s/rad
    return base.replace(motor__emf=bl.BackEmf.symmetric(bl.Sinusoid(k_1=k_1)), name="htm-48v-sine",
                        description="htm-48v with a sinusoidal back-EMF of peak k_phi: the motulator case")


def shared_case(t_stop: float = 1.0) -> Case:
    """Return the case built from htm-48v and bldclab's default ``Sine`` design."""
    import bldclab as bl
    from bldclab.control.sine import fundamental_k1
    from bldclab.model.analytic import i_sN

    drive = shared_drive()
    m, mech = drive.motor, drive.mechanics
    k_p, k_i = bl.Sine().gains(drive)  # 1 kHz, 90 deg: k_p = omega_c L, k_i = omega_c R
    w_b = 2.0 * math.pi * bl.Sine().speed_bandwidth_hz  # Sine's default speed-loop design
    k_p_w = mech.J * w_b
    i_s_max = i_sN(drive)
    return Case(n_p=m.p, R_s=m.R, L=m.L, psi_f=fundamental_k1(drive) / m.p, u_dc=drive.inverter.V_dc,
                f_pwm=drive.inverter.f_pwm, J=mech.J, B=mech.B, tau_c=mech.tau_c, i_s_max=i_s_max,
                tau_max=1.5 * fundamental_k1(drive) * i_s_max, k_p=k_p, k_i=k_i, k_p_w=k_p_w,
                k_i_w=k_p_w * w_b / 4.0, t_stop=t_stop)


def shared_control(case: Case) -> bl.Sine:
    """bldclab's controller of the case: ``Sine`` on the encoder angle with the speed loop.

    ``emf_feedforward=False``: motulator's current vector controller has no back-EMF feed-forward (its integrators
    carry the back-EMF), so neither side has one; on this sinusoidal motor the feed-forward would only remove the
    0.56 A lag of the current during the acceleration ramp. ``handoff_speed=0.5`` rad/s: the sinusoidal mode takes
    over at the first valid Hall speed (two Hall edges), the square-wave start cannot be switched off.
    """
    import bldclab as bl

    return bl.Sine(angle="encoder", emf_feedforward=False, speed_loop=True, handoff_speed=0.5,
                   speed_kp=case.k_p_w, speed_ki=case.k_i_w, tau_max=case.tau_max)


def bldclab_scenario(case: Case, trace: bool = True) -> bl.Scenario:
    """The speed step of the case as a bldclab scenario (rotor dynamics, speed reference from t = 0)."""
    import bldclab as bl

    return bl.Scenario(duration=case.t_stop, omega_ref=case.w_M_ref, theta0=case.theta_e0, trace=trace)


def run_bldclab(case: Case) -> tuple[Signals, float]:
    """Run the bldclab side once with a trace; return the signals on the common grid and the hand-off time (s).

    Signals: ``t``, ``w_M`` (rad/s), ``i_d``, ``i_q`` (A, plant currents in the true rotor frame, d along the PM
    flux), ``tau_M`` (N m), ``w_M_fbk`` (the speed the speed PI sees: Hall speed), ``i_q_ref`` (A), ``tau_mean``
    (N m, the torque's exact mean over each sample period; bldclab only).
    """
    import bldclab as bl

    res = bl.simulate(shared_drive(), shared_control(case), bldclab_scenario(case))
    a = np.exp(2j * np.pi / 3.0)
    i_ab = (2.0 / 3.0) * (res["i_a"] + a * res["i_b"] + a * a * res["i_c"])
    i_dq = i_ab * np.exp(-1j * (res["theta_e"] - np.pi))  # motulator's d axis: theta_e - pi
    sig = {"t": np.asarray(res.t, dtype=float), "w_M": res["omega_m"], "i_d": i_dq.real, "i_q": i_dq.imag,
           "tau_M": res["tau_e"], "w_M_fbk": res["omega_e"].astype(float) / case.n_p,
           "i_q_ref": res["i_q_ref"].astype(float), "tau_mean": res["tau_mean"]}
    sig = {k: np.ascontiguousarray(v[: case.n_samples], dtype=float) for k, v in sig.items()}
    mode = res["mode"]
    t_handoff = float(res.t[int(np.argmax(mode > 0.5))]) if np.any(mode > 0.5) else math.inf
    return sig, t_handoff


def time_bldclab(case: Case, repeats: int) -> dict[str, float]:
    """Best-of-``repeats`` wall and CPU time (s) of ``simulate`` on the case, with and without trace.

    Keys: ``trace``, ``no_trace`` (wall), ``cpu_trace``, ``cpu_no_trace`` (process CPU time), ``setup`` (wall of a
    run of one sample: parameters, tables, the C call; the part of ``simulate`` that does not grow with the
    simulated time) and ``steps`` (integration steps of the run). The best run is taken because other processes on
    the machine only ever slow a run down.
    """
    import bldclab as bl

    drive, ctl = shared_drive(), shared_control(case)
    out: dict[str, float] = {}
    short = dataclasses.replace(case, t_stop=case.T_s)
    for name, c, trace in (("trace", case, True), ("no_trace", case, False), ("setup", short, False)):
        sc = bldclab_scenario(c, trace)
        res = bl.simulate(drive, ctl, sc)  # warm: imports, core load, caches
        walls, cpus = [], []
        for _ in range(repeats):
            c0, t0 = time.process_time(), time.perf_counter()
            bl.simulate(drive, ctl, sc)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        out[name] = min(walls)
        out[f"cpu_{name}"] = min(cpus)
        if c is case:
            out["steps"] = float(res.meta["stats"]["steps"])
    return out


def best_of(a: dict[str, float], b: dict[str, float]) -> dict[str, float]:
    """Element-wise minimum of two :func:`time_bldclab` results (e.g. timed before and after motulator)."""
    return {k: min(a[k], b[k]) for k in a}


# ------------------------------------------------------------------------------------------------------------
# motulator side (runs in the motulator venv: numpy and motulator only)


def motulator_side(case: Case, out: Path) -> dict[str, Any]:
    """Build and run the motulator model of the case; save the signals on the common grid to ``out`` (npz).

    Mirrors motulator's own gallery examples (model: machine, mechanics, converter, ``Drive(pwm=True)``; control:
    ``CurrentVectorController`` in sensored mode inside a ``VectorControlSystem`` with a speed controller; then
    ``Simulation(...).simulate``), with the numbers of the case.
    """
    from importlib.metadata import version

    import motulator.drive.control.sm as control
    from motulator.drive import model

    t0 = time.perf_counter()
    par = model.SynchronousMachinePars(n_p=case.n_p, R_s=case.R_s, L_d=case.L, L_q=case.L, psi_f=case.psi_f)
    machine = model.SynchronousMachine(par)

    def b_l(w_M: float) -> float:
        """Friction coefficient: viscous B plus a smoothed Coulomb term, ``B_L(w) w = B w + tau_c tanh(w/eps)``."""
        w = float(w_M)
        if w == 0.0:
            return case.B + case.tau_c / case.coulomb_eps
        return case.B + case.tau_c * math.tanh(w / case.coulomb_eps) / w

    mechanics = model.MechanicalSystem(J=case.J, B_L=b_l)
    converter = model.VoltageSourceConverter(u_dc=case.u_dc)
    mdl = model.Drive(machine, mechanics, converter, pwm=True, delay=1)
    theta_m0 = case.theta_e0 - math.pi  # motulator's electrical angle is that of the d axis (PM flux)
    machine.state.theta_m = complex(theta_m0)
    mechanics.state.theta_M = complex(theta_m0 / case.n_p)

    # current PI: tracking bandwidth alpha_c = k_p / L and integral bandwidth alpha_i = k_i / k_p give the same
    # closed-loop poles as bldclab's pole-zero cancellation design (tracking: alpha_c; disturbances: alpha_c and
    # alpha_i = R / L)
    cfg = control.CurrentVectorControllerCfg(i_s_max=case.i_s_max, alpha_c=case.k_p / case.L,
                                             alpha_i=case.k_i / case.k_p, alpha_ref=case.alpha_ref,
                                             sensorless=False, T_s=case.T_s)
    vector_ctrl = control.CurrentVectorController(par, cfg)
    vector_ctrl.observer.flux_observer.theta_m = theta_m0
    speed_ctrl = control.PIController(case.k_p_w, case.k_i_w, u_max=case.tau_max)  # 1DOF: k_t = k_p
    ctrl = control.VectorControlSystem(vector_ctrl, speed_ctrl)
    ctrl.set_speed_ref(case.w_M_ref)
    sim = model.Simulation(mdl, ctrl, show_progress=False)
    t1, c1 = time.perf_counter(), time.process_time()
    res = sim.simulate(t_stop=case.t_stop)
    t2, c2 = time.perf_counter(), time.process_time()

    t = np.arange(case.n_samples) * case.T_s
    tm = np.asarray(res.mdl.t, dtype=float)
    i_dq = np.asarray(res.mdl.machine.i_s_dq)
    n = case.n_samples
    sig = {"t": t, "w_M": np.interp(t, tm, np.asarray(res.mdl.mechanics.w_M, dtype=float)),
           "i_d": np.interp(t, tm, i_dq.real), "i_q": np.interp(t, tm, i_dq.imag),
           "tau_M": np.interp(t, tm, np.asarray(res.mdl.machine.tau_M, dtype=float)),
           "w_M_fbk": np.asarray(res.ctrl.fbk.w_M, dtype=float)[:n],
           "i_q_ref": np.asarray(res.ctrl.ref.i_s, dtype=complex).imag[:n]}
    info = {"version": version("motulator"), "python": sys.version.split()[0], "wall_build": t1 - t0,
            "wall_sim": t2 - t1, "cpu_sim": c2 - c1, "solver_points": int(tm.size), "success": bool(res.success)}
    np.savez(out, **sig)
    return info


# ------------------------------------------------------------------------------------------------------------
# the motulator environment and the subprocess


def _is_py312(python: str) -> bool:
    try:
        return subprocess.run([python, "-c", "import sys; assert sys.version_info >= (3, 12)"], capture_output=True,
                              timeout=60).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def find_python312(explicit: str | None = None) -> str | None:
    """A Python >= 3.12 that runs: ``explicit``, else ``python3.12``/``3.13``/``3.14`` on PATH or a pyenv version.

    Every candidate is run once: a pyenv shim on PATH exists even when its version is not selected, and fails.
    """
    if explicit:
        return explicit if _is_py312(explicit) else None
    cands = [found for name in ("python3.12", "python3.13", "python3.14") if (found := shutil.which(name))]
    pyenv = Path(os.environ.get("PYENV_ROOT", Path.home() / ".pyenv")) / "versions"
    for pattern in ("3.12*", "3.13*", "3.14*"):
        cands += sorted(glob.glob(str(pyenv / pattern / "bin" / "python")))
    return next((c for c in cands if _is_py312(c)), None)


def ensure_motulator(venv: Path, python: str | None, timeout: float = 600.0) -> tuple[str | None, str]:
    """Return (the venv's python, "") with motulator installed, or (None, the reason it is not available)."""
    py = venv / "bin" / "python"
    check = [str(py), "-c", f"import motulator, importlib.metadata as m; assert m.version('motulator') == "
                            f"'{MOTULATOR_VERSION}'"]
    if py.exists() and subprocess.run(check, capture_output=True).returncode == 0:
        return str(py), ""
    base = find_python312(python)
    if base is None:
        return None, "no Python >= 3.12 found (motulator needs it; --python PATH)"
    try:
        if not py.exists():
            subprocess.run([base, "-m", "venv", str(venv)], check=True, capture_output=True, text=True,
                           timeout=timeout)
        subprocess.run([str(py), "-m", "pip", "install", "-q", f"motulator=={MOTULATOR_VERSION}"], check=True,
                       capture_output=True, text=True, timeout=timeout)
    except subprocess.CalledProcessError as exc:
        tail = (exc.stderr or exc.stdout or "").strip().splitlines()[-1:] or ["?"]
        return None, f"install failed: {tail[0][:120]}"
    except (subprocess.TimeoutExpired, OSError) as exc:
        return None, f"install failed: {type(exc).__name__}"
    if subprocess.run(check, capture_output=True).returncode != 0:
        return None, "motulator does not import after installation"
    return str(py), ""


def run_motulator(case: Case, python: str, out: Path, timeout: float = 900.0) -> tuple[Signals, dict[str, Any]]:
    """Run :func:`motulator_side` in the motulator venv; return its signals and run information."""
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(dataclasses.asdict(case), f)
        case_file = f.name
    try:
        t0 = time.perf_counter()
        proc = subprocess.run([python, str(Path(__file__).resolve()), "--motulator-side", case_file, "--out",
                               str(out)], capture_output=True, text=True, timeout=timeout)
        wall = time.perf_counter() - t0
    finally:
        os.unlink(case_file)
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-1:] or ["?"]
        raise RuntimeError(f"motulator run failed: {tail[0][:160]}")
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    info["wall_process"] = wall
    if not info["success"]:
        raise RuntimeError("motulator's solver stopped before the end of the run")
    with np.load(out) as z:
        sig = {k: np.asarray(z[k], dtype=float) for k in z.files}
    return sig, info


# ------------------------------------------------------------------------------------------------------------
# agreement


@dataclass(frozen=True)
class Check:
    """One agreement number with its tolerance and the reason for it."""

    name: str
    value: float
    tol: float
    unit: str
    why: str

    @property
    def ok(self) -> bool:
        """Within tolerance."""
        return bool(abs(self.value) <= self.tol)


def _peak(sig: Signals) -> tuple[float, float]:
    k = int(np.argmax(sig["w_M"]))
    return float(sig["w_M"][k]), float(sig["t"][k])


def _crossing(sig: Signals, level: float) -> float:
    above = np.nonzero(sig["w_M"] >= level)[0]
    return float(sig["t"][above[0]]) if above.size else math.inf


def agreement(case: Case, a: Signals, b: Signals, t_handoff: float) -> list[Check]:
    """Compare two runs of the case on the common grid (a: bldclab, b: motulator); differences are a - b.

    The tolerances are set from the differences the two set-ups cannot remove (``docs/benchmarks.md``): bldclab's
    square-wave start until two Hall edges have given a speed (about 23 ms with some 6 % less torque, then the
    hand-off transient: about 0.8 rad/s behind) and its speed feedback from the Hall edges (the mean over the last
    60 electrical degrees, which lags the true speed by ``a dt / 2``, 0.6 rad/s at the end of the ramp, so the
    speed PI leaves its limit later and catches up); PWM-level details move the speed by less than 0.01 rad/s.
    """
    n = min(a["t"].size, b["t"].size)
    a = {k: v[:n] for k, v in a.items()}
    b = {k: v[:n] for k, v in b.items()}
    t = a["t"]
    dw = a["w_M"] - b["w_M"]
    di = np.hypot(a["i_d"] - b["i_d"], a["i_q"] - b["i_q"])
    settled = t >= SETTLED
    sine = t >= t_handoff
    ramp = (t >= t_handoff + 0.005) & (t < 0.08)  # both at the torque limit, in sinusoidal mode
    pa, ta = _peak(a)
    pb, tb = _peak(b)
    tol_w = 1.5
    return [
        Check("max |dw|, whole run", float(np.max(np.abs(dw))), tol_w, "rad/s",
              "square-wave start (0.8) + Hall-speed lag (0.6) + margin; 2.5 % of the step"),
        Check(f"max |dw|, t >= {SETTLED:g} s", float(np.max(np.abs(dw[settled]))), 0.1, "rad/s",
              "the start difference decays with the speed loop's slow zero (omega_b/4)"),
        Check("speed peak (overshoot) a - b", pa - pb, 1.0, "rad/s", "Hall-speed lag at the end of the ramp"),
        Check("time of the peak a - b", ta - tb, 0.01, "s", "set by the 5 Hz loop; the ramp shifts by 1-3 ms"),
        Check("time to 90 % of the step a - b", _crossing(a, 0.9 * case.w_M_ref) - _crossing(b, 0.9 * case.w_M_ref),
              0.004, "s", "1.5 rad/s (first check) at 550 rad/s^2 is 2.7 ms; margin"),
        Check("mean torque on the ramp a - b", float(np.mean(a["tau_M"][ramp]) - np.mean(b["tau_M"][ramp])), 0.3,
              "N m", "same limit 1.5 p psi_f I_s,N = 27.7 N m, same PI ramp lag; 1 %"),
        Check("rms |di_dq|, sinusoidal mode", float(np.sqrt(np.mean(di[sine] ** 2))), 1.0, "A",
              "limit-exit timing (about 1.4 A/ms of slope over 1-2 ms); 2 % of I_s,N"),
        Check(f"rms |di_dq|, t >= {SETTLED:g} s", float(np.sqrt(np.mean(di[settled] ** 2))), 0.2, "A",
              "steady current 0.66 A; PWM sampled at the same carrier instants on both sides"),
        Check(f"mean torque, t >= {SETTLED:g} s, a - b",
              float(np.mean(a["tau_M"][settled]) - np.mean(b["tau_M"][settled])), 0.02, "N m",
              "friction B w + tau_c = 0.32 N m, the same on both sides (motulator's tanh saturated)"),
    ]


# ------------------------------------------------------------------------------------------------------------
# the comparison as one call (used by run_all.py)


@dataclass
class Comparison:
    """Everything the comparison measured; ``reason`` says why motulator is missing if it is."""

    case: Case
    bl_time: dict[str, float]
    t_handoff: float
    checks: list[Check] = dataclasses.field(default_factory=list)
    mot_info: dict[str, Any] = dataclasses.field(default_factory=dict)
    reason: str = ""
    saved: Path | None = None

    @property
    def mot_per_s(self) -> float:
        """motulator wall seconds per simulated second (model build + simulate)."""
        if not self.mot_info:
            return math.nan
        return (self.mot_info["wall_build"] + self.mot_info["wall_sim"]) / self.case.t_stop

    @property
    def ratio(self) -> float:
        """motulator over bldclab, wall time (bldclab with trace: both keep every sample)."""
        return self.mot_per_s / (self.bl_time["trace"] / self.case.t_stop)

    @property
    def ratio_no_trace(self) -> float:
        """motulator over bldclab without trace, wall time."""
        return self.mot_per_s / (self.bl_time["no_trace"] / self.case.t_stop)

    @property
    def ratio_cpu(self) -> float:
        """motulator's simulate over bldclab's simulate with trace, process CPU time: less sensitive to load."""
        return self.mot_info["cpu_sim"] / self.bl_time["cpu_trace"]


def compare(repeats: int = 5, venv: Path = DEFAULT_VENV, python: str | None = None, out: Path = DEFAULT_OUT,
            t_stop: float = 1.0, with_motulator: bool = True) -> Comparison:
    """Run both sides of the case, time them and compare; motulator problems end up in ``reason``."""
    case = shared_case(t_stop)
    bl_sig, t_handoff = run_bldclab(case)
    cmp = Comparison(case, time_bldclab(case, repeats), t_handoff)
    if not with_motulator:
        cmp.reason = "skipped"
        return cmp
    py, reason = ensure_motulator(venv, python)
    if py is None:
        cmp.reason = reason
        return cmp
    try:
        mot_sig, cmp.mot_info = run_motulator(case, py, out / "motulator_side.npz")
    except (RuntimeError, subprocess.TimeoutExpired, ValueError, OSError, KeyError) as exc:
        cmp.reason = str(exc) or type(exc).__name__
        return cmp
    cmp.bl_time = best_of(cmp.bl_time, time_bldclab(case, repeats))  # again, close in time to motulator's run
    cmp.checks = agreement(case, bl_sig, mot_sig, t_handoff)
    cmp.saved = out / "motulator_case.npz"
    np.savez(cmp.saved, **{f"bldclab_{k}": v for k, v in bl_sig.items()},
             **{f"motulator_{k}": v for k, v in mot_sig.items()})
    return cmp


def check_lines(checks: list[Check], saved: Path | None) -> list[str]:
    """The agreement table of a comparison (one line per check) and where its trajectories were saved."""
    w = max(len(ch.name) for ch in checks)
    lines = [f"{'agreement (bldclab - motulator)':<{w}}  {'value':>10}  {'tolerance':>9}  ok"]
    for ch in checks:
        lines.append(f"{ch.name:<{w}}  {ch.value:>+10.4f}  {ch.tol:>9.3g}  {'yes' if ch.ok else 'NO':<3} {ch.unit}"
                     f" ({ch.why})")
    if saved is not None:
        lines.append(f"trajectories: {saved.relative_to(ROOT) if saved.is_relative_to(ROOT) else saved}")
    return lines


def report(cmp: Comparison) -> list[str]:
    """Lines describing a comparison (timing, split of bldclab's time, agreement)."""
    c, bt = cmp.case, cmp.bl_time
    run_c = (bt["no_trace"] - bt["setup"]) / c.t_stop
    lines = [f"shared case: htm-48v with sinusoidal back-EMF (psi_f = {c.psi_f * 1e3:.1f} mV s), encoder-angle "
             f"current vector control, {c.f_pwm / 1e3:g} kHz PWM, speed step 0 -> {c.w_M_ref:g} rad/s, "
             f"{c.t_stop:g} s simulated",
             f"bldclab: {bt['trace'] / c.t_stop:.4f} s per simulated s with trace, {bt['no_trace'] / c.t_stop:.4f} "
             f"without ({bt['setup'] * 1e3:.1f} ms fixed Python setup + {run_c:.4f} s/s in C, "
             f"{bt['steps'] / c.t_stop:.0f} integration steps/s); hand-off to sine at {cmp.t_handoff * 1e3:.1f} ms"]
    if cmp.reason:
        lines.append(f"motulator: not run ({cmp.reason})")
        return lines
    mi = cmp.mot_info
    lines.append(f"motulator {mi['version']} (Python {mi['python']}): {cmp.mot_per_s:.2f} s per simulated s "
                 f"(build {mi['wall_build']:.2f} s + simulate {mi['wall_sim']:.2f} s, {mi['solver_points']} solver "
                 f"points); ratio {cmp.ratio:.0f}x with trace, {cmp.ratio_no_trace:.0f}x without (target >= "
                 f"{TARGET_RATIO:g}x); CPU time ratio {cmp.ratio_cpu:.0f}x")
    return lines + check_lines(cmp.checks, cmp.saved)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="timed bldclab runs before and after motulator's (best)")
    ap.add_argument("--venv", type=Path, default=DEFAULT_VENV, help="motulator's virtual environment")
    ap.add_argument("--python", help="Python >= 3.12 to create it with (default: found on PATH or in pyenv)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help="directory for the saved trajectories")
    ap.add_argument("--seconds", type=float, default=1.0, help="simulated time")
    ap.add_argument("--no-motulator", action="store_true", help="bldclab side only")
    ap.add_argument("--motulator-side", metavar="CASE_JSON", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.motulator_side:
        case = Case(**json.loads(Path(args.motulator_side).read_text()))
        print(json.dumps(motulator_side(case, args.out)))
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    cmp = compare(args.repeats, args.venv, args.python, args.out, args.seconds, not args.no_motulator)
    print("\n".join(report(cmp)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""CLI subcommands that simulate: ``bldclab simulate`` (one run) and ``bldclab compare`` (paper 1 end to end)."""

from __future__ import annotations

import argparse
import io
import json
import math
import re
import sys
import warnings
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._files import write_files
from ..analysis import paper2
from ..analysis.compare import compare, speed_grid
from ..analysis.experiments import electrical_period
from ..analysis.faults import fault_table
from ..control import Control, Lu, Sine, SixStep, SixStepVoltage
from ..errors import BldclabError, PlausibilityWarning
from ..model import analytic
from ..model.catalog import load
from ..model.motor import Drive, Inverter
from ..model.units import to_si
from ..report import plots
from ..report.bundle import compare_command, compare_files, compare_outputs
from ..sim import Scenario, simulate
from ..sim import plausibility as _plaus

if TYPE_CHECKING:
    pass

__all__ = ["configure_compare", "configure_simulate", "parse_speed", "run_compare", "run_simulate"]

CONTROLS = ("square", "sine", "sixv", "lu", "lu-no-do", "rect")


def parse_speed(text: str, drive: Drive) -> float:
    """Read a speed: ``"0.5 pu"`` (of ``Omega_0``), ``"300 rpm"``, ``"31.4 rad/s"`` or a number in rad/s."""
    m = re.fullmatch(r"\s*([-+]?[\d.]+(?:[eE][-+]?\d+)?)\s*pu\s*", text)
    if m:
        return float(m.group(1)) * drive.Omega_0
    return to_si(text, "speed", "--speed")


def _control(name: str, drive: Drive, handoff: float | None = None) -> tuple[Control, float, str]:
    """Return the controller for a --control name, its default reference and what the reference means."""
    if name == "square":
        return SixStep(), drive.motor.I_N, "A"
    if name == "sine":
        ctl = Sine() if handoff is None else Sine(handoff_speed=handoff)
        return ctl, analytic.t_sN(drive), "N m"
    if name == "sixv":
        return SixStepVoltage("high"), 0.5, "duty"
    if name in ("lu", "lu-no-do", "rect"):
        return Lu(method=name), drive.T_N, "N m"
    raise BldclabError("--control", f"must be one of {', '.join(CONTROLS)}, got {name!r}")


def add_inverter_option(p: argparse.ArgumentParser) -> None:
    """Add ``--inverter switching|average`` (overrides the motor file's ``[inverter] model``)."""
    p.add_argument("--inverter", choices=Inverter.MODELS,
                   help="inverter model: switching (every gate edge) or average (half-period averages, faster, "
                        "no PWM ripple); default: the motor file's [inverter] model")


def load_drive(args: argparse.Namespace) -> Drive:
    """Load ``args.motor`` with ``--inverter`` applied."""
    drive = load(args.motor)
    return drive if args.inverter is None else drive.replace(inverter__model=args.inverter)


def _summarise(caught: list[str], runs: int) -> None:
    """Issue one plausibility warning for the many an experiment collected (count and first message)."""
    line = _plaus.summary(caught, runs)
    if line:
        warnings.warn(line, PlausibilityWarning, stacklevel=2)


def _write(out: Path, files: dict[str, bytes]) -> list[Path]:

    return write_files(out, files)


# ---------------------------------------------------------------------------------------------------------------
# simulate


def configure_simulate(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab simulate``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--control", choices=CONTROLS, default="square", help="controller (default square)")
    p.add_argument("--speed", default="0.5 pu",
                   help='imposed speed: "0.5 pu", "300 rpm", "31.4 rad/s" (default 0.5 pu); with --mechanics: the '
                        "rotor starts from standstill and this is ignored")
    p.add_argument("--mechanics", action="store_true", help="rotor dynamics from standstill instead of a dynamometer")
    ref = p.add_mutually_exclusive_group()
    ref.add_argument("--torque", help='torque reference, e.g. "20 N m" (sine, lu, rect)')
    ref.add_argument("--current", help='current reference, e.g. "50 A" (square)')
    ref.add_argument("--duty", type=float, help="duty in [-1, 1] (sixv)")
    p.add_argument("--load", default="0", help='load torque with --mechanics, e.g. "10 N m"')
    p.add_argument("--periods", type=float, default=6.0, help="simulated electrical periods (imposed speed)")
    p.add_argument("--duration", help='simulated time, e.g. "0.2 s" (overrides --periods)')
    p.add_argument("--trace-sub", type=int, default=4, help="trace rows per sample (PWM ripple visible)")
    p.add_argument("--out", type=Path, help="write result.npz, trace.csv, metrics.json (and figures) here")
    p.add_argument("--plot", action="store_true", help="write waveforms.png and .svg (currents, torque, voltages)")
    p.add_argument("--format", choices=("table", "json"), default="table", help="terminal output")
    add_inverter_option(p)


def _reference(args: argparse.Namespace, default: float, unit: str) -> float:
    if args.torque is not None:
        if unit != "N m":
            raise BldclabError("--torque", f"--control {args.control} takes its reference in {unit}")
        return to_si(args.torque, "torque", "--torque")
    if args.current is not None:
        if unit != "A":
            raise BldclabError("--current", f"--control {args.control} takes its reference in {unit}")
        return to_si(args.current, "current", "--current")
    if args.duty is not None:
        if unit != "duty" or not -1.0 <= args.duty <= 1.0 or math.isnan(args.duty):
            raise BldclabError("--duty", f"needs --control sixv and a value in [-1, 1], got {args.duty}")
        return float(args.duty)
    return default


def run_simulate(args: argparse.Namespace) -> int:
    """Run ``bldclab simulate``."""
    drive = load_drive(args)
    if args.trace_sub < 1:
        raise BldclabError("--trace-sub", f"must be >= 1, got {args.trace_sub}")
    ctl, default_ref, unit = _control(args.control, drive)
    ref = _reference(args, default_ref, unit)
    if args.mechanics:
        duration = to_si(args.duration or "0.5 s", "time", "--duration")
        load_t = to_si(args.load, "torque", "--load")
        sc = Scenario(duration=duration, ref=ref, load_torque=load_t, trace_sub=args.trace_sub,
                      window=(0.5 * duration, duration))
        speed = None
    else:
        speed = parse_speed(args.speed, drive)
        if speed == 0:
            raise BldclabError("--speed", "an imposed speed of 0: use --mechanics to start from standstill")
        Te = electrical_period(drive, speed)
        duration = to_si(args.duration, "time", "--duration") if args.duration else args.periods * Te
        if not math.isfinite(duration) or duration <= 0:
            raise BldclabError("--duration", f"must be positive, got {duration}")
        n_meas = min(2.0, max(duration / Te - 1.0, 0.0))
        t0 = duration - n_meas * Te if n_meas >= 1 else 0.5 * duration
        sc = Scenario(duration=duration, speed=speed, ref=ref, trace_sub=args.trace_sub, window=(t0, duration))
    res = simulate(drive, ctl, sc)
    m = res.metrics
    assert m is not None
    summary: dict[str, Any] = {
        "motor": drive.name, "control": args.control, "reference": ref, "reference_unit": unit,
        "inverter": drive.inverter.model,
        "speed_rad_s": m.omega_mean, "speed_pu": m.omega_mean / drive.Omega_0, "window_s": [m.t0, m.t1],
        "tau_mean_N_m": m.tau_mean, "tau_mean_pu": m.tau_mean / drive.T_N, "ripple_N_m": m.ripple,
        "ripple_pwm_averaged_N_m": m.ripple_ma, "ripple_pct_of_mean": 100 * m.ripple / abs(m.tau_mean)
        if m.tau_mean else math.nan, "tau_rms_deviation_N_m": m.tau_std, "efficiency": m.efficiency,
        "p_dc_W": m.p_src, "p_copper_W": m.p_cu, "p_inverter_W": m.p_sw + m.p_diode + m.p_Rsrc,
        "i_rms_A": list(m.i_rms), "i_peak_A": list(m.i_peak), "energy_balance_residue": m.balance_electrical,
        "controller_flags": int(np.bitwise_or.reduce(res.flags.astype(np.int64))) if len(res) else 0,
        "warnings": list(res.meta.get("warnings", [])),
    }
    if args.format == "json":
        print(json.dumps(summary, indent=2))
    else:
        print(f"{drive.name}, {args.control} control, reference {ref:.4g} {unit}, "
              f"{'dynamometer' if speed is not None else 'rotor dynamics'}, {drive.inverter.model} inverter")
        for key, value in summary.items():
            if key in ("motor", "control", "reference", "reference_unit", "inverter", "warnings"):  # warnings: stderr
                continue
            text = ", ".join(f"{v:.4g}" for v in value) if isinstance(value, list) else (
                f"{value:.5g}" if isinstance(value, float) else str(value))
            print(f"  {key:<28} {text}")
    if args.out is not None:
        files: dict[str, bytes] = {}
        buf = io.BytesIO()
        res.to_pandas().to_csv(buf)
        files["trace.csv"] = buf.getvalue()
        files["metrics.json"] = (json.dumps({**summary, "metrics": asdict(m)}, indent=2) + "\n").encode()
        if args.plot:
            fig = res.plot()
            files["waveforms.png"] = plots.figure_bytes(fig, "png")
            files["waveforms.svg"] = plots.figure_bytes(fig, "svg")
        written = _write(args.out, files)
        res.save(args.out / "result.npz")
        for path in [*written, args.out / "result.npz"]:
            print(f"wrote {path}")
    elif args.plot:
        raise BldclabError("--plot", "needs --out DIR to write the figures into")
    return 0


# ---------------------------------------------------------------------------------------------------------------
# compare


def configure_compare(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab compare``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--out", type=Path, help="directory for CSV, figures and the report (default out/<motor>)")
    p.add_argument("--speeds", type=int, default=32, help="speeds per supply (default 32)")
    p.add_argument("--min-speed", type=float, default=0.05, help="lowest speed, p.u. of Omega_0 (default 0.05)")
    p.add_argument("--max-speed", type=float, default=0.98, help="highest speed, p.u. of Omega_0 (default 0.98)")
    p.add_argument("--workers", type=int, default=0, help="processes (default: all cores; 1: serial)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (it is shown on a terminal only)")
    p.add_argument("--no-report", action="store_true", help="do not write report.html (docs/report.md)")
    p.add_argument("--pwm-phases", type=int, default=1,
                   help="PWM-grid phases per point: offsets of the rotor's initial angle within one PWM period; "
                        "points report their mean and range (default 1)")
    add_inverter_option(p)


def run_compare(args: argparse.Namespace) -> int:
    """Run ``bldclab compare``."""
    drive = load_drive(args)
    if args.speeds < 2:
        raise BldclabError("--speeds", f"needs at least 2, got {args.speeds}")
    if not 0 < args.min_speed < args.max_speed < 1.5:
        raise BldclabError("--min-speed", "needs 0 < min-speed < max-speed < 1.5 (p.u. of Omega_0)")
    if args.workers < 0:
        raise BldclabError("--workers", f"must be >= 0, got {args.workers}")
    if args.pwm_phases < 1:
        raise BldclabError("--pwm-phases", f"must be >= 1, got {args.pwm_phases}")
    w = speed_grid(args.speeds, args.min_speed, args.max_speed)
    out = args.out if args.out is not None else Path("out") / drive.name
    res = compare(drive, w, workers=args.workers or None, progress=not args.no_progress and sys.stderr.isatty(),
                  pwm_phases=args.pwm_phases)
    t1 = res.table1
    sim = res.simulated
    print(f"{drive.name}: square-wave (SixStep, I_N = {drive.motor.I_N:g} A) vs sinusoidal (Sine, "
          f"T_sN = {analytic.t_sN(drive):.4g} N m), {args.speeds} speeds x 2 supplies in {res.seconds:.1f} s")
    bs = res.base_speeds.set_index("supply").simulated_pu
    print(f"  Theta_m {t1.Theta_m * 1e3:.2f} mrad; base speed (21) sine {t1.Omega_sB_pu:.3f} p.u., (30) square "
          f"{t1.Omega_qB_pu:.3f} p.u.; with R: {t1.Omega_sB_R_pu:.3f} / {t1.Omega_qB_R_pu:.3f} p.u.; simulated: "
          f"{bs['sine']:.3f} / {bs['square']:.3f} p.u.")
    na = "*" if res.not_applicable else ""  # closed-form columns outside paper 1's premises: labelled, kept
    print(f"  {'Omega':>6} {'T sine':>7} {'T sq':>6} {'(13)/(24)' + na:>10} {'(26)-(32)' + na:>10} | {'TR sine':>7} "
          f"{'sw':>6} {'(15)/(25)' + na:>10} | {'TR sq':>6} {'sw':>6} {'(27)-(33)' + na:>10} | {'eta sine':>8} "
          f"{'eta sq':>6}")
    an = res.analytic.set_index("Omega_pu")
    for wp in w[:: max(1, len(w) // 12)]:
        a = sim[(sim.supply == "sine") & (sim.Omega_pu == wp)].iloc[0]
        b = sim[(sim.supply == "square") & (sim.Omega_pu == wp)].iloc[0]
        r = an.loc[wp]
        print(f"  {wp:>6.3f} {a.T_pu:>7.3f} {b.T_pu:>6.3f} {r.T_s_pu:>10.3f} {r.T_q_pu:>10.3f} | {a.TR_avg_pu:>7.3f} "
              f"{a.TR_ma_pu:>6.3f} {r.TR_s_pu:>10.3f} | {b.TR_avg_pu:>6.3f} {b.TR_ma_pu:>6.3f} {r.TR_q_pu:>10.3f} | "
              f"{a.eta:>8.3f} {b.eta:>6.3f}")
    print(f"  (p.u. of Omega_0, T_N; T: mean torque, {drive.inverter.model} inverter; TR: torque ripple peak to peak "
          "on the averaged inverter (no PWM, the paper-comparable one), sw: the switching drive's, of its "
          "one-PWM-period average; (13)-(33): paper 1, R neglected)")
    if args.pwm_phases > 1:
        spread = {k: float((sim[f"{k}_max"] - sim[f"{k}_min"]).max()) for k in ("T_pu", "TR_pu", "TR_ma_pu")}
        print(f"  over {args.pwm_phases} PWM-grid phases the largest spread is {spread['T_pu']:.4f} p.u. in torque, "
              f"{spread['TR_pu']:.4f} in ripple at the samples, {spread['TR_ma_pu']:.4f} in ripple_ma")
    if res.not_applicable:
        print("  * not applicable to this drive (paper 1's closed forms, shown for reference), because:")
        for reason in res.not_applicable:
            print(f"    - {reason}")
    print("verdict:")
    for line in res.verdict:
        print(f"  - {line}")
    files = compare_files(res)
    files.update(compare_outputs(res, files, command=compare_command(args, out), motor_source=args.motor,
                                 report=not args.no_report))
    for path in _write(out, files):
        print(f"wrote {path}")
    return 0


# ---------------------------------------------------------------------------------------------------------------
# torque-control (paper 2)


def configure_torque_control(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab torque-control``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file (e.g. lu-4kw)")
    p.add_argument("--torques", default="25%,50%,100%",
                   help='torque references: percentages of T_N or torques, comma separated (default "25%%,50%%,100%%")')
    p.add_argument("--speeds", default="",
                   help='imposed speeds, comma separated ("1000 rpm,3000 rpm" or "0.5 pu"); default 1/3, 2/3, 1 of '
                        "the rated speed")
    p.add_argument("--methods", default="rect,lu-no-do,lu", help="methods among rect, lu-no-do, lu")
    p.add_argument("--out", type=Path, help="write methods.csv and paper 2's Figs 10-12 here")
    add_inverter_option(p)


def _list(text: str, parse: Any, field: str) -> list[float]:
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        raise BldclabError(field, "needs at least one value")
    return [parse(t) for t in items]


def run_torque_control(args: argparse.Namespace) -> int:
    """Run ``bldclab torque-control``: paper 2's methods compared over a load x speed grid."""
    drive = load_drive(args)

    def torque(t: str) -> float:
        if t.endswith("%"):
            try:
                return float(t[:-1]) / 100.0 * drive.T_N
            except ValueError:
                raise BldclabError("--torques", f"cannot read {t!r}") from None
        return to_si(t, "torque", "--torques")

    torques = _list(args.torques, torque, "--torques")
    if args.speeds:
        speeds = _list(args.speeds, lambda t: parse_speed(t, drive), "--speeds")
    else:
        speeds = list(paper2.default_grid(drive)[1])
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    with _plaus.collect() as caught:
        table = paper2.compare_methods(drive, torques, speeds, methods)
    _summarise(caught, len(table))
    print(f"{drive.name}: torque control methods (paper 2); ripple in % of the mean torque, dip of the "
          "non-commutated current")
    cols = ["method", "torque_pct", "speed_rpm", "tau_mean_pct_ref", "dcm_pct", "ripple_pp", "ripple_rms",
            "ripple_ma_pp", "ripple_ma_rms", "dip_A", "dip_pct"]
    shown = table.assign(dcm_pct=100.0 * table["dcm_share"])
    print(shown[cols].to_string(index=False, float_format=lambda v: f"{v:.2f}"))
    print("  (tau_mean_pct_ref: mean torque in % of the reference; dcm_pct: % of the time without phase current, "
          "discontinuous conduction within the PWM period)")
    for _, row in table.iterrows():
        cause = paper2.shortfall_cause(row)
        if cause is not None:
            print(f"warning: {row['method']} at {row['torque_pct']:.0f} % of T_N, {row['speed_rpm']:.0f} rpm: {cause}",
                  file=sys.stderr)
    if args.out is not None:
        files = {"methods.csv": table.to_csv(index=False).encode()}
        tq, om = max(torques), max(speeds)
        for name, fn in (("fig10_rect", paper2.fig10), ("fig11_lu_no_do", paper2.fig11), ("fig12_lu", paper2.fig12),
                         ("methods_compared", paper2.fig_compare)):
            fig = fn(drive, tq, om)
            files[f"{name}.png"] = plots.figure_bytes(fig, "png")
            files[f"{name}.svg"] = plots.figure_bytes(fig, "svg")
        for path in _write(args.out, files):
            print(f"wrote {path}")
    return 0


# ---------------------------------------------------------------------------------------------------------------
# faults


def configure_faults(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab faults``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--control", choices=("square", "sine", "lu"), default="square", help="controller")
    p.add_argument("--speed", default="0.5 pu", help='imposed speed (default "0.5 pu")')
    p.add_argument("--out", type=Path, help="write faults.csv here")


def run_faults(args: argparse.Namespace) -> int:
    """Run ``bldclab faults``: each injected fault, detection, time to the safe state, peak current."""
    drive = load(args.motor)
    speed = parse_speed(args.speed, drive)
    ctl, ref, _ = _control(args.control, drive, handoff=0.02 * drive.Omega_0)
    i_max = float(getattr(ctl, "i_max", None) or 2.0 * drive.motor.I_N)
    if args.control == "lu" and getattr(ctl, "i_max", None) is None:
        i_max = 3.0 * drive.motor.I_N
    with _plaus.collect() as caught:
        table = fault_table(drive, ctl, ref, speed, i_max=i_max)
    _summarise(caught, len(table))
    trip = f", hardware trip {drive.inverter.i_trip:g} A" if drive.inverter.i_trip > 0 else ", no hardware trip"
    print(f"{drive.name}, {args.control} control at {speed / drive.Omega_0:.2f} p.u.: firmware over-current trip "
          f"{i_max:g} A{trip}; times from the fault in ms")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    if args.out is not None:
        for path in _write(args.out, {"faults.csv": table.to_csv(index=False).encode()}):
            print(f"wrote {path}")
    return 0

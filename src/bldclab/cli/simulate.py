"""``bldclab simulate``: one switching-level simulation of a drive under a controller named on the command line."""

from __future__ import annotations

import argparse
import io
import json
import math
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from .._files import write_files
from ..analysis.experiments import electrical_period
from ..errors import BldclabError
from ..model.units import to_si
from ..report import plots
from ..sim import Scenario, simulate
from .common import CONTROLS, add_inverter_option, control_of, load_drive, parse_speed

__all__ = ["configure_command", "run_command"]


def configure_command(p: argparse.ArgumentParser) -> None:
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


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab simulate``."""
    drive = load_drive(args)
    if args.trace_sub < 1:
        raise BldclabError("--trace-sub", f"must be >= 1, got {args.trace_sub}")
    ctl, default_ref, unit = control_of(args.control, drive)
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
        "p_dc_W": m.p_src_total, "p_copper_W": m.p_cu,
        "p_inverter_W": m.p_sw + m.p_diode + m.p_Rsrc + m.p_swloss + m.p_rr,
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
        written = write_files(args.out, files)
        res.save(args.out / "result.npz")
        for path in [*written, args.out / "result.npz"]:
            print(f"wrote {path}")
    elif args.plot:
        raise BldclabError("--plot", "needs --out DIR to write the figures into")
    return 0



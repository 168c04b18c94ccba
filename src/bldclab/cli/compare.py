"""``bldclab compare``: square-wave vs sinusoidal supply over speed, closed forms beside simulation (paper 1)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from .._files import write_files
from ..analysis.compare import CompareResult, compare, default_controls, speed_grid
from ..control.sixstep import CHOPPINGS
from ..errors import BldclabError
from ..model import analytic
from ..model.limits import TOP_SPEED_PU
from ..model.motor import Drive
from ..report.bundle import compare_command, compare_directory, runs_text
from ..report.plots import load_matplotlib
from .common import (
    add_inverter_option,
    add_verbose_option,
    check_speed_range,
    load_drive,
    positive_int,
    summarise,
    worker_pool,
    workers_of,
)
from .paths import check_out_dir

__all__ = ["configure_command", "run_command"]

RPM_PER_RAD_S = 30.0 / math.pi


def configure_command(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab compare``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--out", type=Path, help="directory for CSV, figures and the report (default out/<motor>)")
    p.add_argument("--speeds", type=int, default=32, help="speeds per supply (default 32)")
    p.add_argument("--min-speed", type=float, default=0.05, help="lowest speed, p.u. of Omega_0 (default 0.05)")
    p.add_argument("--max-speed", type=float, default=TOP_SPEED_PU,
                   help=f"highest speed, p.u. of Omega_0 (default {TOP_SPEED_PU:g})")
    p.add_argument("--workers", type=positive_int, help="processes, >= 1 (default: all cores; 1: serial)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (it is shown on a terminal only)")
    p.add_argument("--no-report", action="store_true", help="do not write report.html (docs/report.md)")
    p.add_argument("--pwm-phases", type=int, default=1,
                   help="PWM-grid phases per point: offsets of the rotor's initial angle within one PWM period; "
                        "points report their mean and range (default 1)")
    p.add_argument("--chopping", choices=CHOPPINGS, default="pwm-on-pwm",
                   help="square-wave supply's chopping pattern (default pwm-on-pwm; sync: the positive leg "
                        "complementary, no freewheeling through a diode in the off-time)")
    add_inverter_option(p)
    add_verbose_option(p)


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab compare``."""
    drive = load_drive(args)
    if args.speeds < 2:
        raise BldclabError("--speeds", f"needs at least 2, got {args.speeds}")
    check_speed_range(args.min_speed, args.max_speed)
    if args.pwm_phases < 1:
        raise BldclabError("--pwm-phases", f"must be >= 1, got {args.pwm_phases}")
    w = speed_grid(args.speeds, args.min_speed, args.max_speed)
    out = args.out if args.out is not None else Path("out") / drive.name
    check_out_dir(out)  # before the simulations: a bad --out fails in a second, not after the whole run
    workers = workers_of(args.workers)
    load_matplotlib()  # before the pool starts: its workers draw the figures with it already loaded
    with worker_pool(workers) as pool:  # the points, then paper 1's figures and the waveforms, and the drawing
        res = compare(drive, w, workers=workers, executor=pool,
                      progress=not args.no_progress and sys.stderr.isatty(), pwm_phases=args.pwm_phases,
                      controls=default_controls(drive, min(w), args.chopping), summarise=False)
        _print(args, drive, w, res)
        files = compare_directory(res, command=compare_command(args, out), motor_source=args.motor,
                                  report=not args.no_report, executor=pool)
    for path in write_files(out, files):
        print(f"wrote {path}")
    # one line for every run: the points, the waveforms and paper 1's figures (manifest.json lists them all)
    summarise(res.warnings, runs_text(res, figures=True), args.verbose)
    return 0


def _print(args: argparse.Namespace, drive: Drive, w: list[float], res: CompareResult) -> None:
    """Print the comparison: the heading, one line per speed, the notes and the verdict."""
    t1 = res.table1
    sim = res.simulated
    chop = "" if args.chopping == "pwm-on-pwm" else f", {args.chopping} chopping"
    print(f"{drive.name}: square-wave (SixStep{chop}, I_N = {drive.motor.I_N:g} A) vs sinusoidal (Sine, "
          f"T_sN = {analytic.t_sN(drive):.4g} N m), {args.speeds} speeds x 2 supplies in {res.seconds:.1f} s; "
          f"Omega_0 = {drive.Omega_0:.4g} rad/s = {drive.Omega_0 * RPM_PER_RAD_S:.4g} rpm")
    print(f"  {res.comparison}")
    bs = {} if res.base_speeds is None else res.base_speeds.set_index("supply").simulated_pu.to_dict()
    print(f"  Theta_m {t1.Theta_m * 1e3:.2f} mrad; base speed (21) sine {t1.Omega_sB_pu:.3f} p.u., (30) square "
          f"{t1.Omega_qB_pu:.3f} p.u.; with R: {t1.Omega_sB_R_pu:.3f} / {t1.Omega_qB_R_pu:.3f} p.u.; simulated: "
          f"{bs.get('sine', math.nan):.3f} / {bs.get('square', math.nan):.3f} p.u.")
    na = "*" if res.not_applicable else ""  # closed-form columns outside paper 1's premises: labelled, kept
    print(f"  {'Omega':>6} {'rpm':>6} {'T sine':>7} {'T sq':>6} {'(13)/(24)' + na:>10} {'(26)-(32)' + na:>10} | "
          f"{'TR sine':>7} {'sw':>6} {'(15)/(25)' + na:>10} | {'TR sq':>6} {'ctrl':>6} {'sw':>6} "
          f"{'(27)-(33)' + na:>10} | "
          f"{'eta sine':>8} {'eta sq':>6}")
    an = res.analytic.set_index("Omega_pu")
    for wp in w:  # every speed of the heading
        a = sim[(sim.supply == "sine") & (sim.Omega_pu == wp)].iloc[0]
        b = sim[(sim.supply == "square") & (sim.Omega_pu == wp)].iloc[0]
        r = an.loc[wp]
        rpm = wp * drive.Omega_0 * RPM_PER_RAD_S
        print(f"  {wp:>6.3f} {rpm:>6.0f} {a.T_pu:>7.3f} {b.T_pu:>6.3f} {r.T_s_pu:>10.3f} {r.T_q_pu:>10.3f} | "
              f"{a.TR_avg_pu:>7.3f} {a.TR_ma_pu:>6.3f} {r.TR_s_pu:>10.3f} | "
              f"{b.TR_avg_pu:>6.3f} {b.TR_avg_ctrl_pu:>6.3f} {b.TR_ma_pu:>6.3f} {r.TR_q_pu:>10.3f} | "
              f"{a.eta:>8.3f} {b.eta:>6.3f}")
    print("  (p.u. of Omega_0, T_N; rpm: the speed in rpm; "
          f"T: mean torque, {drive.inverter.model} inverter; TR: torque ripple peak to peak "
          "on the averaged inverter (no PWM, the paper-comparable one; square wave: paper 1's ideal current limiter), "
          "ctrl: the square-wave controller's own on the averaged inverter, sw: the switching drive's, of its "
          "one-PWM-period average; (13)-(33): paper 1, R neglected)")
    print(f"  {res.commutation}")
    if args.pwm_phases > 1:
        spread = {k: float((sim[f"{k}_max"] - sim[f"{k}_min"]).max()) for k in ("T_pu", "TR_pu", "TR_ma_pu")}
        print(f"  over {args.pwm_phases} PWM-grid phases the largest spread is {spread['T_pu']:.4f} p.u. in torque, "
              f"{spread['TR_pu']:.4f} in ripple at the samples, {spread['TR_ma_pu']:.4f} in ripple_ma")
    if res.not_applicable:
        print("  * not applicable to this drive (paper 1's closed forms, shown for reference), because:")
        for reason in res.not_applicable:
            print(f"    - {reason}")
    head, *detail = res.verdict
    print(head if head.startswith("bottom line") else f"  - {head}")
    print("verdict in detail:")
    for line in detail:
        print(f"  - {line}")

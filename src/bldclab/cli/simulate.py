"""``bldclab simulate``: one switching-level simulation of a drive under a controller named on the command line."""

from __future__ import annotations

import argparse
import difflib
import io
import math
import sys
import time
import tomllib
import warnings
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any, cast

from .._core import decode_flags
from .._files import json_text, write_files
from ..analysis.experiments import electrical_period
from ..control import Control, Sine, SixStep
from ..control.sixstep import COMMUTATIONS as SIXSTEP_COMMUTATIONS
from ..control.sixstep import REGULATIONS as SIXSTEP_REGULATIONS
from ..control.user import UserControl
from ..errors import BldclabError, PlausibilityError, PlausibilityWarning
from ..model.units import to_si
from ..report import plots
from ..sim import CHUNK, TRACE_LIMIT, Piecewise, Scenario, parse_profile, samples_of, simulate, trace_bytes, trace_rows
from .common import CONTROLS, add_inverter_option, control_of, load_drive, load_estimate, parse_speed
from .paths import check_out_dir

__all__ = ["configure_command", "run_command"]

#: Largest trace (bytes) ``simulate`` keeps; beyond, it asks for --trace-every or --no-trace before running

_RPM = 60.0 / (2.0 * math.pi)

_PROFILE_HELP = ('; or a piecewise-linear profile of "time: value" points, e.g. "0 s: 0 {u}, 0.1 s: {v} {u}" '
                 "(linear between points, constant after the last; repeat a time for a step)")


def configure_command(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab simulate``."""
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file")
    p.add_argument("--control", default="square",
                   help=f"controller: {', '.join(CONTROLS)} (default square), or the path of your controller's "
                        "library (./my.so, from 'bldclab controller build')")
    user = p.add_argument_group("your controller (--control ./my.so: bldclab.UserControl, docs/user-controller.md)")
    user.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                      help="a parameter member by name: a number, a named constant, or comma-separated numbers for "
                           "an array (repeat for each; 'bldclab controller describe LIB' lists them)")
    user.add_argument("--params", type=Path, metavar="FILE.toml",
                      help="parameters from a TOML file (KEY = VALUE lines, tables for nested structs); --param "
                           "overrides them")
    user.add_argument("--ref", type=float, help="the reference, in the unit the controller states (default 0)")
    user.add_argument("--in-process", action="store_true",
                      help="run it in this process (default: a watched child process, so that a crash or a hang "
                           "is reported instead of ending bldclab)")
    user.add_argument("--budget", type=float, default=1.0, metavar="SECONDS",
                      help="step-time budget: a call into the controller that takes longer is a hang (default 1)")
    p.add_argument("--speed",
                   help='imposed speed (a dynamometer holds the rotor): "0.5 pu", "300 rpm", "31.4 rad/s" '
                        "(default 0.5 pu)" + _PROFILE_HELP.format(u="rpm", v=1000) + "; not with --mechanics")
    p.add_argument("--mechanics", action="store_true",
                   help="rotor dynamics from standstill (the drive's inertia and friction, --load) instead of a "
                        "dynamometer")
    ref = p.add_mutually_exclusive_group()
    ref.add_argument("--torque", help='torque reference, e.g. "20 N m" (sine, lu, rect)')
    ref.add_argument("--current", help='current reference, e.g. "50 A" (square)')
    ref.add_argument("--duty", type=float, help="duty in [-1, 1] (sixv; square with --regulation duty)")
    six = p.add_argument_group("six-step settings (--control square: bldclab.SixStep, docs/sixstep.md)")
    six.add_argument("--regulation", choices=SIXSTEP_REGULATIONS,
                     help="current regulation (default predictive); duty: no current loop, the reference is the duty "
                          "(an ESC's throttle; give it with --duty, default 0.5); ideal: paper 1's ideal current "
                          "limiter (averaged inverter only)")
    six.add_argument("--timed", action="store_true",
                     help="commutate at the predicted instant inside the PWM period (an ESC's commutation timer), "
                          "not at the sample nearest it")
    six.add_argument("--timing", metavar="ANGLE",
                     help='timing advance, electrical: "15 deg" (or rad); with --timing-time at most 30 deg')
    six.add_argument("--timing-time", metavar="TIME",
                     help='timing advance per speed, "20 us": the advance grows by |Omega_e| times it')
    six.add_argument("--commutation", choices=SIXSTEP_COMMUTATIONS,
                     help="where the commutation instants come from (default hall; encoder: the exact angle, the "
                          "ideal commutation)")
    sine = p.add_argument_group("sinusoidal settings (--control sine: bldclab.Sine, docs/sine.md, "
                                "docs/sensorless-sine.md)")
    sine.add_argument("--angle", choices=("hall", "pll", "encoder", "observer"),
                      help="angle of the d,q transforms (default hall); observer: sensorless, a rotor-angle observer "
                           "with an I/f start-up (use with --mechanics and --speed-ref)")
    sine.add_argument("--observer", choices=("flux", "reduced"),
                      help="with --angle observer: the nonlinear flux observer with a PLL (default flux) or the "
                           "reduced-order observer")
    p.add_argument("--speed-ref",
                   help='speed reference for a speed loop (--control sine with --mechanics; the loop sets the '
                        'torque): "1000 rpm", "0.5 pu"' + _PROFILE_HELP.format(u="rpm", v=1000))
    p.add_argument("--load", help='load torque, needs --mechanics: "10 N m"' + _PROFILE_HELP.format(u="N m", v=10))
    p.add_argument("--periods", type=float,
                   help="simulated electrical periods at the imposed speed (default 6; not with --mechanics)")
    p.add_argument("--duration", help='simulated time, e.g. "0.2 s" (overrides --periods; default with '
                                      "--mechanics or a --speed profile: 0.5 s)")
    trace = p.add_mutually_exclusive_group()
    trace.add_argument("--trace-sub", type=int,
                       help="trace rows per sample, to see the PWM ripple (default 4, or 1 with --trace-every)")
    trace.add_argument("--trace-every", type=int, metavar="N",
                       help="keep one trace row per N samples (long runs: bounded memory; metrics still cover "
                            "every sample)")
    trace.add_argument("--no-trace", action="store_true", help="keep no trace: metrics only, least memory")
    p.add_argument("--progress", action="store_true",
                   help="show a progress line on stderr (default: on a terminal, for runs over ~10 s wall time)")
    p.add_argument("--out", type=Path, help="write result.npz, trace.csv, metrics.json (and figures) here")
    p.add_argument("--plot", action="store_true",
                   help="write waveforms.png and .svg (phase currents, torque, back-EMFs; speed with "
                        "--mechanics), needs --out")
    p.add_argument("--format", choices=("table", "json"), default="table", help="terminal output")
    p.add_argument("--estimate", metavar="MOTOR",
                   help="the drive data the controller is configured from (built-in name or motor TOML file, e.g. "
                        "the file `bldclab commission --out` writes); the plant stays MOTOR (default: MOTOR's own)")
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
            raise BldclabError("--duty", f"needs --control sixv (or square with --regulation duty) and a value in "
                               f"[-1, 1], got {args.duty}")
        return float(args.duty)
    return default


#: The six-step settings on the command line: option, attribute of the parsed arguments.
_SIXSTEP_OPTIONS = (("--regulation", "regulation"), ("--timed", "timed"), ("--timing", "timing"),
                    ("--timing-time", "timing_time"), ("--commutation", "commutation"))


def _sixstep(args: argparse.Namespace, ctl: Control) -> Control:
    """Return ``SixStep`` with the six-step settings of the command line (each read as the option it came from)."""
    if not isinstance(ctl, SixStep):
        return ctl
    kw: dict[str, Any] = {}
    for option, attr in _SIXSTEP_OPTIONS:
        value = getattr(args, attr)
        if value is None or value is False:
            continue
        if attr == "timing":
            value = to_si(value, "angle", option)
        elif attr == "timing_time":
            value = to_si(value, "time", option)
        kw[attr] = value
    try:
        return replace(ctl, **kw)
    except BldclabError as exc:  # SixStep's own check (an advance above 30 deg, ...): name the option
        option = next((o for o, a in _SIXSTEP_OPTIONS if exc.field == f"control.{a}"), exc.field)
        raise BldclabError(option, exc.problem) from None


def _sine(args: argparse.Namespace, ctl: Control) -> Control:
    """Return ``Sine`` with the sinusoidal settings of the command line."""
    if not isinstance(ctl, Sine):
        return ctl
    kw: dict[str, Any] = {}
    if args.angle is not None:
        kw["angle"] = args.angle
    if args.observer is not None:
        kw["observer"] = args.observer
    return replace(ctl, **kw) if kw else ctl


def is_library(control: str) -> bool:
    """Return whether a ``--control`` value names a user controller's library (a path) rather than a built-in."""
    return control not in CONTROLS and ("/" in control or "\\" in control or control.endswith((".so", ".dylib",
                                                                                               ".dll")))


def parse_params(items: list[str]) -> dict[str, Any]:
    """Read ``--param KEY=VALUE`` items: numbers, named constants, comma-separated numbers for arrays."""
    out: dict[str, Any] = {}

    def one(text: str) -> Any:
        t = text.strip()
        for kind in (int, float):
            try:
                return kind(t)
            except ValueError:
                pass
        return t

    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise BldclabError("--param", f"expected KEY=VALUE (e.g. kp=0.5), got {item!r}")
        if key.strip() in out:
            raise BldclabError("--param", f"{key.strip()} given twice")
        out[key.strip()] = [one(v) for v in value.split(",")] if "," in value else one(value)
    return out


def _user_control(args: argparse.Namespace) -> UserControl:
    """Return the user controller of ``--control PATH --param ...`` (errors naming the option)."""
    try:
        params: dict[str, Any] = {}
        if args.params is not None:
            try:
                params = tomllib.loads(args.params.read_text())
            except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
                raise BldclabError("--params", f"cannot read {args.params}: {exc}") from None
        params.update(parse_params(args.param))
        return UserControl(args.control, params, isolate=not args.in_process, budget=args.budget)
    except BldclabError as exc:
        if exc.field.startswith("control.params."):
            raise BldclabError(f"--param {exc.field.removeprefix('control.params.')}", exc.problem) from None
        if exc.field.startswith("control.params"):
            raise BldclabError("--param", exc.problem) from None
        if exc.field == "control.budget":
            raise BldclabError("--budget", exc.problem) from None
        if exc.field.startswith("control.library"):
            raise BldclabError("--control", f"{args.control}: {exc.problem}") from None
        raise


def _check_options(args: argparse.Namespace) -> None:
    """Refuse option combinations before any work (each error names the option typed)."""
    user = is_library(args.control)
    if not user and args.control not in CONTROLS:
        close = difflib.get_close_matches(args.control, CONTROLS, n=1)
        near = f": did you mean {close[0]!r}?" if close else ""
        raise BldclabError("--control", f"invalid choice: {args.control!r}{near} (one of {', '.join(CONTROLS)}, or "
                           "the path of your controller's library, ./my.so)")
    for option, given in (("--param", bool(args.param)), ("--params", args.params is not None),
                          ("--ref", args.ref is not None),
                          ("--in-process", args.in_process)):
        if given and not user:
            raise BldclabError(option, f"is a setting of your own controller: it needs --control ./my.so, got "
                               f"--control {args.control}")
    if user:
        for option, value in (("--torque", args.torque), ("--current", args.current), ("--duty", args.duty)):
            if value is not None:
                raise BldclabError(option, "your controller takes its reference with --ref (in the unit it states)")
    for option, value in (("--angle", args.angle), ("--observer", args.observer)):
        if value is not None and args.control != "sine":
            raise BldclabError(option, f"is a sinusoidal setting: it needs --control sine, got --control "
                               f"{args.control}")
    if args.observer is not None and args.angle != "observer":
        raise BldclabError("--observer", "chooses the rotor-angle observer: it needs --angle observer")
    for option, attr in _SIXSTEP_OPTIONS:
        if getattr(args, attr) not in (None, False) and args.control != "square":
            raise BldclabError(option, f"is a six-step setting: it needs --control square, got --control "
                               f"{args.control}")
    check_out_dir(args.out)  # before the run: a bad --out fails at once, not after the simulation
    if args.plot and args.out is None:
        raise BldclabError("--plot", "needs --out DIR to write the figures into")
    if args.plot and args.no_trace:
        raise BldclabError("--plot", "draws the trace: drop --no-trace (or thin it with --trace-every)")
    if args.mechanics:
        if args.speed is not None:
            raise BldclabError("--speed", "is the dynamometer's imposed speed; with --mechanics the rotor follows "
                               "its dynamics from standstill: drop one of them")
        if args.periods is not None:
            raise BldclabError("--periods", "counts electrical periods at an imposed speed; with --mechanics give "
                               "--duration")
    elif args.load is not None:
        raise BldclabError("--load", "needs --mechanics (with an imposed speed the dynamometer takes any load)")
    if args.speed_ref is not None:
        if args.control != "sine" or not args.mechanics:
            raise BldclabError("--speed-ref", "needs --control sine and --mechanics (the speed loop of the "
                               "sinusoidal controller drives the rotor's own dynamics)")
        if args.torque is not None:
            raise BldclabError("--speed-ref", "the speed loop sets the torque: drop --torque")
    if args.periods is not None and not (math.isfinite(args.periods) and args.periods > 0):
        raise BldclabError("--periods", f"must be a positive number of electrical periods, got {args.periods:g}")
    for opt, v in (("--trace-sub", args.trace_sub), ("--trace-every", args.trace_every)):
        if v is not None and v < 1:
            raise BldclabError(opt, f"must be an integer >= 1, got {v}")


def _speed(text: str, drive: Any, option: str) -> float:
    """Read one speed (:func:`~bldclab.cli.common.parse_speed`: pu, rpm, rad/s), errors naming ``option``."""
    try:
        return parse_speed(text, drive)
    except BldclabError as exc:
        raise BldclabError(option, exc.problem) from None


def _final(profile: float | Piecewise) -> float:
    return profile.values[-1] if isinstance(profile, Piecewise) else profile


def _scenario(args: argparse.Namespace, drive: Any, ref: float) -> Scenario:
    trace_kw: dict[str, Any] = {"trace": not args.no_trace}
    if args.trace_every is not None:
        trace_kw["trace_every"] = args.trace_every
    elif not args.no_trace:
        trace_kw["trace_sub"] = 4 if args.trace_sub is None else args.trace_sub
    given: float | None = None
    if args.duration is not None:
        given = to_si(args.duration, "time", "--duration")
        if not (math.isfinite(given) and given > 0):
            raise BldclabError("--duration", f"must be positive, got {args.duration!r}")
    if args.mechanics:
        duration = given if given is not None else 0.5
        load = parse_profile(args.load or "0", "torque", "--load")
        w_ref = 0.0 if args.speed_ref is None else parse_profile(args.speed_ref, "speed", "--speed-ref",
                                                                 convert=lambda v: _speed(v, drive, "--speed-ref"))
        return Scenario(duration=duration, ref=ref, omega_ref=w_ref, load_torque=load,
                        window=(0.5 * duration, duration), **trace_kw)
    speed = parse_profile(args.speed or "0.5 pu", "speed", "--speed",
                          convert=lambda v: _speed(v, drive, "--speed"))
    w_end = _final(speed)
    if w_end == 0:
        raise BldclabError("--speed", "an imposed speed of 0 at the end of the run: use --mechanics to start from "
                           "standstill")
    Te = electrical_period(drive, w_end)
    if given is not None:
        duration = given
    elif isinstance(speed, Piecewise):
        duration = max(0.5, speed.times[-1] + 2 * Te)
    else:
        duration = (6.0 if args.periods is None else args.periods) * Te
    n_meas = min(2.0, max(duration / Te - 1.0, 0.0))
    t0 = duration - n_meas * Te if n_meas >= 1 else 0.5 * duration
    if isinstance(speed, Piecewise):  # measure after the profile's last point when the run leaves room
        t0 = max(t0, min(speed.times[-1], 0.5 * duration))
    return Scenario(duration=duration, speed=speed, ref=ref, window=(t0, duration), **trace_kw)


class _Progress:
    """A progress line on stderr, redrawn in place: shown when asked, or on a terminal for a long run."""

    NOTE_S = 60.0  # off a terminal (a log, CI), a run expected to take longer says so once

    def __init__(self, forced: bool, total_s: float) -> None:
        self.forced, self.total_s = forced, total_s
        self.start = time.monotonic()
        self.shown = False
        self.noted = False
        self.drawn = -math.inf

    def __call__(self, done: int, total: int) -> None:
        elapsed = time.monotonic() - self.start
        if not self.shown:
            # on a terminal, only when the run is going to take a while (extrapolated from the first pieces)
            eta = elapsed * total / max(done, 1)
            tty = sys.stderr.isatty()
            if not self.forced and not tty and not self.noted and eta > self.NOTE_S and done < total:
                self.noted = True
                sys.stderr.write(f"bldclab: note: {self.total_s:.4g} s to simulate will take about "
                                 f"{_fmt_duration(eta)} at this rate ({self.total_s * done / total / elapsed:.3g} "
                                 "simulated s per s); --progress shows its progress\n")
                sys.stderr.flush()
            if not (self.forced or (tty and eta > 10.0)):
                return
            self.shown = True
        if done < total and elapsed - self.drawn < 0.25:  # redraw four times a second at most
            return
        self.drawn = elapsed
        end = "\n" if done == total else ""
        sys.stderr.write(f"\rsimulating {100.0 * done / total:5.1f} % ({self.total_s * done / total:.4g} of "
                         f"{self.total_s:.4g} s simulated, {elapsed:.0f} s elapsed){end}")
        sys.stderr.flush()


def _show(caught: list[warnings.WarningMessage]) -> None:
    """Issue again the warnings recorded during a run (the program shows plausibility warnings as one line each)."""
    for w in caught:
        if issubclass(w.category, PlausibilityWarning):
            warnings.warn(str(w.message), PlausibilityWarning, stacklevel=2)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


def _fmt_duration(s: float) -> str:
    """Return a wall time as ``"3.2 min"``, ``"5.1 h"`` or ``"12 days"``."""
    for unit, size in (("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if s >= size:
            return f"{s / size:.2g} {unit}"
    return f"{s:.2g} s"


def _fmt_bytes(b: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if b < 1000 or unit == "TB":
            return f"{b:.3g} {unit}"
        b /= 1000.0
    return ""  # unreachable


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab simulate``."""
    _check_options(args)
    drive = load_drive(args)
    estimate = load_estimate(args.estimate, drive, "--estimate")
    if is_library(args.control):
        ctl: Control = _user_control(args)
        ref, unit = (0.0 if args.ref is None else args.ref), (ctl.ref_meaning or "-")
        if not math.isfinite(ref):
            raise BldclabError("--ref", f"must be finite, got {args.ref}")
    else:
        ctl, default_ref, unit = control_of(args.control, drive)
        ctl = _sine(args, _sixstep(args, ctl))
        if isinstance(ctl, SixStep) and ctl.regulation == "duty":  # no current loop: the reference is the duty
            default_ref, unit = 0.5, "duty"
        ref = _reference(args, default_ref, unit)
    if args.speed_ref is not None and isinstance(ctl, Sine):  # --speed-ref: --control sine, checked above
        ctl = replace(ctl, speed_loop=True)
    sc = _scenario(args, drive, ref)
    need = trace_bytes(drive, sc)
    if need > TRACE_LIMIT:
        opt = "--duration" if args.duration is not None else "--periods"
        raise BldclabError(opt, f"a run of {sc.duration:.4g} s keeps a trace of {trace_rows(drive, sc)} rows, "
                           f"{_fmt_bytes(need)} (limit {_fmt_bytes(TRACE_LIMIT)}): thin it with --trace-every N or "
                           "drop it with --no-trace")
    n = samples_of(drive, sc.duration)
    progress = _Progress(args.progress, sc.duration) if (args.progress or n > 4 * CHUNK) else None
    with warnings.catch_warnings(record=True) as caught:  # shown after the run: a failed run's cause is in its error
        warnings.simplefilter("always", PlausibilityWarning)
        try:
            res = simulate(drive, ctl, sc, progress=progress, estimate=estimate)
        except PlausibilityError as exc:
            _show([w for w in caught if str(w.message) not in str(exc)])  # what the error leads with: not again
            raise
    _show(caught)
    m = res.metrics
    assert m is not None  # the window ends with the run
    flags = int(res.meta["controller_flags"])
    speed_loop = args.speed_ref is not None
    if speed_loop:  # the loop's reference is the speed; Scenario.ref is not used
        assert isinstance(ctl, Sine)
        ref_text, limit = args.speed_ref, ctl.torque_limit(drive)
        reference: dict[str, Any] = {"reference": ref_text, "reference_unit": "speed (as given)",
                                     "torque_limit_N_m": limit}
        w_end = _final(cast("float | Piecewise", sc.omega_ref))  # a bare number is rad/s: say what it was given
        heading = (f"speed reference {ref_text} (final {w_end:.4g} rad/s = {w_end * _RPM:.4g} rpm = "
                   f"{w_end / drive.Omega_0:.3g} pu; speed loop; torque up to {limit:.4g} N m)")
    else:
        reference = {"reference": ref, "reference_unit": unit}
        heading = f"reference {ref:.4g} {unit}"
    summary: dict[str, Any] = {
        "motor": drive.name, "control": args.control, **reference,
        "estimate": None if estimate is None else estimate.name,
        "inverter": drive.inverter.model, "duration_s": sc.duration,
        "speed_rad_s": m.omega_mean, "speed_rpm": m.omega_mean * _RPM, "speed_pu": m.omega_mean / drive.Omega_0,
        "window_s": [m.t0, m.t1],
        "tau_mean_N_m": m.tau_mean, "tau_mean_pu": m.tau_mean / drive.T_N, "ripple_N_m": m.ripple,
        "ripple_pwm_averaged_N_m": m.ripple_ma, "ripple_pct_of_mean": 100 * m.ripple / abs(m.tau_mean)
        if m.tau_mean else math.nan, "tau_rms_deviation_N_m": m.tau_std, "efficiency": m.efficiency,
        "power_flow": m.power_flow, "p_shaft_W": m.p_shaft,
        "p_dc_W": m.p_src_total, "p_copper_W": m.p_cu,
        "p_inverter_W": m.p_sw + m.p_diode + m.p_Rsrc + m.p_swloss + m.p_rr, "p_iron_W": m.p_fe,
        "i_rms_A": list(m.i_rms), "i_peak_A": list(m.i_peak),
        "zero_current_pct": 100.0 * m.zero_current_share, "energy_balance_residue": m.balance_electrical,
        "flags_summary": res.flags_summary(), "flags": res.meta["flags"],
        "controller_flags": decode_flags(flags) or "none", "controller_flags_bits": flags,
        "trace_rows": len(res),
        "warnings": list(res.meta.get("warnings", [])),
    }
    if not sc.trace:
        summary["trace_rows"] = 0
    if args.format == "json":
        print(json_text(summary))
    else:
        print(f"{drive.name}, {args.control} control, {heading}, "
              f"{'dynamometer' if sc.speed is not None else 'rotor dynamics'}, {drive.inverter.model} inverter")
        for key, value in summary.items():
            if key == "estimate" and value is None:
                continue
            if key in ("motor", "control", "reference", "reference_unit", "torque_limit_N_m", "inverter", "warnings",
                       "flags", "controller_flags", "controller_flags_bits"):  # warnings: stderr; flags: the summary
                continue
            text = ", ".join(f"{v:.4g}" for v in value) if isinstance(value, list) else (
                f"{value:.5g}" if isinstance(value, float) else str(value))
            print(f"  {'flags' if key == 'flags_summary' else key:<28} {text}")
    if args.out is not None:
        files: dict[str, bytes] = {}
        if sc.trace:
            buf = io.BytesIO()
            res.to_pandas().to_csv(buf)
            files["trace.csv"] = buf.getvalue()
        files["metrics.json"] = (json_text({**summary, "metrics": asdict(m)}) + "\n").encode()
        if args.plot:
            fig = res.plot()
            files["waveforms.png"] = plots.figure_bytes(fig, "png")
            files["waveforms.svg"] = plots.figure_bytes(fig, "svg")
        written = write_files(args.out, files)
        res.save(args.out / "result.npz")
        for path in [*written, args.out / "result.npz"]:  # --format json: stdout stays one JSON document
            print(f"wrote {path}", file=sys.stderr if args.format == "json" else sys.stdout)
    return 0

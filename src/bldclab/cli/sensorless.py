"""``bldclab sensorless``: the desync map of a sensorless six-step drive through a throttle step or a start-up."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from .._files import json_text, write_files
from ..analysis.desync import AXES, REASONS, Axis, DesyncMapResult, ThrottleStep, desync_map
from ..control.sensorless import SixStepSensorless, throttle_rate
from ..errors import BldclabError
from ..model.units import to_si
from ..report.desync_plots import desync_figures
from ..report.plots import load_matplotlib
from .common import add_inverter_option, add_verbose_option, load_drive, positive_int, summarise, workers_of
from .paths import check_out_dir

__all__ = ["OPTIONS", "configure_command", "run_command"]

#: The map's parameters as options: option -> (axis name, dimension of a value with a unit, default axis, help).
#: Any two of them may take a comma-separated list: those are the map's axes (the first in this order across). With
#: fewer than two given so, ``--timing`` and then ``--rate`` not given take their default lists as the axes.
OPTIONS: dict[str, tuple[str, str, str | None, str]] = {
    "--timing": ("timing", "angle", "0,10,20,30", "timing advance, deg electrical (or '15 deg', 'rad'), in [0, 30]"),
    "--rate": ("rate", "rate", "2,10,50,inf", "throttle ramp limit, %%/ms (inf: none, a hard step)"),
    "--start": ("start", "", None, "throttle before the step, in [0, 1) (0: a start-up from rest at --end; "
                                   "default 0.25)"),
    "--end": ("end", "", None, "throttle after the step, in (0, 1] (default 0.8)"),
    "--k-q": ("k_q", "propeller", None, "propeller k_q, N m s^2/rad^2 (default the motor file's)"),
    "--inertia": ("J", "inertia", None, "inertia J, kg m^2 or 'g cm^2' (default the motor file's)"),
    "--blank": ("blank", "angle", None, "fixed blanking, deg electrical (default the controller's 5)"),
    "--f-pwm": ("f_pwm", "frequency", None, "PWM frequency, kHz (or '48 kHz'; default the motor file's)"),
    "--v-dc": ("v_dc", "voltage", None, "DC bus, V (default the motor file's)"),
    "--chopping": ("chopping", "", None, "chopping pattern: sync, high, pwm-on-pwm, bipolar (default sync)"),
    "--theta0": ("theta0", "angle", None, "initial rotor angle, deg electrical (default 0)"),
    "--fast-demag": ("fast_demag", "", None, "fast demagnetisation: on, off (default on)"),
    "--demag-limit": ("demag_limit", "", None, "demagnetisation limiter, the share of the window from a commutation to "
                                               "the expected crossing the clamp may take, in [0, 1) (0: off; default "
                                               "0.6)"),
    "--duty-limit": ("duty_limit", "current", None, "current of the speed-dependent duty limit, A (or '30 A'; 0: off; "
                                                    "default I_N)"),
    "--delay": ("delay", "", None, "controller delay, samples: 1 (an output computed at a sample applies from the "
                                   "next one, as a sampled controller) or 0 (within the sample, as an ESC's "
                                   "interrupt-driven commutation timer) (default 0)"),
}
#: The unit a value without one is read in (the axis's), as the factor of that unit to SI.
_TO_AXIS = {"angle": math.pi / 180.0, "frequency": 1e3, "voltage": 1.0, "inertia": 1.0, "propeller": 1.0,
            "current": 1.0}


def configure_command(p: argparse.ArgumentParser) -> None:
    """Arguments of ``bldclab sensorless``."""
    p.epilog = ("The options given a comma-separated list (at most two) are the map's axes; with fewer, --timing and "
                "then --rate take their default lists. Values may carry a unit ('20 deg', '48 kHz', '5 %/ms'). "
                "docs/desync.md explains the outcomes, the plant's truth and the physics check.")
    p.add_argument("motor", metavar="MOTOR", help="built-in drive name or motor TOML file (e.g. f60prov-2550kv)")
    p.add_argument("--out", type=Path,
                   help="directory for desync.csv, desync.json and desync.png/svg (default out/<motor>-sensorless)")
    for opt, (_, _, default, text) in OPTIONS.items():
        d = f" (default axis: {default})" if default is not None else ""
        p.add_argument(opt, metavar="V[,V...]", help=text + d)
    p.add_argument("--settle", help="time at --start before the step, e.g. '50 ms' (default: five mechanical time "
                                    "constants)")
    p.add_argument("--observe", help="time after the step, e.g. '300 ms' (default: the ramp, settling and a restart)")
    p.add_argument("--bound", default="30",
                   help="true commutation angle error beyond which the plant's truth calls a commutation out of "
                        "sync, deg electrical, in (0, 90] (default 30)")
    p.add_argument("--method", choices=("comparator", "adc", "integration"), default="comparator",
                   help="crossing detection (default comparator)")
    p.add_argument("--blanking", choices=("demag", "fixed"), default="demag",
                   help="window after a commutation: from the measured end of the demagnetisation, or fixed "
                        "(default demag)")
    p.add_argument("--direct-start", action="store_true",
                   help="no rotor alignment before the forced ramp, as drone firmware starts")
    p.add_argument("--grid", default="0", metavar="GAIN",
                   help="commutate on a uniform 60-degree grid locked to the mean of the six crossings, learning "
                        "each crossing's offset with this gain in [0, 1] (0: off, 30 deg after each crossing; 0.1 "
                        "suits motors whose phases' back-EMFs differ; a grid point past 30 deg after its crossing is "
                        "bounded by the measured demagnetisation; docs/sensorless.md, 'Uniform grid')")
    p.add_argument("--workers", type=positive_int, help="processes, >= 1 (default: all cores; 1: serial)")
    add_inverter_option(p)
    add_verbose_option(p)


def _one(text: str, name: str, dim: str, option: str) -> Any:
    """Read one value of an option in its axis's unit."""
    t = text.strip()
    if name in ("chopping", "fast_demag"):
        return t
    if name == "rate":
        if t.lower() in ("inf", "none"):
            return math.inf
        try:
            return float(t)
        except ValueError:
            pass
        if "%" not in t:
            raise BldclabError(option, f"cannot read {text!r}: a number in %/ms, '<x> %/ms', '<x> %/s' or inf")
        return throttle_rate(t, option) / 10.0  # '5 %/ms' -> 1/s -> %/ms
    try:
        return float(t)
    except ValueError:
        if not dim:
            raise BldclabError(option, f"cannot read {text!r}: expected a number") from None
    return to_si(t, dim, option) / _TO_AXIS[dim]


def _values(text: str, option: str) -> tuple[Any, ...]:
    name, dim, _, _ = OPTIONS[option]
    items = [v for v in text.split(",") if v.strip()]
    if not items:
        raise BldclabError(option, f"needs at least one value, got {text!r}")
    vals = tuple(_one(v, name, dim, option) for v in items)
    try:
        Axis(name, vals)
    except BldclabError as exc:
        raise BldclabError(option, exc.problem) from None
    return vals


def _time(text: str | None, option: str) -> float | None:
    if text is None:
        return None
    v = to_si(text, "time", option)
    if not 0.0 < v <= 10.0:
        raise BldclabError(option, f"must be a time in (0, 10] s, got {text!r}")
    return v


def _parse(args: argparse.Namespace) -> tuple[list[Axis], dict[str, Any], ThrottleStep, SixStepSensorless, float]:
    """Read the options: the axes (options with several values), the single values, the step, the controller."""
    axes: list[Axis] = []
    single: dict[str, Any] = {}
    given = {opt: getattr(args, opt[2:].replace("-", "_")) for opt in OPTIONS}
    for opt, text in given.items():
        if text is None:
            continue
        vals = _values(text, opt)
        if len(vals) > 1:
            axes.append(Axis(OPTIONS[opt][0], vals))
        else:
            single[OPTIONS[opt][0]] = vals[0]
    if len(axes) > 2:
        option = next(o for o, spec in OPTIONS.items() if spec[0] == axes[2].name)
        raise BldclabError(option, f"a map has two axes; {', '.join(a.name for a in axes)} all have "
                           "several values")
    for opt in ("--timing", "--rate"):  # the default axes, where the user left room for them
        if len(axes) < 2 and given[opt] is None:
            axes.append(Axis(OPTIONS[opt][0], _values(str(OPTIONS[opt][2]), opt)))
    if not axes:  # every option one value: a map of one point
        axes.append(Axis("timing", (single.pop("timing"),)))
    order = list(AXES)
    axes.sort(key=lambda a: order.index(a.name))
    try:
        bound = float(args.bound)
    except ValueError:
        raise BldclabError("--bound", f"cannot read {args.bound!r}: degrees") from None
    if not 0.0 < bound <= 90.0:
        raise BldclabError("--bound", f"must be in (0, 90] deg, got {args.bound!r}")
    try:
        step = ThrottleStep(start=single.pop("start", 0.25), end=single.pop("end", 0.8),
                            settle=_time(args.settle, "--settle"), observe=_time(args.observe, "--observe"))
    except BldclabError as exc:
        opt = {"step.start": "--start", "step.end": "--end"}.get(exc.field, exc.field)
        raise BldclabError(opt, exc.problem) from None
    try:
        grid = float(args.grid)
    except ValueError:
        raise BldclabError("--grid", f"cannot read {args.grid!r}: a gain in [0, 1]") from None
    if not 0.0 <= grid <= 1.0:
        raise BldclabError("--grid", f"must be a gain in [0, 1] (0: off), got {args.grid!r}")
    control = SixStepSensorless(method=args.method, blanking=args.blanking,
                                align_time=0.0 if args.direct_start else None, grid_gain=grid)
    return axes, single, step, control, math.radians(bound)


def _apply_single(drive: Any, control: SixStepSensorless, step: ThrottleStep, single: dict[str, Any]
                  ) -> tuple[Any, SixStepSensorless, ThrottleStep]:
    """Apply the single-valued parameters to the drive, controller and step."""
    for name, v in single.items():
        drive, control, step = AXES[name].apply(drive, control, step, v)
    return drive, control, step


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab sensorless``."""
    drive = load_drive(args)
    axes, single, step, control, bound = _parse(args)
    drive, control, step = _apply_single(drive, control, step, single)
    out = args.out if args.out is not None else Path("out") / f"{drive.name}-sensorless"
    check_out_dir(out)  # before the simulations: a bad --out fails in a second, not after the whole map
    workers = workers_of(args.workers)
    load_matplotlib()
    res = desync_map(drive, axes[0], axes[1] if len(axes) > 1 else None, step=step, control=control, bound=bound,
                     workers=workers, summarise=False)
    refused = res.points[res.points.outcome == "refused"]
    if len(refused) == len(res.points):
        why = str(refused.note.iloc[0]).removeprefix("refused: ")
        raise BldclabError("MOTOR", f"every point of the map was refused ({why}); its runs last "
                           f"{_run_times(res)}: give --settle and --observe, or check the drive's inertia")
    _print(res, workers)
    files: dict[str, bytes] = {"desync.csv": res.points.to_csv(index=False).encode(),
                               "desync.json": json_text(_summary(res, args)).encode()}
    files.update(desync_figures(res))
    for path in write_files(out, files):
        print(f"wrote {path}")
    summarise(res.warnings, len(res.points), args.verbose)
    return 0


def _run_times(res: DesyncMapResult) -> str:
    """Return the runs the map's points ask for, in words (before the axes' changes)."""
    step, d, c = res.step, res.drive, res.control
    after = f"{step.observe_time(d, c):.3g} s after the step"
    if step.is_start:
        return after
    return (f"{step.start_time(d, c):.3g} s before the step (of which settle {step.settle_time(d):.3g} s: five "
            f"mechanical time constants at the start throttle with J = {d.mechanics.J:.3g} kg m^2 unless --settle "
            f"is given) and {after}")


def _print(res: DesyncMapResult, workers: int) -> None:
    d = res.drive
    ny = len(res.y.values) if res.y is not None else 1
    print(f"{d.name}: sensorless six-step desync map, {res.disturbance}, {len(res.x.values)} x {ny} points "
          f"({res.x.name}{' x ' + res.y.name if res.y is not None else ''}) in {res.seconds:.1f} s on {workers} "
          f"process{'es' if workers > 1 else ''}; the drive (where no axis changes it): propeller k_q = "
          f"{d.mechanics.k_q:.3g} N m s^2/rad^2, "
          f"J = {d.mechanics.J:.3g} kg m^2, f_pwm = {d.inverter.f_pwm / 1e3:g} kHz, V_dc = {d.inverter.V_dc:g} V")
    print("  sync: held; rec: desync then restarted, in sync at the end; LOST: desync, not back; UNDET: the plant's "
          "truth saw a commutation out of sync, the controller flagged nothing; nostart: not in closed loop at the "
          "step; REFUSED: not simulated (note below); after ':' the controller's reason")
    for line in res.table().splitlines():
        print(f"  {line}")
    for line in res.summary():
        print(f"  {line}")
    used = sorted(set(r for r in res.points.reason if r))
    for r in used:
        print(f"  {r}: {REASONS.get(r, r)}")
    for note in sorted(set(n for n in res.points.note if n)):
        print(f"  note: {note}")


def _summary(res: DesyncMapResult, args: argparse.Namespace) -> dict[str, Any]:
    def axis(a: Axis | None) -> dict[str, Any] | None:
        return None if a is None else {"name": a.name, "unit": a.unit, "values": [
            v if isinstance(v, str) or math.isfinite(v) else "inf" for v in a.values]}

    counts = {o: int((res.points.outcome == o).sum()) for o in res.points.outcome.unique()}
    return {"motor": res.drive.name, "disturbance": res.disturbance,
            "step": {"start": res.step.start, "end": res.step.end, "settle": res.step.settle,
                     "observe": res.step.observe},
            "x": axis(res.x), "y": axis(res.y), "bound_deg": math.degrees(res.bound),
            "control": {"method": res.control.method, "blanking": res.control.blanking,
                        "chopping": res.control.chopping, "align_time": res.control.align_time,
                        "timing_rad": res.control.timing, "throttle_rate_per_s": res.control.throttle_rate,
                        "fast_demag": res.control.fast_demag, "demag_limit": res.control.demag_limit,
                        "grid_gain": res.control.grid_gain, "delay": res.control.delay,
                        "note": "the controller before the axes' changes"},
            "outcomes": counts, "summary": res.summary(), "table": res.table().splitlines(),
            "boundary": [[str(y), None if x is None else str(x)] for y, x in res.boundary()],
            "seconds": res.seconds, "command": "bldclab sensorless " + " ".join(_argv(args))}


def _argv(args: argparse.Namespace) -> list[str]:
    out = [str(args.motor)]
    for opt in OPTIONS:
        v = getattr(args, opt[2:].replace("-", "_"))
        if v is not None:
            out.append(f"{opt}={v}")
    if float(args.grid) > 0.0:
        out.append(f"--grid={args.grid}")
    return out

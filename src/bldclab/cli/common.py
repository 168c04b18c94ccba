"""Helpers shared by the simulating commands.

The drive from MOTOR and ``--inverter``, controllers by their CLI names, speeds with units, warnings summarised.
Where a command may write is checked by :mod:`bldclab.cli.paths` (no controllers imported: the light commands use it).
"""

from __future__ import annotations

import argparse
import os
import warnings
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

from ..control import Control, Lu, Sine, SixStep, SixStepVoltage
from ..errors import BldclabError, PlausibilityWarning
from ..model import analytic
from ..model.catalog import load
from ..model.motor import Drive, Inverter
from ..model.units import per_unit, to_si
from ..sim import check_estimate
from ..sim import plausibility as _plaus

__all__ = ["CONTROLS", "add_inverter_option", "add_verbose_option", "check_speed_range", "control_of", "load_drive",
           "load_estimate", "parse_speed", "positive_int", "summarise", "worker_pool", "workers_of"]


CONTROLS = ("square", "sine", "sixv", "lu", "lu-no-do", "rect")


def parse_speed(text: str, drive: Drive, option: str = "--speed") -> float:
    """Read a speed: ``"0.5 pu"`` (of ``Omega_0``), ``"300 rpm"``, ``"31.4 rad/s"`` or a number in rad/s.

    ``option`` is the option named in the error.
    """
    pu = per_unit(text)
    if pu is not None:
        return pu * drive.Omega_0
    return to_si(text, "speed", option)


def control_of(name: str, drive: Drive, handoff: float | None = None) -> tuple[Control, float, str]:
    """Return the controller for a --control name, its default reference and what the reference means."""
    if name == "square":
        return SixStep(), drive.motor.I_N, "A"
    if name == "sine":
        ctl = Sine() if handoff is None else Sine(handoff_speed=handoff)
        return ctl, analytic.t_sN(drive), "N m"
    if name == "sixv":
        return SixStepVoltage("high"), 0.5, "duty"
    if name in ("lu", "lu-no-do", "rect"):
        return Lu(method=name), drive.T_N, "N m"  # type: ignore[arg-type]  # name: one of Lu's methods, checked above
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


def load_estimate(text: str | None, drive: Drive, option: str) -> Drive | None:
    """Load the drive data a controller is configured from (``--estimate``, ``--nominal``), checked against the plant.

    Its file's own errors name the file; pole pairs or PWM frequency other than the plant's
    (:func:`bldclab.sim.check_estimate`) name ``option``, before any run. None if ``text`` is None.
    """
    if text is None:
        return None
    est = load(text)
    try:
        check_estimate(drive, est)
    except BldclabError as exc:
        raise BldclabError(option, f"{est.name}: {exc.field}: {exc.problem}") from None
    return est


def summarise(caught: list[str], runs: int | str, verbose: bool = False) -> None:
    """Issue one plausibility warning for the many an experiment collected (:func:`bldclab.sim.plausibility.summary`).

    ``verbose`` (``--verbose``): every distinct warning first, one line each, then the summary.
    """
    if verbose:
        for text in _plaus.distinct(caught):
            warnings.warn(text, PlausibilityWarning, stacklevel=2)
    line = _plaus.summary(caught, runs)
    if line:
        warnings.warn(line, PlausibilityWarning, stacklevel=2)


def add_verbose_option(p: argparse.ArgumentParser) -> None:
    """Add ``--verbose``: every distinct plausibility warning of the runs, not only their one summary line."""
    p.add_argument("--verbose", action="store_true",
                   help="list every distinct plausibility warning of the runs (default: one summary line)")


def positive_int(text: str) -> int:
    """Argparse type: an integer >= 1 (``--workers``, ``--speeds`` counts)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def check_speed_range(lo: float, hi: float) -> None:
    """Check ``--min-speed`` and ``--max-speed`` (p.u. of Omega_0), naming the option that is wrong."""
    if not 0 < lo < 1.5:
        raise BldclabError("--min-speed", f"must be in (0, 1.5) p.u. of Omega_0, got {lo:g}")
    if not 0 < hi < 1.5:
        raise BldclabError("--max-speed", f"must be in (0, 1.5) p.u. of Omega_0, got {hi:g}")
    if lo >= hi:
        raise BldclabError("--max-speed", f"must be above --min-speed ({lo:g}), got {hi:g}")


def workers_of(workers: int | None) -> int:
    """Return the processes of ``--workers``: as given, else one per core."""
    return workers or os.cpu_count() or 1


@contextmanager
def worker_pool(workers: int) -> Iterator[ProcessPoolExecutor | None]:
    """Open the command's process pool, for its simulations and then its figures (None for one process: run here).

    One pool for the whole command: its workers start once (at the first job) and draw the figures after the
    simulations, with everything they imported for the simulations still loaded.
    """
    if workers <= 1:
        yield None
        return
    with ProcessPoolExecutor(max_workers=workers) as pool:
        yield pool

"""Command-line interface: ``bldclab <command> [options]``.

Every subcommand is a :class:`Command`: a name, a one-line help and the module of this package that implements
it, with a function that declares its arguments (``configure_command``) and a function that runs it and returns
the exit code (``run_command``). They are registered in :data:`COMMANDS`, the one place to add a new one. A
command's module is imported only when that command runs (or its help is shown): ``bldclab drives`` does not
load matplotlib, pandas or the C library. :func:`main` owns the error handling for all of them: a bad argument or a
:class:`BldclabError` prints one line ``bldclab: error: <message>`` on stderr and exits with status 2, without
a traceback.

Files are written atomically (a temporary file in the target directory, then :func:`os.replace`), after every
result has been computed, so an error leaves no half-written output.
"""

from __future__ import annotations

import argparse
import difflib
import gc
import os  # bldclab.cli.os: the tests fail os.replace through it
import re
import sys
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import NoReturn

from .._files import write_files
from .._lazy import load
from .._version import __version__
from ..errors import BldclabError, PlausibilityWarning
from ..model.analytic.table import table1_text

__all__ = ["COMMANDS", "Command", "build_parser", "did_you_mean", "main", "table1_text", "write_files"]

PROG = "bldclab"


class _UsageError(Exception):
    """A command-line argument is wrong (raised instead of argparse's print-usage-and-exit)."""


class _Parser(argparse.ArgumentParser):
    """Argument parser that raises :class:`_UsageError` instead of printing the usage and exiting."""

    def error(self, message: str) -> NoReturn:
        """Raise the parsing error for :func:`main` to report on one line."""
        raise _UsageError(message)


@dataclass(frozen=True)
class Command:
    """One subcommand.

    Parameters
    ----------
    name : str
        What the user types after ``bldclab``.
    help : str
        One line for ``bldclab --help``.
    module : str
        The module of :mod:`bldclab.cli` that implements it (``"torque_control"``): its ``configure_command(parser)``
        adds the subcommand's arguments to its parser, its ``run_command(args) -> int`` does the work and returns
        the exit status. Imported on first use of :attr:`configure` or :attr:`run`.

    """

    name: str
    help: str
    module: str

    def load(self) -> ModuleType:
        """Import and return the command's module (``bldclab.cli.<module>``)."""
        return load(f"{__name__}.{self.module}")

    @property
    def configure(self) -> Callable[[argparse.ArgumentParser], None]:
        """``configure(parser)``: add the subcommand's arguments to its parser."""
        fn: Callable[[argparse.ArgumentParser], None] = self.load().configure_command
        return fn

    @property
    def run(self) -> Callable[[argparse.Namespace], int]:
        """``run(args) -> int``: do the work and return the exit status."""
        fn: Callable[[argparse.Namespace], int] = self.load().run_command
        return fn


# ------------------------------------------------------------------------------------------------------------
# registry and entry point

#: The subcommands, in the order ``bldclab --help`` lists them. Add new ones here. Their modules are imported by name
#: (:func:`bldclab._lazy.load`) when the command runs; ``tests/test_layers.py`` reads them as imports of this module.
COMMANDS: tuple[Command, ...] = (
    Command("drives", "list the built-in drives: back-EMF, V_dc, I_N, pole pairs, PWM, speeds, source",
            "drives"),
    Command("template", "write a commented motor file to start from (every field with its unit)",
            "template"),
    Command("check", "validate a motor file and print its derived quantities (bases, L/R, PWM per commutation)",
            "check"),
    Command("analyze", "paper 1 closed forms for a motor: Table I, characteristics, Figs 7-8",
            "analyze"),
    Command("sweep", "run many simulations (grid or list of cases) on processes or Dask into a resumable store",
            "sweep"),
    Command("identify", "back-EMF tables from a constant-speed waveform (paper 2)",
            "identify"),
    Command("simulate", "one switching-level simulation: square, sine, sixv, lu, lu-no-do, rect or your controller",
            "simulate"),
    Command("controller", "build your own C controller into a library for simulate --control, or describe one",
            "controller"),
    Command("compare", "square-wave vs sinusoidal supply: closed forms and simulation over speed (paper 1)",
            "compare"),
    Command("effmap", "efficiency and loss maps of both supplies over the torque-speed plane, where each wins",
            "effmap"),
    Command("hall", "mean torque, ripple and efficiency of each supply against the Hall sensors' placement error",
            "hall"),
    Command("sensorless", "desync map of a sensorless six-step drive: throttle step or start-up over two parameters, "
            "each point in sync, desynced (with the reason), recovered or not started", "sensorless"),
    Command("torque-control", "paper 2's torque control vs its baselines over a load x speed grid",
            "torque_control"),
    Command("commission", "self-commissioning on the plant: R, L and flux linkage measured by the controller",
            "commission"),
    Command("thermal", "a load profile (hill climb, duty cycle) through the drive and its thermal network",
            "thermal"),
    Command("faults", "inject sensor, bus and phase faults: detection, time to safe state, peak current",
            "faults"),
    Command("report", "one self-contained HTML report of a comparison (a results directory, or a motor to run)",
            "report"),
)


def build_parser(commands: Iterable[str] | None = None) -> argparse.ArgumentParser:
    """Build the argument parser with every subcommand of :data:`COMMANDS`.

    Parameters
    ----------
    commands : iterable of str, optional
        The subcommands whose arguments are declared (their modules are imported); default all. The others are
        listed by ``--help`` all the same, without their arguments.

    Returns
    -------
    argparse.ArgumentParser

    """
    chosen = None if commands is None else set(commands)
    parser = _Parser(prog=PROG, description="Simulate, analyse and control PM brushless DC motor drives.")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for cmd in COMMANDS:
        p = sub.add_parser(cmd.name, help=cmd.help, description=cmd.help)
        if chosen is None or cmd.name in chosen:
            cmd.configure(p)
            p.set_defaults(run=cmd.run)
    return parser


def _command_name(argv: Sequence[str]) -> list[str]:
    """Return the subcommand named in ``argv`` (as a list of at most one): its first word that is not an option.

    The program's own options (``--help``, ``--version``) take no value, so that word is the one the parser reads
    as the subcommand; only that command's module is then imported.
    """
    return [a for a in argv if not a.startswith("-")][:1]


def _options(parser: argparse.ArgumentParser, argv: Sequence[str]) -> list[str]:
    """Return the option strings the command line could have meant: the program's and its subcommand's."""
    out = [s for a in parser._actions for s in a.option_strings]
    names = _command_name(argv)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction) and names and names[0] in action.choices:
            sub = action.choices[names[0]]
            out += [s for a in sub._actions for s in a.option_strings]
    return out


def did_you_mean(parser: argparse.ArgumentParser, argv: Sequence[str], message: str) -> str:
    """Add the nearest valid spelling to a usage error: a mistyped option, subcommand or choice.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The program's parser (with the subcommand's arguments declared).
    argv : sequence of str
        The command line, without the program name.
    message : str
        argparse's message (``"unrecognized arguments: --contrl sine"``, ``"argument COMMAND: invalid choice:
        'simulat' (choose from ...)"``).

    Returns
    -------
    str
        The message with ``"; did you mean --control?"`` where a close spelling exists (``difflib``), else as it was.
    """
    m = re.match(r"(.*invalid choice: '([^']*)')( \(choose from (.*)\))$", message)
    if m:
        close = difflib.get_close_matches(m.group(2), re.findall(r"'([^']*)'", m.group(4)), n=1, cutoff=0.6)
        return f"{m.group(1)}: did you mean {close[0]!r}?{m.group(3)}" if close else message
    m = re.match(r"unrecognized arguments: (.*)$", message)
    options = _options(parser, argv)
    hints = []
    for token in (m.group(1).split() if m else argv):  # else: a required argument missing past a mistyped option
        name = token.split("=", 1)[0]
        if name.startswith("--") or (name.startswith("-") and name[1:2].isalpha()):
            close = difflib.get_close_matches(name, options, n=1, cutoff=0.6) if name not in options else []
            if close:
                hints.append((close[0], name))
    if len(hints) == 1:
        return f"{message}: did you mean {hints[0][0]}?"
    if hints:
        return f"{message}: did you mean {', '.join(f'{h} (for {t})' for h, t in hints)}?"
    return message


def _one_line(text: str) -> str:
    """Collapse a message onto one line."""
    return " ".join(str(text).split())


def _show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                  file: object = None, line: str | None = None) -> None:
    """Show a plausibility warning as one line ``bldclab: warning: <message>`` on stderr; others as usual."""
    if issubclass(category, PlausibilityWarning):
        sys.stderr.write(f"{PROG}: warning: {_one_line(str(message))}\n")
    else:
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; default ``sys.argv[1:]``, and then (the ``bldclab`` program, about to
        exit) the garbage collector's objects are frozen before returning (:func:`gc.freeze`): the process's memory
        goes with it, without a last collection.

    Returns
    -------
    int
        Exit status: 0 on success, 2 for a bad argument or bad input (one line on stderr), including a simulation
        whose result would be physically meaningless (:class:`~bldclab.errors.PlausibilityError`), 130 if
        interrupted. Plausibility warnings go to stderr, one line each.

    """
    program = argv is None  # run as the bldclab program (not called from Python code)
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(_command_name(argv))
    try:
        args = parser.parse_args(argv)
        with warnings.catch_warnings():
            warnings.simplefilter("always", PlausibilityWarning)
            warnings.showwarning = _show_warning
            return int(args.run(args))
    except SystemExit as exc:  # --help, --version
        return exc.code if isinstance(exc.code, int) else 0  # argparse exits 0 after printing help
    except _UsageError as exc:
        sys.stderr.write(f"{PROG}: error: {_one_line(did_you_mean(parser, argv, str(exc)))}\n")
        return 2
    except BldclabError as exc:
        sys.stderr.write(f"{PROG}: error: {_one_line(str(exc))}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write(f"{PROG}: interrupted\n")
        return 130
    except BrokenPipeError:  # stdout closed early (``bldclab drives | head``): stop quietly, like other tools
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # so that the interpreter's final flush does not fail again
        return 141
    finally:
        if program:  # the process ends next and its memory goes with it: the interpreter's last garbage collection
            gc.freeze()  # (the cycles of figures and tables, 0.1 s after effmap or compare) would free it for nothing

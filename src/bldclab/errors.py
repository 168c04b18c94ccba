"""Error and warning types: bad input names the field and the problem; implausible runs name the cause."""

from __future__ import annotations

__all__ = ["BldclabError", "ControllerError", "PlausibilityError", "PlausibilityWarning"]


class BldclabError(ValueError):
    """Bad user input (a motor file, a CSV, an argument).

    Parameters
    ----------
    field : str
        Dotted name of the offending field, e.g. ``"motor.L"`` or ``"waveform.csv: column v_a"``.
    problem : str
        What is wrong with it, in plain words.
    source : str, optional
        The file or object the field came from.

    """

    def __init__(self, field: str, problem: str, source: str | None = None) -> None:
        self.field = field
        self.problem = problem
        self.source = source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{field}: {problem}")

    def __reduce__(self) -> tuple[type, tuple[str, str, str | None]]:
        """Pickle with the constructor's arguments (errors raised in worker processes reach the parent)."""
        return (type(self), (self.field, self.problem, self.source))


class PlausibilityError(BldclabError):
    """A simulation whose result would be physically meaningless (see :mod:`bldclab.sim.plausibility`).

    ``field`` names the cause (``"inverter.f_pwm"``, ``"scenario.speed"``, ``"result.energy_balance"``, ...),
    ``problem`` the numbers and the threshold crossed.
    """


class ControllerError(BldclabError):
    """A user's controller (:mod:`bldclab.control.user`) failed during a run: no result is returned.

    ``field`` names the controller (``"control (my, ./my.so)"``), ``problem`` what it did and at which sample:
    crashed (the signal and the address), did not return within the step-time budget, wrote NaN or a duty outside
    [0, 1] (the output field and the value), wrote to its inputs, its init rejected the parameters, or a Python
    controller raised (its exception is the ``__cause__``).
    """


class PlausibilityWarning(UserWarning):
    """A simulation that ran but whose result is questionable (see :mod:`bldclab.sim.plausibility`).

    Issued through :mod:`warnings`; silence or escalate it with the usual filters, e.g.
    ``warnings.simplefilter("error", PlausibilityWarning)``.
    """

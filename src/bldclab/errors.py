"""One error type for bad input: it names the field and the problem."""

from __future__ import annotations

__all__ = ["BldclabError"]


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

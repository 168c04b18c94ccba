"""The progress line of a running sweep: done, failed, rate and time left, on a terminal or as plain lines."""

from __future__ import annotations

import math
import shutil
import sys
import time
from typing import TextIO

__all__ = [
    "Progress",
]


def _clock(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "--:--"
    s = round(seconds)
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m:02d}:{s:02d}"


class Progress:
    """A one-line progress bar with rate and ETA on a terminal stream.

    Parameters
    ----------
    total : int
        Number of cases.
    done : int
        Cases already finished (in the store) at the start; they do not count for the rate.
    stream : text stream, optional
        Default ``sys.stderr``.
    enabled : bool, optional
        Default: only if ``stream`` is a terminal.
    label : str
        Text before the bar.
    """

    def __init__(self, total: int, done: int = 0, *, stream: TextIO | None = None, enabled: bool | None = None,
                 label: str = "sweep") -> None:
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.total = total
        self.done = done
        self.start_done = done
        self.failed = 0
        self.label = label
        self.t0 = time.perf_counter()
        self._last = -math.inf
        self._width = 0
        self._render(force=True)

    def advance(self, n: int = 1, *, failed: bool = False, computed: bool = True) -> None:
        """Count ``n`` finished cases (``computed=False``: found in the store, not run)."""
        self.done += n
        if not computed:
            self.start_done += n
        if failed:
            self.failed += n
        self._render()

    def line(self) -> str:
        """Return the current text of the bar."""
        elapsed = time.perf_counter() - self.t0
        run = self.done - self.start_done
        rate = run / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else math.inf
        frac = self.done / self.total if self.total else 1.0
        cols = shutil.get_terminal_size((100, 20)).columns
        fail = f" {self.failed} failed" if self.failed else ""
        tail = f" {self.done}/{self.total}{fail} {rate:.1f}/s {_clock(elapsed)} ETA {_clock(eta)}"
        width = max(10, min(40, cols - len(self.label) - len(tail) - 9))
        fill = int(frac * width)
        return f"{self.label} {100 * frac:3.0f}% |{'#' * fill}{'.' * (width - fill)}|{tail}"

    def _render(self, force: bool = False) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self._last < 0.1 and self.done < self.total:
            return
        self._last = now
        text = self.line()
        self.stream.write("\r" + text + " " * max(0, self._width - len(text)))
        self.stream.flush()
        self._width = len(text)

    def close(self) -> None:
        """Draw the final state and end the line."""
        if self.enabled:
            self._render(force=True)
            self.stream.write("\n")
            self.stream.flush()

"""The base of every controller choice."""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

if TYPE_CHECKING:
    from .._core import Core
    from ..motor import Drive

__all__ = ["Control"]


class Control:
    """Base class: the C registry name and how to fill the parameter struct."""

    c_name: ClassVar[str] = ""
    ref_meaning: ClassVar[str] = ""

    def c_params(self, drive: Drive, core: Core, keep: list[object], n_samples: int) -> np.ndarray:
        """Return the filled C parameter record; arrays it points to are appended to ``keep``."""
        raise NotImplementedError  # pragma: no cover - abstract

    def with_delay(self, delay: int) -> Control:
        """Return the controller configured for the runner's computation delay (samples, 0 or 1).

        :func:`bldclab.simulate` calls this with ``Scenario.delay``, so a controller that predicts across the delay
        always knows the delay actually applied. Controllers without such a setting return themselves.
        """
        return self

    def describe(self) -> dict[str, object]:
        """Return the settings as plain values (for result metadata)."""
        out: dict[str, object] = {"controller": self.c_name}
        for k, v in self.__dict__.items():
            out[k] = v.tolist() if isinstance(v, np.ndarray) else v
        return out

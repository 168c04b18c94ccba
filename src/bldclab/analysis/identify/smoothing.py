"""Periodic local linear regression: the zero-phase smoother of step 3 of the identification.

It estimates a periodic signal sampled at scattered angles over many periods, exactly on straight segments (see
:mod:`bldclab.analysis.identify.algorithm`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...model.emf import TWO_PI

__all__ = [
]


class _Periodic:
    """Samples (angle, value) pooled over periods; local linear regression at any angle (cumulative sums).

    The estimate at ``g`` is the intercept of the least-squares line through the samples whose angle lies
    within ``g +- h`` (mod 2 pi). A symmetric window makes it zero-phase; a straight segment is reproduced
    exactly; a corner (slope change ``ds``) is rounded within ``+-h`` by at most ``ds h / 4``.
    """

    def __init__(self, angle: NDArray[np.float64], values: NDArray[np.float64]) -> None:
        x = np.mod(angle, TWO_PI)
        order = np.argsort(x, kind="stable")
        xs = x[order]
        self.xe = np.concatenate([xs - TWO_PI, xs, xs + TWO_PI])
        ones = np.ones(self.xe.size)
        self.c0 = np.concatenate([[0.0], np.cumsum(ones)])
        self.c1 = np.concatenate([[0.0], np.cumsum(self.xe)])
        self.c2 = np.concatenate([[0.0], np.cumsum(self.xe * self.xe)])
        self.cy = []
        self.cxy = []
        for y in np.atleast_2d(values):
            ye = np.tile(y[order], 3)
            self.cy.append(np.concatenate([[0.0], np.cumsum(ye)]))
            self.cxy.append(np.concatenate([[0.0], np.cumsum(self.xe * ye)]))

    def count(self, g: NDArray[np.float64], h: NDArray[np.float64] | float) -> NDArray[np.float64]:
        """Return the number of samples within ``g +- h``."""
        g = np.mod(g, TWO_PI)
        i0 = np.searchsorted(self.xe, g - h, "left")
        i1 = np.searchsorted(self.xe, g + h, "right")
        return self.c0[i1] - self.c0[i0]

    def __call__(self, g: NDArray[np.float64], h: NDArray[np.float64] | float, which: int = 0
                 ) -> NDArray[np.float64]:
        """Return the local-linear estimate of series ``which`` at angles ``g`` (rad), window ``+-h``."""
        g = np.mod(np.asarray(g, dtype=float), TWO_PI)
        i0 = np.searchsorted(self.xe, g - h, "left")
        i1 = np.searchsorted(self.xe, g + h, "right")
        n = self.c0[i1] - self.c0[i0]
        s1x = self.c1[i1] - self.c1[i0]
        s2x = self.c2[i1] - self.c2[i0]
        sy = self.cy[which][i1] - self.cy[which][i0]
        sxy = self.cxy[which][i1] - self.cxy[which][i0]
        s1 = s1x - n * g  # sums of d = x - g
        s2 = s2x - 2.0 * g * s1x + n * g * g
        sdy = sxy - g * sy
        den = n * s2 - s1 * s1
        mean = sy / np.maximum(n, 1.0)
        ok = den > 1e-12 * np.maximum(n * s2, 1e-300)
        return np.where(ok, (s2 * sy - s1 * sdy) / np.where(ok, den, 1.0), mean)

    def self_weight(self, g: NDArray[np.float64], h: NDArray[np.float64] | float) -> NDArray[np.float64]:
        """Return the weight of a sample at angle ``g`` in the estimate at ``g`` (the hat matrix diagonal)."""
        g = np.mod(np.asarray(g, dtype=float), TWO_PI)
        i0 = np.searchsorted(self.xe, g - h, "left")
        i1 = np.searchsorted(self.xe, g + h, "right")
        n = self.c0[i1] - self.c0[i0]
        s1x = self.c1[i1] - self.c1[i0]
        s1 = s1x - n * g
        s2 = self.c2[i1] - self.c2[i0] - 2.0 * g * s1x + n * g * g
        den = n * s2 - s1 * s1
        ok = den > 1e-12 * np.maximum(n * s2, 1e-300)
        return np.where(ok, s2 / np.where(ok, den, 1.0), 1.0 / np.maximum(n, 1.0))

    def window(self, g: NDArray[np.float64], h: float, min_count: int = 4) -> NDArray[np.float64]:
        """Return per-angle half-widths: ``h``, widened where the window holds too few samples or lopsided ones.

        Widened where fewer than ``min_count`` samples fall inside, or where they lie so much to one side of ``g``
        that the line's intercept carries more than twice the noise variance of ``min_count`` evenly spread samples
        (an unevenly sampled record: four samples bunched at one end of the window extrapolate the line, and the
        noise with it, up to 59 times its variance).
        """
        hw = np.full(np.shape(g), float(h))
        for _ in range(40):
            few = (self.count(g, hw) < min_count) | (self.self_weight(g, hw) > 2.0 / min_count)
            if not np.any(few):
                break
            hw[few] *= 1.5
        return hw

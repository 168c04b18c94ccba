"""Back-EMF shapes and cogging: what the motor's magnets induce in each phase and the torque they cog.

Back-EMF shapes ``k_x(theta_x)`` are in V s/rad (per mechanical rad/s) as a function of the phase's own electrical
angle ``theta_x = theta_e - x 2 pi/3`` (``docs/conventions.md``): the ideal :class:`Trapezoid`, a :class:`Sinusoid`,
a :class:`Fourier` series or a piecewise-linear :class:`Table`, three of them (one per phase) in a :class:`BackEmf`.
Every class is a frozen dataclass that validates itself on construction and raises
:class:`~bldclab.errors.BldclabError` naming the offending field.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import BldclabError
from ._checks import check_array, check_number

__all__ = [
    "TWO_PI",
    "BackEmf",
    "Cogging",
    "Fourier",
    "Shape",
    "Sinusoid",
    "Table",
    "Trapezoid",
]

TWO_PI = 2.0 * math.pi

#: The phases' letters, in the order of :attr:`BackEmf.shapes` (motor files name per-phase columns ``k_a`` ...).
PHASES = "abc"


class Shape(ABC):
    """Base of the back-EMF shapes: ``k(theta)`` in V s/rad of the phase's local electrical angle."""

    kind: ClassVar[str] = ""

    @abstractmethod
    def __call__(self, theta: ArrayLike) -> NDArray[np.float64]:
        """Evaluate the shape.

        Parameters
        ----------
        theta : array_like
            Local electrical angle of the phase (rad); any real value, the shape is 2 pi periodic.

        Returns
        -------
        ndarray
            ``k(theta)`` in V s/rad.

        """

    def breakpoints(self) -> NDArray[np.float64]:
        """Return the angles in [0, 2 pi) where the shape has corners (empty for smooth shapes)."""
        return np.empty(0)

    @abstractmethod
    def c_form(self) -> tuple[int, NDArray[np.float64], NDArray[np.float64]]:
        """Return the C core's form (kind code, x, y): table (0): angles, values; Fourier (1): a, b."""

    @abstractmethod
    def fourier(self, n_max: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Return the Fourier coefficients ``a_n, b_n``, n = 0..n_max, of ``k = sum a_n cos nx + b_n sin nx``.

        Computed exactly for piecewise-linear and Fourier shapes.
        """

    @abstractmethod
    def to_toml_dict(self) -> dict[str, Any]:
        """Return the TOML table describing this shape (SI numbers)."""

    def mean_abs_power(self, q: float) -> float:
        """Return the mean over one period of ``|k(theta)|^q`` ((V s/rad)^q).

        Exact for piecewise-linear shapes (segment by segment, split at zero crossings) and, for ``q = 2``, for
        Fourier shapes (Parseval: ``a_0^2 + sum (a_n^2 + b_n^2) / 2``); other Fourier cases by the trapezoidal
        rule on 2^15 points of the period (relative error below 1e-9 for ``q >= 1.5``).

        Parameters
        ----------
        q : float
            Exponent, >= 1.
        """
        kind, x, y = self.c_form()
        if kind == 1:
            a, b = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
            if q == 2.0:
                return float(a[0] ** 2 + 0.5 * np.sum(a[1:] ** 2 + b[1:] ** 2))
            th = np.linspace(0.0, TWO_PI, 1 << 15, endpoint=False)
            return float(np.mean(np.abs(self(th)) ** q))
        return _pwl_mean_abs_power(np.asarray(x, dtype=float), np.asarray(y, dtype=float), q)

    def flux_peak(self) -> float:
        """Return the peak of the shape's zero-mean integral over the angle, ``max |int k dtheta|`` (V s).

        Divided by the pole pairs it is the peak magnet flux linkage of the phase (Wb): ``e = d psi/dt =
        omega_m k`` and ``d theta_e = p omega_m dt``. Half the peak-to-peak of the integral (the trapezoidal rule on
        2^16 points of the period and the shape's corners; relative error below 1e-8).
        """
        th = np.unique(np.concatenate([np.linspace(0.0, TWO_PI, 1 << 16, endpoint=False), self.breakpoints(),
                                       [TWO_PI]]))
        k = self(th)
        integral = np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]) * np.diff(th))])
        return float(0.5 * (integral.max() - integral.min()))

    @abstractmethod
    def scaled(self, factor: float) -> Shape:
        """Return the same shape with every value times ``factor`` (> 0)."""


def _pwl_fourier(x: NDArray[np.float64], y: NDArray[np.float64], n_max: int
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Exact Fourier coefficients of a periodic piecewise-linear function through (x, y) on [0, 2 pi)."""
    xs = np.append(x, x[0] + TWO_PI)
    ys = np.append(y, y[0])
    a = np.zeros(n_max + 1)
    b = np.zeros(n_max + 1)
    x0, x1, y0, y1 = xs[:-1], xs[1:], ys[:-1], ys[1:]
    dx = x1 - x0
    a[0] = np.sum(0.5 * (y0 + y1) * dx) / TWO_PI
    s = (y1 - y0) / dx
    for n in range(1, n_max + 1):
        # integral of (y0 + s (x - x0)) * cos(n x) over [x0, x1], by parts
        c0, c1 = np.cos(n * x0), np.cos(n * x1)
        s0, s1 = np.sin(n * x0), np.sin(n * x1)
        ic = (y1 * s1 - y0 * s0) / n + s * (c1 - c0) / n**2
        is_ = -(y1 * c1 - y0 * c0) / n + s * (s1 - s0) / n**2
        a[n] = np.sum(ic) / math.pi
        b[n] = np.sum(is_) / math.pi
    return a, b


def _pwl_mean_abs_power(x: NDArray[np.float64], y: NDArray[np.float64], q: float) -> float:
    """Exact period mean of ``|f|^q`` for the periodic piecewise-linear ``f`` through (x, y) on [0, 2 pi)."""
    xs = np.append(x, x[0] + TWO_PI)
    ys = np.append(y, y[0])
    total = 0.0
    for x0, x1, y0, y1 in zip(xs[:-1], xs[1:], ys[:-1], ys[1:], strict=True):
        pieces = [(x1 - x0, abs(y0), abs(y1))]
        if y0 * y1 < 0.0:  # split at the zero: |f| is linear on each side
            xz = (x1 - x0) * y0 / (y0 - y1)
            pieces = [(xz, abs(y0), 0.0), (x1 - x0 - xz, 0.0, abs(y1))]
        for dx, u, v in pieces:
            if abs(v - u) <= 1e-6 * max(u, v):  # nearly flat: the cancellation-free midpoint form, error O((v-u)^2)
                total += dx * 0.5 * (u**q + v**q)
            else:  # integral of a linear |f| from u to v: (v^(q+1) - u^(q+1)) / ((q + 1) (v - u)) per unit length
                total += dx * (v ** (q + 1) - u ** (q + 1)) / ((q + 1) * (v - u))
    return total / TWO_PI


@dataclass(frozen=True)
class Trapezoid(Shape):
    """Ideal trapezoid: flat top ``k_phi`` for ``flat_top`` rad, linear ramps through zero, half-wave odd.

    Parameters
    ----------
    k_phi : float
        Flat-top value (V s/rad), > 0.
    flat_top : float
        Width of each flat top (rad, electrical), in [0, pi). Default 2 pi/3 (paper 1).

    """

    k_phi: float
    flat_top: float = TWO_PI / 3.0
    kind: ClassVar[str] = "trapezoid"

    def __post_init__(self) -> None:
        check_number("k_phi", self.k_phi, lo=0.0, lo_open=True)
        check_number("flat_top", self.flat_top, lo=0.0, hi=math.pi, hi_open=True)

    @property
    def ramp(self) -> float:
        """Half width of the ramp through zero (rad): ``(pi - flat_top)/2``."""
        return 0.5 * (math.pi - self.flat_top)

    def breakpoints(self) -> NDArray[np.float64]:  # noqa: D102
        r = self.ramp
        pts = np.array([r, math.pi - r, math.pi + r, TWO_PI - r])
        return np.unique(pts)

    def _table(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        x = self.breakpoints()
        return x, self(x)

    def __call__(self, theta: ArrayLike) -> NDArray[np.float64]:  # noqa: D102
        t = np.mod(np.asarray(theta, dtype=float) + math.pi / 2, TWO_PI) - math.pi / 2  # in [-pi/2, 3pi/2)
        half = np.where(t < math.pi / 2, t, math.pi - t)  # fold onto [-pi/2, pi/2] using k(pi - t) = k(t)
        return self.k_phi * np.clip(half / self.ramp, -1.0, 1.0)

    def c_form(self) -> tuple[int, NDArray[np.float64], NDArray[np.float64]]:  # noqa: D102
        x, y = self._table()
        return 0, x, y

    def fourier(self, n_max: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # noqa: D102
        return _pwl_fourier(*self._table(), n_max)

    def to_toml_dict(self) -> dict[str, Any]:  # noqa: D102
        return {"kind": self.kind, "k_phi": self.k_phi, "flat_top": self.flat_top}

    def scaled(self, factor: float) -> Trapezoid:  # noqa: D102
        return dataclasses.replace(self, k_phi=self.k_phi * factor)


@dataclass(frozen=True)
class Sinusoid(Shape):
    """Sinusoidal back-EMF ``k(theta) = k_1 sin(theta)``.

    Parameters
    ----------
    k_1 : float
        Peak value (V s/rad), > 0. For a PMSM, ``k_1 = p psi_f``.

    """

    k_1: float
    kind: ClassVar[str] = "sinusoid"

    def __post_init__(self) -> None:
        check_number("k_1", self.k_1, lo=0.0, lo_open=True)

    def __call__(self, theta: ArrayLike) -> NDArray[np.float64]:  # noqa: D102
        return self.k_1 * np.sin(np.asarray(theta, dtype=float))

    def c_form(self) -> tuple[int, NDArray[np.float64], NDArray[np.float64]]:  # noqa: D102
        return 1, np.zeros(2), np.array([0.0, self.k_1])

    def fourier(self, n_max: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # noqa: D102
        a, b = np.zeros(n_max + 1), np.zeros(n_max + 1)
        if n_max >= 1:
            b[1] = self.k_1
        return a, b

    def to_toml_dict(self) -> dict[str, Any]:  # noqa: D102
        return {"kind": self.kind, "k_1": self.k_1}

    def scaled(self, factor: float) -> Sinusoid:  # noqa: D102
        return dataclasses.replace(self, k_1=self.k_1 * factor)


@dataclass(frozen=True)
class Fourier(Shape):
    """Fourier series ``k(theta) = sum_n a[n] cos(n theta) + b[n] sin(n theta)``, n = 0 .. len-1.

    Parameters
    ----------
    a, b : tuple of float
        Cosine and sine coefficients (V s/rad) of equal length >= 2; index = harmonic order.

    """

    a: tuple[float, ...]
    b: tuple[float, ...]
    kind: ClassVar[str] = "fourier"

    def __post_init__(self) -> None:
        a = check_array("a", self.a, min_len=2)
        b = check_array("b", self.b, min_len=2)
        if a.size != b.size:
            raise BldclabError("b", f"must have as many entries as a ({a.size}), got {b.size}")
        if not np.any(a[1:]) and not np.any(b[1:]):
            raise BldclabError("b", "all harmonics are zero: the motor has no back-EMF")
        object.__setattr__(self, "a", tuple(float(v) for v in a))
        object.__setattr__(self, "b", tuple(float(v) for v in b))

    def __call__(self, theta: ArrayLike) -> NDArray[np.float64]:  # noqa: D102
        t = np.asarray(theta, dtype=float)
        out = np.zeros_like(t)
        for n, (an, bn) in enumerate(zip(self.a, self.b, strict=True)):
            out = out + an * np.cos(n * t) + bn * np.sin(n * t)
        return out

    def c_form(self) -> tuple[int, NDArray[np.float64], NDArray[np.float64]]:  # noqa: D102
        return 1, np.array(self.a), np.array(self.b)

    def fourier(self, n_max: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # noqa: D102
        a, b = np.zeros(n_max + 1), np.zeros(n_max + 1)
        m = min(n_max + 1, len(self.a))
        a[:m], b[:m] = self.a[:m], self.b[:m]
        return a, b

    def to_toml_dict(self) -> dict[str, Any]:  # noqa: D102
        return {"kind": self.kind, "a": list(self.a), "b": list(self.b)}

    def scaled(self, factor: float) -> Fourier:  # noqa: D102
        return dataclasses.replace(self, a=tuple(v * factor for v in self.a), b=tuple(v * factor for v in self.b))


@dataclass(frozen=True)
class Table(Shape):
    """Measured shape: values ``k`` at angles ``theta`` in [0, 2 pi), linear interpolation, periodic.

    Parameters
    ----------
    theta : tuple of float
        Strictly increasing angles (rad) in [0, 2 pi), at least 3.
    k : tuple of float
        Shape values (V s/rad) at those angles.

    """

    theta: tuple[float, ...]
    k: tuple[float, ...]
    kind: ClassVar[str] = "table"

    def __post_init__(self) -> None:
        th = check_array("theta", self.theta, min_len=3)
        k = check_array("k", self.k, min_len=3)
        if th.size != k.size:
            raise BldclabError("k", f"must have as many entries as theta ({th.size}), got {k.size}")
        if th[0] < 0.0 or th[-1] >= TWO_PI:
            raise BldclabError("theta", f"angles must lie in [0, 2 pi) rad, got [{th[0]:g}, {th[-1]:g}] "
                               "(write degrees with theta_unit = \"deg\")")
        bad = np.nonzero(np.diff(th) <= 0.0)[0]
        if bad.size:
            j = int(bad[0])
            raise BldclabError("theta", f"angles must be strictly increasing: entry {j + 1} "
                               f"({th[j + 1]:g} rad) follows {th[j]:g} rad")
        if not np.any(k):
            raise BldclabError("k", "all values are zero: the motor has no back-EMF")
        object.__setattr__(self, "theta", tuple(float(v) for v in th))
        object.__setattr__(self, "k", tuple(float(v) for v in k))

    def __call__(self, theta: ArrayLike) -> NDArray[np.float64]:  # noqa: D102
        x = np.asarray(self.theta)
        return np.interp(np.mod(np.asarray(theta, dtype=float), TWO_PI), x, np.asarray(self.k), period=TWO_PI)

    def breakpoints(self) -> NDArray[np.float64]:  # noqa: D102
        return np.asarray(self.theta)

    def c_form(self) -> tuple[int, NDArray[np.float64], NDArray[np.float64]]:  # noqa: D102
        return 0, np.asarray(self.theta), np.asarray(self.k)

    def fourier(self, n_max: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # noqa: D102
        return _pwl_fourier(np.asarray(self.theta), np.asarray(self.k), n_max)

    def to_toml_dict(self) -> dict[str, Any]:  # noqa: D102
        return {"kind": self.kind, "theta": list(self.theta), "k": list(self.k)}

    def scaled(self, factor: float) -> Table:  # noqa: D102
        return dataclasses.replace(self, k=tuple(v * factor for v in self.k))


SHAPES: dict[str, type[Shape]] = {c.kind: c for c in (Trapezoid, Sinusoid, Fourier, Table)}


@dataclass(frozen=True)
class BackEmf:
    """The three phases' back-EMF shapes, each in its own local angle.

    Parameters
    ----------
    shapes : tuple of Shape
        Shapes of phases a, b, c.

    """

    shapes: tuple[Shape, Shape, Shape]

    def __post_init__(self) -> None:
        if (not isinstance(self.shapes, Sequence) or len(self.shapes) != 3
                or not all(isinstance(s, Shape) for s in self.shapes)):
            raise BldclabError("emf", "needs exactly three shapes (phases a, b, c)")
        object.__setattr__(self, "shapes", tuple(self.shapes))

    @classmethod
    def symmetric(cls, shape: Shape) -> BackEmf:
        """Return a back-EMF with the same shape on the three phases."""
        return cls((shape, shape, shape))

    def scaled(self, factor: float) -> BackEmf:
        """Return the back-EMF with every phase's shape times ``factor`` (> 0)."""
        return BackEmf(tuple(sh.scaled(factor) for sh in self.shapes))  # type: ignore[arg-type]  # three shapes in, three out

    def mean_abs_power(self, q: float) -> float:
        """Return ``sum_x mean_theta |k_x(theta)|^q`` over the three phases ((V s/rad)^q).

        See :meth:`Shape.mean_abs_power`. With ``q = 2``, times ``omega_m^2``: the mean of ``sum_x e_x^2`` at a
        constant speed ``omega_m``, the quantity the iron loss's eddy term scales with.
        """
        return float(sum(sh.mean_abs_power(q) for sh in self.shapes))

    @property
    def is_symmetric(self) -> bool:
        """True if the three phases have equal shapes."""
        return self.shapes[0] == self.shapes[1] == self.shapes[2]

    def k_abc(self, theta_e: ArrayLike) -> NDArray[np.float64]:
        """Evaluate the three shapes at the electrical angle.

        Parameters
        ----------
        theta_e : array_like
            Electrical rotor angle (rad).

        Returns
        -------
        ndarray, shape (3, ...)
            ``k_a, k_b, k_c`` in V s/rad.

        """
        th = np.asarray(theta_e, dtype=float)
        return np.stack([s(th - x * TWO_PI / 3.0) for x, s in enumerate(self.shapes)])

    def line_rms(self) -> float:
        """Return the rms of the line-to-line shapes ``k_x - k_y`` over a period and the three pairs (V s/rad).

        ``sqrt(mean over the pairs of mean (k_x - k_y)^2)`` on 16384 points per period (piecewise-linear shapes:
        relative error about 1e-9); computed once per back-EMF and cached, as :meth:`line_peak`.
        """
        return self._line_rms

    @functools.cached_property
    def _line_rms(self) -> float:
        th = np.arange(1 << 14) * (TWO_PI / (1 << 14))
        k = self.k_abc(th)
        return math.sqrt(float(np.mean([(k[x] - k[y]) ** 2 for x, y in ((0, 1), (1, 2), (2, 0))])))

    def line_peak(self) -> float:
        """Return ``max |k_x - k_y|`` over angles and phase pairs (V s/rad); exact for piecewise-linear.

        Computed once per back-EMF (the shapes are immutable) and cached.
        """
        return self._line_peak

    @functools.cached_property
    def _line_peak(self) -> float:
        pts = [np.linspace(0.0, TWO_PI, 4097)]
        for x, s in enumerate(self.shapes):
            pts.append(np.mod(s.breakpoints() + x * TWO_PI / 3.0, TWO_PI))
        th = np.unique(np.concatenate(pts))
        k = self.k_abc(th)
        best = 0.0
        for x, y in ((0, 1), (1, 2), (2, 0)):
            d = np.abs(k[x] - k[y])
            j = int(np.argmax(d))
            best = max(best, float(d[j]))
            if all(not s.breakpoints().size for s in self.shapes):
                # smooth shapes: refine the maximum by golden-section search around the grid maximum
                lo, hi = th[max(j - 1, 0)], th[min(j + 1, th.size - 1)]
                f = lambda t, x=x, y=y: -abs(float(self.k_abc(t)[x] - self.k_abc(t)[y]))  # noqa: E731
                g = (math.sqrt(5) - 1) / 2
                for _ in range(60):
                    c1, c2 = hi - g * (hi - lo), lo + g * (hi - lo)
                    if f(c1) < f(c2):
                        hi = c2
                    else:
                        lo = c1
                best = max(best, -f(0.5 * (lo + hi)))
        return best


@dataclass(frozen=True)
class Cogging:
    """Cogging torque ``tau_cog = sum_j A_j sin(n_j theta_m + phi_j)`` (mechanical angle).

    Parameters
    ----------
    orders : tuple of int
        Harmonic orders ``n_j`` >= 1 in the mechanical angle.
    amplitudes : tuple of float
        ``A_j`` (N m).
    phases : tuple of float
        ``phi_j`` (rad).

    """

    orders: tuple[int, ...]
    amplitudes: tuple[float, ...]
    phases: tuple[float, ...]

    def __post_init__(self) -> None:
        if isinstance(self.orders, str | bytes) or not isinstance(self.orders, Sequence | np.ndarray):
            raise BldclabError("orders", f"expected a list of integers, got {type(self.orders).__name__}")
        n = len(self.orders)
        if n == 0:
            raise BldclabError("orders", "needs at least one harmonic")
        for j, o in enumerate(self.orders):
            if isinstance(o, bool) or not isinstance(o, int | np.integer) or o < 1:
                raise BldclabError(f"orders[{j}]", f"must be an integer >= 1, got {o!r}")
        amplitudes = check_array("amplitudes", self.amplitudes)
        phases = check_array("phases", self.phases)
        for name, arr in (("amplitudes", amplitudes), ("phases", phases)):
            if arr.size != n:
                raise BldclabError(name, f"must have as many entries as orders ({n}), got {arr.size}")
        object.__setattr__(self, "orders", tuple(int(o) for o in self.orders))
        object.__setattr__(self, "amplitudes", tuple(float(v) for v in amplitudes))
        object.__setattr__(self, "phases", tuple(float(v) for v in phases))

    def __call__(self, theta_m: ArrayLike) -> NDArray[np.float64]:
        """Evaluate the cogging torque (N m) at the mechanical angle ``theta_m`` (rad)."""
        t = np.asarray(theta_m, dtype=float)
        return sum((a * np.sin(n * t + ph) for n, a, ph in zip(self.orders, self.amplitudes, self.phases,
                                                               strict=True)), np.zeros_like(t))

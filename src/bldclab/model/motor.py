"""Drive parameters: the motor, its back-EMF shapes, the inverter, the mechanics and the sensors.

Every class is a frozen dataclass in SI units that validates itself on construction and raises
:class:`~bldclab.errors.BldclabError` naming the offending field. A :class:`Drive` bundles them and
reads and writes TOML motor files (format in ``docs/motor-files.md``).

Back-EMF shapes ``k_x(theta_x)`` are in V s/rad (per mechanical rad/s) as a function of the phase's
own electrical angle ``theta_x = theta_e - x 2 pi/3`` (``docs/conventions.md``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._files import read_toml
from ..errors import BldclabError
from .units import to_si

__all__ = [
    "TWO_PI",
    "BackEmf",
    "Cogging",
    "Drive",
    "Fourier",
    "Inverter",
    "Mechanics",
    "Motor",
    "Sensors",
    "Shape",
    "Sinusoid",
    "Table",
    "Trapezoid",
]

TWO_PI = 2.0 * math.pi


# ----------------------------------------------------------------------------------------------------------
# validation helpers


def _num(name: str, value: object, *, lo: float | None = None, lo_open: bool = False,
         hi: float | None = None, hi_open: bool = False, allow_none: bool = False) -> None:
    """Check one scalar field: a real, finite number within bounds, else raise naming ``name``."""
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise BldclabError(name, f"expected a number, got {type(value).__name__} ({value!r})")
    v = float(value)
    if math.isnan(v):
        raise BldclabError(name, "is NaN")
    if math.isinf(v):
        raise BldclabError(name, "is infinite")
    if lo is not None and (v < lo or (lo_open and v == lo)):
        rel = ">" if lo_open else ">="
        raise BldclabError(name, f"must be {rel} {lo:g}, got {v:g}")
    if hi is not None and (v > hi or (hi_open and v == hi)):
        rel = "<" if hi_open else "<="
        raise BldclabError(name, f"must be {rel} {hi:g}, got {v:g}")


def _array(name: str, values: object, *, min_len: int = 1) -> NDArray[np.float64]:
    """Check a sequence of finite numbers (no holes) and return it as a float array."""
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray):
        raise BldclabError(name, f"expected a list of numbers, got {type(values).__name__}")
    for j, v in enumerate(values):
        if v is None:
            raise BldclabError(name, f"entry {j} is missing (hole in the data)")
        if isinstance(v, bool) or not isinstance(v, int | float | np.floating | np.integer):
            raise BldclabError(name, f"entry {j} is not a number ({v!r})")
        if not math.isfinite(float(v)):
            raise BldclabError(name, f"entry {j} is {float(v)} (NaN or infinite; hole in the data?)")
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1:
        raise BldclabError(name, "must be a one-dimensional list")
    if arr.size < min_len:
        raise BldclabError(name, f"needs at least {min_len} entries, got {arr.size}")
    return arr


# ----------------------------------------------------------------------------------------------------------
# back-EMF shapes


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
        _num("k_phi", self.k_phi, lo=0.0, lo_open=True)
        _num("flat_top", self.flat_top, lo=0.0, hi=math.pi, hi_open=True)

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
        _num("k_1", self.k_1, lo=0.0, lo_open=True)

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
        a = _array("a", self.a, min_len=2)
        b = _array("b", self.b, min_len=2)
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
        th = _array("theta", self.theta, min_len=3)
        k = _array("k", self.k, min_len=3)
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


_SHAPES: dict[str, type[Shape]] = {c.kind: c for c in (Trapezoid, Sinusoid, Fourier, Table)}


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
        amplitudes = _array("amplitudes", self.amplitudes)
        phases = _array("phases", self.phases)
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


# ----------------------------------------------------------------------------------------------------------
# the drive


@dataclass(frozen=True)
class Motor:
    """The PM brushless motor (star connected, no neutral).

    Parameters
    ----------
    p : int
        Pole pairs.
    R : float
        Phase resistance (Ohm), >= 0 (0 gives paper 1's idealisation).
    L : float
        Inclusive phase inductance ``L_self - M`` (H), > 0.
    emf : BackEmf
        Back-EMF shapes.
    V_N : float
        Nominal voltage (V), > 0.
    I_N : float
        Nominal current (A): the square-wave current amplitude of the rating, > 0.
    Omega_N : float, optional
        Conventional nominal speed (rad/s); default paper 1 (2): ``(V_N - 2 R I_N) / (2 k_phi)``.
    T_peak : float, optional
        Peak torque (N m), informative.
    cogging : Cogging, optional
        Cogging torque.

    """

    p: int
    R: float
    L: float
    emf: BackEmf
    V_N: float
    I_N: float
    Omega_N: float | None = None
    T_peak: float | None = None
    cogging: Cogging | None = None

    def __post_init__(self) -> None:
        if isinstance(self.p, bool) or not isinstance(self.p, int | np.integer) or self.p < 1:
            raise BldclabError("p", f"pole pairs must be an integer >= 1, got {self.p!r}")
        _num("R", self.R, lo=0.0)
        _num("L", self.L, lo=0.0, lo_open=True)
        _num("V_N", self.V_N, lo=0.0, lo_open=True)
        _num("I_N", self.I_N, lo=0.0, lo_open=True)
        _num("Omega_N", self.Omega_N, lo=0.0, lo_open=True, allow_none=True)
        _num("T_peak", self.T_peak, lo=0.0, lo_open=True, allow_none=True)
        if not isinstance(self.emf, BackEmf):
            raise BldclabError("emf", "must be a BackEmf")
        if self.Omega_N is None and self.V_N - 2.0 * self.R * self.I_N <= 0.0:
            raise BldclabError("R", "2 R I_N exceeds V_N: no positive nominal speed")

    @property
    def k_phi(self) -> float:
        """Motor constant (V s/rad): half the peak line-to-line shape; the flat top of an ideal trapezoid."""
        return 0.5 * self.emf.line_peak()

    @property
    def T_N(self) -> float:
        """Nominal torque ``2 k_phi I_N`` (N m), paper 1 (6): the torque base."""
        return 2.0 * self.k_phi * self.I_N

    @property
    def Omega_nominal(self) -> float:
        """``Omega_N`` if given, else paper 1 (2) (rad/s)."""
        if self.Omega_N is not None:
            return float(self.Omega_N)
        return (self.V_N - 2.0 * self.R * self.I_N) / (2.0 * self.k_phi)


@dataclass(frozen=True)
class Inverter:
    """Two-level three-phase voltage source inverter.

    Parameters
    ----------
    V_dc : float
        DC source voltage (V), > 0.
    f_pwm : float
        PWM carrier frequency (Hz), > 0. Controllers are sampled at ``2 f_pwm``.
    t_dead : float
        Dead time (s), >= 0, below a quarter period.
    R_on : float
        Switch on-resistance (Ohm), >= 0.
    V_f : float
        Diode forward voltage (V), >= 0.
    r_d : float
        Diode slope resistance (Ohm), >= 0.
    R_src : float
        DC source internal resistance (Ohm), >= 0.
    i_trip : float
        Hardware over-current protection (A): a phase current reaching it switches every gate off, latched, as the
        comparators of a gate driver do, whatever the firmware does. 0 (default): none.
    model : str
        ``"switching"`` (default): every gate edge, dead time and diode transition inside the PWM period.
        ``"average"``: a leg that switches inside a half PWM period applies its half-period average (the
        averaged inverter of motulator and gym-electric-motor, paper 1's ideal current limiter); diodes, the open
        phase and the trip stay, dead time inside PWM is neglected. Faster, no PWM ripple (docs/plant.md).

    """

    V_dc: float
    f_pwm: float
    t_dead: float = 0.0
    R_on: float = 0.0
    V_f: float = 0.0
    r_d: float = 0.0
    R_src: float = 0.0
    i_trip: float = 0.0
    model: str = "switching"

    MODELS: ClassVar[tuple[str, ...]] = ("switching", "average")

    def __post_init__(self) -> None:
        _num("V_dc", self.V_dc, lo=0.0, lo_open=True)
        _num("f_pwm", self.f_pwm, lo=0.0, lo_open=True, hi=1e7)
        _num("t_dead", self.t_dead, lo=0.0)
        if self.t_dead >= 0.25 / self.f_pwm:
            raise BldclabError("t_dead", f"must be below a quarter PWM period ({0.25 / self.f_pwm:g} s at "
                               f"f_pwm = {self.f_pwm:g} Hz), got {self.t_dead:g} s")
        for name in ("R_on", "V_f", "r_d", "R_src", "i_trip"):
            _num(name, getattr(self, name), lo=0.0)
        if self.model not in self.MODELS:
            raise BldclabError("model", f"must be one of {', '.join(self.MODELS)}, got {self.model!r}")


@dataclass(frozen=True)
class Mechanics:
    """Rotor mechanics ``J dw/dt = tau_e - tau_L - B w - tau_c sign(w)``.

    Parameters
    ----------
    J : float
        Inertia of rotor and load (kg m^2), > 0.
    B : float
        Viscous friction (N m s/rad), >= 0.
    tau_c : float
        Coulomb friction (N m), >= 0.

    """

    J: float = 1e-3
    B: float = 0.0
    tau_c: float = 0.0

    def __post_init__(self) -> None:
        _num("J", self.J, lo=0.0, lo_open=True)
        _num("B", self.B, lo=0.0)
        _num("tau_c", self.tau_c, lo=0.0)


_PHASES = "abc"


@dataclass(frozen=True)
class Sensors:
    """Measurement chain seen by the controller.

    Parameters
    ----------
    current_phases : str
        Which phase currents are measured, e.g. ``"ab"`` (default), ``"ac"``, ``"abc"``.
    current_gain, current_offset : tuple of float
        Per-phase gain (-) and offset (A).
    current_noise : float
        Standard deviation of white measurement noise (A).
    current_lsb : float
        Quantisation step (A), 0 for none.
    vdc_gain, vdc_offset, vdc_noise, vdc_lsb : float
        Same for the DC-bus voltage (-, V, V, V).
    hall_error : tuple of float
        Angle error of each Hall sensor (rad, electrical): its edges move by this angle.
    hall_delay : float
        Delay of every Hall edge (s).
    f_tick : float
        Capture-timer frequency (Hz) used to time-stamp Hall edges.
    seed : int
        Seed of the noise generator (runs are deterministic).

    """

    current_phases: str = "ab"
    current_gain: tuple[float, float, float] = (1.0, 1.0, 1.0)
    current_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    current_noise: float = 0.0
    current_lsb: float = 0.0
    vdc_gain: float = 1.0
    vdc_offset: float = 0.0
    vdc_noise: float = 0.0
    vdc_lsb: float = 0.0
    hall_error: tuple[float, float, float] = (0.0, 0.0, 0.0)
    hall_delay: float = 0.0
    f_tick: float = 10e6
    seed: int = 1

    def __post_init__(self) -> None:
        ph = self.current_phases
        if not isinstance(ph, str) or not ph or any(c not in _PHASES for c in ph) or len(set(ph)) != len(ph):
            raise BldclabError("current_phases", f"must be letters from 'abc' without repeats, got {ph!r}")
        if len(ph) < 2:
            raise BldclabError("current_phases", "at least two phases must be measured")
        for name in ("current_gain", "current_offset", "hall_error"):
            v = getattr(self, name)
            if isinstance(v, str | bytes) or not isinstance(v, Sequence | np.ndarray):
                raise BldclabError(name, f"expected three numbers (a, b, c), got {type(v).__name__}")
            if len(v) != 3:
                raise BldclabError(name, f"needs three entries (a, b, c), got {len(v)}")
            for j, x in enumerate(v):
                _num(f"{name}[{j}]", x)
            object.__setattr__(self, name, tuple(float(x) for x in v))
        for name in ("current_noise", "current_lsb", "vdc_noise", "vdc_lsb", "hall_delay"):
            _num(name, getattr(self, name), lo=0.0)
        _num("vdc_gain", self.vdc_gain)
        _num("vdc_offset", self.vdc_offset)
        _num("f_tick", self.f_tick, lo=1e3, hi=1e10)
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise BldclabError("seed", f"must be an integer >= 0, got {self.seed!r}")

    @property
    def current_mask(self) -> int:
        """Bit mask of measured phases (bit 0 = a)."""
        return sum(1 << _PHASES.index(c) for c in self.current_phases)


@dataclass(frozen=True)
class Drive:
    """A complete drive: motor, inverter, mechanics and sensors.

    Parameters
    ----------
    motor : Motor
    inverter : Inverter
    mechanics : Mechanics
    sensors : Sensors
    name : str
        Short name (catalog key or file stem).
    description : str
        Free text: where the data come from.

    """

    motor: Motor
    inverter: Inverter
    mechanics: Mechanics = field(default_factory=Mechanics)
    sensors: Sensors = field(default_factory=Sensors)
    name: str = ""
    description: str = ""

    def __post_init__(self) -> None:
        parts = (("motor", Motor), ("inverter", Inverter), ("mechanics", Mechanics), ("sensors", Sensors))
        for part, cls in parts:
            value = getattr(self, part)
            if not isinstance(value, cls):
                raise BldclabError(part, f"must be a {cls.__name__}, got {type(value).__name__}")
        for key in ("name", "description"):
            if not isinstance(getattr(self, key), str):
                raise BldclabError(key, f"expected a string, got {getattr(self, key)!r}")

    def scaled(self, *, R: float = 1.0, L: float = 1.0, emf: float = 1.0) -> Drive:
        """Return the drive with the motor's resistance, inductance and back-EMF scaled (a controller's estimate).

        For parameter-mismatch studies: ``bl.simulate(drive, control, scenario, estimate=drive.scaled(L=1.2))``
        configures the controller for an inductance 20 % above the plant's.

        Parameters
        ----------
        R, L, emf : float
            Factors (> 0, finite) on ``motor.R``, ``motor.L`` and every phase's back-EMF shape (so on ``k_phi``).

        Returns
        -------
        Drive
            The scaled copy, named ``<name> (estimate)``.

        Raises
        ------
        BldclabError
            Naming the factor that is not a finite number > 0.
        """
        for key, f in (("R", R), ("L", L), ("emf", emf)):
            if isinstance(f, bool) or not isinstance(f, int | float) or not math.isfinite(f) or f <= 0:
                raise BldclabError(f"scaled.{key}", f"must be a finite factor > 0, got {f!r}")
        m = self.motor
        motor = dataclasses.replace(m, R=m.R * R, L=m.L * L, emf=m.emf.scaled(emf) if emf != 1.0 else m.emf)
        return dataclasses.replace(self, motor=motor, name=f"{self.name} (estimate)")

    @property
    def Omega_0(self) -> float:
        """Speed base: no-load speed ``V_dc / (2 k_phi)`` (rad/s), paper 1 (2)."""
        return self.inverter.V_dc / (2.0 * self.motor.k_phi)

    @property
    def T_N(self) -> float:
        """Torque base ``2 k_phi I_N`` (N m)."""
        return self.motor.T_N

    def replace(self, **changes: Any) -> Drive:
        """Return a copy with fields changed; ``motor__R=0.0`` changes a field of a part.

        Parameters
        ----------
        **changes
            ``part__field=value`` or ``part=new_part`` (part in motor, inverter, mechanics, sensors) or
            ``name=...``/``description=...``.

        """
        parts: dict[str, dict[str, Any]] = {}
        top: dict[str, Any] = {}
        for key, value in changes.items():
            if "__" in key:
                part, name = key.split("__", 1)
                if part not in ("motor", "inverter", "mechanics", "sensors"):
                    raise BldclabError(key, f"unknown part {part!r}")
                parts.setdefault(part, {})[name] = value
            else:
                top[key] = value
        for part, kw in parts.items():
            obj = top.get(part, getattr(self, part))
            unknown = set(kw) - {f.name for f in dataclasses.fields(obj)}
            if unknown:
                raise BldclabError(f"{part}.{sorted(unknown)[0]}", "no such field")
            top[part] = dataclasses.replace(obj, **kw)
        return dataclasses.replace(self, **top)

    # ------------------------------------------------------------------------------------------------------
    # files

    @classmethod
    def from_toml(cls, path: str | Path) -> Drive:
        """Read a motor file.

        Parameters
        ----------
        path : str or Path
            TOML file (format: ``docs/motor-files.md``).

        Raises
        ------
        BldclabError
            For an unreadable file, a syntax error, or any missing, mistyped or out-of-range field.

        """
        p = Path(path)
        data = read_toml(p, "motor file")
        return cls.from_dict(data, source=str(p), default_name=p.stem)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None, default_name: str = "") -> Drive:
        """Build a drive from the parsed TOML structure (see :meth:`from_toml`)."""
        try:
            return _drive_from_dict(data, default_name)
        except BldclabError as exc:
            raise BldclabError(exc.field, exc.problem, source) from None

    def to_toml(self) -> str:
        """Return the drive as a TOML motor file (SI numbers)."""
        return _drive_to_toml(self)


# ----------------------------------------------------------------------------------------------------------
# TOML reading


class _Section:
    """A TOML table being read: typed accessors that name the field and reject unknown keys."""

    def __init__(self, data: object, prefix: str) -> None:
        if not isinstance(data, Mapping):
            raise BldclabError(prefix or "file", f"must be a table, got {type(data).__name__}")
        self.data = data
        self.prefix = prefix
        self.used: set[str] = set()

    def name(self, key: str) -> str:
        return f"{self.prefix}.{key}" if self.prefix else key

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: object = ...) -> object:
        self.used.add(key)
        if key not in self.data:
            if default is ...:
                raise BldclabError(self.name(key), "is missing")
            return default
        return self.data[key]

    def quantity(self, key: str, dim: str, default: object = ...) -> Any:
        v = self.raw(key, default)
        if v is None or (v is default and default is not ...):
            return v
        return to_si(v, dim, self.name(key))

    def integer(self, key: str, default: object = ...) -> Any:
        v = self.raw(key, default)
        if v is default and default is not ...:
            return v
        if isinstance(v, bool) or not isinstance(v, int):
            raise BldclabError(self.name(key), f"expected an integer, got {v!r}")
        return v

    def string(self, key: str, default: object = ...) -> Any:
        v = self.raw(key, default)
        if v is default and default is not ...:
            return v
        if not isinstance(v, str):
            raise BldclabError(self.name(key), f"expected a string, got {v!r}")
        return v

    def numbers(self, key: str, scale: float = 1.0) -> list[float]:
        v = self.raw(key)
        arr = _array(self.name(key), v)
        return [float(x) * scale for x in arr]

    def sub(self, key: str) -> _Section | None:
        if key not in self.data:
            self.used.add(key)
            return None
        return _Section(self.raw(key), self.name(key))

    def finish(self) -> None:
        extra = sorted(set(self.data) - self.used)
        if extra:
            raise BldclabError(self.name(extra[0]), "unknown field (misspelt?)")


def _wrap(prefix: str, fn: Any, *args: Any, **kw: Any) -> Any:
    """Call a dataclass constructor, prefixing the field name of its validation error."""
    try:
        return fn(*args, **kw)
    except BldclabError as exc:
        raise BldclabError(f"{prefix}.{exc.field}", exc.problem) from None
    except TypeError as exc:
        raise BldclabError(prefix, str(exc)) from None


def _unit_scale(sec: _Section, key: str, default: str, dim: str) -> float:
    """Read a unit-name field (``unit``, ``theta_unit``) and return its factor to SI."""
    unit = sec.string(key, default)
    return to_si(f"1 {unit}", dim, sec.name(key))


def _shape_from(sec: _Section, phase: int | None) -> Shape:
    """Read one shape; ``phase`` (0, 1, 2) reads the per-phase table column ``k_a``/``k_b``/``k_c``."""
    kind = sec.string("kind")
    if kind not in _SHAPES:
        raise BldclabError(sec.name("kind"), f"unknown shape {kind!r} (use one of {', '.join(_SHAPES)})")
    if kind == "trapezoid":
        shape: Shape = _wrap(sec.prefix, Trapezoid, sec.quantity("k_phi", "emf_constant"),
                             sec.quantity("flat_top", "angle", TWO_PI / 3.0))
    elif kind == "sinusoid":
        shape = _wrap(sec.prefix, Sinusoid, sec.quantity("k_1", "emf_constant"))
    elif kind == "fourier":
        k_scale = _unit_scale(sec, "unit", "V s/rad", "emf_constant")
        shape = _wrap(sec.prefix, Fourier, tuple(sec.numbers("a", k_scale)), tuple(sec.numbers("b", k_scale)))
    else:
        k_scale = _unit_scale(sec, "unit", "V s/rad", "emf_constant")
        th_scale = _unit_scale(sec, "theta_unit", "rad", "angle")
        theta = tuple(sec.numbers("theta", th_scale))
        key = "k" if phase is None else "k_" + _PHASES[phase]
        k = tuple(sec.numbers(key, k_scale))
        try:
            shape = Table(theta, k)
        except BldclabError as exc:
            field_ = key if exc.field == "k" else exc.field  # name the column the file has (k_a, k_b, k_c)
            raise BldclabError(sec.name(field_), exc.problem) from None
    return shape


def _emf_from(sec: _Section) -> BackEmf:
    if sec.has("phase"):
        phases = sec.raw("phase")
        if not isinstance(phases, list) or len(phases) != 3:
            raise BldclabError(sec.name("phase"), "needs exactly three [[motor.emf.phase]] tables (a, b, c)")
        others = sorted(set(sec.data) - {"phase"})
        if others:
            raise BldclabError(sec.name(others[0]), "not allowed next to [[motor.emf.phase]]: give each "
                               "phase's shape in its own [[motor.emf.phase]] table")
        shapes = []
        for j, ph in enumerate(phases):
            s = _Section(ph, f"{sec.name('phase')}[{j}]")
            shapes.append(_shape_from(s, None))
            s.finish()
        sec.finish()
        return BackEmf((shapes[0], shapes[1], shapes[2]))
    if sec.data.get("kind") == "table" and not sec.has("k") and any(sec.has(f"k_{x}") for x in _PHASES):
        shapes = [_shape_from(sec, j) for j in range(3)]
        sec.finish()
        return BackEmf((shapes[0], shapes[1], shapes[2]))
    shape = _shape_from(sec, None)
    sec.finish()
    return BackEmf.symmetric(shape)


def _drive_from_dict(data: Mapping[str, Any], default_name: str) -> Drive:
    top = _Section(data, "")
    name = top.string("name", default_name)
    description = top.string("description", "")
    ms = top.sub("motor")
    if ms is None:
        raise BldclabError("motor", "is missing (a [motor] table is required)")
    es = ms.sub("emf")
    if es is None:
        raise BldclabError("motor.emf", "is missing (a [motor.emf] table is required)")
    emf = _emf_from(es)
    cog = None
    cs = ms.sub("cogging")
    if cs is not None:
        orders = cs.raw("orders")
        if not isinstance(orders, list):
            raise BldclabError(cs.name("orders"), "expected a list of integers")
        cog = _wrap(cs.prefix, Cogging, tuple(orders), tuple(cs.numbers("amplitudes")),
                    tuple(cs.numbers("phases")))
        cs.finish()
    motor = _wrap("motor", Motor, p=ms.integer("p"), R=ms.quantity("R", "resistance"),
                  L=ms.quantity("L", "inductance"), emf=emf, V_N=ms.quantity("V_N", "voltage"),
                  I_N=ms.quantity("I_N", "current"), Omega_N=ms.quantity("Omega_N", "speed", None),
                  T_peak=ms.quantity("T_peak", "torque", None), cogging=cog)
    ms.finish()

    inv_s = top.sub("inverter")
    if inv_s is None:
        raise BldclabError("inverter", "is missing (an [inverter] table with V_dc and f_pwm is required)")
    inverter = _wrap("inverter", Inverter, V_dc=inv_s.quantity("V_dc", "voltage"),
                     f_pwm=inv_s.quantity("f_pwm", "frequency"),
                     t_dead=inv_s.quantity("t_dead", "time", 0.0),
                     R_on=inv_s.quantity("R_on", "resistance", 0.0),
                     V_f=inv_s.quantity("V_f", "voltage", 0.0), r_d=inv_s.quantity("r_d", "resistance", 0.0),
                     R_src=inv_s.quantity("R_src", "resistance", 0.0),
                     i_trip=inv_s.quantity("i_trip", "current", 0.0),
                     model=inv_s.string("model", "switching"))
    inv_s.finish()

    mech = Mechanics()
    mech_s = top.sub("mechanics")
    if mech_s is not None:
        mech = _wrap("mechanics", Mechanics, J=mech_s.quantity("J", "inertia"),
                     B=mech_s.quantity("B", "damping", 0.0), tau_c=mech_s.quantity("tau_c", "torque", 0.0))
        mech_s.finish()

    sensors = Sensors()
    ss = top.sub("sensors")
    if ss is not None:
        kw: dict[str, Any] = {}
        if ss.has("current_phases"):
            kw["current_phases"] = ss.string("current_phases")
        for key, dim in (("current_gain", "dimensionless"), ("current_offset", "current"),
                         ("hall_error", "angle")):
            if ss.has(key):
                raw = ss.raw(key)
                if not isinstance(raw, list):
                    raise BldclabError(ss.name(key), "expected a list of three values (a, b, c)")
                kw[key] = tuple(to_si(v, dim, f"{ss.name(key)}[{j}]") for j, v in enumerate(raw))
        for key, dim in (("current_noise", "current"), ("current_lsb", "current"),
                         ("vdc_gain", "dimensionless"),
                         ("vdc_offset", "voltage"), ("vdc_noise", "voltage"), ("vdc_lsb", "voltage"),
                         ("hall_delay", "time"), ("f_tick", "frequency")):
            if ss.has(key):
                kw[key] = ss.quantity(key, dim)
        if ss.has("seed"):
            kw["seed"] = ss.integer("seed")
        sensors = _wrap("sensors", Sensors, **kw)
        ss.finish()
    top.finish()
    return Drive(motor=motor, inverter=inverter, mechanics=mech, sensors=sensors, name=name,
                 description=description)


# ----------------------------------------------------------------------------------------------------------
# TOML writing (the subset bldclab writes: tables of numbers, strings and lists)


def _fmt_str(v: str) -> str:
    """Return ``v`` as a TOML basic string: backslash, quote and every control character escaped."""
    out = []
    for ch in v:
        if ch in ('"', "\\"):
            out.append("\\" + ch)
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _fmt(v: object) -> str:
    if isinstance(v, bool | np.bool_):
        return "true" if v else "false"
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        return repr(float(v))  # shortest repr: reads back to the same double (numpy's repr is not TOML)
    if isinstance(v, str):
        return _fmt_str(v)
    if isinstance(v, list | tuple):
        items = [_fmt(x) for x in v]
        if len(items) <= 8:
            return "[" + ", ".join(items) + "]"
        lines = [", ".join(items[j:j + 8]) for j in range(0, len(items), 8)]
        return "[\n    " + ",\n    ".join(lines) + ",\n]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _table(header: str, items: Mapping[str, object]) -> str:
    lines = [f"[{header}]"] if header else []
    lines += [f"{k} = {_fmt(v)}" for k, v in items.items() if v is not None]
    return "\n".join(lines) + "\n"


def _drive_to_toml(d: Drive) -> str:
    out = [_table("", {"name": d.name, "description": d.description})]
    m = d.motor
    out.append(_table("motor", {"p": int(m.p), "R": float(m.R), "L": float(m.L), "V_N": float(m.V_N),
                                "I_N": float(m.I_N), "Omega_N": m.Omega_N, "T_peak": m.T_peak}))
    shapes = m.emf.shapes
    if m.emf.is_symmetric:
        out.append(_table("motor.emf", shapes[0].to_toml_dict()))
    elif len(tables := [s for s in shapes if isinstance(s, Table)]) == len(shapes) \
            and len({t.theta for t in tables}) == 1:
        items: dict[str, object] = {"kind": "table", "theta": list(tables[0].theta)}
        for j, t in enumerate(tables):
            items["k_" + _PHASES[j]] = list(t.k)
        out.append(_table("motor.emf", items))
    else:
        for s in shapes:
            out.append("[[motor.emf.phase]]\n" + _table("", s.to_toml_dict()))
    if m.cogging is not None:
        c = m.cogging
        out.append(_table("motor.cogging", {"orders": list(c.orders), "amplitudes": list(c.amplitudes),
                                            "phases": list(c.phases)}))
    inv = dataclasses.asdict(d.inverter)
    if inv["model"] == "switching":
        del inv["model"]  # the default: files written before the averaged inverter existed stay as they were
    out.append(_table("inverter", inv))
    out.append(_table("mechanics", dataclasses.asdict(d.mechanics)))
    sen = dataclasses.asdict(d.sensors)
    sen["current_gain"] = list(sen["current_gain"])
    sen["current_offset"] = list(sen["current_offset"])
    sen["hall_error"] = list(sen["hall_error"])
    out.append(_table("sensors", sen))
    return "\n".join(out)

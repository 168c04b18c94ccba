"""R-aware base speeds, computed numerically from the drive's own back-EMF shapes.

Paper 1 section IV.B: "a numerical computation has been executed ...". They drop the closed forms' premise "R
neglected" (and that of the ideal trapezoid); with ``R = 0`` and an ideal trapezoid they equal (21) and (30).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ...errors import BldclabError
from ..emf import TWO_PI
from ..motor import Drive
from .bases import i_sN, omega_0, r_total

__all__ = [
    "omega_qB_numeric_pu",
    "omega_sB_numeric_pu",
]


def _bisect(f: Callable[[float], float], lo: float, hi: float, xtol: float) -> float:
    """Return the last point with ``f >= 0`` in [lo, hi] by bisection, given ``f(lo) >= 0 > f(hi)``."""
    for _ in range(200):
        if hi - lo <= xtol:
            break
        mid = 0.5 * (lo + hi)
        if f(mid) >= 0.0:
            lo = mid
        else:
            hi = mid
    return lo


def _golden_argmax(f: Callable[[float], float], lo: float, hi: float, iters: int = 80) -> float:
    """Return the argument of the maximum of a unimodal ``f`` on [lo, hi] (golden-section search)."""
    g = (math.sqrt(5.0) - 1.0) / 2.0
    c1, c2 = hi - g * (hi - lo), lo + g * (hi - lo)
    f1, f2 = f(c1), f(c2)
    for _ in range(iters):
        if f1 >= f2:
            hi, c2, f2 = c2, c1, f1
            c1 = hi - g * (hi - lo)
            f1 = f(c1)
        else:
            lo, c1, f1 = c1, c2, f2
            c2 = lo + g * (hi - lo)
            f2 = f(c2)
    return c1 if f1 >= f2 else c2


def _resistance(drive: Drive, R: float | None) -> float:
    """Return the resistance to use: ``R`` if given (checked), else :func:`r_total`."""
    if R is None:
        return r_total(drive)
    if isinstance(R, bool) or not isinstance(R, int | float | np.floating) or not math.isfinite(R) or R < 0.0:
        raise BldclabError("R", f"must be a finite resistance >= 0 Ohm, got {R!r}")
    return float(R)


_PAIRS = ((0, 1), (1, 2), (2, 0))


def _fundamental_phase(drive: Drive) -> float:
    """Return ``phi`` of phase a's back-EMF fundamental ``K sin(theta + phi)`` (rad; 0 for a trapezoid)."""
    a1, b1 = (float(c[1]) for c in drive.motor.emf.shapes[0].fourier(1))
    return math.atan2(a1, b1)


def _line_voltage_parts(drive: Drive, r: float, phi: float, theta: NDArray[np.float64]
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Split the line-to-line voltages at nominal sinusoidal current as ``v = A + Omega B``.

    ``A = R (i_x - i_y)`` (V) and ``B = p L d(i_x - i_y)/dtheta + k_x - k_y`` (V s/rad) for the pairs ab, bc,
    ca; balanced currents ``I_s,N sin(theta + phi - x 2 pi/3)`` in phase with the back-EMF fundamental.
    Shape (3, n).
    """
    m = drive.motor
    i_s = i_sN(drive)
    ph = theta + phi
    k = m.emf.k_abc(theta)
    A, B = [], []
    for x, y in _PAIRS:
        di = i_s * (np.sin(ph - x * TWO_PI / 3.0) - np.sin(ph - y * TWO_PI / 3.0))
        ddi = i_s * (np.cos(ph - x * TWO_PI / 3.0) - np.cos(ph - y * TWO_PI / 3.0))
        A.append(r * di)
        B.append(m.p * m.L * ddi + (k[x] - k[y]))
    return np.array(A), np.array(B)


def omega_sB_numeric_pu(drive: Drive, R: float | None = None, n_grid: int = 2048) -> float:
    """Return the R-aware base speed with sinusoidal supply, computed numerically (per unit of Omega_0).

    The largest speed at which the inverter (linear modulation: peak line-to-line voltage ``<= V_dc``) can
    impress balanced sinusoidal currents of peak ``I_s,N`` (8) in phase with the fundamental of phase a's
    back-EMF:

    ``v_xy(theta) = R (i_x - i_y) + p Omega L d(i_x - i_y)/dtheta + Omega (k_x(theta) - k_y(theta))``

    (paper 1 (16) with R). Its peak over a period and the three line pairs is taken on an angle grid that
    holds every corner of the back-EMF shapes; the speed where it equals ``V_dc`` is found by bisection (the
    peak is convex in the speed, so the root is unique). Smooth maxima between grid points are then located by
    golden-section search, added to the grid, and the bisection repeated. With ``R = 0`` and an ideal
    trapezoid the result equals (21) whenever (18) holds; otherwise (21) is only an approximation and this is
    exact. It is not capped at 1: a back-EMF whose line-to-line peak is reached at isolated angles (rounded or
    sinusoidal shapes) can keep the required voltage below ``V_dc`` slightly above ``Omega_0``.

    Parameters
    ----------
    drive : Drive
        Uses the drive's own back-EMF shapes, ``p``, ``L``, ``I_N`` and ``V_dc``.
    R : float, optional
        Series resistance (Ohm); default :func:`r_total`.
    n_grid : int
        Angle grid points per electrical period (before adding the shape corners).

    Returns
    -------
    float
        Speed (per unit of Omega_0).

    Raises
    ------
    BldclabError
        If the resistive drop alone reaches the DC bus.

    """
    m = drive.motor
    r = _resistance(drive, R)
    V = drive.inverter.V_dc
    w0 = omega_0(drive)
    pts = [np.linspace(0.0, TWO_PI, n_grid, endpoint=False)]
    for x, s in enumerate(m.emf.shapes):
        pts.append(np.mod(s.breakpoints() + x * TWO_PI / 3.0, TWO_PI))
    grid = np.unique(np.concatenate(pts))
    phi = _fundamental_phase(drive)
    A, B = _line_voltage_parts(drive, r, phi, grid)
    if float(np.max(np.abs(A))) >= V:
        raise BldclabError("motor.R", f"the resistive drop {float(np.max(np.abs(A))):g} V alone reaches the "
                           f"DC bus {V:g} V")

    def margin(omega: float) -> float:
        return V - float(np.max(np.abs(A + omega * B)))

    hi = w0
    while margin(hi) >= 0.0:
        hi *= 2.0
    omega = _bisect(margin, 0.0, hi, 1e-14 * w0)
    for _ in range(2):
        # locate the smooth maxima near the grid maxima at this speed and add them to the grid
        extra = []
        v = np.abs(A + omega * B)
        for row in range(3):
            j = int(np.argmax(v[row]))
            lo = grid[j - 1] if j > 0 else grid[-1] - TWO_PI
            hi_t = grid[j + 1] if j + 1 < grid.size else grid[0] + TWO_PI

            def fv(t: float, row: int = row, om: float = omega) -> float:
                a, b = _line_voltage_parts(drive, r, phi, np.array([t]))
                return float(abs(a[row, 0] + om * b[row, 0]))

            extra.append(np.mod(_golden_argmax(fv, float(lo), float(hi_t)), TWO_PI))
        grid = np.unique(np.concatenate([grid, extra]))
        A, B = _line_voltage_parts(drive, r, phi, grid)
        omega = _bisect(margin, 0.0, omega * (1.0 + 1e-9), 1e-14 * w0)
    return omega / w0


#: 120-degree conduction per sector s = 0..5 (conventions.md): (phase tied to +, phase tied to -).
_CONDUCTION = ((0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1))


def _phi(z: float) -> tuple[float, float, float]:
    """Return ``phi_n(z) = integral of exp(-z (1 - u)) u^(n-1) du`` on [0, 1] for n = 1, 2, 3.

    They weigh a forcing ``f0 + f1 u + f2 u^2`` (``u = s/h``) in the exact step of ``L di/dt = f - R i``:
    ``i(h) = i(0) exp(-z) + h/L (f0 phi_1 + f1 phi_2 + f2 phi_3)`` with ``z = R h / L``. Series near z = 0.
    """
    if z < 1e-2:
        z2, z3 = z * z, z * z * z
        return (1.0 - z / 2.0 + z2 / 6.0 - z3 / 24.0, 0.5 - z / 6.0 + z2 / 24.0 - z3 / 120.0,
                1.0 / 3.0 - z / 12.0 + z2 / 60.0 - z3 / 360.0)
    em = math.expm1(-z)  # exp(-z) - 1
    return -em / z, (z + em) / (z * z), (z * z - 2.0 * z - 2.0 * em) / (z * z * z)


def _commutation_margin(drive: Drive, r: float, omega: float, sector: int, n_grid: int) -> float:
    """Return ``max_t (x + w) - 2 I_N`` over the sector after the commutation into ``sector`` at ``omega``.

    Normalised currents (sign ``s = +1`` if the continuing phase y is tied to +, else -1):
    ``x = s (i_y - i_z)`` (continuing minus incoming, from I_N to 2 I_N) and ``w = s i_w`` (outgoing, from
    -I_N up to 0, then 0: its diode blocks). The incoming current reaches I_N when ``x + w = 2 I_N``. With y
    and z tied to opposite rails and w freewheeling to y's rail (``v_n`` from the three phases):

        L dx/dt = V_dc - s (e_y - e_z) - R x
        L dw/dt = V_dc/3 - s (2 e_w - e_y - e_z)/3 - R w

    Both are linear. Each step integrates them exactly for a forcing quadratic in time through the values at
    the step's ends and middle: exact for piecewise-linear shapes on a grid that holds their corners, fourth
    order for smooth shapes.
    """
    m = drive.motor
    V, i_n, L, p = drive.inverter.V_dc, m.I_N, m.L, m.p
    prev, new = _CONDUCTION[(sector - 1) % 6], _CONDUCTION[sector]
    if new[0] == prev[0]:
        y, z, w_ph, s = new[0], new[1], prev[1], 1.0
    else:
        y, z, w_ph, s = new[1], new[0], prev[0], -1.0
    th0 = math.pi / 6.0 + sector * math.pi / 3.0
    pts = [np.linspace(0.0, math.pi / 3.0, n_grid + 1)]
    for ph, sh in enumerate(m.emf.shapes):
        bp = np.mod(sh.breakpoints() + ph * TWO_PI / 3.0 - th0, TWO_PI)
        pts.append(bp[bp < math.pi / 3.0])
    nodes = np.unique(np.concatenate(pts))
    # nodes and step midpoints interleaved: f[2j] at node j, f[2j + 1] in the middle of step j
    dth = np.empty(2 * nodes.size - 1)
    dth[0::2] = nodes
    dth[1::2] = 0.5 * (nodes[:-1] + nodes[1:])
    k = m.emf.k_abc(th0 + dth)
    fx = V - s * omega * (k[y] - k[z])
    fw = V / 3.0 - s * omega * (2.0 * k[w_ph] - k[y] - k[z]) / 3.0
    h = np.diff(nodes) / (p * omega)
    lam = r / L
    x, w, best = i_n, -i_n, -2.0 * i_n
    extinct = False
    for j in range(h.size):
        zj = lam * h[j]
        decay = math.exp(-zj)
        p1, p2, p3 = _phi(zj)
        hl = h[j] / L
        # forcing f0 + (4 fm - 3 f0 - f1) u + (2 f0 - 4 fm + 2 f1) u^2 through the step's ends and middle
        f0, fm, f1 = fx[2 * j], fx[2 * j + 1], fx[2 * j + 2]
        x = x * decay + hl * (f0 * p1 + (4.0 * fm - 3.0 * f0 - f1) * p2 + 2.0 * (f0 - 2.0 * fm + f1) * p3)
        if not extinct:
            f0, fm, f1 = fw[2 * j], fw[2 * j + 1], fw[2 * j + 2]
            w = w * decay + hl * (f0 * p1 + (4.0 * fm - 3.0 * f0 - f1) * p2 + 2.0 * (f0 - 2.0 * fm + f1) * p3)
            if w >= 0.0:
                w, extinct = 0.0, True
        best = max(best, x + w)
    return best - 2.0 * i_n


def omega_qB_numeric_pu(drive: Drive, R: float | None = None, n_grid: int = 64) -> float:
    """R-aware base speed with real square-wave supply, computed numerically (per unit of Omega_0).

    Paper 1's definition (30): the largest speed at which the injected current reaches ``I_N`` by half of its
    2 pi/3 conduction interval, i.e. within the pi/3 sector that follows its commutation. During the
    commutation the incoming and the continuing phase are tied to opposite rails (full voltage: the current
    controller cannot do better) and the outgoing phase freewheels in its diode; R sits in every phase and the
    back-EMFs follow the drive's shapes (the outgoing phase is on its ramp). See :func:`_commutation_margin`
    for the circuit. The six commutations of a period are checked (one for a symmetric motor); the base speed
    is where the worst one just makes it, found by a scan and bisection. With ``R = 0`` and an ideal trapezoid
    it equals (30) exactly: ``L d(i_y - i_z)/dt = V - 2 k_phi Omega`` does not involve the outgoing phase
    (as long as the outgoing current dies within the sector, which (30) assumes).

    The result is capped at 1: at ``Omega_0`` the line-to-line back-EMF reaches the DC bus, and above it the
    120-degree conduction model (the open phase floating inside the bus) no longer holds. Only a back-EMF
    whose line-to-line peak is reached at isolated angles (rounded or sinusoidal shapes) with a small ``L``
    gets there.

    Parameters
    ----------
    drive : Drive
        Uses the drive's own back-EMF shapes, ``p``, ``L``, ``I_N`` and ``V_dc``.
    R : float, optional
        Series resistance (Ohm); default :func:`r_total`.
    n_grid : int
        Time steps per sector (before adding the shape corners).

    Returns
    -------
    float
        Speed (per unit of Omega_0), in (0, 1].

    Raises
    ------
    BldclabError
        If the current cannot reach ``I_N`` within a sector even at the lowest scanned speed.

    """
    r = _resistance(drive, R)
    sectors = range(1) if drive.motor.emf.is_symmetric else range(6)
    w0 = omega_0(drive)

    def margin(omega: float) -> float:
        return min(_commutation_margin(drive, r, omega, s, n_grid) for s in sectors)

    n_scan = 64
    speeds = w0 * np.arange(1, n_scan + 1) / n_scan
    ok = [margin(float(w)) >= 0.0 for w in speeds]
    if not ok[0]:
        raise BldclabError("motor", "the injected current cannot reach I_N within a sector even at "
                           f"{speeds[0] / w0:g} Omega_0 (resistance or inductance too large for V_dc)")
    last = max(j for j, good in enumerate(ok) if good)
    if last == n_scan - 1:  # still reached at Omega_0: capped (see the docstring)
        return 1.0
    omega = _bisect(margin, float(speeds[last]), float(speeds[last + 1]), 1e-14 * w0)
    return omega / w0

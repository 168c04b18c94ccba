"""Independent reference model of the switching-level plant, built from ``docs/plant.md`` with scipy.

This module is a deliberately slow, accurate second implementation of the inverter + motor physics, written
without looking at the C plant (``core/``), so that the test suite can cross-check the two on open-loop cases.

Formulation
-----------
Every phase terminal is in one of five *terminal kinds*: open, switch to the + rail, switch to the - rail,
lower diode, upper diode. A connected (non-open) terminal is a Thevenin source
``v_x = base_x + s_x v_bus - r_x i_x`` with ``s_x = 1`` for terminals tied to the + rail (upper switch, upper
diode) and ``v_bus = V_src - R_src sum_{s_y = 1} i_y``. With ``w_x = v_x - R i_x - e_x`` the star point of the
set C of connected phases is ``v_n = mean_C w_x`` (the Kirchhoff current law ``sum_C di/dt = 0`` for phases of
equal inductance), and ``L di_x/dt = w_x - v_n`` for x in C, ``di_x/dt = 0`` otherwise (``|C| <= 1``: no
current).

Between two scheduled instants (gate edges after dead time, controller samples at every half PWM period, and
corners of piecewise-linear back-EMF shapes) the terminal kinds are constant except for the diode and
open-phase transitions, which are located as terminal events of :func:`scipy.integrate.solve_ivp`; the
integration restarts at each event with the new conduction state. After every gate change and every event the
zero-current gate-off legs are re-resolved to a fixed point (``docs/plant.md``, rule 3). The power flows are
integrated as extra states.
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

__all__ = ["HIGH", "LOW", "OFF", "PWM", "RefResult", "simulate_reference"]

# leg modes (docs/conventions.md)
OFF, PWM, HIGH, LOW = 0, 1, 2, 3

# gate state of a leg
_G_O, _G_U, _G_L = 0, 1, 2

# terminal kinds
_OPEN, _SW_U, _SW_L, _D_LO, _D_UP = 0, 1, 2, 3, 4
_DIODES = frozenset({_D_LO, _D_UP})

_TWO_PI = 2.0 * math.pi
_N_STATE = 10  # i_a, i_b, i_c, E_src, E_Rsrc, E_cu, E_sw, E_diode, E_emf, int tau_e dt
# a floating terminal must pass a diode threshold by this fraction of V_dc to make the diode conduct: a
# terminal sitting exactly on a threshold (V_f = 0 and a terminal held at a rail) must not toggle the diode
# back and forth
_EPS_V = 1e-11
_E_KEYS = ("src", "Rsrc", "cu", "sw", "diode", "emf")


@dataclass
class RefResult:
    """Result of :func:`simulate_reference`.

    Attributes
    ----------
    t : ndarray, shape (N+1,)
        Sample instants ``k T/2`` (s).
    i : ndarray, shape (N+1, 3)
        Phase currents at the samples (A).
    theta_e : ndarray, shape (N+1,)
        Electrical angle at the samples (rad), wrapped to [0, 2 pi).
    tau_e : ndarray, shape (N+1,)
        Electromagnetic torque ``sum_x k_x i_x`` at the samples (N m).
    tau_mean : float
        Time average of ``tau_e`` over [0, N T/2] (N m), from the integrated torque.
    E : dict of str to float
        Energy integrals over the run (J): ``'src'`` (``V_src i_dc``), ``'Rsrc'`` (``R_src i_dc^2``), ``'cu'``
        (``R sum i^2``), ``'sw'`` (``R_on i^2`` of conducting switches), ``'diode'`` (``(V_f + r_d |i|) |i|``
        of conducting diodes), ``'emf'`` (``sum e_x i_x``).
    W_L0, W_L1 : float
        Magnetic energy ``(L/2) sum i^2`` at the start and the end (J).
    """

    t: NDArray[np.float64]
    i: NDArray[np.float64]
    theta_e: NDArray[np.float64]
    tau_e: NDArray[np.float64]
    tau_mean: float
    E: dict[str, float]
    W_L0: float
    W_L1: float

    def energy_residual(self) -> float:
        """Return ``E_src - (E_Rsrc + E_cu + E_sw + E_diode + E_emf + W_L1 - W_L0)`` (J); ideally zero."""
        e = self.E
        sinks = (e["Rsrc"], e["cu"], e["sw"], e["diode"], e["emf"], self.W_L1, -self.W_L0)
        return e["src"] - math.fsum(sinks)


@dataclass(frozen=True)
class _Params:
    """Plain-float copy of the drive parameters the electrical model needs."""

    p: int
    R: float
    L: float
    V_src: float
    R_src: float
    R_on: float
    V_f: float
    r_d: float
    omega_m: float
    theta0: float
    k_abc: Callable[[float], list[float]]
    eps_v: float

    @property
    def w_e(self) -> float:
        """Electrical angular speed (rad/s)."""
        return self.p * self.omega_m

    def theta(self, t: float) -> float:
        """Unwrapped electrical angle at time ``t``."""
        return self.theta0 + self.w_e * t

    def emf(self, t: float) -> tuple[list[float], list[float]]:
        """Return ``(k_x, e_x)`` at time ``t``."""
        k = self.k_abc(self.theta(t))
        w = self.omega_m
        return k, [w * k[0], w * k[1], w * k[2]]

    def thevenin(self, kind: int) -> tuple[float, float, float]:
        """Return ``(base, s, r)`` of a connected terminal: ``v_x = base + s v_bus - r i_x``."""
        if kind == _SW_U:
            return 0.0, 1.0, self.R_on
        if kind == _SW_L:
            return 0.0, 0.0, self.R_on
        if kind == _D_LO:
            return -self.V_f, 0.0, self.r_d
        if kind == _D_UP:
            return self.V_f, 1.0, self.r_d
        raise ValueError(f"terminal kind {kind} is not connected")  # pragma: no cover - internal misuse


# ----------------------------------------------------------------------------------------------------------
# gate timing: PWM carrier, modes, dead time


def _leg_wants(modes: NDArray[np.int_], duties: NDArray[np.float64], T2: float
               ) -> list[tuple[float, bool, bool]]:
    """Return the change points ``(t, upper_wanted, lower_wanted)`` of one leg's commanded switch states.

    Half period k spans [k T2, (k+1) T2]; even k is a rising carrier half (active from ``t_k + (1 - d) T2`` to
    its end), odd k a falling half (active from ``t_k`` to ``t_k + d T2``).
    """
    out: list[tuple[float, bool, bool]] = []

    def push(t: float, uw: bool, lw: bool) -> None:
        if out and out[-1][0] == t:
            out.pop()
        if out and out[-1][1] == uw and out[-1][2] == lw:
            return
        out.append((t, uw, lw))

    for k, (m, d) in enumerate(zip(modes.tolist(), duties.tolist(), strict=True)):
        t_k, t_k1 = k * T2, (k + 1) * T2
        if m == OFF:
            push(t_k, False, False)
            continue
        active = (m in (PWM, HIGH), m == LOW)
        inactive = (False, m == PWM)
        if k % 2 == 0:
            a0, a1 = (k + 1.0 - d) * T2, t_k1
        else:
            a0, a1 = t_k, (k + d) * T2
        pieces = ((t_k, a0, inactive), (a0, a1, active), (a1, t_k1, inactive))
        for s0, s1, (uw, lw) in pieces:
            if s1 > s0:
                push(s0, uw, lw)
    return out


def _leg_gates(wants: list[tuple[float, bool, bool]], t_dead: float, t_end: float
               ) -> tuple[list[float], list[int]]:
    """Apply the dead time to one leg: return its gate timeline ``(times, gates)``, gate j from ``times[j]``.

    A wanted switch turns on once the other switch of the leg has been off for ``t_dead`` (and only if it is
    still wanted then); an unwanted switch turns off at once. Before t = 0 both switches have been off
    forever.
    """
    up_on = lo_on = False
    up_off = lo_off = -math.inf
    events: list[tuple[float, int]] = []

    def gate() -> int:
        return _G_U if up_on else (_G_L if lo_on else _G_O)

    for j, (t, uw, lw) in enumerate(wants):
        t_next = wants[j + 1][0] if j + 1 < len(wants) else t_end
        if up_on and not uw:
            up_on, up_off = False, t
        if lo_on and not lw:
            lo_on, lo_off = False, t
        events.append((t, gate()))
        if uw and not up_on:
            t_on = max(t, lo_off + t_dead)
            if t_on < t_next:
                up_on = True
                events.append((t_on, gate()))
        if lw and not lo_on:
            t_on = max(t, up_off + t_dead)
            if t_on < t_next:
                lo_on = True
                events.append((t_on, gate()))
    times: list[float] = []
    gates: list[int] = []
    for t, g in events:
        if times and times[-1] == t:
            times.pop()
            gates.pop()
        if gates and gates[-1] == g:
            continue
        times.append(t)
        gates.append(g)
    return times, gates


def _corner_times(drive: Any, prm: _Params, t_end: float) -> list[float]:
    """Times in (0, t_end) at which a piecewise-linear back-EMF shape has a corner."""
    w_e = prm.w_e
    if w_e == 0.0:
        return []
    th_a, th_b = prm.theta(0.0), prm.theta(t_end)
    lo, hi = min(th_a, th_b), max(th_a, th_b)
    out: list[float] = []
    for x, shape in enumerate(drive.motor.emf.shapes):
        for phi in np.asarray(shape.breakpoints(), dtype=float).tolist():
            ang = phi + x * _TWO_PI / 3.0
            n0 = math.floor((lo - ang) / _TWO_PI)
            n1 = math.ceil((hi - ang) / _TWO_PI)
            for n in range(n0, n1 + 1):
                t = (ang + n * _TWO_PI - prm.theta0) / w_e
                if 0.0 < t < t_end:
                    out.append(t)
    return out


# ----------------------------------------------------------------------------------------------------------
# the circuit for one conduction state


class _Circuit:
    """Right-hand side and event functions for fixed terminal kinds."""

    def __init__(self, prm: _Params, kinds: Sequence[int]) -> None:
        self.prm = prm
        self.kinds = tuple(kinds)
        self.conn = [x for x in range(3) if self.kinds[x] != _OPEN]
        self.plus = [x for x in self.conn if self.kinds[x] in (_SW_U, _D_UP)]
        self.th = {x: prm.thevenin(self.kinds[x]) for x in self.conn}
        self.switches = [x for x in self.conn if self.kinds[x] in (_SW_U, _SW_L)]
        self.diodes = [x for x in self.conn if self.kinds[x] in _DIODES]
        self.diode_signs = [(x, 1.0 if self.kinds[x] == _D_LO else -1.0) for x in self.diodes]

    def star(self, i: Sequence[float], e: Sequence[float]) -> tuple[float, float, dict[int, float]]:
        """Return ``(v_n, v_bus, w)`` for the connected phases (needs ``|C| >= 1``)."""
        prm = self.prm
        i_dc = math.fsum(i[x] for x in self.plus)
        v_bus = prm.V_src - prm.R_src * i_dc
        w: dict[int, float] = {}
        for x in self.conn:
            base, s, r = self.th[x]
            w[x] = base + s * v_bus - (prm.R + r) * i[x] - e[x]
        return math.fsum(w.values()) / len(w), v_bus, w

    def rhs(self, t: float, y: NDArray[np.float64]) -> list[float]:
        """Derivative of the augmented state (currents, energy flows, torque integral)."""
        prm = self.prm
        k, e = prm.emf(t)
        i = (float(y[0]), float(y[1]), float(y[2]))
        di = [0.0, 0.0, 0.0]
        if len(self.conn) >= 2:
            v_n, _, w = self.star(i, e)
            for x in self.conn:
                di[x] = (w[x] - v_n) / prm.L
        i_dc = math.fsum(i[x] for x in self.plus)
        p_sw = prm.R_on * math.fsum(i[x] * i[x] for x in self.switches)
        # (V_f + r_d |i|) |i| written with the sign the diode fixes: smooth past a current zero (the solver
        # steps over the zero before dense output locates the event; abs() would cost accuracy there)
        p_d = math.fsum((prm.V_f * sg + prm.r_d * i[x]) * i[x] for x, sg in self.diode_signs)
        return [di[0], di[1], di[2],
                prm.V_src * i_dc,
                prm.R_src * i_dc * i_dc,
                prm.R * (i[0] * i[0] + i[1] * i[1] + i[2] * i[2]),
                p_sw,
                p_d,
                e[0] * i[0] + e[1] * i[1] + e[2] * i[2],
                k[0] * i[0] + k[1] * i[1] + k[2] * i[2]]

    def events(self) -> list[tuple[Callable[[float, NDArray[np.float64]], float], tuple[Any, ...]]]:
        """Terminal event functions with the transition each one stands for.

        The transition tags are ``("zero", x)`` (diode current of x reaches zero), ``("cond", y, kind)`` (open
        phase y starts conducting through a diode) and ``("pair", x, y)`` (no phase conducts: x starts through
        the upper diode and y through the lower one).
        """
        prm = self.prm
        eps = prm.eps_v
        out: list[tuple[Callable[[float, NDArray[np.float64]], float], tuple[Any, ...]]] = []

        def make(fun: Callable[[float, NDArray[np.float64]], float], direction: float, tag: tuple[Any, ...]
                 ) -> None:
            fun.terminal = True  # type: ignore[attr-defined]
            fun.direction = direction  # type: ignore[attr-defined]
            out.append((fun, tag))

        for x in self.diodes:
            make(lambda t, y, x=x: float(y[x]), -1.0 if self.kinds[x] == _D_LO else 1.0, ("zero", x))
        opens = [x for x in range(3) if self.kinds[x] == _OPEN]
        if self.conn:
            for y_ in opens:
                def g_lo(t: float, y: NDArray[np.float64], y_: int = y_) -> float:
                    _, e = prm.emf(t)
                    v_n, _, _ = self.star(y[:3].tolist(), e)
                    return e[y_] + v_n + prm.V_f + eps

                def g_hi(t: float, y: NDArray[np.float64], y_: int = y_) -> float:
                    _, e = prm.emf(t)
                    v_n, v_bus, _ = self.star(y[:3].tolist(), e)
                    return e[y_] + v_n - v_bus - prm.V_f - eps

                make(g_lo, -1.0, ("cond", y_, _D_LO))
                make(g_hi, 1.0, ("cond", y_, _D_UP))
        else:
            for a in opens:
                for b in opens:
                    if a == b:
                        continue

                    def g_pair(t: float, y: NDArray[np.float64], a: int = a, b: int = b) -> float:
                        _, e = prm.emf(t)
                        return e[a] - e[b] - prm.V_src - 2.0 * prm.V_f - eps

                    make(g_pair, 1.0, ("pair", a, b))
        return out


def _resolve(prm: _Params, t: float, i: list[float], gates: Sequence[int], kinds: Sequence[int],
             allowed: dict[int, frozenset[int]]) -> list[int]:
    """Return the terminal kinds after a gate change or a transition (``docs/plant.md`` rule 3).

    Legs with a closed switch are tied to its rail; gate-off legs carrying current conduct through the diode
    their current's sign selects. Gate-off legs with zero current start open, except those a transition at
    this instant forced into a diode (``allowed`` maps them to the kinds they may take); then the open phase
    whose floating terminal ``e_x + v_n`` lies farthest outside ``[-V_f, v_bus + V_f]`` is connected to the
    diode it points at, and so on until none is outside (with no connected phase, a pair x, y starts
    conducting when ``e_x - e_y > v_bus + 2 V_f``, the largest excess first).
    """
    new = list(kinds)
    zero: list[int] = []
    for x in range(3):
        if gates[x] == _G_U:
            new[x] = _SW_U
        elif gates[x] == _G_L:
            new[x] = _SW_L
        elif i[x] > 0.0:
            new[x] = _D_LO
        elif i[x] < 0.0:
            new[x] = _D_UP
        else:
            ok = allowed.get(x, _DIODES)
            if len(ok) == 1:
                new[x] = next(iter(ok))
            else:
                new[x] = _OPEN
                zero.append(x)
    _, e = prm.emf(t)
    for _ in range(4):
        cand: list[tuple[float, list[tuple[int, int]]]] = []
        opens = [x for x in zero if new[x] == _OPEN]
        circ = _Circuit(prm, new)
        if circ.conn:
            v_n, v_bus, _ = circ.star(i, e)
            for y in opens:
                ok = allowed.get(y, _DIODES)
                u = e[y] + v_n
                if _D_LO in ok and u < -prm.V_f - prm.eps_v:
                    cand.append((-prm.V_f - u, [(y, _D_LO)]))
                if _D_UP in ok and u > v_bus + prm.V_f + prm.eps_v:
                    cand.append((u - v_bus - prm.V_f, [(y, _D_UP)]))
        else:
            for a in opens:
                for b in opens:
                    if a != b and _D_UP in allowed.get(a, _DIODES) and _D_LO in allowed.get(b, _DIODES):
                        g = e[a] - e[b] - prm.V_src - 2.0 * prm.V_f
                        if g > prm.eps_v:
                            cand.append((g, [(a, _D_UP), (b, _D_LO)]))
        if not cand:
            return new
        for x, kind in max(cand, key=lambda c: c[0])[1]:
            new[x] = kind
    return new


# ----------------------------------------------------------------------------------------------------------
# driver


def _cached_k_abc(emf: Any) -> Callable[[float], list[float]]:
    """Wrap ``emf.k_abc`` for scalar angles, remembering the last angle (RHS and events often share it)."""
    last: list[Any] = [None, None]

    def k_abc(theta: float) -> list[float]:
        if last[0] != theta:
            last[0], last[1] = theta, emf.k_abc(theta).tolist()
        return last[1]

    return k_abc


def simulate_reference(drive: Any, omega_m: float, modes: ArrayLike, duties: ArrayLike, *,
                       theta0: float = 0.0, i0: Sequence[float] = (0.0, 0.0, 0.0), rtol: float = 1e-10,
                       atol: float = 1e-10, method: str = "DOP853") -> RefResult:
    """Simulate the inverter and motor at imposed constant speed with the legs commanded open loop.

    Parameters
    ----------
    drive : bldclab.Drive
        The drive: ``drive.motor`` (p, R, L, emf) and ``drive.inverter`` (V_dc, f_pwm, t_dead, R_on, V_f, r_d,
        R_src) are used.
    omega_m : float
        Imposed mechanical speed (rad/s), any sign; ``theta_e(t) = theta0 + p omega_m t``.
    modes : array_like of int, shape (N, 3)
        Leg mode per half PWM period k and leg: 0 OFF, 1 PWM (complementary), 2 HIGH (upper chops, lower off),
        3 LOW (lower chops, upper off).
    duties : array_like of float, shape (N, 3)
        Duty per half period and leg, in [0, 1].
    theta0 : float, optional
        Electrical angle at t = 0 (rad).
    i0 : sequence of 3 float, optional
        Initial phase currents (A); they must sum to zero.
    rtol, atol : float, optional
        Tolerances of :func:`scipy.integrate.solve_ivp` (all states).
    method : str, optional
        Explicit or implicit solve_ivp method, ``'DOP853'`` (default) or ``'Radau'``.

    Returns
    -------
    RefResult
        Samples at every carrier valley and peak, the time-averaged torque and the energy integrals.

    Raises
    ------
    ValueError
        On malformed commands or initial currents.
    RuntimeError
        If the integrator fails or the conduction state does not settle at an instant.
    """
    modes_a = np.asarray(modes)
    duties_a = np.asarray(duties, dtype=float)
    if modes_a.ndim != 2 or modes_a.shape[1] != 3 or modes_a.shape[0] < 1:
        raise ValueError(f"modes must have shape (N, 3) with N >= 1, got {modes_a.shape}")
    if duties_a.shape != modes_a.shape:
        raise ValueError(f"duties must have the shape of modes {modes_a.shape}, got {duties_a.shape}")
    if not np.all(np.isin(modes_a, (OFF, PWM, HIGH, LOW))):
        raise ValueError("modes must be 0 (OFF), 1 (PWM), 2 (HIGH) or 3 (LOW)")
    if not np.all(np.isfinite(duties_a)) or np.any(duties_a < 0.0) or np.any(duties_a > 1.0):
        raise ValueError("duties must lie in [0, 1]")
    modes_a = modes_a.astype(int)
    i_init = [float(v) for v in i0]
    if len(i_init) != 3 or abs(math.fsum(i_init)) > 1e-9 * max(1.0, max(abs(v) for v in i_init)):
        raise ValueError(f"i0 must be three currents summing to zero, got {i0!r}")
    i_init[2] = -(i_init[0] + i_init[1])  # exactly zero sum

    mot, inv = drive.motor, drive.inverter
    emf_obj = mot.emf
    prm = _Params(p=int(mot.p), R=float(mot.R), L=float(mot.L), V_src=float(inv.V_dc), R_src=float(inv.R_src),
                  R_on=float(inv.R_on), V_f=float(inv.V_f), r_d=float(inv.r_d), omega_m=float(omega_m),
                  theta0=float(theta0), k_abc=_cached_k_abc(emf_obj),
                  eps_v=_EPS_V * float(inv.V_dc))
    N = modes_a.shape[0]
    T2 = 0.5 / float(inv.f_pwm)
    t_end = N * T2

    legs = [_leg_gates(_leg_wants(modes_a[:, x], duties_a[:, x], T2), float(inv.t_dead), t_end)
            for x in range(3)]
    samples = [k * T2 for k in range(N + 1)]
    other = [t for times, _ in legs for t in times] + _corner_times(drive, prm, t_end)
    # merge times closer than a tiny fraction of the half period (floating-point duplicates), samples win
    tol = 1e-13 * T2
    cuts = list(samples)
    for t in sorted(other):
        if not 0.0 < t < t_end:
            continue
        j = bisect.bisect_left(cuts, t)
        if (j < len(cuts) and cuts[j] - t <= tol) or (j > 0 and t - cuts[j - 1] <= tol):
            continue
        cuts.insert(j, t)
    sample_set = set(samples)

    def gates_at(tm: float) -> list[int]:
        out = []
        for times, gl in legs:
            j = bisect.bisect_right(times, tm) - 1
            out.append(gl[j] if j >= 0 else _G_O)
        return out

    y = np.zeros(_N_STATE)
    y[:3] = i_init
    acc: list[list[float]] = [[] for _ in range(_N_STATE - 3)]
    rec_i: list[list[float]] = [list(i_init)]
    kinds: list[int] = [_OPEN, _OPEN, _OPEN]
    prev_gates: list[int] | None = None
    max_step = 0.25 * T2

    for t_a, t_b in itertools.pairwise(cuts):
        gates = gates_at(0.5 * (t_a + t_b))
        i_now = y[:3].tolist()
        if gates != prev_gates:
            kinds = _resolve(prm, t_a, i_now, gates, kinds, {})
            prev_gates = gates
        t = t_a
        stalls = 0
        while t_b - t > tol:
            circ = _Circuit(prm, kinds)
            evs = circ.events()
            y0 = y.copy()
            y0[3:] = 0.0
            sol = solve_ivp(circ.rhs, (t, t_b), y0, method=method, rtol=rtol, atol=atol, max_step=max_step,
                            events=[f for f, _ in evs] or None)
            if sol.status < 0:
                raise RuntimeError(f"solve_ivp failed at t = {t:.9g}: {sol.message}")
            t_new = float(sol.t[-1])
            y = sol.y[:, -1].copy()
            for j in range(_N_STATE - 3):
                acc[j].append(float(y[3 + j]))
            if sol.status == 0:
                t = t_b
                break
            stalls = stalls + 1 if t_new - t <= tol else 0
            if stalls > 20:
                raise RuntimeError(f"conduction state does not settle at t = {t_new:.12g} s")
            t = t_new
            tags = [tag for (_, tag), te in zip(evs, sol.t_events, strict=True) if te.size]
            i_now = y[:3].tolist()
            allowed: dict[int, frozenset[int]] = {}
            for tag in tags:
                if tag[0] == "zero":
                    x = tag[1]
                    i_now[x] = 0.0
                    rest = [z for z in circ.conn if z != x]
                    if rest:
                        r = math.fsum(i_now)
                        for z in rest:
                            i_now[z] -= r / len(rest)
                    other_diode = _D_UP if kinds[x] == _D_LO else _D_LO
                    allowed[x] = frozenset({_OPEN, other_diode})
                elif tag[0] == "cond":
                    allowed[tag[1]] = frozenset({tag[2]})
                else:
                    allowed[tag[1]] = frozenset({_D_UP})
                    allowed[tag[2]] = frozenset({_D_LO})
            y[:3] = i_now  # an opened phase carries exactly zero current
            kinds = _resolve(prm, t, i_now, gates, kinds, allowed)
        if t_b in sample_set:
            rec_i.append(y[:3].tolist())

    if len(rec_i) != N + 1:  # pragma: no cover - internal consistency
        raise RuntimeError(f"recorded {len(rec_i)} samples instead of {N + 1}")
    E = {key: math.fsum(acc[j]) for j, key in enumerate(_E_KEYS)}
    tau_int = math.fsum(acc[6])
    t_s = np.asarray(samples)
    i_s = np.asarray(rec_i)
    th_s = np.mod(prm.theta0 + prm.w_e * t_s, _TWO_PI)
    k_s = emf_obj.k_abc(prm.theta0 + prm.w_e * t_s)
    tau_s = np.einsum("xn,nx->n", k_s, i_s)
    W_L0 = 0.5 * prm.L * math.fsum(v * v for v in i_init)
    W_L1 = 0.5 * prm.L * math.fsum(v * v for v in i_s[-1].tolist())
    return RefResult(t=t_s, i=i_s, theta_e=th_s, tau_e=tau_s, tau_mean=tau_int / t_end, E=E, W_L0=W_L0,
                     W_L1=W_L1)

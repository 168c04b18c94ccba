"""The speed limit of the sinusoidal supply (``bc_sine``, ``docs/sine.md`` section 4): its table against the scan it
tabulates, on every catalog drive and on drives with random Fourier shapes; and, with ``--cost``, what
``bc_sine_step`` costs per sample in closed loop.

- Table against scan: the controller's limit (``bc_sine_i_limit`` of the C library, with the parameters
  :class:`bldclab.Sine` fills) against the 96-angle scan of ``bc_sine.h`` section 5 written here in numpy (double),
  at random speeds (both signs, up to 1.05 times the no-load speed of the bus, most of them near it), buses from
  0.3 to 2 ``V_dc`` and both torque signs: how far above the scan (never, beyond rounding), the worst shortfall in
  % of ``I_s,N`` where the back-EMF alone needs at most 99.5 % of the bus, and the bus the table costs (the smallest
  ``d`` with the table's limit at least the scan's on a bus ``(1 - d) v_dc``).
- Cost (``--cost``, needs valgrind): the closed loop of ``bl.simulate`` at imposed speed with the reference
  ``T_s,N`` under ``valgrind --tool=callgrind --dump-before=bc_sine_step --dump-after=bc_sine_step``: every call of
  ``bc_sine_step`` is one dump, so the mean and the worst instructions per sample are counted, not estimated; the
  calls of the square-wave start (those that call ``bc_sixstep_step``) are reported apart.

Run: ``python benchmarks/sine_limit.py [--samples N] [--random N] [--cost] [--seconds S]``.
"""

from __future__ import annotations

import argparse
import ctypes
import math
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import bldclab as bl
from bldclab._core import core
from bldclab.model.catalog.synthetic import paper1_drive

M = 96  # BC_SINE_LIM_N
CATALOG = ("htm-48v", "lu-4kw", "outrunner-24v", "servo-2k2")


def _pwl(k: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """k(theta) of a table uniform on [0, 2 pi), linear, periodic (the controller's interpolation)."""
    n = k.size
    u = np.asarray(theta, dtype=float) / (2.0 * math.pi) * n
    u = u - n * np.floor(u / n)
    j = np.floor(u).astype(int) % n
    return k[j] + (u - np.floor(u)) * (k[(j + 1) % n] - k[j])


class Scan:
    """The scan of ``bc_sine.h`` 5. in double: ``v_req(omega_e, J)`` over the M grid angles with its margins.

    Parameters
    ----------
    tables : sequence of numpy.ndarray
        The controller's back-EMF tables (V s/rad), phases a, b, c, uniform on [0, 2 pi).
    p : int
        Pole pairs.
    R, L : float
        Resistance (Ohm) and inductance (H) of the controller's model.
    i_s : float
        The current cap ``i_s_max`` (A).
    circle : bool
        The circle limit instead of the hexagon.
    """

    def __init__(self, tables: list[np.ndarray], p: int, R: float, L: float, i_s: float, circle: bool) -> None:
        self.p, self.R, self.L, self.i_s, self.circle = p, R, L, i_s, circle
        th = 2.0 * math.pi * np.arange(M) / M
        tabs = [np.asarray(t, dtype=float) for t in tables]

        def lines(theta: np.ndarray) -> np.ndarray:
            k = np.array([_pwl(tabs[x], theta - x * 2.0 * math.pi / 3.0) for x in range(3)])
            return k - k[[1, 2, 0]]

        def norm(kl: np.ndarray) -> np.ndarray:
            return np.hypot((kl[0] - kl[2]) / 3.0, kl[1] / math.sqrt(3.0))

        self.k = lines(th)                                                  # (3, M) line values
        ix = np.array([np.sin(th - x * 2.0 * math.pi / 3.0) for x in range(3)])
        dx = np.array([np.cos(th - x * 2.0 * math.pi / 3.0) for x in range(3)])
        self.i, self.di = ix - ix[[1, 2, 0]], dx - dx[[1, 2, 0]]
        n_sub = 2 * (tabs[0].size // M + 1)   # the controller's sampling of the margins' deviations
        u = np.arange(1, n_sub) / n_sub
        k0, k1 = self.k, np.roll(self.k, -1, axis=1)
        ks = lines((th[None, :] + u[:, None] * 2.0 * math.pi / M).ravel()).reshape(3, u.size, M)
        self.dev = float(np.max(np.abs(ks - (k0[:, None, :] + u[None, :, None] * (k1 - k0)[:, None, :]))))
        n0, n1 = norm(k0), norm(k1)
        self.dev_c = max(0.0, float(np.max(norm(ks) - (n0[None, :] + u[:, None] * (n1 - n0)[None, :]))))
        if circle:
            self.k_e = math.sqrt(3.0) * (float(np.max(norm(self.k))) + self.dev_c)
        else:
            self.k_e = float(np.max(np.abs(self.k))) + self.dev
        self.c_m = math.cos(math.pi / M)

    def v(self, we: np.ndarray, J: np.ndarray) -> np.ndarray:
        """``v_req(omega_e, J)`` (V) for arrays of electrical speeds (rad/s) and signed currents (A)."""
        we = np.asarray(we, dtype=float)[:, None]
        J = np.asarray(J, dtype=float)[:, None]
        wm, xe = we / self.p, we * self.L
        if self.circle:
            ea, eb = wm * (self.k[0] - self.k[2]) / 3.0, wm * self.k[1] / math.sqrt(3.0)
            ga = (self.R * (self.i[0] - self.i[2]) + xe * (self.di[0] - self.di[2])) / 3.0
            gb = (self.R * self.i[1] + xe * self.di[1]) / math.sqrt(3.0)
            best = np.max(np.hypot(ea + J * ga, eb + J * gb), axis=1)
            return math.sqrt(3.0) * (best + np.abs(wm[:, 0]) * self.dev_c)
        best = np.zeros(we.shape[0])
        for x in range(3):
            best = np.maximum(best, np.max(np.abs(wm * self.k[x] + J * (self.R * self.i[x] + xe * self.di[x])), axis=1))
        m_g = (1.0 - self.c_m) * math.sqrt(3.0) * np.hypot(self.R, xe[:, 0])
        return best + np.abs(wm[:, 0]) * self.dev + np.abs(J[:, 0]) * m_g

    def limit(self, we: np.ndarray, v_dc: np.ndarray, sgn: np.ndarray) -> np.ndarray:
        """The scan's ``min(i_s, I_s,sat)`` (A) for arrays of speeds (rad/s), buses (V) and torque signs."""
        we, v_dc, sgn = (np.asarray(a, dtype=float) for a in (we, v_dc, sgn))
        wm, xe = we[:, None] / self.p, we[:, None] * self.L
        s = sgn[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.circle:
                r = v_dc[:, None] / math.sqrt(3.0) - np.abs(wm) * self.dev_c
                ea, eb = wm * (self.k[0] - self.k[2]) / 3.0, wm * self.k[1] / math.sqrt(3.0)
                ga = s * (self.R * (self.i[0] - self.i[2]) + xe * (self.di[0] - self.di[2])) / 3.0
                gb = s * (self.R * self.i[1] + xe * self.di[1]) / math.sqrt(3.0)
                gg, eg, ee = ga * ga + gb * gb, ea * ga + eb * gb, ea * ea + eb * eb
                root = np.where(gg > 0, (-eg + np.sqrt(np.maximum(eg * eg + gg * (r * r - ee), 0.0))) / gg, np.inf)
                best = np.min(root, axis=1)
            else:
                m_e = np.abs(wm) * self.dev
                m_g = (1.0 - self.c_m) * math.sqrt(3.0) * np.hypot(self.R, xe)
                best = np.full(we.shape, np.inf)
                for x in range(3):
                    e = wm * self.k[x]
                    g = s * (self.R * self.i[x] + xe * self.di[x])
                    for side in (-1.0, 1.0):
                        slope = side * g + m_g
                        b = np.where(slope > 0, (v_dc[:, None] - m_e - side * e) / slope, np.inf)
                        best = np.minimum(best, np.min(b, axis=1))
        out = np.clip(np.minimum(best, self.i_s), 0.0, self.i_s)
        return np.where(self.v(we, np.zeros_like(we)) <= v_dc, out, 0.0)


class Probe:
    """The controller's speed limit for a drive: :class:`bldclab.Sine`'s parameters, ``bc_sine_init``, then
    ``bc_sine_i_limit`` of the C library.

    Parameters
    ----------
    drive : bldclab.Drive
        The drive.
    control : bldclab.Sine
        The controller settings (its ``limit``, ``emf_points``).
    """

    def __init__(self, drive: bl.Drive, control: bl.Sine) -> None:
        c = core()
        self._params = control.c_record(drive, c, 0)
        rec = self._params.record
        self._state = c.opaque("bc_sine_state")
        if c.controller_init(c.controllers["sine"], rec, self._state) != 0:
            raise RuntimeError("bc_sine_init refused the parameters")
        fn = c.lib.bc_sine_i_limit
        fn.restype = ctypes.c_float
        fn.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_float, ctypes.c_float, ctypes.c_float)
        self._fn = fn
        n = int(rec["emf_n"][0])
        tables = [np.ctypeslib.as_array(ctypes.cast(int(a), ctypes.POINTER(ctypes.c_float)), shape=(n,)).copy()
                  for a in rec["emf_k"][0]]
        self.scan = Scan(tables, int(rec["p"][0]), float(rec["R"][0]), float(rec["L"][0]), float(rec["i_s_max"][0]),
                         control.limit == "circle")

    def limit(self, we: np.ndarray, v_dc: np.ndarray, sgn: np.ndarray) -> np.ndarray:
        """The controller's limit (A) for arrays of speeds (rad/s), buses (V) and torque signs."""
        pp, ps = self._params.address, int(self._state.ctypes.data)
        return np.array([self._fn(pp, ps, float(v), float(w), float(s)) for w, v, s in zip(we, v_dc, sgn, strict=True)])


@dataclass
class TableError:
    """The table against the scan on one drive: fractions of ``I_s,N`` and of the bus."""

    above: float   # the largest excess over the scan
    below: float   # the largest shortfall where the back-EMF alone needs at most 99.5 % of the bus
    edge: float    # the largest shortfall nearer the no-load speed (where the scan's limit is steep or steps)
    bus: float     # the bus the table costs: the largest smallest d with I >= I_scan((1 - d) v_dc)
    binding: int   # samples with the limit strictly between 0 and I_s,N


def table_error(drive: bl.Drive, control: bl.Sine, n: int = 6000, seed: int = 1) -> TableError:
    """Compare the controller's limit with the scan on ``n`` random points (module docstring).

    Parameters
    ----------
    drive : bldclab.Drive
        The drive.
    control : bldclab.Sine
        The controller settings.
    n : int
        Number of random (speed, bus, torque sign) points.
    seed : int
        Seed of the points.

    Returns
    -------
    TableError
        The worst excess and shortfalls.
    """
    probe = Probe(drive, control)
    sc = probe.scan
    rng = np.random.default_rng(seed)
    v_dc = drive.inverter.V_dc * rng.uniform(0.3, 2.0, n)
    w0 = sc.p * v_dc / sc.k_e
    lo = np.choose(np.arange(n) % 4, [0.0, 0.75, 0.97, 0.99])  # a quarter anywhere, the rest nearer w0, where a
    hi = np.choose(np.arange(n) % 4, [1.05, 1.005, 1.005, 1.002])  # small drop binds
    we = rng.choice([-1.0, 1.0], n) * rng.uniform(lo, hi) * w0
    sgn = rng.choice([-1.0, 1.0], n)
    tb = probe.limit(we, v_dc, sgn)
    ex = sc.limit(we, v_dc, sgn)
    short = (ex - tb) / sc.i_s
    away = sc.v(we, np.zeros(n)) <= 0.995 * v_dc
    lo_d, hi_d = np.zeros(n), np.full(n, 0.05)
    for _ in range(25):  # the bus the table costs, by bisection (the scan's limit grows with the bus)
        d = 0.5 * (lo_d + hi_d)
        ok = tb >= sc.limit(we, (1.0 - d) * v_dc, sgn) - 1e-5 * sc.i_s
        hi_d, lo_d = np.where(ok, d, hi_d), np.where(ok, lo_d, d)
    bus = np.where(short > 1e-5, hi_d, 0.0)
    return TableError(above=float(np.max(-short)), below=float(np.max(short[away], initial=0.0)),
                      edge=float(np.max(short[~away], initial=0.0)), bus=float(np.max(bus)),
                      binding=int(np.sum((tb > 0) & (tb < sc.i_s))))


def random_drive(seed: int) -> bl.Drive:
    """A paper-1 drive with random per-phase Fourier shapes (harmonics 1 to 9, even ones too, so neither half-wave
    symmetric nor alike between phases), a random drop (``Theta_m``) and a random resistance.

    Parameters
    ----------
    seed : int
        Seed of the draw.

    Returns
    -------
    bldclab.Drive
        The drive.
    """
    rng = np.random.default_rng(seed)
    d = paper1_drive(float(rng.uniform(0.05, 0.6)), p=int(rng.integers(1, 12)), R=0.0)
    d = d.replace(motor__R=float(10 ** rng.uniform(-2.5, -1.0)) * d.inverter.V_dc / d.motor.I_N)
    base_a, base_b = rng.normal(0.0, 0.2, 10) / np.arange(1, 11), rng.normal(0.0, 0.2, 10) / np.arange(1, 11)
    shapes = []
    for _ in range(3):
        a = np.concatenate([[0.0], base_a[:9] + rng.normal(0.0, 0.02, 9) / np.arange(1, 10)])
        b = np.concatenate([[0.0], base_b[:9] + rng.normal(0.0, 0.02, 9) / np.arange(1, 10)])
        a[1], b[1] = 0.0, 1.0  # the fundamental: k_1 sin(theta)
        shapes.append(bl.Fourier(tuple(a * d.motor.k_phi), tuple(b * d.motor.k_phi)))
    return d.replace(motor__emf=bl.BackEmf(tuple(shapes)))  # type: ignore[arg-type]


def closed_loop_cost(name: str, w_pu: float, seconds: float, limit: str = "hexagon") -> dict[str, float]:
    """Instructions per call of ``bc_sine_step`` in closed loop (module docstring), under callgrind.

    Parameters
    ----------
    name : str
        Catalog drive.
    w_pu : float
        Imposed speed in p.u. of ``Omega_0``.
    seconds : float
        Simulated time (s).
    limit : str
        ``Sine.limit``.

    Returns
    -------
    dict of str to float
        ``mean`` and ``worst`` over the calls in the sine mode (``bc_sixstep_step`` not called), ``start_worst``
        over those of the square-wave start, and ``calls``.
    """
    script = ("import bldclab as bl\nfrom bldclab.model import analytic as an\n"
              f"d = bl.load({name!r})\n"
              f"bl.simulate(d, bl.Sine(limit={limit!r}), bl.Scenario(duration={seconds!r}, "
              f"speed={w_pu!r} * d.Omega_0, ref=an.T_SN_PU * d.T_N, trace=False))\n")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "cg"
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", "--dump-before=bc_sine_step",
                        "--dump-after=bc_sine_step", sys.executable, "-c", script], check=True, capture_output=True)
        sine, start = [], []
        for f in Path(tmp).glob("cg.*"):
            text = f.read_text(errors="replace")
            if "Trigger: --dump-after=bc_sine_step" in text[:4000]:
                n = int(re.search(r"^summary: (\d+)", text, flags=re.M).group(1))
                (start if "bc_sixstep_step" in text else sine).append(n)
    return {"mean": float(np.mean(sine)), "worst": float(np.max(sine)),
            "start_worst": float(np.max(start, initial=0)), "calls": float(len(sine) + len(start))}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=6000, help="random points per drive and limit")
    ap.add_argument("--random", type=int, default=8, help="drives with random Fourier shapes")
    ap.add_argument("--cost", action="store_true", help="also the closed-loop cost per sample (valgrind)")
    ap.add_argument("--seconds", type=float, default=0.2, help="simulated time of each cost run")
    args = ap.parse_args()
    print("speed limit: the table against the 96-angle scan (% of I_s,N; bus: % of v_dc)")
    print(f"{'drive':<16} {'limit':<8} {'above':>8} {'below':>7} {'near w0':>8} {'bus':>6} {'binding':>8}")
    drives = [(n, bl.load(n)) for n in CATALOG] + [(f"random-{s}", random_drive(s)) for s in range(args.random)]
    for name, drive in drives:
        for limit in ("hexagon", "circle"):
            e = table_error(drive, bl.Sine(limit=limit), args.samples)
            print(f"{name:<16} {limit:<8} {100 * e.above:>8.1e} {100 * e.below:>7.3f} {100 * e.edge:>8.2f} "
                  f"{100 * e.bus:>6.3f} {e.binding:>8d}")
    if args.cost:
        if shutil.which("valgrind") is None:
            print("missing tool: valgrind", file=sys.stderr)
            return 1
        print("bc_sine_step in closed loop (imposed speed, reference T_s,N): instructions per sample in the sine mode")
        for name, w in (("htm-48v", 0.5), ("htm-48v", 0.95), ("htm-48v", 0.99), ("lu-4kw", 0.9), ("servo-2k2", 0.9)):
            c = closed_loop_cost(name, w, args.seconds)
            print(f"{name:<12} {w:>5.2f} Omega_0: mean {c['mean']:7.0f}, worst {c['worst']:6.0f} "
                  f"(square-wave start: worst {c['start_worst']:.0f}; {c['calls']:.0f} samples)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

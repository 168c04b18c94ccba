"""Heat: a lumped thermal network of the drive, fed by the plant's loss buckets, and the parameters that follow it.

The network (docs/thermal.md) is a set of **nodes** joined by thermal **links**:

- a *capacity* node ``i`` (winding, stator iron, magnets, housing, a switch's junction, a heat sink) has a heat
  capacity ``C_i`` (J/K) and a temperature ``T_i`` that evolves;
- a *boundary* node (ambient air, a coolant) has a fixed temperature;
- a link between two nodes conducts ``(T_a - T_b) / R`` (W), ``R`` its thermal resistance (K/W).

With ``T`` the capacity nodes' temperatures, ``T_b`` the boundary nodes', ``P`` the heat each capacity node receives
(the losses routed to it),

    C dT/dt = -G T + G_b T_b + P                                                       (1)

``G`` the conductance matrix among capacity nodes (Laplacian plus the ties to the boundary on its diagonal),
``G_b`` the ties to the boundary. ``G`` is symmetric positive definite when every capacity node has a path to a
boundary node (checked), so (1) has the steady state ``T_ss = G^-1 (G_b T_b + P)`` and, for ``P`` constant over a
step ``h``, the exact solution

    T(t + h) = T_ss + exp(-C^-1 G h) (T(t) - T_ss)                                      (2)

evaluated through the symmetric form ``S = C^-1/2 G C^-1/2 = V diag(lambda) V^T`` (eigenvalues ``lambda`` > 0):
``exp(-C^-1 G h) = C^-1/2 V diag(exp(-lambda h)) V^T C^1/2``, stable and exact for any ``h`` (Moler and Van Loan
2003; no step-size limit from the fastest node). The heat a step sends to the boundary is the exact integral of the
links' flows, from ``int_0^h T dt = T_ss h + C^-1/2 V diag((1 - exp(-lambda h)) / lambda) V^T C^1/2 (T(t) - T_ss)``,
so ``heat stored + heat to the boundary = losses`` holds to rounding (:meth:`ThermalNetwork.step`).

The network is the "Cauer" form: every node a physical temperature, so a switch's junction-to-case network can be
joined to a heat sink. A datasheet's Foster fit of ``Z_th,JC(t)`` (terms ``R_i``, ``tau_i``) is turned into the
equivalent Cauer ladder by :func:`foster_to_cauer`.

**Losses to nodes.** The plant's loss buckets (:data:`LOSS_SOURCES`) are routed to nodes with fractions that sum
to one per bucket (``cu`` -> ``winding``; ``sw`` -> the junction node, ...); a bucket may also go to a boundary node
(heat leaving at once, e.g. the source resistance's loss in the battery and cables).

**Parameters that follow temperature** (:class:`Thermal`), linear about ``T_ref``:

    R(T_w)     = R (1 + alpha_R (T_w - T_ref))        copper: alpha_R = 1 / (234.5 K + T_ref) (IEC 60028)
    k_x(T_m)   = k_x (1 + alpha_k (T_m - T_ref))       the magnets' remanence: NdFeB about -0.12 %/K
    R_on(T_j)  = R_on (1 + alpha_Ron (T_j - T_ref))    MOSFET on-resistance

``T_w`` the mean of the winding nodes, ``T_m`` the magnet node, ``T_j`` the mean of the switch nodes. The plant
applies them between chunks of a run (``bc_sim_set_thermal``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import BldclabError
from ._checks import check_number
from .motorfile import Section, toml_table, toml_value
from .units import to_si

__all__ = ["COPPER_T0", "LOSS_SOURCES", "Thermal", "ThermalLink", "ThermalNetwork", "ThermalNode", "copper_alpha",
           "foster_to_cauer", "read_thermal", "thermal_tables"]

#: Copper's resistance is linear in temperature with its zero at -234.5 degC (annealed copper, IEC 60028; IEC
#: 60034-1 rounds it to 235 for winding-temperature measurement by resistance): alpha(T_ref) = 1 / (234.5 + T_ref)
COPPER_T0 = 234.5

#: Loss sources a network takes, by name: what each is, the plant's integrated lane it comes from
#: (bc_plant.h, ``BC_ACC_*``). ``cu`` and the per-phase ``cu_a``, ``cu_b``, ``cu_c`` exclude each other.
LOSS_SOURCES: dict[str, tuple[str, str]] = {
    "cu": ("winding copper R(T) (i_a^2 + i_b^2 + i_c^2)", "cu"),
    "cu_a": ("copper of phase a, R(T) i_a^2", "i2a"),
    "cu_b": ("copper of phase b, R(T) i_b^2", "i2b"),
    "cu_c": ("copper of phase c, R(T) i_c^2", "i2c"),
    "fe": ("stator iron: eddy, hysteresis and excess loss", "fe"),
    "fric": ("friction: bearings and windage (B omega^2 + tau_c |omega|)", "fric"),
    "sw": ("switch conduction R_on(T) i^2", "sw"),
    "diode": ("diode conduction (V_f + r_d |i|) |i|", "diode"),
    "swloss": ("switching E_on + E_off at hard edges", "swloss"),
    "rr": ("diode reverse recovery E_rr", "rr"),
    "Rsrc": ("DC source resistance R_src i_dc^2 (battery, cables)", "Rsrc"),
}


def copper_alpha(T_ref: float) -> float:
    """Return copper's temperature coefficient of resistance at ``T_ref`` (degC): ``1 / (234.5 + T_ref)`` (1/K).

    0.393 %/K at 20 degC, 0.385 %/K at 25 degC (annealed copper, IEC 60028).
    """
    return 1.0 / (COPPER_T0 + float(T_ref))


@dataclass(frozen=True)
class ThermalNode:
    """A node of the network.

    Parameters
    ----------
    name : str
        Its name (a letter, then letters, digits or ``_``), e.g. ``"winding"``.
    C : float, optional
        Heat capacity (J/K), > 0: a node whose temperature evolves. ``None``: a boundary node (ambient, coolant)
        held at ``T``.
    T : float, optional
        A boundary node's temperature (degC), required for one; a capacity node's initial temperature (default:
        the first boundary node's).
    T_max : float, optional
        The node's temperature limit (degC): insulation class of a winding, the magnets' grade, a junction's
        rating. Studies (envelopes, derating checks) respect it.
    """

    name: str
    C: float | None = None
    T: float | None = None
    T_max: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or not (self.name[0].isalpha() and all(
                ch.isalnum() or ch == "_" for ch in self.name)):
            raise BldclabError("name", f"must be a name (a letter, then letters, digits, '_'), got {self.name!r}")
        check_number("C", self.C, lo=0.0, lo_open=True, allow_none=True)
        check_number("T", self.T, lo=-273.15, lo_open=True, allow_none=True)
        check_number("T_max", self.T_max, lo=-273.15, lo_open=True, allow_none=True)
        if self.C is None and self.T is None:
            raise BldclabError("T", "is missing: a node without a heat capacity C is a boundary (ambient, coolant) "
                               "and needs its fixed temperature T")

    @property
    def boundary(self) -> bool:
        """True for a boundary node (fixed temperature, no heat capacity)."""
        return self.C is None


@dataclass(frozen=True)
class ThermalLink:
    """A thermal resistance between two nodes.

    Parameters
    ----------
    a, b : str
        The nodes it joins (different).
    R : float
        Thermal resistance (K/W), > 0: the link conducts ``(T_a - T_b) / R``.
    """

    a: str
    b: str
    R: float

    def __post_init__(self) -> None:
        for key in ("a", "b"):
            if not isinstance(getattr(self, key), str):
                raise BldclabError(key, f"must be a node name, got {getattr(self, key)!r}")
        if self.a == self.b:
            raise BldclabError("between", f"joins node {self.a!r} to itself")
        check_number("R", self.R, lo=0.0, lo_open=True)


Routing = tuple[tuple[str, tuple[tuple[str, float], ...]], ...]


def _routing(losses: object) -> Routing:
    """Normalise ``{bucket: node or {node: fraction}}`` to ``((bucket, ((node, fraction), ...)), ...)``."""
    if isinstance(losses, tuple) and all(isinstance(x, tuple) and len(x) == 2 and isinstance(x[1], tuple)
                                         for x in losses):
        items: Iterable[tuple[object, object]] = losses
    elif isinstance(losses, Mapping):
        items = losses.items()
    else:
        raise BldclabError("losses", f"expected a table of loss sources, got {type(losses).__name__}")
    out = []
    for bucket, where in items:
        field = f"losses.{bucket}"
        if isinstance(where, str):
            route: tuple[tuple[str, float], ...] = ((where, 1.0),)
        elif isinstance(where, Mapping):
            route = tuple((str(n), f) for n, f in where.items())
        elif isinstance(where, tuple):
            route = tuple(where)
        else:
            raise BldclabError(field, "expected a node name or a table {node = fraction, ...}")
        for node, frac in route:
            check_number(f"{field}.{node}", frac, lo=0.0, lo_open=True, hi=1.0)
        out.append((str(bucket), tuple((n, float(f)) for n, f in route)))
    return tuple(out)


@dataclass(frozen=True)
class Thermal:
    """The drive's thermal model: network, loss routing, temperature coefficients, sensors.

    Parameters
    ----------
    nodes : tuple of ThermalNode
        At least one boundary node and one capacity node; names unique.
    links : tuple of ThermalLink
        Every capacity node needs a path to a boundary node.
    losses : mapping
        Where each loss source goes: ``{"cu": "winding", "fric": {"magnets": 0.5, "housing": 0.5}}``; sources in
        :data:`LOSS_SOURCES`, fractions of one source summing to 1. A source the drive produces but the network
        does not route is refused when the model is used (:meth:`check_sources`).
    T_ref : float
        Temperature (degC) at which the drive's ``R``, back-EMF and ``R_on`` are given; default 25.
    alpha_R : float, optional
        Winding resistance coefficient (1/K) at ``T_ref``; default copper's ``1 / (234.5 + T_ref)``.
    alpha_k : float
        The magnets' flux (remanence) coefficient (1/K): sintered NdFeB about -0.0012 (default), SmCo -0.00035,
        hard ferrite -0.002.
    alpha_Ron : float
        The switches' on-resistance coefficient (1/K), default 0 (no change).
    winding : tuple of str
        Nodes whose mean temperature sets ``R`` (default ``("winding",)``).
    magnets : str, optional
        Node whose temperature sets the back-EMF (default ``"magnets"`` if there is one); ``None``: fixed flux.
    switches : tuple of str
        Nodes whose mean temperature sets ``R_on``; empty: ``R_on`` at ``T_ref``.
    sensor_winding, sensor_switch : str, optional
        Nodes the controller's temperature inputs read (an NTC in the winding; one on the heat sink or the
        switches' board); ``None``: no such sensor (the controller's input reads invalid).
    """

    nodes: tuple[ThermalNode, ...]
    links: tuple[ThermalLink, ...]
    losses: Any
    T_ref: float = 25.0
    alpha_R: float | None = None
    alpha_k: float = -0.0012
    alpha_Ron: float = 0.0
    winding: tuple[str, ...] = ("winding",)
    magnets: str | None = "magnets"
    switches: tuple[str, ...] = ()
    sensor_winding: str | None = None
    sensor_switch: str | None = None

    def __post_init__(self) -> None:
        nodes = tuple(self.nodes)
        if not all(isinstance(n, ThermalNode) for n in nodes):
            raise BldclabError("nodes", "must be ThermalNode objects")
        object.__setattr__(self, "nodes", nodes)
        names = [n.name for n in nodes]
        for j, nm in enumerate(names):
            if nm in names[:j]:
                raise BldclabError(f"nodes.{nm}", "is defined twice")
        if not any(n.boundary for n in nodes):
            raise BldclabError("nodes", "needs a boundary node (ambient or coolant: T given, no C)")
        if all(n.boundary for n in nodes):
            raise BldclabError("nodes", "needs a node with a heat capacity C")
        links = tuple(self.links)
        if not all(isinstance(x, ThermalLink) for x in links):
            raise BldclabError("links", "must be ThermalLink objects")
        object.__setattr__(self, "links", links)
        for j, x in enumerate(links):
            for end in (x.a, x.b):
                if end not in names:
                    raise BldclabError(f"links[{j}].between", f"names no node {end!r} (nodes: {', '.join(names)})")
        # every capacity node reaches a boundary node
        reach = {n.name for n in nodes if n.boundary}
        grew = True
        while grew:
            grew = False
            for x in links:
                if (x.a in reach) != (x.b in reach):
                    reach |= {x.a, x.b}
                    grew = True
        for n in nodes:
            if n.name not in reach:
                raise BldclabError(f"nodes.{n.name}", "has no path of links to a boundary node: its temperature "
                                   "would rise without limit")
        routing = _routing(self.losses)
        seen = set()
        for bucket, route in routing:
            if bucket not in LOSS_SOURCES:
                raise BldclabError(f"losses.{bucket}", f"is not a loss source (use {', '.join(LOSS_SOURCES)})")
            if bucket in seen:
                raise BldclabError(f"losses.{bucket}", "is routed twice")
            seen.add(bucket)
            for node, _ in route:
                if node not in names:
                    raise BldclabError(f"losses.{bucket}", f"names no node {node!r} (nodes: {', '.join(names)})")
            total = sum(f for _, f in route)
            if abs(total - 1.0) > 1e-9:
                raise BldclabError(f"losses.{bucket}", f"fractions must add up to 1 (all of the loss goes "
                                   f"somewhere), got {total:.12g}")
        if "cu" in seen and seen & {"cu_a", "cu_b", "cu_c"}:
            raise BldclabError("losses.cu", "cannot be routed with cu_a, cu_b, cu_c: route the whole copper loss "
                               "or each phase's")
        if seen & {"cu_a", "cu_b", "cu_c"} and not {"cu_a", "cu_b", "cu_c"} <= seen:
            missing = sorted({"cu_a", "cu_b", "cu_c"} - seen)[0]
            raise BldclabError(f"losses.{missing}", "is missing: route every phase's copper loss")
        object.__setattr__(self, "losses", routing)
        check_number("T_ref", self.T_ref, lo=-273.15, lo_open=True)
        check_number("alpha_R", self.alpha_R, lo=-0.1, hi=0.1, allow_none=True)
        check_number("alpha_k", self.alpha_k, lo=-0.1, hi=0.1)
        check_number("alpha_Ron", self.alpha_Ron, lo=-0.1, hi=0.1)
        cap = {n.name for n in nodes if not n.boundary}
        for key in ("winding", "switches"):
            v = getattr(self, key)
            v = (v,) if isinstance(v, str) else tuple(v)
            object.__setattr__(self, key, v)
            for nm in v:
                if nm not in cap:
                    raise BldclabError(key, f"names {nm!r}, which is not a node with a heat capacity "
                                       f"({', '.join(sorted(cap))})")
        if not self.winding:
            raise BldclabError("winding", "needs at least one node (the winding's temperature sets R)")
        for key in ("magnets", "sensor_winding", "sensor_switch"):
            v = getattr(self, key)
            if v is None:
                continue
            if key == "magnets" and v == "magnets" and v not in names:
                object.__setattr__(self, key, None)  # the default names a node the network does not have
                continue
            if v not in cap:
                raise BldclabError(key, f"names {v!r}, which is not a node with a heat capacity "
                                   f"({', '.join(sorted(cap))})")

    # ------------------------------------------------------------------------------------------------------
    @property
    def alpha_R_value(self) -> float:
        """The winding resistance coefficient used (1/K): ``alpha_R`` or copper's at ``T_ref``."""
        return copper_alpha(self.T_ref) if self.alpha_R is None else float(self.alpha_R)

    @property
    def routing(self) -> dict[str, dict[str, float]]:
        """Return the loss routing as ``{source: {node: fraction}}``."""
        return {b: dict(route) for b, route in self.losses}

    @property
    def ambient(self) -> float:
        """The first boundary node's temperature (degC): the default initial temperature."""
        return float(next(n.T for n in self.nodes if n.boundary and n.T is not None))

    def node(self, name: str) -> ThermalNode:
        """Return the node called ``name``."""
        for n in self.nodes:
            if n.name == name:
                return n
        raise BldclabError("thermal.node", f"no node {name!r}")

    def network(self) -> ThermalNetwork:
        """Return the network's matrices (:class:`ThermalNetwork`)."""
        return ThermalNetwork(self)

    def with_ambient(self, T: float) -> Thermal:
        """Return the model with every boundary node at ``T`` (degC)."""
        check_number("ambient", T, lo=-273.15, lo_open=True)
        nodes = tuple(dataclasses.replace(n, T=float(T)) if n.boundary else n for n in self.nodes)
        return dataclasses.replace(self, nodes=nodes)

    def with_cooling(self, factor: float) -> Thermal:
        """Return the model with every link to a boundary node ``factor`` times as conductive (forced air, a fan)."""
        check_number("cooling", factor, lo=0.0, lo_open=True)
        bnd = {n.name for n in self.nodes if n.boundary}
        links = tuple(dataclasses.replace(x, R=x.R / factor) if (x.a in bnd or x.b in bnd) else x for x in self.links)
        return dataclasses.replace(self, links=links)

    def scales(self, temps: Mapping[str, float]) -> tuple[float, float, float]:
        """Return ``(r_scale, k_scale, ron_scale)`` at the node temperatures ``temps`` (degC).

        ``r = 1 + alpha_R (T_w - T_ref)`` (mean of the winding nodes), ``k = 1 + alpha_k (T_m - T_ref)`` (the magnet
        node; 1 without one), ``ron = 1 + alpha_Ron (T_j - T_ref)`` (mean of the switch nodes; 1 without).

        Raises
        ------
        BldclabError
            If a scale is not positive (a temperature far outside the linear law's range).
        """
        tw = float(np.mean([temps[n] for n in self.winding]))
        r = 1.0 + self.alpha_R_value * (tw - self.T_ref)
        k = 1.0 if self.magnets is None else 1.0 + self.alpha_k * (float(temps[self.magnets]) - self.T_ref)
        ron = 1.0 if not self.switches else 1.0 + self.alpha_Ron * (
            float(np.mean([temps[n] for n in self.switches])) - self.T_ref)
        for name, v in (("alpha_R", r), ("alpha_k", k), ("alpha_Ron", ron)):
            if not (math.isfinite(v) and v > 0.0):
                raise BldclabError(f"thermal.{name}", f"the linear law gives a factor {v:.4g} <= 0 at the node "
                                   f"temperatures {dict(temps)}: outside its range")
        return r, k, ron

    def check_sources(self, present: Iterable[str]) -> None:
        """Refuse if a loss source in ``present`` (the drive produces it) is not routed to a node.

        Raises
        ------
        BldclabError
            Naming ``thermal.losses.<source>``.
        """
        routed = {b for b, _ in self.losses}
        per_phase = {"cu_a", "cu_b", "cu_c"} <= routed
        for b in present:
            if b in routed or (b == "cu" and per_phase):
                continue
            raise BldclabError(f"thermal.losses.{b}", f"is missing: the drive has {LOSS_SOURCES[b][0]}, route "
                               f"it to a node (e.g. {b} = \"{self.winding[0]}\")")


class ThermalNetwork:
    """The matrices of a :class:`Thermal` model's network and its exact integration (module docstring, (1), (2)).

    Attributes
    ----------
    names : list of str
        The capacity nodes, in the order of every array here.
    boundary : list of str
        The boundary nodes.
    C : ndarray
        Heat capacities (J/K).
    G : ndarray
        Conductance matrix among capacity nodes (W/K), boundary ties on its diagonal.
    Gb : ndarray
        Ties to the boundary nodes (W/K), one column each.
    Tb : ndarray
        Boundary temperatures (degC).
    """

    def __init__(self, thermal: Thermal) -> None:
        self.thermal = thermal
        self.names = [n.name for n in thermal.nodes if not n.boundary]
        self.boundary = [n.name for n in thermal.nodes if n.boundary]
        ix = {nm: j for j, nm in enumerate(self.names)}
        bx = {nm: j for j, nm in enumerate(self.boundary)}
        n, m = len(self.names), len(self.boundary)
        self.C = np.array([thermal.node(nm).C for nm in self.names], dtype=float)
        self.Tb = np.array([thermal.node(nm).T for nm in self.boundary], dtype=float)
        G = np.zeros((n, n))
        Gb = np.zeros((n, m))
        for x in thermal.links:
            g = 1.0 / x.R
            for p, q in ((x.a, x.b), (x.b, x.a)):
                if p in ix:
                    G[ix[p], ix[p]] += g
                    if q in ix:
                        G[ix[p], ix[q]] -= g
                    else:
                        Gb[ix[p], bx[q]] += g
        self.G, self.Gb = G, Gb
        s = 1.0 / np.sqrt(self.C)
        lam, V = np.linalg.eigh(s[:, None] * G * s[None, :])
        self.lam = lam  # 1/s: the network's time constants are 1/lam
        self._V = V
        self._s = s
        # routing: source -> (heat to capacity nodes per watt, heat straight to the boundary per watt)
        self.route: dict[str, tuple[NDArray[np.float64], float]] = {}
        for bucket, route in thermal.losses:
            w = np.zeros(n)
            direct = 0.0
            for node, f in route:
                if node in ix:
                    w[ix[node]] += f
                else:
                    direct += f
            self.route[bucket] = (w, direct)

    @property
    def time_constants(self) -> NDArray[np.float64]:
        """The network's time constants (s), longest first: ``1 / lambda``."""
        return np.sort(1.0 / self.lam)[::-1]

    def initial(self) -> NDArray[np.float64]:
        """Return the initial temperatures (degC): each node's ``T`` if given, else the ambient."""
        amb = self.thermal.ambient
        return np.array([self.thermal.node(nm).T if self.thermal.node(nm).T is not None else amb
                         for nm in self.names], dtype=float)

    def heat(self, losses: Mapping[str, float]) -> tuple[NDArray[np.float64], float]:
        """Return the heat into the capacity nodes (W, array) and straight to the boundary (W) of ``losses`` (W).

        ``losses`` maps loss sources to powers; ``cu`` given while the network routes per phase is split in three
        equal parts (a balanced winding). A source not routed raises (:meth:`Thermal.check_sources`).
        """
        P = np.zeros(len(self.names))
        direct = 0.0
        for b, p in losses.items():
            if p == 0.0:
                continue
            if b == "cu" and b not in self.route and "cu_a" in self.route:
                for ph in ("cu_a", "cu_b", "cu_c"):
                    w, d = self.route[ph]
                    P += w * p / 3.0
                    direct += d * p / 3.0
                continue
            if b not in self.route:
                self.thermal.check_sources([b])
            w, d = self.route[b]
            P += w * p
            direct += d * p
        return P, direct

    def steady(self, P: ArrayLike) -> NDArray[np.float64]:
        """Return the steady temperatures (degC) for the heat ``P`` (W) into the capacity nodes.

        ``T_ss = G^-1 (G_b T_b + P)``.
        """
        return np.asarray(np.linalg.solve(self.G, self.Gb @ self.Tb + np.asarray(P, dtype=float)))

    def step(self, T: ArrayLike, P: ArrayLike, h: float) -> tuple[NDArray[np.float64], float]:
        """Advance the temperatures ``T`` (degC) over ``h`` (s) with the heat ``P`` (W) held constant: exact.

        Returns
        -------
        T1 : ndarray
            The temperatures at the end (degC).
        Q_out : float
            The heat the links delivered to the boundary nodes over the step (J): with the stored heat
            ``sum C (T1 - T)`` it adds up to ``sum(P) h`` to rounding.
        """
        T0 = np.asarray(T, dtype=float)
        Tss = self.steady(P)
        if h <= 0.0:
            return T0.copy(), 0.0
        s, V, lam = self._s, self._V, self.lam
        x = (V.T @ ((T0 - Tss) / s))  # modal coordinates of C^1/2 (T0 - Tss)
        e = np.exp(-lam * h)
        T1 = Tss + s * (V @ (e * x))
        integ = Tss * h + s * (V @ (-np.expm1(-lam * h) / lam * x))  # int_0^h T dt
        # heat to the boundary: sum over boundary ties g (T_i - T_b) integrated
        q = float(np.sum(self.Gb * (integ[:, None] - h * self.Tb[None, :])))
        return T1, q

    def stored(self, T: ArrayLike) -> float:
        """Return the heat stored above the initial temperatures (J): ``sum C (T - T_0)``."""
        return float(np.sum(self.C * (np.asarray(T, dtype=float) - self.initial())))

    def temps(self, T: ArrayLike) -> dict[str, float]:
        """Return ``{node: temperature}`` for the capacity nodes' array ``T`` and the boundary nodes (degC)."""
        out = {nm: float(v) for nm, v in zip(self.names, np.asarray(T, dtype=float), strict=True)}
        out.update({nm: float(v) for nm, v in zip(self.boundary, self.Tb, strict=True)})
        return out


def foster_to_cauer(R: Sequence[float], tau: Sequence[float]) -> list[tuple[float, float]]:
    """Return the Cauer ladder ``[(C_1, R_1), (C_2, R_2), ...]`` equivalent to a Foster network ``(R_i, tau_i)``.

    A datasheet fits the junction-to-case step response as ``Z_th(t) = sum R_i (1 - exp(-t / tau_i))`` (Foster:
    RC pairs in series, ``C_i = tau_i / R_i``). Its nodes are not temperatures of the device, so it cannot be joined
    to a heat sink; the Cauer ladder with the same impedance ``Z(s) = sum R_i / (1 + s tau_i)`` can. The ladder (from
    the junction: a capacity ``C_1`` to the reference, then ``R_1``, then ``C_2`` ...) comes from the continued
    fraction of the admittance ``Y(s) = 1 / Z(s) = s C_1 + 1 / (R_1 + 1 / (s C_2 + ...))`` (Infineon application
    note AN2008-03, "Thermal equivalent circuit models", 2008).

    Parameters
    ----------
    R : sequence of float
        Foster resistances (K/W), > 0.
    tau : sequence of float
        Their time constants (s), > 0, distinct.

    Returns
    -------
    list of (float, float)
        ``(C_k, R_k)`` pairs (J/K, K/W) from the junction side; ``sum R_k = sum R_i``.

    Raises
    ------
    BldclabError
        For bad terms, or a fit whose continued fraction is not a passive ladder (rounding with many terms).
    """
    if len(R) != len(tau) or not R:
        raise BldclabError("foster", "needs as many resistances as time constants, at least one")
    for j, (r, t) in enumerate(zip(R, tau, strict=True)):
        check_number(f"foster.R[{j}]", r, lo=0.0, lo_open=True)
        check_number(f"foster.tau[{j}]", t, lo=0.0, lo_open=True)
    P = np.polynomial.Polynomial
    # Z(s) = N(s) / D(s), D = prod (1 + s tau_i) of degree n, N = sum R_i prod_{j != i} (1 + s tau_j) of degree n - 1
    D = P([1.0])
    for t in tau:
        D = D * P([1.0, float(t)])
    N = P([0.0])
    for i, r in enumerate(R):
        term = P([float(r)])
        for j, t in enumerate(tau):
            if j != i:
                term = term * P([1.0, float(t)])
        N = N + term
    d, nn = D.coef.copy(), N.coef.copy()  # ascending coefficients, len(d) = len(nn) + 1
    out: list[tuple[float, float]] = []
    while len(nn) >= 1 and len(d) >= 2:
        # Y = D / N = s C + D' / N
        c = d[-1] / nn[-1]
        d = (d - np.concatenate(([0.0], c * nn)))[:-1]
        # Z' = N / D' = R + N' / D'   (equal degrees)
        r = nn[-1] / d[-1]
        nn = (nn - r * d)[:-1]
        if not (c > 0 and r > 0 and math.isfinite(c) and math.isfinite(r)):
            raise BldclabError("foster", "the continued fraction is not a passive ladder (too many terms for the "
                               "rounding, or a degenerate fit)")
        out.append((float(c), float(r)))
    return out


# ----------------------------------------------------------------------------------------------------------
# motor files: [thermal]

_COEFFS = ("alpha_R", "alpha_k", "alpha_Ron")


def read_thermal(sec: Section) -> Thermal:
    """Read a ``[thermal]`` table (docs/motor-files.md, "[thermal]") into a :class:`Thermal`.

    Raises
    ------
    BldclabError
        Naming the field (``thermal.nodes.winding.C``, ``thermal.links[2].R``, ...) and the problem.
    """
    ns = sec.sub("nodes")
    if ns is None:
        raise BldclabError(sec.name("nodes"), "is missing (a [thermal.nodes] table: name = {C = ..., T = ...})")
    nodes = []
    for name in list(ns.data):
        sub = ns.sub(name)
        assert sub is not None
        kw = {"C": sub.quantity("C", "heat_capacity", None), "T": sub.quantity("T", "temperature", None),
              "T_max": sub.quantity("T_max", "temperature", None)}
        sub.finish()
        try:
            nodes.append(ThermalNode(name=name, **kw))
        except BldclabError as exc:
            raise BldclabError(sub.name(exc.field) if exc.field != "name" else sub.prefix, exc.problem) from None
    ns.finish()
    raw = sec.raw("links", None)
    if raw is None:
        raise BldclabError(sec.name("links"), "is missing ([[thermal.links]] tables: between = [a, b], R = ...)")
    if not isinstance(raw, list):
        raise BldclabError(sec.name("links"), "must be a list of tables ([[thermal.links]])")
    links = []
    for j, item in enumerate(raw):
        ls = Section(item, f"{sec.name('links')}[{j}]")
        between = ls.raw("between")
        if not (isinstance(between, list) and len(between) == 2 and all(isinstance(v, str) for v in between)):
            raise BldclabError(ls.name("between"), f"must be two node names, got {between!r}")
        R = ls.quantity("R", "thermal_resistance")
        ls.finish()
        try:
            links.append(ThermalLink(between[0], between[1], R))
        except BldclabError as exc:
            raise BldclabError(ls.name(exc.field), exc.problem) from None
    lsec = sec.sub("losses")
    if lsec is None:
        raise BldclabError(sec.name("losses"), "is missing (a [thermal.losses] table: cu = \"winding\", ...)")
    routing: dict[str, Any] = {}
    for key in list(lsec.data):
        v = lsec.raw(key)
        if isinstance(v, str):
            routing[key] = v
        elif isinstance(v, Mapping):
            fr = {}
            for node, f in v.items():
                fr[node] = to_si(f, "dimensionless", f"{lsec.name(key)}.{node}")
            routing[key] = fr
        else:
            raise BldclabError(lsec.name(key), "expected a node name or a table {node = fraction, ...}")
    lsec.finish()
    kw2: dict[str, Any] = {}
    if sec.has("T_ref"):
        kw2["T_ref"] = sec.quantity("T_ref", "temperature")
    for key in _COEFFS:
        if sec.has(key):
            kw2[key] = sec.quantity(key, "temperature_coefficient")
    for key in ("winding", "switches"):
        if sec.has(key):
            v = sec.raw(key)
            if isinstance(v, str):
                v = [v]
            if not (isinstance(v, list) and all(isinstance(x, str) for x in v)):
                raise BldclabError(sec.name(key), f"must be a node name or a list of them, got {v!r}")
            kw2[key] = tuple(v)
    for key in ("magnets", "sensor_winding", "sensor_switch"):
        if sec.has(key):
            kw2[key] = sec.string(key)
    sec.finish()
    try:
        return Thermal(nodes=tuple(nodes), links=tuple(links), losses=routing, **kw2)
    except BldclabError as exc:
        raise BldclabError(sec.name(exc.field), exc.problem) from None


def thermal_tables(th: Thermal) -> list[str]:
    """Return the ``[thermal]`` tables of a model (SI numbers: degC, K/W, J/K, 1/K), as :func:`read_thermal` reads."""
    top: dict[str, object] = {"T_ref": float(th.T_ref)}
    if th.alpha_R is not None:
        top["alpha_R"] = float(th.alpha_R)
    top["alpha_k"] = float(th.alpha_k)
    top["alpha_Ron"] = float(th.alpha_Ron)
    top["winding"] = list(th.winding)
    if th.magnets is not None:
        top["magnets"] = th.magnets
    if th.switches:
        top["switches"] = list(th.switches)
    for key in ("sensor_winding", "sensor_switch"):
        if getattr(th, key) is not None:
            top[key] = getattr(th, key)
    out = [toml_table("thermal", top)]
    lines = ["[thermal.nodes]"]
    for n in th.nodes:
        items = ", ".join(f"{k} = {toml_value(float(v))}" for k, v in (("C", n.C), ("T", n.T), ("T_max", n.T_max))
                          if v is not None)
        lines.append(f"{n.name} = {{ {items} }}")
    out.append("\n".join(lines) + "\n")
    for x in th.links:
        out.append(f"[[thermal.links]]\nbetween = {toml_value([x.a, x.b])}\nR = {toml_value(float(x.R))}\n")
    lines = ["[thermal.losses]"]
    for b, route in th.losses:
        if len(route) == 1 and route[0][1] == 1.0:
            lines.append(f"{b} = {toml_value(route[0][0])}")
        else:
            lines.append(f"{b} = {{ " + ", ".join(f"{n} = {toml_value(f)}" for n, f in route) + " }")
    out.append("\n".join(lines) + "\n")
    return out

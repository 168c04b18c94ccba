"""Multirate coupling of the switching plant and the thermal network (docs/thermal.md, "Coupled runs").

The plant runs in chunks of ``h`` seconds (whole controller samples). After each chunk the runner's integrated loss
lanes (``bc_plant.h``'s ``acc[]``: the exact integrals of every loss over the chunk) give each loss source's mean
power over it; the network (:class:`~bldclab.model.thermal.ThermalNetwork`) advances exactly over the chunk with
those powers held constant; the new temperatures set the plant's ``R``, back-EMF and ``R_on`` for the next chunk
(``bc_sim_set_thermal``), and the network's sensor nodes (``sensor_winding``, ``sensor_switch``) what the
controller's temperature inputs read (``bc_sim_set_temperatures``, ``bc_ctrl_in.temp``: a controller with a
:class:`~bldclab.control.TemperatureDerating` derates its current limit with them). The heat the network receives
is the heat the plant dissipated, to rounding, so the coupled run's energy balance closes: heat stored + heat to
the boundary = losses.

The error of the coupling is that of holding the parameters over a chunk: the temperatures move by
``dT/dt h`` within it, so a chunk much shorter than the network's fastest time constant of interest (the winding's
minutes; a junction's tens of milliseconds) makes it negligible. The network itself is exact at any ``h``.
"""

from __future__ import annotations

import ctypes
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import BldclabError
from ..model._checks import check_number
from ..model.motor import Drive
from ..model.thermal import LOSS_SOURCES, Thermal, ThermalNetwork

__all__ = ["ThermalCoupling", "ThermalTrace"]


@dataclass(frozen=True)
class ThermalCoupling:
    """How :func:`bldclab.simulate` couples the plant with the drive's thermal network (``thermal=``).

    Parameters
    ----------
    h : float
        Thermal step (s): the plant runs this long between updates of the temperatures (rounded to whole samples).
    T0 : mapping, optional
        Initial temperatures (degC) of capacity nodes by name; the others start at their file's ``T`` or the
        ambient.
    ambient : float, optional
        Every boundary node's temperature (degC) instead of the file's.
    follow : bool
        True (default): ``R``, the back-EMF and ``R_on`` follow the temperatures; False: the temperatures are
        computed but the plant keeps its parameters at ``T_ref`` (to see what the dependence does).
    """

    h: float = 0.05
    T0: Mapping[str, float] | None = None
    ambient: float | None = None
    follow: bool = True

    def __post_init__(self) -> None:
        check_number("thermal.h", self.h, lo=0.0, lo_open=True)
        if self.ambient is not None:
            check_number("thermal.ambient", self.ambient, lo=-273.15, lo_open=True)
        if not isinstance(self.follow, bool):
            raise BldclabError("thermal.follow", f"must be True or False, got {self.follow!r}")

    def model(self, drive: Drive) -> Thermal:
        """Return the drive's thermal model with this coupling's ambient; refuse a drive without one."""
        th = drive.thermal
        if th is None:
            raise BldclabError("thermal", f"drive {drive.name!r} has no thermal model ([thermal] in its motor file)")
        th.check_sources(drive.loss_sources)
        return th if self.ambient is None else th.with_ambient(self.ambient)

    def initial(self, net: ThermalNetwork) -> NDArray[np.float64]:
        """Return the initial temperatures of the network's capacity nodes (degC)."""
        T = net.initial()
        for name, v in (self.T0 or {}).items():
            if name not in net.names:
                raise BldclabError(f"thermal.T0.{name}", f"is not a node with a heat capacity ({', '.join(net.names)})")
            check_number(f"thermal.T0.{name}", v, lo=-273.15, lo_open=True)
            T[net.names.index(name)] = float(v)
        return T


@dataclass
class ThermalTrace:
    """Temperatures, losses and parameter scales at the thermal time scale, one row per thermal step.

    Attributes
    ----------
    t : ndarray
        End of each step (s); row 0 is the start (t = 0, no losses yet).
    T : dict of str to ndarray
        Temperature of each node (degC), capacity and boundary nodes.
    P : dict of str to ndarray
        Mean power of each routed loss source over the step ending at ``t`` (W); 0 in row 0.
    r_scale, k_scale, ron_scale : ndarray
        The plant's ``R``, back-EMF and ``R_on`` factors in force during the step ending at ``t`` (row 0: at the
        start).
    E_loss, E_stored, E_out : float
        Losses over the run (J), heat stored in the network (above its initial temperatures) and heat delivered to
        the boundary nodes (links plus sources routed there directly): ``E_stored + E_out = E_loss`` to rounding.
    extra : dict of str to ndarray
        Further per-step signals: ``tau`` (mean torque over the step, N m) and, from
        :func:`bldclab.analysis.thermal.run_profile`, ``speed``, ``torque_ref``, ``derate``.
    """

    t: NDArray[np.float64]
    T: dict[str, NDArray[np.float64]]
    P: dict[str, NDArray[np.float64]]
    r_scale: NDArray[np.float64]
    k_scale: NDArray[np.float64]
    ron_scale: NDArray[np.float64]
    E_loss: float = 0.0
    E_stored: float = 0.0
    E_out: float = 0.0
    extra: dict[str, NDArray[np.float64]] = field(default_factory=dict)

    @property
    def balance(self) -> float:
        """``(E_stored + E_out - E_loss) / E_loss`` (-): the coupled run's heat balance, zero to rounding."""
        return (self.E_stored + self.E_out - self.E_loss) / self.E_loss if self.E_loss else 0.0

    def final(self) -> dict[str, float]:
        """Return the last temperatures (degC)."""
        return {k: float(v[-1]) for k, v in self.T.items()}

    def summary(self) -> dict[str, Any]:
        """Return a JSON-able summary (final and peak temperatures, energies, balance)."""
        return {"final": self.final(), "peak": {k: float(np.max(v)) for k, v in self.T.items()},
                "E_loss": self.E_loss, "E_stored": self.E_stored, "E_out": self.E_out, "balance": self.balance,
                "steps": int(self.t.size - 1)}

    def to_pandas(self) -> Any:
        """Return the trace as a :class:`pandas.DataFrame` (columns ``T_<node>``, ``P_<source>``, scales)."""
        import pandas as pd

        cols: dict[str, Any] = {"t": self.t}
        cols.update({f"T_{k}": v for k, v in self.T.items()})
        cols.update({f"P_{k}": v for k, v in self.P.items()})
        cols.update({"r_scale": self.r_scale, "k_scale": self.k_scale, "ron_scale": self.ron_scale})
        cols.update(self.extra)
        return pd.DataFrame(cols)


class Coupler:
    """The per-chunk work of a coupled run (used by :func:`bldclab.simulate`)."""

    def __init__(self, coupling: ThermalCoupling, drive: Drive, acc_names: tuple[str, ...]) -> None:
        self.coupling = coupling
        self.th = coupling.model(drive)
        self.net = self.th.network()
        self.T = coupling.initial(self.net)
        self.T_start = self.T.copy()
        self.lanes = {name: j for j, name in enumerate(acc_names)}
        self.sources = [b for b, _ in self.th.losses]
        self.R = drive.motor.R
        self.acc0: NDArray[np.float64] | None = None
        self.t0 = 0.0
        self.scales = self._scales()
        self.rows_t = [0.0]
        self.rows_T = [self.T.copy()]
        self.rows_P = [np.zeros(len(self.sources))]
        self.rows_s = [self.scales]
        self.rows_tau = [float("nan")]
        self.E_loss = self.E_out = 0.0

    def _scales(self) -> tuple[float, float, float]:
        if not self.coupling.follow:
            return (1.0, 1.0, 1.0)
        return self.th.scales(self.net.temps(self.T))

    def apply(self, lib: Any, cfg: Any, state: Any) -> None:
        """Set the plant's parameters at the current temperatures (``bc_sim_set_thermal``)."""
        r, k, ron = self.scales
        rc = lib.bc_sim_set_thermal(cfg.ctypes.data, state.ctypes.data, ctypes.c_double(r), ctypes.c_double(k),
                                    ctypes.c_double(ron))
        if rc != 0:
            raise BldclabError("thermal", f"the plant refused the temperature scales R x {r:.4g}, k x {k:.4g}, "
                               f"R_on x {ron:.4g}")
        temps = self.net.temps(self.T)
        sensed = [temps[n] if n is not None else float("nan") for n in (self.th.sensor_winding, self.th.sensor_switch)]
        lib.bc_sim_set_temperatures(cfg.ctypes.data, state.ctypes.data, ctypes.c_double(sensed[0]),
                                    ctypes.c_double(sensed[1]))

    def start(self, acc: NDArray[np.float64]) -> None:
        """Record the loss lanes at the start of the run."""
        self.acc0 = np.array(acc, dtype=float)

    def chunk(self, t: float, acc: NDArray[np.float64]) -> None:
        """Advance the network over the chunk that ended at ``t`` (s), given the loss lanes ``acc`` then."""
        assert self.acc0 is not None
        h = t - self.t0
        if h <= 0.0:
            return
        d = np.asarray(acc, dtype=float) - self.acc0
        self.acc0 = np.array(acc, dtype=float)
        r = self.scales[0]
        powers = {}
        for b in self.sources:
            lane = LOSS_SOURCES[b][1]
            e = d[self.lanes[lane]]
            if b in ("cu_a", "cu_b", "cu_c"):
                e *= self.R * r  # the lane is the integral of i^2: times the phase's resistance in the chunk
            powers[b] = float(e) / h
        P, direct = self.net.heat(powers)
        self.T, q = self.net.step(self.T, P, h)
        self.E_loss += (float(np.sum(P)) + direct) * h
        self.E_out += q + direct * h
        self.t0 = t
        self.scales = self._scales()
        self.rows_t.append(t)
        self.rows_T.append(self.T.copy())
        self.rows_P.append(np.array([powers[b] for b in self.sources]))
        self.rows_s.append(self.scales)
        self.rows_tau.append(float(d[self.lanes["tau"]]) / h)

    def trace(self) -> ThermalTrace:
        """Return the trace of the run so far."""
        T = np.array(self.rows_T)
        temps = {nm: T[:, j] for j, nm in enumerate(self.net.names)}
        temps.update({nm: np.full(T.shape[0], v) for nm, v in zip(self.net.boundary, self.net.Tb, strict=True)})
        P = np.array(self.rows_P)
        s = np.array(self.rows_s)
        # the scales in force during step j were computed at its start: shift by one row
        s_during = np.vstack([s[:1], s[:-1]])
        stored = float(np.sum(self.net.C * (self.T - self.T_start)))
        return ThermalTrace(t=np.array(self.rows_t), T=temps, P={b: P[:, j] for j, b in enumerate(self.sources)},
                            r_scale=s_during[:, 0], k_scale=s_during[:, 1], ron_scale=s_during[:, 2],
                            E_loss=self.E_loss, E_stored=stored, E_out=self.E_out,
                            extra={"tau": np.array(self.rows_tau)})

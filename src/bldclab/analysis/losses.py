"""The loss buckets of an operating point, named in one place, and the efficiencies computed from them.

:data:`LOSS_BUCKETS` lists the :class:`~bldclab.sim.results.Metrics` fields that are losses;
:func:`point_losses` closes the accounting of one measured window,
``p_src_total = p_shaft + sum(buckets) + p_stored + residue``, and gives its efficiency.
:mod:`bldclab.analysis.effmap` (the efficiency maps) and :mod:`bldclab.analysis.compare` (paper 1's efficiency
comparison) both read them from here, so a loss the plant adds (a new ``Metrics`` field) is added once, here.
"""

from __future__ import annotations

import dataclasses

from ..sim.results import Metrics, efficiency_of

__all__ = ["LOSS_BUCKETS", "NOT_LOSSES", "copper_only_efficiency", "efficiency", "loss_buckets", "point_losses"]

#: The loss buckets, by their :class:`~bldclab.sim.results.Metrics` field names (W): source resistance, windings,
#: switch conduction, diodes, switching, diode recovery, friction, stator iron. A bucket the plant does not report
#: (yet) is skipped; add a new one here.
LOSS_BUCKETS: tuple[str, ...] = ("p_Rsrc", "p_cu", "p_sw", "p_diode", "p_swloss", "p_rr", "p_fric", "p_fe")
#: The ``p_*`` fields of :class:`~bldclab.sim.results.Metrics` that are not losses: the input, the load, and the
#: two that make up the shaft power with friction and iron loss. Every other ``p_*`` field must be in
#: :data:`LOSS_BUCKETS` (a test checks it, so a bucket added to the plant is not silently left out of the maps).
NOT_LOSSES: tuple[str, ...] = ("p_src", "p_src_total", "p_load", "p_emf", "p_cog")


def loss_buckets() -> tuple[str, ...]:
    """Return the loss buckets of :data:`LOSS_BUCKETS` that :class:`~bldclab.sim.results.Metrics` has."""
    names = {f.name for f in dataclasses.fields(Metrics)}
    return tuple(b for b in LOSS_BUCKETS if b in names)


def efficiency(p_in: float, p_out: float) -> float:
    """Motoring: output over input power; generating (both negative): input over output; else nan.

    Parameters
    ----------
    p_in : float
        Power flowing in from the electrical side (W); negative when the machine generates.
    p_out : float
        Power flowing out on the mechanical side (W); negative when the machine is driven.

    Returns
    -------
    float
        Efficiency (-), nan when both powers flow into the machine or neither does (no meaningful efficiency):
        :func:`bldclab.sim.results.efficiency_of`, the definition :attr:`Metrics.efficiency` uses.
    """
    return efficiency_of(p_in, p_out)[1]


def point_losses(m: Metrics, buckets: tuple[str, ...] | None = None) -> dict[str, float]:
    """Return the accounting of one measured window: input, shaft power, every loss bucket, efficiency.

    Parameters
    ----------
    m : Metrics
        The window's metrics.
    buckets : tuple of str, optional
        Loss buckets to read; default :func:`loss_buckets`.

    Returns
    -------
    dict of str to float
        ``p_in`` (``Metrics.p_src_total``, W), ``p_shaft`` (``p_emf + p_cog - p_fric - p_fe``, W), each bucket (W),
        ``p_loss`` (their sum, W), ``p_stored`` (change of the windings' magnetic energy over the window per second,
        W), ``residue`` (``p_in - p_shaft - p_loss - p_stored``, W) and ``efficiency``
        (:func:`efficiency` of ``p_in - p_stored`` and ``p_shaft``: every loss counted).
    """
    names = loss_buckets() if buckets is None else buckets
    shaft = m.p_emf + m.p_cog - m.p_fric - m.p_fe
    losses = {b: float(getattr(m, b)) for b in names}
    p_loss = sum(losses.values())
    p_stored = m.dW_L / (m.t1 - m.t0)  # zero in an exactly periodic steady state
    return {"p_in": m.p_src_total, "p_shaft": shaft, **losses, "p_loss": p_loss, "p_stored": p_stored,
            "residue": m.p_src_total - shaft - p_loss - p_stored,
            "efficiency": efficiency(m.p_src_total - p_stored, shaft)}


def copper_only_efficiency(m: Metrics) -> float:
    """Return the efficiency with the windings' copper loss as the only loss: ``P_m / (P_m + p_cu)``.

    Paper 1's (34) with its simplification ii) (mechanical and magnetic losses neglected) and no inverter losses,
    but with the simulated currents (commutation transients and PWM ripple included): ``P_m = p_emf + p_cog`` is
    the electromagnetic power. With every other loss zero it equals :func:`point_losses`' efficiency to the
    integration's energy balance.

    Parameters
    ----------
    m : Metrics
        The window's metrics.

    Returns
    -------
    float
        Efficiency (-), nan where input and output have different signs.
    """
    p_m = m.p_emf + m.p_cog
    return efficiency(p_m + m.p_cu, p_m)

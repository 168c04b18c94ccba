"""Hall angle options shared by the controllers: the edge table and the angle estimator (``bc_hall.h``).

Every Hall-commutated controller (:class:`~bldclab.control.SixStep`, :class:`~bldclab.control.Sine`,
:class:`~bldclab.control.Lu`) takes

- ``hall_table``: the angles of the six Hall edges (rad, electrical), edge ``j`` between sectors ``j-1`` and ``j``,
  nominally ``pi/6 + j pi/3``: six values (both directions) or twelve (six crossed forward, then six crossed
  backward); e.g. the ``table`` of :func:`bldclab.sim.hallcal.calibrate`. ``None``: the nominal edges.
- an estimator choice: (46) (interpolation from the last edge at the speed of the last edge interval) or ``"pll"``,
  a tracking loop on the edges with a time constant of ``pll_edges`` edges (``docs/hall-calibration.md``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .._core import Core
from ..errors import BldclabError

__all__ = ["NOMINAL_EDGES", "check_hall_options", "hall_record", "normalize_table"]

#: Nominal edge angles (rad, electrical): edge j at pi/6 + j pi/3
NOMINAL_EDGES: tuple[float, ...] = tuple(math.pi / 6 + j * math.pi / 3 for j in range(6))


def _wrap_pm(x: float) -> float:
    return (x + math.pi) % (2 * math.pi) - math.pi


def normalize_table(table: object, field: str = "control.hall_table") -> tuple[float, ...] | None:
    """Return a Hall edge table as a tuple of 6 or 12 floats (rad), or ``None``.

    Raises
    ------
    BldclabError
        If it is not 6 or 12 finite numbers each within 30 electrical degrees (exclusive) of its nominal edge.
    """
    if table is None:
        return None
    if isinstance(table, str | bytes) or not isinstance(table, Sequence | np.ndarray):
        raise BldclabError(field, f"expected 6 or 12 edge angles (rad), got {type(table).__name__}")
    vals = list(table)
    if len(vals) not in (6, 12):
        raise BldclabError(field, f"needs 6 edge angles (or 12: forward, then backward), got {len(vals)}")
    out = []
    for j, v in enumerate(vals):
        if isinstance(v, bool) or not isinstance(v, int | float | np.integer | np.floating) or not math.isfinite(v):
            raise BldclabError(f"{field}[{j}]", f"must be a finite number (rad), got {v!r}")
        err = _wrap_pm(float(v) - NOMINAL_EDGES[j % 6])
        if abs(err) >= math.pi / 6:
            raise BldclabError(f"{field}[{j}]", f"edge {j % 6} at {float(v):.4g} rad is {math.degrees(err):.3g} "
                               "electrical degrees from its nominal angle; must be within (-30, 30)")
        out.append(float(v))
    return tuple(out)


def check_hall_options(pll_edges: object, hall_angle: object = "interp") -> None:
    """Check the Hall angle estimator ``hall_angle`` (interp or pll) and the loop's ``pll_edges`` (edges, 1 .. 1000)."""
    if hall_angle not in ("interp", "pll"):
        raise BldclabError("control.hall_angle", f"must be interp or pll, got {hall_angle!r}")
    if isinstance(pll_edges, bool) or not isinstance(pll_edges, int | float) or not 1 <= pll_edges <= 1000:
        raise BldclabError("control.pll_edges", f"must be a number of edges in [1, 1000], got {pll_edges!r}")


def hall_record(core: Core, pll: bool, pll_edges: float, table: tuple[float, ...] | None) -> dict[str, object]:
    """Return the ``hall_mode``, ``hall_pll_edges``, ``hall_table`` members of a controller's C params."""
    rec = core.record("bc_hall_table")
    if table is not None:
        rec["set"] = 1
        rec["fwd"] = table[:6]
        rec["bwd"] = table[6:] if len(table) == 12 else table[:6]
    return {"hall_mode": core.const("BC_HALL_PLL" if pll else "BC_HALL_INTERP"), "hall_pll_edges": float(pll_edges),
            "hall_table": rec[0]}

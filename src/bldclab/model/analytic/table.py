"""Paper 1 Table I and the characteristic (Figs 7-8) of a drive.

The derived quantities of section IV in one record (:func:`table1`) and its text as a table, CSV or JSON
(:func:`table1_text`), and torque, ripple and efficiency of both supplies over speed as a table
(:func:`characteristic`).
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ...errors import BldclabError
from ..emf import TWO_PI
from ..motor import Drive
from ._common import _speed
from .bases import omega_0, t_N
from .blac import T_BLAC_N_PU, t_blac_pu
from .efficiency import (
    eta_q,
    eta_ratio,
    eta_s,
    p_lCu_consistent_pu,
    p_lCu_pu,
    p_R_pu,
)
from .numeric import (
    omega_qB_numeric_pu,
    omega_sB_numeric_pu,
)
from .sine import (
    T_SN_PU,
    TR_SN_PU,
    condition_18,
    omega_sB_pu,
    theta_m,
)
from .speed_range import (
    region_q,
    region_s,
    t_q_pu,
    t_s_pu,
    tr_q_pu,
    tr_s_pu,
)
from .square import omega_qB_pu, t_qB_pu

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "CHARACTERISTIC_COLUMNS",
    "TABLE1_ROWS",
    "Table1",
    "characteristic",
    "table1",
    "table1_text",
]


@dataclass(frozen=True)
class Table1:
    """Paper 1 Table I and the other derived quantities of section IV, for one drive.

    Parameters
    ----------
    name : str
        Drive name.
    Omega_0 : float
        Speed base (2) (rad/s).
    T_N : float
        Torque base (6) (N m).
    Theta_m : float
        Motor-specific parameter (22) (rad).
    cond_18 : bool
        Whether (18)/(19) holds (``v_ab`` peaks at pi/6, so (20)-(21) are exact for R = 0).
    Omega_sB_pu : float
        Base speed with sinusoidal supply (21) (per unit).
    Omega_qB_pu : float
        Base speed with real square-wave supply (30) (per unit).
    T_qB_pu : float
        Square-wave torque at its base speed (31) (per unit).
    T_sN_pu : float
        Nominal torque with sinusoidal supply (13) (per unit).
    TR_sN_pu : float
        Torque ripple with sinusoidal supply (15) (per unit).
    T_blac_N_pu : float
        Nominal torque of the equivalent PM BLAC motor, section IV.B (per unit).
    P_R_pu : float
        Resistive parameter of (36) (-).
    eta_ratio_0955 : float
        ``eta_s / eta_q`` at ``Omega_pu = 0.955``, (40) with (36): (43).
    eta_ratio_0455 : float
        ``eta_s / eta_q`` at ``Omega_pu = 0.455``, (40) with (36): (44).
    eta_ratio_0955_consistent : float
        The same with the consistent loss count :func:`p_lCu_consistent_pu` (not in the paper).
    eta_ratio_0455_consistent : float
        The same with the consistent loss count :func:`p_lCu_consistent_pu` (not in the paper).
    Omega_sB_R_pu : float
        R-aware numeric base speed, sinusoidal supply (per unit).
    Omega_qB_R_pu : float
        R-aware numeric base speed, square-wave supply (per unit).
    ratio_sB_R : float
        ``Omega_sB_R_pu`` over the numeric base speed with R = 0 (equal to (21) for the ideal trapezoid).
    ratio_qB_R : float
        ``Omega_qB_R_pu`` over the numeric base speed with R = 0 (equal to (30) for the ideal trapezoid).

    """

    name: str
    Omega_0: float
    T_N: float
    Theta_m: float
    cond_18: bool
    Omega_sB_pu: float
    Omega_qB_pu: float
    T_qB_pu: float
    T_sN_pu: float
    TR_sN_pu: float
    T_blac_N_pu: float
    P_R_pu: float
    eta_ratio_0955: float
    eta_ratio_0455: float
    eta_ratio_0955_consistent: float
    eta_ratio_0455_consistent: float
    Omega_sB_R_pu: float
    Omega_qB_R_pu: float
    ratio_sB_R: float
    ratio_qB_R: float

    def to_dict(self) -> dict[str, float | str | bool]:
        """Return the fields as a plain dict (JSON-ready)."""
        return asdict(self)

    def rows(self) -> list[tuple[str, str, float | bool, str, str]]:
        """Return one row per quantity: ``(key, description, value, unit, source)``."""
        out: list[tuple[str, str, float | bool, str, str]] = []
        for key, (desc, unit, src) in TABLE1_ROWS.items():
            out.append((key, desc, getattr(self, key), unit, src))
        return out


#: Description, unit and source of each numeric :class:`Table1` field, in print order.
TABLE1_ROWS: dict[str, tuple[str, str, str]] = {
    "Omega_0": ("speed base (no-load speed)", "rad/s", "(2)"),
    "T_N": ("torque base (nominal torque)", "N m", "(6)"),
    "Theta_m": ("motor-specific parameter", "rad", "(22)"),
    "cond_18": ("v_ab peaks at pi/6 (R = 0)", "-", "(18)"),
    "Omega_sB_pu": ("base speed, sinusoidal supply", "pu", "(21)"),
    "Omega_qB_pu": ("base speed, square-wave supply", "pu", "(30)"),
    "T_qB_pu": ("torque at base speed, square-wave supply", "pu", "(31)"),
    "T_sN_pu": ("nominal torque, sinusoidal supply", "pu", "(13)"),
    "TR_sN_pu": ("torque ripple, sinusoidal supply", "pu", "(15)"),
    "T_blac_N_pu": ("nominal torque, equivalent BLAC motor", "pu", "IV.B"),
    "P_R_pu": ("resistive parameter P_R,pu", "-", "(36)"),
    "eta_ratio_0955": ("eta_s/eta_q at Omega_pu = 0.955", "-", "(40),(43)"),
    "eta_ratio_0455": ("eta_s/eta_q at Omega_pu = 0.455", "-", "(40),(44)"),
    "eta_ratio_0955_consistent": ("eta_s/eta_q at 0.955, losses 2 R I_N^2", "-", "docs"),
    "eta_ratio_0455_consistent": ("eta_s/eta_q at 0.455, losses 2 R I_N^2", "-", "docs"),
    "Omega_sB_R_pu": ("base speed with R, sinusoidal supply", "pu", "numeric"),
    "Omega_qB_R_pu": ("base speed with R, square-wave supply", "pu", "numeric"),
    "ratio_sB_R": ("base speed with R / without, sinusoidal", "-", "numeric"),
    "ratio_qB_R": ("base speed with R / without, square-wave", "-", "numeric"),
}


def table1(drive: Drive) -> Table1:
    """Compute paper 1 Table I and the related quantities of section IV for a drive.

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.

    Returns
    -------
    Table1

    """
    th = theta_m(drive)
    pcu = p_lCu_pu(drive)
    pcu_c = p_lCu_consistent_pu(drive)
    sB_R = omega_sB_numeric_pu(drive)
    qB_R = omega_qB_numeric_pu(drive)
    sB_0 = omega_sB_numeric_pu(drive, R=0.0)
    qB_0 = omega_qB_numeric_pu(drive, R=0.0)
    return Table1(
        name=drive.name,
        Omega_0=omega_0(drive),
        T_N=t_N(drive),
        Theta_m=th,
        cond_18=condition_18(drive),
        Omega_sB_pu=omega_sB_pu(th),
        Omega_qB_pu=omega_qB_pu(th),
        T_qB_pu=t_qB_pu(th),
        T_sN_pu=T_SN_PU,
        TR_sN_pu=TR_SN_PU,
        T_blac_N_pu=T_BLAC_N_PU,
        P_R_pu=p_R_pu(drive),
        eta_ratio_0955=float(eta_ratio(0.955, th, pcu)),
        eta_ratio_0455=float(eta_ratio(0.455, th, pcu)),
        eta_ratio_0955_consistent=float(eta_ratio(0.955, th, pcu_c)),
        eta_ratio_0455_consistent=float(eta_ratio(0.455, th, pcu_c)),
        Omega_sB_R_pu=sB_R,
        Omega_qB_R_pu=qB_R,
        ratio_sB_R=sB_R / sB_0,
        ratio_qB_R=qB_R / qB_0,
    )


#: Columns of :func:`characteristic`, in order.
CHARACTERISTIC_COLUMNS = ("Omega_pu", "Omega", "Omega_rpm", "T_s_pu", "T_q_pu", "TR_s_pu", "TR_q_pu", "T_s",
                          "T_q", "TR_s", "TR_q", "eta_s", "eta_q", "eta_ratio", "region_s", "region_q",
                          "T_blac_pu")


def characteristic(drive: Drive, speeds_pu: ArrayLike) -> pd.DataFrame:
    """Return the torque and ripple characteristics of both supplies at nominal current (paper 1 Figs 7-8).

    Parameters
    ----------
    drive : Drive
        The drive: motor and inverter data.
    speeds_pu : array_like
        Speeds (per unit of Omega_0), >= 0, one-dimensional.

    Returns
    -------
    pandas.DataFrame
        One row per speed; columns ``Omega_pu``, ``Omega`` (rad/s), ``Omega_rpm``, ``T_s_pu``, ``T_q_pu``,
        ``TR_s_pu``, ``TR_q_pu`` (per unit), ``T_s``, ``T_q``, ``TR_s``, ``TR_q`` (N m), ``eta_s``, ``eta_q``,
        ``eta_ratio`` ((38)-(40) with the paper's losses (36); NaN above the base speeds), ``region_s``,
        ``region_q`` (the equations used) and ``T_blac_pu`` (the equivalent BLAC motor).

    """
    w = _speed(speeds_pu, "speeds_pu")
    if w.ndim != 1:
        raise BldclabError("speeds_pu", "must be a one-dimensional list of speeds")
    th = theta_m(drive)
    w0, tn = omega_0(drive), t_N(drive)
    pcu = p_lCu_pu(drive)
    ts = np.asarray(t_s_pu(w, th))
    tq = np.asarray(t_q_pu(w, th))
    rs = np.asarray(tr_s_pu(w, th))
    rq = np.asarray(tr_q_pu(w, th))
    data = {
        "Omega_pu": w,
        "Omega": w * w0,
        "Omega_rpm": w * w0 * 60.0 / TWO_PI,
        "T_s_pu": ts,
        "T_q_pu": tq,
        "TR_s_pu": rs,
        "TR_q_pu": rq,
        "T_s": ts * tn,
        "T_q": tq * tn,
        "TR_s": rs * tn,
        "TR_q": rq * tn,
        "eta_s": np.asarray(eta_s(w, th, pcu)),
        "eta_q": np.asarray(eta_q(w, th, pcu)),
        "eta_ratio": np.asarray(eta_ratio(w, th, pcu)),
        "region_s": region_s(w, th),
        "region_q": region_q(w, th),
        "T_blac_pu": np.asarray(t_blac_pu(w, th)),
    }
    import pandas as pd  # imported here: `import bldclab` (and every sweep worker) starts 0.3 s faster without it

    return pd.DataFrame(data, columns=list(CHARACTERISTIC_COLUMNS))


def _fmt_value(value: float | bool) -> str:
    """Format a table value for people: yes/no for flags, n/a for NaN, 6 significant digits otherwise."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if math.isnan(value):
        return "n/a"
    return f"{value:.6g}"


def _json_value(value: float | bool) -> float | bool | None:
    """Return a JSON-safe value: NaN (a quantity undefined for this motor) becomes null."""
    if isinstance(value, float) and math.isnan(value):
        return None
    return value


def table1_text(t: Table1, fmt: str, not_applicable: Sequence[str] = ()) -> str:
    """Render a :class:`Table1` as ``table`` (aligned text), ``csv`` or ``json``.

    Parameters
    ----------
    t : Table1
        The quantities.
    fmt : {"table", "csv", "json"}
        Output format.
    not_applicable : sequence of str
        Why the closed forms do not describe the drive (:func:`bldclab.model.analytic.applicability`): one line each
        under the table, a ``not_applicable`` list in JSON (CSV: not written, the file stays one table).

    Returns
    -------
    str
        The text, ending with a newline.

    """
    rows = t.rows()  # NaN marks a quantity that is undefined for this motor (e.g. (40) above its base speed)
    if fmt == "json":
        doc = {"motor": t.name,
               "quantities": [{"key": k, "description": d, "value": _json_value(v), "unit": u, "source": s}
                              for k, d, v, u, s in rows],
               "not_applicable": list(not_applicable)}
        return json.dumps(doc, indent=2, allow_nan=False) + "\n"
    if fmt == "csv":
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["key", "description", "value", "unit", "source"])
        for k, d, v, u, s in rows:
            w.writerow([k, d, repr(v) if not isinstance(v, bool) else str(v).lower(), u, s])
        return buf.getvalue()
    if fmt != "table":
        raise BldclabError("--format", f"unknown format {fmt!r}")
    head = ("key", "quantity", "value", "unit", "source")
    body = [(k, d, _fmt_value(v), u, s) for k, d, v, u, s in rows]
    widths = [max(len(r[j]) for r in [head, *body]) for j in range(len(head))]
    lines = [f"Paper 1 Table I and derived quantities: {t.name or '(unnamed drive)'}"]
    for r in [head, *body]:
        lines.append("  ".join(c.rjust(widths[j]) if j == 2 else c.ljust(widths[j])
                               for j, c in enumerate(r)).rstrip())
    if not_applicable:
        lines.append("The closed forms (sources (13) to (44)) are outside paper 1's premises for this drive:")
        lines += [f"  - {reason}" for reason in not_applicable]
    return "\n".join(lines) + "\n"

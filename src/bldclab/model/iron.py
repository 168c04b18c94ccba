"""Core material from a standard electrical-steel grade: the loss terms ``Motor.with_iron_from_material`` takes.

A non-oriented electrical steel grade (EN 10106, IEC 60404-8-4: ``M270-35A`` is at most 2.70 W/kg at 1.5 T,
50 Hz, 0.35 mm thick) is specified by its maximum specific total loss at a sinusoidal polarisation of 1.0 T and
1.5 T at 50 Hz, its nominal thickness and its conventional density. From these and the sheet's resistivity,
:meth:`SteelGrade.terms` separates the loss the usual way (docs/motor-files.md, "Iron losses from a steel grade"):

- classical eddy loss from the lamination's own physics, ``p_eddy = pi^2 d^2 B^2 f^2 / (6 rho_e delta)`` (W/kg; sheet
  thickness ``d``, resistivity ``rho_e``, density ``delta``), the thin-sheet formula of the plant's eddy term;
- the rest at 1.0 T and 1.5 T is booked as hysteresis ``p_hyst B^alpha`` with the exponent ``alpha`` that fits both
  points; the excess loss is folded into it (``p_ex = 0``), since two points at one frequency cannot separate a term
  in ``f`` from one in ``f^1.5``.

The result reproduces the grade's two 50 Hz values exactly. Away from 50 Hz, folding the excess loss into the
hysteresis term under-counts it above 50 Hz and over-counts it below: by ``x ((f/50)^0.5 - 1)`` of the folded part
if a share ``x`` of it is really excess loss (for ``x`` = 0.3, a common share in such steels: 12 % of the folded
part low at 100 Hz, 9 % high at 25 Hz).
"""

from __future__ import annotations

import dataclasses
import math

from ..errors import BldclabError
from ._checks import check_number

__all__ = ["GRADES", "M270_35A", "SteelGrade"]

F_TEST = 50.0
"""Test frequency of the grade's loss values (Hz)."""


@dataclasses.dataclass(frozen=True)
class SteelGrade:
    """A non-oriented electrical steel grade: its specified 50 Hz losses and the sheet's physical data.

    Parameters
    ----------
    name : str
        Grade designation, e.g. ``"M270-35A"``.
    P10, P15 : float
        Specific total loss at 50 Hz and a sinusoidal polarisation of 1.0 T and 1.5 T (W/kg), > 0; their ratio is
        checked by :meth:`terms` (the fitted hysteresis exponent must lie in [1, 3]).
    thickness : float
        Nominal sheet thickness (m), > 0.
    density : float
        Conventional density (kg/m^3), > 0.
    resistivity : float
        Electrical resistivity of the sheet (Ohm m), > 0. Not part of the grade's specification: the source of the
        value is in ``source``.
    source : str
        Where each number comes from.
    """

    name: str
    P10: float
    P15: float
    thickness: float
    density: float
    resistivity: float
    source: str = ""

    def __post_init__(self) -> None:
        for field in ("P10", "P15", "thickness", "density", "resistivity"):
            check_number(f"grade.{field}", getattr(self, field), lo=0.0, lo_open=True)

    def p_eddy(self, B: float = 1.0, f: float = F_TEST) -> float:
        """Classical eddy-current loss (W/kg) of the sheet at a sinusoidal flux density of peak ``B`` (T), ``f`` (Hz).

        ``pi^2 d^2 B^2 f^2 / (6 rho_e delta)``: the thin-sheet limit (sheet thinner than the skin depth, true for
        0.35 mm silicon steel up to a few hundred Hz).
        """
        d = self.thickness
        return math.pi**2 * d * d * B * B * f * f / (6.0 * self.resistivity * self.density)

    def terms(self) -> dict[str, float]:
        """Return ``p_hyst``, ``p_eddy``, ``p_ex`` (W/kg at 1 T, 50 Hz) and ``alpha`` for ``with_iron_from_material``.

        ``p_eddy`` is the classical term; ``p_hyst`` and ``alpha`` fit the rest at 1.0 T and 1.5 T; ``p_ex = 0``
        (folded into ``p_hyst``). Together they give ``P10`` at 1.0 T and ``P15`` at 1.5 T exactly.

        Raises
        ------
        BldclabError
            If the classical term alone exceeds a specified loss, or the fitted exponent is outside [1, 3] (the
            data are not those of a silicon steel sheet, or the resistivity is wrong).
        """
        pe = self.p_eddy()
        r10 = self.P10 - pe
        r15 = self.P15 - pe * 1.5**2
        if r10 <= 0.0 or r15 <= 0.0:
            raise BldclabError("grade.resistivity", f"the classical eddy loss ({pe:.3g} W/kg at 1 T, "
                               f"{pe * 2.25:.3g} W/kg at 1.5 T) exceeds the specified loss: the resistivity or the "
                               "thickness is wrong")
        alpha = math.log(r15 / r10) / math.log(1.5)
        check_number("grade.alpha", alpha, lo=1.0, hi=3.0)
        return {"p_hyst": r10, "p_eddy": pe, "p_ex": 0.0, "alpha": alpha}


M270_35A = SteelGrade(
    name="M270-35A",
    P10=1.10,
    P15=2.70,
    thickness=0.35e-3,
    density=7650.0,
    resistivity=0.52e-6,
    source="EN 10106 / IEC 60404-8-4 grade M270-35A: maximum specific total loss 1.10 W/kg at 1.0 T and 2.70 W/kg "
           "at 1.5 T, 50 Hz; nominal thickness 0.35 mm; conventional density 7.65 kg/dm^3. Resistivity 0.52 uOhm m: "
           "ASSUMED, typical of fully processed steels of this density (about 3 % Si + Al); the standard does not "
           "specify it. The classical term it sets is 0.12 W/kg of the 1.10 W/kg at 1 T, so +-20 % on it moves the "
           "hysteresis/eddy split by about 2 % of the total. The grade's values are maxima: typical sheets are some "
           "10 % lower; punching and stacking raise a core's loss, often by tens of percent.",
)
"""EN 10106 grade M270-35A (0.35 mm), the core of the catalog drive ``htm-48v-losses``."""

GRADES: dict[str, SteelGrade] = {M270_35A.name: M270_35A}
"""Built-in grades by designation."""

"""Catalogue ratings and bldclab's fields: KV, pole count, line-to-line resistance and inductance.

Hobby and catalogue data give a motor's speed constant ``KV`` (rpm/V), its pole count and the resistance and
inductance measured between two terminals; bldclab's fields are the back-EMF shape in V s/rad per phase, the pole
pairs ``p`` and the phase ``R`` and ``L``. The conversions (docs/motor-files.md, "Catalogue ratings"):

- ``poles = 2 p``; an odd pole count is no motor's.
- A star-connected winding measured between two terminals (the third open) shows two phases in series:
  ``R_ll = 2 R`` and ``L_ll = 2 L`` (``L`` the inclusive phase inductance ``L_self - M``: the line's flux linkage
  is ``(L_self - M) i`` in each of the two phases).
- ``KV`` (:data:`KV_CONVENTIONS`), the speed per volt of *peak line-to-line* back-EMF: ``KV = 1 / (2 k_phi)`` in
  rad/s per volt, since bldclab's ``k_phi`` is half the peak line-to-line shape (docs/conventions.md, "Per unit").
  It is also bldclab's no-load speed per volt of DC bus, ``Omega_0 / V_dc = 1 / (2 k_phi)``: six-step operation at
  no load, R neglected, reaches the speed at which the peak line-to-line back-EMF equals the bus. In rpm/V,
  ``k_phi = 60 / (2 pi KV) / 2 = 15 / (pi KV)``.
- ``KV_rms``: the speed per volt of *rms line-to-line* back-EMF (a voltmeter across two terminals of the motor
  spun by hand): ``KV_rms = 1 / rms(k_x - k_y)``, which depends on the shape: ``rms = peak / sqrt(2)`` for a
  sinusoid, ``peak / 1.342`` for the ideal 120-degree trapezoid (:func:`line_crest_factor`).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import BldclabError
from .emf import TWO_PI, BackEmf, Shape

__all__ = ["KV_CONVENTIONS", "POLE_FREQUENCY_MAX", "RPM_PER_V", "emf_for_kv", "kv", "line_crest_factor",
           "line_rms", "pole_count_hint", "pole_pairs"]

#: rpm/V in rad/s per volt (the SI unit of a speed constant).
RPM_PER_V = 2.0 * math.pi / 60.0

#: The motor-file keys of a speed constant and the line-to-line back-EMF each one is per volt of.
KV_CONVENTIONS: dict[str, str] = {"KV": "peak", "KV_rms": "rms"}

#: Electrical frequency (Hz) at the no-load speed above which a pole-pair count looks like a pole count
#: (:func:`pole_count_hint`): 8 kHz, 480,000 electrical rpm. PM motors are built for a few kHz at most (the iron loss
#: grows with the square of the frequency); a 1950 KV drone motor with 7 pole pairs on 24 V, among the fastest, is at
#: 5.5 kHz.
POLE_FREQUENCY_MAX = 8000.0


def pole_pairs(p: object = None, poles: object = None) -> int:
    """Return the pole pairs from ``p`` or from ``poles`` (exactly one of them given).

    Parameters
    ----------
    p : int, optional
        Pole pairs, >= 1.
    poles : int, optional
        Pole count: even, >= 2.

    Returns
    -------
    int

    Raises
    ------
    BldclabError
        ``poles``: odd, or given with ``p``; ``p``: missing.
    """
    if poles is None:
        if p is None:
            raise BldclabError("p", "is missing (pole pairs; or give the pole count as poles)")
        return p  # type: ignore[return-value]  # Motor checks it
    if p is not None:
        raise BldclabError("poles", f"cannot be given with p: give the pole pairs p or the pole count poles (= 2 p), "
                           f"not both (got p = {p!r}, poles = {poles!r})")
    if isinstance(poles, bool) or not isinstance(poles, int | np.integer) or poles < 2:
        raise BldclabError("poles", f"must be an even integer >= 2, got {poles!r}")
    if poles % 2:
        raise BldclabError("poles", f"must be even (two poles per pole pair), got {poles}: for {poles} pole pairs "
                           f"write p = {poles}")
    return int(poles) // 2


def line_rms(emf: BackEmf) -> float:
    """Return the rms of the line-to-line shapes ``k_x - k_y`` (V s/rad), over an electrical period and the pairs.

    Parameters
    ----------
    emf : BackEmf

    Returns
    -------
    float
        ``sqrt(mean over the three pairs of mean (k_x - k_y)^2)`` (:meth:`BackEmf.line_rms`, cached).
    """
    return emf.line_rms()


def line_crest_factor(emf: BackEmf) -> float:
    """Return peak over rms of the line-to-line back-EMF: sqrt(2) for a sinusoid, 1.342 for the ideal trapezoid."""
    return emf.line_peak() / line_rms(emf)


def kv(emf: BackEmf, convention: str = "peak") -> float:
    """Return the speed constant of a back-EMF in rad/s per volt (times 60 / (2 pi) for rpm/V).

    Parameters
    ----------
    emf : BackEmf
    convention : {"peak", "rms"}
        Per volt of peak line-to-line back-EMF (``KV``, bldclab's ``1 / (2 k_phi)``, its no-load speed per volt of
        DC bus) or of rms line-to-line back-EMF (``KV_rms``).

    Returns
    -------
    float
    """
    if convention == "peak":
        return 1.0 / emf.line_peak()
    if convention == "rms":
        return 1.0 / line_rms(emf)
    raise BldclabError("convention", f"must be 'peak' or 'rms', got {convention!r}")


def emf_for_kv(shape: Shape, speed_constant: float, convention: str = "peak") -> BackEmf:
    """Return the symmetric back-EMF of ``shape``'s form whose speed constant is ``speed_constant``.

    Parameters
    ----------
    shape : Shape
        The form (any size), e.g. ``Sinusoid(1.0)`` or ``Trapezoid(1.0, flat_top)``.
    speed_constant : float
        rad/s per volt (rpm/V times :data:`RPM_PER_V`), > 0.
    convention : {"peak", "rms"}
        What volt it is per (:func:`kv`).

    Returns
    -------
    BackEmf
        ``BackEmf.symmetric(shape)`` scaled: ``kv(result, convention) == speed_constant``.
    """
    if not (math.isfinite(speed_constant) and speed_constant > 0):
        raise BldclabError("KV", f"must be > 0, got {speed_constant!r} rad/s per V")
    unit = BackEmf.symmetric(shape)
    return BackEmf.symmetric(shape.scaled(kv(unit, convention) / speed_constant))


def pole_count_hint(p: int, omega_0: float) -> str | None:
    """Say when a pole-pair count looks like a pole count, naming both readings; None when it does not.

    ``p`` is suspect when it is even, its electrical frequency at the no-load speed is above
    :data:`POLE_FREQUENCY_MAX` and half of it is not.

    Parameters
    ----------
    p : int
        Pole pairs as given.
    omega_0 : float
        The no-load speed (rad/s), ``V_dc / (2 k_phi)``.

    Returns
    -------
    str or None
    """
    f_e = p * omega_0 / TWO_PI
    if p < 4 or p % 2 or f_e <= POLE_FREQUENCY_MAX or f_e / 2 > POLE_FREQUENCY_MAX:
        return None
    rpm = omega_0 * 60.0 / TWO_PI
    return (f"p = {p} pole pairs ({2 * p} poles) gives {f_e / 1e3:.3g} kHz electrical at the no-load speed "
            f"{rpm:.0f} rpm, above the {POLE_FREQUENCY_MAX / 1e3:g} kHz PM motors are built for; if {p} is the pole "
            f"count ({p // 2} pole pairs, {f_e / 2e3:.3g} kHz), write poles = {p}")

"""Drive parameters: the motor, the inverter, the mechanics and the sensors, and the drive that bundles them.

Every class is a frozen dataclass in SI units that validates itself on construction and raises
:class:`~bldclab.errors.BldclabError` naming the offending field. A :class:`Drive` bundles them and
reads and writes TOML motor files (format in ``docs/motor-files.md``; the table machinery is in
:mod:`bldclab.model.motorfile`). The motor's back-EMF shapes and cogging are in :mod:`bldclab.model.emf`.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from .._files import read_toml
from ..errors import BldclabError, PlausibilityWarning
from ._checks import check_number
from .emf import PHASES, BackEmf, Cogging, Shape, Sinusoid, Trapezoid
from .iron import GRADES, SteelGrade
from .motorfile import (
    Section,
    cogging_table,
    emf_tables,
    read_cogging,
    read_emf,
    read_form,
    toml_table,
    toml_value,
    wrap,
)
from .ratings import KV_CONVENTIONS, RPM_PER_V, emf_for_kv, kv, pole_count_hint, pole_pairs
from .thermal import Thermal, read_thermal, thermal_tables
from .units import to_si

__all__ = [
    "Drive",
    "Inverter",
    "Mechanics",
    "Motor",
    "Sensors",
    "switching_energies",
]


@dataclass(frozen=True)
class Motor:
    """The PM brushless motor (star connected, no neutral).

    Parameters
    ----------
    p : int
        Pole pairs.
    R : float
        Phase resistance (Ohm), >= 0 (0 gives paper 1's idealisation).
    L : float
        Inclusive phase inductance ``L_self - M`` (H), > 0.
    emf : BackEmf
        Back-EMF shapes.
    V_N : float
        Nominal voltage (V), > 0.
    I_N : float
        Nominal current (A): the square-wave current amplitude of the rating, > 0.
    Omega_N : float, optional
        Conventional nominal speed (rad/s); default paper 1 (2): ``(V_N - 2 R I_N) / (2 k_phi)``.
    T_peak : float, optional
        Peak torque (N m), informative.
    cogging : Cogging, optional
        Cogging torque.
    P_fe_eddy, P_fe_hyst, P_fe_ex : float
        Stator iron loss caused by the magnets (W), >= 0, default 0 (none): its eddy-current, hysteresis and
        excess parts at the speed ``speed_fe_ref`` (a measured no-load loss split by its speed dependence, or a
        core-loss calculation). The plant evaluates them in the time domain from the back-EMF,
        ``p_fe = k_fe_e sum e_x^2 + k_fe_h |omega_e| + k_fe_x sum |e_x|^1.5``, with the coefficients
        (:attr:`k_fe_eddy`, :attr:`k_fe_hyst`, :attr:`k_fe_ex`) that reproduce these powers at ``speed_fe_ref``
        with this motor's back-EMF shape; the loss acts as a drag torque on the rotor (docs/plant.md, "Iron
        losses").
    speed_fe_ref : float, optional
        Mechanical speed (rad/s) at which ``P_fe_eddy``, ``P_fe_hyst``, ``P_fe_ex`` hold; > 0, required when any
        of them is > 0.

    """

    p: int
    R: float
    L: float
    emf: BackEmf
    V_N: float
    I_N: float
    Omega_N: float | None = None
    T_peak: float | None = None
    cogging: Cogging | None = None
    P_fe_eddy: float = 0.0
    P_fe_hyst: float = 0.0
    P_fe_ex: float = 0.0
    speed_fe_ref: float | None = None

    #: The iron-loss fields, all 0 / None by default (a file without them has no iron loss).
    IRON_LOSS_FIELDS: ClassVar[tuple[str, ...]] = ("P_fe_eddy", "P_fe_hyst", "P_fe_ex", "speed_fe_ref")

    def __post_init__(self) -> None:
        if isinstance(self.p, bool) or not isinstance(self.p, int | np.integer) or self.p < 1:
            raise BldclabError("p", f"pole pairs must be an integer >= 1, got {self.p!r}")
        check_number("R", self.R, lo=0.0)
        check_number("L", self.L, lo=0.0, lo_open=True)
        check_number("V_N", self.V_N, lo=0.0, lo_open=True)
        check_number("I_N", self.I_N, lo=0.0, lo_open=True)
        check_number("Omega_N", self.Omega_N, lo=0.0, lo_open=True, allow_none=True)
        check_number("T_peak", self.T_peak, lo=0.0, lo_open=True, allow_none=True)
        if not isinstance(self.emf, BackEmf):
            raise BldclabError("emf", "must be a BackEmf")
        k = self.emf.k_abc(np.linspace(0.0, 2.0 * math.pi, 1441))
        if not float(np.max(np.abs(k - k.mean(axis=0)))) > 1e-9 * float(np.max(np.abs(k))):
            # only a part common to the three phases (a constant, triplen harmonics): no line-to-line back-EMF, no
            # torque from any current (sum i_x = 0), and no speed base V_dc / (2 k_phi)
            raise BldclabError("emf", "the line-to-line back-EMF k_x - k_y is zero at every angle (k_phi = 0): the "
                               "shapes hold only a part common to the three phases (a constant, triplen harmonics), "
                               "which a star motor without neutral cannot turn into torque; give the phase back-EMF "
                               "with its fundamental")
        if self.Omega_N is None and self.V_N - 2.0 * self.R * self.I_N <= 0.0:
            raise BldclabError("R", "2 R I_N exceeds V_N: no positive nominal speed")
        for name in ("P_fe_eddy", "P_fe_hyst", "P_fe_ex"):
            check_number(name, getattr(self, name), lo=0.0)
        check_number("speed_fe_ref", self.speed_fe_ref, lo=0.0, lo_open=True, allow_none=True)
        if self.has_iron_losses and self.speed_fe_ref is None:
            raise BldclabError("speed_fe_ref", "is missing: P_fe_eddy, P_fe_hyst and P_fe_ex are losses at a "
                               "reference speed, give it (e.g. speed_fe_ref = \"3000 rpm\")")

    @classmethod
    def from_ratings(cls, *, V_N: float | str, I_N: float | str, p: int | None = None, poles: int | None = None,
                     R: float | str | None = None, R_ll: float | str | None = None, L: float | str | None = None,
                     L_ll: float | str | None = None, emf: BackEmf | None = None, KV: float | str | None = None,
                     KV_rms: float | str | None = None, shape: str | Shape = "sinusoid", **fields: Any) -> Motor:
        """Build a motor from catalogue ratings: pole count, line-to-line R and L, speed constant KV.

        The conversions (:mod:`bldclab.model.ratings`, docs/motor-files.md "Catalogue ratings"): ``p = poles / 2``,
        ``R = R_ll / 2``, ``L = L_ll / 2`` (star connection, two phases between two terminals), and the back-EMF
        of ``shape``'s form whose speed per volt of peak line-to-line back-EMF is ``KV`` (``k_phi = 15 / (pi KV)``
        with KV in rpm/V: bldclab's no-load speed per volt of DC bus) or of rms line-to-line back-EMF is ``KV_rms``.
        A motor file's ``poles``, ``R_ll``, ``L_ll``, ``KV`` and ``KV_rms`` are read through this.

        Parameters
        ----------
        V_N, I_N : float or str
            Nominal voltage (V) and current (A), numbers or unit strings.
        p, poles : int, optional
            Pole pairs, or the pole count (even): one of them.
        R, R_ll : float or str, optional
            Phase or line-to-line resistance (Ohm, or ``"0.08 Ohm"``): one of them.
        L, L_ll : float or str, optional
            Phase (inclusive, ``L_self - M``) or line-to-line inductance (H, or ``"15 uH"``): one of them.
        emf : BackEmf, optional
            The back-EMF in V s/rad; or instead:
        KV, KV_rms : float or str, optional
            Speed constant: a number in rpm/V (a KV rating's unit) or a string with a unit (``"1950 rpm/V"``,
            ``"204 rad/s/V"``); per volt of peak (``KV``) or rms (``KV_rms``) line-to-line back-EMF.
        shape : {"sinusoid", "trapezoid"} or Shape
            The back-EMF's form with a speed constant: a sinusoid, the ideal 120-degree trapezoid, or any shape
            (its size is replaced).
        **fields
            The other fields of :class:`Motor` (``Omega_N``, ``T_peak``, ``cogging``, iron losses), SI numbers.

        Returns
        -------
        Motor

        Raises
        ------
        BldclabError
            Naming the argument: both forms of one quantity given, neither, an odd pole count, a bad value.
        """
        pairs = pole_pairs(p, poles)
        r = _phase_value("R", R, R_ll, "resistance")
        ind = _phase_value("L", L, L_ll, "inductance")
        given = [(k, v) for k, v in (("KV", KV), ("KV_rms", KV_rms)) if v is not None]
        if len(given) > 1:
            raise BldclabError("KV_rms", "cannot be given with KV: one speed constant, per volt of peak (KV) or of "
                               "rms (KV_rms) line-to-line back-EMF")
        if given:
            key, value = given[0]
            if emf is not None:
                raise BldclabError(key, "cannot be given with emf: the back-EMF's size is given once")
            speed = value * RPM_PER_V if isinstance(value, int | float) and not isinstance(value, bool) else \
                to_si(value, "speed_constant", key)
            check_number(key, speed, lo=0.0, lo_open=True)
            forms = {"sinusoid": Sinusoid(1.0), "trapezoid": Trapezoid(1.0)}
            if not isinstance(shape, Shape) and shape not in forms:
                raise BldclabError("shape", f"must be 'sinusoid', 'trapezoid' or a Shape, got {shape!r}")
            form = shape if isinstance(shape, Shape) else forms[shape]
            emf = emf_for_kv(form, speed, KV_CONVENTIONS[key])
        elif emf is None:
            raise BldclabError("emf", "is missing: give the back-EMF, or a speed constant KV (or KV_rms) and its "
                               "shape")
        return cls(p=pairs, R=r, L=ind, emf=emf, V_N=to_si(V_N, "voltage", "V_N"), I_N=to_si(I_N, "current", "I_N"),
                   **fields)

    @property
    def poles(self) -> int:
        """Pole count ``2 p``."""
        return 2 * int(self.p)

    @property
    def R_ll(self) -> float:
        """Line-to-line resistance ``2 R`` (Ohm): two phases in series between two terminals."""
        return 2.0 * self.R

    @property
    def L_ll(self) -> float:
        """Line-to-line inductance ``2 L`` (H): two phases in series between two terminals, the third open."""
        return 2.0 * self.L

    @property
    def KV(self) -> float:
        """Speed constant (rpm/V) per volt of peak line-to-line back-EMF: ``60 / (2 pi) / (2 k_phi)``.

        bldclab's no-load speed per volt of DC bus, ``Omega_0 / V_dc`` in rpm/V.
        """
        return kv(self.emf, "peak") / RPM_PER_V

    @property
    def KV_rms(self) -> float:
        """Speed constant (rpm/V) per volt of rms line-to-line back-EMF (depends on the shape)."""
        return kv(self.emf, "rms") / RPM_PER_V

    @property
    def has_iron_losses(self) -> bool:
        """True if any of ``P_fe_eddy``, ``P_fe_hyst``, ``P_fe_ex`` is positive."""
        return self.P_fe_eddy > 0.0 or self.P_fe_hyst > 0.0 or self.P_fe_ex > 0.0

    @property
    def k_fe_eddy(self) -> float:
        """Eddy coefficient ``k_fe_e = P_fe_eddy / (speed_fe_ref^2 sum_x mean k_x^2)`` (W/V^2), 0 without it.

        The plant's eddy loss ``k_fe_e sum_x e_x^2`` then equals ``P_fe_eddy`` at ``speed_fe_ref``.
        """
        if self.P_fe_eddy == 0.0 or self.speed_fe_ref is None:
            return 0.0
        return float(self.P_fe_eddy / (self.speed_fe_ref**2 * self.emf.mean_abs_power(2.0)))

    @property
    def k_fe_hyst(self) -> float:
        """Hysteresis coefficient ``k_fe_h = P_fe_hyst / (p speed_fe_ref)`` (J/rad), 0 without it.

        Per electrical radian: the plant's hysteresis loss is ``k_fe_h |omega_e|``.
        """
        if self.P_fe_hyst == 0.0 or self.speed_fe_ref is None:
            return 0.0
        return float(self.P_fe_hyst / (self.p * self.speed_fe_ref))

    @property
    def k_fe_ex(self) -> float:
        """Excess coefficient ``k_fe_x = P_fe_ex / (speed_fe_ref^1.5 sum_x mean |k_x|^1.5)`` (W/V^1.5), 0 without it.

        The plant's excess loss is ``k_fe_x sum_x |e_x|^1.5``.
        """
        if self.P_fe_ex == 0.0 or self.speed_fe_ref is None:
            return 0.0
        return float(self.P_fe_ex / (self.speed_fe_ref**1.5 * self.emf.mean_abs_power(1.5)))

    def with_iron_from_material(self, *, mass: float, B_peak: float, p_hyst: float, p_eddy: float,
                                p_ex: float = 0.0, alpha: float = 2.0, speed_ref: float | None = None) -> Motor:
        """Return the motor with ``P_fe_eddy``, ``P_fe_hyst``, ``P_fe_ex`` at ``speed_ref`` from core-material data.

        The material's loss at 50 Hz and 1 T (sinusoidal flux) split by term, ``p_hyst``, ``p_eddy``, ``p_ex``
        (W/kg), with the Steinmetz exponent ``alpha`` of the hysteresis term, the core mass and its peak flux
        density. The assumed flux: each third of the core carries a flux density that follows its phase's magnet
        flux linkage, ``B_x = B_peak psi_x / psi_pk``, so ``dB_x/dt = (B_peak / psi_pk) e_x`` with ``psi_pk`` the
        peak magnet flux linkage of a phase (:meth:`BackEmf`'s shapes, ``Shape.flux_peak / p``, averaged over the
        phases). Then, matching each term of the material's sinusoidal loss
        ``p_hyst (f/50) B^alpha + p_eddy (f/50)^2 B^2 + p_ex (f/50)^1.5 B^1.5`` in the time domain:

        - eddy ``mass p_eddy / (2 pi^2 50^2) mean (dB/dt)^2``: ``k_fe_e = mass p_eddy B_peak^2 / (6 pi^2 50^2
          psi_pk^2)``;
        - hysteresis ``mass p_hyst B_peak^alpha / 50`` per electrical cycle: ``k_fe_h = mass p_hyst B_peak^alpha /
          (100 pi)``;
        - excess ``mass p_ex / ((2 pi 50)^1.5 m_15) mean |dB/dt|^1.5``, ``m_15 = mean |cos|^1.5``:
          ``k_fe_x = mass p_ex B_peak^1.5 / (3 (2 pi 50)^1.5 m_15 psi_pk^1.5)``;

        and the returned powers are these coefficients' losses at ``speed_ref``. A sinusoidal back-EMF gets the
        material's formula at every speed; a trapezoidal one more eddy and excess loss (its harmonics). Limits
        (docs/motor-files.md, "Iron losses from material data"): one effective peak flux density for teeth and
        yoke, tooth flux taken as the phase's flux linkage (sharper in reality for a distributed winding), no
        rotational loss.

        Parameters
        ----------
        mass : float
            Core (stator iron) mass (kg), > 0.
        B_peak : float
            Peak flux density in the core at no load (T), > 0.
        p_hyst, p_eddy, p_ex : float
            Material loss at 1 T, 50 Hz by term (W/kg), >= 0.
        alpha : float
            Steinmetz exponent of the hysteresis term, in [1, 3]; default 2.
        speed_ref : float, optional
            Reference speed of the returned powers (rad/s), > 0; default the rated speed ``Omega_nominal``.

        Returns
        -------
        Motor
            The motor with ``P_fe_eddy``, ``P_fe_hyst``, ``P_fe_ex``, ``speed_fe_ref`` set.

        Raises
        ------
        BldclabError
            Naming the material argument that is out of range.
        """
        check_number("material.mass", mass, lo=0.0, lo_open=True)
        check_number("material.B_peak", B_peak, lo=0.0, lo_open=True)
        for name, v in (("material.p_hyst", p_hyst), ("material.p_eddy", p_eddy), ("material.p_ex", p_ex)):
            check_number(name, v, lo=0.0)
        check_number("material.alpha", alpha, lo=1.0, hi=3.0)
        check_number("material.speed_ref", speed_ref, lo=0.0, lo_open=True, allow_none=True)
        w = float(speed_ref) if speed_ref is not None else self.Omega_nominal
        psi = float(np.mean([sh.flux_peak() for sh in self.emf.shapes])) / self.p
        m15 = math.gamma(1.25) / (math.sqrt(math.pi) * math.gamma(1.75))
        k_e = mass * p_eddy * B_peak**2 / (6.0 * math.pi**2 * 50.0**2 * psi**2)
        k_h = mass * p_hyst * B_peak**alpha / (100.0 * math.pi)
        k_x = mass * p_ex * B_peak**1.5 / (3.0 * (2.0 * math.pi * 50.0) ** 1.5 * m15 * psi**1.5)
        return dataclasses.replace(self, P_fe_eddy=k_e * w**2 * self.emf.mean_abs_power(2.0),
                                   P_fe_hyst=k_h * self.p * w, P_fe_ex=k_x * w**1.5 * self.emf.mean_abs_power(1.5),
                                   speed_fe_ref=w)

    def with_iron_from_grade(self, grade: SteelGrade, *, mass: float, B_peak: float,
                             speed_ref: float | None = None) -> Motor:
        """Return the motor with its iron-loss fields from a standard steel grade (:class:`~.iron.SteelGrade`).

        :meth:`with_iron_from_material` with the grade's separated terms (:meth:`SteelGrade.terms`: classical eddy
        from the sheet's thickness, resistivity and density; hysteresis, with the excess folded in, fitted to the
        grade's 1.0 T and 1.5 T losses at 50 Hz).

        Parameters
        ----------
        grade : SteelGrade
            The core's steel, e.g. ``bldclab.model.iron.M270_35A``.
        mass : float
            Core (stator iron) mass (kg), > 0.
        B_peak : float
            Peak flux density in the core at no load (T), > 0.
        speed_ref : float, optional
            Reference speed of the returned powers (rad/s), > 0; default the rated speed ``Omega_nominal``.

        Returns
        -------
        Motor
        """
        return self.with_iron_from_material(mass=mass, B_peak=B_peak, speed_ref=speed_ref, **grade.terms())

    def iron_loss(self, omega: float) -> float:
        """Return the mean iron loss (W) the plant books at a constant mechanical speed ``omega`` (rad/s), any load.

        ``P_fe_eddy (w/w_ref)^2 + P_fe_hyst |w/w_ref| + P_fe_ex |w/w_ref|^1.5`` with ``w_ref = speed_fe_ref``: the
        model's loss depends on the magnets' flux only, not on the current (docs/plant.md, "Iron losses").
        """
        if not self.has_iron_losses or self.speed_fe_ref is None:
            return 0.0
        r = abs(float(omega)) / self.speed_fe_ref
        return self.P_fe_eddy * r**2 + self.P_fe_hyst * r + self.P_fe_ex * r**1.5

    @property
    def k_phi(self) -> float:
        """Motor constant (V s/rad): half the peak line-to-line shape; the flat top of an ideal trapezoid."""
        return 0.5 * self.emf.line_peak()

    @property
    def T_N(self) -> float:
        """Nominal torque ``2 k_phi I_N`` (N m), paper 1 (6): the torque base."""
        return 2.0 * self.k_phi * self.I_N

    @property
    def Omega_nominal(self) -> float:
        """``Omega_N`` if given, else paper 1 (2) (rad/s)."""
        if self.Omega_N is not None:
            return float(self.Omega_N)
        return (self.V_N - 2.0 * self.R * self.I_N) / (2.0 * self.k_phi)


def _phase_value(name: str, phase: object, line: object, dimension: str) -> float:
    """Return a phase quantity given per phase (``R``) or line to line (``R_ll``, halved): exactly one of them."""
    ll = f"{name}_ll"
    if phase is not None and line is not None:
        raise BldclabError(ll, f"cannot be given with {name}: give the phase value {name} or the line-to-line value "
                           f"{ll} (= 2 {name}), not both")
    if line is not None:
        value = to_si(line, dimension, ll)
        check_number(ll, value, lo=0.0, lo_open=name == "L")  # the rules of R (>= 0) and L (> 0), named as given
        return value / 2.0
    if phase is None:
        raise BldclabError(name, f"is missing (per phase; or give the line-to-line value as {ll})")
    if isinstance(phase, str) and "line" in phase.lower():
        typed = phase[:phase.lower().index("line")].strip().rstrip("(,;").strip()
        raise BldclabError(name, f"is the phase value; a line-to-line one goes in {ll}: {ll} = \"{typed}\"")
    return to_si(phase, dimension, name)


@dataclass(frozen=True)
class Inverter:
    """Two-level three-phase voltage source inverter.

    Parameters
    ----------
    V_dc : float
        DC source voltage (V), > 0.
    f_pwm : float
        PWM carrier frequency (Hz), > 0. Controllers are sampled at ``2 f_pwm``.
    t_dead : float
        Dead time (s), >= 0, below a quarter period.
    R_on : float
        Switch on-resistance (Ohm), >= 0.
    V_f : float
        Diode forward voltage (V), >= 0.
    r_d : float
        Diode slope resistance (Ohm), >= 0.
    R_src : float
        DC source internal resistance (Ohm), >= 0.
    i_trip : float
        Hardware over-current protection (A): a phase current reaching it switches every gate off, latched, as the
        comparators of a gate driver do, whatever the firmware does. 0 (default): none.
    model : str
        ``"switching"`` (default): every gate edge, dead time and diode transition inside the PWM period.
        ``"average"``: a leg that switches inside a half PWM period applies its half-period average (the
        averaged inverter of motulator and gym-electric-motor, paper 1's ideal current limiter); diodes, the open
        phase and the trip stay, dead time inside PWM is neglected. Faster, no PWM ripple (docs/plant.md).
    E_on, E_off, E_rr : float
        Switching losses (J), >= 0, default 0 (none): a switch's turn-on and turn-off energy and the diode's
        reverse-recovery energy measured at ``V_test`` and ``I_test`` (datasheet values). The plant books them at
        each hard gate edge scaled as ``E (|i| / I_test) (v_bus / V_test)``: ``E_off`` when a switch turns off
        under current, ``E_on + E_rr`` when a switch turns on while the opposite diode carries the current; soft
        edges (the switch's own diode conducts) and zero-current edges book nothing. The energy comes from the DC
        source (docs/plant.md, "Switching losses").
    V_test, I_test : float
        Test voltage (V) and current (A) of ``E_on``, ``E_off``, ``E_rr``; > 0 when any of them is > 0.

    """

    V_dc: float
    f_pwm: float
    t_dead: float = 0.0
    R_on: float = 0.0
    V_f: float = 0.0
    r_d: float = 0.0
    R_src: float = 0.0
    i_trip: float = 0.0
    model: str = "switching"
    E_on: float = 0.0
    E_off: float = 0.0
    E_rr: float = 0.0
    V_test: float = 0.0
    I_test: float = 0.0

    MODELS: ClassVar[tuple[str, ...]] = ("switching", "average")
    #: The switching-loss fields, all 0 by default (a file without them has no switching losses).
    SWITCHING_LOSS_FIELDS: ClassVar[tuple[str, ...]] = ("E_on", "E_off", "E_rr", "V_test", "I_test")

    def __post_init__(self) -> None:
        check_number("V_dc", self.V_dc, lo=0.0, lo_open=True)
        check_number("f_pwm", self.f_pwm, lo=0.0, lo_open=True, hi=1e7)
        check_number("t_dead", self.t_dead, lo=0.0)
        if self.t_dead >= 0.25 / self.f_pwm:
            raise BldclabError("t_dead", f"must be below a quarter PWM period ({0.25 / self.f_pwm:g} s at "
                               f"f_pwm = {self.f_pwm:g} Hz), got {self.t_dead:g} s")
        for name in ("R_on", "V_f", "r_d", "R_src", "i_trip"):
            check_number(name, getattr(self, name), lo=0.0)
        if self.model not in self.MODELS:
            raise BldclabError("model", f"must be one of {', '.join(self.MODELS)}, got {self.model!r}")
        for name in self.SWITCHING_LOSS_FIELDS:
            check_number(name, getattr(self, name), lo=0.0)
        if self.has_switching_losses:
            for name in ("V_test", "I_test"):
                if not getattr(self, name) > 0.0:
                    raise BldclabError(name, "must be > 0 when E_on, E_off or E_rr is > 0 (the datasheet's test "
                                       f"{'voltage' if name == 'V_test' else 'current'} the energies scale from), "
                                       f"got {getattr(self, name):g}")

    @property
    def has_switching_losses(self) -> bool:
        """True if any of ``E_on``, ``E_off``, ``E_rr`` is positive."""
        return self.E_on > 0.0 or self.E_off > 0.0 or self.E_rr > 0.0


#: Motor-file keys of the "from rise/fall times" input of the switching energies (:func:`switching_energies`).
TRANSITION_FIELDS: tuple[str, ...] = ("t_rise", "t_fall", "Q_rr")


def switching_energies(V_test: float, I_test: float, t_rise: float, t_fall: float,
                       Q_rr: float = 0.0) -> tuple[float, float, float]:
    """Estimate ``(E_on, E_off, E_rr)`` from a switch's rise and fall times and its diode's recovery charge.

    The linear-transition estimate of hard switching on an inductive, clamped load (the drive's phase current does
    not change during the edge): at turn-on the current rises in ``t_rise`` while the voltage stays at ``V_test``,
    at turn-off the voltage rises and the current falls in ``t_fall``; a linear ramp of one against the other
    dissipates half the rectangle,

        E_on = V_test I_test t_rise / 2,   E_off = V_test I_test t_fall / 2,   E_rr = Q_rr V_test

    (``E_rr``: the recovery charge swept out at the bus voltage, which the turning-on switch mostly dissipates; the
    usual rough estimate, an upper one for the diode's own share of about ``Q_rr V_test / 4``). Limits: datasheet
    times are measured in a resistive or gate-charge test circuit, not the drive's inductive switching, and with a
    given gate resistance; the Miller plateau (voltage and current transitions in sequence, not together), the
    parasitic inductances and the output-capacitance charge are ignored. Good for an order of magnitude; datasheet
    energies, where given, are better.

    Parameters
    ----------
    V_test : float
        Voltage at the edge (V), > 0.
    I_test : float
        Switched current (A), > 0.
    t_rise, t_fall : float
        Current rise time at turn-on and fall time at turn-off (s), >= 0.
    Q_rr : float
        Diode reverse-recovery charge (C), >= 0.

    Returns
    -------
    tuple of float
        ``(E_on, E_off, E_rr)`` (J), the energies at ``V_test``, ``I_test`` (:class:`Inverter`'s fields).
    """
    check_number("V_test", V_test, lo=0.0, lo_open=True)
    check_number("I_test", I_test, lo=0.0, lo_open=True)
    for name, value in (("t_rise", t_rise), ("t_fall", t_fall), ("Q_rr", Q_rr)):
        check_number(name, value, lo=0.0)
    return 0.5 * V_test * I_test * t_rise, 0.5 * V_test * I_test * t_fall, Q_rr * V_test


@dataclass(frozen=True)
class Mechanics:
    """Rotor mechanics ``J dw/dt = tau_e - tau_L - k_q w |w| - B w - tau_c sign(w)``.

    Parameters
    ----------
    J : float
        Inertia of rotor and load (kg m^2), > 0 (with a propeller: the propeller's too).
    B : float
        Viscous friction (N m s/rad), >= 0.
    tau_c : float
        Coulomb friction (N m), >= 0 (a propeller's constant torque ``tau_0``, if any, goes here).
    k_q : float
        Propeller or fan load ``tau = k_q w^2`` against the motion (N m s^2/rad^2), >= 0; 0 for none. It acts with
        rotor dynamics (at an imposed speed the dynamometer is the load) and is booked as the load's energy, so its
        power counts as output: ``k_q = C_P rho D^5 / (2 pi)^3`` from a propeller's power coefficient.

    """

    J: float = 1e-3
    B: float = 0.0
    tau_c: float = 0.0
    k_q: float = 0.0

    def __post_init__(self) -> None:
        check_number("J", self.J, lo=0.0, lo_open=True)
        check_number("B", self.B, lo=0.0)
        check_number("tau_c", self.tau_c, lo=0.0)
        check_number("k_q", self.k_q, lo=0.0)


def _per_sensor(name: str, v: object, hi: float | None) -> tuple[float, float, float]:
    """Check a per-Hall-sensor quantity >= 0 (and < ``hi``): a number for all three, or three numbers (a, b, c)."""
    if isinstance(v, str | bytes) or not isinstance(v, Sequence | np.ndarray | int | float | np.floating | np.integer):
        raise BldclabError(name, f"expected a number or three numbers (a, b, c), got {type(v).__name__}")
    if isinstance(v, Sequence | np.ndarray):
        if len(v) != 3:
            raise BldclabError(name, f"needs one number or three entries (a, b, c), got {len(v)}")
        vals = list(v)
        names = [f"{name}[{j}]" for j in range(3)]
    else:
        vals = [v] * 3
        names = [name] * 3
    for nm, x in zip(names, vals, strict=True):
        check_number(nm, x, lo=0.0)
        if hi is not None and not float(x) < hi:
            raise BldclabError(nm, f"must be < {math.degrees(hi):.4g} deg electrical ({hi:.6g} rad), got "
                               f"{math.degrees(float(x)):.4g} deg")
    a, b, c = (float(x) for x in vals)
    return (a, b, c)


@dataclass(frozen=True)
class Sensors:
    """Measurement chain seen by the controller.

    Parameters
    ----------
    current_phases : str
        Which phase currents are measured, e.g. ``"ab"`` (default), ``"ac"``, ``"abc"``.
    current_gain, current_offset : tuple of float
        Per-phase gain (-) and offset (A).
    current_noise : float
        Standard deviation of white measurement noise (A).
    current_lsb : float
        Quantisation step (A), 0 for none.
    current_full_scale : float
        Full scale of the current measurement (A), > 0: a reading (after gain, offset, noise and quantisation) clips
        to ``[-current_full_scale, current_full_scale]``, as a shunt amplifier and its ADC saturate; ``inf`` (the
        default) for none.
    vdc_gain, vdc_offset, vdc_noise, vdc_lsb : float
        Same for the DC-bus voltage (-, V, V, V).
    hall_error : tuple of float
        Placement error of each Hall sensor (rad, electrical), within +-pi/6 (30 degrees): both its edges move by
        this angle.
    hall_hysteresis : float or tuple of float
        Magnetic hysteresis of each Hall sensor (rad, electrical), in [0, pi/3): its edges come half of it late in
        the direction of travel (forward: at the placed edge + h/2, backward: - h/2). A number is used for all
        three sensors.
    hall_delay : float or tuple of float
        Propagation delay of each sensor's edges (s), >= 0; a number is used for all three.
    hall_tau : float or tuple of float
        Time constant (s), >= 0, of a first-order RC filter on each Hall line read by the MCU at half the swing:
        an edge is seen ``tau ln 2`` late, a pulse shorter than that never; 0 for none. A number is used for all
        three. The model of all four is in docs/hall.md.
    f_tick : float
        Capture-timer frequency (Hz) used to time-stamp Hall edges (and back-EMF comparator edges).
    seed : int
        Seed of the noise generator (runs are deterministic).
    bemf : bool
        The drive has back-EMF sensing (terminal-voltage dividers, RC filters, comparators and an ADC; the model is
        in docs/sensing.md). A controller that needs it (a sensorless one) turns it on; ``True`` turns it on for any
        controller (your own in the loop). The ``bemf_*`` settings below are in volts at the motor terminal: a
        value at the MCU pin is divided by the divider ratio.
    bemf_tau : float
        Time constant of the RC filter between the divider and the comparators and ADC (s), >= 0; 0 for none.
    bemf_reference : str
        The comparators' reference: ``"star"`` (the virtual star point of the three dividers, default) or
        ``"half"`` (half the DC bus).
    bemf_offset : float
        Comparator input offset (V at the terminal).
    bemf_hysteresis : float
        Comparator hysteresis, total width (V at the terminal), >= 0.
    bemf_delay : float
        Comparator propagation delay (s), >= 0: the MCU sees an edge this much later.
    bemf_adc_at : float
        ADC sampling instant after the carrier peak (s), in [-T/2, T/2) with T the PWM period: one conversion of the
        three filtered terminals and the reference per PWM period.
    bemf_adc_lsb : float
        ADC quantisation step (V at the terminal), >= 0; 0 for none.
    bemf_adc_max : float
        ADC full scale (V at the terminal), > 0; ``inf`` for none.
    bemf_adc_noise : float
        ADC noise, standard deviation (V at the terminal), >= 0.

    """

    current_phases: str = "ab"
    current_gain: tuple[float, float, float] = (1.0, 1.0, 1.0)
    current_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    current_noise: float = 0.0
    current_lsb: float = 0.0
    current_full_scale: float = math.inf
    vdc_gain: float = 1.0
    vdc_offset: float = 0.0
    vdc_noise: float = 0.0
    vdc_lsb: float = 0.0
    hall_error: tuple[float, float, float] = (0.0, 0.0, 0.0)
    hall_hysteresis: tuple[float, float, float] = (0.0, 0.0, 0.0)
    hall_delay: tuple[float, float, float] = (0.0, 0.0, 0.0)
    hall_tau: tuple[float, float, float] = (0.0, 0.0, 0.0)
    f_tick: float = 10e6
    seed: int = 1
    bemf: bool = False
    bemf_tau: float = 0.0
    bemf_reference: str = "star"
    bemf_offset: float = 0.0
    bemf_hysteresis: float = 0.0
    bemf_delay: float = 0.0
    bemf_adc_at: float = 0.0
    bemf_adc_lsb: float = 0.0
    bemf_adc_max: float = math.inf
    bemf_adc_noise: float = 0.0

    #: The back-EMF sensing settings and their defaults (a file writes only those it changes).
    BEMF_FIELDS: ClassVar[tuple[str, ...]] = ("bemf", "bemf_tau", "bemf_reference", "bemf_offset", "bemf_hysteresis",
                                              "bemf_delay", "bemf_adc_at", "bemf_adc_lsb", "bemf_adc_max",
                                              "bemf_adc_noise")

    def __post_init__(self) -> None:
        ph = self.current_phases
        if not isinstance(ph, str) or not ph or any(c not in PHASES for c in ph) or len(set(ph)) != len(ph):
            raise BldclabError("current_phases", f"must be letters from 'abc' without repeats, got {ph!r}")
        if len(ph) < 2:
            raise BldclabError("current_phases", "at least two phases must be measured")
        for name in ("current_gain", "current_offset", "hall_error"):
            v = getattr(self, name)
            if isinstance(v, str | bytes) or not isinstance(v, Sequence | np.ndarray):
                raise BldclabError(name, f"expected three numbers (a, b, c), got {type(v).__name__}")
            if len(v) != 3:
                raise BldclabError(name, f"needs three entries (a, b, c), got {len(v)}")
            for j, x in enumerate(v):
                check_number(f"{name}[{j}]", x)
            object.__setattr__(self, name, tuple(float(x) for x in v))
        for j, x in enumerate(self.hall_error):
            if not abs(x) < math.pi / 6.0:
                raise BldclabError(f"hall_error[{j}]", f"must be within +-30 deg electrical (pi/6 rad), got "
                                   f"{math.degrees(x):.4g} deg")
        for name, hi in (("hall_hysteresis", math.pi / 3.0), ("hall_delay", None), ("hall_tau", None)):
            object.__setattr__(self, name, _per_sensor(name, getattr(self, name), hi))
        for name in ("current_noise", "current_lsb", "vdc_noise", "vdc_lsb"):
            check_number(name, getattr(self, name), lo=0.0)
        fs = self.current_full_scale
        if isinstance(fs, bool) or not isinstance(fs, int | float | np.floating) or math.isnan(fs) or not fs > 0.0:
            raise BldclabError("current_full_scale", f"must be a number > 0 (inf for no clipping), got {fs!r}")
        object.__setattr__(self, "current_full_scale", float(fs))
        check_number("vdc_gain", self.vdc_gain)
        check_number("vdc_offset", self.vdc_offset)
        check_number("f_tick", self.f_tick, lo=1e3, hi=1e10)
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise BldclabError("seed", f"must be an integer >= 0, got {self.seed!r}")
        if not isinstance(self.bemf, bool):
            raise BldclabError("bemf", f"must be true or false, got {self.bemf!r}")
        for name in ("bemf_tau", "bemf_hysteresis", "bemf_delay", "bemf_adc_lsb", "bemf_adc_noise"):
            check_number(name, getattr(self, name), lo=0.0)
        check_number("bemf_offset", self.bemf_offset)
        check_number("bemf_adc_at", self.bemf_adc_at)
        if isinstance(self.bemf_adc_max, bool) or not isinstance(self.bemf_adc_max, int | float | np.floating) or \
                math.isnan(self.bemf_adc_max) or not self.bemf_adc_max > 0.0:
            raise BldclabError("bemf_adc_max", f"must be a number > 0 (inf for no clipping), got {self.bemf_adc_max!r}")
        if self.bemf_reference not in ("star", "half"):
            raise BldclabError("bemf_reference", f"must be 'star' (virtual star point) or 'half' (half the DC bus), "
                               f"got {self.bemf_reference!r}")

    @property
    def current_mask(self) -> int:
        """Bit mask of measured phases (bit 0 = a)."""
        return sum(1 << PHASES.index(c) for c in self.current_phases)


@dataclass(frozen=True)
class Drive:
    """A complete drive: motor, inverter, mechanics and sensors.

    Parameters
    ----------
    motor : Motor
    inverter : Inverter
    mechanics : Mechanics
    sensors : Sensors
    name : str
        Short name (catalog key or file stem).
    description : str
        Free text: where the data come from.
    thermal : Thermal, optional
        The thermal model (``[thermal]`` of a motor file, :mod:`bldclab.model.thermal`): network, loss routing and
        the temperature coefficients of ``R``, the back-EMF and ``R_on``; ``None`` (default): none, the
        parameters hold at every temperature.

    """

    motor: Motor
    inverter: Inverter
    mechanics: Mechanics = field(default_factory=Mechanics)
    sensors: Sensors = field(default_factory=Sensors)
    name: str = ""
    description: str = ""
    thermal: Thermal | None = None

    def __post_init__(self) -> None:
        parts = (("motor", Motor), ("inverter", Inverter), ("mechanics", Mechanics), ("sensors", Sensors))
        for part, cls in parts:
            value = getattr(self, part)
            if not isinstance(value, cls):
                raise BldclabError(part, f"must be a {cls.__name__}, got {type(value).__name__}")
        for key in ("name", "description"):
            if not isinstance(getattr(self, key), str):
                raise BldclabError(key, f"expected a string, got {getattr(self, key)!r}")
        if self.thermal is not None:
            if not isinstance(self.thermal, Thermal):
                raise BldclabError("thermal", "must be a bldclab.model.thermal.Thermal, got "
                                   f"{type(self.thermal).__name__}")
        half = 0.5 / self.inverter.f_pwm
        if not -half <= self.sensors.bemf_adc_at < half:
            raise BldclabError("sensors.bemf_adc_at", f"must be within [-T/2, T/2) = [{-half * 1e6:.4g}, "
                               f"{half * 1e6:.4g}) us of the carrier peak (T = 1/f_pwm), got "
                               f"{self.sensors.bemf_adc_at * 1e6:.4g} us")

    def scaled(self, *, R: float = 1.0, L: float = 1.0, emf: float = 1.0) -> Drive:
        """Return the drive with the motor's resistance, inductance and back-EMF scaled (a controller's estimate).

        For parameter-mismatch studies: ``bl.simulate(drive, control, scenario, estimate=drive.scaled(L=1.2))``
        configures the controller for an inductance 20 % above the plant's.

        Parameters
        ----------
        R, L, emf : float
            Factors (> 0, finite) on ``motor.R``, ``motor.L`` and every phase's back-EMF shape (so on ``k_phi``).

        Returns
        -------
        Drive
            The scaled copy, named ``<name> (estimate)``.

        Raises
        ------
        BldclabError
            Naming the factor that is not a finite number > 0.
        """
        for key, f in (("R", R), ("L", L), ("emf", emf)):
            if isinstance(f, bool) or not isinstance(f, int | float) or not math.isfinite(f) or f <= 0:
                raise BldclabError(f"scaled.{key}", f"must be a finite factor > 0, got {f!r}")
        m = self.motor
        motor = dataclasses.replace(m, R=m.R * R, L=m.L * L, emf=m.emf.scaled(emf) if emf != 1.0 else m.emf)
        return dataclasses.replace(self, motor=motor, name=f"{self.name} (estimate)")

    @property
    def loss_sources(self) -> tuple[str, ...]:
        """The loss sources (:data:`bldclab.model.thermal.LOSS_SOURCES`) this drive's parameters can produce.

        ``cu`` with ``R > 0``, ``fe`` with iron losses, ``fric`` with ``B`` or ``tau_c``, ``sw`` with ``R_on``,
        ``diode`` with ``V_f`` or ``r_d``, ``swloss`` with ``E_on`` or ``E_off``, ``rr`` with ``E_rr``, ``Rsrc`` with
        ``R_src``: a thermal model must route each of them to a node.
        """
        m, inv, mech = self.motor, self.inverter, self.mechanics
        have = {"cu": m.R > 0.0, "fe": m.has_iron_losses, "fric": mech.B > 0.0 or mech.tau_c > 0.0,
                "sw": inv.R_on > 0.0, "diode": inv.V_f > 0.0 or inv.r_d > 0.0,
                "swloss": inv.E_on > 0.0 or inv.E_off > 0.0, "rr": inv.E_rr > 0.0, "Rsrc": inv.R_src > 0.0}
        return tuple(k for k, v in have.items() if v)

    def at_temperature(self, *, winding: float | None = None, magnets: float | None = None,
                       switches: float | None = None) -> Drive:
        """Return the drive with ``R``, the back-EMF and ``R_on`` at the given temperatures (the plant when hot).

        The linear laws of :class:`~bldclab.model.thermal.Thermal` (``R (1 + alpha_R (T_w - T_ref))``, the shapes
        times ``1 + alpha_k (T_m - T_ref)``, ``R_on (1 + alpha_Ron (T_j - T_ref))``); a temperature not given stays
        at ``T_ref``. A controller configured from the result knows the hot values (a temperature-compensated
        firmware); pass the cold drive as ``estimate=`` to :func:`bldclab.simulate` for one that does not.

        Parameters
        ----------
        winding, magnets, switches : float, optional
            Temperatures (degC) of the winding, the magnets, the switches.

        Returns
        -------
        Drive
            Named ``<name> (<T> degC)``, with the same thermal model.

        Raises
        ------
        BldclabError
            Without a thermal model, or for a temperature whose factor is not positive.
        """
        th = self.thermal
        if th is None:
            raise BldclabError("thermal", f"drive {self.name!r} has no thermal model ([thermal] in its motor file)")
        temps = {n: th.T_ref for n in (*th.winding, *th.switches, *([th.magnets] if th.magnets else []))}
        mag = (th.magnets,) if th.magnets else ()
        for names, T in ((th.winding, winding), (th.switches, switches), (mag, magnets)):
            if T is not None:
                check_number("temperature", T, lo=-273.15, lo_open=True)
                temps.update({n: float(T) for n in names})
        r, k, ron = th.scales(temps)
        m = self.motor
        motor = dataclasses.replace(m, R=m.R * r, emf=m.emf.scaled(k) if k != 1.0 else m.emf)
        inverter = dataclasses.replace(self.inverter, R_on=self.inverter.R_on * ron)
        label = ", ".join(f"{k_} {v:g} degC" for k_, v in (("winding", winding), ("magnets", magnets),
                                                           ("switches", switches)) if v is not None)
        return dataclasses.replace(self, motor=motor, inverter=inverter,
                                   name=f"{self.name} ({label or 'T_ref'})")

    @property
    def Omega_0(self) -> float:
        """Speed base: no-load speed ``V_dc / (2 k_phi)`` (rad/s), paper 1 (2)."""
        return self.inverter.V_dc / (2.0 * self.motor.k_phi)

    @property
    def T_N(self) -> float:
        """Torque base ``2 k_phi I_N`` (N m)."""
        return self.motor.T_N

    def replace(self, **changes: Any) -> Drive:
        """Return a copy with fields changed; ``motor__R=0.0`` changes a field of a part.

        Parameters
        ----------
        **changes
            ``part__field=value`` or ``part=new_part`` (part in motor, inverter, mechanics, sensors) or
            ``name=...``/``description=...``.

        """
        parts: dict[str, dict[str, Any]] = {}
        top: dict[str, Any] = {}
        for key, value in changes.items():
            if "__" in key:
                part, name = key.split("__", 1)
                if part not in ("motor", "inverter", "mechanics", "sensors"):
                    raise BldclabError(key, f"unknown part {part!r}")
                parts.setdefault(part, {})[name] = value
            else:
                top[key] = value
        for part, kw in parts.items():
            obj = top.get(part, getattr(self, part))
            unknown = set(kw) - {f.name for f in dataclasses.fields(obj)}
            if unknown:
                raise BldclabError(f"{part}.{sorted(unknown)[0]}", "no such field")
            top[part] = dataclasses.replace(obj, **kw)
        return dataclasses.replace(self, **top)

    # ------------------------------------------------------------------------------------------------------
    # files

    @classmethod
    def from_toml(cls, path: str | Path) -> Drive:
        """Read a motor file.

        Parameters
        ----------
        path : str or Path
            TOML file (format: ``docs/motor-files.md``).

        Raises
        ------
        BldclabError
            For an unreadable file, a syntax error, or any missing, mistyped or out-of-range field.

        """
        p = Path(path)
        data = read_toml(p, "motor file")
        return cls.from_dict(data, source=str(p), default_name=p.stem)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None, default_name: str = "") -> Drive:
        """Build a drive from the parsed TOML structure (see :meth:`from_toml`)."""
        try:
            drive = _drive_from_dict(data, default_name)
        except BldclabError as exc:
            raise BldclabError(exc.field, exc.problem, source) from None
        hint = pole_count_hint(drive.motor.p, drive.Omega_0)
        if hint:  # a pole count typed as pole pairs: valid, and a PlausibilityWarning naming both readings
            where = f"{source}: " if source else ""
            warnings.warn(f"{where}motor.p: {hint}", PlausibilityWarning, stacklevel=3)
        return drive

    def to_toml(self) -> str:
        """Return the drive as a TOML motor file (SI numbers)."""
        return _drive_to_toml(self)


# ----------------------------------------------------------------------------------------------------------
# motor files: the drive's tables (the back-EMF's and the table machinery are in motorfile)


def _drive_from_dict(data: Mapping[str, Any], default_name: str) -> Drive:
    top = Section(data, "")
    name = top.string("name", default_name)
    description = top.string("description", "")
    ms = top.sub("motor")
    if ms is None:
        raise BldclabError("motor", "is missing (a [motor] table is required)")
    es = ms.sub("emf")
    if es is None:
        raise BldclabError("motor.emf", "is missing (a [motor.emf] table is required)")
    sizes = [k for k in KV_CONVENTIONS if ms.has(k)]
    form = read_form(es, ms.name(sizes[0])) if sizes else None
    emf = read_emf(es) if form is None else None
    cog = None
    cs = ms.sub("cogging")
    if cs is not None:
        cog = read_cogging(cs)
    iron_s = ms.sub("iron")
    given_p = [k for k in Motor.IRON_LOSS_FIELDS if ms.has(k)]
    if iron_s is not None and given_p:
        raise BldclabError(ms.name(given_p[0]), f"cannot be given with {iron_s.prefix}: give the iron losses as "
                           "powers (P_fe_eddy, P_fe_hyst, P_fe_ex at speed_fe_ref) or as a steel grade, core mass "
                           "and flux density ([motor.iron]), not both")
    motor = wrap("motor", Motor.from_ratings, p=ms.integer("p", None), poles=ms.integer("poles", None),
                  R=ms.raw("R", None), R_ll=ms.raw("R_ll", None), L=ms.raw("L", None), L_ll=ms.raw("L_ll", None),
                  emf=emf, KV=ms.raw("KV", None), KV_rms=ms.raw("KV_rms", None), shape=form or "sinusoid",
                  V_N=ms.quantity("V_N", "voltage"),
                  I_N=ms.quantity("I_N", "current"), Omega_N=ms.quantity("Omega_N", "speed", None),
                  T_peak=ms.quantity("T_peak", "torque", None), cogging=cog,
                  P_fe_eddy=ms.quantity("P_fe_eddy", "power", 0.0), P_fe_hyst=ms.quantity("P_fe_hyst", "power", 0.0),
                  P_fe_ex=ms.quantity("P_fe_ex", "power", 0.0),
                  speed_fe_ref=ms.quantity("speed_fe_ref", "speed", None))
    if iron_s is not None:
        motor = _iron_from_table(iron_s, motor)
    ms.finish()

    inv_s = top.sub("inverter")
    if inv_s is None:
        raise BldclabError("inverter", "is missing (an [inverter] table with V_dc and f_pwm is required)")
    energies = _inverter_energies(inv_s, motor)
    inverter = wrap("inverter", Inverter, V_dc=inv_s.quantity("V_dc", "voltage"),
                     f_pwm=inv_s.quantity("f_pwm", "frequency"),
                     t_dead=inv_s.quantity("t_dead", "time", 0.0),
                     R_on=inv_s.quantity("R_on", "resistance", 0.0),
                     V_f=inv_s.quantity("V_f", "voltage", 0.0), r_d=inv_s.quantity("r_d", "resistance", 0.0),
                     R_src=inv_s.quantity("R_src", "resistance", 0.0),
                     i_trip=inv_s.quantity("i_trip", "current", 0.0),
                     model=inv_s.string("model", "switching"), **energies)
    inv_s.finish()

    mech = Mechanics()
    mech_s = top.sub("mechanics")
    if mech_s is not None:
        mech = wrap("mechanics", Mechanics, J=mech_s.quantity("J", "inertia"),
                     B=mech_s.quantity("B", "damping", 0.0), tau_c=mech_s.quantity("tau_c", "torque", 0.0),
                     k_q=mech_s.quantity("k_q", "propeller", 0.0))
        mech_s.finish()

    sensors = Sensors()
    ss = top.sub("sensors")
    if ss is not None:
        kw: dict[str, Any] = {}
        if ss.has("current_phases"):
            kw["current_phases"] = ss.string("current_phases")
        for key, dim in (("hall_hysteresis", "angle"), ("hall_delay", "time"), ("hall_tau", "time")):
            if ss.has(key):  # one value for all three sensors, or a list (a, b, c)
                raw = ss.raw(key)
                kw[key] = (tuple(to_si(v, dim, f"{ss.name(key)}[{j}]") for j, v in enumerate(raw))
                           if isinstance(raw, list) else ss.quantity(key, dim))
        for key, dim in (("current_gain", "dimensionless"), ("current_offset", "current"),
                         ("hall_error", "angle")):
            if ss.has(key):
                raw = ss.raw(key)
                if not isinstance(raw, list):
                    raise BldclabError(ss.name(key), "expected a list of three values (a, b, c)")
                kw[key] = tuple(to_si(v, dim, f"{ss.name(key)}[{j}]") for j, v in enumerate(raw))
        for key, dim in (("current_noise", "current"), ("current_lsb", "current"), ("current_full_scale", "current"),
                         ("vdc_gain", "dimensionless"),
                         ("vdc_offset", "voltage"), ("vdc_noise", "voltage"), ("vdc_lsb", "voltage"),
                         ("f_tick", "frequency")):
            if ss.has(key):
                kw[key] = ss.quantity(key, dim)
        if ss.has("seed"):
            kw["seed"] = ss.integer("seed")
        if ss.has("bemf"):
            kw["bemf"] = ss.boolean("bemf")
        if ss.has("bemf_reference"):
            kw["bemf_reference"] = ss.string("bemf_reference")
        for key, dim in (("bemf_tau", "time"), ("bemf_offset", "voltage"), ("bemf_hysteresis", "voltage"),
                         ("bemf_delay", "time"), ("bemf_adc_at", "time"), ("bemf_adc_lsb", "voltage"),
                         ("bemf_adc_max", "voltage"), ("bemf_adc_noise", "voltage")):
            if ss.has(key):
                kw[key] = ss.quantity(key, dim)
        sensors = wrap("sensors", Sensors, **kw)
        ss.finish()
    thermal = None
    ths = top.sub("thermal")
    if ths is not None:
        thermal = read_thermal(ths)
    top.finish()
    return Drive(motor=motor, inverter=inverter, mechanics=mech, sensors=sensors, name=name,
                 description=description, thermal=thermal)


#: ``[motor.iron]`` keys of a steel grade given by its data instead of a built-in name (:class:`.iron.SteelGrade`).
GRADE_FIELDS: dict[str, str] = {"P10": "specific_power", "P15": "specific_power", "thickness": "length",
                                "density": "density", "resistivity": "resistivity"}


def _iron_from_table(sec: Section, motor: Motor) -> Motor:
    """Return ``motor`` with its iron-loss fields from a ``[motor.iron]`` table: a steel grade, core mass, flux.

    The grade is a built-in name (``grade = "M270-35A"``, :data:`.iron.GRADES`) or its five data
    (:data:`GRADE_FIELDS`); the result is :meth:`Motor.with_iron_from_grade`, and the file is written back with
    the ``P_fe_*`` fields it gives (as rise and fall times are written back as energies).
    """
    given_data = [k for k in GRADE_FIELDS if sec.has(k)]
    if sec.has("grade") and given_data:
        raise BldclabError(sec.name(given_data[0]), f"cannot be given with {sec.name('grade')}: name a built-in "
                           f"grade ({', '.join(GRADES)}) or give its data ({', '.join(GRADE_FIELDS)}), not both")
    key = sec.string("grade", None)
    if key is not None and key not in GRADES:
        raise BldclabError(sec.name("grade"), f"unknown grade {key!r}: built in are {', '.join(GRADES)}; "
                           f"another grade is given by its data ({', '.join(GRADE_FIELDS)})")
    data = {} if key is not None else {k: sec.quantity(k, dim) for k, dim in GRADE_FIELDS.items()}
    mass = sec.quantity("mass", "mass")
    B_peak = sec.quantity("B_peak", "flux_density")
    speed_ref = sec.quantity("speed_ref", "speed", None)
    sec.finish()
    try:
        grade = GRADES[key] if key is not None else SteelGrade(name="user grade", source="motor file", **data)
        return motor.with_iron_from_grade(grade, mass=mass, B_peak=B_peak, speed_ref=speed_ref)
    except BldclabError as exc:
        field, problem = exc.field.split(".", 1)[-1], exc.problem
        if field == "alpha":  # the fitted hysteresis exponent: the two losses do not fit a silicon steel
            field, problem = "P15", f"with P10 gives a hysteresis exponent that {problem}"
        raise BldclabError(sec.name(field), problem) from None


def _inverter_energies(inv_s: Section, motor: Motor) -> dict[str, float]:
    """Return ``E_on``, ``E_off``, ``E_rr``, ``V_test``, ``I_test`` of an ``[inverter]`` table.

    Given as energies, or estimated from ``t_rise``, ``t_fall``, ``Q_rr`` (:func:`switching_energies`; ``V_test``
    and ``I_test`` default to ``V_dc`` and the motor's ``I_N`` there).
    """
    given_e = [k for k in ("E_on", "E_off", "E_rr") if inv_s.has(k)]
    given_t = [k for k in TRANSITION_FIELDS if inv_s.has(k)]
    if given_e and given_t:
        raise BldclabError(inv_s.name(given_t[0]), f"cannot be given with {inv_s.name(given_e[0])}: give the "
                           "switching energies (E_on, E_off, E_rr) or the rise/fall times and recovery charge "
                           "(t_rise, t_fall, Q_rr), not both")
    if not given_t:
        return {"E_on": inv_s.quantity("E_on", "energy", 0.0), "E_off": inv_s.quantity("E_off", "energy", 0.0),
                "E_rr": inv_s.quantity("E_rr", "energy", 0.0), "V_test": inv_s.quantity("V_test", "voltage", 0.0),
                "I_test": inv_s.quantity("I_test", "current", 0.0)}
    v = inv_s.quantity("V_test", "voltage", None)
    i = inv_s.quantity("I_test", "current", None)
    v = inv_s.quantity("V_dc", "voltage") if v is None else v
    i = motor.I_N if i is None else i
    times = {"t_rise": inv_s.quantity("t_rise", "time", 0.0), "t_fall": inv_s.quantity("t_fall", "time", 0.0),
             "Q_rr": inv_s.quantity("Q_rr", "charge", 0.0)}
    try:
        e_on, e_off, e_rr = switching_energies(v, i, **times)
    except BldclabError as exc:
        raise BldclabError(inv_s.name(exc.field), exc.problem) from None
    return {"E_on": e_on, "E_off": e_off, "E_rr": e_rr, "V_test": v, "I_test": i}


def _motor_table(m: Motor) -> str:
    """Return the ``[motor]`` table in bldclab's canonical fields, the catalogue forms in comments beside them.

    ``p``, ``R``, ``L`` as the file reads them (a file with ``poles``, ``R_ll``, ``L_ll`` or ``KV`` is written back in
    these), with the pole count, the line-to-line values and the speed constants (of the ``[motor.emf]`` below) as
    comments: docs/motor-files.md, "Catalogue ratings".
    """
    mot: dict[str, object] = {"p": int(m.p), "R": float(m.R), "L": float(m.L), "V_N": float(m.V_N),
                              "I_N": float(m.I_N), "Omega_N": m.Omega_N, "T_peak": m.T_peak}
    if m.has_iron_losses or m.speed_fe_ref is not None:  # otherwise (the default) written as before they existed
        mot.update({k: getattr(m, k) for k in Motor.IRON_LOSS_FIELDS})
    notes = {"p": f"pole pairs ({m.poles} poles)", "R": f"Ohm per phase (line to line R_ll = {toml_value(m.R_ll)})",
             "L": f"H per phase (line to line L_ll = {toml_value(m.L_ll)})"}
    lines = ["[motor]"]
    for k, v in mot.items():
        if v is not None:
            lines.append(f"{k} = {toml_value(v)}" + (f"  # {notes[k]}" if k in notes else ""))
    lines.append(f"# back-EMF below: KV = {m.KV:.6g} rpm/V (per volt of peak line-to-line back-EMF: Omega_0 / V_dc), "
                 f"KV_rms = {m.KV_rms:.6g} rpm/V")
    return "\n".join(lines) + "\n"


def _drive_to_toml(d: Drive) -> str:
    out = [toml_table("", {"name": d.name, "description": d.description})]
    m = d.motor
    out.append(_motor_table(m))
    out += emf_tables(m.emf)
    if m.cogging is not None:
        out.append(cogging_table(m.cogging))
    inv = dataclasses.asdict(d.inverter)
    if inv["model"] == "switching":
        del inv["model"]  # the default: files written before the averaged inverter existed stay as they were
    if all(inv[k] == 0.0 for k in Inverter.SWITCHING_LOSS_FIELDS):
        for k in Inverter.SWITCHING_LOSS_FIELDS:
            del inv[k]  # no switching losses (the default): written as before they existed
    out.append(toml_table("inverter", inv))
    mech = dataclasses.asdict(d.mechanics)
    if mech["k_q"] == 0.0:
        del mech["k_q"]  # no propeller (the default): written as before it existed
    out.append(toml_table("mechanics", mech))
    sen = dataclasses.asdict(d.sensors)
    sen["current_gain"] = list(sen["current_gain"])
    sen["current_offset"] = list(sen["current_offset"])
    sen["hall_error"] = list(sen["hall_error"])
    for key in ("hall_hysteresis", "hall_delay", "hall_tau"):
        v = sen[key]
        if key != "hall_delay" and all(x == 0.0 for x in v):
            del sen[key]  # no hysteresis / filter (the default): written as before they existed
        else:
            sen[key] = v[0] if v[0] == v[1] == v[2] else list(v)
    if math.isinf(sen["current_full_scale"]):
        del sen["current_full_scale"]  # no full scale (the default): written as before it existed
    defaults = Sensors()
    for key in Sensors.BEMF_FIELDS:
        if sen[key] == getattr(defaults, key):
            del sen[key]  # no back-EMF sensing settings (the default): written as before they existed
    out.append(toml_table("sensors", sen))
    if d.thermal is not None:
        out += thermal_tables(d.thermal)
    return "\n".join(out)

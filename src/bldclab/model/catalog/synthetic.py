"""Synthetic non-ideal back-EMF shapes, and the ``lu-4kw`` catalog drive built from them.

Paper 2 (Lu, Zhang, Qu 2008) shows its motor's measured back-EMF only as a figure (its Fig. 6,
"significantly distorted comparing to the ideal 120 deg flat trapezoidal back EMF"), so the ``lu-4kw``
motor file carries a documented synthetic shape with the three defects that matter to its torque
controller:

1. **Rounded corners.** Flux fringing and slot openings smear the magnet edge: the trapezoid's corners
   become smooth arcs. The ideal shape is convolved with a Hann (raised-cosine) window of angular width
   ``c = corner`` (rad, electrical): ``w(u) = (1 + cos(2 pi u / c)) / c`` for ``|u| < c/2``. The
   convolution leaves every straight segment unchanged farther than ``c/2`` from a corner (a symmetric
   unit-area window maps a linear function to itself) and has a closed form near a corner: a slope
   change ``ds`` at ``x_j`` adds

       ds * (R(d) - max(d, 0)),   R(d) = ((d + c/2)^2 / 2 - (1 + cos(2 pi d / c)) (c / 2 pi)^2) / c,

   with ``d = theta - x_j`` wrapped to [-pi, pi) and ``|d| < c/2``. ``R'' = w``, so the rounded shape
   has a continuous slope and curvature. Nothing is truncated: every table value is exact to rounding.
2. **Tilted flat top.** Within each flat top the shape rises linearly by ``tilt`` times its mean height
   from start to end (``1 - tilt/2`` to ``1 + tilt/2``); the negative half is the mirror image, so the
   half-wave antisymmetry ``k(theta + pi) = -k(theta)`` is kept. An asymmetric flux distribution does
   this; under 120-degree rectangular current it makes the torque slope inside every 60-degree sector:
   the normal-conduction ripple paper 2's duty ``D_n`` removes.
3. **Phase mismatch.** Magnet and winding tolerances make the phases differ by a few percent in
   amplitude and by a degree or two in angle. :func:`lu4kw_emf` gives phase x the table
   ``k_x(theta_x) = s_x h(theta_x - delta_x)``: amplitude scale ``s_x``, angle offset ``delta_x``
   (positive: the phase lags its ideal position).

Every shape is then put on bldclab's angle convention (``docs/conventions.md``): the tilt moves the
fundamental by a small angle (2.0 deg for ``lu-4kw``), and the shape is shifted so that its fundamental
crosses zero rising at ``theta = 0`` (phase a has offset 0, so electrical angle 0 is phase a's
fundamental zero crossing). Last, the values are scaled so that the motor constant in bldclab's definition,
``k_phi = max |k_x - k_y| / 2`` over angle and phase pairs, is exactly the requested one for the table.

Chosen values for ``lu-4kw`` (paper 2 gives none of them):

- ``flat_top = 120 deg``: a 120-degree-style motor, the design two-phase conduction assumes.
- ``corner = 40 deg``: each corner rounded over +-20 deg, leaving 80 of the 120 deg of flat top
  straight: clearly distorted, as the paper's Fig. 6 describes, while 120-degree two-phase conduction
  remains the natural supply.
- ``tilt = 0.08``: the flat top rises by 8 % of its height, a torque slope of a few percent in normal
  conduction that the conventional controller cannot remove and ``D_n`` can.
- amplitude scales ``(1.00, 0.97, 1.025)`` and angle offsets ``(0, +2, -1.5) deg`` for phases a, b, c:
  "a few percent phase mismatch", unequal on purpose so that no two phases and no two sectors are
  alike. Phase a is the reference (scale 1, offset 0).
- 360 points per phase (1 deg) on a common grid: linear interpolation then stays within 2.1e-4
  ``k_phi`` of the smooth shape (``h^2/8`` times the peak curvature), and it is a table a DSP holds.
- ``k_phi = 0.4 V s/rad`` and the other drive numbers: see :func:`lu4kw_drive`.

Result: under ideal 120-degree rectangular current of amplitude ``I`` (Hall commutation,
``docs/conventions.md``) the ``lu-4kw`` torque stays between 0.91 and 1.00 times ``2 k_phi I``
(mean 0.97): a 9 % peak-to-peak ripple from the shape alone, before any commutation effect.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...errors import BldclabError
from ..emf import TWO_PI, BackEmf, Table, Trapezoid
from ..motor import Drive, Inverter, Mechanics, Motor, Sensors

__all__ = [
    "LU4KW_AMPLITUDE",
    "LU4KW_CORNER",
    "LU4KW_FLAT_TOP",
    "LU4KW_K_PHI",
    "LU4KW_N_POINTS",
    "LU4KW_OFFSET",
    "LU4KW_TILT",
    "lu4kw_drive",
    "lu4kw_emf",
    "paper1_drive",
    "rounded_trapezoid",
]

#: Motor constant of ``lu-4kw`` (V s/rad), bldclab definition (half the peak line-to-line shape).
LU4KW_K_PHI = 0.4
#: Flat-top width of the underlying trapezoid (rad, electrical): 120 deg.
LU4KW_FLAT_TOP = TWO_PI / 3.0
#: Width of the corner-rounding window (rad, electrical): 40 deg.
LU4KW_CORNER = math.radians(40.0)
#: Rise of the flat top from start to end, as a fraction of its mean height.
LU4KW_TILT = 0.08
#: Amplitude scale of phases a, b, c.
LU4KW_AMPLITUDE = (1.00, 0.97, 1.025)
#: Angle offset of phases a, b, c (rad, electrical; positive: the phase lags).
LU4KW_OFFSET = (0.0, math.radians(2.0), math.radians(-1.5))
#: Table points per phase (uniform in [0, 2 pi)).
LU4KW_N_POINTS = 360


def _check_trapezoid_args(flat_top: float, corner: float, tilt: float) -> None:
    """Validate the shape arguments shared by the generators; raise naming the field."""
    for name, value in (("flat_top", flat_top), ("corner", corner), ("tilt", tilt)):
        if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
            raise BldclabError(name, f"expected a number, got {type(value).__name__} ({value!r})")
        if not math.isfinite(float(value)):
            raise BldclabError(name, f"must be finite, got {value}")
    if not 0.0 < flat_top < math.pi:
        raise BldclabError("flat_top", f"must lie in (0, pi) rad, got {flat_top:g}")
    limit = min(flat_top, math.pi - flat_top)
    if not 0.0 <= corner <= limit:
        raise BldclabError("corner", f"must lie in [0, min(flat_top, pi - flat_top)] = [0, {limit:g}] rad "
                           f"so that neighbouring corners stay apart, got {corner:g}")
    if not -2.0 < tilt < 2.0:
        raise BldclabError("tilt", f"must lie in (-2, 2) so that the flat top keeps its sign, got {tilt:g}")


def _unit_shape(theta: ArrayLike, flat_top: float, corner: float, tilt: float) -> NDArray[np.float64]:
    """Evaluate the rounded, tilted trapezoid of mean flat-top height 1 (before alignment and scaling).

    Parameters
    ----------
    theta : array_like
        Angle (rad, electrical), any real value.
    flat_top, corner, tilt : float
        As in :func:`rounded_trapezoid`.

    Returns
    -------
    ndarray
        The shape (dimensionless, mean flat-top height 1).

    """
    th = np.mod(np.asarray(theta, dtype=float), TWO_PI)
    r = 0.5 * (math.pi - flat_top)  # half width of the ramp through zero
    x = np.array([r, math.pi - r, math.pi + r, TWO_PI - r])  # corners
    y = np.array([1.0 - tilt / 2, 1.0 + tilt / 2, -(1.0 - tilt / 2), -(1.0 + tilt / 2)])
    out = np.interp(th, x, y, period=TWO_PI)
    if corner > 0.0:
        s_flat = tilt / flat_top  # slope of the positive flat top (the negative one has -s_flat)
        s_ramp = 1.0 / r  # slope of the rising ramp (the falling one has -s_ramp)
        # slope change (after - before) at each corner
        jumps = (s_flat - s_ramp, -s_ramp - s_flat, -s_flat + s_ramp, s_ramp + s_flat)
        c = corner
        for xj, ds in zip(x, jumps, strict=True):
            d = np.mod(th - xj + math.pi, TWO_PI) - math.pi
            near = np.abs(d) < 0.5 * c
            dn = d[near]
            # R(d) = ((d + c/2)^2 / 2 - (1 + cos(2 pi d/c)) (c/2pi)^2) / c: the corner convolved with w
            rounded = ((dn + 0.5 * c) ** 2 / 2.0 - (1.0 + np.cos(TWO_PI * dn / c)) * (c / TWO_PI) ** 2) / c
            out[near] += ds * (rounded - np.maximum(dn, 0.0))
    return out


def _alignment(flat_top: float, tilt: float) -> float:
    """Return the angle phi (rad) of the unit shape's fundamental ``A sin(theta + phi)``.

    The rounding window is even with a positive transform at order 1, so it does not move the
    fundamental: the exact Fourier coefficients of the piecewise-linear unrounded shape give the angle.
    """
    r = 0.5 * (math.pi - flat_top)
    corners = Table((r, math.pi - r, math.pi + r, TWO_PI - r),
                    (1.0 - tilt / 2, 1.0 + tilt / 2, -(1.0 - tilt / 2), -(1.0 + tilt / 2)))
    a, b = corners.fourier(1)
    return math.atan2(float(a[1]), float(b[1]))


def _grid(n_points: int) -> NDArray[np.float64]:
    """Return ``n_points`` uniform angles in [0, 2 pi) (rad)."""
    if isinstance(n_points, bool) or not isinstance(n_points, int | np.integer) or n_points < 3:
        raise BldclabError("n_points", f"must be an integer >= 3, got {n_points!r}")
    return TWO_PI * np.arange(int(n_points)) / int(n_points)


def _check_k_phi(k_phi: float) -> None:
    """Validate the requested motor constant."""
    if isinstance(k_phi, bool) or not isinstance(k_phi, int | float | np.floating | np.integer):
        raise BldclabError("k_phi", f"expected a number, got {type(k_phi).__name__} ({k_phi!r})")
    if not (math.isfinite(float(k_phi)) and k_phi > 0.0):
        raise BldclabError("k_phi", f"must be a finite number > 0, got {k_phi}")


def rounded_trapezoid(k_phi: float, flat_top: float = TWO_PI / 3.0, corner: float = 0.0,
                      tilt: float = 0.0, n_points: int = 360) -> Table:
    """Return a 120-degree-style trapezoid with rounded corners and a tilted flat top, as a table.

    The construction (module docstring): an ideal trapezoid with flat tops of width ``flat_top``
    rising by ``tilt`` from start to end, convolved with a Hann window of width ``corner``, shifted so
    that its fundamental crosses zero rising at ``theta = 0``, sampled at ``n_points`` uniform angles in
    [0, 2 pi) and scaled so that a symmetric three-phase set of it has the motor constant ``k_phi``
    (``docs/conventions.md``). Half-wave antisymmetric: ``k(theta + pi) = -k(theta)``.

    Parameters
    ----------
    k_phi : float
        Motor constant of the result (V s/rad), > 0: half the peak line-to-line value of three phases
        of this shape. It is the flat-top height when ``corner = tilt = 0`` and ``flat_top >= pi/3``.
    flat_top : float
        Width of each flat top before rounding (rad, electrical), in (0, pi). Default 2 pi/3 (120 deg).
    corner : float
        Angular width of the rounding window (rad, electrical), in [0, min(flat_top, pi - flat_top)];
        0 keeps sharp corners. Default 0.
    tilt : float
        Rise of the flat top from its start to its end as a fraction of its mean height (-), in (-2, 2);
        positive rises. Default 0.
    n_points : int
        Number of samples, >= 3. A multiple of 12 puts samples on the Hall edges ``pi/6 + n pi/3``.
        Default 360 (1 deg).

    Returns
    -------
    Table
        ``k(theta)`` in V s/rad at ``theta = 2 pi j / n_points``.

    Raises
    ------
    BldclabError
        If an argument is out of range; the error names it.

    """
    _check_k_phi(k_phi)
    _check_trapezoid_args(flat_top, corner, tilt)
    theta = _grid(n_points)
    phi = _alignment(flat_top, tilt)
    k = _unit_shape(theta - phi, flat_top, corner, tilt)
    shape = Table(tuple(theta), tuple(k))
    scale = 2.0 * float(k_phi) / BackEmf.symmetric(shape).line_peak()
    return Table(tuple(theta), tuple(scale * k))


def lu4kw_emf() -> BackEmf:
    """Return the synthetic back-EMF of the ``lu-4kw`` motor (paper 2's appendix motor).

    Three tables on a common grid of :data:`LU4KW_N_POINTS` angles: the rounded, tilted trapezoid of
    :func:`rounded_trapezoid` (:data:`LU4KW_FLAT_TOP`, :data:`LU4KW_CORNER`, :data:`LU4KW_TILT`),
    phase x scaled by ``LU4KW_AMPLITUDE[x]`` and delayed by ``LU4KW_OFFSET[x]``, then all scaled
    together so that the motor constant is :data:`LU4KW_K_PHI`. Values and reasons: module docstring.

    Returns
    -------
    BackEmf
        Per-phase tables ``k_a, k_b, k_c`` (V s/rad) of the phases' local angles.

    """
    theta = _grid(LU4KW_N_POINTS)
    phi = _alignment(LU4KW_FLAT_TOP, LU4KW_TILT)
    raw = [s * _unit_shape(theta - phi - delta, LU4KW_FLAT_TOP, LU4KW_CORNER, LU4KW_TILT)
           for s, delta in zip(LU4KW_AMPLITUDE, LU4KW_OFFSET, strict=True)]
    a, b, c = (Table(tuple(theta), tuple(k)) for k in raw)
    scale = 2.0 * LU4KW_K_PHI / BackEmf((a, b, c)).line_peak()
    a, b, c = (Table(tuple(theta), tuple(scale * k)) for k in raw)
    return BackEmf((a, b, c))


def lu4kw_drive() -> Drive:
    """Return the ``lu-4kw`` drive: paper 2's appendix motor with documented assumptions.

    From the paper (appendix): 4 poles (``p = 2``), 4 kW, 300 V, 3000 rpm rated,
    ``R = 0.059 Ohm``, ``L = 0.29 mH``; current sensors on phases a and c and a DC-bus voltage sensor
    (its Fig. 5); IGBTs driven by a TMS320F240 DSP.

    Assumed (the paper gives no back-EMF constant, current, inertia or PWM frequency):

    - ``k_phi = 0.4 V s/rad``. At rated speed ``Omega_N = 3000 rpm = 314.16 rad/s`` the peak
      line-to-line back-EMF is ``2 k_phi Omega_N = 251.3 V``: below the 300 V bus, with about 49 V left
      to drive current. And ``4 E = 4 k_phi Omega_N = 502.7 V > V_dc``, so at rated speed the DC bus
      limits commutation (the incoming phase current rises slower than the outgoing one falls): the
      case paper 2's ``D_o`` mode is for. The bus stops being the limit below
      ``V_dc / (4 k_phi) = 187.5 rad/s = 1790 rpm``. No-load speed
      ``Omega_0 = V_dc / (2 k_phi) = 375 rad/s = 3581 rpm``.
    - ``I_N`` from the rating: ``T_N = P_N / Omega_N = 4000 W / 314.16 rad/s = 12.732 N m`` and
      ``T_N = 2 k_phi I_N`` give ``I_N = 12.732 N m / 0.8 V s/rad = 15.915 A``. The paper's current
      and torque plots (10 A/div, 2.54 N m/div) are of the same order.
    - ``J = 5e-3 kg m^2``: a 4 kW, 3000 rpm rotor (about 2e-3 kg m^2) coupled to a load machine of
      similar size; rated torque takes it to rated speed in about 0.12 s.
    - ``B = 2e-4 N m s/rad``, ``tau_c = 0.06 N m``: friction and windage of about 40 W at rated
      speed, 1 % of the rating, half viscous (``B Omega_N^2 = 20 W``), half Coulomb
      (``tau_c Omega_N = 19 W``).
    - ``f_pwm = 10 kHz``: a usual IGBT chopping frequency for a TMS320F240 drive; the controller is
      sampled at 20 kHz.
    - ``f_tick = 20 MHz``: the F240's timer clock (its CPU clock), which time-stamps the Hall edges.
    - Ideal inverter (no dead time, on-resistance or diode drop): paper 2's duty laws neglect them
      too; a study of their effect sets them with :meth:`Drive.replace`.
    - No ``T_peak``: the paper gives none, and nothing in bldclab needs it.

    Returns
    -------
    Drive
        The drive that ``tools/make_lu4kw.py`` writes to ``catalog/lu-4kw.toml``.

    """
    P_N = 4000.0  # rated power (W)
    Omega_N = 3000.0 * TWO_PI / 60.0  # rated speed (rad/s)
    I_N = P_N / Omega_N / (2.0 * LU4KW_K_PHI)  # T_N = P_N / Omega_N = 2 k_phi I_N
    description = (
        "4 kW BLDC motor of paper 2 (Lu, Zhang, Qu, IEEE Trans. Power Electron. 2008), appendix: 4 poles, "
        "4 kW, 300 V, 3000 rpm, 0.059 Ohm, 0.29 mH; currents of phases a and c measured (its Fig. 5). "
        "SYNTHETIC back-EMF (the paper shows the measured shape only as a figure), made by "
        "bldclab.model.catalog.synthetic.lu4kw_emf(): a 120-degree trapezoid with corners rounded by a 40-degree "
        "Hann window and a flat top rising by 8 %, phases a, b, c scaled by 1.00/0.97/1.025 and delayed by "
        "0/+2/-1.5 deg, scaled to k_phi = 0.4 V s/rad (assumed), 360 points per phase. Also assumed: "
        "I_N = 4 kW / (3000 rpm * 2 k_phi) = 15.92 A, J, B, tau_c, f_pwm = 10 kHz, f_tick = 20 MHz, "
        "ideal inverter with a hardware over-current trip at 4 I_N = 64 A (assumed); reasons in "
        "bldclab.model.catalog.synthetic.lu4kw_drive. Regenerate with "
        "tools/make_lu4kw.py; do not edit by hand."
    )
    return Drive(
        motor=Motor(p=2, R=0.059, L=0.29e-3, emf=lu4kw_emf(), V_N=300.0, I_N=I_N, Omega_N=Omega_N),
        inverter=Inverter(V_dc=300.0, f_pwm=10e3, i_trip=64.0),
        mechanics=Mechanics(J=5e-3, B=2e-4, tau_c=0.06),
        sensors=Sensors(current_phases="ac", f_tick=20e6),
        name="lu-4kw",
        description=description,
    )


def paper1_drive(Theta_m: float, *, p: int = 4, V_N: float = 48.0, I_N: float = 10.0, Omega_0: float = 100.0,
                 R: float = 0.0, f_pwm: float | None = None, pwm_per_commutation: float = 50.0,
                 f_tick: float = 100e6, name: str = "paper1-synthetic") -> Drive:
    """Return a drive on paper 1's premises with a chosen motor-specific parameter ``Theta_m``.

    Paper 1's per-unit results (torque, ripple, base speeds) depend on the motor only through
    ``Theta_m = p L I_N / (2 k_phi)`` (its (22)) when ``R = 0``, the back-EMF is the ideal 120-degree trapezoid,
    and the DC bus equals the nominal voltage. This builds such a drive from per-unit choices, so that studies and
    tests can range over motors of any size: ``k_phi = V_N / (2 Omega_0)`` (paper 1 (2)), ``L = 2 k_phi Theta_m /
    (p I_N)``, an ideal inverter (no dead time, on-resistance or diode drop) with a hardware trip at ``4 I_N``.

    Parameters
    ----------
    Theta_m : float
        Motor-specific parameter (rad, electrical), > 0 (0.047 for paper 1's study case).
    p : int
        Pole pairs.
    V_N : float
        DC bus = nominal voltage (V).
    I_N : float
        Nominal current (A).
    Omega_0 : float
        No-load speed ``V_N / (2 k_phi)`` (rad/s, mechanical).
    R : float
        Phase resistance (Ohm); the closed forms assume 0.
    f_pwm : float, optional
        Carrier frequency (Hz). Default: ``pwm_per_commutation`` PWM periods per commutation interval (a sixth of
        the electrical period) at ``Omega_0``.
    pwm_per_commutation : float
        PWM periods per commutation interval at ``Omega_0`` when ``f_pwm`` is not given.
    f_tick : float
        Hall capture-timer frequency (Hz).
    name : str
        Drive name.

    Returns
    -------
    Drive
        The drive (its ``motor.L`` and ``motor.emf`` follow from the arguments).

    """
    if not (math.isfinite(Theta_m) and Theta_m > 0.0):
        raise BldclabError("Theta_m", f"must be a positive number of radians, got {Theta_m!r}")
    if not (math.isfinite(Omega_0) and Omega_0 > 0.0):
        raise BldclabError("Omega_0", f"must be a positive speed in rad/s, got {Omega_0!r}")
    if not (math.isfinite(pwm_per_commutation) and pwm_per_commutation > 0.0):
        raise BldclabError("pwm_per_commutation", f"must be positive, got {pwm_per_commutation!r}")
    k_phi = V_N / (2.0 * Omega_0)
    L = 2.0 * k_phi * Theta_m / (p * I_N)
    if f_pwm is None:
        f_pwm = pwm_per_commutation * 6.0 * p * Omega_0 / TWO_PI
    description = (f"Synthetic drive on paper 1's premises: Theta_m = {Theta_m:.4g} rad, p = {p}, V_N = {V_N:.4g} V, "
                   f"I_N = {I_N:.4g} A, Omega_0 = {Omega_0:.4g} rad/s, R = {R:.4g} Ohm, f_pwm = {f_pwm:.4g} Hz "
                   "(bldclab.model.catalog.synthetic.paper1_drive).")
    return Drive(
        motor=Motor(p=p, R=R, L=L, emf=BackEmf.symmetric(Trapezoid(k_phi)), V_N=V_N, I_N=I_N),
        inverter=Inverter(V_dc=V_N, f_pwm=f_pwm, i_trip=4.0 * I_N),
        mechanics=Mechanics(),
        sensors=Sensors(f_tick=f_tick),
        name=name,
        description=description,
    )

"""Paper 1's closed forms against simulation on drives drawn at random (shared by the tests and the benchmark).

A drive is drawn on paper 1's premises (ideal 120-degree trapezoid, DC bus at the nominal voltage) with
``bldclab.catalog.synthetic.paper1_drive``: ``Theta_m`` from 0.01 to 0.2 rad, 1 to 20 pole pairs, any size
(voltage, current, no-load speed), a carrier from 5 to 200 PWM periods per commutation, and a phase resistance from
0 to a significant share of ``V/I``. The commutation is the time the outgoing current takes to fall from ``I_N``
to zero through its diode, ``t_c = 3 L I_N / (V_N (1 + W))`` at the per-unit speed ``W`` (paper 1, IV.A: the first
part of every commutation, at any speed), i.e. ``3 Theta_m / (p Omega_0 (1 + W))``: the closed forms assume an
ideal current limiter, which a sampled controller only approaches when a commutation spans several samples.
Each example runs both supplies at one speed (the square wave regulating ``I_N``, the sinusoidal supply asked for
``T_sN``) and returns the deviations from the closed forms, so that the test asserts them and the benchmark prints
the worst.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from hypothesis import strategies as st

from bldclab.analysis.compare import default_controls
from bldclab.analysis.experiments import steady_state
from bldclab.model import analytic
from bldclab.model.catalog.synthetic import paper1_drive
from bldclab.model.emf import TWO_PI, BackEmf, Trapezoid
from bldclab.model.motor import Drive

#: Highest carrier drawn (Hz): the catalog's Inverter accepts up to 10 MHz; a drive drawn beyond 2 MHz is redrawn.
MAX_F_PWM = 2e6


@dataclass(frozen=True)
class Case:
    """One drawn drive and operating speed."""

    Theta_m: float
    p: int
    V_N: float
    I_N: float
    Omega_0: float
    pwm_per_commutation: float  # f_pwm t_c at the case's speed
    r_share: float  # R I_N / V_N
    speed_pu: float

    @property
    def f_pwm(self) -> float:
        """Carrier frequency (Hz): ``pwm_per_commutation / t_c`` with ``t_c = 3 Theta_m / (p Omega_0 (1 + W))``."""
        t_c = 3.0 * self.Theta_m / (self.p * self.Omega_0 * (1.0 + self.speed_pu))
        return self.pwm_per_commutation / t_c

    def drive(self, model: str = "average", flat_top: float = TWO_PI / 3.0) -> Drive:
        """The drive with the given inverter model and trapezoid flat-top width (rad, electrical)."""
        d = paper1_drive(self.Theta_m, p=self.p, V_N=self.V_N, I_N=self.I_N, Omega_0=self.Omega_0,
                         R=self.r_share * self.V_N / self.I_N, f_pwm=self.f_pwm)
        motor = dataclasses.replace(d.motor, emf=BackEmf.symmetric(Trapezoid(d.motor.k_phi, flat_top)))
        return dataclasses.replace(d, motor=motor, inverter=dataclasses.replace(d.inverter, model=model))


def cases(r_max: float = 0.0, pwm_max: float = 200.0) -> st.SearchStrategy[Case]:
    """Drives and speeds; ``r_max``: largest ``R I_N / V_N`` (0: paper 1's R = 0); ``pwm_max``: most PWM periods
    per commutation (the cost of a run grows with it)."""
    return st.builds(
        Case,
        Theta_m=st.floats(0.01, 0.2),
        p=st.integers(1, 20),
        V_N=st.floats(12.0, 600.0),
        I_N=st.floats(1.0, 200.0),
        Omega_0=st.floats(20.0, 2000.0),
        pwm_per_commutation=st.floats(5.0, pwm_max),
        r_share=st.just(0.0) if r_max == 0.0 else st.floats(0.0, r_max),
        speed_pu=st.floats(0.05, 0.98),
    ).filter(lambda c: c.f_pwm <= MAX_F_PWM)


@dataclass(frozen=True)
class Outcome:
    """Simulated per-unit mean torque and instantaneous ripple of both supplies, and paper 1's closed forms."""

    T_q: float
    TR_q: float
    T_s: float
    TR_s: float
    T_q_cf: float
    TR_q_cf: float
    T_s_cf: float
    TR_s_cf: float


#: Flat top under which paper 1's square-wave closed forms hold exactly: (26)-(33) take the back-EMF of the outgoing
#: phase as constant during a commutation, but with the 120-degree trapezoid that phase leaves its flat top at the
#: very instant it commutates and its back-EMF ramps down while its current falls. A 160-degree flat top keeps every
#: commutation (at most ``3 Theta_m W / (1 + W)`` <= 17 degrees for the outgoing current) on the flat tops, with the
#: same torque outside commutation. On the 120-degree shape the closed forms are off by an error of their own, which
#: grows with ``Theta_m`` (``benchmarks/random_drives.py`` prints it).
FLAT_TOP_SQUARE = math.radians(160.0)


def run(case: Case, model: str = "average", square_flat_top: float = FLAT_TOP_SQUARE) -> Outcome:
    """Simulate both supplies at the case's speed (imposed) and evaluate the closed forms there.

    The sinusoidal supply runs on paper 1's 120-degree trapezoid ((13)-(15) are for that shape); the square wave on a
    trapezoid of ``square_flat_top`` (:data:`FLAT_TOP_SQUARE`: the premise of (26)-(33)).
    """
    th = case.Theta_m
    w = case.speed_pu
    out = {}
    for supply, flat_top in (("square", square_flat_top), ("sine", TWO_PI / 3.0)):
        drive = case.drive(model, flat_top)
        control, ref = default_controls(drive, lowest_speed_pu=min(w, 0.05))[supply]
        point, _ = steady_state(drive, control, w * drive.Omega_0, ref)
        out[supply] = (point.tau_mean_pu, point.ripple_pu)
    return Outcome(T_q=out["square"][0], TR_q=out["square"][1], T_s=out["sine"][0], TR_s=out["sine"][1],
                   T_q_cf=float(analytic.t_q_pu(w, th)), TR_q_cf=float(analytic.tr_q_pu(w, th)),
                   T_s_cf=float(analytic.t_s_pu(w, th)), TR_s_cf=float(analytic.tr_s_pu(w, th)))


def mean_torque_switching(case: Case, supply: str) -> tuple[float, float]:
    """Per-unit mean torque of one supply in the averaged and the switching inverter model."""
    res = []
    for model in ("average", "switching"):
        drive = case.drive(model)
        control, ref = default_controls(drive, lowest_speed_pu=min(case.speed_pu, 0.05))[supply]
        point, _ = steady_state(drive, control, case.speed_pu * drive.Omega_0, ref)
        res.append(point.tau_mean_pu)
    return res[0], res[1]


def describe(case: Case) -> str:
    """One line naming the case (for failure messages and the benchmark)."""
    return (f"Theta_m={case.Theta_m:.4f} p={case.p} V_N={case.V_N:.1f} I_N={case.I_N:.1f} "
            f"Omega_0={case.Omega_0:.1f} pwm/comm={case.pwm_per_commutation:.1f} (f_pwm={case.f_pwm:.4g} Hz) "
            f"R_share={case.r_share:.3f} "
            f"W={case.speed_pu:.3f}")


__all__ = ["FLAT_TOP_SQUARE", "MAX_F_PWM", "Case", "Outcome", "cases", "describe", "mean_torque_switching", "run"]

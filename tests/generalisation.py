"""Paper 1's closed forms against simulation on drives drawn at random (shared by the tests and the benchmark).

A drive is drawn on paper 1's premises (ideal 120-degree trapezoid, DC bus at the nominal voltage) with
``bldclab.catalog.synthetic.paper1_drive``: ``Theta_m`` from 0.01 to 0.2 rad, 1 to 20 pole pairs, any size
(voltage, current, no-load speed), PWM from 5 to 200 periods per commutation interval (a sixth of the electrical
period) at the no-load speed, and a phase resistance from 0 to a significant share of ``V/I``. Each example runs
both supplies at one speed (the square wave regulating ``I_N``, the sinusoidal supply asked for ``T_sN``) and
returns the deviations from the closed forms, so that the test asserts them and the benchmark prints the worst.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from hypothesis import strategies as st

from bldclab import analytic
from bldclab.catalog.synthetic import paper1_drive
from bldclab.compare import default_controls
from bldclab.experiments import steady_state
from bldclab.motor import Drive


@dataclass(frozen=True)
class Case:
    """One drawn drive and operating speed."""

    Theta_m: float
    p: int
    V_N: float
    I_N: float
    Omega_0: float
    pwm_per_commutation: float
    r_share: float  # R I_N / V_N
    speed_pu: float

    def drive(self, model: str = "average", f_scale: float = 1.0) -> Drive:
        """The drive, its inverter model, and its carrier frequency scaled by ``f_scale``."""
        d = paper1_drive(self.Theta_m, p=self.p, V_N=self.V_N, I_N=self.I_N, Omega_0=self.Omega_0,
                         R=self.r_share * self.V_N / self.I_N, pwm_per_commutation=self.pwm_per_commutation)
        inv = dataclasses.replace(d.inverter, model=model, f_pwm=d.inverter.f_pwm * f_scale)
        return dataclasses.replace(d, inverter=inv)


def cases(r_max: float = 0.0) -> st.SearchStrategy[Case]:
    """Drives and speeds; ``r_max``: largest ``R I_N / V_N`` (0: paper 1's R = 0)."""
    return st.builds(
        Case,
        Theta_m=st.floats(0.01, 0.2),
        p=st.integers(1, 20),
        V_N=st.floats(12.0, 600.0),
        I_N=st.floats(1.0, 200.0),
        Omega_0=st.floats(20.0, 2000.0),
        pwm_per_commutation=st.floats(5.0, 200.0),
        r_share=st.just(0.0) if r_max == 0.0 else st.floats(0.0, r_max),
        speed_pu=st.floats(0.05, 0.98),
    )


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


def run(case: Case, model: str = "average") -> Outcome:
    """Simulate both supplies at the case's speed (imposed) and evaluate the closed forms there."""
    drive = case.drive(model)
    th = analytic.theta_m(drive)
    w = case.speed_pu
    controls = default_controls(drive, lowest_speed_pu=min(w, 0.05))
    out = {}
    for supply, (control, ref) in controls.items():
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
            f"Omega_0={case.Omega_0:.1f} pwm/comm={case.pwm_per_commutation:.1f} R_share={case.r_share:.3f} "
            f"W={case.speed_pu:.3f}")


__all__ = ["Case", "Outcome", "cases", "describe", "mean_torque_switching", "run"]

"""Self-commissioning of a drive ("motor detection").

Runs :class:`~bldclab.control.commission.Commission` on the plant and builds the estimated drive from what the
controller measured (``docs/sensorless-sine.md``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from .._core import core as load_core
from ..control.commission import Commission
from ..control.sine import fundamental_k1
from ..errors import BldclabError
from ..model.motor import Drive
from ..sim import Fault, Scenario, simulate

__all__ = ["Estimate", "commission"]


@dataclass(frozen=True)
class Estimate:
    """What self-commissioning measured.

    Attributes
    ----------
    status : str
        ``"DONE"``, or the failure: ``"ROTOR_MOVING"``, ``"NO_CURRENT"``, ``"SATURATED"``, ``"NOT_FOLLOWING"``,
        ``"NOISY"`` (the current's noise leaves L imprecise), ``"FAULT"``, ``"CLIPPED"`` (a current reading at the
        sensors' full scale, ``Sensors.current_full_scale``; ``bc_commission.h``), or ``"UNFINISHED"`` (the run
        ended first).
    R : float
        Resistance in series with a phase, ``R + R_on`` (Ohm); 0 if not measured.
    L : float
        Inductance (H); 0 if not measured.
    psi_f : float
        PM flux linkage of the fundamental, ``k_1 / p`` (V s); 0 if not measured.
    t_test : float
        Time the routine took on the drive (s).
    wall_time : float
        Simulation wall time (s).
    nominal : Drive
        The nominal data the routine was configured from.
    """

    status: str
    R: float
    L: float
    psi_f: float
    t_test: float
    wall_time: float
    nominal: Drive

    @property
    def ok(self) -> bool:
        """True if every value was measured (status ``DONE``)."""
        return self.status == "DONE"

    @property
    def drive(self) -> Drive:
        """Return the estimated drive for ``simulate(..., estimate=)``.

        The nominal drive with its motor's R (the measured value less the inverter's ``R_on``), L and back-EMF
        amplitude (its shape kept) from the measurement.

        Raises
        ------
        BldclabError
            ``commission.status`` when the routine did not finish (its status named).
        """
        if not self.ok:
            raise BldclabError("commission.status", f"the routine ended with {self.status}: nothing to estimate")
        m = self.nominal.motor
        r_motor = self.R - self.nominal.inverter.R_on
        if not r_motor > 0:
            raise BldclabError("commission.R", f"measured {self.R:.4g} Ohm, not above the inverter's R_on "
                               f"{self.nominal.inverter.R_on:.4g} Ohm")
        emf = self.psi_f * m.p / fundamental_k1(self.nominal)
        return self.nominal.scaled(R=r_motor / m.R, L=self.L / m.L, emf=emf)

    def to_dict(self) -> dict[str, object]:
        """Return the values as a plain dict (SI units)."""
        return {"status": self.status, "R_Ohm": self.R, "L_H": self.L, "psi_f_Vs": self.psi_f,
                "t_test_s": self.t_test, "wall_time_s": self.wall_time}


def commission(drive: Drive, nominal: Drive | None = None, control: Commission | None = None, *,
               speed: float | None = None, load_torque: float = 0.0, faults: tuple[Fault, ...] = ()) -> Estimate:
    """Run the self-commissioning routine on a drive's plant and return what it measured.

    Parameters
    ----------
    drive : Drive
        The plant (the true motor).
    nominal : Drive, optional
        The data the routine is configured from (test currents, timing, gains; a motor file's values, possibly
        wrong); default the plant's own. The results never use them, except the inverter's ``R_on`` and the shape
        of the back-EMF that :attr:`Estimate.drive` keeps.
    control : Commission, optional
        The routine's settings.
    speed : float, optional
        A dynamometer holding the rotor at this speed (rad/s) instead of the free rotor (to show ROTOR_MOVING).
    load_torque : float
        Load on the free rotor (N m).
    faults : tuple of Fault
        Faults of the plant during the routine (an open phase: NO_CURRENT).

    Returns
    -------
    Estimate
    """
    nominal = drive if nominal is None else nominal
    control = Commission() if control is None else control
    t_run = 1.05 * control.duration(nominal)
    t0 = time.perf_counter()
    r = simulate(drive, control, Scenario(duration=t_run, speed=speed, load_torque=load_torque, trace_every=64,
                                                  faults=faults),
                 estimate=nominal)
    wall = time.perf_counter() - t0
    groups = load_core().groups
    names = {v: k.removeprefix("BC_COMM_") for k, v in groups["commission_status"].items()}
    code = int(r["status"][-1])
    status = "UNFINISHED" if code == 0 else names.get(code, str(code))
    done = r["phase"] >= groups["commission_phase"]["BC_COMM_PH_DONE"]
    t_test = float(r["t"][done][0]) if done.any() else t_run
    return Estimate(status=status, R=float(r["R"][-1]), L=float(r["L"][-1]), psi_f=float(r["psi"][-1]),
                    t_test=t_test, wall_time=wall, nominal=nominal)

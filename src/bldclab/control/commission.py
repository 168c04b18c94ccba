"""Motor self-commissioning (``core/ctrl/include/bldc/bc_commission.h``).

R, L and the PM flux linkage measured by the controller; :func:`bldclab.analysis.commission.commission` runs it and
builds the estimated drive.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from .._core import Core, CParams
from ..errors import BldclabError
from ..model.analytic import i_sN, r_total
from ..model.design import pi_gains
from ..model.motor import Drive
from .base import Control, check_number
from .sine import fundamental_k1

__all__ = ["Commission"]


@dataclass(frozen=True)
class Commission(Control):
    """Self-commissioning: DC injection at two currents (R), voltage pulses (L), an I/f spin (flux linkage).

    The drive given to :meth:`c_record` is the controller's *nominal* data (a motor file's values, which may be
    wrong): they set only the test's currents, timing and PI gains, never the results. The phases and the statuses
    are in ``bc_commission.h`` and ``docs/sensorless-sine.md``.

    Parameters
    ----------
    test_current : float, optional
        DC test current (A) of the R and L tests; default ``0.5 I_s,N``.
    spin_speed : float, optional
        Mechanical speed of the I/f spin (rad/s); default ``0.3 Omega_N`` (the rated speed, a nameplate value).
    spin_current : float, optional
        Current of the spin (A); default the test current.
    pulse_samples : int
        Samples per inductance pulse at most. A pulse moves the current by ``pulse_current`` times the test current;
        its voltage is ``pulse_current i_test L / (n T_s)`` with ``n`` samples, ``n = pulse_samples`` unless that
        voltage would be below ``pulse_margin`` times the dead time's voltage error ``(V_dc + 2 V_f) t_dead f_pwm``:
        then the pulses are shorter (and higher) until it is not, down to one sample.
    pulse_current : float
        The pulses' current step, a fraction of the test current in (0, 1] (-): the current swings between
        ``i_test / 2`` (the held point) and ``(1/2 + pulse_current) i_test`` (the test current itself at the
        default 0.5, the range the R test has run). A larger step needs fewer pulses for the same precision against
        the current's noise (L's standard error falls as ``1 / (step sqrt(pairs))``).
    pulse_margin : float
        Smallest ratio of the pulse voltage to the dead time's voltage error (-).
    pulses : int
        Pulse pairs (+, -) at least.
    max_pulses : int
        Pulse pairs at most (``pulses`` .. 1000): while L's relative standard error from the current's noise
        (measured with the legs off before the tests) is above ``tol_noise``, the routine adds a pair; after
        ``max_pulses`` it ends with the status ``NOISY``.
    tol_noise : float
        Largest relative standard error of L from the current's noise (-); 0.5 % by default (1 % before the pulses
        of half the test current: the same time at 1 % noise of ``2 I_N``, half the error).
    offset_time : float
        Time (s) the routine reads the current sensors with the legs off, before the tests: their means are the
        offsets it takes off every later sample, their spread the noise.
    tol_move, tol_follow : float
        Thresholds of the ROTOR_MOVING and NOT_FOLLOWING statuses (-).
    """

    test_current: float | None = None
    spin_speed: float | None = None
    spin_current: float | None = None
    pulse_samples: int = 10
    pulse_current: float = 0.5
    pulse_margin: float = 5.0
    pulses: int = 8
    max_pulses: int = 500
    tol_noise: float = 0.005
    offset_time: float = 0.02
    tol_move: float = 0.05
    tol_follow: float = 0.3
    c_name: ClassVar[str] = "commission"
    ref_meaning: ClassVar[str] = "unused"

    def __post_init__(self) -> None:
        for name in ("test_current", "spin_speed", "spin_current"):
            if getattr(self, name) is not None:
                check_number(name, getattr(self, name))
        for name in ("pulse_samples", "pulses", "max_pulses"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 1000:
                raise BldclabError(f"control.{name}", f"must be an integer in [1, 1000], got {v!r}")
        if self.max_pulses < self.pulses:
            raise BldclabError("control.max_pulses", f"must be >= pulses = {self.pulses}, got {self.max_pulses}")
        check_number("pulse_current", self.pulse_current)
        if not self.pulse_current <= 1.0:
            raise BldclabError("control.pulse_current", f"must be in (0, 1] (a fraction of the test current), got "
                               f"{self.pulse_current!r}")
        check_number("pulse_margin", self.pulse_margin)
        check_number("tol_move", self.tol_move)
        check_number("tol_follow", self.tol_follow)
        check_number("tol_noise", self.tol_noise)
        check_number("offset_time", self.offset_time)

    def settings(self, drive: Drive) -> dict[str, float]:
        """Return the routine's settings for a drive's nominal data (currents A, times s, speeds rad/s, V).

        Parameters
        ----------
        drive : Drive
            The nominal data.
        """
        m, inv, J = drive.motor, drive.inverter, drive.mechanics.J
        ts = 0.5 / inv.f_pwm
        k1 = fundamental_k1(drive)
        i_t = 0.5 * i_sN(drive) if self.test_current is None else float(self.test_current)
        i_if = i_t if self.spin_current is None else float(self.spin_current)
        w_n = math.sqrt(m.p * 1.5 * k1 * i_t / J)  # the rotor's swing about the test current (rad/s)
        w_spin = m.p * (0.3 * m.Omega_nominal if self.spin_speed is None else float(self.spin_speed))
        w_nif = math.sqrt(m.p * 1.5 * k1 * i_if / J)
        tau_el = m.L / r_total(drive)
        swing = 2 * math.pi / w_n
        # the L pulses: a current step of pulse_current i_t in pulse_len samples, the voltage at least pulse_margin
        # times the dead time's error (shorter, higher pulses where it would not be)
        v_dt = (inv.V_dc + 2.0 * inv.V_f) * inv.t_dead * inv.f_pwm
        flux_step = self.pulse_current * i_t * m.L  # V s of each pulse
        n_len = self.pulse_samples
        if v_dt > 0.0:
            n_len = max(1, min(n_len, math.floor(flux_step / (self.pulse_margin * v_dt * ts))))
        return {
            "ts": ts, "i_test": i_t, "i_if": i_if, "t_offset": self.offset_time,
            "t_ramp": 3 * swing, "t_settle": 5 * tau_el + 0.01 + 2 * swing, "t_window": max(0.05, 2 * swing),
            "v_pulse": flux_step / (n_len * ts), "pulse_len": n_len,
            "if_accel": min(m.p * 0.5 * 1.5 * k1 * i_if / J, 0.02 * w_spin * w_nif), "w_spin": w_spin,
            "t_spin": max(10 * 2 * math.pi / w_spin, 5 * 2 * math.pi / w_nif), "psi_min": 0.25 * k1 / m.p,
            # i_q = -k u_q brakes the swing at the rate 1.5 p^2 psi^2 k / J: made w_n (near critical damping)
            "k_damp": w_n * J / (1.5 * m.p**2 * (k1 / m.p) ** 2),
        }

    def duration(self, drive: Drive) -> float:
        """Return the routine's length for a drive's nominal data (s), with ``max_pulses`` pulse pairs."""
        st = self.settings(drive)
        return (st["t_offset"] + 2 * st["t_ramp"] + st["t_settle"] + st["t_window"] + st["t_settle"] + st["t_window"]
                + (2 * self.max_pulses * st["pulse_len"] + 2) * st["ts"] + st["t_settle"]
                + st["t_ramp"] + st["w_spin"] / st["if_accel"] + st["t_settle"] + st["t_spin"])

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        st = self.settings(drive)
        i_max = 2.0 * drive.motor.I_N
        for name in ("i_test", "i_if"):
            if st[name] >= i_max:
                raise BldclabError(f"control.{'test_current' if name == 'i_test' else 'spin_current'}",
                                   f"must be below the trip 2 I_N = {i_max:.4g} A, got {st[name]:.4g} A")
        bw = 2 * math.pi * min(200.0, drive.inverter.f_pwm / 50.0)
        kp, ki = pi_gains(max(r_total(drive), bw * drive.motor.L / 10), drive.motor.L, bw / (2 * math.pi), 90.0)
        rec = core.filled(
            "bc_commission_params", kp=kp, ki=ki, n_pulse=self.pulses, pulse_len=int(st["pulse_len"]),
            n_pulse_max=self.max_pulses, tol_noise=self.tol_noise, tol_move=self.tol_move, tol_follow=self.tol_follow,
            i_max=i_max, v_max=2.0 * drive.inverter.V_dc,
            t_dead=drive.inverter.t_dead, v_diode=drive.inverter.V_f,
            # the current sensors' full scale (firmware knows its ADC's range): a reading at it ends CLIPPED
            i_fs=drive.sensors.current_full_scale if math.isfinite(drive.sensors.current_full_scale) else 0.0,
            **{k: st[k] for k in ("ts", "i_test", "t_ramp", "t_settle", "t_window", "v_pulse", "i_if", "if_accel",
                                  "w_spin", "t_spin", "psi_min", "k_damp", "t_offset")})
        return CParams(rec, [])

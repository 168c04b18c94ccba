"""Paper 2's torque controller and its two comparison methods (``core/ctrl/include/bldc/bc_lu.h``).

H. Lu, L. Zhang, W. Qu, *A New Torque Control Method for Torque Ripple Minimization of BLDC Motors With Un-Ideal
Back EMF*, IEEE Trans. Power Electron. 2008. Two-phase conduction with bipolar chopping; the duties ``D_n``
(normal conduction), ``D_c`` (commutation) and ``D_o`` (the outgoing phase slowed when ``D_c`` saturates) are
computed from the back-EMF shape functions, the measured DC bus and the torque estimated from the measured
currents. Theory, conventions and results: ``docs/theory-paper2.md``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np

from .._core import Core, CParams
from ..errors import BldclabError
from ..model.analytic import r_total
from ..model.design import max_bandwidth, pi_gains
from ..model.emf import TWO_PI
from ..model.motor import Drive
from .base import Control, check_number
from .hall import check_hall_options, hall_record, normalize_table

__all__ = ["Lu"]

_METHOD = {"lu": "BC_LU_TORQUE", "lu-no-do": "BC_LU_NO_DO", "rect": "BC_LU_RECT"}  # C constants (bldclab._core)

#: ``rect``'s current-loop bandwidth when the drive allows it (Hz).
DEFAULT_BANDWIDTH_HZ = 1000.0

#: Meaning of the controller's diagnostic channels (``SimResult`` signal names).
DIAG = ("mode", "duty", "tau_est", "tau_pred", "theta_est", "omega_est", "i_off", "sector")


@dataclass(frozen=True)
class Lu(Control):
    """Paper 2's torque control (``"lu"``), without ``D_o`` (``"lu-no-do"``), or rectangular current (``"rect"``).

    The reference (``Scenario.ref``) is the torque in N m; a negative torque swaps the two conducting phases. The
    controller's diagnostics appear in the result as ``mode`` (-1 safe, 0 normal conduction, 1 commutation with
    ``D_c``, 2 ``D_o`` mode, 3 the mean law in discontinuous conduction), ``duty`` (the duty computed), ``tau_est``
    (torque from the measured currents and the shapes, N m), ``tau_pred`` (its model's torque at the next sample,
    N m), ``theta_est`` (Hall-interpolated electrical angle, rad), ``omega_est`` (electrical speed, rad/s),
    ``i_off`` (current of the phase whose leg is off, A: the outgoing current during a commutation) and ``sector``.

    Parameters
    ----------
    method : {"lu", "lu-no-do", "rect"}
        ``lu``: paper 2's method, ``D_n`` / ``D_c`` / ``D_o``; ``lu-no-do``: the same without the ``D_o`` mode
        (paper 2's "torque control neglecting finite dc bus supply voltage", its Figs 11 and 14); ``rect``:
        conventional rectangular current control with the same commutation and bipolar chopping, a PI (no back-EMF
        feed-forward) holding the pair current at ``|T_ref| / (2 k_phi)`` (its Figs 10 and 13).
    delay : int
        Samples between computing and applying an output, 0 or 1; :func:`bldclab.simulate` sets it from
        ``Scenario.delay``. With 1 the laws start from the state predicted for the next sample under the output
        already in force.
    model_R : bool
        Include the winding resistance ``R + R_on`` in the one-step models (the paper neglects it: ``False``).
    switching_order : bool
        Follow the order of the off and on parts of each centre-aligned half period in the one-step model, so that
        a pair phase at zero current (the incoming phase at the start of a commutation, discontinuous conduction)
        stays open in the off part, and solve the laws on that model (``False``: the paper's averaged models only).
    mean_law : bool
        With ``switching_order``: where the current stops within the PWM period (discontinuous conduction, light
        load), choose the duties so that the model's *mean* torque over the PWM period is the reference instead of
        the torque at the next sample (whose mean is then up to 2.4 times the reference on ``lu-4kw``, see
        ``docs/theory-paper2.md``). ``False``: the end-value laws everywhere, as before.
    shape_points : int
        Points per shape table handed to the controller, uniform over the phase's local angle (a table shape on
        this grid is reproduced exactly).
    i_max : float, optional
        Over-current trip (A); default ``3 I_N`` (bipolar chopping at 10 kHz has a large current ripple).
    i_zero : float, optional
        An outgoing current at or below this is zero: the commutation is over (A); default ``0.01 I_N``.
    bandwidth_hz : float, optional
        ``rect``: crossover of the PI design for the line ``(2 (R + R_on), 2 L)`` with the loop delay
        ``(delay + 1/2) T_s`` (:func:`bldclab.model.design.pi_gains`). Default: 1 kHz where a PI can give the margin
        there; where the drive's PWM makes the delay too long for that, the highest bandwidth at which the PI keeps
        its zero a decade below the crossover (:func:`bldclab.model.design.max_bandwidth`; 745 Hz for ``servo-2k2``:
        51 mH at 8 kHz PWM). A bandwidth given here is used as it is (and refused if a PI cannot reach it).
    phase_margin_deg : float
        ``rect``: phase margin of that design.
    kp, ki : float, optional
        ``rect``: PI gains (V/A, V/(A s)) overriding the design.
    omega_min : float, optional
        Slowest speed the Hall estimate reports (electrical rad/s); default ``0.01 p Omega_0``.
    theta_offset : float
        Hall angle correction (electrical rad).
    adapt_L : float
        Inductance adaptation gain in [0, 1]; 0 (default) keeps the inductance of the drive description. Where the
        current stops within the PWM period the laws are feed-forward and the mean torque is ``T_ref L_est / L``
        (``docs/theory-paper2.md``, 5.2); with ``adapt_L > 0`` the controller fits its inductance to the measured
        rise of each pulse that starts from zero current (``core/ctrl/include/bldc/bc_lu.h``). 0.05 converges
        within about 100 PWM periods of discontinuous conduction.
    hall_angle : {"interp", "pll"}
        Hall angle estimator: ``interp`` is paper 1's (46), ``pll`` a tracking loop on the edges
        (``core/ctrl/include/bldc/bc_hall.h``) that averages the edge errors of misplaced sensors.
    pll_edges : float
        Time constant of the tracking loop in Hall edges (1 .. 1000).
    hall_table : sequence of float, optional
        Calibrated Hall edge angles (rad, electrical): 6 (both directions) or 12 (forward, then backward), e.g.
        from :func:`bldclab.sim.hallcal.calibrate`; used for the angle, the speed and the commutation instant (the
        pair changes at the nominal sector boundaries, as six-step's with ``advance``; ``sector`` is the sector
        commanded). ``None``: the nominal edges ``pi/6 + j pi/3``, the pair changes with the Hall code.
    """

    method: Literal["lu", "lu-no-do", "rect"] = "lu"
    delay: int = 1
    model_R: bool = True
    switching_order: bool = True
    mean_law: bool = True
    shape_points: int = 360
    i_max: float | None = None
    i_zero: float | None = None
    bandwidth_hz: float | None = None
    phase_margin_deg: float = 60.0
    kp: float | None = None
    ki: float | None = None
    omega_min: float | None = None
    theta_offset: float = 0.0
    adapt_L: float = 0.0
    hall_angle: Literal["interp", "pll"] = "interp"
    pll_edges: float = 3.0
    hall_table: tuple[float, ...] | None = None
    c_name: ClassVar[str] = "lu"
    ref_meaning: ClassVar[str] = "torque, N m"

    def __post_init__(self) -> None:
        if self.method not in _METHOD:
            raise BldclabError("control.method", f"must be one of {', '.join(_METHOD)}, got {self.method!r}")
        if isinstance(self.delay, bool) or self.delay not in (0, 1):
            raise BldclabError("control.delay", f"must be 0 or 1 sample, got {self.delay!r}")
        for name in ("model_R", "switching_order", "mean_law"):
            if not isinstance(getattr(self, name), bool):
                raise BldclabError(f"control.{name}", f"must be True or False, got {getattr(self, name)!r}")
        if isinstance(self.shape_points, bool) or not isinstance(self.shape_points, int) or self.shape_points < 12:
            raise BldclabError("control.shape_points", f"must be an integer >= 12, got {self.shape_points!r}")
        check_number("phase_margin_deg", self.phase_margin_deg)
        for name in ("bandwidth_hz", "i_max", "omega_min"):
            check_number(name, getattr(self, name), allow_none=True)
        for name in ("i_zero", "kp", "ki"):
            check_number(name, getattr(self, name), allow_zero=True, allow_none=True)
        if isinstance(self.theta_offset, bool) or not isinstance(self.theta_offset, int | float) or not math.isfinite(
                self.theta_offset):
            raise BldclabError("control.theta_offset", f"must be a finite number, got {self.theta_offset!r}")
        a = self.adapt_L
        if isinstance(a, bool) or not isinstance(a, int | float) or not 0.0 <= a <= 1.0:
            raise BldclabError("control.adapt_L", f"must be a number in [0, 1], got {a!r}")
        check_hall_options(self.pll_edges, self.hall_angle)
        object.__setattr__(self, "hall_table", normalize_table(self.hall_table))

    def gains(self, drive: Drive) -> tuple[float, float]:
        """Return ``rect``'s PI gains ``(k_p, k_i)`` of the pair-current loop (V/A, V/(A s)).

        Parameters
        ----------
        drive : Drive
            Its ``R + R_on``, ``L`` and ``f_pwm`` give the line plant ``exp(-s (delay + 1/2) T_s) / (2 R + s 2 L)``.

        Returns
        -------
        tuple of float
            The given gains, else :func:`bldclab.model.design.pi_gains` at :meth:`bandwidth` and ``phase_margin_deg``.
        """
        ts = 0.5 / drive.inverter.f_pwm
        kp, ki = pi_gains(2.0 * r_total(drive), 2.0 * drive.motor.L, self.bandwidth(drive), self.phase_margin_deg,
                          delay=(self.delay + 0.5) * ts)
        return (kp if self.kp is None else float(self.kp)), (ki if self.ki is None else float(self.ki))

    def bandwidth(self, drive: Drive) -> float:
        """Return ``rect``'s current-loop bandwidth (Hz): ``bandwidth_hz`` if given, else the default.

        The default is :data:`DEFAULT_BANDWIDTH_HZ` if :func:`bldclab.model.design.pi_gains` can give
        ``phase_margin_deg``
        there for the line ``(2 (R + R_on), 2 L)`` with the loop delay ``(delay + 1/2) T_s``, else
        :func:`bldclab.model.design.max_bandwidth` of that loop (lower: the delay of a slow PWM takes the phase).

        Parameters
        ----------
        drive : Drive
            Its ``R + R_on``, ``L`` and ``f_pwm``.

        Returns
        -------
        float
            Bandwidth (Hz).
        """
        if self.bandwidth_hz is not None:
            return float(self.bandwidth_hz)
        delay = (self.delay + 0.5) * 0.5 / drive.inverter.f_pwm
        r, ell = 2.0 * r_total(drive), 2.0 * drive.motor.L
        try:
            pi_gains(r, ell, DEFAULT_BANDWIDTH_HZ, self.phase_margin_deg, delay=delay)
        except BldclabError:
            return min(DEFAULT_BANDWIDTH_HZ, max_bandwidth(r, ell, self.phase_margin_deg, delay))
        return DEFAULT_BANDWIDTH_HZ

    def shape_tables(self, drive: Drive) -> np.ndarray:
        """Return the shape tables the controller reads: ``f_x`` at ``2 pi j / n`` of phase x's local angle.

        Parameters
        ----------
        drive : Drive
            Its ``motor.emf`` shapes (V s/rad).

        Returns
        -------
        ndarray, shape (3, shape_points), float32
            ``f_a, f_b, f_c`` in V s/rad (the controller's single precision).
        """
        n = self.shape_points
        theta = TWO_PI * np.arange(n) / n
        return np.ascontiguousarray(np.stack([np.asarray(s(theta), dtype=float) for s in drive.motor.emf.shapes]),
                                    dtype=np.float32)

    def with_delay(self, delay: int) -> Control:  # noqa: D102 - Control.with_delay
        return self if delay == self.delay else dataclasses.replace(self, delay=delay)

    def c_record(self, drive: Drive, core: Core, n_samples: int) -> CParams:  # noqa: D102
        m, inv = drive.motor, drive.inverter
        tables = self.shape_tables(drive)
        kp, ki = self.gains(drive) if self.method == "rect" else (0.0, 0.0)
        rec = core.filled(
            "bc_lu_params",
            f=[tables.ctypes.data + x * tables.strides[0] for x in range(3)],
            n=tables.shape[1],
            p=m.p,
            method=core.const(_METHOD[self.method]),
            delay=self.delay,
            order=(2 if self.mean_law else 1) if self.switching_order else 0,
            L=m.L,
            R=r_total(drive) if self.model_R else 0.0,
            ts=0.5 / inv.f_pwm,
            i_max=3.0 * m.I_N if self.i_max is None else self.i_max,
            i_zero=0.01 * m.I_N if self.i_zero is None else self.i_zero,
            v_max=2.0 * inv.V_dc,
            k_phi=m.k_phi,
            kp=kp,
            ki=ki,
            f_tick=drive.sensors.f_tick,
            omega_min=0.01 * m.p * drive.Omega_0 if self.omega_min is None else self.omega_min,
            theta_offset=self.theta_offset,
            l_adapt=float(self.adapt_L),
            **hall_record(core, self.hall_angle == "pll", self.pll_edges, self.hall_table),
        )
        return CParams(rec, [tables])

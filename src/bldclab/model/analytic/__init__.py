"""Paper 1's closed forms: torque, ripple, base speed and efficiency of a PM BLDC drive, for any motor.

Bertoluzzo, Buja, Keshri, Menis, *Sinusoidal vs. square-wave current supply of PM BLDC drives: a convenience
analysis* (IEEE, 2015). Every function names the equation it implements, numbered as in the paper. The theory,
the conventions and the places where the printed text is garbled are in ``docs/theory-paper1.md``.

Premises of the closed forms (paper section II.B): ideal 120-degree trapezoidal back-EMF of flat top
``E = k_phi Omega``, equal peak voltage (the DC bus ``V_N``, here ``drive.inverter.V_dc``) and equal rms
current for both supplies (``I_s,N = 2/sqrt(3) I_N``), phase resistance neglected. The R-aware base speeds
(:func:`omega_sB_numeric_pu`, :func:`omega_qB_numeric_pu`) drop the last premise and are computed numerically
from the drive's own back-EMF shapes.

Per-unit bases: speed ``Omega_0 = V_dc / (2 k_phi)`` (2), torque ``T_N = 2 k_phi I_N`` (6). The per-unit
functions take the per-unit speed ``omega_pu`` (scalar or array) and the motor-specific parameter
``theta_m`` (22) and are vectorised; a scalar input gives a ``float``, an array input an array of its shape.

One submodule per section of the paper, every public name re-exported here (``analytic.t_s_pu``):
:mod:`~bldclab.model.analytic.bases` (II: bases and ratings), :mod:`~bldclab.model.analytic.sine` (III: sinusoidal
supply), :mod:`~bldclab.model.analytic.square` (IV.A: real square-wave supply),
:mod:`~bldclab.model.analytic.speed_range` (both supplies over the whole speed range),
:mod:`~bldclab.model.analytic.blac` (IV.B: the equivalent BLAC motor), :mod:`~bldclab.model.analytic.efficiency`
(IV.C), :mod:`~bldclab.model.analytic.numeric` (R-aware numeric base speeds),
:mod:`~bldclab.model.analytic.premises` (where the closed forms apply) and :mod:`~bldclab.model.analytic.table`
(Table I and its text, the characteristic).
"""

from __future__ import annotations

from ._common import SQRT3
from .bases import e_N, i_sN, omega_0, omega_N, r_total, t_N
from .blac import T_BLAC_N_PU, omega_blac_B_pu, t_blac_pu
from .efficiency import (
    eta_34,
    eta_q,
    eta_ratio,
    eta_ratio_coefficients,
    eta_s,
    p_lCu_consistent_pu,
    p_lCu_pu,
    p_q_m_pu,
    p_R_pu,
    p_s_m_pu,
)
from .numeric import omega_qB_numeric_pu, omega_sB_numeric_pu
from .premises import (
    COMMUTATION_PERIODS_MIN,
    R_DROP_MAX,
    SHAPE_DEVIATION_MAX,
    SINUSOIDAL_THD_MAX,
    VDC_MISMATCH_MAX,
    applicability,
    commutation_periods,
    commutation_premise,
    harmonic_ratio,
    shape_applies,
    shape_deviation,
    sine_torque_pu,
)
from .sine import (
    T_SN_PU,
    TR_SN_PU,
    condition_18,
    e_1,
    i_s_sat,
    omega_sB_pu,
    p_sN,
    t_s_sat,
    t_s_sat_pu,
    t_sN,
    t_sN_pu,
    theta_m,
    tr_s_sat_pu,
    tr_sN,
    tr_sN_pu,
    v_ab_17,
    v_ab_peak,
)
from .speed_range import (
    REGION_Q_HIGH,
    REGION_Q_LOW,
    REGION_Q_SAT,
    REGION_S_BASE,
    REGION_S_SAT,
    REGION_STOP,
    region_q,
    region_s,
    t_q_pu,
    t_s_pu,
    tr_q_pu,
    tr_s_pu,
)
from .square import omega_qB_pu, t_q_high_pu, t_q_low_pu, t_q_sat_pu, t_qB_pu, tr_q_high_pu, tr_q_low_pu, tr_q_sat_pu
from .table import CHARACTERISTIC_COLUMNS, TABLE1_ROWS, Table1, characteristic, table1, table1_text

__all__ = [
    "CHARACTERISTIC_COLUMNS",
    "COMMUTATION_PERIODS_MIN",
    "REGION_Q_HIGH",
    "REGION_Q_LOW",
    "REGION_Q_SAT",
    "REGION_STOP",
    "REGION_S_BASE",
    "REGION_S_SAT",
    "R_DROP_MAX",
    "SHAPE_DEVIATION_MAX",
    "SINUSOIDAL_THD_MAX",
    "SQRT3",
    "TABLE1_ROWS",
    "TR_SN_PU",
    "T_BLAC_N_PU",
    "T_SN_PU",
    "VDC_MISMATCH_MAX",
    "Table1",
    "applicability",
    "characteristic",
    "commutation_periods",
    "commutation_premise",
    "condition_18",
    "e_1",
    "e_N",
    "eta_34",
    "eta_q",
    "eta_ratio",
    "eta_ratio_coefficients",
    "eta_s",
    "harmonic_ratio",
    "i_sN",
    "i_s_sat",
    "omega_0",
    "omega_N",
    "omega_blac_B_pu",
    "omega_qB_numeric_pu",
    "omega_qB_pu",
    "omega_sB_numeric_pu",
    "omega_sB_pu",
    "p_R_pu",
    "p_lCu_consistent_pu",
    "p_lCu_pu",
    "p_q_m_pu",
    "p_sN",
    "p_s_m_pu",
    "r_total",
    "region_q",
    "region_s",
    "shape_applies",
    "shape_deviation",
    "sine_torque_pu",
    "t_N",
    "t_blac_pu",
    "t_qB_pu",
    "t_q_high_pu",
    "t_q_low_pu",
    "t_q_pu",
    "t_q_sat_pu",
    "t_sN",
    "t_sN_pu",
    "t_s_pu",
    "t_s_sat",
    "t_s_sat_pu",
    "table1",
    "table1_text",
    "theta_m",
    "tr_q_high_pu",
    "tr_q_low_pu",
    "tr_q_pu",
    "tr_q_sat_pu",
    "tr_sN",
    "tr_sN_pu",
    "tr_s_pu",
    "tr_s_sat_pu",
    "v_ab_17",
    "v_ab_peak",
]

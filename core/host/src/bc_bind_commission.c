/* bc_bind_commission.c - binding provider of the self-commissioning routine (bc_commission.h). */
#include "bldc/bc_bind.h"
#include "bldc/bc_commission.h"

#define F BC_BIND_FIELD

static const bc_field_desc COMM_FIELDS[] = {
    F(bc_commission_params, ts, "f4"),        F(bc_commission_params, kp, "f4"),
    F(bc_commission_params, ki, "f4"),        F(bc_commission_params, i_test, "f4"),
    F(bc_commission_params, t_ramp, "f4"),    F(bc_commission_params, t_settle, "f4"),
    F(bc_commission_params, t_window, "f4"),  F(bc_commission_params, v_pulse, "f4"),
    F(bc_commission_params, n_pulse, "i4"),   F(bc_commission_params, pulse_len, "i4"),
    F(bc_commission_params, n_pulse_max, "i4"), F(bc_commission_params, tol_noise, "f4"),
    F(bc_commission_params, t_offset, "f4"),
    F(bc_commission_params, i_if, "f4"),      F(bc_commission_params, if_accel, "f4"),
    F(bc_commission_params, w_spin, "f4"),    F(bc_commission_params, t_spin, "f4"),
    F(bc_commission_params, psi_min, "f4"),   F(bc_commission_params, tol_move, "f4"),
    F(bc_commission_params, tol_follow, "f4"), F(bc_commission_params, k_damp, "f4"),
    F(bc_commission_params, i_max, "f4"),
    F(bc_commission_params, v_max, "f4"),     F(bc_commission_params, t_dead, "f4"),
    F(bc_commission_params, v_diode, "f4"),   F(bc_commission_params, i_fs, "f4"),
};
static const bc_struct_desc COMM_STRUCTS[] = {BC_BIND_STRUCT(bc_commission_params),
                                              BC_BIND_STRUCT(bc_commission_state)};
static int comm_init(const void *p, void *s) { return bc_commission_init(p, s); }
static void comm_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_commission_step(p, s, in, out);
}
static const bc_ctrl_info COMM_INFO = {"commission", "bc_commission_params", "bc_commission_state", comm_init,
                                       comm_step, {"phase", "R", "L", "psi", "i_d", "i_q", "phi", "status"}};
static const bc_const_desc COMM_CONSTS[] = {
    BC_BIND_CONST("commission_status", BC_COMM_RUNNING),
    BC_BIND_CONST("commission_status", BC_COMM_DONE),
    BC_BIND_CONST("commission_status", BC_COMM_ROTOR_MOVING),
    BC_BIND_CONST("commission_status", BC_COMM_NO_CURRENT),
    BC_BIND_CONST("commission_status", BC_COMM_SATURATED),
    BC_BIND_CONST("commission_status", BC_COMM_NOT_FOLLOWING),
    BC_BIND_CONST("commission_status", BC_COMM_FAULT),
    BC_BIND_CONST("commission_status", BC_COMM_NOISY),
    BC_BIND_CONST("commission_status", BC_COMM_CLIPPED),
    BC_BIND_CONST("commission_phase", BC_COMM_PH_OFFSET),
    BC_BIND_CONST("commission_phase", BC_COMM_PH_ALIGN),
    BC_BIND_CONST("commission_phase", BC_COMM_PH_R_HI),
    BC_BIND_CONST("commission_phase", BC_COMM_PH_R_LO),
    BC_BIND_CONST("commission_phase", BC_COMM_PH_L),
    BC_BIND_CONST("commission_phase", BC_COMM_PH_SPIN),
    BC_BIND_CONST("commission_phase", BC_COMM_PH_DONE),
};
const bc_bind_provider bc_bind_commission = {COMM_FIELDS, (int32_t)(sizeof COMM_FIELDS / sizeof COMM_FIELDS[0]),
                                             COMM_STRUCTS, 2, &COMM_INFO, COMM_CONSTS,
                                             (int32_t)(sizeof COMM_CONSTS / sizeof COMM_CONSTS[0])};

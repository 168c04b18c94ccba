/* bc_bind_bemf.c - binding provider of the sensorless six-step controller (bc_bemf.h): the members of its params,
 * its structs' sizes, its registry entry (name "bemf") and its enum values. */
#include "bldc/bc_bemf.h"
#include "bldc/bc_bind.h"

#define F BC_BIND_FIELD

static const bc_field_desc BEMF_FIELDS[] = {
    F(bc_bemf_params, method, "i4"),       F(bc_bemf_params, chop, "i4"),
    F(bc_bemf_params, delay, "i4"),        F(bc_bemf_params, blanking, "i4"),
    F(bc_bemf_params, ts, "f4"),           F(bc_bemf_params, f_tick, "f4"),
    F(bc_bemf_params, blank_angle, "f4"),  F(bc_bemf_params, blank_time, "f4"),
    F(bc_bemf_params, min_pulse, "f4"),    F(bc_bemf_params, n_samples, "i4"),
    F(bc_bemf_params, tau_filter, "f4"),   F(bc_bemf_params, t_comp, "f4"),
    F(bc_bemf_params, adv_angle, "f4"),    F(bc_bemf_params, adv_time, "f4"),
    F(bc_bemf_params, adv_demag, "f4"),    F(bc_bemf_params, adv_max, "f4"),
    F(bc_bemf_params, t60_gain, "f4"),     F(bc_bemf_params, int_limit, "f4"),
    F(bc_bemf_params, zc_timeout, "f4"),   F(bc_bemf_params, jump_max, "f4"),
    F(bc_bemf_params, miss_max, "i4"),     F(bc_bemf_params, omega_stall, "f4"),
    F(bc_bemf_params, align_time, "f4"),   F(bc_bemf_params, align_duty, "f4"),
    F(bc_bemf_params, ramp_w0, "f4"),      F(bc_bemf_params, ramp_w1, "f4"),
    F(bc_bemf_params, ramp_accel, "f4"),   F(bc_bemf_params, ramp_duty, "f4"),
    F(bc_bemf_params, ramp_vf, "f4"),      F(bc_bemf_params, ramp_tau, "f4"),
    F(bc_bemf_params, ramp_hold, "i4"),    F(bc_bemf_params, n_handover, "i4"),
    F(bc_bemf_params, duty_min, "f4"),     F(bc_bemf_params, duty_rate, "f4"),
    F(bc_bemf_params, ref_stop, "f4"),     F(bc_bemf_params, restart_wait, "f4"),
    F(bc_bemf_params, restart_max, "f4"),  F(bc_bemf_params, use_current, "i4"),
    F(bc_bemf_params, i_max, "f4"),        F(bc_bemf_params, i_limit, "f4"),
    F(bc_bemf_params, k_limit, "f4"),      F(bc_bemf_params, v_max, "f4"),
    F(bc_bemf_params, fast_demag, "i4"),   F(bc_bemf_params, fd_after, "f4"),
    F(bc_bemf_params, dlim_d0, "f4"),
    F(bc_bemf_params, dlim_vf, "f4"),      F(bc_bemf_params, dlim_tau, "f4"),
    F(bc_bemf_params, demag_max, "f4"),     F(bc_bemf_params, cmp_gate, "i4"),
    F(bc_bemf_params, cmp_blind, "i4"),
    F(bc_bemf_params, i_start, "f4"),      F(bc_bemf_params, d_diode, "f4"),
    F(bc_bemf_params, grid_gain, "f4"),    F(bc_bemf_params, brake_tau, "f4"),
    F(bc_bemf_params, brake_acc, "f4"),    F(bc_bemf_params, brake_q, "f4"),
};
static const bc_struct_desc BEMF_STRUCTS[] = {BC_BIND_STRUCT(bc_bemf_params), BC_BIND_STRUCT(bc_bemf_state)};
static int bemf_init(const void *p, void *s) { return bc_bemf_init(p, s); }
static void bemf_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out) { bc_bemf_step(p, s, in, out); }
static const bc_ctrl_info BEMF_INFO = {
    "bemf", "bc_bemf_params", "bc_bemf_state", bemf_init, bemf_step,
    {"state", "sector", "omega_e", "comm_error", "demag", "advance", "duty", "desync_reason"}};
static const bc_const_desc BEMF_CONSTS[] = {
    BC_BIND_CONST("bemf_method", BC_BEMF_COMPARATOR),   BC_BIND_CONST("bemf_method", BC_BEMF_ADC),
    BC_BIND_CONST("bemf_method", BC_BEMF_INTEGRATE),    BC_BIND_CONST("bemf_blanking", BC_BEMF_BLANK_FIXED),
    BC_BIND_CONST("bemf_blanking", BC_BEMF_BLANK_DEMAG), BC_BIND_CONST("bemf_state", BC_BEMF_STOP),
    BC_BIND_CONST("bemf_state", BC_BEMF_ALIGN),         BC_BIND_CONST("bemf_state", BC_BEMF_RAMP),
    BC_BIND_CONST("bemf_state", BC_BEMF_CLOSED),        BC_BIND_CONST("bemf_reason", BC_BEMF_REASON_NONE),
    BC_BIND_CONST("bemf_reason", BC_BEMF_REASON_TIMEOUT), BC_BIND_CONST("bemf_reason", BC_BEMF_REASON_HIDDEN),
    BC_BIND_CONST("bemf_reason", BC_BEMF_REASON_JUMP),  BC_BIND_CONST("bemf_reason", BC_BEMF_REASON_STALL),
    BC_BIND_CONST("bemf_reason", BC_BEMF_REASON_START),
};
const bc_bind_provider bc_bind_bemf = {BEMF_FIELDS, (int32_t)(sizeof BEMF_FIELDS / sizeof BEMF_FIELDS[0]),
                                       BEMF_STRUCTS, 2, &BEMF_INFO, BEMF_CONSTS,
                                       (int32_t)(sizeof BEMF_CONSTS / sizeof BEMF_CONSTS[0])};

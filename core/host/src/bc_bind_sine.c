/* bc_bind_sine.c - binding provider of the sinusoidal current supply (bc_sine.h): layouts, sizes, registry. */
#include "bldc/bc_bind.h"
#include "bldc/bc_sine.h"

#define F BC_BIND_FIELD

static const bc_field_desc SINE_FIELDS[] = {
    F(bc_sine_params, p, "i4"),
    F(bc_sine_params, R, "f4"),
    F(bc_sine_params, L, "f4"),
    F(bc_sine_params, k_phi, "f4"),
    F(bc_sine_params, k_1, "f4"),
    F(bc_sine_params, ts, "f4"),
    F(bc_sine_params, kp, "f4"),
    F(bc_sine_params, ki, "f4"),
    F(bc_sine_params, v_max, "f4"),
    F(bc_sine_params, i_s_max, "f4"),
    F(bc_sine_params, i_max, "f4"),
    F(bc_sine_params, speed_limit, "i4"),
    F(bc_sine_params, decouple, "i4"),
    F(bc_sine_params, advance, "f4"),
    F(bc_sine_params, limit, "i4"),
    F(bc_sine_params, overmod, "i4"),
    F(bc_sine_params, emf_ff, "i4"),
    F(bc_sine_params, emf_n, "i4"),
    F(bc_sine_params, emf_k, "ptr"),
    F(bc_sine_params, angle, "i4"),
    F(bc_sine_params, f_tick, "f4"),
    F(bc_sine_params, omega_min, "f4"),
    F(bc_sine_params, theta_offset, "f4"),
    F(bc_sine_params, hall_mode, "i4"),
    F(bc_sine_params, hall_pll_edges, "f4"),
    F(bc_sine_params, hall_table, "bc_hall_table"),
    F(bc_sine_params, omega_on, "f4"),
    F(bc_sine_params, omega_off, "f4"),
    F(bc_sine_params, six, "bc_sixstep_params"),
    F(bc_sine_params, flying_start, "i4"),
    F(bc_sine_params, speed_loop, "i4"),
    F(bc_sine_params, kp_w, "f4"),
    F(bc_sine_params, ki_w, "f4"),
    F(bc_sine_params, tau_max, "f4"),
    F(bc_sine_params, derate, "bc_derate_params"),
};
static const bc_struct_desc SINE_STRUCTS[] = {BC_BIND_STRUCT(bc_sine_params), BC_BIND_STRUCT(bc_sine_state)};
static int sine_init(const void *p, void *s) { return bc_sine_init(p, s); }
static void sine_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sine_step(p, s, in, out); }
static const bc_ctrl_info SINE_INFO = {"sine", "bc_sine_params", "bc_sine_state", sine_init, sine_step,
                                       {"i_d", "i_q", "i_q_ref", "v_d", "v_q", "theta", "omega_e", "mode"}};
static const bc_const_desc SINE_CONSTS[] = {
    BC_BIND_CONST("sine_angle", BC_SINE_ANGLE_HALL), BC_BIND_CONST("sine_angle", BC_SINE_ANGLE_ENCODER),
    BC_BIND_CONST("sine_limit", BC_SINE_LIMIT_HEX),  BC_BIND_CONST("sine_limit", BC_SINE_LIMIT_CIRCLE),
    BC_BIND_CONST("sine_mode", BC_SINE_MODE_START),  BC_BIND_CONST("sine_mode", BC_SINE_MODE_SINE),
};
const bc_bind_provider bc_bind_sine = {SINE_FIELDS, (int32_t)(sizeof SINE_FIELDS / sizeof SINE_FIELDS[0]),
                                       SINE_STRUCTS, 2, &SINE_INFO, SINE_CONSTS,
                                       (int32_t)(sizeof SINE_CONSTS / sizeof SINE_CONSTS[0])};

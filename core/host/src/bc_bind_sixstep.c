/* bc_bind_sixstep.c - binding provider of the real square-wave current controller (bc_sixstep.h): the members of
 * its params, its structs' sizes and its registry entry (name "sixstep"). */
#include "bldc/bc_bind.h"
#include "bldc/bc_sixstep.h"

#define F BC_BIND_FIELD

static const bc_field_desc SIXSTEP_FIELDS[] = {
    F(bc_sixstep_params, reg, "i4"),      F(bc_sixstep_params, chop, "i4"),
    F(bc_sixstep_params, ref_torque, "i4"), F(bc_sixstep_params, delay, "i4"),
    F(bc_sixstep_params, advance, "i4"),  F(bc_sixstep_params, timed, "i4"),
    F(bc_sixstep_params, adv_angle, "f4"), F(bc_sixstep_params, adv_time, "f4"),
    F(bc_sixstep_params, comm, "i4"),     F(bc_sixstep_params, emf_ff, "i4"),
    F(bc_sixstep_params, regen, "i4"),
    F(bc_sixstep_params, p, "i4"),        F(bc_sixstep_params, ts, "f4"),
    F(bc_sixstep_params, R, "f4"),        F(bc_sixstep_params, L, "f4"),
    F(bc_sixstep_params, k_e, "f4"),      F(bc_sixstep_params, kp, "f4"),
    F(bc_sixstep_params, ki, "f4"),       F(bc_sixstep_params, band, "f4"),
    F(bc_sixstep_params, i_max, "f4"),    F(bc_sixstep_params, v_max, "f4"),
    F(bc_sixstep_params, f_tick, "f4"),   F(bc_sixstep_params, omega_min, "f4"),
    F(bc_sixstep_params, theta_offset, "f4"),
    F(bc_sixstep_params, hall_mode, "i4"),
    F(bc_sixstep_params, hall_pll_edges, "f4"),
    F(bc_sixstep_params, hall_table, "bc_hall_table"),
    F(bc_sixstep_params, derate, "bc_derate_params"),
    F(bc_sixstep_params, open_frac, "f4"),
};
static const bc_struct_desc SIXSTEP_STRUCTS[] = {BC_BIND_STRUCT(bc_sixstep_params), BC_BIND_STRUCT(bc_sixstep_state)};
static int sixstep_init(const void *p, void *s) { return bc_sixstep_init(p, s); }
static void sixstep_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_sixstep_step(p, s, in, out);
}
static const bc_ctrl_info SIXSTEP_INFO = {
    "sixstep", "bc_sixstep_params", "bc_sixstep_state", sixstep_init, sixstep_step,
    {"sector", "i_reg", "i_ref", "duty", "omega_e", "incoming", "chop_leg", "i_out"}};
static const bc_const_desc SIXSTEP_CONSTS[] = {
    BC_BIND_CONST("sixstep_reg", BC_SIXSTEP_PI),        BC_BIND_CONST("sixstep_reg", BC_SIXSTEP_HYST),
    BC_BIND_CONST("sixstep_reg", BC_SIXSTEP_PRED),      BC_BIND_CONST("sixstep_reg", BC_SIXSTEP_DUTY),
    BC_BIND_CONST("sixstep_reg", BC_SIXSTEP_IDEAL),
    BC_BIND_CONST("sixstep_comm", BC_SIXSTEP_COMM_HALL), BC_BIND_CONST("sixstep_comm", BC_SIXSTEP_COMM_ENCODER),
    BC_BIND_CONST("sixstep_chop", BC_SIXSTEP_BIPOLAR),
    BC_BIND_CONST("sixstep_chop", BC_SIXSTEP_HIGH),     BC_BIND_CONST("sixstep_chop", BC_SIXSTEP_PWMPWM),
    BC_BIND_CONST("sixstep_chop", BC_SIXSTEP_SYNC),
};
const bc_bind_provider bc_bind_sixstep = {SIXSTEP_FIELDS, (int32_t)(sizeof SIXSTEP_FIELDS / sizeof SIXSTEP_FIELDS[0]),
                                          SIXSTEP_STRUCTS, 2, &SIXSTEP_INFO, SIXSTEP_CONSTS,
                                          (int32_t)(sizeof SIXSTEP_CONSTS / sizeof SIXSTEP_CONSTS[0])};

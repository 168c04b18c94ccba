/* bc_bind_lu.c - binding provider of paper 2's torque controller (bc_lu.h): the members of its params, its structs'
 * sizes and its registry entry (name "lu"; the method, LU / NO_DO / RECT, is a parameter). */
#include "bldc/bc_bind.h"
#include "bldc/bc_lu.h"

#define F BC_BIND_FIELD

static const bc_field_desc LU_FIELDS[] = {
    F(bc_lu_params, f, "ptr"),        F(bc_lu_params, n, "i4"),      F(bc_lu_params, p, "i4"),
    F(bc_lu_params, method, "i4"),    F(bc_lu_params, delay, "i4"),  F(bc_lu_params, order, "i4"),
    F(bc_lu_params, L, "f4"),         F(bc_lu_params, R, "f4"),      F(bc_lu_params, ts, "f4"),
    F(bc_lu_params, i_max, "f4"),     F(bc_lu_params, i_zero, "f4"), F(bc_lu_params, v_max, "f4"),
    F(bc_lu_params, k_phi, "f4"),     F(bc_lu_params, kp, "f4"),     F(bc_lu_params, ki, "f4"),
    F(bc_lu_params, f_tick, "f4"),    F(bc_lu_params, omega_min, "f4"), F(bc_lu_params, theta_offset, "f4"),
    F(bc_lu_params, l_adapt, "f4"),
    F(bc_lu_params, hall_mode, "i4"), F(bc_lu_params, hall_pll_edges, "f4"), F(bc_lu_params, hall_table, "bc_hall_table"),
};
static const bc_struct_desc LU_STRUCTS[] = {BC_BIND_STRUCT(bc_lu_params), BC_BIND_STRUCT(bc_lu_state)};
static int lu_init(const void *p, void *s) { return bc_lu_init(p, s); }
static void lu_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out) { bc_lu_step(p, s, in, out); }
static const bc_ctrl_info LU_INFO = {
    "lu", "bc_lu_params", "bc_lu_state", lu_init, lu_step,
    {"mode", "duty", "tau_est", "tau_pred", "theta_est", "omega_est", "i_off", "sector"}};
static const bc_const_desc LU_CONSTS[] = {
    BC_BIND_CONST("lu_method", BC_LU_TORQUE), BC_BIND_CONST("lu_method", BC_LU_NO_DO),
    BC_BIND_CONST("lu_method", BC_LU_RECT),
};
const bc_bind_provider bc_bind_lu = {LU_FIELDS, (int32_t)(sizeof LU_FIELDS / sizeof LU_FIELDS[0]), LU_STRUCTS, 2,
                                     &LU_INFO, LU_CONSTS, (int32_t)(sizeof LU_CONSTS / sizeof LU_CONSTS[0])};

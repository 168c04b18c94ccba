/* bc_bind_hallcal.c - binding provider of the Hall calibration (bc_hallcal.h) and of bc_hall's edge table and
 * modes (bc_hall.h), which the controllers' params embed. */
#include "bldc/bc_bind.h"
#include "bldc/bc_hallcal.h"

#define F BC_BIND_FIELD

static const bc_field_desc HALLCAL_FIELDS[] = {
    F(bc_hall_table, set, "i4"),
    F(bc_hall_table, fwd, "f4"),
    F(bc_hall_table, bwd, "f4"),
    F(bc_hallcal_params, method, "i4"),
    F(bc_hallcal_params, n_rev, "i4"),
    F(bc_hallcal_params, f_tick, "f4"),
    F(bc_hallcal_params, ts, "f4"),
    F(bc_hallcal_params, t_max, "f4"),
    F(bc_hallcal_params, speed_tol, "f4"),
    F(bc_hallcal_params, v_align, "f4"),
    F(bc_hallcal_params, v_emf, "f4"),
    F(bc_hallcal_params, omega_ol, "f4"),
    F(bc_hallcal_params, t_align, "f4"),
    F(bc_hallcal_params, lag_max, "f4"),
    F(bc_hallcal_params, i_max, "f4"),
    F(bc_hallcal_params, v_max, "f4"),
};
static const bc_struct_desc HALLCAL_STRUCTS[] = {BC_BIND_STRUCT(bc_hall_table), BC_BIND_STRUCT(bc_hallcal_params),
                                                 BC_BIND_STRUCT(bc_hallcal_state)};
static int hallcal_init(const void *p, void *s) { return bc_hallcal_init(p, s); }
static void hallcal_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_hallcal_step(p, s, in, out);
}
static const bc_ctrl_info HALLCAL_INFO = {
    "hallcal", "bc_hallcal_params", "bc_hallcal_state", hallcal_init, hallcal_step,
    {"edge0", "edge1", "edge2", "edge3", "edge4", "edge5", "cal_status", "cal_progress"}};
static const bc_const_desc HALLCAL_CONSTS[] = {
    BC_BIND_CONST("hall_mode", BC_HALL_INTERP),          BC_BIND_CONST("hall_mode", BC_HALL_PLL),
    BC_BIND_CONST("hallcal_method", BC_HALLCAL_SPEED),   BC_BIND_CONST("hallcal_method", BC_HALLCAL_OPENLOOP),
    BC_BIND_CONST("hallcal_flag", BC_HALLCAL_BUSY),      BC_BIND_CONST("hallcal_flag", BC_HALLCAL_DONE),
    BC_BIND_CONST("hallcal_flag", BC_HALLCAL_FAIL),      BC_BIND_CONST("hallcal_flag", BC_HALLCAL_E_INVALID),
    BC_BIND_CONST("hallcal_flag", BC_HALLCAL_E_ORDER),   BC_BIND_CONST("hallcal_flag", BC_HALLCAL_E_REVERSAL),
    BC_BIND_CONST("hallcal_flag", BC_HALLCAL_E_SPEED),   BC_BIND_CONST("hallcal_flag", BC_HALLCAL_E_FEW),
    BC_BIND_CONST("hallcal_flag", BC_HALLCAL_E_RANGE),   BC_BIND_CONST("hallcal_flag", BC_HALLCAL_E_INPUT),
};
const bc_bind_provider bc_bind_hallcal = {
    HALLCAL_FIELDS, (int32_t)(sizeof HALLCAL_FIELDS / sizeof HALLCAL_FIELDS[0]), HALLCAL_STRUCTS, 3, &HALLCAL_INFO,
    HALLCAL_CONSTS, (int32_t)(sizeof HALLCAL_CONSTS / sizeof HALLCAL_CONSTS[0])};

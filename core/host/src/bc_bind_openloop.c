/* bc_bind_openloop.c - binding provider of the open-loop drivers (bc_openloop.h): layouts, sizes, registry.
 * A controller's provider is the template for adding one: its params' members (complete), its structs' sizes,
 * two adapters, and a bc_ctrl_info; then one line in bc_bind.c's PROVIDERS. */
#include "bldc/bc_bind.h"
#include "bldc/bc_openloop.h"

static const bc_field_desc TABLE_FIELDS[] = {
    BC_BIND_FIELD(bc_table_params, cmd, "ptr"),
    BC_BIND_FIELD(bc_table_params, n, "i8"),
};
static const bc_struct_desc TABLE_STRUCTS[] = {BC_BIND_STRUCT(bc_table_params), BC_BIND_STRUCT(bc_table_state)};
static int table_init(const void *p, void *s) { return bc_table_init(p, s); }
static void table_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out) { bc_table_step(p, s, in, out); }
static const bc_ctrl_info TABLE_INFO = {"table", "bc_table_params", "bc_table_state", table_init, table_step,
                                        {"", "", "", "", "", "", "", ""}};
const bc_bind_provider bc_bind_openloop_table = {TABLE_FIELDS, 2, TABLE_STRUCTS, 2, &TABLE_INFO, 0, 0};

static const bc_field_desc SIXV_FIELDS[] = {
    BC_BIND_FIELD(bc_sixv_params, chop, "i4"),
};
static const bc_struct_desc SIXV_STRUCTS[] = {BC_BIND_STRUCT(bc_sixv_params), BC_BIND_STRUCT(bc_sixv_state)};
static int sixv_init(const void *p, void *s) { return bc_sixv_init(p, s); }
static void sixv_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sixv_step(p, s, in, out); }
static const bc_ctrl_info SIXV_INFO = {"sixv", "bc_sixv_params", "bc_sixv_state", sixv_init, sixv_step,
                                       {"sector", "duty", "", "", "", "", "", ""}};
static const bc_const_desc SIXV_CONSTS[] = {
    BC_BIND_CONST("sixv_chop", BC_SIXV_HIGH),    BC_BIND_CONST("sixv_chop", BC_SIXV_LOW),
    BC_BIND_CONST("sixv_chop", BC_SIXV_BIPOLAR), BC_BIND_CONST("sixv_chop", BC_SIXV_SYNC),
};
const bc_bind_provider bc_bind_openloop_sixv = {SIXV_FIELDS, 1, SIXV_STRUCTS, 2, &SIXV_INFO, SIXV_CONSTS, 4};

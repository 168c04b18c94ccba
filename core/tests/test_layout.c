/* test_layout.c - the binding's layout table describes every struct it lists completely: members in order,
 * inside the struct, not overlapping, and the gaps between them no larger than alignment padding; trace rows
 * are as many doubles as BC_TRACE_FIELDS lists; every registered controller initialises and steps. */
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_bind.h"
#include "bldc/bc_sim.h"

static uint32_t struct_size(const char *name)
{
    for (int32_t j = 0; j < bc_struct_count(); ++j) {
        if (strcmp(bc_struct_get(j)->name, name) == 0) return bc_struct_get(j)->size;
    }
    return 0u;
}

int main(void)
{
    /* structs the host fills completely must have no undescribed member */
    static const char *const complete[] = {"bc_fault", "bc_leg_cmd", "bc_emf_shape", "bc_plant_params", "bc_sensor_params", "bc_sense_params",
                                           "bc_ctrl", "bc_sim_config", "bc_sim_inputs", "bc_sim_metrics",
                                           "bc_ctrl_in", "bc_ctrl_out"};
    const char *names[64];
    size_t n_names = 0;
    for (size_t c = 0; c < sizeof complete / sizeof complete[0]; ++c) names[n_names++] = complete[c];
    for (int32_t j = 0; j < bc_ctrl_count() && n_names < 64; ++j) names[n_names++] = bc_ctrl_get(j)->params;
    for (size_t c = 0; c < n_names; ++c) {
        uint32_t size = struct_size(names[c]), end = 0u, covered = 0u;
        CHECK(size > 0u, "%s has a size entry", names[c]);
        for (int32_t j = 0; j < bc_layout_count(); ++j) {
            const bc_field_desc *f = bc_layout_get(j);
            if (strcmp(f->strct, names[c]) != 0) continue;
            CHECK(f->offset >= end, "%s.%s does not overlap the previous member", f->strct, f->field);
            CHECK(f->offset - end < 8u, "%s.%s: gap of %u bytes before it (a member missing?)", f->strct, f->field,
                  f->offset - end);
            end = f->offset + f->size;
            covered += f->size;
            CHECK(end <= size, "%s.%s inside the struct", f->strct, f->field);
        }
        CHECK(size - end < 8u, "%s: %u bytes undescribed at the end", names[c], size - end);
        CHECK(covered + 16u > size, "%s: %u of %u bytes described", names[c], covered, size);
    }
    CHECK(struct_size("bc_trace_row") == (uint32_t)bc_trace_count() * (uint32_t)sizeof(double), "trace row");
    CHECK(strcmp(bc_trace_name(0), "t") == 0 && bc_trace_name(bc_trace_count()) == 0, "trace names");
    /* every controller: init with zeroed params either succeeds or reports BC_ERR_PARAM, step keeps legs sane */
    for (int32_t j = 0; j < bc_ctrl_count(); ++j) {
        const bc_ctrl_info *ci = bc_ctrl_get(j);
        CHECK(struct_size(ci->params) > 0u && struct_size(ci->state) > 0u, "%s sizes", ci->name);
        static unsigned char pbuf[4096], sbuf[65536];
        memset(pbuf, 0, sizeof pbuf);
        memset(sbuf, 0, sizeof sbuf);
        CHECK(struct_size(ci->params) <= sizeof pbuf && struct_size(ci->state) <= sizeof sbuf, "buffers");
        if (ci->init(pbuf, sbuf) == BC_OK) {
            bc_ctrl_in in;
            memset(&in, 0, sizeof in);
            in.hall = 1u;
            in.v_dc = 48.0f;
            bc_ctrl_out out;
            ci->step(pbuf, sbuf, &in, &out);
            for (int x = 0; x < 3; ++x) {
                CHECK(out.leg[x].duty >= 0.0f && out.leg[x].duty <= 1.0f, "%s duty in [0, 1]", ci->name);
            }
        }
    }
    /* named constants: each has a group and a name, names are unique, flag bits are distinct single bits */
    int n_flag = 0;
    uint64_t bits = 0u;
    CHECK(bc_const_count() > 40, "constants listed: %d", (int)bc_const_count());
    CHECK(bc_const_get(-1) == 0 && bc_const_get(bc_const_count()) == 0, "constants out of range: null");
    for (int32_t j = 0; j < bc_const_count(); ++j) {
        const bc_const_desc *k = bc_const_get(j);
        CHECK(k != 0 && k->group && k->name && strncmp(k->name, "BC_", 3) == 0, "constant %d named", (int)j);
        for (int32_t q = 0; q < j; ++q) CHECK(strcmp(bc_const_get(q)->name, k->name) != 0, "%s listed once", k->name);
        if (strcmp(k->group, "flag") == 0) {
            ++n_flag;
            uint64_t v = (uint64_t)k->value;
            CHECK(v != 0u && (v & (v - 1u)) == 0u && !(bits & v), "%s is a bit of its own", k->name);
            bits |= v;
        }
    }
    CHECK(n_flag == 14 && bits == (BC_FLAG_SAFE | BC_FLAG_HALL_INVALID | BC_FLAG_OVERCURRENT | BC_FLAG_BAD_INPUT |
                                   BC_FLAG_SATURATED | BC_FLAG_DESYNC | BC_FLAG_ZC_TIMEOUT | BC_FLAG_ZC_HIDDEN |
                                   BC_FLAG_ZC_JUMP | BC_FLAG_STALL | BC_FLAG_START_FAIL | BC_FLAG_OPEN_LOOP |
                                   BC_FLAG_COMM_LATE | BC_FLAG_LOCK_LOST), "every controller flag listed");
    CHECK(bits < (1u << BC_SIM_NFLAG), "every flag bit counted by the runner (BC_SIM_NFLAG)");
    return bc_test_summary("test_layout");
}

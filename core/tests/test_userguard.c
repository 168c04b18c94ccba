/* test_userguard.c - the guard around a user's controller (bc_userguard.h): every output rule, the progress counts,
 * the end of a closed-loop run at the first bad sample (and the same run, unguarded, identical up to it), a write to
 * the const inputs, and the description tables of the user structs (complete, as test_layout checks the core's). */
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_bind.h"
#include "bldc/bc_openloop.h"
#include "bldc/bc_sim.h"
#include "bldc/bc_user.h"
#include "bldc/bc_userguard.h"
#include "fixtures.h"

static void good(bc_ctrl_out *o)
{
    memset(o, 0, sizeof *o);
    o->leg[0].mode = BC_LEG_HIGH;
    o->leg[0].duty = 0.5f;
    o->leg[1].mode = BC_LEG_LOW;
    o->leg[1].duty = 1.0f;
}

static void test_check(void)
{
    bc_ctrl_out o;
    int32_t j = -9;
    double v = 0.0;
    good(&o);
    CHECK(bc_user_check(&o, &j, &v) == 0, "a valid output passes");
    good(&o);
    o.leg[2].duty = 1.0000001f;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_DUTY && j == 2 && v > 1.0, "duty above 1: leg 2, %g", v);
    good(&o);
    o.leg[1].duty = -0.0f;
    CHECK(bc_user_check(&o, &j, &v) == 0, "duty -0 is in [0, 1]");
    good(&o);
    o.leg[1].duty = NAN;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_DUTY && j == 1 && isnan(v), "NaN duty");
    good(&o);
    o.leg[0].mode = BC_LEG_HOLD;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_MODE && j == 0 && v == 4.0, "BC_LEG_HOLD is no command");
    good(&o);
    o.leg[0].mode = -1;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_MODE && v == -1.0, "negative mode");
    good(&o);
    o.has_at = 2u;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_HAS_AT && v == 2.0, "has_at 2");
    good(&o);
    o.has_at = 1u;
    o.t_at = -1e-6f;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_T_AT, "negative t_at");
    good(&o);
    o.has_at = 1u;
    o.t_at = 1e-5f;
    o.leg_at[1].duty = 2.0f;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_DUTY_AT && j == 1 && v == 2.0, "leg_at duty");
    good(&o);
    o.t_at = NAN;
    o.leg_at[1].duty = 2.0f;
    CHECK(bc_user_check(&o, &j, &v) == 0, "t_at and leg_at unread without has_at");
    good(&o);
    o.diag[7] = INFINITY;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_DIAG && j == 7 && isinf(v), "diag 7 infinite");
    good(&o);
    o.i_hold_at = NAN;
    CHECK(bc_user_check(&o, &j, &v) == BC_USER_AT_HOLD && j == 1, "i_hold_at NaN");
}

/* A test controller: six-step voltage (bc_sixv) that writes a bad value at sample `bad_k` (-1: never). */
typedef struct {
    bc_sixv_params sixv;
    int64_t bad_k;
    int32_t what; /* 0 duty 1.5, 1 NaN diag, 2 write to the inputs */
} test_params;

typedef struct {
    bc_sixv_state sixv;
    int64_t k;
} test_state;

static int test_init(const void *p, void *s)
{
    const test_params *tp = p;
    test_state *ts = s;
    ts->k = 0;
    return bc_sixv_init(&tp->sixv, &ts->sixv);
}

static void test_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    const test_params *tp = p;
    test_state *ts = s;
    bc_sixv_step(&tp->sixv, &ts->sixv, in, out);
    if (ts->k == tp->bad_k) {
        if (tp->what == 0) out->leg[1].duty = 1.5f;
        if (tp->what == 1) out->diag[3] = NAN;
        if (tp->what == 2) ((bc_ctrl_in *)(uintptr_t)in)->v_dc = 0.0f; /* the bug being caught */
    }
    ts->k += 1;
}

#define N 2000
static bc_trace_row rows_a[N], rows_b[N];

typedef struct {
    fixture f;
    bc_sim_config cfg;
    bc_sim_inputs in;
    bc_sim_state s;
    test_params p;
    test_state st;
    bc_user_guard g;
    bc_user_watch w;
    bc_ctrl_in gin;
    bc_ctrl_out gout;
} rig;

static void rig_make(rig *r, int guarded, int64_t bad_k, int32_t what)
{
    memset(r, 0, sizeof *r);
    fixture_htm(&r->f, BC_MECH_IMPOSED);
    r->p.sixv.chop = BC_SIXV_HIGH;
    r->p.bad_k = bad_k;
    r->p.what = what;
    r->cfg.plant = &r->f.p;
    r->cfg.sensors = &r->f.sp;
    r->cfg.delay = 1;
    r->cfg.trace_every = 1;
    r->cfg.trace_sub = 1;
    r->in.ref_c = 0.4;
    r->in.omega_c = 60.0;
    r->in.v_src_c = 48.0;
    if (guarded) {
        r->g = (bc_user_guard){.init = test_init, .step = test_step, .params = &r->p, .state = &r->st,
                               .in = &r->gin, .out = &r->gout, .watch = &r->w};
        CHECK(bc_user_init(&r->g) == BC_OK, "guarded init");
        r->cfg.ctrl = (bc_ctrl){.step = bc_user_step, .params = 0, .state = &r->g};
    } else {
        CHECK(test_init(&r->p, &r->st) == BC_OK, "init");
        r->cfg.ctrl = (bc_ctrl){.step = test_step, .params = &r->p, .state = &r->st};
    }
    const double i0[3] = {0.0, 0.0, 0.0};
    CHECK(bc_sim_init(&r->cfg, &r->s, 0.3, 60.0, i0, 48.0) == BC_OK, "sim init");
}

static rig ra, rb;

static void test_closed_loop(void)
{
    /* no fault: the guarded run is the unguarded one, bit for bit, and counts every call */
    int64_t na = 0, nb = 0;
    rig_make(&ra, 0, -1, 0);
    rig_make(&rb, 1, -1, 0);
    CHECK(bc_sim_run(&ra.cfg, &ra.s, &ra.in, N, rows_a, N, &na) == BC_OK, "plain run");
    CHECK(bc_user_run(&rb.cfg, &rb.s, &rb.in, N, rows_b, N, &nb, &rb.g) == BC_OK, "guarded run");
    CHECK(na == N && nb == N && memcmp(rows_a, rows_b, sizeof rows_a) == 0, "same trace, bit for bit");
    CHECK(rb.w.entered == (uint64_t)N + 1u && rb.w.done == rb.w.entered && rb.w.busy == 0, "calls: init + %d steps",
          N);
    CHECK(rb.w.k == N - 1 && rb.g.k == N && rb.w.fault == BC_USER_FAULT_NONE && rb.g.jump == 0, "last sample");

    /* a duty of 1.5 at sample 777: the run ends there, the watch says where; the rows before are the plain run's */
    rig_make(&rb, 1, 777, 0);
    nb = 0;
    int rc = bc_user_run(&rb.cfg, &rb.s, &rb.in, N, rows_b, N, &nb, &rb.g);
    CHECK(rc == BC_USER_STOPPED && rb.g.jump == 0, "stopped: %d", rc);
    CHECK(rb.w.fault == BC_USER_FAULT_OUTPUT && rb.w.where == BC_USER_AT_DUTY && rb.w.index == 1 &&
              rb.w.value == 1.5 && rb.w.k == 777, "fault at sample %lld: where %d index %d value %g",
          (long long)rb.w.k, (int)rb.w.where, (int)rb.w.index, rb.w.value);
    CHECK(rb.s.k == 777 && memcmp(rows_a, rows_b, 777 * sizeof rows_a[0]) == 0, "rows before the fault unchanged");

    /* NaN diagnostic */
    rig_make(&rb, 1, 5, 1);
    rc = bc_user_run(&rb.cfg, &rb.s, &rb.in, N, rows_b, N, &nb, &rb.g);
    CHECK(rc == BC_USER_STOPPED && rb.w.where == BC_USER_AT_DIAG && rb.w.index == 3 && rb.w.k == 5, "NaN diag 3");

    /* a write to the const inputs: the first byte changed is v_dc's */
    rig_make(&rb, 1, 9, 2);
    rc = bc_user_run(&rb.cfg, &rb.s, &rb.in, N, rows_b, N, &nb, &rb.g);
    CHECK(rc == BC_USER_STOPPED && rb.w.fault == BC_USER_FAULT_INPUT && rb.w.k == 9, "input write stops the run");
    CHECK(rb.w.index >= (int32_t)offsetof(bc_ctrl_in, v_dc) &&
              rb.w.index < (int32_t)(offsetof(bc_ctrl_in, v_dc) + sizeof(float)), "at v_dc: byte %d",
          (int)rb.w.index);

    /* a callback's stop request */
    rig_make(&rb, 1, -1, 0);
    rb.g.stop = 1;
    rc = bc_user_run(&rb.cfg, &rb.s, &rb.in, N, rows_b, N, &nb, &rb.g);
    CHECK(rc == BC_USER_STOPPED && rb.w.fault == BC_USER_FAULT_STOP && rb.w.k == 0, "stop at the first sample");

    /* outside bc_user_run the guard cannot end the run: the legs go off */
    rig_make(&rb, 1, 0, 0);
    bc_ctrl_in in;
    memset(&in, 0, sizeof in);
    in.hall = 1u;
    in.v_dc = 48.0f;
    in.ref = 0.4f;
    bc_ctrl_out out;
    memset(&out, 0, sizeof out);
    bc_user_step(0, &rb.g, &in, &out);
    CHECK(rb.w.fault == BC_USER_FAULT_OUTPUT && out.leg[0].mode == BC_LEG_OFF && out.leg[1].mode == BC_LEG_OFF &&
              out.leg[1].duty == 0.0f, "legs off");
}

static uint32_t struct_size(const char *name)
{
    for (int32_t j = 0; j < bc_struct_count(); ++j) {
        if (strcmp(bc_struct_get(j)->name, name) == 0) return bc_struct_get(j)->size;
    }
    return 0u;
}

static void test_tables(void)
{
    static const char *const names[] = {"bc_user_desc", "bc_user_entry", "bc_user_watch", "bc_user_guard"};
    for (size_t c = 0; c < sizeof names / sizeof names[0]; ++c) {
        uint32_t size = struct_size(names[c]), end = 0u;
        CHECK(size > 0u, "%s has a size entry", names[c]);
        for (int32_t j = 0; j < bc_layout_count(); ++j) {
            const bc_field_desc *f = bc_layout_get(j);
            if (strcmp(f->strct, names[c]) != 0) continue;
            CHECK(f->offset >= end && f->offset - end < 8u, "%s.%s follows the previous member", f->strct, f->field);
            end = f->offset + f->size;
        }
        CHECK(end <= size && size - end < 8u, "%s: %u of %u bytes described", names[c], end, size);
    }
    CHECK(struct_size("bc_user_watch") % 8u == 0u, "watch: a whole number of 8-byte words");
    CHECK(bc_user_arm(0) == BC_ERR_PARAM, "arm needs a watch");
    CHECK(bc_user_page() >= 4096 || bc_user_page() == 0, "page size");
}

int main(void)
{
    test_check();
    test_closed_loop();
    test_tables();
    return bc_test_summary("test_userguard");
}

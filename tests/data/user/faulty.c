/* faulty.c - a user controller that misbehaves on purpose at sample `at` (tests/test_user_control.py): six-step
 * voltage control (duty = ref on the Hall sector's pair) until then, then the failure `mode` selects. */
#include <stdint.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_types.h"
#include "bldc/bc_user.h"

#define F_OK 0
#define F_CRASH 1    /* write through a null pointer */
#define F_HANG 2     /* never return */
#define F_NAN 3      /* a NaN duty */
#define F_RANGE 4    /* a duty of 1.5 */
#define F_OVERREAD 5 /* read past the end of bc_ctrl_in */
#define F_INWRITE 6  /* write to the const inputs */
#define F_REJECT 7   /* init rejects the parameters */
#define F_INIT_HANG 8 /* init never returns */

typedef struct {
    int32_t mode; /* F_* */
    int32_t at;   /* sample of the failure */
    float gain;   /* duty per unit reference */
} faulty_params;

typedef struct {
    int64_t k;
    volatile float sink;
} faulty_state;

static int faulty_init(const faulty_params *p, faulty_state *s)
{
    s->k = 0;
    s->sink = 0.0f;
    if (p->mode == F_INIT_HANG) {
        for (;;) s->sink += 1.0f;
    }
    return p->mode == F_REJECT ? BC_ERR_PARAM : BC_OK;
}

static void faulty_step(const faulty_params *p, faulty_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    int sector = bc_hall_sector(in->hall);
    float d = p->gain * in->ref;
    if (d < 0.0f) d = 0.0f;
    if (d > 1.0f) d = 1.0f;
    bc_legs_off(out);
    if (sector >= 0) {
        int pos, neg;
        (void)bc_sector_phases(sector, &pos, &neg);
        out->leg[pos].mode = BC_LEG_HIGH;
        out->leg[pos].duty = d;
        out->leg[neg].mode = BC_LEG_LOW;
        out->leg[neg].duty = 1.0f;
    }
    out->diag[0] = (float)sector;
    if (s->k == (int64_t)p->at) {
        volatile int32_t *null = 0;
        const volatile float *past = (const volatile float *)(in + 1);
        switch (p->mode) {
        case F_CRASH: *null = 1; break;
        case F_HANG:
            for (;;) s->sink += 1.0f;
        case F_NAN: out->leg[0].duty = s->sink / s->sink; break; /* 0/0 */
        case F_RANGE: out->leg[2].duty = 1.5f; break;
        case F_OVERREAD:
            for (int j = 0; j < 4096; ++j) s->sink += past[j];
            break;
        case F_INWRITE: ((bc_ctrl_in *)(uintptr_t)in)->hall = 0u; break;
        default: break;
        }
    }
    s->k += 1;
}

static const bc_field_desc FAULTY_FIELDS[] = {
    BC_BIND_FIELD(faulty_params, mode, "i4"),
    BC_BIND_FIELD(faulty_params, at, "i4"),
    BC_BIND_FIELD(faulty_params, gain, "f4"),
};

static const bc_const_desc FAULTY_CONSTS[] = {
    BC_BIND_CONST("mode", F_OK), BC_BIND_CONST("mode", F_CRASH), BC_BIND_CONST("mode", F_HANG),
    BC_BIND_CONST("mode", F_NAN), BC_BIND_CONST("mode", F_RANGE), BC_BIND_CONST("mode", F_OVERREAD),
    BC_BIND_CONST("mode", F_INWRITE), BC_BIND_CONST("mode", F_REJECT), BC_BIND_CONST("mode", F_INIT_HANG),
};

static const faulty_params FAULTY_DEFAULTS = {F_OK, -1, 1.0f};

static const bc_user_desc FAULTY = {
    .name = "faulty",
    .fields = FAULTY_FIELDS,
    .n_fields = BC_USER_COUNT(FAULTY_FIELDS),
    .diag = {"sector"},
    .consts = FAULTY_CONSTS,
    .n_consts = BC_USER_COUNT(FAULTY_CONSTS),
    .defaults = &FAULTY_DEFAULTS,
    .ref = "duty",
};

#ifndef WRONG_SIZE
BC_USER_CONTROLLER(FAULTY, faulty_params, faulty_state, faulty_init, faulty_step);
#else
/* an entry claiming another bc_ctrl_in (a library built against another bldclab) */
static int init_adapter(const void *p, void *s) { return faulty_init((const faulty_params *)p, (faulty_state *)s); }
static void step_adapter(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    faulty_step((const faulty_params *)p, (faulty_state *)s, in, out);
}
BC_USER_EXPORT extern const bc_user_entry bc_user_controller;
BC_USER_EXPORT const bc_user_entry bc_user_controller = {
    BC_USER_ABI, (uint32_t)sizeof(bc_ctrl_in) - 8u, (uint32_t)sizeof(bc_ctrl_out), BC_DIAG_N, "",
    &FAULTY, "faulty_params", "faulty_state", (uint32_t)sizeof(faulty_params), (uint32_t)sizeof(faulty_state),
    init_adapter, step_adapter};
#endif

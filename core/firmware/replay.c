/*
 * replay.c - closed-loop inputs replayed into a controller, one callgrind dump per step (benchmarks/firmware.py).
 *
 * Built as a shared library with the controllers (core/ctrl/src/*.c, -O2 like the cost harness) and loaded by the
 * firmware benchmark into a Python process running under valgrind --tool=callgrind --instr-atstart=no:
 *
 *   1. record: bldclab.simulate runs the closed loop with the plant, the controller's registry step replaced by
 *      bc_fw_record_step, which calls the real step and keeps every bc_ctrl_in it gets and bc_ctrl_out it returns;
 *   2. replay: bc_fw_replay initialises a fresh state with this library's init, switches the instrumentation on
 *      and steps the controller through the recorded inputs, dumping the profile after every step
 *      (CALLGRIND_DUMP_STATS_AT "bc_fw_step"). Each dump then holds exactly one call of the step: its inclusive
 *      instructions are the cost of that sample, so the worst sample is exact, not sampled.
 *
 * The controller's params are the record bldclab built for the run (same struct layout as the core library: the
 * same headers and compiler); the replayed outputs must equal the recorded ones bit for bit, which the benchmark
 * checks: the replay is then the closed loop, not an approximation of it.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <valgrind/callgrind.h>

#include "bldc/bc_bemf.h"
#include "bldc/bc_commission.h"
#include "bldc/bc_hallcal.h"
#include "bldc/bc_lu.h"
#include "bldc/bc_openloop.h"
#include "bldc/bc_sine.h"
#include "bldc/bc_sixstep.h"

typedef int (*init_fn)(const void *p, void *s);

typedef struct {
    const char *name; /* registry name (bldclab._core.core().controllers) */
    init_fn init;
    bc_ctrl_step_fn step;
    size_t params_size, state_size;
} replay_target;

#define TARGET(NAME, X)                                                                                       \
    static int init_##NAME(const void *p, void *s) { return bc_##X##_init(p, s); }                           \
    static void step_##NAME(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)                   \
    {                                                                                                         \
        bc_##X##_step(p, s, in, out);                                                                         \
    }

TARGET(sixstep, sixstep)
TARGET(sine, sine)
TARGET(lu, lu)
TARGET(sixv, sixv)
TARGET(hallcal, hallcal)
TARGET(bemf, bemf)
TARGET(commission, commission)

#define ENTRY(NAME) {#NAME, init_##NAME, step_##NAME, sizeof(bc_##NAME##_params), sizeof(bc_##NAME##_state)}
static const replay_target TARGETS[] = {ENTRY(sixstep), ENTRY(sine), ENTRY(lu), ENTRY(sixv), ENTRY(hallcal),
                                        ENTRY(bemf), ENTRY(commission)};

static const replay_target *find(const char *name)
{
    for (size_t j = 0; j < sizeof TARGETS / sizeof TARGETS[0]; ++j) {
        if (strcmp(TARGETS[j].name, name) == 0) return &TARGETS[j];
    }
    return 0;
}

/* Sizes of a target's params and state, and of the controller contract (to check against the core's own). */
int bc_fw_sizes(const char *name, int64_t sizes[4])
{
    const replay_target *t = find(name);
    if (t == 0) return BC_ERR_PARAM;
    sizes[0] = (int64_t)t->params_size;
    sizes[1] = (int64_t)t->state_size;
    sizes[2] = (int64_t)sizeof(bc_ctrl_in);
    sizes[3] = (int64_t)sizeof(bc_ctrl_out);
    return BC_OK;
}

/* ---- recording ------------------------------------------------------------------------------------------ */

static struct {
    bc_ctrl_step_fn inner;
    bc_ctrl_in *in;
    bc_ctrl_out *out;
    int64_t cap, n;
} rec;

/* Start recording: bc_fw_record_step will call `inner` and keep up to `cap` inputs and outputs. */
void bc_fw_record_begin(bc_ctrl_step_fn inner, bc_ctrl_in *in, bc_ctrl_out *out, int64_t cap)
{
    rec.inner = inner;
    rec.in = in;
    rec.out = out;
    rec.cap = cap;
    rec.n = 0;
}

/* Steps recorded since bc_fw_record_begin (more than `cap` means some were not kept). */
int64_t bc_fw_record_count(void) { return rec.n; }

void bc_fw_record_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    rec.inner(p, s, in, out);
    if (rec.n < rec.cap) {
        rec.in[rec.n] = *in;
        rec.out[rec.n] = *out;
    }
    rec.n++;
}

/* ---- replay --------------------------------------------------------------------------------------------- */

/* Initialise `state` from `params` with this library's init and step through in[0 .. n), writing out[]. With
 * `dump`, the instrumentation is on during the steps only and the profile is dumped after each. Returns the init's
 * code (BC_OK) or BC_ERR_PARAM for an unknown target. */
int bc_fw_replay(const char *name, const void *params, void *state, const bc_ctrl_in *in, bc_ctrl_out *out,
                 int64_t n, int dump)
{
    const replay_target *t = find(name);
    if (t == 0) return BC_ERR_PARAM;
    int rc = t->init(params, state);
    if (rc != BC_OK) return rc;
    if (dump) {
        CALLGRIND_START_INSTRUMENTATION;
        CALLGRIND_ZERO_STATS;
    }
    for (int64_t k = 0; k < n; ++k) {
        memset(&out[k], 0, sizeof out[k]);
        t->step(params, state, &in[k], &out[k]);
        if (dump) CALLGRIND_DUMP_STATS_AT("bc_fw_step");
    }
    if (dump) CALLGRIND_STOP_INSTRUMENTATION;
    return BC_OK;
}

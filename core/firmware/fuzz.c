/*
 * fuzz.c - libFuzzer target over every controller in targets.c. The input is a controller selector byte followed
 * by a sequence of raw bc_ctrl_in records (any bit pattern: NaN, inf, huge, negative bus, invalid Hall codes, time
 * jumps of the capture counters), fed one per step so that controller state is explored too. After every step:
 *   - every leg mode is one of the four and every duty is finite and in [0, 1], also of a timed change (has_at),
 *     whose time is finite and >= 0;
 *   - every diagnostic is finite;
 *   - an invalid Hall code (for controllers that use Hall), a non-finite current (for those that measure
 *     currents), or a non-finite or non-positive DC bus (for those that use it) gives all legs off and BC_FLAG_SAFE.
 * A violated property aborts (a finding). Build: clang -fsanitize=fuzzer,address,undefined (tests/test_fuzz.py).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "targets.h"

static int hall_invalid(uint32_t code) { return code == 0u || code >= 7u; }

static void check(const bc_fw_target *tg, const bc_ctrl_in *in, const bc_ctrl_out *out)
{
    for (int x = 0; x < 3; ++x) {
        if (out->leg[x].mode < BC_LEG_OFF || out->leg[x].mode > BC_LEG_LOW) abort();
        if (!(out->leg[x].duty >= 0.0f && out->leg[x].duty <= 1.0f)) abort();
    }
    if (out->has_at > 1u) abort();
    if (out->has_at) { /* a timed change inside the half period: as valid legs, at a finite, non-negative time */
        for (int x = 0; x < 3; ++x) {
            if (out->leg_at[x].mode < BC_LEG_OFF || out->leg_at[x].mode > BC_LEG_LOW) abort();
            if (!(out->leg_at[x].duty >= 0.0f && out->leg_at[x].duty <= 1.0f)) abort();
        }
        if (!(out->t_at >= 0.0f) || !isfinite(out->t_at)) abort();
    }
    for (int j = 0; j < BC_DIAG_N; ++j) {
        if (!isfinite(out->diag[j])) abort();
    }
    if (tg->uses & BC_IS_BLOCK) return;
    int must_stop = 0;
    if ((tg->uses & BC_USES_HALL) && hall_invalid(in->hall)) must_stop = 1;
    if ((tg->uses & BC_USES_VDC) && !(isfinite(in->v_dc) && in->v_dc > 0.0f)) must_stop = 1;
    if (tg->uses & BC_USES_CURRENT) {
        for (int x = 0; x < 3; ++x) {
            if ((in->i_mask & (1u << x)) && !isfinite(in->i_abc[x])) must_stop = 1;
        }
    }
    if (must_stop) {
        if (!(out->flags & BC_FLAG_SAFE) || out->has_at) abort();
        for (int x = 0; x < 3; ++x) {
            if (out->leg[x].mode != BC_LEG_OFF) abort();
        }
    }
}

/* BC_FUZZ_ONLY="name" builds a binary for one target (inputs per controller are then countable). */
static const bc_fw_target *select_target(uint8_t selector)
{
#ifdef BC_FUZZ_ONLY
    (void)selector;
    for (int j = 0; j < bc_fw_n_targets; ++j) {
        if (strcmp(bc_fw_targets[j].name, BC_FUZZ_ONLY) == 0) return &bc_fw_targets[j];
    }
    abort();
#else
    return &bc_fw_targets[selector % (uint8_t)bc_fw_n_targets];
#endif
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    const bc_fw_target *tg = select_target(data[0]);
    if (tg->init() != BC_OK) abort(); /* the targets' parameters are valid */
    data += 1;
    size -= 1;
    while (size >= sizeof(bc_ctrl_in)) {
        bc_ctrl_in in;
        memcpy(&in, data, sizeof in);
        data += sizeof in;
        size -= sizeof in;
        bc_ctrl_out out;
        memset(&out, 0, sizeof out);
        tg->step(&in, &out);
        check(tg, &in, &out);
    }
    return 0;
}

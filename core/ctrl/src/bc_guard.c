/* bc_guard.c - the input guard shared by the controllers. The rule and its reasons: bc_guard.h. */
#include "bldc/bc_guard.h"

#include <math.h>

int bc_guard_init(const bc_guard_params *p, bc_guard_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!(isfinite(p->i_max) && p->i_max > 0.0f) || !(isfinite(p->v_max) && p->v_max > 0.0f)) return BC_ERR_PARAM;
    s->latched = 0;
    return BC_OK;
}

uint32_t bc_guard_step(const bc_guard_params *p, bc_guard_state *s, const bc_ctrl_in *in, float i[3])
{
    /* 1. currents: two measured phases give the third, i_a + i_b + i_c = 0 */
    uint32_t mask = in->i_mask & 7u;
    int n = 0, bad = 0;
    float sum = 0.0f;
    for (int x = 0; x < 3; ++x) {
        i[x] = 0.0f;
        if (mask & (1u << x)) {
            ++n;
            if (!isfinite(in->i_abc[x])) {
                bad = 1;
            } else {
                i[x] = in->i_abc[x];
                sum += i[x];
            }
        }
    }
    if (n == 2 && !bad) {
        for (int x = 0; x < 3; ++x)
            if (!(mask & (1u << x))) i[x] = -sum;
    }
    /* 2. the DC bus */
    float v = in->v_dc;
    if (n < 2 || bad || !isfinite(sum) || !isfinite(v) || !(v > 0.0f) || !(v <= p->v_max)) {
        i[0] = i[1] = i[2] = 0.0f;
        return BC_FLAG_BAD_INPUT;
    }
    /* 3. the inverter's hardware protection */
    if (in->fault_pin) return BC_FLAG_OVERCURRENT;
    /* 4. trip above i_max, latched until every |i| < i_max / 2 */
    /* the largest |i| (finite here): compared in line, no libm call (fmaxf) per sample */
    float i_abs = fabsf(i[0]);
    if (fabsf(i[1]) > i_abs) i_abs = fabsf(i[1]);
    if (fabsf(i[2]) > i_abs) i_abs = fabsf(i[2]);
    /* a measured reading at the full scale is clipped: the current is at least that, how much more unknown */
    int clipped = 0;
    if (in->i_fs > 0.0f) {
        for (int x = 0; x < 3; ++x)
            if ((mask & (1u << x)) && !(fabsf(i[x]) < in->i_fs)) clipped = 1;
    }
    if (!(i_abs <= p->i_max) || clipped) s->latched = 1;
    else if (s->latched && i_abs < 0.5f * p->i_max) s->latched = 0;
    return s->latched ? BC_FLAG_OVERCURRENT : 0u;
}

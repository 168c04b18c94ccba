/* bc_derate.c - temperature derating of the current limit and the winding temperature from its resistance
 * (bc_derate.h). */
#include "bldc/bc_derate.h"

#include <math.h>

#include "bldc/bc_types.h"

static int fin(float v) { return isfinite(v) ? 1 : 0; }

int bc_derate_init(const bc_derate_params *p, bc_derate_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!fin(p->f_min) || p->f_min < 0.0f || p->f_min >= 1.0f) return BC_ERR_PARAM;
    if (!fin(p->f_fault) || p->f_fault < 0.0f || p->f_fault > 1.0f) return BC_ERR_PARAM;
    if (!fin(p->T_lo) || !fin(p->T_hi) || !(p->T_hi > p->T_lo)) return BC_ERR_PARAM;
    if (!fin(p->tau) || p->tau < 0.0f || !fin(p->ts) || !(p->ts > 0.0f)) return BC_ERR_PARAM;
    for (int c = 0; c < BC_DERATE_CH; ++c) {
        if (p->enabled[c] != 0 && p->enabled[c] != 1) return BC_ERR_PARAM;
        if (p->enabled[c] && (!fin(p->T_start[c]) || !fin(p->T_end[c]) || !(p->T_end[c] > p->T_start[c])))
            return BC_ERR_PARAM;
        s->T_f[c] = 0.0f;
        s->primed[c] = 0;
        s->fault[c] = 0;
        s->factor[c] = 1.0f;
    }
    s->a = p->tau > 0.0f ? -expm1f(-p->ts / p->tau) : 1.0f;
    return BC_OK;
}

static float band(const bc_derate_params *p, int c, float T)
{
    if (T <= p->T_start[c]) return 1.0f;
    if (T >= p->T_end[c]) return p->f_min;
    const float x = (T - p->T_start[c]) / (p->T_end[c] - p->T_start[c]); /* in (0, 1) */
    const float f = 1.0f - (1.0f - p->f_min) * x;
    return f < p->f_min ? p->f_min : (f > 1.0f ? 1.0f : f);
}

float bc_derate_step(const bc_derate_params *p, bc_derate_state *s, const float T_meas[BC_DERATE_CH])
{
    float out = 1.0f;
    for (int c = 0; c < BC_DERATE_CH; ++c) {
        if (!p->enabled[c]) continue;
        const float T = T_meas[c];
        float f;
        if (!fin(T) || T < p->T_lo || T > p->T_hi) {
            s->fault[c] = 1;
            f = p->f_fault;
        } else {
            s->fault[c] = 0;
            if (s->primed[c]) {
                s->T_f[c] += s->a * (T - s->T_f[c]);
            } else {
                s->T_f[c] = T;
                s->primed[c] = 1;
            }
            f = band(p, c, s->T_f[c]);
        }
        s->factor[c] = f;
        if (f < out) out = f;
    }
    return out;
}

int bc_derate_r_to_temp(float R, float R_ref, float T_ref, float k, float *T)
{
    if (T == 0 || !fin(R) || !fin(R_ref) || !fin(T_ref) || !fin(k)) return BC_ERR_INPUT;
    if (!(R > 0.0f) || !(R_ref > 0.0f) || !(k + T_ref > 0.0f)) return BC_ERR_INPUT;
    const float t = R / R_ref * (k + T_ref) - k;
    if (!fin(t)) return BC_ERR_INPUT;
    *T = t;
    return BC_OK;
}

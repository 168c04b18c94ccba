/* bc_rest.c - the winding resistance during operation by d-axis current injection (bc_rest.h). */
#include "bldc/bc_rest.h"

#include <math.h>

#include "bldc/bc_derate.h"
#include "bldc/bc_types.h"

static int fin(float v) { return isfinite(v) ? 1 : 0; }

static void clear_period(bc_rest_state *s)
{
    s->k = 0;
    s->bad = 0;
    s->v0 = 0.0f;
    for (int j = 0; j < 2; ++j) {
        s->sv[j] = 0.0f;
        s->si[j] = 0.0f;
        s->n[j] = 0;
    }
}

int bc_rest_init(const bc_rest_params *p, bc_rest_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!fin(p->i_inj) || !(p->i_inj > 0.0f)) return BC_ERR_PARAM;
    if (p->n_skip < 0 || p->n_half < 2 || p->n_half - 2 < p->n_skip || p->n_half > (INT32_MAX / 2)) return BC_ERR_PARAM;
    if (!fin(p->r_lo) || !fin(p->r_hi) || !(p->r_lo > 0.0f) || !(p->r_hi > p->r_lo)) return BC_ERR_PARAM;
    if (!fin(p->a) || !(p->a > 0.0f) || p->a > 1.0f) return BC_ERR_PARAM;
    if (!fin(p->r_ref) || !(p->r_ref > 0.0f) || !fin(p->T_ref) || !(p->T_ref > -234.5f)) return BC_ERR_PARAM;
    clear_period(s);
    s->r = 0.0f;
    s->r_last = 0.0f;
    s->count = 0u;
    s->rejected = 0u;
    return BC_OK;
}

void bc_rest_restart(bc_rest_state *s) { clear_period(s); }

float bc_rest_ref(const bc_rest_params *p, const bc_rest_state *s)
{
    return s->k < p->n_half ? p->i_inj : -p->i_inj;
}

void bc_rest_step(const bc_rest_params *p, bc_rest_state *s, float v_d, float i_d, int32_t ok)
{
    int32_t half = s->k < p->n_half ? 0 : 1;
    int32_t j = s->k - half * p->n_half; /* sample within the half */
    if (!ok || !fin(v_d) || !fin(i_d)) s->bad = 1;
    if (!s->bad && j >= p->n_skip) {
        if (half == 0 && j == p->n_skip) s->v0 = v_d;
        s->sv[half] += v_d - s->v0;
        s->si[half] += i_d;
        s->n[half] += 1;
    }
    s->k += 1;
    if (s->k < 2 * p->n_half) return;
    /* end of the period: R_hat = (<v_d>+ - <v_d>-) / (<i_d>+ - <i_d>-) */
    int valid = !s->bad && s->n[0] > 0 && s->n[1] > 0;
    if (valid) {
        float dv = s->sv[0] / (float)s->n[0] - s->sv[1] / (float)s->n[1];
        float di = s->si[0] / (float)s->n[0] - s->si[1] / (float)s->n[1];
        float r = di >= p->i_inj ? dv / di : NAN;
        valid = fin(r) && r >= p->r_lo && r <= p->r_hi;
        if (valid) {
            s->r_last = r;
            s->r = s->count == 0u ? r : s->r + p->a * (r - s->r); /* r += a (R_hat - r) */
            if (s->count < UINT32_MAX) s->count += 1u;
        }
    }
    if (!valid && s->rejected < UINT32_MAX) s->rejected += 1u;
    clear_period(s);
}

int bc_rest_temp(const bc_rest_params *p, const bc_rest_state *s, float *T)
{
    if (T == 0 || s->count == 0u) return BC_ERR_PARAM;
    return bc_derate_r_to_temp(s->r, p->r_ref, p->T_ref, 234.5f, T);
}

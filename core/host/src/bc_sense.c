/* bc_sense.c - back-EMF sensing (comparators and ADC behind an RC filter). Equations in bc_sense.h. */
#include "bldc/bc_sense.h"

#include <math.h>
#include <string.h>

#include "bldc/bc_sensors.h"

static int finite_nonneg(double v) { return isfinite(v) && v >= 0.0; }

/* ---- the filter over one step ------------------------------------------------------------------------- */

/* One step of the three inputs: the cubic u_x(s) = c[x][0] + c[x][1] s + c[x][2] s^2 + c[x][3] s^3 on [0, h] and the
 * filter states at s = 0. */
typedef struct {
    double h;
    double c[3][4];
    double y0[3];
} seg_t;

/* phi_1 .. phi_4 at w <= 0 and exp(w): the series of phi_4 for |w| < 1 then phi_j = 1/j! + w phi_{j+1} downwards;
 * the recurrence phi_{j+1} = (phi_j - 1/j!) / w upwards from exp(w) otherwise (both stable where used). */
static void phi_fns(double w, double *e, double ph[5])
{
    static const double INV_FACT[5] = {1.0, 1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0};
    if (fabs(w) < 1.0) {
        /* phi_4(w) = sum_m w^m / (m + 4)!, to m = 16 (the next term is below 1e-20) */
        static const double INV_FACT4[17] = {
        0.041666666666666664,
        0.0083333333333333332,
        0.0013888888888888889,
        0.00019841269841269841,
        2.4801587301587302e-05,
        2.7557319223985893e-06,
        2.7557319223985888e-07,
        2.505210838544172e-08,
        2.08767569878681e-09,
        1.6059043836821613e-10,
        1.1470745597729725e-11,
        7.6471637318198164e-13,
        4.7794773323873853e-14,
        2.8114572543455206e-15,
        1.5619206968586225e-16,
        8.2206352466243295e-18,
        4.1103176233121648e-19};
        double t = 0.0;
        for (int m = 16; m >= 0; --m) t = INV_FACT4[m] + w * t;
        ph[4] = t;
        for (int j = 3; j >= 0; --j) ph[j] = INV_FACT[j] + w * ph[j + 1];
        *e = ph[0];
    } else {
        ph[0] = exp(w);
        for (int j = 0; j < 4; ++j) ph[j + 1] = (ph[j] - INV_FACT[j]) / w;
        *e = ph[0];
    }
}

/* The filter states at s in [0, h]. */
static void seg_eval(const bc_sense_params *p, const seg_t *g, double s, double y[3])
{
    if (!(p->tau > 0.0)) {
        for (int x = 0; x < 3; ++x) {
            const double *c = g->c[x];
            y[x] = c[0] + s * (c[1] + s * (c[2] + s * c[3]));
        }
        return;
    }
    double z = s / p->tau, e, ph[5];
    phi_fns(-z, &e, ph);
    /* y = e y0 + z (c0 phi_1 + c1 s phi_2 + 2 c2 s^2 phi_3 + 6 c3 s^3 phi_4) */
    double b1 = z * ph[1], b2 = z * s * ph[2], b3 = 2.0 * z * s * s * ph[3], b4 = 6.0 * z * s * s * s * ph[4];
    for (int x = 0; x < 3; ++x) {
        const double *c = g->c[x];
        y[x] = e * g->y0[x] + b1 * c[0] + b2 * c[1] + b3 * c[2] + b4 * c[3];
    }
}

static double ref_of(const bc_sense_params *p, const bc_sense_state *s, const double y[3])
{
    return p->ref == BC_SENSE_REF_HALF ? 0.5 * s->vbus : (y[0] + y[1] + y[2]) / 3.0;
}

/* Comparator x's switching condition from output state `o` at filter states y: > 0 once it switches. */
static double cmp_drive(const bc_sense_params *p, const bc_sense_state *s, const double y[3], int x, int o)
{
    double c = y[x] - ref_of(p, s, y) - p->offset;
    return o ? -(c + 0.5 * p->hyst) : c - 0.5 * p->hyst;
}

/* ---- edges --------------------------------------------------------------------------------------------- */

static void deliver(bc_sense_state *s, int j)
{
    int x = s->q_x[j];
    s->seen ^= 1u << x;
    s->count[x] += 1u;
    s->t_seen[x] = s->q_t[j];
}

static void edge_push(const bc_sense_params *p, bc_sense_state *s, int x, double t)
{
    s->out ^= 1u << x;
    s->n_edges += 1u;
    if (s->q_n == BC_SENSE_QUEUE) { /* full: the oldest is seen now, early */
        deliver(s, 0);
        memmove(s->q_t, s->q_t + 1, (BC_SENSE_QUEUE - 1) * sizeof s->q_t[0]);
        memmove(s->q_x, s->q_x + 1, (BC_SENSE_QUEUE - 1) * sizeof s->q_x[0]);
        s->q_n -= 1;
        s->overrun = 1;
    }
    s->q_t[s->q_n] = t + p->delay;
    s->q_x[s->q_n] = x;
    s->q_n += 1;
}

/* The first comparator to switch in (sa, sb] of the step (none at sa), located by bisection; -1 if none switches at
 * sb. A comparator may switch and back inside (sa, sb] unseen: the bracket is one grid interval. */
static int first_switch(const bc_sense_params *p, const bc_sense_state *s, const seg_t *g, double sa, double sb,
                        double *s_at)
{
    double y[3];
    seg_eval(p, g, sb, y);
    int best = -1;
    double s_best = sb;
    for (int x = 0; x < 3; ++x) {
        int o = (int)((s->out >> x) & 1u);
        if (!(cmp_drive(p, s, y, x, o) > 0.0)) continue;
        double lo = sa, hi = sb;
        /* condition false at lo, true at hi: shrink to 1e-12 of the step (about 40 halvings) */
        while (hi - lo > 1e-12 * g->h) {
            double mid = 0.5 * (lo + hi);
            if (!(mid > lo && mid < hi)) break;
            double ym[3];
            seg_eval(p, g, mid, ym);
            if (cmp_drive(p, s, ym, x, o) > 0.0) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        if (best < 0 || hi < s_best) {
            best = x;
            s_best = hi;
        }
    }
    *s_at = s_best;
    return best;
}

/* ---- ADC ----------------------------------------------------------------------------------------------- */

static double adc_q(const bc_sense_params *p, bc_sense_state *s, double v)
{
    if (p->adc_noise > 0.0) v += p->adc_noise * bc_rng_normal(&s->rng, &s->has_spare, &s->spare);
    if (p->adc_lsb > 0.0) v = p->adc_lsb * floor(v / p->adc_lsb + 0.5);
    if (v < 0.0) v = 0.0;
    if (v > p->adc_max) v = p->adc_max;
    return v;
}

static void adc_convert(const bc_sense_params *p, bc_sense_state *s, const double y[3])
{
    double vr = ref_of(p, s, y);
    for (int x = 0; x < 3; ++x) s->adc_v[x] = (float)adc_q(p, s, y[x]);
    s->adc_vr = (float)adc_q(p, s, vr);
    s->adc_t = s->t_adc;
    s->n_adc += 1u;
    s->t_adc += 1.0 / p->f_pwm;
}

/* ---- API ----------------------------------------------------------------------------------------------- */

int bc_sense_init(const bc_sense_params *p, bc_sense_state *s, double t0, const double v[3], double v_bus)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    memset(s, 0, sizeof *s);
    if (p->on == 0) return BC_OK;
    if (p->on != 1 || !finite_nonneg(p->tau) || (p->ref != BC_SENSE_REF_STAR && p->ref != BC_SENSE_REF_HALF) ||
        !isfinite(p->offset) || !finite_nonneg(p->hyst) || !finite_nonneg(p->delay) || !finite_nonneg(p->adc_lsb) ||
        !(p->adc_max > 0.0) || isnan(p->adc_max) || !finite_nonneg(p->adc_noise) ||
        !(isfinite(p->f_pwm) && p->f_pwm > 0.0) || !(isfinite(p->f_tick) && p->f_tick > 0.0))
        return BC_ERR_PARAM;
    double T = 1.0 / p->f_pwm;
    if (!(p->adc_at >= -0.5 * T && p->adc_at < 0.5 * T)) return BC_ERR_PARAM;
    if (!isfinite(t0) || !isfinite(v_bus)) return BC_ERR_PARAM;
    for (int x = 0; x < 3; ++x) {
        if (!isfinite(v[x])) return BC_ERR_PARAM;
        s->vf[x] = v[x];
    }
    s->t = t0;
    s->vbus = v_bus;
    for (int x = 0; x < 3; ++x) {
        if (cmp_drive(p, s, s->vf, x, 0) > -0.5 * p->hyst) s->out |= 1u << x; /* c_x > 0 */
    }
    s->seen = s->out;
    /* carrier peaks at (m + 1/2) T: the first conversion after t0 */
    double m = ceil((t0 - 0.5 * T - p->adc_at) / T);
    s->t_adc = (m + 0.5) * T + p->adc_at;
    if (!(s->t_adc > t0)) s->t_adc += T;
    s->rng = p->seed ^ 0xD1B54A32D192ED03ull;
    if (s->rng == 0u) s->rng = 1u;
    return BC_OK;
}

void bc_sense_step(const bc_sense_params *p, bc_sense_state *s, double t1, const double v0[3], const double dv0[3],
                   const double v1[3], const double dv1[3], double v_bus)
{
    if (!p->on) return;
    double h = t1 - s->t;
    s->vbus = v_bus;
    if (!(h > 0.0)) return;
    seg_t g;
    g.h = h;
    for (int x = 0; x < 3; ++x) {
        double D = (v1[x] - v0[x]) / h;
        double *c = g.c[x];
        c[0] = v0[x];
        c[1] = dv0[x];
        c[2] = (3.0 * D - 2.0 * dv0[x] - dv1[x]) / h;
        c[3] = (dv0[x] + dv1[x] - 2.0 * D) / (h * h);
        g.y0[x] = s->vf[x];
    }
    /* comparator edges, grid interval by interval, in time order */
    double sa = 0.0;
    for (int j = 1; j <= BC_SENSE_GRID; ++j) {
        double sb = h * (double)j / (double)BC_SENSE_GRID;
        for (int guard = 0; guard < 8; ++guard) {
            double s_at;
            int x = first_switch(p, s, &g, sa, sb, &s_at);
            if (x < 0) break;
            edge_push(p, s, x, s->t + s_at);
            sa = s_at;
        }
        sa = sb;
    }
    /* conversions in (t0, t1] */
    while (s->t_adc <= t1) {
        double y[3];
        seg_eval(p, &g, s->t_adc - s->t, y);
        adc_convert(p, s, y);
    }
    seg_eval(p, &g, h, s->vf);
    s->t = t1;
}

void bc_sense_fill(const bc_sense_params *p, bc_sense_state *s, double t, bc_ctrl_in *in)
{
    if (!p->on) return;
    int j = 0;
    while (j < s->q_n && s->q_t[j] <= t) deliver(s, j++);
    if (j > 0) {
        memmove(s->q_t, s->q_t + j, (size_t)(s->q_n - j) * sizeof s->q_t[0]);
        memmove(s->q_x, s->q_x + j, (size_t)(s->q_n - j) * sizeof s->q_x[0]);
        s->q_n -= j;
    }
    in->zc_state = s->seen;
    for (int x = 0; x < 3; ++x) {
        in->zc_count[x] = s->count[x];
        in->zc_tick[x] = bc_tick_at(p->f_tick, s->t_seen[x]);
        in->v_term[x] = s->adc_v[x];
    }
    in->v_neutral = s->adc_vr;
    in->n_adc = s->n_adc;
    in->tick_adc = bc_tick_at(p->f_tick, s->adc_t);
}

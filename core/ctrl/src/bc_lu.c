/* bc_lu.c - paper 2's torque controller, its no-D_o variant and rectangular current control. Laws in bc_lu.h,
 * derivations in docs/theory-paper2.md. */
#include "bldc/bc_lu.h"

#include <math.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_inverter.h"
#include "bldc/bc_math.h"

/* |lev| below lev_min is replaced by lev_min with lev's sign (+ for 0 or NaN): a denominator never near 0. */
static float guard(float lev, float lev_min)
{
    if (fabsf(lev) >= lev_min) return lev;
    return lev < 0.0f ? -lev_min : lev_min;
}

/* ---- shapes and torque ------------------------------------------------------------------------------------ */

float bc_lu_shape(const float *table, int32_t n, float theta)
{
    float nf = (float)n;
    if (!isfinite(theta)) theta = 0.0f;
    /* u = theta n / (2 pi) wrapped to [0, n); f = table[j] + (u - j) (table[j+1] - table[j]), table[n] = table[0].
     * Within one turn of the range (every angle a running step asks for: theta - x 2 pi/3, theta + Omega_e T_s) no
     * fmodf: its remainder is y itself, or y - n exactly (Sterbenz: n <= y < 2 n), so the same u. */
    float y = theta * (nf / BC_TWO_PI_F), u;
    if (y >= 0.0f && y < nf) u = y;
    else if (y >= nf && y < 2.0f * nf) u = y - nf;
    else if (y < 0.0f && y > -nf) u = y + nf;
    else {
        u = fmodf(y, nf);
        if (u < 0.0f) u += nf;
    }
    if (!(u >= 0.0f && u < nf)) u = 0.0f;
    int32_t j = (int32_t)u;
    if (j > n - 1) j = n - 1;
    float fr = u - (float)j;
    int32_t j1 = j + 1 < n ? j + 1 : 0;
    return table[j] + fr * (table[j1] - table[j]);
}

void bc_lu_shapes(const bc_lu_params *p, float theta, float f[3])
{
    /* f_x = f_x(theta - x 2 pi/3): each table is a function of its phase's local angle */
    for (int x = 0; x < 3; ++x) f[x] = bc_lu_shape(p->f[x], p->n, theta - (float)x * (BC_TWO_PI_F / 3.0f));
}

/* T = sum f_x i_x: (1) with e_x = f_x w, so w cancels */
float bc_lu_torque(const bc_lu_point *x) { return x->f[0] * x->i[0] + x->f[1] * x->i[1] + x->f[2] * x->i[2]; }

static float sum3(const float v[3]) { return v[0] + v[1] + v[2]; }

/* g / w^2 = (f_a - f_b)^2 + (f_b - f_c)^2 + (f_c - f_a)^2 */
static float g_of(const float f[3])
{
    float ab = f[0] - f[1], bc = f[1] - f[2], ca = f[2] - f[0];
    return ab * ab + bc * bc + ca * ca;
}

/* ---- one-step models ------------------------------------------------------------------------------------- */

/* Diode voltage of an off phase: lower diode (0) for i_F > 0, upper diode (V) for i_F < 0. */
static float v_diode(float i_f, float v) { return i_f >= 0.0f ? 0.0f : v; }

/* Off phase's slope while P and N chop bipolar (v_P + v_N = V at every instant, so v_n does not depend on S):
 *     s_F = (v_F - v_n - w f_F - R i_F) / L,   v_n = (V + v_F - w sum f) / 3 */
static float slope_off(const bc_lu_params *p, const bc_lu_point *x, int off)
{
    float v_f = v_diode(x->i[off], x->v_dc);
    float v_n = (x->v_dc + v_f - x->omega_m * sum3(x->f)) / 3.0f;
    return (v_f - v_n - x->omega_m * x->f[off] - p->R * x->i[off]) / p->L;
}

float bc_lu_extinction(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg)
{
    int off = 3 - pos - neg;
    float i_f = x->i[off];
    if (!(fabsf(i_f) > p->i_zero)) return 0.0f;
    /* i_F(T_s) = i_F + s_F T_s; t_x = T_s i_F / (i_F - i_F(T_s)) = -i_F / s_F when the sign changes */
    float end = i_f + slope_off(p, x, off) * p->ts;
    if ((i_f > 0.0f && end > 0.0f) || (i_f < 0.0f && end < 0.0f)) return p->ts;
    float t_x = p->ts * i_f / (i_f - end); /* |i_f - end| >= |i_f| > i_zero: no division by ~0 */
    return bc_clampf(t_x, 0.0f, p->ts);
}

void bc_lu_predict(const bc_lu_params *p, const bc_lu_point *x, const bc_lu_plan *plan, float i_next[3])
{
    if (plan->kind != BC_LU_PAIR && plan->kind != BC_LU_DO) { /* SAFE: all legs off, the diodes conduct */
        bc_lu_predict_ordered(p, x, plan, 1, i_next);
        return;
    }
    for (int k = 0; k < 3; ++k) i_next[k] = x->i[k];
    int P = plan->pos, N = plan->neg, F = plan->off;
    float v = x->v_dc, w = x->omega_m, ts = p->ts, L = p->L, R = p->R;
    float d = plan->duty;
    if (plan->kind == BC_LU_PAIR) {
        float t_x = bc_lu_extinction(p, x, P, N);
        /* (6)/(7): L di_P/dt = V (2D - 1)/2 + c2,  c2 = w (f_N - f_P)/2 - R i_P                         (F open)
         * (14)/(15): L di_P/dt = V (2D - 1)/2 + c3,  c3 = V/6 - v_F/3 + w sum f/3 - w f_P - R i_P    (F conducts)
         * di_P = (T_s V (2D - 1)/2 + t_x c3 + (T_s - t_x) c2) / L;  di_F = s_F T_s, or -i_F if F opens at t_x */
        float v_f = v_diode(x->i[F], v);
        float c2 = w * (x->f[N] - x->f[P]) * 0.5f - R * x->i[P];
        float c3 = v / 6.0f - v_f / 3.0f + w * sum3(x->f) / 3.0f - w * x->f[P] - R * x->i[P];
        float di_p = (ts * v * (2.0f * d - 1.0f) * 0.5f + t_x * c3 + (ts - t_x) * c2) / L;
        float di_f = 0.0f;
        if (t_x > 0.0f) di_f = t_x < ts ? -x->i[F] : slope_off(p, x, F) * ts;
        i_next[P] = x->i[P] + di_p;
        i_next[F] = x->i[F] + di_f;
        i_next[N] = x->i[N] - di_p - di_f;
        return;
    }
    /* (22): di_x = T_s (v_x - v_n - w f_x - R i_x) / L, v_P = V, v_N = 0, v_F = D_o V (sig > 0) or (1 - D_o) V,
     * v_n = (sum v - w sum f) / 3 */
    float vt[3];
    vt[P] = v;
    vt[N] = 0.0f;
    vt[F] = plan->sig > 0 ? d * v : (1.0f - d) * v;
    float v_n = (vt[0] + vt[1] + vt[2] - w * sum3(x->f)) / 3.0f;
    for (int k = 0; k < 3; ++k) i_next[k] = x->i[k] + ts * (vt[k] - v_n - w * x->f[k] - R * x->i[k]) / L;
    /* past its zero F would open: (22) does not hold there; stop F at 0 and give the difference to the
     * non-commutated phase (the pair phase of the other sign) */
    float sig = plan->sig > 0 ? 1.0f : -1.0f;
    if (sig * i_next[F] < 0.0f) {
        int nc = plan->sig > 0 ? N : P;
        i_next[nc] += i_next[F];
        i_next[F] = 0.0f;
    }
}

/* Leg states within a part of the half period. */
#define SEG_OFF 0 /* both switches off: a diode carries the current, if any */
#define SEG_HI 1  /* upper switch on: terminal at V whatever the current's sign */
#define SEG_LO 2  /* lower switch on: terminal at 0 */

/* Advance the currents over tau seconds with the legs in fixed states: the connected phases C (switched, or off
 * with current through a diode) obey L di_x/dt = u_x - w f_x - R i_x(0) - v_n, v_n = mean_C (u_x - w f_x - R i_x(0)),
 * a diode-only phase opens when its current reaches zero (the part is split there), open phases keep i = 0.
 * wf[x] = w f_x and r_drop[x] = R i_x at the start of the step (as in the averaged models); eps: a current within
 * it is zero. */
static void segment(const bc_lu_params *p, const bc_lu_point *x, const float wf[3], const float r_drop[3],
                    const int leg[3], float tau, float eps, float i[3], float *area, int *dry)
{
    float v = x->v_dc;
    for (int ev = 0; ev < 4 && tau > 0.0f; ++ev) {
        float u[3], slope[3];
        int conn[3], diode[3];
        for (int k = 0; k < 3; ++k) {
            diode[k] = 0;
            conn[k] = 1;
            if (leg[k] == SEG_HI) {
                u[k] = v;
            } else if (leg[k] == SEG_LO) {
                u[k] = 0.0f;
            } else if (i[k] > eps) {
                u[k] = 0.0f; /* lower diode */
                diode[k] = 1;
            } else if (i[k] < -eps) {
                u[k] = v; /* upper diode */
                diode[k] = 1;
            } else {
                u[k] = 0.0f;
                conn[k] = 0; /* open */
                i[k] = 0.0f;
            }
        }
        /* the circuit (bc_inverter.h): terms (u_x - w f_x) - R i_x(0) */
        if (bc_inv_slopes(u, wf, r_drop, conn, p->L, slope) == BC_INV_NO_PATH) {
            /* no circuit: no current (for the rest of the part: no torque) */
            for (int k = 0; k < 3; ++k) i[k] = 0.0f;
            if (dry) *dry = 1;
            return;
        }
        /* the first diode current to reach zero ends the part early */
        float t_ev;
        int who = bc_inv_first_zero(diode, i, slope, tau, &t_ev);
        /* the currents are linear over the piece: its torque integral is t_ev T(mid-piece) (shapes frozen) */
        if (area) {
            float t_mid = 0.0f;
            for (int k = 0; k < 3; ++k) t_mid += x->f[k] * (i[k] + 0.5f * slope[k] * t_ev);
            *area += t_ev * t_mid;
        }
        bc_inv_advance(conn, slope, t_ev, who, i);
        if (dry && fabsf(i[0]) <= eps && fabsf(i[1]) <= eps && fabsf(i[2]) <= eps) *dry = 1; /* none left */
        tau -= t_ev;
        if (who < 0) break;
    }
}

/* The ordered step; with area and dry non-null also the torque integral (N m s) and whether the current stops. */
static void ordered(const bc_lu_params *p, const bc_lu_point *x, const bc_lu_plan *plan, int rising, float i_next[3],
                    float *area, int *dry)
{
    float r_drop[3], wf[3];
    for (int k = 0; k < 3; ++k) {
        i_next[k] = x->i[k];
        r_drop[k] = p->R * x->i[k];
        wf[k] = x->omega_m * x->f[k];
    }
    float eps = 1e-6f * p->i_max;
    int on[3] = {SEG_OFF, SEG_OFF, SEG_OFF}, off[3] = {SEG_OFF, SEG_OFF, SEG_OFF};
    float d = 0.0f;
    if (plan->kind == BC_LU_PAIR || plan->kind == BC_LU_DO) {
        d = bc_clampf(plan->duty, 0.0f, 1.0f);
        on[plan->pos] = SEG_HI; /* S = +1 */
        on[plan->neg] = SEG_LO;
        if (plan->kind == BC_LU_DO) {
            off[plan->pos] = SEG_HI; /* D_o: P and N stay on, F's switch chops */
            off[plan->neg] = SEG_LO;
            on[plan->off] = plan->sig > 0 ? SEG_HI : SEG_LO;
        }
    }
    /* centre-aligned PWM: the on part is next to the carrier peak, so a rising half period starts off */
    float t_on = d * p->ts, t_off = p->ts - t_on;
    if (rising) {
        segment(p, x, wf, r_drop, off, t_off, eps, i_next, area, dry);
        segment(p, x, wf, r_drop, on, t_on, eps, i_next, area, dry);
    } else {
        segment(p, x, wf, r_drop, on, t_on, eps, i_next, area, dry);
        segment(p, x, wf, r_drop, off, t_off, eps, i_next, area, dry);
    }
}

void bc_lu_predict_ordered(const bc_lu_params *p, const bc_lu_point *x, const bc_lu_plan *plan, int rising,
                           float i_next[3])
{
    ordered(p, x, plan, rising, i_next, 0, 0);
}

float bc_lu_mean_ordered(const bc_lu_params *p, const bc_lu_point *x, const bc_lu_plan *plan, int rising,
                         float i_next[3], int *dry)
{
    float area = 0.0f;
    float eps = 1e-6f * p->i_max;
    *dry = fabsf(x->i[0]) <= eps && fabsf(x->i[1]) <= eps && fabsf(x->i[2]) <= eps;
    ordered(p, x, plan, rising, i_next, &area, dry);
    return area / p->ts;
}

/* ---- the evaluations of one step, kept ------------------------------------------------------------------ */

/* The solves and the period test of one step evaluate the ordered model from one point (x1) and for one pair, and
 * they meet the same duties again: the bracket solve's first estimate is the guess it has just evaluated, the mean
 * law starts from the end-value duty the period test has just evaluated (and brackets with the end value's d = 1 or
 * 0), and the test of the mean law's duty repeats the solve's last evaluation. Each half period is therefore kept
 * (a few, most recent first overwritten) and taken again for the same duty: the same inputs through the same
 * arithmetic, so the same numbers, without the second evaluation. Keyed by the duty clamped to [0, 1] (all the
 * model uses of it) and the half's direction; a memo belongs to one point and pair (checked: another one clears
 * it). */
#define MEMO_HALVES 4
#define MEMO_SECONDS 2

typedef struct {
    float d;          /* duty clamped to [0, 1] */
    int32_t rising;   /* direction of the half period (the second half of a period: of the first one) */
    int32_t has_mean; /* mean and dry computed (bc_lu_mean_ordered), else the currents only */
    float i[3];       /* currents at the end of the half period */
    float mean;       /* mean torque over it, N m */
    int32_t dry;      /* the current stops in it (bc_lu_mean_ordered) */
} half_eval;

typedef struct {
    const bc_lu_point *x; /* the point every half starts from (the second halves: from a first one's end) */
    int32_t pos, neg;
    int32_t want_mean;    /* also compute the mean and dry of an end-value evaluation (a period test follows) */
    half_eval half[MEMO_HALVES];    /* half periods from x */
    half_eval second[MEMO_SECONDS]; /* the half period after one from x under the same duty, keyed by the first */
    int32_t n_half, n_second, next_half, next_second;
} lu_memo;

static void memo_init(lu_memo *m, const bc_lu_point *x, int pos, int neg, int want_mean)
{
    m->x = x;
    m->pos = pos;
    m->neg = neg;
    m->want_mean = want_mean;
    m->n_half = m->n_second = m->next_half = m->next_second = 0;
}

/* The memo for this point and pair (cleared if it held another). */
static void memo_bind(lu_memo *m, const bc_lu_point *x, int pos, int neg)
{
    if (m->x != x || m->pos != pos || m->neg != neg) memo_init(m, x, pos, neg, m->want_mean);
}

static const half_eval *memo_find(const half_eval *e, int32_t n, float d, int rising, int mean)
{
    for (int32_t k = 0; k < n; ++k) {
        if (e[k].d == d && e[k].rising == rising && (e[k].has_mean || !mean)) return &e[k];
    }
    return 0;
}

/* The half period from x under the PAIR plan with duty d (mean: with its mean torque and dry). */
static const half_eval *half_of(const bc_lu_params *p, lu_memo *m, bc_lu_plan *plan, int rising, float d, int mean)
{
    float dc = bc_clampf(d, 0.0f, 1.0f);
    const half_eval *hit = memo_find(m->half, m->n_half, dc, rising, mean);
    if (hit) return hit;
    half_eval *e = &m->half[m->next_half];
    if (++m->next_half == MEMO_HALVES) m->next_half = 0;
    if (m->n_half < MEMO_HALVES) ++m->n_half;
    e->d = dc;
    e->rising = rising;
    e->has_mean = mean;
    plan->duty = d;
    if (mean) {
        int dry;
        e->mean = bc_lu_mean_ordered(p, m->x, plan, rising, e->i, &dry);
        e->dry = dry;
    } else {
        bc_lu_predict_ordered(p, m->x, plan, rising, e->i);
        e->mean = 0.0f;
        e->dry = 0;
    }
    return e;
}

/* The half period after `first` (from its end, the other direction, the same duty), with its mean and dry. */
static const half_eval *second_of(const bc_lu_params *p, lu_memo *m, bc_lu_plan *plan, const half_eval *first)
{
    const half_eval *hit = memo_find(m->second, m->n_second, first->d, first->rising, 1);
    if (hit) return hit;
    half_eval *e = &m->second[m->next_second];
    if (++m->next_second == MEMO_SECONDS) m->next_second = 0;
    if (m->n_second < MEMO_SECONDS) ++m->n_second;
    bc_lu_point y = *m->x;
    int dry;
    for (int k = 0; k < 3; ++k) y.i[k] = first->i[k];
    plan->duty = first->d;
    e->d = first->d;
    e->rising = first->rising;
    e->has_mean = 1;
    e->mean = bc_lu_mean_ordered(p, &y, plan, !first->rising, e->i, &dry);
    e->dry = dry;
    return e;
}

/* The ordered model's torque under a PAIR duty d: at the end of the step (mean = 0), its mean over the step
 * (mean = 1), or its mean over the step and the next one under the same duty, the next half period the other
 * direction (mean = 2: a whole PWM period when the step rises). */
static float pair_torque(const bc_lu_params *p, lu_memo *m, bc_lu_plan *plan, int rising, float d, int mean)
{
    if (!mean) {
        const half_eval *h = half_of(p, m, plan, rising, d, m->want_mean);
        bc_lu_point y = *m->x;
        for (int k = 0; k < 3; ++k) y.i[k] = h->i[k];
        return bc_lu_torque(&y);
    }
    const half_eval *h = half_of(p, m, plan, rising, d, 1);
    if (mean == 1) return h->mean;
    return 0.5f * (h->mean + second_of(p, m, plan, h)->mean);
}

typedef struct {
    const bc_lu_params *p;
    lu_memo *m;
    bc_lu_plan *plan;
    float t_ref, sgn;
    int rising, mean;
} pair_goal;

static float pair_gap(float d, void *ctx)
{
    const pair_goal *g = (const pair_goal *)ctx;
    return g->sgn * (pair_torque(g->p, g->m, g->plan, g->rising, d, g->mean) - g->t_ref);
}

/* Root of sgn (pair_torque(d) - T*) on [0, 1] (see bc_lu_solve_pair), the evaluations kept in m. */
static float solve_pair(const bc_lu_params *p, lu_memo *m, const bc_lu_point *x, int pos, int neg, float t_ref,
                        int rising, float d0, float tol, int mean)
{
    /* g(d) = sgn (T(d) - T*), increasing in d (sgn: the sign of the pair's lever f_P - f_N) */
    float sgn = x->f[pos] - x->f[neg] >= 0.0f ? 1.0f : -1.0f;
    bc_lu_plan plan = {BC_LU_PAIR, pos, neg, 3 - pos - neg, 0, 0.0f};
    memo_bind(m, x, pos, neg);
#define G_OF(dd, out)                                                              \
    do {                                                                           \
        (out) = sgn * (pair_torque(p, m, &plan, rising, (dd), mean) - t_ref);      \
    } while (0)
    float g;
    float a = 0.0f, b = 1.0f, ga, gb, d;
    if (d0 > 0.0f && d0 < 1.0f) {
        /* a first estimate inside [0, 1] (the closed-form law's duty, or the mean law's last period's): bracket on
         * its side only (the far end's evaluation is saved) */
        G_OF(d0, g);
        if (fabsf(g) <= tol) return d0;
        if (g < 0.0f) {
            a = d0;
            ga = g;
            G_OF(1.0f, gb);
            if (gb < 0.0f) return 1.0f - gb * (1.0f - d0) / fmaxf(gb - ga, 1e-30f); /* out of reach */
        } else {
            b = d0;
            gb = g;
            G_OF(0.0f, ga);
            if (ga > 0.0f) return -ga * d0 / fmaxf(gb - ga, 1e-30f); /* too much even at zero duty */
        }
        d = bc_clampf(a - ga * (b - a) / fmaxf(gb - ga, 1e-30f), a, b);
    } else {
        if (d0 >= 0.0f && d0 <= 1.0f) {
            G_OF(d0, g);
            if (fabsf(g) <= tol) return d0; /* the averaged model holds */
        }
        G_OF(0.0f, ga);
        G_OF(1.0f, gb);
        float range = fmaxf(gb - ga, 1e-30f);
        if (gb < 0.0f) return d0 > 1.0f ? d0 : 1.0f - gb / range; /* out of reach at full duty */
        if (ga > 0.0f) return d0 < 0.0f ? d0 : -ga / range;        /* too much even at zero duty */
        d = a - ga * (b - a) / range;
    }
    /* Illinois (modified regula falsi, bc_root_bracket) on the bracket [a, b], g(a) <= 0 <= g(b) */
#undef G_OF
    pair_goal goal = {p, m, &plan, t_ref, sgn, rising, mean};
    return bc_root_bracket(pair_gap, &goal, a, b, ga, gb, d, tol, 1e-7f, 40, BC_ROOT_ILLINOIS);
}

float bc_lu_solve_pair(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, int rising,
                       float d0, float tol)
{
    lu_memo m;
    memo_init(&m, x, pos, neg, 0);
    return solve_pair(p, &m, x, pos, neg, t_ref, rising, d0, tol, 0);
}

float bc_lu_solve_pair_mean(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, int rising,
                            float d0, float tol, int two)
{
    lu_memo m;
    memo_init(&m, x, pos, neg, 0);
    return solve_pair(p, &m, x, pos, neg, t_ref, rising, d0, tol, two ? 2 : 1);
}

/* ---- the laws -------------------------------------------------------------------------------------------- */

float bc_lu_dn(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, float lever_min)
{
    /* (9')  D_n = 1/2 + (T* - T) L / (V T_s lam) + w lam / (2 V) + R i_P / V,   lam = f_P - f_N */
    float v = x->v_dc;
    float lam = x->f[pos] - x->f[neg];
    float t = bc_lu_torque(x);
    return 0.5f + (t_ref - t) * p->L / (v * p->ts * guard(lam, lever_min)) + x->omega_m * lam / (2.0f * v) +
           p->R * x->i[pos] / v;
}

float bc_lu_dc(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, float lever_min)
{
    /* (17')  D_c = [(T* - T) L / T_s + w g / 3 + R T - V (f_N - fbar) - v_F (f_F - fbar)] / (V lam) */
    int off = 3 - pos - neg;
    float v = x->v_dc;
    float fbar = sum3(x->f) / 3.0f;
    float t = bc_lu_torque(x);
    float v_f = v_diode(x->i[off], v);
    float num = (t_ref - t) * p->L / p->ts + x->omega_m * g_of(x->f) / 3.0f + p->R * t - v * (x->f[neg] - fbar) -
                v_f * (x->f[off] - fbar);
    return num / (v * guard(x->f[pos] - x->f[neg], lever_min));
}

float bc_lu_ds(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, float lever_min)
{
    /* D_s = D_n + i_F L (2 f_F - f_P - f_N) / (2 V T_s lam) + R t_x i_F / (2 V T_s)   (F opens at t_x < T_s) */
    int off = 3 - pos - neg;
    float v = x->v_dc, i_f = x->i[off];
    float lam = guard(x->f[pos] - x->f[neg], lever_min);
    float t_x = bc_lu_extinction(p, x, pos, neg);
    return bc_lu_dn(p, x, pos, neg, t_ref, lever_min) +
           i_f * p->L * (2.0f * x->f[off] - x->f[pos] - x->f[neg]) / (2.0f * v * p->ts * lam) +
           p->R * t_x * i_f / (2.0f * v * p->ts);
}

float bc_lu_do(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, float lever_min)
{
    /* (24')  D_o = [(T* - T) L / T_s + w g / 3 + R T - B] / (sig V (f_F - fbar)),
     *        B = V (f_P - fbar) (i_F > 0),  -V (f_N - fbar) (i_F < 0) */
    int off = 3 - pos - neg;
    float v = x->v_dc;
    float fbar = sum3(x->f) / 3.0f;
    float t = bc_lu_torque(x);
    float sig = x->i[off] >= 0.0f ? 1.0f : -1.0f;
    float b = sig > 0.0f ? v * (x->f[pos] - fbar) : -v * (x->f[neg] - fbar);
    float num = (t_ref - t) * p->L / p->ts + x->omega_m * g_of(x->f) / 3.0f + p->R * t - b;
    return num / (v * guard(sig * (x->f[off] - fbar), lever_min));
}

void bc_lu_do_bounds(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float *d_zero, float *d_hold)
{
    /* (22) for F: di_F = T_s ((2/3) v_F - V/3 - w (f_F - fbar) - R i_F) / L with v_P + v_N = V. Solving
     * i_F + di_F = 0 and di_F = 0 for v_F:  v_F = (3/2) (V/3 + w (f_F - fbar) + R i_F - i_F L / T_s)  and  the same
     * without the last term;  D_o = v_F / V (sig > 0) or 1 - v_F / V (sig < 0) */
    int off = 3 - pos - neg;
    float v = x->v_dc, i_f = x->i[off];
    float fbar = sum3(x->f) / 3.0f;
    float a = v / 3.0f + x->omega_m * (x->f[off] - fbar) + p->R * i_f;
    float vz = 1.5f * (a - i_f * p->L / p->ts);
    float vh = 1.5f * a;
    if (i_f >= 0.0f) {
        *d_zero = vz / v;
        *d_hold = vh / v;
    } else {
        *d_zero = 1.0f - vz / v;
        *d_hold = 1.0f - vh / v;
    }
}

/* Whether the current stops at some instant of a PWM period (a rising half period from x, then a falling one)
 * under the PAIR plan with duty d in both halves; *t_first: the model's mean torque over the first half (N m). The
 * halves are the memo's (x and the plan's pair). */
static int period_dry(const bc_lu_params *p, lu_memo *m, const bc_lu_point *x, bc_lu_plan *plan, float d,
                      float *t_first)
{
    memo_bind(m, x, plan->pos, plan->neg);
    const half_eval *h = half_of(p, m, plan, 1, d, 1);
    const half_eval *h2 = second_of(p, m, plan, h);
    *t_first = h->mean;
    return h->dry || h2->dry;
}

/* ---- init and step --------------------------------------------------------------------------------------- */

int bc_lu_init(const bc_lu_params *p, bc_lu_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (p->n < 3 || p->f[0] == 0 || p->f[1] == 0 || p->f[2] == 0) return BC_ERR_PARAM;
    if (p->p < 1 || p->method < BC_LU_TORQUE || p->method > BC_LU_RECT || (p->delay != 0 && p->delay != 1) ||
        p->order < 0 || p->order > 2)
        return BC_ERR_PARAM;
    const float v[] = {p->L, p->R, p->ts, p->i_max, p->i_zero, p->v_max, p->k_phi, p->kp, p->ki, p->f_tick,
                       p->omega_min, p->theta_offset, p->l_adapt};
    for (unsigned j = 0; j < sizeof v / sizeof v[0]; ++j) {
        if (!isfinite(v[j])) return BC_ERR_PARAM;
    }
    if (!(p->L > 0.0f) || p->R < 0.0f || !(p->ts > 0.0f) || !(p->i_max > 0.0f) || p->i_zero < 0.0f ||
        !(p->i_zero < p->i_max) || !(p->v_max > 0.0f) || !(p->k_phi > 0.0f) || p->kp < 0.0f || p->ki < 0.0f ||
        p->l_adapt < 0.0f || p->l_adapt > 1.0f)
        return BC_ERR_PARAM;
    float f_max = 0.0f;
    for (int x = 0; x < 3; ++x) {
        for (int32_t j = 0; j < p->n; ++j) {
            float f = p->f[x][j];
            if (!isfinite(f)) return BC_ERR_PARAM;
            if (fabsf(f) > f_max) f_max = fabsf(f);
        }
    }
    if (!(f_max > 0.0f)) return BC_ERR_PARAM; /* no back-EMF: no torque lever */
    s->hall_p = (bc_hall_params){.f_tick = p->f_tick, .omega_min = p->omega_min, .theta_offset = p->theta_offset,
                                 .mode = p->hall_mode, .pll_edges = p->hall_pll_edges, .table = p->hall_table};
    if (bc_hall_init(&s->hall_p, &s->hall) != BC_OK) return BC_ERR_PARAM;
    s->pi_p = (bc_pi_params){.kp = p->kp, .ki = p->ki, .ts = p->ts,
                             .u_min = -p->v_max, .u_max = p->v_max};
    if (bc_pi_init(&s->pi_p, &s->pi) != BC_OK) return BC_ERR_PARAM;
    s->lever_min = 1e-3f * f_max;
    s->tol = 1e-4f * f_max * p->i_max;
    s->parity = 0;
    s->applied.kind = BC_LU_SAFE;
    s->applied.pos = 0;
    s->applied.neg = 1;
    s->applied.off = 2;
    s->applied.sig = 0;
    s->applied.duty = 0.0f;
    s->guard_p = (bc_guard_params){.i_max = p->i_max, .v_max = p->v_max};
    if (bc_guard_init(&s->guard_p, &s->guard) != BC_OK) return BC_ERR_PARAM;
    s->dir = 0;
    s->dcm = 0;
    s->t_first = 0.0f;
    s->d_mean = 0.0f;
    s->l_hat = p->L;
    for (int k = 0; k < 3; ++k) s->i_start[k] = s->i_end[k] = 0.0f;
    s->pred_plan = s->applied;
    s->pred_rising = 0;
    s->pred_speed = 0;
    s->sector = -1;
    s->seen = -1;
    return BC_OK;
}

/* All legs off, the reason in the flags; RECT's integrator is reset; the delay-1 prediction sees SAFE. */
static void go_safe(bc_lu_state *s, bc_ctrl_out *out, uint32_t why)
{
    bc_legs_off(out);
    out->flags |= why;
    out->diag[0] = -1.0f;
    out->diag[7] = -1.0f;
    s->applied.kind = BC_LU_SAFE;
    s->applied.duty = 0.0f;
    s->pred_plan.kind = BC_LU_SAFE;
    s->sector = -1;
    s->seen = -1;
    bc_pi_reset(&s->pi_p, &s->pi, 0.0f);
}

/* Inductance adaptation (see the header): compare the last step's predicted rise of the pair current with the
 * measured one, over a rising half period in normal conduction (F open at both ends) with a valid speed. */
static void adapt_l(const bc_lu_params *p, bc_lu_state *s, const float i_now[3])
{
    const bc_lu_plan *q = &s->pred_plan;
    if (q->kind != BC_LU_PAIR || !s->pred_rising) return; /* a rising half: off part, then on part to the end */
    int pos = q->pos, off = q->off;
    if (!s->pred_speed || fabsf(s->i_start[off]) > p->i_zero || fabsf(i_now[off]) > p->i_zero) return;
    float d_pred = s->i_end[pos] - s->i_start[pos], d_meas = i_now[pos] - s->i_start[pos];
    float th = 0.005f * p->i_max;
    if (!(fabsf(d_pred) > th) || !(fabsf(d_meas) > th) || (d_pred > 0.0f) != (d_meas > 0.0f)) return;
    float r = bc_clampf(d_pred / d_meas, 0.5f, 2.0f);
    s->l_hat = bc_clampf(s->l_hat * (1.0f + p->l_adapt * (r - 1.0f)), 0.25f * p->L, 4.0f * p->L);
}

/* The one-step model the parameters ask for: ordered (order = 1) or averaged. */
static void model_step(const bc_lu_params *p, const bc_lu_point *x, const bc_lu_plan *plan, int rising, float i[3])
{
    if (p->order) {
        bc_lu_predict_ordered(p, x, plan, rising, i);
    } else {
        bc_lu_predict(p, x, plan, i);
    }
}

/* RECT: PI on the pair current. Returns the unclamped duty, updates the integrator with the realised output. */
static float rect_duty(const bc_lu_params *p, bc_lu_state *s, const bc_lu_point *x, int pos, int neg, float t_ref)
{
    /* a reversed torque swaps the pair, whose back-EMF changes sign: bumpless, the integrator changes sign too */
    int dir = t_ref < 0.0f ? -1 : 1;
    if (dir != s->dir) {
        if (s->dir != 0) bc_pi_reset(&s->pi_p, &s->pi, -s->pi.x);
        s->dir = dir;
    }
    /* I* = min(|T*| / (2 k_phi), i_max);  i_m = the current of the non-commutated phase in the pair's direction:
     * -i_N while F's current is >= 0 (the positive side commutates), i_P while it is < 0 (= i_P = -i_N when F is open) */
    int off = 3 - pos - neg;
    float i_ref = fminf(fabsf(t_ref) / (2.0f * p->k_phi), p->i_max);
    float i_m = x->i[off] >= 0.0f ? -x->i[neg] : x->i[pos];
    float e = i_ref - i_m;
    /* u = k_p e + x (pair voltage, V);  D = 1/2 + u / (2 V);  realised u = (2 D - 1) V (anti-windup) */
    float u = bc_pi_output(&s->pi_p, &s->pi, e, 0.0f);
    float d = 0.5f + u / (2.0f * x->v_dc);
    float u_real = (2.0f * bc_clampf(d, 0.0f, 1.0f) - 1.0f) * x->v_dc;
    bc_pi_update(&s->pi_p, &s->pi, e, u, u_real);
    return d;
}

void bc_lu_step(const bc_lu_params *p, bc_lu_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    /* this sample is at a carrier valley (parity 0) or peak; the half period after it rises or falls */
    int rising_now = s->parity == 0;
    s->parity ^= 1;
    for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
    out->flags = 0u;
    for (int x = 0; x < 3; ++x) {
        out->leg[x].mode = BC_LEG_OFF;
        out->leg[x].duty = 0.0f;
    }

    /* angle and speed: Hall sector, edge timing, interpolation (bc_hall) */
    bc_hall_out h;
    bc_hall_step(&s->hall_p, &s->hall, in, &h);
    out->diag[4] = h.theta;
    out->diag[5] = h.omega_e;

    /* measurements, DC bus, hardware and software over-current trips: the input guard (bc_guard.h) */
    bc_lu_point x0;
    float v = in->v_dc, t_ref = in->ref;
    uint32_t why = bc_guard_step(&s->guard_p, &s->guard, in, x0.i);
    if (!h.valid) why |= BC_FLAG_HALL_INVALID;
    if (!isfinite(t_ref)) why |= BC_FLAG_BAD_INPUT;
    if (why) {
        go_safe(s, out, why);
        return;
    }
    x0.v_dc = v;
    x0.omega_m = h.omega_e / (float)p->p; /* 0 without a speed estimate (standstill) */
    bc_lu_params p_adapted;
    if (p->l_adapt > 0.0f) {
        adapt_l(p, s, x0.i);
        p_adapted = *p;
        p_adapted.L = s->l_hat;
        p = &p_adapted; /* every model and law below uses L_hat */
    }
    bc_lu_shapes(p, h.theta, x0.f);
    float t0 = bc_lu_torque(&x0);
    out->diag[2] = t0;

    /* the state at the start of the interval the new output applies to */
    bc_lu_point x1 = x0;
    float i_pred[3];
    float t_half = s->t_first; /* the model's mean torque over the half period in force (delay 0: predicted) */
    if (p->delay == 1) {
        /* i(k+1) from i(k) under the output in force over [k, k+1]; theta(k+1) = theta(k) + Omega_e T_s */
        if (p->order == 2) {
            int dry;
            t_half = bc_lu_mean_ordered(p, &x0, &s->applied, rising_now, x1.i, &dry);
        } else {
            model_step(p, &x0, &s->applied, rising_now, x1.i);
        }
        bc_lu_shapes(p, h.theta + h.omega_e * p->ts, x1.f);
        for (int k = 0; k < 3; ++k) i_pred[k] = x1.i[k];
    }

    /* the sector commanded: the Hall sector seen (nominal table), or with a calibrated table the one whose nominal
     * span holds the middle of the interval the new output applies to (bc_hall_commutate: at the nominal boundary,
     * never back while the rotor turns one way) */
    int sector = h.sector;
    if (p->hall_table.set) {
        float travel;
        sector = bc_hall_commutate(&s->hall_p, &h, in, ((float)p->delay + 0.5f) * p->ts, 1, 0.0f, s->sector, &s->seen,
                                   &travel);
    }
    s->sector = sector;
    s->seen = h.sector;

    /* the pair: the commanded sector's pos/neg, swapped for a negative torque; F the third phase */
    int pos = 0, neg = 1;
    (void)bc_sector_phases(sector, &pos, &neg);
    if (t_ref < 0.0f) {
        int t = pos;
        pos = neg;
        neg = t;
    }
    int off = 3 - pos - neg;
    int conducting = fabsf(x1.i[off]) > p->i_zero;

    bc_lu_plan plan = {BC_LU_PAIR, pos, neg, off, 0, 0.0f};
    int rising_out = p->delay == 1 ? !rising_now : rising_now; /* the half period the new output applies to */
    lu_memo memo; /* the ordered model's evaluations from x1 for this pair (with means where a period test follows) */
    memo_init(&memo, &x1, pos, neg, p->order == 2 && rising_out);
    if (rising_out) s->dcm = 0; /* set again below if the new period conducts discontinuously */
    float d;
    int deferred = 0; /* the end-value solve of normal conduction is left to after the mean law's test */
    float mode = conducting ? 1.0f : 0.0f;
    if (p->method == BC_LU_RECT) {
        d = rect_duty(p, s, &x0, pos, neg, t_ref);
    } else if (!conducting) {
        d = bc_lu_dn(p, &x1, pos, neg, t_ref, s->lever_min); /* normal conduction (9') */
        /* order 2 in a discontinuous period (the last one, or this one's first half, was): the mean law below
         * comes first and the end-value solve only if it does not apply (it is costly where the end value is flat) */
        deferred = p->order == 2 && (rising_out ? s->d_mean > 0.0f : s->dcm);
        if (p->order && !deferred) d = solve_pair(p, &memo, &x1, pos, neg, t_ref, rising_out, d, s->tol, 0);
    } else {
        /* commutation: (17') if F conducts the whole sample, D_s if it opens inside it */
        float t_x = bc_lu_extinction(p, &x1, pos, neg);
        d = t_x >= p->ts ? bc_lu_dc(p, &x1, pos, neg, t_ref, s->lever_min)
                         : bc_lu_ds(p, &x1, pos, neg, t_ref, s->lever_min);
        if (p->order) d = solve_pair(p, &memo, &x1, pos, neg, t_ref, rising_out, d, s->tol, 0);
        if (p->method == BC_LU_TORQUE && d > 1.0f) {
            /* torque still short at full duty: D_o mode if F's switch acts in the torque's direction */
            float fbar = sum3(x1.f) / 3.0f;
            float sig = x1.i[off] >= 0.0f ? 1.0f : -1.0f;
            float lam = x1.f[pos] - x1.f[neg];
            float lever = sig * (x1.f[off] - fbar) * (lam >= 0.0f ? 1.0f : -1.0f);
            if (lever > s->lever_min) {
                float d_zero, d_hold;
                bc_lu_do_bounds(p, &x1, pos, neg, &d_zero, &d_hold);
                d = bc_clampf(bc_lu_do(p, &x1, pos, neg, t_ref, s->lever_min), d_zero, d_hold);
                plan.kind = BC_LU_DO;
                plan.sig = sig > 0.0f ? 1 : -1;
                mode = 2.0f;
            }
        }
    }
    if (p->order == 2 && rising_out && plan.kind == BC_LU_PAIR && p->method != BC_LU_RECT) {
        /* a PWM period starts: if under the duty that gives a mean of T* over the whole period the current
         * stops at some instant (discontinuous conduction), the mean law replaces the end-value law. Where the
         * current does not stop under the end-value duty either, the period is continuous: nothing to solve. */
        bc_lu_plan trial = plan;
        float t_first;
        int dcm = deferred || period_dry(p, &memo, &x1, &trial, bc_clampf(d, 0.0f, 1.0f), &t_first);
        float guess = s->d_mean > 0.0f ? s->d_mean : d;
        s->d_mean = 0.0f;
        if (dcm) {
            float d_m = solve_pair(p, &memo, &x1, pos, neg, t_ref, 1, guess, s->tol, 2);
            if (period_dry(p, &memo, &x1, &trial, bc_clampf(d_m, 0.0f, 1.0f), &s->t_first)) {
                d = d_m;
                mode = 3.0f;
                s->dcm = 1;
                s->d_mean = bc_clampf(d_m, 0.0f, 1.0f); /* the next period's first guess */
            } else if (deferred) {
                d = solve_pair(p, &memo, &x1, pos, neg, t_ref, 1, d, s->tol, 0);
            }
        }
    } else if (p->order == 2 && s->dcm && plan.kind == BC_LU_PAIR && p->method != BC_LU_RECT) {
        /* the period's second half: its mean makes up for the first half's (the model's, from the
         * measurements with delay 1) */
        float d0 = s->applied.kind == BC_LU_PAIR ? s->applied.duty : d; /* the first half's: symmetric at rest */
        float d_m = solve_pair(p, &memo, &x1, pos, neg, 2.0f * t_ref - t_half, 0, d0, s->tol, 1);
        if (d_m >= 0.0f && d_m <= 1.0f) {
            d = d_m;
            mode = 3.0f;
        } else if (deferred) {
            /* the make-up is out of reach (e.g. a commutation in this half): the end value at least */
            d = solve_pair(p, &memo, &x1, pos, neg, t_ref, 0, d, s->tol, 0);
        }
    }
    if (isnan(d)) { /* only a degenerate measurement (e.g. v_dc ~ 1e-38) gets here */
        go_safe(s, out, BC_FLAG_BAD_INPUT);
        return;
    }
    if (d < 0.0f || d > 1.0f) out->flags |= BC_FLAG_SATURATED;
    plan.duty = bc_clampf(d, 0.0f, 1.0f);

    if (plan.kind == BC_LU_PAIR) {
        out->leg[pos].mode = BC_LEG_HIGH; /* S = +1: P's upper and N's lower switch on; S = -1: both off */
        out->leg[pos].duty = plan.duty;
        out->leg[neg].mode = BC_LEG_LOW;
        out->leg[neg].duty = plan.duty;
    } else {
        out->leg[pos].mode = BC_LEG_HIGH; /* incoming and non-commutated switches on, F chops with D_o */
        out->leg[pos].duty = 1.0f;
        out->leg[neg].mode = BC_LEG_LOW;
        out->leg[neg].duty = 1.0f;
        out->leg[off].mode = plan.sig > 0 ? BC_LEG_HIGH : BC_LEG_LOW;
        out->leg[off].duty = plan.duty;
    }

    /* the model's torque at the next sample, shapes frozen at theta(k) as in the paper's (8), (16), (23) */
    if (p->delay == 0) model_step(p, &x0, &plan, rising_now, i_pred);
    if (p->l_adapt > 0.0f) { /* the prediction over [k, k+1] the next step checks */
        s->pred_plan = p->delay == 1 ? s->applied : plan;
        s->pred_rising = rising_now;
        s->pred_speed = h.speed_valid;
        for (int k = 0; k < 3; ++k) {
            s->i_start[k] = x0.i[k];
            s->i_end[k] = i_pred[k];
        }
    }
    bc_lu_point xp = x0;
    for (int k = 0; k < 3; ++k) xp.i[k] = i_pred[k];
    s->applied = plan;

    out->diag[0] = mode;
    out->diag[1] = plan.duty;
    out->diag[3] = bc_lu_torque(&xp);
    out->diag[6] = x1.i[off];
    out->diag[7] = (float)sector;
}

/* bc_plant.c - switching-level BLDC plant. Model and rules in bc_plant.h and docs/plant.md. */
#include "bldc/bc_plant.h"

#include <math.h>
#include <string.h>

/* Layout of the integrated state y; the accumulators acc[] are integrated apart (acc_step). */
#define Y_I 0 /* three currents */
#define Y_TH 3
#define Y_OM 4
#define NY 5

/* the optional lanes are the last three */
typedef char bc_acc_opt_last[(BC_ACC_OPT + 3 == BC_ACC_N && BC_ACC_RR == BC_ACC_OPT + 1 &&
                              BC_ACC_FE == BC_ACC_OPT + 2) ? 1 : -1];

/* Local angle offset of phase x: theta_x = theta_e - PHI[x]. */
static const double PHI[3] = {0.0, BC_TWO_PI / 3.0, 2.0 * BC_TWO_PI / 3.0};
static const double COS_PHI[3] = {1.0, -0.5, -0.5};
static const double SIN_PHI[3] = {0.0, 0.86602540378443864676, -0.86602540378443864676};

#define MAX_ZERO_LENGTH_EVENTS 64
#define ROOT_MAX_ITER 80

/* Force inlining where a function's constant arguments select its branches (GCC and Clang; elsewhere a hint). */
#if defined(__GNUC__)
#define BC_ALWAYS_INLINE inline __attribute__((always_inline))
#define BC_NOINLINE __attribute__((noinline))
#else
#define BC_ALWAYS_INLINE inline
#define BC_NOINLINE
#endif

typedef bc_plant_aux aux_t; /* the circuit quantities computed with a derivative (bc_plant.h) */

static BC_ALWAYS_INLINE uint32_t watch_eval(const bc_plant_params *p, const bc_plant_state *s, const double *y,
                                            const aux_t *a, int dir_om, double *g);
static int faults_apply(const bc_plant_params *p, bc_plant_state *s);

double bc_plant_t_half(const bc_plant_params *p) { return 0.5 / p->f_pwm; }

/* The longest step. Half a PWM period by default, widened by 1e-9 of itself so that a step from the start of a
 * half period reaches its end in one piece instead of leaving a sliver step of rounding size (k T/2 + T/2 is
 * not always (k + 1) T/2 in floating point); a step never passes its target anyway. */
static double h_max_of(const bc_plant_params *p)
{
    double th = bc_plant_t_half(p);
    return (p->h_max > 0.0 && p->h_max < th) ? p->h_max : th * (1.0 + 1e-9);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* back-EMF shapes and cogging at an angle inside the current pieces                                          */

/* cos and sin of th: rotated from a reference angle ref = {th_r, cos th_r, sin th_r} when th is within 0.03 rad of
 * it, by the Taylor series of cos and sin of the difference (truncation below 2e-17), else from libm. The reference
 * is always a libm value (an anchor: shapes_at passes the reference on as the evaluation's cs when it rotated from
 * it), so no rotation is ever rotated again and the error stays at a few ulp however long the run: the RK4 stages
 * and the step ends within 0.03 rad of the last libm angle cost no libm call. Returns 1 if it rotated from ref. */
/* out of line: gcc fuses the pair into one sincos call here, not where cos_sin is inlined */
static BC_NOINLINE void cos_sin_libm(double th, double *c, double *sn)
{
    *c = cos(th);
    *sn = sin(th);
}

/* cos d and sin d for |d| < 0.03 by their Taylor series to d^6 and d^7 (truncation below 2e-17), with constant
 * coefficients and split in two halves (d^4 times the higher terms): multiplications only, and a shorter chain of
 * dependent operations than the nested form (the derivative's evaluations wait on it). A division by 12.0 is not
 * one by its reciprocal, so the compiler keeps it: the nested form with divisions cost five a call. */
static BC_ALWAYS_INLINE void cs_series(double d, double *cd, double *sd)
{
    const double d2 = d * d, d4 = d2 * d2;
    *cd = (1.0 - 0.5 * d2) + d4 * (1.0 / 24.0 - d2 * (1.0 / 720.0));
    *sd = d * ((1.0 - d2 * (1.0 / 6.0)) + d4 * (1.0 / 120.0 - d2 * (1.0 / 5040.0)));
}

static BC_ALWAYS_INLINE int cos_sin(double th, const double *ref, double *c, double *sn, double lim)
{
    double d = ref ? th - ref[0] : 1.0;
    if (fabs(d) < lim) {
        double cd, sd;
        cs_series(d, &cd, &sd);
        *c = ref[1] * cd - ref[2] * sd;
        *sn = ref[2] * cd + ref[1] * sd;
        return 1;
    }
    cos_sin_libm(th, c, sn);
    return 0;
}

/* cs = the anchor of an evaluation at th: ref if cos_sin rotated from it, else {th, c, sn} (libm) */
static BC_ALWAYS_INLINE void cs_anchor(double *cs, int rotated, const double *ref, double th, double c, double sn)
{
    if (rotated) {
        cs[0] = ref[0];
        cs[1] = ref[1];
        cs[2] = ref[2];
    } else {
        cs[0] = th;
        cs[1] = c;
        cs[2] = sn;
    }
}

/* Sinusoidal shapes (one Fourier order, fz_n = 2) near an anchor {th_a, c_a, s_a}: k_x(th_a + d) = ks (a_x0 +
 * a_x1 cos(th_a + d) + b_x1 sin(th_a + d)) = al_x + be_x cos d + ga_x sin d, dk_x/dth = ga_x cos d - be_x sin d: the
 * rotation from the anchor folded into the coefficients, once a step for its four derivative evaluations. */
typedef struct sin_fold {
    int on;                      /* 1: set (an anchor and one order) */
    double th_a, c_a, s_a;       /* the anchor */
    double al[3], be[3], ga[3];  /* V s/rad */
} sin_fold;

static BC_ALWAYS_INLINE void sin_fold_init(const bc_plant_state *s, sin_fold *f)
{
    const double *cs = s->work.cs;
    f->on = s->fz_n == 2 && cs[0] != HUGE_VAL;
    if (!f->on) return;
    const double ks = s->k_scale;
    f->th_a = cs[0];
    f->c_a = cs[1];
    f->s_a = cs[2];
    for (int x = 0; x < 3; ++x) {
        const double a1 = s->fz_a[x][1], b1 = s->fz_b[x][1];
        f->al[x] = ks * s->fz_a[x][0];
        f->be[x] = ks * (a1 * cs[1] + b1 * cs[2]);
        f->ga[x] = ks * (b1 * cs[1] - a1 * cs[2]);
    }
}

/* k_x(th) of the three phases and, if dk is non-null, dk_x/dth (tables: the piece's slope; Fourier: the series
 * differentiated term by term, sum_m m (y_m cos - x_m sin)). A Fourier shape needs cos and sin of th: from ref
 * (cos_sin) and, if cs is non-null, its anchor returned there: {th_a, cos th_a, sin th_a} of the libm angle it was
 * rotated from, or of th itself (cs[0] = HUGE_VAL if none was needed). */
static BC_ALWAYS_INLINE void shapes_at(const bc_plant_params *restrict p, const bc_plant_state *restrict s, double th,
                             double *restrict k, double *restrict dk, const double *ref, double *cs,
                             const sin_fold *fo)
{
    if (cs) { /* none (table shapes); the zeros keep the aux fully defined */
        cs[0] = HUGE_VAL;
        cs[1] = cs[2] = 0.0;
    }
    const double ks = s->k_scale; /* the magnets' flux at temperature (bc_plant_set_thermal) */
    if (s->emf_tables) { /* the usual case (tables and trapezoids): one multiply-add per phase */
        for (int x = 0; x < 3; ++x) {
            const bc_emf_piece *pc = &s->piece[x];
            k[x] = ks * (pc->k0 + pc->slope * (th - pc->lo));
            if (dk) dk[x] = ks * pc->slope;
        }
        return;
    }
    /* an evaluation that hands its anchor on (cs: the step ends) takes a new one from libm half-way through the
     * rotation's range, so that the RK4 stages of the next step, which cannot, stay inside it */
    const double lim = cs ? 0.015 : 0.03;
    if (fo && fo->on && fabs(th - fo->th_a) < lim) { /* a sinusoid near the step's anchor (sin_fold) */
        double cd, sd;
        cs_series(th - fo->th_a, &cd, &sd);
        for (int x = 0; x < 3; ++x) k[x] = fo->al[x] + (fo->be[x] * cd + fo->ga[x] * sd);
        if (dk) {
            for (int x = 0; x < 3; ++x) dk[x] = fo->ga[x] * cd - fo->be[x] * sd;
        }
        if (cs) {
            cs[0] = fo->th_a;
            cs[1] = fo->c_a;
            cs[2] = fo->s_a;
        }
        return;
    }
    if (s->fz_n > 0) { /* three Fourier series in the global angle: one recurrence cos(m th), sin(m th) for all */
        double c, sn;
        const int rot = cos_sin(th, ref, &c, &sn, lim);
        if (cs) cs_anchor(cs, rot, ref, th, c, sn);
        /* m = 0 (cos 0 = 1, sin 0 = 0, no derivative) and m = 1 (cos th, sin th) as the loop would add them */
        double k0 = s->fz_a[0][0], k1 = s->fz_a[1][0], k2 = s->fz_a[2][0], d0 = 0.0, d1 = 0.0, d2 = 0.0;
        double cm = c, sm = sn;
        /* the recurrence's next cos, sin only where another order follows (a sinusoid has one order: none) */
        for (int32_t m = 1; m < s->fz_n;) {
            k0 += s->fz_a[0][m] * cm + s->fz_b[0][m] * sm;
            k1 += s->fz_a[1][m] * cm + s->fz_b[1][m] * sm;
            k2 += s->fz_a[2][m] * cm + s->fz_b[2][m] * sm;
            if (dk) { /* dk/dth = sum_m m (b_m cos - a_m sin) */
                const double fm = (double)m;
                d0 += fm * (s->fz_b[0][m] * cm - s->fz_a[0][m] * sm);
                d1 += fm * (s->fz_b[1][m] * cm - s->fz_a[1][m] * sm);
                d2 += fm * (s->fz_b[2][m] * cm - s->fz_a[2][m] * sm);
            }
            if (++m >= s->fz_n) break;
            const double cn = cm * c - sm * sn;
            sm = sm * c + cm * sn;
            cm = cn;
        }
        k[0] = ks * k0;
        k[1] = ks * k1;
        k[2] = ks * k2;
        if (dk) {
            dk[0] = ks * d0;
            dk[1] = ks * d1;
            dk[2] = ks * d2;
        }
        return;
    }
    int trig = 0;
    double c = 0.0, sn = 0.0;
    for (int x = 0; x < 3; ++x) {
        const bc_emf_shape *sh = &p->emf[x];
        if (sh->kind == BC_EMF_TABLE) {
            k[x] = ks * (s->piece[x].k0 + s->piece[x].slope * (th - s->piece[x].lo));
            if (dk) dk[x] = ks * s->piece[x].slope;
            continue;
        }
        if (!trig) {
            const int rot = cos_sin(th, ref, &c, &sn, lim);
            trig = 1;
            if (cs) cs_anchor(cs, rot, ref, th, c, sn);
        }
        /* cos and sin of the local angle th - PHI[x] by rotation, then harmonics by recurrence */
        double c1 = c * COS_PHI[x] + sn * SIN_PHI[x];
        double s1 = sn * COS_PHI[x] - c * SIN_PHI[x];
        double cm = 1.0, sm = 0.0, acc = 0.0, acc_d = 0.0;
        for (int32_t m = 0; m < sh->n; ++m) {
            acc += sh->x[m] * cm + sh->y[m] * sm;
            if (dk) acc_d += (double)m * (sh->y[m] * cm - sh->x[m] * sm);
            double cn = cm * c1 - sm * s1;
            sm = sm * c1 + cm * s1;
            cm = cn;
        }
        k[x] = ks * acc;
        if (dk) dk[x] = ks * acc_d;
    }
}

static double cogging_at(const bc_plant_params *p, const bc_plant_state *s, double th)
{
    double th_m = (th + BC_TWO_PI * (double)s->turns) / (double)p->p;
    double tau = 0.0;
    for (int32_t j = 0; j < p->n_cog; ++j) {
        tau += p->cog_amp[j] * sin(p->cog_order[j] * th_m + p->cog_phase[j]);
    }
    return tau;
}

static double sign_of(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

/* ---------------------------------------------------------------------------------------------------------- */
/* the derivative and the power flows                                                                         */

/* dy = f(y) for the five states (i_a, i_b, i_c, theta, omega) under the present conduction states, and (a != 0) the
 * circuit quantities at y (with dk/dtheta if WANT_DK) for the watches, the outputs and the power flows. ref: cos and
 * sin at a nearby angle for Fourier shapes (cos_sin), or 0.
 *
 * The currents: with U_x = up_x v_src + U0_x the terminal sources, M = R_src W + diag(r) their resistance matrix
 * (W = up up^T, or the averaged legs' M_xy), u = U - (M + R I) i - e and v_n = c.u / n over the n connected
 * phases, L di_x/dt = c_x (u_x - v_n), i.e. di/dt = P u with P = g (C - c c^T / n), g = 1/L (0 with fewer than
 * two connected phases). topology_set precomputes P (M + R I), P up and P U0, so that a derivative costs a 3 x 3
 * product: di/dt = v_src P up + P U0 - P (M + R I) i - g c_x (e_x - c.e / n). */
static BC_ALWAYS_INLINE void aux_terminals(const bc_plant_params *restrict p, const bc_plant_state *restrict s, const double *restrict y,
                          aux_t *restrict a);

#define WANT_DK 1 /* core(): dk/dtheta in the aux (the power flows need it) */
#define WANT_V 2  /* core(): the terminal voltages and the star point in the aux even if no phase is open */

static BC_ALWAYS_INLINE void core_at(const bc_plant_params *restrict p, const bc_plant_state *restrict s,
                                     const double *restrict y, double *restrict dy, aux_t *restrict a, int want,
                                     const double *ref, const sin_fold *fo)
{
    const double i0 = y[Y_I], i1 = y[Y_I + 1], i2 = y[Y_I + 2];
    const double th = y[Y_TH], om = y[Y_OM];
    double k[3], dk[3], cs[3];
    shapes_at(p, s, th, k, (want & WANT_DK) ? dk : 0, ref, a ? cs : 0, fo);
    const double e0 = om * k[0], e1 = om * k[1], e2 = om * k[2];
    if (s->tc_gain != 0.0) {
        const double *B = s->tc_b;
        const double eb = s->tc_cn[0] * e0 + s->tc_cn[1] * e1 + s->tc_cn[2] * e2;
        const double vs = s->v_src;
        dy[Y_I] = vs * s->tc_pup[0] + s->tc_pu0[0] - (B[0] * i0 + B[1] * i1 + B[2] * i2) - s->tc_pc[0] * (e0 - eb);
        dy[Y_I + 1] = vs * s->tc_pup[1] + s->tc_pu0[1] - (B[3] * i0 + B[4] * i1 + B[5] * i2) - s->tc_pc[1] * (e1 - eb);
        dy[Y_I + 2] = vs * s->tc_pup[2] + s->tc_pu0[2] - (B[6] * i0 + B[7] * i1 + B[8] * i2) - s->tc_pc[2] * (e2 - eb);
    } else {
        dy[Y_I] = dy[Y_I + 1] = dy[Y_I + 2] = 0.0;
    }
    double dh = 0.0;
    if (s->hold_on) { /* the ideal limiter: the duty d* that holds di_x/dt = 0 (topology_set put d = 0 in up) */
        const int x = s->hold_x;
        const double cx = s->v_src * s->tc_hcol[x];
        if (cx > 0.0) {
            dh = -dy[Y_I + x] / cx;
            for (int j = 0; j < 3; ++j) dy[Y_I + j] += dh * s->v_src * s->tc_hcol[j];
            dy[Y_I + x] = 0.0;
        }
    }
    const double tau_cog = p->n_cog > 0 ? cogging_at(p, s, th) : 0.0;
    const double tau = k[0] * i0 + k[1] * i1 + k[2] * i2 + tau_cog;
    const double t_prop = s->prop_on ? p->k_q * om * fabs(om) : 0.0; /* smooth through 0: no event needed */
    const double tau_net = tau - s->tau_load - t_prop;
    double t_fric = 0.0, t_fe = 0.0, sgn = 0.0;
    if (s->drag_on && !s->stuck) {
        /* the Coulomb-like terms take the sign of the motion at the step start (work.wdir, valid inside a step):
         * the speed keeps it up to the W_OMEGA event, and RK4 stages evaluated past the zero must not flip it
         * (their flipped drags cancel in the RK4 sum and the rotor would coast at a small constant speed) */
        sgn = (s->work.valid && s->work.wdir != 0) ? (double)s->work.wdir : sign_of(om);
        if (sgn == 0.0) sgn = sign_of(tau_net);
        t_fric = p->B * om + p->tau_c * sgn;
        /* iron-loss drag (bc_plant.h): eddy k_fe_e omega sum k^2, hysteresis p k_fe_h sign(omega), excess
         * k_fe_x sign(omega) |omega|^0.5 sum |k|^1.5 */
        if (s->fe_on) {
            t_fe = p->k_fe_e * om * (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]) + s->fe_tc * sgn;
            if (p->k_fe_x > 0.0) {
                const double ak0 = fabs(k[0]), ak1 = fabs(k[1]), ak2 = fabs(k[2]);
                t_fe += p->k_fe_x * sgn * sqrt(fabs(om)) * (ak0 * sqrt(ak0) + ak1 * sqrt(ak1) + ak2 * sqrt(ak2));
            }
        }
    }
    dy[Y_TH] = (double)p->p * om;
    dy[Y_OM] = (p->mech == BC_MECH_DYNAMIC && !s->stuck) ? (tau_net - t_fric - t_fe) * s->work.inv_J : 0.0;
    if (!a) return;
    a->k[0] = k[0];
    a->k[1] = k[1];
    a->k[2] = k[2];
    if (want & WANT_DK) {
        a->dk[0] = dk[0];
        a->dk[1] = dk[1];
        a->dk[2] = dk[2];
    }
    a->cs[0] = cs[0];
    a->cs[1] = cs[1];
    a->cs[2] = cs[2];
    a->e[0] = e0;
    a->e[1] = e1;
    a->e[2] = e2;
    a->tau = tau;
    a->tau_cog = tau_cog;
    a->tau_net = tau_net;
    a->tau_fe = t_fe;
    a->t_fric = t_fric;
    a->t_prop = t_prop;
    a->sgn = sgn;
    a->n_conn = s->tc_n;
    a->dh = dh;
    /* the circuit quantities: DC current and bus, and the terminals v_x = up v_bus + U0 - r i (averaged legs with
     * R_src: up v_src - R_src w_x + U0 - r i), the open terminals floating at e + v_n; the terminals only where
     * something reads them (an open phase's watches, the trace's lanes, the outputs) */
    const double idc = s->tc_up[0] * i0 + s->tc_up[1] * i1 + s->tc_up[2] * i2 + (s->hold_on ? dh * y[Y_I + s->hold_x] : 0.0);
    const double vbus = s->v_src - p->R_src * idc;
    a->idc = idc;
    a->vbus = vbus;
    double w0 = 0.0, w1 = 0.0, w2 = 0.0;
    if (s->tc_msrc) {
        const double *m = s->tc_msrc_m;
        w0 = m[0] * i0 + m[1] * i1 + m[2] * i2;
        w1 = m[3] * i0 + m[4] * i1 + m[5] * i2;
        w2 = m[6] * i0 + m[7] * i1 + m[8] * i2;
        a->p_rsrc = p->R_src * (i0 * w0 + i1 * w1 + i2 * w2);
    } else {
        a->p_rsrc = p->R_src * idc * idc;
    }
    a->w[0] = w0;
    a->w[1] = w1;
    a->w[2] = w2;
    if ((want & WANT_V) || s->tc_n < 3 || (s->acc_mask & (1u << BC_ACC_VA))) aux_terminals(p, s, y, a);
}

/* The terminals v_x = up v_bus + U0 - r i (averaged legs with R_src: up v_src - R_src w_x + U0 - r i), the open
 * terminals floating at e + v_n, and v_n, into a (whose e, w, vbus are set). */
static BC_ALWAYS_INLINE void aux_terminals(const bc_plant_params *restrict p, const bc_plant_state *restrict s, const double *restrict y,
                          aux_t *restrict a)
{
    const double i0 = y[Y_I], i1 = y[Y_I + 1], i2 = y[Y_I + 2];
    const double e0 = a->e[0], e1 = a->e[1], e2 = a->e[2], w0 = a->w[0], w1 = a->w[1], w2 = a->w[2];
    const double vbus = a->vbus;
    const double R = s->r_ph;
    const double r0 = s->tc_r[0], r1 = s->tc_r[1], r2 = s->tc_r[2];
    double v0, v1, v2;
    if (s->tc_msrc) {
        v0 = s->tc_up[0] * s->v_src - p->R_src * w0 + s->tc_u0[0] - r0 * i0;
        v1 = s->tc_up[1] * s->v_src - p->R_src * w1 + s->tc_u0[1] - r1 * i1;
        v2 = s->tc_up[2] * s->v_src - p->R_src * w2 + s->tc_u0[2] - r2 * i2;
    } else {
        v0 = s->tc_up[0] * vbus + s->tc_u0[0] - r0 * i0;
        v1 = s->tc_up[1] * vbus + s->tc_u0[1] - r1 * i1;
        v2 = s->tc_up[2] * vbus + s->tc_u0[2] - r2 * i2;
    }
    if (s->hold_on) { /* the hold leg's d* v_bus (its up is 0 in the coefficients) */
        const double vh = a->dh * vbus;
        if (s->hold_x == 0) v0 += vh;
        else if (s->hold_x == 1) v1 += vh;
        else v2 += vh;
    }
    const double u0 = v0 - R * i0 - e0, u1 = v1 - R * i1 - e1, u2 = v2 - R * i2 - e2;
    const double c0 = s->tc_conn[0], c1 = s->tc_conn[1], c2 = s->tc_conn[2];
    const double vn = s->tc_n > 0 ? (c0 * u0 + c1 * u1 + c2 * u2) * s->tc_inv_n : 0.5 * vbus - (e0 + e1 + e2) / 3.0;
    a->v[0] = c0 != 0.0 ? v0 : e0 + vn;
    a->v[1] = c1 != 0.0 ? v1 : e1 + vn;
    a->v[2] = c2 != 0.0 ? v2 : e2 + vn;
    a->vn = vn;
}

/* core() out of line (the integrator's step end inlines core_at) */
static void core(const bc_plant_params *restrict p, const bc_plant_state *restrict s, const double *restrict y,
                 double *restrict dy, aux_t *restrict a, int want, const double *ref)
{
    core_at(p, s, y, dy, a, want, ref, 0);
}

/* d tau_cog/dt = omega_m sum_j amp_j order_j cos(order_j theta_m + phase_j). */
static double cogging_rate(const bc_plant_params *p, const bc_plant_state *s, double th, double om)
{
    double th_m = (th + BC_TWO_PI * (double)s->turns) / (double)p->p;
    double d = 0.0;
    for (int32_t j = 0; j < p->n_cog; ++j) {
        d += p->cog_amp[j] * p->cog_order[j] * cos(p->cog_order[j] * th_m + p->cog_phase[j]);
    }
    return om * d;
}

/* The power flows integrated in acc[] (bc_plant.h's BC_ACC_FIELDS) at state y, f, and their time derivatives along
 * the circuit equations, fd = df/dt (chain rule with dy = f(y), the aux a of core(..., WANT_DK) at y). Every
 * rate is a smooth function of the state inside a step (the conduction states, the drags' sign and the shapes'
 * pieces are fixed there), so the corrected trapezoid rule (acc_step) integrates it to O(h^5); and because the
 * rates of the energy balance add up to dW_L/dt identically, so do their derivatives to d^2W_L/dt^2. Only the lanes
 * of s->acc_lane[] are computed: those the parameters can make nonzero, and the trace's (terminal voltages, star
 * point, DC current) only when acc_on asks for them. */
static BC_ALWAYS_INLINE void lanes_at(const bc_plant_params *restrict p, const bc_plant_state *restrict s,
                            const double *restrict y, const double *restrict dy, const aux_t *restrict a,
                            double *restrict f, double *restrict fd, const int edge)
{
    /* the currents and their rates read in place: copies into local arrays, stored one by one and then loaded in
     * pairs by the vectorised loops below, would wait for the stores (failed store-to-load forwarding) */
    const double *i = y + Y_I, *di = dy + Y_I;
    const double om = y[Y_OM], dom = dy[Y_OM], dth = dy[Y_TH];
    const double R = s->r_ph, R_src = p->R_src;
    const uint32_t on = s->acc_mask;
    double dkt[3], de[3], sq[3];
    for (int x = 0; x < 3; ++x) {
        dkt[x] = a->dk[x] * dth;             /* dk/dt */
        de[x] = dom * a->k[x] + om * dkt[x]; /* de/dt = domega/dt k + omega dk/dt */
        sq[x] = i[x] * i[x];
    }
    double didc = s->tc_up[0] * di[0] + s->tc_up[1] * di[1] + s->tc_up[2] * di[2];
    /* the hold leg's duty d* and its rate d(d^*)/dt = ((B di)_x + pc_x (de_x - sum cn de)) / (v_src c_x) (R_src = 0) */
    double ddh = 0.0;
    if (s->hold_on) {
        const int x = s->hold_x;
        const double cx = s->v_src * s->tc_hcol[x];
        if (cx > 0.0) {
            const double *B = s->tc_b + 3 * x;
            const double deb = s->tc_cn[0] * de[0] + s->tc_cn[1] * de[1] + s->tc_cn[2] * de[2];
            ddh = (B[0] * di[0] + B[1] * di[1] + B[2] * di[2] + s->tc_pc[x] * (de[x] - deb)) / cx;
        }
        didc += ddh * i[x] + a->dh * di[x];
    }
    const double dvbus = -R_src * didc;

    f[BC_ACC_SRC] = s->v_src * a->idc;
    fd[BC_ACC_SRC] = s->v_src * didc;
    if (!edge) f[BC_ACC_CU] = R * (sq[0] + sq[1] + sq[2]);
    fd[BC_ACC_CU] = 2.0 * R * (i[0] * di[0] + i[1] * di[1] + i[2] * di[2]);
    if (!edge) f[BC_ACC_EMF] = a->e[0] * i[0] + a->e[1] * i[1] + a->e[2] * i[2];
    fd[BC_ACC_EMF] = de[0] * i[0] + de[1] * i[1] + de[2] * i[2] + a->e[0] * di[0] + a->e[1] * di[1] + a->e[2] * di[2];
    if (!edge) {
        f[BC_ACC_LOAD] = (s->tau_load + a->t_prop) * om;
        fd[BC_ACC_LOAD] = (s->tau_load + 3.0 * a->t_prop) * dom; /* d(k_q omega^2 |omega|)/dt = 3 k_q omega |omega| */
    }
    /* dtau/dt = sum_x (k_x di_x/dt + p omega dk_x/dtheta i_x) + dtau_cog/dt */
    double dtau = 0.0;
    for (int x = 0; x < 3; ++x) dtau += a->k[x] * di[x] + (double)p->p * om * a->dk[x] * i[x];
    if (on & (1u << BC_ACC_COG)) {
        double dcog = cogging_rate(p, s, y[Y_TH], om);
        dtau += dcog;
        if (!edge) {
            f[BC_ACC_COG] = a->tau_cog * om;
            fd[BC_ACC_COG] = dcog * om + a->tau_cog * dom;
        }
    }
    fd[BC_ACC_TAU] = dtau;
    fd[BC_ACC_TAU2] = 2.0 * a->tau * dtau;
    for (int x = 0; x < 3; ++x) fd[BC_ACC_I2A + x] = 2.0 * i[x] * di[x];
    if (!edge) {
        f[BC_ACC_TAU] = a->tau;
        f[BC_ACC_TAU2] = a->tau * a->tau;
        for (int x = 0; x < 3; ++x) f[BC_ACC_I2A + x] = sq[x];
    }
    if (on & (1u << BC_ACC_RSRC)) {
        double dw = 0.0;
        if (s->tc_msrc) {
            const double *m = s->tc_msrc_m;
            for (int x = 0; x < 3; ++x) {
                double dwx = m[3 * x] * di[0] + m[3 * x + 1] * di[1] + m[3 * x + 2] * di[2];
                dw += di[x] * a->w[x] + i[x] * dwx;
            }
        } else {
            dw = 2.0 * a->idc * didc;
        }
        f[BC_ACC_RSRC] = a->p_rsrc;
        fd[BC_ACC_RSRC] = R_src * dw;
    }
    if (on & (1u << BC_ACC_SW)) {
        f[BC_ACC_SW] = s->tc_rsw[0] * sq[0] + s->tc_rsw[1] * sq[1] + s->tc_rsw[2] * sq[2];
        fd[BC_ACC_SW] = 2.0 * (s->tc_rsw[0] * i[0] * di[0] + s->tc_rsw[1] * i[1] * di[1] + s->tc_rsw[2] * i[2] * di[2]);
    }
    /* |i| and its rate: a diode carries its current one way (D_L: i >= 0, D_U: i <= 0), also at the instant it starts
     * to conduct from i = 0, where sign(i) would be 0 but d|i|/dt = |di/dt| */
    double ab[3], sg[3];
    if (on & ((1u << BC_ACC_DIODE) | (1u << BC_ACC_OPT))) {
        for (int x = 0; x < 3; ++x) {
            ab[x] = fabs(i[x]);
            sg[x] = s->cond[x] == BC_COND_D_L ? 1.0 : (s->cond[x] == BC_COND_D_U ? -1.0 : sign_of(i[x]));
        }
    }
    if (on & (1u << BC_ACC_DIODE)) {
        double fdi = 0.0, fdd = 0.0;
        for (int x = 0; x < 3; ++x) {
            if (s->tc_dio[x] == 0.0) continue;
            fdi += s->tc_dio[x] * (p->V_f + p->r_d * ab[x]) * ab[x];
            fdd += s->tc_dio[x] * (p->V_f + 2.0 * p->r_d * ab[x]) * sg[x] * di[x];
        }
        f[BC_ACC_DIODE] = fdi;
        fd[BC_ACC_DIODE] = fdd;
    }
    if (!edge && (on & (1u << BC_ACC_FRIC))) {
        f[BC_ACC_FRIC] = a->t_fric * om;
        fd[BC_ACC_FRIC] = a->sgn != 0.0 ? (2.0 * p->B * om + p->tau_c * a->sgn) * dom : 0.0;
    }
    if (on & (1u << BC_ACC_VA)) { /* the trace's lanes: terminal voltages, star point, DC current */
        double dv[3], du[3];
        if (s->tc_msrc) {
            const double *m = s->tc_msrc_m;
            for (int x = 0; x < 3; ++x) {
                double dwx = m[3 * x] * di[0] + m[3 * x + 1] * di[1] + m[3 * x + 2] * di[2];
                dv[x] = -R_src * dwx - s->tc_r[x] * di[x];
            }
        } else {
            for (int x = 0; x < 3; ++x) dv[x] = s->tc_up[x] * dvbus - s->tc_r[x] * di[x];
        }
        if (s->hold_on) dv[s->hold_x] += ddh * a->vbus + a->dh * dvbus;
        for (int x = 0; x < 3; ++x) du[x] = dv[x] - R * di[x] - de[x];
        const double dvn = s->tc_n > 0 ? (s->tc_conn[0] * du[0] + s->tc_conn[1] * du[1] + s->tc_conn[2] * du[2]) *
                                             s->tc_inv_n
                                       : 0.5 * dvbus - (de[0] + de[1] + de[2]) / 3.0;
        for (int x = 0; x < 3; ++x) {
            f[BC_ACC_VA + x] = a->v[x];
            fd[BC_ACC_VA + x] = s->tc_conn[x] != 0.0 ? dv[x] : de[x] + dvn;
        }
        f[BC_ACC_VN] = a->vn;
        fd[BC_ACC_VN] = dvn;
        f[BC_ACC_IDC] = a->idc;
        fd[BC_ACC_IDC] = didc;
    }
    if (!(on & (1u << BC_ACC_OPT))) return; /* the optional loss lanes have zero rates (bc_plant.h) */
    double swa = 0.0, swd = 0.0, rra = 0.0, rrd = 0.0;
    for (int x = 0; x < 3; ++x) {
        swa += s->tc_swk[x] * ab[x];
        swd += s->tc_swk[x] * sg[x] * di[x];
        rra += s->tc_rrk[x] * ab[x];
        rrd += s->tc_rrk[x] * sg[x] * di[x];
    }
    f[BC_ACC_SWLOSS] = a->vbus * swa;
    fd[BC_ACC_SWLOSS] = dvbus * swa + a->vbus * swd;
    f[BC_ACC_RR] = a->vbus * rra;
    fd[BC_ACC_RR] = dvbus * rra + a->vbus * rrd;
    f[BC_ACC_FE] = a->tau_fe * om;
    fd[BC_ACC_FE] = 0.0;
    if (s->fe_on && a->sgn != 0.0) {
        /* p_fe = k_fe_e omega^2 sum k^2 + p k_fe_h sgn omega + k_fe_x sgn omega |omega|^0.5 sum |k|^1.5 */
        const double *k = a->k;
        double k2 = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
        double dk2 = 2.0 * (k[0] * dkt[0] + k[1] * dkt[1] + k[2] * dkt[2]);
        double d = p->k_fe_e * (2.0 * om * dom * k2 + om * om * dk2) + s->fe_tc * a->sgn * dom;
        if (p->k_fe_x > 0.0) {
            double k15 = 0.0, dk15 = 0.0;
            for (int x = 0; x < 3; ++x) {
                double sk = sqrt(fabs(k[x]));
                k15 += fabs(k[x]) * sk;
                dk15 += 1.5 * sk * sign_of(k[x]) * dkt[x];
            }
            double so = sqrt(fabs(om));
            d += p->k_fe_x * a->sgn * (1.5 * so * dom * k15 + om * so * dk15);
        }
        fd[BC_ACC_FE] = d;
    }
}

static void lanes(const bc_plant_params *restrict p, const bc_plant_state *restrict s, const double *restrict y,
                  const double *restrict dy, const aux_t *restrict a, double *restrict f, double *restrict fd)
{
    lanes_at(p, s, y, dy, a, f, fd, 0);
}

/* The lanes after a gate edge that changed only the conduction coefficients (switch_update): the state, the back-EMFs,
 * the torque and the rotor's rates are those of the same instant, so the rates that depend on nothing else (copper,
 * EMF, torque, torque^2 and i^2 values, load, friction, cogging) are already in f, fd; those that depend on di/dt
 * or on the conduction coefficients are recomputed by the same expressions (bit for bit what lanes() gives). */
static void lanes_edge(const bc_plant_params *restrict p, const bc_plant_state *restrict s, const double *restrict y,
                       const double *restrict dy, const aux_t *restrict a, double *restrict f, double *restrict fd)
{
    lanes_at(p, s, y, dy, a, f, fd, 1);
}

/* acc[] over a step of length h from (f0, fd0) to (f1, fd1): the corrected trapezoid rule (bc_plant.h). Every lane in
 * one loop over lanes 0 .. n - 1: the rates of the lanes not integrated are held at zero (lanes_select). */
static BC_ALWAYS_INLINE void acc_step(double *restrict acc, int n, double h, const double *restrict f0, const double *restrict fd0,
                     const double *restrict f1, const double *restrict fd1)
{
    const double a = 0.5 * h, b = h * h / 12.0;
    /* loops of a fixed length (unrolled, no remainder loop), the one that covers lanes 0 .. n - 1: the rates of the
     * lanes beyond n are zero, so adding them changes nothing */
    if (n <= BC_ACC_COG) { /* the metric lanes and friction */
        for (int j = 0; j < BC_ACC_COG; ++j) acc[j] += a * (f0[j] + f1[j]) + b * (fd0[j] - fd1[j]);
    } else if (n <= BC_ACC_VA) {
        for (int j = 0; j < BC_ACC_VA; ++j) acc[j] += a * (f0[j] + f1[j]) + b * (fd0[j] - fd1[j]);
    } else if (n <= BC_ACC_OPT) {
        for (int j = 0; j < BC_ACC_OPT; ++j) acc[j] += a * (f0[j] + f1[j]) + b * (fd0[j] - fd1[j]);
    } else {
        for (int j = 0; j < BC_ACC_N; ++j) acc[j] += a * (f0[j] + f1[j]) + b * (fd0[j] - fd1[j]);
    }
}

/* The lanes integrated at accumulation level `level` (bc_plant_set_accumulate): acc_mask, and
 * the zeroed rates of the others. A lane whose rate the parameters keep at zero is left out (its acc[] stays). */
static void lanes_select(const bc_plant_params *p, bc_plant_state *s, int level)
{
    uint32_t m = 0u;
    if (level >= BC_ACC_METRICS) {
        m = (1u << BC_ACC_SRC) | (1u << BC_ACC_CU) | (1u << BC_ACC_EMF) | (1u << BC_ACC_LOAD) | (1u << BC_ACC_TAU) |
            (1u << BC_ACC_TAU2) | (1u << BC_ACC_I2A) | (1u << BC_ACC_I2B) | (1u << BC_ACC_I2C);
        if (p->R_src > 0.0) m |= 1u << BC_ACC_RSRC;
        if (p->R_on > 0.0) m |= 1u << BC_ACC_SW;
        if (p->V_f > 0.0 || p->r_d > 0.0) m |= 1u << BC_ACC_DIODE;
        if (p->n_cog > 0) m |= 1u << BC_ACC_COG;
        if (p->B > 0.0 || p->tau_c > 0.0) m |= 1u << BC_ACC_FRIC;
        /* the optional lanes integrate when a rate can be nonzero: iron loss, or switching losses on averaged legs
         * (the switching inverter books them at its gate edges) */
        if (s->fe_on || (s->sw_on && p->inverter == BC_INV_AVERAGE)) {
            m |= (1u << BC_ACC_SWLOSS) | (1u << BC_ACC_RR) | (1u << BC_ACC_FE);
        }
    }
    if (level >= BC_ACC_ALL) {
        m |= (1u << BC_ACC_VA) | (1u << BC_ACC_VB) | (1u << BC_ACC_VC) | (1u << BC_ACC_VN) | (1u << BC_ACC_IDC);
    }
    if (s->term_on) m |= (1u << BC_ACC_VA) | (1u << BC_ACC_VB) | (1u << BC_ACC_VC);
    s->acc_mask = m;
    s->acc_hi = 0;
    for (int j = 0; j < BC_ACC_N; ++j) { /* acc_step adds zero on the lanes not integrated */
        if (m & (1u << j)) s->acc_hi = j + 1;
        if (m & (1u << j)) continue;
        s->work.f[0][j] = s->work.f[1][j] = 0.0;
        s->work.fd[0][j] = s->work.fd[1][j] = 0.0;
    }
    s->acc_on = level;
    s->lanes_on = m != 0u;
}

/* The coefficients of switching leg x in conduction state s->cond[x] (topology_set). */
static inline void switch_leg_set(const bc_plant_params *p, bc_plant_state *s, int x)
{
    double up = 0.0, u0 = 0.0, r = 0.0, conn = 1.0, rsw = 0.0, dio = 0.0;
    switch (s->cond[x]) {
    case BC_COND_SW_U: up = 1.0; r = s->r_on; rsw = s->r_on; break;
    case BC_COND_SW_L: r = s->r_on; rsw = s->r_on; break;
    case BC_COND_D_U: up = 1.0; u0 = p->V_f; r = p->r_d; dio = 1.0; break;
    case BC_COND_D_L: u0 = -p->V_f; r = p->r_d; dio = 1.0; break;
    default: conn = 0.0; break;
    }
    s->tc_cond[x] = s->cond[x];
    s->tc_lo_a[x] = 0.0; /* the diode window [-V_f, v_bus + V_f] */
    s->tc_lo_b[x] = -p->V_f;
    s->tc_hi_a[x] = 1.0;
    s->tc_hi_b[x] = p->V_f;
    s->tc_up[x] = up;
    s->tc_u0[x] = u0;
    s->tc_r[x] = r;
    s->tc_conn[x] = conn;
    s->tc_rsw[x] = rsw;
    s->tc_dio[x] = dio;
    s->tc_swk[x] = 0.0;
    s->tc_rrk[x] = 0.0;
}

/* P up and P U0 from the legs' sources and the connection weights (topology_set). */
static inline void pu_set(bc_plant_state *s)
{
    const double *cn = s->tc_cn, *pc = s->tc_pc;
    const double ub = cn[0] * s->tc_up[0] + cn[1] * s->tc_up[1] + cn[2] * s->tc_up[2];
    const double u0b = cn[0] * s->tc_u0[0] + cn[1] * s->tc_u0[1] + cn[2] * s->tc_u0[2];
    for (int x = 0; x < 3; ++x) {
        s->tc_pup[x] = pc[x] * (s->tc_up[x] - ub);
        s->tc_pu0[x] = pc[x] * (s->tc_u0[x] - u0b);
    }
}

static void b_set(const bc_plant_params *p, bc_plant_state *s);

/* topology_set where only switching legs changed state and every phase stays connected or open (a gate edge: a leg
 * between its switches or between a switch and the opposite diode): the connection weights n, c, P's diagonal and,
 * unless a device resistance (or, with R_src, a + rail tie) changed, B stay; the changed legs' sources and P up,
 * P U0 are recomputed by the same expressions as in the full path. Returns 0 where it does not apply. */
static int topology_edge(const bc_plant_params *p, bc_plant_state *s)
{
    if (!s->tc_b_ok || s->tc_msrc || s->hold_on || (s->avg[0] | s->avg[1] | s->avg[2])) return 0;
    for (int x = 0; x < 3; ++x) {
        const int32_t c = s->tc_cond[x];
        if (c != s->cond[x] && (c < 0 || (c == BC_COND_OPEN) != (s->cond[x] == BC_COND_OPEN))) return 0;
    }
    int b_stale = 0;
    for (int x = 0; x < 3; ++x) {
        if (s->tc_cond[x] == s->cond[x]) continue;
        const double r0 = s->tc_r[x], up0 = s->tc_up[x];
        switch_leg_set(p, s, x);
        b_stale |= s->tc_r[x] != r0 || (p->R_src != 0.0 && s->tc_up[x] != up0);
    }
    pu_set(s);
    if (b_stale) b_set(p, s);
    return 1;
}

/* Circuit coefficients of the present conduction states (bc_plant.h, tc_*). Call after any change of cond[]. */
static void topology_set(const bc_plant_params *p, bc_plant_state *s)
{
    if (topology_edge(p, s)) return;
    /* B depends on the connected phases, the device resistances and, with R_src, on the + rail ties: a PWM leg
     * moving between its switches changes none of these (R_src = 0), so B is kept */
    double key[10];
    for (int x = 0; x < 3; ++x) {
        key[x] = s->tc_conn[x];
        key[3 + x] = s->tc_r[x];
        key[6 + x] = s->tc_up[x];
    }
    key[9] = (double)s->tc_msrc;
    int n = 0;
    for (int x = 0; x < 3; ++x) {
        if (!s->avg[x] && s->tc_cond[x] == s->cond[x]) { /* a switching leg in the same state: unchanged */
            n += s->tc_conn[x] != 0.0;
            continue;
        }
        s->tc_cond[x] = s->avg[x] ? -1 : s->cond[x];
        double up = 0.0, u0 = 0.0, r = 0.0, conn = 1.0, rsw = 0.0, dio = 0.0, swk = 0.0, rrk = 0.0;
        if (s->avg[x]) {
            /* averaged leg (bc_plant.h): the weighted mean of its gate states */
            const double fu = s->fr_u[x], fo = s->fr_o[x], fs = s->fr_u[x] + s->fr_l[x];
            switch (s->cond[x]) {
            case BC_COND_SW_U: case BC_COND_SW_L: up = fu; r = s->r_on; rsw = s->r_on; break;
            case BC_COND_D_U: up = fu + fo; u0 = fo * p->V_f; rsw = fs * s->r_on; dio = fo; break;
            case BC_COND_D_L: up = fu; u0 = -fo * p->V_f; rsw = fs * s->r_on; dio = fo; break;
            default: conn = 0.0; break;
            }
            if (s->cond[x] == BC_COND_D_U || s->cond[x] == BC_COND_D_L) r = rsw + fo * p->r_d;
            /* switching losses (bc_plant.h): PWM legs switch hard at either sign, HIGH legs for i > 0 (D_L in the
             * off fraction), LOW legs for i < 0 (D_U) */
            int hard = conn != 0.0 && ((s->fr_u[x] > 0.0 && s->fr_l[x] > 0.0) || (s->hold_on && s->hold_x == x) ||
                                       (s->fr_u[x] > 0.0 && s->cond[x] == BC_COND_D_L) ||
                                       (s->fr_l[x] > 0.0 && s->cond[x] == BC_COND_D_U));
            swk = hard ? p->f_pwm * (p->E_on + p->E_off) * s->sw_inv_vi : 0.0;
            rrk = hard ? p->f_pwm * p->E_rr * s->sw_inv_vi : 0.0;
            s->tc_lo_a[x] = fu;
            s->tc_lo_b[x] = -fo * p->V_f;
            s->tc_hi_a[x] = fu + fo;
            s->tc_hi_b[x] = fo * p->V_f;
        } else {
            switch_leg_set(p, s, x);
            n += s->tc_conn[x] != 0.0;
            continue;
        }
        s->tc_up[x] = up;
        s->tc_u0[x] = u0;
        s->tc_r[x] = r;
        s->tc_conn[x] = conn;
        s->tc_rsw[x] = rsw;
        s->tc_dio[x] = dio;
        s->tc_swk[x] = swk;
        s->tc_rrk[x] = rrk;
        n += conn != 0.0;
    }
    s->tc_n = n;
    s->tc_inv_n = n > 0 ? 1.0 / (double)n : 0.0;
    s->tc_gain = n >= 2 ? 1.0 / p->L : 0.0;
    /* the affine map of core(): P = g (C - c c^T / n), M = R_src W + diag(r) */
    /* averaged legs with a source resistance: the half-period mean of up_x(t) up_y(t) (bc_plant.h) */
    s->tc_msrc = (s->avg[0] | s->avg[1] | s->avg[2]) && p->R_src > 0.0;
    if (s->tc_msrc) {
        double d[3], ua[3], ui[3];
        for (int x = 0; x < 3; ++x) {
            if (s->tc_conn[x] == 0.0) {
                d[x] = 1.0;
                ua[x] = ui[x] = 0.0;
            } else if (s->avg[x]) { /* active: upper (PWM, HIGH) or lower (LOW) switch; idle: lower switch or O */
                ua[x] = s->fr_u[x] > 0.0 ? 1.0 : 0.0;
                d[x] = s->fr_u[x] > 0.0 ? s->fr_u[x] : s->fr_l[x];
                ui[x] = (s->fr_o[x] > 0.0 && s->cond[x] == BC_COND_D_U) ? 1.0 : 0.0;
            } else {
                d[x] = 1.0;
                ua[x] = ui[x] = s->tc_up[x];
            }
        }
        for (int x = 0; x < 3; ++x) {
            for (int y = 0; y < 3; ++y) {
                s->tc_msrc_m[3 * x + y] = ua[x] * ua[y] * fmin(d[x], d[y]) + ua[x] * ui[y] * fmax(0.0, d[x] - d[y]) +
                                          ui[x] * ua[y] * fmax(0.0, d[y] - d[x]) +
                                          ui[x] * ui[y] * fmin(1.0 - d[x], 1.0 - d[y]);
            }
        }
    }
    /* (P v)_x = g c_x (v_x - c.v / n); B = P (M + R I) with M = R_src W + diag(r): column y of B is P applied to
     * column y of M + R I, which is (r_y + R) at row y plus R_src times W's column (W = up up^T: R_src up_y P up) */
    for (int x = 0; x < 3; ++x) {
        s->tc_cn[x] = s->tc_conn[x] * s->tc_inv_n;
        s->tc_pc[x] = s->tc_gain * s->tc_conn[x];
    }
    if (s->hold_on) { /* d(di/dt)/dd = v_src P e_x: column x of P, (P e_x)_j = pc_j (delta_jx - cn_x) */
        for (int j = 0; j < 3; ++j) s->tc_hcol[j] = s->tc_pc[j] * ((j == s->hold_x ? 1.0 : 0.0) - s->tc_cn[s->hold_x]);
    }
    pu_set(s);
    int same = s->tc_b_ok && key[9] == (double)s->tc_msrc && !s->tc_msrc;
    for (int x = 0; x < 3 && same; ++x) {
        same = key[x] == s->tc_conn[x] && key[3 + x] == s->tc_r[x] && (p->R_src == 0.0 || key[6 + x] == s->tc_up[x]);
    }
    if (!same) b_set(p, s);
}

/* B = P (M + R I) (topology_set). */
static void b_set(const bc_plant_params *p, bc_plant_state *s)
{
    const double *cn = s->tc_cn, *pc = s->tc_pc;
    s->tc_b_ok = 1;
    for (int y = 0; y < 3; ++y) {
        const double d = s->tc_r[y] + s->r_ph; /* diagonal of M + R I */
        double col[3] = {0.0, 0.0, 0.0};    /* R_src W's column y */
        if (p->R_src > 0.0) {
            for (int x = 0; x < 3; ++x) {
                col[x] = p->R_src * (s->tc_msrc ? s->tc_msrc_m[3 * x + y] : s->tc_up[x] * s->tc_up[y]);
            }
        }
        col[y] += d;
        const double mb = cn[0] * col[0] + cn[1] * col[1] + cn[2] * col[2];
        for (int x = 0; x < 3; ++x) s->tc_b[3 * x + y] = pc[x] * (col[x] - mb);
    }
}

/* Outputs from the quantities computed with a derivative. */
static void aux_to_out(const bc_plant_params *p, const bc_plant_state *s, const double *y, const aux_t *a,
                       bc_plant_out *out)
{
    for (int x = 0; x < 3; ++x) {
        out->e[x] = a->e[x];
        out->k[x] = a->k[x];
        out->v[x] = a->v[x];
    }
    out->v_n = a->vn;
    out->v_bus = a->vbus;
    out->i_dc = a->idc;
    out->tau_e = a->tau;
    out->tau_cog = a->tau_cog;
    double om = y[Y_OM];
    out->tau_shaft = a->tau - p->B * om - p->tau_c * sign_of(om);
    if (s->fe_on && om != 0.0) out->tau_shaft -= a->tau_fe; /* at rest, as tau_c: none */
    out->w_l = 0.5 * p->L * (y[Y_I] * y[Y_I] + y[Y_I + 1] * y[Y_I + 1] + y[Y_I + 2] * y[Y_I + 2]);
    out->d_hold = s->hold_x < 0 ? 0.0 : (s->hold_on ? a->dh : s->hold_d);
}

static void pack(const bc_plant_state *s, double *y)
{
    y[Y_I] = s->i[0];
    y[Y_I + 1] = s->i[1];
    y[Y_I + 2] = s->i[2];
    y[Y_TH] = s->theta;
    y[Y_OM] = s->omega;
}

static void unpack(bc_plant_state *s, const double *y)
{
    s->i[0] = y[Y_I];
    s->i[1] = y[Y_I + 1];
    s->i[2] = y[Y_I + 2];
    s->theta = y[Y_TH];
    s->omega = y[Y_OM];
}

/* One classical Runge-Kutta step of length h from y0 with derivative k1 = f(y0) (the five states only; the power
 * flows follow by acc_step from the step's ends). */
/* What core_at computes from the step's constants alone (the conduction coefficients, the supply, the drags' sign
 * and the mechanics are fixed inside a step), taken once per step for the three inner stages. */
typedef struct {
    double src[3]; /* v_src P up + P U0 */
    double sgn;    /* the Coulomb-like drags' sign */
    int fric;      /* friction acts */
    int dyn;       /* the speed is a state */
    const struct sin_fold *fo; /* the step's sinusoid folded with its anchor, or 0 */
} stage_c;

/* Fourier shapes on the usual plant (no ideal limiter, cogging, fan load or iron loss; a conducting circuit; the
 * drags' sign fixed at the step start): stage_at may replace core_at without its aux. Table shapes keep core_at:
 * there the same path measured 1.4 % more instructions (sine on the flux observer), not fewer. */
static int stage_ok(const bc_plant_params *p, const bc_plant_state *s)
{
    return s->fz_n > 0 && !s->hold_on && p->n_cog == 0 && !s->prop_on && !s->fe_on && s->tc_gain != 0.0 &&
           (!(s->drag_on && !s->stuck) || (s->work.valid && s->work.wdir != 0));
}

static BC_ALWAYS_INLINE void stage_init(const bc_plant_params *p, const bc_plant_state *s, stage_c *c)
{
    const double vs = s->v_src;
    for (int x = 0; x < 3; ++x) c->src[x] = vs * s->tc_pup[x] + s->tc_pu0[x];
    c->fric = s->drag_on && !s->stuck;
    c->sgn = c->fric ? (double)s->work.wdir : 0.0;
    c->dyn = p->mech == BC_MECH_DYNAMIC && !s->stuck;
}

/* core_at(p, s, y, dy, 0, 0, ref, fo) where stage_ok, without the terms that are zero there: the currents' rates by the
 * same expressions, the speed's to rounding (the load and drags summed apart from the torque). */
static BC_ALWAYS_INLINE void stage_at(const bc_plant_params *restrict p, const bc_plant_state *restrict s,
                                      const stage_c *restrict c, const double *restrict y, double *restrict dy,
                                      const double *ref)
{
    const double i0 = y[Y_I], i1 = y[Y_I + 1], i2 = y[Y_I + 2];
    const double th = y[Y_TH], om = y[Y_OM];
    double k[3];
    shapes_at(p, s, th, k, 0, ref, 0, c->fo);
    const double e0 = om * k[0], e1 = om * k[1], e2 = om * k[2];
    const double *B = s->tc_b;
    const double eb = s->tc_cn[0] * e0 + s->tc_cn[1] * e1 + s->tc_cn[2] * e2;
    dy[Y_I] = c->src[0] - (B[0] * i0 + B[1] * i1 + B[2] * i2) - s->tc_pc[0] * (e0 - eb);
    dy[Y_I + 1] = c->src[1] - (B[3] * i0 + B[4] * i1 + B[5] * i2) - s->tc_pc[1] * (e1 - eb);
    dy[Y_I + 2] = c->src[2] - (B[6] * i0 + B[7] * i1 + B[8] * i2) - s->tc_pc[2] * (e2 - eb);
    /* the rotor: the load and the drags (independent of tau) are added first, off tau's chain of operations */
    const double tau = k[0] * i0 + k[1] * i1 + k[2] * i2;
    const double t_fric = c->fric ? p->B * om + p->tau_c * c->sgn : 0.0;
    dy[Y_TH] = (double)p->p * om;
    dy[Y_OM] = c->dyn ? (tau - (s->tau_load + t_fric)) * s->work.inv_J : 0.0;
}

typedef char bc_ny_is_5[NY == 5 ? 1 : -1]; /* axpy5 */

/* yt = y0 + a k over the five states, written out: the loop vectoriser would pack pairs of the stages' k, which are
 * stored one by one, and the packed loads wait for the stores (a failed store-to-load forwarding, measured) */
static BC_ALWAYS_INLINE void axpy5(double *restrict yt, const double *restrict y0, double a, const double *restrict k)
{
    yt[0] = y0[0] + a * k[0];
    yt[1] = y0[1] + a * k[1];
    yt[2] = y0[2] + a * k[2];
    yt[3] = y0[3] + a * k[3];
    yt[4] = y0[4] + a * k[4];
}

static void rk4(const bc_plant_params *p, const bc_plant_state *s, const double *y0, const double *k1, double h,
                double *y1, const sin_fold *fo)
{
    double k2[NY], k3[NY], k4[NY], yt[NY];
    sin_fold own;
    if (!fo) { /* the caller has none: the same from the same anchor */
        sin_fold_init(s, &own);
        fo = &own;
    }
    if (stage_ok(p, s)) {
        stage_c c;
        stage_init(p, s, &c);
        c.fo = fo;
        axpy5(yt, y0, 0.5 * h, k1);
        stage_at(p, s, &c, yt, k2, s->work.cs);
        axpy5(yt, y0, 0.5 * h, k2);
        stage_at(p, s, &c, yt, k3, s->work.cs);
        axpy5(yt, y0, h, k3);
        stage_at(p, s, &c, yt, k4, s->work.cs);
    } else {
        axpy5(yt, y0, 0.5 * h, k1);
        core_at(p, s, yt, k2, 0, 0, s->work.cs, fo);
        axpy5(yt, y0, 0.5 * h, k2);
        core_at(p, s, yt, k3, 0, 0, s->work.cs, fo);
        axpy5(yt, y0, h, k3);
        core_at(p, s, yt, k4, 0, 0, s->work.cs, fo);
    }
    const double h6 = h / 6.0;
#define BC_RK4_SUM(j) y1[j] = y0[j] + h6 * (k1[j] + 2.0 * (k2[j] + k3[j]) + k4[j])
    BC_RK4_SUM(0);
    BC_RK4_SUM(1);
    BC_RK4_SUM(2);
    BC_RK4_SUM(3);
    BC_RK4_SUM(4);
#undef BC_RK4_SUM
    if (p->mech == BC_MECH_IMPOSED) {
        y1[Y_OM] = y0[Y_OM]; /* exactly constant */
    }
}

/* The same step where the circuit is linear with a forcing affine in time: at constant speed (imposed, or a rotor
 * held by friction) on table shapes, the angle moves as theta0 + p omega t inside one piece, so e(t) = e0 + e1 t and
 * (core()) di/dt = -B i + g0 + g1 t with g1 = -P e1. For such a system the RK4 step is exactly the Taylor polynomial
 * of degree four, i(h) = i + h D1 + h^2/2 D2 + h^3/6 D3 + h^4/24 D4 with the derivatives of the linear ODE
 * D1 = di/dt, D2 = -B D1 + g1, D3 = -B D2, D4 = -B D3: the same step to rounding, for three 3 x 3 products instead
 * of three derivative evaluations. */
static int linear_step_ok(const bc_plant_params *p, const bc_plant_state *s)
{
    return s->emf_tables && (p->mech == BC_MECH_IMPOSED || s->stuck) && !s->hold_on;
}

static BC_ALWAYS_INLINE void taylor4(const bc_plant_params *p, const bc_plant_state *s, const double *y0, const double *k1, double h,
                    double *y1)
{
    const double *B = s->tc_b;
    const double om = y0[Y_OM], wth = (double)p->p * om; /* d theta/dt */
    double de[3]; /* de_x/dt = omega slope_x p omega */
    for (int x = 0; x < 3; ++x) de[x] = om * s->k_scale * s->piece[x].slope * wth;
    const double eb = s->tc_cn[0] * de[0] + s->tc_cn[1] * de[1] + s->tc_cn[2] * de[2];
    double d1[3], d2[3], d3[3], d4[3];
    for (int x = 0; x < 3; ++x) d1[x] = k1[Y_I + x];
    for (int x = 0; x < 3; ++x) {
        d2[x] = -(B[3 * x] * d1[0] + B[3 * x + 1] * d1[1] + B[3 * x + 2] * d1[2]) - s->tc_pc[x] * (de[x] - eb);
    }
    for (int x = 0; x < 3; ++x) d3[x] = -(B[3 * x] * d2[0] + B[3 * x + 1] * d2[1] + B[3 * x + 2] * d2[2]);
    for (int x = 0; x < 3; ++x) d4[x] = -(B[3 * x] * d3[0] + B[3 * x + 1] * d3[1] + B[3 * x + 2] * d3[2]);
    for (int x = 0; x < 3; ++x) {
        y1[Y_I + x] = y0[Y_I + x] + h * (d1[x] + 0.5 * h * (d2[x] + h / 3.0 * (d3[x] + 0.25 * h * d4[x])));
    }
    y1[Y_TH] = y0[Y_TH] + h * wth;
    y1[Y_OM] = om;
}

/* One step of the five states: taylor4 where the circuit is linear (identical to RK4 there), else rk4. */
static BC_ALWAYS_INLINE void state_step(const bc_plant_params *p, const bc_plant_state *s, const double *y0, const double *k1, double h,
                       double *y1, const sin_fold *fo)
{
    if (linear_step_ok(p, s)) {
        taylor4(p, s, y0, k1, h, y1);
    } else {
        rk4(p, s, y0, k1, h, y1, fo);
    }
}

/* ---------------------------------------------------------------------------------------------------------- */
/* angle pieces: back-EMF segments and Hall intervals                                                          */

static void hall_raw_toggle(const bc_plant_params *p, bc_plant_state *s, int x);

/* Hall intervals around the current angle for the current direction (bc_plant.h: each sensor switches at
 * PHI_x - pi/6 + err_x + dir h_x/2 + k pi). keep < 0 (init): the code follows from the angle. keep >= 0 (a
 * reversal): the sensors keep their bits; one whose bit contradicts its interval is either inside its hysteresis
 * band (within h_x behind the next bound in the new direction: it holds its state for one more interval) or was
 * left exactly on a bound (h_x = 0: it switches now). */
static void hall_locate(const bc_plant_params *p, bc_plant_state *s, int keep)
{
    int code = 0, now = 0;
    for (int x = 0; x < 3; ++x) {
        double base = PHI[x] - BC_PI / 6.0 + p->hall_error[x] + 0.5 * (double)s->dir * p->hall_hyst[x];
        double m = floor((s->theta - base) / BC_PI);
        double lo = base + m * BC_PI; /* at a threshold: the interval above (moving back crosses at once) */
        int bit = ((long)m % 2 == 0) ? 1 : 0;
        if (keep >= 0 && ((keep >> x) & 1) != bit) {
            double band = s->dir > 0 ? lo + BC_PI - s->theta : s->theta - lo;
            if (band < p->hall_hyst[x]) {
                lo += (double)s->dir * BC_PI;
                bit ^= 1;
            } else {
                now |= 1 << x;
            }
        }
        s->hseg[x].lo = lo;
        s->hseg[x].hi = lo + BC_PI;
        s->work.th_ok = 0;
        code |= bit << x;
    }
    if (keep < 0) {
        s->hall_raw = code;
        return;
    }
    s->hall_raw = keep;
    for (int x = 0; x < 3; ++x) {
        if (now & (1 << x)) hall_raw_toggle(p, s, x);
    }
}

static void pieces_locate(const bc_plant_params *p, bc_plant_state *s)
{
    s->work.th_ok = 0; /* the angle bound ahead moves */
    s->work.out_ok = 0; /* the shapes' pieces change */
    for (int x = 0; x < 3; ++x) {
        bc_emf_piece_at(&p->emf[x], s->theta - PHI[x], s->dir, &s->piece[x]);
        if (p->emf[x].kind == BC_EMF_TABLE) {
            s->piece[x].lo += PHI[x];
            s->piece[x].hi += PHI[x];
        }
    }
    /* keep the Hall code; only re-derive the intervals around the current angle */
    hall_locate(p, s, s->hall_raw);
}

/* The code the controller sees: the delayed sensor code with the active sensor faults applied. */
static int32_t hall_visible(const bc_plant_params *p, const bc_plant_state *s, double t)
{
    int32_t code = s->hall_true;
    for (int j = 0; j < BC_FAULT_MAX; ++j) {
        const bc_fault *f = &p->fault[j];
        if (!(t >= f->t_on && t < f->t_off)) continue;
        int32_t bit = 1 << f->phase;
        if (f->kind == BC_FAULT_HALL_STUCK) {
            code = f->value != 0.0 ? (code | bit) : (code & ~bit);
        } else if (f->kind == BC_FAULT_HALL_GLITCH) {
            code ^= bit;
        }
    }
    return code;
}

/* Recompute the visible code; every change is an edge for the capture timer. */
static void hall_refresh(const bc_plant_params *p, bc_plant_state *s, double t)
{
    int32_t code = hall_visible(p, s, t);
    if (code != s->hall_out) {
        s->hall_out = code;
        s->n_edges += 1u;
        s->t_edge = t;
    }
}

static void hall_output_toggle(const bc_plant_params *p, bc_plant_state *s, int bit, double t)
{
    s->hall_true ^= bit;
    hall_refresh(p, s, t);
}

/* Remove entry j of the delayed-edge queue. */
static void hq_remove(bc_plant_state *s, int j)
{
    int n = s->hq_n - 1 - j;
    if (n > 0) {
        memmove(&s->hq_t[j], &s->hq_t[j + 1], (size_t)n * sizeof s->hq_t[0]);
        memmove(&s->hq_code[j], &s->hq_code[j + 1], (size_t)n * sizeof s->hq_code[0]);
    }
    s->hq_n -= 1;
}

/* An edge of the input bit `bit` seen by the MCU at time t: now if t is not later, else queued in time order
 * (after entries of the same time). A full queue sees its oldest edge now (flagged). */
static void hq_push(const bc_plant_params *p, bc_plant_state *s, int32_t bit, double t)
{
    if (!(t > s->t)) {
        hall_output_toggle(p, s, bit, s->t);
        return;
    }
    if (s->hq_n == BC_HALL_QUEUE) {
        hall_output_toggle(p, s, s->hq_code[0], s->t);
        hq_remove(s, 0);
        s->flags |= BC_PLANT_HALL_OVERRUN;
    }
    int j = s->hq_n;
    while (j > 0 && s->hq_t[j - 1] > t) {
        s->hq_t[j] = s->hq_t[j - 1];
        s->hq_code[j] = s->hq_code[j - 1];
        --j;
    }
    s->hq_t[j] = t;
    s->hq_code[j] = bit;
    s->hq_n += 1;
}

/* Sensor x switched at the rotor now: its edge reaches the line d_x later and the MCU input through the RC filter
 * (bc_plant.h). A crossing of the previous input step not reached by the new step's time never happens. */
static void hall_raw_toggle(const bc_plant_params *p, bc_plant_state *s, int x)
{
    int32_t bit = 1 << x;
    s->hall_raw ^= bit;
    double t_in = s->t + p->hall_delay[x];
    double tau = p->hall_tau[x];
    if (!(tau > 0.0)) {
        hq_push(p, s, bit, t_in);
        return;
    }
    double u0 = (double)s->hf_u[x];
    double v = u0 + (s->hf_v[x] - u0) * exp(-(t_in - s->hf_t[x]) / tau);
    for (int j = s->hq_n - 1; j >= 0; --j) { /* the last queued edge of this input: cancelled if not reached */
        if (s->hq_code[j] != bit) continue;
        if (s->hq_t[j] >= t_in) hq_remove(s, j);
        break;
    }
    int32_t u = (s->hall_raw >> x) & 1;
    s->hf_t[x] = t_in;
    s->hf_v[x] = v;
    s->hf_u[x] = u;
    if (u == 1 && v < 0.5) {
        hq_push(p, s, bit, t_in + tau * log((1.0 - v) / 0.5));
    } else if (u == 0 && v > 0.5) {
        hq_push(p, s, bit, t_in + tau * log(v / 0.5));
    }
}

/* Cross every piece/Hall bound reached at angle th_reach in the current direction. Returns 1 if any. */
static int angles_cross(const bc_plant_params *p, bc_plant_state *s, double th_reach)
{
    int any = 0;
    const double tol = 1e-12;
    for (int x = 0; x < 3; ++x) {
        if (s->dir > 0) {
            while (s->piece[x].hi <= th_reach + tol) {
                bc_emf_piece_step(&p->emf[x], 1, &s->piece[x]);
                any = 1;
            }
            while (s->hseg[x].hi <= th_reach + tol) {
                s->hseg[x].lo = s->hseg[x].hi;
                s->hseg[x].hi += BC_PI;
                hall_raw_toggle(p, s, x);
                any = 1;
            }
        } else {
            while (s->piece[x].lo >= th_reach - tol) {
                bc_emf_piece_step(&p->emf[x], -1, &s->piece[x]);
                any = 1;
            }
            while (s->hseg[x].lo >= th_reach - tol) {
                s->hseg[x].hi = s->hseg[x].lo;
                s->hseg[x].lo -= BC_PI;
                hall_raw_toggle(p, s, x);
                any = 1;
            }
        }
    }
    if (any) s->work.th_ok = 0;
    return any;
}

/* Keep theta in [0, 2 pi): shift the angle frame of every piece with it. */
static void wrap_angle(const bc_plant_params *p, bc_plant_state *s)
{
    double shift = 0.0;
    if (s->theta >= BC_TWO_PI) {
        shift = -BC_TWO_PI;
        s->turns = (s->turns + 1u) % (uint32_t)p->p;
    } else if (s->theta < 0.0) {
        shift = BC_TWO_PI;
        s->turns = (s->turns + (uint32_t)p->p - 1u) % (uint32_t)p->p;
    } else {
        return;
    }
    s->theta += shift;
    if (s->theta >= BC_TWO_PI) {
        /* a negative angle within rounding of 0 rounds up to 2 pi: the rotor has moved back past 0, so it is just
         * below 2 pi (at 0 it would be back where it started, and a short backward step would repeat forever) */
        s->theta = nextafter(BC_TWO_PI, 0.0);
    } else if (s->theta < 0.0) {
        s->theta = 0.0;
    }
    for (int x = 0; x < 3; ++x) {
        if (p->emf[x].kind == BC_EMF_TABLE) {
            s->piece[x].lo += shift;
            s->piece[x].hi += shift;
        }
        s->hseg[x].lo += shift;
        s->hseg[x].hi += shift;
    }
    s->work.th_ok = 0;
    s->work.out_ok = 0; /* the cached circuit quantities were computed at the unwrapped angle */
}

/* Time to the next angle bound, or HUGE_VAL. *th_ev receives the bound. A bound the rotor cannot reach within twice
 * h_lim (the step's length without it) ends no step, so its time is not solved for (HUGE_VAL): the step is the same. */
static double angle_event(const bc_plant_params *p, bc_plant_state *s, double *th_ev, double h_lim)
{
    double om = s->omega;
    if (s->stuck || (p->mech == BC_MECH_IMPOSED && om == 0.0)) {
        return HUGE_VAL;
    }
    double target = s->work.th_next;
    if (!s->work.th_ok) { /* the pieces or intervals changed (or the direction: pieces_locate) */
        if (s->dir > 0) {
            target = HUGE_VAL;
            for (int x = 0; x < 3; ++x) {
                if (s->piece[x].hi < target) target = s->piece[x].hi;
                if (s->hseg[x].hi < target) target = s->hseg[x].hi;
            }
        } else {
            target = -HUGE_VAL;
            for (int x = 0; x < 3; ++x) {
                if (s->piece[x].lo > target) target = s->piece[x].lo;
                if (s->hseg[x].lo > target) target = s->hseg[x].lo;
            }
        }
        s->work.th_next = target;
        s->work.th_ok = 1;
    }
    *th_ev = target;
    const double d_e = (target - s->theta) * (double)s->dir; /* electrical angle to go */
    double w0 = om * (double)s->dir;
    double acc = p->mech == BC_MECH_IMPOSED ? 0.0 : s->work.k1[Y_OM] * (double)s->dir;
    /* out of reach: at most p (|w0| t + |acc| t^2 / 2) in t = 2 h_lim (the 1 % covers the rounding of the time the
     * code below solves for, which then exceeds 2 h_lim > h_lim by far more than a rounding of the clock) */
    const double hb = 2.0 * h_lim;
    if (d_e > 1.01 * (double)p->p * (fabs(w0) + 0.5 * fabs(acc) * hb) * hb) {
        return HUGE_VAL;
    }
    double delta = d_e / (double)p->p; /* mechanical angle to go, >= 0 */
    if (!(delta >= 0.0)) {
        return 0.0;
    }
    if (p->mech == BC_MECH_IMPOSED) {
        return w0 > 0.0 ? delta / w0 : HUGE_VAL;
    }
    double disc = w0 * w0 + 2.0 * acc * delta;
    if (disc < 0.0) {
        return HUGE_VAL; /* stops before the bound: the speed zero crossing comes first */
    }
    double den = w0 + sqrt(disc);
    return den > 0.0 ? 2.0 * delta / den : HUGE_VAL;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* inverter gates                                                                                             */

/* The gate state of a leg in mode OFF, PWM, HIGH, LOW (checked by the caller) while its carrier is active / idle. */
static const int32_t MODE_GATE[2][4] = {
    {BC_GATE_O, BC_GATE_L, BC_GATE_O, BC_GATE_O}, /* idle */
    {BC_GATE_O, BC_GATE_U, BC_GATE_U, BC_GATE_L}, /* active */
};
typedef char bc_leg_mode_order[(BC_LEG_OFF == 0 && BC_LEG_PWM == 1 && BC_LEG_HIGH == 2 && BC_LEG_LOW == 3) ? 1 : -1];

static int32_t mode_gate(int32_t mode, int active) { return MODE_GATE[active != 0][mode]; }

/* Switching losses of the switch `sw` (BC_GATE_U / BC_GATE_L) of leg x turning on (on = 1) or off at the present
 * state (bc_plant.h): hard if the current flows the switch's forward way (upper: i > 0, lower: i < 0). */
static void book_edge(const bc_plant_params *p, bc_plant_state *s, int x, int32_t sw, int on)
{
    double i = s->i[x];
    if (!(sw == BC_GATE_U ? i > 0.0 : i < 0.0)) return; /* soft (own diode) or no current */
    double k = fabs(i) * bc_plant_vbus(p, s) * s->sw_inv_vi;
    if (on) {
        s->acc[BC_ACC_SWLOSS] += p->E_on * k;
        s->acc[BC_ACC_RR] += p->E_rr * k;
    } else {
        s->acc[BC_ACC_SWLOSS] += p->E_off * k;
    }
}

/* Move the actual gate of leg x toward the desired one at time t (a switch turns on only after the other one
 * has been off for t_dead). Returns 1 if the gate changed. */
static int gate_update(const bc_plant_params *p, bc_plant_state *s, int x, double t)
{
    int32_t g = s->gate[x], des = s->des[x], g0 = g;
    if (g == des) {
        return 0;
    }
    if (g == BC_GATE_U) {
        s->t_off_u[x] = t;
        g = BC_GATE_O;
    } else if (g == BC_GATE_L) {
        s->t_off_l[x] = t;
        g = BC_GATE_O;
    }
    if (des == BC_GATE_U && t >= s->t_off_l[x] + p->t_dead) {
        g = BC_GATE_U;
    } else if (des == BC_GATE_L && t >= s->t_off_u[x] + p->t_dead) {
        g = BC_GATE_L;
    }
    s->gate[x] = g;
    if (g != g0 && s->sw_on) {
        if (g0 != BC_GATE_O) book_edge(p, s, x, g0, 0);
        if (g != BC_GATE_O) book_edge(p, s, x, g, 1);
    }
    return g != g0;
}

/* An averaged leg stops at time t: the switches it used count as turned off then (for the dead time). */
static void leg_average_end(bc_plant_state *s, int x, double t)
{
    if (s->fr_u[x] > 0.0) s->t_off_u[x] = t;
    if (s->fr_l[x] > 0.0) s->t_off_l[x] = t;
    s->avg[x] = 0;
}

static double next_gate_time(const bc_plant_params *p, const bc_plant_state *s)
{
    double tn = s->at_on ? s->at_t : HUGE_VAL; /* a scheduled command change (bc_plant_schedule) */
    for (int x = 0; x < 3; ++x) {
        if (s->edge_to[x] >= 0 && s->edge_t[x] < tn) {
            tn = s->edge_t[x];
        }
        if (s->gate[x] != s->des[x] && s->des[x] != BC_GATE_O) {
            double tp = (s->des[x] == BC_GATE_U ? s->t_off_l[x] : s->t_off_u[x]) + p->t_dead;
            if (tp < tn) {
                tn = tp;
            }
        }
    }
    return tn;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* conduction states                                                                                          */

static void conduction_from_gates(const bc_plant_params *p, bc_plant_state *s)
{
    for (int x = 0; x < 3; ++x) {
        if (s->open_fault & (1 << x)) {
            s->cond[x] = BC_COND_OPEN; /* disconnected: neither switch nor diode can carry current */
        } else if (s->avg[x] && s->fr_o[x] == 0.0) {
            s->cond[x] = BC_COND_SW_U; /* averaged PWM leg: connected whatever the current */
        } else if (s->gate[x] == BC_GATE_U) {
            s->cond[x] = BC_COND_SW_U;
        } else if (s->gate[x] == BC_GATE_L) {
            s->cond[x] = BC_COND_SW_L;
        } else if (s->i[x] > 0.0) {
            s->cond[x] = BC_COND_D_L;
        } else if (s->i[x] < 0.0) {
            s->cond[x] = BC_COND_D_U;
        } else if (s->cond[x] != BC_COND_D_L && s->cond[x] != BC_COND_D_U) {
            s->cond[x] = BC_COND_OPEN; /* a phase that has just been made to conduct keeps its diode */
        }
    }
    topology_set(p, s);
}

/* All phases open: the pair (hi through its upper clamp, lo through its lower one) closest to conducting, and its
 * margin (U_hi_hi - e_hi) - (U_lo_lo - e_lo): the pair conducts when it is negative. Switching legs: the largest
 * and smallest back-EMF, margin v_bus + 2 V_f - (e_hi - e_lo). */
static double pair_margin(const bc_plant_params *p, const bc_plant_state *s, const aux_t *a, int *hi, int *lo)
{
    double best = HUGE_VAL;
    *hi = -1;
    *lo = -1;
    if (!(s->avg[0] | s->avg[1] | s->avg[2])) {
        for (int x = 0; x < 3; ++x) {
            if (s->open_fault & (1 << x)) continue;
            if (*hi < 0 || a->e[x] > a->e[*hi]) *hi = x;
            if (*lo < 0 || a->e[x] < a->e[*lo]) *lo = x;
        }
        if (*hi >= 0 && *lo >= 0 && *hi != *lo) {
            best = a->vbus + 2.0 * p->V_f - (a->e[*hi] - a->e[*lo]);
        }
        return best;
    }
    for (int x = 0; x < 3; ++x) {
        if (s->open_fault & (1 << x)) continue;
        for (int y = 0; y < 3; ++y) {
            if (y == x || (s->open_fault & (1 << y))) continue;
            double m = (s->tc_hi_a[x] * a->vbus + s->tc_hi_b[x] - a->e[x]) -
                       (s->tc_lo_a[y] * a->vbus + s->tc_lo_b[y] - a->e[y]);
            if (m < best) {
                best = m;
                *hi = x;
                *lo = y;
            }
        }
    }
    return best;
}

/* Cache the derivative, torque, watches and (while acc[] is integrated) the power flows at the current state y,
 * whose core() gave dy and a (with dk if acc_on): the start of the next step. */
static void work_fill(const bc_plant_params *p, bc_plant_state *s, const double *y, const double *dy, const aux_t *a)
{
    memcpy(s->work.k1, dy, sizeof s->work.k1);
    memcpy(s->work.cs, a->cs, sizeof s->work.cs);
    if (a != &s->work.a[s->work.cur]) s->work.a[s->work.cur] = *a;
    s->work.a_ok = 1;
    s->work.out_ok = 1;
    s->work.tau = a->tau;
    s->work.wdir = s->omega > 0.0 ? 1 : (s->omega < 0.0 ? -1 : 0);
    (void)watch_eval(p, s, y, a, s->work.wdir, s->work.w[s->work.cur]);
    if (s->lanes_on) lanes(p, s, y, dy, a, s->work.f[s->work.cur], s->work.fd[s->work.cur]);
    s->work.valid = 1;
}

/* Open phases whose floating terminal leaves their window ([-V_f, v_bus + V_f] for a both-off leg) conduct
 * (fixed point, docs/plant.md). */
static void resolve_open(const bc_plant_params *p, bc_plant_state *s)
{
    int any_open = 0;
    for (int x = 0; x < 3; ++x) any_open |= (s->cond[x] == BC_COND_OPEN);
    if (!any_open) {
        return;
    }
    double y[NY], dy[NY];
    aux_t a;
    double tol = 1e-9 * (1.0 + fabs(s->v_src));
    for (int iter = 0; iter < 4; ++iter) {
        pack(s, y);
        core(p, s, y, dy, &a, s->lanes_on ? WANT_DK : 0, 0);
        int changed = 0;
        if (a.n_conn == 0) {
            int hi = -1, lo = -1;
            double margin = pair_margin(p, s, &a, &hi, &lo);
            int conducts = (s->avg[0] | s->avg[1] | s->avg[2])
                               ? margin < -tol
                               : (hi >= 0 && lo >= 0 && hi != lo && a.e[hi] - a.e[lo] > a.vbus + 2.0 * p->V_f + tol);
            if (hi >= 0 && lo >= 0 && hi != lo && conducts) {
                s->cond[hi] = BC_COND_D_U;
                s->cond[lo] = BC_COND_D_L;
                changed = 1;
            }
        } else {
            for (int x = 0; x < 3; ++x) {
                if (s->cond[x] != BC_COND_OPEN || ((s->hold_open | s->open_fault) & (1 << x))) continue;
                if (a.v[x] < s->tc_lo_a[x] * a.vbus + s->tc_lo_b[x] - tol) {
                    s->cond[x] = BC_COND_D_L;
                    changed = 1;
                    break; /* one at a time: the star point moves */
                }
                if (a.v[x] > s->tc_hi_a[x] * a.vbus + s->tc_hi_b[x] + tol) {
                    s->cond[x] = BC_COND_D_U;
                    changed = 1;
                    break;
                }
            }
        }
        if (changed) {
            topology_set(p, s);
        } else {
            work_fill(p, s, y, dy, &a); /* the derivative at this state and topology starts the next step */
            return;
        }
    }
    s->work.valid = 0;
}

/* A gate edge at a state whose circuit quantities are cached (work.a): when every phase that conducted still conducts
 * and every open phase stays open (a leg moving between its switch and the opposite diode, or between its two
 * switches), the shapes, back-EMFs, torque and drags are those of the same state, so the derivative follows from the
 * new conduction coefficients and the cached back-EMFs without evaluating the shapes again; the open phases' windows
 * are checked as resolve_open does (a terminal leaving its window takes the full path), then the watches and power
 * flows are recomputed. Returns 0 where it does not apply (averaged legs, a phase opening or closing). */
static int switch_update(const bc_plant_params *p, bc_plant_state *s, const int32_t old[3])
{
    if (!(s->work.valid && s->work.a_ok) || s->tc_msrc) return 0;
    for (int x = 0; x < 3; ++x) {
        if (s->avg[x] || (old[x] == BC_COND_OPEN) != (s->cond[x] == BC_COND_OPEN)) return 0;
    }
    aux_t *a = &s->work.a[s->work.cur];
    double y[NY];
    pack(s, y);
    const double *B = s->tc_b, *e = a->e;
    const double eb = s->tc_cn[0] * e[0] + s->tc_cn[1] * e[1] + s->tc_cn[2] * e[2];
    for (int x = 0; x < 3; ++x) { /* as core(): di/dt = v_src P up + P U0 - B i - g c_x (e_x - c.e / n) */
        s->work.k1[Y_I + x] = s->tc_gain != 0.0 ? s->v_src * s->tc_pup[x] + s->tc_pu0[x] -
                                                      (B[3 * x] * y[Y_I] + B[3 * x + 1] * y[Y_I + 1] +
                                                       B[3 * x + 2] * y[Y_I + 2]) -
                                                      s->tc_pc[x] * (e[x] - eb)
                                                : 0.0;
    }
    const double idc = s->tc_up[0] * y[Y_I] + s->tc_up[1] * y[Y_I + 1] + s->tc_up[2] * y[Y_I + 2];
    a->idc = idc;
    a->vbus = s->v_src - p->R_src * idc;
    a->p_rsrc = p->R_src * idc * idc;
    if (s->tc_n < 3 || (s->acc_mask & (1u << BC_ACC_VA))) aux_terminals(p, s, y, a);
    double tol = 1e-9 * (1.0 + fabs(s->v_src)); /* resolve_open's test of the open terminals */
    for (int x = 0; x < 3; ++x) {
        if (s->cond[x] != BC_COND_OPEN || ((s->hold_open | s->open_fault) & (1 << x))) continue;
        if (a->n_conn == 0 || a->v[x] < s->tc_lo_a[x] * a->vbus + s->tc_lo_b[x] - tol ||
            a->v[x] > s->tc_hi_a[x] * a->vbus + s->tc_hi_b[x] + tol)
            return 0;
    }
    /* the watches: those of diodes and open phases change with the conduction states; with every phase on a switch
     * before and after, only the trip, speed and sticking ones are left, functions of the unchanged state */
    int sw = 1;
    for (int x = 0; x < 3; ++x) {
        sw &= (old[x] == BC_COND_SW_U || old[x] == BC_COND_SW_L) &&
              (s->cond[x] == BC_COND_SW_U || s->cond[x] == BC_COND_SW_L);
    }
    if (!sw) (void)watch_eval(p, s, y, a, s->work.wdir, s->work.w[s->work.cur]);
    if (s->lanes_on) lanes_edge(p, s, y, s->work.k1, a, s->work.f[s->work.cur], s->work.fd[s->work.cur]);
    return 1;
}

static void resolve(const bc_plant_params *p, bc_plant_state *s)
{
    int32_t old[3] = {s->cond[0], s->cond[1], s->cond[2]};
    conduction_from_gates(p, s);
    if (switch_update(p, s, old)) return;
    s->work.valid = 0;
    resolve_open(p, s);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* watched functions: must stay >= 0 inside a step                                                            */

#define W_DIODE 0  /* + phase: current of a diode-conducting phase, signed to be positive */
#define W_OPEN_LO 3 /* + phase: open terminal above -V_f */
#define W_OPEN_HI 6 /* + phase: open terminal below v_bus + V_f */
#define W_PAIR 9   /* all open: no pair can conduct */
#define W_OMEGA 10 /* moving: omega keeps its sign */
#define W_STICK 11 /* stuck: |tau_net| <= tau_c */
#define W_TRIP 12  /* + phase: |i_x| below the hardware trip level */
#define W_HOLD_LO 15 /* holding: d* >= 0 */
#define W_HOLD_HI 16 /* holding: d* <= 1 */
#define W_REACH 17   /* free: the held current not yet reached (i_ref - i_x, signed by the drive's direction) */
#define NW BC_PLANT_NW

/* The watches active at the present conduction states, mechanics and limiter into g, and the mask of those negative
 * (bit w: watch w). Only the active entries are written: which watches are active depends on nothing that changes
 * inside a step (conduction states, connected phases, faults, trip, limiter, sticking, the speed's sign at the step
 * start), so a step's two ends have the same active set and the integrator reads g only at the bits of this mask. The
 * one exception, the all-open pair's (it needs e_hi > e_lo on the switching inverter), is written always. */
static BC_ALWAYS_INLINE uint32_t watch_eval(const bc_plant_params *p, const bc_plant_state *s, const double *y,
                                            const aux_t *a, int dir_om, double *g)
{
    uint32_t neg = 0u;
    for (int x = 0; x < 3; ++x) {
        switch (s->cond[x]) {
        case BC_COND_D_L:
            g[W_DIODE + x] = y[Y_I + x];
            neg |= (uint32_t)(y[Y_I + x] < 0.0) << (W_DIODE + x);
            break;
        case BC_COND_D_U:
            g[W_DIODE + x] = -y[Y_I + x];
            neg |= (uint32_t)(y[Y_I + x] > 0.0) << (W_DIODE + x);
            break;
        case BC_COND_OPEN:
            if (a->n_conn > 0 && !(s->open_fault & (1 << x))) {
                double lo = a->v[x] - (s->tc_lo_a[x] * a->vbus + s->tc_lo_b[x]);
                double hi = (s->tc_hi_a[x] * a->vbus + s->tc_hi_b[x]) - a->v[x];
                g[W_OPEN_LO + x] = lo;
                g[W_OPEN_HI + x] = hi;
                neg |= ((uint32_t)(lo < 0.0) << (W_OPEN_LO + x)) | ((uint32_t)(hi < 0.0) << (W_OPEN_HI + x));
            }
            break;
        default: break;
        }
    }
    if (a->n_conn == 0) {
        int hi, lo;
        double m = pair_margin(p, s, a, &hi, &lo);
        g[W_PAIR] = HUGE_VAL;
        if (hi >= 0 && lo >= 0 && hi != lo && (s->avg[0] | s->avg[1] | s->avg[2] || a->e[hi] > a->e[lo])) {
            g[W_PAIR] = m;
            neg |= (uint32_t)(m < 0.0) << W_PAIR;
        }
    }
    if (p->i_trip > 0.0 && !s->tripped) {
        for (int x = 0; x < 3; ++x) {
            g[W_TRIP + x] = p->i_trip - fabs(y[Y_I + x]);
            neg |= (uint32_t)(g[W_TRIP + x] < 0.0) << (W_TRIP + x);
        }
    }
    if (s->hold_x >= 0) {
        if (s->hold_on) {
            g[W_HOLD_LO] = a->dh;
            g[W_HOLD_HI] = 1.0 - a->dh;
            neg |= ((uint32_t)(a->dh < 0.0) << W_HOLD_LO) | ((uint32_t)(a->dh > 1.0) << W_HOLD_HI);
        } else {
            double gr = s->hold_d > 0.5 ? s->hold_i - y[Y_I + s->hold_x] : y[Y_I + s->hold_x] - s->hold_i;
            g[W_REACH] = gr;
            neg |= (uint32_t)(gr < 0.0) << W_REACH;
        }
    }
    if (p->mech == BC_MECH_DYNAMIC) {
        if (s->stuck) {
            g[W_STICK] = p->tau_c + s->fe_tc - fabs(a->tau_net);
            neg |= (uint32_t)(g[W_STICK] < 0.0) << W_STICK;
        } else if (dir_om != 0) {
            g[W_OMEGA] = y[Y_OM] * (double)dir_om;
            neg |= (uint32_t)(g[W_OMEGA] < 0.0) << W_OMEGA;
        }
    }
    return neg;
}

static double watch_tol(const bc_plant_params *p, const bc_plant_state *s, int w)
{
    if (w < W_OPEN_LO) {
        return 1e-10 * (1.0 + fabs(s->i[0]) + fabs(s->i[1]) + fabs(s->i[2]));
    }
    if (w <= W_PAIR) {
        return 1e-10 * (1.0 + fabs(s->v_src));
    }
    if (w == W_OMEGA) {
        return 1e-12 * (1.0 + fabs(s->omega));
    }
    if (w == W_HOLD_LO || w == W_HOLD_HI) {
        return 1e-12;
    }
    if (w == W_REACH) {
        return 1e-12 * (1.0 + fabs(s->hold_i));
    }
    if (w >= W_TRIP) {
        return 1e-9 * (1.0 + p->i_trip);
    }
    return 1e-10 * (1.0 + p->tau_c + s->fe_tc);
}

/* Zero in (0, h) of the cubic Hermite interpolant through (0, g0, d0) and (h, g1, d1) (d: dg/dt), by Newton
 * from the secant; -1 if none is found. */
static double hermite_zero(double h, double g0, double g1, double d0, double d1)
{
    double u = g0 / (g0 - g1);
    for (int it = 0; it < 8; ++it) {
        double u2 = u * u, u3 = u2 * u;
        double h00 = 2.0 * u3 - 3.0 * u2 + 1.0, h10 = u3 - 2.0 * u2 + u, h01 = -2.0 * u3 + 3.0 * u2, h11 = u3 - u2;
        double g = h00 * g0 + h10 * h * d0 + h01 * g1 + h11 * h * d1;
        double dg = (6.0 * u2 - 6.0 * u) * g0 + (3.0 * u2 - 4.0 * u + 1.0) * h * d0 + (-6.0 * u2 + 6.0 * u) * g1 +
                    (3.0 * u2 - 2.0 * u) * h * d1;
        if (dg == 0.0) break;
        double un = u - g / dg;
        if (!(un > 0.0 && un < 1.0)) return -1.0;
        if (fabs(un - u) < 1e-12) return un * h;
        u = un;
    }
    return (u > 0.0 && u < 1.0) ? u * h : -1.0;
}

/* The watch w after an RK4 step of length c; the step's end state, derivative and aux land in *root. */
typedef struct {
    double h;
    double y[NY], dy[NY];
    aux_t a;
} root_pt;

static double watch_at(const bc_plant_params *p, const bc_plant_state *s, const double *y0, const double *k1,
                       double c, int w, int dir_om, root_pt *rp)
{
    double g[NW];
    state_step(p, s, y0, k1, c, rp->y, 0);
    core(p, s, rp->y, rp->dy, &rp->a, s->lanes_on ? WANT_DK : 0, s->work.cs);
    rp->h = c;
    (void)watch_eval(p, s, rp->y, &rp->a, dir_om, g);
    return g[w];
}

/* Locate the zero of watch w inside (0, h]: Illinois regula falsi on the RK4 step length. A watch that starts at
 * zero (a diode that has just begun to conduct) first has its positive excursion found by bisection; 0 is
 * returned if there is none (the crossing is immediate). */
static double root_find(const bc_plant_params *p, const bc_plant_state *s, const double *y0, const double *k1,
                        double h, int w, int dir_om, double g0, double g1, double hermite_guess, root_pt *rp)
{
    rp->h = -1.0; /* no state computed at the returned length yet */
    double tol = watch_tol(p, s, w);
    double ttol = 1e-13 * h + 1e-18;
    double a = 0.0, b = h, ga = g0, gb = g1;
    if (gb >= -tol) {
        return b;
    }
    if (!(ga > tol)) {
        for (;;) {
            if (b <= ttol) {
                return 0.0;
            }
            double c = 0.5 * b;
            double gc = watch_at(p, s, y0, k1, c, w, dir_om, rp);
            if (gc > tol) {
                a = c;
                ga = gc;
                break;
            }
            b = c;
            gb = gc;
        }
        if (gb >= -tol) {
            return b;
        }
    }
    int side = 0;
    double guess = hermite_guess >= 0.0 ? hermite_guess : -1.0;
    for (int it = 0; it < ROOT_MAX_ITER; ++it) {
        if (b - a <= ttol) {
            return b;
        }
        double c = b - gb * (b - a) / (gb - ga);
        if (guess > a && guess < b) {
            c = guess; /* first try: the zero of the cubic Hermite interpolant of the current */
        }
        guess = -1.0;
        if (!(c > a && c < b)) {
            c = 0.5 * (a + b);
        }
        double gc = watch_at(p, s, y0, k1, c, w, dir_om, rp);
        if (fabs(gc) <= tol) {
            return c;
        }
        if (gc < 0.0) {
            b = c;
            gb = gc;
            if (side == -1) ga *= 0.5;
            side = -1;
        } else {
            a = c;
            ga = gc;
            if (side == 1) gb *= 0.5;
            side = 1;
        }
    }
    return b;
}

/* The held current reached its reference (free -> hold): hold if d* is in [0, 1] there, else stay free at the bound
 * beyond which d* lies (the current then moves away from the reference and the reach watch stays positive). */
static int leg_average(const bc_plant_params *p, bc_plant_state *s, int x, int32_t mode, double d, double t);

static void hold_engage(const bc_plant_params *p, bc_plant_state *s)
{
    const int x = s->hold_x;
    /* on the reference exactly (the event located it to the watch's tolerance), the sum kept zero */
    double r = s->i[x] - s->hold_i;
    int others = 0;
    for (int z = 0; z < 3; ++z) others += (z != x && s->cond[z] != BC_COND_OPEN);
    for (int z = 0; z < 3 && others > 0; ++z) {
        if (z != x && s->cond[z] != BC_COND_OPEN) s->i[z] += r / others;
    }
    if (others > 0) s->i[x] = s->hold_i;
    s->hold_on = 1;
    (void)leg_average(p, s, x, BC_LEG_PWM, 0.0, s->t);
    topology_set(p, s);
    double y[NY], dy[NY];
    aux_t a;
    pack(s, y);
    core(p, s, y, dy, &a, 0, 0);
    if (a.dh >= 0.0 && a.dh <= 1.0 && s->v_src * s->tc_hcol[x] > 0.0) return;
    s->hold_on = 0;
    s->hold_d = a.dh > 1.0 ? 1.0 : 0.0;
    (void)leg_average(p, s, x, BC_LEG_PWM, s->hold_d, s->t);
}

/* Apply the transition of watch w at the current state. */
static void apply_event(const bc_plant_params *p, bc_plant_state *s, int w, const aux_t *a)
{
    if (w < W_OPEN_LO) {
        int x = w - W_DIODE;
        double r = s->i[x];
        s->i[x] = 0.0;
        /* keep the sum exactly zero */
        int others = 0;
        for (int z = 0; z < 3; ++z) others += (z != x && s->cond[z] != BC_COND_OPEN);
        for (int z = 0; z < 3 && others > 0; ++z) {
            if (z != x && s->cond[z] != BC_COND_OPEN) s->i[z] += r / others;
        }
        s->cond[x] = BC_COND_OPEN;
        if (s->t_iz[x] < 0.0) s->t_iz[x] = s->t;
        if (others == 1) { /* the last pair stopped: the other phase stops too */
            for (int z = 0; z < 3; ++z) {
                if (z != x && s->cond[z] != BC_COND_OPEN && fabs(s->i[z]) < 1e-9) {
                    s->i[z] = 0.0;
                    if (s->cond[z] == BC_COND_D_L || s->cond[z] == BC_COND_D_U) s->cond[z] = BC_COND_OPEN;
                    if (s->t_iz[z] < 0.0) s->t_iz[z] = s->t;
                }
            }
        }
    } else if (w < W_OPEN_HI) {
        s->cond[w - W_OPEN_LO] = BC_COND_D_L;
    } else if (w < W_PAIR) {
        s->cond[w - W_OPEN_HI] = BC_COND_D_U;
    } else if (w == W_PAIR) {
        int hi = -1, lo = -1;
        (void)pair_margin(p, s, a, &hi, &lo);
        if (hi >= 0 && lo >= 0 && hi != lo) {
            s->cond[hi] = BC_COND_D_U;
            s->cond[lo] = BC_COND_D_L;
        }
    } else if (w == W_OMEGA) {
        s->omega = 0.0;
        if (fabs(a->tau_net) <= p->tau_c + s->fe_tc) {
            s->stuck = 1;
        } else {
            int nd = a->tau_net > 0.0 ? 1 : -1;
            if (nd != s->dir) {
                s->dir = nd;
                pieces_locate(p, s);
            }
        }
    } else if (w == W_HOLD_LO || w == W_HOLD_HI) {
        /* d* left [0, 1]: free at the bound it crossed (the current leaves the reference) */
        s->hold_on = 0;
        s->hold_d = w == W_HOLD_HI ? 1.0 : 0.0;
        (void)leg_average(p, s, s->hold_x, BC_LEG_PWM, s->hold_d, s->t);
    } else if (w == W_REACH) {
        hold_engage(p, s);
    } else if (w >= W_TRIP) {
        s->tripped = 1;
        s->hold_x = -1;
        s->hold_on = 0; /* every gate off from now on: the diodes carry the currents to zero */
        s->t_trip = s->t;
        for (int x = 0; x < 3; ++x) {
            if (s->avg[x]) leg_average_end(s, x, s->t);
            s->des[x] = BC_GATE_O;
            s->edge_to[x] = -1;
            if (s->gate[x] == BC_GATE_U) s->t_off_u[x] = s->t;
            if (s->gate[x] == BC_GATE_L) s->t_off_l[x] = s->t;
            if (s->gate[x] != BC_GATE_O && s->sw_on) book_edge(p, s, x, s->gate[x], 0);
            s->gate[x] = BC_GATE_O;
        }
    } else if (w == W_STICK) {
        s->stuck = 0;
        int nd = a->tau_net > 0.0 ? 1 : -1;
        if (nd != s->dir) {
            s->dir = nd;
            pieces_locate(p, s);
        }
    }
    resolve(p, s);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* public                                                                                                     */

static int finite_nonneg(double v) { return isfinite(v) && v >= 0.0; }

int bc_plant_init(const bc_plant_params *p, bc_plant_state *s, double t0, double theta0, double omega0,
                  const double i0[3], double v_src)
{
    if (p == 0 || s == 0 || i0 == 0) return BC_ERR_PARAM;
    if (p->p < 1 || !finite_nonneg(p->R) || !(isfinite(p->L) && p->L > 0.0)) return BC_ERR_PARAM;
    for (int x = 0; x < 3; ++x) {
        if (bc_emf_check(&p->emf[x]) != BC_OK) return BC_ERR_PARAM;
        if (!isfinite(p->hall_error[x]) || fabs(p->hall_error[x]) >= BC_PI / 6.0) return BC_ERR_PARAM;
        if (!finite_nonneg(p->hall_hyst[x]) || p->hall_hyst[x] >= BC_PI / 3.0) return BC_ERR_PARAM;
        if (!finite_nonneg(p->hall_delay[x]) || !finite_nonneg(p->hall_tau[x])) return BC_ERR_PARAM;
    }
    if (p->n_cog < 0) return BC_ERR_PARAM;
    if (p->n_cog > 0) {
        if (p->cog_order == 0 || p->cog_amp == 0 || p->cog_phase == 0) return BC_ERR_PARAM;
        for (int32_t j = 0; j < p->n_cog; ++j) {
            if (!isfinite(p->cog_order[j]) || !isfinite(p->cog_amp[j]) || !isfinite(p->cog_phase[j]))
                return BC_ERR_PARAM;
        }
    }
    if (!(isfinite(p->f_pwm) && p->f_pwm > 0.0)) return BC_ERR_PARAM;
    if (!finite_nonneg(p->t_dead) || p->t_dead >= 0.25 / p->f_pwm) return BC_ERR_PARAM;
    if (!finite_nonneg(p->R_on) || !finite_nonneg(p->V_f) || !finite_nonneg(p->r_d) || !finite_nonneg(p->R_src) ||
        !finite_nonneg(p->i_trip))
        return BC_ERR_PARAM;
    if (p->inverter != BC_INV_SWITCHING && p->inverter != BC_INV_AVERAGE) return BC_ERR_PARAM;
    if (!finite_nonneg(p->E_on) || !finite_nonneg(p->E_off) || !finite_nonneg(p->E_rr)) return BC_ERR_PARAM;
    if (!finite_nonneg(p->k_fe_e) || !finite_nonneg(p->k_fe_h) || !finite_nonneg(p->k_fe_x)) return BC_ERR_PARAM;
    int sw_on = p->E_on > 0.0 || p->E_off > 0.0 || p->E_rr > 0.0;
    if (sw_on && !(isfinite(p->V_test) && p->V_test > 0.0 && isfinite(p->I_test) && p->I_test > 0.0))
        return BC_ERR_PARAM;
    if (p->mech != BC_MECH_IMPOSED && p->mech != BC_MECH_DYNAMIC) return BC_ERR_PARAM;
    if (p->mech == BC_MECH_DYNAMIC && !(isfinite(p->J) && p->J > 0.0)) return BC_ERR_PARAM;
    if (!finite_nonneg(p->B) || !finite_nonneg(p->tau_c) || !finite_nonneg(p->k_q)) return BC_ERR_PARAM;
    if (!isfinite(p->h_max)) return BC_ERR_PARAM;
    for (int j = 0; j < BC_FAULT_MAX; ++j) {
        const bc_fault *f = &p->fault[j];
        if (f->kind == BC_FAULT_NONE) continue;
        if (f->kind < BC_FAULT_NONE || f->kind > BC_FAULT_HALL_GLITCH || f->phase < 0 || f->phase > 2) return BC_ERR_PARAM;
        if (isnan(f->t_on) || isnan(f->t_off) || !(f->t_off > f->t_on) || !isfinite(f->value)) return BC_ERR_PARAM;
    }
    if (!isfinite(t0) || !isfinite(theta0) || !isfinite(omega0) || !isfinite(v_src)) return BC_ERR_PARAM;
    for (int x = 0; x < 3; ++x) {
        if (!isfinite(i0[x])) return BC_ERR_PARAM;
    }

    memset(s, 0, sizeof *s);
    s->tc_cond[0] = s->tc_cond[1] = s->tc_cond[2] = -1; /* no conduction coefficients computed yet */
    s->hold_x = -1; /* no ideal current limiter */
    s->t_iz[0] = s->t_iz[1] = s->t_iz[2] = -1.0;
    s->r_ph = p->R; /* at the parameters' temperature (bc_plant_set_thermal) */
    s->r_on = p->R_on;
    s->k_scale = 1.0;
    s->t = t0;
    s->sw_on = sw_on;
    s->sw_inv_vi = sw_on ? 1.0 / (p->V_test * p->I_test) : 0.0;
    s->fe_on = p->k_fe_e > 0.0 || p->k_fe_h > 0.0 || p->k_fe_x > 0.0;
    s->fe_tc = (double)p->p * p->k_fe_h;
    s->drag_on = p->B > 0.0 || p->tau_c > 0.0 || s->fe_on;
    s->prop_on = p->k_q > 0.0 && p->mech == BC_MECH_DYNAMIC;
    /* the rotor equation multiplies by 1/J: a division in every derivative evaluation would cost its latency */
    s->work.inv_J = p->mech == BC_MECH_DYNAMIC ? 1.0 / p->J : 0.0;
    /* the optional lanes integrate when a rate can be nonzero: iron loss, or switching losses on averaged legs
     * (the switching inverter books them at its gate edges) */
    lanes_select(p, s, BC_ACC_ALL);
    s->emf_tables = p->emf[0].kind == BC_EMF_TABLE && p->emf[1].kind == BC_EMF_TABLE && p->emf[2].kind == BC_EMF_TABLE;
    s->fz_n = 0;
    for (int x = 0; x < 3; ++x) {
        int32_t n = p->emf[x].kind == BC_EMF_FOURIER ? p->emf[x].n : BC_PLANT_FZ_N + 1;
        if (n > s->fz_n) s->fz_n = n;
    }
    if (s->fz_n > BC_PLANT_FZ_N) s->fz_n = 0;
    for (int x = 0; x < 3 && s->fz_n > 0; ++x) {
        /* x_m cos(m (th - phi)) + y_m sin(m (th - phi)) = a_m cos(m th) + b_m sin(m th), a_m = x_m cos(m phi) -
         * y_m sin(m phi), b_m = x_m sin(m phi) + y_m cos(m phi); the phase offset phi = 2 pi x/3 */
        for (int32_t m = 0; m < s->fz_n; ++m) {
            double xm = m < p->emf[x].n ? p->emf[x].x[m] : 0.0, ym = m < p->emf[x].n ? p->emf[x].y[m] : 0.0;
            double cp = cos((double)m * PHI[x]), sp = sin((double)m * PHI[x]);
            s->fz_a[x][m] = xm * cp - ym * sp;
            s->fz_b[x][m] = xm * sp + ym * cp;
        }
    }
    double mean = (i0[0] + i0[1] + i0[2]) / 3.0;
    for (int x = 0; x < 3; ++x) {
        s->i[x] = i0[x] - mean;
    }
    double th = fmod(theta0, BC_TWO_PI);
    if (th < 0.0) th += BC_TWO_PI;
    if (th >= BC_TWO_PI) th = 0.0;
    s->theta = th;
    s->turns = 0u;
    s->omega = omega0;
    s->dir = omega0 < 0.0 ? -1 : 1;
    s->v_src = v_src;
    s->t_half = t0;
    s->rising = 1;
    for (int x = 0; x < 3; ++x) {
        s->cmd[x].mode = BC_LEG_OFF;
        s->cmd[x].duty = 0.0f;
        s->des[x] = BC_GATE_O;
        s->gate[x] = BC_GATE_O;
        s->edge_to[x] = -1;
        s->t_off_u[x] = -HUGE_VAL;
        s->t_off_l[x] = -HUGE_VAL;
        s->cond[x] = BC_COND_OPEN;
    }
    hall_locate(p, s, -1);
    pieces_locate(p, s);
    for (int j = 0; j < BC_FAULT_MAX; ++j) s->has_faults |= p->fault[j].kind != BC_FAULT_NONE;
    s->hall_true = s->hall_raw;
    for (int x = 0; x < 3; ++x) {
        s->hf_t[x] = t0;
        s->hf_u[x] = (s->hall_raw >> x) & 1;
        s->hf_v[x] = (double)s->hf_u[x];
    }
    s->hall_out = hall_visible(p, s, t0);
    s->t_edge = -HUGE_VAL;
    (void)faults_apply(p, s);
    resolve(p, s);
    bc_plant_reset_extremes(p, s);
    return BC_OK;
}

void bc_plant_set_inputs(const bc_plant_params *p, bc_plant_state *s, double omega, double tau_load, double v_src)
{
    double tl = isfinite(tau_load) ? tau_load : 0.0;
    double vs = isfinite(v_src) ? v_src : 0.0;
    int imposed = p->mech == BC_MECH_IMPOSED && isfinite(omega);
    if (tl == s->tau_load && vs == s->v_src && (!imposed || omega == s->omega)) {
        return; /* nothing changed: the cached derivative stays valid */
    }
    s->tau_load = tl;
    s->v_src = vs;
    if (imposed) {
        s->omega = omega;
        int nd = omega < 0.0 ? -1 : (omega > 0.0 ? 1 : s->dir);
        if (nd != s->dir) {
            s->dir = nd;
            pieces_locate(p, s);
        }
    }
    s->work.valid = 0;
    resolve_open(p, s);
}

/* Leg x applies the half-period average of `mode` at duty d in (0, 1) from time t (bc_plant.h). Returns 1 if the
 * circuit changed. */
static int leg_average(const bc_plant_params *p, bc_plant_state *s, int x, int32_t mode, double d, double t)
{
    double fu = 0.0, fl = 0.0, fo = 0.0;
    switch (mode) {
    case BC_LEG_PWM: fu = d; fl = 1.0 - d; break; /* dead time neglected */
    case BC_LEG_HIGH: fu = d; fo = 1.0 - d; break;
    default: fl = d; fo = 1.0 - d; break; /* BC_LEG_LOW */
    }
    int changed = !s->avg[x] || fu != s->fr_u[x] || fl != s->fr_l[x] || fo != s->fr_o[x];
    s->avg[x] = 1;
    s->fr_u[x] = fu;
    s->fr_l[x] = fl;
    s->fr_o[x] = fo;
    s->des[x] = BC_GATE_O; /* the gate machinery rests; the fractions set the leg */
    (void)gate_update(p, s, x, t);
    return changed;
}

/* Apply leg commands from time t inside the current half period (started at t_half, rising or not): each leg's gate
 * follows the centre-aligned carrier, so at t it is where the command puts it at that instant (bc_plant.h), with its
 * remaining edge pending. Averaged legs apply the command's half-period average from t. */
static void legs_apply(const bc_plant_params *p, bc_plant_state *s, const bc_leg_cmd cmd[3], double i_hold, double t)
{
    double th = bc_plant_t_half(p);
    double t0 = s->t_half;
    int changed = 0;
    /* the ideal current limiter: one HOLD leg with a finite current, on the averaged inverter without R_src */
    int hx = -1;
    for (int x = 0; x < 3; ++x) {
        if (cmd[x].mode != BC_LEG_HOLD) continue;
        if (hx >= 0 || p->inverter != BC_INV_AVERAGE || p->R_src > 0.0 || !isfinite(i_hold) || s->tripped) {
            s->flags |= BC_PLANT_BAD_DUTY; /* the legs asking for it are off */
            hx = -2;
        } else {
            hx = x;
        }
    }
    if (hx >= 0) {
        double ir = i_hold;
        if (hx != s->hold_x || ir != s->hold_i) { /* a new reference or leg starts free, at full drive toward it */
            s->hold_x = hx;
            s->hold_i = ir;
            s->hold_on = 0;
            s->hold_d = s->i[hx] < ir ? 1.0 : 0.0;
        }
    } else {
        s->hold_x = -1;
        s->hold_on = 0;
    }
    for (int x = 0; x < 3; ++x) {
        int32_t mode = cmd[x].mode;
        float d = cmd[x].duty;
        if (mode == BC_LEG_HOLD && x == s->hold_x) {
            s->cmd[x] = cmd[x];
            s->edge_to[x] = -1;
            changed |= leg_average(p, s, x, BC_LEG_PWM, s->hold_on ? 0.0 : s->hold_d, t);
            continue;
        }
        if (mode < BC_LEG_OFF || mode > BC_LEG_LOW) {
            mode = BC_LEG_OFF;
            s->flags |= BC_PLANT_BAD_DUTY;
        }
        if (!(d >= 0.0f)) { /* negative or NaN */
            d = 0.0f;
            s->flags |= BC_PLANT_BAD_DUTY;
        } else if (d > 1.0f) {
            d = 1.0f;
            s->flags |= BC_PLANT_BAD_DUTY;
        }
        if (s->tripped) {
            mode = BC_LEG_OFF; /* the hardware protection holds the gates off */
            d = 0.0f;
        }
        s->cmd[x].mode = mode;
        s->cmd[x].duty = d;
        double dd = (double)d;
        int32_t act = mode_gate(mode, 1), idle = mode_gate(mode, 0);
        s->edge_to[x] = -1;
        if (p->inverter == BC_INV_AVERAGE && act != idle && dd > 0.0 && dd < 1.0) {
            changed |= leg_average(p, s, x, mode, dd, t);
            continue;
        }
        if (s->avg[x]) {
            leg_average_end(s, x, t);
            changed = 1;
        }
        if (s->rising) { /* idle, then active from t0 + (1 - d) T/2 */
            if (dd >= 1.0) {
                s->des[x] = act;
            } else {
                double te = t0 + (1.0 - dd) * th;
                s->des[x] = (dd > 0.0 && t >= te) ? act : idle;
                if (dd > 0.0 && act != idle && t < te) {
                    s->edge_to[x] = act;
                    s->edge_t[x] = te;
                }
            }
        } else { /* active until t0 + d T/2, then idle */
            if (dd <= 0.0) {
                s->des[x] = idle;
            } else {
                double te = t0 + dd * th;
                s->des[x] = (dd >= 1.0 || t < te) ? act : idle;
                if (dd < 1.0 && act != idle && t < te) {
                    s->edge_to[x] = idle;
                    s->edge_t[x] = te;
                }
            }
        }
        changed |= gate_update(p, s, x, t);
    }
    if (changed) {
        resolve(p, s); /* otherwise the circuit and its cached derivative are unchanged */
    }
}

void bc_plant_set_half(const bc_plant_params *p, bc_plant_state *s, const bc_leg_cmd cmd[3], int rising)
{
    s->t_half = s->t;
    s->rising = rising ? 1 : 0;
    s->at_on = 0;
    legs_apply(p, s, cmd, s->hold_req, s->t);
}

void bc_plant_set_hold(const bc_plant_params *p, bc_plant_state *s, double i_hold, double i_hold_at)
{
    (void)p;
    s->hold_req = i_hold;
    s->hold_req_at = i_hold_at;
}

void bc_plant_schedule(const bc_plant_params *p, bc_plant_state *s, const bc_leg_cmd cmd[3], double dt)
{
    double th = bc_plant_t_half(p);
    if (!(dt >= 0.0)) dt = 0.0; /* NaN or negative: now */
    if (dt >= th) return;        /* beyond this half period: not in it */
    for (int x = 0; x < 3; ++x) s->at_cmd[x] = cmd[x];
    s->at_hold = s->hold_req_at;
    s->at_t = s->t_half + dt;
    s->at_on = 1;
    if (!(s->at_t > s->t)) { /* due now */
        s->at_on = 0;
        legs_apply(p, s, s->at_cmd, s->at_hold, s->t);
    }
}

/* Next start or end of an injected fault after the current time (HUGE_VAL if none). */
static double next_fault_time(const bc_plant_params *p, const bc_plant_state *s)
{
    double tn = HUGE_VAL;
    if (!s->has_faults) return tn;
    for (int j = 0; j < BC_FAULT_MAX; ++j) {
        const bc_fault *f = &p->fault[j];
        if (f->kind == BC_FAULT_NONE) continue;
        if (f->t_on > s->t && f->t_on < tn) tn = f->t_on;
        if (f->t_off > s->t && f->t_off < tn) tn = f->t_off;
    }
    return tn;
}

/* Apply the faults active now. A phase disconnected while carrying current loses it at once (an arc): the other
 * two keep the sum zero with the least change, and the magnetic energy that disappears is booked in e_fault.
 * Returns 1 if the circuit changed. */
static int faults_apply(const bc_plant_params *p, bc_plant_state *s)
{
    if (!s->has_faults) return 0;
    int32_t open = 0;
    for (int j = 0; j < BC_FAULT_MAX; ++j) {
        const bc_fault *f = &p->fault[j];
        if (f->kind == BC_FAULT_PHASE_OPEN && s->t >= f->t_on && s->t < f->t_off) open |= 1 << f->phase;
    }
    hall_refresh(p, s, s->t);
    if (open == s->open_fault) return 0;
    int32_t newly = open & ~s->open_fault;
    s->open_fault = open;
    for (int x = 0; x < 3; ++x) {
        if (!(newly & (1 << x)) || s->i[x] == 0.0) continue;
        double w0 = 0.5 * p->L * (s->i[0] * s->i[0] + s->i[1] * s->i[1] + s->i[2] * s->i[2]);
        int y = (x + 1) % 3, z = (x + 2) % 3;
        double iy = 0.5 * (s->i[y] - s->i[z]);
        s->i[x] = 0.0;
        s->i[y] = iy;
        s->i[z] = -iy;
        double w1 = 0.5 * p->L * (s->i[0] * s->i[0] + s->i[1] * s->i[1] + s->i[2] * s->i[2]);
        s->e_fault += w0 - w1;
    }
    return 1;
}

/* Process everything due at the current time and angle. Returns 1 if the circuit changed. */
static int process_due(const bc_plant_params *p, bc_plant_state *s)
{
    int changed = faults_apply(p, s);
    for (int x = 0; x < 3; ++x) {
        if (s->edge_to[x] >= 0 && s->edge_t[x] <= s->t) {
            s->des[x] = s->edge_to[x];
            s->edge_to[x] = -1;
        }
        if (s->gate[x] != s->des[x]) {
            changed |= gate_update(p, s, x, s->t);
        }
    }
    while (s->hq_n > 0 && s->hq_t[0] <= s->t) {
        hall_output_toggle(p, s, s->hq_code[0], s->hq_t[0]);
        hq_remove(s, 0);
    }
    if (changed) {
        resolve(p, s);
    }
    if (s->at_on && s->at_t <= s->t) { /* a scheduled command change (bc_plant_schedule) */
        s->at_on = 0;
        legs_apply(p, s, s->at_cmd, s->at_hold, s->t);
        changed = 1;
    }
    return changed;
}

static void ensure_k1(const bc_plant_params *p, bc_plant_state *s)
{
    if (s->work.valid) {
        return;
    }
    double y[NY], dy[NY];
    aux_t a;
    pack(s, y);
    core(p, s, y, dy, &a, s->lanes_on ? WANT_DK : 0, 0);
    work_fill(p, s, y, dy, &a);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* torque extremes inside a step                                                                              */

/* Fold the turning points of the cubic Hermite interpolant through (0, f0, d0) and (h, f1, d1) into [*lo, *hi]:
 *     q(u) = f0 + m0 u + (3 D - 2 m0 - m1) u^2 + (m0 + m1 - 2 D) u^3,  u in (0, 1),  m = h d,  D = f1 - f0. */
static BC_ALWAYS_INLINE void hermite_extremes(double h, double f0, double f1, double d0, double d1, double *lo, double *hi)
{
    double m0 = h * d0, m1 = h * d1, D = f1 - f0;
    double c2 = 3.0 * D - 2.0 * m0 - m1, c3 = m0 + m1 - 2.0 * D;
    /* q'(u) in Bernstein form on [0, 1] has the coefficients m0, m0 + c2, m1: all three of one sign, with a margin far
     * above the rounding of the roots below, leave no turning point inside (a torque monotonic over the step, the
     * common case) and nothing to solve for */
    const double mu = 1e-6 * (fabs(m0) + fabs(m1) + fabs(D)), b1 = m0 + c2;
    if ((m0 > mu && m1 > mu && b1 > mu) || (m0 < -mu && m1 < -mu && b1 < -mu)) return;
    /* q'(u) = m0 + 2 c2 u + 3 c3 u^2 */
    double a = 3.0 * c3, b = 2.0 * c2, c = m0;
    double u[2];
    int n = 0;
    double scale = fabs(a) + fabs(b) + fabs(c);
    if (!(scale > 0.0) || !isfinite(scale)) return;
    if (fabs(a) <= 1e-12 * scale) {
        if (b != 0.0) u[n++] = -c / b;
    } else {
        double disc = b * b - 4.0 * a * c;
        if (disc < 0.0) return;
        double sq = sqrt(disc);
        double qq = -0.5 * (b + (b >= 0.0 ? sq : -sq));
        if (qq != 0.0) {
            u[n++] = qq / a;
            u[n++] = c / qq;
        } else {
            u[n++] = 0.0;
        }
    }
    for (int j = 0; j < n; ++j) {
        double v = u[j];
        if (!(v > 0.0 && v < 1.0)) continue;
        double f = f0 + v * (m0 + v * (c2 + v * c3));
        if (f < *lo) *lo = f;
        if (f > *hi) *hi = f;
    }
}

/* A step of length h has ended at the current state (y1, dy1 = f(y1), aux a1; the work cache still holds its start):
 * integrate acc[] over it and update the extremes, including the torque's turning points inside the step (from the
 * torque and its rate at both ends), while acc_on; then tell the observer. */
static BC_ALWAYS_INLINE void step_done(const bc_plant_params *p, bc_plant_state *s, double h, const double *y1, const double *dy1,
                      const aux_t *a1, double *f1, double *fd1)
{
    if (s->lanes_on) lanes(p, s, y1, dy1, a1, f1, fd1);
    if (s->term_on && s->on_term && h > 0.0) {
        const double *f0 = s->work.f[s->work.cur], *fd0 = s->work.fd[s->work.cur];
        s->on_term(s->on_step_ctx, s->t - h, s->t, f0 + BC_ACC_VA, fd0 + BC_ACC_VA, f1 + BC_ACC_VA, fd1 + BC_ACC_VA,
                   a1->vbus);
    }
    if (s->acc_on) {
        if (h > 0.0) acc_step(s->acc, s->acc_hi, h, s->work.f[s->work.cur], s->work.fd[s->work.cur], f1, fd1);
        double tau0 = s->work.tau, tau1 = a1->tau;
        if (tau1 < s->tau_min) s->tau_min = tau1;
        if (tau1 > s->tau_max) s->tau_max = tau1;
        if (h > 0.0) {
            hermite_extremes(h, tau0, tau1, s->work.fd[s->work.cur][BC_ACC_TAU], fd1[BC_ACC_TAU], &s->tau_min,
                             &s->tau_max);
        }
        for (int x = 0; x < 3; ++x) {
            double v = fabs(s->i[x]);
            if (v > s->i_peak[x]) s->i_peak[x] = v;
        }
        /* the step's conduction state (apply_event changes it after this call): with two phases open the third
         * carries no current either (no neutral wire), whatever its switches do */
        int zero_i = (s->cond[0] == BC_COND_OPEN) + (s->cond[1] == BC_COND_OPEN) + (s->cond[2] == BC_COND_OPEN) >= 2;
        if (zero_i && h > 0.0) {
            s->t_zero_i += h;
            if (!s->zero_i) s->n_zero_i += 1;
        }
        if (h > 0.0) s->zero_i = zero_i;
    }
    if (s->on_step) s->on_step(s->on_step_ctx, s->t, s->acc, a1->tau);
}

void bc_plant_advance(const bc_plant_params *p, bc_plant_state *s, double t_end)
{
    double hmax = h_max_of(p);
    int zero_len = 0;
    double y0[NY], y1[NY], k1n[NY];
    root_pt rtry, rbest;
    for (;;) {
        process_due(p, s);
        if (s->t >= t_end) {
            break;
        }
        ensure_k1(p, s);
        if (p->mech == BC_MECH_DYNAMIC && !s->stuck) {
            /* the angle pieces and Hall intervals face the way the rotor moves. A speed zero crossing is an event
             * that turns them; a start from rest is not (no crossing to watch): at rest the rotor moves the way it
             * accelerates, and a step that left rest with zero acceleration is caught by its speed's sign */
            double acc = s->work.k1[Y_OM];
            int nd = s->omega < 0.0 ? -1 : s->omega > 0.0 ? 1 : (acc < 0.0 ? -1 : (acc > 0.0 ? 1 : s->dir));
            if (nd != s->dir) {
                s->dir = nd;
                pieces_locate(p, s);
            }
        }
        pack(s, y0);
        /* the step's end goes into the other buffers, current once the step is accepted */
        const int nx = s->work.cur ^ 1;
        double *f1 = s->work.f[nx], *fd1 = s->work.fd[nx], *g1 = s->work.w[nx];
        aux_t *a1 = &s->work.a[nx];
        /* the step: to the target, a gate edge, a delayed Hall edge, h_max, or an angle bound */
        double t_stop = t_end;
        double tg = next_gate_time(p, s);
        if (tg < t_stop) t_stop = tg;
        if (s->hq_n > 0 && s->hq_t[0] < t_stop) t_stop = s->hq_t[0];
        double tf = next_fault_time(p, s);
        if (tf < t_stop) t_stop = tf;
        if (s->t + hmax < t_stop) t_stop = s->t + hmax;
        double th_ev = 0.0;
        double ha = angle_event(p, s, &th_ev, t_stop - s->t);
        int angle_step = 0;
        if (s->t + ha < t_stop) {
            t_stop = s->t + ha;
            angle_step = 1;
        }
        double h = t_stop - s->t;
        if (!(h > 0.0)) {
            /* nothing left to integrate at this instant (an angle bound at the current angle, rounding) */
            if (angle_step) {
                angles_cross(p, s, th_ev);
                s->work.valid = 0;
            }
            if (++zero_len > MAX_ZERO_LENGTH_EVENTS) {
                s->flags |= BC_PLANT_CHATTER;
                h = 1e-9 * bc_plant_t_half(p);
                t_stop = s->t + h;
                angle_step = 0;
            } else {
                continue;
            }
        }
        sin_fold fold; /* the step's sinusoid and anchor: its RK4 stages and its end */
        sin_fold_init(s, &fold);
        state_step(p, s, y0, s->work.k1, h, y1, &fold);
        core_at(p, s, y1, k1n, a1, s->lanes_on ? WANT_DK : 0, s->work.cs, &fold);
        /* watched functions: the first that goes negative inside the step is an event */
        int dir_om = s->work.wdir;
        const uint32_t neg = watch_eval(p, s, y1, a1, dir_om, g1);
        int w_hit = -1;
        double h_hit = h;
        if (neg && zero_len <= MAX_ZERO_LENGTH_EVENTS) {
            const double *g0 = s->work.w[s->work.cur]; /* the watches at the step start (the same active set) */
            for (int w = 0; w < NW; ++w) {
                if (neg & (1u << w)) {
                    double guess = -1.0;
                    if (w < W_OPEN_LO && g0[w] > 0.0) { /* a diode current: its derivative is known at both ends */
                        int x = w - W_DIODE;
                        double sg = s->cond[x] == BC_COND_D_L ? 1.0 : -1.0;
                        guess = hermite_zero(h, g0[w], g1[w], sg * s->work.k1[Y_I + x], sg * k1n[Y_I + x]);
                    }
                    double hw = root_find(p, s, y0, s->work.k1, h, w, dir_om, g0[w], g1[w], guess, &rtry);
                    if (w_hit < 0 || hw < h_hit) {
                        w_hit = w;
                        h_hit = hw;
                        if (rtry.h == hw) {
                            rbest = rtry;
                        } else {
                            rbest.h = -1.0;
                        }
                    }
                }
            }
        }
        if (w_hit >= 0) {
            if (h_hit < h && rbest.h == h_hit) {
                memcpy(y1, rbest.y, sizeof y1);
                memcpy(k1n, rbest.dy, sizeof k1n);
                *a1 = rbest.a;
            } else if (h_hit < h) {
                state_step(p, s, y0, s->work.k1, h_hit, y1, &fold);
                core(p, s, y1, k1n, a1, s->lanes_on ? WANT_DK : 0, 0);
            }
            unpack(s, y1);
            s->work.a_ok = 0; /* the cache holds the step's start */
            s->work.out_ok = 0;
            s->t = (h_hit < h) ? s->t + h_hit : t_stop;
            if (p->mech == BC_MECH_IMPOSED) s->omega = y0[Y_OM];
            step_done(p, s, h_hit < h ? h_hit : h, y1, k1n, a1, f1, fd1);
            s->work.tau = a1->tau;
            apply_event(p, s, w_hit, a1);
            s->n_events += 1;
            s->n_steps += 1;
            if (h_hit <= 0.0) {
                /* a diode that began to conduct at this instant is reverse-driven at once: it stays open until
                 * time moves on (the terminal sits at its clamp and is leaving it) */
                if (w_hit < W_OPEN_LO && y0[Y_I + (w_hit - W_DIODE)] == 0.0) {
                    s->hold_open |= 1 << (w_hit - W_DIODE);
                    s->cond[w_hit - W_DIODE] = BC_COND_OPEN;
                    topology_set(p, s);
                    s->work.valid = 0;
                }
                ++zero_len;
            } else {
                s->hold_open = 0;
                zero_len = 0;
            }
            wrap_angle(p, s);
            continue;
        }
        unpack(s, y1);
        s->t = t_stop;
        step_done(p, s, h, y1, k1n, a1, f1, fd1);
        s->work.tau = a1->tau;
        memcpy(s->work.k1, k1n, sizeof k1n);
        memcpy(s->work.cs, a1->cs, sizeof a1->cs);
        s->work.a_ok = 1;
        s->work.out_ok = 1;
        s->work.cur = nx; /* the step's end (f1, fd1, g1, a1) starts the next step */
        s->work.valid = 1;
        s->n_steps += 1;
        zero_len = 0;
        s->hold_open = 0;
        if (angle_step && angles_cross(p, s, th_ev) && s->lanes_on) {
            /* the shapes are continuous, so the cached derivative stays valid; their slopes are not: the power
             * flows' rates start the next step on the new pieces */
            aux_t *a = &s->work.a[s->work.cur];
            core(p, s, y1, k1n, a, WANT_DK, 0);
            lanes(p, s, y1, s->work.k1, a, s->work.f[s->work.cur], s->work.fd[s->work.cur]);
        }
        wrap_angle(p, s);
    }
}

double bc_plant_vbus(const bc_plant_params *p, const bc_plant_state *s)
{
    double idc = 0.0;
    for (int x = 0; x < 3; ++x) {
        if (s->avg[x]) {
            /* an averaged leg at the sample instant, as the switching legs are there: at the end of a rising half
             * (carrier peak) in its active state, at the end of a falling half (valley) in its idle state */
            int up = s->rising ? s->fr_u[x] > 0.0 : (s->fr_o[x] > 0.0 && s->cond[x] == BC_COND_D_U);
            if (s->cond[x] != BC_COND_OPEN && up) idc += s->i[x];
        } else if (s->cond[x] == BC_COND_SW_U || s->cond[x] == BC_COND_D_U) {
            idc += s->i[x];
        }
    }
    return s->v_src - p->R_src * idc;
}

void bc_plant_output(const bc_plant_params *p, const bc_plant_state *s, bc_plant_out *out)
{
    double y[NY], dy[NY];
    aux_t a;
    pack(s, y);
    /* the circuit quantities of the current state are cached where the integrator computed them at it with the
     * terminals (the trace's lanes on: every step end, gate edge and refill computes them by the same expressions) */
    if (s->work.valid && s->work.a_ok && s->work.out_ok && s->lanes_on && (s->acc_mask & (1u << BC_ACC_VA))) {
        aux_to_out(p, s, y, &s->work.a[s->work.cur], out);
        return;
    }
    core(p, s, y, dy, &a, WANT_V, 0);
    aux_to_out(p, s, y, &a, out);
}

double bc_plant_tau(const bc_plant_params *p, bc_plant_state *s)
{
    ensure_k1(p, s);
    return s->work.tau;
}

/* Select the lanes for accumulation level `level` and the terminals' watch; lanes that start being computed get
 * their rates at the current state (the start of the next step). The cached derivative stays: the state's path is
 * the same whatever is computed. */
static void lanes_change(const bc_plant_params *p, bc_plant_state *s, int level)
{
    uint32_t had = s->acc_mask;
    lanes_select(p, s, level);
    if ((s->acc_mask & ~had) != 0u && s->work.valid) {
        double y[NY], dy[NY];
        aux_t *a = &s->work.a[s->work.cur]; /* with dk now: the power flows need it */
        pack(s, y);
        core(p, s, y, dy, a, WANT_DK, 0);
        s->work.a_ok = 1;
        s->work.out_ok = 1;
        lanes(p, s, y, s->work.k1, a, s->work.f[s->work.cur], s->work.fd[s->work.cur]);
    }
}

void bc_plant_set_accumulate(const bc_plant_params *p, bc_plant_state *s, int level)
{
    int v = level <= BC_ACC_OFF ? BC_ACC_OFF : (level >= BC_ACC_ALL ? BC_ACC_ALL : BC_ACC_METRICS);
    if (v != s->acc_on) lanes_change(p, s, v);
}

void bc_plant_set_terminals(const bc_plant_params *p, bc_plant_state *s, int on)
{
    int v = on ? 1 : 0;
    if (v == s->term_on) return;
    s->term_on = v;
    lanes_change(p, s, s->acc_on);
}

int bc_plant_set_thermal(const bc_plant_params *p, bc_plant_state *s, double r_scale, double k_scale,
                         double ron_scale)
{
    if (!(isfinite(r_scale) && r_scale > 0.0 && isfinite(k_scale) && k_scale > 0.0 && isfinite(ron_scale) &&
          ron_scale > 0.0))
        return BC_ERR_PARAM;
    s->r_ph = p->R * r_scale;
    s->r_on = p->R_on * ron_scale;
    s->k_scale = k_scale;
    /* every coefficient afresh: the device resistances of the switching legs and B = P (M + R I) */
    for (int x = 0; x < 3; ++x) s->tc_cond[x] = -1;
    s->tc_b_ok = 0;
    topology_set(p, s);
    s->work.valid = 0;
    return BC_OK;
}

void bc_plant_reset_extremes(const bc_plant_params *p, bc_plant_state *s)
{
    ensure_k1(p, s);
    s->tau_min = s->work.tau;
    s->tau_max = s->work.tau;
    for (int x = 0; x < 3; ++x) {
        s->i_peak[x] = fabs(s->i[x]);
    }
}

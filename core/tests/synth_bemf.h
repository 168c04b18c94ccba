/* synth_bemf.h - a synthetic sensorless drive for the host tests of bc_bemf: a rotor, the phase pair the controller
 * drives, and what its comparators and ADC see.
 *
 * Rotor. Kinematic (theta(t) = th0 + w0 t + acc t^2 / 2, electrical, until t_freeze, after which it stands still),
 * or dynamic (dyn = 1): d omega / dt = k_acc i (k_pos - k_neg) - damp omega - load sgn(omega), the pair current
 * i = max(0, (m V - (e_pos - e_neg)) / r2) of an average model without inductance, integrated in steps of h.
 * Back-EMF e_x = ke omega k(theta - x 2 pi/3), k the ideal 120-degree trapezoid of unit flat top, zero rising at 0.
 *
 * Terminal level of phase x (1: above the reference): driven positive 1, negative 0; floating: during the clamp after
 * the commutation that made it float (its diode carries the outgoing current for `demag` seconds, `demag_long` from
 * commutation n_long on), 0 if it was driven positive (lower diode), 1 if negative (upper diode); after it, e_x > 0.
 * The comparator shows that level d_cmp late (filter + propagation, a pure delay); edges are time-stamped
 * floor(t f_tick). A glitch (glitch_t >= 0) inverts phase glitch_x's comparator for glitch_len.
 * ADC: once per PWM period at the carrier peak (odd samples), of the terminal voltage d_adc late (rail: 0 or V,
 * floating unclamped V/2 + e_x, within [0, V]: beyond a rail its diode conducts), v_neutral = V/2; in the next
 * sample's input. Off-time clamp (clamp_pre, clamp_post < 1): the floating terminal (after its demagnetisation) also
 * reads the rail on its back-EMF's side (0 for e_x < 0, V for e_x > 0) where |k| exceeds clamp_pre before its
 * crossing or clamp_post after it (k the trapezoid, its ramp 30 degrees either side of the crossing): the phase
 * still conducts a current its back-EMF drove in the PWM off-time (high-side chopping: e_x < 0 clamps to 0 V).
 *
 * Blind off-times (blind = 1; ideal diodes with high-side or synchronous chopping): the pair's off-time (centred at
 * the carrier valleys, the even samples, half-width (1 - m) ts) holds both driven terminals at 0 V, and a floating
 * phase (after its demagnetisation) whose back-EMF is below the reference there conducts through its lower diode and
 * reads the reference exactly: its comparator holds the level it showed at the off-time's start a. A back-EMF that
 * rises through zero at t_z in the off-time frees it when the diode current built since a has decayed, at 2 t_z - a
 * (a linear back-EMF), or at the on-time's start b; one that falls through zero shows it at b.
 *
 * The controller's output at sample k applies from t_(k+delay) (and leg_at from there + t_at); every change of the
 * driven pair is a commutation, recorded with its time. True crossings of the floating phase are recorded too. */
#ifndef SYNTH_BEMF_H
#define SYNTH_BEMF_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "bldc/bc_types.h"

#define SB_NSEG 64
#define SB_NLOG 8192
#define SB_NSUB 256

typedef struct {
    /* rotor */
    double th0, w0, acc, t_freeze;
    int dyn;
    double k_acc, r2, damp, load, h;
    double th, w; /* dynamic state at t_now */
    /* drive and sensing */
    double ts, f_tick, v_dc, ke;
    int delay;
    double d_cmp, d_adc;
    double demag, demag_long;
    double clamp_pre, clamp_post; /* off-time clamp beyond these |k| (>= 1: none) */
    double shift[3];              /* each phase's back-EMF delayed by this electrical angle (0: the magnet's grid) */
    int blind;                    /* 1: the floating phase's comparator blind in the pair's off-time (above) */
    long n_long;
    int glitch_x;
    double glitch_t, glitch_len;
    /* pair history */
    int nseg;
    double seg_t[SB_NSEG];
    int seg_pos[SB_NSEG], seg_neg[SB_NSEG], seg_fl[SB_NSEG], seg_cl[SB_NSEG];
    double seg_m[SB_NSEG], seg_cl_end[SB_NSEG];
    /* comparators */
    int lvl[3];
    uint32_t count[3], tick[3];
    double t_eval; /* true time evaluated up to */
    /* ADC */
    uint32_t n_adc, tick_adc;
    float v_term[3];
    /* dynamic trajectory over the last sample interval */
    double tab_t0;
    int tab_n;
    double tab_th[SB_NSUB + 1];
    /* logs */
    long n_comm;
    double t_comm[SB_NLOG];
    int comm_fl[SB_NLOG];
    long n_zc;
    double t_zc[SB_NLOG];
    int zc_x[SB_NLOG];
    double t_now;
} synth_bemf;

static inline double sb_trap(double th)
{
    th = fmod(th, 2.0 * BC_PI);
    if (th < 0.0) th += 2.0 * BC_PI;
    double sgn = 1.0;
    if (th > BC_PI) {
        th -= BC_PI;
        sgn = -1.0;
    }
    double k = 1.0;
    if (th < BC_PI / 6.0) k = th / (BC_PI / 6.0);
    else if (th > 5.0 * BC_PI / 6.0) k = (BC_PI - th) / (BC_PI / 6.0);
    return sgn * k;
}

/* phase x's back-EMF angle offset: x 2 pi / 3 and its shift */
static inline double sb_off(const synth_bemf *g, int x) { return (double)x * 2.0 * BC_PI / 3.0 + g->shift[x]; }

static inline void sb_init(synth_bemf *g, double ts, double f_tick, int delay)
{
    memset(g, 0, sizeof *g);
    g->ts = ts;
    g->f_tick = f_tick;
    g->delay = delay;
    g->v_dc = 12.0;
    g->ke = 0.01;
    g->clamp_pre = 2.0;
    g->clamp_post = 2.0;
    g->t_freeze = HUGE_VAL;
    g->n_long = -1;
    g->glitch_t = -1.0;
    g->h = 0.5e-6;
    g->nseg = 1; /* all legs off from the start */
    g->seg_t[0] = -1.0;
    g->seg_pos[0] = g->seg_neg[0] = g->seg_fl[0] = -1;
    g->seg_cl_end[0] = -1.0;
}

/* a dynamic rotor at th0 (electrical rad), w0 (rad/s) */
static inline void sb_dynamic(synth_bemf *g, double th0, double w0, double k_acc, double r2, double damp, double load)
{
    g->dyn = 1;
    g->th = th0;
    g->w = w0;
    g->k_acc = k_acc;
    g->r2 = r2;
    g->damp = damp;
    g->load = load;
    g->tab_t0 = 0.0;
    g->tab_n = 0;
    g->tab_th[0] = th0;
}

/* the kinematic angle and speed */
static inline double sb_theta_kin(const synth_bemf *g, double t)
{
    double tt = t < g->t_freeze ? t : g->t_freeze;
    return g->th0 + g->w0 * tt + 0.5 * g->acc * tt * tt;
}
static inline double sb_omega(const synth_bemf *g, double t)
{
    if (g->dyn) { /* over the step of the last integrated interval that holds t */
        if (g->tab_n < 1) return g->w;
        int j = (int)((t - g->tab_t0) / g->h);
        if (j < 0) j = 0;
        if (j >= g->tab_n) j = g->tab_n - 1;
        return (g->tab_th[j + 1] - g->tab_th[j]) / g->h;
    }
    return t < g->t_freeze ? g->w0 + g->acc * t : 0.0;
}
/* angle at t (dynamic: inside the last integrated interval, linear between steps) */
static inline double sb_theta(const synth_bemf *g, double t)
{
    if (!g->dyn) return sb_theta_kin(g, t);
    double u = (t - g->tab_t0) / g->h;
    if (u <= 0.0) return g->tab_th[0];
    if (u >= (double)g->tab_n) return g->tab_th[g->tab_n];
    int j = (int)u;
    return g->tab_th[j] + (u - (double)j) * (g->tab_th[j + 1] - g->tab_th[j]);
}

static inline int sb_seg_at(const synth_bemf *g, double t)
{
    int lo = g->nseg > SB_NSEG ? g->nseg - SB_NSEG : 0;
    for (int j = g->nseg - 1; j >= lo; --j) {
        if (g->seg_t[j % SB_NSEG] <= t) return j % SB_NSEG;
    }
    return lo % SB_NSEG;
}

/* the pair's off-time [*a, *b) holding t (centred at the nearest carrier valley, half-width (1 - m) ts): 1, else 0 */
static inline int sb_offtime(const synth_bemf *g, double t, double *a, double *b)
{
    double per = 2.0 * g->ts, v = per * floor(t / per + 0.5);
    double h = (1.0 - g->seg_m[sb_seg_at(g, v)]) * g->ts;
    *a = v - h;
    *b = v + h;
    return t >= *a && t < *b;
}

static inline double sb_solve(const synth_bemf *g, double t1, double t2, double ang);

/* the zero of phase x's back-EMF in (t1, t2], if one: 1 and *tz */
static inline int sb_zero_in(const synth_bemf *g, int x, double t1, double t2, double *tz)
{
    double a1 = sb_theta(g, t1), a2 = sb_theta(g, t2), off = sb_off(g, x);
    double lo = a1 < a2 ? a1 : a2, hi = a1 < a2 ? a2 : a1;
    for (double n = ceil((lo - off) / BC_PI); n * BC_PI + off <= hi; n += 1.0) {
        double tgt = n * BC_PI + off;
        if ((a1 - tgt) * (a2 - tgt) > 0.0 || a1 == tgt) continue;
        *tz = sb_solve(g, t1, t2, tgt);
        return 1;
    }
    return 0;
}

/* phase x's back-EMF at t */
static inline double sb_emf(const synth_bemf *g, int x, double t) { return sb_omega(g, t) * sb_trap(sb_theta(g, t) - sb_off(g, x)); }

/* true level of phase x at t (the back-EMF's sign from the speed at t) */
static inline int sb_level(const synth_bemf *g, int x, double t)
{
    int j = sb_seg_at(g, t);
    if (x == g->seg_pos[j]) return 1;
    if (x == g->seg_neg[j]) return 0;
    if (x == g->seg_fl[j] && t < g->seg_cl_end[j]) return g->seg_cl[j];
    double e = sb_emf(g, x, t), a, b;
    if (g->blind && x == g->seg_fl[j] && sb_offtime(g, t, &a, &b) && a >= g->seg_t[j] && a >= g->seg_cl_end[j]) {
        int at_a = sb_emf(g, x, a) > 0.0;
        if (!(e > 0.0)) return at_a; /* clamped: the comparator holds */
        double tz;
        if (!at_a && sb_zero_in(g, x, a, t, &tz) && t < 2.0 * tz - a) return 0; /* the diode current decays */
        return 1;
    }
    return e > 0.0 ? 1 : 0;
}

/* floating phase at t, -1 if none (no pair, or all off) */
static inline int sb_floating(const synth_bemf *g, double t)
{
    int j = sb_seg_at(g, t);
    if (g->seg_pos[j] < 0 || g->seg_neg[j] < 0) return -1;
    return 3 - g->seg_pos[j] - g->seg_neg[j];
}

/* time in [t1, t2] at which theta reaches ang (theta monotonic there) */
static inline double sb_solve(const synth_bemf *g, double t1, double t2, double ang)
{
    double a = t1, b = t2, fa = sb_theta(g, a) - ang;
    for (int it = 0; it < 80; ++it) {
        double c = 0.5 * (a + b), fc = sb_theta(g, c) - ang;
        if ((fa <= 0.0) == (fc <= 0.0)) {
            a = c;
            fa = fc;
        } else {
            b = c;
        }
    }
    return 0.5 * (a + b);
}

static inline void sb_sort(double *v, int n)
{
    for (int i = 1; i < n; ++i) {
        double x = v[i];
        int j = i - 1;
        while (j >= 0 && v[j] > x) {
            v[j + 1] = v[j];
            --j;
        }
        v[j + 1] = x;
    }
}

/* advance the dynamic rotor over [t_now, t] under the pairs in force, recording the trajectory table */
static inline void sb_integrate(synth_bemf *g, double t)
{
    g->tab_t0 = g->t_now;
    int n = (int)ceil((t - g->t_now) / g->h - 1e-9);
    if (n > SB_NSUB) n = SB_NSUB;
    if (n < 1) n = 1;
    double h = (t - g->t_now) / (double)n;
    g->h = h;
    g->tab_n = n;
    g->tab_th[0] = g->th;
    for (int j = 0; j < n; ++j) {
        double tm = g->t_now + ((double)j + 0.5) * h;
        int s = sb_seg_at(g, tm);
        double a = -g->damp * g->w - (g->w > 0.0 ? g->load : (g->w < 0.0 ? -g->load : 0.0));
        if (g->seg_pos[s] >= 0 && g->seg_neg[s] >= 0) {
            double kp = sb_trap(g->th - sb_off(g, g->seg_pos[s]));
            double kn = sb_trap(g->th - sb_off(g, g->seg_neg[s]));
            double i = (g->seg_m[s] * g->v_dc - g->ke * g->w * (kp - kn)) / g->r2;
            if (i < 0.0) i = 0.0;
            a += g->k_acc * i * (kp - kn);
        }
        if (g->w == 0.0 && fabs(a) <= g->load) a = 0.0; /* static friction holds */
        double w_old = g->w;
        g->w += a * h;
        if (w_old * g->w < 0.0) g->w = 0.0; /* friction stops it (no chatter around zero) */
        g->th += g->w * h;
        g->tab_th[j + 1] = g->th;
    }
    g->t_now = t;
}

/* comparator edges over true times (t1, t2]: each phase's level changes at pair changes, clamp ends, back-EMF
 * zeros; logged crossings: the zeros of the floating phase */
static inline void sb_edges(synth_bemf *g, double t1, double t2, int log_zc)
{
    for (int x = 0; x < 3; ++x) {
        double c[2 * SB_NSEG + SB_NSUB + 16];
        int nc = 0;
        int lo = g->nseg > SB_NSEG ? g->nseg - SB_NSEG : 0;
        for (int j = lo; j < g->nseg; ++j) {
            int q = j % SB_NSEG;
            if (g->seg_t[q] > t1 && g->seg_t[q] <= t2) c[nc++] = g->seg_t[q];
            if (g->seg_cl_end[q] > t1 && g->seg_cl_end[q] <= t2) c[nc++] = g->seg_cl_end[q];
        }
        double a1 = sb_theta(g, t1), a2 = sb_theta(g, t2);
        double lo_a = a1 < a2 ? a1 : a2, hi_a = a1 < a2 ? a2 : a1;
        double off = sb_off(g, x);
        if (hi_a > lo_a) {
            for (double n = ceil((lo_a - off) / BC_PI); n * BC_PI + off <= hi_a && nc < 2 * SB_NSEG + 14; n += 1.0) {
                double tgt = n * BC_PI + off;
                if ((a1 - tgt) * (a2 - tgt) > 0.0 || a1 == tgt) continue; /* not crossed inside (t1, t2] */
                double tz = sb_solve(g, t1, t2, tgt);
                if (tz <= t1) tz = t1 + 1e-13; /* crossed just after t1 (rounding) */
                if (tz > t1 && tz <= t2) {
                    c[nc++] = tz;
                    if (log_zc && sb_floating(g, tz) == x && g->n_zc < SB_NLOG) {
                        g->t_zc[g->n_zc] = tz;
                        g->zc_x[g->n_zc++] = x;
                    }
                }
            }
        }
        if (g->dyn) { /* the speed changes sign between steps (a rotor starting or reversing): every step */
            for (int j = 1; j < g->tab_n; ++j) {
                double tj = g->tab_t0 + (double)j * g->h;
                if (tj > t1 && tj <= t2) c[nc++] = tj;
            }
        }
        if (g->blind) { /* the off-times' ends, and where a rising crossing's diode current ends */
            double per = 2.0 * g->ts;
            for (double v = per * floor(t1 / per) - per; v <= t2 + per && nc < 2 * SB_NSEG + SB_NSUB + 10; v += per) {
                double a, b, tz;
                (void)sb_offtime(g, v, &a, &b);
                if (a > t1 && a <= t2) c[nc++] = a;
                if (b > t1 && b <= t2) c[nc++] = b;
                if (sb_zero_in(g, x, a, b, &tz) && 2.0 * tz - a > t1 && 2.0 * tz - a <= t2) c[nc++] = 2.0 * tz - a;
            }
        }
        if (g->glitch_t >= 0.0 && x == g->glitch_x) {
            double ge = g->glitch_t + g->glitch_len;
            if (g->glitch_t > t1 && g->glitch_t <= t2) c[nc++] = g->glitch_t;
            if (ge > t1 && ge <= t2) c[nc++] = ge;
        }
        sb_sort(c, nc);
        for (int j = 0; j < nc; ++j) {
            double mid = j + 1 < nc ? 0.5 * (c[j] + c[j + 1]) : 0.5 * (c[j] + t2);
            if (mid < c[j] + 1e-10) mid = c[j] + 1e-10; /* just after it (a crossing at the window's end) */
            int lv = sb_level(g, x, mid);
            if (g->glitch_t >= 0.0 && x == g->glitch_x && mid > g->glitch_t && mid < g->glitch_t + g->glitch_len)
                lv = !lv;
            if (lv != g->lvl[x]) {
                g->lvl[x] = lv;
                g->count[x] += 1u;
                g->tick[x] = (uint32_t)(uint64_t)floor((c[j] + g->d_cmp) * g->f_tick);
            }
        }
    }
}

/* the inputs of sample k: comparators up to t_k - d_cmp, the conversion of sample k - 1 if it was a peak */
static inline void sb_sample(synth_bemf *g, long k, bc_ctrl_in *in)
{
    double t = (double)k * g->ts;
    if (g->dyn && t > g->t_now) sb_integrate(g, t);
    double te = t - g->d_cmp;
    if (k == 0) { /* the levels at the start, no edge */
        for (int x = 0; x < 3; ++x) g->lvl[x] = sb_level(g, x, te);
        g->t_eval = te;
        g->t_now = t;
    }
    if (k > 0 && te > g->t_eval) sb_edges(g, g->t_eval, te, 1);
    if (te > g->t_eval) g->t_eval = te;
    if (k > 0 && ((k - 1) & 1)) { /* a conversion at the previous sample (a carrier peak) */
        double ta = (double)(k - 1) * g->ts, tv = ta - g->d_adc;
        g->n_adc += 1u;
        g->tick_adc = (uint32_t)(uint64_t)floor(ta * g->f_tick);
        double w = sb_omega(g, tv);
        for (int x = 0; x < 3; ++x) {
            int j = sb_seg_at(g, tv);
            double v;
            if (x == g->seg_pos[j]) v = g->v_dc;
            else if (x == g->seg_neg[j]) v = 0.0;
            else if (x == g->seg_fl[j] && tv < g->seg_cl_end[j]) v = g->seg_cl[j] ? g->v_dc : 0.0;
            else {
                double th = sb_theta(g, tv) - sb_off(g, x);
                double k = sb_trap(th), e = g->ke * w * k;
                /* after the crossing: |k| grows along the motion */
                int post = fabs(sb_trap(th + (w >= 0.0 ? 1e-6 : -1e-6))) > fabs(k);
                v = 0.5 * g->v_dc + e;
                if (fabs(k) > (post ? g->clamp_post : g->clamp_pre)) v = e < 0.0 ? 0.0 : g->v_dc;
                v = v < 0.0 ? 0.0 : (v > g->v_dc ? g->v_dc : v);
            }
            g->v_term[x] = (float)v;
        }
    }
    memset(in, 0, sizeof *in);
    in->tick_now = (uint32_t)(uint64_t)llround(t * g->f_tick);
    in->v_dc = (float)g->v_dc;
    for (int x = 0; x < 3; ++x) {
        in->zc_count[x] = g->count[x];
        in->zc_tick[x] = g->tick[x];
        if (g->lvl[x]) in->zc_state |= 1u << x;
        in->v_term[x] = g->v_term[x];
    }
    in->v_neutral = (float)(0.5 * g->v_dc);
    in->n_adc = g->n_adc;
    in->tick_adc = g->tick_adc;
}

/* a new pair from t (all off: pos = neg = -1) */
static inline void sb_pair(synth_bemf *g, double t, int pos, int neg, double m)
{
    int last = (g->nseg - 1) % SB_NSEG;
    if (pos == g->seg_pos[last] && neg == g->seg_neg[last]) {
        g->seg_m[last] = m; /* the same pair: its duty (from t on; good enough for the average model) */
        return;
    }
    int q = g->nseg % SB_NSEG;
    g->seg_t[q] = t;
    g->seg_pos[q] = pos;
    g->seg_neg[q] = neg;
    g->seg_m[q] = m;
    g->seg_fl[q] = -1;
    g->seg_cl_end[q] = -1.0;
    if (pos >= 0 && neg >= 0) {
        int fl = 3 - pos - neg;
        int was_pos = fl == g->seg_pos[last], was_neg = fl == g->seg_neg[last];
        if (was_pos || was_neg) { /* the outgoing phase: its diode clamps it */
            long nc = g->n_comm;
            g->seg_fl[q] = fl;
            g->seg_cl[q] = was_neg ? 1 : 0;
            g->seg_cl_end[q] = t + ((g->n_long >= 0 && nc >= g->n_long) ? g->demag_long : g->demag);
        }
        if (g->seg_pos[last] >= 0 && g->n_comm < SB_NLOG) {
            g->t_comm[g->n_comm] = t;
            g->comm_fl[g->n_comm++] = fl;
        }
    }
    g->nseg += 1;
}

static inline void sb_legs_pair(const bc_leg_cmd l[3], int *pos, int *neg, double *m)
{
    /* the two driven legs; pos the one of the higher mean terminal voltage (PWM, HIGH: the duty; LOW: one minus it),
     * so that a pair whose continuing leg chops (fast demagnetisation) is the same pair; m the pair's mean voltage */
    *pos = *neg = -1;
    *m = 0.0;
    int on[3], n = 0;
    double mean[3] = {0.0, 0.0, 0.0};
    for (int x = 0; x < 3; ++x) {
        if (l[x].mode == BC_LEG_OFF) continue;
        mean[x] = l[x].mode == BC_LEG_LOW ? 1.0 - (double)l[x].duty : (double)l[x].duty;
        on[n++] = x;
    }
    if (n == 3) { /* a three-leg alignment: the positive leg against one of the negative ones */
        for (int x = 0; x < 3; ++x) {
            if ((l[x].mode == BC_LEG_HIGH || l[x].mode == BC_LEG_PWM) && l[x].duty > 0.0f) *pos = x;
            if (l[x].mode == BC_LEG_LOW && l[x].duty > 0.0f) *neg = x;
        }
        if (*pos < 0 || *neg < 0) {
            *pos = *neg = -1;
            return;
        }
        *m = (double)l[*pos].duty * (double)l[*neg].duty;
        return;
    }
    if (n != 2 || mean[on[0]] == mean[on[1]]) return;
    *pos = mean[on[0]] > mean[on[1]] ? on[0] : on[1];
    *neg = on[0] + on[1] - *pos;
    *m = mean[*pos] - mean[*neg];
}

/* the controller's output of sample k */
static inline void sb_apply(synth_bemf *g, long k, const bc_ctrl_out *o)
{
    double ta = (double)(k + g->delay) * g->ts;
    int pos, neg;
    double m;
    sb_legs_pair(o->leg, &pos, &neg, &m);
    sb_pair(g, ta, pos, neg, m);
    if (o->has_at) {
        sb_legs_pair(o->leg_at, &pos, &neg, &m);
        sb_pair(g, ta + (double)o->t_at, pos, neg, m);
    }
}

#endif /* SYNTH_BEMF_H */

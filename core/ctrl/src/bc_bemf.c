/* bc_bemf.c - sensorless six-step drive from the floating phase's back-EMF. Laws (numbered as here) in bc_bemf.h. */
#include "bldc/bc_bemf.h"

#include <math.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_math.h"

#define PI3_F (BC_PI_F / 3.0f)
#define PI6_F (BC_PI_F / 6.0f)
#define RAMP_W_MAX 3.0f /* RAMP: a crossing interval giving more than this times the forced speed is no rotor's */

static int fin(float v) { return isfinite(v) ? 1 : 0; }

/* a - b in ticks, signed (wrap-safe: the two within 2^31 ticks of each other) */
static float tdiff(uint32_t a, uint32_t b)
{
    uint32_t d = a - b;
    return d < 0x80000000u ? (float)d : -(float)(0u - d);
}

/* t + n ticks (n rounded to the nearest tick, limited to +-2e9) */
static uint32_t tadd(uint32_t t, float n)
{
    if (!fin(n)) return t;
    n = bc_clampf(n, -2.0e9f, 2.0e9f);
    int32_t k = (int32_t)(n >= 0.0f ? n + 0.5f : n - 0.5f);
    return t + (uint32_t)k;
}

static int in01(float v) { return fin(v) && v >= 0.0f && v <= 1.0f; }
static int nonneg(float v) { return fin(v) && v >= 0.0f; }

int bc_bemf_init(const bc_bemf_params *p, bc_bemf_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (p->method < BC_BEMF_COMPARATOR || p->method > BC_BEMF_INTEGRATE) return BC_ERR_PARAM;
    if (p->chop < BC_CHOP_BIPOLAR || p->chop > BC_CHOP_SYNC) return BC_ERR_PARAM;
    if ((p->delay != 0 && p->delay != 1) || (p->blanking != BC_BEMF_BLANK_FIXED && p->blanking != BC_BEMF_BLANK_DEMAG) ||
        (p->use_current != 0 && p->use_current != 1))
        return BC_ERR_PARAM;
    if (!(fin(p->ts) && p->ts > 0.0f) || !(fin(p->f_tick) && p->f_tick > 0.0f) || !(p->ts * p->f_tick >= 1.0f))
        return BC_ERR_PARAM;
    if (!nonneg(p->blank_angle) || !(p->blank_angle < PI3_F) || !nonneg(p->blank_time) || !nonneg(p->min_pulse) ||
        p->n_samples < 1 || p->n_samples > 16 || !nonneg(p->tau_filter) || !nonneg(p->t_comp))
        return BC_ERR_PARAM;
    if (!nonneg(p->adv_angle) || !nonneg(p->adv_time) || !nonneg(p->adv_demag) || !nonneg(p->adv_max) ||
        p->adv_max > PI6_F || !(fin(p->t60_gain) && p->t60_gain > 0.0f && p->t60_gain <= 1.0f))
        return BC_ERR_PARAM;
    if (p->method == BC_BEMF_INTEGRATE && !(fin(p->int_limit) && p->int_limit > 0.0f)) return BC_ERR_PARAM;
    if (!in01(p->grid_gain)) return BC_ERR_PARAM;
    if (!nonneg(p->int_limit) || !(fin(p->zc_timeout) && p->zc_timeout >= 1.05f && p->zc_timeout <= 4.0f) ||
        !(fin(p->jump_max) && p->jump_max > 1.0f) || !nonneg(p->brake_tau) || !nonneg(p->brake_acc) ||
        !nonneg(p->brake_q) ||
        p->miss_max < 0 || p->miss_max > 100 ||
        !(fin(p->omega_stall) && p->omega_stall > 0.0f))
        return BC_ERR_PARAM;
    if (!nonneg(p->align_time) || !in01(p->align_duty) || !nonneg(p->ramp_w0) || !(fin(p->ramp_w1) && p->ramp_w1 > 0.0f) ||
        p->ramp_w1 < p->ramp_w0 || !nonneg(p->ramp_accel) || (p->ramp_w0 == 0.0f && !(p->ramp_accel > 0.0f)) ||
        !in01(p->ramp_duty) || !nonneg(p->ramp_vf) || !nonneg(p->ramp_tau) || p->ramp_hold < 1 || p->n_handover < 2 || p->n_handover > 1000)
        return BC_ERR_PARAM;
    if (!in01(p->duty_min) || !nonneg(p->duty_rate) || !(fin(p->ref_stop) && p->ref_stop >= 0.0f && p->ref_stop < 1.0f) ||
        !nonneg(p->restart_wait) || !(fin(p->restart_max) && p->restart_max >= p->restart_wait))
        return BC_ERR_PARAM;
    if (!(fin(p->i_max) && p->i_max > 0.0f) || !nonneg(p->i_limit) || !nonneg(p->k_limit) ||
        !(fin(p->v_max) && p->v_max > 0.0f) || (p->fast_demag != 0 && p->fast_demag != 1) ||
        !(fin(p->fd_after) && p->fd_after >= 0.0f && p->fd_after < 1.0f) || !in01(p->dlim_d0) ||
        !nonneg(p->dlim_vf) || !nonneg(p->dlim_tau) || !(fin(p->demag_max) && p->demag_max >= 0.0f && p->demag_max < 1.0f) ||
        (p->cmp_gate != 0 && p->cmp_gate != 1) || (p->cmp_blind != 0 && p->cmp_blind != 1) || !nonneg(p->i_start) ||
        !(fin(p->d_diode) && p->d_diode >= 0.0f && p->d_diode < 1.0f))
        return BC_ERR_PARAM;
    *s = (bc_bemf_state){0};
    s->ts_tick = p->ts * p->f_tick;
    s->inv_tick = 1.0f / p->f_tick;
    s->mode = BC_BEMF_STOP;
    s->dir = 1;
    s->fresh = 1;
    s->sector = -1;
    s->incoming = -1;
    s->outgoing = -1;
    s->d_lim = 1.0f;
    s->d_dm = 1.0f;
    s->guard_p = (bc_guard_params){.i_max = p->i_max, .v_max = p->v_max};
    if (bc_guard_init(&s->guard_p, &s->guard) != BC_OK) return BC_ERR_PARAM;
    return BC_OK;
}

/* ------------------------------------------------------------------------------------------------------------ */

/* Everything one sample needs besides params and state. */
typedef struct {
    uint32_t tk;     /* tick_now */
    uint32_t ta;     /* start of the interval the output applies to */
    int adc_new;     /* a new conversion in this input */
    uint32_t flags;  /* flags raised so far */
} bemf_now;

static int floating(int sector)
{
    int pos, neg;
    if (bc_sector_phases(sector, &pos, &neg) != 0) return 0;
    return 3 - pos - neg;
}

/* speed estimate, electrical rad/s (0: none) */
static float omega_of(const bc_bemf_params *p, const bc_bemf_state *s)
{
    (void)p;
    if (s->mode == BC_BEMF_RAMP) return s->w_zc > s->w_ol ? s->w_zc : s->w_ol;
    if (s->t60 > 0.0f) {
        float w = PI3_F / s->t60;
        return fin(w) ? w : 0.0f;
    }
    return 0.0f;
}

/* the filter's delay of a crossing at electrical speed w: atan(w tau) / w (tau as w -> 0) */
static float filter_delay(const bc_bemf_params *p, float w)
{
    if (!(p->tau_filter > 0.0f)) return 0.0f;
    if (!(w > 0.0f) || !fin(w)) return p->tau_filter;
    float d = atanf(w * p->tau_filter) / w;
    return fin(d) ? d : p->tau_filter;
}

/* adv = min(adv_angle + w adv_time + adv_demag w t_demag, adv_max) */
static float advance_of(const bc_bemf_params *p, const bc_bemf_state *s, float w)
{
    float a = p->adv_angle + w * p->adv_time + p->adv_demag * w * s->t_demag;
    return fin(a) ? bc_clampf(a, 0.0f, p->adv_max) : p->adv_max;
}

/* a duty of the ideal inverter (synchronous, no dead time, no diode drop) made the inverter's: d_diode + (1 - d_diode) d,
 * in [0, 1] (2) */
static float with_diode(const bc_bemf_params *p, float d)
{
    float m = p->d_diode + (1.0f - p->d_diode) * d;
    return fin(m) ? bc_clampf(m, 0.0f, 1.0f) : 0.0f;
}

/* the forced ramp's duty at electrical speed w: d_diode + (1 - d_diode) (ramp_duty sqrt(1 + (w ramp_tau)^2) +
 * ramp_vf w), in [0, 1] */
static float ramp_duty_at(const bc_bemf_params *p, float w)
{
    float x = w * p->ramp_tau;
    return with_diode(p, p->ramp_duty * sqrtf(1.0f + x * x) + p->ramp_vf * w);
}

/* Open-loop time to an angle: w tau + a tau^2 / 2 (w + a tau capped at w1) reaches ang. */
static float angle_time(float w, float a, float w1, float ang)
{
    if (a > 0.0f && w < w1) {
        float t1 = (w1 - w) / a;               /* time to the cap */
        float ang1 = 0.5f * (w + w1) * t1;     /* angle on the way */
        if (ang1 >= ang) return 2.0f * ang / (w + sqrtf(w * w + 2.0f * a * ang));
        return t1 + (ang - ang1) / w1;
    }
    return ang / w1;
}

static float sector_time(float w, float a, float w1) { return angle_time(w, a, w1, PI3_F); }

/* A new sector: the phase that entered the pair (the incoming phase), the detector reset for the commutation at tc. */
static void enter_sector(const bc_bemf_params *p, bc_bemf_state *s, const bc_ctrl_in *in, int sector, uint32_t tc,
                         int out_first)
{
    int inc = -1, outp = out_first;
    int pn, nn;
    (void)bc_sector_phases(sector, &pn, &nn);
    if (s->sector >= 0) {
        int po, no;
        (void)bc_sector_phases(s->sector, &po, &no);
        if (pn != po && pn != no) inc = pn;
        else if (nn != po && nn != no) inc = nn;
        if (po != pn && po != nn) outp = po;
        else if (no != pn && no != nn) outp = no;
    } else {
        inc = s->dir > 0 ? pn : nn;
    }
    s->incoming = inc;
    s->outgoing = outp;
    {
        int pp = pn, qq = nn;
        if (s->dir < 0) {
            pp = nn;
            qq = pn;
        }
        int cont = inc == pp ? qq : pp;
        s->fd_neg = p->fast_demag && outp >= 0 && p->chop != BC_CHOP_BIPOLAR && inc >= 0 && cont == qq;
    }
    s->first = 0;
    s->fd_on = 0;
    s->fd_comp = 0;
    s->sector = sector;
    s->t_c = tc;
    float w = omega_of(p, s);
    float blank = p->blank_time;
    if (w > 0.0f && p->blank_angle / w > blank) blank = p->blank_angle / w;
    s->t_open = tadd(tc, blank * p->f_tick);
    s->det = 0;
    s->adc_seen = 0;
    s->post_open = 0;
    s->pre_seen = 0;
    s->dm_known = 0;
    s->n_post = 0;
    s->pre_free = 0;
    s->zc_est = 0;
    s->integ = 0;
    s->sector_ok = 0;
    s->pending = 0;
    s->cnt_open = in->zc_count[floating(sector)];
    s->cnt_c = s->cnt_open;
}

static void stop(bc_bemf_state *s, int reason)
{
    s->mode = BC_BEMF_STOP;
    s->t_in = 0.0f;
    s->fresh = 0;
    s->pending = 0;
    s->sector = -1;
    s->incoming = -1;
    s->outgoing = -1;
    s->d_cmd = 0.0f;
    if (reason != BC_BEMF_REASON_NONE) s->reason = reason;
}

static uint32_t reason_flag(int reason)
{
    switch (reason) {
    case BC_BEMF_REASON_TIMEOUT: return BC_FLAG_ZC_TIMEOUT;
    case BC_BEMF_REASON_HIDDEN: return BC_FLAG_ZC_HIDDEN;
    case BC_BEMF_REASON_JUMP: return BC_FLAG_ZC_JUMP;
    case BC_BEMF_REASON_STALL: return BC_FLAG_STALL;
    default: return BC_FLAG_START_FAIL;
    }
}

/* 10. desync: legs off from t_a, STOP, the reason's flags */
static void desync(bc_bemf_state *s, bemf_now *n, int reason)
{
    n->flags |= BC_FLAG_DESYNC | reason_flag(reason);
    stop(s, reason);
}

/* The ramp's first sector, from t_a: after the alignment (the rotor at pi, the middle of sector 2) sector 2 in
 * either direction for the open-loop time of 30 degrees; a direct start: 2 forward, 1 backward, a whole sector. */
static void begin_ramp(const bc_bemf_params *p, bc_bemf_state *s, const bc_ctrl_in *in, const bemf_now *n)
{
    int aligned = s->mode == BC_BEMF_ALIGN;
    s->mode = BC_BEMF_RAMP;
    s->t_in = 0.0f;
    s->valid = 0;
    s->hold = 0;
    s->have_zc = 0;
    s->sector = -1;
    s->w_ol = p->ramp_w0;
    s->w_zc = 0.0f;
    s->tau_ol = sector_time(s->w_ol, p->ramp_accel, p->ramp_w1);
    /* after the alignment phase a (sector 2's floating phase) still carries the alignment current: the first
     * sector's outgoing phase, its clamp as after any commutation */
    enter_sector(p, s, in, aligned ? 2 : (s->dir > 0 ? 2 : 1), n->ta, aligned ? 0 : -1);
    s->first = aligned;
    float first = aligned ? angle_time(s->w_ol, p->ramp_accel, p->ramp_w1, PI6_F) : s->tau_ol;
    s->t_next = tadd(n->ta, first * p->f_tick);
    s->pending = 1;
    s->adv = 0.0f;
    s->adv_prev = 0.0f;
}

static void start(const bc_bemf_params *p, bc_bemf_state *s, const bc_ctrl_in *in, const bemf_now *n, int dir)
{
    s->dir = dir;
    s->fresh = 0;
    s->reason = BC_BEMF_REASON_NONE;
    s->d_cmd = 0.0f;
    s->t60 = 0.0f;
    s->r_zc = 0.0f;
    s->t_last = 0.0f;
    s->have_zc = 0;
    s->virt = 0;
    s->misses = 0;
    s->t_demag = 0.0f;
    s->err = 0.0f;
    s->d_dm = 1.0f;
    s->adv = 0.0f;
    s->adv_prev = 0.0f;
    if (p->align_time > 0.0f) {
        s->mode = BC_BEMF_ALIGN;
        s->t_in = 0.0f;
        s->sector = -1;
        s->pending = 0;
    } else {
        begin_ramp(p, s, in, n);
    }
}

/* ------------------------------------------------------------------------------------------------------------ */
/* 6. zero-crossing detection */

/* 6, cmp_blind: an accepted edge at x_e (s relative to t_k) whose comparator input changed in the pair's off-time
 * [v - h, v + h] (v the carrier valley; the pair's active state is next to the peak; even samples are valleys; h =
 * (1 - m) T_s with the duty of the last output), or at the start of the on-time after it (within min_pulse + 2
 * tau_filter + one tick, at most half the on-time), came from a crossing in that off-time. Into the clamped level
 * (below: even sectors) F reads the reference from the crossing to the on-time, which shows it: the crossing
 * anywhere in the off-time, its middle v. Out of it (odd sectors) F's diode current, built since v - h while its back-EMF was below, decays as long after
 * the crossing (a linear back-EMF): an edge inside the off-time at 2 t_z - (v - h), so t_z = (t_e + v - h) / 2; one
 * at the on-time's start, t_z in [v, v + h], its middle. Not while the fast pattern, which centres the pair's
 * on-time at the valley, may have been in force over that off-time (before t_plain). */
static float blind_edge(const bc_bemf_params *p, const bc_bemf_state *s, const bemf_now *n, float x_e)
{
    if (p->chop != BC_CHOP_SYNC && p->chop != BC_CHOP_HIGH) return x_e;
    float x = x_e - p->t_comp; /* the comparator's input changed */
    float h = (1.0f - bc_clampf(s->m_app, 0.0f, 1.0f)) * p->ts, per = 2.0f * p->ts;
    /* at most half the on-time, m T_s: an edge later in it is the on-time's own (and the valley below unique) */
    float tol = fminf(p->min_pulse + 2.0f * p->tau_filter + s->inv_tick, p->ts - h);
    float v0 = (s->k_samp & 1u) ? -p->ts : 0.0f;                    /* the last valley at or before t_k */
    float v = v0 - per * floorf((v0 - (x - tol)) / per + 0.5f);    /* the valley nearest x - tol */
    float y = x - v;
    if (!(fin(y) && y >= -h && y <= h + tol)) return x_e; /* in an on-time: the crossing itself */
    if (s->fd_on && tdiff(tadd(n->tk, (v - h) * p->f_tick), s->t_plain) < 0.0f) return x_e;
    if (s->sector & 1) { /* into above: the pre level was the clamped one */
        float z = y < h - s->inv_tick ? 0.5f * (x + (v - h)) : v + 0.5f * h;
        return z + p->t_comp;
    }
    return v + p->t_comp;
}

/* Comparator. Returns 1 with *x_e (s, relative to t_k) when a crossing is accepted at this sample; post_open while
 * the level has been post since the window opened (the clamp, or a crossing already past). */
static int detect_comparator(const bc_bemf_params *p, bc_bemf_state *s, const bc_ctrl_in *in, const bemf_now *n,
                             float *x_e)
{
    int f = floating(s->sector);
    int post = s->sector & 1; /* odd sectors: above the reference after the crossing */
    uint32_t cnt = in->zc_count[f];
    uint32_t te = in->zc_tick[f];
    int lvl = (int)((in->zc_state >> f) & 1u);
    /* fast demagnetisation on the negative leg: the comparator only in the pair's on-time, centred at the carrier
     * peak (odd samples) when the leg chops with its lower switch, at the valley when it is complementary (sync) */
    if (p->cmp_gate && s->fd_neg && s->fd_on && (s->k_samp & 1u) == (p->chop == BC_CHOP_SYNC ? 1u : 0u)) return 0;
    if (tdiff(n->tk, s->t_c) < 0.0f) s->cnt_c = cnt;
    int opening = 0;
    if (s->det == 0) {
        if (tdiff(n->tk, s->t_open) < 0.0f) { /* before the window */
            s->cnt_open = cnt;
            return 0;
        }
        s->det = 1;
        opening = 1;
    }
    float min_pulse = p->min_pulse * p->f_tick;
    int te_past = tdiff(te, n->tk) <= 0.0f;
    int edge_in = cnt != s->cnt_open && te_past && tdiff(te, s->t_open) >= 0.0f;
    if (opening && lvl == post && !edge_in) s->post_open = 1; /* the post level when the window opens */
    if (edge_in || lvl != post) s->post_open = 0;               /* ... until it leaves it */
    if (lvl != post) { /* the pre level at a sample: the demagnetisation is over */
        if (!s->dm_known) {
            s->dm_known = 1;
            if (!s->pre_seen) s->t_plain = n->ta;
            s->pre_seen = 1;
            int edge = cnt != s->cnt_c && te_past && tdiff(te, s->t_c) >= 0.0f; /* the clamp's end, seen */
            s->t_dm = edge ? te : s->t_c;
            s->t_demag = edge ? fmaxf(tdiff(te, s->t_c) * s->inv_tick - filter_delay(p, omega_of(p, s)) - p->t_comp,
                                      0.0f)
                              : 0.0f;
        }
        return 0;
    }
    /* the post level: a crossing only through an edge inside the window (else the clamp, or a crossing already
     * past when the window opened: rejected) */
    if (!edge_in) return 0;
    if (!s->pre_seen) s->t_plain = n->ta;
    s->pre_seen = 1; /* an edge into post in the window: the pre level was there before it */
    if (p->blanking == BC_BEMF_BLANK_DEMAG && s->dm_known && tdiff(te, s->t_dm) < min_pulse) return 0;
    if (tdiff(n->tk, te) < min_pulse) return 0; /* minimum pulse: not yet */
    *x_e = tdiff(te, n->tk) * s->inv_tick;
    if (p->cmp_blind) *x_e = blind_edge(p, s, n, *x_e);
    return 1;
}

/* F's terminal within V_dc/32 of a rail (or beyond): F conducts through a diode (the outgoing current, or a current
 * its back-EMF drove in a PWM off-time that has not yet decayed), and the sample's value is not its back-EMF. Its
 * sign still is (the rail is on the side F's back-EMF or the outgoing current pushes it); free, F sits at least
 * 0.046 V_dc from the rails in the pair's on-time up to 30 degrees after its crossing (6). */
static int rail_clamped(const bc_ctrl_in *in, int f)
{
    float band = in->v_dc * (1.0f / 32.0f);
    return in->v_term[f] > band && in->v_term[f] < in->v_dc - band ? 0 : 1;
}

/* ADC. Returns 1 with *x_e when a crossing is accepted at this sample's conversion; post_open while every
 * conversion since the window opened showed the post level. */
static int detect_adc(const bc_bemf_params *p, bc_bemf_state *s, const bc_ctrl_in *in, const bemf_now *n, float *x_e)
{
    if (s->det == 0) {
        if (tdiff(n->tk, s->t_open) < 0.0f) return 0;
        s->det = 1;
    }
    if (!n->adc_new) return 0;
    uint32_t t = in->tick_adc;
    if (tdiff(t, s->t_open) < 0.0f || tdiff(t, n->tk) > 0.0f) return 0; /* sampled before the window */
    int f = floating(s->sector);
    float u = (s->sector & 1) ? in->v_term[f] - in->v_neutral : in->v_neutral - in->v_term[f];
    if (!fin(u)) return 0;
    int cl = rail_clamped(in, f);
    int opening = !s->adc_seen;
    s->adc_seen = 1;
    if (opening && u > 0.0f) s->post_open = 1; /* the post level at the window's first conversion ... */
    if (!(u > 0.0f)) s->post_open = 0;         /* ... until a pre sample */
    if (!(u > 0.0f)) { /* pre */
        if (!s->pre_seen) {
            s->pre_seen = 1;
            s->dm_known = 1;
            s->t_dm = t;
            s->t_demag = fmaxf(tdiff(t, s->t_c) * s->inv_tick - filter_delay(p, omega_of(p, s)), 0.0f);
        }
        s->n_post = 0;
        s->t_pre = t;
        if (!cl) { /* the value only from a free terminal */
            s->u_pre = u;
            s->t_pre_free = t;
            s->pre_free = 1;
        }
        return 0;
    }
    if (!s->pre_seen) return 0; /* post with no pre sample in the window: the clamp, or already past */
    if (s->n_post == 0) { /* the first post sample: the crossing between it and the last pre sample */
        float dt = tdiff(t, s->t_pre);
        float xe;
        if (!cl && s->pre_free) { /* linear between the last free pre sample and this one, inside (t_pre, t] */
            float dtf = tdiff(t, s->t_pre_free);
            float frac = -s->u_pre / (u - s->u_pre);
            xe = (fin(frac) ? bc_clampf(frac, 0.0f, 1.0f) * dtf : dtf) - tdiff(s->t_pre, s->t_pre_free);
            xe = bc_clampf(xe, 0.0f, dt);
        } else if (!cl && s->r_zc > 0.0f) { /* the pre end clamped: back along the last crossing's slope */
            xe = bc_clampf(dt - u / s->r_zc * p->f_tick, 0.0f, dt);
            if (!fin(xe)) xe = 0.5f * dt;
        } else { /* no value to interpolate: the middle of the bracket */
            xe = 0.5f * dt;
        }
        /* with the pre end clamped and this sample free, refined at the next free post sample (the line through the
         * two) */
        s->zc_est = !cl && !s->pre_free;
        s->te_off = xe; /* crossing, ticks after t_pre */
        /* the integral from the crossing (u = 0 there); a clamped first post sample is not integrated */
        s->lam = cl ? 0.0f : 0.5f * u * (dt - xe) * s->inv_tick;
        /* the slope: the interpolation's line, or from the crossing */
        if (!cl && s->pre_free) s->r_last = fmaxf((u - s->u_pre) / (tdiff(t, s->t_pre_free) * s->inv_tick), 0.0f);
        else s->r_last = dt - xe > 0.0f && !cl ? fmaxf(u / ((dt - xe) * s->inv_tick), 0.0f) : 0.0f;
        if (!cl && s->pre_free && fin(s->r_last)) s->r_zc = s->r_last;
        s->u_last = cl ? 0.0f : u;
        s->t_u = cl ? tadd(s->t_pre, xe) : t;
    } else if (!cl) { /* the trapezoid from the last free post sample (over clamped ones: a linear ramp exactly) */
        float dtu = tdiff(t, s->t_u) * s->inv_tick;
        if (s->zc_est) { /* the crossing back along the line through the first two free post samples, in the bracket */
            float dt = tdiff(s->t_u, s->t_pre);
            float back = s->u_last * tdiff(t, s->t_u) / (u - s->u_last);
            if (fin(back) && u > s->u_last) {
                s->te_off = bc_clampf(dt - back, 0.0f, dt);
                s->lam = 0.5f * s->u_last * (dt - s->te_off) * s->inv_tick;
                s->r_zc = (u - s->u_last) / dtu;
                if (!fin(s->r_zc)) s->r_zc = 0.0f;
            }
            s->zc_est = 0;
        }
        s->lam += 0.5f * (s->u_last + u) * dtu;
        s->r_last = dtu > 0.0f ? fmaxf((u - s->u_last) / dtu, 0.0f) : 0.0f;
        s->u_last = u;
        s->t_u = t;
    }
    if (!fin(s->r_last)) s->r_last = 0.0f;
    if (!fin(s->lam)) s->lam = 0.0f;
    s->n_post += 1;
    if (s->n_post < p->n_samples) return 0;
    *x_e = (tdiff(s->t_pre, n->tk) + s->te_off) * s->inv_tick;
    return 1;
}

/* 7. BC_BEMF_INTEGRATE: from the samples integrated so far, the commutation instant (s relative to t_k). */
static float integrate_predict(const bc_bemf_params *p, const bc_bemf_state *s, const bemf_now *n, float w)
{
    float r = (PI6_F - s->adv) / PI6_F;
    float thr = p->int_limit * r * r;
    float x_u = tdiff(s->t_u, n->tk) * s->inv_tick; /* last sample, s relative to t_k */
    float u = s->u_last, a = s->r_last, tau;
    if (s->lam >= thr) { /* already reached: back between the last two samples */
        tau = u > 0.0f ? -(s->lam - thr) / u : 0.0f;
    } else if (a > 0.0f) {
        tau = (-u + sqrtf(u * u + 2.0f * a * (thr - s->lam))) / a;
    } else if (u > 0.0f) {
        tau = (thr - s->lam) / u;
    } else {
        tau = 1e30f;
    }
    float x = x_u + tau - filter_delay(p, w);
    return fin(x) ? x : 1e30f;
}

/* ------------------------------------------------------------------------------------------------------------ */

/* 7, uniform grid: D_s, the lag (s) of sector sec's crossing behind the uniform grid through the mean of the six
 * (0, *tn left, until twelve intervals have been seen), at most 10 degrees; *tn the grid's interval */
static float grid_lag(const bc_bemf_state *s, int sec, float *tn)
{
    if (s->grid_n < 12 || sec < 0 || sec > 5 || !(fin(s->grid_tn) && s->grid_tn > 0.0f)) return 0.0f;
    float rm = 0.0f, pc[6], pm = 0.0f;
    for (int j = 0; j < 6; ++j) rm += s->grid_t[j];
    rm *= 1.0f / 6.0f;
    if (!(fin(rm) && rm > 0.0f)) return 0.0f;
    int at = 0; /* P over the sectors in the order of rotation from sector 0 (forward) or 5 (backward) */
    pc[0] = 0.0f;
    for (int r = 1; r < 6; ++r) pc[r] = pc[r - 1] + s->grid_t[s->dir > 0 ? r : 5 - r] / rm - 1.0f;
    for (int r = 0; r < 6; ++r) {
        pm += pc[r];
        if ((s->dir > 0 ? r : 5 - r) == sec) at = r;
    }
    float d = (pc[at] - pm * (1.0f / 6.0f)) * s->grid_tn;
    if (!fin(d)) return 0.0f;
    *tn = s->grid_tn;
    return bc_clampf(d, -s->grid_tn / 6.0f, s->grid_tn / 6.0f);
}

/* 7, uniform grid, bounded by the demagnetisation: the latest commutation (s relative to t_k) that leaves the next
 * crossing visible. The next crossing is expected at the earlier of the plain estimate (one T60 after this one) and
 * the grid's (this crossing's grid point plus Tn plus the next sector's lag); the window from the commutation to it
 * must hold the longest demagnetisation measured over the last six sectors as at most demag_max of it (the share the
 * limiter of 2 keeps; the whole window without the limiter), and the blanking, plus min_pulse. */
static float grid_latest(const bc_bemf_params *p, const bc_bemf_state *s, float x_zc, float lag, float tn, float w)
{
    float t60 = PI3_F / w, tn1 = tn;
    int next = (s->sector + (s->dir > 0 ? 1 : 5)) % 6;
    float lag1 = grid_lag(s, next, &tn1);
    float x_z1 = x_zc + fminf(t60, tn - lag + lag1);
    float dm = 0.0f;
    for (int j = 0; j < 6; ++j) dm = fmaxf(dm, s->grid_dm[j]);
    float blank = fmaxf(p->blank_angle / w, p->blank_time);
    float need = fmaxf(p->demag_max > 0.0f ? dm / p->demag_max : dm, blank) + p->min_pulse;
    return x_z1 - need;
}

/* 7, uniform grid: learn from the crossing interval T ending in the current sector */
static void grid_learn(const bc_bemf_params *p, bc_bemf_state *s, float T)
{
    if (s->sector < 0 || s->sector > 5) return;
    s->grid_ring[s->grid_k] = T;
    s->grid_k = (s->grid_k + 1) % 6;
    s->grid_n += s->grid_n < 1000;
    if (s->grid_n < 6) return;
    float m6 = 0.0f;
    for (int j = 0; j < 6; ++j) m6 += s->grid_ring[j];
    m6 *= 1.0f / 6.0f;
    float r = T / m6, *g = &s->grid_t[s->sector];
    *g = s->grid_n <= 12 ? r : *g + p->grid_gain * (r - *g);
    if (s->grid_n < 12) return;
    float rm = 0.0f;
    for (int j = 0; j < 6; ++j) rm += s->grid_t[j];
    rm *= 1.0f / 6.0f;
    float tn = T * rm / *g; /* this interval over its sector's ratio */
    s->grid_tn = s->grid_n == 12 ? m6 : s->grid_tn + p->t60_gain * (tn - s->grid_tn);
    if (!(fin(s->grid_tn) && s->grid_tn > 0.0f && fin(*g) && *g > 0.0f)) s->grid_n = 0; /* relearn */
}

/* 5. The handover's fit. The last m = min(valid, BC_BEMF_HO_FIT) crossings (angle k pi/3 at the k-th) against the
 * least-squares path of a rotor at constant acceleration whose rising and falling crossings may be displaced
 * oppositely (a comparator offset, an asymmetric back-EMF): k pi/3 = c0 + c1 x + c2 x^2 + c3 (-1)^k, x the time in
 * some unit from some origin (the fitted path, hence the distances from it and c3, do not depend on which: 1, x, x^2
 * span the same functions of time). The fit is made in two parts so that the crossing that decides pays only for its
 * own point: after each crossing (ho_prepare, at the next sample) the m - 1 crossings known for the next fit, their
 * time unit the mean interval between them and their origin half a unit after their middle (where the next fit's
 * middle is expected: the moments nearly centred, as well conditioned as centred ones), their times in that unit and
 * the moments of the normal equations over them; at the crossing its own time and moments, the 4 x 4 Cholesky solve
 * and the distances. */
static void ho_prepare(bc_bemf_state *s, int32_t v)
{
    s->ho_n = v;
    int m = v + 1 < BC_BEMF_HO_FIT ? (int)v + 1 : BC_BEMF_HO_FIT;
    if (m < 5) return;
    int n = m - 1, last = (int)((v - 1) % BC_BEMF_HO_FIT);
    s->ho_k = last;
    s->ho_t = s->ho_ring[last];
    float u[BC_BEMF_HO_FIT - 1], sum = 0.0f;
    int j = last - (n - 1);
    if (j < 0) j += BC_BEMF_HO_FIT;
    for (int k = 0; k < n; ++k) { /* time of the k-th crossing relative to the last known, s */
        u[k] = tdiff(s->ho_ring[j], s->ho_ring[last]) * s->inv_tick;
        sum += u[k];
        if (++j == BC_BEMF_HO_FIT) j = 0;
    }
    float tm = -u[0] / (float)(n - 1); /* the mean interval */
    if (!(tm > 0.0f)) { /* crossings out of order (no rotor's; the fit will say so): a unit that spans them */
        tm = 0.0f;
        for (int k = 0; k < n; ++k) tm = fabsf(u[k]) > tm ? fabsf(u[k]) : tm;
        tm = tm > 0.0f ? tm / (float)(n - 1) : s->inv_tick;
    }
    float c = (sum + tm) / (float)m, inv = 1.0f / tm;
    s->ho_c = c;
    s->ho_inv = inv;
    float s1 = 0.0f, s2 = 0.0f, s3 = 0.0f, s4 = 0.0f, sa = 0.0f, sax = 0.0f, sax2 = 0.0f;
    float y0 = 0.0f, y1 = 0.0f, y2 = 0.0f, y3 = 0.0f;
    for (int k = 0; k < n; ++k) {
        float x = (u[k] - c) * inv, x2 = x * x, sg = (k & 1) ? -1.0f : 1.0f, fk = (float)k;
        s->ho_x[k] = x;
        s1 += x;
        s2 += x2;
        s3 += x2 * x;
        s4 += x2 * x2;
        sa += sg;
        sax += sg * x;
        sax2 += sg * x2;
        y0 += fk;
        y1 += x * fk;
        y2 += x2 * fk;
        y3 += sg * fk;
    }
    float *mo = s->ho_mom;
    mo[0] = s1;
    mo[1] = s2;
    mo[2] = s3;
    mo[3] = s4;
    mo[4] = sa;
    mo[5] = sax;
    mo[6] = sax2;
    mo[7] = y0;
    mo[8] = y1;
    mo[9] = y2;
    mo[10] = y3;
}

void bc_bemf_ho_prepare(bc_bemf_state *s) { ho_prepare(s, s->valid); }

int bc_bemf_ho_fit(bc_bemf_state *s, float *alt, float *res, float *acc)
{
    *alt = 0.0f;
    *res = 0.0f;
    *acc = 0.0f;
    int m = s->valid < BC_BEMF_HO_FIT ? (int)s->valid : BC_BEMF_HO_FIT;
    if (m < 5) return 1;
    if (!(s->ho_n == s->valid - 1 && s->ho_t == s->ho_ring[s->ho_k])) ho_prepare(s, s->valid - 1);
    int prev = s->ho_k, last = prev < BC_BEMF_HO_FIT - 1 ? prev + 1 : 0, first = last - (m - 1);
    if (first < 0) first += BC_BEMF_HO_FIT;
    if (!(tdiff(s->ho_ring[first], s->ho_ring[last]) < 0.0f)) return -1; /* the crossings span no time */
    /* this crossing, the last (k = m - 1), and the moments with it */
    float x = (tdiff(s->ho_ring[last], s->ho_ring[prev]) * s->inv_tick - s->ho_c) * s->ho_inv;
    float x2 = x * x, sg = (m & 1) ? 1.0f : -1.0f, fk = (float)(m - 1);
    const float *mo = s->ho_mom;
    float s1 = mo[0] + x, s2 = mo[1] + x2, s3 = mo[2] + x2 * x, s4 = mo[3] + x2 * x2, sa = mo[4] + sg;
    float sax = mo[5] + sg * x, sax2 = mo[6] + sg * x2;
    float y0 = mo[7] + fk, y1 = mo[8] + x * fk, y2 = mo[9] + x2 * fk, y3 = mo[10] + sg * fk;
    /* the normal equations of 1, x, x^2, (-1)^k, [[m, s1, s2, sa], [s1, s2, s3, sax], [s2, s3, s4, sax2], [sa, sax,
     * sax2, m]] c = y, by L D L^T (L unit lower triangular; D positive for distinct times): L z = y, L^T c = D^-1 z */
    float d0 = (float)m;
    float l10 = s1 / d0, l20 = s2 / d0, l30 = sa / d0;
    float d1 = s2 - l10 * s1;
    if (!(d1 > 1e-9f)) return -1;
    float e21 = s3 - l20 * s1, e31 = sax - l30 * s1;
    float l21 = e21 / d1, l31 = e31 / d1;
    float d2 = s4 - l20 * s2 - l21 * e21;
    if (!(d2 > 1e-9f)) return -1;
    float e32 = sax2 - l30 * s2 - l31 * e21;
    float l32 = e32 / d2;
    float d3 = d0 - l30 * sa - l31 * e31 - l32 * e32;
    if (!(d3 > 1e-9f)) return -1;
    float z1 = y1 - l10 * y0, z2 = y2 - l20 * y0 - l21 * z1, z3 = y3 - l30 * y0 - l31 * z1 - l32 * z2;
    float c3 = z3 / d3, c2 = z2 / d2 - l32 * c3, c1 = z1 / d1 - l21 * c2 - l31 * c3;
    float c0 = y0 / d0 - l10 * c1 - l20 * c2 - l30 * c3;
    /* the largest distance of a crossing from the path (k even and odd in pairs; this one the last) */
    s->ho_x[m - 1] = x;
    float ce = c0 + c3, co = c0 - c3, fj = 0.0f, worst = 0.0f;
    int k = 0;
    for (; k + 1 < m; k += 2, fj += 2.0f) {
        float xe = s->ho_x[k], xo = s->ho_x[k + 1];
        float ee = fabsf(ce + (c1 + c2 * xe) * xe - fj), eo = fabsf(co + (c1 + c2 * xo) * xo - (fj + 1.0f));
        worst = ee > worst ? ee : worst;
        worst = eo > worst ? eo : worst;
    }
    if (k < m) {
        float ee = fabsf(ce + (c1 + c2 * s->ho_x[k]) * s->ho_x[k] - fj);
        worst = ee > worst ? ee : worst;
    }
    *alt = fabsf(c3) * PI3_F;
    *res = worst * PI3_F;
    *acc = 2.0f * c2 * PI3_F * s->ho_inv * s->ho_inv;
    return fin(*alt) && fin(*res) && fin(*acc) ? 0 : -1;
}

/* 5. The handover's plausibility: the crossings lie on a turning rotor's path, their alternate displacement and the
 * distance of each from the path within what the closed loop's jump check tolerates (alternate crossings (pi/6)
 * (jump - 1) / (jump + 1) off), at an acceleration the start-up can give (at most BC_BEMF_HO_ACC ramp_accel either
 * way). */
static int plausible(const bc_bemf_params *p, bc_bemf_state *s)
{
    float alt, res, acc;
    int f = bc_bemf_ho_fit(s, &alt, &res, &acc);
    if (f != 0) return f > 0;
    float d_max = PI6_F * (p->jump_max - 1.0f) / (p->jump_max + 1.0f);
    return alt <= d_max && res <= d_max && !(p->ramp_accel > 0.0f && fabsf(acc) > BC_BEMF_HO_ACC * p->ramp_accel);
}

/* 9. The timeout after the crossing at t_zc (s): zc_timeout T60, or, with brake_tau, at least the latest the next
 * crossing can come for a rotor braked as hard as the drive can brake it, dw/dt = -w / tau - brake_acc from
 * the speed w0 of the last interval (1 / tau = 1 / brake_tau + brake_q w0), plus the same margin (zc_timeout - 1)
 * T60: its angle c tau (1 - e^(-t/tau)) -
 * a tau t (c = w0 + a tau) reaches pi/3 (Newton from t = 0: the angle is concave, the steps approach from below),
 * or, if the rotor falls below omega_stall first, the time it takes to. */
static float timeout_of(const bc_bemf_params *p, const bc_bemf_state *s)
{
    float t = p->zc_timeout * s->t60;
    if (!(p->brake_tau > 0.0f) || !(s->t60 > 0.0f)) return t;
    float tl = s->t_last > 0.0f ? s->t_last : s->t60;
    float w0 = PI3_F / tl, a = p->brake_acc;
    float tau = p->brake_tau / (1.0f + p->brake_q * w0 * p->brake_tau); /* the propeller's drag k_q w <= k_q w0 */
    float c = w0 + a * tau;
    float ts = tau * logf(c / (p->omega_stall + a * tau)); /* to the stall speed */
    if (!(fin(ts) && ts > 0.0f)) return t;
    float tb = 0.0f;
    for (int k = 0; k < 8; ++k) {
        float e = expf(-tb / tau);
        float f = c * tau * (1.0f - e) - a * tau * tb - PI3_F, d = c * e - a * tau; /* angle, speed */
        if (!(d > 0.0f) || f >= 0.0f) break;
        tb -= f / d;
        if (!(tb < ts)) {
            tb = ts;
            break;
        }
    }
    float tw = tb + (p->zc_timeout - 1.0f) * s->t60;
    return fin(tw) && tw > t ? tw : t;
}

/* timeout_of, computed again only when T60 or the last interval changed (at a crossing; its exp/log cost once a
 * sector, not every sample) */
static float timeout_cached(const bc_bemf_params *p, bc_bemf_state *s)
{
    if (!(s->to_t60 == s->t60 && s->to_tl == s->t_last)) {
        s->to_t60 = s->t60;
        s->to_tl = s->t_last;
        s->to_val = timeout_of(p, s);
    }
    return s->to_val;
}

/* 5 and 7: an accepted crossing at x_e (s relative to t_k). */
static int on_crossing(const bc_bemf_params *p, bc_bemf_state *s, bemf_now *n, float x_e)
{
    float w0 = omega_of(p, s);
    float x_zc = x_e - filter_delay(p, w0) - (p->method == BC_BEMF_COMPARATOR ? p->t_comp : 0.0f);
    float T = s->have_zc ? x_zc - tdiff(s->t_zc, n->tk) * s->inv_tick : 0.0f;
    if (!(fin(T) && T > 0.0f)) T = 0.0f;
    if (s->mode == BC_BEMF_RAMP) { /* a crossing interval the rotor cannot have (noise on a small back-EMF) */
        float into = x_zc - tdiff(s->t_c, n->tk) * s->inv_tick;
        float wf = fminf(s->w_ol + p->ramp_accel * fmaxf(into, 0.0f), p->ramp_w1);
        if (T > 0.0f && PI3_F / T > RAMP_W_MAX * wf) return 0;
    }
    s->det = 2;
    if (s->mode == BC_BEMF_RAMP) {
        s->sector_ok = 1;
        s->valid += 1;
        s->t_zc = tadd(n->tk, x_zc * p->f_tick);
        s->have_zc = 1;
        s->ho_ring[(s->valid - 1) % BC_BEMF_HO_FIT] = s->t_zc;
        if (!(s->valid >= p->n_handover && T > 0.0f && PI3_F / T >= 1.5f * p->omega_stall && plausible(p, s))) {
            /* not yet: the crossing commutates the forced sector 30 degrees after it, if that comes before the
             * forced instant, at the speed from the crossing interval (two crossings in a row), else from the 30
             * degrees between the sector's start and its crossing, at most twice the forced speed: a rotor that
             * leads the forced field by phi crosses (30 deg - phi) after the sector's start, which overstates its
             * speed, and a commutation that comes early leaves it lagging, where the pair's torque falls
             * (docs/sensorless.md, section 8); a rotor started from rest under the pair's best torque (twice the
             * default ramp's acceleration) is at most twice as fast as the ramp */
            float into = x_zc - tdiff(s->t_c, n->tk) * s->inv_tick;
            float wf = fminf(s->w_ol + p->ramp_accel * fmaxf(into, 0.0f), p->ramp_w1);
            float wc = T > 0.0f ? PI3_F / T : (into > 0.0f ? fminf(PI6_F / into, 2.0f * wf) : wf);
            s->w_zc = fin(wc) && wc > 0.0f ? wc : 0.0f;
            if (wc > 0.0f && fin(wc)) {
                uint32_t tn = tadd(n->tk, (x_zc + PI6_F / wc) * p->f_tick);
                if (tdiff(tn, s->t_next) < 0.0f) s->t_next = tn;
            }
            return 1;
        }
        /* handover: the throttle ramp starts from the duty the forced ramp applied */
        s->d_cmd = ramp_duty_at(p, omega_of(p, s));
        s->mode = BC_BEMF_CLOSED;
        s->grid_n = 0;
        s->grid_k = 0;
        for (int j = 0; j < 6; ++j) s->grid_dm[j] = 0.0f;
        s->t_in = 0.0f;
        s->t60 = T;
        s->t_last = T;
        s->virt = 0;
        s->misses = 0;
        s->err = 0.0f;
    } else {
        s->err = w0 * (x_zc - tdiff(s->t_c, n->tk) * s->inv_tick) - (PI6_F + s->adv_prev);
        if (!fin(s->err)) s->err = 0.0f;
        if (p->demag_max > 0.0f && s->dm_known) { /* the demagnetisation limiter */
            float r = w0 * s->t_demag / (PI6_F + s->adv_prev);
            float d = fminf(s->d_dm, s->m_app + 0.05f) + 0.2f * (p->demag_max - r);
            s->d_dm = fin(d) ? bc_clampf(d, 0.0f, 1.0f) : s->d_dm;
        }
        if (T > 0.0f && s->t_last > 0.0f && !s->virt) {
            float ratio = T / s->t_last;
            if (!(ratio <= p->jump_max && ratio * p->jump_max >= 1.0f)) {
                desync(s, n, BC_BEMF_REASON_JUMP);
                return 1;
            }
        }
        if (T > 0.0f && !s->virt) {
            s->t60 += p->t60_gain * (T - s->t60);
            s->t_last = T;
            if (p->grid_gain > 0.0f) grid_learn(p, s, T); /* 7: the uniform grid */
        } else {
            s->t_last = 0.0f;
        }
        s->virt = 0;
        s->misses = 0;
        s->t_zc = tadd(n->tk, x_zc * p->f_tick);
        s->have_zc = 1;
        if (p->grid_gain > 0.0f && s->sector >= 0 && s->sector <= 5) { /* this sector's demagnetisation (the bound) */
            /* not seen at a sample: the pre level lasted less than one, the clamp ended within the sample before */
            float since = x_zc - tdiff(s->t_c, n->tk) * s->inv_tick;
            float dm = s->dm_known ? s->t_demag : since - p->ts;
            s->grid_dm[s->sector] = fin(dm) && dm > 0.0f ? dm : 0.0f;
        }
    }
    float w = omega_of(p, s);
    if (!(w >= p->omega_stall)) {
        desync(s, n, BC_BEMF_REASON_STALL);
        return 1;
    }
    s->adv = advance_of(p, s, w);
    float x_n;
    /* with sync or high chopping the floating phase conducts in every off-time after a falling crossing (its
     * terminal pushed below 0 V, its lower diode on) and the filter carries that dip into each conversion: those
     * samples are not its back-EMF, and the integration commutates from the crossing at the measured speed */
    int dipped = p->tau_filter > 0.0f && (p->chop == BC_CHOP_SYNC || p->chop == BC_CHOP_HIGH) && !(s->sector & 1);
    if (p->method == BC_BEMF_INTEGRATE && !dipped) {
        s->integ = 1;
        s->t_int_max = tadd(n->tk, (x_zc + PI3_F / w) * p->f_tick);
        x_n = integrate_predict(p, s, n, w);
    } else {
        float t60 = PI3_F / w;
        x_n = x_zc + (PI6_F - s->adv) / PI3_F * t60; /* 30 - adv degrees after the crossing */
        if (s->mode == BC_BEMF_CLOSED && p->grid_gain > 0.0f) { /* its grid point, no later than the bound */
            float tn = t60;
            float lag = grid_lag(s, s->sector, &tn);
            float x_g = x_zc - lag + (PI6_F - s->adv) / PI3_F * tn;
            x_n = x_g > x_n ? fmaxf(x_n, fminf(x_g, grid_latest(p, s, x_zc, lag, tn, w))) : x_g;
        }
    }
    s->t_next = tadd(n->tk, x_n * p->f_tick);
    s->pending = 1;
    return 1;
}

/* ------------------------------------------------------------------------------------------------------------ */

/* demag: the outgoing phase may still conduct (fast demagnetisation, 8) */
static int legs_of(const bc_bemf_params *p, const bc_bemf_state *s, int sector, float m, float travel, int demag,
                   int comp, bc_leg_cmd c[3])
{
    int pos, neg;
    (void)bc_sector_phases(sector, &pos, &neg);
    if (s->dir < 0) {
        int t = pos;
        pos = neg;
        neg = t;
    }
    int inc = (s->incoming == pos || s->incoming == neg) ? s->incoming : pos;
    int cont = inc == pos ? neg : pos;
    int chop_leg = pos;
    if (p->chop == BC_CHOP_PWMPWM) chop_leg = travel < PI6_F ? inc : cont;
    if (demag && s->fd_on && p->chop != BC_CHOP_BIPOLAR && s->incoming >= 0 && s->outgoing >= 0) {
        if (p->chop == BC_CHOP_SYNC && cont == neg) { /* neg complementary at the average (1 - m) V, pos on */
            /* comp: the change of chopping leg costs one dead time of the pair's voltage (8): made up in the
             * first whole half period, 2 d_diode (SYNC's d_diode is the dead time's share of a period) */
            float dc = comp ? 2.0f * p->d_diode : 0.0f;
            bc_pair_legs(BC_CHOP_PWMPWM, pos, neg, neg, m, c);
            c[neg].mode = BC_LEG_PWM;
            c[neg].duty = bc_clampf(1.0f - m - dc, 0.0f, 1.0f);
            return 1;
        }
        if (p->chop != BC_CHOP_SYNC) { /* the continuing leg chops with its own switch */
            bc_pair_legs(BC_CHOP_PWMPWM, pos, neg, cont, m, c);
            return 0;
        }
    }
    bc_pair_legs((int)p->chop, pos, neg, chop_leg, m, c);
    return 0;
}

/* the demagnetisation of the sector's commutation not yet seen over (no pre level, no crossing) */
static int demag_now(const bc_bemf_state *s) { return s->det < 2 && !s->dm_known && !s->pre_seen; }

/* fast demagnetisation (8): engaged from the output whose interval ends with the clamp on for fd_after of the window
 * (travel_end: the electrical angle from the commutation to the interval's end); it stays engaged until the clamp is
 * seen over. Where one sample spans that share of the window, it is engaged from the commutation. */
static int fd_engage(const bc_bemf_params *p, bc_bemf_state *s, float travel_end)
{
    int dm = demag_now(s);
    if (p->fast_demag && dm && !s->fd_on && !(travel_end < p->fd_after * (PI6_F + s->adv_prev))) {
        s->fd_on = 1;
        s->fd_comp = p->chop == BC_CHOP_SYNC;
    }
    return dm;
}

/* 2. the duty applied: the state's, limited by the current limiter */
static float duty_of(const bc_bemf_params *p, const bc_bemf_state *s)
{
    float m = 0.0f;
    if (s->mode == BC_BEMF_ALIGN) m = with_diode(p, p->align_duty);
    else if (s->mode == BC_BEMF_RAMP) m = ramp_duty_at(p, s->w_now); /* at the forced speed now */
    else if (s->mode == BC_BEMF_CLOSED) {
        m = fmaxf(s->d_cmd, p->duty_min);
        if (p->demag_max > 0.0f) m = fminf(m, s->d_dm);
        if (p->dlim_d0 > 0.0f) { /* speed-dependent limit */
            float w = omega_of(p, s), x = w * p->dlim_tau;
            m = fminf(m, with_diode(p, p->dlim_d0 * sqrtf(1.0f + x * x) + p->dlim_vf * w));
        }
    }
    m = fminf(m, s->d_lim);
    return fin(m) ? bc_clampf(m, 0.0f, 1.0f) : 0.0f;
}

/* all legs off, coasting (STOP: not the safe state, no BC_FLAG_SAFE) */
static void coast(bc_ctrl_out *out)
{
    for (int x = 0; x < 3; ++x) {
        out->leg[x].mode = BC_LEG_OFF;
        out->leg[x].duty = 0.0f;
        out->leg_at[x] = out->leg[x];
    }
    out->has_at = 0u;
    out->t_at = 0.0f;
}

static void safe(bc_bemf_state *s, bc_ctrl_out *out, uint32_t flags)
{
    bc_legs_off(out);
    stop(s, BC_BEMF_REASON_NONE);
    s->d_lim = 1.0f;
    out->flags |= flags | BC_FLAG_SAFE;
    out->diag[0] = -1.0f;
    out->diag[1] = -1.0f;
    out->diag[7] = (float)s->reason;
}

void bc_bemf_step(const bc_bemf_params *p, bc_bemf_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
    out->flags = 0u;
    out->has_at = 0u;
    out->t_at = 0.0f;

    bemf_now n;
    n.tk = in->tick_now;
    n.ta = tadd(n.tk, (float)p->delay * s->ts_tick);
    n.flags = 0u;
    if (s->started) s->k_samp += 1u;
    n.adc_new = s->started && in->n_adc != s->n_adc_seen;
    s->n_adc_seen = in->n_adc;
    if (!s->started) {
        s->started = 1;
        for (int x = 0; x < 3; ++x) s->cnt_seen[x] = in->zc_count[x];
    }
    /* comparator activity on any phase (the restart waits for quiet comparators) */
    s->quiet = fminf(s->quiet + p->ts, 1e6f);
    s->t_in = fminf(s->t_in + p->ts, 1e6f);
    for (int x = 0; x < 3; ++x) {
        if (in->zc_count[x] != s->cnt_seen[x]) s->quiet = 0.0f;
        s->cnt_seen[x] = in->zc_count[x];
    }

    /* 1. input checks */
    float i[3] = {0.0f, 0.0f, 0.0f};
    uint32_t why = 0u;
    if (p->use_current) {
        why |= bc_guard_step(&s->guard_p, &s->guard, in, i);
    } else {
        if (!(fin(in->v_dc) && in->v_dc > 0.0f && in->v_dc <= p->v_max)) why |= BC_FLAG_BAD_INPUT;
        if (in->fault_pin) why |= BC_FLAG_OVERCURRENT;
    }
    if (!fin(in->ref)) why |= BC_FLAG_BAD_INPUT;
    if (p->method != BC_BEMF_COMPARATOR && n.adc_new &&
        !(fin(in->v_term[0]) && fin(in->v_term[1]) && fin(in->v_term[2]) && fin(in->v_neutral)))
        why |= BC_FLAG_BAD_INPUT;
    if (why) {
        safe(s, out, why);
        return;
    }

    /* 2. throttle: d_cmd toward d_ref at most duty_rate T_s per sample; the current limiter */
    float mag = fabsf(in->ref);
    int want = in->ref > 0.0f ? 1 : (in->ref < 0.0f ? -1 : 0);
    if (mag > 1.0f) n.flags |= BC_FLAG_SATURATED;
    float d_ref = bc_clampf(mag, 0.0f, 1.0f);
    if (p->duty_rate > 0.0f) {
        float lim = p->duty_rate * p->ts;
        s->d_cmd = bc_clampf(s->d_cmd + bc_clampf(d_ref - s->d_cmd, -lim, lim), 0.0f, 1.0f);
    } else {
        s->d_cmd = d_ref;
    }
    float i_pk = fmaxf(fabsf(i[0]), fmaxf(fabsf(i[1]), fabsf(i[2])));
    if (p->use_current && p->i_limit > 0.0f) {
        float d = s->d_lim + p->k_limit * (p->i_limit - i_pk) * p->ts;
        s->d_lim = fin(d) ? bc_clampf(d, 0.0f, 1.0f) : 0.0f;
    } else {
        s->d_lim = 1.0f;
    }

    /* 3. states: stop on a small or reversed reference; start from STOP */
    if (s->mode != BC_BEMF_STOP && (mag <= p->ref_stop || want != s->dir)) stop(s, BC_BEMF_REASON_NONE);
    if (s->mode == BC_BEMF_STOP && mag > p->ref_stop && want != 0) {
        if (s->fresh || (s->quiet >= p->restart_wait && s->t_in >= p->restart_wait) || s->t_in >= p->restart_max)
            start(p, s, in, &n, want);
    }
    /* 4. alignment over: the ramp */
    if (s->mode == BC_BEMF_ALIGN && s->t_in >= p->align_time) begin_ramp(p, s, in, &n);
    /* 5. the handover's fit prepared at the first sample after each forced sector's crossing (ho_prepare) */
    if (s->mode == BC_BEMF_RAMP && s->ho_n != s->valid) ho_prepare(s, s->valid);

    /* 5-9. detection, commutation schedule, timeout */
    if (s->mode == BC_BEMF_RAMP || s->mode == BC_BEMF_CLOSED) {
        float x_e = 0.0f;
        if (s->mode == BC_BEMF_RAMP && s->first) {
            /* the first forced sector after the alignment: the rotor starts at rest at its crossing (pi), where the
             * floating phase reads the reference within noise; nothing it shows is a crossing */
        } else if (s->det < 2) {
            int got = p->method == BC_BEMF_COMPARATOR ? detect_comparator(p, s, in, &n, &x_e)
                                                      : detect_adc(p, s, in, &n, &x_e);
            if (got) {
                if (!on_crossing(p, s, &n, x_e)) { /* rejected: wait for a new pre level and edge */
                    s->det = 1;
                    s->cnt_open = in->zc_count[floating(s->sector)];
                    s->pre_seen = 0;
                    s->pre_free = 0;
                    s->post_open = 0;
                    s->n_post = 0;
                }
            } else if (s->mode == BC_BEMF_RAMP && s->post_open && tdiff(n.tk, s->t_c) >= 0.5f * s->tau_ol * p->f_tick) {
                /* start-up: the post level since the window opened and still at half the forced sector: not a clamp
                 * but a rotor leading the forced field (its crossing came before the window). The forced sector is
                 * cut short, the next one commanded from t_a; not a valid crossing */
                s->det = 2;
                s->valid = 0;
                s->have_zc = 0;
                s->w_zc = 0.0f;
                s->t_next = n.ta;
            }
        } else if (s->integ && s->mode == BC_BEMF_CLOSED && n.adc_new) {
            /* BC_BEMF_INTEGRATE: the next conversion, integrated (trapezoid) and the instant predicted again */
            uint32_t t = in->tick_adc;
            int f = floating(s->sector);
            float u = (s->sector & 1) ? in->v_term[f] - in->v_neutral : in->v_neutral - in->v_term[f];
            float dt = tdiff(t, s->t_u) * s->inv_tick;
            /* a clamped sample is skipped: the instant stays the one predicted from the last free sample, and the
             * next free one integrates the trapezoid over the gap */
            if (fin(u) && dt > 0.0f && tdiff(t, n.tk) <= 0.0f && !rail_clamped(in, f)) {
                s->lam += 0.5f * (s->u_last + u) * dt;
                s->r_last = fmaxf((u - s->u_last) / dt, 0.0f);
                s->u_last = u;
                s->t_u = t;
                s->t_next = tadd(n.tk, integrate_predict(p, s, &n, omega_of(p, s)) * p->f_tick);
            }
        }
        if (s->integ && s->mode == BC_BEMF_CLOSED && s->pending && tdiff(n.tk, s->t_int_max) >= 0.0f &&
            tdiff(s->t_next, s->t_int_max) > 0.0f)
            s->t_next = s->t_int_max; /* not reached 60 degrees after the crossing: at once */
        /* 9. timeout */
        if (s->mode == BC_BEMF_CLOSED && s->det < 2 && s->have_zc &&
            tdiff(n.tk, s->t_zc) >= timeout_cached(p, s) * p->f_tick) {
            if (s->misses < p->miss_max) { /* a blind commutation at once, a virtual crossing */
                s->misses += 1;
                s->d_dm *= 0.7f;
                s->t_zc = tadd(s->t_zc, s->t60 * p->f_tick);
                s->virt = 1;
                s->t_last = 0.0f;
                s->t_next = tadd(n.tk, -1.0f); /* past: the late path */
                s->pending = 1;
                s->det = 2;
            } else {
                desync(s, &n, s->pre_seen ? BC_BEMF_REASON_TIMEOUT : BC_BEMF_REASON_HIDDEN);
            }
        }
    }

    /* 8. the commutation timer, and the legs */
    int shown = -1;
    float m = 0.0f;
    if (s->mode == BC_BEMF_STOP) {
        coast(out);
    } else if (s->mode == BC_BEMF_ALIGN) {
        m = duty_of(p, s);
        if (s->t_in < p->align_time * (2.0f / 7.0f)) { /* a+ and b+ with a, c-: the rotor to 4 pi/3 */
            bc_pair_legs((int)p->chop, 0, 2, 0, m, out->leg);
            out->leg[1] = out->leg[0];
        } else if (s->t_in < p->align_time * (3.0f / 7.0f)) { /* a+ and c+ with a, b-: to 2 pi/3, off the last
                                                                 * step's dead point (0), where the first may
                                                                 * leave a held rotor */
            bc_pair_legs((int)p->chop, 0, 1, 0, m, out->leg);
            out->leg[2] = out->leg[0];
        } else { /* a+, b- and c- with b: the rotor to theta_e = pi */
            bc_pair_legs((int)p->chop, 0, 1, 0, m, out->leg);
            out->leg[2] = out->leg[1];
        }
        shown = 0;
    } else {
        float w = omega_of(p, s);
        int now = s->pending && tdiff(s->t_next, n.ta) < s->ts_tick;
        if (s->mode == BC_BEMF_RAMP) { /* the forced speed at the output's interval, w_ol + accel (t_a - t_c) */
            float el = tdiff(n.ta, s->t_c) * s->inv_tick;
            s->w_now = fminf(s->w_ol + p->ramp_accel * fmaxf(el, 0.0f), p->ramp_w1);
            if (!fin(s->w_now)) s->w_now = p->ramp_w1;
        }
        if (now && s->mode == BC_BEMF_RAMP) { /* a forced commutation: the next sector's speed; give up? */
            if (!s->sector_ok) {
                s->valid = 0;
                s->have_zc = 0;
                s->w_zc = 0.0f;
            }
            /* the open-loop speed at the commutation: w0 + accel t (the sector may have ended early, at a crossing) */
            float dn0 = tdiff(s->t_next, n.ta);
            float el = tdiff(dn0 >= 0.0f ? s->t_next : n.ta, s->t_c) * s->inv_tick;
            float w_next = fminf(s->w_ol + p->ramp_accel * fmaxf(el, 0.0f), p->ramp_w1);
            if (w_next >= p->ramp_w1) s->hold += 1;
            if (s->hold > p->ramp_hold) {
                desync(s, &n, BC_BEMF_REASON_START);
                coast(out);
                now = 0;
            } else {
                s->w_ol = w_next;
                s->tau_ol = sector_time(w_next, p->ramp_accel, p->ramp_w1);
            }
        }
        if (s->mode != BC_BEMF_STOP) {
            m = duty_of(p, s); /* for the interval the output applies to (the ramp's speed just updated) */
            int next = (s->sector + (s->dir > 0 ? 1 : 5)) % 6;
            float dn = tdiff(s->t_next, n.ta);
            float travel = w * tdiff(n.ta, s->t_c) * s->inv_tick;
            if (!fin(travel)) travel = 0.0f;
            if (now && dn >= 0.0f) { /* inside the interval: the commutation timer */
                int dm = fd_engage(p, s, travel + w * p->ts);
                if (legs_of(p, s, s->sector, m, travel, dm, s->fd_comp, out->leg)) s->fd_comp = 0;
                shown = s->sector;
                uint32_t tc = s->t_next;
                enter_sector(p, s, in, next, tc, -1);
                dm = fd_engage(p, s, w * (p->ts - dn * s->inv_tick));
                (void)legs_of(p, s, next, m, 0.0f, dm, 0, out->leg_at); /* made up in the next whole half */
                out->has_at = 1u;
                out->t_at = bc_clampf(dn * s->inv_tick, 0.0f, p->ts * 0.999999f);
                s->adv_prev = s->adv;
            } else if (now) { /* already past: at once, from t_a */
                n.flags |= BC_FLAG_COMM_LATE;
                enter_sector(p, s, in, next, n.ta, -1);
                int dm = fd_engage(p, s, w * p->ts);
                if (legs_of(p, s, next, m, 0.0f, dm, s->fd_comp, out->leg)) s->fd_comp = 0;
                shown = next;
                s->adv_prev = s->adv;
            } else {
                int dm = fd_engage(p, s, travel + w * p->ts);
                if (legs_of(p, s, s->sector, m, travel, dm, s->fd_comp, out->leg)) s->fd_comp = 0;
                shown = s->sector;
            }
            if (now && s->mode == BC_BEMF_RAMP) { /* the next forced commutation */
                s->t_next = tadd(s->t_c, s->tau_ol * p->f_tick);
                s->pending = 1;
            }
        }
    }
    if (s->mode == BC_BEMF_STOP) {
        coast(out);
        out->has_at = 0u;
        shown = -1;
        m = 0.0f;
    } else if ((s->mode == BC_BEMF_ALIGN || s->mode == BC_BEMF_RAMP) && p->use_current && p->i_start > 0.0f &&
               i_pk > p->i_start) {
        /* the start-up's cycle-by-cycle current limit: every switch off over the interval, the current returns to
         * the bus through the diodes (a zero vector would short the back-EMF of a moving rotor); the commutation
         * schedule goes on */
        coast(out);
        m = 0.0f;
        n.flags |= BC_FLAG_SATURATED;
    }
    for (int j = 0; j < 3; ++j) { /* never pass on a bad duty */
        if (!in01(out->leg[j].duty)) out->leg[j].duty = 0.0f;
        if (!in01(out->leg_at[j].duty)) out->leg_at[j].duty = 0.0f;
    }
    if (s->mode == BC_BEMF_ALIGN || s->mode == BC_BEMF_RAMP) n.flags |= BC_FLAG_OPEN_LOOP;
    out->flags |= n.flags;
    float w = omega_of(p, s);
    out->diag[0] = (float)s->mode;
    out->diag[1] = (float)shown;
    out->diag[2] = s->mode == BC_BEMF_STOP ? 0.0f : (float)s->dir * w;
    out->diag[3] = s->err;
    out->diag[4] = s->t_demag;
    out->diag[5] = s->adv;
    out->diag[6] = m;
    s->m_app = m;
    out->diag[7] = (float)s->reason;
    for (int j = 0; j < BC_DIAG_N; ++j) {
        if (!fin(out->diag[j])) out->diag[j] = 0.0f;
    }
}

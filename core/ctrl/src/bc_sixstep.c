/* bc_sixstep.c - real square-wave (120-degree) current-controlled supply. Laws in bc_sixstep.h. */
#include "bldc/bc_sixstep.h"

#include <math.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_inverter.h"
#include "bldc/bc_math.h"
#include "bldc/bc_transform.h"

#define PI3_F (BC_PI_F / 3.0f)
#define PI6_F (BC_PI_F / 6.0f)

static int fin(float v) { return isfinite(v) ? 1 : 0; }

int bc_sixstep_init(const bc_sixstep_params *p, bc_sixstep_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (p->reg < BC_SIXSTEP_PI || p->reg > BC_SIXSTEP_IDEAL) return BC_ERR_PARAM;
    if ((p->timed != 0 && p->timed != 1) || (p->comm != BC_SIXSTEP_COMM_HALL && p->comm != BC_SIXSTEP_COMM_ENCODER) ||
        !fin(p->adv_angle) || !fin(p->adv_time) || p->adv_angle < 0.0f || p->adv_time < 0.0f)
        return BC_ERR_PARAM;
    if (p->chop < BC_SIXSTEP_BIPOLAR || p->chop > BC_SIXSTEP_SYNC) return BC_ERR_PARAM;
    if ((p->ref_torque != 0 && p->ref_torque != 1) || (p->delay != 0 && p->delay != 1) ||
        (p->advance != 0 && p->advance != 1) || (p->emf_ff != 0 && p->emf_ff != 1) ||
        (p->regen != 0 && p->regen != 1) || p->p < 1)
        return BC_ERR_PARAM;
    if (!fin(p->ts) || !fin(p->R) || !fin(p->L) || !fin(p->k_e) || !fin(p->kp) || !fin(p->ki) || !fin(p->band) ||
        !fin(p->i_max) || !fin(p->v_max) || !fin(p->f_tick) || !fin(p->omega_min) || !fin(p->theta_offset))
        return BC_ERR_PARAM;
    if (!(p->ts > 0.0f) || p->R < 0.0f || !(p->L > 0.0f) || !(p->k_e > 0.0f) || p->kp < 0.0f || p->ki < 0.0f ||
        !(p->band > 0.0f) || !(p->i_max > 0.0f) || !(p->v_max > 0.0f))
        return BC_ERR_PARAM;
    if (!fin(p->open_frac) || p->open_frac < 0.0f || !(p->open_frac < 0.5f)) return BC_ERR_PARAM;
    s->open_n = 0;
    s->open_acc = 0.0f;
    s->hall_p = (bc_hall_params){.f_tick = p->f_tick, .omega_min = p->omega_min, .theta_offset = p->theta_offset,
                                 .mode = p->hall_mode, .pll_edges = p->hall_pll_edges, .table = p->hall_table};
    if (bc_hall_init(&s->hall_p, &s->hall) != BC_OK) return BC_ERR_PARAM;
    s->pi_p = (bc_pi_params){.kp = p->kp, .ki = p->ki, .ts = p->ts,
                             .u_min = -1.0f, .u_max = 1.0f};
    if (bc_pi_init(&s->pi_p, &s->pi) != BC_OK) return BC_ERR_PARAM;
    for (int x = 0; x < 3; ++x) {
        s->applied[x].mode = BC_LEG_OFF;
        s->applied[x].duty = 0.0f;
        s->applied_at[x] = s->applied[x];
    }
    s->applied_t = -1.0f;
    s->sector = -1;
    s->seen = -1;
    s->incoming = -1;
    s->hyst_on = 0;
    s->guard_p = (bc_guard_params){.i_max = p->i_max, .v_max = p->v_max};
    if (bc_guard_init(&s->guard_p, &s->guard) != BC_OK) return BC_ERR_PARAM;
    s->derate_on = p->derate.enabled[0] != 0 || p->derate.enabled[1] != 0;
    s->derate_f = 1.0f;
    if (s->derate_on && bc_derate_init(&p->derate, &s->derate) != BC_OK) return BC_ERR_PARAM;
    return BC_OK;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* average model (BC_SIXSTEP_PRED) */

/* Ideal 120-degree trapezoid of unit flat top, zero rising at th = 0:
 * k(th) = 6 th/pi on [0, pi/6], 1 on [pi/6, 5 pi/6], 6 (pi - th)/pi on [5 pi/6, pi], odd. */
static float trapezoid(float th)
{
    if (!(fabsf(th) <= 64.0f)) return 0.0f; /* NaN and infinities too */
    while (th < 0.0f) th += BC_TWO_PI_F; /* a few turns at most */
    while (th >= BC_TWO_PI_F) th -= BC_TWO_PI_F;
    float sgn = 1.0f;
    if (th > BC_PI_F) {
        th -= BC_PI_F;
        sgn = -1.0f;
    }
    float k = 1.0f;
    if (th < PI6_F) k = th / PI6_F;
    else if (th > 5.0f * PI6_F) k = (BC_PI_F - th) / PI6_F;
    return sgn * bc_clampf(k, 0.0f, 1.0f);
}

/* Average terminal voltage u of a leg over a half period from its command and the sign of its current; returns 1 if
 * the phase is connected, 0 if open. A HIGH/LOW leg with d = 0 never switches on: it behaves as OFF. */
static int leg_average(const bc_leg_cmd *c, float i, float v, float *u)
{
    float d = c->duty;
    int mode = (int)c->mode;
    if ((mode == BC_LEG_HIGH || mode == BC_LEG_LOW) && !(d > 0.0f)) mode = BC_LEG_OFF;
    switch (mode) {
    case BC_LEG_PWM:                   /* u = d V whatever the current */
        *u = d * v;
        return 1;
    case BC_LEG_HIGH:                  /* i < 0: switch or upper diode, V; i >= 0: V for d, lower diode 0 after */
        *u = i < 0.0f ? v : d * v;
        return 1;
    case BC_LEG_LOW:                   /* i > 0: switch or lower diode, 0; i <= 0: 0 for d, upper diode V after */
        *u = i > 0.0f ? 0.0f : (1.0f - d) * v;
        return 1;
    default:                           /* diodes only: 0 (i > 0), V (i < 0), open (i = 0) */
        if (i > 0.0f) {
            *u = 0.0f;
            return 1;
        }
        if (i < 0.0f) {
            *u = v;
            return 1;
        }
        *u = 0.0f;
        return 0;
    }
}

static int diode_only(const bc_leg_cmd *c)
{
    return c->mode == BC_LEG_OFF || ((c->mode == BC_LEG_HIGH || c->mode == BC_LEG_LOW) && !(c->duty > 0.0f));
}

int bc_sixstep_predict(const bc_leg_cmd cmd[3], float v, const float e[3], float R, float L, float t, float i[3])
{
    float left = t;
    int opened = 0;
    /* at most one segment per diode-only phase opening, plus the last (the circuit: bc_inverter.h) */
    for (int seg = 0; seg < 4 && left > 0.0f; ++seg) {
        float u[3], ri[3], di[3];
        int conn[3], diode[3];
        for (int x = 0; x < 3; ++x) {
            conn[x] = leg_average(&cmd[x], i[x], v, &u[x]);
            diode[x] = conn[x] && diode_only(&cmd[x]);
            ri[x] = R * i[x];
        }
        if (bc_inv_slopes(u, ri, e, conn, L, di) == BC_INV_NO_PATH) { /* no closed path: no current */
            i[0] = i[1] = i[2] = 0.0f;
            return opened;
        }
        float h;
        int z = bc_inv_first_zero(diode, i, di, left, &h);
        bc_inv_advance(conn, di, h, z, i);
        if (z >= 0) ++opened;
        left -= h;
    }
    return opened;
}

/* ------------------------------------------------------------------------------------------------------------ */
/* commands */

/* Leg commands of a chopping pattern: bc_pair_legs (bc_commutation.h), whose pattern constants are the same numbers
 * as this controller's (checked at compile time). */
typedef char chop_values_agree[(BC_SIXSTEP_BIPOLAR == BC_CHOP_BIPOLAR && BC_SIXSTEP_HIGH == BC_CHOP_HIGH &&
                                BC_SIXSTEP_PWMPWM == BC_CHOP_PWMPWM && BC_SIXSTEP_SYNC == BC_CHOP_SYNC) ? 1 : -1];

/* The ideal limiter's legs (BC_SIXSTEP_IDEAL): the continuing phase fully on, the incoming phase x held at sgn_x I_ref
 * (pos: +, neg: -), the third off. */
static void build_ideal(int pos, int neg, int x, float i_ref, bc_leg_cmd c[3], float *i_hold)
{
    for (int j = 0; j < 3; ++j) {
        c[j].mode = BC_LEG_OFF;
        c[j].duty = 0.0f;
    }
    c[pos].mode = BC_LEG_HIGH;
    c[pos].duty = 1.0f;
    c[neg].mode = BC_LEG_LOW;
    c[neg].duty = 1.0f;
    c[x].mode = BC_LEG_HOLD;
    *i_hold = x == pos ? i_ref : -i_ref;
}

static void safe(bc_sixstep_state *s, bc_ctrl_out *out, uint32_t flags)
{
    bc_legs_off(out);
    for (int x = 0; x < 3; ++x) s->applied[x] = out->leg[x];
    s->applied_t = -1.0f;
    out->flags |= flags | BC_FLAG_SAFE;
    out->diag[0] = -1.0f;
    out->diag[5] = -1.0f;
    out->diag[6] = -1.0f;
    bc_pi_reset(&s->pi_p, &s->pi, 0.0f);
    s->hyst_on = 0;
    s->sector = -1;
    s->seen = -1;
    s->incoming = -1;
}

/* Everything the duty solver needs. */
typedef struct {
    int chop, pos, neg, chop_leg, x;
    float sgn, v, R, L, ts;
    float e1[3];  /* back-EMF over the interval the output applies to */
    float i1[3];  /* currents at its start */
} pred_ctx;

/* Regulated current at the end of the interval the output applies to, with pair voltage m; *opened counts the
 * diode currents that end inside it. */
static float pred_end(const pred_ctx *c, float m, int *opened)
{
    bc_leg_cmd cmd[3];
    float i[3] = {c->i1[0], c->i1[1], c->i1[2]};
    bc_pair_legs(c->chop, c->pos, c->neg, c->chop_leg, m, cmd);
    *opened += bc_sixstep_predict(cmd, c->v, c->e1, c->R, c->L, c->ts, i);
    return c->sgn * i[c->x];
}

typedef struct {
    const pred_ctx *c;
    float target;
} pred_goal;

static float pred_gap(float m, void *ctx)
{
    const pred_goal *g = (const pred_goal *)ctx;
    int op = 0;
    return pred_end(g->c, m, &op) - g->target;
}

/* Solve pred_end(m) = target for m in [lo, hi] given f at both ends (f_lo < 0 < f_hi). Without a diode current
 * ending inside the sample at either end, none ends in between (its end time is monotonic in m) and the end
 * current is affine in m: the line through the ends is the solution. Otherwise regula falsi on the bracket
 * (bc_root_bracket, Illinois rule: superlinear; the every-time halving used before took up to 12 evaluations in
 * a commutation, the controller's worst step). */
static float solve_bracket(const pred_ctx *c, float target, float lo, float hi, float f_lo, float f_hi, int affine)
{
    float tol = 1e-4f * (1.0f + fabsf(target));
    float d = lo - f_lo * (hi - lo) / (f_hi - f_lo);
    if (affine) return fin(d) ? bc_clampf(d, lo, hi) : lo;
    pred_goal g = {c, target};
    d = bc_root_bracket(pred_gap, &g, lo, hi, f_lo, f_hi, d, tol, 1e-6f, 12, BC_ROOT_ILLINOIS);
    return fin(d) ? bc_clampf(d, lo, hi) : lo;
}

/* Solve pred_end(m) = target for m in [m_lo, 1]: first on [0, 1], then on [m_lo, 0]; *sat = 1 if limited. */
static float solve_m(const pred_ctx *c, float target, float m_lo, int *sat)
{
    int op01 = 0, op_lo = 0;
    float f0 = pred_end(c, 0.0f, &op01) - target;
    float f1 = pred_end(c, 1.0f, &op01) - target;
    *sat = 0;
    if (!(fin(f0) && fin(f1))) {
        *sat = 1;
        return 0.0f;
    }
    if (f1 <= 0.0f) { /* full voltage cannot do more */
        *sat = f1 < 0.0f;
        return 1.0f;
    }
    if (f0 < 0.0f) return solve_bracket(c, target, 0.0f, 1.0f, f0, f1, op01 == 0);
    if (f0 == 0.0f || !(m_lo < 0.0f)) {
        *sat = f0 > 0.0f;
        return 0.0f;
    }
    float fl = pred_end(c, m_lo, &op_lo) - target;
    if (!fin(fl)) {
        *sat = 1;
        return 0.0f;
    }
    if (fl >= 0.0f) {
        *sat = fl > 0.0f;
        return m_lo;
    }
    /* m = 0 (unipolar pattern) and m < 0 (both legs chop) are different circuits: never assume a line across */
    return solve_bracket(c, target, m_lo, 0.0f, fl, f0, 0);
}

/* ------------------------------------------------------------------------------------------------------------ */

/* The timing advance at electrical speed w (rad/s): adv_angle + w adv_time, at most pi/6. */
static float timing_advance(const bc_sixstep_params *p, float w)
{
    float a = p->adv_angle + w * p->adv_time;
    return fin(a) ? bc_clampf(a, 0.0f, PI6_F) : 0.0f;
}

/* Sector (0..5) whose span, advanced by adv in the direction of motion, holds the electrical angle th, and the angle
 * travelled into it (*travel). Forward, sector s spans [pi/6 + s pi/3, pi/2 + s pi/3) (bc_commutation.h); backward it
 * is entered at its upper end. */
static int encoder_sector(float th, int dir, float adv, float *travel)
{
    float u = dir >= 0 ? bc_wrap_2pi(th - PI6_F + adv) : bc_wrap_2pi(PI3_F + PI6_F + adv - th);
    int j = (int)(u / PI3_F);
    if (j < 0) j = 0;
    if (j > 5) j = 5;
    *travel = u - (float)j * PI3_F;
    return dir >= 0 ? j : (6 - j) % 6;
}

/* Command a sector: a new one records the phase that entered the pair (the incoming phase). */
static void set_sector(bc_sixstep_state *s, int sector)
{
    if (sector == s->sector) return;
    int inc = -1;
    if (s->sector >= 0) {
        int po, no, pn, nn;
        (void)bc_sector_phases(s->sector, &po, &no);
        (void)bc_sector_phases(sector, &pn, &nn);
        if (pn != po && pn != no) inc = pn;
        else if (nn != po && nn != no) inc = nn;
    }
    s->incoming = inc;
    s->sector = sector;
}

/* The chopping leg (3: both): PWM-on-PWM chops the incoming phase x in the first half of the sector (travel < pi/6,
 * or unknown), the other one in the second. */
static int chop_leg_of(const bc_sixstep_params *p, int pos, int neg, int x, float travel)
{
    if (p->chop == BC_SIXSTEP_PWMPWM) return (travel < 0.0f || travel < PI6_F) ? x : (x == pos ? neg : pos);
    if (p->chop == BC_SIXSTEP_BIPOLAR) return 3;
    return pos;
}

void bc_sixstep_step(const bc_sixstep_params *p, bc_sixstep_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
    out->flags = 0u;
    out->has_at = 0u; /* no timed commutation unless one is scheduled below */
    out->i_hold = 0.0f;
    out->i_hold_at = 0.0f;

    bc_hall_out h;
    bc_hall_step(&s->hall_p, &s->hall, in, &h);
    out->diag[4] = h.omega_e;
    if (s->derate_on) s->derate_f = bc_derate_step(&p->derate, &s->derate, in->temp); /* in [0, 1] */

    /* measurements, DC bus, hardware and software over-current trips: the input guard (bc_guard.h) */
    float i[3];
    uint32_t why = bc_guard_step(&s->guard_p, &s->guard, in, i);
    float v = in->v_dc;
    if (!h.valid) why |= BC_FLAG_HALL_INVALID;
    if (!fin(in->ref)) why |= BC_FLAG_BAD_INPUT;
    if (s->open_n < 0) why |= BC_FLAG_BAD_INPUT; /* no current path found: latched */
    if (why) {
        safe(s, out, why);
        return;
    }

    /* commutation: the sector seen, or the next one when its (advanced) boundary is due by the middle of the
     * interval this output applies to (advance; at the nominal boundary with a calibrated table):
     * bc_hall_commutate; with timed, the sector at the interval's start and the next one at its instant */
    float ts = p->ts;
    int timed = p->timed;
    float lead = ((float)p->delay + (timed ? 0.0f : 0.5f)) * ts;
    float travel;
    int dir = h.dir;
    float w_c = fabsf(h.omega_e); /* the speed the commutation instants come from */
    int sector;
    if (p->comm == BC_SIXSTEP_COMM_ENCODER) {
        float we = in->omega_enc * (float)p->p;
        if (!fin(in->theta_enc) || !fin(we)) {
            safe(s, out, BC_FLAG_BAD_INPUT);
            return;
        }
        w_c = fabsf(we);
        dir = we < 0.0f ? -1 : 1;
        sector = encoder_sector(in->theta_enc + we * lead, dir, timing_advance(p, w_c), &travel);
    } else {
        float adv = h.speed_valid ? timing_advance(p, w_c) : 0.0f;
        sector = bc_hall_commutate(&s->hall_p, &h, in, lead, p->advance || timed, adv, s->sector, &s->seen, &travel);
        if (!h.speed_valid) w_c = 0.0f;
    }
    set_sector(s, sector);
    /* the next commutation inside the interval, at its instant (timed) */
    int next = -1;
    float t_next = 0.0f;
    if (timed && travel >= 0.0f && w_c > 0.0f && dir != 0) {
        float dt = (PI3_F - travel) / w_c;
        if (fin(dt) && dt < ts) {
            next = (sector + (dir > 0 ? 1 : 5)) % 6;
            t_next = bc_clampf(dt, 0.0f, ts);
        }
    }
    int pos, neg;
    (void)bc_sector_phases(sector, &pos, &neg);
    float ref = in->ref;
    if (ref < 0.0f) { /* reverse torque: swap the roles */
        int t = pos;
        pos = neg;
        neg = t;
    }
    int third = 3 - pos - neg;
    int x = (s->incoming == pos || s->incoming == neg) ? s->incoming : pos;
    float sgn = x == pos ? 1.0f : -1.0f;
    float i_reg = sgn * i[x];
    float i_ref = fabsf(ref);
    if (p->ref_torque) i_ref /= p->k_e;
    i_ref = bc_clampf(i_ref, 0.0f, s->derate_f * p->i_max);

    /* PWM-on-PWM: the incoming phase chops in the first half of the sector, the other one in the second */
    int chop_leg = chop_leg_of(p, pos, neg, x, travel);

    /* back-EMF estimate over the interval the output applies to (mid-interval angle):
     * e_j = (k_e/2) (Omega_e/p) k(theta + Omega_e t - j 2 pi/3) */
    float w_m = h.omega_e / (float)p->p;
    float e1[3], e0[3];
    for (int j = 0; j < 3; ++j) {
        float th = h.theta - (float)j * (BC_TWO_PI_F / 3.0f);
        e0[j] = 0.5f * p->k_e * w_m * trapezoid(th + h.omega_e * 0.5f * ts);
        e1[j] = 0.5f * p->k_e * w_m * trapezoid(th + h.omega_e * lead);
    }

    /* lowest normalised pair voltage: -1 (both legs off) with bipolar chopping or regen, else 0 (freewheel) */
    float m_lo = (p->chop == BC_SIXSTEP_BIPOLAR || p->regen) ? -1.0f : 0.0f;
    float m = 0.0f;
    int sat = 0;
    if (p->reg == BC_SIXSTEP_PRED) {
        pred_ctx c;
        c.chop = (int)p->chop;
        c.pos = pos;
        c.neg = neg;
        c.chop_leg = chop_leg;
        c.x = x;
        c.sgn = sgn;
        c.v = v;
        c.R = p->R;
        c.L = p->L;
        c.ts = ts;
        for (int j = 0; j < 3; ++j) {
            c.e1[j] = e1[j];
            c.i1[j] = i[j];
        }
        /* i(k+1) = F(i(k), c_applied): the command already in force (delay 1), in two parts if a timed
         * commutation falls in it */
        if (p->delay) {
            if (s->applied_t >= 0.0f) {
                (void)bc_sixstep_predict(s->applied, v, e0, p->R, p->L, s->applied_t, c.i1);
                (void)bc_sixstep_predict(s->applied_at, v, e0, p->R, p->L, ts - s->applied_t, c.i1);
            } else {
                (void)bc_sixstep_predict(s->applied, v, e0, p->R, p->L, ts, c.i1);
            }
        }
        /* sgn_x i_x(k+1+D) = F(i(k+D), c(m)) = I_ref */
        m = solve_m(&c, i_ref, m_lo, &sat);
    } else if (p->reg == BC_SIXSTEP_DUTY) {
        /* no current loop: the duty asked for (an ESC's throttle) */
        float d = fabsf(ref);
        m = bc_clampf(d, 0.0f, 1.0f);
        sat = d > 1.0f;
    } else if (p->reg == BC_SIXSTEP_IDEAL) {
        m = 1.0f; /* the plant regulates (diagnostic: full voltage available) */
    } else if (p->reg == BC_SIXSTEP_HYST) {
        /* m = 1 below I_ref - band/2, m = m_lo above I_ref + band/2, else unchanged */
        if (i_reg < i_ref - 0.5f * p->band) s->hyst_on = 1;
        else if (i_reg > i_ref + 0.5f * p->band) s->hyst_on = 0;
        m = s->hyst_on ? 1.0f : m_lo;
    } else {
        /* m = u / V_dc = k_p e / V_dc + x + u_ff / V_dc,  u_ff = e_pos - e_neg + 2 R I_ref;  x updated with the
         * realised m (back-calculation, bc_pi.h) */
        float err = i_ref - i_reg;
        float ff = p->emf_ff ? (e1[pos] - e1[neg] + 2.0f * p->R * i_ref) / v : 0.0f;
        float mu = bc_pi_output(&s->pi_p, &s->pi, err / v, ff);
        m = bc_clampf(fin(mu) ? mu : 0.0f, m_lo, 1.0f);
        sat = !(m == mu);
        bc_pi_update(&s->pi_p, &s->pi, err / v, mu, m);
    }
    m = fin(m) ? bc_clampf(m, m_lo, 1.0f) : 0.0f;

    /* no current path (an open phase, a lost current sensor): a current loop driving the pair with the voltage
     * u = m V_dc - |e_pos - e_neg| (this sample's command over the line back-EMF estimate) whose regulated current
     * stays below f I_ref (f = open_frac), where the pair's R-L circuit would reach 2 f I_ref from zero within
     *     t_2 = -(L/R) ln(1 - 2 f I_ref / I_inf),  I_inf = u / (2 R)     (t_2 = 4 L f I_ref / u for R = 0).
     * Over consecutive such samples the sum of T_s / t_2 is the share of that time the applied voltage has had:
     * past 2 (twice the time) and 4 samples (the delay, a commutation) the current has no path: safe state,
     * BC_FLAG_BAD_INPUT, latched. Not tested where I_inf <= 2 f I_ref (no margin to tell), nor without a speed
     * estimate (before the Hall speed is valid the back-EMF, hence the margin, is unknown). */
    if (p->open_frac > 0.0f && i_ref > 0.0f && (h.speed_valid || p->comm == BC_SIXSTEP_COMM_ENCODER) &&
        (p->reg == BC_SIXSTEP_PRED || p->reg == BC_SIXSTEP_PI || p->reg == BC_SIXSTEP_HYST)) {
        float thr = p->open_frac * i_ref;
        float u = m * v - fabsf(e1[pos] - e1[neg]);
        float t2 = -1.0f;
        if (u > 0.0f) {
            if (p->R > 0.0f) {
                float q = 2.0f * thr * 2.0f * p->R / u; /* 2 f I_ref / I_inf */
                if (q < 1.0f) t2 = -(p->L / p->R) * logf(1.0f - q);
            } else {
                t2 = 4.0f * p->L * thr / u;
            }
        }
        if (t2 > 0.0f && fin(t2) && i_reg < thr) {
            s->open_n += 1;
            s->open_acc += ts / t2;
            if (s->open_acc > 2.0f && s->open_n > 4) {
                s->open_n = -1;
                safe(s, out, BC_FLAG_BAD_INPUT);
                return;
            }
        } else {
            s->open_n = 0;
            s->open_acc = 0.0f;
        }
    } else {
        s->open_n = 0;
        s->open_acc = 0.0f;
    }

    if (p->reg == BC_SIXSTEP_IDEAL) {
        build_ideal(pos, neg, x, i_ref, out->leg, &out->i_hold);
    } else {
        bc_pair_legs((int)p->chop, pos, neg, chop_leg, m, out->leg);
    }
    if (next >= 0) { /* the timed commutation: the next sector's legs from t_next, the same pair voltage */
        int pn, nn;
        (void)bc_sector_phases(next, &pn, &nn);
        if (ref < 0.0f) {
            int t = pn;
            pn = nn;
            nn = t;
        }
        set_sector(s, next); /* the sector in force at the interval's end, and its incoming phase */
        int xn = (s->incoming == pn || s->incoming == nn) ? s->incoming : pn;
        if (p->reg == BC_SIXSTEP_IDEAL) {
            build_ideal(pn, nn, xn, i_ref, out->leg_at, &out->i_hold_at);
        } else {
            bc_pair_legs((int)p->chop, pn, nn, chop_leg_of(p, pn, nn, xn, 0.0f), m, out->leg_at);
        }
        out->has_at = 1u;
        out->t_at = t_next;
    }
    for (int j = 0; j < 3; ++j) { /* never pass on a bad duty */
        if (!(out->leg[j].duty >= 0.0f && out->leg[j].duty <= 1.0f)) out->leg[j].duty = 0.0f;
        if (!(out->leg_at[j].duty >= 0.0f && out->leg_at[j].duty <= 1.0f)) out->leg_at[j].duty = 0.0f;
        s->applied[j] = out->leg[j];
        s->applied_at[j] = out->leg_at[j];
    }
    s->applied_t = out->has_at ? out->t_at : -1.0f;
    if (sat) out->flags |= BC_FLAG_SATURATED;
    out->diag[0] = (float)sector;
    out->diag[1] = i_reg;
    out->diag[2] = i_ref;
    out->diag[3] = m;
    out->diag[5] = (float)x;
    out->diag[6] = m < 0.0f ? 3.0f : (float)chop_leg;
    out->diag[7] = fabsf(i[third]);
}

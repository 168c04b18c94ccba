/*
 * sixstep_pi.c - the built-in six-step (bc_sixstep.c with regulation "pi", Hall commutation) rewritten as a user
 * controller: what a firmware's control step looks like when it is run in bldclab (docs/user-controller.md).
 *
 * Hall commutation (at the sample nearest the predicted edge, or at the predicted instant itself through the
 * output's commutation timer, with a timing advance) with the outgoing phase left to freewheel, the current of the
 * incoming phase regulated by a PI
 * on the normalised pair voltage with back-EMF feed-forward, a chopping pattern from bc_pair_legs. It uses the
 * same controller blocks as the built-in (bc_hall, bc_guard, bc_pi, bc_commutation: linked by `bldclab controller
 * build`) and the same float operations in the same order, so its trace is the built-in's bit for bit
 * (tests/test_user_control.py). Build it, and run it beside the built-in:
 *
 *     bldclab controller build examples/user_controller/sixstep_pi.c -o sixstep_pi.so
 *     python examples/user_controller/run_sixstep_pi.py       (builds its own copy and compares)
 */
#include <math.h>
#include <stdint.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_guard.h"
#include "bldc/bc_hall.h"
#include "bldc/bc_math.h"
#include "bldc/bc_pi.h"
#include "bldc/bc_types.h"
#include "bldc/bc_user.h"

/* What the firmware is configured with (in bldclab: set by name from Python or `--param key=value`). */
typedef struct {
    int32_t chop;    /* chopping pattern: BC_CHOP_BIPOLAR, _HIGH, _PWMPWM, _SYNC */
    int32_t delay;   /* samples between computing and applying an output (0 or 1: the runner's delay) */
    int32_t advance; /* 1: commutate at the sample nearest the predicted Hall edge; 0: on the edge seen */
    int32_t emf_ff;  /* 1: back-EMF and 2 R I feed-forward */
    int32_t regen;   /* 1: the unipolar patterns reach negative pair voltages by chopping both legs */
    int32_t ref_torque; /* 0: in->ref is the current amplitude I (A); 1: a torque (N m), I = ref / k_e */
    int32_t timed;   /* 1: commutate at the predicted instant inside the PWM period (a commutation timer) */
    float adv_angle; /* timing advance at any speed, electrical rad */
    float adv_time;  /* timing advance per speed, s (the angle grows by |Omega_e| adv_time); total <= pi/6 */
    int32_t p;       /* pole pairs */
    float ts;        /* sampling period, half the PWM period, s */
    float R;         /* phase resistance with the switch, Ohm */
    float L;         /* phase inductance L - M, H (unused by the law; kept for a firmware's own checks) */
    float k_e;       /* line back-EMF constant 2 k_phi, V s/rad */
    float kp, ki;    /* PI gains of the line current loop, V/A and V/(A s) */
    float i_max;     /* over-current trip and reference limit, A */
    float v_max;     /* largest plausible DC-bus measurement, V */
    float f_tick;    /* Hall capture timer, Hz */
    float omega_min; /* slowest speed the Hall estimate reports, electrical rad/s */
} ss_params;

typedef struct {
    bc_hall_params hall_p;
    bc_hall_state hall;
    bc_pi_params pi_p;
    bc_pi_state pi;
    bc_guard_params guard_p;
    bc_guard_state guard;
    int32_t sector, seen, incoming;
} ss_state;

#define PI3_F (BC_PI_F / 3.0f)
#define PI6_F (BC_PI_F / 6.0f)

static int fin(float v) { return isfinite(v) ? 1 : 0; }

static int ss_init(const ss_params *p, ss_state *s)
{
    if (p->chop < BC_CHOP_BIPOLAR || p->chop > BC_CHOP_SYNC || (p->delay != 0 && p->delay != 1) ||
        (p->advance != 0 && p->advance != 1) || (p->emf_ff != 0 && p->emf_ff != 1) ||
        (p->regen != 0 && p->regen != 1) || (p->ref_torque != 0 && p->ref_torque != 1) || (p->timed != 0 && p->timed != 1) || p->p < 1)
        return BC_ERR_PARAM;
    if (!fin(p->adv_angle) || !fin(p->adv_time) || p->adv_angle < 0.0f || p->adv_time < 0.0f)
        return BC_ERR_PARAM;
    if (!(p->ts > 0.0f) || !(p->R >= 0.0f) || !(p->L > 0.0f) || !(p->k_e > 0.0f) || !(p->kp >= 0.0f) ||
        !(p->ki >= 0.0f) || !(p->i_max > 0.0f) || !(p->v_max > 0.0f) || !fin(p->ts) || !fin(p->R) || !fin(p->kp) ||
        !fin(p->ki) || !fin(p->i_max) || !fin(p->v_max))
        return BC_ERR_PARAM;
    s->hall_p = (bc_hall_params){.f_tick = p->f_tick, .omega_min = p->omega_min, .theta_offset = 0.0f,
                                 .mode = BC_HALL_INTERP, .pll_edges = 3.0f};
    if (bc_hall_init(&s->hall_p, &s->hall) != BC_OK) return BC_ERR_PARAM;
    s->pi_p = (bc_pi_params){.kp = p->kp, .ki = p->ki, .ts = p->ts, .u_min = -1.0f, .u_max = 1.0f};
    if (bc_pi_init(&s->pi_p, &s->pi) != BC_OK) return BC_ERR_PARAM;
    s->guard_p = (bc_guard_params){.i_max = p->i_max, .v_max = p->v_max};
    if (bc_guard_init(&s->guard_p, &s->guard) != BC_OK) return BC_ERR_PARAM;
    s->sector = s->seen = s->incoming = -1;
    return BC_OK;
}

/* The timing advance at electrical speed w (rad/s): adv_angle + w adv_time, at most pi/6. */
static float timing_advance(const ss_params *p, float w)
{
    float a = p->adv_angle + w * p->adv_time;
    return fin(a) ? bc_clampf(a, 0.0f, PI6_F) : 0.0f;
}

/* Ideal 120-degree trapezoid of unit flat top rising at th = 0: the back-EMF shape the feed-forward assumes. */
static float trapezoid(float th)
{
    if (!fin(th) || fabsf(th) > 64.0f) return 0.0f;
    while (th < 0.0f) th += BC_TWO_PI_F;
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

static void safe(ss_state *s, bc_ctrl_out *out, uint32_t why)
{
    bc_legs_off(out);
    out->flags |= why | BC_FLAG_SAFE;
    out->diag[0] = -1.0f;
    out->diag[5] = -1.0f;
    out->diag[6] = -1.0f;
    bc_pi_reset(&s->pi_p, &s->pi, 0.0f);
    s->sector = s->seen = s->incoming = -1;
}

/* The chopping leg (3: both): PWM-on-PWM chops the incoming phase x in the first half of the sector, the other one
 * in the second. */
static int chop_leg_of(const ss_params *p, int pos, int neg, int x, float travel)
{
    if (p->chop == BC_CHOP_PWMPWM) return (travel < 0.0f || travel < PI6_F) ? x : (x == pos ? neg : pos);
    if (p->chop == BC_CHOP_BIPOLAR) return 3;
    return pos;
}

/* A new sector records the phase that entered the conducting pair. */
static void set_sector(ss_state *s, int sector)
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

static void ss_step(const ss_params *p, ss_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_hall_out h;
    bc_hall_step(&s->hall_p, &s->hall, in, &h);
    out->diag[4] = h.omega_e;

    float i[3];
    uint32_t why = bc_guard_step(&s->guard_p, &s->guard, in, i); /* bad measurements, over-current, trip pin */
    float v = in->v_dc;
    if (!h.valid) why |= BC_FLAG_HALL_INVALID;
    if (!fin(in->ref)) why |= BC_FLAG_BAD_INPUT;
    if (why) {
        safe(s, out, why);
        return;
    }

    /* commutation: the sector seen, or the next one when its (advanced) boundary is due by the middle of the
     * output's interval; timed: the sector at the interval's start, and the next one at its instant */
    float ts = p->ts;
    float lead = ((float)p->delay + (p->timed ? 0.0f : 0.5f)) * ts;
    float travel;
    float w_c = fabsf(h.omega_e);
    float adv = h.speed_valid ? timing_advance(p, w_c) : 0.0f;
    int sector = bc_hall_commutate(&s->hall_p, &h, in, lead, p->advance || p->timed, adv, s->sector, &s->seen,
                                   &travel);
    if (!h.speed_valid) w_c = 0.0f;
    set_sector(s, sector);
    int next = -1; /* the next commutation inside the interval (timed): sector and instant */
    float t_next = 0.0f;
    if (p->timed && travel >= 0.0f && w_c > 0.0f && h.dir != 0) {
        float dt = (PI3_F - travel) / w_c;
        if (fin(dt) && dt < ts) {
            next = (sector + (h.dir > 0 ? 1 : 5)) % 6;
            t_next = bc_clampf(dt, 0.0f, ts);
        }
    }
    int pos, neg;
    (void)bc_sector_phases(sector, &pos, &neg);
    float ref = in->ref; /* current amplitude (A) or torque (N m); negative: reverse torque */
    if (ref < 0.0f) {
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
    i_ref = bc_clampf(i_ref, 0.0f, p->i_max);
    int chop_leg = chop_leg_of(p, pos, neg, x, travel);

    /* back-EMF over the interval the output applies to */
    float w_m = h.omega_e / (float)p->p;
    float e1[3];
    for (int j = 0; j < 3; ++j) {
        float th = h.theta - (float)j * (BC_TWO_PI_F / 3.0f);
        e1[j] = 0.5f * p->k_e * w_m * trapezoid(th + h.omega_e * lead);
    }

    /* PI on the normalised pair voltage m = u / V_dc, back-calculation anti-windup (bc_pi.h) */
    float m_lo = (p->chop == BC_CHOP_BIPOLAR || p->regen) ? -1.0f : 0.0f;
    float err = i_ref - i_reg;
    float ff = p->emf_ff ? (e1[pos] - e1[neg] + 2.0f * p->R * i_ref) / v : 0.0f;
    float mu = bc_pi_output(&s->pi_p, &s->pi, err / v, ff);
    float m = bc_clampf(fin(mu) ? mu : 0.0f, m_lo, 1.0f);
    int sat = !(m == mu);
    bc_pi_update(&s->pi_p, &s->pi, err / v, mu, m);
    m = fin(m) ? bc_clampf(m, m_lo, 1.0f) : 0.0f;

    bc_pair_legs((int)p->chop, pos, neg, chop_leg, m, out->leg);
    if (next >= 0) { /* the commutation timer: the next sector's legs from t_next, the same pair voltage */
        int pn, nn;
        (void)bc_sector_phases(next, &pn, &nn);
        if (ref < 0.0f) {
            int t = pn;
            pn = nn;
            nn = t;
        }
        set_sector(s, next);
        int xn = (s->incoming == pn || s->incoming == nn) ? s->incoming : pn;
        bc_pair_legs((int)p->chop, pn, nn, chop_leg_of(p, pn, nn, xn, 0.0f), m, out->leg_at);
        out->has_at = 1u;
        out->t_at = t_next;
    }
    for (int j = 0; j < 3; ++j) {
        if (!(out->leg[j].duty >= 0.0f && out->leg[j].duty <= 1.0f)) out->leg[j].duty = 0.0f;
        if (!(out->leg_at[j].duty >= 0.0f && out->leg_at[j].duty <= 1.0f)) out->leg_at[j].duty = 0.0f;
    }
    if (sat) out->flags |= BC_FLAG_SATURATED;
    out->diag[0] = (float)sector;
    out->diag[1] = i_reg;
    out->diag[2] = i_ref;
    out->diag[3] = m;
    out->diag[5] = (float)x;
    out->diag[6] = m < 0.0f ? 3.0f : (float)chop_leg;
    out->diag[7] = fabsf(i[third]);
}

/* The description: every member of ss_params by name, the diagnostics, what in->ref means. */
static const bc_field_desc SS_FIELDS[] = {
    BC_BIND_FIELD(ss_params, chop, "i4"),   BC_BIND_FIELD(ss_params, delay, "i4"),
    BC_BIND_FIELD(ss_params, advance, "i4"), BC_BIND_FIELD(ss_params, emf_ff, "i4"),
    BC_BIND_FIELD(ss_params, regen, "i4"),  BC_BIND_FIELD(ss_params, ref_torque, "i4"),
    BC_BIND_FIELD(ss_params, timed, "i4"),  BC_BIND_FIELD(ss_params, adv_angle, "f4"),
    BC_BIND_FIELD(ss_params, adv_time, "f4"), BC_BIND_FIELD(ss_params, p, "i4"),
    BC_BIND_FIELD(ss_params, ts, "f4"),     BC_BIND_FIELD(ss_params, R, "f4"),
    BC_BIND_FIELD(ss_params, L, "f4"),      BC_BIND_FIELD(ss_params, k_e, "f4"),
    BC_BIND_FIELD(ss_params, kp, "f4"),     BC_BIND_FIELD(ss_params, ki, "f4"),
    BC_BIND_FIELD(ss_params, i_max, "f4"),  BC_BIND_FIELD(ss_params, v_max, "f4"),
    BC_BIND_FIELD(ss_params, f_tick, "f4"), BC_BIND_FIELD(ss_params, omega_min, "f4"),
};

static const bc_user_desc SS = {
    .name = "sixstep_pi",
    .fields = SS_FIELDS,
    .n_fields = BC_USER_COUNT(SS_FIELDS),
    .diag = {"sector", "i_reg A", "i_ref A", "duty", "omega_e rad/s", "incoming", "chop_leg", "i_out A"},
    .ref = "current amplitude, A (ref_torque = 1: torque, N m)",
};

BC_USER_CONTROLLER(SS, ss_params, ss_state, ss_init, ss_step);

/* test_sine.c - bc_transform (Clarke, Park, min-max SVM) and bc_sine: parameter validation, limits, hand-off,
 * safe states, random and extreme inputs, and the closed loop with the htm-48v fixture (imposed speed, and a start
 * from standstill through the square-wave hand-off). */
#include <math.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_commutation.h"
#include "bldc/bc_sim.h"
#include "bldc/bc_sine.h"
#include "bldc/bc_transform.h"
#include "fixtures.h"

#define EMF_N 360
static float emf_tab[3][EMF_N];

static const double K_PHI = 0.32;
static const double I_N = 50.0;
static const double OMEGA_N = 640.0 * 2.0 * BC_PI / 60.0; /* Table II, rad/s */

static double k1_trap(void) { return 12.0 / (BC_PI * BC_PI) * K_PHI; } /* paper 1 (10) */
static double i_sn(void) { return 2.0 / sqrt(3.0) * I_N; }            /* paper 1 (8) */

/* 32-bit LCG for reproducible random inputs */
static uint32_t rng = 12345u;
static uint32_t rnd_u32(void)
{
    rng = rng * 1664525u + 1013904223u;
    return rng;
}
static double rnd(void) { return (double)(rnd_u32() >> 8) / 16777216.0; } /* [0, 1) */

/* The htm-48v controller as bldclab.Sine fills it (PI gains of pi_gains(0.05, 75e-6, 1 kHz, 90 deg)). */
static void sine_params(bc_sine_params *p, const fixture *f)
{
    memset(p, 0, sizeof *p);
    for (int x = 0; x < 3; ++x) {
        for (int j = 0; j < EMF_N; ++j) {
            emf_tab[x][j] = (float)bc_emf_eval(&f->p.emf[x], 2.0 * BC_PI * j / EMF_N);
        }
        p->emf_k[x] = emf_tab[x];
    }
    double wc = 2.0 * BC_PI * 1000.0;
    p->p = 8;
    p->R = (float)f->p.R;
    p->L = 75e-6f;
    p->k_phi = (float)K_PHI;
    p->k_1 = (float)k1_trap();
    p->ts = (float)bc_plant_t_half(&f->p);
    p->kp = (float)(wc * 75e-6);
    p->ki = (float)(wc * 0.05);
    p->v_max = 96.0f;
    p->i_s_max = (float)i_sn();
    p->i_max = 100.0f;
    p->speed_limit = 1;
    p->decouple = 1;
    p->advance = 1.5f;
    p->limit = BC_SINE_LIMIT_HEX;
    p->emf_ff = 1;
    p->emf_n = EMF_N;
    p->angle = BC_SINE_ANGLE_HALL;
    p->f_tick = (float)f->sp.f_tick;
    p->omega_on = (float)(8.0 * 0.1 * OMEGA_N);
    p->omega_off = 0.8f * p->omega_on;
    p->omega_min = 0.25f * p->omega_off;
    bc_sixstep_params *q = &p->six;
    q->reg = BC_SIXSTEP_PRED; /* bldclab.SixStep's defaults */
    q->chop = BC_SIXSTEP_PWMPWM;
    q->ref_torque = 1;
    q->delay = 1;
    q->advance = 1;
    q->emf_ff = 1;
    q->regen = 1;
    q->p = 8;
    q->ts = p->ts;
    q->R = p->R;
    q->L = p->L;
    q->k_e = (float)(2.0 * K_PHI);
    q->kp = (float)(wc * 150e-6);
    q->ki = (float)(wc * 0.1);
    q->band = 5.0f;
    q->i_max = 100.0f;
    q->v_max = 96.0f;
    q->f_tick = p->f_tick;
    q->omega_min = 0.05f * p->omega_on;
}

static void sine_slot(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sine_step(p, s, in, out); }

/* the resistance estimate (bc_rest.h) for htm-48v at 14 kHz: +-5 A on d, 10 ms half periods, half of each skipped */
static bc_rest_params rest_params(void)
{
    bc_rest_params r;
    memset(&r, 0, sizeof r);
    r.i_inj = 5.0f;
    r.n_half = 280;
    r.n_skip = 140;
    r.r_lo = 0.025f;
    r.r_hi = 0.15f;
    r.a = 0.05f;
    r.r_ref = 0.05f;
    r.T_ref = 25.0f;
    return r;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* a synthetic rotor at constant electrical speed we (rad/s) from theta0, carrying i_x = I sin(theta - x 2pi/3 + phi) */

typedef struct {
    double theta0, we, I, phi, f_tick;
} rotor;

static void rotor_in(const rotor *r, double t, float tau_ref, bc_ctrl_in *in)
{
    memset(in, 0, sizeof *in);
    double th = r->theta0 + r->we * t;
    double m0 = floor((r->theta0 - BC_PI / 6.0) / (BC_PI / 3.0));
    double m = floor((th - BC_PI / 6.0) / (BC_PI / 3.0));
    int sector = (int)(m - 6.0 * floor(m / 6.0));
    in->hall = bc_sector_code(sector);
    in->n_edges = (uint32_t)(m - m0);
    if (m > m0) {
        double te = (BC_PI / 6.0 + m * BC_PI / 3.0 - r->theta0) / r->we;
        in->tick_edge = (uint32_t)(te * r->f_tick);
    }
    in->tick_now = (uint32_t)(t * r->f_tick);
    for (int x = 0; x < 3; ++x) in->i_abc[x] = (float)(r->I * sin(th - x * 2.0 * BC_PI / 3.0 + r->phi));
    in->i_mask = 3u;
    in->v_dc = 48.0f;
    in->theta_enc = (float)fmod(th, 2.0 * BC_PI);
    in->omega_enc = (float)(r->we / 8.0);
    in->ref = tau_ref;
}

/* ---------------------------------------------------------------------------------------------------------- */

static void test_transforms(void)
{
    bc_ab ab = bc_clarke((bc_abc){1.0f, -0.5f, -0.5f});
    CHECK_NEAR(ab.alpha, 1.0, 1e-6, "Clarke alpha of (1, -1/2, -1/2)");
    CHECK_NEAR(ab.beta, 0.0, 1e-6, "Clarke beta of (1, -1/2, -1/2)");
    ab = bc_clarke((bc_abc){0.0f, 1.0f, -1.0f});
    CHECK_NEAR(ab.beta, 2.0 / sqrt(3.0), 1e-6, "Clarke beta of (0, 1, -1)");
    ab = bc_clarke((bc_abc){3.0f, 3.0f, 3.0f});
    CHECK(fabsf(ab.alpha) < 1e-6f && fabsf(ab.beta) < 1e-6f, "zero sequence dropped");
    for (int k = 0; k < 72; ++k) {
        float th = (float)k * (BC_TWO_PI_F / 72.0f);
        float I = 57.7f;
        bc_abc i = {I * sinf(th), I * sinf(th - BC_TWO_PI_F / 3.0f), I * sinf(th - 2.0f * BC_TWO_PI_F / 3.0f)};
        bc_ab a = bc_clarke(i);
        CHECK(fabsf(a.alpha - I * sinf(th)) < 1e-4f && fabsf(a.beta + I * cosf(th)) < 1e-4f,
              "alpha = I sin, beta = -I cos at %g", (double)th);
        float thd = bc_theta_d(th);
        bc_dq dq = bc_park(a, sinf(thd), cosf(thd));
        CHECK(fabsf(dq.q - I) < 1e-4f * I && fabsf(dq.d) < 1e-4f * I, "q along the back-EMF: i_q = I, i_d = 0 at %g: "
              "(%g, %g)", (double)th, (double)dq.d, (double)dq.q);
        /* d is the PM flux axis, 90 degrees behind q: a current set leading i_q by 90 degrees lies on -d */
        bc_abc i2 = {I * cosf(th), I * cosf(th - BC_TWO_PI_F / 3.0f), I * cosf(th - 2.0f * BC_TWO_PI_F / 3.0f)};
        bc_dq dq2 = bc_park(bc_clarke(i2), sinf(thd), cosf(thd));
        CHECK(fabsf(dq2.d + I) < 1e-4f * I && fabsf(dq2.q) < 1e-4f * I, "90 degrees ahead of q is -d at %g",
              (double)th);
        bc_abc back = bc_clarke_inv(bc_park_inv(dq, sinf(thd), cosf(thd)));
        CHECK(fabsf(back.a - i.a) < 1e-3f && fabsf(back.b - i.b) < 1e-3f && fabsf(back.c - i.c) < 1e-3f,
              "round trip abc -> dq -> abc");
    }
    CHECK_NEAR(bc_wrap_2pi(-0.5f), 2.0 * BC_PI - 0.5, 1e-5, "wrap negative");
    CHECK(bc_wrap_2pi(NAN) == 0.0f && bc_wrap_2pi(INFINITY) == 0.0f, "wrap non-finite");
    {
        /* the fast path (within a turn of the range) gives fmodf's result: every 31st float in [-20, 20], and
         * large angles */
        long differ = 0;
        for (float x = -20.0f; x <= 20.0f;) {
            float ref = fmodf(x, BC_TWO_PI_F);
            if (ref < 0.0f) ref += BC_TWO_PI_F;
            if (ref >= BC_TWO_PI_F) ref = 0.0f;
            float got = bc_wrap_2pi(x);
            differ += !(got == ref && got >= 0.0f && got < BC_TWO_PI_F);
            for (int j = 0; j < 31; ++j) x = nextafterf(x, 100.0f);
        }
        CHECK(differ == 0, "wrap equals fmodf's reference: %ld differ", differ);
        CHECK(bc_wrap_2pi(1e6f) == fmodf(1e6f, BC_TWO_PI_F) && bc_wrap_2pi(-1e6f) == fmodf(-1e6f, BC_TWO_PI_F) +
              BC_TWO_PI_F, "wrap large angles");
    }
    CHECK_NEAR(bc_theta_d(0.25f), 0.25 + BC_PI, 1e-5, "theta_d = theta - pi, wrapped");
}

static void test_svm(void)
{
    float d[3];
    /* linear range: the half-period averages of the line voltages equal the references' differences */
    int worst_lin = 0;
    double worst = 0.0;
    for (int k = 0; k < 20000; ++k) {
        float vdc = (float)(1.0 + 100.0 * rnd());
        bc_abc v = {(float)((rnd() - 0.5) * 2.0 * (double)vdc), (float)((rnd() - 0.5) * 2.0 * (double)vdc),
                    (float)((rnd() - 0.5) * 2.0 * (double)vdc)};
        float hi = fmaxf(v.a, fmaxf(v.b, v.c)), lo = fminf(v.a, fminf(v.b, v.c));
        int r = bc_svm(v, vdc, d);
        for (int x = 0; x < 3; ++x) CHECK(d[x] >= 0.0f && d[x] <= 1.0f, "duty in [0, 1]");
        if (hi - lo <= 0.999f * vdc) {
            worst_lin |= r;
            double e1 = fabs((double)((d[0] - d[1]) * vdc) - (double)(v.a - v.b));
            double e2 = fabs((double)((d[1] - d[2]) * vdc) - (double)(v.b - v.c));
            worst = fmax(worst, fmax(e1, e2) / (double)vdc);
            CHECK_NEAR(0.5f * (fmaxf(d[0], fmaxf(d[1], d[2])) + fminf(d[0], fminf(d[1], d[2]))), 0.5, 1e-6,
                       "min-max: centred between the rails");
        } else if (hi - lo > 1.001f * vdc) {
            CHECK(r == BC_SVM_CLIPPED, "outside the hexagon: clipped");
        }
    }
    CHECK(worst_lin == BC_SVM_LINEAR, "inside the hexagon: linear");
    CHECK(worst < 1e-6, "line voltages averaged = references: worst error %.3g of V_dc", worst);
    /* a balanced sine of peak V_dc / sqrt(3) is the largest that stays linear */
    int clipped_at = 0, clipped_over = 0;
    for (int k = 0; k < 360; ++k) {
        float th = (float)k * (BC_TWO_PI_F / 360.0f);
        float a = 48.0f / BC_SQRT3_F;
        bc_abc v = {a * sinf(th), a * sinf(th - BC_TWO_PI_F / 3.0f), a * sinf(th + BC_TWO_PI_F / 3.0f)};
        clipped_at |= bc_svm(v, 48.0f, d);
        bc_abc w = {1.02f * v.a, 1.02f * v.b, 1.02f * v.c};
        clipped_over |= bc_svm(w, 48.0f, d);
    }
    CHECK(clipped_at == BC_SVM_LINEAR && clipped_over == BC_SVM_CLIPPED, "sine limit V_dc/sqrt(3)");
    CHECK(bc_svm((bc_abc){NAN, 0.0f, 0.0f}, 48.0f, d) == BC_SVM_CLIPPED && d[0] == 0.5f && d[1] == 0.5f,
          "NaN reference: duties 1/2");
    CHECK(bc_svm((bc_abc){1.0f, 0.0f, 0.0f}, 0.0f, d) == BC_SVM_CLIPPED && d[2] == 0.5f, "v_dc = 0: duties 1/2");
    bc_svm((bc_abc){3e38f, -3e38f, 0.0f}, 48.0f, d);
    for (int x = 0; x < 3; ++x) CHECK(isfinite(d[x]) && d[x] >= 0.0f && d[x] <= 1.0f, "huge references");
}

static void test_params(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_sine_params p, q;
    static bc_sine_state s;
    sine_params(&p, &f);
    CHECK(bc_sine_init(&p, &s) == BC_OK, "htm parameters accepted");
    CHECK(s.mode == BC_SINE_MODE_START && s.guard.latched == 0, "starts in the square-wave mode");
    memset(&q, 0, sizeof q);
    CHECK(bc_sine_init(&q, &s) == BC_ERR_PARAM, "zeroed parameters rejected");
    CHECK(bc_sine_init(0, &s) == BC_ERR_PARAM && bc_sine_init(&p, 0) == BC_ERR_PARAM, "NULL rejected");
#define BAD(stmt, what)                                                    \
    do {                                                                   \
        q = p;                                                             \
        stmt;                                                              \
        CHECK(bc_sine_init(&q, &s) == BC_ERR_PARAM, "rejected: %s", what); \
    } while (0)
    BAD(q.p = 0, "p = 0");
    BAD(q.L = 0.0f, "L = 0");
    BAD(q.R = -1.0f, "R < 0");
    BAD(q.k_1 = NAN, "k_1 NaN");
    BAD(q.k_phi = 0.0f, "k_phi = 0");
    BAD(q.ts = 0.0f, "ts = 0");
    BAD(q.kp = -1.0f, "kp < 0");
    BAD(q.ki = INFINITY, "ki inf");
    BAD(q.i_s_max = 0.0f, "i_s_max = 0");
    BAD(q.i_max = NAN, "i_max NaN");
    BAD(q.i_s_max = 1.01f * q.i_max, "i_s_max > i_max (the trip would cut the limit off)");
    BAD((q.rest = rest_params(), q.rest.i_inj = 2.0f * q.i_s_max), "rest.i_inj > i_s_max");
    BAD((q.rest = rest_params(), q.rest.n_half = 1), "rest.n_half = 1");
    BAD(q.v_max = 0.0f, "v_max = 0");
    BAD(q.decouple = 2, "decouple = 2");
    BAD(q.advance = 5.0f, "advance = 5");
    BAD(q.limit = 2, "limit = 2");
    BAD(q.angle = -1, "angle = -1");
    BAD(q.emf_n = 2, "emf_n = 2");
    BAD(q.emf_k[1] = 0, "emf table NULL");
    BAD(q.omega_off = 2.0f * q.omega_on, "omega_off > omega_on");
    BAD(q.omega_on = 0.0f, "omega_on = 0");
    BAD(q.f_tick = 0.0f, "f_tick = 0");
    BAD((q.speed_loop = 1, q.tau_max = 0.0f), "speed loop without a torque limit");
    BAD(q.six.ref_torque = 0, "start controller not in torque mode");
    BAD(q.six.L = 0.0f, "start controller parameters");
#undef BAD
    q = p;
    q.emf_ff = 0;
    q.emf_k[0] = 0;
    CHECK(bc_sine_init(&q, &s) == BC_OK, "no tables needed without feed-forward");
    emf_tab[2][7] = NAN;
    CHECK(bc_sine_init(&p, &s) == BC_ERR_PARAM, "non-finite table value rejected");
    sine_params(&p, &f);
}

static void test_safe_states(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_sine_params p;
    static bc_sine_state s;
    sine_params(&p, &f);
    rotor r = {0.3, 8.0 * 0.5 * 75.0, 0.0, 0.0, f.sp.f_tick};
    bc_ctrl_in in;
    bc_ctrl_out out;
    const uint32_t SAFE_HALL = BC_FLAG_SAFE | BC_FLAG_HALL_INVALID, SAFE_BAD = BC_FLAG_SAFE | BC_FLAG_BAD_INPUT;
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    for (uint32_t code = 0u; code < 8u; code += 7u) {
        rotor_in(&r, 0.0, 10.0f, &in);
        in.hall = code;
        bc_sine_step(&p, &s, &in, &out);
        CHECK(out.flags == SAFE_HALL, "Hall code %u: flags 0x%x", code, out.flags);
        for (int x = 0; x < 3; ++x) CHECK(out.leg[x].mode == BC_LEG_OFF && out.leg[x].duty == 0.0f, "legs off");
    }
    const char *what[] = {"NaN current", "inf current", "v_dc = 0", "v_dc < 0", "v_dc NaN", "ref NaN", "one phase"};
    for (int k = 0; k < 7; ++k) {
        rotor_in(&r, 1e-3, 10.0f, &in);
        if (k == 0) in.i_abc[0] = NAN;
        if (k == 1) in.i_abc[1] = -INFINITY;
        if (k == 2) in.v_dc = 0.0f;
        if (k == 3) in.v_dc = -48.0f;
        if (k == 4) in.v_dc = NAN;
        if (k == 5) in.ref = NAN;
        if (k == 6) in.i_mask = 4u;
        bc_sine_step(&p, &s, &in, &out);
        CHECK(out.flags == SAFE_BAD, "%s: flags 0x%x", what[k], out.flags);
        for (int x = 0; x < 3; ++x) CHECK(out.leg[x].mode == BC_LEG_OFF, "%s: legs off", what[k]);
    }
    /* an unmeasured phase may hold anything */
    rotor_in(&r, 1e-3, 10.0f, &in);
    in.i_abc[2] = NAN;
    bc_sine_step(&p, &s, &in, &out);
    CHECK(!(out.flags & BC_FLAG_SAFE), "unmeasured phase ignored: flags 0x%x", out.flags);
    /* encoder angle: a NaN encoder is bad input only when it is used */
    bc_sine_params pe = p;
    pe.angle = BC_SINE_ANGLE_ENCODER;
    CHECK(bc_sine_init(&pe, &s) == BC_OK, "init encoder");
    in.theta_enc = NAN;
    bc_sine_step(&pe, &s, &in, &out);
    CHECK(out.flags == SAFE_BAD, "NaN encoder angle");
    /* over-current on the derived phase c, latched until every |i| < i_max / 2 (bc_guard.h) */
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    rotor_in(&r, 1e-3, 10.0f, &in);
    in.i_abc[0] = 60.0f;
    in.i_abc[1] = 60.0f; /* i_c = -120 A */
    bc_sine_step(&p, &s, &in, &out);
    CHECK(out.flags == (BC_FLAG_SAFE | BC_FLAG_OVERCURRENT), "over-current on the derived phase: 0x%x", out.flags);
    rotor_in(&r, 2e-3, 10.0f, &in);
    in.i_abc[0] = 60.0f;
    in.i_abc[1] = -60.0f; /* below i_max = 100 A, above i_max / 2 */
    bc_sine_step(&p, &s, &in, &out);
    CHECK(out.flags == (BC_FLAG_SAFE | BC_FLAG_OVERCURRENT) && out.leg[0].mode == BC_LEG_OFF, "trip latched");
    rotor_in(&r, 3e-3, 10.0f, &in);
    in.v_dc = NAN; /* invalid measurements neither re-arm nor clear */
    in.i_abc[0] = 1.0f;
    in.i_abc[1] = -1.0f;
    bc_sine_step(&p, &s, &in, &out);
    CHECK(out.flags == SAFE_BAD && s.guard.latched == 1, "bad input keeps the latch: 0x%x", out.flags);
    rotor_in(&r, 4e-3, 10.0f, &in);
    in.i_abc[0] = 49.0f;
    in.i_abc[1] = -49.0f;
    bc_sine_step(&p, &s, &in, &out);
    CHECK(!(out.flags & BC_FLAG_SAFE) && s.guard.latched == 0, "re-armed below i_max / 2: 0x%x", out.flags);
    CHECK(bc_sine_init(&p, &s) == BC_OK && s.guard.latched == 0, "init clears the trip");
    /* the DC bus above v_max is bad input (bc_guard.h) */
    rotor_in(&r, 5e-3, 10.0f, &in);
    in.v_dc = 97.0f;
    bc_sine_step(&p, &s, &in, &out);
    CHECK(out.flags == SAFE_BAD, "v_dc > v_max: 0x%x", out.flags);
}

/* Random and extreme inputs, every option: the output is always finite, duties in [0, 1], modes valid. */
static void test_fuzz(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_sine_params base;
    sine_params(&base, &f);
    static const float special[] = {NAN, INFINITY, -INFINITY, 3e38f, -3e38f, 1e-38f, -1e-38f, 0.0f, 1e6f, -1e6f};
    int bad_out = 0, n_sine = 0, n_rearm = 0;
    for (int variant = 0; variant < 8; ++variant) {
        bc_sine_params p = base;
        p.angle = variant & 1;
        p.limit = (variant >> 1) & 1;
        p.overmod = (variant >> 2) & 1;
        p.speed_loop = variant == 3 || variant == 6;
        p.tau_max = 40.0f;
        p.emf_ff = variant != 5;
        p.omega_on = (variant & 1) ? 1.0f : p.omega_on; /* reach the sine mode easily */
        p.omega_off = (variant & 1) ? 0.5f : p.omega_off;
        p.omega_min = (variant & 1) ? 0.1f : p.omega_min;
        if (variant % 3 == 0) p.rest = rest_params(); /* the resistance estimate's injection in the sine mode */
        if (variant == 3) p.rest.n_half = 3, p.rest.n_skip = 1;
        static bc_sine_state s;
        CHECK(bc_sine_init(&p, &s) == BC_OK, "init variant %d", variant);
        uint32_t tick = 0u, edges = 0u, hall_code = 1u, tick_edge = 0u;
        for (int k = 0; k < 30000; ++k) {
            bc_ctrl_in in;
            memset(&in, 0, sizeof in);
            int wild = (rnd_u32() % 64u) == 0u;
            for (int x = 0; x < 3; ++x) {
                in.i_abc[x] = wild ? special[rnd_u32() % 10u] : (float)((rnd() - 0.5) * 160.0);
            }
            in.i_mask = wild ? rnd_u32() : 3u;
            in.v_dc = wild ? special[rnd_u32() % 10u] : (float)(1.0 + 100.0 * rnd());
            tick += (uint32_t)(rnd_u32() % 2000u);
            if (rnd_u32() % 16u == 0u) { /* a Hall edge, mostly forward */
                int sec = bc_hall_sector(hall_code);
                hall_code = bc_sector_code((sec + ((rnd_u32() % 4u) == 0u ? 5 : 1)) % 6);
                edges += 1u;
                tick_edge = tick;
            }
            in.hall = wild ? (rnd_u32() % 9u) : hall_code;
            in.n_edges = wild ? rnd_u32() : edges;
            in.tick_edge = wild ? rnd_u32() : tick_edge;
            in.tick_now = tick;
            in.theta_enc = wild ? special[rnd_u32() % 10u] : (float)(rnd() * 7.0);
            in.omega_enc = (float)(rnd() * 100.0);
            in.ref = wild ? special[rnd_u32() % 10u] : (float)((rnd() - 0.5) * 200.0);
            in.omega_ref = wild ? special[rnd_u32() % 10u] : (float)((rnd() - 0.5) * 200.0);
            bc_ctrl_out out;
            bc_sine_step(&p, &s, &in, &out);
            for (int x = 0; x < 3; ++x) {
                if (!(out.leg[x].duty >= 0.0f && out.leg[x].duty <= 1.0f) || out.leg[x].mode < BC_LEG_OFF ||
                    out.leg[x].mode > BC_LEG_LOW)
                    bad_out += 1;
            }
            for (int j = 0; j < BC_DIAG_N; ++j) bad_out += !isfinite(out.diag[j]);
            n_sine += s.mode == BC_SINE_MODE_SINE;
            if (s.guard.latched) {
                /* re-arm the over-current trip with one valid sample, currents 0 (bc_guard.h), rather than
                 * re-initialising: the test stays in bc_sine_step (bc_sine_init tabulates the speed limit, tens of
                 * microseconds), and the re-arm path is exercised too */
                bc_ctrl_in in0 = in;
                for (int x = 0; x < 3; ++x) in0.i_abc[x] = 0.0f;
                in0.i_mask = 3u;
                in0.v_dc = 48.0f;
                in0.hall = hall_code;
                in0.n_edges = edges;
                in0.tick_edge = tick_edge;
                in0.theta_enc = 1.0f;
                in0.ref = 10.0f;
                in0.omega_ref = 10.0f;
                bc_sine_step(&p, &s, &in0, &out);
                n_rearm += 1;
                CHECK(!s.guard.latched, "variant %d: re-armed by a valid sample", variant);
            }
        }
    }
    CHECK(bad_out == 0, "every output finite, duties in [0, 1]: %d bad", bad_out);
    CHECK(n_sine > 1000, "the sine mode was exercised: %d samples", n_sine);
    CHECK(n_rearm > 100, "the over-current trip was re-armed %d times", n_rearm);
}

/* The sensorless mode (both observers, with and without the speed loop) under random and non-finite inputs: the
 * outputs stay finite and the duties in [0, 1] in every phase of the I/f start (its load-adaptive ramp and the swing
 * damping read the observer, whatever it estimates); the parameters of the start are validated. */
static void observer_params(bc_sine_params *p, int32_t observer)
{
    const bc_fluxobs_params f = {.R = 0.05f, .L = 75e-6f, .psi = 0.0486f, .ts = p->ts, .gain = 107.2f,
                                 .pll_bw = 556.0f, .i_max = 100.0f, .v_max = 96.0f};
    const bc_redobs_params r = {.R = 0.05f, .L = 75e-6f, .psi = 0.0486f, .ts = p->ts, .alpha_o = 556.0f,
                                .sigma0 = 333.3f, .zeta_inf = 0.2f, .i_max = 100.0f, .v_max = 96.0f};
    p->angle = BC_SINE_ANGLE_OBSERVER;
    p->observer = observer;
    p->fobs = f;
    p->robs = r;
    p->if_current = 28.87f;
    p->if_align_current = 51.96f;
    p->if_align = 0.006f; /* short: the ramp is reached often (the alignment and its closing sweep, 0.0073 s, between
                          * the fuzz's wild inputs) */
    p->if_accel = 278.4f;
    p->if_accel_min = 13.92f;
    p->if_hold = 0.05f;
    p->lock_time = 0.0466f;
    p->lock_tol = 0.2f;
    p->restart_wait = 0.005f;
    p->if_damp = 11.43f;
}

static void test_fuzz_observer(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_sine_params base;
    sine_params(&base, &f);
    static const float special[] = {NAN, INFINITY, -INFINITY, 3e38f, -3e38f, 1e-38f, -1e-38f, 0.0f, 1e6f, -1e6f};
    int bad_out = 0, n_ramp = 0, n_align = 0, n_pulse = 0, n_seed = 0;
    for (int variant = 0; variant < 5; ++variant) {
        bc_sine_params p = base;
        observer_params(&p, (variant & 1) || variant == 4 ? BC_SINE_OBS_REDUCED : BC_SINE_OBS_FLUX);
        p.speed_loop = (variant >> 1) & 1;
        p.tau_max = 40.0f;
        p.if_r_est = variant == 0 || variant == 3; /* the resistance of the alignment, both observers */
        p.if_psi_est = variant != 3;              /* the flux linkage estimate (no effect on the reduced one) */
        p.zc_catch = variant == 1 || variant == 2; /* the zero-current catch */
        p.catch_pulse = variant == 2 || variant == 4; /* the zero-vector pulses (bc_sine.h, PULSE) */
        static bc_sine_state s;
        CHECK(bc_sine_init(&p, &s) == BC_OK, "init observer variant %d", variant);
        float phase = 0.0f;
        for (int k = 0; k < 40000; ++k) {
            bc_ctrl_in in;
            memset(&in, 0, sizeof in);
            int wild = (rnd_u32() % 512u) == 0u;
            /* currents: a turning vector of random amplitude and speed plus noise (the observers then see a
             * motion), sometimes anything */
            phase += (float)(rnd() * 0.3);
            float amp = (float)(rnd() * 60.0);
            for (int x = 0; x < 3; ++x) {
                float v = amp * cosf(phase - (float)x * 2.0943951f) + (float)((rnd() - 0.5) * 10.0);
                in.i_abc[x] = wild ? special[rnd_u32() % 10u] : v;
            }
            in.i_mask = wild ? rnd_u32() : 3u;
            in.v_dc = wild ? special[rnd_u32() % 10u] : (float)(20.0 + 70.0 * rnd()); /* v_max 96 V */
            in.ref = wild ? special[rnd_u32() % 10u] : (float)((rnd() - 0.2) * 40.0);
            in.omega_ref = wild ? special[rnd_u32() % 10u] : (float)((rnd() - 0.2) * 60.0);
            bc_ctrl_out out;
            memset(&out, 0, sizeof out); /* as the runner clears it (has_at = 0) */
            bc_sine_step(&p, &s, &in, &out);
            for (int x = 0; x < 3; ++x) {
                if (!(out.leg[x].duty >= 0.0f && out.leg[x].duty <= 1.0f) || out.leg[x].mode < BC_LEG_OFF ||
                    out.leg[x].mode > BC_LEG_LOW)
                    bad_out += 1;
            }
            if (out.has_at) {
                n_pulse += 1;
                bad_out += !(out.t_at >= 0.0f && out.t_at < p.ts);
                for (int x = 0; x < 3; ++x)
                    bad_out += !(out.leg_at[x].duty >= 0.0f && out.leg_at[x].duty <= 1.0f) ||
                               out.leg_at[x].mode < BC_LEG_OFF || out.leg_at[x].mode > BC_LEG_LOW;
            }
            n_seed += s.fc_seed != 0;
            for (int j = 0; j < BC_DIAG_N; ++j) bad_out += !isfinite(out.diag[j]);
            bad_out += !isfinite(s.if_theta) || !isfinite(s.if_omega) || !isfinite(s.rho_f) || !(s.r_obs >= 0.0f) ||
                       !isfinite(s.r_obs);
            n_ramp += s.mode == BC_SINE_MODE_START && s.sl_phase == BC_SINE_SL_RAMP;
            n_align += s.mode == BC_SINE_MODE_START && s.sl_phase == BC_SINE_SL_ALIGN;
            if (s.guard.latched) {
                bc_ctrl_in in0 = in;
                for (int x = 0; x < 3; ++x) in0.i_abc[x] = 0.0f;
                in0.i_mask = 3u;
                in0.v_dc = 48.0f;
                in0.ref = 10.0f;
                in0.omega_ref = 10.0f;
                bc_sine_step(&p, &s, &in0, &out);
            }
        }
    }
    CHECK(bad_out == 0, "observer mode: every output finite, duties in [0, 1]: %d bad", bad_out);
    CHECK(n_ramp > 1000, "the I/f ramp was exercised: %d samples", n_ramp);
    CHECK(n_align > 1000, "the alignment was exercised: %d samples", n_align);
    CHECK(n_pulse > 100 && n_seed > 0, "the zero-vector pulses were exercised: %d pulses, %d seeded samples", n_pulse,
          n_seed);

    /* the start's parameters: a slowest ramp above the fastest, an alignment current above i_s_max, non-finite */
    static bc_sine_state s;
    bc_sine_params p = base;
    observer_params(&p, BC_SINE_OBS_FLUX);
    CHECK(bc_sine_init(&p, &s) == BC_OK, "valid observer parameters accepted");
    p.if_accel_min = 1.01f * p.if_accel;
    CHECK(bc_sine_init(&p, &s) == BC_ERR_PARAM, "if_accel_min > if_accel rejected");
    p.if_accel_min = p.if_accel; /* a fixed ramp */
    CHECK(bc_sine_init(&p, &s) == BC_OK, "if_accel_min = if_accel accepted");
    p.if_accel_min = 0.0f;
    CHECK(bc_sine_init(&p, &s) == BC_ERR_PARAM, "if_accel_min = 0 rejected");
    p.if_accel_min = NAN;
    CHECK(bc_sine_init(&p, &s) == BC_ERR_PARAM, "if_accel_min NaN rejected");
    observer_params(&p, BC_SINE_OBS_FLUX);
    p.if_align_current = 1.01f * p.i_s_max;
    CHECK(bc_sine_init(&p, &s) == BC_ERR_PARAM, "if_align_current > i_s_max rejected");
    p.if_align_current = 0.0f;
    CHECK(bc_sine_init(&p, &s) == BC_ERR_PARAM, "if_align_current = 0 rejected");
    observer_params(&p, BC_SINE_OBS_FLUX);
    p.if_r_est = 2;
    CHECK(bc_sine_init(&p, &s) == BC_ERR_PARAM, "if_r_est = 2 rejected");
    observer_params(&p, BC_SINE_OBS_FLUX);
    p.if_psi_est = 2;
    CHECK(bc_sine_init(&p, &s) == BC_ERR_PARAM, "if_psi_est = 2 rejected");
}

/* The resistance measured in ALIGN (if_r_est): a locked rotor (no back-EMF), the windings an R-L load integrated
 * exactly over each half period with the voltage of the duties (one sample late, as the PWM applies them); the
 * controller and its observers configured with R 1.5 and 0.5 times the load's. At the ramp's first sample the
 * observer's R is the load's to 0.1 %; without if_r_est it stays the configured one. */
static void test_alignment_resistance(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    const double R = 0.05, L = 75e-6, vdc = 48.0;
    for (int c = 0; c < 3; ++c) {
        bc_sine_params p;
        sine_params(&p, &f);
        observer_params(&p, c == 1 ? BC_SINE_OBS_REDUCED : BC_SINE_OBS_FLUX);
        float rc = (float)(c == 2 ? 0.5 * R : 1.5 * R);
        p.R = p.fobs.R = p.robs.R = rc;
        p.if_align = 0.1f; /* the current settled long before its last quarter */
        p.if_r_est = 1;
        static bc_sine_state s;
        CHECK(bc_sine_init(&p, &s) == BC_OK, "init (case %d)", c);
        double ia = 0.0, ib = 0.0, ua = 0.0, ub = 0.0, ts = (double)p.ts, e = exp(-R * ts / L);
        int k;
        for (k = 0; k < 200000 && !(s.sl_phase == BC_SINE_SL_RAMP); ++k) {
            bc_ctrl_in in;
            memset(&in, 0, sizeof in);
            in.i_abc[0] = (float)ia;
            in.i_abc[1] = (float)(-0.5 * ia + 0.8660254037844386 * ib);
            in.i_abc[2] = (float)(-0.5 * ia - 0.8660254037844386 * ib);
            in.i_mask = 3u;
            in.v_dc = (float)vdc;
            in.ref = 10.0f;
            bc_ctrl_out out;
            bc_sine_step(&p, &s, &in, &out);
            /* the voltage of the previous sample's duties acts over this half period */
            ia = ia * e + (1.0 - e) * ua / R;
            ib = ib * e + (1.0 - e) * ub / R;
            double v[3];
            for (int x = 0; x < 3; ++x) v[x] = out.leg[x].mode == BC_LEG_PWM ? (double)out.leg[x].duty * vdc : 0.0;
            ua = (2.0 * v[0] - v[1] - v[2]) / 3.0;
            ub = (v[1] - v[2]) / 1.7320508075688772;
        }
        CHECK(s.sl_phase == BC_SINE_SL_RAMP, "case %d: the ramp was reached (%d samples)", c, k);
        CHECK(fabs((double)s.r_obs / R - 1.0) < 1e-3, "case %d: the observer's R %.6g Ohm against the load's %.6g", c,
              (double)s.r_obs, R);
        p.if_r_est = 0;
        CHECK(bc_sine_init(&p, &s) == BC_OK, "init without if_r_est (case %d)", c);
        CHECK(s.r_obs == rc, "case %d: without if_r_est the configured R", c);
    }
}

/* Limits of the current reference, linear modulation, and the bumpless hand-off on a synthetic rotor. */
static void test_limits_and_handoff(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_sine_params p;
    static bc_sine_state s;
    sine_params(&p, &f);
    p.emf_ff = 0; /* the hand-off voltage is then the model's exactly (no table ripple on q) */
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    double k1 = k1_trap(), R = 0.05, L = 75e-6, Ts = (double)p.ts;
    double wm = 37.5, we = 8.0 * wm; /* 0.5 Omega_0 */
    rotor r = {0.3, we, i_sn(), 0.0, f.sp.f_tick};
    float tau_n = (float)(1.5 * k1 * i_sn()); /* T_s,N (12) */
    bc_ctrl_in in;
    bc_ctrl_out out;
    int k_switch = -1, n_sat = 0;
    double worst_spread = 0.0, worst_theta = 0.0;
    for (int k = 0; k < 2000; ++k) {
        rotor_in(&r, k * Ts, tau_n, &in);
        int before = s.mode;
        bc_sine_step(&p, &s, &in, &out);
        if (before == BC_SINE_MODE_START && s.mode == BC_SINE_MODE_SINE && k_switch < 0) {
            k_switch = k;
            /* bumpless: the first sine output is the voltage the present state needs (i_d = 0, i_q = I_s,N) */
            CHECK_NEAR(out.diag[4], wm * k1 + R * i_sn(), 0.02, "hand-off v_q = omega_m k_1 + R i_q");
            CHECK_NEAR(out.diag[3], -we * L * i_sn(), 0.02, "hand-off v_d = -omega_e L i_q");
        }
        if (s.mode == BC_SINE_MODE_SINE) {
            double hi = fmax(out.leg[0].duty, fmax(out.leg[1].duty, out.leg[2].duty));
            double lo = fmin(out.leg[0].duty, fmin(out.leg[1].duty, out.leg[2].duty));
            worst_spread = fmax(worst_spread, hi - lo);
            n_sat += (out.flags & BC_FLAG_SATURATED) != 0u;
            double th = fmod(0.3 + we * k * Ts, 2.0 * BC_PI), dth = fabs((double)out.diag[5] - th);
            worst_theta = fmax(worst_theta, fmin(dth, 2.0 * BC_PI - dth));
            CHECK_NEAR(out.diag[2], i_sn(), 1e-3, "i_q,ref = tau / (1.5 k_1) = I_s,N");
            for (int x = 0; x < 3; ++x) CHECK(out.leg[x].mode == BC_LEG_PWM, "complementary legs");
        }
    }
    CHECK(k_switch > 0 && k_switch < 400, "hand-off after two Hall edges: sample %d", k_switch);
    CHECK(n_sat == 0 && worst_spread < 1.0, "linear modulation at half speed: duty spread %.3f", worst_spread);
    CHECK(worst_theta < 1e-3, "Hall-interpolated angle at constant speed: error %.2g rad", worst_theta);

    /* torque reference beyond the rating: |i_q,ref| <= I_s,N (8), both signs */
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        rotor_in(&r, 2000 * Ts, (float)sgn * 1e4f, &in);
        bc_sine_step(&p, &s, &in, &out);
        CHECK_NEAR(out.diag[2], sgn * i_sn(), 1e-3, "|i_q,ref| <= I_s,N");
    }
    /* above the base speed: I_s,sat ((23) with R) */
    for (int lim = 0; lim <= 1; ++lim) {
        p.speed_limit = lim;
        CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
        double w2 = 0.97 * 75.0, we2 = 8.0 * w2;
        rotor r2 = {0.3, we2, 20.0, 0.0, f.sp.f_tick};
        for (int k = 0; k < 400; ++k) {
            rotor_in(&r2, k * Ts, tau_n, &in);
            bc_sine_step(&p, &s, &in, &out);
        }
        double isat = (48.0 - 2.0 * K_PHI * w2) / (sqrt(3.0) / 2.0 * we2 * L + 1.5 * R);
        CHECK(s.mode == BC_SINE_MODE_SINE, "sine mode at 0.97 Omega_0");
        CHECK_NEAR(out.diag[2], lim ? isat : i_sn(), 2e-3 * i_sn(), lim ? "I_s,sat (23) with R" : "limit off");
    }
    /* with R = 0, (23) exactly: I_s,sat = 2/sqrt(3) (V - 2 k_phi Omega) / (p Omega L) */
    p.speed_limit = 1;
    p.R = 0.0f;
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    {
        double w2 = 0.97 * 75.0;
        rotor r2 = {0.3, 8.0 * w2, 20.0, 0.0, f.sp.f_tick};
        for (int k = 0; k < 400; ++k) {
            rotor_in(&r2, k * Ts, tau_n, &in);
            bc_sine_step(&p, &s, &in, &out);
        }
        double i23 = 2.0 / sqrt(3.0) * (48.0 - 2.0 * K_PHI * w2) / (8.0 * w2 * L);
        CHECK_NEAR(out.diag[2], i23, 2e-3 * i23, "paper 1 (23)");
    }
    /* without shape tables: (23) with R as before */
    sine_params(&p, &f);
    p.emf_ff = 0;
    for (int x = 0; x < 3; ++x) p.emf_k[x] = 0;
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    {
        double w2 = 0.97 * 75.0, we2 = 8.0 * w2;
        rotor r2 = {0.3, we2, 20.0, 0.0, f.sp.f_tick};
        for (int k = 0; k < 400; ++k) {
            rotor_in(&r2, k * Ts, tau_n, &in);
            bc_sine_step(&p, &s, &in, &out);
        }
        double isat = (48.0 - 2.0 * K_PHI * w2) / (sqrt(3.0) / 2.0 * we2 * L + 1.5 * R);
        CHECK_NEAR(out.diag[2], isat, 2e-3 * i_sn(), "I_s,sat (23) with R, no tables");
    }
}

/* The speed limit on a sinusoidal back-EMF k_x = k_1 sin(theta) (tables given to the controller; the plant
 * model of rotor_in is irrelevant to i_q,ref): the back-EMF and the drop add in quadrature,
 * sqrt(3) |omega_m k_1 + (R + j omega_e L) I| = V_dc, for both limits (a balanced sinusoidal set has a constant
 * alpha-beta vector of length |.| = V_dc / sqrt(3) on the circle too). */
static void test_speed_limit_sinusoid(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    static bc_sine_params p;
    static bc_sine_state s;
    static float tab[3][360];
    sine_params(&p, &f);
    double k1 = 0.33;
    p.L = 750e-6f; /* the controller's model only: a drop comparable with the back-EMF near the base speed */
    for (int x = 0; x < 3; ++x) {
        for (int j = 0; j < 360; ++j) tab[x][j] = (float)(k1 * sin(2.0 * BC_PI * j / 360.0));
        p.emf_k[x] = tab[x];
    }
    p.emf_n = 360;
    p.k_1 = (float)k1;
    double Ts = (double)p.ts, L = 750e-6;
    bc_ctrl_in in;
    bc_ctrl_out out;
    for (int lim = 0; lim <= 1; ++lim) {
        for (int rr = 0; rr <= 1; ++rr) {
            p.limit = lim ? BC_SINE_LIMIT_CIRCLE : BC_SINE_LIMIT_HEX;
            p.R = rr ? 0.05f : 0.0f;
            double R = (double)p.R;
            for (int iw = 0; iw < 3; ++iw) {
                double w2 = (0.7 + 0.1 * iw) * 75.0, we2 = 8.0 * w2;
                CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
                rotor r2 = {0.3, we2, 20.0, 0.0, f.sp.f_tick};
                for (int k = 0; k < 400; ++k) {
                    rotor_in(&r2, k * Ts, 1e4f, &in);
                    bc_sine_step(&p, &s, &in, &out);
                }
                /* (R^2 + X^2) I^2 + 2 E R I + E^2 - V^2/3 = 0 */
                double E = w2 * k1, X = we2 * L, V = 48.0;
                double a = R * R + X * X, b = 2.0 * E * R, c = E * E - V * V / 3.0;
                double iq = (-b + sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
                double want = fmin(iq, i_sn());
                CHECK(s.mode == BC_SINE_MODE_SINE, "sine mode");
                CHECK(fabs((double)out.diag[2] - want) <= 2e-3 * i_sn(),
                      "sinusoid: quadrature limit %.4f vs %.4f A (limit %d, R %g, %.2f Omega_0)", (double)out.diag[2],
                      want, lim, R, w2 / 75.0);
                CHECK((double)out.diag[2] <= want * (1.0 + 1e-4), "never above the exact limit: %.4f vs %.4f A",
                      (double)out.diag[2], want);
            }
        }
    }
}

/* ---------------------------------------------------------------------------------------------------------- */
/* The speed limit's table (bc_sine.h, 5.) against the scan it tabulates, written here in double: v_req(omega_e, J)
 * over the M grid angles with the margins (dev and dev_c sampled as bc_sine_init samples them), and the exact
 * largest current by lines (hexagon: I <= (v_dc - m_e -+ e) / (m_g -+ s G) for every line with a positive slope;
 * circle: the positive root of |E + s I G| = v_dc / sqrt(3) - m_c at every angle). */

#define SCAN_M BC_SINE_LIM_N
typedef struct {
    int hex, p;
    double R, L, i_s, dev, dev_c, k_e;
    double k[3][SCAN_M], i[3][SCAN_M], di[3][SCAN_M]; /* line values at the grid angles */
} scan;

static double scan_pwl(const float *k, int n, double th)
{
    double u = th / (2.0 * BC_PI) * n;
    u -= n * floor(u / n);
    int j = (int)u;
    if (j < 0) j = 0;
    if (j > n - 1) j = n - 1; /* u rounded to n: the end of the last segment */
    double fr = fmin(fmax(u - j, 0.0), 1.0);
    int j1 = j + 1 < n ? j + 1 : 0;
    return (double)k[j] + fr * ((double)k[j1] - (double)k[j]);
}

static void scan_line_k(const bc_sine_params *p, double th, double k[3])
{
    double kx[3];
    for (int x = 0; x < 3; ++x) kx[x] = scan_pwl(p->emf_k[x], p->emf_n, th - x * 2.0 * BC_PI / 3.0);
    for (int x = 0; x < 3; ++x) k[x] = kx[x] - kx[(x + 1) % 3];
}

static double scan_norm(const double k[3])
{
    double a = (k[0] - k[2]) / 3.0, b = k[1] / sqrt(3.0);
    return sqrt(a * a + b * b);
}

static void scan_init(scan *sc, const bc_sine_params *p)
{
    sc->hex = p->limit == BC_SINE_LIMIT_HEX;
    sc->p = p->p;
    sc->R = p->R;
    sc->L = p->L;
    sc->i_s = p->i_s_max;
    double kmax = 0.0, kmax_c = 0.0;
    sc->dev = sc->dev_c = 0.0;
    int n_sub = 2 * (p->emf_n / SCAN_M + 1);
    for (int j = 0; j < SCAN_M; ++j) {
        double th = 2.0 * BC_PI * j / SCAN_M, k0[3], k1[3], k[3];
        scan_line_k(p, th, k0);
        scan_line_k(p, 2.0 * BC_PI * ((j + 1) % SCAN_M) / SCAN_M, k1);
        for (int x = 0; x < 3; ++x) {
            int y = (x + 1) % 3;
            sc->k[x][j] = k0[x];
            sc->i[x][j] = sin(th - x * 2.0 * BC_PI / 3.0) - sin(th - y * 2.0 * BC_PI / 3.0);
            sc->di[x][j] = cos(th - x * 2.0 * BC_PI / 3.0) - cos(th - y * 2.0 * BC_PI / 3.0);
            kmax = fmax(kmax, fabs(k0[x]));
        }
        double n0 = scan_norm(k0), n1 = scan_norm(k1);
        kmax_c = fmax(kmax_c, n0);
        for (int q = 1; q < n_sub; ++q) {
            double u = (double)q / n_sub;
            scan_line_k(p, 2.0 * BC_PI * (j + u) / SCAN_M, k);
            for (int x = 0; x < 3; ++x) sc->dev = fmax(sc->dev, fabs(k[x] - (k0[x] + u * (k1[x] - k0[x]))));
            sc->dev_c = fmax(sc->dev_c, scan_norm(k) - (n0 + u * (n1 - n0)));
        }
    }
    sc->k_e = sc->hex ? kmax + sc->dev : sqrt(3.0) * (kmax_c + sc->dev_c); /* v_req(omega_e, 0) = |omega_m| k_e */
}

/* v_req(omega_e, J) */
static double scan_v(const scan *sc, double we, double J)
{
    double wm = we / sc->p, x_e = we * sc->L, best = 0.0;
    for (int j = 0; j < SCAN_M; ++j) {
        if (sc->hex) {
            for (int x = 0; x < 3; ++x) {
                best = fmax(best, fabs(wm * sc->k[x][j] + J * (sc->R * sc->i[x][j] + x_e * sc->di[x][j])));
            }
        } else {
            double ea = wm * (sc->k[0][j] - sc->k[2][j]) / 3.0, eb = wm * sc->k[1][j] / sqrt(3.0);
            double ga = (sc->R * (sc->i[0][j] - sc->i[2][j]) + x_e * (sc->di[0][j] - sc->di[2][j])) / 3.0;
            double gb = (sc->R * sc->i[1][j] + x_e * sc->di[1][j]) / sqrt(3.0);
            best = fmax(best, hypot(ea + J * ga, eb + J * gb));
        }
    }
    if (sc->hex) {
        return best + fabs(wm) * sc->dev + fabs(J) * (1.0 - cos(BC_PI / SCAN_M)) * sqrt(3.0) * hypot(sc->R, x_e);
    }
    return sqrt(3.0) * (best + fabs(wm) * sc->dev_c);
}

/* The exact min(i_s, I_s,sat) of the scan. */
static double scan_limit(const scan *sc, double we, double v_dc, double sgn)
{
    double wm = we / sc->p, x_e = we * sc->L, best = sc->i_s;
    if (!(scan_v(sc, we, 0.0) <= v_dc)) return 0.0;
    if (sc->hex) {
        double m_e = fabs(wm) * sc->dev, m_g = (1.0 - cos(BC_PI / SCAN_M)) * sqrt(3.0) * hypot(sc->R, x_e);
        for (int j = 0; j < SCAN_M; ++j) {
            for (int x = 0; x < 3; ++x) {
                double e = wm * sc->k[x][j], g = sgn * (sc->R * sc->i[x][j] + x_e * sc->di[x][j]);
                for (int side = -1; side <= 1; side += 2) {
                    double slope = side * g + m_g;
                    if (slope > 0.0) best = fmin(best, (v_dc - m_e - side * e) / slope);
                }
            }
        }
    } else {
        double r = v_dc / sqrt(3.0) - fabs(wm) * sc->dev_c;
        for (int j = 0; j < SCAN_M; ++j) {
            double ea = wm * (sc->k[0][j] - sc->k[2][j]) / 3.0, eb = wm * sc->k[1][j] / sqrt(3.0);
            double ga = sgn * (sc->R * (sc->i[0][j] - sc->i[2][j]) + x_e * (sc->di[0][j] - sc->di[2][j])) / 3.0;
            double gb = sgn * (sc->R * sc->i[1][j] + x_e * sc->di[1][j]) / sqrt(3.0);
            double gg = ga * ga + gb * gb, eg = ea * ga + eb * gb, ee = ea * ea + eb * eb;
            if (gg > 0.0) best = fmin(best, (-eg + sqrt(fmax(eg * eg + gg * (r * r - ee), 0.0))) / gg);
        }
    }
    return fmin(fmax(best, 0.0), sc->i_s);
}

/* At random speeds (both signs, up to 1.05 times the no-load speed w0 of the bus, two thirds of them near w0 where
 * a small drop binds), buses from 0.3 to 2 V_dc and both torque signs, the table's limit I is
 *   - never above the scan's: I <= I_scan(v_dc);
 *   - at most tol I_s,N below it where the back-EMF alone needs at most 99.5 % of the bus. Nearer w0 the scan's
 *     limit is steep in v_dc and speed, and it steps: braking, from 0 (the back-EMF alone above v_dc) to the current
 *     that brings the voltage back down to v_dc; the table's rounding up moves that step by about 1e-4 of v_dc;
 *   - everywhere at least the scan's on a bus btol lower: I >= I_scan((1 - btol) v_dc).
 * Also every node of the table lies at or above v_req. Prints the worst shortfalls and the bus the table costs
 * (the smallest d with I >= I_scan((1 - d) v_dc), by bisection); returns the first (fraction of I_s,N). */
static double check_limit_table(const char *what, bc_sine_params *p, double tol, double btol)
{
    static bc_sine_state s;
    static scan sc;
    CHECK(bc_sine_init(p, &s) == BC_OK && s.lim_shape == 1, "%s: init with the table", what);
    scan_init(&sc, p);
    double node_low = 0.0, node_high = 0.0;
    for (int n = 0; n <= BC_SINE_LIM_W; ++n) {
        int nf = BC_SINE_LIM_WF, nc = BC_SINE_LIM_W / 2 - nf, k = n - BC_SINE_LIM_W / 2, ak = k < 0 ? -k : k;
        double wt = (double)s.lim_w_top, w1 = (double)BC_SINE_LIM_W1 * wt;
        double we = ak <= nf ? ak * w1 / nf : w1 + (ak - nf) * (wt - w1) / nc;
        if (k < 0) we = -we;
        for (int m = 0; m <= 2 * BC_SINE_LIM_J; ++m) {
            double J = (m - BC_SINE_LIM_J) * (double)s.lim_h;
            double stored = (double)s.lim_base[n] + (double)s.lim_q[n] * s.lim_tab[n][m];
            node_low = fmax(node_low, scan_v(&sc, we, J) - stored);
            node_high = fmax(node_high, stored - scan_v(&sc, we, J));
        }
    }
    CHECK(node_low <= 0.0, "%s: every node at or above v_req (%.3g V below)", what, node_low);
    double below = 0.0, above = 0.0, edge = 0.0, bus = 0.0;
    int n_mid = 0, n_away = 0;
    for (int k = 0; k < 4000; ++k) {
        double v_dc = 48.0 * (0.3 + 1.7 * rnd());
        double w0 = sc.p * v_dc / sc.k_e; /* the back-EMF alone needs v_dc */
        double lo = k % 3 == 0 ? 0.0 : (k % 3 == 1 ? 0.75 : 0.97), hi = k % 3 == 0 ? 1.05 : 1.005;
        double we = (rnd() < 0.5 ? -1.0 : 1.0) * (lo + (hi - lo) * rnd()) * w0, sgn = rnd() < 0.5 ? -1.0 : 1.0;
        double tb = (double)bc_sine_i_limit(p, &s, (float)v_dc, (float)we, (float)sgn);
        double ex = scan_limit(&sc, we, v_dc, sgn), short_i = (ex - tb) / sc.i_s;
        above = fmax(above, -short_i);
        if (scan_v(&sc, we, 0.0) <= 0.995 * v_dc) {
            below = fmax(below, short_i);
            n_away += 1;
        } else {
            edge = fmax(edge, short_i);
        }
        n_mid += tb > 0.0 && tb < sc.i_s;
        CHECK(tb >= scan_limit(&sc, we, (1.0 - btol) * v_dc, sgn) - 1e-5 * sc.i_s,
              "%s: at least the scan's limit on a bus %.1f %% lower (%.4f rad/s, %.3f V, sign %g: %.4f A)", what,
              100.0 * btol, we, v_dc, sgn, tb);
        if (short_i > 1e-4) { /* the bus the table costs here (below 1e-4 of I_s,N: a few 1e-5 of v_dc) */
            double d_lo = 0.0, d_hi = btol;
            for (int it = 0; it < 14; ++it) {
                double d = 0.5 * (d_lo + d_hi);
                if (tb >= scan_limit(&sc, we, (1.0 - d) * v_dc, sgn) - 1e-5 * sc.i_s) {
                    d_hi = d;
                } else {
                    d_lo = d;
                }
            }
            bus = fmax(bus, d_hi);
        }
    }
    printf("speed limit table, %s: %.3f %% of I_s,N below the scan (%d samples; nearer w0 %.1f %%), %.1e above; "
           "bus cost %.3f %%; nodes up to %.2g V above v_req\n", what, 100.0 * below, n_away, 100.0 * edge, above,
           100.0 * bus, node_high);
    CHECK(above <= 1e-5, "%s: never above the scan (%.2g of I_s,N)", what, above);
    CHECK(below <= tol, "%s: %.3f %% of I_s,N below the scan (tolerance %.2f %%)", what, 100.0 * below, 100.0 * tol);
    CHECK(n_mid > 100 && n_away > 1500, "%s: the limit binds in %d samples, %d away from w0", what, n_mid, n_away);
    return below;
}

/* The table on a trapezoid (the htm-48v fixture), a sinusoid with a large drop and a table with even harmonics that
 * differ between phases, with R = 0 and R > 0, both limits; and its answer to inputs no drive gives. */
static void test_speed_limit_table(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    static bc_sine_params p;
    static float tab[3][EMF_N];
    double worst = 0.0;
    for (int shape = 0; shape < 3; ++shape) {
        sine_params(&p, &f); /* the trapezoid of the fixture in emf_tab */
        if (shape > 0) {
            for (int x = 0; x < 3; ++x) {
                for (int j = 0; j < EMF_N; ++j) {
                    double th = 2.0 * BC_PI * j / EMF_N;
                    double k = shape == 1 ? sin(th)
                                          : sin(th) + 0.15 * sin(3.0 * th) + 0.08 * cos(5.0 * th + 0.3 * x) +
                                                0.05 * sin(2.0 * th + x);
                    tab[x][j] = (float)((shape == 1 ? 0.33 : 0.3) * k);
                }
                p.emf_k[x] = tab[x];
            }
            p.L = 750e-6f; /* a drop comparable with the back-EMF */
        }
        for (int rr = 0; rr <= 1; ++rr) {
            for (int lim = 0; lim <= 1; ++lim) {
                char what[64];
                p.R = rr ? 0.05f : 0.0f;
                p.limit = lim ? BC_SINE_LIMIT_CIRCLE : BC_SINE_LIMIT_HEX;
                static const char *const names[] = {"trapezoid", "sinusoid", "table"};
                snprintf(what, sizeof what, "%s, R = %g, %s", names[shape], (double)p.R, lim ? "circle" : "hexagon");
                worst = fmax(worst, check_limit_table(what, &p, 0.015, 0.01));
            }
        }
    }
    printf("speed limit table: worst %.3f %% of I_s,N below the scan\n", 100.0 * worst);

    /* inputs no drive gives: 0 or a value in [0, i_s_max], never NaN */
    static bc_sine_state s;
    sine_params(&p, &f);
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    static const float bad_w[] = {NAN, INFINITY, -INFINITY, 3e38f, -3e38f, 1e6f, -1e6f};
    for (unsigned k = 0; k < sizeof bad_w / sizeof bad_w[0]; ++k) {
        CHECK(bc_sine_i_limit(&p, &s, 48.0f, bad_w[k], 1.0f) == 0.0f, "speed %g: 0", (double)bad_w[k]);
    }
    static const float bad_v[] = {NAN, -INFINITY, -48.0f, 0.0f, -1e-38f};
    for (unsigned k = 0; k < sizeof bad_v / sizeof bad_v[0]; ++k) {
        for (int w = -600; w <= 600; w += 300) {
            CHECK(bc_sine_i_limit(&p, &s, bad_v[k], (float)w, -1.0f) == 0.0f, "v_dc %g at %d rad/s: 0",
                  (double)bad_v[k], w);
        }
    }
    float big = bc_sine_i_limit(&p, &s, INFINITY, 300.0f, 1.0f);
    CHECK(big == p.i_s_max, "infinite bus: i_s_max (%g)", (double)big);
    CHECK(bc_sine_i_limit(&p, &s, 48.0f, 0.0f, 1.0f) == p.i_s_max, "standstill: i_s_max");
    p.speed_limit = 0;
    CHECK(bc_sine_i_limit(&p, &s, NAN, NAN, 1.0f) == p.i_s_max, "no speed limit: i_s_max");
    /* all-zero shape tables: no w_top, the closed form (23) */
    static float zero[EMF_N];
    sine_params(&p, &f);
    for (int x = 0; x < 3; ++x) p.emf_k[x] = zero;
    CHECK(bc_sine_init(&p, &s) == BC_OK && s.lim_shape == 0, "zero back-EMF: (23)");
}

/* Decoupling from the measured currents: two controllers in the same state, given currents that differ only in
 * i_q by di, differ in v_d by -omega_e L di (the rotational voltage the motor's own d,q coupling adds) and in v_q by
 * -k_p di (the PI). A feed-forward from the references alone (v_d unchanged) leaves the coupling in the error
 * dynamics: with k_p << omega_e L a slow, lightly damped mode (k_i / (k_p + j omega_e L)) results. */
static void test_decoupling_measured(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_sine_params p;
    static bc_sine_state s, s2;
    sine_params(&p, &f);
    p.emf_ff = 0;
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    double L = 75e-6, Ts = (double)p.ts, we = 8.0 * 37.5, di = 2.0;
    rotor r = {0.3, we, i_sn(), 0.0, f.sp.f_tick};
    rotor r2 = r;
    r2.I += di; /* phi = 0: the current is on q, so only i_q differs */
    float tau_n = (float)(1.5 * k1_trap() * i_sn());
    bc_ctrl_in in, in2;
    bc_ctrl_out out, out2;
    int k = 0;
    for (; k < 2000 && s.mode != BC_SINE_MODE_SINE; ++k) {
        rotor_in(&r, k * Ts, tau_n, &in);
        bc_sine_step(&p, &s, &in, &out);
    }
    CHECK(s.mode == BC_SINE_MODE_SINE, "sine mode");
    for (int j = 0; j < 50; ++j, ++k) {
        rotor_in(&r, k * Ts, tau_n, &in);
        rotor_in(&r2, k * Ts, tau_n, &in2);
        s2 = s;
        bc_sine_step(&p, &s2, &in2, &out2);
        bc_sine_step(&p, &s, &in, &out);
        CHECK(!(out.flags & BC_FLAG_SATURATED) && !(out2.flags & BC_FLAG_SATURATED), "unsaturated");
        CHECK_NEAR(out2.diag[1] - out.diag[1], di, 1e-3, "measured i_q differs by di");
        CHECK_NEAR(out2.diag[3] - out.diag[3], -we * L * di, 2e-4, "v_d: -omega_e L di (decoupling)");
        CHECK_NEAR(out2.diag[4] - out.diag[4], -(double)p.kp * di, 2e-4, "v_q: -k_p di (PI)");
    }
}

/* Flying start: coast until the rotor is known to be slower than omega_on. */
static void test_flying_start(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_sine_params p;
    static bc_sine_state s;
    sine_params(&p, &f);
    p.flying_start = 1;
    double Ts = (double)p.ts;
    float tau_n = (float)(1.5 * k1_trap() * i_sn());
    bc_ctrl_in in;
    bc_ctrl_out out;
    /* a rotor turning at 0.9 Omega_0 with a braking torque: legs off until the sine mode takes over */
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    rotor r = {0.3, 8.0 * 0.9 * 75.0, 0.0, 0.0, f.sp.f_tick};
    int k_sine = -1, active_before = 0;
    for (int k = 0; k < 600; ++k) {
        rotor_in(&r, k * Ts, -tau_n, &in);
        bc_sine_step(&p, &s, &in, &out);
        if (s.mode == BC_SINE_MODE_SINE && k_sine < 0) k_sine = k;
        if (k_sine < 0) {
            for (int x = 0; x < 3; ++x) active_before |= out.leg[x].mode != BC_LEG_OFF;
            CHECK(out.flags == 0u, "coasting is not a fault");
        }
    }
    double t_two_edges = 2.0 * (BC_PI / 3.0) / r.we;
    CHECK(k_sine > 0 && k_sine * Ts < t_two_edges + 2.0 * Ts, "sine after two edges: %.3f ms", k_sine * Ts * 1e3);
    CHECK(!active_before, "no square-wave braking at high speed");
    /* braking: the drop opposes the back-EMF, so its voltage stays within the hexagon at the full I_s,N (the
     * shape-aware limit is per sign); the closed form (23) (no shape tables) is symmetric: -I_s,sat */
    CHECK_NEAR(out.diag[2], -i_sn(), 1e-3 * i_sn(), "braking at -I_s,N");
    double isat = (48.0 - 2.0 * K_PHI * 0.9 * 75.0) / (sqrt(3.0) / 2.0 * r.we * 75e-6 + 1.5 * 0.05);
    p.emf_ff = 0;
    for (int x = 0; x < 3; ++x) p.emf_k[x] = 0;
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    for (int k = 0; k < 600; ++k) {
        rotor_in(&r, k * Ts, -tau_n, &in);
        bc_sine_step(&p, &s, &in, &out);
    }
    CHECK_NEAR(out.diag[2], -isat, 2e-3 * isat, "braking at -I_s,sat (23) without tables");
    sine_params(&p, &f);
    p.flying_start = 1;
    /* at standstill the square-wave start begins once no edge came for (pi/3) / omega_on */
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    rotor r0 = {0.3, 1e-9, 0.0, 0.0, f.sp.f_tick};
    int k_act = -1;
    for (int k = 0; k < 1000 && k_act < 0; ++k) {
        rotor_in(&r0, k * Ts, tau_n, &in);
        bc_sine_step(&p, &s, &in, &out);
        if (out.leg[0].mode != BC_LEG_OFF || out.leg[1].mode != BC_LEG_OFF || out.leg[2].mode != BC_LEG_OFF) k_act = k;
    }
    double t_wait = (BC_PI / 3.0) / (double)p.omega_on;
    CHECK(k_act > 0 && fabs(k_act * Ts - t_wait) <= 2.0 * Ts, "square-wave start after %.3f ms (wait %.3f ms)",
          k_act * Ts * 1e3, t_wait * 1e3);
    /* without flying start the square wave drives from the first sample */
    p.flying_start = 0;
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    rotor_in(&r0, 0.0, tau_n, &in);
    bc_sine_step(&p, &s, &in, &out);
    CHECK(out.leg[0].mode != BC_LEG_OFF || out.leg[1].mode != BC_LEG_OFF, "start at once");
}

/* Closed loop, htm-48v with R = 0 at imposed half speed: mean torque (13) and ripple (15) of paper 1. */
static void test_closed_loop_imposed(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.R = 0.0;
    static bc_sine_params p;
    static bc_sine_state s;
    sine_params(&p, &f); /* model R = 0; the PI keeps the gains designed for 50 mOhm */
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    static bc_sim_config cfg;
    static bc_sim_inputs in;
    static bc_sim_state st;
    memset(&cfg, 0, sizeof cfg);
    memset(&in, 0, sizeof in);
    cfg.plant = &f.p;
    cfg.sensors = &f.sp;
    cfg.delay = 1;
    cfg.trace_every = 1;
    cfg.trace_sub = 1;
    double om = 37.5, Te = 2.0 * BC_PI / (8.0 * om), TN = 2.0 * K_PHI * I_N;
    cfg.metric_t0 = 2.0 * Te;
    cfg.metric_t1 = 4.0 * Te;
    in.omega_c = om;
    in.v_src_c = 48.0;
    in.ref_c = 1.5 * k1_trap() * i_sn();
    cfg.ctrl.step = sine_slot;
    cfg.ctrl.params = &p;
    cfg.ctrl.state = &s;
    static const double i0[3] = {0.0, 0.0, 0.0};
    CHECK(bc_sim_init(&cfg, &st, 0.3, om, i0, 48.0) == BC_OK, "sim init");
    int64_t n = (int64_t)ceil(4.1 * Te / bc_plant_t_half(&f.p)), nw = 0;
    CHECK(bc_sim_run(&cfg, &st, &in, n, 0, 0, &nw) == BC_OK, "run");
    CHECK(st.m.state == 2, "window closed");
    double tau = st.m.E[BC_ACC_TAU] / (st.m.t1 - st.m.t0) / TN;
    double rip = (st.m.tau_ma_max - st.m.tau_ma_min) / TN;
    CHECK_NEAR(tau, 18.0 / (sqrt(3.0) * BC_PI * BC_PI), 0.005, "mean torque (13), p.u.");
    CHECK_NEAR(rip, 2.0 / sqrt(3.0) - 1.0, 0.02, "PWM-averaged ripple (15), p.u.");
    for (int x = 0; x < 3; ++x) {
        CHECK(fabs(st.m.i_peak[x] - i_sn()) < 0.05 * i_sn(), "peak current %.2f A", st.m.i_peak[x]);
    }
}

/* The resistance estimate in closed loop on the plant (imposed speed, 20 N m): the plant's winding hot (R x 1.3),
 * the controller's model at 25 degC. Each period's R_hat scatters by about +-10 % (the trapezoid's harmonics and the
 * Hall interpolation's error do not average out over 5 ms windows); the filter (a = 0.05, about 20 periods) brings
 * the estimate within 1.5 % of the plant's R in 1.5 s, and its temperature within 5 K. */
static void test_closed_loop_rest(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    const double R_hot = 1.3 * f.p.R;
    static bc_sine_params p;
    static bc_sine_state s;
    sine_params(&p, &f); /* model R = 50 mOhm */
    f.p.R = R_hot;
    p.rest = rest_params();
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    static bc_sim_config cfg;
    static bc_sim_inputs in;
    static bc_sim_state st;
    memset(&cfg, 0, sizeof cfg);
    memset(&in, 0, sizeof in);
    cfg.plant = &f.p;
    cfg.sensors = &f.sp;
    cfg.delay = 1;
    cfg.trace_every = 1;
    cfg.trace_sub = 1;
    const double speeds[3] = {10.0, 30.0, 60.0}; /* 0.15 to 0.9 Omega_N */
    for (int j = 0; j < 3; ++j) {
        double om = speeds[j];
        in.omega_c = om;
        in.v_src_c = 48.0;
        in.ref_c = 20.0;
        cfg.ctrl.step = sine_slot;
        cfg.ctrl.params = &p;
        cfg.ctrl.state = &s;
        CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
        static const double i0[3] = {0.0, 0.0, 0.0};
        CHECK(bc_sim_init(&cfg, &st, 0.3, om, i0, 48.0) == BC_OK, "sim init");
        int64_t n = (int64_t)ceil(1.5 / bc_plant_t_half(&f.p)), nw = 0;
        CHECK(bc_sim_run(&cfg, &st, &in, n, 0, 0, &nw) == BC_OK, "run");
        CHECK(s.mode == BC_SINE_MODE_SINE && s.rest.count >= 60u, "%g rad/s: sine mode, %u valid periods", om,
              s.rest.count);
        CHECK(fabs((double)s.rest.r - R_hot) < 0.015 * R_hot, "%g rad/s: R estimate %.5f Ohm, plant %.5f", om,
              (double)s.rest.r, R_hot);
        float T = 0.0f;
        CHECK(bc_rest_temp(&p.rest, &s.rest, &T) == BC_OK, "temperature");
        double T_true = 1.3 * (234.5 + 25.0) - 234.5; /* 102.9 degC */
        CHECK(fabs((double)T - T_true) < 5.0, "%g rad/s: winding %.1f degC from R, true %.1f", om, (double)T, T_true);
    }
    /* without a winding sensor (the run's readings are NaN) the derating reads the estimate's temperature: above
     * its band (60 to 90 degC) the factor is f_min; without the estimate the missing reading is a fault, f_fault */
    for (int with = 0; with < 2; ++with) {
        p.rest = rest_params();
        if (!with) p.rest.i_inj = 0.0f;
        p.derate.enabled[0] = 1;
        p.derate.T_start[0] = 60.0f;
        p.derate.T_end[0] = 90.0f;
        p.derate.f_min = 0.25f;
        p.derate.f_fault = 0.5f;
        p.derate.T_lo = -40.0f;
        p.derate.T_hi = 250.0f;
        p.derate.ts = p.ts;
        CHECK(bc_sine_init(&p, &s) == BC_OK, "init with derating");
        static const double i0[3] = {0.0, 0.0, 0.0};
        in.omega_c = 30.0;
        CHECK(bc_sim_init(&cfg, &st, 0.3, 30.0, i0, 48.0) == BC_OK, "sim init");
        int64_t n = (int64_t)ceil(0.5 / bc_plant_t_half(&f.p)), nw = 0;
        CHECK(bc_sim_run(&cfg, &st, &in, n, 0, 0, &nw) == BC_OK, "run");
        CHECK(s.derate_f == (with ? 0.25f : 0.5f), "derating %s the estimate: factor %g", with ? "with" : "without",
              (double)s.derate_f);
    }
}

/* Closed loop from standstill with the rotor mechanics: square-wave start, hand-off at 0.1 Omega_N, no current
 * above 1.2 I_N around the switch. */
static void test_closed_loop_start(void)
{
    static fixture f;
    fixture_htm(&f, BC_MECH_DYNAMIC);
    static bc_sine_params p;
    static bc_sine_state s;
    sine_params(&p, &f);
    CHECK(bc_sine_init(&p, &s) == BC_OK, "init");
    static bc_sim_config cfg;
    static bc_sim_inputs in;
    static bc_sim_state st;
    memset(&cfg, 0, sizeof cfg);
    memset(&in, 0, sizeof in);
    cfg.plant = &f.p;
    cfg.sensors = &f.sp;
    cfg.ctrl.step = sine_slot;
    cfg.ctrl.params = &p;
    cfg.ctrl.state = &s;
    cfg.delay = 1;
    cfg.trace_every = 1;
    cfg.trace_sub = 1;
    in.v_src_c = 48.0;
    in.ref_c = 1.5 * k1_trap() * i_sn(); /* T_s,N */
    in.tau_load_c = 0.5 * 2.0 * K_PHI * I_N;
    static const double i0[3] = {0.0, 0.0, 0.0};
    CHECK(bc_sim_init(&cfg, &st, 0.3, 0.0, i0, 48.0) == BC_OK, "sim init");
    enum { N = 1680 }; /* 60 ms */
    static bc_trace_row rows[N];
    int64_t nw = 0;
    CHECK(bc_sim_run(&cfg, &st, &in, N, rows, N, &nw) == BC_OK && nw == N, "run");
    int k_sw = -1, safe = 0;
    for (int k = 0; k < N; ++k) {
        if (k_sw < 0 && rows[k].d7 == 1.0) k_sw = k;
        safe |= ((uint32_t)rows[k].flags & BC_FLAG_SAFE) != 0u;
    }
    CHECK(!safe, "never safe");
    CHECK(k_sw > 0, "hands off to the sine mode");
    if (k_sw <= 0) return;
    CHECK(rows[k_sw].d6 >= 8.0 * 0.1 * OMEGA_N * (1.0 - 1e-6), "Hall speed at the switch %.2f rad/s >= 0.1 Omega_N",
          rows[k_sw].d6);
    CHECK(rows[k_sw].omega_m >= 0.1 * OMEGA_N, "rotor speed at the switch %.2f rad/s", rows[k_sw].omega_m);
    double peak = 0.0;
    for (int k = k_sw - 140; k < k_sw + 280 && k < N; ++k) { /* 5 ms before, 10 ms after */
        for (int x = 0; x < 3; ++x) peak = fmax(peak, fabs((&rows[k].i_a)[x]));
    }
    CHECK(peak <= 1.2 * I_N, "no current above 1.2 I_N around the switch: %.2f A", peak);
    int back = 0;
    for (int k = k_sw; k < N; ++k) back |= rows[k].d7 != 1.0;
    CHECK(!back, "stays in the sine mode while accelerating");
    CHECK(st.plant.omega > rows[k_sw].omega_m, "keeps accelerating: %.2f rad/s", st.plant.omega);
}

int main(void)
{
    test_transforms();
    test_svm();
    test_params();
    test_safe_states();
    test_fuzz();
    test_fuzz_observer();
    test_alignment_resistance();
    test_closed_loop_rest();
    test_limits_and_handoff();
    test_decoupling_measured();
    test_flying_start();
    test_speed_limit_sinusoid();
    test_speed_limit_table();
    test_closed_loop_imposed();
    test_closed_loop_start();
    return bc_test_summary("test_sine");
}

/* test_bemf.c - the sensorless six-step controller (bc_bemf) against a synthetic drive (synth_bemf.h): parameter
 * validation; safe states; bounded outputs for random and extreme inputs; the commutation instants 30 - adv degrees
 * after the true crossings (comparator and ADC methods, delays compensated, fixed and automatic advance, constant and
 * ramping speed, both directions, two PWM periods per commutation); the back-EMF integration's instant; the blanking
 * against the diode clamp's false crossing; the minimum-pulse filter; the desyncs and their reasons (a clamp
 * outlasting the crossing, a rotor that stops, a false crossing, a stall, a start that fails); the late commutation;
 * the forced ramp following a faster rotor by its crossings, and its V/f duty; the start-up from alignment to closed
 * loop on a dynamic rotor in both directions and from any angle without alignment, a stop and a reverse; the
 * throttle ramp and the current limit; the handover's fit made in two parts against the one-shot fit and the exact one
 * on random crossing sequences. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_bemf.h"
#include "bldc/bc_commutation.h"
#include "synth_bemf.h"

#define TS 25e-6 /* 20 kHz PWM, sampled at valley and peak */
#define F_TICK 10e6
#define TICK (1.0 / F_TICK)
#define DEG (BC_PI / 180.0)

static bc_bemf_params params(int method)
{
    bc_bemf_params p;
    memset(&p, 0, sizeof p);
    p.method = method;
    p.chop = BC_CHOP_HIGH;
    p.delay = 1;
    p.blanking = BC_BEMF_BLANK_DEMAG;
    p.ts = (float)TS;
    p.f_tick = (float)F_TICK;
    p.blank_angle = 0.0f;
    p.blank_time = 2e-6f;
    p.min_pulse = 0.0f;
    p.n_samples = 1;
    p.adv_max = (float)(BC_PI / 6.0);
    p.t60_gain = 1.0f;
    p.int_limit = (float)(0.01 * BC_PI / 12.0); /* ke pi/12: the synthetic back-EMF's integral to 30 degrees */
    p.zc_timeout = 1.5f;
    p.jump_max = 2.0f;
    p.miss_max = 0;
    p.omega_stall = 50.0f;
    p.align_time = 0.02f;
    p.align_duty = 0.1f;
    p.ramp_w0 = 20.0f;
    p.ramp_w1 = 300.0f;
    p.ramp_accel = 5000.0f;
    p.ramp_duty = 0.15f;
    p.ramp_hold = 24;
    p.n_handover = 6;
    p.duty_min = 0.02f;
    p.duty_rate = 0.0f;
    p.ref_stop = 0.0f;
    p.restart_wait = 0.01f;
    p.restart_max = 0.1f;
    p.use_current = 0;
    p.i_max = 100.0f;
    p.v_max = 30.0f;
    return p;
}

static int all_off(const bc_ctrl_out *o)
{
    for (int x = 0; x < 3; ++x)
        if (o->leg[x].mode != BC_LEG_OFF) return 0;
    return o->has_at == 0u;
}

static int bounded(const bc_ctrl_out *o)
{
    for (int x = 0; x < 3; ++x) {
        if (o->leg[x].mode < BC_LEG_OFF || o->leg[x].mode > BC_LEG_LOW) return 0;
        if (!(o->leg[x].duty >= 0.0f && o->leg[x].duty <= 1.0f)) return 0;
        if (o->has_at && (!(o->leg_at[x].duty >= 0.0f && o->leg_at[x].duty <= 1.0f) || o->leg_at[x].mode < 0 ||
                          o->leg_at[x].mode > 3))
            return 0;
    }
    if (o->has_at > 1u || (o->has_at && !(o->t_at >= 0.0f && o->t_at < (float)TS))) return 0;
    for (int j = 0; j < BC_DIAG_N; ++j)
        if (!isfinite(o->diag[j])) return 0;
    return 1;
}

/* ------------------------------------------------------------------------------------------------------------ */

static void test_init(void)
{
    bc_bemf_params p = params(BC_BEMF_COMPARATOR);
    bc_bemf_state s;
    CHECK(bc_bemf_init(&p, &s) == BC_OK, "valid parameters");
    CHECK(bc_bemf_init(0, &s) == BC_ERR_PARAM && bc_bemf_init(&p, 0) == BC_ERR_PARAM, "null");
#define BAD(member, value)                                                                                    \
    do {                                                                                                      \
        bc_bemf_params q = params(BC_BEMF_INTEGRATE);                                                         \
        q.member = value;                                                                                     \
        CHECK(bc_bemf_init(&q, &s) == BC_ERR_PARAM, "%s = %s refused", #member, #value);                     \
    } while (0)
    BAD(method, 3);
    BAD(chop, 4);
    BAD(delay, 2);
    BAD(blanking, 2);
    BAD(ts, 0.0f);
    BAD(ts, NAN);
    BAD(f_tick, -1.0f);
    BAD(blank_angle, 1.1f);
    BAD(blank_time, -1e-6f);
    BAD(min_pulse, INFINITY);
    BAD(n_samples, 0);
    BAD(n_samples, 17);
    BAD(tau_filter, -1.0f);
    BAD(t_comp, NAN);
    BAD(adv_angle, -0.1f);
    BAD(adv_max, 0.6f);
    BAD(t60_gain, 0.0f);
    BAD(t60_gain, 1.5f);
    BAD(int_limit, 0.0f);
    BAD(zc_timeout, 1.0f);
    BAD(jump_max, 1.0f);
    BAD(brake_tau, -1e-3f);
    BAD(brake_acc, NAN);
    BAD(brake_q, -1.0f);
    BAD(miss_max, -1);
    BAD(omega_stall, 0.0f);
    BAD(align_duty, 1.5f);
    BAD(ramp_w1, 10.0f); /* below ramp_w0 */
    BAD(ramp_hold, 0);
    BAD(n_handover, 1);
    BAD(duty_min, -0.1f);
    BAD(ref_stop, 1.0f);
    BAD(restart_max, 0.001f); /* below restart_wait */
    BAD(use_current, 2);
    BAD(i_max, 0.0f);
    BAD(v_max, NAN);
#undef BAD
    bc_bemf_params q = params(BC_BEMF_COMPARATOR);
    q.ramp_w0 = 0.0f;
    q.ramp_accel = 0.0f;
    CHECK(bc_bemf_init(&q, &s) == BC_ERR_PARAM, "a ramp that never moves refused");
    q = params(BC_BEMF_COMPARATOR);
    q.int_limit = 0.0f;
    CHECK(bc_bemf_init(&q, &s) == BC_OK, "int_limit unused by the comparator method");
}

static void test_safe_states(void)
{
    for (int method = 0; method < 3; ++method) {
        bc_bemf_params p = params(method);
        p.use_current = 1;
        bc_bemf_state s;
        (void)bc_bemf_init(&p, &s);
        bc_ctrl_in in;
        bc_ctrl_out o;
        for (int c = 0; c < 8; ++c) {
            memset(&in, 0, sizeof in);
            in.v_dc = 12.0f;
            in.i_mask = 3u;
            in.ref = 0.3f;
            in.tick_now = 250u;
            in.n_adc = 1u;
            uint32_t want = BC_FLAG_BAD_INPUT;
            switch (c) {
            case 0: in.ref = NAN; break;
            case 1: in.v_dc = 0.0f; break;
            case 2: in.v_dc = 31.0f; break;
            case 3: in.v_dc = INFINITY; break;
            case 4: in.i_abc[1] = NAN; break;
            case 5: in.fault_pin = 1u; want = BC_FLAG_OVERCURRENT; break;
            case 6: in.i_abc[0] = 150.0f; in.i_abc[1] = -150.0f; want = BC_FLAG_OVERCURRENT; break;
            default: in.v_term[2] = NAN; in.n_adc = 2u; want = method ? BC_FLAG_BAD_INPUT : 0u; break;
            }
            memset(&o, 0, sizeof o);
            bc_bemf_step(&p, &s, &in, &o);
            if (want) {
                CHECK(all_off(&o) && (o.flags & BC_FLAG_SAFE) && (o.flags & want) && o.diag[0] == -1.0f,
                      "method %d case %d: safe state, flags 0x%x", method, c, o.flags);
            } else {
                CHECK(!(o.flags & BC_FLAG_SAFE), "comparator method ignores the ADC (case %d)", c);
            }
        }
        /* without current sensing the currents are ignored, the bus still checked */
        p.use_current = 0;
        (void)bc_bemf_init(&p, &s);
        memset(&in, 0, sizeof in);
        in.v_dc = 12.0f;
        in.i_abc[0] = NAN;
        in.ref = 0.3f;
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        CHECK(!(o.flags & BC_FLAG_SAFE) && (o.flags & BC_FLAG_OPEN_LOOP), "use_current = 0: currents ignored");
        in.v_dc = -1.0f;
        bc_bemf_step(&p, &s, &in, &o);
        CHECK(all_off(&o) && (o.flags & BC_FLAG_SAFE), "use_current = 0: the bus checked");
    }
}

static uint32_t rnd(uint32_t *x)
{
    *x ^= *x << 13;
    *x ^= *x >> 17;
    *x ^= *x << 5;
    return *x;
}

static float rnd_float(uint32_t *x)
{
    static const float special[] = {NAN, INFINITY, -INFINITY, 0.0f, -0.0f, 1e30f, -1e30f, 1e-30f, 12.0f, 0.5f, -0.5f};
    uint32_t r = rnd(x);
    if (r % 3u == 0u) return special[r % (uint32_t)(sizeof special / sizeof special[0])];
    float f;
    uint32_t b = rnd(x);
    memcpy(&f, &b, sizeof f);
    return (r % 3u == 1u) ? f : (float)((double)(rnd(x) % 2000u) / 100.0 - 10.0);
}

static void test_fuzz(void)
{
    uint32_t seed = 12345u;
    int bad = 0, unsafe = 0, n = 0;
    for (int run = 0; run < 300; ++run) {
        bc_bemf_params p = params((int)(rnd(&seed) % 3u));
        p.chop = (int32_t)(rnd(&seed) % 4u);
        p.use_current = (int32_t)(rnd(&seed) % 2u);
        p.delay = (int32_t)(rnd(&seed) % 2u);
        p.blanking = (int32_t)(rnd(&seed) % 2u);
        p.miss_max = (int32_t)(rnd(&seed) % 3u);
        p.i_limit = 20.0f;
        p.k_limit = 1.0f;
        p.align_time = (rnd(&seed) % 2u) ? 0.0f : 1e-3f;
        p.grid_gain = (rnd(&seed) % 2u) ? 0.2f : 0.0f; /* the uniform grid's code fuzzed too */
        p.brake_tau = (rnd(&seed) % 2u) ? 2e-3f : 0.0f;    /* and the braking timeout's (9) */
        p.cmp_blind = (int32_t)(rnd(&seed) % 2u);        /* and the blind off-times' (6) */
        p.brake_acc = 500.0f;
        p.brake_q = 1e-4f;
        bc_bemf_state s;
        if (bc_bemf_init(&p, &s) != BC_OK) {
            ++bad;
            continue;
        }
        uint32_t tick = rnd(&seed);
        for (int k = 0; k < 400; ++k) {
            bc_ctrl_in in;
            memset(&in, 0, sizeof in);
            for (int x = 0; x < 3; ++x) {
                in.i_abc[x] = (rnd(&seed) % 4u) ? (float)((double)(rnd(&seed) % 200u) - 100.0) : rnd_float(&seed);
                in.v_term[x] = rnd_float(&seed);
                in.zc_count[x] = (rnd(&seed) % 3u) ? (uint32_t)k / 3u : rnd(&seed);
                in.zc_tick[x] = (rnd(&seed) % 2u) ? tick - rnd(&seed) % 3000u : rnd(&seed);
            }
            in.i_mask = rnd(&seed) % 8u;
            in.v_dc = (rnd(&seed) % 4u) ? 12.0f : rnd_float(&seed);
            in.ref = (rnd(&seed) % 4u) ? (float)((double)(rnd(&seed) % 300u) / 100.0 - 1.5) : rnd_float(&seed);
            in.zc_state = rnd(&seed);
            in.v_neutral = (rnd(&seed) % 4u) ? 6.0f : rnd_float(&seed);
            in.n_adc = (uint32_t)k / 2u + ((rnd(&seed) % 16u) ? 0u : rnd(&seed));
            in.tick_adc = tick - rnd(&seed) % 500u;
            in.fault_pin = (rnd(&seed) % 50u) == 0u;
            tick += (rnd(&seed) % 8u) ? 250u : rnd(&seed);
            in.tick_now = tick;
            bc_ctrl_out o;
            memset(&o, 0, sizeof o);
            bc_bemf_step(&p, &s, &in, &o);
            ++n;
            if (!bounded(&o)) ++bad;
            int must = !isfinite(in.ref) || !(isfinite(in.v_dc) && in.v_dc > 0.0f && in.v_dc <= 30.0f);
            if (must && !(all_off(&o) && (o.flags & BC_FLAG_SAFE))) ++unsafe;
        }
    }
    CHECK(bad == 0, "fuzz: %d of %d outputs out of bounds", bad, n);
    CHECK(unsafe == 0, "fuzz: %d invalid inputs without the safe state", unsafe);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* closed loop against the kinematic rotor */

typedef struct {
    long late, timed, desync, n_closed_comm, handover_k, missing;
    uint32_t flags_or;
    double worst, mean_err;
    long n_err;
    double last_diag[BC_DIAG_N];
    long first_desync_k;
    uint32_t desync_flags;
} run_stats;

/* Run n samples; the rotor direct-started at its own speed (forced commutation at w, phase-locked with the
 * rotor), then closed loop. Checks every commutation after `settle` s: t_comm - t_zc (the crossing of the sector it
 * ends) against (pi/6 - adv)/w at the rotor's speed at the crossing (adv_fn: the expected advance). */
static run_stats run_kinematic(bc_bemf_params p, synth_bemf *g, long n, float ref, double settle, double adv)
{
    run_stats r;
    memset(&r, 0, sizeof r);
    r.first_desync_k = -1;
    r.handover_k = -1;
    bc_bemf_state s;
    CHECK(bc_bemf_init(&p, &s) == BC_OK, "init");
    for (long k = 0; k < n; ++k) {
        bc_ctrl_in in;
        sb_sample(g, k, &in);
        in.ref = ref;
        bc_ctrl_out o;
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        sb_apply(g, k, &o);
        if (getenv("BEMF_DEBUG_K") && labs(k - atol(getenv("BEMF_DEBUG_K"))) < 6)
            printf("    k %ld tk %u zc %u cnt %u %u %u tick %u %u %u has_at %u t_at %.3g flags 0x%x sector %.0f\n", k,
                   in.tick_now, in.zc_state, in.zc_count[0], in.zc_count[1], in.zc_count[2], in.zc_tick[0],
                   in.zc_tick[1], in.zc_tick[2], o.has_at, (double)o.t_at, o.flags, (double)o.diag[1]);
        r.flags_or |= o.flags;
        if (o.flags & BC_FLAG_COMM_LATE) ++r.late;
        if (o.has_at) ++r.timed;
        if ((o.flags & BC_FLAG_DESYNC) && r.first_desync_k < 0) {
            r.first_desync_k = k;
            r.desync_flags = o.flags;
        }
        if (o.flags & BC_FLAG_DESYNC) ++r.desync;
        if (r.handover_k < 0 && o.diag[0] == (float)BC_BEMF_CLOSED) r.handover_k = k;
        for (int j = 0; j < BC_DIAG_N; ++j) r.last_diag[j] = (double)o.diag[j];
    }
    /* commutations after the settling time: against the crossing of the sector they end */
    for (long i = 1; i < g->n_comm; ++i) {
        double tc = g->t_comm[i], t0 = g->t_comm[i - 1];
        if (t0 < settle) continue;
        int fl = g->comm_fl[i - 1];
        double tz = -1.0;
        for (long j = 0; j < g->n_zc; ++j)
            if (g->zc_x[j] == fl && g->t_zc[j] > t0 && g->t_zc[j] < tc) tz = g->t_zc[j];
        if (tz < 0.0) { /* the rotor's crossing was not in the sector the controller commanded */
            r.missing += 1;
            continue;
        }
        double w = fabs(sb_omega(g, tz));
        double e = (tc - tz) - (BC_PI / 6.0 - adv) / w;
        if (getenv("BEMF_DEBUG") && fabs(e) > 3e-7) {
            printf("  commutation %ld at %.7f: crossing %.7f, error %.3g s\n", i, tc, tz, e);
            for (long q = i - 3; q <= i + 1 && q < g->n_comm; ++q) printf("    comm %ld %.7f fl %d\n", q, g->t_comm[q], g->comm_fl[q]);
            for (long q = 0; q < g->n_zc; ++q)
                if (fabs(g->t_zc[q] - tc) < 8e-4) printf("    zc %.7f x %d\n", g->t_zc[q], g->zc_x[q]);
        }
        if (fabs(e) > r.worst) r.worst = fabs(e);
        r.mean_err += e;
        r.n_err += 1;
        r.n_closed_comm += 1;
    }
    if (r.n_err) r.mean_err /= (double)r.n_err;
    return r;
}

/* a rotor locked to the forced start: at the start of sector 2 (forward) or the end of sector 1 (backward) at T_s */
static void kin_rotor(synth_bemf *g, double w, int dir, double acc)
{
    g->w0 = dir * w;
    g->acc = acc;
    g->th0 = 5.0 * BC_PI / 6.0 - g->w0 * TS - 0.5 * acc * TS * TS;
}

static bc_bemf_params locked(int method, double w)
{
    bc_bemf_params p = params(method);
    p.align_time = 0.0f; /* direct start */
    p.ramp_w0 = (float)w;
    p.ramp_w1 = (float)w;
    p.ramp_accel = 0.0f;
    p.omega_stall = (float)(0.2 * w);
    return p;
}

static void test_commutation_instants(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 300.0; /* 300 Hz electrical: 556 us per sector, 22 samples */
    const double tau = 20e-6, tcmp = 1e-6;
    for (int dir = 1; dir >= -1; dir -= 2) {
        for (int ia = 0; ia < 3; ++ia) {
            double adv = (double)ia * 10.0 * DEG;
            bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
            p.tau_filter = (float)tau;
            p.t_comp = (float)tcmp;
            p.blank_time = (float)(2.0 * tau + tcmp); /* covers the comparator's view of the clamp's onset */
            p.adv_angle = (float)adv;
            sb_init(&g, TS, F_TICK, 1);
            kin_rotor(&g, w, dir, 0.0);
            g.d_cmp = atan(w * tau) / w + tcmp;
            g.demag = 30e-6;
            run_stats r = run_kinematic(p, &g, 2400, (float)dir * 0.5f, 0.02, adv);
            CHECK(r.handover_k > 0 && r.handover_k < 200 && r.desync == 0 && r.late == 0,
                  "dir %d adv %.0f: handover at sample %ld, %ld desyncs, %ld late", dir, adv / DEG, r.handover_k,
                  r.desync, r.late);
            CHECK(r.n_closed_comm > 60 && r.missing == 0 && r.worst < 2.5 * TICK,
                  "dir %d adv %.0f deg: %ld commutations 30 - adv after the crossing within %.3g s (mean %.3g)", dir,
                  adv / DEG, r.n_closed_comm, r.worst, r.mean_err);
            CHECK(fabs(r.last_diag[2] - dir * w) < 1e-3 * w && fabs(r.last_diag[5] - adv) < 1e-5,
                  "speed %.1f and advance %.4f reported", r.last_diag[2], r.last_diag[5]);
            CHECK(fabs(r.last_diag[3]) < 0.2 * DEG, "commutation error %.4f rad", r.last_diag[3]);
            CHECK(fabs(r.last_diag[4] - 30e-6) < 3.0 * TICK, "demagnetisation measured %.4g s (30 us)",
                  r.last_diag[4]);
            if (ia == 0 && dir == 1) printf("test_bemf: 300 Hz, 20 us filter, 1 us comparator: worst %.2g s\n", r.worst);
        }
    }
    /* advance per speed and from the demagnetisation: adv = 5 deg + w 10 us + 0.5 x demag angle (600 Hz) */
    {
        const double w = 2.0 * BC_PI * 600.0;
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        p.adv_angle = (float)(5.0 * DEG);
        p.adv_time = 10e-6f;
        p.adv_demag = 0.5f;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = 40e-6;
        double adv = 5.0 * DEG + w * 10e-6 + 0.5 * w * 40e-6;
        run_stats r = run_kinematic(p, &g, 1200, 0.5f, 0.01, adv);
        CHECK(r.worst < 2.5 * TICK && fabs(r.last_diag[5] - adv) < 5e-4,
              "automatic advance %.4f rad (expected %.4f): worst %.3g s", r.last_diag[5], adv, r.worst);
    }
    /* two PWM periods per commutation (a drone motor at full speed): every commutation timed, none late */
    {
        const double wf = (BC_PI / 3.0) / (4.0 * TS);
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, wf);
        p.n_handover = 12;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, wf, 1, 0.0);
        g.demag = 5e-6;
        run_stats r = run_kinematic(p, &g, 2000, 0.9f, 0.01, 0.0);
        CHECK(r.desync == 0 && r.late == 0 && r.n_closed_comm > 300 && r.worst < 2.5 * TICK,
              "4 samples per sector: %ld commutations, %ld late, worst %.3g s", r.n_closed_comm, r.late, r.worst);
    }
}

static void test_ramping_speed(void)
{
    static synth_bemf g;
    /* from 2 pi 300 to about 2 pi 700 rad/s in 0.1 s: the commutation error is the interval's change over a sector */
    const double w = 2.0 * BC_PI * 300.0, acc = 2.0 * BC_PI * 4000.0;
    for (int dir = 1; dir >= -1; dir -= 2) {
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        p.n_handover = 3;
        p.jump_max = 1.5f;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, dir, dir * acc);
        g.demag = 20e-6;
        run_stats r = run_kinematic(p, &g, 4000, (float)dir * 0.5f, 0.005, 0.0);
        /* the last interval T60 predicts the next half interval: late by (T_prev - T_next) / 2 ~ acc T60^2 / (2 w) */
        double w1 = w + acc * 0.1, t60 = (BC_PI / 3.0) / w;
        double bound = acc * t60 * t60 / (2.0 * w) * 0.5 + 3.0 * TICK;
        CHECK(r.desync == 0 && r.n_closed_comm > 200 && r.worst < bound,
              "dir %d, accelerating to %.0f rad/s: %ld commutations within %.3g s (bound %.3g, mean %.3g)", dir, w1,
              r.n_closed_comm, r.worst, bound, r.mean_err);
    }
}

/* the back-EMF constant of the ADC tests: 4 V at 600 Hz, inside the 12 V bus (the sample's value stays V/2 + e) */
#define KE_ADC (4.0 / (2.0 * BC_PI * 600.0))

static void test_adc_methods(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 300.0; /* 556 us per sector: 11 conversions */
    const double tau = 20e-6;
    for (int method = BC_BEMF_ADC; method <= BC_BEMF_INTEGRATE; ++method) {
        for (int ia = 0; ia < 2; ++ia) {
            double adv = (double)ia * 15.0 * DEG;
            bc_bemf_params p = locked(method, w);
            p.tau_filter = (float)tau;
            p.blank_time = 40e-6f;
            p.adv_angle = (float)adv;
            p.n_samples = ia ? 1 : 2; /* 15 deg: a crossing seen up to one conversion late leaves 89 us */
            p.int_limit = (float)(KE_ADC * BC_PI / 12.0);
            sb_init(&g, TS, F_TICK, 1);
            g.ke = KE_ADC;
            kin_rotor(&g, w, 1, 0.0);
            g.d_adc = atan(w * tau) / w;
            g.demag = 60e-6;
            run_stats r = run_kinematic(p, &g, 2400, 0.5f, 0.01, adv);
            CHECK(r.desync == 0 && r.late == 0 && r.n_closed_comm > 80 && r.worst < 3.0 * TICK,
                  "%s adv %.0f deg: %ld commutations within %.3g s of 30 - adv after the crossing (mean %.3g)",
                  method == BC_BEMF_ADC ? "ADC" : "integration", adv / DEG, r.n_closed_comm, r.worst, r.mean_err);
            printf("test_bemf: %s, %.0f deg advance: worst %.2g s over %ld commutations\n",
                   method == BC_BEMF_ADC ? "ADC crossing" : "back-EMF integration", adv / DEG, r.worst, r.n_closed_comm);
            CHECK(fabs(r.last_diag[4] - 60e-6) <= 2.0 * TS, "ADC demagnetisation %.3g s (60 us, one conversion)",
                  r.last_diag[4]);
        }
    }
    /* the integral threshold does not depend on speed: the same int_limit at twice the speed */
    bc_bemf_params p = locked(BC_BEMF_INTEGRATE, 2.0 * w);
    p.tau_filter = (float)tau;
    p.n_samples = 1;
    p.blank_time = 40e-6f;
    p.int_limit = (float)(KE_ADC * BC_PI / 12.0);
    sb_init(&g, TS, F_TICK, 1);
    g.ke = KE_ADC;
    kin_rotor(&g, 2.0 * w, 1, 0.0);
    g.d_adc = atan(2.0 * w * tau) / (2.0 * w);
    g.demag = 30e-6;
    run_stats r = run_kinematic(p, &g, 2400, 0.5f, 0.01, 0.0);
    CHECK(r.desync == 0 && r.n_closed_comm > 150 && r.worst < 3.0 * TICK,
          "integration at 600 Hz, same threshold: worst %.3g s", r.worst);
}

/* The floating phase conducting outside the demagnetisation: a current its back-EMF drove in the PWM off-time that
 * has not decayed by the conversion (high-side or synchronous chopping) holds its terminal at the rail on its
 * back-EMF's side. Here beyond 1.5 degrees before its crossing and 12 degrees after it: the last pre sample is mostly
 * clamped (its value no back-EMF, its sign right), the integration runs over clamped samples. Skipping their values
 * (the crossing along the free samples' line, the integral over a gap by the trapezoid of its free ends, the instant
 * predicted from the last free sample) the commutation stays at 30 - adv degrees after the crossing, exact for the
 * trapezoid's linear ramp. */
static void test_adc_offtime_clamp(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 300.0;
    for (int method = BC_BEMF_ADC; method <= BC_BEMF_INTEGRATE; ++method) {
        for (int ns = 1; ns <= 2; ++ns) {
            bc_bemf_params p = locked(method, w);
            p.blank_time = 40e-6f;
            p.n_samples = ns;
            p.int_limit = (float)(KE_ADC * BC_PI / 12.0);
            sb_init(&g, TS, F_TICK, 1);
            g.ke = KE_ADC;
            g.clamp_pre = 0.05;
            g.clamp_post = 0.4;
            kin_rotor(&g, w, 1, 0.0);
            g.demag = 60e-6;
            run_stats r = run_kinematic(p, &g, 2400, 0.5f, 0.01, 0.0);
            CHECK(r.desync == 0 && r.late == 0 && r.n_closed_comm > 80 && r.worst < 3.0 * TICK,
                  "%s, n_samples %d, clamped samples: %ld commutations within %.3g s (mean %.3g)",
                  method == BC_BEMF_ADC ? "ADC" : "integration", ns, r.n_closed_comm, r.worst, r.mean_err);
            printf("test_bemf: %s, n_samples %d, off-time clamp: worst %.2g s over %ld commutations\n",
                   method == BC_BEMF_ADC ? "ADC crossing" : "back-EMF integration", ns, r.worst, r.n_closed_comm);
        }
    }
}

/* ------------------------------------------------------------------------------------------------------------ */
/* the clamp, blanking, filters and desyncs */

static void test_clamp_and_blanking(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 600.0;
    for (int blanking = 0; blanking < 2; ++blanking) {
        /* a clamp of 20 degrees (93 us) and a window opening after 5 degrees, during it: the comparator shows the
         * post level there (a naive reader would commutate on it), the controller waits for the edge */
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        p.blanking = blanking;
        p.blank_angle = (float)(5.0 * DEG);
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = 20.0 * DEG / w;
        run_stats r = run_kinematic(p, &g, 1500, 0.5f, 0.01, 0.0);
        /* the level at each window opening: the clamp's (the post level: the physics the controller relies on) */
        long at_post = 0, n_open = 0;
        for (long i = 0; i + 1 < g.n_comm; ++i) {
            double t_open = g.t_comm[i] + 5.0 * DEG / w;
            int fl = g.comm_fl[i];
            int q = sb_seg_at(&g, t_open);
            if (fl >= 0 && g.seg_fl[q] == fl && t_open < g.t_comm[i + 1]) {
                int post = 0;
                for (int sec = 0; sec < 6; ++sec) { /* the sector of this pair: odd sectors cross upward */
                    int pp, nn;
                    (void)bc_sector_phases(sec, &pp, &nn);
                    if (pp == g.seg_pos[q] && nn == g.seg_neg[q]) post = sec & 1;
                }
                ++n_open;
                at_post += sb_level(&g, fl, t_open) == post && g.seg_cl[q] == post;
            }
        }
        CHECK(n_open > 80 && at_post == n_open, "blanking %d: the clamp shows the post level at %ld of %ld openings",
              blanking, at_post, n_open);
        CHECK(r.desync == 0 && r.n_closed_comm > 80 && r.worst < 2.5 * TICK,
              "blanking %d: no false crossing, %ld commutations within %.3g s", blanking, r.n_closed_comm, r.worst);
        CHECK(fabs(r.last_diag[4] - 20.0 * DEG / w) < 3.0 * TICK, "demagnetisation %.4g s measured (%.4g)",
              r.last_diag[4], 20.0 * DEG / w);
    }
    /* the window opening before the comparator shows the clamp (blanking shorter than its filter delay): with the
     * fixed blanking the clamp's onset is taken for a crossing (the controller commutates at once, early) */
    {
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        p.blanking = BC_BEMF_BLANK_FIXED;
        p.tau_filter = 20e-6f;
        p.blank_time = 2e-6f;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.d_cmp = atan(w * 20e-6) / w;
        g.demag = 30e-6;
        run_stats r = run_kinematic(p, &g, 600, 0.5f, 0.0, 0.0);
        CHECK(r.handover_k < 0 || r.desync > 0 || r.missing > 0 || r.worst > 10e-6,
              "a blanking shorter than the filter's view of the clamp: false crossings (handover %ld, %ld desyncs, %ld "
              "sectors without their crossing, worst %.3g s)", r.handover_k, r.desync, r.missing, r.worst);
    }
}

static void test_min_pulse(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 600.0, t60 = (BC_PI / 3.0) / w;
    for (int filt = 0; filt < 2; ++filt) {
        /* a 30 us pulse of the floating phase's comparator to the post level 60 us into a sector (13 degrees, in
         * the pre level: the real crossing is at 139 us), in closed loop */
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        p.min_pulse = filt ? 40e-6f : 0.0f;
        p.jump_max = 1.5f;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = 20e-6;
        double n = floor((0.02 - TS) / (6.0 * t60));
        double t_sector = TS + n * 6.0 * t60; /* sector 2 begins (its floating phase: a) */
        g.glitch_x = 0;
        g.glitch_t = t_sector + 60e-6;
        g.glitch_len = 30e-6;
        run_stats r = run_kinematic(p, &g, 1600, 0.5f, 1e9, 0.0);
        if (filt) {
            CHECK(r.desync == 0, "min_pulse 40 us: the 30 us pulse filtered (%ld desyncs)", r.desync);
        } else {
            double t_d = (double)r.first_desync_k * TS;
            /* the false crossing shortens T60 and commutates 78 us early: the next crossing comes after the
             * timeout (1.5 x the short interval) or, if it came before, with an interval ratio out of bounds */
            CHECK(r.desync >= 1 && (r.desync_flags & (BC_FLAG_ZC_JUMP | BC_FLAG_ZC_TIMEOUT)) && t_d > g.glitch_t &&
                      t_d < g.glitch_t + 3.0 * t60,
                  "no filter: the pulse is a false crossing and the drive desyncs (flags 0x%x at %.5f s, pulse at "
                  "%.5f)", r.desync_flags, t_d, g.glitch_t);
        }
    }
}

static void test_desyncs(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 600.0;
    /* a clamp outlasting the crossing (40 degrees) from commutation 60 on: the crossing hidden */
    {
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = 20e-6;
        g.demag_long = 40.0 * DEG / w;
        g.n_long = 60;
        run_stats r = run_kinematic(p, &g, 1500, 0.5f, 1e9, 0.0);
        double t_long = g.n_comm > 60 ? g.t_comm[60] : 1.0;
        CHECK(r.first_desync_k > 0 && (r.desync_flags & BC_FLAG_ZC_HIDDEN) && !(r.desync_flags & BC_FLAG_ZC_TIMEOUT),
              "clamp outlasting the crossing: desync, flags 0x%x", r.desync_flags);
        double t_d = (double)(double)r.first_desync_k * TS;
        CHECK(t_d > t_long && t_d < t_long + 2.0 * (BC_PI / 3.0) / w, "detected %.1f us after the long clamp began",
              (t_d - t_long) * 1e6);
        CHECK(r.last_diag[7] == (double)BC_BEMF_REASON_HIDDEN, "reason in diag 7: %.0f", r.last_diag[7]);
        printf("test_bemf: a 40-degree clamp from commutation 60: desync ZC_HIDDEN %.1f us after it began\n",
               (t_d - t_long) * 1e6);
        /* the next miss allowed: a blind commutation instead, then the desync (the clamp stays long) */
        p.miss_max = 1;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = 20e-6;
        g.demag_long = 40.0 * DEG / w;
        g.n_long = 60;
        r = run_kinematic(p, &g, 1500, 0.5f, 1e9, 0.0);
        CHECK(r.late >= 1 && (r.desync_flags & BC_FLAG_ZC_HIDDEN) && (double)(double)r.first_desync_k * TS > t_d,
              "miss_max 1: %ld blind commutation(s) first, desync at %.4f s", r.late, (double)r.first_desync_k * TS);
        /* ... and the same clamp once only: the blind commutation carries the drive through it */
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = 20e-6;
        g.demag_long = 40.0 * DEG / w;
        g.n_long = 60;
        bc_bemf_state s;
        (void)bc_bemf_init(&p, &s);
        long blind = 0, des = 0;
        for (long k = 0; k < 1500; ++k) {
            bc_ctrl_in in;
            if (g.n_comm > 60) g.n_long = 1000000; /* the long clamp on commutation 60 only */
            sb_sample(&g, k, &in);
            in.ref = 0.5f;
            bc_ctrl_out o;
            memset(&o, 0, sizeof o);
            bc_bemf_step(&p, &s, &in, &o);
            sb_apply(&g, k, &o);
            blind += (o.flags & BC_FLAG_COMM_LATE) != 0u;
            des += (o.flags & BC_FLAG_DESYNC) != 0u;
        }
        CHECK(blind == 1 && des == 0, "one hidden crossing, miss_max 1: %ld blind commutation, %ld desyncs", blind,
              des);
    }
    /* the rotor stops: it left the clamp, no crossing follows */
    {
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = 20e-6;
        g.t_freeze = 0.02 + 0.3 * (BC_PI / 3.0) / w;
        run_stats r = run_kinematic(p, &g, 1200, 0.5f, 1e9, 0.0);
        CHECK(r.first_desync_k > 0 && (r.desync_flags & BC_FLAG_ZC_TIMEOUT),
              "rotor stopped: desync with ZC_TIMEOUT (flags 0x%x)", r.desync_flags);
        double t_d = (double)(double)r.first_desync_k * TS;
        CHECK(t_d > g.t_freeze && t_d < g.t_freeze + 2.0 * (BC_PI / 3.0) / w, "within the timeout: %.1f us after",
              (t_d - g.t_freeze) * 1e6);
        CHECK(r.last_diag[0] == (double)BC_BEMF_STOP && r.last_diag[7] == (double)BC_BEMF_REASON_TIMEOUT,
              "STOP, reason TIMEOUT");
    }
    /* a slow deceleration below the stall speed */
    {
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        p.omega_stall = (float)(0.5 * w);
        p.jump_max = 1.5f;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, -0.5 * w / 0.1); /* half the speed in 0.1 s */
        g.demag = 10e-6;
        run_stats r = run_kinematic(p, &g, 6000, 0.5f, 1e9, 0.0);
        CHECK(r.first_desync_k > 0 && (r.desync_flags & BC_FLAG_STALL), "deceleration: STALL (flags 0x%x)",
              r.desync_flags);
        double t_d = (double)(double)r.first_desync_k * TS;
        CHECK(fabs(sb_omega(&g, t_d) - 0.5 * w) < 0.02 * w, "at %.1f rad/s (stall %.1f)", sb_omega(&g, t_d), 0.5 * w);
    }
}

static void test_late_commutation(void)
{
    static synth_bemf g;
    /* 26 degrees of advance at 300 Hz: the commutation is due 4 degrees (37 us) after the crossing; the crossing is
     * seen at the next sample and acted on by the output after it, 25 to 50 us after the crossing: about half the
     * instants are already past. Those commutate at once, at the start of the output's interval, and say so; the
     * others are timed to the tick. */
    const double w = 2.0 * BC_PI * 300.0, adv = 26.0 * DEG;
    bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
    p.adv_angle = (float)adv;
    sb_init(&g, TS, F_TICK, 1);
    kin_rotor(&g, w, 1, 0.0);
    g.demag = 20e-6;
    bc_bemf_state s;
    (void)bc_bemf_init(&p, &s);
    long late = 0, timed = 0, late_ok = 0, timed_ok = 0, des = 0;
    for (long k = 0; k < 4000; ++k) {
        bc_ctrl_in in;
        sb_sample(&g, k, &in);
        in.ref = 0.5f;
        bc_ctrl_out o;
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        long before = g.n_comm;
        sb_apply(&g, k, &o);
        des += (o.flags & BC_FLAG_DESYNC) != 0u;
        if (o.diag[0] != (float)BC_BEMF_CLOSED || g.n_comm != before + 1 || before < 1) continue;
        double tc = g.t_comm[before], tz = -1.0;
        for (long j = 0; j < g.n_zc; ++j)
            if (g.zc_x[j] == g.comm_fl[before - 1] && g.t_zc[j] > g.t_comm[before - 1] && g.t_zc[j] < tc) tz = g.t_zc[j];
        double due = tz + (BC_PI / 6.0 - adv) / w;
        if (o.flags & BC_FLAG_COMM_LATE) {
            ++late;
            late_ok += fabs(tc - (double)(k + 1) * TS) < 1e-12 && due < tc;
        } else {
            ++timed;
            timed_ok += fabs(tc - due) < 2.5 * TICK;
        }
    }
    printf("test_bemf: 26 deg advance at 300 Hz: %ld commutations late (at the output's start), %ld timed\n", late,
           timed);
    CHECK(des == 0 && late > 30 && timed > 30 && late_ok == late && timed_ok == timed,
          "26 deg at 300 Hz: %ld late commutations (%ld at the output's start, after the instant), %ld timed (%ld within "
          "2.5 ticks), %ld desyncs", late, late_ok, timed, timed_ok, des);
}

static void test_ramp_follows_crossings(void)
{
    static synth_bemf g;
    /* the forced ramp at half the rotor's speed (a rotor faster than the ramp): each crossing commutates its forced
     * sector 30 degrees after it, the drive follows the rotor and hands over; the ramp's duty is the V/f law */
    const double w = 2.0 * BC_PI * 300.0;
    bc_bemf_params p = locked(BC_BEMF_COMPARATOR, 0.5 * w);
    p.omega_stall = (float)(0.2 * w);
    p.ramp_vf = 1e-4f;
    p.ramp_duty = 0.05f;
    sb_init(&g, TS, F_TICK, 1);
    kin_rotor(&g, w, 1, 0.0);
    g.demag = 20e-6;
    bc_bemf_state s;
    (void)bc_bemf_init(&p, &s);
    long k_closed = -1, bad_duty = 0, n_ramp = 0;
    for (long k = 0; k < 2400; ++k) {
        bc_ctrl_in in;
        sb_sample(&g, k, &in);
        in.ref = 0.5f;
        bc_ctrl_out o;
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        sb_apply(&g, k, &o);
        if (o.diag[0] == (float)BC_BEMF_RAMP) {
            ++n_ramp;
            /* V/f at the forced speed, which is never above the estimate (max of it and the crossings' speed) */
            double d6 = (double)o.diag[6];
            if (d6 < 0.05 + 1e-4 * 0.99 * (double)p.ramp_w0 - 1e-6 || d6 > 0.05 + 1e-4 * fabs((double)o.diag[2]) + 1e-6 ||
                d6 > 0.05 + 1e-4 * (double)p.ramp_w1 + 1e-6)
                ++bad_duty;
        }
        if (k_closed < 0 && o.diag[0] == (float)BC_BEMF_CLOSED) k_closed = k;
    }
    long missing = 0, n = 0;
    double worst = 0.0;
    for (long i = 1; i < g.n_comm; ++i) {
        double t0 = g.t_comm[i - 1], tc = g.t_comm[i], tz = -1.0;
        if (t0 < 2e-3) continue; /* after the first two sectors (the first has no crossing interval) */
        for (long j = 0; j < g.n_zc; ++j)
            if (g.zc_x[j] == g.comm_fl[i - 1] && g.t_zc[j] > t0 && g.t_zc[j] < tc) tz = g.t_zc[j];
        if (tz < 0.0) {
            ++missing;
            continue;
        }
        double e = fabs((tc - tz) - (BC_PI / 6.0) / w);
        if (e > worst) worst = e;
        ++n;
    }
    CHECK(k_closed > 0 && missing == 0 && n > 80 && worst < 2.5 * TICK,
          "ramp at half the rotor's speed: handover at sample %ld, %ld commutations 30 deg after their crossing "
          "within %.3g s, %ld sectors without one", k_closed, n, worst, missing);
    CHECK(n_ramp > 0 && bad_duty == 0, "V/f ramp duty 0.05 + 1e-4 Omega_ol in %ld of %ld ramp samples", n_ramp - bad_duty,
          n_ramp);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* start-up on a dynamic rotor */

typedef struct {
    long k_closed, k_desync;
    uint32_t flags_or, desync_flags;
    double w_end;
    long n_samples_open;
} start_stats;

static start_stats run_dynamic(bc_bemf_params p, synth_bemf *g, long n, const float *ref, long n_ref)
{
    start_stats r;
    memset(&r, 0, sizeof r);
    r.k_closed = r.k_desync = -1;
    bc_bemf_state s;
    CHECK(bc_bemf_init(&p, &s) == BC_OK, "init");
    for (long k = 0; k < n; ++k) {
        bc_ctrl_in in;
        sb_sample(g, k, &in);
        in.ref = ref[k * n_ref / n];
        bc_ctrl_out o;
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        sb_apply(g, k, &o);
        if (!bounded(&o)) CHECK(0, "bounded at %ld", k);
        r.flags_or |= o.flags;
        if (o.flags & BC_FLAG_OPEN_LOOP) ++r.n_samples_open;
        if (r.k_closed < 0 && o.diag[0] == (float)BC_BEMF_CLOSED) r.k_closed = k;
        if (r.k_desync < 0 && (o.flags & BC_FLAG_DESYNC)) {
            r.k_desync = k;
            r.desync_flags = o.flags;
        }
    }
    r.w_end = g->w;
    return r;
}

static bc_bemf_params start_params(int method)
{
    bc_bemf_params p = params(method);
    p.omega_stall = 20.0f;
    p.ramp_w0 = 30.0f;
    p.ramp_w1 = 150.0f;
    p.ramp_accel = 4000.0f;
    p.ramp_duty = 0.3f;
    p.align_time = 0.1f;
    p.align_duty = 0.2f;
    p.n_handover = 6;
    p.blank_angle = (float)(10.0 * DEG);
    return p;
}

/* the dynamic rotor of the start-up tests: 1000 rad/s^2 per A and unit torque shape, 0.2 Ohm line, 50 /s viscous,
 * 500 rad/s^2 friction; no-load speed 600 d rad/s (ke 0.01 V s/rad, 12 V) */
static void dyn_rotor(synth_bemf *g, double th0, double load)
{
    sb_dynamic(g, th0, 0.0, 1000.0, 0.2, 50.0, load);
}

static void test_start_up(void)
{
    static synth_bemf g;
    for (int method = 0; method < 3; method += 1) {
        for (int dir = 1; dir >= -1; dir -= 2) {
            bc_bemf_params p = start_params(method);
            sb_init(&g, TS, F_TICK, 1);
            dyn_rotor(&g, 1.0 + 2.0 * (double)method, 500.0);
            g.demag = 30e-6;
            float ref = (float)dir * 0.5f;
            start_stats r = run_dynamic(p, &g, 12000, &ref, 1); /* 0.3 s */
            /* no load torque beyond friction: at duty 0.5 the speed settles where 2 ke w = 0.5 V - r2 i */
            CHECK(r.k_closed > 0 && r.k_desync < 0 && dir * r.w_end > 200.0,
                  "method %d dir %d: closed loop at %.1f ms, no desync (flags 0x%x), %.0f rad/s at the end", method,
                  dir, (double)r.k_closed * TS * 1e3, r.flags_or, r.w_end);
            CHECK(r.n_samples_open == r.k_closed, "OPEN_LOOP raised exactly until the handover (%ld, %ld)",
                  r.n_samples_open, r.k_closed);
            if (method == 0 && dir == 1) printf("test_bemf: start-up: closed loop after %.1f ms, %.0f rad/s at 0.3 s\n",
                                                (double)r.k_closed * TS * 1e3, r.w_end);
        }
    }
    /* a direct start (no alignment), the rotor anywhere */
    for (int j = 0; j < 6; ++j) {
        bc_bemf_params p = start_params(BC_BEMF_COMPARATOR);
        p.align_time = 0.0f;
        sb_init(&g, TS, F_TICK, 1);
        dyn_rotor(&g, (double)j * 1.047 + 0.3, 500.0);
        g.demag = 30e-6;
        float ref = 0.5f;
        start_stats r = run_dynamic(p, &g, 12000, &ref, 1);
        CHECK(r.k_closed > 0 && r.w_end > 200.0, "direct start from %.2f rad: closed loop at %.1f ms (flags 0x%x), "
              "%.0f rad/s", (double)j * 1.047 + 0.3, (double)r.k_closed * TS * 1e3, r.flags_or, r.w_end);
    }
    /* a rotor that cannot move (load above the start-up torque): START_FAIL, then retries */
    {
        bc_bemf_params p = start_params(BC_BEMF_COMPARATOR);
        p.restart_wait = 0.005f;
        sb_init(&g, TS, F_TICK, 1);
        dyn_rotor(&g, 1.0, 1e6);
        g.demag = 30e-6;
        float ref = 0.5f;
        start_stats r = run_dynamic(p, &g, 12000, &ref, 1);
        double t_ramp = 0.1 + (150.0 - 30.0) / 4000.0;
        CHECK(r.k_desync > 0 && (r.desync_flags & BC_FLAG_START_FAIL) && r.k_closed < 0,
              "stuck rotor: START_FAIL (flags 0x%x) at %.1f ms (ramp %.1f ms + %d sectors at 150 rad/s)",
              r.desync_flags, (double)r.k_desync * TS * 1e3, t_ramp * 1e3, p.ramp_hold);
        double t_d = (double)r.k_desync * TS;
        CHECK(t_d > t_ramp && t_d < t_ramp + (double)p.ramp_hold * (BC_PI / 3.0) / 150.0 + 1e-3,
              "START_FAIL after the ramp, within %d sectors at its end speed (%.4f s)", p.ramp_hold, t_d);
        CHECK(r.n_samples_open > 2 * (long)(t_ramp / TS), "and a second attempt (%ld open-loop samples)",
              r.n_samples_open);
    }
}

static void test_stop_and_reverse(void)
{
    static synth_bemf g;
    bc_bemf_params p = start_params(BC_BEMF_COMPARATOR);
    p.restart_wait = 0.02f;
    p.restart_max = 0.5f;
    sb_init(&g, TS, F_TICK, 1);
    dyn_rotor(&g, 1.0, 500.0);
    g.demag = 30e-6;
    bc_bemf_state s;
    (void)bc_bemf_init(&p, &s);
    double w_fwd = 0.0, w_stop = 0.0;
    long k_stopped = -1, k_rev = -1;
    int reason_flags = 0;
    for (long k = 0; k < 40000; ++k) { /* 0.3 s forward, 0.1 s at 0, then reverse */
        double t = (double)k * TS;
        float ref = t < 0.3 ? 0.5f : (t < 0.4 ? 0.0f : -0.5f);
        bc_ctrl_in in;
        sb_sample(&g, k, &in);
        in.ref = ref;
        bc_ctrl_out o;
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        sb_apply(&g, k, &o);
        reason_flags |= (int)(o.flags & (BC_FLAG_DESYNC | BC_FLAG_ZC_TIMEOUT | BC_FLAG_ZC_HIDDEN | BC_FLAG_ZC_JUMP |
                                         BC_FLAG_STALL | BC_FLAG_START_FAIL));
        if (k == (long)(0.3 / TS) - 1) w_fwd = g.w;
        if (t >= 0.3 && t < 0.4) {
            if (!all_off(&o)) k_stopped = -2;
            else if (k_stopped == -1) k_stopped = k;
        }
        if (k == (long)(0.4 / TS) - 1) w_stop = g.w;
        if (t >= 0.4 && k_rev < 0 && o.diag[0] == (float)BC_BEMF_ALIGN) k_rev = k;
    }
    CHECK(w_fwd > 200.0 && k_stopped == lround(0.3 / TS), "forward at %.0f rad/s; legs off from the stop (%ld)", w_fwd,
          k_stopped);
    CHECK(reason_flags == 0, "a stop and a reverse are not desyncs (flags 0x%x)", reason_flags);
    CHECK(k_rev > 0 && g.w < -200.0, "reverse: alignment at %.3f s (the rotor coasting at %.0f rad/s at 0.4 s), "
          "%.0f rad/s at the end", (double)k_rev * TS, w_stop, g.w);
}

static void test_throttle_and_limit(void)
{
    static synth_bemf g;
    /* throttle steps 0.2 -> 0.8 with a 1 %/ms ramp (10 /s): the duty climbs 2.5e-4 per sample */
    bc_bemf_params p = start_params(BC_BEMF_COMPARATOR);
    p.duty_rate = 10.0f;
    sb_init(&g, TS, F_TICK, 1);
    dyn_rotor(&g, 1.0, 500.0);
    g.demag = 30e-6;
    bc_bemf_state s;
    (void)bc_bemf_init(&p, &s);
    float prev = -1.0f, worst = 0.0f;
    long k_step = (long)(0.3 / TS), k_full = -1;
    for (long k = 0; k < 20000; ++k) {
        bc_ctrl_in in;
        sb_sample(&g, k, &in);
        in.ref = k < k_step ? 0.2f : 0.8f;
        bc_ctrl_out o;
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        sb_apply(&g, k, &o);
        if (k >= k_step && o.diag[0] == (float)BC_BEMF_CLOSED && prev >= 0.0f) {
            float d = o.diag[6] - prev;
            if (d > worst) worst = d;
            if (k_full < 0 && o.diag[6] >= 0.8f) k_full = k;
        }
        prev = o.diag[0] == (float)BC_BEMF_CLOSED ? o.diag[6] : -1.0f;
    }
    CHECK(worst <= 10.0f * (float)TS * 1.0001f && k_full > 0 && fabs((double)(k_full - k_step) * TS - 0.06) < 1e-3,
          "throttle ramp: at most %.3g per sample, 0.2 -> 0.8 in %.1f ms (60 ms)", (double)worst,
          (double)(k_full - k_step) * TS * 1e3);
    /* current limit, an alignment at duty 1 limited to 10 A: 20 A measured, k_limit 1 /(A s): the duty falls by
     * 1 x 10 x T_s per sample */
    p = start_params(BC_BEMF_COMPARATOR);
    p.use_current = 1;
    p.align_duty = 1.0f;
    p.i_limit = 10.0f;
    p.k_limit = 1.0f;
    (void)bc_bemf_init(&p, &s);
    bc_ctrl_in in;
    memset(&in, 0, sizeof in);
    in.v_dc = 12.0f;
    in.i_mask = 3u;
    in.i_abc[0] = 20.0f;
    in.i_abc[1] = -20.0f;
    in.ref = 0.5f;
    bc_ctrl_out o;
    for (int k = 0; k < 400; ++k) {
        in.tick_now = (uint32_t)(k * 250);
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
    }
    CHECK(fabs((double)o.diag[6] - (1.0 - 400.0 * 10.0 * TS)) < 1e-4 && o.diag[0] == (float)BC_BEMF_ALIGN,
          "limiter: duty %.4f after 400 samples at twice the limit (%.4f)", (double)o.diag[6], 1.0 - 400.0 * 10.0 * TS);
    in.i_abc[0] = 5.0f;
    in.i_abc[1] = -5.0f;
    for (int k = 400; k < 480; ++k) {
        in.tick_now = (uint32_t)(k * 250);
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
    }
    CHECK(fabs((double)o.diag[6] - (0.9 + 80.0 * 5.0 * TS)) < 1e-4, "limiter recovers below the limit: %.4f",
          (double)o.diag[6]);
}

/* the start-up's cycle-by-cycle current limit (i_start) and the ramp's duty law with ramp_tau */
static void test_start_current_limit(void)
{
    bc_bemf_params p = start_params(BC_BEMF_COMPARATOR);
    p.use_current = 1;
    p.i_start = 10.0f;
    p.ramp_tau = 2e-3f;
    p.ramp_vf = 1e-4f;
    bc_bemf_state s;
    CHECK(bc_bemf_init(&p, &s) == BC_OK, "init with i_start and ramp_tau");
    bc_ctrl_in in;
    memset(&in, 0, sizeof in);
    in.v_dc = 12.0f;
    in.i_mask = 3u;
    in.ref = 0.5f;
    bc_ctrl_out o;
    long off_hi = 0, on_lo = 0, sat_hi = 0, n_hi = 0, n_lo = 0, bad_ramp = 0, n_ramp = 0;
    double m_prev = 0.0;
    long k_end = (long)((double)p.align_time / TS) + 400;
    for (long k = 0; k < k_end; ++k) {
        int hi = (int)((k / 7) % 2); /* alternately above and below the limit, in ALIGN and then in RAMP */
        in.i_abc[0] = hi ? 12.0f : 8.0f;
        in.i_abc[1] = -in.i_abc[0];
        in.tick_now = (uint32_t)(k * 250);
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        if (o.diag[0] != (float)BC_BEMF_ALIGN && o.diag[0] != (float)BC_BEMF_RAMP) continue;
        if (hi) {
            ++n_hi;
            off_hi += all_off(&o) && o.has_at == 0u;
            sat_hi += (o.flags & BC_FLAG_SATURATED) != 0u;
        } else {
            ++n_lo;
            on_lo += !all_off(&o) && (o.flags & BC_FLAG_SATURATED) == 0u;
            if (o.diag[0] == (float)BC_BEMF_RAMP) { /* m = ramp_duty sqrt(1 + (w ramp_tau)^2) + ramp_vf w, w in
                                                      * [w0, w1] = [30, 150] rad/s, the forced speed never falling */
                ++n_ramp;
                double lo = 0.3 * sqrt(1.0 + 0.06 * 0.06) + 1e-4 * 30.0;
                double top = 0.3 * sqrt(1.0 + 0.3 * 0.3) + 1e-4 * 150.0;
                double m = (double)o.diag[6];
                if (!(m >= lo - 1e-6 && m <= top + 1e-6 && m >= m_prev - 1e-6)) ++bad_ramp;
                m_prev = m;
            }
        }
    }
    CHECK(n_hi > 100 && off_hi == n_hi && sat_hi == n_hi,
          "start-up current limit: every switch off and SATURATED in %ld and %ld of %ld samples above i_start", off_hi,
          sat_hi, n_hi);
    CHECK(n_lo > 100 && on_lo == n_lo, "below i_start the legs driven in %ld of %ld samples", on_lo, n_lo);
    CHECK(n_ramp > 50 && bad_ramp == 0 && m_prev > 0.3 * sqrt(1.0 + 0.06 * 0.06) + 3e-3 + 1e-3,
          "ramp duty ramp_duty sqrt(1 + (w ramp_tau)^2) + ramp_vf w, rising within the sector: %ld of %ld, last %.4f",
          n_ramp - bad_ramp, n_ramp, m_prev);
    p.ramp_tau = -1e-3f;
    CHECK(bc_bemf_init(&p, &s) == BC_ERR_PARAM, "ramp_tau < 0 refused");
    p.ramp_tau = 0.0f;
    p.i_start = NAN;
    CHECK(bc_bemf_init(&p, &s) == BC_ERR_PARAM, "i_start NaN refused");
}

/* the inverter's share d_diode (2): the start-up's duties and the speed-dependent limit are an ideal inverter's; the
 * duty applied is d_diode + (1 - d_diode) x that, sample by sample the same run otherwise (a rotor that does not move:
 * the same inputs reach both controllers), and the chopping leg's duty (high-side pattern) is that duty */
static void test_diode_share(void)
{
    bc_bemf_params p0 = start_params(BC_BEMF_COMPARATOR);
    p0.chop = BC_CHOP_HIGH;
    p0.ramp_vf = 1e-4f;
    p0.ramp_tau = 2e-3f;
    bc_bemf_params p1 = p0;
    const float q = 0.04f; /* 0.7 V of a diode on a 16.8 V bus: 0.7 / 17.5 */
    p1.d_diode = q;
    bc_bemf_state s0, s1;
    CHECK(bc_bemf_init(&p0, &s0) == BC_OK && bc_bemf_init(&p1, &s1) == BC_OK, "init with d_diode");
    bc_ctrl_in in;
    memset(&in, 0, sizeof in);
    in.v_dc = 16.8f;
    in.ref = 0.5f;
    bc_ctrl_out o0, o1;
    long n_align = 0, n_ramp = 0, bad = 0, bad_leg = 0;
    long k_end = (long)((double)p0.align_time / TS) + 400;
    for (long k = 0; k < k_end; ++k) {
        in.tick_now = (uint32_t)(k * 250);
        memset(&o0, 0, sizeof o0);
        memset(&o1, 0, sizeof o1);
        bc_bemf_step(&p0, &s0, &in, &o0);
        bc_bemf_step(&p1, &s1, &in, &o1);
        if (o1.diag[0] != o0.diag[0]) {
            ++bad;
            continue;
        }
        if (o0.diag[0] == (float)BC_BEMF_ALIGN) ++n_align;
        else if (o0.diag[0] == (float)BC_BEMF_RAMP) ++n_ramp;
        else continue;
        double want = (double)q + (1.0 - (double)q) * (double)o0.diag[6];
        if (fabs((double)o1.diag[6] - want) > 1e-6) ++bad;
        double top = 0.0; /* the chopping (high) leg's duty */
        for (int x = 0; x < 3; ++x)
            if (o1.leg[x].mode == BC_LEG_HIGH && (double)o1.leg[x].duty > top) top = (double)o1.leg[x].duty;
        if (fabs(top - want) > 1e-6) ++bad_leg;
    }
    CHECK(n_align > 100 && n_ramp > 50 && bad == 0 && bad_leg == 0,
          "d_diode: duty q + (1 - q) d in %ld of %ld alignment and ramp samples, the chopping leg at it in %ld",
          n_align + n_ramp - bad, n_align + n_ramp, n_align + n_ramp - bad_leg);
    p1.d_diode = 1.0f;
    CHECK(bc_bemf_init(&p1, &s1) == BC_ERR_PARAM, "d_diode = 1 refused");
    p1.d_diode = -0.01f;
    CHECK(bc_bemf_init(&p1, &s1) == BC_ERR_PARAM, "d_diode < 0 refused");
    p1.d_diode = NAN;
    CHECK(bc_bemf_init(&p1, &s1) == BC_ERR_PARAM, "d_diode NaN refused");
}

/* 7, uniform grid (grid_gain): phases b and c's back-EMFs delayed by 2 and -1.5 degrees cross zero off the magnet's
 * grid; 30 degrees after each crossing the six commutations lie 0, +2 and -1.5 degrees off it (a spread of 3.5
 * degrees). On the grid phase-locked to the mean of the six crossings every commutation lies the crossings' mean
 * offset, (2 + 2 - 1.5 - 1.5) / 6 = 1/6 degree, off the magnet's grid, whatever its sector. Both directions, 300 Hz,
 * the comparator. */
static void test_uniform_grid(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 300.0;
    for (int dir = 1; dir >= -1; dir -= 2) {
        for (int grid = 0; grid <= 1; ++grid) {
            bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
            p.grid_gain = grid ? 0.2f : 0.0f;
            sb_init(&g, TS, F_TICK, 1);
            kin_rotor(&g, w, dir, 0.0);
            g.shift[1] = 2.0 * DEG;
            g.shift[2] = -1.5 * DEG;
            g.demag = 30e-6;
            run_stats r = run_kinematic(p, &g, 4000, (float)dir * 0.5f, 0.0, 0.0);
            double lo[6], hi[6];
            for (int j = 0; j < 6; ++j) {
                lo[j] = 1e9;
                hi[j] = -1e9;
            }
            double sum = 0.0;
            long n = 0;
            for (long i = 1; i < g.n_comm; ++i) { /* the commutation ending sector (floating fl), 2 periods on */
                double tc = g.t_comm[i];
                if (tc < 0.05) continue;
                int fl = g.comm_fl[i - 1];
                /* magnet's grid: 30 degrees after fl's unshifted crossing, n pi + fl 2 pi / 3 (+ pi/6 forward) */
                double th = sb_theta(&g, tc) - (double)fl * 2.0 * BC_PI / 3.0 - (double)dir * BC_PI / 6.0;
                double e = (double)dir * (th - BC_PI * floor(th / BC_PI + 0.5)); /* > 0: late */
                int slot = fl + 3 * (int)(fmod(floor(th / BC_PI + 0.5), 2.0) != 0.0);
                if (slot < 0 || slot > 5) continue;
                if (e < lo[slot]) lo[slot] = e;
                if (e > hi[slot]) hi[slot] = e;
                sum += e;
                ++n;
            }
            double min = 1e9, max = -1e9;
            for (int j = 0; j < 6; ++j) {
                if (lo[j] < min) min = lo[j];
                if (hi[j] > max) max = hi[j];
            }
            double mean = n ? sum / (double)n : 0.0;
            /* a shift delays the crossing in angle: later in time forward, earlier backward */
            if (grid)
                CHECK(r.desync == 0 && n > 60 && (max - min) < 0.05 * DEG &&
                          fabs(mean - (double)dir * DEG / 6.0) < 0.05 * DEG,
                      "dir %d, grid: commutations %.3f to %.3f deg off the magnet's grid (mean %.3f, expected %.3f; "
                      "%ld commutations, %ld desyncs)", dir, min / DEG, max / DEG, mean / DEG, (double)dir / 6.0, n,
                      r.desync);
            else /* the crossings' 3.5 degrees, and the interval filter's speed from unequal intervals on top */
                CHECK(r.desync == 0 && n > 60 && (max - min) > 3.4 * DEG,
                      "dir %d, after each crossing: commutations %.3f to %.3f deg off the magnet's grid", dir,
                      min / DEG, max / DEG);
        }
    }
    bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
    bc_bemf_state st;
    p.grid_gain = 1.5f;
    CHECK(bc_bemf_init(&p, &st) == BC_ERR_PARAM, "grid_gain 1.5 refused");
    p.grid_gain = NAN;
    CHECK(bc_bemf_init(&p, &st) == BC_ERR_PARAM, "grid_gain NaN refused");
}

/* 6, cmp_blind. The synthetic drive's comparators blind in the pair's off-time (ideal diodes: the floating phase
 * clamped at the driven terminals' rail reads the reference), high-side and synchronous chopping, duty 0.2, 287 Hz
 * (11.6 PWM periods a sector: the crossings drift through the carrier; the interval filter slow, 0.05, so that each
 * commutation's error is its crossing's). Taken as seen, a crossing in the off-time [a, b] (half-width h = 0.8 T_s
 * = 20 us) is late: rising, by min(t_z - a, b - t_z) (the diode current's decay; h / 2 on average over the
 * off-time), falling by b - t_z (h on average): over the carrier (a share 1 - m of the crossings in an off-time)
 * 3 (1 - m) h / 4 = 12 us, up to 2 h. Placed in the off-time (the rising ones inside it exactly, those at the
 * on-time's start and the falling ones at the middle of where they can be): no bias (the mean within 1 us: the
 * crossings' carrier phases over 140 sectors are not exactly uniform), each within h of its crossing (1.1 h for
 * the commutation: the interval filter's share). */
static void test_blind_offtime(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 287.0, m = 0.2, h = (1.0 - m) * TS, lag = 0.75 * (1.0 - m) * h;
    const int chops[2] = {BC_CHOP_HIGH, BC_CHOP_SYNC};
    for (int ic = 0; ic < 2; ++ic) {
        for (int dir = 1; dir >= -1; dir -= 2) {
            double mean[2], worst[2];
            for (int blind = 0; blind <= 1; ++blind) {
                bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
                p.chop = chops[ic];
                p.cmp_blind = blind;
                p.t60_gain = 0.05f;
                sb_init(&g, TS, F_TICK, 1);
                kin_rotor(&g, w, dir, 0.0);
                g.demag = 30e-6;
                g.blind = 1;
                run_stats r = run_kinematic(p, &g, 4000, (float)(dir * m), 0.02, 0.0);
                CHECK(r.desync == 0 && r.missing == 0 && r.n_closed_comm > 120,
                      "chop %d dir %d cmp_blind %d: %ld commutations, %ld desyncs, %ld missing", chops[ic], dir, blind,
                      r.n_closed_comm, r.desync, r.missing);
                mean[blind] = r.mean_err;
                worst[blind] = r.worst;
            }
            CHECK(mean[0] > 0.85 * lag && mean[0] < 1.15 * lag && worst[0] > 1.5 * h && worst[0] < 2.0 * h + 3.0 * TICK,
                  "chop %d dir %d, edges as seen: mean lag %.3g s (closed form %.3g), worst %.3g s", chops[ic], dir,
                  mean[0], lag, worst[0]);
            CHECK(fabs(mean[1]) < 1e-6 && worst[1] < 1.1 * h,
                  "chop %d dir %d, cmp_blind: mean error %.3g s, worst %.3g s (h %.3g)", chops[ic], dir, mean[1],
                  worst[1], h);
            if (ic == 1 && dir == 1)
                printf("test_bemf: blind off-times, duty 0.2: mean lag %.2f us as seen (closed form %.2f), %.2f us "
                       "placed (worst %.1f -> %.1f us)\n", mean[0] * 1e6, lag * 1e6, mean[1] * 1e6, worst[0] * 1e6,
                       worst[1] * 1e6);
        }
    }
    bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
    bc_bemf_state st;
    p.cmp_blind = 2;
    CHECK(bc_bemf_init(&p, &st) == BC_ERR_PARAM, "cmp_blind 2 refused");
}

/* 7, the uniform grid bounded by the demagnetisation. Phases b and c 2 and -1.5 degrees off as above, and a clamp of
 * 18 degrees (0.6 of the 30-degree window) against demag_max 0.6: a commutation must leave the next crossing at least
 * 18 / 0.6 = 30 degrees (the clamp at most demag_max of the window), and the next crossing is expected one T60 after
 * this one at the latest, so no grid point may come later than the plain instant, 30 degrees (at T60) after its
 * crossing. After c's crossings (1.5 degrees early) and a's (on the magnet's grid) the grid point is later than that:
 * those commutations stay at the plain instant, where the drive after each crossing puts them; after b's (2 degrees
 * late: its grid point is earlier) on the grid, 1/6 degree off the magnet's grid. Unbounded every commutation was
 * 1/6 degree off; with a short clamp (30 us) it still is (the bound does not act). Forward, 300 Hz. */
static void grid_offsets(int grid, double demag, double m[3], double hi[3], long *desync)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 300.0;
    bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
    p.grid_gain = grid ? 0.2f : 0.0f;
    p.demag_max = 0.6f;
    sb_init(&g, TS, F_TICK, 1);
    kin_rotor(&g, w, 1, 0.0);
    g.shift[1] = 2.0 * DEG;
    g.shift[2] = -1.5 * DEG;
    g.demag = demag;
    run_stats r = run_kinematic(p, &g, 4000, 0.5f, 0.0, 0.0);
    *desync = r.desync;
    double sum[3] = {0.0, 0.0, 0.0};
    long n[3] = {0, 0, 0};
    for (int x = 0; x < 3; ++x) hi[x] = -1e9;
    for (long i = 1; i < g.n_comm; ++i) { /* the commutation ending the sector in which fl floats */
        double tc = g.t_comm[i];
        int fl = g.comm_fl[i - 1];
        if (tc < 0.05 || fl < 0 || fl > 2) continue;
        double th = sb_theta(&g, tc) - (double)fl * 2.0 * BC_PI / 3.0 - BC_PI / 6.0;
        double e = (th - BC_PI * floor(th / BC_PI + 0.5)) / DEG; /* > 0: late against the magnet's grid */
        sum[fl] += e;
        n[fl] += 1;
        if (e > hi[fl]) hi[fl] = e;
    }
    for (int x = 0; x < 3; ++x) m[x] = n[x] > 20 ? sum[x] / (double)n[x] : 1e9;
}

static void test_uniform_grid_demag_bound(void)
{
    const double w = 2.0 * BC_PI * 300.0, clamp = 0.6 * (BC_PI / 6.0) / w;
    double pm[3], ph[3], gm[3], gh[3], sm[3], sh[3];
    long pd, gd, sd;
    grid_offsets(0, clamp, pm, ph, &pd);
    grid_offsets(1, clamp, gm, gh, &gd);
    grid_offsets(1, 30e-6, sm, sh, &sd);
    CHECK(pd == 0 && gd == 0 && fabs(gm[0] - pm[0]) < 0.02 && fabs(gm[2] - pm[2]) < 0.02 && gh[0] < ph[0] + 0.02 &&
              gh[2] < ph[2] + 0.02 && fabs(gm[1] - 1.0 / 6.0) < 0.05,
          "grid bounded by an 18-degree clamp: after a, b, c's crossings %.3f, %.3f, %.3f deg off the magnet's grid "
          "(latest %.3f, %.3f, %.3f); after each crossing %.3f, %.3f, %.3f (latest %.3f, -, %.3f); %ld, %ld desyncs",
          gm[0], gm[1], gm[2], gh[0], gh[1], gh[2], pm[0], pm[1], pm[2], ph[0], ph[2], pd, gd);
    CHECK(sd == 0 && fabs(sm[0] - 1.0 / 6.0) < 0.05 && fabs(sm[1] - 1.0 / 6.0) < 0.05 && fabs(sm[2] - 1.0 / 6.0) < 0.05,
          "grid with a 30-us clamp (the bound idle): after a, b, c's crossings %.3f, %.3f, %.3f deg off the magnet's "
          "grid (1/6 expected)", sm[0], sm[1], sm[2]);
}

/* SYNC fast demagnetisation with the inverter's dead time (d_diode > 0): the change of chopping leg (the positive
 * leg's turn-ons to the negative leg's turn-offs, each losing one dead time of the pair's voltage to a diode) costs one
 * dead time more per episode (docs/sensorless.md, 8); the first whole half period of the fast pattern makes it up,
 * the negative leg at 1 - m - 2 d_diode, every later one at 1 - m. Engaged mid-sector (fd_after 0.5, a clamp of 0.8 of
 * the window) and from the commutation (fd_after 0: the leg_at part carries none, the next whole half period does). */
static void test_fast_demag_dead_time(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 300.0;
    const float q = 0.02f;
    for (int from_comm = 0; from_comm <= 1; ++from_comm) {
        bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
        p.chop = BC_CHOP_SYNC;
        p.fast_demag = 1;
        p.fd_after = from_comm ? 0.0f : 0.5f;
        p.d_diode = q;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = from_comm ? 60e-6 : 0.8 * (BC_PI / 6.0) / w;
        bc_bemf_state s;
        CHECK(bc_bemf_init(&p, &s) == BC_OK, "init");
        long episodes = 0, first = 0, later = 0, bad = 0, nsync = 0, nc = 0;
        int in_fd = 0;
        for (long k = 0; k < 2400; ++k) {
            bc_ctrl_in in;
            sb_sample(&g, k, &in);
            in.ref = 0.5f;
            bc_ctrl_out o;
            memset(&o, 0, sizeof o);
            bc_bemf_step(&p, &s, &in, &o);
            sb_apply(&g, k, &o);
            if (o.diag[0] != (float)BC_BEMF_CLOSED) continue;
            ++nc;
            nsync += !(o.flags & BC_FLAG_DESYNC);
            int fd = -1; /* the leg complementary below its pair's positive leg held on: the fast pattern's */
            for (int x = 0; x < 3; ++x)
                if (o.leg[x].mode == BC_LEG_PWM && o.leg[(x + 1) % 3].mode != BC_LEG_PWM &&
                    o.leg[(x + 2) % 3].mode != BC_LEG_PWM &&
                    (o.leg[(x + 1) % 3].mode == BC_LEG_HIGH || o.leg[(x + 2) % 3].mode == BC_LEG_HIGH))
                    fd = x;
            if (fd < 0 || o.has_at) {
                if (fd < 0) in_fd = 0;
                continue;
            }
            double want = 1.0 - (double)o.diag[6];
            double dd = want - (double)o.leg[fd].duty;
            if (!in_fd) {
                ++episodes;
                first += fabs(dd - 2.0 * (double)q) < 1e-6;
                bad += fabs(dd - 2.0 * (double)q) >= 1e-6;
            } else {
                later += fabs(dd) < 1e-6;
                bad += fabs(dd) >= 1e-6;
            }
            in_fd = 1;
        }
        CHECK(nc > 1000 && nsync == nc && episodes > 20 && first == episodes && later > episodes && bad == 0,
              "fast pattern with dead time (%s): %ld episodes, %ld first halves at 1 - m - 2 d_diode, %ld later at 1 - m, "
              "%ld wrong", from_comm ? "from the commutation" : "fd_after 0.5", episodes, first, later, bad);
    }
}

/* fast demagnetisation and the demagnetisation limiter on the kinematic rotor (300 Hz, 22 samples a sector) */
static void test_fast_demag_and_limiter(void)
{
    static synth_bemf g;
    const double w = 2.0 * BC_PI * 300.0;
    /* sync: after each commutation whose outgoing current was positive (its clamp at 0 V) the negative leg is
     * complementary at 1 - m until the clamp's end is seen; the commutation instants stay 30 degrees after the
     * crossings */
    bc_bemf_params p = locked(BC_BEMF_COMPARATOR, w);
    p.chop = BC_CHOP_SYNC;
    p.fast_demag = 1;
    sb_init(&g, TS, F_TICK, 1);
    kin_rotor(&g, w, 1, 0.0);
    g.demag = 60e-6; /* 2.4 samples */
    bc_bemf_state s;
    CHECK(bc_bemf_init(&p, &s) == BC_OK, "init");
    long n_fast = 0, n_bad = 0, n_closed = 0;
    for (long k = 0; k < 2400; ++k) {
        bc_ctrl_in in;
        sb_sample(&g, k, &in);
        in.ref = 0.5f;
        bc_ctrl_out o;
        memset(&o, 0, sizeof o);
        bc_bemf_step(&p, &s, &in, &o);
        sb_apply(&g, k, &o);
        if (o.diag[0] != (float)BC_BEMF_CLOSED || o.has_at) continue; /* (a commutation's sample: two pairs) */
        ++n_closed;
        int pos, neg;
        double m;
        sb_legs_pair(o.leg, &pos, &neg, &m);
        if (pos < 0) continue;
        int bad = 0;
        if (o.leg[neg].mode == BC_LEG_PWM) { /* the fast pattern: pos on, neg at 1 - m, the pair at m */
            ++n_fast;
            bad = o.leg[pos].mode != BC_LEG_HIGH || o.leg[pos].duty != 1.0f || fabs(m - (double)o.diag[6]) > 1e-6;
        } else {
            bad = o.leg[pos].mode != BC_LEG_PWM || o.leg[neg].mode != BC_LEG_LOW || fabs(m - (double)o.diag[6]) > 1e-6;
        }
        if (bad) {
            ++n_bad;
            printf("    k %ld legs (%d %.3f) (%d %.3f) (%d %.3f) m %.4f\n", k, o.leg[0].mode, (double)o.leg[0].duty,
                   o.leg[1].mode, (double)o.leg[1].duty, o.leg[2].mode, (double)o.leg[2].duty, m);
        }
    }
    /* three of the six commutations per period have a positive outgoing current; their clamp (60 us) is seen at
     * the first sample after it: 3 to 5 samples of the fast pattern each */
    double per = (double)n_fast / ((double)n_closed * TS * 300.0 * 3.0); /* per positive-outgoing commutation */
    CHECK(n_bad == 0 && per >= 3.0 && per <= 5.0, "fast demagnetisation: %ld samples of %ld (%.2f per commutation), "
          "%ld with wrong legs", n_fast, n_closed, per, n_bad);
    /* fd_after = 0.5: a clamp of 60 us (0.22 of the 278 us window) never sees the fast pattern; a clamp of 0.8 of
     * the window sees it from the output whose interval reaches half the window (5.55 samples after the
     * commutation: from about 4.6) until the clamp's end is seen (8.9 samples, seen 1 to 2.5 samples later, as in the
     * fd_after = 0 case above): 4.5 to 7 samples per positive-outgoing commutation */
    for (int longer = 0; longer <= 1; ++longer) {
        p = locked(BC_BEMF_COMPARATOR, w);
        p.chop = BC_CHOP_SYNC;
        p.fast_demag = 1;
        p.fd_after = 0.5f;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = longer ? 0.8 * (BC_PI / 6.0) / w : 60e-6;
        CHECK(bc_bemf_init(&p, &s) == BC_OK, "init");
        long nf = 0, nc = 0, nsync = 0;
        for (long k = 0; k < 2400; ++k) {
            bc_ctrl_in in;
            sb_sample(&g, k, &in);
            in.ref = 0.5f;
            bc_ctrl_out o;
            memset(&o, 0, sizeof o);
            bc_bemf_step(&p, &s, &in, &o);
            sb_apply(&g, k, &o);
            if (o.diag[0] != (float)BC_BEMF_CLOSED || o.has_at) continue;
            ++nc;
            nsync += !(o.flags & BC_FLAG_DESYNC);
            int pos, neg;
            double m;
            sb_legs_pair(o.leg, &pos, &neg, &m);
            if (pos >= 0 && o.leg[neg].mode == BC_LEG_PWM) ++nf;
        }
        double per = (double)nf / ((double)nc * TS * 300.0 * 3.0);
        CHECK(nc > 1000 && nsync == nc && (longer ? (per >= 4.5 && per <= 7.0) : nf == 0),
              "fd_after 0.5, clamp %s: %ld fast samples of %ld (%.2f per commutation)", longer ? "0.8 window" : "60 us",
              nf, nc, per);
    }
    p.fd_after = 1.0f;
    CHECK(bc_bemf_init(&p, &s) != BC_OK, "fd_after 1 refused");
    /* the demagnetisation limiter: a clamp of 0.7 of the window (30 degrees: 278 us) against demag_max 0.6 lowers
     * the duty cap by 0.2 x 0.1 per crossing once it is below the duty plus 0.05; with a clamp of 0.3 the duty
     * stays at the throttle */
    for (int longer = 0; longer <= 1; ++longer) {
        p = locked(BC_BEMF_COMPARATOR, w);
        p.demag_max = 0.6f;
        sb_init(&g, TS, F_TICK, 1);
        kin_rotor(&g, w, 1, 0.0);
        g.demag = (longer ? 0.7 : 0.3) * (BC_PI / 6.0) / w;
        CHECK(bc_bemf_init(&p, &s) == BC_OK, "init");
        float d_first = -1.0f, d_last = -1.0f;
        long k_first = -1, k_last = -1;
        int full = 0; /* the duty has reached the throttle (after the handover's sample at the ramp's duty) */
        for (long k = 0; k < 2400; ++k) {
            bc_ctrl_in in;
            sb_sample(&g, k, &in);
            in.ref = 0.5f;
            bc_ctrl_out o;
            memset(&o, 0, sizeof o);
            bc_bemf_step(&p, &s, &in, &o);
            sb_apply(&g, k, &o);
            if (o.diag[0] != (float)BC_BEMF_CLOSED || (o.flags & BC_FLAG_DESYNC)) continue;
            if (o.diag[6] >= 0.5f) full = 1;
            if (!full) continue;
            if (k_first < 0 && o.diag[6] < 0.45f) {
                k_first = k;
                d_first = o.diag[6];
            }
            if (k_first >= 0 && k - k_first < 440) { /* 20 sectors of 22 samples */
                k_last = k;
                d_last = o.diag[6];
            }
            if (!longer) d_last = o.diag[6];
        }
        if (longer) {
            /* 20 sectors after the duty first fell below 0.45: 0.4 lower (one crossing per sector) */
            double fall = (double)(d_first - d_last);
            CHECK(k_first > 0 && fabs(fall - 0.02 * (double)((k_last - k_first) / 22)) < 0.021,
                  "limiter: the duty falls %.3f over %ld samples (0.02 a sector)", fall, k_last - k_first);
        } else {
            CHECK(k_first < 0 && fabs((double)d_last - 0.5) < 1e-6, "limiter idle: duty %.4f", (double)d_last);
        }
    }
}

/* The handover's fit (5) as the controller makes it, in two parts (bc_bemf_ho_prepare after a crossing,
 * bc_bemf_ho_fit at the next), against the one-shot fit it replaced (all m crossings' times centred on their mean,
 * in their mean interval, the normal equations from their moments, in float: the reference for the decision) and
 * the same fit in double (the exact answer for these purposes). Random crossing sequences: rotors at constant
 * acceleration with noise and an alternate displacement, held rotors' twitches (random intervals), crossings out of
 * order or at one tick (no rotor's), at any ring position and across the tick counter's wrap. The two float forms
 * differ only in rounding: their accept/reject decisions (as plausible takes them: alt and res within 10 deg, |acc|
 * within 4 ramp_accel, no check for m < 5, a refusal for a degenerate fit) differ only where the exact values lie
 * within rounding of a limit, and the two part form is no less accurate. */
#define HO_M(valid) ((valid) < BC_BEMF_HO_FIT ? (int)(valid) : BC_BEMF_HO_FIT)

/* the crossings' times relative to the last, s, oldest first (as the one-shot fit read them) */
static int ho_times(const uint32_t *ring, int32_t valid, float inv_tick, float *u, double *ud)
{
    int m = HO_M(valid), last = (int)((valid - 1) % BC_BEMF_HO_FIT), j = last - (m - 1);
    if (j < 0) j += BC_BEMF_HO_FIT;
    for (int k = 0; k < m; ++k) {
        int32_t dt = (int32_t)(ring[j] - ring[last]);
        u[k] = (float)dt * inv_tick;
        ud[k] = (double)dt * (double)inv_tick;
        if (++j == BC_BEMF_HO_FIT) j = 0;
    }
    return m;
}

/* the one-shot fit in float, as bc_bemf.c made it before the fit was split (1 for m < 5, -1 degenerate) */
static int ho_ref_float(const uint32_t *ring, int32_t valid, float inv_tick, float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    float u[BC_BEMF_HO_FIT];
    double ud[BC_BEMF_HO_FIT];
    int m = ho_times(ring, valid, inv_tick, u, ud);
    if (m < 5) return 1;
    float tm = -u[0] / (float)(m - 1);
    if (!(isfinite(tm) && tm > 0.0f)) return -1;
    float um = 0.0f;
    for (int k = 0; k < m; ++k) {
        u[k] /= tm;
        um += u[k];
    }
    um /= (float)m;
    float s1 = 0.0f, s2 = 0.0f, s3 = 0.0f, s4 = 0.0f, sa = 0.0f, sax = 0.0f, sax2 = 0.0f;
    float y[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int k = 0; k < m; ++k) {
        float x = u[k] - um, x2 = x * x, sg = (k & 1) ? -1.0f : 1.0f, fk = (float)k;
        s1 += x;
        s2 += x2;
        s3 += x2 * x;
        s4 += x2 * x2;
        sa += sg;
        sax += sg * x;
        sax2 += sg * x2;
        y[0] += fk;
        y[1] += x * fk;
        y[2] += x2 * fk;
        y[3] += sg * fk;
    }
    float a[4][4] = {{(float)m, 0.0f, 0.0f, 0.0f}, {s1, s2, 0.0f, 0.0f}, {s2, s3, s4, 0.0f}, {sa, sax, sax2, (float)m}};
    for (int c = 0; c < 4; ++c) {
        for (int q = 0; q < c; ++q) a[c][c] -= a[c][q] * a[c][q];
        if (!(a[c][c] > 1e-9f)) return -1;
        a[c][c] = sqrtf(a[c][c]);
        for (int r = c + 1; r < 4; ++r) {
            for (int q = 0; q < c; ++q) a[r][c] -= a[r][q] * a[c][q];
            a[r][c] /= a[c][c];
        }
    }
    float cf[4];
    for (int r = 0; r < 4; ++r) {
        float v = y[r];
        for (int q = 0; q < r; ++q) v -= a[r][q] * cf[q];
        cf[r] = v / a[r][r];
    }
    for (int r = 3; r >= 0; --r) {
        float v = cf[r];
        for (int q = r + 1; q < 4; ++q) v -= a[q][r] * cf[q];
        cf[r] = v / a[r][r];
    }
    float worst = 0.0f;
    for (int k = 0; k < m; ++k) {
        float x = u[k] - um;
        float d = fabsf(cf[0] + cf[1] * x + cf[2] * x * x + cf[3] * ((k & 1) ? -1.0f : 1.0f) - (float)k);
        if (d > worst) worst = d;
    }
    out[0] = fabsf(cf[3]) * (float)(BC_PI / 3.0);
    out[1] = worst * (float)(BC_PI / 3.0);
    out[2] = 2.0f * cf[2] * (float)(BC_PI / 3.0) / (tm * tm);
    return isfinite(out[0]) && isfinite(out[1]) && isfinite(out[2]) ? 0 : -1;
}

/* the same fit in double (Gram-Schmidt on the centred regressors: 1 for m < 5, -1 singular to 1e-9 of their size) */
static int ho_ref_double(const uint32_t *ring, int32_t valid, float inv_tick, double out[3])
{
    out[0] = out[1] = out[2] = 0.0;
    float u[BC_BEMF_HO_FIT];
    double ud[BC_BEMF_HO_FIT];
    int m = ho_times(ring, valid, inv_tick, u, ud);
    if (m < 5) return 1;
    double tm = -ud[0] / (double)(m - 1);
    if (!(tm > 0.0)) return -1;
    double um = 0.0;
    for (int k = 0; k < m; ++k) um += ud[k] / tm / (double)m;
    double q[4][BC_BEMF_HO_FIT], cq[4], r[4][4] = {{0.0}};
    for (int k = 0; k < m; ++k) {
        double x = ud[k] / tm - um;
        q[0][k] = 1.0;
        q[1][k] = x;
        q[2][k] = x * x;
        q[3][k] = (k & 1) ? -1.0 : 1.0;
    }
    for (int c = 0; c < 4; ++c) { /* modified Gram-Schmidt, q = Q, r = R */
        double n0 = 0.0, n = 0.0;
        for (int k = 0; k < m; ++k) n0 += q[c][k] * q[c][k];
        for (int p = 0; p < c; ++p) {
            double d = 0.0;
            for (int k = 0; k < m; ++k) d += q[p][k] * q[c][k];
            r[p][c] = d;
            for (int k = 0; k < m; ++k) q[c][k] -= d * q[p][k];
        }
        for (int k = 0; k < m; ++k) n += q[c][k] * q[c][k];
        if (!(n > 1e-18 * n0)) return -1;
        r[c][c] = sqrt(n);
        for (int k = 0; k < m; ++k) q[c][k] /= r[c][c];
    }
    for (int c = 0; c < 4; ++c) {
        cq[c] = 0.0;
        for (int k = 0; k < m; ++k) cq[c] += q[c][k] * (double)k;
    }
    double cf[4];
    for (int c = 3; c >= 0; --c) {
        double v = cq[c];
        for (int p = c + 1; p < 4; ++p) v -= r[c][p] * cf[p];
        cf[c] = v / r[c][c];
    }
    double worst = 0.0;
    for (int k = 0; k < m; ++k) {
        double x = ud[k] / tm - um;
        worst = fmax(worst, fabs(cf[0] + cf[1] * x + cf[2] * x * x + cf[3] * ((k & 1) ? -1.0 : 1.0) - (double)k));
    }
    out[0] = fabs(cf[3]) * BC_PI / 3.0;
    out[1] = worst * BC_PI / 3.0;
    out[2] = 2.0 * cf[2] * BC_PI / 3.0 / (tm * tm);
    return 0;
}

/* plausible's decision on a fit's outcome */
static int ho_accept(int r, double alt, double res, double acc, double d_max, double acc_max)
{
    return r != 0 ? r > 0 : alt <= d_max && res <= d_max && !(fabs(acc) > acc_max);
}

static void test_handover_fit(void)
{
    uint32_t seed = 12345u;
    const double d_max = BC_PI / 6.0 / 3.0; /* jump_max 2's 10 degrees */
    long n = 0, n_acc = 0, n_rej = 0, n_none = 0, n_ret = 0, n_diff = 0, n_far = 0, n_same = 0, n_rot = 0;
    long w_new = 0, w_ref = 0; /* decisions other than the exact one's */
    long t_new = 0, t_ref = 0; /* errors above 1e-3 of the size (rotors) */
    double err_new = 0.0, err_ref = 0.0, ss_new = 0.0, ss_ref = 0.0; /* errors relative to size (rotors) */
    double far = 0.0; /* the furthest from a limit a decision changed */
    for (long trial = 0; trial < 200000; ++trial) {
        bc_bemf_state s;
        memset(&s, 0, sizeof s);
        double f_tick = (trial % 2) ? 10e6 : 84e6;
        s.inv_tick = (float)(1.0 / f_tick);
        int32_t valid = (int32_t)(3u + rnd(&seed) % 40u);
        uint32_t t0 = (trial % 5 == 0) ? 0xffffffffu - rnd(&seed) % 2000000u : rnd(&seed); /* across the wrap */
        uint32_t tk[BC_BEMF_HO_FIT];
        int kind = (int)(rnd(&seed) % 10u);
        double w = 20.0 + (double)(rnd(&seed) % 100000u) * 0.05; /* electrical rad/s, 20 .. 5,020 */
        double a_ramp = w * (0.5 + (double)(rnd(&seed) % 1000u) / 100.0); /* rad/s^2 */
        if (kind < 6) { /* a rotor: constant acceleration, an alternate displacement and noise (up to 10 and 15 deg) */
            double acc = a_ramp * ((double)(rnd(&seed) % 2001u) / 200.0 - 5.0);
            double alt = ((double)(rnd(&seed) % 2001u) / 100.0 - 10.0) * DEG * (kind < 3);
            double noise = (double)(rnd(&seed) % 1501u) / 100.0 * DEG * (kind % 2);
            for (int k = 0; k < BC_BEMF_HO_FIT; ++k) {
                double g = (k + 1) * BC_PI / 3.0 + ((k & 1) ? -alt : alt) +
                           noise * ((double)(rnd(&seed) % 2001u) / 1000.0 - 1.0);
                double disc = w * w + 2.0 * acc * g, t = 2.0 * (double)k / w; /* stopped before: anything */
                if (fabs(acc) < 1e-9) t = g / w;
                else if (disc > 0.0) t = (-w + sqrt(disc)) / acc;
                tk[k] = t0 + (uint32_t)lround(t * f_tick);
            }
        } else if (kind < 9) { /* a held rotor's twitch: random intervals */
            uint32_t t = t0, span = (uint32_t)(f_tick * (BC_PI / 3.0) / w);
            for (int k = 0; k < BC_BEMF_HO_FIT; ++k) {
                t += rnd(&seed) % (2u * span + 1u);
                tk[k] = t;
            }
        } else { /* no rotor's: out of order, or at one tick */
            for (int k = 0; k < BC_BEMF_HO_FIT; ++k)
                tk[k] = (rnd(&seed) % 3u == 0u) ? t0 : t0 + rnd(&seed) % 5000u - 2500u;
        }
        int m = HO_M(valid);
        for (int k = 0; k < m; ++k) s.ho_ring[(valid - m + k) % BC_BEMF_HO_FIT] = tk[BC_BEMF_HO_FIT - m + k];
        float ref[3], out[3], again[3];
        double ex[3];
        int r_ref = ho_ref_float(s.ho_ring, valid, s.inv_tick, ref);
        int r_ex = ho_ref_double(s.ho_ring, valid, s.inv_tick, ex);
        /* as in the controller: prepared at valid - 1, before the last crossing took its slot (which held an older
         * one), then the fit; in a quarter of the trials prepared at the crossing itself, stale from another ring */
        uint32_t keep = s.ho_ring[(valid - 1) % BC_BEMF_HO_FIT];
        s.ho_ring[(valid - 1) % BC_BEMF_HO_FIT] = tk[0] ^ 0x5a5a5a5au;
        s.valid = valid - 1;
        bc_bemf_ho_prepare(&s);
        s.ho_ring[(valid - 1) % BC_BEMF_HO_FIT] = keep;
        if (trial % 4 == 0) s.ho_ring[(valid + 5) % BC_BEMF_HO_FIT] += 1u; /* the crossing before the last moved */
        s.valid = valid;
        int r = bc_bemf_ho_fit(&s, &out[0], &out[1], &out[2]);
        if (trial % 4 == 0) { /* prepared again (the preparation is not the last crossing's): as the exact data */
            s.ho_ring[(valid + 5) % BC_BEMF_HO_FIT] -= 1u;
            r_ref = ho_ref_float(s.ho_ring, valid, s.inv_tick, ref);
            r_ex = ho_ref_double(s.ho_ring, valid, s.inv_tick, ex);
            s.ho_t += 1u; /* and the stale preparation's key no longer matches */
            r = bc_bemf_ho_fit(&s, &out[0], &out[1], &out[2]);
        }
        /* the fit prepared at the crossing itself gives the same, bit for bit */
        s.ho_n = -1;
        int r2 = bc_bemf_ho_fit(&s, &again[0], &again[1], &again[2]);
        n_same += r2 == r && memcmp(again, out, sizeof out) == 0;
        ++n;
        double lim = 4.0 * a_ramp;
        int d_new = ho_accept(r, (double)out[0], (double)out[1], (double)out[2], d_max, lim);
        int d_ref = ho_accept(r_ref, (double)ref[0], (double)ref[1], (double)ref[2], d_max, lim);
        int d_ex = ho_accept(r_ex, ex[0], ex[1], ex[2], d_max, lim);
        n_none += r_ref == 1;
        n_acc += r_ref != 1 && d_ref;
        n_rej += !d_ref;
        n_ret += r != r_ref;
        w_new += d_new != d_ex;
        w_ref += d_ref != d_ex;
        if (r_ex != 0 || r_ref != 0 || r != 0) continue;
        /* relative to each quantity's own size and a share of its limit */
        double sc[3] = {fabs(ex[0]) + 0.01 * d_max, fabs(ex[1]) + 0.01 * d_max, fabs(ex[2]) + 0.01 * lim};
        double e_new = 0.0, e_ref = 0.0, margin = fmin(fmin(fabs(ex[0] - d_max) / sc[0], fabs(ex[1] - d_max) / sc[1]),
                                                       fabs(fabs(ex[2]) - lim) / sc[2]);
        for (int q = 0; q < 3; ++q) {
            e_new = fmax(e_new, fabs((double)out[q] - ex[q]) / sc[q]);
            e_ref = fmax(e_ref, fabs((double)ref[q] - ex[q]) / sc[q]);
        }
        if (kind < 6) { /* a rotor's crossings */
            ++n_rot;
            err_new = fmax(err_new, e_new);
            err_ref = fmax(err_ref, e_ref);
            ss_new += e_new * e_new;
            ss_ref += e_ref * e_ref;
            t_new += e_new > 1e-3;
            t_ref += e_ref > 1e-3;
        }
        if (d_new != d_ref) {
            ++n_diff;
            far = fmax(far, margin);
            n_far += margin > 1e-2;
        }
    }
    double nr = (double)(n_rot > 0 ? n_rot : 1), rms_new = sqrt(ss_new / nr), rms_ref = sqrt(ss_ref / nr);
    printf("test_bemf: handover fit: %ld crossing sequences, the one-shot fit accepts %ld, refuses %ld, %ld without a "
           "check; decisions different from its %ld (the furthest %.1e of its size from a limit), from the exact "
           "fit's %ld (the one-shot fit's %ld); error against the exact fit over %ld rotors' sequences, rms %.2e, "
           "above 1e-3 %ld times, largest %.2e (the one-shot fit's %.2e, %ld, %.2e); other return codes %ld "
           "(degenerate sequences)\n", n, n_acc, n_rej, n_none, n_diff, far, w_new, w_ref, n_rot, rms_new, t_new,
           err_new, rms_ref, t_ref, err_ref, n_ret);
    CHECK(n_acc > 20000 && n_rej > 20000 && n_none > 5000 && n_rot > 100000,
          "the sequences cover every decision: %ld, %ld, %ld, %ld", n_acc, n_rej, n_none, n_rot);
    CHECK(n_same == n, "prepared ahead and at the crossing: %ld of %ld the same", n_same, n);
    CHECK(n_far == 0, "%ld decisions differ from the one-shot fit's further than 1e-2 of a limit", n_far);
    /* as accurate: as many decisions as the one-shot fit's the exact fit's, errors as small (their largest are both
     * the rounding noise of an acceleration the exact fit puts at zero) */
    CHECK(w_new <= w_ref + 5 && rms_new <= 1.25 * rms_ref && t_new <= t_ref + t_ref / 4 && err_new < 0.1,
          "error against the exact fit rms %.2e, above 1e-3 %ld times, largest %.2e (the one-shot fit's %.2e, %ld, "
          "%.2e), decisions other than the exact one's %ld (%ld)", rms_new, t_new, err_new, rms_ref, t_ref, err_ref,
          w_new, w_ref);
}

int main(void)
{
    test_init();
    test_safe_states();
    test_fuzz();
    test_commutation_instants();
    test_ramping_speed();
    test_adc_methods();
    test_adc_offtime_clamp();
    test_clamp_and_blanking();
    test_min_pulse();
    test_desyncs();
    test_late_commutation();
    test_ramp_follows_crossings();
    test_start_up();
    test_stop_and_reverse();
    test_throttle_and_limit();
    test_start_current_limit();
    test_diode_share();
    test_fast_demag_and_limiter();
    test_fast_demag_dead_time();
    test_uniform_grid();
    test_uniform_grid_demag_bound();
    test_handover_fit();
    test_blind_offtime();
    return bc_test_summary("test_bemf");
}

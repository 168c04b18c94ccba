/* test_sixstep.c - the real square-wave current controller: parameter validation, commutation table in both
 * directions and with reversed torque, safe states (invalid Hall, bad inputs, latched over-current), duties for
 * random and extreme inputs, the average model and the predictive law against hand-solved R-L cases, and closed
 * loops with the htm-48v plant through bc_sim_run (PWM-on-PWM predictive, PI, hysteresis, braking, start-up). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_commutation.h"
#include "bldc/bc_sim.h"
#include "bldc/bc_sixstep.h"
#include "fixtures.h"
#include "synth_hall.h"

#define TS (0.5 / 14e3)
#define F_TICK 10e6

static bc_sixstep_params params(int reg, int chop)
{
    bc_sixstep_params p;
    memset(&p, 0, sizeof p);
    p.reg = reg;
    p.chop = chop;
    p.delay = 1;
    p.advance = 1;
    p.emf_ff = 1;
    p.regen = 1;
    p.p = 8;
    p.ts = (float)TS;
    p.R = 0.05f;
    p.L = 75e-6f;
    p.k_e = 0.64f;
    p.kp = (float)(2.0 * BC_PI * 1000.0 * 150e-6); /* pi_gains(2R, 2L, 1 kHz, 90 deg) */
    p.ki = (float)(2.0 * BC_PI * 1000.0 * 0.1);
    p.band = 5.0f;
    p.i_max = 100.0f;
    p.v_max = 96.0f;
    p.f_tick = (float)F_TICK;
    p.omega_min = 6.0f;
    p.theta_offset = 0.0f;
    return p;
}

static bc_ctrl_in input(uint32_t hall, float ia, float ib, float v, float ref)
{
    bc_ctrl_in in;
    memset(&in, 0, sizeof in);
    in.i_abc[0] = ia;
    in.i_abc[1] = ib;
    in.i_mask = 3u;
    in.v_dc = v;
    in.hall = hall;
    in.ref = ref;
    return in;
}

static int all_off(const bc_ctrl_out *o)
{
    for (int x = 0; x < 3; ++x)
        if (o->leg[x].mode != BC_LEG_OFF || o->leg[x].duty != 0.0f) return 0;
    return 1;
}

/* Synthetic Hall input at time t for a constant electrical speed w_e (rad/s, forward if > 0) that crossed the
 * edge into sector s0 at t = 0: sector, edge count and capture ticks as the sensor chain gives them. */
static void hall_at(double t, double w_e, int s0, bc_ctrl_in *in)
{
    double dt = (BC_PI / 3.0) / fabs(w_e);
    long n = (long)floor(t / dt);
    int dir = w_e > 0.0 ? 1 : -1;
    int s = ((s0 + dir * (int)(n % 6)) % 6 + 6) % 6;
    in->hall = bc_sector_code(s);
    in->n_edges = (uint32_t)(n + 1);
    in->tick_edge = (uint32_t)floor((double)n * dt * F_TICK);
    in->tick_now = (uint32_t)floor(t * F_TICK);
}

static void test_init(void)
{
    bc_sixstep_state s;
    bc_sixstep_params p = params(BC_SIXSTEP_PRED, BC_SIXSTEP_PWMPWM);
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "valid params");
    CHECK(bc_sixstep_init(0, &s) == BC_ERR_PARAM && bc_sixstep_init(&p, 0) == BC_ERR_PARAM, "null pointers");
    const float nan = NAN, inf = INFINITY;
    struct {
        const char *what;
        bc_sixstep_params q;
    } bad[30];
    int n = 0;
#define BAD(field, value)                    \
    bad[n].what = #field " = " #value;       \
    bad[n].q = params(BC_SIXSTEP_PRED, BC_SIXSTEP_PWMPWM); \
    bad[n].q.field = value;                  \
    ++n
    BAD(reg, BC_SIXSTEP_IDEAL + 1);
    BAD(open_frac, -0.1f);
    BAD(open_frac, 0.5f);
    BAD(open_frac, nan);
    BAD(timed, 2);
    BAD(comm, 2);
    BAD(adv_angle, -0.1f);
    BAD(adv_angle, nan);
    BAD(adv_time, -1e-6f);
    BAD(adv_time, inf);
    BAD(chop, -1);
    BAD(delay, 2);
    BAD(advance, 5);
    BAD(ref_torque, -1);
    BAD(regen, 2);
    BAD(p, 0);
    BAD(ts, 0.0f);
    BAD(ts, nan);
    BAD(R, -0.1f);
    BAD(L, 0.0f);
    BAD(L, inf);
    BAD(k_e, 0.0f);
    BAD(kp, -1.0f);
    BAD(ki, nan);
    BAD(band, 0.0f);
    BAD(i_max, -5.0f);
    BAD(v_max, nan);
    BAD(f_tick, 0.0f);
    BAD(omega_min, 0.0f);
    BAD(theta_offset, inf);
#undef BAD
    for (int j = 0; j < n; ++j) CHECK(bc_sixstep_init(&bad[j].q, &s) == BC_ERR_PARAM, "rejected: %s", bad[j].what);
}

/* Every sector, both torque signs: pos HIGH, neg LOW, third leg off; forward and backward sequences give the
 * incoming phase of the table. */
static void test_commutation_table(void)
{
    static const int pos_t[6] = {0, 0, 1, 1, 2, 2}, neg_t[6] = {1, 2, 2, 0, 0, 1};
    static const int inc_fwd[6] = {0, 2, 1, 0, 2, 1}; /* phase entering sector s from s - 1 */
    static const int inc_bwd[6] = {1, 0, 2, 1, 0, 2}; /* phase entering sector s from s + 1 */
    bc_sixstep_params p = params(BC_SIXSTEP_PRED, BC_SIXSTEP_HIGH);
    bc_sixstep_state s;
    bc_ctrl_out o;
    for (int sign = -1; sign <= 1; sign += 2) {
        CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
        for (int k = 0; k < 14; ++k) {
            int sec = k % 6;
            bc_ctrl_in in = input(bc_sector_code(sec), 0.0f, 0.0f, 48.0f, 90.0f * (float)sign);
            in.n_edges = (uint32_t)k;
            bc_sixstep_step(&p, &s, &in, &o);
            int pos = sign > 0 ? pos_t[sec] : neg_t[sec], neg = sign > 0 ? neg_t[sec] : pos_t[sec];
            int third = 3 - pos - neg;
            CHECK(o.leg[pos].mode == BC_LEG_HIGH && o.leg[neg].mode == BC_LEG_LOW && o.leg[neg].duty == 1.0f &&
                      o.leg[third].mode == BC_LEG_OFF,
                  "sector %d sign %d: legs %d %d %d", sec, sign, o.leg[0].mode, o.leg[1].mode, o.leg[2].mode);
            CHECK(o.flags == BC_FLAG_SATURATED && o.diag[0] == (float)sec, "sector %d: flags 0x%x", sec, o.flags);
            int inc = k == 0 ? pos : inc_fwd[sec];
            CHECK((int)o.diag[5] == inc, "forward sector %d: incoming %d, expected %d", sec, (int)o.diag[5], inc);
        }
    }
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
    for (int k = 0; k < 14; ++k) {
        int sec = (6 - k % 6) % 6;
        bc_ctrl_in in = input(bc_sector_code(sec), 0.0f, 0.0f, 48.0f, 20.0f);
        bc_sixstep_step(&p, &s, &in, &o);
        int inc = k == 0 ? pos_t[sec] : inc_bwd[sec];
        CHECK((int)o.diag[5] == inc, "backward sector %d: incoming %d, expected %d", sec, (int)o.diag[5], inc);
        CHECK(o.leg[pos_t[sec]].mode == BC_LEG_HIGH && o.leg[neg_t[sec]].mode == BC_LEG_LOW, "backward legs");
    }
    /* regulated current: the incoming phase as a magnitude (sector 1 entered forward: c incoming, driven
     * negative; i_c reconstructed from a and b) */
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
    bc_ctrl_in in = input(bc_sector_code(0), 30.0f, -30.0f, 48.0f, 30.0f);
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK_NEAR(o.diag[1], 30.0f, 1e-6, "before the first commutation: the positive phase");
    in = input(bc_sector_code(1), 30.0f, -22.0f, 48.0f, 30.0f);
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK_NEAR(o.diag[1], 8.0f, 1e-6, "incoming c: -i_c = i_a + i_b");
    CHECK_NEAR(o.diag[7], 22.0f, 1e-6, "outgoing b still freewheels");
    in.i_abc[0] = 40.0f; /* phase c measured instead of b: i_b = -(i_a + i_c) */
    in.i_abc[1] = 0.0f;
    in.i_abc[2] = -12.0f;
    in.i_mask = 5u;
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK_NEAR(o.diag[1], 12.0f, 1e-6, "mask a, c");
    CHECK_NEAR(o.diag[7], 28.0f, 1e-6, "reconstructed b");
}

/* BC_SIXSTEP_IDEAL: the continuing phase fully on, the incoming phase HOLD at +-I_ref (i_hold), the third off; every
 * duty in [0, 1] (the held current travels in i_hold, not in a duty). */
static void test_ideal_legs(void)
{
    static const int pos_t[6] = {0, 0, 1, 1, 2, 2}, neg_t[6] = {1, 2, 2, 0, 0, 1};
    static const int inc_fwd[6] = {0, 2, 1, 0, 2, 1};
    bc_sixstep_params p = params(BC_SIXSTEP_IDEAL, BC_SIXSTEP_PWMPWM);
    bc_sixstep_state s;
    bc_ctrl_out o;
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init ideal");
    for (int k = 0; k < 13; ++k) {
        int sec = k % 6;
        bc_ctrl_in in = input(bc_sector_code(sec), 0.0f, 0.0f, 48.0f, 30.0f);
        in.n_edges = (uint32_t)k;
        bc_sixstep_step(&p, &s, &in, &o);
        int pos = pos_t[sec], neg = neg_t[sec], third = 3 - pos - neg;
        int inc = k == 0 ? pos : inc_fwd[sec];
        int cont = inc == pos ? neg : pos;
        CHECK(o.leg[inc].mode == BC_LEG_HOLD && o.i_hold == (inc == pos ? 30.0f : -30.0f),
              "sector %d: incoming %d held at %g A", sec, inc, (double)o.i_hold);
        CHECK(o.leg[cont].mode == (cont == pos ? BC_LEG_HIGH : BC_LEG_LOW) && o.leg[cont].duty == 1.0f &&
                  o.leg[third].mode == BC_LEG_OFF,
              "sector %d: continuing fully on, third off", sec);
        for (int x = 0; x < 3; ++x) CHECK(o.leg[x].duty >= 0.0f && o.leg[x].duty <= 1.0f, "duty in [0, 1]");
    }
    /* an invalid input: all legs off, nothing held */
    bc_ctrl_in bad = input(0u, 0.0f, 0.0f, 48.0f, 30.0f);
    bc_sixstep_step(&p, &s, &bad, &o);
    CHECK(all_off(&o) && (o.flags & BC_FLAG_SAFE), "safe state");
}

static void test_safe_states(void)
{
    bc_sixstep_params p = params(BC_SIXSTEP_PI, BC_SIXSTEP_BIPOLAR);
    bc_sixstep_state s;
    bc_ctrl_out o;
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
    const uint32_t codes[4] = {0u, 7u, 8u, 0xffffffffu};
    for (int j = 0; j < 4; ++j) {
        bc_ctrl_in in = input(codes[j], 1.0f, -1.0f, 48.0f, 10.0f);
        bc_sixstep_step(&p, &s, &in, &o);
        CHECK(all_off(&o) && (o.flags & BC_FLAG_HALL_INVALID) && (o.flags & BC_FLAG_SAFE), "code %u: safe", codes[j]);
    }
    const float nan = NAN, inf = INFINITY;
    struct {
        const char *what;
        bc_ctrl_in in;
    } bad[9];
    bad[0].what = "NaN i_a";
    bad[0].in = input(1u, nan, 0.0f, 48.0f, 10.0f);
    bad[1].what = "inf i_b";
    bad[1].in = input(1u, 0.0f, -inf, 48.0f, 10.0f);
    bad[2].what = "v_dc = 0";
    bad[2].in = input(1u, 0.0f, 0.0f, 0.0f, 10.0f);
    bad[3].what = "v_dc < 0";
    bad[3].in = input(1u, 0.0f, 0.0f, -48.0f, 10.0f);
    bad[4].what = "v_dc NaN";
    bad[4].in = input(1u, 0.0f, 0.0f, nan, 10.0f);
    bad[5].what = "v_dc above v_max";
    bad[5].in = input(1u, 0.0f, 0.0f, 1e30f, 10.0f);
    bad[6].what = "ref NaN";
    bad[6].in = input(1u, 0.0f, 0.0f, 48.0f, nan);
    bad[7].what = "one phase measured";
    bad[7].in = input(1u, 0.0f, 0.0f, 48.0f, 10.0f);
    bad[7].in.i_mask = 4u;
    bad[8].what = "ref inf";
    bad[8].in = input(1u, 0.0f, 0.0f, 48.0f, inf);
    for (int j = 0; j < 9; ++j) {
        bc_sixstep_step(&p, &s, &bad[j].in, &o);
        CHECK(all_off(&o) && o.flags == (BC_FLAG_BAD_INPUT | BC_FLAG_SAFE), "%s: flags 0x%x", bad[j].what, o.flags);
    }
    /* an unmeasured phase may hold anything: it is not read */
    bc_ctrl_in in = input(1u, 10.0f, -10.0f, 48.0f, 10.0f);
    in.i_abc[2] = nan;
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK(!(o.flags & BC_FLAG_SAFE), "NaN in an unmeasured phase ignored: 0x%x", o.flags);

    /* over-current: trip above i_max (on a reconstructed phase too), latched until every |i| < i_max / 2 */
    in = input(1u, 60.0f, 50.0f, 48.0f, 10.0f); /* i_c = -110 */
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK(all_off(&o) && o.flags == (BC_FLAG_OVERCURRENT | BC_FLAG_SAFE), "trip on reconstructed i_c: 0x%x", o.flags);
    in = input(1u, 60.0f, -60.0f, 48.0f, 10.0f);
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK(all_off(&o) && (o.flags & BC_FLAG_OVERCURRENT), "still latched at 60 A");
    in = input(1u, 49.0f, -49.0f, 48.0f, 10.0f);
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK(!all_off(&o) && o.flags == 0u, "released below i_max / 2: 0x%x", o.flags);
    in = input(1u, 101.0f, -101.0f, 48.0f, 10.0f);
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK(o.flags & BC_FLAG_OVERCURRENT, "trips again");
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init resets the latch");
    in = input(1u, 60.0f, -60.0f, 48.0f, 10.0f);
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK(o.flags == 0u && !all_off(&o), "no latch after init");
}

static uint64_t rng_next(uint64_t *x)
{
    *x ^= *x >> 12;
    *x ^= *x << 25;
    *x ^= *x >> 27;
    return *x * 2685821657736338717ull;
}

static float rnd_float(uint64_t *x)
{
    static const float special[10] = {NAN, INFINITY, -INFINITY, 0.0f, -0.0f, 1e30f, -1e30f, 1e-30f, 3.4e38f, -48.0f};
    uint64_t r = rng_next(x);
    if ((r & 7u) == 0u) return special[(r >> 3) % 10u];
    double u = (double)(r >> 11) / 9007199254740992.0; /* [0, 1) */
    int e = (int)((r >> 4) % 12u);
    return (float)((2.0 * u - 1.0) * pow(10.0, (double)e - 3.0));
}

/* Whatever comes in, the duties are finite and in [0, 1] and the modes valid. */
static void test_fuzz(void)
{
    uint64_t x = 0x9e3779b97f4a7c15ull;
    long bad = 0, safe = 0, n = 0;
    for (int reg = BC_SIXSTEP_PI; reg <= BC_SIXSTEP_PRED; ++reg)
        for (int chop = BC_SIXSTEP_BIPOLAR; chop <= BC_SIXSTEP_SYNC; ++chop)
            for (int delay = 0; delay <= 1; ++delay) {
                bc_sixstep_params p = params(reg, chop);
                p.delay = delay;
                p.open_frac = delay ? 0.2f : 0.0f; /* the no-current-path test fed garbage too */
                bc_sixstep_state s;
                CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
                uint32_t ticks = 0u, edges = 0u;
                for (int k = 0; k < 20000; ++k) {
                    if (s.open_n < 0) CHECK(bc_sixstep_init(&p, &s) == BC_OK, "re-init after a latched detection");
                    bc_ctrl_in in;
                    memset(&in, 0, sizeof in);
                    uint64_t r = rng_next(&x);
                    int plausible = (r & 3u) != 0u; /* mostly plausible values, so the laws are exercised */
                    for (int j = 0; j < 3; ++j)
                        in.i_abc[j] = plausible ? (float)((double)(rng_next(&x) >> 11) / 9e15 - 0.5) * 80.0f
                                                : rnd_float(&x);
                    in.i_mask = plausible ? 3u : (uint32_t)rng_next(&x);
                    in.v_dc = plausible ? 10.0f + (float)(rng_next(&x) % 80u) : rnd_float(&x);
                    in.ref = plausible ? (float)((int)(rng_next(&x) % 300u) - 150) : rnd_float(&x);
                    ticks += (uint32_t)(rng_next(&x) % (plausible ? 400u : 0xffffffffu));
                    if (rng_next(&x) % 5u == 0u) {
                        edges += (uint32_t)(plausible ? 1u : rng_next(&x) % 5u);
                        in.tick_edge = ticks;
                    }
                    in.n_edges = edges;
                    in.tick_now = ticks;
                    in.hall = plausible ? bc_sector_code((int)(edges % 6u)) : (uint32_t)(rng_next(&x) % 9u);
                    bc_ctrl_out o;
                    bc_sixstep_step(&p, &s, &in, &o);
                    for (int j = 0; j < 3; ++j) {
                        float d = o.leg[j].duty;
                        int mode = (int)o.leg[j].mode;
                        if (!(d >= 0.0f && d <= 1.0f) || mode < BC_LEG_OFF || mode > BC_LEG_LOW) ++bad;
                    }
                    for (int j = 0; j < BC_DIAG_N; ++j)
                        if (!isfinite(o.diag[j])) ++bad;
                    safe += (o.flags & BC_FLAG_SAFE) != 0u;
                    ++n;
                }
            }
    CHECK(bad == 0, "%ld invalid duties, modes or diagnostics in %ld samples", bad, n);
    CHECK(safe > n / 20 && safe < n, "both safe and normal samples exercised: %ld of %ld", safe, n);
}

/* The average model against the hand-solved commutation a+b- -> a+c- with R = 0: the outgoing b freewheels
 * through its upper diode, L di_b/dt = (V + 2E)/3 until i_b = 0, L di_a/dt = (V - 4E)/3; then a, c alone:
 * 2 L di_a/dt = V - 2E. */
static void test_average_model(void)
{
    const double V = 48.0, E = 6.0, L = 75e-6, I = 50.0, t = 200e-6;
    bc_leg_cmd cmd[3] = {{BC_LEG_HIGH, 1.0f}, {BC_LEG_OFF, 0.0f}, {BC_LEG_LOW, 1.0f}};
    float e[3] = {(float)E, (float)-E, (float)-E};
    float i[3] = {(float)I, (float)-I, 0.0f};
    CHECK(bc_sixstep_predict(cmd, (float)V, e, 0.0f, (float)L, (float)t, i) == 1, "one diode current ended");
    double tz = I * 3.0 * L / (V + 2.0 * E);
    double ia = I + (V - 4.0 * E) / (3.0 * L) * tz + (V - 2.0 * E) / (2.0 * L) * (t - tz);
    CHECK_NEAR(i[0], ia, 1e-3, "i_a after the outgoing current died");
    CHECK(i[1] == 0.0f, "outgoing phase open: i_b = %g", (double)i[1]);
    CHECK_NEAR(i[2], -ia, 1e-3, "i_c");
    /* shorter than the decay: three phases throughout */
    float j[3] = {(float)I, (float)-I, 0.0f};
    CHECK(bc_sixstep_predict(cmd, (float)V, e, 0.0f, (float)L, 100e-6f, j) == 0, "no diode current ended");
    CHECK_NEAR(j[1], -I + (V + 2.0 * E) / (3.0 * L) * 100e-6, 1e-3, "i_b decaying");
    CHECK_NEAR(j[2], -2.0 * (V - E) / (3.0 * L) * 100e-6, 1e-3, "i_c rising");
    /* all legs off, two-phase current: both diodes return it to the bus, 2 L di/dt = -(V + 2E), to zero */
    bc_leg_cmd off[3] = {{BC_LEG_OFF, 0.0f}, {BC_LEG_OFF, 0.0f}, {BC_LEG_OFF, 0.0f}};
    float k[3] = {10.0f, -10.0f, 0.0f};
    float e2[3] = {(float)E, (float)-E, 0.0f};
    bc_sixstep_predict(off, (float)V, e2, 0.0f, (float)L, 20e-6f, k);
    CHECK_NEAR(k[0], 10.0 - (V + 2.0 * E) / (2.0 * L) * 20e-6, 1e-3, "diode return");
    bc_sixstep_predict(off, (float)V, e2, 0.0f, (float)L, 1e-3f, k);
    CHECK(k[0] == 0.0f && k[1] == 0.0f && k[2] == 0.0f, "currents end at zero, not beyond");
}

/* Predictive law in two-phase conduction on the flat tops: i(k+1) = i + T (m V - 2 R i - 2 E) / (2 L), solved for
 * the m that gives I at the sample after next (delay 1) or the next (delay 0). */
/* No current path (open_frac): zero measured currents at full voltage, a valid speed and a voltage margin: safe
 * state with BC_FLAG_BAD_INPUT after 2 t_2 + 4 T_s, t_2 = -(L/R) ln(1 - 2 f I_ref 2R / u), latched; never with the
 * test off or with the current following the reference. */
static void test_open_detect(void)
{
    const double w_e = 300.0, V = 48.0, I = 24.0, f = 0.1;
    const double u = V - 0.64 * w_e / 8.0;                        /* margin over the flat-top line back-EMF */
    const double t2 = -(75e-6 / 0.05) * log(1.0 - 2.0 * f * I * 2.0 * 0.05 / u);
    for (int variant = 0; variant < 3; ++variant) { /* 0: open, test on; 1: open, test off; 2: healthy, on */
        bc_sixstep_params p = params(BC_SIXSTEP_PRED, BC_SIXSTEP_PWMPWM);
        p.open_frac = variant == 1 ? 0.0f : (float)f;
        bc_sixstep_state s;
        CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
        bc_ctrl_out o;
        double t_flag = -1.0, t_valid = -1.0;
        int stays = 1;
        for (double t = 0.0; t < 6.0 * (BC_PI / 3.0) / w_e; t += TS) {
            bc_ctrl_in in = input(0u, 0.0f, 0.0f, (float)V, (float)I);
            hall_at(t, w_e, 0, &in);
            if (variant == 2) {
                static const int pos_t[6] = {0, 0, 1, 1, 2, 2}, neg_t[6] = {1, 2, 2, 0, 0, 1};
                int sec = bc_hall_sector(in.hall);
                in.i_abc[0] = in.i_abc[1] = in.i_abc[2] = 0.0f;
                in.i_abc[pos_t[sec]] = (float)I;
                in.i_abc[neg_t[sec]] = (float)-I;
                in.i_mask = 7u;
            }
            bc_sixstep_step(&p, &s, &in, &o);
            if (t_valid < 0.0 && o.diag[4] != 0.0f) t_valid = t;
            if (t_flag >= 0.0 && !(o.flags & BC_FLAG_BAD_INPUT)) stays = 0;
            if (t_flag < 0.0 && (o.flags & BC_FLAG_BAD_INPUT)) t_flag = t;
        }
        if (variant == 0) {
            CHECK(t_valid >= 0.0 && t_flag > t_valid + 2.0 * t2, "not before 2 t_2 of full voltage: %g", t_flag);
            CHECK(t_flag <= t_valid + 2.0 * t2 + 7.0 * TS, "within 2 t_2 + 4 T_s (+ the sample grid): %g after %g",
                  t_flag, t_valid);
            CHECK(stays && all_off(&o) && (o.flags & BC_FLAG_SAFE), "latched in the safe state");
        } else {
            CHECK(t_flag < 0.0, "variant %d: no detection (flag at %g)", variant, t_flag);
        }
    }
}

static void test_predictive_two_phase(void)
{
    static const int pos_t[6] = {0, 0, 1, 1, 2, 2}, neg_t[6] = {1, 2, 2, 0, 0, 1};
    const double w_e = 300.0, V = 48.0, R = 0.05, L = 75e-6, ke = 0.64, T = TS;
    const double E2 = ke * w_e / 8.0; /* line back-EMF on the flat tops */
    const double i0 = 20.0, I = 24.0;
    const int chops[4] = {BC_SIXSTEP_HIGH, BC_SIXSTEP_BIPOLAR, BC_SIXSTEP_PWMPWM, BC_SIXSTEP_SYNC};
    for (int c = 0; c < 4; ++c) {
        for (int delay = 0; delay <= 1; ++delay) {
            bc_sixstep_params p = params(BC_SIXSTEP_PRED, chops[c]);
            p.delay = delay;
            p.advance = 0;
            bc_sixstep_state s;
            CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
            /* constant speed through three edges holding i0 (all phases measured), so that the speed estimate is
             * valid; then, in the middle of sector 2 (b+ c-, both on their flat tops), ask for I */
            double dt = (BC_PI / 3.0) / w_e;
            bc_ctrl_out o;
            bc_ctrl_in in;
            double t = 0.0;
            for (; t < 2.4 * dt; t += T) {
                in = input(0u, 0.0f, 0.0f, (float)V, (float)i0);
                hall_at(t, w_e, 0, &in);
                int sec = bc_hall_sector(in.hall);
                in.i_abc[pos_t[sec]] = (float)i0;
                in.i_abc[neg_t[sec]] = (float)-i0;
                in.i_mask = 7u;
                bc_sixstep_step(&p, &s, &in, &o);
            }
            CHECK(in.hall == 2u, "sector 2");
            const double m_prev = o.diag[3];
            in.ref = (float)I;
            hall_at(t, w_e, 0, &in);
            bc_sixstep_step(&p, &s, &in, &o);
            CHECK(o.diag[4] > 0.999f * (float)w_e && o.diag[4] < 1.001f * (float)w_e, "speed %g", (double)o.diag[4]);
            /* (delay 1: the synthetic current does not respond, so the deadbeat alternates around the hold) */
            if (!delay) CHECK_NEAR(m_prev, (2.0 * R * i0 + E2) / V, 1e-4, "holding i0: m = (2 R i0 + 2 E) / V");
            double i1 = delay ? i0 + T * (m_prev * V - 2.0 * R * i0 - E2) / (2.0 * L) : i0;
            double m = (2.0 * L * (I - i1) / T + 2.0 * R * i1 + E2) / V;
            CHECK(m > 0.05 && m < 0.95, "case not saturated (m = %g)", m);
            CHECK_NEAR(o.diag[3], m, 1e-4, "deadbeat pair voltage");
            CHECK(o.flags == 0u, "flags 0x%x", o.flags);
            /* the legs realise it: b is driven positive, c negative, a off */
            float db = o.leg[1].duty, dc = o.leg[2].duty, mm = o.diag[3];
            CHECK(o.leg[2].mode == BC_LEG_LOW && o.leg[0].mode == BC_LEG_OFF, "legs");
            if (chops[c] == BC_SIXSTEP_HIGH) CHECK(o.leg[1].mode == BC_LEG_HIGH && db == mm && dc == 1.0f, "high side");
            if (chops[c] == BC_SIXSTEP_SYNC) CHECK(o.leg[1].mode == BC_LEG_PWM && db == mm && dc == 1.0f, "sync");
            if (chops[c] == BC_SIXSTEP_BIPOLAR) CHECK_NEAR(db, 0.5f * (1.0f + mm), 1e-7, "bipolar d = (1 + m)/2");
            if (chops[c] == BC_SIXSTEP_BIPOLAR) CHECK(db == dc, "bipolar: both legs");
            if (chops[c] == BC_SIXSTEP_PWMPWM) CHECK((db == 1.0f) != (dc == 1.0f) && fminf(db, dc) == mm, "pwm-on-pwm");
            /* a reference out of reach: full voltage, flagged */
            in.ref = 99.0f;
            bc_sixstep_step(&p, &s, &in, &o);
            CHECK(o.diag[3] == 1.0f && (o.flags & BC_FLAG_SATURATED), "saturates at full voltage");
            CHECK(o.leg[1].duty == 1.0f && o.leg[2].duty == 1.0f, "both legs fully on");
            /* the reference is limited to i_max */
            in.ref = 1e9f;
            bc_sixstep_step(&p, &s, &in, &o);
            CHECK(o.diag[2] == p.i_max, "reference limited to i_max: %g", (double)o.diag[2]);
            /* zero reference from i0: the current must fall faster than freewheeling allows, m < 0 (regen) */
            in.ref = 0.0f;
            bc_sixstep_step(&p, &s, &in, &o);
            CHECK(o.diag[3] < 0.0f && o.leg[1].mode == BC_LEG_HIGH && o.leg[1].duty < 0.5f && o.leg[2].duty < 0.5f,
                  "regen: both legs chop, m = %g", (double)o.diag[3]);
        }
    }
    /* without regen a unipolar pattern stops at m = 0 */
    bc_sixstep_params p = params(BC_SIXSTEP_PRED, BC_SIXSTEP_HIGH);
    p.regen = 0;
    bc_sixstep_state s;
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
    bc_ctrl_in in = input(1u, 40.0f, -40.0f, 48.0f, 0.0f);
    bc_ctrl_out o;
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK(o.diag[3] == 0.0f && (o.flags & BC_FLAG_SATURATED) && o.leg[1].duty == 1.0f, "no regen: freewheel");
    /* torque reference: I = tau / k_e */
    p = params(BC_SIXSTEP_PRED, BC_SIXSTEP_HIGH);
    p.ref_torque = 1;
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
    in = input(1u, 0.0f, 0.0f, 48.0f, -16.0f);
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK_NEAR(o.diag[2], 25.0f, 1e-5, "16 N m / 0.64 V s/rad = 25 A");
    CHECK(o.leg[1].mode == BC_LEG_HIGH && o.leg[0].mode == BC_LEG_LOW, "negative torque: roles swapped");
}

/* ------------------------------------------------------------------------------------------------------------ */
/* commutation advance: no back-steps */

/* Hall input at capture tick `now` for edges at ticks e[0..n-1] (increasing) in direction dir, from sector s0
 * before the first edge: sector, edge count, tick of the last edge. */
static void hall_edges(uint32_t now, const uint32_t *e, int n, int s0, int dir, bc_ctrl_in *in)
{
    int k = 0;
    while (k < n && e[k] <= now) ++k;
    in->hall = bc_sector_code(((s0 + dir * k) % 6 + 6) % 6);
    in->n_edges = (uint32_t)k;
    in->tick_edge = k > 0 ? e[k - 1] : 0u;
    in->tick_now = now;
}

/* Step of the commanded sector between two samples in the direction dir: 0 same, 1 ahead, -1 back, 2 other. */
static int sector_step(int from, int to, int dir)
{
    int d = ((to - from) * dir % 6 + 6) % 6;
    return d == 0 ? 0 : (d == 1 ? 1 : (d == 5 ? -1 : 2));
}

/* A Hall edge that comes a little later than the speed predicts (the rotor slows by a few capture ticks per
 * sector, or tick rounding): the advance commands the next sector at the sample before the predicted edge; at the
 * next sample the edge is overdue and bc_hall's speed estimate has decayed to (pi/3)/(time since the edge), so the
 * angle "travelled" is pi/3 while the Hall code still shows the old sector. The commanded sector must stay the
 * next one (it used to fall back to the sector seen for a sample: a back-step), in both directions of rotation,
 * for a range of lateness (the decayed estimate times the time since the edge rounds either side of pi/3). Then
 * the rotor stops before the edge: the advanced sector is held even after the speed estimate has timed out, until
 * a Hall edge backward (the rotor reversed) proves it wrong. */
static void test_no_back_step(void)
{
    const double tick_per_sample = TS * F_TICK; /* 357.14 */
    const uint32_t D = 3571u;                   /* edge interval, about ten samples */
    bc_sixstep_params p = params(BC_SIXSTEP_PRED, BC_SIXSTEP_PWMPWM);
    int n_cases = 0, n_advanced = 0, n_overdue = 0, n_held = 0, n_end = 0, n_safe = 0, n_back = 0, n_other = 0;
    char first[160] = "";
    for (int dir = -1; dir <= 1; dir += 2) {
        for (uint32_t early = 1u; early <= 40u; ++early) {
            for (uint32_t late = 1u; late <= 40u; late += 13u) {
                bc_sixstep_state s;
                CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
                /* sample 40 comes `early` ticks after the edge predicted from the interval D; the real edge is
                 * `late` ticks after that sample */
                uint32_t t40 = (uint32_t)llround(40.0 * tick_per_sample);
                uint32_t e3 = t40 - early - D;
                uint32_t e[4] = {e3 - 2u * D, e3 - D, e3, t40 + late};
                int prev = -1;
                for (int k = 0; k < 46; ++k) { /* the next edge, after sample 40, would be overdue at about 50 */
                    uint32_t now = (uint32_t)llround((double)k * tick_per_sample);
                    bc_ctrl_in in = input(0u, 0.0f, 0.0f, 48.0f, 30.0f);
                    hall_edges(now, e, 4, 5, dir, &in);
                    bc_ctrl_out o;
                    bc_sixstep_step(&p, &s, &in, &o);
                    int cmd = (int)o.diag[0];
                    n_safe += (o.flags & BC_FLAG_SAFE) != 0u;
                    if (prev >= 0) {
                        int st = sector_step(prev, cmd, dir);
                        n_back += st < 0;
                        n_other += st == 2;
                        if (st < 0 && first[0] == '\0')
                            snprintf(first, sizeof first, "dir %d early %u late %u sample %d: sector %d -> %d", dir,
                                     early, late, k, prev, cmd);
                    }
                    /* sample 39: the edge is predicted within 1.5 samples, the next sector is commanded */
                    if (k == 39) n_advanced += cmd == (5 + 4 * dir) % 6 && bc_hall_sector(in.hall) == (5 + 3 * dir) % 6;
                    if (k == 40) {
                        /* the edge is overdue, not seen yet; the estimate has decayed below pi/3 over D */
                        n_overdue += bc_hall_sector(in.hall) == (5 + 3 * dir) % 6 &&
                                     (double)o.diag[4] * (double)dir < (BC_PI / 3.0) / ((double)D / F_TICK);
                        n_held += cmd == (5 + 4 * dir) % 6;
                    }
                    prev = cmd;
                }
                ++n_cases;
                n_end += prev == (5 + 4 * dir) % 6;
            }
        }
    }
    CHECK(n_safe == 0, "safe state in %d samples", n_safe);
    CHECK(n_advanced == n_cases, "the advance fired before the edge in %d of %d cases", n_advanced, n_cases);
    CHECK(n_overdue == n_cases, "overdue edge with a decayed estimate in %d of %d cases", n_overdue, n_cases);
    CHECK(n_back == 0 && n_other == 0, "%d back-steps (first: %s), %d other jumps, in %d cases", n_back, first,
          n_other, n_cases);
    CHECK(n_held == n_cases, "advanced sector held at the overdue sample in %d of %d cases", n_held, n_cases);
    CHECK(n_end == n_cases, "ends in the sector after the late edge in %d of %d cases", n_end, n_cases);

    /* the rotor stops just before the edge after the advance: held through the speed time-out, then a Hall edge
     * backward (a real reversal) takes it back */
    bc_sixstep_state s;
    CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
    uint32_t t40 = (uint32_t)llround(40.0 * tick_per_sample);
    uint32_t e3 = t40 - 5u - D;
    uint32_t e[3] = {e3 - 2u * D, e3 - D, e3};
    bc_ctrl_out o;
    int k = 0;
    for (; k < 40; ++k) {
        bc_ctrl_in in = input(0u, 0.0f, 0.0f, 48.0f, 30.0f);
        hall_edges((uint32_t)llround((double)k * tick_per_sample), e, 3, 5, 1, &in);
        bc_sixstep_step(&p, &s, &in, &o);
    }
    CHECK((int)o.diag[0] == 3, "advanced to sector 3 before the edge (%d)", (int)o.diag[0]);
    /* omega_min = 6 rad/s: the estimate times out (pi/3)/6 = 0.17 s after the edge; run 0.3 s */
    int n_moved = 0;
    for (; k < 40 + (int)(0.3 / TS); ++k) {
        bc_ctrl_in in = input(0u, 0.0f, 0.0f, 48.0f, 30.0f);
        hall_edges((uint32_t)llround((double)k * tick_per_sample), e, 3, 5, 1, &in);
        bc_sixstep_step(&p, &s, &in, &o);
        n_moved += (int)o.diag[0] != 3;
    }
    CHECK(n_moved == 0, "stopped rotor: the advanced sector left in %d samples", n_moved);
    CHECK(o.diag[4] == 0.0f, "the speed estimate has timed out");
    /* the rotor goes back into sector 1: edge backward */
    bc_ctrl_in in = input(bc_sector_code(1), 0.0f, 0.0f, 48.0f, 30.0f);
    in.n_edges = 4u;
    in.tick_now = (uint32_t)llround((double)k * tick_per_sample);
    in.tick_edge = in.tick_now - 10u;
    bc_sixstep_step(&p, &s, &in, &o);
    CHECK((int)o.diag[0] == 1, "a Hall edge backward: the sector seen (%d)", (int)o.diag[0]);
}

/* ------------------------------------------------------------------------------------------------------------ */
/* closed loop with the htm-48v plant */

typedef struct {
    fixture f;
    bc_sixstep_params cp;
    bc_sixstep_state cs;
    bc_sim_config cfg;
    bc_sim_inputs in;
    bc_sim_state s;
} rig;

static void slot(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sixstep_step(p, s, in, out); }

static const double I0[3] = {0.0, 0.0, 0.0};

static void rig_make(rig *r, int mech, int reg, int chop, double omega, double ref)
{
    memset(r, 0, sizeof *r);
    fixture_htm(&r->f, mech);
    r->cp = params(reg, chop);
    CHECK(bc_sixstep_init(&r->cp, &r->cs) == BC_OK, "init");
    r->cfg.plant = &r->f.p;
    r->cfg.sensors = &r->f.sp;
    r->cfg.ctrl.step = slot;
    r->cfg.ctrl.params = &r->cp;
    r->cfg.ctrl.state = &r->cs;
    r->cfg.delay = 1;
    r->cfg.trace_every = 1;
    r->cfg.trace_sub = 1;
    r->in.ref_c = ref;
    r->in.omega_c = omega;
    r->in.v_src_c = 48.0;
}

#define NROWS 12000
static bc_trace_row rows[NROWS];

/* Run 4 electrical periods at imposed speed, metrics over the last 2; return rows written. */
static int64_t run_imposed(rig *r, double omega)
{
    double Te = 2.0 * BC_PI / (8.0 * fabs(omega));
    r->cfg.metric_t0 = 2.0 * Te;
    r->cfg.metric_t1 = 4.0 * Te;
    CHECK(bc_sim_init(&r->cfg, &r->s, 0.1, omega, I0, 48.0) == BC_OK, "sim init");
    int64_t n = (int64_t)ceil(4.0 * Te / TS) + 1;
    int64_t nw = 0;
    CHECK(n <= NROWS, "buffer");
    CHECK(bc_sim_run(&r->cfg, &r->s, &r->in, n, rows, NROWS, &nw) == BC_OK, "run");
    CHECK(r->s.m.state == 2, "metric window closed");
    return nw;
}

static double tau_mean(const rig *r) { return r->s.m.E[BC_ACC_TAU] / (r->s.m.t1 - r->s.m.t0); }

/* Regulation error at the samples of the metric window in two-phase conduction (outgoing current zero), skipping
 * the samples while the incoming current is still rising at full voltage. */
static void reg_error(const rig *r, int64_t nw, double ref, double *mean_err, double *max_err, long *n_used)
{
    double sum = 0.0, mx = 0.0;
    long n = 0;
    for (int64_t k = 3; k < nw; ++k) {
        const bc_trace_row *w = &rows[k];
        if (w->t < r->s.m.t0 || w->t >= r->s.m.t1) continue;
        if (w->d7 != 0.0 || rows[k - 1].d7 != 0.0 || rows[k - 2].d7 != 0.0 || w->d3 >= 1.0 || rows[k - 1].d3 >= 1.0 ||
            rows[k - 2].d3 >= 1.0)
            continue;
        double e = w->d1 - ref;
        sum += e;
        if (fabs(e) > mx) mx = fabs(e);
        ++n;
    }
    *mean_err = n ? sum / (double)n : 1e9;
    *max_err = mx;
    *n_used = n;
}

static void test_closed_loop_predictive(void)
{
    static rig r;
    const double om = 0.3 * 75.0, I = 40.0;
    rig_make(&r, BC_MECH_IMPOSED, BC_SIXSTEP_PRED, BC_SIXSTEP_PWMPWM, om, I);
    int64_t nw = run_imposed(&r, om);
    double me, mx;
    long n;
    reg_error(&r, nw, I, &me, &mx, &n);
    CHECK(n > 500, "samples used %ld", n);
    CHECK(mx < 0.01, "deadbeat holds the reference: worst error %.4f A", mx);
    /* the sampled current is the plant's: the conducting phases carry +-I at the samples */
    int checked = 0;
    for (int64_t k = 3; k < nw; ++k) {
        const bc_trace_row *w = &rows[k];
        if (w->t < r.s.m.t0 || w->d7 != 0.0 || rows[k - 1].d7 != 0.0 || rows[k - 2].d3 >= 1.0 || w->d3 >= 1.0) continue;
        double imax = fmax(fabs(w->i_a), fmax(fabs(w->i_b), fabs(w->i_c)));
        CHECK(fabs(imax - I) < 0.01, "plant current %.3f at t = %.6f", imax, w->t);
        if (++checked > 50) break;
    }
    /* mean torque k_e I plus the small positive commutation excess of paper 1 (26) (R = 50 mOhm here), and the
     * positive commutation spike of the low-speed process */
    double T_N = 0.64 * I;
    double tm = tau_mean(&r);
    CHECK(fabs(tm / T_N - 1.0) < 0.01, "mean torque %.4f of k_e I", tm / T_N);
    CHECK(r.s.m.tau_ma_max / T_N > 1.1, "positive commutation spike at low speed: %.3f", r.s.m.tau_ma_max / T_N);
    long n_safe = 0;
    for (int64_t k = 0; k < nw; ++k) n_safe += ((uint32_t)rows[k].flags & BC_FLAG_SAFE) != 0u;
    CHECK(n_safe == 0, "never in the safe state: %ld samples", n_safe);
}

static void test_closed_loop_options(void)
{
    static rig r;
    const double om = 0.3 * 75.0, I = 40.0, T_N = 0.64 * I;
    const int chops[4] = {BC_SIXSTEP_BIPOLAR, BC_SIXSTEP_HIGH, BC_SIXSTEP_PWMPWM, BC_SIXSTEP_SYNC};
    for (int c = 0; c < 4; ++c) {
        /* PI with back-EMF feed-forward: the mean error over two-phase conduction is small */
        rig_make(&r, BC_MECH_IMPOSED, BC_SIXSTEP_PI, chops[c], om, I);
        int64_t nw = run_imposed(&r, om);
        double me, mx;
        long n;
        reg_error(&r, nw, I, &me, &mx, &n);
        /* the integrator moves during the full-voltage rise after each commutation (back-calculation with gain
         * 1/k_p): a positive offset of about 1.5 % remains at 0.3 Omega_0 */
        CHECK(fabs(me) < 1.0 && n > 300, "PI chop %d: mean error %.3f A over %ld samples", chops[c], me, n);
        CHECK(fabs(tau_mean(&r) / T_N - 1.0) < 0.02, "PI chop %d: torque %.4f", chops[c], tau_mean(&r) / T_N);
        /* predictive with every pattern */
        rig_make(&r, BC_MECH_IMPOSED, BC_SIXSTEP_PRED, chops[c], om, I);
        nw = run_imposed(&r, om);
        reg_error(&r, nw, I, &me, &mx, &n);
        CHECK(mx < 0.01, "predictive chop %d: worst error %.4f A", chops[c], mx);
    }
    /* hysteresis with bipolar chopping, decided at the samples and applied one sample later: in two-phase
     * conduction the sampled current stays within the band widened by two samples of the full-voltage slope each
     * way, s_on = (V - 2E - 2RI) T / (2L) up, s_off = (V + 2E + 2RI) T / (2L) down (about 8 and 15 A here, so the
     * 5 A band itself cannot be held at 28 kHz) */
    rig_make(&r, BC_MECH_IMPOSED, BC_SIXSTEP_HYST, BC_SIXSTEP_BIPOLAR, om, I);
    int64_t nw = run_imposed(&r, om);
    const double V = 48.0, E2 = 0.64 * om, L = 75e-6, R = 0.05;
    double s_on = (V - E2 - 2.0 * R * I) * TS / (2.0 * L), s_off = (V + E2 + 2.0 * R * I) * TS / (2.0 * L);
    double lo = 1e9, hi = -1e9;
    int n_on = 0, n_off = 0;
    for (int64_t k = 3; k < nw; ++k) {
        const bc_trace_row *w = &rows[k];
        if (w->t < r.s.m.t0 || w->d7 != 0.0 || rows[k - 1].d7 != 0.0 || rows[k - 2].d7 != 0.0) continue;
        if (w->d1 < lo) lo = w->d1;
        if (w->d1 > hi) hi = w->d1;
        n_on += w->d3 == 1.0;
        n_off += w->d3 == -1.0;
    }
    CHECK(n_on > 100 && n_off > 100, "two-level switching: %d on, %d off", n_on, n_off);
    CHECK(hi <= I + 2.5 + 2.0 * s_on && lo >= I - 2.5 - 2.0 * s_off, "hysteresis: current in [%.2f, %.2f], bounds "
          "[%.2f, %.2f]", lo, hi, I - 2.5 - 2.0 * s_off, I + 2.5 + 2.0 * s_on);
    CHECK(hi > I + 2.5 + 0.5 * s_on && lo < I - 2.5 - 0.5 * s_off, "the delay widens the band: [%.2f, %.2f]", lo, hi);
}

/* Reverse reference while turning forward: regenerative braking. In two-phase conduction the current is held
 * exactly; at each commutation (roles swapped, R neglected) the incoming current rises at 2 (V + E)/(3 L) to I in
 * t1 while the outgoing one only decays at (V - 2 E)/(3 L) (the deadbeat holds the incoming current with both legs
 * chopping, m < 0), so the continuing phase carries I + i_out: a mean braking torque above k_e I by
 * i_out(t1) (t1 + t_decay) / (2 I T_sector). */
static void test_braking(void)
{
    static rig r;
    const double om = 0.5 * 75.0, I = 30.0, V = 48.0, L = 75e-6, E = 0.32 * om;
    rig_make(&r, BC_MECH_IMPOSED, BC_SIXSTEP_PRED, BC_SIXSTEP_PWMPWM, om, -I);
    int64_t nw = run_imposed(&r, om);
    double me, mx;
    long n;
    reg_error(&r, nw, I, &me, &mx, &n);
    CHECK(mx < 0.02 && n > 500, "braking current held: worst error %.4f A", mx);
    double t1 = 3.0 * L * I / (2.0 * (V + E));
    double i_out = I - (V - 2.0 * E) * t1 / (3.0 * L);
    double t_dec = 3.0 * L * i_out / (V - 2.0 * E);
    double excess = 0.5 * i_out * (t1 + t_dec) / ((BC_PI / 3.0) / (8.0 * om)) / I;
    double ratio = tau_mean(&r) / (-0.64 * I);
    CHECK(fabs(ratio - 1.0 - excess) < 0.003, "braking torque %.4f k_e I, commutation estimate %.4f", ratio,
          1.0 + excess);
    CHECK(r.s.m.E[BC_ACC_SRC] < 0.0, "energy returned to the bus: %.3f J", r.s.m.E[BC_ACC_SRC]);
}

/* From standstill with rotor dynamics: the Hall sector alone (no speed yet) starts the motor. */
static void test_start_up(void)
{
    static rig r;
    rig_make(&r, BC_MECH_DYNAMIC, BC_SIXSTEP_PRED, BC_SIXSTEP_PWMPWM, 0.0, 30.0);
    CHECK(bc_sim_init(&r.cfg, &r.s, 1.0, 0.0, I0, 48.0) == BC_OK, "init");
    int64_t nw;
    CHECK(bc_sim_run(&r.cfg, &r.s, &r.in, 2000, 0, 0, &nw) == BC_OK, "run");
    /* J = 0.05 kg m^2, no friction, tau = k_e I = 19.2 N m for 71 ms */
    double expect = 0.64 * 30.0 / 0.05 * 2000.0 * TS;
    CHECK(r.s.plant.omega > 0.9 * expect && r.s.plant.omega < 1.05 * expect, "speed %.2f rad/s, expected about %.2f",
          r.s.plant.omega, expect);
}

/* Timed commutation (timed = 1) with a timing advance: a rotor at constant speed with nominal Hall edges; whenever the
 * advanced boundary pi/6 + j pi/3 - adv falls inside the interval an output applies to ([t_k + T_s, t_k + 2 T_s) with
 * delay 1), the output schedules the next sector's legs at that instant (has_at, t_at), to the capture timer's
 * resolution; otherwise it schedules nothing. The sector in force follows the advanced boundaries exactly. */
static void test_timed_commutation(void)
{
    const double edges[6] = {BC_PI / 6.0, BC_PI / 2.0, 5.0 * BC_PI / 6.0, 7.0 * BC_PI / 6.0, 3.0 * BC_PI / 2.0,
                             11.0 * BC_PI / 6.0};
    for (int ia = 0; ia < 3; ++ia) {
        const double adv = (double)ia * BC_PI / 18.0; /* 0, 10, 20 degrees */
        const double w = 2.0 * BC_PI * 600.0;            /* 600 Hz electrical: 7.8 samples per sector at 28 kHz */
        bc_sixstep_params p = params(BC_SIXSTEP_DUTY, BC_SIXSTEP_HIGH);
        p.timed = 1;
        p.adv_angle = (float)adv;
        bc_sixstep_state s;
        CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
        synth_hall g;
        synth_init(&g, edges, w, 0.0, TS, F_TICK);
        int n_sched = 0, n_due = 0, n_wrong = 0;
        double worst = 0.0;
        for (long k = 0; k < 400; ++k) {
            bc_ctrl_in in;
            synth_sample(&g, k, &in);
            in.ref = 0.8f;
            bc_ctrl_out o;
            memset(&o, 0, sizeof o);
            bc_sixstep_step(&p, &s, &in, &o);
            if (k < 40) continue; /* the speed estimate needs two edges */
            /* the advanced boundaries inside [t_a, t_a + T_s), t_a = (k + 1) T_s */
            double t_a = (double)(k + 1) * TS, th_a = synth_theta(&g, t_a), th_b = synth_theta(&g, t_a + TS);
            double first = HUGE_VAL;
            for (int j = -1; j < 200; ++j) {
                double b = BC_PI / 6.0 + (double)j * BC_PI / 3.0 - adv;
                if (b >= th_a && b < th_b) {
                    first = (b - th_a) / w;
                    break;
                }
            }
            int due = first < HUGE_VAL;
            n_due += due;
            if (o.has_at) {
                ++n_sched;
                double err = fabs((double)o.t_at - first);
                if (err > worst) worst = err;
                /* the next sector's legs: its positive phase HIGH, its negative LOW */
                int pn, nn;
                (void)bc_sector_phases((int)o.diag[0] == 5 ? 0 : (int)o.diag[0] + 1, &pn, &nn);
                if (o.leg_at[pn].mode != BC_LEG_HIGH || o.leg_at[nn].mode != BC_LEG_LOW) ++n_wrong;
            }
            if (due != (int)o.has_at) ++n_wrong;
        }
        CHECK(n_due > 20 && n_sched == n_due && n_wrong == 0, "adv %.0f deg: %d commutations due, %d scheduled, %d "
              "wrong", adv * 180.0 / BC_PI, n_due, n_sched, n_wrong);
        CHECK(worst < 2.0 / F_TICK, "adv %.0f deg: scheduled instants within %.3g s (2 capture ticks)",
              adv * 180.0 / BC_PI, worst);
    }
}

/* Temperature derating (bc_derate.h via p.derate): the reference's limit is f(T) i_max, the winding's band 100-150
 * degC with f_min 0.2; no sensor (NaN) gives f_fault; a band that is not valid is refused at init. */
static void test_derating(void)
{
    bc_sixstep_params p = params(BC_SIXSTEP_PRED, BC_SIXSTEP_HIGH);
    p.derate.enabled[0] = 1;
    p.derate.T_start[0] = 100.0f;
    p.derate.T_end[0] = 150.0f;
    p.derate.f_min = 0.2f;
    p.derate.f_fault = 0.5f;
    p.derate.T_lo = -40.0f;
    p.derate.T_hi = 250.0f;
    p.derate.tau = 0.0f;
    p.derate.ts = (float)TS;
    bc_sixstep_state s;
    bc_ctrl_out o;
    const float temps[][2] = {{25.0f, 1.0f}, {125.0f, 0.6f}, {160.0f, 0.2f}, {NAN, 0.5f}, {400.0f, 0.5f}};
    for (int k = 0; k < 5; ++k) {
        CHECK(bc_sixstep_init(&p, &s) == BC_OK, "init");
        bc_ctrl_in in = input(1u, 0.0f, 0.0f, 48.0f, 1e9f);
        in.temp[0] = temps[k][0];
        in.temp[1] = NAN; /* channel 1 not fitted: ignored */
        bc_sixstep_step(&p, &s, &in, &o);
        CHECK_NEAR(o.diag[2], temps[k][1] * p.i_max, 1e-4, "derated limit");
        for (int x = 0; x < 3; ++x) CHECK(isfinite(o.leg[x].duty) && o.leg[x].duty >= 0.0f && o.leg[x].duty <= 1.0f,
                                          "duty in [0, 1]");
    }
    p.derate.T_end[0] = 90.0f;
    CHECK(bc_sixstep_init(&p, &s) == BC_ERR_PARAM, "a band ending before it starts is refused");
}

int main(void)
{
    test_derating();
    test_ideal_legs();
    test_init();
    test_commutation_table();
    test_safe_states();
    test_open_detect();
    test_fuzz();
    test_average_model();
    test_predictive_two_phase();
    test_no_back_step();
    test_closed_loop_predictive();
    test_closed_loop_options();
    test_braking();
    test_start_up();
    test_timed_commutation();
    return bc_test_summary("test_sixstep");
}

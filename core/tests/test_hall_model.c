/* test_hall_model.c - the plant's Hall error model (bc_plant.h, docs/hall.md): placement error, hysteresis,
 * per-sensor propagation delay and the RC line filter move every edge by exactly the expected angle or time at
 * constant speed, both directions; a reversal inside the hysteresis band switches nothing; the filter swallows a
 * pulse shorter than tau ln 2 and passes a longer one at the exact RC crossing times; bad parameters are refused
 * and extreme ones stay finite. */
#include <math.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_plant.h"
#include "fixtures.h"

static const double I0[3] = {0.0, 0.0, 0.0};
static const double PHI[3] = {0.0, 2.0 * BC_PI / 3.0, 4.0 * BC_PI / 3.0};

/* distance of a from b modulo pi, in [0, pi/2] */
static double mod_pi(double a, double b)
{
    double d = fmod(a - b, BC_PI);
    if (d < 0.0) d += BC_PI;
    return d > 0.5 * BC_PI ? BC_PI - d : d;
}

static void legs_off(bc_leg_cmd *c)
{
    for (int x = 0; x < 3; ++x) {
        c[x].mode = BC_LEG_OFF;
        c[x].duty = 0.0f;
    }
}

/* Constant speed omega (mechanical) with the errors of f: every edge seen by the controller, moved back by the
 * sensor's delay d_x + tau_x ln 2, sits at the rotor angle PHI_x - pi/6 + err_x + dir h_x / 2 (mod pi). */
static void edges_at_constant_speed(const fixture *f, double omega, const char *what)
{
    bc_plant_state s;
    double th0 = 0.3;
    CHECK(bc_plant_init(&f->p, &s, 0.0, th0, omega, I0, 48.0) == BC_OK, "%s: init", what);
    bc_leg_cmd c[3];
    legs_off(c);
    double dir = omega > 0.0 ? 1.0 : -1.0, th = bc_plant_t_half(&f->p), worst = 0.0;
    int32_t code = s.hall_out;
    uint32_t edges = s.n_edges;
    int seen[3] = {0, 0, 0};
    for (long k = 0; k < 4000; ++k) {
        bc_plant_set_half(&f->p, &s, c, (k % 2) == 0);
        bc_plant_advance(&f->p, &s, (double)(k + 1) * th);
        if (s.n_edges == edges) continue;
        CHECK(s.n_edges == edges + 1u, "%s: one edge per half period", what);
        int32_t diff = s.hall_out ^ code;
        int x = diff == 1 ? 0 : (diff == 2 ? 1 : (diff == 4 ? 2 : -1));
        CHECK(x >= 0, "%s: one sensor per edge (code %d -> %d)", what, code, s.hall_out);
        edges = s.n_edges;
        code = s.hall_out;
        if (x < 0) continue;
        double t_raw = s.t_edge - f->p.hall_delay[x] - f->p.hall_tau[x] * log(2.0);
        double th_raw = th0 + (double)f->p.p * omega * t_raw;
        double expect = PHI[x] - BC_PI / 6.0 + f->p.hall_error[x] + dir * 0.5 * f->p.hall_hyst[x];
        double e = mod_pi(th_raw, expect);
        if (e > worst) worst = e;
        seen[x] += 1;
    }
    CHECK(seen[0] >= 4 && seen[1] >= 4 && seen[2] >= 4, "%s: edges seen %d %d %d", what, seen[0], seen[1], seen[2]);
    CHECK(worst < 1e-9, "%s: worst edge angle error %.3g rad", what, worst);
}

static void test_each_error_moves_the_edges(void)
{
    const double omega = 30.0; /* 240 rad/s electrical: edges 4.4 ms apart */
    for (int dir = -1; dir <= 1; dir += 2) {
        fixture f;
        fixture_htm(&f, BC_MECH_IMPOSED);
        edges_at_constant_speed(&f, dir * omega, dir > 0 ? "ideal fwd" : "ideal back");
        fixture_htm(&f, BC_MECH_IMPOSED);
        f.p.hall_error[0] = 0.05;
        f.p.hall_error[1] = -0.12;
        f.p.hall_error[2] = 0.2;
        edges_at_constant_speed(&f, dir * omega, dir > 0 ? "placement fwd" : "placement back");
        fixture_htm(&f, BC_MECH_IMPOSED);
        f.p.hall_hyst[0] = 0.02;
        f.p.hall_hyst[1] = 0.1;
        f.p.hall_hyst[2] = 0.9;
        edges_at_constant_speed(&f, dir * omega, dir > 0 ? "hysteresis fwd" : "hysteresis back");
        fixture_htm(&f, BC_MECH_IMPOSED);
        f.p.hall_delay[0] = 3e-6;
        f.p.hall_delay[1] = 0.0;
        f.p.hall_delay[2] = 250e-6;
        edges_at_constant_speed(&f, dir * omega, dir > 0 ? "delay fwd" : "delay back");
        fixture_htm(&f, BC_MECH_IMPOSED);
        f.p.hall_tau[0] = 10e-6;
        f.p.hall_tau[1] = 47e-6;
        f.p.hall_tau[2] = 0.0;
        edges_at_constant_speed(&f, dir * omega, dir > 0 ? "filter fwd" : "filter back");
        fixture_htm(&f, BC_MECH_IMPOSED);
        for (int x = 0; x < 3; ++x) {
            f.p.hall_error[x] = 0.03 * (double)(x - 1);
            f.p.hall_hyst[x] = 0.04;
            f.p.hall_delay[x] = 5e-6 * (double)(x + 1);
            f.p.hall_tau[x] = 20e-6;
        }
        edges_at_constant_speed(&f, dir * omega, dir > 0 ? "all fwd" : "all back");
    }
}

/* Sensor a's forward edge at -pi/6 + h/2; the rotor turns forward to -pi/6 + h/4 (inside the band, never
 * switching), reverses and turns back past -pi/6: still no edge until -pi/6 - pi - h/2; and without hysteresis the
 * same path switches twice. */
static int edges_of_a_on_band_path(double h)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.hall_hyst[0] = h;
    const double w = 10.0, we = 8.0 * w;
    double th = bc_plant_t_half(&f.p);
    const long N = 70; /* half periods each way: 70 / 28 kHz * 80 rad/s = 0.2 rad electrical */
    double th0 = -BC_PI / 6.0 - we * (double)N * th + 0.25 * (h > 0.0 ? h : 0.4);
    bc_plant_state s;
    CHECK(bc_plant_init(&f.p, &s, 0.0, th0 + BC_TWO_PI, w, I0, 48.0) == BC_OK, "band: init");
    bc_leg_cmd c[3];
    legs_off(c);
    int n = 0;
    int32_t code = s.hall_out;
    for (long k = 0; k < 2 * N; ++k) {
        if (k == N) bc_plant_set_inputs(&f.p, &s, -w, 0.0, 48.0);
        bc_plant_set_half(&f.p, &s, c, (k % 2) == 0);
        bc_plant_advance(&f.p, &s, (double)(k + 1) * th);
        if ((s.hall_out ^ code) & 1) ++n;
        code = s.hall_out;
    }
    return n;
}

static void test_hysteresis_band_reversal(void)
{
    CHECK(edges_of_a_on_band_path(0.4) == 0, "a reversal inside the band switches nothing");
    CHECK(edges_of_a_on_band_path(0.0) == 2, "without hysteresis the same path switches twice");
}

/* The rotor turns forward across sensor a's edge and back after a raw pulse of width wp: the filtered input sees
 * nothing if wp < tau ln 2, else two edges at the RC crossing times. */
static void glitch(double wp, double tau, int *n_edges, double *t_edges)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.hall_tau[0] = tau;
    f.p.h_max = 1e-6;
    const double w = 10.0, we = 8.0 * w, t1 = 2e-6; /* raw edges at t1 and t1 + wp */
    double th0 = -BC_PI / 6.0 - we * t1 + BC_TWO_PI;
    bc_plant_state s;
    CHECK(bc_plant_init(&f.p, &s, 0.0, th0, w, I0, 48.0) == BC_OK, "glitch: init");
    bc_leg_cmd c[3];
    legs_off(c);
    bc_plant_set_half(&f.p, &s, c, 1);
    *n_edges = 0;
    int32_t code = s.hall_out;
    double t_rev = t1 + 0.5 * wp, t = 0.0, dt = 0.25e-6;
    while (t < t_rev + 20.0 * tau + 20e-6) {
        double tn = t + dt;
        if (t < t_rev && tn > t_rev) tn = t_rev;
        bc_plant_advance(&f.p, &s, tn);
        t = tn;
        if (t == t_rev) bc_plant_set_inputs(&f.p, &s, -w, 0.0, 48.0);
        if ((s.hall_out ^ code) & 1) {
            if (*n_edges < 2) t_edges[*n_edges] = s.t_edge;
            *n_edges += 1;
        }
        code = s.hall_out;
    }
}

static void test_filter_glitch(void)
{
    const double tau = 10e-6, t1 = 2e-6, lim = tau * log(2.0);
    int n;
    double te[2];
    glitch(0.8 * lim, tau, &n, te);
    CHECK(n == 0, "a %.3g us pulse (< tau ln 2 = %.3g us) is swallowed, saw %d edges", 0.8 * lim * 1e6, lim * 1e6, n);
    double wp = 1.5 * lim;
    glitch(wp, tau, &n, te);
    CHECK(n == 2, "a %.3g us pulse passes as two edges, saw %d", wp * 1e6, n);
    if (n == 2) {
        double v = 1.0 - exp(-wp / tau); /* level when the line falls back */
        CHECK_NEAR(te[0], t1 + lim, 1e-12, "rising edge at t1 + tau ln 2");
        CHECK_NEAR(te[1], t1 + wp + tau * log(v / 0.5), 1e-12, "falling edge at the RC crossing");
    }
    /* without the filter the same pulse is seen as it is */
    glitch(0.8 * lim, 0.0, &n, te);
    CHECK(n == 2, "unfiltered: the short pulse is seen, %d edges", n);
    if (n == 2) CHECK_NEAR(te[1] - te[0], 0.8 * lim, 1e-12, "unfiltered pulse width");
}

static void test_bad_and_extreme(void)
{
    fixture f;
    bc_plant_state s;
    const double bad[] = {-1e-9, NAN, INFINITY};
    for (int j = 0; j < 3; ++j) {
        fixture_htm(&f, BC_MECH_IMPOSED);
        f.p.hall_delay[1] = bad[j];
        CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 30.0, I0, 48.0) == BC_ERR_PARAM, "delay %g refused", bad[j]);
        fixture_htm(&f, BC_MECH_IMPOSED);
        f.p.hall_tau[2] = bad[j];
        CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 30.0, I0, 48.0) == BC_ERR_PARAM, "tau %g refused", bad[j]);
        fixture_htm(&f, BC_MECH_IMPOSED);
        f.p.hall_hyst[0] = bad[j];
        CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 30.0, I0, 48.0) == BC_ERR_PARAM, "hysteresis %g refused", bad[j]);
    }
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.hall_hyst[0] = BC_PI / 3.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 30.0, I0, 48.0) == BC_ERR_PARAM, "hysteresis pi/3 refused");
    /* extremes: finite state, codes in range, both directions */
    const double delays[] = {0.0, 1e-300, 1e-3, 1e6, 1.7e308};
    const double taus[] = {0.0, 1e-300, 1e-3, 1e6, 1.7e308};
    for (int j = 0; j < 5; ++j) {
        for (int d = -1; d <= 1; d += 2) {
            fixture_htm(&f, BC_MECH_IMPOSED);
            for (int x = 0; x < 3; ++x) {
                f.p.hall_error[x] = (double)(x - 1) * nextafter(BC_PI / 6.0, 0.0);
                f.p.hall_hyst[x] = nextafter(BC_PI / 3.0, 0.0);
                f.p.hall_delay[x] = delays[(j + x) % 5];
                f.p.hall_tau[x] = taus[(j + 2 * x) % 5];
            }
            CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 600.0 * d, I0, 48.0) == BC_OK, "extreme init");
            bc_leg_cmd c[3];
            legs_off(c);
            double th = bc_plant_t_half(&f.p);
            int ok = 1;
            for (long k = 0; k < 3000; ++k) {
                bc_plant_set_half(&f.p, &s, c, (k % 2) == 0);
                bc_plant_advance(&f.p, &s, (double)(k + 1) * th);
                if (k == 1500) bc_plant_set_inputs(&f.p, &s, -600.0 * d, 0.0, 48.0);
                ok &= isfinite(s.t) && isfinite(s.theta) && s.hall_out >= 0 && s.hall_out <= 7;
                for (int q = 0; q < s.hq_n; ++q) ok &= !isnan(s.hq_t[q]);
                for (int x = 0; x < 3; ++x) ok &= isfinite(s.hf_v[x]) && s.hf_v[x] >= 0.0 && s.hf_v[x] <= 1.0;
            }
            CHECK(ok, "extreme set %d dir %d: finite state", j, d);
        }
    }
}

int main(void)
{
    test_each_error_moves_the_edges();
    test_hysteresis_band_reversal();
    test_filter_glitch();
    test_bad_and_extreme();
    return bc_test_summary("test_hall_model");
}

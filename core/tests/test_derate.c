/* test_derate.c - temperature derating (bc_derate.h): the band, two channels, the filter against its closed form,
 * sensor faults, any input giving a factor in [0, 1], the resistance method. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_derate.h"

static bc_derate_params params(void)
{
    bc_derate_params p;
    memset(&p, 0, sizeof p);
    p.enabled[0] = 1;
    p.T_start[0] = 100.0f;
    p.T_end[0] = 150.0f;
    p.enabled[1] = 1;
    p.T_start[1] = 80.0f;
    p.T_end[1] = 110.0f;
    p.f_min = 0.2f;
    p.f_fault = 0.2f;
    p.T_lo = -40.0f;
    p.T_hi = 250.0f;
    p.tau = 0.0f;
    p.ts = 0.01f;
    return p;
}

static void test_band(void)
{
    bc_derate_params p = params();
    bc_derate_state s;
    CHECK(bc_derate_init(&p, &s) == BC_OK, "init");
    const float cases[][3] = {/* T winding, T switches, factor */
                              {25.0f, 25.0f, 1.0f},   {100.0f, 25.0f, 1.0f},  {125.0f, 25.0f, 0.6f},
                              {150.0f, 25.0f, 0.2f},  {200.0f, 25.0f, 0.2f},  {25.0f, 95.0f, 0.6f},
                              {125.0f, 95.0f, 0.6f},  {140.0f, 95.0f, 0.36f}, {25.0f, 110.0f, 0.2f}};
    for (int k = 0; k < 9; ++k) {
        bc_derate_init(&p, &s);
        const float T[2] = {cases[k][0], cases[k][1]};
        CHECK_NEAR(bc_derate_step(&p, &s, T), cases[k][2], 1e-6, "band");
    }
    p.enabled[1] = 0; /* a channel not fitted is ignored, whatever it reads */
    bc_derate_init(&p, &s);
    const float T[2] = {125.0f, NAN};
    CHECK_NEAR(bc_derate_step(&p, &s, T), 0.6f, 1e-6, "one channel");
    p.enabled[0] = 0;
    bc_derate_init(&p, &s);
    CHECK(bc_derate_step(&p, &s, T) == 1.0f, "no channel: 1");
}

static void test_filter(void)
{
    bc_derate_params p = params();
    p.tau = 2.0f;
    p.ts = 0.05f;
    p.enabled[1] = 0;
    bc_derate_state s;
    CHECK(bc_derate_init(&p, &s) == BC_OK, "init");
    float T[2] = {25.0f, 0.0f};
    bc_derate_step(&p, &s, T); /* the first reading sets the filter */
    CHECK(s.T_f[0] == 25.0f, "primed");
    T[0] = 125.0f;
    for (int n = 1; n <= 200; ++n) {
        bc_derate_step(&p, &s, T);
        const double exact = 125.0 - 100.0 * exp(-(double)n * 0.05 / 2.0);
        if (n % 40 == 0) CHECK_NEAR(s.T_f[0], exact, 2e-3, "first-order step response");
    }
}

static void test_faults_and_fuzz(void)
{
    bc_derate_params p = params();
    p.tau = 1.0f;
    bc_derate_state s;
    bc_derate_init(&p, &s);
    float T[2] = {120.0f, 25.0f};
    const float f0 = bc_derate_step(&p, &s, T);
    const float bad[] = {NAN, INFINITY, -INFINITY, -60.0f, 400.0f};
    for (int k = 0; k < 5; ++k) {
        T[0] = bad[k];
        const float held = s.T_f[0];
        CHECK(bc_derate_step(&p, &s, T) == p.f_fault && s.fault[0] == 1 && s.T_f[0] == held, "fault %d", k);
    }
    T[0] = 120.0f;
    CHECK(bc_derate_step(&p, &s, T) == f0 && s.fault[0] == 0, "the fault clears at a plausible reading");
    uint32_t x = 12345u;
    int ok = 1;
    for (int k = 0; k < 100000; ++k) {
        float v[2];
        for (int c = 0; c < 2; ++c) {
            x = x * 1664525u + 1013904223u;
            uint32_t bits = x;
            memcpy(&v[c], &bits, sizeof bits); /* any float: NaN, inf, denormals, huge */
            if (k % 2) v[c] = (float)(x % 40000u) / 100.0f - 100.0f;
        }
        const float f = bc_derate_step(&p, &s, v);
        if (!(isfinite(f) && f >= 0.0f && f <= 1.0f)) ok = 0;
    }
    CHECK(ok, "any input: a factor in [0, 1]");
}

static void test_init_refusals(void)
{
    bc_derate_state s;
    bc_derate_params p;
    for (int k = 0; k < 9; ++k) {
        p = params();
        switch (k) {
        case 0: p.f_min = 1.0f; break;
        case 1: p.f_min = -0.1f; break;
        case 2: p.f_fault = 1.5f; break;
        case 3: p.T_end[0] = p.T_start[0]; break;
        case 4: p.T_hi = p.T_lo; break;
        case 5: p.tau = -1.0f; break;
        case 6: p.ts = 0.0f; break;
        case 7: p.T_start[1] = NAN; break;
        default: p.enabled[0] = 2; break;
        }
        CHECK(bc_derate_init(&p, &s) == BC_ERR_PARAM, "refused %d", k);
    }
    p = params();
    p.enabled[1] = 0;
    p.T_start[1] = NAN; /* a channel not fitted needs no band */
    CHECK(bc_derate_init(&p, &s) == BC_OK, "disabled channel's band ignored");
}

static void test_resistance_method(void)
{
    float T = 0.0f;
    /* copper: R rises by (234.5 + T) / (234.5 + T_ref) */
    const float R_ref = 0.050f, T_ref = 25.0f;
    for (int k = 0; k < 5; ++k) {
        const float Tk = -20.0f + 45.0f * (float)k;
        const float R = R_ref * (234.5f + Tk) / (234.5f + T_ref);
        CHECK(bc_derate_r_to_temp(R, R_ref, T_ref, 234.5f, &T) == BC_OK, "ok");
        CHECK_NEAR(T, Tk, 2e-4, "resistance method");
    }
    T = 7.0f;
    CHECK(bc_derate_r_to_temp(0.0f, R_ref, T_ref, 234.5f, &T) == BC_ERR_INPUT && T == 7.0f, "R = 0");
    CHECK(bc_derate_r_to_temp(NAN, R_ref, T_ref, 234.5f, &T) == BC_ERR_INPUT, "R NaN");
    CHECK(bc_derate_r_to_temp(0.06f, -1.0f, T_ref, 234.5f, &T) == BC_ERR_INPUT, "R_ref < 0");
    CHECK(bc_derate_r_to_temp(0.06f, R_ref, -300.0f, 234.5f, &T) == BC_ERR_INPUT, "k + T_ref <= 0");
    CHECK(bc_derate_r_to_temp(0.06f, R_ref, T_ref, 234.5f, 0) == BC_ERR_INPUT, "no output");
}

int main(void)
{
    test_band();
    test_filter();
    test_faults_and_fuzz();
    test_init_refusals();
    test_resistance_method();
    return bc_test_summary("test_derate");
}

/* test_rest.c - the winding resistance during operation (bc_rest.h): exact on a d-axis plant with offsets that do
 * not change with the injection, invalid periods discarded, any input giving a finite estimate in range or none,
 * parameter refusals, the temperature of the estimate. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_rest.h"

static bc_rest_params params(void)
{
    bc_rest_params p;
    memset(&p, 0, sizeof p);
    p.i_inj = 2.0f;
    p.n_half = 1000; /* the test plant's slowest mode (L / R, 42 samples at R = 50 mOhm) settles in n_skip */
    p.n_skip = 500;
    p.r_lo = 0.01f;
    p.r_hi = 1.0f;
    p.a = 0.25f;
    p.r_ref = 0.05f;
    p.T_ref = 25.0f;
    return p;
}

/* The d axis of a motor in discrete time: L di/dt = v_d - R i_d - c (c = -omega_e L i_q + e_d + dv_d, constant),
 * under a PI current loop on the block's reference; returns the estimate after `periods` periods. */
static float run_plant(const bc_rest_params *p, bc_rest_state *s, float R, float c, int periods)
{
    const float L = 75e-6f, ts = 1.0f / 28000.0f;
    const float kp = 2.0f * 3.14159265f * 1000.0f * L, ki = kp * R / L;
    float i_d = 0.0f, x = 0.0f;
    for (int k = 0; k < periods * 2 * p->n_half; ++k) {
        float ref = bc_rest_ref(p, s);
        float e = ref - i_d;
        x += ki * ts * e;
        float v = kp * e + x;
        bc_rest_step(p, s, v, i_d, 1);
        i_d += ts / L * (v - R * i_d - c); /* explicit Euler: its steady state is v = R i_d + c exactly */
    }
    return s->r;
}

static void test_exact_with_offsets(void)
{
    bc_rest_params p = params();
    bc_rest_state s;
    const float Rs[3] = {0.05f, 0.0745f, 0.2f}, cs[3] = {0.0f, 3.7f, -11.0f};
    for (int j = 0; j < 3; ++j) {
        CHECK(bc_rest_init(&p, &s) == BC_OK, "init");
        CHECK(bc_rest_ref(&p, &s) == p.i_inj, "first half +i_inj");
        (void)run_plant(&p, &s, Rs[j], cs[j], 6); /* the first period holds the loop's start-up transient */
        CHECK_NEAR(s.r_last, Rs[j], 1e-4f * Rs[j], "R with the offset c (which cancels)");
        CHECK(s.count == 6u && s.rejected == 0u, "six valid periods (%u, %u)", s.count, s.rejected);
    }
    /* the filter: from R1, the next periods move by a (R2 - r) each */
    CHECK(bc_rest_init(&p, &s) == BC_OK, "init");
    float r1 = run_plant(&p, &s, 0.05f, 1.0f, 3);
    float r2 = run_plant(&p, &s, 0.06f, 1.0f, 1);
    float expect = r1 + p.a * (s.r_last - r1);
    CHECK(fabsf(r2 - expect) <= 1e-6f * r2, "one filtered step: %g vs %g", (double)r2, (double)expect);
    (void)run_plant(&p, &s, 0.06f, 1.0f, 1);
    CHECK_NEAR(s.r_last, 0.06f, 1e-4f * 0.06f, "the new R once settled");
    float T = -1.0f;
    CHECK(bc_rest_temp(&p, &s, &T) == 0 && T > 25.0f, "temperature of a larger R is above T_ref");
}

static void test_invalid_periods(void)
{
    bc_rest_params p = params();
    bc_rest_state s;
    bc_rest_init(&p, &s);
    float T = 7.0f;
    CHECK(bc_rest_temp(&p, &s, &T) != 0 && T == 7.0f, "no temperature before an estimate");
    float r = run_plant(&p, &s, 0.08f, 2.0f, 2);
    CHECK_NEAR(s.r_last, 0.08f, 1e-5, "estimate");
    /* one sample not ok, one NaN: those periods are discarded, the estimate kept */
    for (int k = 0; k < 2 * p.n_half; ++k) bc_rest_step(&p, &s, 1.0f, bc_rest_ref(&p, &s), k == 700 ? 0 : 1);
    for (int k = 0; k < 2 * p.n_half; ++k) bc_rest_step(&p, &s, k == 1300 ? NAN : 1.0f, bc_rest_ref(&p, &s), 1);
    CHECK(s.r == r && s.rejected == 2u, "discarded: r %g, rejected %u", (double)s.r, s.rejected);
    /* the current did not follow (no change of i_d): discarded */
    for (int k = 0; k < 2 * p.n_half; ++k) bc_rest_step(&p, &s, 1.0f, 0.0f, 1);
    CHECK(s.r == r && s.rejected == 3u, "no current step: discarded");
    /* an implausible ratio (R_hat = 5 Ohm > r_hi): discarded */
    for (int k = 0; k < 2 * p.n_half; ++k) {
        float i = bc_rest_ref(&p, &s);
        bc_rest_step(&p, &s, 5.0f * i, i, 1);
    }
    CHECK(s.r == r && s.rejected == 4u, "implausible: discarded");
    /* restart mid-period: a fresh period from +i_inj */
    for (int k = 0; k < p.n_half + 3; ++k) bc_rest_step(&p, &s, 0.0f, 0.0f, 1);
    CHECK(bc_rest_ref(&p, &s) == -p.i_inj, "second half");
    bc_rest_restart(&s);
    CHECK(bc_rest_ref(&p, &s) == p.i_inj && s.k == 0, "restarted");
}

static uint32_t lcg(uint32_t *x)
{
    *x = *x * 1664525u + 1013904223u;
    return *x;
}

static void test_fuzz(void)
{
    bc_rest_params p = params();
    p.n_half = 3;
    p.n_skip = 1;
    bc_rest_state s;
    bc_rest_init(&p, &s);
    uint32_t x = 12345u;
    int bad = 0;
    const float special[5] = {NAN, INFINITY, -INFINITY, 1e30f, -0.0f};
    for (int k = 0; k < 100000; ++k) {
        uint32_t u = lcg(&x);
        float v, i;
        if (u % 7u == 0u) {
            v = special[(u >> 8) % 5u];
        } else {
            v = ((float)(lcg(&x) >> 8) / 16777216.0f - 0.5f) * 10.0f;
        }
        if (u % 11u == 0u) {
            i = special[(u >> 12) % 5u];
        } else {
            i = bc_rest_ref(&p, &s) * (1.0f + ((float)(lcg(&x) >> 8) / 16777216.0f - 0.5f) * 0.5f);
        }
        bc_rest_step(&p, &s, v, i, (int32_t)(u % 13u != 0u));
        float ref = bc_rest_ref(&p, &s);
        if (!(isfinite(s.r) && (s.r == 0.0f || (s.r >= p.r_lo && s.r <= p.r_hi)))) ++bad;
        if (!(ref == p.i_inj || ref == -p.i_inj)) ++bad;
    }
    CHECK(bad == 0, "finite estimate in [r_lo, r_hi] (or none) and a reference +-i_inj: %d bad", bad);
    CHECK(s.count > 0u && s.rejected > 0u, "some periods valid (%u), some not (%u)", s.count, s.rejected);
}

static void test_init_refusals(void)
{
    bc_rest_state s;
    for (int k = 0; k < 10; ++k) {
        bc_rest_params p = params();
        switch (k) {
        case 0: p.i_inj = 0.0f; break;
        case 1: p.i_inj = NAN; break;
        case 2: p.n_half = 1; break;
        case 3: p.n_skip = p.n_half - 1; break;
        case 4: p.n_skip = -1; break;
        case 5: p.r_lo = 0.0f; break;
        case 6: p.r_hi = p.r_lo; break;
        case 7: p.a = 1.5f; break;
        case 8: p.r_ref = INFINITY; break;
        default: p.T_ref = -300.0f; break;
        }
        CHECK(bc_rest_init(&p, &s) == BC_ERR_PARAM, "refused %d", k);
    }
    bc_rest_params p = params();
    CHECK(bc_rest_init(0, &s) == BC_ERR_PARAM && bc_rest_init(&p, 0) == BC_ERR_PARAM, "null");
}

int main(void)
{
    test_exact_with_offsets();
    test_invalid_periods();
    test_fuzz();
    test_init_refusals();
    return bc_test_summary("test_rest");
}

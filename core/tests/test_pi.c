/* test_pi.c - PI law, output-then-update, anti-windup on the realised output, robustness. */
#include <math.h>

#include "bc_test.h"
#include "bldc/bc_pi.h"
#include "bldc/bc_types.h"

int main(void)
{
    bc_pi_params p = {2.0f, 100.0f, 1e-3f, -10.0f, 10.0f};
    bc_pi_state s;
    CHECK(bc_pi_init(&p, &s) == BC_OK, "init");
    /* unsaturated: u_k = kp e + ki Ts sum_{j<k} e_j */
    float sum = 0.0f;
    for (int k = 0; k < 20; ++k) {
        float e = 0.5f + 0.01f * (float)k;
        float u = bc_pi_step(&p, &s, e, 0.0f);
        CHECK(fabsf(u - (p.kp * e + p.ki * p.ts * sum)) < 1e-5f, "PI law at %d", k);
        sum += e;
    }
    /* saturated for a long time: no windup, the output leaves the limit as soon as the error changes sign */
    CHECK(bc_pi_init(&p, &s) == BC_OK, "init");
    for (int k = 0; k < 10000; ++k) (void)bc_pi_step(&p, &s, 100.0f, 0.0f);
    CHECK(s.x <= p.u_max, "integrator bounded: %g", (double)s.x);
    float u = bc_pi_step(&p, &s, -1.0f, 0.0f);
    CHECK(u < p.u_max, "leaves saturation immediately: %g", (double)u);
    /* external limit: update with the realised output pulls the integrator back */
    CHECK(bc_pi_init(&p, &s) == BC_OK, "init");
    for (int k = 0; k < 1000; ++k) {
        float uu = bc_pi_output(&p, &s, 3.0f, 0.0f);
        float ur = uu > 4.0f ? 4.0f : uu; /* caller's own limit */
        bc_pi_update(&p, &s, 3.0f, uu, ur);
    }
    /* back-calculation with gain 1/kp: the integrator settles on the realised output, so when the error changes
     * sign the output is kp e + 4 at once (no windup to unwind) */
    CHECK(fabsf(s.x - 4.0f) < 1e-4f, "integrator tracks the realised output: %g", (double)s.x);
    CHECK(fabsf(bc_pi_output(&p, &s, -1.0f, 0.0f) - (4.0f - p.kp)) < 1e-4f, "immediate recovery");
    /* bad inputs */
    u = bc_pi_step(&p, &s, NAN, INFINITY);
    CHECK(isfinite(u) && u >= p.u_min && u <= p.u_max, "NaN error -> finite output");
    bc_pi_params bad = {1.0f, 1.0f, 0.0f, -1.0f, 1.0f};
    CHECK(bc_pi_init(&bad, &s) == BC_ERR_PARAM, "Ts = 0 rejected");
    bad.ts = 1e-3f;
    bad.u_min = 2.0f;
    CHECK(bc_pi_init(&bad, &s) == BC_ERR_PARAM, "u_min >= u_max rejected");
    /* pure integrator (kp = 0) stays clamped */
    bc_pi_params pi0 = {0.0f, 10.0f, 1e-3f, -1.0f, 1.0f};
    CHECK(bc_pi_init(&pi0, &s) == BC_OK, "init kp = 0");
    for (int k = 0; k < 1000; ++k) (void)bc_pi_step(&pi0, &s, 100.0f, 0.0f);
    CHECK(s.x == 1.0f, "clamped integrator");
    return bc_test_summary("test_pi");
}

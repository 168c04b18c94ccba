/* test_guard.c - the shared input guard (bc_guard.h): reconstruction, bus limits, NaN inputs, hardware and software
 * trips, re-arm; and the shared numerical tools (bc_math.h: clamp, bracketed root) and the average inverter piece
 * (bc_inverter.h) against closed forms. */
#include <math.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_guard.h"
#include "bldc/bc_inverter.h"
#include "bldc/bc_math.h"

static bc_ctrl_in input(uint32_t mask, float ia, float ib, float ic, float v)
{
    bc_ctrl_in in;
    memset(&in, 0, sizeof in);
    in.i_mask = mask;
    in.i_abc[0] = ia;
    in.i_abc[1] = ib;
    in.i_abc[2] = ic;
    in.v_dc = v;
    return in;
}

static void test_guard(void)
{
    const bc_guard_params p = {100.0f, 96.0f};
    bc_guard_state s;
    float i[3];
    CHECK(bc_guard_init(&p, &s) == BC_OK && s.latched == 0, "init");
    const bc_guard_params bad_p[] = {{0.0f, 96.0f}, {NAN, 96.0f}, {100.0f, -1.0f}, {100.0f, INFINITY}};
    for (int k = 0; k < 4; ++k) CHECK(bc_guard_init(&bad_p[k], &s) == BC_ERR_PARAM, "params %d rejected", k);
    CHECK(bc_guard_init(&p, &s) == BC_OK, "init again");

    /* reconstruction: each pair of measured phases gives the third; three measured are taken as they are */
    bc_ctrl_in in = input(3u, 10.0f, -4.0f, 1e9f, 48.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u && i[0] == 10.0f && i[1] == -4.0f && i[2] == -6.0f, "a, b -> c");
    in = input(5u, 10.0f, NAN, -4.0f, 48.0f); /* an unmeasured phase may hold anything */
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u && i[1] == -6.0f, "a, c -> b");
    in = input(6u, NAN, 10.0f, -4.0f, 48.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u && i[0] == -6.0f, "b, c -> a");
    in = input(7u, 10.0f, -4.0f, -5.0f, 48.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u && i[2] == -5.0f, "three measured: no projection");

    /* bad measurements: NaN or inf on a measured phase, fewer than two phases, the bus outside (0, v_max] */
    const bc_ctrl_in bad[] = {input(3u, NAN, 0.0f, 0.0f, 48.0f),   input(3u, 0.0f, -INFINITY, 0.0f, 48.0f),
                              input(1u, 1.0f, 0.0f, 0.0f, 48.0f),  input(0u, 0.0f, 0.0f, 0.0f, 48.0f),
                              input(3u, 1.0f, 1.0f, 0.0f, 0.0f),   input(3u, 1.0f, 1.0f, 0.0f, -48.0f),
                              input(3u, 1.0f, 1.0f, 0.0f, NAN),    input(3u, 1.0f, 1.0f, 0.0f, INFINITY),
                              input(3u, 1.0f, 1.0f, 0.0f, 96.01f), input(3u, 3e38f, 3e38f, 0.0f, 48.0f)};
    for (int k = 0; k < 10; ++k) {
        i[0] = i[1] = i[2] = 7.0f;
        CHECK(bc_guard_step(&p, &s, &bad[k], i) == BC_FLAG_BAD_INPUT, "bad input %d", k);
        CHECK(i[0] == 0.0f && i[1] == 0.0f && i[2] == 0.0f, "bad input %d: currents zeroed", k);
        CHECK(s.latched == 0, "bad input %d does not trip", k);
    }
    in = input(3u, 1.0f, 1.0f, 0.0f, 96.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u, "v_dc = v_max accepted");

    /* hardware trip: reported, not latched by the guard */
    in = input(3u, 1.0f, -1.0f, 0.0f, 48.0f);
    in.fault_pin = 1u;
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_OVERCURRENT && s.latched == 0, "fault pin");
    in.fault_pin = 0u;
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u, "fault pin released");

    /* software trip on a reconstructed phase, latched until every |i| < i_max / 2 at a valid sample */
    in = input(3u, 60.0f, 50.0f, 0.0f, 48.0f); /* i_c = -110 A */
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_OVERCURRENT && s.latched == 1, "trip on i_c = %g", (double)i[2]);
    in = input(3u, 100.0f, -100.0f, 0.0f, 48.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_OVERCURRENT, "latched at i_max");
    in = input(3u, 50.0f, -50.0f, 0.0f, 48.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_OVERCURRENT, "latched at exactly i_max / 2");
    in = input(3u, 1.0f, -1.0f, 0.0f, NAN);
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_BAD_INPUT && s.latched == 1, "a bad sample keeps the latch");
    in = input(3u, 49.0f, -49.0f, 0.0f, 48.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u && s.latched == 0, "re-armed below i_max / 2");
    in = input(3u, 100.0f, -100.0f, 0.0f, 48.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u, "i_max itself does not trip");
    in = input(3u, 100.5f, -100.0f, 0.0f, 48.0f);
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_OVERCURRENT, "trips again");
    CHECK(bc_guard_init(&p, &s) == BC_OK && s.latched == 0, "init clears the latch");

    /* a measured reading at the sensors' full scale (i_fs > 0) trips, far below i_max: the current beyond it is
     * unknown; the latch re-arms only when every reading is inside it (and below i_max / 2) */
    in = input(3u, 20.0f, -5.0f, 0.0f, 48.0f);
    in.i_fs = 20.0f;
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_OVERCURRENT && s.latched == 1, "trip at +i_fs");
    in.i_abc[0] = 19.0f;
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u && s.latched == 0, "re-armed inside the full scale");
    in = input(3u, 5.0f, -20.0f, 1e9f, 48.0f);
    in.i_fs = 20.0f;
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_OVERCURRENT, "trip at -i_fs on phase b");
    CHECK(bc_guard_step(&p, &s, &in, i) == BC_FLAG_OVERCURRENT, "no re-arm while a reading is at the full scale");
    CHECK(bc_guard_init(&p, &s) == BC_OK, "init");
    in = input(3u, 15.0f, -15.0f, 0.0f, 48.0f); /* i_c reconstructed, 0: not a reading */
    in.i_fs = 15.5f;
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u, "inside the full scale: no trip");
    in = input(3u, 19.0f, 1.0f, 25.0f, 48.0f); /* phase c unmeasured: its entry is not a reading */
    in.i_fs = 20.0f;
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u && i[2] == -20.0f, "a reconstructed phase at i_fs does not trip");
    in.i_fs = 0.0f;
    in.i_abc[0] = 99.0f;
    CHECK(bc_guard_step(&p, &s, &in, i) == 0u, "i_fs = 0: no full scale");
}

typedef struct {
    float a, b, c; /* g(d) = a d^3 + b d + c, increasing */
    int n;
} cubic;

static float cubic_g(float d, void *ctx)
{
    cubic *q = (cubic *)ctx;
    q->n += 1;
    return q->a * d * d * d + q->b * d + q->c;
}

static void test_math(void)
{
    CHECK(bc_clampf(2.0f, 0.0f, 1.0f) == 1.0f && bc_clampf(-2.0f, 0.0f, 1.0f) == 0.0f, "clamp outside");
    CHECK(bc_clampf(0.25f, 0.0f, 1.0f) == 0.25f, "clamp inside");
    CHECK(isnan(bc_clampf(NAN, 0.0f, 1.0f)), "clamp passes NaN on (documented)");
    /* root of d^3 + d - 1 on [0, 1]: 0.682327803828019 (Cardano) */
    double exact = cbrt(0.5 + sqrt(0.25 + 1.0 / 27.0)) + cbrt(0.5 - sqrt(0.25 + 1.0 / 27.0));
    for (int rule = 0; rule < 2; ++rule) {
        cubic q = {1.0f, 1.0f, -1.0f, 0};
        float d = bc_root_bracket(cubic_g, &q, 0.0f, 1.0f, -1.0f, 1.0f, 0.5f, 1e-6f, 1e-7f, 40, rule);
        CHECK_NEAR(d, exact, 2e-6, rule ? "halving rule: root" : "Illinois: root");
        CHECK(q.n < (rule == BC_ROOT_ILLINOIS ? 12 : 25), "rule %d: %d evaluations", rule, q.n);
    }
    /* a NaN g stops it inside the bracket */
    cubic q = {NAN, 1.0f, -1.0f, 0};
    float d = bc_root_bracket(cubic_g, &q, 0.0f, 1.0f, -1.0f, 1.0f, 0.5f, 1e-6f, 1e-7f, 40, BC_ROOT_ILLINOIS);
    CHECK(d == 0.5f && q.n == 1, "NaN: stops at the estimate");
}

static void test_inverter(void)
{
    /* a and b connected through V, c open: L di_a/dt = (V - e_a - e_b... ) / 2 on the line; closed form */
    const float u[3] = {48.0f, 0.0f, 0.0f}, e[3] = {10.0f, -10.0f, 0.0f}, ri[3] = {1.0f, -1.0f, 0.0f};
    const int conn[3] = {1, 1, 0}, none[3] = {0, 0, 0};
    float sl[3];
    CHECK(bc_inv_slopes(u, e, ri, conn, 1e-3f, sl) == 2, "two connected");
    /* di_a/dt = ((48 - 10 - 1) - (0 + 10 + 1)) / (2 L) = 13000 A/s */
    CHECK_NEAR(sl[0], 13000.0, 0.01, "line slope");
    CHECK(sl[0] == -sl[1] && sl[2] == 0.0f, "the pair's slopes are opposite, the open phase has none");
    const int one[3] = {1, 0, 0};
    CHECK(bc_inv_slopes(u, e, ri, one, 1e-3f, sl) == BC_INV_NO_PATH && sl[0] == 0.0f, "one phase: no path");
    CHECK(bc_inv_slopes(u, e, ri, none, 1e-3f, sl) == BC_INV_NO_PATH, "none: no path");
    /* a diode current of 1.3 A falling at 13000 A/s reaches zero at 100 us; the residue goes to a connected phase */
    float i[3] = {-1.3f, 1.3f, 0.0f}, h;
    const int diode[3] = {1, 0, 0};
    float slope[3] = {13000.0f, -13000.0f, 0.0f};
    int z = bc_inv_first_zero(diode, i, slope, 200e-6f, &h);
    CHECK(z == 0 && fabs((double)h - 100e-6) < 1e-9, "first zero at %g s", (double)h);
    bc_inv_advance(conn, slope, h, z, i);
    CHECK(i[0] == 0.0f && i[0] + i[1] + i[2] == 0.0f && i[2] == 0.0f, "opened exactly, sum zero, open phase untouched");
    z = bc_inv_first_zero(none, i, slope, 200e-6f, &h);
    CHECK(z == -1 && h == 200e-6f, "no diode phase: the whole piece");
}

int main(void)
{
    test_guard();
    test_math();
    test_inverter();
    return bc_test_summary("test_guard");
}

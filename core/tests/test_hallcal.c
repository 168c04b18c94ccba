/* test_hallcal.c - six-edge calibration: constant speed from synthetic edges (accuracy, revolutions), every bad
 * input ends in a flagged failure without a table, and the open-loop routine's outputs and bad inputs. */
#include <math.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_commutation.h"
#include "bldc/bc_hallcal.h"
#include "synth_hall.h"

#define TS 35.714286e-6
#define FT 10e6

static const double ERR[3] = {0.08, -0.05, 0.03}; /* sensors a, b, c; edge j belongs to sensor 2 - j % 3 */

static bc_hallcal_params speed_params(int n_rev)
{
    bc_hallcal_params p;
    memset(&p, 0, sizeof p);
    p.method = BC_HALLCAL_SPEED;
    p.n_rev = n_rev;
    p.f_tick = (float)FT;
    p.ts = (float)TS;
    p.t_max = 1.0f;
    p.speed_tol = 0.02f;
    return p;
}

static double wrap_pm(double x)
{
    x = fmod(x + BC_PI, 2.0 * BC_PI);
    if (x < 0.0) x += 2.0 * BC_PI;
    return x - BC_PI;
}

/* Run the SPEED method on synthetic edges; return the status and the table. */
static uint32_t run_speed(const bc_hallcal_params *p, const double truth[6], double w0, double a, double t_end,
                          bc_hall_table *t)
{
    synth_hall g;
    synth_init(&g, truth, w0, a, TS, FT);
    bc_hallcal_state s;
    CHECK(bc_hallcal_init(p, &s) == BC_OK, "init");
    long n = (long)(t_end / TS);
    for (long k = 0; k < n; ++k) {
        bc_ctrl_in in;
        synth_sample(&g, k, &in);
        bc_ctrl_out out;
        bc_hallcal_step(p, &s, &in, &out);
        for (int x = 0; x < 3; ++x) CHECK(out.leg[x].mode == BC_LEG_OFF, "SPEED: legs off");
        if (!(s.status & BC_HALLCAL_BUSY)) break;
    }
    return bc_hallcal_result(&s, t);
}

static void test_speed(void)
{
    double truth[6], mean = 0.0;
    for (int j = 0; j < 6; ++j) {
        truth[j] = BC_PI / 6.0 + (double)j * BC_PI / 3.0 + ERR[2 - j % 3];
        mean += ERR[2 - j % 3] / 6.0;
    }
    for (int n_rev = 1; n_rev <= 4; n_rev *= 2) {
        bc_hallcal_params p = speed_params(n_rev);
        bc_hall_table t;
        memset(&t, 0, sizeof t);
        uint32_t st = run_speed(&p, truth, 300.0, 0.0, 0.5, &t);
        CHECK(st == BC_HALLCAL_DONE, "n_rev %d: status 0x%x", n_rev, (unsigned)st);
        double worst = 0.0;
        for (int j = 0; j < 6; ++j) {
            /* the zero-mean assumption: table = truth - mean(errors) */
            double e = wrap_pm((double)t.fwd[j] - (truth[j] - mean));
            if (fabs(e) > worst) worst = fabs(e);
            CHECK(t.fwd[j] == t.bwd[j], "both directions");
        }
        printf("test_hallcal: constant speed, %d rev: worst edge error (mean removed) %.2e rad\n", n_rev, worst);
        CHECK(worst < 1e-4, "n_rev %d: worst %.3g rad", n_rev, worst);
        CHECK(t.set == 1, "table set");
    }
}

static void expect_fail(const char *what, uint32_t st, uint32_t reason, const bc_hall_table *t)
{
    CHECK((st & BC_HALLCAL_FAIL) && (st & reason) && !(st & BC_HALLCAL_DONE), "%s: status 0x%x", what, (unsigned)st);
    CHECK(t->set == 0 && t->fwd[0] == 0.0f && t->bwd[5] == 0.0f, "%s: table untouched", what);
}

static void test_speed_bad(void)
{
    double nominal[6];
    for (int j = 0; j < 6; ++j) nominal[j] = BC_PI / 6.0 + (double)j * BC_PI / 3.0;
    bc_hallcal_params p = speed_params(4);
    bc_hall_table t;
    memset(&t, 0, sizeof t);
    /* speed rising by 10 % per revolution: beyond the 2 % tolerance */
    expect_fail("acceleration", run_speed(&p, nominal, 300.0, 3000.0, 0.5, &t), BC_HALLCAL_E_SPEED, &t);
    /* too slow for n_rev within t_max */
    p.t_max = 0.05f;
    expect_fail("timeout", run_speed(&p, nominal, 300.0, 0.0, 0.5, &t), BC_HALLCAL_E_FEW, &t);
    p.t_max = 1.0f;

    /* hand-made sequences: reversal, invalid code, skipped sector */
    const uint32_t rev[] = {1u, 3u, 2u, 6u, 2u};
    const uint32_t inv[] = {1u, 3u, 7u, 6u};
    const uint32_t skip[] = {1u, 3u, 6u, 4u};
    const uint32_t *seq[3] = {rev, inv, skip};
    const int len[3] = {5, 4, 4};
    const uint32_t why[3] = {BC_HALLCAL_E_REVERSAL, BC_HALLCAL_E_INVALID, BC_HALLCAL_E_ORDER};
    const char *name[3] = {"reversal", "stuck sensor (code 7)", "skipped sector"};
    for (int c = 0; c < 3; ++c) {
        bc_hallcal_state s;
        CHECK(bc_hallcal_init(&p, &s) == BC_OK, "init");
        bc_ctrl_in in;
        memset(&in, 0, sizeof in);
        bc_ctrl_out out;
        for (int k = 0; k < len[c]; ++k) {
            in.hall = seq[c][k];
            in.n_edges = (uint32_t)k;
            in.tick_edge = (uint32_t)k * 10000u;
            in.tick_now = in.tick_edge + 10u;
            bc_hallcal_step(&p, &s, &in, &out);
        }
        memset(&t, 0, sizeof t);
        expect_fail(name[c], bc_hallcal_result(&s, &t), why[c], &t);
        CHECK((int)out.diag[6] == (int)s.status, "%s: status in diag[6]", name[c]);
    }
    /* parameters */
    bc_hallcal_state s;
    bc_hallcal_params b = p;
    b.n_rev = 0;
    CHECK(bc_hallcal_init(&b, &s) == BC_ERR_PARAM, "n_rev 0 rejected");
    b = p;
    b.speed_tol = 1.0f;
    CHECK(bc_hallcal_init(&b, &s) == BC_ERR_PARAM, "speed_tol 1 rejected");
    b = p;
    b.method = BC_HALLCAL_OPENLOOP;
    CHECK(bc_hallcal_init(&b, &s) == BC_ERR_PARAM, "open loop without its settings rejected");
}

/* The open-loop routine: legs PWM in [0, 1] while it turns, the commanded angle ramps up at omega_ol^2 / pi; a NaN current
 * or an invalid code fails it with the legs off and BC_FLAG_SAFE. */
static void test_openloop(void)
{
    bc_hallcal_params p;
    memset(&p, 0, sizeof p);
    p.method = BC_HALLCAL_OPENLOOP;
    p.n_rev = 2;
    p.f_tick = (float)FT;
    p.ts = (float)TS;
    p.v_align = 2.5f;
    p.omega_ol = 12.566f;
    p.t_align = 0.01f;
    p.lag_max = 1.5f;
    p.i_max = 100.0f;
    p.v_max = 96.0f;
    for (int c = 0; c < 3; ++c) {
        bc_hallcal_state s;
        CHECK(bc_hallcal_init(&p, &s) == BC_OK, "init");
        bc_ctrl_in in;
        memset(&in, 0, sizeof in);
        in.v_dc = 48.0f;
        in.i_mask = 7u;
        in.hall = 1u;
        bc_ctrl_out out;
        long n = (long)(0.1 / TS);
        int n_pwm = 0;
        for (long k = 0; k < n; ++k) {
            if (c == 1 && k == n / 2) in.i_abc[1] = NAN;
            if (c == 2 && k == n / 2) in.hall = 0u;
            bc_hallcal_step(&p, &s, &in, &out);
            for (int x = 0; x < 3; ++x) {
                CHECK(out.leg[x].duty >= 0.0f && out.leg[x].duty <= 1.0f, "duty in [0, 1]");
                n_pwm += out.leg[x].mode == BC_LEG_PWM;
            }
        }
        CHECK(n_pwm > 0, "the vector is applied");
        if (c == 0) {
            double tt = 0.1 - 0.01, acc = 12.566 * 12.566 / BC_PI; /* still ramping: omega_ol after pi / omega_ol */
            double turned = 0.5 * acc * tt * tt;
            CHECK(s.status == BC_HALLCAL_BUSY && s.phase == 1, "still sweeping forward");
            CHECK(fabs((double)s.travel - turned) < 1e-2, "travel %.4g vs %.4g rad", (double)s.travel, turned);
        } else {
            CHECK((s.status & BC_HALLCAL_FAIL) && (s.status & (c == 1 ? BC_HALLCAL_E_INPUT : BC_HALLCAL_E_INVALID)),
                  "case %d failed: 0x%x", c, (unsigned)s.status);
            CHECK((out.flags & BC_FLAG_SAFE) && out.leg[0].mode == BC_LEG_OFF && out.leg[2].mode == BC_LEG_OFF,
                  "case %d: legs off, safe", c);
        }
    }
}

int main(void)
{
    test_speed();
    test_speed_bad();
    test_openloop();
    return bc_test_summary("test_hallcal");
}

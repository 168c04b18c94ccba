/* test_hall.c - Hall decoding, speed and angle from the real plant and sensor chain at constant speed, both
 * directions, capture-timer wrap-around, invalid codes, standstill. */
#include <math.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_commutation.h"
#include "bldc/bc_hall.h"
#include "bldc/bc_plant.h"
#include "bldc/bc_sensors.h"
#include "fixtures.h"
#include "synth_hall.h"

static double angle_diff(double a, double b)
{
    double d = fmod(a - b, 2.0 * BC_PI);
    if (d > BC_PI) d -= 2.0 * BC_PI;
    if (d < -BC_PI) d += 2.0 * BC_PI;
    return d;
}

/* Spin at omega (mechanical) for n samples starting at time t0; return the worst angle error once the speed is
 * valid, and the speed error. */
static void spin(double omega, double t0, long n, double *err_th, double *err_om, int *edges, int *valid_from)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_plant_state ps;
    double i0[3] = {0.0, 0.0, 0.0};
    CHECK(bc_plant_init(&f.p, &ps, t0, 0.3, omega, i0, 48.0) == BC_OK, "plant");
    bc_sensor_state ss;
    CHECK(bc_sensor_init(&f.sp, &ss) == BC_OK, "sensors");
    bc_hall_params hp = {(float)f.sp.f_tick, 5.0f, 0.0f, BC_HALL_INTERP, 1.0f, {0, {0}, {0}}};
    bc_hall_state hs;
    CHECK(bc_hall_init(&hp, &hs) == BC_OK, "hall");
    bc_leg_cmd off[3] = {{0, 0.0f}, {0, 0.0f}, {0, 0.0f}};
    double th = bc_plant_t_half(&f.p);
    *err_th = 0.0;
    *err_om = 0.0;
    *edges = 0;
    *valid_from = -1;
    for (long k = 0; k < n; ++k) {
        bc_ctrl_in in;
        memset(&in, 0, sizeof in);
        bc_sensor_measure(&f.sp, &ss, &ps, 48.0, &in);
        bc_hall_out ho;
        bc_hall_step(&hp, &hs, &in, &ho);
        CHECK(ho.valid == 1 && ho.sector >= 0, "valid code");
        CHECK(ho.theta >= 0.0f && ho.theta < BC_TWO_PI_F, "angle in range");
        *edges += ho.edge;
        if (ho.speed_valid) {
            if (*valid_from < 0) *valid_from = *edges;
            double e = fabs(angle_diff((double)ho.theta, ps.theta));
            if (e > *err_th) *err_th = e;
            double eo = fabs((double)ho.omega_e - 8.0 * omega) / fabs(8.0 * omega);
            if (eo > *err_om) *err_om = eo;
            CHECK(ho.dir == (omega > 0.0 ? 1 : -1), "direction");
        }
        bc_plant_set_half(&f.p, &ps, off, 1);
        bc_plant_advance(&f.p, &ps, t0 + (double)(k + 1) * th);
    }
}

/* The interpolated angle never steps back while the rotor turns one way: from an edge until long after the next
 * edge is overdue (the speed estimate then decays as (pi/3)/(time since the edge)), sampled at every capture tick
 * in both directions, it rises (falls, backward) to the next edge angle and stays exactly there; the speed
 * estimate never rises. */
static void test_monotone_angle(void)
{
    const uint32_t D = 100003u; /* edge interval, ticks: 10 ms at 10 MHz */
    bc_hall_params hp = {10e6f, 5.0f, 0.0f, BC_HALL_INTERP, 1.0f, {0, {0}, {0}}};
    for (int dir = -1; dir <= 1; dir += 2) {
        bc_hall_state hs;
        CHECK(bc_hall_init(&hp, &hs) == BC_OK, "init");
        bc_ctrl_in in;
        memset(&in, 0, sizeof in);
        bc_hall_out ho;
        int s0 = 2; /* sectors s0, s0 + dir, s0 + 2 dir: edges at D, 2 D */
        in.hall = bc_sector_code(s0);
        bc_hall_step(&hp, &hs, &in, &ho);
        for (uint32_t k = 1u; k <= 2u; ++k) {
            in.hall = bc_sector_code((s0 + dir * (int)k + 6) % 6);
            in.n_edges = k;
            in.tick_edge = in.tick_now = k * D;
            bc_hall_step(&hp, &hs, &in, &ho);
        }
        CHECK(ho.speed_valid == 1 && ho.dir == dir, "speed from two edges");
        int s2 = (s0 + 2 * dir + 6) % 6;
        double next = dir > 0 ? (double)bc_sector_angle((s2 + 1) % 6) : (double)bc_sector_angle(s2);
        double prev_th = ho.theta, prev_w = fabs((double)ho.omega_e);
        long n_back = 0, n_rise = 0, n_off = 0, n_overdue = 0;
        for (uint32_t t = 2u * D + 1u; t < 2u * D + 3u * D; ++t) {
            in.tick_now = t;
            bc_hall_step(&hp, &hs, &in, &ho);
            if (!ho.speed_valid) break;
            double step = angle_diff((double)ho.theta, prev_th) * (double)dir;
            n_back += step < 0.0;
            n_rise += fabs((double)ho.omega_e) > prev_w;
            if (t - 2u * D >= D) {
                ++n_overdue;
                n_off += fabs(angle_diff((double)ho.theta, next)) > 0.0;
            }
            prev_th = ho.theta;
            prev_w = fabs((double)ho.omega_e);
        }
        CHECK(n_overdue > 100000, "dir %d: %ld overdue ticks checked", dir, n_overdue);
        CHECK(n_back == 0, "dir %d: the angle stepped back at %ld ticks", dir, n_back);
        CHECK(n_rise == 0, "dir %d: the speed estimate rose at %ld ticks", dir, n_rise);
        CHECK(n_off == 0, "dir %d: overdue angle off the next edge at %ld ticks", dir, n_off);
    }
}

/* Run bc_hall on synthetic edges (true angles `truth`) with params hp; return the rms and max angle error over the
 * samples after `skip` s, and whether the speed was valid there. */
static void synth_err(const bc_hall_params *hp, const double truth[6], double w0, double a, double t_end, double skip,
                      double *rms, double *mx)
{
    synth_hall g;
    synth_init(&g, truth, w0, a, 35.714286e-6, 10e6);
    bc_hall_state hs;
    CHECK(bc_hall_init(hp, &hs) == BC_OK, "init");
    double s2 = 0.0;
    long n = 0;
    *mx = 0.0;
    long n_end = (long)(t_end / g.ts);
    for (long k = 0; k < n_end; ++k) {
        bc_ctrl_in in;
        synth_sample(&g, k, &in);
        bc_hall_out ho;
        bc_hall_step(hp, &hs, &in, &ho);
        if ((double)k * g.ts < skip) continue;
        CHECK(ho.valid && ho.speed_valid && isfinite(ho.theta) && isfinite(ho.omega_e), "valid at %ld", k);
        double e = angle_diff((double)ho.theta, synth_theta(&g, (double)k * g.ts));
        s2 += e * e;
        ++n;
        if (fabs(e) > *mx) *mx = fabs(e);
    }
    *rms = sqrt(s2 / (double)(n > 0 ? n : 1));
}

/* The edge table: with the true edges the interpolation is exact at constant speed; the nominal table filled in
 * explicitly matches set = 0 to float rounding; out-of-range tables and PLL settings are rejected. The PLL averages
 * the misplacement at constant speed and follows a constant acceleration without a steady error. */
static void test_table_and_pll(void)
{
    const double err[3] = {0.08, -0.05, 0.03}; /* sensor a, b, c: edge j belongs to sensor 2 - j % 3 */
    double truth[6], nominal[6];
    for (int j = 0; j < 6; ++j) {
        nominal[j] = BC_PI / 6.0 + (double)j * BC_PI / 3.0;
        truth[j] = nominal[j] + err[2 - j % 3];
    }
    bc_hall_params hp = {10e6f, 5.0f, 0.0f, BC_HALL_INTERP, 3.0f, {0, {0}, {0}}};
    double rms0, mx0, rms1, mx1;
    synth_err(&hp, nominal, 300.0, 0.0, 0.2, 0.05, &rms0, &mx0);
    CHECK(mx0 < 2e-3, "nominal edges, nominal table: max error %.3g rad", mx0);
    synth_err(&hp, truth, 300.0, 0.0, 0.2, 0.05, &rms0, &mx0);
    CHECK(mx0 > 0.05, "misplaced edges, nominal table: max error %.3g rad (the misplacement shows)", mx0);
    bc_hall_params ht = hp;
    ht.table.set = 1;
    for (int j = 0; j < 6; ++j) ht.table.fwd[j] = ht.table.bwd[j] = (float)truth[j];
    synth_err(&ht, truth, 300.0, 0.0, 0.2, 0.05, &rms1, &mx1);
    CHECK(mx1 < 2e-3, "misplaced edges, true table: max error %.3g rad", mx1);
    bc_hall_params hn = hp;
    bc_hall_table_nominal(&hn.table);
    CHECK(hn.table.set == 1 && fabsf(hn.table.fwd[3] - (float)nominal[3]) < 1e-6f, "nominal table filled");
    double rmsn, mxn;
    synth_err(&hn, nominal, 300.0, 0.0, 0.2, 0.05, &rmsn, &mxn);
    synth_err(&hp, nominal, 300.0, 0.0, 0.2, 0.05, &rms0, &mx0);
    CHECK(fabs(rmsn - rms0) < 1e-5 && fabs(mxn - mx0) < 1e-5, "explicit nominal table = unset: %.3g vs %.3g", mxn, mx0);
    /* entry lead: dir (edge - nominal) */
    CHECK(fabsf(bc_hall_entry_lead(&ht, 1, 1) - (float)err[1]) < 1e-6f, "lead of edge 1 forward");
    CHECK(fabsf(bc_hall_entry_lead(&ht, 1, -1) - (float)(-err[0])) < 1e-6f, "lead of edge 2 backward");
    CHECK(bc_hall_entry_lead(&hp, 1, 1) == 0.0f, "no lead without a table");
    /* rejected settings */
    bc_hall_state hs;
    bc_hall_params bad = ht;
    bad.table.fwd[2] = (float)(nominal[2] + 0.53);
    CHECK(bc_hall_init(&bad, &hs) == BC_ERR_PARAM, "an edge 30.4 deg off is rejected");
    bad = ht;
    bad.table.bwd[4] = NAN;
    CHECK(bc_hall_init(&bad, &hs) == BC_ERR_PARAM, "NaN edge rejected");
    bad = hp;
    bad.mode = BC_HALL_PLL;
    bad.pll_edges = 0.5f;
    CHECK(bc_hall_init(&bad, &hs) == BC_ERR_PARAM, "pll_edges < 1 rejected");
    bad.mode = 7;
    CHECK(bc_hall_init(&bad, &hs) == BC_ERR_PARAM, "unknown mode rejected");

    /* PLL at constant speed with misplaced edges and no table: smaller error than (46) */
    bc_hall_params hl = hp;
    hl.mode = BC_HALL_PLL;
    double rmsp, mxp;
    synth_err(&hl, truth, 300.0, 0.0, 0.3, 0.15, &rmsp, &mxp);
    synth_err(&hp, truth, 300.0, 0.0, 0.3, 0.15, &rms0, &mx0);
    printf("test_hall: misplaced (4.6/-2.9/1.7 deg), 300 rad/s: (46) rms %.2f max %.2f deg, "
           "PLL(3) rms %.2f max %.2f deg\n",
           rms0 * 180.0 / BC_PI, mx0 * 180.0 / BC_PI, rmsp * 180.0 / BC_PI, mxp * 180.0 / BC_PI);
    CHECK(rmsp < 0.6 * rms0 && mxp < mx0, "PLL rms %.3g vs (46) %.3g rad", rmsp, rms0);
    /* constant acceleration, exact edges: type 3, no steady error once converged */
    synth_err(&hl, nominal, 300.0, 3000.0, 0.3, 0.15, &rmsp, &mxp);
    synth_err(&hp, nominal, 300.0, 3000.0, 0.3, 0.15, &rms0, &mx0);
    printf("test_hall: 3000 rad/s^2 from 300 rad/s: (46) max %.3f deg, PLL(3) max %.3f deg\n", mx0 * 180.0 / BC_PI,
           mxp * 180.0 / BC_PI);
    CHECK(mxp < 2e-3, "PLL under constant acceleration: max error %.3g rad", mxp);
    /* pll with the true table: exact at constant speed */
    hl.table = ht.table;
    synth_err(&hl, truth, 300.0, 0.0, 0.3, 0.15, &rmsp, &mxp);
    CHECK(mxp < 2e-3, "PLL with the true table: max error %.3g rad", mxp);
}

/* The decoder's angle wrap (without fmodf within a turn of the range) gives fmodf's wrap bit for bit: the
 * standstill angle is wrap(middle of the sector + theta_offset), so theta_offset sweeps the wrap's input over every
 * 1021st float in [-20, 20] (about 3 turns each way) and every float near the turn boundaries. */
static float wrap_fmodf(float th)
{
    th = fmodf(th, BC_TWO_PI_F);
    if (th < 0.0f) th += BC_TWO_PI_F;
    if (th >= BC_TWO_PI_F) th = 0.0f;
    return th;
}

static int wrap_differs(unsigned code, int sector, float offset)
{
    bc_hall_params hp = {10e6f, 5.0f, offset, BC_HALL_INTERP, 1.0f, {0, {0}, {0}}};
    bc_hall_state hs;
    if (bc_hall_init(&hp, &hs) != BC_OK) return 1;
    bc_ctrl_in in;
    memset(&in, 0, sizeof in);
    in.hall = code;
    bc_hall_out ho;
    bc_hall_step(&hp, &hs, &in, &ho);
    float ref = wrap_fmodf(bc_sector_angle(sector) + BC_PI_F / 6.0f + offset); /* the decoder's own expression */
    return memcmp(&ho.theta, &ref, sizeof ref) != 0 || ho.speed_valid != 0;
}

static void test_wrap_matches_fmodf(void)
{
    unsigned code = 1u;
    while (bc_hall_sector(code) != 2) ++code;
    float mid = bc_sector_angle(2) + BC_PI_F / 6.0f;
    long differ = 0, n = 0;
    uint32_t top;
    float twenty = 20.0f;
    memcpy(&top, &twenty, sizeof top);
    for (uint32_t b = 0; b <= top; b += 2039u) { /* |offset| over every 2039th float up to 20, both signs */
        float off;
        memcpy(&off, &b, sizeof off);
        for (int sgn = 0; sgn < 2; ++sgn, ++n, off = -off) differ += wrap_differs(code, 2, off);
    }
    const float bounds[] = {0.0f, BC_TWO_PI_F, -BC_TWO_PI_F, 2.0f * BC_TWO_PI_F, -2.0f * BC_TWO_PI_F};
    for (unsigned b = 0; b < sizeof bounds / sizeof bounds[0]; ++b) {
        float off = bounds[b] - mid;
        for (int j = 0; j < 2000; ++j) off = nextafterf(off, -INFINITY);
        for (int j = 0; j < 4001; ++j, ++n, off = nextafterf(off, INFINITY)) differ += wrap_differs(code, 2, off);
    }
    CHECK(differ == 0 && n > 100000, "angle wrap equals fmodf's: %ld of %ld differ", differ, n);
}

int main(void)
{
    test_wrap_matches_fmodf();
    double e_th, e_om;
    int edges, from;
    /* 0.5 Omega_0 forward: 10 MHz capture, intervals of ~2 ms: speed to 1e-4, angle to a few 1e-4 rad */
    spin(37.5, 0.0, 8000, &e_th, &e_om, &edges, &from);
    CHECK(from == 2, "speed valid from the second edge (got %d)", from);
    CHECK(edges > 20, "edges %d", edges);
    CHECK(e_om < 1e-4, "speed error %.3g", e_om);
    CHECK(e_th < 1e-3, "angle error %.3g rad", e_th);
    /* backward */
    spin(-37.5, 0.0, 8000, &e_th, &e_om, &edges, &from);
    CHECK(e_om < 1e-4 && e_th < 1e-3, "backward: speed %.3g, angle %.3g", e_om, e_th);
    /* the capture timer wraps (2^32 ticks at 10 MHz = 429.5 s): start just before */
    spin(37.5, 429.0, 20000, &e_th, &e_om, &edges, &from);
    CHECK(e_om < 1e-4 && e_th < 1e-3, "across the tick wrap: speed %.3g, angle %.3g", e_om, e_th);

    /* invalid codes and standstill */
    bc_hall_params hp = {10e6f, 5.0f, 0.0f, BC_HALL_INTERP, 1.0f, {0, {0}, {0}}};
    bc_hall_state hs;
    CHECK(bc_hall_init(&hp, &hs) == BC_OK, "init");
    bc_ctrl_in in;
    memset(&in, 0, sizeof in);
    bc_hall_out ho;
    in.hall = 7u;
    bc_hall_step(&hp, &hs, &in, &ho);
    CHECK(ho.valid == 0 && ho.sector == -1 && ho.speed_valid == 0, "111 invalid");
    in.hall = 0u;
    bc_hall_step(&hp, &hs, &in, &ho);
    CHECK(ho.valid == 0, "000 invalid");
    in.hall = 3u;
    in.tick_now = 1000u;
    bc_hall_step(&hp, &hs, &in, &ho);
    CHECK(ho.valid == 1 && ho.sector == 1 && ho.speed_valid == 0, "standstill: sector, no speed");
    CHECK(fabsf(ho.theta - (BC_PI_F / 6.0f + BC_PI_F / 3.0f + BC_PI_F / 6.0f)) < 1e-6f, "middle of the sector");
    /* two edges then the motor stops: the speed decays to zero */
    in.hall = 2u; in.n_edges = 1u; in.tick_edge = 100000u; in.tick_now = 100010u;
    bc_hall_step(&hp, &hs, &in, &ho);
    in.hall = 6u; in.n_edges = 2u; in.tick_edge = 200000u; in.tick_now = 200010u;
    bc_hall_step(&hp, &hs, &in, &ho);
    CHECK(ho.speed_valid == 1 && fabsf(ho.omega_e - (BC_PI_F / 3.0f) / 0.01f) < 1e-2f, "speed from 10 ms");
    in.tick_now = 200000u + 10000000u; /* 1 s later, no edge */
    bc_hall_step(&hp, &hs, &in, &ho);
    CHECK(ho.speed_valid == 0 && ho.omega_e == 0.0f, "stopped motor: speed 0 after the timeout");
    /* a skipped sector (two edges between steps) does not give a false speed */
    in.hall = 5u; in.n_edges = 4u; in.tick_edge = 210000000u; in.tick_now = 210000010u;
    bc_hall_step(&hp, &hs, &in, &ho);
    CHECK(ho.speed_valid == 0, "skipped edge: no speed");
    bc_hall_params bad = {0.0f, 5.0f, 0.0f, BC_HALL_INTERP, 1.0f, {0, {0}, {0}}};
    CHECK(bc_hall_init(&bad, &hs) == BC_ERR_PARAM, "f_tick = 0 rejected");
    test_monotone_angle();
    test_table_and_pll();
    return bc_test_summary("test_hall");
}

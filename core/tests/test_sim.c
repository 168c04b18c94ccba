/* test_sim.c - the closed-loop runner with the open-loop drivers: six-step voltage mode at imposed speed and
 * from standstill with rotor dynamics, chunked runs, trace rows and metric windows. */
#include <math.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_openloop.h"
#include "bldc/bc_sim.h"
#include "fixtures.h"

static const double I0[3] = {0.0, 0.0, 0.0};

typedef struct {
    fixture f;
    bc_sixv_params cp;
    bc_sixv_state cs;
    bc_sim_config cfg;
    bc_sim_inputs in;
} rig;

static void rig_make(rig *r, int mech, float duty)
{
    memset(r, 0, sizeof *r);
    fixture_htm(&r->f, mech);
    r->cp.chop = BC_SIXV_HIGH;
    CHECK(bc_sixv_init(&r->cp, &r->cs) == BC_OK, "sixv init");
    r->cfg.plant = &r->f.p;
    r->cfg.sensors = &r->f.sp;
    r->cfg.ctrl.step = (bc_ctrl_step_fn)0;
    r->cfg.delay = 1;
    r->cfg.trace_every = 1;
    r->cfg.trace_sub = 1;
    r->in.ref_c = (double)duty;
    r->in.v_src_c = 48.0;
}

static void sixv_slot(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sixv_step(p, s, in, out); }

static void test_imposed_speed_metrics(void)
{
    static rig r;
    rig_make(&r, BC_MECH_IMPOSED, 0.6f);
    r.cfg.ctrl.step = sixv_slot;
    r.cfg.ctrl.params = &r.cp;
    r.cfg.ctrl.state = &r.cs;
    double om = 30.0;
    r.in.omega_c = om;
    double Te = 2.0 * BC_PI / (8.0 * om);
    r.cfg.metric_t0 = 3.0 * Te;
    r.cfg.metric_t1 = 5.0 * Te;
    static bc_sim_state s;
    CHECK(bc_sim_init(&r.cfg, &s, 0.1, om, I0, 48.0) == BC_OK, "sim init");
    double th = bc_plant_t_half(&r.f.p);
    int64_t n = (int64_t)ceil(5.5 * Te / th);
    static bc_trace_row rows[8000];
    int64_t nw = 0;
    CHECK(n < 8000, "buffer");
    CHECK(bc_sim_run(&r.cfg, &s, &r.in, n, rows, 8000, &nw) == BC_OK, "run");
    CHECK(nw == n, "one row per sample: %lld of %lld", (long long)nw, (long long)n);
    CHECK(s.m.state == 2, "metric window closed");
    CHECK_NEAR(s.m.t1 - s.m.t0, 2.0 * Te, 1e-12, "window is exactly two electrical periods");
    double E_out = s.m.E[BC_ACC_CU] + s.m.E[BC_ACC_EMF] + s.m.w_l1 - s.m.w_l0;
    CHECK(fabs(s.m.E[BC_ACC_SRC] - E_out) < 1e-6 * s.m.E[BC_ACC_SRC], "window energy balance");
    double tau_mean = s.m.E[BC_ACC_TAU] / (s.m.t1 - s.m.t0);
    CHECK(tau_mean > 0.0, "motoring, %.3f N m", tau_mean);
    CHECK(s.m.tau_min <= s.m.tau_ma_min && s.m.tau_ma_max <= s.m.tau_max, "moving average within extremes");
    CHECK(s.m.n_ma > 100, "moving-average values %d", s.m.n_ma);
    CHECK(s.m.n_ma > s.m.n_ma_grid && s.m.n_ma_grid > 100, "continuous average evaluated more often than the grid's");
    CHECK(s.m.tau_ma_min <= s.m.tau_ma_grid_min + 1e-12 && s.m.tau_ma_grid_max <= s.m.tau_ma_max + 1e-12,
          "continuous moving average bounds the sample-grid one");
    CHECK(s.m.ma_lost == 0, "history ring large enough: %d lost", s.m.ma_lost);
    CHECK(s.m.tau_min <= s.m.tau_s_min && s.m.tau_s_max <= s.m.tau_max, "samples within the exact extremes");
    /* rows: window means integrate to the same total */
    double sum = 0.0;
    for (int64_t j = 0; j < nw; ++j) {
        CHECK(rows[j].tau_min <= rows[j].tau_mean + 1e-9 && rows[j].tau_mean <= rows[j].tau_max + 1e-9, "row %lld", (long long)j);
        sum += rows[j].tau_mean * th;
    }
    CHECK_NEAR(sum, s.plant.acc[BC_ACC_TAU], 1e-9 * fabs(sum), "rows cover the run");
    CHECK(rows[10].mode_a >= 0.0 && rows[10].hall >= 1.0 && rows[10].hall <= 6.0, "row fields");
}

static void test_chunked_equals_whole(void)
{
    static rig r1, r2;
    static bc_sim_state s1, s2;
    rig_make(&r1, BC_MECH_DYNAMIC, 0.5f);
    rig_make(&r2, BC_MECH_DYNAMIC, 0.5f);
    r1.cfg.ctrl.step = sixv_slot;
    r1.cfg.ctrl.params = &r1.cp;
    r1.cfg.ctrl.state = &r1.cs;
    r2.cfg.ctrl.step = sixv_slot;
    r2.cfg.ctrl.params = &r2.cp;
    r2.cfg.ctrl.state = &r2.cs;
    r1.f.p.tau_c = 0.2;
    r2.f.p.tau_c = 0.2;
    CHECK(bc_sim_init(&r1.cfg, &s1, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    CHECK(bc_sim_init(&r2.cfg, &s2, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    int64_t nw;
    CHECK(bc_sim_run(&r1.cfg, &s1, &r1.in, 6000, 0, 0, &nw) == BC_OK, "whole");
    for (int j = 0; j < 6; ++j) CHECK(bc_sim_run(&r2.cfg, &s2, &r2.in, 1000, 0, 0, &nw) == BC_OK, "chunk");
    CHECK(s1.plant.t == s2.plant.t && s1.plant.i[0] == s2.plant.i[0] && s1.plant.omega == s2.plant.omega,
          "chunked run identical: omega %.17g vs %.17g", s1.plant.omega, s2.plant.omega);
    CHECK(s1.plant.omega > 5.0, "accelerates from standstill: %.3f rad/s", s1.plant.omega);
}

static void test_acceleration_to_no_load(void)
{
    static rig r;
    static bc_sim_state s;
    rig_make(&r, BC_MECH_DYNAMIC, 0.5f);
    r.f.p.J = 0.005;
    r.cp.chop = BC_SIXV_SYNC; /* synchronous rectification: the leg averages d V whatever the current */
    r.cfg.ctrl.step = sixv_slot;
    r.cfg.ctrl.params = &r.cp;
    r.cfg.ctrl.state = &r.cs;
    r.cfg.metric_t0 = 0.0; /* acc[] is integrated where something reads it: this window, the whole run */
    r.cfg.metric_t1 = 1.0;
    CHECK(bc_sim_init(&r.cfg, &s, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    int64_t nw;
    CHECK(bc_sim_run(&r.cfg, &s, &r.in, 28000, 0, 0, &nw) == BC_OK, "1 s");
    /* no load, no friction: steady speed where the mean line voltage d V balances 2 k_phi omega */
    double om_nl = 0.5 * 48.0 / (2.0 * 0.32);
    CHECK(fabs(s.plant.omega - om_nl) < 0.03 * om_nl, "no-load speed %.3f vs d V/(2 k_phi) = %.3f", s.plant.omega, om_nl);
    /* mechanical energy balance over the run */
    bc_plant_state *ps = &s.plant;
    double wk = 0.5 * r.f.p.J * ps->omega * ps->omega;
    double bal = ps->acc[BC_ACC_EMF] + ps->acc[BC_ACC_COG] - ps->acc[BC_ACC_FRIC] - ps->acc[BC_ACC_LOAD] - wk;
    CHECK(fabs(bal) < 1e-6 * wk, "mechanical energy balance %.3g J of %.3g J", bal, wk);

    /* high-side chopping without synchronous rectification: at no load the current is discontinuous, the open
     * phase floats at its back-EMF during the off time, and the motor runs far above d V / (2 k_phi) */
    rig_make(&r, BC_MECH_DYNAMIC, 0.5f);
    r.f.p.J = 0.005;
    r.cfg.ctrl.step = sixv_slot;
    r.cfg.ctrl.params = &r.cp;
    r.cfg.ctrl.state = &r.cs;
    CHECK(bc_sim_init(&r.cfg, &s, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    CHECK(bc_sim_run(&r.cfg, &s, &r.in, 28000, 0, 0, &nw) == BC_OK, "1 s");
    CHECK(s.plant.omega > 1.5 * om_nl && s.plant.omega < 75.0, "DCM no-load speed %.3f rad/s", s.plant.omega);
}

static void test_coulomb_stiction(void)
{
    static rig r;
    static bc_sim_state s;
    rig_make(&r, BC_MECH_DYNAMIC, 0.01f); /* 0.01 * 48 V / 2R = 4.8 A: 3.1 N m < tau_c */
    r.f.p.tau_c = 5.0;
    r.cfg.ctrl.step = sixv_slot;
    r.cfg.ctrl.params = &r.cp;
    r.cfg.ctrl.state = &r.cs;
    CHECK(bc_sim_init(&r.cfg, &s, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    int64_t nw;
    CHECK(bc_sim_run(&r.cfg, &s, &r.in, 2000, 0, 0, &nw) == BC_OK, "run");
    CHECK(s.plant.omega == 0.0 && s.plant.stuck == 1, "held by friction: omega %.3g", s.plant.omega);
}

/* What the plant integrates besides the state follows what is read (bc_plant_set_accumulate): a run with no trace
 * integrates the power flows only inside its metric window, one with a trace everywhere. The path of the state is the
 * same bit for bit, and the window's integrals agree to rounding (they start from different absolute values). */
static void test_accumulate_where_read(void)
{
    static rig r1, r2;
    static bc_sim_state s1, s2;
    static bc_trace_row rows[3000];
    for (int k = 0; k < 2; ++k) {
        rig *r = k ? &r2 : &r1;
        rig_make(r, BC_MECH_DYNAMIC, 0.6f);
        r->f.p.V_f = 0.7; /* a diode lane too */
        r->f.p.R_on = 0.004;
        r->cfg.ctrl.step = sixv_slot;
        r->cfg.ctrl.params = &r->cp;
        r->cfg.ctrl.state = &r->cs;
        r->cfg.metric_t0 = 0.04;
        r->cfg.metric_t1 = 0.07;
        r->in.tau_load_c = 1.0;
        CHECK(bc_sim_init(&r->cfg, k ? &s2 : &s1, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    }
    int64_t nw;
    CHECK(bc_sim_run(&r1.cfg, &s1, &r1.in, 2800, 0, 0, &nw) == BC_OK, "no trace");
    CHECK(bc_sim_run(&r2.cfg, &s2, &r2.in, 2800, rows, 3000, &nw) == BC_OK && nw == 2800, "trace");
    CHECK(s1.plant.t == s2.plant.t && s1.plant.omega == s2.plant.omega && s1.plant.theta == s2.plant.theta &&
              s1.plant.i[0] == s2.plant.i[0] && s1.plant.i[1] == s2.plant.i[1] && s1.plant.n_steps == s2.plant.n_steps,
          "the same path: omega %.17g vs %.17g, %lld vs %lld steps", s1.plant.omega, s2.plant.omega,
          (long long)s1.plant.n_steps, (long long)s2.plant.n_steps);
    CHECK(s1.m.state == 2 && s2.m.state == 2, "windows closed");
    for (int j = 0; j < BC_ACC_N; ++j) { /* the metrics' lanes (the trace's: terminal voltages, star point, DC current
                                          * are integrated with a trace only) */
        if (j >= BC_ACC_VA && j <= BC_ACC_IDC) continue;
        double a = s1.m.E[j], b = s2.m.E[j];
        CHECK(fabs(a - b) <= 1e-12 * (1.0 + fabs(b)), "window integral %d: %.17g vs %.17g", j, a, b);
    }
    CHECK(s1.m.tau_min == s2.m.tau_min && s1.m.tau_max == s2.m.tau_max, "the same torque extremes");
    CHECK(fabs(s1.m.tau_ma_max - s2.m.tau_ma_max) < 1e-12 * fabs(s2.m.tau_ma_max), "the same moving average");
    /* without a trace, nothing before the window was integrated; after it nothing either */
    CHECK(s1.plant.acc_on == BC_ACC_OFF && s2.plant.acc_on == BC_ACC_ALL, "levels after the window: %d, %d",
          s1.plant.acc_on, s2.plant.acc_on);
    CHECK(s1.plant.acc[BC_ACC_VA] == 0.0 && s2.plant.acc[BC_ACC_VA] != 0.0, "the trace's lanes only with a trace");
}

int main(void)
{
    test_imposed_speed_metrics();
    test_chunked_equals_whole();
    test_acceleration_to_no_load();
    test_accumulate_where_read();
    test_coulomb_stiction();
    return bc_test_summary("test_sim");
}

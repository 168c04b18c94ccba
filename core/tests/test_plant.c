/* test_plant.c - physics of the plant alone: standstill DC, Hall sequence both ways, open circuit,
 * diode freewheeling to an open phase, energy balance, step-size convergence, the averaged inverter, bad
 * parameters, switching and iron losses. */
#include <math.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_commutation.h"
#include "bldc/bc_plant.h"
#include "fixtures.h"

static const double I0[3] = {0.0, 0.0, 0.0};

static void legs(bc_leg_cmd c[3], int ma, float da, int mb, float db, int mc, float dc)
{
    c[0].mode = ma; c[0].duty = da;
    c[1].mode = mb; c[1].duty = db;
    c[2].mode = mc; c[2].duty = dc;
}

/* Run whole half periods with a fixed command. */
static void run_halves(const bc_plant_params *p, bc_plant_state *s, const bc_leg_cmd c[3], long n, long *k)
{
    double th = bc_plant_t_half(p);
    for (long j = 0; j < n; ++j, ++*k) {
        bc_plant_set_half(p, s, c, (*k % 2) == 0);
        bc_plant_advance(p, s, (double)(*k + 1) * th);
    }
}

static void test_standstill_dc(void)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_plant_state s;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_HIGH, 1.0f, BC_LEG_LOW, 1.0f, BC_LEG_OFF, 0.0f);
    long k = 0;
    double tau = f.p.L / f.p.R, ifin = 48.0 / (2.0 * f.p.R);
    double worst = 0.0;
    for (int m = 1; m <= 20; ++m) {
        run_halves(&f.p, &s, c, 70, &k); /* 70 halves = 2.5 ms */
        double exact = ifin * (1.0 - exp(-s.t / tau));
        double err = fabs(s.i[0] - exact) / ifin;
        if (err > worst) worst = err;
    }
    CHECK(worst < 1e-9, "standstill RL response error %.3g of V/2R", worst);
    CHECK_NEAR(s.i[0], ifin, 1e-3 * ifin, "i_a -> V/(2R) after 33 time constants");
    CHECK_NEAR(s.i[1], -s.i[0], 1e-9, "i_b = -i_a");
    CHECK(s.i[2] == 0.0, "open phase c carries no current");
}

static void test_hall_sequence(double omega, const int *expect, double *edge_angles)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_plant_state s;
    double th0 = 0.01; /* just inside sector 5 -> code 5 */
    CHECK(bc_plant_init(&f.p, &s, 0.0, th0, omega, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f);
    CHECK(s.hall_out == 5, "initial code at theta = 0.01 is 5, got %d", s.hall_out);
    long k = 0;
    int seen = 0;
    uint32_t edges = s.n_edges;
    double th = bc_plant_t_half(&f.p);
    for (long j = 0; j < 200000 && seen < 12; ++j, ++k) {
        bc_plant_set_half(&f.p, &s, c, (k % 2) == 0);
        bc_plant_advance(&f.p, &s, (double)(k + 1) * th);
        if (s.n_edges != edges) {
            CHECK(s.n_edges == edges + 1u, "one edge per half period");
            edges = s.n_edges;
            CHECK(s.hall_out == expect[seen % 6], "edge %d: code %d, expected %d", seen, s.hall_out, expect[seen % 6]);
            /* angle at the edge time, from the imposed speed */
            double th_edge = fmod(th0 + (double)f.p.p * omega * s.t_edge, 2.0 * BC_PI);
            if (th_edge < 0.0) th_edge += 2.0 * BC_PI;
            double d = fabs(th_edge - edge_angles[seen % 6]);
            if (d > BC_PI) d = 2.0 * BC_PI - d;
            CHECK(d < 1e-9, "edge %d at %.12f rad, expected %.12f", seen, th_edge, edge_angles[seen % 6]);
            ++seen;
        }
    }
    CHECK(seen == 12, "saw %d edges", seen);
}

static void test_hall_both_directions(void)
{
    const int fwd[6] = {1, 3, 2, 6, 4, 5};
    double afwd[6], arev[6];
    for (int j = 0; j < 6; ++j) afwd[j] = BC_PI / 6.0 + (double)j * BC_PI / 3.0;
    test_hall_sequence(30.0, fwd, afwd);
    /* backward from code 5 (sector 5, [11pi/6, pi/6)): crossing 11pi/6 enters sector 4 (code 4), ... */
    const int rev[6] = {4, 6, 2, 3, 1, 5};
    for (int j = 0; j < 6; ++j) arev[j] = 11.0 * BC_PI / 6.0 - (double)j * BC_PI / 3.0;
    test_hall_sequence(-30.0, rev, arev);
}

static void test_open_circuit(void)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_plant_state s;
    double om = 0.8 * 48.0 / (2.0 * 0.32); /* below the no-load speed */
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, om, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f);
    long k = 0;
    double worst = 0.0;
    for (int j = 0; j < 400; ++j) {
        run_halves(&f.p, &s, c, 5, &k);
        bc_plant_out o;
        bc_plant_output(&f.p, &s, &o);
        CHECK(s.i[0] == 0.0 && s.i[1] == 0.0 && s.i[2] == 0.0, "no current below no-load speed");
        /* line-to-line terminal voltage = line-to-line back-EMF = omega (k_a - k_b) */
        double want = om * (bc_emf_eval(&f.p.emf[0], s.theta) - bc_emf_eval(&f.p.emf[1], s.theta - 2.0 * BC_PI / 3.0));
        double err = fabs((o.v[0] - o.v[1]) - want);
        if (err > worst) worst = err;
    }
    CHECK(worst < 1e-9, "open-circuit line voltage = back-EMF (err %.3g V)", worst);

    /* above the no-load speed the diodes rectify: current flows back to the source */
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 1.3 * 75.0, I0, 48.0) == BC_OK, "init");
    k = 0;
    run_halves(&f.p, &s, c, 2000, &k);
    CHECK(s.acc[BC_ACC_SRC] < -1.0, "generator: energy to the source %.3g J", s.acc[BC_ACC_SRC]);
    double lhs = s.acc[BC_ACC_SRC];
    double w_l = 0.5 * f.p.L * (s.i[0] * s.i[0] + s.i[1] * s.i[1] + s.i[2] * s.i[2]);
    double rhs = s.acc[BC_ACC_CU] + s.acc[BC_ACC_DIODE] + s.acc[BC_ACC_SW] + s.acc[BC_ACC_EMF] + w_l;
    CHECK(fabs(lhs - rhs) < 1e-6 * fabs(lhs), "rectifier energy balance %.3g J of %.3g J", lhs - rhs, lhs);
}

/* Six-step by the Hall sector, run n electrical periods; returns mean torque over the last one. */
static double six_step(bc_plant_params *p, bc_plant_state *s, double om, float duty, int periods, double *balance,
                       int *opens)
{
    CHECK(bc_plant_init(p, s, 0.0, 0.2, om, I0, 48.0) == BC_OK, "init");
    double th = bc_plant_t_half(p);
    double Te = 2.0 * BC_PI / ((double)p->p * om);
    long k = 0;
    bc_leg_cmd c[3];
    double acc0[BC_ACC_N];
    double wl0 = 0.0;
    double t_start = (periods - 1) * Te;
    int started = 0;
    *opens = 0;
    while ((double)k * th < periods * Te) {
        int sec = bc_hall_sector((uint32_t)s->hall_out), pos, neg;
        legs(c, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f);
        if (bc_sector_phases(sec, &pos, &neg) == 0) {
            c[pos].mode = BC_LEG_HIGH;
            c[pos].duty = duty;
            c[neg].mode = BC_LEG_LOW;
            c[neg].duty = 1.0f;
        }
        bc_plant_set_half(p, s, c, (k % 2) == 0);
        double t1 = (double)(k + 1) * th;
        if (!started && t_start < t1) {
            bc_plant_advance(p, s, t_start);
            memcpy(acc0, s->acc, sizeof acc0);
            wl0 = 0.5 * p->L * (s->i[0] * s->i[0] + s->i[1] * s->i[1] + s->i[2] * s->i[2]);
            started = 1;
        }
        int64_t ev = s->n_events;
        bc_plant_advance(p, s, t1 < periods * Te ? t1 : periods * Te);
        if (s->n_events > ev) *opens += (int)(s->n_events - ev);
        ++k;
    }
    double E[BC_ACC_N];
    for (int j = 0; j < BC_ACC_N; ++j) E[j] = s->acc[j] - acc0[j];
    double wl1 = 0.5 * p->L * (s->i[0] * s->i[0] + s->i[1] * s->i[1] + s->i[2] * s->i[2]);
    double out = E[BC_ACC_RSRC] + E[BC_ACC_CU] + E[BC_ACC_SW] + E[BC_ACC_DIODE] + E[BC_ACC_EMF] + (wl1 - wl0);
    *balance = (E[BC_ACC_SRC] - out) / E[BC_ACC_SRC];
    return E[BC_ACC_TAU] / Te;
}

static void test_six_step_physics(void)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.R_on = 0.004;
    f.p.V_f = 0.7;
    f.p.r_d = 0.002;
    f.p.R_src = 0.01;
    bc_plant_state s;
    double bal;
    int ev;
    double om = 0.5 * 75.0;
    double tau = six_step(&f.p, &s, om, 0.7f, 4, &bal, &ev);
    CHECK(fabs(bal) < 1e-6, "six-step energy balance %.3g relative", bal);
    double bal1 = bal;
    CHECK(ev > 0, "diode current zero crossings located (%d events)", ev);
    CHECK(tau > 1.0, "motoring torque %.4f N m", tau);
    /* step-size convergence: halve and quarter h_max */
    double T_N = 2.0 * 0.32 * 50.0;
    f.p.h_max = 0.5 * bc_plant_t_half(&f.p);
    double tau2 = six_step(&f.p, &s, om, 0.7f, 4, &bal, &ev);
    f.p.h_max = 0.125 * bc_plant_t_half(&f.p);
    double tau8 = six_step(&f.p, &s, om, 0.7f, 4, &bal, &ev);
    CHECK(fabs(tau - tau2) / T_N < 1e-6, "halving the step: %.3g p.u.", fabs(tau - tau2) / T_N);
    /* the residue of the balance is RK4 truncation error: it falls with the step (4th order) */
    CHECK(fabs(bal) < fabs(bal1) / 4.0 || fabs(bal) < 1e-12, "balance converges: %.3g -> %.3g", bal1, bal);
    CHECK(fabs(tau2 - tau8) / T_N < 1e-6, "quartering it again: %.3g p.u.", fabs(tau2 - tau8) / T_N);
}

/* Low-side chopping (LOW with duty, the other phase's upper switch on) and PWM legs, n half periods at omega. */
static void run_fixed(bc_plant_params *p, bc_plant_state *s, const bc_leg_cmd c[3], double om, long n)
{
    long k = 0;
    CHECK(bc_plant_init(p, s, 0.0, 0.3, om, I0, 48.0) == BC_OK, "init");
    run_halves(p, s, c, n, &k);
}

static void test_average_model(void)
{
    fixture f;
    bc_plant_state s;
    double bal, tau_sw, tau_av;
    int ev_sw, ev_av;
    double om = 0.5 * 75.0, T_N = 2.0 * 0.32 * 50.0;
    /* six-step with every loss: the averaged sources and loss terms close the balance */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.R_on = 0.004;
    f.p.V_f = 0.7;
    f.p.r_d = 0.002;
    f.p.R_src = 0.01;
    f.p.inverter = BC_INV_AVERAGE;
    (void)six_step(&f.p, &s, om, 0.7f, 4, &bal, &ev_av);
    CHECK(fabs(bal) < 1e-6, "averaged six-step energy balance %.3g relative", bal);
    CHECK(s.acc[BC_ACC_DIODE] > 0.0 && s.acc[BC_ACC_SW] > 0.0, "switch and diode losses booked");
    /* the averaged plant is the switching one's limit: same torque at 14 kHz to 1e-3 p.u., with about one step per
     * half period and no PWM diode events */
    f.p.inverter = BC_INV_SWITCHING;
    tau_sw = six_step(&f.p, &s, om, 0.7f, 4, &bal, &ev_sw);
    int64_t steps_sw = s.n_steps;
    f.p.inverter = BC_INV_AVERAGE;
    tau_av = six_step(&f.p, &s, om, 0.7f, 4, &bal, &ev_av);
    CHECK(fabs(tau_av - tau_sw) / T_N < 1e-3, "averaged %.5f vs switching %.5f N m", tau_av, tau_sw);
    CHECK(s.n_steps < steps_sw * 2 / 3, "steps %lld vs %lld", (long long)s.n_steps, (long long)steps_sw);
    CHECK(ev_av * 10 < ev_sw, "events %d vs %d", ev_av, ev_sw);

    /* a PWM leg is d v_bus on average, exactly: over a half period its terminal integrates to d V T/2 */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.inverter = BC_INV_AVERAGE;
    bc_leg_cmd c[3];
    legs(c, BC_LEG_PWM, 0.625f, BC_LEG_PWM, 0.375f, BC_LEG_OFF, 0.0f);
    run_fixed(&f.p, &s, c, 10.0, 40);
    double va0 = s.acc[BC_ACC_VA], th = bc_plant_t_half(&f.p);
    long k = 40;
    run_halves(&f.p, &s, c, 1, &k);
    CHECK(fabs(s.acc[BC_ACC_VA] - va0 - 0.625 * 48.0 * th) < 1e-9 * 48.0 * th, "PWM leg mean %.9g V",
          (s.acc[BC_ACC_VA] - va0) / th);

    /* low-side chopping: the lower switch chops phase a (negative current, upper diode in the off fraction);
     * the switching plant at 20x the frequency is within 1 % of the averaged one at the base frequency */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.R_on = 0.004;
    f.p.V_f = 0.7;
    f.p.r_d = 0.002;
    double i_av[3], i_sw[3];
    legs(c, BC_LEG_LOW, 0.6f, BC_LEG_HIGH, 1.0f, BC_LEG_OFF, 0.0f);
    f.p.inverter = BC_INV_AVERAGE;
    double e0 = 0.0;
    run_fixed(&f.p, &s, c, 5.0, 2000);
    for (int x = 0; x < 3; ++x) i_av[x] = s.i[x];
    e0 = s.acc[BC_ACC_DIODE];
    CHECK(s.i[0] < -1.0 && e0 > 0.0, "phase a sinks %.3g A, upper diode loss %.3g J", s.i[0], e0);
    f.p.inverter = BC_INV_SWITCHING;
    f.p.f_pwm = 20.0 * 14e3;
    run_fixed(&f.p, &s, c, 5.0, 40000);
    /* the switching current at a carrier peak/valley is its half-period average */
    for (int x = 0; x < 3; ++x) i_sw[x] = s.i[x];
    CHECK(fabs(i_sw[0] - i_av[0]) < 0.01 * fabs(i_av[0]), "phase a: switching %.5g A, averaged %.5g A", i_sw[0],
          i_av[0]);
    CHECK(fabs(i_sw[1] - i_av[1]) < 0.01 * fabs(i_av[1]), "phase b: switching %.5g A, averaged %.5g A", i_sw[1],
          i_av[1]);

    /* the trip works on averaged legs: every gate off, the diodes take the currents to zero */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.inverter = BC_INV_AVERAGE;
    f.p.i_trip = 30.0;
    legs(c, BC_LEG_HIGH, 0.9f, BC_LEG_LOW, 1.0f, BC_LEG_OFF, 0.0f);
    run_fixed(&f.p, &s, c, 5.0, 400);
    CHECK(s.tripped && s.i[0] == 0.0 && s.i[1] == 0.0, "tripped at %.3g s, currents %.3g %.3g A", s.t_trip, s.i[0],
          s.i[1]);
    CHECK(s.avg[0] == 0 && s.avg[1] == 0, "no averaged leg after the trip");
}

/* Switching losses at standstill (no back-EMF): one leg chops at duty 0.1 into R L, the other holds its switch on.
 * Every carrier period has one hard turn-off (at the ripple top) and one hard turn-on (at the ripple bottom, ending
 * the opposite diode's conduction), so E_swloss = periods (E_on i_lo + E_off i_hi) v_bus / (V_test I_test) and
 * E_rr = periods E_rr i_lo v_bus / (V_test I_test), i_lo and i_hi the ripple's ends (a near-triangle of 2 A on 48 A). A leg chopping with its own diode
 * carrying the current (a LOW leg with i > 0) books nothing. */
static void test_switching_losses(void)
{
    for (int lower = 0; lower < 2; ++lower) {
        fixture f;
        fixture_htm(&f, BC_MECH_IMPOSED);
        f.p.E_on = 1e-4;
        f.p.E_off = 2e-4;
        f.p.E_rr = 0.5e-4;
        f.p.V_test = 40.0;
        f.p.I_test = 50.0;
        bc_plant_state s;
        CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
        bc_leg_cmd c[3];
        if (lower) {
            legs(c, BC_LEG_HIGH, 1.0f, BC_LEG_LOW, 0.1f, BC_LEG_OFF, 0.0f); /* the lower switch of b chops, i_b < 0 */
        } else {
            legs(c, BC_LEG_HIGH, 0.1f, BC_LEG_LOW, 1.0f, BC_LEG_OFF, 0.0f); /* the upper switch of a chops, i_a > 0 */
        }
        long k = 0;
        run_halves(&f.p, &s, c, 1680, &k); /* 60 ms = 40 L/R */
        double a0[BC_ACC_N];
        memcpy(a0, s.acc, sizeof a0);
        double t0 = s.t;
        long periods = 200;
        run_halves(&f.p, &s, c, 2 * periods, &k);
        double i_mean = sqrt((s.acc[BC_ACC_I2A] - a0[BC_ACC_I2A]) / (s.t - t0));
        /* ripple: the chopping switch is on for d T with (48 V - 2 R i) across 2 L */
        double di = (48.0 - 2.0 * f.p.R * i_mean) * 0.1 / f.p.f_pwm / (2.0 * f.p.L);
        double i_lo = i_mean - 0.5 * di, i_hi = i_mean + 0.5 * di;
        double k_s = (double)periods * 48.0 / (40.0 * 50.0);
        double sw = s.acc[BC_ACC_SWLOSS] - a0[BC_ACC_SWLOSS], rr = s.acc[BC_ACC_RR] - a0[BC_ACC_RR];
        double sw_hand = k_s * (1e-4 * i_lo + 2e-4 * i_hi), rr_hand = k_s * 0.5e-4 * i_lo;
        CHECK(fabs(sw / sw_hand - 1.0) < 1e-3, "%s leg chopping: E_swloss %.6g J, hand %.6g J",
              lower ? "lower" : "upper", sw, sw_hand);
        CHECK(fabs(rr / rr_hand - 1.0) < 1e-3, "E_rr %.6g J, hand %.6g J", rr, rr_hand);
        /* the circuit's balance is untouched by the booking */
        double wl = 0.5 * f.p.L * (s.i[0] * s.i[0] + s.i[1] * s.i[1] + s.i[2] * s.i[2]);
        double out = s.acc[BC_ACC_CU] + s.acc[BC_ACC_SW] + s.acc[BC_ACC_DIODE] + s.acc[BC_ACC_EMF] + wl;
        CHECK(fabs(s.acc[BC_ACC_SRC] - out) < 1e-8 * s.acc[BC_ACC_SRC], "circuit balance %.3g J", s.acc[BC_ACC_SRC] - out);
        if (lower) continue;
        /* soft: leg a now chops its lower switch while i_a > 0 flows through that switch's own diode */
        legs(c, BC_LEG_LOW, 0.5f, BC_LEG_LOW, 1.0f, BC_LEG_OFF, 0.0f);
        memcpy(a0, s.acc, sizeof a0);
        run_halves(&f.p, &s, c, 20, &k);
        CHECK(s.i[0] > 10.0, "still freewheeling (%.3g A)", s.i[0]);
        CHECK(s.acc[BC_ACC_SWLOSS] == a0[BC_ACC_SWLOSS] && s.acc[BC_ACC_RR] == a0[BC_ACC_RR],
              "soft edges book nothing (%.3g J, %.3g J)", s.acc[BC_ACC_SWLOSS] - a0[BC_ACC_SWLOSS],
              s.acc[BC_ACC_RR] - a0[BC_ACC_RR]);
    }
    /* bad switching-loss data */
    fixture f;
    bc_plant_state s;
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.E_on = -1e-6;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "E_on < 0 rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.E_rr = 1e-6;
    f.p.I_test = 10.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "E_rr without V_test rejected");
}

/* Iron losses (bc_plant.h). A sinusoidal back-EMF k_1 sin at an imposed constant speed, inverter off (no current):
 * over whole electrical periods p_fe = 3 k_fe_e E^2 / 2 + k_fe_h omega_e + 3 k_fe_x E^1.5 mean|sin|^1.5 with
 * E = k_1 omega and mean|sin|^q = Gamma((q + 1)/2) / (sqrt(pi) Gamma(q/2 + 1)). Then a free spin-down with rotor
 * dynamics: the kinetic energy goes into the iron (balance), hysteresis alone decelerates at the constant
 * p k_fe_h / J and holds the rotor once it stops. */
static void test_iron_losses(void)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    double fx[2] = {0.0, 0.0}, fy[2] = {0.0, 0.3};
    for (int x = 0; x < 3; ++x) {
        f.p.emf[x].kind = BC_EMF_FOURIER;
        f.p.emf[x].n = 2;
        f.p.emf[x].x = fx;
        f.p.emf[x].y = fy;
    }
    f.p.k_fe_e = 0.02;
    f.p.k_fe_h = 0.05;
    f.p.k_fe_x = 0.01;
    const double om = 40.0, E = 0.3 * om, w_e = 8.0 * om;
    const double msin15 = tgamma(1.25) / (sqrt(BC_PI) * tgamma(1.75));
    const double p_eddy = 1.5 * 0.02 * E * E, p_hyst = 0.05 * w_e, p_ex = 3.0 * 0.01 * pow(E, 1.5) * msin15;
    bc_plant_state s;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f);
    double Te = BC_TWO_PI / w_e;
    for (int j = 0; j < 3; ++j) {
        bc_plant_set_half(&f.p, &s, c, j % 2 == 0);
        bc_plant_advance(&f.p, &s, (double)(j + 1) * Te);
    }
    double a0 = s.acc[BC_ACC_FE];
    for (int j = 3; j < 7; ++j) bc_plant_advance(&f.p, &s, (double)(j + 1) * Te);
    double p_fe = (s.acc[BC_ACC_FE] - a0) / (4.0 * Te), hand = p_eddy + p_hyst + p_ex;
    CHECK(s.i[0] == 0.0 && s.acc[BC_ACC_CU] == 0.0, "no current");
    CHECK(fabs(p_fe / hand - 1.0) < 1e-6, "sinusoidal iron loss %.9g W, formula %.9g W", p_fe, hand);
    bc_plant_out out;
    bc_plant_output(&f.p, &s, &out);
    CHECK(out.tau_shaft < -p_hyst / om, "the dynamometer holds the iron drag (%.4g N m)", out.tau_shaft);

    /* spin-down: no current, no friction; eddy + excess + hysteresis */
    fixture_htm(&f, BC_MECH_DYNAMIC);
    f.p.k_fe_e = 0.02;
    f.p.k_fe_h = 0.01;
    f.p.k_fe_x = 0.005;
    f.p.J = 0.01;
    const double om0 = 50.0; /* line back-EMF 32 V < 48 V: the diodes stay off */
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om0, I0, 48.0) == BC_OK, "init");
    long k = 0;
    run_halves(&f.p, &s, c, 4000, &k);
    double w_kin = 0.5 * f.p.J * (om0 * om0 - s.omega * s.omega);
    CHECK(s.omega > 0.0 && s.omega < 0.95 * om0, "decelerating (%.4g rad/s)", s.omega);
    /* the power flows are integrated by the corrected trapezoid rule (bc_plant.h), O(h^5) per step for smooth rates;
     * the excess term's |k|^1.5 is only C1 where a shape crosses zero inside a step, which costs about 1e-8 here at
     * the default step and falls with it (below 1e-10 at h_max = T/32) */
    CHECK(fabs(s.acc[BC_ACC_FE] / w_kin - 1.0) < 3e-8, "kinetic energy into the iron: %.9g J vs %.9g J",
          s.acc[BC_ACC_FE], w_kin);
    f.p.h_max = bc_plant_t_half(&f.p) / 16.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om0, I0, 48.0) == BC_OK, "init");
    k = 0;
    run_halves(&f.p, &s, c, 4000, &k);
    w_kin = 0.5 * f.p.J * (om0 * om0 - s.omega * s.omega);
    CHECK(fabs(s.acc[BC_ACC_FE] / w_kin - 1.0) < 1e-10, "... and at h_max = T/32: %.9g J vs %.9g J",
          s.acc[BC_ACC_FE], w_kin);
    CHECK(s.acc[BC_ACC_FRIC] == 0.0 && s.acc[BC_ACC_CU] == 0.0, "no friction, no current");
}

/* A rotor coasting down against a constant drag, Coulomb friction tau_c or the iron's hysteresis p k_fe_h:
 * omega = om0 - tau t / J until t_stop = J om0 / tau, then held at rest; every joule of kinetic energy is booked.
 * om0 is chosen so that the stop falls inside a step (the RK4 stages past the zero once cancelled the drag and left
 * the rotor coasting at a small constant speed). */
static void test_coulomb_stop(void)
{
    for (int hyst = 0; hyst < 2; ++hyst) {
        for (int j = 0; j < 2; ++j) {
            fixture f;
            fixture_htm(&f, BC_MECH_DYNAMIC);
            f.p.J = 0.002;
            if (hyst) {
                f.p.k_fe_h = 0.01; /* tau = p k_fe_h = 0.08 N m */
            } else {
                f.p.tau_c = 0.08;
            }
            const double om0 = j == 0 ? 50.0 : 50.0007, tau = 0.08, t_stop = f.p.J * om0 / tau;
            bc_plant_state s;
            CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om0, I0, 48.0) == BC_OK, "init");
            bc_leg_cmd c[3];
            legs(c, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f);
            long k = 0, half = (long)(0.5 * t_stop / bc_plant_t_half(&f.p));
            run_halves(&f.p, &s, c, half, &k);
            CHECK(fabs(s.omega - (om0 - tau * s.t / f.p.J)) < 1e-9 * om0, "%s: constant drag, %.12g rad/s",
                  hyst ? "hysteresis" : "Coulomb", s.omega);
            run_halves(&f.p, &s, c, 2 * half, &k);
            CHECK(s.stuck && s.omega == 0.0, "%s from %.4f rad/s: stopped and held (omega %.3g)",
                  hyst ? "hysteresis" : "Coulomb", om0, s.omega);
            double e = s.acc[hyst ? BC_ACC_FE : BC_ACC_FRIC], w0 = 0.5 * f.p.J * om0 * om0;
            CHECK(fabs(e - w0) < 1e-9 * w0, "all kinetic energy booked: %.9g J of %.9g J", e, w0);
            CHECK(s.acc[hyst ? BC_ACC_FRIC : BC_ACC_FE] == 0.0, "in its own lane");
            double th = s.theta;
            run_halves(&f.p, &s, c, 100, &k);
            CHECK(s.theta == th && s.omega == 0.0, "stays at rest");
        }
    }
}

static void test_iron_bad_params(void)
{
    fixture f;
    bc_plant_state s;
    bc_leg_cmd c[3];
    legs(c, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f);
    long k = 0;
    /* zero coefficients: the lane stays zero */
    fixture_htm(&f, BC_MECH_IMPOSED);
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 40.0, I0, 48.0) == BC_OK, "init");
    run_halves(&f.p, &s, c, 100, &k);
    CHECK(s.acc[BC_ACC_FE] == 0.0 && s.acc[BC_ACC_SWLOSS] == 0.0 && s.acc[BC_ACC_RR] == 0.0, "no loss booked");
    /* bad iron-loss coefficients */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.k_fe_e = -1e-3;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "k_fe_e < 0 rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.k_fe_h = NAN;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "k_fe_h = NaN rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.k_fe_x = INFINITY;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "k_fe_x = inf rejected");
}

static void test_bad_params(void)
{
    fixture f;
    bc_plant_state s;
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.L = 0.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "L = 0 rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.R = NAN;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "R = NaN rejected");
    fixture_htm(&f, BC_MECH_DYNAMIC);
    f.p.J = -1.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "J < 0 rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.y[1] = INFINITY;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "inf in table rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.x[2] = f.x[1];
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "non-increasing angles rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.t_dead = 1.0 / 14e3;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "dead time > T/4 rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.inverter = 2;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 0.0, I0, 48.0) == BC_ERR_PARAM, "unknown inverter model rejected");
    /* NaN duties are sanitised by the plant */
    fixture_htm(&f, BC_MECH_IMPOSED);
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, 10.0, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_HIGH, NAN, BC_LEG_LOW, 2.0f, 9, 0.5f);
    bc_plant_set_half(&f.p, &s, c, 1);
    bc_plant_advance(&f.p, &s, bc_plant_t_half(&f.p));
    CHECK((s.flags & BC_PLANT_BAD_DUTY) != 0u, "bad duty flagged");
    CHECK(isfinite(s.i[0]) && isfinite(s.i[1]), "currents finite");
}

/* A rotor turning backward from angle 0 in steps shorter than the rounding of 2 pi (0 - tiny + 2 pi rounds to 2 pi):
 * the angle must land just below 2 pi, not back at 0, where a table's piece bounds (shifted by 2 pi with the frame)
 * no longer contain it and the integrator stalls in zero-length steps. Found as lu-4kw started from rest under a
 * load beyond its friction: a phase's table point 1e-16 rad behind 0 made the first step 1e-9 s long, the rotor
 * moved 4e-16 rad back and the run hung at t = 1e-9 s. Here: an imposed speed of -1e-12 rad/s and a 180-point
 * table (more pieces than the zero-length event budget). */
static void test_backward_from_zero_angle(void)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    enum { NT = 180 };
    static double xt[NT], yt[NT];
    for (int j = 0; j < NT; ++j) { /* the trapezoid sampled every 2 degrees from 0 */
        double a = BC_TWO_PI * (double)j / (double)NT, r = BC_PI / 6.0;
        xt[j] = a;
        yt[j] = a < r ? 0.32 * a / r
                      : (a < BC_PI - r ? 0.32
                                       : (a < BC_PI + r ? 0.32 * (BC_PI - a) / r
                                                        : (a < BC_TWO_PI - r ? -0.32 : 0.32 * (a - BC_TWO_PI) / r)));
    }
    for (int j = 0; j < 3; ++j) {
        f.p.emf[j].kind = BC_EMF_TABLE;
        f.p.emf[j].n = NT;
        f.p.emf[j].x = xt;
        f.p.emf[j].y = yt;
    }
    bc_plant_state s;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.0, -1e-12, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f);
    long k = 0;
    run_halves(&f.p, &s, c, 4, &k);
    CHECK(s.t == 4.0 * bc_plant_t_half(&f.p), "the run ends (t = %.9g s)", s.t);
    CHECK(s.theta > 6.28 && s.theta < BC_TWO_PI, "just below 2 pi: theta %.17g", s.theta);
    CHECK(s.n_steps < 100 && !(s.flags & BC_PLANT_CHATTER), "%lld steps, flags %u", (long long)s.n_steps, s.flags);
}

/* A leg change scheduled inside a half period (bc_plant_schedule, a commutation timer): from its time the leg follows
 * the new command on the same carrier. Phase a's terminal is a PWM leg (connected whatever the current), so its mean
 * over the half period is v_bus times its on-time. */
static void test_scheduled_change(void)
{
    for (int rising = 0; rising < 2; ++rising) {
        for (int avg = 0; avg < 2; ++avg) {
            fixture f;
            fixture_htm(&f, BC_MECH_IMPOSED);
            if (avg) f.p.inverter = BC_INV_AVERAGE;
            bc_plant_state s;
            CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 10.0, I0, 48.0) == BC_OK, "init");
            bc_leg_cmd c[3], c2[3];
            legs(c, BC_LEG_PWM, 0.5f, BC_LEG_PWM, 0.5f, BC_LEG_OFF, 0.0f);
            double th = bc_plant_t_half(&f.p);
            long k = 0;
            run_halves(&f.p, &s, c, 4, &k); /* k = 4: the next half period rises */
            if (!rising) run_halves(&f.p, &s, c, 1, &k);
            double va0 = s.acc[BC_ACC_VA];
            /* rising: on from 0.5 T/2; at 0.2 T/2 the duty becomes 0.9 (on from 0.1 T/2: on at once) -> on 0.8 T/2.
             * falling: on until 0.5 T/2; at 0.2 T/2 the duty becomes 0.1 (off after 0.1 T/2: off at once) -> 0.2 */
            legs(c2, BC_LEG_PWM, rising ? 0.9f : 0.1f, BC_LEG_PWM, 0.5f, BC_LEG_OFF, 0.0f);
            bc_plant_set_half(&f.p, &s, c, rising);
            bc_plant_schedule(&f.p, &s, c2, 0.2 * th);
            bc_plant_advance(&f.p, &s, (double)(k + 1) * th);
            double on = (s.acc[BC_ACC_VA] - va0) / (48.0 * th);
            /* averaged: 0.5 for 0.2 T/2, then the new duty's mean for 0.8 T/2 */
            double d2 = (double)c2[0].duty; /* 0.9f or 0.1f as a double */
            double want = avg ? 0.2 * 0.5 + 0.8 * d2 : (rising ? 0.8 : 0.2);
            CHECK(fabs(on - want) < 1e-9, "%s%s half: on-time %.12f of T/2, expected %.3f", avg ? "averaged, " : "",
                  rising ? "rising" : "falling", on, want);
            CHECK(s.cmd[0].duty == (rising ? 0.9f : 0.1f), "the new command is in force");
            /* a change at or beyond the half period's end is not in it */
            ++k;
            bc_plant_set_half(&f.p, &s, c, (k % 2) == 0);
            bc_plant_schedule(&f.p, &s, c2, th);
            CHECK(s.at_on == 0, "beyond the half period: ignored");
        }
    }
}

/* The ideal current limiter (BC_LEG_HOLD): a+ b(hold at -20 A) with both back-EMFs on their flat tops. Free at full
 * voltage until i_b reaches -20 A, then held there exactly at d* = 1 - (2 R I + e_a - e_b) / V; a bus too low to
 * hold frees it at d = 0 (the current falls), restoring the bus holds it again. Refused (leg off, BAD_DUTY) on the
 * switching inverter and for two HOLD legs. */
static void test_hold(void)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.inverter = BC_INV_AVERAGE;
    f.p.h_max = 0.25 * bc_plant_t_half(&f.p); /* the balance below converges at fourth order: 1.3e-7 at T/2, 6e-10 */
    bc_plant_state s;
    const double om = 1.0, th0 = 1.2; /* e_a = +0.32 V, e_b = -0.32 V (flat tops), c on its ramp */
    CHECK(bc_plant_init(&f.p, &s, 0.0, th0, om, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_HIGH, 1.0f, BC_LEG_HOLD, 1.0f, BC_LEG_OFF, 0.0f);
    bc_plant_set_hold(&f.p, &s, -20.0, 0.0);
    long k = 0;
    run_halves(&f.p, &s, c, 14, &k); /* 0.5 ms */
    CHECK(s.hold_x == 1 && s.hold_on == 1, "holding phase b");
    CHECK(s.i[1] == -20.0 && s.i[0] == 20.0, "the held current is the reference exactly: %.17g, %.17g", s.i[0], s.i[1]);
    bc_plant_out o;
    bc_plant_output(&f.p, &s, &o);
    double want = 1.0 - (2.0 * 0.05 * 20.0 + 2.0 * 0.32 * om) / 48.0;
    CHECK(fabs(o.d_hold - want) < 1e-12, "d* %.15f vs %.15f", o.d_hold, want);
    CHECK(fabs(o.v[1] - want * 48.0) < 1e-9, "the held leg's terminal is d* V: %.12g", o.v[1]);
    CHECK(s.flags == 0u, "no plant flag");
    /* the bus drops below what holding needs: free at d = 0, the current falls; back to 48 V: held again */
    bc_plant_set_inputs(&f.p, &s, om, 0.0, 2.0);
    run_halves(&f.p, &s, c, 4, &k);
    CHECK(s.hold_on == 0 && s.hold_d == 0.0 && s.i[1] > -20.0, "freed at d = 0 (i_b %.6g A)", s.i[1]);
    bc_plant_set_inputs(&f.p, &s, om, 0.0, 48.0);
    run_halves(&f.p, &s, c, 14, &k);
    CHECK(s.hold_on == 1 && s.i[1] == -20.0, "held again (i_b %.17g A)", s.i[1]);
    /* energy: what the source gives, the copper and the back-EMF take (magnetic energy from 0) */
    double w_l = 0.5 * f.p.L * (s.i[0] * s.i[0] + s.i[1] * s.i[1] + s.i[2] * s.i[2]);
    double out = s.acc[BC_ACC_CU] + s.acc[BC_ACC_EMF] + w_l;
    CHECK(fabs(s.acc[BC_ACC_SRC] - out) < 2e-9 * s.acc[BC_ACC_SRC], "energy balance %.3g relative",
          (s.acc[BC_ACC_SRC] - out) / s.acc[BC_ACC_SRC]);

    /* refused: the switching inverter, or two legs */
    for (int q = 0; q < 2; ++q) {
        fixture_htm(&f, BC_MECH_IMPOSED);
        if (q == 1) f.p.inverter = BC_INV_AVERAGE;
        CHECK(bc_plant_init(&f.p, &s, 0.0, th0, om, I0, 48.0) == BC_OK, "init");
        if (q == 0) legs(c, BC_LEG_HIGH, 1.0f, BC_LEG_HOLD, 1.0f, BC_LEG_OFF, 0.0f);
        else legs(c, BC_LEG_HOLD, 1.0f, BC_LEG_HOLD, 1.0f, BC_LEG_OFF, 0.0f);
        bc_plant_set_hold(&f.p, &s, -20.0, 0.0);
        k = 0;
        run_halves(&f.p, &s, c, 4, &k);
        CHECK((s.flags & BC_PLANT_BAD_DUTY) && s.hold_x == -1 && s.i[1] == 0.0, "%s: refused, leg off",
              q == 0 ? "switching inverter" : "two HOLD legs");
    }
}

/* A propeller load on a coasting rotor (legs off, the back-EMF below the bus: no current): J domega/dt = -k_q omega^2,
 * so omega(t) = omega_0 / (1 + k_q omega_0 t / J), and the load takes the kinetic energy lost. */
static void test_propeller_coast(void)
{
    fixture f;
    fixture_htm(&f, BC_MECH_DYNAMIC);
    f.p.J = 0.02;
    f.p.k_q = 2e-3;
    bc_plant_state s;
    const double om0 = 50.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om0, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f, BC_LEG_OFF, 0.0f);
    long k = 0;
    run_halves(&f.p, &s, c, 2800, &k); /* 0.1 s */
    double want = om0 / (1.0 + f.p.k_q * om0 * s.t / f.p.J);
    CHECK(fabs(s.omega - want) < 1e-9 * om0, "omega %.12g vs %.12g rad/s", s.omega, want);
    CHECK(s.i[0] == 0.0 && s.i[1] == 0.0, "no current");
    double dw = 0.5 * f.p.J * (om0 * om0 - s.omega * s.omega);
    CHECK(fabs(s.acc[BC_ACC_LOAD] - dw) < 1e-9 * dw, "the load takes the kinetic energy: %.12g vs %.12g J",
          s.acc[BC_ACC_LOAD], dw);
    f.p.k_q = -1.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om0, I0, 48.0) == BC_ERR_PARAM, "negative k_q refused");
}

/* Temperature (bc_plant_set_thermal): at standstill a DC current settles at V / (2 R r_scale); spinning with the legs
 * off, the open-circuit line voltage is k_scale times the shape's. Refused: a zero or NaN scale. */
static void test_thermal_scales(void)
{
    fixture f;
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_plant_state s;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    CHECK(bc_plant_set_thermal(&f.p, &s, 1.25, 0.9, 1.5) == BC_OK, "set");
    bc_leg_cmd c[3];
    legs(c, BC_LEG_PWM, 0.55f, BC_LEG_PWM, 0.45f, BC_LEG_OFF, 0.0f);
    long k = 0;
    run_halves(&f.p, &s, c, 2000, &k); /* 71 ms: many L / (2 R) */
    double want = 0.1 * 48.0 / (2.0 * 0.05 * 1.25);
    CHECK(fabs(s.i[0] - want) < 2e-3 * want, "DC current %.6g vs %.6g A at 1.25 R", s.i[0], want);
    fixture_htm(&f, BC_MECH_IMPOSED);
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 20.0, I0, 48.0) == BC_OK, "init spinning");
    bc_plant_out o1, o2;
    bc_plant_output(&f.p, &s, &o1);
    CHECK(bc_plant_set_thermal(&f.p, &s, 1.0, 0.9, 1.0) == BC_OK, "set k");
    bc_plant_output(&f.p, &s, &o2);
    for (int x = 0; x < 3; ++x) CHECK(fabs(o2.e[x] - 0.9 * o1.e[x]) < 1e-12, "back-EMF scaled");
    CHECK(bc_plant_set_thermal(&f.p, &s, 0.0, 1.0, 1.0) == BC_ERR_PARAM && bc_plant_set_thermal(&f.p, &s, 1.0, NAN,
          1.0) == BC_ERR_PARAM && s.k_scale == 0.9, "bad scales refused, nothing changed");
}

int main(void)
{
    test_thermal_scales();
    test_propeller_coast();
    test_hold();
    test_standstill_dc();
    test_hall_both_directions();
    test_open_circuit();
    test_six_step_physics();
    test_average_model();
    test_bad_params();
    test_switching_losses();
    test_iron_losses();
    test_coulomb_stop();
    test_backward_from_zero_angle();
    test_scheduled_change();
    test_iron_bad_params();
    return bc_test_summary("test_plant");
}

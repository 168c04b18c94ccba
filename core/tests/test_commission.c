/* test_commission.c - the self-commissioning routine (bc_commission.h) against a small plant written here: a
 * surface-mount PM motor with a sinusoidal back-EMF behind an averaged inverter (each leg's terminal at d_x v_dc over
 * the half period, no dead time, no ripple), the one-sample computation delay of the runner, a free rotor with a
 * little viscous friction, and current sensors on phases a and b with offsets, white noise and a full scale. The
 * plant integrates its own equations (RK4, 8 steps a sample):
 *
 *     L di/dt = u - R i - e,   e = j omega_e psi e^(j theta),   u = Clarke(d v_dc)     (alpha-beta, amplitude-invariant)
 *     J domega_m/dt = 1.5 p psi (i_beta cos theta - i_alpha sin theta) - B omega_m,   dtheta/dt = p omega_m
 *
 * and the routine knows none of its R, L, psi, J. Checked: the phases in order (OFFSET, ALIGN, R_HI, R_LO, L, SPIN,
 * DONE); the offsets read with the legs off; R, L, psi_f against the plant's (an averaged plant leaves the routine
 * only its own errors); each status on the case that names it; a full scale above every reading changing nothing;
 * and init's refusals. Every output finite, every duty in [0, 1], throughout. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_commission.h"
#include "bldc/bc_transform.h"

/* the plant: a small outrunner-like motor, 24 V, 20 kHz PWM (T_s = 25 us) */
#define TS 25e-6
#define P_ 7

typedef struct {
    double R, L, psi, J, B; /* Ohm, H, V s, kg m^2, N m s/rad */
    double v_dc;            /* V */
    double i[2];            /* alpha-beta current, A */
    double th, w;           /* electrical angle of the PM flux (rad), mechanical speed (rad/s) */
    double w_imposed;       /* a dynamometer's speed (rad/s), used when `imposed` */
    int imposed;            /* 1: the speed is imposed */
    int open;               /* 1: the motor is disconnected (no current can flow) */
    double off[2], noise, fs; /* sensors a, b: offsets (A), noise (A, standard deviation), full scale (A; 0 none) */
    uint64_t rng;
    int nan_at;             /* sample at which the sensors read NaN (-1: never) */
} plant;

static void plant_init(plant *m)
{
    memset(m, 0, sizeof *m);
    m->R = 0.1;
    m->L = 50e-6;
    m->psi = 0.005;
    m->J = 2e-5;
    m->B = 1e-6;
    m->v_dc = 24.0;
    m->rng = 0x2545F4914F6CDD1Dull;
    m->nan_at = -1;
}

/* a standard normal variate (xorshift64*, Box-Muller; one of the pair used) */
static double normal(uint64_t *r)
{
    double u[2];
    for (int j = 0; j < 2; ++j) {
        *r ^= *r >> 12;
        *r ^= *r << 25;
        *r ^= *r >> 27;
        u[j] = ((double)((*r * 0x2545F4914F6CDD1Dull) >> 11) + 0.5) / 9007199254740992.0;
    }
    return sqrt(-2.0 * log(u[0])) * cos(2.0 * BC_PI * u[1]);
}

/* derivatives of (i_alpha, i_beta, theta, omega_m) under the alpha-beta voltage u */
static void deriv(const plant *m, const double x[4], const double u[2], double dx[4])
{
    double c = cos(x[2]), s = sin(x[2]), we = P_ * x[3];
    double e[2] = {-we * m->psi * s, we * m->psi * c}; /* j omega_e psi e^(j theta) */
    dx[0] = (u[0] - m->R * x[0] - e[0]) / m->L;
    dx[1] = (u[1] - m->R * x[1] - e[1]) / m->L;
    dx[2] = we;
    double tau = 1.5 * P_ * m->psi * (x[1] * c - x[0] * s);
    dx[3] = m->imposed ? 0.0 : (tau - m->B * x[3]) / m->J;
}

/* one sample period under the legs `cmd` (the command of the sample before: the one-sample delay) */
static void plant_advance(plant *m, const bc_leg_cmd cmd[3])
{
    int on = !m->open;
    double v[3];
    for (int x = 0; x < 3; ++x) {
        on = on && cmd[x].mode == BC_LEG_PWM;
        v[x] = (double)cmd[x].duty * m->v_dc;
    }
    if (m->imposed) m->w = m->w_imposed;
    if (!on) {
        /* a leg off (the routine's offsets, its end) or no motor: a motor at rest carries no current; the currents
         * of these tests are zero there, or forced to it (the open motor) */
        m->i[0] = m->i[1] = 0.0;
        m->th += P_ * m->w * TS;
        return;
    }
    double u[2] = {(2.0 * v[0] - v[1] - v[2]) / 3.0, (v[1] - v[2]) / sqrt(3.0)};
    double x[4] = {m->i[0], m->i[1], m->th, m->w}, h = TS / 8.0;
    for (int n = 0; n < 8; ++n) {
        double k1[4], k2[4], k3[4], k4[4], y[4];
        deriv(m, x, u, k1);
        for (int j = 0; j < 4; ++j) y[j] = x[j] + 0.5 * h * k1[j];
        deriv(m, y, u, k2);
        for (int j = 0; j < 4; ++j) y[j] = x[j] + 0.5 * h * k2[j];
        deriv(m, y, u, k3);
        for (int j = 0; j < 4; ++j) y[j] = x[j] + h * k3[j];
        deriv(m, y, u, k4);
        for (int j = 0; j < 4; ++j) x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    }
    m->i[0] = x[0];
    m->i[1] = x[1];
    m->th = fmod(x[2], 2.0 * BC_PI);
    m->w = x[3];
}

/* the sensors at the sample: phases a and b, offsets, noise, the full scale */
static void plant_measure(plant *m, long k, bc_ctrl_in *in)
{
    memset(in, 0, sizeof *in);
    double ia = m->i[0], ib = -0.5 * m->i[0] + 0.5 * sqrt(3.0) * m->i[1];
    double r[2] = {ia, ib};
    for (int x = 0; x < 2; ++x) {
        double v = r[x] + m->off[x] + (m->noise > 0.0 ? m->noise * normal(&m->rng) : 0.0);
        if (m->fs > 0.0) v = v > m->fs ? m->fs : (v < -m->fs ? -m->fs : v);
        in->i_abc[x] = (float)v;
    }
    if (k == m->nan_at) in->i_abc[0] = NAN;
    in->i_mask = 3u;
    in->v_dc = (float)m->v_dc;
    in->hall = 1u;
}

/* the routine's settings for this motor as bldclab.control.Commission derives them from nominal data (a test
 * current of 5 A, PIs at 400 Hz, the swing of the current-fed rotor w_n = sqrt(1.5 p^2 psi i / J) = 303 rad/s) */
static bc_commission_params settings(void)
{
    bc_commission_params p;
    memset(&p, 0, sizeof p);
    double L = 50e-6, R = 0.1, psi = 0.005, J = 2e-5, i_t = 5.0;
    double w_n = sqrt(1.5 * P_ * P_ * psi * i_t / J), swing = 2.0 * BC_PI / w_n, w_spin = 2.0 * BC_PI * 50.0;
    p.ts = (float)TS;
    p.kp = (float)(2.0 * BC_PI * 400.0 * L);
    p.ki = (float)(2.0 * BC_PI * 400.0 * R);
    p.i_test = (float)i_t;
    p.t_ramp = (float)(3.0 * swing);
    p.t_settle = (float)(5.0 * L / R + 0.01 + 2.0 * swing);
    p.t_window = (float)fmax(0.05, 2.0 * swing);
    p.v_pulse = (float)(0.5 * i_t * L / (10.0 * TS));
    p.n_pulse = 8;
    p.pulse_len = 10;
    p.n_pulse_max = 500;
    p.tol_noise = 0.01f;
    p.t_offset = 0.02f;
    p.i_if = (float)i_t;
    p.if_accel = (float)(0.02 * w_spin * w_n);
    p.w_spin = (float)w_spin;
    p.t_spin = (float)fmax(10.0 * 2.0 * BC_PI / w_spin, 5.0 * swing);
    p.psi_min = (float)(0.25 * psi);
    p.tol_move = 0.05f;
    p.tol_follow = 0.3f;
    p.k_damp = (float)(w_n * J / (1.5 * P_ * P_ * psi * psi));
    p.i_max = 20.0f;
    p.v_max = 48.0f;
    return p;
}

typedef struct {
    int status, order_ok, outputs_ok;
    float R, L, psi, i_off[2];
    int32_t n_cmd;  /* pulse commands of the L test */
    long samples;   /* samples until DONE */
    int phase_seen[BC_COMM_PH_DONE + 1];
} outcome;

/* run the routine against the plant until it is done (or 3 s): the phases seen, in order, and the results */
static outcome run(plant *m, const bc_commission_params *p)
{
    outcome o;
    memset(&o, 0, sizeof o);
    bc_commission_state s;
    o.status = -1;
    if (bc_commission_init(p, &s) != BC_OK) return o;
    o.order_ok = o.outputs_ok = 1;
    bc_leg_cmd prev[3];
    memset(prev, 0, sizeof prev); /* legs off before the first sample */
    int32_t last = -1;
    long k;
    for (k = 0; k < (long)(3.0 / TS); ++k) {
        bc_ctrl_in in;
        bc_ctrl_out out;
        plant_measure(m, k, &in);
        bc_commission_step(p, &s, &in, &out);
        int32_t ph = (int32_t)out.diag[0];
        if (ph < last) o.order_ok = 0; /* never back */
        if (ph >= 0 && ph <= BC_COMM_PH_DONE) o.phase_seen[ph] = 1;
        last = ph;
        for (int x = 0; x < 3; ++x) {
            if (!(out.leg[x].duty >= 0.0f && out.leg[x].duty <= 1.0f)) o.outputs_ok = 0; /* NaN fails too */
        }
        for (int j = 0; j < BC_DIAG_N; ++j) {
            if (!isfinite(out.diag[j])) o.outputs_ok = 0;
        }
        if (s.phase == BC_COMM_PH_L) o.n_cmd = s.n_cmd;
        plant_advance(m, prev);
        memcpy(prev, out.leg, sizeof prev);
        if (s.phase == BC_COMM_PH_DONE) break;
    }
    o.samples = k;
    o.status = s.status;
    o.R = s.R;
    o.L = s.L;
    o.psi = s.psi;
    o.i_off[0] = s.i_off[0];
    o.i_off[1] = s.i_off[1];
    return o;
}

static double rel(double a, double b) { return fabs(a / b - 1.0); }

int main(void)
{
    bc_commission_params p = settings();
    plant m;

    /* 1. the whole routine: every phase in order, R, L, psi_f of the plant (averaged: only the routine's errors) */
    plant_init(&m);
    m.off[0] = 0.3;
    m.off[1] = -0.2;
    outcome o = run(&m, &p);
    CHECK(o.status == BC_COMM_DONE, "status %d", o.status);
    CHECK(o.order_ok && o.outputs_ok, "phases in order (%d), outputs finite and duties in [0, 1] (%d)", o.order_ok,
          o.outputs_ok);
    for (int ph = BC_COMM_PH_OFFSET; ph <= BC_COMM_PH_DONE; ++ph) CHECK(o.phase_seen[ph], "phase %d seen", ph);
    CHECK_NEAR(o.i_off[0], 0.3, 1e-5, "offset a read with the legs off (a float sum of 800 samples)");
    CHECK_NEAR(o.i_off[1], -0.2, 1e-5, "offset b");
    printf("test_commission: R %+.4f %%, L %+.4f %%, psi_f %+.4f %% in %.3f s\n", 100.0 * ((double)o.R / m.R - 1.0),
           100.0 * ((double)o.L / m.L - 1.0), 100.0 * ((double)o.psi / m.psi - 1.0), (double)o.samples * TS);
    CHECK(rel(o.R, m.R) < 0.002, "R %.6g vs %.6g", (double)o.R, m.R);
    CHECK(rel(o.L, m.L) < 0.01, "L %.6g vs %.6g", (double)o.L, m.L);
    CHECK(rel(o.psi, m.psi) < 0.01, "psi %.6g vs %.6g", (double)o.psi, m.psi);
    CHECK(o.n_cmd == 2 * p.n_pulse * p.pulse_len, "no noise: the minimum pulse train (%d commands)", o.n_cmd);
    /* the same with the offsets gone: the results do not depend on them (taken off every sample) */
    plant_init(&m);
    outcome clean = run(&m, &p);
    CHECK(clean.status == BC_COMM_DONE && rel(clean.R, o.R) < 1e-4 && rel(clean.L, o.L) < 1e-4 &&
              rel(clean.psi, o.psi) < 1e-4,
          "offsets calibrated out: R %.6g / %.6g, L %.6g / %.6g, psi %.6g / %.6g", (double)clean.R, (double)o.R,
          (double)clean.L, (double)o.L, (double)clean.psi, (double)o.psi);

    /* 2. the nominal data off (R x1.5, L x0.7, psi x1.25, J x2 in the settings): the measured values are the plant's */
    {
        bc_commission_params q = p;
        q.kp *= 0.7f;
        q.ki *= 1.5f;
        q.psi_min *= 1.25f;
        q.k_damp *= 2.0f / 1.5625f;
        plant_init(&m);
        outcome w = run(&m, &q);
        CHECK(w.status == BC_COMM_DONE && rel(w.R, m.R) < 0.002 && rel(w.L, m.L) < 0.01 && rel(w.psi, m.psi) < 0.01,
              "wrong nominal data: status %d, R %.6g, L %.6g, psi %.6g", w.status, (double)w.R, (double)w.L,
              (double)w.psi);
    }

    /* 3. current noise (2 % of the test current): more pulse pairs until L's standard error is tol_noise, DONE */
    plant_init(&m);
    m.noise = 0.1;
    o = run(&m, &p);
    CHECK(o.status == BC_COMM_DONE, "noise 0.1 A: status %d", o.status);
    CHECK(o.n_cmd > 2 * p.n_pulse * p.pulse_len, "noise: pulse pairs added (%d commands)", o.n_cmd);
    CHECK(rel(o.R, m.R) < 0.02 && rel(o.L, m.L) < 0.05 && rel(o.psi, m.psi) < 0.02, "noise: R %.6g, L %.6g, psi %.6g",
          (double)o.R, (double)o.L, (double)o.psi);
    CHECK(o.outputs_ok, "noise: outputs");
    printf("test_commission: noise 0.1 A: R %+.4f %%, L %+.4f %%, psi_f %+.4f %%, %d pulse pairs\n",
           100.0 * ((double)o.R / m.R - 1.0), 100.0 * ((double)o.L / m.L - 1.0), 100.0 * ((double)o.psi / m.psi - 1.0),
           o.n_cmd / (2 * p.pulse_len));
    /* ... and beyond what n_pulse_max pairs can average: NOISY, R measured before the pulses, L refused */
    {
        bc_commission_params q = p;
        q.n_pulse_max = q.n_pulse;
        plant_init(&m);
        m.noise = 0.25;
        o = run(&m, &q);
        CHECK(o.status == BC_COMM_NOISY, "noise 0.25 A, 8 pairs at most: status %d", o.status);
        CHECK(rel(o.R, m.R) < 0.05 && o.psi == 0.0f, "NOISY: R %.6g measured, psi %.6g not", (double)o.R,
              (double)o.psi);
    }

    /* 4. the other statuses, each on its case */
    plant_init(&m);
    m.imposed = 1;
    m.w_imposed = 20.0 / P_; /* a dynamometer turning the rotor: 0.1 V of back-EMF against 0.5 V of test voltage */
    o = run(&m, &p);
    CHECK(o.status == BC_COMM_ROTOR_MOVING, "turning rotor: status %d", o.status);
    plant_init(&m);
    m.open = 1;
    o = run(&m, &p);
    CHECK(o.status == BC_COMM_NO_CURRENT, "no motor: status %d", o.status);
    plant_init(&m);
    m.v_dc = 0.6; /* the bus's linear limit 0.35 V below the test current's 0.5 V */
    o = run(&m, &p);
    CHECK(o.status == BC_COMM_SATURATED, "low bus: status %d", o.status);
    plant_init(&m);
    m.J *= 1e4; /* the rotor does not follow the I/f vector */
    o = run(&m, &p);
    CHECK(o.status == BC_COMM_NOT_FOLLOWING, "heavy rotor: status %d", o.status);
    plant_init(&m);
    m.nan_at = (long)(0.3 / TS); /* a non-finite reading in the R test */
    o = run(&m, &p);
    CHECK(o.status == BC_COMM_FAULT && o.outputs_ok, "NaN reading: status %d", o.status);
    CHECK(o.samples == m.nan_at, "FAULT at the sample of the reading (%ld, %d)", o.samples, m.nan_at);
    {
        bc_commission_params q = p;
        q.i_fs = 4.0f; /* the sensors saturate below the 5-A test current */
        plant_init(&m);
        m.fs = 4.0;
        o = run(&m, &q);
        CHECK(o.status == BC_COMM_CLIPPED && o.outputs_ok, "full scale 4 A: status %d", o.status);
        CHECK(o.R == 0.0f && o.L == 0.0f, "CLIPPED before any value");
        /* a full scale above every reading (8 A against 5 A and the damping's q current) changes nothing */
        q.i_fs = 8.0f;
        plant_init(&m);
        m.fs = 8.0;
        o = run(&m, &q);
        CHECK(o.status == BC_COMM_DONE && o.R == clean.R && o.L == clean.L && o.psi == clean.psi &&
                  o.samples == clean.samples,
              "full scale 8 A: status %d, the same values bit for bit", o.status);
    }

    /* 5. init refuses what the routine cannot run with */
    {
        bc_commission_state s;
        bc_commission_params q;
        CHECK(bc_commission_init(&p, &s) == BC_OK, "valid");
        q = p;
        q.i_test = q.i_max;
        CHECK(bc_commission_init(&q, &s) == BC_ERR_PARAM, "test current at the trip");
        q = p;
        q.ts = NAN;
        CHECK(bc_commission_init(&q, &s) == BC_ERR_PARAM, "NaN ts");
        q = p;
        q.n_pulse_max = q.n_pulse - 1;
        CHECK(bc_commission_init(&q, &s) == BC_ERR_PARAM, "n_pulse_max < n_pulse");
        q = p;
        q.i_fs = -1.0f;
        CHECK(bc_commission_init(&q, &s) == BC_ERR_PARAM, "negative full scale");
        q = p;
        q.i_fs = NAN;
        CHECK(bc_commission_init(&q, &s) == BC_ERR_PARAM, "NaN full scale");
        q = p;
        q.t_dead = q.ts;
        CHECK(bc_commission_init(&q, &s) == BC_ERR_PARAM, "dead time of a whole sample");
        CHECK(bc_commission_init(0, &s) == BC_ERR_PARAM && bc_commission_init(&p, 0) == BC_ERR_PARAM, "null");
    }
    return bc_test_summary("test_commission");
}

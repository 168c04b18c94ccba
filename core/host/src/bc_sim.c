/* bc_sim.c - the closed-loop runner. Order of one sample in bc_sim.h. */
#include "bldc/bc_sim.h"

#include <math.h>
#include <string.h>

static void sim_on_step(void *ctx, double t, const double *acc, double tau);
static void sim_on_term(void *ctx, double t0, double t1, const double v0[3], const double dv0[3],
                        const double v1[3], const double dv1[3], double v_bus1);

static int sense_on(const bc_sim_config *c) { return c->sense != 0 && c->sense->on; }

/* the history ring is indexed with a mask: its length is a power of two */
typedef char bc_sim_hist_pow2[(BC_SIM_HIST & (BC_SIM_HIST - 1)) == 0 ? 1 : -1];

static int config_ok(const bc_sim_config *c)
{
    if (c == 0 || c->plant == 0 || c->sensors == 0 || c->ctrl.step == 0) return 0;
    if (c->delay != 0 && c->delay != 1) return 0;
    if (c->trace_every < 1 || c->trace_sub < 1 || (c->trace_sub > 1 && c->trace_every != 1)) return 0;
    if (!isfinite(c->metric_t0) || !isfinite(c->metric_t1)) return 0;
    return 1;
}

int bc_sim_init(const bc_sim_config *cfg, bc_sim_state *s, double theta0, double omega0, const double i0[3],
                double v_src0)
{
    if (!config_ok(cfg) || s == 0) return BC_ERR_PARAM;
    memset(s, 0, sizeof *s);
    int rc = bc_plant_init(cfg->plant, &s->plant, 0.0, theta0, omega0, i0, v_src0);
    if (rc != BC_OK) return rc;
    rc = bc_sensor_init(cfg->sensors, &s->sensors);
    if (rc != BC_OK) return rc;
    if (sense_on(cfg)) {
        bc_plant_out po;
        bc_plant_output(cfg->plant, &s->plant, &po);
        rc = bc_sense_init(cfg->sense, &s->sense, s->plant.t, po.v, po.v_bus);
        if (rc != BC_OK) return rc;
    }
    s->k = 0;
    s->th_prev = s->plant.theta;
    s->th_run = 0.0;
    /* s->pending, cleared above: all legs off (BC_LEG_OFF = 0), no timed change */
    s->t_pwm = 2.0 * bc_plant_t_half(cfg->plant);
    sim_on_step(s, s->plant.t, s->plant.acc, s->plant.tau_min); /* the first history node (tau_min: tau_e now) */
    s->temp[0] = NAN; /* no temperature sensor until a thermal model says what it reads */
    s->temp[1] = NAN;
    return BC_OK;
}

int bc_sim_set_temperatures(const bc_sim_config *cfg, bc_sim_state *s, double T_winding, double T_switches)
{
    if (!config_ok(cfg) || s == 0) return BC_ERR_PARAM;
    s->temp[0] = (float)T_winding;
    s->temp[1] = (float)T_switches;
    return BC_OK;
}

int bc_sim_set_thermal(const bc_sim_config *cfg, bc_sim_state *s, double r_scale, double k_scale, double ron_scale)
{
    if (!config_ok(cfg) || s == 0) return BC_ERR_PARAM;
    return bc_plant_set_thermal(cfg->plant, &s->plant, r_scale, k_scale, ron_scale);
}

static double input_at(const double *arr, double c, int64_t n) { return arr ? arr[n] : c; }

/* ---- trace rows ---------------------------------------------------------------------------------------- */

static void row_open(const bc_sim_config *cfg, bc_sim_state *s)
{
    const bc_plant_state *ps = &s->plant;
    bc_plant_out po;
    bc_plant_output(cfg->plant, ps, &po);
    bc_trace_row *r = &s->row;
    r->t = ps->t;
    r->theta_e = ps->theta;
    r->omega_m = ps->omega;
    r->i_a = ps->i[0];
    r->i_b = ps->i[1];
    r->i_c = ps->i[2];
    r->e_a = po.e[0];
    r->e_b = po.e[1];
    r->e_c = po.e[2];
    r->tau_e = po.tau_e;
    r->tau_shaft = po.tau_shaft;
    r->v_bus = po.v_bus;
    r->hall = (double)ps->hall_out;
    r->mode_a = (double)ps->cmd[0].mode;
    r->mode_b = (double)ps->cmd[1].mode;
    r->mode_c = (double)ps->cmd[2].mode;
    /* a held leg (BC_LEG_HOLD) shows the duty it has now, not the current it holds */
    r->duty_a = ps->cmd[0].mode == BC_LEG_HOLD ? po.d_hold : (double)ps->cmd[0].duty;
    r->duty_b = ps->cmd[1].mode == BC_LEG_HOLD ? po.d_hold : (double)ps->cmd[1].duty;
    r->duty_c = ps->cmd[2].mode == BC_LEG_HOLD ? po.d_hold : (double)ps->cmd[2].duty;
    r->d0 = (double)s->last.diag[0];
    r->d1 = (double)s->last.diag[1];
    r->d2 = (double)s->last.diag[2];
    r->d3 = (double)s->last.diag[3];
    r->d4 = (double)s->last.diag[4];
    r->d5 = (double)s->last.diag[5];
    r->d6 = (double)s->last.diag[6];
    r->d7 = (double)s->last.diag[7];
    r->flags = (double)s->last.flags;
    r->hw_trip = (double)ps->tripped;
    r->t_at = -1.0;
    for (int x = 0; x < 3; ++x) s->plant.t_iz[x] = -1.0; /* the plant notes the first current end from here */
    memcpy(s->row_acc0, ps->acc, sizeof s->row_acc0);
    s->row_tmin = po.tau_e;
    s->row_tmax = po.tau_e;
    s->row_open = 1;
}

static void row_close(bc_sim_state *s, bc_trace_row *rows, int64_t cap, int64_t *nw, int *overflow)
{
    s->row_open = 0;
    if (rows == 0) return;
    if (*nw >= cap) {
        *overflow = 1;
        return;
    }
    /* the fields set at the row's start are copied, stored long ago; the means are written in place (copying them
     * just after storing them would wait for the stores: gcc copies the record with `rep movs`) */
    bc_trace_row *r = &rows[*nw];
    *r = s->row;
    const bc_plant_state *ps = &s->plant;
    double dt = ps->t - r->t;
    const double *a0 = s->row_acc0, *a1 = ps->acc;
    double inv = dt > 0.0 ? 1.0 / dt : 0.0;
    r->tau_mean = (a1[BC_ACC_TAU] - a0[BC_ACC_TAU]) * inv;
    r->tau_min = s->row_tmin;
    r->tau_max = s->row_tmax;
    r->p_src = (a1[BC_ACC_SRC] - a0[BC_ACC_SRC]) * inv;
    r->p_cu = (a1[BC_ACC_CU] - a0[BC_ACC_CU]) * inv;
    /* the gate-edge energies (impulses) as the row's mean power: the trace integrates to the metrics' sums */
    r->p_swloss = (a1[BC_ACC_SWLOSS] - a0[BC_ACC_SWLOSS] + a1[BC_ACC_RR] - a0[BC_ACC_RR]) * inv;
    r->p_inv = (a1[BC_ACC_SW] - a0[BC_ACC_SW] + a1[BC_ACC_DIODE] - a0[BC_ACC_DIODE] + a1[BC_ACC_RSRC] -
                a0[BC_ACC_RSRC]) * inv + r->p_swloss;
    r->p_emf = (a1[BC_ACC_EMF] - a0[BC_ACC_EMF]) * inv;
    r->t_iz_a = ps->t_iz[0];
    r->t_iz_b = ps->t_iz[1];
    r->t_iz_c = ps->t_iz[2];
    r->v_a = (a1[BC_ACC_VA] - a0[BC_ACC_VA]) * inv;
    r->v_b = (a1[BC_ACC_VB] - a0[BC_ACC_VB]) * inv;
    r->v_c = (a1[BC_ACC_VC] - a0[BC_ACC_VC]) * inv;
    r->v_n = (a1[BC_ACC_VN] - a0[BC_ACC_VN]) * inv;
    r->i_dc = (a1[BC_ACC_IDC] - a0[BC_ACC_IDC]) * inv;
    *nw += 1;
    /* the result checks' summary of the rows (bldclab.sim.plausibility), gathered here instead of by strided passes
     * over the record array */
    const double pk[4] = {fabs(r->i_a), fabs(r->i_b), fabs(r->i_c), fabs(r->omega_m)};
    for (int j = 0; j < 4; ++j) {
        if (pk[j] > s->row_peak[j]) s->row_peak[j] = pk[j];
    }
    if (!(isfinite(r->i_a) && isfinite(r->i_b) && isfinite(r->i_c) && isfinite(r->tau_e) && isfinite(r->omega_m)))
        s->row_nonfinite = 1;
}

/* ---- continuous moving average ------------------------------------------------------------------------- */

/* Force inlining into the per-step callback (GCC and Clang; elsewhere a hint). */
#if defined(__GNUC__)
#define BC_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define BC_ALWAYS_INLINE inline
#endif

/* A at tq inside history segment [a, a+1] (absolute indices): cubic Hermite through the node values of A and their
 * derivatives tau_e. */
static BC_ALWAYS_INLINE double hist_interp(const bc_sim_state *s, int64_t a, double tq)
{
    int ja = (int)(a & (BC_SIM_HIST - 1)), jb = (int)((a + 1) & (BC_SIM_HIST - 1));
    double h = s->h_t[jb] - s->h_t[ja];
    if (!(h > 0.0)) return s->h_a[jb];
    double u = (tq - s->h_t[ja]) / h;
    if (u < 0.0) u = 0.0;
    if (u > 1.0) u = 1.0;
    /* A(u) = A_a + u (h tau_a + u (3 D - 2 h tau_a - h tau_b + u (h tau_a + h tau_b - 2 D))), D = A_b - A_a */
    double D = s->h_a[jb] - s->h_a[ja], m0 = h * s->h_tau[ja], m1 = h * s->h_tau[jb];
    return s->h_a[ja] + u * (m0 + u * (3.0 * D - 2.0 * m0 - m1 + u * (m0 + m1 - 2.0 * D)));
}

/* Fold MA = num / T into the extremes. Division by T > 0 is monotonic (correctly rounded), so the extreme of the
 * quotients is the quotient of the extreme numerator: the division is made only where an extreme moves. */
static void ma_fold(bc_sim_state *s, double num, double T)
{
    if (num < s->ma_num_min) {
        s->ma_num_min = num;
        s->m.tau_ma_min = num / T;
    }
    if (num > s->ma_num_max) {
        s->ma_num_max = num;
        s->m.tau_ma_max = num / T;
    }
    s->m.n_ma += 1;
}

/* Every accepted plant step ends here (bc_plant_step_fn): push (t, A, tau_e) into the history and, inside the metric
 * window, evaluate MA(t) = (A(t) - A(t - T)) / T at the new node and at the older nodes shifted by T that fall in
 * the step just ended. */
/* Add the angle moved since the last call to th_run. A step moves the angle by far less than pi (it is at most
 * half a PWM period), so the difference taken into [-pi, pi) undoes the plant's wrapping to [0, 2 pi). */
static void angle_track(bc_sim_state *s)
{
    double d = s->plant.theta - s->th_prev;
    if (d >= BC_PI) d -= BC_TWO_PI;
    if (d < -BC_PI) d += BC_TWO_PI;
    s->th_run += d;
    s->th_prev = s->plant.theta;
}

static void sim_on_step(void *ctx, double t, const double *acc, double tau)
{
    bc_sim_state *s = (bc_sim_state *)ctx;
    angle_track(s);
    if (s->m.state != 1) return; /* outside the metric window nothing reads the history (metric_start resets it) */
    const double A = acc[BC_ACC_TAU];
    int64_t n = s->h_n;
    if (n > 0) {
        int jl = (int)((n - 1) & (BC_SIM_HIST - 1));
        if (!(t > s->h_t[jl])) { /* a zero-length step (an event at this instant): same node */
            s->h_a[jl] = A;
            s->h_tau[jl] = tau;
            return;
        }
    }
    int jn = (int)(n & (BC_SIM_HIST - 1));
    s->h_t[jn] = t;
    s->h_a[jn] = A;
    s->h_tau[jn] = tau;
    s->h_n = ++n;
    const int64_t oldest = n - BC_SIM_HIST;
    const int in = s->m.state == 1;
    const double T = s->t_pwm;
    const double eps = 1e-9 * T;
    const double t0e = s->m.t0 - eps; /* the window's start, less rounding */
    int64_t lag = s->h_lag;           /* kept in a local: ma_fold writes through s */
    if (lag < oldest) {
        if (in && s->h_t[(int)(oldest & (BC_SIM_HIST - 1))] - T > t0e) s->m.ma_lost += 1;
        lag = oldest;
    }
    if (n < 2) {
        s->h_lag = lag;
        return;
    }
    const int64_t prev = n - 2;
    const double t_prev = s->h_t[(int)(prev & (BC_SIM_HIST - 1))];
    /* older nodes j whose t_j + T lies in (t_prev, t]: A(t_j + T) from the step just ended, A(t_j) exact */
    while (lag + 1 < n - 1) {
        const int j = (int)((lag + 1) & (BC_SIM_HIST - 1));
        const double ts = s->h_t[j] + T;
        if (ts > t) break;
        if (in && ts > t_prev && s->h_t[j] >= t0e) ma_fold(s, hist_interp(s, prev, ts) - s->h_a[j], T);
        lag += 1;
    }
    s->h_lag = lag;
    /* the new node: A(t - T) from the history segment holding t - T */
    const double tq = t - T;
    if (in && tq >= t0e && s->h_t[(int)(lag & (BC_SIM_HIST - 1))] <= tq + eps) {
        ma_fold(s, A - hist_interp(s, lag, tq), T);
    }
}

/* The plant's terminal observer: the back-EMF sensing follows every step. */
static void sim_on_term(void *ctx, double t0, double t1, const double v0[3], const double dv0[3],
                        const double v1[3], const double dv1[3], double v_bus1)
{
    bc_sim_state *s = (bc_sim_state *)ctx;
    (void)t0;
    bc_sense_step(s->sense_p, &s->sense, t1, v0, dv0, v1, dv1, v_bus1);
}

/* ---- metrics ------------------------------------------------------------------------------------------- */

static double w_kin(const bc_plant_params *p, const bc_plant_state *ps)
{
    return p->mech == BC_MECH_DYNAMIC ? 0.5 * p->J * ps->omega * ps->omega : 0.0;
}

static double w_mag(const bc_plant_params *p, const bc_plant_state *ps)
{
    return 0.5 * p->L * (ps->i[0] * ps->i[0] + ps->i[1] * ps->i[1] + ps->i[2] * ps->i[2]);
}

static void metric_start(const bc_sim_config *cfg, bc_sim_state *s, int trace)
{
    bc_plant_state *ps = &s->plant;
    bc_plant_set_accumulate(cfg->plant, ps, trace ? BC_ACC_ALL : BC_ACC_METRICS);
    double tau = bc_plant_tau(cfg->plant, ps);
    s->m.t0 = ps->t;
    memcpy(s->m_acc0, ps->acc, sizeof s->m_acc0);
    s->m.w_l0 = w_mag(cfg->plant, ps);
    s->m.w_kin0 = w_kin(cfg->plant, ps);
    angle_track(s);
    s->m.th0 = s->th_run;
    s->m.t_zero_i0 = ps->t_zero_i;
    ps->zero_i = 0; /* a zero-current interval running at t0 counts as one of the window's */
    s->m.n_zero_i0 = ps->n_zero_i;
    s->m.tau_min = tau;
    s->m.tau_max = tau;
    s->m.tau_ma_min = HUGE_VAL;
    s->m.tau_ma_max = -HUGE_VAL;
    s->ma_num_min = HUGE_VAL;
    s->ma_num_max = -HUGE_VAL;
    s->m.tau_ma_grid_min = HUGE_VAL;
    s->m.tau_ma_grid_max = -HUGE_VAL;
    s->m.tau_s_min = HUGE_VAL;
    s->m.tau_s_max = -HUGE_VAL;
    for (int x = 0; x < 3; ++x) s->m.i_peak[x] = fabs(ps->i[x]);
    s->m.n_ma = 0;
    s->m.n_ma_grid = 0;
    s->m.ma_lost = 0;
    s->ma_have = 0;
    s->m.state = 1;
    /* the moving average's history starts at t0 (before it acc[] may not have been integrated) */
    s->h_n = 0;
    s->h_lag = 0;
    sim_on_step(s, ps->t, ps->acc, tau);
}

static void metric_stop(const bc_sim_config *cfg, bc_sim_state *s, int trace)
{
    const bc_plant_state *ps = &s->plant;
    s->m.t1 = ps->t;
    for (int j = 0; j < BC_ACC_N; ++j) s->m.E[j] = ps->acc[j] - s->m_acc0[j];
    s->m.w_l1 = w_mag(cfg->plant, ps);
    s->m.w_kin1 = w_kin(cfg->plant, ps);
    angle_track(s);
    s->m.th1 = s->th_run;
    s->m.t_zero_i1 = ps->t_zero_i;
    s->m.n_zero_i1 = ps->n_zero_i;
    s->m.state = 2;
    if (!trace) bc_plant_set_accumulate(cfg->plant, &s->plant, BC_ACC_OFF); /* nothing reads acc[] any more */
}

/* Integrate to t, then merge the chunk's extremes into the open row and the running metrics. */
static void advance_chunk(const bc_sim_config *cfg, bc_sim_state *s, double t)
{
    bc_plant_reset_extremes(cfg->plant, &s->plant);
    bc_plant_advance(cfg->plant, &s->plant, t);
    const bc_plant_state *ps = &s->plant;
    if (s->row_open) {
        if (ps->tau_min < s->row_tmin) s->row_tmin = ps->tau_min;
        if (ps->tau_max > s->row_tmax) s->row_tmax = ps->tau_max;
    }
    if (s->m.state == 1) {
        if (ps->tau_min < s->m.tau_min) s->m.tau_min = ps->tau_min;
        if (ps->tau_max > s->m.tau_max) s->m.tau_max = ps->tau_max;
        for (int x = 0; x < 3; ++x) {
            if (ps->i_peak[x] > s->m.i_peak[x]) s->m.i_peak[x] = ps->i_peak[x];
        }
    }
}

/* Count the flag bits raised at the sample at t (over the run, and in the window if in_window). */
static void flags_count(bc_sim_state *s, uint32_t flags, double t, int in_window)
{
    if (in_window) s->m.n_samples += 1;
    for (int j = 0; flags != 0u && j < BC_SIM_NFLAG; ++j, flags >>= 1) {
        if (!(flags & 1u)) continue;
        if (s->flag_run_n[j]++ == 0) s->flag_run_t0[j] = t;
        s->flag_run_t1[j] = t;
        if (!in_window) continue;
        if (s->m.flag_n[j]++ == 0) s->m.flag_t0[j] = t;
        s->m.flag_t1[j] = t;
    }
}

/* ---- the loop ------------------------------------------------------------------------------------------ */

static const bc_ctrl_in ZERO_IN;   /* all zero: what the measurements and the controller's output start from */
static const bc_ctrl_out ZERO_OUT;

int bc_sim_run(const bc_sim_config *cfg, bc_sim_state *s, const bc_sim_inputs *in, int64_t n, bc_trace_row *rows,
               int64_t rows_cap, int64_t *rows_written)
{
    if (!config_ok(cfg) || s == 0 || in == 0 || n < 0 || rows_written == 0) return BC_ERR_PARAM;
    const bc_plant_params *pp = cfg->plant;
    double th = bc_plant_t_half(pp);
    int has_window = cfg->metric_t1 > cfg->metric_t0;
    int overflow = 0;
    *rows_written = 0;
    s->plant.on_step = sim_on_step; /* set on every call: the state may have been copied */
    s->plant.on_step_ctx = s;
    s->plant.on_term = sim_on_term;
    s->sense_p = cfg->sense;
    bc_plant_set_terminals(pp, &s->plant, sense_on(cfg));
    /* the power flows and extremes are integrated where something reads them: a trace, the metric window */
    bc_plant_set_accumulate(pp, &s->plant, rows != 0 ? BC_ACC_ALL : (s->m.state == 1 ? BC_ACC_METRICS : BC_ACC_OFF));

    for (int64_t j = 0; j < n; ++j) {
        int64_t k = s->k;
        double t_k = (double)k * th;
        double t_next = (double)(k + 1) * th;
        bc_plant_state *ps = &s->plant;
        ps->t = t_k; /* exact, whatever rounding the last step left */

        /* 1. inputs held over the sample */
        bc_plant_set_inputs(pp, ps, input_at(in->omega, in->omega_c, j), input_at(in->tau_load, in->tau_load_c, j),
                            input_at(in->v_src, in->v_src_c, j));

        /* 2. measure, control */
        /* the measurements and the output are made in place: last_in, last (no copies per sample) */
        bc_ctrl_in *ci = &s->last_in;
        *ci = ZERO_IN; /* a copy, not memset: gcc's `rep stos` for that cannot forward to the loads that follow */
        bc_sensor_measure(cfg->sensors, &s->sensors, ps, bc_plant_vbus(pp, ps), ci);
        if (sense_on(cfg)) bc_sense_fill(cfg->sense, &s->sense, t_k, ci);
        ci->ref = (float)input_at(in->ref, in->ref_c, j);
        ci->omega_ref = (float)input_at(in->omega_ref, in->omega_ref_c, j);
        ci->temp[0] = s->temp[0];
        ci->temp[1] = s->temp[1];
        bc_ctrl_out *co = &s->last;
        *co = ZERO_OUT;
        cfg->ctrl.step(cfg->ctrl.params, cfg->ctrl.state, ci, co);
        s->flags_seen |= co->flags;
        flags_count(s, co->flags, t_k, has_window && t_k >= cfg->metric_t0 && t_k < cfg->metric_t1);

        /* 3. apply; gate edges at t_k book their energies (E_on, E_off, E_rr) here, and belong to a row or metric
         * window that starts at t_k: [t0, t1) holds the edges at t0, not those at t1 (each edge once per period) */
        double pre_swloss = ps->acc[BC_ACC_SWLOSS], pre_rr = ps->acc[BC_ACC_RR];
        const bc_ctrl_out *applied = cfg->delay ? &s->pending : co;
        bc_plant_set_hold(pp, ps, (double)applied->i_hold, (double)applied->i_hold_at);
        bc_plant_set_half(pp, ps, applied->leg, (k % 2) == 0);
        if (applied->has_at) bc_plant_schedule(pp, ps, applied->leg_at, (double)applied->t_at);
        s->at_time = applied->has_at ? t_k + (double)applied->t_at : -1.0;
        s->pending = *co; /* after: applied may point to it */

        /* torque at the sample instant, inside the metric window */
        if (s->m.state == 1) {
            double tau = bc_plant_tau(pp, ps);
            if (tau < s->m.tau_s_min) s->m.tau_s_min = tau;
            if (tau > s->m.tau_s_max) s->m.tau_s_max = tau;
        }

        /* half-period torque mean for the moving average */
        s->half_tau0 = ps->acc[BC_ACC_TAU];
        s->half_in = has_window && s->m.state == 1 && t_k >= cfg->metric_t0;

        /* 4. integrate to t_next through the row and metric bounds */
        int sub = cfg->trace_sub;
        for (int q = 0; q < sub; ++q) {
            double t_row = t_k + th * (double)q / (double)sub;
            int row_start = (sub > 1) || (k % cfg->trace_every == 0);
            if (row_start && (rows != 0)) {
                if (s->row_open && ps->t >= t_row) {
                    row_close(s, rows, rows_cap, rows_written, &overflow);
                }
                if (!s->row_open) {
                    row_open(cfg, s);
                    if (q == 0) {
                        s->row_acc0[BC_ACC_SWLOSS] = pre_swloss;
                        s->row_acc0[BC_ACC_RR] = pre_rr;
                    }
                }
            }
            double t_seg = (q + 1 == sub) ? t_next : t_k + th * (double)(q + 1) / (double)sub;
            if (rows != 0 && s->row_open && s->at_time >= t_row && s->at_time < t_seg) s->row.t_at = s->at_time;
            /* metric bounds inside this segment */
            if (has_window && s->m.state == 0 && cfg->metric_t0 >= ps->t && cfg->metric_t0 < t_seg) {
                if (cfg->metric_t0 > ps->t) advance_chunk(cfg, s, cfg->metric_t0);
                metric_start(cfg, s, rows != 0);
                if (ps->t == t_k) {
                    s->m_acc0[BC_ACC_SWLOSS] = pre_swloss;
                    s->m_acc0[BC_ACC_RR] = pre_rr;
                }
            }
            if (has_window && s->m.state == 1 && cfg->metric_t1 > ps->t && cfg->metric_t1 <= t_seg) {
                advance_chunk(cfg, s, cfg->metric_t1);
                metric_stop(cfg, s, rows != 0);
            }
            advance_chunk(cfg, s, t_seg);
            if (sub > 1 && rows != 0 && s->row_open) {
                row_close(s, rows, rows_cap, rows_written, &overflow);
            }
        }
        ps->t = t_next;

        /* sample-grid moving average over one PWM period of the half-period means, halves fully inside the window */
        if (s->half_in && s->m.state == 1) {
            double mean = (ps->acc[BC_ACC_TAU] - s->half_tau0) / th;
            if (s->ma_have) {
                double ma = 0.5 * (mean + s->ma_prev);
                if (ma < s->m.tau_ma_grid_min) s->m.tau_ma_grid_min = ma;
                if (ma > s->m.tau_ma_grid_max) s->m.tau_ma_grid_max = ma;
                s->m.n_ma_grid += 1;
            }
            s->ma_prev = mean;
            s->ma_have = 1;
        }
        s->k = k + 1;
        /* a row spanning several samples closes at its window's end */
        if (sub == 1 && rows != 0 && s->row_open && (s->k % cfg->trace_every) == 0) {
            row_close(s, rows, rows_cap, rows_written, &overflow);
        }
    }
    return overflow ? BC_ERR_SIZE : BC_OK;
}

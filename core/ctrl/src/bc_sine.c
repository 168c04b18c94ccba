/* bc_sine.c - sinusoidal current supply with square-wave start. Laws and their order in bc_sine.h. */
#include "bldc/bc_sine.h"

#include <math.h>

#include "bldc/bc_math.h"

static int finite_pos(float v) { return isfinite(v) && v > 0.0f; }
static int finite_nonneg(float v) { return isfinite(v) && v >= 0.0f; }
static int is_flag(int32_t v) { return v == 0 || v == 1; }
static float table_k(const float *k, int32_t n, float theta);

/* Length of the alpha-beta vector of line values v_ab, v_bc, v_ca: alpha = (v_ab - v_ca) / 3, beta = v_bc / sqrt(3). */
static float lim_norm(float ab, float bc, float ca)
{
    float a = (ab - ca) * (1.0f / 3.0f), b = bc * BC_INV_SQRT3_F;
    return sqrtf(a * a + b * b);
}

/* Tables of the shape-aware speed limit (bc_sine.h, 5.) at theta_j = 2 pi j / M: line-to-line back-EMF shape
 * k_xy, current i_xy of i_q = 1 A (i_x = sin(theta - x 2 pi/3)) and di_xy/dtheta. */
static void lim_tables(const bc_sine_params *p, bc_sine_state *s)
{
    for (int32_t j = 0; j < BC_SINE_LIM_N; ++j) {
        float th = (float)j * (BC_TWO_PI_F / (float)BC_SINE_LIM_N);
        float k[3], ix[3], dix[3];
        for (int x = 0; x < 3; ++x) {
            float ph = th - (float)x * (BC_TWO_PI_F / 3.0f);
            k[x] = table_k(p->emf_k[x], p->emf_n, ph);
            ix[x] = sinf(ph);
            dix[x] = cosf(ph);
        }
        for (int x = 0; x < 3; ++x) {
            int y = (x + 1) % 3;
            s->lim_k[x][j] = k[x] - k[y];
            s->lim_i[x][j] = ix[x] - ix[y];
            s->lim_di[x][j] = dix[x] - dix[y];
        }
    }
    /* lim_dev: the largest deviation of a line shape k_xy above or below the chord between neighbouring grid
     * angles (0 for a piecewise-linear shape whose corners are grid angles, (1 - cos(pi/M)) sqrt(3) k_1 for a
     * sinusoid), sampled at every table spacing or finer */
    int32_t n_sub = 2 * (p->emf_n / BC_SINE_LIM_N + 1);
    float dev = 0.0f, dev_c = 0.0f;
    for (int32_t j = 0; j < BC_SINE_LIM_N; ++j) {
        int32_t j1 = (j + 1) % BC_SINE_LIM_N;
        for (int32_t q = 1; q < n_sub; ++q) {
            float u = (float)q / (float)n_sub;
            float th = ((float)j + u) * (BC_TWO_PI_F / (float)BC_SINE_LIM_N);
            float k[3];
            for (int x = 0; x < 3; ++x) k[x] = table_k(p->emf_k[x], p->emf_n, th - (float)x * (BC_TWO_PI_F / 3.0f));
            for (int x = 0; x < 3; ++x) {
                float kxy = k[x] - k[(x + 1) % 3];
                float chord = s->lim_k[x][j] + u * (s->lim_k[x][j1] - s->lim_k[x][j]);
                dev = fmaxf(dev, fabsf(kxy - chord));
            }
            /* circle: the length of the alpha-beta vector above the chord of the lengths */
            float n0 = lim_norm(s->lim_k[0][j], s->lim_k[1][j], s->lim_k[2][j]);
            float n1 = lim_norm(s->lim_k[0][j1], s->lim_k[1][j1], s->lim_k[2][j1]);
            float nk = lim_norm(k[0] - k[1], k[1] - k[2], k[2] - k[0]);
            dev_c = fmaxf(dev_c, nk - (n0 + u * (n1 - n0)));
        }
    }
    s->lim_dev = dev;
    s->lim_dev_c = dev_c;
    s->lim_shape = 1;
}

int bc_sine_init(const bc_sine_params *p, bc_sine_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (p->p < 1 || !finite_nonneg(p->R) || !finite_pos(p->L) || !finite_pos(p->k_phi) || !finite_pos(p->k_1))
        return BC_ERR_PARAM;
    if (!finite_pos(p->ts) || !finite_nonneg(p->kp) || !finite_nonneg(p->ki) || !finite_pos(p->v_max) ||
        !finite_pos(p->i_s_max) || !finite_pos(p->i_max))
        return BC_ERR_PARAM;
    if (!is_flag(p->speed_limit) || !is_flag(p->decouple) || !is_flag(p->overmod) || !is_flag(p->emf_ff) ||
        !is_flag(p->speed_loop))
        return BC_ERR_PARAM;
    if (!(isfinite(p->advance) && p->advance >= 0.0f && p->advance <= 4.0f)) return BC_ERR_PARAM;
    if (p->limit != BC_SINE_LIMIT_HEX && p->limit != BC_SINE_LIMIT_CIRCLE) return BC_ERR_PARAM;
    if (p->angle != BC_SINE_ANGLE_HALL && p->angle != BC_SINE_ANGLE_ENCODER) return BC_ERR_PARAM;
    if (p->emf_ff) {
        if (p->emf_n < 3 || p->emf_n > BC_SINE_EMF_N_MAX) return BC_ERR_PARAM;
        for (int x = 0; x < 3; ++x) {
            if (p->emf_k[x] == 0) return BC_ERR_PARAM;
            for (int32_t j = 0; j < p->emf_n; ++j) {
                if (!isfinite(p->emf_k[x][j])) return BC_ERR_PARAM;
            }
        }
    }
    if (!finite_pos(p->omega_on) || !finite_nonneg(p->omega_off) || p->omega_off > p->omega_on) return BC_ERR_PARAM;
    if (p->speed_loop && (!finite_nonneg(p->kp_w) || !finite_nonneg(p->ki_w) || !finite_pos(p->tau_max)))
        return BC_ERR_PARAM;
    if (!is_flag(p->flying_start)) return BC_ERR_PARAM;
    if (p->six.ref_torque != 1 || bc_sixstep_init(&p->six, &s->six) != BC_OK) return BC_ERR_PARAM;

    s->hall_p = (bc_hall_params){.f_tick = p->f_tick, .omega_min = p->omega_min, .theta_offset = p->theta_offset,
                                 .mode = p->hall_mode, .pll_edges = p->hall_pll_edges, .table = p->hall_table};
    if (bc_hall_init(&s->hall_p, &s->hall) != BC_OK) return BC_ERR_PARAM;
    s->pi_p = (bc_pi_params){.kp = p->kp, .ki = p->ki, .ts = p->ts,
                             .u_min = -p->v_max, .u_max = p->v_max};
    if (bc_pi_init(&s->pi_p, &s->pi_d) != BC_OK || bc_pi_init(&s->pi_p, &s->pi_q) != BC_OK) return BC_ERR_PARAM;
    s->piw_p.kp = p->speed_loop ? p->kp_w : 0.0f;
    s->piw_p.ki = p->speed_loop ? p->ki_w : 0.0f;
    s->piw_p.ts = p->ts;
    s->piw_p.u_min = p->speed_loop ? -p->tau_max : -1.0f;
    s->piw_p.u_max = p->speed_loop ? p->tau_max : 1.0f;
    if (bc_pi_init(&s->piw_p, &s->pi_w) != BC_OK) return BC_ERR_PARAM;
    s->mode = BC_SINE_MODE_START;
    s->guard_p = (bc_guard_params){.i_max = p->i_max, .v_max = p->v_max};
    if (bc_guard_init(&s->guard_p, &s->guard) != BC_OK) return BC_ERR_PARAM;
    s->six_run = !p->flying_start;
    s->n_quiet = 0;
    s->lim_shape = 0;
    if (p->speed_limit && p->emf_k[0] != 0 && p->emf_k[1] != 0 && p->emf_k[2] != 0) {
        if (p->emf_n < 3 || p->emf_n > BC_SINE_EMF_N_MAX) return BC_ERR_PARAM;
        for (int x = 0; x < 3; ++x) {
            for (int32_t j = 0; j < p->emf_n; ++j) {
                if (!isfinite(p->emf_k[x][j])) return BC_ERR_PARAM;
            }
        }
        lim_tables(p, s);
    }
    return BC_OK;
}

/* k_x(theta) from a table of n points uniform on [0, 2 pi), linear interpolation, periodic. */
static float table_k(const float *k, int32_t n, float theta)
{
    float u = bc_wrap_2pi(theta) * ((float)n / BC_TWO_PI_F);
    int32_t j = (int32_t)u;
    if (j < 0) j = 0;
    if (j > n - 1) j = n - 1;
    float frac = bc_clampf(u - (float)j, 0.0f, 1.0f);
    int32_t j1 = (j + 1 < n) ? j + 1 : 0;
    return k[j] + frac * (k[j1] - k[j]); /* k = k_j + (k_j+1 - k_j) frac */
}

/* Largest k in [0, 1] with max - min of (f + k g) <= lim: each line pair must satisfy |f_xy + k g_xy| <= lim.
 * Assumes |f_xy| <= lim. */
static float hex_scale(const float f[3], const float g[3], float lim)
{
    float k = 1.0f;
    for (int x = 0; x < 3; ++x) {
        int y = (x + 1) % 3;
        float fxy = f[x] - f[y], gxy = g[x] - g[y];
        if (gxy > 0.0f && fxy + gxy > lim) k = fminf(k, (lim - fxy) / gxy);
        if (gxy < 0.0f && fxy + gxy < -lim) k = fminf(k, (-lim - fxy) / gxy);
    }
    return bc_clampf(k, 0.0f, 1.0f);
}

/* Largest k in [0, 1] with |F + k G| <= r (alpha-beta vectors), assuming |F| <= r:
 * |F|^2 + 2 k F.G + k^2 |G|^2 = r^2 solved for its positive root. */
static float circle_scale(bc_ab F, bc_ab G, float r)
{
    float gg = G.alpha * G.alpha + G.beta * G.beta;
    float fg = F.alpha * G.alpha + F.beta * G.beta;
    float ff = F.alpha * F.alpha + F.beta * F.beta;
    if (!(gg > 0.0f)) return 1.0f;
    float sum = ff + 2.0f * fg + gg;
    if (sum <= r * r) return 1.0f;
    float disc = fg * fg - gg * (ff - r * r);
    float k = (-fg + sqrtf(fmaxf(disc, 0.0f))) / gg;
    return isfinite(k) ? bc_clampf(k, 0.0f, 1.0f) : 0.0f;
}

/* Line-to-line spread max - min of three values. */
static float spread(const float v[3]) { return fmaxf(v[0], fmaxf(v[1], v[2])) - fminf(v[0], fminf(v[1], v[2])); }

/* I_s,sat: the largest current amplitude whose peak line-to-line voltage stays within v_dc ((23) with R). */
static float i_sat(const bc_sine_params *p, float v_dc, float omega_e)
{
    float w = fabsf(omega_e);
    float x = w * p->L;                              /* reactance omega_e L */
    float head = v_dc - 2.0f * p->k_phi * w / (float)p->p; /* v_dc - 2 k_phi |omega_m| */
    if (!(head > 0.0f)) return 0.0f;
    float g;
    if (x * BC_SQRT3_F >= p->R) {
        g = 0.5f * BC_SQRT3_F * x + 1.5f * p->R; /* g = sqrt(3)/2 omega_e L + 3/2 R */
    } else {
        g = BC_SQRT3_F * sqrtf(p->R * p->R + x * x); /* g = sqrt(3) |R + j omega_e L| */
    }
    if (!(g > 0.0f)) return p->i_s_max;
    float i = head / g; /* I_s,sat = (v_dc - 2 k_phi |omega_m|) / g */
    return isfinite(i) ? i : p->i_s_max;
}

/* min(cap, I_s,sat) from the shape tables (bc_sine.h, 5.): the largest I in [0, cap] with the steady-state
 * voltage e + I G of currents of sign sgn within the linear range at every tabulated angle. */
static float i_sat_shape(const bc_sine_params *p, const bc_sine_state *s, float v_dc, float omega_e, float sgn,
                         float cap)
{
    const float c_m = cosf(BC_PI_F / (float)BC_SINE_LIM_N); /* a sinusoid's samples reach c_M of its peak */
    float wm = omega_e / (float)p->p;
    float x_e = omega_e * p->L;
    float r_g = sgn * p->R, x_g = sgn * x_e; /* G = s (R i_xy + omega_e L di_xy) */
    /* margins for the peaks between grid points: the back-EMF's deviation above its chords, and that of the
     * drop, a sinusoid of amplitude sqrt(3) |R + j omega_e L| I */
    float m_e = fabsf(wm) * s->lim_dev;
    float m_g = (1.0f - c_m) * BC_SQRT3_F * sqrtf(p->R * p->R + x_e * x_e);
    float best = cap;
    if (p->limit == BC_SINE_LIMIT_HEX) {
        float lim = v_dc - m_e;
        for (int x = 0; x < 3; ++x) {
            const float *kk = s->lim_k[x], *ii = s->lim_i[x], *di = s->lim_di[x];
            for (int32_t j = 0; j < BC_SINE_LIM_N; ++j) {
                float e = wm * kk[j];
                float g = r_g * ii[j] + x_g * di[j];
                if (!(fabsf(e) <= lim)) return 0.0f; /* the back-EMF alone exceeds the limit (or NaN) */
                float num = lim - (g >= 0.0f ? e : -e), den = fabsf(g) + m_g; /* I <= num / den */
                if (num < best * den) best = num / den;
            }
        }
    } else {
        /* the drop of balanced sinusoidal currents is a vector of constant length: only the back-EMF's margin */
        float r = v_dc * BC_INV_SQRT3_F - fabsf(wm) * s->lim_dev_c, r2 = r * r;
        if (!(r > 0.0f)) return 0.0f;
        for (int32_t j = 0; j < BC_SINE_LIM_N; ++j) {
            /* alpha = (v_ab - v_ca) / 3, beta = v_bc / sqrt(3) */
            float ea = wm * (s->lim_k[0][j] - s->lim_k[2][j]) * (1.0f / 3.0f);
            float eb = wm * s->lim_k[1][j] * BC_INV_SQRT3_F;
            float ga = (r_g * (s->lim_i[0][j] - s->lim_i[2][j]) + x_g * (s->lim_di[0][j] - s->lim_di[2][j])) *
                       (1.0f / 3.0f);
            float gb = (r_g * s->lim_i[1][j] + x_g * s->lim_di[1][j]) * BC_INV_SQRT3_F;
            float ee = ea * ea + eb * eb;
            if (!(ee <= r2)) return 0.0f;
            float va = ea + best * ga, vb = eb + best * gb;
            if (va * va + vb * vb > r2) {
                /* |E + I G|^2 = r^2: I = (-E.G + sqrt((E.G)^2 + |G|^2 (r^2 - |E|^2))) / |G|^2 */
                float gg = ga * ga + gb * gb, eg = ea * ga + eb * gb;
                float i = (-eg + sqrtf(fmaxf(eg * eg + gg * (r2 - ee), 0.0f))) / gg;
                best = isfinite(i) ? bc_clampf(i, 0.0f, best) : 0.0f;
            }
        }
    }
    return isfinite(best) ? bc_clampf(best, 0.0f, cap) : 0.0f;
}

/* Enter the start mode: the square-wave controller starts afresh, the d,q integrators are cleared (the hand-off
 * sets them again). */
static void reset_to_start(const bc_sine_params *p, bc_sine_state *s)
{
    s->mode = BC_SINE_MODE_START;
    s->six_run = !p->flying_start;
    s->n_quiet = 0;
    (void)bc_sixstep_init(&p->six, &s->six); /* validated in bc_sine_init */
    bc_pi_reset(&s->pi_p, &s->pi_d, 0.0f);
    bc_pi_reset(&s->pi_p, &s->pi_q, 0.0f);
}

static void go_safe(const bc_sine_params *p, bc_sine_state *s, bc_ctrl_out *out, uint32_t why)
{
    reset_to_start(p, s);
    bc_legs_off(out);
    out->flags |= why | BC_FLAG_SAFE;
}

void bc_sine_step(const bc_sine_params *p, bc_sine_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
    for (int x = 0; x < 3; ++x) {
        out->leg[x].mode = BC_LEG_OFF;
        out->leg[x].duty = 0.0f;
    }
    out->flags = 0u;

    /* 1. safety: the input guard (bc_guard.h), the Hall code, the reference and the encoder angle if used */
    bc_hall_out h;
    bc_hall_step(&s->hall_p, &s->hall, in, &h); /* keeps the edge bookkeeping even when the output is safe */
    float i3[3];
    uint32_t why = bc_guard_step(&s->guard_p, &s->guard, in, i3);
    if (!h.valid) why |= BC_FLAG_HALL_INVALID;
    if (p->angle == BC_SINE_ANGLE_ENCODER && !isfinite(in->theta_enc)) why |= BC_FLAG_BAD_INPUT;
    if (p->speed_loop ? !isfinite(in->omega_ref) : !isfinite(in->ref)) why |= BC_FLAG_BAD_INPUT;
    if (why) {
        go_safe(p, s, out, why);
        return;
    }
    bc_abc i = {i3[0], i3[1], i3[2]};

    /* 2. angle and speed */
    float theta = (p->angle == BC_SINE_ANGLE_ENCODER) ? bc_wrap_2pi(in->theta_enc) : h.theta;
    float omega_e = h.speed_valid ? h.omega_e : 0.0f;
    float omega_m = omega_e / (float)p->p;
    float v_dc = in->v_dc;

    /* 3. mode */
    int was = s->mode;
    if (s->mode == BC_SINE_MODE_START) {
        if (h.speed_valid && fabsf(omega_e) >= p->omega_on) s->mode = BC_SINE_MODE_SINE;
    } else if (!h.speed_valid || fabsf(omega_e) < p->omega_off) {
        reset_to_start(p, s);
    }

    /* measured d,q currents at theta (d axis at theta - pi: sin(theta - pi) = -sin theta) */
    float sd = -sinf(theta), cd = -cosf(theta);
    bc_dq idq = bc_park(bc_clarke(i), sd, cd);

    /* 4. torque reference */
    float tau, tau_u = 0.0f, e_w = 0.0f;
    if (p->speed_loop) {
        e_w = in->omega_ref - omega_m;
        tau_u = bc_pi_output(&s->piw_p, &s->pi_w, e_w, 0.0f); /* tau = PI_w(omega_ref - omega_m) */
        tau = bc_pi_limit(&s->piw_p, tau_u);
    } else {
        tau = in->ref;
    }

    if (s->mode == BC_SINE_MODE_START && !s->six_run) {
        /* flying start: coast until the rotor is known to be slower than omega_on */
        s->n_quiet = h.edge ? 0 : (s->n_quiet < INT32_MAX ? s->n_quiet + 1 : s->n_quiet);
        float quiet = (float)s->n_quiet * p->ts;
        if ((h.speed_valid && fabsf(omega_e) < p->omega_on) || quiet * p->omega_on >= BC_PI_F / 3.0f) s->six_run = 1;
        if (p->speed_loop) bc_pi_update(&s->piw_p, &s->pi_w, e_w, tau_u, 0.0f);
    }
    if (s->mode == BC_SINE_MODE_START && s->six_run) {
        /* square-wave start: bc_sixstep with the torque limited to a square-wave current of I_N */
        float tau_lim = p->six.k_e * (0.5f * BC_SQRT3_F) * p->i_s_max;
        bc_ctrl_in in6 = *in;
        in6.ref = bc_clampf(tau, -tau_lim, tau_lim);
        bc_sixstep_step(&p->six, &s->six, &in6, out);
        if (p->speed_loop) bc_pi_update(&s->piw_p, &s->pi_w, e_w, tau_u, in6.ref);
        for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
        out->diag[2] = in6.ref / (1.5f * p->k_1);
    }
    out->diag[0] = idq.d;
    out->diag[1] = idq.q;
    out->diag[5] = theta;
    out->diag[6] = omega_e;
    out->diag[7] = (float)s->mode;
    if (s->mode == BC_SINE_MODE_START) return;

    /* 5. current references (45), (8), I_s,sat from the shape tables or (23) with R */
    float i_lim = p->i_s_max;
    if (p->speed_limit) {
        i_lim = s->lim_shape ? i_sat_shape(p, s, v_dc, omega_e, tau < 0.0f ? -1.0f : 1.0f, i_lim)
                             : fminf(i_lim, i_sat(p, v_dc, omega_e));
    }
    float iq_ref = bc_clampf(tau / (1.5f * p->k_1), -i_lim, i_lim); /* i_q,ref = tau / (1.5 k_1) */
    float id_ref = 0.0f;
    if (p->speed_loop) bc_pi_update(&s->piw_p, &s->pi_w, e_w, tau_u, 1.5f * p->k_1 * iq_ref);

    /* 6. current PIs with the R-L feed-forward */
    float ff_d = 0.0f, ff_q = 0.0f;
    if (p->decouple) {
        /* the rotational voltage from the measured currents: it cancels the plant's d,q cross-coupling, so each
         * PI sees R + s L (a feed-forward from the references would leave it in the error dynamics) */
        ff_d = p->R * id_ref - omega_e * p->L * idq.q; /* ff_d = R i_d,ref - omega_e L i_q */
        ff_q = p->R * iq_ref + omega_e * p->L * idq.d; /* ff_q = R i_q,ref + omega_e L i_d */
    }
    if (was == BC_SINE_MODE_START) {
        /* bumpless hand-off: integrators from the voltage the present state needs */
        float e_q1 = omega_m * p->k_1; /* back-EMF fundamental on q */
        float x_d = p->R * idq.d - omega_e * p->L * idq.q - ff_d;
        float x_q = p->R * idq.q + omega_e * p->L * idq.d + e_q1 - ff_q - (p->emf_ff ? e_q1 : 0.0f);
        bc_pi_reset(&s->pi_p, &s->pi_d, x_d);
        bc_pi_reset(&s->pi_p, &s->pi_q, x_q);
    }
    float e_d = id_ref - idq.d, e_q = iq_ref - idq.q;
    bc_dq u;
    u.d = bc_pi_output(&s->pi_p, &s->pi_d, e_d, ff_d); /* u_d = k_p e_d + x_d + ff_d */
    u.q = bc_pi_output(&s->pi_p, &s->pi_q, e_q, ff_q); /* u_q = k_p e_q + x_q + ff_q */

    /* 7. voltage angle advanced by the loop delay: theta_v = theta + advance Omega_e T_s */
    float theta_v = bc_wrap_2pi(theta + p->advance * omega_e * p->ts);
    float sv = -sinf(theta_v), cv = -cosf(theta_v);
    /* the two axes' voltages separately: the limit fits the d axis first (d-axis priority) */
    bc_abc g_d = bc_clarke_inv(bc_park_inv((bc_dq){u.d, 0.0f}, sv, cv));
    bc_abc g_q = bc_clarke_inv(bc_park_inv((bc_dq){0.0f, u.q}, sv, cv));
    float gd[3] = {g_d.a, g_d.b, g_d.c}, gq[3] = {g_q.a, g_q.b, g_q.c};

    /* 8. back-EMF feed-forward f_x = omega_m k_x(theta_v - x 2 pi/3) */
    float f[3] = {0.0f, 0.0f, 0.0f};
    if (p->emf_ff) {
        for (int x = 0; x < 3; ++x) {
            f[x] = omega_m * table_k(p->emf_k[x], p->emf_n, theta_v - (float)x * (BC_TWO_PI_F / 3.0f));
        }
    }

    /* 9. linear-modulation limit: v = f + k_d u_d + k_q u_q, d axis first */
    float k_d = 1.0f, k_q = 1.0f;
    if (!p->overmod) {
        if (p->limit == BC_SINE_LIMIT_HEX) {
            float sf = spread(f);
            if (sf > v_dc) {
                for (int x = 0; x < 3; ++x) f[x] *= v_dc / sf;
            }
            k_d = hex_scale(f, gd, v_dc);
            float f2[3] = {f[0] + k_d * gd[0], f[1] + k_d * gd[1], f[2] + k_d * gd[2]};
            k_q = hex_scale(f2, gq, v_dc);
        } else {
            float r = v_dc * BC_INV_SQRT3_F;
            bc_abc fa = {f[0], f[1], f[2]};
            bc_ab F = bc_clarke(fa), Gd = bc_clarke(g_d), Gq = bc_clarke(g_q);
            float nf = sqrtf(F.alpha * F.alpha + F.beta * F.beta);
            if (nf > r) {
                for (int x = 0; x < 3; ++x) f[x] *= r / nf;
                F = bc_clarke((bc_abc){f[0], f[1], f[2]});
            }
            k_d = circle_scale(F, Gd, r);
            bc_ab F2 = {F.alpha + k_d * Gd.alpha, F.beta + k_d * Gd.beta};
            k_q = circle_scale(F2, Gq, r);
        }
    }
    bc_abc v = {f[0] + k_d * gd[0] + k_q * gq[0], f[1] + k_d * gd[1] + k_q * gq[1],
                f[2] + k_d * gd[2] + k_q * gq[2]};

    /* 10. SVM */
    float duty[3];
    int clipped = bc_svm(v, v_dc, duty);
    bc_dq ur = {k_d * u.d, k_q * u.q};
    if (clipped && p->overmod) {
        /* realised voltage from the clipped duties, minus the feed-forward, in the frame of theta_v */
        bc_abc va = {duty[0] * v_dc - f[0], duty[1] * v_dc - f[1], duty[2] * v_dc - f[2]};
        ur = bc_park(bc_clarke(va), sv, cv);
    }
    bc_pi_update(&s->pi_p, &s->pi_d, e_d, u.d, ur.d);
    bc_pi_update(&s->pi_p, &s->pi_q, e_q, u.q, ur.q);
    if (k_d < 1.0f || k_q < 1.0f || clipped) out->flags |= BC_FLAG_SATURATED;

    for (int x = 0; x < 3; ++x) {
        out->leg[x].mode = BC_LEG_PWM;
        out->leg[x].duty = duty[x];
    }
    bc_dq vdq = bc_park(bc_clarke(v), sv, cv);
    out->diag[2] = iq_ref;
    out->diag[3] = vdq.d;
    out->diag[4] = vdq.q;
}

/* bc_sine.c - sinusoidal current supply with square-wave start. Laws and their order in bc_sine.h. */
#include "bldc/bc_sine.h"
#include "bldc/bc_rest.h"

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

/* k(theta) of a table of n points uniform on [0, 2 pi), linear, periodic (table_k without fmodf, for bc_sine_init). */
static float lim_pwl(const float *k, int32_t n, float theta)
{
    float u = theta * ((float)n / BC_TWO_PI_F);
    u -= (float)n * floorf(u / (float)n);
    int32_t j = (int32_t)u;
    if (j < 0) j = 0;
    if (j > n - 1) j = n - 1; /* u rounded to n: the end of the last segment */
    float fr = bc_clampf(u - (float)j, 0.0f, 1.0f);
    int32_t j1 = j + 1 < n ? j + 1 : 0;
    return k[j] + fr * (k[j1] - k[j]);
}

/* Line values k_xy (pairs ab, bc, ca) of the back-EMF shape at the angle th. */
static void lim_k(const bc_sine_params *p, float th, float k[3])
{
    float kx[3];
    for (int x = 0; x < 3; ++x) kx[x] = lim_pwl(p->emf_k[x], p->emf_n, th - (float)x * (BC_TWO_PI_F / 3.0f));
    for (int x = 0; x < 3; ++x) k[x] = kx[x] - kx[(x + 1) % 3];
}

/* Upper envelope of the M lines c_g + S_g J of one row of the hexagon's table, at the nodes J_m = (m - N_J) h,
 * m = 0 .. 2 N_J: out[m] = max_g (c_g + S_g J_m), c_g = a K_g, S_g = sqrt(3) (R cos(phi_g) - x_e sin(phi_g)),
 * phi_g = 2 pi g / M.
 *
 * S_g = -A cos(phi_g - phi_0) (A = sqrt(3) |R + j x_e|, phi_0 = pi - atan2(x_e, R)) grows with the distance of
 * phi_g from phi_0, so the lines taken alternately from both sides of phi_0 (the nearer first) come in increasing
 * slope, without sorting; the cosine follows each side by rotation (a relative error of about 1e-5 after M/2
 * steps, covered by lim_table's pad). The convex hull trick keeps the lines of the envelope (the top line goes when
 * the new one overtakes its predecessor no later than it does; of equal slopes, or unequal by rounding, the larger
 * intercept stays), and the nodes, in increasing J, walk along them: O(M + N_J) per row instead of M (2 N_J + 1).
 * Scratch: the slopes hs and groups hg of the hull's lines, M each. */
static void lim_row_hex(const float *kk, float a, float R, float x_e, float h, float *out, float *hs, uint8_t *hg)
{
    enum { M = BC_SINE_LIM_N, NQ = 2 * BC_SINE_LIM_J + 1 };
    const float d = BC_TWO_PI_F / (float)M, cd = cosf(d), sd = sinf(d);
    float amp = BC_SQRT3_F * sqrtf(R * R + x_e * x_e);
    if (!(amp > 0.0f)) { /* no drop (R = 0 at standstill): every slope is 0 */
        float c = -3.0e38f;
        for (int32_t g = 0; g < M; ++g) c = fmaxf(c, a * kk[g]);
        for (int32_t m = 0; m < NQ; ++m) out[m] = c;
        return;
    }
    /* phi_0 at the grid position t: the left side starts at g_l = floor(t), the right one at g_l + 1 */
    float t = (BC_PI_F - atan2f(x_e, R)) / d;
    t -= (float)M * floorf(t / (float)M);
    int32_t gl = (int32_t)t;
    if (gl < 0 || gl >= M) gl = 0;
    int32_t gr = gl + 1 < M ? gl + 1 : 0;
    float fl = t - (float)gl; /* distances in steps: fl + i on the left, 1 - fl + i on the right */
    float cl = cosf(fl * d), sl = sinf(fl * d), cr = cosf((1.0f - fl) * d), sr = sinf((1.0f - fl) * d);
    int left = fl <= 0.5f;
    int32_t size = 0;
    for (int32_t r = 0; r < M; ++r) {
        int32_t g;
        float sg, c2;
        if (left) {
            g = gl;
            sg = -amp * cl;
            gl = gl > 0 ? gl - 1 : M - 1;
            c2 = cl * cd - sl * sd; /* one step further from phi_0 */
            sl = sl * cd + cl * sd;
            cl = c2;
        } else {
            g = gr;
            sg = -amp * cr;
            gr = gr + 1 < M ? gr + 1 : 0;
            c2 = cr * cd - sr * sd;
            sr = sr * cd + cr * sd;
            cr = c2;
        }
        left = !left;
        float c = a * kk[g];
        int skip = 0;
        while (size > 0 && !(sg > hs[size - 1])) { /* equal slopes: the larger intercept stays */
            if (c <= a * kk[hg[size - 1]]) {
                skip = 1;
                break;
            }
            --size;
        }
        if (skip) continue;
        /* the top line b goes when the new line overtakes its predecessor q no later than b does:
         * (c_q - c) / (S - S_q) <= (c_q - c_b) / (S_b - S_q) */
        while (size >= 2) {
            float cq = a * kk[hg[size - 2]], sq = hs[size - 2], cb = a * kk[hg[size - 1]], sb = hs[size - 1];
            if (!((cq - c) * (sb - sq) <= (cq - cb) * (sg - sq))) break;
            --size;
        }
        hs[size] = sg;
        hg[size] = (uint8_t)g;
        ++size;
    }
    int32_t k = 0;
    float ck = a * kk[hg[0]];
    for (int32_t m = 0; m < NQ; ++m) {
        float J = (float)(m - BC_SINE_LIM_J) * h;
        while (k + 1 < size) {
            float c1 = a * kk[hg[k + 1]];
            if (!(c1 + hs[k + 1] * J >= ck + hs[k] * J)) break;
            ++k;
            ck = c1;
        }
        out[m] = ck + hs[k] * J;
    }
}

/* Speed of node n of the speed limit's table (bc_sine.h, 5.): k = n - N_W/2 cells from 0, N_F fine ones of
 * w_1 / N_F up to w_1 = BC_SINE_LIM_W1 w_top, then N_W/2 - N_F coarse ones up to w_top. */
static float lim_node_w(int32_t n, float w_top)
{
    const int32_t nf = BC_SINE_LIM_WF, nc = BC_SINE_LIM_W / 2 - BC_SINE_LIM_WF;
    const float w1 = BC_SINE_LIM_W1 * w_top;
    int32_t k = n - BC_SINE_LIM_W / 2, ak = k < 0 ? -k : k;
    float w = ak <= nf ? (float)ak * (w1 / (float)nf) : w1 + (float)(ak - nf) * ((w_top - w1) / (float)nc);
    return k < 0 ? -w : w;
}

/* Table of the shape-aware speed limit (bc_sine.h, 5.): v_req(omega_n, J_m) as b_n + q_n tab[n][m], rounded up.
 *
 * Hexagon: the line of the pair xy at theta_j is e + J G with e = omega_m k_xy(theta_j) and, since i_xy = sqrt(3)
 * cos(phi) and di_xy/dtheta = -sqrt(3) sin(phi) with phi = theta_j - (2x + 1) pi/3, G = S(phi) = sqrt(3) (R cos(phi)
 * - omega_e L sin(phi)); -(e + J G) has the slope S(phi + pi). The 6 M lines of the |.| thus fall into M groups
 * of equal slope S_g = S(2 pi g / M), of which only the largest intercept counts:
 *
 *     v_req - m_e - |J| m_g = max_g (|omega_m| K_g + J S_g)     (omega_m >= 0; K_{g + M/2} for omega_m < 0)
 *     K_g = max(k_xy(theta_j) of the lines e + J G of group g, -k_xy(theta_j) of the lines -(e + J G) of group g)
 *
 * K_g from one pass over the M angles, then each row's envelope by lim_row_hex. If K_{-g} = K_g (a shape symmetric
 * about the zero of its fundamental: all but lu-4kw's), v_req(-omega_e, -J) = v_req(omega_e, J) (the substitution
 * g -> M/2 - g), and the rows of omega_e < 0 are those of omega_e > 0 read backwards in J.
 *
 * Circle: |E_j + J G_j|^2 = |E_j|^2 + 2 J E_j.G_j + J^2 |R + j omega_e L|^2 (G_j = R u_j + omega_e L du_j/dtheta,
 * u_j = (sin theta_j, -cos theta_j) the current's alpha-beta direction: |u_j| = |du_j/dtheta| = 1, orthogonal), so
 * the largest over j is that of M lines in J, each evaluated at every node, then one square root.
 *
 * Stack: about 1.3 kB (Cortex-M4, -Os; M = 96, N_J = 24). */
static void lim_table(const bc_sine_params *p, bc_sine_state *s)
{
    enum { M = BC_SINE_LIM_N, NJ = BC_SINE_LIM_J, NQ = 2 * BC_SINE_LIM_J + 1, NW = BC_SINE_LIM_W };
    const int hex = p->limit == BC_SINE_LIMIT_HEX;
    const float d = BC_TWO_PI_F / (float)M;
    float scr[2][M]; /* hexagon: K_g and the hull's slopes; circle: k_alpha, k_beta at theta_j */
    float row[NQ];   /* a row's maxima */
    uint8_t hg[M];   /* hexagon: the hull's groups */
    for (int32_t g = 0; g < M; ++g) scr[0][g] = -3.0e38f;

    /* one pass over the grid angles: dev (the largest deviation of a line shape k_xy from the chord between
     * neighbouring grid angles), dev_c (the excess of |k_alpha,beta| over the chord of its grid values), both sampled
     * at every table spacing or finer; kmax, kmax_c (the largest |k_xy|, |k_alpha,beta| at the grid angles); K_g */
    int32_t n_sub = 2 * (p->emf_n / M + 1);
    float dev = 0.0f, dev_c = 0.0f, kmax = 0.0f, kmax_c = 0.0f;
    float k0[3], k1[3], k[3];
    lim_k(p, 0.0f, k0);
    for (int32_t j = 0; j < M; ++j) {
        lim_k(p, (float)((j + 1) % M) * d, k1);
        float n0 = lim_norm(k0[0], k0[1], k0[2]), n1 = lim_norm(k1[0], k1[1], k1[2]);
        kmax_c = fmaxf(kmax_c, n0);
        for (int32_t q = 1; q < n_sub; ++q) {
            float u = (float)q / (float)n_sub;
            lim_k(p, ((float)j + u) * d, k);
            for (int x = 0; x < 3; ++x) dev = fmaxf(dev, fabsf(k[x] - (k0[x] + u * (k1[x] - k0[x]))));
            dev_c = fmaxf(dev_c, lim_norm(k[0], k[1], k[2]) - (n0 + u * (n1 - n0)));
        }
        if (hex) {
            for (int x = 0; x < 3; ++x) {
                int32_t g = (j - (2 * x + 1) * (M / 6) + M) % M; /* e + J G in group g, -(e + J G) in g + M/2 */
                int32_t g2 = (g + M / 2) % M;
                kmax = fmaxf(kmax, fabsf(k0[x]));
                scr[0][g] = fmaxf(scr[0][g], k0[x]);
                scr[0][g2] = fmaxf(scr[0][g2], -k0[x]);
            }
        } else {
            scr[0][j] = (k0[0] - k0[2]) * (1.0f / 3.0f); /* alpha = (k_ab - k_ca) / 3, beta = k_bc / sqrt(3) */
            scr[1][j] = k0[1] * BC_INV_SQRT3_F;
        }
        for (int x = 0; x < 3; ++x) k0[x] = k1[x];
    }
    /* v_req(omega_e, 0) = |omega_m| K_e; w_top = p v_max / K_e */
    float k_e = hex ? kmax + dev : BC_SQRT3_F * (kmax_c + dev_c);
    float w_top = (float)p->p * p->v_max / k_e;
    float c_m = cosf(BC_PI_F / (float)M); /* a sinusoid's samples reach c_M of its peak */
    if (!(k_e > 0.0f) || !isfinite(w_top)) return; /* no back-EMF: (23) with R */
    float h = p->i_s_max / (float)NJ;

    /* hexagon: K_{-g} = K_g to rounding makes the rows of omega_e < 0 mirror those of omega_e > 0; K_g then takes
     * the larger of the two (never lower) */
    int mirror = 0;
    if (hex) {
        float asym = 0.0f;
        for (int32_t g = 1; g < M; ++g) asym = fmaxf(asym, fabsf(scr[0][g] - scr[0][M - g]));
        mirror = asym <= 1e-6f * k_e;
        if (mirror) {
            for (int32_t g = 1; g < M / 2; ++g) scr[0][g] = scr[0][M - g] = fmaxf(scr[0][g], scr[0][M - g]);
        }
    }
    for (int32_t n = mirror ? NW / 2 : 0; n <= NW; ++n) {
        float we = lim_node_w(n, w_top), wm = we / (float)p->p, awm = fabsf(wm), x_e = we * p->L;
        float zz = p->R * p->R + x_e * x_e;
        if (hex) {
            if (wm < 0.0f) { /* K_{g + M/2}: the halves swapped for the row, then back */
                for (int32_t g = 0; g < M / 2; ++g) {
                    float tmp = scr[0][g];
                    scr[0][g] = scr[0][g + M / 2];
                    scr[0][g + M / 2] = tmp;
                }
            }
            lim_row_hex(scr[0], awm, p->R, x_e, h, row, scr[1], hg);
            if (wm < 0.0f) {
                for (int32_t g = 0; g < M / 2; ++g) {
                    float tmp = scr[0][g];
                    scr[0][g] = scr[0][g + M / 2];
                    scr[0][g + M / 2] = tmp;
                }
            }
        } else {
            float sj = 0.0f, cj = 1.0f, cd = cosf(d), sd = sinf(d); /* sin, cos of theta_j by rotation */
            for (int32_t m = 0; m < NQ; ++m) row[m] = -3.0e38f;
            for (int32_t j = 0; j < M; ++j) {
                float ea = wm * scr[0][j], eb = wm * scr[1][j];
                float ga = p->R * sj + x_e * cj, gb = -p->R * cj + x_e * sj; /* G_j = R u_j + omega_e L du_j */
                float c = ea * ea + eb * eb, sl = 2.0f * (ea * ga + eb * gb);  /* |E_j|^2 + J 2 E_j.G_j */
                for (int32_t m = 0; m < NQ; ++m) {
                    float v = c + (float)(m - NJ) * h * sl;
                    row[m] = v > row[m] ? v : row[m]; /* finite values: no fmaxf call */
                }
                float c2 = cj * cd - sj * sd;
                sj = sj * cd + cj * sd;
                cj = c2;
            }
        }
        float m_g = (1.0f - c_m) * BC_SQRT3_F * sqrtf(zz);
        float v_lo = 3.0e38f, v_up = 0.0f;
        for (int32_t m = 0; m < NQ; ++m) {
            float J = (float)(m - NJ) * h;
            if (hex) {
                row[m] += awm * dev + fabsf(J) * m_g; /* + m_e + |J| m_g */
            } else {
                /* sqrt(3) (|E + J G| + m_c) */
                row[m] = BC_SQRT3_F * (sqrtf(fmaxf(row[m] + J * J * zz, 0.0f)) + awm * dev_c);
            }
            row[m] = fmaxf(row[m], 0.0f);
            v_lo = fminf(v_lo, row[m]);
            v_up = fmaxf(v_up, row[m]);
        }
        /* rounding pad: the float sums (1e-6 of the largest value) and the rotations that follow cos(phi) (2e-5 of
         * the drop sqrt(3) |R + j omega_e L| i_s_max); then counts of q_n above b_n, rounded up: the stored
         * b_n + q_n tab lies between v_req + pad and v_req + pad + q_n */
        float pad = 1e-6f * v_up + 2e-5f * BC_SQRT3_F * sqrtf(zz) * p->i_s_max;
        float qn = fmaxf(v_up + pad - v_lo, 1e-30f) / 65000.0f, inv = 1.0f / qn;
        for (int32_t m = 0; m < NQ; ++m) {
            s->lim_tab[n][m] = (uint16_t)((uint32_t)fminf((row[m] + pad - v_lo) * inv, 65000.0f) + 1u);
        }
        s->lim_base[n] = v_lo;
        s->lim_q[n] = qn;
    }
    if (mirror) {
        for (int32_t n = 0; n < NW / 2; ++n) {
            for (int32_t m = 0; m < NQ; ++m) s->lim_tab[n][m] = s->lim_tab[NW - n][NQ - 1 - m];
            s->lim_base[n] = s->lim_base[NW - n];
            s->lim_q[n] = s->lim_q[NW - n];
        }
    }
    s->lim_w_top = w_top;
    s->lim_inv_df = (float)BC_SINE_LIM_WF / (BC_SINE_LIM_W1 * w_top);
    s->lim_inv_dc = (float)(NW / 2 - BC_SINE_LIM_WF) / ((1.0f - BC_SINE_LIM_W1) * w_top);
    s->lim_h = h;
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
    /* a current limit the over-current trip cuts off is a misconfiguration: i_s_max <= i_max */
    if (p->i_s_max > p->i_max) return BC_ERR_PARAM;
    if (!is_flag(p->speed_limit) || !is_flag(p->decouple) || !is_flag(p->overmod) || !is_flag(p->emf_ff) ||
        !is_flag(p->speed_loop))
        return BC_ERR_PARAM;
    if (!(isfinite(p->advance) && p->advance >= 0.0f && p->advance <= 4.0f)) return BC_ERR_PARAM;
    if (p->limit != BC_SINE_LIMIT_HEX && p->limit != BC_SINE_LIMIT_CIRCLE) return BC_ERR_PARAM;
    if (p->angle != BC_SINE_ANGLE_HALL && p->angle != BC_SINE_ANGLE_ENCODER && p->angle != BC_SINE_ANGLE_OBSERVER)
        return BC_ERR_PARAM;
    if (p->angle == BC_SINE_ANGLE_OBSERVER) {
        if (p->observer == BC_SINE_OBS_FLUX) {
            if (p->fobs.ts != p->ts || bc_fluxobs_init(&p->fobs, &s->fobs) != BC_OK) return BC_ERR_PARAM;
        } else if (p->observer == BC_SINE_OBS_REDUCED) {
            if (p->robs.ts != p->ts || bc_redobs_init(&p->robs, &s->robs) != BC_OK) return BC_ERR_PARAM;
        } else {
            return BC_ERR_PARAM;
        }
        if (!finite_pos(p->if_current) || p->if_current > p->i_s_max || !finite_pos(p->if_align_current) ||
            p->if_align_current > p->i_s_max || !finite_nonneg(p->if_align) ||
            !finite_pos(p->if_accel) || !finite_pos(p->if_accel_min) || p->if_accel_min > p->if_accel ||
            !finite_pos(p->if_hold) || !finite_pos(p->lock_time) ||
            !finite_pos(p->lock_tol) || p->lock_tol >= 1.0f || !finite_nonneg(p->restart_wait) || !finite_nonneg(p->if_damp) ||
            !finite_nonneg(p->t_dead) || p->t_dead >= p->ts || !is_flag(p->if_r_est) || !is_flag(p->if_psi_est) ||
            !is_flag(p->zc_catch) || !is_flag(p->catch_pulse))
            return BC_ERR_PARAM;
    }
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
    s->sl_phase = BC_SINE_SL_IDLE;
    s->sl_dir = 1;
    s->if_theta = s->if_omega = s->sl_t = s->n_lock = s->omega_f = s->rho_f = s->if_t = 0.0f;
    s->u_hist[0][0] = s->u_hist[0][1] = s->u_hist[1][0] = s->u_hist[1][1] = 0.0f;
    s->u_ok[0] = s->u_ok[1] = 0;
    s->n_restart = 0u;
    s->if_trust = 0;
    s->r_obs = p->observer == BC_SINE_OBS_REDUCED ? p->robs.R : p->fobs.R;
    s->psi_obs = p->observer == BC_SINE_OBS_REDUCED ? p->robs.psi : p->fobs.psi;
    s->flux_f = s->n_psi = 0.0f;
    s->psi_adapt = s->psi_done = 0;
    s->n_zero = s->z_flux = s->z_w = s->z_n = s->z_tgt = s->z_u[0] = s->z_u[1] = s->n_zc = 0.0f;
    s->r_ui = s->r_ii = 0.0f;
    s->n_catch = s->w_rev = s->if_wmin = s->if_tb = s->if_tr = 0.0f;
    s->caught = 0;
    s->fc_k = s->fc_on = s->fc_seed = 0;
    s->fc_tau = s->fc_i[0] = s->fc_i[1] = s->fc_i2[0] = s->fc_i2[1] = 0.0f;
    s->derate_on = p->derate.enabled[0] != 0 || p->derate.enabled[1] != 0;
    s->derate_f = 1.0f;
    if (s->derate_on && bc_derate_init(&p->derate, &s->derate) != BC_OK) return BC_ERR_PARAM;
    s->rest_on = p->rest.i_inj != 0.0f;
    if (s->rest_on && (bc_rest_init(&p->rest, &s->rest) != BC_OK || p->rest.i_inj > p->i_s_max)) return BC_ERR_PARAM;
    s->lim_shape = 0;
    if (p->speed_limit && p->emf_k[0] != 0 && p->emf_k[1] != 0 && p->emf_k[2] != 0) {
        if (p->emf_n < 3 || p->emf_n > BC_SINE_EMF_N_MAX) return BC_ERR_PARAM;
        for (int x = 0; x < 3; ++x) {
            for (int32_t j = 0; j < p->emf_n; ++j) {
                if (!isfinite(p->emf_k[x][j])) return BC_ERR_PARAM;
            }
        }
        lim_table(p, s);
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

/* V(i) of the speed limit (bc_sine.h, 5.): the table at column i interpolated along omega_e, V = b + c0 t0[i] +
 * c1 t1[i]. */
static float lim_v(const uint16_t *t0, const uint16_t *t1, float b, float c0, float c1, int32_t i)
{
    return b + c0 * (float)t0[i] + c1 * (float)t1[i];
}

/* min(cap, I_s,sat) from the table (bc_sine.h, 5.): the largest I with V(s I) <= v_dc, linear between current
 * nodes. Safe on any input: a NaN or out-of-range speed and a NaN or non-positive bus give 0. */
static float i_sat_table(const bc_sine_state *s, float v_dc, float omega_e, float sgn, float cap)
{
    float aw = fabsf(omega_e), w1 = BC_SINE_LIM_W1 * s->lim_w_top;
    if (!(aw < s->lim_w_top)) return 0.0f; /* |omega_e| >= w_top (or NaN): the back-EMF alone exceeds v_max */
    /* the position among the nodes: the fine cells up to w_1, the coarse ones above */
    float pos = aw < w1 ? aw * s->lim_inv_df : (float)BC_SINE_LIM_WF + (aw - w1) * s->lim_inv_dc;
    float u = (float)(BC_SINE_LIM_W / 2) + (omega_e < 0.0f ? -pos : pos);
    int32_t n = (int32_t)u;
    if (n < 0) n = 0;
    if (n > BC_SINE_LIM_W - 1) n = BC_SINE_LIM_W - 1;
    float a = bc_clampf(u - (float)n, 0.0f, 1.0f);
    const uint16_t *t0 = &s->lim_tab[n][BC_SINE_LIM_J], *t1 = &s->lim_tab[n + 1][BC_SINE_LIM_J];
    /* V = (1 - a) (b_n + q_n t0) + a (b_n+1 + q_n+1 t1) */
    float b = (1.0f - a) * s->lim_base[n] + a * s->lim_base[n + 1];
    float c0 = (1.0f - a) * s->lim_q[n], c1 = a * s->lim_q[n + 1];
    int32_t d = sgn < 0.0f ? -1 : 1; /* the side of the torque's sign */
    float v_lo = lim_v(t0, t1, b, c0, c1, 0);
    if (!(v_lo <= v_dc)) return 0.0f; /* the back-EMF alone exceeds v_dc (or v_dc is NaN) */
    float v_hi = lim_v(t0, t1, b, c0, c1, d * BC_SINE_LIM_J);
    if (v_hi <= v_dc) return cap;
    int32_t lo = 0, hi = BC_SINE_LIM_J; /* V(lo) <= v_dc < V(hi) */
    while (hi - lo > 1) {
        int32_t mid = (lo + hi) / 2;
        float v = lim_v(t0, t1, b, c0, c1, d * mid);
        if (v <= v_dc) {
            lo = mid;
            v_lo = v;
        } else {
            hi = mid;
            v_hi = v;
        }
    }
    float i = s->lim_h * ((float)lo + (v_dc - v_lo) / (v_hi - v_lo)); /* I = h (m + (v_dc - V(m)) / (V(m+1) - V(m))) */
    return bc_clampf(i, 0.0f, cap);
}

float bc_sine_i_limit(const bc_sine_params *p, const bc_sine_state *s, float v_dc, float omega_e, float sgn)
{
    if (!p->speed_limit) return p->i_s_max;
    if (s->lim_shape) return i_sat_table(s, v_dc, omega_e, sgn, p->i_s_max);
    return bc_clampf(i_sat(p, v_dc, omega_e), 0.0f, p->i_s_max);
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
    s->sl_phase = BC_SINE_SL_IDLE;
    s->sl_t = 0.0f;
    s->n_lock = 0.0f;
    s->omega_f = 0.0f;
    s->u_ok[0] = s->u_ok[1] = 0;
    if (s->rest_on) bc_rest_restart(&s->rest);
}

static void go_safe(const bc_sine_params *p, bc_sine_state *s, bc_ctrl_out *out, uint32_t why)
{
    reset_to_start(p, s);
    bc_legs_off(out);
    out->flags |= why | BC_FLAG_SAFE;
}

/* Steps 6 to 10 (bc_sine.h): the current PIs on (id_ref, iq_ref) in the frame of theta, the voltage angle, the
 * back-EMF feed-forward if emf_ff, the linear-modulation limit and SVM; with handoff the integrators are set first
 * (bumpless hand-off). Writes the legs, BC_FLAG_SATURATED, diag 2 to 4. */
static void current_loops(const bc_sine_params *p, bc_sine_state *s, bc_dq idq, float id_ref, float iq_ref,
                          float theta, float omega_e, float v_dc, int32_t emf_ff, int handoff, bc_ctrl_out *out)
{
    float omega_m = omega_e / (float)p->p;
    /* 6. current PIs with the R-L feed-forward */
    float ff_d = 0.0f, ff_q = 0.0f;
    if (p->decouple) {
        /* the rotational voltage from the measured currents: it cancels the plant's d,q cross-coupling, so each
         * PI sees R + s L (a feed-forward from the references would leave it in the error dynamics) */
        ff_d = p->R * id_ref - omega_e * p->L * idq.q; /* ff_d = R i_d,ref - omega_e L i_q */
        ff_q = p->R * iq_ref + omega_e * p->L * idq.d; /* ff_q = R i_q,ref + omega_e L i_d */
    }
    if (handoff) {
        /* bumpless hand-off: integrators from the voltage the present state needs */
        float e_q1 = omega_m * p->k_1; /* back-EMF fundamental on q */
        float x_d = p->R * idq.d - omega_e * p->L * idq.q - ff_d;
        float x_q = p->R * idq.q + omega_e * p->L * idq.d + e_q1 - ff_q - (emf_ff ? e_q1 : 0.0f);
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
    if (emf_ff) {
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

/* The observer chosen by p->observer: reset (seed) and one step. */
static void obs_reset(const bc_sine_params *p, bc_sine_state *s, float theta_e, float omega_e, bc_ab i)
{
    if (p->observer == BC_SINE_OBS_FLUX) {
        bc_fluxobs_params fp = p->fobs;
        fp.psi = s->psi_obs; /* seeded on the circle in use */
        bc_fluxobs_reset(&fp, &s->fobs, theta_e, omega_e, i);
    } else {
        bc_redobs_reset(&p->robs, &s->robs, theta_e, omega_e, i);
    }
}

static void obs_run(const bc_sine_params *p, bc_sine_state *s, const bc_obs_in *in, bc_obs_out *o)
{
    if (p->observer == BC_SINE_OBS_FLUX) {
        bc_fluxobs_params fp = p->fobs;
        fp.R = s->r_obs; /* the configured R, or the one measured in ALIGN (if_r_est) */
        fp.psi = s->psi_obs; /* the configured psi_f, or the one estimated at omega_on (if_psi_est) */
        bc_fluxobs_step(&fp, &s->fobs, in, o);
    } else {
        bc_redobs_params rp = p->robs;
        rp.R = s->r_obs;
        bc_redobs_step(&rp, &s->robs, in, o);
    }
}

/* The configured resistance and flux linkage of the observer chosen. */
static float obs_r(const bc_sine_params *p) { return p->observer == BC_SINE_OBS_FLUX ? p->fobs.R : p->robs.R; }
static float obs_psi(const bc_sine_params *p) { return p->observer == BC_SINE_OBS_FLUX ? p->fobs.psi : p->robs.psi; }

/* Legs off in the sensorless start (IDLE, WAIT): the voltage of the coming samples is not known. */
static void sl_off(bc_sine_state *s, bc_ctrl_out *out)
{
    bc_legs_off(out);
    s->u_ok[0] = 0;
}

/* Failed start or lost lock: legs off, the flags, WAIT. */
static void sl_desync(const bc_sine_params *p, bc_sine_state *s, bc_ctrl_out *out, uint32_t why)
{
    reset_to_start(p, s);
    s->sl_phase = BC_SINE_SL_WAIT;
    s->n_restart++;
    sl_off(s, out);
    out->flags |= why | BC_FLAG_DESYNC;
}

/* The torque reference: the speed PI's limited output on omega_ref - omega_m (its unlimited output and error in
 * *tau_u, *e_w for the PI's update once the current is known), or the input's torque reference. */
static float torque_ref(const bc_sine_params *p, bc_sine_state *s, const bc_ctrl_in *in, float omega_m, float *tau_u,
                        float *e_w)
{
    if (!p->speed_loop) return in->ref;
    *e_w = in->omega_ref - omega_m;
    *tau_u = bc_pi_output(&s->piw_p, &s->pi_w, *e_w, 0.0f); /* tau = PI_w(omega_ref - omega_m) */
    return bc_pi_limit(&s->piw_p, *tau_u);
}

/* RAMP's creep speed and the observer's trust threshold (bc_sine.h, RAMP): 5 % of omega_on, at most sqrt(2
 * if_accel_min), the speed at which a rotor that breaks away from rest against a friction load at the design bound
 * still catches the vector before its load angle passes the far equilibrium (whatever its inertia) */
static float creep_speed(const bc_sine_params *p)
{
    return fminf(0.05f * p->omega_on, sqrtf(2.0f * fmaxf(p->if_accel_min, 0.0f)));
}

/* ALIGN -> RAMP: the ramp's clocks and limits from the start */
static void ramp_start(bc_sine_state *s)
{
    s->sl_phase = BC_SINE_SL_RAMP;
    s->sl_t = 0.0f;
    s->rho_f = 0.0f;
    s->if_t = s->if_tb = s->if_tr = 0.0f;
    s->if_wmin = 0.0f;
    s->if_trust = 0;
}

/* ALIGN's swing frequency at if_align_current on the configured inertia, rad/s: if_align is three periods at
 * if_current (sensorless_settings), w_a = (6 pi / if_align) sqrt(if_align_current / if_current); 0 without an
 * alignment */
static float align_wa(const bc_sine_params *p)
{
    if (!(p->if_align > 0.0f)) return 0.0f;
    return 6.0f * BC_PI_F / p->if_align * sqrtf(p->if_align_current / p->if_current);
}

/* ALIGN's swing back-EMF on d of theta_if (the rotor's q axis there), V: the d PI's integrator with decoupling
 * (its feed-forward carries R i_d,ref), x_d - R i_d without */
static float align_ed(const bc_sine_params *p, const bc_sine_state *s, bc_abc i, float theta)
{
    if (p->decouple) return s->pi_d.x;
    bc_dq idq = bc_park(bc_clarke(i), -sinf(theta), -cosf(theta));
    return s->pi_d.x - p->R * idq.d;
}

/* ALIGN's zero-current catch window (zc_catch, or a turning rotor the pulses found): the first 3 lock_time of each
 * alignment after the pulses, once a start. */
static int zc_window(const bc_sine_params *p, const bc_sine_state *s)
{
    return (p->zc_catch || s->fc_on) && !s->caught && s->n_zc < 3.0f * p->lock_time;
}

/* PULSE (catch_pulse; bc_sine.h): the samples of each ALIGN the pulses take */
#define FC_SAMPLES 6

/* The back-EMF vector (V, alpha-beta) from a zero-vector pulse of length tau that ended with the current i (from
 * zero): L di/dt = -(e + R i) gives i(tau) = -(e / R) (1 - exp(-R tau / L)) */
static bc_ab fc_emf(const bc_sine_params *p, float tau, float ia, float ib)
{
    float x = p->R * tau / p->L;
    float k = x > 1e-4f ? p->R / (1.0f - expf(-x)) : (p->L / tau) * (1.0f + 0.5f * x);
    bc_ab e = {-k * ia, -k * ib};
    return e;
}

/* One sample of PULSE at step k of it (0 .. FC_SAMPLES - 1), the phase currents i_ab measured now: writes the legs
 * (off, and the zero vector at the end of the half periods commanded at steps 0 and 3); at the last step reads the
 * rotor from both pulses and, turning at least at omega_on, seeds the observer and opens the zero-current catch */
static void fc_step(const bc_sine_params *p, bc_sine_state *s, const bc_ctrl_in *in, bc_ab i_ab, bc_ctrl_out *out)
{
    int k = s->fc_k;
    sl_off(s, out);
    if (k == 0) {
        /* tau from the drive's data: at 1.25 times the no-load speed the pulse's current is i_s_max / 3 */
        float e_top = 1.25f * p->k_1 * in->v_dc / (2.0f * p->k_phi);
        float tau = p->L * (p->i_s_max / 3.0f) / fmaxf(e_top, 1e-30f);
        s->fc_tau = isfinite(tau) ? bc_clampf(tau, 1e-3f * p->ts, 0.9f * p->ts) : 0.5f * p->ts;
    }
    if (k == 0 || k == 3) {
        out->has_at = 1u;
        out->t_at = p->ts - s->fc_tau;
        for (int x = 0; x < 3; ++x) {
            out->leg_at[x].mode = BC_LEG_LOW;
            out->leg_at[x].duty = 1.0f;
        }
    }
    if (k == 2) {
        s->fc_i[0] = i_ab.alpha; /* the first pulse's, from zero current */
        s->fc_i[1] = i_ab.beta;
    }
    if (k == 4) {
        /* the first pulse's current left (near the no-load speed the diodes barely take it) */
        s->fc_i2[0] = i_ab.alpha;
        s->fc_i2[1] = i_ab.beta;
    }
    if (k == FC_SAMPLES - 1) {
        /* the back-EMF from the first pulse (from zero current: its angle and amplitude), the second pulse's rise
         * over the current left from the first (only its direction of turn): |omega| = |e_1| / psi_f, its sign
         * that of the turn from e_1 to e_2, theta = phi_1 + sgn(omega) pi / 2 + omega 3 ts */
        bc_ab e1 = fc_emf(p, s->fc_tau, s->fc_i[0], s->fc_i[1]);
        bc_ab e2 = fc_emf(p, s->fc_tau, i_ab.alpha - s->fc_i2[0], i_ab.beta - s->fc_i2[1]);
        float a1 = sqrtf(e1.alpha * e1.alpha + e1.beta * e1.beta);
        float dphi = atan2f(e1.alpha * e2.beta - e1.beta * e2.alpha, e1.alpha * e2.alpha + e1.beta * e2.beta);
        float wa = a1 / fmaxf(s->psi_obs, 1e-30f);
        float w = dphi > 0.0f ? wa : -wa;
        if (isfinite(w) && isfinite(dphi) && wa >= p->omega_on && fabsf(dphi) >= 0.25f * wa * 3.0f * p->ts &&
            fabsf(dphi) <= 4.0f * wa * 3.0f * p->ts) {
            /* the back-EMF lies on q (the d axis at theta - pi): theta = phi + sgn(omega) pi / 2 */
            float th = atan2f(e1.beta, e1.alpha) + (w > 0.0f ? 0.5f : -0.5f) * BC_PI_F + w * 3.0f * p->ts;
            th = bc_wrap_2pi(th);
            s->if_theta = th;
            s->if_omega = w;
            obs_reset(p, s, th, w, i_ab);
            s->omega_f = w;
            s->flux_f = s->psi_obs;
            s->fc_on = s->fc_seed = 1;
        }
    }
    s->fc_k = k + 1;
}

/* Sensorless sample (bc_sine.h, "Sensorless"): observer, I/f start-up, handover, loss of lock. */
static void sensorless_step(const bc_sine_params *p, bc_sine_state *s, const bc_ctrl_in *in, bc_abc i,
                            bc_ctrl_out *out)
{
    /* the observer, with the voltage commanded two samples ago (applied over [t_k-1, t_k]) */
    bc_obs_out o = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0};
    bc_ab i_ab = bc_clarke(i);
    const float u_obs[2] = {s->u_hist[1][0], s->u_hist[1][1]}; /* the voltage over [t_k-1, t_k] */
    const int32_t u_obs_ok = s->u_ok[1];
    if (u_obs_ok) {
        bc_obs_in oi = {{u_obs[0], u_obs[1]}, i_ab};
        obs_run(p, s, &oi, &o);
    } else {
        /* nothing known to integrate: held at the I/f angle, or the pulses' seed carried on at its speed */
        if (s->fc_seed) s->if_theta = bc_wrap_2pi(s->if_theta + s->if_omega * p->ts);
        float w_seed = s->fc_seed ? s->if_omega : 0.0f;
        obs_reset(p, s, s->if_theta, w_seed, i_ab);
        o.theta = s->if_theta;
        o.omega_e = w_seed;
    }
    if (u_obs_ok) s->fc_seed = 0;
    s->u_hist[1][0] = s->u_hist[0][0];
    s->u_hist[1][1] = s->u_hist[0][1];
    s->u_ok[1] = s->u_ok[0];
    s->u_ok[0] = 0;
    int flux_ok = fabsf(o.flux / s->psi_obs - 1.0f) <= p->lock_tol;
    /* the observer's speed (and flux) through a first-order low-pass of time constant lock_time (the rotor's I/f
     * swing out) */
    float k_f = bc_clampf(p->ts / p->lock_time, 0.0f, 1.0f);
    s->omega_f += k_f * (o.omega_e - s->omega_f);
    s->flux_f += k_f * (o.flux - s->flux_f);
    /* if_psi_est (flux observer), in RAMP: its low-passed flux off the configured circle by more than half the
     * band holds the hand-off until the flux has been read at zero current (below), once a start */
    int psi_off = p->if_psi_est && p->observer == BC_SINE_OBS_FLUX && !s->psi_done &&
                  s->mode == BC_SINE_MODE_START && s->sl_phase == BC_SINE_SL_RAMP &&
                  (s->n_zero > 0.0f || fabsf(s->flux_f / s->psi_obs - 1.0f) > 0.5f * p->lock_tol);

    float tau, tau_u = 0.0f, e_w = 0.0f, ref = p->speed_loop ? in->omega_ref : in->ref;
    int was = s->mode;
    float theta = o.theta, omega_e = o.omega_e;

    if (s->mode == BC_SINE_MODE_SINE) {
        s->n_lock = flux_ok ? 0.0f : s->n_lock + p->ts;
        float ref0 = p->speed_loop ? in->omega_ref : in->ref;
        /* turning with the reference: w_rev follows the speed; against it (a reversal, a caught rotor braked)
         * the speed must fall: faster than w_rev + omega_off against it, the load outweighs the current limit */
        int against = ref0 * s->omega_f < 0.0f;
        if (!against) s->w_rev = fabsf(s->omega_f);
        if (against && fabsf(s->omega_f) > s->w_rev + p->omega_off) {
            sl_desync(p, s, out, BC_FLAG_START_FAIL);
        } else if (fabsf(s->omega_f) < p->omega_off && flux_ok && ref0 != 0.0f) {
            /* slowing through the hand-off speed with the observer consistent (a reversal under load, a brake):
             * back to the I/f ramp without turning the legs off, the vector on the rotor's q axis as the observer
             * has it, at its speed: the I/f current carries the rotor through the speeds the observer cannot */
            out->flags |= BC_FLAG_STALL;
            s->mode = BC_SINE_MODE_START;
            s->sl_phase = BC_SINE_SL_RAMP;
            s->sl_dir = ref0 < 0.0f ? -1 : 1;
            s->if_theta = bc_wrap_2pi(o.theta);
            s->if_omega = bc_clampf(o.omega_e, -p->omega_on, p->omega_on);
            s->sl_t = s->n_lock = s->n_catch = 0.0f; /* if_t goes on: the start's budget (a reset at the top) */
            s->rho_f = 1.0f;
            s->if_trust = 0;
            s->if_wmin = fminf(s->if_wmin, (float)s->sl_dir * s->if_omega);
            if (s->rest_on) bc_rest_restart(&s->rest);
        } else if (fabsf(s->omega_f) < p->omega_off) {
            sl_desync(p, s, out, BC_FLAG_STALL);
        } else if (s->n_lock >= p->lock_time) {
            sl_desync(p, s, out, BC_FLAG_LOCK_LOST);
        }
    } else {
        if (s->sl_phase == BC_SINE_SL_WAIT) {
            s->sl_t += p->ts;
            if (s->sl_t >= p->restart_wait) {
                s->sl_phase = BC_SINE_SL_IDLE;
                s->sl_t = 0.0f;
            }
        }
        if (s->sl_phase == BC_SINE_SL_IDLE && ref != 0.0f) {
            s->sl_phase = BC_SINE_SL_ALIGN;
            s->sl_dir = ref < 0.0f ? -1 : 1;
            s->sl_t = 0.0f;
            s->if_theta = 0.0f;
            s->if_omega = 0.0f;
            s->n_lock = 0.0f;
            s->r_obs = obs_r(p);
            if (s->psi_obs != obs_psi(p)) {
                s->psi_obs = obs_psi(p); /* a new start from the configured flux linkage */
                if (p->observer == BC_SINE_OBS_FLUX) bc_fluxobs_set_psi(&p->fobs, &s->fobs, s->psi_obs);
            }
            s->n_psi = s->n_zero = s->n_zc = 0.0f;
            s->al_stage = 0;
            s->al_t = s->al_quiet = 0.0f;
            s->psi_adapt = s->psi_done = 0;
            s->n_catch = 0.0f;
            s->caught = 0;
            s->fc_k = p->catch_pulse ? 0 : FC_SAMPLES;
            s->fc_on = s->fc_seed = 0;
            s->if_t = 0.0f;
            s->r_ui = 0.0f;
            s->r_ii = 0.0f;
            bc_pi_reset(&s->pi_p, &s->pi_d, 0.0f);
            bc_pi_reset(&s->pi_p, &s->pi_q, 0.0f);
        }
        float dir = (float)s->sl_dir;
        if (s->sl_phase == BC_SINE_SL_ALIGN && s->fc_k < FC_SAMPLES) {
            /* catch_pulse: the alignment waits for the pulses (their legs below) */
        } else if (s->sl_phase == BC_SINE_SL_ALIGN && zc_window(p, s)) {
            /* zc_catch: the alignment waits while the current loops hold i = 0 in the observer's frame (below) */
            s->n_zc += p->ts;
            if (!zc_window(p, s)) {
                bc_pi_reset(&s->pi_p, &s->pi_d, 0.0f); /* no catch: the alignment from a clean start */
                bc_pi_reset(&s->pi_p, &s->pi_q, 0.0f);
                s->if_omega = 0.0f; /* the pulses' seed: not the alignment's */
                s->fc_seed = 0;
            }
        } else if (s->sl_phase == BC_SINE_SL_ALIGN && s->al_stage == 1) {
            /* the closing sweep: the vector turned forwards (dir) by beta at w_s, dragging a rotor that friction
             * holds off the rest angle from behind; then the seed at the vector's rest angle, RAMP */
            float w_a = align_wa(p);
            float beta = 2.0f * asinf(fminf(BC_SINE_RHO_HI * p->if_current / p->if_align_current, 1.0f));
            float w_s = BC_SINE_SWEEP_K * w_a;
            s->al_t += p->ts;
            s->if_omega = dir * w_s;
            s->if_theta = bc_wrap_2pi(s->if_theta + s->if_omega * p->ts);
            if (s->al_t * w_s >= beta) {
                /* the unloaded rotor's q axis is pi/2 behind the vector's (dir < 0: ahead): the seed */
                obs_reset(p, s, s->if_theta + dir * 0.5f * BC_PI_F, 0.0f, i_ab);
                ramp_start(s);
                s->if_omega = dir * fminf(w_s, creep_speed(p)); /* the ramp goes on from the sweep */
            }
        } else if (s->sl_phase == BC_SINE_SL_ALIGN) {
            s->sl_t += p->ts;
            /* two steps: the vector at pi/2 for the first third, then at 0 (a rotor at the unstable point of
             * one, or held by friction near it, is a quarter turn from the other's) */
            s->if_theta = 3.0f * s->sl_t < p->if_align ? 0.5f * BC_PI_F : 0.0f;
            /* the swing has died when its back-EMF |e_d| stays below psi_f w_q for T_q (half a swing period at
             * if_align_current on the configured inertia): a swing whose peak speed is above 2 w_q spends less
             * than a sixth of its period below w_q, so T_q holds it up to nine times that inertia */
            float w_a = align_wa(p);
            float e_d = align_ed(p, s, i, s->if_theta);
            int still = 3.0f * s->sl_t >= p->if_align && fabsf(e_d) <= BC_SINE_QUIET_K * w_a * s->psi_obs;
            s->al_quiet = still ? s->al_quiet + p->ts : 0.0f;
            /* the resistance over the last quarter (if_r_est): sums of u.i and i.i, u the applied voltage the
             * observer took this sample (over [t_k-1, t_k]), i the current at t_k */
            if (p->if_r_est && 4.0f * s->sl_t >= 3.0f * p->if_align && u_obs_ok) {
                float ui = u_obs[0] * i_ab.alpha + u_obs[1] * i_ab.beta;
                float ii = i_ab.alpha * i_ab.alpha + i_ab.beta * i_ab.beta;
                if (isfinite(ui) && isfinite(ii)) {
                    s->r_ui += ui;
                    s->r_ii += ii;
                }
            }
            int died = s->al_quiet * w_a >= BC_PI_F || s->sl_t >= 2.0f * p->if_align;
            if (s->sl_t >= p->if_align && (died || !(w_a > 0.0f))) {
                if (p->if_r_est) {
                    /* R^ = sum u.i / sum i.i, accepted if the current was there and R^ is plausible */
                    float n = 0.25f * p->if_align / p->ts, ia = p->if_align_current;
                    float r0 = obs_r(p), r = s->r_ui / fmaxf(s->r_ii, 1e-30f);
                    float r_lo = 0.25f * r0, r_hi = r0 > 0.0f ? 4.0f * r0 : p->v_max / ia;
                    if (isfinite(r) && s->r_ii >= 0.25f * ia * ia * fmaxf(n - 2.0f, 1.0f) && r >= r_lo && r <= r_hi)
                        s->r_obs = r;
                }
                if (w_a > 0.0f) {
                    s->al_stage = 1; /* the closing sweep (above), which seeds the observer at its end */
                    s->al_t = 0.0f;
                } else {
                    /* the unloaded rotor's q axis is pi/2 behind the vector's (dir < 0: ahead): the seed */
                    obs_reset(p, s, s->if_theta + dir * 0.5f * BC_PI_F, 0.0f, i_ab);
                    ramp_start(s);
                }
            }
        } else if (s->sl_phase == BC_SINE_SL_RAMP) {
            /* the load-adaptive ramp (if_accel_min < if_accel; otherwise the fixed ramp at if_accel): the
             * torque's share of the I/f torque rho = cos(theta^ - theta_if) sets the acceleration
             * a = if_accel clamp((RHO_HI - rho) / (RHO_HI - RHO_LO), -1, 1): full while the torque is at most
             * RHO_LO of the I/f torque, none at RHO_HI, and past it the vector slows (waits for the rotor) */
            int adaptive = p->if_accel_min < p->if_accel;
            s->rho_f = cosf(o.theta - s->if_theta);
            float a = p->if_accel;
            /* the observer is trusted when it sees the rotor move (at least 5 % of omega_on): at rest it holds its
             * seed, which a load holding the rotor leaves off. Not trusted: the vector creeps (below) at
             * if_accel_min at least, the swing is not braked */
            float w_cr = creep_speed(p);
            int moving = fabsf(o.omega_e) >= w_cr;
            s->if_trust = adaptive && moving;
            /* the rotor keeps up with a vector turning forwards (its low-passed speed within the trust threshold
             * of the vector's): it carries the slowest ramp, whatever the observer's angle says. Below about
             * lambda the observer's angle keeps its seed's error (it decays at omega^2 / lambda), which a friction
             * load held in the alignment makes up to asin(tau_L / tau_align) and the ramp reads as torque margin
             * the rotor does not have: without this the vector waits at the rotor's stick-slip speed */
            int sync = s->if_trust && dir * s->if_omega > 0.0f &&
                       dir * s->omega_f >= dir * s->if_omega - w_cr;
            /* the vector turned against dir that has found no lower speed for a swing period at if_current (a
             * third of if_align, its default three periods): the push that turned it is absorbed (a rotor an
             * active load pushes back within the I/f torque is caught within a swing; a pushed rotor still
             * running away makes new lowest speeds), and what the vector follows now is a rotor it drags. The
             * observer's angle cannot tell: a flux error offsets it by atan(k / omega) at low speed, 70 deg on
             * mn3110-780kv with psi_f configured 40 % low, read as rho = RHO_HI, and the rule below (at most the
             * observer's speed) then ratcheted the vector back on each dip of the observer's speed, the unloaded
             * rotor following it at a steady -240 rad/s. So it turns back towards dir at if_accel_min at least,
             * the rule below not applied, until it turns with dir again */
            int back = adaptive && dir * s->if_omega < 0.0f && s->if_t > p->if_align / 3.0f;
            if (adaptive) {
                a *= bc_clampf((BC_SINE_RHO_HI - s->rho_f) / (BC_SINE_RHO_HI - BC_SINE_RHO_LO), -1.0f, 1.0f);
                if (!moving || sync || back) a = fmaxf(a, p->if_accel_min);
            }
            /* omega_if += dir a T_s within dir [-omega_on, omega_on] (a rotor pushed back by an active load is
             * followed back); theta_if += omega_if T_s */
            float w = fmaxf(dir * s->if_omega + a * p->ts, -p->omega_on);
            /* a rotor at rest is passed slowly (it breaks away where the torque is largest): at most a creep */
            if (adaptive && !moving) w = fminf(w, w_cr);
            /* at the top of the band the vector does not outrun the rotor (the observer's speed) */
            if (s->if_trust && s->rho_f >= BC_SINE_RHO_HI && !sync && !back)
                w = fminf(w, fmaxf(dir * o.omega_e, -p->omega_on));
            /* in the zero-current reading (if_psi_est, taken at the top) the vector carries no current: its angle
             * against the observer's is no torque share, and it turns on at omega_on (read as one, a rotor coasting
             * slower than the vector pulled it below omega_on through the rule above, which dropped the reading) */
            if (s->n_zero > 0.0f) w = p->omega_on;
            int at_top = w >= p->omega_on;
            s->if_omega = dir * (at_top ? p->omega_on : w);
            s->if_theta = bc_wrap_2pi(s->if_theta + s->if_omega * p->ts);
            if (!at_top) {
                /* below omega_on for longer than the slowest ramp takes from its lowest speed (the mean
                 * acceleration since then below if_accel_min): the load is beyond the I/f torque. A vector that
                 * followed a rotor pushed back starts the count again from its new lowest speed. */
                if (w < s->if_wmin) {
                    s->if_wmin = w;
                    s->if_t = 0.0f;
                }
                s->if_t += p->ts;
                s->if_tr += p->ts;
                if (w < 0.0f) s->if_tb += p->ts;
                /* and, whatever the lowest speed, against dir for the slowest ramp's time in all, or below
                 * omega_on for twice it (the slowest ramp from -omega_on): every ramp ends within a bound */
                float t_min = p->omega_on / p->if_accel_min;
                /* plus the creep's sweep: a rotor held at the seed's rest angle moves once the vector has turned
                 * from there to its breakaway angle acos(tau_load / tau_if), at most a quarter turn, at the creep's
                 * speed w_cr: t_sw = (pi / 2) / w_cr */
                float t_sw = 0.5f * BC_PI_F / fmaxf(w_cr, 1e-30f);
                if (adaptive && (s->if_t >= (p->omega_on - s->if_wmin) / p->if_accel_min + t_sw ||
                                 s->if_tb >= t_min || s->if_tr >= 2.0f * t_min + t_sw))
                    sl_desync(p, s, out, BC_FLAG_START_FAIL);
            }
            if (at_top) {
                s->sl_t += p->ts;
                int lock = flux_ok && fabsf(o.err) <= p->lock_tol && s->omega_f * dir >= p->omega_off && !psi_off;
                s->n_lock = lock ? s->n_lock + p->ts : 0.0f;
                if (s->n_lock >= p->lock_time) {
                    s->mode = BC_SINE_MODE_SINE;
                    s->n_lock = 0.0f;
                    s->sl_t = 0.0f;
                    s->if_t = s->if_tb = s->if_tr = 0.0f; /* a completed ramp: a later hand-back has the whole budget */
                    s->w_rev = fabsf(s->omega_f);
                } else if (s->sl_t >= p->if_hold) {
                    sl_desync(p, s, out, BC_FLAG_START_FAIL);
                }
            }
        }
    }
    if (s->mode == BC_SINE_MODE_START && was == BC_SINE_MODE_START &&
        (s->sl_phase == BC_SINE_SL_ALIGN || s->sl_phase == BC_SINE_SL_RAMP)) {
        /* catch: the observer consistent on a rotor already turning at least at omega_on, either direction (a
         * rotor turning when the drive starts, or pushed by an active load): the sine mode at once, whose speed
         * loop brakes or drives it with the whole current limit */
        int turning = !s->caught && flux_ok && fabsf(o.err) <= p->lock_tol && fabsf(s->omega_f) >= p->omega_on;
        /* (a flux off the circle holds the catch of a rotor turning with the ramp until it is read, not that of
         * a rotor turning against it: the reading needs the ramp's direction) */
        s->n_catch = turning && !(psi_off && (float)s->sl_dir * s->omega_f > 0.0f) ? s->n_catch + p->ts : 0.0f;
        /* the flux linkage read at zero current (if_psi_est; bc_sine.h, RAMP): the flux off the circle for 2
         * lock_time at the top of the ramp, the observer consistent on a rotor turning at least at omega_off,
         * starts the reading: i = 0, and once the current has settled (t_set) the current loops' voltage is the
         * back-EMF alone (R i and L di/dt zero, whatever R and L), psi^ = sum |u| T_s / (the angle u turned) */
        int steady = fabsf(o.err) <= p->lock_tol && (float)s->sl_dir * s->omega_f >= p->omega_off;
        int top = s->sl_phase == BC_SINE_SL_RAMP && fabsf(s->if_omega) >= p->omega_on;
        if (s->n_zero > 0.0f) {
            if (!steady || !top || !u_obs_ok) {
                /* dropped: the current back on, and the flux no longer holds the hand-off (as without the reading) */
                s->n_zero = s->n_psi = 0.0f;
                s->psi_done = 1;
            } else {
                s->n_zero += p->ts;
                /* the current's settling: lock_time / 2, at least ten of the current loop's time constants L / k_p */
                float t_set = fmaxf(0.5f * p->lock_time, p->kp > 0.0f ? 10.0f * p->L / p->kp : 0.0f);
                if (s->n_zero > t_set) {
                    /* the back-EMF's length times T_s, and the angle it has turned (from the last sample's) */
                    if (s->z_n > 0.0f) {
                        float cr = s->z_u[0] * u_obs[1] - s->z_u[1] * u_obs[0];
                        float dt = s->z_u[0] * u_obs[0] + s->z_u[1] * u_obs[1];
                        s->z_flux += p->ts * sqrtf(u_obs[0] * u_obs[0] + u_obs[1] * u_obs[1]);
                        s->z_w += atan2f(cr, dt);
                    }
                    s->z_u[0] = u_obs[0];
                    s->z_u[1] = u_obs[1];
                    s->z_n += 1.0f;
                }
                /* ends after lock_time / 2 of it, on a whole number of turns of u (the ripple of |u| that a
                 * trapezoidal or tabulated back-EMF gives averages out), at the latest after 4 lock_time */
                if (s->z_tgt <= 0.0f && s->n_zero >= t_set + 0.5f * p->lock_time)
                    s->z_tgt = fmaxf(ceilf(fabsf(s->z_w) / BC_TWO_PI_F), 1.0f) * BC_TWO_PI_F;
                if ((s->z_tgt > 0.0f && fabsf(s->z_w) >= s->z_tgt) || s->n_zero >= t_set + 4.0f * p->lock_time) {
                    float est = s->z_flux / fmaxf(fabsf(s->z_w), 1e-30f); /* psi^ = sum |u| T_s / angle */
                    if (isfinite(est) && est >= 0.5f * p->fobs.psi && est <= 2.0f * p->fobs.psi &&
                        fabsf(est / s->psi_obs - 1.0f) > 0.5f * p->lock_tol) {
                        s->psi_adapt = 1;
                        s->psi_obs = est;
                        bc_fluxobs_set_psi(&p->fobs, &s->fobs, est);
                    }
                    s->psi_done = 1;
                    s->n_zero = s->n_psi = 0.0f;
                }
            }
        } else {
            s->n_psi = steady && top && psi_off ? s->n_psi + p->ts : 0.0f;
            if (s->n_psi >= 2.0f * p->lock_time) {
                s->n_zero = p->ts; /* the reading starts: i = 0 from the next sample's current loops on */
                s->z_flux = s->z_w = s->z_n = s->z_tgt = 0.0f;
            }
        }
        if (s->n_catch >= p->lock_time) {
            s->mode = BC_SINE_MODE_SINE;
            s->n_lock = s->sl_t = s->n_catch = 0.0f;
            s->caught = 1; /* once a start */
            /* the speed the braked rotor must not exceed: the observer's own, where the low-pass lags a rotor an
             * active load still accelerates (it goes on rising towards the speed at the catch) */
            s->w_rev = fmaxf(fabsf(s->omega_f), fabsf(o.omega_e));
        }
    }
    out->diag[5] = o.theta;
    out->diag[6] = o.omega_e;
    out->diag[7] = (float)s->mode;
    if (s->mode == BC_SINE_MODE_START && (s->sl_phase == BC_SINE_SL_IDLE || s->sl_phase == BC_SINE_SL_WAIT)) {
        if (!(out->flags & BC_FLAG_DESYNC)) sl_off(s, out);
        if (p->speed_loop) bc_pi_reset(&s->piw_p, &s->pi_w, 0.0f);
        return;
    }
    if (s->mode == BC_SINE_MODE_START && s->sl_phase == BC_SINE_SL_ALIGN && s->fc_k < FC_SAMPLES) {
        fc_step(p, s, in, i_ab, out); /* catch_pulse */
        out->flags |= BC_FLAG_OPEN_LOOP;
        if (p->speed_loop) bc_pi_reset(&s->piw_p, &s->pi_w, 0.0f);
        return;
    }

    float id_ref = 0.0f, iq_ref;
    int handoff = 0, zc = 0;
    if (s->mode == BC_SINE_MODE_START) {
        /* I/f: the current vector on the q axis of theta_if */
        theta = s->if_theta;
        omega_e = s->if_omega;
        iq_ref = (float)s->sl_dir * p->if_current * s->derate_f; /* derated like the current limit */
        if (s->sl_phase == BC_SINE_SL_ALIGN && zc_window(p, s)) {
            /* the zero-current catch (zc_catch): i = 0 in the observer's frame, with the back-EMF feed-forward;
             * the voltage is then the back-EMF of a turning rotor, which the observer locks onto */
            theta = o.theta;
            omega_e = o.omega_e;
            id_ref = iq_ref = 0.0f;
            zc = 1;
        } else if (s->sl_phase == BC_SINE_SL_ALIGN) {
            /* the current rises over a tenth of if_align (enough holding torque early against an active load), and
             * the rotor's swing is braked: its back-EMF lies on d of theta_if (the rotor's q axis there, either
             * direction), seen in the d integrator; i_d,ref = -if_damp (x_d - R i_d) */
            iq_ref = (float)s->sl_dir * p->if_align_current * s->derate_f;
            if (p->if_align > 0.0f) iq_ref *= bc_clampf(10.0f * s->sl_t / p->if_align, 0.0f, 1.0f);
            float sd1 = -sinf(theta), cd1 = -cosf(theta);
            bc_dq idq1 = bc_park(bc_clarke(i), sd1, cd1);
            float ia = p->if_align_current;
            float id_max = fminf(0.5f * ia, sqrtf(fmaxf(p->i_s_max * p->i_s_max - ia * ia, 0.0f))) * s->derate_f;
            /* the d voltage beyond R i_d is the swing's back-EMF: with decoupling the PI's feed-forward already
             * carries R i_d,ref and the integrator holds the back-EMF alone (x_d - R i_d would feed the current
             * back with the gain if_damp R, which above 1 latches i_d at its limit and turns the rest angle by
             * atan(i_d / i_q)); without it the integrator holds R i_d + e_d */
            float e_d = s->pi_d.x - (p->decouple ? 0.0f : p->R * idq1.d);
            /* in the closing sweep the swing about the turning vector: less the back-EMF of a rotor that follows
             * it, -dir omega_if psi_f (braking that too would drag the unloaded rotor behind the seed) */
            if (s->al_stage == 1) e_d += (float)s->sl_dir * s->if_omega * s->psi_obs;
            id_ref = bc_clampf(-p->if_damp * e_d, -id_max, id_max);
        } else if (s->sl_phase == BC_SINE_SL_RAMP) {
            /* the swing braked through the observer: i_d = if_damp psi_f (omega^ - omega_if) / sin Delta makes
             * the torque -1.5 k_1 if_damp psi_f (omega^ - omega_if) (bc_sine.h, RAMP); near sin Delta = 0 (the
             * rotor at the I/f current's largest torque) it fades: sin Delta / max(sin^2 Delta, 1/16) */
            float psi = s->psi_obs;
            float sdl = sinf(o.theta - s->if_theta);
            float id_max = sqrtf(fmaxf(p->i_s_max * p->i_s_max - p->if_current * p->if_current, 0.0f));
            id_max = fminf(id_max, p->if_current) * s->derate_f;
            id_ref = s->if_trust ? bc_clampf(p->if_damp * psi * (o.omega_e - s->if_omega) * sdl /
                                                 fmaxf(sdl * sdl, 0.0625f), -id_max, id_max)
                                 : 0.0f;
            if (s->n_zero > 0.0f) id_ref = iq_ref = 0.0f; /* the zero-current reading (if_psi_est) */
        }
        out->flags |= BC_FLAG_OPEN_LOOP;
    } else {
        handoff = was == BC_SINE_MODE_START;
        float sd0 = -sinf(theta), cd0 = -cosf(theta);
        bc_dq idq0 = bc_park(bc_clarke(i), sd0, cd0);
        if (handoff && p->speed_loop) {
            /* bumpless: the torque the present current makes; but a rotor caught turning against the reference
             * (pushed back by an active load) is braked with the whole torque limit: the slipping I/f vector's
             * torque there pulsates at the slip frequency about zero and says nothing of the load */
            float tau0 = 1.5f * p->k_1 * idq0.q;
            if (in->omega_ref * s->omega_f < 0.0f) tau0 = in->omega_ref > 0.0f ? p->tau_max : -p->tau_max;
            bc_pi_reset(&s->piw_p, &s->pi_w, tau0);
        }
        tau = torque_ref(p, s, in, omega_e / (float)p->p, &tau_u, &e_w);
        float i_lim = s->derate_f * bc_sine_i_limit(p, s, in->v_dc, omega_e, tau < 0.0f ? -1.0f : 1.0f);
        iq_ref = bc_clampf(tau / (1.5f * p->k_1), -i_lim, i_lim); /* i_q,ref = tau / (1.5 k_1) */
        if (p->speed_loop) bc_pi_update(&s->piw_p, &s->pi_w, e_w, tau_u, 1.5f * p->k_1 * iq_ref);
    }
    float sd = -sinf(theta), cd = -cosf(theta);
    bc_dq idq = bc_park(bc_clarke(i), sd, cd);
    out->diag[0] = idq.d;
    out->diag[1] = idq.q;
    if (s->mode == BC_SINE_MODE_SINE && s->rest_on) id_ref = bc_rest_ref(&p->rest, &s->rest);
    current_loops(p, s, idq, id_ref, iq_ref, theta, omega_e, in->v_dc,
                  s->mode == BC_SINE_MODE_SINE || zc ? p->emf_ff : 0, handoff, out);
    if (s->rest_on) {
        if (s->mode == BC_SINE_MODE_SINE) {
            int32_t ok = !handoff && !(out->flags & BC_FLAG_SATURATED);
            bc_rest_step(&p->rest, &s->rest, out->diag[3], idq.d, ok);
        } else {
            bc_rest_restart(&s->rest);
        }
    }
    /* the voltage these duties apply: Clarke(d_x v_dc - dead-time error), the zero sequence removed. A phase whose
     * current flows into the motor loses v_dc t_dead at each turn-on of its upper switch (its lower diode holds
     * the terminal low meanwhile), one per PWM period: -sgn(i_x) v_dc t_dead / (2 T_s) on average, sgn linear
     * within +-2 % of i_s_max */
    float vd = in->v_dc * p->t_dead / (2.0f * p->ts), band = 0.02f * p->i_s_max;
    float i3v[3] = {i.a, i.b, i.c}, vx[3];
    for (int x = 0; x < 3; ++x) vx[x] = out->leg[x].duty * in->v_dc - vd * bc_clampf(i3v[x] / band, -1.0f, 1.0f);
    bc_abc va = {vx[0], vx[1], vx[2]};
    bc_ab ua = bc_clarke(va);
    s->u_hist[0][0] = ua.alpha;
    s->u_hist[0][1] = ua.beta;
    s->u_ok[0] = 1;
}

void bc_sine_step(const bc_sine_params *p, bc_sine_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
    for (int x = 0; x < 3; ++x) {
        out->leg[x].mode = BC_LEG_OFF;
        out->leg[x].duty = 0.0f;
    }
    out->flags = 0u;
    out->has_at = 0u; /* no timed change but the pulses' (catch_pulse) */

    /* 1. safety: the input guard (bc_guard.h), the Hall code, the reference and the encoder angle if used */
    bc_hall_out h;
    bc_hall_step(&s->hall_p, &s->hall, in, &h); /* keeps the edge bookkeeping even when the output is safe */
    if (s->derate_on) {
        /* without a winding reading, the winding temperature of the resistance estimate (bc_rest.h) */
        float temp[BC_DERATE_CH] = {in->temp[0], in->temp[1]};
        float T_r;
        if (s->rest_on && !isfinite(temp[0]) && bc_rest_temp(&p->rest, &s->rest, &T_r) == BC_OK) temp[0] = T_r;
        s->derate_f = bc_derate_step(&p->derate, &s->derate, temp); /* in [0, 1] */
    }
    float i3[3];
    uint32_t why = bc_guard_step(&s->guard_p, &s->guard, in, i3);
    if (!h.valid && p->angle != BC_SINE_ANGLE_OBSERVER) why |= BC_FLAG_HALL_INVALID;
    if (p->angle == BC_SINE_ANGLE_ENCODER && !isfinite(in->theta_enc)) why |= BC_FLAG_BAD_INPUT;
    if (p->speed_loop ? !isfinite(in->omega_ref) : !isfinite(in->ref)) why |= BC_FLAG_BAD_INPUT;
    if (why) {
        go_safe(p, s, out, why);
        return;
    }
    bc_abc i = {i3[0], i3[1], i3[2]};
    if (p->angle == BC_SINE_ANGLE_OBSERVER) {
        sensorless_step(p, s, in, i, out);
        return;
    }

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
    float tau_u = 0.0f, e_w = 0.0f;
    float tau = torque_ref(p, s, in, omega_m, &tau_u, &e_w);

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

    /* 5. current references (45), (8), I_s,sat from the table or (23) with R; i_d,ref: the resistance estimate's
     * square wave (bc_rest.h) or 0 */
    float i_lim = s->derate_f * bc_sine_i_limit(p, s, v_dc, omega_e, tau < 0.0f ? -1.0f : 1.0f);
    float iq_ref = bc_clampf(tau / (1.5f * p->k_1), -i_lim, i_lim); /* i_q,ref = tau / (1.5 k_1) */
    if (p->speed_loop) bc_pi_update(&s->piw_p, &s->pi_w, e_w, tau_u, 1.5f * p->k_1 * iq_ref);
    float id_ref = s->rest_on ? bc_rest_ref(&p->rest, &s->rest) : 0.0f;
    current_loops(p, s, idq, id_ref, iq_ref, theta, omega_e, v_dc, p->emf_ff, was == BC_SINE_MODE_START, out);
    if (s->rest_on) {
        int32_t ok = was == BC_SINE_MODE_SINE && !(out->flags & BC_FLAG_SATURATED);
        bc_rest_step(&p->rest, &s->rest, out->diag[3], idq.d, ok); /* v_d applied, i_d measured */
    }
}

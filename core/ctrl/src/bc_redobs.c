/* bc_redobs.c - reduced-order observer in estimated rotor coordinates (Hinkkanen et al. 2018). Equations and their
 * order in bc_redobs.h. */
#include "bldc/bc_redobs.h"

#include <math.h>

static int finite_pos(float v) { return isfinite(v) && v > 0.0f; }
static float finite_or_zero(float v) { return isfinite(v) ? v : 0.0f; }

int bc_redobs_init(const bc_redobs_params *p, bc_redobs_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!(isfinite(p->R) && p->R >= 0.0f) || !finite_pos(p->L) || !finite_pos(p->psi) || !finite_pos(p->ts) ||
        !finite_pos(p->alpha_o) || !(isfinite(p->sigma0) && p->sigma0 >= 0.0f) ||
        !(isfinite(p->zeta_inf) && p->zeta_inf >= 0.0f && p->zeta_inf <= 1.0f) || !finite_pos(p->i_max) ||
        !finite_pos(p->v_max))
        return BC_ERR_PARAM;
    if (p->alpha_o * p->ts > 0.5f || 2.0f * p->sigma0 * p->ts > 0.5f) return BC_ERR_PARAM;
    s->k_theta = 2.0f * p->alpha_o;         /* k_theta = 2 alpha_o */
    s->k_omega = p->alpha_o * p->alpha_o;   /* k_omega = alpha_o^2 */
    s->omega_max = 4.0f * p->v_max / p->psi;
    s->x_max = 4.0f * p->psi + p->L * p->i_max;
    if (!isfinite(s->k_omega) || !isfinite(s->omega_max) || !isfinite(s->x_max)) return BC_ERR_PARAM;
    bc_redobs_reset(p, s, 0.0f, 0.0f, (bc_ab){0.0f, 0.0f});
    s->started = 0;
    return BC_OK;
}

void bc_redobs_reset(const bc_redobs_params *p, bc_redobs_state *s, float theta_e, float omega_e, bc_ab i)
{
    float th = bc_wrap_2pi(theta_e);
    float ia = bc_clampf(finite_or_zero(i.alpha), -p->i_max, p->i_max);
    float ib = bc_clampf(finite_or_zero(i.beta), -p->i_max, p->i_max);
    s->psi_s[0] = p->L * ia - p->psi * cosf(th); /* L i + psi_f exp(j (theta_e - pi)) */
    s->psi_s[1] = p->L * ib - p->psi * sinf(th);
    s->i_prev[0] = ia;
    s->i_prev[1] = ib;
    s->started = 1;
    s->theta = th;
    s->omega = bc_clampf(finite_or_zero(omega_e), -s->omega_max, s->omega_max);
}

void bc_redobs_step(const bc_redobs_params *p, bc_redobs_state *s, const bc_obs_in *in, bc_obs_out *out)
{
    bc_ab u, i;
    out->valid = bc_obs_sanitise(in, p->v_max, p->i_max, &u, &i);
    out->theta = s->theta;
    out->theta_raw = s->theta;
    out->omega_e = s->omega;
    out->err = 0.0f;
    if (!out->valid) {
        float fa = s->psi_s[0] - p->L * s->i_prev[0], fb = s->psi_s[1] - p->L * s->i_prev[1];
        out->flux = sqrtf(fa * fa + fb * fb);
        s->theta = bc_wrap_2pi(s->theta + p->ts * s->omega); /* coast on the speed */
        return;
    }
    if (!s->started) {
        s->i_prev[0] = i.alpha;
        s->i_prev[1] = i.beta;
        s->started = 1;
    }
    /* 2. voltage model in stator coordinates: psi^ += T_s (u - R (i_k-1 + i_k) / 2) */
    s->psi_s[0] += p->ts * (u.alpha - p->R * 0.5f * (s->i_prev[0] + i.alpha));
    s->psi_s[1] += p->ts * (u.beta - p->R * 0.5f * (s->i_prev[1] + i.beta));
    s->i_prev[0] = i.alpha;
    s->i_prev[1] = i.beta;
    /* 3. in estimated rotor coordinates (d axis at theta^ - pi: cos = -cos theta^, sin = -sin theta^):
     *    e_o = L i' + psi_f - psi',  eps = -Im(e_o) / psi_f */
    float c = -cosf(s->theta), sn = -sinf(s->theta);
    bc_dq ip = bc_park(i, sn, c);
    bc_dq fp = bc_park((bc_ab){s->psi_s[0], s->psi_s[1]}, sn, c);
    float e_d = p->L * ip.d + p->psi - fp.d, e_q = p->L * ip.q - fp.q;
    float eps = -e_q / p->psi;
    /* 4. k_1 e_o + k_2 e_o* = 2 sigma Re(e_o) on d,  sigma = sigma_0 + zeta_inf |omega^| */
    float m = bc_clampf(2.0f * p->ts * (p->sigma0 + p->zeta_inf * fabsf(s->omega)), 0.0f, 1.0f);
    s->psi_s[0] = bc_clampf(s->psi_s[0] + m * e_d * c, -s->x_max, s->x_max);
    s->psi_s[1] = bc_clampf(s->psi_s[1] + m * e_d * sn, -s->x_max, s->x_max);
    /* 5. omega_c = omega^ + k_theta eps,  omega^ += T_s k_omega eps,  theta^ += T_s omega_c */
    float fa = s->psi_s[0] - p->L * i.alpha, fb = s->psi_s[1] - p->L * i.beta;
    out->flux = sqrtf(fa * fa + fb * fb);
    out->err = eps;
    float w_c = s->omega + s->k_theta * eps;
    s->omega = bc_clampf(s->omega + p->ts * s->k_omega * eps, -s->omega_max, s->omega_max);
    s->theta = bc_wrap_2pi(s->theta + p->ts * w_c);
}

/* bc_fluxobs.c - nonlinear flux observer with a PLL (Lee et al. 2010). Equations and their order in bc_fluxobs.h. */
#include "bldc/bc_fluxobs.h"

#include <math.h>

static int finite_pos(float v) { return isfinite(v) && v > 0.0f; }
static float finite_or_zero(float v) { return isfinite(v) ? v : 0.0f; }

int bc_fluxobs_init(const bc_fluxobs_params *p, bc_fluxobs_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!(isfinite(p->R) && p->R >= 0.0f) || !finite_pos(p->L) || !finite_pos(p->psi) || !finite_pos(p->ts) ||
        !finite_pos(p->gain) || !finite_pos(p->pll_bw) || !finite_pos(p->i_max) || !finite_pos(p->v_max))
        return BC_ERR_PARAM;
    if (p->gain * p->ts > 0.5f || p->pll_bw * p->ts > 0.5f) return BC_ERR_PARAM;
    s->psi2 = p->psi * p->psi;
    s->half_gamma = 0.5f * p->gain / s->psi2; /* gamma / 2 = lambda / (2 psi_f^2) */
    s->kp = 2.0f * p->pll_bw;                 /* k_p = 2 omega_p */
    s->ki = p->pll_bw * p->pll_bw;            /* k_i = omega_p^2 */
    s->omega_max = 4.0f * p->v_max / p->psi;
    s->x_max = 4.0f * p->psi + p->L * p->i_max;
    if (!isfinite(s->half_gamma) || !isfinite(s->omega_max) || !isfinite(s->x_max) || !isfinite(s->ki))
        return BC_ERR_PARAM;
    bc_fluxobs_reset(p, s, 0.0f, 0.0f, (bc_ab){0.0f, 0.0f});
    s->started = 0;
    return BC_OK;
}

void bc_fluxobs_set_psi(const bc_fluxobs_params *p, bc_fluxobs_state *s, float psi)
{
    if (!finite_pos(psi)) return;
    float psi2 = psi * psi, hg = 0.5f * p->gain / psi2, w_max = 4.0f * p->v_max / psi, x_max = 4.0f * psi + p->L * p->i_max;
    if (!isfinite(hg) || !isfinite(w_max) || !isfinite(x_max) || !(psi2 > 0.0f)) return;
    s->psi2 = psi2;
    s->half_gamma = hg;
    s->omega_max = w_max;
    s->x_max = x_max;
}

void bc_fluxobs_reset(const bc_fluxobs_params *p, bc_fluxobs_state *s, float theta_e, float omega_e, bc_ab i)
{
    float th = bc_wrap_2pi(theta_e); /* non-finite: 0 */
    float ia = bc_clampf(finite_or_zero(i.alpha), -p->i_max, p->i_max);
    float ib = bc_clampf(finite_or_zero(i.beta), -p->i_max, p->i_max);
    /* x^ = L i + psi_f (cos th_d, sin th_d), th_d = theta_e - pi: (cos th_d, sin th_d) = -(cos th, sin th) */
    s->x[0] = p->L * ia - p->psi * cosf(th);
    s->x[1] = p->L * ib - p->psi * sinf(th);
    s->i_prev[0] = ia;
    s->i_prev[1] = ib;
    s->started = 1;
    s->theta = th;
    s->omega = bc_clampf(finite_or_zero(omega_e), -s->omega_max, s->omega_max);
}

void bc_fluxobs_step(const bc_fluxobs_params *p, bc_fluxobs_state *s, const bc_obs_in *in, bc_obs_out *out)
{
    bc_ab u, i;
    out->valid = bc_obs_sanitise(in, p->v_max, p->i_max, &u, &i);
    if (out->valid) {
        if (!s->started) {
            s->i_prev[0] = i.alpha;
            s->i_prev[1] = i.beta;
            s->started = 1;
        }
        /* 2. voltage model: x^ += T_s (u - R (i_k-1 + i_k) / 2) */
        s->x[0] += p->ts * (u.alpha - p->R * 0.5f * (s->i_prev[0] + i.alpha));
        s->x[1] += p->ts * (u.beta - p->R * 0.5f * (s->i_prev[1] + i.beta));
        s->i_prev[0] = i.alpha;
        s->i_prev[1] = i.beta;
        /* 3. correction: x^ += m eta,  m = T_s (gamma/2) (psi_f^2 - |eta|^2) in [-1, T_s lambda / 2] */
        float ea = s->x[0] - p->L * i.alpha, eb = s->x[1] - p->L * i.beta;
        float m = p->ts * s->half_gamma * (s->psi2 - (ea * ea + eb * eb));
        m = bc_clampf(m, -1.0f, 0.5f * p->ts * p->gain);
        s->x[0] = bc_clampf(s->x[0] + m * ea, -s->x_max, s->x_max);
        s->x[1] = bc_clampf(s->x[1] + m * eb, -s->x_max, s->x_max);
    }
    /* 4. angle of eta = x^ - L i (the d axis), theta_raw = atan2(eta) + pi */
    float ea = s->x[0] - p->L * s->i_prev[0], eb = s->x[1] - p->L * s->i_prev[1];
    float raw = bc_wrap_2pi(atan2f(eb, ea) + BC_PI_F);
    /* the output is the PLL's angle at t_k (predicted at sample k-1: exact at constant speed), then its update */
    float th_out = s->theta, w_out = s->omega, e = 0.0f;
    if (out->valid) {
        /* 5. PLL: e = wrap(theta_raw - theta^), theta^ += T_s (omega^ + k_p e), omega^ += T_s k_i e */
        e = bc_obs_wrap_pm(raw - s->theta);
        s->theta = bc_wrap_2pi(s->theta + p->ts * (s->omega + s->kp * e));
        s->omega = bc_clampf(s->omega + p->ts * s->ki * e, -s->omega_max, s->omega_max);
    } else {
        s->theta = bc_wrap_2pi(s->theta + p->ts * s->omega); /* coast on the speed */
    }
    out->theta = th_out;
    out->omega_e = w_out;
    out->theta_raw = raw;
    out->flux = sqrtf(ea * ea + eb * eb);
    out->err = e;
}

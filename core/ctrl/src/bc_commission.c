/* bc_commission.c - motor self-commissioning: R, L, psi_f. Phases, laws and statuses in bc_commission.h. */
#include "bldc/bc_commission.h"

#include <math.h>

#include "bldc/bc_math.h"
#include "bldc/bc_transform.h"

static int finite_pos(float v) { return isfinite(v) && v > 0.0f; }
static int finite_nonneg(float v) { return isfinite(v) && v >= 0.0f; }

int bc_commission_init(const bc_commission_params *p, bc_commission_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!finite_pos(p->ts) || !finite_nonneg(p->kp) || !finite_nonneg(p->ki) || !finite_pos(p->i_test) ||
        !finite_nonneg(p->t_ramp) || !finite_nonneg(p->t_settle) || !finite_pos(p->t_window) ||
        !finite_pos(p->v_pulse) || !finite_pos(p->i_if) || !finite_pos(p->if_accel) || !finite_pos(p->w_spin) ||
        !finite_pos(p->t_spin) || !finite_pos(p->psi_min) || !finite_pos(p->tol_move) ||
        !finite_pos(p->tol_follow) || !finite_pos(p->i_max) || !finite_pos(p->v_max) || !finite_nonneg(p->k_damp) ||
        !finite_nonneg(p->t_dead) || !(p->t_dead < p->ts) || !finite_nonneg(p->v_diode) ||
        !finite_pos(p->tol_noise) || !finite_pos(p->t_offset))
        return BC_ERR_PARAM;
    if (p->n_pulse < 1 || p->n_pulse > 1000 || p->pulse_len < 1 || p->pulse_len > 1000) return BC_ERR_PARAM;
    if (p->n_pulse_max < p->n_pulse || p->n_pulse_max > 1000) return BC_ERR_PARAM;
    if (p->i_test >= p->i_max || p->i_if >= p->i_max) return BC_ERR_PARAM;
    s->guard_p = (bc_guard_params){.i_max = p->i_max, .v_max = p->v_max};
    if (bc_guard_init(&s->guard_p, &s->guard) != BC_OK) return BC_ERR_PARAM;
    s->pi_p = (bc_pi_params){.kp = p->kp, .ki = p->ki, .ts = p->ts, .u_min = -p->v_max, .u_max = p->v_max};
    if (bc_pi_init(&s->pi_p, &s->pi_d) != BC_OK || bc_pi_init(&s->pi_p, &s->pi_q) != BC_OK) return BC_ERR_PARAM;
    s->phase = BC_COMM_PH_OFFSET;
    s->status = BC_COMM_RUNNING;
    s->t = 0.0f;
    s->k = 0;
    s->phi = s->w_phi = 0.0f;
    for (int x = 0; x < 3; ++x) s->i_off[x] = s->s_o[x] = 0.0f;
    s->sig_i = 0.0f;
    s->n_cmd = 0;
    s->b_a = s->b_b = 0.0f;
    s->b_n = 0;
    for (int j = 0; j < 2; ++j) {
        s->u_hist[j][0] = s->u_hist[j][1] = 0.0f;
        s->phi_hist[j] = 0.0f;
        s->i_prev[j] = 0.0f;
        s->u_hold[j] = 0.0f;
    }
    s->n = s->s_v = s->s_i = s->s_vb = s->v_lo = s->v_hi = s->s_e = s->s_e2 = s->s_dd = s->e_ang = 0.0f;
    s->l_num = s->l_den = 0.0f;
    s->V1 = s->I1 = s->V2 = s->I2 = 0.0f;
    s->R = s->L = s->psi = 0.0f;
    return BC_OK;
}

static void next_phase(bc_commission_state *s, int32_t phase)
{
    s->phase = phase;
    s->t = 0.0f;
    s->k = 0;
    s->n = s->s_v = s->s_i = s->s_vb = s->s_e = s->s_e2 = s->s_dd = s->e_ang = 0.0f;
    s->b_a = s->b_b = 0.0f;
    s->b_n = 0;
    s->v_lo = 3.0e38f;
    s->v_hi = -3.0e38f;
}

static void stop(bc_commission_state *s, int32_t status)
{
    s->status = status;
    s->phase = BC_COMM_PH_DONE;
}

/* A window sample of the R test: the voltage over [t_k-1, t_k] and the current at t_k into the means; the voltage
 * into the mean of its block (BC_COMM_BLOCKS a window), and each block's mean into the spread of alpha and the
 * largest |beta| (block means: the current's noise through k_p would dominate single samples). */
static void r_sample(const bc_commission_params *p, bc_commission_state *s, bc_ab u, bc_ab i)
{
    s->n += 1.0f;
    s->s_v += u.alpha;
    s->s_i += i.alpha;
    s->b_a += u.alpha;
    s->b_b += u.beta;
    s->b_n += 1;
    int32_t nb = (int32_t)(p->t_window / ((float)BC_COMM_BLOCKS * p->ts));
    if (s->b_n >= (nb > 1 ? nb : 1)) {
        float a = s->b_a / (float)s->b_n, b = s->b_b / (float)s->b_n;
        s->s_vb = fmaxf(s->s_vb, fabsf(b));
        s->v_lo = fminf(s->v_lo, a);
        s->v_hi = fmaxf(s->v_hi, a);
        s->b_a = s->b_b = 0.0f;
        s->b_n = 0;
    }
}

/* L's relative standard error from the current's noise within tol_noise after `pairs` pulse pairs: the sum
 * sum s (i_k - i_k-1) takes each sample's noise at the 2 pairs - 1 sign changes twice and at its ends once,
 * variance (8 pairs - 2) sig_i^2. */
static int l_precise(const bc_commission_params *p, const bc_commission_state *s, int32_t pairs)
{
    return s->sig_i * sqrtf((float)(8 * pairs - 2)) <= p->tol_noise * fabsf(s->l_den);
}

/* End of an R window: the means, and ROTOR_MOVING if the rotor's back-EMF shows. Returns 1 if it may go on. */
static int r_end(const bc_commission_params *p, bc_commission_state *s, float *V, float *I)
{
    *V = s->s_v / s->n;
    *I = s->s_i / s->n;
    float lim = p->tol_move * fabsf(*V);
    if (s->s_vb > lim || s->v_hi - s->v_lo > lim) {
        stop(s, BC_COMM_ROTOR_MOVING);
        return 0;
    }
    return 1;
}

void bc_commission_step(const bc_commission_params *p, bc_commission_state *s, const bc_ctrl_in *in,
                        bc_ctrl_out *out)
{
    for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
    out->flags = 0u;
    bc_legs_off(out);
    float i3[3];
    uint32_t why = bc_guard_step(&s->guard_p, &s->guard, in, i3);
    if (why && s->phase != BC_COMM_PH_DONE) stop(s, BC_COMM_FAULT);
    out->flags |= why;
    if (s->phase == BC_COMM_PH_DONE) {
        out->flags |= BC_FLAG_SAFE;
        out->diag[0] = (float)s->phase;
        out->diag[1] = s->R;
        out->diag[2] = s->L;
        out->diag[3] = s->psi;
        out->diag[7] = (float)s->status;
        return;
    }
    for (int x = 0; x < 3; ++x) i3[x] -= s->i_off[x]; /* the sensors' offsets, measured in OFFSET */
    bc_ab i = bc_clarke((bc_abc){i3[0], i3[1], i3[2]});
    bc_ab u = {s->u_hist[1][0], s->u_hist[1][1]}; /* applied over [t_k-1, t_k] */
    float phi_u = s->phi_hist[1];                /* its vector angle */
    float ts = p->ts;
    s->t += ts;
    s->k++;

    if (s->phase == BC_COMM_PH_OFFSET) {
        /* legs off, no current: the sensors read their offsets, and the spread of alpha is the noise */
        s->n += 1.0f;
        for (int x = 0; x < 3; ++x) s->s_o[x] += i3[x];
        s->s_i += i.alpha;
        s->s_e2 += i.alpha * i.alpha;
        if (s->t >= p->t_offset) {
            float m = s->s_i / s->n;
            s->sig_i = sqrtf(fmaxf(s->s_e2 / s->n - m * m, 0.0f));
            for (int x = 0; x < 3; ++x) s->i_off[x] = s->s_o[x] / s->n;
            next_phase(s, BC_COMM_PH_ALIGN);
        }
        out->diag[0] = (float)s->phase;
        out->diag[7] = (float)s->status;
        return;
    }

    float i_ref = p->i_test;
    int pulse = 0;     /* 1: open loop, u_hold + the pulse */
    float v_add = 0.0f;
    switch (s->phase) {
    case BC_COMM_PH_ALIGN:
        /* at pi/2 with the current rising over t_ramp, then turned slowly to 0 over t_ramp (a rotor that sat at the
         * unstable point of one angle is pulled off it by the other) */
        if (p->t_ramp > 0.0f) {
            i_ref *= bc_clampf(s->t / p->t_ramp, 0.0f, 1.0f);
            s->phi = 0.5f * BC_PI_F * bc_clampf(2.0f - s->t / p->t_ramp, 0.0f, 1.0f);
        }
        if (s->t >= 2.0f * p->t_ramp) {
            s->phi = 0.0f;
            next_phase(s, BC_COMM_PH_R_HI);
        }
        break;
    case BC_COMM_PH_R_HI:
        if (s->t > p->t_settle) r_sample(p, s, u, i);
        if (s->t >= p->t_settle + p->t_window) {
            if (!r_end(p, s, &s->V2, &s->I2)) break;
            if (fabsf(s->I2) < 0.5f * p->i_test) {
                stop(s, BC_COMM_NO_CURRENT);
                break;
            }
            next_phase(s, BC_COMM_PH_R_LO);
        }
        break;
    case BC_COMM_PH_R_LO:
        i_ref = 0.5f * p->i_test;
        if (s->t > p->t_settle) r_sample(p, s, u, i);
        if (s->t >= p->t_settle + p->t_window) {
            if (!r_end(p, s, &s->V1, &s->I1)) break;
            s->R = (s->V2 - s->V1) / (s->I2 - s->I1); /* R = (V_2 - V_1) / (I_2 - I_1) */
            if (!isfinite(s->R)) s->R = 0.0f;
            s->u_hold[0] = s->pi_d.x;
            s->u_hold[1] = s->pi_q.x;
            s->l_num = s->l_den = 0.0f;
            s->n_cmd = 2 * p->n_pulse * p->pulse_len;
            next_phase(s, BC_COMM_PH_L);
        }
        break;
    case BC_COMM_PH_L: {
        i_ref = 0.5f * p->i_test;
        int32_t c = s->k - 1; /* this sample's command index in the phase */
        /* measurement: the interval [t_k-1, t_k] carries the command of two samples ago, c - 2 */
        int32_t cm = c - 2;
        if (cm >= 0 && cm < s->n_cmd) {
            float sg = ((cm / p->pulse_len) % 2 == 0) ? 1.0f : -1.0f;
            float im = 0.5f * (s->i_prev[0] + i.alpha);
            /* L = sum s (u - V_1 - R (i_mean - I_1)) T_s / sum s (i_k - i_k-1) */
            s->l_num += sg * (u.alpha - s->V1 - s->R * (im - s->I1)) * ts;
            s->l_den += sg * (i.alpha - s->i_prev[0]);
        }
        int32_t pairs = s->n_cmd / (2 * p->pulse_len);
        /* at the train's end, a pair more while L's standard error from the noise is above tol_noise (the sums
         * lack the last two intervals: the estimate errs on the safe side) */
        if (c == s->n_cmd && pairs < p->n_pulse_max && !l_precise(p, s, pairs)) s->n_cmd += 2 * p->pulse_len;
        int32_t n_cmd = s->n_cmd;
        if (c < n_cmd) {
            pulse = 1;
            v_add = ((c / p->pulse_len) % 2 == 0) ? p->v_pulse : -p->v_pulse;
        } else if (c < n_cmd + 2) {
            pulse = 1;
        } else {
            s->L = (s->l_den != 0.0f) ? s->l_num / s->l_den : 0.0f;
            if (!isfinite(s->L)) s->L = 0.0f;
            if (!l_precise(p, s, pairs)) {
                stop(s, BC_COMM_NOISY); /* n_pulse_max pairs and still not precise */
                break;
            }
            if (s->t >= (float)(n_cmd + 2) * ts + p->t_settle) next_phase(s, BC_COMM_PH_SPIN);
        }
        break;
    }
    case BC_COMM_PH_SPIN: {
        /* the current rises from i_test/2 to i_if over the first t_ramp (the vector still), then it turns with the
         * ramp: the whole I/f torque is there before the acceleration asks for its share */
        float a = p->t_ramp > 0.0f ? bc_clampf(s->t / p->t_ramp, 0.0f, 1.0f) : 1.0f;
        i_ref = 0.5f * p->i_test + a * (p->i_if - 0.5f * p->i_test);
        if (s->t > p->t_ramp) s->w_phi = fminf(s->w_phi + p->if_accel * ts, p->w_spin);
        float t_top = p->t_ramp + p->w_spin / p->if_accel + p->t_settle;
        if (s->t > t_top) {
            /* e' = u' - R i' - j omega L i' (u' at the interval's mid-angle, i' at phi_k) */
            float pm = phi_u + 1.5f * s->w_phi * ts; /* the interval [t_k-1, t_k]: 1.5 samples after its command */
            float cu = cosf(pm), su = sinf(pm), ci = cosf(s->phi), si = sinf(s->phi);
            float ud = cu * u.alpha + su * u.beta, uq = -su * u.alpha + cu * u.beta;
            float id = ci * i.alpha + si * i.beta, iq = -si * i.alpha + ci * i.beta;
            float ed = ud - s->R * id + s->w_phi * s->L * iq;
            float eq = uq - s->R * iq - s->w_phi * s->L * id;
            float e = sqrtf(ed * ed + eq * eq);
            /* the rotor's travel against the vector: the angle of e' (q of the rotor) advances by dd */
            float ang = atan2f(eq, ed);
            if (s->n > 0.0f) {
                float dd = ang - s->e_ang;
                dd = dd > BC_PI_F ? dd - BC_TWO_PI_F : (dd < -BC_PI_F ? dd + BC_TWO_PI_F : dd);
                s->s_dd += dd;
            }
            s->e_ang = ang;
            s->n += 1.0f;
            s->s_e += e;
            s->s_e2 += e * e;
        }
        if (s->t >= t_top + p->t_spin) {
            float m = s->s_e / s->n;
            float var = fmaxf(s->s_e2 / s->n - m * m, 0.0f);
            /* psi_f = sum |e'| T_s / (rotor travel) = sum |e'| T_s / (n w_spin T_s + sum dd) */
            float travel = s->n * p->w_spin * ts + s->s_dd;
            s->psi = travel > 0.0f ? s->s_e * ts / travel : 0.0f;
            if (!(sqrtf(var) <= p->tol_follow * m) || !(m >= p->w_spin * p->psi_min)) {
                stop(s, BC_COMM_NOT_FOLLOWING);
            } else {
                stop(s, BC_COMM_DONE);
            }
        }
        break;
    }
    default:
        stop(s, BC_COMM_FAULT);
        break;
    }
    s->i_prev[0] = i.alpha;
    s->i_prev[1] = i.beta;
    if (s->phase == BC_COMM_PH_DONE) {
        out->flags |= BC_FLAG_SAFE;
        out->diag[0] = (float)s->phase;
        out->diag[1] = s->R;
        out->diag[2] = s->L;
        out->diag[3] = s->psi;
        out->diag[7] = (float)s->status;
        s->u_hist[1][0] = s->u_hist[0][0];
        s->u_hist[1][1] = s->u_hist[0][1];
        return;
    }

    /* the current vector: PIs in the frame of phi, the voltage rotated back at phi + 1.5 omega T_s */
    float c = cosf(s->phi), sn = sinf(s->phi);
    float id = c * i.alpha + sn * i.beta, iq = -sn * i.alpha + c * i.beta;
    float iq_ref = 0.0f;
    if (s->phase == BC_COMM_PH_ALIGN || s->phase == BC_COMM_PH_R_HI || s->phase == BC_COMM_PH_R_LO) {
        /* damping: the q PI's integrator, less the resistive drop, is the swinging rotor's back-EMF omega_e psi_f
         * (d on the current); i_q,ref = -k_damp (x_q - R i_q) brakes it. The integrator, not the applied voltage:
         * through the proportional gain the loop -k_p k_damp would chatter (k_p k_damp > 1) */
        iq_ref = bc_clampf(-p->k_damp * (s->pi_q.x - s->R * iq), -0.5f * p->i_test, 0.5f * p->i_test);
    }
    float e_d = i_ref - id, e_q = iq_ref - iq;
    float ud, uq;
    if (pulse) {
        ud = s->u_hold[0] + v_add;
        uq = s->u_hold[1];
    } else {
        ud = bc_pi_output(&s->pi_p, &s->pi_d, e_d, 0.0f);
        uq = bc_pi_output(&s->pi_p, &s->pi_q, e_q, 0.0f);
        ud = bc_pi_limit(&s->pi_p, ud);
        uq = bc_pi_limit(&s->pi_p, uq);
        bc_pi_update(&s->pi_p, &s->pi_d, e_d, ud, ud);
        bc_pi_update(&s->pi_p, &s->pi_q, e_q, uq, uq);
    }
    float pv = s->phi + 1.5f * s->w_phi * ts;
    float cv = cosf(pv), sv = sinf(pv);
    bc_ab uab = {cv * ud - sv * uq, sv * ud + cv * uq};
    float duty[3];
    int clipped = bc_svm(bc_clarke_inv(uab), in->v_dc, duty);
    if (clipped) {
        /* the bus is not enough: with less than half the current it drives, the circuit is open */
        stop(s, fabsf(id) < 0.5f * fabsf(i_ref) ? BC_COMM_NO_CURRENT : BC_COMM_SATURATED);
        out->flags |= BC_FLAG_SAFE | BC_FLAG_SATURATED;
        out->diag[7] = (float)s->status;
        return;
    }
    for (int x = 0; x < 3; ++x) {
        out->leg[x].mode = BC_LEG_PWM;
        out->leg[x].duty = duty[x];
    }
    /* the voltage these duties apply, the dead time's loss or gain at each leg's edges (bc_commission.h), with the
     * currents of the interval they apply to (the vector turned 1.5 samples on) */
    float vt = (in->v_dc + 2.0f * p->v_diode) * p->t_dead / (2.0f * ts), b = 0.02f * fmaxf(p->i_test, p->i_if);
    float vx[3] = {duty[0] * in->v_dc, duty[1] * in->v_dc, duty[2] * in->v_dc};
    if (vt > 0.0f) { /* without a dead time the duties give the voltage as it is */
        float kr = s->L > 0.0f ? in->v_dc * ts / (3.0f * s->L) : 0.0f;
        float cr = cosf(1.5f * s->w_phi * ts), sr = sinf(1.5f * s->w_phi * ts);
        bc_abc ia = bc_clarke_inv((bc_ab){cr * i.alpha - sr * i.beta, sr * i.alpha + cr * i.beta});
        float ix[3] = {ia.a, ia.b, ia.c};
        for (int x = 0; x < 3; ++x) {
            float dx = duty[x], rho = 2.0f * dx * (1.0f - dx);
            for (int y = 0; y < 3; ++y) {
                if (y != x) rho -= fminf(dx, duty[y]) - dx * duty[y];
            }
            rho = fmaxf(kr * rho, 0.0f);
            float w = bc_clampf((ix[x] - rho) / b, -1.0f, 1.0f) + bc_clampf((ix[x] + rho) / b, -1.0f, 1.0f);
            vx[x] -= 0.5f * vt * w;
        }
    }
    bc_ab ua = bc_clarke((bc_abc){vx[0], vx[1], vx[2]});
    s->u_hist[1][0] = s->u_hist[0][0];
    s->u_hist[1][1] = s->u_hist[0][1];
    s->phi_hist[1] = s->phi_hist[0];
    s->u_hist[0][0] = ua.alpha;
    s->u_hist[0][1] = ua.beta;
    s->phi_hist[0] = s->phi;
    s->phi = bc_wrap_2pi(s->phi + s->w_phi * ts);
    out->diag[0] = (float)s->phase;
    out->diag[1] = s->R;
    out->diag[2] = s->L;
    out->diag[3] = s->psi;
    out->diag[4] = id;
    out->diag[5] = iq;
    out->diag[6] = s->phi;
    out->diag[7] = (float)s->status;
}

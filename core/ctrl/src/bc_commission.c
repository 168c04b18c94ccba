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
        !finite_pos(p->tol_noise) || !finite_pos(p->t_offset) || !(p->i_fs >= 0.0f))
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
    s->d_cmd[0] = s->d_cmd[1] = s->d_cmd[2] = s->v_cmd = 0.0f;
    s->has_cmd = 0;
    s->odd = 0u;
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

/* The dead time's loss or gain (alpha-beta, V) over the half period [t_k, t_k+1] the last command's duties d_cmd
 * apply to, from the phase currents i3 at t_k, the back-EMF and resistive drop eb (phase to star, V) and whether
 * t_k is a carrier peak: the half period simulated event by event (bc_commission.h, "dead time"). */
static bc_ab dt_voltage(const bc_commission_params *p, const bc_commission_state *s, const float i3[3],
                        const float eb[3], int peak)
{
    float td = p->t_dead, ts = p->ts, v = s->v_cmd, vd = p->v_diode;
    const float *d = s->d_cmd;
    float w[3];
    if (!(td > 0.0f)) return (bc_ab){0.0f, 0.0f}; /* without a dead time the duties give the voltage */
    if (!(s->L > 0.0f)) {
        /* L not measured yet: the loss by the current's sign, over a band of 2 % of the larger test current */
        float vt = (v + 2.0f * vd) * td / (2.0f * ts), b = 0.02f * fmaxf(p->i_test, p->i_if);
        for (int x = 0; x < 3; ++x) w[x] = -vt * bc_clampf(i3[x] / b, -1.0f, 1.0f);
        return bc_clarke((bc_abc){w[0], w[1], w[2]});
    }
    float to = peak ? 0.0f : v; /* the level each leg goes to at its edge */
    float cur[3], lv[3], area[3], te[3], tend[3];
    int todo[3], indt[3], flt[3];
    for (int x = 0; x < 3; ++x) {
        cur[x] = i3[x];
        area[x] = 0.0f;
        todo[x] = d[x] > 0.0f && d[x] < 1.0f; /* an edge in this half period */
        lv[x] = peak ? (d[x] > 0.0f ? v : 0.0f) : (d[x] >= 1.0f ? v : 0.0f);
        te[x] = peak ? d[x] * ts : (1.0f - d[x]) * ts;
        tend[x] = ts;
        indt[x] = flt[x] = 0;
    }
    float t = 0.0f;
    for (int it = 0; it < 16; ++it) {
        /* a leg in its dead time: its diode's rail by the current's sign; at zero current it floats where the
         * current stays zero, v_x = 1.5 e_x + (v_y + v_z) / 2 (within the rails) */
        for (int x = 0; x < 3; ++x) {
            if (!indt[x]) continue;
            if (flt[x]) {
                float o = lv[(x + 1) % 3] + lv[(x + 2) % 3];
                lv[x] = bc_clampf(1.5f * eb[x] + 0.5f * o, 0.0f, v);
            } else {
                lv[x] = cur[x] > 0.0f ? -vd : v + vd;
            }
        }
        float vn = (lv[0] + lv[1] + lv[2]) / 3.0f, sl[3];
        for (int x = 0; x < 3; ++x) sl[x] = flt[x] ? 0.0f : (lv[x] - vn - eb[x]) / s->L; /* di/dt */
        float tn = ts;
        int kind = 0, who = 0;
        for (int x = 0; x < 3; ++x) {
            if (todo[x] && te[x] < tn) {
                tn = te[x];
                kind = 1;
                who = x;
            }
            if (indt[x] && tend[x] < tn) {
                tn = tend[x];
                kind = 2;
                who = x;
            }
            if (indt[x] && !flt[x] && cur[x] * sl[x] < 0.0f) {
                float tz = t - cur[x] / sl[x];
                if (tz < tn) {
                    tn = tz;
                    kind = 3;
                    who = x;
                }
            }
        }
        if (tn < t) tn = t;
        for (int x = 0; x < 3; ++x) {
            area[x] += lv[x] * (tn - t);
            cur[x] += sl[x] * (tn - t);
        }
        t = tn;
        if (kind == 0) break;
        if (kind == 1) { /* the edge: both switches off for t_dead */
            todo[who] = 0;
            indt[who] = 1;
            tend[who] = t + td;
        } else if (kind == 2) { /* the dead time's end: the switch takes the leg to its new level */
            indt[who] = flt[who] = 0;
            lv[who] = to;
        } else { /* the current reached zero inside the dead time */
            cur[who] = 0.0f;
            flt[who] = 1;
        }
    }
    for (int x = 0; x < 3; ++x) {
        w[x] = area[x] / ts - d[x] * v;
        if (!isfinite(w[x])) w[x] = 0.0f; /* measurements out of any range: no correction rather than NaN */
    }
    return bc_clarke((bc_abc){w[0], w[1], w[2]});
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
    /* a measured phase at the sensors' full scale (the routine's own i_fs, else the one the input states):
     * saturated, not the current; named before the guard's over-current verdict on the same reading */
    float i_fs = p->i_fs > 0.0f ? p->i_fs : in->i_fs;
    if (i_fs > 0.0f && s->phase != BC_COMM_PH_DONE) {
        for (int x = 0; x < 3; ++x) {
            if ((in->i_mask & (1u << x)) && fabsf(in->i_abc[x]) >= i_fs) stop(s, BC_COMM_CLIPPED);
        }
    }
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
    int peak = (int)s->odd; /* t_k a carrier peak (odd k: the samples alternate from a valley) */
    s->odd ^= 1u;
    if (s->has_cmd) {
        /* the last command's half period starts now: its dead-time loss or gain from these currents, against the
         * back-EMF and resistive drop of the half period before, e + R i = u - L (i_k - i_k-1) / T_s */
        bc_abc e3 = bc_clarke_inv((bc_ab){s->u_hist[1][0] - s->L * (i.alpha - s->i_prev[0]) / p->ts,
                                          s->u_hist[1][1] - s->L * (i.beta - s->i_prev[1]) / p->ts});
        float eb[3] = {e3.a, e3.b, e3.c};
        bc_ab w = dt_voltage(p, s, i3, eb, peak);
        s->u_hist[0][0] += w.alpha;
        s->u_hist[0][1] += w.beta;
        s->has_cmd = 0;
    }
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
            if (pairs >= p->n_pulse_max && !l_precise(p, s, pairs)) {
                /* n_pulse_max pairs and still not precise. Fewer pairs were found precise at the train's end, and
                 * the two intervals measured since then do not undo that (their noise could, by a hair: the
                 * routine ended NOISY with pairs to spare, mn3110-780kv at 1 % dead time and 1 % noise) */
                stop(s, BC_COMM_NOISY);
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
    /* the voltage these duties apply without the dead time; its loss or gain is added at the next sample, when the
     * currents at the start of the half period they apply to are measured (dt_voltage) */
    bc_ab ua = bc_clarke((bc_abc){duty[0] * in->v_dc, duty[1] * in->v_dc, duty[2] * in->v_dc});
    for (int x = 0; x < 3; ++x) s->d_cmd[x] = duty[x];
    s->v_cmd = in->v_dc;
    s->has_cmd = 1;
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

/* bc_hallcal.c - six-edge Hall calibration. Equations in bc_hallcal.h. */
#include "bldc/bc_hallcal.h"

#include <math.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_transform.h"

#define PI6_F (BC_PI_F / 6.0f)
#define PI12_F (BC_PI_F / 12.0f)

static int fin_pos(float v) { return isfinite(v) && v > 0.0f; }

static float wrap_pm(float th)
{
    th = fmodf(th, BC_TWO_PI_F);
    if (th <= -BC_PI_F) th += BC_TWO_PI_F;
    if (th > BC_PI_F) th -= BC_TWO_PI_F;
    return th;
}

int bc_hallcal_init(const bc_hallcal_params *p, bc_hallcal_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (p->method != BC_HALLCAL_SPEED && p->method != BC_HALLCAL_OPENLOOP) return BC_ERR_PARAM;
    if (p->n_rev < 1 || p->n_rev > BC_HALLCAL_REV_MAX || !fin_pos(p->f_tick) || !fin_pos(p->ts)) return BC_ERR_PARAM;
    if (p->method == BC_HALLCAL_SPEED && (!fin_pos(p->t_max) || !(p->speed_tol > 0.0f && p->speed_tol < 1.0f)))
        return BC_ERR_PARAM;
    if (p->method == BC_HALLCAL_OPENLOOP &&
        (!fin_pos(p->v_align) || !(isfinite(p->v_emf) && p->v_emf >= 0.0f) || !fin_pos(p->omega_ol) ||
         !(isfinite(p->t_align) && p->t_align >= 0.0f) ||
         !(p->lag_max > 0.0f && p->lag_max <= 0.5f * BC_PI_F) || !fin_pos(p->i_max) || !fin_pos(p->v_max)))
        return BC_ERR_PARAM;
    s->status = BC_HALLCAL_BUSY;
    s->started = 0;
    s->sector = -1;
    s->n_edges = 0u;
    s->dir = 0;
    s->j0 = -1;
    s->n_in_rev = 0;
    s->revs = 0;
    s->tick_ref = 0u;
    s->t_min = 0.0f;
    s->t_max = 0.0f;
    s->t_sum = 0.0f;
    for (int j = 0; j < 6; ++j) {
        s->off[j] = 0u;
        s->off_j[j] = 0;
        s->acc[j] = 0.0f;
        s->acc_b[j] = 0.0f;
        s->cnt[j] = 0;
        s->cnt_b[j] = 0;
        s->table[j] = bc_sector_angle(j);
    }
    s->k = 0;
    s->phase = 0;
    s->theta_cmd = 0.0f;
    s->omega_cmd = 0.0f;
    s->travel = 0.0f;
    s->pos = 0;
    s->pos_max = 0;
    s->guard_p = (bc_guard_params){.i_max = p->method == BC_HALLCAL_OPENLOOP ? p->i_max : 1.0f,
                                   .v_max = p->method == BC_HALLCAL_OPENLOOP ? p->v_max : 1.0f};
    if (bc_guard_init(&s->guard_p, &s->guard) != BC_OK) return BC_ERR_PARAM;
    return BC_OK;
}

uint32_t bc_hallcal_result(const bc_hallcal_state *s, bc_hall_table *t)
{
    if (s == 0) return BC_HALLCAL_FAIL;
    if ((s->status & BC_HALLCAL_DONE) && t != 0) {
        t->set = 1;
        for (int j = 0; j < 6; ++j) {
            t->fwd[j] = s->table[j];
            t->bwd[j] = s->table[j];
        }
    }
    return s->status;
}

static void fail(bc_hallcal_state *s, uint32_t why)
{
    s->status = (s->status & ~(BC_HALLCAL_BUSY | BC_HALLCAL_DONE)) | BC_HALLCAL_FAIL | why;
}

/* Accept a candidate table of offsets d_j = wrap(table_j - a_j): every |d_j| < pi/6, else E_RANGE. */
static void finish(bc_hallcal_state *s, const float d[6])
{
    for (int j = 0; j < 6; ++j) {
        if (!(isfinite(d[j]) && fabsf(d[j]) < PI6_F)) {
            fail(s, BC_HALLCAL_E_RANGE);
            return;
        }
    }
    for (int j = 0; j < 6; ++j) {
        float a = bc_sector_angle(j) + d[j];
        s->table[j] = a < 0.0f ? a + BC_TWO_PI_F : (a >= BC_TWO_PI_F ? a - BC_TWO_PI_F : a);
    }
    s->status = BC_HALLCAL_DONE;
}

/* (a) an edge into `sector` at `tick` in direction dir */
static void speed_edge(const bc_hallcal_params *p, bc_hallcal_state *s, int sector, int dir, uint32_t tick)
{
    int j = dir > 0 ? sector : (sector + 1) % 6; /* the edge crossed */
    if (s->j0 < 0) {
        s->j0 = j;
        s->tick_ref = tick;
        s->dir = dir;
        s->n_in_rev = 0;
        return;
    }
    if (dir != s->dir) {
        fail(s, BC_HALLCAL_E_REVERSAL);
        return;
    }
    if (j != s->j0) {
        if (s->n_in_rev >= 5) { /* cannot happen with neighbour codes in one direction; defensive */
            fail(s, BC_HALLCAL_E_ORDER);
            return;
        }
        s->off[s->n_in_rev] = tick - s->tick_ref;
        s->off_j[s->n_in_rev] = j;
        s->n_in_rev += 1;
        return;
    }
    /* the reference edge again: one revolution */
    uint32_t t_rev_ticks = tick - s->tick_ref;
    if (s->n_in_rev != 5 || t_rev_ticks == 0u) {
        fail(s, BC_HALLCAL_E_ORDER);
        return;
    }
    float t_rev = (float)t_rev_ticks / p->f_tick;
    for (int k = 0; k < 5; ++k) s->acc[s->off_j[k]] += BC_TWO_PI_F * ((float)s->off[k] / (float)t_rev_ticks);
    s->t_min = s->revs == 0 ? t_rev : fminf(s->t_min, t_rev);
    s->t_max = s->revs == 0 ? t_rev : fmaxf(s->t_max, t_rev);
    s->t_sum += t_rev;
    s->revs += 1;
    s->tick_ref = tick;
    s->n_in_rev = 0;
    if (s->revs < p->n_rev) return;
    float mean = s->t_sum / (float)s->revs;
    if (!(s->t_max - s->t_min <= p->speed_tol * mean)) {
        fail(s, BC_HALLCAL_E_SPEED);
        return;
    }
    /* table_j = a_j0 + dir phi_j - c, c = mean_j wrap(a_j0 + dir phi_j - a_j) */
    float raw[6], c = 0.0f;
    for (int q = 0; q < 6; ++q) {
        float phi = q == s->j0 ? 0.0f : s->acc[q] / (float)s->revs;
        raw[q] = wrap_pm(bc_sector_angle(s->j0) + (float)s->dir * phi - bc_sector_angle(q));
        c += raw[q];
    }
    c /= 6.0f;
    float d[6];
    for (int q = 0; q < 6; ++q) d[q] = raw[q] - c;
    finish(s, d);
}

/* (b) an edge into `sector` in direction dir at the commanded angle th */
static void openloop_edge(const bc_hallcal_params *p, bc_hallcal_state *s, int sector, int dir, float th)
{
    int sweep = s->phase == 1 ? 1 : -1;
    s->pos += dir * sweep;
    if (s->pos < s->pos_max - 1) {
        fail(s, BC_HALLCAL_E_REVERSAL);
        return;
    }
    if (s->pos <= s->pos_max) return; /* swinging back over an edge already counted */
    s->pos_max = s->pos;
    if (dir != sweep || s->travel < BC_PI_F) return;
    int j = dir > 0 ? sector : (sector + 1) % 6;
    float d = wrap_pm(th - bc_sector_angle(j));
    if (dir > 0) {
        if (s->cnt[j] < p->n_rev) {
            s->acc[j] += d;
            s->cnt[j] += 1;
        }
    } else if (s->cnt_b[j] < p->n_rev) {
        s->acc_b[j] += d;
        s->cnt_b[j] += 1;
    }
}

static void openloop_finish(const bc_hallcal_params *p, bc_hallcal_state *s)
{
    float d[6];
    for (int j = 0; j < 6; ++j) {
        if (s->cnt[j] < p->n_rev || s->cnt_b[j] < p->n_rev) {
            fail(s, BC_HALLCAL_E_FEW);
            return;
        }
        float f = s->acc[j] / (float)s->cnt[j], b = s->acc_b[j] / (float)s->cnt_b[j];
        if (!(f - b >= -PI12_F && f - b <= p->lag_max)) {
            fail(s, BC_HALLCAL_E_RANGE);
            return;
        }
        d[j] = 0.5f * (f + b);
    }
    finish(s, d);
}

void bc_hallcal_step(const bc_hallcal_params *p, bc_hallcal_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_legs_off(out);
    out->flags = 0u;
    for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
    int ol = p->method == BC_HALLCAL_OPENLOOP;

    float i3[3];
    uint32_t why = ol ? bc_guard_step(&s->guard_p, &s->guard, in, i3) : 0u;
    int sector = bc_hall_sector(in->hall);
    if (sector < 0) why |= BC_FLAG_HALL_INVALID;
    if (why) out->flags |= why | BC_FLAG_SAFE;
    if (s->status & BC_HALLCAL_BUSY) {
        if (why) {
            fail(s, (why & BC_FLAG_HALL_INVALID) ? BC_HALLCAL_E_INVALID : BC_HALLCAL_E_INPUT);
        } else {
            float t = (float)s->k * p->ts;
            s->k += 1;
            uint32_t new_edges = s->started ? in->n_edges - s->n_edges : 0u;
            if (!s->started) {
                s->started = 1;
                s->sector = sector;
            } else if (sector != s->sector || new_edges > 0u) {
                int dd = (sector - s->sector + 6) % 6;
                int dir = dd == 1 ? 1 : (dd == 5 ? -1 : 0);
                if (dir == 0 || new_edges != 1u) {
                    fail(s, BC_HALLCAL_E_ORDER);
                } else if (ol) {
                    if (s->phase == 1 || s->phase == 2) {
                        float late = (float)(uint32_t)(in->tick_now - in->tick_edge) / p->f_tick;
                        float sweep = s->phase == 1 ? 1.0f : -1.0f;
                        float th = s->theta_cmd - sweep * s->omega_cmd * late;
                        openloop_edge(p, s, sector, dir, th);
                    }
                } else {
                    speed_edge(p, s, sector, dir, in->tick_edge);
                }
                s->sector = sector;
            }
            s->n_edges = in->n_edges;
            if (!ol && (s->status & BC_HALLCAL_BUSY) && t > p->t_max) fail(s, BC_HALLCAL_E_FEW);
            if (ol && (s->status & BC_HALLCAL_BUSY)) {
                /* the vector: align, forward, backward */
                float sweep_len = BC_TWO_PI_F * (float)(p->n_rev + 1);
                float step;
                if (s->phase == 0 && t >= p->t_align) {
                    s->phase = 1;
                    s->travel = 0.0f;
                    s->pos = s->pos_max = 0;
                } else if (s->phase == 1 || s->phase == 2) {
                    /* speed ramp at omega_ol^2 / pi: omega_ol after pi/2 of travel */
                    s->omega_cmd = fminf(p->omega_ol, s->omega_cmd + p->omega_ol * p->omega_ol / BC_PI_F * p->ts);
                    step = s->omega_cmd * p->ts;
                    s->theta_cmd = wrap_pm(s->theta_cmd + (s->phase == 1 ? step : -step));
                    s->travel += step;
                    if (s->travel >= sweep_len) {
                        if (s->phase == 1) {
                            s->phase = 2;
                            s->travel = 0.0f;
                            s->omega_cmd = 0.0f;
                            s->pos = s->pos_max = 0;
                        } else {
                            s->phase = 3;
                            openloop_finish(p, s);
                        }
                    }
                }
                if (s->status & BC_HALLCAL_BUSY) {
                    /* u_d = v_align, u_q = dir v_emf omega_cmd / omega_ol at theta_d = theta_cmd - pi; min-max SVM */
                    float thd = s->theta_cmd - BC_PI_F;
                    float sw = s->phase == 1 ? 1.0f : (s->phase == 2 ? -1.0f : 0.0f);
                    bc_dq u = {p->v_align, sw * p->v_emf * (s->omega_cmd / p->omega_ol)};
                    bc_abc v = bc_clarke_inv(bc_park_inv(u, sinf(thd), cosf(thd)));
                    float duty[3];
                    if (bc_svm(v, in->v_dc, duty) != BC_SVM_LINEAR) out->flags |= BC_FLAG_SATURATED;
                    for (int x = 0; x < 3; ++x) {
                        out->leg[x].mode = BC_LEG_PWM;
                        out->leg[x].duty = (duty[x] >= 0.0f && duty[x] <= 1.0f) ? duty[x] : 0.5f;
                    }
                }
            }
        }
    }
    if (!(s->status & BC_HALLCAL_BUSY)) {
        bc_legs_off(out);
        if (ol) out->flags |= BC_FLAG_SAFE;
    }
    for (int j = 0; j < 6; ++j) out->diag[j] = s->table[j];
    out->diag[6] = (float)s->status;
    out->diag[7] = ol ? wrap_pm(s->theta_cmd) : (float)s->revs;
    if (!isfinite(out->diag[7])) out->diag[7] = 0.0f;
}

/* bc_hall.c - Hall sector, speed and angle interpolation or tracking. Equations in bc_hall.h. */
#include "bldc/bc_hall.h"

#include <math.h>

#include "bldc/bc_commutation.h"

#define PI3_F (BC_PI_F / 3.0f)
#define PI6_F (BC_PI_F / 6.0f)
#define PI12_F (BC_PI_F / 12.0f)

static float wrap_2pi(float th)
{
    /* within one turn of the range (the angles of a running decoder) no fmodf: its remainder is th itself, or
     * th - 2 pi exactly (Sterbenz: 2 pi <= th < 4 pi); -2 pi (fmodf: -0) and anything else (NaN stays NaN) take
     * fmodf */
    if (th >= BC_TWO_PI_F && th < 2.0f * BC_TWO_PI_F) th -= BC_TWO_PI_F;
    else if (!(th > -BC_TWO_PI_F && th < BC_TWO_PI_F)) th = fmodf(th, BC_TWO_PI_F);
    if (th < 0.0f) th += BC_TWO_PI_F;
    if (th >= BC_TWO_PI_F) th = 0.0f;
    return th;
}

/* wrap into (-pi, pi] */
static float wrap_pm(float th)
{
    th = wrap_2pi(th);
    return th > BC_PI_F ? th - BC_TWO_PI_F : th;
}

void bc_hall_table_nominal(bc_hall_table *t)
{
    t->set = 1;
    for (int j = 0; j < 6; ++j) {
        t->fwd[j] = bc_sector_angle(j);
        t->bwd[j] = bc_sector_angle(j);
    }
}

int bc_hall_table_check(const bc_hall_table *t)
{
    if (t == 0) return BC_ERR_PARAM;
    if (t->set == 0) return BC_OK;
    if (t->set != 1) return BC_ERR_PARAM;
    for (int j = 0; j < 6; ++j) {
        float a = bc_sector_angle(j);
        if (!isfinite(t->fwd[j]) || !isfinite(t->bwd[j]) || fabsf(t->fwd[j]) > 64.0f || fabsf(t->bwd[j]) > 64.0f)
            return BC_ERR_PARAM;
        if (!(fabsf(wrap_pm(t->fwd[j] - a)) < PI6_F) || !(fabsf(wrap_pm(t->bwd[j] - a)) < PI6_F)) return BC_ERR_PARAM;
    }
    return BC_OK;
}

int bc_hall_init(const bc_hall_params *p, bc_hall_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!(isfinite(p->f_tick) && p->f_tick > 0.0f) || !(isfinite(p->omega_min) && p->omega_min > 0.0f) ||
        !isfinite(p->theta_offset))
        return BC_ERR_PARAM;
    if (p->mode != BC_HALL_INTERP && p->mode != BC_HALL_PLL) return BC_ERR_PARAM;
    if (p->mode == BC_HALL_PLL && !(p->pll_edges >= 1.0f && p->pll_edges <= 1000.0f)) return BC_ERR_PARAM;
    if (bc_hall_table_check(&p->table) != BC_OK) return BC_ERR_PARAM;
    s->code = 0u;
    s->n_edges = 0u;
    s->tick_edge = 0u;
    s->tick_prev = 0u;
    s->sector = -1;
    s->dir = 0;
    s->n_run = 0;
    s->started = 0;
    s->pll_on = 0;
    s->pll_theta = 0.0f;
    s->pll_omega = 0.0f;
    s->pll_acc = 0.0f;
    return BC_OK;
}

/* Table lookups (set = 1); the nominal expressions are kept in the callers for set = 0. */
static float fwd_width(const bc_hall_table *t, int s) { return wrap_2pi(t->fwd[(s + 1) % 6] - t->fwd[s]); }
static float bwd_width(const bc_hall_table *t, int s) { return wrap_2pi(t->bwd[(s + 1) % 6] - t->bwd[s]); }

float bc_hall_entry_lead(const bc_hall_params *p, int sector, int dir)
{
    if (p == 0 || !p->table.set || sector < 0 || sector > 5 || (dir != 1 && dir != -1)) return 0.0f;
    if (dir > 0) return wrap_pm(p->table.fwd[sector] - bc_sector_angle(sector));
    int j = (sector + 1) % 6;
    return -wrap_pm(p->table.bwd[j] - bc_sector_angle(j));
}

void bc_hall_step(const bc_hall_params *p, bc_hall_state *s, const bc_ctrl_in *in, bc_hall_out *out)
{
    int sector = bc_hall_sector(in->hall);
    out->edge = 0;
    if (sector < 0) {
        out->valid = 0;
        out->sector = -1;
        out->dir = 0;
        out->speed_valid = 0;
        out->omega_e = 0.0f;
        out->theta = 0.0f;
        s->n_run = 0;
        s->pll_on = 0;
        s->n_edges = in->n_edges;
        return;
    }
    /* edges since the last step */
    uint32_t new_edges = s->started ? in->n_edges - s->n_edges : 0u;
    if (!s->started || s->sector < 0) {
        s->sector = sector;
        s->code = in->hall;
        s->started = 1;
        s->n_run = 0;
        s->dir = 0;
        s->tick_edge = in->tick_edge;
    } else if (sector != s->sector || new_edges > 0u) {
        int d = (sector - s->sector + 6) % 6; /* 1: forward, 5: backward */
        int dir = d == 1 ? 1 : (d == 5 ? -1 : 0);
        if (new_edges == 1u && dir != 0 && dir == s->dir) {
            s->n_run += 1;
        } else {
            s->n_run = (new_edges == 1u && dir != 0) ? 1 : 0;
        }
        s->dir = dir;
        s->tick_prev = s->tick_edge;
        s->tick_edge = in->tick_edge;
        s->sector = sector;
        s->code = in->hall;
        out->edge = 1;
    }
    s->n_edges = in->n_edges;

    out->valid = 1;
    out->sector = sector;
    out->dir = s->dir;
    const bc_hall_table *tb = &p->table;
    int fwd = s->dir > 0;
    /* sector widths: the one just crossed (w_prev) and the one entered (w_cur); pi/3 exactly without a table */
    float w_prev = PI3_F, w_cur = PI3_F;
    if (tb->set) {
        w_prev = fwd ? fwd_width(tb, (sector + 5) % 6) : bwd_width(tb, (sector + 1) % 6);
        w_cur = fwd ? fwd_width(tb, sector) : bwd_width(tb, sector);
    }
    float since = (float)(uint32_t)(in->tick_now - s->tick_edge) / p->f_tick; /* s, wrap-safe */
    float omega = 0.0f, interval = 0.0f;
    int speed_valid = 0, overdue = 0;
    if (s->n_run >= 2) {
        interval = (float)(uint32_t)(s->tick_edge - s->tick_prev) / p->f_tick;
        if (interval > 0.0f) {
            omega = w_prev / interval;
            if (since >= interval * (w_cur / w_prev)) {
                omega = w_cur / since; /* no edge yet: at most this fast */
                overdue = 1;
            }
            speed_valid = omega >= p->omega_min;
        }
    }
    if (!speed_valid) {
        out->speed_valid = 0;
        out->omega_e = 0.0f;
        s->pll_on = 0;
        float mid = bc_sector_angle(sector) + PI6_F; /* middle of the sector */
        if (tb->set) {
            float mf = tb->fwd[sector] + 0.5f * fwd_width(tb, sector);
            float mb = tb->bwd[sector] + 0.5f * bwd_width(tb, sector);
            mid = mf + 0.5f * wrap_pm(mb - mf);
        }
        out->theta = wrap_2pi(mid + p->theta_offset);
        return;
    }
    float dir = (float)s->dir;
    float edge_angle;
    if (tb->set) edge_angle = fwd ? tb->fwd[sector] : tb->bwd[(sector + 1) % 6];
    else edge_angle = bc_sector_angle(fwd ? sector : (sector + 1) % 6); /* backward: entered at its upper bound */
    out->speed_valid = 1;
    if (p->mode == BC_HALL_PLL) {
        if (!s->pll_on) { /* start: (46) at this edge */
            s->pll_on = 1;
            s->pll_theta = wrap_2pi(edge_angle);
            s->pll_omega = dir * (w_prev / interval);
            s->pll_acc = 0.0f;
        } else if (out->edge) {
            float r = 1.0f - 1.0f / p->pll_edges;
            float q = 1.0f - r;
            float alpha = 1.0f - r * r * r, gamma = 0.5f * q * q * q;
            float beta = 2.0f - 3.0f * r + r * r * r - gamma;
            float h2 = interval * interval;
            float pred = s->pll_theta + s->pll_omega * interval + 0.5f * s->pll_acc * h2;
            float e = wrap_pm(edge_angle - pred);
            s->pll_theta = wrap_2pi(pred + alpha * e);
            s->pll_omega += s->pll_acc * interval + beta * e / interval;
            s->pll_acc += 2.0f * gamma * e / h2;
            if (!isfinite(s->pll_omega) || !isfinite(s->pll_theta) || !isfinite(s->pll_acc)) { /* restart */
                s->pll_theta = wrap_2pi(edge_angle);
                s->pll_omega = dir * (w_prev / interval);
                s->pll_acc = 0.0f;
            }
        }
        /* travel from the edge in the direction of motion, within [-pi/12, w_cur + pi/12] */
        float w_now = s->pll_omega + s->pll_acc * since;
        float rel = dir * wrap_pm(s->pll_theta + (s->pll_omega + 0.5f * s->pll_acc * since) * since - edge_angle);
        if (!(rel <= w_cur + PI12_F)) rel = w_cur + PI12_F;
        if (!(rel >= -PI12_F)) rel = -PI12_F;
        float w_abs = dir * w_now > 0.0f ? fabsf(w_now) : 0.0f;
        if (overdue && w_abs > omega) w_abs = omega;
        if (!isfinite(w_abs)) w_abs = omega;
        out->omega_e = dir * w_abs;
        out->theta = wrap_2pi(edge_angle + dir * rel + p->theta_offset);
        return;
    }
    /* never beyond the next edge; once the edge is overdue exactly at it (omega since would round either side).
     * "At it" is the next sector's own entry angle, computed by the same expression as its edge_angle above (not
     * edge_angle + w_cur, which can round one ulp past it): the angle then never steps back, not even by rounding,
     * when the edge moves it into the next sector. */
    float next;
    if (fwd) next = tb->set ? tb->fwd[(sector + 1) % 6] : bc_sector_angle((sector + 1) % 6);
    else next = tb->set ? tb->bwd[sector] : bc_sector_angle(sector);
    float travel = overdue ? w_cur : omega * since;
    float theta = edge_angle + dir * travel;
    if (travel >= w_cur || dir * wrap_pm(next - theta) < 0.0f) theta = next;
    out->omega_e = dir * omega;
    out->theta = wrap_2pi(theta + p->theta_offset);
}

int bc_hall_commutate(const bc_hall_params *p, const bc_hall_out *h, const bc_ctrl_in *in, float lead, int advance,
                      float adv, int prev, int32_t *seen, float *travel_out)
{
    /* the sector seen, or the next one when its Hall edge is due by the middle of the interval the output applies
     * to (advance). A sector once commanded ahead of the sector seen is held until the Hall code moves: only a Hall
     * edge ends it (forward: the sector seen catches up; backward: the rotor reversed). */
    float w_abs = fabsf(h->omega_e);
    float travel = -1.0f; /* angle travelled since the edge at the middle of that interval; < 0 unknown */
    int sector = h->sector;
    int held = !h->edge && h->sector == *seen && prev >= 0 && prev != h->sector;
    if (h->speed_valid) {
        float since = (float)(uint32_t)(in->tick_now - in->tick_edge) / p->f_tick;
        travel = w_abs * (since + lead);
    }
    /* calibrated edges: o = how far the edge just crossed lies beyond the nominal one (bc_hall_entry_lead); the
     * nominal boundary ahead is pi/3 - o away, and with o < 0 (an early edge) the first -o still belong to the
     * previous nominal sector. Nominal table: o = 0, d_next = pi/3. */
    float o = bc_hall_entry_lead(p, h->sector, h->dir);
    float a = advance ? adv : 0.0f;    /* the timing advance moves every boundary ahead by a */
    float d_next = PI3_F - o - a;
    int behind = p->table.set && h->dir != 0 && prev == (h->sector - h->dir + 6) % 6;
    /* travel is returned into the commanded sector's span as advanced by a (its nominal span moved a earlier) */
    if (held && behind && advance) {
        /* holding the previous sector after an early edge: move on at the nominal boundary (or without a speed) */
        if (!h->speed_valid || travel >= -o - a) {
            sector = h->sector;
            travel = travel >= 0.0f ? travel + o + a : -1.0f;
        } else {
            sector = prev;
            travel += PI3_F + o + a;
        }
    } else if (held) {
        sector = prev;
        travel = travel >= d_next ? travel - d_next : -1.0f;
    } else if (advance && h->edge && behind && o + a < 0.0f && h->speed_valid && travel >= 0.0f &&
               travel < -o - a) {
        sector = prev; /* early edge: the commutation waits for the (advanced) nominal boundary */
        travel += PI3_F + o + a;
    } else if (advance && h->speed_valid && h->dir != 0 && travel >= d_next) {
        sector = (sector + (h->dir > 0 ? 1 : 5)) % 6;
        travel -= d_next;
    } else if (travel >= 0.0f) {
        travel += o + a; /* the sector seen: the rotor entered its advanced span o + a before the edge */
    }
    *seen = h->sector;
    *travel_out = travel;
    return sector;
}

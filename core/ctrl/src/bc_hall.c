/* bc_hall.c - Hall sector, speed and angle interpolation. Equations in bc_hall.h. */
#include "bldc/bc_hall.h"

#include <math.h>

#include "bldc/bc_commutation.h"

int bc_hall_init(const bc_hall_params *p, bc_hall_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!(isfinite(p->f_tick) && p->f_tick > 0.0f) || !(isfinite(p->omega_min) && p->omega_min > 0.0f) ||
        !isfinite(p->theta_offset))
        return BC_ERR_PARAM;
    s->code = 0u;
    s->n_edges = 0u;
    s->tick_edge = 0u;
    s->tick_prev = 0u;
    s->sector = -1;
    s->dir = 0;
    s->n_run = 0;
    s->started = 0;
    return BC_OK;
}

static float wrap_2pi(float th)
{
    th = fmodf(th, BC_TWO_PI_F);
    if (th < 0.0f) th += BC_TWO_PI_F;
    if (th >= BC_TWO_PI_F) th = 0.0f;
    return th;
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
    float since = (float)(uint32_t)(in->tick_now - s->tick_edge) / p->f_tick; /* s, wrap-safe */
    float omega = 0.0f;
    int speed_valid = 0, overdue = 0;
    if (s->n_run >= 2) {
        float interval = (float)(uint32_t)(s->tick_edge - s->tick_prev) / p->f_tick;
        if (interval > 0.0f) {
            omega = (BC_PI_F / 3.0f) / interval;
            if (since >= interval) {
                omega = (BC_PI_F / 3.0f) / since; /* no edge yet: at most this fast */
                overdue = 1;
            }
            speed_valid = omega >= p->omega_min;
        }
    }
    if (!speed_valid) {
        out->speed_valid = 0;
        out->omega_e = 0.0f;
        out->theta = wrap_2pi(bc_sector_angle(sector) + BC_PI_F / 6.0f + p->theta_offset); /* middle of the sector */
        return;
    }
    float dir = (float)s->dir;
    float edge_angle = dir > 0.0f ? bc_sector_angle(sector) : bc_sector_angle(sector) + BC_PI_F / 3.0f;
    /* never beyond the next edge; once the edge is overdue exactly at it (omega since would round either side) */
    float travel = overdue ? BC_PI_F / 3.0f : omega * since;
    if (travel > BC_PI_F / 3.0f) travel = BC_PI_F / 3.0f;
    out->speed_valid = 1;
    out->omega_e = dir * omega;
    out->theta = wrap_2pi(edge_angle + dir * travel + p->theta_offset);
}

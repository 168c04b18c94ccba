/* synth_hall.h - synthetic Hall inputs for the host tests: a rotor at theta(t) = th0 + w0 t + a t^2 / 2 (forward,
 * w0 > 0, a >= 0) crossing edges at the angles edge[j] (edge j between sectors j-1 and j), sampled every ts with a
 * capture timer at f_tick. The edge times are solved in double precision. */
#ifndef SYNTH_HALL_H
#define SYNTH_HALL_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_types.h"

typedef struct {
    double edge[6];          /* true edge angles, rad */
    double th0, w0, a;       /* trajectory: rad, rad/s, rad/s^2 */
    double ts, f_tick;       /* s, Hz */
    long n_cross;            /* edges crossed so far */
    double next_t;           /* time of the next edge */
    int next_j;              /* its index */
    double next_ang;         /* its unwrapped angle */
    uint32_t tick_edge;
    int sector;
} synth_hall;

static inline double synth_time_of(const synth_hall *g, double ang)
{
    double d = ang - g->th0;
    if (g->a == 0.0) return d / g->w0;
    return (-g->w0 + sqrt(g->w0 * g->w0 + 2.0 * g->a * d)) / g->a;
}

/* start just after edge 0 (in sector 0) */
static inline void synth_init(synth_hall *g, const double edge[6], double w0, double a, double ts, double f_tick)
{
    memset(g, 0, sizeof *g);
    for (int j = 0; j < 6; ++j) g->edge[j] = edge[j];
    g->th0 = edge[0] + 1e-3;
    g->w0 = w0;
    g->a = a;
    g->ts = ts;
    g->f_tick = f_tick;
    g->sector = 0;
    g->next_j = 1;
    g->next_ang = edge[1] < edge[0] ? edge[1] + 2.0 * BC_PI : edge[1];
    g->next_t = synth_time_of(g, g->next_ang);
}

static inline double synth_theta(const synth_hall *g, double t) { return g->th0 + g->w0 * t + 0.5 * g->a * t * t; }

/* the inputs at sample k */
static inline void synth_sample(synth_hall *g, long k, bc_ctrl_in *in)
{
    double t = (double)k * g->ts;
    while (g->next_t <= t) {
        g->n_cross += 1;
        g->sector = g->next_j;
        g->tick_edge = (uint32_t)(uint64_t)llround(g->next_t * g->f_tick);
        int j = (g->next_j + 1) % 6;
        double step = g->edge[j] - g->edge[g->next_j];
        while (step <= 0.0) step += 2.0 * BC_PI;
        g->next_ang += step;
        g->next_j = j;
        g->next_t = synth_time_of(g, g->next_ang);
    }
    memset(in, 0, sizeof *in);
    in->hall = bc_sector_code(g->sector);
    in->n_edges = (uint32_t)g->n_cross;
    in->tick_edge = g->tick_edge;
    in->tick_now = (uint32_t)(uint64_t)llround(t * g->f_tick);
    in->v_dc = 48.0f;
    in->i_mask = 7u;
}

#endif /* SYNTH_HALL_H */

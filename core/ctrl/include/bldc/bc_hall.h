/*
 * bc_hall.h - three Hall sensors: sector, direction, speed and interpolated angle (paper 1, (46)) (float).
 *
 * Edges are time-stamped by a free-running capture timer (ticks at f_tick, wrap-safe unsigned differences).
 * With the last two edges consecutive in the same direction, t_(k-1) and t_k apart:
 *
 *     Omega_e = dir (pi/3) / (t_k - t_(k-1))                                  (paper 1: pi/3 over the edge interval)
 *     theta(t) = theta_edge + Omega_e (t - t_k),  |Omega_e (t - t_k)| <= pi/3  (46), evaluated from the capture
 *                                                                              time instead of summing Omega_e dt
 *
 * theta_edge is the angle of the edge just crossed (docs/conventions.md: pi/6 + s pi/3 entering sector s forward,
 * pi/6 + (s+1) pi/3 entering it backward) plus theta_offset. The interpolation stops at the next edge angle. If no
 * edge follows within the previous interval (the edge is overdue: t - t_k >= t_k - t_(k-1)), the speed estimate
 * decays as (pi/3)/(t - t_k), an upper bound, and the angle is exactly the next edge angle. So while the rotor turns
 * one way the angle never steps back within a sector (it rises, then holds at the next edge; the edge itself moves
 * it on) and the speed estimate never rises between edges. The speed is zero (speed_valid = 0) once the bound falls
 * below omega_min, (pi/3)/omega_min after the last edge, or without two consecutive edges in the same direction;
 * the angle is then the middle of the sector (the rotor is taken as stopped, anywhere in the sector: the angle
 * moves back from the next edge to the middle when the speed times out).
 *
 * Invalid codes (000, 111) give valid = 0, sector = -1, speed_valid = 0: the caller goes to its safe state.
 */
#ifndef BC_HALL_H
#define BC_HALL_H

#include <stdint.h>

#include "bldc/bc_types.h"

typedef struct {
    float f_tick;       /* capture timer frequency, Hz (> 0) */
    float omega_min;    /* electrical rad/s (> 0): slower than this the speed is reported as 0 */
    float theta_offset; /* electrical rad added to the edge angles (sensor placement correction) */
} bc_hall_params;

typedef struct {
    uint32_t code;      /* last valid code */
    uint32_t n_edges;   /* edge counter at the last step */
    uint32_t tick_edge; /* tick of the last edge */
    uint32_t tick_prev; /* tick of the edge before it */
    int32_t sector;     /* last valid sector, -1 before the first */
    int32_t dir;        /* direction of the last edge: +1, -1, 0 unknown */
    int32_t n_run;      /* consecutive single edges in the same direction */
    int32_t started;    /* a step has been taken */
} bc_hall_state;

typedef struct {
    int32_t valid;       /* 1 if the code is valid */
    int32_t sector;      /* 0..5, -1 if invalid */
    int32_t edge;        /* 1 if an edge arrived since the last step */
    int32_t dir;         /* +1 forward, -1 backward, 0 unknown */
    int32_t speed_valid; /* 1 if omega_e comes from two consecutive edges */
    float omega_e;       /* electrical speed, rad/s, signed (0 if not speed_valid) */
    float theta;         /* electrical angle, rad, [0, 2 pi) */
} bc_hall_out;

int bc_hall_init(const bc_hall_params *p, bc_hall_state *s);
void bc_hall_step(const bc_hall_params *p, bc_hall_state *s, const bc_ctrl_in *in, bc_hall_out *out);

#endif /* BC_HALL_H */

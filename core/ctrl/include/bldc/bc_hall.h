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
 *
 * Edge table (calibrated edges, bc_hallcal.h). Edge j lies between sector j-1 and sector j (nominal angle
 * a_j = pi/6 + j pi/3). With table.set = 1 the decoder uses the measured angles instead: fwd[j] where the code
 * changes j-1 -> j turning forward, bwd[j] where it changes j -> j-1 turning backward (two tables: with hysteresis
 * and delay a sensor switches at different angles in the two directions; the forward table is all a drive that only
 * turns forward needs, pass it as both when the backward edges were not measured). Every entry must lie within
 * pi/6 of its nominal angle (so the edges keep their order and every sector a width > 0). In the equations above
 * pi/3 becomes the table's sector widths: entering sector s forward at t_k, after crossing sector s-1,
 *
 *     theta_edge = fwd[s],   w_prev = fwd[s] - fwd[s-1],   w_cur = fwd[s+1] - fwd[s]        (mod 2 pi, in (0, 2 pi))
 *     Omega_e = dir w_prev / (t_k - t_(k-1)),   theta(t) = theta_edge + Omega_e (t - t_k),  travel <= w_cur
 *
 * (backward, entering s from s+1: theta_edge = bwd[s+1], w_prev = bwd[s+2] - bwd[s+1], w_cur = bwd[s+1] - bwd[s]).
 * The edge is overdue when the travel reaches w_cur, i.e. t - t_k >= (t_k - t_(k-1)) w_cur / w_prev, and the
 * speed bound is then w_cur / (t - t_k). The middle of a sector (standstill angle) is the mean of the forward and
 * backward middles. table.set = 0 is the nominal table (the arrays are ignored; the same as filling them with
 * bc_hall_table_nominal, up to the rounding of pi/3).
 *
 * Tracking estimator (mode = BC_HALL_PLL). A type-3 tracking loop (an alpha-beta-gamma filter: the discrete PLL of
 * an event-driven phase detector, with speed and acceleration) on the edge angles: at each edge k of a run of
 * consecutive edges in one direction, h = t_k - t_(k-1), with theta_hat, Omega_hat, A_hat the estimate at the
 * previous edge,
 *
 *     e_k = wrap_(-pi, pi](theta_edge,k - (theta_hat + Omega_hat h + A_hat h^2 / 2))   phase error at the edge
 *     theta_hat <- theta_hat + Omega_hat h + A_hat h^2 / 2 + alpha e_k
 *     Omega_hat <- Omega_hat + A_hat h + beta e_k / h,      A_hat <- A_hat + 2 gamma e_k / h^2
 *     alpha = 1 - r^3,  gamma = (1 - r)^3 / 2,  beta = 2 - 3 r + r^3 - gamma,  r = 1 - 1/pll_edges
 *
 * which places the three closed-loop poles of the error (z^3 + (alpha + beta + gamma - 3) z^2 + (3 - 2 alpha -
 * beta + gamma) z + alpha - 1, at constant h) at z = r: the loop's time constant is pll_edges edges at any speed,
 * and a constant acceleration leaves no steady error (type 3). pll_edges = 1 is the dead-beat filter (alpha = 1,
 * beta = 3/2, gamma = 1/2: the parabola through the last three edges). Larger values average the edge errors of
 * misplaced sensors (a pattern repeating every 6 edges) at the cost of a slower start and of tracking a change of
 * acceleration more slowly. Between edges theta = theta_hat + Omega_hat tau + A_hat tau^2 / 2 (tau = t - t_k),
 * kept within [theta_edge - pi/12, theta_edge + w_cur + pi/12] in the direction of motion (the rotor has not yet
 * crossed the next edge; pi/12 allows for an uncalibrated sensor up to 15 degrees off). The loop starts
 * (theta_hat = theta_edge, Omega_hat = (46)'s speed, A_hat = 0) with the speed becoming valid and restarts after
 * a reversal, a skipped edge or a timeout. The speed output is Omega_hat + A_hat tau (0 if its sign is against the
 * direction of motion), never above (46)'s bound once the edge is overdue; speed_valid and the standstill angle
 * are (46)'s.
 */
#ifndef BC_HALL_H
#define BC_HALL_H

#include <stdint.h>

#include "bldc/bc_types.h"

#define BC_HALL_INTERP 0 /* (46): interpolation from the last edge at the speed of the last interval */
#define BC_HALL_PLL 1    /* tracking loop on the edges (see above) */

typedef struct {
    int32_t set; /* 0: nominal edges (the arrays are ignored); 1: the arrays below */
    float fwd[6]; /* rad electrical: edge j (sectors j-1 | j) as crossed forward (code j-1 -> j) */
    float bwd[6]; /* rad electrical: edge j as crossed backward (code j -> j-1) */
} bc_hall_table;

typedef struct {
    float f_tick;        /* capture timer frequency, Hz (> 0) */
    float omega_min;     /* electrical rad/s (> 0): slower than this the speed is reported as 0 */
    float theta_offset;  /* electrical rad added to the edge angles (sensor placement correction) */
    int32_t mode;        /* BC_HALL_INTERP (0) or BC_HALL_PLL */
    float pll_edges;     /* BC_HALL_PLL: time constant of the loop in edges, 1 .. 1000 */
    bc_hall_table table; /* edge angles (set = 0: nominal) */
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
    int32_t pll_on;     /* PLL: the loop is running */
    float pll_theta;    /* PLL: angle estimate at the last edge, rad (without theta_offset) */
    float pll_omega;    /* PLL: speed estimate at the last edge, electrical rad/s, signed */
    float pll_acc;      /* PLL: acceleration estimate, electrical rad/s^2, signed */
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

/* Validate the parameters (finite, f_tick and omega_min > 0, mode, pll_edges, a set table within pi/6 of the
 * nominal edges) and reset the state. BC_OK or BC_ERR_PARAM. */
int bc_hall_init(const bc_hall_params *p, bc_hall_state *s);
/* Fill a table with the nominal edges pi/6 + j pi/3 (both directions), set = 1. */
void bc_hall_table_nominal(bc_hall_table *t);
/* Check a table: BC_OK if set = 0, or every entry finite and within pi/6 of its nominal angle; else BC_ERR_PARAM. */
int bc_hall_table_check(const bc_hall_table *t);
/* Angle (rad, within (-pi/6, pi/6)) by which the edge through which the rotor entered `sector` turning `dir`
 * (+1, -1) lies beyond the nominal edge in the direction of motion: dir (theta_edge - nominal); 0 for a nominal
 * table or an invalid sector/direction. Used by bc_hall_commutate to commutate at the nominal angle. */
float bc_hall_entry_lead(const bc_hall_params *p, int sector, int dir);
/* The sector to command (bc_sixstep with advance, bc_lu with a table), from the decoder's output h of this sample,
 * the sector commanded at the last call (prev, -1 none) and the sector seen then (*seen, set to h->sector here).
 * lead (s): from this sample to the middle of the interval the output applies to ((delay + 1/2) T_s). With
 * travel = |Omega_e| (t_k - t_edge + lead) (the angle since the edge by then, from the capture time of the last
 * edge and in->tick_now) and o = bc_hall_entry_lead of the edge just crossed (0 for a nominal table):
 *   - the next sector h.sector + dir is commanded once travel >= pi/3 - o - adv (the nominal boundary ahead, moved
 *     adv earlier by a timing advance (rad, 0 <= adv < pi/3 - |o|), is due);
 *   - after an early edge (o < 0, table set) the sector commanded before it is held while travel < -o (the rotor
 *     is still in the previous nominal sector), then the sector seen follows;
 *   - a sector commanded ahead of the sector seen is held until the Hall code moves (only an edge ends it: the
 *     sector seen catches up, or the rotor reversed).
 * So a commanded sector is only ever replaced by the next one in the direction of motion or by a Hall edge, never
 * stepped back while the rotor turns one way. advance = 0: the sector seen (the table is ignored). *travel: the
 * angle (rad) the rotor will have travelled into the returned sector's span (nominal, moved adv earlier) by the
 * time lead from now, < 0 if unknown (no speed estimate): the next commutation is due pi/3 - travel later. */
int bc_hall_commutate(const bc_hall_params *p, const bc_hall_out *h, const bc_ctrl_in *in, float lead, int advance,
                      float adv, int prev, int32_t *seen, float *travel_out);
void bc_hall_step(const bc_hall_params *p, bc_hall_state *s, const bc_ctrl_in *in, bc_hall_out *out);

#endif /* BC_HALL_H */

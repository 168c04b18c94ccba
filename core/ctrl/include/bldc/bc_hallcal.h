/*
 * bc_hallcal.h - six-edge Hall calibration: the angle of each of the six Hall edges, for bc_hall's edge table
 * (bc_hall.h) (float, no malloc, no globals). A controller (bc_ctrl contract) run at start-up; the result is read
 * with bc_hallcal_result. Edge j lies between sectors j-1 and j, nominally at a_j = pi/6 + j pi/3.
 *
 * (a) BC_HALLCAL_SPEED: constant speed, from the edge times (legs off: the rotor coasts or a dynamometer turns it;
 *     a host controller can feed the same inputs while it runs the motor). The first edge is the reference edge j0
 *     at t_ref; over each of n_rev electrical revolutions r (t_ref,r to t_ref,r+1 = t_ref,r + T_r, the same edge
 *     again) the edge j crossed at t_j,r lies at
 *
 *         phi_j = 2 pi (t_j,r - t_ref,r) / T_r      (relative to edge j0, in the direction of motion)
 *
 *     if the speed is constant within the revolution; phi_j is averaged over the revolutions. The absolute angle is
 *     not observable from times alone: the table assumes that the placement errors have zero mean,
 *
 *         table_j = a_j0 + dir phi_j - c,    c = mean_j wrap(a_j0 + dir phi_j - a_j)
 *
 *     (a sensor misplaced by e moves its two edges by e: the table is then off by e/3 at every edge, the sector
 *     widths are exact; a common delay d of all edges shifts them by Omega d, which c absorbs). The edges are
 *     those crossed in the direction of motion; the table holds them in both directions (fwd = bwd).
 *     Bad input: an invalid code (000, 111: a stuck or broken sensor), a code that is not the next or previous
 *     sector (a skipped or spurious edge: non-monotonic edges), a reversal, a spread of the revolution times
 *     (max_r T_r - min_r T_r) > speed_tol mean_r T_r, too few edges before t_max, or a result beyond pi/6 of
 *     nominal: failed (BC_HALLCAL_FAIL with the reason), the table is never written.
 *     Convergence: at constant speed one revolution determines the table up to the capture-timer resolution
 *     (2 pi f_e / f_tick: measured 1.3e-5 rad at 300 electrical rad/s with a 10 MHz timer, test_hallcal.c); more
 *     revolutions only average speed ripple and timer jitter. The absolute error is the mean placement error
 *     (measured on the catalog drives with errors of up to 10 degrees: 0.5 to 3.4 degrees, the widths to 0.001).
 *
 * (b) BC_HALLCAL_OPENLOOP: start-up routine, an open-loop voltage vector (bc_transform: min-max SVM of
 *
 *         u_d = v_align,   u_q = dir v_emf omega_cmd / omega_ol   at the Park angle theta_cmd - pi
 *
 *     u_d drives the current that pulls the rotor's d axis along, u_q cancels the back-EMF of a rotor that follows,
 *     a V/f start) so that the rotor follows theta_cmd with a lag delta (friction, load, cogging). It holds
 *     theta_cmd = 0 for t_align, turns it forward for n_rev + 1 revolutions, its speed omega_cmd ramping up at
 *     omega_ol^2 / pi (omega_ol after pi/2 of travel) and then constant, then backward the same way. At each edge
 *     crossed for the first time in the sweep's direction (a rotor swinging back over an edge is not counted
 *     again) after the first half revolution of a sweep, the commanded angle at the edge's capture time,
 *
 *         theta_cmd(t_edge) = theta_cmd(t_k) - dir omega_cmd (t_k - t_edge)
 *
 *     is recorded: forward f_j = edge_fwd,j + delta_f, backward b_j = edge_bwd,j - delta_b. With the same lag in
 *     both directions and a hysteresis h_j symmetric about the sensor's position c_j (edge_fwd = c_j + h_j/2,
 *     edge_bwd = c_j - h_j/2):
 *
 *         table_j = (f_j + b_j) / 2 = c_j + (delta_f - delta_b)/2          (lag and hysteresis cancel)
 *
 *     averaged over the n_rev revolutions of each sweep; the table holds c_j in both directions (lag and hysteresis
 *     cannot be told apart, only their sum (f_j - b_j)/2 per edge). Bad input as in (a) (an invalid code; an edge
 *     the rotor steps back over by more than one edge: it lost the vector), an over-current or bad measurement
 *     (bc_guard: the legs go off), fewer than n_rev records of an edge in either direction, f_j - b_j outside
 *     [-pi/12, lag_max] (the rotor did not follow), or a result beyond pi/6 of nominal: failed, no table.
 *     Duration t_align + 2 ((n_rev + 1) 2 pi + pi/2) / omega_ol. Measured (catalog drives, sensors up to 10
 *     degrees off, omega_ol = 4 pi rad/s, docs/hall-calibration.md): the worst edge within 0.5 degree on htm-48v
 *     with 1 revolution per direction (no gain from more: a lag that differs between the directions at some
 *     angles), 1.2 / 0.9 / 0.7 degree on lu-4kw (a high-inertia rotor swinging about the vector) with 1 / 2 / 4
 *     revolutions, below 0.01 degree on outrunner-24v and servo-2k2 (bldclab.HallCal defaults to 3).
 *
 * Outputs: legs (OPENLOOP: all PWM with the SVM duties while turning, off with BC_FLAG_SAFE when done or failed;
 * SPEED: always off), BC_FLAG_SAFE with BC_FLAG_HALL_INVALID / _BAD_INPUT / _OVERCURRENT at any sample with an
 * invalid code or (OPENLOOP) a bad measurement (bc_guard), whatever the status. diag[0..5] the table
 * (rad; the nominal angles until done), [6] the status word (BC_HALLCAL_*), [7] OPENLOOP: theta_cmd (rad); SPEED:
 * revolutions completed.
 */
#ifndef BC_HALLCAL_H
#define BC_HALLCAL_H

#include <stdint.h>

#include "bldc/bc_guard.h"
#include "bldc/bc_hall.h"
#include "bldc/bc_types.h"

#define BC_HALLCAL_SPEED 0    /* constant speed, from edge times */
#define BC_HALLCAL_OPENLOOP 1 /* open-loop voltage vector, forward then backward */

/* status word */
#define BC_HALLCAL_BUSY 0x1u       /* collecting */
#define BC_HALLCAL_DONE 0x2u       /* the table is valid */
#define BC_HALLCAL_FAIL 0x4u       /* failed: no table (the reason below) */
#define BC_HALLCAL_E_INVALID 0x10u /* invalid Hall code 000/111 (stuck or broken sensor) */
#define BC_HALLCAL_E_ORDER 0x20u   /* a code that is not a neighbour of the last (skipped/spurious edge) */
#define BC_HALLCAL_E_REVERSAL 0x40u /* the rotor reversed (SPEED) or fell back over the edges (OPENLOOP) */
#define BC_HALLCAL_E_SPEED 0x80u   /* SPEED: revolution times spread beyond speed_tol */
#define BC_HALLCAL_E_FEW 0x100u    /* too few edges before t_max / the end of the sweeps */
#define BC_HALLCAL_E_RANGE 0x200u  /* a result beyond pi/6 of nominal, or OPENLOOP lag outside its range */
#define BC_HALLCAL_E_INPUT 0x400u  /* OPENLOOP: bad measurement or over-current (bc_guard) */

#define BC_HALLCAL_REV_MAX 1000

typedef struct {
    int32_t method;  /* BC_HALLCAL_SPEED or BC_HALLCAL_OPENLOOP */
    int32_t n_rev;   /* electrical revolutions averaged (per direction for OPENLOOP), 1 .. BC_HALLCAL_REV_MAX */
    float f_tick;    /* capture-timer frequency, Hz (> 0) */
    float ts;        /* sampling period, s (> 0) */
    float t_max;     /* SPEED: give up after this long, s (> 0) */
    float speed_tol; /* SPEED: largest (max - min)/mean of the revolution times, (0, 1) */
    float v_align;   /* OPENLOOP: voltage vector amplitude at standstill, V (> 0) */
    float v_emf;     /* OPENLOOP: q-axis voltage at omega_ol (the back-EMF there), V (>= 0) */
    float omega_ol;  /* OPENLOOP: speed of the vector, electrical rad/s (> 0) */
    float t_align;   /* OPENLOOP: hold at the start angle, s (>= 0) */
    float lag_max;   /* OPENLOOP: largest f_j - b_j accepted, rad, (0, pi/2] */
    float i_max;     /* OPENLOOP: over-current trip, A (> 0) */
    float v_max;     /* OPENLOOP: largest plausible DC bus, V (> 0) */
} bc_hallcal_params;

typedef struct {
    uint32_t status;    /* BC_HALLCAL_* */
    int32_t started;    /* a step has been taken */
    int32_t sector;     /* last valid sector */
    uint32_t n_edges;   /* edge counter at the last step */
    int32_t dir;        /* SPEED: direction of the run (0 before the second edge) */
    int32_t j0;         /* SPEED: reference edge, -1 before the first edge */
    int32_t n_in_rev;   /* SPEED: edges since the reference edge in this revolution */
    int32_t revs;       /* SPEED: completed revolutions */
    uint32_t tick_ref;  /* SPEED: tick of the reference edge of this revolution */
    uint32_t off[6];    /* SPEED: ticks of the edges after the reference edge in this revolution */
    int32_t off_j[6];   /* SPEED: their edge indices */
    float t_min, t_max, t_sum; /* SPEED: revolution times, s */
    float acc[6];       /* SPEED: sum of phi_j; OPENLOOP: sum of wrap(f_j - a_j) */
    float acc_b[6];     /* OPENLOOP: sum of wrap(b_j - a_j) */
    int32_t cnt[6];     /* records of edge j (forward or SPEED) */
    int32_t cnt_b[6];   /* OPENLOOP: backward records */
    int64_t k;          /* samples taken */
    int32_t phase;      /* OPENLOOP: 0 align, 1 forward, 2 backward, 3 done */
    float theta_cmd;    /* OPENLOOP: commanded angle, rad, (-pi, pi] */
    float omega_cmd;    /* OPENLOOP: speed of the vector, electrical rad/s (>= 0) */
    float travel;       /* OPENLOOP: angle turned in this sweep, rad */
    int32_t pos, pos_max; /* OPENLOOP: edges counted in the sweep's direction (net, and furthest) */
    float table[6];     /* result (valid with BC_HALLCAL_DONE) */
    bc_guard_params guard_p;
    bc_guard_state guard;
} bc_hallcal_state;

/* Validate the parameters and reset the state (status BC_HALLCAL_BUSY). BC_OK or BC_ERR_PARAM. */
int bc_hallcal_init(const bc_hallcal_params *p, bc_hallcal_state *s);

/* One sample (bc_ctrl contract): see above. */
void bc_hallcal_step(const bc_hallcal_params *p, bc_hallcal_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);

/* The status word; with BC_HALLCAL_DONE the table is copied into *t (set = 1, fwd = bwd), otherwise *t is left
 * untouched. */
uint32_t bc_hallcal_result(const bc_hallcal_state *s, bc_hall_table *t);

#endif /* BC_HALLCAL_H */

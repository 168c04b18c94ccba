/*
 * bc_commission.h - motor self-commissioning ("motor detection", float): the stator resistance, the inductance and
 * the PM flux linkage measured by the controller from its own voltages and currents, pole pairs given.
 * docs/sensorless-sine.md, "Self-commissioning", has the measurements against the plant.
 *
 * Frames: amplitude-invariant alpha-beta (bc_transform.h). The controller drives a current vector i_ref e^(j phi)
 * with two PIs in the frame of phi (the same gains for both axes), the voltage rotated back with the loop's delay
 * compensated (phi + 1.5 omega_phi T_s) and min-max SVM. The voltage of sample k-2 (the one applied over [t_k-1,
 * t_k], as in bc_obs.h) is taken back from its duties and the dead time ("dead time"): u = Clarke(d_x v_dc + w_x).
 *
 * Dead time. The samples alternate between the carrier's valley and peak (the first a valley): a half period from a
 * peak holds each leg's turn-off edge (at d_x T_s), one from a valley its turn-on (at (1 - d_x) T_s). When a
 * command's half period starts (the next sample), its loss or gain w_x is worked out event by event from the phase
 * currents measured then: between events every current changes at
 *
 *     di_x/dt = (v_x - (v_a + v_b + v_c) / 3 - eb_x) / L,    eb = e + R i = u - L (i_k - i_k-1) / T_s
 *
 * (eb of the half period before: its voltage, corrected, less what the inductance took); a leg at its edge has both
 * switches off for t_dead, its terminal set by its current, -v_diode for i_x > 0 and v_dc + v_diode for i_x < 0,
 * and if that current reaches zero in the dead time it floats where it stays zero, v_x = 1.5 eb_x + (v_y + v_z) / 2
 * (within the rails), until the switch takes it to its new level; w_x is the mean terminal voltage so found less
 * d_x v_dc. The events (three edges, their dead times' ends, the currents' ends) move each other: a leg held by its
 * diode lengthens the others' states, and their ripple decides whether the next edge is held. Before L is measured
 * the loss is -v_t sat(i_x / b), v_t = (v_dc + 2 v_diode) t_dead / (2 T_s), b 2 % of the larger test current. The
 * R test's two levels and the pulses about a held point cancel this error anyway; the spin's back-EMF would keep it.
 * Phases, in order:
 *
 *  0. OFFSET  t_offset with the legs off (no current flows in a motor at rest): the mean of each phase current is
 *             its sensor's offset, taken off every later sample (as firmware calibrates with the PWM off); the
 *             standard deviation of i_alpha is the noise sig_i that sets the pulses of L.
 *  1. ALIGN   phi = pi/2, i_ref rising linearly 0 -> i_test over t_ramp (the rotor's d axis pulled onto the vector
 *             slowly, so that it is left with little swing), then phi turned linearly to 0 over t_ramp (a rotor at
 *             the unstable point of one angle, its d axis opposite the current, is pulled off it by the other).
 *             In ALIGN and the R test the rotor's swing about the current (a current-fed rotor has no damping of
 *             its own) is braked: i_q,ref = -k_damp (x_q - R i_q), x_q the q PI's integrator (the low-frequency q
 *             voltage: the swing's back-EMF omega_e psi_f when the d axis is on the current; R = 0 before it is
 *             measured), clamped to +-i_test / 2. The integrator and not the applied voltage: through k_p the loop
 *             gain k_p k_damp would exceed 1 and chatter; on x_q it is a pole at -k_i k_damp.
 *  2. R_HI    t_settle, then t_window at i_test: means V_2 = <u_alpha>, I_2 = <i_alpha>; over it the spread of u_alpha and the
 *             largest |u_beta| (a turning rotor's back-EMF), both of the means of BC_COMM_BLOCKS blocks of the window
 *             (single samples carry the current's noise through k_p).
 *  3. R_LO    t_settle, then t_window at i_test / 2: V_1, I_1, likewise. Two levels cancel the inverter's voltage
 *             error (diode drops, dead time), constant at a constant current sign:
 *
 *                 R = (V_2 - V_1) / (I_2 - I_1)          (the resistance in series with a phase: R + R_on)
 *
 *  4. L       n_pulse pairs of voltage pulses on alpha, +v_pulse then -v_pulse for pulse_len samples each, added to
 *             the PIs' output at I_1 (held, the PIs paused), then 2 samples of that output alone (bldclab's
 *             Commission sizes them: a current step of half the test current, the voltage at least five times the
 *             dead time's error (v_dc + 2 v_diode) t_dead / (2 ts), shorter pulses where needed). Over the pulses,
 *             the sign s of each:
 *
 *                 L = sum s (u_alpha - V_1 - R ((i_k-1 + i_k)/2 - I_1)) T_s / sum s (i_k - i_k-1)
 *
 *             (u - V_1 - R (i - I_1) is what the inductance takes, the inverter's error cancelled by V_1 - R I_1).
 *             The voltage is the held command, free of noise; the current's noise enters the denominator at the
 *             sign changes, variance (8 P - 2) sig_i^2 after P pairs: while sig_i sqrt(8 P - 2) > tol_noise |sum s
 *             (i_k - i_k-1)| at the train's end a pair is added, up to n_pulse_max pairs (then NOISY if the
 *             whole sums are still not precise).
 *             Then t_settle with the PIs at I_1 again.
 *  5. SPIN    I/f: i_ref rising to i_if over t_ramp with the vector still, then the vector turning, omega_phi
 *             ramped by if_accel to w_spin (electrical rad/s), t_settle there, then t_spin of the back-EMF in the frame of phi,
 *
 *                 e' = u' - R i' - j omega_phi L i'      (u' the applied voltage in the frame at the
 *                                                    interval's middle, 1.5 samples after its command's angle)
 *
 *             and psi_f = sum |e'| T_s / (n w_spin T_s + sum d arg e'): |e'| = |omega_r| psi_f, and the rotor's
 *             travel is the vector's plus the change of the angle of e' (the rotor's q axis in the frame of phi),
 *             so the swing of a current-fed rotor about the vector (undamped) leaves no error.
 *  6. DONE    legs off; the results stay in the state.
 *
 * Statuses (status, diag 7): RUNNING until DONE; a failure turns the legs off for good and names its cause:
 *   ROTOR_MOVING   in R_HI or R_LO, the largest |u_beta| or the spread of u_alpha (block means) exceeds tol_move |V|
 *                  (a rotor turned by its load or a dynamometer: back-EMF where a standing rotor has none)
 *   NO_CURRENT     |I_2| < i_test / 2 at the end of R_HI, or the duties clipped with |i_d| < i_ref / 2 (an open
 *                  phase: the PI winds up against no current)
 *   SATURATED      the duties clipped with the current there (the test voltage or the spin's back-EMF above the
 *                  bus)
 *   NOT_FOLLOWING  in SPIN, the spread (standard deviation) of |e'| exceeds tol_follow <|e'|>, or <|e'|> is below
 *                  w_spin psi_min: the rotor does not turn with the vector
 *   NOISY          after n_pulse_max pulse pairs L's relative standard error from the current's noise is still
 *                  above tol_noise
 *   FAULT          the input guard (over-current, bus, fault pin, non-finite measurement; bc_guard.h)
 *   CLIPPED        a measured phase current at the sensors' full scale i_fs (|i_x| >= i_fs, before the offsets
 *                  are taken off): the shunt amplifier or the ADC saturated, the reading is not the current, and
 *                  R, L or psi_f from it would be wrong (i_fs = 0: the full scale not given, no check)
 *
 * diag: 0 phase (BC_COMM_PH_*), 1 R (Ohm), 2 L (H), 3 psi_f (V s), 4 i' real (A), 5 i' imaginary (A), 6 phi (rad),
 * 7 status (BC_COMM_*).
 */
#ifndef BC_COMMISSION_H
#define BC_COMMISSION_H

#include <stdint.h>

#include "bldc/bc_guard.h"
#include "bldc/bc_pi.h"
#include "bldc/bc_types.h"

#define BC_COMM_RUNNING 0
#define BC_COMM_DONE 1
#define BC_COMM_ROTOR_MOVING 2
#define BC_COMM_NO_CURRENT 3
#define BC_COMM_SATURATED 4
#define BC_COMM_NOT_FOLLOWING 5
#define BC_COMM_FAULT 6
#define BC_COMM_NOISY 7
#define BC_COMM_CLIPPED 8

#define BC_COMM_BLOCKS 8 /* blocks of an R window whose mean voltages show a turning rotor */

#define BC_COMM_PH_OFFSET 0
#define BC_COMM_PH_ALIGN 1
#define BC_COMM_PH_R_HI 2
#define BC_COMM_PH_R_LO 3
#define BC_COMM_PH_L 4
#define BC_COMM_PH_SPIN 5
#define BC_COMM_PH_DONE 6

typedef struct {
    float ts;         /* sampling period, s (> 0) */
    float kp, ki;     /* current PI gains, V/A and V/(A s) (>= 0) */
    float i_test;     /* DC test current, A (> 0, < i_max) */
    float t_ramp;     /* alignment ramp, s (>= 0) */
    float t_settle;   /* settling time before each window, s (>= 0) */
    float t_window;   /* averaging window of the R test, s (> 0) */
    float v_pulse;    /* inductance pulse voltage, V (> 0) */
    int32_t n_pulse;  /* pulse pairs (1 .. 1000) */
    int32_t pulse_len; /* samples per pulse (1 .. 1000) */
    int32_t n_pulse_max; /* most pulse pairs while the noise asks for more (n_pulse .. 1000) */
    float tol_noise;  /* largest relative standard error of L from the current's noise, - (> 0) */
    float t_offset;   /* current-sensor offset calibration with the legs off, s (> 0) */
    float i_if;       /* I/f current of the spin, A (> 0, < i_max) */
    float if_accel;   /* spin ramp, electrical rad/s^2 (> 0) */
    float w_spin;     /* spin speed, electrical rad/s (> 0) */
    float t_spin;     /* averaging window of the spin, s (> 0) */
    float psi_min;    /* smallest plausible flux linkage, V s (> 0) */
    float tol_move;   /* ROTOR_MOVING threshold, - (> 0) */
    float tol_follow; /* NOT_FOLLOWING threshold, - (> 0) */
    float k_damp;     /* swing damping of ALIGN and the R test, A/V (>= 0) */
    float i_max;      /* over-current trip, A (> 0) */
    float v_max;      /* bound of the PI outputs and of a plausible bus, V (> 0) */
    float t_dead;     /* the inverter's dead time, s (0 <= t_dead < ts): the voltage taken back is corrected */
    float v_diode;    /* its diodes' forward drop, V (>= 0), in the same correction */
    float i_fs;       /* the current sensors' full scale, A (> 0; 0: not given): a reading at it ends CLIPPED */
} bc_commission_params;

typedef struct {
    bc_guard_params guard_p;
    bc_guard_state guard;
    bc_pi_params pi_p;
    bc_pi_state pi_d, pi_q;
    int32_t phase, status;
    float t;               /* time in the phase, s */
    int32_t k;             /* samples in the phase */
    float phi, w_phi;      /* vector angle (rad) and speed (rad/s) */
    float u_hist[2][2];    /* alpha-beta voltage commanded 1 and 2 samples ago, V */
    float phi_hist[2];     /* the vector angle of those samples, rad */
    float i_prev[2];       /* current of the previous sample, A */
    float u_hold[2];       /* the PIs' output (frame of phi) held during the pulses, V */
    float n, s_v, s_i, s_vb, v_lo, v_hi; /* window sums: count, u_alpha, i_alpha, max |u_beta|, u_alpha range */
    float s_e, s_e2;      /* spin: sum |e'|, |e'|^2 */
    float s_dd, e_ang;    /* spin: the rotor's travel against the vector (sum of the steps of arg e'), last arg e' */
    float l_num, l_den;   /* inductance sums */
    float V1, I1, V2, I2;
    float i_off[3];        /* current-sensor offsets measured in OFFSET, A (0 before) */
    float s_o[3];          /* OFFSET: sums of the phase currents */
    float sig_i;           /* the alpha current's noise measured in OFFSET (standard deviation), A */
    int32_t n_cmd;         /* L: commands of the pulse train (grows a pair at a time while the noise asks) */
    float b_a, b_b;        /* R test: the voltage's sums over the block (alpha, beta) */
    int32_t b_n;           /* ... and its samples */
    float d_cmd[3], v_cmd; /* the last command's duties and bus voltage (V), for its dead-time correction */
    int32_t has_cmd;       /* 1: that correction is still to be added to u_hist[0] */
    uint32_t odd;          /* 1: this sample is at a carrier peak (odd samples from the first, a valley) */
    float R, L, psi;       /* results (0 until measured) */
} bc_commission_state;

/* Validate (BC_ERR_PARAM) and reset: ALIGN, RUNNING. */
int bc_commission_init(const bc_commission_params *p, bc_commission_state *s);

/* One sample. */
void bc_commission_step(const bc_commission_params *p, bc_commission_state *s, const bc_ctrl_in *in,
                        bc_ctrl_out *out);

#endif /* BC_COMMISSION_H */

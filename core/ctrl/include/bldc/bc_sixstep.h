/*
 * bc_sixstep.h - the real square-wave (120-degree) current-controlled supply of paper 1, section IV.A (float).
 *
 * Commutation. bc_hall gives the sector s of the Hall code and the electrical speed Omega_e (bc_hall.h). The
 * sector gives the phase driven positive and the phase driven negative (bc_commutation.h); the third leg is OFF,
 * so the phase leaving the pair keeps conducting through a diode until its current is zero (the plant does that,
 * nothing is scripted here). A negative reference swaps the roles of the two phases (reverse torque: the motor
 * is driven backward or braked forward), the amplitude is |ref|:
 *
 *     I_ref = min(|ref|, i_max)               (ref_torque = 0: ref is the current amplitude, A)
 *     I_ref = min(|ref| / k_e, i_max)         (ref_torque = 1: ref is a torque, N m; k_e = 2 k_phi, T = k_e I)
 *
 * With `advance` = 1 the controller commutates at the sample nearest the Hall edge predicted from the speed: the
 * output applies over [t_(k+D), t_(k+D+1)] (D = delay), so the next sector s_seen + dir is commanded when
 *
 *     |Omega_e| (t_k - t_edge + (D + 1/2) T_s) >= pi/3
 *
 * (the edge is due by the middle of the interval the output applies to; dir = direction of the last Hall edge).
 * The advance is never taken back: once s_seen + dir is commanded it is held, whatever the speed estimate says,
 * until the next Hall edge, which either confirms it (forward: s_seen catches up) or proves that the rotor reversed
 * (backward: the sector seen, or the next one backward, is commanded). Without this rule a Hall edge a few capture
 * ticks later than predicted made the sector fall back for a sample (bc_hall's estimate decays as (pi/3)/(t_k -
 * t_edge) once the edge is overdue, so |Omega_e| (t_k - t_edge) reaches pi/3 while the code still shows s_seen),
 * interrupting the incoming phase. The test above is monotone within a sector anyway (|Omega_e| is constant until
 * the edge is overdue and (pi/3)/(t_k - t_edge) after, so the left side never falls below pi/3 once there), and the
 * hold also covers the speed estimate timing out (a rotor stopped just before the edge). With advance = 0 the
 * legs follow the Hall sector seen, (D + 1/2) T_s late on average.
 *
 * Timing advance and timed commutation. adv = min(adv_angle + |Omega_e| adv_time, pi/6) moves every commutation adv
 * earlier (a constant adv_time compensates a fixed delay, as an ESC's timing advance does). With timed = 1 the
 * sector is decided for the start of the interval the output applies to, t_a = t_k + D T_s, and the next one is
 * scheduled at the predicted instant inside it, as a commutation timer does on an MCU:
 *
 *     travel = angle into the commanded sector's (advanced) span at t_a;   dt = (pi/3 - travel) / |Omega_e|
 *     dt < T_s:  legs of this sector from t_a, of the next from t_a + dt (bc_ctrl_out.has_at, t_at = dt)
 *
 * both built with the same pair voltage m (the regulation runs again at the next sample); the predictive law then
 * predicts the sample in force in its two parts. comm = BC_SIXSTEP_COMM_ENCODER takes sector and travel from the
 * encoder's angle and speed instead of the Hall sensors: the ideal commutation instant, a reference to measure the
 * Hall drive against (as the encoder angle of bc_sine). reg = BC_SIXSTEP_DUTY has no current loop: m = |ref|, a duty
 * in [0, 1] (above 1: 1 and BC_FLAG_SATURATED), the throttle of an ESC.
 *
 * Calibrated edges (hall_table set, bc_hall.h). The commutation is due at the *nominal* sector boundary, not at the
 * misplaced edge: with o = dir (theta_edge - nominal edge) of the edge just crossed (bc_hall_entry_lead), the next
 * sector is commanded when |Omega_e| (t_k - t_edge + (D + 1/2) T_s) >= pi/3 - o; after an early edge (o < 0) the
 * sector commanded before it is held while the travel since the edge is below -o (the rotor is still in the
 * previous nominal sector), then the sector seen follows. Both are monotone: a commanded sector is only ever
 * replaced by the next one in the direction of motion or by a Hall edge, never stepped back. With the nominal
 * table o = 0 and this is the rule above. advance = 0 ignores the table for the commutation. The rule is
 * bc_hall_commutate (bc_hall.h), shared with bc_lu, which applies it whenever it has a table.
 *
 * Regulated current. The phase x that entered the pair at the most recent commutation (the incoming phase: the
 * phase of the new pair that was not in the old one; the positive phase before the first commutation) is
 * regulated, as a magnitude: i_reg = +i_x if x is driven positive, -i_x if driven negative. Unmeasured phases are
 * reconstructed from i_mask: two measured phases give the third as -(sum) (fewer than two: BC_FLAG_BAD_INPUT).
 *
 * Chopping patterns. Every regulation law demands the normalised pair voltage m = u / V_dc (u: average
 * pos-to-neg voltage in continuous two-phase conduction); the pattern realises it with leg duties
 * (pos = phase driven positive, neg = phase driven negative):
 *
 *     BC_SIXSTEP_BIPOLAR  pos HIGH d, neg LOW d,  d = (1 + m)/2              u = (2 d - 1) V_dc,  m in [-1, 1]
 *     BC_SIXSTEP_HIGH     pos HIGH m, neg LOW 1                             u = m V_dc,          m in [0, 1]
 *     BC_SIXSTEP_PWMPWM   the chopping leg HIGH/LOW m, the other HIGH/LOW 1  u = m V_dc,          m in [0, 1]
 *                         a phase chops in the first and the last 30 degrees of its 120-degree conduction and is
 *                         fully on in the middle 60: in the first half of a sector (travel since the Hall edge
 *                         < pi/6, from the Hall speed) the incoming phase chops, in the second half the other one.
 *                         Without a speed estimate the incoming phase chops.
 *     BC_SIXSTEP_SYNC     pos PWM m (complementary), neg LOW 1               u = m V_dc, also in discontinuous
 *                                                                            conduction,          m in [0, 1]
 *
 * regen = 1 extends the three unipolar patterns to m in [-1, 0): both legs chop as in BIPOLAR with d = (1 + m)/2.
 * Their own lowest voltage, u = 0, short-circuits the line back-EMF through a switch and a diode, so a braking
 * current cannot be held once the line back-EMF exceeds 2 R I, nor pulled down faster than it freewheels.
 * PWM-on-PWM is the pattern that realises paper 1's commutation: while the outgoing current decays the continuing
 * phase is fully on and only the incoming phase chops.
 *
 * Regulation (reg):
 *
 *  BC_SIXSTEP_PI     u = k_p e + x + u_ff,  e = I_ref - i_reg,  u_ff = e_pos - e_neg + 2 R I_ref (emf_ff = 1)
 *                    bc_pi on the normalised pair voltage m = u / V_dc (the error and feed-forward are divided by
 *                    the measured bus), limited to [m_lo, 1] (m_lo = -1 with BIPOLAR or regen, else 0); the
 *                    integrator is updated with the realised m (anti-windup on the realised duty, bc_pi.h). Gains
 *                    for the line R-L (2R, 2L): bldclab.design.pi_gains.
 *  BC_SIXSTEP_IDEAL  paper 1's ideal current limiter, in continuous time, on the plant's averaged inverter: the
 *                    continuing phase fully on (HIGH or LOW at duty 1), the incoming phase x BC_LEG_HOLD at sgn_x
 *                    I_ref (its current held there while a duty in [0, 1] can, at full voltage toward it
 *                    otherwise: bc_plant.h), the third leg off. Not a controller for an MCU: the legs are no PWM
 *                    pattern; it gives the torque of (26)-(33)'s premise on any motor.
 *  BC_SIXSTEP_HYST   m = 1 when i_reg < I_ref - band/2, m = m_lo when i_reg > I_ref + band/2, else the previous
 *                    (evaluated at the samples; band = total width, A).
 *  BC_SIXSTEP_PRED   predictive ("deadbeat"): the m that brings i_reg to I_ref at the sample after next:
 *
 *                        i(k+1)     = F(i(k), c_applied)                 (the command already in force, D = 1)
 *                        i(k+1+D)   = F(i(k+D), c(m)),     solve  sgn_x i_x(k+1+D) = I_ref  for m in [m_lo, 1]
 *
 *                    saturating at m = 1 (full voltage: paper 1's "incoming current driven at full voltage until
 *                    it reaches I_N") or m_lo; c(m) are the pattern's leg commands. F advances the phase currents
 *                    over one sample T_s with the average model of the inverter and motor (forward Euler, exact
 *                    for R = 0 and piecewise-constant back-EMF):
 *
 *                        u_j  = average terminal voltage of leg j over the half period, from its mode, duty d
 *                               and the sign of i_j:  PWM d V;  HIGH: d V (i >= 0), V (i < 0);  LOW: (1 - d) V
 *                               (i <= 0), 0 (i > 0);  OFF (or HIGH/LOW with d = 0): 0 (i > 0), V (i < 0),
 *                               open (i = 0);   V = measured V_dc
 *                        v_n  = mean over the connected phases of (u_j - R i_j - e_j)
 *                        L di_j/dt = u_j - R i_j - e_j - v_n    (connected), 0 (open)
 *                        e_j  = (k_e / 2) (Omega_e / p) k(theta + Omega_e t - j 2 pi/3)   (ideal 120-degree
 *                               trapezoid k of unit flat top, at the Hall-interpolated angle at mid-interval)
 *
 *                    A diode-only phase whose current reaches zero inside the sample opens there (the step is
 *                    split), so the law covers the three-phase commutation interval, where the outgoing phase
 *                    still conducts, as well as two-phase conduction, for every chopping pattern. In two-phase
 *                    conduction with R = 0 it reduces to  i(k+2) = i(k+1) + T_s (m V_dc - e_pos + e_neg) / (2 L),
 *                    m = (2 L (I_ref - i(k+1)) / T_s + e_pos - e_neg) / V_dc. m is solved on [0, 1], then on
 *                    [m_lo, 0] if even m = 0 overshoots: when no diode current ends inside the sample at either
 *                    end of the bracket the end current is affine in m and the line through the ends is exact;
 *                    otherwise (and on [m_lo, 0], where m < 0 switches both legs) the Illinois method refines it.
 *
 * Safety: the input guard (bc_guard.h, with i_max and v_max: current reconstruction from i_mask, the DC-bus limits
 * 0 < V_dc <= v_max, the hardware fault pin, the over-current trip |i_x| > i_max latched until every |i_x| < i_max / 2
 * at a sample with valid measurements, or bc_sixstep_init) gives BC_FLAG_BAD_INPUT or BC_FLAG_OVERCURRENT; an
 * invalid Hall code adds BC_FLAG_HALL_INVALID, a non-finite reference BC_FLAG_BAD_INPUT. Any of them: all legs off,
 * BC_FLAG_SAFE. In the safe state the PI integrator and the hysteresis state are reset and the incoming phase
 * is forgotten. Output duties are always finite and in [0, 1].
 *
 * Diagnostics: diag[0] sector commanded (-1 safe), [1] i_reg (A), [2] I_ref (A), [3] m (pair voltage / V_dc),
 * [4] Omega_e (electrical rad/s), [5] incoming phase (0..2, -1), [6] chopping leg (0..2; 3 both; -1 none), [7] |i|
 * of the phase outside the pair (A): non-zero while the outgoing phase freewheels.
 */
#ifndef BC_SIXSTEP_H
#define BC_SIXSTEP_H

#include <stdint.h>

#include "bldc/bc_derate.h"
#include "bldc/bc_guard.h"
#include "bldc/bc_hall.h"
#include "bldc/bc_pi.h"
#include "bldc/bc_types.h"

/* regulation */
#define BC_SIXSTEP_PI 0
#define BC_SIXSTEP_HYST 1
#define BC_SIXSTEP_PRED 2
#define BC_SIXSTEP_DUTY 3 /* no current loop: m = |ref| (a duty in [0, 1], ref's sign the direction), as an ESC */
#define BC_SIXSTEP_IDEAL 4 /* paper 1's ideal current limiter (a reference model for the averaged inverter, not an
                              MCU's): the incoming phase's leg is BC_LEG_HOLD at sgn_x I_ref, the plant holds it */

/* commutation angle source */
#define BC_SIXSTEP_COMM_HALL 0    /* the Hall sensors (bc_hall_commutate) */
#define BC_SIXSTEP_COMM_ENCODER 1 /* the encoder angle and speed: the ideal instant, a reference for comparison */

/* chopping pattern */
#define BC_SIXSTEP_BIPOLAR 0
#define BC_SIXSTEP_HIGH 1
#define BC_SIXSTEP_PWMPWM 2
#define BC_SIXSTEP_SYNC 3

typedef struct {
    int32_t reg;          /* BC_SIXSTEP_PI, _HYST, _PRED, _DUTY, _IDEAL */
    int32_t chop;         /* BC_SIXSTEP_BIPOLAR, _HIGH, _PWMPWM, _SYNC */
    int32_t ref_torque;   /* 0: ref = current amplitude I (A); 1: ref = torque (N m), I = ref / k_e */
    int32_t delay;        /* samples between computing and applying an output, 0 or 1 (as the runner/DSP) */
    int32_t advance;      /* 1: commutate at the sample nearest the predicted Hall edge; 0: on the edge seen */
    int32_t timed;        /* 1: commutate at the predicted instant inside the interval (bc_ctrl_out.has_at: a
                             commutation timer); implies the prediction of advance = 1 */
    float adv_angle;      /* timing advance at any speed, electrical rad (>= 0) */
    float adv_time;       /* timing advance per speed, s: the advance angle grows by |Omega_e| adv_time (>= 0);
                             the total is capped at pi/6 */
    int32_t comm;         /* BC_SIXSTEP_COMM_HALL or _ENCODER */
    int32_t emf_ff;       /* 1: PI with back-EMF (and 2 R I_ref) feed-forward */
    int32_t regen;        /* 1: unipolar patterns reach m < 0 by chopping both legs */
    int32_t p;            /* pole pairs (>= 1) */
    float ts;             /* sampling period, half the PWM period, s (> 0) */
    float R;              /* phase resistance including the switch, Ohm (>= 0) */
    float L;              /* inclusive phase inductance L_self - M, H (> 0) */
    float k_e;            /* line back-EMF constant 2 k_phi, V s/rad (per mechanical rad/s) (> 0) */
    float kp;             /* PI proportional gain of the line current loop, V/A (>= 0) */
    float ki;             /* PI integral gain, V/(A s) (>= 0) */
    float band;           /* hysteresis band (total width), A (> 0) */
    float i_max;          /* over-current trip and reference limit, A (> 0) */
    float v_max;          /* largest plausible DC-bus measurement, V (> 0) */
    float f_tick;         /* Hall capture-timer frequency, Hz (> 0) */
    float omega_min;      /* Hall: slowest speed estimated, electrical rad/s (> 0) */
    float theta_offset;   /* Hall: angle correction, electrical rad */
    int32_t hall_mode;       /* Hall angle: BC_HALL_INTERP (46) or BC_HALL_PLL (bc_hall.h) */
    float hall_pll_edges;    /* BC_HALL_PLL: loop time constant in edges (1 .. 1000) */
    bc_hall_table hall_table; /* calibrated edge angles (set = 0: nominal; bc_hallcal.h) */
    bc_derate_params derate;  /* temperature derating of the current reference's limit i_max (bc_derate.h) from
                                 in->temp; no channel enabled (all zero): none */
    float open_frac;          /* no-current-path detection (0: off; else in (0, 0.5)): see bc_sixstep_step */
} bc_sixstep_params;

typedef struct {
    bc_hall_params hall_p; /* derived in init */
    bc_hall_state hall;
    bc_pi_params pi_p;     /* derived in init: the PI on the normalised pair voltage, limits [-1, 1] */
    bc_pi_state pi;
    bc_leg_cmd applied[3]; /* command in force over the current sample (the previous output when delay = 1) */
    bc_leg_cmd applied_at[3]; /* ... and from applied_t on, if applied_t >= 0 (a timed commutation in it) */
    float applied_t;       /* s after the start of the sample, -1 none */
    int32_t sector;        /* sector commanded, -1 none */
    int32_t seen;          /* Hall sector seen at the last sample, -1 none */
    int32_t incoming;      /* phase that entered at the last commutation, -1 none */
    int32_t hyst_on;       /* hysteresis: 1 switch on */
    bc_guard_params guard_p; /* derived in init: i_max, v_max */
    bc_guard_state guard;    /* input guard: the over-current latch (bc_guard.h) */
    bc_derate_state derate;  /* the derating's filter */
    int32_t derate_on;       /* a derating channel is enabled */
    float derate_f;          /* its factor at the last sample (1 without) */
    int32_t open_n;          /* no-current-path detection: samples counted; -1 latched (safe until init) */
    float open_acc;          /* ... and the sum of T_s / t_2 over them (bc_sixstep_step) */
} bc_sixstep_state;

/* Validate the parameters (finite, in range) and reset the state. BC_OK or BC_ERR_PARAM. */
int bc_sixstep_init(const bc_sixstep_params *p, bc_sixstep_state *s);

/* One sample: measurements in, leg commands for the next half period out (see above). */
void bc_sixstep_step(const bc_sixstep_params *p, bc_sixstep_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);

/* Average-model prediction used by BC_SIXSTEP_PRED (exposed for tests): advance the phase currents i[3] (A, sum 0)
 * over t seconds under the leg commands cmd[3] with bus voltage v (V), back-EMFs e[3] (V), R (Ohm), L (H).
 * Returns the number of diode-only phases whose current ended inside t. */
int bc_sixstep_predict(const bc_leg_cmd cmd[3], float v, const float e[3], float R, float L, float t, float i[3]);

#endif /* BC_SIXSTEP_H */

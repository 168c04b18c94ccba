/*
 * bc_lu.h - paper 2's torque controller (H. Lu, L. Zhang, W. Qu, IEEE Trans. Power Electron. 2008) and the two
 * methods it is compared with: torque control neglecting the finite DC bus (no D_o) and conventional rectangular
 * current control (float). Derivations and conventions: docs/theory-paper2.md.
 *
 * Notation. The sector commanded gives the phase driven positive and the one driven negative (bc_commutation.h).
 * With the nominal table (hall_table.set = 0) it is the Hall sector seen: no advance, the pair changes only with the
 * Hall code, so it never steps back unless the rotor does. With a calibrated table (set = 1) the pair changes at the
 * nominal sector boundary instead of the misplaced edge (bc_hall_commutate, the rule of bc_sixstep.h, "Calibrated
 * edges", with advance): the next sector is commanded once the angle travelled since the Hall edge, at the middle
 * of the interval the output applies to ((delay + 1/2) T_s after the sample), reaches the nominal boundary (a late
 * edge: before the code moves); after an early edge the previous sector is held until the nominal boundary. A
 * commanded sector is replaced only by the next one in the direction of motion or by a Hall edge, never stepped
 * back. Everything below that uses the pair (P, N, the outgoing phase F, the commutation and D_o modes, RECT)
 * follows the commanded sector. With
 * T* = in.ref (N m) >= 0 the pair is P = pos, N = neg; with T* < 0 the roles swap (reverse torque). F is the third
 * phase, whose leg is off (in a commutation: the outgoing phase). V = measured v_dc; Omega_e from bc_hall,
 * w = Omega_e / p (mechanical); theta from bc_hall (angle interpolated between Hall edges, paper 2 Figs 8-9).
 * f_x = f_x(theta - x 2 pi/3) are the back-EMF shape functions (25), V s/rad, read from three tables of n uniform
 * points of the phase's local angle by linear interpolation; e_x = w f_x. Sums run over a, b, c:
 *
 *     T      = sum f_x i_x                                    torque (1) with e = f w: w cancels (defined at w = 0)
 *     fbar   = (f_a + f_b + f_c) / 3,    g = (f_a - f_b)^2 + (f_b - f_c)^2 + (f_c - f_a)^2,    lam = f_P - f_N
 *
 * One-step models (the paper's state-space averages over one sample T_s, shapes frozen over the step, R i taken
 * at the start of the step; the paper neglects R, here R = params.R, 0 reproduces the paper). Bipolar chopping:
 * S = +1 for D T_s (P's upper and N's lower switch on), S = -1 otherwise (both off, the diodes conduct):
 *
 *   (6)/(7)   F open:       di_P = -di_N = T_s (V (2D - 1) - w lam - 2 R i_P) / (2 L)
 *   (14)/(15) F conducts through its diode (v_F = 0 if i_F > 0, V if i_F < 0), three phases:
 *                           di_x = T_s (v_x - v_n - w f_x - R i_x) / L,   v_n = (v_a + v_b + v_c - w sum f) / 3,
 *                           v_P = D V, v_N = (1 - D) V   (average terminal voltages over the sample)
 *   (22)      D_o mode:     the same with v_P = V, v_N = 0, v_F = D_o V (i_F > 0) or (1 - D_o) V (i_F < 0)
 *   extinction: in (14)/(15) v_n does not depend on D, so F's slope s_F = (v_F - v_n - w f_F - R i_F) / L does not
 *             either. If i_F + s_F T_s has the other sign, F opens at t_x = -i_F / s_F inside the sample: the step is
 *             (14)/(15) over [0, t_x] and (6)/(7) over [t_x, T_s] (the duty enters both with the same gain).
 *
 * Laws: the duty that makes the model's T(k+1) = T*, written with the shapes (w appears only in numerators):
 *
 *   (9')   D_n = 1/2 + (T* - T) L / (V T_s lam) + w lam / (2 V) + R i_P / V                        F open
 *   (17')  D_c = [(T* - T) L / T_s + w g / 3 + R T - V (f_N - fbar) - v_F (f_F - fbar)] / (V lam)   F conducts all T_s
 *   (D_s)  D_s = D_n + i_F L (2 f_F - f_P - f_N) / (2 V T_s lam) + R t_x i_F / (2 V T_s)      F opens at t_x < T_s
 *   (24')  D_o = [(T* - T) L / T_s + w g / 3 + R T - B] / (sig V (f_F - fbar)),   sig = sign(i_F),
 *               B = V (f_P - fbar) (i_F > 0),  B = -V (f_N - fbar) (i_F < 0)
 *
 * (9') is paper (9), (17') is (17) (with i_F > 0: P incoming, N non-commutated, F outgoing; i_F < 0 is the mirror
 * image), (24') is (24), each multiplied out with e = f w and R added. D_s (not in the paper) is the exact
 * solution of the split step: D_s -> D_n as i_F -> 0 and D_s = D_c when t_x = T_s.
 *
 * Switching logic (one sample; "conducts" = |i_F| > i_zero):
 *   - F open: normal conduction, pos HIGH D_n, neg LOW D_n (S = -1: both off, diodes), F off.    mode 0
 *   - F conducts: commutation, the pair (incoming and non-commutated phases) chops with D_c (or D_s), F off so its
 *     diode freewheels.                                                                         mode 1
 *   - method LU, D_c (or D_s) > 1 (torque still short at full duty), and the D_o lever sig (f_F - fbar) has the
 *     torque's sign: D_o mode: P HIGH 1, N LOW 1, F HIGH D_o (i_F > 0) or LOW D_o (i_F < 0), with D_o kept
 *     between D_zero (F reaches exactly 0 at the end of the sample: (22) is invalid past the zero) and D_hold
 *     (i_F constant: D_o slows the outgoing current, it never stops or reverses it).             mode 2
 *   - The commutation ends when |i_F| <= i_zero (measured, or predicted with delay 1).
 *   - method NO_DO: as LU without the D_o mode (paper 2's "torque control neglecting finite dc bus").
 *   - method RECT: conventional rectangular current control: the same pairs and bipolar chopping, F off; a PI
 *     (bc_pi) on the current of the non-commutated phase in the pair's direction, i_m = -i_N if i_F >= 0, i_P if
 *     i_F < 0 (the pair current i_P = -i_N in two-phase conduction), holds I* = min(|T*| / (2 k_phi), i_max):
 *         u = k_p (I* - i_m) + x   (V, pair voltage, no back-EMF feed-forward),   D = 1/2 + u / (2 V),
 *     the integrator updated with the realised u = (2 D - 1) V (anti-windup), and negated when the sign of T*
 *     changes (the swapped pair's back-EMF has the other sign).
 *   Duties are clamped to [0, 1] (BC_FLAG_SATURATED when clamped).
 *
 * Switching order (order >= 1; not in the paper). The averaged models assume both phases of the pair conduct in
 * both switch states. A pair phase with zero current cannot conduct in the off state (its diode would have to carry
 * current the wrong way): the incoming phase at the start of a commutation, and any phase in discontinuous
 * conduction. Centre-aligned PWM puts the off part of a rising half period (after a carrier valley) first and that
 * of a falling half period last, so the end current then depends on the order. With order >= 1 the step follows the
 * half period part by part (the same circuit, R i at the start of the step, a diode-only phase opening when its
 * current reaches zero: exact for R = 0 and frozen shapes) and the PAIR duty is the root of T(k+1) = T* in [0, 1]
 * (Illinois method started from the closed-form duty, which is returned unchanged whenever the averaged model holds).
 * The half period's direction comes from counting samples from bc_lu_init, which the runner calls before its first
 * sample, taken at a carrier valley (firmware: the PWM timer's counting direction).
 *
 * The mean law (order = 2; not in the paper). The laws above make the torque at the SAMPLES equal to T*. That is its
 * mean only while the current is continuous (a symmetric triangle about each sample). At light load bipolar chopping
 * stops the current within the PWM period (its ripple V D (1 - D) / (L f_pwm) exceeds twice the mean): the rising
 * half (off part first) can only reach T* at its end by letting the current die and rise again, the falling half then
 * carries a large pulse above T*, and the mean torque is up to 2.4 times T* on lu-4kw (docs/theory-paper2.md). With
 * order = 2, at the start of each PWM period (the output for a rising half period) the step also solves for the
 * PAIR duty d_m that makes the ordered model's mean torque over the whole period (rising then falling half, the same
 * duty) equal to T* (skipped if the current does not stop under the end-value duty either, unless the last period
 * was discontinuous); if under d_m the current stops at some instant of the period, d_m is used (diag mode 3) and
 * the period's falling half gets the duty whose mean over that half is 2 T* - (the model's mean over the rising
 * half, from the measured currents with delay 1, as predicted with delay 0), so the period's mean is T* whatever the
 * first half did (if that is out of reach, e.g. a commutation in the half, the end-value law). Otherwise
 * (continuous conduction) the end-value laws stay: a mean law alone is only marginally stable there (mean =
 * (i(k) + i(k+2)) / 2 fixes the sum of two sample currents, not each). Not applied in D_o mode and not to RECT. A
 * period mean beyond reach saturates the duty (BC_FLAG_SATURATED).
 *
 * Delay. The runner applies an output one sample after it was computed (delay = 1, the DSP case) or at once
 * (delay = 0, what the paper's laws assume: the duty computed at k acts over [k, k+1]). With delay = 1 the step
 * first predicts i(k+1) from the measured i(k) under the command already in force over [k, k+1] (the same models),
 * takes theta(k+1) = theta(k) + Omega_e T_s, and solves the law for [k+1, k+2] from there. With delay = 0 the laws
 * start from the measurements.
 *
 * Guards. |lam| (and the D_o lever) below lever_min = 1e-3 max|f| is replaced by lever_min with its sign: the
 * duties saturate instead of dividing by ~0 (only a wrong angle puts the pair near a zero crossing). Omega_e = 0
 * (standstill, no two Hall edges yet): the angle is the middle of the sector and every law still holds.
 *
 * Inductance adaptation (l_adapt > 0; not in the paper). Every law above is a model prediction. While the current
 * is continuous the sampled current feeds back and the end-value laws converge for any inductance estimate below
 * about 2 L (deadbeat: the error shrinks by 1 - L_est / L per sample). Where the current stops within the PWM period
 * (light load, or a low L f_pwm) the period starts from zero whatever the last one did: the law is feed-forward
 * and the mean torque is T* L_est / L (docs/theory-paper2.md, 5.2). The step then fits its inductance to the
 * measured current: over a rising half period (off part first, then on part) in normal conduction (F open at both
 * ends), with a valid speed estimate (else the model's back-EMF is zero), the model's rise of the pair current
 * dI_pred = i_P,pred(k+1) - i_P(k) scales as 1/L_hat and the measured rise dI_meas as 1/L (exactly where the
 * current starts at zero: the off part is dead, the on part rises under the same voltage). When both rises exceed
 * 0.5 % of i_max with the same sign:
 *
 *     L_hat <- clamp(L_hat (1 + l_adapt (clamp(dI_pred / dI_meas, 1/2, 2) - 1)), L/4, 4 L)
 *
 * and every model and law of the step uses L_hat. While the current is continuous and steady the rises are below
 * the threshold (the samples sit at the ripple's mean) and L_hat holds. With l_adapt = 0 the controller is the one
 * described above. An error in the back-EMF estimate is absorbed into L_hat (the rise is fitted, not L itself).
 * Limits (measured in docs/theory-paper2.md, 5.2): where the current stops between samples and the model, with L_hat
 * above L, does not predict the stop, the ratio is not 1/L and L_hat wanders; the torque is then that of the
 * non-adaptive law (no worse).
 *
 * Safety: the input guard (bc_guard.h, with i_max and v_max: current reconstruction from i_mask, the DC-bus limits
 * 0 < v_dc <= v_max, the hardware fault pin, the over-current trip |i_x| > i_max latched until every |i_x| < i_max / 2
 * at a sample with valid measurements, or bc_lu_init) gives BC_FLAG_BAD_INPUT or BC_FLAG_OVERCURRENT; an invalid
 * Hall code (000, 111) adds BC_FLAG_HALL_INVALID, a non-finite reference BC_FLAG_BAD_INPUT. Any of them: all legs
 * off, BC_FLAG_SAFE.
 * Output duties are finite and in [0, 1] for any input.
 *
 * Diagnostics: diag[0] mode (-1 safe, 0 normal, 1 commutation D_c/D_s, 2 D_o, 3 mean law), [1] duty computed (D_n,
 * D_c, D_s, D_o or the mean law's; RECT: D), [2] T estimated at this sample from the measured currents (N m), [3]
 * the model's torque at the next sample (N m: under the new output with delay 0, under the output in force with
 * delay 1), [4] theta (rad),
 * [5] Omega_e (electrical rad/s), [6] i_F of the new output's off phase at the start of its interval (A),
 * [7] sector commanded (-1 safe).
 */
#ifndef BC_LU_H
#define BC_LU_H

#include <stdint.h>

#include "bldc/bc_guard.h"
#include "bldc/bc_hall.h"
#include "bldc/bc_pi.h"
#include "bldc/bc_types.h"

/* method */
#define BC_LU_TORQUE 0 /* paper 2: D_n, D_c, D_o */
#define BC_LU_NO_DO 1  /* paper 2 without D_o: "torque control neglecting finite dc bus" */
#define BC_LU_RECT 2   /* conventional rectangular current control (PI), same commutation and chopping */

/* plan kinds: what an output does (kept for the delay-1 prediction) */
#define BC_LU_SAFE 0 /* all legs off */
#define BC_LU_PAIR 1 /* P HIGH d, N LOW d, F off: normal conduction and commutation (D_n, D_c, D_s, RECT) */
#define BC_LU_DO 2   /* P HIGH 1, N LOW 1, F HIGH d (i_F > 0) or LOW d (i_F < 0) */

typedef struct {
    const float *f[3];  /* shape tables f_a, f_b, f_c: f_x at its local angle 2 pi j / n, j = 0..n-1, V s/rad */
    int32_t n;          /* points per table (>= 3) */
    int32_t p;          /* pole pairs (>= 1) */
    int32_t method;     /* BC_LU_TORQUE, BC_LU_NO_DO, BC_LU_RECT */
    int32_t delay;      /* samples between computing and applying an output, 0 or 1 (as the runner/DSP) */
    int32_t order;      /* 0: the averaged models; 1: also the switching order within the half period; 2: as 1,
                         * and the mean law in discontinuous conduction (see above) */
    float L;            /* inclusive phase inductance L_self - M, H (> 0) */
    float R;            /* phase resistance in the models, Ohm (>= 0; 0: the paper's laws) */
    float ts;           /* sampling period, half the PWM period, s (> 0) */
    float i_max;        /* over-current trip, A (> 0) */
    float i_zero;       /* an off phase with |i| <= i_zero is open (commutation over), A (>= 0, < i_max) */
    float v_max;        /* largest plausible DC-bus measurement, V (> 0) */
    float k_phi;        /* RECT: I* = |T*| / (2 k_phi), V s/rad (> 0) */
    float kp;           /* RECT: PI proportional gain of the pair-current loop, V/A (>= 0) */
    float ki;           /* RECT: PI integral gain, V/(A s) (>= 0) */
    float f_tick;       /* Hall capture-timer frequency, Hz (> 0) */
    float omega_min;    /* Hall: slowest speed estimated, electrical rad/s (> 0) */
    float theta_offset; /* Hall: angle correction, electrical rad */
    float l_adapt;      /* inductance adaptation gain in [0, 1] (0: off, L fixed; see "Inductance adaptation") */
    int32_t hall_mode;       /* Hall angle: BC_HALL_INTERP (46) or BC_HALL_PLL (bc_hall.h) */
    float hall_pll_edges;    /* BC_HALL_PLL: loop time constant in edges (1 .. 1000) */
    bc_hall_table hall_table; /* calibrated edge angles (set = 0: nominal; bc_hallcal.h) */
} bc_lu_params;

/* What an output does over its interval. */
typedef struct {
    int32_t kind; /* BC_LU_SAFE, BC_LU_PAIR, BC_LU_DO */
    int32_t pos;  /* P: phase whose upper switch chops (PAIR) or is on (DO) */
    int32_t neg;  /* N: phase whose lower switch chops (PAIR) or is on (DO) */
    int32_t off;  /* F: the third phase (off in PAIR, chopping in DO) */
    int32_t sig;  /* DO: +1 F's upper switch chops (i_F > 0), -1 its lower switch (i_F < 0); PAIR: 0 */
    float duty;   /* D (PAIR) or D_o (DO) */
} bc_lu_plan;

typedef struct {
    bc_hall_params hall_p; /* derived in init */
    bc_hall_state hall;
    bc_pi_params pi_p;     /* derived in init: RECT's PI, output the pair voltage in [-v_max, v_max] */
    bc_pi_state pi;
    float lever_min;       /* derived in init: 1e-3 max |f|, V s/rad */
    float tol;             /* derived in init: torque tolerance of the ordered solve, 1e-4 max |f| i_max, N m */
    bc_lu_plan applied;    /* the output in force over the current sample (delay 1: the previous output) */
    bc_guard_params guard_p; /* derived in init: i_max, v_max */
    bc_guard_state guard;    /* input guard: the over-current latch (bc_guard.h) */
    int32_t parity;        /* 0: the sample being taken is at a carrier valley (the next half period rises) */
    int32_t dir;           /* RECT: sign of the last torque reference (+1, -1; 0 none yet) */
    int32_t dcm;           /* order 2: the PWM period under way conducts discontinuously (mean law) */
    float t_first;         /* order 2: the model's mean torque over the period's first half, N m */
    float d_mean;          /* order 2: the last discontinuous period's duty (0: none), the next solve's guess */
    float l_hat;           /* the inductance the models use: p->L, adapted when l_adapt > 0, H */
    float i_start[3];      /* adaptation: measured currents at the start of the last step's interval, A */
    float i_end[3];        /* adaptation: the model's currents at its end (prediction), A */
    bc_lu_plan pred_plan;  /* adaptation: the output the prediction assumed (SAFE: no prediction to check) */
    int32_t pred_rising;   /* adaptation: that interval was a rising half period (off part first) */
    int32_t pred_speed;    /* adaptation: the speed estimate was valid (the model's back-EMF is not 0) */
    int32_t sector;        /* sector commanded by the last output (its pair), -1 none */
    int32_t seen;          /* Hall sector seen at the last sample, -1 none */
} bc_lu_state;

/* An operating point at the start of a step: what the models and laws need. */
typedef struct {
    float i[3];    /* phase currents, A (sum 0) */
    float f[3];    /* shapes at the step's angle, V s/rad */
    float omega_m; /* mechanical speed, rad/s */
    float v_dc;    /* DC bus, V (> 0) */
} bc_lu_point;

/* Validate the parameters (finite, in range, tables present and not all zero) and reset the state.
 * BC_OK or BC_ERR_PARAM. */
int bc_lu_init(const bc_lu_params *p, bc_lu_state *s);

/* One sample: measurements in, leg commands for the next half period out (see above). */
void bc_lu_step(const bc_lu_params *p, bc_lu_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);

/* The blocks of the step, exposed for tests. */

/* Linear interpolation of a table of n uniform points over [0, 2 pi) at any finite angle theta (rad). */
float bc_lu_shape(const float *table, int32_t n, float theta);

/* Shapes f_a, f_b, f_c at the electrical angle theta (each at its local angle theta - x 2 pi/3). */
void bc_lu_shapes(const bc_lu_params *p, float theta, float f[3]);

/* T = sum f_x i_x (N m). */
float bc_lu_torque(const bc_lu_point *x);

/* Time (s, in [0, ts]) the off phase F keeps conducting through its diode while P, N chop (the extinction rule
 * above): 0 if |i_F| <= i_zero, ts if its current does not reach zero within the sample. */
float bc_lu_extinction(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg);

/* The laws (unclamped duties): (9'), (17'), D_s, (24'). lever_min guards the denominators. */
float bc_lu_dn(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, float lever_min);
float bc_lu_dc(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, float lever_min);
float bc_lu_ds(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, float lever_min);
float bc_lu_do(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, float lever_min);

/* D_o keeping F's current between zero and constant over the sample: *d_zero (reaches 0 at the end), *d_hold. */
void bc_lu_do_bounds(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float *d_zero, float *d_hold);

/* The averaged one-step models: the currents at the end of the step under a plan (SAFE: all legs off, ordered). */
void bc_lu_predict(const bc_lu_params *p, const bc_lu_point *x, const bc_lu_plan *plan, float i_next[3]);

/* The ordered one-step model: the same circuit followed through the half period's two parts in their order
 * (rising = 1: off-part first; 0: on-part first), a diode-only phase opening when its current reaches zero. */
void bc_lu_predict_ordered(const bc_lu_params *p, const bc_lu_point *x, const bc_lu_plan *plan, int rising,
                           float i_next[3]);

/* The same, also returning the mean torque over the step (N m, shapes frozen) and *dry = 1 if at some instant of
 * the step no phase carries current (discontinuous conduction; also when the step starts with no current). */
float bc_lu_mean_ordered(const bc_lu_params *p, const bc_lu_point *x, const bc_lu_plan *plan, int rising,
                         float i_next[3], int *dry);

/* The PAIR duty that makes the ordered model's T(k+1) = T* (|error| <= tol, N m), starting from the closed-form
 * duty d0 (inside [0, 1]: bracketed between d0 and the end of [0, 1] on the root's side, the other end never
 * evaluated); beyond [0, 1] it returns d0 if d0 is beyond on the same side, else past 1 (or 0) by the shortfall
 * over the bracket's slope: > 1 means T* is out of reach at full duty, < 0 at zero duty. */
float bc_lu_solve_pair(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, int rising,
                       float d0, float tol);

/* The same for the ordered model's mean torque over the step (bc_lu_mean_ordered) instead of T(k+1); two = 1:
 * over the step and the next one (the other direction) under the same duty. */
float bc_lu_solve_pair_mean(const bc_lu_params *p, const bc_lu_point *x, int pos, int neg, float t_ref, int rising,
                            float d0, float tol, int two);

#endif /* BC_LU_H */

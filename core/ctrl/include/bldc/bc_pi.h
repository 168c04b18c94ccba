/*
 * bc_pi.h - discrete PI controller, output first then update, anti-windup on the realised output (float).
 *
 *     u_k     = k_p e_k + x_k + u_ff                             (bc_pi_output: the unlimited output)
 *     x_(k+1) = x_k + k_i T_s (e_k + (u_real,k - u_k) / k_p)      (bc_pi_update)
 *
 * u_real is the output actually applied (after this block's limits, or a caller's: a voltage-vector limit, a
 * duty saturation). When nothing was limited the update is the forward-Euler integral of the error; when the
 * output was limited the integrator is pulled back to what would have produced the applied output (back-
 * calculation with gain 1/k_p), so it cannot wind up. With k_p = 0 the integrator is clamped to [u_min, u_max].
 * Continuous-time equivalent: C(s) = k_p + k_i / s. Gains from a bandwidth and a phase margin:
 * bldclab.design.pi_gains (Python).
 *
 * Non-finite errors or feed-forwards are treated as 0; the state stays finite and within the limits.
 */
#ifndef BC_PI_H
#define BC_PI_H

typedef struct {
    float kp;    /* proportional gain, output unit per error unit */
    float ki;    /* integral gain, output unit per (error unit s) */
    float ts;    /* sampling period, s */
    float u_min; /* output limits (bc_pi_step) and integrator bounds */
    float u_max;
} bc_pi_params;

typedef struct {
    float x; /* integrator, output unit */
} bc_pi_state;

/* Validate (finite, k_p, k_i, T_s >= 0, T_s > 0, u_min < u_max) and reset the integrator to 0 clamped. */
int bc_pi_init(const bc_pi_params *p, bc_pi_state *s);

/* Set the integrator (bumpless transfer), clamped to the limits. */
void bc_pi_reset(const bc_pi_params *p, bc_pi_state *s, float x0);

/* Unlimited output u = k_p e + x + u_ff. */
float bc_pi_output(const bc_pi_params *p, const bc_pi_state *s, float e, float u_ff);

/* u clamped to [u_min, u_max] (NaN gives 0 clamped). */
float bc_pi_limit(const bc_pi_params *p, float u);

/* Integrator update with the error e, the unlimited output u and the output actually applied u_real. */
void bc_pi_update(const bc_pi_params *p, bc_pi_state *s, float e, float u, float u_real);

/* One complete step with this block's own limits: output, limit, update; returns the applied output. */
float bc_pi_step(const bc_pi_params *p, bc_pi_state *s, float e, float u_ff);

#endif /* BC_PI_H */

/*
 * bc_fluxobs.h - nonlinear flux observer with a phase-locked loop (float): the rotor angle and speed of a
 * surface-mount PM motor from its voltages and currents, without a position sensor.
 *
 * Reference: J. Lee, J. Hong, K. Nam, R. Ortega, L. Praly, A. Astolfi, "Sensorless control of surface-mount
 * permanent-magnet synchronous motors based on a nonlinear observer," IEEE Trans. Power Electronics 25(2), 290-297,
 * 2010, DOI 10.1109/TPEL.2009.2025276 (the observer VESC and ODrive run). docs/sensorless-sine.md has the theory,
 * the defaults and the measurements.
 *
 * Model (stator frame, amplitude-invariant alpha-beta, bc_transform.h): with x = L i + psi_f (cos th_d, sin th_d)
 * the stator flux and th_d = theta_e - pi the d axis (PM flux) of bldclab's electrical angle theta_e,
 *
 *     dx/dt = u - R i,        eta(x) = x - L i = psi_f (cos th_d, sin th_d),        |eta|^2 = psi_f^2
 *
 * The observer integrates the voltage model and pulls eta onto the circle of radius psi_f (paper (8)):
 *
 *     dx^/dt = u - R i + (gamma/2) eta(x^) (psi_f^2 - |eta(x^)|^2),        gamma = lambda / psi_f^2
 *
 * Linearised about the circle, the radial error r of eta obeys dr/dt = -gamma psi_f^2 r = -lambda r: lambda (rad/s,
 * `gain`) is the radial convergence rate, independent of the motor's flux (ODrive's normalisation). The angle of
 * eta is the d axis; theta_raw = atan2(eta_beta, eta_alpha) + pi.
 *
 * One sample k (T_s = ts), in order:
 *
 *  1. Sanitise. A non-finite input (u or i): no update (the state holds, the PLL angle advances with its speed, valid
 *     = 0). Otherwise u and i are clamped to +-v_max, +-i_max per component.
 *  2. Voltage model over [t_k-1, t_k] (u: the voltage applied over that interval; the trapezoid rule on the current):
 *
 *         x^ += T_s (u - R (i_k-1 + i_k) / 2)         (first sample: i_k-1 = i_k)
 *
 *  3. Correction, explicit Euler with its step bounded so that it never overshoots the circle's centre:
 *
 *         eta = x^ - L i_k,    m = T_s (gamma/2) (psi_f^2 - |eta|^2) clamped to [-1, T_s lambda / 2],
 *         x^ += m eta                                  (then |x^_alpha,beta| <= 4 psi_f + L i_max)
 *
 *  4. Angle: eta = x^ - L i_k,  theta_raw = wrap(atan2(eta_beta, eta_alpha) + pi).
 *  5. PLL (type 2, critically damped, bandwidth omega_p = pll_bw; ODrive's design): with the phase error
 *     e = wrap_pm(theta_raw - theta^),
 *
 *         theta^ += T_s (omega^ + k_p e),  omega^ += T_s k_i e,     k_p = 2 omega_p,  k_i = omega_p^2
 *
 *     (closed loop (s^2 + k_p s + k_i) = (s + omega_p)^2 on the angle; a constant electrical acceleration a lags it
 *     by a / omega_p^2), |omega^| <= omega_max = 4 v_max / psi_f.
 *
 * Outputs (bc_obs_out): theta = the PLL's angle for t_k, predicted at sample k-1 (before the update of 5: exact at
 * constant speed; its update is the prediction for t_k+1), omega_e (rad/s, likewise), theta_raw, flux = |eta| (V s;
 * a converged observer holds psi_f), err = e (rad), valid. Everything is finite for any input.
 *
 * Parameters and their defaults (bldclab.control.observer, docs/sensorless-sine.md, "Defaults"): lambda and omega_p
 * are rates in rad/s; init requires lambda T_s <= 0.5 and omega_p T_s <= 0.5 (the discrete loops are then within
 * 1 % of their continuous-time poles at the defaults, lambda T_s and omega_p T_s below 0.05).
 */
#ifndef BC_FLUXOBS_H
#define BC_FLUXOBS_H

#include <stdint.h>

#include "bldc/bc_obs.h"

typedef struct {
    float R;      /* stator resistance the observer uses, Ohm (>= 0) */
    float L;      /* inductance the observer uses, H (> 0) */
    float psi;    /* PM flux linkage psi_f = k_1 / p, V s (> 0) */
    float ts;     /* sampling period T_s, s (> 0) */
    float gain;   /* lambda = gamma psi_f^2: radial convergence rate, rad/s (> 0, lambda T_s <= 0.5) */
    float pll_bw; /* PLL bandwidth omega_p, rad/s (> 0, omega_p T_s <= 0.5) */
    float i_max;  /* current inputs are clamped to +-i_max, A (> 0) */
    float v_max;  /* voltage inputs are clamped to +-v_max, V (> 0) */
} bc_fluxobs_params;

typedef struct {
    float x[2];         /* stator flux estimate x^, V s (alpha, beta) */
    float i_prev[2];    /* current of the last valid sample, A */
    int32_t started;    /* a valid sample has been taken */
    float theta;        /* PLL angle, rad in [0, 2 pi) */
    float omega;        /* PLL speed, electrical rad/s */
    float half_gamma;   /* gamma / 2 = lambda / (2 psi_f^2), derived in init */
    float psi2;         /* psi_f^2 */
    float kp, ki;       /* PLL gains */
    float omega_max;    /* 4 v_max / psi_f */
    float x_max;        /* 4 psi_f + L i_max */
} bc_fluxobs_state;

/* Validate (BC_ERR_PARAM) and reset: x^ on the circle at theta_e = 0, PLL at 0. */
int bc_fluxobs_init(const bc_fluxobs_params *p, bc_fluxobs_state *s);

/* Seed the estimate: rotor at theta_e (rad), speed omega_e (rad/s), present current i (A): x^ = L i + psi_f
 * (cos(theta_e - pi), sin(theta_e - pi)), the PLL at (theta_e, omega_e). Non-finite arguments count as 0. */
void bc_fluxobs_reset(const bc_fluxobs_params *p, bc_fluxobs_state *s, float theta_e, float omega_e, bc_ab i);

/* Change the flux linkage psi_f the observer pulls eta to (the circle's radius, gamma = lambda / psi^2, the
 * clamps), keeping its state x^ and PLL; with p the params it was initialised with (p->psi replaced by psi). A psi
 * that is not finite and positive, or that would make a derived value non-finite: nothing changes. */
void bc_fluxobs_set_psi(const bc_fluxobs_params *p, bc_fluxobs_state *s, float psi);

/* One sample: the voltage applied over the last sample period and the current now in, the estimate out. */
void bc_fluxobs_step(const bc_fluxobs_params *p, bc_fluxobs_state *s, const bc_obs_in *in, bc_obs_out *out);

#endif /* BC_FLUXOBS_H */

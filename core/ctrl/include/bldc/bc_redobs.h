/*
 * bc_redobs.h - reduced-order flux observer in estimated rotor coordinates with speed estimation (float): the second
 * rotor-angle observer, for comparison with bc_fluxobs.h.
 *
 * Reference: M. Hinkkanen, S. E. Saarakkala, H. A. A. Awan, E. Molsa, T. Tuovinen, "Observers for sensorless
 * synchronous motor drives: framework for design and analysis," IEEE Trans. Industry Applications 54(6), 6090-6100,
 * 2018, DOI 10.1109/TIA.2018.2858753 (the observer of motulator's sensorless drives). Written here for a surface-
 * mount motor (L_d = L_q = L: the auxiliary flux is psi_f, real), from the paper's equations; docs/sensorless-sine.md.
 *
 * Why this one and not a sliding-mode observer: its gains have a design (pole placement of the linearised error
 * dynamics, the electrical and mechanical parts decoupled), it is continuous (a sliding-mode observer chatters and
 * needs a low-pass filter whose phase lag must be compensated, a speed-dependent angle error), and it is the
 * observer of motulator's sensorless example, which benchmarks/sensorless_case.py runs beside bldclab.
 *
 * Model in coordinates aligned with the estimated d axis th^_d = theta^ - pi (bldclab's theta^_e, bc_obs.h), primes
 * marking vectors there (complex: real d, imaginary q): psi_s' = L i' + psi_f (the current model), and
 *
 *     dpsi^_s/dt = u' - R i' - j omega_c psi^_s + k_1 e_o + k_2 e_o*        e_o = L i' + psi_f - psi^_s
 *     dtheta^/dt = omega_c = omega^ + k_theta eps,   domega^/dt = k_omega eps,   eps = -Im(e_o) / psi_f
 *
 * eps is the sine of the angle error theta - theta^ when the flux estimate is right. k_2 = k_1 psi_a / psi_a* (=
 * k_1 here) decouples the flux estimate from the angle error; k_1 = k_2 = sigma, so only the d component of e_o
 * corrects the flux: the linearised error dynamics have D(s) = s^2 + 2 sigma s + omega_e^2. The attenuation
 * sigma = sigma_0 + zeta_inf |omega^| (motulator's default schedule: sigma_0 = R/(2L) puts the standstill poles at 0
 * and -R/L; zeta_inf the damping at high speed). The speed loop on eps is critically damped with k_theta = 2 alpha_o,
 * k_omega = alpha_o^2 (double pole at -alpha_o, the same structure as bc_fluxobs's PLL).
 *
 * Discrete form, one sample k (T_s = ts): the flux is kept in stator coordinates, where the voltage applied over the
 * period is constant, so the frame's rotation -j omega_c psi^ is exact (the hold-equivalent of the rotor-frame form):
 *
 *  1. Sanitise (bc_obs_sanitise): a non-finite input leaves the state (theta^ advances with omega^), valid = 0.
 *  2. psi^_ab += T_s (u - R (i_k-1 + i_k) / 2)                         (first sample: i_k-1 = i_k)
 *  3. with c + j s = exp(j th^_d): i' = e^(-j th^_d) i, psi' = e^(-j th^_d) psi^_ab,
 *     e_o = L i' + psi_f - psi',  eps = -Im(e_o) / psi_f
 *  4. psi^_ab += m Re(e_o) (c, s),   m = 2 sigma T_s clamped to [0, 1]   (k_1 e_o + k_2 e_o* = 2 sigma Re(e_o) on d)
 *     (then |psi^_alpha,beta| <= 4 psi_f + L i_max)
 *  5. output theta = theta^ (the angle at t_k, predicted at sample k-1), omega_e = omega^; then
 *     omega_c = omega^ + k_theta eps,  omega^ += T_s k_omega eps (|omega^| <= 4 v_max / psi_f),  theta^ += T_s omega_c
 *
 * Outputs (bc_obs_out): theta, omega_e, theta_raw = theta, flux = |psi^_ab - L i| (V s), err = eps, valid; finite for
 * any input. init requires 2 sigma_0 T_s <= 0.5 and alpha_o T_s <= 0.5.
 */
#ifndef BC_REDOBS_H
#define BC_REDOBS_H

#include <stdint.h>

#include "bldc/bc_obs.h"

typedef struct {
    float R;        /* stator resistance the observer uses, Ohm (>= 0) */
    float L;        /* inductance the observer uses, H (> 0) */
    float psi;      /* PM flux linkage psi_f = k_1 / p, V s (> 0) */
    float ts;       /* sampling period T_s, s (> 0) */
    float alpha_o;  /* speed-estimation bandwidth, rad/s (> 0, alpha_o T_s <= 0.5) */
    float sigma0;   /* attenuation at standstill sigma_0, rad/s (>= 0, 2 sigma_0 T_s <= 0.5) */
    float zeta_inf; /* damping at high speed, - (0 .. 1) */
    float i_max;    /* current inputs are clamped to +-i_max, A (> 0) */
    float v_max;    /* voltage inputs are clamped to +-v_max, V (> 0) */
} bc_redobs_params;

typedef struct {
    float psi_s[2];  /* stator flux estimate, stator coordinates, V s */
    float i_prev[2]; /* current of the last valid sample, A */
    int32_t started;
    float theta;     /* theta^, rad in [0, 2 pi) */
    float omega;     /* omega^, electrical rad/s */
    float k_theta, k_omega; /* 2 alpha_o, alpha_o^2 */
    float omega_max; /* 4 v_max / psi_f */
    float x_max;     /* 4 psi_f + L i_max */
} bc_redobs_state;

/* Validate (BC_ERR_PARAM) and reset: rotor at theta_e = 0, at rest. */
int bc_redobs_init(const bc_redobs_params *p, bc_redobs_state *s);

/* Seed the estimate: rotor at theta_e (rad), speed omega_e (rad/s), present current i (A). Non-finite: 0. */
void bc_redobs_reset(const bc_redobs_params *p, bc_redobs_state *s, float theta_e, float omega_e, bc_ab i);

/* One sample: the voltage applied over the last sample period and the current now in, the estimate out. */
void bc_redobs_step(const bc_redobs_params *p, bc_redobs_state *s, const bc_obs_in *in, bc_obs_out *out);

#endif /* BC_REDOBS_H */

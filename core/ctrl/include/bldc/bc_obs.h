/*
 * bc_obs.h - what the rotor-angle observers share (float, header-only): their input and output, and the input
 * sanitiser. The observers: bc_fluxobs.h (Lee et al. 2010, nonlinear flux observer with a PLL) and bc_redobs.h
 * (Hinkkanen et al. 2018, reduced-order observer in estimated rotor coordinates).
 *
 * Timing (docs/conventions.md, "PWM"): at sample k the observer gets the current measured at t_k and the voltage
 * that was applied over [t_k-1, t_k] (with the runner's one-sample delay, the output computed at sample k-2). A
 * controller keeps that voltage from its own duties: the half-period mean of the phase voltages of min-max SVM is
 * the reference itself in linear modulation (bc_transform.h), d_x v_dc minus the zero sequence in general.
 *
 * Angles follow bldclab's convention: theta_e = 0 where phase a's back-EMF fundamental crosses zero rising; the
 * PM flux (d axis) lies at theta_e - pi in the alpha-beta plane.
 */
#ifndef BC_OBS_H
#define BC_OBS_H

#include <math.h>
#include <stdint.h>

#include "bldc/bc_math.h"
#include "bldc/bc_transform.h"
#include "bldc/bc_types.h"

typedef struct {
    bc_ab u; /* voltage applied over [t_k-1, t_k], stator frame, V */
    bc_ab i; /* current measured at t_k, stator frame, A */
} bc_obs_in;

typedef struct {
    float theta;     /* rotor electrical angle estimate, rad in [0, 2 pi) */
    float omega_e;   /* electrical speed estimate, rad/s */
    float theta_raw; /* the angle before speed tracking (bc_fluxobs: of eta; bc_redobs: theta), rad in [0, 2 pi) */
    float flux;      /* bc_fluxobs: |eta|; bc_redobs: |psi_s^ - L i| (the PM flux seen), V s */
    float err;       /* the tracking loop's error signal: bc_fluxobs: the PLL's phase error (rad); bc_redobs:
                        epsilon = -Im(e_o) / psi_f (sine of the angle error) */
    int32_t valid;   /* 0: the input was not finite and the state did not update */
} bc_obs_out;

/* (-pi, pi] wrap of an angle within a few turns of the range (any finite value; non-finite gives 0). */
static inline float bc_obs_wrap_pm(float a)
{
    float w = bc_wrap_2pi(a);
    return w > BC_PI_F ? w - BC_TWO_PI_F : w;
}

/* 1 if every input is finite; then u and i are clamped to +-v_max and +-i_max per component. */
static inline int bc_obs_sanitise(const bc_obs_in *in, float v_max, float i_max, bc_ab *u, bc_ab *i)
{
    if (!(isfinite(in->u.alpha) && isfinite(in->u.beta) && isfinite(in->i.alpha) && isfinite(in->i.beta))) return 0;
    u->alpha = bc_clampf(in->u.alpha, -v_max, v_max);
    u->beta = bc_clampf(in->u.beta, -v_max, v_max);
    i->alpha = bc_clampf(in->i.alpha, -i_max, i_max);
    i->beta = bc_clampf(in->i.beta, -i_max, i_max);
    return 1;
}

#endif /* BC_OBS_H */

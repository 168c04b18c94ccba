/*
 * params.h - the controllers configured for the htm-48v drive (paper 1, Table II: 8 pole pairs, 50 mOhm, 75 uH,
 * k_phi 0.32 V s/rad, 14 kHz PWM sampled at 28 kHz), as the firmware harness and the host tools use them.
 * Current-loop gains: bldclab.design.pi_gains(R, L, 1000 Hz, 90 deg) (phase loop: R, L; line loop: 2R, 2L).
 */
#ifndef BC_FW_PARAMS_H
#define BC_FW_PARAMS_H

#include "bldc/bc_bemf.h"
#include "bldc/bc_commission.h"
#include "bldc/bc_commutation.h"
#include "bldc/bc_fluxobs.h"
#include "bldc/bc_hall.h"
#include "bldc/bc_hallcal.h"
#include "bldc/bc_lu.h"
#include "bldc/bc_redobs.h"
#include "bldc/bc_sine.h"
#include "bldc/bc_sixstep.h"

#define HTM_TS 35.714286e-6f

#define HTM_SIXSTEP_PARAMS(REF_TORQUE)                                                                        \
    {.reg = BC_SIXSTEP_PRED, .chop = BC_SIXSTEP_PWMPWM, .ref_torque = (REF_TORQUE), .delay = 1, .advance = 1, \
     .emf_ff = 1, .regen = 1, .p = 8, .ts = HTM_TS, .R = 0.05f, .L = 75e-6f, .k_e = 0.64f, .kp = 0.9425f,      \
     .ki = 628.3f, .band = 5.0f, .i_max = 100.0f, .v_max = 96.0f, .f_tick = 10e6f, .omega_min = 6.0f,         \
     .theta_offset = 0.0f, .hall_mode = BC_HALL_INTERP, .hall_pll_edges = 1.0f, .hall_table = {0, {0}, {0}}}

/* k_a of the ideal 120-degree trapezoid at 12 points over one electrical period (multiples of 30 degrees). */
static const float HTM_EMF_12[12] = {0.0f,  0.32f,  0.32f,  0.32f,  0.32f,  0.32f,
                                     0.0f, -0.32f, -0.32f, -0.32f, -0.32f, -0.32f};

#define HTM_SINE_PARAMS                                                                                         \
    {.p = 8, .R = 0.05f, .L = 75e-6f, .k_phi = 0.32f, .k_1 = 0.3891f, .ts = HTM_TS, .kp = 0.4712f, .ki = 314.2f, \
     .v_max = 96.0f, .i_s_max = 57.7f, .i_max = 100.0f, .speed_limit = 1, .decouple = 1, .advance = 1.5f,        \
     .limit = BC_SINE_LIMIT_HEX, .overmod = 0, .emf_ff = 1, .emf_n = 12,                                          \
     .emf_k = {HTM_EMF_12, HTM_EMF_12, HTM_EMF_12}, .angle = BC_SINE_ANGLE_HALL, .f_tick = 10e6f,                 \
     .omega_min = 10.0f, .theta_offset = 0.0f, .omega_on = 53.6f, .omega_off = 42.9f,                             \
     .six = HTM_SIXSTEP_PARAMS(1), .flying_start = 0, .speed_loop = 0, .kp_w = 0.0f, .ki_w = 0.0f, .tau_max = 0.0f}

/* bc_lu on the lu-4kw drive (paper 2: 2 pole pairs, 0.059 Ohm, 0.29 mH, 300 V, 10 kHz PWM sampled at 20 kHz),
 * with a 12-point ideal trapezoid for its shape tables (k_phi 0.4 V s/rad). */
static const float LU_F_12[12] = {0.0f, 0.4f, 0.4f, 0.4f, 0.4f, 0.4f, 0.0f, -0.4f, -0.4f, -0.4f, -0.4f, -0.4f};

#define LU4KW_LU_PARAMS                                                                                           \
    {.f = {LU_F_12, LU_F_12, LU_F_12}, .n = 12, .p = 2, .method = BC_LU_TORQUE, .delay = 1, .order = 2,            \
     .L = 0.29e-3f, .R = 0.059f, .ts = 50e-6f, .i_max = 48.0f, .i_zero = 0.16f, .v_max = 600.0f, .k_phi = 0.4f,     \
     .kp = 3.63f, .ki = 1939.0f, .f_tick = 20e6f, .omega_min = 7.5f, .theta_offset = 0.0f,               \
     .hall_mode = BC_HALL_INTERP, .hall_pll_edges = 1.0f, .hall_table = {0, {0}, {0}}}

/* bc_hall in tracking mode with a calibrated edge table (edges a few degrees off nominal). */
#define HALL_PLL_PARAMS                                                                                           \
    {.f_tick = 10e6f, .omega_min = 5.0f, .theta_offset = 0.0f, .mode = BC_HALL_PLL, .pll_edges = 3.0f,            \
     .table = {1, {0.60f, 1.52f, 2.67f, 3.67f, 4.70f, 5.76f}, {0.60f, 1.52f, 2.67f, 3.67f, 4.70f, 5.76f}}}

/* bc_hallcal on htm-48v: the open-loop start-up routine (I_N = 50 A through 50 mOhm + switch, 2 Hz electrical) and
 * the constant-speed method. */
#define HTM_HALLCAL_OL_PARAMS                                                                                     \
    {.method = BC_HALLCAL_OPENLOOP, .n_rev = 2, .f_tick = 10e6f, .ts = HTM_TS, .t_max = 1.0f, .speed_tol = 0.02f, \
     .v_align = 3.0f, .v_emf = 0.6f, .omega_ol = 12.566f, .t_align = 0.1f, .lag_max = 1.5f, .i_max = 100.0f,  \
     .v_max = 96.0f}
#define HTM_HALLCAL_SPEED_PARAMS                                                                                  \
    {.method = BC_HALLCAL_SPEED, .n_rev = 2, .f_tick = 10e6f, .ts = HTM_TS, .t_max = 1.0f, .speed_tol = 0.02f,    \
     .v_align = 0.0f, .v_emf = 0.0f, .omega_ol = 0.0f, .t_align = 0.0f, .lag_max = 0.0f, .i_max = 0.0f,           \
     .v_max = 0.0f}

/* The rotor-angle observers on htm-48v (psi_f = k_1 / p = 0.389 / 8 V s), with bldclab.control.observer's defaults
 * for the drive: lambda = 2 omega_on (omega_on = 0.1 Omega_0 p = 60 rad/s), omega_p = alpha_o = sqrt(p T_s,N / (J
 * 1 deg)) = 556 rad/s; sigma_0 = R / (2 L), zeta_inf = 0.2. */
#define HTM_FLUXOBS_PARAMS                                                                                        \
    {.R = 0.05f, .L = 75e-6f, .psi = 0.0486f, .ts = HTM_TS, .gain = 120.0f, .pll_bw = 556.0f, .i_max = 100.0f,   \
     .v_max = 96.0f}
#define HTM_REDOBS_PARAMS                                                                                         \
    {.R = 0.05f, .L = 75e-6f, .psi = 0.0486f, .ts = HTM_TS, .alpha_o = 556.0f, .sigma0 = 333.3f, .zeta_inf = 0.2f, \
     .i_max = 100.0f, .v_max = 96.0f}
/* bc_bemf (sensorless six-step) on htm-48v: the record bldclab.SixStepSensorless() builds for the drive (comparator,
 * synchronous chopping, demagnetisation blanking 5 deg / 1 us; alignment at 0.5 I_N through R for three periods of
 * the rotor's oscillation with J = 0.05 kg m^2, 0.38 s; V/f ramp 0.01 to 0.1 Omega_0 at half the alignment torque's
 * acceleration; stall 0.03 Omega_0; speeds electrical), with the integration threshold of
 * SixStepSensorless(method="integration") and the firmware's 10 MHz capture timer. */
#define HTM_BEMF_PARAMS                                                                                           \
    {.method = BC_BEMF_COMPARATOR, .chop = BC_CHOP_SYNC, .delay = 1, .blanking = BC_BEMF_BLANK_DEMAG, .ts = HTM_TS,  \
     .f_tick = 10e6f, .blank_angle = 0.08726646f, .blank_time = 1e-6f, .min_pulse = 1e-6f, .n_samples = 2,         \
     .tau_filter = 0.0f, .t_comp = 0.0f, .adv_angle = 0.0f, .adv_time = 0.0f, .adv_demag = 0.0f,                  \
     .adv_max = 0.5235982f, .t60_gain = 0.5f, .int_limit = 0.006981317f, .zc_timeout = 1.5f, .jump_max = 2.0f,    \
     .miss_max = 0, .omega_stall = 18.0f, .align_time = 0.3812374f, .align_duty = 0.05208333f, .ramp_w0 = 6.0f,   \
     .ramp_w1 = 60.0f, .ramp_accel = 1280.0f, .ramp_duty = 0.05208333f, .ramp_vf = 0.001666667f,                 \
     .ramp_tau = 1.5e-3f, .ramp_hold = 12,                                                                         \
     .n_handover = 6, .duty_min = 0.0f, .duty_rate = 0.0f, .ref_stop = 0.0f, .restart_wait = 0.05f,              \
     .restart_max = 1.0f, .use_current = 1, .i_max = 100.0f, .i_limit = 0.0f, .k_limit = 2.083333f, .v_max = 96.0f, \
     .fast_demag = 1, .fd_after = 0.3f, .dlim_d0 = 0.05208333f, .dlim_vf = 0.001666667f, .dlim_tau = 1.5e-3f,     \
     .demag_max = 0.6f, .cmp_gate = 0, .cmp_blind = 0, .i_start = 50.0f}

/* The sensorless Sine on htm-48v: HTM_SINE_PARAMS with the angle from the flux observer (HTM_FLUXOBS_PARAMS with
 * Sine(angle="observer")'s defaults for the drive: lambda = 2 omega_on = 107 rad/s) and its I/f start-up (0.5 I_s,N,
 * align 0.363 s, ramp 278 rad/s^2, lock 46.6 ms within 0.2, hold 1.17 s, restart after 0.1 s). */
static inline void htm_sine_observer(bc_sine_params *p)
{
    const bc_fluxobs_params f = HTM_FLUXOBS_PARAMS;
    p->angle = BC_SINE_ANGLE_OBSERVER;
    p->observer = BC_SINE_OBS_FLUX;
    p->fobs = f;
    p->fobs.gain = 107.2f;
    p->if_current = 28.87f;
    p->if_align = 0.363f;
    p->if_align_current = 51.96f;
    p->if_accel = 278.4f;
    p->if_accel_min = 13.92f;
    p->if_hold = 1.172f;
    p->lock_time = 0.0466f;
    p->lock_tol = 0.2f;
    p->restart_wait = 0.1f;
    p->if_damp = 11.43f;
    p->if_r_est = 0;
    p->if_psi_est = 1;  /* the zero-current flux reading, Sine()'s default */
    p->catch_pulse = 1; /* the zero-vector pulses at the alignment's start, Sine()'s default */
}

/* Self-commissioning on htm-48v: the record bldclab.control.Commission() builds for the drive, its current sensors'
 * full scale 2 I_N (Sensors.current_full_scale = 100 A; the catalog drive has none): the CLIPPED check runs. */
#define HTM_COMMISSION_PARAMS                                                                                     \
    {.ts = HTM_TS, .kp = 0.09425f, .ki = 62.83f, .i_test = 28.87f, .t_ramp = 0.3631f, .t_settle = 0.2595f,        \
     .t_window = 0.2420f, .v_pulse = 3.031f, .n_pulse = 8, .pulse_len = 10, .n_pulse_max = 500, .tol_noise = 0.01f,  \
     .t_offset = 0.02f, .i_if = 28.87f, .if_accel = 167.0f,                                                       \
     .w_spin = 160.8f, .t_spin = 0.6051f, .psi_min = 0.01216f, .tol_move = 0.05f, .tol_follow = 0.3f,             \
     .k_damp = 11.43f, .i_max = 100.0f, .v_max = 96.0f, .i_fs = 100.0f}

#endif /* BC_FW_PARAMS_H */

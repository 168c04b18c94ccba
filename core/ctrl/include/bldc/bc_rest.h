/* bc_rest.h - the winding resistance during operation, by a square wave of d-axis current (C99, no malloc, no
 * globals, no I/O).
 *
 * A drive without a winding sensor estimates the winding's temperature from its resistance (bc_derate.h,
 * bc_derate_r_to_temp). The commissioning test measures R at standstill; this block measures it while the motor
 * runs under field-oriented control, from the d axis of the rotor frame. For a non-salient motor in the steady
 * state of each half period:
 *
 *     v_d = R i_d - omega_e L i_q + e_d + dv_d
 *
 * e_d the back-EMF on d (omega_m k_1 sin delta for an angle error delta), dv_d the inverter's voltage error. The
 * controller adds i_d,ref = +i_inj for n_half samples, then -i_inj for n_half samples, and so on (no torque: the
 * torque is 3/2 k_1 i_q). Over each half period, after n_skip samples of settling, the means of v_d (the voltage
 * the controller applies, in the frame of the rotor) and of the measured i_d give
 *
 *     R_hat = (<v_d>+ - <v_d>-) / (<i_d>+ - <i_d>-)
 *
 * Every term that does not change with the injection's sign cancels: omega_e L i_q, the back-EMF's d part (so
 * neither the magnets' flux, which also changes with temperature, nor a constant angle error enters), a constant
 * voltage error. What remains is the series resistance the voltage sees: the winding's R and, if the inverter's
 * drops are not compensated, the switches' R_on. Speed and i_q must be steady over a period (a period spanning a
 * torque step gives a wrong R_hat, which the plausible range [r_lo, r_hi] and the filter bound).
 *
 * A period counts when every sample of it was valid (ok = 1, finite inputs), the current followed
 * (<i_d>+ - <i_d>- >= i_inj) and R_hat is finite and in [r_lo, r_hi]; then r = R_hat (first) or
 * r += a (R_hat - r). bc_rest_temp gives the temperature by bc_derate_r_to_temp (copper, k = 234.5 degC).
 *
 * Call per control sample: i_d,ref = bc_rest_ref(p, s); ... current loops ...; bc_rest_step(p, s, v_d, i_d, ok).
 */
#ifndef BC_REST_H
#define BC_REST_H

#include <stdint.h>

#include "bldc/bc_types.h"

typedef struct {
    float i_inj;     /* amplitude of the injected d current, A (> 0) */
    int32_t n_half;  /* samples per half period (n_half >= n_skip + 2) */
    int32_t n_skip;  /* samples skipped after each sign change (>= 0) */
    float r_lo;      /* plausible estimates: [r_lo, r_hi], Ohm (0 < r_lo < r_hi) */
    float r_hi;
    float a;         /* filter gain per valid period, (0, 1] */
    float r_ref;     /* resistance at T_ref, Ohm (> 0): for bc_rest_temp */
    float T_ref;     /* its temperature, degC (> -234.5) */
} bc_rest_params;

typedef struct {
    int32_t k;        /* sample within the period, 0 .. 2 n_half - 1 */
    int32_t bad;      /* an invalid sample in this period */
    float v0;         /* v_d of the period's first counted sample, V: the sums are of v_d - v0, so that a large
                         common voltage (the offsets that cancel) does not cost the float sums their precision */
    float sv[2];      /* sums of v_d - v0 over the counted samples of each half ([0] +i_inj, [1] -i_inj), V */
    float si[2];      /* sums of i_d, A */
    int32_t n[2];     /* counted samples */
    float r;          /* the estimate, Ohm (0 until the first valid period) */
    float r_last;     /* the last period's R_hat, Ohm (0 until one) */
    uint32_t count;   /* valid periods */
    uint32_t rejected; /* periods discarded */
} bc_rest_state;

/* Check the parameters (BC_ERR_PARAM) and clear the state. */
int bc_rest_init(const bc_rest_params *p, bc_rest_state *s);
/* Restart the period (the estimate is kept): after a mode change, a fault. */
void bc_rest_restart(bc_rest_state *s);
/* The d current reference of this sample: +i_inj in the first half period, -i_inj in the second. */
float bc_rest_ref(const bc_rest_params *p, const bc_rest_state *s);
/* Account this sample: v_d the voltage applied on d (V), i_d the measured d current (A), ok 0 if the sample is not
 * in steady field-oriented operation (start mode, saturated voltage). */
void bc_rest_step(const bc_rest_params *p, bc_rest_state *s, float v_d, float i_d, int32_t ok);
/* The winding temperature (degC) of the estimate: BC_OK; non-zero (T untouched) before the first valid period. */
int bc_rest_temp(const bc_rest_params *p, const bc_rest_state *s, float *T);

#endif /* BC_REST_H */

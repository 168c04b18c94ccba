/*
 * bc_derate.h - temperature derating of the current limit, as drive firmware does it, and the winding temperature
 * from a measured resistance where no sensor is fitted (issue 27; docs/thermal.md, "Derating in firmware").
 *
 * Two channels, [0] the winding and [1] the switches (heat sink or board NTC), each with a linear band:
 *
 *     f(T) = 1                                                  T <= T_start
 *            1 - (1 - f_min) (T - T_start) / (T_end - T_start)   T_start < T < T_end
 *            f_min                                              T >= T_end
 *
 * The factor returned is the smaller of the enabled channels' (1 with none): the controller multiplies its current
 * limit (or its torque reference) by it. f_min is the factor at and above T_end: 0 stops the drive, a small value
 * leaves a limp-home current.
 *
 * Each reading is low-pass filtered first (first order, time constant tau: T_f += a (T - T_f), a = 1 - exp(-ts/tau)
 * computed at init, the exact discretisation of the filter for a reading held over the call period ts; tau = 0: no
 * filter), so that ADC noise does not modulate the limit. The first valid reading sets the filter.
 *
 * A reading that is not finite or outside [T_lo, T_hi] (an open or shorted NTC, a broken wire) is a sensor fault:
 * the channel gives f_fault and holds its filter; the fault clears at the next plausible reading. Whatever the
 * inputs, the factor is finite and in [0, 1].
 *
 * Without a winding sensor, the winding temperature follows from its resistance (the commissioning R test, or one
 * measured during operation), by the resistance method of IEC 60034-1:
 *
 *     T = (R / R_ref) (k + T_ref) - k,        k = 234.5 degC for copper (235 in IEC 60034-1), 225 for aluminium
 *
 *     int   bc_derate_init(const bc_derate_params *p, bc_derate_state *s);
 *               BC_ERR_PARAM unless f_min in [0, 1), f_fault in [0, 1], T_end > T_start (enabled channels), T_hi > T_lo,
 *               tau >= 0, ts > 0, all finite
 *     float bc_derate_step(const bc_derate_params *p, bc_derate_state *s, const float T_meas[2]);
 *               the factor in [0, 1]; T_meas in degC (a disabled channel's entry is ignored)
 *     int   bc_derate_r_to_temp(float R, float R_ref, float T_ref, float k, float *T);
 *               BC_OK and *T (degC), or BC_ERR_INPUT (*T untouched) unless R, R_ref > 0, k + T_ref > 0, all finite
 */
#ifndef BC_DERATE_H
#define BC_DERATE_H

#include <stdint.h>

#include "bldc/bc_types.h"

#define BC_DERATE_CH 2 /* [0] winding, [1] switches */

typedef struct {
    int32_t enabled[BC_DERATE_CH]; /* channel fitted (1) or not (0) */
    float T_start[BC_DERATE_CH];   /* start of the band, degC */
    float T_end[BC_DERATE_CH];     /* end of the band (> T_start), degC */
    float f_min;                   /* factor at and above T_end, [0, 1) */
    float f_fault;                 /* factor of a channel whose reading is implausible, [0, 1] */
    float T_lo, T_hi;              /* plausible readings, degC (T_hi > T_lo) */
    float tau;                     /* filter time constant, s (0: none) */
    float ts;                      /* call period, s (> 0) */
} bc_derate_params;

typedef struct {
    float T_f[BC_DERATE_CH];       /* filtered temperatures, degC */
    float a;                       /* filter gain 1 - exp(-ts / tau) */
    int32_t primed[BC_DERATE_CH];  /* a valid reading has set the filter */
    int32_t fault[BC_DERATE_CH];   /* the last reading was implausible */
    float factor[BC_DERATE_CH];    /* each channel's factor at the last step */
} bc_derate_state;

int bc_derate_init(const bc_derate_params *p, bc_derate_state *s);
float bc_derate_step(const bc_derate_params *p, bc_derate_state *s, const float T_meas[BC_DERATE_CH]);
int bc_derate_r_to_temp(float R, float R_ref, float T_ref, float k, float *T);

#endif /* BC_DERATE_H */

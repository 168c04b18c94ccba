/*
 * bc_guard.h - the input guard every current-measuring controller runs at every sample before its own law
 * (bc_sixstep, bc_sine, bc_lu). One rule for all of them:
 *
 *  1. Currents. A phase whose bit is set in i_mask is measured and must be finite; at least two must be measured.
 *     With exactly two, the third is reconstructed from i_a + i_b + i_c = 0:
 *
 *         i_z = -((0 + i_x) + i_y)          (x < y the measured phases, summed in phase order)
 *
 *     With three, all three are used as measured (no projection). An unmeasured phase's i_abc entry is ignored,
 *     whatever it holds. Violations: BC_FLAG_BAD_INPUT.
 *  2. DC bus. v_dc must be finite and 0 < v_dc <= v_max (v_max: the largest plausible bus measurement, a broken
 *     divider or an ADC rail reads above it; a controller dividing by v_dc must never see 0). Else BC_FLAG_BAD_INPUT.
 *  3. Hardware trip. fault_pin = 1 (the inverter's own protection has switched its gates off and latched):
 *     BC_FLAG_OVERCURRENT. The hardware holds that latch; the guard does not add one.
 *  4. Software trip and re-arm. max_x |i_x| > i_max over the measured and reconstructed phases (or not finite)
 *     trips: BC_FLAG_OVERCURRENT, latched; so does a measured phase at the readings' full scale, |i_x| >= in->i_fs
 *     (i_fs > 0): the reading is clipped and the current unknown beyond it (a trip above the full scale could never
 *     see its level). A latched guard re-arms at the first sample whose measurements are valid (1 and 2), whose
 *     every |i_x| < i_max / 2 and whose every reading is inside the full scale. Samples with invalid measurements
 *     leave the latch as it is. bc_guard_init clears it.
 *
 * The checks run in this order and the first one that fails gives the verdict (0: all passed). The controller
 * adds its own checks (Hall code, reference, angle) to the verdict and, if anything is set, turns all legs off
 * with BC_FLAG_SAFE and resets its regulators, so a re-armed controller starts from rest (no integrator windup).
 *
 * Why re-arm at i_max / 2 rather than latch until init: the hardware protection (fault_pin) is the latched last
 * line; the software trip is a current limit whose cause (a transient at a reversal, a bus step, a start into a
 * spinning rotor) passes. With all legs off the phase currents freewheel into the bus and decay to zero within a
 * few L/R, so a latch until init would stop the drive for good after any transient, and the half-limit hysteresis
 * keeps it from chattering at the trip level: it re-arms only once the freewheeling has mostly ended, and the
 * controllers limit their own references to at most i_max.
 *
 *     int      bc_guard_init(const bc_guard_params *p, bc_guard_state *s);   BC_ERR_PARAM unless i_max, v_max > 0
 *     uint32_t bc_guard_step(const bc_guard_params *p, bc_guard_state *s, const bc_ctrl_in *in, float i[3]);
 *                                                                            verdict; i: the phase currents, A
 *                                                                            (0 where the verdict is BAD_INPUT)
 */
#ifndef BC_GUARD_H
#define BC_GUARD_H

#include <stdint.h>

#include "bldc/bc_types.h"

typedef struct {
    float i_max; /* over-current trip, A (> 0) */
    float v_max; /* largest plausible DC-bus measurement, V (> 0) */
} bc_guard_params;

typedef struct {
    int32_t latched; /* software over-current trip latched */
} bc_guard_state;

int bc_guard_init(const bc_guard_params *p, bc_guard_state *s);
uint32_t bc_guard_step(const bc_guard_params *p, bc_guard_state *s, const bc_ctrl_in *in, float i[3]);

#endif /* BC_GUARD_H */

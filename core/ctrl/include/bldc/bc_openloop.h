/*
 * bc_openloop.h - two open-loop drivers that exercise the plant before (and beside) the real controllers.
 *
 * bc_table: replays precomputed leg commands, one triple per sample: out.leg = cmd[3k .. 3k+2]; all legs off
 * after the table ends.
 *
 * bc_sixv: six-step voltage mode. The Hall sector s gives the phase pair (pos, neg) (bc_commutation.h); the
 * reference u = in.ref in [-1, 1] is the duty (|u|), its sign the direction (u < 0 swaps pos and neg, i.e. drives
 * the motor backward / brakes it forward). The third phase is left off so its diode freewheels. Chopping:
 *
 *     BC_SIXV_HIGH      pos: HIGH |u|         neg: LOW 1          (high-side chopping)
 *     BC_SIXV_LOW       pos: HIGH 1           neg: LOW |u|        (low-side chopping)
 *     BC_SIXV_BIPOLAR   pos: HIGH |u|         neg: LOW |u|        (both chop together)
 *     BC_SIXV_SYNC      pos: PWM |u|          neg: LOW 1          (synchronous rectification on pos)
 *
 * An invalid Hall code (000, 111) or a non-finite reference gives all legs off and BC_FLAG_SAFE.
 * diag[0] = sector (-1 invalid), diag[1] = applied duty.
 */
#ifndef BC_OPENLOOP_H
#define BC_OPENLOOP_H

#include <stdint.h>

#include "bldc/bc_types.h"

typedef struct {
    const bc_leg_cmd *cmd; /* 3 n commands: legs a, b, c of sample 0, then sample 1, ... */
    int64_t n;             /* number of samples in the table */
} bc_table_params;

typedef struct {
    int64_t k; /* next sample */
} bc_table_state;

int bc_table_init(const bc_table_params *p, bc_table_state *s);
void bc_table_step(const bc_table_params *p, bc_table_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);

#define BC_SIXV_HIGH 0
#define BC_SIXV_LOW 1
#define BC_SIXV_BIPOLAR 2
#define BC_SIXV_SYNC 3

typedef struct {
    int32_t chop; /* BC_SIXV_* */
} bc_sixv_params;

typedef struct {
    int32_t sector; /* last valid sector, -1 before the first */
} bc_sixv_state;

int bc_sixv_init(const bc_sixv_params *p, bc_sixv_state *s);
void bc_sixv_step(const bc_sixv_params *p, bc_sixv_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);

#endif /* BC_OPENLOOP_H */

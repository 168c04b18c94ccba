/*
 * targets.h - the controllers as host tools see them (instruction counts, fuzzing): each with working
 * parameters, an init, a step, and the inputs it depends on (so a checker knows when the safe state is required).
 * Adding a controller: one entry in targets.c.
 */
#ifndef BC_FW_TARGETS_H
#define BC_FW_TARGETS_H

#include "bldc/bc_types.h"

#define BC_USES_HALL 0x1u     /* an invalid Hall code must give the safe state */
#define BC_USES_CURRENT 0x2u  /* a non-finite current must give the safe state */
#define BC_USES_VDC 0x4u      /* a non-finite or non-positive DC bus must give the safe state */
#define BC_IS_BLOCK 0x8u      /* a building block (not a controller): its own checks in diag */

typedef struct {
    const char *name;
    unsigned uses;
    int (*init)(void);
    void (*step)(const bc_ctrl_in *in, bc_ctrl_out *out);
    float v_dc;        /* nominal DC bus of the drive it is configured for, V */
    float i_amp;       /* nominal phase current amplitude, A */
    float ref;         /* a nominal reference (the controller's own unit) */
    float tick_per_ts; /* capture-timer ticks per sample */
} bc_fw_target;

extern const bc_fw_target bc_fw_targets[];
extern const int bc_fw_n_targets;

#endif

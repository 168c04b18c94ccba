/* plain.h - a firmware's controller without a description (tests/test_user_control.py): bldclab controller build
 * --params-header plain.h writes it. The law is sixstep_voltage.c's; the params carry every kind of member the
 * generator reads. */
#ifndef PLAIN_H
#define PLAIN_H

#include <stdint.h>

#include "bldc/bc_types.h"

typedef struct {
    float lo, hi; /* duty limits */
    uint8_t unused;
} plain_limits;

typedef struct {
    float gain;          /* duty per unit reference */
    plain_limits limits; /* a nested struct of this header */
    int16_t order[3];    /* an array: leg order (0, 1, 2) */
    double spare;        // a double, unused
    uint32_t flags;
} plain_params;

typedef struct {
    int32_t k;
} plain_state;

int plain_init(const plain_params *p, plain_state *s);
void plain_step(const plain_params *p, plain_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);

#endif

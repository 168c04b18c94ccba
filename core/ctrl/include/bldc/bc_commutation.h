/*
 * bc_commutation.h - Hall code <-> sector <-> conducting phases for 120-degree conduction
 * (table in docs/conventions.md):
 *
 *     code    1     3     2     6     4     5        (bit 0 = H_a, bit 1 = H_b, bit 2 = H_c)
 *     sector  0     1     2     3     4     5        entered at theta_e = pi/6 + sector pi/3
 *     +, -    a,b   a,c   b,c   b,a   c,a   c,b      phase driven positive, phase driven negative
 *
 * Forward rotation runs through the sectors in increasing order. Codes 0 and 7 are invalid.
 *
 * bc_pair_legs: the leg commands of a chopping pattern for a pair voltage (shared by bc_sixstep and bc_bemf).
 */
#ifndef BC_COMMUTATION_H
#define BC_COMMUTATION_H

#include <stdint.h>

#include "bldc/bc_types.h"

/* Chopping patterns of a six-step pair (bc_pair_legs; the same values as bc_sixstep's BC_SIXSTEP_BIPOLAR ..). */
#define BC_CHOP_BIPOLAR 0 /* pos HIGH d, neg LOW d, d = (1 + m)/2:              u = (2 d - 1) V_dc, m in [-1, 1] */
#define BC_CHOP_HIGH 1    /* pos HIGH m, neg LOW 1:                              u = m V_dc,         m in [0, 1] */
#define BC_CHOP_PWMPWM 2  /* the chopping leg HIGH/LOW m, the other HIGH/LOW 1:  u = m V_dc,         m in [0, 1] */
#define BC_CHOP_SYNC 3    /* pos PWM m (complementary), neg LOW 1:               u = m V_dc,         m in [0, 1] */

/* Sector 0..5 of a Hall code, or -1 for an invalid code (0, 7, or any bit above bit 2). */
int bc_hall_sector(uint32_t code);

/* Hall code of a sector (0..5); 0 for an invalid sector. */
uint32_t bc_sector_code(int sector);

/* Phase driven positive and phase driven negative in a sector (0..5). Returns 0, or -1 for an invalid sector. */
int bc_sector_phases(int sector, int *pos, int *neg);

/* Electrical angle (rad) where forward rotation enters the sector: pi/6 + sector pi/3, in [0, 2 pi). */
float bc_sector_angle(int sector);

/* Leg commands of a chopping pattern (BC_CHOP_*) realising the normalised pair voltage m = u / V_dc between the
 * phase driven positive (pos) and the one driven negative (neg); the third leg OFF (its diodes free). m < 0 (any
 * pattern): both legs chop as BC_CHOP_BIPOLAR, d = (1 + m)/2. chop_leg (pos or neg) is the leg that chops with
 * BC_CHOP_PWMPWM. m is clamped to [-1, 1] (BIPOLAR) or [0, 1]; the duties are in [0, 1] for any finite m. */
void bc_pair_legs(int chop, int pos, int neg, int chop_leg, float m, bc_leg_cmd c[3]);

#endif /* BC_COMMUTATION_H */

/*
 * bc_commutation.h - Hall code <-> sector <-> conducting phases for 120-degree conduction
 * (table in docs/conventions.md):
 *
 *     code    1     3     2     6     4     5        (bit 0 = H_a, bit 1 = H_b, bit 2 = H_c)
 *     sector  0     1     2     3     4     5        entered at theta_e = pi/6 + sector pi/3
 *     +, -    a,b   a,c   b,c   b,a   c,a   c,b      phase driven positive, phase driven negative
 *
 * Forward rotation runs through the sectors in increasing order. Codes 0 and 7 are invalid.
 */
#ifndef BC_COMMUTATION_H
#define BC_COMMUTATION_H

#include <stdint.h>

/* Sector 0..5 of a Hall code, or -1 for an invalid code (0, 7, or any bit above bit 2). */
int bc_hall_sector(uint32_t code);

/* Hall code of a sector (0..5); 0 for an invalid sector. */
uint32_t bc_sector_code(int sector);

/* Phase driven positive and phase driven negative in a sector (0..5). Returns 0, or -1 for an invalid sector. */
int bc_sector_phases(int sector, int *pos, int *neg);

/* Electrical angle (rad) where forward rotation enters the sector: pi/6 + sector pi/3, in [0, 2 pi). */
float bc_sector_angle(int sector);

#endif /* BC_COMMUTATION_H */

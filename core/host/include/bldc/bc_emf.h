/*
 * bc_emf.h - back-EMF shape of one phase, k(theta) in V s/rad, for the plant (double).
 *
 *     e_x = omega_m * k_x(theta_x),   theta_x = theta_e - x 2 pi/3           (docs/conventions.md)
 *
 * Two kinds cover every shape bldclab knows:
 *   BC_EMF_TABLE    periodic piecewise-linear through (x[j], y[j]), x strictly increasing in [0, 2 pi), n >= 2.
 *                   An ideal trapezoid is the 4-point table of bc_emf_trapezoid(); a measured shape is its table.
 *                   k(theta) = y[j] + (y[j+1] - y[j]) (theta - x[j]) / (x[j+1] - x[j]),  x[n] = x[0] + 2 pi.
 *   BC_EMF_FOURIER  k(theta) = sum_{m=0}^{n-1} x[m] cos(m theta) + y[m] sin(m theta)    (x = a_m, y = b_m).
 *
 * The plant integrates between corners: a "piece" is the linear segment the angle is in, with its bounds in the
 * caller's (unwrapped) angle frame; the plant steps from piece to piece as the rotor turns, so evaluating k is
 * one multiply-add and no corner is ever stepped over. Fourier shapes are one unbounded piece.
 */
#ifndef BC_EMF_H
#define BC_EMF_H

#include <stdint.h>

#define BC_EMF_TABLE 0
#define BC_EMF_FOURIER 1

typedef struct {
    int32_t kind;    /* BC_EMF_TABLE or BC_EMF_FOURIER */
    int32_t n;       /* table points, or Fourier coefficients (orders 0 .. n-1) */
    const double *x; /* table: angles (rad); Fourier: cosine coefficients a_m (V s/rad) */
    const double *y; /* table: values (V s/rad); Fourier: sine coefficients b_m (V s/rad) */
} bc_emf_shape;

/* The linear segment of a table shape the angle is in: k(theta) = k0 + slope (theta - lo) on [lo, hi]. */
typedef struct {
    int32_t j;    /* segment index: from point j to point j+1 (mod n); -1 for a Fourier shape */
    double lo;    /* lower bound, rad, in the caller's angle frame (-HUGE_VAL for Fourier) */
    double hi;    /* upper bound, rad (HUGE_VAL for Fourier) */
    double k0;    /* k at lo, V s/rad */
    double slope; /* dk/dtheta, V s/rad^2 */
} bc_emf_piece;

/* Validate a shape: BC_OK, or BC_ERR_PARAM (NULL arrays, n too small, non-finite, angles not increasing in
 * [0, 2 pi)). */
int bc_emf_check(const bc_emf_shape *s);

/* k(theta) for any theta (binary search for tables: for setup and tests, not for the inner loop). */
double bc_emf_eval(const bc_emf_shape *s, double theta);

/* The piece containing theta (any real). At a corner, dir >= 0 picks the piece starting there, dir < 0 the
 * piece ending there. Bounds are returned in theta's frame (lo <= theta <= hi). */
void bc_emf_piece_at(const bc_emf_shape *s, double theta, int dir, bc_emf_piece *pc);

/* Move to the next piece in direction dir (+1 forward: the new lo is the old hi; -1 backward). */
void bc_emf_piece_step(const bc_emf_shape *s, int dir, bc_emf_piece *pc);

/* Fill the 4-point table of an ideal trapezoid: flat top k_phi for flat_top rad, linear ramps through zero,
 * half-wave antisymmetric. Returns the number of points written (4, or 2 when flat_top = 0), or 0 if the
 * arguments are out of range (k_phi <= 0, flat_top outside [0, pi)). */
int bc_emf_trapezoid(double k_phi, double flat_top, double x[4], double y[4]);

#endif /* BC_EMF_H */

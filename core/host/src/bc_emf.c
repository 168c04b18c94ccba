/* bc_emf.c - back-EMF shapes: validation, evaluation, piece walking. Equations in bc_emf.h. */
#include "bldc/bc_emf.h"

#include <math.h>

#include "bldc/bc_types.h"

int bc_emf_check(const bc_emf_shape *s)
{
    if (s == 0 || s->x == 0 || s->y == 0) {
        return BC_ERR_PARAM;
    }
    if (s->kind == BC_EMF_TABLE) {
        if (s->n < 2) {
            return BC_ERR_PARAM;
        }
        for (int32_t j = 0; j < s->n; ++j) {
            if (!isfinite(s->x[j]) || !isfinite(s->y[j])) {
                return BC_ERR_PARAM;
            }
            if (j > 0 && !(s->x[j] > s->x[j - 1])) {
                return BC_ERR_PARAM;
            }
        }
        if (s->x[0] < 0.0 || s->x[s->n - 1] >= BC_TWO_PI) {
            return BC_ERR_PARAM;
        }
        return BC_OK;
    }
    if (s->kind == BC_EMF_FOURIER) {
        if (s->n < 1) {
            return BC_ERR_PARAM;
        }
        for (int32_t m = 0; m < s->n; ++m) {
            if (!isfinite(s->x[m]) || !isfinite(s->y[m])) {
                return BC_ERR_PARAM;
            }
        }
        return BC_OK;
    }
    return BC_ERR_PARAM;
}

/* Angle of table point j for any integer j (periodic extension). */
static double table_x(const bc_emf_shape *s, int64_t j, double *value)
{
    int64_t n = s->n;
    int64_t q = j >= 0 ? j / n : -((-j + n - 1) / n);
    int64_t r = j - q * n;
    *value = s->y[r];
    return s->x[r] + (double)q * BC_TWO_PI;
}

static void table_piece(const bc_emf_shape *s, int64_t j, double shift, bc_emf_piece *pc)
{
    double y0, y1;
    double x0 = table_x(s, j, &y0);
    double x1 = table_x(s, j + 1, &y1);
    int64_t r = j % s->n;
    pc->j = (int32_t)(r < 0 ? r + s->n : r);
    pc->lo = x0 + shift;
    pc->hi = x1 + shift;
    pc->k0 = y0;
    pc->slope = (y1 - y0) / (x1 - x0);
}

void bc_emf_piece_at(const bc_emf_shape *s, double theta, int dir, bc_emf_piece *pc)
{
    if (s->kind != BC_EMF_TABLE) {
        pc->j = -1;
        pc->lo = -HUGE_VAL;
        pc->hi = HUGE_VAL;
        pc->k0 = 0.0;
        pc->slope = 0.0;
        return;
    }
    /* reduce theta to [0, 2 pi) and remember the shift back to the caller's frame */
    double turns = floor(theta / BC_TWO_PI);
    double w = theta - turns * BC_TWO_PI;
    if (w >= BC_TWO_PI) {
        w -= BC_TWO_PI;
        turns += 1.0;
    }
    double shift = turns * BC_TWO_PI;
    /* segment j with x[j] <= w < x[j+1]; j = -1 means before x[0] (wrapped segment n-1, shifted) */
    int32_t lo = 0, hi = s->n - 1;
    int64_t j;
    if (w < s->x[0]) {
        j = -1;
    } else {
        while (lo < hi) {
            int32_t mid = (lo + hi + 1) / 2;
            if (s->x[mid] <= w) {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        j = lo;
    }
    double y;
    if (dir < 0 && j >= 0 && table_x(s, j, &y) == w) {
        j -= 1; /* exactly at a corner moving backward: take the piece ending here */
    }
    table_piece(s, j, shift, pc);
}

void bc_emf_piece_step(const bc_emf_shape *s, int dir, bc_emf_piece *pc)
{
    if (s->kind != BC_EMF_TABLE) {
        return;
    }
    /* the frame shift of this piece (lo = x[j] + frame); neighbours share their common bound exactly */
    double y;
    double frame = pc->lo - table_x(s, pc->j, &y);
    if (dir >= 0) {
        double lo = pc->hi;
        table_piece(s, (int64_t)pc->j + 1, frame, pc);
        pc->lo = lo;
    } else {
        double hi = pc->lo;
        table_piece(s, (int64_t)pc->j - 1, frame, pc);
        pc->hi = hi;
    }
}

double bc_emf_eval(const bc_emf_shape *s, double theta)
{
    if (s->kind == BC_EMF_TABLE) {
        bc_emf_piece pc;
        bc_emf_piece_at(s, theta, 1, &pc);
        return pc.k0 + pc.slope * (theta - pc.lo);
    }
    double c1 = cos(theta), s1 = sin(theta);
    double cm = 1.0, sm = 0.0, k = 0.0;
    for (int32_t m = 0; m < s->n; ++m) {
        k += s->x[m] * cm + s->y[m] * sm;
        double c_next = cm * c1 - sm * s1;
        sm = sm * c1 + cm * s1;
        cm = c_next;
    }
    return k;
}

int bc_emf_trapezoid(double k_phi, double flat_top, double x[4], double y[4])
{
    if (!(k_phi > 0.0) || !(flat_top >= 0.0) || !(flat_top < BC_PI)) {
        return 0;
    }
    double r = 0.5 * (BC_PI - flat_top); /* half width of the ramp through zero */
    if (flat_top == 0.0) {
        x[0] = 0.5 * BC_PI;
        y[0] = k_phi;
        x[1] = 1.5 * BC_PI;
        y[1] = -k_phi;
        return 2;
    }
    x[0] = r;
    y[0] = k_phi;
    x[1] = BC_PI - r;
    y[1] = k_phi;
    x[2] = BC_PI + r;
    y[2] = -k_phi;
    x[3] = BC_TWO_PI - r;
    y[3] = -k_phi;
    return 4;
}

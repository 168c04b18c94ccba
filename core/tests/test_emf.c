/* test_emf.c - back-EMF shapes: trapezoid table, evaluation, piece walking both ways, Fourier recurrence. */
#include <math.h>

#include "bc_test.h"
#include "bldc/bc_emf.h"
#include "bldc/bc_types.h"

static double trap_exact(double th, double k, double flat)
{
    double r = 0.5 * (BC_PI - flat);
    double t = fmod(th + 0.5 * BC_PI, 2.0 * BC_PI);
    if (t < 0.0) t += 2.0 * BC_PI;
    t -= 0.5 * BC_PI;                         /* [-pi/2, 3pi/2) */
    double half = t < 0.5 * BC_PI ? t : BC_PI - t;
    double v = half / r;
    return k * (v > 1.0 ? 1.0 : (v < -1.0 ? -1.0 : v));
}

int main(void)
{
    double x[4], y[4];
    int n = bc_emf_trapezoid(0.32, 2.0 * BC_PI / 3.0, x, y);
    CHECK(n == 4, "4 corners");
    bc_emf_shape s = {BC_EMF_TABLE, n, x, y};
    CHECK(bc_emf_check(&s) == BC_OK, "valid");
    double worst = 0.0;
    for (int j = -2000; j <= 2000; ++j) {
        double th = 0.00731 * j;
        double e = fabs(bc_emf_eval(&s, th) - trap_exact(th, 0.32, 2.0 * BC_PI / 3.0));
        if (e > worst) worst = e;
    }
    CHECK(worst < 1e-14, "trapezoid table equals the closed form (err %.3g)", worst);
    CHECK(bc_emf_trapezoid(0.32, BC_PI, x, y) == 0, "flat top of pi rejected");
    CHECK(bc_emf_trapezoid(0.32, 0.0, x, y) == 2, "triangle has 2 corners");
    n = bc_emf_trapezoid(0.32, 2.0 * BC_PI / 3.0, x, y);

    /* walk forward two turns, then backward, checking continuity and that every piece contains the angle */
    bc_emf_piece pc;
    bc_emf_piece_at(&s, -1.0, 1, &pc);
    CHECK(pc.lo <= -1.0 && -1.0 <= pc.hi, "piece contains theta");
    double th = -1.0;
    int steps = 0;
    while (th < 4.0 * BC_PI) {
        double hi = pc.hi, khi = pc.k0 + pc.slope * (pc.hi - pc.lo);
        bc_emf_piece_step(&s, 1, &pc);
        CHECK(pc.lo == hi, "forward pieces share their bound");
        CHECK(fabs(pc.k0 - khi) < 1e-14, "continuous at %.6f", hi);
        CHECK(fabs(pc.k0 - bc_emf_eval(&s, pc.lo)) < 1e-13, "piece value right at %.6f", pc.lo);
        th = pc.lo;
        ++steps;
    }
    CHECK(steps == 10, "corners in (-1, 4 pi] plus the one beyond: 10, got %d", steps);
    while (th > -2.0 * BC_PI) {
        double lo = pc.lo;
        bc_emf_piece_step(&s, -1, &pc);
        CHECK(pc.hi == lo, "backward pieces share their bound");
        CHECK(fabs(pc.k0 + pc.slope * (pc.hi - pc.lo) - bc_emf_eval(&s, lo)) < 1e-13, "value at %.6f", lo);
        th = pc.lo;
    }
    /* at a corner, the direction picks the piece */
    bc_emf_piece_at(&s, x[1], 1, &pc);
    CHECK(pc.lo == x[1] && pc.slope < 0.0, "forward at a corner: piece starting there");
    bc_emf_piece_at(&s, x[1], -1, &pc);
    CHECK(pc.hi == x[1] && pc.slope == 0.0, "backward at a corner: piece ending there");

    /* Fourier: sum of harmonics by recurrence equals direct evaluation */
    double a[6] = {0.01, 0.0, 0.0, 0.02, 0.0, 0.001}, b[6] = {0.0, 0.3, 0.0, 0.05, 0.0, -0.01};
    bc_emf_shape f = {BC_EMF_FOURIER, 6, a, b};
    CHECK(bc_emf_check(&f) == BC_OK, "fourier valid");
    worst = 0.0;
    for (int j = 0; j < 1000; ++j) {
        double t = -7.0 + 0.0141 * j, d = 0.0;
        for (int m = 0; m < 6; ++m) d += a[m] * cos(m * t) + b[m] * sin(m * t);
        double e = fabs(bc_emf_eval(&f, t) - d);
        if (e > worst) worst = e;
    }
    CHECK(worst < 1e-14, "fourier recurrence (err %.3g)", worst);
    b[3] = NAN;
    CHECK(bc_emf_check(&f) == BC_ERR_PARAM, "NaN coefficient rejected");
    double xb[3] = {0.0, 1.0, 7.0}, yb[3] = {0.0, 1.0, 0.0};
    bc_emf_shape bad = {BC_EMF_TABLE, 3, xb, yb};
    CHECK(bc_emf_check(&bad) == BC_ERR_PARAM, "angle beyond 2 pi rejected");
    return bc_test_summary("test_emf");
}

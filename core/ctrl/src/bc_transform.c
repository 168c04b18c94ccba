/* bc_transform.c - Clarke, Park, min-max modulation. Equations in bc_transform.h. */
#include "bldc/bc_transform.h"

#include <math.h>

#include "bldc/bc_types.h"

/* rounding allowance: a reference exactly on the hexagon is linear */
#define BC_SVM_TOL 1e-5f

bc_ab bc_clarke(bc_abc x)
{
    bc_ab y;
    y.alpha = (2.0f * x.a - x.b - x.c) * (1.0f / 3.0f); /* alpha = (2a - b - c)/3 */
    y.beta = (x.b - x.c) * BC_INV_SQRT3_F;              /* beta = (b - c)/sqrt(3) */
    return y;
}

bc_abc bc_clarke_inv(bc_ab x)
{
    bc_abc y;
    y.a = x.alpha;                                      /* a = alpha */
    y.b = -0.5f * x.alpha + 0.5f * BC_SQRT3_F * x.beta; /* b = -alpha/2 + sqrt(3)/2 beta */
    y.c = -0.5f * x.alpha - 0.5f * BC_SQRT3_F * x.beta; /* c = -alpha/2 - sqrt(3)/2 beta */
    return y;
}

bc_dq bc_park(bc_ab x, float s, float c)
{
    bc_dq y;
    y.d = x.alpha * c + x.beta * s;  /* d = alpha cos + beta sin */
    y.q = -x.alpha * s + x.beta * c; /* q = -alpha sin + beta cos */
    return y;
}

bc_ab bc_park_inv(bc_dq x, float s, float c)
{
    bc_ab y;
    y.alpha = x.d * c - x.q * s; /* alpha = d cos - q sin */
    y.beta = x.d * s + x.q * c;  /* beta = d sin + q cos */
    return y;
}

float bc_wrap_2pi(float theta)
{
    if (!isfinite(theta)) return 0.0f;
    /* an angle within one turn of the range (every call of a running controller) without fmodf: the same result,
     * since fmodf's remainder of a value in [2 pi, 4 pi) is exactly theta - 2 pi (Sterbenz), and below 0 both add
     * 2 pi once */
    if (theta >= BC_TWO_PI_F) {
        theta = theta < 2.0f * BC_TWO_PI_F ? theta - BC_TWO_PI_F : fmodf(theta, BC_TWO_PI_F);
    } else if (theta < -BC_TWO_PI_F) {
        theta = fmodf(theta, BC_TWO_PI_F);
    }
    if (theta < 0.0f) theta += BC_TWO_PI_F;
    if (theta >= BC_TWO_PI_F) theta = 0.0f;
    return theta;
}

float bc_theta_d(float theta_e) { return bc_wrap_2pi(theta_e - BC_PI_F); }

int bc_svm(bc_abc v, float v_dc, float duty[3])
{
    if (!(isfinite(v.a) && isfinite(v.b) && isfinite(v.c) && isfinite(v_dc) && v_dc > 0.0f)) {
        duty[0] = duty[1] = duty[2] = 0.5f;
        return BC_SVM_CLIPPED;
    }
    float hi = fmaxf(v.a, fmaxf(v.b, v.c));
    float lo = fminf(v.a, fminf(v.b, v.c));
    /* the mid point is computed as lo + (hi - lo)/2 so that it cannot overflow */
    float mid = lo + 0.5f * (hi - lo);
    float in[3] = {v.a, v.b, v.c};
    int clipped = BC_SVM_LINEAR;
    for (int x = 0; x < 3; ++x) {
        float d = 0.5f + (in[x] - mid) / v_dc; /* d_x = 1/2 + (v_x - v_mid)/V_dc */
        if (!(d >= 0.0f)) {                    /* also catches NaN from inf - inf */
            if (!(d >= -BC_SVM_TOL)) clipped = BC_SVM_CLIPPED;
            d = (d < 0.0f) ? 0.0f : 0.5f;
        } else if (d > 1.0f) {
            if (d > 1.0f + BC_SVM_TOL) clipped = BC_SVM_CLIPPED;
            d = 1.0f;
        }
        duty[x] = d;
    }
    return clipped;
}

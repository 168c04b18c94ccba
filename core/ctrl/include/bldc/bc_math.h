/*
 * bc_math.h - the small numerical tools every controller shares (float, header-only: static inline, so each
 * controller's compiler specialises them and a firmware image pays only for what it calls).
 *
 *  bc_clampf(v, lo, hi)   min(max(v, lo), hi) for lo <= hi; a NaN v is returned unchanged (callers that may see
 *                         one test isfinite first).
 *
 *  bc_root_bracket        a root of g on a bracket [a, b] with g(a) < 0 < g(b) (g increasing through the root) by
 *                         regula falsi with end-value scaling:
 *
 *                             d = a - g_a (b - a) / max(g_b - g_a, 1e-30),   d clamped to [a, b]
 *
 *                         g(d) < 0 replaces a, else b. The end that stays has its g halved, so the bracket
 *                         shrinks from both sides instead of regula falsi's one-sided crawl: BC_ROOT_ILLINOIS
 *                         halves it when the same end stayed twice in a row (the Illinois method, superlinear),
 *                         BC_ROOT_HALVE every time it stays (slower on a smooth root: bc_sixstep's predictive
 *                         solve used it until its worst closed-loop step, 7,748 instructions with up to 12
 *                         evaluations of the prediction, came down to 4,782 with BC_ROOT_ILLINOIS).
 *                         Stops when |g(d)| <= tol, b - a < width, g(d) is not finite, or after max_it
 *                         evaluations; returns the last d
 *                         (evaluated, or the next estimate when max_it ran out), clamped to the final bracket
 *                         (NaN only if the first estimate is NaN: callers test isfinite on the result).
 */
#ifndef BC_MATH_H
#define BC_MATH_H

#include <math.h>

static inline float bc_clampf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }

/* The function whose root is sought: g(d) given the caller's context. */
typedef float (*bc_root_fn)(float d, void *ctx);

#define BC_ROOT_ILLINOIS 0 /* halve the staying end's g when it stayed the previous time too */
#define BC_ROOT_HALVE 1    /* halve the staying end's g every time */

/* Root of g on [a, b] from the first estimate d (ga = g(a) < 0 < gb = g(b)); see the header comment. */
static inline float bc_root_bracket(bc_root_fn g, void *ctx, float a, float b, float ga, float gb, float d, float tol,
                                    float width, int max_it, int rule)
{
    int side = 0;
    for (int it = 0; it < max_it; ++it) {
        d = bc_clampf(d, a, b);
        float gd = g(d, ctx);
        if (!isfinite(gd) || fabsf(gd) <= tol || b - a < width) break;
        if (gd < 0.0f) {
            a = d;
            ga = gd;
            if (rule == BC_ROOT_HALVE || side == -1) gb *= 0.5f;
            side = -1;
        } else {
            b = d;
            gb = gd;
            if (rule == BC_ROOT_HALVE || side == 1) ga *= 0.5f;
            side = 1;
        }
        d = a - ga * (b - a) / fmaxf(gb - ga, 1e-30f);
    }
    return bc_clampf(d, a, b);
}

#endif /* BC_MATH_H */

/* bc_pi.c - PI with anti-windup on the realised output. Law in bc_pi.h. */
#include "bldc/bc_pi.h"

#include <math.h>

#include "bldc/bc_math.h"
#include "bldc/bc_types.h"

static float finite_or_zero(float v) { return isfinite(v) ? v : 0.0f; }

int bc_pi_init(const bc_pi_params *p, bc_pi_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    if (!isfinite(p->kp) || !isfinite(p->ki) || !isfinite(p->ts) || !isfinite(p->u_min) || !isfinite(p->u_max))
        return BC_ERR_PARAM;
    if (p->kp < 0.0f || p->ki < 0.0f || !(p->ts > 0.0f) || !(p->u_min < p->u_max)) return BC_ERR_PARAM;
    s->x = bc_clampf(0.0f, p->u_min, p->u_max);
    return BC_OK;
}

void bc_pi_reset(const bc_pi_params *p, bc_pi_state *s, float x0)
{
    s->x = bc_clampf(finite_or_zero(x0), p->u_min, p->u_max);
}

float bc_pi_output(const bc_pi_params *p, const bc_pi_state *s, float e, float u_ff)
{
    return p->kp * finite_or_zero(e) + s->x + finite_or_zero(u_ff);
}

float bc_pi_limit(const bc_pi_params *p, float u) { return bc_clampf(finite_or_zero(u), p->u_min, p->u_max); }

void bc_pi_update(const bc_pi_params *p, bc_pi_state *s, float e, float u, float u_real)
{
    e = finite_or_zero(e);
    float x;
    if (p->kp > 0.0f && isfinite(u) && isfinite(u_real)) {
        x = s->x + p->ki * p->ts * (e + (u_real - u) / p->kp);
    } else {
        x = s->x + p->ki * p->ts * e;
    }
    s->x = bc_clampf(finite_or_zero(x), p->u_min, p->u_max);
}

float bc_pi_step(const bc_pi_params *p, bc_pi_state *s, float e, float u_ff)
{
    float u = bc_pi_output(p, s, e, u_ff);
    float ur = bc_pi_limit(p, u);
    bc_pi_update(p, s, e, u, ur);
    return ur;
}

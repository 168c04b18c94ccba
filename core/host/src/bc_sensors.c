/* bc_sensors.c - measurement chain. Equations in bc_sensors.h. */
#include "bldc/bc_sensors.h"

#include <float.h>
#include <math.h>

static int finite_nonneg(double v) { return isfinite(v) && v >= 0.0; }

int bc_sensor_init(const bc_sensor_params *p, bc_sensor_state *s)
{
    if (p == 0 || s == 0) return BC_ERR_PARAM;
    uint32_t m = p->i_mask & 7u;
    if (m != p->i_mask || m == 0u || m == 1u || m == 2u || m == 4u) return BC_ERR_PARAM;
    for (int x = 0; x < 3; ++x) {
        if (!isfinite(p->i_gain[x]) || !isfinite(p->i_offset[x])) return BC_ERR_PARAM;
    }
    if (!finite_nonneg(p->i_noise) || !finite_nonneg(p->i_lsb) || !(p->i_fs >= 0.0) || !isfinite(p->v_gain) ||
        !isfinite(p->v_offset) || !finite_nonneg(p->v_noise) || !finite_nonneg(p->v_lsb) ||
        !(isfinite(p->f_tick) && p->f_tick > 0.0))
        return BC_ERR_PARAM;
    for (int j = 0; j < BC_FAULT_MAX; ++j) {
        const bc_fault *f = &p->fault[j];
        if (f->kind == BC_FAULT_NONE) continue;
        if ((f->kind != BC_FAULT_CURRENT_OFFSET && f->kind != BC_FAULT_CURRENT_LOSS) || f->phase < 0 || f->phase > 2 ||
            isnan(f->t_on) || isnan(f->t_off) || !(f->t_off > f->t_on) || !isfinite(f->value))
            return BC_ERR_PARAM;
    }
    s->rng = p->seed ^ 0x9E3779B97F4A7C15ull;
    if (s->rng == 0u) s->rng = 1u;
    s->has_spare = 0;
    s->spare = 0.0;
    s->edge_t = NAN;
    s->edge_f = NAN;
    s->edge_tick = 0u;
    return BC_OK;
}

static double uniform01(uint64_t *rng)
{
    uint64_t x = *rng;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    *rng = x;
    uint64_t r = x * 0x2545F4914F6CDD1Dull;
    return ((double)(r >> 11) + 0.5) * (1.0 / 9007199254740992.0); /* (0, 1) */
}

double bc_rng_normal(uint64_t *rng, int32_t *has_spare, double *spare)
{
    if (*has_spare) {
        *has_spare = 0;
        return *spare;
    }
    double u1 = uniform01(rng), u2 = uniform01(rng);
    double r = sqrt(-2.0 * log(u1));
    *spare = r * sin(BC_TWO_PI * u2);
    *has_spare = 1;
    return r * cos(BC_TWO_PI * u2);
}

static double normal(bc_sensor_state *s) { return bc_rng_normal(&s->rng, &s->has_spare, &s->spare); }

static double quantise(double v, double lsb) { return lsb > 0.0 ? lsb * floor(v / lsb + 0.5) : v; }

/* the full scale: min(max(v, -fs), fs) for fs > 0 (NaN passes, as without a full scale) */
static double clip(double v, double fs)
{
    if (!(fs > 0.0)) return v;
    return v > fs ? fs : (v < -fs ? -fs : v);
}

/* floor(t f_tick) mod 2^32, in this file's own calls inlined (an exported function in a shared library is not) */
static inline uint32_t tick_at(double f_tick, double t)
{
    if (!(t >= 0.0) || !isfinite(t)) return 0u;
    double ticks = floor(t * f_tick);
    /* mod 2^32: the conversion of an integer below 2^64 to uint64_t, then to uint32_t, takes it exactly */
    return ticks < 18446744073709551616.0 ? (uint32_t)(uint64_t)ticks : (uint32_t)(uint64_t)fmod(ticks, 4294967296.0);
}

uint32_t bc_tick_at(double f_tick, double t) { return tick_at(f_tick, t); }

uint32_t bc_sensor_tick(const bc_sensor_params *p, double t) { return tick_at(p->f_tick, t); }

void bc_sensor_measure(const bc_sensor_params *p, bc_sensor_state *s, const bc_plant_state *ps, double v_bus,
                       bc_ctrl_in *in)
{
    int faults = 0; /* any sensor fault configured: then each phase looks for its own */
    for (int j = 0; j < BC_FAULT_MAX; ++j) faults |= p->fault[j].kind != BC_FAULT_NONE;
    for (int x = 0; x < 3; ++x) {
        if (p->i_mask & (1u << x)) {
            double v = p->i_gain[x] * ps->i[x] + p->i_offset[x];
            if (p->i_noise > 0.0) v += p->i_noise * normal(s);
            for (int j = 0; j < BC_FAULT_MAX && faults; ++j) {
                const bc_fault *f = &p->fault[j];
                if (f->kind == BC_FAULT_NONE || f->phase != x || !(ps->t >= f->t_on && ps->t < f->t_off)) continue;
                if (f->kind == BC_FAULT_CURRENT_OFFSET) v += f->value;
                if (f->kind == BC_FAULT_CURRENT_LOSS) v = 0.0;
            }
            in->i_abc[x] = (float)clip(quantise(v, p->i_lsb), p->i_fs);
        } else {
            in->i_abc[x] = 0.0f;
        }
    }
    in->i_mask = p->i_mask;
    in->i_fs = p->i_fs > 0.0 && p->i_fs < (double)FLT_MAX ? (float)p->i_fs : 0.0f;
    double v = p->v_gain * v_bus + p->v_offset;
    if (p->v_noise > 0.0) v += p->v_noise * normal(s);
    in->v_dc = (float)quantise(v, p->v_lsb);
    in->hall = (uint32_t)ps->hall_out;
    in->n_edges = ps->n_edges;
    if (!(ps->t_edge == s->edge_t && p->f_tick == s->edge_f)) {
        s->edge_t = ps->t_edge;
        s->edge_f = p->f_tick;
        s->edge_tick = tick_at(p->f_tick, ps->t_edge);
    }
    in->tick_edge = s->edge_tick;
    in->tick_now = tick_at(p->f_tick, ps->t);
    in->theta_enc = (float)ps->theta;
    if (in->theta_enc >= BC_TWO_PI_F) in->theta_enc = 0.0f;
    in->omega_enc = (float)ps->omega;
    in->fault_pin = ps->tripped ? 1u : 0u;
}

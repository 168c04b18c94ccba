/*
 * cost.c - host harness for instruction counts per controller step (benchmarks/firmware.py runs it under
 * valgrind --tool=callgrind). Usage: cost CONTROLLER SCENARIO N. Each scenario feeds a class of inputs:
 *   run      a motor turning: Hall edges every few samples, currents near the reference, and the back-EMF sensing
 *            (comparator edges at mid-sector, ADC samples) of the same rotor
 *   edge     a Hall edge at every sample (commutation every step)
 *   invalid  invalid Hall codes (safe-state path)
 *   nan      non-finite measurements (input-validation path)
 * The target's step (targets.c) inclusive instruction count divided by N is the cost per step; the worst scenario is
 * the figure that matters for a real-time budget.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bldc/bc_types.h"
#include "targets.h"

static void make_input(const bc_fw_target *tg, const char *scenario, long k, bc_ctrl_in *in)
{
    static const uint32_t seq[6] = {1u, 3u, 2u, 6u, 4u, 5u};
    memset(in, 0, sizeof *in);
    long per_edge = strcmp(scenario, "edge") == 0 ? 1 : 40;
    long e = k / per_edge;
    in->hall = seq[e % 6];
    in->n_edges = (uint32_t)e;
    in->tick_edge = (uint32_t)((float)(e * per_edge) * tg->tick_per_ts);
    in->tick_now = (uint32_t)((float)k * tg->tick_per_ts);
    float th = 0.1f * (float)k;
    in->i_abc[0] = tg->i_amp * sinf(th);
    in->i_abc[1] = tg->i_amp * sinf(th - 2.0944f);
    in->i_abc[2] = tg->i_amp * sinf(th + 2.0944f);
    in->i_mask = 3u;
    in->v_dc = tg->v_dc;
    in->ref = tg->ref;
    in->omega_ref = 30.0f;
    in->theta_enc = fmodf(th, 6.2831853f);
    in->omega_enc = 30.0f;
    /* the back-EMF sensing of a motor turning at the same speed (the sensorless controllers; the others ignore it),
     * two sectors ahead of the Hall codes' (a sensorless start commands sector 2 first, bc_bemf.h 4): it enters a
     * sector at theta_e = pi/6 + e pi/3, phase x's back-EMF ~ sin(theta_e - x 2 pi/3) crosses zero at x 2 pi/3 + n pi
     * (mid-sector); the comparators show its sign, time-stamped at the crossings; an ADC conversion at every other
     * sample, of V/2 plus a quarter of the bus times that sine */
    const double ahead = 2.0 * 3.14159265358979 / 3.0;
    double te = ahead + 3.14159265358979 / 6.0 + (double)k / (double)per_edge * (3.14159265358979 / 3.0);
    for (int x = 0; x < 3; ++x) {
        double ph = te - (double)x * (2.0 * 3.14159265358979 / 3.0);
        double n = floor(ph / 3.14159265358979);
        double s = sin(ph);
        if (s > 0.0) in->zc_state |= 1u << x;
        in->zc_count[x] = (uint32_t)(int64_t)(n + 4.0);
        double k_cross = (n * 3.14159265358979 + (double)x * (2.0 * 3.14159265358979 / 3.0) - 3.14159265358979 / 6.0 -
                          ahead) /
                         (3.14159265358979 / 3.0) * (double)per_edge;
        in->zc_tick[x] = (uint32_t)(int64_t)(k_cross * (double)tg->tick_per_ts);
        double ka = (double)(k - 1 - (k - 1) % 2);
        double pa = ahead + 3.14159265358979 / 6.0 + ka / (double)per_edge * (3.14159265358979 / 3.0) -
                    (double)x * (2.0 * 3.14159265358979 / 3.0);
        in->v_term[x] = (float)(0.5 * (double)tg->v_dc + 0.25 * (double)tg->v_dc * sin(pa));
    }
    in->v_neutral = 0.5f * tg->v_dc;
    in->n_adc = (uint32_t)((k + 1) / 2);
    in->tick_adc = (uint32_t)(int64_t)((double)(k - 1 - (k - 1) % 2) * (double)tg->tick_per_ts);
    if (strcmp(scenario, "invalid") == 0) in->hall = (k % 2) ? 7u : 0u;
    if (strcmp(scenario, "nan") == 0) {
        in->i_abc[0] = NAN;
        in->v_dc = INFINITY;
        in->ref = NAN;
    }
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: cost CONTROLLER run|edge|invalid|nan N\n");
        return 2;
    }
    long n = atol(argv[3]);
    for (int j = 0; j < bc_fw_n_targets; ++j) {
        const bc_fw_target *tg = &bc_fw_targets[j];
        if (strcmp(tg->name, argv[1]) != 0) continue;
        if (tg->init() != BC_OK) {
            fprintf(stderr, "init failed\n");
            return 1;
        }
        static bc_ctrl_in inputs[1024];
        for (long k = 0; k < 1024; ++k) make_input(tg, argv[2], k, &inputs[k]);
        bc_ctrl_out out;
        double sink = 0.0;
        for (long k = 0; k < n; ++k) {
            memset(&out, 0, sizeof out);
            tg->step(&inputs[k % 1024], &out);
            sink += (double)out.leg[0].duty + (double)out.diag[0];
        }
        printf("%s %s %ld %g\n", argv[1], argv[2], n, sink);
        return 0;
    }
    fprintf(stderr, "unknown controller %s\n", argv[1]);
    return 2;
}

/*
 * bc_sensors.h - the measurement chain between the plant (double) and a controller (float).
 *
 *     i_meas,x = c(q(gain_x i_x + offset_x + n)),   n ~ N(0, sigma_i^2),   q(v) = lsb round(v / lsb)  (lsb > 0)
 *     c(v)     = min(max(v, -i_fs), i_fs)      (the shunt amplifier's and ADC's full scale, i_fs > 0; 0: none)
 *     v_meas   = q(gain_v v_bus + offset_v + n), n ~ N(0, sigma_v^2)
 *     tick(t)  = floor(t f_tick) mod 2^32          (free-running capture timer)
 *
 * Unmeasured phases read 0 with their i_mask bit clear. Hall code, edge count and edge time come from the plant
 * (which models the sensors' angle errors and delay); the encoder reports the exact angle and speed.
 * Noise comes from a seeded xorshift64* generator in caller-owned state: runs are reproducible.
 */
#ifndef BC_SENSORS_H
#define BC_SENSORS_H

#include <stdint.h>

#include "bldc/bc_plant.h"
#include "bldc/bc_types.h"

typedef struct {
    uint32_t i_mask;     /* measured phases, bit 0 = a; at least two bits */
    double i_gain[3];    /* - */
    double i_offset[3];  /* A */
    double i_noise;      /* standard deviation, A */
    double i_lsb;        /* quantisation step, A (0: none) */
    double i_fs;         /* full scale: a reading clips to [-i_fs, i_fs], A (0 or HUGE_VAL: none) */
    double v_gain;       /* - */
    double v_offset;     /* V */
    double v_noise;      /* standard deviation, V */
    double v_lsb;        /* quantisation step, V (0: none) */
    double f_tick;       /* capture timer frequency, Hz */
    uint64_t seed;       /* noise generator seed */
    bc_fault fault[BC_FAULT_MAX]; /* sensor faults (BC_FAULT_CURRENT_*), each active on [t_on, t_off) */
} bc_sensor_params;

typedef struct {
    uint64_t rng;       /* xorshift64* state */
    int32_t has_spare;  /* Box-Muller keeps one normal variate */
    double spare;
    double edge_t;      /* the last Hall edge time converted to a capture tick (NaN: none yet), s */
    double edge_f;      /* ... at this timer frequency, Hz */
    uint32_t edge_tick; /* ... its tick (an edge is rare: the conversion is kept) */
} bc_sensor_state;

int bc_sensor_init(const bc_sensor_params *p, bc_sensor_state *s);

/* Fill the measurement fields of `in` (not ref/omega_ref) from the plant at its current time. */
void bc_sensor_measure(const bc_sensor_params *p, bc_sensor_state *s, const bc_plant_state *ps, double v_bus,
                       bc_ctrl_in *in);

/* Capture-timer tick at time t (0 for t < 0 or non-finite t). */
uint32_t bc_sensor_tick(const bc_sensor_params *p, double t);

/* ... of a timer counting at f_tick, Hz: floor(t f_tick) mod 2^32. */
uint32_t bc_tick_at(double f_tick, double t);

/* A standard normal variate from the xorshift64* state *rng (Box-Muller; the second variate kept in *spare). */
double bc_rng_normal(uint64_t *rng, int32_t *has_spare, double *spare);

#endif /* BC_SENSORS_H */

/* fixtures.h - the htm-48v drive (paper 1, Table II) as plain C parameters for the host tests. */
#ifndef FIXTURES_H
#define FIXTURES_H

#include <string.h>

#include "bldc/bc_emf.h"
#include "bldc/bc_plant.h"
#include "bldc/bc_sensors.h"

typedef struct {
    double x[4], y[4];
    bc_plant_params p;
    bc_sensor_params sp;
} fixture;

/* 48 V, R = 50 mOhm, L = 75 uH, k_phi = 0.32 V s/rad, p = 8, 14 kHz, ideal 120-degree trapezoid. */
static void fixture_htm(fixture *f, int mech)
{
    memset(f, 0, sizeof *f);
    int n = bc_emf_trapezoid(0.32, 2.0 * BC_PI / 3.0, f->x, f->y);
    for (int k = 0; k < 3; ++k) {
        f->p.emf[k].kind = BC_EMF_TABLE;
        f->p.emf[k].n = n;
        f->p.emf[k].x = f->x;
        f->p.emf[k].y = f->y;
    }
    f->p.p = 8;
    f->p.R = 0.05;
    f->p.L = 75e-6;
    f->p.f_pwm = 14e3;
    f->p.mech = mech;
    f->p.J = 0.05;
    f->sp.i_mask = 3u;
    for (int k = 0; k < 3; ++k) f->sp.i_gain[k] = 1.0;
    f->sp.v_gain = 1.0;
    f->sp.f_tick = 10e6;
    f->sp.seed = 1u;
}

#endif /* FIXTURES_H */

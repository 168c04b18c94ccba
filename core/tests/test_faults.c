/* test_faults.c - injected faults: phase open (broken wire), Hall sensor stuck and glitch, current sensor offset and
 * loss: what the plant and the sensors do, with the energy lost in the arc accounted. */
#include <math.h>
#include <string.h>

#include "bc_test.h"
#include "bldc/bc_commutation.h"
#include "bldc/bc_plant.h"
#include "bldc/bc_sensors.h"
#include "fixtures.h"

static const double I0[3] = {0.0, 0.0, 0.0};

/* Six-step at a fixed duty, imposed speed, for n half periods; calls back after each. */
static void six_step(const bc_plant_params *p, bc_plant_state *s, long n, void (*each)(const bc_plant_state *, void *),
                     void *ctx)
{
    double th = bc_plant_t_half(p);
    long k0 = lround(s->t / th); /* continue from where the plant is */
    for (long k = k0; k < k0 + n; ++k) {
        bc_leg_cmd c[3] = {{0, 0.0f}, {0, 0.0f}, {0, 0.0f}};
        int pos, neg;
        if (bc_sector_phases(bc_hall_sector((uint32_t)s->hall_out), &pos, &neg) == 0) {
            c[pos].mode = BC_LEG_HIGH;
            c[pos].duty = 0.6f;
            c[neg].mode = BC_LEG_LOW;
            c[neg].duty = 1.0f;
        }
        bc_plant_set_half(p, s, c, (k % 2) == 0);
        bc_plant_advance(p, s, (double)(k + 1) * th);
        if (each) each(s, ctx);
    }
}

typedef struct {
    double t_on;
    int phase;
    int violations;
    int seen_invalid;
    int codes_with_bit;
} watch;

static void check_open(const bc_plant_state *s, void *ctx)
{
    watch *w = ctx;
    if (s->t > w->t_on && s->i[w->phase] != 0.0) w->violations += 1;
    if (fabs(s->i[0] + s->i[1] + s->i[2]) > 1e-9) w->violations += 1;
}

static void check_stuck(const bc_plant_state *s, void *ctx)
{
    watch *w = ctx;
    if (s->t > w->t_on) {
        if (!(s->hall_out & (1 << w->phase))) w->violations += 1;
        if (s->hall_out == 7) w->seen_invalid = 1;
    }
}

int main(void)
{
    fixture f;
    bc_plant_state s;
    double om = 0.4 * 75.0;
    /* phase open at 20 ms on a motor carrying current */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.fault[0].kind = BC_FAULT_PHASE_OPEN;
    f.p.fault[0].phase = 1;
    f.p.fault[0].t_on = 0.0105; /* theta = 2.82 rad: sector 2, phase b carries the current */
    f.p.fault[0].t_off = HUGE_VAL;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om, I0, 48.0) == BC_OK, "init");
    watch w = {0.0105, 1, 0, 0, 0};
    six_step(&f.p, &s, 1400, check_open, &w);
    CHECK(w.violations == 0, "open phase carries no current after the fault (%d violations)", w.violations);
    CHECK(s.e_fault > 0.0, "energy lost in the arc booked: %.3g J", s.e_fault);
    double wl = 0.5 * f.p.L * (s.i[0] * s.i[0] + s.i[1] * s.i[1] + s.i[2] * s.i[2]);
    double out = s.acc[BC_ACC_CU] + s.acc[BC_ACC_SW] + s.acc[BC_ACC_DIODE] + s.acc[BC_ACC_EMF] + wl + s.e_fault;
    CHECK(fabs(s.acc[BC_ACC_SRC] - out) < 1e-6 * s.acc[BC_ACC_SRC], "energy balance with the arc: %.3g J",
          s.acc[BC_ACC_SRC] - out);

    /* Hall sensor a stuck at 1 from 10 ms: bit a always set, the invalid code 7 appears */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.fault[0].kind = BC_FAULT_HALL_STUCK;
    f.p.fault[0].phase = 0;
    f.p.fault[0].value = 1.0;
    f.p.fault[0].t_on = 0.01;
    f.p.fault[0].t_off = HUGE_VAL;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om, I0, 48.0) == BC_OK, "init");
    watch ws = {0.01, 0, 0, 0, 0};
    six_step(&f.p, &s, 3000, check_stuck, &ws);
    CHECK(ws.violations == 0, "stuck bit stays set");
    CHECK(ws.seen_invalid, "the controller sees the invalid code 111");

    /* Hall glitch: sensor b inverted for 50 us: two extra edges */
    fixture_htm(&f, BC_MECH_IMPOSED);
    bc_plant_state s0;
    CHECK(bc_plant_init(&f.p, &s0, 0.0, 0.3, om, I0, 48.0) == BC_OK, "init");
    six_step(&f.p, &s0, 500, 0, 0);
    f.p.fault[0].kind = BC_FAULT_HALL_GLITCH;
    f.p.fault[0].phase = 1;
    f.p.fault[0].t_on = 0.005;
    f.p.fault[0].t_off = 0.00505;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om, I0, 48.0) == BC_OK, "init");
    six_step(&f.p, &s, 500, 0, 0);
    CHECK(s.n_edges == s0.n_edges + 2u, "glitch adds two edges: %u vs %u", s.n_edges, s0.n_edges);
    CHECK(s.hall_out == s0.hall_out, "after the glitch the code is right again");

    /* current sensor faults */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.sp.fault[0].kind = BC_FAULT_CURRENT_LOSS;
    f.sp.fault[0].phase = 0;
    f.sp.fault[0].t_on = 0.0;
    f.sp.fault[0].t_off = HUGE_VAL;
    f.sp.fault[1].kind = BC_FAULT_CURRENT_OFFSET;
    f.sp.fault[1].phase = 1;
    f.sp.fault[1].value = 5.0;
    f.sp.fault[1].t_on = 0.0;
    f.sp.fault[1].t_off = HUGE_VAL;
    bc_sensor_state ss;
    CHECK(bc_sensor_init(&f.sp, &ss) == BC_OK, "sensor init");
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om, I0, 48.0) == BC_OK, "init");
    double true_max = 0.0, lost_max = 0.0, off_err = 0.0;
    for (int j = 0; j < 40; ++j) {
        six_step(&f.p, &s, 20, 0, 0);
        bc_ctrl_in in;
        memset(&in, 0, sizeof in);
        bc_sensor_measure(&f.sp, &ss, &s, 48.0, &in);
        if (fabs(s.i[0]) > true_max) true_max = fabs(s.i[0]);
        if (fabs((double)in.i_abc[0]) > lost_max) lost_max = fabs((double)in.i_abc[0]);
        double e = fabs((double)in.i_abc[1] - (s.i[1] + 5.0));
        if (e > off_err) off_err = e;
    }
    CHECK(lost_max == 0.0 && true_max > 10.0, "lost sensor reads 0 (true current up to %.3g A)", true_max);
    CHECK(off_err < 1e-4, "offset sensor reads 5 A more (err %.3g)", off_err);
    f.sp.fault[0].kind = 9;
    CHECK(bc_sensor_init(&f.sp, &ss) == BC_ERR_PARAM, "unknown sensor fault rejected");
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.fault[0].kind = BC_FAULT_PHASE_OPEN;
    f.p.fault[0].phase = 3;
    f.p.fault[0].t_off = 1.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, om, I0, 48.0) == BC_ERR_PARAM, "fault on phase 3 rejected");
    /* hardware over-current trip: a DC step at standstill heads for V/2R = 480 A; the trip at 100 A switches every
     * gate off at the exact instant of the RL response, and the current decays through the diodes */
    fixture_htm(&f, BC_MECH_IMPOSED);
    f.p.i_trip = 100.0;
    CHECK(bc_plant_init(&f.p, &s, 0.0, 0.3, 0.0, I0, 48.0) == BC_OK, "init");
    bc_leg_cmd dc[3] = {{BC_LEG_HIGH, 1.0f}, {BC_LEG_LOW, 1.0f}, {BC_LEG_OFF, 0.0f}};
    double th = bc_plant_t_half(&f.p), peak = 0.0;
    for (long k = 0; k < 400; ++k) {
        bc_plant_set_half(&f.p, &s, dc, (k % 2) == 0);
        bc_plant_advance(&f.p, &s, (double)(k + 1) * th);
        if (fabs(s.i[0]) > peak) peak = fabs(s.i[0]);
    }
    double tau = f.p.L / f.p.R, t_exact = -tau * log(1.0 - 100.0 / 480.0);
    CHECK(s.tripped == 1, "tripped");
    CHECK(fabs(s.t_trip - t_exact) < 1e-9, "trip at %.9f s, RL response reaches 100 A at %.9f s", s.t_trip, t_exact);
    CHECK(peak <= 100.0 + 1e-6, "current never above the trip level: %.6f A", peak);
    CHECK(fabs(s.i[0]) < 1e-6, "freewheeled to zero: %.3g A", s.i[0]);
    return bc_test_summary("test_faults");
}

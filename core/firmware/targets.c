/* targets.c - every controller (and the blocks they are built of) with working parameters, for host tools. */
#include "targets.h"

#include <math.h>

#include "bldc/bc_fluxobs.h"
#include "bldc/bc_hall.h"
#include "bldc/bc_hallcal.h"
#include "bldc/bc_openloop.h"
#include "bldc/bc_pi.h"
#include "bldc/bc_redobs.h"
#include "params.h"

/* The host tools call each target through a pointer: keep the steps out of line so they are measurable. */
#define STEP_FN __attribute__((noinline)) static void

static bc_sixv_params sixv_p = {BC_SIXV_HIGH};
static bc_sixv_state sixv_s;
static int sixv_init(void) { return bc_sixv_init(&sixv_p, &sixv_s); }
STEP_FN sixv_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sixv_step(&sixv_p, &sixv_s, in, out); }

static bc_hall_params hall_p = {10e6f, 5.0f, 0.0f, BC_HALL_INTERP, 1.0f, {0, {0}, {0}}};
static bc_hall_state hall_s;
static int hall_init(void) { return bc_hall_init(&hall_p, &hall_s); }
STEP_FN hall_step(const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_hall_out h;
    bc_hall_step(&hall_p, &hall_s, in, &h);
    out->diag[0] = h.theta;
    out->diag[1] = h.omega_e;
}

static const bc_hall_params hall_pll_p = HALL_PLL_PARAMS;
static bc_hall_state hall_pll_s;
static int hall_pll_init(void) { return bc_hall_init(&hall_pll_p, &hall_pll_s); }
STEP_FN hall_pll_step(const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_hall_out h;
    bc_hall_step(&hall_pll_p, &hall_pll_s, in, &h);
    out->diag[0] = h.theta;
    out->diag[1] = h.omega_e;
}

static const bc_hallcal_params hallcal_p = HTM_HALLCAL_OL_PARAMS;
static bc_hallcal_state hallcal_s;
static int hallcal_init(void) { return bc_hallcal_init(&hallcal_p, &hallcal_s); }
STEP_FN hallcal_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_hallcal_step(&hallcal_p, &hallcal_s, in, out); }

static const bc_hallcal_params hallcal_speed_p = HTM_HALLCAL_SPEED_PARAMS;
static bc_hallcal_state hallcal_speed_s;
static int hallcal_speed_init(void) { return bc_hallcal_init(&hallcal_speed_p, &hallcal_speed_s); }
STEP_FN hallcal_speed_step(const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_hallcal_step(&hallcal_speed_p, &hallcal_speed_s, in, out);
}

static bc_pi_params pi_p = {0.47f, 314.0f, 35.7e-6f, -48.0f, 48.0f};
static bc_pi_state pi_s;
static int pi_init(void) { return bc_pi_init(&pi_p, &pi_s); }
STEP_FN pi_step(const bc_ctrl_in *in, bc_ctrl_out *out) { out->diag[0] = bc_pi_step(&pi_p, &pi_s, in->ref - in->i_abc[0], 0.0f); }

static const bc_sixstep_params sixstep_p = HTM_SIXSTEP_PARAMS(0);
static bc_sixstep_state sixstep_s;
static int sixstep_init(void) { return bc_sixstep_init(&sixstep_p, &sixstep_s); }
STEP_FN sixstep_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sixstep_step(&sixstep_p, &sixstep_s, in, out); }

/* six-step with a timing advance (10 deg + 30 us) and the commutation timer (bc_ctrl_out.has_at) */
static bc_sixstep_params sixstep_timed_p = HTM_SIXSTEP_PARAMS(0);
static bc_sixstep_state sixstep_timed_s;
static int sixstep_timed_init(void)
{
    sixstep_timed_p.timed = 1;
    sixstep_timed_p.adv_angle = 0.1745f;
    sixstep_timed_p.adv_time = 30e-6f;
    return bc_sixstep_init(&sixstep_timed_p, &sixstep_timed_s);
}
STEP_FN sixstep_timed_step(const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_sixstep_step(&sixstep_timed_p, &sixstep_timed_s, in, out);
}

static const bc_sine_params sine_p = HTM_SINE_PARAMS;
static bc_sine_state sine_s;
static int sine_init(void) { return bc_sine_init(&sine_p, &sine_s); }
STEP_FN sine_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sine_step(&sine_p, &sine_s, in, out); }

/* the sensorless Sine (flux observer, I/f start-up) and the self-commissioning routine, on htm-48v */
static bc_sine_params sine_obs_p = HTM_SINE_PARAMS;
static bc_sine_state sine_obs_s;
static int sine_obs_init(void)
{
    htm_sine_observer(&sine_obs_p);
    return bc_sine_init(&sine_obs_p, &sine_obs_s);
}
STEP_FN sine_obs_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_sine_step(&sine_obs_p, &sine_obs_s, in, out); }

static const bc_commission_params comm_p = HTM_COMMISSION_PARAMS;
static bc_commission_state comm_s;
static int commission_init(void) { return bc_commission_init(&comm_p, &comm_s); }
STEP_FN commission_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_commission_step(&comm_p, &comm_s, in, out); }

static const bc_lu_params lu_p = LU4KW_LU_PARAMS;
static bc_lu_state lu_s;
static int lu_init(void) { return bc_lu_init(&lu_p, &lu_s); }
STEP_FN lu_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_lu_step(&lu_p, &lu_s, in, out); }

/* The observers as blocks: the phase currents (Clarke of i_abc, the two measured phases of i_mask when only two are)
 * and a stator voltage carried in (ref, omega_ref) as (u_alpha, u_beta); diag: angle, speed, flux, error signal,
 * valid. */
static bc_obs_in obs_input(const bc_ctrl_in *in)
{
    bc_abc i = {in->i_abc[0], in->i_abc[1], -(in->i_abc[0] + in->i_abc[1])};
    bc_obs_in o = {{in->ref, in->omega_ref}, bc_clarke(i)};
    return o;
}

static void obs_diag(const bc_obs_out *o, bc_ctrl_out *out)
{
    out->diag[0] = o->theta;
    out->diag[1] = o->omega_e;
    out->diag[2] = o->flux;
    out->diag[3] = o->err;
    out->diag[4] = (float)o->valid;
}

static const bc_fluxobs_params fluxobs_p = HTM_FLUXOBS_PARAMS;
static bc_fluxobs_state fluxobs_s;
static int fluxobs_init(void) { return bc_fluxobs_init(&fluxobs_p, &fluxobs_s); }
STEP_FN fluxobs_step(const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_obs_in oi = obs_input(in);
    bc_obs_out oo;
    bc_fluxobs_step(&fluxobs_p, &fluxobs_s, &oi, &oo);
    obs_diag(&oo, out);
}

static const bc_redobs_params redobs_p = HTM_REDOBS_PARAMS;
static bc_redobs_state redobs_s;
static int redobs_init(void) { return bc_redobs_init(&redobs_p, &redobs_s); }
STEP_FN redobs_step(const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_obs_in oi = obs_input(in);
    bc_obs_out oo;
    bc_redobs_step(&redobs_p, &redobs_s, &oi, &oo);
    obs_diag(&oo, out);
}
/* the sensorless controller: as configured for htm-48v (its start-up from standstill), and locked to the cost
 * harness's turning motor (a direct start at its speed, 40 samples per sector: closed loop within a few sectors),
 * with the back-EMF integration method and a timing advance */
static const bc_bemf_params bemf_p = HTM_BEMF_PARAMS;
static bc_bemf_state bemf_s;
static int bemf_init(void) { return bc_bemf_init(&bemf_p, &bemf_s); }
STEP_FN bemf_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_bemf_step(&bemf_p, &bemf_s, in, out); }

static bc_bemf_params bemf_int_p = HTM_BEMF_PARAMS;
static bc_bemf_state bemf_int_s;
static int bemf_int_init(void)
{
    const float w = 3.14159265f / 3.0f / (40.0f * HTM_TS); /* cost.c: a sector every 40 samples */
    bemf_int_p.method = BC_BEMF_INTEGRATE;
    bemf_int_p.align_time = 0.0f;
    bemf_int_p.ramp_w0 = w;
    bemf_int_p.ramp_w1 = w;
    bemf_int_p.ramp_accel = 0.0f;
    bemf_int_p.omega_stall = 0.2f * w;
    bemf_int_p.adv_angle = 0.1745f;
    bemf_int_p.adv_demag = 0.5f;
    bemf_int_p.d_diode = 0.04f; /* the inverter's share (a diode's drop) in the fuzzed start-up and limit duties */
    bemf_int_p.grid_gain = 0.1f; /* the uniform commutation grid (off in "bemf"), so the fuzzer reaches its code */
    bemf_int_p.brake_tau = 2e-3f; /* and the braking timeout (9) */
    bemf_int_p.brake_acc = 500.0f;
    return bc_bemf_init(&bemf_int_p, &bemf_int_s);
}
STEP_FN bemf_int_step(const bc_ctrl_in *in, bc_ctrl_out *out) { bc_bemf_step(&bemf_int_p, &bemf_int_s, in, out); }

#ifdef BC_FUZZ_CANARY
/* A deliberately wrong controller (built only by the test that proves the fuzz checks can fail): on a NaN bus it
 * emits a duty above 1 instead of the safe state. */
STEP_FN canary_step(const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_sixv_step(&sixv_p, &sixv_s, in, out);
    if (isnan(in->v_dc)) out->leg[0].duty = 2.0f;
}
#endif

const bc_fw_target bc_fw_targets[] = {
#ifdef BC_FUZZ_CANARY
    {"canary", BC_USES_HALL, sixv_init, canary_step, 48.0f, 50.0f, 0.5f, 357.0f},
#endif
    {"sixv", BC_USES_HALL, sixv_init, sixv_step, 48.0f, 50.0f, 0.5f, 357.0f},
    {"sixstep", BC_USES_HALL | BC_USES_CURRENT | BC_USES_VDC, sixstep_init, sixstep_step, 48.0f, 50.0f, 50.0f, 357.0f},
    {"sixstep_timed", BC_USES_HALL | BC_USES_CURRENT | BC_USES_VDC, sixstep_timed_init, sixstep_timed_step, 48.0f,
     50.0f, 50.0f, 357.0f},
    {"sine", BC_USES_HALL | BC_USES_CURRENT | BC_USES_VDC, sine_init, sine_step, 48.0f, 57.7f, 33.7f, 357.0f},
    {"sine_obs", BC_USES_CURRENT | BC_USES_VDC, sine_obs_init, sine_obs_step, 48.0f, 57.7f, 33.7f, 357.0f},
    {"commission", BC_USES_CURRENT | BC_USES_VDC, commission_init, commission_step, 48.0f, 57.7f, 0.0f, 357.0f},
    {"lu", BC_USES_HALL | BC_USES_CURRENT | BC_USES_VDC, lu_init, lu_step, 300.0f, 15.9f, 12.7f, 1000.0f},
    {"hall", BC_IS_BLOCK, hall_init, hall_step, 48.0f, 50.0f, 0.0f, 357.0f},
    {"hall_pll", BC_IS_BLOCK, hall_pll_init, hall_pll_step, 48.0f, 50.0f, 0.0f, 357.0f},
    {"hallcal", BC_USES_HALL | BC_USES_CURRENT | BC_USES_VDC, hallcal_init, hallcal_step, 48.0f, 50.0f, 0.0f, 357.0f},
    {"hallcal_speed", BC_USES_HALL, hallcal_speed_init, hallcal_speed_step, 48.0f, 50.0f, 0.0f, 357.0f},
    {"pi", BC_IS_BLOCK, pi_init, pi_step, 48.0f, 50.0f, 10.0f, 357.0f},
    {"fluxobs", BC_IS_BLOCK, fluxobs_init, fluxobs_step, 48.0f, 50.0f, 10.0f, 357.0f},
    {"redobs", BC_IS_BLOCK, redobs_init, redobs_step, 48.0f, 50.0f, 10.0f, 357.0f},
    {"bemf", BC_USES_CURRENT | BC_USES_VDC, bemf_init, bemf_step, 48.0f, 50.0f, 0.5f, 357.0f},
    {"bemf_int", BC_USES_CURRENT | BC_USES_VDC, bemf_int_init, bemf_int_step, 48.0f, 50.0f, 0.5f, 357.0f},
};
const int bc_fw_n_targets = (int)(sizeof bc_fw_targets / sizeof bc_fw_targets[0]);

/*
 * harness.c - bare-metal harness for the controllers: the image an MCU would run, minus the peripherals.
 * Built for a Cortex-M4F by benchmarks/firmware.py with exactly one BC_FW_<NAME> defined (a "harness" line of
 * targets.txt, or BC_FW_NONE for the baseline), so each controller's flash and RAM cost is the difference to the
 * baseline image.
 * Measurements come from volatile locations (as if from ADC and timer registers); the leg commands go to volatile
 * locations (as if to the timer's compare registers).
 */
#include <stdint.h>

#include "bldc/bc_types.h"

volatile bc_ctrl_in bc_fw_in;    /* written by "interrupts" */
volatile bc_ctrl_out bc_fw_out;  /* read by "the PWM timer" */

#if defined(BC_FW_TABLE)
#include "bldc/bc_openloop.h"
static bc_leg_cmd cmds[3];
static const bc_table_params P = {cmds, 1};
static bc_table_state S;
#define INIT() bc_table_init(&P, &S)
#define STEP(in, out) bc_table_step(&P, &S, in, out)
#elif defined(BC_FW_SIXV)
#include "bldc/bc_openloop.h"
static const bc_sixv_params P = {BC_SIXV_HIGH};
static bc_sixv_state S;
#define INIT() bc_sixv_init(&P, &S)
#define STEP(in, out) bc_sixv_step(&P, &S, in, out)
#elif defined(BC_FW_HALL)
#include "bldc/bc_hall.h"
static const bc_hall_params P = {10e6f, 5.0f, 0.0f, BC_HALL_INTERP, 1.0f, {0, {0}, {0}}};
static bc_hall_state S;
static bc_hall_out H;
#define INIT() bc_hall_init(&P, &S)
#define STEP(in, out) (bc_hall_step(&P, &S, in, &H), (out)->diag[0] = H.theta)
#elif defined(BC_FW_HALL_PLL)
#include "bldc/bc_hall.h"
#include "params.h"
static const bc_hall_params P = HALL_PLL_PARAMS;
static bc_hall_state S;
static bc_hall_out H;
#define INIT() bc_hall_init(&P, &S)
#define STEP(in, out) (bc_hall_step(&P, &S, in, &H), (out)->diag[0] = H.theta)
#elif defined(BC_FW_HALLCAL)
#include "bldc/bc_hallcal.h"
#include "params.h"
static const bc_hallcal_params P = HTM_HALLCAL_OL_PARAMS;
static bc_hallcal_state S;
#define INIT() bc_hallcal_init(&P, &S)
#define STEP(in, out) bc_hallcal_step(&P, &S, in, out)
#elif defined(BC_FW_PI)
#include "bldc/bc_pi.h"
static const bc_pi_params P = {0.47f, 314.0f, 35.7e-6f, -48.0f, 48.0f};
static bc_pi_state S;
#define INIT() bc_pi_init(&P, &S)
#define STEP(in, out) ((out)->diag[0] = bc_pi_step(&P, &S, (in)->ref - (in)->i_abc[0], 0.0f))
#elif defined(BC_FW_SIXSTEP)
#include "params.h"
static const bc_sixstep_params P = HTM_SIXSTEP_PARAMS(0);
static bc_sixstep_state S;
#define INIT() bc_sixstep_init(&P, &S)
#define STEP(in, out) bc_sixstep_step(&P, &S, in, out)
#elif defined(BC_FW_SINE)
#include "params.h"
static const bc_sine_params P = HTM_SINE_PARAMS;
static bc_sine_state S;
#define INIT() bc_sine_init(&P, &S)
#define STEP(in, out) bc_sine_step(&P, &S, in, out)
#elif defined(BC_FW_SINE_OBS)
#include "params.h"
static bc_sine_params P = HTM_SINE_PARAMS;
static bc_sine_state S;
#define INIT() (htm_sine_observer(&P), bc_sine_init(&P, &S))
#define STEP(in, out) bc_sine_step(&P, &S, in, out)
#elif defined(BC_FW_COMMISSION)
#include "params.h"
static const bc_commission_params P = HTM_COMMISSION_PARAMS;
static bc_commission_state S;
#define INIT() bc_commission_init(&P, &S)
#define STEP(in, out) bc_commission_step(&P, &S, in, out)
#elif defined(BC_FW_LU)
#include "params.h"
static const bc_lu_params P = LU4KW_LU_PARAMS;
static bc_lu_state S;
#define INIT() bc_lu_init(&P, &S)
#define STEP(in, out) bc_lu_step(&P, &S, in, out)
#elif defined(BC_FW_FLUXOBS)
#include "bldc/bc_fluxobs.h"
#include "params.h"
static const bc_fluxobs_params P = HTM_FLUXOBS_PARAMS;
static bc_fluxobs_state S;
static bc_obs_in OI;
static bc_obs_out OO;
#define INIT() bc_fluxobs_init(&P, &S)
#define STEP(in, out)                                                                                             \
    (OI.u = (bc_ab){(in)->ref, (in)->omega_ref}, OI.i = (bc_ab){(in)->i_abc[0], (in)->i_abc[1]},                 \
     bc_fluxobs_step(&P, &S, &OI, &OO), (out)->diag[0] = OO.theta)
#elif defined(BC_FW_REDOBS)
#include "bldc/bc_redobs.h"
#include "params.h"
static const bc_redobs_params P = HTM_REDOBS_PARAMS;
static bc_redobs_state S;
static bc_obs_in OI;
static bc_obs_out OO;
#define INIT() bc_redobs_init(&P, &S)
#define STEP(in, out)                                                                                             \
    (OI.u = (bc_ab){(in)->ref, (in)->omega_ref}, OI.i = (bc_ab){(in)->i_abc[0], (in)->i_abc[1]},                 \
     bc_redobs_step(&P, &S, &OI, &OO), (out)->diag[0] = OO.theta)
#elif defined(BC_FW_BEMF)
#include "params.h"
static const bc_bemf_params P = HTM_BEMF_PARAMS;
static bc_bemf_state S;
#define INIT() bc_bemf_init(&P, &S)
#define STEP(in, out) bc_bemf_step(&P, &S, in, out)
#elif defined(BC_FW_NONE)
#define INIT() 0
#define STEP(in, out) ((out)->diag[0] = (in)->ref)
#else
#error "define BC_FW_NONE or the BC_FW_<NAME> of a target listed in targets.txt"
#endif

int main(void)
{
    int rc = INIT();
    for (;;) {
        bc_ctrl_in in = bc_fw_in;
        bc_ctrl_out out;
        out.flags = (uint32_t)rc;
        STEP(&in, &out);
        bc_fw_out = out;
    }
}

/* bc_bind.c - layout tables, trace fields and controller registry for the host binding (bc_bind.h). */
#include "bldc/bc_bind.h"

#include <stddef.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_derate.h"
#include "bldc/bc_rest.h"
#include "bldc/bc_emf.h"
#include "bldc/bc_plant.h"
#include "bldc/bc_sensors.h"
#include "bldc/bc_sim.h"
#include "bldc/bc_user.h"
#include "bldc/bc_userguard.h"

#define F BC_BIND_FIELD

static const bc_field_desc FIELDS[] = {
    F(bc_leg_cmd, mode, "i4"),
    F(bc_leg_cmd, duty, "f4"),

    F(bc_emf_shape, kind, "i4"),
    F(bc_emf_shape, n, "i4"),
    F(bc_emf_shape, x, "ptr"),
    F(bc_emf_shape, y, "ptr"),

    F(bc_fault, kind, "i4"),
    F(bc_fault, phase, "i4"),
    F(bc_fault, t_on, "f8"),
    F(bc_fault, t_off, "f8"),
    F(bc_fault, value, "f8"),

    F(bc_plant_params, p, "i4"),
    F(bc_plant_params, R, "f8"),
    F(bc_plant_params, L, "f8"),
    F(bc_plant_params, emf, "bc_emf_shape"),
    F(bc_plant_params, n_cog, "i4"),
    F(bc_plant_params, cog_order, "ptr"),
    F(bc_plant_params, cog_amp, "ptr"),
    F(bc_plant_params, cog_phase, "ptr"),
    F(bc_plant_params, k_fe_e, "f8"),
    F(bc_plant_params, k_fe_h, "f8"),
    F(bc_plant_params, k_fe_x, "f8"),
    F(bc_plant_params, f_pwm, "f8"),
    F(bc_plant_params, t_dead, "f8"),
    F(bc_plant_params, R_on, "f8"),
    F(bc_plant_params, V_f, "f8"),
    F(bc_plant_params, r_d, "f8"),
    F(bc_plant_params, R_src, "f8"),
    F(bc_plant_params, i_trip, "f8"),
    F(bc_plant_params, E_on, "f8"),
    F(bc_plant_params, E_off, "f8"),
    F(bc_plant_params, E_rr, "f8"),
    F(bc_plant_params, V_test, "f8"),
    F(bc_plant_params, I_test, "f8"),
    F(bc_plant_params, inverter, "i4"),
    F(bc_plant_params, mech, "i4"),
    F(bc_plant_params, J, "f8"),
    F(bc_plant_params, B, "f8"),
    F(bc_plant_params, tau_c, "f8"),
    F(bc_plant_params, k_q, "f8"),
    F(bc_plant_params, hall_error, "f8"),
    F(bc_plant_params, hall_hyst, "f8"),
    F(bc_plant_params, hall_delay, "f8"),
    F(bc_plant_params, hall_tau, "f8"),
    F(bc_plant_params, h_max, "f8"),
    F(bc_plant_params, fault, "bc_fault"),

    F(bc_sensor_params, i_mask, "u4"),
    F(bc_sensor_params, i_gain, "f8"),
    F(bc_sensor_params, i_offset, "f8"),
    F(bc_sensor_params, i_noise, "f8"),
    F(bc_sensor_params, i_lsb, "f8"),
    F(bc_sensor_params, i_fs, "f8"),
    F(bc_sensor_params, v_gain, "f8"),
    F(bc_sensor_params, v_offset, "f8"),
    F(bc_sensor_params, v_noise, "f8"),
    F(bc_sensor_params, v_lsb, "f8"),
    F(bc_sensor_params, f_tick, "f8"),
    F(bc_sensor_params, seed, "u8"),
    F(bc_sensor_params, fault, "bc_fault"),

    F(bc_sense_params, on, "i4"),
    F(bc_sense_params, tau, "f8"),
    F(bc_sense_params, ref, "i4"),
    F(bc_sense_params, offset, "f8"),
    F(bc_sense_params, hyst, "f8"),
    F(bc_sense_params, delay, "f8"),
    F(bc_sense_params, adc_at, "f8"),
    F(bc_sense_params, adc_lsb, "f8"),
    F(bc_sense_params, adc_max, "f8"),
    F(bc_sense_params, adc_noise, "f8"),
    F(bc_sense_params, f_pwm, "f8"),
    F(bc_sense_params, f_tick, "f8"),
    F(bc_sense_params, seed, "u8"),

    F(bc_sense_state, vf, "f8"),
    F(bc_sense_state, out, "u4"),
    F(bc_sense_state, seen, "u4"),
    F(bc_sense_state, count, "u4"),
    F(bc_sense_state, n_edges, "u4"),
    F(bc_sense_state, overrun, "i4"),
    F(bc_sense_state, n_adc, "u4"),

    F(bc_ctrl, step, "ptr"),
    F(bc_ctrl, params, "ptr"),
    F(bc_ctrl, state, "ptr"),

    F(bc_sim_config, plant, "ptr"),
    F(bc_sim_config, sensors, "ptr"),
    F(bc_sim_config, sense, "ptr"),
    F(bc_sim_config, ctrl, "bc_ctrl"),
    F(bc_sim_config, delay, "i4"),
    F(bc_sim_config, trace_every, "i4"),
    F(bc_sim_config, trace_sub, "i4"),
    F(bc_sim_config, metric_t0, "f8"),
    F(bc_sim_config, metric_t1, "f8"),

    F(bc_sim_inputs, ref, "ptr"),
    F(bc_sim_inputs, omega_ref, "ptr"),
    F(bc_sim_inputs, omega, "ptr"),
    F(bc_sim_inputs, tau_load, "ptr"),
    F(bc_sim_inputs, v_src, "ptr"),
    F(bc_sim_inputs, ref_c, "f8"),
    F(bc_sim_inputs, omega_ref_c, "f8"),
    F(bc_sim_inputs, omega_c, "f8"),
    F(bc_sim_inputs, tau_load_c, "f8"),
    F(bc_sim_inputs, v_src_c, "f8"),

    F(bc_sim_metrics, t0, "f8"),
    F(bc_sim_metrics, t1, "f8"),
    F(bc_sim_metrics, E, "f8"),
    F(bc_sim_metrics, w_l0, "f8"),
    F(bc_sim_metrics, w_l1, "f8"),
    F(bc_sim_metrics, w_kin0, "f8"),
    F(bc_sim_metrics, w_kin1, "f8"),
    F(bc_sim_metrics, th0, "f8"),
    F(bc_sim_metrics, th1, "f8"),
    F(bc_sim_metrics, t_zero_i0, "f8"),
    F(bc_sim_metrics, t_zero_i1, "f8"),
    F(bc_sim_metrics, n_zero_i0, "i8"),
    F(bc_sim_metrics, n_zero_i1, "i8"),
    F(bc_sim_metrics, tau_min, "f8"),
    F(bc_sim_metrics, tau_max, "f8"),
    F(bc_sim_metrics, tau_ma_min, "f8"),
    F(bc_sim_metrics, tau_ma_max, "f8"),
    F(bc_sim_metrics, tau_ma_grid_min, "f8"),
    F(bc_sim_metrics, tau_ma_grid_max, "f8"),
    F(bc_sim_metrics, tau_s_min, "f8"),
    F(bc_sim_metrics, tau_s_max, "f8"),
    F(bc_sim_metrics, i_peak, "f8"),
    F(bc_sim_metrics, n_samples, "i4"),
    F(bc_sim_metrics, flag_n, "i4"),
    F(bc_sim_metrics, flag_t0, "f8"),
    F(bc_sim_metrics, flag_t1, "f8"),
    F(bc_sim_metrics, n_ma, "i4"),
    F(bc_sim_metrics, n_ma_grid, "i4"),
    F(bc_sim_metrics, ma_lost, "i4"),
    F(bc_sim_metrics, state, "i4"),

    /* the part of the plant state the host reads */
    F(bc_plant_state, t, "f8"),
    F(bc_plant_state, i, "f8"),
    F(bc_plant_state, theta, "f8"),
    F(bc_plant_state, turns, "u4"),
    F(bc_plant_state, omega, "f8"),
    F(bc_plant_state, stuck, "i4"),
    F(bc_plant_state, hall_out, "i4"),
    F(bc_plant_state, n_edges, "u4"),
    F(bc_plant_state, acc, "f8"),
    F(bc_plant_state, flags, "u4"),
    F(bc_plant_state, n_steps, "i8"),
    F(bc_plant_state, n_events, "i8"),
    F(bc_plant_state, e_fault, "f8"),
    F(bc_plant_state, tripped, "i4"),
    F(bc_plant_state, t_trip, "f8"),

    F(bc_sim_state, plant, "bc_plant_state"),
    F(bc_sim_state, sense, "bc_sense_state"),
    F(bc_sim_state, k, "i8"),
    F(bc_sim_state, flags_seen, "u4"),
    F(bc_sim_state, flag_run_n, "i4"),
    F(bc_sim_state, flag_run_t0, "f8"),
    F(bc_sim_state, flag_run_t1, "f8"),
    F(bc_sim_state, m, "bc_sim_metrics"),
    F(bc_sim_state, row_peak, "f8"),
    F(bc_sim_state, row_nonfinite, "i4"),

    F(bc_ctrl_in, i_abc, "f4"),
    F(bc_ctrl_in, i_mask, "u4"),
    F(bc_ctrl_in, v_dc, "f4"),
    F(bc_ctrl_in, hall, "u4"),
    F(bc_ctrl_in, n_edges, "u4"),
    F(bc_ctrl_in, tick_edge, "u4"),
    F(bc_ctrl_in, tick_now, "u4"),
    F(bc_ctrl_in, theta_enc, "f4"),
    F(bc_ctrl_in, omega_enc, "f4"),
    F(bc_ctrl_in, ref, "f4"),
    F(bc_ctrl_in, omega_ref, "f4"),
    F(bc_ctrl_in, fault_pin, "u4"),
    F(bc_ctrl_in, zc_state, "u4"),
    F(bc_ctrl_in, zc_count, "u4"),
    F(bc_ctrl_in, zc_tick, "u4"),
    F(bc_ctrl_in, v_term, "f4"),
    F(bc_ctrl_in, v_neutral, "f4"),
    F(bc_ctrl_in, n_adc, "u4"),
    F(bc_ctrl_in, tick_adc, "u4"),

    F(bc_ctrl_in, temp, "f4"),
    F(bc_ctrl_in, i_fs, "f4"),

    F(bc_ctrl_out, leg, "bc_leg_cmd"),
    F(bc_ctrl_out, diag, "f4"),
    F(bc_ctrl_out, flags, "u4"),
    F(bc_ctrl_out, has_at, "u4"),
    F(bc_ctrl_out, t_at, "f4"),
    F(bc_ctrl_out, leg_at, "bc_leg_cmd"),
    F(bc_ctrl_out, i_hold, "f4"),
    F(bc_ctrl_out, i_hold_at, "f4"),

    /* a user's controller (bc_user.h) and the guard it runs through (bc_userguard.h) */
    F(bc_user_desc, name, "ptr"),
    F(bc_user_desc, fields, "ptr"),
    F(bc_user_desc, n_fields, "i4"),
    F(bc_user_desc, structs, "ptr"),
    F(bc_user_desc, n_structs, "i4"),
    F(bc_user_desc, diag, "ptr"),
    F(bc_user_desc, consts, "ptr"),
    F(bc_user_desc, n_consts, "i4"),
    F(bc_user_desc, defaults, "ptr"),
    F(bc_user_desc, ref, "ptr"),
    F(bc_user_desc, bemf_sensing, "i4"),

    F(bc_user_entry, abi, "u4"),
    F(bc_user_entry, size_in, "u4"),
    F(bc_user_entry, size_out, "u4"),
    F(bc_user_entry, diag_n, "u4"),
    F(bc_user_entry, built_by, "ptr"),
    F(bc_user_entry, desc, "ptr"),
    F(bc_user_entry, params, "ptr"),
    F(bc_user_entry, state, "ptr"),
    F(bc_user_entry, params_size, "u4"),
    F(bc_user_entry, state_size, "u4"),
    F(bc_user_entry, init, "ptr"),
    F(bc_user_entry, step, "ptr"),

    F(bc_user_watch, k, "i8"),
    F(bc_user_watch, entered, "u8"),
    F(bc_user_watch, done, "u8"),
    F(bc_user_watch, busy, "i4"),
    F(bc_user_watch, fault, "i4"),
    F(bc_user_watch, where, "i4"),
    F(bc_user_watch, index, "i4"),
    F(bc_user_watch, value, "f8"),
    F(bc_user_watch, signo, "i4"),
    F(bc_user_watch, pad, "i4"),
    F(bc_user_watch, addr, "u8"),
    F(bc_user_watch, at, "u8"),
    F(bc_user_watch, size, "u8"),

    F(bc_user_guard, init, "ptr"),
    F(bc_user_guard, step, "ptr"),
    F(bc_user_guard, params, "ptr"),
    F(bc_user_guard, state, "ptr"),
    F(bc_user_guard, in, "ptr"),
    F(bc_user_guard, out, "ptr"),
    F(bc_user_guard, watch, "ptr"),
    F(bc_user_guard, stop, "i4"),
    F(bc_user_guard, pad, "i4"),
    F(bc_user_guard, k, "i8"),
    F(bc_user_guard, jump, "ptr"),

    F(bc_derate_params, enabled, "i4"),
    F(bc_derate_params, T_start, "f4"),
    F(bc_derate_params, T_end, "f4"),
    F(bc_derate_params, f_min, "f4"),
    F(bc_derate_params, f_fault, "f4"),
    F(bc_derate_params, T_lo, "f4"),
    F(bc_derate_params, T_hi, "f4"),
    F(bc_derate_params, tau, "f4"),
    F(bc_derate_params, ts, "f4"),

    F(bc_rest_params, i_inj, "f4"),
    F(bc_rest_params, n_half, "i4"),
    F(bc_rest_params, n_skip, "i4"),
    F(bc_rest_params, r_lo, "f4"),
    F(bc_rest_params, r_hi, "f4"),
    F(bc_rest_params, a, "f4"),
    F(bc_rest_params, r_ref, "f4"),
    F(bc_rest_params, T_ref, "f4"),
    F(bc_rest_state, k, "i4"),
    F(bc_rest_state, bad, "i4"),
    F(bc_rest_state, v0, "f4"),
    F(bc_rest_state, sv, "f4"),
    F(bc_rest_state, si, "f4"),
    F(bc_rest_state, n, "i4"),
    F(bc_rest_state, r, "f4"),
    F(bc_rest_state, r_last, "f4"),
    F(bc_rest_state, count, "u4"),
    F(bc_rest_state, rejected, "u4"),
};

#define S BC_BIND_STRUCT

static const bc_struct_desc STRUCTS[] = {
    S(bc_fault),        S(bc_leg_cmd),      S(bc_emf_shape),    S(bc_plant_params), S(bc_plant_state), S(bc_sensor_params),
    S(bc_sensor_state), S(bc_ctrl),         S(bc_sim_config),   S(bc_sim_inputs),  S(bc_sim_metrics),
    S(bc_sim_state),    S(bc_trace_row),    S(bc_ctrl_in),      S(bc_ctrl_out),     S(bc_sense_params), S(bc_sense_state),
    S(bc_user_desc),    S(bc_user_entry),   S(bc_user_watch),   S(bc_user_guard),
    S(bc_derate_params), S(bc_derate_state), S(bc_rest_params), S(bc_rest_state),
};

#define K BC_BIND_CONST

/* Constants shared by every block (bc_types.h, the chopping patterns of bc_commutation.h) and the plant's (bc_emf.h,
 * bc_plant.h). */
static const bc_const_desc CONSTS[] = {
    K("flag", BC_FLAG_SAFE),         K("flag", BC_FLAG_HALL_INVALID),     K("flag", BC_FLAG_OVERCURRENT),
    K("flag", BC_FLAG_BAD_INPUT),    K("flag", BC_FLAG_SATURATED),        K("flag", BC_FLAG_DESYNC),
    K("flag", BC_FLAG_ZC_TIMEOUT),   K("flag", BC_FLAG_ZC_HIDDEN),        K("flag", BC_FLAG_ZC_JUMP),
    K("flag", BC_FLAG_STALL),        K("flag", BC_FLAG_START_FAIL),       K("flag", BC_FLAG_OPEN_LOOP),
    K("flag", BC_FLAG_COMM_LATE),    K("flag", BC_FLAG_LOCK_LOST),
    K("chop", BC_CHOP_BIPOLAR),      K("chop", BC_CHOP_HIGH),             K("chop", BC_CHOP_PWMPWM),
    K("chop", BC_CHOP_SYNC),
    K("leg", BC_LEG_OFF),            K("leg", BC_LEG_PWM),                K("leg", BC_LEG_HIGH),
    K("leg", BC_LEG_LOW),            K("leg", BC_LEG_HOLD),
    K("err", BC_OK),                 K("err", BC_ERR_PARAM),              K("err", BC_ERR_SIZE),
    K("err", BC_ERR_INPUT),
    K("emf", BC_EMF_TABLE),          K("emf", BC_EMF_FOURIER),
    K("mech", BC_MECH_IMPOSED),      K("mech", BC_MECH_DYNAMIC),
    K("inverter", BC_INV_SWITCHING), K("inverter", BC_INV_AVERAGE),
    K("fault", BC_FAULT_NONE),       K("fault", BC_FAULT_PHASE_OPEN),     K("fault", BC_FAULT_HALL_STUCK),
    K("fault", BC_FAULT_HALL_GLITCH), K("fault", BC_FAULT_CURRENT_OFFSET), K("fault", BC_FAULT_CURRENT_LOSS),
    K("sense_ref", BC_SENSE_REF_STAR), K("sense_ref", BC_SENSE_REF_HALF),
    K("plant_flag", BC_PLANT_BAD_DUTY), K("plant_flag", BC_PLANT_CHATTER), K("plant_flag", BC_PLANT_HALL_OVERRUN),
    K("user", BC_USER_ABI),          K("user", BC_USER_STOPPED),
    K("user_fault", BC_USER_FAULT_NONE), K("user_fault", BC_USER_FAULT_OUTPUT), K("user_fault", BC_USER_FAULT_INPUT),
    K("user_fault", BC_USER_FAULT_STOP), K("user_fault", BC_USER_FAULT_SIGNAL),
    K("user_at", BC_USER_AT_MODE),   K("user_at", BC_USER_AT_DUTY),       K("user_at", BC_USER_AT_HAS_AT),
    K("user_at", BC_USER_AT_T_AT),   K("user_at", BC_USER_AT_MODE_AT),    K("user_at", BC_USER_AT_DUTY_AT),
    K("user_at", BC_USER_AT_DIAG),   K("user_at", BC_USER_AT_HOLD),
};

/* Controller providers (host/src/bc_bind_<name>.c): one line each. */
extern const bc_bind_provider bc_bind_openloop_table;
extern const bc_bind_provider bc_bind_openloop_sixv;
extern const bc_bind_provider bc_bind_sixstep;
extern const bc_bind_provider bc_bind_sine;
extern const bc_bind_provider bc_bind_lu;
extern const bc_bind_provider bc_bind_hallcal;
extern const bc_bind_provider bc_bind_bemf;
extern const bc_bind_provider bc_bind_commission;

static const bc_bind_provider *const PROVIDERS[] = {
    &bc_bind_openloop_table,
    &bc_bind_openloop_sixv,
    &bc_bind_sixstep,
    &bc_bind_sine,
    &bc_bind_lu,
    &bc_bind_hallcal,
    &bc_bind_bemf,
    &bc_bind_commission,
};

#define N_PROVIDERS ((int32_t)(sizeof PROVIDERS / sizeof PROVIDERS[0]))
#define N_FIELDS ((int32_t)(sizeof FIELDS / sizeof FIELDS[0]))
#define N_STRUCTS ((int32_t)(sizeof STRUCTS / sizeof STRUCTS[0]))
#define N_CONSTS ((int32_t)(sizeof CONSTS / sizeof CONSTS[0]))

int32_t bc_layout_count(void)
{
    int32_t n = N_FIELDS;
    for (int32_t j = 0; j < N_PROVIDERS; ++j) n += PROVIDERS[j]->n_fields;
    return n;
}

const bc_field_desc *bc_layout_get(int32_t j)
{
    if (j < 0) return 0;
    if (j < N_FIELDS) return &FIELDS[j];
    j -= N_FIELDS;
    for (int32_t q = 0; q < N_PROVIDERS; ++q) {
        if (j < PROVIDERS[q]->n_fields) return &PROVIDERS[q]->fields[j];
        j -= PROVIDERS[q]->n_fields;
    }
    return 0;
}

int32_t bc_struct_count(void)
{
    int32_t n = N_STRUCTS;
    for (int32_t j = 0; j < N_PROVIDERS; ++j) n += PROVIDERS[j]->n_structs;
    return n;
}

const bc_struct_desc *bc_struct_get(int32_t j)
{
    if (j < 0) return 0;
    if (j < N_STRUCTS) return &STRUCTS[j];
    j -= N_STRUCTS;
    for (int32_t q = 0; q < N_PROVIDERS; ++q) {
        if (j < PROVIDERS[q]->n_structs) return &PROVIDERS[q]->structs[j];
        j -= PROVIDERS[q]->n_structs;
    }
    return 0;
}

int32_t bc_const_count(void)
{
    int32_t n = N_CONSTS;
    for (int32_t j = 0; j < N_PROVIDERS; ++j) n += PROVIDERS[j]->n_consts;
    return n;
}

const bc_const_desc *bc_const_get(int32_t j)
{
    if (j < 0) return 0;
    if (j < N_CONSTS) return &CONSTS[j];
    j -= N_CONSTS;
    for (int32_t q = 0; q < N_PROVIDERS; ++q) {
        if (j < PROVIDERS[q]->n_consts) return &PROVIDERS[q]->consts[j];
        j -= PROVIDERS[q]->n_consts;
    }
    return 0;
}

#define TRACE_NAME(name, unit, doc) #name,
#define TRACE_UNIT(name, unit, doc) unit,
#define TRACE_DOC(name, unit, doc) doc,
static const char *const TRACE_NAMES[] = {BC_TRACE_FIELDS(TRACE_NAME)};
static const char *const TRACE_UNITS[] = {BC_TRACE_FIELDS(TRACE_UNIT)};
static const char *const TRACE_DOCS[] = {BC_TRACE_FIELDS(TRACE_DOC)};

int32_t bc_trace_count(void) { return (int32_t)(sizeof TRACE_NAMES / sizeof TRACE_NAMES[0]); }
const char *bc_trace_name(int32_t j) { return (j >= 0 && j < bc_trace_count()) ? TRACE_NAMES[j] : 0; }
const char *bc_trace_unit(int32_t j) { return (j >= 0 && j < bc_trace_count()) ? TRACE_UNITS[j] : 0; }
const char *bc_trace_doc(int32_t j) { return (j >= 0 && j < bc_trace_count()) ? TRACE_DOCS[j] : 0; }

#define ACC_NAME(NAME, name, unit, doc) #name,
static const char *const ACC_NAMES[] = {BC_ACC_FIELDS(ACC_NAME)};

int32_t bc_acc_count(void) { return BC_ACC_N; }
const char *bc_acc_name(int32_t j) { return (j >= 0 && j < BC_ACC_N) ? ACC_NAMES[j] : 0; }

int32_t bc_ctrl_count(void) { return N_PROVIDERS; }
const bc_ctrl_info *bc_ctrl_get(int32_t j) { return (j >= 0 && j < N_PROVIDERS) ? PROVIDERS[j]->info : 0; }

const char *bc_version(void) { return "0.1.0"; }

/*
 * bc_sim.h - the closed-loop runner: plant + sensors + one controller, sample by sample.
 *
 * One sample k (t_k = k T/2, carrier valley for even k, peak for odd k):
 *
 *   1. hold the per-sample inputs (imposed speed, load torque, DC source voltage) over [t_k, t_k+1]
 *   2. measure the plant at t_k (bc_sensor_measure; the back-EMF sensing's comparator edges and ADC conversions up
 *      to t_k, bc_sense_fill), add the references, call the controller
 *   3. apply a command for [t_k, t_k+1]: the controller's previous output (delay = 1, as on a DSP that loads the
 *      PWM shadow registers at the next carrier extreme) or this one (delay = 0, ideal), and the leg change it
 *      schedules inside the half period, if any (bc_ctrl_out.has_at: a commutation timer; bc_plant_schedule)
 *   4. integrate to t_k+1, landing on trace points and metric-window bounds
 *
 * Output: an optional trace (one row per `trace_every` samples, or `trace_sub` rows per sample), each row
 * holding the instantaneous state at its start and means/extremes over its window (the powers are the row's
 * integrals of bc_plant.h's acc[] over its length: p_swloss is the gate-edge energies E_on, E_off, E_rr booked
 * inside the row divided by its length, included in p_inv; per row p_src + p_swloss = p_cu + p_inv + p_emf +
 * dW_L/dt up to the integration error, and sum(p dt) over rows equals the metrics' integrals); and metrics over one
 * window [metric_t0, metric_t1] given in time (not samples), so that a caller can measure exactly whole
 * electrical periods. State is caller-owned: a long run can be done in chunks, the result is the same (bldclab's
 * simulate calls bc_sim_run on pieces of its run, so memory does not grow with the duration). The state also keeps
 * the OR of every controller flag raised (flags_seen), for each flag bit the number of samples that raised it and
 * the first and last of them (over the run, and inside the metric window), and the unwrapped electrical angle travelled (th_run, from
 * which the window's mean speed is (th1 - th0) / (p (t1 - t0)) without a trace).
 */
#ifndef BC_SIM_H
#define BC_SIM_H

#include <stdint.h>

#include "bldc/bc_plant.h"
#include "bldc/bc_sense.h"
#include "bldc/bc_sensors.h"
#include "bldc/bc_types.h"

/* Trace fields, listed once: X(name, unit, description). Every field is a double. */
#define BC_TRACE_FIELDS(X)                                                                          \
    X(t, "s", "start of the row's window")                                                          \
    X(theta_e, "rad", "electrical angle")                                                           \
    X(omega_m, "rad/s", "mechanical speed")                                                         \
    X(i_a, "A", "phase current a")                                                                  \
    X(i_b, "A", "phase current b")                                                                  \
    X(i_c, "A", "phase current c")                                                                  \
    X(e_a, "V", "back-EMF a")                                                                       \
    X(e_b, "V", "back-EMF b")                                                                       \
    X(e_c, "V", "back-EMF c")                                                                       \
    X(tau_e, "N m", "electromagnetic torque (with cogging)")                                        \
    X(tau_shaft, "N m", "torque minus friction and iron drag: what a dynamometer holds")              \
    X(v_bus, "V", "DC bus at the inverter")                                                         \
    X(hall, "-", "Hall code seen by the controller")                                                \
    X(tau_mean, "N m", "mean torque over the window")                                               \
    X(tau_min, "N m", "smallest torque in the window")                                              \
    X(tau_max, "N m", "largest torque in the window")                                               \
    X(p_src, "W", "mean power from the DC source")                                                  \
    X(p_cu, "W", "mean copper loss")                                                                \
    X(p_inv, "W", "mean inverter loss (switches, diodes, source resistance, p_swloss)")             \
    X(p_swloss, "W", "E_on, E_off, E_rr booked at the row's gate edges / row length (mean power)")  \
    X(p_emf, "W", "mean electromagnetic power sum e i")                                             \
    X(v_a, "V", "mean terminal voltage a (from the negative rail)")                                 \
    X(v_b, "V", "mean terminal voltage b")                                                          \
    X(v_c, "V", "mean terminal voltage c")                                                          \
    X(v_n, "V", "mean star-point voltage")                                                          \
    X(i_dc, "A", "mean DC current")                                                                 \
    X(mode_a, "-", "leg a mode applied (0 off, 1 pwm, 2 high, 3 low, 4 hold)")                              \
    X(mode_b, "-", "leg b mode applied")                                                            \
    X(mode_c, "-", "leg c mode applied")                                                            \
    X(duty_a, "-", "leg a duty applied")                                                            \
    X(duty_b, "-", "leg b duty applied")                                                            \
    X(duty_c, "-", "leg c duty applied")                                                            \
    X(d0, "-", "controller diagnostic 0")                                                           \
    X(d1, "-", "controller diagnostic 1")                                                           \
    X(d2, "-", "controller diagnostic 2")                                                           \
    X(d3, "-", "controller diagnostic 3")                                                           \
    X(d4, "-", "controller diagnostic 4")                                                           \
    X(d5, "-", "controller diagnostic 5")                                                           \
    X(d6, "-", "controller diagnostic 6")                                                           \
    X(d7, "-", "controller diagnostic 7")                                                           \
    X(flags, "-", "controller flags")                                                               \
    X(hw_trip, "-", "1 once the inverter's hardware over-current trip has switched it off")          \
    X(t_at, "s", "instant of the commutation timer's leg change in the row (bc_ctrl_out.has_at); -1: none") \
    X(t_iz_a, "s", "instant phase a's current first ended in the row (its diode turned off); -1: none")   \
    X(t_iz_b, "s", "the same for phase b")                                                        \
    X(t_iz_c, "s", "the same for phase c")

typedef struct {
#define BC_TRACE_MEMBER(name, unit, doc) double name;
    BC_TRACE_FIELDS(BC_TRACE_MEMBER)
#undef BC_TRACE_MEMBER
} bc_trace_row;

/* Controller flag bits counted per sample (the BC_FLAG_* of bc_types.h and any a controller adds, up to bit 15). */
#define BC_SIM_NFLAG 16

/* Metrics over [t0, t1]. Three views of the torque's extremes (docs/plant.md, "Metrics"):
 *
 *   tau_min, tau_max        the instantaneous torque over every integration step and event: step ends, and the
 *                           turning points inside a step of the cubic Hermite interpolant of tau_e (bc_plant.h)
 *   tau_ma_min, tau_ma_max  the one-PWM-period moving average MA(t) = (A(t) - A(t - T)) / T, T = 1/f_pwm,
 *                           A = integral of tau_e (acc[BC_ACC_TAU]), for t in [t0 + T, t1], evaluated continuously:
 *                           at every step end t and at every history node shifted by T (A(t - T) and A(t + T)
 *                           from the cubic Hermite of A through its node values and derivatives tau_e)
 *   tau_s_min, tau_s_max    the torque at the controller samples (carrier valleys and peaks)
 *
 * and the former sample-grid moving average (the mean of two consecutive half periods, at the samples only) as
 * tau_ma_grid_min/max. The history of step ends is a ring of BC_SIM_HIST nodes; when one PWM period holds more steps
 * than that, the evaluations whose past fell out of it are skipped and counted in ma_lost. */
typedef struct {
    double t0, t1;           /* window, s */
    double E[BC_ACC_N];      /* integrals of bc_plant.h's acc[] over the window */
    double w_l0, w_l1;       /* magnetic energy at t0, t1, J */
    double w_kin0, w_kin1;   /* J omega^2 / 2 at t0, t1, J (dynamic mechanics) */
    double th0, th1;         /* electrical angle travelled since the start (unwrapped) at t0, t1, rad */
    double t_zero_i0, t_zero_i1; /* the plant's t_zero_i (time with every phase current zero) at t0, t1, s */
    int64_t n_zero_i0, n_zero_i1; /* the plant's n_zero_i (intervals of it) at t0, t1 */
    double tau_min, tau_max; /* extremes of the instantaneous torque, N m */
    double tau_ma_min;       /* extremes of the continuous one-PWM-period moving average of the torque, N m */
    double tau_ma_max;
    double tau_ma_grid_min;     /* extremes of the moving average on the sample grid (two half-period means), N m */
    double tau_ma_grid_max;
    double tau_s_min;        /* extremes of the torque at the samples (carrier valleys and peaks), N m: there the */
    double tau_s_max;        /* currents cross their PWM-period average, so this is the ripple without PWM */
    double i_peak[3];        /* largest |i_x|, A */
    int32_t n_samples;       /* controller samples inside the window (t_k in [t0, t1)) */
    int32_t flag_n[BC_SIM_NFLAG];  /* ... at which the controller raised flag bit j (BC_FLAG_*: bit j = 1 << j) */
    double flag_t0[BC_SIM_NFLAG];  /* first and last such sample time, s (0 if none) */
    double flag_t1[BC_SIM_NFLAG];
    int32_t n_ma;            /* continuous moving-average values seen */
    int32_t n_ma_grid;       /* sample-grid moving-average values seen */
    int32_t ma_lost;         /* continuous moving-average evaluations skipped (history ring too short) */
    int32_t state;           /* 0 not started, 1 running, 2 done */
} bc_sim_metrics;

/* Step ends kept for the continuous moving average: more than the steps of one PWM period in any run bldclab
 * makes (gate and dead-time edges, events, h_max steps, trace sub-rows: typically 10 - 100). */
#define BC_SIM_HIST 1024

typedef struct {
    const bc_plant_params *plant;
    const bc_sensor_params *sensors;
    const bc_sense_params *sense; /* NULL or off: no back-EMF sensing (bc_ctrl_in's zc_*, v_term, ... stay 0) */
    bc_ctrl ctrl;
    int32_t delay;        /* 0 or 1 sample of computation delay */
    int32_t trace_every;  /* >= 1: samples per trace row */
    int32_t trace_sub;    /* >= 1: trace rows per sample (needs trace_every == 1) */
    double metric_t0;     /* metric window, s; none if metric_t1 <= metric_t0 */
    double metric_t1;
} bc_sim_config;

/* Per-sample inputs: arrays of the run's length, or NULL to use the constant. */
typedef struct {
    const double *ref;       /* controller reference (in.ref) */
    const double *omega_ref; /* speed reference, rad/s (in.omega_ref) */
    const double *omega;     /* imposed speed, rad/s (BC_MECH_IMPOSED) */
    const double *tau_load;  /* load torque, N m (BC_MECH_DYNAMIC) */
    const double *v_src;     /* DC source voltage, V */
    double ref_c, omega_ref_c, omega_c, tau_load_c, v_src_c;
} bc_sim_inputs;

typedef struct {
    bc_plant_state plant;
    bc_sensor_state sensors;
    bc_sense_state sense;      /* back-EMF sensing (bc_sim_config.sense) */
    const bc_sense_params *sense_p; /* cfg->sense while bc_sim_run runs (the plant's terminal observer reads it) */
    int64_t k;                 /* next sample index */
    bc_ctrl_out pending;       /* controller output waiting for the next sample (delay 1): legs and a timed change */
    bc_ctrl_out last;          /* last controller output */
    bc_ctrl_in last_in;        /* last measurements */
    uint32_t flags_seen;       /* BC_FLAG_* bits the controller raised at any sample so far (OR) */
    int32_t flag_run_n[BC_SIM_NFLAG]; /* samples of the whole run at which flag bit j was raised */
    double flag_run_t0[BC_SIM_NFLAG]; /* first and last such sample time, s (0 if none) */
    double flag_run_t1[BC_SIM_NFLAG];
    double th_prev;            /* plant angle at the last step end, rad */
    double th_run;             /* electrical angle travelled since the start, unwrapped, rad */
    bc_sim_metrics m;
    double m_acc0[BC_ACC_N];   /* acc[] at the metric window start */
    double ma_prev;            /* previous half-period mean torque in the window (sample-grid average) */
    int32_t ma_have;
    double t_pwm;              /* PWM period, s */
    int64_t h_n;               /* step ends pushed into the history ring so far */
    int64_t h_lag;             /* history node at or before t - t_pwm (absolute index) */
    double h_t[BC_SIM_HIST];   /* history ring: time, s */
    double h_a[BC_SIM_HIST];   /* acc[BC_ACC_TAU], N m s */
    double h_tau[BC_SIM_HIST]; /* tau_e, N m */
    double ma_num_min, ma_num_max; /* extremes of T MA (the moving average's numerators), N m s: m.tau_ma_min, _max
                                      are these over T */
    double half_tau0;          /* acc[TAU] at the start of the current half period */
    int32_t half_in;           /* current half period started inside the window */
    int32_t row_open;          /* a trace row is being accumulated */
    bc_trace_row row;          /* the row being accumulated */
    double at_time;            /* instant of the timed leg change applied in the current sample, s (-1: none) */
    double row_acc0[BC_ACC_N];
    double row_tmin, row_tmax;
    double row_peak[4];        /* largest |i_a|, |i_b|, |i_c|, |omega_m| of the trace rows written so far */
    int32_t row_nonfinite;     /* 1: a trace row written so far holds a non-finite i_x, tau_e or omega_m */
    float temp[2];             /* what the temperature sensors read (bc_ctrl_in.temp), degC; NaN: none */
} bc_sim_state;

/* Validate the configuration and start: plant at t = 0 with the given angle, speed, currents and source voltage;
 * sensors seeded; all legs off; the controller state must have been initialised by its own init. */
int bc_sim_init(const bc_sim_config *cfg, bc_sim_state *s, double theta0, double omega0, const double i0[3],
                double v_src0);

/* Temperature between chunks of a run (bc_plant_set_thermal on the run's plant): R r_scale, k_scale times the
 * back-EMF, R_on ron_scale from the next sample on. BC_ERR_PARAM for a scale that is not finite and > 0. */
int bc_sim_set_thermal(const bc_sim_config *cfg, bc_sim_state *s, double r_scale, double k_scale, double ron_scale);

/* What the controller's temperature sensors read from the next sample on (bc_ctrl_in.temp: [0] winding, [1]
 * switches), degC; NaN: no sensor (the value after init). A thermal model calls it between chunks of a run. */
int bc_sim_set_temperatures(const bc_sim_config *cfg, bc_sim_state *s, double T_winding, double T_switches);

/* Run n samples. Writes complete trace rows into rows[0 .. rows_cap) and their count into *rows_written.
 * Returns BC_OK, BC_ERR_PARAM (bad config/inputs) or BC_ERR_SIZE (rows_cap too small; rows beyond it dropped). */
int bc_sim_run(const bc_sim_config *cfg, bc_sim_state *s, const bc_sim_inputs *in, int64_t n, bc_trace_row *rows,
               int64_t rows_cap, int64_t *rows_written);

#endif /* BC_SIM_H */

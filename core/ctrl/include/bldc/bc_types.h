/*
 * bc_types.h - what every block of bldclab shares: constants, error codes, the leg command, and the contract
 * between a controller and whatever drives it (the simulation runner on the host, timers and ADCs on an MCU).
 *
 * A controller is a pair of functions over caller-owned memory:
 *
 *     int  bc_X_init(const bc_X_params *p, bc_X_state *s);                  validates p, resets s
 *     void bc_X_step(const bc_X_params *p, bc_X_state *s,
 *                    const bc_ctrl_in *in, bc_ctrl_out *out);               one sample
 *
 * `in` holds measurements only (never plant state); `out` holds the three leg commands for the next half PWM
 * period plus diagnostics. Conventions (angles, Hall codes, PWM timing): docs/conventions.md.
 */
#ifndef BC_TYPES_H
#define BC_TYPES_H

#include <stdint.h>

#define BC_PI 3.14159265358979323846
#define BC_PI_F 3.14159265f
#define BC_TWO_PI (2.0 * BC_PI)
#define BC_TWO_PI_F 6.28318531f

/* Error codes returned by every init function. */
#define BC_OK 0
#define BC_ERR_PARAM (-1)   /* a parameter is out of range, NaN or inconsistent */
#define BC_ERR_SIZE (-2)    /* a caller buffer is too small */
#define BC_ERR_INPUT (-3)   /* an input array or value is invalid */

/* Leg modes, one per leg and half PWM period (docs/conventions.md). */
#define BC_LEG_OFF 0   /* both switches off: the leg's diodes carry any current */
#define BC_LEG_PWM 1   /* complementary: upper on for duty d, lower on otherwise */
#define BC_LEG_HIGH 2  /* upper switch chops with duty d, lower off */
#define BC_LEG_LOW 3   /* lower switch chops with duty d, upper off */
/* A plant idealisation, not hardware: paper 1's ideal current limiter. On the averaged inverter the leg's duty is set
 * in continuous time so that its phase current stays at bc_ctrl_out.i_hold (A, signed; i_hold_at for leg_at), and at
 * full drive (duty 0 or 1) toward it while it cannot be held; the leg's own duty is unused (1). At most one leg per
 * command; the switching inverter treats it as off. Only reference models use it (SixStep regulation "ideal"); no
 * controller for an MCU may. */
#define BC_LEG_HOLD 4

typedef struct {
    int32_t mode; /* BC_LEG_* */
    float duty;   /* [0, 1]: fraction of the half period the chopping switch is on */
} bc_leg_cmd;

/* Number of diagnostic values a controller may report per sample (meaning: the controller's header). */
#define BC_DIAG_N 8

/* Status flags a controller reports. */
#define BC_FLAG_SAFE 0x1u        /* all legs off: safe state */
#define BC_FLAG_HALL_INVALID 0x2u /* Hall code 000 or 111 */
#define BC_FLAG_OVERCURRENT 0x4u /* a measured current exceeded the limit */
#define BC_FLAG_BAD_INPUT 0x8u   /* a measurement was NaN/inf or out of its physical range */
#define BC_FLAG_SATURATED 0x10u  /* the demanded voltage/duty was limited */
/* Sensorless commutation (bc_bemf.h). DESYNC is raised at the sample that detects a loss of synchronisation, with
 * the flag of its reason; OPEN_LOOP at every sample of the start-up (alignment, forced commutation); COMM_LATE at a
 * sample whose commutation instant had already passed (it commutates at once, at the start of the output's interval). */
#define BC_FLAG_DESYNC 0x20u     /* synchronisation lost: all legs off, restart (one of the next five says why) */
#define BC_FLAG_ZC_TIMEOUT 0x40u /* reason: no crossing within the timeout after the floating phase left the clamp */
#define BC_FLAG_ZC_HIDDEN 0x80u  /* reason: the floating phase never left the clamp level in the window (the
                                    demagnetisation outlasted the crossing: the crossing hidden) */
#define BC_FLAG_ZC_JUMP 0x100u   /* reason: ratio of successive crossing intervals out of bounds (a false crossing) */
#define BC_FLAG_STALL 0x200u     /* reason: speed from the crossings below the slowest closed-loop speed */
#define BC_FLAG_START_FAIL 0x400u /* reason: the open-loop ramp ended without the crossings for a handover */
#define BC_FLAG_OPEN_LOOP 0x800u /* aligning or commutating open loop (start-up) */
#define BC_FLAG_COMM_LATE 0x1000u /* a commutation instant already past: commutated at once */
#define BC_FLAG_LOCK_LOST 0x2000u /* reason: the rotor-angle observer's flux left its band (sensorless sine) */

/* Measurements presented to a controller at one sample. */
typedef struct {
    float i_abc[3];      /* measured phase currents, A, positive into the motor; 0 where not measured */
    uint32_t i_mask;     /* bit x set: phase x measured (bit 0 = a) */
    float v_dc;          /* measured DC-bus voltage, V */
    uint32_t hall;       /* Hall code: bit 0 = H_a, bit 1 = H_b, bit 2 = H_c */
    uint32_t n_edges;    /* Hall edges seen since start (wraps) */
    uint32_t tick_edge;  /* capture-timer tick of the last Hall edge */
    uint32_t tick_now;   /* capture-timer tick of this sample */
    float theta_enc;     /* encoder electrical angle, rad in [0, 2 pi) (reference sensor) */
    float omega_enc;     /* encoder mechanical speed, rad/s (reference sensor) */
    float ref;           /* primary reference: torque N m, current A or duty, per controller */
    float omega_ref;     /* speed reference, rad/s (controllers with a speed loop) */
    uint32_t fault_pin;  /* 1: the inverter's hardware protection has tripped (its gates are off, latched) */
    /* back-EMF sensing of a sensorless drive (all zero where the drive has none; docs/sensing.md): */
    uint32_t zc_state;    /* comparator outputs, bit x: phase x's filtered terminal voltage above the reference */
    uint32_t zc_count[3]; /* edges of comparator x seen since start (wraps) */
    uint32_t zc_tick[3];  /* capture-timer tick of comparator x's last edge */
    float v_term[3];      /* ADC samples of the terminal voltages (phase to DC minus), V at the terminal: through the
                             divider and its RC filter, converted, scaled back by the divider ratio */
    float v_neutral;      /* ADC sample of the comparators' reference (virtual star point or half the bus), V */
    uint32_t n_adc;       /* ADC conversions since start (wraps): a new one when it changes */
    uint32_t tick_adc;    /* capture-timer tick of the last conversion's sampling instant */
    float temp[2];        /* temperature sensors, degC: [0] the winding's, [1] the switches' (heat sink or board);
                             NaN where none is fitted (a controller's derating then reads a sensor fault) */
    float i_fs;           /* full scale of the current readings, A: a reading at +-i_fs is clipped (the shunt
                             amplifier or the ADC saturated), the current at least that; 0: none (or not known) */
} bc_ctrl_in;

/* What a controller returns at one sample. The legs apply to the next half period (with the runner's one-sample
 * delay; the current one without). A controller may also change them inside that half period, at t_at seconds after
 * its start, as an MCU's commutation timer does (the output compare of a timer running beside the PWM): from then
 * on the legs are leg_at, each on the same carrier. has_at = 0 (what the runner clears the output to): no change. */
typedef struct {
    bc_leg_cmd leg[3];     /* legs a, b, c for the next half period */
    float diag[BC_DIAG_N]; /* diagnostics for the trace */
    uint32_t flags;        /* BC_FLAG_* */
    uint32_t has_at;       /* 1: leg_at from t_at on */
    float t_at;            /* s after the start of the half period, in [0, T/2) (a later time is ignored) */
    bc_leg_cmd leg_at[3];  /* legs from t_at on */
    float i_hold;          /* current a BC_LEG_HOLD leg of leg holds, A (plant idealisation; 0 otherwise) */
    float i_hold_at;       /* ... of leg_at */
} bc_ctrl_out;

/* A controller slot: the runner calls step(params, state, in, out) once per sample. */
typedef void (*bc_ctrl_step_fn)(const void *params, void *state, const bc_ctrl_in *in, bc_ctrl_out *out);

typedef struct {
    bc_ctrl_step_fn step;
    const void *params;
    void *state;
} bc_ctrl;

/* All legs off (the safe state). */
void bc_legs_off(bc_ctrl_out *out);

#endif /* BC_TYPES_H */

/*
 * bc_sense.h - back-EMF sensing of a sensorless drive: the terminal voltages through a resistor divider and an RC
 * filter to three comparators and an ADC, as an ESC's hardware has them (double; host only: the MCU sees the
 * results in bc_ctrl_in's zc_* and v_term, v_neutral, n_adc, tick_adc). Full description: docs/sensing.md.
 *
 * Each phase's terminal voltage v_x (phase to DC minus, from the plant: the rail or diode clamp of a conducting leg,
 * e_x + v_n of a floating one, PWM included) reaches the MCU pin through a divider of ratio k and a first-order RC
 * filter of time constant tau. Everything here is in volts at the terminal (the pin voltage divided by k): an ADC
 * step or a comparator offset given in pin volts is divided by k.
 *
 *     tau dv_f,x/dt = v_x(t) - v_f,x          (tau = 0: v_f,x = v_x)
 *
 * Inside one plant step v_x(t) is smooth: it is taken as the cubic u(s) = c0 + c1 s + c2 s^2 + c3 s^3 through its
 * values and exact time derivatives at the step's ends (bc_plant_term_fn), and the filter is integrated in closed
 * form,
 *
 *     v_f(s) = exp(-z) v_f(0) + z sum_k k! c_k s^k phi_{k+1}(-z),   z = s / tau,
 *
 * phi_j the functions of exponential integrators (phi_0(w) = exp(w), phi_{j+1}(w) = (phi_j(w) - 1/j!) / w; from
 * their series for |w| < 1). It is exact for the cubic at any s / tau, so the filter is as accurate as the plant's
 * step (O(h^4)) whether tau is far shorter or far longer than the step.
 *
 * The comparators' reference is the virtual star point of the three filtered dividers, v_r = (v_f,a + v_f,b +
 * v_f,c) / 3 (BC_SENSE_REF_STAR: the PWM of the driven phases cancels in v_f,x - v_r), or half the DC bus
 * (BC_SENSE_REF_HALF: the bus at the step's end). Comparator x switches high when c_x = v_f,x - v_r - offset rises
 * above +hyst/2 and low when it falls below -hyst/2. The crossing is bracketed on a grid of BC_SENSE_GRID points per
 * plant step (two crossings of one threshold closer than h / BC_SENSE_GRID are missed: the plant's steps end at every
 * gate edge, so between them the input is one smooth stroke) and located by bisection to 1e-12 of the step. The MCU
 * sees an edge `delay` later (propagation delay), time-stamped by its capture timer; a pulse shorter than the delay is
 * still seen (the output is delayed, not filtered: the RC network is the filter).
 *
 * The ADC converts once per PWM period, at the carrier peak (the centre of the on-time of centre-aligned PWM) plus
 * adc_at (s, in [-T/2, T/2)): v_term[x] = q(v_f,x(t_a) + n), v_neutral = q(v_r(t_a) + n), q the rounding to adc_lsb
 * (0: none) and clipping to [0, adc_max], n white noise of standard deviation adc_noise. A controller sample at t
 * sees the conversions at t_a <= t.
 */
#ifndef BC_SENSE_H
#define BC_SENSE_H

#include <stdint.h>

#include "bldc/bc_types.h"

#define BC_SENSE_REF_STAR 0 /* virtual star point of the three filtered dividers */
#define BC_SENSE_REF_HALF 1 /* half the DC bus */

#define BC_SENSE_QUEUE 16 /* comparator edges in flight (propagation delay) */
#define BC_SENSE_GRID 4   /* bracketing points per plant step */

typedef struct {
    int32_t on;       /* 1: the drive has back-EMF sensing; 0: none (the inputs stay zero) */
    double tau;       /* RC filter time constant, s (>= 0; 0: no filter) */
    int32_t ref;      /* BC_SENSE_REF_STAR or BC_SENSE_REF_HALF */
    double offset;    /* comparator input offset, V at the terminal */
    double hyst;      /* comparator hysteresis (total width), V at the terminal (>= 0) */
    double delay;     /* comparator propagation delay, s (>= 0) */
    double adc_at;    /* ADC sampling instant after the carrier peak, s, in [-T/2, T/2) */
    double adc_lsb;   /* ADC quantisation step, V at the terminal (>= 0; 0: none): V_ref / 2^bits / k */
    double adc_max;   /* ADC full scale, V at the terminal (> 0; HUGE_VAL: none): V_ref / k */
    double adc_noise; /* ADC noise, standard deviation, V at the terminal (>= 0) */
    double f_pwm;     /* PWM carrier frequency, Hz (the ADC's trigger): the plant's */
    double f_tick;    /* capture-timer frequency, Hz: the sensors' */
    uint64_t seed;    /* noise generator seed */
} bc_sense_params;

typedef struct {
    double t;                   /* time the filter states hold, s */
    double vf[3];               /* filtered terminal voltages, V */
    double vbus;                /* DC bus at the last step's end, V (half-bus reference) */
    uint32_t out;               /* comparator outputs at their inputs (before the delay), bit x */
    uint32_t seen;              /* comparator outputs the MCU sees (after the delay) */
    uint32_t count[3];          /* edges seen per comparator */
    double t_seen[3];           /* time each was last seen, s */
    uint32_t n_edges;           /* comparator edges located at the inputs */
    int32_t q_n;                /* edges in flight, in time order */
    double q_t[BC_SENSE_QUEUE]; /* when the MCU sees them, s */
    int32_t q_x[BC_SENSE_QUEUE];
    int32_t overrun;            /* 1: more edges in flight than the queue holds (the oldest were seen early) */
    double t_adc;               /* next ADC sampling instant, s */
    uint32_t n_adc;             /* conversions made */
    double adc_t;               /* instant of the last, s */
    float adc_v[3];             /* its results, V */
    float adc_vr;
    uint64_t rng; /* xorshift64* state */
    int32_t has_spare;
    double spare;
} bc_sense_state;

/* Validate p (BC_ERR_PARAM; nothing to check when p->on is 0) and start at time t0 with the filters settled at the
 * terminal voltages v[3] and the bus v_bus: the comparators' outputs from them (no edge), the first ADC instant
 * after t0. */
int bc_sense_init(const bc_sense_params *p, bc_sense_state *s, double t0, const double v[3], double v_bus);

/* One plant step [s->t, t1]: the terminal voltages' values v0, v1 and time derivatives dv0, dv1 at its ends, and the
 * bus at its end. Advances the filters, locates the comparator edges and takes the ADC conversions in it. */
void bc_sense_step(const bc_sense_params *p, bc_sense_state *s, double t1, const double v0[3], const double dv0[3],
                   const double v1[3], const double dv1[3], double v_bus);

/* Fill the sensing inputs of `in` for a controller sample at time t: the edges seen by then, the last conversion. */
void bc_sense_fill(const bc_sense_params *p, bc_sense_state *s, double t, bc_ctrl_in *in);

#endif /* BC_SENSE_H */

/*
 * bc_plant.h - switching-level model of a PM brushless motor on a two-level inverter (double precision).
 *
 * Motor (star, no neutral wire), x in {a, b, c}:
 *
 *     v_x - v_n = R i_x + L di_x/dt + e_x,    e_x = omega_m k_x(theta_e - x 2pi/3),    i_a + i_b + i_c = 0
 *     tau_e = sum_x k_x i_x + tau_cog(theta_m),                 theta_e = p theta_m
 *     J domega_m/dt = tau_e - tau_L - k_q omega_m |omega_m| - B omega_m - tau_c sign(omega_m) - tau_fe
 *     (or omega_m imposed, whose dynamometer is the load; k_q: a propeller or fan, booked with tau_L as the load's
 *     energy, acc LOAD; tau_fe: the
 *                                                                              iron-loss drag, "Iron losses" below)
 *
 * Inverter: each leg's gate state (upper on, lower on, both off) comes from the half-period command
 * (bc_plant_set_half), centre-aligned PWM and dead time. A connected phase has v_x = U_x - r_x i_x:
 *
 *     upper switch  U = v_bus,        r = R_on          lower switch  U = 0,     r = R_on
 *     upper diode   U = v_bus + V_f,  r = r_d (i < 0)   lower diode   U = -V_f,  r = r_d (i > 0)
 *     v_bus = V_src - R_src i_dc,     i_dc = sum of i_x over phases tied to the + rail
 *
 * With C the set of connected phases (|C| >= 2): v_n = mean_C (U_x - (R + r_x) i_x - e_x) and
 * L di_x/dt = U_x - (R + r_x) i_x - e_x - v_n for x in C. A both-off phase whose current reaches zero opens
 * (i_x = 0, terminal floating at e_x + v_n) and conducts again when that voltage leaves [-V_f, v_bus + V_f].
 * These rules alone produce freewheeling, open phase, current dips and torque spikes: nothing is scripted.
 *
 * Averaged inverter (params.inverter = BC_INV_AVERAGE): a leg commanded to switch inside the half period
 * (BC_LEG_PWM, HIGH or LOW with 0 < d < 1) applies its half-period average instead of its gate edges. With f_U,
 * f_L, f_O the fractions of the half period with the upper switch on, the lower switch on, both off
 * (PWM: d, 1-d, 0; HIGH: d, 0, 1-d; LOW: 0, d, 1-d; dead time neglected), the leg is the weighted mean of its
 * gate states, the both-off fraction conducting through the diode that the current's sign selects:
 *
 *     f_O = 0 (PWM, always connected):  U = f_U v_bus,                      r = R_on
 *     i > 0 (lower diode in f_O):       U = f_U v_bus - f_O V_f,            r = (f_U + f_L) R_on + f_O r_d
 *     i < 0 (upper diode in f_O):       U = (f_U + f_O) v_bus + f_O V_f,    r = (f_U + f_L) R_on + f_O r_d
 *     i = 0: open while the floating terminal e_x + v_n stays in [U_lo, U_hi] =
 *            [f_U v_bus - f_O V_f, (f_U + f_O) v_bus + f_O V_f] (the diode window of a both-off leg, narrowed
 *            by the switch's share; f_O = 1 gives [-V_f, v_bus + V_f]); leaving it, the leg conducts as above.
 *
 * i_dc takes f_U i (+ f_O i through the upper diode), the switch loss is (f_U + f_L) R_on i^2 and the diode loss
 * f_O (V_f + r_d |i|) |i|: exactly the power the averaged sources and resistances take, so the energy balance
 * closes as in the switching model. With R_src > 0 the bus drop is averaged exactly too: leg x sees
 * f_up,x V_src - R_src sum_y M_xy i_y and the source resistance takes R_src sum_xy i_x M_xy i_y, where
 * M_xy = mean over the half period of up_x(t) up_y(t) (up: tied to the + rail); the active intervals of all legs
 * are anchored at the same end of the half period (centre-aligned PWM), so with a_x the active fraction and
 * A_x, I_x = 1 if the active / idle state ties the + rail:
 *     M_xy = A_x A_y min(a_x, a_y) + A_x I_y max(0, a_x - a_y) + I_x A_y max(0, a_y - a_x)
 *            + I_x I_y min(1 - a_x, 1 - a_y).
 * The open-phase windows use the mean bus v_bus = V_src - R_src i_dc. The i > 0 and i < 0 states are the cond codes BC_COND_D_L / BC_COND_D_U of
 * the leg (BC_COND_SW_U for f_O = 0), so current zeros and re-conduction are the same located events. Exact for
 * continuous conduction over the half period; a current that would reach zero inside it (discontinuous
 * conduction) is approximated by an open phase (i = 0 while the terminal is inside the window): the neglected
 * pulses are bounded by |U - e_x - v_n| T/(2L) and vanish as f_pwm grows. Legs that are off or held at d = 0 or
 * 1, dead time between such states, the open phase and the trip are those of the switching model. No gate edge
 * falls inside a half period, so steps are as long as h_max (half a PWM period) allows.
 *
 * Ideal current limiter (BC_LEG_HOLD, averaged inverter, R_src = 0): paper 1's idealisation of a current controller
 * infinitely faster than the commutation. Leg x is an always-connected PWM leg whose duty d follows the state: while
 * holding, d = d*(y), the duty at which di_x/dt = 0 (di/dt is affine in d: di_x/dt = base_x + v_src c_x d, c_x =
 * (1 - 1/n)/L over the n connected phases, so d* = -base_x / (v_src c_x), and its rate follows from the chain rule,
 * d(d^*)/dt = -(d base_x/dt) / (v_src c_x)); i_x stays at the reference. While d* would leave [0, 1] (a watched event) the
 * leg is free at full drive toward the reference (d = 1 below it, 0 above) until i_x reaches it again (an event),
 * where it holds if d* is in [0, 1]. The terminal, i_dc and the power flows use d* (the trace's duty column shows
 * it at the row start). A new reference or leg starts free.
 *
 * Switching losses (an accounting on top of the ideal switches; the circuit above is unchanged). At each gate
 * edge of a switching leg, with i = i_x and v_bus the bus voltage at the edge:
 *
 *     hard turn-off (upper off with i > 0, lower off with i < 0: the current leaves the switch for the opposite
 *         diode)                                    E_swloss += E_off s,
 *     hard turn-on (upper on with i > 0, lower on with i < 0: the current commutates from the opposite diode)
 *                                                    E_swloss += E_on s,   E_rr += E_rr s,
 *     s = (|i| / I_test) (v_bus / V_test)  (linear in current and voltage, the usual datasheet scaling).
 *
 * Soft edges (a switch turning on or off while its own antiparallel diode carries the current) and zero-current
 * edges book nothing. With t_dead = 0 the opposite device counts as a diode (a hard turn-on books E_rr). The
 * trip's turn-off is a hard turn-off. The energies are drawn from the DC source on top of V_src i_dc (acc SWLOSS,
 * RR). Averaged legs have no edges and book the period-average expectation as a power: a PWM leg
 * f_pwm (E_on + E_off) s (and f_pwm E_rr s) at any current sign, a HIGH leg only for i > 0, a LOW leg only for
 * i < 0 (otherwise both its edges are soft), with v_bus the half-period mean bus; the edges at the start or
 * end of an averaged stretch are not booked.
 *
 * Hall sensors (docs/hall.md). Sensor x, placed at its nominal edges theta_n = PHI_x - pi/6 + k pi (conventions.md)
 * plus its placement error err_x, switches where the rotor reaches
 *     theta_sw = theta_n + err_x + dir h_x / 2          (dir = +1 forward, -1 backward; h_x its hysteresis),
 * i.e. a magnetic threshold +-B_h on a field ~ sin(theta - theta_n - err_x): both edges come h_x/2 late in the
 * direction of travel, and a reversal inside the band of width h_x switches nothing. The edge then reaches the
 * line after the propagation delay d_x and passes a first-order RC filter (time constant tau_x) whose output
 * level v (0..1) the MCU input reads against half the swing:
 *     v(t) = u + (v(t_u) - u) exp(-(t - t_u) / tau_x)   after the (delayed) input steps to u at t_u,
 *     the input switches at t_u + tau_x ln((u - v(t_u)) / (u - 1/2))  if v(t_u) is on the other side of 1/2.
 * An isolated edge is thus seen d_x + tau_x ln 2 late; a pulse on the line shorter than tau_x ln 2 is never seen.
 * All switching angles are located exactly (integration events) and every time is exact.
 *
 * Iron losses (stator core loss caused by the magnets' flux; an accounting with its drag torque, the circuit is
 * unchanged). The flux linked by phase x's teeth and yoke follows psi_PM,x, so the back-EMF e_x = dpsi_PM,x/dt
 * (any shape) is the flux rate the core sees. In the time domain:
 *
 *     p_eddy = k_fe_e sum_x e_x^2                 classical eddy-current loss, k_fe_e in W/V^2;
 *     p_hyst = k_fe_h |omega_e|,  omega_e = p omega_m   hysteresis: an energy 2 pi k_fe_h per electrical cycle, fixed
 *                                                  by the peak flux density, which the magnets fix; J/rad;
 *     p_ex = k_fe_x sum_x |e_x|^1.5               excess (Bertotti) loss, |dB/dt|^1.5 in the time domain; W/V^1.5;
 *     p_fe = p_eddy + p_hyst + p_ex,
 *     tau_fe = p_fe / omega_m = k_fe_e omega_m sum_x k_x^2 + p k_fe_h sign(omega_m)
 *              + k_fe_x sign(omega_m) |omega_m|^0.5 sum_x |k_x|^1.5.
 *
 * For a non-sinusoidal back-EMF the mean of e_x^2 is the sum of its harmonics' mean squares (Parseval), so the eddy
 * term counts every harmonic of the trapezoid with the f^2 weight of the classical eddy loss; a sinusoidal e_x of
 * peak E gives 3 k_fe_e E^2 / 2. tau_fe is a drag on the rotor: it enters the rotor equation next to friction,
 *
 *     J domega_m/dt = tau_e - tau_L - B omega_m - tau_c sign(omega_m) - tau_fe,
 *
 * the eddy part as a viscous drag, the excess part vanishing at rest like |omega_m|^0.5, the hysteresis part as
 * Coulomb friction (a rotor at rest stays stuck while |tau_e - tau_L| <= tau_c + p k_fe_h);
 * with an imposed speed the dynamometer supplies it. The loss is booked in acc FE (tau_fe omega_m = p_fe), so the
 * shaft balance reads E_emf + E_cog = E_fric + E_fe + E_load + dW_kin. Not modelled: the flux of the stator currents
 * (armature reaction L i, and the PWM ripple flux): their core loss would need a magnetising branch in the circuit;
 * minor hysteresis loops (dc-biased or reversing flux in a period); eddy currents' own field (valid while the
 * lamination is thin against the skin depth at the harmonics that carry the loss); rotational loss in the yoke
 * beyond what k_fe_e, k_fe_h calibrate. Full description: docs/plant.md, "Iron losses".
 *
 * Integration: RK4 between events; lands exactly on gate edges, back-EMF corners and Hall edges (predicted),
 * and on diode current zeros, re-conduction and speed zero crossings (root finding); within a step the Coulomb-like
 * drags (tau_c, p k_fe_h) keep the sign of the motion at its start. The power flows acc[] are integrated over each
 * step by the corrected trapezoid rule from their rates f and the rates' exact time derivatives f' (chain rule along
 * the circuit equations) at the step's two ends,
 *
 *     acc(t + h) = acc(t) + h (f(t) + f(t + h)) / 2 + h^2 (f'(t) - f'(t + h)) / 12      (exact for cubics, O(h^5)),
 *
 * so the RK4 stages evaluate only the five states (i_a, i_b, i_c, theta, omega) and the energy balance, an
 * identity of the rates, closes to the integration accuracy. Full description: docs/plant.md.
 */
#ifndef BC_PLANT_H
#define BC_PLANT_H

#include <stdint.h>

#include "bldc/bc_emf.h"
#include "bldc/bc_types.h"

#define BC_MECH_IMPOSED 0 /* omega_m is an input (dynamometer) */
#define BC_MECH_DYNAMIC 1 /* omega_m from the rotor equation */

/* Gate state of a leg. */
#define BC_GATE_O 0 /* both off */
#define BC_GATE_U 1 /* upper on */
#define BC_GATE_L 2 /* lower on */

/* Inverter model (bc_plant_params.inverter). */
#define BC_INV_SWITCHING 0
#define BC_INV_AVERAGE 1

/* Conduction state of a phase (an averaged leg: D_L / D_U for i > 0 / i < 0, SW_U if it has no off fraction). */
#define BC_COND_OPEN 0
#define BC_COND_SW_U 1
#define BC_COND_SW_L 2
#define BC_COND_D_U 3
#define BC_COND_D_L 4

/* Integrated quantities acc[], listed once: X(NAME, name, unit, description). The order serves the integrator, which
 * adds up the lanes 0 .. acc_hi - 1 (the rates of the lanes not integrated are held at zero): first the lanes every
 * metric window reads, then those the parameters may keep at zero (friction, cogging, switch, diode and source
 * resistance losses), then the trace's (terminal voltages, star point, DC current), last the optional loss lanes
 * SWLOSS, RR, FE (BC_ACC_OPT is the first of them: a plant whose switching-loss energies and iron-loss coefficients
 * are all zero, or whose switching losses are only booked at gate edges, never integrates them). */
#define BC_ACC_FIELDS(X)                                                                      \
    X(TAU, tau, "N m s", "integral of tau_e")                                                 \
    X(TAU2, tau2, "N^2 m^2 s", "integral of tau_e^2")                                         \
    X(I2A, i2a, "A^2 s", "integral of i_a^2")                                                 \
    X(I2B, i2b, "A^2 s", "integral of i_b^2")                                                 \
    X(I2C, i2c, "A^2 s", "integral of i_c^2")                                                 \
    X(CU, cu, "J", "R sum i^2: copper loss")                                                  \
    X(EMF, emf, "J", "sum e_x i_x = tau_em omega_m: electrical to mechanical")               \
    X(SRC, src, "J", "V_src i_dc: energy delivered by the DC source")                         \
    X(LOAD, load, "J", "tau_L omega: energy to the load")                                     \
    X(FRIC, fric, "J", "(B omega + tau_c sign omega) omega: friction loss")                   \
    X(COG, cog, "J", "tau_cog omega_m")                                                       \
    X(SW, sw, "J", "R_on i^2 in conducting switches")                                         \
    X(DIODE, diode, "J", "(V_f + r_d |i|) |i| in conducting diodes")                          \
    X(RSRC, Rsrc, "J", "R_src i_dc^2: loss in the source resistance")                        \
    X(VA, va, "V s", "integral of the terminal voltage v_a")                                  \
    X(VB, vb, "V s", "integral of v_b")                                                       \
    X(VC, vc, "V s", "integral of v_c")                                                       \
    X(VN, vn, "V s", "integral of the star-point voltage")                                    \
    X(IDC, idc, "A s", "integral of the DC current")                                          \
    X(SWLOSS, swloss, "J", "E_on + E_off booked at hard gate edges (switching loss, from the source)") \
    X(RR, rr, "J", "E_rr booked at hard turn-ons: the opposite diode's reverse recovery")     \
    X(FE, fe, "J", "tau_fe omega: stator iron loss (eddy k_fe_e sum e^2 + hysteresis k_fe_h |omega_e|)")

enum {
#define BC_ACC_ENUM(NAME, name, unit, doc) BC_ACC_##NAME,
    BC_ACC_FIELDS(BC_ACC_ENUM)
#undef BC_ACC_ENUM
    BC_ACC_N
};
#define BC_ACC_OPT BC_ACC_SWLOSS /* first optional lane: SWLOSS, RR, FE are the last three */

#define BC_HALL_QUEUE 8
#define BC_PLANT_FZ_N 16 /* Fourier shapes up to this many orders share one cos/sin recurrence for the three phases */
#define BC_PLANT_NW 18 /* functions watched for sign changes inside a step (diodes, open phases, speed, trip, hold) */

/* Faults the plant injects (bc_plant_params.fault): each active on [t_on, t_off). */
#define BC_FAULT_MAX 4
#define BC_FAULT_NONE 0
#define BC_FAULT_PHASE_OPEN 1  /* phase `phase` disconnected (broken wire): no current through switch or diode */
#define BC_FAULT_HALL_STUCK 2  /* Hall sensor `phase` reads `value` (0 or 1) */
#define BC_FAULT_HALL_GLITCH 3 /* Hall sensor `phase` reads inverted */
/* ... and the sensor chain injects (bc_sensor_params.fault): */
#define BC_FAULT_CURRENT_OFFSET 4 /* current sensor of phase `phase` reads `value` A more */
#define BC_FAULT_CURRENT_LOSS 5   /* current sensor of phase `phase` reads 0 (lost) */

typedef struct {
    int32_t kind;  /* BC_FAULT_* */
    int32_t phase; /* phase or sensor index 0..2 */
    double t_on;   /* start, s */
    double t_off;  /* end, s (HUGE_VAL: permanent) */
    double value;  /* kind-specific value */
} bc_fault;

/* Plant flags (bc_plant_state.flags). */
#define BC_PLANT_BAD_DUTY 0x1u   /* a leg command had a NaN or out-of-range duty (treated as clamped / 0) */
#define BC_PLANT_CHATTER 0x2u    /* too many events at one instant; the integrator forced progress */
#define BC_PLANT_HALL_OVERRUN 0x4u /* delayed Hall edges overflowed the queue */

typedef struct {
    /* motor */
    int32_t p;              /* pole pairs */
    double R;               /* phase resistance, Ohm */
    double L;               /* inclusive phase inductance L_self - M, H */
    bc_emf_shape emf[3];    /* k_x of phases a, b, c in their local angles */
    int32_t n_cog;          /* cogging harmonics (0: none) */
    const double *cog_order;  /* harmonic orders in theta_m */
    const double *cog_amp;    /* amplitudes, N m */
    const double *cog_phase;  /* phases, rad: tau_cog = sum amp sin(order theta_m + phase) */
    double k_fe_e;          /* iron loss, eddy term: p_eddy = k_fe_e sum_x e_x^2, W/V^2 (0: none) */
    double k_fe_h;          /* iron loss, hysteresis term: p_hyst = k_fe_h |omega_e|, J/rad (0: none) */
    double k_fe_x;          /* iron loss, excess term: p_ex = k_fe_x sum_x |e_x|^1.5, W/V^1.5 (0: none) */
    /* inverter */
    double f_pwm;           /* carrier frequency, Hz (half period T/2 = 1/(2 f_pwm)) */
    double t_dead;          /* dead time, s */
    double R_on;            /* switch on-resistance, Ohm */
    double V_f;             /* diode forward voltage, V */
    double r_d;             /* diode slope resistance, Ohm */
    double R_src;           /* DC source resistance, Ohm */
    double i_trip;          /* hardware over-current trip, A: |i_x| reaching it switches every gate off, latched
                               (a comparator on the phase shunts, as gate drivers have); 0: none */
    double E_on;            /* switching losses (see "Switching losses" above): turn-on energy at (V_test, I_test), J */
    double E_off;           /* turn-off energy at (V_test, I_test), J */
    double E_rr;            /* diode reverse-recovery energy at (V_test, I_test), J */
    double V_test;          /* datasheet test voltage of E_on, E_off, E_rr, V (> 0 if any energy > 0) */
    double I_test;          /* datasheet test current, A (> 0 if any energy > 0) */
    int32_t inverter;       /* BC_INV_SWITCHING (gate edges) or BC_INV_AVERAGE (half-period averages) */
    /* mechanics */
    int32_t mech;           /* BC_MECH_IMPOSED or BC_MECH_DYNAMIC */
    double J;               /* inertia, kg m^2 */
    double B;               /* viscous friction, N m s/rad */
    double tau_c;           /* Coulomb friction, N m */
    double k_q;             /* propeller or fan load k_q omega_m |omega_m| (rotor dynamics only), N m s^2/rad^2 */
    /* Hall sensors */
    double hall_error[3];   /* placement error of each sensor, rad (electrical), |.| < pi/6 */
    double hall_hyst[3];    /* hysteresis of each sensor, rad (electrical), in [0, pi/3): its edges sit dir h/2
                               past the placed edge (later in the direction of travel, both edges) */
    double hall_delay[3];   /* propagation delay of each sensor's edges, s */
    double hall_tau[3];     /* time constant of the RC filter on each sensor line, s (0: none); the MCU input
                               switches where the filtered level crosses half the swing */
    /* numerics */
    double h_max;           /* longest RK4 step, s (<= 0: half a PWM period) */
    /* injected faults */
    bc_fault fault[BC_FAULT_MAX];
} bc_plant_params;

/* Instantaneous quantities at the current state (for sensors and the trace). */
typedef struct {
    double e[3];      /* back-EMF, V */
    double k[3];      /* shapes, V s/rad */
    double v[3];      /* terminal voltages, V */
    double v_n;       /* star point, V */
    double v_bus;     /* DC bus at the inverter, V */
    double i_dc;      /* DC current, A */
    double tau_e;     /* electromagnetic torque incl. cogging, N m */
    double tau_cog;   /* cogging torque, N m */
    double tau_shaft; /* tau_e - B omega - tau_c sign(omega) - tau_fe: what a dynamometer holds, N m */
    double w_l;       /* magnetic energy (L/2) sum i^2, J */
    double d_hold;    /* the hold leg's duty now (BC_LEG_HOLD), or 0 */
} bc_plant_out;

typedef struct {
    double lo, hi; /* bounds of the constant-state interval of a Hall sensor, in the plant's angle frame */
} bc_hall_seg;

/* Observer of every accepted integration step, called at its end with the time (s), acc[] and tau_e (N m) there.
 * The runner (bc_sim) uses it for the continuous PWM-period moving average of the torque. */
typedef void (*bc_plant_step_fn)(void *ctx, double t, const double *acc, double tau);

/* Observer of the terminal voltages over every accepted step of positive length [t0, t1], called before on_step
 * while the terminals are watched (bc_plant_set_terminals): v0, dv0 their values and exact time derivatives just
 * after the step's start (after any gate edge or event there), v1, dv1 at its end (before any), V and V/s, and v_bus1 the DC bus at its
 * end, V. Inside
 * the step they are smooth. The back-EMF sensing of a sensorless drive (bc_sense) filters them. */
typedef void (*bc_plant_term_fn)(void *ctx, double t0, double t1, const double v0[3], const double dv0[3],
                                 const double v1[3], const double dv1[3], double v_bus1);

/* Circuit quantities computed with a derivative (private to bc_plant.c, like bc_plant_work). */
typedef struct {
    double k[3], dk[3], e[3], v[3]; /* shapes, dk/dtheta (when asked for), back-EMFs, terminals (where read) */
    double cs[3];                   /* {theta_a, cos, sin} for Fourier shapes: the libm anchor the evaluation's cos,
                                       sin were rotated from, or its own angle (theta_a = HUGE_VAL: none) */
    double w[3];                    /* averaged legs with R_src: sum_y M_xy i_y */
    double vn, vbus, idc, tau, tau_cog, tau_net, tau_fe, t_fric, p_rsrc;
    double t_prop;                  /* the propeller's load torque k_q omega |omega|, N m */
    double dh;                      /* holding: the hold leg's duty d* (BC_LEG_HOLD) */
    double sgn;                     /* sign of the motion the Coulomb-like drags used (0: no drag) */
    int32_t n_conn;
} bc_plant_aux;

/* The integrator's work memory: the derivative, the electrical torque, the watched functions and (while acc[] is
 * integrated) the rates of acc[] and their time derivatives at the current state, reused as the start of the next
 * step. Private to bc_plant.c: it lives inside bc_plant_state only so that the state stays one caller-owned block
 * (no malloc); the binding does not describe it, and the plant invalidates it (valid = 0) whenever it changes the
 * state itself (init, inputs, half-period start, events). */
typedef struct {
    int32_t valid;              /* 1: the members below hold the current state's values */
    int32_t wdir;               /* speed sign the watches were evaluated with */
    double k1[5];               /* derivative of (i_a, i_b, i_c, theta, omega) at the current state */
    double tau;                 /* tau_e at the current state, N m */
    double w[2][BC_PLANT_NW];   /* watched functions at the current state: w[cur] */
    double cs[3];               /* {theta_a, cos theta_a, sin theta_a} for Fourier shapes: the libm anchor within
                                   0.03 rad of the current angle (theta_a = HUGE_VAL: none), the reference the RK4
                                   stages and the step end rotate from */
    double f[2][BC_ACC_N];      /* rates of acc[] at the current state (valid while acc_on): f[cur] */
    double fd[2][BC_ACC_N];     /* their time derivatives: fd[cur] */
    int32_t a_ok;               /* 1: a[cur] holds the circuit quantities at the current state (a gate edge then
                                   updates the derivative and the power flows from them) */
    bc_plant_aux a[2];
    int32_t cur;                /* which of the double buffers w, f, fd, a is current; the other takes a step's end */
    int32_t out_ok;             /* 1: a[cur] is what core() computes at the stored state (not only at the same
                                   instant: the angle's wrap by 2 pi changes the rounding), for bc_plant_output */
    int32_t th_ok;              /* 1: th_next holds the next angle bound in the direction of motion */
    double th_next;             /* the nearest bound of the back-EMF pieces and Hall intervals ahead, rad (kept
                                   while the pieces and intervals are; an angle event recomputes it) */
    double inv_J;               /* 1 / J with rotor dynamics (set at init), 1/(kg m^2) */
} bc_plant_work;

typedef struct {
    double t;               /* time, s */
    double i[3];            /* phase currents, A */
    double theta;           /* electrical angle, rad, [0, 2 pi) between steps */
    uint32_t turns;         /* electrical turns modulo p: theta_m = (theta + 2 pi turns) / p */
    double omega;           /* mechanical speed, rad/s */
    int32_t stuck;          /* rotor held by Coulomb friction */
    int32_t dir;            /* direction the angle pieces are set for: +1 / -1 */
    /* inputs held over a sample */
    double v_src;           /* DC source voltage, V */
    double tau_load;        /* load torque, N m */
    /* inverter */
    double t_half;          /* start of the current half period, s */
    int32_t rising;         /* 1 in a rising (valley -> peak) half period */
    bc_leg_cmd cmd[3];      /* command in force (sanitised): the half period's, or a scheduled change's from its time */
    int32_t at_on;          /* 1: at_cmd takes over at at_t (bc_plant_schedule) */
    double at_t;            /* its time, s (inside the current half period) */
    bc_leg_cmd at_cmd[3];
    int32_t des[3];         /* desired gate state (from the carrier) */
    int32_t gate[3];        /* actual gate state (after dead time) */
    int32_t edge_to[3];     /* desired state after the pending edge, -1 if none */
    double edge_t[3];       /* time of the pending desired edge, s */
    double t_off_u[3];      /* last time the upper switch turned off, s */
    double t_off_l[3];      /* last time the lower switch turned off, s */
    int32_t cond[3];        /* BC_COND_* */
    int32_t avg[3];         /* 1: leg x applies its half-period average (BC_INV_AVERAGE) */
    double fr_u[3];         /* averaged leg: fraction with the upper switch on */
    double fr_l[3];         /* ... with the lower switch on */
    double fr_o[3];         /* ... with both off */
    int32_t hold_open;      /* bit x: phase x stays open until time advances (a spurious diode turn-on) */
    int32_t hold_x;         /* BC_LEG_HOLD: the leg whose current is held (-1: none) */
    double hold_i;          /* ... the current it holds, A */
    int32_t hold_on;        /* 1: holding (d = d*(y)); 0: free at d = hold_d */
    double hold_d;          /* free duty, 0 or 1 */
    double tc_hcol[3];      /* holding: d(di/dt)/d(d) / v_src, 1/(H) */
    double hold_req, hold_req_at; /* the currents the HOLD legs of the next commands hold (bc_plant_set_hold), A */
    double at_hold;         /* ... of the scheduled change */
    int32_t sw_on;          /* 1 if any of E_on, E_off, E_rr is positive (set at init) */
    double sw_inv_vi;       /* 1 / (V_test I_test), 1/(V A) (0 without switching losses) */
    int32_t fe_on;          /* 1 if k_fe_e, k_fe_h or k_fe_x is positive (set at init) */
    int32_t emf_tables;     /* 1 if the three shapes are tables (set at init) */
    int32_t fz_n;           /* > 0: the three shapes are Fourier series of at most BC_PLANT_FZ_N orders, evaluated from
                               fz_a, fz_b (set at init); 0: from the shapes themselves */
    double fz_a[3][BC_PLANT_FZ_N]; /* k_x(theta) = sum_m fz_a[x][m] cos(m theta) + fz_b[x][m] sin(m theta): the */
    double fz_b[3][BC_PLANT_FZ_N]; /* series of phase x in the global angle (its offset 2 pi x/3 folded in), V s/rad */
    double fe_tc;           /* Coulomb-like hysteresis drag p k_fe_h, N m */
    int32_t drag_on;        /* 1 if B, tau_c or an iron-loss coefficient is positive (set at init) */
    int32_t prop_on;        /* 1 if k_q > 0 with rotor dynamics (set at init) */
    double r_ph;            /* phase resistance now, Ohm: R at init, R r_scale after bc_plant_set_thermal */
    double r_on;            /* switch on-resistance now, Ohm */
    double k_scale;         /* the back-EMF shapes' factor now (magnets' flux at temperature), 1 at init */
    int32_t acc_on;         /* BC_ACC_OFF, _METRICS or _ALL: what is integrated (bc_plant_set_accumulate; _ALL
                               after init) */
    uint32_t acc_mask;      /* bit j: lane j of acc[] is integrated (its rate can be nonzero at this level) */
    int32_t acc_hi;         /* lanes 0 .. acc_hi - 1 are added up each step (1 + the last integrated one) */
    int32_t term_on;        /* 1: the terminal voltages' rates are computed every step for on_term, at any level */
    int32_t lanes_on;       /* 1: the rates f, fd are computed every step (acc_on or term_on) */
    /* circuit coefficients of the present conduction states, set whenever they change (internal) */
    int32_t tc_cond[3];     /* conduction state the coefficients of a switching leg were set for (-1: averaged or
                               none yet) */
    double tc_up[3];        /* 1 if tied to the + rail */
    double tc_u0[3];        /* constant part of the terminal source U_x, V */
    double tc_r[3];         /* device resistance in series, Ohm */
    double tc_conn[3];      /* 1 if connected */
    double tc_rsw[3];       /* switch resistance in series (R_on times the switch fraction), Ohm */
    double tc_dio[3];       /* diode fraction (1 if through a diode) */
    double tc_swk[3];       /* averaged leg: switching-loss power per volt and ampere, f_pwm (E_on + E_off) / (V I)_test
                               if the leg switches hard at the current's sign, else 0, W/(V A) */
    double tc_rrk[3];       /* ... recovery: f_pwm E_rr / (V_test I_test), W/(V A) */
    double tc_lo_a[3], tc_lo_b[3]; /* open phase conducts (i > 0) below U_lo = a v_bus + b, V */
    double tc_hi_a[3], tc_hi_b[3]; /* ... (i < 0) above U_hi = a v_bus + b, V */
    int32_t tc_msrc;        /* averaged legs and R_src > 0: the source drop uses tc_msrc_m */
    double tc_msrc_m[9];    /* M_xy = half-period mean of up_x(t) up_y(t), row-major */
    double tc_inv_n;        /* 1 / connected phases (0 if none) */
    double tc_gain;         /* 1/L if at least two phases conduct, else 0 */
    /* the current derivative as an affine map of the currents and back-EMFs (docs/plant.md, "Integration"):
       di/dt = v_src tc_pup + tc_pu0 - tc_b i - tc_pc (e - sum_y tc_cn_y e_y) */
    double tc_b[9];         /* P (M + R I), row-major, 1/s */
    int32_t tc_b_ok;        /* tc_b has been computed (set by the first topology_set) */
    double tc_pup[3];       /* P up, 1/H */
    double tc_pu0[3];       /* P U0, A/s */
    double tc_pc[3];        /* g c_x (P's diagonal part), 1/H */
    double tc_cn[3];        /* c_x / n */
    int32_t tc_n;           /* connected phases */
    /* angle-dependent pieces */
    bc_emf_piece piece[3];  /* current back-EMF piece per phase (bounds in the global angle frame) */
    bc_hall_seg hseg[3];    /* current Hall interval per sensor */
    int32_t hall_raw;       /* Hall code at the sensors now */
    int32_t hall_true;      /* Hall code after the sensors' delay, before faults */
    int32_t hall_out;       /* Hall code the controller sees (after the delay and the sensor faults) */
    int32_t open_fault;     /* bit x: phase x disconnected now */
    int32_t has_faults;     /* any fault configured (checked once at init) */
    int32_t tripped;        /* the hardware over-current trip has switched the inverter off (latched) */
    double t_trip;          /* when, s */
    double e_fault;         /* magnetic energy lost when a phase with current was disconnected, J */
    uint32_t n_edges;       /* edges seen by the controller */
    double t_edge;          /* time of the last edge seen, s */
    int32_t hq_n;           /* delayed edges waiting, in time order */
    double hq_t[BC_HALL_QUEUE];
    int32_t hq_code[BC_HALL_QUEUE];
    /* RC filter of each sensor line (level 0..1): the last input edge (after the propagation delay) at hf_t, the
       filtered level hf_v there, the input level hf_u since then */
    double hf_t[3], hf_v[3];
    int32_t hf_u[3];
    /* integrals and trackers */
    double acc[BC_ACC_N];
    double tau_min, tau_max; /* extreme tau_e since the last bc_plant_reset_extremes: at every step end and, inside
                                a step, at the turning points of the cubic Hermite interpolant of tau_e through
                                its end values and exact time derivatives (error O(h^4), as the RK4 step) */
    double i_peak[3];        /* largest |i_x| since then */
    double t_zero_i;         /* time with at least two phases open (then every current is zero, no neutral wire:
                                discontinuous conduction), s, integrated while acc_on (each step's conduction
                                state: the events that change it end the steps) */
    int64_t n_zero_i;        /* intervals of it begun while acc_on (t_zero_i / n_zero_i: their mean length) */
    int32_t zero_i;          /* 1 while in such an interval (the last step integrated had every current zero) */
    double t_iz[3];          /* instant of the first end of each phase's current (a diode's, located as an event)
                                since the runner last set it to -1 (bc_sim: at each trace row); -1: none */
    bc_plant_step_fn on_step; /* NULL or called after every accepted step (not copied meaningfully: a runner sets it) */
    void *on_step_ctx;        /* ... and of on_term */
    bc_plant_term_fn on_term; /* NULL or called with the terminal voltages over every step while term_on */
    /* statistics */
    uint32_t flags;          /* BC_PLANT_* */
    int64_t n_steps;         /* accepted RK4 steps */
    int64_t n_events;        /* located events (zero crossings, re-conductions) */
    bc_plant_work work;      /* private to bc_plant.c (see bc_plant_work): never read or written by a caller */
} bc_plant_state;

/* Validate params and set the initial state at time t0 (a half-period boundary), electrical angle theta0,
 * speed omega0, currents i0 (projected to sum zero), DC source v_src, all legs off.
 * Returns BC_OK or BC_ERR_PARAM. */
int bc_plant_init(const bc_plant_params *p, bc_plant_state *s, double t0, double theta0, double omega0,
                  const double i0[3], double v_src);

/* Change the inputs held over the coming sample (imposed speed, load torque, DC source voltage). */
void bc_plant_set_inputs(const bc_plant_params *p, bc_plant_state *s, double omega, double tau_load, double v_src);

/* Start a half period at the current time with the three leg commands (rising = carrier valley -> peak).
 * NaN duties are treated as 0 and out-of-range duties clamped (BC_PLANT_BAD_DUTY is set). */
void bc_plant_set_half(const bc_plant_params *p, bc_plant_state *s, const bc_leg_cmd cmd[3], int rising);

/* Change the leg commands dt seconds after the start of the current half period (a commutation timer): from then on
 * each leg follows cmd on the same carrier, as if it had been commanded for the whole half period (its gate is where
 * cmd puts it at that instant; an averaged leg applies cmd's average). dt >= T/2: ignored (not in this half period);
 * dt <= now: at once. Call after bc_plant_set_half; a new half period cancels a change not yet due. */
void bc_plant_schedule(const bc_plant_params *p, bc_plant_state *s, const bc_leg_cmd cmd[3], double dt);

/* The currents the BC_LEG_HOLD leg of the next bc_plant_set_half (i_hold) and bc_plant_schedule (i_hold_at) holds,
 * A (the ideal current limiter; bc_ctrl_out.i_hold, i_hold_at). */
void bc_plant_set_hold(const bc_plant_params *p, bc_plant_state *s, double i_hold, double i_hold_at);

/* Integrate to t_end (<= the end of the current half period), landing on every event. */
void bc_plant_advance(const bc_plant_params *p, bc_plant_state *s, double t_end);

/* Instantaneous outputs at the current state. */
void bc_plant_output(const bc_plant_params *p, const bc_plant_state *s, bc_plant_out *out);

/* DC bus voltage at the inverter now, V (cheaper than bc_plant_output). Averaged legs count in the gate state they
 * would have at this instant, the carrier peak or valley that ends the half period (active / idle), so the sensors
 * read what they read on the switching plant. */
double bc_plant_vbus(const bc_plant_params *p, const bc_plant_state *s);

/* What the plant integrates besides the state (bc_plant_set_accumulate). */
#define BC_ACC_OFF 0     /* nothing: acc[] and the tau_min/tau_max/i_peak trackers hold their values */
#define BC_ACC_METRICS 1 /* the lanes a metric window reads (all but VA, VB, VC, VN, IDC) and the trackers */
#define BC_ACC_ALL 2     /* every lane (the trace's means of the terminal voltages, star point and DC current too);
                            the level after init */

/* Set what is integrated (BC_ACC_*). The state evolves bit for bit the same at every level; a lane whose rate the
 * parameters keep at zero (no R_src, R_on, diode drop, cogging, friction, iron or averaged switching loss) is never
 * integrated. A runner lowers the level where nothing reads the lanes (outside a metric window, no trace). */
void bc_plant_set_accumulate(const bc_plant_params *p, bc_plant_state *s, int level);

/* Watch the terminal voltages (on = 1): their values and time derivatives are computed at every step's ends and
 * passed to on_term, whatever the accumulation level (the state evolves bit for bit the same). */
void bc_plant_set_terminals(const bc_plant_params *p, bc_plant_state *s, int on);

/* Temperature: from now on the phase resistance is R r_scale, the back-EMF shapes k_scale times theirs (the
 * magnets' remanence; the cogging torque is left as given) and the switches' on-resistance R_on ron_scale. The
 * state is continuous (currents, angle, speed); the circuit's coefficients follow. A thermal model calls it between
 * chunks of a run. Returns BC_ERR_PARAM (nothing changed) unless each scale is finite and > 0. */
int bc_plant_set_thermal(const bc_plant_params *p, bc_plant_state *s, double r_scale, double k_scale,
                         double ron_scale);

/* Electromagnetic torque tau_e at the current state, N m (cheaper than bc_plant_output: cached). */
double bc_plant_tau(const bc_plant_params *p, bc_plant_state *s);

/* Restart the tau_min/tau_max/i_peak trackers from the current state. */
void bc_plant_reset_extremes(const bc_plant_params *p, bc_plant_state *s);

/* Half PWM period, s. */
double bc_plant_t_half(const bc_plant_params *p);

#endif /* BC_PLANT_H */

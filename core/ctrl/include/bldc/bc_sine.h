/*
 * bc_sine.h - sinusoidal current supply of a PM BLDC motor (paper 1, section V): d,q current control on the
 * Hall-interpolated angle, min-max SVM kept in linear modulation, square-wave start (float).
 *
 * Axes (bc_transform.h): q along phase a's back-EMF fundamental (the torque axis), d along the rotor PM flux,
 * 90 degrees behind q; i_d < 0 would weaken the field (not used: i_d,ref = 0). Paper 1 names its torque axis "d"
 * ((45)); its i_d,s,ref is our i_q,ref. The Park angle is theta_d = theta - pi.
 *
 * One sample (T_s = half a PWM period), in this order:
 *
 *  1. Safety. The input guard (bc_guard.h, with i_max and v_max: current reconstruction from i_mask, the DC-bus
 *     limits 0 < v_dc <= v_max, the hardware fault pin, the over-current trip |i_x| > i_max on a measured or
 *     derived phase, latched until every |i_x| < i_max / 2 at a sample with valid measurements, or bc_sine_init),
 *     an invalid Hall code, a non-finite reference (or encoder angle, when used): all legs off (BC_FLAG_SAFE with
 *     BC_FLAG_OVERCURRENT, _HALL_INVALID and/or _BAD_INPUT) and back to the start mode.
 *  2. Angle and speed from bc_hall: theta(k) = theta_edge + Omega_e (t_k - t_edge), Omega_e = (pi/3) / (time
 *     between the last two edges) (paper 1 (46)); or theta = in->theta_enc (angle = BC_SINE_ANGLE_ENCODER, a
 *     reference for comparison); bc_hall uses the calibrated edge table hall_table and, with hall_mode =
 *     BC_HALL_PLL, its tracking loop instead of (46) (bc_hall.h). The speed is always bc_hall's.
 *     omega_m = Omega_e / p. With (46), while the rotor turns one way and the speed is valid, theta never steps
 *     back (it holds at the next edge angle once the edge is overdue, bc_hall.h; the tracking loop may correct
 *     backward by a fraction of the phase error at an edge); a timed-out speed leaves the sine mode (3.).
 *  3. Mode. Start (square wave, bc_sixstep) until |Omega_e| >= omega_on with a valid speed; sine until
 *     |Omega_e| < omega_off (hysteresis) or the speed becomes invalid. With flying_start the start mode first
 *     coasts (legs off) until the rotor is known to be slower than omega_on (a valid speed below it, or no Hall
 *     edge for (pi/3) / omega_on), so that a drive enabled on a fast-turning rotor (a dynamometer) goes straight
 *     to the sine mode after two Hall edges instead of square-wave braking at high speed.
 *  4. Torque reference tau: in->ref (N m), or a speed PI on omega_m (speed_loop = 1, in->omega_ref in rad/s):
 *
 *         tau = PI_w(omega_ref - omega_m),  |tau| <= tau_max,  anti-windup on the torque actually commanded
 *
 *  5. Sine mode, current references (45) and the limits that keep modulation linear:
 *
 *         i_q,ref = tau / (1.5 k_1)                          (45): torque of a current in phase with the
 *                                                            fundamental k_1 (for the ideal trapezoid
 *                                                            1.5 k_1 = 18 k_phi / pi^2, (12))
 *         |i_q,ref| <= i_s_max = I_s,N = 2/sqrt(3) I_N        (8)
 *         |i_q,ref| <= I_s,sat(omega_e, v_dc, sign tau)       (speed_limit = 1)
 *         i_d,ref = 0
 *
 *     I_s,sat is the largest amplitude I >= 0 of balanced currents i_x = s I sin(theta - x 2 pi/3) (s = sign of
 *     tau; in phase with the fundamental, i_q = s I) whose steady-state voltage stays within the linear range at
 *     every angle of the period. With J = s I, the signed current:
 *
 *         v_xy(theta) = omega_m k_xy(theta) + J (R i_xy(theta) + omega_e L di_xy/dtheta(theta))
 *                     = e_xy(theta) + J G_xy(theta)         (pairs ab, bc, ca; i_xy, di_xy of i_q = 1 A)
 *
 *     The voltage this needs, from the grid theta_j = 2 pi j / M (M = BC_SINE_LIM_N; k_xy from the emf_k tables,
 *     i_xy and di_xy/dtheta exact) and margins for the peaks between grid angles:
 *
 *         BC_SINE_LIMIT_HEX:     v_req(omega_e, J) = max_{j,xy} |e_xy(theta_j) + J G_xy(theta_j)| + m_e + |J| m_g
 *         BC_SINE_LIMIT_CIRCLE:  v_req(omega_e, J) = sqrt(3) (max_j |E_j + J G_j| + m_c)   (alpha-beta vectors
 *                                of the line values: alpha = (v_ab - v_ca)/3, beta = v_bc/sqrt(3))
 *
 *         m_e = |omega_m| dev    dev: the largest deviation of k_xy from its chords between grid angles (0 for a
 *                                piecewise-linear shape whose corners are grid angles, e.g. the ideal trapezoid;
 *                                (1 - cos(pi/M)) sqrt(3) k_1 for a sinusoid), sampled at the tables' spacing or finer
 *         m_g = (1 - cos(pi/M)) sqrt(3) |R + j omega_e L|   (the drop is a sinusoid of amplitude sqrt(3) |R + j
 *                                omega_e L| |J|)
 *         m_c = |omega_m| dev_c  dev_c: the excess of |k_alpha,beta| over the chords of its grid values (the drop's
 *                                vector has a constant length)
 *
 *         I_s,sat = 0                                          if v_req(omega_e, 0) > v_dc (the back-EMF alone)
 *         I_s,sat = max {I in [0, i_s_max] : v_req(omega_e, s I) <= v_dc}   otherwise
 *
 *     v_req is convex in J, so the currents that fit form an interval that contains 0. For sinusoidal shapes (R = 0,
 *     HEX) this is sqrt(3) |omega_m k_1 + j omega_e L I| <= v_dc: the back-EMF and the inductive drop add in
 *     quadrature.
 *
 *     v_req is tabulated by bc_sine_init, not scanned at every step. It is convex in omega_e at fixed J (|.| of
 *     functions affine in omega_e, |omega_m|, |R + j omega_e L|) and convex in J at fixed omega_e, so its bilinear
 *     interpolation between nodes over-estimates it (along omega_e on each of the two J nodes, then along J): the
 *     table's I_s,sat is never above the scan's. Nodes, N_W = BC_SINE_LIM_W speed cells (omega_e = 0 is a node) and
 *     N_J = BC_SINE_LIM_J current cells per sign:
 *
 *         omega_n, n = 0 .. N_W: N_F = BC_SINE_LIM_WF cells of w_1 / N_F on each side of 0 up to w_1 =
 *                     BC_SINE_LIM_W1 w_top, then N_W/2 - N_F cells of (w_top - w_1) / (N_W/2 - N_F) up to w_top
 *                     (the resistive drop's share of the voltage, which bends v_req in omega_e, changes fastest at
 *                     low speed)
 *         w_top = p v_max / K_e       v_req(omega_e, 0) = |omega_m| K_e (hexagon: K_e = max |k_xy(theta_j)| + dev;
 *                                     circle: sqrt(3) (max |k_alpha,beta(theta_j)| + dev_c)): beyond w_top the
 *                                     back-EMF alone needs more than v_max >= v_dc, and I_s,sat = 0
 *         J_m = m h,                  m = -N_J .. N_J,  h = i_s_max / N_J
 *         tab[n][m] = floor((v_req(omega_n, J_m) + pad_n - b_n) / q_n) + 1   (uint16, rounded up)
 *                     b_n = min_m v_req(omega_n, J_m), q_n = (max_m v_req + pad_n - b_n) / 65000, pad_n = 1e-6
 *                     max_m v_req + 2e-5 sqrt(3) |R + j omega_n L| i_s_max (covers the float rounding of the
 *                     computation): b_n + q_n tab[n][m] lies between v_req + pad_n and v_req + pad_n + q_n
 *
 *     The node values come from the M grid angles in O(M) per row, not M (2 N_J + 1). Hexagon: since i_xy =
 *     sqrt(3) cos(phi) and di_xy/dtheta = -sqrt(3) sin(phi), phi = theta_j - (2x + 1) pi/3, the line of a pair at
 *     an angle has the slope S(phi) = sqrt(3) (R cos(phi) - omega_e L sin(phi)) in J, and -(e + J G) has S(phi +
 *     pi): the 6 M lines of the |.| fall into M groups of equal slope S_g = S(2 pi g / M), whose largest intercept
 *     alone counts,
 *
 *         max_{j,xy} |e_xy + J G_xy| = max_g (|omega_m| K_g + J S_g)     (omega_m >= 0; K_{g + M/2} if < 0)
 *         K_g = the largest k_xy(theta_j) of the lines of group g, -k_xy(theta_j) of their negatives
 *
 *     S_g = -sqrt(3) |R + j omega_e L| cos(phi_g - phi_0) grows with the distance of phi_g from phi_0 = pi -
 *     atan2(omega_e L, R): the groups taken alternately from both sides of phi_0 come in increasing slope, and the
 *     convex hull trick gives the upper envelope at the J nodes. If K_{-g} = K_g (shapes symmetric about the zero
 *     of their fundamental), v_req(-omega_e, -J) = v_req(omega_e, J) and the rows of omega_e < 0 are copies.
 *     Circle: |E_j + J G_j|^2 = |E_j|^2 + 2 J E_j.G_j + J^2 |R + j omega_e L|^2 at every angle (|G_j| is constant),
 *     the largest of M lines in J at every node (M (2 N_J + 1) multiply-adds a row), then one square root.
 *     bc_sine_init thus costs 0.3 to 0.7 million host instructions with the hexagon (the fewer for a symmetric
 *     shape and 12-point tables: the margins' deviations are sampled at the tables' spacing), 2 million with the
 *     circle, and about 1.3 kB of stack (Cortex-M4, -Os).
 *
 *     Each step (s: the sign of tau):
 *
 *         the cell n of |omega_e| (fine below w_1, coarse above; |omega_e| >= w_top or NaN: I_s,sat = 0), and a in
 *         [0, 1] its position in the cell
 *         V(m) = (1 - a) (b_n + q_n tab[n][N_J + s m]) + a (b_n+1 + q_n+1 tab[n+1][N_J + s m]),  m = 0 .. N_J
 *         V(0) > v_dc (or v_dc NaN): I_s,sat = 0;  V(N_J) <= v_dc: I_s,sat = i_s_max
 *         otherwise the m with V(m) <= v_dc < V(m+1) (bisection, log2 N_J probes) and
 *         I_s,sat = h (m + (v_dc - V(m)) / (V(m+1) - V(m)))
 *
 *     Against the scan (tested in core/tests/test_sine.c and tests/test_sine.py, measured by
 *     benchmarks/sine_limit.py; docs/sine.md, section 4): never above it. Below it by at most 0.75 % of I_s,N on the
 *     catalog drives (measured 0.5 %), 1.5 % on the C test's harsher shapes and 3 % on random Fourier shapes where
 *     the back-EMF alone needs at most 99.5 % of the bus (nearer the no-load speed the scan's limit is steep in v_dc
 *     and, braking, steps); everywhere at least the scan's limit of a bus 0.1 % lower on the catalog drives (1 % and
 *     1.5 % on the others).
 *     Without shape tables (an emf_k pointer is null) the closed form of the ideal 120-degree trapezoid is used
 *     (paper 1 (23) with R):
 *
 *         I_s,sat = (v_dc - 2 k_phi |omega_m|) / g(omega_e)
 *         g = sqrt(3)/2 |omega_e| L + 3/2 R      if |omega_e| L >= R / sqrt(3)
 *         g = sqrt(3) sqrt(R^2 + (omega_e L)^2)  otherwise
 *
 *     the peak line-to-line voltage of balanced currents of peak I is then at most 2 k_phi |omega_m| + g I (for
 *     the trapezoid the back-EMF and the drop add linearly: the drop peaks inside the flat top when (18) holds).
 *     On the trapezoid the table gives the same I_s,sat up to its tolerance; on other shapes (23) is wrong:
 *     for a sinusoid it adds what adds in quadrature and lowers the current well below the base speed. (23) is
 *     also used when the shape tables are all zero (no w_top).
 *  6. Current PIs (bc_pi), output first:
 *
 *         u_d = k_p e_d + x_d + ff_d,   e_d = i_d,ref - i_d,   ff_d = R i_d,ref - omega_e L i_q   (decouple)
 *         u_q = k_p e_q + x_q + ff_q,   e_q = i_q,ref - i_q,   ff_q = R i_q,ref + omega_e L i_d   (decouple)
 *
 *     The rotational voltages use the measured currents: they cancel the motor's d,q coupling (v_d = R i_d +
 *     L di_d/dt - omega_e L i_q, v_q = R i_q + L di_q/dt + omega_e L i_d + e_q), so each PI sees R + s L at any
 *     speed. From the references instead, the coupling stays in the error dynamics and, with R = 0, the loop
 *     L s^2 + (k_p + j omega_e L) s + k_i = 0 has a slow root near -k_i / (k_p + j omega_e L) when omega_e L >> k_p.
 *
 *  7. Voltage angle with delay compensation: the output is applied one sample later and held for one sample, so
 *     it acts on average 1.5 T_s after the measurement: theta_v = theta + advance Omega_e T_s (advance = 1.5).
 *     u_abc = Clarke^-1 Park^-1(u_dq, theta_v - pi).
 *  8. Back-EMF feed-forward (emf_ff = 1): from the per-phase shape tables (emf_n points uniform on [0, 2 pi) of
 *     each phase's local angle, linear interpolation):
 *
 *         f_x = omega_m k_x(theta_v - x 2 pi/3)
 *
 *     so the voltage carries the shape's harmonics and the currents stay sinusoidal (paper 1 (15) assumes
 *     sinusoidal currents).
 *  9. Linear-modulation limit, d axis first: with g_d, g_q the phase voltages of (u_d, 0) and (0, u_q) at theta_v,
 *
 *         v_abc = f_abc + k_d g_d + k_q g_q,  k_d in [0, 1] the largest with f + k_d g_d within the limit, then
 *                                             k_q in [0, 1] the largest with v within it
 *
 *         BC_SINE_LIMIT_HEX:     max_x v_x - min_x v_x <= v_dc    (the whole linear range of min-max SVM; the
 *                                                                 instantaneous form of paper 1 (20) <= V_N)
 *         BC_SINE_LIMIT_CIRCLE:  |Clarke(v_abc)| <= v_dc / sqrt(3) (the hexagon's inscribed circle)
 *
 *     If f alone exceeds the limit it is scaled down to it (k_d = k_q = 0). The PIs update with the realised
 *     outputs: bc_pi_update(e_d, u_d, k_d u_d), bc_pi_update(e_q, u_q, k_q u_q) (anti-windup). The d axis goes
 *     first so that i_d can always be brought back to 0: scaling both together can hold a saturated state with
 *     i_d > 0 in which the q axis needs more than the bus (a hand-off from the square wave at high speed).
 *     overmod = 1 skips the limit (k_d = k_q = 1): the duties clip and the realised voltage, taken back from the
 *     clipped duties, drives the anti-windup.
 * 10. SVM (bc_svm): d_x = 1/2 + (v_x - (max + min)/2) / v_dc, all legs BC_LEG_PWM.
 *
 * Square-wave start: bc_sixstep (composed, its own parameters in `six`, re-initialised on every entry to the start
 * mode) with the torque reference limited to |tau| <= six.k_e sqrt(3)/2 i_s_max, i.e. a square-wave current of at
 * most I_N = sqrt(3)/2 I_s,N (paper 1's equal rms premise (7)); its flags pass through.
 * Hand-off to sine (bumpless): the d,q integrators are set so that the first sine output is the voltage the present
 * state needs (i_d, i_q measured, omega_m k_1 the back-EMF fundamental on q):
 *
 *         x_d = R i_d - omega_e L i_q - ff_d
 *         x_q = R i_q + omega_e L i_d + omega_m k_1 - ff_q - [emf_ff] omega_m k_1
 *
 * Sensorless (angle = BC_SINE_ANGLE_OBSERVER; docs/sensorless-sine.md). No Hall sensor is read (its code is not
 * checked); the angle and the speed come from an observer (observer = BC_SINE_OBS_FLUX: bc_fluxobs.h, or
 * BC_SINE_OBS_REDUCED: bc_redobs.h) fed, at sample k, with the current measured at t_k and the voltage commanded
 * at sample k-2, the one applied over [t_k-1, t_k]: u = Clarke(d_x v_dc - sgn(i_x) v_dc t_dead / (2 T_s)) of its
 * duties and the currents measured when they were computed (the half-period mean of centre-aligned PWM, less the
 * dead time's mean loss: one turn-on delay per PWM period against the current's sign; sgn linear within +-2 % of
 * i_s_max; device drops are not in it). The start mode is I/f, in phases:
 *
 *   IDLE   the reference (tau, or omega_ref with the speed loop) is 0: legs off. Otherwise dir = its sign, ALIGN.
 *   ALIGN  the current vector i_q,ref = dir if_align_current, i_d,ref = 0 in the frame of theta_if = pi/2 for the
 *          first third of if_align, then of theta_if = 0 (two steps: a rotor at the unstable point of one, or held
 *          near it by friction, is a quarter turn from the other's rest angle; the same PIs, decoupling with
 *          omega_if, no back-EMF feed-forward), its amplitude rising linearly over the first tenth of if_align
 *          (holding torque early, against an active load). A larger current than the ramp's narrows the band of
 *          angles in which a load holding the rotor (friction) leaves it away from the rest angle the observer is
 *          seeded with: asin(tau_load / (1.5 k_1 if_align_current)). A current-fed rotor has no damping of its own
 *          and would swing about the vector; its swing's back-EMF e_d lies on d of theta_if (the rotor's q axis
 *          there, for either dir), and i_d,ref = -if_damp e_d (clamped to +-min(if_align_current / 2,
 *          sqrt(i_s_max^2 - if_align_current^2))) brakes it; e_d = x_d, the d PI's integrator, with decouple = 1
 *          (its feed-forward carries R i_d,ref), x_d - R i_d without (x_d - R i_d with decoupling fed the current
 *          back with the gain if_damp R, which above 1 latched i_d at its limit on a rotor at rest). The second
 *          step lasts until if_align and until the swing has died: |e_d| <= psi_f w_q (w_q = BC_SINE_QUIET_K w_a)
 *          for half a swing period pi / w_a, at most until 2 if_align (w_a = (6 pi / if_align) sqrt(if_align_current
 *          / if_current), the swing's frequency at if_align_current on the configured inertia, if_align being three
 *          periods at if_current by default; a swing whose peak speed is above 2 w_q spends less than a sixth of
 *          its period below w_q, so the wait holds up to nine times that inertia). Then the closing sweep: the
 *          vector turns forwards (dir) by beta = 2 asin(min(BC_SINE_RHO_HI if_current / if_align_current, 1)),
 *          twice the band in which a friction load within the design bound holds the rotor off the rest angle, at
 *          w_s = BC_SINE_SWEEP_K w_a (omega_if = dir w_s; the damping then brakes the swing about the turning vector,
 *          i_d,ref = -if_damp (e_d + dir omega_if psi_f), not the motion with it): a rotor held anywhere in that
 *          band is dragged from behind, so the seed below lies ahead of it (dir-wise), an error Lee's observer
 *          removes as the rotor turns (one behind the rotor grows at low speed: section RAMP). An unloaded rotor
 *          settles with its q axis pi/2 behind the vector's (dir = -1: ahead); the observer is seeded there at
 *          the sweep's end: theta^ = theta_if + dir pi/2, omega^ = 0, then RAMP from omega_if = dir min(w_s,
 *          w_cr). Without an alignment (if_align = 0) neither the wait nor the sweep.
 *          With if_r_est = 1 the alignment also measures the resistance the observers use: over its last quarter
 *          (the vector still, the rotor at rest or swinging out) R^ = sum u.i / sum i.i of the applied
 *          alpha-beta voltage (the one the observer takes, dead-time corrected) and the current. At rest the
 *          voltage is R i; a swing's back-EMF adds its mechanical power tau omega_m, whose sum over the window is
 *          the change of the kinetic energy (small once braked). R^ replaces the observers' R from the ramp on if
 *          it is finite, the window's mean |i|^2 at least a quarter of if_align_current^2, and R^ within [R/4, 4 R]
 *          of the configured R (outside: the configured R; with R = 0 configured: within [0, v_max / i]); kept
 *          through the sine mode until the next ALIGN. A wrong R biases the observer most at low speed (R i
 *          against a back-EMF that starts at zero), where the start reads it.
 *   RAMP   omega_if += dir a T_s up to |omega_if| = omega_on, theta_if += omega_if T_s. The rotor follows
 *          with the load angle its torque needs (a torque below 1.5 k_1 if_current). With if_accel_min < if_accel
 *          the ramp adapts to the load: with Delta = theta^ - theta_if (the observer's angle against the vector's)
 *          the rotor's torque is rho 1.5 k_1 if_current, rho = cos Delta (either dir), and
 *          a = if_accel clamp((BC_SINE_RHO_HI - rho) / (BC_SINE_RHO_HI - BC_SINE_RHO_LO), -1, 1): the full ramp
 *          while the torque is at most RHO_LO of the I/f torque, none at RHO_HI, and above it the vector slows
 *          (down to dir omega_if = -omega_on, following a rotor an active load pushes back); at rho >= RHO_HI the
 *          vector does not outrun the rotor (dir omega_if <= dir omega^). A vector turned against dir (dir omega_if
 *          < 0) that has found no lower speed for if_align / 3 (the swing's period at if_current with the default
 *          alignment) drags its rotor, no load pushes it (a rotor pushed back within the I/f torque is caught
 *          within a swing; one still running away makes new lowest speeds): a >= if_accel_min and the rule before
 *          not applied, until dir omega_if >= 0 (a flux error's angle offset at low speed, read as rho = RHO_HI,
 *          otherwise held an unloaded rotor and the vector turning backwards together). A rotor that keeps up
 *          with a vector turning forwards (the observer sees it move, dir omega_if > 0, dir omega_f >= dir
 *          omega_if - w_cr) carries the slowest ramp whatever the observer's angle says: then a >= if_accel_min and the
 *          vector may run ahead of omega^ (below about lambda the observer keeps the error of its seed, which
 *          decays at omega^2 / lambda; a friction load leaves the rotor up to asin(tau_load / (1.5 k_1
 *          if_align_current)) off the seed, read as torque margin the rotor does not have). A rotor the
 *          observer sees at rest (|omega^| < w_cr) is evidence of nothing (the observer holds its
 *          seed, which a load holding the rotor leaves off): then a >= if_accel_min and |omega_if| <= w_cr
 *          (the vector creeps past the rotor's angle of largest torque, where it breaks away). The creep speed and
 *          the trust threshold are w_cr = min(0.05 omega_on, sqrt(2 if_accel_min)): a rotor breaking away from
 *          rest against a load f of the I/f torque tau_if must reach the vector's speed before the vector's lead
 *          passes pi - asin f, where the torque falls below the load again: w_cr^2 <= 2 p tau_if g(f) / J, g(f)
 *          = 2 cos(asin f) - f (pi - 2 asin f); with x = J if_accel_min / (p tau_if), the inertia's share of the
 *          design bound at the slowest ramp, at the bound f = f_b - x that is w_cr^2 <= 2 if_accel_min g(f_b - x)
 *          / x, at least 2.56 if_accel_min whatever the inertia. The
 *          swing about the turning vector is braked through the observer while it sees the rotor move:
 *          i_d,ref = if_damp psi_f (omega^ - omega_if) sin Delta / max(sin^2 Delta, 1/16), within +-min(if_current,
 *          sqrt(i_s_max^2 - if_current^2)), a torque -1.5 k_1 if_damp psi_f (omega^ - omega_if) against the
 *          rotor's slip (the current's torque is 1.5 k_1 (i_q cos Delta - i_d sin Delta)). Below omega_on for longer
 *          than (omega_on - omega_low) / if_accel_min + t_sw (the slowest ramp's time from the vector's lowest speed
 *          dir omega_low, <= 0, reached since the ramp's start, plus the creep's sweep t_sw = (pi / 2) / w_cr: a
 *          rotor held at the seed's rest angle breaks away once the vector has turned from there to
 *          acos(tau_load / (1.5 k_1 if_current)), at most a quarter turn, at the creep's speed): BC_FLAG_START_FAIL |
 *          BC_FLAG_DESYNC, WAIT. The same end, whatever the lowest speed, once the vector has turned against dir
 *          for omega_on / if_accel_min in all, or has been below omega_on for 2 omega_on / if_accel_min + t_sw in
 *          all (the slowest ramp from -omega_on), since the ramp's start (a hand-back's ramp counts on; a
 *          completed ramp resets both): every ramp ends within 2 omega_on / if_accel_min + t_sw, every start
 *          attempt within 2 if_align + beta / w_s + 2 omega_on / if_accel_min + t_sw + if_hold
 *          (a rotor pushed back ever faster, or a vector that follows an observer misled by a wrong R, would
 *          otherwise restart the lowest-speed count). With if_accel_min = if_accel: the fixed ramp at if_accel,
 *          none of this.
 *          At omega_on the lock is checked every sample: |flux / psi_f - 1| <= lock_tol (the observer's flux
 *          output, bc_obs.h), |err| <= lock_tol (its tracking loop's error: rad, or the sine of the angle error)
 *          and dir omega_f >= omega_off (omega_f: omega^ through a low-pass of time constant lock_time). The
 *          observer's own consistency, not its speed against omega_if: the rotor may still swing about the
 *          turning vector at sqrt(p 1.5 k_1 if_current / J) (undamped with the fixed ramp), and the observer
 *          follows the swing. When the lock has held for lock_time
 *          the drive hands over to the sine mode on the observer's angle: the d,q integrators as in the Hall
 *          hand-off below (from the current measured in the observer's frame), the speed PI's integrator at the
 *          torque 1.5 k_1 i_q that current makes (a rotor caught turning against the reference, omega_ref
 *          omega_f < 0: tau_max in the reference's direction, the whole limit to brake it; the slipping I/f
 *          vector's torque pulsates about zero there). Not locked within if_hold at omega_on: BC_FLAG_START_FAIL |
 *          BC_FLAG_DESYNC, WAIT.
 *          With if_psi_est = 1 (flux observer), once a start: at omega_on, when the observer is consistent
 *          (|err| <= lock_tol, dir omega_f >= omega_off) but its flux rho (low-passed like omega_f) is off the
 *          configured psi_f by more than lock_tol / 2 for 2 lock_time, the hand-off waits and the current loops
 *          hold i = 0 (the I/f vector turning on at omega_on, the ramp's law suspended: without current its angle
 *          against theta^ is no torque share): the zero-current reading. With i = 0 the voltage
 *          they apply is the back-EMF alone (R i and L di/dt are zero, whatever R and L); after t_set =
 *          max(lock_time / 2, 10 L / k_p) for the current to settle, psi^ = sum |u| T_s / (the angle u has
 *          turned), summed over at least lock_time / 2 and a whole number of turns of u (the ripple of |u| of a
 *          non-sinusoidal back-EMF averages out; at most t_set + 4 lock_time in all); u the applied voltage the
 *          observer takes (the observer's own speed is not used: its angle settles meanwhile). Why not from the observer with the current on: its steady state on a
 *          rotor turning with the true flux psi_t is rho e^(j phi) = psi_a omega / (omega + j k), k = (lambda / 2)
 *          (1 - rho^2 / psi_c^2), with the apparent flux psi_a = psi_t - (L_c - L_t - j (R_c - R_t) / omega) i
 *          in the rotor's frame: the I/f current of an unloaded rotor lies on its d axis, and a wrong L moves
 *          |psi_a| by -(L_c - L_t) i_d, which a reading with the current on takes for a flux error. psi^
 *          becomes the flux linkage the observer uses and the lock checks if it is within [psi_f / 2, 2 psi_f]
 *          and off the one in use by more than lock_tol / 2; the reading is not repeated until the next ALIGN
 *          (which starts from the configured psi_f again), and the flux no longer holds the hand-off. A reading
 *          during which the observer loses its consistency, the rotor falls below omega_off or the vector leaves
 *          omega_on is dropped (the current back on) and ends the hold too (as without if_psi_est).
 *   WAIT   legs off for restart_wait, then IDLE (and a new ALIGN).
 *
 *   CATCH  (in ALIGN and RAMP, once a start) the observer runs from the first sample of ALIGN; when it is
 *          consistent (|flux / psi_f - 1| <= lock_tol, |err| <= lock_tol) on a rotor turning at least at omega_on
 *          (|omega_f| >= omega_on, either direction) for lock_time, the drive goes to the sine mode at once (the
 *          hand-off below): a rotor turning when the drive starts (a flying start), or one an active load has
 *          pushed through the alignment vector's unstable point and spins backwards (the alignment's stationary
 *          vector cannot catch it: its torque averages zero on a slipping rotor), is driven or braked by the speed
 *          loop with the whole current limit. With zc_catch = 1 each ALIGN (until a catch) first holds i = 0 for
 *          3 lock_time: the current loops in the observer's frame (theta^, omega^) with the back-EMF feed-forward,
 *          the alignment's clock stopped; their voltage is then the back-EMF of a turning rotor, the observer locks
 *          on it without the alignment current's torque pulsating on the slipping rotor; no catch in the window:
 *          the integrators reset and the alignment as above (a rotor at rest, or slower than omega_on).
 *   PULSE  (catch_pulse = 1; the first 6 samples of each ALIGN, before the above) the back-EMF read before any
 *          voltage is applied: legs off, and in the half periods commanded at samples 0 and 3 the zero vector (every
 *          leg LOW at duty 1, from t_at = ts - tau to the half period's end, legs off before) for
 *              tau = min(0.9 ts, L (i_s_max / 3) / e_top),  e_top = 1.25 k_1 v_dc / (2 k_phi)
 *          (the back-EMF vector's amplitude at 1.25 times the no-load speed): the current from zero at the
 *          pulse's end (read two samples after its command), L di/dt = -(e + R i), gives
 *              e = -i R / (1 - exp(-R tau / L))   (R -> 0: -i L / tau),
 *          the first pulse's (from zero current) gives the back-EMF's angle phi_1 and amplitude, |omega| =
 *          |e_1| / psi_f; the second's rise over the current the first left (read at sample 4) only the sign of
 *          the turn between them (3 ts apart; within a factor 4 of |omega| 3 ts, below pi); the rotor's angle
 *          theta = phi_1 + sgn(omega) pi / 2 + omega 3 ts (the back-EMF on q, the d axis at theta - pi).
 *          |omega| >= omega_on: the observer is seeded (theta, omega,
 *          carried on by omega ts until it runs on applied voltages), omega_f = omega, and the zero-current catch
 *          window above runs (with or without zc_catch): its current loops' first voltage is the back-EMF of that
 *          angle. Otherwise the alignment goes on as above; the pulses' currents (at most i_s_max / 3 below
 *          1.25 times the no-load speed) cost 6 samples.
 *
 * In the sine mode the lock is checked every sample with the same band (the speed against itself: only the flux
 * magnitude); violated for lock_time: BC_FLAG_LOCK_LOST | BC_FLAG_DESYNC, legs off, WAIT, then a new start
 * (n_restart counts them). |omega_f| < omega_off (a rotor slowing through the hand-off speed: a reversal, a
 * caught rotor braked, an overload) with the flux in band and a non-zero reference: BC_FLAG_STALL and back to
 * RAMP without turning the legs off (the hand-back), the vector on the rotor's q axis as the observer has it
 * (theta_if = theta^, omega_if = omega^ within +-omega_on, dir the reference's sign), so that the I/f current
 * carries the rotor through the speeds the observer cannot see; its time below omega_on goes on counting from
 * the start's (reset at ALIGN and at a hand-off at the top). Without the flux in band, or with a zero reference:
 * BC_FLAG_STALL | BC_FLAG_DESYNC, WAIT. Turning against the reference (a reversal, a caught backward rotor) the
 * speed must fall: |omega_f| above w_rev + omega_off (w_rev: |omega_f| when it last turned with the reference,
 * or at the catch the larger of |omega_f| and the observer's |omega^|, which the low-pass lags on a rotor an active
 * load accelerates) means the load outweighs the current limit: BC_FLAG_START_FAIL | BC_FLAG_DESYNC, WAIT.
 * diag in this mode: 0 i_d, 1 i_q (A, in the frame used: theta_if in the start mode), 2 i_q,ref (A), 3 v_d, 4 v_q
 * (V), 5 the observer's angle (rad), 6 its speed (electrical rad/s), 7 mode (0 start, 1 sine).
 *
 * diag: 0 i_d (A), 1 i_q (A), 2 i_q,ref (A; in the start mode the sine current of the same torque), 3 v_d (V),
 *       4 v_q (V) (the applied voltage in the frame of theta_v; 0 in the start mode), 5 theta (rad, the angle
 *       used), 6 omega_e (rad/s, Hall), 7 mode (0 square start, 1 sine).
 */
#ifndef BC_SINE_H
#define BC_SINE_H

/* The load-adaptive I/f ramp's band of the torque's share of the I/f torque (section "Sensorless", RAMP). */
#define BC_SINE_RHO_LO 0.6f
#define BC_SINE_RHO_HI 0.95f
#define BC_SINE_SWEEP_K 0.2f  /* ALIGN's closing sweep: its speed w_s over the swing frequency w_a */
#define BC_SINE_QUIET_K 0.025f /* ALIGN: the swing has died below the speed w_q = BC_SINE_QUIET_K w_a */

#include <stdint.h>

#include "bldc/bc_derate.h"
#include "bldc/bc_fluxobs.h"
#include "bldc/bc_guard.h"
#include "bldc/bc_hall.h"
#include "bldc/bc_pi.h"
#include "bldc/bc_redobs.h"
#include "bldc/bc_rest.h"
#include "bldc/bc_sixstep.h"
#include "bldc/bc_transform.h"
#include "bldc/bc_types.h"

#define BC_SINE_ANGLE_HALL 0    /* bc_hall's interpolated angle (46) */
#define BC_SINE_ANGLE_ENCODER 1 /* in->theta_enc (reference sensor) */
#define BC_SINE_ANGLE_OBSERVER 2 /* a rotor-angle observer (sensorless), I/f start-up */

#define BC_SINE_OBS_FLUX 0    /* bc_fluxobs.h: Lee et al. 2010 nonlinear flux observer with a PLL */
#define BC_SINE_OBS_REDUCED 1 /* bc_redobs.h: Hinkkanen et al. 2018 reduced-order observer */

#define BC_SINE_SL_IDLE 0  /* sensorless start: zero reference, legs off */
#define BC_SINE_SL_ALIGN 1 /* the I/f current vector held at its start angle */
#define BC_SINE_SL_RAMP 2  /* the I/f vector turning, its speed ramped to omega_on, then held for the lock */
#define BC_SINE_SL_WAIT 3  /* legs off after a failed start or a lost lock, before the next start */

#define BC_SINE_LIMIT_HEX 0    /* max - min of the phase references <= v_dc */
#define BC_SINE_LIMIT_CIRCLE 1 /* |v_alpha,beta| <= v_dc / sqrt(3) */

#define BC_SINE_MODE_START 0
#define BC_SINE_MODE_SINE 1

#define BC_SINE_EMF_N_MAX 4096 /* largest back-EMF table */
#define BC_SINE_LIM_N 96 /* angles per electrical period the speed limit's table is computed from (multiple of 12,
                             at most 252) */
#define BC_SINE_LIM_W 32    /* speed cells of the speed limit's table over [-w_top, w_top] (even) */
#define BC_SINE_LIM_WF 10   /* of the N_W/2 cells of each side, the fine ones over [0, w_1] */
#define BC_SINE_LIM_W1 0.3f /* w_1 / w_top */
#define BC_SINE_LIM_J 24 /* current cells per torque sign of the speed limit's table over [0, i_s_max] */

typedef struct {
    /* the controller's motor model */
    int32_t p;   /* pole pairs (>= 1) */
    float R;     /* phase resistance, Ohm (>= 0): limits, decoupling, hand-off */
    float L;     /* inclusive phase inductance, H (> 0) */
    float k_phi; /* half the peak line-to-line shape, V s/rad (> 0): voltage limit (23) */
    float k_1;   /* amplitude of the back-EMF fundamental, V s/rad (> 0): (45) */
    /* current loops */
    float ts;       /* sampling period, s (> 0): half the PWM period */
    float kp;       /* d,q PI proportional gain, V/A (>= 0) */
    float ki;       /* d,q PI integral gain, V/(A s) (>= 0) */
    float v_max;    /* bound of the d,q PI integrators and largest plausible DC-bus measurement, V (> 0); sets
                       the speed range of the speed limit's table (5.) */
    float i_s_max;  /* current limit of |i_q,ref|, A (0 < i_s_max <= i_max); paper 1: I_s,N */
    float i_max;    /* over-current trip, A (> 0) */
    int32_t speed_limit; /* 1: |i_q,ref| <= I_s,sat above base speed (from the shape tables if given, else (23)
                            with R); 0: off */
    int32_t decouple;    /* 1: R-L feed-forward ff_d, ff_q; 0: off */
    float advance;       /* voltage angle advance, samples (0 .. 4; 1.5 compensates delay + PWM) */
    /* modulation */
    int32_t limit;   /* BC_SINE_LIMIT_* */
    int32_t overmod; /* 1: no linear limit, duties clip (explicit overmodulation); 0: linear only */
    /* back-EMF feed-forward */
    int32_t emf_ff;          /* 1: add f_x = omega_m k_x(theta_v - x 2 pi/3) */
    int32_t emf_n;           /* points per table (3 .. BC_SINE_EMF_N_MAX) */
    const float *emf_k[3];   /* k_x at local angles 2 pi j / emf_n, V s/rad (phases a, b, c); also used by the
                                speed limit when given (all three non-null) */
    /* angle */
    int32_t angle;      /* BC_SINE_ANGLE_* */
    float f_tick;       /* Hall capture timer, Hz (> 0) */
    float omega_min;    /* Hall: slower than this (electrical rad/s) the speed is invalid (> 0) */
    float theta_offset; /* Hall angle correction, electrical rad */
    int32_t hall_mode;       /* Hall angle: BC_HALL_INTERP (46) or BC_HALL_PLL (bc_hall.h) */
    float hall_pll_edges;    /* BC_HALL_PLL: loop time constant in edges (1 .. 1000) */
    bc_hall_table hall_table; /* calibrated edge angles (set = 0: nominal; bc_hallcal.h) */
    /* square-wave start and hand-off */
    float omega_on;         /* electrical rad/s: sine from |Omega_e| >= omega_on (> 0) */
    float omega_off;        /* electrical rad/s: back to start below (0 <= omega_off <= omega_on) */
    bc_sixstep_params six;  /* the start controller; ref_torque must be 1 (bc_sine passes it a torque) */
    int32_t flying_start;   /* 1: in the start mode, coast (legs off) until the rotor is known to be slower than
                               omega_on: a valid Hall speed below it, or no Hall edge for (pi/3) / omega_on */
    /* optional speed loop */
    int32_t speed_loop; /* 1: tau = PI_w(omega_ref - omega_m) */
    float kp_w;         /* N m / (rad/s) (>= 0) */
    float ki_w;         /* N m / rad (>= 0) */
    float tau_max;      /* torque limit of the speed loop, N m (> 0 when speed_loop) */
    /* sensorless (angle = BC_SINE_ANGLE_OBSERVER; section "Sensorless" above) */
    int32_t observer;          /* BC_SINE_OBS_* */
    bc_fluxobs_params fobs;    /* the flux observer's parameters (observer = BC_SINE_OBS_FLUX; ts must equal ts) */
    bc_redobs_params robs;     /* the reduced-order observer's (observer = BC_SINE_OBS_REDUCED) */
    float if_current; /* I/f current amplitude, A (0 < if_current <= i_s_max) */
    float if_align;   /* time the vector is held at its start angle, s (>= 0) */
    float if_align_current; /* current amplitude of ALIGN, A (0 < if_align_current <= i_s_max) */
    float if_accel;   /* I/f ramp's electrical acceleration, rad/s^2 (> 0): its largest (load-adaptive ramp) */
    float if_accel_min; /* the ramp's smallest acceleration, rad/s^2 (0 < if_accel_min <= if_accel; = if_accel:
                           a fixed ramp) */
    float if_hold;    /* longest time at omega_on waiting for the lock, s (> 0) */
    float lock_time;  /* the lock criterion must hold this long for the handover, its violation for a loss, s (> 0) */
    float lock_tol;   /* relative band of the lock criterion, - (0 .. 1) */
    float restart_wait; /* legs off after a failed start or a lost lock, s (>= 0) */
    float if_damp;      /* swing damping of ALIGN and RAMP, A/V (>= 0) */
    float t_dead;       /* the inverter's dead time, s (0 <= t_dead < ts): the observer's voltage is corrected */
    int32_t if_r_est;   /* 1: the observers use the resistance measured in ALIGN (section "Sensorless"); 0: R of
                           fobs / robs */
    int32_t if_psi_est; /* 1: the flux observer's psi_f read at zero current at omega_on when its flux is off the
                           lock band's half (section "Sensorless", RAMP); 0: psi of fobs. No effect with the
                           reduced-order observer */
    int32_t zc_catch;   /* 1: each ALIGN starts with 3 lock_time at zero current (the catch, section "Sensorless",
                           CATCH); 0: the catch with the alignment's current on */
    int32_t catch_pulse; /* 1: each ALIGN starts with two zero-vector pulses read by the current sensors (section
                            "Sensorless", PULSE): a rotor found turning at least at omega_on seeds the observer and
                            is caught at zero current; 0: none */
    bc_derate_params derate; /* temperature derating of the current limit i_s_max (bc_derate.h) from in->temp; no
                                channel enabled (all zero): none. The start controller derates by six.derate. */
    bc_rest_params rest; /* the winding resistance during operation (bc_rest.h): in sine mode i_d,ref is its square
                            wave; without a winding reading (in->temp[0] not finite) its temperature is the
                            derating's winding input. rest.i_inj = 0: off (then the rest is not checked) */
} bc_sine_params;

typedef struct {
    bc_hall_params hall_p; /* derived in init */
    bc_hall_state hall;
    bc_pi_params pi_p;     /* d and q loops (same gains) */
    bc_pi_state pi_d, pi_q;
    bc_pi_params piw_p;    /* speed loop */
    bc_pi_state pi_w;
    bc_sixstep_state six;  /* the start controller, re-initialised whenever the start mode is entered */
    int32_t mode;    /* BC_SINE_MODE_* */
    bc_guard_params guard_p; /* derived in init: i_max, v_max */
    bc_guard_state guard;    /* input guard: the over-current latch (bc_guard.h) */
    int32_t six_run; /* start mode: the square-wave controller runs (0: coasting, flying_start) */
    int32_t n_quiet; /* samples since the last Hall edge while coasting */
    bc_derate_state derate; /* the derating's filter */
    int32_t derate_on;      /* a derating channel is enabled */
    float derate_f;         /* its factor at the last sample (1 without) */
    bc_rest_state rest;     /* the resistance estimate (rest_on) */
    int32_t rest_on;        /* p->rest.i_inj != 0 */
    /* shape-aware speed limit (5.), filled by bc_sine_init */
    int32_t lim_shape; /* 1: the table below is used; 0: (23) with R */
    float lim_w_top;   /* w_top: the table spans |omega_e| < w_top, electrical rad/s */
    float lim_inv_df;  /* fine cells per rad/s (below w_1) */
    float lim_inv_dc;  /* coarse cells per rad/s (above w_1) */
    float lim_h;       /* current node spacing h = i_s_max / BC_SINE_LIM_J, A */
    float lim_base[BC_SINE_LIM_W + 1]; /* b_n: the smallest v_req of row n, V */
    float lim_q[BC_SINE_LIM_W + 1];    /* q_n: volts per count of row n, V */
    uint16_t lim_tab[BC_SINE_LIM_W + 1][2 * BC_SINE_LIM_J + 1]; /* v_req(omega_n, J_m) ~ b_n + q_n tab (rounded
                                                                    up); column BC_SINE_LIM_J + m is J_m */
    /* sensorless */
    bc_fluxobs_state fobs;
    bc_redobs_state robs;
    int32_t sl_phase;  /* BC_SINE_SL_* (start mode) */
    int32_t sl_dir;    /* +1 / -1: direction of the start */
    float if_theta;    /* I/f angle, rad in [0, 2 pi) */
    float if_omega;    /* I/f electrical speed, rad/s */
    float sl_t;        /* time in the present phase (RAMP: at omega_on; sine mode: below omega_off), s */
    float n_lock;      /* time the lock criterion has held (start) or failed (sine), s */
    float omega_f;     /* the observer's speed low-passed (time constant lock_time), electrical rad/s */
    float if_t;        /* RAMP: time below omega_on, s */
    float if_tb;       /* RAMP: time the vector has turned against dir since the ramp's start, s */
    float if_tr;       /* RAMP: time below omega_on since the ramp's start, s */
    int32_t if_trust;  /* RAMP: 1 while the observer sees the rotor move (adaptive ramp) */
    float rho_f;       /* RAMP: the torque's share of 1.5 k_1 if_current, cos(theta^ - theta_if) */
    float r_obs;       /* the resistance the observer uses, Ohm (if_r_est: measured in the last ALIGN) */
    float psi_obs;     /* the flux linkage the observer uses and the lock checks, V s (if_psi_est: estimated) */
    float flux_f;      /* the observer's flux through the low-pass of omega_f, V s */
    float n_psi;       /* ALIGN, RAMP: time consistent with the flux off the circle since the last estimate, s */
    int32_t psi_adapt; /* if_psi_est: 1 once this start has estimated the flux linkage */
    int32_t psi_done;  /* if_psi_est: 1 once this start has read the flux at zero current (estimate final) */
    float n_zero;      /* RAMP, if_psi_est: time in the zero-current reading, s (0: none) */
    float z_flux, z_w; /* RAMP, if_psi_est: the reading's sums of |u| T_s (V s) and of the angle u turned (rad) */
    float z_n;         /* RAMP, if_psi_est: the samples in those sums */
    float z_u[2];      /* RAMP, if_psi_est: the last sample's voltage in the reading, V (alpha, beta) */
    float z_tgt;       /* RAMP, if_psi_est: the angle u is to turn in the reading, rad (0: not yet set) */
    float n_zc;        /* ALIGN, zc_catch: time at zero current in this alignment, s */
    int32_t al_stage;  /* ALIGN: 0 the two steps, 1 the closing sweep */
    float al_t;        /* ALIGN: time in the closing sweep, s */
    float al_quiet;    /* ALIGN: time the swing's back-EMF has stayed below psi_f w_q, s */
    float r_ui, r_ii;  /* ALIGN: sums of u.i (W) and i.i (A^2) over its last quarter */
    float n_catch;     /* ALIGN, RAMP: time the observer has held a consistent lock at |omega_f| >= omega_on, s */
    int32_t caught;    /* this start has caught a turning rotor (once a start) */
    int32_t fc_k;      /* ALIGN, catch_pulse: samples since the alignment's start while the pulses run (>= 6: done) */
    int32_t fc_on;     /* ALIGN, catch_pulse: the pulses found a turning rotor; its zero-current catch window runs */
    int32_t fc_seed;   /* catch_pulse: the observer carries the pulses' angle and speed until it has voltages to run
                          on */
    float fc_tau;      /* catch_pulse: the pulse length, s (in (0, ts)) */
    float fc_i[2];     /* catch_pulse: the first pulse's current at its end, A (alpha, beta) */
    float fc_i2[2];    /* catch_pulse: the current left at the second pulse's half period's start, A */
    float if_wmin;     /* RAMP: the vector's lowest speed in dir since the ramp's start, electrical rad/s */
    float w_rev;       /* sine mode: |omega_f| when it last turned with the reference (or at the catch), rad/s */
    float u_hist[2][2]; /* alpha-beta voltage commanded one and two samples ago, V */
    int32_t u_ok[2];    /* 1: that voltage was applied by PWM on every leg */
    uint32_t n_restart; /* failed starts and lost locks since init */
} bc_sine_state;

/* Validate the parameters (BC_ERR_PARAM) and reset the state: start mode, integrators 0, trip cleared. */
int bc_sine_init(const bc_sine_params *p, bc_sine_state *s);

/* The current limit of step 5: min(i_s_max, I_s,sat) for the electrical speed omega_e (rad/s), the bus v_dc (V) and
 * the torque's sign sgn (< 0: negative), from the table (or (23) with R without shape tables); i_s_max with
 * speed_limit = 0. Any input (NaN, inf, v_dc <= 0) gives a value in [0, i_s_max]. For diagnostics and tests. */
float bc_sine_i_limit(const bc_sine_params *p, const bc_sine_state *s, float v_dc, float omega_e, float sgn);

/* One sample: measurements in, leg commands for the next half period and diagnostics out. */
void bc_sine_step(const bc_sine_params *p, bc_sine_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);

#endif /* BC_SINE_H */

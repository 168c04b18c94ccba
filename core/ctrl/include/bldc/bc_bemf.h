/*
 * bc_bemf.h - sensorless six-step (square-wave) drive: commutation from the back-EMF of the floating phase, as a
 * drone or RC ESC (AM32, BLHeli) or VESC's BLDC mode does it. Float C99, no Hall sensors, no encoder.
 *
 * The drive it assumes. 120-degree conduction: in sector s (bc_commutation.h) phase pos is driven positive, neg
 * negative, the third phase F = 3 - pos - neg floats. Its back-EMF crosses zero in the middle of the sector, 30
 * electrical degrees after the sector's start, in either direction of rotation; the crossing falls (F's level goes
 * from above to below the reference) in the even sectors and rises in the odd ones, forward and backward alike (the
 * direction reverses both the order of the angles and the sign of the back-EMF). After a commutation the outgoing
 * phase is F: its current freewheels through a diode until it is zero (demagnetisation), which clamps F's terminal
 * to a rail: 0 V (lower diode) if the current was positive, V_dc (upper diode) if negative. For a motoring current
 * that rail is always on the *post-crossing* side of the reference: the comparator shows during the clamp the level
 * the crossing will give. What the comparator shows after a commutation is therefore
 *
 *     [clamp: post level]  ->  [demagnetisation over: pre level]  ->  crossing  ->  [post level]
 *
 * and a demagnetisation that lasts past the crossing hides it (post level throughout): the desync.
 *
 * Inputs (bc_ctrl_in): the comparators (zc_state bit x: phase x above the reference; zc_count[x] edges since start;
 * zc_tick[x] capture tick of the last edge), the ADC samples of the terminal voltages (v_term[x], v_neutral, a new
 * conversion when n_adc changes, sampled at tick_adc), tick_now, v_dc, the phase currents if use_current, and ref.
 * Times are capture-timer ticks (f_tick, wrap-safe unsigned differences); t_k = tick_now. The output applies over
 * [t_a, t_a + T_s), t_a = t_k + D T_s (D = delay).
 *
 * One sample, in order:
 *
 *  1. Input checks. ref finite; 0 < v_dc <= v_max; with use_current the input guard (bc_guard.h: currents of i_mask,
 *     i_max trip latched until every |i_x| < i_max/2, fault pin), else the fault pin alone (BC_FLAG_OVERCURRENT);
 *     with an ADC method, a new conversion's v_term[0..2] and v_neutral finite. Any failure: all legs off,
 *     BC_FLAG_SAFE | the reason, state STOP (a restart then waits as in 3).
 *
 *  2. Throttle. The duty asked for d_ref = min(|ref|, 1) (BC_FLAG_SATURATED above 1), the direction sgn(ref). The
 *     commanded duty moves toward it at most duty_rate T_s per sample (duty_rate in 1/s; 0: no limit):
 *
 *         d_cmd <- d_cmd + clamp(d_ref - d_cmd, -duty_rate T_s, +duty_rate T_s)
 *
 *     and the duty applied is m = min(d_state, d_lim), d_state = align_duty (ALIGN), min(ramp_duty + ramp_vf
 *     Omega_ol, 1) (RAMP, Omega_ol the forced speed of 5 at the start of the output's interval, not a crossing's;
 *     it follows the forced speed within the sector: a voltage-driven rotor runs near the speed whose back-EMF the
 *     duty balances, pulled there with the time constant J 2 (R + R_on) / k_pair^2, a millisecond on a low-R
 *     motor of large k_phi such as lu-4kw: a duty held at the sector's start speed holds the rotor there and
 *     the next sector's duty then drives the back-EMF it does not have; with ramp_vf = k_e / (p V_dc) the back-EMF
 *     is compensated and the current stays near ramp_duty V_dc / (2 R); a false crossing at start-up cannot raise
 *     it; with ramp_tau = L / (R + R_on) the first term is ramp_duty sqrt(1 + (Omega_ol ramp_tau)^2), the drop of
 *     that current on the pair's impedance |R + j Omega L| at the forced speed, so that the inductance does not
 *     take the current as the ramp speeds up), max(d_cmd, duty_min) (CLOSED; d_cmd starts from the ramp's duty at the handover).
 *     Start-up current limit (use_current, i_start > 0; as an ESC's cycle-by-cycle limit): in ALIGN and RAMP a
 *     sample whose largest measured phase current exceeds i_start turns every switch off over the output's interval
 *     (the current returns to the bus through the diodes; a zero vector would short the back-EMF of a moving rotor;
 *     BC_FLAG_SATURATED, the commutation schedule goes on). The ramp's V/f duty assumes a rotor that follows: a rotor held by its
 *     load, or left behind, would see the duty of a back-EMF it does not have, and the current would rise to the
 *     over-current trip (lu-4kw: 6.8 A per mechanical rad/s of lag); limited, the start fails by its hold
 *     (START_FAIL) instead, or the field pulls the rotor when it comes round.
 *     Current limit (use_current,
 *     i_limit > 0), an integrating limiter on the largest measured phase current (d_lim = 1 at init and after a
 *     safe state; without a limit always 1):
 *
 *         d_lim <- clamp(d_lim + k_limit (i_limit - max_x |i_x|) T_s, 0, 1)
 *
 *     A current-limited alignment: align_duty = 1 and i_limit the alignment current.
 *     Speed-dependent duty limit (dlim_d0 > 0; no current sensor needed, as an ESC's low-speed throttle limit): in
 *     CLOSED m <= dlim_d0 sqrt(1 + (Omega dlim_tau)^2) + dlim_vf Omega, Omega the speed estimate of 7. With
 *     dlim_vf = 2 k_phi / (p V_dc) (the back-EMF's duty), dlim_d0 = 2 (R + R_on) I / V_dc and dlim_tau = L / (R +
 *     R_on) (the pair's impedance at the electrical speed) the pair's current stays near I whatever the throttle
 *     does: a throttle step cannot trip the drive at low speed.
 *     The inverter's share (d_diode): the three duties above (align_duty, the ramp's law, the speed-dependent limit)
 *     are those of an ideal inverter, d_s = u / V_dc for the pair voltage u; the duty applied is d_diode + (1 -
 *     d_diode) d_s. A pattern that leaves the chopping leg's current to a diode in the off-time (HIGH, PWMPWM,
 *     BIPOLAR) puts the leg at -V_d there instead of near 0 (the pair at -(V_dc + 2 V_d) instead of -V_dc, BIPOLAR),
 *     V_d = V_f + (r_d - R_on) I: u = m (V_dc + V_d) - V_d, so d_diode = V_d / (V_dc + V_d); SYNC loses the dead time
 *     before each turn-on of the chopping switch and after each turn-off to the diode, d_diode = t_dead f_pwm (V_dc +
 *     2 V_f) / V_dc (to first order). At the alignment's few percent of duty the drop is the whole difference:
 *     f60prov-2550kv (0.034 at 16.8 V) with a 0.7 V diode and d_diode = 0 drives no current at all in the high-side
 *     pattern.
 *     Demagnetisation limiter (demag_max > 0), at each crossing in CLOSED whose sector's demagnetisation was
 *     measured (6): r = Omega t_demag / (pi/6 + adv), the share of the window from the commutation to the crossing
 *     that the clamp took; the duty cap
 *
 *         d_dm <- clamp(min(d_dm, m + 0.05) + 0.2 (demag_max - r), 0, 1)       (m: the duty applied)
 *
 *     falls while the clamp takes more than demag_max of the window (the current, and with it the clamp, falls
 *     with the duty) and recovers while it takes less; m <= d_dm in CLOSED. A blind commutation (9) scales d_dm by
 *     0.7. This keeps the crossing visible through a throttle step whatever the load does (docs/sensorless.md).
 *
 *  3. States. STOP (all legs off, coasting: not the safe state, no BC_FLAG_SAFE) -> ALIGN (align_time > 0) or RAMP
 *     (direct start, align_time = 0) -> CLOSED; a desync, |ref| <= ref_stop or a change of sign of ref goes back to
 *     STOP. STOP starts when |ref| > ref_stop and either the controller has never run (the rotor is taken to be at
 *     rest after init), or the comparators have been quiet (no edge on any phase) for restart_wait and STOP has
 *     lasted restart_wait, or STOP has lasted restart_max: a rotor still turning after a desync or a stop coasts down
 *     before a new start, and a reverse (sign change) is a stop followed by a start the other way.
 *
 *  4. ALIGN at align_duty for align_time, all three legs driven with the pattern chop (two phases in parallel against
 *     the third, so that the motion induces a current in the parallel pair's loop that damps the rotor: a drone
 *     rotor has almost no friction, and a pair alone, whose loop sees no back-EMF at its own equilibrium, leaves it
 *     swinging): for 2/7 of align_time a+ and b+ against c- (the rotor to theta_e = 4 pi/3), for 1/7 a+ and c+
 *     against b- (to 2 pi/3: off the last step's dead point 0, which a held rotor creeping from the first step's
 *     dead point can reach), then for the last 4/7 a+ against b- and c- (to theta_e = pi, the middle of sector 2).
 *     RAMP then commands sector 2 from t_a in either direction, for the open-loop time of 30 degrees. A direct start
 *     (align_time = 0) commands sector 2 (forward) or 1 (backward) for a whole sector.
 *
 *  5. RAMP (forced commutation). The open-loop speed Omega_ol(t) = min(ramp_w0 + ramp_accel t, ramp_w1) (electrical
 *     rad/s, t since the ramp began); a forced sector begun at t_c with Omega_ol = w ends when the open-loop angle
 *     has advanced pi/3, at t_c + tau(w):
 *
 *         tau = 2 (pi/3) / (w + sqrt(w^2 + 2 ramp_accel pi/3))      (below the cap; with the cap reached on the way:
 *                                                                     the time to it plus the rest at ramp_w1)
 *
 *     scheduled with the commutation timer (8). The zero-crossing detector (6) runs in every forced sector (its
 *     speed: w, or the speed from the last forced sector's crossing if higher). A sector with an accepted crossing
 *     counts as valid, one without resets the count. At a crossing:
 *       - handover to CLOSED when it makes n_handover consecutive valid sectors, the speed from its crossing
 *         interval T (two valid sectors in a row) is at least 1.5 omega_stall (a margin above the stall limit),
 *         and the crossings are a turning rotor's: the last m = min(valid, BC_BEMF_HO_FIT) of them (m >= 5; fewer:
 *         no check), at angles k pi/3, fitted by least squares with c0 + c1 t + c2 t^2 + c3 (-1)^k (a constant
 *         acceleration, rising and falling crossings displaced oppositely by c3): |c3| and each crossing's
 *         distance from the fit within (pi/6) (jump_max - 1) / (jump_max + 1) (the displacement of alternate
 *         crossings the closed loop's jump check tolerates) and |2 c2| <= BC_BEMF_HO_ACC ramp_accel (if
 *         ramp_accel > 0): a held rotor's twitch gives crossings that are not (docs/sensorless.md, law 5).
 *         T60 = T, and the commutation is scheduled from that crossing as in 7;
 *       - else the crossing commutates the forced sector pi/6 / w_c after it if that comes before the forced instant
 *         (w_c = (pi/3) / T, or (pi/6) / (t_zc - t_c) without T: the rotor crossed 30 degrees after the sector
 *         began), as an ESC does as soon as it sees the back-EMF: a rotor faster than the ramp is followed, not left
 *         to run ahead of the field.
 *     A rotor that leads the forced field by more than 30 degrees crosses before the window opens: if F shows the
 *     post level from the window's opening until half the forced sector (tau / 2 after t_c; a clamp ends long
 *     before that at start-up currents), the sector is cut short: the next one is commanded from t_a (not a valid
 *     crossing). After ramp_hold forced sectors begun at ramp_w1 without a handover: desync BC_FLAG_START_FAIL.
 *
 *  6. Zero-crossing detection on F, after the commutation at t_c that began the sector. The window opens at
 *
 *         t_open = t_c + max(blank_angle / Omega, blank_time)       (Omega: the speed estimate, 7, or that of 5)
 *
 *     The fixed blanking must cover the comparator's view of the clamp's onset (its filter and propagation delay:
 *     a window that opens before the clamp shows takes the clamp's onset for a crossing). A post level that is
 *     already there when the window opens is never a crossing: it is the clamp, or a crossing that came before the
 *     window ("a crossing already past", rejected: the controller waits for an edge; if none comes, 9 decides; in
 *     RAMP, 5's lead rule). post = F's level after the crossing (even sector: below, odd: above).
 *
 *     Comparator (method BC_BEMF_COMPARATOR). The crossing is the first edge into the post level inside the window
 *     (its tick t_e >= t_open, zc_count[F] changed since the last sample before the window), once the post level
 *     has been held min_pulse since that edge (the minimum-pulse filter: t_k - t_e >= min_pulse; a later edge
 *     restarts it). The demagnetisation's end is the first sample in the window showing the pre level: t_dm = its
 *     edge's tick if that edge came after t_c, else t_c (no clamp seen). With blanking = BC_BEMF_BLANK_DEMAG the
 *     crossing's window opens there: the edge into post must come at least min_pulse after t_dm (a short return to
 *     the pre level inside the clamp, ringing, does not end it); a pre level shorter than a sample (two edges
 *     between samples) is not measured and the crossing is accepted as with BC_BEMF_BLANK_FIXED, which needs no
 *     pre level at a sample: the first edge into post in the window.
 *     Blind off-times (cmp_blind = 1; BC_CHOP_SYNC or BC_CHOP_HIGH): the pair's off-time holds both its terminals
 *     at the negative rail, and with ideal diodes (no forward voltage) a floating terminal clamped there by its
 *     lower diode reads exactly the star reference: the comparator holds its level, and a crossing in the off-time
 *     shows late, at most at the next on-time's start. The pair's off-time is centred at a carrier valley v (its
 *     active state next to the peak; even samples are valleys, the first sample is taken to be one), of half-width
 *     h = (1 - m) T_s (m: the duty of the last output). An accepted edge whose comparator input changed, t_e -
 *     t_comp, within [v - h, v + h + tol] of the valley v nearest it (tol = min_pulse + 2 tau_filter + 1 / f_tick,
 *     at most half the on-time m T_s: the floating phase's off-time current decays and the filter settles after
 *     the on-time's start, and the capture tick) came from a crossing in that off-time, and is placed there:
 *     into the clamped level (below, even sectors) F reads the reference from the crossing until the on-time shows
 *     it, so the crossing lay anywhere in the off-time: t_z = v; out of it (above, odd sectors) F's diode current,
 *     built from v - h while its back-EMF was below, decays as long after the crossing as it grew (a linear
 *     back-EMF): an edge inside the off-time (before v + h - 1 / f_tick) gives t_z = (t_e - t_comp + v - h) / 2,
 *     one at the on-time's start t_z in [v, v + h], its middle v + h/2. Unbiased where the carrier and the rotor
 *     are not synchronous, each within h of the crossing; t_e is taken as t_z + t_comp (the filter's delay of 7
 *     still applies). An edge in an on-time is the crossing as before. Not while the fast pattern (8) may have
 *     been in force over that off-time (it centres the pair's on-time at the valley): from the sample that first
 *     sees the pre level in the window its outputs are the plain pattern, from t_a on.
 *
 *     ADC (BC_BEMF_ADC, BC_BEMF_INTEGRATE). At each new conversion sampled at t >= t_open, the sign-corrected sample
 *     u = s_F (v_term[F] - v_neutral), s_F = +1 (post above) or -1, is post when u > 0. The crossing needs a pre
 *     sample (u <= 0) in the window, then n_samples consecutive post samples (the N-consistent-samples filter; a
 *     pre sample in between restarts it); it is placed by linear interpolation between the last pre sample
 *     (t0, u0) and the first post one (t1, u1):  t_e = t0 + (t1 - t0) (-u0) / (u1 - u0). The demagnetisation end
 *     t_dm is the first pre sample in the window (resolution: one conversion). Every level is seen at a conversion,
 *     so the two blankings are the same rule here.
 *     Clamped samples: a conversion with v_term[F] within v_dc/32 of a rail (or beyond) shows F conducting through a
 *     diode: the outgoing current, or (high-side or synchronous chopping) a current F's back-EMF drove in the PWM
 *     off-time that has not decayed by the conversion. Its level counts (the rail is on the side F's current, and
 *     so its back-EMF, pushes it), its value is no back-EMF and is never used: the interpolation runs between the
 *     last free pre sample and the first post one (kept inside (t0, t1]); with the pre end clamped, back from the
 *     free post sample along the last crossing's slope (the middle of the bracket before the first), refined at the
 *     next free post sample from the line through the two. The band: a free F sits at v_dc/2 + e_F - (e_p + e_q)/2
 *     in the pair's on-time (centre-aligned PWM, the default conversion instant), at least 0.046 v_dc from either
 *     rail up to 30 degrees after its crossing for any motoring duty (a sinusoid at full duty and no load; the ideal
 *     trapezoid 0.25 v_dc); the diode puts a conducting F beyond the rail, so the band covers the ADC's noise and
 *     step only. Sampled in the off-time, a free F near its crossing is near a rail too (and read as clamped).
 *
 *     Measured demagnetisation (diag 4): t_demag = t_dm - t_c - the delays of 7 (the filter's, and the comparator's
 *     propagation with BC_BEMF_COMPARATOR; exact for a pure delay, an RC filter shows a step tau ln 2 late rather
 *     than atan(Omega tau)/Omega), at least 0; measured with either blanking.
 *
 *  7. Commutation from the crossing (CLOSED; also the handover of 5). The true crossing, the filter and comparator
 *     delays compensated, and the interval estimate:
 *
 *         t_zc = t_e - atan(Omega tau_filter) / Omega - t_comp       (t_comp: comparator only, 0 for the ADC methods)
 *         T    = t_zc - t_zc,prev;   T60 <- T60 + t60_gain (T - T60);   Omega = (pi/3) / T60
 *
 *     (the first-order RC filter of the terminal divider delays a sinusoid by its phase lag atan(Omega tau) / Omega,
 *     a ramp by tau; the compensation uses the estimate before this crossing). Advance:
 *
 *         adv = min(adv_angle + Omega adv_time + adv_demag Omega t_demag, adv_max)      (t_demag: last measured, 6)
 *
 *     BC_BEMF_COMPARATOR, BC_BEMF_ADC: the next commutation at  t_zc + (pi/6 - adv) / Omega.
 *     Uniform grid (grid_gain > 0, comparator and ADC): a motor whose phases' back-EMFs differ (shifted, scaled)
 *     crosses zero off the magnet's 60-degree grid, and 30 degrees after each crossing is not where a Hall drive
 *     commutates. Each sector's crossing interval is filtered, T_s <- T_s + grid_gain (T - T_s) (in the order of
 *     rotation; reset at the handover), and once twelve have been learned the crossing of sector s is placed on the
 *     uniform grid through the mean of the six. Each interval is taken relative to the mean of the last six, r = T /
 *     mean(T_k-5 .. T_k) (a rotor's acceleration changes every sector's r alike), r_s <- r_s + grid_gain (r - r_s)
 *     for its sector s; with rho_s = r_s / mean r and P_s the cumulative sum of (rho_j - 1) in the order of rotation,
 *     D_s = (P_s - mean P) Tn (the crossing's lag behind the grid, at most 10 degrees), where the grid's interval
 *     Tn <- Tn + t60_gain (T / rho_s - Tn); the commutation at t_zc - D_s + (pi/6 - adv) Tn / (pi/3): every
 *     commutation a uniform 60 degrees apart, phase-locked to the crossings' mean, the Hall drive's symmetric
 *     placement. Bounded by the demagnetisation: a grid point later than the plain instant t_zc + (pi/6 - adv) /
 *     Omega is taken only up to the latest instant that leaves the next crossing visible, t_z1 - need, never
 *     earlier than the plain instant (a grid point earlier than it is taken as it is: it lengthens the window).
 *     t_z1 = t_zc + min(T60, Tn - D_s + D_s+1), the next crossing by the earlier of the two estimates; need =
 *     max(dm / demag_max (dm without the limiter), blanking) + min_pulse, dm the longest demagnetisation measured
 *     in the last six sectors (both crossing directions; a sector whose pre level no sample saw: the time from its
 *     commutation to its crossing less one sample). The window then holds the clamp as at most the share the
 *     limiter of 2 keeps. Steady, with each phase's two crossings equally off the magnet's grid (a shifted phase),
 *     the grid's shortest window is never shorter than the plain one's (30 degrees plus the smallest offset less
 *     their mean, against at most the smallest less the largest) and the bound rarely acts; it acts in a
 *     transient, where the grid's interval lags the rotor (servo-2k2's throttle step at zero advance: up to 12
 *     degrees late unbounded, the crossing hidden).
 *     BC_BEMF_INTEGRATE (VESC's BLDC mode): from the crossing the sign-corrected samples are integrated by the
 *     trapezoidal rule (the first piece from t_e, where u = 0); except after a falling crossing (sectors 0, 2, 4)
 *     with chop BC_CHOP_SYNC or BC_CHOP_HIGH and tau_filter > 0, which commutate as BC_BEMF_ADC does: there the
 *     floating phase conducts in every off-time and the filter carries that into each conversion,
 *
 *         lambda(t) = integral from t_e to t of u dt,      commutation when  lambda = int_limit ((pi/6 - adv)/(pi/6))^2
 *
 *     int_limit (V s) is the integral from the crossing to 30 degrees; for a back-EMF proportional to speed the
 *     integral over an angle does not depend on the speed (e = k Omega (theta - theta_zc) gives lambda =
 *     k (theta - theta_zc)^2 / 2), which is why the threshold is speed-independent, and the square scales it to
 *     30 - adv (exact for a linear ramp, 1.3 % off at 10 degrees for a sinusoid). After each conversion the instant
 *     is predicted from the last sample u_j and slope r (from the previous post sample; for the first, from the last
 *     pre sample, as the interpolation; clamped >= 0): lambda_j + u_j tau + r tau^2 / 2 = threshold, commutation at
 *     t_j + tau - atan(Omega tau_filter) / Omega (a threshold already passed: interpolated back between the samples).
 *     A clamped sample (6) is not integrated: the instant stays the one predicted from the last free sample, and the
 *     next free one adds the trapezoid over the whole gap (exact for a linear ramp).
 *     It is committed once it falls before the end of the interval the output applies to (8), else predicted again
 *     from the next conversion. Not reached by t_zc + (pi/3) / Omega (60 degrees after the crossing): at once.
 *
 *     Checks at each accepted crossing in CLOSED (a desync, 10): T / T_prev outside [1/jump_max, jump_max] (T_prev:
 *     the previous interval between two real crossings) -> BC_FLAG_ZC_JUMP; Omega < omega_stall -> BC_FLAG_STALL.
 *
 *  8. Commutation timer. A commutation due at t_n (7, or 5) is issued by the first output whose interval
 *     [t_a, t_a + T_s) it falls before the end of: t_n >= t_a: out->has_at = 1, out->t_at = t_n - t_a, the current
 *     sector's legs in out->leg and the next sector's in out->leg_at (the plant switches at t_n exactly); t_n < t_a
 *     (already past): the next sector's legs from t_a, BC_FLAG_COMM_LATE (with delay = 1 a crossing seen at t_k can
 *     move the legs at t_k + T_s at the earliest). At most one commutation per half period. The next sector:
 *     s + 1 forward, s - 1 backward; its legs: bc_pair_legs (bc_commutation.h) with the pattern chop, the pair
 *     voltage m, pos and neg swapped backward. BC_CHOP_PWMPWM chops the incoming phase (the one that entered the
 *     pair at the last commutation) during the first half of the sector (Omega (t_a - t_c) < pi/6) and the
 *     continuing one after; the other patterns chop pos.
 *     Fast demagnetisation (fast_demag = 1; BC_CHOP_SYNC, _HIGH, _PWMPWM; not in a start's first sector, which
 *     has no outgoing phase): from the output whose interval ends with the clamp on for fd_after of the window pi/6 + adv
 *     (fd_after = 0: from the commutation) until the detector has seen the demagnetisation over (the pre level, 6)
 *     or a crossing, the continuing phase (in both pairs) chops instead: as BC_LEG_PWM with its average at the same pair voltage m (sync), else its own switch at m. The
 *     outgoing phase's current, averaged over the PWM, then falls with (2 - m) V_dc / 3 plus the back-EMF term
 *     instead of m V_dc / 3 when the pattern would chop the incoming phase (docs/sensorless.md, the closed forms):
 *     at low duty and high current the difference between a visible crossing and a hidden one. A clamp shorter
 *     than fd_after of the window never sees the pattern change, so the drive's torque is that of the plain
 *     pattern (the fast fall of the outgoing current dips the torque in each commutation).
 *     Dead time (BC_CHOP_SYNC): a complementary leg loses one dead time a period to a diode, the positive leg (its
 *     current > 0) at each turn-on of its upper switch, the fast pattern's negative leg (< 0) at each turn-off;
 *     changing from one to the other costs one dead time more per episode, t_dead (V_dc + V_f) of the pair's
 *     volt-seconds. The first whole half period the fast pattern is issued in (not the leg_at part of a
 *     commutation's sample) makes it up: the negative leg at 1 - m - 2 d_diode (SYNC's d_diode, 2, is the dead
 *     time's share of a period, so 2 d_diode is one dead time in a half period); every later one at 1 - m.
 *     When it chops the negative leg, the pair's off-time holds both its terminals at V_dc, and between the clamp's
 *     end and the sample that sees it the floating phase (still on its pre side, e_F > 0) can clamp to V_dc in the
 *     off-times, where a comparator with an offset reads the post level: in such a sector (cmp_gate = 1; with a
 *     comparator of no offset the clamp reads exactly the reference and changes nothing) the comparator is read
 *     (once the pattern is engaged) only at the samples in the pair's on-time (an active switch state is centred at the carrier peak: the
 *     valleys for the complementary negative leg of BC_CHOP_SYNC, the peaks for a lower switch chopping; the
 *     first sample is taken to be at a valley) until the crossing.
 *
 *  9. Timeout (CLOSED). No crossing accepted by t_zc,prev + max(zc_timeout T60, T_b + (zc_timeout - 1) T60)
 *     (zc_timeout = 1.5: when the next commutation would be due without advance; T_b, with brake_tau > 0: the
 *     latest the next crossing can come for a rotor braked as hard as the drive can, dw/dt = -w / tau - brake_acc,
 *     1 / tau = 1 / brake_tau + brake_q w0, from w0 = (pi/3) / T, T the last interval (T60 without one): its angle (w0 + a tau) tau (1 -
 *     exp(-t / tau)) - a tau t reaches pi/3 at T_b, or, if its speed falls below omega_stall first, T_b is the time
 *     to it): with fewer than miss_max misses in a row, a blind commutation at
 *     once (BC_FLAG_COMM_LATE) and a virtual crossing t_zc,prev += T60 (T60 kept; no jump check on the next
 *     interval); otherwise a desync, BC_FLAG_ZC_HIDDEN if F never showed the pre level in the window (the
 *     demagnetisation outlasted the crossing, or the crossing came before the window), else BC_FLAG_ZC_TIMEOUT (it
 *     left the clamp, and no crossing followed: the rotor slowed or stopped).
 *
 * 10. Desync: BC_FLAG_DESYNC | the reason's flag at that sample, all legs off from t_a, state STOP (the restart
 *     rule of 3). The reason stays in diag 7 until the next start.
 *
 * Reference: in->ref = duty (throttle) in [-1, 1], its sign the direction of rotation. Output duties are finite and
 * in [0, 1] for any input; flags as above; BC_FLAG_OPEN_LOOP at every sample of ALIGN and RAMP.
 *
 * Diagnostics: diag[0] state (0 STOP, 1 ALIGN, 2 RAMP, 3 CLOSED; -1 safe), [1] sector commanded at the start of the
 * output's interval (ALIGN: 0; -1 legs off), [2] speed estimate Omega (electrical rad/s, signed by the direction;
 * in RAMP that of 5, in STOP 0), [3]
 * commutation error at the last crossing, rad: the crossing's angle after the commutation that began its sector,
 * Omega (t_zc - t_c), minus the expected pi/6 + adv (positive: the commutation came early for the rotor), [4]
 * demagnetisation time last measured (6), s, [5] advance adv computed at the last crossing, rad, [6] duty m applied,
 * [7] desync reason (0 none, 1 ZC_TIMEOUT, 2 ZC_HIDDEN, 3 ZC_JUMP, 4 STALL, 5 START_FAIL).
 */
#ifndef BC_BEMF_H
#define BC_BEMF_H

#include <stdint.h>

#include "bldc/bc_guard.h"
#include "bldc/bc_types.h"

/* crossing detection and commutation method */
#define BC_BEMF_COMPARATOR 0 /* comparator edges; commutation 30 - adv degrees after the crossing */
#define BC_BEMF_ADC 1        /* ADC samples, N consistent, interpolated; commutation 30 - adv degrees after */
#define BC_BEMF_INTEGRATE 2  /* ADC crossing, then the back-EMF integral to int_limit (VESC's BLDC mode) */

/* blanking after a commutation */
#define BC_BEMF_BLANK_FIXED 0 /* the window opens at t_c + max(blank_angle / Omega, blank_time) */
#define BC_BEMF_BLANK_DEMAG 1 /* ... and the crossing's window at the measured end of the demagnetisation */

/* states (diag[0]) */
#define BC_BEMF_STOP 0
#define BC_BEMF_ALIGN 1
#define BC_BEMF_RAMP 2
#define BC_BEMF_CLOSED 3

/* desync reasons (diag[7]) */
#define BC_BEMF_REASON_NONE 0
#define BC_BEMF_REASON_TIMEOUT 1
#define BC_BEMF_REASON_HIDDEN 2
#define BC_BEMF_REASON_JUMP 3
#define BC_BEMF_REASON_STALL 4
#define BC_BEMF_REASON_START 5

/* crossings fitted at the handover (5): the last six crossing intervals */
#define BC_BEMF_HO_FIT 7
/* the largest acceleration of a handover's fit, in ramp_accel (5) */
#define BC_BEMF_HO_ACC 4.0f

typedef struct {
    int32_t method;      /* BC_BEMF_COMPARATOR, _ADC, _INTEGRATE */
    int32_t chop;        /* BC_CHOP_BIPOLAR, _HIGH, _PWMPWM, _SYNC (bc_commutation.h) */
    int32_t delay;       /* samples between computing and applying an output, 0 or 1 */
    int32_t blanking;    /* BC_BEMF_BLANK_FIXED or _DEMAG */
    float ts;            /* sampling period, half the PWM period, s (> 0) */
    float f_tick;        /* capture-timer frequency, Hz (> 0) */
    float blank_angle;   /* blanking after a commutation, electrical rad, [0, pi/3) */
    float blank_time;    /* blanking after a commutation, s (>= 0; the larger of the two applies) */
    float min_pulse;     /* comparator: post level held at least this long after its edge, s (>= 0) */
    int32_t n_samples;   /* ADC: consecutive post samples for a crossing (1 .. 16) */
    float tau_filter;    /* time constant of the terminal voltages' RC filter, s (>= 0) */
    float t_comp;        /* comparator propagation delay, s (>= 0) */
    float adv_angle;     /* timing advance, electrical rad (>= 0) */
    float adv_time;      /* timing advance per speed, s: + Omega adv_time (>= 0) */
    float adv_demag;     /* automatic advance: + adv_demag x the measured demagnetisation angle (>= 0) */
    float adv_max;       /* cap of the total advance, electrical rad, [0, pi/6] */
    float t60_gain;      /* gain of the crossing-interval filter, (0, 1] (1: the last interval) */
    float int_limit;     /* BC_BEMF_INTEGRATE: back-EMF integral from the crossing to 30 degrees, V s (> 0) */
    float zc_timeout;    /* crossing missing after zc_timeout T60 from the previous crossing, [1.05, 4] */
    float jump_max;      /* largest ratio of successive crossing intervals, > 1 */
    int32_t miss_max;    /* blind commutations in a row before a desync (0 .. 100) */
    float omega_stall;   /* slowest closed-loop speed, electrical rad/s (> 0) */
    float align_time;    /* alignment, s (>= 0; 0: direct start) */
    float align_duty;    /* duty of the alignment, [0, 1] */
    float ramp_w0;       /* open-loop speed at the start of the ramp, electrical rad/s (>= 0) */
    float ramp_w1;       /* open-loop speed at its end, electrical rad/s (>= ramp_w0, >= 1.5 omega_stall) */
    float ramp_accel;    /* open-loop acceleration, electrical rad/s^2 (>= 0; > 0 if ramp_w0 = 0) */
    float ramp_duty;     /* duty of the forced commutation at standstill, [0, 1] */
    float ramp_vf;       /* ... plus ramp_vf per electrical rad/s of the speed estimate (V/f), 1/(rad/s) (>= 0) */
    float ramp_tau;      /* the pair's L / (R + R_on): ramp_duty sqrt(1 + (Omega_ol ramp_tau)^2) + ..., s (>= 0) */
    int32_t ramp_hold;   /* forced sectors at ramp_w1 before the start fails (>= 1) */
    int32_t n_handover;  /* consecutive valid crossings for the handover (2 .. 1000) */
    float duty_min;      /* smallest duty in closed loop, [0, 1] */
    float duty_rate;     /* throttle ramp limit, 1/s (>= 0; 0: none; 10 /s = 1 %/ms) */
    float ref_stop;      /* |ref| <= ref_stop: stop (legs off), [0, 1) */
    float restart_wait;  /* quiet comparators (and time in STOP) before a restart, s (>= 0) */
    float restart_max;   /* restart after this long in STOP whatever the comparators show, s (>= restart_wait) */
    int32_t use_current; /* 1: phase currents measured (the input guard, i_max, i_limit); 0: ignored */
    float i_max;         /* over-current trip, A (> 0) */
    float i_limit;       /* current limit, A (>= 0; 0: none) */
    float k_limit;       /* current limiter gain, 1/(A s) (>= 0) */
    float v_max;         /* largest plausible DC-bus measurement, V (> 0) */
    int32_t fast_demag;  /* 1: the continuing phase chops until the demagnetisation is seen over (8); 0: never */
    float fd_after;      /* ... once the clamp has lasted this share of the window pi/6 + adv, [0, 1); 0: at once */
    float dlim_d0;       /* speed-dependent duty limit (2), CLOSED: m <= dlim_d0 + dlim_vf Omega; 0: none, [0, 1] */
    float dlim_vf;       /* its slope, 1/(rad/s) electrical (>= 0) */
    float dlim_tau;      /* the inductive part: dlim_d0 sqrt(1 + (Omega dlim_tau)^2), s (>= 0) */
    float demag_max;     /* demagnetisation limiter (2): largest demagnetisation angle / (pi/6 + adv), [0, 1); 0: off */
    int32_t cmp_gate;    /* 1: in a fast-demagnetisation sector on the negative leg, the comparator in the on-time only */
    int32_t cmp_blind;   /* 1: the comparator sees no crossing in the pair's off-time (ideal diodes; SYNC, HIGH): an edge
                          * there or at the next on-time's start is taken at the off-time's middle (6); 0: as seen */
    float i_start;       /* start-up current limit (ALIGN, RAMP; use_current), cycle by cycle, A (>= 0; 0: none) */
    float d_diode;       /* the inverter's share (2): align, ramp and dlim duties d -> d_diode + (1 - d_diode) d, [0, 1) */
    float grid_gain;     /* 7, CLOSED: > 0, commutate on the uniform grid phase-locked to the mean of the six crossings,
                          * each sector's crossing interval filtered with this gain, [0, 1]; 0: after each crossing */
    float brake_tau;     /* 9: time constant of the fastest fall of the rotor's speed, s (the pair shorted: J / (D + B),
                            D = k_pair^2 / (2 (R + R_on))); 0: the timeout is zc_timeout T60 only */
    float brake_acc;     /* 9: and its speed-independent part (Coulomb friction p tau_c / J), electrical rad/s^2 */
    float brake_q;       /* 9: and the propeller's, k_q / (p J): 1 / tau grows by brake_q w0 (w0: electrical), 1/rad */
} bc_bemf_params;

typedef struct {
    float ts_tick;         /* derived: T_s in ticks */
    float inv_tick;        /* derived: 1 / f_tick, s */
    int32_t mode;          /* BC_BEMF_STOP ... CLOSED */
    int32_t dir;           /* +1 forward, -1 backward (the run's direction) */
    int32_t fresh;         /* never run since init: the rotor is taken to be at rest */
    int32_t started;       /* a sample has been seen */
    int32_t reason;        /* last desync reason (BC_BEMF_REASON_*) */
    float t_in;            /* time in the state, s */
    float quiet;           /* time since the last comparator edge on any phase, s */
    uint32_t cnt_seen[3];  /* zc_count at the last sample */
    uint32_t n_adc_seen;   /* n_adc at the last sample */
    /* commutation */
    int32_t sector;        /* sector in force at the end of the last output's interval, -1 none */
    int32_t incoming;      /* phase that entered the pair at the last commutation, -1 none */
    int32_t outgoing;      /* phase that left the pair at the last commutation, -1 none (a start's first sector) */
    int32_t fd_neg;        /* fast demagnetisation chops the negative leg in this sector (its off-time at V_dc) */
    int32_t fd_on;         /* fast demagnetisation engaged in this sector (fd_after reached, the clamp not yet over) */
    int32_t fd_comp;       /* SYNC: fast demagnetisation newly engaged, its first whole half period not yet issued (8) */
    float grid_t[6];       /* grid_gain: each sector's filtered crossing interval over the mean of the last six */
    float grid_ring[6];    /* grid_gain: the last six crossing intervals, s */
    float grid_tn;         /* grid_gain: the filtered interval of the grid (each interval over its sector's ratio), s */
    float grid_dm[6];      /* grid_gain: each sector's last measured demagnetisation (the grid's bound), s */
    int32_t grid_k;        /* grid_gain: next slot of grid_ring */
    int32_t grid_n;        /* grid_gain: crossing intervals seen since the handover (the grid applies from 12) */
    uint32_t k_samp;       /* samples since init (even: carrier valley, odd: carrier peak) */
    uint32_t t_c;          /* tick of the commutation that began the sector */
    int32_t pending;       /* a commutation is scheduled at t_next */
    uint32_t t_next;       /* tick of the scheduled commutation */
    float d_cmd;           /* ramped throttle */
    float d_lim;           /* current limiter's duty */
    float adv;             /* advance computed at the last crossing, rad */
    float adv_prev;        /* advance of the commutation that began the sector, rad */
    /* crossing interval */
    float t60;             /* filtered crossing interval, s (0: none) */
    float t_last;          /* last interval between two real crossings, s (0: none) */
    uint32_t t_zc;         /* tick of the previous (true or virtual) crossing */
    int32_t have_zc;       /* t_zc valid */
    int32_t virt;          /* t_zc is virtual (a blind commutation) */
    int32_t misses;        /* blind commutations in a row */
    float t_demag;         /* last measured demagnetisation, s */
    float err;             /* last commutation error, rad */
    float d_dm;            /* duty cap of the demagnetisation limiter */
    float m_app;           /* duty applied at the last sample */
    /* open loop */
    float w_ol;            /* open-loop speed at the start of the forced sector, electrical rad/s */
    float w_now;           /* open-loop speed at the start of the output's interval, electrical rad/s */
    float tau_ol;          /* duration of the forced sector, s */
    float w_zc;            /* speed from the last forced sector's crossing, electrical rad/s (0: none) */
    int32_t valid;         /* consecutive forced sectors with a crossing */
    uint32_t ho_ring[BC_BEMF_HO_FIT]; /* ticks of the last crossings of those sectors (the handover's fit, 5) */
    /* the handover's fit prepared from the crossings known, for the next crossing's (5, bc_bemf_ho_prepare) */
    int32_t ho_n;          /* valid it was prepared at (the next fit's crossings: min(ho_n + 1, BC_BEMF_HO_FIT)) */
    int32_t ho_k;          /* ho_ring's slot of the last crossing it knows */
    uint32_t ho_t;         /* that crossing's tick */
    float ho_c, ho_inv;    /* its time origin after that crossing (s) and 1 / its time unit (1/s) */
    float ho_x[BC_BEMF_HO_FIT]; /* the known crossings' times in that unit from that origin, oldest first (and the
                                 * fitted crossing's, last) */
    float ho_mom[11];      /* their moments: x, x^2, x^3, x^4, (-1)^k, (-1)^k x, (-1)^k x^2, k, k x, k x^2, k (-1)^k */
    float to_t60, to_tl, to_val; /* 9: the timeout (s) and the T60 and last interval it was computed for */
    int32_t hold;          /* forced sectors at ramp_w1 */
    int32_t sector_ok;     /* the current forced sector had a crossing */
    int32_t first;         /* the first forced sector after an alignment (no crossing read) */
    /* detector of the current sector */
    int32_t det;           /* 0 before the window, 1 in it, 2 crossing found (commutation pending) */
    int32_t pre_seen;      /* the pre level was in the window */
    int32_t adc_seen;      /* ADC: a conversion in the window */
    int32_t post_open;     /* the post level since the window opened */
    int32_t dm_known;      /* t_dm measured */
    uint32_t t_open;       /* tick the window opens */
    uint32_t t_plain;      /* tick from which the outputs are the plain pattern (the pre level seen; cmp_blind, 6) */
    uint32_t t_dm;         /* tick the demagnetisation ended */
    uint32_t cnt_c;        /* zc_count[F] at the last sample before the commutation */
    uint32_t cnt_open;     /* zc_count[F] at the last sample before the window */
    int32_t n_post;        /* ADC: consecutive post samples */
    float u_pre;           /* ADC: the last pre sample of a free terminal (not at a rail) */
    uint32_t t_pre_free;   /* ADC: its tick */
    int32_t pre_free;      /* ADC: u_pre is from this window */
    uint32_t t_pre;        /* ADC: the tick of the last pre sample, free or clamped */
    float te_off;          /* ADC: the crossing, ticks after t_pre */
    float r_zc;            /* ADC: the slope of the last crossing's line, V/s (0: none) */
    int32_t zc_est;        /* ADC: te_off the bracket's middle (its pre end clamped), to refine at the next free post */
    /* integration (BC_BEMF_INTEGRATE) */
    int32_t integ;         /* integrating since the crossing */
    float lam;             /* integral so far, V s */
    float u_last;          /* last post sample */
    float r_last;          /* its slope, V/s */
    uint32_t t_u;          /* its tick */
    uint32_t t_int_max;    /* commutate at once after this tick */
    bc_guard_params guard_p; /* derived: i_max, v_max */
    bc_guard_state guard;
} bc_bemf_state;

/* Validate the parameters (finite, in range) and reset the state. BC_OK or BC_ERR_PARAM. */
int bc_bemf_init(const bc_bemf_params *p, bc_bemf_state *s);

/* One sample: measurements in, leg commands for the next half period (and a timed commutation inside it) out. */
void bc_bemf_step(const bc_bemf_params *p, bc_bemf_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);

/* The handover's fit (5) in its two parts, exposed for tests. bc_bemf_ho_prepare: the moments of the last
 * min(valid + 1, BC_BEMF_HO_FIT) - 1 crossings in ho_ring, for the fit at the next crossing (the controller calls it
 * at the first sample of a forced sector after its crossing). bc_bemf_ho_fit: at a crossing (valid and ho_ring
 * updated), the fit of the last m = min(valid, BC_BEMF_HO_FIT) crossings, prepared again first unless the preparation
 * is the one for valid - 1 and the same last crossing. Returns 0 with, in rad, *alt = |c3| pi/3, *res the largest
 * distance of a crossing from the fitted path and *acc its acceleration (rad/s^2); 1 with m < 5 (no check); -1 if the
 * crossings do not span a positive time or the fit is degenerate. */
void bc_bemf_ho_prepare(bc_bemf_state *s);
int bc_bemf_ho_fit(bc_bemf_state *s, float *alt, float *res, float *acc);

#endif /* BC_BEMF_H */

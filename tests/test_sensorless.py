"""SixStepSensorless (``bc_bemf``): its parameters (units, errors naming the field, defaults derived from the drive
against their closed forms), its C step driven from Python through the record Python builds, on a synthetic
sensorless drive (comparator edges and ADC samples of a kinematic rotor with the diode clamp after each commutation),
and its start-up path against the switching-level plant.

The plant has no back-EMF sensing yet (issue 24's sensing part is built beside this controller): ``bc_ctrl_in``'s
comparator and ADC fields are zero in ``bl.simulate``. The closed-loop tests against the plant (handover, commutation
angle against the Hall-exact instant, desync map) are added when it lands; ``SyntheticDrive`` and
``run_synthetic`` are the pieces they can reuse to compare the plant's sensing with the ideal one.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import pytest

import bldclab as bl
from bldclab._core import core
from bldclab.control.sensorless import integral_to_30, throttle_rate
from bldclab.errors import BldclabError

TWO_PI = 2.0 * math.pi
STATE = {"stop": 0, "align": 1, "ramp": 2, "closed": 3}


def trap(th: float) -> float:
    """The ideal 120-degree trapezoid of unit flat top, zero rising at 0."""
    th = th % TWO_PI
    sgn = 1.0
    if th > math.pi:
        th -= math.pi
        sgn = -1.0
    k = 1.0
    if th < math.pi / 6:
        k = th / (math.pi / 6)
    elif th > 5 * math.pi / 6:
        k = (math.pi - th) / (math.pi / 6)
    return sgn * k


@dataclass
class SyntheticDrive:
    """A kinematic rotor ``theta_e = th0 + w t`` and what a sensorless ESC's comparators see.

    Phase x's level is 1 when driven positive, 0 when driven negative; floating, the diode clamp's after the
    commutation that made it float (``demag`` s: 0 if it was driven positive, 1 if negative), then the sign of its
    back-EMF ``w k(theta - x 2 pi/3)``. Edges are time-stamped ``floor(t f_tick)``. The pair in force is the
    controller's output (from the next sample, ``has_at`` inside it).
    """

    w: float
    th0: float
    ts: float
    f_tick: float
    demag: float = 20e-6
    pairs: list[tuple[float, int, int, int, float]] = field(default_factory=list)  # (t, pos, neg, clamp lvl, end)
    level: list[int] = field(default_factory=lambda: [0, 0, 0])
    count: list[int] = field(default_factory=lambda: [0, 0, 0])
    tick: list[int] = field(default_factory=lambda: [0, 0, 0])
    t_eval: float = 0.0
    commutations: list[tuple[float, int]] = field(default_factory=list)  # (t, floating phase)
    crossings: list[tuple[float, int]] = field(default_factory=list)  # (t, phase) of the floating phase

    def theta(self, t: float) -> float:
        return self.th0 + self.w * t

    def pair_at(self, t: float) -> tuple[float, int, int, int, float]:
        for p in reversed(self.pairs):
            if p[0] <= t:
                return p
        return (-1.0, -1, -1, -1, -1.0)

    def lvl(self, x: int, t: float) -> int:
        _, pos, neg, cl, end = self.pair_at(t)
        if x == pos:
            return 1
        if x == neg:
            return 0
        if pos >= 0 and x == 3 - pos - neg and t < end:
            return cl
        return 1 if self.w * trap(self.theta(t) - x * TWO_PI / 3) > 0 else 0

    def edges(self, t1: float, t2: float) -> None:
        for x in range(3):
            cands = [p[0] for p in self.pairs if t1 < p[0] <= t2] + [p[4] for p in self.pairs if t1 < p[4] <= t2]
            th1, th2 = self.theta(t1), self.theta(t2)
            a1, a2 = sorted((th1, th2))
            off = x * TWO_PI / 3
            n = math.floor((a1 - off) / math.pi)
            while n * math.pi + off <= a2:
                tgt = n * math.pi + off
                n += 1
                if not (th1 < tgt <= th2 if self.w > 0 else th2 <= tgt < th1):  # crossed inside (t1, t2]
                    continue
                tz = min(max(t1 + (tgt - th1) / self.w, t1 + 1e-13), t2)  # (rounding at the window's ends)
                cands.append(tz)
                _, pos, neg, _, _ = self.pair_at(tz)
                if pos >= 0 and x == 3 - pos - neg:
                    self.crossings.append((tz, x))
            cands.sort()
            for j, c in enumerate(cands):
                nxt = cands[j + 1] if j + 1 < len(cands) else t2
                mid = max(0.5 * (c + nxt), c + 1e-10)
                lv = self.lvl(x, mid)
                if lv != self.level[x]:
                    self.level[x] = lv
                    self.count[x] += 1
                    self.tick[x] = math.floor(c * self.f_tick)

    def sample(self, k: int, inp: np.ndarray) -> None:
        t = k * self.ts
        if k == 0:
            self.level = [self.lvl(x, 0.0) for x in range(3)]
        else:
            self.edges(self.t_eval, t)
        self.t_eval = t
        inp[...] = 0
        inp["tick_now"] = round(t * self.f_tick)
        inp["v_dc"] = 48.0
        inp["i_mask"] = 3
        inp["zc_state"] = sum(1 << x for x in range(3) if self.level[x])
        inp["zc_count"] = self.count
        inp["zc_tick"] = self.tick

    def apply(self, k: int, out: np.ndarray, delay: int) -> None:
        ta = (k + delay) * self.ts
        self.set_pair(ta, out["leg"][0])
        if int(out["has_at"][0]):
            self.set_pair(ta + float(out["t_at"][0]), out["leg_at"][0])

    def set_pair(self, t: float, legs: np.ndarray) -> None:
        # the two driven legs; pos the one of the higher mean terminal voltage (PWM, HIGH: duty; LOW: 1 - duty), so
        # that a pair whose continuing leg chops (fast demagnetisation) is read as the same pair
        on = [x for x in range(3) if legs["mode"][x] != 0]
        pos = neg = -1
        if len(on) == 2:
            mean = [float(legs["duty"][x]) if legs["mode"][x] in (1, 2) else 1.0 - float(legs["duty"][x]) for x in on]
            if mean[0] != mean[1]:
                pos, neg = (on[0], on[1]) if mean[0] > mean[1] else (on[1], on[0])
        last = self.pair_at(float("inf"))
        if (pos, neg) == (last[1], last[2]):
            return
        cl, end = -1, -1.0
        if pos >= 0:
            fl = 3 - pos - neg
            if fl in (last[1], last[2]):  # the outgoing phase: its diode clamps it
                cl, end = (0 if fl == last[1] else 1), t + self.demag
            if last[1] >= 0:
                self.commutations.append((t, fl))
        self.pairs.append((t, pos, neg, cl, end))


def run_synthetic(ctl: bl.SixStepSensorless, drive: bl.Drive, syn: SyntheticDrive, n: int, ref: float):
    """Step the C controller, with the record ``ctl`` builds for ``drive``, through ``n`` samples of ``syn``.

    Returns
    -------
    list of (numpy record copy of bc_ctrl_out)
    """
    c = core()
    info = c.controllers["bemf"]
    owner = ctl.c_record(drive, c, n)
    state = c.opaque(info.state)
    assert c.controller_init(info, owner.record, state) == 0
    inp, out = c.record("bc_ctrl_in"), c.record("bc_ctrl_out")
    outs = []
    for k in range(n):
        syn.sample(k, inp)
        inp["ref"] = ref
        out[...] = 0
        c.controller_step(info, owner.record, state, inp, out)
        syn.apply(k, out, delay=ctl.delay)
        outs.append(out.copy())
    return outs


def locked(drive: bl.Drive, w_e: float, **kw) -> bl.SixStepSensorless:
    """A direct start whose forced commutation runs at the rotor's speed ``w_e`` (electrical), so it locks at once.

    The synthetic drive's comparators see the off-time (no blindness to compensate: ``comparator_blind=False``).
    """
    w_m = w_e / drive.motor.p
    kw.setdefault("comparator_blind", False)
    return bl.SixStepSensorless(align_time=0.0, ramp_start_speed=w_m, ramp_end_speed=w_m, stall_speed=0.2 * w_m,
                                blank=0.0, blank_time="2 us", min_pulse=0.0, **kw)


def commutation_errors(syn: SyntheticDrive, adv: float, after: float) -> list[float]:
    """For each commutation after ``after``: its time minus (its sector's crossing + (30 deg - adv) / w)."""
    errs = []
    for (t0, fl), (t1, _) in zip(syn.commutations, syn.commutations[1:], strict=False):
        if t0 < after:
            continue
        tz = [t for t, x in syn.crossings if x == fl and t0 < t < t1]
        assert tz, f"no crossing in the sector {t0:.6f} .. {t1:.6f}"
        errs.append(t1 - (tz[-1] + (math.pi / 6 - adv) / abs(syn.w)))
    return errs


# ---------------------------------------------------------------------------------------------------------------
# parameters


def test_units_and_defaults_from_the_drive():
    d = bl.load("htm-48v")
    ctl = bl.SixStepSensorless(timing="15 deg", timing_time="20 us", blank="3 deg", min_pulse="2 us",
                               stall_speed="20 rpm", throttle_rate="5 %/ms", restart_wait="20 ms")
    assert ctl.timing == pytest.approx(math.radians(15)) and ctl.timing_time == pytest.approx(20e-6)
    assert ctl.stall_speed == pytest.approx(20 * TWO_PI / 60) and ctl.throttle_rate == pytest.approx(50.0)
    rec = ctl.c_record(d, core(), 0).record
    m = d.motor
    assert float(rec["omega_stall"][0]) == pytest.approx(m.p * 20 * TWO_PI / 60, rel=1e-6)  # electrical in C
    assert float(rec["adv_angle"][0]) == pytest.approx(math.radians(15), rel=1e-6)
    assert float(rec["duty_rate"][0]) == pytest.approx(50.0)
    su = bl.SixStepSensorless().start_up(d)
    r = d.motor.R + d.inverter.R_on
    assert su["align_duty"] == pytest.approx(1.5 * r * 0.5 * m.I_N / d.inverter.V_dc)  # a against b and c in parallel
    assert su["ramp_vf"] == pytest.approx(2 * m.k_phi / (m.p * d.inverter.V_dc))
    k = 6 / math.pi * m.p * m.k_phi * 0.5 * m.I_N
    damp = 2 * m.k_phi**2 / r  # the parallel pair's damping: htm-48v is near critical (zeta = 0.83)
    # the first and last steps' time, and a sixth of it for the middle step (law 4)
    assert su["align_time"] == pytest.approx(7 / 6 * max(3 * TWO_PI * math.sqrt(d.mechanics.J / k), 12 * damp / k,
                                                         5 * d.mechanics.J / (damp + d.mechanics.B)))
    lu = bl.load("lu-4kw")  # overdamped (zeta = 11): twelve time constants D / K
    k_lu = 6 / math.pi * lu.motor.p * lu.motor.k_phi * 0.5 * lu.motor.I_N
    d_lu = 2 * lu.motor.k_phi**2 / (lu.motor.R + lu.inverter.R_on)
    assert bl.SixStepSensorless().start_up(lu)["align_time"] == pytest.approx(7 / 6 * 12 * d_lu / k_lu)
    assert su["ramp_end_speed"] == pytest.approx(0.1 * d.Omega_0)
    assert throttle_rate("1 %/ms") == pytest.approx(10.0) and throttle_rate("100 %/s") == pytest.approx(1.0)


@pytest.mark.parametrize(("kw", "field"), [
    ({"method": "hall"}, "control.method"), ({"chopping": "low"}, "control.chopping"),
    ({"blanking": "none"}, "control.blanking"), ({"timing": "40 deg"}, "control.timing"),
    ({"timing": "15 us"}, "control.timing"), ({"blank": "60 deg"}, "control.blank"),
    ({"throttle_rate": "5 %/h"}, "control.throttle_rate"), ({"throttle_rate": -1.0}, "control.throttle_rate"),
    ({"timeout": 1.0}, "control.timeout"), ({"jump": 1.0}, "control.jump"), ({"n_samples": 0}, "control.n_samples"),
    ({"handover": 1}, "control.handover"), ({"misses": -1}, "control.misses"), ({"delay": 2}, "control.delay"),
    ({"interval_gain": 1.5}, "control.interval_gain"), ({"ramp_duty": 1.2}, "control.ramp_duty"),
    ({"restart_wait": "2 s"}, "control.restart_max"), ({"current_sensing": 1}, "control.current_sensing"),
    ({"comparator_delay": "-1 us"}, "control.comparator_delay"), ({"filter_tau": -1e-6}, "control.filter_tau"),
    ({"grid_gain": 1.5}, "control.grid_gain"), ({"grid_gain": -0.1}, "control.grid_gain"),
    ({"grid_gain": math.nan}, "control.grid_gain"),
])
def test_bad_settings_name_the_field(kw, field):
    with pytest.raises(BldclabError, match=field.replace(".", r"\.")):
        bl.SixStepSensorless(**kw)


def test_the_esc_runs_without_the_samples_delay_unless_the_scenario_says_so():
    """An ESC's firmware commutates in its interrupts: ``SixStepSensorless`` runs with ``delay`` 0 where the Scenario
    leaves it (``None``), its first output (the alignment's legs) applied from t = 0; a Scenario's delay of 1 is
    applied to it (the first half period with every leg off), and other controllers keep their 1."""
    d = bl.load("f60prov-2550kv")
    sc = bl.Scenario(duration=4e-4, ref=0.3)
    assert sc.delay is None and bl.SixStepSensorless().delay == 0 and bl.SixStepSensorless().own_delay == 0
    for delay, on_at_0 in ((None, True), (1, False), (0, True)):
        r = bl.simulate(d, bl.SixStepSensorless(), dataclasses.replace(sc, delay=delay), check="off")
        modes = np.vstack([r.signals[f"mode_{x}"] for x in "abc"])
        assert r.meta["control"]["delay"] == r.meta["scenario"]["delay"] == (0 if delay is None else delay)
        assert bool(modes[:, 0].any()) == on_at_0 and modes[:, 1].any(), (delay, modes[:, :2])
    assert bl.SixStep().own_delay == 1 and bl.Sine().own_delay == 1
    for bad in (2, True, -1):
        with pytest.raises(BldclabError, match=r"scenario\.delay"):
            bl.Scenario(duration=1e-3, delay=bad)


def test_comparator_needs_the_star_reference():
    """The comparators' reference is hardware (``drive.sensors.bemf_reference``): against half the bus the comparator
    method is refused by name (the comparator sees the PWM), the ADC methods run (they sample in the on-time) and
    the integration threshold is computed against half the bus."""
    d = bl.load("htm-48v")
    half = d.replace(sensors=dataclasses.replace(d.sensors, bemf_reference="half"))
    with pytest.raises(BldclabError, match=r"control\.method.*star"):
        bl.SixStepSensorless().c_record(half, core(), 0)
    rec = bl.SixStepSensorless(method="integration").c_record(half, core(), 0).record
    assert float(rec["int_limit"][0]) == pytest.approx(integral_to_30(d, "half"), rel=1e-6)
    res = bl.simulate(half, bl.SixStepSensorless(method="adc", throttle_rate="1 %/ms"),
                      bl.Scenario(duration=1.0, ref=0.4, theta0=1.0), check="warn")
    assert set(res.meta["flags"]) == {"OPEN_LOOP"} and res.signals["state"][-1] == STATE["closed"]


def test_speeds_must_leave_room_for_the_handover():
    d = bl.load("htm-48v")
    with pytest.raises(BldclabError, match=r"control\.ramp_end_speed.*1\.5 stall_speed"):
        bl.SixStepSensorless(stall_speed="70 rpm", ramp_end_speed="100 rpm").c_record(d, core(), 0)


def test_integration_threshold_against_its_closed_forms():
    """The back-EMF integral from the crossing to 30 degrees: (2/3) k_phi pi / (12 p) (star) and k_phi pi / (12 p)
    (half bus) for the ideal trapezoid; K (1 - cos 30 deg) / p for a sinusoid of peak K (star: 2/3 (e_F - (e_p +
    e_n)/2) = e_F when the three sum to zero)."""
    d = bl.load("htm-48v")
    m = d.motor
    assert integral_to_30(d, "star") == pytest.approx(2 / 3 * m.k_phi * math.pi / 12 / m.p, rel=1e-4)
    assert integral_to_30(d, "half") == pytest.approx(m.k_phi * math.pi / 12 / m.p, rel=1e-4)
    s = bl.load("servo-2k2")
    k_peak = float(np.max(s.motor.emf.k_abc(np.linspace(0, TWO_PI, 3601))[0]))
    assert integral_to_30(s, "star") == pytest.approx(k_peak * (1 - math.cos(math.pi / 6)) / s.motor.p, rel=2e-3)
    rec = bl.SixStepSensorless(method="integration").c_record(d, core(), 0).record
    assert float(rec["int_limit"][0]) == pytest.approx(integral_to_30(d), rel=1e-6)


def test_new_flags_are_named():
    names = ("DESYNC", "ZC_TIMEOUT", "ZC_HIDDEN", "ZC_JUMP", "STALL", "START_FAIL", "OPEN_LOOP", "COMM_LATE")
    bits = [bl.flag(n) for n in names]
    assert len(set(bits)) == len(bits) and all(b & (b - 1) == 0 for b in bits)
    assert bl.decode_flags(bits[0] | bits[2]) == "DESYNC|ZC_HIDDEN"


# ---------------------------------------------------------------------------------------------------------------
# the C step on the synthetic drive


@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("timing_deg", [0.0, 10.0])
def test_commutation_30_deg_minus_advance_after_each_crossing(direction, timing_deg):
    """Commutation instants ``30 deg - timing`` after the rotor's crossings, to the capture timer's resolution, in
    both directions: the record Python builds (mechanical speeds, degrees) drives the C controller."""
    d = bl.load("htm-48v")
    ts = 0.5 / d.inverter.f_pwm
    w = TWO_PI * 300.0  # 300 Hz electrical: 3.3 ms per revolution, 47 samples per sector
    syn = SyntheticDrive(w=direction * w, th0=5 * math.pi / 6 - direction * w * ts, ts=ts, f_tick=d.sensors.f_tick)
    outs = run_synthetic(locked(d, w, timing=f"{timing_deg} deg"), d, syn, 1400, 0.5 * direction)
    flags = np.array([int(o["flags"][0]) for o in outs])
    states = np.array([float(o["diag"][0][0]) for o in outs])
    assert not np.any(flags & bl.flag("DESYNC")) and not np.any(flags & bl.flag("COMM_LATE"))
    handover = int(np.argmax(states == STATE["closed"]))
    assert 0 < handover < 400
    errs = commutation_errors(syn, math.radians(timing_deg), after=(handover + 50) * ts)
    assert len(errs) > 30
    assert max(abs(e) for e in errs) < 2.5 / d.sensors.f_tick  # the tick of the edge, the tick of the schedule
    last = outs[-1]["diag"][0]
    assert last[2] == pytest.approx(direction * w, rel=1e-3)  # omega_e, signed
    assert last[4] == pytest.approx(syn.demag, abs=3 / d.sensors.f_tick)  # demagnetisation measured


def test_a_clamp_outlasting_the_crossing_is_a_named_desync():
    """From a time on the clamp lasts 40 degrees: the floating phase never leaves the post-crossing level before
    the timeout, the crossing is hidden; the controller says so (ZC_HIDDEN, reason 2), turns the legs off and waits."""
    d = bl.load("htm-48v")
    ts = 0.5 / d.inverter.f_pwm
    w = TWO_PI * 300.0
    syn = SyntheticDrive(w=w, th0=5 * math.pi / 6 - w * ts, ts=ts, f_tick=d.sensors.f_tick)
    c = core()
    info = c.controllers["bemf"]
    ctl = locked(d, w)
    owner = ctl.c_record(d, c, 0)
    state = c.opaque(info.state)
    assert c.controller_init(info, owner.record, state) == 0
    inp, out = c.record("bc_ctrl_in"), c.record("bc_ctrl_out")
    t_long, first = 0.02, None
    for k in range(1200):
        if k * ts >= t_long:
            syn.demag = math.radians(40) / w
        syn.sample(k, inp)
        inp["ref"] = 0.5
        out[...] = 0
        c.controller_step(info, owner.record, state, inp, out)
        syn.apply(k, out, delay=ctl.delay)
        if first is None and int(out["flags"][0]) & bl.flag("DESYNC"):
            first = (k, int(out["flags"][0]), out.copy())
    assert first is not None
    k, flags, o = first
    assert bl.decode_flags(flags) == "DESYNC|ZC_HIDDEN"
    assert t_long < k * ts < t_long + 3 * (math.pi / 3) / w
    assert int(o["diag"][0][7]) == c.const("BC_BEMF_REASON_HIDDEN")
    assert np.all(o["leg"]["mode"][0] == 0) and not flags & bl.flag("SAFE")  # coasting, not the safe state
    assert float(out["diag"][0][0]) == STATE["stop"]


# ---------------------------------------------------------------------------------------------------------------
# the start-up path against the plant and its back-EMF sensing


def test_alignment_ramp_and_handover_on_the_plant():
    """htm-48v, rotor free, the plant's comparators (virtual star, no filter): the alignment (a+ and b+ against c-,
    then a+ against b- and c-) brings the rotor to theta_e = pi; the forced ramp's duty follows V/f between its
    standstill value and that of the end speed and never falls; the crossings hand over to closed loop within the
    ramp and the sectors it may hold; at the handover the speed estimate is the rotor's within 10 %; in closed loop
    the drive accelerates without a desync, and at the end the estimate is the rotor's electrical speed within
    1 %. OPEN_LOOP is raised exactly up to the handover."""
    d = bl.load("htm-48v")
    ctl = bl.SixStepSensorless(throttle_rate="0.1 %/ms")
    su = ctl.start_up(d)
    res = bl.simulate(d, ctl, bl.Scenario(duration=1.2, ref=0.3, theta0=0.3), check="warn")
    t, st, p = res.t, res.signals["state"], d.motor.p
    j_end = int(np.searchsorted(t, su["align_time"])) - 1
    assert np.all(st[:j_end] == STATE["align"])
    dist = (res.signals["theta_e"][j_end] - math.pi + math.pi) % TWO_PI - math.pi
    assert abs(dist) < 0.25, dist  # within 15 electrical degrees of the aligned position
    ramp = st == STATE["ramp"]
    assert np.any(ramp)
    duty = res.signals["duty"][ramp]
    w1 = p * su["ramp_end_speed"]
    top = su["ramp_duty"] * math.sqrt(1.0 + (w1 * su["ramp_tau"]) ** 2) + su["ramp_vf"] * w1  # |R + j w L|, V/f
    assert su["ramp_tau"] == pytest.approx(d.motor.L / d.motor.R)
    assert np.all(duty >= su["ramp_duty"] - 1e-6) and np.all(duty <= top + 1e-6)
    assert duty.max() == pytest.approx(top, rel=1e-4)
    assert np.all(np.diff(duty) >= -1e-6)  # the forced speed never falls
    closed = st == STATE["closed"]
    j_h = int(np.argmax(closed))
    assert closed[j_h] and np.all(closed[j_h:])
    sector_end = (math.pi / 3) / (p * su["ramp_end_speed"])
    assert t[j_h] < su["align_time"] + su["ramp_time"] + ctl.ramp_hold * sector_end
    w_true = p * res.signals["omega_m"]
    assert res.signals["omega_e"][j_h] == pytest.approx(w_true[j_h], rel=0.1)
    assert res.signals["omega_e"][-1] == pytest.approx(w_true[-1], rel=0.01)
    assert w_true[-1] > 1.5 * w_true[j_h]
    flags = res.meta["flags"]
    assert set(flags) == {"OPEN_LOOP"}, flags
    assert flags["OPEN_LOOP"]["run"]["last"] == pytest.approx(t[j_h - 1])


@pytest.mark.parametrize("name", ["f60prov-2550kv", "htm-48v-losses"])
@pytest.mark.parametrize("chop", ["sync", "high", "pwm-on-pwm", "bipolar"])
def test_alignment_current_counts_the_inverters_diodes_and_dead_time(name, chop):
    """The alignment duty is an ideal inverter's (``1.5 (R + R_on) I / V_dc``); the controller applies ``q + (1 - q)
    d`` with ``q`` the inverter's share (:func:`inverter_share`): ``V_d / (V_dc + V_d)``, ``V_d = V_f + (r_d - R_on)
    I``, where the chopping leg's current takes a diode in the off-time (high, pwm-on-pwm, bipolar), and ``t_dead
    f_pwm (V_dc + 2 V_f) / V_dc`` with synchronous chopping. On the switching plant the current in phase a at the
    alignment's end is then the alignment current within 2 % in every pattern, on f60prov-2550kv (0.77 V body
    diodes, a duty of 0.034: the diode's drop is larger than the whole alignment voltage, uncounted the high-side
    pattern drives no current) and on htm-48v-losses (0.76 V, 300 ns dead time)."""
    from bldclab.control.sensorless import inverter_share

    d = bl.load(name)
    inv = d.inverter
    ctl = bl.SixStepSensorless(chopping=chop)
    su = ctl.start_up(d)
    i_al = su["align_current"]
    v_d = inv.V_f + (inv.r_d - inv.R_on) * i_al
    q = (inv.t_dead * inv.f_pwm * (inv.V_dc + 2 * inv.V_f) / inv.V_dc if chop == "sync" else v_d / (inv.V_dc + v_d))
    assert su["diode_duty"] == pytest.approx(q) and inverter_share(d, chop, i_al) == pytest.approx(q)
    assert float(ctl.c_record(d, core(), 0).record["d_diode"][0]) == pytest.approx(q, rel=1e-6)
    res = bl.simulate(d, ctl, bl.Scenario(duration=su["align_time"], ref=0.3, theta0=3.0), check="warn")
    k = len(res.t) // 10
    assert np.mean(res.signals["i_a"][-k:]) == pytest.approx(i_al, rel=0.02)
    assert np.allclose(res.signals["duty"][-k:], q + (1 - q) * su["align_duty"], rtol=1e-6)


# ---------------------------------------------------------------------------------------------------------------
# closed loop on the plant


def _final_speed(res: bl.SimResult, share: float = 0.1) -> float:
    k = max(1, int(len(res.t) * share))
    return float(np.mean(res.signals["omega_m"][-k:]))


@pytest.mark.parametrize(("name", "duty", "dur", "chop", "method", "load", "tol"), [
    ("htm-48v", 0.5, 1.5, "sync", "comparator", 0.0, 0.005),
    ("htm-48v", 0.6, 2.0, "high", "comparator", 0.3, 0.005),
    ("htm-48v", 0.5, 1.5, "sync", "adc", 0.0, 0.005),
    ("mn3110-780kv", 0.5, 1.4, "sync", "comparator", 0.0, 0.02),
    ("mn3110-780kv", 0.5, 1.4, "high", "comparator", 0.0, 0.02),
    ("mn3110-780kv", 0.5, 1.4, "pwm-on-pwm", "comparator", 0.0, 0.02),
    ("mn3110-780kv", 0.5, 1.4, "bipolar", "comparator", 0.0, 0.02),
    ("mn3110-780kv", 0.5, 1.4, "sync", "adc", 0.0, 0.02),
    ("f60prov-2550kv", 0.3, 0.6, "sync", "comparator", 0.0, 0.02),
    ("f60prov-2550kv", 0.3, 0.6, "high", "comparator", 0.0, 0.02),
    ("f60prov-2550kv", 0.3, 0.6, "pwm-on-pwm", "comparator", 0.0, 0.02),
    ("f60prov-2550kv", 0.3, 0.6, "bipolar", "comparator", 0.0, 0.02),
    ("f60prov-2550kv", 0.2, 0.6, "sync", "adc", 0.0, 0.02),
])
def test_steady_speed_matches_hall_six_step_at_equal_duty(name, duty, dur, chop, method, load, tol):
    """Rotor free (the drones with their propellers): started, handed over and run to steady state, the
    sensorless drive settles at the speed Hall six-step (``SixStep(regulation="duty")``, the same pattern, the
    commutation timer at the predicted Hall instants) settles at with the same duty, within 0.5 % on htm-48v and 2 %
    on the drone motors (few samples per sector: the floating phase's off-time clamp and the sample grid move their
    crossings by up to a PWM off-time). Unloaded htm-48v with the non-synchronous patterns is left out: its current
    is discontinuous (about 0.6 A) and its torque-speed curve so flat that neither drive settles within seconds
    (at equal imposed speed their torques agree to 1e-4 N m, docs/sensorless.md); loaded (0.3 T_N, applied after
    the start) the two agree to 0.1 %."""
    d = bl.load(name)
    t_n = 2 * d.motor.k_phi * d.motor.I_N

    def load_torque(t):  # applied after the start (a load at standstill is the start-up study's question)
        return load * t_n * np.clip((t - 0.5 * dur) / (0.2 * dur), 0.0, 1.0)

    sl = bl.simulate(d, bl.SixStepSensorless(chopping=chop, method=method, throttle_rate="1 %/ms"),
                     bl.Scenario(duration=dur, ref=duty, theta0=1.0, load_torque=load_torque), check="warn")
    assert "DESYNC" not in sl.meta["flags"] and "SAFE" not in sl.meta["flags"], sl.meta["flags"]
    assert np.all(sl.signals["state"][-len(sl.t) // 5:] == STATE["closed"])
    n = bl.sim.samples_of(d, dur)
    ramp = np.minimum(duty, np.arange(n) * 0.5 / d.inverter.f_pwm * (1.0 if load else 10.0))
    hall = bl.simulate(d, bl.SixStep(regulation="duty", chopping=chop, timed=True),
                       bl.Scenario(duration=dur, ref=ramp, theta0=1.0, load_torque=load_torque), check="warn")
    w_sl, w_h = _final_speed(sl), _final_speed(hall)
    assert w_h > 0.1 * d.Omega_0
    assert w_sl == pytest.approx(w_h, rel=tol)


def test_hard_throttle_step_on_the_drone_stays_in_sync():
    """f60prov-2550kv with its propeller, default settings (no throttle ramp): at 0.3 s the throttle steps from 0.25
    to 1 in one sample, from fifteen initial rotor angles (each start leaves the closed loop in another state at the
    step). The drive stays in closed loop, without a desync or a trip, and accelerates to above 0.45 Omega_0 from at
    least ten of them (the margin at this step is thin: measured 11 of 15, and 12 of 15 before the start-up work,
    which changes the state at the step; elsewhere the clamp hides a crossing, ZC_HIDDEN, and the drive restarts,
    never a trip): the speed-dependent duty limit holds the current near I_N and the demagnetisation limiter keeps
    the clamp at 0.6 of the window on average (measured 0.59, the duty then 0.72). Without the two limits and the
    fast demagnetisation the same step hides the crossing behind the clamp (ZC_HIDDEN) within 40 ms."""
    d = bl.load("f60prov-2550kv")
    dur, t_step = 0.6, 0.3
    n = bl.sim.samples_of(d, dur)
    t = np.arange(n) * 0.5 / d.inverter.f_pwm
    ref = np.where(t < t_step, 0.25, 1.0)
    held = 0
    for theta0 in np.arange(0.2, 6.0, 0.4):
        res = bl.simulate(d, bl.SixStepSensorless(), bl.Scenario(duration=dur, ref=ref, theta0=theta0), check="warn")
        flags = res.meta["flags"]
        assert not {"SAFE", "OVERCURRENT"} & set(flags), flags
        assert np.max(np.abs(res.signals["i_a"])) < 2 * d.motor.I_N
        if "DESYNC" in flags:
            assert "ZC_HIDDEN" in flags, flags  # the clamp's desync, named
            continue
        held += 1
        st = res.signals["state"]
        assert np.all(st[res.t > t_step - 0.1] == STATE["closed"])
        assert _final_speed(res) > 0.45 * d.Omega_0
        # the demagnetisation limiter at its set point: the clamp takes 0.6 of the window on average, the duty below 1
        late = res.t > dur - 0.1
        share = np.abs(res.signals["omega_e"][late]) * res.signals["demag"][late] / (math.pi / 6)
        assert np.mean(share) == pytest.approx(0.6, abs=0.05) and np.max(res.signals["duty"][late]) < 0.9
    assert held >= 10, held
    bare = bl.SixStepSensorless(fast_demag=False, demag_limit=0.0, duty_limit_current=0.0, throttle_rate="0.65 %/ms")
    res = bl.simulate(d, bare, bl.Scenario(duration=dur, ref=ref, theta0=1.8), check="warn")
    flags = res.meta["flags"]
    assert "ZC_HIDDEN" in flags and t_step < flags["ZC_HIDDEN"]["run"]["first"] < t_step + 0.04, flags


def test_speed_dependent_duty_limit_after_the_handover():
    """htm-48v, throttle 0.5 from the start without a ramp: after the handover the duty is the speed-dependent limit
    ``2 (R + R_on) I_N sqrt(1 + (Omega_e L / (R + R_on))^2) / V_dc + 2 k_phi Omega_e / (p V_dc)`` at the estimated
    speed (to float precision) until it reaches the throttle, and the drive neither trips nor desyncs; with the
    limit off the same start trips the over-current protection at the handover."""
    d = bl.load("htm-48v")
    m, v = d.motor, d.inverter.V_dc
    r = d.motor.R + d.inverter.R_on
    res = bl.simulate(d, bl.SixStepSensorless(), bl.Scenario(duration=1.0, ref=0.5, theta0=1.0), check="warn")
    assert set(res.meta["flags"]) == {"OPEN_LOOP"}, res.meta["flags"]
    s = res.signals
    closed = s["state"] == STATE["closed"]
    closed[int(np.argmax(closed))] = False  # the handover's sample applies the ramp's duty
    w = np.abs(s["omega_e"][closed])
    cap = 2 * r * m.I_N * np.sqrt(1 + (w * m.L / r) ** 2) / v + 2 * m.k_phi * w / (m.p * v)
    duty = s["duty"][closed]
    limited = cap < 0.5 - 1e-3
    assert np.count_nonzero(limited) > 100
    assert np.allclose(duty[limited], cap[limited], rtol=1e-4, atol=1e-5)
    assert np.all(duty <= np.minimum(cap, 0.5) + 1e-5)
    res = bl.simulate(d, bl.SixStepSensorless(duty_limit_current=0.0), bl.Scenario(duration=1.0, ref=0.5, theta0=1.0),
                      check="warn")
    assert "OVERCURRENT" in res.meta["flags"]

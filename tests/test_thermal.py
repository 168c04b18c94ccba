"""The thermal network (issue 27): closed forms, steady state, energy, Foster to Cauer, [thermal] in motor files."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from bldclab.errors import BldclabError
from bldclab.model import catalog
from bldclab.model.motor import Drive
from bldclab.model.thermal import (
    Thermal,
    ThermalLink,
    ThermalNode,
    copper_alpha,
    foster_to_cauer,
)


def _single(C: float = 40.0, R: float = 2.5, T_amb: float = 20.0, T0: float | None = None) -> Thermal:
    return Thermal(nodes=(ThermalNode("winding", C=C, T=T0), ThermalNode("ambient", T=T_amb)),
                   links=(ThermalLink("winding", "ambient", R),), losses={"cu": "winding"}, magnets=None)


def test_single_node_step_response_closed_form() -> None:
    """One node: T(t) = T_a + P R (1 - exp(-t / RC)) + (T0 - T_a) exp(-t / RC), for any step length."""
    C, R, Ta, T0, P = 40.0, 2.5, 20.0, 35.0, 12.0
    net = _single(C, R, Ta, T0).network()
    tau = R * C
    assert net.time_constants == pytest.approx([tau], rel=1e-14)
    for h in (1e-3, 0.37, 10.0, 3 * tau):
        T = net.initial()
        t = 0.0
        for _ in range(25):
            T, _q = net.step(T, [P], h)
            t += h
        exact = Ta + P * R * (1 - math.exp(-t / tau)) + (T0 - Ta) * math.exp(-t / tau)
        assert T[0] == pytest.approx(exact, rel=1e-12, abs=1e-12)


def test_steady_temperatures_are_loss_times_resistance() -> None:
    """A chain winding - stator - housing - ambient with losses at two nodes: the rises are sums of P R."""
    th = Thermal(nodes=(ThermalNode("winding", C=300.0), ThermalNode("stator", C=900.0),
                        ThermalNode("housing", C=1200.0), ThermalNode("ambient", T=30.0)),
                 links=(ThermalLink("winding", "stator", 0.1), ThermalLink("stator", "housing", 0.5),
                        ThermalLink("housing", "ambient", 0.3)),
                 losses={"cu": "winding", "fe": "stator"}, magnets=None)
    net = th.network()
    Pcu, Pfe = 120.0, 40.0
    P, direct = net.heat({"cu": Pcu, "fe": Pfe})
    assert direct == 0.0
    T = net.steady(P)
    T_h = 30.0 + (Pcu + Pfe) * 0.3
    T_s = T_h + (Pcu + Pfe) * 0.5
    T_w = T_s + Pcu * 0.1
    assert T == pytest.approx([T_w, T_s, T_h], rel=1e-13)
    # a long exact step lands there too
    T_end, _ = net.step(net.initial(), P, 50 * max(net.time_constants))
    assert T_end == pytest.approx(T, rel=1e-12)


def _random_network(rng: np.random.Generator, n: int) -> Thermal:
    nodes = [ThermalNode(f"n{j}", C=float(rng.uniform(0.05, 2000.0))) for j in range(n)]
    nodes += [ThermalNode("ambient", T=25.0), ThermalNode("coolant", T=float(rng.uniform(-10, 60)))]
    links = [ThermalLink(f"n{j}", f"n{j + 1}", float(rng.uniform(0.01, 3.0))) for j in range(n - 1)]
    links += [ThermalLink("n0", "ambient", float(rng.uniform(0.1, 2.0))),
              ThermalLink(f"n{n - 1}", "coolant", float(rng.uniform(0.1, 2.0)))]
    for _ in range(n):
        a, b = rng.choice(n, size=2, replace=False)
        links.append(ThermalLink(f"n{a}", f"n{b}", float(rng.uniform(0.05, 5.0))))
    return Thermal(nodes=tuple(nodes), links=tuple(links),
                   losses={"cu": {"n0": 0.6, f"n{n - 1}": 0.4}, "sw": "n1", "Rsrc": "ambient"}, magnets=None,
                   winding=("n0",))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_energy_stored_plus_to_boundary_equals_losses(seed: int) -> None:
    """Heat stored + heat to the boundary = losses, to 1e-6 relative over 200 steps of random length and power."""
    rng = np.random.default_rng(seed)
    net = _random_network(rng, 6).network()
    T = net.initial()
    E_in = E_out = 0.0
    for _ in range(200):
        h = float(10 ** rng.uniform(-4, 3))
        P, direct = net.heat({"cu": float(rng.uniform(0, 500)), "sw": float(rng.uniform(0, 50)),
                              "Rsrc": float(rng.uniform(0, 10))})
        T, q = net.step(T, P, h)
        E_in += float(np.sum(P)) * h
        E_out += q
        assert direct > 0.0
    stored = net.stored(T)
    assert abs(stored + E_out - E_in) <= 1e-6 * E_in
    assert stored > 0.0 and E_out > 0.0


def test_time_constants_and_exactness_against_fine_steps() -> None:
    """The exact step over h equals the product of 1000 steps of h/1000 (the semigroup property, to rounding)."""
    net = catalog.load("htm-48v-losses").thermal.network()  # type: ignore[union-attr]
    P, _ = net.heat({"cu": 200.0, "fe": 30.0, "sw": 15.0, "fric": 5.0})
    T1, q1 = net.step(net.initial(), P, 60.0)
    T2 = net.initial()
    q2 = 0.0
    for _ in range(1000):
        T2, q = net.step(T2, P, 0.06)
        q2 += q
    assert T1 == pytest.approx(T2, rel=1e-11)
    assert q1 == pytest.approx(q2, rel=1e-9)
    tc = net.time_constants
    assert tc[0] > 600.0 and tc[-1] < 0.1  # hub motor's tens of minutes, a die's tens of ms


def test_foster_to_cauer_same_impedance_and_step() -> None:
    """The Cauer ladder has the Foster network's impedance at every frequency and its step response."""
    R = [0.05, 0.2, 0.28]
    tau = [1e-3, 2e-2, 0.3]
    ladder = foster_to_cauer(R, tau)
    assert sum(r for _, r in ladder) == pytest.approx(sum(R), rel=1e-12)
    for w in (0.1, 3.0, 100.0, 1e4):
        s = 1j * w
        zf = sum(r / (1 + s * t) for r, t in zip(R, tau, strict=True))
        y: complex = 0.0
        for c, r in reversed(ladder):  # from the reference end: Z_k = R_k + 1 / (s C_{k+1} + Y_{k+1})
            y = 1.0 / (r + (1.0 / y if y != 0 else 0.0)) if y != 0 else 1.0 / r
            y = s * c + y
        assert 1.0 / y == pytest.approx(zf, rel=1e-9)
    # step response of the ladder as a network: junction node fed, last R to an ambient at 0
    nodes = [ThermalNode(f"k{j}", C=c) for j, (c, _) in enumerate(ladder)] + [ThermalNode("amb", T=0.0)]
    names = [n.name for n in nodes]
    links = [ThermalLink(names[j], names[j + 1], r) for j, (_, r) in enumerate(ladder)]
    net = Thermal(nodes=tuple(nodes), links=tuple(links), losses={"sw": "k0"}, magnets=None, winding=("k0",)).network()
    for t in (1e-3, 0.05, 1.0):
        T, _ = net.step(net.initial(), [1.0] + [0.0] * (len(ladder) - 1), t)
        zth = sum(r * (1 - math.exp(-t / tt)) for r, tt in zip(R, tau, strict=True))
        assert T[0] == pytest.approx(zth, rel=1e-9)


def test_copper_alpha() -> None:
    assert copper_alpha(20.0) == pytest.approx(0.003930, abs=2e-6)
    assert copper_alpha(25.0) == pytest.approx(1 / 259.5)


def test_at_temperature_scales_R_emf_Ron() -> None:
    d = catalog.load("htm-48v-losses")
    th = d.thermal
    assert th is not None
    hot = d.at_temperature(winding=125.0, magnets=85.0, switches=100.0)
    assert hot.motor.R == pytest.approx(d.motor.R * (1 + 100.0 / 259.5), rel=1e-14)
    assert hot.inverter.R_on == pytest.approx(d.inverter.R_on * (1 + 0.006 * 75.0), rel=1e-14)
    assert hot.motor.k_phi == pytest.approx(d.motor.k_phi * (1 - 0.0012 * 60.0), rel=1e-12)
    with pytest.raises(BldclabError, match="thermal"):
        catalog.load("lu-4kw").at_temperature(winding=100.0)


def test_motor_file_roundtrip_and_units() -> None:
    for name in ("htm-48v", "htm-48v-losses"):
        d = catalog.load(name)
        back = Drive.from_dict(tomllib.loads(d.to_toml()))
        assert back.thermal == d.thermal


def _file(**changes: object) -> dict[str, object]:
    d = tomllib.loads(catalog.load("htm-48v").to_toml())
    th = d["thermal"]
    assert isinstance(th, dict)
    for path, value in changes.items():
        keys = path.split("__")
        node = th
        for k in keys[:-1]:
            node = node[int(k)] if isinstance(node, list) else node[k]
        if value is None:
            del node[keys[-1]]
        elif isinstance(node, list):
            node[int(keys[-1])] = value
        else:
            node[keys[-1]] = value
    return d


@pytest.mark.parametrize(("changes", "field", "words"), [
    ({"nodes__stator__C": "-3 J/K"}, "thermal.nodes.stator.C", "> 0"),
    ({"nodes__stator__C": "3 K/W"}, "thermal.nodes.stator.C", "heat capacity"),
    ({"nodes__ambient": {}}, "thermal.nodes.ambient.T", "boundary"),
    ({"links__0__R": 0.0}, "thermal.links[0].R", "> 0"),
    ({"links__0__between": ["winding", "rotorr"]}, "thermal.links[0].between", "rotorr"),
    ({"links__0__between": ["winding", "winding"]}, "thermal.links[0].between", "itself"),
    ({"losses__fric": {"rotor": 0.5, "housing": 0.4}}, "thermal.losses.fric", "add up to 1"),
    ({"losses__copper": "winding"}, "thermal.losses.copper", "not a loss source"),
    ({"alpha_k": "-12 %/K"}, "thermal.alpha_k", ">= -0.1"),
    ({"magnets": "axle"}, "thermal.magnets", "axle"),
    ({"T_ref": "25 K/W"}, "thermal.T_ref", "temperature"),
])
def test_thermal_field_errors(changes: dict[str, object], field: str, words: str) -> None:
    with pytest.raises(BldclabError) as exc:
        Drive.from_dict(_file(**changes))
    assert exc.value.field == field
    assert words in str(exc.value)


def test_unreachable_node_refused() -> None:
    with pytest.raises(BldclabError, match="no path of links to a boundary"):
        Thermal(nodes=(ThermalNode("winding", C=1.0), ThermalNode("island", C=1.0), ThermalNode("ambient", T=20.0)),
                links=(ThermalLink("winding", "ambient", 1.0),), losses={"cu": "winding"}, magnets=None)


def test_kelvin_and_celsius() -> None:
    d = _file(nodes__ambient={"T": "313.15 K"})
    assert Drive.from_dict(d).thermal.node("ambient").T == pytest.approx(40.0)  # type: ignore[union-attr]


# ----------------------------------------------------------------------------------------------------------
# coupled runs (multirate with the switching plant), the fast mode, profiles, envelopes

def _fast_network(name: str = "htm-48v-losses", factor: float = 100.0) -> Drive:
    """The catalog drive with its heat capacities divided by ``factor``: minutes become seconds."""
    import dataclasses

    d = catalog.load(name)
    th = d.thermal
    assert th is not None
    nodes = tuple(dataclasses.replace(n, C=n.C / factor) if n.C else n for n in th.nodes)
    return dataclasses.replace(d, thermal=dataclasses.replace(th, nodes=nodes))


def test_coupled_run_heat_balance_and_losses_are_the_plants() -> None:
    import bldclab as bl
    from bldclab.analysis.effmap import map_controls
    from bldclab.sim.thermal import ThermalCoupling

    d = _fast_network()
    res = bl.simulate(d, map_controls(d, 20.0)["square"], bl.Scenario(duration=0.6, speed=40.0, ref=30.0,
                                                                       trace=False),
                      thermal=ThermalCoupling(h=0.05))
    tr = res.thermal
    m = res.metrics
    assert m is not None
    assert abs(tr.balance) < 1e-9
    span = tr.t[-1]
    for b in ("cu", "sw", "diode", "swloss", "fe", "fric"):
        mean = float(np.sum(tr.P[b][1:] * np.diff(tr.t))) / span
        assert mean == pytest.approx(getattr(m, f"p_{b}"), rel=1e-9), b
    assert tr.T["winding"][-1] > tr.T["winding"][0] + 5.0
    assert res.meta["thermal"]["balance"] == tr.balance


def test_coupled_run_hot_winding_scales_copper_loss() -> None:
    """Same regulated current, winding at 125 degC: copper loss x (1 + alpha_R 100 K), the plant's R follows."""
    import bldclab as bl
    from bldclab.analysis.effmap import map_controls
    from bldclab.sim.thermal import ThermalCoupling

    d = catalog.load("htm-48v")  # the slow network: one chunk, temperatures barely move within it
    ctl = map_controls(d, 20.0)["sine"]
    sc = bl.Scenario(duration=0.2, speed=40.0, ref=30.0, trace=False)
    cold = bl.simulate(d, ctl, sc, thermal=ThermalCoupling(h=0.2))
    hot = bl.simulate(d, ctl, sc, thermal=ThermalCoupling(h=0.2, T0={"winding": 125.0}))
    held = bl.simulate(d, ctl, sc, thermal=ThermalCoupling(h=0.2, T0={"winding": 125.0}, follow=False))
    assert hot.metrics is not None and cold.metrics is not None and held.metrics is not None
    r = 1 + 100.0 / 259.5
    assert hot.thermal.r_scale[-1] == pytest.approx(r, rel=1e-12)
    assert hot.metrics.p_cu / cold.metrics.p_cu == pytest.approx(r, rel=2e-3)
    assert held.metrics.p_cu == pytest.approx(cold.metrics.p_cu, rel=1e-12)


def test_coupled_run_refusals() -> None:
    import bldclab as bl
    from bldclab.analysis.effmap import map_controls
    from bldclab.sim.thermal import ThermalCoupling

    ctl = map_controls(catalog.load("lu-4kw"), 20.0)["sine"]
    with pytest.raises(BldclabError, match="no thermal model"):
        bl.simulate(catalog.load("lu-4kw"), ctl, bl.Scenario(duration=0.01, speed=40.0), thermal=ThermalCoupling())
    with pytest.raises(BldclabError) as exc:
        ThermalCoupling(h=0.0)
    assert exc.value.field == "thermal.h"
    with pytest.raises(BldclabError) as exc:
        bl.simulate(catalog.load("htm-48v"), ctl, bl.Scenario(duration=0.01, speed=40.0),
                    thermal=ThermalCoupling(T0={"windng": 50.0}))
    assert exc.value.field == "thermal.T0.windng"


@pytest.mark.parametrize("supply", ["sine", "square"])
def test_fast_mode_agrees_with_switching_run(supply: str) -> None:
    """A 4 s profile of three steps on the fast network: the cycle-averaged mode against every PWM period.

    Measured: winding within 0.10 K (sine) and 0.16 K (square) of rises of 51 K and 70 K; junction within 0.06 K and
    0.6 K of 17 K and 32 K (the square wave's commutation transients after each step of the profile).
    """
    from bldclab.analysis.thermal import LoadProfile, run_profile

    d = _fast_network()
    prof = LoadProfile(times=(0, 1, 1, 3, 3, 4), speed=(40, 40, 60, 60, 20, 20), torque=(30, 30, 20, 20, 40, 40))
    sw = run_profile(d, prof, supply=supply, mode="switching", h=0.02)
    fa = run_profile(d, prof, supply=supply, mode="fast", h=0.02)
    assert sw.trace.t == pytest.approx(fa.trace.t, abs=1e-9)
    for node, rel in (("winding", 0.005), ("stator", 0.005), ("junction", 0.03)):
        rise = sw.trace.T[node][-1] - 25.0
        assert rise > 10.0
        assert np.max(np.abs(sw.trace.T[node] - fa.trace.T[node])) < rel * rise, node
    assert fa.trace.E_loss == pytest.approx(sw.trace.E_loss, rel=2e-3)
    assert abs(fa.trace.balance) < 1e-9 and abs(sw.trace.balance) < 1e-9


def test_profile_file_and_errors(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from bldclab.analysis.thermal import read_profile

    p = tmp_path / "p.toml"
    p.write_text('repeat = 3\ntime = [0, "1 min"]\nspeed = ["100 rpm", "200 rpm"]\ntorque = [5, "10 N m"]\n')
    prof = read_profile(p)
    assert prof.duration == pytest.approx(180.0)
    assert prof.speed_at(np.array([90.0]))[0] == pytest.approx(150 * math.pi / 30)
    assert prof.torque_at(np.array([180.0]))[0] == pytest.approx(10.0)
    for text, field in (('time = [0, 1]\nspeed = [1, "2 V"]\ntorque = [0, 0]\n', "profile.speed[1]"),
                        ('time = [0, 2, 1]\nspeed = [1, 2, 3]\ntorque = [0, 0, 0]\n', "profile.time[2]"),
                        ('time = [1, 2]\nspeed = [1, 2]\ntorque = [0, 0]\n', "profile.time[0]"),
                        ('time = [0, 1]\nspeed = [1, 2]\n', "profile.torque"),
                        ('time = [0, 1]\nspeed = [1, 2]\ntorque = [0, 0]\nrepeat = 0\n', "profile.repeat"),
                        ('time = [0, 1]\nspeed = [1, 2]\ntorque = [0, 0]\nspeeds = 1\n', "profile.speeds")):
        p.write_text(text)
        with pytest.raises(BldclabError) as exc:
            read_profile(p)
        assert exc.value.field == field, text


def test_derating_holds_the_winding() -> None:
    """A derating from 70 to 90 degC of the winding: the torque falls, the winding settles inside the band."""
    from bldclab.analysis.thermal import Derating, LoadProfile, run_profile

    d = _fast_network("htm-48v", 100.0)
    prof = LoadProfile(times=(0.0, 60.0), speed=(40.0, 40.0), torque=(40.0, 40.0))
    free = run_profile(d, prof, h=0.5)
    held = run_profile(d, prof, h=0.5, derate=Derating("winding", 70.0, 90.0))
    assert free.trace.T["winding"].max() > 100.0
    Tw = held.trace.T["winding"]
    assert 70.0 < Tw[-1] < 90.0 and Tw.max() < 90.5
    assert held.trace.extra["derate"][-1] < 0.9


def test_continuous_envelope_is_the_steady_state_of_a_long_run() -> None:
    """The continuous torque at a speed, held for ten of the network's longest time constants from the ambient,
    keeps the winding below its T_max; one torque resolution step more takes it over (a transient run, not the
    envelope's fixed point, decides)."""
    from bldclab.analysis.thermal import LoadProfile, envelope, run_profile

    d = catalog.load("htm-48v")
    tol = 0.002
    env = envelope(d, [40.0], supply="sine", tol=tol)
    q = float(env.torque[0])
    assert env.limiting == ["winding"]
    assert 0.2 * d.T_N < q < 2 * d.T_N
    tmax = 10 * float(d.thermal.network().time_constants[0])  # type: ignore[union-attr]
    peaks = []
    for torque in (q, q + 2 * tol * d.T_N):
        run = run_profile(d, LoadProfile(times=(0.0, tmax), speed=(40.0, 40.0), torque=(torque, torque)), h=30.0,
                          compensated=True)
        peaks.append(float(run.trace.T["winding"].max()))
    assert 140.0 < peaks[0] <= 155.0 < peaks[1]


def test_unrouted_loss_refused_when_run() -> None:
    """A drive with a loss its network does not route is refused by a thermal run, naming the source."""
    from bldclab.analysis.thermal import LoadProfile, run_profile

    d = Drive.from_dict(_file(losses__cu=None))
    with pytest.raises(BldclabError) as exc:
        run_profile(d, LoadProfile(times=(0.0, 1.0), speed=(40.0, 40.0), torque=(5.0, 5.0)))
    assert exc.value.field == "thermal.losses.cu"


def test_cli_thermal(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    from bldclab.cli import main

    prof = tmp_path / "p.toml"
    prof.write_text('name = "short"\ntime = [0, "20 s"]\nspeed = ["300 rpm", "300 rpm"]\n'
                    'torque = ["20 N m", "20 N m"]\n')
    out = tmp_path / "t.csv"
    rc = main(["thermal", "htm-48v", "--profile", str(prof), "--step", "5 s", "--ambient", "40 degC",
               "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert "winding" in text and "balance" in text and out.is_file()
    import pandas as pd

    df = pd.read_csv(out)
    assert list(df["t"]) == [0.0, 5.0, 10.0, 15.0, 20.0]
    assert df["T_ambient"].iloc[0] == 40.0 and df["T_winding"].iloc[-1] > 40.0
    rc = main(["thermal", "lu-4kw", "--profile", str(prof)])
    err = capsys.readouterr().err
    assert rc == 2 and "no thermal model" in err
    rc = main(["thermal", "htm-48v", "--profile", str(prof), "--derate", "winding:130"])
    assert rc == 2 and "--derate" in capsys.readouterr().err
    env = tmp_path / "env.csv"
    rc = main(["thermal", "htm-48v", "--envelope", "--speeds", "200 rpm", "--durations", "60 s", "--out", str(env)])
    text = capsys.readouterr().out
    assert rc == 0 and "sine cont" in text and "winding" in text
    table = pd.read_csv(env)
    assert table["square cont limit"][0] == "winding" and 0.5 < table["sine cont"][0] / table["square cont"][0] < 2
    rc = main(["thermal", "htm-48v", "--envelope", "--speeds", "-3 rpm"])
    assert rc == 2 and "--speeds" in capsys.readouterr().err


def test_derating_factor_is_the_firmwares_band() -> None:
    """Derating.factor runs bc_derate_step: 1, linear, f_min, never outside [0, 1]."""
    from bldclab.analysis.thermal import Derating

    d = Derating("winding", 100.0, 150.0, f_min=0.2)
    for T, f in ((25.0, 1.0), (100.0, 1.0), (125.0, 0.6), (140.0, 0.36), (150.0, 0.2), (400.0, 0.2)):
        assert d.factor(T) == pytest.approx(f, abs=1e-6)
    assert Derating("winding", 100.0, 150.0).factor(151.0) == 0.0
    with pytest.raises(BldclabError) as exc:
        Derating("winding", 100.0, 90.0)
    assert exc.value.field == "derating.T_end"


def test_winding_temperature_from_measured_resistance() -> None:
    """The firmware's resistance method inverts the model's R(T) (copper, 234.5 degC) to float precision."""
    from bldclab.analysis.thermal import temperature_from_resistance

    d = catalog.load("htm-48v")
    for T in (-20.0, 25.0, 80.0, 155.0):
        R = d.at_temperature(winding=T).motor.R
        assert temperature_from_resistance(R, d.motor.R, 25.0) == pytest.approx(T, abs=1e-4 * (234.5 + T))
    with pytest.raises(BldclabError):
        temperature_from_resistance(0.0, d.motor.R)
    with pytest.raises(BldclabError):
        temperature_from_resistance(float("nan"), d.motor.R)


# ----------------------------------------------------------------------------------------------------------
# the controllers' own derating (bc_derate in bc_sixstep and bc_sine, fed by the network's sensor nodes)

@pytest.mark.parametrize("supply", ["square", "sine"])
def test_controller_derating_holds_the_winding_in_a_coupled_run(supply: str) -> None:
    """The firmware derates its current limit from the winding sensor: the winding settles in the band."""
    import bldclab as bl
    from bldclab.control import Sine, SixStep, TemperatureDerating
    from bldclab.sim.thermal import ThermalCoupling

    d = _fast_network("htm-48v", 100.0)
    der = TemperatureDerating(winding=(60.0, 80.0))
    ctl = SixStep(reference="torque", derate=der) if supply == "square" else Sine(handoff_speed=10.0, derate=der)
    free = SixStep(reference="torque") if supply == "square" else Sine(handoff_speed=10.0)
    sc = bl.Scenario(duration=30.0, speed=40.0, ref=40.0, trace=False)
    hot = bl.simulate(d, free, sc, thermal=ThermalCoupling(h=0.1))
    held = bl.simulate(d, ctl, sc, thermal=ThermalCoupling(h=0.1))
    assert hot.thermal.T["winding"][-1] > 100.0
    Tw = held.thermal.T["winding"]
    assert 60.0 < Tw[-1] < 80.0 and Tw.max() < 81.0
    tau = held.thermal.extra["tau"]
    assert tau[-1] < 0.8 * tau[5]  # the torque fell as the winding warmed


def test_controller_derating_without_a_sensor_reads_a_fault() -> None:
    """No temperature sensor (NaN inputs): the derating's f_fault limits the current, as firmware must."""
    import bldclab as bl
    from bldclab.control import SixStep, TemperatureDerating

    d = catalog.load("htm-48v")
    sc = bl.Scenario(duration=0.1, speed=40.0, ref=20.0, window=(0.05, 0.1))
    full = bl.simulate(d, SixStep(reference="torque"), sc).metrics
    faulted = bl.simulate(d, SixStep(reference="torque", derate=TemperatureDerating(winding=(100.0, 150.0),
                                                                                     f_fault=0.5)), sc).metrics
    assert full is not None and faulted is not None
    i_max = 2 * d.motor.I_N
    # 20 N m needs 31 A, below the faulted limit 0.5 i_max = 50 A: no change; 60 N m (94 A) is capped at 50 A
    assert faulted.tau_mean == pytest.approx(full.tau_mean, rel=2e-3)
    sc2 = bl.Scenario(duration=0.1, speed=40.0, ref=60.0, window=(0.05, 0.1))
    capped = bl.simulate(d, SixStep(reference="torque", derate=TemperatureDerating(winding=(100.0, 150.0),
                                                                                    f_fault=0.5)), sc2).metrics
    assert capped is not None
    assert capped.tau_mean == pytest.approx(0.5 * i_max * 2 * d.motor.k_phi, rel=0.05)
    with pytest.raises(BldclabError) as exc:
        TemperatureDerating()
    assert exc.value.field == "derate"


# ---------------------------------------------------------------------------------------------------------------
# the second catalog drive with a network (servo-2k2), the sine controller's current limit, maps at temperature

def test_servo_network_meets_its_stated_calibration() -> None:
    """servo-2k2's file: the rated 4.3 A rms held at 40 degC ambient puts the winding at 140 degC (the 100 K rating
    its comments calibrate to), with R at the winding's temperature (closed form of the steady network)."""
    d = catalog.load("servo-2k2")
    th = d.thermal
    assert th is not None
    net = th.with_ambient(40.0).network()
    P_cu = 3 * d.motor.R * (1 + th.alpha_R_value * (140.0 - th.T_ref)) * 4.3**2
    T = net.temps(net.steady(net.heat({"cu": P_cu})[0]))
    assert T["winding"] == pytest.approx(140.0, abs=0.5)
    assert 15 * 60 < float(net.time_constants[0]) < 60 * 60  # a self-cooled servo's tens of minutes


@pytest.mark.parametrize("supply", ["sine", "square"])
def test_servo_continuous_envelope_brackets_the_winding_limit(supply: str) -> None:
    """servo-2k2 at 500 rpm: the continuous reference held for ten of the network's longest time constants keeps
    the winding at or below 155 degC, one resolution step more exceeds it; the delivered torque is the reference's
    (within the controller's torque-per-reference factor)."""
    from bldclab.analysis.thermal import LoadProfile, envelope, envelope_controls, run_profile

    d = catalog.load("servo-2k2")
    w, tol = 500 * math.pi / 30, 0.002
    env = envelope(d, [w], supply=supply, tol=tol)
    assert env.limiting == ["winding"]
    q = float(env.reference[0])
    assert 0.5 * d.T_N < q < 2 * d.T_N and 0.93 * q < env.torque[0] <= 1.001 * q
    tmax = 10 * float(d.thermal.network().time_constants[0])  # type: ignore[union-attr]
    peaks = []
    for torque in (q, q + 2 * tol * d.T_N):
        run = run_profile(d, LoadProfile(times=(0.0, tmax), speed=(w, w), torque=(torque, torque)), h=60.0,
                          control=envelope_controls(d, w)[supply], compensated=True)
        peaks.append(float(run.trace.T["winding"].max()))
    assert 145.0 < peaks[0] <= 155.0 < peaks[1]


def test_sixty_second_envelope_is_the_current_limit_given() -> None:
    """Within 60 s from cold no node of servo-2k2 reaches its limit at 500 rpm: the envelope is the controllers'
    current limit ``i_limit``, torque 1.5 k_1 i_limit for the sinusoidal supply (the magnets barely warm), and it
    scales with the limit given."""
    from bldclab.analysis.thermal import envelope
    from bldclab.control.sine import fundamental_k1

    d = catalog.load("servo-2k2")
    w = 500 * math.pi / 30
    k1 = fundamental_k1(d)
    for i_lim in (2.0 * d.motor.I_N, 1.5 * d.motor.I_N):
        env = envelope(d, [w], supply="sine", duration=60.0, i_limit=i_lim, tol=0.002)
        assert env.limiting == ["delivery"] and env.i_limit == i_lim
        assert float(env.torque[0]) == pytest.approx(1.5 * k1 * i_lim, rel=0.01)


def test_sine_current_limit_setting() -> None:
    """Sine(i_s_max=...) is the amplitude the controller regulates to: the mean torque at a saturating reference is
    1.5 k_1 i_s_max (paper 1 (45)); a bad value or one above the trip names the field."""
    from bldclab.analysis.experiments import steady_state
    from bldclab.control import Sine
    from bldclab.control.sine import fundamental_k1
    from bldclab.model.analytic import i_sN

    d = catalog.load("servo-2k2")
    w = 500 * math.pi / 30
    k1 = fundamental_k1(d)
    for i_s in (None, 1.8 * d.motor.I_N):
        c = Sine(handoff_speed=0.5 * w, i_s_max=i_s, i_max=2.5 * d.motor.I_N)
        point, _ = steady_state(d, c, w, 2.0 * d.T_N)
        expect = 1.5 * k1 * (i_sN(d) if i_s is None else i_s)
        assert point.tau_mean == pytest.approx(expect, rel=0.01)
    for bad in (0.0, -1.0, math.nan, "5 A"):
        with pytest.raises(BldclabError) as exc:
            Sine(i_s_max=bad)  # type: ignore[arg-type]
        assert exc.value.field == "control.i_s_max"
    with pytest.raises(BldclabError) as exc:
        steady_state(d, Sine(handoff_speed=0.5 * w, i_s_max=2.5 * d.motor.I_N), w, d.T_N)  # trip 2 I_N below it
    assert exc.value.field == "control.i_s_max" and "i_max" in exc.value.problem


def test_effmap_at_temperature_cli(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """``bldclab effmap MOTOR --temperature``: servo-2k2's only loss is copper, so at every point the hot map's
    copper loss is the cold one's times R(T)/R(T_ref) over the flux factor squared (the current for a torque rises
    as the magnets weaken), and its efficiency is lower. Bad values exit 2 and write nothing."""
    import pandas as pd

    from bldclab.cli import main

    d = catalog.load("servo-2k2")
    th = d.thermal
    assert th is not None
    maps = {}
    for key, extra in (("cold", []), ("hot", ["--temperature", "120 degC"])):
        out = tmp_path / key
        assert main(["effmap", "servo-2k2", "--torques", "2", "--speeds", "2", "--min-torque", "0.3",
                     "--max-torque", "0.8", "--min-speed", "0.3", "--max-speed", "0.6", "--no-store", "--workers",
                     "1", "--out", str(out), *extra]) == 0
        maps[key] = pd.read_csv(out / "effmap.csv")
    r, k, _ = th.scales({"winding": 120.0, "rotor": 120.0})
    cold, hot = maps["cold"], maps["hot"]
    assert len(cold) == len(hot) == 8
    assert np.allclose(cold.torque_ref, hot.torque_ref) and np.allclose(cold.speed, hot.speed)  # the same grid
    both = cold.feasible & hot.feasible
    assert both[cold.supply == "sine"].all() and both.sum() >= 6
    ratio = hot.p_cu[both] / cold.p_cu[both]
    assert np.allclose(ratio, r / k**2, rtol=0.01), (ratio.tolist(), r / k**2)
    assert (hot.efficiency[both] < cold.efficiency[both]).all()
    capsys.readouterr()
    for bad, words in (("120 V", "--temperature"), ("-300 degC", "absolute zero")):
        assert main(["effmap", "servo-2k2", "--temperature", bad, "--out", str(tmp_path / "bad")]) == 2
        assert words in capsys.readouterr().err
    assert main(["effmap", "outrunner-24v", "--temperature", "80 degC", "--out", str(tmp_path / "bad")]) == 2
    assert "[thermal]" in capsys.readouterr().err
    assert not (tmp_path / "bad").exists()


# ---------------------------------------------------------------------------------------------------------------
# the winding resistance during operation (bc_rest.h in bc_sine)

def test_resistance_estimate_feeds_the_derating_without_a_sensor() -> None:
    """No winding sensor: without the estimate the derating reads a fault (f_fault); with the d-axis injection the
    controller's resistance estimate gives the winding temperature, and the derating holds the winding in its band,
    as with a sensor (htm-48v, capacities / 100, 40 N m at 40 rad/s)."""
    import dataclasses

    import bldclab as bl
    from bldclab.control import ResistanceEstimate, Sine, TemperatureDerating
    from bldclab.sim.thermal import ThermalCoupling

    d = _fast_network("htm-48v", 100.0)
    d = dataclasses.replace(d, thermal=dataclasses.replace(d.thermal, sensor_winding=None))  # type: ignore[arg-type]
    der = TemperatureDerating(winding=(60.0, 80.0), f_fault=0.3)
    sc = bl.Scenario(duration=30.0, speed=40.0, ref=40.0, trace=False)
    blind = bl.simulate(d, Sine(handoff_speed=10.0, derate=der), sc, thermal=ThermalCoupling(h=0.1)).thermal
    est = bl.simulate(d, Sine(handoff_speed=10.0, derate=der, r_estimate=ResistanceEstimate(current=5.0)), sc,
                      thermal=ThermalCoupling(h=0.1)).thermal
    # blind: f_fault of the current limit from the first sample, the winding stays cool
    assert blind.extra["tau"][-1] == pytest.approx(0.3 * 1.5 * _k1(d) * _isn(d), rel=0.02)
    assert blind.T["winding"].max() < 50.0
    # the estimate: the full current limit (1.5 k_1 I_s,N, 34 N m) while cold, then derated, the winding in the band
    Tw = est.T["winding"]
    assert est.extra["tau"][5] == pytest.approx(1.5 * _k1(d) * _isn(d), rel=0.02)
    assert est.extra["tau"][-1] < 0.6 * est.extra["tau"][5]
    assert 60.0 < Tw[-1] < 80.0 and Tw.max() < 82.0


def _k1(d: Drive) -> float:
    from bldclab.control.sine import fundamental_k1

    return fundamental_k1(d)


def _isn(d: Drive) -> float:
    from bldclab.model.analytic import i_sN

    return i_sN(d)


def test_resistance_injection_costs_its_copper_loss_not_torque() -> None:
    """The d-axis square wave leaves the torque (non-salient: 3/2 k_1 i_q) and adds its copper loss, 3/2 R i_inj^2
    (the square wave's rms is its amplitude); bad settings name the field."""
    import bldclab as bl
    from bldclab.control import ResistanceEstimate, Sine

    d = catalog.load("htm-48v")
    sc = bl.Scenario(duration=0.5, speed=40.0, ref=20.0, window=(0.1, 0.5), trace=False)
    base = bl.simulate(d, Sine(handoff_speed=10.0), sc).metrics
    inj = bl.simulate(d, Sine(handoff_speed=10.0, r_estimate=ResistanceEstimate(current=5.0)), sc).metrics
    assert base is not None and inj is not None
    assert inj.tau_mean == pytest.approx(base.tau_mean, rel=2e-3)
    assert inj.p_cu - base.p_cu == pytest.approx(1.5 * d.motor.R * 5.0**2, rel=0.1)
    for kw, field in (({"current": 0.0}, "r_estimate.current"), ({"current": 5.0, "period": -1.0},
                                                                  "r_estimate.period"),
                      ({"current": 5.0, "filter": 1.5}, "r_estimate.filter")):
        with pytest.raises(BldclabError) as exc:
            ResistanceEstimate(**kw)  # type: ignore[arg-type]
        assert exc.value.field == field
    for est, field in ((ResistanceEstimate(current=200.0), "control.r_estimate.current"),
                       (ResistanceEstimate(current=5.0, period=1e-4), "control.r_estimate.period")):
        with pytest.raises(BldclabError) as exc:
            bl.simulate(d, Sine(r_estimate=est), bl.Scenario(duration=0.01, speed=40.0, ref=5.0))
        assert exc.value.field == field
    with pytest.raises(BldclabError) as exc:
        Sine(r_estimate=5.0)  # type: ignore[arg-type]
    assert exc.value.field == "control.r_estimate"


def test_cli_envelope_current_limit(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    """``bldclab thermal --envelope --current-limit``: the 60 s envelope of servo-2k2 at 500 rpm is the sinusoidal
    supply's 1.5 k_1 i_limit (no node near its limit in 60 s); bad values exit 2 and write nothing."""
    import pandas as pd

    from bldclab.cli import main

    d = catalog.load("servo-2k2")
    out = tmp_path / "env.csv"
    assert main(["thermal", "servo-2k2", "--envelope", "--speeds", "500 rpm", "--durations", "60 s",
                 "--current-limit", "8 A", "--out", str(out)]) == 0
    assert "8 A peak" in capsys.readouterr().out
    env = pd.read_csv(out)
    assert float(env["sine 60 s"][0]) == pytest.approx(1.5 * _k1(d) * 8.0, rel=0.01)
    assert env["sine 60 s limit"][0] == "delivery"
    for args, words in ((["--envelope", "--current-limit", "-2 A"], "must be a current > 0"),
                        (["--envelope", "--current-limit", "2 V"], "--current-limit"),
                        (["--profile", "examples/profiles/hill-climb.toml", "--current-limit", "2 A"],
                         "option of --envelope")):
        assert main(["thermal", "servo-2k2", *args, "--out", str(tmp_path / "bad.csv")]) == 2
        assert words in capsys.readouterr().err
    assert not (tmp_path / "bad.csv").exists()

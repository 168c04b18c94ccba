"""The Python-C contract: constants and flags come from the library's tables, parameter records are filled
completely (a member left unset or unknown is an error), and controllers own the memory their records point to."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import bldclab as bl
import bldclab._core as bcore
from bldclab._core import CParams, core
from bldclab.errors import BldclabError

CORE = Path(__file__).resolve().parents[1] / "core"

# one configuration per registered controller (every chopping / option with its own constant as well)
CONTROLS = {
    "table": [bl.OpenLoop(modes=[[0, 0, 0]], duties=[[0.0, 0.0, 0.0]])],
    "sixv": [bl.SixStepVoltage(chopping=c) for c in ("high", "low", "bipolar", "sync")],
    "sixstep": [bl.SixStep(regulation=r, chopping=c) for r in ("predictive", "pi", "hysteresis")
                for c in ("pwm-on-pwm", "bipolar", "high", "sync")],
    "sine": [bl.Sine(), bl.Sine(angle="encoder", limit="circle"), bl.Sine(angle="pll"), bl.Sine(angle="observer"),
             bl.Sine(angle="observer", observer="reduced", speed_loop=True)],
    "lu": [bl.Lu(method=m) for m in ("lu", "lu-no-do", "rect")] + [bl.Lu(hall_angle="pll")],
    "hallcal": [bl.HallCal(), bl.HallCal(method="open-loop")],
    "commission": [bl.control.Commission()],
    "bemf": [bl.SixStepSensorless(method=m, chopping=c, blanking=b)
             for m, c, b in (("comparator", "sync", "demag"), ("adc", "high", "fixed"),
                             ("integration", "pwm-on-pwm", "demag"), ("comparator", "bipolar", "fixed"))],
}


def _c_macros() -> dict[str, int]:
    """Integer #defines of the ctrl and host headers, read here only to check the table against the source."""
    out = {}
    for h in [*(CORE / "ctrl" / "include" / "bldc").glob("*.h"), *(CORE / "host" / "include" / "bldc").glob("*.h")]:
        for name, val in re.findall(r"^#define (BC_\w+) \(?(-?(?:0x[0-9a-fA-F]+|\d+))u?\)?\s*(?:/\*.*)?$",
                                    h.read_text(), flags=re.M):
            out[name] = int(val, 0)
    return out


def test_every_registered_controller_is_covered():
    assert set(core().controllers) == set(CONTROLS)


@pytest.mark.parametrize("name", sorted(CONTROLS))
def test_every_params_member_is_filled_and_init_accepts_it(name):
    c = core()
    info = c.controllers[name]
    drive = bl.load("lu-4kw" if name == "lu" else "htm-48v")
    for ctl in CONTROLS[name]:
        assert ctl.c_name == name
        params = ctl.c_record(drive, c, 100)  # core.filled raises on any member left unset
        assert isinstance(params, CParams)
        assert params.record.dtype == c.dtypes[info.params]
        state = c.opaque(info.state)
        assert c.controller_init(info, params.record, state) == 0, ctl


def test_a_controller_without_c_record_is_refused():
    class Bare(bl.Control):
        c_name = "sixv"

    d = bl.load("htm-48v")
    with pytest.raises(NotImplementedError, match="Bare does not implement c_record"):
        bl.simulate(d, Bare(), bl.Scenario(duration=1e-3, speed=0.3 * d.Omega_0, ref=0.5))


def test_flag_bits_come_from_the_library():
    assert bl.flag("SAFE") == core().const("BC_FLAG_SAFE") and bl.decode_flags(bl.flag("SATURATED")) == "SATURATED"
    with pytest.raises(KeyError):
        bl.flag("NO_SUCH_FLAG")


def test_filled_names_every_unset_and_unknown_member():
    c = core()
    members = c.dtypes["bc_sixstep_params"].names
    full = dict.fromkeys(members, 1)
    rec = c.filled("bc_sixstep_params", **full)
    for m in members:  # a nested struct (hall_table) has every field set
        sub = rec.dtype[m].names
        assert all(np.all(rec[m][0][f] == 1) for f in sub) if sub else np.all(rec[m][0] == 1), m
    partial = {k: v for k, v in full.items() if k not in ("v_max", "theta_offset")}
    with pytest.raises(BldclabError, match=r"bc_sixstep_params.*left unset: v_max, theta_offset"):
        c.filled("bc_sixstep_params", **partial)
    with pytest.raises(BldclabError, match=r"not members: vmax"):
        c.filled("bc_sixstep_params", **full, vmax=1.0)


def test_a_control_that_forgets_a_member_fails(monkeypatch):
    c = core()
    real = c.filled

    def forgetful(name, **fields):
        fields.pop("i_max", None)
        return real(name, **fields)

    monkeypatch.setattr(c, "filled", forgetful)
    with pytest.raises(BldclabError, match="i_max"):
        bl.SixStep().c_record(bl.load("htm-48v"), c, 10)


def test_constants_match_the_headers():
    """The library's table and the headers agree (a table entry naming the wrong macro would show here)."""
    macros = _c_macros()
    table = core().constants
    assert len(table) > 40
    for name, value in table.items():
        assert macros.get(name) == value, name
    flags = {n for n in macros if n.startswith("BC_FLAG_")}
    assert flags == set(core().groups["flag"]), "every controller flag is in the table"
    assert bcore.BC_FLAG_OVERCURRENT == table["BC_FLAG_OVERCURRENT"]
    with pytest.raises(AttributeError):
        _ = bcore.BC_NO_SUCH_THING


def test_decode_flags():
    k = core().groups["flag"]
    assert bcore.decode_flags(0) == ""
    assert bcore.decode_flags(k["BC_FLAG_SAFE"] | k["BC_FLAG_OVERCURRENT"]) == "SAFE|OVERCURRENT"
    every = 0
    for name, bit in k.items():
        assert bcore.decode_flags(bit) == name.removeprefix("BC_FLAG_")
        every |= bit
    assert bcore.decode_flags(every).count("|") == len(k) - 1
    unknown = 1 << 20
    assert bcore.decode_flags(unknown | k["BC_FLAG_SAFE"]) == f"SAFE|{hex(unknown)}"
    assert bcore.decode_flags(np.uint32(k["BC_FLAG_SATURATED"])) == "SATURATED"


def test_controllers_restate_no_c_constant():
    """Settings map to C constant names, never to numbers (the values come from the library)."""
    src = Path(bl.__file__).parent / "control"
    for f in src.glob("*.py"):
        for line in f.read_text().splitlines():
            m = re.match(r"^_([A-Z]+) = \{(.*)\}", line)
            if m and m.group(1) != "REF":  # ref_torque is a 0/1 switch, not a C constant
                assert re.search(r'"BC_\w+"', m.group(2)) and not re.search(r":\s*-?\d", m.group(2)), (f.name, line)


def test_the_plant_integrator_cache_is_private():
    """The binding describes the plant state a caller reads; the integrator's work memory is not part of it."""
    names = set(core().dtypes["bc_plant_state"].names)
    assert {"t", "i", "theta", "omega", "acc", "flags"} <= names
    assert not names & {"work", "k1", "k1_valid", "wcache", "aux_tau", "wdir"}

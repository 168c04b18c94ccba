"""``bldclab template``: a commented motor file to start from, every field with its unit and meaning.

The file is a drive's :meth:`~bldclab.model.motor.Drive.to_toml` (so it loads back to the same drive) with a comment
above every field; optional parts the drive does not use are shown commented out.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

from .._files import write_atomic
from ..errors import BldclabError
from ..model.catalog import load
from ..model.motor import Drive
from ..model.thermal import LOSS_SOURCES
from .paths import check_out_file

__all__ = ["FIELDS", "configure_command", "run_command", "template"]

#: (table, key) -> "unit: meaning" written above the field. Units are those of the numbers bldclab writes (SI);
#: a string with a unit ("75 uH", "640 rpm", "120 deg") is accepted too (docs/motor-files.md).
FIELDS: dict[tuple[str, str], str] = {
    ("", "name"): "the drive's name (default: the file name without .toml)",
    ("", "description"): "free text: where the numbers come from, which are assumed",
    ("motor", "p"): "pole pairs (integer >= 1; or poles = 2 p, the pole count)",
    ("motor", "R"): "Ohm: phase resistance (>= 0; or R_ll = 2 R, line to line)",
    ("motor", "L"): "H: phase inductance L_self - M (> 0; or L_ll = 2 L, line to line)",
    ("motor", "V_N"): "V: nominal voltage",
    ("motor", "I_N"): "A: nominal current, the square-wave current amplitude of the rating",
    ("motor", "Omega_N"): "rad/s: rated speed (optional; default (V_N - 2 R I_N) / (2 k_phi))",
    ("motor", "T_peak"): "N m: peak torque (optional, informative)",
    ("motor", "P_fe_eddy"): "W: stator iron loss, eddy-current part, at speed_fe_ref (default 0: no iron loss)",
    ("motor", "P_fe_hyst"): "W: stator iron loss, hysteresis part, at speed_fe_ref",
    ("motor", "P_fe_ex"): "W: stator iron loss, excess part, at speed_fe_ref",
    ("motor", "speed_fe_ref"): "rad/s: speed of the iron-loss data (required with any P_fe_*)",
    ("motor.emf", "kind"): "back-EMF shape: trapezoid (k_phi, flat_top), sinusoid (k_1), fourier (a, b), table "
                           "(theta, k or k_a/k_b/k_c)",
    ("motor.emf", "k_phi"): "V s/rad: flat-top back-EMF per mechanical rad/s (or KV = \"... rpm/V\" in [motor])",
    ("motor.emf", "flat_top"): "rad: width of the flat top in electrical angle (2.0944 rad = 120 deg)",
    ("motor.emf", "k_1"): "V s/rad: peak phase back-EMF per mechanical rad/s (or KV = \"... rpm/V\" in [motor])",
    ("motor.emf", "a"): "V s/rad (see unit): cosine coefficients, index = harmonic order",
    ("motor.emf", "b"): "V s/rad (see unit): sine coefficients, index = harmonic order",
    ("motor.emf", "unit"): "unit of the shape values (default V s/rad)",
    ("motor.emf", "theta"): "rad (see theta_unit): the phase's own electrical angle, one period",
    ("motor.emf", "theta_unit"): "unit of theta (default rad)",
    ("motor.emf", "k"): "V s/rad: shape values at theta, the same for the three phases",
    ("motor.emf", "k_a"): "V s/rad: phase a's shape values at theta",
    ("motor.emf", "k_b"): "V s/rad: phase b's shape values at theta",
    ("motor.emf", "k_c"): "V s/rad: phase c's shape values at theta",
    ("inverter", "V_dc"): "V: DC bus voltage",
    ("inverter", "f_pwm"): "Hz: PWM carrier frequency (controllers sample at 2 f_pwm)",
    ("inverter", "t_dead"): "s: dead time (below a quarter PWM period)",
    ("inverter", "R_on"): "Ohm: switch on-resistance",
    ("inverter", "V_f"): "V: diode forward voltage",
    ("inverter", "r_d"): "Ohm: diode slope resistance",
    ("inverter", "R_src"): "Ohm: DC source internal resistance",
    ("inverter", "i_trip"): "A: hardware over-current trip, latched (0: none)",
    ("inverter", "model"): "switching (every gate edge) or average (half-period averages, no PWM ripple)",
    ("inverter", "E_on"): "J: switch turn-on energy at V_test, I_test (datasheet; or give t_rise instead)",
    ("inverter", "E_off"): "J: switch turn-off energy at V_test, I_test (or t_fall)",
    ("inverter", "E_rr"): "J: diode reverse-recovery energy at V_test, I_test (or Q_rr)",
    ("inverter", "V_test"): "V: test voltage of the switching energies",
    ("inverter", "I_test"): "A: test current of the switching energies",
    ("motor.cogging", "orders"): "harmonic orders n_j in the mechanical angle (integers >= 1)",
    ("motor.cogging", "amplitudes"): "N m: amplitudes A_j of sum_j A_j sin(n_j theta_m + phi_j)",
    ("motor.cogging", "phases"): "rad: phases phi_j",
    ("mechanics", "J"): "kg m^2: inertia of rotor and load",
    ("mechanics", "B"): "N m s/rad: viscous friction",
    ("mechanics", "tau_c"): "N m: Coulomb friction",
    ("mechanics", "k_q"): "N m s^2/rad^2: propeller or fan load k_q omega^2 (rotor dynamics; 0: none)",
    ("sensors", "current_phases"): "measured phase currents: two or three of a, b, c",
    ("sensors", "current_gain"): "-: gain of each current sensor (a, b, c)",
    ("sensors", "current_offset"): "A: offset of each current sensor (a, b, c)",
    ("sensors", "current_noise"): "A: standard deviation of the current measurement noise",
    ("sensors", "current_lsb"): "A: current quantisation step (0: none)",
    ("sensors", "current_full_scale"): "A: full scale of the current measurement, a reading clips to +-it (> 0)",
    ("sensors", "vdc_gain"): "-: gain of the DC-bus voltage measurement",
    ("sensors", "vdc_offset"): "V: offset of the DC-bus voltage measurement",
    ("sensors", "vdc_noise"): "V: standard deviation of its noise",
    ("sensors", "vdc_lsb"): "V: its quantisation step (0: none)",
    ("sensors", "hall_error"): "rad: electrical angle error of each Hall sensor (a, b, c)",
    ("sensors", "hall_hysteresis"): "rad: electrical hysteresis of the Hall sensors (one value or a, b, c)",
    ("sensors", "hall_delay"): "s: propagation delay of the Hall edges (one value or a, b, c)",
    ("sensors", "hall_tau"): "s: RC filter time constant on the Hall lines (one value or a, b, c; 0: none)",
    ("sensors", "f_tick"): "Hz: capture-timer frequency time-stamping the Hall edges",
    ("sensors", "seed"): "seed of the noise generator (integer >= 0)",
    ("thermal", "T_ref"): "degC: temperature at which R, the back-EMF and R_on above are given",
    ("thermal", "alpha_R"): "1/K: winding resistance coefficient (default copper's 1 / (234.5 + T_ref))",
    ("thermal", "alpha_k"): "1/K: the magnets' flux coefficient (sintered NdFeB about -0.0012)",
    ("thermal", "alpha_Ron"): "1/K: the switches' on-resistance coefficient (0: none)",
    ("thermal", "winding"): "node(s) whose mean temperature sets R",
    ("thermal", "magnets"): "node whose temperature sets the back-EMF",
    ("thermal", "switches"): "node(s) whose mean temperature sets R_on",
    ("thermal", "sensor_winding"): "node a winding temperature sensor reads",
    ("thermal", "sensor_switch"): "node a switch (heat sink) temperature sensor reads",
    ("thermal.links", "between"): "the two nodes a thermal resistance joins",
    ("thermal.links", "R"): "K/W: its thermal resistance",
}

def _optional(drive: Drive) -> dict[str, list[str]]:
    """Return the optional fields and tables shown commented out when the drive does not use them, per table.

    Every example value is this drive's (its own default rated speed, twice its torque base, its bus and rated
    current), written with its unit in the string so that no comment names another unit.
    """
    m, inv = drive.motor, drive.inverter
    rpm = m.Omega_nominal * 30.0 / math.pi
    e_on = inv.V_dc * m.I_N * 20e-9 / 2.0  # a 20 ns rise at V_dc, I_N (docs/motor-files.md: E = V I t / 2)
    return {
        "motor": [f'# Omega_N = "{rpm:.4g} rpm"  # rated speed (optional; without it (V_N - 2 R I_N) / (2 k_phi), '
                  f"{rpm:.4g} rpm here)",
                  f'# T_peak = "{2.0 * drive.T_N:.3g} N m"  # peak torque (optional, informative; here 2 T_N)',
                  '# P_fe_eddy = "0 W"  # iron loss (optional, default none): eddy-current part at speed_fe_ref',
                  '# P_fe_hyst = "0 W"  # iron loss, hysteresis part at speed_fe_ref',
                  '# P_fe_ex = "0 W"  # iron loss, excess part at speed_fe_ref',
                  f'# speed_fe_ref = "{rpm:.4g} rpm"  # speed of the iron-loss data (a plain number: rad/s)',
                  "# (or, instead of P_fe_*: a [motor.iron] table, a steel grade with core mass and flux density: "
                  "docs/motor-files.md)"],
        "motor.emf": ["", "# [motor.cogging]  # optional: cogging torque sum_j A_j sin(n_j theta_m + phi_j), theta_m "
                      "the mechanical angle",
                      f"# orders = [{6 * m.p}]  # n_j: harmonic orders in the mechanical angle (integers >= 1; here "
                      "6 p, an integral-slot winding's)",
                      f"# amplitudes = [{0.01 * drive.T_N:.3g}]  # A_j: N m (here 1 % of T_N)",
                      "# phases = [0.0]  # phi_j: rad"],
        "inverter": ["# model: switching (every gate edge) or average (half-period averages, no PWM ripple)",
                     '# model = "switching"',
                     f'# E_on = "{e_on * 1e6:.3g} uJ"  # switching losses (optional, default none): turn-on energy '
                     'at V_test, I_test (here a 20 ns rise; or t_rise = "20 ns")',
                     f'# E_off = "{e_on * 1e6:.3g} uJ"  # turn-off energy (or t_fall = "20 ns")',
                     '# E_rr = "0 uJ"  # diode reverse-recovery energy (or Q_rr = "50 nC")',
                     f'# V_test = "{inv.V_dc:g} V"  # test voltage of the energies (here V_dc)',
                     f'# I_test = "{m.I_N:g} A"  # test current of the energies (here I_N)'],
        "sensors": [f'# current_full_scale = "{2.0 * m.I_N:.4g} A"  # full scale of the current measurement '
                    "(optional, default none): a reading clips to +-it, as a shunt amplifier and its ADC saturate "
                    "(here 2 I_N)"],
    }


_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)\s*=")
_TABLE = re.compile(r"^\[\[?([A-Za-z0-9_.]+)\]\]?\s*$")

HEADER = """\
# bldclab motor file (format: docs/motor-files.md). Numbers are SI (the unit is in the comment above each field);
# a string with a unit works too: R = "50 mOhm", L = "75 uH", Omega_N = "640 rpm", flat_top = "120 deg".
# Check it with: bldclab check FILE.toml
"""


def template(source: str) -> str:
    """Return the commented motor file of a drive.

    Parameters
    ----------
    source : str
        A built-in drive name or a motor file path.

    Returns
    -------
    str
        TOML text that loads back (:func:`bldclab.model.catalog.load`) to the same drive.
    """
    drive = load(source)
    optional = _optional(drive)
    out = [HEADER.rstrip("\n"), f"# Written by bldclab template from {source}.", ""]
    table = ""
    present: set[str] = set()

    def close(tbl: str) -> None:
        extra = [line for line in optional.get(tbl, []) if not any(
            line.startswith((f"# {k} =", f"# {k}:")) for k in present)]
        if tbl == "motor.emf" and drive.motor.cogging is not None:
            extra = []
        if extra:
            out.extend(extra)

    for line in drive.to_toml().splitlines():
        m = _TABLE.match(line)
        if m:
            while out and out[-1] == "":
                out.pop()
            close(table)
            out.append("")
            table, present = m.group(1), set()
            out.append(line)
            continue
        k = _KEY.match(line)
        if k:
            present.add(k.group(1))
            doc = FIELDS.get((table, k.group(1)))
            if table == "thermal.nodes":
                doc = ("a node: C J/K heat capacity (none: a boundary, ambient or coolant, held at T), T degC "
                       "initial or fixed temperature, T_max degC its limit")
            elif table == "thermal.losses":
                doc = f"the node(s) that {LOSS_SOURCES.get(k.group(1), ('this loss', ''))[0]} heats (or a table of " \
                      "fractions)"
            if doc:
                out.append(f"# {k.group(1)}: {doc}")
        out.append(line)
    close(table)
    return "\n".join(out).rstrip("\n") + "\n"


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab template``."""
    p.add_argument("--from", dest="source", metavar="MOTOR", default="htm-48v",
                   help="drive to start from: built-in name (bldclab drives) or motor file (default: htm-48v)")
    p.add_argument("--out", type=Path, metavar="FILE.toml", help="write the file here (default: standard output); "
                   "an existing file is kept unless --force")
    p.add_argument("--force", action="store_true", help="overwrite an existing --out file")


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab template``: print or write the commented motor file."""
    check_out_file(args.out)
    if args.out is not None and args.out.exists() and not args.force:
        # a template is where a hand-written motor file starts: writing over one (`--from my.toml --out my.toml`
        # rewrites it in SI numbers, its comments and unit strings gone) needs to be asked for
        same = Path(args.source).exists() and Path(args.source).resolve() == args.out.resolve()
        raise BldclabError("--out", f"{str(args.out)!r} exists" + (", and is the --from file (its comments and "
                           "units would be lost)" if same else "") + ": give another name, or --force to overwrite it")
    try:
        text = template(args.source)
    except BldclabError as exc:
        if exc.field != "MOTOR":
            raise
        raise BldclabError("--from", exc.problem) from None
    if args.out is None:
        sys.stdout.write(text)
    else:
        write_atomic(args.out, text.encode(), "--out")
        print(f"wrote {args.out} (check it: bldclab check {args.out})")
    return 0

"""``bldclab check``: validate a motor file and print what follows from it (bases, time constants, PWM, paper 1)."""

from __future__ import annotations

import argparse
import math
import warnings

import numpy as np

from ..errors import PlausibilityWarning
from ..model import analytic
from ..model.catalog import load
from ..model.limits import PWM_PER_PERIOD_WARN, TOP_SPEED_PU, check_pwm
from ..model.motor import Drive
from .drives import drive_kind

__all__ = ["configure_command", "derived", "premises", "run_command"]

RPM_PER_RAD_S = 30.0 / math.pi


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab check``."""
    p.add_argument("motor", metavar="MOTOR", help="motor TOML file (or a built-in drive name) to validate")


def derived(drive: Drive) -> list[tuple[str, str, str]]:
    """Return the derived quantities of a drive as ``(name, value with unit, meaning)`` rows.

    Parameters
    ----------
    drive : Drive
        The drive.

    Returns
    -------
    list of tuple of str
        Speed and torque bases, motor constant, paper 1's ``Theta_m``, the electrical time constant, the electrical
        frequency at ``Omega_0`` and the PWM periods per commutation interval (a sixth of an electrical period).
    """
    m, inv = drive.motor, drive.inverter
    r = m.R + inv.R_on
    tau = m.L / r if r > 0 else math.inf
    f_e = m.p * drive.Omega_0 / (2.0 * math.pi)
    k1 = [float(np.hypot(*(c[1] for c in sh.fourier(1)))) for sh in m.emf.shapes]
    rows = [
        ("p", f"{m.p} pole pairs = {m.poles} poles", "theta_e = p theta_m"),
        ("R", f"{_eng(m.R, 'Ohm')} per phase = {_eng(m.R_ll, 'Ohm')} line to line",
         "winding resistance; line to line R_ll = 2 R (star, two phases in series)"),
        ("L", f"{_eng(m.L, 'H')} per phase = {_eng(m.L_ll, 'H')} line to line",
         "inclusive inductance L_self - M; line to line L_ll = 2 L"),
        ("KV", f"{m.KV:.6g} rpm/V (KV_rms {m.KV_rms:.6g} rpm/V)",
         "speed per volt of peak line-to-line back-EMF = Omega_0 / V_dc; KV_rms: per volt rms"),
        ("Omega_0", f"{drive.Omega_0:.6g} rad/s = {drive.Omega_0 * RPM_PER_RAD_S:.6g} rpm",
         "no-load speed V_dc / (2 k_phi), the speed base (paper 1 (2))"),
        ("Omega_N", f"{m.Omega_nominal:.6g} rad/s = {m.Omega_nominal * RPM_PER_RAD_S:.6g} rpm",
         "rated speed" + (" (given)" if m.Omega_N is not None else " (V_N - 2 R I_N) / (2 k_phi), paper 1 (2)")),
        ("T_N", f"{drive.T_N:.6g} N m", "torque base 2 k_phi I_N (paper 1 (6))"),
        ("k_phi", f"{m.k_phi:.6g} V s/rad", "motor constant: half the peak line-to-line back-EMF per rad/s"),
        ("k_1", f"{sum(k1) / 3:.6g} V s/rad", "peak of a phase's back-EMF fundamental per rad/s (mean of the phases); "
         f"sinusoidal torque 3/2 k_1 = {1.5 * sum(k1) / 3:.4g} N m per peak phase amp"),
        ("back-EMF", drive_kind(drive), "shape kind"),
        ("Theta_m", f"{analytic.theta_m(drive):.6g} rad", "p L I_N / (2 k_phi), paper 1 (22)"),
        ("L/R", "infinite (R = 0)" if math.isinf(tau) else f"{tau * 1e3:.6g} ms",
         "electrical time constant, R + R_on"),
        ("f_e at Omega_0", f"{f_e:.6g} Hz", "electrical frequency p Omega_0 / (2 pi)"),
        ("PWM per commutation", f"{inv.f_pwm / (6.0 * f_e):.4g}",
         f"PWM periods in a sixth of an electrical period at Omega_0 (simulations warn below "
         f"{PWM_PER_PERIOD_WARN / 6:g}: {PWM_PER_PERIOD_WARN:g} per electrical period)"),
    ]
    if not math.isinf(tau):
        rows.append(("PWM per L/R", f"{inv.f_pwm * tau:.4g}", "PWM periods in the electrical time constant"))
    if m.has_iron_losses:
        rows.append(("iron loss at Omega_0", f"{m.iron_loss(drive.Omega_0):.4g} W",
                     "stator iron loss the model books at Omega_0 (any load; docs/plant.md, \"Iron losses\")"))
    return rows


def _eng(value: float, unit: str) -> str:
    """``value`` with a prefix that keeps three digits before the point at most: 0.04 Ohm -> "40 mOhm"."""
    for prefix, scale in (("", 1.0), ("m", 1e-3), ("u", 1e-6), ("n", 1e-9)):
        if abs(value) >= scale or prefix == "n":
            return f"{value / scale:.6g} {prefix}{unit}"
    return f"{value:.6g} {unit}"  # pragma: no cover - the loop returns


def premises(drive: Drive) -> list[str]:
    """Return what the simulations of ``bldclab compare`` warn about for this drive before any run, in their words.

    The drive-only premises of :mod:`bldclab.model.limits` (PWM against ``L/R`` and against the electrical frequency)
    at the top speed ``compare`` runs by default (:data:`~bldclab.model.limits.TOP_SPEED_PU`); an error there is
    said to be one. Paper 1's premises (back-EMF shape, R, bus voltage) are
    :func:`bldclab.model.analytic.applicability`'s, printed by :func:`run_command` as ``compare`` prints them.

    Parameters
    ----------
    drive : Drive

    Returns
    -------
    list of str
        One line per finding.
    """
    w = TOP_SPEED_PU * drive.Omega_0
    out = []
    for f in check_pwm(drive, w):
        refused = "; simulations refuse this as an error" if f.level == "error" else ""
        out.append(f"at {TOP_SPEED_PU:g} Omega_0 (bldclab compare's top speed{refused}): {f}")
    return out


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab check``: load the file (one error line and exit 2 if it is bad), print the derived quantities."""
    drive = load(args.motor)
    print(f"{args.motor}: valid motor file, drive {drive.name!r} (V_dc {drive.inverter.V_dc:g} V, I_N "
          f"{drive.motor.I_N:g} A, p = {drive.motor.p}, f_pwm {drive.inverter.f_pwm:g} Hz, "
          f"{drive.inverter.model} inverter)")
    rows = derived(drive)
    w0 = max(len(r[0]) for r in rows)
    w1 = max(len(r[1]) for r in rows)
    for name, value, meaning in rows:
        print(f"  {name:<{w0}}  {value:<{w1}}  {meaning}")
    for finding in premises(drive):  # what bldclab compare warns about, in its words
        warnings.warn(finding, PlausibilityWarning, stacklevel=2)
    reasons = analytic.applicability(drive)
    if reasons:
        print("paper 1's closed forms (bldclab analyze) do not describe this drive exactly, because:")
        for reason in reasons:
            print(f"  - {reason}")
    else:
        print("paper 1's closed forms (bldclab analyze) apply: ideal trapezoid, R negligible, V_dc = V_N")
    print(analytic.commutation_premise(drive)[0])
    return 0

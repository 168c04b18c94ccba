"""``bldclab drives``: the built-in drives, one line each (name, back-EMF, bus, current, poles, PWM, speeds, source)."""

from __future__ import annotations

import argparse
import math

from ..model.catalog import load, names
from ..model.motor import Drive

__all__ = ["SOURCES", "configure_command", "drive_kind", "run_command"]

RPM_PER_RAD_S = 30.0 / math.pi

#: Where each built-in drive's numbers come from (its motor file's description says it in full).
SOURCES: dict[str, str] = {
    "htm-48v": "paper 1 (Bertoluzzo et al. 2015) Table II",
    "htm-48v-losses": "htm-48v + onsemi NTB5860NL, M270-35A losses",
    "lu-4kw": "paper 2 (Lu et al. 2008) appendix; synthetic back-EMF",
    "outrunner-24v": "Mini Cheetah firmware (B. Katz)",
    "servo-2k2": "motulator examples (Aalto Univ.)",
}


def drive_kind(drive: Drive) -> str:
    """Return the back-EMF kind as the motor file names it: ``trapezoid``, ``sinusoid``, ``fourier``, ``table``.

    Shapes that differ per phase get `` per phase``.
    """
    kinds = sorted({type(s).__name__.lower() for s in drive.motor.emf.shapes})
    return "/".join(kinds) + ("" if drive.motor.emf.is_symmetric else " per phase")


def configure_command(p: argparse.ArgumentParser) -> None:
    """Declare the arguments of ``bldclab drives`` (none)."""


def run_command(args: argparse.Namespace) -> int:
    """Run ``bldclab drives``: print the table of built-in drives."""
    rows = [("name", "back-EMF", "V_dc (V)", "I_N (A)", "p", "f_pwm (kHz)", "Omega_N (rpm)", "Omega_0 (rpm)",
             "source")]
    for name in names():
        d = load(name)
        source = SOURCES.get(name) or d.description.split(":")[0][:60]
        rows.append((name, drive_kind(d), f"{d.inverter.V_dc:g}", f"{d.motor.I_N:.4g}", str(d.motor.p),
                     f"{d.inverter.f_pwm / 1e3:g}", f"{d.motor.Omega_nominal * RPM_PER_RAD_S:.0f}",
                     f"{d.Omega_0 * RPM_PER_RAD_S:.0f}", source))
    widths = [max(len(r[j]) for r in rows) for j in range(len(rows[0]))]
    for r in rows:
        cells = [c.ljust(w) if j in (0, 1, 8) else c.rjust(w) for j, (c, w) in enumerate(zip(r, widths, strict=True))]
        print("  ".join(cells).rstrip())
    print("(Omega_N: rated speed; Omega_0: no-load speed V_dc / (2 k_phi), the p.u. base. Details: bldclab check "
          "NAME; a motor file to start from: bldclab template --from NAME)")
    return 0

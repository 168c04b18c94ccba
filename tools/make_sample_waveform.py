"""Regenerate ``src/bldclab/data/lu4kw_backemf_1300rpm.csv``: a simulated constant-speed back-EMF record.

Usage::

    PYTHONPATH=src python tools/make_sample_waveform.py            # rewrite the sample file
    PYTHONPATH=src python tools/make_sample_waveform.py --check    # exit 1 if the file differs from the generator
    PYTHONPATH=src python tools/make_sample_waveform.py -o out.csv

The record is paper 2's constant-speed test (its Fig. 6, 1300 rpm) done on the ``lu-4kw`` catalog drive by
bldclab's simulator: :func:`bldclab.analysis.identify.synthetic_measurement` with the settings below (all legs off, no
current; voltages to an artificial star point; a 12-bit scope with 0.5 % noise; the Hall sensors on digital
channels). Deterministic: a fixed noise seed. Provenance: ``src/bldclab/data/README.txt`` and
``docs/identify.md``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from bldclab import load
from bldclab.analysis.identify import SAMPLE_FILE, synthetic_measurement, waveform_csv

DEFAULT_OUTPUT = Path(__file__).resolve().parents[1] / "src" / "bldclab" / "data" / SAMPLE_FILE

DRIVE = "lu-4kw"
RPM = 1300.0  # paper 2, Fig. 6
SETTINGS = {
    "periods": 2.6,  # electrical periods: 60 ms at 1300 rpm with p = 2
    "f_sample": 50e3,  # Hz
    "theta0": 1.0,  # rad, electrical angle when the record starts (not aligned on purpose)
    "t_start": -0.005,  # s: the scope's pre-trigger
    "noise": 0.005,  # standard deviation, fraction of the peak voltage
    "bits": 12,
    "seed": 2008,
}


def render() -> str:
    """Return the text of the sample file."""
    drive = load(DRIVE)
    speed = RPM * 2.0 * math.pi / 60.0
    cols = synthetic_measurement(drive, speed, **SETTINGS)  # type: ignore[arg-type]
    comments = [
        f"Simulated constant-speed back-EMF test: bldclab drive '{DRIVE}' at {RPM:g} rpm (paper 2, Fig. 6), "
        "open circuit (all inverter legs off).",
        "Made by tools/make_sample_waveform.py with bldclab.analysis.identify.synthetic_measurement: "
        + ", ".join(f"{k} = {v:g}" for k, v in SETTINGS.items()) + ".",
        "Columns: t (s, sample centre); v_a, v_b, v_c (V): terminal voltages to an artificial star point, "
        "Gaussian noise and a 12-bit quantiser on a 1-2-5 scope range;",
        "h_a, h_b, h_c: Hall sensors (0/1, digital channels). Identify with: "
        f"bldclab identify {SAMPLE_FILE} --speed '1300 rpm' --base lu-4kw",
    ]
    return waveform_csv(cols, comments)


def main(argv: list[str] | None = None) -> int:
    """Write (or check) the sample file; return the process exit code."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=DEFAULT_OUTPUT, help="file to write")
    parser.add_argument("--check", action="store_true", help="only compare; exit 1 if the file is stale")
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        current = args.output.read_text(encoding="utf-8") if args.output.is_file() else None
        if current != text:
            print(f"{args.output} is stale: run tools/make_sample_waveform.py", file=sys.stderr)
            return 1
        print(f"{args.output} is up to date")
        return 0
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(text, encoding="utf-8")
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

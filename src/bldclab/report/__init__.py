"""Reports: figures, the results directory of a comparison and the HTML page.

Reports: matplotlib figures (:mod:`.plots`), the results directory of a comparison (:mod:`.bundle`) and the self-
contained HTML page (:mod:`.html`).

Layer 7 of the package (see the design page): imports any lower layer, never the CLI.
"""

from __future__ import annotations

from ..svg import Series, svg_plot
from .bundle import (
    compare_command,
    compare_files,
    compare_outputs,
    comparison_figures,
    make_manifest,
    methods_traces,
    motor_results,
    read_results,
    waveforms,
)
from .html import FORMAT, FORMAT_VERSION, MANIFEST, PARAMETERS, REPORT, WAVEFORM_SPEEDS, Results, render

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "MANIFEST",
    "PARAMETERS",
    "REPORT",
    "WAVEFORM_SPEEDS",
    "Results",
    "Series",
    "compare_command",
    "compare_files",
    "compare_outputs",
    "comparison_figures",
    "make_manifest",
    "methods_traces",
    "motor_results",
    "read_results",
    "render",
    "svg_plot",
    "waveforms",
]

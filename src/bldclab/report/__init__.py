"""Reports: figures, the results directory of a comparison and the HTML page.

Reports: matplotlib figures (:mod:`.plots`), the results directory of a comparison (:mod:`.bundle`) and the self-
contained HTML page (:mod:`.html`).

Layer 7 of the package (see the design page): imports any lower layer, never the CLI.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import Lazy, attach
from ..svg import Series, svg_plot

if TYPE_CHECKING:  # the same names, for type checkers and readers; at run time they are imported on first use
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

#: The names re-exported from :mod:`.bundle` and :mod:`.html` (pandas, the analyses), imported on first use
#: (:mod:`bldclab._lazy`): ``bldclab analyze`` imports :mod:`.plots` without them.
LAZY: Lazy = {
    **{name: ("bldclab.report.bundle", name) for name in (
        "compare_command", "compare_files", "compare_outputs", "comparison_figures", "make_manifest",
        "methods_traces", "motor_results", "read_results", "waveforms")},
    **{name: ("bldclab.report.html", name) for name in (
        "FORMAT", "FORMAT_VERSION", "MANIFEST", "PARAMETERS", "REPORT", "WAVEFORM_SPEEDS", "Results", "render")},
}

__getattr__, __dir__ = attach(globals(), LAZY)

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

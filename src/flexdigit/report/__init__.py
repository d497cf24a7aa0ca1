"""The reproduce-the-thesis report: every chapter's figures beside the thesis's, as HTML and ``results.json``.

:data:`CHAPTERS` lists the chapter modules in reading order; each exposes ``build(ctx) -> Chapter`` and only turns
a library study (each domain's module of chapter studies, e.g. ``control/chapter4_studies.py``) into entries,
tables and figures. The chapters are independent and are built in parallel processes
(:func:`flexdigit.report.build.reproduce`). The report only reads the rest of the package; nothing imports it.
"""

from __future__ import annotations

from flexdigit._lazy import lazy_exports

#: Chapter modules in the order they appear in the report.
CHAPTERS: tuple[str, ...] = (
    "flexdigit.report.ch3_models",
    "flexdigit.report.ch3_twin",
    "flexdigit.report.ch3_identify",
    "flexdigit.report.ch4_control",
    "flexdigit.report.ch5_digital",
    "flexdigit.report.ch6_tactile",
    "flexdigit.report.ch7_tactile",
    "flexdigit.report.ch8_shape",
    "flexdigit.report.ch8_studies",
    "flexdigit.report.ch6_7_noise",
    "flexdigit.report.ch8_palpation",
)

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, _exports = lazy_exports(
    __name__,
    {
        "reproduce": "flexdigit.report.build",
        "ReportSummary": "flexdigit.report.build",
        "Chapter": "flexdigit.report.chapter",
        "ReportContext": "flexdigit.report.chapter",
    },
)
__all__ = ["CHAPTERS", *_exports]

"""Build the report: run every chapter, write ``index.html``, ``results.json`` and ``figures/``."""

from __future__ import annotations

import html
import importlib
import json
import time
import traceback
from dataclasses import asdict, dataclass, field
from pathlib import Path

import matplotlib

from flexdigit import __version__
from flexdigit._json import to_jsonable
from flexdigit.params import RigParams
from flexdigit.report import CHAPTERS
from flexdigit.report.chapter import Chapter, ReportContext

matplotlib.use("Agg")


@dataclass
class ReportSummary:
    """What :func:`reproduce` wrote and how it went."""

    out_dir: Path
    entries: int
    counts: dict[str, int]
    chapters: list[str]
    failed: dict[str, str] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)


def reproduce(
    out_dir: str | Path,
    *,
    params: RigParams | None = None,
    seed: int = 0,
    fast: bool = False,
    chapters: tuple[str, ...] | None = None,
    progress=None,
) -> ReportSummary:
    """Run the report's chapters on the twin and write ``out_dir/index.html`` and ``out_dir/results.json``.

    A chapter that fails is shown in the report with its error (and listed in ``failed``) instead of
    hiding the chapters that worked.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ctx = ReportContext(out_dir=out, params=params or RigParams(), seed=seed, fast=fast)
    built: list[Chapter] = []
    failed: dict[str, str] = {}
    seconds: dict[str, float] = {}
    for module_name in chapters or CHAPTERS:
        start = time.perf_counter()
        if progress is not None:
            progress(module_name)
        try:
            built.append(importlib.import_module(module_name).build(ctx))
        except Exception:  # a broken chapter must not hide the others; its traceback goes in the report
            failed[module_name] = traceback.format_exc()
        seconds[module_name] = time.perf_counter() - start
    entries = [asdict(e) for chapter in built for e in chapter.entries]
    (out / "results.json").write_text(json.dumps(to_jsonable(entries), indent=2) + "\n")
    (out / "index.html").write_text(_render(built, failed, ctx))
    counts = {s: sum(e["status"] == s for e in entries) for s in ("match", "discrepancy", "new")}
    return ReportSummary(out, len(entries), counts, [c.title for c in built], failed, seconds)


_CSS = """
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}
td,th{border:1px solid #ccc;padding:3px 7px;vertical-align:top}
th{background:#f3f3f3}.match{background:#e8f6e8}.discrepancy{background:#fff2d9}.new{background:#e8effa}
.failed{background:#fde4e4;padding:0.5em;white-space:pre-wrap;font-family:monospace;font-size:0.8em}
figure{display:inline-block;margin:0.5em;max-width:520px;vertical-align:top}figure img{max-width:100%}
figcaption{font-size:0.85em;color:#444}code{background:#f5f5f5}
"""


def _cell(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return html.escape("" if value is None else str(value))


def _render(chapters: list[Chapter], failed: dict[str, str], ctx: ReportContext) -> str:
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>flexdigit: the thesis reproduced</title>",
        f"<style>{_CSS}</style></head><body>",
        "<h1>The cable-actuated flexible digit, reproduced on its digital twin</h1>",
        f"<p>flexdigit {html.escape(__version__)}, seed {ctx.seed}{', fast mode' if ctx.fast else ''}, "
        f"twin calibration: {html.escape(_calibration_source())}. "
        "Each entry puts the figure as printed in the thesis beside ours: <span class='match'>match</span>, "
        "<span class='discrepancy'>discrepancy</span> (the note explains it and gives the corrected figure) or "
        "<span class='new'>new</span> (not in the thesis). The same entries are in <code>results.json</code>.</p>",
        "<ul>" + "".join(f"<li><a href='#{c.slug}'>{html.escape(c.title)}</a></li>" for c in chapters) + "</ul>",
    ]
    for chapter in chapters:
        parts.append(f"<h2 id='{chapter.slug}'>{html.escape(chapter.title)}</h2>")
        parts.extend(f"<p>{html.escape(p)}</p>" for p in chapter.paragraphs)
        if chapter.entries:
            parts.append(
                "<table><tr><th>key</th><th>section</th><th>thesis</th><th>ours</th><th>unit</th>"
                "<th>rel. error</th><th>status</th><th>note</th></tr>"
            )
            for e in chapter.entries:
                rel = "" if e.rel_error is None else f"{100 * e.rel_error:.3g} %"
                parts.append(
                    f"<tr class='{e.status}'><td>{_cell(e.key)}</td><td>{_cell(e.section)}</td>"
                    f"<td>{_cell(e.thesis)}</td><td>{_cell(e.ours)}</td><td>{_cell(e.unit)}</td><td>{rel}</td>"
                    f"<td>{e.status}</td><td>{_cell(e.note)}</td></tr>"
                )
            parts.append("</table>")
        for table in chapter.tables:
            parts.append(f"<h3>{html.escape(table.title)}</h3><table><tr>")
            parts.extend(f"<th>{html.escape(c)}</th>" for c in table.columns)
            parts.append("</tr>")
            for row in table.rows:
                parts.append("<tr>" + "".join(f"<td>{_cell(v)}</td>" for v in row) + "</tr>")
            parts.append("</table>")
        for fig in chapter.figures:
            ref = f" (beside thesis {html.escape(fig.thesis_ref)})" if fig.thesis_ref else ""
            parts.append(
                f"<figure><img src='figures/{html.escape(fig.name)}.png' alt='{html.escape(fig.caption)}'>"
                f"<figcaption>{html.escape(fig.caption)}{ref}</figcaption></figure>"
            )
    for module_name, error in failed.items():
        parts.append(f"<h2>{html.escape(module_name)}: failed</h2><div class='failed'>{html.escape(error)}</div>")
    parts.append("</body></html>\n")
    return "\n".join(parts)


def _calibration_source() -> str:
    from flexdigit.twin.calibration import default_calibration_source

    source = default_calibration_source()
    return "packaged (fitted to the thesis)" if source == "packaged" else source

"""Build the report: run every chapter, write ``index.html``, ``results.json`` and ``figures/``."""

from __future__ import annotations

import contextlib
import html
import importlib
import json
import multiprocessing
import os
import time
import traceback
from concurrent.futures import ProcessPoolExecutor, as_completed
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
    workers: int | None = None,
) -> ReportSummary:
    """Run the report's chapters on the twin and write ``out_dir/index.html`` and ``out_dir/results.json``.

    A chapter that fails is shown in the report with its error (and listed in ``failed``) instead of
    hiding the chapters that worked.

    Parameters
    ----------
    progress : callable, optional
        Called with each chapter's module name as it starts (one worker) or finishes (several).
    workers : int, optional
        Chapters built at once, each in its own process (default: one per available core). Chapters are
        independent and seeded by ``seed`` and their own streams, so the numbers do not depend on it; ``1``
        builds them one after another in this process.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ctx = ReportContext(out_dir=out, params=params or RigParams(), seed=seed, fast=fast)
    names = tuple(chapters or CHAPTERS)
    n_workers = _available_cores() if workers is None else int(workers)
    n_workers = max(1, min(n_workers, len(names)))
    if n_workers == 1:
        done = {}
        for name in names:
            if progress is not None:
                progress(name)
            done[name] = _build_chapter(name, ctx)
    else:
        done = _build_in_processes(names, ctx, n_workers, progress)
    built = [done[n][0] for n in names if done[n][0] is not None]
    failed = {n: done[n][1] for n in names if done[n][1] is not None}
    seconds = {n: done[n][2] for n in names}
    entries = [asdict(e) for chapter in built for e in chapter.entries]
    (out / "results.json").write_text(json.dumps(to_jsonable(entries), indent=2) + "\n")
    (out / "index.html").write_text(_render(built, failed, ctx))
    counts = {s: sum(e["status"] == s for e in entries) for s in ("match", "discrepancy", "new")}
    return ReportSummary(out, len(entries), counts, [c.title for c in built], failed, seconds)


#: Rough seconds each chapter takes (full report, 2-core machine): only the order in which chapters are handed to
#: the worker processes (longest first, so that no long chapter starts last), never their numbers.
EXPECTED_SECONDS = {
    "flexdigit.report.ch7_tactile": 45.0,
    "flexdigit.report.ch6_tactile": 35.0,
    "flexdigit.report.ch4_control": 12.0,
    "flexdigit.report.ch3_twin": 9.0,
    "flexdigit.report.ch5_digital": 7.0,
    "flexdigit.report.ch3_identify": 5.0,
}


def _available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _build_chapter(module_name: str, ctx: ReportContext) -> tuple[Chapter | None, str | None, float]:
    """``(chapter, None, seconds)``, or ``(None, traceback, seconds)`` if it failed."""
    start = time.perf_counter()
    try:
        chapter = importlib.import_module(module_name).build(ctx)
        return chapter, None, time.perf_counter() - start
    except Exception:  # a broken chapter must not hide the others; its traceback goes in the report
        return None, traceback.format_exc(), time.perf_counter() - start


#: What a worker process keeps entered for its lifetime (the calibration the report runs on).
_WORKER_CONTEXT = contextlib.ExitStack()


def _calibration_state():
    """The twin calibration a ``use_calibration`` block made the default here, to hand to the workers (a spawned
    process starts on the packaged one); None when it is the packaged one."""
    from flexdigit.twin.calibration import default_calibration, default_calibration_source, default_fit_record

    source = default_calibration_source()
    return None if source == "packaged" else (default_calibration(), source, default_fit_record())


def _worker_init(calibration_state) -> None:
    # one BLAS thread per worker: the workers already use every core, and OpenBLAS threads fighting over them make
    # small factorisations (SLICOT's) tens of times slower
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    if calibration_state is not None:  # the parent's use_calibration block, for every chapter of this worker
        from flexdigit.twin.calibration import use_calibration

        _WORKER_CONTEXT.enter_context(use_calibration(*calibration_state))


def _build_in_processes(names, ctx: ReportContext, workers: int, progress) -> dict:
    order = sorted(names, key=lambda n: -EXPECTED_SECONDS.get(n, 5.0))
    done = {}
    context = multiprocessing.get_context("spawn")  # a fresh interpreter: no state inherited from this one
    init = {"initializer": _worker_init, "initargs": (_calibration_state(),)}
    with ProcessPoolExecutor(workers, mp_context=context, **init) as pool:
        futures = {pool.submit(_build_chapter, name, ctx): name for name in order}
        for future in as_completed(futures):
            name = futures[future]
            try:
                done[name] = future.result()
            except Exception:  # the worker died (out of memory, killed): say so in the report
                done[name] = (None, traceback.format_exc(), float("nan"))
            if progress is not None:
                progress(name)
    return done


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

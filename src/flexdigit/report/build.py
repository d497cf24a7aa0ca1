"""Build the report: run every chapter (in parallel processes), write ``index.html``, ``results.json``, ``figures/``.

``results.json`` holds every entry and every table as numbers (:func:`results_document`); ``index.html`` opens on
the headline figures and the per-chapter counts, then the chapters, long tables collapsed.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import html
import importlib
import json
import math
import multiprocessing
import os
import shutil
import stat
import tempfile
import time
import traceback
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import matplotlib

from flexdigit import __version__
from flexdigit._io import atomic_write, check_output
from flexdigit._json import to_jsonable
from flexdigit._repr import fields_summary
from flexdigit._system import available_cores, check_workers
from flexdigit.errors import OutputExistsError
from flexdigit.interrupts import raise_if_stopping, signals_deferred
from flexdigit.params import RigParams
from flexdigit.report import CHAPTERS
from flexdigit.report.chapter import DERIVED_CALIBRATION_SOURCE, Chapter, ReportContext
from flexdigit.report.results import NOT_APPLICABLE, not_applicable, thesis_comparisons
from flexdigit.twin.calibration import (
    default_calibration,
    default_calibration_source,
    default_fit_record,
    use_calibration,
)
from flexdigit.twin.digit_calibration import calibration_for

__all__ = [
    "ReportSummary",
    "reproduce",
    "HEADLINE",
    "DIGIT_HEADLINE",
    "STATUSES",
    "results_document",
    "EXPECTED_SECONDS",
    "check_report_dir",
    "COLLAPSE_ROWS",
    "FRONT_FIGURES",
    "entry_label",
]

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

    __repr__ = fields_summary


def reproduce(
    out_dir: str | Path,
    *,
    params: RigParams | None = None,
    seed: int = 0,
    fast: bool = False,
    chapters: tuple[str, ...] | None = None,
    progress=None,
    workers: int | None = None,
    force: bool = False,
) -> ReportSummary:
    """Run the report's chapters on the twin and write ``out_dir/index.html`` and ``out_dir/results.json``.

    A chapter that fails is shown in the report with its error (and listed in ``failed``) instead of
    hiding the chapters that worked. A folder that already holds a report is refused before any chapter runs,
    unless ``force``; every file is written atomically (:mod:`flexdigit._io`).

    Parameters
    ----------
    progress : callable, optional
        ``progress(module_name, title, seconds)`` as each chapter is done (its title, or the module's name if it
        failed; its wall-clock seconds), for a display such as "Chapter 5: ... done in 3.2 s".
    workers : int, optional
        Chapters built at once, each in its own process (default: one per available core). Chapters are
        independent and seeded by ``seed`` and their own streams, so the numbers do not depend on it; ``1``
        builds them one after another in this process.
    """
    out = check_report_dir(out_dir, force=force)
    with _new_report(out) as work, _digit_calibration(params):
        summary = _build(work, params, seed, fast, chapters, progress, workers)
    return replace(summary, out_dir=out)


@contextlib.contextmanager
def _digit_calibration(params: RigParams | None) -> Iterator[None]:
    """Every twin of every chapter on the calibration of the digit ``params`` describes: for a digit other than
    the thesis rig, with no calibration given (a ``use_calibration`` block), the thesis's scaled to it
    (:func:`flexdigit.twin.digit_calibration.calibration_for`; the packaged one has the thesis rig's 3 sections
    and 3 gauges, and the chapters' studies take the default calibration)."""
    if params is None or params == RigParams() or default_calibration_source() != "packaged":
        yield
        return
    with use_calibration(calibration_for(params), source=DERIVED_CALIBRATION_SOURCE):
        yield


def _build(work: Path, params, seed, fast, chapters, progress, workers) -> ReportSummary:
    """The report, built in the folder ``work``."""
    ctx = ReportContext(out_dir=work, params=params or RigParams(), seed=seed, fast=fast)
    names = CHAPTERS if chapters is None else tuple(chapters)  # () is a value: no chapter
    n_workers = available_cores() if workers is None else check_workers(int(workers), "workers", CHAPTER_BYTES)
    n_workers = max(1, min(n_workers, len(names) or 1))
    if n_workers == 1:
        done = {}
        with _one_thread_here():
            for name in names:
                done[name] = _build_chapter(name, ctx)
                _report_progress(progress, name, done[name])
    else:
        done = _build_in_processes(names, ctx, n_workers, progress)
    built = [done[n][0] for n in names if done[n][0] is not None]
    failed = {n: done[n][1] for n in names if done[n][1] is not None}
    seconds = {n: done[n][2] for n in names}
    document = results_document(
        built,
        ctx,
        seconds={c.slug: done[n][2] for n, c in _pairs(names, done)},
        cpu_seconds={c.slug: done[n][3] for n, c in _pairs(names, done)},
    )
    with atomic_write(work / "results.json", "w") as fh:
        fh.write(json.dumps(to_jsonable(document), indent=2) + "\n")
    with atomic_write(work / "index.html", "w") as fh:
        fh.write(_render(built, failed, ctx, document))
    return ReportSummary(work, len(document["entries"]), document["counts"], [c.title for c in built], failed, seconds)


#: What a report folder holds that the report wrote (anything else in it is the user's, and is kept).
REPORT_ENTRIES = ("index.html", "results.json", "figures", "data")


@contextlib.contextmanager
def _new_report(out: Path) -> Iterator[Path]:
    """A temporary folder beside ``out`` to build the report in, swapped in for ``out`` when the block ends
    cleanly: until then the old report stays whole, and a stop (Ctrl-C, SIGTERM, an error) leaves it so, with
    nothing behind (issue 22: an interrupted ``reproduce --force`` left the old index.html and results.json
    beside some of the new figures, and ``.tmp`` files in figures/).

    The swap is one step where the system allows it (Linux's ``renameat2(RENAME_EXCHANGE)``), else two renames
    that a signal cannot split; files of the user's in ``out`` (not in :data:`REPORT_ENTRIES`) stay in it.
    """
    out = out.resolve()  # a symlinked report folder: the folder it points at is swapped, the link kept
    work = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
    try:
        os.chmod(work, stat.S_IMODE(out.stat().st_mode) if out.is_dir() else 0o777 & ~_umask())
        yield work
        with signals_deferred():  # a signal waits for the swap's end: the folder is the old report or the new
            _swap_in(work, out)
    finally:
        with signals_deferred():  # the old report swapped out, or the new one left unfinished
            if not any(e.name not in REPORT_ENTRIES and not e.name.endswith(".tmp") for e in _entries(work)):
                shutil.rmtree(work, ignore_errors=True)  # (never a file of the user's a failed move left there)


def _entries(folder: Path) -> list[Path]:
    try:
        return list(folder.iterdir())
    except FileNotFoundError:
        return []


def _swap_in(work: Path, out: Path) -> None:
    """Put the folder ``work`` at ``out``; the old ``out`` (if any) ends at ``work``, less the user's files."""
    if not out.is_dir():
        os.rename(work, out)
        return
    if not _exchange(work, out):
        old = work.with_name(work.name + ".old")
        os.rename(out, old)
        os.rename(work, out)
        os.rename(old, work)
    for entry in _entries(work):  # the old folder: what the user put beside the report goes in the new one
        if entry.name not in REPORT_ENTRIES and not (out / entry.name).exists():
            os.rename(entry, out / entry.name)


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one step (Linux's ``renameat2`` with ``RENAME_EXCHANGE``); False where the system or
    the file system cannot (then nothing happened)."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError):  # not Linux, or a C library without it
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):  # an old kernel, a file system without it
        return False
    raise OSError(code, os.strerror(code), str(b))


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _pairs(names, done):
    return [(n, done[n][0]) for n in names if done[n][0] is not None]


#: The report's first screen: the figures a reader wants first, each the thesis's beside ours (entry key -> what it
#: is; a key whose chapter failed or was not built is left out).
HEADLINE = {
    "plant.G.num": "plant G(s) of 3.5 rebuilt from its components: numerator",
    "plant.G.den[s^0]": "plant G(s): constant of the denominator",
    "cable.commands_for_30deg_tip_rotation": "commands for 30 deg of tip rotation",
    "conversion.K1_sg1": "K1, gauge 1 (E 3.16)",
    "twin.release_with_housing.wn_rad_s": "twin release test: wn (table 3.2)",
    "twin.release_with_housing.zeta": "twin release test: zeta (table 3.2)",
    "identify.servo.lsq.wn_rad_s": "servo wn identified by least squares (3.2.4)",
    "identify.digit.thesis.wn_rad_s": "digit wn by the thesis's wn = 4/(zeta Ts)",
    "hinf.tzw_peak_db": "||T_zw|| of the 5 Hz design (4.4)",
    "hinf.k_39hz_num_lead": "39 Hz controller gain (table 4.3)",
    "hinf.additive_tolerance_5Hz": "additive tolerance, 5 Hz filter (4.7)",
    "digital.euler_unstable_above_s": "forward Euler unstable above (5.1.2)",
    "digital20.settling_time_s": "30 deg step at 20 ms on the twin: 2 % settling",
    "non_actuated.test_corr2_at_thesis_optimum": "tactile corr2, non-actuated (6.9)",
    "actuated.test_corr2_at_thesis_optimum": "tactile corr2, actuated (7.5)",
    "actuated.best_estimator_position_rmse_mm": "actuated: best estimator's position error",
    "actuated.bayes_position_rmse_identifiable_mm": "actuated: the Bayes limit of that error",
}
#: The first screen of a digit other than the thesis rig's report: its own figures (the thesis rig's headline keys
#: are its printed figures, most of them not computed for another digit).
DIGIT_HEADLINE = {
    "plant.consistent.tip_rotation_deg_per_command": "tip rotation per servo command (cable model)",
    "cable.commands_for_30deg_tip_rotation": "commands for 30 deg of tip rotation",
    "twin.release_with_housing.wn_rad_s": "twin release test: wn",
    "twin.release_with_housing.zeta": "twin release test: zeta",
    "identify.digit.lsq.wn_rad_s": "digit wn identified by least squares",
    "hinf.digit.plant_dc_gain_mm_per_command": "plant G(0) from the digit's components (gauge 1)",
    "hinf.k_5hz.tzw_peak_db": "||T_zw|| of the 5 Hz H-infinity design on the digit's plant",
    "digital20.settling_time_s": "30 deg step at 20 ms on the twin: 2 % settling",
    "digital20.overshoot_percent": "30 deg step at 20 ms on the twin: overshoot",
    "non_actuated.best_estimator_position_rmse_mm": "non-actuated: best estimator's position error",
    "non_actuated.bayes_position_rmse_identifiable_mm": "non-actuated: the Bayes limit of that error",
    "actuated.best_estimator_position_rmse_mm": "actuated: best estimator's position error",
    "actuated.bayes_position_rmse_identifiable_mm": "actuated: the Bayes limit of that error",
    "palpation.stiffness.max_rel_error": "palpation: largest relative error of the fitted stiffness",
}
STATUSES = ("match", "discrepancy", "new")


def results_document(
    chapters: list[Chapter],
    ctx: ReportContext,
    seconds: dict[str, float] | None = None,
    cpu_seconds: dict[str, float] | None = None,
) -> dict:
    """What ``results.json`` holds: every entry, every table as numbers, the headline and per-chapter counts.

    ``{"flexdigit", "seed", "fast", "calibration", "counts", "headline", "chapters", "entries", "tables"}``:
    ``entries`` is the list of ``{key, section, thesis, ours, unit, rel_error, status, note}``; ``tables`` the list of
    ``{key, chapter, title, columns, rows}`` (cells are numbers, or strings for labels; NaN is null);
    ``headline`` the ``{key, figure}`` of :data:`HEADLINE` present; ``chapters`` each chapter's slug, title,
    counts, numbers of tables and figures, and build seconds (wall, and CPU of its process: all its threads).
    """
    entries = [dict(asdict(e), chapter=c.slug) for c in chapters for e in c.entries]
    present = {e["key"] for e in entries}
    seconds, cpu_seconds = seconds or {}, cpu_seconds or {}
    return {
        "flexdigit": __version__,
        "seed": ctx.seed,
        "fast": ctx.fast,
        "calibration": _calibration_source(),
        "counts": _counts(entries),
        "headline": [
            {"key": k, "figure": label}
            for k, label in (HEADLINE if ctx.thesis_rig else DIGIT_HEADLINE).items()
            if k in present
        ],
        "chapters": [
            {
                "slug": c.slug,
                "title": c.title,
                "counts": _counts([asdict(e) for e in c.entries]),
                "tables": len(c.tables),
                "figures": len(c.figures),
                "seconds": seconds.get(c.slug),
                "cpu_seconds": cpu_seconds.get(c.slug),
            }
            for c in chapters
        ],
        "entries": entries,
        "tables": [dict(t.as_dict(), chapter=c.slug) for c in chapters for t in c.tables],
    }


def _counts(entries) -> dict[str, int]:
    return {s: sum(e["status"] == s for e in entries) for s in STATUSES}


#: Memory one chapter's worker process may hold, bytes, for the cap on ``workers``
#: (:func:`flexdigit._system.check_workers`): a chapter's sweeps and figures take a few hundred MB.
CHAPTER_BYTES = 2**30
#: Relative cost of each chapter (its seconds in one full run, 2 workers, on a quiet 2-core machine): only the order
#: in which chapters are handed to the worker processes (longest first, so that no long chapter starts last), never
#: their numbers. A chapter not listed counts as a short one.
EXPECTED_SECONDS = {
    "flexdigit.report.ch7_tactile": 27.5,
    "flexdigit.report.ch6_tactile": 26.0,
    "flexdigit.report.ch6_7_noise": 10.1,
    "flexdigit.report.ch4_control": 7.9,
    "flexdigit.report.ch8_palpation": 6.5,
    "flexdigit.report.ch5_digital": 5.3,
    "flexdigit.report.ch8_studies": 5.3,
    "flexdigit.report.ch3_identify": 4.4,
    "flexdigit.report.ch3_twin": 2.7,
    "flexdigit.report.ch3_models": 2.5,
}


def _build_chapter(module_name: str, ctx: ReportContext) -> tuple[Chapter | None, str | None, float, float]:
    """``(chapter, None, seconds, cpu_seconds)``, or ``(None, traceback, seconds, cpu_seconds)`` if it failed."""
    start, cpu = time.perf_counter(), time.process_time()
    thesis_rig = ctx.params == RigParams()
    try:
        with thesis_comparisons(thesis_rig):
            chapter, error = importlib.import_module(module_name).build(ctx), None
        if not thesis_rig:  # another digit: no entry stands against the thesis rig's figure, however it was made
            chapter.entries = [not_applicable(e) for e in chapter.entries]
            # nor a figure "beside" a thesis figure of the thesis rig's (its caption says what it shows)
            chapter.figures = [replace(f, thesis_ref="") for f in chapter.figures]
    except Exception as exc:  # a broken chapter must not hide the others; one line says why in the report
        raise_if_stopping(exc)  # a stop signal a compiled kernel handed back as another exception is a stop
        chapter, error = None, _one_line(exc)
    return chapter, error, time.perf_counter() - start, time.process_time() - cpu


def _one_line(exc: BaseException) -> str:
    """Why a chapter failed, in one line: the error's type and message, and the line of flexdigit that raised it."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if "flexdigit" in f.filename] or [None]
    where = f" (at {Path(frames[-1].filename).name}:{frames[-1].lineno})" if frames[-1] is not None else ""
    message = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {message}{where}"


#: What a worker process keeps entered for its lifetime (the calibration the report runs on).
_WORKER_CONTEXT = contextlib.ExitStack()


def _calibration_state():
    """The twin calibration a ``use_calibration`` block made the default here, to hand to the workers (a spawned
    process starts on the packaged one); None when it is the packaged one."""
    source = default_calibration_source()
    return None if source == "packaged" else (default_calibration(), source, default_fit_record())


#: One thread for every BLAS and OpenMP runtime a chapter loads (numpy, SciPy, slycot and scikit-learn each bring
#: their own): read when a library loads, so also for those loaded after :func:`_worker_init`.
_ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def _worker_init(calibration_state) -> None:
    # one BLAS thread per worker: the workers already use every core, and BLAS threads fighting over them make
    # factorisations ten times slower (a 500 x 500 Cholesky: 6 ms on one thread, 70 ms on two here)
    import os

    from threadpoolctl import threadpool_limits

    os.environ.update(_ONE_THREAD)  # the libraries not loaded yet (SciPy's, slycot's OpenBLAS; scikit-learn's OpenMP)
    threadpool_limits(1)  # those already loaded (numpy's OpenBLAS)
    if calibration_state is not None:  # the parent's use_calibration block, for every chapter of this worker
        _WORKER_CONTEXT.enter_context(use_calibration(*calibration_state))


@contextlib.contextmanager
def _one_thread_here() -> Iterator[None]:
    """One BLAS and OpenMP thread in this process while the chapters are built in it, as in a worker
    (:func:`_worker_init`): the same factorisations as a report built by workers, and no BLAS threads fighting
    whatever else runs on the cores (a 200 x 200 Cholesky of the tactile chapters' Gaussian process: 0.4 ms on one
    thread, 52 ms on two on a busy 2-core machine). Restored on leaving."""
    import scipy.linalg  # noqa: F401  (SciPy's and slycot's own OpenBLAS, loaded now so that they are limited too)
    import slycot  # noqa: F401
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        yield


def _build_in_processes(names, ctx: ReportContext, workers: int, progress) -> dict:
    order = sorted(names, key=lambda n: -EXPECTED_SECONDS.get(n, 10.0))
    done = {}
    context = multiprocessing.get_context("spawn")  # a fresh interpreter: no state inherited from this one
    init = {"initializer": _worker_init, "initargs": (_calibration_state(),)}
    with ProcessPoolExecutor(workers, mp_context=context, **init) as pool:
        try:
            futures = {pool.submit(_build_chapter, name, ctx): name for name in order}
            for future in as_completed(futures):
                name = futures[future]
                try:
                    done[name] = future.result()
                except Exception as exc:  # the worker died (out of memory, killed): say so in the report
                    done[name] = (None, _one_line(exc), float("nan"), float("nan"))
                _report_progress(progress, name, done[name])
        except BaseException:  # a stop (Ctrl-C, SIGTERM): end the chapters now, not after minutes of them
            _halt(pool)
            raise
    return done


def _report_progress(progress, name: str, built: tuple) -> None:
    """Tell ``progress`` a chapter is done: its module name, its title (the name if it failed) and seconds."""
    if progress is not None:
        chapter, _, seconds, _ = built
        progress(name, chapter.title if chapter is not None else name, seconds)


def _halt(pool: ProcessPoolExecutor) -> None:
    """Cancel the chapters not started and end the workers running the others (they write only in the report's
    temporary folder, removed next)."""
    processes = list((pool._processes or {}).values())  # the executor's own list; no public way to end them
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        process.terminate()
    for process in processes:
        process.join(timeout=30)


def check_report_dir(out_dir: str | Path, *, force: bool = False) -> Path:
    """The report folder, created if needed (its parent must exist); one that holds a report is refused unless
    ``force``, before any chapter runs."""
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"{out}: is a file, not a report folder")
    if not out.exists():
        check_output(out)  # names a missing or read-only parent directory; the folder appears whole at the end
        return out
    existing = [p for p in (out / "results.json", out / "index.html") if p.exists()]
    existing += sorted((out / "figures").glob("*.png"))[:1]
    if existing and not force:
        raise OutputExistsError(f"{out}: already holds a report ({existing[0].name}); pass --force to overwrite it")
    return out


_CSS = """
*{box-sizing:border-box}
body{font-family:system-ui,sans-serif;max-width:1150px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
.scroll{max-width:100%;overflow-x:auto}
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}
td,th{border:1px solid #ccc;padding:3px 7px;vertical-align:top;overflow-wrap:anywhere}
th{background:#f3f3f3}.match{background:#e8f6e8}.discrepancy{background:#fff2d9}.new{background:#e8effa}
.failed{background:#fde4e4;padding:0.5em;white-space:pre-wrap;overflow-wrap:anywhere;font-family:monospace;
font-size:0.8em}
p{overflow-wrap:anywhere}
figure{margin:1em 0;max-width:100%}figure img{max-width:100%;height:auto;border:1px solid #eee}
.gallery{display:grid;grid-template-columns:repeat(auto-fill,minmax(340px,1fr));gap:1em}
.gallery figure{margin:0}
figcaption{font-size:0.9em;color:#444}code{background:#f5f5f5;overflow-wrap:anywhere}
details{margin:1em 0}summary{cursor:pointer;font-weight:600}
"""


@dataclass(frozen=True)
class _Link:
    """A table cell linking to a chapter."""

    slug: str
    text: str


def _cell(value: object) -> str:
    if isinstance(value, _Link):
        return f"<a href='#{html.escape(value.slug)}'>{html.escape(value.text)}</a>"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):  # NaN: no figure there (a thesis column of another digit, a case not run)
        return "n/a" if math.isnan(value) else f"{value:.6g}"
    return html.escape("" if value is None else str(value))


#: Tables longer than this are collapsed under their title (click to open).
COLLAPSE_ROWS = 12


@dataclass(frozen=True)
class _Label:
    """A table cell naming an entry in words, its key (as in ``results.json``) shown on hover."""

    key: str

    def __str__(self) -> str:
        return entry_label(self.key)


def _table_html(columns, rows, row_class=None) -> str:
    head = "<div class='scroll'><table><tr>" + "".join(f"<th>{html.escape(c)}</th>" for c in columns) + "</tr>"
    body = []
    for row in rows:
        cls = f" class='{row_class(row)}'" if row_class else ""
        body.append(f"<tr{cls}>" + "".join(_td(v) for v in row) + "</tr>")
    return head + "".join(body) + "</table></div>"


def _td(value: object) -> str:
    if isinstance(value, _Label):
        return f"<td title='{html.escape(value.key)}'>{html.escape(str(value))}</td>"
    return f"<td>{_cell(value)}</td>"


#: The words of a key's unit suffix, dropped from its label (the unit has its own column).
_UNIT_SUFFIXES = (
    "_rad_s", "_n_m2", "_n_m", "_m_per_command", "_per_command", "_mm", "_db", "_percent", "_hz", "_deg", "_s",
    "_v", "_n", "_m", "_kg", "_g",
)  # fmt: skip
#: Abbreviations of the keys, in words.
_WORDS = {
    "wn": "natural frequency wn",
    "zeta": "damping ratio zeta",
    "lsq": "least squares",
    "rmse": "RMSE",
    "corr2": "corr2",
    "hinf": "H-infinity",
    "sg1": "gauge 1",
    "sg2": "gauge 2",
    "sg3": "gauge 3",
    "num": "numerator",
    "den": "denominator",
}


def entry_label(key: str) -> str:
    """An entry's key in words: ``"twin.release_with_housing.wn_rad_s"`` -> ``"twin, release with housing:
    natural frequency wn"`` (the unit has its column; the key stays in ``results.json`` and on hover).

    Examples
    --------
    >>> entry_label("twin.release_with_housing.wn_rad_s")
    'twin, release with housing: natural frequency wn'
    >>> entry_label("plant.G.den[s^0]")
    'plant, G: denominator [s^0]'
    """
    parts = [p for p in key.split(".") if p]
    words = []
    for i, part in enumerate(parts):
        stem, bracket, rest = part.partition("[")
        if i == len(parts) - 1:
            for suffix in _UNIT_SUFFIXES:
                if stem.endswith(suffix) and len(stem) > len(suffix):
                    stem = stem[: -len(suffix)]
                    break
        text = " ".join(_WORDS.get(w, w) for w in stem.split("_") if w)
        words.append(text + (f" [{rest}" if bracket else ""))
    if len(words) == 1:
        return words[0]
    return ", ".join(words[:-1]) + ": " + words[-1]


def _collapsible(summary: str, inner: str, n_rows: int) -> str:
    if n_rows <= COLLAPSE_ROWS:
        return f"<h3>{summary}</h3>{inner}"
    return f"<details><summary>{summary} ({n_rows} rows)</summary>{inner}</details>"


def _entry_row(e) -> list:
    rel = None if e.rel_error is None else f"{100 * e.rel_error:.3g} %"
    return [_Label(e.key), e.section, e.thesis, e.ours, e.unit, rel, e.status, e.note]


#: The pictures of the first screen: the digit itself, then a few of the thesis's figures beside ours (a figure
#: whose chapter failed or was not built is left out).
FRONT_FIGURES = (
    "twin_shapes_and_servo_step",
    "twin_release_tests",
    "twin_actuation_sweep",
    "ch5_20ms_twin",
    "shape_from_gauges",
    "palpation_force_indentation",
)


def _figure_html(fig) -> str:
    """A figure linked to its full-size image (a click opens it)."""
    src = f"figures/{html.escape(fig.name)}.png"
    ref = f" (beside thesis {html.escape(fig.thesis_ref)})" if fig.thesis_ref else ""
    return (
        f"<figure><a href='{src}'><img src='{src}' alt='{html.escape(fig.caption)}' loading='lazy'></a>"
        f"<figcaption>{html.escape(fig.caption)}{ref}</figcaption></figure>"
    )


def _gallery(chapters: list[Chapter]) -> str:
    by_name = {f.name: f for c in chapters for f in c.figures}
    shown = [by_name[name] for name in FRONT_FIGURES if name in by_name]
    if not shown:
        return ""
    return "<div class='gallery'>" + "".join(_figure_html(f) for f in shown) + "</div>"


def _digit_words(ctx: ReportContext) -> str:
    """A digit in a few words: "2 sections, 2 gauges, 150 mm, a cable pair"."""
    g = ctx.params.geometry
    cables = "one cable" if ctx.params.cables.count == 1 else "a cable pair"
    sections = f"{g.section_count} section{'s' if g.section_count > 1 else ''}"
    return f"{sections}, {ctx.gauges_text}, {1000 * g.digit_length_m:g} mm, {cables}"


def _front_page(chapters: list[Chapter], failed: dict[str, str], ctx: ReportContext, document: dict) -> list[str]:
    by_key = {e.key: e for c in chapters for e in c.entries}
    counts = document["counts"]
    if ctx.thesis_rig:
        title = "The cable-actuated flexible digit, reproduced on its digital twin"
        legend = (
            ". Each entry puts the figure as printed in the thesis beside ours: <span class='match'>match</span>, "
            "<span class='discrepancy'>discrepancy</span> (the note explains it and gives the corrected figure) or "
            "<span class='new'>new</span> (not in the thesis)."
        )
    else:
        title = f"Your digit ({_digit_words(ctx)}) on its digital twin, chapter by chapter as the thesis"
        legend = (
            ". Every entry is this digit's figure (<span class='new'>new</span>); where the thesis printed a figure "
            f"of its own rig for the same quantity, its column reads '{NOT_APPLICABLE}': no figure of this digit is "
            "compared with the thesis rig's."
        )
    parts = [
        f"<h1>{html.escape(title)}</h1>",
        f"<p>flexdigit {html.escape(__version__)}, seed {ctx.seed}{', fast mode' if ctx.fast else ''}, "
        f"twin calibration: {html.escape(_calibration_source())}: "
        f"{sum(counts.values())} entries, "
        + ", ".join(f"<span class='{s}'>{counts[s]} {s}</span>" for s in STATUSES)
        + legend
        + " The same entries, and every table as numbers, are in "
        "<code>results.json</code> (hover over an entry for its key there). Click a figure for its full size.</p>",
        _gallery(chapters),
        "<h2 id='headline'>Headline figures</h2>",
        _table_html(
            ["figure", "section", "thesis", "ours", "unit", "status", "note"],
            [
                [_Headline(h["key"], h["figure"]), by_key[h["key"]].section, by_key[h["key"]].thesis]
                + [by_key[h["key"]].ours, by_key[h["key"]].unit, by_key[h["key"]].status]
                + [_first_sentence(by_key[h["key"]].note)]
                for h in document["headline"]
            ],
            row_class=lambda row: row[5],
        ),  # fmt: skip
        "<h2 id='chapters'>Chapters</h2>",
        _table_html(
            ["chapter", *STATUSES, "tables", "figures", "seconds", "CPU seconds"],
            [
                [_Link(c["slug"], c["title"]), *(c["counts"][s] for s in STATUSES)]
                + [c["tables"], c["figures"], c["seconds"], c["cpu_seconds"]]
                for c in document["chapters"]
            ],
        ),
    ]
    if failed:
        parts.append("<p class='failed'>Failed: " + ", ".join(html.escape(n) for n in failed) + " (below).</p>")
    return parts


@dataclass(frozen=True)
class _Headline(_Label):
    """A headline entry: its words from :data:`HEADLINE`, its key on hover."""

    words: str = ""

    def __str__(self) -> str:
        return self.words


def _first_sentence(note: str) -> str:
    head, _, _ = note.partition(". ")
    return head + ("." if head and not head.endswith(".") else "")


def _render(chapters: list[Chapter], failed: dict[str, str], ctx: ReportContext, document: dict) -> str:
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>flexdigit: "
        + ("the thesis reproduced" if ctx.thesis_rig else "your digit")
        + "</title>",
        f"<style>{_CSS}</style></head><body>",
        *_front_page(chapters, failed, ctx, document),
    ]
    for chapter in chapters:
        parts.append(f"<h2 id='{chapter.slug}'>{html.escape(chapter.title)}</h2>")
        parts.extend(f"<p>{html.escape(p)}</p>" for p in chapter.paragraphs)
        if chapter.entries:
            inner = _table_html(
                ["entry", "section", "thesis", "ours", "unit", "rel. error", "status", "note"],
                [_entry_row(e) for e in chapter.entries],
                row_class=lambda row: row[6],
            )
            heading = "Entries: the thesis beside ours" if ctx.thesis_rig else "Entries: this digit's figures"
            parts.append(_collapsible(heading, inner, len(chapter.entries)))
        for table in chapter.tables:
            title = f"{html.escape(table.title)} <code>{html.escape(table.key)}</code>"
            parts.append(_collapsible(title, _table_html(table.columns, table.rows), len(table.rows)))
        parts.extend(_figure_html(fig) for fig in chapter.figures)
    for module_name, error in failed.items():
        parts.append(f"<h2>{html.escape(module_name)}: failed</h2><div class='failed'>{html.escape(error)}</div>")
    parts.append("</body></html>\n")
    return "\n".join(parts)


def _calibration_source() -> str:
    source = default_calibration_source()
    return "packaged (fitted to the thesis)" if source == "packaged" else source

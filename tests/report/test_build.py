"""The report builder: results.json entries, index.html, figures, and a failing chapter kept visible."""

import json
import sys
import types

import matplotlib.pyplot as plt
import numpy as np
import pytest

from flexdigit.report.build import reproduce
from flexdigit.report.chapter import Chapter, ResultTable
from flexdigit.report.results import compare, new

#: 14 rows: more than build.COLLAPSE_ROWS, so the table is collapsed in the HTML
rows = tuple((0.5 * k, 0.0182 + k * 1e-4, "riccati" if k % 2 else "lmi") for k in range(14)) + (
    (50.0, float("nan"), "x"),
)


def _install(name, build):
    module = types.ModuleType(name)
    module.build = build
    sys.modules[name] = module
    return name


@pytest.fixture
def chapters():
    def good(ctx):
        fig, ax = plt.subplots()
        ax.plot([0, 1], [0, 1])
        return Chapter(
            slug="demo",
            title="Demo chapter",
            paragraphs=["A <b> paragraph & more."],
            entries=[
                compare("demo.k2", "3.4.2", 0.089377, 0.0894, "N m/rad", rtol=1e-3),
                compare("demo.db", "4.6", 0.85, 1.28e-4, "%", rtol=0.01, discrepancy_note="117.83 dB is 1.28e-6."),
                new("demo.new", "7", 1.5, "mm", "RMSE"),
            ],
            tables=[ResultTable("demo.gamma", "gamma by two routes", ("filter_hz", "gamma", "route"), rows)],
            figures=[ctx.save_figure(fig, "demo_line", "a line", thesis_ref="figure 3.5")],
        )

    def bad(ctx):
        raise RuntimeError("chapter exploded")

    names = (_install("fd_test_good_chapter", good), _install("fd_test_bad_chapter", bad))
    yield names
    for name in names:
        sys.modules.pop(name, None)


def test_report_writes_entries_html_and_figures(tmp_path, chapters):
    summary = reproduce(tmp_path, chapters=chapters, workers=1)  # the test chapters live in this process only
    document = json.loads((tmp_path / "results.json").read_text())
    entries = document["entries"]
    assert [e["status"] for e in entries] == ["match", "discrepancy", "new"]
    assert set(entries[0]) == {"key", "section", "thesis", "ours", "unit", "rel_error", "status", "note", "chapter"}
    # every table as numbers (issue 15): cells keep their type, NaN becomes null
    (table,) = document["tables"]
    assert table["key"] == "demo.gamma"
    assert table["chapter"] == "demo"
    assert table["rows"][3] == [1.5, pytest.approx(0.0185), "riccati"]
    assert table["rows"][-1][1] is None
    assert document["counts"] == {"match": 1, "discrepancy": 1, "new": 1}
    assert document["chapters"][0]["counts"] == {"match": 1, "discrepancy": 1, "new": 1}
    assert entries[0]["rel_error"] == pytest.approx(abs(0.0894 - 0.089377) / 0.089377)
    assert summary.counts == {"match": 1, "discrepancy": 1, "new": 1}
    html = (tmp_path / "index.html").read_text()
    assert "A &lt;b&gt; paragraph &amp; more." in html  # text is escaped, never raw HTML
    assert "figures/demo_line.png" in html
    assert (tmp_path / "figures" / "demo_line.png").stat().st_size > 1000
    # the failing chapter is shown with its error, the good one is kept
    assert "fd_test_bad_chapter" in summary.failed
    assert "chapter exploded" in html
    # the first screen: counts per chapter, then the chapters; the 15-row table collapsed under its title
    assert html.index("Chapters</h2>") < html.index("id='demo'")
    assert "<details><summary>gamma by two routes <code>demo.gamma</code> (15 rows)</summary>" in html


def test_unexplained_discrepancy_is_refused():
    with pytest.raises(ValueError, match="no explanation"):
        compare("x", "3.1", 1.0, 2.0, "", rtol=0.01)


CHAPTER_SOURCE = """
import numpy as np
from flexdigit.report.chapter import Chapter
from flexdigit.report.results import new
from flexdigit._result_table import ResultTable


def build(ctx):
    x = ctx.rng({stream}).normal(size=3)  # seeded by the report seed and the chapter's own stream
    if {fail}:
        raise RuntimeError("chapter {name} exploded")
    rows = tuple((float(v),) for v in x)
    return Chapter("{name}", "Chapter {name}", entries=[new("{name}.x0", "1", float(x[0]), "", "")],
                   tables=[ResultTable("{name}.x", "draws", ("x",), rows)])
"""


@pytest.fixture
def chapter_files(tmp_path, monkeypatch):
    # real modules on sys.path: worker processes (spawned) import the chapters by name as the report does
    src = tmp_path / "chapters"
    src.mkdir()
    for name, stream, fail in (("fdpa", 1, False), ("fdpb", 2, False), ("fdpc", 3, True)):
        (src / f"{name}.py").write_text(CHAPTER_SOURCE.format(name=name, stream=stream, fail=fail))
    monkeypatch.syspath_prepend(str(src))
    return ("fdpa", "fdpb", "fdpc")


def test_parallel_chapters_give_the_same_numbers_in_reading_order(tmp_path, chapter_files):
    # issue 15: chapters run in worker processes; the numbers and their order do not depend on the workers
    one = reproduce(tmp_path / "one", chapters=chapter_files, workers=1, seed=7)
    two = reproduce(tmp_path / "two", chapters=chapter_files, workers=2, seed=7)
    a = json.loads((tmp_path / "one" / "results.json").read_text())
    b = json.loads((tmp_path / "two" / "results.json").read_text())
    assert a["entries"] == b["entries"]
    assert a["tables"] == b["tables"]
    assert [e["key"] for e in b["entries"]] == ["fdpa.x0", "fdpb.x0"]  # reading order, the failed one left out
    # the same draws as numpy's generator seeded [seed, stream]: the chapter's own stream, in whichever process
    assert b["tables"][1]["rows"][2][0] == np.random.default_rng([7, 2]).normal(size=3)[2]
    assert set(one.failed) == set(two.failed) == {"fdpc"}
    assert "fdpc exploded" in two.failed["fdpc"]
    assert set(two.seconds) == set(chapter_files)


def test_worker_processes_run_on_the_calibration_of_the_caller(tmp_path, monkeypatch):
    # a use_calibration block (flexdigit reproduce --calibration) reaches every chapter, also in worker processes
    from flexdigit.twin.calibration import packaged_calibration, use_calibration

    src = tmp_path / "chapters"
    src.mkdir()
    for name in ("fdcala", "fdcalb"):
        (src / f"{name}.py").write_text(
            "from flexdigit.report.chapter import Chapter\nfrom flexdigit.report.results import new\n\n\n"
            "def build(ctx):\n    from flexdigit.twin.calibration import default_calibration\n\n"
            f"    gain = default_calibration().channel_gain[0]\n"
            f"    return Chapter('{name}', '{name}', entries=[new('{name}.gain', '3.4', gain, '', '')])\n"
        )
    monkeypatch.syspath_prepend(str(src))
    mine = packaged_calibration().replace(channel_gain=(0.2, 0.25, 0.3))
    with use_calibration(mine, source="a test"):
        reproduce(tmp_path / "report", chapters=("fdcala", "fdcalb"), workers=2)
    document = json.loads((tmp_path / "report" / "results.json").read_text())
    assert [e["ours"] for e in document["entries"]] == [0.2, 0.2]
    assert document["calibration"] == "a test"


def test_a_worker_runs_every_blas_and_openmp_library_on_one_thread():
    # numpy, SciPy, slycot and scikit-learn each load their own OpenBLAS / OpenMP: those a chapter loads after the
    # worker starts must be held to one thread too (two fight over the cores: a Cholesky ten times slower)
    import ast
    import subprocess

    code = (
        "from flexdigit.report.build import _worker_init; _worker_init(None)\n"
        "import scipy.linalg, sklearn.gaussian_process, slycot\n"
        "from threadpoolctl import threadpool_info\n"
        "print(sorted({(i['internal_api'], i['num_threads']) for i in threadpool_info()}))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    pools = ast.literal_eval(out)  # a printed list of (api, threads) tuples
    assert {api for api, _ in pools} >= {"openblas", "openmp"}  # the libraries are there to be checked
    assert {threads for _, threads in pools} == {1}


def test_a_report_built_in_this_process_runs_its_chapters_on_one_blas_thread(tmp_path):
    # as its workers do (above): the same factorisations, and no BLAS threads fighting for the cores; restored after
    from threadpoolctl import threadpool_info

    seen = []

    def counting(ctx):
        seen.extend(i["num_threads"] for i in threadpool_info() if i["internal_api"] == "openblas")
        return Chapter(slug="threads", title="Threads", entries=[new("threads.n", "1", 1.0, "", "one")])

    before = {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["internal_api"] == "openblas"}
    name = _install("fd_test_threads_chapter", counting)
    try:
        reproduce(tmp_path, chapters=(name,), workers=1)
    finally:
        sys.modules.pop(name, None)
    assert len(seen) >= 3  # numpy's, SciPy's and slycot's OpenBLAS, each held
    assert set(seen) == {1}
    after = {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["filepath"] in before}
    assert after == before

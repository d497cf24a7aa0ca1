"""The report builder: results.json entries, index.html, figures, and a failing chapter kept visible."""

import json
import sys
import types

import matplotlib.pyplot as plt
import pytest

from flexdigit.report.build import reproduce
from flexdigit.report.chapter import Chapter
from flexdigit.report.results import compare, new


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
    entries = json.loads((tmp_path / "results.json").read_text())
    assert [e["status"] for e in entries] == ["match", "discrepancy", "new"]
    assert set(entries[0]) == {"key", "section", "thesis", "ours", "unit", "rel_error", "status", "note"}
    assert entries[0]["rel_error"] == pytest.approx(abs(0.0894 - 0.089377) / 0.089377)
    assert summary.counts == {"match": 1, "discrepancy": 1, "new": 1}
    html = (tmp_path / "index.html").read_text()
    assert "A &lt;b&gt; paragraph &amp; more." in html  # text is escaped, never raw HTML
    assert "figures/demo_line.png" in html and (tmp_path / "figures" / "demo_line.png").stat().st_size > 1000
    # the failing chapter is shown with its error, the good one is kept
    assert "fd_test_bad_chapter" in summary.failed and "chapter exploded" in html


def test_unexplained_discrepancy_is_refused():
    with pytest.raises(ValueError, match="no explanation"):
        compare("x", "3.1", 1.0, 2.0, "", rtol=0.01)

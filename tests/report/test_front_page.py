"""The report's first screen (issue 28, item 4): pictures first (the digit, the thesis's figures beside ours),
entries labelled in words with their key kept, figures linked to their full size, no sideways overflow at 1400 px
(Chromium, as tests/live drives it), and ``reproduce`` saying when each chapter is done and in how long."""

from __future__ import annotations

import json
import os
import re
import sys
import types

import matplotlib.pyplot as plt
import pytest

from flexdigit.cli import main
from flexdigit.report.build import FRONT_FIGURES, entry_label, reproduce
from flexdigit.report.chapter import Chapter, ResultTable
from flexdigit.report.results import compare, new

#: The window the issue names: a laptop's browser, not maximised.
VIEWPORT_PX = 1400
LONG_KEY = "studies.sobol.tip_stiffness_nm_per_rad.geometry.cable_eccentricity_m.S1_confidence_interval_width"


def _install(name, build):
    module = types.ModuleType(name)
    module.build = build
    sys.modules[name] = module
    return name


@pytest.fixture
def wide_chapter():
    """A chapter as wide as the real ones get: a 12-inch figure, long keys and notes, a 12-column table."""

    def build(ctx):
        fig, ax = plt.subplots(figsize=(12, 3.6))
        ax.plot([0, 1], [0, 1])
        small, ax = plt.subplots()
        ax.plot([0, 1], [1, 0])
        note = "a_note_without_spaces_" * 12
        return Chapter(
            slug="wide",
            title="Chapter 9: a wide one",
            paragraphs=["A paragraph."],
            entries=[
                compare("twin.release_with_housing.wn_rad_s", "3.1.2", 13.09, 13.08, "rad/s", rtol=0.01),
                new(LONG_KEY, "8", 0.0624, "", note),
            ],
            tables=[
                ResultTable(
                    "wide.table",
                    "twelve columns",
                    tuple(f"column_{i}_long" for i in range(12)),
                    tuple((1.23456789e-5,) * 12 for _ in range(3)),
                )
            ],  # fmt: skip
            figures=[
                ctx.save_figure(fig, FRONT_FIGURES[1], "a release test", thesis_ref="figure 3.6"),
                ctx.save_figure(small, "not_on_the_front", "a detail"),
            ],
        )

    name = _install("fd_test_wide_chapter", build)
    yield name
    sys.modules.pop(name, None)


def test_entries_are_labelled_in_words_and_keep_their_key(tmp_path, wide_chapter):
    reproduce(tmp_path, chapters=(wide_chapter,), workers=1)
    page = (tmp_path / "index.html").read_text()
    words = "twin, release with housing: natural frequency wn"
    assert f"<td title='twin.release_with_housing.wn_rad_s'>{words}</td>" in page
    assert "<td>twin.release_with_housing.wn_rad_s</td>" not in page  # the key is no longer the label
    keys = [e["key"] for e in json.loads((tmp_path / "results.json").read_text())["entries"]]
    assert keys == ["twin.release_with_housing.wn_rad_s", LONG_KEY]  # results.json keeps the keys


def test_the_first_screen_shows_pictures_linked_to_full_size(tmp_path, wide_chapter):
    reproduce(tmp_path, chapters=(wide_chapter,), workers=1)
    page = (tmp_path / "index.html").read_text()
    gallery = page[page.index("<div class='gallery'>") : page.index("id='headline'")]
    src = f"figures/{FRONT_FIGURES[1]}.png"
    assert f"<a href='{src}'><img src='{src}'" in gallery
    assert "beside thesis figure 3.6" in gallery
    assert "not_on_the_front" not in gallery  # a chapter's detail stays in its chapter
    assert page.index("<div class='gallery'>") < page.index("id='chapters'")  # before any table of numbers
    # every figure of the chapters opens at full size on a click
    images = re.findall(r"<img src='([^']+)'", page)
    linked = re.findall(r"<a href='([^']+)'><img", page)
    assert images == linked


@pytest.mark.parametrize(
    ("key", "words"),
    [
        ("plant.G.num", "plant, G: numerator"),
        ("identify.servo.lsq.wn_rad_s", "identify, servo, least squares: natural frequency wn"),
        ("hinf.tzw_peak_db", "H-infinity: tzw peak"),
        ("actuated.best_estimator_position_rmse_mm", "actuated: best estimator position RMSE"),
    ],
)
def test_entry_label(key, words):
    assert entry_label(key) == words


def test_no_sideways_overflow_at_1400_px(tmp_path, wide_chapter):
    from flexdigit.live.browser import CHROMIUM, launch

    if not os.path.exists(CHROMIUM):
        pytest.fail(f"{CHROMIUM} is missing: `make test` installs Debian's chromium (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    reproduce(tmp_path, chapters=(wide_chapter,), workers=1)
    with sync_playwright() as pw:
        browser = launch(pw)
        try:
            page = browser.new_page(viewport={"width": VIEWPORT_PX, "height": 900})
            page.goto((tmp_path / "index.html").as_uri())
            page.evaluate("() => document.querySelectorAll('details').forEach(d => d.open = true)")
            widths = page.evaluate("() => [document.documentElement.scrollWidth, window.innerWidth]")
            assert widths[0] <= widths[1], widths
            page.click(f"a[href='figures/{FRONT_FIGURES[1]}.png']")  # the full-size figure, on a click
            assert page.url.endswith(f"figures/{FRONT_FIGURES[1]}.png")
        finally:
            browser.close()


def test_reproduce_says_each_chapter_is_done_with_its_time(tmp_path, wide_chapter, capsys, monkeypatch):
    from flexdigit.report import build

    monkeypatch.setattr(build, "CHAPTERS", (wide_chapter,))
    assert main(["reproduce", "--out", str(tmp_path / "r"), "--workers", "1"]) == 0
    (line,) = capsys.readouterr().err.strip().splitlines()
    seconds = float(re.fullmatch(r"Chapter 9: a wide one done in ([\d.]+) s", line.strip()).group(1))
    chapter = json.loads((tmp_path / "r" / "results.json").read_text())["chapters"][0]
    assert seconds == pytest.approx(chapter["seconds"], abs=0.05)  # the time results.json records, to 0.1 s


#: What a chapter's text must not show a reader: a test file, a source file, a module below a domain.
INTERNAL_PATH = re.compile(r"tests/|\b\w+\.py\b|flexdigit\.[a-z_0-9]+\.[a-z_0-9]+")


def _chapter_texts():
    """Every string a chapter module writes (not its docstrings, not its entries' notes), with where it is."""
    import ast
    from pathlib import Path

    import flexdigit.report

    for path in sorted(Path(flexdigit.report.__file__).parent.glob("ch*.py")):
        tree = ast.parse(path.read_text())
        skip = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Module | ast.FunctionDef | ast.ClassDef) and ast.get_docstring(node) is not None:
                skip.add(id(node.body[0].value))
            if isinstance(node, ast.keyword) and node.arg in ("note", "discrepancy_note"):
                skip.update(id(n) for n in ast.walk(node.value))
            if isinstance(node, ast.ImportFrom | ast.Import):
                skip.update(id(n) for n in ast.walk(node))
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skip:
                yield f"{path.name}:{node.lineno}", node.value


def test_chapter_texts_name_no_internal_module_or_test_path():
    found = [f"{where}: {INTERNAL_PATH.search(text).group(0)}" for where, text in _chapter_texts()
             if INTERNAL_PATH.search(text)]  # fmt: skip
    assert not found, found


def test_the_internal_path_rule_itself():
    assert INTERNAL_PATH.search("checked in tests/control/test_analysis.py")
    assert INTERNAL_PATH.search("(flexdigit.control.design20ms)")
    assert not INTERNAL_PATH.search("flexdigit.identify does the same (the ShapeEstimator of flexdigit.shape)")

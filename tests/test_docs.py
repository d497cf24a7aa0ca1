"""The documentation site (issue 28): it builds offline with no warning, every public name of every domain has its
reference page, every gallery example ran in the build and shows its figure, the benchmark page comes from
``make bench``'s JSON, and the README stays one screen that links into the site.

The site is built by the command ``make docs`` runs (incremental: right after ``make docs``, as in ``make test``,
there is nothing left to redo), with every proxy pointed at a closed port, so a build that tried to download
anything would warn and fail.
"""

from __future__ import annotations

import html
import importlib
import importlib.util
import json
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest
from numpydoc import docscrape_sphinx, numpydoc

import flexdigit
from flexdigit.control import thesis_design
from flexdigit.twin import Twin, release_test

#: The first build of the site (a fresh clone without `make docs` before) imports every domain and runs the gallery:
#: a few minutes on a loaded 2-core machine, more than pytest-timeout's 600 s default allows.
pytestmark = [pytest.mark.slow, pytest.mark.timeout(1800)]

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
HTML = DOCS / "_build" / "html"
PACKAGE = Path(flexdigit.__file__).parent
#: The Makefile's `docs` target: -W turns every warning into a failure, --keep-going reports them all.
SPHINX = [sys.executable, "-m", "sphinx", "-b", "html", "-W", "--keep-going", "-q", str(DOCS), str(HTML)]
#: Nothing listens on port 9 (discard): any download the build attempted would fail there.
OFFLINE = {"http_proxy": "http://127.0.0.1:9", "https_proxy": "http://127.0.0.1:9", "no_proxy": ""}
OFFLINE |= {key.upper(): value for key, value in OFFLINE.items()}
#: The README is one screen (issue 28, item 6).
README_MAX_LINES = 150


def _generator():
    spec = importlib.util.spec_from_file_location("flexdigit_docs", DOCS / "_ext" / "flexdigit_docs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def build():
    env = {**os.environ, **OFFLINE, "MPLBACKEND": "Agg"}
    return subprocess.run(SPHINX, capture_output=True, text=True, env=env, cwd=ROOT, timeout=1800)


def test_the_site_builds_offline_with_no_warning(build):
    assert build.returncode == 0, build.stderr[-4000:]
    assert "WARNING" not in build.stderr, build.stderr[-4000:]
    assert (HTML / "index.html").is_file()


def test_no_page_of_the_site_loads_a_script_or_style_from_the_network(build):
    """sphinx-gallery's timing pages loaded jQuery and DataTables from CDNs: a site read offline broke there."""
    assert build.returncode == 0, build.stderr[-2000:]
    remote = re.compile(r"<(?:script|link)\b[^>]*\b(?:src|href)=\"(?:https?:)?//")
    pages = sorted(HTML.rglob("*.html"))
    assert len(pages) > 100  # the whole site, not an empty walk
    offenders = [str(p.relative_to(HTML)) for p in pages if remote.search(p.read_text(errors="replace"))]
    assert not offenders, offenders


def _packages() -> list[str]:
    # every package but the command line, found from the files (not from the generator under test)
    return sorted(
        ".".join(("flexdigit", *p.parent.relative_to(PACKAGE).parts))
        for p in PACKAGE.rglob("__init__.py")
        if p.parent.name != "cli"
    )


def test_every_public_name_of_every_domain_has_a_reference_page(build):
    assert build.returncode == 0, build.stderr[-2000:]
    missing = []
    checked = 0
    for package in _packages():
        module = importlib.import_module(package)
        for name in module.__all__:
            obj = getattr(module, name)
            if isinstance(obj, types.ModuleType):  # a domain named at the top level: its own reference page
                candidates = [HTML / "api" / f"{obj.__name__}.html"]
            else:  # its page, or for a re-export at the top level the page of the domain it comes from
                candidates = [HTML / "api" / "generated" / f"{package}.{name}.html"]
                candidates += [
                    page
                    for page in sorted((HTML / "api" / "generated").glob(f"*.{name}.html"))
                    if getattr(importlib.import_module(page.name[: -len(f".{name}.html")]), name, None) is obj
                ]
            page = next((c for c in candidates if c.is_file()), None)
            checked += 1
            if page is None or (f"{name}</span>" not in page.read_text() and name not in page.name):
                missing.append(f"{package}.{name}")
    assert checked > 250  # every domain's names, not an empty walk (flexdigit has ~300 public names)
    assert not missing, missing


def test_a_reference_page_shows_the_docstring_and_the_members(build):
    page = (HTML / "api" / "generated" / "flexdigit.twin.Twin.html").read_text()
    assert "read_at" in page  # a method, documented on its class's page
    assert "Parameters" in page  # numpydoc's sections rendered


def test_every_gallery_example_ran_in_the_build_and_shows_a_figure(build):
    assert build.returncode == 0, build.stderr[-2000:]
    examples = sorted((ROOT / "examples").glob("plot_*.py"))
    assert len(examples) >= 12  # issue 28: at least 12, from a first step to a design study
    for example in examples:
        page = HTML / "auto_examples" / f"{example.stem}.html"
        assert page.is_file(), example.name
        figure = f"sphx_glr_{example.stem}_001.png"
        assert figure in page.read_text(), f"{example.name} drew no figure"
        assert (HTML / "_images" / figure).is_file(), figure


def test_numpydoc_renders_a_docstring_the_same_with_its_template_compiled_once(monkeypatch):
    """The site's extension hands numpydoc a ``get_doc_object`` that compiles the docstring template once per build
    (numpydoc's own compiles it per docstring): the same text for a class, a function and a design entry point (a
    numpydoc release that changed its own would show here, not as a quietly different reference)."""
    monkeypatch.setattr(numpydoc, "get_doc_object", numpydoc.get_doc_object)  # put back after the test
    _generator().numpydoc_template_once()
    assert numpydoc.get_doc_object is not docscrape_sphinx.get_doc_object
    for obj in (Twin, release_test, thesis_design):
        ours = str(numpydoc.get_doc_object(obj, config={"show_class_members": False}))
        theirs = str(docscrape_sphinx.get_doc_object(obj, config={"show_class_members": False}))
        assert obj.__doc__.strip().splitlines()[0] in ours, obj.__name__  # a rendered docstring, not an empty one
        assert ours == theirs, obj.__name__


def test_the_search_index_stems_a_word_as_sphinx_does_once_per_build():
    """The site's search language keeps each word's stem for the build (Sphinx keeps it for one page)."""
    from sphinx.search.en import SearchEnglish

    ours, sphinx = _generator().search_stems_memoised()({}), SearchEnglish({})
    assert ours.lang == "en"
    for word in ("Controllers", "controlling", "gauges", "Identified", "palpation", "Riccati", "the"):
        assert ours.stem(word) == sphinx.stem(word), word
        assert ours.stem(word) == sphinx.stem(word), word  # from the memo the second time


def test_the_sidebar_kept_by_entry_is_the_theme_s_own_text(build, monkeypatch):
    """The site's extension renders a cached sidebar from the text of its unchanged top-level entries: after the
    theme moves the "current" markers to page after page (from the first entries' level to the last), the text is
    ``str(soup)``, BeautifulSoup's whole rendering that the theme returns."""
    from bs4 import BeautifulSoup
    from pydata_sphinx_theme import toctree

    monkeypatch.setattr(toctree, "_patch_cached_sidebar", toctree._patch_cached_sidebar)  # put back after the test
    generator = _generator()
    assert generator.sidebar_serialised_by_entry()  # the theme as the patch was written for (0.24)
    page = (HTML / "api" / "generated" / "flexdigit.twin.Twin.html").read_text()
    start = page.index('<ul class="current nav bd-sidenav">')
    soup = BeautifulSoup(page[start : page.index("</div>", start)], "html.parser")
    hrefs = sorted(set(re.findall(r'href="([^"#]+)"', str(soup))))
    assert len(hrefs) > 300  # the whole reference, each domain's page and each name's
    kept: dict[int, str] = {}
    current = "flexdigit.twin.Twin.html"
    for href in [*hrefs[:25], *hrefs[::9], current]:
        assert toctree._move_current_markers(soup, old_href=current, new_href=href, show_nav_level=1), href
        current = href
        assert generator.render_sidebar(soup, href, kept) == str(soup), href


def test_the_firmware_sketch_is_not_in_the_gallery(build):
    assert build.returncode == 0, build.stderr[-2000:]
    assert not list((HTML / "auto_examples").rglob("*flexdigit_stream*"))


def test_every_example_imports_from_the_domains_not_their_modules():
    deep = re.compile(r"^\s*(from|import) flexdigit\.\w+\.\w+")
    offenders = [
        f"{path.name}:{number}: {line.strip()}"
        for path in sorted((ROOT / "examples").glob("plot_*.py"))
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if deep.match(line)
    ]
    assert not offenders, offenders


def test_the_benchmark_page_shows_the_json_rows_and_their_run():
    results = {
        "context": {"date_utc": "2026-11-26 10:00", "commit": "abc1234", "cpu_count": 2, "load_average_1min": 0.8},
        "rows": [
            {"module": "bench_control", "name": "H-inf design", "value": 2.1234567, "unit": "ms", "goal": "<= 20 ms"},
            {
                "module": "bench_twin",
                "name": "real-time factor",
                "value": 175.0,
                "unit": "x",
                "goal": ">= 100",
                "note": "best of 3",
            },
        ],
    }
    page = _generator().benchmark_page(results)
    assert "| H-inf design | 2.123 | ms | <= 20 ms |" in page
    assert "| real-time factor | 175 | x | >= 100 |" in page
    assert "## bench_control" in page
    assert "## bench_twin" in page
    assert "abc1234" in page
    assert "2026-11-26 10:00" in page
    assert "- real-time factor: best of 3" in page


def test_without_benchmark_results_the_page_says_how_to_measure_them():
    page = _generator().benchmark_page(None)
    assert "make bench" in page
    assert "|---" not in page  # no table, so no number that was not measured


def test_the_benchmark_page_lists_every_benchmark_and_what_it_measures():
    """Every ``benchmarks/bench_*.py`` is run by ``python -m benchmarks`` (``MODULES`` or ``ON_REQUEST``) and listed
    on the page, measured or not, with its docstring's first sentence (a benchmark added without registering it,
    or without saying what it measures, fails here)."""
    generator = _generator()
    files = sorted(p.stem for p in (ROOT / "benchmarks").glob("bench_*.py"))
    listed = generator.registered_benchmarks()
    assert sorted(listed) == files
    page = generator.benchmark_page(None)
    for name, what in listed.items():
        assert len(what) > 20, name
        assert f"- `{name}` (`python -m benchmarks {name.removeprefix('bench_')}`): {what}" in page
    assert "`bench_stepfix` (`python -m benchmarks stepfix`): The coarse-step check of a digit's 20 ms design" in page
    assert generator.benchmark_index()[0] in generator.benchmark_page({"rows": []})


def test_the_findings_page_shows_every_entry_of_the_report():
    results = {
        "flexdigit": "0.1.0",
        "seed": 0,
        "fast": False,
        "counts": {"match": 1, "discrepancy": 1, "new": 0},
        "chapters": [{"slug": "ch3-models", "title": "Chapter 3: models"}],
        "entries": [
            {
                "key": "table_3_1.zeta[1]",
                "section": "3.1.2",
                "thesis": 0.0008,
                "ours": 0.000801557,
                "unit": "",
                "status": "match",
                "note": "from %OS",
                "chapter": "ch3-models",
            },
            {
                "key": "plant.k1",
                "section": "4.1",
                "thesis": 1.7699,
                "ours": 17.6991,
                "unit": "command/mm",
                "status": "discrepancy",
                "note": "a slip | of 10x",
                "chapter": "ch3-models",
            },
        ],
    }
    page = _generator().findings_page(results)
    assert "## Chapter 3: models" in page
    assert "| `table_3_1.zeta[1]` | 3.1.2 | 0.0008 | 0.00080156 |  | match | from %OS |" in page
    assert "| `plant.k1` | 4.1 | 1.7699 | 17.699 | command/mm | discrepancy | a slip \\| of 10x |" in page
    assert "1 entries match" in page


def test_without_a_report_the_findings_page_says_how_to_make_one():
    page = _generator().findings_page(None)
    assert "make run" in page
    assert "|" not in page


def test_the_readme_is_one_screen_and_links_into_the_site():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= README_MAX_LINES
    for command in ("make run", "make test", "pip install"):
        assert command in readme, command
    links = re.findall(r"\]\((docs/[^)#]+)", readme)
    assert len(links) >= 5
    for link in links:
        assert (ROOT / link).exists(), link


def test_a_benchmark_table_takes_the_rows_of_its_module_and_name():
    results = {
        "rows": [
            {"module": "bench_a", "name": "twin real-time factor", "value": 16.7123, "unit": "x", "note": "best of 3"},
            {"module": "bench_a", "name": "cases per second", "value": 82900.4, "unit": "cases/s"},
            {"module": "bench_b", "name": "twin real-time factor", "value": 2.0, "unit": "x"},
        ]
    }
    rows = _generator().benchmark_rows
    assert rows(results, "bench_a") == [
        ["twin real-time factor", "16.71", "x", "best of 3"],
        ["cases per second", "8.29e+04", "cases/s", ""],
    ]
    assert rows(results, match="real-time") == [["twin real-time factor", "16.71", "x", "best of 3"], [
        "twin real-time factor", "2", "x", ""]]  # fmt: skip
    line = _generator().measured_line(
        {"context": {"date_utc": "2026-11-26 16:15", "commit": "0c598c5"}}, "b.json", "bench_a"
    )
    assert "`b.json`" in line
    assert "2026-11-26 16:15" in line
    assert "`python -m benchmarks bench_a --out b.json`" in line


#: ```{benchmark-table} FILE``` and its options in a page's Markdown.
BENCHMARK_TABLE = re.compile(r"```\{benchmark-table\} (\S+)\n((?::\w+: .*\n)*)```")


def test_every_benchmark_table_of_the_site_shows_its_json_rows(build):
    """The docs' benchmark tables are generated from the JSON a benchmark run wrote, never copied by hand."""
    assert build.returncode == 0, build.stderr[-2000:]
    generator = _generator()
    tables = 0
    for page in sorted(DOCS.rglob("*.md")):
        if "_build" in page.parts:
            continue
        for path, options in BENCHMARK_TABLE.findall(page.read_text()):
            opts = dict(re.findall(r":(\w+): (.*)", options))
            built = (HTML / page.relative_to(DOCS).with_suffix(".html")).read_text()
            source = ROOT / path
            if not source.exists():
                assert "Not measured in this build" in built, (page.name, path)
                assert f"{path}</span>" in built, (page.name, path)
                continue
            rows = generator.benchmark_rows(json.loads(source.read_text()), opts.get("module"), opts.get("match"))
            assert rows, (page.name, path)
            # each row's name as written ("--fast", not an en dash; an apostrophe may be typeset)
            shown = html.unescape(built).replace("\u2019", "'")
            for name, value, _unit, _note in rows:
                assert f"<p>{name}</p>" in shown, (page.name, name)
                assert f"<p>{value}</p>" in shown, (page.name, name, value)
            tables += 1
    assert tables >= 3  # digits.md's and studies.md's, from the JSON kept in benchmarks/


def test_every_file_format_is_on_the_site_with_its_example(build):
    """The help describes each file flexdigit reads with an example; the site shows the same, generated."""
    from flexdigit.cli._formats import FORMATS

    assert build.returncode == 0, build.stderr[-2000:]
    page = (HTML / "_generated" / "file-formats.html").read_text()
    text = re.sub(r"<[^>]+>", "", page)
    for title, _what, example in FORMATS.values():
        heading = title.split(" (")[0]
        assert heading[1:] in text, heading
        for line in example.strip().splitlines():  # each example line, as html escapes it
            assert html.escape(line.strip(), quote=False) in text, (heading, line)
    assert "file-formats.html" in (HTML / "guide" / "cli.html").read_text()  # linked from the command line's guide

"""The documentation site (issue 28): it builds offline with no warning, every public name of every domain has its
reference page, every gallery example ran in the build and shows its figure, the benchmark page comes from
``make bench``'s JSON, and the README stays one screen that links into the site.

The site is built by the command ``make docs`` runs (incremental: right after ``make docs``, as in ``make test``,
there is nothing left to redo), with every proxy pointed at a closed port, so a build that tried to download
anything would warn and fail.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

import flexdigit

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
    assert "|" not in page  # no table, so no number that was not measured


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

"""Pages of the site generated at build time, so none is kept by hand: the API reference from each domain's
``__all__``, the benchmark tables from ``make bench``'s JSON (``benchmarks/results.json``), the findings from
``make run``'s ``report/results.json`` and the rig backends' URL options from their declarations.

A Sphinx extension (``conf.py`` lists it): on ``config-inited`` it writes ``docs/api/*.rst`` (one page per domain,
an autosummary of its public names; autosummary then writes one page per name into ``docs/api/generated/``) and
``docs/_generated/*.md``. A file is rewritten only when its text changes, so an unchanged build stays incremental.
``tests/test_docs.py`` checks the built site against every ``__all__`` and these pages against their JSON.
"""

from __future__ import annotations

import ast
import functools
import html
import importlib
import json
import re
import types
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
PACKAGE = ROOT / "src" / "flexdigit"
BENCH_JSON = ROOT / "benchmarks" / "results.json"
BENCH_MAIN = ROOT / "benchmarks" / "__main__.py"
REPORT_JSON = ROOT / "report" / "results.json"  # what `make run` writes

#: Public modules that are not packages but hold public names of their own (the top level's ``__all__`` names
#: ``params``; ``errors`` and ``interrupts`` are what a caller catches and wraps).
MODULES = ("flexdigit.params", "flexdigit.errors", "flexdigit.interrupts")

#: One line per domain for the reference's index (the domain's docstring says the rest).
TITLES = {
    "flexdigit": "the few objects a user starts from",
    "flexdigit.params": "rig parameters: frozen dataclasses, SI units, TOML",
    "flexdigit.reference": "the thesis's printed figures",
    "flexdigit.models": "component models and the plant (chapters 2-3)",
    "flexdigit.twin": "the digital twin",
    "flexdigit.tdcr": "tendon-driven continuum robots in 3D",
    "flexdigit.identify": "release and step tests to second-order models",
    "flexdigit.control": "H-infinity design, analysis, discretisation, runtime, C export (chapters 4-5)",
    "flexdigit.rig": "the Rig contract, the loop, logs, safety",
    "flexdigit.rig.backends": "the rig backends, by URL",
    "flexdigit.tactile": "load localisation (chapters 6-7)",
    "flexdigit.shape": "the centre line from the gauges",
    "flexdigit.palpation": "contact, tissue stiffness, force control",
    "flexdigit.calibrate": "the twin fitted to a rig's records",
    "flexdigit.live": "the live page and its server",
    "flexdigit.studies": "sensitivity and design studies",
    "flexdigit.report": "the reproduce-the-thesis report",
    "flexdigit.errors": "the exceptions flexdigit raises",
    "flexdigit.interrupts": "stops on signals",
}


def packages() -> list[str]:
    """Every package of flexdigit but the command line (as ``tests/test_public_api.py`` lists them)."""
    return sorted(
        ".".join(("flexdigit", *p.parent.relative_to(PACKAGE).parts))
        for p in PACKAGE.rglob("__init__.py")
        if p.parent.name != "cli" and "static" not in p.parent.parts
    )


def public_names(module_name: str) -> list[str]:
    """The names ``module_name`` exports that are not themselves modules (a domain listed at the top level)."""
    module = importlib.import_module(module_name)
    return [n for n in module.__all__ if not isinstance(getattr(module, n), types.ModuleType)]


def domains() -> dict[str, list[str]]:
    """Domain -> its public names, in the order of its ``__all__``: what the reference documents."""
    return {name: public_names(name) for name in [*packages(), *MODULES]}


def page_name(domain: str, name: str, found: dict[str, list[str]] | None = None) -> str:
    """The reference page of ``domain.name``: its own, or for a name the top level re-exports from a domain
    (``flexdigit.Twin`` is ``flexdigit.twin.Twin``) the domain's, so one object is described once."""
    if domain != "flexdigit":
        return f"{domain}.{name}"
    found = domains() if found is None else found
    obj = getattr(importlib.import_module(domain), name)
    for other, names in found.items():
        if other != domain and name in names and getattr(importlib.import_module(other), name) is obj:
            return f"{other}.{name}"
    return f"{domain}.{name}"


def _write_if_changed(path: Path, text: str) -> None:
    if path.exists() and path.read_text() == text:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def _domain_page(name: str, names: list[str], found: dict[str, list[str]]) -> str:
    title = f"``{name}``"
    lines = [
        title,
        "=" * len(title),
        "",
        f".. automodule:: {name}",
        "   :no-members:",
        "   :no-index:",
        "",
        f".. currentmodule:: {name}",
        "",
        ".. autosummary::",
        "   :toctree: generated/",
        "",
    ]
    # relative to the current module (autosummary refuses a name that repeats it): twin.Twin under flexdigit
    lines += [f"   {page_name(name, n, found).removeprefix(name + '.')}" for n in names]
    return "\n".join(lines) + "\n"


def write_api_pages(app=None, config=None) -> None:
    """``docs/api/index.rst`` and one page per domain (autosummary writes the per-name pages from them)."""
    api = DOCS / "api"
    found = domains()
    index = [
        "API reference",
        "=============",
        "",
        "Every public name of every domain, one page each, generated from the domains' ``__all__``. Import from the",
        "domain, never from a module behind it: ``from flexdigit.control import hinf_riccati``.",
        "",
    ]
    index += [f"- :doc:`{name}`: {TITLES.get(name, '')} ({len(names)} names)" for name, names in found.items()]
    index += ["", ".. toctree::", "   :hidden:", ""] + [f"   {name}" for name in found]
    _write_if_changed(api / "index.rst", "\n".join(index) + "\n")
    for name, names in found.items():
        _write_if_changed(api / f"{name}.rst", _domain_page(name, names, found))
    # a name dropped from an __all__ leaves its stub behind, which autosummary never removes: remove it here
    pages = {page_name(d, n, found) for d, names in found.items() for n in names}
    for stub in (api / "generated").glob("*.rst"):
        if stub.stem not in pages:
            stub.unlink()


def _cell(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def registered_benchmarks() -> dict[str, str]:
    """Every benchmark module ``python -m benchmarks`` runs (``MODULES``, then ``ON_REQUEST``, said so), in its order,
    each with what it measures: its docstring's first sentence. Read from the files, not imported (a benchmark
    imports what it times)."""
    tree = ast.parse(BENCH_MAIN.read_text())
    out: dict[str, str] = {}
    for node in tree.body:
        target = node.target if isinstance(node, ast.AnnAssign) else getattr(node, "targets", [None])[0]
        if isinstance(target, ast.Name) and target.id in ("MODULES", "ON_REQUEST"):
            for module in ast.literal_eval(node.value):
                name = module.rsplit(".", 1)[-1]
                what = _first_sentence(BENCH_MAIN.parent / f"{name}.py")
                out[name] = f"{what} (run only when named)" if target.id == "ON_REQUEST" else what
    return out


def _first_sentence(path: Path) -> str:
    """The first sentence of ``path``'s module docstring, on one line (its first paragraph if it has no full stop),
    its reST roles and literals as Markdown code."""
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    paragraph = " ".join(doc.split("\n\n")[0].split())
    found = re.match(r"(.+?\.)(?:\s+[A-Z(`]|$)", paragraph)
    text = found.group(1) if found else paragraph.removesuffix(":") + "."  # a paragraph that opens a list
    text = re.sub(r":\w+:`~?([^`]+)`", r"`\1`", text)  # :func:`x` -> `x`
    return text.replace("``", "`")


def benchmark_index() -> list[str]:
    """The page's list of every benchmark and what it measures (whether or not ``make bench`` has run)."""
    lines = ["## What each benchmark measures", ""]
    for name, what in registered_benchmarks().items():
        lines.append(f"- `{name}` (`python -m benchmarks {name.removeprefix('bench_')}`): {what}")
    return [*lines, ""]


def benchmark_page(results: dict | None) -> str:
    """The benchmark tables as Markdown, one per benchmark module, from ``make bench``'s JSON (or how to get it),
    after the list of every benchmark and what it measures (:func:`benchmark_index`)."""
    head = ["# Benchmarks", ""]
    if results is None:
        return "\n".join(
            head
            + [
                "No benchmark results in this build: `make bench` measures them on your machine and writes",
                "`benchmarks/results.json`; the next `make docs` turns that file into the tables of this page.",
                "(`python -m benchmarks bench_twin --out FILE` runs one module.)",
                "",
                *benchmark_index(),
            ]
        )
    ctx = results.get("context", {})
    lines = head + [
        f"Measured by `make bench` on {ctx.get('date_utc', '?')} UTC (commit `{ctx.get('commit', '?')}`, "
        f"{ctx.get('cpu_count', '?')} cores, load average {ctx.get('load_average_1min', 0):.1f}, "
        f"Python {ctx.get('python', '?')}). The figures are indicative: compare rows of one run with each other. "
        "This page is generated from `benchmarks/results.json` at every build.",
        "",
        *benchmark_index(),
    ]
    modules: dict[str, list[dict]] = {}
    for row in results.get("rows", []):
        modules.setdefault(row.get("module", "?"), []).append(row)
    for module, rows in modules.items():
        lines += [
            f"## {module}",
            "",
            f"`python -m benchmarks {module}`",
            "",
            "| benchmark | value | unit | goal |",
            "|---|---|---|---|",
        ]
        for row in rows:
            value = row.get("value")
            shown = f"{value:.4g}" if isinstance(value, int | float) else _cell(value)
            lines.append(
                f"| {_cell(row.get('name', ''))} | {shown} | {_cell(row.get('unit', ''))} | "
                f"{_cell(row.get('goal', ''))} |"
            )
        notes = [f"- {_cell(r['name'])}: {_cell(r['note'])}" for r in rows if r.get("note")]
        lines += ["", *notes, ""] if notes else [""]
    return "\n".join(lines)


def write_benchmark_page(app=None, config=None) -> None:
    results = json.loads(BENCH_JSON.read_text()) if BENCH_JSON.exists() else None
    _write_if_changed(DOCS / "_generated" / "benchmarks.md", benchmark_page(results))


def _number(value: object) -> str:
    if isinstance(value, bool) or value is None:
        return "" if value is None else str(value)
    if isinstance(value, int | float):
        return f"{value:.5g}"
    return _cell(value)


def findings_page(results: dict | None) -> str:
    """The report's entries (thesis figure, ours, status, note) per chapter, from ``make run``'s results.json."""
    head = ["# Findings", "", "The thesis against the twin, entry by entry.", ""]
    if results is None:
        return "\n".join(
            head
            + [
                "No report in this build: `make run` reproduces the thesis on the twin and writes",
                "`report/results.json`; the next `make docs` turns it into the tables of this page (every entry: the",
                "thesis's figure as printed, flexdigit's, and whether they match, differ for a stated reason, or are",
                "new).",
                "",
            ]
        )
    counts = results.get("counts", {})
    lines = head + [
        f"From `report/results.json` (flexdigit {results.get('flexdigit', '?')}, seed {results.get('seed', '?')}"
        + (", fast settings" if results.get("fast") else "")
        + f"): {counts.get('match', 0)} entries match the thesis, {counts.get('discrepancy', 0)} differ for the "
        f"reason their note gives, {counts.get('new', 0)} are new (figures the thesis does not have). "
        "`report/index.html` shows them with their figures; this page is generated at every build.",
        "",
    ]
    by_chapter: dict[str, list[dict]] = {}
    for entry in results.get("entries", []):
        by_chapter.setdefault(entry.get("chapter", "?"), []).append(entry)
    titles = {c.get("slug"): c.get("title", c.get("slug")) for c in results.get("chapters", [])}
    for slug, entries in by_chapter.items():
        lines += [
            f"## {titles.get(slug, slug)}",
            "",
            "| entry | section | thesis | ours | unit | status | note |",
            "|---|---|---|---|---|---|---|",
        ]
        for e in entries:
            lines.append(
                f"| `{_cell(e.get('key', ''))}` | {_cell(e.get('section', ''))} | {_number(e.get('thesis'))} | "
                f"{_number(e.get('ours'))} | {_cell(e.get('unit', ''))} | {_cell(e.get('status', ''))} | "
                f"{_cell(e.get('note', ''))} |"
            )
        lines.append("")
    return "\n".join(lines)


def write_findings_page(app=None, config=None) -> None:
    results = json.loads(REPORT_JSON.read_text()) if REPORT_JSON.exists() else None
    _write_if_changed(DOCS / "_generated" / "findings.md", findings_page(results))


def url_options_page(scheme: str) -> str:
    """The options a backend's URL takes, as a Markdown table, from its declarations (``URL_OPTIONS``)."""
    from flexdigit.rig import BACKENDS

    module = importlib.import_module(BACKENDS[scheme].partition(":")[0])
    options = getattr(module, "URL_OPTIONS", ())
    if not options:
        return f"A `{scheme}` URL takes no options.\n"
    lines = ["| option | value | meaning |", "|---|---|---|"]
    for option in options:
        lines.append(f"| `{option.name}` | {_cell(option.expected())} | {_cell(option.help)} |")
    return "\n".join(lines) + "\n"


def file_formats_page() -> str:
    """Every file format flexdigit reads, with its example: the text ``--help`` shows (``flexdigit.cli._formats``,
    whose examples tests/cli/test_help.py loads with each format's reader), so the site and the help agree."""
    from flexdigit.cli._formats import FORMATS, WHERE

    lines = [
        "# File formats",
        "",
        "Every file flexdigit reads, what it holds and an example that loads, as `flexdigit COMMAND --help` shows",
        "them (this page is generated from the same text). Units are SI unless a key names another; an unknown key",
        "is refused in one line naming the file and the key. The built-in files a command takes by name:",
        "`flexdigit list protocols|tissues|specs|robots`.",
        "",
    ]
    for name, (title, what, example) in FORMATS.items():
        heading, _, rest = title.partition(" (")
        suffix = "json" if example.lstrip().startswith("{") else "toml" if "=" in example else "text"
        lines += [
            f"## {heading[0].upper()}{heading[1:]}",
            "",
            f"({rest}" if rest else "",
            "",
            what,
            f"In the help: `{WHERE[name]}`." if name in WHERE else "",
            "",
            f"```{suffix}",
            example.rstrip("\n"),
            "```",
            "",
        ]
    return "\n".join(lines)


def write_file_formats_page(app=None, config=None) -> None:
    _write_if_changed(DOCS / "_generated" / "file-formats.md", file_formats_page())


def write_url_option_pages(app=None, config=None) -> None:
    from flexdigit.rig import BACKENDS

    for scheme in BACKENDS:
        name = scheme.replace("+", "-")
        _write_if_changed(DOCS / "_generated" / "url-options" / f"{name}.md", url_options_page(scheme))


def benchmark_rows(results: dict, module: str | None = None, match: str | None = None) -> list[list[str]]:
    """The rows of a benchmark JSON (``python -m benchmarks ... --out FILE``) as table cells ``[benchmark, value,
    unit, note]``: those of ``module`` whose name contains ``match`` (each optional), in the file's order."""
    cells = []
    for row in results.get("rows", []):
        if module is not None and row.get("module") != module:
            continue
        if match is not None and match not in str(row.get("name", "")):
            continue
        value = row.get("value")
        shown = f"{value:.4g}" if isinstance(value, int | float) and not isinstance(value, bool) else str(value)
        cells.append([str(row.get("name", "")), shown, str(row.get("unit", "")), str(row.get("note", ""))])
    return cells


def measured_line(results: dict, path: str, module: str | None) -> str:
    """Where a generated table's figures come from: the file, its run's date, commit and load, the command."""
    ctx = results.get("context", {})
    load = ctx.get("load_average_1min")
    command = ctx.get("command") or f"python -m benchmarks {module or ''} --out {path}".replace("  ", " ")
    return (
        f"Generated at build time from `{path}` (measured {ctx.get('date_utc', '?')} UTC, commit "
        f"`{ctx.get('commit', '?')}`, {ctx.get('cpu_count', '?')} cores"
        + (f", load average {load:.1f}" if isinstance(load, int | float) else "")
        + f"): `{command}`."
    )


def benchmark_table_directive():
    """The ``{benchmark-table} FILE`` directive (options ``:module:``, ``:match:``): a table of a benchmark JSON's
    rows made at build time, so the figures a page shows are the file's, never copied by hand; the line under it
    says when, where and by what command they were measured. Without the file (``make bench`` writes
    ``benchmarks/results.json``, which git does not keep) a line saying how to measure them."""
    from docutils import nodes
    from docutils.parsers.rst import directives
    from sphinx.util.docutils import SphinxDirective

    def paragraph(text: str):
        # `code` spans as literals, the rest as text (the directive's own lines; no other markup in them)
        para = nodes.paragraph()
        for k, part in enumerate(text.split("`")):
            para += nodes.literal(part, part) if k % 2 else nodes.Text(part)
        return para

    class Directive(SphinxDirective):
        required_arguments = 1
        option_spec = {"module": directives.unchanged, "match": directives.unchanged}

        def run(self):
            path = self.arguments[0]
            module, match = self.options.get("module"), self.options.get("match")
            source = ROOT / path
            self.env.note_dependency(str(source))
            if not source.exists():
                return [
                    paragraph(
                        f"Not measured in this build: `python -m benchmarks {module or ''} --out {path}` (or "
                        "`make bench` for `benchmarks/results.json`) measures these rows on your machine; the next "
                        "`make docs` shows them here."
                    )
                ]
            results = json.loads(source.read_text())
            rows = benchmark_rows(results, module, match)
            if not rows:
                raise self.error(f"{path}: no row of module {module!r} whose name contains {match!r}")
            table = nodes.table(classes=["benchmark-table"])
            group = nodes.tgroup(cols=4)
            table += group
            for width in (30, 8, 6, 40):
                group += nodes.colspec(colwidth=width)
            head, body = nodes.thead(), nodes.tbody()
            group += head
            group += body
            for target, cells in ((head, ["benchmark", "value", "unit", "note"]), *((body, r) for r in rows)):
                row = nodes.row()
                for cell in cells:
                    entry = nodes.entry()
                    entry += nodes.paragraph(cell, cell)
                    row += entry
                target += row
            return [table, paragraph(measured_line(results, path, module))]

    return Directive


#: Pages conf.py excludes (sphinx-gallery's timing pages, which load scripts from CDNs): a build made before they
#: were excluded left their HTML behind, which Sphinx never removes.
UNPUBLISHED = ("sg_execution_times", "auto_examples/sg_execution_times")


def remove_unpublished_pages(app, exception) -> None:
    for page in UNPUBLISHED:
        for path in (Path(app.outdir) / f"{page}.html", Path(app.outdir) / "_sources" / f"{page}.rst.txt"):
            path.unlink(missing_ok=True)


def numpydoc_template_once() -> None:
    """Have numpydoc compile its docstring template once per builder, not once per docstring.

    ``numpydoc.docscrape_sphinx.get_doc_object`` builds a Jinja environment and compiles
    ``numpydoc_docstring.rst`` on every call: ~2300 calls, ~1.5 ms each, 3-4 s of a cold build's CPU for the same
    template. numpydoc's ``setup`` takes a replacement (``get_doc_object_``), read from its module's global at each
    docstring: this one renders with the same template and classes, compiled on first use.
    """
    from jinja2 import FileSystemLoader
    from jinja2.sandbox import SandboxedEnvironment
    from numpydoc import docscrape, docscrape_sphinx, numpydoc
    from sphinx.jinja2glue import BuiltinTemplateLoader

    folders = [str(Path(docscrape_sphinx.__file__).parent / "templates")]
    compiled: dict[int, object] = {}

    def get_doc_object(obj, what=None, doc=None, config=None, builder=None):
        config = {} if config is None else config
        if id(builder) not in compiled:
            loader = FileSystemLoader(folders)
            if builder is not None:
                loader = BuiltinTemplateLoader()
                loader.init(builder, dirs=folders)
            compiled[id(builder)] = SandboxedEnvironment(loader=loader).get_template("numpydoc_docstring.rst")
        config["template"] = compiled[id(builder)]
        classes = {"class_doc": docscrape_sphinx.SphinxClassDoc, "func_doc": docscrape_sphinx.SphinxFunctionDoc}
        classes["obj_doc"] = docscrape_sphinx.SphinxObjDoc
        return docscrape.get_doc_object(obj, what=what, doc=doc, config=config, **classes)

    numpydoc.get_doc_object = get_doc_object


def search_stems_memoised():
    """Sphinx's English search language with its stems kept for the whole build, as a class for
    ``app.add_search_language``.

    Sphinx memoises a word's stem within one page only (``IndexBuilder.feed``): the ~490 pages stem ~55,000 words,
    in pure Python (snowballstemmer; PyStemmer is not installed), mostly the same few thousand again. The stem of a
    word does not depend on its page, so the search index is the same.
    """
    from sphinx.search.en import SearchEnglish

    class SearchEnglishMemo(SearchEnglish):
        def __init__(self, options):
            super().__init__(options)
            self.stem = functools.cache(self.stem)

    return SearchEnglishMemo


def sidebar_serialised_by_entry() -> bool:
    """Have pydata-sphinx-theme reuse the text of the sidebar's top-level entries a page does not change.

    The theme renders the sidebar of a section once and, for each further page of it, moves the "current" markers
    on the kept BeautifulSoup (``_move_current_markers``) and serialises the whole soup again: every API page's
    sidebar holds the ~440 entries of the reference, ~8 s of a build. Only the top-level entries (``<li>``) that
    held the previous page or hold this one change, so the others' text is kept from the page before; each piece
    is still BeautifulSoup's own rendering, so the page is the same text (``tests/test_docs.py`` checks it against
    ``str(soup)``). The theme's private functions are replaced only where they are as this was written for (0.24),
    else the theme is left as it is (returns False).
    """
    try:
        from pydata_sphinx_theme import toctree
    except ImportError:
        return False
    needed = ("_patch_cached_sidebar", "_move_current_markers", "_sidebar_cache")
    if not all(callable(getattr(toctree, name, None)) for name in needed):
        return False
    pieces: dict[int, dict[int, str]] = {}  # id(soup) -> id(top-level <li>) -> its text

    def patch_cached_sidebar(app, cache_key, pagename, show_nav_level):
        # pydata-sphinx-theme 0.24's _patch_cached_sidebar, but for its last line (str(soup))
        cached = toctree._sidebar_cache(app).get(cache_key)
        if cached is None:
            return None
        cached_pagename, soup = cached
        new_href = app.builder.get_relative_uri(cached_pagename, pagename)
        moved = toctree._move_current_markers(
            soup,
            old_href=app.builder.get_relative_uri(pagename, cached_pagename),
            new_href=new_href,
            show_nav_level=show_nav_level,
        )
        if not moved:
            return None
        cached[0] = pagename
        return render_sidebar(soup, new_href, pieces.setdefault(id(soup), {}))

    toctree._patch_cached_sidebar = patch_cached_sidebar
    return True


def render_sidebar(soup, new_href: str, kept: dict[int, str]) -> str:
    """``str(soup)`` for a sidebar whose "current" markers just moved to the entry linking ``new_href``: each
    top-level ``<li>`` from ``kept`` (its text at the previous page, updated here) unless it held the previous
    page's entry (``href="#"``) or holds this one's; every other piece rendered by BeautifulSoup as ``str`` does."""
    from bs4 import NavigableString

    changed = ('href="#"', f'href="{html.escape(new_href, quote=False)}"')

    def render(node) -> str:
        if isinstance(node, NavigableString):
            return node.output_ready()
        if node.name == "li":
            text = kept.get(id(node))
            if text is None or any(mark in text for mark in changed):
                text = kept[id(node)] = node.decode()
            return text
        shell = node.decode(iterator=iter([node]))  # its start and end tags, as decode writes them
        end = f"</{node.name}>" if shell.endswith(f"</{node.name}>") else ""
        return shell[: len(shell) - len(end)] + "".join(render(child) for child in node.contents) + end

    return render(soup)


def setup(app):
    # on config-inited: before Sphinx looks for source files and autosummary reads the pages written here
    app.connect("config-inited", write_api_pages)
    app.connect("config-inited", write_benchmark_page)
    app.connect("config-inited", write_url_option_pages)
    app.connect("config-inited", write_findings_page)
    app.connect("config-inited", write_file_formats_page)
    app.connect("build-finished", remove_unpublished_pages)
    app.add_directive("benchmark-table", benchmark_table_directive())
    numpydoc_template_once()
    app.add_search_language(search_stems_memoised())
    sidebar_serialised_by_entry()
    return {"parallel_read_safe": True, "parallel_write_safe": True}

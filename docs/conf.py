"""Sphinx configuration of flexdigit's site: ``make docs`` (offline, warnings are errors).

Prose is Markdown (myst-parser), docstrings numpydoc, the API reference autosummary pages generated from each
domain's ``__all__`` (``_ext/flexdigit_docs.py``), the gallery sphinx-gallery running ``examples/plot_*.py``.
Nothing is fetched: no intersphinx, the theme's assets are packaged.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(ROOT / "src"))  # this checkout's sources, whatever the venv's editable install points at
os.environ.setdefault("MPLBACKEND", "Agg")

import flexdigit  # noqa: E402

project = "flexdigit"
author = "flexdigit contributors"
copyright = "2026, flexdigit contributors; the thesis: see Citing"
release = version = flexdigit.__version__ if hasattr(flexdigit, "__version__") else "0.1.0"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "flexdigit_docs",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]  # autosummary/class.rst: a class's members on its own page
exclude_patterns = [
    "_build",
    "_templates",
    "auto_examples/*.ipynb",
    "auto_examples/*.py",
    "auto_examples/*.zip",
    "**.mjs",
    # sphinx-gallery's timing pages load jQuery and DataTables from CDNs: kept on disk (the build's times per
    # example, docs/sg_execution_times.rst), not published, so no page of the site fetches anything
    "sg_execution_times.rst",
    "auto_examples/sg_execution_times.rst",
]
suppress_warnings: list[str] = []
# quotes and ellipses, not dashes: "--force" in a generated table's cell (a benchmark's name) stays an option
smartquotes_action = "qe"

# -- myst: the README's tutorials moved here as they were written (headings linked by their slug)
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence", "deflist"]

# -- API reference
autosummary_generate = True
autosummary_imported_members = True
# scikit-learn adds these request setters to every estimator; their docstrings cite scikit-learn's own glossary
autodoc_default_options = {
    "exclude-members": "set_fit_request,set_predict_request,set_score_request,set_transform_request,"
    "set_partial_fit_request,set_output",
}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
numpydoc_show_class_members = False  # one page per public name; a class's methods stay on its page
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# -- gallery: examples/plot_*.py, each run at build time; examples/flexdigit_stream is a firmware sketch
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "ignore_pattern": r"flexdigit_stream",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "show_memory": False,
    "plot_gallery": "True",
    "capture_repr": (),
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "min_reported_time": 0,
}

# -- HTML
html_theme = "pydata_sphinx_theme"
html_title = "flexdigit"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 5,
    "icon_links": [],
}
html_show_sourcelink = False

"""Every domain's public names are one import away and listed (issue 23): ``from flexdigit.palpation import
ContactEstimator`` works, ``dir(flexdigit.control)`` shows ``hinf_riccati`` before its first use, and importing a
domain loads none of its modules (the command line's start-up)."""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

import flexdigit

PACKAGE = Path(flexdigit.__file__).parent
#: Every package of flexdigit but the command line (which nothing imports, and which exports nothing).
PACKAGES = sorted(
    ".".join(("flexdigit", *p.parent.relative_to(PACKAGE).parts))
    for p in PACKAGE.rglob("__init__.py")
    if p.parent.name != "cli"
)


@pytest.mark.parametrize("package", PACKAGES)
def test_every_package_declares_all(package):
    module = importlib.import_module(package)
    assert isinstance(getattr(module, "__all__", None), list), f"{package} has no __all__"


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_name_imports_and_is_listed(package):
    module = importlib.import_module(package)
    listed = set(dir(module))
    for name in module.__all__:
        assert name in listed, f"dir({package}) lacks {name}"
        assert getattr(module, name) is not None, f"{package}.{name}"


@pytest.mark.parametrize("package", PACKAGES)
def test_no_public_name_is_also_a_submodule(package):
    # `flexdigit.control.discretise` cannot be both the function and the module: whichever is imported last would
    # win; so a public name never repeats a module's name (a package is its own submodule only at the top)
    module = importlib.import_module(package)
    folder = Path(module.__file__).parent
    submodules = {p.stem for p in folder.glob("*.py")} | {p.name for p in folder.iterdir() if p.is_dir()}
    clashes = {name for name in module.__all__ if name in submodules and package != "flexdigit"}
    assert not clashes, clashes


@pytest.mark.parametrize(
    ("statement", "name"),
    [
        ("from flexdigit.palpation import ContactEstimator", "ContactEstimator"),
        ("from flexdigit.control import hinf_riccati", "hinf_riccati"),
        ("from flexdigit.tactile import collect, thesis_split, ThesisNetwork", "ThesisNetwork"),
        ("from flexdigit.rig import make_controller, open_rig, run_loop", "make_controller"),
        ("from flexdigit import RigParams, Twin, open_rig, make_controller, collect", "Twin"),
    ],
)
def test_the_names_a_newcomer_looks_for(statement, name):
    # the names issue 23 took ten minutes with `inspect` to find
    scope: dict = {}
    exec(statement, scope)
    assert callable(scope[name])


def test_a_public_name_is_the_object_of_its_module():
    from flexdigit.control import hinf_riccati
    from flexdigit.control.synthesis import hinf_riccati as defined

    assert hinf_riccati is defined


def test_an_unknown_name_is_an_attribute_error_naming_the_package():
    import flexdigit.tactile

    with pytest.raises(AttributeError, match="'flexdigit.tactile' has no attribute 'colect'"):
        flexdigit.tactile.colect  # noqa: B018


def test_importing_the_packages_loads_none_of_their_modules():
    # a fresh interpreter: the package import is what `flexdigit --help` pays for
    code = (
        "import sys, flexdigit, " + ", ".join(PACKAGES) + "\n"
        "heavy = [m for m in ('control', 'scipy', 'numba', 'sklearn', 'flexdigit.twin.twin') if m in sys.modules]\n"
        "print(','.join(heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ""


#: An import from a module behind a domain: ``from flexdigit.tactile.runner import collect``, also as
#: ``import flexdigit.tactile.runner`` and in a doctest's ``>>>`` line.
DEEP_IMPORT = re.compile(r"^\s*(>>> |\.\.\. )?\s*(from flexdigit\.\w+\.\w+[\w.]* import |import flexdigit\.\w+\.\w+)")


def test_the_docs_examples_import_from_the_domain():
    # a newcomer copies the README's, the docs' and the gallery's imports: they show the public door, not a module
    # behind it
    root = Path(__file__).resolve().parents[1]
    pages = [root / "README.md", *sorted((root / "docs").rglob("*.md")), *sorted((root / "docs").rglob("*.rst"))]
    offenders = [
        f"{path.name}:{number}: {line.strip()}"
        for path in [*pages, *sorted((root / "examples").glob("*.py"))]
        if "_build" not in path.parts
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if DEEP_IMPORT.match(line)
    ]
    assert not offenders, offenders


@pytest.mark.parametrize(
    ("line", "deep"),
    [
        ("from flexdigit.tactile.runner import collect", True),
        ("    import flexdigit.tactile.runner as runner", True),
        (">>> from flexdigit.twin.twin import Twin", True),
        ("from flexdigit.tactile import collect", False),
        ("import flexdigit", False),
        ("from flexdigit import Twin", False),
    ],
)
def test_the_deep_import_pattern_itself(line, deep):
    assert bool(DEEP_IMPORT.match(line)) is deep


MODULES = sorted(
    ".".join(("flexdigit", *p.relative_to(PACKAGE).with_suffix("").parts))
    for p in PACKAGE.rglob("*.py")
    if p.name not in ("__init__.py", "__main__.py") and "cli" not in p.relative_to(PACKAGE).parts
)


@pytest.mark.parametrize("module_name", MODULES)
def test_every_name_a_module_declares_public_exists(module_name):
    # a module's __all__ is its public part: a stale entry would break `from module import *` and the docs
    module = importlib.import_module(module_name)
    missing = [name for name in getattr(module, "__all__", ()) if not hasattr(module, name)]
    assert not missing, missing

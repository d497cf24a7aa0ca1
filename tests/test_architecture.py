"""The package's layout holds: imports run one way along the chain, no domain imports the CLI, no module imports
itself back through others, and no module name is used twice.

params -> models -> twin -> identify -> control -> rig -> (tactile, shape) -> palpation -> calibrate ->
(live, studies) -> report -> cli (docs/conventions.md, issues 15 and 23): a module may import its own domain, the
shared leaf modules and the domains before it, never one after it. Read from the source (every ``import`` and
``from ... import``, also inside functions), so an import placed in a function to dodge a cycle is caught as well.
tdcr (tendon robots in 3D, issue 26) sits at the twin's rank.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import flexdigit

PACKAGE = Path(flexdigit.__file__).parent
#: The chain, in order; domains at the same rank (live, studies) may not import each other either.
RANK = {
    "params": 1,
    "models": 2,
    "twin": 3,
    "tdcr": 3,  # the twin's rank: tendon robots in 3D may use params and models, and only the CLI/report use them
    "identify": 4,
    "control": 5,
    "rig": 6,
    "tactile": 7,
    "shape": 7,
    "palpation": 8,
    "calibrate": 9,
    "live": 10,
    "studies": 10,
    "report": 11,
    "cli": 12,
}
#: Shared leaf modules every domain may use (they import no domain).
SHARED = {
    "_validation",
    "_constants",
    "_io",
    "_plot",
    "_json",
    "_command",
    "_lazy",
    "_system",
    "_table",
    "_result_table",
    "_estimator",
    "_repr",
    "_numba_cache",
    "errors",
    "interrupts",
    "reference",
    "__init__",
}
#: Imports that run up the chain today, each with the reason and who removes it (empty when none is known).
KNOWN: dict[tuple[str, str], str] = {}


def _domain(module: str) -> str | None:
    """``flexdigit.twin.calibration`` -> ``twin``; shared -> None. The command line (``flexdigit.cli``) is a domain
    of its own, the top of the chain: a sub-command may present any domain's results (``flexdigit simulate release``
    prints the identified wn and zeta), and nothing imports it."""
    parts = module.split(".")
    if parts[0] != "flexdigit" or len(parts) == 1:
        return None
    head = parts[1]
    if head in SHARED:
        return None
    return head


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    package = _module_name(path) if path.name == "__init__.py" else _module_name(path).rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative import
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            out.add(name)
            out.update(f"{name}.{a.name}" for a in node.names)  # `from flexdigit import twin`
    return {m for m in out if m.startswith("flexdigit")}


def _edges():
    for path in sorted(PACKAGE.rglob("*.py")):
        module = _module_name(path)
        source = _domain(module)
        for target in _imports(path):
            dest = _domain(target)
            if dest is not None and dest in RANK and source is not None:
                yield module, source, target, dest


def _violations():
    out = []
    for module, source, target, dest in _edges():
        if source == dest or source not in RANK:
            continue
        if RANK[dest] >= RANK[source]:
            out.append((module, target, source, dest))
    return out


def test_every_domain_is_on_the_chain():
    domains = {d.name for d in PACKAGE.iterdir() if d.is_dir() and (d / "__init__.py").exists()}
    assert domains <= set(RANK) | {"reference"}, domains - set(RANK)


def test_every_top_level_module_is_a_domain_or_shared():
    # a module beside params.py that is neither would escape every rule here (its imports are not checked)
    modules = {p.stem for p in PACKAGE.glob("*.py")}
    assert modules <= set(RANK) | SHARED, modules - set(RANK) - SHARED


def test_the_shared_modules_import_no_domain():
    # what makes them leaves every domain may use; the package's own __init__ names the start-up objects lazily
    offenders = {
        f"{_module_name(path)} imports {target}"
        for path in sorted(PACKAGE.rglob("*.py"))
        if _domain(_module_name(path)) is None and _module_name(path) != "flexdigit"
        for target in _imports(path) | _named_modules(path)
        if _domain(target) is not None
    }
    assert not offenders, offenders


#: A module named in a string: ``lazy_exports``'s name -> module maps, ``BACKENDS``' "module:factory" entries.
NAMED_MODULE = re.compile(r"flexdigit(\.\w+)+(:\w+)?")


def _named_modules(path: Path | ast.Module) -> set[str]:
    """The flexdigit modules ``path`` (or its parsed tree) names as whole strings, which ``importlib`` imports
    when used: an import by name ties the modules as an ``import`` does (a domain's ``__init__`` exporting a name
    of a domain above it would be an upward import no ``import`` statement shows)."""
    tree = path if isinstance(path, ast.Module) else ast.parse(path.read_text(), filename=str(path))
    return {
        node.value.partition(":")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and NAMED_MODULE.fullmatch(node.value)
    }


def test_no_module_named_in_a_string_runs_up_the_chain():
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        source = _domain(_module_name(path))
        for target in _named_modules(path):
            dest = _domain(target)
            if source in RANK and dest in RANK and dest != source and RANK[dest] >= RANK[source]:
                found.append(f"{_module_name(path)} names {target}")
    assert not found, found


def test_the_named_module_finder_itself():
    tree = ast.parse(
        'X = {"a": "flexdigit.report.build", "b": "flexdigit.rig.backends.sim_backend:from_url"}\n'
        '"""flexdigit.twin names no module: a sentence."""\nY = "flexdigit"'
    )
    assert _named_modules(tree) == {"flexdigit.report.build", "flexdigit.rig.backends.sim_backend"}


def test_no_import_runs_up_the_chain():
    found = {(source, dest): f"{module} imports {target}" for module, target, source, dest in _violations()}
    unexpected = {k: v for k, v in found.items() if k not in KNOWN}
    assert not unexpected, "imports up the chain (params -> ... -> report -> cli):\n" + "\n".join(unexpected.values())
    stale = set(KNOWN) - set(found)
    assert not stale, f"known violations no longer present, remove them from KNOWN: {stale}"


def test_no_domain_imports_the_cli():
    # neither the entry point nor a sub-command's module: python-control's hidden cycle of issue 15
    offenders = [m for m, source, _, dest in _edges() if dest == "cli" and source != "cli"]
    assert not offenders, offenders


@pytest.mark.parametrize(
    ("source", "target", "bad"),
    [
        ("twin", "flexdigit.tactile.pipeline", True),  # the known shape of the old twin -> tactile import
        ("models", "flexdigit.cli", True),
        ("report", "flexdigit.tactile.localisation", False),
        ("live", "flexdigit.studies.sensitivity", True),  # siblings on the chain
        ("rig", "flexdigit._validation", False),
        ("tactile", "flexdigit.cli.simulate", True),  # a domain importing a sub-command
        ("palpation", "flexdigit.tactile.bounds", False),
        ("tactile", "flexdigit.palpation.contact_estimation", True),
        ("shape", "flexdigit.tactile.dataset", True),  # siblings on the chain
    ],
)
def test_the_rule_itself(source, target, bad):
    # the checker would catch each kind of edge (a test of the test: it can fail)
    dest = _domain(target)
    assert (dest is not None and dest != source and RANK[dest] >= RANK[source]) is bad


def test_no_module_name_is_used_twice():
    # one name per concept (issue 23): `flexdigit.tactile.contact` beside `flexdigit.twin.contact` made a reader
    # guess which contact an import meant; packages' __init__ and __main__ are the language's, not concepts
    seen: dict[str, list[str]] = {}
    for path in PACKAGE.rglob("*.py"):
        if path.name not in ("__init__.py", "__main__.py"):
            seen.setdefault(path.stem, []).append(str(path.relative_to(PACKAGE)))
    twice = {name: sorted(paths) for name, paths in seen.items() if len(paths) > 1}
    assert not twice, twice


def _module_graph() -> dict[str, set[str]]:
    """Module -> the flexdigit modules it imports (also inside functions); ``from pkg import name`` counts as an
    import of ``pkg.name`` when that is a module, else of ``pkg``."""
    modules = {_module_name(path): path for path in PACKAGE.rglob("*.py")}
    graph = {}
    for module, path in modules.items():
        targets = set()
        for name in _imports(path):
            while name not in modules and "." in name:
                name = name.rsplit(".", 1)[0]
            if name in modules and name != module:
                targets.add(name)
        graph[module] = targets
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out = []

    def visit(v):  # the graph is a few hundred modules deep at most: recursion is fine
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycle():
    # also inside one folder (studies/loop -> metrics -> spec -> metrics was one, issue 23): a cycle hidden by an
    # import inside a function still ties the modules into one, which no reader can take apart
    assert not _cycles(_module_graph())


def test_the_cycle_finder_itself():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert _cycles(graph) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


#: Names that must be defined once in the package (issue 23: two ConvergenceWarning classes and two step_figures
#: once scored a step two ways), each with the module that holds the one definition.
DEFINED_ONCE = {
    "ConvergenceWarning": "flexdigit.errors",
    "step_figures": "flexdigit.control.analysis",
    "G_STANDARD_M_S2": "flexdigit._constants",
}


def _definitions(tree: ast.Module) -> dict[str, int]:
    """Top-level classes, functions and module-level assigned names of a module -> line."""
    out = {}
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            out[node.name] = node.lineno
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            out.update({t.id: node.lineno for t in targets if isinstance(t, ast.Name)})
    return out


def _gravity_literals(tree: ast.Module) -> list[int]:
    """Lines where a number between 9.7 and 9.9 is given a name or made a parameter's default: a gravity of its
    own (the docstrings' toy examples and tables of hints are neither)."""
    values = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
            values.append(node.value)
        elif isinstance(node, ast.arguments):
            values.extend(d for d in node.defaults + node.kw_defaults if d is not None)
    return [
        v.lineno for v in values if isinstance(v, ast.Constant) and isinstance(v.value, float) and 9.7 < v.value < 9.9
    ]


def test_one_definition_of_a_shared_constant_class_or_figure():
    where: dict[str, list[str]] = {name: [] for name in DEFINED_ONCE}
    gravities = []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = _module_name(path)
        tree = ast.parse(path.read_text(), filename=str(path))
        for name in set(_definitions(tree)) & set(DEFINED_ONCE):
            where[name].append(module)
        if module != DEFINED_ONCE["G_STANDARD_M_S2"]:
            gravities += [f"{module}:{line}" for line in _gravity_literals(tree)]
    assert where == {name: [module] for name, module in DEFINED_ONCE.items()}, "import these, do not redefine them"
    assert not gravities, f"gravity given a value of its own (import flexdigit._constants.G_STANDARD_M_S2): {gravities}"


def test_the_definition_finders_themselves():
    tree = ast.parse("G = 9.81\nclass ConvergenceWarning(UserWarning): pass\ndef f(g_m_s2=9.80665, *, k=1.0): pass")
    assert _definitions(tree) == {"G": 1, "ConvergenceWarning": 2, "f": 3}
    assert _gravity_literals(tree) == [1, 3]
    assert _gravity_literals(ast.parse('HINTS = {"N": ((9.81, "kg"),)}\nx = 9.91')) == []


#: Most lines a function may span (issue 23, docs/conventions.md), counted from ``def`` to its last line, docstring
#: and nested functions included: what a reader scrolls through. ruff has no such rule, so this test enforces it.
MAX_FUNCTION_LINES = 80
#: Functions allowed to be longer, each with why: "kernel" (numerical code read as one piece) or "to split" (a debt:
#: remove the entry when the function is split). The compiled ``_*_kernel.py`` modules are kernels as a whole.
LONG_FUNCTIONS = {}


def _function_lengths(tree: ast.Module, module: str) -> dict[str, int]:
    """``module:Class.method`` (or ``module:function``, ``module:outer.inner``) -> lines spanned."""
    out = {}

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                out[f"{module}:{prefix}{child.name}"] = child.end_lineno - child.lineno + 1
                visit(child, f"{prefix}{child.name}.")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(tree, "")
    return out


def _long_functions() -> dict[str, int]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.stem.startswith("_") and path.stem.endswith("_kernel"):
            continue
        lengths = _function_lengths(ast.parse(path.read_text(), filename=str(path)), _module_name(path))
        out.update({name: n for name, n in lengths.items() if n > MAX_FUNCTION_LINES})
    return out


def test_no_function_is_longer_than_80_lines():
    found = _long_functions()
    unexpected = {name: n for name, n in found.items() if name not in LONG_FUNCTIONS}
    assert not unexpected, f"functions over {MAX_FUNCTION_LINES} lines (split them): {unexpected}"
    stale = set(LONG_FUNCTIONS) - set(found)
    assert not stale, f"no longer over {MAX_FUNCTION_LINES} lines, remove them from LONG_FUNCTIONS: {stale}"
    reasons = {reason for reason in LONG_FUNCTIONS.values() if reason != "to split" and not reason.startswith("kernel")}
    assert not reasons, reasons


def test_the_function_length_counter_itself():
    source = "def f():\n    def g():\n        pass\n    return g\n\n\nclass C:\n    def m(self):\n        return 1\n"
    assert _function_lengths(ast.parse(source), "m") == {"m:f": 4, "m:f.g": 2, "m:C.m": 2}


#: flexdigit imports allowed inside a function outside the command line (docs/conventions.md: flexdigit's own
#: imports at the module top), as (importing module, imported module) -> why. Only heavy third-party packages
#: behind a flexdigit module qualify: numba behind the compiled kernels, python-control and scipy behind the
#: modules the CLI's parser reads constants from (``flexdigit --help`` <= 0.3 s, tests/cli/test_main.py).
LAZY_IMPORTS = {
    ("flexdigit.twin.batched", "flexdigit.twin._batched_kernel"): "numba: imported and compiled when a batch runs",
    ("flexdigit.twin.digit", "flexdigit.twin._batched_kernel"): "numba: imported and compiled when a batch runs",
    ("flexdigit.twin.contact", "flexdigit.twin._contact_points"): "numba: imported and compiled on the first press",
    ("flexdigit.palpation.contact_estimation", "flexdigit.palpation._contact_kernel"): "numba, once in _kernel()",
    ("flexdigit.tactile.netlab", "flexdigit.tactile._scg_kernel"): "numba: imported and compiled when a net trains",
    (
        "flexdigit.studies.execution",
        "flexdigit.studies._warm_worker",
    ): "distributed, when a study runs on Dask",
    ("flexdigit.rig.step_test", "flexdigit.control.analysis"): "python-control; cli/run.py reads a constant here",
    ("flexdigit.rig.step_test", "flexdigit.control.design20ms"): "python-control; cli/run.py reads a constant here",
    ("flexdigit.rig.controllers", "flexdigit.control.design20ms"): "python-control; cli/run.py reads a constant here",
    ("flexdigit.rig.backends.stream_emulator", "flexdigit.twin.twin"): "scipy; cli/run.py reads its defaults",
    ("flexdigit.rig.step_test", "flexdigit.rig.backends.hil_backend"): "scipy (its twin); cli/run.py reads a constant",
    ("flexdigit.twin.digit_calibration", "flexdigit.twin.digit"): "scipy; cli/run.py reads constants beside it",
}


def _modules_imported(node: ast.Import | ast.ImportFrom, package: str) -> set[str]:
    """The flexdigit modules ``node`` imports (``from flexdigit.palpation import _contact_kernel`` -> the kernel)."""
    if isinstance(node, ast.Import):
        return {a.name for a in node.names if a.name.startswith("flexdigit")}
    if node.level:
        base = package.split(".")[: len(package.split(".")) - node.level + 1]
        name = ".".join(base + ([node.module] if node.module else []))
    else:
        name = node.module or ""
    if not name.startswith("flexdigit"):
        return set()
    submodules = {f"{name}.{a.name}" for a in node.names}
    found = {m for m in submodules if _is_module(m)}
    return found or {name}


def _is_module(name: str) -> bool:
    path = PACKAGE.parent.joinpath(*name.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def _imports_in_functions(tree: ast.Module, module: str, package: str) -> set[tuple[str, str]]:
    """(module, imported flexdigit module) for every flexdigit import inside a function of ``tree``."""
    out = set()

    def visit(node, in_function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.Import, ast.ImportFrom)) and in_function:
                out.update((module, target) for target in _modules_imported(child, package))
            visit(child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)))

    visit(tree, False)
    return out


def _lazy_imports() -> set[tuple[str, str]]:
    out = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        module = _module_name(path)
        if module.startswith("flexdigit.cli"):
            continue  # the command line imports per command: start-up time
        package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
        out |= _imports_in_functions(ast.parse(path.read_text(), filename=str(path)), module, package)
    return out


def test_flexdigit_imports_sit_at_the_module_top():
    found = _lazy_imports()
    unexpected = sorted(found - set(LAZY_IMPORTS))
    assert not unexpected, f"flexdigit imports inside functions (move them to the module top): {unexpected}"
    stale = set(LAZY_IMPORTS) - found
    assert not stale, f"no longer imported inside a function, remove them from LAZY_IMPORTS: {stale}"


def test_the_lazy_import_finder_itself():
    source = (
        "from flexdigit.params import RigParams\n"
        "def f():\n    from flexdigit.twin import _batched_kernel\n    import numpy\n"
        "class C:\n    def m(self):\n        if True:\n            from .beam import x\n"
    )
    found = _imports_in_functions(ast.parse(source), "flexdigit.models.plant", "flexdigit.models")
    assert found == {
        ("flexdigit.models.plant", "flexdigit.twin._batched_kernel"),
        ("flexdigit.models.plant", "flexdigit.models.beam"),
    }


#: Most lines a function of the command line may span: a handler parses, makes one library call and formats
#: (issue 23); what it computes lives in the library with the same defaults.
MAX_CLI_FUNCTION_LINES = 45
#: Command-line functions allowed to be longer, each with why ("to split": a debt, remove the entry when done).
LONG_CLI_FUNCTIONS = {
    "flexdigit.cli.design:register": "parser: one add_argument per flag, nothing computed",
    "flexdigit.cli.identify:register": "parser: one add_argument per flag, nothing computed",
    "flexdigit.cli.run:register": "parser: one add_argument per flag, nothing computed",
    "flexdigit.cli.live:register": "parser: one add_argument per flag, nothing computed",
    "flexdigit.cli.tdcr:register": "parser: one add_argument per flag, nothing computed",
}


def test_no_cli_function_is_longer_than_45_lines():
    found = {}
    for path in sorted((PACKAGE / "cli").glob("*.py")):
        lengths = _function_lengths(ast.parse(path.read_text(), filename=str(path)), _module_name(path))
        found.update({name: n for name, n in lengths.items() if n > MAX_CLI_FUNCTION_LINES})
    unexpected = {name: n for name, n in found.items() if name not in LONG_CLI_FUNCTIONS}
    assert not unexpected, (
        f"command-line functions over {MAX_CLI_FUNCTION_LINES} lines (move the work into the library): {unexpected}"
    )
    stale = set(LONG_CLI_FUNCTIONS) - set(found)
    assert not stale, f"no longer over {MAX_CLI_FUNCTION_LINES} lines, remove them from LONG_CLI_FUNCTIONS: {stale}"


# -- the tests' own rules (issue 23): one fact per assert, no module-level warning filter, helpers not in conftest
TESTS = Path(__file__).resolve().parent


def _test_trees():
    for path in sorted(TESTS.rglob("*.py")):
        yield path.relative_to(TESTS), ast.parse(path.read_text(), filename=str(path))


def _chained_asserts(tree: ast.Module) -> list[int]:
    """Lines of ``assert a and b``: two facts in one, so a failure does not say which (write two asserts)."""
    return [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Assert) and isinstance(node.test, ast.BoolOp) and isinstance(node.test.op, ast.And)
    ]


def _module_warning_filters(tree: ast.Module) -> list[int]:
    """Lines of a ``warnings.filterwarnings``/``simplefilter`` call at a module's top level: it silences the
    warning for every test that runs after the import (``@pytest.mark.filterwarnings`` scopes it to one test)."""
    return [
        node.lineno
        for node in tree.body
        if isinstance(node, ast.Expr)
        and isinstance(node.value, ast.Call)
        and isinstance(node.value.func, ast.Attribute)
        and node.value.func.attr in ("filterwarnings", "simplefilter")
    ]


def _conftest_imports(tree: ast.Module) -> list[int]:
    """Lines importing from a conftest: shared helpers live in a module (tests/rig/helpers.py), a conftest only
    makes fixtures (under --import-mode=importlib a conftest is not an importable module anyway)."""
    return [
        node.lineno
        for node in ast.walk(tree)
        if (isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[-1] == "conftest")
        or (isinstance(node, ast.Import) and any(a.name.split(".")[-1] == "conftest" for a in node.names))
    ]


@pytest.mark.parametrize("rule", [_chained_asserts, _module_warning_filters, _conftest_imports])
def test_the_tests_keep_their_rules(rule):
    found = {str(path): lines for path, tree in _test_trees() if (lines := rule(tree))}
    assert not found, f"{rule.__doc__.split(':')[0]}: {found}"


def test_the_test_rule_finders_themselves():
    tree = ast.parse(
        "import warnings\nwarnings.filterwarnings('ignore')\nfrom .conftest import stats\n"
        "def test_x():\n    warnings.simplefilter('error')\n    assert 1 and 2\n"
        "    assert 1 or 2\n    assert 1, 'a and b'\n"
    )
    assert _chained_asserts(tree) == [6]
    assert _module_warning_filters(tree) == [2]  # not the one inside the test
    assert _conftest_imports(tree) == [3]

"""The package's layout holds: imports run one way along the chain, no domain imports the CLI, no module imports
itself back through others, and no module name is used twice.

params -> models -> twin -> identify -> control -> rig -> (tactile, shape) -> palpation -> calibrate ->
(live, studies) -> report -> cli (docs/conventions.md, issues 15 and 23): a module may import its own domain, the
shared leaf modules and the domains before it, never one after it. Read from the source (every ``import`` and
``from ... import``, also inside functions), so an import placed in a function to dodge a cycle is caught as well.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import flexdigit

PACKAGE = Path(flexdigit.__file__).parent
#: The chain, in order; domains at the same rank (live, studies) may not import each other either.
RANK = {
    "params": 1,
    "models": 2,
    "twin": 3,
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
    "_io",
    "_json",
    "_command",
    "_lazy",
    "_system",
    "_table",
    "_result_table",
    "_estimator",
    "errors",
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

"""The package's layout holds: imports run one way along the chain, and no domain imports the CLI.

params -> models -> twin -> identify -> control -> rig -> tactile -> calibrate -> (live, studies) -> report -> cli
(docs/conventions.md, issue 15): a module may import its own domain, the shared leaf modules and the domains before
it, never one after it. Read from the source (every ``import`` and ``from ... import``, also inside functions),
so an import placed in a function to dodge a cycle is caught as well.
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
    "calibrate": 8,
    "live": 9,
    "studies": 9,
    "report": 10,
    "cli": 11,
}
#: Shared leaf modules every domain may use (they import no domain).
SHARED = {
    "_validation",
    "_io",
    "_json",
    "_command",
    "_table",
    "_result_table",
    "_estimator",
    "errors",
    "interrupts",
    "reference",
    "__init__",
}
#: Imports that run up the chain today, each with the reason and who removes it (empty when none is known).
KNOWN: dict[tuple[str, str], str] = {}


def _domain(module: str) -> str | None:
    """``flexdigit.twin.calibration`` -> ``twin``; shared -> None. A domain's ``commands`` module (and
    ``params_commands``) is the command line's, the top of the chain: it may present any domain's results (``flexdigit
    simulate release`` prints the identified wn and zeta), and only ``cli`` may import it."""
    parts = module.split(".")
    if parts[0] != "flexdigit" or len(parts) == 1:
        return None
    head = parts[1]
    if head in SHARED:
        return None
    if head == "params_commands" or (len(parts) > 2 and parts[2] == "commands"):
        return "cli"
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
    # neither the entry point nor a domain's commands module (the CLI's): python-control's hidden cycle of issue 15
    offenders = [m for m, source, _, dest in _edges() if dest == "cli" and source != "cli"]
    assert not offenders, offenders


@pytest.mark.parametrize(
    ("source", "target", "bad"),
    [
        ("twin", "flexdigit.tactile.pipeline", True),  # the known shape of the old twin -> tactile import
        ("models", "flexdigit.cli", True),
        ("report", "flexdigit.tactile.studies", False),
        ("live", "flexdigit.studies.sensitivity", True),  # siblings on the chain
        ("rig", "flexdigit._validation", False),
        ("tactile", "flexdigit.twin.commands", True),  # a domain importing another's command line
    ],
)
def test_the_rule_itself(source, target, bad):
    # the checker would catch each kind of edge (a test of the test: it can fail)
    dest = _domain(target)
    assert (dest is not None and dest != source and RANK[dest] >= RANK[source]) is bad

"""``flexdigit list digits|protocols|...``: the built-in files a command takes by name, one line each.

What ``--params`` (digits), ``collect`` and ``palpate --protocol`` (protocols), ``palpate --tissue`` (tissues),
``study`` (specs) and ``tdcr --robot`` (robots) accept instead of a file of your own; each domain lists its own.
"""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command

KINDS = ("digits", "protocols", "tissues", "specs", "robots")


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = add_command(
        subparsers,
        "list",
        _list,
        help="list the built-in example digits, protocols, tissues, study specs or robots, one line each",
        description=__doc__.splitlines()[0].replace("``", ""),
    )
    parser.add_argument("kind", choices=KINDS, help="what to list")


def _builtins(kind: str) -> dict[str, dict[str, str]]:
    """Per group (the command that takes them), name -> one line."""
    if kind == "digits":
        from flexdigit.params import builtin_digits

        return {
            "--params NAME on any command (copy one to edit: flexdigit params NAME --write mine.toml)": builtin_digits()
        }
    if kind in ("protocols", "tissues"):
        from flexdigit.palpation.palpation_files import builtin_palpation_files

        palpation = builtin_palpation_files()
        if kind == "tissues":
            return {"flexdigit palpate --tissue NAME": palpation["tissues"]}
        from flexdigit.tactile.protocols import builtin_protocols

        return {
            "flexdigit collect NAME (load protocols)": builtin_protocols(),
            "flexdigit palpate --protocol NAME (palpation protocols)": palpation["protocols"],
        }
    if kind == "specs":
        from flexdigit.studies.robot_study import shipped_robot_specs
        from flexdigit.studies.spec import shipped_specs

        return {
            "flexdigit study sensitivity|design NAME": shipped_specs(),
            "flexdigit study sensitivity NAME (tendon robots)": shipped_robot_specs(),
        }
    from flexdigit.tdcr.description import builtin_robots

    return {"flexdigit tdcr statics|dynamics|shape|contact NAME (simulate|live --robot NAME)": builtin_robots()}


def _list(args: argparse.Namespace) -> CommandResult:
    groups = _builtins(args.kind)
    lines = []
    for group, items in groups.items():
        lines.append(f"{group}:")
        width = max(len(name) for name in items)
        lines += [f"  {name:<{width}}  {text}" for name, text in items.items()]
    return CommandResult(data=groups, text="\n".join(lines))

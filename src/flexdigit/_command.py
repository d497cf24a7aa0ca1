"""The plumbing every sub-command shares: what a command returns and how it is added to the parser.

A leaf module (standard library only), so that a sub-command's module (``flexdigit/cli/<command>.py``) never
imports the entry point (:mod:`flexdigit.cli`), which only assembles the sub-commands.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import dataclass, field

__all__ = ["CommandResult", "add_command", "digit_name", "name_sub_commands"]


@dataclass
class CommandResult:
    """What a sub-command returns: JSON-able ``data`` for ``--json`` and ``text`` for people."""

    data: object
    text: str = ""
    exit_code: int = 0
    extra: dict = field(default_factory=dict)


def digit_name(params_path) -> str | None:
    """Whose digit a command ran on, for titles and output: the ``--params`` file's stem (``mine`` for
    ``lab/mine.toml``), or None for the thesis rig (no ``--params``)."""
    if params_path is None:
        return None
    from pathlib import Path

    return Path(params_path).stem


def add_command(
    subparsers: argparse._SubParsersAction,
    name: str,
    func: Callable[[argparse.Namespace], CommandResult],
    help: str,
    description: str | None = None,
) -> argparse.ArgumentParser:
    """Add a sub-command with the common ``--json`` flag; ``func(args)`` returns a :class:`CommandResult`."""
    parser = subparsers.add_parser(name, help=help, description=description or help)
    parser.add_argument("--json", action="store_true", help="print the result as JSON on stdout")
    # the command as typed ("design 20ms", not "20ms"): errors are prefixed "flexdigit design 20ms: error:"
    parser.set_defaults(func=func, command_name=parser.prog.removeprefix("flexdigit").strip())
    return parser


def name_sub_commands(sub: argparse._SubParsersAction) -> None:
    """Let each of ``sub``'s commands report its errors under its whole name ("simulate release", not "simulate")."""
    for parser in sub.choices.values():
        parser.set_defaults(command_name=parser.prog.removeprefix("flexdigit").strip())

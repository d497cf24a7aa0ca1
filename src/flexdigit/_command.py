"""The plumbing every sub-command shares: what a command returns and how it is added to the parser.

A leaf module (standard library only), so that a sub-command's module (``flexdigit/cli/<command>.py``) never
imports the entry point (:mod:`flexdigit.cli`), which only assembles the sub-commands.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

__all__ = ["CommandResult", "add_command", "digit_name", "name_sub_commands", "said_warnings"]


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


@contextlib.contextmanager
def said_warnings(command: str, category: type[Warning]):
    """The warnings of ``category`` raised inside (a design's: ``flexdigit.errors.DesignWarning``), collected into
    the list it yields and said on stderr, one line each prefixed as the command's errors are
    ("flexdigit run: warning: ..."), before the command's report; any other warning goes on as it came."""
    said: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", category)
        yield said
    for w in caught:
        if issubclass(w.category, category):
            said.append(str(w.message))
            print(f"flexdigit {command}: warning: {w.message}", file=sys.stderr, flush=True)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)

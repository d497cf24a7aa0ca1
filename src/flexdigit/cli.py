"""The ``flexdigit`` command: one sub-command per domain, every one with ``--json``.

Each domain registers its own sub-commands from ``flexdigit/<domain>/commands.py`` through a function
``register(subparsers)``; this module only lists those modules, runs the chosen command and prints its
:class:`~flexdigit._command.CommandResult`. Bad input never ends in a traceback: flexdigit's errors (and
``ValueError``/``OSError``) become one line on stderr naming the culprit, with exit code 2 (``--debug`` shows the
traceback).
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
from pathlib import Path

from flexdigit import __version__

#: Modules that add sub-commands, in the order of the architecture (params -> ... -> report).
COMMAND_MODULES: tuple[str, ...] = (
    "flexdigit.params_commands",
    "flexdigit.models.commands",
    "flexdigit.twin.commands",
    "flexdigit.identify.commands",
    "flexdigit.control.commands",
    "flexdigit.rig.commands",
    "flexdigit.tactile.commands",
    "flexdigit.tactile.palpation_commands",
    "flexdigit.calibrate.commands",
    "flexdigit.live.commands",
    "flexdigit.studies.commands",
    "flexdigit.report.commands",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="flexdigit",
        description="The cable-actuated flexible digit (Ward 2004 MPhil thesis), on its digital twin or a real rig.",
    )
    parser.add_argument("--version", action="version", version=f"flexdigit {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks instead of one-line errors")
    subparsers = parser.add_subparsers(title="commands", metavar="COMMAND")
    for module_name in COMMAND_MODULES:
        importlib.import_module(module_name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``flexdigit`` with ``argv`` (default ``sys.argv[1:]``) and return the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    try:
        result = args.func(args)
    except KeyboardInterrupt:
        print(f"flexdigit {args.command_name}: interrupted", file=sys.stderr)
        return 130
    except (ValueError, OSError, ArithmeticError, KeyError) as exc:
        if args.debug:
            raise
        print(f"flexdigit {args.command_name}: error: {_message(exc)}", file=sys.stderr)
        return 2
    try:
        if getattr(args, "json", False):
            from flexdigit._json import to_jsonable  # numpy: not for --help or --version

            json.dump(to_jsonable(result.data), sys.stdout, indent=2)
            sys.stdout.write("\n")
        elif result.text:
            print(result.text)
        sys.stdout.flush()
    except BrokenPipeError:  # `flexdigit ... | head`: the reader left; say nothing more
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - keeps Python's exit-time flush quiet
    return result.exit_code


def _message(exc: BaseException) -> str:
    if isinstance(exc, FileNotFoundError) and exc.filename:
        return f"no such file: {Path(exc.filename)}"
    if isinstance(exc, KeyError) and exc.args:
        return str(exc.args[0])
    return str(exc) or type(exc).__name__


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())

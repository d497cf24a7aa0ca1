"""The ``flexdigit`` command: a module per sub-command, every one with ``--json``; nothing imports this package.

Each sub-command lives in its own module here (``flexdigit/cli/<command>.py``), which adds it to the parser
through a function ``register(subparsers)``; this module only lists those modules, runs the chosen command and
prints its :class:`~flexdigit._command.CommandResult`. Bad input never ends in a traceback: flexdigit's errors (and
``ValueError``/``OSError``) become one line on stderr naming the culprit, with exit code 2 (``--debug`` shows the
traceback). Under ``--json`` the same error is also an object on stdout, so a client always gets JSON::

    {"error": "...", "error_type": "DataFileError", "command": "train", "exit_code": 2}

Command-line mistakes (an unknown option, ``--seed abc``) are reported the same way. Progress displays write to
stderr only: stdout carries the result and nothing else.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import json
import os
import re
import sys
from pathlib import Path

from flexdigit import __version__
from flexdigit.errors import one_line
from flexdigit.interrupts import stop_on_signals, stop_requested

#: Modules that add sub-commands, in the order of the architecture (params -> ... -> report).
COMMAND_MODULES: tuple[str, ...] = (
    "flexdigit.cli.params_file",
    "flexdigit.cli.model",
    "flexdigit.cli.simulate",
    "flexdigit.cli.tdcr",
    "flexdigit.cli.identify",
    "flexdigit.cli.design",
    "flexdigit.cli.run",
    "flexdigit.cli.export",
    "flexdigit.cli.collect",
    "flexdigit.cli.palpate",
    "flexdigit.cli.calibrate",
    "flexdigit.cli.live",
    "flexdigit.cli.study",
    "flexdigit.cli.reproduce",
    "flexdigit.cli.listing",  # `flexdigit list`: a module named list would shadow the builtin in this package
)


class UsageError(ValueError):
    """A command-line mistake argparse found (unknown option, a value of the wrong type)."""


#: What argparse takes for a negative number rather than an option: also a comma list that starts with one
#: (``--gauges-v -0.19,0.1,0.2``, ``--loads-g -5e-1,2``), which argparse alone refuses without ``=``.
_NEGATIVE_VALUE = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(,\s*-?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?)*$")


#: Sphinx roles and RST literals in help text (the sub-commands' docstrings are also the docs'): shown as plain text.
_ROLE = re.compile(r":[a-z]+(?::[a-z]+)?:`~?(?:[^`<]*<)?([^`>]+)>?`")
_LITERAL = re.compile(r"``([^`]+)``")


def plain_text(text: str) -> str:
    """Help text without RST markup: ````x```` -> ``x``, ``:func:`~flexdigit.a.b``` -> ``b``.

    >>> plain_text("see :func:`~flexdigit.rig.open_rig` and ``--seed``")
    'see open_rig and --seed'
    """

    def role(match: re.Match) -> str:
        target = match.group(1)
        return target.rsplit(".", 1)[-1] if match.group(0).startswith(":") and "`~" in match.group(0) else target

    return _LITERAL.sub(r"\1", _ROLE.sub(role, text))


class _HelpFormatter(argparse.HelpFormatter):
    """Descriptions and epilogs wrapped by paragraph, indented lines (examples) kept as written; each option's
    default shown (as argparse's ArgumentDefaultsHelpFormatter, but not "None" or "False", nor where the help
    already gives it)."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        import textwrap

        out = []
        for block in text.split("\n\n"):
            lines = block.splitlines()
            if lines and all(line.startswith(" ") or not line for line in lines):
                out.append("\n".join(indent + line for line in lines))  # an example: as written
            else:
                out.append(
                    textwrap.fill(" ".join(block.split()), width, initial_indent=indent, subsequent_indent=indent)
                )
        return "\n\n".join(out)

    def _get_help_string(self, action) -> str:
        text = action.help or ""
        default = action.default
        if (
            "%(default)" in text
            or "default" in text.lower()
            or default is None
            or default is False
            or default == argparse.SUPPRESS
            or not action.option_strings
            or isinstance(action, argparse._HelpAction | argparse._VersionAction)
        ):
            return text
        return f"{text} (default: %(default)s)" if text else "(default: %(default)s)"


class _Parser(argparse.ArgumentParser):
    """argparse, raising :class:`UsageError` instead of exiting, so that ``--json`` can report it as JSON."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_VALUE  # argparse's hook (a private attribute, stable since 3.2)

    def format_help(self) -> str:
        return plain_text(super().format_help())

    def format_usage(self) -> str:
        return plain_text(super().format_usage())

    def error(self, message: str):  # argparse's hook
        # a declared flag's refusal (flexdigit._validation.Flag) in the format of every parameter message
        flag, sep, rest = message.removeprefix("argument ").partition(": must ")
        if sep and message.startswith("argument "):
            command = self.prog.removeprefix("flexdigit").strip()
            message = f"The '{flag.split('/')[-1]}' parameter of flexdigit {command} must {rest}"
        exc = UsageError(message)
        exc.prog = self.prog
        raise exc


def build_parser() -> argparse.ArgumentParser:
    from flexdigit.cli._formats import index

    parser = _Parser(
        prog="flexdigit",
        description="The cable-actuated flexible digit (Ward 2004 MPhil thesis), on its digital twin or a real rig.",
        epilog=index(),
    )
    parser.add_argument("--version", action="version", version=f"flexdigit {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks instead of one-line errors")
    subparsers = parser.add_subparsers(title="commands", metavar="COMMAND")
    for module_name in COMMAND_MODULES:
        importlib.import_module(module_name).register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``flexdigit`` with ``argv`` (default ``sys.argv[1:]``) and return the exit code.

    From the first import of a sub-command to its result, SIGTERM and SIGHUP stop the command as Ctrl-C does
    (:mod:`flexdigit.interrupts`: the rig's safe state, footers, no temporary file left) and exit with 128 + the
    signal's number; the result is printed after, with the default handlers back.
    """
    if argv is None:  # the program itself (the ``flexdigit`` script, ``python -m flexdigit.cli``): it exits next
        code = main(sys.argv[1:])
        _leave_the_heap_to_the_exit()
        return code
    argv = list(argv)
    with stop_on_signals():
        try:
            outcome = _run_command(argv)
        except KeyboardInterrupt as exc:  # while the sub-commands load or the arguments are parsed
            return _interrupted(exc, "", "--json" in argv)
    if isinstance(outcome, int):
        return outcome
    result, wants_json = outcome
    try:
        if wants_json:
            from flexdigit._json import to_jsonable  # numpy: not for --help or --version

            json.dump(to_jsonable(result.data), sys.stdout, indent=2)
            sys.stdout.write("\n")
        elif result.text:
            print(result.text)
        sys.stdout.flush()
    except BrokenPipeError:  # `flexdigit ... | head`: the reader left; say nothing more
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - keeps Python's exit-time flush quiet
    except OSError:  # the terminal closed (SIGHUP): the work is done and saved, the exit code says how it ended
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115
    return result.exit_code


def _leave_the_heap_to_the_exit() -> None:
    """Move every object to the garbage collector's permanent generation just before the process exits, so the
    interpreter's exit does not walk and free one by one the ~200,000 objects numpy, scipy, numba and the domains
    leave behind: the system takes the memory back at once (0.3-0.4 s of CPU a command: ``flexdigit run --duration
    0.5`` 2.8 -> 2.5 s user). Nothing is lost: the command has returned, its files are written and closed (atomic
    writes, logs, recordings), and ``atexit`` handlers and the flush of stdout and stderr still run. Only for the
    program: a caller of :func:`main` in its own process keeps a collector that collects."""
    gc.freeze()


def _run_command(argv: list[str]):
    """Parse ``argv`` and run the sub-command: ``(result, wants_json)``, or the exit code of an error reported."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except UsageError as exc:
        # argparse has not told us whether --json was asked for: look for it (before any "--" end of options)
        wants_json = "--json" in (argv[: argv.index("--")] if "--" in argv else argv)
        command = exc.prog.removeprefix(parser.prog).strip()
        if not command:  # argparse reports a sub-command's unknown options from the top parser: name the command
            command = next((a for a in argv if not a.startswith("-")), "")
            command = command if command in _command_names(parser) else ""
        return _fail(f"{exc} (see flexdigit {command} --help)".replace("  ", " "), "UsageError", command, wants_json, 2)
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    wants_json = bool(getattr(args, "json", False))
    try:
        result = args.func(args)
    except KeyboardInterrupt as exc:
        return _interrupted(exc, args.command_name, wants_json)
    except Exception as exc:  # noqa: BLE001 - bad input or a bug: one line (and JSON), never a traceback
        stop = stop_requested()
        if stop is not None:  # a stop signal that C code (a numba kernel) handed back as another exception
            return _interrupted(stop, args.command_name, wants_json)
        if args.debug:
            raise
        if isinstance(exc, ValueError | OSError | ArithmeticError | KeyError):  # bad input, named
            return _fail(_message(exc), type(exc).__name__, args.command_name, wants_json, 2)
        text = f"internal error ({type(exc).__name__}: {exc}); please report it, --debug shows the traceback"
        return _fail(text, type(exc).__name__, args.command_name, wants_json, 2)
    return result, wants_json


def _command_names(parser: argparse.ArgumentParser) -> set[str]:
    return {name for action in parser._subparsers._group_actions for name in action.choices}


def _interrupted(exc: KeyboardInterrupt, command: str, wants_json: bool) -> int:
    """A stop by Ctrl-C or a signal: ``{"error": "interrupted by SIGTERM", "signal": "SIGTERM", ...}`` under
    ``--json`` and the shell's exit code for it, 128 + the signal's number."""
    name = getattr(exc, "signal_name", "SIGINT")
    code = getattr(exc, "exit_code", 130)
    return _fail(f"interrupted by {name}", "Interrupted", command, wants_json, code, signal=name)


#: The longest error line printed (characters): a message that echoes a huge value is cut in its middle.
MESSAGE_LIMIT = 2000


def _fail(message: str, error_type: str, command: str, wants_json: bool, code: int, signal: str | None = None) -> int:
    """Report an error: one line on stderr and, under ``--json``, an ``{"error": ...}`` object on stdout."""
    message = one_line(message)  # a library's message may carry newlines; ours are one line
    if len(message) > MESSAGE_LIMIT:  # a value echoed whole (2e6 gauge positions): the line's start and end say it
        half, cut = MESSAGE_LIMIT // 2, len(message) - MESSAGE_LIMIT
        message = f"{message[:half]} ... ({cut} characters left out) ... {message[-half:]}"
    prefix = f"flexdigit {command}" if command else "flexdigit"
    doc = {"error": message, "error_type": error_type, "command": command or None, "exit_code": code}
    if signal is not None:
        doc["signal"] = signal
    try:  # a closed terminal (SIGHUP) takes stderr with it: the exit code still says it
        print(f"{prefix}: {message if signal else 'error: ' + message}", file=sys.stderr)
    except OSError:
        pass
    if wants_json:
        try:
            json.dump(doc, sys.stdout)
            sys.stdout.write("\n")
            sys.stdout.flush()
        except BrokenPipeError:
            sys.stdout = open(os.devnull, "w")  # noqa: SIM115
        except OSError:  # the terminal is gone (SIGHUP)
            pass
    return code


def _message(exc: BaseException) -> str:
    if isinstance(exc, FileNotFoundError) and exc.filename:
        return f"no such file: {Path(exc.filename)}"
    if isinstance(exc, KeyError) and exc.args:
        return str(exc.args[0])
    return str(exc) or type(exc).__name__

"""Help and files (issue 28, item 5): every sub-command's ``--help`` is plain text with its defaults shown, every
file format flexdigit reads is described in some ``--help`` with an example that its reader accepts, and
``flexdigit list`` names the built-ins the commands take by name.

Reference for the built-ins: the library's own lists (tactile.protocols.BUILTIN, palpation's TISSUES and
PROTOCOLS, studies' SHIPPED_SPECS, tdcr's ROBOTS)."""

from __future__ import annotations

import argparse
import json
import re

import pytest

from flexdigit.cli import build_parser, main
from flexdigit.cli._formats import FORMATS

#: RST a docstring may carry into a help text.
MARKUP = re.compile(r"``|:(?:func|mod|class|data|meth|attr|ref|doc):`")


def _parsers(parser: argparse.ArgumentParser, path=()):
    """Every (command path, parser) below ``parser``, itself included."""
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, (*path, name))


PARSERS = list(_parsers(build_parser()))
HELP = {" ".join(path): parser.format_help() for path, parser in PARSERS}


def test_every_sub_command_is_walked():
    assert {"simulate release", "design hinf", "dataset import", "tdcr dynamics", "list", "run", "shape"} <= set(HELP)
    assert len(HELP) > 30


@pytest.mark.parametrize("command", sorted(HELP))
def test_help_is_plain_text(command):
    found = MARKUP.findall(HELP[command])
    assert not found, f"flexdigit {command} --help shows markup: {found}"


@pytest.mark.parametrize(("path", "parser"), PARSERS, ids=[" ".join(p) or "flexdigit" for p, _ in PARSERS])
def test_help_shows_every_default(path, parser):
    formatter = parser._get_formatter()
    for action in parser._actions:
        if not action.option_strings or action.default is None or action.default is False:
            continue
        if action.default == argparse.SUPPRESS:
            continue
        if isinstance(action, argparse._HelpAction | argparse._VersionAction):
            continue
        where = f"flexdigit {' '.join(path)} {action.option_strings[0]}"
        assert action.help, f"{where} has no help: its default is not shown"
        shown = formatter._get_help_string(action) % {**vars(action), "prog": parser.prog}
        assert "default" in shown.lower(), f"{where}: {shown!r}"


def test_help_shows_a_default_argparse_would_not():
    # `--duration` of `simulate step` said nothing of its 1.5 s before
    assert "(default: 1.5)" in re.sub(r"\s+", " ", HELP["simulate step"])


def _reader(name):
    from flexdigit.control.kept_design import read_kept_design
    from flexdigit.identify import read_timeseries
    from flexdigit.palpation.palpation_files import load_palpation_protocol, load_tissue
    from flexdigit.params import load_params
    from flexdigit.studies.spec import load_spec
    from flexdigit.tactile.protocols import load_protocol
    from flexdigit.tdcr import ROBOTS, read_readings
    from flexdigit.tdcr.description import load_robot
    from flexdigit.twin.calibration import load_calibration

    return {
        "kept_design": read_kept_design,
        "record": lambda path: read_timeseries(path, "sg1"),
        "gauge_readings": lambda path: read_readings(path, ROBOTS["rao2021"]),
        "params": load_params,
        "calibration": load_calibration,
        "protocol": load_protocol,
        "tissue": load_tissue,
        "palpation": load_palpation_protocol,
        "spec": load_spec,
        "robot": load_robot,
    }[name]


#: The formats that are not TOML, by the suffix their readers take.
SUFFIX = {"kept_design": ".json", "gauge_readings": ".csv", "record": ".csv"}


@pytest.mark.parametrize("name", sorted(set(FORMATS) - {"dataset"}))
def test_each_file_format_example_is_read_by_its_reader(name, tmp_path):
    path = tmp_path / f"example-{name}{SUFFIX.get(name, '.toml')}"
    example = FORMATS[name][2]
    if name == "record":  # the help shows its first rows; an identification needs 20 or more: the same, continued
        example += "".join(f"{k / 1000:.3f},51,0.471,-0.119\n" for k in range(4, 30))
    path.write_text(example)
    assert _reader(name)(path) is not None


def test_the_dataset_example_imports_with_the_command_its_help_gives(tmp_path, capsys):
    title, what, example = FORMATS["dataset"]
    (command,) = re.findall(r"'(flexdigit dataset import [^']+)'", what)
    (tmp_path / "readings.csv").write_text(example)
    argv = command.split()[1:]
    argv = [str(tmp_path / a) if a in ("readings.csv", "d.parquet") else a for a in argv]
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["samples"] == 3
    assert data["protocol"]["loads_kg"] == pytest.approx([0.025])  # 25 g
    assert data["protocol"]["positions_from_tip_m"] == pytest.approx([0.03, 0.12])  # 30 and 120 mm


@pytest.mark.parametrize("name", sorted(FORMATS))
def test_each_file_format_is_described_in_a_help(name):
    title = FORMATS[name][0]
    flat = {command: re.sub(r"\s+", " ", text) for command, text in HELP.items()}
    assert any(f"File format: {title}" in text for text in flat.values()), title
    assert title.split(" (")[0] in flat[""]  # and listed in `flexdigit --help`


def _builtins():
    from flexdigit.palpation.palpation_files import PROTOCOLS, TISSUES
    from flexdigit.studies.robot_study import SHIPPED_ROBOT_SPECS
    from flexdigit.studies.spec import SHIPPED_SPECS
    from flexdigit.tactile.protocols import BUILTIN
    from flexdigit.tdcr.description import ROBOTS

    return {
        "protocols": (*BUILTIN, *PROTOCOLS),
        "tissues": TISSUES,
        "specs": (*SHIPPED_SPECS, *SHIPPED_ROBOT_SPECS),
        "robots": tuple(ROBOTS),
    }


@pytest.mark.parametrize("kind", ["protocols", "tissues", "specs", "robots"])
def test_list_names_every_built_in_one_line_each(kind, capsys):
    assert main(["list", kind]) == 0
    lines = capsys.readouterr().out.splitlines()
    items = [line.split()[0] for line in lines if line.startswith("  ")]
    assert items == list(_builtins()[kind])
    assert all(len(line.split()) > 2 for line in lines if line.startswith("  "))  # each with its description
    assert main(["list", kind, "--json"]) == 0
    groups = json.loads(capsys.readouterr().out)
    assert [n for group in groups.values() for n in group] == list(_builtins()[kind])


def test_list_refuses_an_unknown_kind_in_one_line(capsys):
    assert main(["list", "robot"]) == 2
    err = capsys.readouterr().err.strip()
    assert "invalid choice: 'robot'" in err
    assert "\n" not in err


def test_no_help_asks_for_an_equals_sign_before_a_negative_value():
    """A negative value or comma list needs no `=` (`--tip-force-n -1,0,0`); tdcr's help still said it did."""
    unwrapped = {command: re.sub(r"-\n\s+", "-", text) for command, text in HELP.items()}  # argparse breaks at "-"
    offenders = [command for command, text in unwrapped.items() if re.search(r"--[\w-]+=-", text)]
    assert not offenders, offenders

"""Brackets nested 10**5 deep in a file a user gives are bad input named by file, never a RecursionError reaching
the top as an internal error (issue 22): the TOML loaders (params, study spec, protocol, calibration, tissue) and
the JSON ones (rotation map)."""

from __future__ import annotations

import importlib

import pytest

DEPTH = 100_000
TOML = "[study]\nname = " + "[" * DEPTH + "]" * DEPTH + "\n"
JSON = "[" * DEPTH + "]" * DEPTH


@pytest.mark.parametrize(
    ("loader", "suffix", "text"),
    [
        ("flexdigit.params:load_params", ".toml", TOML),
        ("flexdigit.studies.spec:load_spec", ".toml", TOML),
        ("flexdigit.tactile.protocols:load_protocol", ".toml", TOML),
        ("flexdigit.twin.calibration:load_calibration", ".toml", TOML),
        ("flexdigit.palpation.palpation_files:load_tissue", ".toml", TOML),
        ("flexdigit.rig.rotation:load_rotation_map", ".json", JSON),
    ],
)
def test_deeply_nested_input_is_named(tmp_path, loader, suffix, text):
    module, name = loader.split(":")
    load = getattr(importlib.import_module(module), name)
    path = tmp_path / f"deep{suffix}"
    path.write_text(text)
    with pytest.raises(ValueError) as err:  # DataFileError and ParameterError are ValueErrors
        load(path)
    assert str(err.value).startswith(str(path)), err.value


@pytest.mark.parametrize("line", [1, 2])
def test_deeply_nested_collect_journal_is_named_by_file_and_line(tmp_path, line):
    import json

    from flexdigit.errors import DataFileError
    from flexdigit.tactile.dataset import JOURNAL_FORMAT, read_journal

    header = json.dumps({"journal": JOURNAL_FORMAT})
    lines = [JSON, header] if line == 1 else [header, JSON]
    path = tmp_path / "collect.journal"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataFileError) as err:
        read_journal(path)
    assert str(err.value).startswith(f"{path}: line {line} ")
    assert "\n" not in str(err.value)

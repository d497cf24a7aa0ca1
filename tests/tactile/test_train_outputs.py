"""``flexdigit train``: the model file is never clobbered without --force, and 0 is a value (issue 16)."""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main
from flexdigit.tactile.protocols import Protocol
from flexdigit.tactile.runner import collect


def _error(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


def test_train_refuses_to_overwrite_a_model_before_training(tmp_path, capsys, make_rig):
    small = Protocol("s", (0.0125, 0.025), (0.0, 0.05, 0.10), repetitions=6, no_load_repetitions=3)
    data = tmp_path / "d.parquet"
    collect(small, make_rig(seed=0), data)
    model = tmp_path / "m.json"
    model.write_text("precious")
    argv = ["train", str(data), "--hidden", "3", "--tol", "1e-4", "--model", str(model), "--json"]
    assert main(argv) == 2
    assert "pass --force" in _error(capsys)["error"]
    assert model.read_text() == "precious"
    assert main([*argv, "--force"]) == 0
    assert json.loads(model.read_text())["hidden"] == 3


@pytest.mark.parametrize("flag", ["--hidden", "--tol"])
def test_zero_is_a_value_for_train(flag, tmp_path, capsys, make_rig):
    """Issue 16: --hidden 0 and --tol 0 were taken as "not given" and started the full sweep."""
    data = tmp_path / "d.parquet"
    collect(Protocol("s", (0.0125,), (0.0, 0.05), repetitions=6, no_load_repetitions=3), make_rig(seed=0), data)
    other = "--tol" if flag == "--hidden" else "--hidden"
    value = "1e-4" if other == "--tol" else "3"
    assert main(["train", str(data), flag, "0", other, value, "--json"]) == 2
    error = _error(capsys)["error"]
    assert f"'{flag}' parameter of flexdigit train" in error
    assert "Got 0" in error  # refused by its declared range


@pytest.mark.parametrize(
    "field, value, culprit",
    [
        ("hidden", "five", r"'hidden' parameter of a model file must be an integer inside \[1, 10000\]. Got 'five'"),
        ("hidden", True, "'hidden' parameter of a model file must be an integer"),
        ("n_outputs", 0, "'n_outputs' parameter of a model file must be an integer inside"),
        ("tol", "small", "'tol' parameter of a model file must be a real number"),
        ("inputs", "gauge1_v", "field 'inputs' must be a list of column names"),
        ("weights", [1, "a"], "field 'weights' must be a list of numbers"),
        ("target", ["position"], "field 'target' is"),
        ("meta", [], "field 'meta' must be an object"),
    ],
)
def test_a_model_file_with_a_bad_field_names_it(field, value, culprit, tmp_path, capsys, make_rig):
    """Issue 16: a model JSON with "hidden": "five" gave a numpy TypeError."""
    data = tmp_path / "d.parquet"
    collect(Protocol("s", (0.0125,), (0.0, 0.05), repetitions=6, no_load_repetitions=3), make_rig(seed=0), data)
    model = tmp_path / "m.json"
    assert main(["train", str(data), "--hidden", "3", "--tol", "1e-4", "--model", str(model)]) == 0
    doc = json.loads(model.read_text())
    doc[field] = value
    model.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["predict", str(model), str(data), "--json"]) == 2
    error = _error(capsys)
    assert error["error_type"] == "DataFileError"
    assert error["error"].startswith(str(model))
    import re

    assert re.search(culprit, error["error"]), error["error"]

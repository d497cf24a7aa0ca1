"""What a newcomer tripped on (issue 28's "Tried by someone who has never seen flexdigit"): each a behaviour, each
with the command line they typed."""

import json

import pytest

from flexdigit.cli import main
from flexdigit.tactile.protocols import Protocol
from flexdigit.tactile.runner import collect

SMALL = Protocol("small", loads_kg=(0.025,), positions_from_tip_m=(0.0, 0.04, 0.08), repetitions=6)


@pytest.fixture
def dataset_file(tmp_path, make_rig):
    path = tmp_path / "lab.parquet"
    collect(SMALL, make_rig(seed=0), path)
    return path


def test_train_writes_its_model_with_out_as_the_other_commands(dataset_file, tmp_path, capsys):
    model = tmp_path / "m.json"
    argv = ["train", str(dataset_file), "--target", "contact", "--hidden", "3", "--tol", "1e-4", "--json"]
    assert main([*argv, "--out", str(model)]) == 0
    assert json.loads(capsys.readouterr().out)["model"] == str(model) and model.is_file()
    assert main([*argv, "--out", str(model)]) == 2  # never over it without --force
    assert "--force" in capsys.readouterr().err
    assert main([*argv, "--model", str(tmp_path / "n.json")]) == 0  # the old name still works
    assert (tmp_path / "n.json").is_file()


def _readings(tmp_path):
    path = tmp_path / "lab.csv"
    path.write_text("A,B,C,L,X\n0.1,0.2,0.3,0,\n0.2,0.3,0.4,0.01,0.02\n0.2,0.3,0.5,0.02,0.04\n")
    return path


def test_a_column_map_takes_the_gauges_as_the_flag_does(tmp_path, capsys):
    columns = tmp_path / "columns.toml"
    columns.write_text('gauges = "A,B,C"\nload = "L"\nposition = "X"\n')
    out = tmp_path / "lab.parquet"
    assert main(["dataset", "import", str(_readings(tmp_path)), "--map", str(columns), "--out", str(out)]) == 0
    assert "3 readings (2 loaded, 1 no load" in capsys.readouterr().out


@pytest.mark.parametrize("gauges", ["3", '["A", 3]', "[]"])
def test_a_bad_gauges_key_names_the_file_the_key_and_a_toml_list(tmp_path, capsys, gauges):
    columns = tmp_path / "columns.toml"
    columns.write_text(f'gauges = {gauges}\nload = "L"\nposition = "X"\n')
    code = main(
        ["dataset", "import", str(_readings(tmp_path)), "--map", str(columns), "--out", str(tmp_path / "o.csv")]
    )
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert f"{columns}: key 'gauges' must be 1 to 8 column names (a TOML list" in err
    assert "ColumnMap" not in err

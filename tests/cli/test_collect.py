import json

import numpy as np
import pytest

from cantilever import SMALL_PROTOCOL
from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.tactile import load_dataset, predict_dataset
from flexdigit.tactile.model_io import SavedModel, load_model
from flexdigit.tactile.runner import collect

#: The command and the library run the same code in one process: the same numbers but for summation order.
SAME_RTOL = 1e-12


@pytest.fixture
def dataset_file(tmp_path, make_rig):
    path = tmp_path / "d.parquet"
    collect(SMALL_PROTOCOL, make_rig(seed=0), path)
    return path


def test_train_and_predict_round_trip(dataset_file, tmp_path, capsys):
    model = tmp_path / "pos.json"
    code = main(
        [
            "train",
            str(dataset_file),
            "--target",
            "position",
            "--hidden",
            "6",
            "--tol",
            "1e-7",
            "--model",
            str(model),
            "--json",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["hidden"] == 6
    # gauge 2 and 3 both see loads beyond gauge 3 (tip 0-4.5 cm) and gauge 1-2 beyond 13.5 cm: position is
    # determined, so a 6-node network on a clean closed-form cantilever locates it to well under 5 mm
    assert out["rmse_mm"] < 5.0
    assert main(["predict", str(model), str(dataset_file), "--json"]) == 0
    pred = json.loads(capsys.readouterr().out)
    assert pred["target"] == "position"
    assert pred["scores"]["corr2"] > 0.99
    assert len(pred["predicted"]) == 2 * 6 * 10  # the loaded readings


def test_contact_target_and_bad_files_give_one_line_errors(dataset_file, tmp_path, capsys):
    assert main(["train", str(dataset_file), "--target", "contact", "--hidden", "4", "--tol", "1e-5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["accuracy"] >= 0.95  # every position of SMALL_PROTOCOL bends gauges 1 and 2: contact is plain to see
    bad = tmp_path / "bad.parquet"
    bad.write_text("nope")
    assert main(["train", str(bad)]) == 2
    assert "not a readable Parquet file" in capsys.readouterr().err
    assert main(["predict", str(dataset_file), str(dataset_file)]) == 2
    assert "not a model file" in capsys.readouterr().err
    assert main(["collect", "no-such-protocol", "--out", str(tmp_path / "x.parquet")]) == 2
    assert "no protocol 'no-such-protocol'" in capsys.readouterr().err


def test_collect_on_the_twin_uses_the_given_calibration(tmp_path, capsys):
    # the same protocol and seed on two calibrations: the gauge volts scale with the channel gains
    from flexdigit.tactile.dataset import load_dataset
    from flexdigit.twin.calibration import packaged_calibration, save_calibration

    protocol = tmp_path / "tiny.toml"
    protocol.write_text(
        'name = "tiny"\nloads_g = [25.0]\npositions_from_tip_cm = [2, 8]\nrepetitions = 2\n'
        "no_load_repetitions = 2\nsettle_s = 0.5\n"
    )
    base = packaged_calibration().replace(noise_white_v=(0.0,) * 3, noise_drift_v_per_sqrt_s=(0.0,) * 3)
    doubled = base.replace(channel_gain=tuple(2 * g for g in base.channel_gain))
    runs = {}
    for name, cal in (("base", base), ("doubled", doubled)):
        path = save_calibration(cal, tmp_path / f"{name}.toml")
        out = tmp_path / f"{name}.parquet"
        assert main(["collect", str(protocol), "--calibration", str(path), "--out", str(out), "--no-progress"]) == 0
        runs[name] = load_dataset(out)
    offsets = np.array(base.channel_offset_v)
    np.testing.assert_allclose(
        runs["doubled"].gauges_v - offsets, 2 * (runs["base"].gauges_v - offsets), rtol=1e-3, atol=2e-4
    )  # 16-bit ADC steps of 0.15 mV
    capsys.readouterr()
    args = ["collect", str(protocol), "--backend", "replay:///nope.jsonl", "--calibration", str(path)]
    assert main([*args, "--out", str(tmp_path / "x.parquet")]) == 2
    assert "--calibration calibrates the twin: it needs a sim backend" in capsys.readouterr().err


def test_predict_is_the_library_call(dataset_file, tmp_path, capsys):
    # issue 23: `flexdigit predict` parses, calls tactile.predict_dataset and formats; it computed the tare, the
    # inputs and the scores itself before
    model = tmp_path / "pos.json"
    argv = ["train", str(dataset_file), "--hidden", "4", "--tol", "1e-5", "--model", str(model), "--json"]
    assert main(argv) == 0
    capsys.readouterr()
    assert main(["predict", str(model), str(dataset_file), "--json"]) == 0
    command = json.loads(capsys.readouterr().out)
    library = predict_dataset(load_model(model), load_dataset(dataset_file))
    assert command["samples"] == library.rows.tolist()
    np.testing.assert_allclose(command["predicted"], library.predicted, rtol=SAME_RTOL)
    np.testing.assert_allclose(command["actual"], library.actual, rtol=SAME_RTOL)
    # the scores against numpy's own Pearson coefficient and a plain RMSE
    pearson = np.corrcoef(library.predicted, library.actual)[0, 1]
    assert library.scores["corr2"] == pytest.approx(pearson, rel=SAME_RTOL)
    error_mm = 1e3 * np.sqrt(np.mean((library.predicted - library.actual) ** 2))
    assert library.scores["rmse_mm"] == pytest.approx(error_mm, rel=SAME_RTOL)
    assert command["scores"]["rmse_mm"] == pytest.approx(error_mm, rel=SAME_RTOL)
    # one note a prediction: the text zips them with the rows strictly, cut at --limit alike
    assert len(library.notes) == len(library.rows)
    assert main(["predict", str(model), str(dataset_file), "--limit", "3"]) == 0
    assert capsys.readouterr().out.count("  sample ") == 3


def test_predict_dataset_names_a_missing_input_column(dataset_file):
    saved = SavedModel(network=None, target="position", inputs=["gauge1_v", "gauge9_v"])
    with pytest.raises(DataFileError, match="d.parquet: the model needs column 'gauge9_v'"):
        predict_dataset(saved, load_dataset(dataset_file), source=str(dataset_file))

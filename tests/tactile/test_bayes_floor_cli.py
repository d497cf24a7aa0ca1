"""``flexdigit train --bayes-limit`` compares the network with the limit of its own split (trial 2, item 10): the
span limit on held-out positions (the default), the settings limit on the thesis's shuffle of readings; each
figure named by its prior. The readings are a closed-form cantilever's (:class:`~cantilever.CantileverRig`), the
limits the thesis twin's: what is checked is which limit each ratio divides by, not the ratio's size."""

from __future__ import annotations

import json

import pytest

from cantilever import SMALL_PROTOCOL
from flexdigit.cli import main
from flexdigit.tactile.runner import collect


@pytest.fixture
def dataset_file(tmp_path, make_rig):
    path = tmp_path / "d.parquet"
    collect(SMALL_PROTOCOL, make_rig(seed=0), path)
    return path


def _train(dataset_file, tmp_path, capsys, *flags) -> dict:
    model = tmp_path / f"m{len(flags)}.json"
    argv = ["train", str(dataset_file), "--hidden", "6", "--tol", "1e-7", "--model", str(model), "--json"]
    assert main([*argv, "--bayes-limit", *flags]) == 0
    out = json.loads(capsys.readouterr().out)
    assert json.loads(model.read_text())["meta"]["split"] == out["split"]
    return out


def test_default_is_held_out_positions_against_the_span_limit(dataset_file, tmp_path, capsys):
    out = _train(dataset_file, tmp_path, capsys)
    assert (out["split"], out["bayes_limit_prior"]) == ("positions", "span")
    assert out["bayes_limit_mm"] == out["bayes_limit_span_mm"]
    assert out["bayes_limit_settings_mm"] is None  # on held-out positions it would be told the test positions
    assert out["rmse_over_bayes_limit"] == pytest.approx(out["rmse_mm"] / out["bayes_limit_mm"], rel=1e-12)
    # the limit's own estimator on the same test readings, and the note when it does not reach the limit
    assert out["rmse_over_bayes_estimator"] == pytest.approx(out["rmse_mm"] / out["bayes_estimator_rmse_mm"], rel=1e-12)
    assert out["bayes_limit_reached"] == ("the limit's own estimator" not in out.get("bayes_limit_note", ""))
    # issue 24's ratio: over the span limit with the run's drift counted, named in the output
    assert out["compared_limit"] == "bayes_limit_with_drift_mm"
    drift_mm = out["bayes_limit_with_drift_mm"]
    assert out["rmse_over_compared_limit"] == pytest.approx(out["rmse_mm"] / drift_mm, rel=1e-12)


def test_thesis_split_is_compared_with_the_settings_limit(dataset_file, tmp_path, capsys):
    out = _train(dataset_file, tmp_path, capsys, "--split", "readings")
    assert (out["split"], out["bayes_limit_prior"]) == ("readings", "settings")
    assert out["bayes_limit_settings_mm"] <= out["bayes_limit_span_mm"]  # it knows the positions themselves
    assert out["rmse_over_bayes_limit"] == pytest.approx(out["rmse_mm"] / out["bayes_limit_settings_mm"], rel=1e-12)
    assert "bayes_estimator_rmse_mm" not in out  # the span estimator is no floor's estimator on this split
    assert out["compared_limit"] == "bayes_limit_settings_mm"  # a readings split's test settings are trained on
    assert "bayes_estimator_with_drift_rmse_mm" not in out


def test_split_positions_needs_a_position_target(dataset_file, capsys):
    assert main(["train", str(dataset_file), "--target", "magnitude", "--split", "positions"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--split positions holds out load positions: it needs --target position, not magnitude" in err
    assert "\n" not in err

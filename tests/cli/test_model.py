"""``flexdigit model``: the printed plant's figures through the CLI, JSON and one-line errors."""

import json

import pytest

from flexdigit.cli import main
from flexdigit.reference import thesis_value

PRINTED_4_DIGITS_RTOL = 1e-3  # 48.7 and 86.2, printed to 3 significant digits (within 0.03 %, 3.5)


def test_model_json_printed(capsys):
    assert main(["model", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    plant = data["plant"]
    assert plant["num"][0] == pytest.approx(thesis_value("plant.g_num")[0], rel=PRINTED_4_DIGITS_RTOL)  # 48.7 (3.5)
    assert plant["controllability_rank"] == 4
    assert plant["minimum_phase"] is True
    assert data["closed_loop"]["num"][-1] == pytest.approx(
        thesis_value("plant.closed_loop_num")[0], rel=PRINTED_4_DIGITS_RTOL
    )


def test_model_text_consistent_with_explanations(capsys):
    assert main(["model", "--variant", "consistent", "--output", "tip_rotation_rad", "--explain"]) == 0
    out = capsys.readouterr().out
    assert "[rad]" in out
    assert "1. Digit factor" in out


def test_model_bad_output_is_one_line_error(capsys):
    assert main(["model", "--output", "tip_rotation_rad"]) == 2
    err = capsys.readouterr().err
    assert "output" in err
    assert "Traceback" not in err

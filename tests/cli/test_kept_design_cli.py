"""``flexdigit design 20ms --params D.toml --out ctrl.json`` then ``flexdigit run --params D.toml --controller
ctrl.json``: the run does not search the digit's weights again (issue 24), holds the step as the
searched design does, and refuses in one line a design of another digit or period."""

from __future__ import annotations

import json

import pytest

from digits import write_digit
from flexdigit.cli import main

# issue 24's figures for the 30 deg step (true rotation, on the twin), as tests/cli/test_digit_control.py
SETTLING_S = 1.0
OVERSHOOT_PERCENT = 10.0
FINAL_FRACTION = 0.02
#: the kept and the searched run on the same twin seed: the same weights to a rounding (same candidate), so the
#: same integer commands; a flipped rounding of one command would move the held rotation by ~1.7 deg, not 0.05
SAME_RUN_DEG = 0.05


def _cli(argv, capsys) -> tuple[int, dict]:
    code = main([*argv, "--json"])
    return code, json.loads(capsys.readouterr().out)


def test_a_kept_design_runs_without_the_search(tmp_path, capsys, monkeypatch):
    digit = write_digit("two-sections", tmp_path)
    ctrl = tmp_path / "ctrl.json"
    code, design = _cli(["design", "20ms", "--params", str(digit), "--out", str(ctrl)], capsys)
    assert code == 0
    assert design["out"] == str(ctrl)
    assert design["search"]["meets"]
    kept = json.loads(ctrl.read_text())
    assert kept["weights"] == design["weights"]
    assert kept["params_file"] == str(digit)
    run = ["run", "--params", str(digit), "--setpoint-deg", "30", "--duration", "2.5", "--seed", "1"]
    code, searched = _cli(run, capsys)
    assert code == 0
    assert searched["controller_file"] is None

    from flexdigit.control import design20ms

    def no_search(*args, **kwargs):
        raise AssertionError("the weights were searched again")

    monkeypatch.setattr(design20ms, "digit_weights", no_search)
    code, held = _cli([*run, "--controller", str(ctrl)], capsys)
    assert code == 0, held
    assert held["controller"] == "digital20"
    assert held["controller_file"] == str(ctrl)
    true = held["step_metrics"]["true"]
    assert true["settling_time_s"] < SETTLING_S
    assert true["overshoot_percent"] < OVERSHOOT_PERCENT
    assert abs(held["true_final_rotation_deg"] - 30.0) < FINAL_FRACTION * 30.0
    assert held["true_final_rotation_deg"] == pytest.approx(searched["true_final_rotation_deg"], abs=SAME_RUN_DEG)
    # never overwritten without --force, refused before the search
    monkeypatch.setattr(design20ms, "digit_design_20ms_summary", no_search)
    assert main(["design", "20ms", "--params", str(digit), "--out", str(ctrl)]) != 0
    err = capsys.readouterr().err.strip()
    assert "exists" in err
    assert "\n" not in err


def test_a_design_of_another_digit_is_refused_before_the_rig_moves(tmp_path, capsys, work_must_not_start):
    from flexdigit.rig import base

    digit = write_digit("two-sections", tmp_path)
    thesis = tmp_path / "thesis.json"
    assert main(["design", "20ms", "--out", str(thesis)]) == 0  # the thesis rig's (chapter 5, no search)
    capsys.readouterr()
    work_must_not_start(base, "open_rig")
    assert main(["run", "--params", str(digit), "--controller", str(thesis)]) == 2
    err = capsys.readouterr().err.strip()
    assert f"{thesis}: a design for another digit" in err
    assert "\n" not in err
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "flexdigit-20ms-design-1"}')
    assert main(["run", "--controller", str(broken)]) != 0
    err = capsys.readouterr().err.strip()
    assert str(broken) in err
    assert "no 'calibration_fingerprint'" in err
    assert "\n" not in err
    assert main(["run", "--controller", "nothing"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--controller must be one of digital20" in err
    assert "kept design FILE.json" in err


def test_a_design_for_another_period_is_refused_before_the_loop(tmp_path, capsys):
    thesis = tmp_path / "thesis.json"
    assert main(["design", "20ms", "--out", str(thesis)]) == 0
    capsys.readouterr()
    assert main(["run", "--controller", str(thesis), "--period", "0.01", "--duration", "0.5"]) != 0
    err = capsys.readouterr().err.strip()
    assert "designed for a 20 ms period, this run's is 10 ms" in err
    assert "\n" not in err
    code, run = _cli(["run", "--controller", str(thesis), "--duration", "1"], capsys)  # its own period: runs
    assert code == 0
    assert run["controller_file"] == str(thesis)

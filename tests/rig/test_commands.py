"""``flexdigit run`` end to end on the twin (virtual time)."""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main
from flexdigit.rig.loop import read_log

pytestmark = pytest.mark.slow


def test_run_digital20_json_with_log_and_saved_calibration(tmp_path, capsys):
    cal, log = tmp_path / "cal.json", tmp_path / "run.jsonl"
    argv = ["run", "--json", "--duration", "2", "--setpoint-deg", "20", "--calibration", str(cal), "--log", str(log)]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["status"] == "completed" and data["samples"] == 100 and data["overruns"] == 0
    assert abs(data["estimated_final_rotation_deg"] - 20) < 1.0  # measured rotation within about half a quantum
    # the sim backend also reports the twin's own rotation: within one quantum (1.7 deg) of the estimate at the end
    # and at the peak (the ill-posed least-squares map once read 41.5 deg at a true 31 deg)
    assert abs(data["true_final_rotation_deg"] - 20) < 1.0
    assert abs(data["true_peak_rotation_deg"] - data["estimated_peak_rotation_deg"]) < 1.7
    assert cal.exists() and read_log(log)[2]["stop"] == "completed"
    # second run reuses the saved map (no calibration sweep) and gives the same numbers: deterministic
    argv[-1] = str(tmp_path / "again.jsonl")
    assert main(argv) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["estimated_final_rotation_deg"] == data["estimated_final_rotation_deg"]
    assert again["true_peak_rotation_deg"] == data["true_peak_rotation_deg"]
    # a backend without a twin has only the estimate: the true rotation is null, not a copy of the estimate
    assert main(["run", "--json", "--backend", f"replay://{log}", "--calibration", str(cal), "--duration", "1"]) == 0
    replayed = json.loads(capsys.readouterr().out)
    assert replayed["true_peak_rotation_deg"] is None and replayed["true_final_rotation_deg"] is None
    assert replayed["estimated_peak_rotation_deg"] > 15  # the recorded gauges did move


def test_run_errors_are_one_line(capsys, tmp_path):
    assert main(["run", "--controller", "pid"]) == 2
    assert "--controller must be one of" in capsys.readouterr().err
    bad = tmp_path / "cal.json"
    bad.write_text("{}")
    assert main(["run", "--calibration", str(bad)]) == 2
    assert "not a rotation calibration" in capsys.readouterr().err


def test_replay_needs_a_saved_calibration(tmp_path, capsys):
    log = tmp_path / "rec.jsonl"
    log.write_text('{"format": "flexdigit-loop-log/1"}\n{"k": 0, "t": 0.0, "gauges_v": [0, 0, 0], "command": 8}\n')
    assert main(["run", "--backend", f"replay://{log}"]) == 2
    assert "--calibration" in capsys.readouterr().err

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
    assert abs(data["final_rotation_deg"] - 20) < 1.0  # measured rotation within about half a quantum
    assert cal.exists() and read_log(log)[2]["stop"] == "completed"
    # second run reuses the saved map (no calibration sweep) and gives the same numbers: deterministic
    assert main(argv) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["final_rotation_deg"] == data["final_rotation_deg"]


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

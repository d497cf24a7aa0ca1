"""Issue 16's reproductions not covered beside their domain's other tests: each gives a one-line error now.

(The others: tests/rig/test_urls.py, test_logs.py, test_safety.py, test_fault_matrix.py; tests/tactile/
test_resume.py, test_dataset_checks.py, test_train_outputs.py; tests/test_outputs.py, tests/cli/test_main.py.)
"""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main
from flexdigit.twin.twin import Twin

BINARY = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe"


def _error(capsys) -> dict:
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err
    assert captured.err.count("\n") == 1
    return json.loads(captured.out)


@pytest.mark.parametrize(
    "argv, culprit",
    [
        (["collect", "thesis-6.1", "--out", "{tmp}/d.parquet", "--settle", "1e9"], "'--settle' parameter"),
        (["run", "--period", "1e-7"], "'--period' parameter of flexdigit run must be a real number inside [0.0001, 1]"),
        (["run", "--period", "0"], "Got 0.0 s instead"),  # 0 is a value (refused), not "not given"
        (["run", "--duration", "1e9"], "'--duration' parameter"),
    ],
)
def test_hangs_are_bounded(argv, culprit, tmp_path, capsys, work_must_not_start):
    """`collect --settle 1e9` and `run --period 1e-7` hung; both are refused before the twin takes a step."""
    work_must_not_start(Twin, "advance")
    assert main([a.replace("{tmp}", str(tmp_path)) for a in argv] + ["--json"]) == 2
    error = _error(capsys)["error"]
    assert culprit in error
    assert "the work started" not in error
    assert list(tmp_path.iterdir()) == []


def test_two_gauge_positions_are_checked_whole_then_simulate(tmp_path, capsys):
    """They passed `params` and failed later with a numpy broadcast message. A description is now checked whole
    (issue 24: one ADC channel per gauge, named), and a consistent two-gauge digit simulates on the calibration
    derived for it, one column per gauge."""
    import pyarrow.parquet as pq

    rig = tmp_path / "rig.toml"
    rig.write_text("[geometry]\ngauge_positions_m = [0.045, 0.135]\n")
    assert main(["params", str(rig)]) == 2
    assert "adc_channels has 3 channels for 2 gauges" in capsys.readouterr().err
    rig.write_text("[geometry]\ngauge_positions_m = [0.045, 0.135]\n[sensors]\nadc_channels = [0, 1]\n")
    assert main(["params", str(rig)]) == 0
    capsys.readouterr()
    out = tmp_path / "s.parquet"
    assert main(["simulate", "sweep", "--commands", "8,9", "--params", str(rig), "--out", str(out)]) == 0
    names = pq.read_schema(out).names
    assert "gauge2_v" in names
    assert "gauge3_v" not in names


@pytest.mark.parametrize(
    "argv",
    [
        ["params", "{bad}"],
        ["collect", "{bad}", "--out", "{tmp}/d.parquet"],
        ["simulate", "release", "--calibration", "{bad}", "--out", "{tmp}/r.parquet"],
        ["simulate", "release", "--params", "{bad}", "--out", "{tmp}/r.parquet"],
        ["run", "--backend", "replay://{bad}"],
        ["train", "{bad}"],
        ["predict", "{bad}", "{bad}"],
        ["palpate", "--tissue", "{bad}"],
        ["palpate", "--tissue", "soft-block", "--protocol", "{bad}"],
        ["study", "sensitivity", "{bad}", "--out", "{tmp}/study"],
    ],
    ids=[
        "params",
        "protocol",
        "calibration",
        "params-of-simulate",
        "replay-log",
        "dataset",
        "model",
        "tissue",
        "palpation-protocol",
        "study-spec",
    ],
)
def test_binary_garbage_names_the_file(argv, tmp_path, capsys):
    """Binary garbage said "'utf-8' codec can't decode ..." with no file name."""
    bad = tmp_path / "garbage.toml"
    bad.write_bytes(BINARY)
    assert main([a.replace("{bad}", str(bad)).replace("{tmp}", str(tmp_path)) for a in argv] + ["--json"]) == 2
    doc = _error(capsys)
    assert str(bad) in doc["error"], doc
    assert doc["error_type"] == "DataFileError", doc
    assert "codec" not in doc["error"]

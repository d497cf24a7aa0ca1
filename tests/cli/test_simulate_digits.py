"""``flexdigit simulate release|sweep|load --params FILE`` on every test digit (issue 24): exit 0, one gauge column
per gauge of the digit, the twin calibrated by :func:`flexdigit.twin.digit_calibration.calibration_for`."""

from __future__ import annotations

import json

import pytest

from digits import DIGITS, write_digit
from flexdigit.cli import main
from flexdigit.params import load_params

EXPERIMENTS = {
    "release": ["--duration", "3"],
    "sweep": ["--commands", "8,20,30", "--samples", "2", "--settle", "1"],
    "step": ["--duration", "0.5", "--cable"],
    "load": ["--loads-g", "10", "--positions-cm", "0,5", "--repetitions", "2"],
}


@pytest.mark.parametrize("experiment", list(EXPERIMENTS))
@pytest.mark.parametrize("name", [n for n in DIGITS if n != "thesis"])
def test_simulate_runs_on_the_digit(name, experiment, tmp_path, capsys):
    path = write_digit(name, tmp_path)
    gauges = len(load_params(path).geometry.gauge_positions_m)
    out = tmp_path / f"{experiment}.csv"
    extra = list(EXPERIMENTS[experiment])
    argv = ["simulate", experiment, "--params", str(path), "--out", str(out), "--json", *extra]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    columns = data["columns"]
    assert out.exists()
    assert [c for c in columns if c.startswith("gauge")] == [f"gauge{i + 1}_v" for i in range(gauges)]
    if experiment == "release":  # the digit rings: every identified gauge gives one wn (the median's)
        assert 1.0 < data["findings"]["wn_rad_s"] < 100.0


def test_a_digit_that_buckles_tip_up_is_refused_in_one_line_when_asked_tip_up(tmp_path, capsys):
    """0.5 m with five 8 g supports: P_cr = pi^2 EI / 4 L^2 ~ 0.16 N against ~0.4 N of supports (docs/digits.md).
    Without --orientation it hangs (tests/cli/test_simulate_mount.py); asked tip up, it is refused."""
    path = write_digit("five-sections-eight-gauges", tmp_path)
    argv = ["simulate", "release", "--params", str(path), "--out", str(tmp_path / "r.csv"), "--orientation", "vertical"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "buckles" in err[0]
    assert "hanging" in err[0]
    assert not (tmp_path / "r.csv").exists()

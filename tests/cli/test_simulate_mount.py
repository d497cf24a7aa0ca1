"""One mount for every command (issue 24's trial): a digit that buckles tip up is hung, as ``run`` and ``collect``
hang it (:func:`flexdigit.control.design20ms.digit_mount`), and the output says so; and a release record long
enough for the digit's first mode by default.

References: five_unequal_bronze_full (0.5 m, five bronze sections, tests/data/handmade_digits) keeps a negative
share of its stiffness tip up (``digit_mount`` -> "hanging"); seven_sections_pair_mixed's bare first mode is
2.39 rad/s (the twin's linear modal analysis), a 2.6 s period: the thesis's 8 s hold three.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from flexdigit.cli import main
from flexdigit.cli.simulate import RELEASE_CYCLES, release_duration_s
from flexdigit.control.design20ms import digit_mount
from flexdigit.params import load_params
from flexdigit.twin.digit_calibration import calibration_for

HANDMADE = Path(__file__).resolve().parent.parent / "data" / "handmade_digits"
BUCKLING = HANDMADE / "five_unequal_bronze_full.toml"
SLOW = HANDMADE / "seven_sections_pair_mixed.toml"
HUNG = "mount: hanging (tip down)"


def test_the_reference_digit_buckles_tip_up():
    params = load_params(BUCKLING)
    assert digit_mount(params, calibration_for(params)) == "hanging"


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", "release", "--out", "{tmp}/r.csv"],
        ["simulate", "sweep", "--commands", "8,20,30", "--samples", "2", "--settle", "1", "--out", "{tmp}/s.csv"],
        ["simulate", "step", "--duration", "0.5", "--out", "{tmp}/p.csv"],
        ["design", "hinf", "--filter-hz", "3"],
        ["design", "20ms"],
    ],
    ids=["release", "sweep", "step", "hinf", "20ms"],
)
def test_every_command_hangs_a_digit_that_buckles_tip_up_and_says_so(argv, tmp_path, capsys):
    argv = [a.format(tmp=tmp_path) for a in argv] + ["--params", str(BUCKLING)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert HUNG in out
    if argv[0] == "simulate":
        assert main([*argv, "--force", "--json"]) == 0
        data = json.loads(capsys.readouterr().out)
        record = Path(data["out"]).read_text().splitlines()[1]
        assert '"orientation": "hanging"' in record


def test_calibrate_fits_the_hung_records_hung(tmp_path, capsys):
    out = tmp_path / "r.csv"
    assert main(["simulate", "release", "--params", str(BUCKLING), "--out", str(out), "--seed", "2"]) == 0
    capsys.readouterr()
    argv = ["calibrate", "--params", str(BUCKLING), "--release-housed", str(out), "--out", str(tmp_path / "c.toml")]
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["orientation"] == "hanging"
    assert abs(data["worst"]["times_scale"]) < 0.01  # wn and zeta met: hung, as recorded


def test_a_slow_digit_gets_a_release_long_enough_by_default(tmp_path, capsys):
    params = load_params(SLOW)
    duration = release_duration_s(params, calibration_for(params), housing=False, orientation="vertical")
    assert duration >= RELEASE_CYCLES * 2 * 3.14159 / 2.40  # 12 periods of 2.39 rad/s: 31.5 s
    out = tmp_path / "b.csv"
    assert main(["simulate", "release", "--no-housing", "--params", str(SLOW), "--out", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["findings"]["wn_rad_s"] == pytest.approx(2.39, rel=0.01)  # the modal analysis's, within 1 %


def test_a_release_too_short_names_duration_not_force(tmp_path, capsys):
    argv = ["simulate", "release", "--no-housing", "--params", str(SLOW), "--out", str(tmp_path / "b.csv")]
    assert main([*argv, "--duration", "8", "--force"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "--duration" in err[0]
    assert "--force" not in err[0]
    assert not (tmp_path / "b.csv").exists()

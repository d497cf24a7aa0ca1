"""A digit of unequal sections from the command line (issue 24): ``params`` prints its layout, ``simulate release``
and ``simulate sweep`` write its records, ``calibrate`` fits its twin to them (exit 0 each, no Python written by a
user). Design, run, collect, train, predict, shape and palpate go through the parametrised test-digit tests
(``DIGITS["unequal-sections"]``)."""

from __future__ import annotations

import json

import pytest

from digits import write_digit
from flexdigit.cli import main
from flexdigit.params import load_params

# calibrate on the twin's own noisy records: its fit meets each release/sweep target to this (the fitted twin
# reproduces the records it was simulated from; 1e-6 measured on seed 0, the noise is in both sides)
FIT_RTOL = 1e-3
# the layout the file implies: 60, 100, 80 mm of strip with 10, 12, 10 mm supports (m)
STARTS_M, ENDS_M = [0.005, 0.075, 0.187], [0.065, 0.175, 0.267]


def _json(argv, capsys) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_params_prints_where_each_unequal_section_lies(tmp_path, capsys):
    path = write_digit("unequal-sections", tmp_path)
    assert main(["params", str(path)]) == 0
    out = capsys.readouterr().out
    assert "section_length_m = [0.06, 0.1, 0.08]" in out
    assert "section_starts_m = [0.005, 0.075, 0.187]" in out
    assert "support_centres_m = [0.07, 0.181, 0.272]" in out
    derived = _json(["params", str(path)], capsys)["derived"]
    assert derived["section_starts_m"] == pytest.approx(STARTS_M, abs=1e-12)
    assert derived["section_ends_m"] == pytest.approx(ENDS_M, abs=1e-12)


def test_the_template_says_a_list_is_allowed(tmp_path):
    path = tmp_path / "t.toml"
    assert main(["params", "--template", str(path)]) == 0
    text = path.read_text()
    assert "a list of section_count lengths from the base" in text
    assert "section_length_m = 0.08" in text  # the thesis rig's one value, as ever


def test_simulate_then_calibrate_the_unequal_digit(tmp_path, capsys):
    path = write_digit("unequal-sections", tmp_path)
    p = ["--params", str(path)]
    release, sweep, out = tmp_path / "release.parquet", tmp_path / "sweep.parquet", tmp_path / "cal.toml"
    findings = _json(["simulate", "release", *p, "--out", str(release)], capsys)["findings"]
    assert 1.0 < findings["wn_rad_s"] < 100.0
    _json(["simulate", "sweep", *p, "--out", str(sweep)], capsys)
    fit = _json(["calibrate", *p, "--release-housed", str(release), "--sweep", str(sweep), "--out", str(out)], capsys)
    assert fit["success"]
    for row in fit["residuals"]:
        assert abs(row["relative"]) < FIT_RTOL, row
    assert out.exists()
    assert load_params(path).geometry.section_lengths_m == pytest.approx((0.06, 0.10, 0.08), abs=1e-12)


def test_params_write_keeps_the_lengths(tmp_path, capsys):
    path, written = write_digit("unequal-sections", tmp_path), tmp_path / "written.toml"
    assert main(["params", str(path), "--write", str(written)]) == 0
    assert load_params(written) == load_params(path)
    assert "section_length_m = [" in written.read_text()

"""`flexdigit palpate --params D` on the trial's cable pairs and fine-step digit, and a hold that never touches
(issue 24's trial, /work/coord/trial_report.md: pairs ran away at -124..-131 deg, the 0.31 deg servo's modulus was
"not determined", a hold that never touched the tissue reported "completed").

References: the twin's tissue (soft-block: 1000 N/m^2, 30 mm away); the fit's own standard deviation (an unbiased fit
lands within ``SIGMAS`` of it); ``REL_SD``: a sweep that presses the tissue measures it to a few per cent.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from digits import write_digit
from flexdigit.cli import main

HANDMADE = Path(__file__).parents[1] / "data" / "handmade_digits"
SIGMAS = 4.0
REL_SD = 0.05


def _sweep(name: str, capsys, *extra: str) -> dict:
    argv = ["palpate", "--params", str(HANDMADE / f"{name}.toml"), "--tissue", "soft-block", "--json", *extra]
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(
    ("name", "last"),
    [("design_front_10_small_pair", 149), ("design_front_30_six_gauges_pair", 250)],  # 22 x 1.735 / 0.31 = 123
)
def test_a_pair_sweeps_from_its_straight_command_and_measures_the_tissue(name, last, capsys):
    data = _sweep(name, capsys)
    assert data["protocol"]["commands"][0] == 127
    assert data["protocol"]["commands"][-1] == last
    r = data["result"]
    assert r["modulus_sd_n_m2"] < REL_SD * 1000.0
    assert abs(r["modulus_n_m2"] - 1000.0) < SIGMAS * r["modulus_sd_n_m2"], r


def test_a_geared_digits_builtin_sweep_reaches_the_tissue(tmp_path, capsys):
    """4:1 gearing: the built-in sweep 8..30 runs 8..96 (it did not reach soft-block: "modulus not determined")."""
    params = write_digit("six-gauges-geared", tmp_path)
    argv = ["palpate", "--params", str(params), "--tissue", "soft-block", "--json"]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["protocol"]["commands"] == list(range(8, 97, 4))
    r = data["result"]
    assert r["modulus_sd_n_m2"] < REL_SD * 1000.0
    assert abs(r["modulus_n_m2"] - 1000.0) < SIGMAS * r["modulus_sd_n_m2"], r


def test_thesis_commands_given_for_a_pair_are_refused_in_one_line(tmp_path, capsys):
    protocol = tmp_path / "mine.toml"
    protocol.write_text("[sweep]\ncommands = { from = 8, to = 30, step = 2 }\ntare_command = 8\n")
    argv = ["palpate", "--params", str(HANDMADE / "short_pair_quarter.toml"), "--tissue", "soft-block"]
    assert main([*argv, "--protocol", str(protocol)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert str(protocol) in err
    assert "straight command is 127" in err


def test_a_single_cable_refuses_tissue_on_its_other_side(tmp_path, capsys):
    tissue = tmp_path / "other.toml"
    tissue.write_text(
        '[tissue]\nside = "opposite"\nstart_mm = 150.0\nend_mm = 350.0\ngap_mm = 30.0\nmodulus_n_m2 = 1000.0\n'
    )
    assert main(["palpate", "--tissue", str(tissue)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "'tissue.side'" in err
    assert "single cable" in err


def test_a_hold_that_never_touches_fails_in_one_line(tmp_path, capsys):
    """The thesis rig against a block 200 mm away: 3 s of approach reach command ~20, far short of it."""
    tissue = tmp_path / "far.toml"
    tissue.write_text("[tissue]\nstart_mm = 150.0\nend_mm = 350.0\ngap_mm = 200.0\nmodulus_n_m2 = 1000.0\n")
    protocol = tmp_path / "hold.toml"
    protocol.write_text("[force]\nsetpoint_n = 0.1\nduration_s = 3.0\n")
    out = tmp_path / "hold.json"
    assert main(["palpate", "--tissue", str(tissue), "--protocol", str(protocol), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "never reached 0.1 N" in err
    assert "digit relaxed to command 8" in err
    assert not out.exists()


@pytest.mark.parametrize("protocol", ["hold", "sweep"])
def test_palpate_refuses_tissue_past_the_tip_in_one_line(protocol, tmp_path, capsys):
    # a tissue file from 150 mm, the 0.15 m pair's tip: the contact estimator's region was empty (a ParameterError
    # about 'region_m' of ContactEstimator); the sweep fitted "30 +- inf". (The built-in soft-block, also from
    # 150 mm, is now laid out beside the digit: tests/palpation/test_sweep_any_digit.py.)
    tissue = tmp_path / "far.toml"
    tissue.write_text("[tissue]\nstart_mm = 150.0\nend_mm = 350.0\ngap_mm = 30.0\nmodulus_n_m2 = 1000.0\n")
    argv = ["palpate", "--params", str(HANDMADE / "short_pair_quarter.toml"), "--tissue", str(tissue)]
    assert main([*argv, "--protocol", protocol]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"{tissue}: key 'tissue.start_mm'" in err
    assert "starts at 150 mm" in err


@pytest.mark.slow
def test_a_digit_that_buckles_tip_up_is_palpated_hanging_without_warnings(capsys, recwarn):
    """five_unequal_bronze_full tip up: 69 ConvergenceWarnings and still running at 6 min; hung as `run` hangs it."""
    data = _sweep("five_unequal_bronze_full", capsys)
    assert data["rig"]["orientation"] == "hanging"
    assert not [w for w in recwarn if "Convergence" in type(w.message).__name__], [str(w.message) for w in recwarn]
    r = data["result"]
    assert abs(r["modulus_n_m2"] - 1000.0) < SIGMAS * r["modulus_sd_n_m2"], r


@pytest.mark.slow
def test_a_long_lightly_damped_section_settles_and_measures(capsys):
    """The 0.49 m one-section digit rang through 2.5 s plateaus: chi2/dof 948; now 10.8 s (+5.4 s to close)."""
    data = _sweep("one_long_section_full", capsys)
    assert data["protocol"]["settle_s"] == pytest.approx(10.8)
    r = data["result"]
    assert r["chi2_per_dof"] < 4.0
    assert abs(r["modulus_n_m2"] - 1000.0) < SIGMAS * r["modulus_sd_n_m2"], r

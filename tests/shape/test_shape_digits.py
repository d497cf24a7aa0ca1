"""The shape estimator and ``shape --accuracy`` on the hand-made digits of the trial (issue 24).

The trial (tests/data/handmade_digits) found: on every cable pair ``shape --accuracy`` scored commands 8..43, far
from a pair's straight command 127, and the estimator's cable could only pull one way (median tip error 168-465
mm); a digit that buckles tip up was still scored upright (the twin's ConvergenceWarning, 278 mm); a geared digit
at its straight command cycled between a slack and a taut cable ("lever arms not settled").

Reference: the twin's static solution (:func:`flexdigit.twin.static_gauges_v`, a discrete elastica within 0.1 %
of ``solve_bvp``'s, tests/digit_campaign.py) gives the readings and the true centre line; the estimator sees only
the readings and the command. Tolerance: ``TIP_M``, the tip within 2 mm (the bare pair's worst of 15 commands:
0.85 mm; the taut cables' guide friction moves each gauge by about one white-noise standard deviation).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.params import RigParams, load_params
from flexdigit.shape.shape import (
    ACCURACY_POSITIONS_M,
    DigitBeam,
    ShapeEstimator,
    accuracy_commands,
    accuracy_positions_m,
    shape_accuracy,
    true_centre_line_m,
)
from flexdigit.twin import static_gauges_v
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, cached_digit

HANDMADE = Path(__file__).parents[1] / "data" / "handmade_digits"
TIP_M = 2e-3


def _digit(name: str):
    return load_params(HANDMADE / f"{name}.toml")


def _tip_errors(params, orientation, commands, seed):
    """The estimator's tip error (m) and tip angle (rad) against the twin's, bare, one noisy reading a command."""
    cal = twin_calibration(params)
    zeros = np.zeros(len(commands))
    volts, sol = static_gauges_v(
        zeros, zeros, commands, params=params, calibration=cal, orientation=orientation, seed=seed,
        return_solution=True,
    )  # fmt: skip
    est = ShapeEstimator(params, cal, orientation=orientation).estimate(volts, command=commands)
    chain = cached_digit(params, cal, True, orientation, DEFAULT_CELLS_PER_SECTION)
    truth = true_centre_line_m(sol.psi_rad, chain, est.s_m)
    return np.linalg.norm(est.tip_m - truth[:, -1], axis=1), est, sol


def test_accuracy_commands_come_from_the_digit():
    # the thesis rig: 8..43 every 5, what `shape --accuracy` always scored (its operating range, 3.4.1)
    assert accuracy_commands(RigParams()) == tuple(range(8, 44, 5))
    assert accuracy_positions_m(RigParams()) == ACCURACY_POSITIONS_M
    # a pair described without a range: straight 127, 35 commands either way (params' derived 92..162)
    pair = _digit("short_pair_quarter")
    commands = accuracy_commands(pair)
    assert (commands[0], commands[-1], len(commands)) == (92, 162, 15)
    assert commands[7] == 127
    # the exported design 30: its own range 30..224 around 127
    front = accuracy_commands(_digit("design_front_30_six_gauges_pair"))
    assert (front[0], front[-1]) == (30, 224)
    assert 127 in front
    # load places: 27 along the digit, the last at its tip
    positions = accuracy_positions_m(pair)
    assert len(positions) == 27
    assert positions[-1] == pytest.approx(pair.geometry.digit_length_m, abs=1e-4)


@pytest.mark.filterwarnings("error")
def test_a_cable_pair_is_estimated_bent_both_ways():
    pair = _digit("short_pair_quarter")
    commands = [92, 110, 127, 145, 162]
    tip_error, est, sol = _tip_errors(pair, "horizontal", commands, seed=3)
    assert np.all(tip_error < TIP_M), tip_error
    true_angle = sol.psi_rad[:, -1]
    assert true_angle[0] < -0.3  # the twin bends it 20-30 deg both ways
    assert true_angle[-1] > 0.3
    np.testing.assert_allclose(est.angle_rad[:, -1], true_angle, atol=0.01)  # the tip equation's own 0.01 rad
    # the net tension T1 - T2 takes the bend's sign (the old estimator's cable could only pull: T >= 0)
    assert est.tension_n[0] < 0 < est.tension_n[-1]
    assert np.all(est.consistent)


@pytest.mark.filterwarnings("error")
def test_a_digit_that_buckles_tip_up_is_scored_hanging():
    digit = _digit("five_unequal_bronze_full")
    length = digit.geometry.digit_length_m
    acc = shape_accuracy((8, 20), (round(0.8 * length, 3),), seed=0, params=digit)
    assert acc.mount == "hanging"
    assert [g["case"] for g in acc.summary()] == ["bare, hanging", "bare, horizontal", "weight, horizontal"]
    bare = acc.case == "bare, hanging"
    assert np.all(acc.tip_error_m[bare] < TIP_M), acc.tip_error_m[bare]  # was 278 mm, scored tip up


@pytest.mark.filterwarnings("error")
def test_a_geared_digit_settles_at_its_straight_command():
    # seed 0, command 8, tip up: the reading whose cable flipped between slack and taut (T 0 <-> 0.005 N) for
    # all 100 iterations ("lever arms not settled"); the cable's state is now held with the model
    digit = _digit("four_sections_geared_eight")
    tip_error, est, _ = _tip_errors(digit, "vertical", [8], seed=0)
    assert tip_error[0] < TIP_M
    assert bool(est.consistent[0])


def test_the_estimator_defaults_to_the_digits_own_calibration():
    digit = _digit("four_sections_geared_eight")  # 4 sections, 8 gauges: the packaged fit has 3 and 3
    own = twin_calibration(digit)
    est = ShapeEstimator(digit)
    est._setup()
    np.testing.assert_array_equal(est.calibration_.housing_ei_n_m2, own.housing_ei_n_m2)
    np.testing.assert_array_equal(est.calibration_.channel_gain, own.channel_gain)
    # the beam helper too (it raised "'housing_ei_n_m2' ... must have 4 values" with the thesis's fit)
    beam = DigitBeam.from_params(digit)
    np.testing.assert_array_equal(beam.inv_ei, DigitBeam.from_params(digit, own).inv_ei)
    np.testing.assert_array_equal(beam.mass_kg, DigitBeam.from_params(digit, own).mass_kg)


@pytest.mark.filterwarnings("error")
def test_shape_accuracy_command_on_a_pair(capsys):
    code = main(["shape", "--accuracy", "--params", str(HANDMADE / "short_pair_quarter.toml"), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert (out["commands"][0], out["commands"][-1], out["mount"]) == (92, 162, "vertical")
    medians = {g["case"]: g["tip_error_median_mm"] for g in out["groups"]}
    assert max(medians["bare, upright"], medians["bare, horizontal"]) < 1.0  # the trial's: 168 mm
    assert medians["weight, horizontal"] < 2.0


@pytest.mark.filterwarnings("error")
def test_shape_accuracy_command_says_a_buckling_digit_is_hung(capsys):
    code = main(["shape", "--accuracy", "--params", str(HANDMADE / "five_unequal_bronze_full.toml")])
    text = capsys.readouterr().out
    assert code == 0
    assert "the digit buckles tip up: its bare cases are hanging" in text
    assert "bare, upright" not in text
    hanging = next(line for line in text.splitlines() if line.startswith("bare, hanging"))
    assert float(hanging.split()[3]) < 2.0  # its median tip error, mm (the trial's upright worst: 278 mm)


#: Trial 3's rough cable guides: the thesis rig whose guides take a third of the tension (its description's
#: ``guide_friction_ratio = 0.3``).
HIGH_FRICTION = Path(__file__).parents[1] / "data" / "handmade_digits3" / "high_friction_guides.toml"
#: A 2-sd band covers 95 % of a normal error; over 108 cases (4 seeds x 3 commands x 9 places) the binomial sd of
#: that share is 2.1 %: 85 % is ~5 of them below. Measured 97.2 % (43.5 % before the band counted unseen loads).
COVERAGE_MIN = 0.85


@pytest.mark.slow
def test_the_band_covers_the_weights_that_guide_friction_hides():
    """With friction 0.3 a 25 g weight lowers chi-square by ~4 (the friction's scatter at the gauges is as large as
    its moment): no contact is found, and the band held the tension's uncertainty alone (1.3 mm) while the tip
    moved up to 42 mm (``shape --accuracy``: 37 % within 2 sd). The band now counts the load the readings cannot
    exclude, at the worst place: the true tip within 2 sd in at least COVERAGE_MIN of seeded cases."""
    params = load_params(HIGH_FRICTION)
    places = accuracy_positions_m(params)[2::3]
    within = []
    for seed in range(4):
        acc = shape_accuracy(commands=(8, 28, 43), positions_from_base_m=places, seed=seed, params=params)
        rows = acc.case == "weight, horizontal"
        within.append(acc.tip_error_m[rows] <= 2 * acc.tip_sd_m[rows])
    within = np.concatenate(within)
    assert within.size == 4 * 3 * len(places)
    assert np.mean(within) >= COVERAGE_MIN

"""A digit's 20 ms design kept in a file (:mod:`flexdigit.control.kept_design`): the kept weights give the searched
design back, the file round-trips, and a design is refused, in one line naming the file, for another digit,
calibration, mount or period, or when the file is not one."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from digits import DIGITS
from flexdigit.control.design20ms import Weights, design_20ms, digit_design_20ms
from flexdigit.control.kept_design import (
    FORMAT,
    KeptDesign,
    calibration_fingerprint,
    keep_design,
    params_fingerprint,
    read_kept_design,
    write_kept_design,
)
from flexdigit.errors import DataFileError, OutputExistsError, ParameterError
from flexdigit.params import RigParams
from flexdigit.twin.digit_calibration import twin_calibration

#: The same design computed twice in one process from the same weights (to float rounding: the rescaled weights
#: differ from the search's candidate by a rounding or two, the Riccati solvers amplify that by their condition)
SAME_DESIGN_RTOL = 1e-9
DIGIT = RigParams.from_dict(DIGITS["two-sections"])


def _matrices(design):
    c = design.controller
    return [np.asarray(x) for x in (c.A, c.B, c.C, c.D, design.aw_gain)]


def _kept(design, params=DIGIT) -> KeptDesign:
    return KeptDesign(
        params_fingerprint(params), calibration_fingerprint(params), "vertical", 0.02, design.deg_per_command,
        design.weights,
    )  # fmt: skip


@pytest.fixture(scope="module")
def searched():
    return digit_design_20ms(DIGIT)


def test_kept_weights_give_the_searched_design_back(searched):
    assert searched.choice is not None
    assert searched.choice.candidates == 48  # it was searched
    kept = digit_design_20ms(DIGIT, weights=_kept(searched).weights)
    assert kept.choice is None  # not searched
    assert kept.weights == searched.weights
    for a, b in zip(_matrices(kept), _matrices(searched), strict=True):
        np.testing.assert_allclose(a, b, rtol=SAME_DESIGN_RTOL, atol=0)


def test_at_a_measured_rotation_per_command_they_are_the_search_candidates_design(searched):
    # a run designs at the rotation map's measured rotation per command: the kept weights are rescaled as the
    # search rescales its candidates, so where the search picks the same candidate the design is the same
    measured = 0.95 * searched.deg_per_command
    search = digit_design_20ms(DIGIT, deg_per_command=measured)
    kept = digit_design_20ms(DIGIT, deg_per_command=measured, weights=searched.weights)
    assert search.deg_per_command == pytest.approx(measured, rel=1e-12)
    for name in ("q_rate", "r_u", "q_disturbance", "q_input", "r_measurement", "q_shape"):
        assert getattr(kept.weights, name) == pytest.approx(getattr(search.weights, name), rel=1e-12), name
    # the command terms moved with the gain (r_u x 0.95^2): not the unscaled weights
    assert kept.weights.r_u == pytest.approx(searched.weights.r_u * 0.95**2, rel=1e-12)
    for a, b in zip(_matrices(kept), _matrices(search), strict=True):
        np.testing.assert_allclose(a, b, rtol=SAME_DESIGN_RTOL, atol=1e-12 * np.max(np.abs(b)))


def test_the_thesis_rig_keeps_chapter_5s_design():
    k = keep_design()
    assert k.weights == Weights()
    assert k.period_s == 0.02
    assert k.search is None
    assert k.params_fingerprint == params_fingerprint(RigParams())
    for a, b in zip(_matrices(digit_design_20ms(weights=k.weights)), _matrices(design_20ms()), strict=True):
        assert np.array_equal(a, b)  # one code path, the same weights object's values


def test_a_kept_design_round_trips_and_is_never_overwritten(tmp_path, searched):
    kept = dataclasses.replace(_kept(searched), search={"meets": True}, params_file="d.toml")
    path = write_kept_design(kept, tmp_path / "c.json")
    back = read_kept_design(path)
    assert back == kept
    assert back.source == str(path)
    with pytest.raises(OutputExistsError):
        write_kept_design(kept, path)
    write_kept_design(dataclasses.replace(kept, period_s=0.01), path, force=True)
    assert read_kept_design(path).period_s == 0.01


def test_another_digit_calibration_mount_or_period_is_refused_in_one_line(searched):
    kept = dataclasses.replace(_kept(searched), source="c.json")
    kept.check(DIGIT, None, orientation="vertical", period_s=0.02)  # its own: accepted
    kept.check(DIGIT, twin_calibration(DIGIT), orientation="vertical", period_s=0.02)  # the default, given
    longer = DIGIT.replace(geometry=dataclasses.replace(DIGIT.geometry, strip_thickness_m=0.4e-3))
    other_cal = twin_calibration(DIGIT).replace(cable_stiffness_n_m=2 * twin_calibration(DIGIT).cable_stiffness_n_m)
    cases = [
        (longer, None, "vertical", 0.02, "a design for another digit"),
        (RigParams(), None, "vertical", 0.02, "a design for another digit"),
        (DIGIT, other_cal, "vertical", 0.02, "another twin calibration"),
        (DIGIT, None, "hanging", 0.02, "mounted vertical, this run's is hanging"),
        (DIGIT, None, "vertical", 0.01, "a 20 ms period, this run's is 10 ms"),
    ]
    for params, cal, mount, period, expected in cases:
        with pytest.raises(ParameterError) as err:
            kept.check(params, cal, orientation=mount, period_s=period)
        message = str(err.value)
        assert message.startswith("c.json: ")
        assert expected in message
        assert "\n" not in message


def _good() -> dict:
    data = keep_design().to_dict()
    assert data["format"] == FORMAT
    return data


BAD_FILES = {
    "not JSON": ("{", "not JSON"),
    "a list": ("[]", "not a kept design"),
    "another format": (json.dumps({**_good(), "format": "x"}), "format 'x'"),
    "unknown key": (json.dumps({**_good(), "gains": 1}), "unknown key 'gains'"),
    "no weights": (json.dumps({k: v for k, v in _good().items() if k != "weights"}), "no 'weights'"),
    "short fingerprint": (json.dumps({**_good(), "params_fingerprint": "abc"}), "'params_fingerprint' must be"),
    "bad mount": (json.dumps({**_good(), "orientation": "sideways"}), "'orientation' must be one of"),
    "zero period": (json.dumps({**_good(), "period_s": 0}), "'period_s' must be a positive number"),
    "boolean gain": (json.dumps({**_good(), "deg_per_command": True}), "'deg_per_command' must be"),
    "missing weight": (json.dumps({**_good(), "weights": {"q_rate": 1.0}}), "'weights' must be a table of"),
    "string weight": (
        json.dumps({**_good(), "weights": {**_good()["weights"], "r_u": "30"}}),
        "'weights' must be finite numbers",
    ),
    "negative weight": (json.dumps({**_good(), "weights": {**_good()["weights"], "r_u": -1.0}}), "r_u"),
}


@pytest.mark.parametrize("case", list(BAD_FILES))
def test_a_file_that_is_not_a_kept_design_is_refused_naming_it(case, tmp_path):
    text, expected = BAD_FILES[case]
    path = tmp_path / "c.json"
    path.write_text(text)
    with pytest.raises(DataFileError) as err:
        read_kept_design(path)
    message = str(err.value)
    assert message.startswith(f"{path}: ")
    assert expected in message
    assert "\n" not in message

"""A planar digit described in the params TOML (issue 24, part 1): every test digit loads and derives its figures;
every inconsistency is refused in one line naming its key; today's files (``params --write``) keep loading."""

from __future__ import annotations

import math
import tomllib

import pytest

from digits import DIGITS, write_digit
from flexdigit.cli import main
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams, derived_figures, digit_inconsistencies, load_params, params_template

# lengths in a file are decimals; what is derived from them agrees to float rounding (m)
LENGTH_ATOL_M = 1e-12


@pytest.mark.parametrize("name", list(DIGITS))
def test_each_test_digit_loads_and_derives(name, tmp_path):
    params = load_params(write_digit(name, tmp_path))
    d = derived_figures(params)
    g = params.geometry
    # the sections and supports add up to the digit
    supports = d["supports_m"]  # half the first at the clamp, the others whole, the last one's centre at the tip
    assert math.fsum(g.section_lengths_m) + 0.5 * supports[0] + sum(supports[:-1]) + 0.5 * supports[-1] == (
        pytest.approx(g.digit_length_m, abs=LENGTH_ATOL_M)
    )
    # each section's free strip is its length, after its predecessor and one support; the last support ends the tip
    bounds = list(zip(d["section_starts_m"], d["section_ends_m"], strict=True))
    assert [b - a for a, b in bounds] == pytest.approx(list(g.section_lengths_m), abs=LENGTH_ATOL_M)
    assert bounds[0][0] == pytest.approx(0.5 * supports[0], abs=LENGTH_ATOL_M)
    gaps = [a - b for (_, b), (a, _) in zip(bounds[:-1], bounds[1:], strict=True)]
    assert gaps == pytest.approx(supports[:-1], abs=LENGTH_ATOL_M)
    assert d["support_centres_m"][-1] == g.digit_length_m
    assert d["gauge_count"] == len(g.gauge_positions_m) == len(params.sensors.adc_channels)
    # E 3.15 with the gearing: tip degrees per command = servo step / gear ratio x r_M / e
    a = params.actuator
    expected = 219.0 / 254.0 / a.gear_ratio * a.pulley_radius_m / g.cable_eccentricity_m
    assert d["tip_deg_per_command"] == pytest.approx(expected, rel=1e-12)


def test_the_command_prints_what_it_derives(tmp_path, capsys):
    path = write_digit("five-sections-eight-gauges", tmp_path)
    assert main(["params", str(path)]) == 0
    out = capsys.readouterr().out
    assert "support_length_m = 0.01" in out  # (0.5 - 5 x 0.09) / 5
    assert "gauge_count = 8" in out


def test_the_thesis_rig_derives_its_figures():
    d = derived_figures(RigParams())
    assert d["support_length_m"] == pytest.approx(0.010, abs=LENGTH_ATOL_M)  # 2.2.1: 10 mm supports
    assert d["tip_deg_per_command"] == pytest.approx(0.8622 * 11.5 / 5.715, rel=1e-4)  # E 3.15, table 3.7


def test_the_template_is_annotated_and_loads_as_the_thesis_rig(tmp_path):
    path = tmp_path / "digit.toml"
    assert main(["params", "--template", str(path)]) == 0
    text = path.read_text()
    assert "# Number of sections (2.2): 3." in text
    assert "# 1: the thesis's cable" in text
    assert load_params(path) == RigParams()
    assert params_template() == text
    assert main(["params", "--template", str(path)]) == 2  # never clobbered without --force


def test_written_files_keep_loading(tmp_path):
    path = tmp_path / "rig.toml"
    assert main(["params", "--write", str(path)]) == 0
    assert load_params(path) == RigParams()
    data = tomllib.loads(path.read_text())
    del data["cables"]  # a file written before [cables] existed
    assert RigParams.from_dict(data) == RigParams()


BAD = {
    # the 4 x 80 mm digit with digit_length_m left at 0.27
    "lengths do not add up": (
        {"geometry": {"section_count": 4, "strip_length_m": 0.24, "digit_length_m": 0.27}},  # as --write wrote them
        "strip_length_m",
    ),
    "a strip longer than the digit": (
        {"geometry": {"section_count": 4, "strip_length_m": 0.32, "digit_length_m": 0.27}},
        "strip_length_m",
    ),
    "a gauge on a support": ({"geometry": {"gauge_positions_m": [0.045, 0.088, 0.225]}}, "gauge_positions_m[1]"),
    "a gauge past the strip": ({"geometry": {"gauge_positions_m": [0.045, 0.135, 0.268]}}, "gauge_positions_m[2]"),
    "two gauges at one place": ({"geometry": {"gauge_positions_m": [0.045, 0.045, 0.225]}}, "one place"),
    "a cable pair without pretension": ({"cables": {"count": 2}}, "pretension_n"),
    "nine gauges": (
        {
            "geometry": {"gauge_positions_m": [0.02 + 0.03 * k for k in range(9)]},
            "sensors": {"adc_channels": list(range(9))},
        },
        "gauge_positions_m has 9 gauges",
    ),
    "a channel short": ({"geometry": {"gauge_positions_m": [0.045, 0.135, 0.225, 0.25]}}, "adc_channels"),
    "nine sections": (
        {
            "geometry": {
                "section_count": 9,
                "section_length_m": 0.03,
                "strip_length_m": 0.27,
                "digit_length_m": 0.36,
                "gauge_positions_m": [0.02],
            },
            "sensors": {"adc_channels": [0]},
        },
        "section_count = 9",
    ),
    # sections of unequal lengths: the list must have one length per section, add up and leave room for supports
    "unequal lengths, one short": ({"geometry": {"section_length_m": [0.08, 0.16]}}, "section_length_m"),
    "unequal lengths that do not add up": (
        {"geometry": {"section_length_m": [0.06, 0.10, 0.09], "strip_length_m": 0.24}},  # 0.25 m: 10 mm over
        "the sum of section_length_m [0.06, 0.1, 0.09] = 0.25 m",
    ),
    "unequal lengths, a gauge on a moved support": (
        {"geometry": {"section_length_m": [0.125, 0.035, 0.08]}},  # the first support centred at 0.135 m
        "gauge_positions_m[1] = 0.135 m is on the support at 0.135 m",
    ),
    "unequal lengths, not a number": ({"geometry": {"section_length_m": [0.06, "0.1", 0.08]}}, "section_length_m"),
    "supports that do not add up": (
        {"geometry": {"support_lengths_m": [0.01, 0.02, 0.01], "digit_length_m": 0.27}},  # 0.28 m
        "support_lengths_m [0.01, 0.02, 0.01]",
    ),
    "a support short": ({"geometry": {"support_lengths_m": [0.01, 0.01]}}, "support_lengths_m"),
    "a gauge on a longer support": (
        {"geometry": {"support_lengths_m": [0.01, 0.02, 0.01], "gauge_positions_m": [0.045, 0.135, 0.19]}},
        "gauge_positions_m[2] = 0.19 m is on the support at 0.185 m (0.175 to 0.195 m)",  # 20 mm: 0.28 m long
    ),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_descriptions_are_refused_in_one_line(case, tmp_path, capsys):
    changes, key = BAD[case]
    path = write_digit("thesis", tmp_path, **changes)
    with pytest.raises(ParameterError) as info:
        load_params(path)
    message = str(info.value)
    assert "\n" not in message
    assert key in message
    assert str(path) in message
    assert main(["params", str(path)]) == 2
    out = capsys.readouterr()
    lines = (out.out + out.err).strip().splitlines()
    assert lines
    assert all(str(path) in line for line in lines)
    assert any(key in line for line in lines)


def test_the_gauge_on_a_support_names_the_support():
    params = RigParams.from_dict({"geometry": {"gauge_positions_m": [0.045, 0.093, 0.225]}})
    (line,) = digit_inconsistencies(params)
    assert "support at 0.09 m" in line
    assert math.isfinite(float(line.split("= ")[1].split(" m")[0]))


def test_a_per_gauge_list_of_the_wrong_length_is_named(tmp_path):
    path = write_digit("two-sections", tmp_path, sensors={"gauge_bridges": ["full", "half", "quarter"]})
    with pytest.raises(ParameterError, match=r"gauge_bridges has 3 values for 2 gauges"):
        load_params(path)
    path = write_digit("two-sections", tmp_path, sensors={"gauge_bridges": ["full", "hexa"]})
    with pytest.raises(ParameterError, match=r"'gauge_bridges' parameter of Sensors"):
        load_params(path)


def test_lengths_left_out_are_derived_from_the_sections(tmp_path):
    path = tmp_path / "four.toml"
    path.write_text("[geometry]\nsection_count = 4\n")
    g = load_params(path).geometry
    assert g.strip_length_m == pytest.approx(0.32, abs=LENGTH_ATOL_M)  # 4 x 80 mm
    assert g.digit_length_m == pytest.approx(0.36, abs=LENGTH_ATOL_M)  # and four 10 mm supports
    path.write_text("[geometry]\nsection_count = 2\nsection_length_m = 0.1\ngauge_positions_m = [0.05, 0.15]\n"
                    "[sensors]\nadc_channels = [0, 1]\n")  # fmt: skip
    assert load_params(path).geometry.digit_length_m == pytest.approx(0.22, abs=LENGTH_ATOL_M)

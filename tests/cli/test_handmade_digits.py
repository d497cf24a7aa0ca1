"""Issue 24 from a user's side: digit descriptions written by hand from ``flexdigit params --template`` (not from
tests/digits.py), each loaded by ``flexdigit params``, and hostile ones, each refused in one line naming its key.

The expected layouts are worked by hand from the rules the template states: half a support at the clamp, each
section its free strip then one support, the last support's centre at the tip; EI = E w t^3 / 12."""

import json
from pathlib import Path

import pytest

from flexdigit.cli import main

HERE = Path(__file__).resolve().parent.parent / "data" / "handmade_digits"

# file: (section_starts_m, digit_length_m, E w t^3 / 12 in N m^2), by hand from the file's values
GOOD = {
    "thesis_template": ([0.005, 0.095, 0.185], 0.27, 205e9 * 0.0127 * 0.000381**3 / 12),
    "one_section_quarter": ([0.005], 0.16, 205e9 * 0.0127 * 0.000381**3 / 12),
    "two_sections_half": ([0.005, 0.115], 0.22, 205e9 * 0.0127 * 0.000381**3 / 12),
    "five_unequal_bronze_full": ([0.005, 0.075, 0.155, 0.245, 0.345], 0.45, 110e9 * 0.012 * 0.0004**3 / 12),
    "seven_sections_pair_mixed": (
        [0.004, 0.057, 0.110, 0.163, 0.216, 0.269, 0.322],
        0.371,
        205e9 * 0.0127 * 0.000381**3 / 12,
    ),
    "four_sections_geared_eight": ([0.005, 0.115, 0.225, 0.335], 0.44, 205e9 * 0.0127 * 0.000381**3 / 12),
    "nitinol_unequal_supports": ([0.006, 0.068, 0.148], 0.242, 75e9 * 0.010 * 0.0005**3 / 12),
    "peek_two_sections": ([0.005, 0.105], 0.20, 3.6e9 * 0.015 * 0.0015**3 / 12),
    "six_sections_long_pair_geared": (
        [0.005, 0.085, 0.165, 0.245, 0.325, 0.405],
        0.48,
        205e9 * 0.0127 * 0.000381**3 / 12,
    ),
    "short_pair_quarter": ([0.005, 0.080], 0.15, 205e9 * 0.0127 * 0.000381**3 / 12),
    "one_long_section_full": ([0.005], 0.50, 205e9 * 0.0127 * 0.0006**3 / 12),
    # 3 x 60 mm sections on 7.5 mm supports (size x0.75 of the thesis rig)
    "design_front_10_small_pair": ([0.00375, 0.07125, 0.13875], 0.2025, 205e9 * 0.0127 * 0.000381**3 / 12),
    "design_front_30_six_gauges_pair": ([0.005, 0.095, 0.185], 0.27, 205e9 * 0.0127 * 0.000381**3 / 12),
}
# the layout is given to 1 um (the template's rule), EI from four exact decimal inputs
LAYOUT_ABS_M = 1e-9
EI_REL = 1e-12

# bad file: the key its one line must name
BAD = {
    "absurd_length": "section_length_m",
    "absurd_pretension": "pretension_n",
    "bool_count": "section_count",
    "channels_mismatch": "adc_channels",
    "duplicate_channels": "adc_channels",
    "eccentricity_negative": "cable_eccentricity_m",
    "empty_gauges": "gauge_positions_m",
    "float_section_count": "section_count",
    "gauge_factors_count": "gauge_factors",
    "gauge_in_clamp": "gauge_positions_m",
    "gauge_on_support": "gauge_positions_m",
    "gauge_past_strip": "gauge_positions_m",
    "geometry_not_table": "[geometry]",
    "inverted_adc_range": "adc_range_v",
    "lengths_list_count": "section_length_m",
    "list_sum_mismatch": "section_length_m",
    "misspelt_key": "gauge_postions_m",
    "nan_width": "strip_width_m",
    "negative_gear": "gear_ratio",
    "negative_section_length": "section_length_m",
    "negative_support": "support_lengths_m",
    "negative_thickness": "strip_thickness_m",
    "nine_gauges": "gauge_positions_m",
    "nine_sections": "section_count",
    "not_utf8": "UTF-8",
    "pair_no_pretension": "pretension_n",
    "single_cable_pretension": "pretension_n",
    "string_section_count": "section_count",
    "strip_length_not_sum": "strip_length_m",
    "supports_count": "support_lengths_m",
    "supports_digit_mismatch": "digit_length_m",
    "three_cables": "count",
    "truncated": "not valid TOML",
    "two_gauges_one_place": "gauge_positions_m",
    "unknown_bridge": "bridge",
    "zero_adc_bits": "adc_bits",
    "zero_modulus": "youngs_modulus_pa",
    "zero_sections": "section_count",
}


def test_every_file_is_listed():
    assert {p.stem for p in HERE.glob("*.toml")} == set(GOOD)
    # digit_length_short.toml is refused but names strip_length_m, not the key it got wrong: in the report
    assert {p.stem for p in (HERE / "bad").glob("*.toml")} - {"digit_length_short"} == set(BAD)


@pytest.mark.parametrize("name", sorted(GOOD))
def test_a_handmade_digit_loads_with_the_layout_worked_by_hand(name, capsys):
    assert main(["params", str(HERE / f"{name}.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    starts, length, ei = GOOD[name]
    assert out["problems"] == []
    assert out["derived"]["section_starts_m"] == pytest.approx(starts, abs=LAYOUT_ABS_M)
    assert out["params"]["geometry"]["digit_length_m"] == pytest.approx(length, abs=LAYOUT_ABS_M)
    assert out["derived"]["bending_stiffness_n_m2"] == pytest.approx(ei, rel=EI_REL)


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_hostile_description_is_refused_in_one_line_naming_its_key(name, capsys):
    path = HERE / "bad" / f"{name}.toml"
    assert main(["params", str(path)]) == 2
    captured = capsys.readouterr()
    # a value's type or range goes to stderr; a description's inconsistency is params' own output (stdout)
    lines = (captured.err + captured.out).strip().splitlines()
    assert len(lines) == 1, captured.err + captured.out
    assert str(path) in lines[0]
    assert BAD[name] in lines[0]
    assert "Traceback" not in captured.err + captured.out

"""A second, independent set of hand-made digit descriptions (issue 24's hidden acceptance digits stand-in).

The files in tests/data/handmade_digits2/ were written by hand from ``flexdigit params --template`` only (no
flexdigit helper made them): each good one must load with ``flexdigit params``, and each bad one in bad/ must be
refused with exit 2 and one line on stderr naming the offending key (or the file's defect: not TOML, not UTF-8).
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from flexdigit.cli import main

DATA = Path(__file__).resolve().parents[1] / "data" / "handmade_digits2"
GOOD = sorted(DATA.glob("*.toml"))

#: The thesis rig's values a file leaves out (``flexdigit params --template``).
THESIS_YOUNGS_MODULUS_PA = 205e9
THESIS_STRIP_THICKNESS_M = 0.000381
THESIS_STRIP_WIDTH_M = 0.0127
THESIS_GAUGE_COUNT = 3
THESIS_SECTION_COUNT = 3
THESIS_SECTION_LENGTH_M = 0.08
#: The derived values are a few float operations on the file's numbers.
DERIVED_RTOL = 1e-9

#: bad file -> what its one error line must name (the key, or the file's defect).
BAD = {
    "adc_bits_fraction": "adc_bits",
    "adc_channels_repeated": "adc_channels",
    "adc_channels_short": "adc_channels",
    "adc_range_reversed": "adc_range_v",
    "bridge_misspelt": "bridge",
    "command_sync_byte": "command_max",
    "count_as_bool": "section_count",
    "count_as_string": "section_count",
    "empty_gauge_factors": "gauge_factors",
    "gains_long": "amplifier_gains_v_per_v",
    "gauge_bridges_misspelt": "gauge_bridges",
    "gauge_bridges_short": "gauge_bridges",
    "gauge_in_support": "gauge_positions_m[1]",
    "gauges_unsorted": "gauge_positions_m",
    "huge_exponent": "section_count",
    "inf_gain": "amplifier_gain_v_per_v",
    "list_for_thickness": "strip_thickness_m",
    "nan_width": "strip_width_m",
    "neg_inf_gauge": "gauge_positions_m",
    "nested_list_gauges": "gauge_positions_m",
    "nine_sections": "section_count",
    "operating_reversed": "operating_commands",
    "pair_negative_pretension": "pretension_n",
    "sum_off_1e4": "strip_length_m",
    "support_lengths_mismatch": "support_lengths_m",
    "table_for_width": "strip_width_m",
    "three_cables": "count",
    "top_level_key": "section_count",
    "unknown_key": "gauge_position_m",
    "unknown_table": "geometery",
    "units_as_string": "section_length_m",
    "zero_sections": "section_count",
    # defects of the file itself: the parser's line and column, or the offending byte
    "duplicate_key": "line 4",
    "duplicate_table": "sensors",
    "fullwidth_count": "line 3",
    "latin1_comment": "0xe9",
}


#: hostile files that are consistent after all and must load.
HOSTILE_BUT_VALID = ("sum_off_1e9",)


def test_every_bad_file_is_listed():
    assert sorted(p.stem for p in (DATA / "bad").glob("*.toml")) == sorted([*BAD, *HOSTILE_BUT_VALID])


@pytest.mark.parametrize("path", GOOD, ids=lambda p: p.stem)
def test_good_digit_loads_and_derives_its_geometry(path, capsys):
    assert main(["params", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["problems"] == []
    given = tomllib.loads(path.read_text(encoding="utf-8"))
    geometry = given.get("geometry", {})
    derived = out["derived"]
    # the gauges and sections the file describes, counted from the file itself
    assert derived["gauge_count"] == len(geometry.get("gauge_positions_m", [0] * THESIS_GAUGE_COUNT))
    count = geometry.get("section_count", THESIS_SECTION_COUNT)
    lengths = geometry.get("section_length_m", THESIS_SECTION_LENGTH_M)
    lengths = lengths if isinstance(lengths, list) else [lengths] * count
    spans = [end - start for start, end in zip(derived["section_starts_m"], derived["section_ends_m"], strict=True)]
    assert spans == pytest.approx(lengths, rel=DERIVED_RTOL)
    # EI = E w t^3 / 12 of a rectangular strip
    youngs = given.get("material", {}).get("youngs_modulus_pa", THESIS_YOUNGS_MODULUS_PA)
    width = geometry.get("strip_width_m", THESIS_STRIP_WIDTH_M)
    thickness = geometry.get("strip_thickness_m", THESIS_STRIP_THICKNESS_M)
    assert derived["bending_stiffness_n_m2"] == pytest.approx(youngs * width * thickness**3 / 12, rel=DERIVED_RTOL)


def test_strip_length_off_its_sections_by_a_nanometre_loads(capsys):
    # 1e-9 m is far below any workshop's tolerance: the file is consistent, not refused
    assert main(["params", str(DATA / "bad" / "sum_off_1e9.toml"), "--json"]) == 0
    ends = json.loads(capsys.readouterr().out)["derived"]["section_ends_m"]
    assert ends[-1] == pytest.approx(0.385, rel=DERIVED_RTOL)  # 5 mm half support + 0.36 m + two 10 mm supports


@pytest.mark.parametrize("name", sorted(BAD), ids=str)
def test_bad_digit_is_refused_in_one_line_naming_the_key(name, capsys):
    path = DATA / "bad" / f"{name}.toml"
    assert main(["params", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("flexdigit params: error: ")
    assert path.name in lines[0]
    assert BAD[name] in lines[0]

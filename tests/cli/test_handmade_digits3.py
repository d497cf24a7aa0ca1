"""A third independent set of hand-made digit descriptions (stand-ins for issue 24's hidden acceptance digits).

tests/data/handmade_digits3/ was typed by hand from ``flexdigit params --template`` and docs/digits.md only: each
good file must load with ``flexdigit params`` and derive what its own numbers say; each file in bad/ must be
refused with exit 2 and one line on stderr naming the file and the offending key (or the file's own defect).
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from flexdigit.cli import main

DATA = Path(__file__).resolve().parents[1] / "data" / "handmade_digits3"
GOOD = sorted(DATA.glob("*.toml"))

#: What a file leaves out is the thesis rig's (``flexdigit params --template``).
THESIS = {"section_count": 3, "section_length_m": 0.08, "strip_width_m": 0.0127, "strip_thickness_m": 0.000381}
THESIS_YOUNGS_MODULUS_PA = 205e9
THESIS_GAUGE_COUNT = 3
#: A support left out is 10 mm long (the template's rules).
DEFAULT_SUPPORT_M = 0.01
#: Derived values are a few float operations on the file's numbers.
RTOL = 1e-9

#: bad file -> what its one error line must name.
BAD = {
    "bits_overflow": "adc_bits",
    "bom_bad_thickness": "strip_thickness_m",
    "bool_in_lengths": "section_length_m",
    "bridge_with_space": "bridge",
    "capital_table": "Geometry",
    "date_for_count": "section_count",
    "digit_length_off_2um": "digit_length_m",
    "gauge_count_given": "gauge_count",
    "gauges_in_mm": "gauge_positions_m",
    "inf_pretension": "pretension_n",
    "length_with_unit": "section_length_m",
    "list_for_modulus": "youngs_modulus_pa",
    "nan_gauge_position": "gauge_positions_m",
    "negative_channel": "adc_channels",
    "negative_zero_thickness": "strip_thickness_m",
    "operating_past_254": "operating_commands",
    "overdrive_gear": "gear_ratio",
    "pulse_widths_swapped": "pulse_width_max_s",
    "trailing_space_key": "adc_bits ",
    "zero_width_space_key": "section\\u200bcount",
    # defects of the file itself
    "dotted_duplicate": "line 3",
    "utf16_file": "0xff",
}


def test_every_bad_file_is_listed():
    assert sorted(p.stem for p in (DATA / "bad").glob("*.toml")) == sorted(BAD)


@pytest.mark.parametrize("path", GOOD, ids=lambda p: p.stem)
def test_good_digit_loads_with_the_layout_its_numbers_give(path, capsys):
    assert main(["params", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    derived = out["derived"]
    given = tomllib.loads(path.read_text(encoding="utf-8"))
    geometry = {**THESIS, **given.get("geometry", {})}
    count = geometry["section_count"]
    lengths = geometry["section_length_m"]
    lengths = lengths if isinstance(lengths, list) else [lengths] * count
    supports = geometry.get("support_lengths_m", [DEFAULT_SUPPORT_M] * count)
    # each section: half the first support at the clamp, then strip, support, strip ... (docs/digits.md)
    starts, position = [], supports[0] / 2
    for length, support in zip(lengths, supports, strict=True):
        starts.append(position)
        position += length + support
    assert derived["section_starts_m"] == pytest.approx(starts, rel=RTOL)
    # the last support's centre is the tip
    tip = position - supports[-1] / 2
    assert out["params"]["geometry"]["digit_length_m"] == pytest.approx(tip, rel=RTOL)
    assert derived["gauge_count"] == len(geometry.get("gauge_positions_m", [0.0] * THESIS_GAUGE_COUNT))
    youngs = given.get("material", {}).get("youngs_modulus_pa", THESIS_YOUNGS_MODULUS_PA)
    # EI = E w t^3 / 12 of a rectangular strip
    ei = youngs * geometry["strip_width_m"] * geometry["strip_thickness_m"] ** 3 / 12
    assert derived["bending_stiffness_n_m2"] == pytest.approx(ei, rel=RTOL)


@pytest.mark.parametrize("name", sorted(BAD), ids=str)
def test_bad_digit_is_refused_in_one_line_naming_the_key(name, capsys):
    path = DATA / "bad" / f"{name}.toml"
    assert main(["params", str(path)]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert captured.out == ""
    assert len(lines) == 1
    assert lines[0].startswith(f"flexdigit params: error: {path}")
    assert BAD[name] in lines[0]


def test_a_two_megabyte_bridge_name_is_refused_in_a_short_line(tmp_path, capsys):
    path = tmp_path / "huge_bridge.toml"
    path.write_text('[sensors]\nbridge = "' + "h" * 2_000_000 + '"\n', encoding="utf-8")
    assert main(["params", str(path)]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line
    assert "bridge" in line
    assert len(line) < 1000  # the value is cut, not echoed whole

"""Hostile digit descriptions (issue 24: "bad descriptions refused in one line, fuzzed like the other loaders").

The valid seeds are the campaign's drawn digits (``tests/digit_campaign.py``: 1-8 sections, 1-8 gauges with a
chain each, a cable pair or one, any strip), written by its own TOML writer. Each example edits one key: a value
of the wrong kind or range (NaN, infinities, negative, zero, a string, a boolean, 1e30, 1e-30, a list), one list
element so, the key removed, or an unknown key added. The contract, beyond the loaders' (one line naming the
file): a refusal names the key edited (or, for a key removed, some key of the file), and an edited value is never
silently taken for another (``"0.05"`` for 0.05, ``true`` for 1.0).
"""

from __future__ import annotations

import copy
import math
from numbers import Integral

import pytest
from hypothesis import given
from hypothesis import strategies as st

from digit_campaign import campaign_digit, to_toml
from flexdigit.errors import ParameterError
from flexdigit.params import load_params, plausible_ranges

from .strategies import assert_loader_contract

SEEDS = (0, 2, 5, 12)
HOSTILE = {
    "nan": math.nan,
    "inf": math.inf,
    "-inf": -math.inf,
    "negative": -1.0,
    "negative int": -3,
    "zero": 0,
    "string": "abc",
    "number as string": "0.05",
    "boolean": True,
    "huge": 1e30,
    "tiny": 1e-30,
    "list": [1.0],
}
#: Values that are still a valid description after the edit (the key's own range allows them): a friction of
#: 0 or 1e-30, a single cable's pretension of 0, a density of exactly 0 (a weightless strip, the idealisation the
#: beam oracles take; 1e-30 kg/m^3 is refused: no material is that light).
BENIGN = {
    ("cables", "guide_friction_ratio", "zero"),
    ("cables", "guide_friction_ratio", "tiny"),
    ("cables", "pretension_n", "zero"),
    ("cables", "pretension_n", "tiny"),
    ("material", "strip_density_kg_m3", "zero"),
}


def _keys(data: dict) -> list[tuple[str, str]]:
    return [(table, key) for table, values in data.items() for key in values]


@st.composite
def hostile_digits(draw):
    """A campaign digit with one key made hostile: ``(document, table, key, what)``."""
    data = campaign_digit(draw(st.sampled_from(SEEDS)))
    table, key = draw(st.sampled_from(_keys(data)))
    action = draw(st.sampled_from(["value", "value", "element", "remove", "unknown"]))
    doc = copy.deepcopy(data)
    if action == "remove":
        del doc[table][key]
        return doc, table, key, "removed"
    if action == "unknown":
        doc[table]["colour_m"] = draw(st.sampled_from(list(HOSTILE.values())))
        return doc, table, "colour_m", "unknown"
    name = draw(st.sampled_from(list(HOSTILE)))
    if action == "element" and isinstance(doc[table][key], list):
        values = doc[table][key]
        values[draw(st.integers(0, len(values) - 1))] = HOSTILE[name]
        return doc, table, key, f"element {name}"
    doc[table][key] = HOSTILE[name]
    return doc, table, key, name


@given(case=hostile_digits())
def test_a_hostile_key_is_refused_in_one_line_naming_it(case, tmp_path_factory):
    doc, table, key, what = case
    path = tmp_path_factory.mktemp("hostile") / "digit.toml"
    path.write_text(to_toml(doc))
    outcome = assert_loader_contract(load_params, path)
    if what == "removed":  # a key left out takes its default, or the refusal names a key of the description
        if isinstance(outcome, Exception):
            assert any(k in str(outcome) for _, k in _keys(doc)) or key in str(outcome), str(outcome)
        return
    if (table, key, what) in BENIGN:
        return
    name = what.removeprefix("element ")
    if key == "adc_range_v" and name in ("negative", "negative int", "zero", "tiny"):
        return  # an asymmetric or unipolar ADC range (its order is checked)
    if key == "adc_channels" and name == "zero":
        return  # channel 0 (distinct channels are checked)
    assert isinstance(outcome, ParameterError), f"[{table}] {key} = {what} was accepted"
    assert key in str(outcome), str(outcome)


@pytest.mark.parametrize(
    "value", [["0.05", 0.1], [True, 0.1], [0.05, False]], ids=["a number as a string", "true", "false"]
)
def test_a_gauge_list_holding_text_or_a_boolean_is_refused(value, tmp_path):
    """Regression: ``np.array(["0.05"], dtype=float)`` reads the string as 0.05 and ``true`` as 1.0, so a per-gauge
    list with a quoted number or a boolean loaded as another digit."""
    data = campaign_digit(0)
    data["sensors"]["gauge_factors"][:2] = value
    path = tmp_path / "digit.toml"
    path.write_text(to_toml(data))
    with pytest.raises(ParameterError, match=r"'gauge_factors' parameter .* an array of real numbers"):
        load_params(path)


def test_two_gauges_a_tenth_of_a_micrometre_apart_are_at_one_place(tmp_path):
    """Regression: only repr-equal positions counted as one place; 0.1 um apart passed (positions count to 1 um,
    as the lengths do)."""
    data = campaign_digit(0)
    positions = data["geometry"]["gauge_positions_m"]
    positions[1] = positions[0] + 1e-7
    path = tmp_path / "digit.toml"
    path.write_text(to_toml(data))
    with pytest.raises(ParameterError, match=r"gauge_positions_m\[1\] = .* 0.1 um from gauge_positions_m\[0\]"):
        load_params(path)


def test_a_servo_too_weak_for_its_gearing_names_the_gear_ratio(tmp_path):
    """Regression: a 1:100 overdrive (``gear_ratio = 0.01``) made the servo too weak, and the message listed every
    key but the gear ratio. An overdrive is now refused by the gear ratio's own range (1 to 20); a servo too weak
    for its strip still names the gear ratio among what to check."""
    data = campaign_digit(12)
    data["actuator"]["gear_ratio"] = 0.01
    path = tmp_path / "digit.toml"
    path.write_text(to_toml(data))
    with pytest.raises(ParameterError, match=r"'gear_ratio' .* inside \[1, 20\]"):
        load_params(path)
    data["actuator"]["gear_ratio"] = 1.0
    data["actuator"]["stall_torque_nm"] = 0.005  # the smallest servo the range allows, for a 0.3 mm steel strip
    data["geometry"]["strip_thickness_m"] = 0.001
    path.write_text(to_toml(data))
    with pytest.raises(ParameterError, match=r"cannot bend.*gear_ratio"):
        load_params(path)


@st.composite
def hostile_unequal_digits(draw):
    """The test digit of unequal sections and supports (tests/digits.py) with one geometry key made hostile, or one
    element of its per-section lists: ``(document, key, what)``."""
    from digits import DIGITS

    doc = copy.deepcopy(DIGITS["unequal-sections"])
    key = draw(st.sampled_from(["section_length_m", "support_lengths_m", "section_count", "digit_length_m"]))
    name = draw(st.sampled_from(list(HOSTILE)))
    if isinstance(doc["geometry"][key], list) and draw(st.booleans()):
        doc["geometry"][key][draw(st.integers(0, 2))] = HOSTILE[name]
        return doc, key, f"element {name}"
    doc["geometry"][key] = HOSTILE[name]
    return doc, key, name


@given(case=hostile_unequal_digits())
def test_a_hostile_per_section_length_is_refused_in_one_line_naming_it(case, tmp_path_factory):
    """Sections of unequal lengths: a hostile length or support (or count, or digit length) is refused naming its
    key, never laid out as another digit (a support of 0 or 1e-30 m no longer adds up to the digit's length)."""
    doc, key, what = case
    path = tmp_path_factory.mktemp("hostile") / "digit.toml"
    path.write_text(to_toml(doc))
    outcome = assert_loader_contract(load_params, path)
    assert isinstance(outcome, ParameterError), f"[geometry] {key} = {what} was accepted"
    assert key in str(outcome), str(outcome)


#: Every key with a plausible range (flexdigit.params.plausible_ranges), each list key by one of its values.
RANGES = sorted(plausible_ranges().items())


@st.composite
def out_of_range_digits(draw):
    """A campaign digit with one ranged key set outside its plausible range, below or above by a factor of 1.001 to
    1e6 (an integer key by 1 to 1000): ``(document, table, key, value, range)``."""
    data = copy.deepcopy(campaign_digit(draw(st.sampled_from(SEEDS))))
    (table, key), r = draw(st.sampled_from(RANGES))
    below = draw(st.booleans())
    if r.type is Integral:
        step = draw(st.integers(1, 1000))
        value = r.low - step if below else r.high + step
    else:
        factor = draw(st.floats(1.001, 1e6))
        bound = r.low if below else r.high
        if bound == 0:  # a range from 0: a negative value
            value = -1e-3 * factor
        else:  # away from the range: a positive low divided, a negative low or a high multiplied
            value = bound / factor if below and bound > 0 else bound * factor
    if key in ("gauge_factors", "amplifier_gains_v_per_v"):
        values = data["sensors"].get(key) or [1.0] * len(data["geometry"]["gauge_positions_m"])
        values[draw(st.integers(0, len(values) - 1))] = value
        data["sensors"][key] = values
    else:
        data.setdefault(table, {})[key] = value
    return data, table, key, value, r


@given(case=out_of_range_digits())
def test_an_out_of_range_value_is_refused_in_one_line_naming_it(case, tmp_path_factory):
    """Each out-of-range value is refused by the loader in one clean line (the contract: no traceback, the file
    named) naming the key and, for a scalar key, the value and the expected range with its reason."""
    doc, table, key, value, r = case
    path = tmp_path_factory.mktemp("range") / "digit.toml"
    path.write_text(to_toml(doc))
    outcome = assert_loader_contract(load_params, path)
    assert isinstance(outcome, ParameterError), f"[{table}] {key} = {value!r} was accepted"
    message = str(outcome)
    assert f"'{key}'" in message, message
    if key not in ("gauge_factors", "amplifier_gains_v_per_v"):
        assert r.describe() in message, message

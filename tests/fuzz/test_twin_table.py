"""Hostile ``[twin]`` tables (the twin's resolution, issue 24), fuzzed like the other loaders: a key of the table
given a value of the wrong kind or range (NaN, infinities, negative, zero, a string, a boolean, 1e30, 1e-30, a
list, a whole number as a float), one element of a per-section list so, both keys at once, or an unknown key, on
the campaign's drawn digits. The contract: a refusal in one line naming the file and the key, or a description
whose twin is the one asked for (never another count read from a string or a boolean)."""

from __future__ import annotations

import copy
import math

from hypothesis import given
from hypothesis import strategies as st

from digit_campaign import campaign_digit, to_toml
from flexdigit.errors import ParameterError
from flexdigit.params import load_params, twin_cells

from .strategies import assert_loader_contract

SEEDS = (0, 2, 5, 12)
HOSTILE = [math.nan, math.inf, -math.inf, -1.0, -3, 0, 0.0, "abc", "9", True, False, 1e30, 1e-30, [0.5], 9.5, []]
KEYS = ("max_cell_length_m", "cells_per_section")


@st.composite
def hostile_twin_tables(draw):
    """``(document, key)``: a campaign digit with a ``[twin]`` table holding one hostile entry."""
    doc = copy.deepcopy(campaign_digit(draw(st.sampled_from(SEEDS))))
    sections = doc["geometry"]["section_count"]
    key = draw(st.sampled_from(KEYS))
    action = draw(st.sampled_from(["value", "element", "both", "unknown"]))
    value = draw(st.sampled_from(HOSTILE))
    if action == "element":
        counts = [draw(st.integers(1, 9)) for _ in range(sections)]
        counts[draw(st.integers(0, sections - 1))] = value
        doc["twin"] = {"cells_per_section": counts}
        return doc, "cells_per_section"
    if action == "both":
        doc["twin"] = {"max_cell_length_m": 0.01, "cells_per_section": 5}
        return doc, "cells_per_section"
    if action == "unknown":
        doc["twin"] = {key: 0.01 if key == "max_cell_length_m" else 5, "cells_m": value}
        return doc, "cells_m"
    doc["twin"] = {key: value}
    return doc, key


@given(case=hostile_twin_tables())
def test_a_hostile_twin_table_is_refused_in_one_line_naming_its_key(case, tmp_path_factory):
    doc, key = case
    path = tmp_path_factory.mktemp("hostile") / "digit.toml"
    path.write_text(to_toml(doc))
    outcome = assert_loader_contract(load_params, path)
    assert isinstance(outcome, ParameterError), f"[twin] {doc['twin']} was accepted"
    assert key in str(outcome), str(outcome)


@given(seed=st.sampled_from(SEEDS), count=st.integers(1, 81), per_section=st.booleans())
def test_a_plausible_count_gives_that_twin_or_the_springs_limit(seed, count, per_section, tmp_path_factory):
    doc = copy.deepcopy(campaign_digit(seed))
    sections = doc["geometry"]["section_count"]
    doc["twin"] = {"cells_per_section": [count] * sections if per_section else count}
    path = tmp_path_factory.mktemp("twin") / "digit.toml"
    path.write_text(to_toml(doc))
    outcome = assert_loader_contract(load_params, path)
    if count * sections > 243:
        assert isinstance(outcome, ParameterError), str(outcome)
        assert "at most 243" in str(outcome), str(outcome)
    else:
        assert twin_cells(outcome) == (count,) * sections

"""The packaged thesis figures: present, typed, and missing keys named."""

import math

import pytest

from flexdigit.reference import thesis_complex, thesis_value


def test_packaged_figures_are_the_printed_ones():
    assert thesis_value("plant.g_num") == [48.7]
    assert thesis_value("digit.model.e_den") == [1, 1.782, 171.61]
    assert math.isnan(thesis_value("digit.release_tests_with_housing.percent_overshoot")[1])  # garbled in print
    assert thesis_complex("plant.poles")[0] == complex(-11.555, 16.97)


def test_missing_key_is_named():
    with pytest.raises(KeyError, match="plant.nope"):
        thesis_value("plant.nope")

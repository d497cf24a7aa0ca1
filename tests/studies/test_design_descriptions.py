"""The design study's digits are parameter files like any other (issue 24): every candidate design, written out
as its description, holds together (:func:`flexdigit.params.digit_inconsistencies`) and loads back the same."""

from __future__ import annotations

import dataclasses

import pytest
import tomli_w

from flexdigit.params import digit_inconsistencies, load_params
from flexdigit.studies.design_study import DesignSettings, candidates, design_parameter_set
from flexdigit.studies.parameter_set import ParameterSet

# every option of the study but the D-optimal layout (its positions cost a Fisher-information search each; they are
# grid points on the strip, chosen by the same _onto_strip rule the equal layout uses)
SETTINGS = dataclasses.replace(DesignSettings(), layouts=("thesis", "equal"), adc_bits=(16,))


@pytest.mark.parametrize("index", range(0, len(candidates(SETTINGS, 0)), 7))
def test_a_design_is_a_consistent_description(index, tmp_path):
    candidate = candidates(SETTINGS, 0)[index]
    description = design_parameter_set(ParameterSet(), candidate).description()
    assert digit_inconsistencies(description) == [], candidate.label()
    assert description.cables.count == (2 if candidate.pretension_n > 0 else 1)
    path = tmp_path / "design.toml"
    path.write_text(tomli_w.dumps(description.to_dict()))
    assert load_params(path) == description


def test_a_one_cable_design_from_a_pair_digit_is_one_cable():
    # a study whose baseline digit describes the pair ([cables] count = 2): its "1 cable" candidates drop the pair
    # (the batched twin takes a described pair, so a kept one would score them as pairs under a "1 cable" label)
    from digits import DIGITS
    from flexdigit.params import RigParams

    pair = RigParams.from_dict(DIGITS["four-sections-two-cables"])
    settings = dataclasses.replace(SETTINGS, layouts=("equal",))
    for candidate in candidates(settings, 0)[::11]:
        ps = design_parameter_set(ParameterSet(pair), candidate)
        assert ps.pair_pretension_n == (candidate.pretension_n if candidate.pretension_n > 0 else None)
        assert ps.description().cables.count == (2 if candidate.pretension_n > 0 else 1)

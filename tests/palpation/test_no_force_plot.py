"""The force-indentation figure marks the plateaus where the gauges read no force, with a legend entry, instead of
drawing a number there (the estimator's 1 N clip read as a force before). Reference: the twin's statics
(:func:`flexdigit.palpation.palpation_studies.sweep_example`: nothing touches the straight digit at command 8)."""

from __future__ import annotations

import numpy as np
import pytest

from flexdigit.palpation import palpation_studies as studies
from flexdigit.palpation.palpation import PalpationProtocol
from flexdigit.palpation.palpation_plot import indentation_figure


@pytest.fixture(scope="module")
def result():
    return studies.sweep_example(1000.0, protocol=PalpationProtocol(commands=tuple(range(8, 23, 2))), seed=0)


def test_the_sweep_reads_no_force_clear_of_the_block(result):
    clear = result.curve["true_force_n"] == 0.0
    assert np.all(np.isnan(result.curve["force_n"][clear]))


def test_the_figure_has_a_legend_entry_for_no_force_read(result):
    fig = indentation_figure(result)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any(label.startswith("no force read") for label in labels)


def test_the_figure_draws_a_point_only_where_a_force_was_read(result):
    fig = indentation_figure(result)
    drawn = fig.axes[0].containers[0].lines[0].get_ydata()  # the errorbar's points: "from the gauges"
    assert np.size(drawn) == np.count_nonzero(result.curve["force_read"])

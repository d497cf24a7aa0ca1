"""Finding the instant, the spikes and the hum of a record (flexdigit.identify.events) on known answers.

Signals are built here in closed form (a second-order response written out, sinusoids, spikes at chosen samples),
so each expected value is known exactly. Tolerances: the instant within two samples (the fit refines it), hum
frequency within 0.01 Hz and amplitude within 2 %, spikes found exactly.
"""

import numpy as np
import pytest

from flexdigit.errors import DataFileError
from flexdigit.identify.events import find_spikes, remove_hum, survey
from flexdigit.identify.timeseries import TimeSeries

from .records import free_response, step_shape


def _step(t, t0, wn=20.53, zeta=0.5629, size=0.4, start=1.0):
    return start + size * step_shape(t - t0, wn, zeta)


@pytest.mark.parametrize(("t0", "size"), [(0.3, 0.4), (0.1, -0.4), (0.0, 0.4), (0.45, -1.2)])
def test_survey_finds_the_step_instant_either_way(t0, size):
    t = np.arange(0, 2.5, 0.002)
    y = _step(t, t0, size=size) + np.random.default_rng(1).normal(0, 0.01 * abs(size), t.size)
    s = survey(TimeSeries.from_arrays(t, y), "step")
    assert s.found_from == "signal"
    assert s.problems == ()
    assert s.direction == (1 if size > 0 else -1)
    # the start value is where the response leaves the noise band, walked back: within 5 ms of the truth
    assert s.t0_s == pytest.approx(t0, abs=0.005)
    assert s.baseline_s == pytest.approx(t0, abs=0.005)


def test_survey_finds_the_release_after_a_held_deflection():
    t = np.arange(0, 6, 0.001)
    y = 0.2 + 0.8 * free_response(t - 0.35, 13.1, 0.068) + np.random.default_rng(2).normal(0, 0.01, t.size)
    s = survey(TimeSeries.from_arrays(t, y), "release")
    assert s.t0_s == pytest.approx(0.35, abs=0.01)
    assert s.direction == -1
    assert s.problems == ()
    assert s.start_level == pytest.approx(1.0, abs=0.005)


def test_command_column_gives_the_instant():
    t = np.arange(0, 2, 0.002)
    u = np.where(t >= 0.5, 59.0, 8.0)  # first new command at 0.5 s: the step is between 0.498 and 0.5 s
    s = survey(TimeSeries.from_arrays(t, _step(t, 0.5), u=u), "step")
    assert s.found_from == "command"
    assert s.t0_s == pytest.approx(0.499)
    assert s.input_step == 51.0


def test_a_constant_record_has_nothing_to_identify():
    t = np.arange(0, 1, 0.01)
    with pytest.raises(DataFileError, match=r"array:y: the signal is constant \(0.25\) over the whole record"):
        survey(TimeSeries.from_arrays(t, np.full(t.size, 0.25)), "step")


def test_find_spikes_finds_exactly_the_spikes_also_on_a_steep_edge():
    # at 200 Hz the servo's step falls 6 noise deviations per sample; a spike there used to pull its neighbours
    t = np.arange(0, 2, 0.005)
    rng = np.random.default_rng(3)
    y = _step(t, 0.2, wn=18.4, size=-0.4) + rng.normal(0, 0.003, t.size)
    where = [7, 47, 48, 120, 300]  # 47 on the steepest part of the edge, 48 right after it
    y[where] += [0.2, -0.15, 0.1, 0.12, -0.18]
    assert find_spikes(y, 0.003).tolist() == where


def test_find_spikes_leaves_a_longer_run_alone():
    y = np.zeros(100)
    y[40:45] = 1.0  # five samples: a feature (or a clipped stretch), not a spike
    y[60:] += 2.0  # a step: neither its corners nor its edge are spikes
    y[70] += 1.0
    assert find_spikes(y, 0.01).tolist() == [70]


@pytest.mark.parametrize(("f", "fs"), [(50.0, 200.0), (60.0, 500.0), (49.93, 2000.0), (60.07, 1000.0)])
def test_remove_hum_recovers_frequency_and_amplitude(f, fs):
    t = np.arange(0, 3, 1 / fs)
    clean = _step(t, 0.4)
    hum = 0.03 * np.sin(2 * np.pi * f * t + 0.7)
    if 3 * f < 0.45 * fs:
        hum += 0.01 * np.sin(2 * np.pi * 3 * f * t)  # and its third harmonic
    y = clean + hum + np.random.default_rng(4).normal(0, 0.004, t.size)
    out, found = remove_hum(t, y)
    assert found.frequency_hz == pytest.approx(f, abs=0.01)
    assert found.amplitude == pytest.approx(0.03, rel=0.02)
    if 3 * f < 0.45 * fs:
        assert found.harmonics == (1, 3)
        assert found.amplitudes[1] == pytest.approx(0.01, rel=0.1)
    assert np.std(out - clean) == pytest.approx(0.004, rel=0.1)  # only the white noise is left


def test_no_hum_is_found_where_there_is_none():
    t = np.arange(0, 3, 0.001)
    y = _step(t, 0.4) + np.random.default_rng(5).normal(0, 0.01, t.size)
    out, found = remove_hum(t, y)
    assert found is None
    assert np.array_equal(out, y)

"""When the live loop re-estimates the shape (:func:`flexdigit.live.session.estimate_due`), on seeded readings
with known answers: pure noise (a digit at rest), a creeping tail and a moving digit."""

import math

import numpy as np

from flexdigit.live.session import LiveSession, estimate_due
from flexdigit.twin.calibration import default_calibration

WHITE_V = float(np.max(default_calibration().noise_white_v))  # the twin's white noise per reading, V
SD_MEAN_DIFF_V = WHITE_V * math.sqrt(2.0 / LiveSession.AVERAGE)  # of the difference of two 5-reading means
DUE = dict(
    still_v=LiveSession.STILL_SIGMAS * SD_MEAN_DIFF_V,
    creep_v=LiveSession.CREEP_SIGMAS * SD_MEAN_DIFF_V,
    window_s=LiveSession.AVERAGE * 0.020,
    max_gap_s=LiveSession.MAX_ESTIMATE_GAP_S,
)
CHECK_S = LiveSession.ESTIMATE_EVERY * 0.020  # the loop asks every other 20 ms frame


def _run(readings_v):
    """Feed 5-reading means of ``readings_v`` (N, 3) to the rule as the loop does; the check times estimated."""
    last_mean, last_t, times = None, None, []
    for k in range(LiveSession.AVERAGE, len(readings_v) + 1, LiveSession.ESTIMATE_EVERY):
        mean, t = readings_v[k - LiveSession.AVERAGE : k].mean(axis=0), k * 0.020
        if last_mean is None or estimate_due(float(np.max(np.abs(mean - last_mean))), False, t - last_t, **DUE):
            last_mean, last_t = mean, t
            times.append(t)
    return np.array(times)


def test_a_digit_at_rest_is_estimated_once_a_second():
    # pure noise: a 3-sigma change of the largest of three gauges happens on ~0.8 % of the checks (3 x 0.27 %),
    # so the estimates come from the one-second refresh
    rng = np.random.default_rng(4)
    times = _run(0.3 + WHITE_V * rng.standard_normal((50 * 60, 3)))
    assert 55 <= times.size <= 75  # 60 s: ~60 refreshes, a few noise crossings


def test_a_creeping_tail_is_estimated_once_per_window_and_a_move_every_check():
    rng = np.random.default_rng(5)
    frames = np.arange(50 * 10)[:, None]
    noise = WHITE_V * rng.standard_normal((frames.size, 3))
    # 4 standard deviations of the mean difference per 0.12 s: between still and creep
    creep = _run(0.3 + frames * (4.0 * SD_MEAN_DIFF_V / 6.0) + noise)
    gaps = np.diff(creep)
    assert np.median(gaps) >= DUE["window_s"] - 1e-9
    assert np.median(gaps) <= 0.12 + 1e-9
    # 20 standard deviations per frame: every check
    move = _run(0.3 + frames * (20.0 * SD_MEAN_DIFF_V) + noise)
    assert np.allclose(np.diff(move), CHECK_S)


def test_a_new_command_or_a_second_without_one_is_always_due():
    assert estimate_due(0.0, True, 0.04, **DUE)
    assert estimate_due(0.0, False, DUE["max_gap_s"], **DUE)
    assert not estimate_due(0.5 * DUE["still_v"], False, 0.5, **DUE)

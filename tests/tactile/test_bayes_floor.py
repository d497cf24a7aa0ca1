"""The Bayes limit a position network is compared with is a floor for how it is scored (trial 2, item 10).

The reference is a linear-Gaussian gauge, ``v = k a m / m0`` with white noise ``sigma`` and one load ``m0``: for a
position uniform over a stretch the posterior is Gaussian with standard deviation ``sigma / k`` away from the
stretch's ends, so the span limit there is ``sigma / k`` in closed form (any estimator's RMSE at a position is at
least that, the unbiased inverse ``v / k`` has exactly that).

Tolerances:

- ``LIMIT_RTOL = 0.03``: the span limit's Monte Carlo (1000 draws a setting over the rows' settings: ~1 % of the
  RMS) and its grid (a quarter of ``sigma / k``, under 1 %).
- The limit's own estimator (the posterior mean, :func:`span_estimator_rmse_m`) on ``n`` readings: its RMSE
  scatters by ``1 / sqrt(2 n)`` too; on readings offset by ``c`` (a drift since the tare) it reads
  ``sqrt((sigma / k)^2 + (c / k)^2)`` in closed form (a shifted Gaussian posterior away from the stretch's ends).
- The network's RMSE on ``n`` test readings scatters by ``1 / sqrt(2 n)`` of itself (the RMS of ``n`` Gaussian
  errors); "not beating the limit" is an RMSE over the limit above ``1 - 3 / sqrt(2 n) - LIMIT_RTOL``.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.tactile.bounds import span_position_mse_m2
from flexdigit.tactile.dataset import Dataset, dataset_columns, make_meta
from flexdigit.tactile.localisation import position_bayes_rmse_m, span_estimator_rmse_m, train_network
from flexdigit.tactile.pipeline import held_out_positions_split
from flexdigit.tactile.position_floor import network_floor, split_for_limit
from flexdigit.tactile.protocols import load_protocol

LIMIT_RTOL = 0.03
MASS_KG = 0.025
SIGMA_V = 0.002
SLOPE_V_PER_M = 1.0  # sigma / k = 2 mm; the positions 10 mm (5 sigma) apart


class LinearGauge:
    """One gauge reading ``k a m / m0`` with white noise (the closed-form case)."""

    noise_v = np.array([SIGMA_V])

    def gauges_v(self, a, m, command):
        a, m = np.broadcast_arrays(np.atleast_1d(a), np.atleast_1d(m))
        return (SLOPE_V_PER_M * a * m / MASS_KG)[:, None]


def _dataset(positions_m, repetitions: int, seed: int = 1) -> Dataset:
    a = np.repeat(positions_m, repetitions)
    cols = {c: np.zeros(a.size, dtype=d) for c, d in dataset_columns(1).items()}
    cols["sample"][:] = np.arange(a.size)
    cols["load_kg"][:] = MASS_KG
    cols["position_from_base_m"][:] = a
    cols["position_from_tip_m"][:] = 0.5 - a
    cols["position_index"][:] = np.repeat(np.arange(len(positions_m)) + 1, repetitions)
    cols["time_s"][:] = 0.02 * np.arange(a.size)
    noise = SIGMA_V * np.random.default_rng(seed).standard_normal(a.size)
    cols["gauge1_v"][:] = LinearGauge().gauges_v(a, MASS_KG, 0)[:, 0] + noise
    return Dataset(cols, make_meta(load_protocol("thesis-6.1"), {}, 0.5, gauge_count=1))


POSITIONS_M = 0.1 + 0.01 * np.arange(31)


def test_span_limit_is_sigma_over_slope_at_every_interior_position():
    # each position alone: the grid once sat the protocol's positions between its points, a prior heavier there
    # (1.88 mm at odd positions, 2.00 at even ones)
    ds = _dataset(POSITIONS_M, 4)
    limits = [position_bayes_rmse_m(LinearGauge(), ds, np.arange(4 * k, 4 * k + 4)) for k in range(2, 29)]
    np.testing.assert_allclose(limits, SIGMA_V / SLOPE_V_PER_M, rtol=2 * LIMIT_RTOL)  # 1000 draws each: ~2 %
    assert np.mean(limits) == pytest.approx(SIGMA_V / SLOPE_V_PER_M, rel=LIMIT_RTOL / 3)


def test_held_out_split_keeps_test_positions_out_of_training():
    a = np.repeat(POSITIONS_M, 3)
    split = held_out_positions_split(a, seed=4)
    train, val, test = (set(np.round(a[s], 6)) for s in (split.train, split.val, split.test))
    assert (train & val, train & test, val & test) == (set(), set(), set())
    assert (len(train), len(val), len(test)) == (16, 10, 5)  # every other interior one held, 1/3 of them test
    assert (min(train), max(train)) == (min(a), max(a))  # nothing extrapolated
    assert sorted(np.r_[split.train, split.val, split.test].tolist()) == list(range(a.size))
    with pytest.raises(ParameterError, match="at least 5 distinct load positions; the readings have 4"):
        held_out_positions_split(np.repeat(POSITIONS_M[:4], 3), seed=0)


@pytest.mark.slow
def test_network_on_held_out_positions_does_not_beat_the_span_limit():
    ds = _dataset(POSITIONS_M, 100)
    result, rows, _, _ = train_network(ds, "position", seed=0, hidden=5, tol=1e-7, split="positions")
    test = rows[result.split.test]
    assert not np.isin(
        np.round(ds["position_from_base_m"][test], 6), np.round(ds["position_from_base_m"][rows[result.split.train]], 6)
    ).any()
    rmse_m = float(np.sqrt(np.mean((result.y_pred - result.y_test) ** 2)))
    scores = network_floor(LinearGauge(), ds, test, rmse_m, split="positions")
    assert scores["bayes_limit_prior"] == "span"
    assert scores["bayes_limit_mm"] == pytest.approx(1e3 * SIGMA_V / SLOPE_V_PER_M, rel=LIMIT_RTOL)
    floor = 1.0 - 3.0 / np.sqrt(2 * test.size) - LIMIT_RTOL
    assert floor < scores["rmse_over_bayes_limit"] < 1.3, scores


def test_readings_split_is_compared_with_the_settings_limit():
    ds = _dataset(POSITIONS_M, 4)
    rows = np.arange(len(ds))
    scores = network_floor(LinearGauge(), ds, rows, 2e-3, split="readings")
    # positions 5 sigma apart: a reading mixes two with probability 2 Q(2.5) = 1.2 %, each a 10 mm error
    assert scores["bayes_limit_prior"] == "settings"
    assert 0.5 < scores["bayes_limit_settings_mm"] < 1.5 < scores["bayes_limit_span_mm"]
    assert scores["rmse_over_bayes_limit"] == pytest.approx(2.0 / scores["bayes_limit_settings_mm"])


def test_no_ratio_where_the_floor_is_unresolved():
    far = 0.1 + 0.2 * np.arange(6)  # 100 sigma apart: no draw mixes two positions
    scores = network_floor(LinearGauge(), _dataset(far, 4), np.arange(24), 2e-3, split="readings")
    assert (scores["bayes_limit_settings_mm"], scores["rmse_over_bayes_limit"]) == (None, None)
    assert "no ratio: the settings limit" in scores["bayes_limit_note"]


def test_a_protocol_too_short_to_hold_positions_out_is_scored_on_readings():
    assert split_for_limit(_dataset(POSITIONS_M, 2)) == "positions"
    assert split_for_limit(_dataset(POSITIONS_M[:4], 2)) == "readings"


def test_a_coarse_grid_still_gives_the_closed_form():
    # the span grid's step up to the posterior's sd gives the continuous posterior mean (common draws): what lets a
    # limit of one grid step be reported (SPAN_RESOLVED_STEPS)
    a = POSITIONS_M + 3e-4  # off every lattice
    sd = SIGMA_V / SLOPE_V_PER_M
    rms = []
    for step in (0.25 * sd, sd, 2 * sd):
        mse = span_position_mse_m2(LinearGauge(), a, MASS_KG, 0, step_m=step, half_width_m=5e-3, samples=2000)
        rms.append(float(np.sqrt(np.mean(mse[5:26]))))
    assert rms[1] == pytest.approx(rms[0], rel=1e-6)
    assert rms[2] == pytest.approx(rms[0], rel=2e-3)
    assert rms[0] == pytest.approx(sd, rel=LIMIT_RTOL)


def test_the_limits_own_estimator_reads_the_limit_on_the_models_noise():
    ds = _dataset(POSITIONS_M, 100)
    rows = np.arange(5 * 100, 26 * 100)  # interior positions: the posterior is Gaussian there
    scatter = 3.0 / np.sqrt(2 * rows.size) + LIMIT_RTOL
    assert span_estimator_rmse_m(LinearGauge(), ds, rows) == pytest.approx(SIGMA_V / SLOPE_V_PER_M, rel=scatter)
    scores = network_floor(LinearGauge(), ds, rows, 2.2e-3, split="positions")
    assert scores["bayes_limit_reached"] is True
    assert "bayes_limit_note" not in scores


def test_readings_with_a_drift_the_limit_does_not_count_are_said():
    # every reading 2 sigma off (a drift since the tare): the limit's own estimator reads sqrt(2^2 + 4^2) mm
    ds = _dataset(POSITIONS_M, 100)
    ds.columns["gauge1_v"] += 2 * SIGMA_V
    rows = np.arange(5 * 100, 26 * 100)
    shifted = np.hypot(SIGMA_V, 2 * SIGMA_V) / SLOPE_V_PER_M
    scatter = 3.0 / np.sqrt(2 * rows.size) + LIMIT_RTOL
    assert span_estimator_rmse_m(LinearGauge(), ds, rows) == pytest.approx(shifted, rel=scatter)
    scores = network_floor(LinearGauge(), ds, rows, 5e-3, split="positions")
    assert scores["bayes_limit_reached"] is False
    assert scores["rmse_over_bayes_estimator"] == pytest.approx(5e-3 / shifted, rel=scatter)
    assert "the limit's own estimator (the twin's response known) reads 4.4" in scores["bayes_limit_note"]

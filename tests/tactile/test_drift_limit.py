"""The localisation Bayes limit with the run's drift counted, the limit issue 24's network ratio is judged against
(:func:`flexdigit.tactile.position_floor.network_floor`'s ``compared_limit``).

References, each independent of the code under test:

- a linear gauge ``g = k m a`` with white noise ``sigma`` and a random-walk drift of rate ``r``: readings simulated
  on a thesis-6.1-like clock (:func:`numpy.cumsum` of Gaussian steps, what a run's readings carry), then located by
  the drift-counted limit's own estimator. For a linear gauge the posterior is Gaussian and its mean's error is the
  reading's noise over ``k m``, so that estimator's RMSE over many runs is the limit itself, reading by reading
  (closed form; the Monte Carlo limit and the simulated runs share nothing but the clock).
- the bookkeeping: the ratio is the network's RMSE over the limit the dict names, by arithmetic.

Tolerances: ``POOLED_RTOL = 0.1`` between the estimator's RMSE pooled over ``RUNS`` simulated runs (about 3000
independent drift offsets: 1.3 % one sd on the RMS) and the limit's Monte Carlo (1000 draws a setting, 120
settings: under 1 %); 0.1 also covers the span's ends, where the flat prior's truncation makes the posterior
slightly narrower than the closed form.
"""

from __future__ import annotations

import numpy as np
import pytest

from drift_runs import Linear, _run
from flexdigit.tactile.dataset import Dataset
from flexdigit.tactile.localisation import position_bayes_rmse_m, span_estimator_rmse_m
from flexdigit.tactile.position_floor import COMPARED_LIMIT, NETWORK_RATIO_MAX, network_floor

POOLED_RTOL = 0.1
RUNS = 25
RATE_V_PER_SQRT_S = 2e-4  # the thesis chain's order (0.1-0.2 mV/sqrt(s)); 2 mV after 100 s, twice the white noise
WHITE_V = 1e-3


def _simulated(ds: Dataset, seed: int) -> Dataset:
    """``ds`` with one run's gauge readings: the load's signal, a random walk on the run's clock, white noise."""
    rng = np.random.default_rng(seed)
    t = ds["time_s"]
    walk = np.cumsum(np.sqrt(np.diff(np.r_[0.0, t])) * RATE_V_PER_SQRT_S * rng.standard_normal(t.size))
    signal = np.where(ds["load_kg"] > 0, ds["load_kg"] * np.nan_to_num(ds["position_from_base_m"]), 0.0)
    cols = dict(ds.columns)
    cols["gauge1_v"] = signal + walk + WHITE_V * rng.standard_normal(t.size)
    return Dataset(cols, dict(ds.meta))


def _interior(ds: Dataset) -> np.ndarray:
    loaded = np.flatnonzero(ds["load_kg"] > 0)
    base = ds["position_from_base_m"][loaded]
    return loaded[(base > 0.07) & (base < 0.13)]


def test_the_drift_counted_limits_estimator_reads_it_on_drifting_runs():
    """Runs whose gauge drifts 2e-4 V/sqrt(s) (tared once a test, 20 tests of six positions): the estimator that
    knows the gauge and weighs each reading with its drift variance reads the drift-counted limit, and the
    white-noise estimator, misled by the drift, reads more."""
    ds = _run(tests=20, positions=6, reps=2, no_load=10)
    model = Linear(1.0, WHITE_V, drift=RATE_V_PER_SQRT_S)
    rows = _interior(ds)
    limit = position_bayes_rmse_m(model, ds, rows, samples=4000, drift=True)
    runs = [_simulated(ds, seed) for seed in range(RUNS)]
    pooled = np.sqrt(np.mean([span_estimator_rmse_m(model, run, rows, drift=True) ** 2 for run in runs]))
    white = np.sqrt(np.mean([span_estimator_rmse_m(model, run, rows) ** 2 for run in runs]))
    assert pooled == pytest.approx(limit, rel=POOLED_RTOL)
    assert white > (1.0 + POOLED_RTOL) * limit, (white, limit)


def test_the_ratio_is_judged_against_the_limit_it_names():
    """Held-out positions: the network's RMSE over the drift-counted limit, named, and over the 1.3 bound or not;
    the white-noise figure keeps its own name and ratio."""
    ds = _simulated(_run(tests=4, positions=6, reps=5, no_load=10), seed=0)
    model = Linear(1.0, WHITE_V, drift=RATE_V_PER_SQRT_S)
    rows = _interior(ds)
    rmse_m = 4e-3
    scores = network_floor(model, ds, rows, rmse_m, split="positions")
    assert scores["compared_limit"] == COMPARED_LIMIT["positions"] == "bayes_limit_with_drift_mm"
    drift_mm = scores["bayes_limit_with_drift_mm"]
    assert scores["rmse_over_compared_limit"] == pytest.approx(4.0 / drift_mm, rel=1e-12)
    assert scores["within_network_ratio_max"] is (4.0 / drift_mm <= NETWORK_RATIO_MAX)
    assert scores["rmse_over_bayes_limit"] == pytest.approx(4.0 / scores["bayes_limit_mm"], rel=1e-12)
    assert drift_mm > scores["bayes_limit_mm"]
    assert "bayes_estimator_with_drift_rmse_mm" in scores


def test_under_the_drift_counted_limit_is_said():
    """A network under the drift-counted limit learnt part of the run's drift: the note says that limit is a floor
    for a new run's readings."""
    ds = _simulated(_run(tests=4, positions=6, reps=5, no_load=10), seed=0)
    scores = network_floor(Linear(1.0, WHITE_V, drift=RATE_V_PER_SQRT_S), ds, _interior(ds), 1e-4, split="positions")
    assert scores["rmse_over_compared_limit"] < 1.0
    assert "new run's readings" in scores["bayes_limit_note"]

"""The localisation Bayes limit of ``flexdigit train --bayes-limit`` (issue 24): known answers, and the failure
classes of the hand-made digits' trial (/work/coord/trial_report.md, docs/digits.md "Bayes limit of your digit").

- A linear gauge ``g = k m a`` with white noise ``sigma``: a reading well inside the span is located to
  ``sigma / (k m)`` (the Gaussian posterior of a flat prior; closed form). ``MC_RTOL = 0.12``: 1000 draws give the
  MSE to ``sqrt(2 / 1000)`` = 4.5 % (one sd), the RMS to half that; 0.12 on the RMS is over 5 sd.
- Positions many sigmas apart (a stiff or high-gain digit on the thesis's 1 cm positions): the settings-aware
  limit falls to nothing (the trial's PEEK digit: 1.4e-11 mm) while the span limit stays ``sigma / (k m)``.
- A limit the grid cannot resolve is refused in one line, never printed.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexdigit.tactile.bounds import span_position_mse_m2
from flexdigit.tactile.dataset import Dataset, dataset_columns
from flexdigit.tactile.localisation import position_bayes_rmse_m

MC_RTOL = 0.12


class Linear:
    """One gauge reading ``slope * m * a`` volts (a in m, m in kg), white noise ``noise_v``."""

    def __init__(self, slope_v_per_kg_m: float, noise_v: float) -> None:
        self.slope = slope_v_per_kg_m
        self.noise_v = np.array([noise_v])

    def gauges_v(self, a, m, command):
        a, m = np.broadcast_arrays(np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(m, float)))
        return (self.slope * m * a)[:, None]


def _dataset(positions_m, mass_kg: float = 1.0, repeats: int = 1) -> Dataset:
    a = np.repeat(np.asarray(positions_m, dtype=float), repeats)
    cols = {c: np.zeros(a.size, dtype=d) for c, d in dataset_columns(1).items()}
    cols["load_kg"][:] = mass_kg
    cols["position_from_base_m"][:] = a
    cols["command"][:] = -1
    return Dataset(cols, {"gauge_count": 1})


def test_linear_gauge_is_located_to_sigma_over_slope():
    model = Linear(1.0, 1e-3)  # 1 mm per sigma under 1 kg
    a = np.array([0.05, 0.1, 0.15])  # the span 0.05..0.15 m; 0.1 m is 50 sigma from either end
    mse = span_position_mse_m2(model, a, np.ones(3), -1, step_m=2.5e-4, samples=1000, seed=0)
    assert np.sqrt(mse[1]) == pytest.approx(1e-3, rel=MC_RTOL)


def test_stretches_around_positions_are_the_prior():
    """With ``half_width_m`` the prior is the stretches around the positions: two positions 10 sigma apart
    with stretches of 2 sigma each way locate no worse than the truncated Gaussian, better than the whole span;
    a half-width of 50 sigma gives the span's answer."""
    model = Linear(1.0, 1e-3)
    a = np.array([0.05, 0.06])
    narrow = span_position_mse_m2(model, a, np.ones(2), -1, step_m=2.5e-4, half_width_m=2e-3, samples=1000, seed=2)
    wide = span_position_mse_m2(model, a, np.ones(2), -1, step_m=2.5e-4, half_width_m=0.05, samples=1000, seed=2)
    # a flat prior on +-2 sigma: the posterior mean's RMS error is under the prior's own sd, 4 / sqrt(12) sigma
    assert np.all(np.sqrt(narrow) < 4e-3 / np.sqrt(12))
    assert np.sqrt(wide) == pytest.approx([1e-3, 1e-3], rel=MC_RTOL)


def test_heavier_load_is_located_better_in_proportion():
    """The slope scales with the mass: twice the mass, half the limit (the same Gaussian posterior, k m doubled)."""
    model = Linear(1.0, 1e-3)
    a = np.array([0.05, 0.1, 0.1, 0.15])
    m = np.array([1.0, 1.0, 2.0, 1.0])
    mse = span_position_mse_m2(model, a, m, -1, step_m=1e-4, samples=1000, seed=1)
    assert np.sqrt(mse[2]) == pytest.approx(0.5e-3, rel=MC_RTOL)


def test_positions_many_sigmas_apart_keep_a_span_limit():
    """The trial's failure class: 1 cm positions with a 1 mm resolution are 10 sigma apart. Knowing the positions
    the posterior never mixes them (the settings limit is ~0: P(mix) ~ Q(5) ~ 3e-7); the span limit is the
    resolution, what a regression of a continuous position can reach."""
    model = Linear(1.0, 1e-3)
    ds = _dataset(np.arange(0.05, 0.2001, 0.01))
    inner = np.arange(2, 14)  # away from the span's ends
    from flexdigit.tactile.localisation import bayes_limits

    limits = bayes_limits(model, ds, inner, samples=1000)
    settings = float(np.sqrt(np.nanmean(limits.position_mse_m2)))
    stretches = position_bayes_rmse_m(model, ds, inner, samples=4000)
    assert settings < 1e-5  # 0.01 mm: not one of 16000 draws mixed two positions by more than that
    # positions continuous within half a step (5 sigma) of each: the Gaussian posterior, barely cut
    assert stretches == pytest.approx(1e-3, rel=MC_RTOL)


def test_unresolved_limit_is_refused():
    """A limit under one grid step (here 1e-9 m against a 0.25 mm grid over a 1 m span) is refused, not printed."""
    model = Linear(1.0, 1e-12)
    ds = _dataset([0.0, 0.5, 1.0])
    with pytest.raises(ValueError, match=r"under one step of its position grid"):
        position_bayes_rmse_m(model, ds, [1], samples=400)


def test_settings_limit_the_draws_never_resolved_is_refused():
    """Positions 100 sigma apart: no draw mixes two, the settings limit would print as rounding (the trial's
    1.4e-11 mm); refused in one line naming the prior to use."""
    ds = _dataset(np.arange(0.05, 0.2001, 0.01))
    with pytest.raises(ValueError, match=r"never mixed two positions; not reported \(use prior='span'\)"):
        position_bayes_rmse_m(Linear(1.0, 1e-4), ds, np.arange(16), samples=200, prior="settings")


def test_unknown_prior_is_refused():
    with pytest.raises(ValueError, match=r"prior must be 'span' or 'settings', not 'flat'"):
        position_bayes_rmse_m(Linear(1.0, 1e-3), _dataset([0.1, 0.2]), [0], prior="flat")


def _staircase_dataset(seed: int = 0) -> Dataset:
    """Readings of a 3-gauge cantilever (moment at each gauge, 2 V per N m, 1 mV noise) under thesis-6.1's loads at
    16 positions 7.4 mm apart: 15-40 sigma between neighbours, as the hand-made PEEK digit's."""
    from flexdigit.tactile.dataset import make_meta
    from flexdigit.tactile.protocols import Protocol

    gauges_m = np.array([0.03, 0.07, 0.15])
    tips = tuple(round(0.0074 * k, 6) for k in range(16))
    protocol = Protocol("staircase", (0.0075, 0.0125, 0.025), tips, (), repetitions=25, no_load_repetitions=0)
    a = 0.2 - np.repeat(np.array(tips), 3 * 25)
    m = np.tile(np.repeat(protocol.loads_kg, 25), len(tips))
    rng = np.random.default_rng(seed)
    moment_n_m = (9.81 * m)[:, None] * np.clip(a[:, None] - gauges_m, 0, None)
    volts = 2.0 * moment_n_m + 1e-3 * rng.standard_normal((a.size, 3))
    cols = {c: np.zeros(a.size, dtype=d) for c, d in dataset_columns(3).items()}
    cols.update(load_kg=m, position_from_base_m=a, position_from_tip_m=0.2 - a, command=np.full(a.size, -1))
    cols["sample"] = np.arange(a.size)
    for k in range(3):
        cols[f"gauge{k + 1}_v"] = volts[:, k]
    return Dataset(cols, make_meta(protocol, {}, 0.2))


@pytest.mark.slow
def test_longer_training_is_kept_only_where_validation_falls():
    """The trial's under-trained class (the PEEK digit's network 1.09 mm at 50 epochs, 0.48 at 800): the chosen
    size is retrained longer and a longer training kept only where its validation MSE is over LONGER_GAIN below
    the thesis's 50-epoch network's (same split, same seeds); never a worse one."""
    from flexdigit.tactile.localisation import LONGER_GAIN, train_network
    from flexdigit.tactile.pipeline import features, run_pipeline, targets

    ds = _staircase_dataset()
    result, rows, _, _ = train_network(ds, "position", hidden=17, tol=1e-7)
    _, y = targets(ds, "position")
    x = features(ds)[rows]
    thesis = run_pipeline(x, y, epochs=50, fixed_hidden=17, fixed_tol=1e-7, curve_hidden=None, target="position")
    val = result.split.val

    def val_mse(r):
        return float(np.mean((r.model.predict(x[val]) - y[val]) ** 2))

    if result.model.epochs == 50:
        assert val_mse(result) == pytest.approx(val_mse(thesis), rel=1e-9)
    else:
        assert result.model.epochs in (100, 200, 400, 800)
        assert val_mse(result) < (1.0 - LONGER_GAIN) * val_mse(thesis)

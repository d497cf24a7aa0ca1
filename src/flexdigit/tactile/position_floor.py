"""The localisation Bayes limit a trained network is compared with: the floor of the scoring it really has.

``flexdigit train --bayes-limit`` scores a position network on its test readings and divides its RMSE by a Bayes
limit. The ratio means something only where the limit is a floor for that scoring, which depends on what the test
readings share with the training ones (:func:`network_floor`):

- ``split="positions"`` (:func:`~flexdigit.tactile.pipeline.held_out_positions_split`): the test loads hang at
  positions no training reading has, so the network must locate a load anywhere on the stretch: the floor is the
  span prior's limit (the position continuous within the protocol's stretch, :func:`~flexdigit.tactile.
  localisation.position_bayes_rmse_m` ``prior="span"``). On a linear gauge it is ``sigma / slope`` in closed form
  and a network trained on the other positions does not beat it (tests/tactile/test_bayes_floor.py).
- ``split="readings"`` (the thesis's shuffle of readings): every test position is a training position, and a
  network can learn the positions themselves (snap to them): its floor is the settings prior's limit (the
  estimator knows the load hangs at one of the protocol's positions; ``prior="settings"``, chapter 6's
  ``protocol_limits`` and the design study's ``bayes_position_limit_mm``). The span limit is no floor for it: the
  hand-made stainless digit's network read 0.18 mm against a 0.71 mm span limit (trial 2). Where the positions
  are so many sigmas apart that the settings limit is unresolved (no Monte Carlo draw mixed two positions), no
  ratio is given: the scoring is then a classification the limit cannot bound from the draws made.

Both limits are returned whichever is compared, with names that say their prior.

On a held-out positions split the span limit's own estimator (the posterior mean that knows the twin's response
exactly, :func:`~flexdigit.tactile.localisation.span_estimator_rmse_m`) is also run on the network's test readings:
it reads the limit where the readings carry the model's noise alone, and more where they carry what the limit does
not count. The thesis's protocols tare once a test (a 774 s run on thesis-6.1) and the twin's amplifiers drift: on
the hand-made digits of trial two it read 1.2-4.3 x the limit (thin shim 2.03 mm against 0.47; 0.44 mm with the
drift off), and a network's ratio there is mostly that. Such a ratio is said (``bayes_limit_note``,
``rmse_over_bayes_estimator``), not taken for the network's own.

The ratio issue 24 asks for (a network within :data:`NETWORK_RATIO_MAX` of "the localisation Bayes limit") is
judged against the limit of what one reading can tell once the protocol's drift is counted
(``bayes_limit_with_drift_mm``, ``rmse_over_compared_limit``, named by ``compared_limit``): between two tares the
gauges' random walk is a nuisance one reading cannot separate from the load, so it is integrated as noise
(:func:`~flexdigit.tactile.localisation.drift_variance_v2`, each reading against the better of its tare and the
run's mean offset). The white-noise figure keeps its name and its ratio (``bayes_limit_mm``,
``rmse_over_bayes_limit``): a floor no network beats, but one no estimator reached on these readings. The
drift-counted limit's own estimator (the twin's response known, the drift's variance in its likelihood) is run on
the same test readings (``bayes_estimator_with_drift_rmse_mm``): where it reads that limit, the limit counts what
the readings carry. A network trained on the same run may read under it (a setting's drift is shared by its
readings and slow along the protocol's order, and a network learns part of it): then the figure is a floor only
for a new run's readings, and the note says so.
"""

from __future__ import annotations

import math

from flexdigit.errors import ParameterError
from flexdigit.tactile.dataset import Dataset
from flexdigit.tactile.localisation import position_bayes_rmse_m, span_estimator_rmse_m
from flexdigit.tactile.pipeline import held_out_positions_split

__all__ = [
    "SPLIT_PRIOR",
    "ESTIMATOR_RTOL",
    "NETWORK_RATIO_MAX",
    "COMPARED_LIMIT",
    "network_floor",
    "split_for_limit",
    "estimator_reaches_limit",
]

#: The prior whose Bayes limit is a floor for a network scored on each split's test readings
SPLIT_PRIOR = {"positions": "span", "readings": "settings"}


#: Issue 24's bound: a trained network's RMSE within this factor of its compared limit (:data:`COMPARED_LIMIT`)
NETWORK_RATIO_MAX = 1.3

#: The limit each split's network is judged against for :data:`NETWORK_RATIO_MAX` (the key of :func:`network_floor`'s
#: dict): held-out positions, the span limit with the run's drift counted; the thesis's readings split, the settings
#: limit (no drift-counted settings limit is computed: a readings split's test settings are training settings)
COMPARED_LIMIT = {"positions": "bayes_limit_with_drift_mm", "readings": "bayes_limit_settings_mm"}

#: The span limit's Monte Carlo and grid (tests/tactile/test_bayes_floor.py's ``LIMIT_RTOL``): the limit's own
#: estimator on ``n`` readings reaches it when its RMSE is under ``1 + 3 / sqrt(2 n) + ESTIMATOR_RTOL`` of it (an
#: RMS of ``n`` Gaussian errors scatters by ``1 / sqrt(2 n)`` of itself)
ESTIMATOR_RTOL = 0.03


def estimator_reaches_limit(estimator_rmse: float, limit: float, n_readings: int) -> bool:
    """Whether the limit's own estimator, scored on ``n_readings`` readings, reads the limit within its scatter
    (:data:`ESTIMATOR_RTOL`)."""
    return estimator_rmse <= limit * (1.0 + 3.0 / math.sqrt(2.0 * max(n_readings, 1)) + ESTIMATOR_RTOL)


def network_floor(model, dataset: Dataset, test_rows, rmse_m: float, *, split: str, seed: int = 0) -> dict:
    """The Bayes limits of a position network's test readings ``test_rows`` and its RMSE (m) over the one that is a
    floor for its ``split`` (:data:`SPLIT_PRIOR`) and over the one issue 24's bound is judged against
    (:data:`COMPARED_LIMIT`).

    Returns a dict (mm; JSON-ready): ``bayes_limit_span_mm`` and ``bayes_limit_settings_mm`` (None where the
    figure is not resolved, with the reason in ``bayes_limit_note``; the settings one only on a ``"readings"``
    split: on held-out positions it would be the limit of an estimator told the test positions),
    ``bayes_limit_prior`` (the prior compared), ``bayes_limit_mm`` (its limit) and ``rmse_over_bayes_limit``
    (None with ``bayes_limit_note`` where that limit is not resolved: a ratio the code cannot stand behind is not
    given). On a ``"positions"`` split also ``bayes_estimator_rmse_mm`` (the span limit's own estimator on the
    test readings), ``rmse_over_bayes_estimator`` and ``bayes_limit_reached`` (whether that estimator reads the
    limit within its scatter, :func:`estimator_reaches_limit`; False is said in the note).

    Then the drift (module docstring): ``bayes_limit_with_drift_mm`` (the span limit with the run's drift counted
    as noise, :func:`~flexdigit.tactile.localisation.position_bayes_rmse_m` ``drift=True``),
    ``rmse_over_bayes_limit_with_drift``, and on held-out positions ``bayes_estimator_with_drift_rmse_mm`` and
    ``bayes_limit_with_drift_reached``; ``compared_limit`` (the key of the limit issue 24's ratio is judged
    against), ``rmse_over_compared_limit`` and ``within_network_ratio_max`` (that ratio within
    :data:`NETWORK_RATIO_MAX`; None where there is no ratio).
    """
    if split not in SPLIT_PRIOR:
        raise ValueError(f"network_floor: split must be one of {sorted(SPLIT_PRIOR)}, not {split!r}")
    limits, notes = {"settings": None}, []
    for prior in ("span", "settings") if split == "readings" else ("span",):
        try:
            limits[prior] = 1e3 * position_bayes_rmse_m(model, dataset, test_rows, seed=seed, prior=prior)
        except ValueError as exc:
            limits[prior] = None
            notes.append(f"{prior}: {exc}")
    prior = SPLIT_PRIOR[split]
    limit = limits[prior]
    out = {
        "bayes_limit_prior": prior,
        "bayes_limit_mm": limit,
        "rmse_over_bayes_limit": 1e3 * rmse_m / limit if limit else None,
        "bayes_limit_span_mm": limits["span"],
        "bayes_limit_settings_mm": limits["settings"],
    }
    if split == "positions" and limit:
        out.update(_estimator_scores(model, dataset, test_rows, rmse_m, limit, notes, drift=False))
    if limit is None:
        notes.append(
            f"no ratio: the {prior} limit is the floor of a network scored on a {split} split and it is not "
            f"resolved{' (train --split positions compares with the span limit)' if split == 'readings' else ''}"
        )
    drift = _drift_scores(model, dataset, test_rows, rmse_m, split=split, seed=seed, settings_mm=limits["settings"],
                          notes=notes)  # fmt: skip
    out.update(drift)
    if notes:
        out["bayes_limit_note"] = "; ".join(notes)
    return out


def _estimator_scores(model, dataset, test_rows, rmse_m: float, limit_mm: float, notes: list, *, drift: bool) -> dict:
    """The span limit's own estimator (``drift``: the drift-counted limit's) on the test readings, its ratio and
    whether it reads its limit; a miss said in ``notes``."""
    estimator = 1e3 * span_estimator_rmse_m(model, dataset, test_rows, drift=drift)
    reached = estimator_reaches_limit(estimator, limit_mm, len(test_rows))
    if drift:
        if not reached:
            notes.append(
                f"the drift-counted limit's own estimator reads {estimator:.3g} mm on these test readings, "
                f"{estimator / limit_mm:.2f} x that limit: the readings carry more than its noise model (a twin unlike "
                "the digit, or the drift's realisation over few settings far from its average)"
            )
        return {"bayes_estimator_with_drift_rmse_mm": estimator, "bayes_limit_with_drift_reached": reached}
    if not reached:
        notes.append(
            f"the limit's own estimator (the twin's response known) reads {estimator:.3g} mm on these test "
            f"readings, {estimator / limit_mm:.2f} x the limit: the readings carry noise the limit does not count "
            "(the gauges' drift since their tare, or a twin unlike the digit); the ratio is not the network's "
            "alone"
        )
    return {
        "bayes_estimator_rmse_mm": estimator,
        "rmse_over_bayes_estimator": 1e3 * rmse_m / estimator,
        "bayes_limit_reached": reached,
    }


def _drift_scores(model, dataset, test_rows, rmse_m: float, *, split: str, seed: int, settings_mm, notes) -> dict:
    """:func:`network_floor`'s drift-counted limit, its estimator (held-out positions) and issue 24's ratio."""
    try:
        drift = 1e3 * position_bayes_rmse_m(model, dataset, test_rows, seed=seed, drift=True)
    except ValueError as exc:  # unresolved, as the span limit
        drift = None
        notes.append(f"drift counted: {exc}")
    out = {
        "bayes_limit_with_drift_mm": drift,
        "rmse_over_bayes_limit_with_drift": 1e3 * rmse_m / drift if drift else None,
    }
    if split == "positions" and drift:
        out.update(_estimator_scores(model, dataset, test_rows, rmse_m, drift, notes, drift=True))
    key = COMPARED_LIMIT[split]
    compared = {"bayes_limit_with_drift_mm": drift, "bayes_limit_settings_mm": settings_mm}[key]
    ratio = 1e3 * rmse_m / compared if compared else None
    out.update(
        {
            "compared_limit": key,
            "rmse_over_compared_limit": ratio,
            "within_network_ratio_max": None if ratio is None else bool(ratio <= NETWORK_RATIO_MAX),
        }
    )
    if ratio is not None and key == "bayes_limit_with_drift_mm" and ratio < 1.0:
        notes.append(
            "the network reads under the drift-counted limit: it learnt part of this run's drift (a setting's drift "
            "is shared by its readings and slow along the protocol's order); that limit is a floor for a new run's "
            "readings, and the white-noise ratio (rmse_over_bayes_limit) is this run's floor"
        )
    return out


def split_for_limit(dataset: Dataset) -> str:
    """The split ``train --bayes-limit`` scores a position network on by default: ``"positions"`` where the
    dataset's loaded positions can be held out (:func:`~flexdigit.tactile.pipeline.held_out_positions_split`: 5 or
    more, two of them interior), so the network is compared with the span limit; else ``"readings"`` (compared with
    the settings limit, :func:`network_floor`)."""
    loaded = dataset["load_kg"] > 0
    try:
        held_out_positions_split(dataset["position_from_base_m"][loaded], seed=0)
    except ParameterError:
        return "readings"
    return "positions"

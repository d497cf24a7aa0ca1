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
"""

from __future__ import annotations

import math

from flexdigit.errors import ParameterError
from flexdigit.tactile.dataset import Dataset
from flexdigit.tactile.localisation import position_bayes_rmse_m, span_estimator_rmse_m
from flexdigit.tactile.pipeline import held_out_positions_split

__all__ = ["SPLIT_PRIOR", "ESTIMATOR_RTOL", "network_floor", "split_for_limit", "estimator_reaches_limit"]

#: The prior whose Bayes limit is a floor for a network scored on each split's test readings
SPLIT_PRIOR = {"positions": "span", "readings": "settings"}


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
    floor for its ``split`` (:data:`SPLIT_PRIOR`).

    Returns a dict (mm; JSON-ready): ``bayes_limit_span_mm`` and ``bayes_limit_settings_mm`` (None where the
    figure is not resolved, with the reason in ``bayes_limit_note``; the settings one only on a ``"readings"``
    split: on held-out positions it would be the limit of an estimator told the test positions),
    ``bayes_limit_prior`` (the prior compared), ``bayes_limit_mm`` (its limit) and ``rmse_over_bayes_limit``
    (None with ``bayes_limit_note`` where that limit is not resolved: a ratio the code cannot stand behind is not
    given). On a ``"positions"`` split also ``bayes_estimator_rmse_mm`` (the span limit's own estimator on the
    test readings), ``rmse_over_bayes_estimator`` and ``bayes_limit_reached`` (whether that estimator reads the
    limit within its scatter, :func:`estimator_reaches_limit`; False is said in the note).
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
        estimator = 1e3 * span_estimator_rmse_m(model, dataset, test_rows)
        reached = estimator_reaches_limit(estimator, limit, len(test_rows))
        out["bayes_estimator_rmse_mm"] = estimator
        out["rmse_over_bayes_estimator"] = 1e3 * rmse_m / estimator
        out["bayes_limit_reached"] = reached
        if not reached:
            notes.append(
                f"the limit's own estimator (the twin's response known) reads {estimator:.3g} mm on these test "
                f"readings, {estimator / limit:.2f} x the limit: the readings carry noise the limit does not count "
                "(the gauges' drift since their tare, or a twin unlike the digit); the ratio is not the network's "
                "alone"
            )
    if limit is None:
        notes.append(
            f"no ratio: the {prior} limit is the floor of a network scored on a {split} split and it is not "
            f"resolved{' (train --split positions compares with the span limit)' if split == 'readings' else ''}"
        )
    if notes:
        out["bayes_limit_note"] = "; ".join(notes)
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

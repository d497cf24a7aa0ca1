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
"""

from __future__ import annotations

from flexdigit.errors import ParameterError
from flexdigit.tactile.dataset import Dataset
from flexdigit.tactile.localisation import position_bayes_rmse_m
from flexdigit.tactile.pipeline import held_out_positions_split

__all__ = ["SPLIT_PRIOR", "network_floor", "split_for_limit"]

#: The prior whose Bayes limit is a floor for a network scored on each split's test readings
SPLIT_PRIOR = {"positions": "span", "readings": "settings"}


def network_floor(model, dataset: Dataset, test_rows, rmse_m: float, *, split: str, seed: int = 0) -> dict:
    """The Bayes limits of a position network's test readings ``test_rows`` and its RMSE (m) over the one that is a
    floor for its ``split`` (:data:`SPLIT_PRIOR`).

    Returns a dict (mm; JSON-ready): ``bayes_limit_span_mm`` and ``bayes_limit_settings_mm`` (None where the
    figure is not resolved, with the reason in ``bayes_limit_note``; the settings one only on a ``"readings"``
    split: on held-out positions it would be the limit of an estimator told the test positions),
    ``bayes_limit_prior`` (the prior compared), ``bayes_limit_mm`` (its limit) and ``rmse_over_bayes_limit``
    (None with ``bayes_limit_note`` where that limit is not resolved: a ratio the code cannot stand behind is not
    given).
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

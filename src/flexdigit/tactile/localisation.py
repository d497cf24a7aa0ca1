"""Beyond the thesis's corr2: localisation in millimetres against the Cramer-Rao bound, contact and magnitude.

:func:`localisation_study` puts four estimators side by side on identical data (the thesis's split of one
dataset, readings tared on each test's no-load readings): an MLP of the thesis's architecture trained on the
position in metres, the beam-model inversion (mass free, or from the protocol's load set) and the Gaussian
process (:mod:`flexdigit.tactile.estimators`). Each test reading also gets the Cramer-Rao bound of its position
and its identifiability zone (:mod:`flexdigit.tactile.bounds`), so the errors are compared with what the gauges
physically allow, only where the load can be located at all.

Note on the bound: it is the floor for an *unbiased* estimate of a continuous position and mass from one reading.
Estimators trained on a protocol learn that masses (and positions) come from a short list and can beat it on
that protocol's data; the free-mass beam inversion assumes nothing of the sort and cannot.
"""

from __future__ import annotations

import contextlib
import warnings
from dataclasses import dataclass, field

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.tactile.accuracy import accuracy, corr2, rmse
from flexdigit.tactile.bounds import (
    ZONES,
    cramer_rao,
    protocol_limits,
    readings_gauge_model,
    span_position_mse_m2,
    span_posterior_mean_m,
)
from flexdigit.tactile.dataset import Dataset
from flexdigit.tactile.estimators import BeamInversion, GPLocaliser
from flexdigit.tactile.network_sizes import EPOCHS_MAX, LONGER_GAIN
from flexdigit.tactile.pipeline import (
    Split,
    ThesisNetwork,
    features,
    held_out_positions_split,
    run_pipeline,
    targets,
    thesis_split,
)
from flexdigit.tactile.prediction_plot import target_unit

__all__ = [
    "ESTIMATORS",
    "CONTACT_CHI2",
    "tare",
    "reading_zones",
    "LocalisationResult",
    "localisation_study",
    "bayes_limits",
    "readings_gauge_model",
    "position_bayes_rmse_m",
    "span_estimator_rmse_m",
    "drift_variance_v2",
    "drift_referenced_readings",
    "SPAN_GRID_MAX",
    "SPAN_RESOLVED_STEPS",
    "SETTINGS_RESOLVED",
    "train_network",
    "bending_gauges",
    "located_validation",
    "BEND_SIGMAS",
    "BEND_SHARE",
    "EPOCHS_MAX",
    "LONGER_GAIN",
    "Prediction",
    "predict_dataset",
    "identifiability_map",
]

ESTIMATORS = ("MLP (thesis architecture)", "beam inversion", "beam inversion, known load set", "Gaussian process")
#: chi-square(2 dof) 99.9 % quantile: a load is declared when it explains the reading this much better than none
CONTACT_CHI2 = 13.8155


def tare(dataset: Dataset) -> tuple[Dataset, np.ndarray]:
    """Subtract from every reading the mean of the no-load readings taken before it in its test (6.5, 7.2).

    The no-load readings of a test come in blocks (one at its start in the thesis's protocols; one before every
    position with ``tare_each_position``); a reading is tared on the last block before it (in sample order) or,
    between two blocks, on the two interpolated in time to it (the drift between them removed, as a lab brackets
    a weighing with two zero readings), a reading of a block on its own block, and a test's readings before its
    first block (an imported file's order) on the mean of all its no-load readings. Tests without no-load
    readings are left as they are; the thesis's layout (one block, at the start) is tared as it always was.

    Returns the tared dataset and, per reading, the seconds since its tare (the nearer tare block's mean time;
    since the first reading for tests without no-load readings; 0 when the readings have no times, e.g.
    imported).
    """
    gauges = dataset.gauges_v.copy()
    time = dataset["time_s"]
    if not np.all(np.isfinite(time)):  # readings imported without times: none accrues drift since its tare
        time = np.zeros(len(dataset))
    since = time - time.min()
    order = np.argsort(dataset["sample"], kind="stable")
    unloaded = dataset["load_kg"] == 0
    for test in np.unique(dataset["test"]):
        rows = order[dataset["test"][order] == test]  # the test's readings in sample order
        zero = np.flatnonzero(unloaded[rows])  # where its no-load readings are in that order
        if not zero.size:
            continue
        first = np.r_[True, np.diff(zero) != 1]  # a block starts where the no-load run does
        block = np.cumsum(first) - 1  # each no-load reading's block
        blocks = [rows[zero[block == b]] for b in range(int(block[-1]) + 1)]
        refs = [(gauges[b].mean(axis=0), time[b].mean()) for b in blocks]
        whole = (gauges[rows[zero]].mean(axis=0), time[rows[zero]].mean())
        last = np.searchsorted(zero, np.arange(rows.size), side="right") - 1  # the last no-load reading at or before
        for row, k in zip(rows, last, strict=True):
            ref, ref_t = whole if k < 0 else refs[block[k]]
            after = int(block[k]) + 1 if k >= 0 else len(refs)
            if k >= 0 and not unloaded[row] and after < len(refs) and time[rows[zero[block == after]][0]] > ref_t:
                # a block after it too (a tare before each position): the drift between the two, interpolated in time
                ref2, t2 = refs[after]
                w = (time[row] - ref_t) / (t2 - ref_t)
                ref, since[row] = (1.0 - w) * ref + w * ref2, min(abs(time[row] - ref_t), abs(t2 - time[row]))
            else:
                since[row] = abs(time[row] - ref_t)
            gauges[row] = gauges[row] - ref
    columns = dict(dataset.columns)
    for i, name in enumerate(dataset.gauge_columns):
        columns[name] = gauges[:, i]
    return Dataset(columns, dict(dataset.meta)), since


def train_network(
    dataset: Dataset, target: str, *, seed: int = 0, hidden=None, tol=None, epochs: int = 50, split: str = "readings"
):
    """``flexdigit train``'s network: the thesis's pipeline (:func:`~flexdigit.tactile.pipeline.run_pipeline`, no
    error curves) on the dataset's G gauges and, on an actuated protocol, the command.

    On a dataset with no-load readings (a block at the start of every test, as the thesis's "no load condition
    ... measured at the start of every test", 6.5; or one before each position, ``tare_each_position``) the
    network is trained on the readings as read and on the tared ones (:func:`tare`), with the same split and
    seeds, and the one with the lower validation error is kept, as the thesis chose its hidden nodes: a tare
    removes the drift before it but adds its own block's noise to every reading it tares, and which weighs more
    depends on the digit and the run (a one-gauge digit's network: 1.44 x its Bayes limit as read, 1.14 tared; a
    12-bit six-gauge one's 1.03 as read, 1.36 tared). The test readings are not looked at.

    The size and tolerance are swept at ``epochs`` (the thesis's 50); the chosen size is then trained again
    (its tolerance swept again, unless given) with twice, four times ... the epochs up to :data:`EPOCHS_MAX`,
    and a longer training is kept where it lowers the validation error by more than :data:`LONGER_GAIN`. The
    thesis rig's 3 gauges at 2.7 mm are learnt in 50 epochs; a digit that resolves its positions many times
    finer is not: the hand-made PEEK digit's network went from 1.09 mm at 50 epochs to 0.48 at 800
    (docs/digits.md, tactile section).

    ``split``: ``"readings"`` the thesis's (:func:`~flexdigit.tactile.pipeline.thesis_split`: the test positions
    are training positions too), ``"positions"`` the validation and test readings at positions the network never
    saw (:func:`~flexdigit.tactile.pipeline.held_out_positions_split`; a position target only): the scoring the
    span Bayes limit is a floor for (:mod:`flexdigit.tactile.position_floor`). Its networks are chosen (and
    stopped early) on the validation readings whose load the gauges can locate (:func:`located_validation`).

    Returns ``(result, rows, inputs, tared)``: the pipeline's result, the dataset rows with the target, the inputs'
    column names (what ``predict`` reads) and whether the kept network reads tared readings.
    """
    rows, y = targets(dataset, target)
    actuated = dataset.protocol.actuated
    inputs = [*dataset.gauge_columns] + (["command"] if actuated else [])
    options = {"seed": seed, "target": target, "curve_hidden": None}
    if split == "positions":
        if target != "position":
            raise ParameterError(f"a held-out positions split scores a position network, not {target!r}")
        held = held_out_positions_split(dataset["position_from_base_m"][rows], seed)
        options["split"] = located_validation(held, dataset, rows)
    elif split != "readings":
        raise ParameterError(f"train_network's split must be 'readings' or 'positions', not {split!r}")
    best = None
    for tared in (False, True) if _has_tares(dataset) else (False,):
        readings = tare(dataset)[0] if tared else dataset
        x = features(readings, with_command=actuated)[rows]
        result = run_pipeline(x, y, epochs=epochs, fixed_hidden=hidden, fixed_tol=tol, **options)
        val_mse = _val_mse(result, x, y)
        if best is None or val_mse < best[0]:
            best = (val_mse, result, tared, x)
    val_mse, result, tared, x = best
    longer = epochs
    while 2 * longer <= EPOCHS_MAX:
        longer *= 2  # the chosen size trained longer, its tolerance swept again (unless given)
        trial = run_pipeline(x, y, epochs=longer, fixed_hidden=result.best_hidden, fixed_tol=tol, **options)
        trial_mse = _val_mse(trial, x, y)
        if trial_mse < (1.0 - LONGER_GAIN) * val_mse:
            val_mse, result = trial_mse, trial
    return result, rows, inputs, tared


#: A gauge bends under a setting's load where the setting's mean tared reading departs from its tare by more than
#: this many of the gauge's no-load standard deviations (:func:`bending_gauges`) ...
BEND_SIGMAS = 5.0
#: ... and by more than this share of the largest departure the gauge reads over the dataset's settings: the drift
#: since the tare stays under it (thick_stiff_strong_servo's gauge 2 drifted 0.6 mV, 3 sds, against its 20 mV).
BEND_SHARE = 0.05


def bending_gauges(dataset: Dataset) -> np.ndarray:
    """How many gauges each reading's load bends (0 for a no-load reading), read from the dataset alone: a gauge
    bends at a setting (position, mass, command, test) where its readings' mean, tared (:func:`tare`), departs by
    more than :data:`BEND_SIGMAS` of the gauge's no-load standard deviation and :data:`BEND_SHARE` of its largest
    departure. The thesis's zones (:data:`~flexdigit.tactile.bounds.ZONES`) in data: on a cantilever no moment
    reaches a gauge past the load, so a load bending one gauge tells the moment there, ``m g (a - x)``, and not its
    position and mass apart; two gauges or more locate it."""
    gauges = tare(dataset)[0].gauges_v
    loaded = dataset["load_kg"] > 0
    count = np.zeros(len(dataset), dtype=int)
    if not np.any(loaded) or np.all(loaded):
        return count
    spread = [gauges[(~loaded) & (dataset["test"] == t)] for t in np.unique(dataset["test"][~loaded])]
    sd = np.sqrt(np.mean([np.var(v, axis=0, ddof=1) for v in spread if len(v) > 1] or [np.zeros(gauges.shape[1])], 0))
    keys = np.column_stack([np.round(dataset["position_from_base_m"], 6), dataset["load_kg"], dataset["command"],
                            dataset["test"]])[loaded]  # fmt: skip
    _, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    means = np.stack([gauges[loaded][inverse == k].mean(axis=0) for k in range(inverse.max() + 1)])
    departure = np.abs(means)
    bends = (departure > BEND_SIGMAS * sd) & (departure > BEND_SHARE * departure.max(axis=0))
    count[loaded] = bends.sum(axis=1)[inverse]
    return count


def located_validation(split: Split, dataset: Dataset, rows) -> Split:
    """A held-out positions ``split`` of ``dataset``'s ``rows`` (:func:`~flexdigit.tactile.pipeline.
    held_out_positions_split`) with its validation readings those whose load bends two gauges or more
    (:func:`bending_gauges`; one where the protocol hangs a single mass: the moment then tells the lever): what
    chooses a network's size and tolerance and stops its training early. A reading bending one gauge of a protocol
    of several masses cannot be located by any estimator (a 7.5 g load 147 mm from thick_stiff_strong_servo's base
    reads as 12.5 g at 110 mm: gauge 2 is at 165 mm), its error is the mix-up's whatever the network, and where such
    readings are most of the validation set they choose networks by chance: its three confounded validation
    positions held every size's validation RMSE at 11.5-13.4 mm while the test RMSE went 6.7-33 mm. The test
    readings are kept whole (the limit counts the mix-up). The split itself where no validation reading drops or
    fewer than two validation positions would stay (a one-gauge digit)."""
    rows = np.asarray(rows, dtype=int)
    masses = np.unique(dataset["load_kg"][dataset["load_kg"] > 0])
    need = 2 if masses.size > 1 else 1  # one load of the protocol's mass: one gauge's moment locates it
    located = split.val[bending_gauges(dataset)[rows[split.val]] >= need]
    if (
        located.size == split.val.size
        or np.unique(np.round(dataset["position_from_base_m"][rows[located]], 6)).size < 2
    ):
        return split
    return Split(split.train, located, split.test)


def _has_tares(dataset: Dataset) -> bool:
    """Whether every test of ``dataset`` has no-load readings to tare on (:func:`tare` leaves a test without any
    as read)."""
    unloaded = dataset["load_kg"] == 0
    tests = dataset["test"]
    return bool(len(dataset)) and all(np.any(unloaded[tests == t]) for t in np.unique(tests))


def _val_mse(result, x, y) -> float:
    """The validation readings' mean squared error of a pipeline's network (what chooses among networks)."""
    val = result.split.val
    return float(np.mean((result.model.predict(x[val]) - y[val]) ** 2))


@dataclass(frozen=True)
class Prediction:
    """A saved network's predictions on a dataset (:func:`predict_dataset`, ``flexdigit predict``).

    Attributes
    ----------
    target : str
    rows : ndarray of int
        The dataset rows with the target (the loaded readings for a position or a magnitude).
    predicted, actual : ndarray
        The network's and the dataset's values of the target, in its SI unit (m from the tip, kg, ...).
    scores : dict
        ``corr2`` and ``rmse`` (the target's SI unit), and ``rmse_<unit>`` where the target has a display unit
        (``rmse_mm``, ``rmse_g``).
    notes : tuple of str
        Per prediction, ``""`` or why it is suspect: a position outside the digit (0..its length from the tip,
        the dataset's ``digit_length_m``) or outside the span of positions the network was trained on (its
        ``meta["position_span_m"]``), by more than the predictions' RMSE: an extrapolation, not a reading of the
        gauges (trial 3: 0.33 m on a 0.30 m digit).
    """

    target: str
    rows: np.ndarray
    predicted: np.ndarray
    actual: np.ndarray
    scores: dict
    notes: tuple = ()

    __repr__ = fields_summary


def predict_dataset(saved, dataset: Dataset, *, source: str = "the dataset") -> Prediction:
    """Predict ``saved``'s target (a :class:`~flexdigit.tactile.model_io.SavedModel`) on every reading of
    ``dataset`` that has it, reading the inputs as the network was trained: tared when it was (``meta["tared"]``,
    :func:`train_network`), as read otherwise; scored by corr2 and the RMSE.

    Raises
    ------
    DataFileError
        If the dataset lacks a column the model reads (named, with ``source``).
    """
    missing = [c for c in saved.inputs if c not in dataset.columns]
    if missing:
        raise DataFileError(f"{source}: the model needs column '{missing[0]}'")
    rows, actual = targets(dataset, saved.target)
    readings = tare(dataset)[0] if saved.meta.get("tared") is True else dataset
    x = np.column_stack([readings[c].astype(float) for c in saved.inputs])[rows]
    predicted = saved.network.predict(x)
    scores = {"corr2": corr2(predicted, actual), "rmse": rmse(predicted, actual)}
    _, unit, scale = target_unit(saved.target)
    if unit:
        scores[f"rmse_{unit}"] = scale * scores["rmse"]
    position = saved.target == "position"
    notes = _position_notes(predicted, dataset, saved, scores["rmse"]) if position else ("",) * len(rows)
    return Prediction(saved.target, rows, predicted, actual, scores, notes)


def _position_notes(predicted, dataset: Dataset, saved, margin_m: float) -> tuple[str, ...]:
    """:attr:`Prediction.notes` of positions from the tip (m): outside the digit or the trained span by more than
    ``margin_m`` (the predictions' own RMSE: a position a few mm past the tip is the network's scatter)."""
    length = dataset.meta.get("digit_length_m")
    span = saved.meta.get("position_span_m")
    m = float(margin_m) if np.isfinite(margin_m) else 0.0
    notes = []
    for p in np.asarray(predicted, dtype=float):
        if isinstance(length, int | float) and not -m <= p <= length + m:
            notes.append(f"outside the digit (0 to {1e3 * length:g} mm from the tip)")
        elif isinstance(span, list | tuple) and len(span) == 2 and not span[0] - m <= p <= span[1] + m:
            notes.append(f"outside the trained positions ({1e3 * span[0]:g} to {1e3 * span[1]:g} mm from the tip)")
        else:
            notes.append("")
    return tuple(notes)


def reading_zones(model, dataset: Dataset, since_tare_s=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Zone, position CRLB (mass unknown) and CRLB (mass known) of every reading (no-load rows: zone ``""``).

    With ``since_tare_s`` and a model with ``drift_v_per_sqrt_s``, each reading's noise is the model's (white,
    and the cable-guide friction when the cable is taut) plus the random-walk drift accumulated since its tare:
    ``sigma^2 = sigma_model^2 + rate^2 t``.
    """
    n = len(dataset)
    zone = np.full(n, "", dtype=object)
    crlb = np.full(n, np.nan)
    crlb_known = np.full(n, np.nan)
    loaded = np.flatnonzero(dataset["load_kg"] > 0)
    rate = np.asarray(getattr(model, "drift_v_per_sqrt_s", np.zeros(3)), dtype=float)
    since = np.zeros(n) if since_tare_s is None else np.asarray(since_tare_s, dtype=float)
    keys = np.column_stack([dataset["position_from_base_m"], dataset["load_kg"], dataset["command"], dataset["test"]])
    settings, inverse = np.unique(keys[loaded], axis=0, return_inverse=True)
    for k, (a, m, c, _) in enumerate(settings):
        rows = loaded[inverse.ravel() == k]
        b = cramer_rao(model, [a], m, int(c), extra_variance_v2=rate**2 * float(np.mean(since[rows])))
        zone[rows], crlb[rows], crlb_known[rows] = b.zone[0], b.crlb_m[0], b.crlb_known_mass_m[0]
    return zone, crlb, crlb_known


@dataclass
class LocalisationResult:
    """Scores of every estimator on the same test readings (see :func:`localisation_study`)."""

    test_rows: np.ndarray
    zone: np.ndarray
    crlb_m: np.ndarray
    crlb_known_mass_m: np.ndarray
    position_pred_m: dict[str, np.ndarray]
    position_true_m: np.ndarray
    mass_pred_kg: dict[str, np.ndarray]
    mass_true_kg: np.ndarray
    position_rmse_m: dict[str, float]
    position_rmse_identifiable_m: dict[str, float]
    crlb_rms_identifiable_m: float
    crlb_known_rms_identifiable_m: float
    magnitude_rel_rmse: dict[str, float]
    magnitude_rel_rmse_identifiable: dict[str, float]
    contact_accuracy: dict[str, float]
    contact_accuracy_visible: dict[str, float]
    gp_std_m: np.ndarray
    bayes: dict = field(default_factory=dict)
    extra: dict = field(default_factory=dict)

    @property
    def best(self) -> str:
        """The estimator with the lowest position RMSE over identifiable readings."""
        return min(self.position_rmse_identifiable_m, key=self.position_rmse_identifiable_m.get)

    __repr__ = fields_summary


def localisation_study(
    dataset: Dataset,
    model,
    *,
    seed: int = 0,
    hidden: int = 18,
    tol: float = 1e-7,
    epochs: int = 50,
    digit_length_m: float | None = None,
    fast: bool = False,
) -> LocalisationResult:
    """Position, magnitude and contact by the three estimators on the thesis split of ``dataset``.

    Parameters
    ----------
    dataset : Dataset
        Readings of one protocol (with no-load readings for the contact scores).
    model : gauge model
        The static gauge model and noise (the twin's, :class:`~flexdigit.tactile.bounds.TwinGaugeModel`).
    seed : int
        Seeds the split (same as the thesis pipeline's for the same seed) and every estimator.
    hidden, tol, epochs : thesis MLP settings.
    digit_length_m : float, optional
        Clamp to tip (default: from the dataset's metadata).
    fast : bool
        Coarser inversion grid (2 mm, 41 masses) and a 200-reading GP: for tests.
    """
    length = float(digit_length_m or dataset.meta.get("digit_length_m", 0.270))
    actuated = dataset.protocol.actuated
    raw = dataset
    dataset, since = tare(dataset)
    x = features(dataset, with_command=actuated)
    split = thesis_split(len(dataset), seed)
    mass = dataset["load_kg"]
    loaded = mass > 0
    pos = np.nan_to_num(dataset["position_from_tip_m"], nan=0.0)
    tr, va, te = (rows[loaded[rows]] for rows in (split.train, split.val, split.test))
    zone, crlb, crlb_known = reading_zones(model, raw, since)
    mlps = _fit_networks(x, pos, mass, loaded, split, tr, va, seed, hidden, tol, epochs)
    pos_pred, mass_pred, contact_pred, gp_std = _predictions(model, mlps, x, pos, mass, loaded, split, tr, va, te,
                                                             length, seed, fast)  # fmt: skip
    ident = zone[te] == ZONES[2]
    pos_true, mass_true = pos[te], mass[te]
    visible = zone[split.test] != ZONES[0]
    contact_true = loaded.astype(float)[split.test]
    with _empty_means_are_nan(not ident.any()):
        return _result(
            model, raw, split, te, zone, crlb, crlb_known, pos_pred, pos_true, mass_pred, mass_true, gp_std, ident,
            visible, contact_pred, contact_true, seed,
        )  # fmt: skip


@contextlib.contextmanager
def _empty_means_are_nan(empty: bool):
    """With no identifiable test reading (a single gauge cannot tell a load's position from its mass: trial 3's
    one-quarter-gauge pair), the identifiable figures are means over nothing: NaN by definition (the report says
    "not applicable"), without numpy's "Mean of empty slice" reaching the user."""
    if not empty:
        yield
        return
    with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
        warnings.filterwarnings("ignore", "Mean of empty slice", RuntimeWarning)
        warnings.filterwarnings("ignore", "invalid value encountered", RuntimeWarning)
        yield


def _result(model, raw, split, te, zone, crlb, crlb_known, pos_pred, pos_true, mass_pred, mass_true, gp_std, ident,
            visible, contact_pred, contact_true, seed):  # fmt: skip
    """:func:`localisation_study`'s result from its predictions and bounds."""
    return LocalisationResult(
        test_rows=te,
        zone=zone[te],
        crlb_m=crlb[te],
        crlb_known_mass_m=crlb_known[te],
        position_pred_m=pos_pred,
        position_true_m=pos_true,
        mass_pred_kg=mass_pred,
        mass_true_kg=mass_true,
        crlb_rms_identifiable_m=float(np.sqrt(np.mean(crlb[te][ident] ** 2))),
        crlb_known_rms_identifiable_m=float(np.sqrt(np.mean(crlb_known[te][ident] ** 2))),
        gp_std_m=gp_std[:, 0],
        bayes=_bayes_limits(model, raw, split.test, te[ident], split.test[visible], seed),
        extra={
            "split": split,
            "identifiable_fraction": float(np.mean(ident)),
            "zone_all": zone,
            "crlb_all_m": crlb,
            "contact_pred": contact_pred,
            "contact_rows": split.test,
            "contact_visible": visible,
        },
        **_scores(pos_pred, pos_true, mass_pred, mass_true, contact_pred, contact_true, ident, visible),
    )


def _fit_networks(x, pos, mass, loaded, split, tr, va, seed: int, hidden: int, tol: float, epochs: int):
    """The thesis-architecture networks for position (loaded readings), magnitude and contact (all readings)."""
    rng = np.random.default_rng([seed, 7])
    mlp_pos = ThesisNetwork(hidden=hidden, tol=tol, epochs=epochs, random_state=int(rng.integers(2**31)))
    mlp_pos.fit(x[tr], pos[tr], x[va], pos[va])
    mlp_mass = ThesisNetwork(hidden=hidden, tol=tol, epochs=epochs, random_state=int(rng.integers(2**31)))
    mlp_mass.fit(x[split.train], mass[split.train], x[split.val], mass[split.val])
    mlp_contact = ThesisNetwork(hidden=hidden, tol=tol, epochs=epochs, random_state=int(rng.integers(2**31)))
    contact = loaded.astype(float)
    mlp_contact.fit(x[split.train], contact[split.train], x[split.val], contact[split.val])
    return mlp_pos, mlp_mass, mlp_contact


def _predictions(model, mlps, x, pos, mass, loaded, split, tr, va, te, length: float, seed: int, fast: bool):
    """Each estimator's position and magnitude on the loaded test readings, and contact on all test readings.

    Also the Gaussian process's standard deviations (position, magnitude) on the loaded test readings.
    """
    mlp_pos, mlp_mass, mlp_contact = mlps
    y = np.column_stack([pos, mass])
    trva = np.concatenate([tr, va])
    grid = {"position_step_m": 2e-3, "mass_steps": 41} if fast else {}
    inversion = BeamInversion(model, digit_length_m=length, max_mass_kg=2.0 * float(mass.max()), tared=True, **grid)
    inversion.fit(x[trva], y[trva])
    known_set = BeamInversion(model, digit_length_m=length, load_set=True, tared=True, **grid).fit(x[trva], y[trva])
    set_pred = known_set.predict(x[te])
    gp = GPLocaliser(random_state=seed, max_train=200 if fast else 500).fit(x[trva], y[trva])

    inv_all, inv_cost = inversion.predict(x[split.test], return_cost=True)
    gp_all, gp_std = gp.predict(x[te], return_std=True)
    pos_pred = {
        "MLP (thesis architecture)": mlp_pos.predict(x[te]),
        "beam inversion": inv_all[loaded[split.test], 0],
        "beam inversion, known load set": set_pred[:, 0],
        "Gaussian process": gp_all[:, 0],
    }
    mass_pred = {
        "MLP (thesis architecture)": mlp_mass.predict(x[te]),
        "beam inversion": inv_all[loaded[split.test], 1],
        "beam inversion, known load set": set_pred[:, 1],
        "Gaussian process": gp_all[:, 1],
    }
    # contact: the thesis-style network thresholded at 0.5; the inversion's likelihood-ratio test against no load
    no_load_cost = inversion.no_load_cost(x[split.test])
    contact_pred = {
        "MLP (thesis architecture)": (mlp_contact.predict(x[split.test]) >= 0.5).astype(float),
        "beam inversion": (no_load_cost - inv_cost > CONTACT_CHI2).astype(float),
    }
    return pos_pred, mass_pred, contact_pred, gp_std


def _rel_rmse(p, t) -> float:
    """Root mean square of the relative error ``(p - t) / t`` (NaN for no readings)."""
    return float(np.sqrt(np.mean(((p - t) / t) ** 2))) if t.size else float("nan")


def _scores(pos_pred, pos_true, mass_pred, mass_true, contact_pred, contact_true, ident, visible) -> dict:
    """Each estimator's scores: on all its test readings, and on the identifiable (visible, for contact) ones."""
    return dict(
        position_rmse_m={k: rmse(v, pos_true) for k, v in pos_pred.items()},
        position_rmse_identifiable_m={k: rmse(v[ident], pos_true[ident]) for k, v in pos_pred.items()},
        magnitude_rel_rmse={k: _rel_rmse(v, mass_true) for k, v in mass_pred.items()},
        magnitude_rel_rmse_identifiable={k: _rel_rmse(v[ident], mass_true[ident]) for k, v in mass_pred.items()},
        contact_accuracy={k: accuracy(v, contact_true) for k, v in contact_pred.items()},
        contact_accuracy_visible={k: accuracy(v[visible], contact_true[visible]) for k, v in contact_pred.items()},
    )


def _bayes_limits(model, raw: Dataset, test_rows, ident_rows, visible_rows, seed: int) -> dict:
    """The Bayes limits of position, magnitude and contact on the test readings.

    Each with the prior of the readings it is scored on (more knowledge than any estimator has, so a floor for
    every estimator scored on those readings): identifiable loads; visible readings; all readings.
    """

    def limit(rows):
        lim = bayes_limits(model, raw, rows, seed=seed)
        return lim, lim.index(raw["position_from_base_m"][rows], raw["load_kg"][rows], raw["command"][rows])

    lim_id, k_id = limit(ident_rows)
    lim_vis, k_vis = limit(visible_rows)
    lim_all, k_all = limit(test_rows)
    return {
        "position_rmse_identifiable_m": float(np.sqrt(np.mean(lim_id.position_mse_m2[k_id]))),
        "magnitude_rel_rmse_identifiable": float(np.sqrt(np.mean(lim_id.magnitude_rel_mse[k_id]))),
        "contact_accuracy_visible": float(1.0 - np.mean(lim_vis.contact_error[k_vis])),
        "contact_accuracy": float(1.0 - np.mean(lim_all.contact_error[k_all])),
        "limits_identifiable": lim_id,
    }


def bayes_limits(model, dataset: Dataset, rows=None, *, samples: int = 4000, seed: int = 0):
    """:func:`~flexdigit.tactile.bounds.protocol_limits` on the distinct settings of ``dataset`` (or of its
    ``rows``), weighted by how often each occurs in the whole dataset: what the best estimator that knows the
    protocol, and that the reading is one of those settings, could score on them.

    The no-load readings carry the model's white noise only: they are read one after another after the weights
    are lifted (the protocols re-hang only loaded readings), so they share one cable-guide friction state, which
    the tare on their mean removes.
    """
    mass = dataset["load_kg"]
    a = np.where(mass > 0, np.nan_to_num(dataset["position_from_base_m"], nan=0.0), 0.0)
    all_keys = np.column_stack([np.round(a, 6), mass, dataset["command"]])
    keys, inverse, counts = np.unique(all_keys, axis=0, return_inverse=True, return_counts=True)
    keep = np.unique(inverse.ravel()[np.arange(len(dataset)) if rows is None else np.asarray(rows)])
    k = keys[keep]
    white = getattr(model, "noise_v", None)
    return protocol_limits(
        model, k[:, 0], k[:, 1], k[:, 2], counts[keep], samples=samples, seed=[seed, 11], no_load_noise_v=white
    )


def drift_variance_v2(model, dataset: Dataset, *, tared: bool | None = None) -> np.ndarray:
    """Variance (V^2) of the gauges' random-walk drift each reading of ``dataset`` carries, (n, G), for a gauge
    model with ``drift_v_per_sqrt_s`` (the rate ``r`` of :class:`~flexdigit.tactile.bounds.TwinGaugeModel`; zeros
    without one, or for readings without times).

    Against the readings' reference (what an estimator of one reading can hold its drift to):

    - as read (``tared`` False): the run's mean offset over its loaded readings, which a network trained on them
      learns as a constant: ``Var(W(t_k) - mean_i W(t_i)) = r^2 (t_k - 2 mean_i min(t_k, t_i) + mean_ij min(t_i,
      t_j))`` for a Wiener process (about ``r^2 T/6`` on average over a run ``T`` long read evenly);
    - tared (``tared`` True, :func:`tare`): the drift since the reading's tare, ``r^2 dt``, plus the tare block's
      own white noise, ``sigma^2 / n`` (``n`` the readings of a tare block; as read in a test without one);
    - ``tared`` None: the smaller of the two, reading by reading (the best an estimator that may tare can do).

    A protocol that tares before each position leaves under a second of drift (``r^2`` x 1 s is 1 % of the
    thesis chain's white variance); thesis-6.1, one no-load block a test over a 774 s run, leaves ``T/6`` = 129 s
    of it: 2.3 mV on the thesis chain's 2 mV of white noise. It is no noise to a network trained on the same run,
    which learns much of it (a setting's offset, shared by its training and test readings, slow along the
    protocol's order): on thesis-6.1 (twin seed 0) the thesis rig's network, tared on each test's block, read
    3.20 mm against a 2.79 mm white-noise limit and 4.58 mm counting this drift (3.54 mm with the twin's drift
    off). ``position_bayes_rmse_m(drift=True)`` counts it: the limit of one reading of a run whose drift the
    estimator has not learnt (a new run's).
    """
    n, gauges = len(dataset), dataset.gauge_count
    rate = np.asarray(getattr(model, "drift_v_per_sqrt_s", np.zeros(gauges)), dtype=float)
    time = np.asarray(dataset["time_s"], dtype=float)
    if not np.any(rate > 0) or not np.all(np.isfinite(time)) or n == 0:
        return np.zeros((n, gauges))
    t = time - time.min()
    loaded_t = np.sort(t[dataset["load_kg"] > 0]) if np.any(dataset["load_kg"] > 0) else np.sort(t)
    below = np.r_[0.0, np.cumsum(loaded_t)]

    def mean_min(q):  # mean_i min(q, t_i) over the loaded readings' times, by sorting
        k = np.searchsorted(loaded_t, q, side="right")
        return (below[k] + q * (loaded_t.size - k)) / loaded_t.size

    raw = np.maximum(t - 2.0 * mean_min(t) + np.mean(mean_min(loaded_t)), 0.0)
    white2 = np.asarray(model.noise_v, dtype=float) ** 2
    since = tare(dataset)[1]
    block = np.zeros(n)  # readings in the test's tare blocks, on average (0: the test has none)
    order = np.argsort(dataset["sample"], kind="stable")
    unloaded = dataset["load_kg"] == 0
    for test in np.unique(dataset["test"]):
        rows = order[dataset["test"][order] == test]
        zero = np.flatnonzero(unloaded[rows])
        if zero.size:
            block[rows] = zero.size / np.count_nonzero(np.r_[True, np.diff(zero) != 1])
    as_read = rate**2 * raw[:, None]
    with np.errstate(divide="ignore"):
        tared_v2 = np.where(block[:, None] > 0, rate**2 * since[:, None] + white2 / block[:, None], as_read)
    if tared is None:
        return np.minimum(as_read, tared_v2)
    return tared_v2 if tared else as_read


def drift_referenced_readings(model, dataset: Dataset) -> tuple[np.ndarray, np.ndarray]:
    """Every reading (n, G) against the reference :func:`drift_variance_v2` (``tared=None``) holds it to, gauge by
    gauge, and that drift variance (V^2, (n, G)): the readings the drift-counted limit's estimator weighs.

    Tared (the smaller variance): the reading minus its tare (:func:`tare`) plus the model's no-load gauges at its
    command, so it compares with the model's absolute voltages. As read: the reading minus the run's mean offset
    from the model over its loaded readings (the constant a network trained on the run learns; here computed
    from the model that knows each setting's response, as the limit's estimator does).
    """
    as_read_v2 = drift_variance_v2(model, dataset, tared=False)
    tared_v2 = drift_variance_v2(model, dataset, tared=True)
    loaded = np.flatnonzero(dataset["load_kg"] > 0)
    position = np.nan_to_num(dataset["position_from_base_m"], nan=0.0)
    command = dataset["command"]
    raw = dataset.gauges_v
    offset = np.mean(raw[loaded] - model.gauges_v(position[loaded], dataset["load_kg"][loaded], command[loaded]), 0)
    free = model.gauges_v(position, np.zeros(len(dataset)), command)
    tared = tare(dataset)[0].gauges_v + free
    use_tare = tared_v2 < as_read_v2
    return np.where(use_tare, tared, raw - offset), np.where(use_tare, tared_v2, as_read_v2)


#: The span prior's grid: a quarter of the smallest Cramer-Rao bound (adds under 1 % to the limit), at most this
#: many points per command's span (beyond, the step is coarser and a limit under :data:`SPAN_RESOLVED_STEPS` steps is
#: refused).
SPAN_GRID_MAX = 4000
#: A span limit under this many steps of its grid is refused. The posterior mean on a lattice of step ``h`` is the
#: continuous one to ``exp(-2 pi^2 s^2 / h^2)`` for a posterior sd ``s`` (Poisson summation): a linear gauge's limit
#: read 2.00257 mm at h = 0.25 s, 2.00258 at h = s, 2.00370 at h = 2 s (common draws; tests/tactile/
#: test_bayes_floor.py). One step (h = s) keeps the error under 1e-6: two refused the 8-gauge stainless digit's
#: resolved 0.079 mm on a 0.042 mm grid.
SPAN_RESOLVED_STEPS = 1.0
#: A settings-prior limit under this fraction of the protocol's step is refused: the Monte Carlo never mixed two
#: positions (the hand-made PEEK digit's 1.4e-11 mm; the pairwise mix-up probability put it near 1e-4 mm)
SETTINGS_RESOLVED = 1e-3


def position_bayes_rmse_m(model, dataset, rows, *, samples=4000, seed=0, prior="span", drift=False, tared=None):
    """The localisation Bayes limit on the loaded readings ``rows`` of ``dataset``: the RMS position error (m) of the
    best estimator of the position from one reading, averaged over those readings as a trained network's RMSE on
    them is.

    ``prior="span"`` (the default, ``flexdigit train --bayes-limit``): the position continuous and uniform within
    half the protocol's step (the median spacing of its positions) of each of the protocol's positions, the
    masses the protocol's (:func:`~flexdigit.tactile.bounds.span_position_mse_m2`): the limit of localising a
    load anywhere on the protocol's stretch of the digit, which a network regressing a continuous position can
    approach. ``prior="settings"``: the estimator also knows the load hangs at one of the protocol's positions
    (:func:`bayes_limits`, chapter 6's ``protocol_limits``): a floor for any estimator, but where the positions
    are many noise sigmas apart (a stiff or high-gain digit on the thesis's 1 cm positions scaled) it is near
    zero (the hand-made PEEK digit's 1.4e-11 mm: no draw ever mixed two positions) and no regression of a
    continuous position reaches it; where the positions are closer than the digit resolves (the thesis rig) the
    two agree. A network under the span limit has learnt the protocol's positions (it snaps to them).

    The readings' noise is the model's (white noise and quantisation, :func:`readings_gauge_model`): the floor of
    an estimator that knows each setting's offset. The run's drift is such an offset, which a network trained on
    the run learns much of (:func:`drift_variance_v2` has the figures); ``drift=True`` counts it as noise, the
    limit of a reading whose drift was not learnt, no floor. The digit must have settled: a swing is not counted.

    Parameters
    ----------
    model : gauge model
        The digit's static gauges and noise, e.g. :func:`readings_gauge_model`.
    dataset : Dataset
        The readings (any gauge count).
    rows : array_like of int
        Loaded readings (a network's test readings); a no-load row is refused, having no position.
    samples, seed
        Monte Carlo readings per setting (the span prior draws a quarter of them: its grid is larger), and their
        seed.
    prior : {"span", "settings"}
    drift, tared : bool; bool or None
        Count the drift (span prior only), against ``tared``'s reference (:func:`drift_variance_v2`).

    Raises
    ------
    ValueError
        A no-load row, an unknown prior, or a span limit under one grid step (a figure the grid cannot resolve,
        never printed).

    Examples
    --------
    >>> import numpy as np
    >>> from flexdigit.tactile.dataset import Dataset, dataset_columns
    >>> class Line:
    ...     noise_v = np.array([1e-3])
    ...     def gauges_v(self, a, m, command):
    ...         a, m = np.broadcast_arrays(np.atleast_1d(a), np.atleast_1d(m))
    ...         return (m * a)[:, None]  # 1 V per kg m: positions 1 mm apart under 1 kg are 1 sigma apart
    >>> cols = {c: np.zeros(4, dtype=d) for c, d in dataset_columns(1).items()}
    >>> cols["load_kg"][:] = 1.0
    >>> cols["position_from_base_m"][:] = [0.100, 0.101, 0.200, 0.201]
    >>> ds = Dataset(cols, {"gauge_count": 1})
    >>> bool(1e-4 < position_bayes_rmse_m(Line(), ds, [0, 1, 2, 3], prior="settings") < 1e-3)  # the pairs mix
    True

    With the span prior, a reading in the span's middle is located to ``sigma / slope`` (the Gaussian posterior):
    >>> cols["position_from_base_m"][:] = [0.100, 0.150, 0.151, 0.200]  # two inside a 0.1 m span
    >>> float(np.round(1e3 * position_bayes_rmse_m(Line(), Dataset(cols, {"gauge_count": 1}), [1, 2]), 1))
    1.0
    """
    rows = np.asarray(rows, dtype=int)
    if rows.size == 0 or np.any(dataset["load_kg"][rows] <= 0):
        raise ValueError("position_bayes_rmse_m needs loaded readings (a no-load reading has no position)")
    if prior not in ("span", "settings"):
        raise ValueError(f"position_bayes_rmse_m: prior must be 'span' or 'settings', not {prior!r}")
    if drift and prior != "span":
        raise ValueError("position_bayes_rmse_m: the drift is counted with the span prior only")
    if prior == "settings":
        return _settings_limit_m(model, dataset, rows, samples=samples, seed=seed)
    return _span_limit_m(model, dataset, rows, samples=samples, seed=seed, drift=drift, tared=tared)


def _settings_limit_m(model, dataset: Dataset, rows, *, samples: int, seed: int) -> float:
    """:func:`position_bayes_rmse_m`'s settings prior (:func:`bayes_limits`), refused where unresolved."""
    limits = bayes_limits(model, dataset, rows, samples=samples, seed=seed)
    k = limits.index(dataset["position_from_base_m"][rows], dataset["load_kg"][rows], dataset["command"][rows])
    limit = float(np.sqrt(np.mean(limits.position_mse_m2[k])))
    distinct = np.unique(limits.position_from_base_m[limits.mass_kg > 0])
    step = float(np.median(np.diff(distinct))) if distinct.size > 1 else 0.0
    if limit < SETTINGS_RESOLVED * step:  # no draw mixed two positions: the Monte Carlo saw only rounding
        raise ValueError(
            f"the settings Bayes limit ({1e3 * limit:.3g} mm) is under {SETTINGS_RESOLVED:g} of the protocol's "
            f"step ({1e3 * step:.3g} mm): its draws never mixed two positions; not reported (use prior='span')"
        )
    return limit


def _span_grid(model, dataset: Dataset):
    """The span prior of ``dataset``'s loaded readings: their rows, distinct settings (position rounded to the
    micrometre, mass, command) and each row's setting, the grid step (a quarter of the smallest Cramer-Rao bound,
    at most :data:`SPAN_GRID_MAX` points) and the prior's half width (half the protocol's step; None for one
    position)."""
    mass = dataset["load_kg"]
    loaded = np.flatnonzero(mass > 0)
    a = np.round(dataset["position_from_base_m"][loaded], 6)
    keys = np.column_stack([a, mass[loaded], dataset["command"][loaded]])
    settings, inverse = np.unique(keys, axis=0, return_inverse=True)
    a, m, c = settings[:, 0], settings[:, 1], settings[:, 2].astype(int)
    bound = cramer_rao(model, a, m, c).crlb_known_mass_m
    finite = bound[np.isfinite(bound) & (bound > 0)]
    distinct = np.unique(a)
    half = 0.5 * float(np.median(np.diff(distinct))) if distinct.size > 1 else None  # half the protocol's step
    covered = np.ptp(distinct) if half is None else distinct.size * 2 * half
    step = 0.25 * float(finite.min()) if finite.size else max(covered, 1e-6) / 200
    return loaded, settings, inverse, max(step, covered / SPAN_GRID_MAX), half


def span_estimator_rmse_m(model, dataset: Dataset, rows, *, drift: bool = False) -> float:
    """The RMS position error (m) of the span limit's own estimator on ``dataset``'s readings ``rows`` as read:
    the posterior mean of :func:`position_bayes_rmse_m`'s span prior, which knows the twin's response exactly
    (:func:`~flexdigit.tactile.bounds.span_posterior_mean_m`).

    On readings with only the model's noise it reads the span limit within its scatter (tests/tactile/
    test_bayes_floor.py); above it, the readings carry what the limit does not count, and a network scored on
    them is measured against a floor no estimator reached. On thesis-6.1 of the hand-made thin shim digit (twin
    seed 0) it read 2.03 mm against a 0.47 mm limit: the amplifiers' drift, 7 mV over the run on 1 mV of white
    noise; 0.44 mm on the same digit with the drift off.

    ``drift=True``: the estimator of the drift-counted limit (``position_bayes_rmse_m(drift=True)``) on the same
    readings, each held to the reference that limit gives it (:func:`drift_referenced_readings`) and its likelihood
    widened by that reading's drift variance: where it reads that limit within its scatter, the limit counts what
    these readings carry.
    """
    rows = np.asarray(rows, dtype=int)
    if rows.size == 0 or np.any(dataset["load_kg"][rows] <= 0):
        raise ValueError("span_estimator_rmse_m needs loaded readings (a no-load reading has no position)")
    loaded, settings, _, step, half = _span_grid(model, dataset)
    readings, extra = drift_referenced_readings(model, dataset) if drift else (dataset.gauges_v, None)
    estimate = span_posterior_mean_m(
        model,
        settings[:, 0],
        settings[:, 1],
        settings[:, 2].astype(int),
        readings[rows],
        dataset["command"][rows],
        step_m=step,
        half_width_m=half,
        extra_variance_v2=None if extra is None else extra[rows],
    )
    return float(np.sqrt(np.mean((estimate - dataset["position_from_base_m"][rows]) ** 2)))


def _span_limit_m(model, dataset: Dataset, rows, *, samples: int, seed: int, drift: bool, tared=None) -> float:
    """:func:`position_bayes_rmse_m`'s span prior: the grid a quarter of the smallest Cramer-Rao bound (mass
    known), at most :data:`SPAN_GRID_MAX` points; with ``drift`` each setting's drift its readings' mean
    :func:`drift_variance_v2`; a limit under :data:`SPAN_RESOLVED_STEPS` steps refused."""
    loaded, settings, inverse, step, half = _span_grid(model, dataset)
    a, m, c = settings[:, 0], settings[:, 1], settings[:, 2].astype(int)
    extra = None
    if drift:
        each = drift_variance_v2(model, dataset, tared=tared)[loaded]
        extra = np.stack([each[inverse.ravel() == k].mean(axis=0) for k in range(settings.shape[0])])
    mse = span_position_mse_m2(
        model,
        a,
        m,
        c,
        step_m=step,
        half_width_m=half,
        samples=max(samples // 4, 100),
        seed=[seed, 13],
        extra_variance_v2=extra,
    )
    where = {int(r): int(i) for r, i in zip(loaded, inverse.ravel(), strict=True)}
    limit = float(np.sqrt(np.mean(mse[[where[int(r)] for r in rows]])))
    if limit < SPAN_RESOLVED_STEPS * step:
        raise ValueError(
            f"the localisation Bayes limit ({1e3 * limit:.3g} mm) is under one step of its position grid "
            f"({1e3 * step:.3g} mm): not resolved, not reported"
        )
    return limit


def identifiability_map(model, masses_kg, commands, digit_length_m: float, points: int = 271) -> dict:
    """CRLB (mass unknown and known) and zone along the digit for each (mass, command): arrays of ``points``."""
    a = np.linspace(0.0, digit_length_m, points)
    out = {"position_from_base_m": a, "cases": []}
    for c in commands:
        for m in masses_kg:
            b = cramer_rao(model, a, m, c)
            out["cases"].append(
                {"mass_kg": m, "command": c, "crlb_m": b.crlb_m, "crlb_known_m": b.crlb_known_mass_m, "zone": b.zone}
            )
    return out

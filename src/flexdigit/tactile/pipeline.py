"""The thesis's neural-network pipeline (6.6-6.9, 7.3-7.5), and the three network strategies of 6.2.1.

Steps, as in the thesis: shuffle with a seed; split 1/2 training, 1/3 validation, 1/6 test (6.6); normalise every
set with the training mean and standard deviation (E 6.1); train NETLAB MLPs (tanh hidden layer, linear output,
squared error, SCG, :mod:`flexdigit.tactile.netlab`) with early stopping on the validation set (6.7-6.8); sweep the
hidden nodes coarsely (5-60 step 5), then finely around the best (+-5 step 1: the thesis's 10-20 and 15-25); sweep
the "learning gradient" (SCG tolerance) 1e-1..1e-9 at the chosen size; score the test set by MATLAB's ``corr2``
and per-sample percentage error (6.9).

Targets. The thesis's position target is the position *number* of tables 6.1/7.1 (1 = tip), with the no-load
readings as position 0 (the table's first row), over every sample of the protocol (1275 or 1500): :func:`targets`
``"position_index"``. ``"position"`` is the distance from the tip in metres over the loaded samples only (where a
position exists); ``"magnitude"`` the load in kg (0 for no load); ``"contact"`` 1 for a load, 0 for none.

Examples
--------
>>> import numpy as np
>>> s = thesis_split(12, seed=0)
>>> [len(s.train), len(s.val), len(s.test)]
[6, 4, 2]
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from numbers import Integral, Real

import numpy as np

from flexdigit._estimator import Estimator, check_is_fitted
from flexdigit._repr import fields_summary, summary
from flexdigit._system import available_cores
from flexdigit._validation import (
    Array,
    Interval,
    NoValidation,
    Options,
    check_array,
    check_choice,
    check_int,
    validate_params,
)
from flexdigit.errors import ParameterError
from flexdigit.tactile.accuracy import accuracy, corr2, percentage_error, relative_rmse, rmse
from flexdigit.tactile.dataset import Dataset
from flexdigit.tactile.netlab import MLP
from flexdigit.tactile.network_sizes import HIDDEN, TOL
from flexdigit.tactile.protocols import HELD_OUT_MIN_POSITIONS

__all__ = [
    "TARGETS",
    "LEARNING_GRADIENTS",
    "COARSE_HIDDEN",
    "Split",
    "thesis_split",
    "held_out_positions_split",
    "HELD_OUT_MIN_POSITIONS",
    "Normaliser",
    "features",
    "targets",
    "ThesisNetwork",
    "SweepPoint",
    "PipelineResult",
    "run_pipeline",
    "target_scores",
    "StrategyScore",
    "compare_strategies",
]

TARGETS = ("position", "position_index", "magnitude", "contact")
LEARNING_GRADIENTS = tuple(10.0**-k for k in range(1, 10))
COARSE_HIDDEN = tuple(range(5, 61, 5))


@dataclass(frozen=True)
class Split:
    """Row indices of the training, validation and test sets."""

    train: np.ndarray
    val: np.ndarray
    test: np.ndarray

    __repr__ = fields_summary


def thesis_split(n: int, seed: int) -> Split:
    """Shuffle ``n`` rows with ``seed`` and cut them 1/2, 1/3, 1/6 (6.6)."""
    n = check_int(n, "n", "thesis_split", low=3)
    perm = np.random.default_rng(seed).permutation(n)
    n_train, n_val = int(round(n / 2)), int(round(n / 3))
    return Split(perm[:n_train], perm[n_train : n_train + n_val], perm[n_train + n_val :])


def held_out_positions_split(position_m, seed: int) -> Split:
    """Split readings by their load position: the validation and test readings at positions no training reading
    has, so a network is scored on loads between the ones it learnt (``flexdigit train --split positions``).

    The thesis's :func:`thesis_split` shuffles readings: every test position is also a training position, and a
    network can learn the protocol's positions themselves (snap to them), beating the Bayes limit of a position
    anywhere on the stretch (:func:`flexdigit.tactile.localisation.position_bayes_rmse_m`'s span prior) where the
    positions are many noise sigmas apart (the hand-made stainless digit: 0.18 mm against 0.71). Here the held-out
    positions are every other interior one (sorted; interior: both neighbours within 1.5 median steps, so each
    held-out position has training positions on both sides and nothing is extrapolated); a third of them, chosen
    with ``seed``, are the test positions, the rest validation (the thesis's 1/3 : 1/6 ratio), and every reading at
    a position goes where its position goes. Positions are compared rounded to the micrometre.

    Examples
    --------
    >>> a = np.repeat(np.arange(7) * 0.01, 2)   # 7 positions, 2 readings each
    >>> s = held_out_positions_split(a, seed=0)
    >>> np.unique(a[s.train]).tolist(), np.unique(a[np.r_[s.val, s.test]]).tolist()
    ([0.0, 0.02, 0.04, 0.06], [0.01, 0.03, 0.05])
    """
    a = np.round(check_array(position_m, "position_m", "held_out_positions_split", ndim=1), 6)
    distinct = np.unique(a)
    if distinct.size < HELD_OUT_MIN_POSITIONS:
        raise ParameterError(
            f"a held-out positions split needs at least {HELD_OUT_MIN_POSITIONS} distinct load positions; the "
            f"readings have {distinct.size} (train --split readings trains on them all)"
        )
    gaps = np.diff(distinct)
    near = gaps <= 1.5 * float(np.median(gaps))
    inner = [k for k in range(1, distinct.size - 1) if near[k - 1] and near[k]]
    held, last = [], -2
    for k in inner:  # every other interior position, never two neighbours
        if k - last > 1:
            held.append(k)
            last = k
    if len(held) < 2:
        raise ParameterError(
            f"a held-out positions split needs two interior positions between evenly spaced ones; the readings' "
            f"{distinct.size} positions have {len(held)} (train --split readings trains on them all)"
        )
    held = np.random.default_rng(seed).permutation(held)
    n_test = max(1, int(round(len(held) / 3)))
    test_at, val_at = distinct[held[:n_test]], distinct[held[n_test:]]
    rows = np.arange(a.size)
    test, val = np.isin(a, test_at), np.isin(a, val_at)
    return Split(rows[~(test | val)], rows[val], rows[test])


class Normaliser(Estimator):
    """E 6.1: ``x~ = (x - mean) / sigma`` with the training set's mean and standard deviation (MATLAB ``std``).

    Columns with zero spread are left unscaled (sigma = 1) rather than divided by zero. (scikit-learn's
    ``StandardScaler`` divides by the population deviation, ``ddof=0``; the thesis used MATLAB's ``std``.)
    """

    def fit(self, X, y=None) -> Normaliser:
        x = check_array(X, "X", "Normaliser.fit", ndim=2, min_length=2)
        self.mean_ = x.mean(axis=0)
        std = x.std(axis=0, ddof=1)
        self.std_ = np.where(std > 0, std, 1.0)
        return self

    def transform(self, X) -> np.ndarray:
        check_is_fitted(self, "mean_")
        return (np.asarray(X, dtype=float) - self.mean_) / self.std_

    def inverse_transform(self, Z) -> np.ndarray:
        check_is_fitted(self, "mean_")
        return np.asarray(Z, dtype=float) * self.std_ + self.mean_


def features(dataset: Dataset, with_command: bool = False) -> np.ndarray:
    """Network inputs: the gauge voltages (V; the digit's ``G``, three on the thesis rig), and the servo command if
    asked (chapter 7 extension)."""
    x = dataset.gauges_v
    if with_command:
        x = np.column_stack([x, dataset["command"].astype(float)])
    return x


def targets(dataset: Dataset, target: str) -> tuple[np.ndarray, np.ndarray]:
    """``(rows, y)``: which rows have the target, and its values (see the module docstring)."""
    check_choice(target, "target", TARGETS, "targets")
    n = len(dataset)
    if target == "position_index":
        return np.arange(n), dataset["position_index"].astype(float)
    if target == "position":
        rows = np.flatnonzero(dataset["load_kg"] > 0)
        return rows, dataset["position_from_tip_m"][rows]
    if target == "magnitude":
        return np.arange(n), dataset["load_kg"].astype(float)
    return np.arange(n), dataset.contact.astype(float)


class ThesisNetwork(Estimator):
    """A normalised NETLAB MLP: normalise inputs and targets (E 6.1), train with early stopping, predict.

    Parameters are those of :class:`~flexdigit.tactile.netlab.MLP`. ``fit(X, y, X_val, y_val)``.
    """

    _parameter_constraints = MLP._parameter_constraints

    def __init__(self, hidden=18, tol=1e-7, epochs=50, iterations_per_epoch=50, random_state=0) -> None:
        self.hidden = hidden
        self.tol = tol
        self.epochs = epochs
        self.iterations_per_epoch = iterations_per_epoch
        self.random_state = random_state

    def __repr__(self) -> str:
        return (
            f"ThesisNetwork(hidden={self.hidden}, tol={self.tol:g}, epochs={self.epochs}, "
            f"iterations_per_epoch={self.iterations_per_epoch}, random_state={self.random_state})"
        )

    def fit(self, X, y, X_val=None, y_val=None) -> ThesisNetwork:
        self._validate_params()
        x = check_array(X, "X", "ThesisNetwork.fit", ndim=2, min_length=2)
        t = check_array(y, "y", "ThesisNetwork.fit")
        self.y_ndim_ = t.ndim
        t2 = t.reshape(-1, 1) if t.ndim == 1 else t
        self.x_norm_ = Normaliser().fit(x)
        self.y_norm_ = Normaliser().fit(t2)
        net = MLP(self.hidden, self.tol, self.epochs, self.iterations_per_epoch, self.random_state)
        if X_val is None:
            net.fit(self.x_norm_.transform(x), self.y_norm_.transform(t2))
        else:
            tv = np.asarray(y_val, dtype=float)
            tv = tv.reshape(-1, 1) if tv.ndim == 1 else tv
            net.fit(
                self.x_norm_.transform(x),
                self.y_norm_.transform(t2),
                self.x_norm_.transform(X_val),
                self.y_norm_.transform(tv),
            )
        self.net_ = net
        # error curves in target units^2 (the normalised MSE times the target variance)
        scale = float(np.mean(self.y_norm_.std_**2))
        self.train_error_ = net.train_error_ * scale
        self.val_error_ = net.val_error_ * scale
        return self

    def predict(self, X) -> np.ndarray:
        check_is_fitted(self, "net_")
        x = check_array(X, "X", "ThesisNetwork.predict", ndim=2)
        y = self.y_norm_.inverse_transform(self.net_.predict(self.x_norm_.transform(x)).reshape(x.shape[0], -1))
        return y[:, 0] if self.y_ndim_ == 1 else y


@dataclass
class SweepPoint:
    """One trained configuration: its size, tolerance, best validation and training MSE, and the epoch kept."""

    hidden: int
    tol: float
    val_mse: float
    train_mse: float
    best_epoch: int


@dataclass
class PipelineResult:
    """Everything the thesis pipeline produced for one dataset and target."""

    target: str
    split: Split
    coarse: list[SweepPoint]
    fine: list[SweepPoint]
    gradient: list[SweepPoint]
    best_hidden: int
    best_tol: float
    curve_hidden: int | None
    curve_train: np.ndarray
    curve_val: np.ndarray
    y_test: np.ndarray
    y_pred: np.ndarray
    corr2: float
    percent_error: np.ndarray
    model: ThesisNetwork
    extra: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return summary(
            self,
            target=self.target,
            best_hidden=self.best_hidden,
            best_tol=self.best_tol,
            corr2=self.corr2,
            test_samples=len(self.y_test),
            median_percent_error=float(np.median(np.abs(self.percent_error))) if np.size(self.percent_error) else None,
        )


def _train(x, y, split, hidden, tol, seed, epochs) -> tuple[ThesisNetwork, SweepPoint]:
    model = ThesisNetwork(hidden=hidden, tol=tol, epochs=epochs, random_state=seed)
    model.fit(x[split.train], y[split.train], x[split.val], y[split.val])
    k = model.net_.best_epoch_
    return model, SweepPoint(hidden, tol, float(model.val_error_[k]), float(model.train_error_[k]), k)


def _sweep(x, y, split, configs, epochs) -> list[SweepPoint]:
    """:func:`_train` for each ``(hidden, tol, seed)`` of a sweep, the networks trained together on every core.

    The compiled training releases the GIL, so threads train networks side by side; each network depends only on
    its own configuration and seed, so the points are those of training them one after another, in order.
    """
    configs = list(configs)
    with ThreadPoolExecutor(max_workers=min(len(configs), available_cores()) or 1) as pool:
        return list(pool.map(lambda c: _train(x, y, split, c[0], c[1], c[2], epochs)[1], configs))


@validate_params(
    {
        "x": [NoValidation()],
        "y": [NoValidation()],
        "seed": [Interval(Integral, 0, None)],
        "coarse": [Array(ndim=1, min_length=1, low=1)],
        "fine_halfwidth": [Interval(Integral, 0, None)],
        "gradients": [Array(ndim=1, min_length=1, low=0, low_open=True)],
        "default_tol": [Interval(Real, 0, None, closed="neither")],
        "curve_hidden": [Interval(Integral, 1, None), None],
        "epochs": [Interval(Integral, 1, None)],
        "fixed_hidden": [HIDDEN, None],
        "fixed_tol": [TOL, None],
        "target": [Options(TARGETS)],
    }
)
def run_pipeline(
    x,
    y,
    *,
    seed: int = 0,
    coarse=COARSE_HIDDEN,
    fine_halfwidth: int = 5,
    gradients=LEARNING_GRADIENTS,
    default_tol: float = 1e-7,
    curve_hidden: int | None = 15,
    epochs: int = 50,
    fixed_hidden: int | None = None,
    fixed_tol: float | None = None,
    target: str = "position_index",
    split: Split | None = None,
) -> PipelineResult:
    """The thesis's optimisation and test (6.6-6.9) on inputs ``x`` (n, k) and targets ``y`` (n,).

    Parameters
    ----------
    seed : int
        Seeds the shuffle and every network's initial weights: same seed, same numbers.
    coarse : sequence of int
        Hidden sizes of the coarse sweep (5..60 step 5).
    fine_halfwidth : int
        The fine sweep covers the best coarse size +-this, step 1 (thesis: 10-20, 15-25).
    gradients : sequence of float
        "Learning gradients" (SCG tolerances) swept at the chosen size (1e-1..1e-9).
    default_tol : float
        Tolerance during the hidden-node sweeps (the thesis's default 1e-7).
    curve_hidden : int or None
        Size whose error-vs-iteration curves are kept (figure 6.13: 15; figure 7.4: 20); None trains no network
        for the curves (they are then empty), e.g. when only the test score is wanted.
    epochs : int
        Epochs of 50 SCG iterations per training (50).
    fixed_hidden, fixed_tol : optional
        Skip the sweeps and use these (the thesis's printed optimum, for a like-for-like test).
    split : Split, optional
        The rows' sets (default :func:`thesis_split` with ``seed``; or :func:`held_out_positions_split`).
    """
    x = check_array(x, "x", "run_pipeline", ndim=2, min_length=6)
    y = check_array(y, "y", "run_pipeline", ndim=1)
    if y.shape[0] != x.shape[0]:
        raise ParameterError(f"run_pipeline needs one target per row. Got {y.shape[0]} and {x.shape[0]}.")
    split = thesis_split(x.shape[0], seed) if split is None else split
    seeds = iter(np.random.default_rng([seed, 1]).integers(0, 2**31, size=1000))
    coarse, gradients = [int(h) for h in coarse], [float(g) for g in gradients]  # declared arrays arrive as floats
    if fixed_hidden is None:
        coarse_pts, fine_pts, best_hidden = _hidden_sweeps(x, y, split, coarse, fine_halfwidth, default_tol, seeds,
                                                           epochs)  # fmt: skip
    else:
        coarse_pts, fine_pts, best_hidden = [], [], int(fixed_hidden)
    grad_pts: list[SweepPoint] = []
    if fixed_tol is not None:
        best_tol = float(fixed_tol)
    else:
        grad_pts = _sweep(x, y, split, [(best_hidden, g, next(seeds)) for g in gradients], epochs)
        best_tol = min(grad_pts, key=lambda p: p.val_mse).tol
    curve_seed = next(seeds)  # drawn either way, so the final network's seed does not depend on curve_hidden
    curve_train, curve_val = _curves(x, y, split, curve_hidden, default_tol, curve_seed, epochs)
    model, _ = _train(x, y, split, best_hidden, best_tol, next(seeds), epochs)
    y_test = y[split.test]
    y_pred = model.predict(x[split.test])
    return PipelineResult(
        target=target,
        split=split,
        coarse=coarse_pts,
        fine=fine_pts,
        gradient=grad_pts,
        best_hidden=best_hidden,
        best_tol=best_tol,
        curve_hidden=curve_hidden,
        curve_train=curve_train,
        curve_val=curve_val,
        y_test=y_test,
        y_pred=y_pred,
        corr2=corr2(y_pred, y_test),
        percent_error=percentage_error(y_pred, y_test),
        model=model,
    )


def _hidden_sweeps(x, y, split, coarse, fine_halfwidth: int, default_tol: float, seeds, epochs: int):
    """The coarse sweep of hidden sizes, the fine one around its best, and the best size of both (6.7).

    ``seeds`` is the pipeline's seed iterator, drawn in sweep order.
    """
    coarse_pts = _sweep(x, y, split, [(h, default_tol, next(seeds)) for h in coarse], epochs)
    c = min(coarse_pts, key=lambda p: p.val_mse).hidden
    fine = range(max(1, c - fine_halfwidth), c + fine_halfwidth + 1)
    fine_pts = _sweep(x, y, split, [(h, default_tol, next(seeds)) for h in fine], epochs)
    best_hidden = min(fine_pts + coarse_pts, key=lambda p: p.val_mse).hidden
    return coarse_pts, fine_pts, best_hidden


def _curves(x, y, split, curve_hidden: int | None, tol: float, seed, epochs: int) -> tuple[np.ndarray, np.ndarray]:
    """Training and validation error per iteration of a network of ``curve_hidden`` nodes (empty for None)."""
    if curve_hidden is None:
        return np.empty(0), np.empty(0)
    curve_model, _ = _train(x, y, split, curve_hidden, tol, seed, epochs)
    return curve_model.train_error_, curve_model.val_error_


# ------------------------------------------------------------------------------------ strategies of 6.2.1
@dataclass
class StrategyScore:
    """Test-set scores of one strategy: position (corr2 and RMSE in m, loaded samples), contact, magnitude."""

    strategy: str
    position_corr2: float
    position_rmse_m: float
    contact_accuracy: float
    magnitude_rel_rmse: float
    magnitude_rmse_kg: float


def compare_strategies(dataset: Dataset, *, hidden: int = 18, tol: float = 1e-7, seed: int = 0, epochs: int = 50):
    """Combined, parallel and cascaded networks (figures 6.2-6.4) on the same split of ``dataset``.

    * parallel: three separate networks on the gauges: contact (all rows, 0/1, threshold 0.5), magnitude (all
      rows, kg) and position (loaded rows only, m from the tip); position is reported only where contact is
      predicted.
    * combined: one network with three outputs (contact, magnitude, position; position 0 for no load).
    * cascaded: contact first; magnitude from gauges + predicted contact; position from gauges + predicted contact
      + predicted magnitude (trained on the upstream networks' own predictions, as it would run).

    Returns a list of :class:`StrategyScore` (scores on the test rows; position over loaded test rows).
    """
    x = features(dataset, with_command=dataset.protocol.actuated)
    n = len(dataset)
    split = thesis_split(n, seed)
    contact = dataset.contact.astype(float)
    mass = dataset["load_kg"].astype(float)
    pos = np.nan_to_num(dataset["position_from_tip_m"], nan=0.0)
    loaded = contact > 0
    tr, va, te = split.train, split.val, split.test
    tr_l, va_l = tr[loaded[tr]], va[loaded[va]]
    te_l = te[loaded[te]]

    def net(h=hidden, s=seed):
        return ThesisNetwork(hidden=h, tol=tol, epochs=epochs, random_state=s)

    def score(name, c_pred, m_pred, p_pred) -> StrategyScore:
        c_hat = (c_pred >= 0.5).astype(float)
        pl = p_pred[loaded[te]]
        return StrategyScore(
            name,
            corr2(pl, pos[te_l]),
            rmse(pl, pos[te_l]),
            accuracy(c_hat, contact[te]),
            relative_rmse(m_pred[loaded[te]], mass[te_l]),
            rmse(m_pred, mass[te]),
        )

    scores = []
    # parallel
    c_net = net().fit(x[tr], contact[tr], x[va], contact[va])
    m_net = net().fit(x[tr], mass[tr], x[va], mass[va])
    p_net = net().fit(x[tr_l], pos[tr_l], x[va_l], pos[va_l])
    scores.append(score("parallel", c_net.predict(x[te]), m_net.predict(x[te]), p_net.predict(x[te])))
    # combined
    y3 = np.column_stack([contact, mass, pos])
    comb = net(h=hidden).fit(x[tr], y3[tr], x[va], y3[va])
    y_hat = comb.predict(x[te])
    scores.append(score("combined", y_hat[:, 0], y_hat[:, 1], y_hat[:, 2]))
    # cascaded: each stage sees the previous stages' predictions
    c_all = c_net.predict(x)
    x2 = np.column_stack([x, c_all])
    m2 = net().fit(x2[tr], mass[tr], x2[va], mass[va])
    m_all = m2.predict(x2)
    x3 = np.column_stack([x2, m_all])
    p3 = net().fit(x3[tr_l], pos[tr_l], x3[va_l], pos[va_l])
    scores.append(score("cascaded", c_all[te], m_all[te], p3.predict(x3[te])))
    return scores


def target_scores(result: PipelineResult) -> dict:
    """The scores ``flexdigit train`` reports and keeps with a network, from its test readings.

    Parameters
    ----------
    result : PipelineResult
        A trained network's :func:`run_pipeline` result.

    Returns
    -------
    dict
        ``corr2``, ``hidden``, ``learning_gradient`` and the target's error: ``rmse_mm`` (position, m -> mm),
        ``rmse_g`` (magnitude, kg -> g), ``accuracy`` (contact, thresholded at 0.5) or ``rmse_positions``
        (position index).
    """
    scores = {"corr2": result.corr2, "hidden": result.best_hidden, "learning_gradient": result.best_tol}
    if result.target == "position":
        scores["rmse_mm"] = 1000 * rmse(result.y_pred, result.y_test)
    elif result.target == "magnitude":
        scores["rmse_g"] = 1000 * rmse(result.y_pred, result.y_test)
    elif result.target == "contact":
        scores["accuracy"] = accuracy((result.y_pred >= 0.5).astype(float), result.y_test)
    else:
        scores["rmse_positions"] = rmse(result.y_pred, result.y_test)
    return scores

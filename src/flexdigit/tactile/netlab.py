"""The thesis's network: NETLAB's two-layer MLP (tanh hidden layer, linear output) trained by scaled conjugate
gradients (6.2-6.8), with early stopping on a validation set.

Why not scikit-learn's ``MLPRegressor``: the thesis trained with NETLAB's ``scg`` and swept its "learning
gradient", which is SCG's termination tolerance (below); ``MLPRegressor`` has no SCG and its L-BFGS gives no
per-iteration validation error for the error-vs-iteration curves (figures 6.13, 7.4). NETLAB's ``mlp`` and
``scg`` (Moller 1993; Nabney, *NETLAB*, 2002) are ~80 lines of numpy, ported here line by line
(:func:`mlp_forward`, :func:`mlp_grad`, :func:`scg`: the readable reference). :class:`MLP` trains with the same
algorithm compiled (:mod:`flexdigit.tactile._scg_kernel`, ~4x faster; tested against the reference step by step).

The "learning gradient" (6.8, 7.4) is not a learning rate: SCG has none. NETLAB's ``scg`` stops when both
``max|alpha d| < options(2)`` (step in the weights) and ``|E_new - E_old| < options(3)`` (change of the
sum-of-squares error); the thesis's "default 1e-7" and sweep 1e-1..1e-9 fit these two tolerances, set together
(``foptions`` default is 1e-4; NETLAB's demos set 1e-7..1e-8). :class:`MLP` takes it as ``tol``.
An "epoch" is 50 SCG iterations (6.7); training runs ``epochs`` of them, records the training and validation
error after each, and keeps the weights of the epoch with the lowest validation error (early stopping).

Examples
--------
>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> x = rng.uniform(-1, 1, (200, 3)); y = x @ [1.0, -2.0, 0.5]
>>> net = MLP(hidden=5, epochs=4, random_state=0).fit(x, y)
>>> bool(np.sqrt(np.mean((net.predict(x) - y) ** 2)) < 0.05)
True
"""

from __future__ import annotations

from numbers import Integral

import numpy as np

from flexdigit._estimator import Estimator, check_is_fitted
from flexdigit._validation import Interval, Plausible, check_array
from flexdigit.errors import ParameterError
from flexdigit.tactile.network_sizes import HIDDEN, TOL

__all__ = ["SCG_SIGMA0", "mlp_unpack", "mlp_init", "mlp_forward", "mlp_error", "mlp_grad", "scg", "MLP"]

SCG_SIGMA0 = 1.0e-4  # NETLAB scg.m
_BETA_MIN, _BETA_MAX = 1.0e-15, 1.0e100


def mlp_unpack(w: np.ndarray, nin: int, nhidden: int, nout: int):
    """Split NETLAB's packed weight vector into (w1, b1, w2, b2) (``mlpunpak.m``)."""
    i = 0
    w1 = w[i : i + nin * nhidden].reshape(nin, nhidden)
    i += nin * nhidden
    b1 = w[i : i + nhidden]
    i += nhidden
    w2 = w[i : i + nhidden * nout].reshape(nhidden, nout)
    i += nhidden * nout
    b2 = w[i : i + nout]
    return w1, b1, w2, b2


def mlp_init(nin: int, nhidden: int, nout: int, rng: np.random.Generator) -> np.ndarray:
    """NETLAB ``mlp.m`` initial weights: N(0, 1/(nin+1)) into the hidden layer, N(0, 1/(nhidden+1)) out."""
    w1 = rng.standard_normal((nin, nhidden)) / np.sqrt(nin + 1)
    b1 = rng.standard_normal(nhidden) / np.sqrt(nin + 1)
    w2 = rng.standard_normal((nhidden, nout)) / np.sqrt(nhidden + 1)
    b2 = rng.standard_normal(nout) / np.sqrt(nhidden + 1)
    return np.concatenate([w1.ravel(), b1, w2.ravel(), b2])


def mlp_forward(w: np.ndarray, x: np.ndarray, nhidden: int, nout: int) -> tuple[np.ndarray, np.ndarray]:
    """Outputs (linear) and hidden activations (tanh) of the network (``mlpfwd.m``)."""
    w1, b1, w2, b2 = mlp_unpack(w, x.shape[1], nhidden, nout)
    z = np.tanh(x @ w1 + b1)
    return z @ w2 + b2, z


def mlp_error(w: np.ndarray, x: np.ndarray, t: np.ndarray, nhidden: int) -> float:
    """NETLAB ``mlperr.m`` for linear outputs: ``0.5 * sum((y - t)**2)``."""
    y, _ = mlp_forward(w, x, nhidden, t.shape[1])
    return 0.5 * float(np.sum((y - t) ** 2))


def mlp_grad(w: np.ndarray, x: np.ndarray, t: np.ndarray, nhidden: int, forward=None) -> np.ndarray:
    """Gradient of :func:`mlp_error` by back-propagation (``mlpgrad.m``, ``mlpbkp.m``).

    ``forward``, if given, is :func:`mlp_forward` of the same ``w`` and ``x`` (outputs, hidden activations),
    reused instead of recomputed: the result is the same to the bit.
    """
    nout = t.shape[1]
    w1, b1, w2, b2 = mlp_unpack(w, x.shape[1], nhidden, nout)
    y, z = mlp_forward(w, x, nhidden, nout) if forward is None else forward
    delout = y - t
    gw2 = z.T @ delout
    gb2 = delout.sum(axis=0)
    delhid = (delout @ w2.T) * (1.0 - z * z)
    gw1 = x.T @ delhid
    gb1 = delhid.sum(axis=0)
    return np.concatenate([gw1.ravel(), gb1, gw2.ravel(), gb2])


def scg(f, grad, x: np.ndarray, iterations: int, tol_x: float, tol_f: float) -> tuple[np.ndarray, bool]:
    """NETLAB ``scg.m``: minimise ``f`` from ``x`` by scaled conjugate gradients.

    Parameters
    ----------
    f, grad : callable
        Objective and its gradient.
    x : ndarray
        Start point (not modified).
    iterations : int
        Maximum number of iterations (``options(14)``).
    tol_x, tol_f : float
        ``options(2)`` and ``options(3)``: stop when the step and the change of ``f`` are both below them.

    Returns
    -------
    (ndarray, bool)
        The final point and whether the tolerances were met.
    """
    x = np.array(x, dtype=float)
    nparams = x.size
    fold = f(x)
    gradnew = grad(x)
    gradold = gradnew
    d = -gradnew
    success, nsuccess = True, 0
    beta = 1.0
    mu = kappa = theta = 0.0
    for _ in range(iterations):
        if success:
            mu = float(d @ gradnew)
            if mu >= 0:
                d = -gradnew
                mu = float(d @ gradnew)
            kappa = float(d @ d)
            if kappa < np.finfo(float).eps:
                return x, True
            sigma = SCG_SIGMA0 / np.sqrt(kappa)
            gplus = grad(x + sigma * d)
            theta = float(d @ (gplus - gradnew)) / sigma
        delta = theta + beta * kappa
        if delta <= 0:
            delta = beta * kappa
            beta = beta - theta / kappa
        alpha = -mu / delta
        xnew = x + alpha * d
        fnew = f(xnew)
        big_delta = 2.0 * (fnew - fold) / (alpha * mu)
        if big_delta >= 0:
            success = True
            nsuccess += 1
            x = xnew
        else:
            success = False
        if success:
            if np.max(np.abs(alpha * d)) < tol_x and abs(fnew - fold) < tol_f:
                return x, True
            fold = fnew
            gradold = gradnew
            gradnew = grad(x)
            if float(gradnew @ gradnew) == 0.0:
                return x, True
        if big_delta < 0.25:
            beta = min(4.0 * beta, _BETA_MAX)
        if big_delta > 0.75:
            beta = max(0.5 * beta, _BETA_MIN)
        if nsuccess == nparams:
            d = -gradnew
            nsuccess = 0
        elif success:
            gamma = float((gradold - gradnew) @ gradnew) / mu
            d = gamma * d - gradnew
    return x, False


class MLP(Estimator):
    """NETLAB two-layer perceptron: ``nin`` inputs -> ``hidden`` tanh units -> linear outputs.

    Trained on the sum-of-squares error with SCG in epochs of ``iterations_per_epoch`` iterations, keeping the
    weights with the lowest validation error (early stopping, 6.7-6.8). Inputs and targets should already be
    normalised (E 6.1, :class:`~flexdigit.tactile.pipeline.Normaliser`).

    Parameters
    ----------
    hidden : int
        Hidden units (thesis: 18 non-actuated, 24 actuated).
    tol : float
        The thesis's "learning gradient": SCG's ``options(2)`` and ``options(3)`` (see module docstring).
    epochs : int
        Epochs of training (thesis: 50).
    iterations_per_epoch : int
        SCG iterations per epoch (thesis: 50).
    random_state : int or None
        Seed of the initial weights.

    Attributes
    ----------
    weights_ : ndarray
        Packed weights (NETLAB order: w1, b1, w2, b2).
    train_error_, val_error_ : ndarray
        Mean squared error after each epoch (index 0: the initial weights).
    best_epoch_ : int
        The epoch whose weights were kept.
    n_iter_ : int
        SCG iterations run.
    converged_ : bool
        Whether SCG met the tolerances before the last epoch (else it ran every epoch; not a failure: early
        stopping, not convergence, is the thesis's criterion).
    """

    _parameter_constraints = {
        "hidden": [HIDDEN],
        "tol": [TOL],
        "epochs": [Plausible("", 1, 1_000_000, "epochs: early stopping needs tens", integer=True)],
        "iterations_per_epoch": [Plausible("", 1, 1_000_000, "SCG iterations per epoch", integer=True)],
        "random_state": [Interval(Integral, 0, None), None],
    }

    def __init__(
        self,
        hidden: int = 18,
        tol: float = 1e-7,
        epochs: int = 50,
        iterations_per_epoch: int = 50,
        random_state: int | None = 0,
    ) -> None:
        self.hidden = hidden
        self.tol = tol
        self.epochs = epochs
        self.iterations_per_epoch = iterations_per_epoch
        self.random_state = random_state

    def __repr__(self) -> str:
        return (
            f"MLP(hidden={self.hidden}, tol={self.tol:g}, epochs={self.epochs}, "
            f"iterations_per_epoch={self.iterations_per_epoch}, random_state={self.random_state})"
        )

    def fit(self, X, y, X_val=None, y_val=None) -> MLP:
        """Train on ``(X, y)``; early-stop on ``(X_val, y_val)`` (default: the training data, i.e. no stop)."""
        self._validate_params()
        hidden, tol, epochs = int(self.hidden), float(self.tol), int(self.epochs)
        per_epoch = int(self.iterations_per_epoch)
        x, t = _xy(X, y)
        xv, tv = (x, t) if X_val is None else _xy(X_val, y_val)
        if xv.shape[1] != x.shape[1] or tv.shape[1] != t.shape[1]:
            raise ParameterError("The validation data of MLP.fit must have as many columns as the training data.")
        self.n_inputs_, self.n_outputs_ = x.shape[1], t.shape[1]
        self.y_ndim_ = np.ndim(y)
        w = mlp_init(x.shape[1], hidden, t.shape[1], np.random.default_rng(self.random_state))
        from flexdigit.tactile import _scg_kernel  # numba: compiled on first use, cached per machine

        best_w, best_epoch, epochs_run, train, val, converged = _scg_kernel.train(
            w, x, t, xv, tv, hidden, epochs, per_epoch, tol
        )
        self.weights_ = best_w
        self.best_epoch_ = int(best_epoch)
        self.n_iter_ = int(epochs_run) * per_epoch
        self.train_error_ = train
        self.val_error_ = val
        self.converged_ = bool(converged)
        return self

    def predict(self, X) -> np.ndarray:
        """Network outputs for ``X`` (same shape convention as the ``y`` given to ``fit``)."""
        check_is_fitted(self, "weights_")
        x = check_array(X, "X", "MLP.predict", ndim=2)
        if x.shape[1] != self.n_inputs_:
            raise ParameterError(f"MLP.predict expects {self.n_inputs_} input columns. Got {x.shape[1]} instead.")
        y, _ = mlp_forward(self.weights_, x, int(self.hidden), self.n_outputs_)
        return y[:, 0] if self.y_ndim_ == 1 else y


def _xy(X, y) -> tuple[np.ndarray, np.ndarray]:
    x = check_array(X, "X", "MLP.fit", ndim=2, min_length=1)
    t = check_array(y, "y", "MLP.fit")
    t = t.reshape(-1, 1) if t.ndim == 1 else t
    if t.ndim != 2 or t.shape[0] != x.shape[0]:
        raise ParameterError(f"MLP.fit needs as many targets as samples. Got {t.shape[0]} and {x.shape[0]}.")
    return x, t

"""Load estimators beyond the thesis's MLP, on the same inputs: a beam-model inversion and a Gaussian process.

Both follow scikit-learn's contract. Inputs ``X`` are the gauge voltages (n, G) of a digit's G gauges (1-8; the
thesis rig's 3), optionally with the servo command as a last column (actuated experiments); targets ``Y`` are
``(position_from_tip_m, load_kg)`` (n, 2) of loaded readings.

* :class:`BeamInversion`: least squares on a static gauge model (the twin's, :mod:`flexdigit.tactile.bounds`):
  ``(a, m) = argmin sum_i ((v_i - g_i(a, m, c)) / sigma_i)^2`` on a dense (position, mass) grid with
  parabolic refinement; ``fit`` only calibrates a per-gauge gain and offset of the model on the training
  readings (2 G numbers, G the model's gauges: ``noise_v``'s length; a real rig's gains differ from the model's).
  This is the maximum-likelihood estimate under the model's Gaussian noise, the estimator the Cramer-Rao bound
  is about. A model whose noise depends on the load (``noise_at``: the twin's cable-guide friction, which grows
  with the cable tension) is weighted by it:
  the grid cost is then the full negative log-likelihood, ``sum_i ((v_i - g_i) / sigma_i)^2 + 2 log sigma_i``,
  and the refinement keeps the weights of the best grid point.
* :class:`GPLocaliser`: scikit-learn ``GaussianProcessRegressor`` (anisotropic RBF + white noise) on the
  normalised inputs, one per target, with a predictive standard deviation for every estimate.

Examples
--------
>>> import numpy as np
>>> class Line:
...     noise_v = np.array([0.002, 0.002, 0.002])
...     def gauges_v(self, a, m, command):
...         a, m = np.broadcast_arrays(np.atleast_1d(a), np.atleast_1d(m))
...         return 40.0 * (m * 9.81)[:, None] * np.clip(a[:, None] - [0.045, 0.135, 0.225], 0, None)
>>> inv = BeamInversion(Line(), digit_length_m=0.27, max_mass_kg=0.05)
>>> v = Line().gauges_v(0.27 - 0.05, 0.02, -1)
>>> np.round(inv.fit(v, [[0.05, 0.02]]).predict(v), 4).tolist()
[[0.05, 0.02]]
"""

from __future__ import annotations

import warnings
from numbers import Integral, Real

import numpy as np

from flexdigit._estimator import Estimator, check_is_fitted
from flexdigit._validation import Bool, HasMethods, Interval, check_array
from flexdigit.errors import ParameterError
from flexdigit.tactile.pipeline import Normaliser
from flexdigit.tactile.protocols import RELAXED

__all__ = ["BeamInversion", "GPLocaliser"]


def _split_x(X, gauges: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``gauges`` gauge columns of ``X`` and the command column (``RELAXED`` when ``X`` has none)."""
    x = check_array(X, "X", "estimator", ndim=2)
    if x.shape[1] not in (gauges, gauges + 1):
        raise ParameterError(
            f"X must have {gauges} gauge column(s) (the model's gauges; and optionally the command). "
            f"Got {x.shape[1]} columns."
        )
    command = x[:, gauges].astype(int) if x.shape[1] == gauges + 1 else np.full(x.shape[0], RELAXED)
    return x[:, :gauges], command


class BeamInversion(Estimator):
    """Maximum-likelihood load position and mass from a static gauge model (see the module docstring).

    Parameters
    ----------
    model : gauge model
        ``gauges_v(position_from_base_m, mass_kg, command)`` and ``noise_v``.
    digit_length_m : float
        Clamp to tip (m): positions from the tip are ``digit_length_m - a``.
    max_mass_kg : float
        Upper end of the mass grid (kg).
    position_step_m : float
        Grid step along the digit (m), refined by a parabola through the three best points.
    mass_steps : int
        Mass grid points.
    calibrate : bool
        Fit a per-gauge gain and offset of the model to the training readings.
    tared : bool
        The readings have had their no-load level subtracted (:func:`flexdigit.tactile.localisation.tare`): model
        ``g(a, m, c) - g(., 0, c)`` instead of ``g(a, m, c)``.
    load_set : bool
        Restrict the mass to the loads seen in training (a protocol hangs a few known weights: the same prior
        the learned estimators pick up); the position is then a 1-D least-squares fit per candidate load.
    """

    _parameter_constraints = {
        "model": [HasMethods("gauges_v")],
        "digit_length_m": [Interval(Real, 0, None, closed="neither")],
        "max_mass_kg": [Interval(Real, 0, None, closed="neither")],
        "position_step_m": [Interval(Real, 0, None, closed="neither")],
        "mass_steps": [Interval(Integral, 3, None)],
        "calibrate": [Bool()],
        "load_set": [Bool()],
        "tared": [Bool()],
    }

    def __init__(
        self,
        model,
        digit_length_m: float = 0.270,
        max_mass_kg: float = 0.08,
        position_step_m: float = 1e-3,
        mass_steps: int = 81,
        calibrate: bool = True,
        load_set: bool = False,
        tared: bool = False,
    ) -> None:
        self.model = model
        self.digit_length_m = digit_length_m
        self.max_mass_kg = max_mass_kg
        self.position_step_m = position_step_m
        self.mass_steps = mass_steps
        self.calibrate = calibrate
        self.load_set = load_set
        self.tared = tared

    def __repr__(self) -> str:
        return (
            f"BeamInversion(model={type(self.model).__name__}, digit_length_m={self.digit_length_m}, "
            f"max_mass_kg={self.max_mass_kg}, position_step_m={self.position_step_m}, calibrate={self.calibrate}, "
            f"load_set={self.load_set}, tared={self.tared})"
        )

    def _grid(self, command: int) -> np.ndarray:
        if command not in self.grids_:
            a, m = self.a_grid_, self.m_grid_
            aa, mm = np.meshgrid(a, m, indexing="ij")
            g = self._model(aa.ravel(), mm.ravel(), np.full(aa.size, command))
            gauges = self.noise_v_.size
            self.grids_[command] = g.reshape(a.size, m.size, gauges)
            self.noise_grids_[command] = self._noise(aa.ravel(), mm.ravel(), command).reshape(a.size, m.size, gauges)
        return self.grids_[command]

    def _noise(self, a, m, command: int) -> np.ndarray:
        """Standard deviation (V) of a reading at ``(a, m)`` (n, G), in the calibrated model's units."""
        a = np.atleast_1d(a)
        if hasattr(self.model, "noise_at"):
            sigma = np.asarray(self.model.noise_at(a, np.broadcast_to(m, a.shape), np.full(a.size, command)))
        else:
            sigma = np.broadcast_to(self.noise_v_, (a.size, self.noise_v_.size))
        return sigma * np.abs(self.gain_)

    def no_load_cost(self, X) -> np.ndarray:
        """Negative log-likelihood (as the fit's cost) of each reading under "nothing hung"."""
        check_is_fitted(self, "grids_")
        v, command = _split_x(X, self.noise_v_.size)
        cost = np.empty(v.shape[0])
        for value in np.unique(command):
            rows = command == value
            zero = np.zeros(int(rows.sum()))
            sigma = self._noise(zero, zero, int(value))
            g = self.no_load_v(np.full(int(rows.sum()), value))
            cost[rows] = np.sum(((v[rows] - g) / sigma) ** 2 + 2 * np.log(sigma), axis=1)
        return cost

    def fit(self, X, Y=None) -> BeamInversion:
        self._validate_params()
        length, step = float(self.digit_length_m), float(self.position_step_m)
        self.a_grid_ = np.arange(0.0, length + step / 2, step)
        self.m_grid_ = np.linspace(0.0, float(self.max_mass_kg), int(self.mass_steps))
        self.grids_: dict[int, np.ndarray] = {}
        self.noise_grids_: dict[int, np.ndarray] = {}
        self.noise_v_ = np.atleast_1d(np.asarray(self.model.noise_v, dtype=float))
        gauges = self.noise_v_.size
        self.gain_ = np.ones(gauges)
        self.offset_ = np.zeros(gauges)
        v, command = _split_x(X, gauges)
        if self.load_set:
            if Y is None:
                raise ParameterError("BeamInversion(load_set=True).fit needs Y (position, mass) to learn the loads.")
            masses = np.unique(np.asarray(Y, dtype=float)[:, 1])
            self.m_grid_ = masses[masses > 0]
        if self.calibrate and Y is not None:
            y = check_array(Y, "Y", "BeamInversion.fit", ndim=2, shape=(v.shape[0], 2))
            g = self._model(length - y[:, 0], y[:, 1], command)
            for i in range(gauges):  # v_i ~ gain_i g_i + offset_i, least squares (2 G numbers)
                design = np.column_stack([g[:, i], np.ones(len(g))])
                if np.ptp(g[:, i]) > 0:
                    (self.gain_[i], self.offset_[i]), *_ = np.linalg.lstsq(design, v[:, i], rcond=None)
                else:
                    self.offset_[i] = float(np.mean(v[:, i] - g[:, i]))
        return self

    def predict(self, X, return_cost: bool = False):
        """``(n, 2)``: position from the tip (m) and mass (kg) of each reading (and the residual cost if asked)."""
        check_is_fitted(self, "grids_")
        v, command = _split_x(X, self.noise_v_.size)
        out = np.empty((v.shape[0], 2))
        cost = np.empty(v.shape[0])
        for value in np.unique(command):
            rows = np.flatnonzero(command == value)
            grid = self._grid(int(value)) * self.gain_ + self.offset_
            sigma = self.noise_grids_[int(value)]
            log_term = 2 * np.sum(np.log(sigma), axis=2)
            a0 = np.empty(rows.size)
            m0 = np.empty(rows.size)
            s0 = np.empty((rows.size, v.shape[1]))
            for start in range(0, rows.size, 32):  # batches bound the (batch, na, nm) temporaries
                r = rows[start : start + 32]
                d = np.broadcast_to(log_term, (r.size,) + grid.shape[:2]).copy()
                for i in range(v.shape[1]):
                    d += ((v[r, i, None, None] - grid[None, :, :, i]) / sigma[None, :, :, i]) ** 2
                ia, im = np.unravel_index(d.reshape(r.size, -1).argmin(axis=1), d.shape[1:])
                a0[start : start + 32], m0[start : start + 32] = self.a_grid_[ia], self.m_grid_[im]
                s0[start : start + 32] = sigma[ia, im]
            a, m, c = self._gauss_newton(v[rows], a0, m0, int(value), s0)
            out[rows, 0] = self.digit_length_m - a
            out[rows, 1] = m
            cost[rows] = c
        return (out, cost) if return_cost else out

    def _model(self, a, m, command) -> np.ndarray:
        g = self.model.gauges_v(a, m, command)
        if self.tared:
            g = g - self.model.gauges_v(np.zeros(np.size(a)), np.zeros(np.size(a)), command)
        return g

    def no_load_v(self, command) -> np.ndarray:
        """The calibrated model's reading with nothing hung, for each command (n, G)."""
        command = np.atleast_1d(command)
        return self._model(np.zeros(command.size), np.zeros(command.size), command) * self.gain_ + self.offset_

    def _cost(self, v, a, m, command, sigma):
        g = self._model(a, m, np.full(a.size, command)) * self.gain_ + self.offset_
        return np.sum(((v - g) / sigma) ** 2 + 2 * np.log(sigma), axis=1), g

    def _gauss_newton(self, v, a, m, command, sigma, iterations: int = 4):
        """Refine grid estimates by damped Gauss-Newton on the model itself (joint in position and mass), with
        the noise ``sigma`` (n, G) of each reading's best grid point held."""
        step_a, step_m = 1e-4, 1e-5
        cost, g = self._cost(v, a, m, command, sigma)
        for _ in range(iterations):
            ga = (self._cost(v, a + step_a, m, command, sigma)[1] - self._cost(v, a - step_a, m, command, sigma)[1]) / (
                2 * step_a
            )
            gm = (self._cost(v, a, m + step_m, command, sigma)[1] - self._cost(v, a, m - step_m, command, sigma)[1]) / (
                2 * step_m
            )
            r = (v - g) / sigma
            ja, jm = ga / sigma, gm / sigma
            h11, h22, h12 = np.sum(ja * ja, 1), np.sum(jm * jm, 1), np.sum(ja * jm, 1)
            b1, b2 = np.sum(ja * r, 1), np.sum(jm * r, 1)
            det = h11 * h22 - h12**2
            ok = det > 1e-9 * np.maximum(h11 * h22, 1e-300)
            with np.errstate(divide="ignore", invalid="ignore"):
                da = np.where(ok, (h22 * b1 - h12 * b2) / det, 0.0)
                dm = np.where(ok, (h11 * b2 - h12 * b1) / det, 0.0)
            # never leave the digit or go below zero mass; keep a step only if it lowers the cost
            if self.load_set:  # the mass stays the candidate load: a 1-D Gauss-Newton step in position
                da, dm = np.where(h11 > 0, b1 / np.where(h11 > 0, h11, 1.0), 0.0), 0.0 * dm
            a_new = np.clip(a + np.clip(da, -0.01, 0.01), 0.0, self.digit_length_m)
            m_new = np.clip(m + np.clip(dm, -0.01, 0.01), 0.0, None)
            new_cost, new_g = self._cost(v, a_new, m_new, command, sigma)
            better = new_cost < cost
            a, m = np.where(better, a_new, a), np.where(better, m_new, m)
            cost, g = np.where(better, new_cost, cost), np.where(better[:, None], new_g, g)
        return a, m, cost


class GPLocaliser(Estimator):
    """Gaussian-process regression of position and mass from the gauges, with uncertainty.

    One ``GaussianProcessRegressor`` for all target columns (shared kernel ``C * RBF(anisotropic) + White``),
    inputs and targets normalised (E 6.1 style). ``predict(X, return_std=True)`` also gives the predictive standard
    deviation of each estimate (same units as the target).

    Parameters
    ----------
    n_restarts : int
        Optimiser restarts of the kernel hyper-parameters.
    max_train : int
        Training readings used at most (a seeded subsample beyond it: the GP is O(n^3)).
    random_state : int
        Seed of the optimiser restarts and the subsample.
    """

    _parameter_constraints = {
        "n_restarts": [Interval(Integral, 0, None)],
        "max_train": [Interval(Integral, 2, None)],
        "random_state": [Interval(Integral, 0, None), None],
    }

    def __init__(self, n_restarts: int = 0, max_train: int = 500, random_state: int = 0) -> None:
        self.n_restarts = n_restarts
        self.max_train = max_train
        self.random_state = random_state

    def __repr__(self) -> str:
        return (
            f"GPLocaliser(n_restarts={self.n_restarts}, max_train={self.max_train}, random_state={self.random_state})"
        )

    def fit(self, X, Y) -> GPLocaliser:
        from sklearn.exceptions import ConvergenceWarning
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        self._validate_params()
        x = check_array(X, "X", "GPLocaliser.fit", ndim=2, min_length=2)
        y = check_array(Y, "Y", "GPLocaliser.fit")
        y = y.reshape(-1, 1) if y.ndim == 1 else y
        rng = np.random.default_rng(self.random_state)
        if x.shape[0] > self.max_train:
            keep = np.sort(rng.choice(x.shape[0], self.max_train, replace=False))
            x, y = x[keep], y[keep]
        self.x_norm_ = Normaliser().fit(x)
        xn = self.x_norm_.transform(x)
        # one GP for every target column: shared kernel hyper-parameters, each column normalised (normalize_y)
        kernel = ConstantKernel(1.0, (1e-3, 1e3)) * RBF(np.ones(x.shape[1]), (1e-2, 1e3)) + WhiteKernel(
            1e-3, (1e-8, 1.0)
        )
        gp = GaussianProcessRegressor(
            kernel, normalize_y=True, n_restarts_optimizer=self.n_restarts, random_state=self.random_state
        )
        with warnings.catch_warnings():  # hyper-parameters at a bound (e.g. no noise floor) are fine here
            warnings.simplefilter("ignore", ConvergenceWarning)
            gp.fit(xn, y)
        self.models_ = [gp]
        self.n_outputs_ = y.shape[1]
        return self

    def predict(self, X, return_std: bool = False):
        check_is_fitted(self, "models_")
        xn = self.x_norm_.transform(check_array(X, "X", "GPLocaliser.predict", ndim=2))
        mean, std = self.models_[0].predict(xn, return_std=True)
        mean, std = mean.reshape(xn.shape[0], -1), std.reshape(xn.shape[0], -1)
        return (mean, std) if return_std else mean

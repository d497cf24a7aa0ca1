"""Active sensing for hanging loads: read the gauges at several commands under one hang (issue 13 item 4).

Chapter 7's impasse: at the noise that reproduces the thesis's actuated corr2 (the cable-guide friction,
:mod:`flexdigit.twin.sensors`), one reading holds no more than the thesis network already extracts (Bayes limit
22.5 mm, 12 %). But the digit can move: under one hang the load stays put while the servo changes the cable's
tension, so readings at several commands see the same load through different tensions, and the friction state,
drawn once when the weight was hung, scales with the tension in a known way and partly cancels between them
(:func:`flexdigit.tactile.bounds.hang_readings_model`). :func:`flexdigit.tactile.bounds.active_limits` gives the
Bayes limit of that protocol beside the single-reading one; :class:`HangInversion` is the maximum-likelihood
estimate of position and mass from all the readings of a hang (the full covariance of the shared friction);
:func:`simulate_hangs` draws such readings from the twin's statics and noise.
"""

from __future__ import annotations

from numbers import Integral, Real

import numpy as np

from flexdigit._estimator import Estimator, check_is_fitted
from flexdigit._validation import Array, HasMethods, Interval, check_array, check_int, check_positive
from flexdigit.errors import ParameterError
from flexdigit.tactile.bounds import hang_readings_model
from flexdigit.twin.twin import static_gauges_v

__all__ = ["simulate_hangs", "HangInversion", "HangPosterior"]


def simulate_hangs(model, position_from_base_m, mass_kg, commands, *, repetitions: int = 1, seed=0):
    """Readings (n, 3K) of hangs read at every command: one friction draw per hang, shared by its readings, and
    white noise and ADC quantisation per reading (the twin's sensor chain, statics). Rows are settings repeated
    ``repetitions`` times (setting-major)."""
    a = np.repeat(np.atleast_1d(np.asarray(position_from_base_m, dtype=float)), repetitions)
    m = np.repeat(
        np.broadcast_to(np.asarray(mass_kg, dtype=float), np.shape(np.atleast_1d(position_from_base_m))), repetitions
    )
    rng = np.random.default_rng(seed)
    xi = rng.standard_normal((a.size, len(model.params.geometry.gauge_positions_m)))
    out = []
    for j, c in enumerate(commands):
        out.append(
            static_gauges_v(
                m,
                a,
                np.full(a.size, int(c)),
                calibration=model.calibration,
                params=model.params,
                orientation=model.orientation,
                seed=int(rng.integers(2**31)) + j,
                friction_draws=xi,
            )
        )
    return np.concatenate(out, axis=1)


class HangInversion(Estimator):
    """Maximum-likelihood load position and mass from the readings of one hang at several commands.

    ``(a, m) = argmin (v - g(a, m))' C(a, m)^-1 (v - g(a, m)) + log det C(a, m)`` over a grid (positions along the
    digit, masses up to ``max_mass_kg``) with a parabolic refinement in position; ``g`` and ``C`` stacked over the
    commands (:func:`flexdigit.tactile.bounds.hang_readings_model`). ``predict`` returns position from the tip (m)
    and mass (kg), like :class:`flexdigit.tactile.estimators.BeamInversion`.

    Parameters
    ----------
    model : TwinGaugeModel
    commands : sequence of int
        The commands each hang is read at, in the order of the readings' columns.
    digit_length_m, max_mass_kg, position_step_m, mass_steps
        The grid.
    """

    _parameter_constraints = {
        "model": [HasMethods("gauges_v")],
        "commands": [Array(ndim=1, min_length=1, low=0, high=254)],
        "digit_length_m": [Interval(Real, 0, None, closed="neither")],
        "max_mass_kg": [Interval(Real, 0, None, closed="neither")],
        "position_step_m": [Interval(Real, 0, None, closed="neither")],
        "mass_steps": [Interval(Integral, 3, None)],
    }

    def __init__(self, model, commands, *, digit_length_m=0.270, max_mass_kg=0.06, position_step_m=1e-3, mass_steps=61):
        self.model = model
        self.commands = commands
        self.digit_length_m = digit_length_m
        self.max_mass_kg = max_mass_kg
        self.position_step_m = position_step_m
        self.mass_steps = mass_steps

    def __repr__(self) -> str:
        return (
            f"HangInversion(commands={list(self.commands)}, digit_length_m={self.digit_length_m}, "
            f"max_mass_kg={self.max_mass_kg}, position_step_m={self.position_step_m}, mass_steps={self.mass_steps})"
        )

    def fit(self, X=None, y=None) -> HangInversion:
        self._validate_params()
        owner = "HangInversion"
        self.commands_ = [check_int(c, "commands", owner, low=0, high=254) for c in self.commands]
        if not self.commands_:
            raise ParameterError(f"The 'commands' parameter of {owner} must list at least one command.")
        length = check_positive(self.digit_length_m, "digit_length_m", owner)
        step = check_positive(self.position_step_m, "position_step_m", owner)
        self.a_grid_ = np.arange(0.0, length + step / 2, step)
        self.m_grid_ = np.linspace(
            0.0,
            check_positive(self.max_mass_kg, "max_mass_kg", owner),
            check_int(self.mass_steps, "mass_steps", owner, low=3),
        )[1:]
        aa, mm = np.meshgrid(self.a_grid_, self.m_grid_, indexing="ij")
        mean, chol = hang_readings_model(self.model, aa.ravel(), mm.ravel(), self.commands_)
        self.mean_ = mean
        self.inv_chol_ = np.linalg.inv(chol)
        self.log_det_ = 2 * np.sum(np.log(np.abs(np.einsum("kdd->kd", chol))), axis=1)
        self.shape_ = aa.shape
        return self

    def cost(self, V) -> np.ndarray:
        """Negative log-likelihood (x2, up to a constant) of each reading vector at every grid point (n, na, nm)."""
        v = check_array(V, "V", "HangInversion", ndim=2)
        if v.shape[1] != self.mean_.shape[1]:
            raise ParameterError(
                f"HangInversion expects {self.mean_.shape[1]} columns (3 gauges x {len(self.commands_)} commands). "
                f"Got {v.shape[1]}."
            )
        out = np.empty((v.shape[0], self.mean_.shape[0]))
        for start in range(0, v.shape[0], 8):
            r = v[start : start + 8, None, :] - self.mean_[None]
            z = np.einsum("kde,nke->nkd", self.inv_chol_, r)
            out[start : start + 8] = np.sum(z * z, axis=2) + self.log_det_
        return out.reshape(v.shape[0], *self.shape_)

    def predict(self, V) -> np.ndarray:
        check_is_fitted(self, "mean_")
        cost = self.cost(V)
        n = cost.shape[0]
        flat = cost.reshape(n, -1).argmin(axis=1)
        ia, im = np.unravel_index(flat, self.shape_)
        # parabola through the best position and its neighbours at the best mass
        j = np.clip(ia, 1, self.a_grid_.size - 2)
        rows = np.arange(n)
        c0, c1, c2 = cost[rows, j - 1, im], cost[rows, j, im], cost[rows, j + 1, im]
        denom = c0 - 2 * c1 + c2
        with np.errstate(divide="ignore", invalid="ignore"):
            shift = np.where((denom > 0) & (ia == j), 0.5 * (c0 - c2) / denom, 0.0)
        a = self.a_grid_[ia] + np.clip(shift, -1, 1) * self.position_step_m
        return np.column_stack([self.digit_length_m - a, self.m_grid_[im]])


class HangPosterior(Estimator):
    """The Bayes estimate of position and mass of a hang read at several commands, knowing the protocol's settings
    (the estimator :func:`flexdigit.tactile.bounds.active_limits` scores): the posterior mean of the position and
    the relative-error optimum of the mass over ``settings``, with the full covariance of the shared friction.

    Parameters
    ----------
    model : TwinGaugeModel
    commands : sequence of int
    position_from_base_m, mass_kg : array_like (k,)
        The protocol's loaded settings.
    weights : array_like (k,), optional
        How often each occurs.
    """

    _parameter_constraints = {
        "model": [HasMethods("gauges_v")],
        "commands": [Array(ndim=1, min_length=1, low=0, high=254)],
        "position_from_base_m": [Array(ndim=1, min_length=1, low=0)],
        "mass_kg": [Array(low=0, low_open=True)],
        "weights": [Array(ndim=1, low=0), None],
        "digit_length_m": [Interval(Real, 0, None, closed="neither")],
    }

    def __init__(self, model, commands, position_from_base_m, mass_kg, weights=None, digit_length_m=0.270) -> None:
        self.model = model
        self.commands = commands
        self.position_from_base_m = position_from_base_m
        self.mass_kg = mass_kg
        self.weights = weights
        self.digit_length_m = digit_length_m

    def fit(self, X=None, y=None) -> HangPosterior:
        self._validate_params()
        self.a_ = np.atleast_1d(np.asarray(self.position_from_base_m, dtype=float))
        self.m_ = np.broadcast_to(np.asarray(self.mass_kg, dtype=float), self.a_.shape)
        w = np.ones(self.a_.size) if self.weights is None else np.asarray(self.weights, dtype=float)
        self.log_prior_ = np.log(w / w.sum())
        mean, chol = hang_readings_model(self.model, self.a_, self.m_, list(self.commands))
        self.mean_, self.inv_chol_ = mean, np.linalg.inv(chol)
        self.log_det_ = np.sum(np.log(np.abs(np.einsum("kdd->kd", chol))), axis=1)
        return self

    def predict(self, V) -> np.ndarray:
        check_is_fitted(self, "mean_")
        v = check_array(V, "V", "HangPosterior", ndim=2, shape=(None, self.mean_.shape[1]))
        z = np.einsum("kde,nke->nkd", self.inv_chol_, v[:, None, :] - self.mean_[None])
        log_post = self.log_prior_ - 0.5 * np.sum(z * z, axis=2) - self.log_det_
        post = np.exp(log_post - log_post.max(axis=1, keepdims=True))
        post /= post.sum(axis=1, keepdims=True)
        a = post @ self.a_
        m = (post @ (1.0 / self.m_)) / (post @ (1.0 / self.m_**2))
        return np.column_stack([self.digit_length_m - a, m])

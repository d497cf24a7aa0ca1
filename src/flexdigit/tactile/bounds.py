"""What the gauges can tell, physically: the Cramer-Rao bound of the load position and an identifiability map.

A *gauge model* is anything with ``gauges_v(position_from_base_m, mass_kg, command) -> (n, 3)`` (the static,
noise-free gauge voltages with one point load; ``command`` :data:`~flexdigit.tactile.protocols.RELAXED` for
actuation disabled; ``mass_kg`` 0 means no load) and ``noise_v`` (3,), the standard deviation of one reading per
gauge (V). :class:`TwinGaugeModel` wraps the digital twin; tests use a closed-form cantilever.

For independent Gaussian noise, the Fisher information of ``theta = (a, m)`` (position, mass) in one reading is
``F = J^T diag(1/sigma^2) J`` with ``J = dg/dtheta`` (finite differences of the model). A model whose noise
depends on the load (``noise_at``: the twin's cable-guide friction grows with the cable tension, which the load
changes) adds the information the spread itself carries, ``2 sum_k (dsigma_k/dtheta_i)(dsigma_k/dtheta_j) /
sigma_k^2`` (the Gaussian Fisher information's covariance term for a diagonal covariance). The position's Cramer-Rao
bound is ``sqrt([F^-1]_aa)`` when the mass is unknown, and ``sigma_a = 1/sqrt(F_aa)`` when it is known. A load
between the clamp and gauge 1 bends no gauge (no moment reaches a gauge beyond the load on a cantilever): its
Fisher information is zero and nothing can locate it; between gauges 1 and 2 only gauge 1 bends, so ``F`` has
rank 1 and position and mass are confounded (only the moment ``m g (a - x_1)`` is seen).

Examples
--------
>>> import numpy as np
>>> class Line:
...     noise_v = np.array([0.01, 0.01, 0.01])
...     def gauges_v(self, a, m, command):
...         a, m = np.broadcast_arrays(np.atleast_1d(a), np.atleast_1d(m))
...         return 40.0 * (m * 9.81)[:, None] * np.clip(a[:, None] - [0.045, 0.135, 0.225], 0, None)
>>> zone_of(Line(), 0.03, 0.025, -1)
'no gauge bends'
>>> zone_of(Line(), 0.10, 0.025, -1)
'position and mass confounded'
>>> zone_of(Line(), 0.25, 0.025, -1)
'identifiable'
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit.params import RigParams
from flexdigit.tactile.protocols import RELAXED
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, friction_sd_v, static_gauges_v

__all__ = [
    "ZONES",
    "jacobian",
    "Bound",
    "noise_of",
    "cramer_rao",
    "zone_of",
    "TwinGaugeModel",
    "readings_gauge_model",
    "ProtocolLimits",
    "protocol_limits",
    "span_position_mse_m2",
    "span_posterior_mean_m",
    "CONTACT_ZONES",
    "FORCE_ONLY_FRACTION",
    "point_jacobian",
    "line_jacobian",
    "line_steps",
    "fisher_sd",
    "ContactBound",
    "contact_bounds",
    "line_bounds",
    "gaussian_bayes_limits",
    "hang_readings_model",
    "active_limits",
]

ZONES = ("no gauge bends", "position and mass confounded", "identifiable")


def jacobian(model, position_from_base_m, mass_kg, command, step_m: float = 2e-4, rel_step_mass: float = 0.02):
    """``dg/da`` (V/m) and ``dg/dm`` (V/kg) by central differences, each of shape (n, 3)."""
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
    m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
    c = np.broadcast_to(np.asarray(command), a.shape)
    dm = rel_step_mass * np.maximum(m, 1e-4)
    ga = (model.gauges_v(a + step_m, m, c) - model.gauges_v(a - step_m, m, c)) / (2 * step_m)
    gm = (model.gauges_v(a, m + dm, c) - model.gauges_v(a, m - dm, c)) / (2 * dm)[:, None]
    return ga, gm


@dataclass
class Bound:
    """Cramer-Rao bounds of one reading, per point (m): mass unknown and mass known; the zone of each point."""

    position_from_base_m: np.ndarray
    crlb_m: np.ndarray
    crlb_known_mass_m: np.ndarray
    zone: np.ndarray

    __repr__ = fields_summary


def noise_of(model, position_from_base_m, mass_kg, command) -> np.ndarray:
    """Standard deviation (V) of one reading per point and gauge, (n, 3): the model's ``noise_at`` if it has one
    (load-dependent noise), else its constant ``noise_v``."""
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
    if hasattr(model, "noise_at"):
        m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
        return np.asarray(model.noise_at(a, m, np.broadcast_to(np.asarray(command), a.shape)), dtype=float)
    noise = np.asarray(model.noise_v, dtype=float)
    return np.broadcast_to(noise, (a.size, noise.size))


def cramer_rao(
    model,
    position_from_base_m,
    mass_kg,
    command=RELAXED,
    *,
    step_m: float = 2e-4,
    noise_v=None,
    extra_variance_v2=None,
) -> Bound:
    """Cramer-Rao lower bounds of the position (m, one reading) at each ``(position, mass, command)``.

    Infinite where the position cannot be estimated at all (no gauge bends) or, for ``crlb_m``, where position
    and mass are confounded (a rank-1 Fisher information). The noise is the model's (:func:`noise_of`, with the
    information in a load-dependent spread, module docstring); ``noise_v`` (3,) or (n, 3) overrides it with a
    fixed one; ``extra_variance_v2`` (3,) or (n, 3) adds a load-independent variance (e.g. the drift accumulated
    since the last tare).
    """
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
    m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
    ga, gm = jacobian(model, a, m, command, step_m=step_m)
    extra = 0.0 if extra_variance_v2 is None else np.asarray(extra_variance_v2, dtype=float)
    if noise_v is not None:
        sigma = np.sqrt(np.asarray(noise_v, dtype=float) ** 2 + extra)
        sa = sm = np.zeros_like(ga)
    else:

        def total(aa, mm):
            return np.sqrt(noise_of(model, aa, mm, command) ** 2 + extra)

        sigma = total(a, m)
        if hasattr(model, "noise_at"):  # d sigma / d theta, the same differences as the jacobian
            dm = 0.02 * np.maximum(m, 1e-4)
            sa = (total(a + step_m, m) - total(a - step_m, m)) / (2 * step_m)
            sm = (total(a, m + dm) - total(a, m - dm)) / (2 * dm)[:, None]
        else:
            sa = sm = np.zeros_like(ga)
    w = 1.0 / sigma**2
    faa = np.sum(w * (ga * ga + 2 * sa * sa), axis=1)
    fmm = np.sum(w * (gm * gm + 2 * sm * sm), axis=1)
    fam = np.sum(w * (ga * gm + 2 * sa * sm), axis=1)
    det = faa * fmm - fam**2
    with np.errstate(divide="ignore", invalid="ignore"):
        known = np.where(faa > 0, 1.0 / np.sqrt(faa), np.inf)
        # relative conditioning: det / (faa fmm) = 1 - cos^2 of the angle between the two sensitivity directions
        cos2 = np.where(faa * fmm > 0, fam**2 / (faa * fmm), 1.0)
        unknown = np.where((faa > 0) & (1.0 - cos2 > 1e-6), np.sqrt(fmm / det), np.inf)
    zone = np.array([_zone(k, u) for k, u in zip(known, unknown, strict=True)], dtype=object)
    # a load that moves no gauge by even a tenth of its noise counts as invisible
    dg = np.abs(model.gauges_v(a, m, np.broadcast_to(command, a.shape)) - model.gauges_v(a, 0.0 * m, command))
    invisible = np.all(dg < 0.1 * sigma, axis=1)
    zone[invisible] = ZONES[0]
    known = np.where(invisible, np.inf, known)
    unknown = np.where(zone == ZONES[2], unknown, np.inf)
    return Bound(a, unknown, known, zone)


def _zone(known: float, unknown: float) -> str:
    if not np.isfinite(known):
        return ZONES[0]
    if not np.isfinite(unknown):
        return ZONES[1]
    return ZONES[2]


def zone_of(model, position_from_base_m: float, mass_kg: float, command=RELAXED) -> str:
    """The identifiability zone of one load (see :data:`ZONES`)."""
    return str(cramer_rao(model, [position_from_base_m], mass_kg, command).zone[0])


class TwinGaugeModel:
    """The digital twin's static gauge model and white noise, as a gauge model for the bounds and the inversion.

    Uses the twin's batched static solver (:func:`flexdigit.twin.twin.static_gauges_v`), horizontal digit, no ADC
    quantisation. A reading with command :data:`~flexdigit.tactile.protocols.RELAXED` (actuation disabled,
    chapter 6) is modelled with the cable detached, as the twin models the non-actuated digit.

    Parameters
    ----------
    params : RigParams, optional
    calibration : Calibration, optional
        The twin's calibration (default: the digit's own, :func:`~flexdigit.twin.digit_calibration.twin_calibration`).
    orientation : str
        How the digit lies (the protocols' "horizontal").
    cells_per_section : int
        Springs per section of the twin's chain (its default, 3, unless a study needs finer: a load's effect on a
        gauge is resolved to one cell).

    Attributes
    ----------
    noise_v : ndarray, shape (3,)
        White noise per reading (V): the calibration's ``noise_white_v``. With a taut cable the twin adds the
        cable-guide friction, whose spread depends on the load: :meth:`noise_at`.
    drift_v_per_sqrt_s : ndarray, shape (3,)
        The twin's random-walk drift rate: ``t`` seconds after a tare it adds variance ``rate^2 t``.
    """

    def __init__(self, params=None, calibration=None, orientation: str = "horizontal", cells_per_section=None) -> None:
        self.params = params or RigParams()
        self.calibration = calibration or twin_calibration(self.params)
        self.orientation = orientation
        self.cells_per_section = DEFAULT_CELLS_PER_SECTION if cells_per_section is None else cells_per_section
        self.noise_v = np.asarray(self.calibration.noise_white_v, dtype=float)
        self.drift_v_per_sqrt_s = np.asarray(self.calibration.noise_drift_v_per_sqrt_s, dtype=float)
        self.adc_range_v = None  # (low, high): the card's rails, where the readings are clipped (readings_gauge_model)
        self._kept: dict[tuple, dict] = {}  # the last static solves (_static)

    def __repr__(self) -> str:
        return f"TwinGaugeModel(orientation={self.orientation!r}, noise_v={self.noise_v.tolist()})"

    def gauges_v(self, position_from_base_m, mass_kg, command) -> np.ndarray:
        volts = self._solve(position_from_base_m, mass_kg, command, False)
        return volts if self.adc_range_v is None else np.clip(volts, *self.adc_range_v)

    def noise_at(self, position_from_base_m, mass_kg, command) -> np.ndarray:
        """Standard deviation (V) of one reading, (n, 3): white noise and, with a taut cable, the cable-guide
        friction at that load's tension (:func:`flexdigit.twin.twin.friction_sd_v`, the model the twin draws from).
        """
        friction = self._solve(position_from_base_m, mass_kg, command, True)
        return np.sqrt(self.noise_v**2 + friction**2)

    def _solve(self, position_from_base_m, mass_kg, command, friction: bool) -> np.ndarray:
        a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
        m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
        c = np.broadcast_to(np.asarray(command), a.shape)
        a = np.clip(a, 0.0, self.params.geometry.digit_length_m)  # finite differences may step past the tip
        m = np.maximum(m, 0.0)
        out = np.empty((a.size, len(self.params.geometry.gauge_positions_m)))  # any number of gauges (studies)
        for value in np.unique(c):
            rows = c == value
            if friction and (value == RELAXED or self.calibration.cable_friction_ratio == 0):
                out[rows] = 0.0  # no cable, or no friction: skip the solve
                continue
            out[rows] = self._static(a[rows], m[rows], value, friction)
        return out

    #: Static solves kept per model: the inversion asks for a grid's voltages, then for its noise (one solve); a
    #: Cramer-Rao bound for the voltages at five loads, then for the noise at the same five (4 kept solved 367 of
    #: a one-gauge digit's 1287 again in its report), the inversion's Gauss-Newton for its tare at each step
    _KEPT = 16

    def _static(self, a, m, command, friction: bool) -> np.ndarray:
        """Voltages (or friction spread) of the cases ``(a, m)`` at one command, from one static solve kept for
        both; identical cases (a tare's no-load readings over a whole grid) solved once."""
        settings = (self.params, self.calibration, self.orientation, self.cells_per_section)
        key = (int(command), a.tobytes(), m.tobytes())
        kept = self._kept
        hit = kept.get(key)
        if hit is None or any(x is not y for x, y in zip(hit["settings"], settings, strict=True)):
            cases = np.column_stack([a, m])
            unique, inverse = np.unique(cases, axis=0, return_inverse=True)
            if unique.shape[0] == cases.shape[0]:
                unique, inverse = cases, None  # nothing repeated: solved as given
            volts, sol = static_gauges_v(
                unique[:, 1],
                unique[:, 0],
                None if command == RELAXED else np.full(unique.shape[0], int(command)),
                params=self.params,
                calibration=self.calibration,
                orientation=self.orientation,
                cells_per_section=self.cells_per_section,
                adc=False,
                return_solution=True,
            )
            hit = {"settings": settings, "volts": volts, "solution": sol, "inverse": inverse}
            while len(kept) >= self._KEPT:
                kept.pop(next(iter(kept)))
            kept[key] = hit
        if friction and "friction" not in hit:
            hit["friction"] = friction_sd_v(
                hit["solution"],
                self.params,
                self.calibration,
                orientation=self.orientation,
                cells_per_section=self.cells_per_section,
            )
        values = hit["friction"] if friction else hit["volts"]
        return values if hit["inverse"] is None else values[hit["inverse"].ravel()]


def readings_gauge_model(params=None, calibration=None):
    """The twin's gauge model (:class:`~flexdigit.tactile.bounds.TwinGaugeModel`) of a digit as its card reads it:
    white noise and the ADC's quantisation, ``lsb / sqrt(12)`` (a uniform rounding error), per gauge, V.

    The quantisation matters on a digit whose amplified noise is below one LSB (a quarter bridge's small signal):
    the readings then carry the rounding, and a Bayes limit without it would be a floor no estimator could reach.
    The studies' ``bayes_position_limit_mm`` models the readings the same way. The static voltages are clipped
    to the card's range (``adc_range_v``), as the readings are: a gauge past a rail reads the rail whatever the
    load (a 0-3.3 V card under a half bridge swinging negative reads 0 on every gauge; its limit was 4 mm for a
    network that could only read 61 mm). Near a rail the clipped mean with Gaussian noise is an approximation
    (a censored reading's exact likelihood is not modelled).
    """
    model = TwinGaugeModel(params, calibration)
    sensors = (params or RigParams()).sensors
    model.noise_v = np.sqrt(np.asarray(model.noise_v, dtype=float) ** 2 + sensors.adc_lsb_v**2 / 12.0)
    model.adc_range_v = tuple(sensors.adc_range_v)
    return model


@dataclass
class ProtocolLimits:
    """What the best possible estimator achieves on a protocol's settings (:func:`protocol_limits`), per setting.

    Attributes
    ----------
    position_from_base_m, mass_kg, command : ndarray, shape (k,)
        The settings (``mass_kg`` 0: no load).
    contact_error : ndarray
        Probability that the Bayes load / no-load decision is wrong on a reading of this setting.
    position_mse_m2 : ndarray
        Mean squared error (m^2) of the Bayes (posterior-mean) position of a loaded reading; NaN for no load.
    magnitude_rel_mse : ndarray
        Mean squared relative error of the Bayes mass estimate for the relative-error loss; NaN for no load.
    """

    position_from_base_m: np.ndarray
    mass_kg: np.ndarray
    command: np.ndarray
    contact_error: np.ndarray
    position_mse_m2: np.ndarray
    magnitude_rel_mse: np.ndarray

    def index(self, position_from_base_m, mass_kg, command) -> np.ndarray:
        """The setting of each reading (``position_from_base_m`` is ignored where ``mass_kg`` is 0)."""
        keys = {k: i for i, k in enumerate(_setting_keys(self.position_from_base_m, self.mass_kg, self.command))}
        try:
            return np.array([keys[k] for k in _setting_keys(position_from_base_m, mass_kg, command)], dtype=int)
        except KeyError as err:
            raise ValueError(f"reading at setting {err.args[0]} is not one of the protocol's settings") from None

    __repr__ = fields_summary


def _setting_keys(a, m, c) -> list[tuple]:
    a, m, c = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (a, m, c))
    a = np.where(m > 0, np.nan_to_num(a, nan=0.0), 0.0)
    return [(round(x, 6), round(y, 9), int(z)) for x, y, z in zip(a, m, c, strict=True)]


def protocol_limits(
    model, position_from_base_m, mass_kg, command, weights=None, *, samples: int = 4000, seed=0, no_load_noise_v=None
):
    """Bayes limits of contact, position and magnitude on a protocol's discrete settings (Monte Carlo).

    The Cramer-Rao bound is for an unbiased estimate of a continuous position; an estimator trained on a protocol
    also knows that loads hang at a short list of positions and masses, and can beat it. This is the limit for
    such estimators: readings of every setting are drawn from the model's Gaussian noise (``noise_of``), and
    each is given the Bayes-optimal answer knowing the settings, their frequencies (``weights``) and the servo
    command: load / no load by the larger posterior, the position by the posterior mean over loaded settings
    (the minimiser of the squared error), the mass by ``sum p_k / m_k / sum p_k / m_k^2`` (the minimiser of the
    squared *relative* error). No estimator does better on average on readings drawn this way; the model omits
    drift, tare and ADC quantisation, so the limits are, if anything, optimistic.

    Parameters
    ----------
    model : gauge model
    position_from_base_m, mass_kg, command : array_like, shape (k,)
        The protocol's distinct settings; ``mass_kg`` 0 is a no-load reading (its position is ignored).
    weights : array_like, shape (k,), optional
        How often each setting occurs (default: equally often).
    samples : int
        Monte Carlo readings per setting.
    seed : int or sequence of int
        Seeds the draws: same seed, same limits.
    no_load_noise_v : array_like, shape (3,), optional
        Noise of the no-load readings instead of the model's (e.g. the white noise alone for readings tared on
        their own test's no-load readings, which share one cable-guide friction state).
    """
    keys = _setting_keys(position_from_base_m, mass_kg, command)
    if len(set(keys)) != len(keys):
        raise ValueError("protocol_limits needs distinct settings; got repeated (position, mass, command) rows")
    a = np.array([k[0] for k in keys])
    m = np.array([k[1] for k in keys])
    c = np.array([k[2] for k in keys])
    w = np.ones(a.size) if weights is None else np.asarray(weights, dtype=float)
    mean = model.gauges_v(a, m, c)
    sigma = noise_of(model, a, m, c)
    if no_load_noise_v is not None:
        sigma = np.where((m > 0)[:, None], sigma, np.asarray(no_load_noise_v, dtype=float))
    rng = np.random.default_rng(seed)
    contact_error = np.zeros(a.size)
    pos_mse = np.full(a.size, np.nan)
    mag_mse = np.full(a.size, np.nan)
    for value in np.unique(c):
        group = np.flatnonzero(c == value)
        loaded = m[group] > 0
        log_prior = np.log(w[group] / w[group].sum())
        inv_var = 1.0 / sigma[group] ** 2
        log_norm = np.sum(np.log(sigma[group]), axis=1)
        for j in group:
            noise = sigma[j] * rng.standard_normal((samples, mean.shape[1]))  # a reading of setting j less its mean
            # log posterior over the group's settings (up to a constant), (samples, len(group)): the squared
            # distances sum_g (v_g - mean_kg)^2 / sigma_kg^2 as three products, about setting j's mean so that no
            # term is large where a posterior is not negligible (a (samples, group, gauges) array was 3/4 of the time)
            near = mean[group] - mean[j]
            z2 = (noise**2) @ inv_var.T - 2.0 * (noise @ (near * inv_var).T) + np.sum(near**2 * inv_var, axis=1)
            log_post = log_prior - 0.5 * z2 - log_norm
            post = np.exp(log_post - log_post.max(axis=1, keepdims=True))
            post /= post.sum(axis=1, keepdims=True)
            p_load = post[:, loaded].sum(axis=1)
            contact_error[j] = np.mean((p_load > 0.5) != (m[j] > 0))
            if m[j] > 0:
                pl = post[:, loaded]
                pl = pl / np.maximum(pl.sum(axis=1, keepdims=True), 1e-300)
                pos_mse[j] = np.mean((pl @ a[group][loaded] - a[j]) ** 2)
                mg = m[group][loaded]
                m_hat = (pl @ (1.0 / mg)) / (pl @ (1.0 / mg**2))
                mag_mse[j] = np.mean(((m_hat - m[j]) / m[j]) ** 2)
    return ProtocolLimits(a, m, c, contact_error, pos_mse, mag_mse)


def _position_grid(positions_m, step_m: float, half_width_m) -> np.ndarray:
    """A lattice of ``step_m`` over ``[min, max]`` of ``positions_m`` (``half_width_m`` None) or over the union of
    ``[a - half_width_m, a + half_width_m]`` around each.

    The positions themselves are not added to it: a position between two lattice points made the grid denser
    there, a prior heavier at the protocol's positions than between them, which pulled the posterior mean to the
    true position (a linear gauge's limit 1.88 mm at off-lattice positions against 2.00 on it and ``sigma / k`` =
    2.00 in closed form; tests/tactile/test_bayes_floor.py)."""
    a = np.unique(positions_m)
    if half_width_m is None:
        lo, hi = a.min(), a.max()
    else:
        lo, hi = a - half_width_m, a + half_width_m
    k = np.arange(np.floor(np.min(lo) / step_m), np.ceil(np.max(hi) / step_m) + 1)
    lattice = k * step_m
    if half_width_m is not None:
        near = np.min(np.abs(lattice[:, None] - a[None, :]), axis=1) <= half_width_m + 1e-12
        lattice = lattice[near]
    else:
        lattice = lattice[(lattice >= lo - 1e-12) & (lattice <= hi + 1e-12)]
    return lattice if lattice.size else a


def _span_prior(model, positions_m, masses_kg, command, step_m: float, half_width_m):
    """The span prior of one command's loaded settings: the grid's positions (one per grid point and mass), their
    log prior (uniform in position, the masses as often as the settings have them), the model's gauges there and
    their noise variance (V^2)."""
    grid = _position_grid(positions_m, step_m, half_width_m)
    masses, counts = np.unique(masses_kg, return_counts=True)
    ga = np.repeat(grid, masses.size)
    gm = np.tile(masses, grid.size)
    gc = np.full(ga.size, command)
    # a uniform density in position: the lattice's points weigh alike
    log_prior = np.log(np.tile(counts / counts.sum(), grid.size))
    return ga, log_prior, model.gauges_v(ga, gm, gc), noise_of(model, ga, gm, gc) ** 2


def span_posterior_mean_m(
    model,
    position_from_base_m,
    mass_kg,
    command,
    readings_v,
    reading_command,
    *,
    step_m: float,
    half_width_m=None,
    extra_variance_v2=None,
) -> np.ndarray:
    """The span prior's Bayes estimate (posterior mean, m from the base) of each of ``readings_v`` (n, G), the
    estimator whose error :func:`span_position_mse_m2` averages, applied to readings given rather than drawn.

    The prior is built, as there, from the loaded settings ``(position_from_base_m, mass_kg, command)``; a reading
    is weighed against the grid of its command (``reading_command``, (n,)). On readings that carry only the model's
    noise its RMS error is the limit (within its scatter); on a run's real readings it says what the limit does not
    count (a gauge's drift, a twin unlike the digit): the estimator that knows the twin's response exactly cannot
    do better than it does there.

    ``extra_variance_v2`` (n, G) or (G,), per reading: a variance it carries beyond the model's (its drift since its
    reference, :func:`flexdigit.tactile.localisation.drift_variance_v2`), added to the likelihood as
    :func:`span_position_mse_m2` adds it: the estimator of the drift-counted limit.
    """
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
    m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
    c = np.broadcast_to(np.asarray(command), a.shape).astype(int)
    v = np.atleast_2d(np.asarray(readings_v, dtype=float))
    rc = np.broadcast_to(np.asarray(reading_command), v.shape[:1]).astype(int)
    extra = np.zeros((1, 1)) if extra_variance_v2 is None else np.asarray(extra_variance_v2, dtype=float)
    extra = np.broadcast_to(extra if extra.ndim == 2 else extra[None, :], v.shape)
    if not step_m > 0:
        raise ValueError(f"span_posterior_mean_m needs a positive grid step; got step_m = {step_m}")
    out = np.full(v.shape[0], np.nan)
    for value in np.unique(rc):
        group = (c == value) & (m > 0)
        if not np.any(group):
            continue
        ga, log_prior, mean, noise2 = _span_prior(model, a[group], m[group], value, step_m, half_width_m)
        which = np.flatnonzero(rc == value)
        per = max(1, int(4e6 // mean.size))
        for start in range(0, which.size, per):
            idx = which[start : start + per]
            total = None  # gauge by gauge, summed in gauge order (as _chi2)
            for g in range(v.shape[1]):
                var = noise2[None, :, g] + extra[idx, None, g]  # (readings, grid)
                term = (v[idx, None, g] - mean[None, :, g]) ** 2 / var + np.log(var)
                total = term if total is None else np.add(total, term, out=total)
            log_post = log_prior - 0.5 * total
            post = np.exp(log_post - log_post.max(axis=1, keepdims=True))
            out[idx] = (post @ ga) / post.sum(axis=1)
    return out


def _chi2(v, mean, sigma) -> np.ndarray:
    """``sum_g ((v[r, g] - mean[k, g]) / sigma[k, g])^2`` of readings ``v`` (n, G) on a grid's ``mean``, ``sigma``
    (K, G): (n, K). Gauge by gauge on (n, K) planes, summed in gauge order as ``np.sum(z * z, axis=2)`` sums them
    (the same numbers up to 7 gauges; round-off beyond): the (n, K, G) array's broadcasting and its reduction over
    a last axis of a few gauges were 4/5 of the span limit's time."""
    total = None
    for g in range(v.shape[1]):
        z = (v[:, g, None] - mean[None, :, g]) / sigma[None, :, g]
        z *= z
        total = z if total is None else np.add(total, z, out=total)
    return total


def span_position_mse_m2(
    model,
    position_from_base_m,
    mass_kg,
    command,
    *,
    step_m: float,
    half_width_m=None,
    samples: int = 1000,
    seed=0,
    chunk: int = 200,
    extra_variance_v2=None,
) -> np.ndarray:
    """Bayes position MSE (m^2) of each loaded setting when the position is continuous over the settings' span.

    :func:`protocol_limits` knows the load hangs at one of the protocol's positions: where those are many noise
    sigmas apart its posterior never mixes them and the limit falls to zero (10^-14 m on a stiff polymer digit),
    a floor no regression of a continuous position reaches. Here the prior is uniform in position over
    ``[min, max]`` of each command's loaded positions (a grid of ``step_m``, the settings' own positions on it)
    and the masses are the settings' (their frequencies at that command); readings are drawn at each setting
    from the model's Gaussian noise (``noise_of``) and given the posterior mean over that grid. For a linear
    gauge ``g = k a`` with noise ``sigma`` the result is ``(sigma / k)^2`` away from the span's ends (the
    Gaussian posterior; tested). ``step_m`` must resolve the posterior (a quarter of the smallest Cramer-Rao
    bound adds under 1 % to the RMS).

    ``extra_variance_v2`` (G,) or (k, G), per setting: a variance its readings carry beyond the model's, independent
    of the load (the gauges' drift since the readings' reference, :func:`flexdigit.tactile.localisation.
    drift_variance_v2`), added to the draws and to the posterior's likelihood of that setting's readings alike
    (the estimator knows how much drift a reading may carry, not which). For the linear gauge the limit becomes
    ``sqrt(sigma^2 + s^2) / k`` (tested).

    Returns an array like ``mass_kg``: the MSE of each loaded setting, NaN for no-load ones.
    """
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
    m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
    c = np.broadcast_to(np.asarray(command), a.shape).astype(int)
    if not step_m > 0:
        raise ValueError(f"span_position_mse_m2 needs a positive grid step; got step_m = {step_m}")
    extra = np.zeros((a.size, 1)) if extra_variance_v2 is None else np.asarray(extra_variance_v2, dtype=float)
    extra = np.broadcast_to(extra if extra.ndim == 2 else extra[None, :], (a.size, extra.shape[-1]))
    rng = np.random.default_rng(seed)
    out = np.full(a.size, np.nan)
    for value in np.unique(c[m > 0]):
        group = np.flatnonzero((c == value) & (m > 0))
        ga, log_prior, mean, noise2 = _span_prior(model, a[group], m[group], value, step_m, half_width_m)
        mu = model.gauges_v(a[group], m[group], c[group])
        sd = np.sqrt(noise_of(model, a[group], m[group], c[group]) ** 2 + extra[group])
        per = max(1, min(chunk, int(4e6 // mean.size)))  # (draws, grid, gauges) floats held at once
        for i, j in enumerate(group):
            sigma = np.sqrt(noise2 + extra[j])  # the grid's likelihood of this setting's readings
            log_norm = log_prior - np.sum(np.log(sigma), axis=1)
            err2 = 0.0
            for start in range(0, samples, per):
                n = min(per, samples - start)
                v = mu[i] + sd[i] * rng.standard_normal((n, mu.shape[1]))
                log_post = log_norm - 0.5 * _chi2(v, mean, sigma)
                post = np.exp(log_post - log_post.max(axis=1, keepdims=True))
                err2 += float(np.sum(((post @ ga) / post.sum(axis=1) - a[j]) ** 2))
            out[j] = err2 / samples
    return out


# ---------------------------------------------------------------------------------------------------- contact
#: Identifiability of a contact (issue 13): nothing seen; only a product of force and position seen; the force
#: seen but not where it acts (the position's bound beyond :data:`FORCE_ONLY_FRACTION` of the digit); both.
CONTACT_ZONES = ("no gauge bends", "position and force confounded", "force only", "identifiable")
#: A position bound beyond this fraction of the digit's length counts as "force only".
FORCE_ONLY_FRACTION = 0.1


def point_jacobian(model, position_m, force_n, command, step_m: float = 2e-4, rel_step_force: float = 0.01):
    """``d gauges / d (position, force)`` of a point contact (V/m, V/N), shape (n, 3, 2), by central differences
    of ``model.point_v`` (:class:`flexdigit.palpation.contact_estimation.ContactGaugeModel`), one-sided at the digit's
    ends."""
    s = np.atleast_1d(np.asarray(position_m, dtype=float))
    f = np.broadcast_to(np.asarray(force_n, dtype=float), s.shape)
    length = model.length_m
    lo, hi = np.maximum(s - step_m, 0.0), np.minimum(s + step_m, length)
    df = rel_step_force * np.maximum(np.abs(f), 1e-3)
    batch_s = np.concatenate([hi, lo, s, s])
    batch_f = np.concatenate([f, f, f + df, f - df])
    cmd = np.broadcast_to(np.asarray(command), s.shape)
    v = model.point_v(batch_s, batch_f, np.tile(cmd, 4)).reshape(4, s.size, -1)  # G gauges
    d_pos = (v[0] - v[1]) / (hi - lo)[:, None]
    d_force = (v[2] - v[3]) / (2 * df)[:, None]
    return np.stack([d_pos, d_force], axis=2)


def line_jacobian(model, centre_m, extent_m, total_n, command, step_m: float = 5e-4, rel_step_force: float = 0.01):
    """``d gauges / d (centre, extent, total)`` of an even line load, shape (n, 3, 3), by central differences
    of ``model.line_v`` (steps shrunk to stay on the digit)."""
    c = np.atleast_1d(np.asarray(centre_m, dtype=float))
    w = np.broadcast_to(np.asarray(extent_m, dtype=float), c.shape)
    t = np.broadcast_to(np.asarray(total_n, dtype=float), c.shape)
    hc, hw = line_steps(model.length_m, c, w, step_m)
    dt = rel_step_force * np.maximum(np.abs(t), 1e-3)
    cc = np.concatenate([c + hc, c - hc, c, c, c, c])
    ww = np.concatenate([w, w, w + hw, w - hw, w, w])
    tt = np.concatenate([t, t, t, t, t + dt, t - dt])
    cmd = np.broadcast_to(np.asarray(command), c.shape)
    v = model.line_v(cc, ww, tt, np.tile(cmd, 6)).reshape(6, c.size, 3)
    return np.stack(
        [(v[0] - v[1]) / (2 * hc)[:, None], (v[2] - v[3]) / (2 * hw)[:, None], (v[4] - v[5]) / (2 * dt)[:, None]], 2
    )


def line_steps(length_m, centre_m, extent_m, step_m: float = 5e-4) -> tuple[np.ndarray, np.ndarray]:
    """Central-difference steps of a line load's centre and extent (m) that keep it on the digit (:func:`line_jacobian`
    and the estimator's derivative tables use the same)."""
    c = np.asarray(centre_m, dtype=float)
    w = np.asarray(extent_m, dtype=float)
    room = np.minimum(c - w / 2, length_m - c - w / 2)
    return np.clip(room, 1e-6, step_m), np.clip(np.minimum(room * 2, w / 2), 1e-6, step_m)


def fisher_sd(jac, sigma_v) -> np.ndarray:
    """Cramer-Rao standard deviations ``sqrt(diag(F^-1))``, ``F = J' diag(1/sigma^2) J``, for Jacobians (n, 3, d)
    and noise (3,) or (n, 3); inf for parameters the information does not reach (singular or conditioning worse
    than 1e8 after scaling). Vectorised over the batch (an estimate's latency counts it)."""
    jac = np.asarray(jac, dtype=float)
    w = 1.0 / np.broadcast_to(np.asarray(sigma_v, dtype=float), jac.shape[:2]) ** 2
    info = np.matmul((jac * w[..., None]).transpose(0, 2, 1), jac)
    n, d = info.shape[0], info.shape[1]
    diag = np.einsum("nii->ni", info)
    positive = np.all(diag > 0, axis=1)
    scale = np.sqrt(np.where(positive[:, None], diag, 1.0))
    corr = info / (scale[:, :, None] * scale[:, None, :])
    out = np.full((n, d), np.inf)
    if d == 2:  # closed form: corr = [[1, r], [r, 1]], inverse diagonal 1 / (1 - r^2)
        r2 = corr[:, 0, 1] ** 2
        ok = positive & (1.0 - r2 > 1e-8)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[ok] = np.sqrt(1.0 / (1.0 - r2[ok]))[:, None] / scale[ok]
        return out
    ok = positive.copy()
    ok[ok] = np.linalg.cond(corr[ok]) < 1e8
    if np.any(ok):
        inv = np.linalg.inv(corr[ok])
        out[ok] = np.sqrt(np.einsum("nii->ni", inv)) / scale[ok]
    return out


@dataclass
class ContactBound:
    """Cramer-Rao bounds of a contact from ``n_readings`` averaged readings, per case.

    ``position_m`` / ``force_n`` the cases; ``position_crlb_m``, ``force_crlb_n`` (inf where not identifiable);
    ``zone`` one of :data:`CONTACT_ZONES`.
    """

    position_m: np.ndarray
    force_n: np.ndarray
    position_crlb_m: np.ndarray
    force_crlb_n: np.ndarray
    zone: np.ndarray

    __repr__ = fields_summary


def contact_bounds(model, position_m, force_n, command, *, n_readings: int = 1) -> ContactBound:
    """Cramer-Rao bounds of a point contact's position and force (see :mod:`flexdigit.palpation.contact_estimation`
    for why
    some contacts cannot be located), with the model's white noise over ``n_readings`` averaged readings."""
    s = np.atleast_1d(np.asarray(position_m, dtype=float))
    f = np.broadcast_to(np.asarray(force_n, dtype=float), s.shape)
    sigma = np.asarray(model.noise_v, dtype=float) / np.sqrt(n_readings)
    jac = point_jacobian(model, s, f, command)
    sd = fisher_sd(jac, sigma)
    cmd = np.broadcast_to(np.asarray(command), s.shape)
    change = np.abs(model.point_v(s, f, cmd) - model.free_v(cmd))
    invisible = np.all(change < 0.1 * sigma, axis=1)
    # confounded: the two sensitivity directions (weighted) nearly parallel, as cramer_rao judges mass and position
    info = np.einsum("nki,k,nkj->nij", jac, 1.0 / sigma**2, jac)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos2 = np.where(info[:, 0, 0] * info[:, 1, 1] > 0, info[:, 0, 1] ** 2 / (info[:, 0, 0] * info[:, 1, 1]), 1.0)
    confounded = (1.0 - cos2 <= 1e-6) | ~np.isfinite(sd[:, 1])
    sd[confounded] = np.inf
    zone = np.where(
        invisible,
        CONTACT_ZONES[0],
        np.where(
            confounded,
            CONTACT_ZONES[1],
            np.where(sd[:, 0] > FORCE_ONLY_FRACTION * model.length_m, CONTACT_ZONES[2], CONTACT_ZONES[3]),
        ),
    ).astype(object)
    sd[invisible] = np.inf
    return ContactBound(s, f, sd[:, 0], sd[:, 1], zone)


def line_bounds(model, centre_m, extent_m, total_n, command, *, n_readings: int = 1) -> dict:
    """Cramer-Rao standard deviations of an even line load's centre (m), extent (m) and total (N) from
    ``n_readings`` averaged readings (inf where the gauges do not reach the parameter: a stretch that covers no
    gauge reads as a point at its centroid, so its extent is not seen)."""
    sigma = np.asarray(model.noise_v, dtype=float) / np.sqrt(n_readings)
    sd = fisher_sd(line_jacobian(model, centre_m, extent_m, total_n, command), sigma)
    return {"centre_m": sd[:, 0], "extent_m": sd[:, 1], "total_n": sd[:, 2]}


def gaussian_bayes_limits(
    means,
    noise,
    weights=None,
    *,
    labels=None,
    values=None,
    relative_values=None,
    samples: int = 1000,
    seed=0,
    evaluate=None,
) -> dict:
    """Bayes limits on discrete settings with Gaussian readings (Monte Carlo), for any reading vector.

    The generalisation of :func:`protocol_limits` to stacked readings with correlated noise (e.g. several readings
    under one hang sharing one cable-guide friction state) and to any labels and values. Readings of every setting
    are drawn from ``N(means_j, noise_j)``; each gets the Bayes answer knowing the settings and their frequencies:
    the most probable label, the posterior mean of ``values`` (squared-error optimum) and, for
    ``relative_values``, ``sum p / y / sum p / y^2`` (the relative-error optimum).

    Parameters
    ----------
    means : array_like, shape (k, D)
        Noise-free reading vector of each setting.
    noise : array_like, shape (k, D) or (k, D, D)
        Standard deviations (independent noise) or lower Cholesky factors of the covariance of each setting.
    weights : array_like, shape (k,), optional
        Prior frequencies (default equal).
    labels : array_like, shape (k,), optional
        A class per setting: the limit is the error rate of the maximum-posterior class.
    values, relative_values : array_like, shape (k,) or (k, d), optional
        Quantities to estimate (absolute or relative squared error).
    samples : int
        Monte Carlo readings per setting.
    seed : int or sequence of int
    evaluate : array_like of int, optional
        Draw readings only from these settings (the posterior still runs over all of them): a fine grid of
        settings stands for a continuous prior, and the limit is wanted at a few of them.

    Returns
    -------
    dict
        ``label_error`` (k,), ``value_mse`` (k, d), ``relative_mse`` (k, d): per setting, NaN where not asked or
        not evaluated.
    """
    mu = np.asarray(means, dtype=float)
    k, dim = mu.shape
    noise = np.asarray(noise, dtype=float)
    chol = noise if noise.ndim == 3 else np.einsum("kd,de->kde", noise, np.eye(dim))
    inv = np.linalg.inv(chol)  # (k, D, D)
    log_det = np.sum(np.log(np.abs(np.einsum("kdd->kd", chol))), axis=1)
    w = np.ones(k) if weights is None else np.asarray(weights, dtype=float)
    log_prior = np.log(w / w.sum())
    rng = np.random.default_rng(seed)
    vals = None if values is None else np.asarray(values, dtype=float).reshape(k, -1)
    rel = None if relative_values is None else np.asarray(relative_values, dtype=float).reshape(k, -1)
    lab = None if labels is None else np.asarray(labels)
    out = {
        "label_error": np.full(k, np.nan),
        "value_mse": np.full((k, 1 if vals is None else vals.shape[1]), np.nan),
        "relative_mse": np.full((k, 1 if rel is None else rel.shape[1]), np.nan),
    }
    for j in range(k) if evaluate is None else np.asarray(evaluate, dtype=int):
        v = mu[j] + rng.standard_normal((samples, dim)) @ chol[j].T
        z = np.einsum("kde,ske->skd", inv, v[:, None, :] - mu[None])  # whitened residual under every setting
        log_post = log_prior - 0.5 * np.sum(z * z, axis=2) - log_det
        post = np.exp(log_post - log_post.max(axis=1, keepdims=True))
        post /= post.sum(axis=1, keepdims=True)
        if lab is not None:
            classes = np.unique(lab)
            p_class = np.stack([post[:, lab == c].sum(axis=1) for c in classes], axis=1)
            out["label_error"][j] = np.mean(classes[np.argmax(p_class, axis=1)] != lab[j])
        if vals is not None:
            out["value_mse"][j] = np.mean((post @ vals - vals[j]) ** 2, axis=0)
        if rel is not None:
            est = (post @ (1.0 / rel)) / (post @ (1.0 / rel**2))
            out["relative_mse"][j] = np.mean(((est - rel[j]) / rel[j]) ** 2, axis=0)
    return out


# ----------------------------------------------------------------------------------------------- active sensing
def hang_readings_model(model, position_from_base_m, mass_kg, commands):
    """Mean and noise of the gauges read at each of ``commands`` under one hang, stacked: ``(means (k, 3K),
    chol (k, 3K, 3K))``, for a gauge model with ``noise_at`` (:class:`TwinGaugeModel`).

    The white noise is independent per reading; the cable-guide friction is not: it is drawn when the weight is
    hung and held while the servo moves (:mod:`flexdigit.twin.sensors`), so the same standard-normal state ``xi_g``
    scales with each command's tension, ``sd_{c,g} xi_g``: the covariance of gauge ``g`` across commands is
    ``outer(sd_g, sd_g)`` plus the white noise on the diagonal.
    """
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
    m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
    cmds = list(commands)
    white = np.asarray(model.noise_v, dtype=float)
    means, friction = [], []
    for c in cmds:
        cc = np.full(a.size, c)
        means.append(model.gauges_v(a, m, cc))
        total = noise_of(model, a, m, cc)
        friction.append(np.sqrt(np.maximum(total**2 - white**2, 0.0)))
    gauges = means[0].shape[1]  # the digit's G gauges
    k, dim = a.size, gauges * len(cmds)
    mean = np.concatenate(means, axis=1)
    fric = np.stack(friction, axis=1)  # (k, K, G)
    cov = np.zeros((k, dim, dim))
    idx = np.arange(dim)
    cov[:, idx, idx] = np.tile(np.broadcast_to(white**2, (gauges,)), len(cmds))
    for g in range(gauges):
        rows = np.arange(len(cmds)) * gauges + g
        cov[:, rows[:, None], rows[None, :]] += fric[:, :, g, None] * fric[:, None, :, g]
    return mean, np.linalg.cholesky(cov)


def active_limits(model, position_from_base_m, mass_kg, commands, weights=None, *, samples=4000, seed=0) -> dict:
    """Bayes limits of position and mass from readings at every one of ``commands`` under one hang, beside the
    single-reading limits of the same settings read at each command alone (chapter 7's protocol, 7.1).

    Returns RMS figures over the settings (weighted): ``position_rmse_m`` and ``magnitude_rel_rmse`` of the hang
    read at all commands, ``single_position_rmse_m`` and ``single_magnitude_rel_rmse`` of one reading at one of
    them (averaged over the commands), and the per-setting arrays.
    """
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
    m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
    w = np.ones(a.size) if weights is None else np.asarray(weights, dtype=float)
    mean, chol = hang_readings_model(model, a, m, commands)
    hang = gaussian_bayes_limits(mean, chol, w, values=a, relative_values=m, samples=samples, seed=seed)
    single_pos, single_mag = [], []
    for j, c in enumerate(commands):
        cc = np.full(a.size, c)
        one = gaussian_bayes_limits(
            model.gauges_v(a, m, cc),
            noise_of(model, a, m, cc),
            w,
            values=a,
            relative_values=m,
            samples=samples,
            seed=[*np.atleast_1d(seed).tolist(), j + 1],
        )
        single_pos.append(one["value_mse"][:, 0])
        single_mag.append(one["relative_mse"][:, 0])
    wn = w / w.sum()
    return {
        "position_rmse_m": float(np.sqrt(wn @ hang["value_mse"][:, 0])),
        "magnitude_rel_rmse": float(np.sqrt(wn @ hang["relative_mse"][:, 0])),
        "single_position_rmse_m": float(np.sqrt(wn @ np.mean(single_pos, axis=0))),
        "single_magnitude_rel_rmse": float(np.sqrt(wn @ np.mean(single_mag, axis=0))),
        "position_mse_m2": hang["value_mse"][:, 0],
        "single_position_mse_m2": np.array(single_pos),
    }

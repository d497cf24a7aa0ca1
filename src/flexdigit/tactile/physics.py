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

from flexdigit.tactile.protocols import RELAXED

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


def noise_of(model, position_from_base_m, mass_kg, command) -> np.ndarray:
    """Standard deviation (V) of one reading per point and gauge, (n, 3): the model's ``noise_at`` if it has one
    (load-dependent noise), else its constant ``noise_v``."""
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
    if hasattr(model, "noise_at"):
        m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
        return np.asarray(model.noise_at(a, m, np.broadcast_to(np.asarray(command), a.shape)), dtype=float)
    return np.broadcast_to(np.asarray(model.noise_v, dtype=float), (a.size, 3))


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
        sa = sm = np.zeros((a.size, 3))
    else:

        def total(aa, mm):
            return np.sqrt(noise_of(model, aa, mm, command) ** 2 + extra)

        sigma = total(a, m)
        if hasattr(model, "noise_at"):  # d sigma / d theta, the same differences as the jacobian
            dm = 0.02 * np.maximum(m, 1e-4)
            sa = (total(a + step_m, m) - total(a - step_m, m)) / (2 * step_m)
            sm = (total(a, m + dm) - total(a, m - dm)) / (2 * dm)[:, None]
        else:
            sa = sm = np.zeros((a.size, 3))
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
        The twin's calibration (default: the twin's default calibration).
    orientation : str
        How the digit lies (the protocols' "horizontal").

    Attributes
    ----------
    noise_v : ndarray, shape (3,)
        White noise per reading (V): the calibration's ``noise_white_v``. With a taut cable the twin adds the
        cable-guide friction, whose spread depends on the load: :meth:`noise_at`.
    drift_v_per_sqrt_s : ndarray, shape (3,)
        The twin's random-walk drift rate: ``t`` seconds after a tare it adds variance ``rate^2 t``.
    """

    def __init__(self, params=None, calibration=None, orientation: str = "horizontal") -> None:
        from flexdigit.params import RigParams
        from flexdigit.twin.calibration import default_calibration

        self.params = params or RigParams()
        self.calibration = calibration or default_calibration()
        self.orientation = orientation
        self.noise_v = np.asarray(self.calibration.noise_white_v, dtype=float)
        self.drift_v_per_sqrt_s = np.asarray(self.calibration.noise_drift_v_per_sqrt_s, dtype=float)

    def __repr__(self) -> str:
        return f"TwinGaugeModel(orientation={self.orientation!r}, noise_v={self.noise_v.tolist()})"

    def gauges_v(self, position_from_base_m, mass_kg, command) -> np.ndarray:
        return self._solve(position_from_base_m, mass_kg, command, False)

    def noise_at(self, position_from_base_m, mass_kg, command) -> np.ndarray:
        """Standard deviation (V) of one reading, (n, 3): white noise and, with a taut cable, the cable-guide
        friction at that load's tension (:func:`flexdigit.twin.twin.friction_sd_v`, the model the twin draws from).
        """
        friction = self._solve(position_from_base_m, mass_kg, command, True)
        return np.sqrt(self.noise_v**2 + friction**2)

    def _solve(self, position_from_base_m, mass_kg, command, friction: bool) -> np.ndarray:
        from flexdigit.twin.twin import friction_sd_v, static_gauges_v

        a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))
        m = np.broadcast_to(np.asarray(mass_kg, dtype=float), a.shape)
        c = np.broadcast_to(np.asarray(command), a.shape)
        a = np.clip(a, 0.0, self.params.geometry.digit_length_m)  # finite differences may step past the tip
        m = np.maximum(m, 0.0)
        out = np.empty((a.size, 3))
        for value in np.unique(c):
            rows = c == value
            if friction and (value == RELAXED or self.calibration.cable_friction_ratio == 0):
                out[rows] = 0.0  # no cable, or no friction: skip the solve
                continue
            volts, sol = static_gauges_v(
                m[rows],
                a[rows],
                None if value == RELAXED else np.full(int(rows.sum()), int(value)),
                params=self.params,
                calibration=self.calibration,
                orientation=self.orientation,
                adc=False,
                return_solution=True,
            )
            out[rows] = (
                friction_sd_v(sol, self.params, self.calibration, orientation=self.orientation) if friction else volts
            )
        return out

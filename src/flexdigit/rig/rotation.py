"""Beam (tip) rotation from the three gauge voltages: the map, the sweep that calibrates it, and how far to trust it.

:class:`RotationEstimator` is an affine map fitted on a static calibration sweep (commands 8..32, the digit at rest
at each). The sweep moves the digit along one direction only, so the map inverts each gauge's sensitivity to the
rotation (a well-posed one-parameter fit) rather than regressing the rotation on three nearly collinear gauges.

What the map is fitted to decides what the loop holds (:func:`calibrate_rotation`'s ``reference``):

- ``"twin"``: the twin's own tip rotation (sim backends; a twin calibrated to the rig stands in for it on
  hardware, ``flexdigit run --map-from twin``);
- a :class:`~flexdigit.rig.rotation_reference.MeasuredReference`: tip rotations or deflections at known points
  measured on the rig (protractor, ruler as in table 3.6, camera), read from a small file;
- the operator, asked at each command (a protractor).

Each reading of the sweep is taken once the digit has *settled*, detected from the readings themselves
(:func:`wait_until_settled`: no ringing or drift above the gauges' own noise), not after a fixed time, so a lightly
damped digit is not read mid-swing. The map carries its uncertainty (:meth:`RotationEstimator.uncertainty_deg`):
the spread of the rotation it would hold, from the reference's uncertainty and the readings' noise. The map is tared
at the start of every run (the digit at rest at the equilibrium command is 0 deg by definition), so gauge offsets
and drift between calibration and run do not become a steady-state error. Maps are saved as versioned JSON
(:func:`save_rotation_map`, :func:`load_rotation_map`).
"""

from __future__ import annotations

import copy
import json
import math
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexdigit._io import atomic_write, read_text
from flexdigit._json import fingerprint, to_jsonable
from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_choice, check_int, check_real
from flexdigit.errors import DataFileError, ParameterError, RigError
from flexdigit.models.bridge import gauge_noise_scale
from flexdigit.models.cable import tip_rotation_per_command_deg
from flexdigit.models.servo import command_to_angle_rad
from flexdigit.params import MAX_GAUGES, RigParams
from flexdigit.rig.base import Reading, Rig, open_rig
from flexdigit.rig.rotation_reference import ROTATION_RESOLUTION_DEG, MeasuredReference, read_reference
from flexdigit.twin.digit_calibration import decay_time_constant_s, twin_calibration

__all__ = [
    "RotationEstimator",
    "calibrate_rotation",
    "make_rotation_map",
    "wait_until_settled",
    "settle_timeout_s",
    "Settled",
    "save_rotation_map",
    "load_rotation_map",
    "MAP_FORMAT",
    "SWEEP_COMMANDS",
    "sweep_commands",
    "sweep_protocol",
    "SWEEPS",
    "tare_at_rest",
]

MAP_FORMAT = "flexdigit-rotation-map/1"
#: The default calibration sweep: 0..40 deg of rotation in nine steps.
SWEEP_COMMANDS = (8, 11, 14, 17, 20, 23, 26, 29, 32)
#: The sweep's step, deg of beam rotation: the thesis rig's 3 commands of 1.735 deg (E 3.15).
SWEEP_STEP_DEG = 5.2


def sweep_commands(params=None) -> tuple[int, ...]:
    """The calibration sweep of a digit: nine commands from its straight one over ~40 deg of beam rotation
    (:data:`SWEEP_COMMANDS` on the thesis rig), ~5.2 deg apart at its own rotation per command (a geared servo
    takes more, finer commands); an antagonistic pair (``[cables] count = 2``) is swept ~40 deg either way,
    ~10.4 deg apart. Clipped to the actuator's range."""

    params = params or RigParams()
    a = params.actuator
    step = max(1, round(SWEEP_STEP_DEG / tip_rotation_per_command_deg(params)))
    ks = range(-8, 9, 2) if params.cables.count == 2 else range(9)
    commands = sorted({min(max(a.equilibrium_command + k * step, a.command_min), a.command_max) for k in ks})
    return tuple(int(c) for c in commands)


#: The calibration sweep's protocols (:func:`calibrate_rotation`'s ``sweep``): ``"plain"`` visits the commands once,
#: in order (the thesis rig's, whose report it makes); ``"referenced"`` returns to the straight command between
#: them, so each reading is taken against the gauges' drift at straight just before and after it.
SWEEPS = ("plain", "referenced")


def sweep_protocol(params=None, reference="twin") -> str:
    """The sweep :func:`calibrate_rotation` runs by default: ``"referenced"`` for a digit other than the thesis rig
    mapped on its twin, ``"plain"`` on the thesis rig (the protocol its report, ``flexdigit reproduce``, was made
    with) and for a protractor or a measured reference (read to 1 deg or 0.5 mm, far coarser than the drift).

    Why: a gauge's amplifier drifts (a random walk, ``noise_drift_v_per_sqrt_s``), and over a plain sweep the drift
    leans the fitted slope. One coarse quarter bridge (the one-section test digit: 4.8 mV a degree, 0.2 mV/sqrt(s) of
    drift) ends a 10 s sweep 0.13 deg off, and its map's sensitivity scatters 0.54 % (sd) between twin seeds, 1 %
    at worst: 0.16-0.3 deg at 30 deg. Referenced to straight before and after each command, it scatters 0.09 %
    (0.2 % at worst; 10 seeds each, /tmp measurements quoted in docs/digits.md).

    Examples
    --------
    >>> from flexdigit.params import RigParams
    >>> pair = RigParams.from_dict({"cables": {"count": 2, "pretension_n": 3.0}})
    >>> sweep_protocol(RigParams()), sweep_protocol(pair), sweep_protocol(pair, reference=lambda command: 0.0)
    ('plain', 'referenced', 'plain')
    """
    params = params or RigParams()
    twin = isinstance(reference, str) and reference == "twin"
    return "referenced" if twin and not params.is_thesis_rig() else "plain"


#: Draws of the Monte Carlo that propagates the reference's and the readings' uncertainty into the map.
UNCERTAINTY_DRAWS = 400
#: Residual variance over the variance the stated uncertainties explain above which they are not believed (the
#: 95th percentile of chi-square / dof at 7 degrees of freedom, a nine-point sweep, is 2.0).
BIRGE_LIMIT = 2.0


class RotationEstimator:
    """Beam rotation (deg) from the gauge voltages, ``w @ gauges_v + b - tare`` (scikit-learn's contract): the
    thesis rig's three, or any digit's 1-8 (the map has one weight per gauge the sweep read).

    The calibration sweep moves the digit along one direction only (the cable's pull), so the three gauges are
    nearly collinear: on the twin the sweep's gauge matrix has singular values ~0.40 V against ~0.003 V, and the
    second and third are the readings' own noise (2 mV white / sqrt(5) averaged readings x sqrt(9) commands).
    An unconstrained least-squares fit ``rotation ~ gauges`` (``method="lstsq"``) inverts that noise: its weights
    swing from [75, 66, 28] to [113, 64, -6.5] deg/V between twin seeds, and a map that subtracts one gauge from
    another amplifies the beam's dynamic bending (its vibration shapes differ from the static one), so the estimate
    can ring 10 deg above the true rotation during a step.

    ``method="sensitivity"`` (the default) is the classical calibration the physics suggests: each gauge is a
    linear function of the one sweep parameter, ``g = a + s theta + noise`` (each fit is well posed: theta spans
    the sweep), and ``theta`` is read back by the Gauss-Markov (weighted least-squares) inverse of that model,
    ``theta = s' W (g - a) / (s' W s)`` with ``W = diag(1 / noise_v^2)`` (equal weights when ``noise_v`` is None,
    as on the twin, whose channels all have 2 mV of white noise). Its weights are proportional to the gauges'
    sensitivities (all positive: every gauge bends the same way under the cable), so no gauge is subtracted from
    another; on the twin they are [49.5, 68.2, 50.5] deg/V within 1 % across seeds.

    Parameters
    ----------
    method : {"sensitivity", "lstsq"}
        The fit (see above). ``"lstsq"`` is kept to show why it was replaced.
    noise_v : sequence of floats, optional
        Per-gauge noise standard deviation (V) for the Gauss-Markov weights; equal weights if None.
    ridge : float
        Tikhonov term of ``"lstsq"`` (unused by ``"sensitivity"``).
    degree : {1, 2}
        ``"sensitivity"`` only. 1: each gauge linear in the rotation (the affine map). 2: each gauge
        ``g = a + s theta + c theta^2`` (a quarter bridge of a cable pair reads the cables' summed tension, which
        grows on both sides of straight once one cable slackens: a V the affine map splits into 0.3 deg errors at
        +-30 deg, ``random_digit(20)``). The map then reads ``u = w . g + b = theta + q theta^2`` (``q = w . c``,
        ``quadratic_``) and inverts it exactly, ``theta = 2 u / (1 + sqrt(1 + 4 q u))``; the tare is on ``u``.

    Examples
    --------
    >>> est = RotationEstimator().fit([[0, 0, 0], [1, 2, 1], [2, 4, 2], [3, 6, 3]], [0, 10, 20, 30])
    >>> round(est.predict_one(np.array([1.5, 3, 1.5])), 3), [round(float(w), 3) for w in est.coef_]
    (15.0, [1.667, 3.333, 1.667])
    """

    METHODS = ("sensitivity", "lstsq")
    #: The map's reading's curvature, deg per deg^2 (``degree`` 2; 0 for an affine map).
    quadratic_ = 0.0

    def __init__(self, method: str = "sensitivity", noise_v=None, ridge: float = 1e-9, degree: int = 1) -> None:
        self.method = method
        self.noise_v = noise_v
        self.ridge = ridge
        self.degree = degree

    def fit(self, gauges_v, rotation_deg, *, rotation_cov_deg2=None, gauges_sd_v=None) -> RotationEstimator:
        """Fit the map to gauge readings (n, G) at reference rotations (n,).

        ``rotation_cov_deg2`` (n, n) is the reference rotations' covariance (deg^2) and ``gauges_sd_v`` (n, G) the
        standard uncertainty of each averaged reading; both feed :meth:`uncertainty_deg` (zero if not given).
        """
        check_choice(self.method, "method", self.METHODS, "RotationEstimator")
        X = np.asarray(gauges_v, dtype=float)
        y = np.asarray(rotation_deg, dtype=float).reshape(-1)
        if X.ndim != 2 or not 1 <= X.shape[1] <= MAX_GAUGES or X.shape[0] != y.size or y.size < 4:
            raise DataFileError(
                f"RotationEstimator.fit needs (n, G) gauge voltages (1 <= G <= {MAX_GAUGES}) and n >= 4 angles. "
                f"Got {X.shape} and {y.shape}."
            )
        gauges = X.shape[1]
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
            raise DataFileError("RotationEstimator.fit: the calibration data contain NaN or inf")
        yc = y - y.mean()
        if not np.ptp(y) > 0:
            raise DataFileError(
                f"RotationEstimator.fit: the reference rotations must vary across the sweep. Got {y.tolist()!r}."
            )
        # each gauge's volts per degree along the sweep (least-squares slopes): the sensitivities s
        sens = ((X - X.mean(axis=0)).T @ yc) / float(yc @ yc)
        offset = X.mean(axis=0) - sens * y.mean()  # gauges at 0 deg
        curvature = np.zeros(gauges)
        if self.degree not in (1, 2) or isinstance(self.degree, bool):
            raise ParameterError(f"The 'degree' parameter of RotationEstimator must be 1 or 2. Got {self.degree!r}.")
        if self.degree == 2:
            if self.method != "sensitivity" or y.size < 5 or np.unique(y).size < 3:
                raise DataFileError("RotationEstimator.fit: degree 2 needs method 'sensitivity' and >= 3 rotations")
            offset, sens, curvature = np.linalg.lstsq(np.c_[np.ones(y.size), y, y * y], X, rcond=None)[0]
        self.gauge_v_per_deg_ = sens
        self.gauge_v_per_deg2_ = curvature
        if self.method == "sensitivity":
            if self.noise_v is None:
                weight = np.ones(gauges)
            else:
                noise = check_array(
                    self.noise_v, "noise_v", "RotationEstimator", shape=(gauges,), low=0.0, low_open=True
                )
                weight = 1.0 / noise**2
            information = float(sens @ (weight * sens))
            if not information > 0:
                raise DataFileError("RotationEstimator.fit: the gauges did not change over the sweep")
            self.coef_ = weight * sens / information
            self.intercept_ = float(-self.coef_ @ offset)
        else:
            A = np.c_[X, np.ones(len(X))]
            reg = check_real(self.ridge, "ridge", "RotationEstimator", low=0.0) * np.eye(gauges + 1)
            reg[gauges, gauges] = 0.0
            coef = np.linalg.solve(A.T @ A + reg, A.T @ y)
            self.coef_ = coef[:gauges]
            self.intercept_ = float(coef[gauges])
        self.quadratic_ = float(self.coef_ @ curvature)
        self.tare_deg_ = 0.0
        self.residual_deg_ = float(np.sqrt(np.mean((self.predict(X) - y) ** 2)))
        n = y.size
        cov = np.zeros((n, n)) if rotation_cov_deg2 is None else np.asarray(rotation_cov_deg2, dtype=float)
        sd = np.zeros((n, gauges)) if gauges_sd_v is None else np.asarray(gauges_sd_v, dtype=float)
        good = np.all(np.isfinite(cov)) and np.all(np.isfinite(sd))
        if cov.shape != (n, n) or sd.shape != (n, gauges) or not good:
            raise DataFileError(
                f"RotationEstimator.fit: rotation_cov_deg2 must be ({n}, {n}) and gauges_sd_v ({n}, {gauges}), finite"
            )
        self.gauges_v_, self.rotation_deg_ = X, y
        self.rotation_cov_deg2_, self.gauges_sd_v_ = cov, sd
        return self

    def uncertainty_deg(self, at_deg: float, *, seed: int = 0) -> float:
        """Standard uncertainty (deg) of the rotation the loop holds when the map reads ``at_deg``.

        A Monte Carlo (seeded, :data:`UNCERTAINTY_DRAWS` draws): the reference rotations are drawn from their
        covariance and the readings from their noise, the map is refitted, and the rotation at which the refitted
        map reads ``at_deg`` (on the fitted gauge lines) is recorded; its spread is the answer. Where the fit's
        residuals are more than :data:`BIRGE_LIMIT` times what the stated uncertainties explain, the spread is
        scaled up by the root of that ratio (and is never below a regression's prediction error from the
        residuals), so a reference that claims more than the readings show is not believed.
        """
        at = check_real(at_deg, "at_deg", "RotationEstimator.uncertainty_deg")
        if not hasattr(self, "rotation_deg_"):
            return math.nan  # a map saved without its sweep (the earlier format): nothing to tell
        X, y = self.gauges_v_, self.rotation_deg_
        rng = np.random.default_rng(seed)
        n = y.size
        try:
            chol = np.linalg.cholesky(self.rotation_cov_deg2_ + 1e-18 * np.eye(n))
        except np.linalg.LinAlgError:
            chol = np.diag(np.sqrt(np.clip(np.diag(self.rotation_cov_deg2_), 0.0, None)))
        sens, offset = self.gauge_v_per_deg_, X.mean(axis=0) - self.gauge_v_per_deg_ * y.mean()
        if self.degree == 2:  # the gauge curves fitted now: offsets (0 deg), slopes and curvatures
            offset, sens, curvature = np.linalg.lstsq(np.c_[np.ones(n), y, y * y], X, rcond=None)[0]
        held = np.empty(UNCERTAINTY_DRAWS)
        for k in range(UNCERTAINTY_DRAWS):
            y_k = y + chol @ rng.standard_normal(n)
            X_k = X + self.gauges_sd_v_ * rng.standard_normal(X.shape)
            m = RotationEstimator(self.method, self.noise_v, self.ridge, self.degree).fit(X_k, y_k)
            if self.degree == 1:
                # the refitted map reads `at` where w'(a + s theta) + b' = at, on the gauge lines fitted now
                held[k] = (at - m.intercept_ - m.coef_ @ offset) / (m.coef_ @ sens)
            else:  # ... where w'(a + s theta + c theta^2) + b' = at + q' at^2, on the gauge curves fitted now
                r = at + m.quadratic_ * at * at - m.intercept_ - m.coef_ @ offset
                held[k] = _quadratic_root(float(m.coef_ @ sens), float(m.coef_ @ curvature), r)
        spread = float(np.std(held))
        dof = n - 2
        if dof > 0:
            # the residuals' variance against what the stated uncertainties explain (a Birge ratio): a reference
            # that claims more than the fit shows is not believed, and the spread grows by the ratio's root
            s_res2 = self.residual_deg_**2 * n / dof
            explained = float(np.mean(np.diag(self.rotation_cov_deg2_))) + float(
                np.mean((self.gauges_sd_v_**2) @ (self.coef_**2))
            )
            if s_res2 > BIRGE_LIMIT * explained:
                syy = float(np.sum((y - y.mean()) ** 2))
                by_residuals = math.sqrt(s_res2 * (1 / n + (at - y.mean()) ** 2 / syy))
                spread = max(spread * math.sqrt(s_res2 / explained) if explained > 0 else 0.0, by_residuals)
        return spread

    def predict(self, gauges_v) -> np.ndarray:
        u = np.asarray(gauges_v, dtype=float) @ self.coef_ + self.intercept_ - self.tare_deg_
        q = getattr(self, "quadratic_", 0.0)
        return u if q == 0.0 else 2.0 * u / (1.0 + np.sqrt(np.maximum(1.0 + 4.0 * q * u, 0.0)))

    def predict_one(self, gauges_v: np.ndarray) -> float:
        g = gauges_v
        c = self.coef_
        if c.size == 3:  # the thesis rig's, as ever (the loop's hot path)
            u = float(g[0] * c[0] + g[1] * c[1] + g[2] * c[2]) + self.intercept_ - self.tare_deg_
        else:
            u = float(np.dot(g, c)) + self.intercept_ - self.tare_deg_
        q = self.quadratic_
        return u if q == 0.0 else 2.0 * u / (1.0 + math.sqrt(max(1.0 + 4.0 * q * u, 0.0)))

    def tare(self, gauges_v, at_deg: float = 0.0) -> RotationEstimator:
        """Shift the map so ``gauges_v`` (mean of rows) reads ``at_deg`` (the shift is on the map's linear
        reading ``u``: ``at + q at^2`` there)."""
        g = np.atleast_2d(np.asarray(gauges_v, dtype=float)).mean(axis=0)
        q, self.quadratic_ = self.quadratic_, 0.0
        self.tare_deg_ = 0.0
        self.tare_deg_ = float(self.predict_one(g) - (at_deg + q * at_deg * at_deg if q else at_deg))
        self.quadratic_ = q
        return self

    def __call__(self, reading: Reading) -> float:
        return self.predict_one(reading.gauges_v)

    def to_dict(self) -> dict:
        """Everything needed to use the map again and to say where it came from (JSON-able; :meth:`from_dict`)."""
        out = {
            "format": MAP_FORMAT,
            "method": self.method,
            "coef": self.coef_.tolist(),
            "intercept": self.intercept_,
            "gauge_v_per_deg": self.gauge_v_per_deg_.tolist(),
            "residual_deg": self.residual_deg_ if math.isfinite(self.residual_deg_) else None,
        }
        if self.degree == 2:  # an affine map's file stays as it was
            out.update(degree=2, quadratic=self.quadratic_, gauge_v_per_deg2=self.gauge_v_per_deg2_.tolist())
        if hasattr(self, "rotation_deg_"):  # the sweep it was fitted on: its uncertainty can be told again
            out["gauges_v"] = self.gauges_v_.tolist()
            out["rotation_deg"] = self.rotation_deg_.tolist()
            out["rotation_cov_deg2"] = self.rotation_cov_deg2_.tolist()
            out["gauges_sd_v"] = self.gauges_sd_v_.tolist()
        out.update({key: getattr(self, f"{key}_") for key in _PROVENANCE if hasattr(self, f"{key}_")})
        return out

    @classmethod
    def from_dict(cls, data, source: str = "rotation map") -> RotationEstimator:
        """A fitted map from :meth:`to_dict`'s numbers (a saved map, a recording's metadata, or the earlier
        ``coef/intercept/gauge_v_per_deg`` form); :class:`DataFileError` naming ``source`` and the key if not."""
        return _from_dict(cls, data, source)


#: Where a map came from, kept with it (set by :func:`calibrate_rotation`): the source, the sweep's commands, the
#: time each reading waited for the digit to settle (each visit's, straight ones included, for a referenced sweep),
#: the rotation per command the sweep measured and, where it was not the plain one, the sweep's protocol.
_PROVENANCE = ("source", "commands", "settle_time_s", "deg_per_command", "sweep", "noise_scale")


@dataclass(frozen=True)
class Settled:
    """The digit at rest: the window's mean readings and what it took to get there.

    gauges_v : mean of the window's readings (V); sd_v : its standard uncertainty (V); noise_v : the gauges' noise
    per reading (V); waited_s : from the call to the end of the window (s); truth_deg : the twin's mean tip
    rotation over the window (deg; NaN on hardware).
    """

    gauges_v: np.ndarray
    sd_v: np.ndarray
    noise_v: np.ndarray
    waited_s: float
    truth_deg: float

    __repr__ = fields_summary


def wait_until_settled(
    rig: Rig,
    *,
    window_s: float = 1.0,
    timeout_s: float = 30.0,
    tolerance: float = 1.4,
    truth: Callable[[], float] | None = None,
) -> Settled:
    """Read the rig every serial period until the digit is at rest, judged from the readings (not a fixed time).

    At rest means, over the last ``window_s`` of readings, for every gauge: a spread no more than ``tolerance``
    times the gauge's own noise (so no ringing above the noise: an amplitude under ~1.2 noise standard deviations)
    and a straight-line drift across the window under one noise standard deviation (so no creep). The noise is
    estimated from the readings' second differences (robust median estimate; a swing of the digit's ~2 Hz mode
    barely shows in them at 50 Hz), floored at the ADC's quantisation.

    Raises :class:`~flexdigit.errors.RigError` naming the gauge, its spread and drift if the digit has not settled
    within ``timeout_s``: a reading the map could not stand behind.
    """
    owner = "wait_until_settled"
    window = check_real(window_s, "window_s", owner, low=0.0, low_open=True)
    timeout = check_real(timeout_s, "timeout_s", owner, low=window)
    tol = check_real(tolerance, "tolerance", owner, low=1.0)
    period = rig.params.actuator.serial_period_s
    n = max(5, int(round(window / period)))
    sensors = rig.params.sensors
    lsb = (sensors.adc_range_v[1] - sensors.adc_range_v[0]) / 2**sensors.adc_bits
    ramp = np.arange(n) - (n - 1) / 2
    start = rig.clock()
    rows: list[np.ndarray] = []
    truths: list[float] = []
    while True:
        rig.wait(period)
        rows.append(rig.read().gauges_v)
        truths.append(truth() if truth is not None else math.nan)
        waited = rig.clock() - start
        if len(rows) < n + 2:
            continue
        G = np.asarray(rows)
        d2 = np.diff(G, 2, axis=0)
        noise = np.maximum(1.4826 * np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0) / math.sqrt(6), lsb / 2)
        W = G[-n:]
        spread = W.std(axis=0, ddof=1)
        drift = (ramp @ (W - W.mean(axis=0))) / (ramp @ ramp) * (n - 1)
        if np.all(spread <= tol * noise) and np.all(np.abs(drift) <= noise):
            return Settled(W.mean(axis=0), spread / math.sqrt(n), noise, waited, float(np.mean(truths[-n:])))
        if waited >= timeout:
            worst = int(np.argmax(np.maximum(spread / (tol * noise), np.abs(drift) / noise)))
            raise RigError(
                f"{rig.name}: the digit did not settle within {timeout:g} s at command {rig.command} (gauge "
                f"{worst + 1}: spread {spread[worst] * 1000:.2f} mV and drift {drift[worst] * 1000:+.2f} mV over "
                f"{window:g} s, against noise {noise[worst] * 1000:.2f} mV)"
            )


#: Readings of the thesis rig's tare (its chapter-5 runs and report: kept as they were).
THESIS_TARE_READINGS = 5


def tare_at_rest(estimator: RotationEstimator, rig: Rig, *, window_s: float = 1.0) -> np.ndarray:
    """Tare ``estimator`` on ``rig`` at rest where it stands (the straight command: 0 deg by definition).

    On the thesis rig, the mean of :data:`THESIS_TARE_READINGS` readings (its runs and report as they were). On any
    other digit, the mean of a window of ``window_s`` at rest (:func:`wait_until_settled`, which also checks that
    the digit is at rest): five readings leave the tare as noisy as ``noise / sqrt(5)``, 0.19 deg on one coarse
    quarter bridge (0.41 deg a reading) and 0.25 deg on ``random_digit(4)``'s three, an offset the loop then holds
    for the whole run; a 1 s window's 50 readings leave 0.06 and 0.08 deg, and the gauges' drift over the window
    (0.04 deg/sqrt(s) on the coarse gauge) about as much again: near the least total for that gauge
    (``window = sqrt(3 white^2 / (rate drift^2))``, 2.4 s, 0.053 deg).

    Returns the gauges (V) the map was tared on, the mean of the readings (:meth:`RotationEstimator.tare`).
    """
    if rig.params.is_thesis_rig():
        rest = np.asarray([rig.read().gauges_v for _ in range(THESIS_TARE_READINGS)])
    else:
        rest = wait_until_settled(rig, window_s=window_s, timeout_s=settle_timeout_s(rig)).gauges_v[None, :]
    estimator.tare(rest)
    return rest.mean(axis=0)


def make_rotation_map(
    rig: Rig,
    source: str | Path = "twin",
    *,
    twin_options: dict | None = None,
    ask: Callable[[int], float] | None = None,
    resolution_mm: float = 0.5,
    resolution_deg: float = 1.0,
    replay: bool = False,
) -> RotationEstimator:
    """The gauge -> rotation map of ``rig`` (``flexdigit run --map-from``), made from one of three references.

    Parameters
    ----------
    rig : Rig
        The rig whose gauges are mapped.
    source : "twin", "operator" or path
        ``"twin"``: a separate twin of ``rig.params`` (opened with ``twin_options``), swept and read at its own tip
        rotation; ``"operator"``: ``rig`` swept, ``ask(command) -> deg`` at each command (a protractor read to
        ``resolution_deg``, a uniform error of ``resolution_deg / sqrt(12)`` standard deviation); a path: rotations
        (or deflections) measured on the rig (:func:`~flexdigit.rig.rotation_reference.read_reference`, read to
        ``resolution_mm`` / ``resolution_deg``).
    twin_options : dict, optional
        Keyword options of the ``"sim"`` rig the twin map is made on (``seed``, ``calibration``, ...). Its sweep
        starts each hold at rest (``calibrate_rotation(..., start_at_rest=True)``), and the map is made once per
        process for one digit, twin calibration, set of options and seed (:data:`TWIN_MAPS_KEPT` kept; each call
        gets its own copy, so a tare does not reach another caller's).
    ask : callable, optional
        The operator's reading, required with ``source="operator"``.
    resolution_mm, resolution_deg : float
        Reading resolutions of measured deflections (mm) and rotations (deg): 0.5 mm, 1 deg by default.
    replay : bool
        ``rig`` replays a recording: it ignores commands, so it cannot be swept; only a reference file holding the
        gauge readings (``gauge1_v``, ...) can map it.

    Returns
    -------
    RotationEstimator
        The fitted map (:func:`calibrate_rotation`).

    Raises
    ------
    ParameterError
        A replay asked to be swept, or ``"operator"`` without ``ask``.
    """
    if source == "twin":
        return _twin_map(rig.params, dict(twin_options or {}))
    if source == "operator":
        if replay:
            raise ParameterError("a replay cannot be swept (it ignores commands); pass --rotation-map FILE")
        if ask is None:
            raise ParameterError("make_rotation_map: source 'operator' needs ask(command) -> deg")
        return calibrate_rotation(rig, reference=ask, reference_sd_deg=resolution_deg / math.sqrt(12))
    reference = read_reference(Path(source), rig.params, resolution_mm=resolution_mm, resolution_deg=resolution_deg)
    if replay and reference.gauges_v is None:
        raise ParameterError(
            f"a replay cannot be swept; {source} needs gauge1_v, gauge2_v, gauge3_v columns to fit the map alone"
        )
    return calibrate_rotation(rig, reference=reference)


#: Twin maps :func:`make_rotation_map` keeps per process (the latest used), each under :func:`_twin_map_key`.
TWIN_MAPS_KEPT = 8
_TWIN_MAPS: dict[str, RotationEstimator] = {}
_TWIN_MAPS_LOCK = threading.Lock()


def _twin_map(params: RigParams, options: dict) -> RotationEstimator:
    """The map of a separate twin of ``params`` opened with ``options`` (the ``"sim"`` rig's, in virtual time),
    swept with each hold started at rest; made once per key (:func:`_twin_map_key`), a copy handed out."""
    # the calibration the twin would take by default, named: it may be another one in a use_calibration block
    if options.get("calibration") is None:
        options = {**options, "calibration": twin_calibration(params)}
    key = _twin_map_key(params, options)
    with _TWIN_MAPS_LOCK:
        kept = _TWIN_MAPS.pop(key, None) if key is not None else None
        if kept is not None:
            _TWIN_MAPS[key] = kept  # the latest used last
    if kept is None:
        with open_rig("sim", params, **options) as twin:
            kept = calibrate_rotation(twin, start_at_rest=twin.deterministic)  # a paced twin swings to rest
        if key is not None:
            with _TWIN_MAPS_LOCK:
                _TWIN_MAPS[key] = kept
                while len(_TWIN_MAPS) > TWIN_MAPS_KEPT:
                    _TWIN_MAPS.pop(next(iter(_TWIN_MAPS)))
    return copy.deepcopy(kept)  # a tare (tare_at_rest) changes the map it is given


def _twin_map_key(params: RigParams, options: dict) -> str | None:
    """What a twin map depends on, all of it: the digit's parameters, every option of its twin (the calibration by
    its numbers, the seed among them) and how it is swept (:data:`REST_TIME_CONSTANTS`); None (not kept) when an
    option is not plain data (a ready ``twin``, a clock) or the twin is paced."""
    plain = (bool, int, float, str, type(None))
    named = {}
    for name, value in options.items():
        if name == "calibration" and hasattr(value, "to_dict"):
            named[name] = {"calibration": value.to_dict()}
        elif isinstance(value, plain) or (isinstance(value, tuple | list) and all(isinstance(v, plain) for v in value)):
            named[name] = value if not isinstance(value, float) else float.hex(value)
        else:
            return None
    if named.get("paced"):
        return None
    return fingerprint({"params": params.to_dict(), "options": named, "rest": float.hex(REST_TIME_CONSTANTS)})


#: The least time a sweep reading waits for the digit to come to rest before giving up, s (the thesis rig rests
#: within 1-3 s of a command).
SETTLE_TIMEOUT_S = 30.0
#: Time constants of the digit's slowest vibration a reading may wait at most: a swing decays by e^-10, a 5 deg one
#: to 2e-4 deg, below any gauge's noise.
SETTLE_TIME_CONSTANTS = 10.0


def settle_timeout_s(rig: Rig) -> float:
    """A sweep reading's time limit on ``rig``: :data:`SETTLE_TIMEOUT_S`, or :data:`SETTLE_TIME_CONSTANTS` time
    constants of the digit's slowest vibration where that is longer
    (:func:`~flexdigit.twin.digit_calibration.decay_time_constant_s` of its twin's calibration, or on hardware of
    the one its description gets). A lightly damped digit (a 0.44 m phosphor-bronze pair, zeta 0.015: 5.3 s) is
    read once at rest instead of refused after a fixed 30 s; the thesis rig's 0.44 s leaves 30 s.

    Examples
    --------
    >>> from flexdigit.rig.base import open_rig
    >>> settle_timeout_s(open_rig("sim"))
    30.0
    """
    twin = getattr(rig, "twin", None)
    params = rig.params
    calibration = twin.calibration if twin is not None else twin_calibration(params)
    return max(SETTLE_TIMEOUT_S, SETTLE_TIME_CONSTANTS * decay_time_constant_s(params, calibration))


def calibrate_rotation(
    rig: Rig,
    commands=None,
    *,
    reference="twin",
    settle_s: float | None = None,
    samples: int = 5,
    window_s: float = 1.0,
    timeout_s: float | None = None,
    reference_sd_deg: float | None = None,
    angle_source: Callable[[int], float] | None = None,
    sweep: str | None = None,
    start_at_rest: bool = False,
) -> RotationEstimator:
    """Static calibration sweep: hold each command, wait for the digit to settle, read, fit gauges -> rotation.

    Parameters
    ----------
    rig : Rig
    commands : sequence of int, optional
        The sweep (default :func:`sweep_commands` of the rig's digit, :data:`SWEEP_COMMANDS` on the thesis rig,
        or the commands of a measured ``reference``).
    reference : "twin", MeasuredReference or callable
        Where the reference rotations come from: the twin's own tip rotation (averaged over the same window as the
        readings), rotations measured on the rig (:mod:`flexdigit.rig.rotation_reference`; if it holds gauge
        readings, no sweep is run), or ``reference(command) -> deg`` (e.g. the operator with a protractor).
    settle_s : float, optional
        None (default): wait until the readings show the digit at rest (:func:`wait_until_settled`). A number: the
        old fixed wait, then ``samples`` readings 20 ms apart (kept to compare with).
    window_s, timeout_s : float
        :func:`wait_until_settled`'s window and time limit (default :func:`settle_timeout_s`: from the digit's
        own modal damping).
    reference_sd_deg : float, optional
        Standard uncertainty of a callable reference's rotations (deg): a 1 deg protractor's 0.29 by default.
    angle_source : callable, optional
        Same as a callable ``reference`` (the earlier name).
    sweep : {"plain", "referenced"}, optional
        ``"plain"``: each command once, in order. ``"referenced"``: the straight command before, between and after
        the others, each reading corrected by the gauges (and the reference) at straight interpolated to its time:
        a drift slow against a command's settling cancels, at the cost of twice the settles. Default
        :func:`sweep_protocol` (referenced on a digit other than the thesis rig mapped on its twin) when readings
        are taken at rest (``settle_s`` None), plain after a fixed wait (the report's chapter-5 studies); a
        referenced sweep with a fixed wait is refused.
    start_at_rest : bool
        A twin in virtual time only (a map's own, :func:`make_rotation_map`): each hold starts with the servo at the
        command's angle and the digit in its static equilibrium, 5 time constants on; read once at rest.

    Returns
    -------
    RotationEstimator
        Fitted, with ``source_``, ``commands_``, ``settle_time_s_`` (per reading) and ``deg_per_command_`` (the
        reference's rotation per command over the sweep) set, and :meth:`~RotationEstimator.uncertainty_deg`.
    """
    owner = "calibrate_rotation"
    if angle_source is not None:
        reference = angle_source
    cov, truth = None, None
    if isinstance(reference, MeasuredReference):
        commands = _measured_commands(reference, commands)
        cov = reference.rotation_cov_deg2
        source = f"{reference.kind} measured on the rig ({reference.source})"
        if reference.gauges_v is not None:  # readings taken with the measurements: no sweep needed
            est = RotationEstimator().fit(reference.gauges_v, reference.rotation_deg, rotation_cov_deg2=cov)
            return _provenance(est, source, commands, [math.nan] * len(commands), reference.rotation_deg)
        angle = reference.angle_source()
    else:
        angle, truth, source, sd = _twin_or_operator(rig, reference, reference_sd_deg)
    commands = [int(c) for c in (sweep_commands(rig.params) if commands is None else commands)]
    default = sweep_protocol(rig.params, reference) if settle_s is None else "plain"  # a fixed wait: as it was
    sweep = check_choice(default if sweep is None else sweep, "sweep", SWEEPS, owner)
    how = {"settle_s": settle_s, "samples": samples, "window_s": window_s, "timeout_s": timeout_s}
    X, sd_v, y, waited = _run_sweep(rig, commands, angle, truth, sweep, at_rest=start_at_rest, **how)
    if cov is None and callable(reference) and not isinstance(reference, str):
        cov = np.eye(len(commands)) * sd**2
    noise = gauge_noise_scale(rig.params.sensors, len(X[0]))
    est = _fitted_map(X, y, cov, np.asarray(sd_v), noise, curved=sweep == "referenced")
    est = _provenance(est, source, commands, waited, np.asarray(y))
    if sweep != "plain":  # a plain sweep's map reads as before (the thesis rig's saved maps and logs unchanged)
        est.sweep_ = sweep
    return est


def _fitted_map(X, y, cov, sd_v, noise, *, curved: bool) -> RotationEstimator:
    """The sweep's map: each gauge weighted by its relative noise ``noise`` (None: equally; an amplifier gain per
    gauge, :func:`~flexdigit.models.bridge.gauge_noise_scale`), with its quadratic terms if ``curved`` and material
    (:func:`_curved_if_material`)."""
    est = RotationEstimator(noise_v=noise).fit(X, y, rotation_cov_deg2=cov, gauges_sd_v=sd_v)
    if curved:
        est = _curved_if_material(est, cov, sd_v)
    if noise is not None:
        est.noise_scale_ = [float(v) for v in noise]
    return est


#: How far (deg, anywhere on the sweep, both maps tared at straight) the map with each gauge's quadratic term must
#: read from the affine one for the term to be kept: 3 standard deviations of that difference from the readings'
#: noise alone on the coarsest test digit (one quarter bridge, 0.06 deg a referenced point), so a straight gauge
#: keeps the affine map (and its variance) and a curved one (``random_digit(20)``: 0.33 deg at +-30 deg) does not.
CURVATURE_MATERIAL_DEG = 0.15
#: Two-sided level at which the sweep's curvature must be significant too (the t statistic of ``u^2`` in the
#: reference rotations regressed on ``1, u, u^2``, ``u`` the affine map's reading): a lightly damped digit's readings
#: scatter more than the threshold above assumes (``random_digit(18)``: 0.11 deg a point, t = 2.2 on one seed,
#: where ``random_digit(20)``'s curve gives t = 10-17).
CURVATURE_LEVEL = 0.01


def _curved_if_material(affine: RotationEstimator, cov, sd_v) -> RotationEstimator:
    """The map with each gauge's quadratic term (``degree=2``) where the sweep's curvature is significant at
    :data:`CURVATURE_LEVEL` and that map reads more than :data:`CURVATURE_MATERIAL_DEG` from ``affine`` somewhere on
    the sweep, else ``affine``."""
    from scipy.stats import t as student_t

    X, y = affine.gauges_v_, affine.rotation_deg_
    dof = y.size - 3
    if dof < 2 or np.unique(y).size < 3:
        return affine
    u = affine.predict(X)
    A = np.c_[np.ones_like(u), u, u * u]
    fit, *_ = np.linalg.lstsq(A, y, rcond=None)
    residual = y - A @ fit
    variance = float(residual @ residual) / dof * np.linalg.pinv(A.T @ A)[2, 2]
    if not abs(fit[2]) > student_t.ppf(1 - CURVATURE_LEVEL / 2, dof) * math.sqrt(variance):
        return affine
    curved = RotationEstimator(degree=2, noise_v=affine.noise_v).fit(X, y, rotation_cov_deg2=cov, gauges_sd_v=sd_v)
    straight = X[int(np.argmin(np.abs(y)))]
    gap = curved.tare(straight).predict(X) - affine.tare(straight).predict(X)
    curved.tare_deg_ = affine.tare_deg_ = 0.0
    return curved if float(np.max(np.abs(gap))) > CURVATURE_MATERIAL_DEG else affine


def _twin_or_operator(rig: Rig, reference, reference_sd_deg):
    """``(angle, truth, source, sd)`` of the ``"twin"`` or a callable reference of :func:`calibrate_rotation`."""
    if isinstance(reference, str) and reference == "twin":
        return None, _twin_truth(rig), "twin (its own tip rotation)", None
    if callable(reference):
        sd = ROTATION_RESOLUTION_DEG / math.sqrt(12) if reference_sd_deg is None else reference_sd_deg
        sd = check_real(sd, "reference_sd_deg", "calibrate_rotation", low=0.0)
        return reference, None, "operator (measured at each command)", sd
    raise ParameterError(
        "The 'reference' parameter of calibrate_rotation must be 'twin', a MeasuredReference or a callable. "
        f"Got {reference!r} instead."
    )


def _measured_commands(reference, commands) -> list:
    """The commands measured in ``reference``; a sweep given too must hold the same ones."""
    if commands is not None and sorted(int(c) for c in commands) != sorted(reference.commands.tolist()):
        raise ParameterError(
            f"calibrate_rotation: the sweep's commands {list(commands)} differ from those measured in "
            f"{reference.source} {reference.commands.tolist()}"
        )
    return reference.commands.tolist()


def _twin_truth(rig: Rig) -> Callable[[], float]:
    """The backend's own tip rotation (deg), the "twin" reference; refused where the backend has none."""
    truth = getattr(rig, "tip_rotation_deg", None)
    if truth is None:
        raise ParameterError(
            f"{rig.name}: no way to know the true rotation on this backend; give a reference (a file of measured "
            "rotations or deflections, or ask the operator with a protractor)"
        )
    return truth


def _run_sweep(rig: Rig, commands, angle, truth, sweep: str, *, at_rest, settle_s, samples, window_s, timeout_s):
    """:func:`_sweep` or :func:`_sweep_referenced`, as ``sweep`` says (the referenced one only at rest), each hold
    started at rest (:func:`_twin_at_rest`) if ``at_rest``."""
    timeout_s = settle_timeout_s(rig) if timeout_s is None else timeout_s
    rest_s = _rest_time_s(rig, settle_s) if at_rest else None
    if sweep == "plain":
        how = {"settle_s": settle_s, "samples": samples, "window_s": window_s, "timeout_s": timeout_s}
        return _sweep(rig, commands, angle, truth, rest_s=rest_s, **how)
    if settle_s is not None:
        raise ParameterError("calibrate_rotation: sweep='referenced' reads the digit at rest; give settle_s=None")
    return _sweep_referenced(rig, commands, angle, truth, window_s=window_s, timeout_s=timeout_s, rest_s=rest_s)


#: Time constants of the digit's slowest vibration (:func:`~flexdigit.twin.digit_calibration.decay_time_constant_s`)
#: a hold started at rest (:func:`_twin_at_rest`) lets pass, for the gauges' drift, before its window: the time the
#: sweep waits for a swing to die beyond its window, 4.9 of them (median over the visits) on the five- and the
#: seven-section test digits (``five_unequal_bronze_full``, ``seven_sections_pair_mixed``, seed 1), 1.8-2 on the
#: better damped thesis rig and one-section digit: as much drift as the slowest digits see, or more.
REST_TIME_CONSTANTS = 5.0


def _rest_time_s(rig: Rig, settle_s) -> float:
    """:data:`REST_TIME_CONSTANTS` time constants of ``rig``'s twin; refused off a twin in virtual time or with a
    fixed wait (the chapter-5 studies', kept as it was)."""
    twin = getattr(rig, "twin", None)
    if twin is None or not getattr(rig, "deterministic", False) or settle_s is not None:
        raise ParameterError(
            f"calibrate_rotation: start_at_rest puts a twin at rest in virtual time, with settle_s=None; not {rig.name}"
            + ("" if settle_s is None else f" with settle_s={settle_s}")
        )
    return REST_TIME_CONSTANTS * decay_time_constant_s(rig.params, twin.calibration)


def _twin_at_rest(rig: Rig, rest_s: float = 0.0) -> None:
    """Bring a twin (``sim`` rig, virtual time) to rest at the command in force: its servo at the command's angle
    and its digit in the static equilibrium there, ``rest_s`` seconds on.

    What the twin would reach by integrating the swing down to rest at its 2 ms step (seconds of simulated time on
    a lightly damped digit, most of a map's sweep), at the cost of one static solve. The command takes effect at
    its frame's servo pulse, as it would (up to 40 ms simulated); the gauges' drift walks over the ``rest_s``
    skipped at the next reading, so readings after it have the statistics they would have after a wait. The cable
    guides' friction is left as it is (a servo's pull does not jolt it).
    """
    twin = rig.twin
    servo = twin.servo
    if servo.pending:  # the command is latched at its frame's pulse
        twin.advance(max(servo.pending[-1][0] - twin.time_s, 0.0))
        servo.update_command(twin.time_s)
    angle = float(command_to_angle_rad(servo.command, rig.params))
    servo.angle, servo.rate = min(max(angle, servo.angle_min), servo.angle_max), 0.0
    twin.time_s += check_real(rest_s, "rest_s", "_twin_at_rest", low=0.0)
    twin.deflect(0.0)  # at rest in the static equilibrium, no force at the tip; the integration restarts here


def _sweep(rig: Rig, commands, angle, truth, *, settle_s, samples, window_s, timeout_s, rest_s=None):
    """Hold each command and read the settled gauges and the reference rotation (``angle(command)``, or the
    twin's ``truth()`` when ``angle`` is None), then relax the digit and let it settle again.

    Returns the gauges (V), their standard errors (V), the rotations (deg) and the waits (s), one per command.
    With ``rest_s`` (s), each hold starts at rest :func:`_twin_at_rest` ``rest_s`` on (counted in its wait).
    """
    X, sd_v, y, waited = [], [], [], []
    for command in commands:
        rig.write_command(command)
        if settle_s is None:
            if rest_s is not None:
                _twin_at_rest(rig, rest_s)
            settled = wait_until_settled(
                rig, window_s=window_s, timeout_s=timeout_s, truth=truth if angle is None else None
            )
            X.append(settled.gauges_v)
            sd_v.append(settled.sd_v)
            waited.append(settled.waited_s + (rest_s or 0.0))
            y.append(settled.truth_deg if angle is None else float(angle(command)))
        else:
            rig.wait(check_real(settle_s, "settle_s", "calibrate_rotation", low=0.0))
            rows, truths = [], []
            for _ in range(check_int(samples, "samples", "calibrate_rotation", low=1)):
                rig.wait(0.02)
                rows.append(rig.read().gauges_v)
                truths.append(truth() if angle is None else math.nan)
            X.append(np.mean(rows, axis=0))
            sd_v.append(np.zeros(len(rows[0])))
            waited.append(float(settle_s))
            y.append(float(np.mean(truths)) if angle is None else float(angle(command)))
    _relax(rig, settle_s, rest_s, window_s=window_s, timeout_s=timeout_s)
    return X, sd_v, y, waited


def _relax(rig: Rig, settle_s, rest_s, *, window_s, timeout_s) -> None:
    """The sweep's end: the digit relaxed and left at rest (:func:`_twin_at_rest` with ``rest_s``)."""
    rig.relax()
    if rest_s is not None:
        _twin_at_rest(rig, rest_s)
    elif settle_s is None:
        wait_until_settled(rig, window_s=window_s, timeout_s=timeout_s)
    else:
        rig.wait(settle_s)


def _sweep_referenced(rig: Rig, commands, angle, truth, *, window_s, timeout_s, rest_s=None):
    """:func:`_sweep` with the straight command read before, between and after the others (``sweep="referenced"``).

    Each reading (gauges, and the reference rotation) is taken against the straight readings just before and after
    it: their values linearly interpolated to its time are its drift since the mean straight reading, subtracted
    (the classical A-B-A drift correction of weighing and of strain-gauge zero checks). The straight command itself
    is represented by the mean of its readings. Returns :func:`_sweep`'s lists, one row per command of
    ``commands``; the waits are per visit (every visit's, in order).
    """
    straight = int(rig.params.actuator.equilibrium_command)
    visits = [straight]
    for command in commands:
        if command != straight:
            visits += [command, straight]
    gauges, sds, rotations, times, waited = [], [], [], [], []
    for command in visits:
        rig.write_command(command)
        if rest_s is not None:
            _twin_at_rest(rig, rest_s)
        settled = wait_until_settled(
            rig, window_s=window_s, timeout_s=timeout_s, truth=truth if angle is None else None
        )
        gauges.append(settled.gauges_v)
        sds.append(settled.sd_v)
        waited.append(settled.waited_s + (rest_s or 0.0))
        rotations.append(settled.truth_deg if angle is None else float(angle(command)))
        times.append(rig.clock() - window_s / 2)  # the window's middle: only differences between visits matter
    _relax(rig, None, rest_s, window_s=window_s, timeout_s=timeout_s)
    G, S, Y, T = np.asarray(gauges), np.asarray(sds), np.asarray(rotations), np.asarray(times)
    at = np.array([c == straight for c in visits])
    # the straight readings' drift from their mean, interpolated to every visit
    drift_v = np.column_stack([np.interp(T, T[at], G[at, g] - G[at, g].mean()) for g in range(G.shape[1])])
    drift_deg = np.interp(T, T[at], Y[at] - Y[at].mean())
    straight_sd = np.sqrt(np.mean(S[at] ** 2, axis=0))
    X, sd_v, y = [], [], []
    for command in commands:
        if command == straight:
            X.append(G[at].mean(axis=0))
            sd_v.append(np.sqrt(np.sum(S[at] ** 2, axis=0)) / at.sum())
            y.append(float(Y[at].mean()))
        else:
            k = visits.index(command, 1)
            X.append(G[k] - drift_v[k])
            sd_v.append(np.hypot(S[k], straight_sd))
            y.append(float(Y[k] - drift_deg[k]))
    return X, sd_v, y, waited


def _provenance(est: RotationEstimator, source: str, commands, waited, rotation_deg) -> RotationEstimator:
    est.source_ = source
    est.commands_ = [int(c) for c in commands]
    est.settle_time_s_ = [float(w) for w in waited]
    c = np.asarray(est.commands_, dtype=float)
    est.deg_per_command_ = float(np.polyfit(c, rotation_deg, 1)[0]) if np.ptp(c) > 0 else math.nan
    return est


def save_rotation_map(estimator: RotationEstimator, path, *, force: bool = False) -> Path:
    """Write a fitted map as JSON (atomically; an existing file only with ``force``)."""
    with atomic_write(path, "w", force=force) as fh:
        json.dump(to_jsonable(estimator.to_dict()), fh, indent=1)
    return Path(path)


def load_rotation_map(path) -> RotationEstimator:
    """Read a map saved by :func:`save_rotation_map` (or the earlier ``coef/intercept/gauge_v_per_deg`` JSON).

    Raises :class:`~flexdigit.errors.DataFileError` naming the file and the key that is missing or wrong.
    """
    path = Path(path)
    try:
        data = json.loads(read_text(path, "a rotation calibration JSON"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataFileError(f"{path}: not a rotation calibration, not JSON ({exc}); {_EXPECTED}") from None
    except RecursionError:  # brackets nested past the parser's depth
        raise DataFileError(f"{path}: not a rotation calibration (JSON nested too deep); {_EXPECTED}") from None
    est = RotationEstimator.from_dict(data, source=str(path))
    est.source_ = f"{getattr(est, 'source_', 'a saved map')}, loaded from {path}"
    return est


_EXPECTED = "expected a flexdigit rotation map: coef[G], intercept, gauge_v_per_deg[G] (G = 1..8 gauges)"


def _quadratic_root(slope: float, curvature: float, r: float) -> float:
    """The root of ``curvature x^2 + slope x = r`` that tends to ``r / slope`` as ``curvature`` -> 0 (slope > 0)."""
    return 2.0 * r / (slope + math.sqrt(max(slope * slope + 4.0 * curvature * r, 0.0)))


def _from_dict(cls, data, source: str) -> RotationEstimator:
    """:meth:`RotationEstimator.from_dict`."""
    if not isinstance(data, dict):
        raise DataFileError(f"{source}: not a rotation calibration; {_EXPECTED}")
    if data.get("format", MAP_FORMAT) != MAP_FORMAT:
        raise DataFileError(f"{source}: format {data.get('format')!r}; this flexdigit reads {MAP_FORMAT!r}")
    known = {"format", "method", "coef", "intercept", "gauge_v_per_deg", "residual_deg", "gauges_v", "rotation_deg"}
    known |= {"degree", "quadratic", "gauge_v_per_deg2"}
    known |= {"rotation_cov_deg2", "gauges_sd_v", *_PROVENANCE}
    unknown = sorted(set(data) - known)
    if unknown:
        raise DataFileError(f"{source}: unknown key {unknown[0]!r}; {_EXPECTED}")
    for key in ("coef", "intercept", "gauge_v_per_deg"):
        if key not in data:
            raise DataFileError(f"{source}: not a rotation calibration, no {key!r}; {_EXPECTED}")

    def array(key, shape):
        try:
            value = np.asarray(data[key], dtype=float)
        except (TypeError, ValueError):
            value = np.array([np.nan])
        if value.shape != shape or not np.all(np.isfinite(value)):
            raise DataFileError(f"{source}: {key!r} must be finite numbers of shape {shape}; got {data[key]!r:.80}")
        return value

    est = cls(method=str(data.get("method", "sensitivity")))
    gauges = len(data["coef"]) if isinstance(data["coef"], list) and 1 <= len(data["coef"]) <= MAX_GAUGES else 3
    est.coef_ = array("coef", (gauges,))
    est.intercept_ = float(array("intercept", ()))
    est.gauge_v_per_deg_ = array("gauge_v_per_deg", (gauges,))
    if not np.any(est.coef_ != 0) or not abs(est.coef_ @ est.gauge_v_per_deg_) > 0:
        raise DataFileError(f"{source}: the map's 'coef' {est.coef_.tolist()} read no rotation from the gauges")
    est.tare_deg_ = 0.0
    est.quadratic_ = 0.0
    if data.get("degree", 1) not in (1, 2):
        raise DataFileError(f"{source}: 'degree' must be 1 or 2; got {data.get('degree')!r:.40}")
    if data.get("degree", 1) == 2:
        for key in ("quadratic", "gauge_v_per_deg2"):
            if key not in data:
                raise DataFileError(f"{source}: 'degree' 2 without {key!r}; {_EXPECTED}")
        est.degree = 2
        est.quadratic_ = float(array("quadratic", ()))
        est.gauge_v_per_deg2_ = array("gauge_v_per_deg2", (gauges,))
    residual = data.get("residual_deg")
    est.residual_deg_ = float(residual) if isinstance(residual, int | float) else math.nan
    if "rotation_deg" in data:
        n = len(data["rotation_deg"]) if isinstance(data["rotation_deg"], list) else -1
        est.rotation_deg_ = array("rotation_deg", (n,))
        for key, shape in (("gauges_v", (n, gauges)), ("rotation_cov_deg2", (n, n)), ("gauges_sd_v", (n, gauges))):
            if key not in data:
                raise DataFileError(f"{source}: 'rotation_deg' without {key!r}; {_EXPECTED}")
            setattr(est, f"{key}_", array(key, shape))
    for key in _PROVENANCE:
        if key in data:
            setattr(est, f"{key}_", data[key])
    if "noise_scale" in data:  # the weights it was fitted with: its uncertainty refits the same way
        est.noise_v = array("noise_scale", (gauges,))
    return est

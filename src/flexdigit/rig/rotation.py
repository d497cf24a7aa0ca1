"""Beam (tip) rotation from the three gauge voltages: the map and the static sweep that calibrates it.

:class:`RotationEstimator` is an affine map fitted on a static calibration sweep (commands 8..32, the digit at rest
at each). The sweep moves the digit along one direction only, so the map inverts each gauge's sensitivity to the
rotation (a well-posed one-parameter fit) rather than regressing the rotation on three nearly collinear gauges. On
the twin the reference angle is the twin's own tip rotation; on hardware it is what the operator reads off a
protractor (``angle_source``). The map is tared at the start of every run (the digit at rest at the equilibrium
command is 0 deg by definition), so gauge offsets and drift between calibration and run do not become a
steady-state error.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from flexdigit._validation import check_array, check_choice, check_real
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.rig.base import Reading, Rig

__all__ = ["RotationEstimator", "calibrate_rotation", "load_rotation_map"]


class RotationEstimator:
    """Beam rotation (deg) from the three gauge voltages, ``w . gauges_v + b - tare`` (scikit-learn's contract).

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
    noise_v : sequence of 3 floats, optional
        Per-gauge noise standard deviation (V) for the Gauss-Markov weights; equal weights if None.
    ridge : float
        Tikhonov term of ``"lstsq"`` (unused by ``"sensitivity"``).

    Examples
    --------
    >>> est = RotationEstimator().fit([[0, 0, 0], [1, 2, 1], [2, 4, 2], [3, 6, 3]], [0, 10, 20, 30])
    >>> round(est.predict_one(np.array([1.5, 3, 1.5])), 3), [round(float(w), 3) for w in est.coef_]
    (15.0, [1.667, 3.333, 1.667])
    """

    METHODS = ("sensitivity", "lstsq")

    def __init__(self, method: str = "sensitivity", noise_v=None, ridge: float = 1e-9) -> None:
        self.method = method
        self.noise_v = noise_v
        self.ridge = ridge

    def fit(self, gauges_v, rotation_deg) -> RotationEstimator:
        check_choice(self.method, "method", self.METHODS, "RotationEstimator")
        X = np.asarray(gauges_v, dtype=float)
        y = np.asarray(rotation_deg, dtype=float).reshape(-1)
        if X.ndim != 2 or X.shape[1] != 3 or X.shape[0] != y.size or y.size < 4:
            raise DataFileError(
                f"RotationEstimator.fit needs (n, 3) gauge voltages and n >= 4 angles. Got {X.shape} and {y.shape}."
            )
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
            raise DataFileError("RotationEstimator.fit: the calibration data contain NaN or inf")
        yc = y - y.mean()
        if not np.ptp(y) > 0:
            raise DataFileError(
                f"RotationEstimator.fit: the reference rotations must vary across the sweep. Got {y.tolist()!r}."
            )
        # each gauge's volts per degree along the sweep (least-squares slopes): the sensitivities s
        sens = ((X - X.mean(axis=0)).T @ yc) / float(yc @ yc)
        self.gauge_v_per_deg_ = sens
        if self.method == "sensitivity":
            if self.noise_v is None:
                weight = np.ones(3)
            else:
                noise = check_array(self.noise_v, "noise_v", "RotationEstimator", shape=(3,), low=0.0, low_open=True)
                weight = 1.0 / noise**2
            information = float(sens @ (weight * sens))
            if not information > 0:
                raise DataFileError("RotationEstimator.fit: the gauges did not change over the sweep")
            offset = X.mean(axis=0) - sens * y.mean()  # gauges at 0 deg
            self.coef_ = weight * sens / information
            self.intercept_ = float(-self.coef_ @ offset)
        else:
            A = np.c_[X, np.ones(len(X))]
            reg = check_real(self.ridge, "ridge", "RotationEstimator", low=0.0) * np.eye(4)
            reg[3, 3] = 0.0
            coef = np.linalg.solve(A.T @ A + reg, A.T @ y)
            self.coef_ = coef[:3]
            self.intercept_ = float(coef[3])
        self.residual_deg_ = float(np.sqrt(np.mean((X @ self.coef_ + self.intercept_ - y) ** 2)))
        self.tare_deg_ = 0.0
        return self

    def predict(self, gauges_v) -> np.ndarray:
        return np.asarray(gauges_v, dtype=float) @ self.coef_ + self.intercept_ - self.tare_deg_

    def predict_one(self, gauges_v: np.ndarray) -> float:
        g = gauges_v
        c = self.coef_
        return float(g[0] * c[0] + g[1] * c[1] + g[2] * c[2]) + self.intercept_ - self.tare_deg_

    def tare(self, gauges_v, at_deg: float = 0.0) -> RotationEstimator:
        """Shift the map so ``gauges_v`` (mean of rows) reads ``at_deg``."""
        g = np.atleast_2d(np.asarray(gauges_v, dtype=float)).mean(axis=0)
        self.tare_deg_ = 0.0
        self.tare_deg_ = float(self.predict_one(g) - at_deg)
        return self

    def __call__(self, reading: Reading) -> float:
        return self.predict_one(reading.gauges_v)

    def to_dict(self) -> dict:
        """The fitted map as plain numbers (``flexdigit run --calibration`` saves it; recordings keep it)."""
        return {
            "method": self.method,
            "coef": self.coef_.tolist(),
            "intercept": self.intercept_,
            "gauge_v_per_deg": self.gauge_v_per_deg_.tolist(),
        }

    @classmethod
    def from_dict(cls, data, source="rotation map") -> RotationEstimator:
        """A fitted map from :meth:`to_dict`'s numbers; :class:`DataFileError` naming ``source`` if they are not."""
        try:
            est = cls(method=str(data.get("method", "sensitivity")))
            est.coef_ = np.asarray(data["coef"], dtype=float).reshape(3)
            est.intercept_ = float(data["intercept"])
            est.gauge_v_per_deg_ = np.asarray(data["gauge_v_per_deg"], dtype=float).reshape(3)
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise DataFileError(
                f"{source}: not a rotation calibration (expected coef[3], intercept, gauge_v_per_deg[3]): {exc}"
            ) from None
        if not (np.all(np.isfinite(est.coef_)) and np.isfinite(est.intercept_)):
            raise DataFileError(f"{source}: the rotation map's numbers must be finite")
        est.tare_deg_, est.residual_deg_ = 0.0, float("nan")
        return est


def load_rotation_map(path) -> RotationEstimator:
    """Read a rotation map saved by ``flexdigit run --calibration FILE`` (JSON of :meth:`RotationEstimator.to_dict`)."""
    import json
    from pathlib import Path

    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except ValueError as exc:
        raise DataFileError(f"{path}: not a rotation calibration (not JSON: {exc})") from None
    return RotationEstimator.from_dict(data, source=path)


def calibrate_rotation(
    rig: Rig,
    commands=(8, 11, 14, 17, 20, 23, 26, 29, 32),
    *,
    settle_s: float = 2.0,
    samples: int = 5,
    angle_source: Callable[[int], float] | None = None,
) -> RotationEstimator:
    """Static calibration sweep: hold each command, average ``samples`` readings, fit gauges -> rotation.

    ``angle_source(command)`` gives the reference rotation (deg) at each point; default the twin's own
    (``rig.tip_rotation_deg``), which hardware backends do not have: pass a function that asks the operator.
    """
    if angle_source is None:
        truth = getattr(rig, "tip_rotation_deg", None)
        if truth is None:
            raise ParameterError(
                f"{rig.name}: no way to know the true rotation on this backend; pass angle_source (e.g. a protractor)"
            )

        def angle_source(command: int) -> float:
            return truth()

    X, y = [], []
    for command in commands:
        rig.write_command(int(command))
        rig.wait(settle_s)
        rows = []
        for _ in range(samples):
            rig.wait(0.02)
            rows.append(rig.read().gauges_v)
        X.append(np.mean(rows, axis=0))
        y.append(float(angle_source(int(command))))
    rig.relax()
    rig.wait(settle_s)
    return RotationEstimator().fit(X, y)

"""Closed-loop experiments on any rig: the beam-rotation measurement, controllers by name, and the step test.

- :class:`RotationEstimator`: beam (tip) rotation in degrees from the three gauge voltages, an affine map fitted on
  a static calibration sweep (commands 8..32, the digit at rest at each). The sweep moves the digit along one
  direction only, so the map inverts each gauge's sensitivity to the rotation (a well-posed one-parameter fit)
  rather than regressing the rotation on three nearly collinear gauges. On the twin the reference angle is the
  twin's own tip rotation; on hardware it is what the operator reads off a protractor (``angle_source``). The map
  is tared at the start of every run (the digit at rest at the equilibrium command is 0 deg by definition), so
  gauge offsets and drift between calibration and run do not become a steady-state error.
- :func:`make_controller`: the controllers ``flexdigit run --controller NAME`` knows: ``digital20`` (the discrete
  design of :mod:`flexdigit.control.design20ms`), ``thesis39-euler`` and ``thesis39-tustin`` (the printed 39 Hz
  controller digitised as 5.2 and 5.1.1 did, on gauge-1 deflection in metres).
- :func:`step_test`: 0 -> ``step_deg`` at ``step_time_s``, run on :func:`~flexdigit.rig.loop.run_loop`, with the
  figures the issue asks for (2 % settling time, overshoot, steady-state error in command quanta).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from flexdigit._validation import check_array, check_choice, check_positive, check_real
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.params import RigParams
from flexdigit.rig.base import Reading, Rig
from flexdigit.rig.loop import LoopResult, run_loop

__all__ = [
    "RotationEstimator",
    "calibrate_rotation",
    "CONTROLLERS",
    "make_controller",
    "StepMetrics",
    "step_metrics",
    "StepTest",
    "step_test",
]


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


# -- controllers by name ---------------------------------------------------------------------------------------


def _gauge1_deflection_m(params: RigParams, tare_v: float) -> Callable[[Reading], float]:
    """Gauge-1 deflection (m) from its voltage through the printed K3 (E 3.23, 6.5698 mm/V)."""
    from flexdigit.models.conversion import k3_printed_mm_per_v

    k3_m_per_v = k3_printed_mm_per_v()[0] / 1000.0
    return lambda reading: (float(reading.gauges_v[0]) - tare_v) * k3_m_per_v


class _Wrapped:
    """Adapts a :class:`RuntimeController` to the loop: measurement, setpoint units, optional actuator gain error."""

    def __init__(self, runtime, measure, setpoint_scale: float = 1.0, gain: float = 1.0, equilibrium: int = 8):
        self.runtime, self.measure = runtime, measure
        self.setpoint_scale, self.gain, self.equilibrium = setpoint_scale, gain, equilibrium
        self.name = runtime.name

    def reset(self, command: int) -> None:
        self.runtime.reset(command)

    def step(self, setpoint: float, reading: Reading) -> float:
        u = self.runtime.update(setpoint * self.setpoint_scale, self.measure(reading))
        # a plant gain error, emulated at the actuator: the servo gets gain x the asked deviation
        return self.equilibrium + self.gain * (u - self.equilibrium) if self.gain != 1.0 else u


CONTROLLERS = ("digital20", "thesis39-euler", "thesis39-tustin")


def make_controller(
    name: str,
    rig: Rig,
    *,
    period_s: float = 0.020,
    estimator: RotationEstimator | None = None,
    gain: float = 1.0,
) -> _Wrapped:
    """Build controller ``name`` for ``rig``; its setpoint is beam rotation in degrees for all of them.

    The thesis controllers work on gauge-1 deflection (m): the setpoint in degrees is converted with the sweep's
    gauge-1 volts per degree times the printed K3 (6.5698 mm/V, E 3.23).
    """
    from flexdigit.control.design20ms import design_20ms, thesis_controller

    check_choice(name, "controller", CONTROLLERS, "make_controller")
    check_positive(period_s, "period_s", "make_controller")
    check_real(gain, "gain", "make_controller", low=0.0, low_open=True)
    params = rig.params
    if estimator is None:
        estimator = calibrate_rotation(rig)
    rest = [rig.read().gauges_v for _ in range(5)]
    estimator.tare(rest)
    eq = int(params.actuator.equilibrium_command)
    if name == "digital20":
        design = design_20ms(params, period_s=period_s)
        return _Wrapped(design.runtime(params, name=name), estimator, 1.0, gain, eq)
    method = "forward_euler" if name.endswith("euler") else "tustin"
    measure = _gauge1_deflection_m(params, float(np.mean([g[0] for g in rest])))
    from flexdigit.models.conversion import k3_printed_mm_per_v

    # metres of gauge-1 deflection per degree: K3 (m/V) x the sweep's gauge-1 volts per degree
    scale = k3_printed_mm_per_v()[0] / 1000.0 * float(estimator.gauge_v_per_deg_[0])
    return _Wrapped(thesis_controller(method, period_s, params), measure, scale, gain, eq)


# -- the step test ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StepMetrics:
    """Step figures, on the rotation: 2 % settling time (s, inf if never), overshoot (%), final error (deg),
    final error in command quanta, and whether the response stayed bounded."""

    settling_time_s: float
    overshoot_percent: float
    final_error_deg: float
    final_error_quanta: float
    peak_deg: float
    bounded: bool


def step_metrics(
    t_s, y_deg, step_deg: float, step_time_s: float, deg_per_command: float, band: float = 0.02
) -> StepMetrics:
    """Settling (within ``band`` x step for good), overshoot and final error (mean of the last 0.5 s).

    Examples
    --------
    >>> t = np.arange(0, 3, 0.02); y = np.where(t >= 0.2, 30 * (1 - np.exp(-(t - 0.2) / 0.1)), 0)
    >>> m = step_metrics(t, y, 30, 0.2, 1.735)
    >>> round(m.settling_time_s, 2), m.overshoot_percent
    (0.4, 0.0)
    """
    t = np.asarray(t_s, dtype=float)
    y = np.asarray(y_deg, dtype=float)
    after = t >= step_time_s - 1e-9
    t, y = t[after] - step_time_s, y[after]
    bounded = bool(np.all(np.isfinite(y)) and np.max(np.abs(y)) < 10 * abs(step_deg))
    peak = float(np.max(y)) if y.size else math.nan
    overshoot = max(0.0, (peak - step_deg) / step_deg * 100.0)
    outside = np.nonzero(np.abs(y - step_deg) > band * abs(step_deg))[0]
    if not outside.size:
        settling = 0.0
    elif outside[-1] + 1 < t.size:
        settling = float(t[outside[-1] + 1])
    else:
        settling = math.inf
    tail = y[t >= t[-1] - 0.5] if t.size else y
    final = float(np.mean(tail) - step_deg)
    return StepMetrics(settling, overshoot, final, abs(final) / deg_per_command, peak, bounded)


@dataclass
class StepTest:
    """A step test: the loop's result, the true rotation (twin) or the estimate, and the metrics."""

    controller: str
    gain: float
    result: LoopResult
    rotation_deg: np.ndarray
    metrics: StepMetrics
    extra: dict = field(default_factory=dict)


def step_test(
    rig: Rig,
    controller: str = "digital20",
    *,
    step_deg: float = 30.0,
    step_time_s: float = 0.2,
    duration_s: float = 3.0,
    period_s: float = 0.020,
    gain: float = 1.0,
    estimator: RotationEstimator | None = None,
    log_path=None,
) -> StepTest:
    """Run a 0 -> ``step_deg`` beam-rotation step on ``rig`` with ``controller`` and measure it.

    The rotation scored is the twin's true tip rotation when the rig has one (``tip_rotation_deg``), else the
    estimate from the gauges. The rig is closed at the end (relaxed to command 8).
    """
    from flexdigit.control.design20ms import design_plant

    step = check_real(step_deg, "step_deg", "step_test", low=0.0, low_open=True)
    ctl = make_controller(controller, rig, period_s=period_s, estimator=estimator, gain=gain)
    truth = getattr(rig, "tip_rotation_deg", None)
    est = ctl.measure if controller == "digital20" else None
    rotation: list[float] = []

    def record(k, t, y, command):
        rotation.append(truth() if truth is not None else (y if est is not None else math.nan))

    result = run_loop(
        rig,
        ctl,
        setpoint=lambda t: step if t >= step_time_s - 1e-9 else 0.0,
        duration_s=duration_s,
        period_s=period_s,
        on_sample=record,
        log_path=log_path,
        header={"experiment": "step", "step_deg": step, "gain": gain},
    )
    deg_per_command = float(np.real(design_plant(rig.params).dcgain()))
    metrics = step_metrics(result.time_s, np.array(rotation), step, step_time_s, deg_per_command)
    return StepTest(controller, gain, result, np.array(rotation), metrics)

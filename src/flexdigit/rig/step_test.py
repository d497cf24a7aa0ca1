"""The closed-loop step test on any rig, with the figures a user runs a step for (5.2).

:func:`step_test` runs 0 -> ``step_deg`` at ``step_time_s`` on :func:`~flexdigit.rig.loop.run_loop` and scores it
with :func:`step_metrics` (2 % settling time, overshoot, steady-state error in degrees and command quanta).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from flexdigit._validation import check_real
from flexdigit.rig.base import Rig
from flexdigit.rig.controllers import make_controller
from flexdigit.rig.loop import LoopResult, run_loop
from flexdigit.rig.rotation import RotationEstimator

__all__ = ["StepMetrics", "step_metrics", "StepTest", "step_test"]


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

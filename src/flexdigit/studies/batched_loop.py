"""The 20 ms loop closed on the batched twin: many rigs' setpoint steps at once (the studies' "twin run" metrics).

The linear metrics (:func:`flexdigit.studies.metrics.loop_plant`) judge the 20 ms controller on the digit
linearised mid-range, a clean one-sample delay and a continuous command. On the rig the command is an integer
(1.7 deg of rotation a step), latched on the serial frame and then on the servo's next 52 Hz PWM pulse (0-19 ms
later, not a whole sample), the digit bends by large angles and the cable can go slack. :func:`step_responses`
runs the loop as :func:`flexdigit.rig.loop.run_loop` runs it on the twin, for N rigs together on
:class:`~flexdigit.twin.batched.BatchedTwin`: every 20 ms read the rotation, update the controller, send the integer
command. The controller is :meth:`flexdigit.control.runtime.RuntimeController.update` over a batch
(:class:`BatchedRuntime`, held to the scalar one in the tests).

The schedule (:class:`StepSchedule`): the digit tip up (2.2.4), housed, at rest at the equilibrium command; the
setpoint holds ``mid - step/2`` (the lower end of a step centred on the mid-range rotation, where the linear
model is linearised) for ``hold_s``, then jumps to ``mid + step/2``. The rotation fed back is the twin's true tip
rotation (noise-free: a study of the loop, not of the gauge-to-rotation estimate). The twin steps at 2 ms (as
:class:`~flexdigit.rig.backends.sim_backend.SimRig`: a loop closed every 20 ms acts on the motion between frames).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._validation import check_real
from flexdigit.control.analysis import step_figures
from flexdigit.errors import DesignError
from flexdigit.twin.batched import BatchedTwin

__all__ = ["StepSchedule", "BatchedRuntime", "StepResponses", "step_responses", "step_figures_batch"]


@dataclass(frozen=True)
class StepSchedule:
    """The setpoint step the twin-run metrics score (see the module docstring).

    Attributes
    ----------
    step_deg : float
        Size of the setpoint step (deg of tip rotation), centred on the mid-range rotation.
    hold_s : float
        Time at the lower setpoint before the step (the loop settles there from rest).
    after_s : float
        Time scored after the step.
    tail_s : float
        The last ``tail_s`` of the run give the steady-state error (their mean rotation against the setpoint).
    dt_s : float
        The twin's integration step.
    """

    step_deg: float = 20.0
    hold_s: float = 1.0
    after_s: float = 2.0
    tail_s: float = 0.5
    dt_s: float = 0.002

    def __post_init__(self) -> None:
        check_real(self.step_deg, "step_deg", "StepSchedule", low=0.0, low_open=True)
        check_real(self.hold_s, "hold_s", "StepSchedule", low=0.0)
        after = check_real(self.after_s, "after_s", "StepSchedule", low=0.0, low_open=True)
        check_real(self.tail_s, "tail_s", "StepSchedule", low=0.0, low_open=True, high=after)
        check_real(self.dt_s, "dt_s", "StepSchedule", low=1e-4, high=0.02)


class BatchedRuntime:
    """N runtime controllers updated together: :meth:`RuntimeController.update` over a batch.

    Supports what the loop runs: one or two inputs, saturation, the integer command, back-calculation
    anti-windup (the 20 ms design feeds its observer the applied integer command) or none; no hysteresis or
    deadband. A rig whose controller output is not finite gets NaN commands from then on (its run is void),
    not an exception that would take the batch down.

    Parameters
    ----------
    controllers : sequence of RuntimeController
        One per rig (the same object may repeat).
    """

    def __init__(self, controllers) -> None:
        controllers = list(controllers)
        if not controllers:
            raise DesignError("BatchedRuntime needs at least one controller")
        first = controllers[0]
        for c in controllers:
            if c.hysteresis or c._db_index is not None or c.antiwindup == "clamp":
                raise DesignError(f"BatchedRuntime: {c!r} uses hysteresis, a deadband or clamping (not batched)")
            if (c.nstates, c.ninputs, c.period_s, c.quantise) != (
                first.nstates,
                first.ninputs,
                first.period_s,
                first.quantise,
            ):
                raise DesignError("BatchedRuntime: the controllers differ in states, inputs, period or quantisation")
        self.size = len(controllers)
        self.period_s = first.period_s
        self.quantise = first.quantise
        self.ninputs = first.ninputs
        self._a = np.stack([c.sys.A for c in controllers])
        self._b = np.stack([c.sys.B for c in controllers])
        self._c = np.stack([np.asarray(c.sys.C).reshape(-1) for c in controllers])
        self._d = np.stack([np.asarray(c.sys.D).reshape(-1) for c in controllers])
        self._l = np.stack([c.aw_gain for c in controllers])
        self._lq = np.stack([c._q_gain for c in controllers])
        self.u_eq = np.array([c.u_eq for c in controllers])
        self.u_min = np.array([c.u_min for c in controllers])
        self.u_max = np.array([c.u_max for c in controllers])
        self.x = np.zeros((self.size, first.nstates))  # bumpless start at the equilibrium command (x = 0)

    def update(self, r, y) -> np.ndarray:
        """One sample for every rig: setpoints ``r`` and measurements ``y`` (N,) in, commands (N,) out."""
        r = np.broadcast_to(np.asarray(r, dtype=float), (self.size,))
        y = np.broadcast_to(np.asarray(y, dtype=float), (self.size,))
        w = (r - y)[:, None] if self.ninputs == 1 else np.column_stack([r, y])
        u_raw = self.u_eq + np.einsum("bi,bi->b", self._c, self.x) + np.einsum("bi,bi->b", self._d, w)
        x_next = np.einsum("bij,bj->bi", self._a, self.x) + np.einsum("bij,bj->bi", self._b, w)
        u_clip = np.clip(u_raw, self.u_min, self.u_max)
        u = np.round(u_clip) if self.quantise else u_clip  # half to even, as Python's round
        self.x = x_next + self._l * (u_clip - u_raw)[:, None] + self._lq * (u - u_clip)[:, None]
        void = ~np.isfinite(u_raw)
        self.x[void] = np.nan
        return np.where(void, np.nan, u)


@dataclass(frozen=True)
class StepResponses:
    """The loop's runs: ``time_s`` (K,) sample times, ``rotation_deg`` and ``command`` (N, K) as sampled,
    ``low_deg``/``high_deg`` (N,) the setpoints before and after the step at ``step_time_s``."""

    time_s: np.ndarray
    rotation_deg: np.ndarray
    command: np.ndarray
    low_deg: np.ndarray
    high_deg: np.ndarray
    step_time_s: float
    schedule: StepSchedule

    __repr__ = fields_summary


def step_responses(
    params, calibrations, controllers, mid_deg, schedule: StepSchedule | None = None, *, pretension_n=None
) -> StepResponses:
    """Run the schedule's setpoint step on N rigs of the batched twin, each with its own controller.

    Parameters
    ----------
    params, calibrations : sequence
        One :class:`~flexdigit.params.RigParams` and one :class:`~flexdigit.twin.calibration.Calibration` per rig.
    controllers : sequence of RuntimeController
    mid_deg : array_like, shape (N,)
        The rotation each rig's step is centred on (deg).
    schedule : StepSchedule, optional
    pretension_n : sequence of float or None, optional
        Per rig, the pretension of a second, antagonistic cable (N), None for the thesis's single cable
        (:class:`~flexdigit.twin.batched.BatchedTwin`).
    """
    schedule = schedule or StepSchedule()
    ctl = BatchedRuntime(controllers)
    pre = antagonist = None
    if pretension_n is not None and any(p is not None for p in pretension_n):
        pre = [0.0 if p is None else p for p in pretension_n]
        antagonist = [p is not None for p in pretension_n]
    twins = BatchedTwin(list(params), list(calibrations), dt_s=schedule.dt_s, pretension_n=pre, antagonist=antagonist)
    if twins.size != ctl.size:
        raise DesignError(f"step_responses: {twins.size} rigs and {ctl.size} controllers")
    period = ctl.period_s
    mid = np.broadcast_to(np.asarray(mid_deg, dtype=float), (twins.size,))
    low, high = mid - 0.5 * schedule.step_deg, mid + 0.5 * schedule.step_deg
    n_hold = int(round(schedule.hold_s / period))
    n_samples = n_hold + int(round(schedule.after_s / period))
    start = twins.tip_rotation_deg().copy()  # the rest rotation is the zero of the controller's measurement
    rotation = np.empty((twins.size, n_samples))
    command = np.empty((twins.size, n_samples))
    live = np.ones(twins.size, dtype=bool)
    for k in range(n_samples):
        y = twins.tip_rotation_deg() - start
        rotation[:, k] = y
        u = ctl.update(low if k < n_hold else high, y)
        live &= np.isfinite(u)
        u = np.where(live, u, ctl.u_eq)  # a void rig is relaxed (and scored NaN below)
        command[:, k] = u
        twins.command(u.astype(int))
        twins.advance(period)
    rotation[~live] = np.nan
    return StepResponses(np.arange(n_samples) * period, rotation, command, low, high, n_hold * period, schedule)


def step_figures_batch(run: StepResponses, band: float = 0.02) -> dict[str, np.ndarray]:
    """Settling time (s, 2 % of the step as run, interpolated between samples), overshoot (%) and steady-state
    error (deg, mean of the last ``tail_s`` against the setpoint) of every run after its step.

    The settling and overshoot are :func:`flexdigit.control.analysis.step_figures` of the rotation from its value
    at the step, against its final sample, as the linear metrics score the linear loop's step; the integer command's
    offset shows in the steady-state error instead (the design holds it within half a quantum).
    """

    after = run.time_s >= run.step_time_s - 1e-9
    t = run.time_s[after] - run.step_time_s
    tail = t >= t[-1] - run.schedule.tail_s + 1e-9
    settling, overshoot, error = (np.full(len(run.low_deg), math.nan) for _ in range(3))
    for i, y in enumerate(run.rotation_deg):
        if not np.all(np.isfinite(y)):
            continue
        ya = y[after]
        moved = ya - ya[0]
        if abs(moved[-1]) < 0.5 * run.schedule.step_deg:  # it never followed the step: no settling to speak of
            settling[i], overshoot[i] = math.inf, math.inf
        else:
            figures = step_figures(t, moved, target=float(moved[-1]), band=band)
            settling[i], overshoot[i] = figures.settling_time_s, figures.overshoot_percent
        error[i] = abs(float(np.mean(ya[tail])) - run.high_deg[i])
    return {"settling_time_s": settling, "overshoot_percent": overshoot, "steady_state_error_deg": error}

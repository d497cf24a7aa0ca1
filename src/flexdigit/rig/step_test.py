"""The closed-loop step test on any rig, with the figures a user runs a step for (5.2).

:func:`step_test` runs 0 -> ``step_deg`` at ``step_time_s`` on :func:`~flexdigit.rig.loop.run_loop` and scores it
with :func:`step_metrics` (rise time, 2 % settling time, overshoot, steady-state error in degrees and in commands,
IAE).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from flexdigit._repr import fields_summary, summary
from flexdigit._validation import check_real
from flexdigit.errors import ParameterError
from flexdigit.models.cable import tip_rotation_per_command_deg
from flexdigit.params import RigParams
from flexdigit.rig.base import Rig, open_rig, parse_rig_url
from flexdigit.rig.controllers import make_controller
from flexdigit.rig.loop import LoopResult, run_loop
from flexdigit.rig.rotation import RotationEstimator
from flexdigit.rig.safety import RunawayGuard
from flexdigit.rig.sample_log import SampleLog, board_log_header, board_log_sample

__all__ = [
    "StepMetrics",
    "step_metrics",
    "StepTest",
    "step_test",
    "StepRun",
    "run_step",
    "board_step_test",
    "reachable_rotation_deg",
    "check_setpoint",
    "FINAL_WINDOW_S",
    "ESTIMATE_SMOOTH_S",
]

#: The steady state is the mean of the record's last 0.5 s, and a settling time needs the rotation to stay in the
#: band that long at the end of the record: a record that ends (or faults) sooner after entering the band, or
#: still moving over its last 0.5 s, shows no settling and no steady state (inf and NaN, null in JSON), rather
#: than a plausible number. 0.5 s is a period of the housed digit's ~2 Hz mode: a ring that would carry the
#: rotation out of the band again shows within it.
FINAL_WINDOW_S = 0.5


@dataclass(frozen=True)
class StepMetrics:
    """The figures a user runs a step for, on the beam rotation (deg), scored against the setpoint.

    Attributes
    ----------
    rise_time_s : float
        10 % -> 90 % of the step (inf if 90 % is never reached).
    settling_time_s : float
        Time after the step from which the rotation stays within 2 % of the step of the setpoint to the end of
        the record, at least the last :data:`FINAL_WINDOW_S` (inf if not: with an integer command the loop may
        end up to half a quantum, 0.87 deg, from the setpoint; or the run ended or faulted too soon).
    settling_to_final_s : float
        The same about the final rotation instead of the setpoint: when the digit stopped moving (inf if it
        was still moving over the last :data:`FINAL_WINDOW_S`).
    overshoot_percent : float
        Peak beyond the setpoint, in percent of the step (0 if it never got beyond).
    final_error_deg : float
        Steady-state error: mean of the last :data:`FINAL_WINDOW_S` minus the setpoint (signed, deg); NaN when the
        rotation was still moving then (no steady state in the record).
    final_error_commands : float
        The same in servo commands (signed): deg over the rig's rotation per command.
    final_error_quanta : float
        ``|final_error_commands|``: how many command quanta the loop ends away from the setpoint.
    iae_deg_s : float
        Integral of the absolute error from the step to the end of the run (deg s); also for a zero step.
    peak_deg, peak_time_s : float
        The largest rotation and when it came (s after the step).
    bounded : bool
        Every sample finite and within 10 steps of the setpoint.
    """

    rise_time_s: float
    settling_time_s: float
    settling_to_final_s: float
    overshoot_percent: float
    final_error_deg: float
    final_error_commands: float
    final_error_quanta: float
    iae_deg_s: float
    peak_deg: float
    peak_time_s: float
    bounded: bool

    def to_dict(self) -> dict:
        """The figures by name, units in the names (``--json``, the log's closing record)."""
        return dataclasses.asdict(self)

    __repr__ = fields_summary


def step_metrics(
    t_s,
    y_deg,
    step_deg: float,
    step_time_s: float,
    deg_per_command: float,
    band: float = 0.02,
    initial_deg: float = 0.0,
    smooth_s: float = 0.0,
) -> StepMetrics:
    """Score a step of the beam rotation from ``initial_deg`` to ``step_deg`` applied at ``step_time_s``.

    The figures are :func:`flexdigit.control.analysis.step_figures` (the same code scores a linear model's
    step), against the setpoint: settling means within ``band`` x the step *of the setpoint*, and the
    steady-state error (mean of the last 0.5 s) is given in degrees and in commands. Where the record cannot
    tell (a run shorter than the settling, a fault, a loop that never settles, a zero step's rise and
    overshoot, fewer than two samples after the step) the figure is inf or NaN, never a number the record does
    not support (see :data:`FINAL_WINDOW_S`).

    ``smooth_s`` > 0 first averages the record over a centred window of that length (odd number of samples):
    for a measured rotation, whose noise (about 0.2 deg rms from the gauges' 2 mV on the twin) is half the 2 %
    band of a 20 deg step and would otherwise decide the settling time. A 0.1 s window passes the digit's
    ~2 Hz ringing at 94 %.

    Examples
    --------
    A first-order rise (time constant 0.1 s) sampled at 20 ms: rise 0.1 ln 9 = 0.22 s, settling 0.1 ln 50 = 0.39 s,
    IAE 30 x 0.1 = 3 deg s (the trapezoid over 20 ms samples reads 0.3 % high).

    >>> t = np.arange(0, 3, 0.02); y = np.where(t >= 0.2, 30 * (1 - np.exp(-(t - 0.2) / 0.1)), 0)
    >>> m = step_metrics(t, y, 30, 0.2, 1.735)
    >>> round(m.rise_time_s, 2), round(m.settling_time_s, 2), m.overshoot_percent, round(m.iae_deg_s, 2)
    (0.22, 0.39, 0.0, 3.01)
    """
    from flexdigit.control.analysis import step_figures

    per_command = check_real(deg_per_command, "deg_per_command", "step_metrics", low=0.0, low_open=True)
    y = np.asarray(y_deg, dtype=float).reshape(-1)
    t = np.asarray(t_s, dtype=float).reshape(-1)
    if np.count_nonzero(t >= step_time_s - 1e-9) < 2:  # a run that ended (or faulted) at the step: nothing to score
        nan = math.nan
        return StepMetrics(nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, bool(np.all(np.isfinite(y))))
    options = {"target": float(step_deg), "initial": float(initial_deg), "step_time_s": float(step_time_s)}
    options |= {"tail_s": FINAL_WINDOW_S, "confirm_s": FINAL_WINDOW_S}
    f = step_figures(t, y, band=band, **options)
    error = f.final - float(step_deg)  # always from the record itself: averaging over the tail needs no smoothing
    if check_real(smooth_s, "smooth_s", "step_metrics", low=0.0) > 0 and t.size > 2:
        from scipy.ndimage import uniform_filter1d

        samples = max(1, int(round(smooth_s / float(np.median(np.diff(t))))))  # 0.1 s at 20 ms: 5, not 4.9999
        width = samples if samples % 2 else samples + 1
        f = step_figures(t, uniform_filter1d(y, width, mode="nearest"), band=band, **options)
    if not math.isfinite(f.steady_state_error):  # still moving over the final window (judged as scored)
        error = math.nan
    commands = error / per_command
    return StepMetrics(
        f.rise_time_s,
        f.settling_time_s,
        f.settling_to_final_s,
        f.overshoot_percent,
        error,
        commands,
        abs(commands),
        f.iae,
        f.peak,
        f.peak_time_s,
        f.bounded,
    )


@dataclass
class StepTest:
    """A step test: the loop's result, the true rotation (twin) or the estimate, and the metrics."""

    controller: str
    gain: float
    result: LoopResult
    rotation_deg: np.ndarray
    metrics: StepMetrics
    extra: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return summary(
            self,
            controller=self.controller,
            gain=self.gain,
            status=self.result.status,
            samples=len(self.result.time_s),
            rise_time_s=self.metrics.rise_time_s,
            settling_time_s=self.metrics.settling_time_s,
            overshoot_percent=self.metrics.overshoot_percent,
            final_error_deg=self.metrics.final_error_deg,
        )


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
    guard: RunawayGuard | bool = True,
) -> StepTest:
    """Run a 0 -> ``step_deg`` beam-rotation step on ``rig`` with ``controller`` and measure it.

    The rotation scored is the twin's true tip rotation when the rig has one (``tip_rotation_deg``), else the
    estimate from the gauges. The rig is closed at the end (relaxed to command 8). ``guard``: the loop's runaway
    guard (:func:`~flexdigit.rig.loop.run_loop`); ``False`` lets an unstable design run its course (on the twin
    only: chapter 5's forward-Euler failure is shown that way).
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
        guard=guard,
    )
    result.raise_if_interrupted()  # the step figures of a run cut short are not a step test's
    deg_per_command = float(np.real(design_plant(rig.params).dcgain()))
    metrics = step_metrics(result.time_s, np.array(rotation), step, step_time_s, deg_per_command)
    return StepTest(controller, gain, result, np.array(rotation), metrics)


#: The estimated rotation is averaged over a centred 0.1 s window before its step figures are taken: its noise
#: (~0.2 deg rms on the twin) is half the 2 % band of a 20 deg step (:func:`step_metrics`).
ESTIMATE_SMOOTH_S = 0.1


@dataclass
class StepRun:
    """A closed-loop step from rest held at ``setpoint_deg``: the loop's result and its step figures.

    ``figures`` maps ``"estimated"`` (the gauges' rotation, smoothed over :data:`ESTIMATE_SMOOTH_S`) and, on the
    twin, ``"true"`` (its own tip rotation) to :meth:`StepMetrics.to_dict`; empty below two samples.
    ``true_rotation_deg`` is the twin's tip rotation at each sample (empty on hardware and replays, where
    ``has_truth`` is False).
    """

    result: LoopResult
    figures: dict[str, dict]
    true_rotation_deg: np.ndarray
    has_truth: bool
    deg_per_command: float

    def __repr__(self) -> str:
        return summary(
            self,
            status=self.result.status,
            samples=len(self.result.time_s),
            has_truth=self.has_truth,
            **{f"{k}_{f}": v.get(f) for k, v in self.figures.items() for f in ("rise_time_s", "overshoot_percent")},
        )


def run_step(
    rig: Rig,
    controller: str,
    setpoint_deg: float,
    duration_s: float,
    period_s: float,
    *,
    estimator: RotationEstimator,
    gain: float = 1.0,
    on_sample=None,
    kept=None,
    **loop_options,
) -> StepRun:
    """Hold ``setpoint_deg`` from rest at t = 0 with ``controller`` on ``rig``, and take the step's figures.

    What ``flexdigit run`` runs: the loop (:func:`~flexdigit.rig.loop.run_loop`, runaway guard on) measures the
    rotation by ``estimator``; the figures of the estimate and (twin) of the true rotation go into the closing
    record of the log and the recording, and into :attr:`StepRun.figures`. ``loop_options`` are
    :class:`~flexdigit.rig.loop.LoopSettings` fields (``log_path``, ``recording``, ``header``, ...); the rig is
    closed at the end, relaxed. ``kept``: a kept ``digital20`` design for the rig's digit (:func:`make_controller`).
    """
    check_setpoint(setpoint_deg, rig.params)
    ctl = make_controller(controller, rig, period_s=period_s, estimator=estimator, gain=gain, kept=kept)
    truth = getattr(rig, "tip_rotation_deg", None)  # the twin knows the true rotation; hardware only estimates it
    true_rotation: list[float] = []
    deg_per_command = getattr(estimator, "deg_per_command_", math.nan)
    if not (isinstance(deg_per_command, float) and math.isfinite(deg_per_command) and deg_per_command > 0):
        deg_per_command = _deg_per_command(rig.params)

    def sample(k: int, t: float, y: float, command: int) -> None:
        if truth is not None:
            true_rotation.append(truth())
        if on_sample is not None:
            on_sample(k, t, y, command)

    def summary(time_s, estimated_deg) -> dict:
        figures = {
            "estimated": step_metrics(
                time_s, estimated_deg, setpoint_deg, 0.0, deg_per_command, smooth_s=ESTIMATE_SMOOTH_S
            )
        }
        if truth is not None:
            figures["true"] = step_metrics(
                time_s[: len(true_rotation)], true_rotation, setpoint_deg, 0.0, deg_per_command
            )
        return {name: m.to_dict() for name, m in figures.items()}

    result = run_loop(
        rig, ctl, setpoint_deg, duration_s, period_s, on_sample=sample, measure=estimator, summary=summary,
        truth=truth, **loop_options,
    )  # fmt: skip
    figures = summary(result.time_s, result.measurement) if result.time_s.size >= 2 else {}
    return StepRun(result, figures, np.array(true_rotation, dtype=float), truth is not None, deg_per_command)


def reachable_rotation_deg(params=None) -> tuple[float, float]:
    """The beam rotations the digit's servo reaches, deg, ``(lowest, highest)``, by the cable model (E 3.15 with the
    gearing: ``(command - straight) x deg per command``).

    A single cable pulls one way only (slack below straight): its lowest is 0. An antagonistic pair
    (``[cables] count = 2``) bends both ways, down to the bottom command's rotation.

    Examples
    --------
    >>> [round(deg, 1) for deg in reachable_rotation_deg()]  # the thesis rig: 8..254, straight at 8, 1.735 deg each
    [0.0, 426.8]
    """
    p = params or RigParams()
    a, per_command = p.actuator, tip_rotation_per_command_deg(p)
    top = (a.command_max - a.equilibrium_command) * per_command
    bottom = (a.command_min - a.equilibrium_command) * per_command if p.cables.count == 2 else 0.0
    return float(bottom), float(top)


def check_setpoint(setpoint_deg: float, params=None, *, source=None, name: str = "--setpoint-deg") -> float:
    """``setpoint_deg`` if the digit ``params`` describes (None: the thesis rig) reaches it, else a one-line
    :class:`~flexdigit.errors.ParameterError` naming ``name``, the value and the reachable range (from ``source``,
    the digit's file, when given). Checked before anything moves: a single cable asked for a negative rotation
    otherwise "completed" at 0 deg (trial 3), slack at its lowest command."""
    p = params or RigParams()
    bottom, top = reachable_rotation_deg(p)
    if bottom <= setpoint_deg <= top:
        return setpoint_deg
    a = p.actuator
    where = f" of the digit in {source}" if source is not None else ""
    if p.cables.count == 1 and setpoint_deg < 0:
        raise ParameterError(
            f"{name} {setpoint_deg:g}: the digit{where} has one cable, which bends it one way only: it reaches "
            f"{bottom:.1f} to {top:.1f} deg (a cable pair, [cables] count = 2, bends both ways)"
        )
    raise ParameterError(
        f"{name} {setpoint_deg:g}: the servo{where} reaches {bottom:.1f} to {top:.1f} deg (commands "
        f"{a.command_min}..{a.command_max}, straight at {a.equilibrium_command}, "
        f"{tip_rotation_per_command_deg(p):.3f} deg a command); set [actuator] equilibrium_command nearer the middle"
    )


def _deg_per_command(params) -> float:
    """Beam rotation per servo command of the design model (the cable model's 1.735 deg on the thesis rig)."""
    from flexdigit.control.design20ms import design_plant

    return float(np.real(design_plant(params).dcgain()))


def board_step_test(
    backend: str,
    setpoint_deg: float,
    duration_s: float,
    *,
    seed: int | None = None,
    params=None,
    twin_options: dict | None = None,
    log_path=None,
    log_mode: str = "new",
) -> dict:
    """A step from rest with the loop closed on the board (``flexdigit run --on-board``): the exported controller
    in the image runs it, the host only sends the setpoint and watches the twin's true rotation.

    Parameters
    ----------
    backend : str
        A board that closes the loop: ``hil://IMAGE.elf`` (other schemes are refused, ParameterError).
    setpoint_deg : float
        The beam-rotation step, deg.
    duration_s : float
        How long the host watches, s.
    seed : int, optional
        The twin's seed (default: the URL's or the backend's).
    params : RigParams, optional
        The digit (issue 24; default the thesis rig): the board's image must have been built for it (``make
        firmware PARAMS=D.toml``), and the twin the board meets is that digit's.
    twin_options : dict, optional
        The twin's ``calibration`` and ``orientation`` (as ``flexdigit run --params`` sets them).
    log_path : path-like, optional
        Write the run's log here, as a host run's (:mod:`flexdigit.rig.sample_log`, :func:`board_log_header`):
        every watched period's setpoint, the gauges the board streamed, its command and the twin's true rotation
        (``y`` is null: the board does not stream its rotation estimate).
    log_mode : {"new", "append", "replace"}
        What to do with an existing log (:class:`~flexdigit.rig.sample_log.SampleLog`).

    Returns
    -------
    dict
        ``status`` (``"completed"`` or ``"fault"``), ``message``, ``rig`` (its settings), ``setpoint_deg``,
        ``period_s``, ``samples``, ``true_final_rotation_deg`` (mean of the last :data:`FINAL_WINDOW_S`),
        ``true_peak_rotation_deg``, ``step_metrics`` (``{"true": StepMetrics.to_dict() or None,
        "deg_per_command"}``), ``final_command``, ``board`` (its stats: ``exec_max_cycles``, ``faults``), ``log``
        (its path or None) and ``series`` (``time_s``, ``true_rotation_deg``, ``command``: what ``--plot`` draws).
    """
    if parse_rig_url(backend).scheme != "hil":
        raise ParameterError(
            f"--on-board needs a board that closes the loop: --backend hil://IMAGE.elf. Got {backend!r}."
        )
    check_setpoint(setpoint_deg, params)
    options = {"mode": "board", "setpoint_deg": setpoint_deg} | ({} if seed is None else {"seed": seed})
    with open_rig(backend, params, **options, **(twin_options or {})) as rig:
        settings = rig.settings()
        run, log_path = _watch_board(rig, backend, settings, setpoint_deg, duration_s, log_path, log_mode)
        stats = rig.stats()
    dpc = _deg_per_command(rig.params)
    t, y = run.time_s, run.true_rotation_deg
    metrics = step_metrics(t, y, setpoint_deg, 0.0, dpc) if t.size >= 2 else None
    final = float(y[t >= t[-1] - FINAL_WINDOW_S].mean()) if y.size else math.nan
    est = run.estimate_deg  # the board's own estimate, streamed (NaN from an image that streams none)
    streamed = bool(est.size) and bool(np.all(np.isfinite(est)))
    return {
        "status": run.status,
        "message": run.message,
        "rig": settings,
        "setpoint_deg": setpoint_deg,
        "period_s": run.period_s,
        "samples": int(t.size),
        "true_final_rotation_deg": final,
        # the extreme towards the setpoint (a cable pair's negative step peaks below it)
        "true_peak_rotation_deg": (float(y.min()) if setpoint_deg < 0 else float(y.max())) if y.size else math.nan,
        # as the host loop's estimated_final_rotation_deg: the board's streamed estimate over the final window
        "estimated_final_rotation_deg": float(est[t >= t[-1] - FINAL_WINDOW_S].mean()) if streamed else None,
        "step_metrics": {"true": metrics.to_dict() if metrics else None, "deg_per_command": dpc},
        "final_command": float(run.command[-1]) if run.command.size else None,
        "board": stats,
        "log": None if log_path is None else str(log_path),
        "series": {"time_s": t, "true_rotation_deg": y, "command": run.command, "estimate_deg": run.estimate_deg},
    }


def _watch_board(rig, backend: str, settings: dict, setpoint_deg: float, duration_s: float, log_path, log_mode: str):
    """:func:`board_step_test`'s watch of the board, every period logged when ``log_path`` is given: ``(run, the
    log's path or None)``."""
    # the twin (scipy): cli/run.py reads constants here
    from flexdigit.rig.backends.hil_backend import board_period_s, run_on_board

    if log_path is None:
        return run_on_board(rig, setpoint_deg, duration_s), None
    header = board_log_header(backend, settings, board_period_s(rig), rig.board, setpoint_deg, duration_s)
    log = SampleLog(log_path, header, mode=log_mode)
    with contextlib.ExitStack() as stack:
        stack.callback(log.abandon)  # an error before the footer: the lines written are kept

        def logged(t, reading, true_deg, command, estimate_deg) -> None:
            log.write(board_log_sample(t, setpoint_deg, reading, true_deg, command, estimate_deg))

        run = run_on_board(rig, setpoint_deg, duration_s, on_period=logged)
        stack.pop_all()
    log.write({"stop": run.status, "message": run.message, "safe_command_sent": None, "overruns": 0})
    return run, log.close(complete=run.status == "completed")

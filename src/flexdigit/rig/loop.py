"""The real-time loop: read, compute, command, log, on absolute deadlines (thesis 5.2, figure 5.1).

One sample is ``read -> controller -> write_command -> log``. Sample ``k`` is due at ``t0 + k T`` on the rig's
monotonic clock (virtual time on the twin), never at "last sample + T", so scheduling errors do not accumulate.
A sample that starts more than one period late is an *overrun*: it is counted and the missed deadlines are skipped
(the loop never bursts to catch up, which would hammer the servo board).

Every sample is appended to a JSON-lines log (:mod:`flexdigit.rig.sample_log`: its format, writer and reader) and
flushed to the OS at once, so a crash or Ctrl-C loses nothing already written. The first line is a header with the
period, backend and controller; the last line (when the loop ends normally or by a fault) is a footer with the stop
reason.

On any fault (port lost, sensor NaN or clipped at the ADC rail, Ctrl-C, an exception in the controller) the digit
is sent to the equilibrium command and the port is closed before the loop returns or re-raises.
"""

from __future__ import annotations

import math
import os
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from flexdigit._json import to_jsonable
from flexdigit._repr import fields_summary, summary
from flexdigit._validation import check_positive, check_real
from flexdigit.errors import Interrupted, ParameterError, RigError
from flexdigit.interrupts import signals_deferred, stop_requested
from flexdigit.rig.base import Reading, Rig
from flexdigit.rig.recording import Recording
from flexdigit.rig.safety import RunawayGuard, default_guard

# the log's names, kept importable from here for code written before they had their own module
from flexdigit.rig.sample_log import (  # noqa: F401
    LOG_FORMAT,
    SampleLog,
    check_appendable,
    check_sample,
    read_log,
    read_log_runs,
)

__all__ = [
    "LoopController",
    "TimingStats",
    "LoopResult",
    "LoopSettings",
    "run_loop",
    "check_reading",
    "realtime_priority",
]

#: Shortest and longest sample period the loop takes, s: 0.1 ms is beyond any backend here (the servo board
#: takes a frame every 20 ms, the 1 kHz benchmark is the fastest use), and a shorter one only spins (a loop of
#: 1e-7 s hung); 1 s is the slowest that still controls a digit whose first mode is 1.6 Hz.
MIN_PERIOD_S, MAX_PERIOD_S = 1e-4, 1.0


class LoopController(Protocol):
    """What the loop drives: ``reset(command)`` once, then ``step(setpoint, reading) -> command`` every sample."""

    def reset(self, command: int) -> None: ...

    def step(self, setpoint: float, reading: Reading) -> float: ...


def _finite_or_none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


@dataclass
class TimingStats:
    """Timing of a run, s. ``lateness`` = sample start minus its deadline; ``compute`` = read..log wall time."""

    period_s: float
    samples: int
    overruns: int
    mean_period_s: float
    jitter_p50_s: float
    jitter_p99_s: float
    jitter_max_s: float
    compute_mean_s: float
    compute_p99_s: float
    compute_max_s: float

    @classmethod
    def from_arrays(cls, period_s: float, starts: np.ndarray, lateness: np.ndarray, compute: np.ndarray, overruns: int):
        n = len(starts)
        mean_period = float(np.mean(np.diff(starts))) if n > 1 else math.nan
        late = np.abs(lateness) if n else np.zeros(1)
        comp = compute if n else np.zeros(1)
        return cls(
            period_s,
            n,
            overruns,
            mean_period,
            float(np.percentile(late, 50)),
            float(np.percentile(late, 99)),
            float(np.max(late)),
            float(np.mean(comp)),
            float(np.percentile(comp, 99)),
            float(np.max(comp)),
        )

    __repr__ = fields_summary


@dataclass
class LoopResult:
    """What a run did: the samples, the timing, and why it stopped.

    ``status`` is ``"completed"``, ``"fault"`` (rig or sensor fault; ``message`` says which) or ``"interrupted"``.
    """

    status: str
    message: str
    timing: TimingStats
    time_s: np.ndarray
    setpoint: np.ndarray
    gauges_v: np.ndarray
    measurement: np.ndarray
    command: np.ndarray
    safe_command_sent: bool
    log_path: Path | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.status == "completed"

    def raise_if_interrupted(self) -> None:
        """Raise the stop again when the run was interrupted (the rig is already safe and the log closed): for a
        caller whose work cannot go on without the run (a palpation sweep, the next step of a study).

        Raises :class:`~flexdigit.errors.Interrupted` naming the signal that stopped the run (SIGINT for Ctrl-C).
        """
        if self.status == "interrupted":
            raise Interrupted(getattr(signal, self.extra.get("signal") or "SIGINT"))

    def __repr__(self) -> str:
        return summary(
            self,
            status=self.status,
            message=self.message or None,
            samples=len(self.time_s),
            duration_s=float(self.time_s[-1] - self.time_s[0]) if len(self.time_s) else 0.0,
            period_s=self.timing.period_s,
            overruns=self.timing.overruns,
            safe_command_sent=self.safe_command_sent,
            log_path=self.log_path,
        )


def check_reading(reading: Reading, adc_range_v: tuple[float, float], margin_v: float = 1e-3) -> None:
    """Raise :class:`RigError` when a gauge reads NaN/inf or sits on an ADC rail (clipped), naming the gauge."""
    low, high = adc_range_v
    for i, v in enumerate(reading.gauges_v):
        if not math.isfinite(v):
            raise RigError(f"sensor fault: gauge {i + 1} read {v} at t = {reading.time_s:.3f} s")
        if v >= high - margin_v or v <= low + margin_v:
            raise RigError(
                f"sensor fault: gauge {i + 1} clipped at {v:+.3f} V (ADC range {low:+g}..{high:+g} V) "
                f"at t = {reading.time_s:.3f} s"
            )


@dataclass(frozen=True)
class LoopSettings:
    """How :func:`run_loop` runs, beyond what it drives: the period, the log, the clocks, the checks.

    Every field is also a keyword of :func:`run_loop` (``run_loop(..., log_path="run.jsonl")`` is
    ``run_loop(..., settings=LoopSettings(log_path="run.jsonl"))``); a keyword given beside ``settings`` overrides
    that field.

    Attributes
    ----------
    period_s : float
        Sample period, s (0.020 s: the servo board's rate, 5.2).
    log_path : path-like, optional
        JSON-lines sample log (see the module docstring).
    clock : callable, optional
        Monotonic clock the deadlines are kept on; the rig's clock by default (tests inject a fake).
    timer : callable, optional
        Wall-clock timer for compute time (``time.perf_counter``).
    measure : callable, optional
        ``measure(reading) -> float`` logged as ``y`` (e.g. beam rotation, deg); the controller's
        ``measure`` attribute if it has one.
    on_sample : callable, optional
        ``on_sample(k, t, y, command)`` after each sample (progress display).
    check_sensors : bool
        Stop with a fault when a gauge is NaN or clipped (:func:`check_reading`).
    close_rig : bool
        Close the rig (port) when the loop ends, whatever the reason.
    fsync_every : int
        Samples between two ``fsync`` of the log (each line is flushed to the OS at once).
    header : dict, optional
        Extra entries of the log's first line.
    truth : callable, optional
        ``truth() -> float``: the twin's true tip rotation (deg) after each sample's command, logged as
        ``true_rotation_deg`` beside the estimate ``y`` (hardware has none: leave it None).
    recording : flexdigit.rig.recording.Recording, optional
        An open MCAP recording: every sample goes to it as to the log, and the loop closes it with the stop
        record (so a fault or Ctrl-C still leaves a complete, readable file).
    summary : callable, optional
        ``summary(time_s, measurement) -> dict`` of figures (e.g. the step metrics) written into the closing record
        of the log and the recording under ``"summary"``, whatever the reason the loop stopped.
    stall_s : float
        A sample that starts more than this late (s) is a fault, not an overrun: the rig (a DAQ or stream gone
        silent, a read that blocked) or the computer stopped answering, and the loop has been blind that long.
    guard : RunawayGuard or bool
        Runaway and plausibility checks on every sample (:mod:`flexdigit.rig.safety`); a fault it raises ends
        the run in the safe state like any rig fault. On by default (``True``:
        :func:`~flexdigit.rig.safety.default_guard`, which watches the twin's true rotation, and the measurement
        when it is a rotation estimate); pass a :class:`~flexdigit.rig.safety.RunawayGuard` of your own, or opt
        out with ``False``.
    log_mode : {"new", "append", "replace"}
        An existing ``log_path`` is refused (``"new"``), added to (``"append"``: a log of the same controller,
        period and rig settings) or replaced (``"replace"``, ``--force``); see :class:`SampleLog`.
    """

    period_s: float = 0.020
    log_path: str | os.PathLike | None = None
    clock: Callable[[], float] | None = None
    timer: Callable[[], float] | None = None
    measure: Callable[[Reading], float] | None = None
    on_sample: Callable[[int, float, float, int], None] | None = None
    check_sensors: bool = True
    close_rig: bool = True
    fsync_every: int = 50
    header: dict[str, Any] | None = None
    truth: Callable[[], float] | None = None
    recording: Recording | None = None
    summary: Callable[[np.ndarray, np.ndarray], dict[str, Any]] | None = None
    log_mode: str = "new"
    guard: RunawayGuard | bool = True
    stall_s: float = 0.5


_SETTING_NAMES = frozenset(f.name for f in fields(LoopSettings))


def run_loop(
    rig: Rig,
    controller: LoopController,
    setpoint: float | Callable[[float], float],
    duration_s: float,
    period_s: float | None = None,
    *,
    settings: LoopSettings | None = None,
    **options: Any,
) -> LoopResult:
    """Run ``controller`` on ``rig`` for ``duration_s`` at ``period_s`` on absolute deadlines.

    Parameters
    ----------
    rig : Rig
        Any backend; its :meth:`~Rig.wait` lets time pass (virtual on the twin).
    controller : LoopController
        ``reset(command)`` then ``step(setpoint, reading) -> command`` each sample.
    setpoint : float or callable
        Setpoint (in the controller's unit, e.g. beam rotation deg), or a function of loop time (s).
    duration_s, period_s : float
        Run length and sample period, s (0.020 s: the servo board's rate, 5.2).
    settings : LoopSettings, optional
        The settings below as one object; a keyword given beside it overrides its field.
    **options
        Any field of :class:`LoopSettings` by name (``log_path``, ``clock``, ``guard``, ``recording``, ...): the
        keywords run_loop has always taken; each overrides that field of ``settings``.

    Returns
    -------
    LoopResult
        ``status`` is ``"completed"``, ``"fault"`` or ``"interrupted"``; faults of the rig or the sensors are
        reported there (not raised). Exceptions raised by the controller are re-raised after the safe state.
    """
    s = _settings(settings, period_s, options)
    run = _LoopRun.prepare(rig, controller, setpoint, duration_s, s)
    run.log = _open_log(rig, controller, run, s)
    samples = _Samples()
    status, message = "completed", f"ran {run.n_samples} samples of {run.period * 1000:g} ms"
    pending_error: BaseException | None = None
    stopped_by: str | None = None  # the signal that stopped the run
    try:
        _sample_loop(rig, controller, run, s, samples)
    except BaseException as exc:
        status, message, stopped_by, pending_error = _classify_stop(exc)
    with signals_deferred():  # the safe command and the closing records go out whole, whatever arrives meanwhile
        safe, message = _finish(rig, run.equilibrium, s.close_rig, status, message, samples.ts, samples.ys,
                                stopped_by, samples.overruns, s.summary, s.recording, run.log)  # fmt: skip
    result = samples.result(run.period, status, message, safe, run.log, stopped_by)
    if pending_error is not None:
        raise pending_error
    return result


def _settings(settings: LoopSettings | None, period_s: float | None, options: dict[str, Any]) -> LoopSettings:
    """The run's settings: ``settings`` (or the defaults), with ``period_s`` and the keywords laid over."""
    unknown = sorted(set(options) - _SETTING_NAMES)
    if unknown:
        raise TypeError(f"run_loop() got an unexpected keyword argument {unknown[0]!r}")
    if settings is not None and not isinstance(settings, LoopSettings):
        raise ParameterError(f"The 'settings' parameter of run_loop must be a LoopSettings. Got {settings!r} instead.")
    if period_s is not None:
        options["period_s"] = period_s
    return replace(settings or LoopSettings(), **options)


@dataclass
class _LoopRun:
    """What :func:`run_loop` derives from its arguments before the first sample (checked, defaults filled in)."""

    period: float
    stall: float
    duration: float
    n_samples: int
    clock: Callable[[], float]
    timer: Callable[[], float]
    measure: Callable[[Reading], float]
    target: Callable[[float], float]
    guard: RunawayGuard | None
    adc_range: tuple[float, float]
    equilibrium: int
    command_limits: tuple[float, float]
    log: SampleLog | None = None

    @classmethod
    def prepare(cls, rig: Rig, controller: LoopController, setpoint, duration_s, s: LoopSettings) -> _LoopRun:
        period = check_real(s.period_s, "period_s", "run_loop", low=MIN_PERIOD_S, high=MAX_PERIOD_S)
        stall = check_real(s.stall_s, "stall_s", "run_loop", low=period, low_open=True)
        duration = check_positive(duration_s, "duration_s", "run_loop")
        measure = s.measure or getattr(controller, "measure", None) or (lambda r: math.nan)
        target = setpoint if callable(setpoint) else (lambda t, _s=float(setpoint): _s)
        n_samples = int(math.floor(duration / period + 1e-9))
        if n_samples < 1:
            raise ParameterError(
                f"The 'duration_s' parameter of run_loop must cover at least one period. Got {duration_s}"
            )
        framing = getattr(rig, "framing", None)  # a servo board whose frame allows fewer positions clamps lower
        command_limits = (
            float(rig.params.actuator.command_min),
            float(min(rig.params.actuator.command_max, 254, getattr(framing, "max_position", 254))),
        )
        return cls(
            period, stall, duration, n_samples, s.clock or rig.clock, s.timer or time.perf_counter, measure, target,
            _resolve_guard(s.guard, rig, measure), tuple(rig.params.sensors.adc_range_v),
            int(rig.params.actuator.equilibrium_command), command_limits,
        )  # fmt: skip


def _resolve_guard(guard: RunawayGuard | bool, rig: Rig, measure) -> RunawayGuard | None:
    if guard is True:
        return default_guard(rig, measure)
    if guard is False:
        return None
    if not isinstance(guard, RunawayGuard):
        raise ParameterError(
            f"The 'guard' parameter of run_loop must be a RunawayGuard, True (the default guard) or False (none). "
            f"Got {guard!r} instead."
        )
    return guard


def _open_log(rig: Rig, controller: LoopController, run: _LoopRun, s: LoopSettings) -> SampleLog | None:
    """The sample log, or None without ``log_path``; a log that cannot be opened leaves the rig safe first."""
    if s.log_path is None:
        return None
    meta = {
        "rig": repr(rig),
        "controller": type(controller).__name__,
        "period_s": run.period,
        "duration_s": run.duration,
        "started_unix_s": time.time(),
        **(s.header or {}),
    }
    try:
        return SampleLog(s.log_path, meta, s.fsync_every, mode=s.log_mode)
    except BaseException:
        _safe_state(rig, run.equilibrium, s.close_rig)  # nothing ran, but the caller gave us the rig to leave safe
        raise


@dataclass
class _Samples:
    """The samples kept so far, one list per column, and the overruns counted."""

    starts: list[float] = field(default_factory=list)
    lateness: list[float] = field(default_factory=list)
    compute: list[float] = field(default_factory=list)
    ts: list[float] = field(default_factory=list)
    sps: list[float] = field(default_factory=list)
    gauges: list[Any] = field(default_factory=list)
    ys: list[float] = field(default_factory=list)
    cmds: list[int] = field(default_factory=list)
    overruns: int = 0

    def append(self, now, late, compute_s, t, r, reading: Reading, y, sent) -> None:
        self.compute.append(compute_s)
        self.starts.append(now)
        self.lateness.append(late)
        self.ts.append(t)
        self.sps.append(r)
        self.gauges.append(reading.gauges_v)
        self.ys.append(y)
        self.cmds.append(sent)

    def result(self, period, status, message, safe, log: SampleLog | None, stopped_by) -> LoopResult:
        timing = TimingStats.from_arrays(
            period, np.array(self.starts), np.array(self.lateness), np.array(self.compute), self.overruns
        )
        return LoopResult(
            status,
            message,
            timing,
            np.array(self.ts),
            np.array(self.sps),
            np.array(self.gauges).reshape(len(self.gauges), -1) if self.gauges else np.zeros((0, 3)),  # (n, G)
            np.array(self.ys),
            np.array(self.cmds, dtype=int),
            safe,
            log.path if log is not None else None,
            {"signal": stopped_by} if stopped_by else {},
        )


def _sample_loop(rig: Rig, controller: LoopController, run: _LoopRun, s: LoopSettings, samples: _Samples) -> None:
    """The samples on their deadlines ``t0 + k T``, until the last one or a fault (raised)."""
    start_pacing = getattr(rig, "start_pacing", None)  # a paced backend opened held (start_paced=False): the wall
    if start_pacing is not None:  # clock's from the first sample, what ran before (tare, map) in virtual time
        start_pacing()
    controller.reset(rig.command)
    if run.guard is not None:
        run.guard.reset(rig.command)
    t0 = run.clock()
    k = 0
    while k < run.n_samples:
        k, now, late = _wait_for_sample(rig, run, t0, k, samples)
        if k >= run.n_samples:
            break
        _one_sample(rig, controller, run, s, samples, k, now - t0, now, late)
        k += 1


def _wait_for_sample(rig: Rig, run: _LoopRun, t0: float, k: int, samples: _Samples) -> tuple[int, float, float]:
    """Wait for sample ``k``'s deadline; ``(k, start, lateness)``, ``k`` moved past the deadlines an overrun missed."""
    deadline = t0 + k * run.period
    now = run.clock()
    if now < deadline:
        rig.wait(deadline - now)
        now = run.clock()
    late = now - deadline
    if late > run.stall:
        raise RigError(
            f"the loop stalled: sample {k} started {late:.3f} s late (more than {run.stall:g} s); the rig (a DAQ "
            "or stream gone silent, a read that blocked) or the computer stopped answering"
        )
    if late > run.period:  # missed at least one whole deadline: count it and resynchronise, never burst
        samples.overruns += 1
        k += int(late // run.period)
        late = now - (t0 + k * run.period)
    return k, now, late


def _one_sample(rig, controller, run: _LoopRun, s: LoopSettings, samples: _Samples, k, t, now, late) -> None:
    """Read, check, compute, command, then log and keep the sample (a stop signal waits for its end)."""
    w0 = run.timer()
    reading = rig.read()
    r = float(run.target(t))
    if s.check_sensors:
        check_reading(reading, run.adc_range)
    y = float(run.measure(reading))
    if run.guard is not None:
        run.guard.check_rotation(t, y)
    u = controller.step(r, reading)
    sent = rig.write_command(u)
    # a stop signal waits for the sample's end: the log, the recording and the result keep the same samples
    with signals_deferred():
        if run.log is not None or s.recording is not None:
            record = {
                "k": k,
                "t": round(t, 9),
                "setpoint": r,
                "gauges_v": [_finite_or_none(g) for g in reading.gauges_v],
                "pot_v": _finite_or_none(reading.pot_v),
                "y": _finite_or_none(y),
                "command": sent,
            }
            if run.log is not None:
                # the twin's truth goes to the log only (the recording's schema is the rig's, which has none)
                truth = {} if s.truth is None else {"true_rotation_deg": _finite_or_none(float(s.truth()))}
                run.log.write({**record, **truth})
            if s.recording is not None:
                s.recording.write_sample(record)
        samples.append(now, late, run.timer() - w0, t, r, reading, y, sent)
    if s.on_sample is not None:
        s.on_sample(k, t, y, sent)
    if run.guard is not None:
        run.guard.check_command(t, r, y, float(u), sent, run.command_limits)


def _classify_stop(exc: BaseException) -> tuple[str, str, str | None, BaseException | None]:
    """Why the loop stopped: ``(status, message, signal name, error to re-raise after the safe state)``."""
    # Ctrl-C, or SIGTERM/SIGHUP under flexdigit.interrupts.stop_on_signals (which a compiled twin's kernel may
    # hand back as another exception: asked first)
    stop = exc if isinstance(exc, KeyboardInterrupt) else stop_requested()
    if stop is not None:
        return "interrupted", _interruption(stop), getattr(stop, "signal_name", "SIGINT"), None
    if isinstance(exc, RigError | OSError):
        return "fault", str(exc), None, None
    return "fault", f"{type(exc).__name__}: {exc}", None, exc  # a controller bug: safe state first, then propagate


def _interruption(exc: KeyboardInterrupt) -> str:
    """``"interrupted by SIGTERM"``; a plain KeyboardInterrupt (Python's own Ctrl-C handler) is Ctrl-C."""
    name = getattr(exc, "signal_name", None)
    names = {None: "Ctrl-C", "SIGINT": "SIGINT (Ctrl-C)"}
    return f"interrupted by {names.get(name, name)}"


def _finish(rig, equilibrium, close_rig, status, message, ts, ys, stopped_by, overruns, summary, recording, log):
    """The stop path of :func:`run_loop`: the safe state, then the closing record of the recording and the log
    (naming the stop, and the signal when one stopped the run); ``(safe command sent, message)``."""
    safe = _safe_state(rig, equilibrium, close_rig)
    if status != "completed":
        when = f" at t = {ts[-1]:.3f} s" if ts else " before the first sample"
        if "at t =" in message:
            when = ""
        relaxed = f"digit relaxed to command {equilibrium}" if safe else "could NOT send the safe command (port lost)"
        message = f"{message}{when}; {relaxed}"
    stop: dict[str, Any] = {"stop": status, "message": message, "safe_command_sent": safe, "overruns": overruns}
    if stopped_by:
        stop["signal"] = stopped_by
    if summary is not None and ts:
        stop["summary"] = to_jsonable(summary(np.array(ts), np.array(ys)))  # NaN/inf -> null
    if recording is not None:
        try:  # a full disk (or a vanished drive) must not hide the result
            recording.close(stop)
            message = f"{message}; recording: {recording.path}"
        except OSError as exc:
            message = f"{message}; recording: {recording.path} (not closed: {exc.strerror or exc})"
    if log is not None:
        target = log.target
        try:  # a full disk (or a vanished drive) must not hide the result: the log keeps what it had
            log.write(stop)
            log.close(complete=status == "completed")
            kept = "" if log.path == target else f" (stopped: {target} is kept as it was)"
            message = f"{message}; log: {log.path}{kept}"
        except OSError as exc:
            log.abandon()
            if log.mode == "replace":
                message = f"{message}; log: {target} is kept as it was (this run's log could not be written)"
            else:
                message = f"{message}; log: {target} (its last lines are lost: {exc.strerror or exc})"
    return safe, message


class realtime_priority:
    """Context manager: run the calling process under ``SCHED_FIFO`` (Linux) if allowed, restore it after.

    A real-time loop on a shared machine is preempted by whatever else runs; FIFO priority keeps the scheduler
    from doing that (the loop sleeps most of each period, so it does not starve the machine). Without the
    permission (non-root, no CAP_SYS_NICE, not Linux) it does nothing; :attr:`active` says which.
    """

    def __init__(self, priority: int = 10) -> None:
        self.priority = priority
        self.active = False
        self._previous = None

    def __enter__(self) -> realtime_priority:
        try:
            self._previous = (os.sched_getscheduler(0), os.sched_getparam(0))
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(self.priority))
            self.active = True
        except (AttributeError, OSError):
            self.active = False
        return self

    def __exit__(self, *exc: object) -> None:
        if self.active and self._previous is not None:
            try:
                os.sched_setscheduler(0, self._previous[0], self._previous[1])
            except OSError:
                pass


def _safe_state(rig: Rig, equilibrium: int, close_rig: bool) -> bool:
    """Send the equilibrium command and (optionally) close; True when the safe command went out."""
    sent = False
    try:
        if not rig.closed:
            sent = rig.write_command(equilibrium) == equilibrium
    except (OSError, ValueError):
        sent = False
    if close_rig:
        try:
            rig.close()
        except OSError:
            pass
    return sent

"""``flexdigit run``: a closed-loop run on any backend, with a live progress line (thesis ch. 5).

    flexdigit run --backend sim --controller digital20 --setpoint-deg 30 --duration 3
    flexdigit run --backend "serial:///dev/ttyUSB0?daq=0" --controller digital20 --setpoint-deg 20 --duration 10 \
        --log run.jsonl

The setpoint is a beam-rotation step from rest at t = 0. On the twin the rotation map is calibrated on a separate
twin first; on hardware the operator is asked for the angle at each calibration command (a protractor), or a
saved map is loaded with ``--calibration``. The rotation the loop controls is the gauges' estimate; on the sim
backends the report also gives the twin's true tip rotation (``true_*`` beside ``estimated_*``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from flexdigit._command import CommandResult, add_command


def register(subparsers) -> None:
    parser = add_command(
        subparsers,
        "run",
        _run,
        help="run a controller in closed loop on the twin or the rig (beam-rotation step)",
    )
    parser.add_argument("--backend", default="sim", help="sim, sim+paced, serial://PORT?daq=0, replay://FILE")
    parser.add_argument("--controller", default="digital20", help="digital20, thesis39-euler, thesis39-tustin")
    parser.add_argument("--setpoint-deg", type=float, default=30.0, help="beam rotation to hold, deg (default 30)")
    parser.add_argument("--duration", type=float, default=3.0, help="run length, s (default 3)")
    parser.add_argument("--period", type=float, default=None, help="sample period, s (default the 20 ms serial period)")
    parser.add_argument("--seed", type=int, default=0, help="twin noise seed (sim backends)")
    parser.add_argument("--gain", type=float, default=1.0, help="actuator gain error to emulate (robustness runs)")
    parser.add_argument("--log", type=Path, default=None, help="JSON-lines sample log (survives Ctrl-C)")
    parser.add_argument(
        "--record", type=Path, default=None, help="MCAP recording of every sample (any MCAP tool reads it)"
    )
    parser.add_argument("--force", action="store_true", help="replace an existing --record file")
    parser.add_argument("--calibration", type=Path, default=None, help="saved rotation map (JSON); made if missing")
    parser.add_argument("--no-progress", action="store_true", help="no live progress line")
    parser.add_argument(
        "--realtime", action="store_true", help="run the loop under SCHED_FIFO when permitted (hardware, sim+paced)"
    )


def _run(args: argparse.Namespace) -> CommandResult:
    from flexdigit._validation import check_positive, check_real
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.controllers import CONTROLLERS, make_controller
    from flexdigit.rig.loop import realtime_priority, run_loop
    from flexdigit.rig.rotation import RotationEstimator, calibrate_rotation

    if args.controller not in CONTROLLERS:
        from flexdigit.errors import ParameterError

        raise ParameterError(f"--controller must be one of {', '.join(CONTROLLERS)}. Got {args.controller!r} instead.")
    duration = check_positive(args.duration, "--duration")
    setpoint = check_real(args.setpoint_deg, "--setpoint-deg", low=-60.0, high=120.0)
    sim = args.backend.split("?")[0].split("://")[0] in ("sim", "sim+paced")
    options = {"seed": args.seed} if sim else {}
    rig = open_rig(args.backend, **options)
    try:
        period = check_positive(args.period or rig.params.actuator.serial_period_s, "--period")
        estimator = _estimator(args, rig, sim, RotationEstimator, calibrate_rotation, open_rig)
        controller = make_controller(args.controller, rig, period_s=period, estimator=estimator, gain=args.gain)
    except BaseException:
        rig.close()
        raise
    progress = None if (args.no_progress or args.json or not sys.stderr.isatty()) else _Progress(duration)
    # the twin knows the true beam rotation; the loop (and hardware) only has the gauges' estimate of it
    truth = getattr(rig, "tip_rotation_deg", None)
    true_rotation: list[float] = []

    def on_sample(k: int, t: float, y: float, command: int) -> None:
        if truth is not None:
            true_rotation.append(truth())
        if progress:
            progress.update(k, t, y, command)

    recording = None
    if args.record is not None:
        from flexdigit.rig.recording import Recording, rig_metadata

        try:
            recording = Recording(
                args.record,
                header={"controller": args.controller, "setpoint_deg": setpoint, "backend": args.backend,
                        "period_s": period, "duration_s": duration, "seed": args.seed if sim else None},
                metadata={**rig_metadata(rig), "flexdigit.calibration": {"rotation_map": estimator.to_dict()}},
                force=args.force,
            )  # fmt: skip
        except BaseException:
            rig.close()
            raise
    priority = realtime_priority() if args.realtime else None
    if priority is not None:
        priority.__enter__()
    try:
        result = run_loop(
            rig,
            controller,
            setpoint,
            duration,
            period,
            log_path=args.log,
            on_sample=on_sample,
            measure=estimator,
            header={"controller": args.controller, "setpoint_deg": setpoint, "backend": args.backend},
            recording=recording,
        )
    finally:
        if priority is not None:
            priority.__exit__(None, None, None)
        if progress:
            progress.stop()
    t = result.timing
    final, peak = _final_and_peak(result.time_s, result.measurement)
    true_final, true_peak = _final_and_peak(result.time_s[: len(true_rotation)], true_rotation)
    has_truth = truth is not None
    data = {
        "status": result.status,
        "message": result.message,
        "backend": args.backend,
        "controller": args.controller,
        "setpoint_deg": setpoint,
        "period_s": period,
        "samples": t.samples,
        "overruns": t.overruns,
        "jitter_p50_s": t.jitter_p50_s,
        "jitter_p99_s": t.jitter_p99_s,
        "jitter_max_s": t.jitter_max_s,
        "compute_mean_s": t.compute_mean_s,
        # what the loop measured (the gauges through the rotation map), on every backend
        "estimated_final_rotation_deg": final,
        "estimated_peak_rotation_deg": peak,
        # the twin's own tip rotation (sim backends only; null on hardware and replays)
        "true_final_rotation_deg": true_final if has_truth else None,
        "true_peak_rotation_deg": true_peak if has_truth else None,
        "final_command": int(result.command[-1]) if result.command.size else None,
        "log": str(result.log_path) if result.log_path else None,
        "record": str(recording.path) if recording is not None else None,
    }
    truth_text = f"; true (twin) final {true_final:.2f}, peak {true_peak:.2f} deg" if has_truth else ""
    text = (
        f"{args.controller} on {args.backend}: {result.status} ({result.message})\n"
        f"  rotation estimated from the gauges: final {final:.2f} deg (setpoint {setpoint:g}), peak {peak:.2f} deg"
        f"{truth_text}; last command {data['final_command']}\n"
        f"  timing: {t.samples} samples of {period * 1000:g} ms, {t.overruns} overruns, jitter p99 "
        f"{t.jitter_p99_s * 1000:.3f} ms, compute {t.compute_mean_s * 1e6:.0f} us"
    )
    exit_code = {"completed": 0, "fault": 1, "interrupted": 130}[result.status]
    return CommandResult(data=data, text=text, exit_code=exit_code)


def _final_and_peak(time_s, rotation_deg) -> tuple[float, float]:
    """Mean of the last 0.5 s and maximum of a rotation record (deg); NaN for an empty one."""
    import numpy as np

    t = np.asarray(time_s, dtype=float)
    y = np.asarray(rotation_deg, dtype=float)
    if not y.size:
        return math.nan, math.nan
    return float(y[t >= t[-1] - 0.5].mean()), float(y.max())


def _estimator(args, rig, sim, RotationEstimator, calibrate_rotation, open_rig):
    from flexdigit.rig.rotation import load_rotation_map

    path = args.calibration
    if path is not None and path.exists():
        return load_rotation_map(path)
    if sim:
        est = calibrate_rotation(open_rig(args.backend.split("?")[0], seed=args.seed + 1))
    elif args.backend.startswith("replay") and _recorded_map(rig) is not None:
        est = RotationEstimator.from_dict(_recorded_map(rig), source=rig.path)
    elif args.backend.startswith("replay"):
        from flexdigit.errors import ParameterError

        raise ParameterError("a replay cannot be calibrated (it ignores commands); pass --calibration FILE")
    else:

        def ask(command: int) -> float:
            return float(input(f"Command {command}: beam rotation now, deg? "))

        est = calibrate_rotation(rig, angle_source=ask)
    if path is not None:
        path.write_text(json.dumps(est.to_dict()))
    return est


def _recorded_map(rig) -> dict | None:
    """The rotation map an MCAP recording keeps in its ``flexdigit.calibration`` metadata, if any."""
    from flexdigit.rig.recording import is_mcap, read_metadata

    path = getattr(rig, "path", None)
    if path is None or not is_mcap(path):
        return None
    found = read_metadata(path).get("flexdigit.calibration", {}).get("rotation_map")
    return found if isinstance(found, dict) else None


class _Progress:
    """A one-line live display (rich): time, rotation, command."""

    def __init__(self, duration_s: float) -> None:
        from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

        self._p = Progress(
            TextColumn("[bold]run"),
            BarColumn(),
            TextColumn("{task.description}"),
            TimeRemainingColumn(),
            transient=True,
        )
        self._task = self._p.add_task("", total=duration_s)
        self._p.start()

    def update(self, k: int, t: float, y: float, command: int) -> None:
        if k % 5 == 0:
            self._p.update(
                self._task, completed=t, description=f"t {t:6.2f} s  rotation {y:6.2f} deg  command {command:3d}"
            )

    def stop(self) -> None:
        self._p.stop()

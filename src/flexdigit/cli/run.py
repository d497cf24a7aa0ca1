"""``flexdigit run``: a closed-loop run on any backend, with a live progress line (thesis ch. 5).

    flexdigit run --backend sim --controller digital20 --setpoint-deg 30 --duration 3
    flexdigit run --params mine.toml --setpoint-deg -30          # your digit's twin (a cable pair bends both ways)
    flexdigit run --backend "serial:///dev/ttyUSB0?daq=0" --controller digital20 --setpoint-deg 20 --duration 10 \
        --log run.jsonl

The setpoint is a beam-rotation step from rest at t = 0. On the twin the rotation map is calibrated on a separate
twin first; on hardware the operator is asked for the angle at each calibration command (a protractor), or a
saved map is loaded with ``--rotation-map``. The rotation the loop controls is the gauges' estimate; on the sim
backends the report also gives the twin's true tip rotation (``true_*`` beside ``estimated_*``).

``--params FILE`` describes the digit (``flexdigit params``): the twin is built from it (with ``--calibration``,
or the thesis's calibration scaled to it, :func:`flexdigit.twin.digit_calibration.calibration_for`), the map is
swept over its range (:func:`flexdigit.rig.rotation.sweep_commands`) and the controller designed for it. With an
antagonistic pair (``[cables] count = 2``) one servo drives both cables, wound opposite ways on its pulley: the one
serial command per sample moves both (the log's header says so), and setpoints of both signs are held.

``--controller FILE.json`` runs a kept 20 ms design (``flexdigit design 20ms --params D.toml --out FILE.json``,
:mod:`flexdigit.control.kept_design`) instead of searching the digit's weights again: refused in one line if it is
another digit's (before the rig moves), or another calibration's, mount's or period's (before the loop starts).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from pathlib import Path

from flexdigit._command import CommandResult, add_command, digit_name
from flexdigit._plot import add_plot_flag
from flexdigit._validation import SEED, Flag, Plausible
from flexdigit.rig.step_test import ESTIMATE_SMOOTH_S

#: Longest run ``flexdigit run`` takes, s (a day; a longer one is a typo, and would not end on the twin).
MAX_DURATION_S = 86_400.0
#: Backends that follow the wall clock (a paced twin, the emulated board): opened held, paced from the loop's start.
PACED_SCHEMES = ("sim+paced", "hil")
#: The run's flags, declared once (flexdigit._validation.Flag: refused by argparse, one line naming the flag).
DURATION = Plausible("s", 0.0, MAX_DURATION_S, "a run of at most a day", closed="right")
SETPOINT = Plausible("deg", -60.0, 120.0, "a beam rotation the digit reaches: 30 deg per section, 3 sections")


def register(subparsers) -> None:
    from flexdigit.rig.controllers import ACTUATOR_GAIN

    parser = add_command(
        subparsers,
        "run",
        _run,
        help="run a controller in closed loop on the twin or the rig (beam-rotation step)",
    )
    from flexdigit.cli._formats import epilog

    parser.epilog = epilog("kept_design")
    parser.add_argument("--backend", default="sim", help="sim, sim+paced, serial://PORT?daq=0, replay://FILE")
    parser.add_argument(
        "--controller",
        default="digital20",
        help="digital20, thesis39-euler, thesis39-tustin, or a kept digital20 design FILE.json (flexdigit design 20ms "
        "--params D.toml --out FILE.json: its weights are not searched again)",
    )
    parser.add_argument(
        "--setpoint-deg", type=Flag(SETPOINT), default=30.0, help="beam rotation to hold, deg (default 30)"
    )
    parser.add_argument("--duration", type=Flag(DURATION), default=3.0, help="run length, s (default 3)")
    parser.add_argument(
        "--period",
        type=Flag(Plausible("s", 1e-4, 1.0, "the loop's period: below 0.1 ms it only spins (rig.loop)")),
        default=None,
        help="sample period, s (default the 20 ms serial period)",
    )
    parser.add_argument(
        "--seed", type=Flag(SEED), default=None, help="twin noise seed (sim backends; default 0, or the URL's seed=)"
    )
    parser.add_argument(
        "--gain", type=Flag(ACTUATOR_GAIN), default=1.0, help="actuator gain error to emulate (robustness runs)"
    )
    parser.add_argument("--log", type=Path, default=None, help="JSON-lines sample log (survives Ctrl-C)")
    parser.add_argument(
        "--params", type=Path, default=None, metavar="FILE", help="the digit's parameters TOML (default: thesis rig)"
    )
    parser.add_argument(
        "--orientation",
        choices=("vertical", "hanging", "horizontal"),
        default=None,
        help="the twin's mount (sim backends; default tip up, or hanging for a --params digit that buckles tip up)",
    )
    _add_map_flags(parser)
    parser.add_argument(
        "--calibration",
        type=Path,
        default=None,
        help="twin calibration TOML for the sim backends (flexdigit calibrate)",
    )
    parser.add_argument(
        "--record", type=Path, default=None, help="MCAP recording of every sample (any MCAP tool reads it)"
    )
    writes = parser.add_mutually_exclusive_group()
    writes.add_argument(
        "--append", action="store_true", help="add this run to an existing --log (same controller, period and rig)"
    )
    writes.add_argument(
        "--force",
        action="store_true",
        help="replace an existing --log, --record or --plot file, or --rotation-map when making one",
    )
    add_plot_flag(parser, "the setpoint, the estimated and (twin) true rotation and the command over time")
    parser.add_argument("--no-progress", action="store_true", help="no live progress line")
    parser.add_argument(
        "--realtime", action="store_true", help="run the loop under SCHED_FIFO when permitted (hardware, sim+paced)"
    )
    parser.add_argument(
        "--on-board",
        action="store_true",
        help="close the loop on the board (hil://IMAGE.elf): the host sends the setpoint and watches; --log and "
        "--plot keep what it watched (the board's gauges and command, the twin's true rotation)",
    )

    _add_stream_emulator(subparsers)


def _add_map_flags(parser) -> None:
    """The rotation map's flags: where it is kept and what it is made from."""
    from flexdigit.rig.rotation_reference import READING_RESOLUTION_DEG, READING_RESOLUTION_MM

    parser.add_argument(
        "--rotation-map",
        type=Path,
        default=None,
        help="gauge -> rotation map (JSON): loaded if it exists, else made and saved",
    )
    parser.add_argument(
        "--map-from",
        default=None,
        metavar="twin|operator|FILE",
        help="make the rotation map from: the (calibrated) twin's own rotation (default on sim), the operator at each "
        "command (default on hardware), or a CSV of rotations or deflections measured on the rig",
    )
    parser.add_argument(
        "--resolution-mm",
        type=Flag(READING_RESOLUTION_MM),
        default=0.5,
        help="reading resolution of measured deflections, mm (0.5)",
    )
    parser.add_argument(
        "--resolution-deg",
        type=Flag(READING_RESOLUTION_DEG),
        default=1.0,
        help="reading resolution of measured rotations, deg (1)",
    )


def _add_stream_emulator(subparsers) -> None:
    """``flexdigit stream-emulator``: stream:// without hardware."""
    from flexdigit.rig.backends.stream_emulator import DURATION_S, RATE_HZ

    emulator = add_command(
        subparsers,
        "stream-emulator",
        _stream_emulator,
        help="try stream:// without hardware: the gauge stream's firmware (and a servo board) on pseudo-terminals",
    )
    emulator.add_argument("--twin", action="store_true", help="stream a twin's gauges and serve a servo board for it")
    emulator.add_argument(
        "--params",
        type=Path,
        default=None,
        metavar="FILE",
        help="the digit's parameters TOML: its G gauges on the wire (protocol 2) and its twin (default: thesis rig)",
    )
    emulator.add_argument(
        "--calibration",
        type=Path,
        default=None,
        metavar="FILE",
        help="the twin's calibration TOML (with --twin; default the thesis's scaled to the digit)",
    )
    emulator.add_argument("--rate", type=Flag(RATE_HZ), default=100.0, help="lines per second (100, the firmware's)")
    emulator.add_argument("--seed", type=Flag(SEED), default=0, help="twin and noise seed")
    emulator.add_argument(
        "--duration", type=Flag(DURATION_S), default=None, help="stop after this many seconds (default Ctrl-C)"
    )


def _stream_emulator(args: argparse.Namespace) -> CommandResult:
    from flexdigit.rig.backends.stream_emulator import run_emulator

    said: list[str] = []

    def say(line: str) -> None:
        said.append(line)
        if not args.json:
            print(line, flush=True)

    run_emulator(
        args.twin, args.rate, args.seed, args.duration, say, params_path=args.params, calibration_path=args.calibration
    )
    return CommandResult(data={"lines": said}, text="")


def _run(args: argparse.Namespace) -> CommandResult:
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.loop import realtime_priority
    from flexdigit.rig.step_test import run_step

    if args.on_board:
        return _run_on_board(args)
    duration, setpoint, sim, rig_options = _checked(args)
    with contextlib.ExitStack() as stack:
        # closed on the way out, whatever happens
        rig = stack.enter_context(open_rig(args.backend, args.digit, **rig_options))
        settings = rig.settings()  # what was used (the URL's seed, or --seed, or the default): logged and reported
        period, estimator = _period_and_map(args, rig, sim, settings)
        recording = _recording(args, rig, stack, setpoint, period, duration, settings, estimator)
        progress = None if (args.no_progress or args.json or not sys.stderr.isatty()) else _Progress(duration)
        if args.realtime:
            stack.enter_context(realtime_priority())
        header = {
            "controller": args.controller, "setpoint_deg": setpoint, "backend": args.backend,
            "cables": _cables(rig.params),
        }  # fmt: skip
        if args.kept is not None:
            header["controller_file"] = args.kept.source
        with _design_warnings() as design_warnings:
            run = run_step(
                rig, args.controller, setpoint, duration, period, estimator=estimator, gain=args.gain,
                on_sample=progress.update if progress else None, log_path=args.log, log_mode=_log_mode(args),
                header={**header, "rig_settings": settings}, recording=recording, kept=args.kept,
            )  # fmt: skip
    if progress:
        progress.stop(_figures_line(run.figures))
    data = _run_data(args, run, rig, settings, setpoint, period, estimator, recording)
    data["design_warnings"] = design_warnings
    if args.plot:
        from flexdigit._plot import save_plot
        from flexdigit.rig.run_plot import run_figure

        data["plot"] = str(save_plot(run_figure(run, _plot_title(args, setpoint)), args.plot, "run", force=args.force))
    # a stop by a signal exits as the shell expects of it: 128 + its number (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP)
    exit_code = {"completed": 0, "fault": 1, "interrupted": _signal_exit_code(data["signal"])}[run.result.status]
    return CommandResult(data=data, text=_run_text(args, run, data, setpoint, period), exit_code=exit_code)


def _design_warnings():
    """What the controller's design says it misses (:class:`~flexdigit.errors.DesignWarning`), collected into the
    list it yields and said on stderr, one line each, before the run's report; any other warning goes on as it came."""
    from flexdigit._command import said_warnings
    from flexdigit.errors import DesignWarning

    return said_warnings("run", DesignWarning)


def _plot_title(args, setpoint: float) -> str:
    """``digital20 on sim, step to 30 deg``, after whose digit it is when ``--params`` names one."""
    title = f"{args.controller} on {args.backend}, step to {setpoint:g} deg"
    return title if args.params is None else f"digit {digit_name(args.params)}: {title}"


def _digit_fields(args, rig) -> dict:
    """``run --json``'s digit: the ``--params`` file and how the serial command drives its cable(s)."""
    return {"params": None if args.params is None else str(args.params), "cables": _cables(rig.params)}


def _cables(params) -> dict:
    """How the digit is pulled, for the log and ``--json``: one cable, or a pair on one servo command."""
    c = params.cables
    if c.count == 1:
        return {"count": 1, "command": "one serial command per sample pulls the cable (slack below straight)"}
    return {
        "count": 2,
        "pretension_n": c.pretension_n,
        "straight_command": params.actuator.equilibrium_command,
        "command": "one serial command per sample drives both cables: one servo, the pair wound opposite ways on "
        "its pulley (above the straight command the first cable pulls, below it the second)",
    }


def _log_mode(args) -> str:
    return "append" if args.append else "replace" if args.force else "new"


def _checked(args) -> tuple[float, float, bool, dict]:
    """The run's flags checked before the rig moves: ``(duration, setpoint, sim, the rig's options)``."""
    from flexdigit._io import check_output
    from flexdigit._validation import check_real
    from flexdigit.errors import ParameterError
    from flexdigit.rig.base import parse_rig_url, seed_option
    from flexdigit.rig.controllers import CONTROLLERS
    from flexdigit.rig.step_test import check_setpoint

    args.kept = None
    if args.controller not in CONTROLLERS and not _is_design_file(args.controller):
        raise ParameterError(
            f"--controller must be one of {', '.join(CONTROLLERS)}, or a kept design FILE.json (flexdigit design 20ms "
            f"--out FILE.json). Got {args.controller!r} instead."
        )
    duration = check_real(args.duration, "--duration", low=0, low_open=True, high=MAX_DURATION_S)
    setpoint = check_real(args.setpoint_deg, "--setpoint-deg", low=-60.0, high=120.0)
    args.digit = _digit(args)
    if args.controller not in CONTROLLERS:
        args.kept = _kept_design(args.controller, args.digit)
        args.controller = "digital20"
    check_setpoint(setpoint, args.digit, source=args.params)
    from flexdigit._plot import check_plot

    check_plot(args.plot, "run", force=args.force)  # before the rig moves, not after
    if args.log is not None and not (args.append and args.log.exists()):  # before the rig moves, not after
        check_output(args.log, force=args.force, hint="or --append to add this run to it")
    scheme = parse_rig_url(args.backend).scheme
    sim = scheme in ("sim", "sim+paced")
    twin_options = _twin_options(args, sim)
    if args.rotation_map is not None and (args.map_from is not None or not args.rotation_map.exists()):
        check_output(args.rotation_map, force=args.force)  # before the sweep, not after it
    # --seed reaches a hardware rig only to be refused (it has no noise); with --map-from twin it seeds the map's twin
    rig_options = twin_options if sim else ({} if args.map_from == "twin" else seed_option(args.backend, args.seed))
    if scheme in PACED_SCHEMES:  # held in virtual time until the loop starts (run_loop): the map, the design and
        rig_options["start_paced"] = False  # the tare cost no simulated seconds caught up at the first sample
    return duration, setpoint, sim, rig_options


def _is_design_file(controller: str) -> bool:
    """A ``--controller`` that names a kept design rather than a controller: a .json file name, or a file."""
    return controller.endswith(".json") or Path(controller).is_file()


def _kept_design(path: str, params):
    """The kept design ``--controller`` names, refused in one line if it is not ``params``'s digit's."""
    from flexdigit.control.kept_design import read_kept_design

    kept = read_kept_design(path)
    kept.check_digit(params)
    return kept


def _digit(args):
    """The digit ``--params`` describes (None: the thesis rig)."""
    if args.params is None:
        return None
    from flexdigit.params import load_params

    return load_params(args.params)


def _period_and_map(args, rig, sim: bool, settings: dict):
    """The sample period (the rig's serial period by default) and the rotation map; an --append log checked."""
    from flexdigit._validation import check_real
    from flexdigit.rig.loop import MAX_PERIOD_S, MIN_PERIOD_S
    from flexdigit.rig.sample_log import check_appendable

    # 0 is a value (refused), not "not given"; below 0.1 ms the loop would only spin (--period 1e-7 hung)
    period = rig.params.actuator.serial_period_s if args.period is None else args.period
    period = check_real(period, "--period", low=MIN_PERIOD_S, high=MAX_PERIOD_S)
    if args.log is not None and args.append and args.log.exists():
        check_appendable(args.log, {"controller": args.controller, "period_s": period, "rig_settings": settings})
    return period, _rotation_map(args, rig, sim)


def _recording(args, rig, stack, setpoint, period, duration, settings, estimator):
    """The ``--record`` MCAP recording, open on ``stack`` (the loop closes it with its stop record), or None."""
    if args.record is None:
        return None
    from flexdigit.rig.recording import Recording, rig_metadata

    return stack.enter_context(
        Recording(
            args.record,
            header={"controller": args.controller, "setpoint_deg": setpoint, "backend": args.backend,
                    "period_s": period, "duration_s": duration, "seed": settings.get("seed")},
            metadata={**rig_metadata(rig), "flexdigit.calibration": {"rotation_map": estimator.to_dict()}},
            force=args.force,
        )
    )  # fmt: skip


def _run_data(args, run, rig, settings, setpoint, period, estimator, recording) -> dict:
    """``run --json``: the run's status, timing, rotations, step figures, map and files."""
    result, figures, t = run.result, run.figures, run.result.timing
    final, peak = _final_and_peak(result.time_s, result.measurement)
    true_final, true_peak = _final_and_peak(result.time_s[: len(run.true_rotation_deg)], run.true_rotation_deg)
    return {
        "status": result.status,
        "message": result.message,
        "loop": "host",  # where the loop closed: here (the board closes it with --on-board)
        "backend": args.backend,
        "rig": settings,
        "controller": args.controller,
        "controller_file": args.kept.source if args.kept is not None else None,  # a kept design: no weights search
        "setpoint_deg": setpoint,
        "period_s": period,
        **_digit_fields(args, rig),
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
        "true_final_rotation_deg": true_final if run.has_truth else None,
        "true_peak_rotation_deg": true_peak if run.has_truth else None,
        # rise, 2 % settling, overshoot, steady-state error (deg, commands), IAE of the step to the setpoint, from
        # the estimated rotation and, on the twin, the true one (null where there is none)
        "step_metrics": {
            "estimated": figures["estimated"] if figures else None,
            "true": figures.get("true"),
            "deg_per_command": run.deg_per_command,
            "settling_band": 0.02,
            "estimate_smoothed_s": ESTIMATE_SMOOTH_S,
        },
        # which map turned the gauges into the rotation the loop held, and how far to trust it
        "rotation_map": _map_summary(estimator, args.rotation_map, setpoint),
        "gauge_source": _source_stats(rig),  # a gauge stream's counts (stream://, daq=): valid, dropped, garbled
        "final_command": int(result.command[-1]) if result.command.size else None,
        "log": str(result.log_path) if result.log_path else None,
        "record": str(recording.path) if recording is not None else None,
        "signal": result.extra.get("signal"),  # the signal that stopped the run (SIGTERM, SIGHUP, SIGINT), or null
    }


def _run_text(args, run, data: dict, setpoint: float, period: float) -> str:
    t = run.result.timing
    final, peak = data["estimated_final_rotation_deg"], data["estimated_peak_rotation_deg"]
    true_final, true_peak = data["true_final_rotation_deg"], data["true_peak_rotation_deg"]
    truth_text = f"; true (twin) final {true_final:.2f}, peak {true_peak:.2f} deg" if run.has_truth else ""
    mount = data["rig"].get("orientation") if isinstance(data.get("rig"), dict) else None
    if mount is not None and mount != "vertical" and args.params is not None:
        truth_text += f" (the twin {mount}: tip up this digit buckles under its own weight, or as the URL asked)"
    kept = f" (kept in {args.kept.source})" if args.kept is not None else ""
    digit = f", digit {digit_name(args.params)} ({args.params})" if args.params is not None else ""
    return (
        f"{args.controller}{kept} on {args.backend}{digit}: {run.result.status} ({run.result.message})\n"
        f"  rotation estimated from the gauges: final {final:.2f} deg (setpoint {setpoint:g}), peak {peak:.2f} deg"
        f"{truth_text}; last command {data['final_command']}\n"
        f"  step: {_figures_line(run.figures)}\n"
        f"  rotation map: {data['rotation_map']['source']}; uncertainty {data['rotation_map']['uncertainty_deg']:.2f} "
        f"deg at {setpoint:g} deg\n"
        f"  timing: {t.samples} samples of {period * 1000:g} ms, {t.overruns} overruns, jitter p99 "
        f"{t.jitter_p99_s * 1000:.3f} ms, compute {t.compute_mean_s * 1e6:.0f} us"
        + (f"\n  plot -> {data['plot']}" if data.get("plot") else "")
    )


def _signal_exit_code(name: str | None) -> int:
    import signal

    return 128 + int(getattr(signal, name or "SIGINT"))


def _run_on_board(args: argparse.Namespace) -> CommandResult:
    """``flexdigit run --on-board``: the loop closes on the board (the exported controller in its image)."""
    from flexdigit.rig.step_test import board_step_test

    duration, setpoint = _on_board_checked(args)
    twin = (
        _twin_options(args, True)
        if any(v is not None for v in (args.params, args.calibration, args.orientation))
        else {}
    )
    twin.pop("seed", None)
    run = board_step_test(
        args.backend, setpoint, duration, seed=args.seed, params=args.digit, twin_options=twin, log_path=args.log,
        log_mode=_log_mode(args),
    )  # fmt: skip
    series = run.pop("series")
    data = {"status": run["status"], "message": run["message"], "loop": "board", "backend": args.backend,
            "params": None if args.params is None else str(args.params), **run}  # fmt: skip
    if args.plot:
        from flexdigit._plot import save_plot
        from flexdigit.rig.run_plot import board_run_figure

        title = f"loop on the board ({args.backend}), step to {setpoint:g} deg"
        figure = board_run_figure({**run, "series": series}, title)
        data["plot"] = str(save_plot(figure, args.plot, "run", force=args.force))
    metrics, stats = run["step_metrics"]["true"], run["board"]
    text = (
        f"loop on the board ({args.backend}): {run['status']} ({run['message']})\n"
        f"  true (twin) rotation: final {run['true_final_rotation_deg']:.2f} deg (setpoint {setpoint:g}), peak "
        f"{run['true_peak_rotation_deg']:.2f} deg"
        + (
            f"; the board's estimate: final {run['estimated_final_rotation_deg']:.2f} deg\n"
            if run["estimated_final_rotation_deg"] is not None
            else "\n"
        )
        + f"  step: {_figures_line({'true': metrics}) if metrics else 'too few samples'}\n"
        f"  board: {run['samples']} periods of {run['period_s'] * 1000:g} ms, update <= {stats['exec_max_cycles']} "
        f"cycles ({stats['exec_max_cycles'] / 16:.0f} us at 16 MHz), faults {stats['faults'] or 'none'}"
        + (f"\n  log -> {data['log']}" if data["log"] else "")
        + (f"\n  plot -> {data['plot']}" if data.get("plot") else "")
    )
    return CommandResult(data=data, text=text, exit_code={"completed": 0, "fault": 1}[run["status"]])


def _on_board_checked(args) -> tuple[float, float]:
    """``run --on-board``'s flags checked before the board starts: ``(duration, setpoint)``; what cannot apply to
    a loop on the board refused with why."""
    from flexdigit._io import check_output
    from flexdigit._plot import check_plot
    from flexdigit._validation import check_real
    from flexdigit.errors import ParameterError
    from flexdigit.rig.step_test import check_setpoint

    if _is_design_file(args.controller):
        raise ParameterError(
            f"--controller {args.controller} is not supported with --on-board: the board runs the controller exported "
            "into its image (make firmware)"
        )
    if args.rotation_map is not None:
        raise ParameterError("--rotation-map is not supported with --on-board: the board holds its map (in its image)")
    if args.record is not None:
        raise ParameterError("--record is not written for a loop on the board yet: --log keeps its every period")
    duration = check_real(args.duration, "--duration", low=0, low_open=True, high=MAX_DURATION_S)
    setpoint = check_real(args.setpoint_deg, "--setpoint-deg", low=-60.0, high=120.0)
    # --params: the digit the board's image was built for (make firmware PARAMS=...; the board's banner is checked
    # against it) and the twin it meets, calibrated and mounted as run --params's twin (--calibration for its twin)
    args.digit = _digit(args)
    check_setpoint(setpoint, args.digit, source=args.params)
    check_plot(args.plot, "run", force=args.force)  # before the board starts, not after
    if args.log is not None and not (args.append and args.log.exists()):
        check_output(args.log, force=args.force, hint="or --append to add this run to it")
    return duration, setpoint


def _deg_per_command(params) -> float:
    """Beam rotation per servo command of the design model (the cable model's 1.735 deg on the thesis rig)."""
    from flexdigit.rig.step_test import _deg_per_command

    return _deg_per_command(params)


def _figures_line(figures: dict) -> str:
    """The step figures on one line: the estimated rotation's, and the twin's true ones where there are any."""
    if not figures:
        return "too few samples for step figures"

    def seconds(value: float, none: str) -> str:
        return f"{value:.2f} s" if math.isfinite(value) else none

    def one(m: dict) -> str:
        error = m["final_error_deg"]
        steady = (
            f"steady-state error {error:+.2f} deg ({m['final_error_commands']:+.2f} commands)"
            if math.isfinite(error)
            else "no steady state in the record"
        )
        return (
            f"rise {seconds(m['rise_time_s'], 'not reached')}, settling (2 %) "
            f"{seconds(m['settling_time_s'], 'not settled')} ({seconds(m['settling_to_final_s'], 'still moving')} "
            f"to its final value), overshoot {m['overshoot_percent']:.1f} %, {steady}, IAE {m['iae_deg_s']:.2f} deg s"
        )

    parts = [f"{name} {one(figures[name])}" for name in ("estimated", "true") if name in figures]
    return "; ".join(parts)


def _twin_options(args, sim: bool) -> dict:
    """Keyword options for a twin: ``--seed`` (when given) and, with ``--calibration``, the twin calibration."""
    if not sim and args.map_from != "twin":
        if args.calibration is not None:
            from flexdigit.errors import ParameterError

            raise ParameterError(
                f"--calibration {args.calibration} is a twin calibration: it applies to the sim backends (or to "
                f"--map-from twin), not --backend {args.backend}; a saved rotation map is --rotation-map FILE"
            )
        if args.orientation is not None:
            from flexdigit.errors import ParameterError

            raise ParameterError(f"--orientation is the twin's mount: the sim backends only, not {args.backend}")
        return {}
    options = {} if args.seed is None else {"seed": args.seed}
    if args.calibration is not None:
        from flexdigit.twin.calibration import load_calibration

        options["calibration"] = load_calibration(args.calibration)
    elif getattr(args, "digit", None) is not None:
        from flexdigit.twin.digit_calibration import twin_calibration

        options["calibration"] = twin_calibration(args.digit)
    if getattr(args, "orientation", None) is not None:
        options["orientation"] = args.orientation
    elif getattr(args, "digit", None) is not None and "orientation" not in _url_options(args.backend):
        from flexdigit.control.design20ms import digit_mount

        # tip up a digit may buckle under its supports' weight: its twin then hangs (said in the output)
        if digit_mount(args.digit, options.get("calibration")) == "hanging":
            options["orientation"] = "hanging"
    return options


def _url_options(backend: str) -> dict:
    from flexdigit.rig.base import rig_url_options

    return rig_url_options(backend)[1]


def _final_and_peak(time_s, rotation_deg) -> tuple[float, float]:
    """Mean of the last 0.5 s and maximum of a rotation record (deg); NaN for an empty one."""
    import numpy as np

    t = np.asarray(time_s, dtype=float)
    y = np.asarray(rotation_deg, dtype=float)
    if not y.size:
        return math.nan, math.nan
    return float(y[t >= t[-1] - 0.5].mean()), float(y.max())


def _rotation_map(args, rig, sim: bool):
    """The gauge -> rotation map: loaded from ``--rotation-map``, or made (``--map-from``) and saved there."""
    from flexdigit.rig.base import parse_rig_url, rig_url_options
    from flexdigit.rig.rotation import RotationEstimator, load_rotation_map, make_rotation_map, save_rotation_map

    path, source = args.rotation_map, args.map_from
    if path is not None and path.exists() and source is None:
        return load_rotation_map(path)
    replay = parse_rig_url(args.backend).scheme == "replay"
    if replay and source is None and _recorded_map(rig) is not None:
        return RotationEstimator.from_dict(_recorded_map(rig), source=rig.path)  # the map the recording was run with
    source = source or ("twin" if sim else "operator")
    options = {}
    if source == "twin":
        # the twin (calibrated to the rig with --calibration): a separate one, read at its own tip rotation, set up
        # as the URL says when the rig is the twin, with the next seed
        options = _twin_options(args, True)
        if sim:
            url_options = {k: v for k, v in rig_url_options(args.backend)[1].items() if k != "spin_s"}
            options = {**url_options, **options, "seed": rig.settings()["seed"] + 1}
        else:
            options["seed"] = options.get("seed", 0) + 1
    est = make_rotation_map(
        rig,
        source,
        twin_options=options,
        ask=_ask_operator,
        resolution_mm=args.resolution_mm,
        resolution_deg=args.resolution_deg,
        replay=replay,
    )
    if path is not None:
        save_rotation_map(est, path, force=args.force)
    return est


def _ask_operator(command: int) -> float:
    """The operator's protractor reading at ``command`` (``--map-from operator``), asked on stderr (stdout carries
    the result); no one to ask, or no number, is one line, not a traceback."""
    from flexdigit.errors import ParameterError, RigError

    print(f"Command {command}, digit at rest: tip rotation now, deg? ", end="", file=sys.stderr, flush=True)
    text = sys.stdin.readline() if sys.stdin else ""
    if not text:
        raise RigError(
            f"no operator to read the tip rotation at command {command}: stdin is closed; run it from a terminal, or "
            "give --rotation-map FILE or --map-from twin"
        )
    try:
        return float(text)
    except ValueError:
        raise ParameterError(
            f"The tip rotation at command {command} must be a number of degrees. Got {text.strip()!r} instead."
        ) from None


def _map_summary(estimator, path, setpoint: float) -> dict:
    """What ``run --json`` says about the map: where it came from and its uncertainty at the setpoint."""
    has_data = hasattr(estimator, "rotation_deg_")
    return {
        "source": getattr(estimator, "source_", "given"),
        "file": str(path) if path is not None else None,
        "commands": getattr(estimator, "commands_", None),
        "settle_time_s": getattr(estimator, "settle_time_s_", None),
        "residual_deg": getattr(estimator, "residual_deg_", None),
        "uncertainty_deg": estimator.uncertainty_deg(setpoint) if has_data else math.nan,
        "deg_per_command": getattr(estimator, "deg_per_command_", None),
        "coef_deg_per_v": estimator.coef_.tolist(),
    }


def _source_stats(rig) -> dict | None:
    """Counts of a gauge stream (the rig's own, or its servo board's ``daq=``), if it has one."""
    for part in (rig, *getattr(rig, "companions", [])):
        stats = getattr(part, "stats", None)
        if callable(stats):
            return stats()
    return None


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
        from rich.console import Console
        from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

        self._p = Progress(
            TextColumn("[bold]run"),
            BarColumn(),
            TextColumn("{task.description}"),
            TimeRemainingColumn(),
            transient=True,
            console=Console(stderr=True),  # stdout carries the result only
        )
        self._task = self._p.add_task("", total=duration_s)
        self._p.start()

    def update(self, k: int, t: float, y: float, command: int) -> None:
        if k % 5 == 0:
            self._p.update(
                self._task, completed=t, description=f"t {t:6.2f} s  rotation {y:6.2f} deg  command {command:3d}"
            )

    def stop(self, closing_line: str = "") -> None:
        """End the live line; leave ``closing_line`` (the step figures) in its place on stderr."""
        self._p.stop()
        if closing_line:
            self._p.console.print(f"run: {closing_line}", highlight=False)

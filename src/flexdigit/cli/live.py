"""``flexdigit shape`` (the centre line from one reading, or the estimator's accuracy on the twin).

flexdigit shape --gauges-v 0.21,0.71,0.30 --command 20 --orientation horizontal [--json]
flexdigit shape --accuracy [--seed 0] [--json]
"""

from __future__ import annotations

import argparse
from numbers import Integral

from flexdigit._command import CommandResult, add_command
from flexdigit._plot import add_plot_flag
from flexdigit._validation import SEED, Flag, Interval, Plausible
from flexdigit.params import SERVO_COMMAND


def register(subparsers) -> None:
    live = add_command(
        subparsers,
        "live",
        _live,
        help="serve the live page: the digit's shape, gauges, contact and controller, in a browser",
    )
    live.add_argument("--backend", default="sim", help="sim (the twin, horizontal), serial://..., replay://FILE")
    live.add_argument("--model", default=None, help="a trained position network (flexdigit train) for the contact")
    live.add_argument("--host", default="127.0.0.1", help="address to listen on (default this machine only)")
    live.add_argument(  # a TCP port number; 0 asks the system for a free one
        "--port",
        type=Flag(Interval(Integral, 0, 65535)),
        default=None,
        help="port (0: any free one; default 8050, with --foxglove 8765)",
    )
    live.add_argument("--allow-remote", action="store_true", help="allow a --host other machines can reach")
    live.add_argument("--record", default=None, help="record the session to this MCAP file")
    live.add_argument("--force", action="store_true", help="replace an existing --record file")
    live.add_argument("--params", metavar="FILE", help="the digit's parameters TOML (default: the thesis rig)")
    live.add_argument(
        "--calibration",
        default=None,
        help="calibration TOML: the twin's, and the shape estimate's (default: the thesis's, scaled to the digit)",
    )
    live.add_argument("--rotation-map", default=None, help="rotation map (flexdigit run --rotation-map) on hardware")
    live.add_argument("--orientation", default=None, help="mounting on hardware: vertical, horizontal, hanging")
    live.add_argument(
        "--seed", type=Flag(SEED), default=None, help="twin noise seed (default: the URL's seed=, else 0)"
    )
    live.add_argument(
        "--foxglove",
        action="store_true",
        help="stream the tendon robot (--robot) to Foxglove's WebSocket protocol instead of serving its 3D page",
    )
    live.add_argument("--robot", default=None, help="a tendon robot (rao2021 or a TOML file): its 3D page")
    live.add_argument("--tension-n", default=None, help="with --robot: tendon tensions from t = 0, N (T1,...,Tn)")
    live.add_argument(
        "--duration-s",
        type=Flag(Plausible("s", 1e-3, 3600.0, "a streamed motion: up to an hour")),
        default=None,
        help="with --robot: simulated (and shown) time, s (default 5)",
    )
    parser = add_command(
        subparsers,
        "shape",
        _shape,
        help="the digit's centre line (and a load) from its gauge voltages, or the estimator's accuracy",
    )
    parser.add_argument(
        "--gauges-v",
        default=None,
        help="the digit's gauge voltages, V, comma-separated (base first; 3 on the thesis's)",
    )
    parser.add_argument("--params", metavar="FILE", help="the digit's parameters TOML (default: the thesis rig)")
    parser.add_argument(
        "--calibration", metavar="FILE", help="its calibration TOML (default: the thesis's, scaled to the digit)"
    )
    parser.add_argument(
        "--command", type=Flag(SERVO_COMMAND), default=None, help="servo command in force (0..254); omit if unknown"
    )
    parser.add_argument("--orientation", default="vertical", help="vertical (tip up), horizontal (cable up), hanging")
    parser.add_argument("--no-cable", action="store_true", help="cable detached (the non-actuated digit, ch. 6)")
    parser.add_argument("--load", default="weight", help="what a load is: weight, press or none")
    parser.add_argument(
        "--n-average",
        type=Flag(Plausible("", 1, 1_000_000, "readings averaged into one: the thesis took 25", integer=True)),
        default=1,
        help="readings averaged into the one given",
    )
    parser.add_argument("--accuracy", action="store_true", help="score the estimator against the twin instead")
    parser.add_argument("--seed", type=Flag(SEED), default=0, help="noise seed of --accuracy")
    add_plot_flag(parser, "the estimated centre line with its 2 sd band, the tip and the load")
    parser.add_argument("--force", action="store_true", help="overwrite an existing --plot file")


def _live(args: argparse.Namespace) -> CommandResult:
    from flexdigit._validation import check_int
    from flexdigit.live.server import check_host, serve
    from flexdigit.live.session import LiveSession

    _check_robot_flags(args)
    if args.params is not None and (args.robot is not None or args.foxglove):
        from flexdigit.errors import ParameterError

        raise ParameterError("--params describes a planar digit; a tendon robot (--robot) is described by its own file")
    if args.foxglove:
        return _foxglove(args)
    if args.robot is not None:
        return _robot_page(args)
    args.port = 8050 if args.port is None else args.port
    check_host(args.host, args.allow_remote)
    check_int(args.port, "--port", low=0, high=65535)
    session = LiveSession(
        args.backend,
        model=args.model,
        record=args.record,
        force=args.force,
        params=args.params,
        calibration=args.calibration,
        rotation_map=args.rotation_map,
        orientation=args.orientation,
        seed=args.seed,
    )
    try:
        serve(session, args.host, args.port, allow_remote=args.allow_remote)
    except KeyboardInterrupt as exc:  # Ctrl-C (or SIGTERM, SIGHUP) is how a live session ends: exit 0
        session.stopped_by = session.stopped_by or getattr(exc, "signal_name", "SIGINT")
    finally:
        session.stop()
    data = {
        "status": session.error or "stopped",
        "signal": session.stopped_by,  # what stopped it: SIGINT (Ctrl-C), SIGTERM, SIGHUP
        "backend": args.backend,
        "params": args.params,
        "record": str(session.recording.path) if session.recording is not None else None,
        "overruns": session.state.overruns,
    }
    text = f"flexdigit live: {data['status']}" + (f"; recording {data['record']}" if data["record"] else "")
    return CommandResult(data=data, text=text, exit_code=0 if session.error is None else 1)


def _check_robot_flags(args: argparse.Namespace) -> None:
    """Refuse --tension-n or --duration-s without --robot (the digit's page would ignore them); default 5 s."""
    from flexdigit.errors import ParameterError

    given = [f for f, v in (("--tension-n", args.tension_n), ("--duration-s", args.duration_s)) if v is not None]
    if args.robot is None and given:
        raise ParameterError(f"{given[0]} is for a tendon robot: give --robot NAME|FILE with it")
    args.duration_s = 5.0 if args.duration_s is None else args.duration_s


def _foxglove(args: argparse.Namespace) -> CommandResult:
    """``live --foxglove --robot R --tension-n T``: the robot released into the tensions, streamed as it moves."""
    import sys

    from flexdigit.cli.tdcr import _tensions
    from flexdigit.errors import ParameterError
    from flexdigit.live.foxglove_stream import SCENE_TOPIC, FoxgloveStream, stream_motion
    from flexdigit.tdcr import get_robot, simulate, solve_statics

    if args.robot is None:
        raise ParameterError("--foxglove needs --robot: the tendon robot to stream")
    robot = get_robot(args.robot)
    tensions = [0.0] * len(robot.tendons) if args.tension_n is None else _tensions(args.tension_n, "tension-n", robot)
    motion = simulate(robot, solve_statics(robot, [0.0] * len(robot.tendons)), args.duration_s, tensions_n=tensions)
    port = 8765 if args.port is None else args.port
    with FoxgloveStream(host=args.host, port=port, allow_remote=args.allow_remote) as stream:
        url = f"ws://{args.host}:{stream.port}"
        print(f"streaming {robot.name!r} on {url} ({SCENE_TOPIC}); Foxglove: Open connection -> {url}", file=sys.stderr)
        try:
            sent = stream_motion(stream, robot, motion, tensions_n=tensions)
        except KeyboardInterrupt:
            sent = None
    data = {"robot": robot.name, "url": url, "topic": SCENE_TOPIC, "scenes": sent, "converged": motion.converged}
    text = f"{robot.name}: {sent} scenes on {url} {SCENE_TOPIC}"
    return CommandResult(data=data, text=text, exit_code=0 if motion.converged else 1)


def _robot_page(args: argparse.Namespace) -> CommandResult:
    """``live --robot R --tension-n T``: the robot released into the tensions, drawn in 3D on the page."""
    from flexdigit.cli.tdcr import _tensions
    from flexdigit.live.robot_page import motion_frames, serve_robot
    from flexdigit.tdcr import get_robot, simulate, solve_statics

    robot = get_robot(args.robot)
    tensions = [0.0] * len(robot.tendons) if args.tension_n is None else _tensions(args.tension_n, "tension-n", robot)
    motion = simulate(robot, solve_statics(robot, [0.0] * len(robot.tendons)), args.duration_s, tensions_n=tensions)
    frames = motion_frames(robot, motion)
    try:
        serve_robot(frames, args.host, 8050 if args.port is None else args.port, allow_remote=args.allow_remote)
    except KeyboardInterrupt:
        pass
    data = {"robot": robot.name, "frames": len(frames["t_s"]), "converged": motion.converged, "status": "stopped"}
    return CommandResult(data=data, text=f"{robot.name}: {len(frames['t_s'])} frames served", exit_code=0)


def _shape(args: argparse.Namespace) -> CommandResult:
    from flexdigit._plot import check_plot
    from flexdigit.errors import ParameterError
    from flexdigit.params import RigParams, load_params
    from flexdigit.twin.digit_calibration import twin_calibration

    params = load_params(args.params) if args.params else RigParams()
    calibration = twin_calibration(params, args.calibration)
    if args.accuracy:
        if args.plot:
            raise ParameterError("--plot draws one reading's centre line: give --gauges-v, not --accuracy")
        return _accuracy(args, params, calibration)
    check_plot(args.plot, "shape", force=args.force)
    volts = _gauge_volts(args.gauges_v, len(params.geometry.gauge_positions_m))
    from flexdigit.shape.shape import ShapeEstimator

    est_settings = ShapeEstimator(
        params,
        calibration,
        orientation=args.orientation,
        cable=not args.no_cable,
        load=args.load,
        n_average=args.n_average,
    )
    est = est_settings.estimate(volts, command=args.command)
    row = est.row(0, every=10)
    text = _shape_text(row)
    if not row["consistent"]:
        chi2 = float(est.chi2_load[0] if row["contact"] else est.chi2_no_load[0])
        text = (
            f"the readings do not fit this rig (chi-square {chi2:.0f}, at most {est_settings.misfit_chi2:g} "
            "expected): check the calibration, --orientation, --command and --no-cable; no estimate given"
            + _at_the_rail(volts, params.sensors)
        )
        return CommandResult(data=row, text=text, exit_code=1)
    if args.plot:
        from flexdigit._plot import save_plot
        from flexdigit.shape.shape_plot import shape_figure

        title = f"shape from gauges {args.gauges_v} V" + (
            f", command {args.command}" if args.command is not None else ""
        )
        row["plot"] = str(save_plot(shape_figure(est, 0, title), args.plot, "shape", force=args.force))
        text += f"\nplot -> {args.plot}"
    return CommandResult(data=row, text=text)


def _at_the_rail(volts: list[float], sensors) -> str:
    """``"; gauge 2 reads -2.5 V, ..."`` for readings at the ADC's end of range (clipped: no shape fits them), else
    ``""``. The card's codes run from ``lo`` to ``hi - 1 LSB``."""
    (lo, hi), lsb = sensors.adc_range_v, sensors.adc_lsb_v
    ends = (lo + lsb / 2, hi - 1.5 * lsb)
    railed = [f"gauge {k} reads {v:g} V" for k, v in enumerate(volts, start=1) if v <= ends[0] or v >= ends[1]]
    if not railed:
        return ""
    return f"; {', '.join(railed)}, the ADC's end of range [{lo:g}, {hi:g}] V: clipped (lower the amplifier gain)"


def _gauge_volts(gauges_v: str | None, count: int) -> list[float]:
    """``--gauges-v V1,V2,...``: one number per gauge of the digit, else a one-line error naming the flag."""
    from flexdigit.errors import ParameterError

    names = ",".join(f"V{k}" for k in range(1, count + 1))
    if gauges_v is None:
        raise ParameterError(f"--gauges-v {names} is required (or --accuracy)")
    try:
        volts = [float(x) for x in gauges_v.split(",")]
    except ValueError:
        volts = []
    if len(volts) != count:
        raise ParameterError(
            f"--gauges-v must be {count} numbers separated by commas (one per gauge of the digit, {names}). "
            f"Got {gauges_v!r}."
        )
    return volts


def _shape_text(row: dict) -> str:
    """One estimate's report: the tip, its angle, the cable's tension and the contact, if any."""
    tip_mm = [1e3 * x for x in row["tip_m"]]
    text = (
        f"tip at {tip_mm[0]:.1f}, {tip_mm[1]:.1f} mm (along, towards the cable), "
        f"+- {1e3 * max(row['tip_sd_m']):.1f} mm; tip angle {row['tip_angle_deg']:.1f} deg; "
        f"cable tension {row['tension_n']:.2f} N\n"
    )
    if row["contact"]:
        lo, hi = row["load_position_interval_m"]
        sd = row["load_position_sd_m"]
        sd_text = "not locatable" if sd is None else f"+- {1e3 * sd:.1f} mm"
        text += (
            f"contact: a {row['load_kind']} at {1e3 * row['load_position_from_base_m']:.0f} mm from the base "
            f"({sd_text}; consistent {1e3 * lo:.0f}..{1e3 * hi:.0f} mm), force {row['load_force_n']:.3f} N"
        )
    else:
        text += "no contact"
    return text


def _accuracy(args: argparse.Namespace, params, calibration) -> CommandResult:
    import warnings

    from flexdigit.errors import ConvergenceWarning
    from flexdigit.shape.shape import shape_accuracy

    # the digit's own commands (straight to each end of its operating range) and load places (shape_accuracy's);
    # the twin's unsettled static solves are said in the output, not warned about on the console
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        acc = shape_accuracy(seed=args.seed, params=params, calibration=calibration)
    twin_unsettled = sum(issubclass(w.category, ConvergenceWarning) for w in caught)
    for w in caught:  # anything else goes on as it came
        if not issubclass(w.category, ConvergenceWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    summary = acc.summary()
    commands = sorted(set(acc.command.tolist()))
    lines = [f"commands {', '.join(str(c) for c in commands)} (straight {params.actuator.equilibrium_command})"]
    if acc.mount != "vertical":
        lines.append(f"the digit buckles tip up: its bare cases are {acc.mount} (tip down), as `run` mounts it")
    lines.append("case                 cases  tip median  tip p95  tip max  RMS along  tip within 2 sd")
    for g in summary:
        lines.append(
            f"{g['case']:<20} {g['cases']:>5}  {g['tip_error_median_mm']:7.2f} mm {g['tip_error_p95_mm']:6.2f} mm "
            f"{g['tip_error_max_mm']:6.2f} mm {g['rms_error_mean_mm']:7.2f} mm  {100 * g['tip_within_2sd']:6.0f} %"
        )
    unsettled = sum(g["unsettled"] for g in summary)
    if unsettled:
        lines.append(f"not settled: {unsettled} estimate(s) (their lever arms moved on at the iteration cap)")
    if twin_unsettled:
        lines.append(
            f"the twin's static solve did not settle in {twin_unsettled} batch(es): those rows are scored against "
            "an unsettled shape"
        )
    data = {
        "seed": args.seed,
        "commands": commands,
        "mount": acc.mount,
        "groups": summary,
        "twin_unsettled_batches": twin_unsettled,
    }
    return CommandResult(data=data, text="\n".join(lines), exit_code=0)

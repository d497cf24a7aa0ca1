"""``flexdigit simulate release|step|sweep|load ... --out FILE [--json]``: the thesis's experiments on the twin.

Each writes its tidy table (Parquet, or CSV when FILE ends in .csv) with the parameters, calibration and seed in
its metadata, and prints what the thesis took from that experiment (release: wn and zeta per gauge; step: the
potentiometer's rise; sweep: the E 3.20-3.22 lines; load: rows and mean voltages).

With ``--robot ROBOT`` (a tendon robot: a built-in or a robot TOML, ``flexdigit tdcr``), ``release`` and ``step``
run on the robot's twin instead (:mod:`flexdigit.tdcr.experiments`) and write the tip's path (``t_s, tip_x_m,
tip_y_m, tip_z_m``): a release from a tip deflection under ``--tension-n`` (its first frequency printed beside the
straight backbone's Euler-Bernoulli one), or a step from ``--from-tension-n`` to ``--tension-n``. ``sweep`` and
``load`` are the digit's servo and weights; with ``--robot`` they are refused in one line.
"""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command, digit_name, name_sub_commands
from flexdigit._plot import add_plot_flag
from flexdigit._validation import SEED, Flag, Plausible, check_values
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.params import LOAD_KG, POSITION_FROM_TIP_M, SERVO_COMMAND, RigParams

# The experiments' flags, declared once (flexdigit._validation.Flag): argparse refuses a value outside its range
# before anything is simulated, in one line naming the flag.
#: A simulated record's length: the thesis's records are 1.5-8 s; ten minutes bounds the memory (x the rate).
DURATION = Plausible("s", 0.01, 600.0, "a simulated record of 10 ms to 10 min")
#: The sample rate of a simulated record: the thesis logged at 1 kHz; 10 kHz resolves every mode of the digit.
RATE = Plausible("Hz", 1.0, 1e4, "sampling at 1 Hz to 10 kHz")
#: Commands as a list ("0,20,40") or a range ("8..43"), each a servo position byte (both ends checked first).
COMMANDS = Flag(SERVO_COMMAND, many=True, ranges=True)
#: A release record's default length: this many periods of the digit's first mode (as mounted, housed or bare),
#: enough swings for ``identify`` to see the decay (it needs 4 x the time to swing half-way after the release); the
#: thesis rig's 8 s hold 13 periods of its housed 13.1 rad/s, a 2.4 rad/s bare 0.6 m digit needs 31 s.
RELEASE_CYCLES = 12.0
#: ... and never shorter than the thesis's records.
RELEASE_MIN_S = 8.0
#: ... and long enough for the swing to lose this fraction of its amplitude, as the thesis rig's bare 8 s does:
#: zeta is read from the decay, and a lightly damped bare strip (seven_sections_450mm: zeta 0.001 at 6.9 rad/s)
#: loses 7 % over 12 periods, which left its zeta +-17 % (seeds 0-3; 25 s: within 6 %, 40 s: 2.3 %).
RELEASE_DECAY = 0.18
#: ... up to this long (a digit without damping never decays: identify reads what the record holds).
RELEASE_MAX_S = 120.0
#: Chapter 6's load positions from the tip (cm) on the thesis digit (6.4: 0 to 14 cm, and 24 cm near the clamp).
CHAPTER6_POSITIONS_CM = (0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 24)


def _commands(values: list[int], params, experiment: str) -> list[int]:
    """Commands parsed by :data:`COMMANDS`, each inside this rig's command range (checked here, in the user's
    terms: a rig file may narrow 0..254)."""
    a = params.actuator
    owner = f"flexdigit simulate {experiment}"
    check_values(values, "--commands", owner, low=a.command_min, high=a.command_max, integer=True)
    return values


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = add_command(
        subparsers,
        "simulate",
        _run,
        help="run a thesis experiment on the digital twin and save its table",
        description=__doc__.splitlines()[0],
    )
    sub = parser.add_subparsers(dest="experiment", metavar="EXPERIMENT", required=True)

    for add in (_add_release, _add_step, _add_sweep, _add_load):
        add(sub)
    name_sub_commands(sub)


def _common(p: argparse.ArgumentParser) -> None:
    """The flags every experiment takes."""
    p.add_argument("--out", required=True, help="output file (.parquet, or .csv)")
    p.add_argument("--force", action="store_true", help="overwrite --out (and --plot) if it exists")
    p.add_argument("--seed", type=Flag(SEED), default=0, help="noise seed (default 0)")
    p.add_argument("--params", help="rig parameters TOML (default: the thesis rig)")
    p.add_argument(
        "--calibration",
        help="twin calibration TOML (default: fitted to the thesis, scaled to the --params digit)",
    )
    p.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the result as JSON")
    add_plot_flag(
        p,
        "the record (gauges and pot in V over time, the command or the load's position; with --robot the tip's "
        "x, y and z in mm over time)",
    )
    p.add_argument(
        "--robot",
        metavar="ROBOT",
        help="a tendon robot instead of the digit (release and step only): a built-in (rao2021) or a robot TOML "
        "(backbone, segments and disks, tendons: see flexdigit tdcr statics --help)",
    )


def _robot_flags(p: argparse.ArgumentParser, step: bool) -> None:
    """The robot's flags of release and step (``--robot``)."""
    what = "after t = 0" if step else "held throughout"
    p.add_argument("--tension-n", help=f"with --robot: tendon tensions {what}, N, one per tendon (default all 0)")
    if step:
        p.add_argument("--from-tension-n", help="with --robot: tensions before t = 0, N (default all 0)")


def _add_release(sub) -> None:
    """The release test's flags."""
    p = sub.add_parser("release", help="release test, cable removed (3.1.2, figure 3.6)")
    _common(p)
    p.add_argument("--no-housing", action="store_true", help="bare strip (table 3.1)")
    p.add_argument(
        "--deflection-mm",
        type=Flag(Plausible("mm", -200.0, 200.0, "a release from at most 200 mm either side of straight")),
        default=20.0,
        help="initial tip deflection (mm)",
    )
    p.add_argument(
        "--duration",
        type=Flag(DURATION),
        default=None,
        help=f"seconds (default: {RELEASE_CYCLES:g} periods of the digit's first mode as mounted, at least "
        f"{RELEASE_MIN_S:g} s, the thesis's records, and long enough for its swing to lose "
        f"{100 * RELEASE_DECAY:g} %%, up to {RELEASE_MAX_S:g} s)",
    )
    p.add_argument("--rate", type=Flag(RATE), default=1000.0, help="sample rate (Hz)")
    p.add_argument(
        "--orientation",
        default=None,
        choices=("vertical", "hanging", "horizontal"),
        help="vertical: tip up, as the thesis mounted it (2.2.4); default tip up, or hanging for a digit that "
        "buckles tip up, as flexdigit run mounts it (with --robot: gravity along -z, +z or -x of the robot's base "
        "frame; default -z)",
    )
    _robot_flags(p, step=False)


def _add_step(sub) -> None:
    """The servo step's flags."""
    p = sub.add_parser("step", help="servo command step (3.2.4, figure 3.11)")
    _common(p)
    p.add_argument("--from", dest="command_from", type=Flag(SERVO_COMMAND), default=0, help="servo command before")
    p.add_argument(
        "--to", dest="command_to", type=Flag(SERVO_COMMAND), default=51, help="servo command after (the thesis: 51)"
    )
    p.add_argument("--duration", type=Flag(DURATION), default=1.5, help="seconds")
    p.add_argument("--rate", type=Flag(RATE), default=1000.0, help="sample rate (Hz)")
    p.add_argument("--cable", action="store_true", help="keep the cable attached")
    _orientation_flag(p, "as the thesis mounted it")
    _robot_flags(p, step=True)


def _orientation_flag(p, thesis: str) -> None:
    """``--orientation``: the mount of step and sweep (default: run's choice, hanging for a digit that buckles)."""
    p.add_argument(
        "--orientation",
        default=None,
        choices=("vertical", "hanging", "horizontal"),
        help=f"vertical: tip up, {thesis}; default tip up, or hanging for a digit that buckles tip up, as flexdigit "
        "run mounts it",
    )


def _add_sweep(sub) -> None:
    """The actuation sweep's flags."""
    p = sub.add_parser("sweep", help="actuation sweep, commands 8..43 (3.4.3, E 3.20-3.22)")
    _common(p)
    p.add_argument(
        "--commands",
        type=COMMANDS,
        default=None,
        help="'8..43' or '8,20,43' (default: the digit's [actuator] operating_commands, 8..43 on the thesis rig; "
        "92..162 for a cable pair straight at 127)",
    )
    p.add_argument(
        "--settle",
        type=Flag(Plausible("s", 0.0, 60.0, "the digit settles in ~3 s (wn 13 rad/s, zeta 0.07); a minute is ample")),
        default=3.0,
        help="settling time per command (s)",
    )
    p.add_argument(
        "--samples",
        type=Flag(Plausible("", 1, 10_000, "readings per command: the thesis took 20", integer=True)),
        default=20,
        help="samples per command",
    )
    _orientation_flag(p, "as the thesis swept it (3.4.3)")


def _add_load(sub) -> None:
    """The static load test's flags."""
    p = sub.add_parser("load", help="static load test (6.4-6.5, 7.1-7.2)")
    _common(p)
    p.add_argument(
        "--loads-g",
        type=Flag(LOAD_KG.to("g", 1e3), many=True),
        default="12.5,25,7.5",
        help="weights in grams (default: chapter 6)",
    )
    p.add_argument(
        "--positions-cm",
        type=Flag(POSITION_FROM_TIP_M.to("cm", 1e2), many=True),
        default=None,
        help="positions from the tip in cm (default: chapter 6's 0..14 and 24 cm, on another digit at the same "
        "fractions of its length)",
    )
    p.add_argument(
        "--commands", type=COMMANDS, default=None, help="actuation commands, e.g. '0,20,40' (default: cable detached)"
    )
    p.add_argument(
        "--repetitions",
        type=Flag(Plausible("", 1, 10_000, "repetitions of each load case: the thesis made 25", integer=True)),
        default=25,
        help="readings of each load case",
    )
    p.add_argument(
        "--orientation",
        default="horizontal",
        choices=("horizontal", "vertical", "hanging"),
        help="how the digit lies (the thesis: horizontal, chapters 6-7)",
    )


def _run(args: argparse.Namespace) -> CommandResult:
    from flexdigit._io import check_output
    from flexdigit._plot import check_plot, save_plot
    from flexdigit.params import RigParams, load_params
    from flexdigit.twin.digit_calibration import twin_calibration
    from flexdigit.twin.record_plot import record_figure

    check_output(args.out, force=args.force)  # before the simulation, not after it
    check_plot(args.plot, "simulate", force=args.force)
    if args.robot is not None:
        return _robot(args)
    for flag in ("tension_n", "from_tension_n"):  # the digit's experiment would ignore them
        if getattr(args, flag, None) is not None:
            raise ParameterError(f"--{flag.replace('_', '-')} is a tendon robot's: give --robot NAME|FILE with it")
    params = load_params(args.params) if args.params else RigParams()
    # the file, else the one default: the thesis rig's packaged fit, another digit's scaled to it by the physics
    cal = twin_calibration(params, args.calibration)
    common = dict(seed=args.seed, params=params, calibration=cal)
    gauges = range(1, len(params.geometry.gauge_positions_m) + 1)  # the digit's gauges, 1..G
    mount = _mount(args, params, cal)
    experiment = {"release": _release, "step": _step, "sweep": _sweep}.get(args.experiment, _load)
    res, findings, text = experiment(args, params, gauges, common)
    text += f"\n{mount}" * bool(mount)
    path = res.save(args.out, force=args.force)
    if args.plot:
        save_plot(record_figure(res, digit=digit_name(args.params)), args.plot, "simulate", force=args.force)
    data = {
        "experiment": res.metadata["experiment"],
        "out": str(path),
        "rows": res.table.num_rows,
        "columns": res.table.column_names,
        "seed": args.seed,
        "findings": findings,
        "plot": args.plot,
    }
    text += f"\nplot -> {args.plot}" * bool(args.plot)
    digit = f" of digit {digit_name(args.params)} ({args.params})" if args.params else ""
    head = f"{res.metadata['experiment']}{digit}: {res.table.num_rows} rows -> {path}"
    return CommandResult(data=data, text=f"{head}\n{text}")


def _mount(args, params, calibration) -> str:
    """Set the twin's mount when ``--orientation`` is not given (``load`` keeps its horizontal), as ``flexdigit
    run`` and ``collect`` choose it (:func:`~flexdigit.control.design20ms.digit_mount`): tip up, or hanging for a
    digit that buckles tip up; the line that says it was hung (else empty)."""
    if args.experiment == "load" or args.orientation is not None:
        return ""
    from flexdigit.control.design20ms import digit_mount

    args.orientation = digit_mount(params, calibration)
    if args.orientation == "vertical":
        return ""
    return "mount: hanging (tip down): tip up this digit buckles under its own weight (as run and collect hang it)"


def release_duration_s(params, calibration, *, housing: bool, orientation: str) -> float:
    """The default length of a release record (s): :data:`RELEASE_CYCLES` periods of the digit's first mode as
    mounted (housed or bare, cable removed), at least :data:`RELEASE_MIN_S`, and long enough for the mode to decay
    by :data:`RELEASE_DECAY` (at most :data:`RELEASE_MAX_S` for that).

    Examples
    --------
    >>> from flexdigit.twin.calibration import default_calibration
    >>> release_duration_s(RigParams(), default_calibration(), housing=True, orientation="vertical")
    8.0
    """
    import math

    from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, cached_digit

    wns, zetas = cached_digit(params, calibration, housing, orientation, DEFAULT_CELLS_PER_SECTION).linear_modes()[:2]
    wn, zeta = float(wns[0]), float(zetas[0])
    if not (math.isfinite(wn) and wn > 0):  # buckled as mounted: release_test refuses it in one line
        return RELEASE_MIN_S
    decay = -math.log(1 - RELEASE_DECAY) / (zeta * wn) if zeta > 0 else math.inf  # E^-(zeta wn t) = 1 - decay
    return max(RELEASE_MIN_S, math.ceil(RELEASE_CYCLES * 2 * math.pi / wn), math.ceil(min(RELEASE_MAX_S, decay)))


def _release(args, params, gauges, common: dict):
    """``simulate release``: the record, each gauge's wn and zeta, and their lines."""

    if args.deflection_mm == 0:
        # a release from no deflection is noise, and the fit below would report a wn and zeta fitted to it
        raise ParameterError(
            "The '--deflection-mm' parameter of flexdigit simulate release must not be 0: a release test releases "
            "the digit from a deflection (e.g. 20 mm, either sign). Got 0.0 instead."
        )
    res, findings = _release_record(args, params, gauges, common)
    lines = []
    for g in gauges:
        f = findings[f"gauge{g}"]
        if "error" in f:
            lines.append(f"gauge {g}: not identified ({f['error']})")
        else:
            lines.append(
                f"gauge {g}: wn {f['wn_rad_s']:.3f} rad/s, zeta {f['zeta']:.4f} (fit {f['fit_percent']:.1f} %)"
            )
    lines.append(f"median: wn {findings['wn_rad_s']:.3f} rad/s, zeta {findings['zeta']:.4f}")
    return res, findings, "\n".join(lines)


def _release_record(args, params, gauges, common: dict):
    """The release record (``--duration`` or :func:`release_duration_s`) and its findings; a record too short to
    identify is refused naming ``--duration``."""
    from flexdigit.twin import records as ex

    need = release_duration_s(params, common["calibration"], housing=not args.no_housing, orientation=args.orientation)
    duration = need if args.duration is None else args.duration
    res = ex.release_test(
        housing=not args.no_housing,
        tip_deflection_m=args.deflection_mm * 1e-3,
        duration_s=duration,
        sample_rate_hz=args.rate,
        orientation=args.orientation,
        **common,
    )
    try:
        return res, _release_findings(res, gauges)
    except DataFileError as exc:
        if "too short" not in str(exc):
            raise
        said = str(exc).partition("; pass --force")[0]
        if "quantised: " in said:  # the resolution, not the duration, is what is wrong
            why = "quantised: " + said.partition("quantised: ")[2].partition(";")[0]
            raise ParameterError(f"the release record cannot be identified, {why} (no record written)") from None
        raise ParameterError(
            f"a {duration:g} s release record is too short to identify this digit's first mode: give --duration "
            f"{max(need, 2 * duration):g} or more (no record written; identify: {said})"
        ) from None


def _step(args, params, gauges, common: dict):
    """``simulate step``: the record and the pot's start, peak and end."""
    from flexdigit.twin import records as ex

    res = ex.servo_step_test(
        command_from=args.command_from,
        command_to=args.command_to,
        duration_s=args.duration,
        sample_rate_hz=args.rate,
        cable=args.cable,
        orientation=args.orientation,
        **common,
    )
    pot = res.column("pot_v")
    findings = {"pot_start_v": float(pot[0]), "pot_peak_v": float(pot.max()), "pot_end_v": float(pot[-1])}
    return res, findings, "pot: {pot_start_v:.4f} V -> peak {pot_peak_v:.4f} V -> {pot_end_v:.4f} V".format(**findings)


def _sweep(args, params, gauges, common: dict):
    """``simulate sweep``: the record and each gauge's line against the command (E 3.20-3.22 on the thesis rig)."""
    import numpy as np

    from flexdigit.twin import records as ex

    commands = None if args.commands is None else _commands(args.commands, params, "sweep")
    res = ex.actuation_sweep(
        commands, settle_s=args.settle, samples=args.samples, orientation=args.orientation, **common
    )
    cmd = res.column("command")
    lines, findings = [], {}
    thesis = params.is_thesis_rig()  # the thesis's lines E 3.20-3.22 are its rig's, no other digit's
    for g in gauges:
        slope, offset = np.polyfit(cmd, res.column(f"gauge{g}_v"), 1)
        findings[f"gauge{g}"] = {"slope_v_per_command": float(slope), "offset_v": float(offset)}
        lines.append(f"gauge {g}: V = {slope:.5f} command {offset:+.4f}" + (f"   (E 3.2{g - 1})" if thesis else ""))
    return res, findings, "\n".join(lines)


def _load(args, params, gauges, common: dict):
    """``simulate load``: the record and each gauge's mean."""
    import numpy as np

    from flexdigit.twin import records as ex

    commands = None if args.commands is None else _commands(args.commands, params, "load")
    length_cm = params.geometry.digit_length_m * 1e2
    given = args.positions_cm
    if given is None:  # chapter 6's places on the 27 cm thesis digit, at the same fractions of this one's length
        scale = params.geometry.digit_length_m / RigParams().geometry.digit_length_m
        given = [round(c * scale, 2) for c in CHAPTER6_POSITIONS_CM]
    positions_cm = check_values(
        given,
        "--positions-cm",
        "flexdigit simulate load",
        low=0,
        high=length_cm,
        high_open=True,
        unit="cm from the tip",
        note=f"0 is the tip, {length_cm:g} the clamp: nothing hangs beyond the tip, or at or behind the clamp",
    )
    res = ex.static_load_test(
        [g * 1e-3 for g in args.loads_g],
        [c * 1e-2 for c in positions_cm],
        commands=commands,
        repetitions=args.repetitions,
        orientation=args.orientation,
        **common,
    )
    findings = {f"gauge{g}_mean_v": float(np.mean(res.column(f"gauge{g}_v"))) for g in gauges}
    return res, findings, f"{res.table.num_rows} samples"


def _release_findings(record, gauges=(1, 2, 3)) -> dict:
    """wn and zeta of each gauge of a simulated release test by ``identify``'s lsq fit, and their medians: the
    reduction ``flexdigit calibrate`` applies to a rig's release tests, so one record gives one answer."""
    # the analysis sits above the twin (identify, calibrate); this command only presents it for the record it made
    from flexdigit.calibrate.targets import release_figures
    from flexdigit.identify.timeseries import series_from_table

    figures = release_figures([series_from_table(record, f"gauge{g}") for g in gauges])
    findings: dict = {"wn_rad_s": figures["wn_rad_s"], "zeta": figures["zeta"]}
    for fit in figures["fits"]:
        findings[fit.channel] = {"wn_rad_s": fit.wn_rad_s, "zeta": fit.zeta, "fit_percent": fit.fit_percent}
    for skip in figures["skipped"]:
        findings[skip["record"].rpartition(":")[2]] = {"error": skip["reason"]}
    return findings


# ---------------------------------------------------------------------------------------------- a tendon robot
#: The digit's flags that mean nothing to a robot, refused with --robot when given (the value set, the default).
_DIGIT_ONLY = {"params": None, "calibration": None, "no_housing": False, "cable": False}


def _robot(args: argparse.Namespace) -> CommandResult:
    """``simulate release|step --robot ROBOT``: the experiment on the robot's twin, its table written."""
    from flexdigit.tdcr import euler_bernoulli_first_hz, get_robot

    if args.experiment not in ("release", "step"):
        raise ParameterError(
            f"flexdigit simulate {args.experiment} is the digit's (servo commands, weights): a robot's experiments "
            "are release and step (its statics: flexdigit tdcr statics ROBOT --tension-n ...)"
        )
    for name, default in _DIGIT_ONLY.items():
        if getattr(args, name, default) != default:
            raise ParameterError(f"--{name.replace('_', '-')} is the digit's; it does not apply with --robot")
    robot = get_robot(args.robot)
    test = _robot_test(args, robot)
    path = test.save(args.out, force=args.force)
    data = {**test.metadata(), "out": str(path), "rows": int(test.motion.t_s.size)}
    data["euler_bernoulli_hz"] = euler_bernoulli_first_hz(robot)
    if args.plot:
        from flexdigit._plot import save_plot
        from flexdigit.tdcr import experiment_figure

        data["plot"] = str(save_plot(experiment_figure(test), args.plot, "simulate", force=args.force))
    tip = test.motion.tip_positions_m * 1e3
    lines = [
        f"{data['experiment']} of {robot.name}: {tip.shape[0]} rows -> {path} (converged: {test.motion.converged})",
        "tip from ({:.3f}, {:.3f}, {:.3f}) mm to ({:.3f}, {:.3f}, {:.3f}) mm".format(*tip[0], *tip[-1]),
    ]
    if args.experiment == "release":
        lines.append(
            f"first frequency {test.first_frequency_hz:.4f} Hz (the straight backbone as an Euler-Bernoulli "
            f"cantilever: {data['euler_bernoulli_hz']:.4f} Hz)"
        )
    if args.plot:
        lines.append(f"plot -> {data['plot']}")
    return CommandResult(data=data, text="\n".join(lines), exit_code=0 if test.motion.converged else 1)


def _robot_test(args: argparse.Namespace, robot):
    """The release or step test ``simulate --robot`` asks for (:func:`flexdigit.tdcr.release_test`, ``step_test``)."""
    from flexdigit._constants import G_STANDARD_M_S2
    from flexdigit.tdcr import release_test, step_test

    tensions = _robot_tensions(args.tension_n, "--tension-n", robot)
    if args.experiment == "release":
        g = G_STANDARD_M_S2
        mount = args.orientation or "vertical"
        gravity = {"vertical": (0, 0, -g), "hanging": (0, 0, g), "horizontal": (-g, 0, 0)}[mount]
        sign = 1.0 if args.deflection_mm >= 0 else -1.0
        test = release_test(
            robot,
            tensions,
            tip_deflection_m=abs(args.deflection_mm) * 1e-3,
            direction=(sign, 0.0, 0.0),
            duration_s=args.duration,
            dt_s=1.0 / args.rate,
            gravity_m_s2=gravity,
        )
    else:
        start = _robot_tensions(args.from_tension_n, "--from-tension-n", robot)
        test = step_test(robot, tensions, from_tensions_n=start, duration_s=args.duration, dt_s=1.0 / args.rate)
    return test


def _robot_tensions(text: str | None, flag: str, robot) -> list[float]:
    """A robot's tensions flag: one number >= 0 per tendon (default all zero), refused in one line naming it."""
    if text is None or (not text.strip() and not robot.tendons):
        return [0.0] * len(robot.tendons)
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != len(robot.tendons) or not all(0 <= v < float("inf") for v in values):
        raise ParameterError(
            f"{flag} must give one tension >= 0 N per tendon of {robot.name!r} ({len(robot.tendons)}, comma-"
            f"separated). Got {text!r} instead."
        )
    return values

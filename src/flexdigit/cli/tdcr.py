"""``flexdigit tdcr statics|dynamics|shape|contact ROBOT [--tension-n T1,...,Tn] [...] [--json]``: a tendon robot.

ROBOT is a built-in name (``rao2021``) or a robot TOML file (:mod:`flexdigit.tdcr.description`). ``statics``
prints the tip position and frame and, under ``--json``, the backbone (every disk) as well. ``dynamics`` starts
from the static shape under ``--from-tension-n`` / ``--from-tip-force-n`` (default: straight), applies the given
loads at t = 0 and prints the tip's path. A solve that does not converge is reported with ``converged: false``
and exit code 1. ``--record OUT.mcap`` also writes the shape(s) as an MCAP recording with a
``foxglove.SceneUpdate`` channel (:mod:`flexdigit.tdcr.scene`): it opens in Foxglove's 3D panel.

``shape`` estimates the backbone and the tip pose from strain gauges on the backbone's faces
(:func:`flexdigit.tdcr.sense_shape`): from ``--strains`` (one per gauge of the default layout) or a
``--readings`` CSV, or, with ``--tension-n`` alone, from the twin's own readings (with ``--noise-std`` and
``--seed``), printed beside the twin's shape with the errors. ``contact`` finds a point contact's place and
force from the same gauges (:func:`flexdigit.tdcr.sense_contact`), about the twin's shape under ``--tension-n``;
from readings, or from the twin pressed at ``--contact-s-m`` by ``--contact-force-n``.

Elsewhere a robot is ``--robot ROBOT``: ``flexdigit simulate release|step --robot`` (its release test and first
frequency, a tension step), ``flexdigit live --robot``; and ``flexdigit study sensitivity SPEC`` runs a spec whose
``[study]`` names a robot (:mod:`flexdigit.studies.robot_study`; shipped: ``rao2021-tolerances``).
"""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command, name_sub_commands
from flexdigit._plot import add_plot_flag
from flexdigit._validation import SEED, Flag, Plausible
from flexdigit.errors import ParameterError

#: ``tdcr contact`` says a force is barely seen when its one-sigma uncertainty exceeds this share of its size.
_UNCERTAIN = 0.2
#: ... and a fit poor when it leaves more than this RMS strain (ten times a good amplifier's noise).
_POOR_FIT = 1e-5


def _floats(text: str, name: str, count: int | None = None) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ParameterError(f"--{name} must be comma-separated numbers. Got {text!r} instead.") from None
    if not values or (count is not None and len(values) != count):
        what = f"{count} comma-separated numbers" if count else "at least one number"
        raise ParameterError(f"--{name} must be {what}. Got {text!r} instead.")
    return values


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = add_command(
        subparsers,
        "tdcr",
        _run,
        help="tendon-driven continuum robots in 3D (a Cosserat rod with tendons)",
        description=__doc__.splitlines()[0],
    )
    sub = parser.add_subparsers(dest="tdcr_command", metavar="TDCR_COMMAND", required=True)
    from flexdigit.cli._formats import epilog

    p = sub.add_parser("statics", help="static equilibrium under tendon tensions and tip loads", epilog=epilog("robot"))
    p.add_argument("robot", metavar="ROBOT", help="a built-in robot (rao2021) or a robot TOML file")
    p.add_argument("--tension-n", required=True, help="tendon tensions in N, one per tendon: '4,0,0,0,2,0'")
    vector = "(world frame, e.g. --{} -1,0,0)"
    p.add_argument("--tip-force-n", help="tip force fx,fy,fz in N " + vector.format("tip-force-n"))
    p.add_argument("--tip-moment-nm", help="tip moment mx,my,mz in N m " + vector.format("tip-moment-nm"))
    p.add_argument("--gravity-m-s2", help="gravity gx,gy,gz in m/s^2, base frame (default: none)")
    p.add_argument("--record", metavar="OUT.mcap", help="also write an MCAP recording with a 3D view (Foxglove)")
    p.add_argument("--force", action="store_true", help="replace the --record (and --plot) file if it exists")
    p.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the result as JSON")
    add_plot_flag(
        p, "the robot's backbone from the side (x-z), the front (y-z) and above (x-y) in mm, disks and tip marked"
    )
    p = sub.add_parser(
        "dynamics", help="time response from a static shape to loads applied at t = 0", epilog=epilog("robot")
    )
    p.add_argument("robot", metavar="ROBOT", help="a built-in robot (rao2021) or a robot TOML file")
    p.add_argument("--tension-n", required=True, help="tendon tensions from t = 0, in N, one per tendon")
    p.add_argument("--tip-force-n", help="tip force from t = 0, fx,fy,fz in N " + vector.format("tip-force-n"))
    p.add_argument("--tip-moment-nm", help="tip moment from t = 0, in N m " + vector.format("tip-moment-nm"))
    p.add_argument("--gravity-m-s2", help="gravity gx,gy,gz in m/s^2, base frame, before and after t = 0")
    p.add_argument("--from-tension-n", help="tensions of the initial static shape (default: all zero)")
    p.add_argument("--from-tip-force-n", help="tip force of the initial static shape (default: none)")
    p.add_argument(
        "--duration-s",
        type=Flag(Plausible("s", 1e-4, 600.0, "a simulated response: up to 10 minutes")),
        default=1.0,
        help="simulated time, s, up to 600 (default 1 s)",
    )
    p.add_argument(
        "--dt-s",
        type=Flag(Plausible("s", 1e-6, 0.1, "an implicit time step: 1 us to 0.1 s")),
        default=1e-3,
        help="implicit time step, s, 1e-6..0.1 (default 1 ms)",
    )
    p.add_argument(
        "--method",
        choices=("discrete", "shooting"),
        default="discrete",
        help="the discretised rod (default; fast, robust) or the continuous rod shot at each step",
    )
    p.add_argument("--record", metavar="OUT.mcap", help="also write an MCAP recording with a 3D view (Foxglove)")
    p.add_argument("--force", action="store_true", help="replace the --record (and --plot) file if it exists")
    p.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the result as JSON")
    add_plot_flag(p, "the tip's x, y and z (mm) against time (s)")
    _add_shape(sub, vector)
    _add_contact(sub)
    name_sub_commands(sub)


#: The gauges' default layout, described once for the help of shape and contact.
LAYOUT_HELP = (
    "gauges at STATIONS evenly inside each segment, each station with axial gauges on the faces at 0, 90, 180 and "
    "270 deg from the cross-section's x axis and a +-45 deg torsion rosette on the 0 deg face, in that order "
    "(flexdigit.tdcr.gauge_layout)"
)
READINGS_HELP = "a CSV of gauge readings: header s_m,angle_deg,strain[,tilt_deg], one row per gauge (strain: m/m)"


def _add_sensing_flags(p: argparse.ArgumentParser, stations: int) -> None:
    """The readings flags ``shape`` and ``contact`` share."""
    p.add_argument("robot", metavar="ROBOT", help="a built-in robot (rao2021) or a robot TOML file")
    p.add_argument("--strains", help=f"readings, one per gauge of the default layout: {LAYOUT_HELP}")
    p.add_argument("--readings", metavar="FILE.csv", help=READINGS_HELP)
    p.add_argument(
        "--stations-per-segment",
        type=Flag(Plausible("", 1, 100, "gauge stations per segment", integer=True)),
        default=stations,
        metavar="STATIONS",
        help=f"the default layout's stations per segment (default {stations})",
    )
    p.add_argument(
        "--noise-std",
        type=Flag(Plausible("", 0.0, 1e-3, "white noise on the twin's readings, as a strain: 1e-6 is a microstrain")),
        default=0.0,
        help="white noise on the twin's readings, strain (default 0; a good amplifier: 1e-6)",
    )
    p.add_argument("--seed", type=Flag(SEED), default=0, help="noise seed (default 0)")
    p.add_argument("--out", metavar="FILE.json", help="also write the result (as --json prints it) to FILE")
    p.add_argument("--force", action="store_true", help="replace the --out (and --record, --plot) file if it exists")
    p.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the result as JSON")


def _add_shape(sub, vector: str) -> None:
    from flexdigit.cli._formats import epilog

    p = sub.add_parser(
        "shape",
        help="backbone and tip pose from strain gauges on the backbone's faces, estimate vs twin",
        description="Estimate the backbone and the tip pose from strain gauges: from --strains or --readings, or "
        "from the twin's own readings under --tension-n (and loads), shown beside the twin's shape.",
        epilog=epilog("robot", "gauge_readings"),
    )
    _add_sensing_flags(p, 3)
    p.add_argument("--tension-n", help="tendon tensions in N, one per tendon: the twin to read (or compare with)")
    p.add_argument("--tip-force-n", help="tip force fx,fy,fz in N " + vector.format("tip-force-n"))
    p.add_argument("--tip-moment-nm", help="tip moment mx,my,mz in N m " + vector.format("tip-moment-nm"))
    p.add_argument("--gravity-m-s2", help="gravity gx,gy,gz in m/s^2, base frame (default: none)")
    p.add_argument(
        "--record", metavar="OUT.mcap", help="also write the estimated shape as an MCAP recording (Foxglove 3D)"
    )
    add_plot_flag(
        p,
        "the estimated backbone beside the twin's, seen from the side (x-z) and the front (y-z) in mm, and the "
        "distance between them along the backbone",
    )


def _add_contact(sub) -> None:
    from flexdigit.cli._formats import epilog

    p = sub.add_parser(
        "contact",
        help="a point contact's place and force in space from the gauges",
        description="Locate a point contact and measure its force from strain gauges, about the twin's shape "
        "under --tension-n: from --strains or --readings, or from the twin pressed at --contact-s-m by "
        "--contact-force-n (the truth shown beside the estimate).",
        epilog=epilog("robot", "gauge_readings"),
    )
    _add_sensing_flags(p, 4)
    p.add_argument("--tension-n", required=True, help="tendon tensions in N, one per tendon ('' for none)")
    p.add_argument(
        "--contact-s-m",
        type=Flag(Plausible("m", 0.0, 100.0, "a place along the backbone, from its base")),
        help="where to press the twin: arc length from the base, m",
    )
    p.add_argument("--contact-force-n", help="the force to press the twin with, fx,fy,fz in N, world frame")
    add_plot_flag(
        p,
        "the backbone without the contact from the side (x-z) and the front (y-z) in mm, the estimated contact "
        "with its force's direction and where the twin was pressed",
    )


def _run(args: argparse.Namespace) -> CommandResult:
    if getattr(args, "record", None) is not None:  # refused before the solve, not after it
        from flexdigit._io import check_output

        check_output(args.record, force=args.force)
    if args.plot is not None:
        from flexdigit._plot import check_plot

        check_plot(args.plot, f"tdcr {args.tdcr_command}", force=args.force)
    if args.tdcr_command in ("shape", "contact"):
        return _sensing(args)
    if args.tdcr_command == "dynamics":
        return _dynamics(args)
    return _statics(args)


def _tensions(text: str, flag: str, robot) -> list[float]:
    if not robot.tendons and not text.strip():
        return []  # a rod without tendons: --tension-n ''
    tensions = _floats(text, flag)
    if len(tensions) != len(robot.tendons):
        raise ParameterError(
            f"--{flag} must give one tension per tendon of {robot.name!r} ({len(robot.tendons)}, in the order "
            f"of its description). Got {len(tensions)} in {text!r} instead."
        )
    return tensions


def _loads(args: argparse.Namespace) -> dict:
    return {
        key: _floats(text, flag, 3)
        for key, flag, text in (
            ("tip_force_n", "tip-force-n", args.tip_force_n),
            ("tip_moment_nm", "tip-moment-nm", args.tip_moment_nm),
            ("gravity_m_s2", "gravity-m-s2", args.gravity_m_s2),
        )
        if text is not None
    }


def _record(args: argparse.Namespace, robot, solution, tensions, loads) -> dict:
    """Write ``--record`` (a 3D recording, :func:`flexdigit.tdcr.write_recording`); its path for the result."""
    if args.record is None:
        return {}
    from flexdigit.tdcr import write_recording

    path = write_recording(
        args.record, robot, solution, tensions_n=tensions, tip_force_n=loads.get("tip_force_n"), force=args.force
    )
    return {"recording": str(path)}


def _plot(args: argparse.Namespace, draw) -> dict:
    """``--plot``: the figure ``draw()`` returns (a :mod:`flexdigit.tdcr.robot_plot` one), saved; its path for the
    result (empty without ``--plot``)."""
    if args.plot is None:
        return {}
    from flexdigit._plot import save_plot

    return {"plot": str(save_plot(draw(), args.plot, f"tdcr {args.tdcr_command}", force=args.force))}


def _start(args: argparse.Namespace, robot) -> dict:
    """Where ``tdcr dynamics`` starts from: the statics of ``--from-tension-n`` (zero) and ``--from-tip-force-n``."""
    start = {"tensions_n": [0.0] * len(robot.tendons)}
    if args.from_tension_n is not None:
        start["tensions_n"] = _tensions(args.from_tension_n, "from-tension-n", robot)
    if args.from_tip_force_n is not None:
        start["tip_force_n"] = _floats(args.from_tip_force_n, "from-tip-force-n", 3)
    return start


def _dynamics(args: argparse.Namespace) -> CommandResult:
    import warnings

    from flexdigit.errors import ConvergenceWarning
    from flexdigit.tdcr import get_robot, simulate, solve_statics, trajectory_figure

    robot = get_robot(args.robot)
    tensions = _tensions(args.tension_n, "tension-n", robot)
    loads = _loads(args)
    start = _start(args, robot)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # reported below, in the result and the exit code
        initial = solve_statics(
            robot, start["tensions_n"], gravity_m_s2=loads.get("gravity_m_s2"), tip_force_n=start.get("tip_force_n")
        )
        motion = simulate(
            robot, initial, args.duration_s, dt_s=args.dt_s, tensions_n=tensions, method=args.method, **loads
        )
    converged = initial.converged and motion.converged
    record = {**_record(args, robot, motion, tensions, loads), **_plot(args, lambda: trajectory_figure(motion, robot))}
    data = {
        "robot": robot.name,
        "tensions_n": tensions,
        **loads,
        "initial": {"converged": initial.converged, "tip_position_m": initial.tip_position_m.tolist(), **start},
        "converged": converged,
        "dt_s": args.dt_s,
        "method": args.method,
        "t_s": motion.t_s.tolist(),
        "tip_position_m": motion.tip_positions_m.tolist(),
        "newton_iterations": motion.iterations.tolist(),
        **record,
    }
    tip0, tip1 = initial.tip_position_m * 1e3, motion.tip_positions_m[-1] * 1e3
    lines = [
        f"{robot.name}: {motion.t_s[-1]:.4g} s in steps of {args.dt_s:g} s",
        f"tip from ({tip0[0]:.3f}, {tip0[1]:.3f}, {tip0[2]:.3f}) mm",
        f"      to ({tip1[0]:.3f}, {tip1[1]:.3f}, {tip1[2]:.3f}) mm",
        f"converged: {converged}",
        *(f"{'recording' if key == 'recording' else 'plot ->'} {path}" for key, path in record.items()),
    ]
    return CommandResult(data=data, text="\n".join(lines), exit_code=0 if converged else 1)


def _newton_said(sol) -> str:
    """What the shooting did: Newton's iterations, or none when its start (the clamp wrench of the loads on the
    straight rod: zero under tendons alone, whose pull is internal) already met the tip's balance."""
    if sol.iterations == 0:
        return (
            "no Newton step needed: the start, the straight rod's clamp wrench, met the tip, "
            f"residual {sol.residual:.2g}"
        )
    return f"{sol.iterations} Newton iterations, residual {sol.residual:.2g}"


def _statics(args: argparse.Namespace) -> CommandResult:
    import warnings

    from flexdigit.errors import ConvergenceWarning
    from flexdigit.tdcr import get_robot, solve_statics, statics_figure

    robot = get_robot(args.robot)
    tensions = _tensions(args.tension_n, "tension-n", robot)
    loads = _loads(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # reported below, in the result and the exit code
        sol = solve_statics(robot, tensions, **loads)
    record = {**_record(args, robot, sol, tensions, loads), **_plot(args, lambda: statics_figure(sol, robot))}
    data = {"robot": robot.name, "tensions_n": tensions, **loads, **sol.to_dict(), **record}
    tip = sol.tip_position_m * 1e3
    lines = [
        f"{robot.name}: {len(robot.tendons)} tendons, {len(robot.segments)} segments, {robot.length_m * 1e3:g} mm",
        f"tip position: ({tip[0]:.3f}, {tip[1]:.3f}, {tip[2]:.3f}) mm",
        "tip frame (columns: x, y, z axes; last: position in m):",
        *("  " + "  ".join(f"{v:+.6f}" for v in row) for row in sol.tip_frame[:3]),
        f"converged: {sol.converged} ({_newton_said(sol)})",
        *(f"{'recording' if key == 'recording' else 'plot ->'} {path}" for key, path in record.items()),
    ]
    return CommandResult(data=data, text="\n".join(lines), exit_code=0 if sol.converged else 1)


def _readings(args: argparse.Namespace, robot) -> dict:
    """``--strains`` / ``--readings`` as ``sense_*``'s ``strains`` and ``layout`` (empty: the twin reads)."""
    from flexdigit.tdcr import gauge_layout, read_readings

    if args.strains is not None and args.readings is not None:
        raise ParameterError("give the readings one way: --strains or --readings FILE.csv, not both")
    if args.readings is not None:
        layout, strains = read_readings(args.readings, robot)
        return {"layout": layout, "strains": strains}
    if args.strains is None:
        return {}
    layout = gauge_layout(robot, args.stations_per_segment)
    strains = _floats(args.strains, "strains")
    if len(strains) != layout.s_m.size:
        per = layout.s_m.size // (args.stations_per_segment * len(robot.segments))
        raise ParameterError(
            f"--strains must give one reading per gauge of the layout on {robot.name!r}: {layout.s_m.size} "
            f"({args.stations_per_segment} stations x {len(robot.segments)} segments x {per} gauges, see --help). "
            f"Got {len(strains)} instead."
        )
    return {"layout": layout, "strains": strains}


def _mm(p) -> str:
    return "({:.3f}, {:.3f}, {:.3f}) mm".format(*(1e3 * float(v) for v in p))


def _write_out(args: argparse.Namespace, data: dict) -> None:
    if args.out is None:
        return
    import json

    from flexdigit._io import atomic_write
    from flexdigit._json import to_jsonable

    with atomic_write(args.out, "w", force=args.force) as fh:
        json.dump(to_jsonable(data), fh, indent=1)
    data["out"] = str(args.out)


def _sensing(args: argparse.Namespace) -> CommandResult:
    from flexdigit._io import check_output
    from flexdigit.tdcr import get_robot

    for path in (args.out, getattr(args, "record", None)):  # refused before the work, not after it
        if path is not None:
            check_output(path, force=args.force)
    robot = get_robot(args.robot)
    given = _readings(args, robot)
    common = {"noise_std": args.noise_std, "seed": args.seed, "stations_per_segment": args.stations_per_segment}
    if given and args.noise_std:
        raise ParameterError("--noise-std is added to the twin's readings: it does not apply to --strains/--readings")
    head = {"robot": robot.name, "source": "readings" if given else "twin", "noise_std": args.noise_std}
    head["seed"] = args.seed
    if args.tdcr_command == "shape":
        data, lines = _shape(args, robot, given, common)
    else:
        data, lines = _contact(args, robot, given, common)
    data = {**head, **data}
    if data.get("refused"):  # no place or force to stand behind: nothing written, and the exit code says so
        return CommandResult(data=data, text="\n".join(lines), exit_code=1)
    _write_out(args, data)
    if "out" in data:
        lines.append(f"written: {data['out']}")
    return CommandResult(data=data, text="\n".join(lines))


def _shape(args, robot, given: dict, common: dict) -> tuple[dict, list[str]]:
    from flexdigit.tdcr import sense_shape

    if not given and args.tension_n is None:
        raise ParameterError(
            "tdcr shape needs readings (--strains or --readings FILE.csv) or the loads to read the twin under "
            "(--tension-n T1,...,Tn)"
        )
    loads = _loads(args)
    tensions = None if args.tension_n is None else _tensions(args.tension_n, "tension-n", robot)
    found = sense_shape(robot, given.get("strains"), layout=given.get("layout"), tensions_n=tensions, **loads, **common)
    data = {"tensions_n": tensions, **loads, **found.to_dict(robot)}
    if args.record is not None:
        from flexdigit.tdcr import write_recording

        pulls = [0.0] * len(robot.tendons) if tensions is None else tensions
        disks = found.estimate.at_disks(robot)
        tip = loads.get("tip_force_n")
        path = write_recording(args.record, robot, disks, tensions_n=pulls, tip_force_n=tip, force=args.force)
        data["recording"] = str(path)
    if args.plot is not None:
        from flexdigit._plot import save_plot
        from flexdigit.tdcr import backbone_figure

        data["plot"] = str(save_plot(backbone_figure(found, robot), args.plot, "tdcr shape", force=args.force))
    source = "given readings" if given else f"the twin's readings, noise {args.noise_std:g}, seed {args.seed}"
    lines = [
        f"{robot.name}: shape from {found.layout.s_m.size} gauges ({source})",
        f"estimated tip: {_mm(found.estimate.tip_position_m)}",
    ]
    if found.twin is not None:
        lines += [
            f"twin's tip:    {_mm(found.twin.tip_position_m)}",
            f"tip error {1e3 * found.tip_error_m:.4f} mm, largest along the backbone {1e3 * found.max_error_m:.4f} "
            f"mm, tip angle {found.tip_angle_error_deg:.4f} deg",
        ]
    if "recording" in data:
        lines.append(f"recording: {data['recording']}")
    if "plot" in data:
        lines.append(f"plot -> {data['plot']}")
    return data, lines


def _estimate_lines(est) -> list[str]:
    """The contact's place and force with their sigmas, or that it is out of sight; a barely seen force said."""
    import numpy as np

    if est.out_of_sight:
        return [
            f"out of sight: the readings fit a contact at or nearer the base than {1e3 * est.visible_from_m:.1f} mm, "
            "where one gauge station at most sees it: place and force not determined"
        ]
    if not est.refined:
        return [
            f"no fit: the twin holds no equilibrium under the first-order estimate ({np.linalg.norm(est.force_n):.3g} "
            f"N at {1e3 * est.s_m:.1f} mm): these readings are not a point contact the robot can bear"
        ]
    f, sd = est.force_n, est.force_std_n
    lines = [
        f"at s = {1e3 * est.s_m:.1f} mm" + f" +- {1e3 * est.s_std_m:.2g}" + f", {_mm(est.position_m)}",
        "force ({}) mN".format(", ".join(f"{1e3 * v:.3f} +- {1e3 * e:.2g}" for v, e in zip(f, sd, strict=True))),
    ]
    if est.strain_rms > _POOR_FIT:
        lines.append(
            f"poor fit: {est.strain_rms * 1e6:.3g} microstrain RMS of the readings left unexplained (not one point "
            "contact, or the twin's model is off): the numbers above are only the best such fit"
        )
    if np.linalg.norm(sd) > _UNCERTAIN * np.linalg.norm(f):
        lines.append(
            f"uncertain: the gauges barely see this force (one sigma {1e3 * np.linalg.norm(sd):.3g} mN, more "
            f"than {_UNCERTAIN:.0%} of its size)"
        )
    return lines


def _contact(args, robot, given: dict, common: dict) -> tuple[dict, list[str]]:
    from flexdigit.tdcr import sense_contact

    tensions = _tensions(args.tension_n, "tension-n", robot)
    force = None if args.contact_force_n is None else _floats(args.contact_force_n, "contact-force-n", 3)
    if given and (force is not None or args.contact_s_m is not None):
        raise ParameterError("--contact-s-m/--contact-force-n press the twin: give them or readings, not both")
    if not given and (force is None or args.contact_s_m is None):
        raise ParameterError(
            "tdcr contact needs readings (--strains or --readings FILE.csv) or a contact to press the twin with "
            "(--contact-s-m S --contact-force-n fx,fy,fz)"
        )
    found = sense_contact(
        robot,
        tensions,
        given.get("strains"),
        layout=given.get("layout"),
        contact_s_m=args.contact_s_m,
        contact_force_n=force,
        **common,
    )
    est = found.estimate
    data = {"tensions_n": tensions, **found.to_dict()}
    unseen = data["unseen_direction"]
    said = _estimate_lines(est)
    data["refused"] = said[0] if est.out_of_sight or not est.refined else None  # exit 1, its reason one line
    lines = [
        f"{robot.name}: contact from {found.layout.s_m.size} gauges (visible beyond {1e3 * est.visible_from_m:.1f} mm)",
        *said,
    ]
    if unseen is not None:
        lines.append("unseen: the force along ({:+.3f}, {:+.3f}, {:+.3f}) makes no moment at any gauge".format(*unseen))
    if found.true_s_m is not None:
        lines.append(
            f"twin pressed at s = {1e3 * found.true_s_m:.1f} mm: place error {1e3 * found.place_error_m:.2f} mm, "
            f"force error {1e3 * found.force_error_n:.3f} mN"
            + (" (nearer the base than the gauges can see)" if found.true_s_m < est.visible_from_m else "")
        )
    if args.plot is not None and data["refused"] is None:
        from flexdigit._plot import save_plot
        from flexdigit.tdcr import contact_figure

        data["plot"] = str(save_plot(contact_figure(found, robot), args.plot, "tdcr contact", force=args.force))
        lines.append(f"plot -> {data['plot']}")
    return data, lines

"""``flexdigit tdcr statics|dynamics ROBOT --tension-n T1,...,Tn [...] [--json]``: a tendon robot in 3D.

ROBOT is a built-in name (``rao2021``) or a robot TOML file (:mod:`flexdigit.tdcr.description`). ``statics``
prints the tip position and frame and, under ``--json``, the backbone (every disk) as well. ``dynamics`` starts
from the static shape under ``--from-tension-n`` / ``--from-tip-force-n`` (default: straight), applies the given
loads at t = 0 and prints the tip's path. A solve that does not converge is reported with ``converged: false``
and exit code 1. ``--record OUT.mcap`` also writes the shape(s) as an MCAP recording with a
``foxglove.SceneUpdate`` channel (:mod:`flexdigit.tdcr.scene`): it opens in Foxglove's 3D panel.
"""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command
from flexdigit._validation import Flag, Plausible
from flexdigit.errors import ParameterError


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
    vector = "(world frame; write a leading minus as --{}=-1,0,0)"
    p.add_argument("--tip-force-n", help="tip force fx,fy,fz in N " + vector.format("tip-force-n"))
    p.add_argument("--tip-moment-nm", help="tip moment mx,my,mz in N m " + vector.format("tip-moment-nm"))
    p.add_argument("--gravity-m-s2", help="gravity gx,gy,gz in m/s^2, base frame (default: none)")
    p.add_argument("--record", metavar="OUT.mcap", help="also write an MCAP recording with a 3D view (Foxglove)")
    p.add_argument("--force", action="store_true", help="replace the --record file if it exists")
    p.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the result as JSON")
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
    p.add_argument("--force", action="store_true", help="replace the --record file if it exists")
    p.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the result as JSON")


def _run(args: argparse.Namespace) -> CommandResult:
    if args.record is not None:  # refused before the solve, not after it
        from flexdigit._io import check_output

        check_output(args.record, force=args.force)
    if args.tdcr_command == "dynamics":
        return _dynamics(args)
    return _statics(args)


def _tensions(text: str, flag: str, robot) -> list[float]:
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
    from flexdigit.tdcr import get_robot, simulate, solve_statics

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
    record = _record(args, robot, motion, tensions, loads)
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
        *([f"recording: {record['recording']}"] if record else []),
    ]
    return CommandResult(data=data, text="\n".join(lines), exit_code=0 if converged else 1)


def _statics(args: argparse.Namespace) -> CommandResult:
    import warnings

    from flexdigit.errors import ConvergenceWarning
    from flexdigit.tdcr import get_robot, solve_statics

    robot = get_robot(args.robot)
    tensions = _tensions(args.tension_n, "tension-n", robot)
    loads = _loads(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # reported below, in the result and the exit code
        sol = solve_statics(robot, tensions, **loads)
    record = _record(args, robot, sol, tensions, loads)
    data = {"robot": robot.name, "tensions_n": tensions, **loads, **sol.to_dict(), **record}
    tip = sol.tip_position_m * 1e3
    lines = [
        f"{robot.name}: {len(robot.tendons)} tendons, {len(robot.segments)} segments, {robot.length_m * 1e3:g} mm",
        f"tip position: ({tip[0]:.3f}, {tip[1]:.3f}, {tip[2]:.3f}) mm",
        "tip frame (columns: x, y, z axes; last: position in m):",
        *("  " + "  ".join(f"{v:+.6f}" for v in row) for row in sol.tip_frame[:3]),
        f"converged: {sol.converged} ({sol.iterations} Newton iterations, residual {sol.residual:.2g})",
        *([f"recording: {record['recording']}"] if record else []),
    ]
    return CommandResult(data=data, text="\n".join(lines), exit_code=0 if sol.converged else 1)

"""``flexdigit tdcr statics ROBOT --tension-n T1,...,Tn [...] [--json]``: a tendon robot's static shape.

ROBOT is a built-in name (``rao2021``) or a robot TOML file (:mod:`flexdigit.tdcr.description`). Prints the tip
position and frame and, under ``--json``, the backbone (every disk) as well. A solve that does not converge is
reported with ``converged: false`` and exit code 1.
"""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command
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
    p = sub.add_parser("statics", help="static equilibrium under tendon tensions and tip loads")
    p.add_argument("robot", metavar="ROBOT", help="a built-in robot (rao2021) or a robot TOML file")
    p.add_argument("--tension-n", required=True, help="tendon tensions in N, one per tendon: '4,0,0,0,2,0'")
    vector = "(world frame; write a leading minus as --{}=-1,0,0)"
    p.add_argument("--tip-force-n", help="tip force fx,fy,fz in N " + vector.format("tip-force-n"))
    p.add_argument("--tip-moment-nm", help="tip moment mx,my,mz in N m " + vector.format("tip-moment-nm"))
    p.add_argument("--gravity-m-s2", help="gravity gx,gy,gz in m/s^2, base frame (default: none)")
    p.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the result as JSON")


def _run(args: argparse.Namespace) -> CommandResult:
    import warnings

    from flexdigit.errors import ConvergenceWarning
    from flexdigit.tdcr import get_robot, solve_statics

    robot = get_robot(args.robot)
    tensions = _floats(args.tension_n, "tension-n")
    if len(tensions) != len(robot.tendons):
        raise ParameterError(
            f"--tension-n must give one tension per tendon of {robot.name!r} ({len(robot.tendons)}, in the order "
            f"of its description). Got {len(tensions)} in {args.tension_n!r} instead."
        )
    loads = {
        key: _floats(text, flag, 3)
        for key, flag, text in (
            ("tip_force_n", "tip-force-n", args.tip_force_n),
            ("tip_moment_nm", "tip-moment-nm", args.tip_moment_nm),
            ("gravity_m_s2", "gravity-m-s2", args.gravity_m_s2),
        )
        if text is not None
    }
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)  # reported below, in the result and the exit code
        sol = solve_statics(robot, tensions, **loads)
    data = {"robot": robot.name, "tensions_n": tensions, **loads, **sol.to_dict()}
    tip = sol.tip_position_m * 1e3
    lines = [
        f"{robot.name}: {len(robot.tendons)} tendons, {len(robot.segments)} segments, {robot.length_m * 1e3:g} mm",
        f"tip position: ({tip[0]:.3f}, {tip[1]:.3f}, {tip[2]:.3f}) mm",
        "tip frame (columns: x, y, z axes; last: position in m):",
        *("  " + "  ".join(f"{v:+.6f}" for v in row) for row in sol.tip_frame[:3]),
        f"converged: {sol.converged} ({sol.iterations} Newton iterations, residual {sol.residual:.2g})",
    ]
    return CommandResult(data=data, text="\n".join(lines), exit_code=0 if sol.converged else 1)

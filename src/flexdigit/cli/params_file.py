"""``flexdigit params``: show, check or write the rig parameters."""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = add_command(subparsers, "params", _params, help="show, check or write the rig parameters (TOML)")
    parser.add_argument("file", nargs="?", help="a rig TOML to load and check (default: the thesis rig)")
    parser.add_argument("--write", metavar="FILE", help="write the parameters (defaults, or FILE's) as TOML")
    parser.add_argument("--force", action="store_true", help="overwrite the --write file if it exists")


def _params(args: argparse.Namespace) -> CommandResult:
    from flexdigit.params import RigParams, load_params, save_params

    params = load_params(args.file) if args.file else RigParams()
    data = params.to_dict()
    derived = {
        "second_moment_m4": params.geometry.second_moment_m4,
        "bending_stiffness_n_m2": params.bending_stiffness_n_m2,
        "rad_per_command": params.actuator.rad_per_command,
        "deg_per_command": params.actuator.deg_per_command,
        "pot_v_per_command": params.actuator.pot_v_per_command,
        "adc_lsb_v": params.sensors.adc_lsb_v,
    }
    lines = [f"rig parameters ({args.file or 'thesis defaults'}):"]
    for section, values in data.items():
        lines.append(f"[{section}]")
        lines.extend(f"  {k} = {v}" for k, v in values.items())
    lines.append("derived:")
    lines.extend(f"  {k} = {v:.6g}" for k, v in derived.items())
    if args.write:
        path = save_params(params, args.write, force=args.force)
        lines.append(f"written to {path}")
    return CommandResult(data={"params": data, "derived": derived, "written": args.write}, text="\n".join(lines))

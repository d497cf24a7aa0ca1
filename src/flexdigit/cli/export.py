"""``flexdigit export controller``: the controller as C99 for a microcontroller, and the analysis of its
quantisation (issue 25; :mod:`flexdigit.control.c_export`).

* ``flexdigit export controller --out ctrl.c [--design digital20] [--period-s 0.02] [--format float|fixed]``
  ``[--params D.toml [--calibration C.toml]] [--input-max X] [--prefix P] [--rotation-map FILE | --no-rotation-map]``
  ``[--force] [--json]``

With ``--params`` (issue 24) the export is that digit's own 20 ms design (``flexdigit run --params`` runs the same
one on the host: :func:`flexdigit.control.design20ms.digit_design_20ms`, two outputs, the tip and the gauges' fused
rotation), its rotation map over its G gauges (calibrated on its twin, as ``run --params`` makes it, or
``--rotation-map``), its straight command and range (a cable pair straightens mid-range: its commands are signed
about it), and the runtime's dither (the rounding error carried to the next sample), as the host loop runs it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from flexdigit._command import CommandResult, add_command
from flexdigit._validation import Flag, Plausible

#: Designs ``flexdigit export controller`` knows (those of ``flexdigit run --controller``).
EXPORT_DESIGNS = ("digital20", "thesis39-euler", "thesis39-tustin")


def register(subparsers) -> None:
    parser = subparsers.add_parser("export", help="export a controller as C for a microcontroller (issue 25)")
    sub = parser.add_subparsers(title="export commands", metavar="WHAT")
    parser.set_defaults(
        func=lambda args: CommandResult(data=None, text=parser.format_help(), exit_code=2), command_name="export"
    )
    p = add_command(
        sub,
        "controller",
        _export_controller,
        help="write the discretised controller as one C99 file + header (float32 or fixed point) and analyse it",
    )
    p.set_defaults(command_name="export controller")
    p.add_argument("--out", type=Path, required=True, help="the C source to write (the header goes beside it, .h)")
    p.add_argument("--design", default="digital20", help=f"one of {', '.join(EXPORT_DESIGNS)} (default digital20)")
    p.add_argument(
        "--period-s",
        type=Flag(Plausible("s", 1e-4, 1.0, "a control period: 0.1 ms (the ADC) to 1 s (the digit rings at 2 Hz)")),
        default=0.020,
        help="sample period, s, 1e-4..1 (default 0.020)",
    )
    p.add_argument("--format", choices=("float", "fixed"), default="float", help="float32 or fixed point")
    p.add_argument(
        "--input-max",
        type=Flag(Plausible("", 1e-6, 1e4, "the controller's input in deg (or m for thesis39-*): 1e-6..1e4")),
        default=None,
        help="largest |controller input| the fixed point must hold (default 180 deg; 0.3 m for thesis39-*)",
    )
    p.add_argument("--prefix", default="fd_ctrl", help="C identifier prefix (default fd_ctrl)")
    p.add_argument(
        "--params", type=Path, default=None, metavar="FILE", help="the digit's parameters TOML (default: thesis rig)"
    )
    p.add_argument(
        "--calibration",
        type=Path,
        default=None,
        metavar="FILE",
        help="the digit's twin calibration TOML (default: the thesis's scaled to the digit)",
    )
    maps = p.add_mutually_exclusive_group()
    maps.add_argument(
        "--rotation-map", type=Path, default=None, help="gauge -> rotation map JSON (default: calibrated on the twin)"
    )
    maps.add_argument("--no-rotation-map", action="store_true", help="export the update on (r, y) only")
    p.add_argument("--force", action="store_true", help="replace existing output files")


def _export_controller(args: argparse.Namespace) -> CommandResult:
    from flexdigit._io import check_output
    from flexdigit._validation import check_choice, check_real
    from flexdigit.control.c_export import ControllerSpec, export_controller

    design = check_choice(args.design, "--design", EXPORT_DESIGNS, "flexdigit export controller")
    period = check_real(args.period_s, "--period-s", low=1e-4, high=1.0)
    check_output(args.out, force=args.force)  # before any design work
    params = _digit(args, design)
    if params is not None:
        runtime, plant_d, rotation, scale, input_max = _digit_export_design(params, period, args)
    else:
        runtime, plant_d, rotation, scale, input_max = _export_design(design, period, args)
    if args.input_max is not None:
        input_max = check_real(args.input_max, "--input-max", low=0.0, low_open=True)
    spec = ControllerSpec.from_runtime(runtime, rotation, setpoint_scale=scale)
    setpoints = [s * scale for s in (0.0, 10.0, 30.0)]  # the rotations of the loop's tests, deg
    if params is not None and params.cables.count == 2:
        setpoints.append(-30.0)  # a cable pair bends both ways
    result = export_controller(
        spec, args.out, format=args.format, input_max=input_max, plant_d=plant_d, setpoints=setpoints,
        prefix=args.prefix, force=args.force,
    )  # fmt: skip
    a = result.analysis
    code = 0 if (a.closed_loop_stable is not False) else 1
    data = _export_data(args, design, period, result, spec, scale)
    return CommandResult(data=data, text=f"wrote {result.source_path} and {result.header_path}\n{a!r}", exit_code=code)


def _export_data(args, design: str, period: float, result, spec, scale: float) -> dict:
    """``export controller --json``: the files, the design, the digit's map and commands, the analysis."""
    rotation = spec.rotation
    return {
        "source": str(result.source_path),
        "header": str(result.header_path),
        "format": result.format,
        "design": design,
        "period_s": period,
        "prefix": result.prefix,
        "rotation_map": None if rotation is None else {"coef": list(rotation.coef), "offset": rotation.offset},
        "setpoint_scale": scale,
        "params": None if args.params is None else str(args.params),
        "gauges": None if rotation is None else rotation.gauges,
        "straight_command": int(round(spec.u_eq)),
        "command_range": [spec.u_min, spec.u_max],
        "dither": spec.dither,
        "analysis": result.analysis.to_dict(),
    }


def _export_design(design: str, period: float, args):
    """The runtime controller, its design plant (discrete), the rotation map, the setpoint scale and input range."""
    import control as ct
    import numpy as np

    from flexdigit.control.c_export import RotationMap
    from flexdigit.control.design20ms import design_20ms, thesis_controller
    from flexdigit.models.conversion import k3_printed_mm_per_v
    from flexdigit.models.plant import build_plant
    from flexdigit.params import RigParams

    params = RigParams()
    estimator, rest = None, None
    if not args.no_rotation_map or design != "digital20":
        from flexdigit.rig.base import open_rig
        from flexdigit.rig.rotation import calibrate_rotation, load_rotation_map

        with open_rig("sim") as rig:
            estimator = load_rotation_map(args.rotation_map) if args.rotation_map else calibrate_rotation(rig)
            rest = np.array([rig.read().gauges_v for _ in range(5)])
        estimator.tare(rest)
    if design == "digital20":
        d = design_20ms(params, period_s=period)
        rotation = None if args.no_rotation_map else RotationMap.from_estimator(estimator)
        return d.runtime(params), d.plant_d, rotation, 1.0, 180.0
    method = "forward_euler" if design.endswith("euler") else "tustin"
    k3 = k3_printed_mm_per_v()[0] / 1000.0  # m per V of gauge 1 (E 3.23)
    tare_v = float(np.mean(rest[:, 0]))
    rotation = None if args.no_rotation_map else RotationMap((k3, 0.0, 0.0), -tare_v * k3, unit="m")
    scale = k3 * float(estimator.gauge_v_per_deg_[0])
    plant_d = ct.sample_system(ct.ss(build_plant("printed", params).tf), period, method="zoh")
    return thesis_controller(method, period, params), plant_d, rotation, scale, 0.3


def _digit(args, design: str):
    """The digit ``--params`` describes, or None for the thesis rig (no ``--params``, or a file describing it)."""
    from flexdigit.errors import ParameterError

    if args.params is None:
        if args.calibration is not None:
            raise ParameterError(
                f"--calibration {args.calibration} is a digit's twin calibration: give its --params FILE too"
            )
        return None
    from flexdigit.params import load_params

    params = load_params(args.params)
    if params.is_thesis_rig() and args.calibration is None:
        return None  # the thesis rig: chapter 5's design, as without --params
    if design != "digital20":
        raise ParameterError(
            f"--design {design} is the thesis rig's printed H-infinity controller on gauge 1: with --params "
            f"{args.params} only --design digital20 (the digit's own 20 ms design) is exported"
        )
    return params


def _check_board_window(params, calibration, orientation: str, source) -> None:
    """Refuse, in one line naming the file, each gauge and its volts, a digit whose amplified bridges leave the
    board's ADC window over its operating range (:func:`flexdigit.rig.gauge_rails.board_rail_lines`: the image
    would build and then fault "adc_rail" at run time), saying the gain that fits each."""
    from flexdigit.errors import ParameterError
    from flexdigit.rig.gauge_rails import board_rail_lines

    railing = board_rail_lines(params, calibration, orientation=orientation)
    if railing:
        raise ParameterError(f"{source}: " + "; ".join(railing))


def _digit_export_design(params, period: float, args):
    """A described digit's export: the controller ``flexdigit run --params`` runs on the host (its own 20 ms design
    on the rotation per command its map's sweep measured, dithered), its discrete design plant, the rotation map
    over its gauges (calibrated on its twin, tared at rest), setpoint scale 1 and input range 180 deg."""
    import math

    import numpy as np

    from flexdigit.control.c_export import RotationMap
    from flexdigit.control.design20ms import digit_design_20ms, digit_mount
    from flexdigit.errors import ParameterError
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import calibrate_rotation, load_rotation_map
    from flexdigit.twin.digit_calibration import twin_calibration

    calibration = twin_calibration(params, args.calibration)  # the file, else the digit's default
    # tip up, a digit that buckles under its supports' weight is mounted hanging (as run --params mounts its twin)
    orientation = digit_mount(params, calibration)
    _check_board_window(params, calibration, orientation, args.params)
    with open_rig("sim", params, calibration=calibration, orientation=orientation) as rig:
        estimator = load_rotation_map(args.rotation_map) if args.rotation_map else calibrate_rotation(rig)
        rest = np.array([rig.read().gauges_v for _ in range(5)])
    gauges = len(params.geometry.gauge_positions_m)
    weights = np.asarray(estimator.coef_).reshape(-1).size
    if weights != gauges:
        raise ParameterError(
            f"--rotation-map {args.rotation_map} weighs {weights} gauge(s); the digit in {args.params} has {gauges}"
        )
    estimator.tare(rest)
    measured = getattr(estimator, "deg_per_command_", None)
    measured = measured if isinstance(measured, float) and math.isfinite(measured) and measured > 0 else None
    own = None if args.calibration is None else calibration
    d = digit_design_20ms(params, period_s=period, calibration=own, orientation=orientation, deg_per_command=measured)
    runtime = d.runtime(params, name="digital20", dither=not params.is_thesis_rig())  # as run --params runs it
    rotation = None if args.no_rotation_map else RotationMap.from_estimator(estimator)
    return runtime, d.plant_d, rotation, 1.0, 180.0

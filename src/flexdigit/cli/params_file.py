"""``flexdigit params``: show, check or write a digit's description (the rig parameters)."""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command


def register(subparsers: argparse._SubParsersAction) -> None:
    from flexdigit.cli._formats import epilog

    parser = add_command(subparsers, "params", _params, help="show, check or write the rig parameters (TOML)")
    parser.epilog = epilog("params")
    parser.add_argument("file", nargs="?", help="a rig TOML to load and check (default: the thesis rig)")
    parser.add_argument("--write", metavar="FILE", help="write the parameters (defaults, or FILE's) as TOML")
    parser.add_argument("--template", metavar="FILE", help="write an annotated description of the thesis rig")
    parser.add_argument(
        "--write-calibration",
        metavar="FILE",
        help="write the twin calibration every command uses for this digit when given no --calibration (the "
        "thesis's fit, scaled to the digit by the physics: docs/digits.md) as TOML, to read, edit and pass back",
    )
    parser.add_argument(
        "--force", action="store_true", help="overwrite the --write/--template/--write-calibration file if it exists"
    )


def _params(args: argparse.Namespace) -> CommandResult:
    from flexdigit.errors import ParameterError
    from flexdigit.params import (
        RigParams,
        derived_figures,
        description_notes,
        digit_inconsistencies,
        load_params,
        save_params,
    )

    if args.template:
        return _template(args)
    params = load_params(args.file, check=False) if args.file else RigParams()
    problems = digit_inconsistencies(params)
    # a file's gauges are checked against its ADC (statics: scipy); the thesis defaults keep `params` light
    notes = description_notes(params) + (_reach_notes(params) if args.file and not problems else [])
    data = params.to_dict()
    derived = derived_figures(params)
    lines = [f"rig parameters ({args.file or 'thesis defaults'}):"]
    for section, values in data.items():
        lines.append(f"[{section}]")
        lines.extend(f"  {k} = {_value(v)}" for k, v in values.items())
    lines.append("derived:")
    lines.extend(f"  {k} = {_figure(v)}" for k, v in derived.items())
    lines.extend(f"note: {n}" for n in notes)
    if problems:
        # refused through the one error path (stderr, "flexdigit params: error:", exit 2), every problem on its one
        # line, naming its key; a note may say why (the template's digit_length_m kept for shorter sections)
        raise ParameterError(f"{args.file}: " + "; ".join([*problems, *(f"note: {n}" for n in notes)]))
    # a file's twin is estimated (a static solve: scipy); the thesis defaults keep `params` light (docs/digits.md)
    twin, text = _resolution(params) if args.file else (None, [])
    lines.extend(text)
    if args.write:
        path = save_params(params, args.write, force=args.force)
        lines.append(f"written to {path}")
    if args.write_calibration:
        lines.append(f"twin calibration written to {_write_calibration(params, args)}")
    data = {"params": data, "derived": derived, "twin": twin, "problems": [], "notes": notes, "written": args.write}
    return CommandResult(data=data, text="\n".join(lines))


def _write_calibration(params, args: argparse.Namespace):
    """Save the default calibration of ``params``'s twin (``twin_calibration``), saying where it comes from."""
    from flexdigit.twin.calibration import save_calibration
    from flexdigit.twin.digit_calibration import twin_calibration

    if params.is_thesis_rig():  # the thesis rig, whatever its [twin]
        how = "the packaged fit to the thesis's records (the thesis rig)"
    else:
        how = "the thesis's fit scaled to this digit by the physics (flexdigit.twin.digit_calibration)"
    header = (
        f"# flexdigit twin calibration (SI units) of {args.file or 'the thesis rig'}: {how}.\n"
        "# Pass it back with --calibration FILE; `flexdigit calibrate` fits one to your records.\n"
    )
    return save_calibration(twin_calibration(params), args.write_calibration, force=args.force, header=header)


def _resolution(params) -> tuple[dict, list[str]]:
    """The twin's springs and its estimated static error, and the ``[twin]`` setting that meets 0.1 % when this one
    does not (``twin.resolution.resolution_advice``)."""
    from flexdigit.params import twin_cells
    from flexdigit.twin.resolution import CABLE_TIP_DEG, DERIVED_RTOL, TIP_LOAD_ALPHA2, resolution_advice

    advice = resolution_advice(params)
    error, rtol = advice.error, advice.rtol
    data = {"cells_per_section": list(error.cells), "static_error_tip_load": error.tip_load}
    data["static_error_cable"] = error.cable
    source = "its [twin] table" if not params.twin.is_default else "the default: cells <= 27 mm"
    if params.twin.is_default and error.cells != twin_cells(params):  # a derived calibration's finer default
        source = f"the default on its derived calibration: the fewest within {100 * DERIVED_RTOL:g} %"
    if not advice.determined:  # a static solve that did not converge: no figure rather than a wrong one
        return data, [
            f"twin: {sum(error.cells)} springs, {list(error.cells)} a section ({source}); static error not "
            "determined (the twin's static solve under the tip load or the cable did not converge)"
        ]
    lines = [
        f"twin: {sum(error.cells)} springs, {list(error.cells)} a section ({source}); static error against the "
        f"elastica (estimated, h^2 Richardson): {100 * error.tip_load:.3g} % under a tip load of "
        f"alpha^2 = {TIP_LOAD_ALPHA2:g}, {100 * error.cable:.3g} % under the cable turning the tip "
        f"{CABLE_TIP_DEG:g} deg"
    ]
    if not advice.acceptable:
        h, finer = advice.max_cell_length_m, advice.suggested_error
        data["max_cell_length_m_for_0.1_percent"] = h
        if h is None:
            lines.append(f"  no [twin] max_cell_length_m a twin takes meets {100 * rtol:g} % on this digit")
            return data, lines
        lines.append(
            f"  for {100 * rtol:g} %: [twin] max_cell_length_m = {h:g} ({list(finer.cells)} a section: "
            f"{100 * finer.tip_load:.3g} % | {100 * finer.cable:.3g} %; each step costs more)"
        )
    return data, lines


def _reach_notes(params) -> list[str]:
    """The gauges that reach an ADC rail inside the operating range, or read too coarsely for the loop (the
    digit's statics: :func:`flexdigit.rig.gauge_rails.gauge_rails`)."""
    from flexdigit.errors import FlexdigitError
    from flexdigit.rig.gauge_rails import gauge_rails, rail_lines, resolution_lines

    try:
        reaches = gauge_rails(params)
    except FlexdigitError as exc:  # a digit the statics cannot solve: the other commands say why
        return [f"the gauges' reach over the operating range was not computed ({exc})"]
    return rail_lines(reaches, params) + resolution_lines(reaches, params)


def _value(value) -> str:
    """A parameter as ``params`` prints it: floats to 12 significant digits, so a derived length reads 0.22, not
    0.22000000000000003 (a file keeps every digit)."""
    if isinstance(value, float):
        return f"{value:.12g}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return str(value)


def _figure(value) -> str:
    """A derived figure as ``params`` prints it: ``0.09`` or ``[0.005, 0.085]``."""
    if isinstance(value, list):
        return "[" + ", ".join(f"{v:.6g}" for v in value) + "]"
    return f"{value:.6g}"


def _template(args: argparse.Namespace) -> CommandResult:
    from flexdigit._io import atomic_write
    from flexdigit.errors import DataFileError
    from flexdigit.params import params_template

    try:
        with atomic_write(args.template, "w", force=args.force) as fh:
            fh.write(params_template())
    except FileExistsError:
        raise
    except OSError as exc:
        raise DataFileError(f"cannot write the template to {args.template}: {exc.strerror or exc}") from None
    return CommandResult(
        data={"template": args.template}, text=f"annotated thesis-rig description written to {args.template}"
    )

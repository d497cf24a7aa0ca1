"""``flexdigit calibrate``: fit the twin to a rig's records (or to the thesis) and write a calibration TOML.

Records (see :mod:`flexdigit.calibrate.record_files` for their columns): release tests bare and housed, an actuation
sweep, a deflection table, a record of the resting rig and repeated readings of the unloaded actuated digit; any
subset (what no record identifies keeps the starting calibration's value). Prints the residual of every target
(``--json`` too) and writes the calibration with its fit record, never over an existing file without ``--force``.
Every command that runs the twin takes the file with ``--calibration FILE``.
"""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command, digit_name
from flexdigit._plot import add_plot_flag
from flexdigit._validation import Flag

#: A fit that misses a release test's wn or zeta by more than this many percent, or a deflection by more than this
#: many reading resolutions, is refused (unless --allow-poor-fit): the twin cannot reproduce those records together
#: (records of different rigs or set-ups mixed, a unit slip, a gauge wired to the wrong channel...).
POOR_FIT = 3.0
RECORDS = ("release_bare", "release_housed", "sweep", "deflections", "rest", "actuated_rest")
#: How a digit is mounted for its records: tip up as the thesis's; a long digit buckles so and hangs (tip down).
MOUNTS = ("vertical", "hanging", "horizontal")
MOUNT_HELP = (
    "how the records' digit was mounted (default tip up, or hanging for a digit that buckles tip up, as flexdigit "
    "simulate and run mount it)"
)


def register(subparsers: argparse._SubParsersAction) -> None:
    p = add_command(
        subparsers,
        "calibrate",
        _calibrate,
        help="fit the twin to a rig's records (or to the thesis) and write a calibration TOML",
        description=__doc__.splitlines()[0],
    )
    from flexdigit.cli._formats import epilog

    p.epilog = epilog("calibration")
    p.add_argument("--out", required=True, help="calibration TOML to write")
    p.add_argument("--force", action="store_true", help="overwrite --out (and --plot) if it exists")
    add_plot_flag(p, "the twin's residual on every target")
    p.add_argument("--release-bare", action="append", metavar="FILE", help="release test without housing (repeatable)")
    p.add_argument("--release-housed", action="append", metavar="FILE", help="release test with housing (repeatable)")
    p.add_argument("--sweep", metavar="FILE", help="actuation sweep: command and the three gauges")
    p.add_argument("--deflections", metavar="FILE", help="deflection table: command and y1..y3 (mm, cm or m)")
    from flexdigit.rig.rotation_reference import READING_RESOLUTION_MM

    p.add_argument(
        "--deflection-resolution-mm",
        type=Flag(READING_RESOLUTION_MM),
        default=0.5,
        help="reading resolution (default 0.5)",
    )
    p.add_argument("--rest", metavar="FILE", help="the resting rig: time and the three gauges (noise levels)")
    p.add_argument(
        "--actuated-rest", metavar="FILE", help="repeated readings of the unloaded actuated digit (friction level)"
    )
    p.add_argument("--time-unit", choices=("s", "ms", "us"), help="unit of a time column named without one")
    p.add_argument("--orientation", choices=MOUNTS, default=None, help=MOUNT_HELP)
    p.add_argument(
        "--decimal", choices=(".", ","), default=None, help="decimal mark of the tables (default: detected per file)"
    )
    p.add_argument("--thesis", action="store_true", help="fit to the thesis's figures instead (minutes: the friction)")
    p.add_argument(
        "--allow-poor-fit",
        action="store_true",
        help=f"write the calibration even if the twin misses a target by more than {POOR_FIT:g} of its scale",
    )
    scaled = "calibration to start from (default: the packaged one, scaled to the digit of --params)"
    p.add_argument("--initial", metavar="FILE", help=scaled)
    p.add_argument("--params", metavar="FILE", help="rig parameters TOML (default: the thesis rig)")


def _calibrate(args: argparse.Namespace) -> CommandResult:
    from flexdigit._io import check_output
    from flexdigit._plot import check_plot
    from flexdigit.calibrate.twin_fit import THESIS_SOURCE, calibrate_to_thesis
    from flexdigit.params import RigParams, load_params
    from flexdigit.twin.calibration import load_calibration, save_calibration
    from flexdigit.twin.digit_calibration import twin_calibration

    given = _given_records(args)
    out = check_output(args.out, force=args.force)  # refuse a bad destination before minutes of fitting
    check_plot(args.plot, "calibrate", force=args.force)
    params = load_params(args.params) if args.params else RigParams()
    # a digit nobody has measured starts from the thesis's calibration scaled to it (one value per section, gauge)
    initial = load_calibration(args.initial) if args.initial else twin_calibration(params)
    mount = _mount(args, params, initial)
    if args.thesis:
        result, source, releases = calibrate_to_thesis(params), THESIS_SOURCE, {}
    else:
        result, source, releases = _fit_records(args, given, params, initial, out)
    fit = result.fit_record(source)
    fit.update({"release_tests": {key: _release_summary(fig) for key, fig in releases.items()}} if releases else {})
    save_calibration(result.calibration, out, fit, force=args.force)
    data = _result_data(result, fit, out, args.orientation)
    text = _calibrate_text(result, data, out) + f"\n{mount}" * bool(mount)
    if args.plot:
        from flexdigit._plot import save_plot
        from flexdigit.calibrate.residual_plot import residual_figure

        fig = residual_figure(result, limit=None if args.thesis else POOR_FIT, title=_plot_title(args, out))
        data["plot"] = str(save_plot(fig, args.plot, "calibrate", force=args.force))
        text += f"\nplot -> {args.plot}"
    return CommandResult(data=data, text=text)


def _result_data(result, fit: dict, out, orientation: str) -> dict:
    """What ``--json`` prints: the fit's outcome, residuals, calibration, release tests and notes."""
    row, miss = result.worst()
    return {
        "out": str(out),
        "success": result.success,
        "worst": None if row is None else {"target": row["target"], "times_scale": miss},
        "message": result.message,
        "cost": result.cost,
        "fitted": result.fitted,
        "kept": [name for name in result.calibration.to_dict() if name not in result.fitted],
        "residuals": result.residual_rows(),
        "calibration": result.calibration.to_dict(),
        "release_tests": fit.get("release_tests", {}),
        "notes": list(result.notes),
        "orientation": orientation,
    }


def _mount(args: argparse.Namespace, params, initial) -> str:
    """Set ``args.orientation`` when not given, as simulate, run and collect mount the digit
    (:func:`~flexdigit.control.design20ms.digit_mount`); the line that says it was hung (else empty)."""
    if args.orientation is not None:
        return ""
    from flexdigit.control.design20ms import digit_mount

    args.orientation = digit_mount(params, initial)
    if args.orientation == "vertical":
        return ""
    return (
        "mount: hanging (tip down): tip up this digit buckles under its own weight (as flexdigit simulate and run "
        "mount it; --orientation to say otherwise)"
    )


def _plot_title(args: argparse.Namespace, out) -> str:
    """``calibration cal.toml``, and whose digit when ``--params`` names one."""
    return f"calibration {out}" + (f" of digit {digit_name(args.params)}" if args.params else "")


def _given_records(args: argparse.Namespace) -> dict:
    """The record files given (flag name -> path or paths), the flags checked together."""
    from flexdigit.errors import ParameterError

    given = {name: getattr(args, name) for name in RECORDS if getattr(args, name)}
    if args.thesis and given:
        raise ParameterError("--thesis fits the thesis's figures: give it alone, without record files")
    if not args.thesis and not given:
        raise ParameterError(
            "nothing to calibrate: give record files (--release-bare, --release-housed, --sweep, --deflections, "
            "--rest, --actuated-rest) or --thesis"
        )
    if args.deflection_resolution_mm <= 0:
        raise ParameterError(
            f"--deflection-resolution-mm must be > 0 (the reading resolution). Got {args.deflection_resolution_mm!r}"
        )
    return given


def _fit_records(args, given: dict, params, initial, out):
    """Calibrate to the record files: ``(result, source line, release figures by key)``; a failed or poor fit
    (beyond ``--allow-poor-fit``) is refused naming what was missed."""
    import dataclasses

    from flexdigit.calibrate import record_files as rec
    from flexdigit.calibrate.targets import CalibrationTargets
    from flexdigit.calibrate.twin_fit import calibrate
    from flexdigit.errors import DesignError

    releases, release_targets = _release_targets(args, given)
    kw: dict = {"deflection_resolution_mm": args.deflection_resolution_mm}
    gauges = len(params.geometry.gauge_positions_m)  # the digit's gauges: gauge1 .. gaugeG in every record
    if "sweep" in given:
        kw["sweep"] = rec.read_sweep(given["sweep"], decimal=args.decimal, gauges=gauges)
    if "deflections" in given:
        kw["deflections"] = rec.read_deflections(given["deflections"], decimal=args.decimal, gauges=gauges)
    if "rest" in given:
        kw["rest"] = rec.read_rest(given["rest"], time_unit=args.time_unit, decimal=args.decimal, gauges=gauges)
    if "actuated_rest" in given:
        kw["actuated_rest"] = rec.read_actuated_rest(given["actuated_rest"], decimal=args.decimal, gauges=gauges)
    targets = dataclasses.replace(CalibrationTargets.from_records(**kw), **release_targets)
    result = calibrate(targets, params, initial=initial, orientation=args.orientation)
    if not result.success:
        raise DesignError(f"the fit did not converge ({result.message}); no calibration written to {out}")
    row, miss = result.worst()
    if miss > POOR_FIT and not args.allow_poor_fit:
        raise DesignError(
            f"the calibrated twin misses {row['target']} by {row['twin'] - row['measured']:+.4g} {row['unit']} "
            f"({miss:.1f} times its scale of {row['scale']:.3g} {row['unit']}): it cannot reproduce these records "
            f"together (different rigs or set-ups mixed? a unit slip?); no calibration written to {out} (pass "
            "--allow-poor-fit to write it anyway)"
        )
    source = "flexdigit calibrate " + " ".join(
        f"--{name.replace('_', '-')} {path}"
        for name, paths in given.items()
        for path in (paths if isinstance(paths, list) else [paths])
    )
    return result, source, releases


def _release_targets(args, given: dict) -> tuple[dict, dict]:
    """The release tests' figures by key (bare, housing) and the fit targets they give."""
    from flexdigit.calibrate import record_files as rec
    from flexdigit.calibrate.targets import release_figures

    releases: dict[str, dict] = {}
    targets: dict = {}
    for key, name in (("bare", "release_bare"), ("housing", "release_housed")):
        if name in given:
            read = [rec.read_release(path, time_unit=args.time_unit, decimal=args.decimal) for path in given[name]]
            series = [s for records in read for s in records]
            releases[key] = release_figures(series)
            targets[f"{key}_wn_rad_s"] = releases[key]["wn_rad_s"]
            targets[f"{key}_zeta"] = releases[key]["zeta"]
    return releases, targets


def _calibrate_text(result, data: dict, out) -> str:
    lines = [result.table(), ""]
    for key, summary in data["release_tests"].items():
        for r in summary["records"]:
            lines.append(f"release {key} {r['record']}: wn {r['wn_rad_s']:.4f} rad/s, zeta {r['zeta']:.5f}")
        for s in summary["skipped"]:
            lines.append(f"release {key} {s['record']}: not identified ({s['reason']})")
    lines.append("fitted: " + ", ".join(result.fitted))
    lines.append("kept from the starting calibration: " + (", ".join(data["kept"]) or "none"))
    lines.extend(data["notes"])
    lines.append(f"calibration written to {out}")
    return "\n".join(lines)


def _release_summary(figures: dict) -> dict:
    return {
        "wn_rad_s": figures["wn_rad_s"],
        "zeta": figures["zeta"],
        "records": [
            {"record": f"{f.source}:{f.channel}", "wn_rad_s": f.wn_rad_s, "zeta": f.zeta, "fit_percent": f.fit_percent}
            for f in figures["fits"]
        ],
        "skipped": figures["skipped"],
    }

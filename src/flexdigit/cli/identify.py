"""``flexdigit identify release|step FILE``: a second-order model from a recorded release or step test."""

from __future__ import annotations

import argparse

from flexdigit._plot import add_plot_flag
from flexdigit._validation import Flag, Plausible


def register(subparsers: argparse._SubParsersAction) -> None:
    from flexdigit._command import add_command

    parser = add_command(
        subparsers,
        "identify",
        _identify,
        help="identify a second-order model from a release or step test recording (CSV/Parquet)",
        description=(
            "Identify wn and zeta from a recorded release test (free decay of the digit, thesis 3.1.2) or step "
            "test (the servo, 3.2.4). The recording has a time column (time_s, time_ms, 'Time (ms)', or time with "
            "--time-unit) and channels named with their unit (sg1_v, pot_v; the twin's files say gauge1_v), "
            "separated by commas, semicolons, tabs or spaces; an optional command column gives the input step. "
            "The step or release instant is found from the record (either direction, with or without a baseline "
            "before it; mains hum removed, spikes and drift allowed for) and reported with the fit's quality. A "
            "record that cannot be identified with confidence exits with status 2 and says why, unless --force."
        ),
    )
    from flexdigit.cli._formats import epilog

    parser.epilog = epilog("record")
    parser.add_argument("kind", choices=("release", "step"), help="the experiment")
    parser.add_argument("file", help="the recording (.csv or .parquet)")
    parser.add_argument(
        "--channel",
        help="column to analyse, with or without its unit, in any case (sg1 for 'SG1 (V)'); sg1 and gauge1 name the "
        "same strain gauge "
        "(default: the first channel)",
    )
    parser.add_argument(
        "--method",
        choices=("thesis", "lsq", "arx"),
        default="lsq",
        help="lsq: least-squares fit with confidence intervals (default); thesis: %%OS and wn = 4/(zeta Ts); "
        "arx: dominant poles of a discrete ARX model of the filtered record",
    )
    parser.add_argument(
        "--filter", choices=("butter", "svd", "fft", "none"), default="butter", help="filter for the features"
    )
    parser.add_argument("--time-unit", choices=("s", "ms", "us"), help="unit of a time column named without one")
    parser.add_argument(
        "--t0",
        type=Flag(Plausible("s", -1e7, 1e7, "an instant on the record's clock: within about 4 months of its zero")),
        help="step/release instant in s on the record's clock (default: found from the record)",
    )
    parser.add_argument(
        "--delay",
        choices=("auto", "yes", "no"),
        default="auto",
        help="lsq: fit the step instant too (a dead time); auto: when the record has samples before the step",
    )
    parser.add_argument(
        "--input-step",
        type=Flag(Plausible("", -1e6, 1e6, "an input step in the input's own unit (51 commands, 2 V)")),
        help="size of the input step (e.g. 51 commands) for the gain",
    )
    parser.add_argument(
        "--loss",
        choices=("soft_l1", "huber", "linear"),
        default="soft_l1",
        help="lsq: loss of the fit; soft_l1 (default) and huber keep isolated spikes from biasing it, linear is "
        "plain least squares",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="print the fit even when the record cannot be identified with confidence (the reasons are printed "
        "as warnings, exit status 0); also overwrite an existing --plot file",
    )
    add_plot_flag(parser, "the fitted model over the record and its residual")
    parser.add_argument(
        "--allow-overdamped",
        action="store_true",
        help="fit a release that never undershoots its final value, or a step or release whose fit is overdamped "
        "(zeta >= 1; lsq/arx); by default such a record is refused: the digit's release test is an oscillating "
        "decay, and without an overshoot wn and zeta are poorly told apart",
    )


def _identify(args: argparse.Namespace):
    from flexdigit._command import CommandResult
    from flexdigit._plot import check_plot, save_plot
    from flexdigit.identify.fit_plot import fit_figure
    from flexdigit.identify.identification import identify
    from flexdigit.identify.timeseries import read_timeseries

    check_plot(args.plot, "identify", force=args.force)
    series = read_timeseries(args.file, args.channel, time_unit=args.time_unit)
    result = identify(
        series,
        args.kind,
        method=args.method,
        smoothing=args.filter,
        t0_s=args.t0,
        input_step=args.input_step,
        fit_delay={"auto": None, "yes": True, "no": False}[args.delay],
        allow_overdamped=args.allow_overdamped,
        loss=args.loss,
        force=args.force,
    )
    data = result.summary()
    lines = _report_lines(args, series, result, data)
    if args.plot:
        data["plot"] = str(save_plot(fit_figure(series, result), args.plot, "identify", force=args.force))
        lines.append(f"  plot -> {args.plot}")
    return CommandResult(data=data, text="\n".join(lines))


def _report_lines(args: argparse.Namespace, series, result, data: dict) -> list[str]:
    """The text report of an identification: the record, the instant figures, wn and zeta with their intervals,
    the thesis's formulas, the model, its validation and quality, and the warnings."""
    unit = f" {series.unit}" if series.unit else ""
    how = f", {args.loss} loss" if args.method == "lsq" else ""
    lines = [
        f"{args.kind} test {series.source} (channel {series.channel}{unit}, {series.n_samples} samples "
        f"at {series.sample_rate_hz:.6g} Hz), method {args.method}{how}:",
        _instant_line(result, series),
        f"  wn   = {result.wn_rad_s:.6g} rad/s" + _ci(result, "wn_rad_s"),
        f"  zeta = {result.zeta:.6g}" + _ci(result, "zeta"),
    ]
    if result.features is not None:
        f = result.features
        lines += [
            f"  %OS = {f.percent_overshoot:.6g}, peak time {f.peak_time_s:.4g} s, rise time {f.rise_time_s:.4g} s, "
            f"2% settling time {f.settling_time_s:.4g} s",
            f"  thesis formulas: zeta(%OS) = {f.zeta_os:.4g}, wn = 4/(zeta Ts) = {f.wn_settling_rad_s:.5g} rad/s, "
            f"wn = wd/sqrt(1-zeta^2) = {f.wn_damped_rad_s:.5g} rad/s",
        ]
    num, den = data["tf_num"], data["tf_den"]
    lines += [
        f"  model: {num[0]:.6g} / (s^2 + {den[1]:.6g} s + {den[2]:.6g})",
        f"  validation: corr2 = {result.corr2:.4f}, NRMSE fit = {result.fit_percent:.2f} %",
    ]
    lines += _quality_lines(result, unit)
    lines += [f"  warning: {w}" for w in result.warnings]
    return lines


def _instant_line(result, series) -> str:
    """Where the step or release is, and how it was found."""
    sv = result.survey
    what = "step" if result.kind == "step" else "release"
    where = f"  {what} at t = {result.t0_s:.6g} s"
    if series.time_unit != "s":
        scale = {"ms": 1e3, "us": 1e6}[series.time_unit]
        where += f" ({result.t0_s * scale:.6g} {series.time_unit} on the file's clock)"
    origin = {
        "signal": "found from the signal",
        "command": f"from the {series.input_name!r} column",
        "given": "as given (--t0)",
    }[sv.found_from]
    extra = []
    if sv.found_from != "given" and result.method == "lsq":
        extra.append("fitted")
    extra.append(f"{sv.baseline_s:.3g} s of baseline before it" if sv.baseline_s > 0 else "no baseline before it")
    if result.kind == "step" and sv.direction:
        extra.append("step " + ("up" if sv.direction > 0 else "down"))
    return f"{where}, {origin} ({', '.join(extra)})"


def _quality_lines(result, unit: str) -> list[str]:
    q, sv = result.quality, result.survey
    lb = q.whiteness
    white = "white" if q.summary()["whiteness"]["white"] else "NOT white"
    lines = [
        f"  quality: misfit {q.misfit_percent:.2g} % of the response, residuals {white} (Ljung-Box p = "
        f"{lb.p_value:.2g}, {lb.lags} lags of {q.block_s * 1e3:.3g} ms blocks)"
    ]
    record = [f"noise {sv.noise_std:.3g}{unit}", f"{sv.spikes.size} spike{'s' if sv.spikes.size != 1 else ''}"]
    if sv.hum is not None:
        record.append(f"{sv.hum.frequency_hz:.4g} Hz hum of {sv.hum.amplitude:.3g}{unit} removed")
    if result.drift_per_s:
        record.append(f"drift {result.drift_per_s:.3g}{unit}/s")
    lines.append("  record: " + ", ".join(record))
    return lines


def _ci(result, name: str) -> str:
    if not result.estimates or name not in result.estimates:
        return ""
    e = result.estimates[name]
    return f"  (95% CI {e.ci_low:.6g} .. {e.ci_high:.6g})"

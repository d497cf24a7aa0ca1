"""``flexdigit identify release|step FILE``: a second-order model from a recorded release or step test."""

from __future__ import annotations

import argparse


def register(subparsers: argparse._SubParsersAction) -> None:
    from flexdigit._command import add_command

    parser = add_command(
        subparsers,
        "identify",
        _identify,
        help="identify a second-order model from a release or step test recording (CSV/Parquet)",
        description=(
            "Identify wn and zeta from a recorded release test (free decay of the digit, thesis 3.1.2) or step "
            "test (the servo, 3.2.4). The recording has a time column (time_s, or time with --time-unit) and "
            "channels named with their unit (sg1_v, pot_v; the twin's files say gauge1_v); an optional command "
            "column gives the input step."
        ),
    )
    parser.add_argument("kind", choices=("release", "step"), help="the experiment")
    parser.add_argument("file", help="the recording (.csv or .parquet)")
    parser.add_argument(
        "--channel",
        help="column to analyse, with or without its unit; sg1 and gauge1 name the same strain gauge "
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
    parser.add_argument("--t0", type=float, help="step/release instant in s (default: found from the data)")
    parser.add_argument(
        "--delay",
        choices=("auto", "yes", "no"),
        default="auto",
        help="lsq: fit the step instant too (a dead time); auto: when the record has samples before the step",
    )
    parser.add_argument("--input-step", type=float, help="size of the input step (e.g. 51 commands) for the gain")
    parser.add_argument(
        "--allow-overdamped",
        action="store_true",
        help="release: fit a decay that never undershoots its final value (lsq/arx); by default such a record is "
        "refused, since the digit's release test is an oscillating decay",
    )


def _identify(args: argparse.Namespace):
    from flexdigit._command import CommandResult
    from flexdigit.identify.identification import identify
    from flexdigit.identify.timeseries import read_timeseries

    series = read_timeseries(args.file, args.channel, time_unit=args.time_unit)
    result = identify(
        series,
        args.kind,
        method=args.method,
        filter=args.filter,
        t0_s=args.t0,
        input_step=args.input_step,
        fit_delay={"auto": None, "yes": True, "no": False}[args.delay],
        allow_overdamped=args.allow_overdamped,
    )
    data = result.summary()
    unit = f" {series.unit}" if series.unit else ""
    lines = [
        f"{args.kind} test {series.source} (channel {series.channel}{unit}, {series.n_samples} samples "
        f"at {series.sample_rate_hz:.6g} Hz), method {args.method}:",
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
    return CommandResult(data=data, text="\n".join(lines))


def _ci(result, name: str) -> str:
    if not result.estimates or name not in result.estimates:
        return ""
    e = result.estimates[name]
    return f"  (95% CI {e.ci_low:.6g} .. {e.ci_high:.6g})"

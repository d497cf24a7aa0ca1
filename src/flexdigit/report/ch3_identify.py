"""Report chapter 3 (identification): release and step tests to models, the thesis's way and by least squares.

Beside 3.1.2 (release tests, tables 3.1 and 3.2, E(s), figure 3.6), 3.2.4 (servo step tests, FFT and SVD
filters, MT(s), figures 3.11 and 3.12) and 3.4 (the linear fits behind K1 and K3). The closed-form checks of
the printed tables are in the models chapter; this one runs the identification on records: synthetic second-order
ones with known parameters (to measure each method's error) and the twin's simulated release and step tests
(:mod:`flexdigit.twin.records`, default calibration), from which E(s) and MT(s) are identified as the thesis
identified them from the rig.
"""

from __future__ import annotations

import math

import numpy as np

from flexdigit.identify.filters import fft_filter, noise_reduction, svd_filter
from flexdigit.identify.fit import fit_linear, second_order_response
from flexdigit.identify.identification import average_runs, identify
from flexdigit.identify.response import settling_formula_bias
from flexdigit.identify.timeseries import TimeSeries, series_from_table
from flexdigit.reference import thesis_value
from flexdigit.report.chapter import Chapter, ReportContext, ResultTable
from flexdigit.report.results import Entry, compare, new

SECTION_DIGIT = "3.1.2"
SECTION_SERVO = "3.2.4"
#: Synthetic records: sampling period (s) and white noise (fraction of the response amplitude).
DT_S = 0.002
NOISE = 0.02
#: Input step of the thesis's servo tests (3.2.4: "an input serial command of 51").
STEP_COMMANDS = 51


def build(ctx: ReportContext) -> Chapter:
    """Build the identification chapter."""
    chapter = Chapter(slug="ch3-identify", title="Chapter 3: system identification (release and step tests)")
    chapter.paragraphs.append(
        "The thesis identified each component from one experiment: release tests of the digit (zeta from the "
        "percent overshoot, wn = 4/(zeta Ts) from the 2 % settling time, 3.1.2), step tests of the servo filtered "
        "with an FFT or an SVD filter (3.2.4), validated with MATLAB's corr2. flexdigit.identify does the same "
        "(method 'thesis') and fits the whole raw record by least squares with confidence intervals (method "
        "'lsq'). The release test's %OS is the first undershoot past the final value relative to the initial "
        "deflection, the overshoot of the mirrored step: with the thesis's formula it maps 99.7485 % to 0.0008 "
        "as in table 3.1."
    )
    e = chapter.entries
    _wn_formula_bias(ctx, chapter, e)
    _tables_from_records(ctx, chapter, e)
    _noise_study(ctx, chapter, e)
    _models_from_experiments(ctx, chapter, e)
    _filters(ctx, chapter, e)
    _linear_fits(chapter, e)
    _voltage_fits(ctx, chapter, e)
    chapter.paragraphs.append(_summary(e))
    return chapter


def _summary(entries: list[Entry]) -> str:
    """One paragraph of the chapter's findings, from its own entries."""
    v = {x.key: x.ours for x in entries}

    def pct(key: str) -> str:
        return f"{100 * v['identify.' + key]:.1f} %"

    servo_off = v["identify.servo.thesis.wn_rad_s"] / v["identify.servo.lsq.wn_rad_s"] - 1
    return (
        "Findings. From the twin's release test (gauge 1) the least-squares fit gives wn = "
        f"{v['identify.digit.lsq.wn_rad_s']:.3f} rad/s, zeta = {v['identify.digit.lsq.zeta']:.4f}, and from its "
        f"servo steps wn = {v['identify.servo.lsq.wn_rad_s']:.3f} rad/s, zeta = {v['identify.servo.lsq.zeta']:.4f} "
        "(thesis: 13.0995, 0.06791; 20.53, 0.5629). The thesis method on the same records gives "
        f"{v['identify.digit.thesis.wn_rad_s']:.2f} and {v['identify.servo.thesis.wn_rad_s']:.2f} rad/s: its "
        f"wn = 4/(zeta Ts) is {pct('wn_settling_formula.bias_digit')} high at the digit's damping and "
        f"{pct('wn_settling_formula.bias_servo')} high at the servo's even without noise. On noisy synthetic "
        "records with known parameters, the largest lsq errors are "
        f"{pct('noisy_release.lsq.zeta_max_abs_rel_error')} (release zeta) and "
        f"{pct('noisy_step.lsq.wn_max_abs_rel_error')} (step wn), against "
        f"{pct('noisy_release.thesis.wn_max_abs_rel_error')} and {pct('noisy_step.thesis.wn_max_abs_rel_error')} "
        "for the thesis method's wn. corr2, the thesis's validation figure, is "
        f"{v['identify.servo.thesis.validation_corr2']:.4f} for the thesis method's servo model although its wn is "
        f"{100 * servo_off:.0f} % off (figure 3.12 analogue): it hardly sees a wrong wn; the NRMSE fit does."
    )


# --- the thesis's wn = 4 / (zeta Ts) --------------------------------------------------------------------------
def _wn_formula_bias(ctx: ReportContext, chapter: Chapter, e: list[Entry]) -> None:
    p = ctx.params
    zd, zs = p.dynamics.zeta_housing, p.actuator.servo_zeta
    bias_digit, bias_servo = (float(b) for b in settling_formula_bias([zd, zs]))
    e.append(
        new(
            "identify.wn_settling_formula.bias_digit",
            SECTION_DIGIT,
            bias_digit,
            "",
            f"Relative error of wn = 4/(zeta Ts) on an exact second-order response with the digit's zeta = {zd} "
            "(Ts the true 2 % settling time): the envelope reaches 2 % at ln(50)/(zeta wn) = 3.91/(zeta wn), and the "
            "last exit from the band comes up to half a period earlier.",
        )
    )
    e.append(
        new(
            "identify.wn_settling_formula.bias_servo",
            SECTION_SERVO,
            bias_servo,
            "",
            f"The same at the servo's zeta = {zs}: the response leaves the 2 % band for the last time on its first "
            "overshoot, well before the envelope does, so 4/(zeta Ts) overestimates wn by this much.",
        )
    )
    e.append(
        new(
            "identify.wn_settling_formula.servo_wn_if_read_from_ts",
            SECTION_SERVO,
            p.actuator.servo_wn_rad_s / (1 + bias_servo),
            "rad/s",
            f"If the printed {p.actuator.servo_wn_rad_s} rad/s came from 4/(zeta Ts) on a noise-free second-order "
            "servo, its true natural frequency would be this (the thesis text says wn was 'calculated using the "
            "settling time'). Table 3.2's wn column, by contrast, is wd/sqrt(1 - zeta^2) to 5e-6 rad/s.",
        )
    )
    zetas = np.linspace(0.005, 0.95, 60 if ctx.fast else 190)
    bias = settling_formula_bias(zetas, points_per_period=200 if ctx.fast else 400)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.4))
    ax.plot(zetas, 100 * bias, lw=1.2)
    ax.axhline(100 * (4 / math.log(50) - 1), color="grey", ls=":", lw=1, label="envelope limit 4/ln 50 - 1")
    ax.plot([zd, zs], [100 * bias_digit, 100 * bias_servo], "o", color="C3", label="digit, servo")
    ax.set_xlabel("damping ratio zeta")
    ax.set_ylabel("error of 4/(zeta Ts) (%)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    chapter.figures.append(
        ctx.save_figure(
            fig,
            "ch3_identify_wn_bias",
            "Error of the thesis's wn = 4/(zeta Ts) on exact second-order responses with the true 2 % settling "
            f"time: {100 * bias[zetas < 0.1].min():+.0f} to {100 * bias[zetas < 0.1].max():+.0f} % for zeta < 0.1, "
            f"jumping between {100 * bias[zetas > 0.3].min():+.0f} % and {100 * bias[zetas > 0.3].max():+.0f} % "
            "above zeta = 0.3 as the last exit from the band moves from one extremum to the next.",
        )
    )


# --- tables 3.1 and 3.2 from release records ------------------------------------------------------------------
def _release_record(wn: float, zeta: float, t_end: float, rng: np.random.Generator, noise: float = NOISE):
    """A synthetic release test: 1 V deflection held 0.3 s, released, plus white noise (fraction of it)."""
    t = np.arange(0.0, t_end, DT_S)
    y = second_order_response(t, "release", wn, zeta, 0.0, 1.0, 0.3) + rng.normal(0, noise, t.size)
    return TimeSeries.from_arrays(t, y, channel="sg1", unit="V", source="synthetic release")


def _tables_from_records(ctx: ReportContext, chapter: Chapter, e: list[Entry]) -> None:
    rng = ctx.rng(31)
    for table, name, t_end in (("3.1", "without_housing", 20.0), ("3.2", "with_housing", 8.0)):
        t = thesis_value(f"digit.release_tests_{name}")
        zetas, wns = np.asarray(t["zeta"]), np.asarray(t["wn_rad_s"])
        rows = []
        got = {"thesis_zeta": [], "thesis_wn": [], "lsq_zeta": [], "lsq_wn": []}
        n_rows = 3 if ctx.fast else len(zetas)
        for i in range(n_rows):
            rec = _release_record(wns[i], zetas[i], t_end, rng, noise=0.002)
            th = identify(rec, "release", method="thesis", wn_from="damped")
            ls = identify(rec, "release", method="lsq")
            got["thesis_zeta"].append(th.zeta)
            got["thesis_wn"].append(th.wn_rad_s)
            got["lsq_zeta"].append(ls.zeta)
            got["lsq_wn"].append(ls.wn_rad_s)
            rows.append(
                (
                    i + 1,
                    zetas[i],
                    th.features.percent_overshoot,
                    th.zeta,
                    ls.zeta,
                    wns[i],
                    th.wn_rad_s,
                    ls.wn_rad_s,
                    th.features.settling_time_s,  # inf: the record ends before it settles
                )
            )
        chapter.tables.append(
            ResultTable(
                f"identify.table_{table.replace('.', '_')}_from_records",
                f"Table {table} from synthetic release records ({t_end:g} s, 0.2 % noise) with the printed zeta and "
                "wn (thesis method: wn from the damped frequency; settling time inf: not reached in the record)",
                (
                    "test",
                    "zeta_printed",
                    "percent_overshoot_measured",
                    "zeta_thesis_method",
                    "zeta_lsq",
                    "wn_printed_rad_s",
                    "wn_thesis_method_rad_s",
                    "wn_lsq_rad_s",
                    "settling_2_percent_s",
                ),
                tuple(rows),
            )
        )
        key = f"identify.table_{table.replace('.', '_')}"
        truth_zeta, truth_wn = float(np.mean(zetas[:n_rows])), float(np.mean(wns[:n_rows]))
        for method in ("thesis", "lsq"):
            z_avg = float(np.mean(got[f"{method}_zeta"]))
            wn_avg = float(np.mean(got[f"{method}_wn"]))
            e.append(
                new(
                    f"{key}.{method}_zeta_avg_rel_error",
                    SECTION_DIGIT,
                    z_avg / truth_zeta - 1,
                    "",
                    f"Mean zeta identified by the {method} method from {n_rows} synthetic release records built "
                    f"with table {table}'s printed zeta and wn (0.2 % noise), relative to the mean printed zeta.",
                )
            )
            e.append(
                new(
                    f"{key}.{method}_wn_avg_rel_error",
                    SECTION_DIGIT,
                    wn_avg / truth_wn - 1,
                    "",
                    f"The same for wn ({'wd/sqrt(1-zeta^2), as the table did' if method == 'thesis' else 'fitted'}).",
                )
            )
    chapter.paragraphs.append(
        "Table 3.1's damping (zeta = 0.0008-0.005) cannot give wn = 4/(zeta Ts): the 2 % settling time would be "
        "4/(zeta wn) = 80-490 s, so the table's wn can only come from the damped frequency. Its wn column is "
        "wd/sqrt(1 - zeta^2) with zeta = 0.025-0.029, not with its own zeta column (see the models chapter), which "
        "is the damping the plant G(s) of 3.5 needs. With a lightly damped record the first undershoot alone "
        "gives zeta to about +-0.001 at 0.2 % noise, so table 3.1's zetas are at the resolution of the method."
    )


# --- the same noisy records, both methods -----------------------------------------------------------------------
def _noise_study(ctx: ReportContext, chapter: Chapter, e: list[Entry]) -> None:
    p = ctx.params
    seeds = 4 if ctx.fast else 20
    truth = {
        "release": (p.dynamics.wn_housing_rad_s, p.dynamics.zeta_housing),
        "step": (p.actuator.servo_wn_rad_s, p.actuator.servo_zeta),
    }
    rows = []
    for kind, (wn, zeta) in truth.items():
        rng = ctx.rng(40 if kind == "release" else 41)
        err = {m: [] for m in ("lsq", "arx", "thesis")}
        for _ in range(seeds):
            if kind == "release":
                rec = _release_record(wn, zeta, 8.0, rng)
                t0 = None
            else:
                rec = _step_record(wn, zeta, rng)
                t0 = None
            for method in err:
                r = identify(rec, kind, method=method, t0_s=t0)
                err[method].append((r.wn_rad_s / wn - 1, r.zeta / zeta - 1))
        for method, values in err.items():
            a = np.asarray(values)
            rows.append(
                (
                    kind,
                    method,
                    100 * a[:, 0].mean(),
                    100 * np.abs(a[:, 0]).max(),
                    100 * a[:, 1].mean(),
                    100 * np.abs(a[:, 1]).max(),
                )
            )
            for j, par in enumerate(("wn", "zeta")):
                e.append(
                    new(
                        f"identify.noisy_{kind}.{method}.{par}_max_abs_rel_error",
                        SECTION_DIGIT if kind == "release" else SECTION_SERVO,
                        float(np.abs(a[:, j]).max()),
                        "",
                        f"Largest |relative error| of {par} over {seeds} synthetic {kind} records with known "
                        f"parameters (the thesis's {'digit' if kind == 'release' else 'servo'}) and white noise of "
                        f"{100 * NOISE:g} % of the response; issue 4 asks lsq for < 2 %."
                        + (
                            " The thesis method's error is mostly the bias of 4/(zeta Ts)."
                            if method == "thesis"
                            else ""
                        ),
                    )
                )
    chapter.tables.append(
        ResultTable(
            "identify.noisy_records",
            f"Errors over {seeds} noisy synthetic records ({100 * NOISE:g} % white noise): thesis method, lsq, ARX",
            (
                "test",
                "method",
                "wn_mean_error_percent",
                "wn_max_abs_error_percent",
                "zeta_mean_error_percent",
                "zeta_max_abs_error_percent",
            ),
            tuple(rows),
        )
    )


def _step_record(wn: float, zeta: float, rng: np.random.Generator, noise: float = NOISE, gain: float = 0.0079):
    """A synthetic servo step test: command 8 -> 8 + 51 at 0.2 s, pot volts with white noise."""
    t = np.arange(0.0, 2.0, DT_S)
    amp = gain * STEP_COMMANDS
    y = second_order_response(t, "step", wn, zeta, 0.4669, amp, 0.2) + rng.normal(0, noise * amp, t.size)
    u = np.where(t >= 0.2, 8.0 + STEP_COMMANDS, 8.0)
    return TimeSeries.from_arrays(t, y, channel="pot", unit="V", u=u, source="synthetic step")


# --- E(s) and MT(s) from experiments ----------------------------------------------------------------------------
def _experiments(ctx: ReportContext):
    """The twin's release test of the digit (gauge 1, as 3.5 uses) and its servo step tests (51 commands).

    Returns the release record (gauge 1 and tip deflection), the step records and a phrase naming their origin.
    """
    from flexdigit.twin.records import release_test, servo_step_test

    duration, rate = (5.0, 500.0) if ctx.fast else (8.0, 1000.0)
    rel = release_test(duration_s=duration, sample_rate_hz=rate, seed=ctx.seed, params=ctx.params)
    release, tip = series_from_table(rel, "gauge1"), series_from_table(rel, "tip_deflection")
    steps = [
        series_from_table(
            servo_step_test(command_to=STEP_COMMANDS, sample_rate_hz=rate, seed=ctx.seed + k, params=ctx.params), "pot"
        )
        for k in range(3 if ctx.fast else 5)
    ]
    return release, tip, steps, "the twin's default calibration"


def _models_from_experiments(ctx: ReportContext, chapter: Chapter, e: list[Entry]) -> None:
    import matplotlib.pyplot as plt

    release, tip, steps, origin = _experiments(ctx)
    step = average_runs(steps)
    # the thesis filtered the servo records with its SVD filter (3.2.4); rank 3 holds a step on an offset
    fits = {("digit", m): identify(release, "release", method=m) for m in ("thesis", "lsq")} | {
        ("servo", m): identify(step, "step", method=m, filter="svd") for m in ("thesis", "lsq")
    }
    tip_fits = {m: identify(tip, "release", method=m) for m in ("thesis", "lsq")}
    printed = {
        "digit": (
            thesis_value("digit.release_tests_with_housing.wn_avg_rad_s"),
            thesis_value("digit.release_tests_with_housing.zeta_avg"),
            thesis_value("digit.model.validation_corr2"),
        ),
        "servo": (
            thesis_value("actuator.model.wn_rad_s"),
            thesis_value("actuator.model.zeta"),
            thesis_value("actuator.model.validation_corr2"),
        ),
    }
    rows = []
    for (model, method), r in fits.items():
        wn_p, zeta_p, corr_p = printed[model]
        section = SECTION_DIGIT if model == "digit" else SECTION_SERVO
        rows.append((model, method, wn_p, r.wn_rad_s, zeta_p, r.zeta, *_intervals(r), r.corr2, r.fit_percent))
        why = (
            "The thesis method's wn = 4/(zeta Ts) carries the bias of identify.wn_settling_formula.* plus the noise "
            "in the settling time read off a filtered record."
        )
        why_zeta = "%OS is read off one extremum of a filtered noisy record, so it moves with the noise and the filter."
        if model == "digit":
            tz = tip_fits["thesis"].zeta
            why += " On gauge 1 the settling time is also short because the zeta it starts from is low (next entry)."
            why_zeta = (
                "The digit is a continuous beam: released from the static shape of a tip force, not from its first "
                "mode shape, its strain near the clamp carries higher modes that the tip hardly shows, and these "
                "change the ratio of the first undershoot to the initial strain: gauge 1 reads %OS "
                f"{fits[('digit', 'thesis')].features.percent_overshoot:.2f} where the tip of the same release reads "
                f"{tip_fits['thesis'].features.percent_overshoot:.2f} (zeta {tz:.4f}, the mode's own "
                f"{100 * math.exp(-math.pi * zeta_p / math.sqrt(1 - zeta_p**2)):.2f} % at zeta {zeta_p}). One "
                "extremum of a noisy gauge also carries its noise. The least-squares fit of the whole record is not "
                "fooled on either channel."
            )
        e.append(
            compare(
                f"identify.{model}.{method}.wn_rad_s",
                section,
                wn_p,
                r.wn_rad_s,
                "rad/s",
                rtol=0.03,
                note=f"Identified from {origin} by the {method} method.",
                discrepancy_note=why,
            )
        )
        e.append(
            compare(
                f"identify.{model}.{method}.zeta",
                section,
                zeta_p,
                r.zeta,
                "",
                rtol=0.03,
                note=f"Identified from {origin} by the {method} method.",
                discrepancy_note=why_zeta,
            )
        )
        if method == "thesis":
            e.append(
                new(
                    f"identify.{model}.thesis.validation_corr2",
                    section,
                    r.corr2,
                    "",
                    f"corr2 of the thesis method's model against the same record (NRMSE fit {r.fit_percent:.1f} %).",
                )
            )
        if method == "lsq":
            e.append(
                compare(
                    f"identify.{model}.validation_corr2",
                    section,
                    corr_p,
                    r.corr2,
                    "",
                    rtol=0.01,
                    note="MATLAB corr2 between the recorded response and the identified model's.",
                    discrepancy_note="corr2 measures the noise of the record more than the model: it ignores gain and "
                    "offset errors and falls with the noise level, which for these records is the synthetic/twin "
                    "noise, not the rig's. The NRMSE fit (identify CLI, table) is the better figure.",
                )
            )
    for method, r in tip_fits.items():
        wn_p, zeta_p, _ = printed["digit"]
        rows.append(
            (
                f"digit (tip, {tip.unit})",
                method,
                wn_p,
                r.wn_rad_s,
                zeta_p,
                r.zeta,
                *_intervals(r),
                r.corr2,
                r.fit_percent,
            )
        )
        for par, value in (("wn_rad_s", r.wn_rad_s), ("zeta", r.zeta)):
            e.append(
                new(
                    f"identify.digit_tip.{method}.{par}",
                    SECTION_DIGIT,
                    value,
                    "rad/s" if par == "wn_rad_s" else "",
                    f"The same twin release test read at the tip (a measurement the rig did not have) by the {method} "
                    f"method; thesis: {wn_p if par == 'wn_rad_s' else zeta_p}.",
                )
            )
    chapter.tables.append(
        ResultTable(
            "identify.models_from_twin",
            f"Digit E(s) and servo MT(s) identified from {origin}, beside the thesis's (95 % confidence intervals of "
            "the lsq fits; NaN for the thesis method, which gives none)",
            (
                "model",
                "method",
                "wn_thesis_rad_s",
                "wn_ours_rad_s",
                "zeta_thesis",
                "zeta_ours",
                "wn_ci_low_rad_s",
                "wn_ci_high_rad_s",
                "zeta_ci_low",
                "zeta_ci_high",
                "corr2",
                "nrmse_fit_percent",
            ),
            tuple(rows),
        )
    )
    # figures 3.6 and 3.12: measured versus modelled
    for model, rec, kind, fig_name, ref in (
        ("digit", release, "release", "ch3_identify_release_validation", "figure 3.6"),
        ("servo", step, "step", "ch3_identify_step_validation", "figure 3.12"),
    ):
        fig, ax = plt.subplots(figsize=(6.5, 3.4))
        ax.plot(rec.t_s, rec.y, color="0.6", lw=0.6, label="twin record")
        for method, style in (("thesis", "--"), ("lsq", "-")):
            r = fits[(model, method)]
            ax.plot(
                rec.t_s,
                r.predict(rec.t_s),
                style,
                lw=1.2,
                label=f"{method}: wn {r.wn_rad_s:.2f} rad/s, zeta {r.zeta:.3f}, corr2 {r.corr2:.4f}",
            )
        ax.set_xlabel("time (s)")
        ax.set_ylabel(f"{rec.channel} ({rec.unit})")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        chapter.figures.append(
            ctx.save_figure(fig, fig_name, f"{model}: {kind} record ({origin}) against the identified models.", ref)
        )
    # figure 3.11: the runs, their average, and the two filters of 3.2.4
    fig, ax = plt.subplots(figsize=(6.5, 3.4))
    for r in steps:
        ax.plot(r.t_s, r.y, color="C3", lw=0.4, alpha=0.5)
    ax.plot(step.t_s, step.y, color="C0", lw=0.8, label=f"average of {len(steps)} runs")
    ax.plot(step.t_s, svd_filter(step.y, rank=3), color="k", lw=1.2, label="SVD filter, rank 3")
    ax.plot(step.t_s, fft_filter(step.y, 15), color="C2", lw=1.0, ls="--", label="FFT filter, N = 15")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("potentiometer (V)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    chapter.figures.append(
        ctx.save_figure(
            fig,
            "ch3_identify_step_runs",
            f"Servo step tests ({STEP_COMMANDS} commands, {origin}): runs (red), average (blue), filtered.",
            "figure 3.11",
        )
    )


# --- filters of 3.2.4 -------------------------------------------------------------------------------------------
def _filters(ctx: ReportContext, chapter: Chapter, e: list[Entry]) -> None:
    import matplotlib.pyplot as plt

    p = ctx.params
    rng = ctx.rng(60)
    t = np.arange(0.0, 2.0, DT_S)
    clean = second_order_response(t, "step", p.actuator.servo_wn_rad_s, p.actuator.servo_zeta, 0.0, 1.0, 0.2)
    noisy = clean + rng.normal(0, 0.05, t.size)
    harmonics = np.unique(np.geomspace(1, 500, 12 if ctx.fast else 30).astype(int))
    fft_red = [noise_reduction(clean, noisy, fft_filter(noisy, int(n))) for n in harmonics]
    ranks = np.arange(1, 9)
    svd_red = [noise_reduction(clean, noisy, svd_filter(noisy, rank=int(r))) for r in ranks]
    best_n = int(harmonics[int(np.argmax(fft_red))])
    e.append(
        new(
            "identify.filters.fft_best_harmonics",
            SECTION_SERVO,
            best_n,
            "harmonics",
            "FFT filter N that removes the most noise from a noisy servo step (2 s, 5 % noise). Fewer harmonics ring "
            "(Gibbs) and distort the step, more keep the noise: the trade-off 3.2.4 describes.",
        )
    )
    e.append(
        new(
            "identify.filters.fft_best_noise_reduction",
            SECTION_SERVO,
            float(max(fft_red)),
            "",
            "Fraction of the noise power the best FFT filter removes (distortion counted as noise).",
        )
    )
    e.append(
        new(
            "identify.filters.svd_rank3_noise_reduction",
            SECTION_SERVO,
            float(svd_red[2]),
            "",
            "The same for the SVD filter at rank 3 (a step on an offset); the thesis kept 2, which cannot hold the "
            f"offset and the transient together ({svd_red[1]:.2f} at rank 2).",
        )
    )
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(8, 3.2))
    a1.semilogx(harmonics, fft_red, "o-", ms=3)
    a1.set_xlabel("FFT filter: harmonics kept N")
    a1.set_ylabel("noise power removed (fraction)")
    a1.set_ylim(-1, 1)
    a2.plot(ranks, svd_red, "o-", ms=3)
    a2.set_xlabel("SVD filter: singular values kept")
    a2.set_ylim(-1, 1)
    for a in (a1, a2):
        a.grid(alpha=0.3)
    chapter.figures.append(
        ctx.save_figure(
            fig,
            "ch3_identify_filter_tradeoff",
            "Parameter trade-off of the two filters of 3.2.4 on a noisy servo step: too few harmonics ring, too many "
            "keep the noise; the SVD filter needs rank 3 for a step on an offset.",
        )
    )


# --- 3.4: linear fits with their uncertainty ---------------------------------------------------------------------
def _linear_fits(chapter: Chapter, e: list[Entry]) -> None:
    commands = np.asarray(thesis_value("conversion.table_3_4_commands"), dtype=float)
    printed = thesis_value("conversion.k1_fit")
    rows = []
    for k in range(3):
        y = np.asarray(thesis_value(f"conversion.table_3_6_y_sg{k + 1}_mm"), dtype=float)
        r = fit_linear(commands, y)
        a = float(printed[k]["a"])
        inside = r.slope.ci_low <= a <= r.slope.ci_high
        rows.append((k + 1, r.slope.value, r.slope.ci_low, r.slope.ci_high, a, bool(inside), r.rms, r.r_squared))
        e.append(
            new(
                f"identify.k1_fit.sg{k + 1}.slope_mm_per_command",
                "3.4.1",
                r.slope.value,
                "mm/command",
                f"Least-squares slope of table 3.6 (gauge {k + 1}), "
                f"95 % CI {r.slope.ci_low:.4f}..{r.slope.ci_high:.4f}; "
                f"the printed a = {a} is {'inside' if inside else 'outside'} it (the printed fits pass through "
                "command 8, see the models chapter).",
            )
        )
    chapter.tables.append(
        ResultTable(
            "identify.deflection_fits",
            "3.4.1: deflection vs command fits of table 3.6 with 95 % confidence intervals",
            (
                "gauge",
                "slope_lsq_mm_per_command",
                "slope_ci_low",
                "slope_ci_high",
                "a_printed_mm_per_command",
                "printed_inside_ci",
                "residual_rms_mm",
                "r_squared",
            ),
            tuple(rows),
        )
    )


def _voltage_fits(ctx: ReportContext, chapter: Chapter, e: list[Entry]) -> None:
    """E 3.20-3.22 from the twin's actuation sweep (commands 8..43, each settled): gauge volts vs command."""
    from flexdigit.twin.records import actuation_sweep

    sweep = actuation_sweep(samples=5 if ctx.fast else 20, seed=ctx.seed, params=ctx.params)
    commands = sweep.column("command").astype(float)
    printed = thesis_value("conversion.v_sg_fit")
    rows = []
    for k in range(3):
        r = fit_linear(commands, sweep.column(f"gauge{k + 1}_v"))
        slope_p, offset_p = float(printed[k]["slope"]), float(printed[k]["offset"])
        rows.append(
            (k + 1, slope_p, r.slope.value, r.slope.ci_low, r.slope.ci_high, offset_p, r.intercept.value)
            + (r.intercept.ci_low, r.intercept.ci_high, 1e3 * r.rms, r.r_squared)
        )
        e.append(
            compare(
                f"identify.v_sg_fit.sg{k + 1}.slope_v_per_command",
                "3.4.3",
                slope_p,
                r.slope.value,
                "V/command",
                rtol=0.03,
                note=f"Least-squares line through the twin's actuation sweep (E 3.2{k}); 95 % CI "
                f"{r.slope.ci_low:.5f}..{r.slope.ci_high:.5f}, residual RMS {1e3 * r.rms:.2f} mV.",
                discrepancy_note="The twin's calibration does not reproduce this fit of figure 3.17.",
            )
        )
    chapter.tables.append(
        ResultTable(
            "identify.voltage_fits",
            "3.4.3: gauge voltage vs command (E 3.20-3.22) fitted to the twin's actuation sweep, 95 % intervals",
            (
                "gauge",
                "slope_printed_v_per_command",
                "slope_ours_v_per_command",
                "slope_ci_low",
                "slope_ci_high",
                "offset_printed_v",
                "offset_ours_v",
                "offset_ci_low",
                "offset_ci_high",
                "residual_rms_mv",
                "r_squared",
            ),
            tuple(rows),
        )
    )


def _intervals(r) -> tuple[float, float, float, float]:
    """The 95 % intervals of wn and zeta of an lsq identification (NaN where the method gives none)."""
    if not r.estimates:
        return (math.nan,) * 4
    w, z = r.estimates["wn_rad_s"], r.estimates["zeta"]
    return w.ci_low, w.ci_high, z.ci_low, z.ci_high

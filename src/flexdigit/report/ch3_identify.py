"""Report chapter 3 (identification): release and step tests to models, the thesis's way and by least squares.

Beside 3.1.2 (release tests, tables 3.1 and 3.2, E(s), figure 3.6), 3.2.4 (servo step tests, FFT and SVD
filters, MT(s), figures 3.11 and 3.12) and 3.4 (the linear fits behind K1 and K3). The closed-form checks of
the printed tables are in the models chapter; this one shows
:func:`flexdigit.identify.chapter3_identification.chapter3_identify_study`:
the identification run on synthetic second-order records with known parameters (to measure each method's error)
and on the twin's simulated release and step tests (:mod:`flexdigit.twin.records`, default calibration), from
which E(s) and MT(s) are identified as the thesis identified them from the rig.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from flexdigit.identify.chapter3_identification import STEP_COMMANDS, chapter3_identify_study
from flexdigit.identify.filters import fft_filter, svd_filter
from flexdigit.params import RigParams
from flexdigit.reference import thesis_value
from flexdigit.report.chapter import Chapter, ReportContext, without_columns
from flexdigit.report.results import Entry, compare, new

SECTION_DIGIT = "3.1.2"
SECTION_SERVO = "3.2.4"
#: The report's random stream of this chapter's twin experiments is the report seed itself (ctx.seed).


def build(ctx: ReportContext) -> Chapter:
    """The identification chapter from :func:`~flexdigit.identify.chapter3_identification.chapter3_identify_study`."""
    study = chapter3_identify_study(ctx.params, seed=ctx.seed, fast=ctx.fast)
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
    thesis_rig = ctx.thesis_rig
    _wn_formula_bias(ctx, study, chapter, e)
    _records_tables(study, chapter, e, thesis_rig)
    _noisy_records(study, e, thesis_rig)
    _models_from_experiments(ctx, study.twin, chapter, e)
    _filters(ctx, study.filters, chapter, e)
    if thesis_rig:  # table 3.6: the thesis rig's measured deflections
        _linear_fits(study.deflection[0], e)
    _voltage_fits(study.voltage[0], e, thesis_rig)
    if thesis_rig:
        chapter.tables.extend(study.tables)
    else:
        chapter.tables.extend(_digit_tables(study.tables))
    chapter.paragraphs.append(_summary(e, thesis_rig))
    return chapter


#: The thesis rig's printed figures in the study's tables: blank in another digit's report.
_THESIS_COLUMNS = {
    "identify.models_from_twin": ("wn_thesis_rad_s", "zeta_thesis"),
    "identify.voltage_fits": ("slope_printed_v_per_command", "offset_printed_v"),
}
#: A method check on the thesis's printed tables (synthetic records), the same in every digit's report.
_METHOD_CHECK = " A check of the method on the thesis's printed figures, the same for every digit."


def _digit_tables(tables) -> list:
    """The study's tables on a digit other than the thesis rig: table 3.6's fits (the thesis rig's measured
    deflections) left out, the printed columns of the others blank."""
    out = []
    for table in tables:
        if table.key == "identify.deflection_fits":
            continue
        table = without_columns(table, _THESIS_COLUMNS.get(table.key, ()))
        title = table.title.replace(", beside the thesis's", "").replace(" (E 3.20-3.22)", "")
        title = title.replace("NaN for the thesis method", "blank for the thesis method")  # as its cells show
        out.append(dataclasses.replace(table, title=title))
    return out


def _summary(entries: list[Entry], thesis_rig: bool = True) -> str:
    """One paragraph of the chapter's findings, from its own entries."""
    v = {x.key: x.ours for x in entries}

    def pct(key: str) -> str:
        return f"{100 * v['identify.' + key]:.1f} %"

    def num(key: str, digits: int) -> str:  # a refused record's entry is its "not applicable" text
        value = v[f"identify.{key}"]
        return "(not identified)" if isinstance(value, str) else f"{value:.{digits}f}"

    servo = (v["identify.servo.thesis.wn_rad_s"], v["identify.servo.lsq.wn_rad_s"])
    servo_off = math.nan if any(isinstance(x, str) for x in servo) else servo[0] / servo[1] - 1
    return (
        "Findings. From the twin's release test (gauge 1) the least-squares fit gives wn = "
        f"{num('digit.lsq.wn_rad_s', 3)} rad/s, zeta = {num('digit.lsq.zeta', 4)}, and from its "
        f"servo steps wn = {num('servo.lsq.wn_rad_s', 3)} rad/s, zeta = {num('servo.lsq.zeta', 4)}"
        + (" (thesis: 13.0995, 0.06791; 20.53, 0.5629). " if thesis_rig else ". ")
        + "The thesis method on the same records gives "
        f"{num('digit.thesis.wn_rad_s', 2)} and {num('servo.thesis.wn_rad_s', 2)} rad/s: its "
        f"wn = 4/(zeta Ts) is {pct('wn_settling_formula.bias_digit')} high at the "
        + ("digit's" if thesis_rig else "thesis rig's digit")
        + " damping and "
        f"{pct('wn_settling_formula.bias_servo')} high at the servo's even without noise. On noisy synthetic "
        "records with known parameters, the largest lsq errors are "
        f"{pct('noisy_release.lsq.zeta_max_abs_rel_error')} (release zeta) and "
        f"{pct('noisy_step.lsq.wn_max_abs_rel_error')} (step wn), against "
        f"{pct('noisy_release.thesis.wn_max_abs_rel_error')} and {pct('noisy_step.thesis.wn_max_abs_rel_error')} "
        "for the thesis method's wn. corr2, the thesis's validation figure, is "
        f"{num('servo.thesis.validation_corr2', 4)} for the thesis method's servo model although its wn is "
        f"{100 * servo_off:.0f} % off (figure 3.12 analogue): it hardly sees a wrong wn; the NRMSE fit does."
    )


# --- the thesis's wn = 4 / (zeta Ts) --------------------------------------------------------------------------
def _wn_formula_bias(ctx: ReportContext, study, chapter: Chapter, e: list[Entry]) -> None:
    p = ctx.params
    zd, zs = p.dynamics.zeta_housing, p.actuator.servo_zeta
    whose = "the digit's" if ctx.thesis_rig or p.dynamics != RigParams().dynamics else "table 3.2's (thesis rig)"
    bias_digit, bias_servo = study.settling_bias
    e.append(
        new(
            "identify.wn_settling_formula.bias_digit",
            SECTION_DIGIT,
            bias_digit,
            "",
            f"Relative error of wn = 4/(zeta Ts) on an exact second-order response with {whose} zeta = {zd} "
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
    if ctx.thesis_rig:  # the printed servo wn is the thesis rig's
        _servo_wn_from_ts(p, bias_servo, e)
    _bias_figure(ctx, study, chapter, zd, zs, bias_digit, bias_servo)


def _servo_wn_from_ts(p, bias_servo: float, e: list[Entry]) -> None:
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


def _bias_figure(ctx: ReportContext, study, chapter: Chapter, zd, zs, bias_digit, bias_servo) -> None:
    zetas, bias = study.bias_curve
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


def _records_tables(study, chapter: Chapter, e: list[Entry], thesis_rig: bool = True) -> None:
    """Tables 3.1 and 3.2 identified back from synthetic records: each method's mean error."""
    for rec in study.records.values():
        key = f"identify.table_{rec.number.replace('.', '_')}"
        for method in ("thesis", "lsq"):
            zeta_err, wn_err = rec.mean_rel_error[method]
            e.append(
                new(
                    f"{key}.{method}_zeta_avg_rel_error",
                    SECTION_DIGIT,
                    zeta_err,
                    "",
                    f"Mean zeta identified by the {method} method from {rec.rows} synthetic release records built "
                    f"with table {rec.number}'s printed zeta and wn (0.2 % noise), relative to the mean printed zeta."
                    + ("" if thesis_rig else _METHOD_CHECK),
                )
            )
            e.append(
                new(
                    f"{key}.{method}_wn_avg_rel_error",
                    SECTION_DIGIT,
                    wn_err,
                    "",
                    f"The same for wn ({'wd/sqrt(1-zeta^2), as the table did' if method == 'thesis' else 'fitted'})."
                    + ("" if thesis_rig else _METHOD_CHECK),
                )
            )
    if not thesis_rig:  # table 3.1's damping is the thesis rig's
        return
    chapter.paragraphs.append(
        "Table 3.1's damping (zeta = 0.0008-0.005) cannot give wn = 4/(zeta Ts): the 2 % settling time would be "
        "4/(zeta wn) = 80-490 s, so the table's wn can only come from the damped frequency. Its wn column is "
        "wd/sqrt(1 - zeta^2) with zeta = 0.025-0.029, not with its own zeta column (see the models chapter), which "
        "is the damping the plant G(s) of 3.5 needs. With a lightly damped record the first undershoot alone "
        "gives zeta to about +-0.001 at 0.2 % noise, so table 3.1's zetas are at the resolution of the method."
    )


def _noisy_records(study, e: list[Entry], thesis_rig: bool = True) -> None:
    """Each method's largest error over the noisy synthetic records."""
    n = study.noisy.records
    for (kind, method), a in study.noisy.errors.items():
        for j, par in enumerate(("wn", "zeta")):
            e.append(
                new(
                    f"identify.noisy_{kind}.{method}.{par}_max_abs_rel_error",
                    SECTION_DIGIT if kind == "release" else SECTION_SERVO,
                    float(np.abs(a[:, j]).max()),
                    "",
                    f"Largest |relative error| of {par} over {n} synthetic {kind} records with known "
                    f"parameters (the thesis's {'digit' if kind == 'release' else 'servo'}) and white noise of "
                    "2 % of the response; issue 4 asks lsq for < 2 %."
                    + (" The thesis method's error is mostly the bias of 4/(zeta Ts)." if method == "thesis" else "")
                    + ("" if thesis_rig else _METHOD_CHECK),
                )
            )


# --- E(s) and MT(s) from the twin's experiments -------------------------------------------------------------
def _models_from_experiments(ctx: ReportContext, twin, chapter: Chapter, e: list[Entry]) -> None:
    """E(s) and MT(s) identified from the twin's experiments, beside the thesis's (figures 3.6, 3.11, 3.12)."""
    _model_entries(twin, e)
    _tip_entries(twin, e, ctx.thesis_rig)
    _model_figures(ctx, twin, chapter)


def _model_entries(twin, e: list[Entry]) -> None:
    fits, tip_fits, origin = twin.fits, twin.tip_fits, twin.origin
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
    for (model, method), r in fits.items():
        wn_p, zeta_p, corr_p = printed[model]
        section = SECTION_DIGIT if model == "digit" else SECTION_SERVO
        if isinstance(r, str):  # identify refused the record: its reason, no figure
            corr2 = (
                f"identify.{model}.thesis.validation_corr2"
                if method == "thesis"
                else f"identify.{model}.validation_corr2"
            )
            keys = [f"identify.{model}.{method}.wn_rad_s", f"identify.{model}.{method}.zeta", corr2]
            e.extend(_refused(keys, section, r, origin, method))
            continue
        why = (
            "The thesis method's wn = 4/(zeta Ts) carries the bias of identify.wn_settling_formula.* plus the noise "
            "in the settling time read off a filtered record."
        )
        why_zeta = "%OS is read off one extremum of a filtered noisy record, so it moves with the noise and the filter."
        if (
            model == "digit"
            and not isinstance(tip_fits["thesis"], str)
            and not isinstance(fits[(model, "thesis")], str)
        ):
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
        _corr2_entry(model, method, section, r, corr_p, e)


def _refused(keys: list[str], section: str, reason: str, origin: str, method: str) -> list[Entry]:
    """The entries ``keys`` of a record ``identify`` refuses: "not applicable" and its reason, no figure."""
    note = f"Identified from {origin} by the {method} method."
    return [new(key, section, f"not applicable: {reason}", "", note) for key in keys]


def _corr2_entry(model: str, method: str, section: str, r, corr_p: float, e: list[Entry]) -> None:
    """corr2 of the identified model against its record: new for the thesis method, against print for lsq."""
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


def _tip_entries(twin, e: list[Entry], thesis_rig: bool = True) -> None:
    """The same release read at the tip, a measurement the rig did not have."""
    wn_p = thesis_value("digit.release_tests_with_housing.wn_avg_rad_s")
    zeta_p = thesis_value("digit.release_tests_with_housing.zeta_avg")
    for method, r in twin.tip_fits.items():
        if isinstance(r, str):
            keys = [f"identify.digit_tip.{method}.wn_rad_s", f"identify.digit_tip.{method}.zeta"]
            e.extend(_refused(keys, SECTION_DIGIT, r, twin.origin, method))
            continue
        for par, value in (("wn_rad_s", r.wn_rad_s), ("zeta", r.zeta)):
            e.append(
                new(
                    f"identify.digit_tip.{method}.{par}",
                    SECTION_DIGIT,
                    value,
                    "rad/s" if par == "wn_rad_s" else "",
                    f"The same twin release test read at the tip (a measurement the rig did not have) by the {method} "
                    "method" + (f"; thesis: {wn_p if par == 'wn_rad_s' else zeta_p}." if thesis_rig else "."),
                )
            )


def _model_figures(ctx: ReportContext, twin, chapter: Chapter) -> None:
    import matplotlib.pyplot as plt

    release, steps, step, fits, origin = twin.release, twin.steps, twin.step, twin.fits, twin.origin
    # figures 3.6 and 3.12: measured versus modelled
    for model, rec, kind, fig_name, ref in (
        ("digit", release, "release", "ch3_identify_release_validation", "figure 3.6"),
        ("servo", step, "step", "ch3_identify_step_validation", "figure 3.12"),
    ):
        fig, ax = plt.subplots(figsize=(6.5, 3.4))
        ax.plot(rec.t_s, rec.y, color="0.6", lw=0.6, label="twin record")
        for method, style in (("thesis", "--"), ("lsq", "-")):
            r = fits[(model, method)]
            if isinstance(r, str):  # refused: the record alone
                continue
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
def _filters(ctx: ReportContext, f, chapter: Chapter, e: list[Entry]) -> None:
    """The FFT and SVD filters of 3.2.4 against their parameter."""
    import matplotlib.pyplot as plt

    harmonics, fft_red, ranks, svd_red = f.harmonics, f.fft_reduction, f.ranks, f.svd_reduction
    best_n = f.best_harmonics
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
def _linear_fits(fits: list, e: list[Entry]) -> None:
    """3.4.1: the slopes of table 3.6 with their intervals, beside the printed ones."""
    printed = thesis_value("conversion.k1_fit")
    for k, r in enumerate(fits):
        a = float(printed[k]["a"])
        inside = r.slope.ci_low <= a <= r.slope.ci_high
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


def _voltage_fits(fits: list, e: list[Entry], thesis_rig: bool = True) -> None:
    """E 3.20-3.22 from the twin's actuation sweep, beside the printed lines."""
    printed = thesis_value("conversion.v_sg_fit")
    for k, r in enumerate(fits):
        e.append(
            compare(
                f"identify.v_sg_fit.sg{k + 1}.slope_v_per_command",
                "3.4.3",
                float(printed[k]["slope"]) if k < len(printed) else math.nan,  # NaN: another digit's gauge
                r.slope.value,
                "V/command",
                rtol=0.03,
                note=f"Least-squares line through the twin's actuation sweep "
                f"({f'E 3.2{k}' if thesis_rig else f'gauge {k + 1}'}); 95 % CI "
                f"{r.slope.ci_low:.5f}..{r.slope.ci_high:.5f}, residual RMS {1e3 * r.rms:.2f} mV.",
                discrepancy_note="The twin's calibration does not reproduce this fit of figure 3.17.",
            )
        )

"""Report chapter "beyond the thesis": the digit's shape from its three gauges (thesis 1.1, 3.3, 8).

The thesis promises "a sense of feeling and shape" (1.1) and shows neither live. This chapter scores
:class:`flexdigit.shape.shape.ShapeEstimator` (curvature field from the gauges and the cable's and the load's
moments, integrated to a centre line) against the twin's true centre line over the actuation range, bare and with
a weight hung anywhere (:func:`flexdigit.shape.shape.shape_accuracy`); it computes nothing itself.
"""

from __future__ import annotations

import warnings

import numpy as np

from flexdigit.errors import ConvergenceWarning
from flexdigit.palpation.palpation import digit_command
from flexdigit.params import RigParams
from flexdigit.report import results
from flexdigit.report.chapter import Chapter, ReportContext, ResultTable
from flexdigit.shape.shape import ShapeEstimator, accuracy_commands, shape_accuracy, true_centre_line_m
from flexdigit.twin.batched import BatchedChains
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, cached_digit, static_gauges_v

SECTION = "8 (beyond)"


def build(ctx: ReportContext) -> Chapter:
    """Build the shape chapter: tip and along-the-digit errors, one figure."""
    chapter = Chapter(slug="ch8-shape", title=f"Beyond the thesis: the digit's shape from its {ctx.gauges_text}")
    commands = _commands(ctx)
    length_m = ctx.params.geometry.digit_length_m  # 27 places along the digit (every 10 mm on the thesis rig)
    positions = tuple(round(length_m * k / 27, 3) for k in range(1, 28, 3 if ctx.fast else 1))
    with warnings.catch_warnings(record=True) as unsettled:  # said in words below, not a warning with a path
        warnings.simplefilter("always", ConvergenceWarning)
        acc = shape_accuracy(commands, positions, 0.025, seed=ctx.seed, params=ctx.params)
        figure = _figure(ctx, acc.mount)
    summary = acc.summary()
    chapter.paragraphs.append(
        f"The centre line is estimated from the {ctx.gauges_text.replace('gauge', 'gauge voltage')} and the servo "
        "command alone "
        "(the ShapeEstimator of flexdigit.shape): each gauge's curvature is M/EI (E 3.12) of a moment made of the "
        "cable's T e (3.3), the digit's own weight and one weight at an unknown place; with the cable taut the "
        "command fixes the tip angle (E 3.11, 3.14). The fit (tension, load and where) is integrated to a shape "
        "with large rotations kept. Each case is one noisy reading of the twin (white noise and, with the cable "
        f"taut, one draw of its cable-guide friction; seed {ctx.seed}) at commands {commands[0]}..{commands[-1]}: "
        f"the bare digit {'hanging tip down (it buckles tip up)' if acc.mount == 'hanging' else 'upright'} and "
        "horizontal, and a 25 g weight every "
        f"{1000 * (positions[1] - positions[0]):.3g} mm along the horizontal digit (chapters 6-7's mounting)."
    )
    _accuracy_table(chapter, summary, commands)
    _weight_entries(chapter, acc, ctx.thesis_rig)
    chapter.paragraphs.append(
        "The shape is good to a millimetre or two wherever the weight's moment is seen, and the load's position "
        "is not: with the cable taut its guide friction (fitted to chapter 7's corr2) moves each gauge by as much "
        "as a 25 g weight a centimetre away does, and between gauges 1 and 2 position and mass trade off. The "
        "shape survives because a misplaced load of the wrong mass bends the digit almost as the true one does."
        if ctx.thesis_rig
        else _digit_findings(chapter)
    )
    unsettled = [w for w in unsettled if issubclass(w.category, ConvergenceWarning)]
    if unsettled:
        chapter.paragraphs.append(_unsettled_text(ctx, len(unsettled)))
    chapter.figures.append(figure)
    return chapter


def _digit_findings(chapter: Chapter) -> str:
    """What this digit's entries say, in words (the thesis rig's paragraph quotes its own friction and gauges)."""
    v = {e.key: e.ours for e in chapter.entries}
    text = (
        f"On this digit the median tip error is {v['shape.bare_horizontal.tip_error_median_mm']:.2g} mm bare and "
        f"{v['shape.weight_horizontal.tip_error_median_mm']:.2g} mm with the weight (horizontal); the weight is "
        f"declared a contact in {100 * v['shape.weight.contact_rate']:.0f} % of its cases"
    )
    if "shape.weight.position_error_median_mm" in v:
        text += f", then placed to a median {v['shape.weight.position_error_median_mm']:.2g} mm"
    return text + " (its cable-guide friction is the level fitted on the thesis rig)."


def _commands(ctx: ReportContext) -> tuple[int, ...]:
    """The commands scored: the digit's own (:func:`flexdigit.shape.shape.accuracy_commands`: from its straight
    command to each end of its range, both ways for a cable pair), every other one when fast; the thesis rig's
    8, 13, ..., 43 (fast: 8, 18, 28, 38) as before."""
    if ctx.params == RigParams():
        return tuple(range(8, 44, 10 if ctx.fast else 5))
    commands = accuracy_commands(ctx.params)
    return commands[:: 2 if ctx.fast else 1]


def _unsettled_text(ctx: ReportContext, count: int) -> str:
    """What the twin's unconverged static solves (``count`` batches) mean for this chapter, in words."""
    chains = BatchedChains.from_rigs([ctx.params], [default_calibration()], housing=True, orientation="vertical")
    at_rest = chains.linearised(np.zeros((1, chains.n)), np.array([-np.inf]))[2][0]
    why = (
        "upright, this digit buckles under its own weight (the twin's tangent stiffness at rest has a negative "
        "eigenvalue), so there is no settled upright shape to compare with"
        if np.linalg.eigvalsh(at_rest)[0] <= 0
        else "no equilibrium was found for some of its cases"
    )
    return (
        f"On this digit the twin's static solve did not settle in {count} batch(es) of these cases: {why}. The "
        "rows of those cases score the estimator against an unsettled shape, not against the digit."
    )


def _accuracy_table(chapter: Chapter, summary, commands: tuple[int, ...]) -> None:
    """Each case group's tip and along-the-digit errors: result entries and one table."""
    rows = []
    for group in summary:
        slug = group["case"].replace(", ", "_").replace(" ", "_")
        rows.append(
            (
                group["case"],
                group["cases"],
                group["tip_error_median_mm"],
                group["tip_error_p95_mm"],
                group["tip_error_max_mm"],
                group["rms_error_mean_mm"],
                group["tip_within_2sd"],
            )
        )
        for key, unit, what in (
            ("tip_error_median_mm", "mm", "median tip position error"),
            ("tip_error_p95_mm", "mm", "95th percentile of the tip position error"),
            ("rms_error_mean_mm", "mm", "RMS distance along the digit, mean over the cases"),
        ):
            chapter.entries.append(
                results.new(
                    f"shape.{slug}.{key}",
                    SECTION,
                    group[key],
                    unit,
                    f"{what}, {group['case']} ({group['cases']} cases, one reading each, commands "
                    f"{commands[0]}..{commands[-1]}); the estimator against the twin's true centre line.",
                )
            )
        chapter.entries.append(
            results.new(
                f"shape.{slug}.tip_within_2sd",
                SECTION,
                group["tip_within_2sd"],
                "",
                f"share of {group['case']} tips within two of the estimate's own standard deviations (a "
                "calibrated Gaussian gives 0.95; the rest is the choice between 'a load' and 'none').",
            )
        )
    chapter.tables.append(
        ResultTable(
            "shape.accuracy",
            "Shape from the gauges against the twin (one reading per case)",
            ("case", "cases", "tip_error_median_mm", "tip_error_p95_mm", "tip_error_max_mm", "rms_error_mean_mm")
            + ("tip_within_2sd_fraction",),
            tuple(rows),
        )
    )


def _weight_entries(chapter: Chapter, acc, thesis_rig: bool = True) -> None:
    """How often a hung weight is declared a contact, and how well it is then placed."""
    located = acc.contact & (acc.mass_kg > 0)
    err_mm = np.abs(acc.load_position_error_m[located]) * 1e3
    weighted = acc.mass_kg > 0
    chapter.entries.append(
        results.new(
            "shape.weight.contact_rate",
            SECTION,
            float(np.mean(acc.contact[weighted])),
            "",
            "share of the 25 g weights declared a contact (likelihood ratio, chi-square drop > 25); missed "
            "before gauge 2 (no gauge, or gauge 1 alone, bends) and at high commands, where the taut cable's "
            "guide friction is as large as the weight's moment.",
        )
    )
    if err_mm.size:
        chapter.entries.append(
            results.new(
                "shape.weight.position_error_median_mm",
                SECTION,
                float(np.median(err_mm)),
                "mm",
                "median error of the load's position where a contact was declared (one reading, mass unknown)"
                + ("; chapter 7's estimators reach 22-23 mm at the same friction." if thesis_rig else "."),
            )
        )


def _figure(ctx: ReportContext, mount: str = "upright"):
    """Three cases: the estimated centre line with its band against the twin's; the first one bare as the digit is
    scored (``mount``: upright, or hanging tip down for a digit that buckles upright)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # the load at 200 mm of the thesis rig's 270: the same fraction of another digit
    at_m = 0.20 if ctx.thesis_rig else round(0.20 / 0.27 * ctx.params.geometry.digit_length_m, 3)
    # the thesis rig's commands 30 and 20, as far past this digit's straight command in tip rotation
    high, low = (30, 20) if ctx.thesis_rig else (digit_command(ctx.params, 30), digit_command(ctx.params, 20))
    first = "hanging" if mount == "hanging" else "vertical"
    cases = [(first, 0.0, 0.0, high), ("horizontal", 0.0, 0.0, low), ("horizontal", 0.025, at_m, low)]
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
    for ax, (orientation, mass, position, command) in zip(axes, cases, strict=True):
        volts, sol = static_gauges_v(
            [mass], [position], [command], params=ctx.params, orientation=orientation, seed=ctx.seed,
            return_solution=True,
        )  # fmt: skip
        est = ShapeEstimator(ctx.params, orientation=orientation).estimate(volts, command=command)
        chain = cached_digit(ctx.params, default_calibration(), True, orientation, DEFAULT_CELLS_PER_SECTION)
        truth = true_centre_line_m(sol.psi_rad, chain, est.s_m)[0] * 1e3
        line = est.centre_line_m[0] * 1e3
        normal = np.stack([-np.sin(est.angle_rad[0]), np.cos(est.angle_rad[0])], axis=-1)
        band = 2 * np.minimum(est.sd_normal_m[0], 0.05)[:, None] * 1e3 * normal
        ax.fill(
            np.r_[line[:, 0] + band[:, 0], (line[:, 0] - band[:, 0])[::-1]],
            np.r_[line[:, 1] + band[:, 1], (line[:, 1] - band[:, 1])[::-1]],
            color="tab:blue",
            alpha=0.25,
            label="estimate +- 2 sd",
        )
        ax.plot(line[:, 0], line[:, 1], color="tab:blue", label="estimated")
        ax.plot(truth[:, 0], truth[:, 1], "k--", label="twin (true)")
        if mass > 0:
            ax.plot(*(truth[int(round(position * 1e3))]), "rv", label=f"{mass * 1e3:g} g hung")
        ax.set_title(f"{orientation}, command {command}" + (f", {mass * 1e3:g} g" if mass else ", bare"))
        ax.set_xlabel("along the digit (mm)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("towards the cable (mm)")
    axes[0].legend(fontsize=7)
    return ctx.save_figure(
        fig,
        "shape_from_gauges",
        f"The centre line from the {ctx.gauges_text} (one noisy reading) against the twin's, with its "
        "two-standard-deviation band.",
    )

"""Report chapter 8 (beyond the thesis): sensitivity to the rig's tolerances and the design of the next digit.

The thesis's conclusion asks for "a sensitivity and stability analysis ... into the effects of all system
parameters", feedback from more gauges and a finer motor step; 2.1 for a second cable and a study of size. This
chapter shows two library results (:mod:`flexdigit.studies`): the Sobol indices of the twin's metrics over the
shipped tolerances (:func:`flexdigit.studies.sensitivity.twin_sensitivity`) and a small design study with its
Pareto front (:func:`flexdigit.studies.design_study.showcase_design`). Both run in process at a small size; the
``flexdigit study`` command runs the full studies on Dask.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from flexdigit.report.chapter import Chapter, ReportContext, ResultTable
from flexdigit.report.results import new
from flexdigit.studies import figures
from flexdigit.studies.design_study import design_pareto_figure, showcase_design
from flexdigit.studies.parameter_set import ParameterSet
from flexdigit.studies.sensitivity import twin_sensitivity
from flexdigit.studies.spec import load_spec
from flexdigit.twin.calibration import default_calibration

#: Parameters of thesis-tolerances the report's study keeps: the 11 that move the twin's mechanics, and the
#: servo's wn, which must come out with no effect (a check of the method).
REPORT_PARAMETERS = (
    "material.youngs_modulus_pa",
    "material.strip_density_kg_m3",
    "geometry.strip_thickness_m",
    "geometry.strip_width_m",
    "geometry.cable_eccentricity_m",
    "actuator.pulley_radius_m",
    "actuator.servo_wn_rad_s",
    "calibration.cable_stiffness_n_m",
    "calibration.support_mass_kg[*]",
    "calibration.housing_ei_n_m2[*]",
    "calibration.housing_beta_s",
    "calibration.strip_beta_s",
)


def build(ctx: ReportContext) -> Chapter:
    """Build the chapter."""
    title = "Beyond the thesis: sensitivity and design"
    chapter = Chapter(slug="ch8-studies", title=title)
    _sensitivity(ctx, chapter)
    if ctx.thesis_rig:
        _design(ctx, chapter)
    else:
        chapter.paragraphs.append(
            "The design study is not run for this digit: its space (3-6 gauges, thesis or equal spacing, sizes "
            "x0.75-1.25 of the thesis rig) proposes digits from the thesis rig's, whatever the digit; "
            "`flexdigit study design thesis-design --export K` writes any of its designs as a parameter file."
        )
    return chapter


def rerun_hint(fast: bool, n: int) -> str:
    """What the "NOT converged" warning of the report's study tells the user to run: a command and flags that exist
    (``reproduce`` has ``--fast``, not ``--n``; ``study sensitivity`` has ``--n``)."""
    if fast:
        return "rerun `flexdigit reproduce` without --fast (N = 128)"
    return f"`flexdigit study sensitivity thesis-tolerances --n {4 * n}` takes more samples"


def _sensitivity(ctx: ReportContext, chapter: Chapter) -> None:
    # on a digit other than the thesis rig: the shipped tolerances about its description and its calibration (the
    # report's, default_calibration() inside reproduce); relative and delta ranges are then about its values, and
    # absolute ones scaled to them
    spec = load_spec(
        "thesis-tolerances",
        baseline=None if ctx.thesis_rig else ParameterSet(ctx.params, default_calibration()),
        fields=tuple({name.split("[")[0] for name in REPORT_PARAMETERS}),
        scaled=not ctx.thesis_rig,  # the steel's datasheet range as a spread about this digit's own modulus
    )
    spec = dataclasses.replace(spec, parameters=tuple(p for p in spec.parameters if p.name in REPORT_PARAMETERS))
    n = 16 if ctx.fast else 128
    result = twin_sensitivity(n, seed=ctx.seed, spec=spec, rerun=rerun_hint(ctx.fast, n))
    names = spec.names
    big = 2 * n
    about = "" if ctx.thesis_rig else ", taken about this digit's description and calibration"
    chapter.paragraphs.append(
        f"Sobol indices of the twin's metrics over {len(names)} of the shipped tolerances (thesis-tolerances: each "
        f"tolerance's source is in the spec{about}), Saltelli's design with N = "
        f"{big} ({result.values.shape[0]} evaluations on the batched twin, Morris screening first), 95 % bootstrap "
        f"intervals. Converged means no S1 or ST moved by more than {result.settings.convergence_tol} between "
        f"N = {n} and {big}. The controller, H-infinity and tactile metrics need a design or a Monte Carlo per "
        "rig: `flexdigit study sensitivity thesis-tolerances` computes them on Dask."
    )
    rows = []
    for metric in result.metrics:
        if metric in result.refused:
            chapter.entries.append(new(f"studies.sobol.{metric}", "8", result.refused[metric], "", "no indices"))
            continue
        res = result.sobol[metric][big]
        conv = result.convergence[metric]
        order = np.argsort(-res["ST"])
        top = names[order[0]]
        chapter.entries.append(
            new(
                f"studies.sobol.{metric}.max_change",
                "8",
                conv["max_change"],
                "",
                f"largest change of S1/ST between N = {n} and {big}: "
                + ("converged" if conv["converged"] else "NOT converged")
                + f" (tolerance {conv['tolerance']}); most influential: {top}, ST {res['ST'][order[0]]:.3f}",
            )
        )
        for j, name in enumerate(names):
            for index in ("S1", "ST"):
                chapter.entries.append(
                    new(
                        f"studies.sobol.{metric}.{name}.{index}",
                        "8",
                        res[index][j],
                        "",
                        f"+- {res[f'{index}_conf'][j]:.3f} (95 % bootstrap), N = {big}",
                    )
                )
        rows.append((metric, *(v for j in range(len(names)) for v in (res["ST"][j], res["ST_conf"][j]))))
    if not rows:  # a digit whose tolerances reach rows it cannot run (a servo that stalls): said, not drawn empty
        chapter.paragraphs.append(
            "No metric has Sobol indices: each was refused on some rows of the design (the entries "
            "studies.sobol.METRIC say why), and Saltelli's estimators need every row."
        )
        return
    chapter.tables.append(
        ResultTable(
            "studies.sobol_total",
            f"Total Sobol indices ST and their 95 % half-intervals, N = {big}",
            ("metric", *(c for name in names for c in (f"{name}.ST", f"{name}.ST_conf"))),
            tuple(rows),
        )
    )
    _sensitivity_figures(ctx, chapter, result)


def _sensitivity_figures(ctx: ReportContext, chapter: Chapter, result) -> None:
    """The study's total-index map and the release frequency's bars."""
    size = figures.sample_size_text(result.settings)
    fig = figures.sensitivity_total_map(result, f"Total Sobol indices, {size}")
    chapter.figures.append(ctx.save_figure(fig, "studies_sobol_total", "Total Sobol indices of the twin's metrics."))
    metric = "release_wn_rad_s"
    if metric in result.sobol:
        fig = figures.sensitivity_bars(result, metric, f"{metric}: S1 and ST, {size}, 95 % intervals")
        chapter.figures.append(
            ctx.save_figure(
                fig,
                "studies_sobol_release_wn",
                "Sobol indices of the housed release frequency.",
                thesis_ref="table 3.2",
            )
        )


def _design(ctx: ReportContext, chapter: Chapter) -> None:
    result = showcase_design(8 if ctx.fast else 24, seed=ctx.seed, bayes_samples=50 if ctx.fast else 100)
    o = result.settings.objectives
    chapter.paragraphs.append(
        f"A design study of {len(result.candidates)} designs (3, 4 or 6 gauges, thesis or equal spacing, half or full "
        "bridge, the servo's step or a 4:1 finer one, one cable or the antagonistic pair of 2.1, size x0.75-1.25), "
        f"each with its own 20 ms controller: {o[0]} (chapter 6's Bayes limit) against {o[1]} (linearised twin). "
        "`flexdigit study design thesis-design` runs the full space (2916 designs) on Dask."
    )
    rows = []
    front = set(result.front.tolist())
    for i in sorted(front, key=lambda i: result.outputs[o[0]][i]):
        rows.append((result.candidates[i].label(), *(result.outputs[m][i] for m in o)))
    for name, i in result.marked().items():
        rows.append((f"[{name}] {result.candidates[i].label()}", *(result.outputs[m][i] for m in o)))
        for m in o:
            chapter.entries.append(
                new(
                    f"studies.design.{name.replace(' ', '_').replace(',', '')}.{m}",
                    "8",
                    result.outputs[m][i],
                    "",
                    f"{result.candidates[i].label()}; on the Pareto front: {i in front}",
                )
            )
    for k, i in enumerate(sorted(front, key=lambda i: result.outputs[o[0]][i])):
        for m in o:
            chapter.entries.append(
                new(f"studies.design.front_{k}.{m}", "8", result.outputs[m][i], "", result.candidates[i].label())
            )
    chapter.tables.append(
        ResultTable("studies.design_front", "Pareto front and marked designs", ("design", *o), tuple(rows))
    )
    for p in result.placement:
        chapter.entries.append(
            new(
                f"studies.design.d_optimal_{p['gauges']}_gauges.d_efficiency_of_equal_spacing",
                "8",
                p["d_efficiency_equal"],
                "",
                f"D-optimal positions {p['positions_mm']} mm against equal spacing {p['equal_mm']} mm (largest shift "
                f"{p['max_shift_mm']:.0f} mm): a load's moment passes every gauge between it and the clamp, so the "
                "information concentrates near the clamp; equal spacing is not D-optimal on this strip",
            )
        )
    chapter.figures.append(
        ctx.save_figure(
            design_pareto_figure(result),
            "studies_pareto",
            "Design candidates, their Pareto front, the thesis layout and equal spacing marked.",
        )
    )

"""Report chapter "beyond the thesis: palpation" (issue 13): contact, stiffness, an inclusion, force, active sensing.

Chapter 8 of the thesis says what its sensing is for: "to detect low frequency palpations, to identify variability
in tissue stiffness, and to discriminate against distributed loads". This chapter shows the library's answers
(:mod:`flexdigit.palpation.palpation_studies`) on the twin at the thesis's non-actuated noise level; it computes
nothing itself. It runs small but honest settings (docs/guide/palpation.md quotes the full studies and the command that
measures each); every table is also in results.json.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from flexdigit.control.design20ms import digit_mount
from flexdigit.errors import ParameterError, RigError
from flexdigit.palpation import palpation_studies as studies
from flexdigit.palpation.contact_estimation import ContactGaugeModel
from flexdigit.palpation.palpation import (
    THESIS_STRAIGHT,
    PalpationProtocol,
    check_tissue_reach,
    digit_command,
    digit_protocol,
    digit_tissue,
    twin_step_s,
)
from flexdigit.palpation.palpation_files import load_palpation_protocol, load_tissue
from flexdigit.params import RigParams
from flexdigit.report.chapter import Chapter, ReportContext
from flexdigit.report.results import new
from flexdigit.tactile.bounds import TwinGaugeModel
from flexdigit.tactile.localisation import SETTINGS_RESOLVED
from flexdigit.twin.contact import Tissue
from flexdigit.twin.digit_calibration import twin_calibration

SECTION = "beyond: palpation"
#: The thesis rig's length (m): a digit's regions, extents and scan offsets are the thesis's scaled by L / this.
THESIS_LENGTH_M = 0.27
#: What of the thesis's sweep is laid out on a digit: all of it, as for ``palpate``'s built-in sweep.
_LAID_OUT = ("commands", "tare_command", "settle_s")


@dataclass(frozen=True)
class DigitSetting:
    """The chapter's studies on a digit other than the thesis rig, laid out by the palpation library as ``palpate
    --params`` lays them out (one implementation; the chapter turns its results into entries): the tissue beside
    the digit's outer 45 % (from 0.55 L to 80 mm past the tip, 0.1 L away), the thesis's commands laid out from its
    straight command towards the tissue, as far in tip rotation (:func:`~flexdigit.palpation.palpation.digit_command`,
    :func:`~flexdigit.palpation.palpation.digit_protocol`: the servo's step and gearing both), contact estimates at
    the thesis's command 20, the digit's own calibration
    (:func:`~flexdigit.twin.digit_calibration.twin_calibration`) and its mount (hung tip down if it buckles tip up).
    Before, commands were scaled by the gear ratio alone (a fine-step servo swept a fifth of the way) and the gauge
    model read the thesis rig's calibration."""

    params: RigParams
    orientation: str
    fast: bool

    @property
    def length_m(self) -> float:
        return float(self.params.geometry.digit_length_m)

    @property
    def scale(self) -> float:
        return self.length_m / THESIS_LENGTH_M

    def command(self, thesis_offset: int) -> int:
        """The command as far past the digit's straight one, in tip rotation, as ``thesis_offset`` is past the
        thesis's straight 8 (towards the cable side; negative: the other way), within the servo's range."""
        return digit_command(self.params, THESIS_STRAIGHT + thesis_offset)

    def protocol(self, every: int) -> PalpationProtocol:
        """The thesis's sweep 8..30 every ``every`` commands laid out on the digit (its settling as it rings)."""
        thesis = PalpationProtocol(commands=tuple(range(THESIS_STRAIGHT, 31, every)))
        return digit_protocol(thesis, self.params, laid_out=_LAID_OUT, model=self.contact_model())

    def tissue(self) -> Tissue:
        return Tissue(0.55 * self.length_m, self.length_m + 0.08, 0.1 * self.length_m, 1000.0)

    def contact_model(self, cells_per_section: int | None = None) -> ContactGaugeModel:
        return ContactGaugeModel(
            self.params,
            twin_calibration(self.params),
            orientation=self.orientation,
            cells_per_section=cells_per_section,
        )


def build(ctx: ReportContext) -> Chapter:
    """Build the palpation chapter."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    title = "Beyond the thesis: palpation"
    ch = Chapter(slug="ch8-palpation", title=title)
    if not ctx.thesis_rig:
        return _digit_chapter(ctx, ch, plt)
    ch.paragraphs.append(
        "The digit presses into a compliant body beside it, the cable pulling it in: a unilateral Winkler (or "
        "Hunt-Crossley) foundation in the twin, validated against an independent elastica "
        "boundary-value problem within 0.07 % on the tip and 0.44 % on the contact force. Noise: 2 mV white per "
        "reading and the twin's drift, the thesis's non-actuated level (no weight is hung, so no cable-guide "
        "friction), except for active sensing, which works at chapter 7's actuated level."
    )
    _contact(ctx, ch, plt)
    _classification(ctx, ch)
    _stiffness(ctx, ch, plt)
    _scan(ctx, ch, plt)
    _force(ctx, ch, plt)
    _active(ctx, ch)
    return ch


def digit_setting(ctx: ReportContext) -> DigitSetting:
    """The chapter's setting of the report's digit, mounted as ``palpate --params`` (and ``run``, ``export``,
    chapter 5) mounts it (:func:`~flexdigit.control.design20ms.digit_mount`: hung where it does not stand tip up).
    Before, the release tests' mount (``release_orientation``): three hand-made digits stood tip up here and hung
    in palpate."""
    return DigitSetting(ctx.params, digit_mount(ctx.params, twin_calibration(ctx.params)), ctx.fast)


def _digit_chapter(ctx: ReportContext, ch: Chapter, plt) -> Chapter:
    """The chapter on a digit other than the thesis rig: the same studies laid out on it (:class:`DigitSetting`),
    force control with the digit's own gains (:func:`~flexdigit.palpation.palpation.force_gains`)."""
    digit = digit_setting(ctx)
    g = ctx.params.geometry
    sweep = digit.protocol(2)
    ch.paragraphs.append(
        f"This digit ({g.section_count} sections, {len(g.gauge_positions_m)} gauges, {1000 * digit.length_m:.0f} "
        "mm) presses into a compliant body beside it, the cable pulling it in, on its own twin (the calibration of "
        "every chapter of this report) and its own gauge model, mounted "
        f"{'tip up' if digit.orientation == 'vertical' else 'tip down (it buckles tip up)'}. The thesis rig's "
        "settings are laid out on the digit: positions, regions and extents scaled by its length over 270 mm, the "
        f"body beside its outer 45 % ({1000 * digit.tissue().start_m:.0f} mm on, {1000 * digit.tissue().gap_m:.0f} mm"
        f" away), the sweep's commands {sweep.commands[0]}..{sweep.commands[-1]} laid out from its straight command "
        f"{sweep.tare_command} towards the body, as far in tip rotation as the thesis's 8..30 (as `palpate "
        "--params` sweeps it). Noise: the twin's white noise and drift; active sensing at "
        "its actuated level. Force control runs the library's loop with the digit's own gains (the thesis's "
        "crossover and tip-turning rate, palpation.force_gains): its figures are the twin's true force, so a digit "
        "whose gauges misjudge the force (one gauge, a "
        "short digit) or that presses slowly (a long one) shows it here."
    )
    _contact(ctx, ch, plt, digit)
    _classification(ctx, ch, digit)
    _stiffness(ctx, ch, plt, digit)
    _scan(ctx, ch, plt, digit)
    _force(ctx, ch, plt, digit)
    _active(ctx, ch, digit)
    return ch


def _contact_study(ctx, digit: DigitSetting | None) -> tuple[dict, float]:
    """The contact study (point contacts every ``step`` m along the digit) and its ``step``."""
    step = 0.02 if ctx.fast else 0.01
    forces = (0.1,) if ctx.fast else (0.1, 0.2)
    if digit is None:
        c = studies.contact_study(
            positions_m=np.arange(0.0, 0.2701, step), forces_n=forces, n_readings=25, repetitions=20, seed=ctx.seed
        )
        return c, step
    step *= digit.scale
    c = studies.contact_study(
        positions_m=np.arange(0.0, digit.length_m + 1e-4, step),
        forces_n=forces,
        command=digit.command(12),
        n_readings=25,
        repetitions=20,
        seed=ctx.seed,
        estimator_model=digit.contact_model(3),
        truth_model=digit.contact_model(9),
    )
    return c, step


def _contact(ctx, ch, plt, digit: DigitSetting | None = None) -> None:
    c, step = _contact_study(ctx, digit)
    command = 20 if digit is None else digit.command(12)  # the thesis's command 20, laid out on the digit
    e = ch.entries
    forces = " and ".join(f"{f:g}" for f in np.unique(-c["force_n"]))
    pub = studies.PUBLISHED
    if "seen_rms_position_m" not in c:  # a digit whose gauges see no contact fully (one gauge: F s only)
        e.append(
            new(
                "palpation.contact.identifiable",
                SECTION,
                0,
                "contacts",
                f"of {len(c['zone'])} point contacts of {forces} N, none tells position and force apart",
            )
        )
        _zones(c, e, forces, step)
        _contact_figure(ctx, ch, plt, c, command)
        return
    e.append(
        new(
            "palpation.contact.position_rmse_mm",
            SECTION,
            1000 * c["seen_rms_position_m"],
            "mm",
            f"point contacts of {forces} N the gauges can see ({c['zone_counts']['identifiable']} of "
            f"{len(c['zone'])}: {1000 * c['seen_span_m'][0]:.0f}-{1000 * c['seen_span_m'][1]:.0f} mm), 25 "
            "readings per estimate",
        )
    )
    e.append(
        new(
            "palpation.contact.position_ratio_to_crlb",
            SECTION,
            c["position_ratio"],
            "",
            "RMS position error over the Cramer-Rao bound's RMS on the same contacts (issue: <= 1.2)",
        )
    )
    e.append(
        new(
            "palpation.contact.force_rel_rmse",
            SECTION,
            c["seen_rms_force_rel"],
            "",
            f"relative force RMS; best published {pub['force_rel']:.0%}",
        )
    )
    e.append(new("palpation.contact.force_ratio_to_crlb", SECTION, c["force_ratio"], "", "issue: <= 1.2"))
    if "band_rms_position_m" in c:
        e.append(
            new(
                "palpation.contact.band_position_rmse_mm",
                SECTION,
                1000 * c["band_rms_position_m"],
                "mm",
                f"between gauge 2 and the tip support ({1000 * c['band_m'][0]:.0f}-{1000 * c['band_m'][1]:.0f} "
                f"mm); best published {1000 * pub['location_m']:.1f} mm (1 % of "
                + ("the length)" if digit is None else f"the thesis rig's {1000 * THESIS_LENGTH_M:.0f} mm)"),
            )
        )
    _zones(c, e, forces, step)
    if digit is not None:
        ch.paragraphs.append(
            "Which contacts the gauges cannot see (the zones above): before the first gauge nothing bends; between "
            "the first two gauges, or past the only one, only the product of force and lever is seen; on the tip "
            "support only the force. Where the gauges see the contact, the estimate against its Cramer-Rao bound."
        )
        _contact_figure(ctx, ch, plt, c, command)
        return
    ch.paragraphs.append(
        "Which contacts the gauges cannot see: before gauge 1 (45 mm) "
        "nothing bends; between gauges 1 and 2 only the product F (s - 45 mm) is seen (the taut cable's answer is "
        "proportional to it too), so force and position are confounded; on the rigid tip support (265-270 mm) the "
        "stiff cable pins the tip angle and absorbs the load's moment, so only the force is seen; just past gauge 2 "
        "and in the last section a distant rival explains the reading nearly as well (ambiguous). Where the gauges "
        "see the contact the estimate is at its Cramer-Rao bound."
    )
    _contact_figure(ctx, ch, plt, c, command)


def _zones(c: dict, e: list, forces: str, step: float) -> None:
    for zone, count in c["zone_counts"].items():
        e.append(
            new(
                f"palpation.contact.zone.{zone.replace(' ', '_')}",
                SECTION,
                count,
                "contacts",
                f"cases per identifiability zone ({forces} N, every {1000 * step:g} mm)",
            )
        )


def _contact_figure(ctx, ch, plt, c: dict, command: int = 20) -> None:
    """The contact study's position error beside its Cramer-Rao bound along the digit, read at ``command``."""
    fig, ax = plt.subplots(figsize=(7, 3.6))
    for f, marker in zip(np.unique(c["force_n"])[::-1], "os", strict=False):
        rows = c["force_n"] == f
        ax.semilogy(
            1000 * c["position_m"][rows], 1000 * c["rms_position_m"][rows], marker, label=f"RMS error, {-f:g} N"
        )
        ax.semilogy(1000 * c["position_m"][rows], 1000 * c["crlb_position_m"][rows], "-", label=f"Cramer-Rao, {-f:g} N")
    for x in ctx.params.geometry.gauge_positions_m:
        ax.axvline(1000 * x, color="0.7", lw=0.8)
    published = 1000 * studies.PUBLISHED["location_m"]
    ax.axhline(published, color="k", ls=":", label=_published_label(ctx, published))
    ax.set(xlabel="contact position from the base (mm)", ylabel="position error (mm)", ylim=(0.1, 300))
    ax.legend(fontsize=7, ncol=2)
    ch.figures.append(
        ctx.save_figure(
            fig,
            "palpation_contact_map",
            f"Contact position: error and bound along the digit (25 readings, command {command}; gauges grey)",
        )
    )


def _published_label(ctx, published_mm: float) -> str:
    """The published figure's legend: 1 % of the thesis rig's length, which is not 1 % of another digit's."""
    if ctx.thesis_rig:
        return "best published (1 % of length)"
    return f"best published {published_mm:.1f} mm (1 % of the thesis rig's {1000 * THESIS_LENGTH_M:.0f} mm)"


def _classification(ctx, ch, digit: DigitSetting | None = None) -> None:
    small = {
        "region_m": (0.12, 0.24),
        "extents_m": (0.04, 0.08, 0.12),
        "totals_n": (0.2, 0.4),
        "prior_total_step_n": 0.04,
        "truth_step_m": 0.04,
    }
    if digit is not None:  # the thesis's layout scaled to the digit; models of 3 and 9 cells a section in fast mode
        r = digit.scale
        cells = (3, 9) if ctx.fast else (9, 27)
        small.update(
            region_m=(0.12 * r, 0.24 * r),
            extents_m=tuple(w * r for w in small["extents_m"]),
            truth_step_m=0.04 * r,
            command=digit.command(12),
            estimator_model=digit.contact_model(cells[0]),
            truth_model=digit.contact_model(cells[1]),
        )
    cl = studies.classification_study(**small, repetitions=10, samples=100, seed=ctx.seed)
    e = ch.entries
    e.append(
        new(
            "palpation.classify.bayes_allows_fraction",
            SECTION,
            cl["allowed_fraction"],
            "",
            "share of the point and line-load settings where the Bayes limit tells them apart >= 95 % (25 readings)",
        )
    )
    e.append(
        new(
            "palpation.classify.accuracy_where_allowed",
            SECTION,
            cl["allowed_accuracy"],
            "",
            f"the estimator's Bayes-factor decision there (limit {cl['allowed_bayes']:.3f}); issue: >= 0.95",
        )
    )
    e.append(
        new(
            "palpation.classify.accuracy_overall",
            SECTION,
            cl["overall"],
            "",
            f"all settings (Bayes limit {cl['overall_bayes']:.3f}): a line load whose stretch covers no gauge "
            "reads exactly as a point at its centroid",
        )
    )
    ch.tables.append(cl["table"])


def _stiffness(ctx, ch, plt, digit: DigitSetting | None = None) -> None:
    protocol = PalpationProtocol(commands=tuple(range(8, 31, 2)))
    moduli = (300.0, 1500.0) if ctx.fast else (300.0, 750.0, 1500.0)
    on = {}
    if digit is not None:
        protocol, on = digit.protocol(2), {"model": digit.contact_model(), "placed": digit.tissue()}
    s = studies.stiffness_study(moduli, seeds=(ctx.seed,), protocol=protocol, **on)
    e = ch.entries
    e.append(
        new(
            "palpation.stiffness.max_rel_error",
            SECTION,
            s["max_abs_rel_error"],
            "",
            f"modulus fitted on one sweep each at {', '.join(f'{k / 100:g}' for k in moduli)} N/m per cm "
            f"({s['range']:.0f}x); issue <= 0.10, "
            "best published 0.10-0.16",
        )
    )
    e.append(
        new(
            "palpation.stiffness.rel_bound",
            SECTION,
            float(np.max(s["rel_bound"])),
            "",
            "largest Cramer-Rao bound of the relative modulus on those sweeps",
        )
    )
    ch.tables.append(s["table"])
    for k, r in zip(s["moduli_n_m2"], s["rel_error"], strict=True):
        e.append(new(f"palpation.stiffness.rel_error_at_{k / 100:g}_n_m_per_cm", SECTION, r, "", "table row"))
    result = studies.sweep_example(1000.0, protocol=protocol, seed=ctx.seed, **on)
    cv = result.curve
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    ax.errorbar(
        1000 * cv["indentation_m"], cv["force_n"], yerr=cv["force_sd_n"], fmt="o", ms=3, label="from the gauges"
    )
    ax.plot(1000 * cv["indentation_m"], cv["model_force_n"], "-", label="fitted tissue")
    ax.plot(1000 * cv["indentation_m"], cv["true_force_n"], "x", label="twin (truth)")
    ax.set(xlabel="indentation (mm)", ylabel="contact force (N)")
    ax.legend(fontsize=8)
    ch.figures.append(
        ctx.save_figure(
            fig,
            "palpation_force_indentation",
            f"Force against indentation, soft block (10 N/m per cm): fitted {result.fit.modulus_n_m2 / 100:.2f} +- "
            f"{result.fit.modulus_sd_n_m2 / 100:.2f} N/m per cm; lumped slope {result.lumped_stiffness_n_m:.1f} N/m",
        )
    )
    e.append(
        new(
            "palpation.stiffness.lumped_n_m",
            SECTION,
            result.lumped_stiffness_n_m,
            "N/m",
            "slope of force against deepest indentation, soft block (10 N/m per cm)",
        )
    )


def _scan(ctx, ch, plt, digit: DigitSetting | None = None) -> None:
    offsets = np.arange(-0.02, 0.0201, 0.01)
    if digit is None:
        sc = studies.scan_study(
            offsets_m=offsets, protocol=PalpationProtocol(commands=tuple(range(8, 31, 3))), seed=ctx.seed
        )
    else:  # the nodule under the outer part of the digit, as the thesis rig's 250 mm is (0.8 of the way on)
        offsets = offsets * digit.scale
        placed = digit.tissue()
        sc = studies.scan_study(
            offsets_m=offsets,
            protocol=digit.protocol(3),
            seed=ctx.seed,
            inclusion=(placed.start_m + 0.8 * (digit.length_m - placed.start_m), 0.01, 3.0),
            model=digit.contact_model(),
            placed=placed,
        )
    e = ch.entries
    e.append(
        new(
            "palpation.scan.inclusion_error_mm",
            SECTION,
            1000 * sc["centre_error_m"],
            "mm",
            f"a 10 mm nodule 3x stiffer, {1000 * sc['true_centre_m']:.0f} mm into the phantom, {len(offsets)} "
            f"offsets {1000 * (offsets[1] - offsets[0]):.0f} mm apart; issue: within 10 mm",
        )
    )
    e.append(
        new(
            "palpation.scan.ratio",
            SECTION,
            sc["ratio"],
            "",
            f"fitted stiffness ratio (+- {sc['ratio_sd']:.2f}); truth 3",
        )
    )
    fig, ax = plt.subplots(figsize=(5.5, 3.4))
    ax.errorbar(
        1000 * sc["map_position_m"],
        sc["map_modulus_n_m2"] / 100,
        yerr=sc["map_modulus_sd_n_m2"] / 100,
        fmt="o-",
        label="local fit",
    )
    ax.axvline(1000 * sc["centre_m"], color="r", label="inclusion found")
    ax.axvspan(1000 * sc["true_centre_m"] - 5, 1000 * sc["true_centre_m"] + 5, color="0.85", label="true nodule")
    ax.set(xlabel="position in the phantom (mm)", ylabel="stiffness (N/m per cm)")
    ax.legend(fontsize=8)
    ch.figures.append(ctx.save_figure(fig, "palpation_scan", "Stiffness map of a scan and the inclusion fitted to it"))


#: The force entries, the figure each is of (a hold ``palpate`` would refuse has none of them: each says why).
FORCE_KEYS = ("palpation.force.steady_error", "palpation.force.overshoot", "palpation.force.settling_s")


def _digit_hold(ctx, digit: DigitSetting):
    """``(study, tissue, "")`` of the hold ``flexdigit palpate --tissue soft-block --protocol hold --params D --seed
    S`` runs on the digit (the built-in soft block laid out beside it, :func:`~flexdigit.palpation.palpation.
    digit_tissue`; the built-in hold's setpoint, duration and gains; palpate's checks, the force read's uncertainty
    refused before the digit moves), or ``(None, tissue, reason)``: palpate's one line why it refuses it."""
    params = digit.params
    tissue = digit_tissue(load_tissue("soft-block")[0], params)
    hold = load_palpation_protocol("hold").force
    try:
        check_tissue_reach(tissue, params)
        f = studies.force_study(
            (tissue.modulus_n_m2,),
            setpoint_n=hold["setpoint_n"],
            duration_s=hold["duration_s"],
            seed=ctx.seed + 2,
            dt_s=twin_step_s("force", params),
            model=digit.contact_model(),
            placed=tissue,
            side=tissue.side,
            gain=hold["gain"],
            approach_rate=hold["approach_rate"],
            refuse_uncertain=True,
        )
    except (ParameterError, RigError) as exc:  # palpate's exit 2, in its one line
        return None, tissue, str(exc)
    reason = f["runs"][0].unreached()
    return (None, tissue, f"hold: {reason}") if reason else (f, tissue, "")


def _force(ctx, ch, plt, digit: DigitSetting | None = None) -> None:
    if digit is None:
        f = studies.force_study((1000.0,), duration_s=8.0, seed=ctx.seed + 2)
        setpoint = 0.1
    else:
        f, tissue, reason = _digit_hold(ctx, digit)
        if f is None:
            _force_refused(ch, tissue, reason)
            return
        setpoint = float(f["runs"][0].setpoint_n)
    run = f["runs"][0]
    e = ch.entries
    e.append(
        new(
            "palpation.force.steady_error",
            SECTION,
            float(f["steady_error"][0]),
            "",
            "0.1 N held on the 20 ms loop from the gauges' force estimate, true force over the last 3 s; issue: "
            "within 10 %",
        )
    )
    e.append(
        new(
            "palpation.force.overshoot",
            SECTION,
            float(f["overshoot"][0]),
            "",
            "largest true force over 0.1 N; issue: < 20 %",
        )
    )
    e.append(
        new("palpation.force.settling_s", SECTION, float(f["settling_s"][0]), "s", "last time outside 10 % of 0.1 N")
    )
    fig, ax = plt.subplots(figsize=(5.5, 3.2))
    ax.plot(run.time_s, run.true_force_n, label="true contact force")
    ax.plot(run.time_s, run.force_n, lw=0.6, alpha=0.7, label=estimate_label(run))
    ax.axhspan(0.09, 0.11, color="0.9", label="0.1 N +- 10 %")
    ax.set(xlabel="time (s)", ylabel="force (N)")
    ax.legend(fontsize=8)
    ch.figures.append(
        ctx.save_figure(
            fig, "palpation_force_control", f"Holding {setpoint:g} N against the soft block (twin, 20 ms loop)"
        )
    )


def _force_refused(ch, tissue, reason: str) -> None:
    """The force entries of a hold ``palpate`` refuses on this digit: "not applicable" and palpate's reason, no
    figure (never one ``palpate --protocol hold`` would not give)."""
    said = f"not applicable: {reason}"
    for key in FORCE_KEYS:
        ch.entries.append(
            new(key, SECTION, said, "", "`flexdigit palpate --tissue soft-block --protocol hold --params D` refuses it")
        )
    ch.paragraphs.append(
        "Force control: the built-in hold against the soft block laid out beside this digit "
        f"({1000 * tissue.start_m:.0f} mm on, {1000 * tissue.gap_m:.0f} mm away) is one `flexdigit palpate "
        f"--protocol hold` refuses on it, so no figure is shown: {reason}."
    )


#: The active study's prior grid (table 7.1's settings, palpation_studies.active_study): hangs every 20 mm, masses
#: 25 and 37.5 g (a third of the larger apart).
HANG_STEP_M, MASS_SPACING_REL = 0.02, (0.0375 - 0.025) / 0.0375
#: A Bayes limit over that discrete grid below this fraction of its spacing says only that the readings tell every
#: setting apart: the posterior sits on the true setting to rounding (1.6e-16 on a seven-section pair) and the limit
#: is the grid's, not the digit's: no figure to stand behind (tactile's own threshold for its settings limit).
UNRESOLVED_FRACTION = SETTINGS_RESOLVED


def _resolved(value: float, spacing: float, unit_scale: float = 1.0):
    """``value`` (times ``unit_scale``), or a "not determined" text where it is below the prior grid's resolution."""
    if value < UNRESOLVED_FRACTION * spacing:
        return (
            f"not determined: below {unit_scale * UNRESOLVED_FRACTION * spacing:.2g} (every setting of the discrete "
            f"prior told apart; its spacing {unit_scale * spacing:.3g})"
        )
    return unit_scale * value


def _unresolved_blank(table):
    """The active table with every Bayes-limit cell under its grid's resolution (:func:`_resolved`) left blank (NaN:
    null in results.json), as its entries say "not determined"; estimators' errors stay (a 0 is a count of hits)."""
    spacing = {"position_rmse_mm": 1000 * HANG_STEP_M, "magnitude_rel_rmse": MASS_SPACING_REL}
    rows = []
    for row in table.rows:
        cells = list(row)
        if str(row[0]).startswith("Bayes limit"):
            for j, column in enumerate(table.columns):
                if column in spacing and cells[j] < UNRESOLVED_FRACTION * spacing[column]:
                    cells[j] = math.nan
        rows.append(tuple(cells))
    return replace(table, rows=tuple(rows))


def estimate_label(run) -> str:
    """The force figure's label of the loop's estimate: one reading, or the mean of the hold's ``average_readings``
    (:func:`~flexdigit.palpation.palpation.hold_force` averages on a digit whose one reading is too noisy)."""
    averaged = int(run.region.get("average_readings", 1))
    return "estimate (one reading)" if averaged == 1 else f"estimate (mean of {averaged} readings)"


def _commands_text(commands) -> str:
    """``"commands 0, 20 and 40"``: the commands a study read, in words."""
    words = [str(int(c)) for c in commands]
    if len(words) == 1:
        return f"command {words[0]}"
    return f"commands {', '.join(words[:-1])} and {words[-1]}"


def _active(ctx, ch, digit: DigitSetting | None = None) -> None:
    on = {}
    if digit is not None:  # the hangs of chapter 7 (tip down or level, as TwinGaugeModel's default)
        on = {
            "commands": (digit.command(-8), digit.command(12), digit.command(32)),
            "model": TwinGaugeModel(digit.params, twin_calibration(digit.params)),
        }
    a = studies.active_study(samples=500 if ctx.fast else 1000, repetitions=10, seed=ctx.seed, **on)
    e = ch.entries
    commands = _commands_text(a["commands"])
    if digit is None:
        settings = "table 7.1's settings"
        single = "one reading at one command (chapter 7's 22.5 mm is this over its test split)"
    else:  # the hangs active_study lays out on the digit (palpation_studies.active_study)
        reach_mm = 1000 * min(0.18, 2.0 * digit.length_m / 3.0)
        settings = (
            f"25 and 37.5 g hung every {1000 * HANG_STEP_M:.0f} mm from the tip to {reach_mm:.0f} mm from it "
            "(table 7.1's settings on this digit)"
        )
        single = "one reading at one command"
    e.append(
        new(
            "palpation.active.bayes_position_mm",
            SECTION,
            _resolved(a["position_rmse_m"], HANG_STEP_M, 1000.0),
            "mm",
            f"{settings} read at {commands} under one hang (chapter 7's actuated noise)",
        )
    )
    e.append(
        new(
            "palpation.active.single_bayes_position_mm",
            SECTION,
            1000 * a["single_position_rmse_m"],
            "mm",
            f"the same settings, {single}",
        )
    )
    e.append(
        new(
            "palpation.active.bayes_magnitude",
            SECTION,
            _resolved(a["magnitude_rel_rmse"], MASS_SPACING_REL),
            "",
            f"single reading: {a['single_magnitude_rel_rmse']:.3f}",
        )
    )
    e.append(
        new(
            "palpation.active.posterior_position_mm",
            SECTION,
            1000 * a["posterior_position_rmse_m"],
            "mm",
            "the Bayes estimator on readings the twin draws",
        )
    )
    e.append(
        new(
            "palpation.active.inversion_position_mm",
            SECTION,
            1000 * a["inversion_position_rmse_m"],
            "mm",
            "maximum likelihood without the protocol's prior",
        )
    )
    ch.tables.append(_unresolved_blank(a["table"]))

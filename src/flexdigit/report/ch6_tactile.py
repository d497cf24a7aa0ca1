"""Report chapter 6: tactile sensing of the non-actuated digit (and the builder chapter 7 shares).

The experiment of table 6.1 is collected on the twin through the ``sim`` rig, the thesis's pipeline is run as
printed (sweeps, early stopping, corr2), then the same data are scored the way a user needs: millimetres, the
Cramer-Rao bound, contact and magnitude, and four estimators side by side.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from flexdigit.reference import thesis_value
from flexdigit.report import results
from flexdigit.report.chapter import Chapter, ReportContext
from flexdigit.rig.gauge_rails import railed_readings
from flexdigit.tactile.localisation import SETTINGS_RESOLVED
from flexdigit.tactile.pipeline import Normaliser
from flexdigit.tactile.protocols import load_protocol
from flexdigit.tactile.thesis_experiments import criteria, experiment_tables, position_ratios, run_experiment

TITLES = {
    "non_actuated": ("ch6-tactile", "Chapter 6: tactile sensing of the non-actuated digit", "6"),
    "actuated": ("ch7-tactile", "Chapter 7: tactile sensing of the actuated digit", "7"),
}
#: thesis figure numbers per experiment, in the order of the figures below
FIGURE_REFS = {
    "non_actuated": ("6.9", "6.10", "6.13", "6.14", "6.15", "6.16", "6.17", "6.18"),
    "actuated": ("7.3", "7.3", "7.4", "7.5", "7.6", "7.7", "7.8", "7.9"),
}


def build(ctx: ReportContext) -> Chapter:
    return build_tactile(ctx, "non_actuated")


def build_tactile(ctx: ReportContext, key: str) -> Chapter:
    """Chapter 6 (``non_actuated``) or 7 (``actuated``) from
    :func:`flexdigit.tactile.thesis_experiments.run_experiment`: entries, tables and figures."""
    exp = run_experiment(key, ctx.out_dir / "data", seed=ctx.seed, fast=ctx.fast, params=ctx.params)
    slug, title, _ = TITLES[key]
    chapter = Chapter(slug, title)
    chapter.paragraphs += _protocol_paragraphs(exp, ctx.fast, ctx.params if not ctx.thesis_rig else None)
    _pipeline_entries(exp, chapter.entries, ctx.thesis_rig)
    _beyond_entries(exp, chapter.entries, 1000 * ctx.params.geometry.digit_length_m)
    _bayes_entries(exp, chapter.entries)
    chapter.entries[:] = _not_applicable_without_identifiable(exp, chapter.entries)
    chapter.paragraphs.append(_criteria_paragraph(exp, ctx.thesis_rig))
    chapter.tables.extend(experiment_tables(exp))
    _figures(ctx, exp, chapter)
    return chapter


def _not_applicable_without_identifiable(exp, entries: list) -> list:
    """With no identifiable test reading (one gauge reads a load's position and mass as one number), the figures
    over identifiable readings are not defined: each says so and why, never a NaN (trial 3)."""
    if exp.localisation.extra["identifiable_fraction"] > 0:
        return entries
    why = "not applicable: no test reading is identifiable (its position and mass told apart) with this digit's gauges"
    return [
        dataclasses.replace(e, ours=why, unit="")
        if isinstance(e.ours, float) and not np.isfinite(e.ours) and e.key.startswith(f"{exp.key}.")
        else e
        for e in entries
    ]


def _protocol_paragraphs(exp, fast: bool, digit=None) -> list[str]:
    """The protocol, the network and (chapter 7) the noise in words; ``digit``: the params of a digit other than
    the thesis rig (None on the thesis rig, whose texts are as they were)."""
    ds = exp.dataset
    protocol = ds.protocol
    straight = ""
    if digit is not None and protocol.actuated:
        straight = _digit_commands_text(digit)
    setup = (
        f"cable attached, commands {list(protocol.actuation_commands)}{straight}"
        if protocol.actuated
        else "cable detached (actuation disabled)"
    )
    gauges = ds.gauges_v.shape[1]
    inputs = "3 gauge inputs" if digit is None else f"{gauges} gauge input{'s' if gauges > 1 else ''}"
    out = [
        f"Protocol {protocol.name} ({protocol.thesis_ref}) collected on the twin through the sim rig: digit "
        f"horizontal, {setup}, {protocol.repetitions} readings per setting {1000 * protocol.sample_interval_s:g} ms "
        f"apart after {protocol.settle_s:g} s of settling (the thesis gives neither; the twin's digit rings for ~15 s "
        "after a weight is hung, and readings taken sooner carry the previous setting's swing). "
        f"{len(ds)} readings, of which {int(np.sum(ds['load_kg'] > 0))} loaded.",
        "The position network sees the loaded readings (the no-load readings 'assist in the determination of the "
        "load/no load and load magnitude prediction networks', 6.5; table 7.1's count of 1500 has none); its "
        "target is the position number of the table (1 = tip), as printed. The variant that also feeds the "
        f"no-load readings as position 0 is scored too. Network: {inputs}, tanh hidden layer, linear "
        "output, NETLAB SCG, epochs of 50 iterations with early stopping on the validation third; the 'learning "
        "gradient' is SCG's termination tolerance (NETLAB options(2) and options(3)).",
    ]
    if exp.key == "actuated" and digit is not None:
        out.append(
            "The twin's taut cable brings cable-guide friction, a random share of the tension gained or lost across "
            "the guides before each gauge's section, drawn afresh whenever a weight is hung, lifted or re-hung (the "
            "thesis protocols re-hang before every reading) and zero when the cable is slack; its level is the one "
            "calibrated to the thesis rig's chapter 7 corr2 (see the chapter on the twin's noise)."
        )
    elif exp.key == "actuated":
        out.append(
            "The twin's noise was revisited for this chapter (issue 7), not the pipeline: a taut cable brings "
            "cable-guide friction, a random share of the tension gained or lost across the guides before each "
            "gauge's section, drawn afresh whenever a weight is hung, lifted or re-hung (the thesis protocols "
            "re-hang before every reading) and zero when the cable is slack (so chapter 6 is unchanged); its level "
            "is calibrated to this chapter's corr2 (see the chapter on the twin's noise). Before, with no such "
            "noise (default calibration up to commit 3491245), this chapter gave corr2 0.990 against 0.8998, the "
            "best estimator 6.6 mm = 0.80 x the thesis network, a worst error / bound of 2.39, contact and "
            "magnitude met."
        )
    if digit is not None:
        railed = railed_readings(ds.gauges_v, digit.sensors)
        if railed:
            out.append(f"Readings at an ADC rail are kept (they say only that the gauge is past the range): {railed}.")
    if fast:
        out.append("Fast mode: reduced sweeps (3 coarse sizes, +-1 fine, 3 gradients, 10 epochs).")
    return out


def _digit_commands_text(digit) -> str:
    """How the thesis's commands 0, 20, 40 were laid out on the digit (:func:`flexdigit.tactile.protocols.
    digit_commands`, as ``flexdigit collect --params`` lays them out)."""
    a = digit.actuator
    low, high = a.operating_commands
    ways = "both ways on its cable pair" if digit.cables.count == 2 else "below straight its cable slack"
    return (
        f" (the thesis's 0, 20, 40 laid out on this digit: the same fractions of its operating range {low}..{high} "
        f"from its straight command {a.equilibrium_command} as of the thesis rig's 8..43 from 8, {ways}; as "
        "`flexdigit collect --params` lays them out)"
    )


#: Why a corr2 away from the thesis's would be: the noise, revisited in its own chapter (``report.ch6_7_noise``).
NOISE_NOTE = {
    "non_actuated": "The pipeline is the thesis's; the twin's white gauge noise sets corr2 (chapter on the twin's "
    "noise: tactile.noise_scan). One white level cannot match both chapters; the actuated loss is the cable-guide "
    "friction, which needs a taut cable and so is absent here.",
    "actuated": "The pipeline is the thesis's; the twin's cable-guide friction sets corr2 (chapter on the twin's "
    "noise: tactile.friction_study), fitted so that the mean over 8 seeds is 0.8998; one run scatters by about "
    "0.02 from seed to seed.",
}


def _pipeline_entries(exp, e: list, thesis_rig: bool = True) -> None:
    """The thesis pipeline as printed: sample count, corr2 at the printed optimum and at ours, the optimum."""
    key = exp.key
    chap = TITLES[key][2]
    sec = f"tactile.{key}"
    sweep, opt = exp.sweep, exp.at_thesis_optimum
    thesis_corr2 = float(thesis_value(f"{sec}.test_corr2"))
    tol = 0.03 / thesis_corr2  # the issue's +-0.03 on corr2, as a relative tolerance
    best_h = int(thesis_value(f"{sec}.best_hidden"))
    best_g = float(thesis_value(f"{sec}.best_learning_gradient"))
    table_section = f"{chap}.{'9' if chap == '6' else '5'}"
    optimum_section = f"{chap}.{'8' if chap == '6' else '4'}"
    e += [
        results.compare(
            f"{key}.samples",
            f"{chap}.{'4' if chap == '6' else '1'}",
            int(thesis_value(f"{sec}.samples")),
            load_protocolsamples(key) if thesis_rig else _loaded_readings(exp),
            "readings",
            rtol=0.0,
            note=f"protocol {'thesis-6.1' if chap == '6' else 'thesis-7.1'} as printed"
            if thesis_rig
            else f"loaded readings of protocol {exp.dataset.protocol.name} collected on this digit",
        ),
        results.compare(
            f"{key}.test_corr2_at_thesis_optimum",
            table_section,
            thesis_corr2,
            opt.corr2,
            "",
            rtol=tol,
            note=f"{best_h} hidden nodes, learning gradient {best_g:g}, twin default calibration"
            + ("; within +-0.03 counts as a match." if thesis_rig else "."),
            discrepancy_note=NOISE_NOTE[key],
        ),
        results.compare(
            f"{key}.test_corr2_swept",
            table_section,
            thesis_corr2,
            sweep.corr2,
            "",
            rtol=tol,
            note=f"at our own sweep's optimum: {sweep.best_hidden} nodes, gradient {sweep.best_tol:g}.",
            discrepancy_note=NOISE_NOTE[key],
        ),
        results.compare(
            f"{key}.best_hidden",
            optimum_section,
            best_h,
            sweep.best_hidden,
            "nodes",
            rtol=0.0,
            discrepancy_note="The validation error is nearly flat over the sizes (figures below; the thesis says the "
            "same of 10-60 nodes in 6.8), so which size wins is decided by noise and initial weights.",
        ),
        results.compare(
            f"{key}.best_learning_gradient",
            optimum_section,
            best_g,
            sweep.best_tol,
            "",
            rtol=0.0,
            discrepancy_note="Every tolerance of 1e-4 and below gives the same validation error: SCG stops on the "
            "50 x 50 iteration budget or early stopping before meeting them, so the 'optimum' is a coin toss "
            "among equals; only 1e-1..1e-3 stop training early and cost accuracy.",
        ),
    ]
    _variant_entries(exp, e, thesis_rig)


def _loaded_readings(exp) -> int:
    return int(np.sum(exp.dataset["load_kg"] > 0))


def _variant_entries(exp, e: list, thesis_rig: bool = True) -> None:
    """The no-load variant (chapter 6) and the share of small percentage errors the thesis describes."""
    key = exp.key
    chap = TITLES[key][2]
    sec = f"tactile.{key}"
    table_section = f"{chap}.{'9' if chap == '6' else '5'}"
    opt = exp.at_thesis_optimum
    if chap == "6":
        e.append(
            results.new(
                f"{key}.test_corr2_with_no_load_as_position_0",
                "6.9",
                exp.extra["with_no_load"].corr2,
                "",
                "All 1275 readings, no-load readings as position 0 (table 6.1's first row). A weight 24 cm from the "
                "tip hangs 3 cm from the clamp, before gauge 1 (45 mm): no gauge bends, so it reads exactly as no "
                "load and the network can only split the difference between positions 16 and 0."
                if thesis_rig
                else f"All {len(exp.dataset)} readings, no-load readings as position 0 (table 6.1's first row); a "
                "weight hung before the first gauge reads exactly as no load.",
            )
        )
    pe = opt.percent_error
    bound = thesis_value(f"{sec}.percent_error_mostly_below")
    e.append(
        results.new(
            f"{key}.test_fraction_percent_error_below_{bound}",
            table_section,
            float(np.mean(pe[np.isfinite(pe)] < float(bound))),
            "",
            "Fraction of test readings whose percentage error (of the position number) is below the bound the "
            "thesis says 'generally' holds; it is a relative error, so it is harsh near the tip (position 1).",
        )
    )


def _beyond_entries(exp, e: list, length_mm: float) -> None:
    """Beyond the thesis: millimetres, the Cramer-Rao bound, contact and magnitude, four estimators."""
    key, chap = exp.key, TITLES[exp.key][2]
    loc = exp.localisation
    best = loc.best
    rm = loc.position_rmse_identifiable_m
    thesis_mlp = exp.thesis_mlp_position_m["rmse_identifiable_m"]
    best_h = int(thesis_value(f"tactile.{key}.best_hidden"))
    e += [
        results.new(
            f"{key}.thesis_mlp_position_rmse_mm",
            f"{chap} (new)",
            1000 * thesis_mlp,
            "mm",
            f"The thesis network ({best_h} nodes, position-number target) on its loaded, identifiable test "
            f"readings, numbers mapped back to distances: {100 * thesis_mlp / (length_mm / 1000):.2f} % of the "
            f"{length_mm:g} mm digit, for corr2 {exp.at_thesis_optimum.corr2:.4f}.",
        ),
        results.new(
            f"{key}.best_estimator_position_rmse_mm",
            f"{chap} (new)",
            1000 * rm[best],
            "mm",
            f"Best of four estimators on identical (tared) data: {best}; {100 * rm[best] * 1000 / length_mm:.2f} % "
            f"of the digit; {rm[best] / thesis_mlp:.2f} x the thesis network's RMSE.",
        ),
        results.new(
            f"{key}.crlb_rms_mass_unknown_mm",
            f"{chap} (new)",
            1000 * loc.crlb_rms_identifiable_m,
            "mm",
            "Cramer-Rao bound of one reading (twin sensitivity by finite differences of its static model; white "
            "noise, the cable-guide friction at the load's tension when the cable is taut, and the drift "
            "accumulated since the test's tare), RMS over the identifiable test readings, "
            f"position and mass both unknown. Best estimator / bound = {rm[best] / loc.crlb_rms_identifiable_m:.3f}.",
        ),
        results.new(
            f"{key}.crlb_rms_mass_known_mm",
            f"{chap} (new)",
            1000 * loc.crlb_known_rms_identifiable_m,
            "mm",
            f"The same bound with the mass known. Best estimator / bound = "
            f"{rm[best] / loc.crlb_known_rms_identifiable_m:.3f}. Learned estimators can go below it: they learn "
            "that positions and masses come from the protocol's short lists, which the bound does not assume.",
        ),
        results.new(
            f"{key}.best_estimator_rmse_over_crlb_worst_position",
            f"{chap} (new)",
            max(position_ratios(exp).values(), default=float("nan")),
            "",
            "The RMS bound above is dominated by a few nearly confounded positions, so per position: the largest "
            f"ratio of the best estimator's RMSE ({best}) to that position's bound (mass unknown) over the "
            "identifiable positions of the test set (1.25 is the issue's target; below 1 is possible, see above).",
        ),
        results.new(
            f"{key}.contact_accuracy_visible",
            f"{chap} (new)",
            max(loc.contact_accuracy_visible.values()),
            "",
            "Load / no load on the test readings a load can be seen on (every no-load reading, and loads that bend "
            "a gauge), best of the contact network and the inversion's likelihood-ratio test; over all test "
            f"readings: {', '.join(f'{k} {v:.4f}' for k, v in loc.contact_accuracy.items())}.",
        ),
        results.new(
            f"{key}.magnitude_rel_rmse_identifiable",
            f"{chap} (new)",
            min(loc.magnitude_rel_rmse_identifiable.values()),
            "",
            "RMS relative error of the load estimate on identifiable test readings, best estimator ("
            + ", ".join(f"{k} {v:.3f}" for k, v in loc.magnitude_rel_rmse_identifiable.items())
            + ").",
        ),
    ]


def _bayes_entries(exp, e: list) -> None:
    """The Bayes limits: the best any estimator that knows the protocol can do on the same test readings."""
    key, chap = exp.key, TITLES[exp.key][2]
    loc = exp.localisation
    rm = loc.position_rmse_identifiable_m
    thesis_mlp = exp.thesis_mlp_position_m["rmse_identifiable_m"]
    bayes = loc.bayes
    floor_pos = bayes["position_rmse_identifiable_m"]
    visible = int(np.sum(loc.extra["contact_visible"]))
    unresolved = _unresolved_floor(exp)
    ratios = (
        f"Best estimator / limit = {rm[loc.best] / floor_pos:.2f}; the thesis network / limit = "
        f"{thesis_mlp / floor_pos:.2f}."
        if not unresolved
        else "No ratio to it: it is not determined."
    )
    e += [
        results.new(
            f"{key}.bayes_position_rmse_identifiable_mm",
            f"{chap} (new)",
            unresolved or 1000 * floor_pos,
            "mm",
            "Bayes limit: the RMS position error of the best possible estimator that knows the protocol's settings "
            "(positions, loads, commands, their frequencies) and the twin's noise, on the identifiable test "
            "readings (Monte Carlo, tactile.bounds.protocol_limits). Unlike the Cramer-Rao bound, learned "
            f"estimators cannot beat it. {ratios}",
        ),
        results.new(
            f"{key}.bayes_magnitude_rel_rmse_identifiable",
            f"{chap} (new)",
            bayes["magnitude_rel_rmse_identifiable"],
            "",
            "Bayes limit of the load's RMS relative error on the identifiable test readings (same model).",
        ),
        results.new(
            f"{key}.bayes_contact_accuracy_visible",
            f"{chap} (new)",
            bayes["contact_accuracy_visible"],
            "",
            "Bayes limit of load / no-load accuracy on the test readings a load can be seen on (same model; "
            f"expected errors on these {visible} readings: {visible * (1 - bayes['contact_accuracy_visible']):.1f}).",
        ),
    ]


def _unresolved_floor(exp) -> str:
    """ "not determined: ..." where the position's Bayes limit is under tactile's :data:`~flexdigit.tactile.
    localisation.SETTINGS_RESOLVED` of the protocol's position step (its Monte Carlo never mixed two positions: the
    limit is rounding, 0 on a quiet full-bridge pair), else "" (a figure, or NaN: nothing identifiable)."""
    floor = exp.localisation.bayes["position_rmse_identifiable_m"]
    positions = np.sort(np.asarray(exp.dataset.protocol.positions_from_tip_m, dtype=float))
    step = float(np.median(np.diff(positions))) if positions.size > 1 else 0.0
    if not np.isfinite(floor) or floor >= SETTINGS_RESOLVED * step:
        return ""
    return (
        f"not determined: below {1000 * SETTINGS_RESOLVED * step:.2g} mm (the readings tell every position of the "
        "protocol apart: the limit is the settings grid's rounding, not the digit's)"
    )


def load_protocolsamples(key: str) -> int:
    """Readings of the protocol as printed (thesis-6.1, thesis-7.1)."""
    return load_protocol("thesis-6.1" if key == "non_actuated" else "thesis-7.1").sample_count


def _criteria_paragraph(exp, thesis_rig: bool = True) -> str:
    """Issue 7's criteria on this experiment, each with its figure, and why a failing one fails."""
    loc = exp.localisation
    best = loc.best
    rm = loc.position_rmse_identifiable_m
    thesis_mlp_m = exp.thesis_mlp_position_m["rmse_identifiable_m"]
    corr2_ours = exp.at_thesis_optimum.corr2
    corr2_thesis = float(thesis_value(f"tactile.{exp.key}.test_corr2"))
    met = {name: ok for name, _, _, ok in criteria(exp, corr2_ours)}
    value = {name: v for name, v, _, _ in criteria(exp, corr2_ours)}
    contact_name = max(loc.contact_accuracy_visible, key=loc.contact_accuracy_visible.get)
    corr2 = [(f"corr2 {corr2_ours:.4f} within +-0.03 of {corr2_thesis}", "corr2_distance_from_thesis")]
    labels = [
        *(corr2 if thesis_rig else []),  # the thesis's corr2 is its rig's: no criterion for another digit
        (
            f"best estimator ({best}) {1000 * rm[best]:.1f} mm = {rm[best] / thesis_mlp_m:.2f} x the thesis network's "
            f"{1000 * thesis_mlp_m:.1f} mm (<= 0.5)",
            "best_over_thesis_network",
        ),
        (
            f"its worst per-position error / Cramer-Rao bound {value['worst_position_rmse_over_crlb']:.2f} (<= 1.25)",
            "worst_position_rmse_over_crlb",
        ),  # fmt: skip
        (
            f"contact {100 * value['contact_accuracy_visible']:.1f} % on the readings where some gauge bends (>= 99 %; "
            f"{100 * loc.contact_accuracy[contact_name]:.1f} % on all test readings: a load no gauge sees reads as "
            "no load)",
            "contact_accuracy_visible",
        ),
        (f"magnitude {100 * value['magnitude_rel_rmse']:.1f} % RMS (<= 10 %)", "magnitude_rel_rmse"),
    ]
    if not np.isfinite(rm[best]):  # no identifiable reading (one gauge): no position or magnitude figure to quote
        labels = [item for item in labels if item[1] in ("corr2_distance_from_thesis", "contact_accuracy_visible")]
        labels.append(("position and magnitude: no identifiable test reading to score", "best_over_thesis_network"))
    text = "Issue 7's criteria on this experiment: " + "; ".join(
        f"{label}: {'met' if met[name] else 'NOT met'}" for label, name in labels
    )
    text += "." + _bayes_sentence(exp, thesis_mlp_m, thesis_rig)
    if met["best_over_thesis_network"] and met["worst_position_rmse_over_crlb"]:
        return text
    ratios = np.array(list(position_ratios(exp, "thesis network").values()))
    if not ratios.size:  # e.g. one gauge, command fixed: one voltage cannot tell both position and mass
        return text + (
            " Why: no test reading is identifiable: with the mass unknown, this digit's gauges cannot tell the "
            "position and the mass of a load apart (the Cramer-Rao bound is infinite), so the ratio-to-bound "
            "criterion has nothing to score."
        )
    spread = float(np.std(np.unique(exp.dataset["position_from_tip_m"][exp.dataset["load_kg"] > 0])))
    ident = loc.zone == "identifiable"
    over = float(np.mean(loc.crlb_m[ident] > spread)) if ident.any() else float("nan")
    text += (
        f" Why: position by position the thesis network is already at {np.min(ratios):.2f}-{np.max(ratios):.2f} x "
        f"the one-reading bound (median {np.median(ratios):.2f}), i.e. mostly below it: the bound exceeds the spread "
        f"of the protocol's positions ({1000 * spread:.0f} mm standard deviation) on {over:.0%} of the identifiable "
        "test readings, and a network that has learnt the protocol's short list of positions and loads beats it by "
        "shrinking towards them. An estimator at half its error would sit at half those ratios, further below a "
        "bound no unbiased estimator can cross, so with "
        + ("the noise that reproduces the thesis's corr2" if thesis_rig else "this noise")
        + " the 0.5 x "
        "criterion asks for more than one reading holds, and the ratio-to-bound metric is ill-posed (estimators "
        "beat it by using the protocol, not the gauges)."
    )
    if not met["contact_accuracy_visible"]:
        text += _contact_sentence(exp, contact_name)
    return text


def _bayes_sentence(exp, thesis_mlp_m: float, thesis_rig: bool = True) -> str:
    loc = exp.localisation
    rm = loc.position_rmse_identifiable_m
    bayes = loc.bayes
    floor_pos = bayes["position_rmse_identifiable_m"]
    floor_mag = bayes["magnitude_rel_rmse_identifiable"]
    floor_contact = bayes["contact_accuracy_visible"]
    unresolved = _unresolved_floor(exp)
    position = (
        f"position {unresolved}"
        if unresolved
        else f"position {1000 * floor_pos:.1f} mm (best estimator at {rm[loc.best] / floor_pos:.2f} x, thesis "
        f"network at {thesis_mlp_m / floor_pos:.2f} x)"
    )
    text = (
        " The Bayes limits (the best any estimator that knows the protocol can do on these readings, twin noise "
        f"model): {position}, magnitude {100 * floor_mag:.1f} %, contact {100 * floor_contact:.2f} %."
    )
    if not np.isfinite(floor_pos):  # nothing identifiable: the position and magnitude limits are not defined
        text = (
            " The Bayes limit of contact (the best any estimator that knows the protocol can do on these readings, "
            f"twin noise model): {100 * floor_contact:.2f} %; position and magnitude have none (nothing identifiable)."
        )
    unreachable = []
    if not unresolved and 0.5 * thesis_mlp_m < floor_pos:
        unreachable.append(
            f"half the thesis network's error ({1000 * 0.5 * thesis_mlp_m:.1f} mm) is below the position limit"
        )
    if floor_contact < 0.99:
        unreachable.append(f"99 % contact is above the contact limit ({100 * floor_contact:.2f} %)")
    if floor_mag > 0.10:
        unreachable.append(f"10 % magnitude is below the magnitude limit ({100 * floor_mag:.1f} %)")
    if unreachable:
        text += (
            " So with this noise no estimator can meet every criterion: "
            + "; ".join(unreachable)
            + (
                ". The noise that reproduces the thesis's corr2 leaves too little in one reading."
                if thesis_rig
                else ". This digit's noise leaves too little in one reading."
            )
        )
    return text


def _contact_sentence(exp, name: str) -> str:
    loc = exp.localisation
    crow = loc.extra["contact_rows"]
    wrong = loc.extra["contact_pred"][name] != (exp.dataset["load_kg"][crow] > 0)
    where = exp.dataset["position_from_tip_m"][crow][wrong]
    cmds = exp.dataset["command"][crow][wrong]
    labels = [f"load {100 * w:g} cm from the tip" if np.isfinite(w) else "no load" for w in where]
    counts = {k: labels.count(k) for k in sorted(set(labels))}
    return (
        f" Contact ({name}) errs on {int(wrong.sum())} of {crow.size} test readings ("
        + ", ".join(f"{k}: {v}" for k, v in counts.items())
        + f"; commands {sorted(set(cmds.tolist()))}): a load near the clamp bends gauge 1 by only a few standard "
        "deviations of the friction at those tensions, and the friction scatters the no-load readings alike."
    )


def _figures(ctx: ReportContext, exp, chapter: Chapter) -> None:
    """Figures beside the thesis's (6.9-6.18 or 7.3-7.9), then the bound along the digit."""
    import matplotlib.pyplot as plt

    slug = TITLES[exp.key][0]
    refs = FIGURE_REFS[exp.key]
    figs = chapter.figures
    figs.append(_fig_raw(ctx, exp, slug, refs[0], plt))
    figs.append(_fig_normalised(ctx, exp, slug, refs[1], plt))
    figs.append(_fig_error_curves(ctx, exp.sweep, slug, refs[2], plt))
    figs.extend(_fig_sweeps(ctx, exp.sweep, slug, refs[3:6], plt))
    figs.extend(_fig_test(ctx, exp.at_thesis_optimum, slug, refs[6:8], plt))
    figs.append(_fig_bound(ctx, exp, slug, plt))


def _fig_error_curves(ctx, sweep, slug, ref, plt):
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    it = np.arange(sweep.curve_train.size) * 50
    ax.semilogy(it, sweep.curve_train, label="training")
    ax.semilogy(it, sweep.curve_val, label="validation")
    ax.set(
        xlabel="SCG iterations",
        ylabel="mean squared error (position no.^2)",
        title=f"{sweep.curve_hidden} hidden nodes",
    )
    ax.legend()
    return ctx.save_figure(
        fig,
        f"{slug}-error-vs-iteration",
        "Training and validation error against iterations (epochs of 50)",
        thesis_ref=f"figure {ref}",
    )


def _fig_sweeps(ctx, sweep, slug, refs, plt):
    out = []
    for pts, name, ref, label in (
        (sweep.coarse, "coarse", refs[0], "hidden nodes"),
        (sweep.fine, "fine", refs[1], "hidden nodes"),
        (sweep.gradient, "gradient", refs[2], "learning gradient (SCG tolerance)"),
    ):
        if not pts:
            continue
        fig, ax = plt.subplots(figsize=(5.5, 3.6))
        xs = [p.tol if name == "gradient" else p.hidden for p in pts]
        ax.plot(xs, [p.train_mse for p in pts], "o-", label="training")
        ax.plot(xs, [p.val_mse for p in pts], "s-", label="validation")
        if name == "gradient":
            ax.set_xscale("log")
        ax.set(xlabel=label, ylabel="MSE at the early-stopping epoch")
        ax.legend()
        out.append(
            ctx.save_figure(
                fig, f"{slug}-sweep-{name}", f"Error against {label} ({name} sweep)", thesis_ref=f"figure {ref}"
            )
        )
    return out


def _fig_test(ctx, opt, slug, refs, plt):
    fig, ax = plt.subplots(figsize=(6, 3.6))
    k = np.arange(opt.y_test.size)
    ax.plot(k, opt.y_test, "r.", label="actual")
    ax.plot(k, opt.y_pred, "b.", ms=3, label="predicted")
    ax.set(xlabel="test reading", ylabel="position number (1 = tip)")
    ax.legend()
    first = ctx.save_figure(
        fig,
        f"{slug}-predicted-actual",
        f"Predicted and actual test positions, corr2 {opt.corr2:.4f}",
        thesis_ref=f"figure {refs[0]}",
    )
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.bar(k, np.nan_to_num(opt.percent_error), color="C0")
    ax.set(xlabel="test reading", ylabel="percentage error (%)")
    second = ctx.save_figure(
        fig, f"{slug}-percent-error", "Percentage error of every test reading", thesis_ref=f"figure {refs[1]}"
    )
    return [first, second]


def _fig_raw(ctx, exp, slug, ref, plt):
    ds = exp.dataset
    loaded = ds["load_kg"] > 0
    gauges = ds.gauges_v.shape[1]  # the digit's G gauges, one panel each (the thesis rig's 3)
    fig, axes = plt.subplots(1, gauges, figsize=(11 * max(gauges, 3) / 3, 3.4), sharex=True, squeeze=False)
    for i, ax in enumerate(axes[0]):
        for m in np.unique(ds["load_kg"][loaded]):
            for c in np.unique(ds["command"]):
                sel = loaded & (ds["load_kg"] == m) & (ds["command"] == c)
                lab = f"{1000 * m:g} g" + (f", cmd {c}" if c >= 0 else "")
                ax.plot(100 * ds["position_from_tip_m"][sel], ds.gauges_v[sel, i], ".", ms=2, label=lab)
        ax.set(title=f"gauge {i + 1}", xlabel="load position from tip (cm)", ylabel="V" if i == 0 else None)
    axes[0, 0].legend(fontsize=6)
    return ctx.save_figure(
        fig,
        f"{slug}-raw",
        "Gauge voltages against load position, every load (not normalised)",
        thesis_ref=f"figure {ref}",
    )


def _fig_normalised(ctx, exp, slug, ref, plt):
    ds = exp.dataset.subset(exp.pipeline_rows)
    split = exp.sweep.split
    x = ds.gauges_v
    z = Normaliser().fit(x[split.train]).transform(x[np.concatenate([split.train, split.val, split.test])])
    fig, ax = plt.subplots(figsize=(6, 3.4))
    for i in range(z.shape[1]):
        ax.plot(z[:, i], ".", ms=2, label=f"gauge {i + 1}")
    ax.set(xlabel="reading (shuffled: training, validation, test)", ylabel="normalised (E 6.1)")
    ax.legend(fontsize=7)
    return ctx.save_figure(
        fig,
        f"{slug}-normalised",
        "Normalised, shuffled gauge data (training mean and variance)",
        thesis_ref=f"figure {ref}",
    )


def _fig_bound(ctx, exp, slug, plt):
    ident = exp.identifiability
    loc = exp.localisation
    a = ident["position_from_base_m"]
    length = a[-1]
    fig, ax = plt.subplots(figsize=(7, 3.8))
    for case in ident["cases"]:
        lab = f"{1000 * case['mass_kg']:g} g" + (f", cmd {case['command']}" if case["command"] >= 0 else "")
        ax.semilogy(100 * (length - a), 1000 * case["crlb_known_m"], "-", lw=1, label=f"CRLB mass known, {lab}")
    for k, v in loc.position_pred_m.items():
        p = np.unique(loc.position_true_m)
        r = [1000 * np.sqrt(np.mean((v[loc.position_true_m == q] - q) ** 2)) for q in p]
        ax.semilogy(100 * p, r, "o", ms=4, label=k)
    zones = ident["cases"][0]["zone"]
    for z, color in (("no gauge bends", "0.85"), ("position and mass confounded", "#fde9c9")):
        sel = zones == z
        if sel.any():
            tip = 100 * (length - a[sel])
            ax.axvspan(tip.min(), tip.max(), color=color, zorder=0, label=z)
    ax.set(xlabel="load position from tip (cm)", ylabel="position error (mm)")
    ax.legend(fontsize=6, ncol=2)
    return ctx.save_figure(
        fig,
        f"{slug}-bound",
        "Cramer-Rao bound along the digit (one reading) and every "
        "estimator's RMSE per position; shaded: where no gauge bends, and where position and "
        "mass are confounded (zones for the first load)",
    )

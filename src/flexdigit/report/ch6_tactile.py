"""Report chapter 6: tactile sensing of the non-actuated digit (and the builder chapter 7 shares).

The experiment of table 6.1 is collected on the twin through the ``sim`` rig, the thesis's pipeline is run as
printed (sweeps, early stopping, corr2), then the same data are scored the way a user needs: millimetres, the
Cramer-Rao bound, contact and magnitude, and four estimators side by side.
"""

from __future__ import annotations

import numpy as np

from flexdigit.reference import thesis_value
from flexdigit.report import results
from flexdigit.report.chapter import Chapter, ReportContext, Table

TITLES = {
    "non_actuated": ("ch6-tactile", "Chapter 6: tactile sensing of the non-actuated digit", "6"),
    "actuated": ("ch7-tactile", "Chapter 7: tactile sensing of the actuated digit", "7"),
}
#: thesis figure numbers per experiment, in the order of the figures below
FIGURE_REFS = {
    "non_actuated": ("6.9", "6.10", "6.13", "6.14", "6.15", "6.16", "6.17", "6.18"),
    "actuated": ("7.3", "7.3", "7.4", "7.5", "7.6", "7.7", "7.8", "7.9"),
}
NOISE_SCALES = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)


def build(ctx: ReportContext) -> Chapter:
    return build_tactile(ctx, "non_actuated")


def build_tactile(ctx: ReportContext, key: str) -> Chapter:
    """Chapter 6 (``non_actuated``) or 7 (``actuated``)."""
    import matplotlib.pyplot as plt

    from flexdigit.tactile.thesis_experiments import run_experiment

    slug, title, chap = TITLES[key]
    refs = FIGURE_REFS[key]
    seed = ctx.seed
    exp = run_experiment(key, ctx.out_dir / "data", seed=seed, fast=ctx.fast, params=ctx.params)
    ds = exp.dataset
    protocol = ds.protocol
    length_mm = 1000 * ctx.params.geometry.digit_length_m
    sec = f"tactile.{key}"
    chapter = Chapter(slug, title)
    printed_samples = int(thesis_value(f"{sec}.samples"))
    chapter.paragraphs += [
        f"Protocol {protocol.name} ({protocol.thesis_ref}) collected on the twin through the sim rig: digit "
        f"horizontal, {'cable attached, commands ' + str(list(protocol.actuation_commands)) if protocol.actuated else 'cable detached (actuation disabled)'}"  # noqa: E501
        f", {protocol.repetitions} readings per setting {1000 * protocol.sample_interval_s:g} ms apart after "
        f"{protocol.settle_s:g} s of settling (the thesis gives neither; the twin's digit rings for ~15 s after a "
        "weight is hung, and readings taken sooner carry the previous setting's swing). "
        f"{len(ds)} readings, of which {int(np.sum(ds['load_kg'] > 0))} loaded.",
        "The position network sees the loaded readings (the no-load readings 'assist in the determination of the "
        "load/no load and load magnitude prediction networks', 6.5; table 7.1's count of 1500 has none); its "
        "target is the position number of the table (1 = tip), as printed. The variant that also feeds the "
        "no-load readings as position 0 is scored too. Network: 3 gauge inputs, tanh hidden layer, linear "
        "output, NETLAB SCG, epochs of 50 iterations with early stopping on the validation third; the 'learning "
        "gradient' is SCG's termination tolerance (NETLAB options(2) and options(3)).",
    ]
    if key == "actuated":
        chapter.paragraphs.append(
            "The twin's noise was revisited for this chapter (issue 7), not the pipeline: a taut cable now brings "
            "cable-guide friction, a random share of the tension gained or lost across the guides before each "
            "gauge's section, drawn every reading and zero when the cable is slack (so chapter 6 is unchanged); "
            "its level is calibrated to this chapter's corr2 (tables and entries below). Before, with no such "
            "noise (default calibration up to commit 3491245), this chapter gave corr2 0.990 against 0.8998, the "
            "best estimator 6.6 mm = 0.80 x the thesis network, a worst error / bound of 2.39, contact and "
            "magnitude met."
        )
    if ctx.fast:
        chapter.paragraphs.append("Fast mode: reduced sweeps (3 coarse sizes, +-1 fine, 3 gradients, 10 epochs).")

    # ------------------------------------------------------------------- the thesis pipeline, as printed
    sweep, opt = exp.sweep, exp.at_thesis_optimum
    thesis_corr2 = float(thesis_value(f"{sec}.test_corr2"))
    tol = 0.03 / thesis_corr2  # the issue's +-0.03 on corr2, as a relative tolerance
    best_h = int(thesis_value(f"{sec}.best_hidden"))
    best_g = float(thesis_value(f"{sec}.best_learning_gradient"))
    e = chapter.entries
    e.append(
        results.compare(
            f"{key}.samples",
            f"{chap}.{'4' if chap == '6' else '1'}",
            printed_samples,
            load_protocolsamples(key),
            "readings",
            rtol=0.0,
            note=f"protocol {'thesis-6.1' if chap == '6' else 'thesis-7.1'} as printed",
        )
    )
    if key == "actuated":
        noise_note = _friction_study(ctx, best_h, best_g, chapter)
    else:
        noise_note = _noise_study(ctx, key, best_h, best_g, chapter)
    e.append(
        results.compare(
            f"{key}.test_corr2_at_thesis_optimum",
            f"{chap}.{'9' if chap == '6' else '5'}",
            thesis_corr2,
            opt.corr2,
            "",
            rtol=tol,
            note=f"{best_h} hidden nodes, learning gradient {best_g:g}, twin default calibration; within +-0.03 counts "
            "as a match.",
            discrepancy_note=noise_note,
        )
    )
    e.append(
        results.compare(
            f"{key}.test_corr2_swept",
            f"{chap}.{'9' if chap == '6' else '5'}",
            thesis_corr2,
            sweep.corr2,
            "",
            rtol=tol,
            note=f"at our own sweep's optimum: {sweep.best_hidden} nodes, gradient {sweep.best_tol:g}.",
            discrepancy_note=noise_note,
        )
    )
    e.append(
        results.compare(
            f"{key}.best_hidden",
            f"{chap}.{'8' if chap == '6' else '4'}",
            best_h,
            sweep.best_hidden,
            "nodes",
            rtol=0.0,
            discrepancy_note="The validation error is nearly flat over the sizes (figures below; the thesis says the "
            "same of 10-60 nodes in 6.8), so which size wins is decided by noise and initial weights.",
        )
    )
    e.append(
        results.compare(
            f"{key}.best_learning_gradient",
            f"{chap}.{'8' if chap == '6' else '4'}",
            best_g,
            sweep.best_tol,
            "",
            rtol=0.0,
            discrepancy_note="Every tolerance of 1e-4 and below gives the same validation error: SCG stops on the "
            "50 x 50 iteration budget or early stopping before meeting them, so the 'optimum' is a coin toss "
            "among equals; only 1e-1..1e-3 stop training early and cost accuracy.",
        )
    )
    with_nl = exp.extra["with_no_load"]
    if chap == "6":
        e.append(
            results.new(
                f"{key}.test_corr2_with_no_load_as_position_0",
                "6.9",
                with_nl.corr2,
                "",
                "All 1275 readings, no-load readings as position 0 (table 6.1's first row). A weight 24 cm from the "
                "tip hangs 3 cm from the clamp, before gauge 1 (45 mm): no gauge bends, so it reads exactly as no "
                "load and the network can only split the difference between positions 16 and 0.",
            )
        )
    pe = opt.percent_error
    below = float(np.mean(pe[np.isfinite(pe)] < float(thesis_value(f"{sec}.percent_error_mostly_below"))))
    e.append(
        results.new(
            f"{key}.test_fraction_percent_error_below_{thesis_value(f'{sec}.percent_error_mostly_below')}",
            f"{chap}.{'9' if chap == '6' else '5'}",
            below,
            "",
            "Fraction of test readings whose percentage error (of the position number) is below the bound the "
            "thesis says 'generally' holds; it is a relative error, so it is harsh near the tip (position 1).",
        )
    )

    # ------------------------------------------------------------------------- beyond the thesis
    loc = exp.localisation
    best = loc.best
    rm = loc.position_rmse_identifiable_m
    thesis_mlp = exp.thesis_mlp_position_m["rmse_identifiable_m"]
    e += [
        results.new(
            f"{key}.thesis_mlp_position_rmse_mm",
            f"{chap} (new)",
            1000 * thesis_mlp,
            "mm",
            f"The thesis network ({best_h} nodes, position-number target) on its loaded, identifiable test "
            f"readings, numbers mapped back to distances: {100 * thesis_mlp / (length_mm / 1000):.2f} % of the "
            f"{length_mm:g} mm digit, for corr2 {opt.corr2:.4f}.",
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
            _worst_ratio(loc, best),
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

    bayes = loc.bayes
    floor_pos = bayes["position_rmse_identifiable_m"]
    e += [
        results.new(
            f"{key}.bayes_position_rmse_identifiable_mm",
            f"{chap} (new)",
            1000 * floor_pos,
            "mm",
            "Bayes limit: the RMS position error of the best possible estimator that knows the protocol's settings "
            "(positions, loads, commands, their frequencies) and the twin's noise, on the identifiable test "
            "readings (Monte Carlo, tactile.bounds.protocol_limits). Unlike the Cramer-Rao bound, learned "
            f"estimators cannot beat it. Best estimator / limit = {rm[best] / floor_pos:.2f}; the thesis network / "
            f"limit = {thesis_mlp / floor_pos:.2f}.",
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
            f"expected errors on these {int(np.sum(loc.extra['contact_visible']))} readings: "
            f"{np.sum(loc.extra['contact_visible']) * (1 - bayes['contact_accuracy_visible']):.1f}).",
        ),
    ]
    chapter.paragraphs.append(_criteria_paragraph(exp, opt.corr2, thesis_corr2, thesis_mlp))

    # ------------------------------------------------------------------------------- tables
    chapter.tables.append(
        Table(
            "Network strategies of 6.2.1 (test readings; position over loaded readings, m from the tip)",
            ["strategy", "position corr2", "position RMSE (mm)", "contact accuracy", "magnitude rel. RMSE"],
            [
                [s.strategy, s.position_corr2, 1000 * s.position_rmse_m, s.contact_accuracy, s.magnitude_rel_rmse]
                for s in exp.strategies
            ],
        )
    )
    chapter.tables.append(
        Table(
            "Estimators on identical data (loaded test readings; identifiable = the Fisher information has rank 2)",
            ["estimator", "RMSE all (mm)", "RMSE identifiable (mm)", "% of digit", "magnitude rel. RMSE"],
            [
                [
                    "thesis network (position numbers)",
                    1000 * exp.thesis_mlp_position_m["rmse_m"],
                    1000 * thesis_mlp,
                    100 * thesis_mlp * 1000 / length_mm,
                    None,
                ]
            ]
            + [
                [
                    k,
                    1000 * loc.position_rmse_m[k],
                    1000 * rm[k],
                    100 * rm[k] * 1000 / length_mm,
                    loc.magnitude_rel_rmse_identifiable[k],
                ]
                for k in rm
            ],
        )
    )
    chapter.tables.append(_per_position_table(exp))

    # ------------------------------------------------------------------------------- figures
    figs = chapter.figures
    figs.append(_fig_raw(ctx, exp, slug, refs[0], plt))
    figs.append(_fig_normalised(ctx, exp, slug, refs[1], plt))
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
    figs.append(
        ctx.save_figure(
            fig,
            f"{slug}-error-vs-iteration",
            "Training and validation error against iterations (epochs of 50)",
            thesis_ref=f"figure {refs[2]}",
        )
    )
    for pts, name, ref, label in (
        (sweep.coarse, "coarse", refs[3], "hidden nodes"),
        (sweep.fine, "fine", refs[4], "hidden nodes"),
        (sweep.gradient, "gradient", refs[5], "learning gradient (SCG tolerance)"),
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
        figs.append(
            ctx.save_figure(
                fig, f"{slug}-sweep-{name}", f"Error against {label} ({name} sweep)", thesis_ref=f"figure {ref}"
            )
        )
    fig, ax = plt.subplots(figsize=(6, 3.6))
    k = np.arange(opt.y_test.size)
    ax.plot(k, opt.y_test, "r.", label="actual")
    ax.plot(k, opt.y_pred, "b.", ms=3, label="predicted")
    ax.set(xlabel="test reading", ylabel="position number (1 = tip)")
    ax.legend()
    figs.append(
        ctx.save_figure(
            fig,
            f"{slug}-predicted-actual",
            f"Predicted and actual test positions, corr2 {opt.corr2:.4f}",
            thesis_ref=f"figure {refs[6]}",
        )
    )
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.bar(k, np.nan_to_num(opt.percent_error), color="C0")
    ax.set(xlabel="test reading", ylabel="percentage error (%)")
    figs.append(
        ctx.save_figure(
            fig, f"{slug}-percent-error", "Percentage error of every test reading", thesis_ref=f"figure {refs[7]}"
        )
    )
    figs.append(_fig_bound(ctx, exp, slug, plt))
    return chapter


def load_protocolsamples(key: str) -> int:
    """Readings of the protocol as printed (thesis-6.1, thesis-7.1)."""
    from flexdigit.tactile.protocols import load_protocol

    return load_protocol("thesis-6.1" if key == "non_actuated" else "thesis-7.1").sample_count


def _noise_study(ctx: ReportContext, key: str, hidden: int, tol: float, chapter: Chapter) -> str:
    """corr2 at the thesis optimum against the twin's white-noise level; returns the discrepancy explanation."""
    from flexdigit.tactile.pipeline import features, run_pipeline, targets
    from flexdigit.tactile.protocols import load_protocol
    from flexdigit.tactile.thesis_experiments import EXPERIMENTS, static_dataset
    from flexdigit.twin.calibration import default_calibration

    base = default_calibration()
    scales = (1.0, 4.0) if ctx.fast else NOISE_SCALES
    protocol = load_protocol(EXPERIMENTS[key][0])
    rows = []
    for scale in scales:
        cal = base.replace(noise_white_v=tuple(scale * v for v in base.noise_white_v))
        ds = static_dataset(protocol, seed=ctx.seed, params=ctx.params, calibration=cal)
        ds = ds.subset(ds["load_kg"] > 0)
        _, y = targets(ds, "position_index")
        r = run_pipeline(
            features(ds),
            y,
            seed=ctx.seed,
            fixed_hidden=hidden,
            fixed_tol=tol,
            epochs=10 if ctx.fast else 50,
            curve_hidden=None,
        )
        rows.append([scale, 1000 * base.noise_white_v[0] * scale, r.corr2])
    chapter.tables.append(
        Table(
            "corr2 at the thesis's optimum against the twin's white gauge noise (calibration revisited; readings from "
            "the twin's batched static solver: at rest, white noise only)",
            ["noise scale", "white noise gauge 1 (mV)", "test corr2"],
            rows,
        )
    )
    target = float(thesis_value(f"tactile.{key}.test_corr2"))
    c2 = [r[2] for r in rows]
    if min(c2) <= target <= max(c2):
        order = np.argsort(c2)
        scale_match = float(np.interp(target, np.array(c2)[order], np.array([r[0] for r in rows])[order]))
        matching = f"matching {target} needs about x{scale_match:.2g} the default noise"
    else:
        matching = f"{target} lies outside the scanned range, so no white-noise level alone reproduces it"
    return (
        f"Revisiting the twin's noise calibration rather than the pipeline: corr2 against the white gauge noise "
        f"({', '.join(f'x{r[0]:g}: {r[2]:.4f}' for r in rows)}); {matching}. The default white noise is kept: "
        "one white level cannot match both chapters. The actuated loss is the cable-guide friction, which needs a "
        "taut cable and so is absent here (cable detached; chapter 7)."
    )


def _friction_study(ctx: ReportContext, hidden: int, tol: float, chapter: Chapter) -> str:
    """Chapter 7's noise revisited: corr2 against the cable-guide friction (per reading, per hang) and against
    servo deadband jitter alone; the calibrated level and its physical meaning. Returns the explanation."""
    from flexdigit.tactile.thesis_experiments import pipeline_corr2_static
    from flexdigit.twin.calibration import default_calibration

    cal = default_calibration()
    ratio = cal.cable_friction_ratio
    epochs = 10 if ctx.fast else 50
    kw = {"seed": ctx.seed, "params": ctx.params, "epochs": epochs}
    none = cal.replace(cable_friction_ratio=0.0)
    cases = [
        ("none (previous default)", none, {}),
        ("cable-guide friction, a hang per reading (the thesis, the twin)", cal, {}),
    ]
    cases.append(("cable-guide friction, 25 readings after one hang", cal, {"friction_per": "hang"}))
    if not ctx.fast:
        cases.insert(
            1, (f"friction x0.5 ({ratio / 2:.4f}), a hang per reading", cal.replace(cable_friction_ratio=ratio / 2), {})
        )
        cases.insert(
            3,
            (
                f"friction x1.5 ({1.5 * ratio:.4f}), a hang per reading",
                cal.replace(cable_friction_ratio=1.5 * ratio),
                {},
            ),
        )
    for deg in (1.0,) if ctx.fast else (1.0, 4.0):
        for per in ("reading", "hang"):
            cases.append(
                (
                    f"servo deadband jitter alone, {deg:g} deg per {per}",
                    none,
                    {"servo_jitter_rad": np.radians(deg), "servo_jitter_per": per},
                )
            )
    rows = [[name, pipeline_corr2_static("actuated", c, **kw, **extra)] for name, c, extra in cases]
    chapter.tables.append(
        Table(
            f"Actuated test corr2 at the thesis's optimum ({hidden} nodes, gradient {tol:g}) against the twin's "
            "actuated noise (batched static solver: at rest, no drift; thesis 0.8998)",
            ["noise in the actuated readings", "test corr2"],
            rows,
        )
    )
    per_hang = next(r[1] for r in rows if r[0].endswith("after one hang"))
    eq = _equivalent_servo_angle(ctx, cal)
    e = chapter.entries
    e.append(
        results.new(
            "actuated.cable_friction_ratio",
            "7 (twin calibration)",
            ratio,
            "",
            "Calibrated cable-guide friction (twin default_calibration.toml): standard deviation of the share of the "
            "cable tension gained or lost across the guides before each gauge's section, redrawn whenever a weight is "
            "hung, lifted or re-hung (the thesis protocols re-hang before every reading); fitted "
            "by a 1-D root find so the thesis pipeline's actuated test corr2, averaged over the experiment repeated "
            "with 8 seeds (static twin), is 0.8998, the "
            "only evidence the thesis gives. As friction, mu x wrap angle >= this: e.g. mu 0.2-0.3 (steel on "
            f"nylon) over {ratio / 0.3:.2f}-{ratio / 0.2:.2f} rad of wrap per guide, the order of the sections' "
            "relative rotation at commands 20-40: plausible.",
        )
    )
    if not ctx.fast:
        from flexdigit.tactile.thesis_experiments import FRICTION_FIT_SEEDS, actuated_corr2_score

        mean, sd = actuated_corr2_score(cal, params=ctx.params, spread=True)
        e.append(
            results.compare(
                "actuated.corr2_mean_over_fit_seeds",
                "7.5 (twin calibration)",
                thesis_value("tactile.actuated.test_corr2"),
                mean,
                "",
                rtol=0.03 / 0.8998,
                note=f"Thesis pipeline (24 nodes, 1e-7) on the static twin, mean over the {len(FRICTION_FIT_SEEDS)} "
                f"seeds the friction is fitted on (readings, split and initial weights drawn anew): standard "
                f"deviation {sd:.3f} from one repetition to the next, so any single run (this report's chapter-7 "
                "network among them) may land a few hundredths either side of the printed figure.",
                discrepancy_note="The fit did not converge to the printed figure: rerun python -m "
                "flexdigit.twin.calibration.",
            )
        )
    e.append(
        results.new(
            "actuated.cable_friction_equivalent_servo_deg",
            "7 (twin calibration)",
            eq["median_deg"],
            "deg",
            "The same tension scatter expressed as a servo shaft angle (ratio x T / (dT/dtheta), over the protocol's "
            f"settings): median {eq['median_deg']:.2f} deg = {eq['median_us']:.1f} us of PWM pulse "
            f"({eq['min_deg']:.2f}-{eq['max_deg']:.2f} deg, {eq['min_us']:.1f}-{eq['max_us']:.1f} us; "
            f"{ctx.params.actuator.deg_per_command:.4f} deg = one command = {eq['us_per_command']:.3f} us). A hobby "
            "servo's deadband is a few us (a fraction of a degree to ~1 deg), so the servo alone could not scatter "
            "the tension this much, and the table shows it could not cost corr2 anyway: its jitter moves the gauges "
            "along the one actuation direction, which the network separates from the load.",
        )
    )
    return (
        "Revisited the twin's noise calibration, not the pipeline (issue 7): the previous default had no noise "
        "specific to the taut cable, and white gauge noise high enough for 0.8998 (x9.4) wrecks chapter 6. "
        "Servo deadband jitter alone leaves corr2 at "
        + ", ".join(f"{r[1]:.3f}" for r in rows if r[0].startswith("servo"))
        + " (table); cable-guide friction with a hang per reading reproduces it at ratio "
        f"{ratio:.4f}, 25 readings after one hang do not ({per_hang:.3f}): "
        "the readings of one hang share its friction state and are split at random between training and test. "
        "The thesis repeated 'the procedure' 25 times per setting (6.4, 7.1), so each of its readings had its own "
        "hang, and the thesis protocols re-hang before every repetition (on the twin a re-hang only lets the cable "
        "settle afresh in its guides). The friction is held between jolts, so the chapter-5 loop, with no weight "
        "hung, does not see it."
    )


def _equivalent_servo_angle(ctx: ReportContext, cal) -> dict:
    """The friction's tension scatter over the protocol's settings as a servo shaft angle (deg) and pulse (us)."""
    from flexdigit.tactile.protocols import load_protocol
    from flexdigit.twin.twin import static_gauges_v

    a = ctx.params.actuator
    plan = load_protocol("thesis-7.1-no-load").plan(ctx.params.geometry.digit_length_m)
    keys = np.unique(
        np.column_stack([plan["load_kg"], np.nan_to_num(plan["position_from_base_m"]), plan["command"]]), axis=0
    )
    d = 0.01 * a.rad_per_command
    tension = []
    for off in (-d, 0.0, d):
        _, sol = static_gauges_v(
            keys[:, 0],
            keys[:, 1],
            keys[:, 2].astype(int),
            params=ctx.params,
            calibration=cal,
            adc=False,
            return_solution=True,
            servo_offset_rad=np.full(len(keys), off),
        )
        tension.append(sol.tension_n)
    slope = (tension[2] - tension[0]) / (2 * d)  # N per rad of servo shaft
    deg = np.degrees(cal.cable_friction_ratio * tension[1] / slope)
    us_per_deg = 1e6 * (a.pulse_width_max_s - a.pulse_width_min_s) / (a.angle_max_deg - a.angle_min_deg)
    return {
        "median_deg": float(np.median(deg)),
        "min_deg": float(deg.min()),
        "max_deg": float(deg.max()),
        "median_us": float(np.median(deg) * us_per_deg),
        "min_us": float(deg.min() * us_per_deg),
        "max_us": float(deg.max() * us_per_deg),
        "us_per_command": float(a.deg_per_command * us_per_deg),
    }


def _criteria_paragraph(exp, corr2_ours: float, corr2_thesis: float, thesis_mlp_m: float) -> str:
    """Issue 7's "done when" criteria on this experiment, each with its figure, and why a failing one fails."""
    loc = exp.localisation
    best = loc.best
    rm = loc.position_rmse_identifiable_m
    worst = _worst_ratio(loc, best)
    contact_name = max(loc.contact_accuracy_visible, key=loc.contact_accuracy_visible.get)
    contact = loc.contact_accuracy_visible[contact_name]
    contact_all = loc.contact_accuracy[contact_name]
    magnitude = min(loc.magnitude_rel_rmse_identifiable.values())
    checks = [
        (f"corr2 {corr2_ours:.4f} within +-0.03 of {corr2_thesis}", abs(corr2_ours - corr2_thesis) <= 0.03),
        (
            f"best estimator ({best}) {1000 * rm[best]:.1f} mm = {rm[best] / thesis_mlp_m:.2f} x the thesis network's "
            f"{1000 * thesis_mlp_m:.1f} mm (<= 0.5)",
            rm[best] <= 0.5 * thesis_mlp_m,
        ),
        (f"its worst per-position error / Cramer-Rao bound {worst:.2f} (<= 1.25)", worst <= 1.25),
        (
            f"contact {100 * contact:.1f} % on the readings where some gauge bends (>= 99 %; {100 * contact_all:.1f} "
            "% on all test readings: a load no gauge sees reads as no load)",
            contact >= 0.99,
        ),
        (f"magnitude {100 * magnitude:.1f} % RMS (<= 10 %)", magnitude <= 0.10),
    ]
    text = (
        "Issue 7's criteria on this experiment: "
        + "; ".join(f"{label}: {'met' if ok else 'NOT met'}" for label, ok in checks)
        + "."
    )
    bayes = loc.bayes
    floor_pos = bayes["position_rmse_identifiable_m"]
    floor_mag = bayes["magnitude_rel_rmse_identifiable"]
    floor_contact = bayes["contact_accuracy_visible"]
    text += (
        " The Bayes limits (the best any estimator that knows the protocol can do on these readings, twin noise "
        f"model): position {1000 * floor_pos:.1f} mm (best estimator at {rm[best] / floor_pos:.2f} x, thesis "
        f"network at {thesis_mlp_m / floor_pos:.2f} x), magnitude {100 * floor_mag:.1f} %, contact "
        f"{100 * floor_contact:.2f} %."
    )
    unreachable = []
    if 0.5 * thesis_mlp_m < floor_pos:
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
            + ". The noise that reproduces the thesis's corr2 leaves too little in one reading."
        )
    if checks[1][1] and checks[2][1]:
        return text
    # why: how close the thesis network already is to the bound, position by position
    rows = exp.thesis_mlp_position_m["test_rows"]
    pred = exp.thesis_mlp_position_m["pred_m"]
    true = exp.dataset["position_from_tip_m"][rows]
    zone = loc.extra["zone_all"][rows]
    bound = loc.extra["crlb_all_m"][rows]
    ratios = []
    for p in np.unique(true):
        sel = (true == p) & (zone == "identifiable")
        if sel.any():
            err = np.sqrt(np.mean((pred[sel] - p) ** 2))
            ratios.append(err / np.sqrt(np.mean(bound[sel] ** 2)))
    ratios = np.array(ratios)
    spread = float(np.std(np.unique(exp.dataset["position_from_tip_m"][exp.dataset["load_kg"] > 0])))
    ident = loc.zone == "identifiable"
    over = float(np.mean(loc.crlb_m[ident] > spread)) if ident.any() else float("nan")
    text += (
        f" Why: position by position the thesis network is already at {np.min(ratios):.2f}-{np.max(ratios):.2f} x "
        f"the one-reading bound (median {np.median(ratios):.2f}), i.e. mostly below it: the bound exceeds the spread "
        f"of the protocol's positions ({1000 * spread:.0f} mm standard deviation) on {over:.0%} of the identifiable "
        "test readings, and a network that has learnt the protocol's short list of positions and loads beats it by "
        "shrinking towards them. An estimator at half its error would sit at half those ratios, further below a "
        "bound no unbiased estimator can cross, so with the noise that reproduces the thesis's corr2 the 0.5 x "
        "criterion asks for more than one reading holds, and the ratio-to-bound metric is ill-posed (estimators "
        "beat it by using the protocol, not the gauges)."
    )
    if not checks[3][1]:
        name = max(loc.contact_accuracy_visible, key=loc.contact_accuracy_visible.get)
        crow = loc.extra["contact_rows"]
        wrong = loc.extra["contact_pred"][name] != (exp.dataset["load_kg"][crow] > 0)
        where = exp.dataset["position_from_tip_m"][crow][wrong]
        cmds = exp.dataset["command"][crow][wrong]
        labels = [f"load {100 * w:g} cm from the tip" if np.isfinite(w) else "no load" for w in where]
        counts = {k: labels.count(k) for k in sorted(set(labels))}
        text += (
            f" Contact ({name}) errs on {int(wrong.sum())} of {crow.size} test readings ("
            + ", ".join(f"{k}: {v}" for k, v in counts.items())
            + f"; commands {sorted(set(cmds.tolist()))}): a load near the clamp bends gauge 1 by only a few standard "
            "deviations of the friction at those tensions, and the friction scatters the no-load readings alike."
        )
    return text


def _worst_ratio(loc, name: str) -> float:
    """max over identifiable test positions of RMSE(position) / CRLB(position), mass unknown."""
    ratios = []
    for p in np.unique(loc.position_true_m):
        sel = (loc.position_true_m == p) & (loc.zone == "identifiable")
        if sel.any():
            err = np.sqrt(np.mean((loc.position_pred_m[name][sel] - p) ** 2))
            ratios.append(err / np.sqrt(np.mean(loc.crlb_m[sel] ** 2)))
    return float(max(ratios)) if ratios else float("nan")


def _per_position_table(exp) -> Table:
    loc = exp.localisation
    rows_out = []
    pos_true = loc.position_true_m
    for p in np.unique(pos_true):
        sel = pos_true == p
        zones = sorted(set(loc.zone[sel]))
        row = [
            100 * p,
            "/".join(z for z in zones),
            1000 * float(np.sqrt(np.mean(loc.crlb_m[sel] ** 2))),
            1000 * float(np.sqrt(np.mean(loc.crlb_known_mass_m[sel] ** 2))),
        ]
        row += [1000 * float(np.sqrt(np.mean((v[sel] - p) ** 2))) for v in loc.position_pred_m.values()]
        rows_out.append(row)
    return Table(
        "Per position (test readings): identifiability zone, Cramer-Rao bounds and RMSE of each estimator (mm)",
        ["from tip (cm)", "zone", "CRLB mass unknown", "CRLB mass known"] + list(loc.position_pred_m),
        rows_out,
    )


def _fig_raw(ctx, exp, slug, ref, plt):
    ds = exp.dataset
    loaded = ds["load_kg"] > 0
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), sharex=True)
    for i, ax in enumerate(axes):
        for m in np.unique(ds["load_kg"][loaded]):
            for c in np.unique(ds["command"]):
                sel = loaded & (ds["load_kg"] == m) & (ds["command"] == c)
                lab = f"{1000 * m:g} g" + (f", cmd {c}" if c >= 0 else "")
                ax.plot(100 * ds["position_from_tip_m"][sel], ds.gauges_v[sel, i], ".", ms=2, label=lab)
        ax.set(title=f"gauge {i + 1}", xlabel="load position from tip (cm)", ylabel="V" if i == 0 else None)
    axes[0].legend(fontsize=6)
    return ctx.save_figure(
        fig,
        f"{slug}-raw",
        "Gauge voltages against load position, every load (not normalised)",
        thesis_ref=f"figure {ref}",
    )


def _fig_normalised(ctx, exp, slug, ref, plt):
    from flexdigit.tactile.pipeline import Normaliser

    ds = exp.dataset.subset(exp.pipeline_rows)
    split = exp.sweep.split
    x = ds.gauges_v
    z = Normaliser().fit(x[split.train]).transform(x[np.concatenate([split.train, split.val, split.test])])
    fig, ax = plt.subplots(figsize=(6, 3.4))
    for i in range(3):
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

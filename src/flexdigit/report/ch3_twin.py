"""Report chapter 3 (twin): the calibrated digital twin against tables 3.1, 3.2, 3.6, E 3.20-3.22 and closed forms.

The release tests and the actuation sweep are simulated as experiments (digit, servo, sensor chain with noise) and
analysed like measurements: identify's lsq fit gives wn and zeta (tables 3.1, 3.2), a straight line per gauge gives
the E 3.20-3.22 slopes. The deflections of table 3.6 are read off the twin's static shape. The physics checks
(closed forms the twin was not written from) are repeated at the twin's default resolution.
"""

from __future__ import annotations

import math

import numpy as np

from flexdigit.identify.fit import second_order_response
from flexdigit.reference import thesis_value
from flexdigit.report.chapter import Chapter, ReportContext, ResultTable
from flexdigit.report.results import compare, new


def build(ctx: ReportContext) -> Chapter:
    """Build the twin chapter."""
    from flexdigit.calibrate.targets import CalibrationTargets, release_figures
    from flexdigit.identify.timeseries import series_from_table
    from flexdigit.twin import records as ex
    from flexdigit.twin.calibration import default_calibration, default_calibration_source, default_fit_record
    from flexdigit.twin.twin import Twin

    p = ctx.params
    cal = default_calibration()
    ch = Chapter(slug="ch3-twin", title="Chapter 3 (twin): the calibrated large-deflection digital twin")
    ch.paragraphs.append(
        "The twin models the digit as a planar chain of rigid links and rotational springs (a discrete elastica, "
        "3 springs per 80 mm section, rigid 10 mm nylon supports at 90/180/270 mm), moved by a cable at constant "
        "eccentricity whose shortening is r_M times the servo angle (E 3.11); the servo is the identified second-"
        "order model (3.2.4) driven by integer commands latched on 20 ms serial frames; the gauges go through the "
        "half bridge (E 2.2), a per-channel gain and offset, the 470 Hz low-pass and a 16-bit +-5 V ADC, with seeded "
        "white noise and drift. Support masses, housing stiffness (with a stiffer base section), damping, cable "
        "compliance and channel gains are fitted with scipy.optimize.least_squares (flexdigit.calibrate)."
    )
    e = ch.entries
    rng_seed = int(ctx.rng(3).integers(0, 2**31))
    # the bare digit's time constant is 1/(zeta wn) = 39 s: a zeta from fewer seconds is at the noise's mercy
    dur = {False: 15.0 if ctx.fast else 30.0, True: 5.0 if ctx.fast else 8.0}
    release = {}
    for housing, table, key in ((False, "3.1", "without_housing"), (True, "3.2", "with_housing")):
        res = ex.release_test(housing=housing, duration_s=dur[housing], sample_rate_hz=500, seed=rng_seed, params=p)
        t = res.column("time_s")
        fit = release_figures([series_from_table(res, f"gauge{g}") for g in (1, 2, 3)])
        wn_t = thesis_value(f"digit.release_tests_{key}.wn_avg_rad_s")
        z_t = thesis_value(f"digit.release_tests_{key}.zeta_avg")
        note = (
            f"Median over the gauges of identify's lsq fit (as flexdigit identify release and flexdigit calibrate) "
            f"to a simulated release test (20 mm tip deflection), table {table} average."
            + (f" Gauges not identified: {', '.join(s['record'] for s in fit['skipped'])}." if fit["skipped"] else "")
        )
        why = (
            "The twin is calibrated to this figure; a miss means the calibration and the time integration disagree "
            "(check the integration step against the default)."
        )
        e.append(
            compare(
                f"twin.release_{key}.wn_rad_s",
                "3.1.2",
                wn_t,
                fit["wn_rad_s"],
                "rad/s",
                rtol=0.03,
                note=note,
                discrepancy_note=why,
            )
        )
        e.append(
            compare(
                f"twin.release_{key}.zeta", "3.1.2", z_t, fit["zeta"], "", rtol=0.03, note=note, discrepancy_note=why
            )
        )
        release[housing] = (res, fit)
        gauge2 = _gauge_fit(fit, "gauge2")
        model = second_order_response(t, "release", wn_t, z_t, gauge2.offset, gauge2.amplitude, gauge2.t0_s)
        corr = float(np.corrcoef(model, res.column("gauge2_v"))[0, 1])
        e.append(
            new(
                f"twin.release_{key}.corr2_vs_thesis_model",
                "3.1.2",
                corr,
                "",
                "corr2 of the twin's release signal with the thesis's second-order model (its wn and zeta); the "
                "thesis reports 0.9910 for its measured test #10 against the same model (with housing).",
            )
        )
    ch.figures.append(_release_figure(ctx, release))

    # 20 readings a command even in fast mode: the taut cable's guide friction scatters single readings by
    # 10-40 mV (twin calibration, chapter 7), which 5 readings leave in the small E 3.22 intercept
    sweep = ex.actuation_sweep(settle_s=2.0 if ctx.fast else 3.0, samples=20, seed=rng_seed, params=p)
    cmds = sweep.column("command")
    fits = thesis_value("conversion.v_sg_fit")
    for g, fit in enumerate(fits, start=1):
        slope, offset = np.polyfit(cmds, sweep.column(f"gauge{g}_v"), 1)
        e.append(
            compare(
                f"twin.sweep.gauge{g}.slope_v_per_command",
                "3.4.3",
                fit["slope"],
                slope,
                "V/command",
                rtol=0.05,
                note=f"E 3.2{g - 1}: straight line through the simulated sweep, commands 8..43.",
                discrepancy_note="The channel gains are fitted to this slope; a miss means the sweep did "
                "not settle or the noise is too large for the samples taken.",
            )
        )
        e.append(
            compare(
                f"twin.sweep.gauge{g}.offset_v",
                "3.4.3",
                fit["offset"],
                offset,
                "V",
                rtol=0.05,
                note=f"E 3.2{g - 1} intercept (the per-channel offset is fitted to it).",
                discrepancy_note="The intercept is a small difference of large numbers; see the slope.",
            )
        )
    ch.figures.append(_sweep_figure(ctx, sweep, fits))

    ch.figures.append(_shapes_and_step_figure(ctx, p, cal, rng_seed))

    targets = CalibrationTargets.from_thesis()
    rows = []
    commands = targets.deflection_commands
    measured = np.array(targets.deflection_mm)
    weight = np.array(targets.deflection_weight)
    theory = np.array([thesis_value(f"conversion.table_3_4_y_sg{k}_mm") for k in (1, 2, 3)])
    worst_trusted, worst_all = 0.0, 0.0
    for c, command in enumerate(commands):
        y = Twin(p, cal, command=command).deflection_m(p.geometry.gauge_positions_m) * 1e3
        row: list[object] = [command]
        for g in range(3):
            row += [measured[g, c], theory[g, c], float(y[g])]
            worst_all = max(worst_all, abs(y[g] - measured[g, c]))
            if weight[g, c]:
                worst_trusted = max(worst_trusted, abs(y[g] - measured[g, c]))
                e.append(
                    compare(
                        f"twin.table_3_6.y_sg{g + 1}[{command}]",
                        "3.4.1",
                        measured[g, c],
                        float(y[g]),
                        "mm",
                        rtol=0.5 / measured[g, c] if measured[g, c] else 0.5,
                        note="A reading where the thesis's own model (table 3.4) agrees within 0.5 mm; "
                        "tolerance 0.5 mm, the reading resolution.",
                        discrepancy_note="Outside the 0.5 mm resolution where the thesis model agrees.",
                    )
                )
        rows.append(tuple(row))
    ch.tables.append(
        ResultTable(
            "twin.table_3_6",
            "Table 3.6 beside table 3.4 (thesis model, E 3.15) and the twin: deflection at the gauges (mm)",
            ("command",) + tuple(f"sg{g}_{k}_mm" for g in (1, 2, 3) for k in ("measured", "thesis_model", "twin")),
            tuple(rows),
        )
    )
    e.append(
        new(
            "twin.table_3_6.max_abs_error_trusted_mm",
            "3.4.1",
            worst_trusted,
            "mm",
            "Largest twin error over the table 3.6 readings where table 3.4 agrees within 0.5 mm.",
        )
    )
    e.append(
        new(
            "twin.table_3_6.max_abs_error_all_mm",
            "3.4.1",
            worst_all,
            "mm",
            "Largest twin error over every reading of table 3.6; consecutive readings scatter by up to 3 mm "
            "per command while the cable's kinematics are linear in the command, which no smooth model follows.",
        )
    )
    ch.paragraphs.append(
        "Table 3.6 and the stiffer base: a uniform strip would put 1.5 mm at gauge 1 at command 24; the thesis "
        "measures 1 mm and blames its single-section model. The calibration gives the base section's housing "
        f"{cal.housing_ei_n_m2[0] / cal.housing_ei_n_m2[1]:.2f} times the other sections' stiffness, and the cable "
        f"a stiffness of {cal.cable_stiffness_n_m:.3g} N/m (its stretch takes a few degrees off the pulley's "
        "demand). Note that 3.4.1's 'commands 8..43 = 0..30 degrees' does not follow from E 3.11: r_M/e = 2.01 "
        "turns 35 commands (30.2 deg of servo) into 60.7 deg of tip rotation; the twin reaches "
        f"{math.degrees(_tip_angle(p, cal, 43)):.1f}"
        " deg at command 43 (3.6 itself says about fifteen steps make 30 deg)."
    )

    fit_rec = default_fit_record().get("residuals", [])
    ch.tables.append(
        ResultTable(
            "twin.calibration_residuals",
            f"Calibration ({_source_text(default_calibration_source())}): fit residuals (flexdigit calibrate)",
            ("target", "measured", "twin", "residual", "unit"),
            tuple((r["target"], r["measured"], r["twin"], r["twin"] - r["measured"], r["unit"]) for r in fit_rec),
        )
    )
    ch.tables.append(
        ResultTable(
            "twin.calibration_parameters",
            f"Calibration ({_source_text(default_calibration_source())}): fitted parameters (one row per element of a "
            "per-section or per-gauge parameter)",
            ("parameter", "value"),
            tuple(_flat_parameters(cal.to_dict())),
        )
    )
    gains = np.asarray(cal.channel_gain)
    ch.paragraphs.append(
        "Channel gains: with the nominal chain (Vs = 1 V, an assumption, times the amplifier's 10,000 and the half "
        "bridge's GF/2) the twin's sweep would rise by "
        + ", ".join(f"{fit['slope'] / g:.3f}" for fit, g in zip(fits, gains, strict=True))
        + " V per command at gauges 1-3; E 3.20-3.22 measure "
        + ", ".join(f"{fit['slope']:g}" for fit in fits)
        + f", so the fitted per-channel factors are {', '.join(f'{g:.3f}' for g in gains)}: an effective "
        f"excitation x gain of {1e4 * gains.min():.0f}-{1e4 * gains.max():.0f} V/V instead of 10,000 (a bridge "
        "supply nearer 0.1 V, or a lower gauge factor or gain). The spread between channels (gauge 2 is "
        f"{gains[1] / gains[0]:.2f} x gauge 1) is the per-channel difference the thesis's lines show."
    )
    for entry in _physics_checks():
        e.append(entry)
    ch.tables.append(_convergence_table())
    return ch


def _convergence_table() -> ResultTable:
    """Relative errors against the closed forms as the cells are refined: second order (x 1/4 per halving)."""
    from flexdigit.twin.digit import Chain

    ei, length, mu = 0.012, 0.24, 0.038
    exact_f = 1.8751040687**2 * math.sqrt(ei / (mu * length**4))
    rows = []
    for n in (3, 6, 12, 24, 48):
        chain = Chain.uniform(length, ei, n, mass_per_length_kg_m=mu)
        tip = chain.solve_static(tip_force_n=[[0, 1e-6]]).tip_m[0, 1] / (1e-6 * length**3 / (3 * ei)) - 1
        y = -Chain.uniform(1.0, 1.0, n).solve_static(tip_force_n=[[0, -10.0]]).tip_m[0, 1] / _elastica_y(10.0) - 1
        wn = chain.linear_modes()[0][0] / exact_f - 1
        rows.append((n, tip, y, wn))
    return ResultTable(
        "twin.convergence",
        "Convergence with discretisation (relative errors against closed forms: tip load vs P L^3/3EI, the "
        "elastica at P L^2/EI = 10, the first frequency vs Euler-Bernoulli; the twin's default is 12 cells over "
        "the strip)",
        ("cells", "tip_load_rel_error", "elastica_rel_error", "first_frequency_rel_error"),
        tuple(rows),
    )


def _flat_parameters(values: dict):
    """``(name, number)`` rows: a list-valued parameter gives one row per element, ``name[i]``."""
    for k, v in values.items():
        if isinstance(v, list | tuple):
            yield from ((f"{k}[{i}]", x) for i, x in enumerate(v))
        else:
            yield (k, v)


def _elastica_y(alpha2: float) -> float:
    """Tip deflection / L under a dead tip load, Bisshopp & Drucker's elliptic-integral solution."""
    from scipy.optimize import brentq
    from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

    a = math.sqrt(alpha2)
    k = brentq(
        lambda k: ellipk(k * k) - ellipkinc(math.asin(1 / (math.sqrt(2) * k)), k * k) - a,
        1 / math.sqrt(2) + 1e-12,
        1 - 1e-12,
    )
    phi1 = math.asin(1 / (math.sqrt(2) * k))
    return 1 - 2 / a * (ellipe(k * k) - ellipeinc(phi1, k * k))


def _tip_angle(params, cal, command: int) -> float:
    from flexdigit.twin.twin import Twin

    return float(Twin(params, cal, command=command).state()[0][-1])


def _physics_checks():
    """Closed-form checks at the twin's default cell size (12 cells over the strip)."""
    from flexdigit.twin.digit import Chain

    out = []
    ei, length = 0.012, 0.24
    chain = Chain.uniform(length, ei, 12, mass_per_length_kg_m=0.038)
    tip = chain.solve_static(tip_force_n=[[0, 1e-6]]).tip_m[0, 1]
    out.append(
        new(
            "twin.check.tip_load_rel_error",
            "3.1.1",
            tip / (1e-6 * length**3 / (3 * ei)) - 1,
            "",
            "Small-deflection tip load against P L^3 / 3EI, 12 cells (goal 0.5 %).",
        )
    )
    theta = math.pi / 2
    sol = chain.solve_static(tip_moment_nm=theta * ei / length)
    r = length / theta
    exact = np.array([r * math.sin(theta), r * (1 - math.cos(theta))])
    out.append(
        new(
            "twin.check.arc_90deg_rel_error",
            "3.3",
            float(np.linalg.norm(sol.tip_m[0] - exact) / r),
            "",
            "Pure tip moment bending the strip 90 deg against the exact circular arc, 12 cells (goal 0.5 %).",
        )
    )
    y_exact = _elastica_y(10.0)
    y = -Chain.uniform(1.0, 1.0, 12).solve_static(tip_force_n=[[0, -10.0]]).tip_m[0, 1]
    out.append(
        new(
            "twin.check.elastica_pl2_ei_10_rel_error",
            "3.1.1",
            y / y_exact - 1,
            "",
            "Large-deflection tip load P L^2/EI = 10 against the elastica (elliptic integrals), 12 cells (goal 1 %).",
        )
    )
    wn = chain.linear_modes()[0][0]
    out.append(
        new(
            "twin.check.first_frequency_rel_error",
            "3.1.1",
            wn / (1.8751040687**2 * math.sqrt(ei / (0.038 * length**4))) - 1,
            "",
            "First bending frequency of the uniform strip against Euler-Bernoulli, 12 cells (goal 1 %).",
        )
    )
    return out


def _release_figure(ctx: ReportContext, release):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=False)
    for ax, housing, key in ((axes[0], True, "with_housing"), (axes[1], False, "without_housing")):
        res, fit = release[housing]
        t = res.column("time_s")
        y = res.column("gauge2_v")
        gauge2 = _gauge_fit(fit, "gauge2")
        wn = thesis_value(f"digit.release_tests_{key}.wn_avg_rad_s")
        z = thesis_value(f"digit.release_tests_{key}.zeta_avg")
        model = second_order_response(t, "release", wn, z, gauge2.offset, gauge2.amplitude, gauge2.t0_s)
        ax.plot(t, y, lw=0.8, label="twin (gauge 2, through the sensor chain)")
        ax.plot(t, model, "--", lw=0.8, label=f"thesis model: wn {wn:.2f} rad/s, zeta {z:.4f}")
        ax.set_title("with housing (table 3.2)" if housing else "without housing (table 3.1)")
        ax.set_ylabel("gauge 2 (V)")
        ax.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("time (s)")
    fig.tight_layout()
    return ctx.save_figure(
        fig,
        "twin_release_tests",
        "Simulated release tests beside the thesis's second-order models.",
        thesis_ref="figure 3.6",
    )


def _sweep_figure(ctx: ReportContext, sweep, fits):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    cmds = sweep.column("command")
    for g, fit in enumerate(fits, start=1):
        ax.plot(cmds, sweep.column(f"gauge{g}_v"), ".", ms=3, label=f"twin gauge {g}")
        line = np.array([cmds.min(), cmds.max()])
        ax.plot(line, fit["slope"] * line + fit["offset"], "-", lw=0.8, label=f"E 3.2{g - 1}")
    ax.set_xlabel("command")
    ax.set_ylabel("gauge voltage (V)")
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    return ctx.save_figure(
        fig, "twin_actuation_sweep", "Simulated actuation sweep beside E 3.20-3.22.", thesis_ref="figure 3.17"
    )


def _shapes_and_step_figure(ctx: ReportContext, params, cal, seed: int):
    """Left: the digit's shape at commands 8..43 (large deflection). Right: a servo step against MT(s)."""
    import matplotlib.pyplot as plt
    import scipy.signal

    from flexdigit.twin import records as ex
    from flexdigit.twin.twin import Twin

    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.2))
    s = np.linspace(0.0, params.geometry.digit_length_m, 60)
    for command in (8, 15, 22, 29, 36, 43):
        twin = Twin(params, cal, command=command)
        xy = twin.chain.positions(twin.state()[0], s) * 1e3
        left.plot(xy[:, 1], xy[:, 0], label=f"command {command}")
        g = twin.chain.positions(twin.state()[0], params.geometry.gauge_positions_m) * 1e3
        left.plot(g[:, 1], g[:, 0], "k.", ms=4)
    left.set_xlabel("sideways, towards the cable (mm)")
    left.set_ylabel("along the undeformed digit (mm)")
    left.set_aspect("equal")
    left.legend(fontsize=7)
    left.set_title("twin: digit shape (dots: gauges)")
    res = ex.servo_step_test(command_from=0, command_to=51, duration_s=1.0, seed=seed, params=params, calibration=cal)
    t = res.column("time_s")
    pot = res.column("pot_v")
    step_at = float(t[np.argmax(res.column("command") == 51)])
    num, den = thesis_value("actuator.model.mt_num"), thesis_value("actuator.model.mt_den")
    tt = np.linspace(0, t[-1] - step_at, 400)
    _, y = scipy.signal.step((num, den), T=tt)
    p0, p1 = pot[: max(1, int(np.argmax(t >= step_at)))].mean(), pot[-50:].mean()
    right.plot(t, pot, lw=0.6, label="twin potentiometer (with noise)")
    right.plot(tt + step_at, p0 + (p1 - p0) * y, "--", label="MT(s) of 3.2.4 from the command's arrival")
    right.set_xlabel("time (s)")
    right.set_ylabel("potentiometer (V)")
    right.set_title("servo step 0 -> 51")
    right.legend(fontsize=7)
    fig.tight_layout()
    return ctx.save_figure(
        fig,
        "twin_shapes_and_servo_step",
        "Digit shapes over the operating commands; a servo step beside MT(s).",
        thesis_ref="figure 3.12",
    )


def _gauge_fit(figures: dict, channel: str):
    """The identification of ``channel`` among a release test's fits, or the first gauge identified (offset and
    amplitude to draw the thesis's model on that gauge's scale)."""
    return next((f for f in figures["fits"] if f.channel == channel), figures["fits"][0])


def _source_text(source: str) -> str:
    return "packaged, fitted to the thesis by flexdigit calibrate --thesis" if source == "packaged" else source

"""Report chapter 3: the component models and the plant G(s), beside tables 3.1-3.7, E 3.10-3.25 and 3.5/4.1.

Every figure here is computed from :mod:`flexdigit.models` and compared with the thesis figure as printed
(``reference/thesis.toml``); where they differ the entry says why and gives the corrected figure.
"""

from __future__ import annotations

import math

import control
import numpy as np

from flexdigit.control.design20ms import digit_mount
from flexdigit.control.thesis_designs import digit_plant
from flexdigit.models import cable, conversion, second_order, servo
from flexdigit.models.chapter3_tables import chapter3_study, table_3_4_gauge_columns, table_3_4_printed
from flexdigit.models.plant import (
    PRINTED_DIGIT_DAMPING_1_PER_S,
    closed_loop_printed_k1,
    commands_for_tip_rotation,
    explain_discrepancies,
    printed_digit_zeta,
)
from flexdigit.reference import thesis_complex, thesis_value
from flexdigit.report.chapter import Chapter, ReportContext, ResultTable
from flexdigit.report.results import Entry, compare, new


def _printed_rtol(printed: float, decimals: int) -> float:
    """Relative tolerance of half a unit in the last printed decimal (slightly widened for float noise)."""
    return 0.5 * 10.0**-decimals / abs(printed) * (1 + 1e-9) if printed else 0.0


def build(ctx: ReportContext) -> Chapter:
    """Chapter 3 from :func:`flexdigit.models.chapter3_tables.chapter3_study`: entries, tables and figures."""
    p = ctx.params
    study = chapter3_study(p)
    chapter = Chapter(slug="ch3-models", title="Chapter 3: component models and the plant G(s)")
    if not ctx.thesis_rig:
        return _digit_chapter(ctx, study, chapter)
    chapter.paragraphs.append(
        "Each component of chapter 3 is rebuilt from the rig parameters (flexdigit.models) and the plant G(s) of "
        "3.5 is assembled from them, twice: 'printed' reproduces the thesis's G(s) with its unit slips, "
        "'consistent' is the unit-correct chain command -> servo angle -> cable shortening -> moment -> "
        "curvature -> deflection, rotation or gauge volts. `flexdigit model --explain` prints the same list of "
        "discrepancies as below."
    )
    e = chapter.entries
    for release in study.releases.values():
        _release_entries(release, e)
    _digit_model(ctx, study, chapter)
    zeta_ok = sum(x.status == "match" for x in e if x.key.startswith("table_3_") and ".zeta[" in x.key)
    chapter.paragraphs.append(
        f"Tables 3.1 and 3.2: all {zeta_ok} zetas whose %OS is readable follow from it to the printed 4 decimals; "
        "table 3.2 row 2's %OS is garbled in print and its zeta implies 80.5973 %. Table 3.1's wn column, "
        "unlike table 3.2's, does not follow from its wd column."
    )
    _servo(ctx, study, chapter)
    _cable(p, study, e)
    cells = [x for x in e if x.key.startswith("table_3_4.")]
    gauge_cells = [x for x in cells if not x.key.startswith("table_3_4.y_max_mm")]
    chapter.paragraphs.append(
        f"Table 3.4: {sum(x.status == 'match' for x in gauge_cells)} of the {len(gauge_cells)} gauge cells follow "
        "from E 3.15 to the printed 2 decimals; the y_max column does not at x = l (E 3.14) but does at x = 0.241 m "
        f"({sum(x.status == 'match' for x in cells) - sum(x.status == 'match' for x in gauge_cells)} of its "
        f"{len(cells) - len(gauge_cells)} cells match at x = l, the zero row)."
    )
    _conversion(study.conversion, e)
    _plant_printed(p, study.plant.printed, e)
    _closed_loop(study.plant.printed, e)
    _plant_variants(ctx, study, e, chapter)
    chapter.tables.extend(study.tables)
    chapter.paragraphs.append("Printed versus consistent plant, numbered:")
    chapter.paragraphs.extend(explain_discrepancies(p))
    return chapter


# --- a digit other than the thesis rig ------------------------------------------------------------------------
SECTION_DIGIT = "3 (this digit)"


def _digit_chapter(ctx: ReportContext, study, chapter: Chapter) -> Chapter:
    """The models chapter on a digit other than the thesis rig: its own components from its description (the
    servo's step with its gearing, K2 of E 3.19, E 3.15 at its gauges, the unit-correct plant's gains). The thesis's
    printed tables, fits and plant are its rig's prints and measurements: audited in the thesis rig's report only."""
    p = ctx.params
    a, g = p.actuator, p.geometry
    e = chapter.entries
    chapter.paragraphs.append(
        "The thesis's chapter 3 prints its rig's release tests (tables 3.1, 3.2), deflections (tables 3.4, 3.6), "
        "fits (E 3.16-3.25) and plant G(s) (3.5, table 4.1): those are audited, with their slips, in the thesis "
        "rig's report (`flexdigit reproduce`), not here. This chapter rebuilds this digit's components from its "
        "description (flexdigit.models): the servo's command step at the pulley, the cable's K2 (E 3.19), the "
        "deflections E 3.15 predicts at its gauges, and the unit-correct plant chain command -> servo angle -> "
        "cable shortening -> moment -> curvature -> deflection, rotation or gauge volts."
    )
    gear = f" through its {a.gear_ratio:g}:1 gearing" if a.gear_ratio != 1 else ""
    e += [
        new(
            "servo.rad_per_command",
            SECTION_DIGIT,
            a.rad_per_command,
            "rad/command",
            f"The servo's step: {a.angle_max_deg - a.angle_min_deg:g} deg over commands {a.command_min}.."
            f"{a.command_max} ({a.deg_per_command:.4g} deg a command; {a.pulley_deg_per_command:.4g} deg at the "
            f"pulley{gear}).",
        ),
        new(
            "cable.K2",
            SECTION_DIGIT,
            study.k2,
            "N m/rad",
            "E I r_M/(l e) (E 3.19) from this digit's strip, pulley, gearing and eccentricity.",
        ),
        new(
            "plant.consistent.tip_rotation_deg_per_command",
            SECTION_DIGIT,
            cable.tip_rotation_per_command_deg(p),
            "deg/command",
            "r_M x rad per command / e (with the gearing): what one command does to the tip.",
        ),
        new(
            "cable.commands_for_30deg_tip_rotation",
            SECTION_DIGIT,
            commands_for_tip_rotation(30.0, p),
            "commands",
            "Commands for 30 deg of tip rotation by the cable model.",
        ),
    ]
    for out, c in study.plant.consistent.items():
        e.append(
            new(
                f"plant.consistent.{out}.dc_gain",
                SECTION_DIGIT,
                c.dc_gain,
                f"{c.output_unit}/command",
                "Unit-correct chain from this digit's components, cable-model gains (gauge 1: its first gauge at "
                f"{1000 * g.gauge_positions_m[0]:g} mm).",
            )
        )
    _digit_tables_and_figures(ctx, study, chapter)
    return chapter


def _digit_tables_and_figures(ctx: ReportContext, study, chapter: Chapter) -> None:
    """E 3.15 at the digit's gauges, its plant's DC gains; its servo's and its plant's pole-zero and Bode plots."""

    p, g = ctx.params, ctx.params.geometry
    t34 = study.table_3_4.ours
    columns = table_3_4_gauge_columns(t34)
    chapter.tables.append(
        ResultTable(
            "models.table_3_4",
            f"E 3.15 on this digit (table 3.4's computation): deflection (mm) at its {ctx.gauges_text} "
            f"({', '.join(f'{1000 * x:g}' for x in g.gauge_positions_m)} mm) and at its tip "
            f"({1000 * g.digit_length_m:g} mm), commands {int(t34['commands'][0])}..{int(t34['commands'][-1])} "
            "from its straight command",
            ("command", *(f"sg{col[4:-3]}_mm" for col in columns), "y_tip_mm"),
            tuple(
                (int(c), *(float(t34[col][j]) for col in columns), float(t34["y_max_mm"][j]))
                for j, c in enumerate(t34["commands"])
            ),
        )
    )
    chapter.tables.append(
        ResultTable(
            "models.plant_dc_gains",
            "This digit's unit-correct plant: DC gain per command (in the output's unit)",
            ("output", "unit", "dc_gain_per_command"),
            tuple((out, c.output_unit, c.dc_gain) for out, c in study.plant.consistent.items()),
        )
    )
    mount = digit_mount(p)
    plant = digit_plant(p, orientation=mount)
    fig = _bode_pz([("MT(s) x rad/command (this digit's servo)", study.servo_tf["consistent"])], "Servo")
    chapter.figures.append(ctx.save_figure(fig, "ch3_servo_bode_pz", "This digit's servo MT(s): pole-zero and Bode"))
    fig = _bode_pz([("gauge-1 deflection per command", plant.tf)], "Plant", normalise=True)
    chapter.figures.append(
        ctx.save_figure(
            fig,
            "ch3_plant_bode_pz",
            "This digit's plant from its components (gauge-1 deflection, magnitude normalised to its DC gain; E(s) "
            f"its twin's release mode, mounted {'tip up' if mount == 'vertical' else mount}): pole-zero and Bode",
        )
    )


# --- 3.1.2: release tests and E(s) ------------------------------------------------------------------------
def _release_entries(release, e: list[Entry]) -> None:
    """Table 3.1 or 3.2: each zeta from its %OS, the averages, each wn from its wd."""
    table = release.table.key.removeprefix("models.table_").replace("_", ".")
    t = thesis_value(f"digit.release_tests_{release.name}")
    os_, zeta, wn_from_wd = release.percent_overshoot, release.zeta, release.wn_from_wd_rad_s
    for i, (z_ours, z_print) in enumerate(zip(zeta, t["zeta"], strict=True), start=1):
        key = f"table_{table.replace('.', '_')}.zeta[{i}]"
        if not np.isfinite(z_ours):
            e.append(
                compare(
                    key,
                    "3.1.2",
                    z_print,
                    z_ours,
                    "",
                    rtol=0.0,
                    discrepancy_note=f"The %OS of this row is printed garbled ('80.59.5973'), read as NaN. The "
                    f"printed zeta {z_print} implies %OS = {second_order.overshoot_from_zeta(z_print):.4f}, "
                    "so the value "
                    "was most likely 80.5973 with a stray '59.'.",
                )
            )
            continue
        e.append(
            compare(
                key,
                "3.1.2",
                z_print,
                z_ours,
                "",
                rtol=_printed_rtol(z_print, 4),
                note=f"zeta = -ln(OS/100)/sqrt(pi^2 + ln^2(OS/100)) from %OS = {os_[i - 1]}; printed to 4 decimals.",
                discrepancy_note="The printed zeta does not follow from its printed %OS.",
            )
        )
    # averages: a NaN row (garbled %OS) falls back on its printed zeta
    z_for_avg = np.where(np.isfinite(zeta), zeta, t["zeta"])
    e.append(
        compare(
            f"table_{table.replace('.', '_')}.zeta_avg",
            "3.1.2",
            t["zeta_avg"],
            float(np.mean(z_for_avg)),
            "",
            rtol=_printed_rtol(t["zeta_avg"], 4),
            note="Mean of the recomputed zetas (the printed zeta where %OS is unreadable); the rows are "
            "known to 4 decimals, so is their mean.",
            discrepancy_note="The printed average is not the mean of the rows.",
        )
    )
    e.append(
        compare(
            f"table_{table.replace('.', '_')}.wn_avg_rad_s",
            "3.1.2",
            t["wn_avg_rad_s"],
            float(np.mean(t["wn_rad_s"])),
            "rad/s",
            rtol=1e-4,
            note="Mean of the printed wn column.",
            discrepancy_note="The printed average is not the mean of the rows.",
        )
    )
    _release_wn_rows(table, t, wn_from_wd, e)


def _release_wn_rows(table: str, t: dict, wn_from_wd, e: list[Entry]) -> None:
    """Table 3.1 or 3.2's wn column against wd/sqrt(1 - zeta^2) of each printed row."""
    wn_printed, wd_printed = np.asarray(t["wn_rad_s"]), np.asarray(t["wd_rad_s"])
    for i, (wn_p, wn_o) in enumerate(zip(wn_printed, wn_from_wd, strict=True), start=1):
        implied_zeta = math.sqrt(1 - (wd_printed[i - 1] / wn_p) ** 2)
        e.append(
            compare(
                f"table_{table.replace('.', '_')}.wn_rad_s[{i}]",
                "3.1.2",
                float(wn_p),
                float(wn_o),
                "rad/s",
                rtol=_printed_rtol(float(wn_p), 4),
                note=f"wd/sqrt(1 - zeta^2) from the printed wd = {wd_printed[i - 1]} rad/s and zeta = "
                f"{t['zeta'][i - 1]} of the same row; the printed wn has 4 decimals.",
                discrepancy_note=f"In table {table} the printed wn is not wd/sqrt(1 - zeta^2): wd/wn of this row "
                f"needs zeta = {implied_zeta:.4f}, not the tabulated {t['zeta'][i - 1]}. The wn column must come "
                "from wn = 4/(zeta Ts) with settling times that are not printed; the wd column is the one "
                f"consistent with zeta, and gives wn = {wn_o:.4f} rad/s.",
            )
        )


def _digit_model(ctx: ReportContext, study, chapter: Chapter) -> None:
    """E(s) of 3.1.2 beside its printed coefficients and bandwidth (figure 3.5)."""
    e = chapter.entries
    e_tf = study.digit_tf
    den_e = thesis_value("digit.model.e_den")
    den = e_tf.den[0][0]
    e.append(
        compare(
            "digit.E.wn2",
            "3.1.2",
            den_e[2],
            den[2],
            "rad^2/s^2",
            rtol=1e-3,
            note="wn^2 from table 3.2's average wn = 13.0995 rad/s (printed 171.61 = 13.1^2).",
        )
    )
    e.append(
        compare(
            "digit.E.2_zeta_wn",
            "3.1.2",
            den_e[1],
            den[1],
            "rad/s",
            rtol=1e-3,
            discrepancy_note="2 x 0.06791 x 13.0995 = 1.7792; the printed 1.782 is 2 x 0.068 x 13.1, the average "
            "zeta and wn rounded before multiplying (0.16 %).",
        )
    )
    e.append(
        compare(
            "digit.E.bandwidth_rad_s",
            "3.1.2",
            20.3,
            float(control.bandwidth(e_tf)),
            "rad/s",
            rtol=5e-3,
            note="The 'attenuation around 20.3 rad/s' of figure 3.5 is E(s)'s -3 dB bandwidth (3.23 Hz).",
        )
    )
    fig = _bode_pz([("E(s), with housing (3.1.2)", e_tf), ("bare strip (table 3.1)", study.bare_digit_tf)], "Digit")
    chapter.figures.append(
        ctx.save_figure(fig, "ch3_digit_bode_pz", "Digit E(s): pole-zero and Bode plots", thesis_ref="figure 3.5")
    )


# --- 3.2.4: servo ---------------------------------------------------------------------------------------
def _servo_scale_entries(p, e: list[Entry]) -> None:
    """The potentiometer's slope (3.2.4) and the servo's rad per command (3.4.1) beside their printed values."""
    pot_printed = servo.PotentiometerMap.printed()
    pot_params = servo.PotentiometerMap.from_params(p)
    e.append(
        compare(
            "servo.pot_slope_deg_per_v",
            "3.2.4",
            pot_printed.slope_deg_per_v,
            pot_params.slope_deg_per_v,
            "deg/V",
            rtol=1e-4,
            note="219 deg over the printed end-point voltages.",
            discrepancy_note=f"The printed line 109.1344 V - 51.162 gives 0 deg at {pot_printed.voltage_v(0):.4f} V; "
            f"the printed 0-degree voltage {p.actuator.pot_v_at_min_angle_v} V is a transposition of 0.46880 V. "
            "The printed plant uses the printed line.",
        )
    )
    e.append(
        compare(
            "servo.rad_per_command",
            "3.4.1",
            thesis_value("actuator.rad_per_command"),
            p.actuator.rad_per_command,
            "rad/command",
            rtol=_printed_rtol(thesis_value("actuator.rad_per_command"), 4),
            note="0.8622 pi/180 = 0.015048, printed as 0.0150 (E 3.15); table 3.4 needs the unrounded value.",
        )
    )


def _servo(ctx: ReportContext, study, chapter: Chapter) -> None:
    p = ctx.params
    e = chapter.entries
    mt = study.servo_tf["unit"]
    den = mt.den[0][0]
    mt_den = thesis_value("actuator.model.mt_den")
    e.append(compare("servo.MT.wn2", "3.2.4", mt_den[2], den[2], "rad^2/s^2", rtol=1e-3, note="wn = 20.53 rad/s."))
    e.append(
        compare("servo.MT.2_zeta_wn", "3.2.4", mt_den[1], den[1], "rad/s", rtol=1e-3, note="zeta = 0.5629 (3.2.4).")
    )
    mt_rad = study.servo_tf["printed"]
    e.append(
        compare(
            "servo.MT_rad.num",
            "3.2.4",
            thesis_value("actuator.model.mt_rad_num")[0],
            mt_rad.num[0][0][-1],
            "rad/command (as printed)",
            rtol=1e-3,
            note="421.5 x 109.1344 x pi/180; the unit is not rad per command (see discrepancy 2 below).",
        )
    )
    e.append(
        new(
            "servo.MT_consistent.dc_gain",
            "3.2.4",
            float(study.servo_tf["consistent"].dcgain()),
            "rad/command",
            "MT(s) has unit DC gain; times 219/254 deg per command: the servo's real rad per command.",
        )
    )
    bw = float(control.bandwidth(mt))
    zeta_wn = p.actuator.servo_zeta * p.actuator.servo_wn_rad_s
    e.append(
        compare(
            "servo.MT.bandwidth_rad_s",
            "3.2.4",
            11.55,
            bw,
            "rad/s",
            rtol=0.01,
            discrepancy_note=f"'Most of the energy below 11.55 rad/s' quotes zeta wn = {zeta_wn:.3f} rad/s, the "
            f"real part of MT's poles; MT's -3 dB bandwidth is {bw:.2f} rad/s.",
        )
    )
    _servo_scale_entries(p, e)
    fig = _bode_pz(
        [
            ("MT(s) x 109.1344 pi/180 (printed)", mt_rad),
            ("MT(s) x rad/command (consistent)", study.servo_tf["consistent"]),
        ],
        "Servo",
    )
    chapter.figures.append(
        ctx.save_figure(fig, "ch3_servo_bode_pz", "Servo MT(s): pole-zero and Bode plots", thesis_ref="figure 3.14")
    )


# --- 3.3-3.4.2: cable, K2, table 3.4 ---------------------------------------------------------------------
def _cable(p, study, e: list[Entry]) -> None:
    """K2 (E 3.19) and every cell of table 3.4 (E 3.15)."""
    k2 = study.k2
    e.append(
        compare(
            "cable.K2",
            "3.4.2",
            thesis_value("cable.k2_nm_per_rad"),
            k2,
            "N m/rad",
            rtol=1e-3,
            note=f"E I r_M/(l e) with table 3.7 (E 3.19) is {k2:.6f}, 0.056 % above the printed 0.089377, which "
            f"is reproduced ({study.k2_rounded_i:.6f}) with I rounded to 5.85e-14 m^4 before multiplying.",
            discrepancy_note="More than 0.1 % from the printed K2: the parameters differ from table 3.7.",
        )
    )
    t34 = study.table_3_4
    ours, ours_fit, x_fit = t34.ours, t34.ours_at_fit, t34.tip_x_fit_m
    cmds = ours["commands"]
    n_fit_equal = int(
        np.sum(np.round(ours_fit["y_max_mm"], 2) == np.asarray(thesis_value("conversion.table_3_4_y_max_mm")))
    )
    gauges = [(col, f"gauge {col[4:-3]}") for col in table_3_4_gauge_columns(ours)]
    for col, label in (*gauges, ("y_max_mm", "tip")):
        printed = np.asarray(table_3_4_printed(col, p, len(cmds)), dtype=float)
        if col == "y_max_mm":
            where = f"x = l = {p.geometry.digit_length_m} m (E 3.14)"
        else:
            where = f"x = {p.geometry.gauge_positions_m[int(col[4]) - 1]} m"
        for j, c in enumerate(cmds):
            discrepancy = ""
            if col == "y_max_mm":
                discrepancy = (
                    f"E 3.14 puts y_max at x = l = {p.geometry.digit_length_m} m; the printed column fits x = "
                    f"{x_fit:.4f} m (least squares), which gives {ours_fit['y_max_mm'][j]:.2f} mm here and all "
                    f"{n_fit_equal} of {printed.size} rows as printed. The 240 mm strip gives 3.23 mm per command, "
                    "not the printed 3.26."
                )
            e.append(
                compare(
                    f"table_3_4.{col}[{int(c)}]",
                    "3.4.1",
                    float(printed[j]),
                    float(ours[col][j]),
                    "mm",
                    rtol=_printed_rtol(float(printed[j]), 2),
                    note=f"Deflection at {label} for command {int(c)}, E 3.15 at {where} with 0.8622 deg per "
                    "command; the table prints 2 decimals.",
                    discrepancy_note=discrepancy or "This cell differs from the printed table at its precision.",
                )
            )
    e.append(
        compare(
            "cable.commands_for_30deg_tip_rotation",
            "3.6",
            15.0,
            commands_for_tip_rotation(30.0, p),
            "commands",
            rtol=0.05,
            discrepancy_note=f"By the cable model the tip turns {cable.tip_rotation_per_command_deg(p):.3f} deg per "
            "command, so 30 deg is 17.3 steps (3.6 says 'approximately fifteen'; 3.4.1 calls commands 8..43, "
            "which are 30 deg of servo rotation, '0 to 30 deg of beam rotation').",
        )
    )


# --- 3.4.1, 3.4.3: K1 and K3 ------------------------------------------------------------------------------
def _conversion(study, e: list[Entry]) -> None:
    """K1 and K3 beside E 3.16-3.18 and E 3.23-3.25, the fits' slopes and the K3 offsets."""
    k1, k3 = study.k1, study.k3
    k1_print = thesis_value("conversion.k1_command_per_mm")
    k3_print = thesis_value("conversion.k3_mm_per_v")
    ours_fits, ols_fits, printed_fits = study.through_equilibrium, study.ols, study.printed_fits
    offsets = study.offsets_mm
    offsets_print = thesis_value("conversion.k3_offset_mm")
    for g in range(3):
        n = g + 1
        e.append(
            compare(
                f"conversion.K1_sg{n}",
                f"E 3.{15 + n}",
                k1_print[g],
                k1[g],
                "command/mm",
                rtol=2e-4,
                note="K1 = 1/a of the printed fit.",
            )  # fmt: skip
        )
        e.append(
            compare(
                f"conversion.K3_sg{n}",
                f"E 3.{22 + n}",
                k3_print[g],
                k3[g],
                "mm/V",
                rtol=1e-4,
                note="K3 = a/s: printed deflection slope over printed voltage slope (E 3.20-3.22).",
            )  # fmt: skip
        )
        e.append(
            compare(
                f"conversion.a_sg{n}",
                "3.4.1",
                printed_fits[g].slope,
                ours_fits[g].slope,
                "mm/command",
                rtol=0.01,
                note="Our least-squares slope of table 3.6 through (8, 0), as the printed fits pass through it.",
                discrepancy_note=f"The printed slope does not fit table 3.6 as printed (ordinary least squares "
                f"{ols_fits[g].slope:.4f}, through (8, 0) {ours_fits[g].slope:.4f}); the data behind it (figure 3.17 "
                "runs to command 43) are not in the thesis. K1 and K3 use the printed slopes.",
            )
        )
        e.append(
            compare(
                f"conversion.K3_offset_sg{n}",
                "3.4.3",
                offsets_print[g],
                offsets[g],
                "mm",
                rtol=1e-3,
                discrepancy_note="Substituting V = s command + c into y = a command - b gives the offset "
                "-a c/s - b; the printed offsets are -a c/s alone"
                + (" and gauge 1's is a tenth of it (0.1246 for 1.2456)." if g == 0 else "."),
            )
        )


# --- 3.5 and table 4.1: the plant --------------------------------------------------------------------------
def _pole_entries(e: list[Entry], key: str, section: str, printed: list[complex], ours, note: str, discrepancy=None):
    """One entry for the real and one for the imaginary part of each printed upper-half-plane pole (its conjugate
    is the same figure), beside our nearest pole; ``discrepancy(k, part, printed, ours)`` explains a miss."""
    ours = np.asarray(ours, dtype=complex)
    for k, pp in enumerate((p for p in printed if p.imag > 0), start=1):
        q = ours[np.argmin(np.abs(ours - pp))]
        for part, t_val, o_val in (("real", pp.real, q.real), ("imag", pp.imag, abs(q.imag))):
            e.append(
                compare(
                    f"{key}[{k}].{part}",
                    section,
                    float(t_val),
                    float(o_val),
                    "rad/s",
                    rtol=1e-3,
                    note=f"{'Real' if part == 'real' else 'Imaginary'} part of the pole printed as {pp.real:.4f} +- "
                    f"{pp.imag:.4f}j (ours {q.real:.4f} +- {abs(q.imag):.4f}j). {note}".strip(),
                    discrepancy_note=(discrepancy(k, part, pp, q) if discrepancy else "")
                    or "More than 0.1 % from the printed pole.",
                )
            )


def _plant_printed(p, g, e: list[Entry]) -> None:
    """The printed G(s) of 3.5 from the component models: coefficients, poles, state space, ranks."""
    num = g.tf.num[0][0] / g.tf.den[0][0][0]
    den = g.tf.den[0][0] / g.tf.den[0][0][0]
    e.append(
        compare(
            "plant.G.num",
            "3.5",
            thesis_value("plant.g_num")[0],
            num[-1],
            "m/command (as printed)",
            rtol=1e-3,
            note="K2 x K3[m/V] x 802.854 x wn^2, all from the component models (K1 excluded).",
        )
    )
    for k, (t, o) in enumerate(zip(thesis_value("plant.g_den"), den, strict=True)):
        e.append(compare(f"plant.G.den[s^{4 - k}]", "3.5", t, o, "", rtol=1e-3))
    _pole_entries(
        e,
        "plant.G.poles",
        "3.5",
        thesis_complex("plant.poles"),
        g.poles,
        f"The slow pair is the digit factor's: 2 zeta wn = {PRINTED_DIGIT_DAMPING_1_PER_S} 1/s (zeta = "
        f"{printed_digit_zeta(p):.4f}, the [plant] note's identified factor) with table 3.1's wn; the fast pair is "
        "MT(s)'s.",
    )
    e.append(compare("plant.G.ss_A14", "3.5", -43535.0, g.ss.A[0, 3], "", rtol=1e-3, note="Companion form as 3.5."))
    e.append(
        compare(
            "plant.G.ss_C4",
            "3.5",
            6.7571e10,
            g.ss.C[0, 3],
            "",
            rtol=1e-3,
            discrepancy_note="In the companion form C(4) is G's numerator, 48.7 (m) or 48,700 (mm); the printed "
            "6.7571e10 and the 6.757e13 of the 'mm/m' G match neither, nor each other.",
        )
    )
    e.append(compare("plant.G.controllability_rank", "3.5", 4, g.controllability_rank, "", rtol=0.0))
    e.append(compare("plant.G.observability_rank", "3.5", 4, g.observability_rank, "", rtol=0.0))
    e.append(
        compare(
            "plant.G.minimum_phase",
            "3.5",
            1.0,
            float(g.is_minimum_phase),
            "bool",
            rtol=0.0,
            note=f"{g.zeros.size} finite zeros, all poles stable.",
        )
    )


def _closed_loop(g, e: list[Entry]) -> None:
    """Table 4.1: the printed plant closed with K1, beside the printed numerator, denominator and poles."""
    k1 = closed_loop_printed_k1()
    cl = g.closed_loop(k1)
    cl_den = cl.den[0][0] / cl.den[0][0][0]
    e.append(
        new(
            "plant.closed_loop.K1",
            "4.2",
            k1,
            "command/unit",
            f"The K1 that reproduces table 4.1's numerator 86.2 = K1 x 48.7 (not printed): E 3.16's "
            f"{conversion.k1_printed_command_per_mm()[0]} / 10.",
        )
    )
    e.append(
        compare(
            "plant.closed_loop.num",
            "4.2",
            thesis_value("plant.closed_loop_num")[0],
            cl.num[0][0][-1] / cl.den[0][0][0],
            "",
            rtol=1e-3,
        )  # fmt: skip
    )
    e.append(
        compare(
            "plant.closed_loop.den[s^0]", "4.2", thesis_value("plant.closed_loop_den")[-1], cl_den[-1], "", rtol=1e-3
        )  # fmt: skip
    )
    roots_printed_den = np.roots(thesis_value("plant.closed_loop_den"))

    def closed_loop_miss(k, part, pp, q):
        root = roots_printed_den[np.argmin(np.abs(roots_printed_den - pp))]
        printed_v, root_v, ours_v = (abs(z.imag) if part == "imag" else z.real for z in (pp, root, q))
        return (
            f"The printed {printed_v:.4f} is not the {part} part of a root of table 4.1's own denominator, whose "
            f"root here is {root.real:.4f} +- {abs(root.imag):.4f}j; ours, {ours_v:.4f}, is "
            f"{100 * abs(ours_v / root_v - 1):.2f} % from that root, and |ours - printed| is only "
            f"{100 * abs(q - pp) / abs(pp):.3f} % of the printed pole's modulus."
        )

    _pole_entries(
        e,
        "plant.closed_loop.poles",
        "table 4.1",
        thesis_complex("plant.closed_loop_poles"),
        cl.poles(),
        "Closed loop K1 G/(1 + K1 G) with K1 = 1.7699.",
        closed_loop_miss,
    )


def _plant_variants(ctx: ReportContext, study, e: list[Entry], chapter: Chapter) -> None:
    """The unit-consistent plant's DC gains, and the printed and consistent plants' Bode and pole-zero plots."""
    p = ctx.params
    g = study.plant.printed
    for out, c in study.plant.consistent.items():
        e.append(
            new(
                f"plant.consistent.{out}.dc_gain",
                "3.5",
                c.dc_gain,
                f"{c.output_unit}/command",
                "Unit-correct chain, cable-model gains.",
            )
        )
    cons = study.plant.consistent["deflection_sg1_m"]
    e.append(
        new(
            "plant.printed_over_cable_dc_gain",
            "3.5",
            g.dc_gain / cons.dc_gain,
            "",
            "Printed G(0) over the cable model's deflection per command at gauge 1 (discrepancy 6 below).",
        )
    )
    e.append(
        new(
            "plant.consistent.tip_rotation_deg_per_command",
            "3.4",
            cable.tip_rotation_per_command_deg(p),
            "deg/command",
            "r_M x rad_per_command / e: what one command does to the tip.",
        )
    )
    fig = _bode_pz(
        [("printed G(s) (3.5)", g), ("consistent, gauge-1 deflection", cons.tf)],
        "Plant",
        normalise=True,
    )
    chapter.figures.append(
        ctx.save_figure(
            fig,
            "ch3_plant_bode_pz",
            "Plant G(s), printed and consistent (magnitudes normalised to their DC gains): pole-zero and Bode",
            thesis_ref="figure 3.18",
        )
    )


# --- figures --------------------------------------------------------------------------------------------
def _bode_pz(systems, title: str, *, normalise: bool = False):
    """A pole-zero map beside Bode magnitude and phase, for a few SISO systems (thesis figure layout)."""
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(10, 4.2))
    ax_pz = fig.add_subplot(1, 2, 1)
    ax_mag = fig.add_subplot(2, 2, 2)
    ax_ph = fig.add_subplot(2, 2, 4, sharex=ax_mag)
    w = np.logspace(-1, 3, 600)
    markers = ("x", "+", "1", "2")
    for k, (label, sys) in enumerate(systems):
        tf = sys.tf if hasattr(sys, "tf") else sys
        resp = np.array([complex(tf(1j * x)) for x in w])
        if normalise:
            resp = resp / float(np.real(tf.dcgain()))
        ax_mag.semilogx(w, 20 * np.log10(np.abs(resp)), label=label)
        ax_ph.semilogx(w, np.degrees(np.unwrap(np.angle(resp))))
        poles = tf.poles()
        ax_pz.plot(poles.real, poles.imag, markers[k % 4], markersize=9, label=label)
        zeros = tf.zeros()
        if zeros.size:
            ax_pz.plot(zeros.real, zeros.imag, "o", fillstyle="none")
    ax_pz.axvline(0, color="0.6", lw=0.8)
    ax_pz.axhline(0, color="0.6", lw=0.8)
    ax_pz.set(xlabel="real (1/s)", ylabel="imaginary (rad/s)", title=f"{title}: poles")
    ax_pz.legend(fontsize=7)
    ax_mag.set(ylabel="magnitude (dB)" + (" re DC" if normalise else ""), title=f"{title}: Bode")
    ax_mag.legend(fontsize=7)
    ax_mag.grid(True, which="both", alpha=0.3)
    ax_ph.set(xlabel="frequency (rad/s)", ylabel="phase (deg)")
    ax_ph.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return fig

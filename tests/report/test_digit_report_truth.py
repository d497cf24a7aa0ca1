"""The report of a described digit (``reproduce --params``) tells that digit's figures, never the thesis rig's
(issue 24 item 3): its commands, its step, its plant and its design, with the thesis rig's prints left out rather
than shown beside it. Two hand-made digits of tests/data/handmade_digits: a 150 mm two-section cable pair straight
at command 127 (quarter bridges), and a 440 mm four-section digit with eight gauges behind a 3:1 gear.

The hand figures: E 3.11 with the gearing, the tip turns ``r_M dtheta / (n e)`` a command, with the thesis's
r_M = 11.5 mm, e = 5.715 mm and 219 deg over 254 commands (table 3.7, E 3.15; neither file changes them).
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from flexdigit.params import RigParams, load_params
from flexdigit.report import ch3_models, ch3_twin, ch4_control, ch8_palpation
from flexdigit.report.build import DIGIT_HEADLINE, HEADLINE, _digit_calibration, results_document
from flexdigit.report.chapter import Chapter, ReportContext
from flexdigit.report.results import thesis_comparisons
from flexdigit.twin.records import release_orientation

DIGITS = Path(__file__).resolve().parents[1] / "data" / "handmade_digits"
#: name -> (gear ratio, straight command, gauges), as the files write them (or the thesis defaults they keep)
CASES = {"short_pair_quarter": (1.0, 127, 2), "four_sections_geared_eight": (3.0, 8, 8)}
#: The thesis rig's tip rotation a command by the same formula (1.735 deg, 3.4.1)
THESIS_DEG_PER_COMMAND = math.degrees(11.5e-3 * math.radians(219 / 254) / 5.715e-3)
#: Two implementations of the same closed forms (E 3.15 and the plant chain), in floating point
EXACT = 1e-9


def _deg_per_command(gear: float) -> float:
    return THESIS_DEG_PER_COMMAND / gear


def _build(module, name: str, tmp_path) -> tuple[RigParams, Chapter]:
    params = load_params(DIGITS / f"{name}.toml")
    ctx = ReportContext(out_dir=tmp_path, params=params, fast=True)
    with thesis_comparisons(False), _digit_calibration(params):
        return params, module.build(ctx)


def _texts(chapter: Chapter) -> str:
    return "\n".join(
        [*chapter.paragraphs, *(e.note for e in chapter.entries), *(f.caption for f in chapter.figures)]
        + [t.title for t in chapter.tables]
    )


@pytest.mark.parametrize("name", CASES)
def test_the_models_chapter_gives_the_digits_components_not_the_thesis_prints(name, tmp_path):
    gear, straight, gauges = CASES[name]
    params, ch = _build(ch3_models, name, tmp_path)
    entries = {e.key: e for e in ch.entries}
    deg = _deg_per_command(gear)
    assert entries["plant.consistent.tip_rotation_deg_per_command"].ours == pytest.approx(deg, rel=EXACT)
    assert entries["cable.commands_for_30deg_tip_rotation"].ours == pytest.approx(30.0 / deg, rel=EXACT)
    # the thesis rig's printed tables, fits and plant are not this digit's: not one of their entries
    thesis_only = ("table_3_", "conversion.", "plant.G.", "plant.closed_loop", "digit.E.", "servo.MT")
    assert not [k for k in entries if k.startswith(thesis_only)]
    assert all(e.thesis is None and e.status == "new" for e in entries.values())
    # E 3.15 on the digit: one column per gauge, from its own straight command
    table = next(t for t in ch.tables if t.key == "models.table_3_4")
    assert len(table.columns) == 1 + gauges + 1
    assert table.rows[0][0] == straight
    assert "printed" not in " ".join(table.columns)
    text = _texts(ch)
    assert "0.056 % above the printed" not in text  # K2's note on the thesis rig
    if gear != 1:
        assert f"{0.8622 / gear:.4g} deg at the pulley" in entries["servo.rad_per_command"].note


@pytest.mark.parametrize("name", CASES)
def test_the_control_chapter_designs_on_the_digits_plant(name, tmp_path):
    from flexdigit.models import cable

    params, ch = _build(ch4_control, name, tmp_path)
    entries = {e.key: e for e in ch.entries}
    # the plant's DC gain is this digit's E 3.15 deflection a command at its first gauge (mm)
    e315 = cable.table_3_4(params=params)["y_sg1_mm"]
    assert entries["hinf.digit.plant_dc_gain_mm_per_command"].ours == pytest.approx(e315[1] - e315[0], rel=EXACT)
    # the digit's controllers, one per cut-off of 4.7's sweep; none of the thesis rig's printed-controller analysis
    assert {k[5:-12] for k in entries if k.endswith(".tzw_peak_db")} == {"k_0.5hz", "k_5hz", "k_39hz", "k_50hz"}
    thesis_only = ("hinf.k_5hz_num_lead", "hinf.k_39hz_zeros_vs_plant_poles", "plant.closed_loop_pole_0_abs")
    thesis_only += ("hinf.gamma_opt_lmi", "hinf.filter_peak_db", "hinf.additive_tolerance_5Hz", "mixsyn.command_max")
    assert not [k for k in thesis_only if k in entries]
    # the 5 Hz controller has the error filter's pole at 2 pi 5 rad/s and the others of this digit's design: its
    # poles are not the printed 5 Hz controller's (table 4.2)
    from flexdigit.control.thesis_designs import printed_controller

    poles = sorted(entries[f"hinf.k_5hz_pole_{i}_abs"].ours for i in range(5))
    assert min(abs(p - 2 * math.pi * 5) for p in poles) < 1e-6
    printed = sorted(abs(complex(p)) for p in printed_controller("5hz").poles())
    assert max(abs(a / b - 1) for a, b in zip(poles, printed, strict=True)) > 0.05
    assert "10x" not in " ".join(e.note for e in ch.entries)  # the printed controllers' gain slip
    assert ch.figures
    assert all("printed" not in f.caption for f in ch.figures)


@pytest.mark.parametrize("name", CASES)
def test_active_sensing_is_read_at_the_digits_commands(name, tmp_path):
    # the thesis's commands 0, 20 and 40 (12 commands either side of 20, 8 past straight) laid out on the digit: as
    # far in tip rotation from its straight command as they are from the thesis rig's 8
    gear, straight, _ = CASES[name]
    params = load_params(DIGITS / f"{name}.toml")
    ratio = THESIS_DEG_PER_COMMAND / _deg_per_command(gear)
    expected = [max(0, straight + round(offset * ratio)) for offset in (-8, 12, 32)]
    ctx = ReportContext(out_dir=tmp_path, params=params, fast=True)
    ch = Chapter("ch8-palpation", "palpation")
    ch8_palpation._active(ctx, ch, ch8_palpation.DigitSetting(params, release_orientation(params), True))
    note = next(e.note for e in ch.entries if e.key == "palpation.active.bayes_position_mm")
    assert f"commands {expected[0]}, {expected[1]} and {expected[2]}" in note
    assert "0, 20 and 40" not in note
    length_mm = 1000 * params.geometry.digit_length_m
    assert f"to {min(180, round(2 * length_mm / 3))} mm from it" in note  # the hangs reach 2/3 of the digit
    single = next(e.note for e in ch.entries if e.key == "palpation.active.single_bayes_position_mm")
    assert "22.5 mm" not in single  # chapter 7's figure on the thesis rig


@pytest.mark.parametrize("name", CASES)
def test_the_twin_chapter_describes_the_digit(name, tmp_path):
    _, straight, gauges = CASES[name]
    params = load_params(DIGITS / f"{name}.toml")
    text = ch3_twin._digit_twin_text(params)
    sections = params.geometry.section_count
    assert f"over its {sections} sections of " in text
    assert "90/180/270" not in text
    assert "80 mm section" not in text
    assert f"its {gauges} gauges" in text
    assert f"{params.sensors.adc_bits}-bit" in text
    commands = ch3_twin._shape_commands(ReportContext(out_dir=tmp_path, params=params))
    low, high = params.actuator.operating_commands
    assert (commands[0], commands[-1], len(commands)) == (low, high, 6)
    assert (straight == 8) == (commands == (8, 15, 22, 29, 36, 43))  # the thesis rig's only on its range


def test_the_front_page_headline_is_the_digits(tmp_path):
    params = load_params(DIGITS / "short_pair_quarter.toml")
    digit = ReportContext(out_dir=tmp_path, params=params)
    from flexdigit.report.results import new

    ch = Chapter(
        "x", "x", entries=[new("hinf.k_5hz.tzw_peak_db", "4.4", 0.3, "dB", ""), new("plant.G.num", "", 1, "", "")]
    )
    keys = [h["key"] for h in results_document([ch], digit)["headline"]]
    assert keys == ["hinf.k_5hz.tzw_peak_db"]  # the thesis rig's printed-plant headline is not the digit's
    assert set(DIGIT_HEADLINE).isdisjoint({"plant.G.num", "conversion.K1_sg1", "hinf.k_39hz_num_lead"})
    thesis = ReportContext(out_dir=tmp_path)
    assert [h["key"] for h in results_document([ch], thesis)["headline"]] == ["plant.G.num"]
    assert "plant.G.num" in HEADLINE

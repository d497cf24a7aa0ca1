"""Issue 24, trial 3 (/work/coord/trial3_report.md): what the third hand-made set found in ``run`` and ``params``.

Each test is a refusal or a message checked on one of tests/data/handmade_digits3's digits (or a one-key change of
one), before any twin moves: short by construction.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from flexdigit.cli import main

DATA = Path(__file__).resolve().parents[1] / "data" / "handmade_digits3"
#: The set's single-cable digits (no [cables] table: the thesis rig's one cable).
ONE_CABLE = ["mixed_bridges_three", "spring_bronze_two", "eight_gauges_two_sections"]


def _one_error_line(capsys, command: str) -> str:
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith(f"flexdigit {command}: error: ")
    return lines[0]


@pytest.mark.parametrize("name", ONE_CABLE)
def test_a_negative_setpoint_on_one_cable_is_refused_before_the_twin_moves(name, capsys, work_must_not_start):
    """A single cable pulls one way (slack below straight): -30 deg "completed" at 0.00 deg with exit 0 in trial 3."""
    from flexdigit.twin.twin import Twin

    work_must_not_start(Twin, "advance")
    path = DATA / f"{name}.toml"
    assert main(["run", "--params", str(path), "--setpoint-deg=-30", "--no-progress"]) == 2
    line = _one_error_line(capsys, "run")
    assert "--setpoint-deg -30" in line
    assert str(path) in line
    assert "one cable" in line
    assert "reaches 0.0 to " in line


def test_the_library_check_is_the_one_run_step_and_live_use():
    """run_step, board_step_test and the live page's slider all read :func:`reachable_rotation_deg`."""
    from flexdigit.errors import ParameterError
    from flexdigit.live.session import setpoint_range
    from flexdigit.params import load_params
    from flexdigit.rig.step_test import check_setpoint, reachable_rotation_deg

    params = load_params(DATA / "spring_bronze_two.toml")
    bottom, top = reachable_rotation_deg(params)
    assert bottom == 0.0
    assert top > 30.0
    assert check_setpoint(30.0, params) == 30.0
    assert check_setpoint(0.0, params) == 0.0  # straight: the cable's slack end, reachable
    with pytest.raises(ParameterError, match=r"setpoint_deg -0\.5: .* one cable"):
        check_setpoint(-0.5, params, name="setpoint_deg")
    assert setpoint_range(params, "deg")[0] == 0.0


def test_a_straight_command_outside_the_operating_commands_is_refused_naming_both(tmp_path, capsys):
    """Trial 3: ``equilibrium_command = 60`` beside the thesis's operating commands 8..43 loaded, and ``run`` then
    drove command 78."""
    path = tmp_path / "straight_at_60.toml"
    path.write_text("[actuator]\nequilibrium_command = 60\n", encoding="utf-8")
    assert main(["params", str(path)]) == 2
    line = _one_error_line(capsys, "params")
    assert str(path) in line
    assert "equilibrium_command" in line
    assert "operating_commands" in line
    assert "Got 60" in line
    assert "[8, 43]" in line


def test_a_digit_that_buckles_tip_up_gets_its_gauge_reach_without_a_library_warning(capsys, recwarn):
    """Trial 3: ``params seven_sections_450mm.toml`` printed the statics' ConvergenceWarning (its tip-up solve found
    no straight rest: the digit buckles so). Its reach is now solved hanging, as ``run`` mounts it."""
    from flexdigit.params import load_params
    from flexdigit.rig.gauge_rails import gauge_rails

    path = DATA / "seven_sections_450mm.toml"
    assert main(["params", str(path)]) == 0
    assert capsys.readouterr().err == ""
    assert [str(w.message) for w in recwarn] == []
    reaches = gauge_rails(load_params(path))
    # 42 commands of a 0.8 mm offset cable bend a 0.45 m digit tens of degrees (49.9 deg hanging when measured)
    assert 20.0 < reaches[0].range_deg[1] < 90.0
    assert all(r.v_per_deg != 0.0 for r in reaches)


@pytest.mark.parametrize(
    ("bad", "shown"),
    [
        ("bits_overflow", "Got 99999999999999999999999 bits instead"),  # was "1e+23 bits"
        ("date_for_count", "Got 1979-05-27 (a date) instead"),  # was "datetime.date(1979, 5, 27)"
        ("negative_channel", "Got [-1, 1, 2] instead"),  # was "[-1.0, 1.0, 2.0]"
        # as strip_thickness_m = 0.381 gets "did you mean mm"
        ("gauges_in_mm", "Got [45, 135, 225] instead: did you mean mm ([0.045, 0.135, 0.225] m)?"),
    ],
)
def test_a_refused_value_reads_as_it_was_written(bad, shown, capsys):
    assert main(["params", str(DATA / "bad" / f"{bad}.toml")]) == 2
    assert shown in _one_error_line(capsys, "params")


def test_figures_over_no_identifiable_reading_say_not_applicable_not_nan(recwarn):
    """Trial 3: reproduce --params pair_one_quarter_gauge_geared.toml (one gauge: no reading tells a load's position
    from its mass) printed numpy's "Mean of empty slice" and wrote 8 chapter-6 figures as null. The means over no
    identifiable reading are NaN without a warning, and the chapter's entries say why instead."""
    import math
    from types import SimpleNamespace

    import numpy as np

    from flexdigit.report import results
    from flexdigit.report.ch6_tactile import _not_applicable_without_identifiable
    from flexdigit.tactile.localisation import _empty_means_are_nan

    with _empty_means_are_nan(True):
        rms = float(np.sqrt(np.mean(np.array([])[np.array([], dtype=bool)] ** 2)))
    assert math.isnan(rms)
    assert [str(w.message) for w in recwarn] == []
    entries = [
        results.new("non_actuated.crlb_rms_mass_unknown_mm", "6 (new)", rms, "mm", "bound"),
        results.new("non_actuated.contact_accuracy", "6 (new)", 0.9, "", "contact"),
    ]
    none = SimpleNamespace(key="non_actuated", localisation=SimpleNamespace(extra={"identifiable_fraction": 0.0}))
    out = _not_applicable_without_identifiable(none, entries)
    assert out[0].ours.startswith("not applicable: no test reading is identifiable")
    assert out[1] == entries[1]  # a figure that is defined stays
    some = SimpleNamespace(key="non_actuated", localisation=SimpleNamespace(extra={"identifiable_fraction": 0.5}))
    assert _not_applicable_without_identifiable(some, entries) == entries


def test_a_predicted_position_off_the_digit_or_its_trained_span_is_flagged():
    """Trial 3: predict put loads 0.33 m from the tip of a 0.30 m digit unremarked. Flagged beyond the predictions'
    RMSE (here 3 mm): 2 mm short of the trained span is the network's scatter, 30 mm past the clamp is not."""
    from types import SimpleNamespace

    from flexdigit.tactile.localisation import _position_notes

    dataset = SimpleNamespace(meta={"digit_length_m": 0.30})
    saved = SimpleNamespace(meta={"position_span_m": [0.01, 0.25]})
    notes = _position_notes([0.33, 0.008, 0.12, 0.27, -0.02], dataset, saved, 0.003)
    assert notes[0] == "outside the digit (0 to 300 mm from the tip)"
    assert notes[1] == notes[2] == ""
    assert notes[3] == "outside the trained positions (10 to 250 mm from the tip)"
    assert notes[4].startswith("outside the digit")
    assert _position_notes([0.33], SimpleNamespace(meta={}), SimpleNamespace(meta={}), 0.003) == ("",)

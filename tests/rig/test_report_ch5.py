"""Report chapter 5 builds (fast mode) and says what the study found."""

from __future__ import annotations

import pytest

from flexdigit.report import ch5_digital
from flexdigit.report.chapter import ReportContext
from oracles import assert_entries_unchanged

pytestmark = [pytest.mark.slow, pytest.mark.blas]  # blas: see docs/guide/reliability.md, Portable numbers


def test_chapter_5_entries_and_figures(tmp_path):
    ch = ch5_digital.build(ReportContext(tmp_path, fast=True))
    entries = {e.key: e for e in ch.entries}
    # 5.1.1: the printed loop's bandwidth (24.3 rad/s) and the 10x sampling rule (0.0259 s) reproduce
    assert entries["digital.closed_loop_bandwidth_rad_s"].status == "match"
    assert entries["digital.sample_period_rule_s"].status == "match"
    # 5.1.2: step halving from 20 ms lands on the thesis's 5 ms
    assert entries["digital.step_halving_period_s"].ours == 0.005
    # the Euler limit differs from the printed "10 ms" and the note explains why
    euler = entries["digital.euler_unstable_above_s"]
    assert euler.status == "discrepancy"
    assert "2 zeta/wn" in euler.note
    assert entries["digital20.settling_time_s"].ours < 1.0
    assert entries["digital20.overshoot_percent"].ours < 10.0
    assert {f.name for f in ch.figures} == {"ch5_tustin_periods", "ch5_euler_periods", "ch5_zplane", "ch5_20ms_twin"}
    assert all((tmp_path / "figures" / f"{f.name}.png").exists() for f in ch.figures)
    # issue 15 moved the chapter's computations into rig.studies: every entry as the baseline has it
    assert_entries_unchanged(ch.entries, "ch5-digital")

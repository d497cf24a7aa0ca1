"""The report's force control on a digit is the hold ``flexdigit palpate --tissue soft-block --protocol hold --params
D --seed S`` runs (issue 24: chapter 8 held 0.1 N on digits palpate refuses, and showed the figure): the same
figures where palpate holds, "not applicable: <palpate's reason>" and no figure where it refuses.

Reference: palpate's own output from the command line (the same twin, seed, tissue, gains and checks: the figures
agree to floating point, EXACT).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from digits import write_digit
from flexdigit.cli import main
from flexdigit.params import load_params
from flexdigit.report.ch8_palpation import FORCE_KEYS, _force, digit_setting
from flexdigit.report.chapter import Chapter, ReportContext

DIGITS2 = Path(__file__).resolve().parents[1] / "data" / "handmade_digits2"
#: The report's seed 0 holds on the twin's seed 2 (the chapter's force stream), as `palpate --seed 2`
SEED = 2
#: One simulation twice, in one process: only the floating point of equal operations apart
EXACT = 1e-12


def _report_force(path: Path, tmp_path) -> Chapter:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    params = load_params(path)
    ctx = ReportContext(out_dir=tmp_path / "report", params=params, fast=True)
    ch = Chapter("ch8-palpation", "palpation")
    _force(ctx, ch, plt, digit_setting(ctx))
    return ch


def _palpate(path: Path, capsys) -> tuple[int, str]:
    code = main(["palpate", "--tissue", "soft-block", "--protocol", "hold", "--params", str(path), "--seed", str(SEED),
                 "--json"])  # fmt: skip
    out = capsys.readouterr()
    return code, out.out + out.err


#: quarter_single_150mm stands tip up; unequal_three_two_in_one hangs in palpate (its straight digit does not stand
#: tip up with a margin: control.design20ms.digit_mount), in the chapter too
@pytest.mark.parametrize("name", ["quarter_single_150mm", "unequal_three_two_in_one"])
def test_a_hold_palpate_runs_is_reported_with_palpates_figures(name, tmp_path, capsys):
    path = DIGITS2 / f"{name}.toml"
    ch = _report_force(path, tmp_path)
    code, out = _palpate(path, capsys)
    assert code == 0
    held = json.loads(out)
    entries = {e.key: e.ours for e in ch.entries}
    assert entries["palpation.force.steady_error"] == pytest.approx(held["steady_error"], rel=EXACT, abs=EXACT)
    assert entries["palpation.force.overshoot"] == pytest.approx(held["overshoot"], rel=EXACT, abs=EXACT)
    assert entries["palpation.force.settling_s"] == pytest.approx(held["settling_s"], rel=EXACT)
    assert len(ch.figures) == 1


def test_a_hold_palpate_refuses_is_not_applicable_with_its_reason(tmp_path, capsys):
    path = write_digit("one-section", tmp_path)  # one gauge: its force read is 12 mN uncertain, it holds 0.34 N
    ch = _report_force(path, tmp_path)
    code, out = _palpate(path, capsys)
    assert code == 2
    reason = out.strip().split("error: ", 1)[1]
    assert "cannot hold 0.1 N within 10 %" in reason
    entries = {e.key: e.ours for e in ch.entries}
    assert set(entries) == set(FORCE_KEYS)
    assert all(value == f"not applicable: {reason}" for value in entries.values())
    assert not ch.figures  # never a figure palpate would refuse
    assert reason in " ".join(ch.paragraphs)

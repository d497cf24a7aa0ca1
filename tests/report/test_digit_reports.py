"""``reproduce --params`` on the test digits of issue 24 (tests/digits.py): the report of that digit, its thesis
columns "not applicable", its twin and control chapters computed for it (and the twin's release wn the one
``flexdigit simulate release --params`` measures), the thesis rig's experiments skipped with their reason.

Only the chapters named here run (the library's ``chapters=``), in fast mode, one process: the whole report per
digit takes minutes (``flexdigit reproduce --fast --params D.toml``, docs/digits.md).
"""

from __future__ import annotations

import json

import pytest

from digits import DIGITS, write_digit
from flexdigit.cli import main
from flexdigit.params import load_params
from flexdigit.report.build import reproduce
from flexdigit.report.results import NOT_APPLICABLE

CHAPTERS = (
    "flexdigit.report.ch3_twin",
    "flexdigit.report.ch4_control",
    "flexdigit.report.ch8_studies",
    "flexdigit.report.ch8_palpation",
)
#: The digit whose straight, tip-up release test buckles under its supports' weight (tests/cli/test_simulate_digits)
BUCKLES = "five-sections-eight-gauges"
#: Two release tests of the same digit, seeds and lengths apart (5 s in the report's fast mode, 5 s here), each
#: identified by least squares on the median gauge: their wn agree to the identification's scatter (~1 %).
WN_RTOL = 0.03


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in DIGITS if n != "thesis"])
def test_the_report_of_a_digit(name, tmp_path, capsys):
    path = write_digit(name, tmp_path)
    summary = reproduce(tmp_path / "report", params=load_params(path), fast=True, chapters=CHAPTERS, workers=1)
    document = json.loads((tmp_path / "report" / "results.json").read_text())
    entries = document["entries"]
    # no entry of this digit stands against the thesis rig's figure
    assert entries and all(e["status"] == "new" and e["rel_error"] is None for e in entries)
    assert all(e["thesis"] in (None, NOT_APPLICABLE) for e in entries)
    assert any(e["thesis"] == NOT_APPLICABLE for e in entries)
    control = [e for e in entries if e["chapter"] == "ch4" and isinstance(e["ours"], float)]
    assert control, "the control chapter gave no number for this digit"
    skipped = [c for c in document["chapters"] if c["counts"] == {"match": 0, "discrepancy": 0, "new": 0}]
    assert len(skipped) == 2  # sensitivity/design and palpation: the thesis rig's, skipped with their reason
    html = (tmp_path / "report" / "index.html").read_text()
    assert html.count("Skipped for this digit:") == 2
    if name == BUCKLES:  # tip up it buckles: the twin chapter fails in one line saying so, the others are built
        assert list(summary.failed) == ["flexdigit.report.ch3_twin"]
        assert "buckles" in summary.failed["flexdigit.report.ch3_twin"]
        assert "\n" not in summary.failed["flexdigit.report.ch3_twin"]
        return
    assert summary.failed == {}
    wn = next(e["ours"] for e in entries if e["key"] == "twin.release_with_housing.wn_rad_s")
    out = tmp_path / "release.csv"
    assert main(["simulate", "release", "--params", str(path), "--out", str(out), "--duration", "5", "--json"]) == 0
    simulated = json.loads(capsys.readouterr().out)["findings"]["wn_rad_s"]
    assert wn == pytest.approx(simulated, rel=WN_RTOL)

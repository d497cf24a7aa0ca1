"""The palpation chapter (issue 13) builds in fast mode, with every figure and the issue's criteria as entries."""

import json

import pytest

from flexdigit.report.build import reproduce


@pytest.mark.slow
def test_palpation_chapter_builds_with_the_issue_figures(tmp_path):
    summary = reproduce(tmp_path, fast=True, chapters=("flexdigit.report.ch8_palpation",))
    assert summary.failed == {}
    document = json.loads((tmp_path / "results.json").read_text())
    entries = {e["key"]: e for e in document["entries"]}
    tables = {t["key"]: t for t in document["tables"] if t["chapter"] == "ch8-palpation"}
    assert set(tables) == {"palpation.classify", "palpation.stiffness", "palpation.active"}
    # tables hold numbers, and agree with the entries they sit beside
    stiffness = tables["palpation.stiffness"]
    errors = [row[stiffness["columns"].index("rel_error")] for row in stiffness["rows"]]
    assert max(abs(r) for r in errors) == pytest.approx(entries["palpation.stiffness.max_rel_error"]["ours"])
    active = tables["palpation.active"]["rows"]
    assert active[0][1] == pytest.approx(entries["palpation.active.single_bayes_position_mm"]["ours"])
    assert all(e["status"] == "new" for e in entries.values())
    # issue 13's "Done when", each a figure that could be wrong
    assert entries["palpation.contact.position_ratio_to_crlb"]["ours"] <= 1.2
    assert entries["palpation.contact.force_ratio_to_crlb"]["ours"] <= 1.2
    assert entries["palpation.classify.accuracy_where_allowed"]["ours"] >= 0.95
    assert entries["palpation.stiffness.max_rel_error"]["ours"] <= 0.10
    assert abs(entries["palpation.scan.inclusion_error_mm"]["ours"]) <= 10.0
    assert abs(entries["palpation.force.steady_error"]["ours"]) <= 0.10
    assert entries["palpation.force.overshoot"]["ours"] < 0.20
    single = entries["palpation.active.single_bayes_position_mm"]["ours"]
    assert entries["palpation.active.bayes_position_mm"]["ours"] < 0.5 * single
    for name in ("palpation_contact_map", "palpation_force_indentation", "palpation_scan", "palpation_force_control"):
        assert (tmp_path / "figures" / f"{name}.png").stat().st_size > 1000

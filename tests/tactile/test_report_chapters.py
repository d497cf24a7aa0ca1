import json

import pytest

from flexdigit.report.build import reproduce
from oracles import assert_entries_unchanged, assert_trained_entries_close

pytestmark = pytest.mark.blas  # run again under other OpenBLAS kernels by `make test` (docs/guide/reliability.md)


@pytest.mark.slow
def test_tactile_chapters_build_in_fast_mode(tmp_path):
    chapters = ("flexdigit.report.ch6_tactile", "flexdigit.report.ch7_tactile", "flexdigit.report.ch6_7_noise")
    summary = reproduce(tmp_path, fast=True, chapters=chapters)
    assert summary.failed == {}
    document = json.loads((tmp_path / "results.json").read_text())
    entries = {e["key"]: e for e in document["entries"]}
    # issue 15 moved the chapters' computations into the library and the noise studies into a chapter of their
    # own, built in parallel processes: every entry as the baseline has it
    for slug in ("ch6-tactile", "ch7-tactile", "ch6-7-noise"):
        assert_entries_unchanged(document["entries"], slug, trained_networks=True)
        # and the compiled trainer (issue 15) scores as the numpy one did, within the bands of a change of seed
        assert_trained_entries_close(document["entries"], slug)
    # every table as numbers
    tables = {t["key"]: t for t in document["tables"]}
    assert {"tactile.noise_scan", "tactile.friction_study", "tactile.actuated.estimators"} <= set(tables)
    assert all(isinstance(r[1], float) for r in tables["tactile.friction_study"]["rows"])
    # table 6.1 and 7.1 sample counts as printed (1275, 1500)
    assert entries["non_actuated.samples"]["status"] == "match"
    assert entries["actuated.samples"]["status"] == "match"
    for name in ("ch6-tactile-raw", "ch6-tactile-predicted-actual", "ch7-tactile-bound", "ch7-tactile-percent-error"):
        assert (tmp_path / "figures" / f"{name}.png").stat().st_size > 1000
    # the actuated noise revisited: the calibrated friction and its servo-angle reading are reported
    assert entries["actuated.cable_friction_ratio"]["ours"] > 0
    assert entries["actuated.cable_friction_equivalent_servo_deg"]["unit"] == "deg"
    assert "cable-guide friction" in entries["actuated.test_corr2_at_thesis_optimum"]["note"] or (
        entries["actuated.test_corr2_at_thesis_optimum"]["status"] == "match"
    )
    # the Bayes limits are reported; with the actuated noise no estimator pins every position (limit > 1 mm)
    assert entries["actuated.bayes_position_rmse_identifiable_mm"]["ours"] > 1.0
    assert 0.5 < entries["non_actuated.bayes_contact_accuracy_visible"]["ours"] <= 1.0

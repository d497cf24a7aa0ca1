"""The twin's report chapter builds (fast mode) and every comparison with the thesis is a match."""

import pytest

from flexdigit.report import CHAPTERS
from flexdigit.report.chapter import ReportContext
from oracles import assert_entries_unchanged

pytestmark = pytest.mark.blas  # run again under other OpenBLAS kernels by `make test` (docs/guide/reliability.md)


def test_twin_chapter_matches_the_thesis_figures(tmp_path):
    from flexdigit.report import ch3_twin

    assert "flexdigit.report.ch3_twin" in CHAPTERS
    chapter = ch3_twin.build(ReportContext(out_dir=tmp_path, fast=True))
    statuses = {e.key: e.status for e in chapter.entries}
    assert statuses["twin.release_with_housing.wn_rad_s"] == "match"  # table 3.2 within 3 %
    assert statuses["twin.release_without_housing.zeta"] == "match"  # table 3.1 within 3 %
    assert all(s in ("match", "new") for s in statuses.values()), statuses
    assert {f.thesis_ref for f in chapter.figures} == {"figure 3.6", "figure 3.12", "figure 3.17"}
    assert (tmp_path / "figures" / "twin_release_tests.png").stat().st_size > 10_000
    # issue 15 moved the chapter's computations into calibrate.studies: every entry as the baseline has it
    assert_entries_unchanged(chapter.entries, "ch3-twin")

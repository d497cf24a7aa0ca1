"""Report chapter 3 builds, saves its figures, and its key entries match the thesis where they should."""

import pytest

from flexdigit.report import ch3_models
from flexdigit.report.chapter import ReportContext


@pytest.fixture(scope="module")
def chapter(tmp_path_factory):
    out = tmp_path_factory.mktemp("ch3")
    return ch3_models.build(ReportContext(out_dir=out, fast=True)), out


def _entry(chapter, key):
    (entry,) = [e for e in chapter.entries if e.key == key]
    return entry


def test_plant_and_k2_entries_match_within_0p1_percent(chapter):
    ch, _ = chapter
    for key in ("plant.G.num", "plant.G.den[s^0]", "plant.G.poles[1].abs_error_rel", "cable.K2",
                "plant.closed_loop.poles[2].abs_error_rel"):  # fmt: skip
        e = _entry(ch, key)
        assert e.status == "match", key
        assert e.rel_error < 1e-3
    assert _entry(ch, "plant.G.num").ours == pytest.approx(48.7, rel=1e-3)  # 3.5


def test_release_table_entries(chapter):
    ch, _ = chapter
    assert _entry(ch, "table_3_2.zeta[1]").status == "match"
    garbled = _entry(ch, "table_3_2.zeta[2]")
    assert garbled.status == "discrepancy" and "80.5973" in garbled.note
    assert _entry(ch, "table_3_1.wn_from_wd_worst_rel").status == "discrepancy"


def test_table_3_4_and_explained_discrepancies(chapter):
    ch, _ = chapter
    assert _entry(ch, "table_3_4.y_sg3_mm.rows_equal").ours == 17.0
    y_max = _entry(ch, "table_3_4.y_max_mm[24]")
    assert y_max.status == "discrepancy" and "0.241" in y_max.note
    # every discrepancy carries an explanation, and the numbered list is in the chapter
    assert all(e.note for e in ch.entries if e.status == "discrepancy")
    assert any(p.startswith("1. Digit factor") for p in ch.paragraphs)


def test_figures_saved(chapter):
    ch, out = chapter
    refs = {f.thesis_ref for f in ch.figures}
    assert refs == {"figure 3.5", "figure 3.14", "figure 3.18"}
    for f in ch.figures:
        assert (out / "figures" / f"{f.name}.png").stat().st_size > 5000

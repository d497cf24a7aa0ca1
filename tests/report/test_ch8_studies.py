"""Report chapter 8 (beyond the thesis) builds from the studies' library results, fast."""

import pytest

from flexdigit.report import ch8_studies
from flexdigit.report.chapter import ReportContext

pytestmark = pytest.mark.blas  # run again under other OpenBLAS kernels by `make test` (docs/guide/reliability.md)


@pytest.fixture(scope="module")
def chapter(tmp_path_factory):
    out = tmp_path_factory.mktemp("ch8")
    return ch8_studies.build(ReportContext(out_dir=out, fast=True)), out


def test_sobol_entries_for_at_least_12_parameters(chapter):
    ch, out = chapter
    st = [e for e in ch.entries if e.key.startswith("studies.sobol.release_wn_rad_s.") and e.key.endswith(".ST")]
    assert len(st) >= 12
    by_name = {e.key.split(".", 3)[3].rsplit(".", 1)[0]: e.ours for e in st}
    # the strip's thickness enters EI as t^3 and dominates the housed frequency; the servo cannot move it
    assert max(by_name, key=by_name.get) in ("geometry.strip_thickness_m", "calibration.housing_ei_n_m2[*]")
    assert abs(by_name["actuator.servo_wn_rad_s"]) < 0.05
    assert (out / "figures" / "studies_sobol_total.png").exists()


def test_pareto_entries_mark_the_thesis_layout(chapter):
    ch, out = chapter
    keys = {e.key for e in ch.entries}
    assert "studies.design.thesis_layout.bayes_position_limit_mm" in keys
    thesis = next(e for e in ch.entries if e.key == "studies.design.thesis_layout.bayes_position_limit_mm")
    assert thesis.ours == pytest.approx(2.6, rel=0.2)  # chapter 6's Bayes limit on the thesis rig
    assert (out / "figures" / "studies_pareto.png").exists()
    assert all(e.status == "new" for e in ch.entries)

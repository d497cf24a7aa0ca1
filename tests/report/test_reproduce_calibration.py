"""``flexdigit reproduce --calibration FILE``: every chapter's twin runs on the user's calibration, and says so."""

import json
import sys
import types

import pytest

from flexdigit.cli import main
from flexdigit.report.chapter import Chapter
from flexdigit.report.results import new
from flexdigit.twin.calibration import packaged_calibration, save_calibration


@pytest.fixture
def probe_chapter(monkeypatch):
    """A chapter that records the calibration its twins get by default."""
    seen = {}

    def build(ctx):
        from flexdigit.twin import Twin

        seen["calibration"] = Twin(seed=0).calibration
        return Chapter(
            slug="probe", title="Probe", entries=[new("probe.gain", "3.4", seen["calibration"].channel_gain[0], "", "")]
        )

    module = types.ModuleType("fd_test_probe_chapter")
    module.build = build
    monkeypatch.setitem(sys.modules, "fd_test_probe_chapter", module)
    monkeypatch.setattr("flexdigit.report.build.CHAPTERS", ("fd_test_probe_chapter",))
    return seen


def test_reproduce_runs_every_chapter_on_the_given_calibration(tmp_path, probe_chapter, capsys):
    mine = packaged_calibration().replace(channel_gain=(0.2, 0.25, 0.3))
    path = save_calibration(mine, tmp_path / "mine.toml", {"source": "a test"})
    assert main(["reproduce", "--calibration", str(path), "--out", str(tmp_path / "report"), "--json"]) == 0
    assert probe_chapter["calibration"] == mine
    entries = json.loads((tmp_path / "report" / "results.json").read_text())["entries"]
    assert entries[0]["ours"] == 0.2
    assert f"twin calibration: {path}" in (tmp_path / "report" / "index.html").read_text()
    # and without the option, the packaged one
    assert main(["reproduce", "--out", str(tmp_path / "again"), "--json"]) == 0
    assert probe_chapter["calibration"] == packaged_calibration()
    assert "twin calibration: packaged" in (tmp_path / "again" / "index.html").read_text()


def test_a_bad_calibration_file_stops_reproduce_before_any_chapter(tmp_path, probe_chapter, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[calibration]\nstrip_beta_s = 1e-3\n")
    assert main(["reproduce", "--calibration", str(bad), "--out", str(tmp_path / "report")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "bad.toml: [calibration] lacks key" in err[0]
    assert probe_chapter == {}

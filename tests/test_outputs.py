"""Atomic, never-destructive writes on every command that writes (issue 16).

Each writer refuses an existing file unless --force, checks its directory before the work starts, and leaves the
old file untouched when the write fails (pyarrow used to delete it).
"""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main
from flexdigit.errors import OutputExistsError
from flexdigit.params import RigParams, save_params
from flexdigit.twin.twin import Twin


def _error(capsys) -> dict:
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(
    "argv",
    [
        ["params", "--write", "{out}"],
        ["simulate", "sweep", "--commands", "8,9", "--settle", "0.1", "--samples", "1", "--out", "{out}"],
        ["simulate", "step", "--duration", "0.2", "--rate", "100", "--out", "{out}"],
    ],
    ids=["params", "simulate-sweep", "simulate-step"],
)
def test_existing_outputs_are_refused_without_force(argv, tmp_path, capsys):
    out = tmp_path / ("rig.toml" if argv[0] == "params" else "x.parquet")
    out.write_bytes(b"precious")
    args = [a.replace("{out}", str(out)) for a in argv]
    assert main([*args, "--json"]) == 2
    doc = _error(capsys)
    assert doc["error_type"] == "OutputExistsError"
    assert "pass --force to overwrite it" in doc["error"]
    assert out.read_bytes() == b"precious"
    assert main([*args, "--force", "--json"]) == 0
    capsys.readouterr()
    assert out.read_bytes() != b"precious"


@pytest.mark.parametrize(
    "argv",
    [
        ["params", "--write", "{out}"],
        ["simulate", "release", "--duration", "8", "--out", "{out}"],
        ["collect", "thesis-6.1", "--out", "{out}"],
    ],
    ids=["params", "simulate", "collect"],
)
def test_a_missing_directory_is_refused_before_the_work(argv, tmp_path, capsys, work_must_not_start):
    out = tmp_path / "missing" / "x.parquet"
    # an 8 s release test or a 1275-reading collection is not run first: the twin never takes a step
    work_must_not_start(Twin, "advance")
    assert main([a.replace("{out}", str(out)) for a in argv]) == 2
    err = capsys.readouterr().err
    assert "missing" in err
    assert "the work started" not in err


def test_a_failed_parquet_write_keeps_the_old_file(tmp_path, monkeypatch):
    """pyarrow removes a file it failed to write; the atomic writer writes beside it, so the old one stays."""
    import pyarrow.parquet as pq

    from flexdigit.twin.records import servo_step_test

    out = tmp_path / "step.parquet"
    out.write_bytes(b"old results")
    record = servo_step_test(duration_s=0.1, sample_rate_hz=100)

    def broken(table, where, **kwargs):
        with open(where, "wb") as fh:
            fh.write(b"half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(pq, "write_table", broken)
    with pytest.raises(OSError, match="No space left"):
        record.save(out, force=True)
    assert out.read_bytes() == b"old results"
    assert [p.name for p in tmp_path.iterdir()] == ["step.parquet"]  # no temporary file left behind


def test_save_params_is_atomic_and_refuses_to_clobber(tmp_path):
    out = tmp_path / "rig.toml"
    save_params(RigParams(), out)
    with pytest.raises(OutputExistsError):
        save_params(RigParams(), out)
    save_params(RigParams(), out, force=True)
    assert "[geometry]" in out.read_text()


def test_reproduce_refuses_a_folder_that_holds_a_report(tmp_path, capsys, monkeypatch, work_must_not_start):
    (tmp_path / "results.json").write_text("[]")
    import flexdigit.report.build as build

    work_must_not_start(build, "_build_chapter")  # refused before any chapter is built
    assert main(["reproduce", "--out", str(tmp_path), "--fast", "--workers", "1", "--json"]) == 2
    error = _error(capsys)["error"]
    assert "already holds a report (results.json); pass --force" in error
    assert "the work started" not in error
    assert (tmp_path / "results.json").read_text() == "[]"
    monkeypatch.undo()  # the chapters build again
    from flexdigit.report.build import reproduce

    summary = reproduce(tmp_path, chapters=(), force=True)  # no chapter: an empty report, written over the old
    assert json.loads((tmp_path / "results.json").read_text())["entries"] == []
    assert summary.entries == 0
    assert (tmp_path / "index.html").exists()

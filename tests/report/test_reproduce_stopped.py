"""``flexdigit reproduce --force`` stopped by SIGTERM, SIGHUP or SIGINT (issue 22): the old report stays whole,
nothing of the new run is left (no figure, no ``.tmp`` file, no temporary folder), and a plain rerun writes a
report of one run. Before, the folder held the old index.html and results.json beside 19-34 of the new run's 52
figures, and ``.tmp`` files in figures/.

The command runs in a child process on two small chapters of this test's own (real figures, written by the
report's own ``save_figure``): the first blocks once its figure is written, until the signal comes, so the stop
lands mid-report every time."""

from __future__ import annotations

import json
import os
import signal
import sys

import pytest

from children import STOPS, start_code, stop, wait_until

CHAPTER = """
import os, time
import matplotlib.pyplot as plt
from flexdigit.report.chapter import Chapter
from flexdigit.report.results import new


def build(ctx):
    fig, ax = plt.subplots()
    ax.plot([0, 1], [{n}, 0])
    figure = ctx.save_figure(fig, "{name}_line", "a line")
    deadline = time.monotonic() + 120
    while os.environ.get("FD_BLOCK") == "{name}" and time.monotonic() < deadline:
        time.sleep(0.02)  # mid-report: the test sends its signal now
    return Chapter("{name}", "Chapter {name}", entries=[new("{name}.x", "1", {n}, "", "")], figures=[figure])
"""
#: ``flexdigit reproduce`` on this test's chapters (the report's list of chapters replaced, nothing else).
COMMAND = """
import sys
import flexdigit.report.build as build
build.CHAPTERS = ("fdstopa", "fdstopb")
from flexdigit.cli import main
sys.exit(main(["reproduce", *sys.argv[1:]]))
"""
OLD = {"index.html": "<p>the old report</p>", "results.json": '{"entries": "old"}', "figures/old_line.png": "png"}


@pytest.fixture
def chapters(tmp_path):
    src = tmp_path / "chapters"
    src.mkdir()
    for n, name in enumerate(("fdstopa", "fdstopb"), 1):
        (src / f"{name}.py").write_text(CHAPTER.format(name=name, n=n))
    return src


def _env(chapters, block=None):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(chapters), *sys.path]))  # workers import them by name
    env.pop("FD_BLOCK", None)
    if block:
        env["FD_BLOCK"] = block
    return env


def _tree(folder):
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.slow
@pytest.mark.parametrize("workers", ["1", "2"])
@pytest.mark.parametrize("signum, code", STOPS, ids=[s.name for s, _ in STOPS])
def test_a_stopped_reproduce_leaves_the_old_report_whole(tmp_path, chapters, signum, code, workers):
    out = tmp_path / "report"
    for name, text in OLD.items():
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        (out / name).write_text(text)
    (out / "notes.txt").write_text("the user's")  # not the report's: kept through it all
    before = _tree(out)
    argv = ["--out", out, "--force", "--workers", workers, "--json"]
    proc = start_code(COMMAND, *argv, env=_env(chapters, block="fdstopa"), cwd=tmp_path)

    # the first new figure is written (in the new report's temporary folder beside the old one)
    wait_until(lambda: any(p.suffix == ".png" for p in tmp_path.rglob("fdstopa_line.png")), proc)
    exit_code, result, err = stop(proc, signum)
    name = signal.Signals(signum).name
    assert exit_code == code, err
    assert result["signal"] == name
    assert result["error"] == f"interrupted by {name}"
    assert _tree(out) == before  # the old report, whole: no figure of the new run beside it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chapters", "report"]  # no temporary folder left
    assert not [p for p in tmp_path.rglob("*") if p.name.endswith(".tmp")]
    # a plain rerun: a report of one run (the old figure gone with the old report), the user's file kept
    proc = start_code(COMMAND, *argv, env=_env(chapters), cwd=tmp_path)
    out_text, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert json.loads(out_text)["entries"] == 2
    assert sorted(_tree(out)) == [
        "figures/fdstopa_line.png",
        "figures/fdstopb_line.png",
        "index.html",
        "notes.txt",
        "results.json",
    ]
    assert [e["key"] for e in json.loads((out / "results.json").read_text())["entries"]] == ["fdstopa.x", "fdstopb.x"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chapters", "report"]


def test_the_new_report_is_swapped_in_whole_keeping_the_users_files_and_a_link(tmp_path):
    from flexdigit.report.build import reproduce

    real = tmp_path / "real"
    for name, text in OLD.items():
        (real / name).parent.mkdir(parents=True, exist_ok=True)
        (real / name).write_text(text)
    (real / "notes.txt").write_text("the user's")
    (tmp_path / "report").symlink_to(real)
    reproduce(tmp_path / "report", chapters=(), force=True)  # no chapter: an empty report over the old one
    assert (tmp_path / "report").is_symlink()  # the link kept, the folder it points at swapped
    assert sorted(_tree(real)) == ["index.html", "notes.txt", "results.json"]  # the old figures gone with it
    assert json.loads((real / "results.json").read_text())["entries"] == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["real", "report"]  # no temporary folder left

"""``reproduce --workers`` beyond what the machine can run is refused saying the limit, before any chapter runs."""

import json

from flexdigit._system import worker_limit
from flexdigit.cli import main
from flexdigit.errors import ParameterError
from flexdigit.report.build import CHAPTER_BYTES, reproduce


def test_reproduce_refuses_more_workers_than_the_machine_runs(tmp_path, capsys):
    limit, why = worker_limit(CHAPTER_BYTES)
    assert main(["reproduce", "--out", str(tmp_path / "report"), "--fast", "--workers", "1000", "--json"]) == 2
    error = json.loads(capsys.readouterr().out)["error"]
    assert error.startswith("--workers 1000 is more than this machine can run at once")
    assert f"at most {limit} ({why})" in error
    assert not (tmp_path / "report").exists()


def test_the_library_refuses_them_too(tmp_path):
    limit, _ = worker_limit(CHAPTER_BYTES)
    try:
        reproduce(tmp_path / "report", chapters=(), workers=limit + 1)
    except ParameterError as exc:
        assert str(exc).startswith(f"workers {limit + 1} is more than this machine can run at once")
    else:
        raise AssertionError("reproduce ran with more workers than the machine can")

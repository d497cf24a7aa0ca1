"""``reproduce --workers`` beyond what the machine can run is refused saying the limit, before any chapter runs."""

import json
import re

from flexdigit._system import worker_limit
from flexdigit.cli import main
from flexdigit.errors import ParameterError
from flexdigit.report.build import CHAPTER_BYTES, reproduce


def test_reproduce_refuses_more_workers_than_the_machine_runs(tmp_path, capsys):
    limit, why = worker_limit(CHAPTER_BYTES)
    assert main(["reproduce", "--out", str(tmp_path / "report"), "--fast", "--workers", "1000", "--json"]) == 2
    error = json.loads(capsys.readouterr().out)["error"]
    assert error.startswith("--workers 1000 is more than this machine can run at once")
    # the limit and its reasons; the free memory is read again by the command, and other processes move it by a
    # few hundred MiB in between (21.1 GiB here, 21.0 there): its figure is compared to 0.5 GiB
    said = re.search(r"at most (\d+) \((.*) (\d+\.\d) GiB of memory free (.*)\)", error)
    expected = re.search(r"(.*) (\d+\.\d) GiB of memory free (.*)", why)
    if expected is None:  # the machine's free memory unknown: the cores alone
        assert f"at most {limit} ({why})" in error
        return
    assert said, (error, why)
    assert int(said.group(1)) == limit
    assert (said.group(2), said.group(4)) == (expected.group(1), expected.group(3))
    assert abs(float(said.group(3)) - float(expected.group(2))) <= 0.5
    assert not (tmp_path / "report").exists()


def test_the_library_refuses_them_too(tmp_path):
    limit, _ = worker_limit(CHAPTER_BYTES)
    try:
        reproduce(tmp_path / "report", chapters=(), workers=limit + 1)
    except ParameterError as exc:
        assert str(exc).startswith(f"workers {limit + 1} is more than this machine can run at once")
    else:
        raise AssertionError("reproduce ran with more workers than the machine can")

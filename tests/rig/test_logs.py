"""Loop logs never clobber and never mix (issue 16): an existing log is refused unless --append (a log of the same
format and settings: controller, period, rig) or --force; every field of a sample line is checked on reading."""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main
from flexdigit.errors import DataFileError, OutputExistsError
from flexdigit.rig.loop import run_loop
from flexdigit.rig.sample_log import read_log, read_log_runs

from .helpers import PI, FirstOrderRig


def _run(path, mode="new", period_s=0.02, rig=None):
    rig = rig or FirstOrderRig()
    return rig, run_loop(rig, PI(period_s=period_s), 1.0, 0.1, period_s, log_path=path, log_mode=mode)


def test_an_existing_log_is_refused_and_the_rig_left_safe(tmp_path):
    log = tmp_path / "run.jsonl"
    _run(log)
    before = log.read_bytes()
    rig = FirstOrderRig()
    rig.write_command(40)
    with pytest.raises(OutputExistsError, match="pass --force to overwrite it or --append"):
        _run(log, rig=rig)
    assert log.read_bytes() == before  # untouched
    assert rig.closed
    assert rig.sent[-1] == 8  # relaxed and closed although nothing ran


def test_append_adds_a_run_of_the_same_settings_and_refuses_another(tmp_path):
    log = tmp_path / "run.jsonl"
    _run(log)
    _run(log, "append")
    runs = read_log_runs(log)
    assert [start for start, *_ in runs] == [1, 8]
    assert all(len(samples) == 5 for _, _, samples, _ in runs)
    with pytest.raises(DataFileError, match="period_s=0.02, this run period_s=0.01"):
        _run(log, "append", period_s=0.01)
    assert len(read_log_runs(log)) == 2


def test_append_refuses_a_file_that_is_not_a_loop_log(tmp_path):
    other = tmp_path / "x.parquet"
    other.write_bytes(b"PAR1\x00\x01binary")
    with pytest.raises(DataFileError, match="x.parquet: not a flexdigit loop log"):
        _run(other, "append")
    assert other.read_bytes() == b"PAR1\x00\x01binary"


def test_append_after_a_crash_drops_the_torn_line_only(tmp_path):
    log = tmp_path / "run.jsonl"
    _run(log)
    log.write_text(log.read_text() + '{"k": 99, "t"')  # power cut mid-line
    _run(log, "append")
    assert len(read_log(log, run=1)[1]) == 5
    assert len(read_log(log, run=2)[1]) == 5


def test_force_replaces(tmp_path):
    log = tmp_path / "run.jsonl"
    _run(log)
    _run(log, "append")
    _run(log, "replace")
    assert len(read_log_runs(log)) == 1


def test_a_forced_run_that_stops_early_keeps_the_old_log_and_its_own_as_partial(tmp_path):
    """--force writes beside the old log; an interrupted run (Ctrl-C here) leaves the old log intact and its own
    record, footer included, in run.partial.jsonl (named in the result), never half of one over the other."""
    log = tmp_path / "run.jsonl"
    _run(log)
    old = log.read_bytes()

    class Interrupted(PI):
        def step(self, setpoint, reading):
            if getattr(self, "steps", 0) == 3:
                raise KeyboardInterrupt
            self.steps = getattr(self, "steps", 0) + 1
            return super().step(setpoint, reading)

    result = run_loop(FirstOrderRig(), Interrupted(), 1.0, 0.1, 0.02, log_path=log, log_mode="replace")
    assert result.status == "interrupted"
    assert log.read_bytes() == old
    partial = tmp_path / "run.partial.jsonl"
    assert result.log_path == partial
    assert "run.jsonl is kept as it was" in result.message
    header, samples, footer = read_log(partial)
    assert len(samples) == 3
    assert footer["stop"] == "interrupted"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.jsonl", "run.partial.jsonl"]


@pytest.mark.parametrize(
    "line, culprit",
    [
        ('{"k":0,"gauges_v":[0,0,0],"command":8}', "line 2: field 't' must be a number"),
        ('{"k":0,"t":"a","gauges_v":[0,0,0],"command":8}', "line 2: field 't' must be a number"),
        ('{"k":0,"t":0,"gauges_v":[],"command":8}', "line 2: field 'gauges_v' must be a list of 1 to 8"),
        ('{"k":0,"t":0,"gauges_v":[0,0,0,0,0,0,0,0,0],"command":8}', "field 'gauges_v' must be a list of 1 to 8"),
        ('{"k":0,"t":0,"gauges_v":[0,"a",0],"command":8}', "field 'gauges_v' must be a list of numbers"),
        ('{"k":0,"t":0,"gauges_v":[0,0,0],"command":255}', "field 'command' must be an integer 0..254"),
        ('{"k":0,"t":NaN,"gauges_v":[0,0,0],"command":8}', "line 2: field 't' must be a finite number"),
        ('{"k":0,"t":0,"gauges_v":[0,-Infinity,0],"command":8}', "field 'gauges_v' must be a list of finite"),
        ('{"k":0,"t":0,"y":1e999,"gauges_v":[0,0,0],"command":8}', "field 'y' must be a finite number"),
        ('{"k":0,"t":0,"gauges_v":[0,0,0]}', "field 'command' must be an integer 0..254"),
        ("[1, 2]", "line 2 is not a JSON object"),
    ],
)
def test_bad_sample_lines_name_the_line_and_field(tmp_path, line, culprit):
    """Issue 16: replay said "error: t" and "could not convert string to float: 'a'"."""
    log = tmp_path / "rec.jsonl"
    log.write_text('{"format": "flexdigit-loop-log/1"}\n' + line + "\n" + '{"stop": "completed"}\n')
    with pytest.raises(DataFileError, match=culprit.replace("[", r"\[")):
        read_log(log)


def test_binary_garbage_names_the_file(tmp_path):
    log = tmp_path / "rec.jsonl"
    log.write_bytes(b'{"format": "flexdigit-loop-log/1"}\n\xff\xfe\x00garbage\n')
    with pytest.raises(DataFileError, match=r"rec.jsonl: not a flexdigit loop log: binary or not UTF-8"):
        read_log(log)


@pytest.mark.slow
def test_run_cli_log_flags(tmp_path, capsys):
    cal, log = tmp_path / "cal.json", tmp_path / "run.jsonl"
    base = ["run", "--duration", "0.2", "--rotation-map", str(cal), "--log", str(log), "--json"]
    assert main(base) == 0
    capsys.readouterr()
    before = log.read_bytes()
    assert main(base) == 2  # refused before the rig is opened
    assert "pass --force to overwrite it or --append" in json.loads(capsys.readouterr().out)["error"]
    assert log.read_bytes() == before
    assert main([*base, "--append"]) == 0
    capsys.readouterr()
    assert len(read_log_runs(log)) == 2
    assert main([*base, "--append", "--seed", "4"]) == 2  # another twin seed: other settings, not the same log
    assert "rig_settings" in json.loads(capsys.readouterr().out)["error"]
    assert main([*base, "--force"]) == 0
    assert len(read_log_runs(log)) == 1
    capsys.readouterr()
    not_a_log = tmp_path / "x.parquet"
    not_a_log.write_bytes(b"PAR1")
    argv = ["run", "--duration", "0.2", "--rotation-map", str(cal), "--log", str(not_a_log), "--append"]
    assert main(argv) == 2
    assert "not a flexdigit loop log" in capsys.readouterr().err

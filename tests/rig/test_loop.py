"""The real-time loop on a virtual-time rig: deadlines, overruns, logging, and every fault ending in the safe state."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from flexdigit.errors import DataFileError, RigError
from flexdigit.rig.base import open_rig
from flexdigit.rig.loop import LoopSettings, run_loop
from flexdigit.rig.sample_log import read_log

from .helpers import PI, FirstOrderRig


def test_completed_run_tracks_and_logs_every_sample(tmp_path):
    rig = FirstOrderRig()
    log = tmp_path / "run.jsonl"
    result = run_loop(rig, PI(), setpoint=1.0, duration_s=2.0, period_s=0.02, log_path=log)
    assert result.ok
    assert result.timing.samples == 100
    assert result.timing.overruns == 0
    # virtual time: every sample exactly on its absolute deadline
    np.testing.assert_allclose(result.time_s, np.arange(100) * 0.02, atol=1e-12)
    assert result.timing.jitter_max_s < 1e-12
    assert result.timing.mean_period_s == pytest.approx(0.02)
    # PI with integral action: gauge 1 reaches the setpoint (first-order plant, closed-form steady state = r)
    assert result.measurement[-1] == pytest.approx(1.0, abs=0.05 * 1.0 + 0.05)  # within one command quantum (0.05 V)
    header, samples, footer = read_log(log)
    assert header["period_s"] == 0.02
    assert len(samples) == 100
    assert footer["stop"] == "completed"
    assert [s["command"] for s in samples] == list(result.command)
    assert rig.closed
    assert rig.sent[-1] == 8  # relaxed on the way out


def test_overrun_is_counted_and_deadlines_resync_without_bursting():
    rig = FirstOrderRig()

    class Slow(PI):
        def step(self, setpoint, reading):
            if reading.time_s == pytest.approx(0.2):  # sample 10 takes 2.5 periods
                rig.clock_.sleep(0.05)
            return super().step(setpoint, reading)

    result = run_loop(rig, Slow(), setpoint=0.5, duration_s=1.0, period_s=0.02)
    assert result.timing.overruns == 1
    # sample 10 ran at 0.20 and ended at 0.25: deadline 0.22 is skipped, the 0.24 sample runs late at 0.25, and
    # the one after keeps its absolute deadline 0.26 (no burst of catch-up samples, no drift to 0.27)
    i = int(np.argmin(np.abs(result.time_s - 0.2)))
    np.testing.assert_allclose(result.time_s[i : i + 3], [0.20, 0.25, 0.26])
    assert result.timing.samples == 50 - 1
    assert result.timing.jitter_max_s == pytest.approx(0.01)


def test_nan_gauge_is_a_sensor_fault(tmp_path):
    rig = FirstOrderRig(faults={7: lambda r: (np.array([0.0, math.nan, 0.0]), math.nan)})
    log = tmp_path / "nan.jsonl"
    result = run_loop(rig, PI(), setpoint=1.0, duration_s=1.0, log_path=log)
    assert result.status == "fault"
    assert "gauge 2 read nan" in result.message
    assert "relaxed to command 8" in result.message
    assert result.safe_command_sent
    assert rig.sent[-1] == 8
    assert rig.closed
    _, samples, footer = read_log(log)
    assert len(samples) == 6
    assert footer["stop"] == "fault"


def test_clipped_gauge_is_a_sensor_fault():
    rig = FirstOrderRig(faults={3: lambda r: (np.array([5.0, 0.0, 0.0]), math.nan)})
    result = run_loop(rig, PI(), setpoint=1.0, duration_s=1.0)
    assert result.status == "fault"
    assert "gauge 1 clipped at +5.000 V" in result.message
    assert rig.sent[-1] == 8


def test_ctrl_c_relaxes_closes_and_keeps_the_log(tmp_path):
    rig = FirstOrderRig()

    def interrupt(k, t, y, command):
        if k == 24:
            raise KeyboardInterrupt

    log = tmp_path / "ctrlc.jsonl"
    result = run_loop(rig, PI(), setpoint=1.0, duration_s=5.0, log_path=log, on_sample=interrupt)
    assert result.status == "interrupted"
    assert "Ctrl-C" in result.message
    assert str(log) in result.message
    assert rig.sent[-1] == 8
    assert rig.closed
    lines = log.read_text().splitlines()
    assert len(lines) == 1 + 25 + 1  # header, 25 samples (k = 0..24, each logged before the interrupt), footer
    assert all(json.loads(line) for line in lines)


def test_controller_bug_still_leaves_the_rig_safe():
    rig = FirstOrderRig()

    class Broken(PI):
        def step(self, setpoint, reading):
            raise ZeroDivisionError("oops")

    with pytest.raises(ZeroDivisionError):
        run_loop(rig, Broken(), setpoint=1.0, duration_s=1.0)
    assert rig.sent[-1] == 8
    assert rig.closed


def test_port_lost_mid_run(tmp_path):
    rig = FirstOrderRig(faults={12: lambda r: (_ for _ in ()).throw(RigError("first-order: port lost"))})
    result = run_loop(rig, PI(), setpoint=1.0, duration_s=1.0, log_path=tmp_path / "lost.jsonl")
    assert result.status == "fault"
    assert "port lost" in result.message
    assert rig.closed


def test_replay_reproduces_the_recorded_commands(tmp_path):
    log = tmp_path / "rec.jsonl"
    recorded = run_loop(FirstOrderRig(), PI(), setpoint=1.0, duration_s=1.0, log_path=log)
    replay = open_rig(f"replay://{log}")
    again = run_loop(replay, PI(), setpoint=1.0, duration_s=1.0, close_rig=False)
    # open-loop on the recorded gauges, the same deterministic controller gives the same commands
    np.testing.assert_array_equal(again.command, recorded.command)
    with pytest.raises(RigError, match="recording ends"):
        replay.wait(5.0)
        replay.read()


def test_a_log_that_is_not_a_log_is_refused(tmp_path):
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"hello": 1}\n')
    with pytest.raises(DataFileError, match="line 1"):
        read_log(bad)
    torn = tmp_path / "torn.jsonl"
    run_loop(FirstOrderRig(), PI(), setpoint=1.0, duration_s=0.1, log_path=torn)
    torn.write_text(torn.read_text() + '{"k": 99, "t"')  # a power cut mid-line
    header, samples, footer = read_log(torn)
    assert len(samples) == 5
    # a log a second run was appended to: read_log names the line it starts on (header + 5 + footer) unless asked
    # for one run
    twice = tmp_path / "twice.jsonl"
    for mode in ("new", "append"):
        run_loop(FirstOrderRig(), PI(), setpoint=1.0, duration_s=0.1, log_path=twice, log_mode=mode)
    with pytest.raises(DataFileError, match="line 8 starts a second run"):
        read_log(twice)
    assert len(read_log(twice, run=2)[1]) == 5


def test_realtime_priority_is_restored_or_untouched():
    import os

    from flexdigit.rig.loop import realtime_priority

    if not hasattr(os, "sched_getscheduler"):
        pytest.skip("no POSIX scheduling on this platform")
    before = os.sched_getscheduler(0)
    with realtime_priority() as rt:
        inside = os.sched_getscheduler(0)
        assert inside == (os.SCHED_FIFO if rt.active else before)
    assert os.sched_getscheduler(0) == before


def test_loop_settings_object_runs_as_the_keywords_do(tmp_path):
    settings = LoopSettings(period_s=0.04, log_path=tmp_path / "a.jsonl", header={"who": "settings"})
    by_settings = run_loop(FirstOrderRig(), PI(), 1.0, 1.0, settings=settings)
    by_keywords = run_loop(
        FirstOrderRig(), PI(), 1.0, 1.0, period_s=0.04, log_path=tmp_path / "b.jsonl", header={"who": "settings"}
    )
    assert by_settings.timing.samples == 25
    np.testing.assert_array_equal(by_settings.command, by_keywords.command)  # same virtual clock, same plant
    assert read_log(by_settings.log_path)[0]["who"] == "settings"


def test_a_keyword_beside_settings_overrides_its_field():
    result = run_loop(FirstOrderRig(), PI(), 1.0, 1.0, settings=LoopSettings(period_s=0.04), period_s=0.1)
    assert result.timing.samples == 10


def test_an_unknown_loop_keyword_is_refused_by_name():
    with pytest.raises(TypeError, match="'log_pth'"):
        run_loop(FirstOrderRig(), PI(), 1.0, 1.0, log_pth="x.jsonl")

"""LiveSession's loop is paced by the clock it is given (issue 23: the clock injected everywhere, as run_loop's)."""

import pytest

from flexdigit.live.session import LiveSession

PERIOD_S = 0.02


def test_the_loop_sleeps_to_its_deadlines_on_the_injected_clock():
    now = [100.0]  # a virtual monotonic clock that moves only when the loop sleeps
    sleeps = []

    def sleep(seconds):
        sleeps.append(seconds)
        now[0] += seconds
        if len(sleeps) == 5:
            session._stop.set()  # five periods, then the loop ends as a stop request ends it

    session = LiveSession("sim", period_s=PERIOD_S, seed=0, clock=lambda: now[0], sleep=sleep)
    try:
        session._run()
    finally:
        session.rig.close()
    # the first sample is due at once; every later one a period after the one before, on the virtual clock
    assert sleeps == pytest.approx([PERIOD_S] * 5, abs=1e-12)
    assert now[0] == pytest.approx(100.0 + 5 * PERIOD_S, abs=1e-12)


class _Submits:
    """Stands for the session's map worker: records what it is given, computes nothing."""

    def __init__(self):
        self.keys = []

    def submit(self, func, key):
        self.keys.append(key)


def test_the_locatability_map_waits_for_a_held_command_on_the_injected_clock():
    # the map is computed only for a command held half a second; that half second is the session's clock's
    # (it read time.monotonic, so a virtual clock never reached it and the wall clock did in tests)
    now = [100.0]
    session = LiveSession("sim", period_s=PERIOD_S, seed=0, clock=lambda: now[0], sleep=lambda s: None)
    try:
        session._loc_worker = worker = _Submits()
        assert session._locatability(20) is None
        now[0] += 0.4
        session._locatability(20)
        assert worker.keys == []  # held 0.4 s: not yet
        now[0] += 0.2
        session._locatability(20)
        assert worker.keys == [20]  # held 0.6 s on the virtual clock
    finally:
        session.rig.close()


def test_the_twin_is_paced_from_the_loops_start_its_start_taking_no_twin_time():
    # the session's start (the rotation map, the tare) computes for seconds of wall time; the twin is paced from
    # the loop's start, so those seconds are not simulated afterwards and the stream's time carries on from the
    # twin's (the tare's readings were of the twin at rest, in virtual time)
    now = [100.0]
    sleeps = []

    def sleep(seconds):
        sleeps.append(seconds)
        now[0] += seconds
        if len(sleeps) == 5:
            session._stop.set()

    session = LiveSession("sim", period_s=PERIOD_S, seed=0, clock=lambda: now[0], sleep=sleep)
    try:
        started_s = session.rig.twin.time_s
        now[0] += 30.0  # what the start cost on a loaded machine
        session._run()
        samples = session.snapshot(-1)["samples"]
        ended_s = session.rig.twin.time_s
    finally:
        session.rig.close()
    assert samples[0]["t"] == pytest.approx(started_s, abs=1e-9)  # the first frame: the twin where its start left it
    assert ended_s == pytest.approx(started_s + 5 * PERIOD_S, abs=1e-9)  # five periods simulated, not 30 s more

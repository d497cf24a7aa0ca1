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

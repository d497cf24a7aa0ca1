"""A paced simulation and the wall clock (:mod:`flexdigit.rig.pacing`, ``sim+paced``), on fake clocks: no test here
waits on the wall clock or times anything.

References: the fake clock's own arithmetic (a machine that needs ``SLOWNESS`` wall seconds per simulated second),
and the twin's time, which a held twin's start must not move on the wall clock's account.
"""

from __future__ import annotations

import pytest

from flexdigit.rig.backends.sim_backend import SimRig
from flexdigit.rig.loop import run_loop
from flexdigit.rig.pacing import WallPacer

from ..helpers import PI, FakeClock

#: Wall seconds the fake machine needs per simulated second: slower than real time.
SLOWNESS = 2.0
#: The page's frame, s: the wall time between two calls besides the simulating.
FRAME_S = 0.02
#: The bound on one call's catch-up, s.
CAP_S = 0.1
#: Float sums of a few dozen terms, s.
SUM_TOL_S = 1e-9


def _frames(pacer: WallPacer, frames: int) -> tuple[list[float], float, list[float], list[float]]:
    """``frames`` calls on a machine ``SLOWNESS`` x slower than real time: the time each call ran, the simulated
    time reached, the lag reported after each call and the lag the fake clock says (its time at the call on the
    simulation's axis, less the simulated time reached)."""
    wall, sim = [0.0], 0.0
    pacer.clock = lambda: wall[0]
    pacer.start(sim)
    runs, lags, behind = [], [], []
    for _ in range(frames):
        wall[0] += FRAME_S
        run = pacer.due(sim)
        sim += run
        behind.append(wall[0] - sim)
        wall[0] += SLOWNESS * run  # simulating it took longer than it simulated
        runs.append(run)
        lags.append(pacer.lag_s)
    return runs, sim, lags, behind


def test_without_a_bound_a_slow_machines_catch_up_grows_geometrically():
    # the failure the bound is for: each call runs a frame and what the one before it cost (SLOWNESS times what
    # it ran), r_n = FRAME_S + SLOWNESS r_(n-1): r_n = FRAME_S (SLOWNESS^n - 1) / (SLOWNESS - 1)
    runs, _, _, _ = _frames(WallPacer(), 12)
    assert runs[-1] == pytest.approx(FRAME_S * (SLOWNESS**12 - 1) / (SLOWNESS - 1), rel=1e-9)


def test_a_bounded_pacer_runs_at_most_its_bound_a_call_and_reports_the_lag():
    pacer = WallPacer(max_catch_up_s=CAP_S)
    runs, sim, lags, behind = _frames(pacer, 40)
    for k, run in enumerate(runs):
        assert run <= CAP_S + SUM_TOL_S, f"call {k} ran {run} s"
    # linear, not geometric: 0.02 s and 0.06 s (under the bound), then the bound every call
    assert sim == pytest.approx(0.08 + 38 * CAP_S, abs=SUM_TOL_S)
    # what was not run is reported, as far behind as the fake clock says, and growing while the machine is slow
    assert lags == pytest.approx(behind, abs=SUM_TOL_S)
    assert lags[-1] > lags[len(lags) // 2] > 0.0
    assert pacer.max_lag_s == pytest.approx(lags[-1], abs=SUM_TOL_S)


def test_a_bounded_pacer_catches_up_once_the_machine_is_fast_again():
    wall = [0.0]
    pacer = WallPacer(lambda: wall[0], max_catch_up_s=CAP_S)
    pacer.start(0.0)
    wall[0] = 0.35  # a stall of 0.35 s, then a machine that simulates in no time
    sim, runs = 0.0, []
    for _ in range(6):
        runs.append(pacer.due(sim))
        sim += runs[-1]
    assert runs == pytest.approx([CAP_S, CAP_S, CAP_S, 0.05, 0.0, 0.0], abs=SUM_TOL_S)  # made up, CAP_S a call
    assert pacer.lag_s == pytest.approx(0.0, abs=SUM_TOL_S)


def test_a_held_twin_runs_its_start_in_virtual_time_and_is_paced_from_there():
    clock = FakeClock()
    rig = SimRig(paced=True, start_paced=False, seed=0, clock=clock, sleep=clock.sleep)
    try:
        rig.wait(1.0)  # the start's waits (a tare at rest) step the twin, no wall time passes
        assert rig.twin.time_s == pytest.approx(1.0)
        assert clock.now == 0.0
        clock.sleep(30.0)  # the start computing (a map, a design) for 30 s of wall time
        assert rig.read().time_s == pytest.approx(1.0)  # not simulated afterwards to catch up
        rig.start_pacing()
        assert rig.twin.dynamics.compiled  # the kernel loading since opening was waited for, in virtual time
        clock.sleep(0.25)
        reading = rig.read()
        assert reading.time_s == pytest.approx(1.25)  # the wall clock's from the start, carrying on from the twin's
        assert rig.twin.time_s == pytest.approx(1.25)
        rig.wait(0.1)  # paced: the wait is the wall clock's
        assert clock.now == pytest.approx(30.35)
    finally:
        rig.close()


def test_a_held_twins_loop_is_paced_from_its_first_sample():
    """``run_loop`` starts a held twin's pacing (``flexdigit run --backend sim+paced`` opens it held): the 30 s the
    start computed are not simulated at the first sample, and the samples follow the wall clock from there."""
    clock = FakeClock()
    rig = SimRig(paced=True, start_paced=False, seed=0, clock=clock, sleep=clock.sleep)
    rig.wait(1.0)  # the start's waits at rest (a tare), in virtual time
    clock.sleep(30.0)  # the start computing (a map, a design) for 30 s of wall time
    result = run_loop(rig, PI(), 10.0, 0.2, 0.02, guard=False)
    assert result.status == "completed"
    assert result.time_s[0] == pytest.approx(0.0, abs=SUM_TOL_S)  # loop time from the first sample, at once
    # ten samples 20 ms apart on the wall clock, the twin carried on from its 1 s: not from 31 s
    assert rig.twin.time_s == pytest.approx(1.0 + 0.2, abs=0.02 + SUM_TOL_S)
    assert clock.now == pytest.approx(30.0 + 0.2, abs=0.02 + SUM_TOL_S)

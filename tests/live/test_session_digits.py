"""The live session on a digit of its own (issue 24, item 3's ``live --params``): the twin, the rotation map and
the controller built for that digit, as ``flexdigit run --params`` builds them, and a two-cable digit held below
straight (the antagonistic pair bends it the other way). Run on the loop's injected clock: the twin steps in
virtual time, no wall-clock wait. References: the twin's own tip rotation; the setpoint's sign."""

from __future__ import annotations

import numpy as np
import pytest

from digits import write_digit
from flexdigit.errors import ParameterError
from flexdigit.live.session import LiveSession, setpoint_range
from flexdigit.params import RigParams, load_params

PERIOD_S = 0.02
#: The held rotation's tolerance, deg: one servo command turns the tip 1.735 deg (the cable model, E 3.15), so a
#: controller holding a rotation between two commands dithers across that step; its 2 s mean is within about
#: half of it of the setpoint on the rotation map's estimate, plus the map's own error (~0.3 deg on the twin).
HOLD_TOL_DEG = 1.2


class VirtualClock:
    """The loop's clock and sleep: time moves only when the loop sleeps; after ``frames`` periods the loop is
    stopped as a stop request stops it. The twin's true tip rotation is noted at each of the last ``keep`` frames
    (in the loop's own thread, between its frames)."""

    def __init__(self, frames: int, keep: int) -> None:
        self.now, self.frames, self.keep = 0.0, frames, keep
        self.origin = 0.0  # the loop's start: the rig's waits while the session sets up come before it
        self.session: LiveSession | None = None
        self.true_deg: list[float] = []

    def clock(self) -> float:
        return self.now

    def sleep(self, dt: float) -> None:
        self.now += dt
        if self.session is None:  # the session setting up (its tare steps the twin in virtual time, not this)
            return
        k = int(round((self.now - self.origin) / PERIOD_S))
        if k > self.frames - self.keep:
            self.true_deg.append(self.session.rig.tip_rotation_deg())
        if k >= self.frames:
            self.session._stop.set()


@pytest.mark.slow
def test_a_two_cable_digit_is_held_below_straight(tmp_path):
    path = write_digit("four-sections-two-cables", tmp_path)
    params = load_params(path)
    virtual = VirtualClock(frames=int(6.0 / PERIOD_S), keep=int(2.0 / PERIOD_S))
    record = tmp_path / "pair.mcap"
    session = LiveSession(
        "sim", params=path, seed=0, period_s=PERIOD_S, clock=virtual.clock, sleep=virtual.sleep, record=record
    )
    virtual.session, virtual.origin = session, virtual.now
    try:
        hello = session.hello()
        assert hello["cables"] == 2
        assert hello["section_count"] == 4
        assert hello["digit_length_m"] == pytest.approx(0.36)
        assert len(hello["gauges_m"]) == 4
        assert hello["setpoint_range"][0] < -20 < 0 < hello["setpoint_range"][1]
        assert session.request({"type": "setpoint", "value": -20})["value"] == -20.0
        tared_s = session.rig.twin.time_s  # the twin's time when its start (the tare at rest) left it
        session._run()  # 6 s of the loop, in this thread, on the virtual clock
        samples = session.snapshot(-1)["samples"]
    finally:
        session.stop()
    # the tare waited out its 1 s window at rest on the twin in virtual time (tare_at_rest), and the stream's time
    # carries on from there (the twin is paced from the loop's start)
    assert tared_s >= 1.0
    assert samples[0]["t"] == pytest.approx(tared_s, abs=1e-4)  # as_dict rounds t to 0.1 ms
    assert len(samples[-1]["gauges_v"]) == 4
    assert samples[-1]["setpoint"] == -20.0
    last_2s = samples[-int(2.0 / PERIOD_S) :]
    # the second cable pulls: commands below the straight one (127), the tip turned the other way
    assert np.mean([s["command"] for s in last_2s]) < params.actuator.equilibrium_command - 5
    assert np.mean(virtual.true_deg) == pytest.approx(-20.0, abs=HOLD_TOL_DEG)
    assert np.mean([s["y"] for s in last_2s]) == pytest.approx(-20.0, abs=HOLD_TOL_DEG)
    # its recording replays as that digit: four gauges, the pair's range, without --params
    replay = LiveSession(f"replay://{record}")
    try:
        hello = replay.hello()
    finally:
        replay.rig.close()
    assert (len(hello["gauges_m"]), hello["section_count"], hello["cables"]) == (4, 4, 2)
    assert hello["setpoint_range"][0] < 0


def test_a_single_cable_setpoint_stays_at_or_above_straight_and_a_pair_takes_both_signs():
    single = RigParams()
    pair = RigParams.from_dict({"cables": {"count": 2, "pretension_n": 5.0}})
    assert setpoint_range(single, "deg") == (0.0, 45.0)  # the thesis page's slider, unchanged
    low, high = setpoint_range(pair, "deg")
    # 127 commands each way at 1.735 deg a command reach far past the slider's 45 deg: clipped to it both ways
    assert (low, high) == (-45.0, 45.0)
    # a pair whose straight command sits low reaches only 8 commands below it: 8 x 1.735 = 13.9 deg
    low_pair = RigParams.from_dict(
        {"cables": {"count": 2, "pretension_n": 5.0}, "actuator": {"equilibrium_command": 8}}
    )
    assert setpoint_range(low_pair, "deg")[0] == pytest.approx(-8 * 1.735, abs=0.01)


def test_a_bad_params_file_is_refused_naming_it(tmp_path):
    path = write_digit("two-sections", tmp_path, geometry={"gauge_positions_m": [0.055, 0.055]})
    with pytest.raises(ParameterError, match="two-sections.toml"):
        LiveSession("sim", params=path, seed=0)

"""Runaway and plausibility faults (issue 16): a loop driven by a wrong-signed or dead rotation map, or a gross gain
error, used to report "completed" while the twin's true rotation reached 119-411 deg. It now faults to the safe
state (command 8, port closed) with a message naming what it saw, and leaves a correct loop alone."""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main
from flexdigit.errors import RigError
from flexdigit.rig.safety import ROTATION_RANGE_DEG, RunawayGuard

LIMITS = (0.0, 254.0)


# -- the guard alone, on scripted samples (20 ms apart) -----------------------------------------------------------
def _feed(guard, samples, setpoint=30.0):
    """samples: (estimated_deg, requested, sent) per 20 ms; returns the time of the fault or None."""
    guard.reset(8)
    for k, (y, requested, sent) in enumerate(samples):
        t = 0.02 * k
        try:
            guard.check_rotation(t, y)
            guard.check_command(t, setpoint, y, requested, sent, LIMITS)
        except RigError:
            return t
    return None


def test_the_rotation_range_is_the_physical_one():
    low, high = ROTATION_RANGE_DEG
    assert _feed(RunawayGuard(), [(high, 20, 20)]) is None
    assert _feed(RunawayGuard(), [(high + 0.1, 20, 20)]) == 0
    assert _feed(RunawayGuard(), [(low - 0.1, 20, 20)]) == 0
    twin_says = RunawayGuard(truth=lambda: 151.0)  # the twin's true rotation counts, where it is known
    assert _feed(twin_says, [(10.0, 20, 20)]) == 0


def test_pulling_at_the_top_without_progress_faults_after_saturation_s():
    # the estimate moves the wrong way (sign-flipped map) or not at all while the command sits at 254
    stuck = [(0.0, 400, 254)] * 40
    assert _feed(RunawayGuard(unanswered_fraction=1.0), stuck) == pytest.approx(0.5)
    wrong_way = [(-0.5 * k, 400, 254) for k in range(40)]
    assert _feed(RunawayGuard(), wrong_way) == pytest.approx(0.06)  # error 30 -> 31.5 deg: grew past 1 deg


def test_saturation_with_progress_and_a_relaxed_bottom_are_not_faults():
    closing_in = [(min(1.5 * k, 29.0), 400, 254) for k in range(40)]  # saturated but the error shrinks
    assert _feed(RunawayGuard(), closing_in) is None
    unreachable_negative = [(0.5, -30, 0)] * 100  # the cable is slack at command 0: safe, not a runaway
    assert _feed(RunawayGuard(), unreachable_negative, setpoint=-60.0) is None


def test_a_command_the_estimate_does_not_follow_faults():
    dead_map = [(0.0, 8 + 2 * k, 8 + 2 * k) for k in range(60)]  # the command ramps, the estimate stays at 0
    t = _feed(RunawayGuard(), dead_map)
    # 10 % of 254 is crossed at command 34 (k = 13, 0.26 s); 0.5 s later it faults
    assert t == pytest.approx(0.26 + 0.5)


def test_bad_guard_settings_are_refused():
    with pytest.raises(ValueError, match="range_deg"):
        RunawayGuard(range_deg=(10, -10))
    with pytest.raises(ValueError, match="saturation_s"):
        RunawayGuard(saturation_s=0)


# -- flexdigit run on the twin: the reproductions of issue 16 ----------------------------------------------------
@pytest.fixture(scope="module")
def rotation_maps(tmp_path_factory):
    folder = tmp_path_factory.mktemp("maps")
    good = folder / "good.json"
    assert main(["run", "--duration", "0.1", "--rotation-map", str(good), "--json"]) == 0
    doc = json.loads(good.read_text())
    flipped = dict(doc, coef=[-c for c in doc["coef"]], intercept=-doc["intercept"])
    zero = dict(doc, coef=[0.0, 0.0, 0.0], intercept=0.0)
    # all but dead: 1e-4 of the good map's gain, so the estimate hardly moves (a zero map is refused on load)
    dead = dict(doc, coef=[1e-4 * c for c in doc["coef"]], intercept=0.0)
    maps = {"good": good}
    for name, content in (("flipped", flipped), ("zero", zero), ("dead", dead)):
        maps[name] = folder / f"{name}.json"
        maps[name].write_text(json.dumps(content))
    return maps


def _run(capsys, *argv):
    code = main(["run", "--duration", "3", "--json", *argv])
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(
    "which, extra, culprit",
    [
        ("flipped", [], "left the physical range"),
        ("dead", [], "does not follow the command"),
        # --gain 1e9 (saturating at once) is refused now by the flag's declared range; ten times the gain runs away
        ("good", ["--gain", "10"], "left the physical range"),
    ],
)
def test_runaways_fault_to_the_safe_state(rotation_maps, capsys, which, extra, culprit):
    code, data = _run(capsys, "--rotation-map", str(rotation_maps[which]), *extra)
    assert code == 1
    assert data["status"] == "fault"
    assert "runaway" in data["message"]
    assert culprit in data["message"]
    assert "digit relaxed to command 8" in data["message"]
    # it stopped before the twin's true rotation left the physical range (it reached 342-412 deg unguarded)
    assert data["true_peak_rotation_deg"] < ROTATION_RANGE_DEG[1]


def test_a_zero_map_is_refused_before_the_rig_moves(rotation_maps, capsys):
    """Issue 16's zero map: refused on load (by the map's own check) instead of run to a runaway."""
    code, data = _run(capsys, "--rotation-map", str(rotation_maps["zero"]))
    assert code == 2
    assert "read no rotation from the gauges" in data["error"]


@pytest.mark.parametrize("gain, setpoint", [(0.7, 30), (1.0, 30), (1.3, 30), (1.0, 120), (1.0, 0)])
def test_correct_loops_complete(rotation_maps, capsys, gain, setpoint):
    argv = ["--rotation-map", str(rotation_maps["good"]), "--gain", str(gain), "--setpoint-deg", str(setpoint)]
    code, data = _run(capsys, *argv)
    assert code == 0
    assert data["status"] == "completed"
    assert abs(data["true_final_rotation_deg"] - setpoint) < 2.0  # a quantum of the servo (1.7 deg)


# -- the library's run_loop: the same guard, on unless opted out (issues 22 and 23) -------------------------------
def _library_run(map_path, **loop_options):
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.controllers import make_controller
    from flexdigit.rig.loop import run_loop
    from flexdigit.rig.rotation import load_rotation_map

    rig = open_rig("sim")
    controller = make_controller("digital20", rig, estimator=load_rotation_map(map_path))
    truth = rig.tip_rotation_deg
    peak = []
    result = run_loop(rig, controller, 30.0, 3.0, on_sample=lambda *_: peak.append(truth()), **loop_options)
    return rig, result, max(peak)


def test_the_library_loop_guards_an_unstable_loop_by_default(rotation_maps):
    rig, result, peak = _library_run(rotation_maps["flipped"])  # no guard given: the default one
    assert result.status == "fault"
    assert "runaway" in result.message
    assert "left the physical range" in result.message
    assert result.safe_command_sent
    assert rig.closed
    assert "digit relaxed to command 8" in result.message
    assert peak < ROTATION_RANGE_DEG[1] + 5.0  # stopped within a sample of leaving the range (it went to 342+ deg)


def test_the_library_loop_runs_unguarded_only_when_told(rotation_maps):
    _, result, peak = _library_run(rotation_maps["flipped"], guard=False)  # the explicit opt-out
    assert result.status == "completed"
    assert peak > ROTATION_RANGE_DEG[1]  # what the guard is there for: the twin driven past its physical range
    with pytest.raises(ValueError, match="'guard' parameter of run_loop must be a RunawayGuard, True"):
        _library_run(rotation_maps["good"], guard=None)


def test_the_default_guard_leaves_loops_on_other_quantities_to_the_truth():
    # a loop whose measurement is not a rotation (gauge volts, a force) is judged by the twin's true rotation only
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.safety import default_guard

    rig = open_rig("sim")
    try:
        guard = default_guard(rig, measure=lambda reading: reading.gauges_v[0])
        assert not guard.measured
        assert guard.truth is not None
        guard.reset(8)
        guard.check_command(0.0, 30.0, float("nan"), 254.0, 254, LIMITS)  # nothing to judge: no fault
        guard.check_command(1.0, 30.0, float("nan"), 254.0, 254, LIMITS)
    finally:
        rig.close()

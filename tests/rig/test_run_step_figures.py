"""``flexdigit run --json``'s step figures against an independent computation from the logged samples.

The oracle below is written from docs/guide/rig.md's definitions only (not from ``control.analysis.step_figures``): rise
10-90 % of the step to the setpoint, 2 % settling about the setpoint and about the final value, overshoot beyond the
setpoint in percent of the step, steady-state error = mean of the last 0.5 s minus the setpoint (deg, and over the
rotation per command), IAE by the trapezoid rule; crossings interpolated between samples; the estimate averaged over
a centred 0.1 s window (5 samples at 20 ms, the ends repeating the first and last sample) before its figures are
taken. Where the record cannot show a figure (a run shorter than the settling, a loop that never settles, a zero
setpoint, a fault) the JSON must say null, never a plausible number: a settling time needs the last 0.5 s of the
record inside the band, a steady state needs the last 0.5 s within 2 % of the step of its own mean.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.rig.sample_log import read_log

#: docs/guide/rig.md's settling band and final window
BAND, WINDOW_S, SMOOTH_SAMPLES = 0.02, 0.5, 5


def centred_mean(y: np.ndarray, n: int) -> np.ndarray:
    padded = np.concatenate([np.full(n // 2, y[0]), y, np.full(n // 2, y[-1])])
    return np.array([padded[i : i + n].mean() for i in range(y.size)])


def first_time_at(t, z, level) -> float:
    for i, value in enumerate(z):
        if value >= level:
            return t[0] if i == 0 else t[i - 1] + (t[i] - t[i - 1]) * (level - z[i - 1]) / (value - z[i - 1])
    return math.inf


def enters_band_for_good(t, error, band) -> float:
    outside = [i for i, e in enumerate(error) if e > band]
    if not outside:
        return 0.0
    i = outside[-1]
    if i == len(t) - 1:
        return math.inf
    return t[i] + (t[i + 1] - t[i]) * (error[i] - band) / (error[i] - error[i + 1])


def oracle(t, y_raw, setpoint, deg_per_command, smooth: bool) -> dict:
    y = centred_mean(y_raw, SMOOTH_SAMPLES) if smooth else y_raw
    tail = t >= t[-1] - WINDOW_S
    iae = sum(0.5 * (abs(setpoint - y[i]) + abs(setpoint - y[i + 1])) * (t[i + 1] - t[i]) for i in range(t.size - 1))
    out = {"iae_deg_s": iae}
    steady = bool(np.all(np.abs(y[tail] - y[tail].mean()) <= BAND * abs(setpoint))) if setpoint else True
    error = y_raw[tail].mean() - setpoint if steady else math.nan
    out |= {"final_error_deg": error, "final_error_commands": error / deg_per_command}
    if setpoint == 0:
        return out | dict.fromkeys(("rise_time_s", "settling_time_s", "settling_to_final_s", "overshoot_percent"))
    z = y / setpoint
    settling = enters_band_for_good(t, np.abs(z - 1), BAND)
    return out | {
        "rise_time_s": first_time_at(t, z, 0.9) - first_time_at(t, z, 0.1),
        "settling_time_s": settling if settling <= t[-1] - WINDOW_S else math.inf,
        "settling_to_final_s": enters_band_for_good(t, np.abs(y - y[tail].mean()) / abs(setpoint), BAND)
        if steady
        else math.inf,
        "overshoot_percent": max(0.0, (z.max() - 1) * 100),
    }


def assert_figures_agree(ours: dict, json_figures: dict) -> None:
    for key, value in ours.items():
        reported = json_figures[key]
        if value is None or not math.isfinite(value):
            assert reported is None, (key, reported)  # undefined or never: null in the JSON
        else:
            assert reported == pytest.approx(value, rel=1e-9, abs=1e-12), key


@pytest.fixture(scope="module")
def rotation_map(tmp_path_factory):
    path = tmp_path_factory.mktemp("map") / "map.json"
    assert main(["run", "--duration", "0.02", "--rotation-map", str(path), "--json"]) == 0
    return path


def run_json(capsys, *argv) -> dict:
    main(["run", "--json", *argv])
    return json.loads(capsys.readouterr().out)


def logged(path):
    _, samples, footer = read_log(path)
    return np.array([s["t"] for s in samples]), np.array([s["y"] for s in samples], dtype=float), footer


@pytest.mark.slow
@pytest.mark.parametrize(
    ("controller", "setpoint", "duration", "settles"),
    [
        ("digital20", 20.0, 2.0, True),  # docs/guide/rig.md's example
        ("digital20", 30.0, 0.9, False),  # stopped before the digit settled
        ("digital20", 0.0, 1.0, None),  # a zero setpoint: no step to rise, settle or overshoot
        ("thesis39-euler", 30.0, 2.0, False),  # the thesis controller at 20 ms: runs away, faults at 0.24 s
    ],
)
def test_run_json_step_figures_match_an_independent_computation(
    tmp_path, capsys, rotation_map, controller, setpoint, duration, settles
):
    log = tmp_path / "run.jsonl"
    data = run_json(capsys, "--controller", controller, "--setpoint-deg", str(setpoint), "--duration", str(duration),
                    "--rotation-map", str(rotation_map), "--log", str(log))  # fmt: skip
    t, y, footer = logged(log)
    figures = data["step_metrics"]
    assert figures["settling_band"] == BAND
    assert figures["estimate_smoothed_s"] == 0.1
    ours = oracle(t, y, setpoint, figures["deg_per_command"], smooth=True)
    assert_figures_agree(ours, figures["estimated"])
    assert footer["summary"]["estimated"] == figures["estimated"]  # the log closes with the same figures
    true = figures["true"]
    if settles:
        assert 0.3 < true["settling_time_s"] < 1.2
        assert abs(true["final_error_deg"]) < 0.87  # half a command
    elif settles is False:
        assert true["settling_time_s"] is None
        assert true["final_error_deg"] is None
    else:  # zero setpoint: the digit stays at rest, so its error and IAE are zero and the rest undefined
        assert true["final_error_deg"] == 0.0
        assert true["iae_deg_s"] == 0.0
        assert true["rise_time_s"] is None


@pytest.mark.slow
def test_a_run_that_faults_before_settling_claims_no_settling(tmp_path, capsys, rotation_map):
    log = tmp_path / "run.jsonl"
    run_json(capsys, "--setpoint-deg", "30", "--duration", "2", "--rotation-map", str(rotation_map), "--log", str(log))
    lines = log.read_text().splitlines()
    cut = tmp_path / "cut.jsonl"  # the recording stops at 0.88 s (a crash), mid-settling; replaying it faults there
    cut.write_text("\n".join(lines[:46]) + "\n")
    replay = tmp_path / "replay.jsonl"
    data = run_json(capsys, "--backend", f"replay://{cut}", "--setpoint-deg", "30", "--duration", "2",
                    "--rotation-map", str(rotation_map), "--log", str(replay))  # fmt: skip
    assert data["status"] == "fault"
    assert "recording ends" in data["message"]
    t, y, _ = logged(replay)
    assert t[-1] == pytest.approx(0.88)
    figures = data["step_metrics"]["estimated"]
    assert_figures_agree(oracle(t, y, 30.0, data["step_metrics"]["deg_per_command"], smooth=True), figures)
    assert figures["settling_time_s"] is None
    assert figures["final_error_deg"] is None
    assert figures["rise_time_s"] is not None
    assert figures["iae_deg_s"] > 0


def test_a_one_sample_run_ends_cleanly_with_its_log_closed(tmp_path, capsys, rotation_map):
    log = tmp_path / "one.jsonl"
    data = run_json(capsys, "--duration", "0.02", "--rotation-map", str(rotation_map), "--log", str(log))
    assert data["status"] == "completed"
    assert data["samples"] == 1
    assert data["step_metrics"]["estimated"] is None
    _, samples, footer = read_log(log)
    assert len(samples) == 1
    assert footer["stop"] == "completed"

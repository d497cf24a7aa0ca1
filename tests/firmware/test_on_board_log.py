"""``flexdigit run --on-board --log L.jsonl --plot P.png`` (issue 25, item 4): the host watching a loop closed on
the board keeps what it watched as a host run's log and figure.

References: the run's own ``--json`` (its ``samples`` and true final rotation come from the same watched periods,
summed and averaged in the library: the log must hold those periods, not others), and the loop log's format
(:mod:`flexdigit.rig.sample_log`: read back by :func:`read_log`, which refuses what the loop does not write).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.rig.sample_log import read_log
from flexdigit.rig.step_test import FINAL_WINDOW_S

#: The log's floats are the run's, through JSON (repr: exact) and one mean over the final window: equal up to the
#: mean's summation order.
SAME_RTOL = 1e-12
#: The board's estimate against the twin's true rotation, settled at 20 deg, deg: the map's fit residual on the
#: twin (~0.05 deg), the 10-bit readings (~0.1 deg a count through the map) and the tare: half a degree is generous
#: and still tells an estimate from a missing or misplaced field (0, or the command: tens).
MAP_AGREEMENT_DEG = 0.5


@pytest.mark.slow
def test_run_on_board_logs_and_plots_what_the_host_watched(firmware, tmp_path, capsys, drawn):
    elf = firmware(0.020, "float")
    log, plot = tmp_path / "board.jsonl", tmp_path / "board.png"
    argv = ["run", "--on-board", "--backend", f"hil://{elf}", "--duration", "1.2", "--setpoint-deg", "20"]
    assert main([*argv, "--log", str(log), "--plot", str(plot), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["log"] == str(log)
    assert doc["plot"] == str(plot)

    header, samples, footer = read_log(log)  # the loop log's own reader takes it
    assert header["loop"] == "board"
    assert header["backend"] == f"hil://{elf}"
    assert header["period_s"] == pytest.approx(0.020)
    assert header["image_format"] == "float"
    assert footer["stop"] == "completed"
    assert len(samples) == doc["samples"] == 60  # 1.2 s of 20 ms periods
    t = np.array([s["t"] for s in samples])
    truth = np.array([s["true_rotation_deg"] for s in samples])
    final = truth[t >= t[-1] - FINAL_WINDOW_S].mean()
    assert final == pytest.approx(doc["true_final_rotation_deg"], rel=SAME_RTOL)
    assert all(len(s["gauges_v"]) == 3 for s in samples)
    # the board's own estimate (streamed since issue 24 item 5; tests/firmware/test_board_estimate.py holds it to
    # the Python map): the twin's true rotation within the map's error once settled, not the null of before
    y = np.array([s["y"] for s in samples], dtype=float)
    assert np.all(np.isfinite(y))
    assert abs(y[t >= t[-1] - FINAL_WINDOW_S].mean() - final) < MAP_AGREEMENT_DEG
    assert doc["estimated_final_rotation_deg"] == pytest.approx(y[t >= t[-1] - FINAL_WINDOW_S].mean(), rel=SAME_RTOL)
    # the servo pulse the board generated, in commands, and its nearest serial command
    pulses = np.array([s["board_command"] for s in samples])
    assert doc["final_command"] == pytest.approx(pulses[-1], rel=SAME_RTOL)
    assert np.all(np.abs(np.array([s["command"] for s in samples]) - pulses) <= 0.5)
    assert truth[-1] > 15.0  # the board moved the twin towards 20 deg

    assert plot.read_bytes().startswith(b"\x89PNG")
    rotation_ax, command_ax = drawn[0].axes
    lines = {line.get_label(): line for line in rotation_ax.get_lines()}
    assert {"setpoint", "true rotation (twin)", "estimate (gauges)"} <= set(lines)
    np.testing.assert_allclose(lines["true rotation (twin)"].get_ydata(), truth, rtol=SAME_RTOL)
    np.testing.assert_allclose(lines["estimate (gauges)"].get_ydata(), y, rtol=SAME_RTOL)
    np.testing.assert_allclose(command_ax.get_lines()[0].get_ydata(), pulses, rtol=SAME_RTOL)

    # never over a file without --force; with it, the log is replaced by the new run's
    assert main([*argv, "--log", str(log)]) == 2
    assert "--force" in capsys.readouterr().err
    assert main([*argv, "--log", str(log), "--force", "--orientation", "horizontal", "--json"]) == 0
    assert len(read_log(log)[1]) == 60
    # --orientation reaches the twin the board meets (no longer refused): the log's settings say so
    assert read_log(log)[0]["rig_settings"]["orientation"] == "horizontal"


def test_run_on_board_refuses_only_what_cannot_apply(tmp_path, capsys):
    board = ["run", "--on-board", "--backend", "hil://nowhere.elf"]
    assert main([*board, "--rotation-map", str(tmp_path / "m.json")]) == 2
    assert "the board holds its map" in capsys.readouterr().err
    design = tmp_path / "design.json"
    design.write_text("{}")
    assert main([*board, "--controller", str(design)]) == 2
    assert "exported into its image" in capsys.readouterr().err

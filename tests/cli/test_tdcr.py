"""``flexdigit tdcr statics``: the rao2021 tip through the command line, JSON, and bad input in one line."""

import json

import numpy as np
import pytest

from flexdigit.cli import main

RAO_TIP_M = np.array([127.6, 143.5, 336.4]) * 1e-3  # tdcr-modeling's Cosserat model (see test_statics.py)
RAO_ATOL_M = 1e-3


def test_statics_json_gives_the_tip_and_the_backbone(capsys):
    assert main(["tdcr", "statics", "rao2021", "--tension-n", "4,0,0,0,2,0", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["converged"] is True
    np.testing.assert_allclose(data["tip_position_m"], RAO_TIP_M, atol=RAO_ATOL_M)
    frame = np.array(data["tip_frame"])
    np.testing.assert_allclose(frame[:3, 3], data["tip_position_m"])
    np.testing.assert_allclose(frame[:3, :3].T @ frame[:3, :3], np.eye(3), atol=1e-7)  # RK4 drift ~1e-8
    backbone = np.array(data["backbone_m"])
    assert backbone.shape == (21, 3)
    assert np.allclose(backbone[0], 0.0)
    np.testing.assert_allclose(backbone[-1], data["tip_position_m"])


def test_statics_from_a_file_with_tip_loads(tmp_path, capsys):
    path = tmp_path / "one.toml"
    path.write_text("[[segments]]\nlength_m = 0.2\ndisk_count = 10\n[[tendons]]\noffset_m = 0.01\ndisk = 10\n")
    argv = ["tdcr", "statics", str(path), "--tension-n", "1", "--tip-force-n=-0.01,0,0", "--tip-moment-nm", "0,0,0"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "tip position" in text
    assert "converged: True" in text


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["rao2021", "--tension-n", "4,0,0"], "--tension-n must give one tension per tendon of 'rao2021' (6"),
        (["rao2021", "--tension-n", "4,x,0,0,2,0"], "--tension-n must be comma-separated numbers"),
        (["rao2021", "--tension-n", "4,0,0,0,2,0", "--tip-force-n", "1,2"], "--tip-force-n must be 3"),
        (["rao2021", "--tension-n=-1,0,0,0,2,0"], "'tensions_n' parameter"),
        (["rao2022", "--tension-n", "1"], "unknown robot 'rao2022'"),
        (["missing.toml", "--tension-n", "1"], "no such file: missing.toml"),
    ],
)
def test_bad_input_is_one_json_error(argv, needle, capsys):
    assert main(["tdcr", "statics", *argv, "--json"]) == 2
    captured = capsys.readouterr()
    error = json.loads(captured.out)
    assert needle in error["error"]
    assert error["exit_code"] == 2
    assert captured.err.count("\n") == 1


def test_dynamics_json_gives_the_tip_path(capsys):
    # rao2021 pulled from straight by tendons 1 and 5 at t = 0: it swings towards (and about) its static shape
    argv = ["tdcr", "dynamics", "rao2021", "--tension-n", "4,0,0,0,2,0", "--dt-s", "0.005", "--duration-s", "0.5"]
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["converged"] is True
    tip = np.array(data["tip_position_m"])
    assert tip.shape == (101, 3)
    assert len(data["t_s"]) == 101
    np.testing.assert_allclose(tip[0], [0.0, 0.0, 0.4], atol=1e-9)  # from rest, straight
    # undamped, it overshoots its static tip: the path reaches past it along the static tip's direction
    reach = tip @ RAO_TIP_M / np.linalg.norm(RAO_TIP_M)
    assert reach.max() > np.linalg.norm(RAO_TIP_M) - RAO_ATOL_M


def test_dynamics_refuses_a_wrong_initial_tension_count(capsys):
    argv = ["tdcr", "dynamics", "rao2021", "--tension-n", "0,0,0,0,0,0", "--from-tension-n", "1,0", "--json"]
    assert main(argv) == 2
    assert "--from-tension-n must give one tension per tendon" in json.loads(capsys.readouterr().out)["error"]


def test_dynamics_by_either_method_holds_rao2021_at_rest(capsys):
    """Either method, started at rest in the static shape under the same tensions, stays there (the discrete rod in
    its own equilibrium, which it settles in before t = 0)."""
    for method in ("discrete", "shooting"):
        argv = ["tdcr", "dynamics", "rao2021", "--tension-n", "4,0,0,0,2,0", "--from-tension-n", "4,0,0,0,2,0"]
        assert main([*argv, "--duration-s", "0.005", "--method", method, "--json"]) == 0
        data = json.loads(capsys.readouterr().out)
        tip = np.array(data["tip_position_m"])
        assert data["method"] == method
        assert np.abs(tip - tip[0]).max() < 1e-9

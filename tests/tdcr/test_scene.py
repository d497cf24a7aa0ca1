"""3D recordings of a tendon robot: read back with the ``mcap`` library's own reader, every ``/tdcr/scene``
message validated against Foxglove's published ``foxglove.SceneUpdate`` JSON Schema (tests/data/foxglove, copied
from foxglove-sdk; see its README), and, stricter than that schema, with no field Foxglove does not define.
"""

import copy
import json
import math
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from mcap.reader import make_reader

from flexdigit.cli import main
from flexdigit.tdcr import ROBOTS, Robot, Segment, scene_update, solve_statics, write_recording
from flexdigit.tdcr.dynamics import simulate

FOXGLOVE_SCHEMA = json.loads((Path(__file__).parents[1] / "data" / "foxglove" / "SceneUpdate.json").read_text())
TENSIONS = [4.0, 0.0, 0.0, 0.0, 2.0, 0.0]
GEOMETRY_ATOL = 1e-12  # m: positions go through JSON's shortest round-trip repr of floats, exact to the last bit


def _closed(schema):
    """The schema with ``additionalProperties: false`` on every object that lists its properties."""
    schema = copy.deepcopy(schema)

    def walk(node):
        if isinstance(node, dict):
            if "properties" in node:
                node["additionalProperties"] = False
            for value in node.values():
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)

    walk(schema)
    return schema


VALIDATORS = [jsonschema.Draft202012Validator(s) for s in (FOXGLOVE_SCHEMA, _closed(FOXGLOVE_SCHEMA))]


def _read(path):
    with open(path, "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        out = {}
        for schema, channel, message in reader.iter_messages():
            out.setdefault(channel.topic, []).append((schema, channel, message, json.loads(message.data)))
    return summary, out


def _check_scene(messages):
    for schema, channel, _, update in messages:
        assert (schema.name, schema.encoding) == ("foxglove.SceneUpdate", "jsonschema")
        assert channel.message_encoding == "json"
        for validator in VALIDATORS:
            validator.validate(update)


def test_a_static_recording_validates_and_draws_the_solution(tmp_path):
    robot = ROBOTS["rao2021"]
    tip_force = [0.0, 0.1, 0.0]
    sol = solve_statics(robot, TENSIONS, tip_force_n=tip_force)
    path = write_recording(tmp_path / "rao.mcap", robot, sol, tensions_n=TENSIONS, tip_force_n=tip_force)
    _, topics = _read(path)
    assert len(topics["/tdcr/scene"]) == 1
    assert len(topics["/tdcr/tip"]) == 1
    _check_scene(topics["/tdcr/scene"])
    update = topics["/tdcr/scene"][0][3]
    entities = {e["id"]: e for e in update["entities"]}
    assert {e["frame_id"] for e in entities.values()} == {"tdcr_base"}
    backbone = entities["backbone"]["lines"][0]
    points = np.array([[p["x"], p["y"], p["z"]] for p in backbone["points"]])
    np.testing.assert_allclose(points, sol.positions_m, atol=GEOMETRY_ATOL)
    # one arrow per tendon that pulls, at its termination, pointing along it towards the base, 10 mm per newton
    arrows = entities["tensions"]["arrows"]
    assert len(arrows) == 2
    for arrow, k in zip(arrows, (0, 4), strict=True):
        q = arrow["pose"]["orientation"]
        w, v = q["w"], np.array([q["x"], q["y"], q["z"]])
        assert w * w + v @ v == pytest.approx(1.0, abs=1e-12)
        direction = (w * w - v @ v) * np.array([1.0, 0, 0]) + 2 * v[0] * v + 2 * w * np.cross(v, [1.0, 0, 0])
        end = robot.tendons[k].disk
        assert direction @ sol.rotations[end][:, 2] < -0.99  # against the backbone's tangent
        assert arrow["shaft_length"] + arrow["head_length"] == pytest.approx(TENSIONS[k] * 0.01)
    (load,) = entities["loads"]["arrows"]
    tail = load["pose"]["position"]
    np.testing.assert_allclose([tail["x"], tail["y"], tail["z"]], sol.tip_position_m, atol=GEOMETRY_ATOL)
    tip = topics["/tdcr/tip"][0][3]
    np.testing.assert_allclose(tip["position_m"], sol.tip_position_m, atol=GEOMETRY_ATOL)


def test_a_time_response_is_one_update_per_step(tmp_path):
    rod = Robot(name="rod", segments=(Segment(0.4, 20),))
    bent = solve_statics(rod, [], tip_force_n=[0.01, 0.0, 0.0])
    motion = simulate(rod, bent, 0.02, dt_s=2e-3)  # the step test_dynamics uses (w1 dt ~ 0.045)
    assert motion.converged
    path = write_recording(tmp_path / "rod.mcap", rod, motion, tensions_n=[])
    summary, topics = _read(path)
    scene = topics["/tdcr/scene"]
    assert len(scene) == len(motion.t_s) == 11
    _check_scene(scene)
    stamps = [m.log_time for _, _, m, _ in scene]
    assert stamps == [round(t * 1e9) for t in motion.t_s]
    for (_, _, _, update), positions in zip(scene, motion.positions_m, strict=True):
        line = update["entities"][0]["lines"][0]["points"]
        np.testing.assert_allclose([[p["x"], p["y"], p["z"]] for p in line], positions, atol=GEOMETRY_ATOL)
    assert summary.statistics.message_count == 22


def test_the_cli_records_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "s.mcap"
    assert main(["tdcr", "statics", "rao2021", "--tension-n", "4,0,0,0,2,0", "--record", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["recording"] == str(out)
    _, topics = _read(out)
    _check_scene(topics["/tdcr/scene"])
    tip = topics["/tdcr/tip"][0][3]["position_m"]
    assert [round(c * 1e3, 1) for c in tip] == [127.6, 143.5, 336.4]  # tdcr-modeling's Cosserat tip (issue 26)
    before = out.read_bytes()
    code = main(["tdcr", "statics", "rao2021", "--tension-n", "0,0,0,0,0,0", "--record", str(out)])
    err = capsys.readouterr().err
    assert code != 0
    assert "exists" in err
    assert len(err.strip().splitlines()) == 1
    assert out.read_bytes() == before
    assert main(["tdcr", "statics", "rao2021", "--tension-n", "0,0,0,0,0,0", "--record", str(out), "--force"]) == 0
    _, topics = _read(out)
    assert math.isclose(topics["/tdcr/tip"][0][3]["position_m"][2], 0.4, rel_tol=1e-9)


def test_the_validation_can_fail():
    """The schema check is not vacuous: a wrong enum value, a missing colour channel and a stray key are caught."""
    robot = ROBOTS["rao2021"]
    sol = solve_statics(robot, TENSIONS)
    good = scene_update(robot, sol.positions_m, sol.rotations, tensions_n=TENSIONS)
    for validator in VALIDATORS:
        validator.validate(good)
    bad_type, bad_color, stray = copy.deepcopy(good), copy.deepcopy(good), copy.deepcopy(good)
    bad_type["entities"][0]["lines"][0]["type"] = 5
    del bad_color["entities"][2]["arrows"][0]["color"]["a"]
    stray["entities"][0]["lines"][0]["width"] = 1.0
    for message in (bad_type, bad_color):
        assert not VALIDATORS[0].is_valid(message)
    assert VALIDATORS[0].is_valid(stray)
    assert not VALIDATORS[1].is_valid(stray)


def test_the_dynamics_cli_records_every_step(tmp_path, capsys):
    out = tmp_path / "d.mcap"
    held = ["--from-tension-n", "4,0,0,0,2,0", "--tension-n", "4,0,0,0,2,0"]  # at rest: a static shape held
    args = ["tdcr", "dynamics", "rao2021", *held, "--duration-s", "0.005", "--record", str(out), "--json"]
    assert main(args) == 0
    data = json.loads(capsys.readouterr().out)
    _, topics = _read(out)
    assert len(topics["/tdcr/scene"]) == len(data["t_s"]) == 6
    _check_scene(topics["/tdcr/scene"])
    tips = np.array([m[3]["position_m"] for m in topics["/tdcr/tip"]])
    np.testing.assert_allclose(tips, data["tip_position_m"], atol=GEOMETRY_ATOL)

"""The tendon-robot description: the built-in rao2021 as tdcr-modeling's example, TOML round trip, bad input.

The rao2021 values are tdcr-modeling's ``c++/main.cpp`` (Rao, Peyron, Lilge, Burgner-Kahrs 2021); its shear modulus
convention ``G = E / (2 * 1.3)`` is ``cosseratrodmodel.cpp``'s.
"""

import math

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.tdcr import ROBOTS, Backbone, Robot, Segment, Tendon, get_robot, load_robot, robot_from_dict

RAO_TOML = """
name = "rao2021-file"
[backbone]
youngs_modulus_pa = 54e9
poisson_ratio = 0.3
radius_m = 0.7e-3
[[segments]]
length_m = 0.2
disk_count = 10
[[segments]]
length_m = 0.2
disk_count = 10
"""
for _disk in (10, 20):
    for _angle in (90, -30, 210):
        RAO_TOML += f"[[tendons]]\noffset_m = 0.01\nangle_deg = {_angle}\ndisk = {_disk}\n"


def test_rao2021_is_tdcr_modelings_example():
    robot = ROBOTS["rao2021"]
    b = robot.backbone
    assert robot.length_m == pytest.approx(0.4)
    assert [s.disk_count for s in robot.segments] == [10, 10]
    assert b.youngs_modulus_pa == 54e9
    assert b.radius_m == 0.7e-3
    assert b.shear_modulus_pa == pytest.approx(54e9 / 2.6)  # tdcr-modeling: G = E / (2 * 1.3)
    i = math.pi * 0.7e-3**4 / 4
    np.testing.assert_allclose(b.bending_torsion_stiffness, [54e9 * i, 54e9 * i, 2 * 54e9 / 2.6 * i])
    # routing: (0, r), (r cos -30, r sin -30), (r cos 210, r sin 210), per segment, in the disk frame
    expected = [[0, 0.01, 0], [0.01 * math.cos(-math.pi / 6), -0.005, 0], [0.01 * math.cos(7 * math.pi / 6), -0.005, 0]]
    np.testing.assert_allclose(robot.routing_m, expected * 2, atol=1e-15)
    np.testing.assert_allclose(robot.tendon_ends_m, [0.2] * 3 + [0.4] * 3)
    np.testing.assert_allclose(robot.disk_positions_m[[0, 9, 19]], [0.02, 0.2, 0.4])


def test_toml_file_and_built_in_agree(tmp_path):
    path = tmp_path / "rao.toml"
    path.write_text(RAO_TOML)
    robot = load_robot(path)
    assert robot.name == "rao2021-file"
    assert robot.to_dict() | {"name": "rao2021"} == ROBOTS["rao2021"].to_dict()
    assert get_robot(str(path)) == robot
    assert get_robot("rao2021") is ROBOTS["rao2021"]
    assert robot_from_dict(ROBOTS["rao2021"].to_dict()) == ROBOTS["rao2021"]


@pytest.mark.parametrize(
    ("text", "names"),
    [
        ("[backbone]\nradius_m = -1\n", ["radius_m", "Backbone"]),
        ("[backbone]\npoisson_ratio = 0.7\n", ["poisson_ratio", "(-1, 0.5]"]),
        ("[backbone]\nstiffness = 1\n", ["stiffness", "[backbone]"]),
        ("segments = []\n", ["segments"]),
        ("[[segments]]\nlength_m = 0.1\ndisk_count = 0\n", ["disk_count", "[[segments]] 1"]),
        ("[[segments]]\nlength_m = 0.1\ndisk_count = 5\n[[tendons]]\ndisk = 6\n", ["tendons[0].disk", "[1, 5]"]),
        ("[[segments]]\nlength_m = 0.1\n[[tendons]]\noffset_m = 'far'\n", ["offset_m"]),
        ("[[segments]]\nlength_m = 0.1\ntendons = 3\n", ["tendons"]),
        ("colour = 'red'\n", ["colour"]),
        ("[[segments]\n", ["not valid TOML"]),
        # hostile review: finite but absurd values used to overflow into NaN or an OverflowError naming no key
        ("[[segments]]\nlength_m = 1e308\n", ["length_m", "[[segments]] 1", "[1e-06, 100]"]),
        ("[backbone]\nradius_m = 1e200\n", ["radius_m", "[backbone]", "[1e-06, 1]"]),
        ("[backbone]\nyoungs_modulus_pa = 1e-300\n", ["youngs_modulus_pa", "[1000, 1e+13]"]),
        ("[[segments]]\nlength_m = 0.1\n[[tendons]]\noffset_m = 1e300\ndisk = 1\n", ["offset_m", "[0, 10]"]),
        ("[backbone]\ndensity_kg_m3 = inf\n", ["density_kg_m3"]),
    ],
)
def test_bad_robot_files_are_refused_in_one_line(tmp_path, text, names):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ParameterError) as info:
        load_robot(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    for name in names:
        assert name in message


def test_unknown_robot_name():
    with pytest.raises(ParameterError, match="unknown robot 'rao2022'.*rao2021"):
        get_robot("rao2022")


def test_objects_validate_their_fields():
    with pytest.raises(ParameterError, match="'youngs_modulus_pa' parameter of Backbone"):
        Backbone(youngs_modulus_pa=0)
    with pytest.raises(ParameterError, match="'segments' parameter of Robot"):
        Robot(segments=())
    robot = Robot(segments=(Segment(0.1, 4),), tendons=(Tendon(0.005, 0.0, 4),))
    assert robot.tendon_ends_m.tolist() == [0.1]

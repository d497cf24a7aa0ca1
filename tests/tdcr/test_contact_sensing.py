"""A point contact located and measured in space from the gauges, against the twin pressed there.

The twin with a contact is the discrete rod (:mod:`flexdigit.tdcr._chain_kernel`, which takes a force at any
node) settled under the tensions and the contact; its gauge readings come from its curvatures at the nodes. The
shape without the contact is the same model's (so that what the estimate sees is the contact, not a difference
of models). The estimate is first order in the force about that shape: its errors grow with the deflection the
contact causes (measured: the place exact and the force within 0.1 % on a straight rod at 12 mN; 1 mm and
1.7 % on rao2021 under tensions at 18 mN).
"""

import numpy as np
import pytest

from flexdigit.tdcr import ROBOTS, Robot, Segment, gauge_layout, gauge_strains, pressed_shape, sense_contact
from flexdigit.tdcr.contact_sensing import locate_contact

PLACE_ATOL_M = 2e-3
FORCE_RTOL = 0.05


def _twin(robot, tensions, nodes_per_disk, contact_node=None, force_n=None):
    """The discrete rod settled under the tensions (and a contact force at a node), as a StaticSolution."""
    if contact_node is None:
        return pressed_shape(robot, tensions, nodes_per_disk=nodes_per_disk)
    s_m = pressed_shape(robot, tensions, nodes_per_disk=nodes_per_disk).s_m[contact_node]
    return pressed_shape(robot, tensions, contact_s_m=s_m, contact_force_n=force_n, nodes_per_disk=nodes_per_disk)


@pytest.mark.parametrize(
    ("robot", "tensions", "nodes_per_disk", "s_contact_m", "force_n"),
    [
        (Robot(name="rod", segments=(Segment(0.4, 40),)), [], 2, 0.30, [0.010, -0.006, 0.0]),
        (ROBOTS["rao2021"], [2, 0, 0, 0, 1, 0], 2, 0.27, [-0.01, 0.015, 0.0]),
    ],
)
def test_a_contact_is_located_and_its_force_measured(robot, tensions, nodes_per_disk, s_contact_m, force_n):
    layout = gauge_layout(robot, stations_per_segment=4 // len(robot.segments) * 2)
    free = _twin(robot, tensions, nodes_per_disk)
    node = int(np.argmin(np.abs(free.s_m - s_contact_m)))
    pressed = _twin(robot, tensions, nodes_per_disk, node, np.asarray(force_n))
    estimate = locate_contact(robot, layout, gauge_strains(pressed, layout), free)
    assert estimate.s_m == pytest.approx(free.s_m[node], abs=PLACE_ATOL_M)
    seen = np.asarray(force_n, dtype=float)
    if estimate.unseen_direction is not None:
        seen = seen - (seen @ estimate.unseen_direction) * estimate.unseen_direction
    assert np.linalg.norm(estimate.force_n - seen) < FORCE_RTOL * np.linalg.norm(force_n)


def test_a_straight_rods_axial_push_is_unseen_and_said_so():
    robot = Robot(name="rod", segments=(Segment(0.4, 40),))
    layout = gauge_layout(robot, stations_per_segment=4)
    free = _twin(robot, [], 1)
    pressed = _twin(robot, [], 1, 30, np.array([0.01, 0.0, -0.02]))
    estimate = locate_contact(robot, layout, gauge_strains(pressed, layout), free)
    assert estimate.unseen_direction is not None
    assert abs(estimate.unseen_direction[2]) > 0.99  # along the rod


def test_contacts_near_the_base_are_out_of_sight():
    robot = Robot(name="rod", segments=(Segment(0.4, 40),))
    layout = gauge_layout(robot, stations_per_segment=4)
    estimate = locate_contact(robot, layout, gauge_strains(_twin(robot, [], 1), layout), _twin(robot, [], 1))
    assert estimate.visible_from_m == pytest.approx(0.15)  # the second station
    assert estimate.s_m >= estimate.visible_from_m


def test_sense_contact_presses_the_twin_and_reports_its_errors():
    """The one call behind ``flexdigit tdcr contact``: the same numbers as the steps above, and seeded noise."""
    robot = ROBOTS["rao2021"]
    found = sense_contact(robot, [2, 0, 0, 0, 1, 0], contact_s_m=0.27, contact_force_n=[-0.01, 0.015, 0.0])
    assert found.true_s_m == pytest.approx(0.27)
    assert found.place_error_m < PLACE_ATOL_M
    assert found.force_error_n < FORCE_RTOL * np.hypot(0.01, 0.015)
    noisy = [
        sense_contact(
            robot, [2, 0, 0, 0, 1, 0], contact_s_m=0.27, contact_force_n=[-0.01, 0.015, 0.0], noise_std=1e-6, seed=3
        ).strains
        for _ in range(2)
    ]
    np.testing.assert_array_equal(*noisy)
    assert np.abs(noisy[0] - found.strains).max() > 0  # the noise is there
    with pytest.raises(ValueError, match="readings"):
        sense_contact(robot, [2, 0, 0, 0, 1, 0])

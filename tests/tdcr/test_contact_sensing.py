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

from flexdigit.tdcr import ROBOTS, Robot, Segment, _chain_kernel, gauge_layout, gauge_strains, solve_statics
from flexdigit.tdcr.contact_sensing import locate_contact
from flexdigit.tdcr.dynamics import _discrete_model, _element_frames
from flexdigit.tdcr.statics import StaticSolution, _nodes

PLACE_ATOL_M = 2e-3
FORCE_RTOL = 0.05


def _twin(robot, tensions, nodes_per_disk, contact_node=None, force_n=None):
    """The discrete rod settled under the tensions (and a contact force at a node), as a StaticSolution."""
    nodes, ends = _nodes(robot, nodes_per_disk)
    loads = (np.asarray(tensions, dtype=float), np.zeros(3), np.zeros(3), np.zeros(3))
    model, _, _, hb = _discrete_model(robot, nodes, ends, loads)
    if contact_node is not None:
        model[4][contact_node] += force_n
    n = nodes.size - 1
    start = solve_statics(robot, tensions, nodes_per_disk=nodes_per_disk)  # Newton's start: the shot rod's shape
    x = start.positions_m.copy()
    q = np.ascontiguousarray(_element_frames(start.rotations))
    assert _chain_kernel.equilibrate(x, q, model, hb, 1e-10, 100) != _chain_kernel.NO_PROGRESS
    sig, kap = np.empty((n, 3)), np.empty((n, 3))
    _chain_kernel._state_strains(x, q, model, sig, kap)
    frames = np.empty((1, n + 1, 3, 3))
    _chain_kernel.node_frames(q[None], frames)
    strains = np.zeros((n + 1, 6))
    v = sig + [0.0, 0.0, 1.0]
    strains[0, :3], strains[-1, :3] = v[0], v[-1]
    strains[1:-1, :3] = (v[:-1] + v[1:]) / 2
    strains[:-1, 3:] = kap  # the tip carries no moment
    return StaticSolution(nodes, x, frames[0], strains, strains, np.zeros(6), True, 0, 0.0)


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

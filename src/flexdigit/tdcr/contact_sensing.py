"""A point contact on a tendon robot, located and measured in space from its strain gauges.

A force ``F`` (world frame) pressed at arc length ``s_c`` changes the bending and twisting moment of every
cross-section between the base and ``s_c`` by ``(p(s_c) - p(s)) x F`` and of none beyond it. To first order in
``F`` about the shape without the contact (the twin's, under the known tensions), a gauge station at ``s < s_c``
sees the curvature change

    du(s) = Kbt^-1 R(s)^T [(p(s_c) - p(s)) x F]

which is linear in ``F`` for a given ``s_c``. :func:`locate_contact` fits ``F`` by least squares at every
candidate ``s_c`` (every ``step_m`` along the backbone) and keeps the ``s_c`` whose fit leaves the smallest
residual: the thesis's planar localisation (the moment's slope along the digit gives the force, its zero the
place) in three dimensions.

Where the gauges cannot see it, it says so:

- a contact between the base and the second gauge station (``visible_from_m``) changes the moment at one station
  at most, which cannot tell the place from the force: the fit is not attempted there;
- the component of ``F`` along the lever arms ``p(s_c) - p(s)`` of every seeing station makes no moment (on a
  straight rod, the axial push): it is reported as ``unseen_direction`` and left out of ``force_n``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_real
from flexdigit.errors import ParameterError
from flexdigit.tdcr.description import Robot
from flexdigit.tdcr.sensing import GaugeLayout, _station_curvatures, gauge_strains
from flexdigit.tdcr.statics import StaticSolution

__all__ = ["ContactEstimate", "locate_contact"]


@dataclass(frozen=True)
class ContactEstimate:
    """A point contact estimated from gauge readings.

    Attributes
    ----------
    s_m : float
        Its arc length from the base (m).
    position_m : ndarray (3,)
        Where it is, world frame (on the twin's shape without it).
    force_n : ndarray (3,)
        The force on the robot (N, world frame), less any ``unseen_direction`` component.
    unseen_direction : ndarray (3,) or None
        A unit vector along which the force makes no moment at any seeing station (so is not measured), or None.
    visible_from_m : float
        Contacts nearer the base than this (the second gauge station) cannot be located.
    residual : float
        RMS of the curvature change the fit leaves (1/m).
    """

    s_m: float
    position_m: np.ndarray
    force_n: np.ndarray
    unseen_direction: np.ndarray | None
    visible_from_m: float
    residual: float

    __repr__ = fields_summary


def _interp(s_nodes, values, s):
    return np.stack([np.interp(s, s_nodes, values[:, k]) for k in range(values.shape[1])], axis=-1)


def locate_contact(
    robot: Robot, layout: GaugeLayout, strains, free: StaticSolution, *, step_m: float = 1e-3
) -> ContactEstimate:
    """The contact's place and force from the gauge ``strains``, given the twin's shape ``free`` without it.

    Parameters
    ----------
    robot : Robot
    layout : GaugeLayout
        Where the gauges are (two faces at every station at least).
    strains : array (g,)
        The readings with the contact, in the layout's order.
    free : StaticSolution
        The twin under the same tensions and known loads, without the contact.
    step_m : float
        Spacing of the candidate places (m).
    """
    owner = "locate_contact"
    strains = check_array(strains, "strains", owner, shape=layout.s_m.shape)
    step_m = check_real(step_m, "step_m", owner, low=0.0, low_open=True)
    stations, measured = _station_curvatures(layout, strains)
    _, baseline = _station_curvatures(layout, gauge_strains(free, layout))
    if stations.size < 2:
        raise ParameterError(f"{owner}: the gauges sit at {stations.size} station(s); locating needs two or more.")
    du = (measured - baseline)[:, :3]
    seen = np.any(layout._columns(np.ones(layout.s_m.size, bool))[:, 2] != 0)  # a tilted gauge: twist seen
    rows = [0, 1, 2] if seen else [0, 1]
    kbt = robot.backbone.bending_torsion_stiffness
    s_nodes = free.s_m
    p_st = _interp(s_nodes, free.positions_m, stations)
    r_st = _interp(s_nodes, free.rotations.reshape(-1, 9), stations).reshape(-1, 3, 3)
    candidates = np.arange(stations[1], s_nodes[-1] + 0.5 * step_m, step_m)
    best = None
    for s_c in candidates:
        p_c = _interp(s_nodes, free.positions_m, np.array([s_c]))[0]
        near = stations < s_c
        blocks, targets = [], []
        for k in np.flatnonzero(near):
            arm = p_c - p_st[k]
            hat = np.array([[0.0, -arm[2], arm[1]], [arm[2], 0.0, -arm[0]], [-arm[1], arm[0], 0.0]])
            blocks.append(((r_st[k].T @ hat) / kbt[:, None])[rows])
            targets.append(du[k, rows])
        design, target = np.vstack(blocks), np.concatenate(targets)
        far = du[~near][:, rows].ravel()  # beyond the contact, no change is predicted
        force, *_ = np.linalg.lstsq(design, target, rcond=1e-9)
        left = np.concatenate([design @ force - target, far])
        residual = float(np.sqrt(np.mean(left**2)))
        if best is None or residual < best[0]:
            best = (residual, s_c, p_c, force, design)
    residual, s_c, p_c, force, design = best
    _, sing, vt = np.linalg.svd(design)
    unseen = vt[-1] if sing[-1] < 1e-6 * sing[0] else None
    return ContactEstimate(
        s_m=float(s_c),
        position_m=p_c,
        force_n=force,
        unseen_direction=unseen,
        visible_from_m=float(stations[1]),
        residual=residual,
    )

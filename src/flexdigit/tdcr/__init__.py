"""Tendon-driven continuum robots in three dimensions: description, rod statics, (later) dynamics and sensing.

The thesis's digit is the planar case of such a robot; this domain is its generalisation to space (issue 26):
a Cosserat rod with any number of segments and tendons (:mod:`flexdigit.tdcr.description`) and its static
equilibrium by shooting (:mod:`flexdigit.tdcr.statics`).
"""

from __future__ import annotations

from flexdigit.tdcr.description import ROBOTS, Backbone, Robot, Segment, Tendon, get_robot, load_robot, robot_from_dict
from flexdigit.tdcr.statics import StaticSolution, solve_statics

__all__ = [
    "ROBOTS",
    "Backbone",
    "Robot",
    "Segment",
    "Tendon",
    "get_robot",
    "load_robot",
    "robot_from_dict",
    "StaticSolution",
    "solve_statics",
]

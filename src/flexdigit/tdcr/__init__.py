"""Tendon-driven continuum robots in three dimensions: description, rod statics and dynamics, sensing, recordings.

The thesis's digit is the planar case of such a robot; this domain is its generalisation to space (issue 26):
a Cosserat rod with any number of segments and tendons (:mod:`flexdigit.tdcr.description`), its static
equilibrium by shooting (:mod:`flexdigit.tdcr.statics`) and its motion, implicit in time on a discretised rod
(:mod:`flexdigit.tdcr.dynamics`), its shape from strain gauges on its faces (:mod:`flexdigit.tdcr.sensing`) and
a point contact from them (:mod:`flexdigit.tdcr.contact_sensing`), recordings of either that open in 3D in
Foxglove (:mod:`flexdigit.tdcr.scene`), and the figures the commands draw with ``--plot``
(:mod:`flexdigit.tdcr.robot_plot`).
"""

from flexdigit._lazy import lazy_exports

#: Public names and the submodule each lives in: imported on first use (PEP 562), so that ``flexdigit --help``
#: (which imports ``flexdigit.cli.tdcr``) does not load numba.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "ROBOTS": "flexdigit.tdcr.description",
        "Backbone": "flexdigit.tdcr.description",
        "Robot": "flexdigit.tdcr.description",
        "Segment": "flexdigit.tdcr.description",
        "Tendon": "flexdigit.tdcr.description",
        "get_robot": "flexdigit.tdcr.description",
        "builtin_robots": "flexdigit.tdcr.description",
        "load_robot": "flexdigit.tdcr.description",
        "robot_from_dict": "flexdigit.tdcr.description",
        "StaticSolution": "flexdigit.tdcr.statics",
        "solve_statics": "flexdigit.tdcr.statics",
        "DynamicSolution": "flexdigit.tdcr.dynamics",
        "simulate": "flexdigit.tdcr.dynamics",
        "GaugeLayout": "flexdigit.tdcr.sensing",
        "ShapeEstimate": "flexdigit.tdcr.sensing",
        "gauge_layout": "flexdigit.tdcr.sensing",
        "gauge_strains": "flexdigit.tdcr.sensing",
        "estimate_shape": "flexdigit.tdcr.sensing",
        "ShapeSensing": "flexdigit.tdcr.sensing",
        "read_readings": "flexdigit.tdcr.sensing",
        "sense_shape": "flexdigit.tdcr.sensing",
        "ContactEstimate": "flexdigit.tdcr.contact_sensing",
        "locate_contact": "flexdigit.tdcr.contact_sensing",
        "ContactSensing": "flexdigit.tdcr.contact_sensing",
        "pressed_shape": "flexdigit.tdcr.contact_sensing",
        "sense_contact": "flexdigit.tdcr.contact_sensing",
        "RobotExperiment": "flexdigit.tdcr.experiments",
        "step_test": "flexdigit.tdcr.experiments",
        "release_test": "flexdigit.tdcr.experiments",
        "euler_bernoulli_first_hz": "flexdigit.tdcr.experiments",
        "pencil_frequency_hz": "flexdigit.tdcr.experiments",
        "scene_update": "flexdigit.tdcr.scene",
        "write_recording": "flexdigit.tdcr.scene",
        "experiment_figure": "flexdigit.tdcr.robot_plot",
        "trajectory_figure": "flexdigit.tdcr.robot_plot",
        "statics_figure": "flexdigit.tdcr.robot_plot",
        "backbone_figure": "flexdigit.tdcr.robot_plot",
        "contact_figure": "flexdigit.tdcr.robot_plot",
    },
)

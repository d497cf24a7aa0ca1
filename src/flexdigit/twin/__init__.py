"""The digital twin: a calibrated large-deflection simulator of the whole rig (digit, servo, sensors).

- :class:`Twin`: the stepping API (command, advance, read, place_load) the ``sim`` rig backend drives;
- :func:`static_gauges_v`: steady gauge voltages for many load cases at once (tactile studies);
- :mod:`~flexdigit.twin.records`: the thesis's experiments simulated, as tidy tables (``TwinRecord``);
- :mod:`~flexdigit.twin.calibration`: the fitted parameters (:class:`Calibration`), their file and the default.
  Fitting them to a rig is :mod:`flexdigit.calibrate`'s job, a layer above.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "Twin": "flexdigit.twin.twin",
        "static_gauges_v": "flexdigit.twin.twin",
        "Calibration": "flexdigit.twin.calibration",
        "default_calibration": "flexdigit.twin.calibration",
        "load_calibration": "flexdigit.twin.calibration",
        "save_calibration": "flexdigit.twin.calibration",
        "use_calibration": "flexdigit.twin.calibration",
        "calibration_for": "flexdigit.twin.digit_calibration",
        "TwinRecord": "flexdigit.twin.records",
        "record_figure": "flexdigit.twin.record_plot",
        "release_test": "flexdigit.twin.records",
        "release_orientation": "flexdigit.twin.records",
        "servo_step_test": "flexdigit.twin.records",
        "actuation_sweep": "flexdigit.twin.records",
        "static_load_test": "flexdigit.twin.records",
        "Tissue": "flexdigit.twin.contact",
        "Inclusion": "flexdigit.twin.contact",
        "PointForce": "flexdigit.twin.contact",
        "Pressure": "flexdigit.twin.contact",
        "solve_contact": "flexdigit.twin.contact",
        "BatchedTwin": "flexdigit.twin.batched",
        "SensorChain": "flexdigit.twin.sensors",
        "Chain": "flexdigit.twin.digit",
        "build_digit": "flexdigit.twin.digit",
        "default_cells": "flexdigit.twin.digit",
        "StaticError": "flexdigit.twin.resolution",
        "static_error": "flexdigit.twin.resolution",
        "resolution_for": "flexdigit.twin.resolution",
        "ResolutionAdvice": "flexdigit.twin.resolution",
        "resolution_advice": "flexdigit.twin.resolution",
    },
)

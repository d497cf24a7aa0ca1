"""The digital twin: a calibrated large-deflection simulator of the whole rig (digit, servo, sensors).

- :class:`Twin`: the stepping API (command, advance, read, place_load) the ``sim`` rig backend drives;
- :func:`static_gauges_v`: steady gauge voltages for many load cases at once (tactile studies);
- :mod:`~flexdigit.twin.records`: the thesis's experiments simulated, as tidy tables (``TwinRecord``);
- :mod:`~flexdigit.twin.calibration`: the fitted parameters and :func:`calibrate`.
"""

from flexdigit.twin.calibration import Calibration, CalibrationTargets, calibrate, default_calibration
from flexdigit.twin.twin import Twin, static_gauges_v

__all__ = ["Twin", "static_gauges_v", "Calibration", "CalibrationTargets", "calibrate", "default_calibration"]

"""The digital twin: a calibrated large-deflection simulator of the whole rig (digit, servo, sensors).

- :class:`Twin`: the stepping API (command, advance, read, place_load) the ``sim`` rig backend drives;
- :func:`static_gauges_v`: steady gauge voltages for many load cases at once (tactile studies);
- :mod:`~flexdigit.twin.records`: the thesis's experiments simulated, as tidy tables (``TwinRecord``);
- :mod:`~flexdigit.twin.calibration`: the fitted parameters (:class:`Calibration`), their file and the default.
  Fitting them to a rig is :mod:`flexdigit.calibrate`'s job, a layer above.
"""

from flexdigit.twin.calibration import Calibration, default_calibration, load_calibration, use_calibration
from flexdigit.twin.twin import Twin, static_gauges_v

__all__ = ["Twin", "static_gauges_v", "Calibration", "default_calibration", "load_calibration", "use_calibration"]

"""The digital twin: a calibrated large-deflection simulator of the whole rig (digit, servo, sensors).

- :class:`Twin`: the stepping API (command, advance, read, place_load) the ``sim`` rig backend drives;
- :func:`static_gauges_v`: steady gauge voltages for many load cases at once (tactile studies);
- :mod:`~flexdigit.twin.records`: the thesis's experiments simulated, as tidy tables (``TwinRecord``);
- :mod:`~flexdigit.twin.calibration`: the fitted parameters (:class:`Calibration`), their file and the default.
  Fitting them to a rig is :mod:`flexdigit.calibrate`'s job, a layer above.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the submodule each lives in: imported on first use (PEP 562), so that importing a submodule
#: (``flexdigit.cli.simulate`` for ``flexdigit --help``) does not load python-control and scipy.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "Twin": "flexdigit.twin.twin",
        "static_gauges_v": "flexdigit.twin.twin",
        "Calibration": "flexdigit.twin.calibration",
        "default_calibration": "flexdigit.twin.calibration",
        "load_calibration": "flexdigit.twin.calibration",
        "use_calibration": "flexdigit.twin.calibration",
    },
)

"""Calibration: the twin fitted to a rig, a layer above the twin and the tactile package.

- :mod:`~flexdigit.calibrate.targets`: what is fitted (:class:`CalibrationTargets`, from the thesis or from records);
- :mod:`~flexdigit.calibrate.twin_fit`: :func:`calibrate` (``scipy.optimize.least_squares``) and its residuals;
- :mod:`~flexdigit.calibrate.friction`: the cable-guide friction's level;
- :mod:`~flexdigit.calibrate.record_files`: a rig's record files read for ``flexdigit calibrate``.

The result is a :class:`flexdigit.twin.calibration.Calibration`, written as TOML and loaded by every command that
takes ``--calibration FILE``.
"""

from flexdigit._lazy import lazy_exports

# loaded on first use: the command line imports flexdigit.cli.calibrate for every command, and the fit's
# modules cost ~0.05 s of start-up that `flexdigit --help` or `model` should not pay
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "CalibrationTargets": "flexdigit.calibrate.targets",
        "CalibrationResult": "flexdigit.calibrate.twin_fit",
        "calibrate": "flexdigit.calibrate.twin_fit",
    },
)

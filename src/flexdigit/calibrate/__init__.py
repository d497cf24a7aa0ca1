"""Calibration: the twin fitted to a rig, a layer above the twin and the tactile package.

- :mod:`~flexdigit.calibrate.targets`: what is fitted (:class:`CalibrationTargets`, from the thesis or from records);
- :mod:`~flexdigit.calibrate.fit`: :func:`calibrate` (``scipy.optimize.least_squares``) and its residuals;
- :mod:`~flexdigit.calibrate.friction`: the cable-guide friction's level;
- :mod:`~flexdigit.calibrate.records`: a rig's record files read for ``flexdigit calibrate``.

The result is a :class:`flexdigit.twin.calibration.Calibration`, written as TOML and loaded by every command that
takes ``--calibration FILE``.
"""

from flexdigit.calibrate.fit import CalibrationResult, calibrate
from flexdigit.calibrate.targets import CalibrationTargets

__all__ = ["CalibrationTargets", "CalibrationResult", "calibrate"]

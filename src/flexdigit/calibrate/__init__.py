"""Calibration: the twin fitted to a rig, a layer above the twin and the tactile package.

- :mod:`~flexdigit.calibrate.targets`: what is fitted (:class:`CalibrationTargets`, from the thesis or from records);
- :mod:`~flexdigit.calibrate.twin_fit`: :func:`calibrate` (``scipy.optimize.least_squares``) and its residuals;
- :mod:`~flexdigit.calibrate.friction`: the cable-guide friction's level;
- :mod:`~flexdigit.calibrate.record_files`: a rig's record files read for ``flexdigit calibrate``.

The result is a :class:`flexdigit.twin.calibration.Calibration`, written as TOML and loaded by every command that
takes ``--calibration FILE``.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "CalibrationTargets": "flexdigit.calibrate.targets",
        "CalibrationResult": "flexdigit.calibrate.twin_fit",
        "calibrate": "flexdigit.calibrate.twin_fit",
        "residual_figure": "flexdigit.calibrate.residual_plot",
        "calibrate_to_thesis": "flexdigit.calibrate.twin_fit",
        "Chapter3TwinStudy": "flexdigit.calibrate.chapter3_twin",
        "chapter3_twin_study": "flexdigit.calibrate.chapter3_twin",
    },
)

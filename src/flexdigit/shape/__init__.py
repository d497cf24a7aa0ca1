"""The digit's centre line from the three gauges and the servo command, with its uncertainty (thesis 1.1, 3.3-3.4).

:mod:`~flexdigit.shape.shape` holds the estimator (``ShapeEstimator``) and its accuracy (``shape_accuracy``); the
live page and the report show it. Every public name below is imported from its module on first use.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "DigitBeam": "flexdigit.shape.shape",
        "ShapeEstimate": "flexdigit.shape.shape",
        "ShapeEstimator": "flexdigit.shape.shape",
        "shape_figure": "flexdigit.shape.shape_plot",
        "ShapeAccuracy": "flexdigit.shape.shape",
        "shape_accuracy": "flexdigit.shape.shape",
        "accuracy_commands": "flexdigit.shape.shape",
        "accuracy_positions_m": "flexdigit.shape.shape",
    },
)

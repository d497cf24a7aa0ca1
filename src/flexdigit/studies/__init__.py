"""Studies at scale: sensitivity to every parameter and the design of the next digit, on Dask (thesis chapter 8).

- :mod:`~flexdigit.studies.spec`: uncertain parameters (a TOML giving a distribution to any rig or calibration
  field), validated like a parameter file;
- :mod:`~flexdigit.studies.metrics`: the registry of scalar outputs of a parameter set;
- :mod:`~flexdigit.studies.sensitivity`: Morris screening and Sobol indices (SALib) with intervals and a
  convergence check;
- :mod:`~flexdigit.studies.design_study`: the design study (gauges, bridge, ADC, servo, cable, size) and its Pareto
  front;
- :mod:`~flexdigit.studies.execution`: evaluation on Dask distributed (or in process), seeded, resumable.

This domain sits above tactile in the import chain: it reads the twin, control and tactile; nothing but the report
imports it.
"""

from flexdigit._lazy import lazy_exports

#: Public names and their submodules, imported on first use (PEP 562): the command line imports
#: ``flexdigit.cli.study`` to build its parser, which must not load scipy (issue 15's start-up).
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "METRICS": "flexdigit.studies.metrics",
        "MetricContext": "flexdigit.studies.metrics",
        "ParameterSet": "flexdigit.studies.spec",
        "StudySpec": "flexdigit.studies.spec",
        "load_spec": "flexdigit.studies.spec",
    },
)

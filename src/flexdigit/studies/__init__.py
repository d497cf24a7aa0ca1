"""Studies at scale: sensitivity to every parameter and the design of the next digit, on Dask (thesis chapter 8).

- :mod:`~flexdigit.studies.spec`: uncertain parameters (a TOML giving a distribution to any rig or calibration
  field), validated like a parameter file;
- :mod:`~flexdigit.studies.metrics`: the registry of scalar outputs of a parameter set;
- :mod:`~flexdigit.studies.sensitivity`: Morris screening and Sobol indices (SALib) with intervals and a
  convergence check;
- :mod:`~flexdigit.studies.design`: the design study (gauges, bridge, ADC, servo, cable, size) and its Pareto front;
- :mod:`~flexdigit.studies.execution`: evaluation on Dask distributed (or in process), seeded, resumable.

This domain sits above tactile in the import chain: it reads the twin, control and tactile; nothing but the report
imports it.
"""

from flexdigit.studies.metrics import METRICS, MetricContext
from flexdigit.studies.spec import ParameterSet, StudySpec, load_spec

__all__ = ["METRICS", "MetricContext", "ParameterSet", "StudySpec", "load_spec"]

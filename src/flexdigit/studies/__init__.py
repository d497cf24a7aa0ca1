"""Studies at scale: sensitivity to every parameter and the design of the next digit, on Dask (thesis chapter 8).

- :mod:`~flexdigit.studies.spec`: uncertain parameters (a TOML giving a distribution to any rig or calibration
  field), validated like a parameter file;
- :mod:`~flexdigit.studies.metrics`: the registry of scalar outputs of a parameter set;
- :mod:`~flexdigit.studies.sensitivity`: Morris screening and Sobol indices (SALib) with intervals and a
  convergence check;
- :mod:`~flexdigit.studies.design_study`: the design study (gauges, bridge, ADC, servo, cable, size) and its Pareto
  front;
- :mod:`~flexdigit.studies.execution`: evaluation on Dask distributed (or in process), seeded, resumable;
- :mod:`~flexdigit.studies.robot_study`: the sensitivity of a tendon robot (issue 26), on the same machinery.

This domain sits above tactile in the import chain: it reads the twin, control and tactile; nothing but the report
imports it.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "METRICS": "flexdigit.studies.metrics",
        "Metric": "flexdigit.studies.metrics",
        "MetricContext": "flexdigit.studies.metrics",
        "evaluate": "flexdigit.studies.metrics",
        "register_metric": "flexdigit.studies.metrics",
        "UserMetric": "flexdigit.studies.metrics",
        "metric_of": "flexdigit.studies.metrics",
        "ParameterSet": "flexdigit.studies.parameter_set",
        "StudySpec": "flexdigit.studies.spec",
        "UncertainParameter": "flexdigit.studies.spec",
        "load_spec": "flexdigit.studies.spec",
        "shipped_specs": "flexdigit.studies.spec",
        "SensitivitySettings": "flexdigit.studies.sensitivity",
        "SensitivityResult": "flexdigit.studies.sensitivity",
        "run_sensitivity": "flexdigit.studies.sensitivity",
        "DesignSettings": "flexdigit.studies.design_study",
        "DesignResult": "flexdigit.studies.design_study",
        "run_design": "flexdigit.studies.design_study",
        "export_design": "flexdigit.studies.design_study",
        "run_study": "flexdigit.studies.execution",
        "RobotStudySpec": "flexdigit.studies.robot_study",
        "load_robot_spec": "flexdigit.studies.robot_study",
        "run_robot_sensitivity": "flexdigit.studies.robot_study",
        "StepSchedule": "flexdigit.studies.batched_loop",
        "step_responses": "flexdigit.studies.batched_loop",
    },
)

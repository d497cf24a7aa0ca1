"""Palpation beyond the thesis (chapter 8): contact from the gauges, tissue stiffness, force control, active sensing.

- :mod:`~flexdigit.palpation.contact_estimation`: contact yes / no, where, how hard (``ContactEstimator``);
- :mod:`~flexdigit.palpation.palpation`: sweeps into tissue, the stiffness fit and its bound, scans for an inclusion,
  force control;
- :mod:`~flexdigit.palpation.palpation_files`: tissue and palpation-protocol files (built-ins in ``palpation_data/``);
- :mod:`~flexdigit.palpation.active`: active sensing (hangs at several commands);
- :mod:`~flexdigit.palpation.palpation_studies`: the studies report chapter 8 shows.

Above tactile in the import chain (it uses tactile's bounds); only the report and the CLI import it. Every public
name below is imported from its module on first use.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "ContactGaugeModel": "flexdigit.palpation.contact_estimation",
        "ContactEstimate": "flexdigit.palpation.contact_estimation",
        "ContactEstimator": "flexdigit.palpation.contact_estimation",
        "PalpationProtocol": "flexdigit.palpation.palpation",
        "SweepRecord": "flexdigit.palpation.palpation",
        "run_sweep": "flexdigit.palpation.palpation",
        "TissueFit": "flexdigit.palpation.palpation",
        "fit_tissue": "flexdigit.palpation.palpation",
        "analyse": "flexdigit.palpation.palpation",
        "palpate": "flexdigit.palpation.palpation",
        "simulate_sweep": "flexdigit.palpation.palpation",
        "scan": "flexdigit.palpation.palpation",
        "ForceController": "flexdigit.palpation.palpation",
        "hold_force": "flexdigit.palpation.palpation",
        "rig_contact_model": "flexdigit.palpation.palpation",
        "digit_tissue": "flexdigit.palpation.palpation",
        "check_tissue_reach": "flexdigit.palpation.palpation",
        "digit_scan": "flexdigit.palpation.palpation",
        "indentation_figure": "flexdigit.palpation.palpation_plot",
        "scan_figure": "flexdigit.palpation.palpation_plot",
        "hold_figure": "flexdigit.palpation.palpation_plot",
        "load_tissue": "flexdigit.palpation.palpation_files",
        "builtin_palpation_files": "flexdigit.palpation.palpation_files",
        "load_palpation_protocol": "flexdigit.palpation.palpation_files",
        "simulate_hangs": "flexdigit.palpation.active",
        "HangInversion": "flexdigit.palpation.active",
        "HangPosterior": "flexdigit.palpation.active",
        "contact_study": "flexdigit.palpation.palpation_studies",
        "classification_study": "flexdigit.palpation.palpation_studies",
        "stiffness_study": "flexdigit.palpation.palpation_studies",
        "scan_study": "flexdigit.palpation.palpation_studies",
        "force_study": "flexdigit.palpation.palpation_studies",
        "active_study": "flexdigit.palpation.palpation_studies",
    },
)

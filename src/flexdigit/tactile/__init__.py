"""Tactile sensing, the thesis's load localisation (chapters 6-7): protocols, datasets, the MLP, estimators, bounds.

- :mod:`~flexdigit.tactile.protocols`: load experiments (``load_protocol("thesis-6.1")``);
- :mod:`~flexdigit.tactile.runner`: ``collect(protocol, rig, path)``, a dataset from any rig;
  :mod:`~flexdigit.tactile.refinement`: how finely ``collect`` lays the protocol's positions on a digit;
- :mod:`~flexdigit.tactile.dataset`, :mod:`~flexdigit.tactile.importer`: datasets saved, loaded, imported;
- :mod:`~flexdigit.tactile.pipeline`: the thesis's split and network (``thesis_split``, ``ThesisNetwork``);
- :mod:`~flexdigit.tactile.netlab`: the MLP as netlab trains it; :mod:`~flexdigit.tactile.estimators`: others;
- :mod:`~flexdigit.tactile.accuracy`, :mod:`~flexdigit.tactile.bounds`: scores and Cramer-Rao / Bayes bounds;
  :mod:`~flexdigit.tactile.position_floor`: which Bayes limit a trained network is compared with;
- :mod:`~flexdigit.tactile.localisation`, :mod:`~flexdigit.tactile.thesis_experiments`: the studies the report
  shows.

Shape (:mod:`flexdigit.shape`) and palpation (:mod:`flexdigit.palpation`) are domains of their own.

Every public name below is imported from its module on first use.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "Protocol": "flexdigit.tactile.protocols",
        "load_protocol": "flexdigit.tactile.protocols",
        "builtin_protocols": "flexdigit.tactile.protocols",
        "collect": "flexdigit.tactile.runner",
        "collect_on": "flexdigit.tactile.runner",
        "load_or_collect": "flexdigit.tactile.runner",
        "Refinement": "flexdigit.tactile.refinement",
        "refinement_for": "flexdigit.tactile.refinement",
        "Dataset": "flexdigit.tactile.dataset",
        "load_dataset": "flexdigit.tactile.dataset",
        "save_dataset": "flexdigit.tactile.dataset",
        "ColumnMap": "flexdigit.tactile.importer",
        "import_readings": "flexdigit.tactile.importer",
        "thesis_split": "flexdigit.tactile.pipeline",
        "held_out_positions_split": "flexdigit.tactile.pipeline",
        "ThesisNetwork": "flexdigit.tactile.pipeline",
        "run_pipeline": "flexdigit.tactile.pipeline",
        "target_scores": "flexdigit.tactile.pipeline",
        "compare_strategies": "flexdigit.tactile.pipeline",
        "MLP": "flexdigit.tactile.netlab",
        "BeamInversion": "flexdigit.tactile.estimators",
        "GPLocaliser": "flexdigit.tactile.estimators",
        "save_model": "flexdigit.tactile.model_io",
        "load_model": "flexdigit.tactile.model_io",
        "percentage_error": "flexdigit.tactile.accuracy",
        "rmse": "flexdigit.tactile.accuracy",
        "prediction_figure": "flexdigit.tactile.prediction_plot",
        "dataset_figure": "flexdigit.tactile.dataset_plot",
        "target_unit": "flexdigit.tactile.prediction_plot",
        "TwinGaugeModel": "flexdigit.tactile.bounds",
        "cramer_rao": "flexdigit.tactile.bounds",
        "protocol_limits": "flexdigit.tactile.bounds",
        "LocalisationResult": "flexdigit.tactile.localisation",
        "localisation_study": "flexdigit.tactile.localisation",
        "Prediction": "flexdigit.tactile.localisation",
        "predict_dataset": "flexdigit.tactile.localisation",
        "network_floor": "flexdigit.tactile.position_floor",
        "split_for_limit": "flexdigit.tactile.position_floor",
        "run_experiment": "flexdigit.tactile.thesis_experiments",
        "experiment_tables": "flexdigit.tactile.thesis_experiments",
        "white_noise_scan": "flexdigit.tactile.thesis_experiments",
        "friction_study": "flexdigit.tactile.thesis_experiments",
    },
)

"""Control (thesis chapters 4-5): generalized plant, H-infinity synthesis, analysis, discretisation, runtime.

- :mod:`~flexdigit.control.generalized`: the generalized plant of 4.3 (``thesis_generalized_plant``,
  ``filter_weight``, ``regularise``) and a mixed-sensitivity one;
- :mod:`~flexdigit.control.synthesis`: ``hinf_riccati`` (the 2-Riccati central controller), ``hinf_lmi``;
- :mod:`~flexdigit.control.mixsyn`: mixed-sensitivity design against requirements (``design_mixsyn``);
- :mod:`~flexdigit.control.analysis`: loop maps, stability, margins, ``step_figures``;
- :mod:`~flexdigit.control.discretise`: s -> z (Tustin, forward Euler) and the sampled loop;
- :mod:`~flexdigit.control.design20ms`: the 20 ms digital design (``design_20ms``, a described digit's
  ``digit_design_20ms``);
- :mod:`~flexdigit.control.kept_design`: a digit's 20 ms design kept in a file, checked to be that digit's
  (``keep_design``, ``write_kept_design``, ``read_kept_design``);
- :mod:`~flexdigit.control.digit_model`: a described digit's design model, its twin's chain linearised and
  truncated (``digit_model``);
- :mod:`~flexdigit.control.runtime`: the controller the loop runs (``RuntimeController``);
- :mod:`~flexdigit.control.c_export`: that controller as C99 for a microcontroller, float32 or fixed point, and
  the analysis of its quantisation (``export_controller``, ``analyse_export``);
- :mod:`~flexdigit.control.thesis_designs`: the thesis's printed designs rebuilt;
- :mod:`~flexdigit.control.chapter4_studies`: what report chapter 4 shows (``chapter4_study``).

The controllers ``flexdigit run`` knows by name (``make_controller``) are the rig's (:mod:`flexdigit.rig`): they
read the rig's gauges, a layer above.

Every public name below is imported from its module on first use (python-control costs seconds to import).
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "thesis_generalized_plant": "flexdigit.control.generalized",
        "ControllerSpec": "flexdigit.control.c_export",
        "RotationMap": "flexdigit.control.c_export",
        "fixed_format": "flexdigit.control.c_export",
        "render_c": "flexdigit.control.c_export",
        "analyse_export": "flexdigit.control.c_export",
        "export_controller": "flexdigit.control.c_export",
        "filter_weight": "flexdigit.control.generalized",
        "regularise": "flexdigit.control.generalized",
        "mixed_sensitivity_plant": "flexdigit.control.generalized",
        "HinfDesign": "flexdigit.control.synthesis",
        "hinf_riccati": "flexdigit.control.synthesis",
        "design_figure": "flexdigit.control.design_plot",
        "twenty_ms_figure": "flexdigit.control.design_plot",
        "sweep_figure": "flexdigit.control.design_plot",
        "hinf_lmi": "flexdigit.control.synthesis",
        "regularisation_path": "flexdigit.control.synthesis",
        "reduce_controller": "flexdigit.control.synthesis",
        "MixsynSpec": "flexdigit.control.mixsyn",
        "MixsynDesign": "flexdigit.control.mixsyn",
        "design_mixsyn": "flexdigit.control.mixsyn",
        "mixsyn_on_the_digit": "flexdigit.control.mixsyn",
        "loop_maps": "flexdigit.control.analysis",
        "is_stable": "flexdigit.control.analysis",
        "hinf_norm": "flexdigit.control.analysis",
        "StepFigures": "flexdigit.control.analysis",
        "step_figures": "flexdigit.control.analysis",
        "margins": "flexdigit.control.analysis",
        "map_s_to_z": "flexdigit.control.discretise",
        "sampled_loop": "flexdigit.control.discretise",
        "SampledLoop": "flexdigit.control.discretise",
        "Weights": "flexdigit.control.design20ms",
        "Digital20msDesign": "flexdigit.control.design20ms",
        "design_20ms": "flexdigit.control.design20ms",
        "thesis_controller": "flexdigit.control.design20ms",
        "closed_loop": "flexdigit.control.design20ms",
        "digit_design_20ms": "flexdigit.control.design20ms",
        "digit_design_20ms_summary": "flexdigit.control.design20ms",
        "digit_first_mode": "flexdigit.control.design20ms",
        "straight_is_stable": "flexdigit.control.design20ms",
        "digit_mount": "flexdigit.control.design20ms",
        "stiffness_share": "flexdigit.control.design20ms",
        "digit_weights": "flexdigit.control.design20ms",
        "frame_pulse_deg": "flexdigit.control.design20ms",
        "WeightsChoice": "flexdigit.control.design20ms",
        "KeptDesign": "flexdigit.control.kept_design",
        "keep_design": "flexdigit.control.kept_design",
        "write_kept_design": "flexdigit.control.kept_design",
        "read_kept_design": "flexdigit.control.kept_design",
        "DigitModel": "flexdigit.control.digit_model",
        "digit_plant": "flexdigit.control.thesis_designs",
        "digit_regularisation": "flexdigit.control.thesis_designs",
        "OPEN_LOOP_GAMMA_RTOL": "flexdigit.control.thesis_designs",
        "is_open_loop": "flexdigit.control.thesis_designs",
        "digit_hinf_design": "flexdigit.control.thesis_designs",
        "digit_hinf_summary": "flexdigit.control.thesis_designs",
        "RuntimeController": "flexdigit.control.runtime",
        "printed_controller": "flexdigit.control.thesis_designs",
        "thesis_plant": "flexdigit.control.thesis_designs",
        "thesis_design": "flexdigit.control.thesis_designs",
        "Chapter4Study": "flexdigit.control.chapter4_studies",
        "chapter4_study": "flexdigit.control.chapter4_studies",
    },
)

"""The rig (thesis chapter 5): the Rig contract, the real-time loop and its log, safety, controllers by name.

- :mod:`~flexdigit.rig.base`: the :class:`Rig` contract, :class:`Reading`, ``open_rig(url)`` (``sim``, ``serial://``,
  ``daq://``, ``stream://``, ``replay://``);
- :mod:`~flexdigit.rig.loop`: ``run_loop``, read -> controller -> command -> log on absolute deadlines;
- :mod:`~flexdigit.rig.sample_log`: the loop's JSON-lines log, written and read back (``read_log``);
- :mod:`~flexdigit.rig.safety`: the runaway guard; :mod:`~flexdigit.rig.controllers`: ``make_controller(name, rig)``;
- :mod:`~flexdigit.rig.rotation`, :mod:`~flexdigit.rig.rotation_reference`: the gauges -> beam rotation map;
- :mod:`~flexdigit.rig.pacing`: ``WallPacer``, a paced backend's simulation kept at the wall clock's time;
- :mod:`~flexdigit.rig.recording`: MCAP recordings; :mod:`~flexdigit.rig.step_test`: the closed-loop step test;
- :mod:`~flexdigit.rig.chapter5_studies`: what report chapter 5 shows;
- :mod:`flexdigit.rig.backends`: the backends and their transports.

Every public name below is imported from its module on first use.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "Reading": "flexdigit.rig.base",
        "Rig": "flexdigit.rig.base",
        "open_rig": "flexdigit.rig.base",
        "BACKENDS": "flexdigit.rig.base",
        "LoopController": "flexdigit.rig.loop",
        "LoopResult": "flexdigit.rig.loop",
        "run_loop": "flexdigit.rig.loop",
        "SampleLog": "flexdigit.rig.sample_log",
        "read_log": "flexdigit.rig.sample_log",
        "RunawayGuard": "flexdigit.rig.safety",
        "default_guard": "flexdigit.rig.safety",
        "CONTROLLERS": "flexdigit.rig.controllers",
        "make_controller": "flexdigit.rig.controllers",
        "RotationEstimator": "flexdigit.rig.rotation",
        "calibrate_rotation": "flexdigit.rig.rotation",
        "make_rotation_map": "flexdigit.rig.rotation",
        "WallPacer": "flexdigit.rig.pacing",
        "Recording": "flexdigit.rig.recording",
        "read_recording": "flexdigit.rig.recording",
        "StepTest": "flexdigit.rig.step_test",
        "StepMetrics": "flexdigit.rig.step_test",
        "run_figure": "flexdigit.rig.run_plot",
        "Chapter5Study": "flexdigit.rig.chapter5_studies",
        "chapter5_study": "flexdigit.rig.chapter5_studies",
    },
)

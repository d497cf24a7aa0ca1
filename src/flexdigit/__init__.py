"""flexdigit: the cable-actuated flexible digit of Ward's 2004 MPhil thesis, as software.

Layout (data flows one way): ``params`` -> ``models`` -> ``twin`` -> ``identify`` -> ``control`` -> ``rig`` ->
(``tactile``, ``shape``) -> ``palpation`` -> ``calibrate`` -> (``live``, ``studies``) -> ``report``; one command,
``flexdigit``, with a module per sub-command (``flexdigit.cli``). Each domain exports its public names
(``from flexdigit.control import hinf_riccati``); the few a user starts from are here too::

    import flexdigit

    rig = flexdigit.open_rig("sim")                      # the digital twin behind the Rig contract
    loop = flexdigit.run_loop(rig, flexdigit.make_controller("digital20", rig), 30.0, 2.0)  # guarded
    # without a rig, the twin set up for the protocol as `flexdigit collect thesis-6.1` sets it up: the same data
    dataset = flexdigit.collect(flexdigit.load_protocol("thesis-6.1"), out="thesis-6.1.parquet")

Everything is imported on first use: ``import flexdigit`` loads no domain.
"""

from flexdigit._lazy import lazy_exports

__version__ = "0.1.0"

#: The objects a user starts from, and the domains, each imported on first use (PEP 562).
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "RigParams": "flexdigit.params",
        "load_params": "flexdigit.params",
        "Twin": "flexdigit.twin.twin",
        "open_rig": "flexdigit.rig.base",
        "run_loop": "flexdigit.rig.loop",
        "stop_on_signals": "flexdigit.interrupts",
        "make_controller": "flexdigit.rig.controllers",
        "load_protocol": "flexdigit.tactile.protocols",
        "collect": "flexdigit.tactile.runner",
        "read_timeseries": "flexdigit.identify.timeseries",
        "reproduce": "flexdigit.report.build",
        **{
            domain: f"flexdigit.{domain}"
            for domain in (
                "params",
                "reference",
                "models",
                "twin",
                "identify",
                "control",
                "rig",
                "tactile",
                "shape",
                "palpation",
                "calibrate",
                "live",
                "studies",
                "report",
            )
        },
    },
)

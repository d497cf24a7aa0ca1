"""The surgeon's view: the live page and its server (thesis 1.1, 8).

:class:`~flexdigit.live.session.LiveSession` runs a rig and estimates as it goes; :func:`~flexdigit.live.server.serve`
shows it in a browser (``flexdigit live``). Every public name below is imported from its module on first use.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "FoxgloveStream": "flexdigit.live.foxglove_stream",
        "stream_motion": "flexdigit.live.foxglove_stream",
        "make_robot_app": "flexdigit.live.robot_page",
        "motion_frames": "flexdigit.live.robot_page",
        "serve_robot": "flexdigit.live.robot_page",
        "LiveSession": "flexdigit.live.session",
        "make_app": "flexdigit.live.server",
        "serve": "flexdigit.live.server",
    },
)

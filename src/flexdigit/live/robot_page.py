"""The live page of a tendon robot in 3D: ``flexdigit live --robot ROBOT --tension-n T1,...``.

The robot released into the tensions (:func:`flexdigit.tdcr.simulate`) is served as ``/motion.json`` (the
backbone and every tendon's path at 50 frames a second, metres, the base frame) with a page that draws it with
three.js (vendored from npm into the package data by ``make three``: nothing is fetched from a CDN), replaying
the motion at its own pace. It listens on this machine only unless ``allow_remote``.
"""

from __future__ import annotations

import sys
from importlib import resources

import numpy as np

from flexdigit.errors import DataFileError
from flexdigit.live.server import bind, check_host

__all__ = ["motion_frames", "make_robot_app", "serve_robot"]

_STATIC = resources.files("flexdigit.live") / "static"


def motion_frames(robot, motion, *, rate_hz: float = 50.0) -> dict:
    """The page's ``/motion.json``: ``t_s``, ``backbone_m`` (frames, nodes, 3), ``tendons_m`` (frames, tendons,
    its disks + 1, 3), at ``rate_hz`` (the motion's nearest step to each frame)."""
    t_s = np.asarray(motion.t_s)
    wanted = np.arange(0.0, t_s[-1] + 1e-12, 1.0 / rate_hz)
    picks = np.clip(np.searchsorted(t_s, wanted), 0, t_s.size - 1)
    positions, rotations = motion.positions_m[picks], motion.rotations[picks]
    holes = positions[:, :, None, :] + np.einsum("fnij,tj->fnti", rotations, robot.routing_m)
    tendons = [[holes[f, : t.disk + 1, k].tolist() for k, t in enumerate(robot.tendons)] for f in range(picks.size)]
    return {
        "robot": robot.name,
        "length_m": robot.length_m,
        "t_s": t_s[picks].tolist(),
        "backbone_m": positions.tolist(),
        "tendons_m": tendons,
    }


def make_robot_app(frames: dict):
    """The Starlette app: the page, its script, the vendored three.js and ``/motion.json``."""
    from starlette.applications import Starlette
    from starlette.responses import FileResponse, JSONResponse
    from starlette.routing import Mount, Route
    from starlette.staticfiles import StaticFiles

    if not (_STATIC / "vendor" / "three.module.js").is_file():
        raise DataFileError(
            f"{_STATIC / 'vendor' / 'three.module.js'} is missing: `make three` vendors three.js from npm"
        )

    async def page(request):
        return FileResponse(str(_STATIC / "robot.html"))

    async def data(request):
        return JSONResponse(frames)

    routes = [Route("/", page), Route("/motion.json", data), Mount("/static", StaticFiles(directory=str(_STATIC)))]
    return Starlette(routes=routes)


def serve_robot(frames: dict, host: str = "127.0.0.1", port: int = 8050, *, allow_remote: bool = False) -> None:
    """Serve the page until Ctrl-C (or SIGTERM)."""
    import uvicorn

    check_host(host, allow_remote)
    app = make_robot_app(frames)
    sock = bind(host, port)
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{sock.getsockname()[1]}/"
    print(f"flexdigit live: {url} ({frames['robot']} in 3D); Ctrl-C to stop", file=sys.stderr, flush=True)
    config = uvicorn.Config(app, log_level="warning", lifespan="off", access_log=False, timeout_graceful_shutdown=2)
    uvicorn.Server(config).run(sockets=[sock])

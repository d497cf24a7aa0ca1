"""A tendon robot's motion streamed live to Foxglove over its WebSocket protocol (foxglove-sdk).

``flexdigit live --foxglove --robot ROBOT --tension-n T1,...`` simulates the robot released into those tensions
(:func:`flexdigit.tdcr.simulate`) and streams it, at the pace of its simulated time, as ``foxglove.SceneUpdate``
messages on the topic ``/tdcr/scene`` (the same messages as a recording's, :func:`flexdigit.tdcr.scene_update`;
``jsonschema`` encoding with Foxglove's published schema). Foxglove (app or web) connects with "Open connection"
-> ``ws://127.0.0.1:8765`` and shows the backbone, tendons and tensions in its 3D panel.

The server is foxglove-sdk's own (Foxglove's reference implementation of ``foxglove.websocket.v1``), in its own
``foxglove.Context`` so that two streams in one process do not mix; it listens on this machine only unless
``allow_remote`` (the live page's rule, :func:`flexdigit.live.server.check_host`).

Examples
--------
>>> from flexdigit.tdcr import ROBOTS, solve_statics
>>> robot = ROBOTS["rao2021"]
>>> held = solve_statics(robot, [4, 0, 0, 0, 2, 0])
>>> with FoxgloveStream(port=0) as stream:
...     stream.publish(robot, held.positions_m, held.rotations, 0.0, tensions_n=[4, 0, 0, 0, 2, 0])
...     stream.port > 0
True
"""

from __future__ import annotations

import json
import threading
import time

import numpy as np

from flexdigit.live.server import check_host
from flexdigit.tdcr.scene import scene_update, scene_update_schema

__all__ = ["SCENE_TOPIC", "FoxgloveStream", "stream_motion"]

#: The topic of the scene, as in recordings (:mod:`flexdigit.tdcr.scene`)
SCENE_TOPIC = "/tdcr/scene"


class FoxgloveStream:
    """A Foxglove WebSocket server with one ``foxglove.SceneUpdate`` channel; a context manager (closes the server).

    Parameters
    ----------
    host : str
        Address to listen on (default this machine only).
    port : int
        TCP port; 0 asks the system for a free one (:attr:`port` says which). Foxglove's default is 8765.
    allow_remote : bool
        Allow a ``host`` other machines can reach.
    """

    def __init__(self, *, host: str = "127.0.0.1", port: int = 8765, allow_remote: bool = False) -> None:
        import foxglove

        check_host(host, allow_remote)
        self._context = foxglove.Context()
        schema = foxglove.Schema(
            name="foxglove.SceneUpdate", encoding="jsonschema", data=json.dumps(scene_update_schema()).encode()
        )
        self._server = foxglove.start_server(name="flexdigit", host=host, port=port, context=self._context)
        self._channel = foxglove.Channel(SCENE_TOPIC, schema=schema, message_encoding="json", context=self._context)

    @property
    def port(self) -> int:
        return int(self._server.port)

    def publish(self, robot, positions_m, rotations, t_s: float, *, tensions_n=None, point_loads=()) -> None:
        """Send one scene: the robot in this shape at time ``t_s`` (s)."""
        message = scene_update(robot, positions_m, rotations, t_s=t_s, tensions_n=tensions_n, point_loads=point_loads)
        self._channel.log(json.dumps(message).encode(), log_time=int(round(t_s * 1e9)))

    def close(self) -> None:
        self._channel.close()
        self._server.stop()

    def __enter__(self) -> FoxgloveStream:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def stream_motion(
    stream: FoxgloveStream,
    robot,
    motion,
    *,
    tensions_n=None,
    rate_hz: float = 50.0,
    stop: threading.Event | None = None,
) -> int:
    """Publish a :class:`~flexdigit.tdcr.DynamicSolution` at the pace of its simulated time, ``rate_hz`` scenes a
    second (the motion's nearest step to each), until its end or ``stop`` is set. Returns the scenes sent."""
    t_s = np.asarray(motion.t_s)
    frames = np.arange(0.0, t_s[-1] + 1e-12, 1.0 / rate_hz)
    start = time.monotonic()
    sent = 0
    for frame_t in frames:
        if stop is not None and stop.is_set():
            break
        wait = start + frame_t - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        k = int(np.clip(np.searchsorted(t_s, frame_t), 0, t_s.size - 1))
        stream.publish(robot, motion.positions_m[k], motion.rotations[k], float(t_s[k]), tensions_n=tensions_n)
        sent += 1
    return sent

"""A tendon robot's motion as an MCAP recording that opens with a 3D view in Foxglove.

The recording holds two channels, both ``jsonschema``-encoded JSON:

- ``/tdcr/scene``: ``foxglove.SceneUpdate`` messages (the schema is Foxglove's published one, shipped with the
  package), one per time: the backbone as a line strip, each tendon as a line strip through its disk holes, the
  tension each tendon pulls its termination disk with as an arrow (along the tendon, towards the base, its length
  ``arrow_m_per_n`` per newton), and any point loads (tip force, contacts) as arrows (their length scaled alike).
  Everything is in the frame ``tdcr_base`` (the base frame: z along the unloaded backbone; metres).
- ``/tdcr/tip``: the tip's position and frame, a small schema of flexdigit's own, for plots.

Metadata: ``flexdigit.tdcr`` (the robot's description and the loads). The file is written atomically (a
temporary beside it, renamed over it when complete) and refused if it exists unless ``force``.

Examples
--------
>>> import tempfile, pathlib
>>> from flexdigit.tdcr import ROBOTS, solve_statics
>>> robot = ROBOTS["rao2021"]
>>> sol = solve_statics(robot, [4, 0, 0, 0, 2, 0])
>>> path = write_recording(pathlib.Path(tempfile.mkdtemp()) / "rao.mcap", robot, sol, tensions_n=[4, 0, 0, 0, 2, 0])
>>> path.suffix
'.mcap'
"""

from __future__ import annotations

import json
import os
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from flexdigit._io import atomic_write
from flexdigit.errors import ParameterError
from flexdigit.tdcr.description import Robot

__all__ = ["SCENE_TOPIC", "TIP_TOPIC", "FRAME_ID", "scene_update", "scene_update_schema", "write_recording"]

SCENE_TOPIC = "/tdcr/scene"
TIP_TOPIC = "/tdcr/tip"
FRAME_ID = "tdcr_base"

_BACKBONE = {"r": 0.85, "g": 0.85, "b": 0.85, "a": 1.0}
_TENDON = {"r": 0.2, "g": 0.6, "b": 1.0, "a": 0.8}
_TENSION = {"r": 1.0, "g": 0.35, "b": 0.1, "a": 1.0}
_LOAD = {"r": 0.2, "g": 0.9, "b": 0.3, "a": 1.0}
_IDENTITY = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
_ORIGIN = {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": _IDENTITY}

TIP_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "flexdigit.TdcrTip",
    "description": "The tip of a tendon robot: position (m) and frame (rows of the rotation, columns the tip axes).",
    "type": "object",
    "properties": {
        "t": {"type": "number", "description": "time, s"},
        "position_m": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
        "rotation": {
            "type": "array",
            "items": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
            "minItems": 3,
            "maxItems": 3,
        },
    },
    "required": ["t", "position_m", "rotation"],
}


def scene_update_schema() -> dict[str, Any]:
    """Foxglove's published JSON Schema of ``foxglove.SceneUpdate`` (foxglove-sdk, schemas/jsonschema)."""
    text = resources.files("flexdigit.tdcr").joinpath("foxglove_SceneUpdate.json").read_text(encoding="utf-8")
    return json.loads(text)


def _time(t_s: float) -> dict[str, int]:
    ns = max(int(round(float(t_s) * 1e9)), 0)
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _vec(p) -> dict[str, float]:
    return {"x": float(p[0]), "y": float(p[1]), "z": float(p[2])}


def _quat_x_to(d: np.ndarray) -> dict[str, float]:
    """The quaternion turning +x onto the unit vector ``d`` (Foxglove's arrows point along their +x)."""
    w, v = 1.0 + d[0], np.array([0.0, -d[2], d[1]])  # (1 + x.d, x cross d), normalised: the half-angle rotation
    if w < 1e-9:  # d is -x: half a turn about z
        return {"x": 0.0, "y": 0.0, "z": 1.0, "w": 0.0}
    n = float(np.sqrt(w * w + v @ v))
    return {"x": v[0] / n, "y": v[1] / n, "z": v[2] / n, "w": w / n}


def _arrow(tail, vector, scale_m_per_n: float, diameter_m: float, color) -> dict[str, Any] | None:
    vector = np.asarray(vector, dtype=float)
    magnitude = float(np.linalg.norm(vector))
    if magnitude == 0.0 or not np.isfinite(magnitude):
        return None
    length = magnitude * scale_m_per_n
    head = min(0.3 * length, 4 * diameter_m)
    return {
        "pose": {"position": _vec(tail), "orientation": _quat_x_to(vector / magnitude)},
        "shaft_length": length - head,
        "shaft_diameter": diameter_m,
        "head_length": head,
        "head_diameter": 2.5 * diameter_m,
        "color": color,
    }


def _line(points, thickness_m: float, color) -> dict[str, Any]:
    return {
        "type": 0,  # LINE_STRIP
        "pose": _ORIGIN,
        "thickness": thickness_m,
        "scale_invariant": False,
        "points": [_vec(p) for p in points],
        "color": color,
        "colors": [],
        "indices": [],
    }


def _entity(entity_id: str, t_s: float, *, lines=(), arrows=()) -> dict[str, Any]:
    return {
        "timestamp": _time(t_s),
        "frame_id": FRAME_ID,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": False,
        "metadata": [],
        "arrows": list(arrows),
        "cubes": [],
        "spheres": [],
        "cylinders": [],
        "lines": list(lines),
        "triangles": [],
        "texts": [],
        "models": [],
    }


def scene_update(
    robot: Robot,
    positions_m,
    rotations,
    *,
    t_s: float = 0.0,
    tensions_n=None,
    point_loads=(),
    arrow_m_per_n: float = 0.01,
) -> dict[str, Any]:
    """One ``foxglove.SceneUpdate`` of the robot in a given shape.

    Parameters
    ----------
    robot : Robot
    positions_m : array (n, 3)
        Backbone nodes, world frame: the base, then every disk (``nodes_per_disk=1``, as the solvers' default).
    rotations : array (n, 3, 3)
        Their frames (columns: the cross-section's axes in the world frame).
    t_s : float
        The message's time (s).
    tensions_n : array (n_tendons,), optional
        Tendon tensions (N): each drawn as an arrow at its termination.
    point_loads : sequence of (point, force) pairs
        More arrows (tip force, contacts), world frame, m and N.
    arrow_m_per_n : float
        Arrow length per newton (m/N).
    """
    positions_m = np.asarray(positions_m, dtype=float)
    rotations = np.asarray(rotations, dtype=float)
    n = robot.disk_count + 1
    if positions_m.shape != (n, 3) or rotations.shape != (n, 3, 3):
        raise ParameterError(
            f"scene_update: {robot.name!r} has {n} nodes (base and {n - 1} disks): positions_m must be ({n}, 3) and "
            f"rotations ({n}, 3, 3). Got {positions_m.shape} and {rotations.shape} instead (nodes_per_disk must be 1)."
        )
    radius = robot.backbone.radius_m
    holes = positions_m[:, None, :] + np.einsum("nij,tj->nti", rotations, robot.routing_m)  # (n, tendons, 3)
    tendon_lines = [_line(holes[: t.disk + 1, k], radius, _TENDON) for k, t in enumerate(robot.tendons)]
    arrows = []
    if tensions_n is not None:
        tensions = np.asarray(tensions_n, dtype=float).reshape(-1)
        for k, (tendon, tension) in enumerate(zip(robot.tendons, tensions, strict=True)):
            end, before = holes[tendon.disk, k], holes[tendon.disk - 1, k]
            towards_base = (before - end) / max(float(np.linalg.norm(before - end)), 1e-300)
            arrows.append(_arrow(end, tension * towards_base, arrow_m_per_n, radius, _TENSION))
    loads = [_arrow(p, f, arrow_m_per_n, radius, _LOAD) for p, f in point_loads]
    entities = [
        _entity("backbone", t_s, lines=[_line(positions_m, 2 * radius, _BACKBONE)]),
        _entity("tendons", t_s, lines=tendon_lines),
        _entity("tensions", t_s, arrows=[a for a in arrows if a is not None]),
        _entity("loads", t_s, arrows=[a for a in loads if a is not None]),
    ]
    return {"deletions": [], "entities": entities}


def write_recording(
    path: str | os.PathLike,
    robot: Robot,
    solution,
    *,
    tensions_n,
    tip_force_n=None,
    arrow_m_per_n: float = 0.01,
    force: bool = False,
) -> Path:
    """Write a static solution or a time response as an MCAP recording (see the module docstring).

    Parameters
    ----------
    path : path-like
        The ``.mcap`` file; refused if it exists unless ``force``.
    robot : Robot
    solution : StaticSolution or DynamicSolution
        Solved with ``nodes_per_disk=1`` (the default). A static solution is one message at t = 0.
    tensions_n : array (n_tendons,)
        The tendon tensions (constant over a time response).
    tip_force_n : array (3,), optional
        A tip force, world frame, drawn as an arrow at the tip.

    Returns
    -------
    Path
        Where the recording was written.
    """
    from mcap.writer import CompressionType, Writer

    if hasattr(solution, "t_s"):
        times, positions, rotations = solution.t_s, solution.positions_m, solution.rotations
    else:
        times, positions, rotations = np.zeros(1), solution.positions_m[None], solution.rotations[None]
    tensions = np.asarray(tensions_n, dtype=float).reshape(-1)
    if tensions.size != len(robot.tendons):
        raise ParameterError(
            f"write_recording: {robot.name!r} has {len(robot.tendons)} tendons. Got {tensions.size} tensions."
        )
    tip_force = None if tip_force_n is None else np.asarray(tip_force_n, dtype=float).reshape(3)
    loads_meta = {"tensions_n": tensions.tolist(), "tip_force_n": None if tip_force is None else tip_force.tolist()}
    with atomic_write(path, "wb", force=force) as fh:
        writer = Writer(fh, compression=CompressionType.ZSTD)
        writer.start(profile="", library="flexdigit tdcr")
        scene_schema = writer.register_schema(
            "foxglove.SceneUpdate", "jsonschema", json.dumps(scene_update_schema()).encode()
        )
        tip_schema = writer.register_schema(TIP_SCHEMA["title"], "jsonschema", json.dumps(TIP_SCHEMA).encode())
        scene_channel = writer.register_channel(SCENE_TOPIC, "json", scene_schema)
        tip_channel = writer.register_channel(TIP_TOPIC, "json", tip_schema)
        meta = {"robot": robot.to_dict(), **loads_meta}
        writer.add_metadata("flexdigit.tdcr", {k: json.dumps(v) for k, v in meta.items()})
        for k, t in enumerate(times):
            stamp = int(round(float(t) * 1e9))
            loads = [] if tip_force is None else [(positions[k, -1], tip_force)]
            update = scene_update(
                robot,
                positions[k],
                rotations[k],
                t_s=t,
                tensions_n=tensions,
                point_loads=loads,
                arrow_m_per_n=arrow_m_per_n,
            )
            tip = {"t": float(t), "position_m": positions[k, -1].tolist(), "rotation": rotations[k, -1].tolist()}
            for channel, message in ((scene_channel, update), (tip_channel, tip)):
                data = json.dumps(message, allow_nan=False, separators=(",", ":")).encode()
                writer.add_message(channel, log_time=stamp, data=data, publish_time=stamp, sequence=k)
        writer.finish()
    return Path(path)

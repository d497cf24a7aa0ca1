"""Turn results (numpy arrays, complex numbers, dataclasses, paths) into plain JSON values.

Every ``--json`` output and ``results.json`` goes through :func:`to_jsonable`, so all commands write
complex numbers the same way: ``{"re": x, "im": y}``; NaN and infinity become ``null``.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np


def to_jsonable(obj: object) -> object:
    """Return ``obj`` as nested dicts, lists, str, int, float, bool or None.

    Examples
    --------
    >>> to_jsonable({"pole": -1 + 2j, "x": np.array([1.0, np.nan])})
    {'pole': {'re': -1.0, 'im': 2.0}, 'x': [1.0, None]}
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, (int, np.integer)) and not isinstance(obj, bool):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        return value if math.isfinite(value) else None
    if isinstance(obj, (complex, np.complexfloating)):
        return {"re": to_jsonable(obj.real), "im": to_jsonable(obj.imag)}
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.ndarray):
        return [to_jsonable(v) for v in obj.tolist()] if obj.ndim else to_jsonable(obj.item())
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, enum.Enum):
        return to_jsonable(obj.value)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [to_jsonable(v) for v in obj]
    if hasattr(obj, "to_dict"):
        return to_jsonable(obj.to_dict())
    raise TypeError(f"cannot convert {type(obj).__name__} to JSON")


def fingerprint(obj: object) -> str:
    """A short, stable hash (16 hex digits of SHA-256) of ``obj``'s JSON form, keys sorted: two settings with the
    same fingerprint are the same settings.

    Examples
    --------
    >>> fingerprint({"b": 1, "a": [1.0, 2.0]}) == fingerprint({"a": np.array([1.0, 2.0]), "b": 1})
    True
    """
    import hashlib
    import json

    text = json.dumps(to_jsonable(obj), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]

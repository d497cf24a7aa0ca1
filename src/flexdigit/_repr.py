"""Short reprs: what an object is and its key figures, in one or a few lines, never a page of arrays.

A plant, a design, a loop's result or a data set prints as python-control's ``TransferFunction`` summary or a
scikit-learn estimator does: its class and the figures a reader looks for, units after the value or in the key
(``Plant(variant='consistent', order=4, dc_gain=0.0175 m/command, ...)``). Classes write ``__repr__`` as one call to
:func:`summary` naming their figures; a dataclass keeps that ``__repr__`` (``dataclass`` only adds one when the
class has none).

Examples
--------
>>> import numpy as np
>>> class Fit:
...     def __repr__(self):
...         return summary(self, wn=(12.3456, "rad/s"), zeta=0.0512, poles=np.array([-1 + 2j, -1 - 2j]))
>>> Fit()
Fit(wn=12.35 rad/s, zeta=0.0512, poles=[-1+2j, -1-2j])
"""

from __future__ import annotations

import dataclasses
import numbers
from pathlib import Path

import numpy as np

#: A line wraps after this many characters; a repr stays a few lines at most.
WIDTH = 110
#: Arrays up to this many elements are printed, larger ones by their shape.
MAX_ELEMENTS = 6
#: Significant digits of a float.
DIGITS = 4


def _number(x) -> str:
    if isinstance(x, bool | np.bool_):
        return str(bool(x))
    if isinstance(x, numbers.Integral):
        return str(int(x))
    if isinstance(x, numbers.Real):
        return f"{float(x):.{DIGITS}g}"
    z = complex(x)
    if z.imag == 0:
        return f"{z.real:.{DIGITS}g}"
    return f"{z.real:.{DIGITS}g}{z.imag:+.{DIGITS}g}j"


def _value(v) -> str:
    """One value, short: numbers to 4 significant digits, small arrays in full, large ones by shape and dtype."""
    if isinstance(v, tuple) and len(v) == 2 and isinstance(v[1], str) and not isinstance(v[0], str):
        return f"{_value(v[0])} {v[1]}"  # (value, unit)
    if v is None or isinstance(v, str | Path):
        return repr(str(v) if isinstance(v, Path) else v)
    if isinstance(v, numbers.Number | np.number | np.bool_):
        return _number(v)
    if isinstance(v, np.ndarray | list | tuple):
        a = np.asarray(v) if not isinstance(v, np.ndarray) else v
        if a.dtype.kind in "biufc" and a.size <= MAX_ELEMENTS:
            return "[" + ", ".join(_number(x) for x in a.ravel()) + "]"
        if a.dtype.kind in "biufc":
            return f"<{a.dtype.name} array {'x'.join(map(str, a.shape))}>"
        if len(v) <= MAX_ELEMENTS and all(isinstance(x, str) for x in v):
            return "[" + ", ".join(repr(x) for x in v) + "]"
        return f"<{len(v)} items>"
    if isinstance(v, dict):
        shown = {k: _value(x) for k, x in v.items()} if len(v) <= MAX_ELEMENTS // 2 else {}
        if shown and all(len(x) <= 12 for x in shown.values()):
            return "{" + ", ".join(f"{k!r}: {x}" for k, x in shown.items()) + "}"
        return f"<{len(v)} entries>"
    text = repr(v)
    return text if "\n" not in text and len(text) <= WIDTH // 2 else f"<{type(v).__name__}>"


def summary(obj, **figures) -> str:
    """``Name(key=value, ...)`` for ``obj``: its class name and ``figures``, wrapped at :data:`WIDTH` characters.

    A figure is a number, a string, an array (shown in full up to :data:`MAX_ELEMENTS` elements, else by shape), an
    object (its repr when short, else its class name) or a ``(value, "unit")`` pair. None-valued figures are shown.
    """
    name = obj if isinstance(obj, str) else type(obj).__name__
    parts = [f"{key}={_value(value)}" for key, value in figures.items()]
    lines, line = [], name + "("
    for i, part in enumerate(parts):
        text = part + (", " if i < len(parts) - 1 else "")
        if len(line) + len(text) > WIDTH and line.strip() and not line.endswith("("):
            lines.append(line.rstrip())
            line = "    "
        line += text
    return "\n".join([*lines, line + ")"])


def fields_summary(self) -> str:
    """Every field of the dataclass ``self`` by :func:`summary` (arrays by shape, nested results by class): a
    complete repr in a few lines for results with many fields, used as ``__repr__ = fields_summary``."""
    return summary(self, **{f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.repr})


def differences(obj, reference, prefix: str = "") -> dict:
    """The fields where the dataclass ``obj`` differs from ``reference``, by dotted name (nested dataclasses
    followed): the complete and short description of a parameter set next to its defaults.

    Examples
    --------
    >>> from flexdigit.params import RigParams, Sensors
    >>> differences(RigParams().replace(sensors=Sensors(bridge="full")), RigParams())
    {'sensors.bridge': 'full'}
    """
    out = {}
    for f in dataclasses.fields(obj):
        mine, theirs = getattr(obj, f.name), getattr(reference, f.name)
        if dataclasses.is_dataclass(mine) and type(mine) is type(theirs):
            out.update(differences(mine, theirs, f"{prefix}{f.name}."))
        elif not _equal(mine, theirs):
            out[prefix + f.name] = mine
    return out


def _equal(a, b) -> bool:
    try:
        return bool(np.array_equal(np.asarray(a, dtype=object), np.asarray(b, dtype=object)))
    except (TypeError, ValueError):
        return a == b

"""One validator per kind of quantity: each copies, checks and names the culprit.

Messages follow scikit-learn's ``_param_validation`` format::

    The 'gauge_positions_m' parameter of DigitGeometry must be increasing and inside (0, 0.27].
    Got [0.3] instead.

Validators raise :class:`flexdigit.errors.ParameterError` (a ``ValueError``) unless told otherwise, and never
use ``assert`` (it vanishes under ``python -O``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from numbers import Integral, Real

import numpy as np

from flexdigit.errors import ParameterError


def _fail(name: str, owner: str | None, expected: str, got: object, error: type[Exception]) -> None:
    where = f"The '{name}' parameter of {owner}" if owner else f"The '{name}' parameter"
    raise error(f"{where} must be {expected}. Got {got!r} instead.")


def check_real(
    value: object,
    name: str,
    owner: str | None = None,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    error: type[Exception] = ParameterError,
) -> float:
    """Return ``value`` as a finite float inside the given interval, or raise naming it.

    Examples
    --------
    >>> check_real(0.5, "zeta", "SecondOrder", low=0, high=1)
    0.5
    """
    if isinstance(value, bool) or not isinstance(value, Real):
        _fail(name, owner, "a real number", value, error)
    out = float(value)
    interval = _interval_text(low, high, low_open, high_open)
    if not math.isfinite(out):
        _fail(name, owner, f"a finite real number{interval}", value, error)
    if low is not None and (out < low or (low_open and out == low)):
        _fail(name, owner, f"a real number{interval}", value, error)
    if high is not None and (out > high or (high_open and out == high)):
        _fail(name, owner, f"a real number{interval}", value, error)
    return out


def check_positive(value: object, name: str, owner: str | None = None, **kwargs) -> float:
    """Return ``value`` as a finite float > 0, or raise naming it."""
    return check_real(value, name, owner, low=0.0, low_open=True, **kwargs)


def check_int(
    value: object,
    name: str,
    owner: str | None = None,
    *,
    low: int | None = None,
    high: int | None = None,
    error: type[Exception] = ParameterError,
) -> int:
    """Return ``value`` as an int inside ``[low, high]``, or raise naming it.

    Floats with an integral value (``8.0``) are accepted; ``8.5``, ``True`` and NaN are not.

    Examples
    --------
    >>> check_int(43, "command", "ServoBoard", low=0, high=254)
    43
    """
    interval = _interval_text(low, high, False, False)
    if isinstance(value, bool):
        _fail(name, owner, f"an integer{interval}", value, error)
    if isinstance(value, Integral):
        out = int(value)
    elif isinstance(value, Real) and math.isfinite(float(value)) and float(value).is_integer():
        out = int(value)
    else:
        _fail(name, owner, f"an integer{interval}", value, error)
    if (low is not None and out < low) or (high is not None and out > high):
        _fail(name, owner, f"an integer{interval}", value, error)
    return out


def check_choice(
    value: object,
    name: str,
    choices: Iterable[str],
    owner: str | None = None,
    *,
    error: type[Exception] = ParameterError,
) -> str:
    """Return ``value`` if it is one of ``choices``, or raise naming it and the choices."""
    options = tuple(choices)
    if not isinstance(value, str) or value not in options:
        _fail(name, owner, "one of " + ", ".join(repr(c) for c in options), value, error)
    return value


def check_array(
    value: object,
    name: str,
    owner: str | None = None,
    *,
    ndim: int | None = None,
    shape: Sequence[int | None] | None = None,
    min_length: int | None = None,
    finite: bool = True,
    increasing: bool = False,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    error: type[Exception] = ParameterError,
) -> np.ndarray:
    """Return a float copy of ``value`` after checking its shape and values, or raise naming it.

    Examples
    --------
    >>> check_array([0.045, 0.135], "gauge_positions_m", increasing=True, low=0).tolist()
    [0.045, 0.135]
    """
    try:
        out = np.array(value, dtype=float, copy=True)
    except (TypeError, ValueError):
        _fail(name, owner, "an array of real numbers", value, error)
    got = out.tolist()
    if ndim is not None and out.ndim != ndim:
        _fail(name, owner, f"a {ndim}-dimensional array", got, error)
    if shape is not None:
        ok = out.ndim == len(shape) and all(s is None or s == n for s, n in zip(shape, out.shape, strict=True))
        if not ok:
            text = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
            _fail(name, owner, f"an array of shape {text}", got, error)
    if min_length is not None and (out.ndim == 0 or out.shape[0] < min_length):
        _fail(name, owner, f"an array of at least {min_length} values", got, error)
    if finite and not np.all(np.isfinite(out)):
        _fail(name, owner, "finite (no NaN or infinity)", got, error)
    interval = _interval_text(low, high, low_open, high_open)
    if increasing and out.size > 1 and not np.all(np.diff(out.ravel()) > 0):
        _fail(name, owner, "strictly increasing" + (f" and{interval}" if interval else ""), got, error)
    with np.errstate(invalid="ignore"):
        if low is not None and np.any((out < low) | ((out == low) if low_open else False)):
            _fail(name, owner, f"an array with values{interval}", got, error)
        if high is not None and np.any((out > high) | ((out == high) if high_open else False)):
            _fail(name, owner, f"an array with values{interval}", got, error)
    return out


def _interval_text(low, high, low_open, high_open) -> str:
    if low is None and high is None:
        return ""
    left = "(" if low_open or low is None else "["
    right = ")" if high_open or high is None else "]"
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    return f" inside {left}{lo}, {hi}{right}"

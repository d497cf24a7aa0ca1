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


# Batches (the twin's load cases, a command repeated over every repetition) would make check_array's message a
# wall of numbers: check_values names only the offending values instead.
#: Distinct offending values quoted in a message; the rest are counted.
SHOWN = 3


def describe_values(values) -> str:
    """The distinct values in ``values``, at most :data:`SHOWN`, e.g. ``"300"`` or
    ``"[-1, 300, 400, ...] (5 distinct values)"``: NaN and infinities first (the likeliest mistake), then sorted."""
    flat = np.asarray(values, dtype=float).ravel()
    distinct = np.unique(flat)  # sorted, NaNs collapsed to one and last
    finite = np.isfinite(distinct)
    distinct = np.concatenate([distinct[~finite], distinct[finite]])
    text = [f"{v:g}" for v in distinct[:SHOWN]]
    if distinct.size == 1:
        return text[0]
    if distinct.size <= SHOWN:
        return "[" + ", ".join(text) + "]"
    return "[" + ", ".join(text) + f", ...] ({distinct.size} distinct values)"


def check_values(
    value,
    name: str,
    owner: str,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    integer: bool = False,
    unit: str = "",
    note: str = "",
) -> np.ndarray:
    """Return ``value`` as a float array of finite numbers in the interval, or raise naming only the bad ones.

    Parameters
    ----------
    value : array_like
        Any shape (a scalar is a 0-d array).
    name, owner : str
        The parameter and the function or option it belongs to (for the message).
    low, high, low_open, high_open : optional
        The allowed interval (closed unless told).
    integer : bool
        Values must also be whole numbers (servo commands).
    unit : str
        Appended to the interval in the message (``"m"``, ``"cm from the tip"``).
    note : str
        A reason appended in parentheses (``"a load beyond the tip"``).

    Raises
    ------
    ParameterError
        ``The 'commands' parameter of static_load_test must be integers inside [0, 254]. Got 300 instead.``

    Examples
    --------
    >>> check_values([8, 20], "commands", "static_load_test", low=0, high=254, integer=True).tolist()
    [8.0, 20.0]
    """
    kind = "integers" if integer else "finite real numbers"
    interval = _interval_text(low, high, low_open, high_open)
    expected = kind + interval + (f" {unit}" if unit and interval else "") + (f" ({note})" if note else "")
    try:
        out = np.array(value, dtype=float, copy=True)
    except (TypeError, ValueError):
        raise ParameterError(
            f"The '{name}' parameter of {owner} must be {kind}{interval}. Got a value of type "
            f"{type(value).__name__} that is not numeric instead."
        ) from None
    bad = ~np.isfinite(out)
    with np.errstate(invalid="ignore"):
        if low is not None:
            bad |= (out < low) | ((out == low) if low_open else False)
        if high is not None:
            bad |= (out > high) | ((out == high) if high_open else False)
        if integer:
            bad |= out != np.round(out)
    if np.any(bad):
        raise ParameterError(
            f"The '{name}' parameter of {owner} must be {expected}. Got {describe_values(out[bad])} instead."
        )
    return out


def _interval_text(low, high, low_open, high_open) -> str:
    if low is None and high is None:
        return ""
    left = "(" if low_open or low is None else "["
    right = ")" if high_open or high is None else "]"
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    return f" inside {left}{lo}, {hi}{right}"

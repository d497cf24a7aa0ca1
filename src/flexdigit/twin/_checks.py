"""Validation of the twin's batched inputs (loads, positions, commands, forces) that names only the culprits.

:func:`flexdigit._validation.check_array` quotes the whole array it rejects, which for a batch of thousands of
load cases (or one bad command repeated over every repetition) is a wall of numbers. The twin's entry points
check their batches here instead: the message names the parameter, its owner, what was expected and the
offending values only (distinct, at most :data:`SHOWN`, with how many there were), in the scikit-learn format of
:mod:`flexdigit._validation`.
"""

from __future__ import annotations

import numpy as np

from flexdigit._validation import _interval_text
from flexdigit.errors import ParameterError

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

"""Parameter validation: constraints declared once, checked by one helper, named in one message format.

Messages follow scikit-learn's ``_param_validation`` format::

    The 'gauge_positions_m' parameter of DigitGeometry must be increasing and inside (0, 0.27].
    Got [0.3] instead.

Two layers, one format:

- **Declared constraints** (scikit-learn's ``_parameter_constraints`` and ``validate_params``): a function's or a
  class's parameters are declared once as a dict ``{"name": [constraint, ...]}`` of :class:`Interval`,
  :class:`Options`, :class:`Array`, :class:`Bool`, :class:`InstanceOf`, :class:`HasMethods`, :class:`Callable` or
  ``None`` (the value
  ``None`` allowed: "not given"; 0 is a value). :func:`validate_params` decorates a function; a frozen dataclass
  or an estimator calls :func:`check_params` on its own ``_parameter_constraints``. Every declaration is kept in
  :data:`DECLARED`, and ``tests/test_validation.py`` generates the invalid values of every one of them
  (:meth:`Constraint.invalid_values`) and checks that each is refused with this message, naming the parameter.
- **Validators** (``check_real``, ``check_int``, ``check_choice``, ``check_array``, ``check_values``): the checks
  the constraints run, also for what a declaration cannot say (one field bounded by another, a file's column).

Everything raises :class:`flexdigit.errors.ParameterError` (a ``ValueError``) unless told otherwise, and never
uses ``assert`` (it vanishes under ``python -O``).

Examples
--------
>>> from numbers import Integral, Real
>>> @validate_params({"hidden": [Interval(Integral, 1, None)], "tol": [Interval(Real, 0, None, closed="neither")]})
... def train(hidden, tol=1e-7):
...     return hidden, tol
>>> train(18.0)
(18, 1e-07)
>>> train(True)
Traceback (most recent call last):
...
flexdigit.errors.ParameterError: The 'hidden' parameter of train must be an integer inside [1, inf). Got True instead.
"""

from __future__ import annotations

import functools
import inspect
import math
import sys
from abc import ABC, abstractmethod
from collections.abc import Iterable, Sequence
from numbers import Integral, Real

import numpy as np

from flexdigit.errors import ParameterError


def shown_value(got: object) -> str:
    """A refused value as a message shows it: an integer in its digits (not ``1e+23``), a TOML date or time in its
    ISO form, a list of numbers as written (``[-1, 1, 2]``, not ``[-1.0, 1.0, 2.0]``), anything else by its repr;
    cut past 80 characters (a 400-digit integer from a client: named, not echoed).

    Examples
    --------
    >>> import datetime
    >>> shown_value(10**23), shown_value(datetime.date(1979, 5, 27)), shown_value([-1.0, 1.0, 2.5])
    ('100000000000000000000000', '1979-05-27 (a date)', '[-1, 1, 2.5]')
    """
    import datetime

    if isinstance(got, datetime.date | datetime.time):
        shown = f"{got.isoformat()} (a {'time' if isinstance(got, datetime.time) else 'date'})"
    elif isinstance(got, Integral) and not isinstance(got, bool):
        shown = str(int(got))
    elif isinstance(got, list) and got and all(isinstance(v, float) for v in _flat(got)):
        shown = _numbers(got)
    else:
        shown = repr(got)
    if len(shown) > 80:
        shown = f"{shown[:60]}... ({len(shown)} characters)"
    return shown


def _flat(values: list):
    for v in values:
        if isinstance(v, list):
            yield from _flat(v)
        else:
            yield v


def _numbers(values: list) -> str:
    """A nested list of floats as written: ``[-1, 0.5]``."""
    return "[" + ", ".join(_numbers(v) if isinstance(v, list) else f"{v:.12g}" for v in values) + "]"


def _fail(name: str, owner: str | None, expected: str, got: object, error: type[Exception], tail: str = ".") -> None:
    where = f"The '{name}' parameter of {owner}" if owner else f"The '{name}' parameter"
    raise error(f"{where} must be {expected}. Got {shown_value(got)} instead{tail}")


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
    try:
        out = float(value)
    except OverflowError:  # an integer beyond a float's range (JSON allows any number of digits)
        out = math.inf if value > 0 else -math.inf
    if not math.isfinite(out):
        _fail(name, owner, f"a finite real number{_interval_text(low, high, low_open, high_open)}", value, error)
    if (low is not None and (out < low or (low_open and out == low))) or (
        high is not None and (out > high or (high_open and out == high))
    ):
        _fail(name, owner, f"a real number{_interval_text(low, high, low_open, high_open)}", value, error)
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
    if isinstance(value, Integral) and not isinstance(value, bool):
        out = int(value)
    elif (
        isinstance(value, Real)
        and not isinstance(value, bool)
        and math.isfinite(float(value))
        and float(value).is_integer()
    ):
        out = int(value)
    else:
        out = None
    if out is None or (low is not None and out < low) or (high is not None and out > high):
        _fail(name, owner, f"an integer{_interval_text(low, high, False, False)}", value, error)
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


def _holds_text_or_truth(value: object) -> bool:
    """Whether ``value`` (a list, tuple or array, nested) holds a string or a boolean, which ``np.array(...,
    dtype=float)`` would silently read as a number (``["0.05"]`` as 0.05, ``[true]`` as 1.0)."""
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "bUS":
            return True
        return value.dtype.kind == "O" and any(_holds_text_or_truth(v) for v in value.ravel())
    if isinstance(value, list | tuple):
        return any(_holds_text_or_truth(v) for v in value)
    return isinstance(value, str | bytes | bool | np.bool_)


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
    unit: str = "",
    error: type[Exception] = ParameterError,
) -> np.ndarray:
    """Return a float copy of ``value`` after checking its shape and values, or raise naming it. With ``unit``, values
    outside ``low``..``high`` that a unit slip puts inside are refused naming it (``did you mean mm``, as
    :class:`Plausible` does).

    Examples
    --------
    >>> check_array([0.045, 0.135], "gauge_positions_m", increasing=True, low=0).tolist()
    [0.045, 0.135]
    """
    try:
        out = np.array(value, dtype=float, copy=True)
    except (TypeError, ValueError):
        _fail(name, owner, "an array of real numbers", value, error)
    if _holds_text_or_truth(value):  # numpy reads "0.05" and True as numbers: a file's typo, not a value
        _fail(name, owner, "an array of real numbers", value, error)

    def fail(expected: str, tail: str = "."):  # the message (and the array as a list in it) only built on failure
        _fail(name, owner, expected, out.tolist(), error, tail)

    if ndim is not None and out.ndim != ndim:
        fail(f"a {ndim}-dimensional array")
    if shape is not None:
        ok = out.ndim == len(shape) and all(s is None or s == n for s, n in zip(shape, out.shape, strict=True))
        if not ok:
            fail("an array of shape (" + ", ".join("any" if s is None else str(s) for s in shape) + ")")
    if min_length is not None and (out.ndim == 0 or out.shape[0] < min_length):
        fail(f"an array of at least {min_length} values")
    if finite and not np.isfinite(out).all():
        fail("finite (no NaN or infinity)")
    if increasing and out.size > 1 and not (np.diff(out.ravel()) > 0).all():
        interval = _interval_text(low, high, low_open, high_open)
        fail("strictly increasing" + (f" and{interval}" if interval else ""))
    with np.errstate(invalid="ignore"):
        if (low is not None and ((out < low) | ((out == low) if low_open else False)).any()) or (
            high is not None and ((out > high) | ((out == high) if high_open else False)).any()
        ):
            bad = ~((out >= low if low is not None else True) & (out <= high if high is not None else True))
            if low_open and low is not None:
                bad |= out == low
            if high_open and high is not None:
                bad |= out == high
            first = np.argwhere(bad)[0]
            where = ", ".join(str(int(i)) for i in first)
            interval = _interval_text(low, high, low_open, high_open) + (f" {unit}" if unit else "")
            slip = _array_slip(out, unit, low, high)
            fail(f"an array with values{interval} (element {where}: {out[tuple(first)]:g})", slip or ".")
    return out


def _array_slip(values: np.ndarray, unit: str, low, high) -> str:
    """``": did you mean mm ([0.045, 0.135] m)?"`` when one unit slip puts every value inside, else ``""``."""
    for factor, name in UNIT_SLIPS.get(unit, ()):
        meant = values * factor
        if (low is None or (meant > low).all()) and (high is None or (meant <= high).all()):
            return f": did you mean {name} ({_numbers(meant.tolist())} {unit})?"
    return ""


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
    try:
        out = np.array(value, dtype=float, copy=True)
    except (TypeError, ValueError):
        raise ParameterError(
            f"The '{name}' parameter of {owner} must be {kind}{_interval_text(low, high, low_open, high_open)}. "
            f"Got a value of type "
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
    if bad.any():
        interval = _interval_text(low, high, low_open, high_open)
        expected = kind + interval + (f" {unit}" if unit and interval else "") + (f" ({note})" if note else "")
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


# ------------------------------------------------------------------------------------------ declared constraints
class _Unsatisfied(Exception):
    """A value does not meet one constraint (internal: the caller tries the next one or names them all)."""


class Constraint(ABC):
    """One declared constraint on a parameter: how to convert a value that meets it, how to say what it wants,
    and (for the tests) values that do not meet it."""

    @abstractmethod
    def convert(self, value: object) -> object:
        """Return ``value`` (a copy, or converted: ``8.0`` -> ``8`` for an integer) or raise ``_Unsatisfied``."""

    @abstractmethod
    def describe(self) -> str:
        """What the constraint wants, as the message says it: ``"a real number inside (0, inf)"``."""

    def invalid_values(self) -> list:
        """Values that break this constraint (the declared-validation test feeds each of them)."""
        return []

    def valid_value(self) -> object:
        """One value that meets this constraint (the test's stand-in for required parameters)."""
        raise NotImplementedError(f"no valid value generated for {self!r}")

    def check(self, value: object, name: str, owner: str | None, error: type[Exception]) -> object:
        """:meth:`convert`, raising the one-line message naming the parameter (used when it is the only choice)."""
        try:
            return self.convert(value)
        except _Unsatisfied:
            _fail(name, owner, self.describe(), value, error)

    def satisfied_by(self, value: object) -> bool:
        try:
            self.convert(value)
        except _Unsatisfied:
            return False
        return True


_CLOSED = ("both", "left", "right", "neither")


class Interval(Constraint):
    """A real number or an integer in an interval (scikit-learn's ``Interval``).

    Parameters
    ----------
    type : numbers.Real or numbers.Integral
        ``Integral`` accepts whole floats (``8.0`` -> ``8``) but not ``True``; ``Real`` accepts finite numbers only.
    low, high : float or None
        Bounds; ``None`` is unbounded.
    closed : {"both", "left", "right", "neither"}
        Which bounds belong to the interval (default ``"both"``; an integer interval is always closed).
    """

    def __init__(self, type, low=None, high=None, *, closed: str = "both") -> None:
        if type not in (Real, Integral):
            raise TypeError(f"Interval type must be numbers.Real or numbers.Integral, not {type!r}")
        if closed not in _CLOSED:
            raise ValueError(f"Interval closed must be one of {_CLOSED}, not {closed!r}")
        if low is not None and high is not None and high < low:
            raise ValueError(f"Interval high {high} is below low {low}")
        self.type, self.low, self.high, self.closed = type, low, high, closed

    @property
    def low_open(self) -> bool:
        return self.type is Real and self.closed in ("right", "neither")

    @property
    def high_open(self) -> bool:
        return self.type is Real and self.closed in ("left", "neither")

    def __repr__(self) -> str:
        kind = "Real" if self.type is Real else "Integral"
        return f"Interval({kind}, {self.low}, {self.high}, closed={self.closed!r})"

    def describe(self) -> str:
        kind = "an integer" if self.type is Integral else "a real number"
        return kind + _interval_text(self.low, self.high, self.low_open, self.high_open)

    def convert(self, value):
        try:
            if self.type is Integral:
                return check_int(value, "x", low=self.low, high=self.high, error=_Unsatisfied)
            return check_real(
                value, "x", low=self.low, high=self.high, low_open=self.low_open, high_open=self.high_open,
                error=_Unsatisfied,
            )  # fmt: skip
        except TypeError:  # comparing an exotic Real with the bounds
            raise _Unsatisfied from None

    def check(self, value, name, owner, error):
        """:func:`check_int` or :func:`check_real`, with their messages (e.g. "a finite real number" for NaN)."""
        if self.type is Integral:
            return check_int(value, name, owner, low=self.low, high=self.high, error=error)
        return check_real(
            value, name, owner, low=self.low, high=self.high, low_open=self.low_open, high_open=self.high_open,
            error=error,
        )  # fmt: skip

    def invalid_values(self) -> list:
        out: list = ["1", True]
        if self.type is Integral:
            out.append(1.5)
            out += [v for v in (self.low - 1 if self.low is not None else None,) if v is not None]
            out += [v for v in (self.high + 1 if self.high is not None else None,) if v is not None]
            return out
        out.append(math.nan)
        for bound, is_open, step in ((self.low, self.low_open, -1), (self.high, self.high_open, 1)):
            if bound is not None:
                out.append(bound if is_open else bound + step * max(1e-6, 1e-6 * abs(bound)))
        return out

    def valid_value(self):
        lo = self.low if self.low is not None else (self.high - 1 if self.high is not None else 0)
        hi = self.high if self.high is not None else lo + 2
        mid = (lo + hi) / 2
        return int(math.ceil(mid)) if self.type is Integral else float(mid)


#: Unit slips: for a value in a field of unit U, (factor, the unit the user likely wrote it in). ``value * factor``
#: is what the user meant, in U. A slip is only named when that lands inside the plausible range.
UNIT_SLIPS: dict[str, tuple[tuple[float, str], ...]] = {
    "m": ((1e-3, "mm"), (1e-2, "cm"), (1e-6, "um")),  # a thickness of 0.381 "m" meant mm
    "mm": ((10.0, "cm"), (1e3, "m"), (1e-3, "um")),  # positions in cm read as mm
    "cm": ((1e-1, "mm"), (1e2, "m")),
    "Pa": ((1e9, "GPa"), (1e6, "MPa"), (1e3, "kPa")),  # E = 205 "Pa" meant GPa
    "N/m^2": ((1e3, "kN/m^2 (kPa)"), (1e6, "N/mm^2 (MPa)")),  # a foundation modulus written in kPa
    "kg": ((1e-3, "g"),),
    "kg/m^3": ((1e3, "g/cm^3"),),
    "g": ((1e3, "kg"),),  # a load of 0.025 "g" meant kg
    "s": ((1e-3, "ms"), (1e-6, "us"), (1e3, "ks")),  # a record in ms read as s
    "Hz": ((1e3, "kHz"), (1e-3, "mHz")),
    "ohm": ((1e3, "kohm"),),
    "N": ((9.81e-3, "g (a mass, not a force)"), (9.81, "kg (a mass, not a force)")),
    "deg": ((57.29577951308232, "rad"),),
    "V": ((1e-3, "mV"),),
}


def unit_slip(value: float, unit: str, low: float | None, high: float | None) -> str:
    """The likely unit slip of an out-of-range ``value`` (``"mm (0.000381 m)"``), or ``""`` if none fits.

    Examples
    --------
    >>> unit_slip(0.381, "m", 1e-5, 0.01)
    'mm (0.000381 m)'
    >>> unit_slip(205.0, "Pa", 1e8, 1e12)
    'GPa (2.05e+11 Pa)'
    >>> unit_slip(0.0, "s", 0.0, 10.0)  # zero is zero in any unit (an open bound at 0 refused it)
    ''
    """
    if value == 0:
        return ""
    for factor, name in UNIT_SLIPS.get(unit, ()):
        meant = value * factor
        if (low is None or meant >= low) and (high is None or meant <= high):
            return f"{name} ({meant:.6g} {unit})"
    return ""


class Plausible(Interval):
    """A physical or practical quantity: a finite real number in a plausible range, with its unit and the reason.

    Where :class:`Interval` says what is *possible* (a thickness > 0), ``Plausible`` says what a user's rig can
    *be*: generous bounds (a user's own digit is not the thesis rig), each stated with its reason, so that a
    1e308 N load or a 5e-324 gain is refused, not computed with. A value outside the range whose likely unit slip
    lands inside it is refused naming the slip (``Got 0.381 m instead: did you mean mm (0.000381 m)?``).
    Subnormal numbers are never plausible magnitudes (they are the float format's underflow, not a measurement).

    Parameters
    ----------
    unit : str
        The unit of the field (``"m"``, ``"Pa"``, ``""`` for a pure number); :data:`UNIT_SLIPS` keys the slips.
    low, high : float
        The plausible range (closed unless ``closed`` says otherwise).
    why : str
        Why these bounds, as the message shows it in parentheses.
    integer : bool
        Whole numbers only (a count of samples, a servo command); then ``8.0`` is converted to ``8``.
    zero : str
        If given, exactly 0 is accepted too, as the idealisation this names (a weightless strip, the beam oracles'):
        a model's limit case, never a measured value.

    Examples
    --------
    >>> Plausible("m", 1e-5, 0.01, "a strip 0.01 mm to 10 mm thick").check(0.381e-3, "t", "Geometry", ValueError)
    0.000381
    >>> Plausible("kg/m^3", 800.0, 22_600.0, "PE to osmium", zero="weightless").describe()
    'a real number inside [800, 22600] kg/m^3 (PE to osmium) or 0 (weightless)'
    """

    def __init__(
        self,
        unit: str,
        low: float,
        high: float,
        why: str,
        *,
        closed: str = "both",
        integer: bool = False,
        zero: str = "",
    ) -> None:
        super().__init__(Integral if integer else Real, low, high, closed=closed)
        if not why:
            raise ValueError("Plausible needs the reason for its bounds")
        self.unit, self.why, self.zero = unit, why, zero

    def __repr__(self) -> str:
        zero = f", zero={self.zero!r}" if self.zero else ""
        return f"Plausible({self.unit!r}, {self.low}, {self.high}, {self.why!r}, closed={self.closed!r}{zero})"

    def to(self, unit: str, factor: float) -> Plausible:
        """The same range in another unit (``LOAD_KG.to("g", 1e3)`` for a flag in grams): declared once.

        Examples
        --------
        >>> Plausible("kg", 1e-4, 2.0, "a hung weight").to("g", 1e3).describe()
        'a real number inside [0.1, 2000] g (a hung weight)'
        """
        low = None if self.low is None else self.low * factor
        high = None if self.high is None else self.high * factor
        return Plausible(unit, low, high, self.why, closed=self.closed, integer=self.type is Integral, zero=self.zero)

    def describe(self) -> str:
        kind = "an integer" if self.type is Integral else "a real number"
        unit = f" {self.unit}" if self.unit else ""
        zero = f" or 0 ({self.zero})" if self.zero else ""
        return f"{kind}{_interval_text(self.low, self.high, self.low_open, self.high_open)}{unit} ({self.why}){zero}"

    def convert(self, value):
        if self.zero and isinstance(value, Real) and not isinstance(value, bool) and value == 0:
            return 0 if self.type is Integral else 0.0
        out = super().convert(value)
        if out != 0 and abs(out) < sys.float_info.min:  # subnormal: underflow, never a measured magnitude
            raise _Unsatisfied
        return out

    def check(self, value, name, owner, error):
        """Return the value converted, or raise the one-line message naming the parameter, range and slip."""
        try:
            return self.convert(value)
        except _Unsatisfied:
            pass
        where = f"The '{name}' parameter of {owner}" if owner else f"The '{name}' parameter"
        shown = shown_value(value)
        slip, finite = "", False
        if isinstance(value, Real) and not isinstance(value, bool):
            try:
                number = float(value)
            except OverflowError:  # an integer beyond a float's range
                number = math.inf
            finite = math.isfinite(number)
            if finite:
                exact = isinstance(value, Integral) or (self.type is Integral and number.is_integer())
                text = shown_value(value) if isinstance(value, Integral) else None
                shown = (text or (str(int(number)) if exact and abs(number) < 1e16 else repr(number))) + (
                    f" {self.unit}" if self.unit else ""
                )
                slip = unit_slip(number, self.unit, self.low, self.high)
        tail = f": did you mean {slip}?" if slip else "."
        expected = self.describe()
        if not finite:
            expected = expected.replace("a real number", "a finite real number", 1)
        raise error(f"{where} must be {expected}. Got {shown} instead{tail}")

    def invalid_values(self) -> list:
        out = super().invalid_values() + [math.inf, -math.inf, 1e308]
        if self.type is Real:
            out.append(5e-324 if (self.low is None or self.low > 0 or self.low_open) else -1e308)
        return [v for v in out if not (self.zero and isinstance(v, Real) and not isinstance(v, bool) and v == 0)]


def check_plausible(values, declared: Plausible, name: str, owner: str | None = None, *, error=ParameterError):
    """Check every value of ``values`` (a number or an array) against a :class:`Plausible` declaration; return a
    float array (a scalar gives a 0-d array). The first offending value is named, with its likely unit slip."""
    out = np.asarray(values, dtype=float)
    flat = out.ravel()
    inside = np.isfinite(flat)
    with np.errstate(invalid="ignore"):
        if declared.low is not None:
            inside &= (flat > declared.low) if declared.low_open else (flat >= declared.low)
        if declared.high is not None:
            inside &= (flat < declared.high) if declared.high_open else (flat <= declared.high)
        inside &= (flat == 0) | (np.abs(flat) >= sys.float_info.min)
        if declared.type is Integral:
            inside &= flat == np.round(flat)
        if declared.zero:  # the idealisation it names
            inside |= flat == 0
    if not inside.all():
        declared.check(float(flat[np.argmin(inside)]), name, owner, error)
    return out


class _FlagValueError(ValueError):
    """A command-line value a :class:`Flag` refuses (internal: turned into argparse's ArgumentTypeError)."""


class Flag:
    """An argparse ``type=``: the command-line value parsed and checked against its declared constraint.

    Declaring a flag's range where the flag is declared (``parser.add_argument("--settle",
    type=Flag(Plausible("s", 0, 3600, "an hour per setting")))``) makes argparse refuse a bad value before the
    command runs, in one line naming the flag: ``argument --settle: must be a real number inside [0, 3600] s (an
    hour per setting). Got 1e+308 s instead.``; ``tests/test_validation.py`` walks the parser and feeds every
    declared flag its constraint's invalid values.

    Parameters
    ----------
    constraint : Constraint
        Usually a :class:`Plausible`; an integer one parses integers.
    many : bool
        A comma-separated list (``"12.5,25,7.5"``); each value is checked; a list is returned.
    ranges : bool
        With ``many``, also ``"8..43"`` (both ends checked before the range is made: ``8..1000000000`` is refused,
        never built).
    """

    def __init__(self, constraint: Constraint, *, many: bool = False, ranges: bool = False) -> None:
        self.constraint, self.many, self.ranges = constraint, many, ranges
        self.integer = isinstance(constraint, Interval) and constraint.type is Integral
        # argparse names a type in its own messages ("invalid ... value") by __name__
        self.__name__ = ("integer" if self.integer else "number") + (" list" if many else "")

    def __repr__(self) -> str:
        return f"Flag({self.constraint!r}, many={self.many}, ranges={self.ranges})"

    def _one(self, text: str):
        text = text.strip()
        try:
            value = int(text) if self.integer else float(text)
        except ValueError:
            kind = "an integer" if self.integer else "a number"
            raise _FlagValueError(f"must be {kind}. Got {text!r} instead.") from None
        try:
            return self.constraint.check(value, "x", None, _FlagValueError)
        except _FlagValueError as exc:
            raise _FlagValueError(str(exc).removeprefix("The 'x' parameter ")) from None

    def __call__(self, text: str):
        import argparse

        try:
            if not self.many:
                return self._one(text)
            if self.ranges and ".." in text:
                lo, _, hi = text.partition("..")
                lo, hi = self._one(lo), self._one(hi)
                if hi < lo:
                    raise _FlagValueError(f"must be a range 'low..high' with low <= high. Got {text!r} instead.")
                return list(range(lo, hi + 1))
            values = [self._one(v) for v in text.split(",") if v.strip()]
            if not values:
                raise _FlagValueError(f"must name at least one value (comma-separated). Got {text!r} instead.")
            return values
        except _FlagValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    def invalid_texts(self) -> list[str]:
        """Command-line texts this flag must refuse (generated from its constraint, for the tests)."""
        out = ["abc"]
        for bad in self.constraint.invalid_values():
            if isinstance(bad, bool) or not isinstance(bad, Real):
                continue
            if self.integer and isinstance(bad, float) and not (math.isfinite(bad) and bad.is_integer()):
                out.append(repr(bad))
                continue
            out.append(str(int(bad)) if self.integer else repr(float(bad)))
        if self.many:
            out.append("")
        return out


class Options(Constraint):
    """One of a set of values (scikit-learn's ``Options``/``StrOptions``): ``Options({"thesis", "lsq"})``."""

    def __init__(self, options: Iterable) -> None:
        self.options = tuple(options)
        if not self.options:
            raise ValueError("Options needs at least one option")

    def __repr__(self) -> str:
        return f"Options({self.options!r})"

    def describe(self) -> str:
        return "one of " + ", ".join(repr(o) for o in self.options)

    def convert(self, value):
        # bool is an int: True must not pass for an option 1
        if any(value is o or (type(value) is type(o) and value == o) for o in self.options):
            return value
        raise _Unsatisfied

    def invalid_values(self) -> list:
        probe = "not " + " or ".join(str(o) for o in self.options)
        return [probe] + ([True] if all(isinstance(o, str) for o in self.options) else [])

    def valid_value(self):
        return self.options[0]


def StrOptions(options: Iterable[str]) -> Options:  # noqa: N802 - scikit-learn's name for the same thing
    """:class:`Options` of strings (scikit-learn's spelling)."""
    return Options(sorted(options) if isinstance(options, set | frozenset) else options)


class Bool(Constraint):
    """``True`` or ``False`` (numpy's booleans too; not 0 or 1, which are numbers)."""

    def __repr__(self) -> str:
        return "Bool()"

    def describe(self) -> str:
        return "a boolean (True or False)"

    def convert(self, value):
        if isinstance(value, bool | np.bool_):
            return bool(value)
        raise _Unsatisfied

    def invalid_values(self) -> list:
        return [1, "yes"]

    def valid_value(self):
        return False


class InstanceOf(Constraint):
    """An instance of ``cls`` (a class or a tuple of classes)."""

    def __init__(self, cls, description: str | None = None) -> None:
        self.cls = cls
        names = cls if isinstance(cls, tuple) else (cls,)
        self.text = description or "an instance of " + " or ".join(c.__name__ for c in names)

    def __repr__(self) -> str:
        return f"InstanceOf({self.cls!r})"

    def describe(self) -> str:
        return self.text

    def convert(self, value):
        if isinstance(value, self.cls):
            return value
        raise _Unsatisfied

    def invalid_values(self) -> list:
        return [object()]

    def valid_value(self):
        """An instance built with the class's defaults (parameter sets such as ``RigParams``)."""
        cls = self.cls[0] if isinstance(self.cls, tuple) else self.cls
        try:
            return cls()
        except TypeError:
            raise NotImplementedError(f"{cls.__name__} has no default instance") from None


class Callable(Constraint):
    """A callable (a function or an object with ``__call__``)."""

    def __repr__(self) -> str:
        return "Callable()"

    def describe(self) -> str:
        return "a callable"

    def convert(self, value):
        if callable(value):
            return value
        raise _Unsatisfied

    def invalid_values(self) -> list:
        return [1.0]

    def valid_value(self):
        return len


class HasMethods(Constraint):
    """An object with these methods (a gauge model, a rig): duck typing, declared."""

    def __init__(self, methods) -> None:
        self.methods = (methods,) if isinstance(methods, str) else tuple(methods)

    def __repr__(self) -> str:
        return f"HasMethods({self.methods!r})"

    def describe(self) -> str:
        return "an object with method(s) " + ", ".join(self.methods)

    def convert(self, value):
        if all(callable(getattr(value, m, None)) for m in self.methods):
            return value
        raise _Unsatisfied

    def invalid_values(self) -> list:
        return [object()]

    def valid_value(self):
        return type("Stub", (), {m: lambda self, *a, **k: None for m in self.methods})()


class Array(Constraint):
    """An array of real numbers, checked and copied by :func:`check_array` (same keywords)."""

    def __init__(self, **check_array_kwargs) -> None:
        bad = set(check_array_kwargs) - {
            "ndim", "shape", "min_length", "finite", "increasing", "low", "high", "low_open", "high_open",
        }  # fmt: skip
        if bad:
            raise TypeError(f"Array got unexpected keywords {sorted(bad)}")
        self.kwargs = check_array_kwargs

    def __repr__(self) -> str:
        return "Array(" + ", ".join(f"{k}={v!r}" for k, v in self.kwargs.items()) + ")"

    def describe(self) -> str:
        return "an array of real numbers"

    def convert(self, value):
        if isinstance(value, str | bytes):
            raise _Unsatisfied
        return check_array(value, "x", error=_Unsatisfied, **self.kwargs)

    def check(self, value, name, owner, error):
        """Like :meth:`convert`, but with :func:`check_array`'s own, more precise message."""
        if isinstance(value, str | bytes):
            _fail(name, owner, "an array of real numbers", value, error)
        return check_array(value, name, owner, error=error, **self.kwargs)

    def invalid_values(self) -> list:
        out: list = ["abc"]
        if self.kwargs.get("finite", True):
            out.append([math.nan] * max(1, self.kwargs.get("min_length") or 1))
        return out

    def valid_value(self):
        k = self.kwargs
        shape = k.get("shape")
        n = max(2, k.get("min_length") or 0)
        if shape is not None:
            dims = tuple(n if s is None else s for s in shape)
        else:
            dims = (n,) * (k.get("ndim") or 1)
        lo = k.get("low")
        lo = 0.0 if lo is None else float(lo)
        hi = k.get("high")
        hi = lo + 1.0 if hi is None else float(hi)
        size = int(np.prod(dims))
        return np.linspace(lo + (hi - lo) / 4, hi - (hi - lo) / 4, size).reshape(dims)


class NoValidation(Constraint):
    """Any value: the function checks this parameter itself (a system converted by ``as_statespace``, a dataset
    read from its file). Declared so that every parameter of a decorated function is declared."""

    def __repr__(self) -> str:
        return "NoValidation()"

    def describe(self) -> str:
        return "anything"

    def convert(self, value):
        return value

    def valid_value(self):
        return None


def _constraints(declared) -> list:
    """A parameter's declaration as a list of :class:`Constraint` (``None`` allowed if listed)."""
    items = declared if isinstance(declared, list | tuple) else [declared]
    for c in items:
        if c is not None and not isinstance(c, Constraint):
            raise TypeError(f"a declared constraint must be a Constraint or None, not {c!r}")
    return list(items)


def check_param(value, declared, name: str, owner: str | None = None, *, error: type[Exception] = ParameterError):
    """Return ``value`` converted by the first constraint of ``declared`` it meets, or raise naming it.

    ``declared`` is a :class:`Constraint`, ``None``, or a list of them ("any of"). The message lists what each
    would accept: ``The 'seed' parameter of run must be an integer inside [0, inf) or None. Got -1 instead.``

    Examples
    --------
    >>> check_param(None, [Interval(Integral, 0, None), None], "seed", "run") is None
    True
    """
    items = _constraints(declared)
    if value is None and None in items:
        return None
    real = [c for c in items if c is not None]
    if len(real) == 1:  # a value that is not None can only meet the one constraint: its own, precise message
        return real[0].check(value, name, owner, error)
    for c in real:
        try:
            return c.convert(value)
        except _Unsatisfied:
            continue
    texts = [c.describe() for c in real] + (["None"] if None in items else [])
    _fail(name, owner, " or ".join(texts), value, error)


def check_params(
    values: dict, constraints: dict, owner: str, *, error: type[Exception] = ParameterError
) -> dict[str, object]:
    """Check every declared parameter of ``values`` (a dict) against ``constraints``; return them converted.

    Parameters not in ``values`` are skipped (their defaults were declared valid); a name in ``values`` that
    ``constraints`` does not declare is not checked.
    """
    return {
        name: check_param(values[name], declared, name, owner, error=error)
        for name, declared in constraints.items()
        if name in values
    }


#: Every declaration made by :func:`validate_params` or :func:`declare`: ``(callable, constraints)``. The
#: declared-validation test walks it (after importing every flexdigit module) and feeds each invalid value.
DECLARED: list[tuple[object, dict]] = []


def validate_params(constraints: dict, *, owner: str | None = None, error: type[Exception] = ParameterError):
    """Decorate a function so its declared parameters are checked (and converted) before it runs.

    Parameters
    ----------
    constraints : dict
        ``{"name": constraint or [constraints]}``; the names must be parameters of the function.
    owner : str, optional
        The name in messages (default: the function's qualified name).
    error : type
        The exception raised (default :class:`~flexdigit.errors.ParameterError`).
    """

    def decorate(func):
        sig = inspect.signature(func)
        unknown = set(constraints) - set(sig.parameters)
        if unknown:
            raise TypeError(f"validate_params on {func.__qualname__}: no parameter(s) {sorted(unknown)}")
        name = owner or func.__qualname__
        declared = {k: _constraints(v) for k, v in constraints.items()}

        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            bound = sig.bind(*args, **kwargs)
            for key, value in check_params(bound.arguments, declared, name, error=error).items():
                bound.arguments[key] = value
            return func(*bound.args, **bound.kwargs)

        wrapper.parameter_constraints = declared
        DECLARED.append((wrapper, declared))
        return wrapper

    return decorate


def declare(cls):
    """Class decorator: register a class whose ``__init__`` (or ``__post_init__``) checks its
    ``_parameter_constraints`` with :func:`check_params`, so the declared-validation test covers it."""
    declared = {k: _constraints(v) for k, v in cls._parameter_constraints.items()}
    cls._parameter_constraints = declared
    DECLARED.append((cls, declared))
    return cls


def validate_fields(obj, *, error: type[Exception] = ParameterError) -> None:
    """Check a dataclass instance's fields against its class's ``_parameter_constraints`` (no conversion: a
    frozen dataclass keeps what it was given). Call it first in ``__post_init__``."""
    owner = type(obj).__name__
    values = {k: getattr(obj, k) for k in obj._parameter_constraints}
    check_params(values, obj._parameter_constraints, owner, error=error)


# ------------------------------------------------------------------------------ quantities many commands share
#: A random seed (numpy's ``default_rng``, Dask): any non-negative integer; every random thing takes one.
SEED = Interval(Integral, 0, None)

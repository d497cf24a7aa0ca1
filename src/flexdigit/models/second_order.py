"""The digit as a second-order system, identified from release tests (thesis 3.1.2, tables 3.1 and 3.2).

A release test gives a percent overshoot (%OS) and a 2 % settling time Ts. The thesis turns them into a
damping ratio and a natural frequency with the textbook second-order formulas [21]::

    zeta = -ln(OS/100) / sqrt(pi^2 + ln^2(OS/100))        wn = 4 / (zeta Ts)

and models the digit as ``E(s) = wn^2 / (s^2 + 2 zeta wn s + wn^2)`` (V per N m as printed; the DC gain of one
is a placeholder for the moment-to-gauge-volt gain, see :mod:`flexdigit.models.plant`).

Examples
--------
>>> round(float(zeta_from_overshoot(80.3603)), 4)   # table 3.2 row 1
0.0694
>>> tf = digit_tf(13.0995, 0.06791)                   # 3.1.2: 171.61/(s^2 + 1.782 s + 171.61)
>>> [round(float(c), 3) for c in tf.den[0][0]]
[1.0, 1.779, 171.597]
"""

from __future__ import annotations

import math
from numbers import Real
from typing import TYPE_CHECKING

import numpy as np

from flexdigit._validation import Interval, validate_params
from flexdigit.errors import ParameterError
from flexdigit.models.polytf import PolyTF
from flexdigit.params import RigParams

if TYPE_CHECKING:
    import control

_POSITIVE = Interval(Real, 0, None, closed="neither")


def zeta_from_overshoot(percent_overshoot):
    """Damping ratio from the percent overshoot of a second-order response (3.1.2, [21]).

    Parameters
    ----------
    percent_overshoot : float or array_like
        Overshoot in percent, in (0, 100). NaN (an unreadable printed value) passes through as NaN.

    Returns
    -------
    float or ndarray
        ``-ln(OS/100) / sqrt(pi^2 + ln^2(OS/100))`` (dimensionless).

    Raises
    ------
    ParameterError
        If a finite value lies outside (0, 100).

    Examples
    --------
    >>> round(float(zeta_from_overshoot(99.7485)), 4)   # table 3.1 row 1
    0.0008
    """
    os_ = np.asarray(percent_overshoot, dtype=float)
    finite = np.isfinite(os_)
    if np.any(finite & ((os_ <= 0) | (os_ >= 100))):
        raise ParameterError(
            "The 'percent_overshoot' parameter of zeta_from_overshoot must be inside (0, 100). "
            f"Got {os_.tolist()!r} instead."
        )
    log_os = np.log(os_ / 100.0)
    zeta = -log_os / np.sqrt(math.pi**2 + log_os**2)
    return zeta if zeta.ndim else float(zeta)


def overshoot_from_zeta(zeta):
    """Percent overshoot of an underdamped second-order step response, ``100 exp(-zeta pi / sqrt(1 - zeta^2))``.

    The inverse of :func:`zeta_from_overshoot` for 0 <= zeta < 1.

    Examples
    --------
    >>> round(float(overshoot_from_zeta(zeta_from_overshoot(81.2984))), 4)
    81.2984
    """
    z = np.asarray(zeta, dtype=float)
    if np.any(np.isfinite(z) & ((z < 0) | (z >= 1))):
        raise ParameterError(
            f"The 'zeta' parameter of overshoot_from_zeta must be inside [0, 1). Got {z.tolist()!r} instead."
        )
    out = 100.0 * np.exp(-z * math.pi / np.sqrt(1.0 - z**2))
    return out if out.ndim else float(out)


def wn_from_settling_time(settling_time_s, zeta):
    """Natural frequency from the 2 % settling time, ``wn = 4 / (zeta Ts)`` exactly as the thesis (3.1.2).

    Parameters
    ----------
    settling_time_s : float or array_like
        2 % settling time (s), > 0.
    zeta : float or array_like
        Damping ratio, > 0.

    Returns
    -------
    float or ndarray
        Natural frequency (rad/s).

    Examples
    --------
    >>> round(wn_from_settling_time(4.5, 0.0694), 3)
    12.808
    """
    ts = np.asarray(settling_time_s, dtype=float)
    z = np.asarray(zeta, dtype=float)
    if np.any(~(ts > 0)) or np.any(~(z > 0)):
        raise ParameterError(
            "The 'settling_time_s' and 'zeta' parameters of wn_from_settling_time must be > 0. "
            f"Got {ts.tolist()!r} and {z.tolist()!r} instead."
        )
    out = 4.0 / (z * ts)
    return out if out.ndim else float(out)


@validate_params(
    {"wn_rad_s": [Interval(Real, 0, None, closed="neither")], "zeta": [Interval(Real, 0, None, closed="neither")]}
)
def settling_time_from_wn(wn_rad_s, zeta):
    """The 2 % settling time the thesis's formula implies, ``Ts = 4 / (zeta wn)`` (s)."""
    return 4.0 / (zeta * wn_rad_s)


def damped_frequency(wn_rad_s, zeta):
    """Damped natural frequency ``wd = wn sqrt(1 - zeta^2)`` (rad/s); vectorised."""
    wn = np.asarray(wn_rad_s, dtype=float)
    z = np.asarray(zeta, dtype=float)
    out = wn * np.sqrt(1.0 - z**2)
    return out if out.ndim else float(out)


def natural_frequency_from_damped(wd_rad_s, zeta):
    """Natural frequency from the damped one, ``wn = wd / sqrt(1 - zeta^2)`` (rad/s); vectorised."""
    wd = np.asarray(wd_rad_s, dtype=float)
    z = np.asarray(zeta, dtype=float)
    out = wd / np.sqrt(1.0 - z**2)
    return out if out.ndim else float(out)


_DIGIT_TF_CONSTRAINTS = {
    "wn_rad_s": [Interval(Real, 0, None, closed="neither")],
    "zeta": [Interval(Real, 0, None)],
    "gain": [Interval(Real)],
}


@validate_params(_DIGIT_TF_CONSTRAINTS)
def digit_poly(wn_rad_s: float, zeta: float, gain: float = 1.0) -> PolyTF:
    """``E(s) = gain wn^2 / (s^2 + 2 zeta wn s + wn^2)`` (3.1.2) as a :class:`~flexdigit.models.polytf.PolyTF`.

    What :func:`digit_tf` returns, without importing python-control (the plant and the twin use this one).

    Examples
    --------
    >>> digit_poly(10.0, 0.1).den.tolist()
    [1.0, 2.0, 100.0]
    """
    return PolyTF([gain * wn_rad_s**2], [1.0, 2.0 * zeta * wn_rad_s, wn_rad_s**2])


@validate_params(_DIGIT_TF_CONSTRAINTS)
def digit_tf(wn_rad_s: float, zeta: float, gain: float = 1.0) -> control.TransferFunction:
    """``E(s) = gain wn^2 / (s^2 + 2 zeta wn s + wn^2)`` (3.1.2).

    Parameters
    ----------
    wn_rad_s : float
        Natural frequency (rad/s), > 0.
    zeta : float
        Damping ratio, >= 0.
    gain : float
        DC gain (output unit per input unit); 1 by default, as printed.

    Returns
    -------
    control.TransferFunction

    Examples
    --------
    >>> float(digit_tf(10.0, 0.1).dcgain())
    1.0
    """
    return digit_poly(wn_rad_s, zeta, gain).to_control()


def digit_poly_from_params(params: RigParams | None = None, *, housing: bool = True) -> PolyTF:
    """The digit's unit-DC-gain second-order model from ``params.dynamics``, as a ``PolyTF``.

    ``housing=True`` gives E(s) of 3.1.2 (table 3.2 averages, the rig as it runs); ``housing=False`` the bare
    strip of table 3.1.
    """
    d = (params or RigParams()).dynamics
    if housing:
        return digit_poly(d.wn_housing_rad_s, d.zeta_housing)
    return digit_poly(d.wn_bare_rad_s, d.zeta_bare)


def digit_tf_from_params(params: RigParams | None = None, *, housing: bool = True) -> control.TransferFunction:
    """:func:`digit_poly_from_params` as a ``control.TransferFunction`` (``housing``: with housing or bare)."""
    return digit_poly_from_params(params, housing=housing).to_control()


def release_table(percent_overshoot, wd_rad_s) -> dict[str, np.ndarray]:
    """Recompute a release-test table (tables 3.1, 3.2): zeta from %OS and wn from the damped frequency.

    Parameters
    ----------
    percent_overshoot : array_like
        Percent overshoot per test; NaN where the printed value is unreadable.
    wd_rad_s : array_like
        Damped natural frequency per test (rad/s).

    Returns
    -------
    dict
        ``zeta`` (NaN where %OS is NaN), ``wn_rad_s`` (``wd / sqrt(1 - zeta^2)``), and their averages over the
        finite rows, ``zeta_avg`` and ``wn_avg_rad_s``.
    """
    zeta = np.atleast_1d(zeta_from_overshoot(percent_overshoot))
    wd = np.atleast_1d(np.asarray(wd_rad_s, dtype=float))
    if wd.shape != zeta.shape:
        raise ParameterError(
            f"release_table needs one damped frequency per overshoot: got {wd.size} and {zeta.size} values."
        )
    wn = np.atleast_1d(natural_frequency_from_damped(wd, zeta))
    return {
        "zeta": zeta,
        "wn_rad_s": wn,
        "zeta_avg": float(np.nanmean(zeta)),
        "wn_avg_rad_s": float(np.nanmean(wn)),
    }

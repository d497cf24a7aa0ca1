"""Response analysis of release and step tests (thesis 3.1.2, 3.2.4): the thesis's formulas and better ones.

The thesis identifies a second-order model from one experiment: the damping ratio from the percent overshoot
(%OS) and the natural frequency from the 2 % settling time, ``wn = 4 / (zeta Ts)`` (3.1.2, ref. [21]; the closed
forms live in :mod:`flexdigit.models.second_order` and are re-exported here). This module measures those features on a
recorded response (percent overshoot, peak time, rise time, 2 % settling time, damped frequency, log
decrement) and turns them into ``zeta`` and ``wn`` both the thesis's way and from the damped frequency,
``wn = wd / sqrt(1 - zeta^2)``, which is exact for a second-order system.

Release test and %OS
--------------------
A release test is the free decay of the digit from an initial deflection ``x0`` (relative to the final value)
and zero velocity. Its response is ``x0 (1 - s(t))`` where ``s`` is the unit step response of the same
second-order system, so the thesis's %OS of a release test is the **first undershoot past the final value
relative to the initial deflection**, ``%OS = 100 |x(t1)| / |x0|``: exactly the overshoot of the equivalent
step. With E 3.1.2's formula this maps table 3.1's 99.7485 % to zeta = 0.0008 as printed.

The 2 % settling time of a release test is the last time ``|x| > 0.02 |x0|``, of a step test the last time
``|y - y_final| > 0.02 |y_final - y0|`` (MATLAB ``stepinfo`` / python-control ``step_info``).

Examples
--------
>>> round(zeta_from_overshoot(99.7485), 4)         # table 3.1, row 1
0.0008
>>> round(wn_from_settling_time(0.2856, 0.5629), 2)  # thesis formula on MT(s)'s exact 2 % Ts (0.2856 s): not 20.53
24.88
>>> round(overshoot_from_zeta(0.0685), 4)          # table 3.2 row 2, printed garbled as "80.59.5973"
80.5972
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexdigit._repr import summary
from flexdigit._validation import check_array, check_choice, check_positive
from flexdigit.errors import DataFileError
from flexdigit.models.second_order import (
    natural_frequency_from_damped,
    overshoot_from_zeta,
    wn_from_settling_time,
    zeta_from_overshoot,
)

__all__ = [
    "NoOscillationError",
    "ResponseFeatures",
    "analyze_response",
    "free_response",
    "natural_frequency_from_damped",
    "noise_std",
    "overshoot_from_zeta",
    "settling_formula_bias",
    "wn_from_settling_time",
    "zeta_from_log_decrement",
    "zeta_from_overshoot",
]

#: Settling band of the thesis (3.1.2): 2 % of the final value.
SETTLING_BAND = 0.02


# --- closed forms (3.1.2, ref. [21]); the thesis's own live in flexdigit.models.second_order -------------------------


def zeta_from_log_decrement(delta: float) -> float:
    """Damping ratio from the logarithmic decrement per full period, ``delta / sqrt(4 pi^2 + delta^2)``."""
    d = check_positive(delta, "delta")
    return d / math.sqrt(4.0 * math.pi**2 + d * d)


# --- features of a recorded response ------------------------------------------------------------------------------


class NoOscillationError(DataFileError):
    """The response never overshoots (a release: never undershoots) its final value by more than the noise.

    The thesis method cannot read a damping ratio from such a record, and a release test of the digit should be an
    oscillating decay. A subclass of :class:`~flexdigit.errors.DataFileError` (so ``except DataFileError`` still
    catches it) that keeps what was found, so :func:`flexdigit.identify.identification.identify` can say what to do.

    Attributes
    ----------
    source, kind : str
        The record (file and channel) and the experiment (``"release"`` or ``"step"``).
    final_value : float
        The final value the response never crossed (signal unit).
    finding : str
        The message without the advice.
    """

    def __init__(self, source: str, kind: str, final_value: float):
        self.source, self.kind, self.final_value = source, kind, float(final_value)
        what = "undershoot" if kind == "release" else "overshoot"
        self.finding = (
            f"{source}: no {what} in this {kind} test: the response never crosses its final value "
            f"{final_value:g} by more than the noise (overdamped or too noisy)"
        )
        if kind == "release":
            advice = (
                "a release test of the digit is expected to be an oscillating decay and the thesis method needs one "
                "(lsq and arx fit an overdamped decay with --allow-overdamped, allow_overdamped=True)"
            )
        else:
            advice = "the thesis method needs an underdamped response, use the lsq method"
        super().__init__(f"{self.finding}; {advice}")


@dataclass(frozen=True)
class ResponseFeatures:
    """Features of one release or step response, and the second-order parameters they imply.

    Attributes
    ----------
    kind : {"release", "step"}
    t0_s : float
        Release or step instant (s); every other time is measured from it.
    initial_value, final_value : float
        Signal before the step / at release, and at rest (signal units).
    percent_overshoot : float
        Step: overshoot past the final value relative to the step size. Release: first undershoot past the final
        value relative to the initial deflection (percent). A response that does not cross its final value raises
        instead (:func:`analyze_response`).
    peak_time_s : float
        Time of that first overshoot (undershoot) after ``t0_s`` (s).
    rise_time_s : float
        10-90 % rise time of the (mirrored, for a release) step (s).
    settling_time_s : float
        2 % settling time after ``t0_s`` (s); NaN when the record ends before it settles.
    wd_rad_s : float
        Damped frequency from the spacing of the final-value crossings (``pi / Tp`` when there are too few).
    log_decrement : float
        Logarithmic decrement per full period from the successive extrema; NaN with fewer than two extrema.
    zeta_os, zeta_log_decrement : float
        Damping ratio from %OS (thesis) and from the log decrement.
    wn_settling_rad_s : float
        The thesis's ``4 / (zeta_os Ts)``.
    wn_damped_rad_s : float
        ``wd / sqrt(1 - zeta_os^2)`` (how table 3.2 was computed).
    extrema_times_s, extrema_values : tuple of float
        The successive extrema of ``signal - final_value`` (relative to the final value).
    """

    kind: str
    t0_s: float
    initial_value: float
    final_value: float
    percent_overshoot: float
    peak_time_s: float
    rise_time_s: float
    settling_time_s: float
    wd_rad_s: float
    log_decrement: float
    zeta_os: float
    zeta_log_decrement: float
    wn_settling_rad_s: float
    wn_damped_rad_s: float
    extrema_times_s: tuple[float, ...] = ()
    extrema_values: tuple[float, ...] = ()

    @property
    def step_size(self) -> float:
        """Final minus initial value (the step, or minus the initial deflection for a release)."""
        return self.final_value - self.initial_value

    def __repr__(self) -> str:
        return summary(
            self,
            kind=self.kind,
            percent_overshoot=self.percent_overshoot,
            rise_time_s=self.rise_time_s,
            settling_time_s=self.settling_time_s,
            wd_rad_s=self.wd_rad_s,
            zeta_log_decrement=self.zeta_log_decrement,
            wn_damped_rad_s=self.wn_damped_rad_s,
        )


def final_value_estimate(y: np.ndarray, tail_fraction: float = 0.1) -> float:
    """The value the response settles to: the mean of the last ``tail_fraction`` of the record, over whole cycles.

    A record still oscillating at its end (a lightly damped digit) would bias a plain mean by up to the oscillation
    amplitude; averaging between the first and last upward crossings of the tail removes the partial cycle.
    """
    n = max(3, int(round(len(y) * tail_fraction)))
    tail = np.asarray(y[-n:], dtype=float)
    m = float(np.mean(tail))
    for _ in range(2):
        up = np.nonzero((tail[:-1] < m) & (tail[1:] >= m))[0]
        if up.size < 2:
            break
        m = float(np.mean(tail[up[0] + 1 : up[-1] + 1]))
    return m


def analyze_response(
    t_s,
    y,
    kind: str = "step",
    *,
    t0_s: float | None = None,
    initial_value: float | None = None,
    final_value: float | None = None,
    source: str = "response",
) -> ResponseFeatures:
    """Measure a release or step response (best on a filtered signal, see :mod:`flexdigit.identify.filters`).

    Parameters
    ----------
    t_s, y : array_like
        Time (s, increasing) and signal (any unit).
    kind : {"step", "release"}
        ``"release"``: free decay from rest at an initial deflection (3.1.2). ``"step"``: step response (3.2.4).
    t0_s : float, optional
        Release/step instant (s). Default: a step starts at the first sample; a release at the instant the first
        final-value crossing and the damped frequency point back to (``t_c1 - (pi/2 + asin zeta) / wd``), which
        works whether or not the record holds the deflection before the release.
    initial_value, final_value : float, optional
        Default: the signal at ``t0_s`` (for a step, the mean of the samples up to it) and the mean of the last
        10 % of the record.
    source : str
        Name used in error messages (file and channel).

    Returns
    -------
    ResponseFeatures

    Notes
    -----
    Extrema and crossings count only while the response stands out of the noise (three standard deviations of
    the record's last 10 %, or of its second differences for a record that has not come to rest). The 2 %
    settling time is the instant the response enters the band after its last extremum outside it; when the noise
    is larger than the band it is the last extremum that stands out of the noise, so the thesis method's ``Ts``
    (and its ``wn``) degrade with the noise, as they did.

    Raises
    ------
    NoOscillationError
        A :class:`~flexdigit.errors.DataFileError`: the response does not overshoot (undershoot, for a release)
        its final value, so the thesis method cannot give a damping ratio; the message says so and names
        ``source``.
    DataFileError
        If the response does not move at all.

    Examples
    --------
    >>> import control
    >>> t = np.linspace(0, 2, 4001)
    >>> y = control.step_response(control.tf([421.5], [1, 23.11, 421.5]), t).outputs
    >>> f = analyze_response(t, y, "step")
    >>> round(f.zeta_os, 4), round(f.wn_damped_rad_s, 2), round(f.settling_time_s, 4)  # MT(s) of 3.2.4
    (0.5628, 20.53, 0.2855)
    """
    check_choice(kind, "kind", ("step", "release"), "analyze_response")
    t = check_array(t_s, "t_s", ndim=1, min_length=8, increasing=True, error=DataFileError)
    y = check_array(y, "y", ndim=1, shape=(len(t),), error=DataFileError)
    yf = final_value_estimate(y) if final_value is None else float(final_value)
    noise = _noise_level(y)
    t0 = _release_or_step_instant(t, y, kind, yf, noise, t0_s, source)
    i0 = min(int(np.searchsorted(t, t0)), len(t) - 1)
    y0 = _initial_value(t, y, kind, t0, initial_value)
    size = yf - y0  # step size; for a release, minus the initial deflection
    if size == 0.0:
        raise DataFileError(f"{source}: the response does not move (initial value equals final value {yf:g})")
    tt = t[i0:] - t0
    s = (y[i0:] - y0) / size  # normalised equivalent step: 0 at t0, 1 at rest (a release is mirrored)
    x = s - 1.0  # deviation from the final value in units of the step; -1 at t0
    floor = 3.0 * noise / abs(size)  # below this an extremum is noise
    ext_t, ext_v, crossings = _extrema_out_of_noise(tt, x, floor, source, kind, yf)
    return _features(kind, tt, s, t0, y0, yf, size, ext_t, ext_v, crossings)


def _release_or_step_instant(t, y, kind: str, yf: float, noise: float, t0_s: float | None, source: str) -> float:
    """The release/step instant: the one given, a step's first sample, or where a release's first crossing points."""
    if t0_s is not None:
        return float(t0_s)
    if kind == "step":
        return float(t[0])
    t0 = _release_time(t, y - yf, noise)
    if t0 is None:
        raise NoOscillationError(source, kind, yf)
    return t0


def _initial_value(t, y, kind: str, t0: float, initial_value: float | None) -> float:
    """The value before the response: the one given, a step's mean up to ``t0``, a release's value at ``t0``."""
    if initial_value is not None:
        return float(initial_value)
    if kind == "step":
        before = y[t <= t0]
        return float(np.mean(before)) if before.size else float(y[0])
    return float(np.interp(t0, t, y))


def _extrema_out_of_noise(tt, x, floor: float, source: str, kind: str, yf: float):
    """The extrema (times, values) and crossings of the deviation ``x`` up to the first lost in the noise.

    Raises :class:`NoOscillationError` when none stands out of it.
    """
    ext_t, ext_v, crossings = _extrema(tt, x, max(0.005, floor))
    keep = ext_v > floor
    if ext_v.size and not keep.all():
        first_bad = int(np.argmin(keep))
        ext_t, ext_v, crossings = ext_t[:first_bad], ext_v[:first_bad], crossings[: first_bad + 1]
    if ext_t.size == 0:
        raise NoOscillationError(source, kind, yf)
    return ext_t, ext_v, crossings


def _features(kind, tt, s, t0, y0, yf, size, ext_t, ext_v, crossings) -> ResponseFeatures:
    """The features read from the normalised step ``s`` (time ``tt`` from ``t0``) and its extrema."""
    x = s - 1.0
    percent_os = 100.0 * float(ext_v[0])
    peak_time = float(ext_t[0])
    if len(crossings) >= 3:
        wd = float(math.pi / np.mean(np.diff(crossings)))
    elif ext_t.size >= 2:
        wd = float(math.pi / np.mean(np.diff(ext_t)))
    else:
        wd = float(math.pi / peak_time)
    rise = _crossing_time(tt, s, 0.9) - _crossing_time(tt, s, 0.1)
    settling = _settling_time(tt, x, ext_t, ext_v)
    logdec = _log_decrement(ext_v)
    # an undershoot as large as the release (noise on a nearly undamped digit): damping below the resolution
    zeta_os = float(zeta_from_overshoot(percent_os)) if percent_os < 100 else 0.0
    zeta_ld = zeta_from_log_decrement(logdec) if math.isfinite(logdec) and logdec > 0 else math.nan
    ok_ts = math.isfinite(settling) and settling > 0 and zeta_os > 0
    wn_ts = float(wn_from_settling_time(settling, zeta_os)) if ok_ts else math.nan  # 3.1.2
    wn_wd = float(natural_frequency_from_damped(wd, zeta_os)) if math.isfinite(zeta_os) else math.nan  # table 3.2
    scale = size if kind == "step" else -size
    return ResponseFeatures(
        kind=kind,
        t0_s=t0,
        initial_value=y0,
        final_value=yf,
        percent_overshoot=percent_os,
        peak_time_s=peak_time,
        rise_time_s=float(rise),
        settling_time_s=settling,
        wd_rad_s=wd,
        log_decrement=logdec,
        zeta_os=zeta_os,
        zeta_log_decrement=zeta_ld,
        wn_settling_rad_s=wn_ts,
        wn_damped_rad_s=wn_wd,
        extrema_times_s=tuple(float(v) + t0 for v in ext_t),
        extrema_values=tuple(float(v) * scale * (-1) ** k for k, v in enumerate(ext_v)),
    )


def settling_formula_bias(zeta, wn_rad_s: float = 1.0, *, points_per_period: int = 400) -> np.ndarray:
    """Relative error of the thesis's ``wn = 4 / (zeta Ts)`` on exact second-order step responses.

    ``Ts`` is the true 2 % settling time of ``wn^2 / (s^2 + 2 zeta wn s + wn^2)`` (the same for a release test,
    which is a mirrored step); the error ``4 / (zeta Ts wn) - 1`` does not depend on ``wn``.

    Parameters
    ----------
    zeta : float or array_like
        Damping ratios in (0, 1).
    wn_rad_s : float
        Natural frequency used for the simulation (rad/s); the result does not depend on it.
    points_per_period : int
        Time resolution of the simulation.

    Returns
    -------
    ndarray
        ``wn_estimate / wn - 1`` for each ``zeta`` (positive: the formula overestimates).

    Examples
    --------
    >>> [round(float(e), 3) for e in settling_formula_bias([0.068, 0.5629])]   # the digit and the servo
    [0.032, 0.212]
    """
    zetas = np.atleast_1d(check_array(zeta, "zeta", low=0, high=1, low_open=True, high_open=True))
    wn = check_positive(wn_rad_s, "wn_rad_s")
    out = np.empty_like(zetas)
    for k, z in enumerate(zetas):
        wd = wn * math.sqrt(1 - z * z)
        t_end = 1.5 * math.log(50.0 / math.sqrt(1 - z * z)) / (z * wn) + 2 * math.pi / wd
        n = int(t_end / (2 * math.pi / wd) * points_per_period) + 10
        t = np.linspace(0.0, t_end, n)
        x = free_response(t, wn, z)  # step deviation from final value, normalised: s - 1 = -x
        outside = np.nonzero(np.abs(x) > SETTLING_BAND)[0]
        i = outside[-1]
        ts = _interp_level(t[i], t[i + 1], abs(x[i]), abs(x[i + 1]), SETTLING_BAND)
        out[k] = 4.0 / (z * ts * wn) - 1.0
    return out


def free_response(t_s, wn_rad_s: float, zeta: float) -> np.ndarray:
    """Free response of ``x'' + 2 zeta wn x' + wn^2 x = 0`` from ``x(0) = 1, x'(0) = 0`` (any ``zeta >= 0``).

    ``exp(-zeta wn t) (cos(wd t) + zeta wn sin(wd t) / wd)``, continued through critical damping
    (``1 + wn t``) and into overdamping (``cosh``/``sinh``). A unit step response is ``1 - free_response``.

    Examples
    --------
    >>> float(free_response([0.0], 13.1, 0.068)[0])
    1.0
    """
    t = np.asarray(t_s, dtype=float)
    a = zeta * wn_rad_s
    w2 = wn_rad_s**2 * (1.0 - zeta * zeta)
    if w2 > 1e-12 * wn_rad_s**2:
        w = math.sqrt(w2)
        osc = np.cos(w * t) + a * np.sin(w * t) / w
    elif w2 < -1e-12 * wn_rad_s**2:
        w = math.sqrt(-w2)
        # cosh + a sinh / w, written with decaying exponentials so it does not overflow
        return 0.5 * ((1 + a / w) * np.exp((w - a) * t) + (1 - a / w) * np.exp(-(w + a) * t))
    else:
        osc = 1.0 + a * t
    return np.exp(-a * t) * osc


# --- helpers -----------------------------------------------------------------------------------------------------


def _noise_level(y: np.ndarray) -> float:
    """Noise standard deviation: that of the record's last 10 %, or of its second differences if smaller.

    A record that has come to rest shows its noise in its tail; one that has not (a lightly damped digit) still
    oscillates there, and :func:`noise_std` sees only the noise.
    """
    tail = float(np.std(y[-max(3, y.size // 10) :]))
    return min(tail, noise_std(y)) if y.size > 3 else tail


def noise_std(y) -> float:
    """Standard deviation of the white noise on a smooth signal, from its second differences.

    White noise of deviation ``s`` gives second differences of deviation ``s sqrt(6)``, while a signal sampled
    many times per period gives almost none; the median absolute deviation (/0.6745) makes the estimate blind to
    isolated spikes and to a step's few steep samples.

    Examples
    --------
    >>> t = np.arange(0, 4, 0.002)
    >>> y = np.sin(13.1 * t) + np.random.default_rng(0).normal(0, 0.01, t.size)
    >>> round(noise_std(y), 3)
    0.01
    """
    d2 = np.diff(np.asarray(y, dtype=float), 2)
    if d2.size == 0:
        return 0.0
    return float(np.median(np.abs(d2 - np.median(d2)))) / 0.6745 / math.sqrt(6.0)


def _release_time(t: np.ndarray, x: np.ndarray, noise: float) -> float | None:
    """Release instant from the first two final-value crossings after the largest deviation.

    The free response from rest crosses zero first at ``(pi/2 + asin zeta) / wd`` after the release; the crossings
    give ``wd`` and the ratio of the first two extrema ``zeta``, so the instant is found without relying on the
    (noisy, possibly held) samples before it. The crossings are taken from the lobes themselves, not from the
    extrema :func:`_extrema` keeps: on a lightly damped digit a decaying higher mode or a gauge's nonlinearity can
    make the first undershoot smaller than the swing after it, which :func:`_extrema` rejects as noise (then zeta
    is taken as 0: below the resolution of two extrema anyway). Returns None when the record has fewer than two
    crossings.
    """
    dev = np.abs(x)
    # the first near-largest deviation (a lightly damped record swings almost as far later on), then the largest
    # one of its lobe
    start = int(np.argmax(dev >= 0.9 * dev.max()))
    sign = 1.0 if x[start] > 0 else -1.0
    hyst = max(3.0 * noise, 0.01 * dev.max())
    other_side = np.nonzero(sign * x[start:] < -hyst)[0]
    end = start + int(other_side[0]) if other_side.size else x.size
    peak = start + int(np.argmax(sign * x[start:end]))
    xn = -sign * x[peak:] / abs(x[peak])
    tp, h = t[peak:], hyst / abs(x[peak])
    lobes = _lobes(xn, h)
    if len(lobes) < 3 or xn[lobes[0][0]] > 0:
        return None
    crossings = [_zero_before(tp, xn, a) for a, _ in lobes[1:3]]
    ext_t, ext_v, _ = _extrema(tp, xn, h, from_start=False)
    wd = math.pi / (crossings[1] - crossings[0])
    zeta = 0.0
    if ext_v.size >= 2 and ext_v[1] > 0 and ext_v[0] > ext_v[1]:
        delta = 2.0 * math.log(ext_v[0] / ext_v[1])  # per full period
        zeta = delta / math.sqrt(4 * math.pi**2 + delta**2)
    t0 = crossings[0] - (math.pi / 2 + math.asin(zeta)) / wd
    return float(min(max(t0, t[0]), crossings[0]))


def _interp_level(t1: float, t2: float, v1: float, v2: float, level: float) -> float:
    if v2 == v1:
        return t1
    return t1 + (level - v1) * (t2 - t1) / (v2 - v1)


def _crossing_time(t: np.ndarray, s: np.ndarray, level: float) -> float:
    """First time ``s`` reaches ``level`` (linear interpolation); NaN if never."""
    idx = np.nonzero(s >= level)[0]
    if idx.size == 0:
        return math.nan
    k = int(idx[0])
    if k == 0:
        return float(t[0])
    return float(_interp_level(t[k - 1], t[k], s[k - 1], s[k], level))


def _lobes(x: np.ndarray, hysteresis: float) -> list[tuple[int, int]]:
    """Index ranges where ``x`` keeps one sign, switching only past ``+-hysteresis`` (robust to noise)."""
    lobes = []
    sign = 0
    start = 0
    above = x > hysteresis
    below = x < -hysteresis
    k = 0
    n = x.size
    while k < n:
        if sign <= 0:
            hits = np.nonzero(above[k:])[0]
            nxt = k + int(hits[0]) if hits.size else n
        else:
            hits = np.nonzero(below[k:])[0]
            nxt = k + int(hits[0]) if hits.size else n
        if nxt >= n:
            break
        if sign != 0:
            lobes.append((start, nxt))
        elif x[0] * x[nxt] < 0 and abs(x[0]) > hysteresis:
            lobes.append((0, nxt))
        sign = 1 if above[nxt] else -1
        start = nxt
        k = nxt
    if sign != 0:
        lobes.append((start, n))
    elif n:
        lobes.append((0, n))
    return lobes


def _extrema(
    t: np.ndarray, x: np.ndarray, hysteresis: float, *, from_start: bool = True
) -> tuple[np.ndarray, np.ndarray, list[float]]:
    """Extrema of ``x`` past its first lobe (which must be negative), and the zero crossings before each.

    Returns the extremum times, ``|x|`` at them (the sign alternates, the first is positive) and the
    interpolated zero crossings that start each lobe. Empty when ``x`` never rises past ``hysteresis``.
    ``from_start``: ``t[0]`` is the release/step instant, so extrema must come every ``times[0] - t[0]``.
    """
    lobes = _lobes(x, hysteresis)
    if len(lobes) < 2 or x[lobes[0][0]] > 0:
        return np.empty(0), np.empty(0), []
    times, values, crossings = [], [], []
    for a, b in lobes[1:]:
        k = a + int(np.argmax(np.abs(x[a:b])))
        if b == len(x) and k >= len(x) - 2:
            break  # the record ends inside this lobe: no extremum yet
        if values and abs(x[k]) > values[-1] + 2 * hysteresis:
            break  # a second-order response decays: a clearly larger extremum is noise
        if from_start and times and abs((t[k] - times[-1]) - (times[0] - t[0])) > 0.5 * (times[0] - t[0]):
            break  # extrema come every half period (the first one comes half a period after t0): noise
        crossing = _zero_before(t, x, a)
        if crossing is not None:
            crossings.append(crossing)
        tk, vk = _parabolic_peak(t, np.abs(x), k)
        times.append(tk)
        values.append(vk)
    return np.asarray(times), np.asarray(values), crossings


def _zero_before(t: np.ndarray, x: np.ndarray, a: int) -> float | None:
    """The zero crossing that starts the lobe at ``a``: the last sign change before ``x[a]`` (interpolated)."""
    j = a
    while j > 0 and np.sign(x[j - 1]) == np.sign(x[a]):
        j -= 1
    return _interp_level(t[j - 1], t[j], x[j - 1], x[j], 0.0) if j > 0 else None


def _parabolic_peak(t: np.ndarray, v: np.ndarray, k: int) -> tuple[float, float]:
    """Time and value of the peak of ``v`` near sample ``k`` from the parabola through its 3 samples."""
    if k == 0 or k >= v.size - 1:
        return float(t[k]), float(v[k])
    y1, y2, y3 = v[k - 1], v[k], v[k + 1]
    den = y1 - 2 * y2 + y3
    if den >= 0:
        return float(t[k]), float(y2)
    d = 0.5 * (y1 - y3) / den  # offset in samples, in (-1, 1) for a true local maximum
    dt = 0.5 * (t[k + 1] - t[k - 1])
    return float(t[k] + d * dt), float(y2 - 0.25 * (y1 - y3) * d)


def _settling_time(t: np.ndarray, x: np.ndarray, ext_t: np.ndarray, ext_v: np.ndarray) -> float:
    """2 % settling time: when ``|x|`` enters the band after the last extremum outside it (NaN if it never does)."""
    outside = np.nonzero(ext_v > SETTLING_BAND)[0]
    start = int(np.searchsorted(t, ext_t[outside[-1]])) if outside.size else 0
    inside = np.nonzero(np.abs(x[start:]) <= SETTLING_BAND)[0]
    if inside.size == 0:
        return math.nan
    k = start + int(inside[0])
    if k == 0:
        return 0.0
    return float(_interp_level(t[k - 1], t[k], abs(x[k - 1]), abs(x[k]), SETTLING_BAND))


def _log_decrement(extrema: np.ndarray) -> float:
    """Log decrement per full period from successive half-period extrema (least-squares slope of ln|x|)."""
    if extrema.size < 2:
        return math.nan
    k = np.arange(extrema.size)
    slope = np.polyfit(k, np.log(extrema), 1)[0]
    return float(-2.0 * slope)

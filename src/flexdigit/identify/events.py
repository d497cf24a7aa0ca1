"""The step or release in a record, found from the record itself, and what makes a record unfit to identify.

A recording made on a real rig rarely starts at the step (3.2.4) or the release (3.1.2): it holds a baseline
first, or was triggered late; its step may go down; it carries isolated spikes, mains hum and a drifting
baseline. :func:`survey` looks at the record before any model is fitted:

1. **Mains hum** (50 or 60 Hz and its harmonics below 0.45 x the sampling rate) is found as a peak of the
   spectrum of the record minus its low-passed self, standing out of the spectrum around it, and removed by
   least squares (:func:`remove_hum`); the response (a few Hz) does not reach there.
2. **Isolated spikes** are samples far (:data:`SPIKE_SIGMAS` noise deviations) from the running median
   (:func:`find_spikes`). They are counted and reported; the fit itself does not need them removed (it uses a
   robust loss), but the search for the instant uses a copy with them replaced by the running median.
3. **The instant**: on the cleaned record low-passed at :data:`FIND_CUTOFF_HZ`, the first sample that moves
   half-way to the largest deviation from the start level, then back to the last sample still inside the start
   level's noise band; the second-order response leaves its start with zero slope, so that point is a little
   after the instant, and the fit refines it. A ``command`` column, when it changes once, gives the instant
   instead. The record may start at the instant (no baseline): the instant is then its first sample.
4. **Problems** that no fit can overcome: a constant record, no step (or release) above the noise, a change
   spread over the whole record (a drift, not a step), a pulse (the signal returns to its start level: two
   steps), a command that never changes or changes twice, a record too short for the response, a response that
   grows instead of settling.

Problems found only by a fit (two steps in a row, clipping, a poor or uncertain fit) are in
:mod:`flexdigit.identify.quality`.

Examples
--------
>>> t = np.arange(0, 2, 0.002)
>>> tau = np.maximum(t - 0.3, 0)                  # MT(s) of 3.2.4 (20.53 rad/s, 0.5629), stepping down at 0.3 s
>>> x = np.exp(-11.56 * tau) * (np.cos(16.97 * tau) + 11.56 / 16.97 * np.sin(16.97 * tau))
>>> y = 2.0 - 0.4 * (1 - x) + np.random.default_rng(0).normal(0, 0.004, t.size)
>>> s = survey(TimeSeries.from_arrays(t, y), "step")
>>> s.found_from, round(s.t0_s, 2), s.direction, s.baseline_s > 0.25, s.problems
('signal', 0.3, -1, True, ())
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from flexdigit._repr import fields_summary
from flexdigit.errors import DataFileError
from flexdigit.identify.filters import butter_filter
from flexdigit.identify.response import noise_std
from flexdigit.identify.timeseries import TimeSeries

__all__ = [
    "MAINS_HZ",
    "HUM_PROMINENCE",
    "FIND_CUTOFF_HZ",
    "SPIKE_SIGMAS",
    "MIN_SAMPLES_AFTER",
    "MIN_DURATION_DELAYS",
    "Problem",
    "Hum",
    "Survey",
    "survey",
    "find_spikes",
    "remove_hum",
]

#: Mains frequencies whose hum is looked for (Hz).
MAINS_HZ = (50.0, 60.0)
#: A hum peak must stand this many times above the median spectrum around it.
HUM_PROMINENCE = 6.0
#: Low-pass cut-off used to find the instant (Hz): above the rig's dynamics (servo 3.3 Hz, digit 2.1 Hz, 3.1-3.2),
#: below mains hum; capped at 0.2 x the sampling rate.
FIND_CUTOFF_HZ = 20.0
#: A sample this many noise deviations away from its running median is a spike.
SPIKE_SIGMAS = 6.0
#: Fewest samples after the instant.
MIN_SAMPLES_AFTER = 30
#: The record must last this many times the response's delay time (instant to half-way) after the instant.
MIN_DURATION_DELAYS = 4.0


@dataclass(frozen=True)
class Problem:
    """Why a record cannot be identified with confidence: a short ``code`` and a one-line ``message``."""

    code: str
    message: str


@dataclass(frozen=True)
class Hum:
    """Mains hum removed from a record: its fundamental frequency (Hz), the harmonics found (1 is the fundamental)
    and the amplitude of each (signal unit)."""

    frequency_hz: float
    harmonics: tuple[int, ...]
    amplitudes: tuple[float, ...]

    @property
    def amplitude(self) -> float:
        return self.amplitudes[0]


@dataclass(frozen=True)
class Survey:
    """What :func:`survey` found in a record before any fit.

    Attributes
    ----------
    kind : str
        ``"step"`` or ``"release"``.
    t0_s : float or None
        The instant (s, on the record's clock): the estimate the fit starts from; None when none was found.
    found_from : str
        ``"signal"``, ``"command"`` or ``"given"``.
    baseline_s : float
        How long the record holds its start level before the instant (0: it starts at the instant).
    first_sample : int
        First sample of the part of the record a second-order model describes: 0, unless a release record starts
        before the digit was deflected (then the hold's first sample).
    direction : int
        +1 if the signal moves up from its start level (a step up, a release from below), -1 if down.
    start_level, end_level : float
        Median of the low-passed record before the instant (or its first samples) and over its last 10 %.
    delay_s : float
        Time from the instant to the half-way point of the first swing (the response's delay time: a quarter period
        for a lightly damped release, about ``(1 + 0.7 zeta) / wn`` for a step).
    noise_std : float
        White-noise standard deviation (signal unit, :func:`~flexdigit.identify.response.noise_std`).
    spikes : ndarray of int
        Indices of isolated spikes.
    hum : Hum or None
        Mains hum found and removed from ``cleaned``.
    cleaned : ndarray
        The record without its hum (spikes kept: the robust fit copes with them).
    smooth : ndarray
        ``cleaned`` without spikes, low-passed at :data:`FIND_CUTOFF_HZ`.
    input_step : float or None
        Change of the ``command`` column at its step, when it has one.
    problems : tuple of Problem
        What makes the record unfit for identification (empty when nothing was found wrong).
    """

    kind: str
    t0_s: float | None
    found_from: str
    baseline_s: float
    first_sample: int
    direction: int
    start_level: float
    end_level: float
    delay_s: float
    noise_std: float
    spikes: np.ndarray
    hum: Hum | None
    cleaned: np.ndarray
    smooth: np.ndarray
    input_step: float | None = None
    problems: tuple[Problem, ...] = field(default=())

    __repr__ = fields_summary


def survey(series: TimeSeries, kind: str, *, t0_s: float | None = None) -> Survey:
    """Find the step (or release) instant of a record, its spikes and hum, and what makes it unfit to identify.

    Parameters
    ----------
    series : TimeSeries
        The record; its ``u`` (a ``command`` column), when present, gives the instant of a step.
    kind : {"step", "release"}
    t0_s : float, optional
        The instant, when the user knows it (then only the checks run).

    Returns
    -------
    Survey

    Raises
    ------
    DataFileError
        If the signal is constant: nothing at all can be identified from it.
    """
    _refuse_constant(series, kind)
    t = series.t_s
    cleaned, hum, noise, spikes, smooth, noise_smooth = _clean(series)
    problems: list[Problem] = []
    input_step = None
    found_from = "given" if t0_s is not None else "signal"
    if kind == "step" and series.u is not None:
        command_t0, input_step, problem = _command_step(series)
        if problem is not None:
            problems.append(problem)
        elif t0_s is None:
            t0_s, found_from = command_t0, "command"
    what = "step" if kind == "step" else "release"
    growing = _growth(t, smooth, noise_smooth)
    if growing:
        problems.append(Problem("growing", f"growing: {growing}; expected a response that settles (a stable system)"))
    first = _first_swing(t, smooth, noise_smooth, t0_s, kind)
    shared = dict(
        kind=kind, found_from=found_from, noise_std=noise, spikes=spikes, hum=hum, cleaned=cleaned, smooth=smooth,
        input_step=input_step,
    )  # fmt: skip
    if first is None:
        return _nothing_found(series, what, smooth, noise_smooth, t0_s, problems, shared)
    k_on, k_half, k_first, held, start, end, direction, hold = first
    t_on = float(t[k_on])
    if t0_s is None and not held:
        # in mid-swing the instant may lie before the record: the extreme a quarter period before the first crossing
        # of the rest level (the model's phase; the fit moves it on, past the record's start if need be)
        cross = _crossings(t, smooth - end, max(4.0 * noise_smooth, 0.03 * float(np.max(np.abs(smooth - end)))))
        t0_s = cross[0] - 0.5 * (cross[1] - cross[0]) if len(cross) >= 2 else float(t[0])
    elif t0_s is None:
        # the response leaves its start level with zero slope: walk back about a fifth of the time to half-way
        t0_s = max(float(t[k_first]), t_on - 0.2 * float(t[k_half] - t_on)) if k_on > k_first else float(t[k_first])
    delay = float(t[k_half] - t0_s)
    baseline = max(0.0, float(t0_s - t[k_first])) if held else 0.0
    if hold is not None:  # the hold the extreme's band missed: reported, while the fit starts where it did
        baseline = max(baseline, float(t[hold[1]] - t[hold[0]]))
    if not growing:  # a growing record has no settled levels or delay time to judge it by
        problems += _shape_problems(series, kind, t, smooth, noise_smooth, float(t0_s), k_on, start, end, delay)
    return Survey(
        t0_s=float(t0_s),
        baseline_s=baseline,
        direction=direction,
        start_level=start,
        end_level=end,
        delay_s=delay,
        first_sample=k_first,
        problems=tuple(problems),
        **shared,
    )


def _refuse_constant(series: TimeSeries, kind: str) -> None:
    """A constant signal: nothing at all can be identified from it."""
    y = series.y
    if np.ptp(y) == 0.0:
        what = "step" if kind == "step" else "release"
        raise DataFileError(
            f"{series.name}: the signal is constant ({float(y[0]):g} {series.unit}".rstrip()
            + f") over the whole record: no {what} to identify"
        )


def _clean(series: TimeSeries):
    """The record with its hum out, the hum, noise level and spikes, the despiked low-passed signal and its noise."""
    t, y = series.t_s, series.y
    fs = 1.0 / series.dt_s
    cleaned, hum = remove_hum(t, y)
    noise = noise_std(cleaned)
    spikes = find_spikes(cleaned, noise)
    median5 = ndimage.median_filter(cleaned, size=5, mode="nearest")
    despiked = cleaned.copy()
    despiked[spikes] = median5[spikes]
    cutoff = min(FIND_CUTOFF_HZ, 0.2 * fs)
    smooth = butter_filter(despiked, fs, cutoff) if t.size > 30 else despiked
    noise_smooth = noise * math.sqrt(min(1.0, 2.0 * cutoff / fs))
    return cleaned, hum, noise, spikes, smooth, noise_smooth


def _nothing_found(
    series: TimeSeries, what: str, smooth, noise_smooth: float, t0_s, problems: list[Problem], shared: dict
) -> Survey:
    """The survey of a record where no step or release stands out of the noise (a "no-step"/"no-release" problem)."""
    spread = float(np.ptp(smooth))
    problems.append(
        Problem(
            f"no-{what}",
            f"no {what} found: the signal varies by only {spread:.3g} {series.unit}".rstrip()
            + f", {spread / max(noise_smooth, 1e-300):.2g} times its noise after low-pass filtering (expected a "
            f"change of at least 8 times)",
        )
    )
    level = float(np.median(smooth))
    return Survey(
        t0_s=t0_s, baseline_s=0.0, direction=0, start_level=level, end_level=level, delay_s=math.nan,
        first_sample=0, problems=tuple(problems), **shared,
    )  # fmt: skip


def _first_swing(t, smooth, noise, t0_s, kind):
    """``(onset, half-way, first sample, held, start level, end level, direction, hold)`` of the first swing, or
    None; ``hold`` is ``(first, last)`` sample of a release's hold that sits off its first extreme (else None).

    Step: the start level is the median of the first 20 ms (at least 3 samples), refined to the median of
    everything before the onset; the half-way index is the first sample at half the largest deviation from it.
    Release: see :func:`_release_swing`. Indices are samples of ``smooth``; the first sample is where the part of
    the record a second-order model describes begins (0 unless a release record starts before the deflection);
    ``held`` is False for a release record that starts in mid-swing (no baseline before its instant).
    """
    n = smooth.size
    fs = (n - 1) / (t[-1] - t[0])
    end = float(np.median(smooth[-max(3, n // 10) :]))
    if kind == "release" and t0_s is None:
        return _release_swing(smooth, noise, end)
    if t0_s is not None:
        k0 = int(np.clip(np.searchsorted(t, t0_s), 0, n - 1))
        head = smooth[: k0 + 1] if k0 >= 2 else smooth[: max(3, int(0.02 * fs))]
    else:
        k0 = None
        head = smooth[: max(3, int(0.02 * fs))]
    start = float(np.median(head))
    dev = np.abs(smooth - start)
    peak = float(dev.max())
    if peak < 8.0 * noise:
        return None
    k_half = int(np.argmax(dev >= 0.5 * peak))
    if k0 is not None:
        k_half = max(k_half, k0)
        k_on = k0
    else:
        band = max(4.0 * noise, 0.03 * peak)
        inside = np.nonzero(dev[:k_half] <= band)[0]
        k_on = int(inside[-1]) if inside.size else 0
        if k_on >= 3:
            start = float(np.median(smooth[: k_on + 1]))
    direction = 1 if smooth[k_half] > start else -1
    return k_on, k_half, 0, True, start, end, direction, None


def _crossings(t, x, hysteresis: float) -> list[float]:
    """Times (interpolated) where ``x`` changes sign, counting a change only once ``|x|`` passes ``hysteresis``."""
    side = np.where(x > hysteresis, 1, np.where(x < -hysteresis, -1, 0))
    known = np.nonzero(side)[0]
    out = []
    for a, b in zip(known[:-1], known[1:], strict=True):
        if side[a] != side[b]:
            k = a + int(np.argmax(np.sign(x[a : b + 1]) != side[a]))  # first sample past zero
            x0, x1 = x[k - 1], x[k]
            out.append(float(t[k - 1] + (t[k] - t[k - 1]) * x0 / (x0 - x1)) if x1 != x0 else float(t[k]))
    return out


def _release_swing(smooth, noise, end):
    """The first swing of a release: from the held deflection (the first extreme) through the rest level.

    The deflection is the first stretch at 90 % of the largest deviation from the final level; the release is the
    last sample still within the noise band of its extreme before the signal first crosses the final level, and the
    hold is the stretch before it within that band. A record that starts before the deflection (the digit at
    rest, then pushed over by hand) thus starts its model at the hold, not at the push; one that swings through the
    rest level before its first extreme starts in mid-swing and is kept whole.
    """
    dev = np.abs(smooth - end)
    peak = float(dev.max())
    if peak < 8.0 * noise:
        return None
    band = max(4.0 * noise, 0.03 * peak)
    k90 = int(np.argmax(dev >= 0.9 * peak))
    side = np.sign(smooth[k90] - end)
    crossed = np.nonzero(side * (smooth[k90:] - end) < 0)[0]
    k_cross = k90 + int(crossed[0]) if crossed.size else smooth.size - 1
    k_top = k90 + int(np.argmax(dev[k90 : k_cross + 1]))
    level = float(smooth[k_top])
    near = np.abs(smooth - level) <= band
    leave = np.nonzero(~near[k_top : k_cross + 1])[0]  # near[k_top] holds, so leave[0] >= 1
    k_on = k_top + (int(leave[0]) - 1 if leave.size else k_cross - k_top)
    away = np.nonzero(~near[: k_on + 1])[0]
    k_first = int(away[-1]) + 1 if away.size else 0
    hold = _hold_off_the_extreme(smooth, noise, end, peak, band, k_top, k_cross)
    if hold is not None and hold[1] - hold[0] <= k_on - k_first:
        hold = None  # the extreme's band found it already
    held = True
    if np.any(side * (smooth[:k_first] - end) < -band):
        # the signal swung through its rest level before this extreme: the record starts in mid-swing (a gauge near
        # the clamp released from a tip force carries higher modes, 3.1.2), not before a hold; keep all of it
        k_first, held = 0, False
    start = float(np.median(smooth[k_first : k_on + 1]))
    half = np.nonzero(np.abs(smooth[k_on:] - end) <= 0.5 * abs(start - end))[0]
    k_half = k_on + int(half[0]) if half.size else smooth.size - 1
    direction = 1 if smooth[k_half] > start else -1
    return k_on, k_half, k_first, held, start, end, direction, hold


#: How far (fraction of the swing) a hold may sit from the first extreme of a release and still be its hold.
HOLD_OFFSET = 0.1


def _hold_off_the_extreme(smooth, noise, end, peak, band, k_top, k_cross):
    """``(first, onset)`` of a hold a little off the release's first extreme, or None.

    The extreme need not be the hold: the low-pass filter's start-up at a record's first sample can stand a few
    noise deviations off it, and a gauge near the clamp can swing past its held level just after the release (a
    higher mode, 3.1.2). The hold is then the stretch within :data:`HOLD_OFFSET` of the swing of that extreme,
    before the crossing, flat within ``band`` of its median; it counts only when it lasts longer than the
    time from its end to the crossing (a record that starts at the release has no such stretch: its first
    samples are the swing's slow start). It is the baseline :func:`survey` reports; the fit still starts where
    the extreme's band put it, so records whose hold that band found are identified exactly as before.
    """
    wide = np.abs(smooth[: k_cross + 1] - smooth[k_top]) <= HOLD_OFFSET * peak
    outside = np.nonzero(~wide[: k_top + 1])[0]
    first = int(outside[-1]) + 1 if outside.size else 0
    after = np.nonzero(~wide[k_top:])[0]
    last = k_top + int(after[0]) if after.size else k_cross
    if last - first < 3:
        return None
    level = float(np.median(smooth[first:last]))
    flat = np.abs(smooth[first:last] - level) <= band
    start = first + int(np.argmax(flat))  # past a start-up transient
    leave = np.nonzero(~flat[start - first :])[0]
    onset = start + int(leave[0]) - 1 if leave.size else last - 1
    if onset - start <= k_cross - onset or abs(level - end) < 8.0 * noise:
        return None
    return start, onset


def _shape_problems(series, kind, t, smooth, noise, t0, k_on, start, end, delay) -> list[Problem]:
    """A pulse, a ramp, a record too short for its response, and a response that grows instead of settling."""
    unit = series.unit
    what = "step" if kind == "step" else "release"
    problems = []
    n_after = int(np.sum(t > t0))
    after_s = float(t[-1] - t0)
    dev = smooth - start
    peak = float(np.max(np.abs(dev)))
    if n_after < MIN_SAMPLES_AFTER or after_s < MIN_DURATION_DELAYS * delay:
        need = MIN_DURATION_DELAYS * delay
        problems.append(
            Problem(
                "too-short",
                f"too short: the record ends {after_s:.3g} s ({n_after} samples) after the {what} at "
                f"{t0:.4g} s, but its response needs at least {need:.2g} s ({MIN_DURATION_DELAYS:g} x the "
                f"{delay:.2g} s it takes to swing half-way) and {MIN_SAMPLES_AFTER} samples to be identified",
            )
        )
        return problems
    if kind == "step" and abs(end - start) < 0.3 * peak:
        k_back = int(np.nonzero(np.abs(dev) >= 0.5 * peak)[0][-1])
        problems.append(
            Problem(
                "two-steps",
                f"two steps: the signal leaves its start level {start:.4g} {unit} at {t0:.4g} s and comes back "
                f"to {end:.4g} {unit} after {float(t[k_back]):.4g} s (a pulse); cut the record to one step",
            )
        )
        return problems
    total = end - start
    k90 = np.nonzero(np.abs(dev) >= 0.9 * abs(total))[0]
    k90 = k90[k90 >= k_on]
    if kind == "step" and k90.size and t[k90[0]] - t0 > 0.6 * after_s:
        problems.append(
            Problem(
                f"no-{what}",
                f"no clear step: the signal takes {float(t[k90[0]] - t0):.3g} s of the {after_s:.3g} s after "
                f"{t0:.4g} s to change by 90 % (a drift or a ramp, or a record too short for a slow response)",
            )
        )
        return problems
    # a release's free swing can linger (higher modes on a gauge near the clamp): a second release is left to the
    # fit's misfit; a step's levels are flat once it has settled
    levels = _plateaus(t, smooth, noise, peak, 2.0 * delay) if kind == "step" else []
    later = [lv for lv in levels if lv[0] > k_on]
    if len(later) >= 2:
        (a0, a1, level_a), (b0, _, level_b) = later[0], later[1]
        again = "steps" if kind == "step" else "releases"
        problems.append(
            Problem(
                "two-steps",
                f"two {again}: after the {what} at {t0:.4g} s the signal settles at {level_a:.4g} {unit}".rstrip()
                + f" ({float(t[a0]):.4g}-{float(t[a1]):.4g} s), then moves on to {level_b:.4g} {unit}".rstrip()
                + f" (from {float(t[b0]):.4g} s); cut the record to one {what}",
            )
        )
    return problems


def _plateaus(t, smooth, noise, peak, window_s) -> list[tuple[int, int, float]]:
    """``(first, last, level)`` of the stretches where the signal stays flat for ``window_s``, merged by level.

    Flat: the range over a centred window is within ``max(8 noise, 5 % of the swing)``; consecutive stretches whose
    levels differ by less than 20 % of the swing are one level (the same plateau broken by a spike or a slow
    drift).
    """
    fs = (t.size - 1) / (t[-1] - t[0])
    w = max(5, int(window_s * fs)) if math.isfinite(window_s) else 5
    if w >= smooth.size:
        return []
    spread = ndimage.maximum_filter1d(smooth, w) - ndimage.minimum_filter1d(smooth, w)
    flat = spread <= max(8.0 * noise, 0.05 * peak)
    edges = np.diff(np.concatenate([[0], flat.astype(int), [0]]))
    runs = [(int(a), int(b) - 1) for a, b in zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0], strict=True)]
    out: list[tuple[int, int, float]] = []
    for a, b in runs:
        if b - a + 1 < w:
            continue
        level = float(np.median(smooth[a : b + 1]))
        if out and abs(level - out[-1][2]) < 0.2 * peak:
            out[-1] = (out[-1][0], b, out[-1][2])
        else:
            out.append((a, b, level))
    return out


def _growth(t, smooth, noise) -> str:
    """Why the record grows instead of settling, or ``""``.

    An oscillation whose swing about the final level is larger in the last third of the record than in the middle
    third, or a signal whose rate of change grows quarter after quarter (an exponential run-away). A response that
    settles does neither, wherever its instant is.
    """
    n = smooth.size
    if n < 16:
        return ""
    end = float(np.median(smooth[-max(3, n // 10) :]))
    thirds = np.array_split(smooth, 3)
    middle, last = (float(np.percentile(np.abs(x - end), 95)) for x in thirds[1:])
    if last > 1.25 * middle and last > 10.0 * noise:
        return f"its swing about {end:.4g} grows from {middle:.3g} in the middle third of the record to {last:.3g}"
    quarters = np.array_split(np.arange(n), 4)
    slopes = [float(np.polyfit(t[q], smooth[q], 1)[0]) for q in quarters[1:]]
    span = float(t[quarters[2][-1]] - t[quarters[2][0]])
    same_sign = slopes[0] * slopes[1] > 0 and slopes[1] * slopes[2] > 0
    if (
        same_sign
        and abs(slopes[2]) > 1.5 * abs(slopes[1]) > 2.25 * abs(slopes[0])
        and abs(slopes[1]) * span > 10.0 * noise
    ):
        rates = ", ".join(f"{v:.3g}" for v in slopes)
        return f"its rate of change grows quarter after quarter ({rates} per s over the last three quarters)"
    return ""


def _command_step(series: TimeSeries) -> tuple[float | None, float | None, Problem | None]:
    """``(instant, input change, problem)`` from the command column: one change is a step; none or two are not."""
    t, u = series.t_s, series.u
    moved = np.nonzero(np.abs(np.diff(u)) > 1e-9 * max(1.0, float(np.max(np.abs(u)))))[0] + 1
    col = series.input_name or "command"
    if moved.size == 0:
        return (
            None,
            None,
            Problem(
                "command",
                f"no step in the {col!r} column: it stays at {float(u[0]):g} over the whole record (expected "
                "one change of the command); drop the column to find the step from the signal, or pass --force",
            ),
        )
    # a change spread over a few consecutive samples (a slew-limited or interpolated command) is one step
    groups = np.split(moved, np.nonzero(np.diff(moved) > 3)[0] + 1)
    if len(groups) > 1:
        times = ", ".join(f"{float(t[g[0]]):.4g}" for g in groups[:4])
        more = " ..." if len(groups) > 4 else ""
        return (
            None,
            None,
            Problem(
                "two-steps",
                f"two steps: the {col!r} column changes {len(groups)} times (at t = {times}{more} s); cut the "
                "record to one step",
            ),
        )
    k = int(moved[0])
    t0 = 0.5 * float(t[k - 1] + t[k])  # the input changed somewhere between the two samples: the midpoint
    du = float(np.mean(u[int(groups[0][-1]) :]) - u[0])
    return t0, du, None


def find_spikes(y, noise: float) -> np.ndarray:
    """Indices of isolated spikes: samples more than :data:`SPIKE_SIGMAS` x ``noise`` beyond the median of the three
    samples before them *and* of the three after them, on the same side.

    A sample on a steep edge differs from its two sides with opposite signs, a step's corner from one side only:
    neither is a spike, however fast the signal moves, while a spike on that edge still stands out of both. Runs
    of more than two such samples are a feature of the signal, not spikes.

    Examples
    --------
    >>> y = np.linspace(0, 10, 200)
    >>> y[[50, 51, 120]] += [3.0, -2.0, 4.0]
    >>> find_spikes(y, 0.01).tolist()
    [50, 51, 120]
    """
    x = np.asarray(y, dtype=float)
    if x.size < 7 or noise <= 0:
        return np.empty(0, dtype=int)
    p = np.pad(x, 3, mode="edge")
    n = x.size
    before = x - _median3(p[0:n], p[1 : n + 1], p[2 : n + 2])
    after = x - _median3(p[4 : n + 4], p[5 : n + 5], p[6 : n + 6])
    threshold = SPIKE_SIGMAS * noise
    out = ((before > threshold) & (after > threshold)) | ((before < -threshold) & (after < -threshold))
    idx = np.nonzero(out)[0]
    if idx.size == 0:
        return idx
    runs = np.split(idx, np.nonzero(np.diff(idx) > 1)[0] + 1)
    return np.concatenate([r for r in runs if r.size <= 2] or [np.empty(0, dtype=int)]).astype(int)


def _median3(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Element-wise median of three arrays (without sorting)."""
    return np.maximum(np.minimum(a, b), np.minimum(np.maximum(a, b), c))


def remove_hum(t_s, y, *, mains_hz=MAINS_HZ, max_harmonics: int = 5) -> tuple[np.ndarray, Hum | None]:
    """The record without its mains hum, and the hum found (None if none stands out).

    The record minus its low-passed self (running median of 5, then Butterworth at 20 Hz) holds the noise and
    the hum; a hum is a peak of its (zero-padded, Hann-windowed) spectrum within 1 Hz of a mains frequency,
    :data:`HUM_PROMINENCE` times the median of the spectrum from 0.6 to 1.4 times that frequency. Its frequency is
    refined by a parabola through the log magnitudes of the peak's three bins (the spectrum padded to at least 4
    times the record: a Hann window's peak is then nearly a Gaussian, and the frequency is found to a small
    fraction of ``1 / duration``, so the hum's phase does not slip over the record); the fundamental and the
    harmonics that also stand out are fitted to the whole record by linear least squares and subtracted.

    Examples
    --------
    >>> t = np.arange(0, 2, 1e-3)
    >>> y = np.tanh(3 * t) + 0.05 * np.sin(2 * np.pi * 50.0 * t + 1.0)
    >>> clean, hum = remove_hum(t, y)
    >>> round(hum.frequency_hz, 2), round(hum.amplitude, 3), bool(np.max(np.abs(clean - np.tanh(3 * t))) < 2e-3)
    (50.0, 0.05, True)
    """
    t = np.asarray(t_s, dtype=float)
    x = np.asarray(y, dtype=float)
    n = x.size
    if n < 64:
        return x.copy(), None
    fs = (n - 1) / (t[-1] - t[0])
    slow = butter_filter(ndimage.median_filter(x, size=5, mode="nearest"), fs, min(FIND_CUTOFF_HZ, 0.2 * fs))
    hf = x - slow
    mad = float(np.median(np.abs(hf - np.median(hf)))) * 1.4826
    if mad == 0:
        return x.copy(), None
    hf = np.clip(hf, -5 * mad, 5 * mad)  # spikes spread over the whole spectrum: clip them first
    nfft = 1 << int(math.ceil(math.log2(4 * n)))
    spec = np.abs(np.fft.rfft(hf * np.hanning(n), nfft))
    freqs = np.fft.rfftfreq(nfft, 1.0 / fs)
    best = None
    for base in mains_hz:
        found = _peak(spec, freqs, base, fs)
        if found and (best is None or found[1] > best[1]):
            best = found
    if best is None:
        return x.copy(), None
    f0 = best[0]
    harmonics = [1] + [k for k in range(2, max_harmonics + 1) if _peak(spec, freqs, k * f0, fs, window=0.5)]
    cols = []
    for k in harmonics:
        w = 2 * np.pi * k * f0 * (t - t[0])
        cols += [np.cos(w), np.sin(w)]
    basis = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(basis, hf, rcond=None)
    amps = tuple(float(math.hypot(coef[2 * i], coef[2 * i + 1])) for i in range(len(harmonics)))
    return x - basis @ coef, Hum(float(f0), tuple(harmonics), amps)


def _peak(spec, freqs, f, fs, window: float = 1.0):
    """``(frequency, prominence)`` of a spectral peak within ``window`` Hz of ``f`` that stands out, or None."""
    if f + window >= 0.45 * fs:
        return None
    df = float(freqs[1] - freqs[0])

    def bin_of(freq: float) -> int:
        return int(np.clip(round(freq / df), 0, spec.size - 1))

    near = spec[bin_of(f - window) : bin_of(f + window) + 1]
    lo, hi = bin_of(0.6 * f), bin_of(min(1.4 * f, 0.45 * fs))
    gap_lo, gap_hi = bin_of(f - 2 * window), bin_of(f + 2 * window)
    around = np.concatenate([spec[lo:gap_lo], spec[gap_hi + 1 : hi + 1]])
    if near.size == 0 or around.size < 8:
        return None
    k = bin_of(f - window) + int(np.argmax(near))
    floor = float(np.median(around))
    prominence = float(spec[k]) / floor if floor > 0 else math.inf
    if prominence < HUM_PROMINENCE:
        return None
    if 0 < k < spec.size - 1:  # parabola through the log magnitudes of the three bins around the peak
        a, b, c = np.log(spec[k - 1 : k + 2] + 1e-300)
        d = 0.5 * (a - c) / (a - 2 * b + c) if (a - 2 * b + c) < 0 else 0.0
        return float(freqs[k] + d * df), prominence
    return float(freqs[k]), prominence

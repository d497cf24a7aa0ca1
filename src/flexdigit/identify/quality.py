"""How far a fitted second-order model can be trusted: the quality every identification reports.

Three figures, from the residuals of the model against the record (its hum removed):

- the **NRMSE fit** (%) and MATLAB's ``corr2`` (:mod:`flexdigit.identify.scores`), as the thesis reported;
- the **misfit**: the deviation of the residuals low-passed at three times the model's natural frequency (the
  structure the model misses, at the time scale of the response, white noise mostly filtered out) that only 1 % of
  the record exceeds, in % of the response's amplitude (the step, or the released deflection);
- **residual whiteness**: the Ljung-Box test (:func:`~flexdigit.identify.scores.ljung_box`) on the residuals
  averaged over blocks of a tenth of the natural period, spikes taken out first. Averaging makes noise that a DAQ's
  anti-alias filter coloured look white again, while a model error, which is slow, stays correlated.

From them and the confidence intervals come the problems that make a fit untrustworthy
(:class:`~flexdigit.identify.events.Problem`): a second step after the first has settled (or a change before
it), samples stuck at the record's extreme where the model goes on (clipping), a poor fit (a misfit over
:data:`MAX_MISFIT_PERCENT`, and over twice what the record's white noise alone leaves through the same filter, so
a weak channel's noise is not taken for a model error), and confidence intervals wider than
:data:`MAX_CI_HALFWIDTH`. A
non-white residual alone is a warning: the model holds but misses some structure (higher modes, 3.1.2), and its
confidence intervals are optimistic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit.identify.events import Problem, find_spikes
from flexdigit.identify.filters import butter_filter
from flexdigit.identify.scores import LjungBox, corr2, ljung_box, nrmse_fit

__all__ = [
    "MAX_MISFIT_PERCENT",
    "MAX_CI_HALFWIDTH",
    "WHITENESS_P",
    "SECOND_STEP_FRACTION",
    "QUANTISED_STEPS",
    "FitQuality",
    "assess",
]

#: A fit whose record deviates from it by more than this (% of the response's amplitude) is poor.
MAX_MISFIT_PERCENT = 10.0
#: Widest acceptable 95 % confidence half-width, relative to the value, of each identified parameter.
MAX_CI_HALFWIDTH = {"wn_rad_s": 0.10, "zeta": 0.25}
#: Below this Ljung-Box p-value the residuals are reported as not white.
WHITENESS_P = 0.001
#: A low-passed residual beyond this fraction of the response's amplitude, after it settled, is a second step.
SECOND_STEP_FRACTION = 0.15


@dataclass(frozen=True)
class FitQuality:
    """The quality of one fit (see the module docstring).

    Attributes
    ----------
    fit_percent, corr2 : float
        NRMSE fit (%) and ``corr2`` of the model against the record (hum removed).
    residual_std : float
        Robust standard deviation of the residuals (signal unit).
    misfit_percent : float
        Deviation of the low-passed residual exceeded by 1 % of the record, in % of the response's amplitude.
    noise_misfit_percent : float
        The same for the record's white noise alone (what a perfect model would show).
    whiteness : LjungBox
        Ljung-Box test of the block-averaged residuals.
    block_s : float
        Block length of the whiteness test (s).
    problems : tuple of Problem
        What makes the fit untrustworthy (refused unless forced).
    warnings : tuple of str
        What the user should know, the fit standing.
    """

    fit_percent: float
    corr2: float
    residual_std: float
    misfit_percent: float
    noise_misfit_percent: float
    whiteness: LjungBox
    block_s: float
    problems: tuple[Problem, ...]
    warnings: tuple[str, ...]

    def summary(self) -> dict:
        return {
            "fit_percent": self.fit_percent,
            "corr2": self.corr2,
            "residual_std": self.residual_std,
            "misfit_percent": self.misfit_percent,
            "noise_misfit_percent": self.noise_misfit_percent,
            "whiteness": {
                "test": "Ljung-Box",
                "lags": self.whiteness.lags,
                "block_s": self.block_s,
                "q": self.whiteness.q,
                "p_value": self.whiteness.p_value,
                "white": self.whiteness.p_value >= WHITENESS_P,
            },
        }

    __repr__ = fields_summary


def assess(
    t_s,
    y,
    model,
    *,
    kind: str,
    wn_rad_s: float,
    zeta: float,
    amplitude: float,
    t0_s: float,
    estimates: dict | None = None,
    raw=None,
    noise_std: float = 0.0,
    unit: str = "",
    method: str = "lsq",
) -> FitQuality:
    """Judge a fitted model ``model`` (its response at ``t_s``) against the record ``y`` (hum removed).

    Parameters
    ----------
    t_s, y, model : array_like
        Times (s), the record and the model's response there.
    kind : {"step", "release"}
    wn_rad_s, zeta, amplitude, t0_s : float
        The fitted model (``amplitude``: step size or released deflection, signal unit).
    estimates : dict of str to Estimate, optional
        Confidence intervals to check (``lsq``).
    raw : array_like, optional
        The record as read (with its hum), where clipped samples are looked for; default ``y``.
    noise_std : float
        White-noise deviation of the record (signal unit), the margin of the clipping test.
    unit : str
        Signal unit, for messages.
    method : str
        The method that gave the model. Only the fit of the whole record (``lsq``) can tell a bad record by a
        poor fit; the thesis's formulas and ARX miss good records by their own errors, so for them a poor fit is a
        warning about the method, not a refusal of the record.

    Returns
    -------
    FitQuality

    Examples
    --------
    >>> t = np.arange(0, 2, 0.002)
    >>> clean = 1 - np.exp(-11.6 * t) * (np.cos(17 * t) + 11.6 / 17 * np.sin(17 * t))
    >>> y = clean + np.random.default_rng(1).normal(0, 0.01, t.size)
    >>> q = assess(t, y, clean, kind="step", wn_rad_s=20.58, zeta=0.5636, amplitude=1.0, t0_s=0.0)
    >>> q.problems, q.misfit_percent < 2, q.whiteness.p_value > 0.01
    ((), True, True)
    """
    t = np.asarray(t_s, dtype=float)
    yv = np.asarray(y, dtype=float)
    m = np.asarray(model, dtype=float)
    fs = (t.size - 1) / (t[-1] - t[0])
    scale, clipped, slow, cutoff = _residual(yv - m, fs, wn_rad_s)
    misfit, noise_misfit, limit = _misfit_percent(slow, fs, cutoff, amplitude, noise_std)
    lb, block = _whiteness(clipped, fs, wn_rad_s)
    raw_v = np.asarray(raw if raw is not None else yv, dtype=float)
    problems = _saturation_and_misfit(t, raw_v, m, slow, kind, wn_rad_s, zeta, amplitude, t0_s, noise_std, unit,
                                      misfit, limit, method)  # fmt: skip
    problems += _uncertain(estimates)
    warnings = _warnings(method, misfit, limit, lb, block / fs)
    return FitQuality(
        fit_percent=nrmse_fit(yv, m),
        corr2=corr2(yv, m),
        residual_std=scale,
        misfit_percent=misfit,
        noise_misfit_percent=noise_misfit,
        whiteness=lb,
        block_s=block / fs,
        problems=tuple(problems),
        warnings=tuple(warnings),
    )


def _residual(r: np.ndarray, fs: float, wn_rad_s: float) -> tuple[float, np.ndarray, np.ndarray, float]:
    """The residual's robust scale, the residual with its spikes out, its slow part and that part's cut-off (Hz).

    A systematic deviation is a run of samples, never a spike; the slow part is below 3 x the model's frequency.
    """
    scale = 1.4826 * float(np.median(np.abs(r - np.median(r))))
    clipped = r.copy()  # spikes out (a systematic deviation is a run of samples, never a spike)
    spikes = find_spikes(r, scale)
    clipped[spikes] = np.median(r)
    fn = wn_rad_s / (2 * math.pi)
    cutoff = min(max(3.0 * fn, 1.0), 0.4 * fs)
    slow = butter_filter(clipped, fs, cutoff) if r.size > 30 else clipped
    return scale, clipped, slow, cutoff


def _misfit_percent(
    slow: np.ndarray, fs: float, cutoff: float, amplitude: float, noise_std: float
) -> tuple[float, float, float]:
    """The misfit (% of the response), what white noise alone leaves there, and the limit a misfit may reach."""
    # the 99th percentile, not the maximum: a brief fast transient (higher modes excited at the release, 3.1.2)
    # is not a misfit of the dominant mode, while a model error or a second step lasts
    misfit = 100.0 * float(np.percentile(np.abs(slow), 99)) / abs(amplitude) if amplitude else math.inf
    # what white noise alone leaves there: its 99th percentile through the same filter (Gaussian, 2.576 sigma)
    noise_misfit = 100.0 * 2.576 * noise_std * _noise_gain(fs, cutoff) / abs(amplitude) if amplitude else 0.0
    return misfit, noise_misfit, max(MAX_MISFIT_PERCENT, 2.0 * noise_misfit)


def _whiteness(clipped: np.ndarray, fs: float, wn_rad_s: float):
    """Ljung-Box test of the residual's block means (blocks of a tenth of the model's period) and the block size."""
    fn = wn_rad_s / (2 * math.pi)
    block = max(1, int(fs / (10.0 * fn))) if fn > 0 else 1
    nb = clipped.size // block
    means = clipped[: nb * block].reshape(nb, block).mean(axis=1) if nb >= 8 else clipped
    lags = int(min(20, max(1, means.size // 5)))
    return ljung_box(means, lags), block


def _saturation_and_misfit(
    t, raw, m, slow, kind, wn_rad_s, zeta, amplitude, t0_s, noise_std, unit, misfit, limit, method
) -> list[Problem]:
    """A clipped record, and (for the fit of the whole record, ``lsq``) a misfit over the limit."""
    problems: list[Problem] = []
    sat = _saturation(t, raw, m, noise_std, abs(amplitude), unit)
    if sat:  # plateaus that are a coarse ADC's levels, not a rail: said as what they are
        sat = _quantised(raw, unit) or sat
    if sat:
        problems.append(sat)
    if misfit > limit and method == "lsq":
        problems.append(_misfit(t, slow, kind, wn_rad_s, zeta, amplitude, t0_s, misfit, limit))
    return problems


def _uncertain(estimates: dict | None) -> list[Problem]:
    """A problem for each of wn and zeta whose 95 % interval is wider than :data:`MAX_CI_HALFWIDTH` allows."""
    problems: list[Problem] = []
    for name, limit in MAX_CI_HALFWIDTH.items():
        e = (estimates or {}).get(name)
        if e is not None and not (e.relative_halfwidth <= limit):
            label = "wn" if name == "wn_rad_s" else "zeta"
            problems.append(
                Problem(
                    "uncertain",
                    f"not identified with confidence: the 95 % interval of {label} is +-"
                    f"{100 * e.relative_halfwidth:.3g} % of its value {e.value:.4g} (at most +-{100 * limit:g} %): "
                    "the record is too short or too noisy for this response",
                )
            )
    return problems


def _warnings(method: str, misfit: float, limit: float, lb, block_s: float) -> list[str]:
    """A misfit of another method than lsq (its own error, not the record's), and residuals that are not white."""
    warnings: list[str] = []
    if misfit > limit and method != "lsq":
        warnings.append(
            f"the record deviates from the {method} method's model by up to {misfit:.2g} % of the response "
            f"(more than {limit:.2g} %): its wn or zeta is off; the lsq method fits the whole record"
        )
    if lb.p_value < WHITENESS_P:
        warnings.append(
            f"residuals not white (Ljung-Box p = {lb.p_value:.2g} over {lb.lags} lags of {block_s * 1e3:.3g} ms "
            f"blocks; misfit {misfit:.2g} % of the response): the model misses some structure, so its "
            "confidence intervals are optimistic"
        )
    return warnings


#: A record spanning at most this many quantisation steps is too coarse to identify: its "plateaus" are its levels,
#: not a rail (trial 2: a 10-bit ADC's release record spanned ~5 steps and was called saturated).
QUANTISED_STEPS = 16


def _quantised(raw, unit) -> Problem | None:
    """A record that spans at most :data:`QUANTISED_STEPS` of its own quantisation step (the smallest difference
    between its values): what is wrong is the resolution, not a rail."""
    values = np.unique(np.asarray(raw, dtype=float))
    if values.size < 2:
        return None
    step = float(np.min(np.diff(values)))
    spans = int(round(float(values[-1] - values[0]) / step))
    if spans > QUANTISED_STEPS:
        return None
    return Problem(
        "quantised",
        f"quantised: the record spans {spans} ADC steps of {step:.3g} {unit}".rstrip()
        + ", too few to identify a response from: raise the amplifier gain or the ADC's bits",
    )


def _saturation(t, raw, model, noise, amplitude, unit) -> Problem | None:
    """Samples stuck at the record's maximum (or minimum): a clipped record.

    Either the model goes on beyond that value by more than twice the noise and 0.5 % of the response at three of
    them or more, or, in a noisy record, the value holds at least 10 samples, three times as many as any other
    value (a rail; a plateau quantised finer than its noise shares its samples with the levels next to it, and a
    record quantised coarser than its noise shows no noise at all).
    """
    margin = 2.0 * noise + 0.005 * amplitude
    values, counts = np.unique(raw, return_counts=True)
    for k, sign, word in ((values.size - 1, 1.0, "maximum"), (0, -1.0, "minimum")):
        extreme, n_at = float(values[k]), int(counts[k])
        if n_at < 3:
            continue
        at = np.nonzero(raw == extreme)[0]
        beyond = sign * (model[at] - extreme)
        others = int(np.max(np.delete(counts, k))) if counts.size > 1 else 0
        if int(np.sum(beyond > margin)) >= 3:
            why = f"where the model goes {float(beyond.max()):.3g} {unit} beyond it"
        elif noise > 0 and n_at >= 10 and n_at > 3 * others:
            why = f"{n_at / max(others, 1):.3g} times as many as any other value"
        else:
            continue
        return Problem(
            "saturated",
            f"saturated: {n_at} samples stuck at {extreme:.6g} {unit}".rstrip()
            + f", the record's {word} (first at {float(t[at[0]]):.4g} s), {why}: the amplifier or the ADC "
            "clipped (lower the gain or the step)",
        )
    return None


@lru_cache(maxsize=256)  # a pure function of two floats, asked again for every record at the same rate and cut-off
def _noise_gain(fs: float, cutoff: float) -> float:
    """Standard deviation of unit white noise after :func:`~flexdigit.identify.filters.butter_filter` at ``cutoff``."""
    n = int(min(200_000, max(64, 40 * fs / cutoff)))
    impulse = np.zeros(n)
    impulse[n // 2] = 1.0
    return float(np.sqrt(np.sum(butter_filter(impulse, fs, cutoff) ** 2)))


def _misfit(t, slow, kind, wn, zeta, amplitude, t0, misfit, limit) -> Problem:
    """A second step, a change before the instant, or plainly a poor fit, from where the residual is large."""
    big = np.nonzero(np.abs(slow) > SECOND_STEP_FRACTION * abs(amplitude))[0]
    settled = t0 + (4.0 / (zeta * wn) if zeta * wn > 0 else math.inf)
    if kind == "step" and big.size:
        tx = float(t[big[0]])
        if tx > settled:
            return Problem(
                "two-steps",
                f"two steps: after the step at {t0:.4g} s has settled, the signal moves again from about "
                f"{tx:.4g} s (one step misses it by {misfit:.2g} % of the response); cut the record to one step",
            )
        if tx < t0:
            return Problem(
                "two-steps",
                f"two steps: the signal already changes at about {tx:.4g} s, before the step at {t0:.4g} s "
                f"(one step misses it by {misfit:.2g} % of the response); cut the record to one step",
            )
    return Problem(
        "poor-fit",
        f"poor fit: the record deviates from the best second-order {kind} response by up to {misfit:.2g} % of "
        f"the response (at most {limit:.2g} %): it does not look like one {kind} response",
    )

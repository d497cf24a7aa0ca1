"""From a release or step record to a validated second-order model (thesis 3.1.2, 3.2.4), two ways.

``method="thesis"`` does what the thesis did: filter the record, read the percent overshoot and the 2 % settling
time, ``zeta`` from %OS and ``wn = 4 / (zeta Ts)`` (the text of 3.1.2; table 3.2 actually used
``wn = wd / sqrt(1 - zeta^2)``, reported as ``wn_damped_rad_s``). ``method="lsq"`` fits the whole raw record by
least squares (:class:`~flexdigit.identify.fit.SecondOrderFit`, robust ``soft_l1`` loss, with a baseline drift)
and gives confidence intervals. Neither needs to be told where the step or release is: :func:`survey
<flexdigit.identify.events.survey>` finds it (and removes mains hum); every fit is judged
(:mod:`flexdigit.identify.quality`: NRMSE fit, MATLAB's ``corr2``, the misfit (largest systematic deviation),
Ljung-Box whiteness of the residuals), and a record that cannot be identified with confidence (no step, two
steps, too short, clipped, growing, a poor or uncertain fit) is refused with the reason unless ``force=True``.

Examples
--------
>>> from flexdigit.identify.fit import second_order_response
>>> t = np.arange(0, 8, 0.002)
>>> y = second_order_response(t, "release", 13.1, 0.068, 0.0, 1.0, 0.5)
>>> y = y + np.random.default_rng(0).normal(0, 0.02, t.size)
>>> r = identify(TimeSeries.from_arrays(t, y), "release", method="lsq")
>>> round(r.wn_rad_s, 1), round(r.zeta, 2)      # digit of 3.1.2: 13.1 rad/s, 0.068
(13.1, 0.07)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import control
import numpy as np

from flexdigit._repr import summary
from flexdigit._validation import check_choice, check_real
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.identify.events import Problem, Survey, survey
from flexdigit.identify.filters import FILTERS, apply_filter, butter_filter, default_cutoff_hz
from flexdigit.identify.fit import LOSSES, Estimate, SecondOrderFit, fit_arx, second_order_response
from flexdigit.identify.quality import FitQuality, assess
from flexdigit.identify.response import NoOscillationError, ResponseFeatures, analyze_response
from flexdigit.identify.timeseries import TimeSeries

__all__ = ["METHODS", "KINDS", "Identification", "identify", "average_runs"]

METHODS = ("thesis", "lsq", "arx")
KINDS = ("release", "step")


@dataclass(frozen=True)
class Identification:
    """A second-order model identified from one record, and how well it reproduces it.

    Attributes
    ----------
    kind, method, filter : str
        Experiment (``release``/``step``), method (``thesis``/``lsq``) and the filter used for the features.
    source, channel, unit : str
        Where the record came from.
    wn_rad_s, zeta : float
        The identified model ``wn^2 / (s^2 + 2 zeta wn s + wn^2)``.
    gain : float
        Step: output change per input change (signal unit per input unit) when the input step is known, else the
        output change. Release: the initial deflection (signal unit).
    offset, amplitude, t0_s : float
        As in :func:`~flexdigit.identify.fit.second_order_response`.
    estimates : dict of str to Estimate, or None
        ``lsq`` only: every fitted parameter with its confidence interval.
    features : ResponseFeatures or None
        The thesis-style features of the filtered record (None for an ``lsq``/``arx`` fit of a record without
        overshoot: an overdamped step, or a release with ``allow_overdamped=True``).
    corr2, fit_percent : float
        MATLAB ``corr2`` and NRMSE fit (%) of the model response against the record (its mains hum removed).
    drift_per_s : float
        Baseline drift fitted with the model (signal unit per second; 0 for the thesis and ARX methods).
    survey : Survey or None
        What was found in the record before the fit: the instant and where it came from, spikes, hum, noise.
    quality : FitQuality or None
        Unexplained part, residual whiteness and the problems found after the fit.
    warnings : tuple of str
        Problems overridden with ``force=True`` and other findings the user should read.
    """

    kind: str
    method: str
    filter: str
    source: str
    channel: str
    unit: str
    wn_rad_s: float
    zeta: float
    gain: float
    offset: float
    amplitude: float
    t0_s: float
    estimates: dict[str, Estimate] | None
    features: ResponseFeatures | None
    corr2: float
    fit_percent: float
    drift_per_s: float = 0.0
    drift_reference_s: float = 0.0
    survey: Survey | None = field(default=None, repr=False, compare=False)
    quality: FitQuality | None = None
    warnings: tuple[str, ...] = ()

    def predict(self, t_s) -> np.ndarray:
        """The model's release or step response (with its drift) at ``t_s`` (s), in the record's unit."""
        t = np.asarray(t_s, dtype=float)
        y = second_order_response(t, self.kind, self.wn_rad_s, self.zeta, self.offset, self.amplitude, self.t0_s)
        return y + self.drift_per_s * (t - self.drift_reference_s)

    def transfer_function(self) -> control.TransferFunction:
        """``gain wn^2 / (s^2 + 2 zeta wn s + wn^2)`` for a step (unit DC gain for a release, as E(s) is printed)."""
        k = self.gain if self.kind == "step" else 1.0
        return control.tf([k * self.wn_rad_s**2], [1.0, 2 * self.zeta * self.wn_rad_s, self.wn_rad_s**2])

    def summary(self) -> dict:
        """Plain figures for ``--json`` and reports."""
        tf = self.transfer_function()
        out = {
            "kind": self.kind,
            "method": self.method,
            "filter": self.filter,
            "source": self.source,
            "channel": self.channel,
            "unit": self.unit,
            "wn_rad_s": self.wn_rad_s,
            "zeta": self.zeta,
            "gain": self.gain,
            "t0_s": self.t0_s,
            "corr2": self.corr2,
            "fit_percent": self.fit_percent,
            "tf_num": [float(c) for c in tf.num[0][0]],
            "tf_den": [float(c) for c in tf.den[0][0]],
        }
        if self.survey is not None:
            sv = self.survey
            out["instant"] = {
                "t0_s": self.t0_s,
                "found_from": sv.found_from,
                "start_estimate_s": sv.t0_s,
                "baseline_s": sv.baseline_s,
                "direction": {1: "up", -1: "down"}.get(sv.direction, "none"),
            }
            out["record"] = {
                "noise_std": sv.noise_std,
                "spikes": int(sv.spikes.size),
                "hum_hz": sv.hum.frequency_hz if sv.hum else None,
                "hum_amplitude": sv.hum.amplitude if sv.hum else None,
                "drift_per_s": self.drift_per_s,
            }
        if self.quality is not None:
            out["quality"] = self.quality.summary()
        out["warnings"] = list(self.warnings)
        if self.estimates:
            out["confidence_intervals"] = {k: [e.ci_low, e.ci_high] for k, e in self.estimates.items()}
        if self.features is not None:
            f = self.features
            out["features"] = {
                "percent_overshoot": f.percent_overshoot,
                "peak_time_s": f.peak_time_s,
                "rise_time_s": f.rise_time_s,
                "settling_time_s": f.settling_time_s,
                "wd_rad_s": f.wd_rad_s,
                "log_decrement": f.log_decrement,
                "zeta_from_overshoot": f.zeta_os,
                "zeta_from_log_decrement": f.zeta_log_decrement,
                "wn_from_settling_rad_s": f.wn_settling_rad_s,
                "wn_from_damped_rad_s": f.wn_damped_rad_s,
            }
        return out

    def __repr__(self) -> str:
        return summary(
            self,
            kind=self.kind,
            method=self.method,
            channel=self.channel,
            wn_rad_s=self.wn_rad_s,
            zeta=self.zeta,
            gain=(self.gain, self.unit),
            corr2=self.corr2,
            fit_percent=self.fit_percent,
            warnings=len(self.warnings),
        )


def identify(
    series: TimeSeries,
    kind: str,
    *,
    method: str = "lsq",
    smoothing: str = "butter",
    t0_s: float | None = None,
    input_step: float | None = None,
    wn_from: str = "settling",
    fit_delay: bool | None = None,
    allow_overdamped: bool = False,
    loss: str = "soft_l1",
    drift: bool = True,
    force: bool = False,
    **filter_options,
) -> Identification:
    """Identify a second-order model from a release or step record.

    Parameters
    ----------
    series : TimeSeries
        The record (:func:`~flexdigit.identify.timeseries.read_timeseries`, the twin, or arrays).
    kind : {"release", "step"}
        Free decay from an initial deflection (the digit, 3.1.2) or a step response (the servo, 3.2.4).
    method : {"lsq", "thesis", "arx"}
        Least-squares fit of the raw record; the thesis's %OS and settling-time formulas on the filtered one; or the
        dominant poles of a discrete ARX(2, 2) (AR(2) for a release) fitted to the record and its input, both
        through the same Butterworth pre-filter (``cutoff_hz``) and decimated.
    smoothing : {"butter", "svd", "fft", "none"}
        Filter used to read the features (thesis method, and the start values of ``lsq``).
    t0_s : float, optional
        Step/release instant (s, on the record's clock, inside it). Default: found (:func:`~flexdigit.identify.
        events.survey`): where the ``command`` column changes, else from the signal.
    input_step : float, optional
        Size of the input step (e.g. 51 commands, 3.2.4) when the record has no input column; gives ``gain``.
        Non-zero; when the record has a command column it must agree with it.
    wn_from : {"settling", "damped"}
        Thesis method: ``wn = 4 / (zeta Ts)`` as the text says, or ``wd / sqrt(1 - zeta^2)`` as table 3.2 did.
    fit_delay : bool, optional
        ``lsq``: also fit the instant, i.e. a dead time after ``t0_s`` (the servo board latches a command at its
        next 20 ms serial frame, 5.2). Default: always when the instant was found from the signal; from a command
        column or a given ``t0_s``, for a step when the record has samples before it, for a release when it was
        not given.
    allow_overdamped : bool
        The digit released from a deflection swings through its rest position (3.1.2), and that oscillation is what
        identifies it; a release record that never undershoots its final value (or that the fit finds overdamped,
        ``zeta >= 1``) is refused unless this is True, for ``lsq`` and ``arx`` (the thesis method can never use
        one). A step whose fit is overdamped is refused likewise: without an overshoot its wn and zeta are poorly
        told apart.
    loss : {"soft_l1", "huber", "linear"}
        ``lsq``: loss of the fit; the robust ones keep isolated spikes from biasing it.
    drift : bool
        ``lsq``: fit a linear baseline drift with the model.
    force : bool
        Give the answer even when the record cannot be identified with confidence; the problems are then in
        ``warnings`` instead of raised.
    **filter_options
        Passed to :func:`~flexdigit.identify.filters.apply_filter` (``cutoff_hz``, ``rank``, ``harmonics``...).

    Raises
    ------
    DataFileError
        If the record cannot give a model it can stand behind, naming what looks wrong (unless ``force``): no step
        or release found, two steps, a command that never changes, too short, saturated, growing, a poor or
        uncertain fit; a release test without undershoot, or an overdamped fit (unless ``allow_overdamped``);
        thesis method: no overshoot, settling not reached. A constant record is refused even with ``force``.
    ParameterError
        If ``t0_s`` is outside the record or ``input_step`` is zero, not finite, or contradicts the command column.
    """
    _check_choices(kind, method, smoothing, wn_from, loss)
    t0_s, input_step = _check_instant_and_step(series, t0_s, input_step)
    found, du = _survey_and_input_step(series, kind, t0_s, input_step)
    warnings = _check_problems(series, kind, found.problems, force)
    series, found = _from_the_hold_on(series, found, warnings)
    smooth, features, problem = _read_features(series, found, kind, smoothing, filter_options, t0_s)
    _refuse_release_without_undershoot(problem, kind, method, allow_overdamped, force, warnings)
    fitted = _fit_model(series, found, kind, method, smooth, features, problem, t0_s, wn_from, fit_delay, loss, drift,
                        filter_options)  # fmt: skip
    _refuse_overdamped(series.name, kind, method, fitted.zeta, allow_overdamped, force, warnings)
    return _identification(series, found, kind, method, smoothing, du, features, fitted, force, warnings)


def _check_choices(kind: str, method: str, smoothing: str, wn_from: str, loss: str) -> None:
    """Each string option of :func:`identify` is one of its choices."""
    check_choice(kind, "kind", KINDS, "identify")
    check_choice(method, "method", METHODS, "identify")
    check_choice(smoothing, "smoothing", FILTERS, "identify")
    check_choice(wn_from, "wn_from", ("settling", "damped"), "identify")
    check_choice(loss, "loss", LOSSES, "identify")


def _check_instant_and_step(
    series: TimeSeries, t0_s: float | None, input_step: float | None
) -> tuple[float | None, float | None]:
    """The given instant (inside the record) and input step (finite, non-zero), checked; None stays None."""
    if t0_s is not None:
        t0_s = _check_instant(t0_s, series.t_s)
    if input_step is not None:
        input_step = check_real(input_step, "input_step", "identify")
        if input_step == 0:
            raise ParameterError("The 'input_step' parameter of identify must not be 0 (the gain is output / input).")
    return t0_s, input_step


def _survey_and_input_step(
    series: TimeSeries, kind: str, t0_s: float | None, input_step: float | None
) -> tuple[Survey, float | None]:
    """The record surveyed, and the input step: the command column's (a given one must agree), else the given one."""
    found = survey(series, kind, t0_s=t0_s)
    du = found.input_step
    if du is not None and input_step is not None and not math.isclose(du, input_step, rel_tol=1e-9):
        raise ParameterError(
            f"The 'input_step' parameter of identify ({input_step:g}) contradicts the {series.input_name!r} column "
            f"of {series.source}, which steps by {du:g}; drop one of them."
        )
    if du is None and input_step is not None:
        du = input_step
    return found, du


def _from_the_hold_on(series: TimeSeries, found: Survey, warnings: list[str]) -> tuple[TimeSeries, Survey]:
    """A release recorded from rest: the record and survey cut to where the digit is held deflected (warned)."""
    if found.first_sample == 0:
        return series, found
    t, i0 = series.t_s, found.first_sample
    warnings.append(
        f"the record before {float(t[i0]):.4g} s, where the digit is not yet held deflected, is left out of the fit"
    )
    series = TimeSeries(t[i0:], series.y[i0:], series.channel, series.unit, series.source, None, "",
                        series.time_unit)  # fmt: skip
    found = dataclasses.replace(
        found,
        cleaned=found.cleaned[i0:],
        smooth=found.smooth[i0:],
        spikes=found.spikes[found.spikes >= i0] - i0,
        first_sample=0,
    )
    return series, found


def _start_instant(series: TimeSeries, found: Survey) -> float:
    """The instant found, else the record's first sample: where a fit starts."""
    return found.t0_s if found.t0_s is not None else float(series.t_s[0])


def _read_features(
    series: TimeSeries, found: Survey, kind: str, smoothing: str, filter_options: dict, t0_s: float | None
) -> tuple[np.ndarray, ResponseFeatures | None, DataFileError | None]:
    """The filtered record and its response features, or the reason they cannot be read (lsq and arx go on)."""
    t = series.t_s
    t0_features = _start_instant(series, found) if (kind == "step" or t0_s is not None) else None
    smooth = apply_filter(t, found.cleaned, smoothing, **_feature_filter_options(smoothing, filter_options, found, t))
    try:
        features, problem = analyze_response(t, smooth, kind, t0_s=t0_features, source=series.name), None
    except DataFileError as exc:  # lsq and arx fit an overdamped step; the thesis method needs features
        features, problem = None, exc
    return smooth, features, problem


def _refuse_release_without_undershoot(
    problem: DataFileError | None, kind: str, method: str, allow_overdamped: bool, force: bool, warnings: list[str]
) -> None:
    """A release that never undershoots is refused (always by the thesis method), or warned with ``force``."""
    if kind == "release" and isinstance(problem, NoOscillationError) and not allow_overdamped:
        if not force or method == "thesis":
            raise DataFileError(_not_oscillating(problem.finding)) from None
        warnings.append(_not_oscillating(problem.finding))


@dataclass(frozen=True)
class _Fitted:
    """The model one method gives: its parameters, its baseline drift and (lsq) the estimates' uncertainties."""

    wn: float
    zeta: float
    offset: float
    amplitude: float
    t0: float
    drift_per_s: float
    drift_ref: float
    estimates: dict[str, Estimate] | None


def _fit_model(
    series: TimeSeries,
    found: Survey,
    kind: str,
    method: str,
    smooth: np.ndarray,
    features: ResponseFeatures | None,
    problem: DataFileError | None,
    t0_s: float | None,
    wn_from: str,
    fit_delay: bool | None,
    loss: str,
    drift: bool,
    filter_options: dict,
) -> _Fitted:
    """The second-order model by the method asked for: the thesis's formulas, the ARX poles, or least squares."""
    t, y, t0_start = series.t_s, found.cleaned, _start_instant(series, found)
    if method == "thesis":
        if problem is not None:
            raise problem
        return _thesis_model(series.name, kind, features, wn_from, t0_start)
    if method == "arx":
        t0 = t0_start if kind == "step" or t0_s is not None else (features.t0_s if features else t0_start)
        wn, zeta = _arx_mode(t, y, kind, t0, filter_options.get("cutoff_hz"))
        offset, amplitude = _offset_amplitude(t, y, kind, wn, zeta, t0)
        return _Fitted(wn, zeta, offset, amplitude, t0, 0.0, t0_start, None)
    if found.found_from == "signal":
        fit_t0 = True
    elif fit_delay is None:
        fit_t0 = t0_s is None if kind == "release" else bool(t0_start > t[0] + 2 * series.dt_s)
    else:
        fit_t0 = bool(fit_delay)
    model = SecondOrderFit(
        kind=kind,
        fit_t0=fit_t0,
        t0_s=t0_start,
        loss=loss,
        f_scale=2.0 * found.noise_std if found.noise_std > 0 else None,
        drift=drift,
    ).fit(t, y, source=series.name, smoothed=smooth)
    return _Fitted(model.wn_, model.zeta_, model.offset_, model.amplitude_, model.t0_, model.drift_per_s_,
                   model.drift_reference_s_, model.estimates_)  # fmt: skip


def _thesis_model(name: str, kind: str, f: ResponseFeatures, wn_from: str, t0_start: float) -> _Fitted:
    """The thesis method: zeta from the overshoot, wn from the settling time (or the damped period), 3.1.2."""
    wn = f.wn_settling_rad_s if wn_from == "settling" else f.wn_damped_rad_s
    if not math.isfinite(wn):
        raise DataFileError(
            f"{name}: the {kind} response does not settle inside the 2 % band before the record ends, "
            "so the thesis's wn = 4/(zeta Ts) is undefined; record longer, filter harder, or use the lsq method"
        )
    if kind == "step":
        offset, amplitude = f.initial_value, f.final_value - f.initial_value
    else:
        offset, amplitude = f.final_value, f.initial_value - f.final_value
    return _Fitted(wn, f.zeta_os, offset, amplitude, f.t0_s, 0.0, t0_start, None)


def _refuse_overdamped(
    name: str, kind: str, method: str, zeta: float, allow_overdamped: bool, force: bool, warnings: list[str]
) -> None:
    """An overdamped fit is refused unless allowed, or warned with ``force``."""
    if zeta >= 1.0 and not allow_overdamped:
        finding = f"{name}: the {method} fit of this {kind} test is overdamped (zeta = {float(zeta):.4g} >= 1)"
        message = _not_oscillating(finding) if kind == "release" else _overdamped_step(finding)
        if not force:
            raise DataFileError(message)
        warnings.append(message)


def _identification(
    series: TimeSeries,
    found: Survey,
    kind: str,
    method: str,
    smoothing: str,
    du: float | None,
    features: ResponseFeatures | None,
    m: _Fitted,
    force: bool,
    warnings: list[str],
) -> Identification:
    """The model's quality assessed against the record, and the result put together."""
    t, y = series.t_s, found.cleaned
    prediction = second_order_response(t, kind, m.wn, m.zeta, m.offset, m.amplitude, m.t0) + m.drift_per_s * (
        t - m.drift_ref
    )
    quality = assess(
        t,
        y,
        prediction,
        kind=kind,
        wn_rad_s=float(m.wn),
        zeta=float(m.zeta),
        amplitude=float(m.amplitude),
        t0_s=float(m.t0),
        estimates=m.estimates,
        raw=series.y,
        noise_std=found.noise_std,
        unit=series.unit,
        method=method,
    )
    warnings += _check_problems(series, kind, quality.problems, force)
    gain = m.amplitude / du if (kind == "step" and du) else m.amplitude
    return Identification(
        kind=kind,
        method=method,
        filter=smoothing,
        source=series.source,
        channel=series.channel,
        unit=series.unit,
        wn_rad_s=float(m.wn),
        zeta=float(m.zeta),
        gain=float(gain),
        offset=float(m.offset),
        amplitude=float(m.amplitude),
        t0_s=float(m.t0),
        estimates=m.estimates,
        features=features,
        corr2=quality.corr2,
        fit_percent=quality.fit_percent,
        drift_per_s=float(m.drift_per_s),
        drift_reference_s=float(m.drift_ref),
        survey=found,
        quality=quality,
        warnings=tuple(warnings) + quality.warnings,
    )


def _feature_filter_options(filter: str, options: dict, found: Survey, t: np.ndarray) -> dict:
    """The filter options for reading features: a Butterworth cut-off from the response found, unless given.

    :func:`~flexdigit.identify.filters.default_cutoff_hz` (5 x the spectral peak, at least 20/duration) unless the
    peak is pulled far below the response, to the record's lowest bins, by a drifting baseline or a long step
    record (0.7 Hz for 30 s: the response itself filtered away); then 5 x the dominant frequency estimated from
    the delay time found (instant to half-way): a quarter period for a release (5/(4 delay)), about 1.1/wn for a
    step (5 wn/2pi = 0.875/delay).
    """
    if filter != "butter" or options.get("cutoff_hz") or not (found.delay_s > 0):
        return options
    fs = (t.size - 1) / (t[-1] - t[0])
    per_delay = 1.25 if found.kind == "release" else 0.875
    from_delay = min(0.4 * fs, max(per_delay / found.delay_s, 20.0 / (t[-1] - t[0])))
    from_spectrum = default_cutoff_hz(t, found.cleaned)
    return {**options, "cutoff_hz": from_spectrum if from_spectrum >= 0.5 * from_delay else from_delay}


def _check_instant(t0_s, t: np.ndarray) -> float:
    """``t0_s`` as a float inside the record's time span, or a one-line error naming both."""
    value = check_real(t0_s, "t0_s", "identify")
    if not (t[0] <= value < t[-1]):
        raise ParameterError(
            f"The 't0_s' parameter of identify (--t0) must be inside the record, {float(t[0]):g} .. "
            f"{float(t[-1]):g} s. Got {value:g} instead."
        )
    return value


def _check_problems(series: TimeSeries, kind: str, problems: tuple[Problem, ...], force: bool) -> list[str]:
    """Refuse a record with problems, naming them all in one line; with ``force`` return them as warnings."""
    if not problems:
        return []
    if force:
        return [p.message for p in problems]
    what = "; ".join(p.message for p in problems)
    raise DataFileError(
        f"{series.name}: cannot identify this {kind} test with confidence: {what}; pass --force (force=True) to "
        "get the fit anyway"
    )


def _not_oscillating(finding: str) -> str:
    """The one-line refusal of a release record that does not oscillate: what was found, expected, and the way out."""
    return (
        f"{finding}: expected an oscillating decay (the digit released from a deflection swings through its rest "
        "position, 3.1.2), from which zeta and wn are identified; to fit an overdamped decay anyway, pass "
        "--allow-overdamped (allow_overdamped=True) with the lsq or arx method"
    )


def _overdamped_step(finding: str) -> str:
    """The one-line refusal of an overdamped step: what was found, why it is not trusted, and the way out."""
    return (
        f"{finding}: without an overshoot the record shows mainly the slower of two real poles, so wn and zeta are "
        "poorly told apart (the servo of 3.2.4 overshoots, zeta 0.56); to fit it anyway, pass --allow-overdamped "
        "(allow_overdamped=True)"
    )


def _arx_mode(t, y, kind: str, t0: float, cutoff_hz: float | None) -> tuple[float, float]:
    """``(wn, zeta)`` of the dominant pole pair of an ARX(2, 2) (step) or AR(2) (release) model.

    Equation-error least squares is biased by noise, so input and output both go through the same zero-phase
    Butterworth pre-filter (which leaves the input-output relation unchanged) and are decimated to about 10
    samples per cut-off period (50 per period of the dominant oscillation by default). A release record is used
    from two cut-off periods after the release, where the filter no longer mixes in the hold before it.
    """
    fs = (t.size - 1) / (t[-1] - t[0])
    cutoff = cutoff_hz or default_cutoff_hz(t, y)
    yf = butter_filter(y, fs, cutoff)
    step = max(1, int(fs / (10 * cutoff)))
    if kind == "release":
        keep = t >= t0 + 2.0 / cutoff
        model = fit_arx(yf[keep][::step], dt_s=step / fs, na=2)
    else:
        u = butter_filter((t >= t0).astype(float), fs, cutoff)
        model = fit_arx(yf[::step], u[::step], dt_s=step / fs, na=2, nb=2, nk=1)
    return model.dominant_mode()


def _offset_amplitude(t, y, kind: str, wn: float, zeta: float, t0: float) -> tuple[float, float]:
    """Offset and amplitude of the model response that best fit the record (linear least squares)."""
    shape = second_order_response(t, kind, wn, zeta, 0.0, 1.0, t0)
    (offset, amplitude), *_ = np.linalg.lstsq(np.column_stack([np.ones_like(t), shape]), y, rcond=None)
    return float(offset), float(amplitude)


def average_runs(runs: list[TimeSeries]) -> TimeSeries:
    """The sample-by-sample mean of repeated runs on the same time grid (figure 3.11's "average" curve)."""
    if not runs:
        raise DataFileError("average_runs needs at least one run")
    n = min(r.n_samples for r in runs)
    t = runs[0].t_s[:n]
    for r in runs[1:]:
        if not np.allclose(r.t_s[:n], t, rtol=0, atol=1e-9 + 1e-6 * runs[0].dt_s):
            raise DataFileError(f"{r.name}: runs to average must share their sample times")
    y = np.mean([r.y[:n] for r in runs], axis=0)
    u = runs[0].u[:n] if runs[0].u is not None else None
    first = runs[0]
    source = f"mean of {len(runs)} runs"
    return TimeSeries(t, y, first.channel, first.unit, source, u, first.input_name, first.time_unit)

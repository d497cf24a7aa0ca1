"""Model fitting: second-order least squares with confidence intervals, ARX, and the linear fits of 3.4.

The thesis reads two numbers off a response (%OS and Ts) and discards the rest of the record. Fitting the whole
record is less sensitive to noise and has no envelope approximation:

- :class:`SecondOrderFit` fits ``wn, zeta`` (plus offset, amplitude and, optionally, the release/step instant)
  of a release or step response by nonlinear least squares (``scipy.optimize.least_squares``), with parameter
  confidence intervals from the Jacobian at the optimum, ``cov = s^2 (J^T J)^-1`` (valid for white residuals:
  fit the raw record, not a filtered one);
- :func:`fit_arx` fits a discrete-time ARX model of any order (linear least squares) and returns the dominant
  pole pair as ``wn, zeta``: the higher-order option, and a start for the nonlinear fit;
- :func:`fit_linear` is the straight-line fit of 3.4 (command vs deflection, E 3.16-3.18; command vs gauge
  voltage, E 3.20-3.22) with residuals and confidence intervals (``scipy.stats.linregress``).

Examples
--------
>>> import control
>>> t = np.linspace(0, 1.5, 751)
>>> y = 51 * control.step_response(control.tf([421.5], [1, 23.11, 421.5]), t).outputs
>>> y += np.random.default_rng(1).normal(0, 1.0, t.size)
>>> f = SecondOrderFit(kind="step").fit(t, y)
>>> round(f.wn_, 1), round(f.zeta_, 2)                 # 3.2.4: 20.53 rad/s, 0.5629
(20.5, 0.56)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np
from scipy import optimize, stats
from threadpoolctl import threadpool_limits

from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_choice, check_int, check_real
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.identify.filters import apply_filter
from flexdigit.identify.response import analyze_response, final_value_estimate, free_response, noise_std
from flexdigit.identify.scores import corr2, nrmse_fit
from flexdigit.models.conversion import LinearFit

__all__ = [
    "Estimate",
    "second_order_response",
    "LOSSES",
    "SecondOrderFit",
    "ARXModel",
    "fit_arx",
    "LinearRelation",
    "fit_linear",
]


@dataclass(frozen=True)
class Estimate:
    """A fitted parameter with its standard error and confidence interval (same unit as ``value``)."""

    value: float
    stderr: float
    ci_low: float
    ci_high: float

    @property
    def relative_halfwidth(self) -> float:
        """Half-width of the confidence interval relative to the value."""
        return 0.5 * (self.ci_high - self.ci_low) / abs(self.value) if self.value else math.inf


def second_order_response(t_s, kind: str, wn_rad_s: float, zeta: float, offset: float, amplitude: float, t0_s=0.0):
    """Release or step response of ``wn^2 / (s^2 + 2 zeta wn s + wn^2)`` (E 3.1.2, MT(s) of 3.2.4).

    Step: ``offset + amplitude (1 - x(t - t0))``, ``offset`` before ``t0``. Release: ``offset + amplitude
    x(t - t0)``, ``offset + amplitude`` before ``t0`` (the held deflection), where ``x`` is
    :func:`~flexdigit.identify.response.free_response`.

    Parameters
    ----------
    t_s : array_like
        Time (s).
    kind : {"step", "release"}
    wn_rad_s, zeta : float
        Natural frequency (rad/s) and damping ratio.
    offset : float
        Step: initial value. Release: final value (signal units).
    amplitude : float
        Step: step size of the output. Release: initial deflection from the final value (signal units).
    t0_s : float
        Step or release instant (s).
    """
    t = np.asarray(t_s, dtype=float)
    tau = np.maximum(t - t0_s, 0.0)
    x = free_response(tau, wn_rad_s, zeta)
    if kind == "step":
        return offset + amplitude * (1.0 - x)
    return offset + amplitude * x


#: Losses of the second-order fit (``scipy.optimize.least_squares``): plain least squares, or robust to outliers.
LOSSES = ("linear", "soft_l1", "huber")


def _covariance(loss: str, r: np.ndarray, jac: np.ndarray, f_scale: float, dof: int) -> tuple[np.ndarray, float]:
    """The parameters' covariance and the residuals' standard deviation at a least-squares solution: ``s^2 (J'J)^-1``
    for the linear loss, the sandwich ``A^-1 B A^-1`` of the robust loss (with the residuals' MAD as their spread)."""
    n = r.size
    if loss == "linear":
        s2 = float(np.sum(r**2) / dof)
        return np.linalg.pinv(jac.T @ jac) * s2, math.sqrt(s2)
    w, curvature = _loss_derivatives(loss, (r / f_scale) ** 2)
    a_inv = np.linalg.pinv(jac.T @ (jac * curvature[:, None]))
    b = (jac * (w * r)[:, None]).T @ (jac * (w * r)[:, None])
    return a_inv @ b @ a_inv * (n / dof), 1.4826 * float(np.median(np.abs(r - np.median(r))))


class SecondOrderFit:
    """Least-squares second-order model of a release or step test (3.1.2, 3.2.4), scikit-learn style.

    Parameters
    ----------
    kind : {"step", "release"}
        The experiment: step response (servo, 3.2.4) or free decay from an initial deflection (digit, 3.1.2).
    fit_t0 : bool, optional
        Also fit the step/release instant (a pure delay for a step). Default: yes for a release (the instant of
        release is not recorded), no for a step (it starts at ``t0_s``, default the first sample).
    t0_s : float, optional
        The step/release instant when it is not fitted, or the start value when it is.
    confidence : float
        Level of the confidence intervals, in (0, 1).
    max_zeta : float
        Upper bound on the damping ratio (the model continues smoothly into overdamping).
    loss : {"linear", "soft_l1", "huber"}
        ``linear`` is least squares; ``soft_l1`` and ``huber`` (``scipy.optimize.least_squares``) count a residual
        beyond ``f_scale`` linearly instead of quadratically, so isolated spikes do not bias the fit.
    f_scale : float, optional
        Residual size (signal units) where a robust loss turns linear. Default: twice the noise standard deviation
        estimated from the record's second differences (:func:`~flexdigit.identify.response.noise_std`).
    drift : bool
        Also fit a linear drift of the baseline, ``drift_per_s`` (signal units per second).

    Attributes
    ----------
    wn_, zeta_ : float
        Natural frequency (rad/s) and damping ratio.
    offset_, amplitude_, t0_ : float
        See :func:`second_order_response`; with a drift, ``offset_`` is the level at the start value of ``t0``.
    drift_per_s_ : float
        Baseline drift (signal units per second; 0 unless ``drift``).
    estimates_ : dict of str to Estimate
        ``wn_rad_s``, ``zeta``, ``offset``, ``amplitude`` (and ``t0_s``, ``drift_per_s``) with standard errors and
        intervals.
    covariance_ : ndarray
        Parameter covariance: ``s^2 (J^T J)^-1`` for least squares; for a robust loss the sandwich
        ``A^-1 B A^-1 n / (n - k)`` with ``A = sum psi'(r_i) J_i J_i^T`` and ``B = sum psi(r_i)^2 J_i J_i^T``,
        ``psi`` the derivative of the loss in the residual (the M-estimator covariance, Huber 1981, 7.6).
    residual_std_ : float
        Standard deviation of the residuals (signal units; robust, from their median absolute deviation, for a
        robust loss).
    fit_percent_, corr2_ : float
        NRMSE fit (%) and MATLAB ``corr2`` of the fitted response against the data.
    result_ : scipy.optimize.OptimizeResult
    """

    def __init__(
        self,
        kind: str = "step",
        *,
        fit_t0: bool | None = None,
        t0_s: float | None = None,
        confidence: float = 0.95,
        max_zeta: float = 5.0,
        loss: str = "linear",
        f_scale: float | None = None,
        drift: bool = False,
    ):
        self.kind = kind
        self.fit_t0 = fit_t0
        self.t0_s = t0_s
        self.confidence = confidence
        self.max_zeta = max_zeta
        self.loss = loss
        self.f_scale = f_scale
        self.drift = drift

    def __repr__(self) -> str:
        return (
            f"SecondOrderFit(kind={self.kind!r}, fit_t0={self.fit_t0!r}, t0_s={self.t0_s!r}, "
            f"confidence={self.confidence!r}, max_zeta={self.max_zeta!r}, loss={self.loss!r}, "
            f"f_scale={self.f_scale!r}, drift={self.drift!r})"
        )

    def fit(self, t_s, y, *, initial: dict | None = None, source: str = "response", smoothed=None) -> SecondOrderFit:
        """Fit the model to ``y(t_s)``; ``initial`` may give start values ``wn_rad_s, zeta, offset, amplitude,
        t0_s`` (default: from the features of a smoothed copy, ``smoothed`` or ``y`` through the default
        Butterworth filter, or, for a response that does not overshoot, from its rise time at critical damping)."""
        owner = type(self).__name__
        check_choice(self.kind, "kind", ("step", "release"), owner)
        check_choice(self.loss, "loss", LOSSES, owner)
        level = check_real(self.confidence, "confidence", owner, low=0, high=1, low_open=True, high_open=True)
        t = check_array(t_s, "t_s", owner, ndim=1, min_length=8, increasing=True, error=DataFileError)
        yv = check_array(y, "y", owner, ndim=1, shape=(t.size,), error=DataFileError)
        fit_t0 = (self.kind == "release") if self.fit_t0 is None else bool(self.fit_t0)
        start = _initial_guess(t, yv, self.kind, self.t0_s, source, smoothed)
        start.update(initial or {})
        names = ["wn_rad_s", "zeta", "offset", "amplitude"] + (["t0_s"] if fit_t0 else [])
        names += ["drift_per_s"] if self.drift else []
        t0_fixed = float(start["t0_s"])
        start.setdefault("drift_per_s", 0.0)
        p0 = np.array([float(start[k]) for k in names])
        duration = t[-1] - t[0]
        span = float(np.ptp(yv)) or 1.0
        lower = [1e-6, 1e-6, -np.inf, -np.inf] + ([t[0] - 0.25 * duration] if fit_t0 else [])
        upper = [np.inf, self.max_zeta, np.inf, np.inf] + ([t[-1]] if fit_t0 else [])
        lower += [-np.inf] if self.drift else []
        upper += [np.inf] if self.drift else []
        p0 = np.clip(p0, np.array(lower) + 1e-9, np.array(upper) - 1e-9)
        model = _Model(t, self.kind, t0_fixed, fit_t0, self.drift)

        def residuals(p):
            return model(p) - yv

        if self.f_scale is None:
            f_scale = 2.0 * max(noise_std(yv), 1e-12 * span)
        else:
            f_scale = check_real(self.f_scale, "f_scale", owner, low=0, low_open=True)
        scale = np.array([p0[0], 0.1, span, span] + ([duration / 100] if fit_t0 else []))
        if self.drift:
            scale = np.append(scale, span / duration)
        solve = dict(bounds=(lower, upper), x_scale=scale, method="trf", loss=self.loss)
        # a tall, thin problem (thousands of samples, <= 7 parameters): BLAS threads only contend on a busy machine
        # (the SVD of each step took 70 ms instead of 5 on 2 shared cores)
        with threadpool_limits(1):
            block = _block_size(t, p0[0])
            if block > 1:  # converge on block medians first, then finish on every sample (a few steps)
                m = t.size // block
                tb = t[: m * block].reshape(m, block).mean(axis=1)
                yb = np.median(yv[: m * block].reshape(m, block), axis=1)
                coarse = _Model(tb, self.kind, t0_fixed, fit_t0, self.drift)
                first = optimize.least_squares(
                    lambda p: coarse(p) - yb, p0, jac=coarse.jacobian, f_scale=f_scale, **solve
                )
                p0 = np.clip(first.x, np.array(lower) + 1e-12, np.array(upper) - 1e-12)
            result = optimize.least_squares(residuals, p0, jac=model.jacobian, f_scale=f_scale, **solve)
            n, k = t.size, p0.size
            dof = max(n - k, 1)
            cov, self.residual_std_ = _covariance(self.loss, result.fun, model.jacobian(result.x), f_scale, dof)
        q = stats.t.ppf(0.5 + level / 2, dof)
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
        self.estimates_ = {
            name: Estimate(float(v), float(e), float(v - q * e), float(v + q * e))
            for name, v, e in zip(names, result.x, se, strict=True)
        }
        self.wn_, self.zeta_, self.offset_, self.amplitude_ = (float(v) for v in result.x[:4])
        self.t0_ = float(result.x[4]) if fit_t0 else t0_fixed
        self.drift_per_s_ = float(result.x[-1]) if self.drift else 0.0
        self.drift_reference_s_ = t0_fixed
        self.f_scale_ = f_scale
        self.covariance_ = cov
        self.result_ = result
        fitted = self.predict(t)
        self.fit_percent_ = nrmse_fit(yv, fitted)
        self.corr2_ = corr2(yv, fitted)
        return self

    def predict(self, t_s) -> np.ndarray:
        """The fitted response (with its drift) at ``t_s`` (s)."""
        if not hasattr(self, "wn_"):
            raise ParameterError("This SecondOrderFit is not fitted yet: call fit(t_s, y) first.")
        t = np.asarray(t_s, dtype=float)
        y = second_order_response(t, self.kind, self.wn_, self.zeta_, self.offset_, self.amplitude_, self.t0_)
        return y + self.drift_per_s_ * (t - self.drift_reference_s_)

    def transfer_function(self, gain: float = 1.0) -> control.TransferFunction:
        """``gain wn^2 / (s^2 + 2 zeta wn s + wn^2)`` with the fitted ``wn`` and ``zeta``."""
        if not hasattr(self, "wn_"):
            raise ParameterError("This SecondOrderFit is not fitted yet: call fit(t_s, y) first.")
        return control.tf([gain * self.wn_**2], [1.0, 2 * self.zeta_ * self.wn_, self.wn_**2])


#: Records longer than this are first fitted on block medians (see :func:`_block_size`).
_MAX_DIRECT_SAMPLES = 4000


def _block_size(t: np.ndarray, wn_rad_s: float) -> int:
    """Samples per block for the coarse first fit of a long record: at most 1/60 of a natural period each."""
    if t.size <= _MAX_DIRECT_SAMPLES or not wn_rad_s > 0:
        return 1
    dt = (t[-1] - t[0]) / (t.size - 1)
    limit = int(2 * math.pi / wn_rad_s / 60 / dt)
    return max(1, min(math.ceil(t.size / _MAX_DIRECT_SAMPLES), limit))


def _loss_derivatives(loss: str, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``psi(r) / r = rho'(z)`` and ``psi'(r) = rho'(z) + 2 z rho''(z)`` of scipy's robust losses, ``z = (r/f)^2``.

    The first weighs each residual in the score, the second in the curvature of the cost (as scipy scales its
    Jacobian for a robust loss); both enter the sandwich covariance.
    """
    if loss == "soft_l1":
        w = 1.0 / np.sqrt(1.0 + z)
        return w, w**3
    if loss == "huber":
        inside = z <= 1.0
        return np.where(inside, 1.0, 1.0 / np.sqrt(np.maximum(z, 1.0))), inside.astype(float)
    return np.ones_like(z), np.ones_like(z)


class _Model:
    """The fitted response ``offset + drift (t - t_ref) + amplitude g(t - t0)`` and its Jacobian.

    ``g`` is ``1 - x`` (step) or ``x`` (release), ``x`` the free response
    ``exp(-a tau) (cos(w tau) + a sin(w tau) / w)``, ``a = zeta wn``, ``w = wn sqrt(1 - zeta^2)``. The Jacobian is
    analytic for an underdamped model (one pass of exp/sin/cos instead of one per parameter, which keeps a 30 s
    record at 2 kHz well under a second) and by forward differences near and beyond critical damping.
    """

    def __init__(self, t: np.ndarray, kind: str, t0_fixed: float, fit_t0: bool, drift: bool):
        self.t, self.kind, self.t0_fixed, self.fit_t0, self.drift = t, kind, t0_fixed, fit_t0, drift
        self.sign = -1.0 if kind == "step" else 1.0

    def _t0(self, p) -> float:
        return float(p[4]) if self.fit_t0 else self.t0_fixed

    def __call__(self, p) -> np.ndarray:
        y = second_order_response(self.t, self.kind, p[0], p[1], p[2], p[3], self._t0(p))
        if self.drift:
            y = y + p[-1] * (self.t - self.t0_fixed)
        return y

    def jacobian(self, p) -> np.ndarray:
        wn, zeta, amplitude = float(p[0]), float(p[1]), float(p[3])
        if zeta >= 0.95:
            return self._numeric_jacobian(p)
        t0 = self._t0(p)
        after = self.t > t0
        tau = self.t[after] - t0
        a, root = zeta * wn, math.sqrt(1.0 - zeta * zeta)
        w = wn * root
        e = np.exp(-a * tau)
        sn, cs = np.sin(w * tau), np.cos(w * tau)
        x = e * (cs + (a / w) * sn)
        dx_da = -tau * x + e * sn / w
        dx_dw = e * (-tau * sn + (a / w) * tau * cs - (a / w**2) * sn)
        jac = np.zeros((self.t.size, len(p)))
        k = self.sign * amplitude
        jac[after, 0] = k * (dx_da * zeta + dx_dw * root)
        jac[after, 1] = k * (dx_da * wn - dx_dw * wn * zeta / root)
        jac[:, 2] = 1.0
        g = np.full(self.t.size, 0.0 if self.kind == "step" else 1.0)
        g[after] = 1.0 - x if self.kind == "step" else x
        jac[:, 3] = g
        if self.fit_t0:
            jac[after, 4] = k * (wn * wn / w) * e * sn  # d/dt0 of x(t - t0) = +wn^2/w e^(-a tau) sin(w tau)
        if self.drift:
            jac[:, -1] = self.t - self.t0_fixed
        return jac

    def _numeric_jacobian(self, p) -> np.ndarray:
        p = np.asarray(p, dtype=float)
        base = self(p)
        jac = np.empty((self.t.size, p.size))
        for j in range(p.size):
            h = 1e-7 * max(abs(p[j]), 1e-3)
            q = p.copy()
            q[j] += h
            jac[:, j] = (self(q) - base) / h
        return jac


def _initial_guess(t: np.ndarray, y: np.ndarray, kind: str, t0_s: float | None, source: str, smooth=None) -> dict:
    """Start values: features of a smoothed copy when it over/undershoots, else critical damping and the rise time."""
    smooth = apply_filter(t, y, "butter") if smooth is None else np.asarray(smooth, dtype=float)
    guess = {}
    try:
        f = analyze_response(t, smooth, kind, t0_s=t0_s, source=source)
        zeta = f.zeta_log_decrement if math.isfinite(f.zeta_log_decrement) else f.zeta_os
        if kind == "step":
            zeta = f.zeta_os  # a step rarely has two clean extrema
        guess = {
            "wn_rad_s": f.wd_rad_s / math.sqrt(1 - min(zeta, 0.95) ** 2),
            "zeta": zeta,
            "t0_s": f.t0_s,
        }
        if kind == "step":
            guess.update(offset=f.initial_value, amplitude=f.final_value - f.initial_value)
        else:
            guess.update(offset=f.final_value, amplitude=f.initial_value - f.final_value)
    except DataFileError:
        t0 = t[0] if t0_s is None else float(t0_s)
        yf = final_value_estimate(smooth)
        i0 = int(np.searchsorted(t, t0))
        y0 = float(smooth[i0])
        s = (smooth[i0:] - y0) / ((yf - y0) or 1.0)
        rise = _first_time(t[i0:], s, 0.9) - _first_time(t[i0:], s, 0.1)
        wn = 3.36 / rise if math.isfinite(rise) and rise > 0 else 10.0 / (t[-1] - t0)
        guess = {"wn_rad_s": wn, "zeta": 1.0, "t0_s": t0}
        if kind == "step":
            guess.update(offset=y0, amplitude=yf - y0)
        else:
            guess.update(offset=yf, amplitude=y0 - yf)
    if not all(math.isfinite(v) for v in guess.values()):
        raise DataFileError(f"{source}: could not find start values for the fit (the response has no clear shape)")
    return guess


def _first_time(t: np.ndarray, s: np.ndarray, level: float) -> float:
    idx = np.nonzero(s >= level)[0]
    return float(t[idx[0]]) if idx.size else math.nan


# --- ARX ----------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ARXModel:
    """``A(q) y[k] = B(q) u[k - nk] + c + e[k]`` fitted by linear least squares.

    Attributes
    ----------
    a : ndarray
        ``[1, a1, ..., a_na]``.
    b : ndarray
        ``[b0, ..., b_{nb-1}]`` applied to ``u[k - nk], ..., u[k - nk - nb + 1]`` (empty without input).
    nk : int
        Input delay (samples).
    constant : float
        Equation offset ``c``.
    dt_s : float
        Sampling period (s).
    fit_percent : float
        One-step-ahead NRMSE fit (%) on the data.
    """

    a: np.ndarray
    b: np.ndarray
    nk: int
    constant: float
    dt_s: float
    fit_percent: float

    @property
    def poles(self) -> np.ndarray:
        """Discrete-time poles (roots of ``A``)."""
        return np.roots(self.a)

    def transfer_function(self) -> control.TransferFunction:
        """``B(z) z^-nk / A(z)`` as a discrete python-control transfer function (sampling time ``dt_s``)."""
        if self.b.size == 0:
            raise ParameterError("This ARX model has no input (a release test): it has no transfer function.")
        na, nb = self.a.size - 1, self.b.size
        order = max(na, nb + self.nk - 1)
        num = np.concatenate([np.zeros(self.nk), self.b, np.zeros(order - self.nk - nb + 1)])
        den = np.concatenate([self.a, np.zeros(order - na)])
        return control.tf(np.trim_zeros(num, "f") if num.any() else [0.0], den, self.dt_s)

    def dominant_mode(self) -> tuple[float, float]:
        """``(wn, zeta)`` of the slowest complex pole pair (or real pole) in continuous time, ``s = ln z / dt``."""
        s = np.log(self.poles.astype(complex)) / self.dt_s
        s = s[np.argsort(-s.real)]  # slowest first
        for p in s:
            if abs(p.imag) > 1e-9:
                wn = abs(p)
                return float(wn), float(-p.real / wn)
        p = s[0]
        return float(abs(p)), 1.0

    __repr__ = fields_summary


def fit_arx(y, u=None, *, dt_s: float, na: int = 2, nb: int = 1, nk: int = 1, constant: bool = True) -> ARXModel:
    """Fit an ARX model by linear least squares (``numpy.linalg.lstsq``).

    Parameters
    ----------
    y : array_like
        Output, uniformly sampled.
    u : array_like, optional
        Input (same length); without it, an AR model of the free response (a release test).
    dt_s : float
        Sampling period (s).
    na, nb, nk : int
        Orders of ``A`` and ``B`` and the input delay (samples).
    constant : bool
        Fit an equation offset (a record around a non-zero rest value).

    Notes
    -----
    Equation-error least squares is biased when the output is noisy (the regressors contain the noise):
    filter the record or sample it coarser first; the nonlinear :class:`SecondOrderFit` does not have this bias.

    Examples
    --------
    >>> dt = 0.01
    >>> y = np.exp(-0.9 * dt * np.arange(400)) * np.cos(13.1 * dt * np.arange(400))
    >>> wn, zeta = fit_arx(y, dt_s=dt, na=2).dominant_mode()
    >>> round(wn, 2), round(zeta, 4)     # exact poles -0.9 +- 13.1j: wn = 13.131, zeta = 0.0685
    (13.13, 0.0685)
    """
    yv = check_array(y, "y", "fit_arx", ndim=1, min_length=8, error=DataFileError)
    na = check_int(na, "na", "fit_arx", low=1, high=50)
    dt = check_real(dt_s, "dt_s", "fit_arx", low=0, low_open=True)
    cols = [-yv[na - i - 1 : yv.size - i - 1] for i in range(na)]
    start = na
    b = np.empty(0)
    if u is not None:
        uv = check_array(u, "u", "fit_arx", ndim=1, shape=(yv.size,), error=DataFileError)
        nb = check_int(nb, "nb", "fit_arx", low=1, high=50)
        nk = check_int(nk, "nk", "fit_arx", low=0, high=yv.size // 4)
        start = max(na, nb + nk - 1)
        cols = [-yv[start - i - 1 : yv.size - i - 1] for i in range(na)]
        cols += [uv[start - nk - j : uv.size - nk - j] for j in range(nb)]
    if constant:
        cols.append(np.ones(yv.size - start))
    phi = np.column_stack(cols)
    target = yv[start:]
    theta, *_ = np.linalg.lstsq(phi, target, rcond=None)
    a = np.concatenate([[1.0], theta[:na]])
    if u is not None:
        b = theta[na : na + nb]
    c = float(theta[-1]) if constant else 0.0
    fit = nrmse_fit(target, phi @ theta)
    return ARXModel(a=a, b=np.asarray(b, dtype=float), nk=int(nk), constant=c, dt_s=dt, fit_percent=fit)


# --- linear relations of 3.4 --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class LinearRelation:
    """``y = slope x + intercept`` fitted to data, with its uncertainty (3.4: E 3.16-3.18, E 3.20-3.22).

    Attributes
    ----------
    slope, intercept : Estimate
        Fitted coefficients with standard errors and confidence intervals.
    residuals : ndarray
        ``y - (slope x + intercept)`` at the data points.
    r_squared : float
        Coefficient of determination.
    rms : float
        RMS of the residuals (units of ``y``).
    """

    slope: Estimate
    intercept: Estimate
    residuals: np.ndarray
    r_squared: float
    rms: float

    def __call__(self, x):
        return self.slope.value * np.asarray(x, dtype=float) + self.intercept.value

    def as_model(self):
        """The fit as :class:`flexdigit.models.conversion.LinearFit` (what the K1/K3 formulas take)."""
        return LinearFit(self.slope.value, self.intercept.value, self.rms)

    __repr__ = fields_summary


def fit_linear(x, y, *, confidence: float = 0.95) -> LinearRelation:
    """Least-squares straight line with confidence intervals (``scipy.stats.linregress``).

    Examples
    --------
    >>> r = fit_linear([8, 9, 10, 11], [0.0, 0.9, 1.8, 2.7])
    >>> round(r.slope.value, 6), round(r.intercept.value, 6), round(r.rms, 9)
    (0.9, -7.2, 0.0)
    """
    xa = check_array(x, "x", "fit_linear", ndim=1, min_length=3)
    ya = check_array(y, "y", "fit_linear", ndim=1, shape=(xa.size,))
    level = check_real(confidence, "confidence", "fit_linear", low=0, high=1, low_open=True, high_open=True)
    if np.ptp(xa) == 0:
        raise ParameterError(f"The 'x' parameter of fit_linear must not be constant. Got {xa.tolist()!r} instead.")
    res = stats.linregress(xa, ya)
    q = stats.t.ppf(0.5 + level / 2, xa.size - 2)
    resid = ya - (res.slope * xa + res.intercept)
    b, se = float(res.slope), float(res.stderr)
    slope = Estimate(b, se, float(b - q * se), float(b + q * se))
    c, ise = float(res.intercept), float(res.intercept_stderr)
    intercept = Estimate(c, ise, float(c - q * ise), float(c + q * ise))
    rms = float(np.sqrt(np.mean(resid**2)))
    return LinearRelation(slope, intercept, resid, float(res.rvalue**2), rms)

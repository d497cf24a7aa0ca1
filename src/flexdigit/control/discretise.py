"""Discretisation of a continuous controller, and where each method puts its poles and zeros (thesis 5.1).

Four methods, each a map from the s-plane to the z-plane::

    tustin (trapezoidal, E 5.1)   s = (2/T)(z - 1)/(z + 1)     z = (1 + sT/2)/(1 - sT/2)
    forward Euler (5.1.2)         s = (z - 1)/T                z = 1 + sT
    backward Euler                s = (z - 1)/(T z)            z = 1/(1 - sT)
    zero-order hold               exact for a held input       poles z = exp(sT)

Tustin and backward Euler map the whole left half plane inside the unit circle, so a stable controller stays
stable at any period. Forward Euler maps it onto the half plane Re z < 1: a pole ``-sigma +- j omega`` lands inside
the unit circle only while ``T < 2 sigma / (sigma^2 + omega^2) = 2 zeta / wn`` (``2/a`` for a real pole ``-a``;
:func:`forward_euler_stability_limit_s`). For the thesis's 39 Hz controller that is 2/245 = 8.2 ms for its fast
pole, and its zeros, placed on the lightly damped beam mode (zeta 0.027, wn 10.16 rad/s), leave the circle above
2 zeta/wn = 5.3 ms; this is the explanation of figures 5.5-5.7.

Tustin, ZOH and backward Euler come from python-control's ``sample_system`` (SciPy ``cont2discrete``); forward
Euler is one line by hand, ``x+ = (I + TA) x + TB u`` (E 5.2-5.3 of the thesis), because SciPy's ``"euler"`` is the
same map but python-control refuses to prewarp or name it, and the thesis states it in exactly this form.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from numbers import Integral, Real

import control as ct
import numpy as np

from flexdigit._repr import summary
from flexdigit._validation import Callable as Callable_
from flexdigit._validation import Interval, NoValidation, Options, declare, validate_fields, validate_params
from flexdigit.control._lsim import step_output
from flexdigit.errors import DesignError

__all__ = [
    "METHODS",
    "discretise",
    "map_s_to_z",
    "forward_euler_stability_limit_s",
    "FirstOrderTustin",
    "StepHalving",
    "halve_step",
    "SampledLoop",
    "sampled_loop",
    "sample_period_study",
]

METHODS = ("tustin", "zoh", "forward_euler", "backward_euler")
_POSITIVE = Interval(Real, 0, None, closed="neither")


@validate_params(
    {"sys": [NoValidation()], "period_s": [_POSITIVE], "method": [Options(METHODS)], "prewarp_rad_s": [_POSITIVE, None]}
)
def discretise(sys, period_s: float, method: str = "tustin", *, prewarp_rad_s: float | None = None):
    """Discretise a continuous LTI system at sample period ``period_s``.

    Parameters
    ----------
    sys : control.TransferFunction or control.StateSpace
        Continuous-time system (the controller, or the plant for ``"zoh"``).
    period_s : float
        Sample period T, s.
    method : {"tustin", "zoh", "forward_euler", "backward_euler"}
    prewarp_rad_s : float, optional
        Tustin only: frequency (rad/s) at which the discrete frequency response matches the continuous one.

    Returns
    -------
    control.TransferFunction or control.StateSpace
        A new discrete system with ``dt = period_s``, of the same type as ``sys``.

    Examples
    --------
    >>> import control as ct
    >>> d = discretise(ct.tf([1], [1, 1]), 0.1, "forward_euler")
    >>> [round(float(p.real), 6) for p in d.poles()]     # z = 1 + sT = 1 - 0.1
    [0.9]
    """
    T = period_s
    if not ct.isctime(sys, strict=True):
        raise DesignError(f"The 'sys' parameter of discretise must be a continuous-time system. Got dt={sys.dt}.")
    if prewarp_rad_s is not None:
        if method != "tustin":
            raise DesignError(f"prewarp_rad_s applies to the 'tustin' method only, not {method!r}")
        w = prewarp_rad_s
        if w * T >= np.pi:
            raise DesignError(f"prewarp_rad_s = {w} rad/s is above the Nyquist frequency pi/T = {np.pi / T:.4g} rad/s")
    if method == "forward_euler":
        ss = ct.ss(sys)
        n = ss.nstates
        out = ct.ss(np.eye(n) + T * ss.A, T * ss.B, ss.C, ss.D, T)  # x+ = (I + TA) x + TB u   (5.1.2)
        return ct.tf(out) if isinstance(sys, ct.TransferFunction) else out
    if method == "backward_euler":
        return ct.sample_system(sys, T, method="backward_diff")
    if method == "tustin":
        return ct.sample_system(sys, T, method="tustin", prewarp_frequency=prewarp_rad_s)
    return ct.sample_system(sys, T, method="zoh")


@validate_params({"s": [NoValidation()], "period_s": [_POSITIVE], "method": [Options(METHODS)]})
def map_s_to_z(s, period_s: float, method: str) -> np.ndarray:
    """Where a method sends points of the s-plane (poles; also zeros for every method but ``"zoh"``).

    ZOH maps poles by ``exp(sT)``; its zeros have no closed form, so map only poles with ``"zoh"``.

    Examples
    --------
    >>> round(float(map_s_to_z(-245.04, 0.010, "forward_euler").real), 4)   # the 39 Hz design's fast pole, 10 ms
    -1.4504
    """
    T = period_s
    s = np.asarray(s, dtype=complex)
    if method == "forward_euler":
        return 1 + s * T
    if method == "backward_euler":
        return 1 / (1 - s * T)
    if method == "tustin":
        return (1 + s * T / 2) / (1 - s * T / 2)
    return np.exp(s * T)


def forward_euler_stability_limit_s(points) -> float:
    """Largest period for which forward Euler keeps every left-half-plane point inside the unit circle.

    ``|1 + sT| < 1`` for ``s = -sigma + j omega`` iff ``T < 2 sigma / |s|^2`` (``= 2 zeta / wn``; ``2/a`` for a real
    point ``-a``). Points on or right of the imaginary axis are never inside, and give 0.

    Examples
    --------
    >>> round(forward_euler_stability_limit_s([-245.04]) * 1000, 2)          # ms: 2/245
    8.16
    >>> round(forward_euler_stability_limit_s([-0.2715 + 10.1594j]) * 1000, 2)  # ms: 2 zeta/wn of the beam mode
    5.26
    """
    s = np.atleast_1d(np.asarray(points, dtype=complex))
    if s.size == 0:
        raise DesignError("forward_euler_stability_limit_s needs at least one point")
    sigma = -s.real
    if np.any(sigma <= 0):
        return 0.0
    return float(np.min(2 * sigma / np.abs(s) ** 2))


@declare
@dataclass(frozen=True)
class FirstOrderTustin:
    """The first-order lead/lag ``C(s) = (1 + A s)/(1 + B s)`` as the difference equation of appendix E.

    ``u(k) = [-(T - 2B) u(k-1) + (2A + T) e(k) + (T - 2A) e(k-1)] / (2B + T)``

    (appendix E prints a stray factor ``z`` on the ``u(k-1)`` and ``e(k-1)`` terms of its last two lines; dividing by
    ``z`` had already turned them into delays, so the factor is a typesetting slip and is dropped here.)

    Parameters
    ----------
    lead_s : float
        A, s.
    lag_s : float
        B, s (> 0).
    period_s : float
        T, s.

    Examples
    --------
    >>> f = FirstOrderTustin(0.5, 0.1, 0.01)
    >>> [round(c, 6) for c in (f.b0, f.b1, f.a1)]
    [4.809524, -4.714286, -0.904762]
    """

    lead_s: float
    lag_s: float
    period_s: float
    _state: list = field(default_factory=lambda: [0.0, 0.0], repr=False, compare=False)

    _parameter_constraints = {"lead_s": [Interval(Real)], "lag_s": [_POSITIVE], "period_s": [_POSITIVE]}

    def __post_init__(self) -> None:
        validate_fields(self)

    @property
    def b0(self) -> float:
        return (2 * self.lead_s + self.period_s) / (2 * self.lag_s + self.period_s)

    @property
    def b1(self) -> float:
        return (self.period_s - 2 * self.lead_s) / (2 * self.lag_s + self.period_s)

    @property
    def a1(self) -> float:
        """Coefficient of ``u(k-1)`` on the left: ``u(k) = -a1 u(k-1) + b0 e(k) + b1 e(k-1)``."""
        return (self.period_s - 2 * self.lag_s) / (2 * self.lag_s + self.period_s)

    def transfer_function(self) -> ct.TransferFunction:
        """``C(z) = (b0 z + b1)/(z + a1)`` with ``dt = T``."""
        return ct.tf([self.b0, self.b1], [1.0, self.a1], self.period_s)

    def reset(self) -> None:
        self._state[:] = [0.0, 0.0]

    def step(self, e: float) -> float:
        """One sample: ``u(k)`` from ``e(k)``, remembering ``u(k-1)`` and ``e(k-1)`` (appendix E)."""
        u_prev, e_prev = self._state
        u = -self.a1 * u_prev + self.b0 * e + self.b1 * e_prev
        self._state[:] = [u, e]
        return u

    def simulate(self, e: Sequence[float]) -> np.ndarray:
        """Run the difference equation over a sequence from rest."""
        self.reset()
        return np.array([self.step(float(v)) for v in e])


@dataclass(frozen=True)
class StepHalving:
    """Result of the step-halving procedure of 5.1.2: the chosen period and the error at each halving."""

    period_s: float
    history: tuple[tuple[float, float], ...]  # (alpha, relative difference between alpha and alpha/2)
    converged: bool


@validate_params(
    {
        "response": [Callable_()],
        "initial_period_s": [_POSITIVE],
        "tolerance": [_POSITIVE],
        "max_halvings": [Interval(Integral, 1, None)],
    }
)
def halve_step(
    response: Callable[[float], tuple[np.ndarray, np.ndarray]],
    initial_period_s: float,
    tolerance: float = 0.02,
    max_halvings: int = 8,
) -> StepHalving:
    """Choose a step size the way 5.1.2 does: compare the step response at ``alpha`` and ``alpha/2``, halve until
    they agree within ``tolerance`` (relative to the peak of the finer response), and keep that ``alpha``.

    Parameters
    ----------
    response : callable
        ``response(alpha) -> (t, y)``: the step response computed with step/sample period ``alpha``.
    initial_period_s : float
        First ``alpha``, s.
    tolerance : float
        Largest acceptable ``max|y_alpha - y_alpha/2| / max|y_alpha/2|``, compared on the ``alpha`` grid.
    max_halvings : int

    Returns
    -------
    StepHalving
        ``period_s`` is the first ``alpha`` that agrees with ``alpha/2`` (the last one tried if none does,
        with ``converged=False``). A response that is not finite (an unstable discretisation) never agrees.
    """
    alpha, tol, n = initial_period_s, tolerance, max_halvings
    history = []
    t_a, y_a = response(alpha)
    for _ in range(n):
        t_h, y_h = response(alpha / 2)
        y_h_on_a = np.interp(t_a, t_h, y_h)
        scale = np.max(np.abs(y_h)) if np.all(np.isfinite(y_h)) else np.inf
        if np.all(np.isfinite(y_a)) and np.isfinite(scale) and scale > 0:
            err = float(np.max(np.abs(y_a - y_h_on_a)) / scale)
        else:
            err = float("inf")
        history.append((alpha, err))
        if err <= tol:
            return StepHalving(alpha, tuple(history), True)
        alpha, t_a, y_a = alpha / 2, t_h, y_h
    return StepHalving(alpha, tuple(history), False)


# -- the sample-period study of figures 5.3-5.7 ------------------------------------------------------------------


@dataclass(frozen=True)
class SampledLoop:
    """A plant held by a zero-order hold, in a loop with a digitised controller, ``u = K (w - y)`` (figure 5.1).

    Attributes
    ----------
    method : str
        How the controller was digitised.
    period_s : float
    delay_samples : int
        Extra whole samples of transport delay between the controller and the hold.
    spectral_radius : float
        Largest closed-loop pole magnitude (stable iff < 1).
    t_s, y : ndarray
        Step response at the sample instants (output unit per unit step of ``w``).
    y_continuous : ndarray
        The continuous loop's step response at the same instants.
    error : float
        ``max |y - y_continuous| / max |y_continuous|`` (inf when unstable).
    controller_poles_z, controller_zeros_z, plant_poles_z : ndarray
        Where the digitised controller's poles and zeros and the held plant's poles lie (z-plane).
    """

    method: str
    period_s: float
    delay_samples: int
    spectral_radius: float
    t_s: np.ndarray
    y: np.ndarray
    y_continuous: np.ndarray
    error: float
    controller_poles_z: np.ndarray
    controller_zeros_z: np.ndarray
    plant_poles_z: np.ndarray

    @property
    def stable(self) -> bool:
        return self.spectral_radius < 1.0

    @property
    def cancellation_error(self) -> float:
        """Distance from each held-plant pole to the nearest controller zero, worst case (z-plane units).

        The 39 Hz design cancels the plant's poles with its zeros; this is how far the digitised zeros miss.
        """
        if self.controller_zeros_z.size == 0 or self.plant_poles_z.size == 0:
            return float("inf")
        d = np.abs(self.plant_poles_z[:, None] - self.controller_zeros_z[None, :])
        return float(np.max(np.min(d, axis=1)))

    def __repr__(self) -> str:
        return summary(
            self,
            method=self.method,
            period_s=self.period_s,
            delay_samples=self.delay_samples,
            spectral_radius=self.spectral_radius,
            error=self.error,
            samples=len(self.t_s),
        )


@validate_params(
    {
        "plant": [NoValidation()],
        "controller": [NoValidation()],
        "period_s": [_POSITIVE],
        "method": [Options(METHODS)],
        "delay_samples": [Interval(Integral, 0, None)],
        "t_final_s": [_POSITIVE],
    }
)
def sampled_loop(
    plant,
    controller,
    period_s: float,
    method: str = "tustin",
    *,
    delay_samples: int = 0,
    t_final_s: float = 3.0,
) -> SampledLoop:
    """Digitise ``controller`` with ``method``, hold ``plant`` (ZOH) and close the loop at ``period_s`` (5.1).

    The loop is built in state space (high-order transfer-function products lose the poles near z = 1 at
    sub-millisecond periods). ``delay_samples`` adds ``z^-d`` between controller and hold (the servo board's
    transport delay, 5.2).
    """
    T, d = period_s, delay_samples
    G, K = ct.ss(plant), ct.ss(controller)
    Gd = ct.sample_system(G, T, method="zoh")
    Kd = discretise(K, T, method)
    path = Kd if d == 0 else ct.series(Kd, ct.ss(ct.tf([1.0], [1.0] + [0.0] * d, T)))
    closed = ct.feedback(ct.series(path, Gd), 1)
    poles = closed.poles()
    radius = float(np.max(np.abs(poles))) if poles.size else 0.0
    t = np.arange(0.0, t_final_s + T / 2, T)
    with np.errstate(over="ignore", invalid="ignore"):
        y = step_output(closed, t)
    continuous = ct.feedback(ct.series(K, G), 1)
    t_fine = np.arange(0.0, t_final_s + 1e-4, 1e-4)
    yc_fine = step_output(continuous, t_fine)
    yc = np.interp(t, t_fine, yc_fine)
    if radius < 1 and np.all(np.isfinite(y)):
        error = float(np.max(np.abs(y - yc)) / np.max(np.abs(yc)))
    else:
        error = float("inf")
    return SampledLoop(
        method, T, d, radius, t, y, yc, error, Kd.poles(), Kd.zeros() if K.nstates else np.array([]), Gd.poles()
    )


def sample_period_study(plant, controller, periods_s, methods=("tustin", "forward_euler"), **kwargs):
    """:func:`sampled_loop` for every method and period (figures 5.3-5.7): ``{method: [SampledLoop, ...]}``."""
    return {m: [sampled_loop(plant, controller, T, m, **kwargs) for T in periods_s] for m in methods}

"""Closed-loop analysis of a SISO loop ``u = K (r - G u)`` (thesis 4.4-4.6) and its robustness.

The thesis's LFTs, all with the closed-loop state ``[x; x_k]`` and ``A_cl = [[A, B C_k], [-B_k C, A_k]]``:

* ``T_zw`` (4.4): reference ``w`` -> tracking error ``z = w - y``: the sensitivity ``S = 1/(1 + G K)``;
* ``T_yw`` (4.5): reference -> output, ``T = G K/(1 + G K)``;
* ``T_uw`` (4.5): reference -> command, ``K S`` (commands per output unit);
* ``T_pq`` (4.6): additive-uncertainty output -> input, ``-K S``: the loop survives every stable additive
  ``Delta`` with ``||Delta||_inf < 1/||K S||_inf`` (small gain).

Norms are only computed for stable loops: an unstable loop raises :class:`flexdigit.errors.UnstableError`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np

from flexdigit._repr import fields_summary, summary
from flexdigit._validation import check_array, check_real
from flexdigit.control._lsim import step_output
from flexdigit.control._threads import single_blas_thread
from flexdigit.control.generalized import as_statespace
from flexdigit.errors import UnstableError

__all__ = [
    "LoopMaps",
    "loop_maps",
    "is_stable",
    "hinf_norm",
    "StepFigures",
    "step_figures",
    "step_metrics",
    "additive_tolerance",
    "margins",
    "monte_carlo_stability",
    "closed_loop_poles_batch",
    "root_locus",
]


@dataclass(frozen=True)
class LoopMaps:
    """The four closed-loop maps of a SISO loop, as state-space systems (thesis 4.4-4.6)."""

    T_zw: ct.StateSpace
    T_yw: ct.StateSpace
    T_uw: ct.StateSpace
    T_pq: ct.StateSpace
    poles: np.ndarray

    @property
    def stable(self) -> bool:
        return bool(self.poles.size == 0 or np.max(self.poles.real) < 0)

    def __repr__(self) -> str:
        return summary(
            self,
            closed_loop_order=len(self.poles),
            stable=bool(np.all(np.real(self.poles) < 0)),
            slowest_pole_real=(float(np.max(np.real(self.poles))), "rad/s"),
        )


def loop_maps(plant, controller) -> LoopMaps:
    """Build ``T_zw``, ``T_yw``, ``T_uw``, ``T_pq`` from the state-space formulas of thesis 4.4-4.6.

    Parameters
    ----------
    plant : LTI system
        ``G`` (output unit per command), SISO.
    controller : LTI system
        ``K`` (commands per output unit), SISO, ``u = K (w - y)``.

    Examples
    --------
    >>> import control as ct
    >>> maps = loop_maps(ct.tf([1.0], [1.0, 1.0]), ct.tf([1.0], [1.0]))
    >>> round(float(ct.dcgain(maps.T_zw)), 6)    # S(0) = 1/(1 + 1)
    0.5
    """
    Acl, Bw, Cy, Dy, Ux, Uxk, Uw = _closed_loop(plant, controller)
    T_yw = ct.ss(Acl, Bw, Cy, Dy)
    T_zw = ct.ss(Acl, Bw, -Cy, np.eye(1) - Dy)  # 4.4: z = w - y
    T_uw = ct.ss(Acl, Bw, np.hstack([Ux, Uxk]), Uw)  # 4.5: u
    # 4.6: p enters the controller input with a minus sign (additive Delta between u and y), q = u
    Bp = -Bw
    T_pq = ct.ss(Acl, Bp, np.hstack([Ux, Uxk]), -Uw)
    return LoopMaps(T_zw, T_yw, T_uw, T_pq, np.linalg.eigvals(Acl) if Acl.size else np.array([]))


def _closed_loop(plant, controller):
    """The closed loop ``u = K (w - y)`` in state space: ``Acl, Bw, Cy, Dy`` (w to y) and the rows giving u."""
    G = as_statespace(plant, "plant")
    K = as_statespace(controller, "controller")
    return _closed_loop_matrices(G.A, G.B, G.C, G.D, K)


def _closed_loop_matrices(A, B, C, D, K):
    """:func:`_closed_loop` from the plant's matrices, each possibly a stack (leading axes: one plant each)."""
    Ak, Bk, Ck, Dk = K.A, K.B, K.C, K.D
    # with u = Ck xk + Dk e, e = w - C x - D u  =>  e = (w - C x - D Ck xk) / (1 + D Dk)
    r = 1.0 / (1.0 + D[..., :1, :1] * Dk[0, 0])
    Ex = -r * C  # e in terms of x
    Exk = -r * D @ Ck
    Ew = r
    Ux, Uxk, Uw = Dk @ Ex, Ck + Dk @ Exk, Dk @ Ew  # u
    Acl = _block([[A + B @ Ux, B @ Uxk], [Bk @ Ex, Ak + Bk @ Exk]])  # = [[A, B Ck], [-Bk C, Ak]] when D = Dk = 0
    Bw = _block([[B @ Uw], [Bk @ Ew]])
    Cy = _block([[C + D @ Ux, D @ Uxk]])
    Dy = D @ Uw
    return Acl, Bw, Cy, Dy, Ux, Uxk, Uw


def _block(rows) -> np.ndarray:
    """``np.block`` over the last two axes of matrices or stacks of them (broadcast over the leading axes)."""
    lead = np.broadcast_shapes(*(m.shape[:-2] for row in rows for m in row))
    return np.concatenate(
        [np.concatenate([np.broadcast_to(m, lead + m.shape[-2:]) for m in row], axis=-1) for row in rows], axis=-2
    )


def root_locus(sys, gains) -> np.ndarray:
    """Closed-loop poles of ``1 + k sys`` for every ``k`` of ``gains``: shape (len(gains), order), unsorted.

    The roots of ``den + k num`` for all gains at once, as the eigenvalues of a stack of companion matrices (one
    LAPACK call): python-control's ``root_locus_map`` takes ``np.roots`` gain by gain and sorts the branches,
    ~10x the time for the 4,000 gains of the report's loci (issue 15). ``np.roots`` builds the same companion
    matrix, so each row is its answer; only a polynomial with an exactly zero leading or trailing coefficient
    (whose order drops, or with roots at 0, which ``np.roots`` strips) goes through ``np.roots`` itself, padded
    with NaN to the order of ``den``. Each row's order is LAPACK's.
    """
    tf = ct.tf(sys)
    num = np.atleast_1d(np.asarray(tf.num[0][0], dtype=float))
    den = np.atleast_1d(np.asarray(tf.den[0][0], dtype=float))
    k = check_array(gains, "gains", "root_locus").ravel()  # finite: LAPACK refuses NaN and inf with a traceback
    num = np.concatenate([np.zeros(max(den.size - num.size, 0)), num])
    poly = den[None, :] + k[:, None] * num[None, :]
    n = poly.shape[1] - 1
    loci = np.full((k.size, n), np.nan, dtype=complex)
    if n == 0:
        return loci
    lead = poly[:, 0]
    whole = (lead != 0) & (poly[:, -1] != 0)  # np.roots trims nothing: its companion matrix is this one
    if np.any(whole):
        companion = np.zeros((int(np.sum(whole)), n, n))
        companion[:, 0, :] = -poly[whole, 1:] / lead[whole, None]
        companion[:, np.arange(1, n), np.arange(n - 1)] = 1.0
        loci[whole] = np.linalg.eigvals(companion)
    for i in np.flatnonzero(~whole):
        r = np.roots(np.trim_zeros(poly[i], "f"))
        loci[i, : r.size] = r
    return loci


def closed_loop_poles(plant, controller) -> np.ndarray:
    """The poles of the loop ``u = K (w - y)`` (those of :func:`loop_maps`, without building its four systems).

    Examples
    --------
    >>> import control as ct
    >>> closed_loop_poles(ct.tf([1.0], [1.0, 1.0]), ct.tf([1.0], [1.0])).tolist()     # 1/(s + 1) with K = 1
    [-2.0]
    """
    Acl = _closed_loop(plant, controller)[0]
    return np.linalg.eigvals(Acl) if Acl.size else np.array([])


def closed_loop_poles_batch(abcd, controller) -> np.ndarray:
    """:func:`closed_loop_poles` of many plants at once, from stacks of their state-space matrices.

    ``abcd`` is ``(A, B, C, D)`` of shapes ``(N, n, n)``, ``(N, n, 1)``, ``(N, 1, n)``, ``(N, 1, 1)`` (a plant
    family's :meth:`~flexdigit.control.mixsyn.PlantFamily.state_space`); returns ``(N, n + n_K)`` poles, one LAPACK
    call for the whole stack instead of a python-control system per plant (issue 15).
    """
    K = as_statespace(controller, "controller")
    A, B, C, D = (np.asarray(M, dtype=float) for M in abcd)
    Acl = _closed_loop_matrices(A, B, C, D, K)[0]
    return np.linalg.eigvals(Acl) if Acl.shape[-1] else np.empty(Acl.shape[:-1], dtype=complex)


def is_stable(sys) -> bool:
    """True if every pole of a continuous system is in the open left half plane."""
    A = np.asarray(ct.ss(sys).A)
    return bool(A.size == 0 or np.max(np.linalg.eigvals(A).real) < 0)


def hinf_norm(sys, name: str = "system") -> tuple[float, float]:
    """``(||sys||_inf, peak frequency in rad/s)`` of a stable system; :class:`UnstableError` otherwise.

    Examples
    --------
    >>> import control as ct
    >>> g, w = hinf_norm(ct.tf([1.0], [1.0, 0.2, 1.0]))
    >>> round(g, 3), round(w, 3)
    (5.025, 0.99)
    """
    sys = ct.ss(sys)
    if not is_stable(sys):
        poles = np.linalg.eigvals(sys.A)
        worst = poles[np.argmax(poles.real)]
        raise UnstableError(
            f"{name} is unstable (pole at {worst.real:.4g}{worst.imag:+.4g}j rad/s): its H-infinity norm is not "
            "defined."
        )
    if sys.nstates == 0:
        return float(np.linalg.norm(sys.D, 2)), 0.0
    with single_blas_thread():
        gpeak, fpeak = ct.linfnorm(sys)
    return float(gpeak), float(fpeak)


@dataclass(frozen=True)
class StepFigures:
    """The figures of one step response, in the response's own unit (``y``) and seconds.

    Attributes
    ----------
    rise_time_s : float
        From the first crossing of 10 % of the step to the first crossing of 90 % (inf if 90 % is never reached).
    settling_time_s : float
        Time after the step from which the response stays within ``band`` x ``|step|`` of the target to the end of
        the record (0 if it never leaves the band, inf if it is outside it at the end).
    settling_to_final_s : float
        The same about the measured final value instead of the target (MATLAB's ``stepinfo`` convention): when
        the response stopped moving, even where a steady-state error keeps it out of the target's band.
    overshoot_percent : float
        Largest excursion beyond the target in the step's direction, in percent of the step (0 if none).
    peak, peak_time_s : float
        The response's extreme in the step's direction and when it happened (s after the step).
    final : float
        Mean over the record's last ``tail_s`` (the steady-state value as measured).
    steady_state_error : float
        ``final - target`` (signed); NaN where the record shows no steady state (see ``confirm_s``).
    iae : float
        Integral of ``|target - y|`` from the step to the end of the record (unit x s).
    bounded : bool
        Every value finite and within 10 step sizes of the target.
    """

    rise_time_s: float
    settling_time_s: float
    settling_to_final_s: float
    overshoot_percent: float
    peak: float
    peak_time_s: float
    final: float
    steady_state_error: float
    iae: float
    bounded: bool

    __repr__ = fields_summary


def _settling_time(t: np.ndarray, error: np.ndarray, band: float) -> float:
    """Start of the last stretch with ``error <= band`` (interpolated): 0 if never out, inf if out at the end."""
    outside = np.nonzero(error > band)[0]
    if not outside.size:
        return 0.0
    if outside[-1] + 1 >= t.size:
        return math.inf
    i = int(outside[-1])
    e0, e1 = error[i], error[i + 1]
    return float(t[i] + (t[i + 1] - t[i]) * (e0 - band) / (e0 - e1))


def _first_crossing(t: np.ndarray, z: np.ndarray, level: float) -> float:
    """First time the normalised response ``z`` reaches ``level`` (linear interpolation); inf if never."""
    above = np.nonzero(z >= level)[0]
    if not above.size:
        return math.inf
    i = int(above[0])
    if i == 0:
        return float(t[0])
    z0, z1 = z[i - 1], z[i]
    return float(t[i - 1] + (t[i] - t[i - 1]) * (level - z0) / (z1 - z0))


def _after_step(t_s, y, step_time_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The samples from the step on, times counted from it; at least two."""
    t = np.asarray(t_s, dtype=float).reshape(-1)
    y = np.asarray(y, dtype=float).reshape(-1)
    if t.size != y.size:
        raise ValueError(f"step_figures: {t.size} times for {y.size} values")
    after = t >= step_time_s - 1e-9
    t, y = t[after] - step_time_s, y[after]
    if t.size < 2:
        raise ValueError("step_figures: fewer than two samples after the step")
    return t, y


def _settling_times(t, y, z, final, step, band, tail_length, confirm) -> tuple[float, float, bool]:
    """:func:`step_figures`'s settling time to the target and to the final value, and whether the record shows a
    steady state (``confirm_s`` > 0 asks the record to go on inside the band; see there)."""
    settling = _settling_time(t, np.abs(z - 1.0), band)
    settled = _settling_time(t, np.abs(y - final) / abs(step), band)
    steady = True
    if confirm > 0:
        if settling > t[-1] - confirm:
            settling = math.inf  # in the band only at the very end, if at all: not shown to have settled
        if settled > t[-1] - max(tail_length, confirm):
            settled, steady = math.inf, False  # still moving over the final window: no steady state to give
    return settling, settled, steady


def step_figures(
    t_s,
    y,
    *,
    target: float | None = None,
    initial: float = 0.0,
    step_time_s: float = 0.0,
    band: float = 0.02,
    rise_limits: tuple[float, float] = (0.1, 0.9),
    tail_s: float = 0.5,
    confirm_s: float = 0.0,
) -> StepFigures:
    """Rise time, settling time, overshoot, steady-state error and IAE of a sampled step response.

    One implementation for measured responses (the rig's step, :func:`flexdigit.rig.step_test.step_metrics`) and
    simulated ones (:func:`step_metrics` of a linear model). Crossing times are interpolated linearly between
    samples, so a 20 ms record gives settling times to a few ms rather than to the sample.

    Parameters
    ----------
    t_s, y : array_like
        Sample times (s, increasing) and the response.
    target : float, optional
        The value the response should settle at (the setpoint); default the measured final value.
    initial : float
        The value before the step (0: a step from rest).
    step_time_s : float
        When the step was applied; samples before it are ignored.
    band : float
        Settling band as a fraction of the step size ``|target - initial|`` (0.02: the 2 % settling time).
    rise_limits : (float, float)
        Fractions of the step between which the rise time is measured (10 % to 90 %).
    tail_s : float
        The last ``tail_s`` of the record give the final value.
    confirm_s : float
        How long the record must go on inside a band after entering it for the response to count as settled
        (0: the last sample is enough, as for an exact simulated response). A measured record needs more: a run
        that stops just after the response enters the band, or that ends while it still moves, does not show
        that it settled. With ``confirm_s`` > 0, a settling time is ``inf`` unless the response stayed in the
        band for the last ``confirm_s`` of the record, and the final value is only a steady state (else
        ``settling_to_final_s`` is ``inf`` and ``steady_state_error`` NaN) when the response stayed within ``band``
        of it over the whole final ``tail_s`` window (and at least the last ``confirm_s``).

    Examples
    --------
    First order, time constant 0.1 s: rise 0.1 ln 9 = 0.220 s, 2 % settling 0.1 ln 50 = 0.391 s, IAE = 0.1.

    >>> t = np.linspace(0, 3, 30001)
    >>> f = step_figures(t, 1 - np.exp(-t / 0.1), target=1.0)
    >>> round(f.rise_time_s, 3), round(f.settling_time_s, 3), f.overshoot_percent, round(f.iae, 4)
    (0.22, 0.391, 0.0, 0.1)
    """
    t, y = _after_step(t_s, y, step_time_s)
    tail_length = check_real(tail_s, "tail_s", "step_figures", low=0.0)
    confirm = check_real(confirm_s, "confirm_s", "step_figures", low=0.0)
    tail = y[t >= t[-1] - tail_length]
    final = float(np.mean(tail))
    goal = final if target is None else check_real(target, "target", "step_figures")
    step = goal - float(initial)
    finite = bool(np.all(np.isfinite(y)))
    iae = float(np.trapezoid(np.abs(goal - y), t)) if finite else math.nan
    if step == 0 or not finite:
        nan = math.nan
        return StepFigures(nan, nan, nan, nan, nan, nan, final, final - goal, iae, finite and step == 0)
    z = (y - float(initial)) / step  # 0 -> 1 whichever the step's direction
    bounded = bool(np.max(np.abs(z - 1.0)) < 10.0)
    rise = _first_crossing(t, z, rise_limits[1]) - _first_crossing(t, z, rise_limits[0])
    settling, settled, steady = _settling_times(t, y, z, final, step, band, tail_length, confirm)
    error = final - goal if steady else math.nan
    k = int(np.argmax(z))
    overshoot = max(0.0, float(z[k] - 1.0) * 100.0)
    return StepFigures(rise, settling, settled, overshoot, float(y[k]), float(t[k]), final, error, iae, bounded)


def step_metrics(sys, *, t_final: float | None = None, settling: float = 0.02) -> dict:
    """Step response figures of a stable SISO system (thesis 4.5: settling time and peak control).

    The response is simulated by python-control's recursion (compiled, :func:`~flexdigit.control._lsim.step_output`)
    and scored by :func:`step_figures` (the same code that scores
    the rig's measured steps), against the system's DC gain.

    Returns
    -------
    dict
        ``settling_time_s`` (2 % band), ``rise_time_s`` (10-90 %), ``peak`` (largest absolute value, in the
        output's unit per unit step), ``peak_time_s``, ``final`` (DC gain), ``overshoot_percent``, ``iae``
        (integral of the absolute error from the DC gain over the simulated time).
    """
    sys = ct.ss(sys)
    if not is_stable(sys):
        raise UnstableError("step_metrics: the system is unstable.")
    if t_final is None:  # python-control's own choice of horizon and points
        resp = ct.step_response(sys)
        t, y = resp.time, np.squeeze(resp.outputs)
    else:
        t = np.linspace(0, t_final, 4000)
        y = step_output(sys, t)
    final = float(np.real(ct.dcgain(sys)))
    figures = step_figures(t, y, target=final, band=settling)
    i = int(np.argmax(np.abs(y)))
    return {
        "settling_time_s": figures.settling_time_s,
        "rise_time_s": figures.rise_time_s,
        "peak": float(y[i]),
        "peak_abs": float(np.abs(y[i])),
        "peak_time_s": float(t[i]),
        "final": final,
        "overshoot_percent": figures.overshoot_percent,
        "iae": figures.iae,
    }


def additive_tolerance(plant, controller) -> dict:
    """Largest additive uncertainty the loop tolerates, by the small-gain theorem (thesis 4.6).

    Returns
    -------
    dict
        ``tpq_norm`` (``||K S||_inf``, commands per output unit), ``tpq_db``, ``tpq_peak_rad_s``,
        ``tolerance`` (``1/||T_pq||``, output unit per command), ``tolerance_relative_percent`` (that over
        ``|G(0)|``) and ``thesis_arithmetic_percent`` (``100 / (||T_pq|| in dB)``, the thesis's reading).
    """
    maps = loop_maps(plant, controller)
    if not maps.stable:
        raise UnstableError("additive_tolerance: the closed loop is unstable, so no uncertainty is tolerated.")
    g, w = hinf_norm(maps.T_pq, "T_pq")
    db = 20 * math.log10(g)
    g0 = abs(float(np.real(ct.dcgain(as_statespace(plant, "plant")))))
    tol = 1 / g
    return {
        "tpq_norm": g,
        "tpq_db": db,
        "tpq_peak_rad_s": w,
        "tolerance": tol,
        "tolerance_relative_percent": 100 * tol / g0 if g0 else math.inf,
        "thesis_arithmetic_percent": 100 / db if db > 0 else math.nan,
    }


def margins(plant, controller, omega=None) -> dict:
    """Classical and disk margins of ``L = G K`` (``control.stability_margins``, ``control.disk_margins``).

    Returns
    -------
    dict
        ``gain_margin`` (factor), ``phase_margin_deg``, ``gain_crossover_rad_s``, ``phase_crossover_rad_s``,
        ``disk_margin`` (``alpha = 1/||S - (1 - sigma)/2||``, skew 0), ``disk_gain_margin`` (factor) and
        ``disk_phase_margin_deg``.
    """
    L = ct.tf(as_statespace(plant, "plant")) * ct.tf(as_statespace(controller, "controller"))
    gm, pm, _sm, wpc, wgc, _wsm = ct.stability_margins(L)
    if omega is None:
        omega = np.logspace(-3, 5, 4000)
    dm, dgm, dpm = ct.disk_margins(L, omega, skew=0.0)
    dm, dgm, dpm = (float(np.min(np.atleast_1d(v))) for v in (dm, dgm, dpm))
    return {
        "gain_margin": float(gm),
        "phase_margin_deg": float(pm),
        "gain_crossover_rad_s": float(wgc),
        "phase_crossover_rad_s": float(wpc),
        "disk_margin": dm,
        "disk_gain_margin": float(10 ** (dgm / 20)) if np.isfinite(dgm) else math.inf,
        "disk_phase_margin_deg": dpm,
    }


def monte_carlo_stability(plant_factory, controller, spreads: dict, n: int = 500, seed: int = 0) -> dict:
    """Fraction of sampled plants the controller stabilises (uniform spreads, seeded).

    Parameters
    ----------
    plant_factory : callable
        ``plant_factory(**factors) -> LTI`` with one multiplicative factor per key of ``spreads``.
    controller : LTI system
    spreads : dict
        ``{name: relative half-width}``, e.g. ``{"gain": 0.3, "wn": 0.2}`` samples factors in ``1 +- 0.3`` etc.
    n : int
        Number of samples.
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    dict
        ``n``, ``stable_fraction``, ``worst_pole_real`` (the largest closed-loop pole real part over the samples,
        rad/s) and ``worst_factors``.
    """
    rng = np.random.default_rng(seed)
    K = as_statespace(controller, "controller")
    names = list(spreads)
    # sample by sample, one draw per spread in order (the same numbers as drawing them one at a time)
    factors = 1.0 + np.array([spreads[k] for k in names]) * rng.uniform(-1.0, 1.0, size=(n, len(names)))
    batch = getattr(plant_factory, "state_space", None)
    if batch is not None:  # a family that gives its members' matrices: all the closed loops in one call
        poles = closed_loop_poles_batch(batch(**dict(zip(names, factors.T, strict=True))), K)
        rightmost = np.max(poles.real, axis=1) if poles.shape[1] else np.full(n, -math.inf)
    else:
        rightmost = np.array(
            [np.max(closed_loop_poles(plant_factory(**dict(zip(names, f, strict=True))), K).real) for f in factors]
        )
    i = int(np.argmax(rightmost))
    worst_factors = {k: float(factors[i, j]) for j, k in enumerate(names)}
    return {
        "n": n,
        "stable_fraction": int(np.sum(rightmost < 0)) / n,
        "worst_pole_real": float(rightmost[i]),
        "worst_factors": worst_factors,
    }

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

from flexdigit.control._threads import single_blas_thread
from flexdigit.control.generalized import as_statespace
from flexdigit.errors import UnstableError

__all__ = [
    "LoopMaps",
    "loop_maps",
    "is_stable",
    "hinf_norm",
    "step_metrics",
    "additive_tolerance",
    "margins",
    "monte_carlo_stability",
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
    G = as_statespace(plant, "plant")
    K = as_statespace(controller, "controller")
    A, B, C, D = G.A, G.B, G.C, G.D
    Ak, Bk, Ck, Dk = K.A, K.B, K.C, K.D
    # with u = Ck xk + Dk e, e = w - C x - D u  =>  e = (w - C x - D Ck xk) / (1 + D Dk)
    r = 1.0 / (1.0 + float(D[0, 0] * Dk[0, 0]))
    Ex = -r * C  # e in terms of x
    Exk = -r * D @ Ck
    Ew = np.array([[r]])
    Ux, Uxk, Uw = Dk @ Ex, Ck + Dk @ Exk, Dk @ Ew  # u
    Acl = np.block([[A + B @ Ux, B @ Uxk], [Bk @ Ex, Ak + Bk @ Exk]])  # = [[A, B Ck], [-Bk C, Ak]] when D = Dk = 0
    Bw = np.vstack([B @ Uw, Bk @ Ew])
    Cy = np.hstack([C + D @ Ux, D @ Uxk])
    Dy = D @ Uw
    T_yw = ct.ss(Acl, Bw, Cy, Dy)
    T_zw = ct.ss(Acl, Bw, -Cy, np.eye(1) - Dy)  # 4.4: z = w - y
    T_uw = ct.ss(Acl, Bw, np.hstack([Ux, Uxk]), Uw)  # 4.5: u
    # 4.6: p enters the controller input with a minus sign (additive Delta between u and y), q = u
    Bp = -Bw
    T_pq = ct.ss(Acl, Bp, np.hstack([Ux, Uxk]), -Uw)
    return LoopMaps(T_zw, T_yw, T_uw, T_pq, np.linalg.eigvals(Acl) if Acl.size else np.array([]))


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


def step_metrics(sys, *, t_final: float | None = None, settling: float = 0.02) -> dict:
    """Step response figures of a stable SISO system (thesis 4.5: settling time and peak control).

    Returns
    -------
    dict
        ``settling_time_s`` (2 % band), ``peak`` (largest absolute value, in the output's unit per unit step),
        ``peak_time_s``, ``final`` (DC gain), ``overshoot_percent``.
    """
    sys = ct.ss(sys)
    if not is_stable(sys):
        raise UnstableError("step_metrics: the system is unstable.")
    T = None
    if t_final is not None:
        T = np.linspace(0, t_final, 4000)
    resp = ct.step_response(sys, T=T)
    y = np.squeeze(resp.outputs)
    t = resp.time
    info = ct.step_info(sys, T=t, SettlingTimeThreshold=settling)
    i = int(np.argmax(np.abs(y)))
    return {
        "settling_time_s": float(info["SettlingTime"]),
        "peak": float(y[i]),
        "peak_abs": float(np.abs(y[i])),
        "peak_time_s": float(t[i]),
        "final": float(np.real(ct.dcgain(sys))),
        "overshoot_percent": float(info["Overshoot"]),
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
    stable = 0
    worst, worst_factors = -math.inf, None
    for _ in range(n):
        factors = {k: 1.0 + spreads[k] * rng.uniform(-1.0, 1.0) for k in names}
        maps = loop_maps(plant_factory(**factors), K)
        r = float(np.max(maps.poles.real))
        stable += r < 0
        if r > worst:
            worst, worst_factors = r, factors
    return {"n": n, "stable_fraction": stable / n, "worst_pole_real": worst, "worst_factors": worst_factors}

"""Test oracles shared by the test modules: closed forms and independent models with known answers.

Every expected value a test compares with comes from the thesis (``flexdigit.reference``), from a closed form
here, or from an independent library; none from flexdigit itself. (python-control's ``robust_test.py`` notes
where its values come from; PyElastica keeps its analytical solutions in ``systems/analytical.py``.)

- Beam theory: a cantilever's tip under a small tip load (P L^3 / 3EI), under a pure tip moment (a circular arc),
  under a large tip load (the elastica, Bisshopp & Drucker 1945), and its first bending frequency
  (Euler-Bernoulli).
- Second-order responses with known wn and zeta, with seeded white noise (identification).
- A closed-form cantilever gauge model, independent of the twin (tactile).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc


# ------------------------------------------------------------------------------------------------ beam theory
def cantilever_tip_deflection_m(force_n: float, length_m: float, ei_n_m2: float) -> float:
    """Small-deflection tip deflection under a tip load, ``P L^3 / 3EI``."""
    return force_n * length_m**3 / (3 * ei_n_m2)


def circular_arc_tip_m(theta_rad: float, length_m: float) -> tuple[float, float]:
    """Tip of a strip bent by a pure tip moment into an arc of angle ``theta`` (exact): ``(x, y)`` from the clamp."""
    r = length_m / theta_rad
    return r * math.sin(theta_rad), r * (1 - math.cos(theta_rad))


def elastica_tip_load(alpha2: float) -> tuple[float, float, float]:
    """Cantilever (L = EI = 1) under a dead tip load P perpendicular to its axis, PL^2/EI = alpha2.

    Bisshopp & Drucker (1945): with k^2 = (1 + sin theta0)/2 and sin phi1 = 1/(sqrt(2) k),
    sqrt(alpha2) = K(k) - F(phi1, k); tip deflection 1 - (2/alpha)(E(k) - E(phi1, k)); horizontal tip
    position sqrt(2 sin theta0)/alpha. Returns (x_tip, y_tip, theta0).
    """
    a = math.sqrt(alpha2)

    def f(k):
        return ellipk(k * k) - ellipkinc(math.asin(1 / (math.sqrt(2) * k)), k * k) - a

    k = brentq(f, 1 / math.sqrt(2) + 1e-12, 1 - 1e-12, xtol=1e-15)
    phi1 = math.asin(1 / (math.sqrt(2) * k))
    theta0 = math.asin(2 * k * k - 1)
    y = 1 - 2 / a * (ellipe(k * k) - ellipeinc(phi1, k * k))
    return math.sqrt(2 * math.sin(theta0)) / a, y, theta0


def euler_bernoulli_first_frequency(ei_n_m2: float, mass_per_length_kg_m: float, length_m: float) -> float:
    """First bending frequency (rad/s) of a clamped-free beam: first root of cos cosh = -1, 1.8751040687."""
    return 1.8751040687**2 * math.sqrt(ei_n_m2 / (mass_per_length_kg_m * length_m**4))


# ---------------------------------------------------------------------------------- second-order responses
#: The thesis's digit (3.1.2: E(s), 13.10 rad/s, 0.068) and servo (3.2.4: MT(s), 20.53 rad/s, 0.5629).
DIGIT = {"wn_rad_s": 13.0995, "zeta": 0.06791}
SERVO = {"wn_rad_s": 20.53, "zeta": 0.5629}


def second_order(t, kind: str, wn: float, zeta: float, base: float, amplitude: float, t0: float) -> np.ndarray:
    """Closed-form underdamped second-order response: a unit ``"step"`` at ``t0``, or a ``"release"`` (free decay
    from ``base + amplitude`` held until ``t0``); ``base`` before or after."""
    t = np.asarray(t, dtype=float)
    tau = np.clip(t - t0, 0.0, None)
    wd = wn * math.sqrt(1 - zeta**2)
    decay = np.exp(-zeta * wn * tau) * (np.cos(wd * tau) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * tau))
    if kind == "step":
        return base + amplitude * np.where(t >= t0, 1.0 - decay, 0.0)
    return base + amplitude * np.where(t >= t0, decay, 1.0)


def release_record(seed, *, noise=0.02, wn=DIGIT["wn_rad_s"], zeta=DIGIT["zeta"], hold_s=0.5, dt=0.002, t_end=8.0):
    """Free decay from 1 V (relative to 0.2 V at rest) after holding it ``hold_s``, plus white noise (V)."""
    t = np.arange(0.0, t_end, dt)
    y = second_order(t, "release", wn, zeta, 0.2, 1.0, hold_s)
    return t, y + np.random.default_rng(seed).normal(0.0, noise, t.size)


def step_record(seed, *, noise=0.02, wn=SERVO["wn_rad_s"], zeta=SERVO["zeta"], dt=0.002, t_end=2.0):
    """Unit step from 0.5 (before t = 0.2 s) plus white noise of ``noise`` times the step."""
    t = np.arange(0.0, t_end, dt)
    y = second_order(t, "step", wn, zeta, 0.5, 1.0, 0.2)
    return t, y + np.random.default_rng(seed).normal(0.0, noise, t.size)


# ----------------------------------------------------------------------------------- closed-form gauges
GAUGES_M = np.array([0.045, 0.135, 0.225])  # table 3.5
GAIN_V_PER_NM = np.array([40.0, 45.0, 50.0])  # arbitrary, distinct per channel


def cantilever_gauges_v(position_from_base_m, mass_kg) -> np.ndarray:
    """Closed-form gauge volts, shape (n, 3): gain * m g * max(a - x_i, 0) (the bending moment at each gauge of
    an Euler-Bernoulli cantilever under a point load m at a from the base)."""
    a = np.atleast_1d(np.asarray(position_from_base_m, dtype=float))[:, None]
    m = np.atleast_1d(np.asarray(mass_kg, dtype=float))[:, None]
    return GAIN_V_PER_NM * m * 9.81 * np.clip(a - GAUGES_M, 0.0, None)


# ------------------------------------------------------------------------------------ the report's entries
#: results.json entries of ``flexdigit reproduce --fast`` (seed 0) as they should be: ``{key: [status, ours,
#: chapter]}``. First written from main before issue 15's refactor landed (the report's science moved into the
#: library, tables as numbers, chapters in parallel processes): the refactor had to leave every entry as it was. A
#: change meant to move them rewrites it with ``tests/data/update_report_baseline.py`` and commits the diff with its
#: reason.
FAST_BASELINE_FILE = Path(__file__).with_name("data") / "report_fast_baseline.json"
#: How far an entry may move: network training and every random stream are the same to the bit, so only rounding
#: differences remain (BLAS on one thread per chapter worker, or on two in-process).
BASELINE_RTOL = 1e-6
BASELINE_ATOL = 1e-12


def assert_entries_unchanged(entries, chapter: str) -> None:
    """Every baseline entry of ``chapter`` (its slug) is in ``entries`` with the same status and the same figure
    (within :data:`BASELINE_RTOL`); ``entries`` are :class:`~flexdigit.report.results.Entry` or dicts."""
    import json

    baseline = json.loads(FAST_BASELINE_FILE.read_text())
    got = {(e["key"] if isinstance(e, dict) else e.key): e for e in entries}
    wanted = {k: v[:2] for k, v in baseline.items() if v[2] == chapter}
    assert wanted, f"no baseline entries of chapter {chapter!r}"
    missing = sorted(set(wanted) - set(got))
    assert not missing, f"entries gone from the baseline ({FAST_BASELINE_FILE.name}): {missing}"
    moved = []
    for key, (status, ours) in wanted.items():
        e = got[key]
        e_status, e_ours = (e["status"], e["ours"]) if isinstance(e, dict) else (e.status, e.ours)
        if ours is None:  # NaN in the report, null in JSON
            same = e_ours is None or (isinstance(e_ours, float) and math.isnan(e_ours))
        elif isinstance(ours, str):
            same = e_ours == ours
        else:
            same = e_ours is not None and bool(np.isclose(e_ours, ours, rtol=BASELINE_RTOL, atol=BASELINE_ATOL))
        if not same or e_status != status:
            moved.append(f"{key}: {status} {ours!r} -> {e_status} {e_ours!r}")
    assert not moved, (
        f"entries changed from {FAST_BASELINE_FILE.name} (if meant, rewrite it with "
        "tests/data/update_report_baseline.py and commit the diff with its reason):\n" + "\n".join(moved)
    )

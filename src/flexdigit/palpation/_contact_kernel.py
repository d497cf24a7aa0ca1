"""The contact estimator's force profile, compiled: one reading's estimate within the 1 ms goal.

:meth:`flexdigit.palpation.contact_estimation.ContactEstimator` profiles the force out of every entry of its tables (a
few
hundred point positions, ~800 line loads) by Newton on a degree-5 polynomial per gauge. In numpy that is ~100 small
array operations per reading, each ~5-10 us of dispatch on (1, G, 3) arrays: milliseconds. Here the same arithmetic
runs as plain loops (tens of microseconds). The order of operations follows the numpy version it replaces
(Horner's scheme as :func:`flexdigit.palpation.contact_estimation._horner`, sums over the three gauges in order), so
the numbers
agree to rounding; ``tests/palpation/test_contact_kernel.py`` checks them against that numpy version.
"""

from __future__ import annotations

import numba
import numpy as np

from flexdigit import _numba_cache

_numba_cache.install()  # the machine code kept per user by source text (flexdigit/_numba_cache.py)

__all__ = ["profile"]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")


@_jit
def _horner(coef, g, c, f):
    """``sum_k coef[k, g, c] f^(k+1)`` and its derivative in ``f`` (as contact._horner: first step unrolled)."""
    k_count = coef.shape[0]
    if k_count == 1:
        return coef[0, g, c] * f, coef[0, g, c]
    value = coef[k_count - 1, g, c] * f + coef[k_count - 2, g, c]
    slope = coef[k_count - 1, g, c]
    for k in range(k_count - 3, -1, -1):
        slope = slope * f + value
        value = value * f + coef[k, g, c]
    return value * f, slope * f + value


@_jit
def _clip(f, sign, lim):
    return min(max(f * sign, 0.0), lim) * sign


@_jit
def _sums(r, b, coef, g, w, f):
    """At force ``f``: ``sum_c w res slope``, ``sum_c w slope^2`` and the cost ``sum_c w res^2`` over the gauges."""
    cross = 0.0
    curv = 0.0
    cost = 0.0
    for c in range(w.shape[0]):  # the gauges
        value, slope = _horner(coef, g, c, f)
        res = r[b, c] - value
        cross += w[c] * res * slope
        curv += w[c] * slope * slope
        cost += w[c] * res * res
    return cross, curv, cost


@_jit
def _newton(r, b, coef, g, w, sign, lim, f, steps):
    """``steps`` Newton steps on entry ``g``'s cost from force ``f`` (clipped before each), then the cost and the
    half curvature at the clipped result."""
    for _ in range(steps):
        f = _clip(f, sign, lim)
        cross, curv, _ = _sums(r, b, coef, g, w, f)
        f = f + cross / max(curv, 1e-300)  # the gradient is -cross
    f = _clip(f, sign, lim)
    _, curv, cost = _sums(r, b, coef, g, w, f)
    return f, cost, curv


@_jit
def profile(r, coef, w, sign, lim, half, force, cost, curv):
    """Best force, cost and the cost's half curvature in the force of every entry, in place (B, G).

    ``r`` (B, n) residual readings of the n gauges (3 on the thesis rig), ``coef`` (K, G, n) polynomial
    coefficients (powers 1..K) over the G grid entries, ``w`` (n,) weights,
    ``sign`` the side's sign, ``lim`` the largest force. ``half < 0``: two Newton steps from the linear model's
    force on every entry (:meth:`ContactEstimator._profile`). ``half >= 0``: every entry at the linear model's
    (clipped) force, then Newton on the ``2 half + 1`` entries around the best (``_profile_near_best``: all a point
    estimate needs); ``curv`` is then only meaningful on those.
    """
    n_grid = coef.shape[1]
    for b in range(r.shape[0]):
        for g in range(n_grid):
            num = 0.0
            den = 0.0
            for c in range(w.shape[0]):
                num += r[b, c] * w[c] * coef[0, g, c]
                den += coef[0, g, c] * w[c] * coef[0, g, c]
            f = num / max(den, 1e-300)
            if half < 0:
                force[b, g], cost[b, g], curv[b, g] = _newton(r, b, coef, g, w, sign, lim, f, 2)
            else:
                force[b, g], cost[b, g], curv[b, g] = _newton(r, b, coef, g, w, sign, lim, f, 0)
        if half >= 0:
            best = 0
            for g in range(1, n_grid):
                if cost[b, g] < cost[b, best]:
                    best = g
            h = min(half, (n_grid - 1) // 2)
            centre = min(max(best, h), n_grid - 1 - h)
            for g in range(centre - h, centre + h + 1):
                force[b, g], cost[b, g], curv[b, g] = _newton(r, b, coef, g, w, sign, lim, force[b, g], 2)


def empty_profile(rows: int, grid: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Output arrays for :func:`profile`."""
    return np.empty((rows, grid)), np.empty((rows, grid)), np.empty((rows, grid))


@_jit
def refine(force, cost, grid, pos_out, force_out, cost_out):
    """Best grid entry of each row, refined by a parabola through it and its neighbours (position, force and cost:
    :meth:`ContactEstimator._refine`)."""
    n_grid = grid.size
    step = grid[1] - grid[0]
    for b in range(cost.shape[0]):
        i = 0
        for g in range(1, n_grid):
            if cost[b, g] < cost[b, i]:
                i = g
        j = min(max(i, 1), n_grid - 2)
        c0, c1, c2 = cost[b, j - 1], cost[b, j], cost[b, j + 1]
        denom = c0 - 2 * c1 + c2
        shift = 0.0
        if denom > 0 and i == j:
            shift = min(max(0.5 * (c0 - c2) / denom, -1.0), 1.0)
        pos_out[b] = grid[i] + shift * step
        side = force[b, min(j + 1, n_grid - 1)] if shift >= 0 else force[b, j - 1]
        inner = 1.0 if i == j else 0.0
        force_out[b] = force[b, i] + abs(shift) * (side - force[b, i]) * inner
        cost_out[b] = cost[b, i] - 0.25 * (c0 - c2) * shift * inner


@_jit
def point_sd(position, force, grid, coef, w, out):
    """Fisher standard deviations (n, 2) of position and force of point estimates, from the table's own
    derivatives: coefficients interpolated linearly between grid entries, their slope along the grid
    (:meth:`ContactEstimator._point_sd`; inf where the information does not reach a parameter)."""
    n_grid = grid.size
    k_count = coef.shape[0]
    step = grid[1] - grid[0]
    for b in range(position.size):
        x = min(max((position[b] - grid[0]) / step, 0.0), n_grid - 1 - 1e-9)
        i = min(int(x), n_grid - 2)
        frac = x - i
        f = force[b]
        i00 = 0.0
        i01 = 0.0
        i11 = 0.0
        for c in range(w.shape[0]):
            d_pos = 0.0
            d_force = 0.0
            power = 1.0  # f^(k-1)
            for k in range(k_count):
                lo, hi = coef[k, i, c], coef[k, i + 1, c]
                d_force += (k + 1) * power * (lo * (1 - frac) + hi * frac)
                power *= f
                d_pos += power * (hi - lo) / step
            i00 += w[c] * d_pos * d_pos
            i01 += w[c] * d_pos * d_force
            i11 += w[c] * d_force * d_force
        out[b, 0] = np.inf
        out[b, 1] = np.inf
        if i00 > 0 and i11 > 0:
            r2 = i01 * i01 / (i00 * i11)
            if 1.0 - r2 > 1e-8:
                scale = np.sqrt(1.0 / (1.0 - r2))
                out[b, 0] = scale / np.sqrt(i00)
                out[b, 1] = scale / np.sqrt(i11)


@_jit
def log_evidence(cost, curv, out):
    """``log mean_g exp(-cost_g / 2) sqrt(2 pi / curv_g)`` of each row (:func:`contact._log_evidence`)."""
    n_grid = cost.shape[1]
    for b in range(cost.shape[0]):
        top = -np.inf
        for g in range(n_grid):
            term = -0.5 * cost[b, g] + 0.5 * np.log(2 * np.pi / max(curv[b, g], 1e-300))
            top = max(top, term)
        total = 0.0
        for g in range(n_grid):
            term = -0.5 * cost[b, g] + 0.5 * np.log(2 * np.pi / max(curv[b, g], 1e-300))
            total += np.exp(term - top)
        out[b] = top + np.log(total / n_grid)


@_jit
def line_jacobian(index, total, line, d_centre, d_extent, out):
    """``d gauges / d (centre, extent, total)`` (n, 3, 3) of line-table entries ``index`` at forces ``total``: the
    derivative tables' polynomials (powers 1..K) and the line polynomial's slope."""
    k_count = line.shape[0]
    for b in range(index.size):
        i = index[b]
        f = total[b]
        for c in range(line.shape[2]):
            dc = 0.0
            dw = 0.0
            dt = 0.0
            power = 1.0  # f^(k-1)
            for k in range(k_count):
                dt += (k + 1) * power * line[k, i, c]
                power *= f
                dc += power * d_centre[k, i, c]
                dw += power * d_extent[k, i, c]
            out[b, c, 0] = dc
            out[b, c, 1] = dw
            out[b, c, 2] = dt


@_jit
def fisher_sd(jac, w, out):
    """:func:`flexdigit.tactile.bounds.fisher_sd`'s general branch (d >= 3) for Jacobians (n, 3, d) and weights
    ``1 / sigma^2`` (3,), in place (n, d): ``sqrt(diag(F^-1))``, inf for every parameter where the scaled
    information is singular or worse conditioned than 1e8."""
    n, n_gauges, d = jac.shape
    info = np.empty((d, d))
    corr = np.empty((d, d))
    scale = np.empty(d)
    for b in range(n):
        for i in range(d):
            for j in range(d):
                total = 0.0
                for c in range(n_gauges):
                    total += jac[b, c, i] * w[c] * jac[b, c, j]
                info[i, j] = total
        out[b, :] = np.inf
        positive = True
        for i in range(d):
            positive = positive and info[i, i] > 0
        if not positive:
            continue
        for i in range(d):
            scale[i] = np.sqrt(info[i, i])
        for i in range(d):
            for j in range(d):
                corr[i, j] = info[i, j] / (scale[i] * scale[j])
        if not np.linalg.cond(corr) < 1e8:
            continue
        inv = np.linalg.inv(corr)
        for i in range(d):
            out[b, i] = np.sqrt(inv[i, i]) / scale[i]

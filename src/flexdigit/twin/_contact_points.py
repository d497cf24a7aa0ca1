"""The twin's contact quadrature (:meth:`flexdigit.twin.contact.TissueContact.points`), compiled.

numba, because the quadrature is ~60 numpy operations on arrays of a few dozen numbers: at the batch sizes of a
Newton solve (1-20 shapes) numpy spends ~200 us a call in dispatch and temporaries for ~2 us of arithmetic, and a
palpation study calls it ~9,000 times. The same elementwise IEEE operations in the same order as the numpy
reference (``TissueContact._points_numpy``; the cumulative sums run in order, as ``np.cumsum`` does; no fast-math,
so no fused multiply-adds), so the same bits: ``tests/twin/test_contact.py`` checks them equal.
The generalised forces and their Jacobian (``contact_generalized``) sum over the points in order, as numpy's einsum
does, and add the diagonal's moment term after those sums, as ``TissueContact._generalized_numpy`` does: equal to
the bit here too (the thesis report's palpation tables are unchanged); the resultant (``contact_resultant``) sums
sequentially where ``np.sum`` sums pairwise, so it may differ by an ulp per point.
"""

from __future__ import annotations

import numba
import numpy as np

from flexdigit import _numba_cache

_numba_cache.install()  # the machine code kept per user by source text (flexdigit/_numba_cache.py)

__all__ = ["contact_points"]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def contact_points(psi, link_start, link_len, chain_link_len, sign, gap, lo, hi, k, gauss_t, gauss_w):
    """``(s, w, delta, k)``, each (B, L * M * G), of the quadrature points on the links that reach into the body
    anywhere in the batch (L of them, in order), against its M pieces, G Gauss points each."""
    b, n = psi.shape
    x = np.empty((b, n + 2))
    depth = np.empty((b, n + 2))
    for i in range(b):
        x[i, 0] = 0.0
        x[i, 1] = link_len[0] + 0.0
        depth[i, 0] = sign * 0.0 - gap
        depth[i, 1] = sign * 0.0 - gap
        cx = 0.0
        cy = 0.0
        for j in range(n):
            cx += chain_link_len[j] * np.cos(psi[i, j])
            cy += chain_link_len[j] * np.sin(psi[i, j])
            x[i, j + 2] = link_len[0] + cx
            depth[i, j + 2] = sign * cy - gap
    first, last = lo[0], hi[hi.size - 1]
    chosen = np.zeros(n + 1, dtype=np.bool_)
    for j in range(n + 1):
        for i in range(b):
            if (
                max(depth[i, j], depth[i, j + 1]) > 0
                and max(x[i, j], x[i, j + 1]) >= first
                and min(x[i, j], x[i, j + 1]) <= last
            ):
                chosen[j] = True
                break
    links = np.flatnonzero(chosen)
    m, g = lo.size, gauss_t.size
    p = links.size * m * g
    s_out, w_out, d_out, k_out = np.empty((b, p)), np.empty((b, p)), np.empty((b, p)), np.empty((b, p))
    for i in range(b):
        col = 0
        for j in links:
            x0, x1, d0, d1 = x[i, j], x[i, j + 1], depth[i, j], depth[i, j + 1]
            dx = x1 - x0
            root = d0 / (d0 - d1) if d0 != d1 else 0.0
            for q in range(m):
                if dx > 0:
                    ta = (lo[q] - x0) / dx
                    tb = (hi[q] - x0) / dx
                else:
                    ta = 0.0 if x0 >= lo[q] else 1.0
                    tb = 1.0 if x0 <= hi[q] else 0.0
                ta = min(max(ta, 0.0), 1.0)
                tb = min(max(tb, 0.0), 1.0)
                if d0 <= 0 and d1 > 0:
                    ta = max(ta, root)
                if d0 > 0 and d1 <= 0:
                    tb = min(tb, root)
                span = 0.0 if (tb <= ta or (d0 <= 0 and d1 <= 0)) else tb - ta
                for r in range(g):
                    t = ta + span * gauss_t[r]
                    s_out[i, col] = link_start[j] + t * link_len[j]
                    w_out[i, col] = span * gauss_w[r] * link_len[j]
                    d_out[i, col] = max(d0 + t * (d1 - d0), 0.0)
                    k_out[i, col] = k[q]
                    col += 1
    return s_out, w_out, d_out, k_out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _point_load(delta, k, rate, exponent, damping):
    """``TissueContact.load`` at one point: ``(q, dq/d delta, dq/d rate)``, zero where the body does not push."""
    elastic = k * delta**exponent
    if exponent != 1.0:
        slope = exponent * k * delta ** (exponent - 1.0) if delta > 0 else 0.0
    else:
        slope = k if delta > 0 else 0.0
    factor = 1.0 + 1.5 * damping * rate
    q = elastic * factor
    if q > 0:
        return q, slope * factor, 1.5 * damping * elastic
    return 0.0, 0.0, 0.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _levers_cos(s, joint_s, chain_link_len, cos_psi, lever, c):
    """One point's levers ``min(max(s - s_j, 0), l_j)`` and ``lever_j cos psi_j`` into ``lever``, ``c`` (n,);
    returns how many leading entries are non-zero (the links past the point carry no lever)."""
    count = 0
    for j in range(joint_s.size):
        lj = min(max(s - joint_s[j], 0.0), chain_link_len[j])
        lever[j] = lj
        c[j] = lj * cos_psi[j]
        if lj > 0:
            count = j + 1
    return count


@numba.njit(cache=True, nogil=True, error_model="numpy")
def contact_generalized(psi, omega, link_start, link_len, chain_link_len, joint_s, sign, gap, lo, hi, k, gauss_t,
                        gauss_w, exponent, damping):  # fmt: skip
    """``TissueContact.generalized`` in one pass: ``Q`` (B, n), ``dQ/dpsi`` and ``dQ/domega`` (B, n, n; zeros
    without damping). ``omega`` (B, n) or (0, n) for none (then no penetration rate)."""
    b, n = psi.shape
    s, w, delta, kk = contact_points(psi, link_start, link_len, chain_link_len, sign, gap, lo, hi, k, gauss_t, gauss_w)
    gen = np.zeros((b, n))
    d_psi = np.zeros((b, n, n))
    d_omega = np.zeros((b, n, n))
    lever, c, moment = np.empty(n), np.empty(n), np.empty(n)
    rated = omega.shape[0] == b and damping > 0
    for i in range(b):
        cos_psi, sin_psi = np.cos(psi[i]), np.sin(psi[i])
        moment[:] = 0.0  # sum_p w q lever_pj, added to the diagonal after the sums over the points (numpy's order)
        for p in range(s.shape[1]):
            if w[i, p] == 0.0:
                continue  # a point outside the contact: weight 0, no load
            count = _levers_cos(s[i, p], joint_s, chain_link_len, cos_psi, lever, c)
            rate = 0.0
            if rated:
                for j in range(count):
                    rate += c[j] * omega[i, j]
                rate *= sign
            q, dq_dd, dq_dv = _point_load(delta[i, p], kk[i, p], rate, exponent, damping)
            wq, wd, wv = w[i, p] * q, w[i, p] * dq_dd, w[i, p] * dq_dv
            for j in range(count):
                gen[i, j] += wq * c[j]
                moment[j] += wq * lever[j]
                for m in range(count):
                    d_psi[i, j, m] += wd * c[j] * c[m]
                    d_omega[i, j, m] += wv * c[j] * c[m]
        for j in range(n):
            gen[i, j] *= -sign
            for m in range(n):
                d_psi[i, j, m] = -d_psi[i, j, m]
                d_omega[i, j, m] = -d_omega[i, j, m]
            d_psi[i, j, j] += sign * moment[j] * sin_psi[j]
    return gen, d_psi, d_omega


@numba.njit(cache=True, nogil=True, error_model="numpy")
def contact_resultant(psi, omega, link_start, link_len, chain_link_len, joint_s, gauge_s, sign, gap, lo, hi, k,
                      gauss_t, gauss_w, exponent, damping):  # fmt: skip
    """``TissueContact.resultant`` in one pass: total force (B,) (+ towards the cable side), centroid, first and
    last arc position in contact (B,; NaN without contact) and the force past each gauge (B, G, 2)."""
    b, n = psi.shape
    s, w, delta, kk = contact_points(psi, link_start, link_len, chain_link_len, sign, gap, lo, hi, k, gauss_t, gauss_w)
    total, centroid = np.zeros(b), np.full(b, np.nan)
    first, last = np.full(b, np.nan), np.full(b, np.nan)
    beyond = np.zeros((b, gauge_s.size, 2))
    lever, c = np.empty(n), np.empty(n)
    rated = omega.shape[0] == b and damping > 0
    for i in range(b):
        cos_psi = np.cos(psi[i])
        moment, lo_s, hi_s = 0.0, np.inf, -np.inf
        for p in range(s.shape[1]):
            rate = 0.0
            if rated:
                count = _levers_cos(s[i, p], joint_s, chain_link_len, cos_psi, lever, c)
                for j in range(count):
                    rate += c[j] * omega[i, j]
                rate *= sign
            wq = w[i, p] * _point_load(delta[i, p], kk[i, p], rate, exponent, damping)[0]
            if not wq > 0:
                continue
            total[i] += wq
            moment += wq * s[i, p]
            lo_s, hi_s = min(lo_s, s[i, p]), max(hi_s, s[i, p])
            for g in range(gauge_s.size):
                if s[i, p] > gauge_s[g]:
                    beyond[i, g, 1] -= sign * wq
        if total[i] > 0:
            centroid[i], first[i], last[i] = moment / total[i], lo_s, hi_s
        total[i] *= -sign
    return total, centroid, first, last, beyond

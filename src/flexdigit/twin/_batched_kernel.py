"""The batched twin's dynamics, compiled: the scalar twin's ROS2 step, eight rigs abreast in machine code.

numba, because a step is dozens of 9 x 9 products and solves per rig: over a whole batch axis numpy spends ~10 us
per rig and step in memory traffic and dispatch; compiled, ~2 us (CPU, one thread, 9 links). Every loop below runs
innermost over :data:`LANES` rigs so that the compiler could step eight rigs in vector registers; numba 0.68's
LLVM vectorises little of it (the machine code is mostly scalar): the next factor, if one is needed. A lone rig
(the scalar twin's :meth:`~flexdigit.twin.digit.DynamicState.use_compiled`) runs one lane, not eight of which seven
would idle, its factorisation and solves on plain (n, n) rows (:func:`_lu_factor_one`: the same operations in
the same order, so the same bits as in a batch): ~2-10 x less CPU than the numpy step from 35 links down to 9.

:func:`advance_rigs` advances rigs ``lo..hi`` of a batch over ``K`` steps of ``h`` seconds: the step of
:meth:`flexdigit.twin.digit.DynamicState._ros2` (Verwer et al.'s ROS2, exact Jacobian, non-autonomous cable term)
with the batched twin's antagonistic cable, halved (depth first, at most 12 times) while a link would turn more
than ``max_rotation_rad`` in a step, as :meth:`~flexdigit.twin.digit.DynamicState.step` does, each rig on its own:
a rig that needs halved steps takes them while the others in its group of eight sit out. The lanes never mix
(elementwise IEEE arithmetic in a fixed order), so a rig's numbers do not depend on its batch, its lane or the
thread that runs it: the same bits for any batch size and thread count. The kernel releases the GIL, so blocks of
rigs step on separate cores.
"""

from __future__ import annotations

import numba
import numpy as np

from flexdigit import _numba_cache

_numba_cache.install()  # the machine code kept per user by source text (flexdigit/_numba_cache.py)

__all__ = ["LANES", "advance_rigs"]

#: Rigs stepped abreast (two AVX2 vectors of doubles: enough independent work to hide the latencies).
LANES = 8
_MAX_DEPTH = 12
_GAMMA = 1.0 - 1.0 / np.sqrt(2.0)  # DynamicState.GAMMA

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")


@_jit
def _lu_factor_one(w, n, big, ok):
    """:func:`_lu_factor` of one rig's ``w`` (n, n): the same operations in the same order, so the same bits."""
    big[0] = 0.0
    for i in range(n):
        for j in range(n):
            big[0] = max(big[0], abs(w[i, j]))
    for k in range(n):
        ok[0] = ok[0] and abs(w[k, k]) > 1e-14 * big[0]
        inv = 1.0 / w[k, k]
        for i in range(k + 1, n):
            f = w[i, k] * inv
            w[i, k] = f
            for j in range(k + 1, n):
                w[i, j] -= f * w[k, j]


@_jit
def _lu_factor(w, n, big, inv, f, ok):
    """Unpivoted LU of every lane's ``w`` (n, n, lanes) in place; ``ok[l]`` cleared on a vanishing pivot. The mass
    and iteration matrices are dominated by the positive definite mass matrix, where elimination without pivoting
    is stable."""
    lanes = w.shape[2]
    if lanes == 1:  # one rig: its rows contiguous, so the elimination's inner loop runs in vector registers
        _lu_factor_one(w.reshape(n, n), n, big, ok)
        return
    for lane in range(LANES):
        big[lane] = 0.0
    for i in range(n):
        for j in range(n):
            for lane in range(LANES):
                big[lane] = max(big[lane], abs(w[i, j, lane]))
    for k in range(n):
        for lane in range(LANES):
            ok[lane] = ok[lane] and abs(w[k, k, lane]) > 1e-14 * big[lane]
            inv[lane] = 1.0 / w[k, k, lane]
        for i in range(k + 1, n):
            for lane in range(LANES):
                f[lane] = w[i, k, lane] * inv[lane]
                w[i, k, lane] = f[lane]
            for j in range(k + 1, n):
                for lane in range(LANES):
                    w[i, j, lane] -= f[lane] * w[k, j, lane]


@_jit
def _lu_solve_one(lu, x, n):
    """:func:`_lu_solve` of one rig: ``lu`` (n, n), ``x`` (n, 1)."""
    for k in range(1, n):
        acc = x[k, 0]
        for j in range(k):
            acc -= lu[k, j] * x[j, 0]
        x[k, 0] = acc
    for k in range(n - 1, -1, -1):
        acc = x[k, 0]
        for j in range(k + 1, n):
            acc -= lu[k, j] * x[j, 0]
        x[k, 0] = acc / lu[k, k]


@_jit
def _lu_solve(lu, x, n):
    """Solve every lane in place with :func:`_lu_factor`'s factors: ``x`` (n, lanes)."""
    lanes = x.shape[1]
    if lanes == 1:  # one rig: the same operations in the same order without the lane loops
        _lu_solve_one(lu.reshape(n, n), x, n)
        return
    for k in range(1, n):
        for j in range(k):
            for lane in range(LANES):
                x[k, lane] -= lu[k, j, lane] * x[j, lane]
    for k in range(n - 1, -1, -1):
        for j in range(k + 1, n):
            for lane in range(LANES):
                x[k, lane] -= lu[k, j, lane] * x[j, lane]
        for lane in range(LANES):
            x[k, lane] /= lu[k, k, lane]


@_jit
def _rhs(psi, omega, sh, p, m, sm, rhs, s, co, w2, taut):
    """Mass matrix ``m``, ``sin``-weighted ``sm`` and ``M alpha = rhs`` at a point (DynamicState._rhs), and the
    number of taut cables per lane in ``taut``. ``sh``: the main cable's shortening, not finite when detached."""
    a, k, c, bw, ga, gb, e, kc, pre, anta = p
    lanes = psi.shape[1]
    n = a.shape[0]  # not psi's: the work rows (psi2 below) have at least 7 rows, a chain of fewer links fewer
    for j in range(n):
        for lane in range(lanes):
            s[j, lane] = np.sin(psi[j, lane])
            co[j, lane] = np.cos(psi[j, lane])
            w2[j, lane] = omega[j, lane] * omega[j, lane]
    # cos(psi_j - psi_q), sin(psi_j - psi_q) from products (no trigonometry on n^2 numbers): exactly symmetric and
    # antisymmetric, so half of them are computed
    for j in range(n):
        for lane in range(lanes):
            m[j, j, lane] = a[j, j, lane]
            sm[j, j, lane] = 0.0
        for q in range(j + 1, n):
            for lane in range(lanes):
                cd = co[j, lane] * co[q, lane] + s[j, lane] * s[q, lane]
                sd = s[j, lane] * co[q, lane] - co[j, lane] * s[q, lane]
                m[j, q, lane] = a[j, q, lane] * cd
                m[q, j, lane] = a[q, j, lane] * cd
                sm[j, q, lane] = a[j, q, lane] * sd
                sm[q, j, lane] = -(a[q, j, lane] * sd)
    for j in range(n):
        for lane in range(lanes):
            rhs[j, lane] = co[j, lane] * gb[j, lane] - s[j, lane] * ga[j, lane]
        for q in range(max(0, j - bw), min(n, j + bw + 1)):  # springs and dampers join neighbouring links
            for lane in range(lanes):
                rhs[j, lane] -= k[j, q, lane] * psi[q, lane] + c[j, q, lane] * omega[q, lane]
        for q in range(n):
            for lane in range(lanes):
                rhs[j, lane] -= sm[j, q, lane] * w2[q, lane]
    for lane in range(lanes):
        attached = np.isfinite(sh[lane])
        shortening = sh[lane] if attached else 0.0
        s1 = shortening + pre[lane] - e[lane] * psi[n - 1, lane]
        s2 = pre[lane] - shortening + e[lane] * psi[n - 1, lane]
        t1 = s1 if s1 > 0.0 else 0.0
        t2 = s2 if s2 > 0.0 else 0.0
        count = (1.0 if s1 > 0.0 else 0.0) + anta[lane] * (1.0 if s2 > 0.0 else 0.0)
        taut[lane] = count if attached else 0.0
        rhs[n - 1, lane] += e[lane] * kc[lane] * (t1 - anta[lane] * t2) if attached else 0.0


@_jit
def _ros2(psi, omega, h, sh0, sh1, p, wm, wv, psi_out, omega_out, ok):
    """One ROS2 step (DynamicState._ros2) of every lane into ``psi_out``, ``omega_out``; ``ok`` cleared where a
    matrix is singular."""
    a, k, c, bw, ga, gb, e, kc, pre, anta = p
    n, lanes = psi.shape
    m, sm, f_psi, w, m2, sm2 = wm[0], wm[1], wm[2], wm[3], wm[4], wm[5]
    rhs, s, co, alpha, b1, a1, psi2, omega2 = wv[0], wv[1], wv[2], wv[3], wv[4], wv[5], wv[6], wv[7]
    rhs2, b2, tmp, w2, r1 = wv[8], wv[9], wv[10], wv[11], wv[12]
    taut, q_t, big, inv, f, sa, mw = wv[13, 0], wv[13, 1], wv[13, 2], wv[13, 3], wv[13, 4], wv[13, 5], wv[13, 6]
    gh = _GAMMA * h
    _rhs(psi, omega, sh0, p, m, sm, rhs, s, co, w2, taut)
    # alpha = M^-1 rhs: factor a copy of M (M itself is needed below)
    for j in range(n):
        for lane in range(lanes):
            alpha[j, lane] = rhs[j, lane]
        for q in range(n):
            for lane in range(lanes):
                m2[j, q, lane] = m[j, q, lane]
    _lu_factor(m2, n, big, inv, f, ok)
    _lu_solve(m2, alpha, n)
    # Jacobians of F = M alpha + N(psi, omega) - Q(psi, omega); iteration matrix W = M + gh F_omega + gh^2 F_psi
    for j in range(n):
        for lane in range(lanes):
            sa[lane] = 0.0  # sum_q sm_jq alpha_q
            mw[lane] = 0.0  # sum_q m_jq w2_q
        for q in range(n):
            for lane in range(lanes):
                f_psi[j, q, lane] = sm[j, q, lane] * alpha[q, lane] - m[j, q, lane] * w2[q, lane]
                sa[lane] += sm[j, q, lane] * alpha[q, lane]
                mw[lane] += m[j, q, lane] * w2[q, lane]
        for q in range(max(0, j - bw), min(n, j + bw + 1)):
            for lane in range(lanes):
                f_psi[j, q, lane] += k[j, q, lane]
        for lane in range(lanes):
            f_psi[j, j, lane] += -sa[lane] + mw[lane] + co[j, lane] * ga[j, lane] + s[j, lane] * gb[j, lane]
    for lane in range(lanes):
        f_psi[n - 1, n - 1, lane] += kc[lane] * e[lane] * e[lane] * taut[lane]
        # dQ/dt of the cable on the tip link (its shortening is linear in t over the step)
        moving = np.isfinite(sh0[lane]) and np.isfinite(sh1[lane])
        q_t[lane] = e[lane] * kc[lane] * taut[lane] * ((sh1[lane] - sh0[lane]) / h) if moving else 0.0
    for j in range(n):
        for lane in range(lanes):
            b1[j, lane] = rhs[j, lane]
        for q in range(n):
            for lane in range(lanes):
                w[j, q, lane] = (
                    m[j, q, lane]
                    + gh * (2.0 * sm[j, q, lane] * omega[q, lane] + c[j, q, lane])
                    + gh * gh * f_psi[j, q, lane]
                )
                b1[j, lane] -= gh * f_psi[j, q, lane] * omega[q, lane]
    for lane in range(lanes):
        b1[n - 1, lane] += gh * q_t[lane]
    _lu_factor(w, n, big, inv, f, ok)
    _lu_solve(w, b1, n)
    for j in range(n):
        for lane in range(lanes):
            a1[j, lane] = omega[j, lane] + gh * b1[j, lane]
            psi2[j, lane] = psi[j, lane] + h * a1[j, lane]
            omega2[j, lane] = omega[j, lane] + h * b1[j, lane]
    _rhs(psi2, omega2, sh1, p, m2, sm2, rhs2, s, co, tmp, f)
    _lu_factor(m2, n, big, inv, f, ok)
    _lu_solve(m2, rhs2, n)  # alpha2
    for j in range(n):
        for lane in range(lanes):
            tmp[j, lane] = rhs2[j, lane] - 2.0 * b1[j, lane]
            r1[j, lane] = omega2[j, lane] - 2.0 * a1[j, lane]
    for j in range(n):
        for lane in range(lanes):
            b2[j, lane] = 0.0
        for q in range(n):
            for lane in range(lanes):
                b2[j, lane] += m[j, q, lane] * tmp[q, lane] - gh * f_psi[j, q, lane] * r1[q, lane]
    for lane in range(lanes):
        b2[n - 1, lane] -= gh * q_t[lane]
    _lu_solve(w, b2, n)
    for j in range(n):
        for lane in range(lanes):
            a2 = r1[j, lane] + gh * b2[j, lane]
            psi_out[j, lane] = psi[j, lane] + h * (1.5 * a1[j, lane] + 0.5 * a2)
            omega_out[j, lane] = omega[j, lane] + h * (1.5 * b1[j, lane] + 0.5 * b2[j, lane])


@_jit
def advance_rigs(psi, omega, short, h, a, k, c, bw, ga, gb, e, kc, pre, anta, max_rotation_rad, lo, hi, steps_taken):
    """Advance rigs ``lo..hi-1`` over ``short.shape[0] - 1`` steps of ``h`` s, in place.

    ``psi``, ``omega`` (N, n): link angles (rad) and rates (rad/s); ``short`` (K + 1, N): each rig's main-cable
    shortening (m) at the step boundaries, linear in between (not finite: detached); ``a``, ``k``, ``c`` (N, n, n)
    (``k`` and ``c`` zero beyond ``bw`` entries from the diagonal), ``ga``, ``gb`` (N, n), ``e``, ``kc``, ``pre``
    (N,), ``anta`` (N,) bool: the chains (:class:`~flexdigit.twin.batched.BatchedChains`); ``steps_taken`` (N,)
    counts the ROS2 steps each rig took (halved ones included). Returns -1, or the first rig whose dynamics
    failed (a singular matrix, or non-finite angles after the last halving): the rigs of the groups of eight
    before its group are advanced, the others are left where they were.
    """
    n = psi.shape[1]
    lanes = 1 if hi - lo == 1 else LANES  # one rig (the scalar twin's): one lane, not eight of which seven idle
    depth_slots = 2 * _MAX_DEPTH + 4
    al, kl, cl = np.empty((n, n, lanes)), np.empty((n, n, lanes)), np.empty((n, n, lanes))
    gal, gbl = np.empty((n, lanes)), np.empty((n, lanes))
    el, kcl, prel, antal = np.empty(lanes), np.empty(lanes), np.empty(lanes), np.empty(lanes)
    p = (al, kl, cl, bw, gal, gbl, el, kcl, prel, antal)
    wm = np.empty((6, n, n, lanes))
    wv = np.empty((14, max(n, 7), lanes))
    cur_psi, cur_omega = np.empty((n, lanes)), np.empty((n, lanes))
    new_psi, new_omega = np.empty((n, lanes)), np.empty((n, lanes))
    stack_h = np.empty(depth_slots)
    stack_d = np.empty(depth_slots, dtype=np.int64)
    stack_s0, stack_s1 = np.empty((depth_slots, lanes)), np.empty((depth_slots, lanes))
    stack_on = np.zeros((depth_slots, lanes), dtype=np.bool_)
    s0, s1, on, half = np.empty(lanes), np.empty(lanes), np.zeros(lanes, np.bool_), np.zeros(lanes, np.bool_)
    ok = np.ones(lanes, dtype=np.bool_)
    rig = np.empty(lanes, dtype=np.int64)
    for first in range(lo, hi, lanes):
        for lane in range(lanes):  # a short last group repeats its last rig in the spare lanes, which sit out
            rig[lane] = min(first + lane, hi - 1)
            r = rig[lane]
            for i in range(n):
                for j in range(n):
                    al[i, j, lane], kl[i, j, lane], cl[i, j, lane] = a[r, i, j], k[r, i, j], c[r, i, j]
                gal[i, lane], gbl[i, lane] = ga[r, i], gb[r, i]
                cur_psi[i, lane], cur_omega[i, lane] = psi[r, i], omega[r, i]
            el[lane], kcl[lane], prel[lane], antal[lane] = e[r], kc[r], pre[r], 1.0 if anta[r] else 0.0
        for j in range(short.shape[0] - 1):
            top = 0
            stack_h[0], stack_d[0] = h, 0
            for lane in range(lanes):
                stack_s0[0, lane], stack_s1[0, lane] = short[j, rig[lane]], short[j + 1, rig[lane]]
                stack_on[0, lane] = first + lane < hi
            while top >= 0:
                hh, depth = stack_h[top], stack_d[top]
                for lane in range(lanes):
                    s0[lane], s1[lane], on[lane] = stack_s0[top, lane], stack_s1[top, lane], stack_on[top, lane]
                    ok[lane] = True
                top -= 1
                _ros2(cur_psi, cur_omega, hh, s0, s1, p, wm, wv, new_psi, new_omega, ok)
                halve = False
                for lane in range(lanes):
                    half[lane] = False
                    if not on[lane]:
                        continue
                    steps_taken[rig[lane]] += 1
                    if not ok[lane]:
                        return rig[lane]
                    spin = 0.0
                    finite = True
                    for q in range(n):
                        spin = max(spin, abs(cur_omega[q, lane]), abs(new_omega[q, lane]))
                        finite = finite and np.isfinite(new_omega[q, lane])
                    if (hh * spin > max_rotation_rad or not finite) and depth < _MAX_DEPTH:
                        half[lane] = halve = True
                        continue
                    for q in range(n):
                        if not np.isfinite(new_psi[q, lane]):
                            return rig[lane]
                        cur_psi[q, lane], cur_omega[q, lane] = new_psi[q, lane], new_omega[q, lane]
                if halve:  # the second half below the first: depth first, in time order (DynamicState.step)
                    stack_h[top + 1] = stack_h[top + 2] = 0.5 * hh
                    stack_d[top + 1] = stack_d[top + 2] = depth + 1
                    for lane in range(lanes):
                        mid = 0.5 * (s0[lane] + s1[lane])
                        stack_s0[top + 1, lane], stack_s1[top + 1, lane] = mid, s1[lane]
                        stack_s0[top + 2, lane], stack_s1[top + 2, lane] = s0[lane], mid
                        stack_on[top + 1, lane] = stack_on[top + 2, lane] = half[lane]
                    top += 2
        for lane in range(lanes):
            if first + lane < hi:
                for i in range(n):
                    psi[rig[lane], i], omega[rig[lane], i] = cur_psi[i, lane], cur_omega[i, lane]
    return -1

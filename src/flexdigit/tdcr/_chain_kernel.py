"""The discretised Cosserat rod with tendons, compiled: its forces, the implicit step and its banded Newton.

The rod is PyElastica's discretisation (Gazzola et al. 2018, R. Soc. open sci. 5: 171628): positions ``x_i`` at
``N`` nodes, a frame ``Q_e`` per element (columns: the cross-section's axes in the world frame). Element ``e``'s
shear/extension ``sigma_e = Q_e^T (x_{e+1} - x_e) / l_e - e3`` carries the force ``Q_e Kse sigma_e``; the
relative rotation of neighbouring frames, ``kappa_i = log(Q_{i-1}^T Q_i) / D_i`` over the Voronoi length
``D_i``, carries the moment ``Kbt kappa_i`` (the clamp is a frame ``I`` half an element before element 0).
The bending pair balances angular momentum exactly: element ``i - 1`` gets ``+exp(kappa D) m``, element ``i``
gets ``-m`` (body frames). A tendon at tension ``tau`` is the energy ``tau L`` of its path, a polyline through
its offset ``r`` at each element's middle (the disks), from ``r`` at the clamp to ``x_end + Q_{end-1} r``: its
forces are ``-tau dL/dq``, a frictionless tendon at constant tension (the continuous limit is Rucker & Webster's
2011 tendon load).

Time: BDF2 (A- and L-stable, Hairer & Wanner II.III) on positions, velocities and the body-frame angular
velocities; a frame moves by ``Q^{n+1} = Q^n exp(psi)``, ``psi = -log(Q^{n T} Q^{n-1}) / 3 + (2 dt / 3) W^{n+1}``
(BDF2 in the chart at ``Q^n``). The unknowns of a step are the new velocities, six a block (``W_k, v_{k+1}``:
the frame's first, which narrows the band by three over the node first); each block couples to its neighbours
two blocks away at most (tendons), so the Jacobian is banded with half bandwidth 14 (8 without tendons; checked
against a dense Jacobian in tests/tdcr/test_dynamics.py). It is built by coloured finite differences (Curtis,
Powell & Reid 1974: 29 residual evaluations), factored by banded LU without pivoting (the matrix is mass +
dt^2 stiffness of a stable rod), and reused over steps (a chord Newton, refreshed where it converges slower than a
rate of 0.5: the rule of scipy's BDF and of Hairer & Wanner's RADAU5). Kelvin-Voigt damping ``beta K`` on the
strains' BDF2 rates.

Speed (a step of the 40-node rod is ~1.15 Newton iterations: one residual and one banded solve each): the whole
march is one compiled call writing the response in place; rotations are computed in scalars (a 3x3 scratch array
is memory the outputs might alias, reloaded after every store) with indices rather than views (a view's
reference count costs more than its arithmetic); below 0.1 rad the frames' exp and log use Taylor series; the
banded solve keeps its newest unknowns in registers (through memory each row waited for the last one's store);
the step's arithmetic runs under LLVM's fast-math licences :data:`FAST_MATH` (fused multiply-adds, sums
reordered: 1.34x, the trajectory ~1e-11 m from IEEE's). ``benchmarks/profile_tdcr_dynamics.py`` times the parts:
per iteration ~2.1 us the residual and ~1.35 us the banded solve, per step ~0.4 us the new frames and ~0.45 us
the response's node frames.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from flexdigit import _numba_cache

_numba_cache.install()  # the machine code kept per user by source text (flexdigit/_numba_cache.py)

__all__ = [
    "BUDGET",
    "FAST_MATH",
    "MAX_UPDATE",
    "MEASURE",
    "NO_PROGRESS",
    "RATE",
    "element_frames",
    "equilibrate",
    "forces",
    "node_frames",
    "run",
]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")
#: LLVM's fast-math licences for the step's arithmetic (the residual, the solve, the frames): fused multiply-adds
#: ("contract"), sums reordered ("reassoc", which lets the solve's rows vectorise), reciprocals ("arcp") and zero's
#: sign ignored ("nsz"); each changes a result by round-off, not beyond. Not "nnan"/"ninf" (the Newton's checks for
#: NaN must stay) nor "afn" (approximate functions). Only on the arithmetic: the Newton's control, the finite
#: differences and the statics' Newton keep IEEE's. 1.3x on the 40-node rod's step (benchmarks/bench_tdcr.py).
FAST_MATH = {"contract", "reassoc", "arcp", "nsz"}
_fast = numba.njit(cache=True, nogil=True, error_model="numpy", fastmath=FAST_MATH)
# A callee is compiled once per argument types, and numba types a constant argument (True, 2) as its literal: a
# call with a constant beside one with a variable compiles the callee twice (_newton, _backward_euler, _corotate were,
# ~25 % of the first compile). So the constants passed are typed values: np.bool_(True), np.int64(2).

#: Returned by :func:`equilibrate` when Newton did not converge.
NO_PROGRESS = -1
RATE = 0.9
#: Multiplied by rather than divided by in a step's history (its ~500 divisions were ~8 % of a step)
THIRD = 1.0 / 3.0
#: The rate of the static chord Newton above which its Jacobian is rebuilt
EQUILIBRIUM_RATE = 0.5
#: The update (of the length, or rad) below which the static Newton keeps its Jacobian
CHORD_FROM = 1e-5
#: Newton iterations a Jacobian is given to converge before it is refreshed
BUDGET = 4
#: The largest Newton update of a step's frames (rad) or nodes (of the length): a damped Newton beyond
MAX_UPDATE = 0.1
_IDENTITY = np.eye(3)[None]
#: Below this squared angle (rad^2) the frames' trigonometry is replaced by Taylor series, whose first term left
#: out is ~1e-18 relative there (``asin(s)/s`` to ``s^14``, ``sin(a)/a`` and ``(1 - cos a)/a^2`` to ``a^12``):
#: neighbouring elements' frames and a step's turn are well within it, and the series cost a third of the
#: trigonometric functions
SMALL_ANGLE2 = 0.01
ASIN = np.array([math.comb(2 * k, k) / (4.0**k * (2 * k + 1)) for k in range(8)])
SIN = np.array([(-1.0) ** k / math.factorial(2 * k + 1) for k in range(7)])
COS = np.array([(-1.0) ** k / math.factorial(2 * k + 2) for k in range(7)])
#: Steps between measurements of the chord Newton's rate (the others may stop after one update)
MEASURE = 8


@_fast
def _log_rel(qa, ia, qb, ib):
    """``log(a^T b)`` as a rotation vector and ``a^T b``: twelve scalars (the vector, then the matrix row by row),
    of ``a = qa[ia]``, ``b = qb[ib]`` (angles below pi; neighbours and steps turn far less). Indices and scalars,
    not views and scratch arrays: a view's reference count costs more here than the arithmetic, and a scratch
    array is memory the outputs might alias."""
    r00 = qa[ia, 0, 0] * qb[ib, 0, 0] + qa[ia, 1, 0] * qb[ib, 1, 0] + qa[ia, 2, 0] * qb[ib, 2, 0]
    r01 = qa[ia, 0, 0] * qb[ib, 0, 1] + qa[ia, 1, 0] * qb[ib, 1, 1] + qa[ia, 2, 0] * qb[ib, 2, 1]
    r02 = qa[ia, 0, 0] * qb[ib, 0, 2] + qa[ia, 1, 0] * qb[ib, 1, 2] + qa[ia, 2, 0] * qb[ib, 2, 2]
    r10 = qa[ia, 0, 1] * qb[ib, 0, 0] + qa[ia, 1, 1] * qb[ib, 1, 0] + qa[ia, 2, 1] * qb[ib, 2, 0]
    r11 = qa[ia, 0, 1] * qb[ib, 0, 1] + qa[ia, 1, 1] * qb[ib, 1, 1] + qa[ia, 2, 1] * qb[ib, 2, 1]
    r12 = qa[ia, 0, 1] * qb[ib, 0, 2] + qa[ia, 1, 1] * qb[ib, 1, 2] + qa[ia, 2, 1] * qb[ib, 2, 2]
    r20 = qa[ia, 0, 2] * qb[ib, 0, 0] + qa[ia, 1, 2] * qb[ib, 1, 0] + qa[ia, 2, 2] * qb[ib, 2, 0]
    r21 = qa[ia, 0, 2] * qb[ib, 0, 1] + qa[ia, 1, 2] * qb[ib, 1, 1] + qa[ia, 2, 2] * qb[ib, 2, 1]
    r22 = qa[ia, 0, 2] * qb[ib, 0, 2] + qa[ia, 1, 2] * qb[ib, 1, 2] + qa[ia, 2, 2] * qb[ib, 2, 2]
    w0 = 0.5 * (r21 - r12)
    w1 = 0.5 * (r02 - r20)
    w2 = 0.5 * (r10 - r01)
    s2 = w0 * w0 + w1 * w1 + w2 * w2
    c = 0.5 * (r00 + r11 + r22 - 1.0)
    if c > 0.0 and s2 < SMALL_ANGLE2:  # asin(s) / s by its series
        f = 1.0 + s2 * (
            ASIN[1] + s2 * (ASIN[2] + s2 * (ASIN[3] + s2 * (ASIN[4] + s2 * (ASIN[5] + s2 * (ASIN[6] + s2 * ASIN[7])))))
        )
    else:
        sn = np.sqrt(s2)
        f = np.arctan2(sn, c) / sn
    return f * w0, f * w1, f * w2, r00, r01, r02, r10, r11, r12, r20, r21, r22


@_fast
def _half_way(a, b, out):
    """``out = a sqrt(a^T b)``: the frame half-way (geodesically) between ``a`` and ``b`` (see :func:`node_frames`)."""
    rel = np.empty((3, 3))
    rot = np.empty((3, 3))
    for r in range(3):
        for c in range(3):
            rel[r, c] = a[0, r] * b[0, c] + a[1, r] * b[1, c] + a[2, r] * b[2, c]
    half_cos = 0.5 * np.sqrt(max(1.0 + rel[0, 0] + rel[1, 1] + rel[2, 2], 0.0))
    fa = 0.25 / half_cos
    fs = 0.25 / (1.0 + half_cos)
    for r in range(3):
        for c in range(3):
            eye = 1.0 if r == c else 0.0
            rot[r, c] = eye + fa * (rel[r, c] - rel[c, r]) + fs * (rel[r, c] + rel[c, r] - 2.0 * eye)
    for r in range(3):
        for c in range(3):
            out[r, c] = a[r, 0] * rot[0, c] + a[r, 1] * rot[1, c] + a[r, 2] * rot[2, c]


@_fast
def forces(
    x, q, lengths, voronoi, kse, kbt, g, beta, hsig, hkap, fnode, tip_moment, routing, tau, ends, f, t, sig, kap
):
    """Forces ``f`` (N, 3, world) on the nodes and torques ``t`` (n, 3, body) on the elements, and the strains
    ``sig`` (n, 3) and ``kap`` (n, 3: at nodes 0..n-1). Stress ``K (g strain + beta history)`` (Kelvin-Voigt under
    BDF2; ``g = 1, beta = 0`` without damping); ``fnode`` the external node forces, ``tip_moment`` world frame."""
    n = q.shape[0]
    for i in range(n + 1):
        for k in range(3):
            f[i, k] = fnode[i, k]
    for e in range(n):
        for k in range(3):
            t[e, k] = 0.0
    for k in range(3):
        t[n - 1, k] += q[n - 1, 0, k] * tip_moment[0] + q[n - 1, 1, k] * tip_moment[1] + q[n - 1, 2, k] * tip_moment[2]
    # one allocation for the tendons' scratch vectors (an allocation costs about what an element's forces do)
    scratch = np.empty((4, 3))
    pa, pb, fw, arm = scratch[0], scratch[1], scratch[2], scratch[3]
    disk = np.empty((3, 3))
    for e in range(n):  # in scalars (see _log_rel)
        d0 = x[e + 1, 0] - x[e, 0]
        d1 = x[e + 1, 1] - x[e, 1]
        d2 = x[e + 1, 2] - x[e, 2]
        q00 = q[e, 0, 0]
        q01 = q[e, 0, 1]
        q02 = q[e, 0, 2]
        q10 = q[e, 1, 0]
        q11 = q[e, 1, 1]
        q12 = q[e, 1, 2]
        q20 = q[e, 2, 0]
        q21 = q[e, 2, 1]
        q22 = q[e, 2, 2]
        tb0 = q00 * d0 + q10 * d1 + q20 * d2
        tb1 = q01 * d0 + q11 * d1 + q21 * d2
        tb2 = q02 * d0 + q12 * d1 + q22 * d2
        per_length = 1.0 / lengths[e]  # one division, not three (a division costs ~5 multiplications)
        s0 = tb0 * per_length
        s1 = tb1 * per_length
        s2 = tb2 * per_length - 1.0
        sig[e, 0] = s0
        sig[e, 1] = s1
        sig[e, 2] = s2
        nb0 = kse[0] * (g * s0 + beta * hsig[e, 0])
        nb1 = kse[1] * (g * s1 + beta * hsig[e, 1])
        nb2 = kse[2] * (g * s2 + beta * hsig[e, 2])
        nw0 = q00 * nb0 + q01 * nb1 + q02 * nb2
        nw1 = q10 * nb0 + q11 * nb1 + q12 * nb2
        nw2 = q20 * nb0 + q21 * nb1 + q22 * nb2
        f[e, 0] += nw0
        f[e, 1] += nw1
        f[e, 2] += nw2
        f[e + 1, 0] -= nw0
        f[e + 1, 1] -= nw1
        f[e + 1, 2] -= nw2
        t[e, 0] += tb1 * nb2 - tb2 * nb1
        t[e, 1] += tb2 * nb0 - tb0 * nb2
        t[e, 2] += tb0 * nb1 - tb1 * nb0
    for i in range(n):
        if i == 0:
            k0, k1, k2, r00, r01, r02, r10, r11, r12, r20, r21, r22 = _log_rel(_IDENTITY, 0, q, 0)
        else:
            k0, k1, k2, r00, r01, r02, r10, r11, r12, r20, r21, r22 = _log_rel(q, i - 1, q, i)
        per_length = 1.0 / voronoi[i]
        k0 *= per_length
        k1 *= per_length
        k2 *= per_length
        kap[i, 0] = k0
        kap[i, 1] = k1
        kap[i, 2] = k2
        m0 = kbt[0] * (g * k0 + beta * hkap[i, 0])
        m1 = kbt[1] * (g * k1 + beta * hkap[i, 1])
        m2 = kbt[2] * (g * k2 + beta * hkap[i, 2])
        t[i, 0] -= m0
        t[i, 1] -= m1
        t[i, 2] -= m2
        if i > 0:
            t[i - 1, 0] += r00 * m0 + r01 * m1 + r02 * m2
            t[i - 1, 1] += r10 * m0 + r11 * m1 + r12 * m2
            t[i - 1, 2] += r20 * m0 + r21 * m1 + r22 * m2
    for j in range(routing.shape[0]):
        if tau[j] == 0.0 or ends[j] < 1:
            continue
        r0, r1, r2 = routing[j, 0], routing[j, 1], routing[j, 2]
        end = ends[j]
        if end < n:
            _half_way(q[end - 1], q[end], disk)
        else:
            disk[:, :] = q[n - 1]
        for k in range(3):
            arm[k] = disk[k, 0] * r0 + disk[k, 1] * r1 + disk[k, 2] * r2
        pa[0], pa[1], pa[2] = x[0, 0] + r0, x[0, 1] + r1, x[0, 2] + r2
        for e in range(end + 1):
            for k in range(3):
                if e == end:
                    pb[k] = x[e, k] + arm[k]
                else:
                    pb[k] = 0.5 * (x[e, k] + x[e + 1, k]) + q[e, k, 0] * r0 + q[e, k, 1] * r1 + q[e, k, 2] * r2
            dx0, dx1, dx2 = pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]
            ln = np.sqrt(dx0 * dx0 + dx1 * dx1 + dx2 * dx2)
            u0, u1, u2 = tau[j] * dx0 / ln, tau[j] * dx1 / ln, tau[j] * dx2 / ln
            for side in range(2):
                p = e - 1 + side
                sgn = 1.0 if side == 0 else -1.0
                if p < 0:
                    continue
                fw[0], fw[1], fw[2] = sgn * u0, sgn * u1, sgn * u2
                if p == end:
                    for k in range(3):
                        f[p, k] += fw[k]
                    w0 = arm[1] * fw[2] - arm[2] * fw[1]
                    w1 = arm[2] * fw[0] - arm[0] * fw[2]
                    w2 = arm[0] * fw[1] - arm[1] * fw[0]
                    share = 0.5 if end < n else 1.0
                    for el in (end - 1, end):
                        if el >= n:
                            continue
                        for k in range(3):
                            t[el, k] += share * (q[el, 0, k] * w0 + q[el, 1, k] * w1 + q[el, 2, k] * w2)
                    continue
                for k in range(3):
                    f[p, k] += 0.5 * fw[k]
                    f[p + 1, k] += 0.5 * fw[k]
                b0 = q[p, 0, 0] * fw[0] + q[p, 1, 0] * fw[1] + q[p, 2, 0] * fw[2]
                b1 = q[p, 0, 1] * fw[0] + q[p, 1, 1] * fw[1] + q[p, 2, 1] * fw[2]
                b2 = q[p, 0, 2] * fw[0] + q[p, 1, 2] * fw[1] + q[p, 2, 2] * fw[2]
                t[p, 0] += r1 * b2 - r2 * b1
                t[p, 1] += r2 * b0 - r0 * b2
                t[p, 2] += r0 * b1 - r1 * b0
            for k in range(3):
                pa[k] = pb[k]


@_fast
def _exp9(th0, th1, th2):
    """Rodrigues as nine scalars (row by row): ``exp(hat(th))``, kept in registers by its callers (a scratch array
    would be memory that the outputs might alias)."""
    a2 = th0 * th0 + th1 * th1 + th2 * th2
    if a2 < SMALL_ANGLE2:  # sin(a) / a and (1 - cos(a)) / a^2 by their series: a step turns a frame little
        s = 1.0 + a2 * (SIN[1] + a2 * (SIN[2] + a2 * (SIN[3] + a2 * (SIN[4] + a2 * (SIN[5] + a2 * SIN[6])))))
        c = COS[0] + a2 * (COS[1] + a2 * (COS[2] + a2 * (COS[3] + a2 * (COS[4] + a2 * (COS[5] + a2 * COS[6])))))
    else:
        a = np.sqrt(a2)
        s = np.sin(a) / a
        c = (1.0 - np.cos(a)) / a2
    d = 1.0 - c * a2
    return (
        d + c * th0 * th0,
        c * th0 * th1 - s * th2,
        c * th0 * th2 + s * th1,
        c * th0 * th1 + s * th2,
        d + c * th1 * th1,
        c * th1 * th2 - s * th0,
        c * th0 * th2 - s * th1,
        c * th1 * th2 + s * th0,
        d + c * th2 * th2,
    )


@_fast
def _configure(z, a, xh, qh, psih, x, q):
    """The configuration of the unknowns ``z``: ``x_i = xh_i + a v_i``, ``Q_e = qh_e exp(psih_e + a W_e)``."""
    n = qh.shape[0]
    for k in range(3):
        x[0, k] = xh[0, k]
    for e in range(n):
        for k in range(3):
            x[e + 1, k] = xh[e + 1, k] + a * z[6 * e + 3 + k]
        g00 = qh[e, 0, 0]
        g01 = qh[e, 0, 1]
        g02 = qh[e, 0, 2]
        g10 = qh[e, 1, 0]
        g11 = qh[e, 1, 1]
        g12 = qh[e, 1, 2]
        g20 = qh[e, 2, 0]
        g21 = qh[e, 2, 1]
        g22 = qh[e, 2, 2]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = _exp9(
            psih[e, 0] + a * z[6 * e], psih[e, 1] + a * z[6 * e + 1], psih[e, 2] + a * z[6 * e + 2]
        )
        q[e, 0, 0] = g00 * r00 + g01 * r10 + g02 * r20
        q[e, 0, 1] = g00 * r01 + g01 * r11 + g02 * r21
        q[e, 0, 2] = g00 * r02 + g01 * r12 + g02 * r22
        q[e, 1, 0] = g10 * r00 + g11 * r10 + g12 * r20
        q[e, 1, 1] = g10 * r01 + g11 * r11 + g12 * r21
        q[e, 1, 2] = g10 * r02 + g11 * r12 + g12 * r22
        q[e, 2, 0] = g20 * r00 + g21 * r10 + g22 * r20
        q[e, 2, 1] = g20 * r01 + g21 * r11 + g22 * r21
        q[e, 2, 2] = g20 * r02 + g21 * r12 + g22 * r22


@_fast
def _residual(z, a, mf, xh, qh, psih, vh, wh, mass, inertia, model, dmp, x, q, f, t, sig, kap, res):
    """The step's residual ``M (z - z_h) + gyroscopic - a (forces)`` (``mf = 1``), or ``-(forces)`` (statics,
    ``mf = 0, a = 1``); ``model = (lengths, voronoi, kse, kbt, fnode, tip_moment, routing, tau, ends)``,
    ``dmp = (g, beta, hsig, hkap)``."""
    lengths, voronoi, kse, kbt, fnode, tip_moment, routing, tau, ends = model
    g, beta, hsig, hkap = dmp
    _configure(z, a, xh, qh, psih, x, q)
    forces(x, q, lengths, voronoi, kse, kbt, g, beta, hsig, hkap, fnode, tip_moment, routing, tau, ends, f, t, sig, kap)
    n = qh.shape[0]
    for e in range(n):
        b = 6 * e
        w0, w1, w2 = z[b], z[b + 1], z[b + 2]
        j0, j1, j2 = inertia[e, 0] * w0, inertia[e, 1] * w1, inertia[e, 2] * w2
        gyro0 = w1 * j2 - w2 * j1
        gyro1 = w2 * j0 - w0 * j2
        gyro2 = w0 * j1 - w1 * j0
        for k in range(3):
            res[b + 3 + k] = mf * mass[e + 1] * (z[b + 3 + k] - vh[e + 1, k]) - a * f[e + 1, k]
        res[b] = mf * (inertia[e, 0] * (w0 - wh[e, 0]) + a * gyro0) - a * t[e, 0]
        res[b + 1] = mf * (inertia[e, 1] * (w1 - wh[e, 1]) + a * gyro1) - a * t[e, 1]
        res[b + 2] = mf * (inertia[e, 2] * (w2 - wh[e, 2]) + a * gyro2) - a * t[e, 2]


@_jit
def _jacobian(z, h, hb, a, mf, xh, qh, psih, vh, wh, mass, inertia, model, dmp, x, q, f, t, sig, kap, jac):
    """The banded Jacobian (``jac[i, j - i + hb]``) by coloured forward differences (steps ``h`` per unknown),
    factored in place by LU without pivoting."""
    size = z.shape[0]
    r0 = np.empty(size)
    r1 = np.empty(size)
    zz = z.copy()
    _residual(z, a, mf, xh, qh, psih, vh, wh, mass, inertia, model, dmp, x, q, f, t, sig, kap, r0)
    colours = 2 * hb + 1
    central = mf == 0.0  # statics: central differences (its soft modes are ~1e-11 of its stiff ones)
    for i in range(size):
        for j in range(colours):
            jac[i, j] = 0.0
    for c in range(min(colours, size)):
        if central:
            for j in range(c, size, colours):
                zz[j] = z[j] - h[j]
            _residual(zz, a, mf, xh, qh, psih, vh, wh, mass, inertia, model, dmp, x, q, f, t, sig, kap, r0)
        for j in range(c, size, colours):
            zz[j] = z[j] + h[j]
        _residual(zz, a, mf, xh, qh, psih, vh, wh, mass, inertia, model, dmp, x, q, f, t, sig, kap, r1)
        for j in range(c, size, colours):
            zz[j] = z[j]
            span = 2.0 * h[j] if central else h[j]
            for i in range(max(0, j - hb), min(size, j + hb + 1)):
                jac[i, j - i + hb] = (r1[i] - r0[i]) / span
    _band_factor(jac, hb)


@_jit
def _band_factor(jac, hb):
    """LU (Doolittle, no pivoting: the matrix is mass + dt^2 stiffness of a stable rod) of the band ``jac``
    (``jac[i, j - i + hb]``, zero outside the matrix), in place; the pivots kept as their reciprocals (no
    division in :func:`_band_solve`)."""
    size = jac.shape[0]
    for k in range(size):
        inv = 1.0 / jac[k, hb]
        jac[k, hb] = inv
        for i in range(k + 1, min(size, k + hb + 1)):
            lik = jac[i, k - i + hb] * inv
            jac[i, k - i + hb] = lik
            if lik != 0.0:
                for j in range(k + 1, min(size, k + hb + 1)):
                    jac[i, j - i + hb] -= lik * jac[k, j - k + hb]


@_fast
def _band_solve(jac, hb, rhs, padded):
    """``padded[hb : hb + size] = (LU)^-1 rhs`` for the factored band ``jac`` (pivots as reciprocals);
    ``padded`` has ``hb`` zeros at each end (kept so), and ``jac``'s entries outside the matrix are zero, so every row
    is the same loop. The three unknowns just solved are kept in registers: through memory each would wait for
    its store to be forwarded, which was most of the solve's time."""
    size = rhs.shape[0]
    l1 = 0.0
    l2 = 0.0
    l3 = 0.0
    for i in range(size):
        acc = rhs[i]
        for p in range(hb - 3):
            acc -= jac[i, p] * padded[i + p]
        acc -= jac[i, hb - 3] * l3
        acc -= jac[i, hb - 2] * l2
        new = acc - jac[i, hb - 1] * l1
        padded[i + hb] = new
        l3 = l2
        l2 = l1
        l1 = new
    l1 = 0.0
    l2 = 0.0
    l3 = 0.0
    for i in range(size - 1, -1, -1):
        acc = padded[i + hb]
        for p in range(2 * hb, hb + 3, -1):
            acc -= jac[i, p] * padded[i + p]
        acc -= jac[i, hb + 3] * l3
        acc -= jac[i, hb + 2] * l2
        new = (acc - jac[i, hb + 1] * l1) * jac[i, hb]
        padded[i + hb] = new
        l3 = l2
        l2 = l1
        l1 = new


@_jit
def _steps(size, a, length, relative):
    """Finite-difference steps: a displacement of ``relative`` of the length (velocities) and rad (frames)."""
    h = np.empty(size)
    for i in range(size):
        h[i] = relative * (length if i % 6 >= 3 else 1.0) / a
    return h


@_fast
def _corotate(q, q_jac, turn, vec, backwards):
    """The kept Jacobian, turned with the frames: each block's node (force rows, velocity columns) rotated by its
    element's turn ``q q_jac^T`` since the Jacobian was built (``T J T^T``, whose inverse is ``T J^-1 T^T``).
    ``backwards``: compute the turns and apply ``T^T`` to a residual; else apply ``T`` to an update."""
    n = q.shape[0]
    for e in range(n):
        if backwards:
            for i in range(3):
                for j in range(3):
                    turn[e, i, j] = (
                        q[e, i, 0] * q_jac[e, j, 0] + q[e, i, 1] * q_jac[e, j, 1] + q[e, i, 2] * q_jac[e, j, 2]
                    )
        b = 6 * e + 3  # the block's velocity
        v0, v1, v2 = vec[b], vec[b + 1], vec[b + 2]
        for i in range(3):
            if backwards:
                vec[b + i] = turn[e, 0, i] * v0 + turn[e, 1, i] * v1 + turn[e, 2, i] * v2
            else:
                vec[b + i] = turn[e, i, 0] * v0 + turn[e, i, 1] * v1 + turn[e, i, 2] * v2


@_jit
def equilibrate(x, q, model, hb, tol, max_iter):
    """Newton on the static balance from ``(x, q)`` (overwritten with the equilibrium); the Jacobian kept while
    the updates shrink faster than EQUILIBRIUM_RATE (a chord Newton: a start near the equilibrium needs one
    Jacobian, the costly part), else rebuilt. Returns the iterations taken, or :data:`NO_PROGRESS`."""
    n = q.shape[0]
    size = 6 * n
    length = 0.0
    for e in range(n):
        length += model[0][e]
    z = np.zeros(size)
    padded = np.zeros(size + 2 * hb)
    dz = padded[hb : hb + size]
    res = np.empty(size)
    jac = np.empty((size, 2 * hb + 1))
    zero3 = np.zeros((n + 1, 3))
    psih = np.zeros((n, 3))
    dmp = (1.0, 0.0, zero3, zero3)
    f = np.empty((n + 1, 3))
    t = np.empty((n, 3))
    sig = np.empty((n, 3))
    kap = np.empty((n, 3))
    xx = x.copy()
    qq = q.copy()
    mass = np.zeros(n + 1)
    inertia = np.zeros((n, 3))
    h = _steps(size, 1.0, length, 1e-5)  # central differences: error ~h^2
    last = np.inf  # the last update with the kept Jacobian; inf: rebuild it
    rate = 0.0
    for it in range(max_iter):
        if last == np.inf:
            _jacobian(
                z, h, hb, 1.0, 0.0, x, q, psih, zero3, zero3, mass, inertia, model, dmp, xx, qq, f, t, sig, kap, jac
            )
        _residual(z, 1.0, 0.0, x, q, psih, zero3, zero3, mass, inertia, model, dmp, xx, qq, f, t, sig, kap, res)
        for i in range(size):
            res[i] = -res[i]
        _band_solve(jac, hb, res, padded)
        big = 0.0
        for i in range(size):
            big = max(big, abs(dz[i]) / (length if i % 6 >= 3 else 1.0))
        if not np.isfinite(big) or big > 1.0:
            return NO_PROGRESS
        if last < np.inf:  # the Jacobian kept (a chord Newton): the error left is rate / (1 - rate) of the update
            rate = big / last
            if rate >= EQUILIBRIUM_RATE:  # too slow (or diverging): this update dropped, the Jacobian rebuilt
                last = np.inf
                continue
        _configure(dz, 1.0, x, q, psih, xx, qq)
        x[:, :] = xx
        q[:, :, :] = qq
        if last == np.inf:  # a fresh Jacobian: Newton's update, quadratic
            if big < tol:
                return it + 1
        elif rate / (1.0 - rate) * big < tol:
            return it + 1
        # far from the equilibrium Newton's quadratic rate is worth a fresh Jacobian; near it the chord's is not
        last = big if big < CHORD_FROM else np.inf
    return NO_PROGRESS


@_jit
def _newton(
    z,
    z_guess,
    a,
    xh,
    qh,
    psih,
    vh,
    wh,
    mass,
    inertia,
    model,
    dmp,
    hb,
    tol,
    max_iter,
    length,
    work,
    keep,
    kept_rate,
    trust,
):
    """One implicit step's Newton from ``z_guess`` into ``z``: a chord Newton with the Jacobian kept (``keep[0]``:
    whether ``work``'s is valid for this ``a``), turned with the frames; where it converges slower than RATE or
    would not reach ``tol`` within BUDGET iterations, Newton with the Jacobian refreshed (restarting from the guess
    the first time). Updates are damped to MAX_UPDATE. ``kept_rate[0]``: the rate last measured with this
    Jacobian; with ``trust``, a first update it makes small enough is accepted (Hairer & Wanner's RADAU5 carries
    its ``faccon`` over steps so). Returns ``(converged, iterations)``."""
    jac, q_jac, turn, h, padded, res, xx, qq, f, t, sig, kap = work
    size = z.shape[0]
    dz = padded[hb : hb + size]
    a_per_length = a / length  # an update's size: displacements over the length, rotations in rad
    z[:] = z_guess
    last = np.inf
    stale = keep[0]
    refresh = not keep[0]
    since = 0
    its = 0
    for _ in range(max_iter):
        if refresh:
            if stale:  # the kept Jacobian failed: start over from the guess with a fresh one
                z[:] = z_guess
                stale = False
            for i in range(size):
                h[i] = 1e-8 * (length if i % 6 >= 3 else 1.0) / a
            _jacobian(z, h, hb, a, 1.0, xh, qh, psih, vh, wh, mass, inertia, model, dmp, xx, qq, f, t, sig, kap, jac)
            _configure(z, a, xh, qh, psih, xx, q_jac)
            keep[0] = True
            kept_rate[0] = RATE
            last = np.inf
            refresh = False
            since = 0
        its += 1
        _residual(z, a, 1.0, xh, qh, psih, vh, wh, mass, inertia, model, dmp, xx, qq, f, t, sig, kap, res)
        _corotate(qq, q_jac, turn, res, np.bool_(True))
        for i in range(size):
            res[i] = -res[i]
        _band_solve(jac, hb, res, padded)
        _corotate(qq, q_jac, turn, dz, np.bool_(False))
        big = 0.0
        for i in range(size):
            d = abs(dz[i]) * (a_per_length if i % 6 >= 3 else a)
            if not d <= big:  # NaN too
                big = d
        if not np.isfinite(big):
            return False, its
        cut = min(1.0, MAX_UPDATE / big) if big > 0.0 else 1.0  # a damped Newton: no frame turns by more
        for i in range(size):
            z[i] += cut * dz[i]
        big *= cut
        if big == 0.0:
            return True, its
        if last == np.inf and stale and trust and kept_rate[0] / (1.0 - kept_rate[0]) * big < tol:
            return True, its
        if last < np.inf:  # scipy's BDF: the error left is about rate / (1 - rate) times the last update
            rate = big / last
            kept_rate[0] = rate
            if rate < RATE and rate / (1.0 - rate) * big < tol:
                return True, its
            # refresh where the rate would not reach tol within the Jacobian's budget (scipy's BDF's rule)
            left = BUDGET - since
            refresh = rate >= RATE or (left <= 0 or rate**left / (1.0 - rate) * big > tol)
        last = big
        since += 1
    return False, its


@_jit
def _state_strains(x, q, model, sig, kap):
    """The undamped strains of a state (what the damping's history needs)."""
    n = q.shape[0]
    f = np.empty((n + 1, 3))
    t = np.empty((n, 3))
    zero = np.zeros((n + 1, 3))
    lengths, voronoi, kse, kbt, fnode, tip_moment, routing, tau, ends = model
    forces(
        x, q, lengths, voronoi, kse, kbt, 1.0, 0.0, zero, zero, fnode, tip_moment, routing, tau, ends, f, t, sig, kap
    )


@_jit
def _backward_euler(state, dt, pieces, model, mass, inertia, beta, hb, tol, max_iter, length, work, out):
    """The step from ``state = (x, q, v, w, sig, kap)`` as ``pieces`` backward-Euler steps of ``dt / pieces`` into
    ``out`` (the same layout): the fallback where BDF2's step fails. Returns ``(converged, iterations)``."""
    x, q, v, w, sig, kap = state
    n = q.shape[0]
    size = 6 * n
    ox, oq, ov, ow, osig, okap = out
    ox[:, :] = x
    oq[:, :, :] = q
    ov[:, :] = v
    ow[:, :] = w
    osig[:, :] = sig
    okap[:, :] = kap
    sub = dt / pieces
    psih = np.zeros((n, 3))
    hsig = np.empty((n, 3))
    hkap = np.empty((n, 3))
    z = np.empty(size)
    guess = np.empty(size)
    xh = np.empty((n + 1, 3))
    qh = np.empty((n, 3, 3))
    keep = np.zeros(1, dtype=np.bool_)
    rate = np.full(1, RATE)
    its = 0
    for _ in range(pieces):
        xh[:, :] = ox
        qh[:, :, :] = oq
        for e in range(n):
            for k in range(3):
                hsig[e, k] = -osig[e, k] / sub
                hkap[e, k] = -okap[e, k] / sub
                guess[6 * e + 3 + k] = ov[e + 1, k]
                guess[6 * e + k] = ow[e, k]
        dmp = (1.0 + beta / sub, beta, hsig, hkap)
        ok, more = _newton(
            z,
            guess,
            sub,
            xh,
            qh,
            psih,
            ov.copy(),
            ow.copy(),
            mass,
            inertia,
            model,
            dmp,
            hb,
            tol,
            max_iter,
            length,
            work,
            keep,
            rate,
            np.bool_(False),
        )
        its += more
        if not ok:
            return False, its
        _configure(z, sub, xh, qh, psih, ox, oq)
        for e in range(n):
            for k in range(3):
                ov[e + 1, k] = z[6 * e + 3 + k]
                ow[e, k] = z[6 * e + k]
        _state_strains(ox, oq, model, osig, okap)
    return True, its


@_jit
def run(x0, q0, model, mass, inertia, beta, hb, dt, n_steps, tol, max_iter, xs, rs, vs, ws, iterations):
    """March ``n_steps`` BDF2 steps of ``dt`` from rest at ``(x0, q0)`` (at rest before ``t = 0`` too: the
    history is the initial state). A step whose Newton fails is taken as 2, 4, .. 64 backward-Euler steps (the
    BDF2 history, the states at both ends of a step of ``dt``, stays exact). Every step's nodes and node frames
    (:func:`node_frames`) into ``xs, rs`` (m, n + 1, ..), node velocities and angular velocities (body frame; the
    mean of the neighbouring elements') into ``vs, ws`` (m, n + 1, 3), Newton iterations into ``iterations``;
    returns the number of steps that converged. Written as the steps go, so no element-wise history is kept."""
    n = q0.shape[0]
    size = 6 * n
    length = 0.0
    for e in range(n):
        length += model[0][e]
    a = 2.0 * dt / 3.0
    c0 = 1.5 / dt
    g = 1.0 + beta * c0
    sig0 = np.empty((n, 3))
    kap0 = np.empty((n, 3))
    _state_strains(x0, q0, model, sig0, kap0)
    prev = (x0.copy(), q0.copy(), np.zeros((n + 1, 3)), np.zeros((n, 3)), sig0.copy(), kap0.copy())
    now = (x0.copy(), q0.copy(), np.zeros((n + 1, 3)), np.zeros((n, 3)), sig0.copy(), kap0.copy())
    new = (x0.copy(), q0.copy(), np.zeros((n + 1, 3)), np.zeros((n, 3)), sig0.copy(), kap0.copy())
    xh = np.empty((n + 1, 3))
    vh = np.empty((n + 1, 3))
    wh = np.empty((n, 3))
    psih = np.empty((n, 3))
    hsig = np.zeros((n, 3))
    hkap = np.zeros((n, 3))
    z = np.zeros(size)
    z_guess = np.zeros(size)
    work = (
        np.empty((size, 2 * hb + 1)),
        np.empty((n, 3, 3)),
        np.empty((n, 3, 3)),
        np.empty(size),
        np.zeros(size + 2 * hb),  # the Newton update, padded for the banded solve
        np.empty(size),
        np.empty((n + 1, 3)),
        np.empty((n, 3, 3)),
        np.empty((n + 1, 3)),
        np.empty((n, 3)),
        np.empty((n, 3)),
        np.empty((n, 3)),
    )
    fallback = (
        np.empty((size, 2 * hb + 1)),
        np.empty((n, 3, 3)),
        np.empty((n, 3, 3)),
        np.empty(size),
        np.zeros(size + 2 * hb),  # the Newton update, padded for the banded solve
        np.empty(size),
        np.empty((n + 1, 3)),
        np.empty((n, 3, 3)),
        np.empty((n + 1, 3)),
        np.empty((n, 3)),
        np.empty((n, 3)),
        np.empty((n, 3)),
    )
    keep = np.zeros(1, dtype=np.bool_)
    rate = np.full(1, RATE)  # the chord Newton's last rate, carried over steps (RADAU5's faccon)
    # the last step's turn of each frame, psi (Q^{n+1} = Q^n exp(psi)): log(Q^{n T} Q^{n-1}) is -psi, no log needed
    # after a BDF2 step (after a backward-Euler fallback, and at the start, it is taken from the frames)
    turned = np.empty((n, 3))
    turn_known = False
    xs[0] = x0
    _node_frames_of(q0, rs[0])
    vs[0] = 0.0
    ws[0] = 0.0
    for step in range(n_steps):
        x_prev, q_prev, v_prev, w_prev, sig_prev, kap_prev = prev
        x_now, q_now, v_now, w_now, sig_now, kap_now = now
        for i in range(n + 1):
            for k in range(3):
                xh[i, k] = (4.0 * x_now[i, k] - x_prev[i, k]) * THIRD
                vh[i, k] = (4.0 * v_now[i, k] - v_prev[i, k]) * THIRD
        for e in range(n):
            if turn_known:
                for k in range(3):
                    psih[e, k] = turned[e, k] * THIRD
            else:
                turn = _log_rel(q_now, e, q_prev, e)
                psih[e, 0] = turn[0] / -3.0
                psih[e, 1] = turn[1] / -3.0
                psih[e, 2] = turn[2] / -3.0
            for k in range(3):
                wh[e, k] = (4.0 * w_now[e, k] - w_prev[e, k]) * THIRD
                if beta > 0.0:  # the damping's history (zero without: its divisions were ~8 % of a step)
                    hsig[e, k] = (-4.0 * sig_now[e, k] + sig_prev[e, k]) / (2.0 * dt)
                    hkap[e, k] = (-4.0 * kap_now[e, k] + kap_prev[e, k]) / (2.0 * dt)
                # the guess: the velocities extrapolated linearly
                z_guess[6 * e + 3 + k] = 2.0 * v_now[e + 1, k] - v_prev[e + 1, k]
                z_guess[6 * e + k] = 2.0 * w_now[e, k] - w_prev[e, k]
        dmp = (g, beta, hsig, hkap)
        trust = step % MEASURE != 0  # every MEASURE-th step, the rate measured again
        ok, its = _newton(
            z,
            z_guess,
            a,
            xh,
            q_now,
            psih,
            vh,
            wh,
            mass,
            inertia,
            model,
            dmp,
            hb,
            tol,
            max_iter,
            length,
            work,
            keep,
            rate,
            trust,
        )
        x_new, q_new, v_new, w_new, sig_new, kap_new = new
        if ok:
            _configure(z, a, xh, q_now, psih, x_new, q_new)
            for e in range(n):
                for k in range(3):
                    v_new[e + 1, k] = z[6 * e + 3 + k]
                    w_new[e, k] = z[6 * e + k]
            turn_known = True
            for e in range(n):
                for k in range(3):
                    turned[e, k] = psih[e, k] + a * z[6 * e + k]
                if turned[e, 0] ** 2 + turned[e, 1] ** 2 + turned[e, 2] ** 2 > 9.0:
                    turn_known = False  # near pi, log(exp(psi)) wraps: the frames' log as before
            if beta > 0.0:  # the damping's history; unused without
                _state_strains(x_new, q_new, model, sig_new, kap_new)
        else:
            rate[0] = RATE  # measured afresh on the next step
            turn_known = False
            pieces = np.int64(2)
            while not ok and pieces <= 64:
                ok, more = _backward_euler(
                    now, dt, pieces, model, mass, inertia, beta, hb, tol, max_iter, length, fallback, new
                )
                its += more
                pieces *= 2
        iterations[step] = its
        if not ok:
            return step
        prev, now, new = now, new, prev
        xs[step + 1] = now[0]
        _node_frames_of(now[1], rs[step + 1])
        vs[step + 1] = now[2]
        _node_angular_velocities_of(now[3], ws[step + 1])
    return n_steps


@_fast
def _node_frames_of(q, out):
    """One state's node frames ``out`` (n + 1, 3, 3) of its element frames ``q`` (n, 3, 3), as :func:`node_frames`
    (in scalars: see :func:`_exp9`)."""
    n = q.shape[0]
    for r in range(3):
        for c in range(3):
            out[0, r, c] = 1.0 if r == c else 0.0
            out[n, r, c] = q[n - 1, r, c]
    for i in range(1, n):
        a00 = q[i - 1, 0, 0]
        a01 = q[i - 1, 0, 1]
        a02 = q[i - 1, 0, 2]
        a10 = q[i - 1, 1, 0]
        a11 = q[i - 1, 1, 1]
        a12 = q[i - 1, 1, 2]
        a20 = q[i - 1, 2, 0]
        a21 = q[i - 1, 2, 1]
        a22 = q[i - 1, 2, 2]
        r00 = a00 * q[i, 0, 0] + a10 * q[i, 1, 0] + a20 * q[i, 2, 0]
        r01 = a00 * q[i, 0, 1] + a10 * q[i, 1, 1] + a20 * q[i, 2, 1]
        r02 = a00 * q[i, 0, 2] + a10 * q[i, 1, 2] + a20 * q[i, 2, 2]
        r10 = a01 * q[i, 0, 0] + a11 * q[i, 1, 0] + a21 * q[i, 2, 0]
        r11 = a01 * q[i, 0, 1] + a11 * q[i, 1, 1] + a21 * q[i, 2, 1]
        r12 = a01 * q[i, 0, 2] + a11 * q[i, 1, 2] + a21 * q[i, 2, 2]
        r20 = a02 * q[i, 0, 0] + a12 * q[i, 1, 0] + a22 * q[i, 2, 0]
        r21 = a02 * q[i, 0, 1] + a12 * q[i, 1, 1] + a22 * q[i, 2, 1]
        r22 = a02 * q[i, 0, 2] + a12 * q[i, 1, 2] + a22 * q[i, 2, 2]
        half_cos = 0.5 * np.sqrt(max(1.0 + r00 + r11 + r22, 0.0))
        fa = 0.25 / half_cos
        fs = 0.25 / (1.0 + half_cos)
        h00 = 1.0 + fs * (2.0 * r00 - 2.0)
        h01 = fa * (r01 - r10) + fs * (r01 + r10)
        h02 = fa * (r02 - r20) + fs * (r02 + r20)
        h10 = fa * (r10 - r01) + fs * (r10 + r01)
        h11 = 1.0 + fs * (2.0 * r11 - 2.0)
        h12 = fa * (r12 - r21) + fs * (r12 + r21)
        h20 = fa * (r20 - r02) + fs * (r20 + r02)
        h21 = fa * (r21 - r12) + fs * (r21 + r12)
        h22 = 1.0 + fs * (2.0 * r22 - 2.0)
        out[i, 0, 0] = a00 * h00 + a01 * h10 + a02 * h20
        out[i, 0, 1] = a00 * h01 + a01 * h11 + a02 * h21
        out[i, 0, 2] = a00 * h02 + a01 * h12 + a02 * h22
        out[i, 1, 0] = a10 * h00 + a11 * h10 + a12 * h20
        out[i, 1, 1] = a10 * h01 + a11 * h11 + a12 * h21
        out[i, 1, 2] = a10 * h02 + a11 * h12 + a12 * h22
        out[i, 2, 0] = a20 * h00 + a21 * h10 + a22 * h20
        out[i, 2, 1] = a20 * h01 + a21 * h11 + a22 * h21
        out[i, 2, 2] = a20 * h02 + a21 * h12 + a22 * h22


@_fast
def _node_angular_velocities_of(w, out):
    """One state's node angular velocities ``out`` (n + 1, 3) of its elements' ``w`` (n, 3): the clamp's zero, the
    mean of the neighbouring elements', the last element's at the tip."""
    n = w.shape[0]
    for k in range(3):
        out[0, k] = 0.0
        out[n, k] = w[n - 1, k]
    for i in range(1, n):
        for k in range(3):
            out[i, k] = 0.5 * (w[i - 1, k] + w[i, k])


@_jit
def node_frames(qs, out):
    """Node frames ``out`` (m, n + 1, 3, 3) of element frames ``qs`` (m, n, 3, 3): the clamp's (identity), half-way
    (geodesically) between neighbouring elements', the last element's at the tip. The half-way turn of
    ``R = Q_a^T Q_b`` (angle below pi) without trigonometry: ``sqrt(R) = I + A / (2 c) + (S - I) / (2 (1 + c))``,
    ``A, S`` the antisymmetric and symmetric parts of ``R``, ``c = cos(angle / 2) = sqrt(1 + tr R) / 2``."""
    for s in range(qs.shape[0]):
        _node_frames_of(qs[s], out[s])


@_jit
def element_frames(rs, out):
    """Element frames ``out`` (n, 3, 3) half-way (geodesically) between node frames ``rs`` (n + 1, 3, 3)."""
    for e in range(out.shape[0]):
        _half_way(rs[e], rs[e + 1], out[e])

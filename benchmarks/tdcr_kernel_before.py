"""The tdcr chain kernel as it was before its step was made faster (flexdigit at f3eec46, 2026-11-26), kept
unchanged as the reference that ``bench_tdcr.bench_dynamics`` times beside the current one, in the same run
(same algorithm: BDF2, banded chord Newton; the current kernel changed the step's arithmetic, and its settling
Newton keeps its Jacobian near the equilibrium).

Its original docstring follows.

The discretised Cosserat rod with tendons, compiled: its forces, the implicit step and its banded Newton.

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
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = [
    "BUDGET",
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

#: Returned by :func:`equilibrate` when Newton did not converge.
NO_PROGRESS = -1
RATE = 0.9
#: Newton iterations a Jacobian is given to converge before it is refreshed
BUDGET = 4
#: The largest Newton update of a step's frames (rad) or nodes (of the length): a damped Newton beyond
MAX_UPDATE = 0.1
_IDENTITY = np.eye(3)
#: Steps between measurements of the chord Newton's rate (the others may stop after one update)
MEASURE = 8


@_jit
def _exp(th0, th1, th2, out):
    """Rodrigues: ``out = exp(hat(th))``."""
    a2 = th0 * th0 + th1 * th1 + th2 * th2
    if a2 < 1e-12:
        s = 1.0 - a2 / 6.0
        c = 0.5 - a2 / 24.0
    else:
        a = np.sqrt(a2)
        s = np.sin(a) / a
        c = (1.0 - np.cos(a)) / a2
    d = 1.0 - c * a2
    out[0, 0] = d + c * th0 * th0
    out[1, 1] = d + c * th1 * th1
    out[2, 2] = d + c * th2 * th2
    out[0, 1] = c * th0 * th1 - s * th2
    out[1, 0] = c * th0 * th1 + s * th2
    out[0, 2] = c * th0 * th2 + s * th1
    out[2, 0] = c * th0 * th2 - s * th1
    out[1, 2] = c * th1 * th2 - s * th0
    out[2, 1] = c * th1 * th2 + s * th0


@_jit
def _log_rel(a, b, out, rel):
    """``out = log(a^T b)`` as a rotation vector, and ``rel = a^T b`` (angles below pi; neighbours and steps turn
    far less)."""
    for i in range(3):
        for j in range(3):
            rel[i, j] = a[0, i] * b[0, j] + a[1, i] * b[1, j] + a[2, i] * b[2, j]
    w0 = 0.5 * (rel[2, 1] - rel[1, 2])
    w1 = 0.5 * (rel[0, 2] - rel[2, 0])
    w2 = 0.5 * (rel[1, 0] - rel[0, 1])
    s = np.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    c = 0.5 * (rel[0, 0] + rel[1, 1] + rel[2, 2] - 1.0)
    f = np.arctan2(s, c) / s if s > 1e-10 else 1.0 + s * s / 6.0
    out[0] = f * w0
    out[1] = f * w1
    out[2] = f * w2


@_jit
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


@_jit
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
    # one allocation for the scratch vectors (an allocation costs about what an element's forces do)
    scratch = np.empty((7, 3))
    tb, nb, m, pa, pb, fw, arm = scratch[0], scratch[1], scratch[2], scratch[3], scratch[4], scratch[5], scratch[6]
    rel = np.empty((3, 3))
    disk = np.empty((3, 3)) if routing.shape[0] > 0 else rel
    for e in range(n):
        d0 = x[e + 1, 0] - x[e, 0]
        d1 = x[e + 1, 1] - x[e, 1]
        d2 = x[e + 1, 2] - x[e, 2]
        for k in range(3):
            tb[k] = q[e, 0, k] * d0 + q[e, 1, k] * d1 + q[e, 2, k] * d2
            sig[e, k] = tb[k] / lengths[e]
        sig[e, 2] -= 1.0
        for k in range(3):
            nb[k] = kse[k] * (g * sig[e, k] + beta * hsig[e, k])
        for k in range(3):
            nw = q[e, k, 0] * nb[0] + q[e, k, 1] * nb[1] + q[e, k, 2] * nb[2]
            f[e, k] += nw
            f[e + 1, k] -= nw
        t[e, 0] += tb[1] * nb[2] - tb[2] * nb[1]
        t[e, 1] += tb[2] * nb[0] - tb[0] * nb[2]
        t[e, 2] += tb[0] * nb[1] - tb[1] * nb[0]
    for i in range(n):
        if i == 0:
            _log_rel(_IDENTITY, q[0], kap[0], rel)
        else:
            _log_rel(q[i - 1], q[i], kap[i], rel)
        for k in range(3):
            kap[i, k] /= voronoi[i]
            m[k] = kbt[k] * (g * kap[i, k] + beta * hkap[i, k])
            t[i, k] -= m[k]
        if i > 0:
            for k in range(3):
                t[i - 1, k] += rel[k, 0] * m[0] + rel[k, 1] * m[1] + rel[k, 2] * m[2]
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


@_jit
def _configure(z, a, xh, qh, psih, x, q):
    """The configuration of the unknowns ``z``: ``x_i = xh_i + a v_i``, ``Q_e = qh_e exp(psih_e + a W_e)``."""
    n = qh.shape[0]
    rot = np.empty((3, 3))
    for k in range(3):
        x[0, k] = xh[0, k]
    for e in range(n):
        for k in range(3):
            x[e + 1, k] = xh[e + 1, k] + a * z[6 * e + 3 + k]
        _exp(psih[e, 0] + a * z[6 * e], psih[e, 1] + a * z[6 * e + 1], psih[e, 2] + a * z[6 * e + 2], rot)
        for i in range(3):
            for j in range(3):
                q[e, i, j] = qh[e, i, 0] * rot[0, j] + qh[e, i, 1] * rot[1, j] + qh[e, i, 2] * rot[2, j]


@_jit
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
    for k in range(size):  # Doolittle, in the band
        piv = jac[k, hb]
        for i in range(k + 1, min(size, k + hb + 1)):
            lik = jac[i, k - i + hb] / piv
            jac[i, k - i + hb] = lik
            if lik != 0.0:
                for j in range(k + 1, min(size, k + hb + 1)):
                    jac[i, j - i + hb] -= lik * jac[k, j - k + hb]


@_jit
def _band_solve(jac, hb, rhs, out):
    """``out = (LU)^-1 rhs`` for the factored band ``jac``."""
    size = rhs.shape[0]
    for i in range(size):
        acc = rhs[i]
        for k in range(max(0, i - hb), i):
            acc -= jac[i, k - i + hb] * out[k]
        out[i] = acc
    for i in range(size - 1, -1, -1):
        acc = out[i]
        for j in range(min(size - 1, i + hb), i, -1):  # the unknown just solved (i + 1) last: a short chain
            acc -= jac[i, j - i + hb] * out[j]
        out[i] = acc / jac[i, hb]


@_jit
def _steps(size, a, length, relative):
    """Finite-difference steps: a displacement of ``relative`` of the length (velocities) and rad (frames)."""
    h = np.empty(size)
    for i in range(size):
        h[i] = relative * (length if i % 6 >= 3 else 1.0) / a
    return h


@_jit
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
    """Newton on the static balance from ``(x, q)`` (overwritten with the equilibrium); the Jacobian fresh each
    iteration. Returns the iterations taken, or :data:`NO_PROGRESS`."""
    n = q.shape[0]
    size = 6 * n
    length = 0.0
    for e in range(n):
        length += model[0][e]
    z = np.zeros(size)
    dz = np.empty(size)
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
    for it in range(max_iter):
        _jacobian(z, h, hb, 1.0, 0.0, x, q, psih, zero3, zero3, mass, inertia, model, dmp, xx, qq, f, t, sig, kap, jac)
        _residual(z, 1.0, 0.0, x, q, psih, zero3, zero3, mass, inertia, model, dmp, xx, qq, f, t, sig, kap, res)
        for i in range(size):
            res[i] = -res[i]
        _band_solve(jac, hb, res, dz)
        big = 0.0
        for i in range(size):
            big = max(big, abs(dz[i]) / (length if i % 6 >= 3 else 1.0))
        _configure(dz, 1.0, x, q, psih, xx, qq)
        x[:, :] = xx
        q[:, :, :] = qq
        if big < tol:
            return it + 1
        if not np.isfinite(big) or big > 1.0:
            return NO_PROGRESS
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
    jac, q_jac, turn, h, dz, res, xx, qq, f, t, sig, kap = work
    size = z.shape[0]
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
        _corotate(qq, q_jac, turn, res, True)
        for i in range(size):
            res[i] = -res[i]
        _band_solve(jac, hb, res, dz)
        _corotate(qq, q_jac, turn, dz, False)
        big = 0.0
        for i in range(size):
            d = a * abs(dz[i]) / (length if i % 6 >= 3 else 1.0)
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
            False,
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
    hsig = np.empty((n, 3))
    hkap = np.empty((n, 3))
    z = np.zeros(size)
    z_guess = np.zeros(size)
    work = (
        np.empty((size, 2 * hb + 1)),
        np.empty((n, 3, 3)),
        np.empty((n, 3, 3)),
        np.empty(size),
        np.empty(size),
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
        np.empty(size),
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
    scratch = np.empty((3, 3))
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
                xh[i, k] = (4.0 * x_now[i, k] - x_prev[i, k]) / 3.0
                vh[i, k] = (4.0 * v_now[i, k] - v_prev[i, k]) / 3.0
        for e in range(n):
            if turn_known:
                for k in range(3):
                    psih[e, k] = turned[e, k] / 3.0
            else:
                _log_rel(q_now[e], q_prev[e], psih[e], scratch)
                for k in range(3):
                    psih[e, k] /= -3.0
            for k in range(3):
                wh[e, k] = (4.0 * w_now[e, k] - w_prev[e, k]) / 3.0
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
            pieces = 2
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


@_jit
def _node_frames_of(q, out):
    """One state's node frames ``out`` (n + 1, 3, 3) of its element frames ``q`` (n, 3, 3), as :func:`node_frames`."""
    rel = np.empty((3, 3))
    rot = np.empty((3, 3))
    n = q.shape[0]
    for r in range(3):
        for c in range(3):
            out[0, r, c] = 1.0 if r == c else 0.0
            out[n, r, c] = q[n - 1, r, c]
    for i in range(1, n):
        a = q[i - 1]
        b = q[i]
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
                out[i, r, c] = a[r, 0] * rot[0, c] + a[r, 1] * rot[1, c] + a[r, 2] * rot[2, c]


@_jit
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

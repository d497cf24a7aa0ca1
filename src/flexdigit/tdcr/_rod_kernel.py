"""The Cosserat rod with tendons, compiled: the ODE, its fixed-step integration and the shooting Newton.

numba, because a static solve is ~10-20 integrations of ~200 evaluations of a 6 x 6 linear system each: in numpy
every evaluation would cost ~50 us of dispatch for ~0.2 us of arithmetic. Plain loops on small arrays, the
scratch arrays allocated once an integration (:func:`work`): a small allocation costs about what an evaluation
does.

The state along the backbone is ``y = (p, R, v, u, q, w)`` (24 numbers: position, the rotation row by row, the
strains, and for dynamics the body-frame linear and angular velocities; Rucker & Webster 2011, IEEE T-RO 27(6),
"Statics and dynamics of continuum robots with general tendon routing and external loading"): ``p' = R v``,
``R' = R u^``, and ``(v', u')`` solve their eq. (13)

    [Kse + A   G      ] [v']   [d]
    [B         Kbt + H] [u'] = [c]

for tendons routed straight (``r_i' = 0``). Where tendons terminate, the backbone's strains jump so that the
whole cross-section's wrench (backbone + tendons, ``Phi`` below) stays continuous (a disk carries no external
load); the jump is solved by Newton on ``Phi``, whose Jacobian is the same matrix.

Dynamics (Till, Aloi & Rucker 2019, IJRR 38(6), "Real-time dynamics of soft and continuum robots based on
Cosserat rod models"): time derivatives by an implicit BDF formula ``x_t = c0 x + x_h`` (``x_h`` from the
previous steps, per node), which turns each time step into a boundary-value problem in ``s`` of the same form:
the inertia ``rho A (w x q + q_t)`` and ``w x rho J w + rho J w_t`` enter as distributed loads, and the
compatibility equations ``q' = v_t - u x q + w x v``, ``w' = u_t - u x w`` carry the velocities. Statics is
``c0 = 0`` with no history, where ``q = w = 0`` throughout.
"""

from __future__ import annotations

import numba
import numpy as np

from flexdigit import _numba_cache

_numba_cache.install()  # the machine code kept per user by source text (flexdigit/_numba_cache.py)

__all__ = ["HIST", "RECORD", "STATE", "integrate", "shoot", "simulate", "tip_residual", "work"]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")

STATE = 24
HIST = 12  # v_h, u_h, q_h, w_h
#: A node's record: the state after any jump there, then (v, u, q, w) before it (what the interval ending there
#: saw: the BDF history of that interval's end)
RECORD = STATE + HIST


@_jit
def _solve6(m, rhs, out):
    """Gaussian elimination with partial pivoting of a 6 x 6 system (m and rhs are overwritten)."""
    n = 6
    for k in range(n):
        piv = k
        big = abs(m[k, k])
        for i in range(k + 1, n):
            if abs(m[i, k]) > big:
                big = abs(m[i, k])
                piv = i
        if piv != k:
            for j in range(n):
                tmp = m[k, j]
                m[k, j] = m[piv, j]
                m[piv, j] = tmp
            tmp = rhs[k]
            rhs[k] = rhs[piv]
            rhs[piv] = tmp
        for i in range(k + 1, n):
            f = m[i, k] / m[k, k]
            if f != 0.0:
                for j in range(k, n):
                    m[i, j] -= f * m[k, j]
                rhs[i] -= f * rhs[k]
    for i in range(n - 1, -1, -1):
        acc = rhs[i]
        for j in range(i + 1, n):
            acc -= m[i, j] * out[j]
        out[i] = acc / m[i, i]


@_jit
def work():
    """Scratch arrays for the kernels: ``(mat (6, 6), m3 (10, 7), vec (10, 6))``."""
    return np.empty((6, 6)), np.empty((10, 7)), np.empty((10, 6))


@_jit
def _matrix_and_wrench(v, u, routing, tau, active, kse, kbt, dmp, mat, phi, ab, m3):
    """The Jacobian ``mat`` of ``Phi(v, u)``, ``Phi`` itself (the cross-section's body-frame force and moment,
    backbone + active tendons) and the sums ``ab = (a, b)`` of Rucker & Webster's eq. (13); ``m3`` scratch.

    ``dmp = (g, beta v_h, beta u_h)``: Kelvin-Voigt damping ``beta K (v_t, u_t)`` under BDF, ``g = 1 + beta c0``;
    the backbone's force is ``Kse (g v - e3 + beta v_h)``, its moment ``Kbt (g u + beta u_h)``. ``(1, 0...)``: none.
    """
    for i in range(6):
        phi[i] = 0.0
        ab[i] = 0.0
        for j in range(6):
            mat[i, j] = 0.0
    g = dmp[0]
    for i in range(3):
        mat[i, i] = g * kse[i]
        mat[3 + i, 3 + i] = g * kbt[i]
        phi[i] = kse[i] * (g * v[i] + dmp[1 + i])
        phi[3 + i] = kbt[i] * (g * u[i] + dmp[4 + i])
    phi[2] -= kse[2]
    for k in range(routing.shape[0]):
        if not active[k] or tau[k] == 0.0:
            continue
        r0, r1, r2 = routing[k, 0], routing[k, 1], routing[k, 2]
        # pb = u x r + v: the tendon's tangent in the body frame
        p0 = u[1] * r2 - u[2] * r1 + v[0]
        p1 = u[2] * r0 - u[0] * r2 + v[1]
        p2 = u[0] * r1 - u[1] * r0 + v[2]
        n2 = p0 * p0 + p1 * p1 + p2 * p2
        nrm = np.sqrt(n2)
        t = tau[k]
        # Phi: + tau pb/|pb| (force), + r x tau pb/|pb| (moment)
        phi[0] += t * p0 / nrm
        phi[1] += t * p1 / nrm
        phi[2] += t * p2 / nrm
        phi[3] += t * (r1 * p2 - r2 * p1) / nrm
        phi[4] += t * (r2 * p0 - r0 * p2) / nrm
        phi[5] += t * (r0 * p1 - r1 * p0) / nrm
        # A = -(tau/|pb|^3) pb^ pb^ with pb^ pb^ = pb pb^T - |pb|^2 I
        c = -t / (n2 * nrm)
        m3[0, 0] = c * (p0 * p0 - n2)
        m3[0, 1] = c * p0 * p1
        m3[0, 2] = c * p0 * p2
        m3[1, 0] = m3[0, 1]
        m3[1, 1] = c * (p1 * p1 - n2)
        m3[1, 2] = c * p1 * p2
        m3[2, 0] = m3[0, 2]
        m3[2, 1] = m3[1, 2]
        m3[2, 2] = c * (p2 * p2 - n2)
        m3[6, 0], m3[6, 1], m3[6, 2] = 0.0, -r2, r1  # r^
        m3[7, 0], m3[7, 1], m3[7, 2] = r2, 0.0, -r0
        m3[8, 0], m3[8, 1], m3[8, 2] = -r1, r0, 0.0
        for i in range(3):  # B = r^ A
            for j in range(3):
                m3[3 + i, j] = m3[6 + i, 0] * m3[0, j] + m3[6 + i, 1] * m3[1, j] + m3[6 + i, 2] * m3[2, j]
        for i in range(3):
            for j in range(3):
                mat[i, j] += m3[i, j]
                mat[3 + i, j] += m3[3 + i, j]
                # G = -A r^, H = -B r^
                mat[i, 3 + j] -= m3[i, 0] * m3[6, j] + m3[i, 1] * m3[7, j] + m3[i, 2] * m3[8, j]
                mat[3 + i, 3 + j] -= m3[3 + i, 0] * m3[6, j] + m3[3 + i, 1] * m3[7, j] + m3[3 + i, 2] * m3[8, j]
        # a = A (u x pb), b = r x a
        w0 = u[1] * p2 - u[2] * p1
        w1 = u[2] * p0 - u[0] * p2
        w2 = u[0] * p1 - u[1] * p0
        a0 = m3[0, 0] * w0 + m3[0, 1] * w1 + m3[0, 2] * w2
        a1 = m3[1, 0] * w0 + m3[1, 1] * w1 + m3[1, 2] * w2
        a2 = m3[2, 0] * w0 + m3[2, 1] * w1 + m3[2, 2] * w2
        ab[0] += a0
        ab[1] += a1
        ab[2] += a2
        ab[3] += r1 * a2 - r2 * a1
        ab[4] += r2 * a0 - r0 * a2
        ab[5] += r0 * a1 - r1 * a0


@_jit
def _rhs(y, routing, tau, active, kse, kbt, fdist, ldist, dyn, hist, dhist, dy, mat, m3, vec):
    """``dy/ds`` of the state ``y`` (see the module docstring); ``fdist``, ``ldist`` per length, global frame;
    ``dyn = (c0, rho A, rho J1, rho J2, rho J3, beta)``, ``hist`` the BDF history ``(v_h, u_h, q_h, w_h)`` at this
    s, ``dhist`` the derivative along s of its ``(v_h, u_h)``."""
    v = y[12:15]
    u = y[15:18]
    q = y[18:21]
    w = y[21:24]
    phi = vec[0]
    ab = vec[1]
    rhs = vec[2]
    tt = vec[9]  # v_t, u_t
    dmp = m3[9]
    c0 = dyn[0]
    rho_a = dyn[1]
    beta = dyn[5]
    dmp[0] = 1.0 + beta * c0
    for i in range(6):
        dmp[1 + i] = beta * hist[i]
    _matrix_and_wrench(v, u, routing, tau, active, kse, kbt, dmp, mat, phi, ab, m3)
    for i in range(3):
        tt[i] = c0 * v[i] + hist[i]
        tt[3 + i] = c0 * u[i] + hist[3 + i]
    # the backbone's (damped) force and moment: Phi less the tendons' share
    n0 = kse[0] * (dmp[0] * v[0] + dmp[1])
    n1 = kse[1] * (dmp[0] * v[1] + dmp[2])
    n2 = kse[2] * (dmp[0] * v[2] + dmp[3] - 1.0)
    m0 = kbt[0] * (dmp[0] * u[0] + dmp[4])
    m1 = kbt[1] * (dmp[0] * u[1] + dmp[5])
    m2 = kbt[2] * (dmp[0] * u[2] + dmp[6])
    # body-frame distributed loads: external (R^T f, R^T l; R row-major in y[3:12]) less the inertia
    jw0 = dyn[2] * w[0]
    jw1 = dyn[3] * w[1]
    jw2 = dyn[4] * w[2]
    fi0 = rho_a * (w[1] * q[2] - w[2] * q[1] + c0 * q[0] + hist[6])
    fi1 = rho_a * (w[2] * q[0] - w[0] * q[2] + c0 * q[1] + hist[7])
    fi2 = rho_a * (w[0] * q[1] - w[1] * q[0] + c0 * q[2] + hist[8])
    li0 = w[1] * jw2 - w[2] * jw1 + dyn[2] * (c0 * w[0] + hist[9])
    li1 = w[2] * jw0 - w[0] * jw2 + dyn[3] * (c0 * w[1] + hist[10])
    li2 = w[0] * jw1 - w[1] * jw0 + dyn[4] * (c0 * w[2] + hist[11])
    # d = -u x n - f_body - a ; c = -u x m - v x n - l_body - b
    for i in range(3):  # (and the damping's beta K (v_h', u_h'))
        rhs[i] = -(y[3 + i] * fdist[0] + y[6 + i] * fdist[1] + y[9 + i] * fdist[2]) - ab[i]
        rhs[3 + i] = -(y[3 + i] * ldist[0] + y[6 + i] * ldist[1] + y[9 + i] * ldist[2]) - ab[3 + i]
        rhs[i] -= beta * kse[i] * dhist[i]
        rhs[3 + i] -= beta * kbt[i] * dhist[3 + i]
    rhs[0] += fi0 - (u[1] * n2 - u[2] * n1)
    rhs[1] += fi1 - (u[2] * n0 - u[0] * n2)
    rhs[2] += fi2 - (u[0] * n1 - u[1] * n0)
    rhs[3] += li0 - (u[1] * m2 - u[2] * m1) - (v[1] * n2 - v[2] * n1)
    rhs[4] += li1 - (u[2] * m0 - u[0] * m2) - (v[2] * n0 - v[0] * n2)
    rhs[5] += li2 - (u[0] * m1 - u[1] * m0) - (v[0] * n1 - v[1] * n0)
    _solve6(mat, rhs, dy[12:18])
    for i in range(3):  # p' = R v
        dy[i] = y[3 + 3 * i] * v[0] + y[4 + 3 * i] * v[1] + y[5 + 3 * i] * v[2]
    for i in range(3):  # R' = R u^
        r0, r1, r2 = y[3 + 3 * i], y[4 + 3 * i], y[5 + 3 * i]
        dy[3 + 3 * i] = r1 * u[2] - r2 * u[1]
        dy[4 + 3 * i] = r2 * u[0] - r0 * u[2]
        dy[5 + 3 * i] = r0 * u[1] - r1 * u[0]
    # q' = v_t - u x q + w x v ; w' = u_t - u x w  (p_st = p_ts, R_st = R_ts)
    dy[18] = tt[0] - (u[1] * q[2] - u[2] * q[1]) + (w[1] * v[2] - w[2] * v[1])
    dy[19] = tt[1] - (u[2] * q[0] - u[0] * q[2]) + (w[2] * v[0] - w[0] * v[2])
    dy[20] = tt[2] - (u[0] * q[1] - u[1] * q[0]) + (w[0] * v[1] - w[1] * v[0])
    dy[21] = tt[3] - (u[1] * w[2] - u[2] * w[1])
    dy[22] = tt[4] - (u[2] * w[0] - u[0] * w[2])
    dy[23] = tt[5] - (u[0] * w[1] - u[1] * w[0])


@_jit
def _strains_for(y, target, routing, tau, active, kse, kbt, dmp, mat, m3, vec):
    """Set the strains ``y[12:18]`` so that ``Phi(v, u) = target`` by Newton from their present value."""
    phi = vec[3]
    ab = vec[4]
    step = vec[5]
    for _ in range(30):
        _matrix_and_wrench(y[12:15], y[15:18], routing, tau, active, kse, kbt, dmp, mat, phi, ab, m3)
        for i in range(6):
            phi[i] = target[i] - phi[i]
        _solve6(mat, phi, step)
        big = 0.0
        size = 0.0
        for i in range(6):
            y[12 + i] += step[i]
            big = max(big, abs(step[i]))
            size = max(size, abs(y[12 + i]))
        if big <= 1e-14 * (1.0 + size):  # strains to round-off: v ~ 1, u in 1/m
            return True
    return False


@_jit
def _transition(y, routing, tau, before, after, kse, kbt, dmp_before, dmp_after, mat, m3, vec):
    """Strains after tendons terminate: ``Phi_after(v+, u+) = Phi_before(v-, u-)``. True if it converged."""
    target = vec[6]
    _matrix_and_wrench(y[12:15], y[15:18], routing, tau, before, kse, kbt, dmp_before, mat, target, vec[7], m3)
    return _strains_for(y, target, routing, tau, after, kse, kbt, dmp_after, mat, m3, vec)


@_jit
def _history_at(hist, nodes, k, s, value, slope):
    """The BDF history and its s-derivative at ``s`` in the interval from node ``k - 1`` to ``k``.

    Cubic through the four nearest nodes where no strain jumps among them (the history is ``c0``-sized, ~1/dt
    times the state: a linear interpolant's O(h^2) error, multiplied by it, biases the inertia and damping by
    several per cent), linear (the interval's own ends) where one does."""
    n = nodes.shape[0]
    first = min(max(k - 2, 0), n - 4)
    smooth = n >= 4
    if smooth:
        for j in range(first, first + 4):
            for i in range(HIST):
                if hist[j, i] != hist[j, HIST + i]:
                    smooth = False
    if not smooth:
        a = (s - nodes[k - 1]) / (nodes[k] - nodes[k - 1])
        for i in range(HIST):
            value[i] = (1.0 - a) * hist[k - 1, i] + a * hist[k, HIST + i]
            slope[i] = (hist[k, HIST + i] - hist[k - 1, i]) / (nodes[k] - nodes[k - 1])
        return
    for i in range(HIST):
        value[i] = 0.0
        slope[i] = 0.0
    for j in range(first, first + 4):
        w = 1.0  # Lagrange basis l_j(s) and its derivative
        dw = 0.0
        for m in range(first, first + 4):
            if m == j:
                continue
            f = (s - nodes[m]) / (nodes[j] - nodes[m])
            dw = dw * f + w / (nodes[j] - nodes[m])
            w *= f
        for i in range(HIST):
            value[i] += w * hist[j, i]
            slope[i] += dw * hist[j, i]


@_jit
def integrate(y0, nodes, substeps, routing, tau, end_node, kse, kbt, fdist, ldist, dyn, hist, out):
    """RK4 from node 0 to the last, ``substeps`` steps a node interval; each node's record (:data:`RECORD`) into
    ``out``. ``hist`` (nodes, 24): the BDF history at the nodes, after (:12) and before (12:) any jump there,
    interpolated between them by :func:`_history_at`. Returns False if a transition did not converge or the state
    went non-finite."""
    mat, m3, vec = work()
    y = y0.copy()
    n_t = routing.shape[0]
    active = np.empty(n_t, dtype=np.bool_)
    after = np.empty(n_t, dtype=np.bool_)
    ks = np.empty((5, STATE))
    k1, k2, k3, k4, tmp = ks[0], ks[1], ks[2], ks[3], ks[4]
    hs = np.empty((6, HIST))
    h0, hm, h1, d0, dm, d1 = hs[0], hs[1], hs[2], hs[3], hs[4], hs[5]
    dmps = np.empty((2, 7))
    d_before, d_after = dmps[0], dmps[1]
    beta = dyn[5]
    dynamic = dyn[0] != 0.0
    if not dynamic:
        for i in range(HIST):
            h0[i] = hm[i] = h1[i] = d0[i] = dm[i] = d1[i] = 0.0
    out[0, :STATE] = y
    out[0, STATE:] = y[12:]
    ok = True
    for k in range(1, nodes.shape[0]):
        for i in range(n_t):
            active[i] = end_node[i] >= k
            after[i] = end_node[i] >= k + 1
        h = (nodes[k] - nodes[k - 1]) / substeps
        for j in range(substeps):
            s0 = nodes[k - 1] + j * h
            if dynamic:
                _history_at(hist, nodes, k, s0, h0, d0)
                _history_at(hist, nodes, k, s0 + 0.5 * h, hm, dm)
                _history_at(hist, nodes, k, s0 + h, h1, d1)
            _rhs(y, routing, tau, active, kse, kbt, fdist, ldist, dyn, h0, d0, k1, mat, m3, vec)
            for i in range(STATE):
                tmp[i] = y[i] + 0.5 * h * k1[i]
            _rhs(tmp, routing, tau, active, kse, kbt, fdist, ldist, dyn, hm, dm, k2, mat, m3, vec)
            for i in range(STATE):
                tmp[i] = y[i] + 0.5 * h * k2[i]
            _rhs(tmp, routing, tau, active, kse, kbt, fdist, ldist, dyn, hm, dm, k3, mat, m3, vec)
            for i in range(STATE):
                tmp[i] = y[i] + h * k3[i]
            _rhs(tmp, routing, tau, active, kse, kbt, fdist, ldist, dyn, h1, d1, k4, mat, m3, vec)
            for i in range(STATE):
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        out[k, STATE:] = y[12:]
        if k < nodes.shape[0] - 1:
            changed = False
            for i in range(n_t):
                if active[i] != after[i] and tau[i] != 0.0:
                    changed = True
            d_before[0] = 1.0 + beta * dyn[0]
            d_after[0] = d_before[0]
            for i in range(6):
                d_before[1 + i] = beta * hist[k, HIST + i]
                d_after[1 + i] = beta * hist[k, i]
            if changed and not _transition(y, routing, tau, active, after, kse, kbt, d_before, d_after, mat, m3, vec):
                ok = False
        out[k, :STATE] = y
    for i in range(STATE):
        if not np.isfinite(y[i]):
            ok = False
    return ok


@_jit
def tip_residual(y, routing, tau, end_node, last, kse, kbt, dmp, tip_force, tip_moment, scale_f, scale_m, res):
    """Body-frame wrench balance at the tip: ``Phi(v, u) - R^T (F, L)``, forces over ``scale_f``, moments over
    ``scale_m``."""
    mat, m3, vec = work()
    n_t = routing.shape[0]
    active = np.empty(n_t, dtype=np.bool_)
    for i in range(n_t):
        active[i] = end_node[i] >= last
    phi = vec[0]
    _matrix_and_wrench(y[12:15], y[15:18], routing, tau, active, kse, kbt, dmp, mat, phi, vec[1], m3)
    for i in range(3):
        rf = y[3 + i] * tip_force[0] + y[6 + i] * tip_force[1] + y[9 + i] * tip_force[2]
        rl = y[3 + i] * tip_moment[0] + y[6 + i] * tip_moment[1] + y[9 + i] * tip_moment[2]
        res[i] = (phi[i] - rf) / scale_f
        res[3 + i] = (phi[3 + i] - rl) / scale_m


@_jit
def _evaluate(
    x, nodes, substeps, routing, tau, end_node, kse, kbt, fdist, ldist, dyn, hist, tip_force, tip_moment, buf, res
):
    """Integrate from the scaled base wrench ``x``; the scaled tip residual into ``res``. Returns (ok, 2-norm)."""
    mat, m3, vec = work()
    length = nodes[-1] - nodes[0]
    last = nodes.shape[0] - 1
    scale_m = kbt[0] / length
    scale_f = kbt[0] / (length * length)
    y0 = np.zeros(STATE)
    y0[3] = 1.0
    y0[7] = 1.0
    y0[11] = 1.0
    y0[14] = 1.0
    target = vec[8]
    active = np.empty(routing.shape[0], dtype=np.bool_)
    for i in range(routing.shape[0]):
        active[i] = end_node[i] >= 1
    for i in range(3):
        target[i] = x[i] * scale_f
        target[3 + i] = x[3 + i] * scale_m
    dmp = np.empty(7)  # the damping at the clamp, then at the tip
    dmp[0] = 1.0 + dyn[5] * dyn[0]
    for i in range(6):
        dmp[1 + i] = dyn[5] * hist[0, i]
    ok = _strains_for(y0, target, routing, tau, active, kse, kbt, dmp, mat, m3, vec)
    ok = integrate(y0, nodes, substeps, routing, tau, end_node, kse, kbt, fdist, ldist, dyn, hist, buf) and ok
    for i in range(6):
        dmp[1 + i] = dyn[5] * hist[last, HIST + i]
    tip_residual(buf[last], routing, tau, end_node, last, kse, kbt, dmp, tip_force, tip_moment, scale_f, scale_m, res)
    err = 0.0
    for i in range(6):
        if not np.isfinite(res[i]):
            return False, np.inf
        err += res[i] * res[i]
    return ok, np.sqrt(err)


@_jit
def shoot(
    x0,
    nodes,
    substeps,
    routing,
    tau,
    end_node,
    kse,
    kbt,
    fdist,
    ldist,
    dyn,
    hist,
    tip_force,
    tip_moment,
    tol,
    max_iter,
    out,
    jac,
    have_jac,
):
    """Newton on the base wrench ``x = (n(0) L^2/EI, m(0) L/EI)`` (world = body frame at the clamp; backbone and
    tendons together) until the scaled tip residual's 2-norm <= ``tol``.

    The Jacobian by forward differences (6 extra integrations) at the start, then Broyden's rank-one updates
    while they keep the residual falling (a fresh difference Jacobian when they do not); the step halved while
    the residual does not drop. Returns ``(x, converged, iterations, residual)``; the backbone of the last
    iterate is in ``out``.
    """
    x = x0.copy()
    vecs = np.empty((8, 6))
    res, res_t, rhs, step, trial, dres = vecs[0], vecs[1], vecs[2], vecs[3], vecs[4], vecs[5]
    work_m = np.empty((6, 6))
    scratch = np.empty_like(out)
    args = (nodes, substeps, routing, tau, end_node, kse, kbt, fdist, ldist, dyn, hist, tip_force, tip_moment)
    ok, err = _evaluate(x, *args, out, res)
    iterations = 0
    # have_jac: jac (in and out) holds a Jacobian (differences, maybe Broyden-updated since): a time step starts
    # from the last step's
    from_fd = False  # ... taken by differences at the present iterate
    while (err > tol or not ok) and iterations < max_iter:
        iterations += 1
        if not have_jac:
            for j in range(6):
                h = 1e-7 * (1.0 + abs(x[j]))
                for i in range(6):
                    trial[i] = x[i]
                trial[j] += h
                _evaluate(trial, *args, scratch, res_t)
                for i in range(6):
                    jac[i, j] = (res_t[i] - res[i]) / h
            have_jac = True
            from_fd = True
        for i in range(6):
            rhs[i] = -res[i]
            for j in range(6):
                work_m[i, j] = jac[i, j]
        _solve6(work_m, rhs, step)
        lam = 1.0
        accepted = False
        ok_t, err_t = ok, err
        while lam > (1e-3 if from_fd else 0.2):  # a Broyden Jacobian that needs short steps has gone stale
            for i in range(6):
                trial[i] = x[i] + lam * step[i]
            ok_t, err_t = _evaluate(trial, *args, scratch, res_t)
            if ok_t and err_t < err:
                accepted = True
                break
            lam *= 0.5
        if not accepted:
            if from_fd:
                break
            have_jac = False  # retry from here with a difference Jacobian
            continue
        # Broyden's update J += (dres - J dx) dx^T / (dx^T dx), dx = lam step
        dxx = 0.0
        for i in range(6):
            dxx += (lam * step[i]) ** 2
        for i in range(6):
            acc = res_t[i] - res[i]
            for j in range(6):
                acc -= jac[i, j] * lam * step[j]
            dres[i] = acc / dxx
        for i in range(6):
            for j in range(6):
                jac[i, j] += dres[i] * lam * step[j]
        from_fd = False
        for i in range(6):
            x[i] = trial[i]
            res[i] = res_t[i]
        ok, err = ok_t, err_t
        out[:, :] = scratch
    return x, (err <= tol and ok), iterations, err, have_jac


@_jit
def simulate(
    x0,
    y_init,
    nodes,
    substeps,
    routing,
    tau,
    end_node,
    kse,
    kbt,
    fdist,
    ldist,
    inertia,
    beta,
    tip_force,
    tip_moment,
    dt,
    n_steps,
    tol,
    max_iter,
    states,
    iterations,
):
    """March ``n_steps`` implicit steps of ``dt`` from the rod at rest in ``y_init`` (nodes, :data:`RECORD`); BDF1
    for the first step, BDF2 after. ``inertia = (rho A, rho J1, rho J2, rho J3)``; ``beta`` (s) the Kelvin-Voigt
    damping ``beta K`` (stiffness-proportional). Every step's records into
    ``states`` (steps + 1, nodes, RECORD), its Newton iterations into ``iterations``. Returns the number of steps
    that converged."""
    n_nodes = nodes.shape[0]
    prev1 = y_init.copy()
    prev2 = y_init.copy()
    hist = np.zeros((n_nodes, 2 * HIST))
    dyn = np.empty(6)
    dyn[1:5] = inertia
    dyn[5] = beta
    jac = np.empty((6, 6))
    have_jac = False
    buf = np.empty((n_nodes, RECORD))
    states[0] = y_init
    x = x0.copy()
    x_old = x0.copy()
    guess = x0.copy()
    mat, m3, vec = work()
    phi, ab = vec[0], vec[1]
    active0 = np.empty(routing.shape[0], dtype=np.bool_)
    for i in range(routing.shape[0]):
        active0[i] = end_node[i] >= 1
    for step in range(n_steps):
        # x_t = c0 x + x_h: BDF1 first (x_h = -x1/dt), BDF2 after (x_h = (-4 x1 + x2) / (2 dt)); the history of
        # the velocities and strains after (12:24) and before (24:36) each node's jump
        dyn[0] = 1.0 / dt if step == 0 else 1.5 / dt
        for k in range(n_nodes):
            for i in range(2 * HIST):
                if step == 0:
                    hist[k, i] = -prev1[k, 12 + i] / dt
                else:
                    hist[k, i] = (-4.0 * prev1[k, 12 + i] + prev2[k, 12 + i]) / (2.0 * dt)
        for i in range(6):  # after: a linear extrapolation of the last two steps' clamp wrench
            if step > 1:
                guess[i] = 2.0 * x[i] - x_old[i]
            elif step == 1:
                guess[i] = x[i]
            x_old[i] = x[i]
        x, converged, its, err, have_jac = shoot(
            guess,
            nodes,
            substeps,
            routing,
            tau,
            end_node,
            kse,
            kbt,
            fdist,
            ldist,
            dyn,
            hist,
            tip_force,
            tip_moment,
            tol,
            max_iter,
            buf,
            jac,
            have_jac,
        )
        if not converged and step == 0:
            # the loads change at t = 0, the strains cannot: retry from the clamp wrench of the rest state's base
            # strains under the new tensions (the clamp wrench jumps when tendons are released or pulled)
            no_damping = np.zeros(7)
            no_damping[0] = 1.0  # at rest: the damping carries nothing
            _matrix_and_wrench(
                y_init[0, 12:15], y_init[0, 15:18], routing, tau, active0, kse, kbt, no_damping, mat, phi, ab, m3
            )
            length = nodes[-1] - nodes[0]
            for i in range(3):
                guess[i] = phi[i] / (kbt[0] / (length * length))
                guess[3 + i] = phi[3 + i] / (kbt[0] / length)
            x, converged, more, err, have_jac = shoot(
                guess,
                nodes,
                substeps,
                routing,
                tau,
                end_node,
                kse,
                kbt,
                fdist,
                ldist,
                dyn,
                hist,
                tip_force,
                tip_moment,
                tol,
                max_iter,
                buf,
                jac,
                False,
            )
            its += more
        iterations[step] = its
        if not converged:
            return step
        states[step + 1] = buf
        prev2[:, :] = prev1
        prev1[:, :] = buf
    return n_steps

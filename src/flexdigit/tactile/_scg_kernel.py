"""NETLAB's MLP trained by scaled conjugate gradients, compiled: one network's training as plain loops.

:class:`flexdigit.tactile.netlab.MLP` trains by :func:`~flexdigit.tactile.netlab.scg` on
:func:`~flexdigit.tactile.netlab.mlp_forward` / :func:`~flexdigit.tactile.netlab.mlp_grad`: ~2 forward passes and
~30 small numpy calls per iteration, 2,500 iterations per network, 68 networks in a report. Most of that time is
``np.tanh`` (glibc's scalar ``tanh``, ~19 ns an element here) and the dispatch of the small calls. Here the same
algorithm (the same branches of ``scg.m``, the same epochs and early stopping) runs in one compiled call per
network: the hidden layer, the output, the error and the back-propagation in one pass over the samples, and a
``tanh`` written as arithmetic the compiler vectorises (:func:`_tanh`, within 2 ulp of ``np.tanh``; tested).

The numbers are those of the numpy version to rounding, step by step (``tests/tactile/test_scg_kernel.py`` checks
the error, the gradient and short trainings against it); over a whole training, as with any change of rounding
(a BLAS, a CPU), SCG's accept/reject branches can part after many iterations, so trained networks agree in their
scores, not to the bit.
"""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass

import llvmlite.ir
import numba
import numpy as np
from numba.core import types
from numba.extending import intrinsic

from flexdigit import _numba_cache

_numba_cache.install()  # the machine code kept per user by source text (flexdigit/_numba_cache.py)

__all__ = ["tanh", "train"]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")
# Multiply-adds fused (one rounding instead of two): never reordered, so the forward pass stays as written.
_fused = numba.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"})
_inline = numba.njit(inline="always", error_model="numpy", fastmath={"contract"})  # inlined: loops vectorise
# The back-propagation's sums over the samples may be reassociated (summed in vector lanes): as BLAS sums them.
# Never the forward pass: reassociation would undo the exact split of ln 2 in _exp_neg.
_reduce = numba.njit(cache=True, nogil=True, error_model="numpy", fastmath={"reassoc", "contract"})

# netlab.SCG_SIGMA0, _BETA_MIN, _BETA_MAX (NETLAB scg.m), written here rather than imported: numba freezes a global
# into the compiled code and its cache is keyed on this file, so a value imported from netlab.py could go stale
_SIGMA0 = 1.0e-4
_BETA_MIN, _BETA_MAX = 1.0e-15, 1.0e100
_EPS = np.finfo(float).eps

# exp(-r) - 1 for 0 <= r by r = k ln 2 + f: Cody-Waite split of ln 2 (fdlibm's), Taylor to degree 13 on |f| <= ln 2/2
_LN2_HI, _LN2_LO = 6.93147180369123816490e-01, 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00
_TANH_ONE = 19.1  # beyond, tanh(x) rounds to +-1 in double precision (and 2 * 19.1 / ln 2 < 64)


@intrinsic
def _as_int(typingctx, x):
    """The bits of a float64 as an int64 (an LLVM bitcast: numba has no scalar view, and this one vectorises)."""

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], llvmlite.ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def _as_float(typingctx, x):
    """The bits of an int64 as a float64 (see :func:`_as_int`)."""

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], llvmlite.ir.DoubleType())

    return types.float64(types.int64), codegen


@_inline
def _expm1_neg(r):
    """``exp(-r) - 1`` for ``0 <= r <= 44`` (within 1 ulp): arithmetic only, no branch, so loops vectorise."""
    kf = np.floor(r * _INV_LN2 + 0.5)
    f = (r - kf * _LN2_HI) - kf * _LN2_LO  # r = k ln 2 + f, |f| <= ln 2 / 2
    # exp(-f) - 1 by Horner on its Taylor series to degree 13 (truncation < 5e-18 for |f| <= ln 2 / 2)
    p = 1.0 / 6227020800.0
    p = p * -f + 1.0 / 479001600.0
    p = p * -f + 1.0 / 39916800.0
    p = p * -f + 1.0 / 3628800.0
    p = p * -f + 1.0 / 362880.0
    p = p * -f + 1.0 / 40320.0
    p = p * -f + 1.0 / 5040.0
    p = p * -f + 1.0 / 720.0
    p = p * -f + 1.0 / 120.0
    p = p * -f + 1.0 / 24.0
    p = p * -f + 1.0 / 6.0
    p = p * -f + 0.5
    p = p * -f + 1.0
    p = p * -f
    # exp(-r) - 1 = 2^-k (exp(-f) - 1) + (2^-k - 1). 2^-k built in its exponent field: 1023 - k + 2^52 holds
    # 1023 - k in its low mantissa bits (exactly: an integer below 2^52); shifted 52 bits up, they are the exponent
    s = _as_float(_as_int(1023.0 - kf + 4503599627370496.0) << 52)
    return s * p + (s - 1.0)


@_inline
def _tanh(x):
    """``tanh(x) = -m / (2 + m)``, ``m = expm1(-2|x|)``, signed (within 3 ulp of ``np.tanh``; one division)."""
    m = _expm1_neg(2.0 * min(abs(x), _TANH_ONE))
    return math.copysign(-m / (2.0 + m), x)


@_fused
def _tanh_array(x, out):
    for i in range(x.size):
        out[i] = _tanh(x[i])


def tanh(x) -> np.ndarray:
    """The kernel's ``tanh`` on an array (for tests and comparison with ``np.tanh``)."""
    x = np.ascontiguousarray(x, dtype=float).ravel()
    out = np.empty_like(x)
    _tanh_array(x, out)
    return out


@_fused
def _forward(w, x, t, nin, nh, nout, z, d):
    """Hidden activations into ``z`` (nh, n), output errors ``y - t`` into ``d`` (nout, n); returns
    ``0.5 * sum(d^2)`` (NETLAB ``mlperr``). ``x`` is (nin, n) and ``t`` (nout, n): samples along the rows, so
    that every inner loop runs over contiguous samples and vectorises."""
    n = x.shape[1]
    ob1 = nin * nh
    ow2 = ob1 + nh
    ob2 = ow2 + nh * nout
    a = np.empty(n)
    d[:, :] = 0.0
    for j in range(nh):  # rows as 1-D views: every inner loop a plain contiguous one, which LLVM vectorises
        bj = w[ob1 + j]
        for i in range(n):
            a[i] = bj
        for k in range(nin):
            c = w[k * nh + j]
            xk = x[k]
            for i in range(n):
                a[i] += xk[i] * c
        zj = z[j]
        for i in range(n):
            zj[i] = _tanh(a[i])
        for o in range(nout):
            c = w[ow2 + j * nout + o]
            do = d[o]
            for i in range(n):
                do[i] += zj[i] * c
    err = 0.0
    for o in range(nout):
        b = w[ob2 + o]
        do = d[o]
        to = t[o]
        for i in range(n):
            do[i] = (do[i] + b) - to[i]
            err += do[i] * do[i]
    return 0.5 * err


@_reduce
def _backward(w, x, nin, nh, nout, z, d, g):
    """The gradient of the error whose forward pass left ``z`` and ``d`` (NETLAB ``mlpbkp``), into ``g``."""
    n = x.shape[1]
    ob1 = nin * nh
    ow2 = ob1 + nh
    ob2 = ow2 + nh * nout
    delhid = np.empty(n)
    for o in range(nout):
        s = 0.0
        for i in range(n):
            s += d[o, i]
        g[ob2 + o] = s
    for j in range(nh):
        for i in range(n):
            delhid[i] = 0.0
        for o in range(nout):
            c = w[ow2 + j * nout + o]
            s = 0.0
            for i in range(n):
                s += z[j, i] * d[o, i]
                delhid[i] += d[o, i] * c
            g[ow2 + j * nout + o] = s
        s = 0.0
        for i in range(n):
            delhid[i] *= 1.0 - z[j, i] * z[j, i]
            s += delhid[i]
        g[ob1 + j] = s
        for k in range(nin):
            s = 0.0
            for i in range(n):
                s += x[k, i] * delhid[i]
            g[k * nh + j] = s


@_jit
def _dot(a, b):
    s = 0.0
    for i in range(a.size):
        s += a[i] * b[i]
    return s


@_jit
def _scg(w, x, t, nin, nh, nout, iterations, tol_x, tol_f, z, d, zs, ds):
    """NETLAB ``scg.m`` from ``w`` (updated in place) for at most ``iterations``; True if the tolerances were met.

    ``z, d`` hold the forward pass of the last point whose error was taken (reused for its gradient, as
    netlab._Objective does); ``zs, ds`` are scratch for the gradient at ``x + sigma d``."""
    m = w.size
    fold = _forward(w, x, t, nin, nh, nout, z, d)
    gradnew = np.empty(m)
    _backward(w, x, nin, nh, nout, z, d, gradnew)
    gradold = gradnew.copy()
    gplus = np.empty(m)
    direction = -gradnew
    xnew = np.empty(m)
    xplus = np.empty(m)
    success = True
    nsuccess = 0
    beta = 1.0
    mu = 0.0
    kappa = 0.0
    theta = 0.0
    for _ in range(iterations):
        if success:
            mu = _dot(direction, gradnew)
            if mu >= 0:
                direction[:] = -gradnew
                mu = _dot(direction, gradnew)
            kappa = _dot(direction, direction)
            if kappa < _EPS:
                return True
            sigma = _SIGMA0 / np.sqrt(kappa)
            for i in range(m):
                xplus[i] = w[i] + sigma * direction[i]
            _forward(xplus, x, t, nin, nh, nout, zs, ds)
            _backward(xplus, x, nin, nh, nout, zs, ds, gplus)
            s = 0.0
            for i in range(m):
                s += direction[i] * (gplus[i] - gradnew[i])
            theta = s / sigma
        delta = theta + beta * kappa
        if delta <= 0:
            delta = beta * kappa
            beta = beta - theta / kappa
        alpha = -mu / delta
        for i in range(m):
            xnew[i] = w[i] + alpha * direction[i]
        fnew = _forward(xnew, x, t, nin, nh, nout, z, d)
        big_delta = 2.0 * (fnew - fold) / (alpha * mu)
        success = big_delta >= 0
        if success:
            nsuccess += 1
            w[:] = xnew
            step = 0.0
            for i in range(m):
                step = max(step, abs(alpha * direction[i]))
            if step < tol_x and abs(fnew - fold) < tol_f:
                return True
            fold = fnew
            gradold[:] = gradnew
            _backward(w, x, nin, nh, nout, z, d, gradnew)  # z, d: the forward pass at xnew, now w
            if _dot(gradnew, gradnew) == 0.0:
                return True
        if big_delta < 0.25:
            beta = min(4.0 * beta, _BETA_MAX)
        if big_delta > 0.75:
            beta = max(0.5 * beta, _BETA_MIN)
        if nsuccess == m:
            direction[:] = -gradnew
            nsuccess = 0
        elif success:
            s = 0.0
            for i in range(m):
                s += (gradold[i] - gradnew[i]) * gradnew[i]
            gamma = s / mu
            for i in range(m):
                direction[i] = gamma * direction[i] - gradnew[i]
    return False


@_jit
def _mse(w, x, t, nin, nh, nout, z, d):
    return 2.0 * _forward(w, x, t, nin, nh, nout, z, d) / (x.shape[1] * nout)


@_jit
def _train(w, best_w, train, val, start, best_epoch, x, t, xv, tv, nh, per_epoch, tol):
    """Epochs ``start + 1 .. train.size - 1`` from ``w``, the weights after epoch ``start`` (updated in place), with
    ``train`` and ``val`` filled up to ``start`` (epoch 0: computed here) and ``best_w`` the weights of
    ``best_epoch`` (updated in place). Returns ``(best_epoch, epochs_run, converged)``."""
    nin = x.shape[0]
    nout = t.shape[0]
    n, nv = x.shape[1], xv.shape[1]
    z, d = np.empty((nh, n)), np.empty((nout, n))
    zs, ds = np.empty((nh, n)), np.empty((nout, n))
    zv, dv = np.empty((nh, nv)), np.empty((nout, nv))
    if start == 0:
        train[0] = _mse(w, x, t, nin, nh, nout, zs, ds)
        val[0] = _mse(w, xv, tv, nin, nh, nout, zv, dv)
    last = start
    converged = False
    for epoch in range(start + 1, train.size):
        converged = _scg(w, x, t, nin, nh, nout, per_epoch, tol, tol, z, d, zs, ds)
        train[epoch] = _mse(w, x, t, nin, nh, nout, zs, ds)
        val[epoch] = _mse(w, xv, tv, nin, nh, nout, zv, dv)
        last = epoch
        if val[epoch] < val[best_epoch]:
            best_w[:] = w
            best_epoch = epoch
        if converged:
            break
    return best_epoch, last, converged


@dataclass
class _Run:
    """Where one network's training stopped: the weights after its last epoch, the best ones and the errors."""

    w: np.ndarray
    best_w: np.ndarray
    best_epoch: int
    last: int
    train: np.ndarray
    val: np.ndarray
    converged: bool


#: Trainings kept to be resumed (:func:`train`), the most recent last; each holds two weight vectors and two error
#: curves (a few kB).
RESUMABLE = 64
_runs: OrderedDict[bytes, _Run] = OrderedDict()
_runs_lock = threading.Lock()


def _run_key(arrays, hidden: int, per_epoch: int, tol: float) -> bytes:
    """A digest of everything a training's epochs depend on except their number."""
    h = hashlib.blake2b(repr((hidden, per_epoch, tol, [a.shape for a in arrays])).encode(), digest_size=32)
    for a in arrays:
        h.update(a.tobytes())
    return h.digest()


def train(w0, x, t, xv, tv, hidden: int, epochs: int, iterations_per_epoch: int, tol: float):
    """Train one network as :meth:`flexdigit.tactile.netlab.MLP.fit` does, compiled.

    Returns ``(best_weights, best_epoch, epochs_run, train_mse, val_mse, converged)``: the weights of the epoch
    with the lowest validation MSE, that epoch, how many epochs ran, the MSE after each (index 0: ``w0``) and
    whether SCG met the tolerance ``tol`` (both of ``scg.m``'s) before the last epoch.

    A training asked again with more epochs (the same initial weights, data, size and tolerance: ``flexdigit
    train``'s 50, 100, ... 800 epochs of one network, :func:`flexdigit.tactile.localisation.train_network`) goes
    on from where the last one stopped instead of starting over: each epoch starts SCG afresh from the weights
    alone, so epochs ``1..E`` of a longer training are those of the shorter one, and the result is the one
    training from the start gives, number for number (tests/tactile/test_scg_kernel.py). The last
    :data:`RESUMABLE` trainings are kept.
    """
    c = np.ascontiguousarray
    w0 = c(w0, dtype=float)
    arrays = (w0, *(c(np.transpose(a), dtype=float) for a in (x, t, xv, tv)))
    hidden, epochs, per_epoch, tol = int(hidden), int(epochs), int(iterations_per_epoch), float(tol)
    key = _run_key(arrays, hidden, per_epoch, tol)
    with _runs_lock:
        run = _runs.get(key)
    if run is None or epochs < run.last:  # nothing to go on from (a shorter training starts over)
        run = _Run(w0.copy(), w0.copy(), 0, 0, np.empty(0), np.empty(0), False)
    if not run.converged and epochs > run.last:
        train_mse, val_mse = np.full(epochs + 1, np.nan), np.full(epochs + 1, np.nan)
        train_mse[: run.train.size], val_mse[: run.val.size] = run.train, run.val
        w, best_w = run.w.copy(), run.best_w.copy()
        best, last, converged = _train(w, best_w, train_mse, val_mse, run.last, run.best_epoch, *arrays[1:], hidden,
                                       per_epoch, tol)  # fmt: skip
        run = _Run(w, best_w, int(best), int(last), train_mse[: last + 1], val_mse[: last + 1], bool(converged))
    with _runs_lock:
        _runs[key] = run
        _runs.move_to_end(key)
        while len(_runs) > RESUMABLE:
            _runs.popitem(last=False)
    return run.best_w.copy(), run.best_epoch, run.last, run.train.copy(), run.val.copy(), run.converged

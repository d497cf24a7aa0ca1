"""Step responses of linear systems with python-control's own recursion, compiled (issue 15: reproduce in 60 s).

``control.forced_response`` steps the state in a Python loop, one small matrix-vector product per time point
(~10 us each): chapter 5's sample-period study simulates 17 continuous loops over 20,001 points and as many
sampled ones, seconds of CPU for a few hundred thousand products. :func:`step_output` runs the same recursion in
machine code (numba): for a continuous system python-control's discretisation, ``scipy.linalg.expm`` of the block
matrix ``[[A dt, B dt, 0], [0, 0, I], [0, 0, 0]]`` (the input linear between points), and
``x[i] = Ad x[i-1] + Bd0 u[i-1] + Bd1 u[i]``; for a discrete one scipy's ``dlsim``, ``x[i+1] = A x[i] + B u[i]``.
The operations are the same, summed in a fixed order, so the output equals ``control.step_response`` to rounding
(tests/control/test_lsim.py).
"""

from __future__ import annotations

import control as ct
import numba
import numpy as np
import scipy.linalg

from flexdigit import _numba_cache
from flexdigit.errors import DesignError

_numba_cache.install()  # the machine code kept per user by source text (flexdigit/_numba_cache.py)

__all__ = ["step_output"]


@numba.njit(cache=True, nogil=True)
def _recurse(Ad, Bd0, Bd1, x, u):  # pragma: no cover - compiled; checked against python-control in the tests
    """``x[i] = Ad x[i-1] + Bd0 u[i-1] + Bd1 u[i]`` for ``i >= 1`` in place (``x``: steps x states, ``u``: steps
    x inputs), summed in python-control's order."""
    n_steps, n = x.shape
    m = u.shape[1]
    for i in range(1, n_steps):
        for r in range(n):
            acc = 0.0
            for c in range(n):
                acc += Ad[r, c] * x[i - 1, c]
            b0 = 0.0
            b1 = 0.0
            for c in range(m):
                b0 += Bd0[r, c] * u[i - 1, c]
                b1 += Bd1[r, c] * u[i, c]
            x[i, r] = acc + b0 + b1


def step_output(sys, t) -> np.ndarray:
    """Unit step response of a single-input single-output system at the equally spaced times ``t`` (s).

    The numbers of ``np.squeeze(control.step_response(sys, T=t).outputs)`` (zero initial state, the step at
    ``t[0]``), computed by a compiled recursion. A discrete system's ``t`` must step by its sampling period.

    Examples
    --------
    >>> import control as ct
    >>> t = np.linspace(0.0, 5.0, 501)
    >>> y = step_output(ct.tf([1.0], [1.0, 1.0]), t)
    >>> round(float(y[-1]), 4)  # 1 - exp(-5)
    0.9933
    """
    sys = ct.ss(sys)
    if (sys.ninputs, sys.noutputs) != (1, 1):
        raise DesignError(f"step_output needs a single-input single-output system. Got {sys.noutputs}x{sys.ninputs}.")
    t = np.asarray(t, dtype=float).ravel()
    n_steps = t.size
    if n_steps < 2:
        raise DesignError(f"step_output needs at least two time points. Got {n_steps}.")
    dt = (t[-1] - t[0]) / (n_steps - 1)
    if not (dt > 0 and np.allclose(np.diff(t), dt)):
        raise DesignError("The 't' parameter of step_output must be equally spaced and increasing.")
    A, B, C, D = (np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C, sys.D))
    n = A.shape[0]
    u = np.ones((n_steps, 1))
    x = np.zeros((n_steps, n))
    if n:
        if sys.isctime(strict=True):
            # python-control's forced_response: the input interpolated linearly between the points
            M = np.zeros((n + 2, n + 2))
            M[:n, :n], M[:n, n : n + 1], M[n, n + 1] = A * dt, B * dt, 1.0
            expM = scipy.linalg.expm(M)
            Ad, Bd1 = expM[:n, :n], expM[:n, n + 1 :]
            Bd0 = expM[:n, n : n + 1] - Bd1
        else:
            if not np.isclose(dt, sys.dt):
                raise DesignError(f"The 't' of a discrete system must step by its period {sys.dt!r}. Got {dt!r}.")
            Ad, Bd0, Bd1 = A, B, np.zeros_like(B)  # scipy.signal.dlsim: x[i+1] = A x[i] + B u[i]
        _recurse(np.ascontiguousarray(Ad), np.ascontiguousarray(Bd0), np.ascontiguousarray(Bd1), x, u)
    return (C @ x.T + D @ u.T)[0]

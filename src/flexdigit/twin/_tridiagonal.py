"""Batched tridiagonal solves with partial pivoting (LAPACK's dgtsv, one right-hand side), compiled.

The digit's static Newton solves ``J step = r`` for every load case at once; without a body beside the digit its
Jacobian is the springs' tridiagonal ``K_psi`` plus a diagonal (gravity, the cable), so a case costs O(n) instead of
a dense LU's O(n^3): the contact estimator's tables solve ~400 cases of 35 links per Newton iteration.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["solve_tridiagonal"]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def solve_tridiagonal(lower, diagonal, upper, rhs):
    """``x`` (B, n) with ``T_b x_b = rhs_b``, ``T_b`` of sub-diagonal ``lower`` (n - 1,), diagonal ``diagonal[b]``
    (B, n) and super-diagonal ``upper`` (n - 1,); and whether every ``T_b`` was non-singular (dgtsv's pivots)."""
    b, n = diagonal.shape
    x = np.empty((b, n))
    d, du, dl = np.empty(n), np.empty(n), np.empty(n)
    for k in range(b):
        for i in range(n):
            d[i] = diagonal[k, i]
            x[k, i] = rhs[k, i]
        for i in range(n - 1):
            du[i], dl[i] = upper[i], lower[i]
        for i in range(n - 1):
            if abs(d[i]) >= abs(dl[i]):  # no row interchange
                if d[i] == 0.0:
                    return x, False
                fact = dl[i] / d[i]
                d[i + 1] -= fact * du[i]
                x[k, i + 1] -= fact * x[k, i]
                dl[i] = 0.0
            else:  # interchange rows i and i + 1; dl[i] becomes row i's second super-diagonal
                fact = d[i] / dl[i]
                d[i] = dl[i]
                temp = d[i + 1]
                d[i + 1] = du[i] - fact * temp
                if i < n - 2:
                    dl[i] = du[i + 1]
                    du[i + 1] = -fact * dl[i]
                else:
                    dl[i] = 0.0
                du[i] = temp
                temp = x[k, i]
                x[k, i] = x[k, i + 1]
                x[k, i + 1] = temp - fact * x[k, i + 1]
        if d[n - 1] == 0.0:
            return x, False
        x[k, n - 1] /= d[n - 1]
        if n > 1:
            x[k, n - 2] = (x[k, n - 2] - du[n - 2] * x[k, n - 1]) / d[n - 2]
        for i in range(n - 3, -1, -1):
            x[k, i] = (x[k, i] - du[i] * x[k, i + 1] - dl[i] * x[k, i + 2]) / d[i]
    return x, True

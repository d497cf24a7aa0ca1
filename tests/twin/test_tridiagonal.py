"""The static Newton's tridiagonal solve (:mod:`flexdigit.twin._tridiagonal`, LAPACK's dgtsv) against a dense LU
(``np.linalg.solve``), and the static solve it serves against the dense path it replaced.

Tolerances:
- ``SOLVE_RTOL = 1e-12``: both are Gaussian elimination with partial pivoting, in other orders of operations; on
  the random matrices here (condition numbers up to ~1e4, some needing row interchanges) the solutions agree to
  ~1e-14 of their size, and a wrong pivot or a dropped fill-in entry is off by O(1).
- ``STATIC_RTOL = 1e-10``: Newton's answer is fixed by its residual tolerance (1e-11 of the stiffness), not by the
  solve's rounding: the gauges' curvatures on the two paths agree to ~1e-13 of their size.
"""

import numpy as np
import pytest

from flexdigit.params import RigParams
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.digit import G_STANDARD_M_S2
from flexdigit.twin.twin import cached_digit

SOLVE_RTOL = 1e-12
STATIC_RTOL = 1e-10


def _dense(lower, diagonal, upper):
    return np.stack([np.diag(d) + np.diag(lower, -1) + np.diag(upper, 1) for d in diagonal])


@pytest.mark.parametrize("n", [1, 2, 3, 9, 35])
def test_the_tridiagonal_solve_is_a_dense_lu_solve(n):
    from flexdigit.twin._tridiagonal import solve_tridiagonal

    rng = np.random.default_rng(n)
    lower, upper = rng.normal(0.0, 1.0, n - 1), rng.normal(0.0, 1.0, n - 1)
    # diagonals from dominant to small (row interchanges) and negative (an indefinite Jacobian, a buckling digit)
    diagonal = rng.normal(0.0, 1.0, (40, n)) * np.logspace(-3, 1, 40)[:, None]
    rhs = rng.normal(0.0, 1.0, (40, n))
    x, regular = solve_tridiagonal(lower, diagonal, upper, rhs)
    want = np.linalg.solve(_dense(lower, diagonal, upper), rhs[..., None])[..., 0]
    assert regular
    np.testing.assert_allclose(x, want, rtol=0, atol=SOLVE_RTOL * np.abs(want).max())


def test_a_singular_tridiagonal_matrix_is_said_to_be():
    from flexdigit.twin._tridiagonal import solve_tridiagonal

    # [[1, 1], [1, 1]]: singular after one elimination step
    _, regular = solve_tridiagonal(np.ones(1), np.ones((1, 2)), np.ones(1), np.ones((1, 2)))
    assert not regular


@pytest.mark.parametrize("orientation", ["vertical", "hanging", "horizontal"])
def test_the_static_solve_on_the_tridiagonal_path_is_the_dense_one(orientation):
    # the chain's Jacobian without a body is K_psi plus a diagonal; the same chain made to take the dense path
    chain = cached_digit(RigParams(), default_calibration(), True, orientation, 5)
    s = np.linspace(0.05, chain.length_m, 30)
    force = np.stack([np.zeros(30), np.linspace(-0.5, 0.5, 30) * G_STANDARD_M_S2 * 0.05], axis=1)[:, None, :]
    shortening = np.linspace(-0.004, 0.004, 30)
    fast = chain.solve_static(s[:, None], force, cable_shortening_m=shortening)
    chain._k_tridiagonal = False
    try:
        dense = chain.solve_static(s[:, None], force, cable_shortening_m=shortening)
    finally:
        chain._k_tridiagonal = True
    assert fast.converged
    scale = np.abs(dense.curvature_1_m).max()
    np.testing.assert_allclose(fast.curvature_1_m, dense.curvature_1_m, rtol=0, atol=STATIC_RTOL * scale)

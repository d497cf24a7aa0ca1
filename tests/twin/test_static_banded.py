"""The static Newton's tridiagonal elimination (a batch of 16 cases or more on a chain of 12 links or more) against
LAPACK's dense solve: the same equilibria, and an indefinite Jacobian with a vanishing pivot handed back to LAPACK.

Tolerances: ``PSI_ATOL`` is the Newton's own stopping rule (it stops once a step is below 1e-9 rad), so two solvers
that round differently may stop that far apart; a backward-stable solve is within its condition number times a few
ulps (``ULPS``) of another.
"""

import numpy as np

from flexdigit.twin import digit
from flexdigit.twin.digit import Chain

PSI_ATOL = 1e-9
ULPS = 100
L, EI, MU = 0.5, 205e9 * 12.7e-3 * 0.381e-3**3 / 12, 7850.0 * 12.7e-3 * 0.381e-3


def _chain(n=40):
    return Chain.uniform(L, EI, n, mass_per_length_kg_m=MU, gravity_ab_m_s2=(0.0, -9.80665))


def test_a_batch_takes_the_elimination_and_matches_the_dense_solves_case_by_case():
    chain = _chain()
    forces = np.column_stack([np.zeros(64), np.linspace(-0.05, 0.05, 64)])  # past 60 deg at the tip both ways
    batch = chain.solve_static(tip_force_n=forces)
    assert forces.shape[0] >= digit._BANDED_MIN_BATCH
    assert chain.n >= digit._BANDED_MIN_LINKS
    for k, force in enumerate(forces):  # one case at a time: LAPACK's dense solve
        one = chain.solve_static(tip_force_n=force[None])
        np.testing.assert_allclose(batch.psi_rad[k], one.psi_rad[0], rtol=0, atol=PSI_ATOL, err_msg=f"case {k}")


def test_a_vanishing_pivot_is_solved_densely():
    chain = _chain()
    n = chain.n
    rng = np.random.default_rng(3)
    diag = np.broadcast_to(np.diagonal(chain.k_psi), (20, n)).copy()
    diag[7, 0] = 0.0  # case 7: the first pivot exactly 0 (an indefinite, still regular Jacobian)
    rhs = rng.standard_normal((20, n))
    x = digit._tridiagonal_solve(chain.k_psi, diag, rhs)
    for k in range(20):
        jac = chain.k_psi.copy()
        jac[np.arange(n), np.arange(n)] = diag[k]
        want = np.linalg.solve(jac, rhs[k])
        rtol = ULPS * np.finfo(float).eps * np.linalg.cond(jac)
        np.testing.assert_allclose(x[k], want, rtol=rtol, err_msg=f"case {k}")

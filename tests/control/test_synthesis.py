"""The two synthesis routes, the regularisation path and the thesis reproduction (chapter 4)."""

import control as ct
import numpy as np
import pytest

from flexdigit.control._threads import single_blas_thread
from flexdigit.control.analysis import additive_tolerance, hinf_norm, loop_maps
from flexdigit.control.generalized import filter_weight, regularise, thesis_generalized_plant
from flexdigit.control.synthesis import hinf_lmi, hinf_riccati, reduce_controller, regularisation_path
from flexdigit.control.thesis_designs import (
    fit_thesis_regularisation,
    printed_controller,
    singular_infimum_witness,
    sorted_poles,
    thesis_design,
    thesis_plant,
)
from flexdigit.errors import DesignError, UnstableError
from flexdigit.reference import thesis_complex, thesis_value

pytestmark = pytest.mark.blas  # run again under other OpenBLAS kernels by `make test` (docs/guide/reliability.md)

# Tolerances, each with the reason for its size
GAMMA_ROUTE_RTOL = 0.01  # issue 5: the Riccati and LMI routes agree within 1 %
SLICOT_GAMMA_RTOL = 2e-3  # the bisection's gtol (1e-3) twice over
PRINTED_4_DIGITS_RTOL = 1e-3  # a figure printed to 4 significant digits
PRINTED_10X_RTOL = 0.01  # the printed numerator's 10x, to its printed digits
TZW_PEAK_DB_ATOL = 2e-3  # ||T_zw|| printed to 0.0001 dB; the fitted design is within 0.002 dB
TZW_PEAK_W_RTOL = 0.04  # the printed peak frequency reads a coarse grid (51.8 against our exact 53.3 rad/s)
TPQ_DB_ATOL = 0.05  # ||T_pq|| printed to 0.01 dB, the 39 Hz numerator 0.6 % off (see the report)
PRINTED_TOLERANCE_RTOL = 3e-3  # 22.48 % from the printed K, whose 4 digits move it by +-0.12 %


@pytest.fixture(scope="module")
def G():
    return thesis_plant()


@pytest.fixture(scope="module")
def P5(G):
    return thesis_generalized_plant(G, filter_weight(5.0))


def test_riccati_matches_plain_hinfsyn(P5):
    # independent oracle: python-control's hinfsyn (SLICOT's own gamma search) on the same regularised plant
    P = regularise(P5, 1e-6)
    ours = hinf_riccati(P, gtol=1e-5)
    with single_blas_thread():  # the plain call crawls with OpenBLAS threads on a busy machine
        _, _, gam, _ = ct.hinfsyn(P, 1, 1)
    assert ours.gamma_opt == pytest.approx(gam, rel=SLICOT_GAMMA_RTOL)
    assert ours.achieved <= ours.gamma * (1 + 1e-6)


def test_singular_problem_rejected_by_riccati(P5):
    with pytest.raises(DesignError, match="D12"):
        hinf_riccati(P5)


def test_wrong_partition_raises(P5):
    with pytest.raises(DesignError, match="too few"):
        hinf_riccati(regularise(P5, 1e-6), nmeas=3, ncon=1)


def test_infeasible_gamma_raises(P5):
    P = regularise(P5, 1e-6)
    with pytest.raises(DesignError, match="feasible"):
        hinf_riccati(P, gamma=0.01)  # optimum is 0.0249 (test_riccati_matches_plain_hinfsyn)


@pytest.mark.slow
@pytest.mark.parametrize(
    "hz, eps",
    [(5.0, 1e-5), (5.0, 1e-6), (5.0, 1.0538e-7), (39.0, 8.4175e-7)],
    ids=["5Hz-1e-5", "5Hz-1e-6", "5Hz-fitted", "39Hz-fitted"],
)
def test_lmi_and_riccati_agree(G, hz, eps):
    # issue 5: the two routes agree on gamma within 1 % on the regularised thesis problem, including the levels
    # fitted to the printed controllers (reproduce.THESIS_REGULARISATION). Before the LMI route re-solved in the
    # coordinates of its own centred R, S it stopped 1.1-1.2 % high at eps = 1.05e-7 (10 % on its first solve);
    # measured after: +0.06 % there, <= 0.02 % at the other three.
    P = regularise(thesis_generalized_plant(G, filter_weight(hz)), eps)
    ric = hinf_riccati(P, gtol=1e-6)
    lmi = hinf_lmi(P)
    assert lmi.gamma == pytest.approx(ric.gamma_opt, rel=GAMMA_ROUTE_RTOL)


def test_lmi_rejects_bad_iterations(P5):
    with pytest.raises(DesignError, match="iterations"):
        hinf_lmi(regularise(P5, 1e-6), iterations=0)


def test_lmi_handles_the_singular_problem(P5):
    # no rank conditions: the LMIs accept D12 = 0 and return a level below the regularised optimum at eps = 1e-6
    # (0.0249, test_riccati_matches_plain_hinfsyn); the true infimum is 0, the solver stops where conditioning ends
    singular = hinf_lmi(P5).gamma
    assert 0 < singular < hinf_riccati(regularise(P5, 1e-6)).gamma_opt


def test_gamma_decreases_without_limit_as_eps_goes_to_zero(G, P5):
    # the singular problem has infimum 0: gamma(eps) keeps falling and the controller gain keeps growing
    rows = regularisation_path(P5, [1e-4, 1e-6, 1e-8])
    gammas = [r["gamma_opt"] for r in rows]
    assert gammas[0] > gammas[1] > gammas[2]
    assert rows[2]["dc_gain"] > 5 * rows[0]["dc_gain"]
    # and an explicit stabilising family drives ||F S|| below any regularised optimum
    assert singular_infimum_witness(G, 5.0, 1e-4) < 0.1 * gammas[2]


@pytest.mark.parametrize("which, hz", [("5hz", 5.0), ("39hz", 39.0)])
def test_fitted_design_reproduces_printed_poles_and_structure(G, which, hz):
    fit = fit_thesis_regularisation(hz)
    assert fit["pole_error"] < 1e-3  # tables 4.2 / 4.3 to their printed digits
    # the 39 Hz search stops on its iteration limit (converged False) within the printed digits: no warning
    assert fit["converged"] == (hz == 5.0)
    K = fit["design"].controller
    # controller zeros = plant poles (thesis 4.4) within 0.1 %; filter pole present
    zeros = sorted_poles(ct.zeros(K))
    plant_poles = sorted_poles(ct.poles(G))
    np.testing.assert_allclose(zeros, plant_poles, rtol=PRINTED_4_DIGITS_RTOL)
    assert np.min(np.abs(np.linalg.eigvals(K.A) + 2 * np.pi * hz)) < 1e-3 * 2 * np.pi * hz
    # the printed numerator is 10x ours (same poles): thesis k_*_num[0] vs our leading coefficient
    lead = float(ct.tf(K).num[0][0][0])
    assert thesis_value(f"hinf.k_{which}_num")[0] / lead == pytest.approx(10.0, rel=PRINTED_10X_RTOL)


def test_5hz_tzw_peak_matches_thesis(G):
    # 4.4: ||T_zw|| = 2.2645 dB (the thesis's 51.769 rad/s is 2.8 % below our 53.26, a coarse grid)
    d = thesis_design(5.0, G)
    gpk, w = hinf_norm(loop_maps(G, d.controller).T_zw)
    assert 20 * np.log10(gpk) == pytest.approx(thesis_value("hinf.tzw_peak_db"), abs=TZW_PEAK_DB_ATOL)
    assert w == pytest.approx(thesis_value("hinf.tzw_peak_rad_s"), rel=TZW_PEAK_W_RTOL)
    # T_pq: 117.83 dB printed = ours + 20 dB (the printed controller is 10x ours)
    tol = additive_tolerance(G, d.controller)
    assert tol["tpq_db"] + 20 == pytest.approx(thesis_value("hinf.tpq_peak_db"), abs=TPQ_DB_ATOL)


def test_printed_5hz_controller_destabilises_printed_plant(G):
    maps = loop_maps(G, printed_controller("5hz"))
    assert not maps.stable
    with pytest.raises(UnstableError):
        hinf_norm(maps.T_zw)


def test_printed_39hz_tolerance_is_thesis_arithmetic(G):
    # 4.7: 22.48 % is 100 / (||T_pq|| in dB) of the printed controller, not 1/||T_pq||
    tol = additive_tolerance(G, printed_controller("39hz"))
    assert tol["thesis_arithmetic_percent"] == pytest.approx(22.48, rel=PRINTED_TOLERANCE_RTOL)
    assert 100 * tol["tolerance"] == pytest.approx(59.96, rel=PRINTED_4_DIGITS_RTOL)


def test_thesis_poles_reference_loaded():
    assert len(thesis_complex("hinf.k_5hz_poles")) == 5


def test_reduce_controller_keeps_low_frequency(G):
    K = thesis_design(5.0, G).controller
    Kr = reduce_controller(K, 3)
    assert Kr.nstates == 3
    # balanced truncation error bound: |K - Kr| <= 2 x (sum of the dropped Hankel singular values), all w
    hsv = np.sort(ct.hankel_singular_values(K))[::-1]
    w = np.logspace(-1, 4, 400)
    err = np.max(np.abs(K(1j * w) - Kr(1j * w)))
    assert err <= 2 * hsv[3:].sum() * (1 + 1e-6)
    with pytest.raises(DesignError, match="order"):
        reduce_controller(K, 9)


# issue 15: the LMI route solves problems compiled once (cvxpy DPP) instead of writing the LMIs out per solve
LMI_MAP_RTOL = 1e-12  # the same affine map evaluated two ways (Kronecker products, cvxpy's expression tree)
#: One gamma minimisation of the same problem from two compilations. Clarabel stops within ~1e-4 of the optimum on
#: these problems: the written-out LMIs alone move by up to 1.1e-4 when A is scaled by (1 + 1e-15) (seeds 0-7 of
#: the test below; on the thesis's fitted 5 Hz problem hinf_lmi moves by 2.7e-5, on the singular one by 2.5 %).
LMI_SOLVE_RTOL = 3e-4


def _random_generalized_plant(rng, n):
    """A seeded random stable generalized plant: w, u in; z (two rows), y out; D12, D21 full rank."""
    A = -np.diag(rng.uniform(0.5, 5.0, n)) + 0.3 * rng.normal(size=(n, n))
    return ct.ss(A, rng.normal(size=(n, 2)), rng.normal(size=(3, n)), np.array([[0, 1.0], [0.2, 0], [1.0, 0]]))


@pytest.mark.parametrize("seed", range(3))
def test_lmi_maps_are_the_written_out_lmis(seed):
    # reference: the LMIs as Gahinet and Apkarian write them (synthesis._lmi_constraints, cvxpy expressions),
    # evaluated at random symmetric R, S and level g
    import cvxpy as cp

    from flexdigit.control.synthesis import _lmi_constraints, _lmi_maps

    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 7))
    P = _random_generalized_plant(rng, n)
    nw, nz = 1, 2
    X = [rng.normal(size=(n, n)) for _ in range(2)]
    R, S = (cp.Variable((n, n), symmetric=True) for _ in range(2))
    R.value, S.value = (x + x.T for x in X)
    g = float(rng.uniform(0.1, 2.0))
    strict = 1e-9
    cons = _lmi_constraints(P, nw, nz, R, S, g, strict)
    maps = _lmi_maps(P, nw, nz)
    for con, m, V in zip(cons[1:], maps, (R.value, S.value), strict=True):
        Pm, Q, G, C0 = m
        ours = Q @ V @ Pm.T + Pm @ V @ Q.T + g * G + C0
        ref = -(np.asarray(con.expr.value) + strict * np.eye(ours.shape[0]))  # cvxpy keeps "-strict I - L is PSD"
        np.testing.assert_allclose(ours, ref, rtol=0, atol=LMI_MAP_RTOL * np.abs(ref).max())


def test_compiled_lmi_problems_are_dpp_and_reused(G):
    from flexdigit.control.synthesis import _LMI_PROBLEMS

    hinf_lmi(regularise(thesis_generalized_plant(G, filter_weight(5.0)), 1e-5))
    problems = dict(_LMI_PROBLEMS)
    assert problems
    assert all(p[0].is_dpp() for p in problems.values())
    hinf_lmi(regularise(thesis_generalized_plant(G, filter_weight(39.0)), 1e-6))  # same sizes: nothing new
    assert _LMI_PROBLEMS.keys() == problems.keys()


@pytest.mark.parametrize("seed", range(8))
def test_compiled_lmis_solve_as_the_written_out_ones(seed):
    # one gamma minimisation on a well-conditioned random problem: the compiled problem against the written-out
    # one compiled afresh (the route before issue 15), both by Clarabel
    import cvxpy as cp

    from flexdigit.control.synthesis import _lmi_constraints, _lmi_once, _partition, _scale

    rng = np.random.default_rng(seed)
    P = _random_generalized_plant(rng, int(rng.integers(2, 6)))
    nw, nz = _partition(P, 1, 1)
    Ps, _ = _scale(P, 1, 1)
    ours, _ = _lmi_once(Ps, nw, nz, "CLARABEL", 1e-9)
    n = Ps.nstates
    R, S, g = cp.Variable((n, n), symmetric=True), cp.Variable((n, n), symmetric=True), cp.Variable()
    cp.Problem(cp.Minimize(g), _lmi_constraints(Ps, nw, nz, R, S, g, 1e-9)).solve(solver="CLARABEL")
    assert ours.gamma == pytest.approx(float(g.value), rel=LMI_SOLVE_RTOL)


@pytest.mark.parametrize("hz", [5.0, 39.0])
def test_central_controller_poles_are_the_designs(P5, G, hz):
    # issue 15: the regularisation fit's lean path against the full design it stands for, on the fit's own grid
    # of (eps_u, margin): the same SLICOT calls on the same matrices, so the same numbers bit for bit
    from flexdigit.control.synthesis import central_controller_poles

    P0 = thesis_generalized_plant(G, filter_weight(hz))
    gamma_opts = {}  # the fit's memo of each eps_u's optimum: the second and third margins skip the bisection
    for le in np.arange(-9.0, -2.9, 1.5):
        for margin in (0.01, 0.2, 3.0):
            full = np.linalg.eigvals(hinf_riccati(regularise(P0, 10**le), margin=margin).controller.A)
            np.testing.assert_array_equal(central_controller_poles(P0, 10**le, margin), full)
            np.testing.assert_array_equal(central_controller_poles(P0, 10**le, margin, gamma_opts), full)
    assert len(gamma_opts) == 5  # one optimum per eps_u


def test_central_controller_poles_refuses_what_the_design_refuses(P5):
    from flexdigit.control.synthesis import central_controller_poles

    with pytest.raises(DesignError, match="D12"):
        central_controller_poles(P5, 0.0, 0.1)  # no regularisation: the singular problem


@pytest.mark.slow
def test_lmi_gamma_moves_with_one_ulp_of_the_plant(G):
    # what makes tests/oracles.SOLVER_NOISE_RTOL honest: the two LMI entries of report chapter 4 move under a
    # scaling of A by 1 +- 1e-15, 1 +- 2e-15 (a change of rounding) by less than their band, and the singular
    # problem's by over 0.1 %: that figure is where the solver stops, not a property of the design
    from oracles import SOLVER_NOISE_RTOL

    P5 = thesis_generalized_plant(G, filter_weight(5.0))
    for key, P in (
        ("hinf.gamma_opt_lmi", regularise(P5, 1.0538165452041392e-07)),  # the fitted level in the report
        ("hinf.gamma_lmi_singular", P5),
    ):
        base = hinf_lmi(P).gamma
        moves = [
            abs(hinf_lmi(ct.ss(np.array(P.A) * f, P.B, P.C, P.D)).gamma / base - 1)
            for f in (1 + 1e-15, 1 - 1e-15, 1 + 2e-15, 1 - 2e-15)
        ]
        assert max(moves) < SOLVER_NOISE_RTOL[key] / 2, (key, moves)
        if key == "hinf.gamma_lmi_singular":
            assert max(moves) > 1e-3, moves

"""The two synthesis routes, the regularisation path and the thesis reproduction (chapter 4)."""

import warnings

import control as ct
import numpy as np
import pytest

from flexdigit.control._threads import single_blas_thread
from flexdigit.control.analysis import additive_tolerance, hinf_norm, loop_maps
from flexdigit.control.generalized import filter_weight, regularise, thesis_generalized_plant
from flexdigit.control.reproduce import (
    fit_thesis_regularisation,
    printed_controller,
    singular_infimum_witness,
    sorted_poles,
    thesis_design,
    thesis_plant,
)
from flexdigit.control.synthesis import hinf_lmi, hinf_riccati, reduce_controller, regularisation_path
from flexdigit.errors import DesignError, UnstableError
from flexdigit.reference import thesis_complex, thesis_value

warnings.filterwarnings("ignore", category=UserWarning)

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

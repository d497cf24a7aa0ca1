"""The digit model against physics it did not write: closed forms of beam theory and the elastica.

Tolerances (named, from issue 3): small-deflection tip load 0.5 %, pure-moment circular arc 0.5 % up to 90 deg,
large-deflection elastica 1 %, first bending frequency 1 %. Each test also states the resolution it needs and
checks that the error falls with discretisation (second order: halving h quarters it).
"""

import math

import numpy as np
import pytest

import oracles
from flexdigit.models.beam import Cantilever
from flexdigit.params import RigParams
from flexdigit.twin.digit import Chain, DynamicState
from oracles import elastica_tip_load

SMALL_DEFLECTION_RTOL = 0.005
ARC_RTOL = 0.005
ELASTICA_RTOL = 0.01
FREQUENCY_RTOL = 0.01
N_CELLS = 12  # the resolution these tolerances are checked at

L, EI = 0.24, 205e9 * 12.7e-3 * 0.381e-3**3 / 12  # the digit's strip (table 3.7)
MU = 7850.0 * 12.7e-3 * 0.381e-3  # kg/m


def tip_load_error(n: int) -> float:
    p = 1e-6  # N: tip deflection ~1e-5 L, deep in the linear range
    sol = Chain.uniform(L, EI, n).solve_static(tip_force_n=[[0.0, p]])
    return sol.tip_m[0, 1] / (p * L**3 / (3 * EI)) - 1  # P L^3 / 3EI


def test_small_deflection_tip_load_matches_pl3_over_3ei():
    assert abs(tip_load_error(N_CELLS)) < SMALL_DEFLECTION_RTOL


def test_tip_load_converges_second_order():
    errors = [abs(tip_load_error(n)) for n in (6, 12, 24, 48)]
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(ratios > 3.8)
    assert np.all(ratios < 4.2)  # error ~ h^2


@pytest.mark.parametrize("angle_deg", [10.0, 45.0, 90.0])
def test_pure_tip_moment_bends_a_circular_arc(angle_deg):
    theta = math.radians(angle_deg)
    moment = theta * EI / L  # uniform curvature M/EI (E 3.12), tip angle M L / EI
    chain = Chain.uniform(L, EI, N_CELLS)
    sol = chain.solve_static(tip_moment_nm=moment)
    radius = EI / moment
    exact = np.array([radius * math.sin(theta), radius * (1 - math.cos(theta))])
    assert np.linalg.norm(sol.tip_m[0] - exact) / np.linalg.norm(exact) < ARC_RTOL
    assert sol.psi_rad[0, -1] == pytest.approx(theta, rel=1e-9)  # tip angle exact at any resolution
    # every cell carries the same curvature: springs share the moment equally
    np.testing.assert_allclose(np.diff(sol.psi_rad[0], prepend=0.0) / chain.cell_length_m, 1 / radius, rtol=1e-9)


@pytest.mark.parametrize("alpha2", [1.0, 2.0, 5.0, 10.0])
def test_large_deflection_tip_load_matches_the_elastica(alpha2):
    x_exact, y_exact, theta0 = elastica_tip_load(alpha2)
    sol = Chain.uniform(1.0, 1.0, N_CELLS).solve_static(tip_force_n=[[0.0, -alpha2]])
    assert sol.tip_m[0, 0] == pytest.approx(x_exact, rel=ELASTICA_RTOL)
    assert -sol.tip_m[0, 1] == pytest.approx(y_exact, rel=ELASTICA_RTOL)
    assert -sol.psi_rad[0, -1] == pytest.approx(theta0, rel=ELASTICA_RTOL)


def test_elastica_converges_with_discretisation():
    _, y_exact, _ = elastica_tip_load(10.0)
    errors = [
        abs(-Chain.uniform(1.0, 1.0, n).solve_static(tip_force_n=[[0, -10.0]]).tip_m[0, 1] / y_exact - 1)
        for n in (8, 16, 32)
    ]
    assert errors[0] > 3.5 * errors[1] > 3.5 * 3.5 * errors[2]


def test_elastica_formula_against_quadrature():
    # the oracle itself, against direct quadrature of the first integral EI theta'^2/2 = P (sin theta0 - sin theta)
    from scipy.integrate import quad

    x, y, theta0 = elastica_tip_load(5.0)
    length = quad(lambda t: 1 / math.sqrt(10.0 * (math.sin(theta0) - math.sin(t))), 0, theta0, limit=200)[0]
    depth = quad(lambda t: math.sin(t) / math.sqrt(10.0 * (math.sin(theta0) - math.sin(t))), 0, theta0, limit=200)[0]
    assert length == pytest.approx(1.0, rel=1e-7)
    assert depth == pytest.approx(y, rel=1e-7)


def euler_bernoulli_first_frequency() -> float:
    return oracles.euler_bernoulli_first_frequency(EI, MU, L)  # clamped-free, first root of cos cosh = -1


def test_first_bending_frequency_matches_euler_bernoulli():
    wn, zeta = Chain.uniform(L, EI, N_CELLS, mass_per_length_kg_m=MU).linear_modes()
    assert wn[0] == pytest.approx(euler_bernoulli_first_frequency(), rel=FREQUENCY_RTOL)
    assert zeta[0] == pytest.approx(0.0, abs=1e-12)


def test_frequency_converges_second_order():
    exact = euler_bernoulli_first_frequency()
    errors = [
        abs(Chain.uniform(L, EI, n, mass_per_length_kg_m=MU).linear_modes()[0][0] / exact - 1) for n in (6, 12, 24)
    ]
    assert errors[0] / errors[1] > 3.5
    assert errors[1] / errors[2] > 3.5


def test_small_deflection_limit_agrees_with_models_beam():
    # the Foundation's linear cantilever (models.beam) for the digit's strip: point load mid-span and a tip moment
    beam = Cantilever.from_params(RigParams())
    chain = Chain.uniform(beam.length_m, beam.ei_n_m2, 48)
    x = np.linspace(0.02, beam.length_m, 7)
    sol = chain.solve_static([[0.12]], [[[0.0, 1e-5]]])
    y = chain.positions(sol.psi_rad[0], x)[:, 1]
    np.testing.assert_allclose(y, beam.deflection_point_load(x, 1e-5, 0.12), rtol=2e-3)
    sol = chain.solve_static(tip_moment_nm=1e-6)
    y = chain.positions(sol.psi_rad[0], x)[:, 1]
    np.testing.assert_allclose(y, beam.deflection_tip_moment(x, 1e-6), rtol=2e-3)


def release(chain, h, seconds):
    psi0 = chain.solve_static(tip_force_n=[[0.0, 1e-4]]).psi_rad[0]
    state = DynamicState(chain, psi0)
    tip = [chain.tip(state.psi)[1]]
    for _ in range(int(round(seconds / h))):
        state.step(h, 0.0, 0.0)
        tip.append(chain.tip(state.psi)[1])
    return np.arange(len(tip)) * h, np.array(tip)


def test_time_integration_reproduces_the_linear_mode_without_numerical_damping():
    # identified as a measurement is (identify's lsq fit, an independent least-squares fit of the closed-form
    # second-order release response)
    from flexdigit.identify.identification import identify
    from flexdigit.identify.timeseries import TimeSeries

    base = Chain.uniform(L, EI, 9, mass_per_length_kg_m=MU)
    # a tip mass brings the first mode to the digit's ~10 rad/s
    chain = Chain(
        L,
        base.joint_s_m,
        base.stiffness,
        3e-4 * base.stiffness,
        base.cell_length_m,
        np.append(base.mass_s_m, L),
        np.append(base.mass_kg, 0.02),
        np.append(base.mass_inertia, 0.0),
    )
    wn, zeta = chain.linear_modes()
    t, tip = release(chain, 0.005, 6.0)
    series = TimeSeries.from_arrays(t, tip, channel="tip", source="twin")
    fit = identify(series, "release", method="lsq", t0_s=0.0)  # released at t = 0
    assert fit.wn_rad_s == pytest.approx(wn[0], rel=1e-3)  # trapezoid: period error (w h)^2 / 12
    assert fit.zeta == pytest.approx(zeta[0], rel=0.02)  # no numerical damping on top of the physical


def test_time_integration_is_second_order_in_the_step():
    base = Chain.uniform(L, EI, 6, mass_per_length_kg_m=MU)
    chain = Chain(
        L,
        base.joint_s_m,
        base.stiffness,
        0 * base.stiffness,
        base.cell_length_m,
        np.append(base.mass_s_m, L),
        np.append(base.mass_kg, 0.02),
        np.append(base.mass_inertia, 0.0),
    )
    # large amplitude (tip angle ~ 0.5 rad) so the nonlinear terms count
    psi0 = chain.solve_static(tip_force_n=[[0.0, 0.05]]).psi_rad[0]

    def tip_at(h):
        state = DynamicState(chain, psi0)
        for _ in range(int(round(0.4 / h))):
            state.step(h, 0.0, 0.0)
        return chain.tip(state.psi)

    ref = tip_at(0.0001)
    e1, e2 = (np.linalg.norm(tip_at(h) - ref) for h in (0.004, 0.002))
    assert 3.0 < e1 / e2 < 5.0


def test_unconverged_static_solve_says_so():
    # issue 15: an iterative solver that stops unconverged says so (flag and warning), never a silent answer;
    # 2 Newton steps cannot bend a strip 90 degrees (a large-deflection problem), 80 do
    from flexdigit.errors import ConvergenceWarning
    from flexdigit.twin.digit import Chain

    chain = Chain.uniform(0.24, 0.012, 12)
    with pytest.warns(ConvergenceWarning, match="did not meet its tolerance in 2 iterations"):
        short = chain.solve_static(tip_moment_nm=1.5708 * 0.012 / 0.24, max_iter=2)
    assert not short.converged
    full = chain.solve_static(tip_moment_nm=1.5708 * 0.012 / 0.24)
    assert full.converged
    assert full.iterations < 80
    assert abs(full.tip_m[0, 0] - short.tip_m[0, 0]) > 1e-4  # the unconverged answer really is off

"""Cantilever closed forms against independent oracles: numerical double integration of M/EI (scipy),
textbook tip values, Maxwell-Betti reciprocity and the clamped-free frequency equation (scipy brentq)."""

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid
from scipy.optimize import brentq

from flexdigit.errors import ParameterError
from flexdigit.models.beam import BETA1_L, Cantilever
from flexdigit.params import RigParams

# Tolerances, each with the reason for its size
EXACT_RTOL = 1e-12  # a closed form against the same formula written out here: rounding only
CONTINUITY_RTOL = 1e-6  # the deflection 1e-9 m either side of a point load (its slope times 2e-9 m)
TABLE_3_7_RTOL = 1e-4  # E I of table 3.7, printed to 5 significant digits

BEAM = Cantilever(length_m=0.24, ei_n_m2=0.012, thickness_m=0.381e-3, mass_per_length_kg_m=0.038)


def _integrate_twice(x, curvature):
    """y'' = kappa, y(0) = y'(0) = 0, by the trapezoid rule."""
    slope = cumulative_trapezoid(curvature, x, initial=0.0)
    return cumulative_trapezoid(slope, x, initial=0.0)


@pytest.mark.parametrize(
    "loads",
    [
        {"tip_moment_nm": 2e-3},
        {"tip_load_n": 0.05},
        {"point_loads": ((0.08, 0.1),)},
        {"uniform_load_n_per_m": 0.3},
        {"tip_moment_nm": -1e-3, "point_loads": ((0.02, 0.2), (-0.01, 0.05)), "uniform_load_n_per_m": 0.1},
    ],
)
def test_deflection_is_double_integral_of_curvature(loads):
    x = np.linspace(0.0, BEAM.length_m, 20001)
    y_numeric = _integrate_twice(x, BEAM.curvature(x, **loads))
    y_closed = BEAM.deflection(x, **loads)
    assert np.max(np.abs(y_closed - y_numeric)) < 1e-6 * max(np.max(np.abs(y_closed)), 1e-12) + 1e-12


def test_textbook_tip_values():
    L, EI = BEAM.length_m, BEAM.ei_n_m2
    assert BEAM.deflection_tip_load(L, 0.05) == pytest.approx(0.05 * L**3 / (3 * EI), rel=EXACT_RTOL)
    assert BEAM.deflection_uniform_load(L, 0.3) == pytest.approx(0.3 * L**4 / (8 * EI), rel=EXACT_RTOL)
    assert BEAM.deflection_tip_moment(L, 2e-3) == pytest.approx(2e-3 * L**2 / (2 * EI), rel=EXACT_RTOL)  # E 3.13
    assert BEAM.slope(L, tip_load_n=0.05) == pytest.approx(0.05 * L**2 / (2 * EI), rel=EXACT_RTOL)
    assert BEAM.tip_stiffness_n_per_m() == pytest.approx(3 * EI / L**3)
    m = BEAM.tip_moment_for_deflection_nm(0.01)
    assert BEAM.deflection_tip_moment(L, m) == pytest.approx(0.01, rel=EXACT_RTOL)


def test_maxwell_betti_reciprocity():
    a, b = 0.07, 0.19
    assert BEAM.deflection_point_load(b, 1.0, a) == pytest.approx(BEAM.deflection_point_load(a, 1.0, b), rel=EXACT_RTOL)


def test_point_load_is_continuous_and_zero_moment_beyond_it():
    a = 0.1
    eps = 1e-9
    y = BEAM.deflection_point_load([a - eps, a + eps], 0.1, a)
    assert y[0] == pytest.approx(y[1], rel=CONTINUITY_RTOL)
    assert BEAM.moment(0.2, point_loads=((0.1, a),)) == 0.0


def test_surface_strain_is_curvature_times_half_thickness():
    kappa = BEAM.curvature(0.045, tip_moment_nm=1e-3)
    assert kappa == pytest.approx(1e-3 / 0.012)
    assert BEAM.surface_strain(0.045, tip_moment_nm=1e-3) == pytest.approx(kappa * 0.381e-3 / 2)


def test_first_frequency_uses_root_of_clamped_free_equation():
    root = brentq(lambda b: 1 + math.cos(b) * math.cosh(b), 1.0, 3.0, xtol=1e-14)
    assert BETA1_L == pytest.approx(root, rel=EXACT_RTOL)
    expected = root**2 * math.sqrt(0.012 / (0.038 * 0.24**4))
    assert BEAM.first_natural_frequency_rad_s() == pytest.approx(expected, rel=EXACT_RTOL)


def test_from_params_uses_table_3_7_stiffness():
    b = Cantilever.from_params(RigParams(), length="digit")
    assert b.length_m == 0.270
    assert b.ei_n_m2 == pytest.approx(205e9 * 5.8532e-14, rel=TABLE_3_7_RTOL)  # table 3.7


def test_bad_input_names_the_culprit():
    with pytest.raises(ParameterError, match="x_m"):
        BEAM.deflection(0.5, tip_load_n=1.0)
    with pytest.raises(ParameterError, match="length_m"):
        Cantilever(length_m=-1, ei_n_m2=1, thickness_m=1)
    with pytest.raises(ParameterError, match="length"):
        Cantilever.from_params(length="tip")

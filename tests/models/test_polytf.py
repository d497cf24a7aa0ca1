"""PolyTF (the models' numpy SISO transfer function) against python-control, the independent oracle, on seeded
random transfer functions; and the plant's python-control views (tf, ss, components) against its numpy form."""

import control
import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.models.plant import build_plant, companion_ss
from flexdigit.models.polytf import PolyTF, ctrb, obsv

pytestmark = pytest.mark.blas  # run again under other OpenBLAS kernels by `make test` (docs/guide/reliability.md)

# Tolerances, each with the reason for its size
POLY_RTOL = 1e-12  # the same polynomial products and sums as python-control: rounding only
ROOTS_RTOL = 1e-8  # roots of the same polynomials (python-control rebuilds a common denominator first)

SEEDS = range(20)


def _random_tf(rng, max_order=4):
    """A proper SISO TF with a random stable denominator (roots in the left half plane) and random numerator."""
    n = int(rng.integers(1, max_order + 1))
    poles = -rng.uniform(0.1, 30.0, n) + 1j * np.where(rng.random(n) < 0.5, 0.0, rng.uniform(0, 20, n))
    den = np.real(
        np.poly(np.concatenate([poles[poles.imag == 0], poles[poles.imag != 0], poles[poles.imag != 0].conj()]))
    )
    num = rng.normal(size=int(rng.integers(1, den.size)))
    return num * float(rng.uniform(0.5, 50.0)), den * float(rng.uniform(0.5, 2.0))


def _coef_close(a, b):
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    return a.shape == b.shape and np.allclose(a, b, rtol=POLY_RTOL, atol=POLY_RTOL * np.abs(b).max())


def _roots_close(ours, theirs):
    ours, theirs = np.sort_complex(np.asarray(ours)), np.sort_complex(np.asarray(theirs, complex))
    return ours.shape == theirs.shape and np.allclose(ours, theirs, rtol=ROOTS_RTOL, atol=ROOTS_RTOL)


@pytest.mark.parametrize("seed", SEEDS)
def test_products_gains_and_feedback_match_python_control(seed):
    rng = np.random.default_rng(seed)
    (n1, d1), (n2, d2) = _random_tf(rng), _random_tf(rng)
    k = float(rng.uniform(0.1, 10.0))
    ours = (k * PolyTF(n1, d1) * PolyTF(n2, d2)).feedback()
    theirs = control.feedback(k * control.tf(n1, d1) * control.tf(n2, d2), 1)
    assert _coef_close(ours.num, np.trim_zeros(theirs.num[0][0], "f"))
    assert _coef_close(ours.den, theirs.den[0][0])
    assert ours.dcgain() == pytest.approx(float(np.real(theirs.dcgain())), rel=POLY_RTOL)
    assert _roots_close(ours.poles(), theirs.poles())
    assert _roots_close(ours.zeros(), theirs.zeros())
    s = 1j * np.array([0.3, 3.0, 30.0])
    assert np.allclose(ours(s), theirs(s), rtol=1e-10)


@pytest.mark.parametrize("seed", SEEDS)
def test_ctrb_obsv_match_python_control(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 6))
    a, b, c = rng.normal(size=(n, n)), rng.normal(size=(n, 1)), rng.normal(size=(1, n))
    assert np.allclose(ctrb(a, b), control.ctrb(a, b), rtol=POLY_RTOL, atol=0)
    assert np.allclose(obsv(a, c), control.obsv(a, c), rtol=POLY_RTOL, atol=0)


def test_to_control_round_trip_and_numpy_scalars():
    g = PolyTF([0.0, 2.0], [1.0, 3.0, 2.0])  # the leading zero is dropped, as python-control does
    assert g.num.tolist() == [2.0]
    assert PolyTF.from_control(g.to_control()).den.tolist() == [1.0, 3.0, 2.0]
    assert (np.float64(3.0) * g).num.tolist() == [6.0]  # not an object array: numpy defers to PolyTF
    assert PolyTF([1.0], [1.0, 0.0]).dcgain() == np.inf  # integrator


@pytest.mark.parametrize("num, den", [([1.0], [0.0, 0.0]), ([np.nan], [1.0, 1.0]), ([[1.0]], [1.0])])
def test_bad_coefficients_are_refused(num, den):
    with pytest.raises(ParameterError, match="PolyTF"):
        PolyTF(num, den)


@pytest.mark.parametrize(
    "variant, output", [("printed", "deflection_sg1_m"), ("consistent", "tip_rotation_rad"), ("consistent", "gauge_v")]
)
def test_plant_control_views_match_its_numpy_form(variant, output):
    g = build_plant(variant, output=output)
    assert isinstance(g.tf, control.TransferFunction)
    assert isinstance(g.ss, control.StateSpace)
    assert _coef_close(g.tf.den[0][0], g.poly.den)
    assert _coef_close(g.tf.num[0][0], g.poly.num)
    assert g.ss.nstates == g.order == 4
    # the realisation is of the same G: python-control's own state-space -> transfer function conversion
    back = control.ss2tf(g.ss)
    assert _coef_close(back.den[0][0] / back.den[0][0][0], g.poly.den)
    w = 1j * np.array([0.0, 0.5, 5.0, 50.0])
    assert np.allclose([complex(g.ss(x)) for x in w], g.poly(w), rtol=1e-9)
    for name, value in g.factors.items():
        if isinstance(value, PolyTF):
            assert _coef_close(g.components[name].den[0][0], value.den)
        else:
            assert g.components[name] == value
    k = 1.7699
    assert _coef_close(g.closed_loop(k).den[0][0], control.feedback(k * g.tf, 1).den[0][0])
    if variant == "printed":
        assert np.array_equal(companion_ss(g.tf).A, g.ss.A)  # 3.5's companion form either way

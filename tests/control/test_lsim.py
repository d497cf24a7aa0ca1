"""The compiled step response against python-control's own (the reference it replaces) and closed forms."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from flexdigit.control._lsim import step_output
from flexdigit.control.discretise import discretise
from flexdigit.errors import DesignError
from flexdigit.reference import thesis_value

# Tolerances, each with the reason for its size
SAME_RECURSION_RTOL = 1e-12  # python-control's recursion, summed in another order: rounding over 20,000 steps
CLOSED_FORM_RTOL = 1e-9  # expm-based simulation of a first-order lag against 1 - exp(-t/tau)

K39 = ct.tf(thesis_value("hinf.k_39hz_num"), thesis_value("hinf.k_39hz_den"))  # 4.7 as printed
G = ct.tf([48.7 * 103.3], np.polymul([1.0, 17.8], [1.0, 0.543, 103.3]))  # a printed-plant-like third order


def _random_stable(rng, n):
    """A seeded random stable SISO system with n states (poles in [-20, -0.5] +- j 30), D nonzero."""
    A = np.diag(-rng.uniform(0.5, 20.0, n))
    for i in range(0, n - 1, 2):
        A[i, i + 1], A[i + 1, i] = 30 * rng.uniform(), -30 * rng.uniform()
    T = rng.normal(size=(n, n)) + n * np.eye(n)
    return ct.ss(T @ A @ np.linalg.inv(T), rng.normal(size=(n, 1)), rng.normal(size=(1, n)), rng.normal(size=(1, 1)))


def _reference(sys, t):
    return np.squeeze(ct.step_response(sys, T=t).outputs)


@pytest.mark.parametrize("seed", range(5))
def test_continuous_equals_python_control(seed):
    rng = np.random.default_rng(seed)
    sys = _random_stable(rng, int(rng.integers(1, 9)))
    t = np.linspace(0.0, 3.0, 3001)
    ref = _reference(sys, t)
    np.testing.assert_allclose(
        step_output(sys, t), ref, rtol=SAME_RECURSION_RTOL, atol=SAME_RECURSION_RTOL * np.abs(ref).max()
    )


@pytest.mark.parametrize(
    ("period_s", "method"), [(0.0006, "tustin"), (0.005, "forward_euler"), (0.02, "forward_euler")]
)
def test_sampled_loop_equals_python_control(period_s, method):
    # the chapter 5 loops, the last one unstable (it grows to ~1e51 in 2 s): every sample, rounding only
    Gd = ct.sample_system(ct.ss(G), period_s, method="zoh")
    closed = ct.feedback(ct.series(discretise(ct.ss(K39), period_s, method), Gd), 1)
    t = np.arange(0.0, 2.0 + period_s / 2, period_s)
    ref = _reference(closed, t)
    ours = step_output(closed, t)
    assert ours.shape == ref.shape
    np.testing.assert_allclose(ours, ref, rtol=SAME_RECURSION_RTOL, atol=SAME_RECURSION_RTOL * np.abs(ref[:10]).max())


def test_first_order_lag_closed_form():
    t = np.linspace(0.0, 5.0, 501)
    np.testing.assert_allclose(
        step_output(ct.tf([2.0], [0.5, 1.0]), t), 2 * (1 - np.exp(-t / 0.5)), rtol=CLOSED_FORM_RTOL, atol=1e-12
    )


def test_static_gain_is_constant():
    np.testing.assert_array_equal(step_output(ct.ss([], [], [], [[3.5]]), np.linspace(0, 1, 11)), np.full(11, 3.5))


@pytest.mark.parametrize(
    ("sys", "t", "match"),
    [
        (ct.tf([[[1.0]], [[1.0]]], [[[1.0, 1.0]], [[1.0, 2.0]]]), np.linspace(0, 1, 5), "single-input"),
        (ct.tf([1.0], [1.0, 1.0]), np.array([0.0, 0.1, 0.3]), "equally spaced"),
        (ct.tf([1.0], [1.0, 1.0]), np.array([0.0]), "two time points"),
        (ct.tf([1.0], [1.0, 0.5], 0.1), np.linspace(0, 1, 21), "period"),
    ],
)
def test_bad_input_is_named(sys, t, match):
    with pytest.raises(DesignError, match=match):
        step_output(sys, t)

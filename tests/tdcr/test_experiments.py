"""The release test of a tendon robot: its first frequency against Euler-Bernoulli, and the pencil estimator.

- A uniform cantilever without tendons (40 elements, the rao2021 backbone, 400 mm) released from 1 % of its length
  rings at ``1.8751^2 sqrt(EI / rho A) / L^2`` (``oracles``): within ``FREQUENCY_RTOL`` (measured -0.08 %: the
  discrete rod's element length, second order, and BDF2's dispersion at 200 steps a period); at 10 elements the
  discretisation error is measured -0.87 % (and must be larger than at 40: it converges).
- The matrix pencil reads a synthetic sum of a constant and two tones to round-off (``PENCIL_RTOL``), the smaller
  tone ignored.
"""

import math

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.tdcr import Robot, Segment, euler_bernoulli_first_hz, pencil_frequency_hz, release_test
from oracles import euler_bernoulli_first_frequency

FREQUENCY_RTOL = 3e-3
PENCIL_RTOL = 1e-9


def test_a_released_rod_rings_at_its_first_bending_frequency():
    rod = Robot(name="rod", segments=(Segment(0.4, 40),))
    b = rod.backbone
    w1 = euler_bernoulli_first_frequency(b.bending_torsion_stiffness[0], b.mass_per_length_kg_m, rod.length_m)
    assert euler_bernoulli_first_hz(rod) == pytest.approx(w1 / (2 * math.pi), rel=1e-9)  # the oracle root has 11 digits
    test = release_test(rod, direction=(1.0, 1.0, 0.0))
    assert test.motion.converged
    assert test.first_frequency_hz == pytest.approx(w1 / (2 * math.pi), rel=FREQUENCY_RTOL)
    coarse = release_test(Robot(name="coarse", segments=(Segment(0.4, 10),)))
    assert abs(coarse.first_frequency_hz / test.euler_bernoulli_hz - 1) > abs(
        test.first_frequency_hz / test.euler_bernoulli_hz - 1
    )
    # held by a tip force of 3 EI d / L^3 for d = 1 % of L: the straight cantilever's tip deflection, to first order
    np.testing.assert_allclose(test.initial.tip_position_m[:2], [0.004 / math.sqrt(2)] * 2, rtol=2e-3)


def test_the_pencil_reads_the_strongest_tone():
    t = np.arange(900) * 2e-3
    y = 0.3 + 1e-3 * np.cos(2 * np.pi * 1.7 * t + 0.4) + 2e-5 * np.sin(2 * np.pi * 19.0 * t)
    assert pencil_frequency_hz(y, 2e-3) == pytest.approx(1.7, rel=PENCIL_RTOL)
    with pytest.raises(ParameterError, match="does not oscillate"):
        pencil_frequency_hz(np.exp(-t), 2e-3)


def test_bad_release_arguments_are_refused():
    rod = Robot(name="rod", segments=(Segment(0.2, 10),))
    with pytest.raises(ParameterError, match="tip_deflection_m"):
        release_test(rod, tip_deflection_m=0.5)
    with pytest.raises(ParameterError, match="direction"):
        release_test(rod, direction=(0.0, 0.0, 0.0))

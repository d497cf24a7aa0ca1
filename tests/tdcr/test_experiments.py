"""The release test of a tendon robot: its first frequency against Euler-Bernoulli, and the pencil estimator.

- A uniform cantilever without tendons (40 elements, the rao2021 backbone, 400 mm) released from 1 % of its length
  rings at ``1.8751^2 sqrt(EI / rho A) / L^2`` (``oracles``): within ``FREQUENCY_RTOL`` (measured -0.08 %: the
  discrete rod's element length, second order, and BDF2's dispersion at 200 steps a period); at 10 elements the
  discretisation error is measured -0.87 % (and must be larger than at 40: it converges).
- The matrix pencil reads a synthetic sum of a constant and two tones to round-off (``PENCIL_RTOL``), the smaller
  tone ignored.
"""

import dataclasses
import math

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.tdcr import ROBOTS, Robot, Segment, euler_bernoulli_first_hz, pencil_frequency_hz, release_test, simulate
from flexdigit.tdcr.experiments import _held
from oracles import euler_bernoulli_first_frequency

FREQUENCY_RTOL = 3e-3
PENCIL_RTOL = 1e-9
REST_ATOL_M = 1e-7


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


def test_a_held_robot_the_discrete_newton_misses_is_relaxed_to_rest():
    """A row of the rao2021-tolerances study where the discrete rod's Newton finds no rest from the shot statics
    (so simulate would start it 17 mm from its rest, and its first frequency came out 0.7 % high): the release
    starts from the relaxed rest instead, which the held loads keep still (``REST_ATOL_M``: the relaxation's 4
    periods leave ~1e-9 m), and its frequency is the one found by relaxing it by hand (3 s at damping 0.05 s in
    steps of 2 ms, then released: 3.2718 Hz; 3.2953 Hz from the shot statics)."""
    rao = ROBOTS["rao2021"]
    backbone = dataclasses.replace(rao.backbone, youngs_modulus_pa=48.654e9, radius_m=0.687625e-3)
    tendons = tuple(dataclasses.replace(t, offset_m=t.offset_m * 1.0198) for t in rao.tendons)
    robot = dataclasses.replace(rao, backbone=backbone, tendons=tendons)
    tensions = [4.10303317, 0, 0, 0, 2.10303317, 0]
    f0 = euler_bernoulli_first_hz(robot)
    force = [3 * backbone.bending_torsion_stiffness[0] * 0.004 / 0.4**3, 0.0, 0.0]
    held = _held(robot, tensions, np.array(force), None, 1 / (200 * f0), f0)
    assert held.loads is None  # relaxed, not the shot statics
    still = simulate(robot, held, 1 / f0, dt_s=1 / (200 * f0), tensions_n=tensions, tip_force_n=force)
    assert np.abs(still.tip_positions_m - still.tip_positions_m[0]).max() < REST_ATOL_M
    assert release_test(robot, tensions).first_frequency_hz == pytest.approx(3.2716, rel=1e-3)

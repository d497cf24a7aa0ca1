"""The chain kernel's speed-ups keep its answers: against the kernel as it was before them, and its Newton's cost.

The kernel before (``benchmarks/tdcr_kernel_before.py``, f3eec46: IEEE arithmetic, no series, no registers) is
the reference: the faster kernel's trajectory of the benchmark's rod (``benchmarks/bench_tdcr.py``: 40 nodes,
released from a 2 mN diagonal tip load, 1 ms steps) must be nearer to it than the Newton's own tolerance lets
either be from the converged trajectory (the same run at ``tol = 1e-10``, the floor the finite-difference
Jacobian sets): the speed-ups change round-off, never the method. Measured over 0.3 s: the two kernels 1.1e-11 m
apart (frames 4.6e-11), each 3.1e-6 m from the converged trajectory. Slow the first time only: numba compiles the
kernel before (~50 s on a loaded machine; cached after).
"""

import importlib
import math
from pathlib import Path
from unittest import mock

import numpy as np
import pytest

from flexdigit.tdcr import Robot, Segment, dynamics, simulate, solve_statics

ROD = Robot(name="rod", segments=(Segment(0.4, 39),))  # 40 nodes with the clamp, as benchmarks/bench_tdcr.py
PLANE = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
#: The faster kernel's distance from the one before, as a share of the distance the Newton's tolerance allows
#: between either and the converged trajectory (round-off is ~1e-6 of it)
SHARE_OF_TOLERANCE = 1e-3
#: Newton iterations a step of the rod, on average over 1 s: one residual and one banded solve a step, and every
#: MEASURE-th step a second to measure the chord Newton's rate (1 + 1/8), a few more where a first update is not
#: yet small enough; measured 1.164
MEAN_ITERATIONS = 1.2


def _kernel_before(monkeypatch):
    """The kernel before, imported as the benchmark does (by its package: numba's cache finds it again by name)."""
    monkeypatch.syspath_prepend(str(Path(__file__).parents[2]))
    return importlib.import_module("benchmarks.tdcr_kernel_before")


@pytest.fixture(scope="module")
def bent():
    return solve_statics(ROD, [], tip_force_n=0.002 * PLANE)


@pytest.mark.slow
def test_the_faster_kernel_follows_the_kernel_before_it(bent, monkeypatch):
    now = simulate(ROD, bent, 0.3)
    with mock.patch.object(dynamics, "_chain_kernel", _kernel_before(monkeypatch)):
        before = simulate(ROD, bent, 0.3)
        converged = simulate(ROD, bent, 0.3, tol=1e-10)
    assert now.converged
    assert before.converged
    assert converged.converged
    allowed = np.abs(before.positions_m - converged.positions_m).max()
    assert allowed > 1e-7  # the tolerance's error is there to compare with (3.1e-6 m)
    gap = np.abs(now.positions_m - before.positions_m).max()
    assert gap < SHARE_OF_TOLERANCE * allowed
    element_m = ROD.length_m / 39  # a frame's error is about a position's over an element
    np.testing.assert_allclose(now.rotations, before.rotations, rtol=0, atol=SHARE_OF_TOLERANCE * allowed / element_m)


def test_a_step_of_the_vibrating_rod_is_about_one_newton_iteration(bent):
    motion = simulate(ROD, bent, 1.0)
    assert motion.converged
    assert motion.iterations.mean() < MEAN_ITERATIONS
    assert motion.iterations.max() <= 3

"""The chain kernel's speed-ups keep its answers: against the kernel as it was before them, and its Newton's cost.

The kernel before (``benchmarks/tdcr_kernel_before.py``, f3eec46: IEEE arithmetic, no series, no registers) is
the reference: the faster kernel's trajectory of the benchmark's rod (``benchmarks/bench_tdcr.py``: 40 nodes,
released from a 2 mN diagonal tip load, 1 ms steps) must be nearer to it than the Newton's own tolerance lets
either be from the converged trajectory (the same run at ``tol = 1e-10``, the floor the finite-difference
Jacobian sets): the speed-ups change round-off, never the method. Measured over 0.3 s: the two kernels 1.1e-11 m
apart (frames 4.6e-11), each 3.1e-6 m from the converged trajectory.

The kernel before's answer on this case is stored (``tests/data/chain_kernel_before.npz``, written by
``tests/data/update_chain_kernel_before.py`` from ``benchmarks/tdcr_kernel_before.py``; the file holds the kernel
file's SHA-256, the commit, numba's version and the case): compiling that kernel was ~60 s of this file's 66 on every
fresh clone. The test refuses a file made from another kernel file or for another case; the stored answer, made again
from a fresh compile of that kernel (``update_chain_kernel_before.py --check``), was the same to the bit.
"""

import hashlib
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from flexdigit.tdcr import Robot, Segment, simulate, solve_statics

ROD = Robot(name="rod", segments=(Segment(0.4, 39),))  # 40 nodes with the clamp, as benchmarks/bench_tdcr.py
PLANE = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
#: The faster kernel's distance from the one before, as a share of the distance the Newton's tolerance allows
#: between either and the converged trajectory (round-off is ~1e-6 of it)
SHARE_OF_TOLERANCE = 1e-3
#: Newton iterations a step of the rod, on average over 1 s: one residual and one banded solve a step, and every
#: MEASURE-th step a second to measure the chord Newton's rate (1 + 1/8), a few more where a first update is not
#: yet small enough; measured 1.164
MEAN_ITERATIONS = 1.2
ROOT = Path(__file__).resolve().parents[2]
#: The kernel before's answer on this file's case (tests/data/update_chain_kernel_before.py)
BEFORE = ROOT / "tests" / "data" / "chain_kernel_before.npz"
#: How far the rod's start may be from the one the stored answer started from: round-off, a thousandth of the gap
#: the comparison allows (0 on the machine that wrote it)
START_SHARE = 1e-3


def _kernel_before() -> dict:
    """The stored answer of ``benchmarks/tdcr_kernel_before.py``, checked to be that file's, on this case."""
    with np.load(BEFORE) as stored:
        before = {key: stored[key] for key in stored.files}
    kernel = hashlib.sha256((ROOT / "benchmarks" / "tdcr_kernel_before.py").read_bytes()).hexdigest()
    assert str(before["kernel_sha256"]) == kernel, "benchmarks/tdcr_kernel_before.py changed: regenerate the file"
    assert float(before["length_m"]) == ROD.length_m
    assert int(before["elements"]) == 39
    np.testing.assert_array_equal(before["tip_force_n"], 0.002 * PLANE)
    assert float(before["duration_s"]) == 0.3
    return before


@pytest.fixture(scope="module")
def bent():
    return solve_statics(ROD, [], tip_force_n=0.002 * PLANE)


@pytest.mark.slow  # the faster kernel compiles here on a fresh clone (~30 s CPU), unless another file did
def test_the_faster_kernel_follows_the_kernel_before_it(bent):
    before = _kernel_before()
    now = simulate(ROD, bent, 0.3)
    assert now.converged
    allowed = float(before["tolerance_error_m"])  # the kernel before's distance from its run at tol = 1e-10
    assert allowed > 1e-7  # the tolerance's error is there to compare with (3.1e-6 m)
    start = np.abs(bent.positions_m - before["initial_positions_m"]).max()
    assert start < START_SHARE * SHARE_OF_TOLERANCE * allowed, "solve_statics moved the start: regenerate the file"
    assert now.positions_m.shape == before["positions_m"].shape
    gap = np.abs(now.positions_m - before["positions_m"]).max()
    assert gap < SHARE_OF_TOLERANCE * allowed
    element_m = ROD.length_m / 39  # a frame's error is about a position's over an element
    frames = Rotation.from_rotvec(before["rotation_vectors"].reshape(-1, 3)).as_matrix().reshape(now.rotations.shape)
    np.testing.assert_allclose(now.rotations, frames, rtol=0, atol=SHARE_OF_TOLERANCE * allowed / element_m)


def test_a_step_of_the_vibrating_rod_is_about_one_newton_iteration(bent):
    motion = simulate(ROD, bent, 1.0)
    assert motion.converged
    assert motion.iterations.mean() < MEAN_ITERATIONS
    assert motion.iterations.max() <= 3

"""The 3D rod's dynamics against beam theory and its own statics.

- A cantilever (the rao2021 backbone, 400 mm) released from a tip load in a diagonal plane oscillates at its first
  bending frequency, Euler-Bernoulli's ``1.8751^2 sqrt(EI / (rho A L^4))`` (``oracles``), within ``FREQUENCY_RTOL``
  (issue 26: 0.5 %), and in the plane it was bent in. BDF2's own dispersion at the step used, ``w dt = 0.045``, is
  -0.07 % (the root of ``(3 z^2 - 4 z + 1) / 2 = i w dt z^2``); rotary inertia and shear shift the frequency by
  ~(r/L)^2 ~ 3e-6.
- With Kelvin-Voigt damping proportional to the stiffness (``beta K``), every mode of a beam is damped with the
  ratio ``beta w / 2``: the first mode's amplitude, and so its energy (twice the rate), decays as
  ``exp(-beta w1^2 t / 2)``, within ``DECAY_RTOL`` (measured: 0.1 %).
- A static equilibrium is a rest state of the dynamics: rao2021 held by its tendons does not move.
"""

import math

import numpy as np
import pytest
from scipy.optimize import curve_fit

from flexdigit.errors import ParameterError
from flexdigit.tdcr import ROBOTS, Robot, Segment, solve_statics
from flexdigit.tdcr.dynamics import simulate
from oracles import euler_bernoulli_first_frequency

FREQUENCY_RTOL = 0.005
DECAY_RTOL = 0.02
REST_ATOL_M = 1e-9  # 2.5e-9 of the length: a step's Newton stops at updates of 1e-8 of the length
SETTLED_ATOL_M = 1e-5  # 2.5e-5 of the length, after 1.5 s

ROD = Robot(name="rod", segments=(Segment(0.4, 40),))


def test_released_cantilever_oscillates_at_its_first_bending_frequency():
    b = ROD.backbone
    w1 = euler_bernoulli_first_frequency(b.bending_torsion_stiffness[0], b.mass_per_length_kg_m, ROD.length_m)
    w2 = w1 * (4.6940911 / 1.8751040687) ** 2
    plane = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    bent = solve_statics(ROD, [], tip_force_n=0.002 * plane)  # tip ~4 mm off axis: the linear range
    motion = simulate(ROD, bent, 1.2, dt_s=0.045 / w1)
    assert motion.converged
    x = motion.tip_positions_m @ plane
    across = motion.tip_positions_m @ np.array([-1.0, 1.0, 0.0]) / math.sqrt(2)
    assert abs(across).max() < 1e-9 * ROD.length_m  # stays in the plane it was bent in

    def modes(t, a1, b1, f1, a2, b2, f2, decay, offset):  # the first two modes (a tip load excites both)
        second = np.exp(-decay * t) * (a2 * np.cos(f2 * t) + b2 * np.sin(f2 * t))
        return a1 * np.cos(f1 * t) + b1 * np.sin(f1 * t) + second + offset

    fit, _ = curve_fit(modes, motion.t_s, x, p0=[x[0], 0, w1, 0, 0, w2, 0, 0], maxfev=20000)
    assert fit[2] == pytest.approx(w1, rel=FREQUENCY_RTOL)
    assert abs(fit[7]) < 1e-3 * abs(x[0])  # about the straight rod


def test_stiffness_proportional_damping_decays_the_first_mode_at_beta_w1_squared_over_2():
    from scipy.signal import find_peaks

    b = ROD.backbone
    w1 = euler_bernoulli_first_frequency(b.bending_torsion_stiffness[0], b.mass_per_length_kg_m, ROD.length_m)
    beta = 2 * 0.02 / w1  # the first mode's damping ratio 2 %
    plane = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    bent = solve_statics(ROD, [], tip_force_n=0.002 * plane)
    motion = simulate(ROD, bent, 3.0, dt_s=0.045 / w1, damping_s=beta)
    assert motion.converged
    x = motion.tip_positions_m @ plane
    peaks, _ = find_peaks(x)
    peaks = peaks[motion.t_s[peaks] > 0.5]  # the second mode (damped 6x faster, 12 %) gone by then
    rate = -np.polyfit(motion.t_s[peaks], np.log(x[peaks]), 1)[0]
    assert rate == pytest.approx(beta * w1**2 / 2, rel=DECAY_RTOL)
    energy = motion.kinetic_energy_j(ROD)
    late, early = energy[motion.t_s > 2.5].max(), energy[(motion.t_s > 0.5) & (motion.t_s < 1.0)].max()
    assert late < early * math.exp(-2 * rate * 1.5) * 1.2  # the energy at twice the amplitude's rate


def test_a_static_equilibrium_is_at_rest():
    robot = ROBOTS["rao2021"]
    held = solve_statics(robot, [4, 0, 0, 0, 2, 0])
    motion = simulate(robot, held, 0.02, dt_s=1e-3, tensions_n=[4, 0, 0, 0, 2, 0])
    assert motion.converged
    drift = np.abs(motion.positions_m - motion.positions_m[0]).max()
    assert drift < REST_ATOL_M
    assert motion.kinetic_energy_j(robot).max() < 1e-12


def test_the_shot_continuous_rod_at_its_equilibrium_is_at_rest():
    robot = ROBOTS["rao2021"]
    held = solve_statics(robot, [4, 0, 0, 0, 2, 0])
    motion = simulate(robot, held, 0.01, dt_s=1e-3, tensions_n=[4, 0, 0, 0, 2, 0], method="shooting")
    assert motion.converged
    assert np.abs(motion.positions_m - held.positions_m).max() < REST_ATOL_M


@pytest.mark.parametrize(("nodes_per_disk", "bound_m"), [(1, 12e-3), (2, 3e-3), (4, 0.75e-3)])
def test_the_discrete_rods_rest_approaches_the_continuous_equilibrium(nodes_per_disk, bound_m):
    """The discrete rod settles (before release) near the shot continuous rod on rao2021 (tendons on polylines
    through the disks), the gap shrinking as the elements' length squared: 11.2, 2.80, 0.71 mm at 1, 2, 4 elements
    a disk (measured)."""
    robot = ROBOTS["rao2021"]
    held = solve_statics(robot, [4, 0, 0, 0, 2, 0], nodes_per_disk=nodes_per_disk)
    motion = simulate(robot, held, 0.002, dt_s=1e-3, tensions_n=[4, 0, 0, 0, 2, 0], nodes_per_disk=nodes_per_disk)
    assert np.linalg.norm(motion.tip_positions_m[0] - held.tip_position_m) < bound_m


def test_rao2021_pulled_from_straight_settles_where_it_rests_under_those_tensions():
    """The step that the shooting dynamics could not take (4 and 2 N at once from slack tendons): the disks turn
    by ~0.1 rad in the first step. Damped (beta = 50 ms: the first mode critically, ~20 rad/s), it settles on the
    discrete rod's own equilibrium under those tensions."""
    robot = ROBOTS["rao2021"]
    tensions = [4, 0, 0, 0, 2, 0]
    motion = simulate(robot, solve_statics(robot, [0] * 6), 1.5, dt_s=1e-3, tensions_n=tensions, damping_s=0.05)
    assert motion.converged
    rest = simulate(robot, solve_statics(robot, tensions), 1e-3, dt_s=1e-3, tensions_n=tensions)
    assert np.linalg.norm(motion.tip_positions_m[-1] - rest.tip_positions_m[0]) < SETTLED_ATOL_M


def test_initial_state_must_match_the_robot():
    other = solve_statics(Robot(name="short", segments=(Segment(0.1, 5),)), [])
    with pytest.raises(ParameterError, match="'initial' parameter of simulate"):
        simulate(ROD, other, 0.01)


def test_a_nodes_frame_is_half_way_between_its_elements():
    """Against scipy's rotations: the half turn ``Q_a exp(log(Q_a^T Q_b) / 2)`` for turns up to 2.5 rad."""
    from scipy.spatial.transform import Rotation

    from flexdigit.tdcr import _chain_kernel

    rng = np.random.default_rng(7)
    first = Rotation.random(20, random_state=7)
    turn = Rotation.from_rotvec(rng.normal(size=(20, 3)) * 0.8)
    pairs = np.ascontiguousarray(np.stack([first.as_matrix(), (first * turn).as_matrix()], axis=1))
    out = np.empty((20, 3, 3, 3))
    _chain_kernel.node_frames(pairs, out)
    expected = (first * Rotation.from_rotvec(turn.as_rotvec() / 2)).as_matrix()
    np.testing.assert_allclose(out[:, 1], expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[:, 0], np.broadcast_to(np.eye(3), (20, 3, 3)), rtol=0, atol=0)


@pytest.mark.parametrize(("robot", "tensions_n"), [(ROBOTS["rao2021"], [1, 2, 3, 4, 5, 6]), (ROD, [])])
def test_the_step_jacobian_fits_in_the_band_the_kernel_assumes(robot, tensions_n):
    """A dense forward-difference Jacobian of one step's residual (every unknown perturbed alone; damping,
    gravity, tip force and moment on): no entry outside the half bandwidth :func:`_discrete_model` gives, the
    outermost diagonal used (the band is no wider than it must be). A band too narrow would not give wrong
    answers, only a Newton that converges slowly or not at all."""
    from flexdigit.tdcr import _chain_kernel
    from flexdigit.tdcr.dynamics import _discrete_model, _element_frames
    from flexdigit.tdcr.statics import _nodes

    nodes, ends = _nodes(robot, 1)
    sol = solve_statics(robot, tensions_n)
    loads = (np.asarray(tensions_n, float), np.array([0, 0, -0.1]), np.array([0.01, 0, 0]), np.array([0, 1e-3, 0]))
    model, mass, inertia, hb = _discrete_model(robot, nodes, ends, loads)
    x, q = sol.positions_m, np.ascontiguousarray(_element_frames(sol.rotations))
    n = q.shape[0]
    rng = np.random.default_rng(3)
    z = rng.normal(size=6 * n) * 0.1
    history = tuple(rng.normal(size=shape) for shape in ((n, 3), (n + 1, 3), (n, 3), (n, 3), (n, 3)))
    psih, vh, wh, hsig, hkap = (h * 0.01 if i == 0 else h for i, h in enumerate(history))
    scratch = (np.empty((n + 1, 3)), np.empty((n, 3, 3)), np.empty((n + 1, 3)), *(np.empty((n, 3)) for _ in range(3)))

    def residual(zz):
        res = np.empty(6 * n)
        dmp = (1.3, 0.01, hsig, hkap)
        _chain_kernel._residual(zz, 1e-3, 1.0, x, q, psih, vh, wh, mass, inertia, model, dmp, *scratch, res)
        return res

    r0 = residual(z)
    jac = np.column_stack([(residual(z + 1e-6 * np.eye(6 * n)[j]) - r0) / 1e-6 for j in range(6 * n)])
    rows, cols = np.nonzero(np.abs(jac) > 1e-9 * np.abs(jac).max())  # above the differences' round-off
    assert np.abs(rows - cols).max() == hb


def test_an_elements_frame_is_half_way_between_its_nodes():
    """Against scipy's rotations, on frames 1e-9 off orthonormal (the statics' integrated frames are ~1e-10 off):
    ``Q_a exp(log(Q_a^T Q_b) / 2)`` of the nearest rotations."""
    from scipy.spatial.transform import Rotation

    from flexdigit.tdcr.dynamics import _element_frames

    rng = np.random.default_rng(11)
    nodes = Rotation.random(21, random_state=11)
    frames = nodes.as_matrix() + 1e-9 * rng.normal(size=(21, 3, 3))
    first = Rotation.from_matrix(frames[:-1])
    half = (first.inv() * Rotation.from_matrix(frames[1:])).as_rotvec() / 2
    expected = (first * Rotation.from_rotvec(half)).as_matrix()
    np.testing.assert_allclose(_element_frames(frames), expected, rtol=0, atol=1e-12)


def test_a_response_too_long_to_keep_is_refused_before_it_is_allocated(capsys):
    # hostile review: 'tdcr dynamics --duration-s 600 --dt-s 1e-6' ended in 'internal error (MemoryError: Unable
    # to allocate 282. GiB ...)'
    with pytest.raises(ParameterError, match=r"600000000 steps of 41 nodes.*at most 1 GiB"):
        simulate(ROD, solve_statics(ROD, []), 600.0, dt_s=1e-6)
    from flexdigit.cli import main

    argv = ["tdcr", "dynamics", "rao2021", "--tension-n", "4,0,0,0,2,0", "--duration-s", "600", "--dt-s", "1e-6"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "duration_s 600 s" in err
    assert "dt_s 1e-06 s" in err
    assert "\n" not in err


@pytest.mark.parametrize("hb", [8, 14])
@pytest.mark.parametrize("size", [6, 234])
def test_the_kernels_banded_lu_solves_as_scipy_does(hb, size):
    """The kernel's banded LU (no pivoting, reciprocal pivots) and its padded solve against scipy's
    ``solve_banded`` (LAPACK gbsv, partial pivoting), on a random diagonally dominant band (a step's matrix is
    mass + dt^2 stiffness), at the rod's size and below the band's width."""
    from scipy.linalg import solve_banded

    from flexdigit.tdcr import _chain_kernel

    rng = np.random.default_rng(5)
    band = rng.normal(size=(size, 2 * hb + 1))
    band[:, hb] = 2 * hb + 1 + rng.random(size)
    for i in range(size):  # zero outside the matrix, as _jacobian leaves it
        for c in range(2 * hb + 1):
            if not 0 <= i + c - hb < size:
                band[i, c] = 0.0
    rhs = rng.normal(size=size)
    ab = np.zeros((2 * hb + 1, size))  # LAPACK's layout: ab[hb + i - j, j] = a[i, j]
    for i in range(size):
        for c in range(2 * hb + 1):
            if 0 <= i + c - hb < size:
                ab[2 * hb - c, i + c - hb] = band[i, c]
    expected = solve_banded((hb, hb), ab, rhs)
    padded = np.zeros(size + 2 * hb)
    _chain_kernel._band_factor(band, hb)
    _chain_kernel._band_solve(band, hb, rhs, padded)
    np.testing.assert_allclose(padded[hb : hb + size], expected, rtol=0, atol=1e-13 * np.abs(expected).max())
    assert not padded[:hb].any()
    assert not padded[hb + size :].any()  # the padding stays zero


@pytest.mark.parametrize("angle", [1e-9, 0.05, 0.0999, 0.1001, 0.7, 3.0])
def test_the_kernels_rotations_match_scipys_either_side_of_its_series(angle):
    """Below 0.1 rad the kernel's exponential and logarithm use Taylor series, above it trigonometry: both
    against scipy's rotation vectors to round-off (the series' first term left out is ~1e-18)."""
    from scipy.spatial.transform import Rotation

    from flexdigit.tdcr import _chain_kernel

    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    rotvec = angle * axis
    matrix = Rotation.from_rotvec(rotvec).as_matrix()
    np.testing.assert_allclose(np.reshape(_chain_kernel._exp9(*rotvec), (3, 3)), matrix, rtol=0, atol=2e-16 * 8)
    base = Rotation.from_rotvec([0.2, 0.1, -0.4]).as_matrix()
    turned = base @ matrix
    logged = _chain_kernel._log_rel(base[None], 0, turned[None], 0)
    np.testing.assert_allclose(logged[:3], rotvec, rtol=0, atol=1e-15 * max(1.0, angle) * 8)
    np.testing.assert_allclose(np.reshape(logged[3:], (3, 3)), matrix, rtol=0, atol=1e-15)

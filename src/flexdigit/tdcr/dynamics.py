"""Dynamics of a tendon-driven continuum robot: a discretised Cosserat rod, implicit in time (BDF2).

Why this way. Each time step of a Cosserat rod is stiff: on rao2021's backbone at 10 mm elements the axial and
shear waves cross an element in ~4 us and the shortest bending mode's period is ~70 us, so an explicit
integrator (PyElastica's Position Verlet) takes ~250,000 steps a second. An implicit step of 1 ms is stable
whatever the stiffness, at the cost of a Newton solve. Two ways of doing it:

- shot in space (Till, Aloi & Rucker 2019, IJRR 38(6)): the step is a boundary-value problem in arc length,
  shot from the clamp (``method="shooting"``, the continuous rod of :mod:`flexdigit.tdcr.statics`). Its
  shooting problem amplifies by ``exp(L (rho A c0^2 / EI)^(1/4))`` (``c0 = 1.5 / dt``): ~12 e-folds at 1 ms on
  rao2021, so Newton fails for sudden tension changes or large fast motions (a 5 mm tip release at 1 ms stops
  after ~0.1 s), and each step costs ~10 integrations of the rod (real-time factor 2.2 on a 40-node rod).
- discretised in space (``method="discrete"``, the default; :mod:`flexdigit.tdcr._chain_kernel`): nodes and
  element frames as PyElastica's rod (Gazzola et al. 2018), so that the step's unknowns, the new velocities, are
  coupled only to their neighbours: the Newton matrix is banded (half bandwidth 8, 14 with tendons) and costs
  ``O(n)`` to solve. The Jacobian (coloured finite differences) is kept over steps and turned with the element
  frames (a co-rotated chord Newton): on a vibrating rod it is built once; where Newton slows (a sudden load)
  it is rebuilt, which makes the step robust where shooting fails (rao2021 pulled from slack tendons by 4 and
  2 N at once). Chosen over a chain of rigid links in joint coordinates (the planar twin's) because that
  Newton matrix is dense (``O(n^3)``) and tendons would need the links' kinematics; over a Kirchhoff rod because
  the shear and extension cost nothing extra here and keep tdcr-modeling's Cosserat model.

The discrete rod is not the continuous one: on rao2021 at one element a disk its equilibrium is 11.2 mm (2.8 % of
the length) from the shot statics, 2.8 mm at two, 0.71 mm at four: second order in the element length (a disk a
tendon ends on is turned half-way between its neighbouring elements). So the discrete rod first settles under
the loads ``initial`` was solved for (:attr:`StaticSolution.loads`), then is released.
BDF2's numerical damping is ``O((w dt)^4)`` a step; Kelvin-Voigt damping ``damping_s`` proportional to stiffness.
Speed: ``python -m benchmarks bench_tdcr`` (real-time factor of a 40-node rod at 1 kHz).

Examples
--------
>>> from flexdigit.tdcr import Robot, Segment, solve_statics
>>> rod = Robot(name="rod", segments=(Segment(0.4, 10),))
>>> bent = solve_statics(rod, [], tip_force_n=[0.005, 0, 0])
>>> motion = simulate(rod, bent, 0.05, dt_s=5e-3)  # released: the tip starts back towards the axis
>>> motion.converged, bool(motion.tip_positions_m[-1, 0] < bent.tip_position_m[0])
(True, True)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from flexdigit._repr import summary
from flexdigit._validation import check_array, check_int, check_real
from flexdigit.errors import ConvergenceWarning, ParameterError
from flexdigit.tdcr import _chain_kernel, _rod_kernel
from flexdigit.tdcr.description import Robot
from flexdigit.tdcr.statics import StaticSolution, _nodes

__all__ = ["DynamicSolution", "simulate"]


@dataclass(frozen=True)
class DynamicSolution:
    """A time response of the robot.

    Attributes
    ----------
    t_s : ndarray (m,)
        Times, from 0 (the initial state) in steps of ``dt_s``; only the steps that converged.
    s_m : ndarray (n,)
        Arc length of every node.
    positions_m : ndarray (m, n, 3)
        Backbone positions, world frame.
    rotations : ndarray (m, n, 3, 3)
        Backbone frames (columns: the cross-section's axes in the world frame).
    velocities_m_s, angular_velocities_rad_s : ndarray (m, n, 3)
        Linear and angular velocities, body frame.
    iterations : ndarray (m - 1,)
        Newton iterations of each step.
    converged : bool
        Whether every step asked for converged (else the response stops at the last one that did).
    """

    t_s: np.ndarray
    s_m: np.ndarray
    positions_m: np.ndarray
    rotations: np.ndarray
    velocities_m_s: np.ndarray
    angular_velocities_rad_s: np.ndarray
    iterations: np.ndarray
    converged: bool

    @property
    def tip_positions_m(self) -> np.ndarray:
        return self.positions_m[:, -1]

    def kinetic_energy_j(self, robot: Robot) -> np.ndarray:
        """Kinetic energy at each time (J): ``1/2 (rho A |q|^2 + w . rho J w)`` integrated along the backbone."""
        b = robot.backbone
        rho_j = b.density_kg_m3 * b.second_moment_m4 * np.array([1.0, 1.0, 2.0])
        density = 0.5 * (
            b.mass_per_length_kg_m * (self.velocities_m_s**2).sum(-1)
            + (rho_j * self.angular_velocities_rad_s**2).sum(-1)
        )
        return np.trapezoid(density, self.s_m, axis=1)

    def __repr__(self) -> str:
        return summary(
            self,
            converged=self.converged,
            steps=len(self.t_s),
            duration_s=float(self.t_s[-1] - self.t_s[0]) if len(self.t_s) else 0.0,
            nodes=len(self.s_m),
            final_tip_m=self.positions_m[-1, -1],
        )


def simulate(
    robot: Robot,
    initial: StaticSolution,
    duration_s: float,
    *,
    dt_s: float = 1e-3,
    tensions_n=None,
    tip_force_n=None,
    tip_moment_nm=None,
    gravity_m_s2=None,
    distributed_force_n_per_m=None,
    damping_s: float = 0.0,
    nodes_per_disk: int = 1,
    substeps: int | None = None,
    tol: float | None = None,
    max_iter: int = 50,
    method: str = "discrete",
) -> DynamicSolution:
    """The robot's motion from rest in ``initial`` under the given loads, held constant from ``t = 0``.

    Parameters
    ----------
    robot : Robot
    initial : StaticSolution
        The state at ``t = 0`` (at rest), e.g. :func:`~flexdigit.tdcr.solve_statics` under other loads; solved
        with the same ``nodes_per_disk``.
    duration_s, dt_s : float
        Simulated time and implicit time step (s).
    tensions_n : sequence of float, optional
        Tendon tensions from ``t = 0`` (default all zero: the tendons released).
    tip_force_n, tip_moment_nm, gravity_m_s2, distributed_force_n_per_m : optional
        As in :func:`~flexdigit.tdcr.solve_statics` (world frame); default none.
    damping_s : float
        Kelvin-Voigt material damping proportional to the stiffness, ``n = Kse (v - e3 + beta v_t)``,
        ``m = Kbt (u + beta u_t)`` with ``beta = damping_s`` (s): mode ``i`` is damped with the ratio
        ``beta w_i / 2``. Default 0 (none).
    nodes_per_disk : int
        Nodes per disk interval (the discrete rod's elements, or the shooting's output nodes).
    substeps, max_iter :
        As in :func:`~flexdigit.tdcr.solve_statics`, for each step (``substeps``: shooting only).
    tol : float, optional
        ``"discrete"`` (default 1e-7): on the error left in each step's Newton (scipy's BDF estimate from the
        updates' rate), displacements over the length and rotations in rad; the floor that the finite-difference
        Jacobian and round-off set is ~1e-10. Errors accumulate as a phase: a 4 mm vibration of a 40-node rod is
        9 um off tol = 1e-10's after 1000 steps of 1 ms (1e-4 of its frequency).
        ``"shooting"`` (default 1e-6): on each step's scaled tip residual, whose floor is ~1e-9..1e-8 (round-off
        amplified ~1e5 at 1 ms on rao2021, see the module docstring); 1e-6 is a force error of ~1e-6 EI/L^2.
    method : {"discrete", "shooting"}
        The discretised rod stepped by BDF2 with a banded Newton (default; :mod:`flexdigit.tdcr._chain_kernel`),
        or the continuous rod shot at each step (Till et al. 2019; slower and it fails on large fast motions).

    Returns
    -------
    DynamicSolution
    """
    owner = "simulate"
    if method not in ("discrete", "shooting"):
        raise ParameterError(f"The 'method' parameter of {owner} must be 'discrete' or 'shooting'. Got {method!r}.")
    nodes_per_disk, nodes, end_node = _checked_start(robot, initial, nodes_per_disk)
    duration_s = check_real(duration_s, "duration_s", owner, low=0.0, low_open=True)
    dt_s = check_real(dt_s, "dt_s", owner, low=0.0, high=duration_s, low_open=True)
    loads = _checked_loads(robot, tensions_n, tip_force_n, tip_moment_nm, distributed_force_n_per_m, gravity_m_s2)
    substeps, tol, damping_s, max_iter = _checked_options(robot, nodes, method, substeps, tol, damping_s, max_iter)
    n_steps = _checked_steps(duration_s, dt_s, nodes.size)
    if method == "discrete":
        motion = _simulate_discrete(robot, initial, nodes, end_node, loads, damping_s, dt_s, n_steps, tol, max_iter)
        done = motion.t_s.size - 1
    else:
        states, iterations, done = _integrate(
            robot, initial, nodes, end_node, substeps, loads, damping_s, dt_s, n_steps, tol, max_iter
        )
        motion = _motion(states, iterations, done, n_steps, nodes, dt_s)
    if done < n_steps:
        warnings.warn(
            f"simulate: step {done + 1} of {n_steps} (t = {(done + 1) * dt_s:.4g} s) did not converge on "
            f"{robot.name!r}; the response stops at t = {done * dt_s:.4g} s with converged=False",
            ConvergenceWarning,
            stacklevel=2,
        )
    return motion


#: The most memory the response's node positions may take (its (steps + 1, nodes, 3) float64 history).
MAX_HISTORY_BYTES = 2**30


def _checked_steps(duration_s: float, dt_s: float, n_nodes: int) -> int:
    """The number of steps, refused if the response is too long to keep (600 s in steps of 1 us was a
    MemoryError)."""
    n_steps = int(round(duration_s / dt_s))
    size = (n_steps + 1) * n_nodes * 3 * 8
    if size > MAX_HISTORY_BYTES:
        raise ParameterError(
            f"simulate: duration_s {duration_s:g} s in steps of dt_s {dt_s:g} s is {n_steps} steps of {n_nodes} "
            f"nodes, {size / 2**30:.3g} GiB of positions; expected at most {MAX_HISTORY_BYTES / 2**30:g} GiB: "
            "a shorter duration or a larger step"
        )
    return n_steps


def _checked_options(robot, nodes, method, substeps, tol, damping_s, max_iter):
    """:func:`simulate`'s checked ``(substeps, tol, damping_s, max_iter)``, defaults filled in."""
    owner = "simulate"
    if substeps is None:
        spacing = np.diff(nodes).max()
        substeps = max(1, int(np.ceil(spacing / (robot.length_m / 20) - 1e-9)))
    substeps = check_int(substeps, "substeps", owner, low=1, high=1000)
    tol = (1e-7 if method == "discrete" else 1e-6) if tol is None else tol
    tol = check_real(tol, "tol", owner, low=0.0, low_open=True)
    damping_s = check_real(damping_s, "damping_s", owner, low=0.0)
    max_iter = check_int(max_iter, "max_iter", owner, low=1)
    return substeps, tol, damping_s, max_iter


def _checked_start(robot, initial, nodes_per_disk):
    """:func:`simulate`'s checked ``(nodes_per_disk, nodes, end nodes)``: ``initial`` solved on those nodes."""
    owner = "simulate"
    if not isinstance(robot, Robot):
        raise ParameterError(f"The 'robot' parameter of {owner} must be a Robot. Got {type(robot).__name__} instead.")
    nodes_per_disk = check_int(nodes_per_disk, "nodes_per_disk", owner, low=1, high=100)
    nodes, end_node = _nodes(robot, nodes_per_disk)
    if not isinstance(initial, StaticSolution) or initial.s_m.shape != nodes.shape:
        raise ParameterError(
            f"The 'initial' parameter of {owner} must be a StaticSolution of this robot at nodes_per_disk="
            f"{nodes_per_disk} ({nodes.size} nodes). Got {type(initial).__name__} instead."
        )
    return nodes_per_disk, nodes, end_node


def _checked_loads(robot: Robot, tensions_n, tip_force_n, tip_moment_nm, distributed_force_n_per_m, gravity_m_s2):
    """:func:`simulate`'s checked ``(tensions, force per length, tip force, tip moment)``, gravity included."""
    owner = "simulate"
    n_t = len(robot.tendons)
    tau = np.zeros(n_t) if tensions_n is None else check_array(tensions_n, "tensions_n", owner, ndim=1, low=0.0)
    if tau.shape != (n_t,):
        raise ParameterError(
            f"The 'tensions_n' parameter of {owner} must have one tension per tendon ({n_t}). Got {tau.size} instead."
        )

    def vector(value, name):
        return np.zeros(3) if value is None else check_array(value, name, owner, shape=(3,))

    tip_force = vector(tip_force_n, "tip_force_n")
    tip_moment = vector(tip_moment_nm, "tip_moment_nm")
    fdist = vector(distributed_force_n_per_m, "distributed_force_n_per_m")
    fdist = fdist + robot.backbone.mass_per_length_kg_m * vector(gravity_m_s2, "gravity_m_s2")
    return tau, fdist, tip_force, tip_moment


def _integrate(robot: Robot, initial, nodes, end_node, substeps, loads, damping_s, dt_s, n_steps, tol, max_iter):
    """Run the time-stepping kernel from ``initial``: ``(states per step, Newton iterations per step, steps done)``.

    ``loads`` is ``(tensions, force per length, tip force, tip moment)``.
    """
    tau, fdist, tip_force, tip_moment = loads
    b = robot.backbone
    y_init = np.zeros((nodes.size, _rod_kernel.RECORD))
    y_init[:, 0:3] = initial.positions_m
    y_init[:, 3:12] = initial.rotations.reshape(-1, 9)
    y_init[:, 12:18] = initial.strains
    y_init[:, 24:30] = initial.strains_before_jump
    ei = b.bending_torsion_stiffness[0]
    length = robot.length_m
    scale = np.array([ei / length**2] * 3 + [ei / length] * 3)
    inertia = np.array([b.mass_per_length_kg_m, *(b.density_kg_m3 * b.second_moment_m4 * np.array([1.0, 1.0, 2.0]))])
    states = np.zeros((n_steps + 1, nodes.size, _rod_kernel.RECORD))
    iterations = np.zeros(n_steps, dtype=np.int64)
    done = _rod_kernel.simulate(
        initial.base_wrench / scale,
        y_init,
        nodes,
        substeps,
        np.ascontiguousarray(robot.routing_m),
        tau,
        end_node,
        b.shear_extension_stiffness,
        b.bending_torsion_stiffness,
        fdist,
        np.zeros(3),
        inertia,
        damping_s,
        tip_force,
        tip_moment,
        dt_s,
        n_steps,
        tol,
        max_iter,
        states,
        iterations,
    )
    return states, iterations, done


def _motion(states, iterations, done: int, n_steps: int, nodes, dt_s: float) -> DynamicSolution:
    """The :class:`DynamicSolution` of the ``done`` steps the kernel ran (of ``n_steps``)."""
    kept = states[: done + 1]
    return DynamicSolution(
        t_s=np.arange(done + 1) * dt_s,
        s_m=nodes,
        positions_m=kept[:, :, 0:3].copy(),
        rotations=kept[:, :, 3:12].reshape(done + 1, -1, 3, 3).copy(),
        velocities_m_s=kept[:, :, 18:21].copy(),
        angular_velocities_rad_s=kept[:, :, 21:24].copy(),
        iterations=iterations[:done].copy(),
        converged=bool(done == n_steps),
    )


def _discrete_model(robot: Robot, nodes, end_node, loads):
    """The chain kernel's ``(model, node masses, element inertias, half bandwidth)`` of the robot on ``nodes``."""
    tau, fdist, tip_force, tip_moment = (np.asarray(v, dtype=float) for v in loads)
    b = robot.backbone
    lengths = np.diff(nodes)
    voronoi = np.concatenate([[lengths[0] / 2], (lengths[:-1] + lengths[1:]) / 2])
    lumped = np.zeros(nodes.size)
    lumped[:-1] += lengths / 2
    lumped[1:] += lengths / 2
    fnode = lumped[:, None] * fdist
    fnode[-1] += tip_force
    model = (
        lengths,
        voronoi,
        np.asarray(b.shear_extension_stiffness, dtype=float),
        np.asarray(b.bending_torsion_stiffness, dtype=float),
        fnode,
        tip_moment,
        np.ascontiguousarray(robot.routing_m, dtype=float),
        tau,
        np.asarray(end_node, dtype=np.int64),
    )
    mass = b.mass_per_length_kg_m * lumped
    inertia = b.density_kg_m3 * b.second_moment_m4 * np.array([1.0, 1.0, 2.0]) * lengths[:, None]
    pulled = bool(np.any((tau > 0) & (np.asarray(end_node) >= 1)))
    return model, mass, inertia, 14 if pulled else 8


def _element_frames(rotations: np.ndarray) -> np.ndarray:
    """Each element's frame, half-way (geodesically) between its end nodes' frames (those first made the nearest
    rotations, as scipy's ``Rotation.from_matrix`` does: the statics' integrated frames are ~1e-10 off)."""
    u, _, vt = np.linalg.svd(np.asarray(rotations, dtype=float))
    out = np.empty((len(rotations) - 1, 3, 3))
    _chain_kernel.element_frames(np.ascontiguousarray(u @ vt), out)
    return out


def _simulate_discrete(robot, initial, nodes, end_node, loads, damping_s, dt_s, n_steps, tol, max_iter):
    """The discrete rod's response: settled under ``initial.loads`` (if recorded), then stepped under ``loads``."""
    x0 = np.ascontiguousarray(initial.positions_m, dtype=float)
    q0 = np.ascontiguousarray(_element_frames(initial.rotations))
    if initial.loads is not None:
        model, _, _, hb = _discrete_model(robot, nodes, end_node, initial.loads)
        x_rest, q_rest = x0.copy(), q0.copy()
        if _chain_kernel.equilibrate(x_rest, q_rest, model, hb, 1e-10, 50) == _chain_kernel.NO_PROGRESS:
            warnings.warn(
                f"simulate: the discrete rod of {robot.name!r} found no equilibrium near 'initial' under its loads; "
                "it starts from 'initial' as it is",
                ConvergenceWarning,
                stacklevel=3,
            )
        else:
            x0, q0 = x_rest, q_rest
    model, mass, inertia, hb = _discrete_model(robot, nodes, end_node, loads)
    shape = (n_steps + 1, nodes.size)
    # one buffer for the response: above 4 MB numpy asks for transparent huge pages, whose first touch (what the
    # kernel's writes cost beyond the arithmetic) is ~1/3 of four small-page arrays'
    buffer = np.empty(np.prod(shape) * 18)
    parts = np.split(buffer, np.cumsum([3, 9, 3]) * np.prod(shape))
    tails = ((3,), (3, 3), (3,), (3,))
    xs, rs, vs, ws = (part.reshape(*shape, *tail) for part, tail in zip(parts, tails, strict=True))
    iterations = np.zeros(n_steps, dtype=np.int64)
    done = _chain_kernel.run(
        x0, q0, model, mass, inertia, damping_s, hb, dt_s, n_steps, tol, max_iter, xs, rs, vs, ws, iterations
    )
    kept = slice(0, done + 1)
    return DynamicSolution(
        t_s=np.arange(done + 1) * dt_s,
        s_m=nodes,
        positions_m=xs[kept],
        rotations=rs[kept],
        velocities_m_s=vs[kept],
        angular_velocities_rad_s=ws[kept],
        iterations=iterations[:done].copy(),
        converged=bool(done == n_steps),
    )

"""Statics of a tendon-driven continuum robot: a Cosserat rod in 3D with tendons, solved by shooting.

The model is tdcr-modeling's Cosserat rod model (Rao et al. 2021, after Rucker & Webster 2011): an extensible,
shearable rod (``Kse = diag(GA, GA, EA)``, ``Kbt = diag(EI, EI, 2GI)``), clamped at the base with z along it,
tendons routed straight at fixed offsets and in frictionless continuous contact, each pulling its termination
disk. Loads: tendon tensions, gravity and a uniform distributed force (per length, world frame), a point force
and moment at the tip (world frame). A Cosserat rather than a Kirchhoff rod because it is what the reference
model solves and costs the same here; its shear and extension are ~1e-4 strains at the loads of interest.

Shooting: the six unknowns, the wrench the clamp holds (force and moment on the cross-section, backbone and
tendons together), are found by Newton (forward-difference Jacobian, backtracking) so that the tip's wrench
balance holds. Newton starts from the straight rigid rod's clamp wrench, which is exact without external loads
(tendons alone load the clamp with nothing), so a tendon-only solve is one integration; where Newton fails from
there, the loads are ramped from zero (continuation). RK4 with a fixed number of steps between disks (one for rao2021).
Unconverged solves return ``converged=False`` and warn with :class:`~flexdigit.errors.ConvergenceWarning`.

Where several equilibria exist (buckling under a large compressive tip load), Newton finds the one nearest its
start: by default the straight rod's clamp wrench, so the equilibrium continuous with the unloaded robot; pass
``initial_base_wrench`` (a previous solution's ``base_wrench``) to follow a branch.

Examples
--------
>>> from flexdigit.tdcr import ROBOTS, solve_statics
>>> sol = solve_statics(ROBOTS["rao2021"], [4, 0, 0, 0, 2, 0])
>>> sol.converged, [round(float(c) * 1e3, 1) for c in sol.tip_position_m]
(True, [127.6, 143.5, 336.4])
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from flexdigit._constants import G_STANDARD_M_S2
from flexdigit._repr import summary
from flexdigit._validation import check_array, check_int, check_real
from flexdigit.errors import ConvergenceWarning, ParameterError
from flexdigit.tdcr import _rod_kernel
from flexdigit.tdcr.description import Robot

__all__ = ["StaticSolution", "solve_statics", "STANDARD_GRAVITY_M_S2"]

STANDARD_GRAVITY_M_S2 = G_STANDARD_M_S2  # the package's one gravity (flexdigit._constants)


@dataclass(frozen=True)
class StaticSolution:
    """A static equilibrium of the robot.

    Attributes
    ----------
    s_m : ndarray (n,)
        Arc length of every node: the base and each disk (and intermediate nodes if ``nodes_per_disk > 1``).
    positions_m : ndarray (n, 3)
        Backbone positions, world frame (the base frame: origin at the base, z along the unloaded backbone).
    rotations : ndarray (n, 3, 3)
        Backbone frames: columns are the cross-section's x, y and z (tangent at rest) axes in the world frame.
    strains : ndarray (n, 6)
        ``(v, u)``: shear/extension and curvature/twist (1/m) in the body frame, after any jump at a node.
    strains_before_jump : ndarray (n, 6)
        The same before it (different only where tendons terminate).
    base_wrench : ndarray (6,)
        The shooting unknowns: force (N) and moment (N m) on the clamp's cross-section, backbone and tendons
        together, world frame; a start for a nearby solve.
    converged : bool
        Whether the tip's scaled wrench residual fell below ``tol``.
    iterations : int
        Newton iterations taken.
    residual : float
        2-norm of the tip wrench residual, forces scaled by ``EI/L^2``, moments by ``EI/L``.
    """

    s_m: np.ndarray
    positions_m: np.ndarray
    rotations: np.ndarray
    strains: np.ndarray
    strains_before_jump: np.ndarray
    base_wrench: np.ndarray
    converged: bool
    iterations: int
    residual: float
    #: The loads solved for, ``(tensions, force per length with gravity, tip force, tip moment)``: what the
    #: dynamics' discrete rod settles under before it is released (None: taken as it is)
    loads: tuple | None = field(default=None, repr=False, compare=False)

    @property
    def tip_position_m(self) -> np.ndarray:
        return self.positions_m[-1]

    @property
    def tip_rotation(self) -> np.ndarray:
        return self.rotations[-1]

    @property
    def tip_frame(self) -> np.ndarray:
        """4 x 4 homogeneous transform of the tip (tdcr-modeling's ``ee_frame``)."""
        t = np.eye(4)
        t[:3, :3] = self.tip_rotation
        t[:3, 3] = self.tip_position_m
        return t

    def to_dict(self) -> dict:
        return {
            "converged": self.converged,
            "iterations": self.iterations,
            "residual": self.residual,
            "tip_position_m": self.tip_position_m.tolist(),
            "tip_rotation": self.tip_rotation.tolist(),
            "tip_frame": self.tip_frame.tolist(),
            "s_m": self.s_m.tolist(),
            "backbone_m": self.positions_m.tolist(),
        }

    def __repr__(self) -> str:
        return summary(
            self,
            converged=self.converged,
            iterations=self.iterations,
            residual=self.residual,
            nodes=len(self.s_m),
            tip_m=self.positions_m[-1],
        )


def _vector(value, name: str) -> np.ndarray:
    if value is None:
        return np.zeros(3)
    return check_array(value, name, "solve_statics", shape=(3,))


def solve_statics(
    robot: Robot,
    tensions_n,
    *,
    tip_force_n=None,
    tip_moment_nm=None,
    gravity_m_s2=None,
    distributed_force_n_per_m=None,
    initial_base_wrench=None,
    nodes_per_disk: int = 1,
    substeps: int | None = None,
    tol: float = 1e-9,
    max_iter: int = 50,
) -> StaticSolution:
    """Solve the robot's static equilibrium under tendon tensions and external loads.

    Parameters
    ----------
    robot : Robot
        The description (:data:`flexdigit.tdcr.ROBOTS` or :func:`flexdigit.tdcr.load_robot`).
    tensions_n : sequence of float
        One tension (N, >= 0) per tendon, in the robot's tendon order.
    tip_force_n, tip_moment_nm : sequence of 3 float, optional
        Point force (N) and moment (N m) at the tip, world frame.
    gravity_m_s2 : sequence of 3 float, optional
        Gravity acceleration in the world (base) frame, e.g. ``(0, 0, -9.80665)`` for a robot pointing up; the
        backbone's weight per length is ``rho A g``. None: no gravity (tdcr-modeling has none).
    distributed_force_n_per_m : sequence of 3 float, optional
        A uniform force per length along the backbone, world frame.
    initial_base_wrench : sequence of 6 float, optional
        Newton's start (N, N m); default the clamp wrench of the straight rigid rod under the same loads.
    nodes_per_disk : int
        Output (and integration) nodes per disk interval.
    substeps : int, optional
        RK4 steps per node interval; default enough for steps of at most 1/20 of the length (the tip then
        moves by < 1e-6 of the length from RK4 at 32 times as many steps, under tendons, tip wrench and gravity
        on rao2021).
    tol : float
        On the tip wrench residual, scaled by ``EI/L^2`` (forces) and ``EI/L`` (moments).
    max_iter : int
        Newton iterations at most.

    Returns
    -------
    StaticSolution

    Examples
    --------
    >>> from flexdigit.tdcr import ROBOTS
    >>> straight = solve_statics(ROBOTS["rao2021"], [0] * 6)
    >>> straight.converged, round(float(straight.tip_position_m[2]), 6)
    (True, 0.4)
    """
    owner = "solve_statics"
    loads = _checked_loads(robot, tensions_n, tip_force_n, tip_moment_nm, distributed_force_n_per_m, gravity_m_s2)
    nodes_per_disk = check_int(nodes_per_disk, "nodes_per_disk", owner, low=1, high=100)
    substeps = _default_substeps(robot, nodes_per_disk) if substeps is None else substeps
    substeps = check_int(substeps, "substeps", owner, low=1, high=1000)
    tol = check_real(tol, "tol", owner, low=0.0, low_open=True)
    max_iter = check_int(max_iter, "max_iter", owner, low=0)
    x0, scale = _newton_start(robot, loads, initial_base_wrench)
    kernel_args = _kernel_args(robot, nodes_per_disk, substeps)
    nodes = kernel_args[0]
    out = np.empty((nodes.size, _rod_kernel.RECORD))
    x, converged, iterations, residual = _shoot(kernel_args, loads, 1.0, x0, tol, max_iter, out)
    if not converged and initial_base_wrench is None:
        x, converged, iterations, residual = _continuation(kernel_args, loads, tol, max_iter, out, iterations)
    if not converged:
        warnings.warn(
            f"solve_statics did not converge on {robot.name!r} in {iterations} Newton iterations: tip residual "
            f"{residual:.3g} > tol {tol:.3g}; the result carries converged=False",
            ConvergenceWarning,
            stacklevel=2,
        )
    return _solution(nodes, out, np.array(x) * scale, converged, iterations, residual, loads)


def _checked_loads(robot, tensions_n, tip_force_n, tip_moment_nm, distributed_force_n_per_m, gravity_m_s2):
    """:func:`solve_statics`'s checked ``(tensions, force per length, tip force, tip moment)``, gravity included."""
    owner = "solve_statics"
    if not isinstance(robot, Robot):
        raise ParameterError(f"The 'robot' parameter of {owner} must be a Robot. Got {type(robot).__name__} instead.")
    n_t = len(robot.tendons)
    tau = check_array(tensions_n, "tensions_n", owner, ndim=1, low=0.0)
    if tau.shape != (n_t,):
        raise ParameterError(
            f"The 'tensions_n' parameter of {owner} must have one tension per tendon ({n_t} for "
            f"{robot.name!r}). Got {tau.size} values instead."
        )
    tip_force = _vector(tip_force_n, "tip_force_n")
    tip_moment = _vector(tip_moment_nm, "tip_moment_nm")
    fdist = _vector(distributed_force_n_per_m, "distributed_force_n_per_m")
    if gravity_m_s2 is not None:
        fdist = fdist + robot.backbone.mass_per_length_kg_m * _vector(gravity_m_s2, "gravity_m_s2")
    return tau, fdist, tip_force, tip_moment


def _default_substeps(robot: Robot, nodes_per_disk: int) -> int:
    """RK4 steps per node interval for steps of at most 1/20 of the length."""
    spacing = np.diff(np.concatenate([[0.0], robot.disk_positions_m])).max() / nodes_per_disk
    return max(1, int(np.ceil(spacing / (robot.length_m / 20) - 1e-9)))


def _newton_start(robot: Robot, loads, initial_base_wrench):
    """Newton's start, scaled, and the scale ``(EI/L^2, EI/L)``: the given clamp wrench or the straight rigid
    rod's under the same loads."""
    _, fdist, tip_force, tip_moment = loads
    length = robot.length_m
    if initial_base_wrench is None:
        axis = np.array([0.0, 0.0, length])
        wrench = np.concatenate(
            [tip_force + fdist * length, tip_moment + np.cross(axis, tip_force) + np.cross(axis / 2, fdist * length)]
        )
    else:
        wrench = check_array(initial_base_wrench, "initial_base_wrench", "solve_statics", shape=(6,))
    ei = robot.backbone.bending_torsion_stiffness[0]
    scale = np.array([ei / length**2] * 3 + [ei / length] * 3)
    return wrench / scale, scale


def _kernel_args(robot: Robot, nodes_per_disk: int, substeps: int) -> tuple:
    """The shooting kernel's description of the robot: ``(nodes, substeps, routing, end nodes, Kse, Kbt)``."""
    nodes, end_node = _nodes(robot, nodes_per_disk)
    return (
        nodes,
        substeps,
        np.ascontiguousarray(robot.routing_m),
        end_node,
        robot.backbone.shear_extension_stiffness,
        robot.backbone.bending_torsion_stiffness,
    )


def _solution(nodes, out, base_wrench, converged, iterations, residual, loads=None) -> StaticSolution:
    """The :class:`StaticSolution` of the kernel's node records ``out``."""
    return StaticSolution(
        s_m=nodes,
        positions_m=out[:, 0:3].copy(),
        rotations=out[:, 3:12].reshape(-1, 3, 3).copy(),
        strains=out[:, 12:18].copy(),
        strains_before_jump=out[:, 24:30].copy(),
        base_wrench=base_wrench,
        converged=bool(converged),
        iterations=int(iterations),
        residual=float(residual),
        loads=loads,
    )


def _continuation(kernel_args, loads, tol, max_iter, out, iterations):
    """Continuation in the load factor from the unloaded robot (whose clamp wrench is zero), halving the step
    where Newton fails: the equilibrium reached is the one continuous with the straight robot.

    Returns ``(x, converged, iterations, residual)``, the iterations counted on from ``iterations``.
    """
    done, step, x_done = 0.0, 0.25, np.zeros(6)
    while done < 1.0 and step >= 1.0 / 1024:
        target = min(1.0, done + step)
        x_try, ok, its, residual = _shoot(kernel_args, loads, target, x_done, tol, max_iter, out)
        iterations += its
        if ok:
            done, x_done, step = target, x_try, min(2 * step, 0.5)
        else:
            step /= 2
    return x_done, done == 1.0 and ok, iterations, residual


def _shoot(kernel_args, loads, factor, x0, tol, max_iter, out):
    nodes, substeps, routing, end_node, kse, kbt = kernel_args
    tau, fdist, tip_force, tip_moment = (factor * np.asarray(v) for v in loads)
    statics = np.zeros(6)  # c0 = 0: no time derivatives, no inertia, no damping
    history = np.zeros((nodes.size, 2 * _rod_kernel.HIST))
    x, converged, iterations, residual, _ = _rod_kernel.shoot(
        x0,
        nodes,
        substeps,
        routing,
        tau,
        end_node,
        kse,
        kbt,
        fdist,
        np.zeros(3),
        statics,
        history,
        tip_force,
        tip_moment,
        tol,
        max_iter,
        out,
        np.empty((6, 6)),
        False,
    )
    return x, bool(converged), int(iterations), float(residual)


def _nodes(robot: Robot, nodes_per_disk: int) -> tuple[np.ndarray, np.ndarray]:
    """Node arc lengths (base, then ``nodes_per_disk`` per disk interval) and each tendon's end node index."""
    disks = np.concatenate([[0.0], robot.disk_positions_m])
    frac = np.arange(nodes_per_disk) / nodes_per_disk
    nodes = np.concatenate([(disks[:-1, None] + np.diff(disks)[:, None] * frac).ravel(), disks[-1:]])
    end_node = np.array([t.disk * nodes_per_disk for t in robot.tendons], dtype=np.int64)
    return nodes, end_node

"""A tendon robot's experiments on the twin: the release test (its first frequency) and a tension step.

What ``flexdigit simulate release|step --robot ROBOT`` runs; each returns a :class:`RobotExperiment` whose
:meth:`~RobotExperiment.save` writes the tip's path as a tidy table (Parquet, or CSV), as the digit's do.

The thesis's release test (3.1.2) on the digit, in space: the robot rests under its tendon tensions and a tip
force, the force is removed at ``t = 0`` and the tip swings about the equilibrium under the tensions alone
(:func:`flexdigit.tdcr.simulate`, the discrete rod). The force is the one that would deflect the straight
backbone's tip by ``tip_deflection_m`` (``3 EI d / L^3``), small by default (1 % of the length) so that the
response is the linear modes'.

The first frequency is read from the tip's path along the force by the matrix pencil method (Hua & Sarkar 1990,
IEEE Trans. ASSP 38(5)): the path is a sum of damped exponentials, a constant (the equilibrium) and the modes;
the poles ``z_k = exp((-sigma_k + i w_k) dt)`` are the eigenvalues of the pencil of the path's Hankel matrix
truncated to its ``order`` largest singular values (fewer where the rest are round-off), and the first mode is
the oscillating pole carrying the largest amplitude (a tip release puts ~97 % of the tip's motion in the first
mode). Unlike zero crossings or peaks, it does not mix the second mode's phase into the first's period; unlike an
FFT peak, its resolution is not ``1 / duration``. The step is a 200th of the Euler-Bernoulli period of the
straight backbone, where BDF2's frequency error is ~1e-4 (:mod:`flexdigit.tdcr.dynamics`).

Examples
--------
>>> from flexdigit.tdcr import Robot, Segment
>>> rod = Robot(name="rod", segments=(Segment(0.4, 40),))
>>> test = release_test(rod)
>>> round(test.first_frequency_hz / test.euler_bernoulli_hz, 3)   # the uniform cantilever's first mode
0.999
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexdigit._io import atomic_path, atomic_write
from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_int, check_real
from flexdigit.errors import ConvergenceWarning, ParameterError
from flexdigit.tdcr import _chain_kernel
from flexdigit.tdcr.description import Robot
from flexdigit.tdcr.dynamics import DynamicSolution, _discrete_model, _element_frames, simulate
from flexdigit.tdcr.statics import StaticSolution, _nodes, solve_statics

__all__ = ["RobotExperiment", "release_test", "step_test", "euler_bernoulli_first_hz", "pencil_frequency_hz"]

#: The first root of ``1 + cos(b) cosh(b) = 0``: a uniform cantilever's first mode is ``b^2 sqrt(EI / rho A) / L^2``.
CANTILEVER_ROOT = 1.8751040687119611


def euler_bernoulli_first_hz(robot: Robot) -> float:
    """The straight backbone's first bending frequency as a uniform Euler-Bernoulli cantilever (Hz)."""
    b = robot.backbone
    w = CANTILEVER_ROOT**2 * math.sqrt(b.bending_torsion_stiffness[0] / b.mass_per_length_kg_m) / robot.length_m**2
    return w / (2 * math.pi)


def pencil_frequency_hz(y, dt_s: float, order: int = 7) -> float:
    """The frequency (Hz) of the oscillating component of ``y`` (sampled every ``dt_s``) with the largest amplitude,
    by the matrix pencil method (see the module docstring); ``order`` poles are kept (a constant and three modes).

    Examples
    --------
    >>> t = np.arange(600) * 1e-3
    >>> y = 2.0 + np.cos(2 * np.pi * 3.2 * t) + 0.05 * np.sin(2 * np.pi * 21.0 * t)
    >>> round(pencil_frequency_hz(y, 1e-3), 9)
    3.2
    """
    y = check_array(y, "y", "pencil_frequency_hz", ndim=1, min_length=3 * order)
    dt_s = check_real(dt_s, "dt_s", "pencil_frequency_hz", low=0.0, low_open=True)
    order = check_int(order, "order", "pencil_frequency_hz", low=1)
    n = y.size
    # the pencil parameter: n / 3 is the noise-optimal choice (Hua & Sarkar), but a noise-free response needs only
    # more than ``order``; 8 x order keeps the SVD ~0.5 ms instead of ~20 ms for 600 samples, the same frequency
    pencil = min(n // 3, 8 * order)
    hankel = np.lib.stride_tricks.sliding_window_view(y, pencil + 1)  # (n - pencil, pencil + 1)
    _, sing, vh = np.linalg.svd(hankel, full_matrices=False)
    rank = min(order, int(np.sum(sing > 1e-10 * sing[0])))  # fewer components than order: no poles of round-off
    v = vh[:rank].T  # (pencil + 1, rank): the signal's space
    poles = np.linalg.eigvals(np.linalg.pinv(v[:-1]) @ v[1:])
    vandermonde = poles[None, :] ** np.arange(n)[:, None]
    amplitudes = np.linalg.lstsq(vandermonde, y.astype(complex), rcond=None)[0]
    angle = np.abs(np.angle(poles))
    oscillating = angle > 1e-9
    if not oscillating.any():
        raise ParameterError("pencil_frequency_hz: the signal does not oscillate (no pole off the real axis)")
    k = np.flatnonzero(oscillating)[np.argmax(np.abs(amplitudes[oscillating]))]
    return float(angle[k] / (2 * math.pi * dt_s))


@dataclass(frozen=True)
class RobotExperiment:
    """An experiment's response and what it measured.

    Attributes
    ----------
    experiment : str
        ``"release"`` or ``"step"``.
    robot : Robot
    tensions_n : ndarray
        The tendon tensions after ``t = 0`` (a release holds them throughout).
    tip_force_n : ndarray (3,)
        The force held at the tip before ``t = 0`` (world frame; zero for a step).
    initial : StaticSolution
        The shape at rest before ``t = 0``.
    motion : DynamicSolution
        The response.
    first_frequency_hz : float
        A release's first mode read from the tip's path (NaN for a step, or if the response stopped unconverged).
    euler_bernoulli_hz : float
        The straight backbone's first mode as a uniform cantilever (:func:`euler_bernoulli_first_hz`): the
        reference a robot without tensions meets.
    """

    experiment: str
    robot: Robot
    tensions_n: np.ndarray
    tip_force_n: np.ndarray
    initial: StaticSolution
    motion: DynamicSolution
    first_frequency_hz: float
    euler_bernoulli_hz: float

    def metadata(self) -> dict:
        """What made the table: the experiment, the robot's description, the loads and the step."""
        t = self.motion.t_s
        return {
            "experiment": f"tdcr {self.experiment}",
            "robot": self.robot.to_dict(),
            "tensions_n": self.tensions_n.tolist(),
            "tip_force_n": self.tip_force_n.tolist(),
            "initial_tip_position_m": self.initial.tip_position_m.tolist(),
            "dt_s": float(t[1] - t[0]) if t.size > 1 else None,
            "converged": self.motion.converged,
            "first_frequency_hz": None if math.isnan(self.first_frequency_hz) else self.first_frequency_hz,
            "units": {"t_s": "s", "tip_x_m": "m", "tip_y_m": "m", "tip_z_m": "m"},
        }

    def save(self, path, *, force: bool = False) -> Path:
        """Write the tip's path (``t_s, tip_x_m, tip_y_m, tip_z_m``) as Parquet, or CSV when ``path`` ends in
        ``.csv`` (the metadata as leading ``# key: json`` lines, as the digit's records); atomic, and refused if
        the file exists unless ``force``. Returns the path."""
        import pyarrow as pa

        path = Path(path)
        tip = self.motion.tip_positions_m
        table = pa.table({"t_s": self.motion.t_s, "tip_x_m": tip[:, 0], "tip_y_m": tip[:, 1], "tip_z_m": tip[:, 2]})
        meta = self.metadata()
        if path.suffix.lower() == ".csv":
            import pyarrow.csv as pcsv

            sink = pa.BufferOutputStream()
            pcsv.write_csv(table, sink)
            head = "".join(f"# {k}: {json.dumps(v)}\n" for k, v in meta.items())
            with atomic_write(path, "w", force=force) as fh:
                fh.write(head + sink.getvalue().to_pybytes().decode())
            return path
        import pyarrow.parquet as pq

        with atomic_path(path, force=force) as tmp:
            pq.write_table(table.replace_schema_metadata({b"flexdigit": json.dumps(meta).encode()}), tmp)
        return path

    __repr__ = fields_summary


def release_test(
    robot: Robot,
    tensions_n=None,
    *,
    tip_deflection_m: float | None = None,
    direction=(1.0, 0.0, 0.0),
    periods: float = 3.0,
    steps_per_period: int = 200,
    duration_s: float | None = None,
    dt_s: float | None = None,
    gravity_m_s2=None,
    damping_s: float = 0.0,
) -> RobotExperiment:
    """Release the robot from a tip force under ``tensions_n`` and measure its first frequency.

    Parameters
    ----------
    robot : Robot
    tensions_n : sequence of float, optional
        Held throughout (default all zero).
    tip_deflection_m : float, optional
        How far the force would deflect the straight backbone's tip (default 1 % of the length): the force is
        ``3 EI d / L^3`` along ``direction``.
    direction : sequence of 3 float
        The force's direction, world frame (normalised).
    periods, steps_per_period : float, int
        The response's length and step, in periods of :func:`euler_bernoulli_first_hz`.
    duration_s, dt_s : float, optional
        The response's length and step in seconds instead (a record's; at least 20 steps a period).
    gravity_m_s2, damping_s :
        As in :func:`~flexdigit.tdcr.simulate`.
    """
    owner = "release_test"
    tensions = np.zeros(len(robot.tendons)) if tensions_n is None else tensions_n
    length = robot.length_m
    deflection = 0.01 * length if tip_deflection_m is None else tip_deflection_m
    deflection = check_real(deflection, "tip_deflection_m", owner, low=0.0, high=0.5 * length, low_open=True)
    way = check_array(direction, "direction", owner, shape=(3,))
    if np.linalg.norm(way) == 0:
        raise ParameterError(f"The 'direction' parameter of {owner} must not be zero. Got {way.tolist()} instead.")
    periods = check_real(periods, "periods", owner, low=1.0, high=1000.0)
    steps_per_period = check_int(steps_per_period, "steps_per_period", owner, low=20, high=10_000)
    force = 3 * robot.backbone.bending_torsion_stiffness[0] * deflection / length**3 * way / np.linalg.norm(way)
    reference = euler_bernoulli_first_hz(robot)
    dt = 1.0 / (reference * steps_per_period) if dt_s is None else dt_s
    dt = check_real(dt, "dt_s", owner, low=0.0, high=1.0 / (20 * reference), low_open=True)
    duration = periods / reference if duration_s is None else duration_s
    duration = check_real(duration, "duration_s", owner, low=3 * dt, high=1e4)
    held = _held(robot, tensions, force, gravity_m_s2, dt, reference)
    motion = simulate(
        robot,
        held,
        duration,
        dt_s=dt,
        tensions_n=tensions,
        gravity_m_s2=gravity_m_s2,
        damping_s=damping_s,
    )
    frequency = math.nan
    if motion.converged:
        frequency = pencil_frequency_hz(motion.tip_positions_m @ (force / np.linalg.norm(force)), dt)
    else:
        warnings.warn(
            f"release_test: the response of {robot.name!r} stopped unconverged; no first frequency",
            ConvergenceWarning,
            stacklevel=2,
        )
    return RobotExperiment(
        "release", robot, np.asarray(tensions, dtype=float), force, held, motion, frequency, reference
    )


def _held(robot: Robot, tensions, force, gravity_m_s2, dt_s: float, reference_hz: float) -> StaticSolution:
    """The discrete rod at rest under the held loads, where the response starts.

    :func:`~flexdigit.tdcr.simulate` settles the discrete rod by Newton from the shot statics (~2.8 % of the length
    away at one element a disk). Where that Newton finds nothing (measured: 4 of the first 60 rows of the
    rao2021-tolerances study; the rod then started where the shot statics left it: on one, 17 mm from its rest and
    its first frequency 0.7 % off), the rod is relaxed instead: its held motion damped at ~0.5 of critical in the
    first mode (Kelvin-Voigt ``beta = 1 / w1``) for 4 periods, its last state the start (passed with no loads, so
    not settled again).
    """
    shot = solve_statics(robot, tensions, tip_force_n=force, gravity_m_s2=gravity_m_s2)
    nodes, ends = _nodes(robot, 1)
    model, _, _, hb = _discrete_model(robot, nodes, ends, shot.loads)
    x = np.ascontiguousarray(shot.positions_m, dtype=float).copy()
    q = np.ascontiguousarray(_element_frames(shot.rotations))
    if _chain_kernel.equilibrate(x, q, model, hb, 1e-10, 50) != _chain_kernel.NO_PROGRESS:
        return shot  # simulate finds the same rest
    w1 = 2 * math.pi * reference_hz
    free = dataclasses.replace(shot, loads=None)
    relax = simulate(
        robot,
        free,
        4.0 / reference_hz,
        dt_s=dt_s,
        tensions_n=tensions,
        tip_force_n=force,
        gravity_m_s2=gravity_m_s2,
        damping_s=1.0 / w1,
    )
    speed = float(np.abs(relax.velocities_m_s[-1]).max())
    if not relax.converged or speed > 1e-6 * robot.length_m * w1:
        warnings.warn(
            f"release_test: the held {robot.name!r} did not come to rest (tip speed {speed:.3g} m/s); it is released "
            "from where it was",
            ConvergenceWarning,
            stacklevel=3,
        )
    return dataclasses.replace(free, positions_m=relax.positions_m[-1], rotations=relax.rotations[-1])


def step_test(
    robot: Robot,
    tensions_n,
    *,
    from_tensions_n=None,
    duration_s: float = 1.0,
    dt_s: float = 1e-3,
    gravity_m_s2=None,
    damping_s: float = 0.0,
) -> RobotExperiment:
    """A tension step: the robot at rest under ``from_tensions_n`` (default all zero), ``tensions_n`` from
    ``t = 0`` (:func:`~flexdigit.tdcr.simulate`, the discrete rod).

    Examples
    --------
    >>> from flexdigit.tdcr import ROBOTS
    >>> step = step_test(ROBOTS["rao2021"], [1, 0, 0, 0, 0, 0], duration_s=0.05, dt_s=5e-3)
    >>> step.motion.converged, len(step.motion.t_s)
    (True, 11)
    """
    start = np.zeros(len(robot.tendons)) if from_tensions_n is None else from_tensions_n
    initial = solve_statics(robot, start, gravity_m_s2=gravity_m_s2)
    motion = simulate(
        robot, initial, duration_s, dt_s=dt_s, tensions_n=tensions_n, gravity_m_s2=gravity_m_s2, damping_s=damping_s
    )
    return RobotExperiment(
        "step",
        robot,
        np.asarray(tensions_n, dtype=float),
        np.zeros(3),
        initial,
        motion,
        math.nan,
        euler_bernoulli_first_hz(robot),
    )

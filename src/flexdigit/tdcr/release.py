"""A tendon robot's release test: held by a small tip force under its tensions, let go, its first frequency.

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

import math
import warnings
from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_int, check_real
from flexdigit.errors import ConvergenceWarning, ParameterError
from flexdigit.tdcr.description import Robot
from flexdigit.tdcr.dynamics import DynamicSolution, simulate
from flexdigit.tdcr.statics import StaticSolution, solve_statics

__all__ = ["ReleaseTest", "release_test", "euler_bernoulli_first_hz", "pencil_frequency_hz"]

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
    pencil = n // 3
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
class ReleaseTest:
    """A release test's response and what it measured.

    Attributes
    ----------
    tensions_n : ndarray
        The tendon tensions, held throughout.
    tip_force_n : ndarray (3,)
        The force held at the tip before ``t = 0`` (world frame).
    initial : StaticSolution
        The held shape.
    motion : DynamicSolution
        The response after the release.
    first_frequency_hz : float
        The first mode's frequency read from the tip's path (NaN if the response stopped unconverged).
    euler_bernoulli_hz : float
        The straight backbone's as a uniform cantilever (:func:`euler_bernoulli_first_hz`): the reference a
        robot without tensions meets.
    """

    tensions_n: np.ndarray
    tip_force_n: np.ndarray
    initial: StaticSolution
    motion: DynamicSolution
    first_frequency_hz: float
    euler_bernoulli_hz: float

    __repr__ = fields_summary


def release_test(
    robot: Robot,
    tensions_n=None,
    *,
    tip_deflection_m: float | None = None,
    direction=(1.0, 0.0, 0.0),
    periods: float = 3.0,
    steps_per_period: int = 200,
    gravity_m_s2=None,
    damping_s: float = 0.0,
) -> ReleaseTest:
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
    dt = 1.0 / (reference * steps_per_period)
    held = solve_statics(robot, tensions, tip_force_n=force, gravity_m_s2=gravity_m_s2)
    motion = simulate(
        robot,
        held,
        periods / reference,
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
    return ReleaseTest(np.asarray(tensions, dtype=float), force, held, motion, frequency, reference)

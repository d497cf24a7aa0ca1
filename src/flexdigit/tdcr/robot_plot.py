"""The figures of a tendon robot's commands (``--plot``): ``flexdigit simulate release|step --robot`` and ``flexdigit
tdcr dynamics`` draw the tip's path over time, ``flexdigit tdcr statics`` the robot's backbone, ``flexdigit tdcr
shape`` the backbone the gauges imply beside the twin's, ``flexdigit tdcr contact`` the contact the gauges locate
(and the twin's, when it was pressed).

In the style of the digit's figures (:mod:`flexdigit._plot`): matplotlib ``Figure`` objects without pyplot,
lengths in mm, times in s, units in every axis label.
"""

from __future__ import annotations

import math

import numpy as np

from flexdigit._plot import new_figure

__all__ = ["experiment_figure", "trajectory_figure", "statics_figure", "backbone_figure", "contact_figure"]

#: The tip's coordinates, in the order of ``tip_positions_m``'s columns (world frame: z along the unloaded backbone).
AXES = ("x", "y", "z")
#: A coordinate that moves less than this is drawn on this span, centred: a still one shows flat, not its round-off.
MIN_SPAN_MM = 1.0


def _tip_panels(t_s: np.ndarray, tip_positions_m: np.ndarray, title: str):
    """The tip's x, y and z (mm) against time (s), one panel each, a still coordinate on :data:`MIN_SPAN_MM`."""
    tip_mm = np.asarray(tip_positions_m) * 1e3
    fig, axes = new_figure(3, 1, figsize=(8.0, 5.5), sharex=True)
    for k, ax in enumerate(axes):
        ax.plot(t_s, tip_mm[:, k], label=f"tip {AXES[k]}")
        ax.set_ylabel(f"tip {AXES[k]} (mm)")
        low, high = float(tip_mm[:, k].min()), float(tip_mm[:, k].max())
        if high - low < MIN_SPAN_MM:
            middle = 0.5 * (low + high)
            ax.set_ylim(middle - 0.5 * MIN_SPAN_MM, middle + 0.5 * MIN_SPAN_MM)
    axes[-1].set_xlabel("time (s)")
    axes[0].set_title(title, fontsize=9)
    return fig


def experiment_figure(test):
    """A robot's release or step test (:class:`~flexdigit.tdcr.RobotExperiment`) as a matplotlib ``Figure``: the
    tip's x, y and z (mm) against time (s), the first frequency in the title of a release.

    Parameters
    ----------
    test : RobotExperiment
        What :func:`~flexdigit.tdcr.release_test` or :func:`~flexdigit.tdcr.step_test` returned.
    """
    t = test.motion.t_s
    title = f"{test.experiment} test of {test.robot.name} on its twin"
    if not math.isnan(test.first_frequency_hz):
        title += (
            f": first frequency {test.first_frequency_hz:.3f} Hz "
            f"(Euler-Bernoulli cantilever {test.euler_bernoulli_hz:.3f} Hz)"
        )
    if not test.motion.converged:
        title += f" (stopped unconverged at {t[-1]:.3g} s)"
    return _tip_panels(t, test.motion.tip_positions_m, title)


def trajectory_figure(motion, robot=None):
    """A time response (:func:`~flexdigit.tdcr.simulate`, ``flexdigit tdcr dynamics``) as a matplotlib
    ``Figure``: the tip's x, y and z (mm) against time (s), one panel each.

    Parameters
    ----------
    motion : DynamicSolution
    robot : Robot, optional
        Its name goes in the title.

    Examples
    --------
    >>> from flexdigit.tdcr import ROBOTS, simulate, solve_statics
    >>> robot = ROBOTS["rao2021"]
    >>> straight = solve_statics(robot, [0.0] * 6)
    >>> fig = trajectory_figure(simulate(robot, straight, 0.002, dt_s=1e-3, tensions_n=[1, 0, 0, 0, 0, 0]), robot)
    >>> [ax.get_ylabel() for ax in fig.axes]
    ['tip x (mm)', 'tip y (mm)', 'tip z (mm)']
    """
    t = motion.t_s
    name = robot.name if robot is not None else "the robot"
    title = f"tip of {name} from t = 0 ({len(t) - 1} steps of {t[1] - t[0]:.3g} s)" if len(t) > 1 else name
    if not motion.converged:
        title += f" (stopped unconverged at {t[-1]:.3g} s)"
    return _tip_panels(t, motion.tip_positions_m, title)


def statics_figure(solution, robot=None):
    """A static equilibrium (:func:`~flexdigit.tdcr.solve_statics`, ``flexdigit tdcr statics``) as a matplotlib
    ``Figure``: the backbone seen from the side (x-z), the front (y-z) and above (x-y), in mm, its disks and tip
    marked.

    Parameters
    ----------
    solution : StaticSolution
    robot : Robot, optional
        Its name goes in the title, its disks on the backbone.

    Examples
    --------
    >>> from flexdigit.tdcr import ROBOTS, solve_statics
    >>> fig = statics_figure(solve_statics(ROBOTS["rao2021"], [2, 0, 0, 0, 0, 0]), ROBOTS["rao2021"])
    >>> [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes]
    [('x (mm)', 'z (mm)'), ('y (mm)', 'z (mm)'), ('x (mm)', 'y (mm)')]
    """
    backbone_mm = solution.positions_m * 1e3
    tip_mm = backbone_mm[-1]
    fig, axes = new_figure(1, 3, figsize=(10.0, 4.4))
    disks_mm = None
    if robot is not None:
        disks = np.asarray(robot.disk_positions_m, float)
        disks_mm = np.array([np.interp(disks, solution.s_m, solution.positions_m[:, k]) for k in range(3)]).T * 1e3
    for ax, (i, j) in zip(axes, ((0, 2), (1, 2), (0, 1)), strict=True):
        ax.plot(backbone_mm[:, i], backbone_mm[:, j], label="backbone")
        if disks_mm is not None:
            ax.plot(disks_mm[:, i], disks_mm[:, j], "o", ms=3, label="disks")
        ax.plot([tip_mm[i]], [tip_mm[j]], "*", ms=9, label="tip")
        ax.set_xlabel(f"{AXES[i]} (mm)")
        ax.set_ylabel(f"{AXES[j]} (mm)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"{AXES[i]}-{AXES[j]} view", fontsize=9)
    axes[0].legend(fontsize=7)
    name = robot.name if robot is not None else "the robot"
    title = f"{name} in static equilibrium: tip at ({tip_mm[0]:.1f}, {tip_mm[1]:.1f}, {tip_mm[2]:.1f}) mm"
    if not solution.converged:
        title += f" (NOT converged: residual {solution.residual:.2g})"
    fig.suptitle(title, fontsize=9)
    return fig


def backbone_figure(found, robot=None):
    """What :func:`~flexdigit.tdcr.sense_shape` found as a matplotlib ``Figure``: the estimated backbone (and the
    twin's, when known) seen from the side (x-z) and from the front (y-z), in mm, the gauge stations marked;
    beside a twin, a third panel with the distance between the two backbones along the arc length.

    Parameters
    ----------
    found : ShapeSensing
    robot : Robot, optional
        Its name goes in the title.
    """
    estimate, twin = found.estimate, found.twin
    panels = 3 if twin is not None else 2
    fig, axes = new_figure(1, panels, figsize=(10.0 if twin is not None else 7.0, 4.2))
    stations = estimate.position_at(found.layout.stations_m) * 1e3
    for ax, k in zip(axes[:2], (0, 1), strict=True):
        ax.plot(estimate.positions_m[:, k] * 1e3, estimate.positions_m[:, 2] * 1e3, label="estimate (gauges)")
        if twin is not None:
            ax.plot(twin.positions_m[:, k] * 1e3, twin.positions_m[:, 2] * 1e3, "--", label="twin")
        ax.plot(stations[:, k], stations[:, 2], "o", ms=3, label="gauge stations")
        ax.set_xlabel(f"{AXES[k]} (mm)")
        ax.set_ylabel("z (mm)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"{AXES[k]}-z view", fontsize=9)
    axes[0].legend(fontsize=7)
    if twin is not None:
        error_mm = np.linalg.norm(estimate.position_at(twin.s_m) - twin.positions_m, axis=1) * 1e3
        ax = axes[2]
        ax.plot(twin.s_m * 1e3, error_mm, label="distance to the twin")
        ax.set_xlabel("arc length from the base (mm)")
        ax.set_ylabel("distance to the twin's backbone (mm)")
        ax.set_title(f"tip error {found.tip_error_m * 1e3:.3g} mm", fontsize=9)
    name = f" of {robot.name}" if robot is not None else ""
    fig.suptitle(f"the shape{name} from {found.layout.s_m.size} gauges", fontsize=9)
    return fig


#: A contact force's arrow is drawn this fraction of the backbone's length long (its direction is what it shows).
ARROW_FRACTION = 0.2


def contact_figure(found, robot=None):
    """What :func:`~flexdigit.tdcr.sense_contact` found as a matplotlib ``Figure``: the backbone without the
    contact, seen from the side (x-z) and the front (y-z) in mm, the estimated contact on it with its force's
    direction, and where the twin was pressed, when it was.

    Parameters
    ----------
    found : ContactSensing
    robot : Robot, optional
        Its name goes in the title.
    """
    free, estimate = found.free, found.estimate
    backbone_mm = free.positions_m * 1e3
    length_mm = float(free.s_m[-1]) * 1e3
    fig, axes = new_figure(1, 2, figsize=(8.0, 4.6))
    at_mm = estimate.position_m * 1e3
    force = np.asarray(estimate.force_n, float)
    arrow_mm = force / max(float(np.linalg.norm(force)), 1e-300) * ARROW_FRACTION * length_mm
    true_mm = None
    if found.true_s_m is not None:
        true_mm = np.array([np.interp(found.true_s_m, free.s_m, free.positions_m[:, k]) for k in range(3)]) * 1e3
    for ax, k in zip(axes, (0, 1), strict=True):
        ax.plot(backbone_mm[:, k], backbone_mm[:, 2], label="backbone (without the contact)")
        ax.plot([at_mm[k]], [at_mm[2]], "o", label="estimated contact")
        ax.annotate(
            "", xy=(at_mm[k] + arrow_mm[k], at_mm[2] + arrow_mm[2]), xytext=(at_mm[k], at_mm[2]),
            arrowprops={"arrowstyle": "->", "color": "C1"},
        )  # fmt: skip
        if true_mm is not None:
            ax.plot([true_mm[k]], [true_mm[2]], "x", ms=8, label="pressed here (twin)")
        ax.set_xlabel(f"{AXES[k]} (mm)")
        ax.set_ylabel("z (mm)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"{AXES[k]}-z view", fontsize=9)
    axes[0].legend(fontsize=7)
    name = f" on {robot.name}" if robot is not None else ""
    title = (
        f"contact{name} from {found.layout.s_m.size} gauges: s = {estimate.s_m * 1e3:.1f} mm, "
        f"{np.linalg.norm(force) * 1e3:.2f} mN (arrow: its direction)"
    )
    if found.true_s_m is not None:
        title += f"; pressed at s = {found.true_s_m * 1e3:.1f} mm"
    fig.suptitle(title, fontsize=9)
    return fig

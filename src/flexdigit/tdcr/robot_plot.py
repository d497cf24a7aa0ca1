"""The figures of a tendon robot's commands (``--plot``): ``flexdigit simulate release|step --robot`` draws the
tip's path over time, ``flexdigit tdcr shape`` the backbone the gauges imply beside the twin's.

In the style of the digit's figures (:mod:`flexdigit._plot`): matplotlib ``Figure`` objects without pyplot,
lengths in mm, times in s, units in every axis label.
"""

from __future__ import annotations

import math

import numpy as np

from flexdigit._plot import new_figure

__all__ = ["experiment_figure", "backbone_figure"]

#: The tip's coordinates, in the order of ``tip_positions_m``'s columns (world frame: z along the unloaded backbone).
AXES = ("x", "y", "z")
#: A coordinate that moves less than this is drawn on this span, centred: a still one shows flat, not its round-off.
MIN_SPAN_MM = 1.0


def experiment_figure(test):
    """A robot's release or step test (:class:`~flexdigit.tdcr.RobotExperiment`) as a matplotlib ``Figure``: the
    tip's x, y and z (mm) against time (s), the first frequency in the title of a release.

    Parameters
    ----------
    test : RobotExperiment
        What :func:`~flexdigit.tdcr.release_test` or :func:`~flexdigit.tdcr.step_test` returned.
    """
    t = test.motion.t_s
    tip_mm = test.motion.tip_positions_m * 1e3
    fig, axes = new_figure(3, 1, figsize=(8.0, 5.5), sharex=True)
    for k, ax in enumerate(axes):
        ax.plot(t, tip_mm[:, k], label=f"tip {AXES[k]}")
        ax.set_ylabel(f"tip {AXES[k]} (mm)")
        low, high = float(tip_mm[:, k].min()), float(tip_mm[:, k].max())
        if high - low < MIN_SPAN_MM:
            middle = 0.5 * (low + high)
            ax.set_ylim(middle - 0.5 * MIN_SPAN_MM, middle + 0.5 * MIN_SPAN_MM)
    axes[-1].set_xlabel("time (s)")
    title = f"{test.experiment} test of {test.robot.name} on its twin"
    if not math.isnan(test.first_frequency_hz):
        title += (
            f": first frequency {test.first_frequency_hz:.3f} Hz "
            f"(Euler-Bernoulli cantilever {test.euler_bernoulli_hz:.3f} Hz)"
        )
    if not test.motion.converged:
        title += f" (stopped unconverged at {t[-1]:.3g} s)"
    axes[0].set_title(title, fontsize=9)
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

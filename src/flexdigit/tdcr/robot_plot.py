"""The figures of a tendon robot's commands (``--plot``): ``flexdigit simulate release|step --robot`` draws the
tip's path over time, ``flexdigit tdcr shape`` the backbone the gauges imply beside the twin's, ``flexdigit tdcr
contact`` the contact the gauges locate (and the twin's, when it was pressed).

In the style of the digit's figures (:mod:`flexdigit._plot`): matplotlib ``Figure`` objects without pyplot,
lengths in mm, times in s, units in every axis label.
"""

from __future__ import annotations

import math

import numpy as np

from flexdigit._plot import new_figure

__all__ = ["experiment_figure", "backbone_figure", "contact_figure"]

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

"""The figure of a closed-loop run (``flexdigit run ... --plot``): setpoint, estimate, true rotation and command.

Top, the beam rotation: the setpoint, the loop's estimate from the gauges and, on the twin, its true rotation
(what hardware cannot measure; thesis 5.4 judged its loops on the estimate alone); bottom, the servo command sent.
"""

from __future__ import annotations

import numpy as np

from flexdigit._plot import new_figure
from flexdigit.rig.step_test import StepRun

__all__ = ["run_figure", "board_run_figure"]


def run_figure(run: StepRun, title: str = ""):
    """A run's rotations (deg) and commands over time (s) as a matplotlib ``Figure`` of two axes.

    Examples
    --------
    >>> from flexdigit.rig import open_rig
    >>> from flexdigit.rig.rotation import calibrate_rotation
    >>> from flexdigit.rig.step_test import run_step
    >>> rig = open_rig("sim", seed=0)
    >>> estimator = calibrate_rotation(rig, commands=(8, 20, 30))  # doctest: +SKIP
    >>> fig = run_figure(run_step(rig, "digital20", 20.0, 0.2, 0.02, estimator=estimator))  # doctest: +SKIP
    >>> rig.close()
    """
    r = run.result
    truth = run.true_rotation_deg if run.has_truth else None
    return _figure(r.time_s, r.setpoint, r.measurement, truth, r.command, title)


def board_run_figure(run: dict, title: str = ""):
    """The same figure for a run whose loop closed on the board (:func:`~flexdigit.rig.step_test.board_step_test`'s
    result): the setpoint, the board's streamed rotation estimate (none from an image that streams none), the twin's
    true rotation and the board's command (its servo pulse, in commands)."""
    s = run["series"]
    t = np.asarray(s["time_s"], float)
    estimate = np.asarray(s.get("estimate_deg", np.full(t.size, np.nan)), float)
    estimate = None if not np.isfinite(estimate).any() else estimate
    return _figure(t, np.full(t.size, run["setpoint_deg"]), estimate, s["true_rotation_deg"], s["command"], title)


def _figure(time_s, setpoint, estimate, truth, command, title: str):
    t = np.asarray(time_s, float)
    fig, (top, bottom) = new_figure(2, 1, figsize=(8.0, 5.0), sharex=True, height_ratios=(3, 2))
    top.step(t, setpoint, where="post", color="k", ls=":", lw=1.0, label="setpoint")
    if estimate is not None:
        top.plot(t, estimate, color="C0", label="estimate (gauges)")
    if truth is not None and np.size(truth):
        n = np.size(truth)
        top.plot(t[:n], truth, color="C3", lw=1.0, label="true rotation (twin)")
    top.set_ylabel("beam rotation (deg)")
    top.legend(fontsize=7)
    if title:
        top.set_title(title, fontsize=9)
    bottom.step(t, command, where="post", color="C2", label="command")
    bottom.set_xlabel("time (s)")
    bottom.set_ylabel("servo command")
    bottom.legend(fontsize=7)
    return fig

"""Runaway and plausibility faults of the closed loop: stop in the safe state before the digit is driven to a limit.

A loop can "complete" while driving the digit to its mechanical limit: a rotation map with the wrong sign (the
estimate moves away from the setpoint as the command rises), a dead one (the estimate never moves), or a gross gain
error. On the twin such runs reported "completed" while its true rotation reached 119-411 deg (issue 16). The
:class:`RunawayGuard` watches every sample and raises :class:`~flexdigit.errors.RigError` naming what it saw; the
loop (:func:`flexdigit.rig.loop.run_loop`) then sends the equilibrium command and closes the port, as for any
fault. It faults when

- the estimated rotation, or on the twin its true rotation, leaves the physical range (:data:`ROTATION_RANGE_DEG`);
- the command is saturated (on a limit of the actuator, or clamped there) and the rotation error grows, or it
  has pulled at the top for ``saturation_s`` without the error shrinking by ``min_progress_deg``: the loop pushes
  as hard as it can and gets nowhere, or worse (at the bottom the cable is slack and the digit relaxed: an
  unreachable negative setpoint is not a runaway);
- the command has stayed more than ``unanswered_fraction`` of the actuator's range from where it started for
  ``saturation_s`` while the estimated rotation moved less than ``min_progress_deg``: the estimate does not follow
  the command (a dead map, a gauge source that is not the digit's).

The thresholds are in the loop's measurement unit (degrees of beam rotation for every ``flexdigit run``
controller) and the actuator's command range; they leave a correct loop alone (the 20 ms design's 30 deg step
never saturates; tests/rig/test_safety.py runs it at plant gains 0.7 and 1.3).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from flexdigit._validation import check_real
from flexdigit.errors import RigError
from flexdigit.rig.rotation import RotationEstimator

__all__ = [
    "ROTATION_RANGE_DEG",
    "RunawayGuard",
    "default_guard",
]

#: Beam (tip) rotations the digit can take without harm, deg: the setpoints ``flexdigit run`` accepts (-60..120)
#: with 30 deg of margin. The cable only pulls one way; the twin can be driven far beyond (its elastica wraps).
ROTATION_RANGE_DEG = (-90.0, 150.0)


@dataclass
class RunawayGuard:
    """Per-sample runaway checks for :func:`~flexdigit.rig.loop.run_loop` (module docstring).

    Parameters
    ----------
    range_deg : (float, float)
        Physical range of the rotation, deg.
    saturation_s : float
        How long the command may stay saturated without the error shrinking (or far from its start without the
        estimate moving), s: several time constants of the servo (0.05 s) and of the digit's first mode.
    min_progress_deg : float
        The error must shrink (or the estimate move) by at least this much, deg.
    unanswered_fraction : float
        Share of the actuator's command range the command may move while the estimate stays put.
    truth : callable, optional
        ``truth() -> deg``: the true rotation where it is known (the twin's ``tip_rotation_deg``).
    measured : bool
        The loop's measurement is the beam rotation in degrees (a rotation map's estimate): check it too. False
        watches only ``truth`` (a loop on another quantity: gauge volts, a contact force, a staircase of commands).
    """

    range_deg: tuple[float, float] = ROTATION_RANGE_DEG
    saturation_s: float = 0.5
    min_progress_deg: float = 1.0
    unanswered_fraction: float = 0.1
    truth: Callable[[], float] | None = None
    measured: bool = True
    _saturated_since: float | None = field(default=None, init=False, repr=False)
    _saturated_error: float = field(default=math.nan, init=False, repr=False)
    _start: tuple[float, float] | None = field(default=None, init=False, repr=False)
    _unanswered_since: float | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        low, high = (check_real(v, "range_deg", "RunawayGuard") for v in self.range_deg)
        if not low < high:
            raise ValueError(f"The 'range_deg' parameter of RunawayGuard must be increasing. Got {self.range_deg!r}.")
        check_real(self.saturation_s, "saturation_s", "RunawayGuard", low=0, low_open=True)
        check_real(self.min_progress_deg, "min_progress_deg", "RunawayGuard", low=0)
        check_real(self.unanswered_fraction, "unanswered_fraction", "RunawayGuard", low=0, low_open=True, high=1)

    def reset(self, command: int) -> None:
        """Forget the past (called by the loop before its first sample, with the command in force)."""
        self._saturated_since, self._saturated_error = None, math.nan
        self._start = (float(command), math.nan)
        self._unanswered_since = None

    def check_rotation(self, t: float, estimated_deg: float) -> None:
        """Fault when the estimated or the true rotation is outside :attr:`range_deg`."""
        low, high = self.range_deg
        values = [("estimated", estimated_deg)] if self.measured else []
        if self.truth is not None:
            values.append(("true (twin)", float(self.truth())))
        for what, value in values:
            if math.isfinite(value) and not low <= value <= high:
                raise RigError(
                    f"runaway: the {what} rotation {value:.1f} deg left the physical range {low:g}..{high:g} deg "
                    f"at t = {t:.3f} s"
                )

    def check_command(
        self,
        t: float,
        setpoint: float,
        estimated_deg: float,
        requested: float,
        sent: int,
        command_limits: tuple[float, float],
    ) -> None:
        """Fault when the command stays saturated without progress, or moves far while the estimate does not.

        ``command_limits`` are the lowest and highest command the actuator takes; the command is saturated when it
        sits on one of them or was clamped there (``requested`` beyond it). Pulling at the top for
        ``saturation_s`` without the error shrinking is a fault; at the bottom (the cable slack, the digit
        relaxed) only an error that grows is.
        """
        if not self.measured:  # the measurement is not a rotation: nothing here to judge it by
            return
        low, high = command_limits
        if self._start is None:
            self.reset(sent)
        start_command, start_estimate = self._start
        if math.isnan(start_estimate) and math.isfinite(estimated_deg):
            self._start = (start_command, estimated_deg)
            start_estimate = estimated_deg
        moved = abs(estimated_deg - start_estimate)
        far = abs(sent - start_command) > self.unanswered_fraction * (high - low)
        if far and not moved >= self.min_progress_deg:
            if self._unanswered_since is None:
                self._unanswered_since = t
            elif t - self._unanswered_since >= self.saturation_s:
                raise RigError(
                    f"runaway: the command moved from {start_command:g} to {sent} while the estimated rotation moved "
                    f"{moved:.2f} deg in {t - self._unanswered_since:.2f} s, at t = {t:.3f} s; the rotation estimate "
                    "does not follow the command (a dead rotation map, or gauges that are not the digit's?)"
                )
        else:
            self._unanswered_since = None
        error = abs(setpoint - estimated_deg)
        top = sent >= high or (math.isfinite(requested) and requested - sent >= 1.0)
        bottom = sent <= low or (math.isfinite(requested) and sent - requested >= 1.0)
        if not (top or bottom):
            self._saturated_since = None
            return
        if self._saturated_since is None:
            self._saturated_since, self._saturated_error = t, error
            return
        held = t - self._saturated_since
        grew = error > self._saturated_error + self.min_progress_deg
        stuck = top and held >= self.saturation_s and not error <= self._saturated_error - self.min_progress_deg
        if grew or stuck:
            raise RigError(
                f"runaway: the command has been saturated at {sent} for {held:.2f} s while the rotation error went "
                f"from {self._saturated_error:.1f} to {error:.1f} deg, at t = {t:.3f} s (a rotation map of the "
                "wrong sign, or a gain error?)"
            )


def default_guard(rig, measure) -> RunawayGuard:
    """The guard :func:`~flexdigit.rig.loop.run_loop` keeps unless told not to (``guard=False``).

    It watches the true rotation where the rig knows it (the twin's ``tip_rotation_deg``), and every check on the
    measurement when that is the beam rotation in degrees (``measure`` a fitted
    :class:`~flexdigit.rig.rotation.RotationEstimator`, as ``flexdigit run`` and ``make_controller("digital20",
    ...)`` use); a loop on another quantity is judged by the truth alone, or not at all on hardware.
    """
    return RunawayGuard(truth=getattr(rig, "tip_rotation_deg", None), measured=isinstance(measure, RotationEstimator))

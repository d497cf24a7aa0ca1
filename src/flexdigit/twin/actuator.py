"""The servo as identified (3.2.4): second order, zeta 0.5629, wn 20.53 rad/s, driven by latched integer commands.

The MILINST board receives a command (0..254) in a serial frame every ``serial_period_s`` (20 ms, 5.2) and turns it
into a pulse width; the servo reads the pulse on its next PWM pulse (52 Hz). So a command issued at time ``t``
takes effect at the first PWM pulse at or after the first serial frame boundary at or after ``t`` (then rounded up
to the integration grid). The servo's shaft angle follows ``theta'' = wn^2 (theta_cmd - theta) - 2 zeta wn
theta'`` exactly between grid points (matrix exponential), with ``theta_cmd`` from E 3.15 (0.8622 deg per command,
0 deg at command 0) and the mechanical range 0..219 deg enforced as a hard stop. The potentiometer maps the angle to
volts with the line through params' end points (:class:`flexdigit.models.servo.PotentiometerMap`).

Two drives bring the command to the servo (``Servo(..., drive=...)``, ``Twin(servo_drive=...)``,
``sim?servo_drive=timer``):

- ``"serial"`` (the thesis rig): the serial board above, 0-19 ms from the frame to the servo's own pulse;
- ``"timer"`` (the reference firmware, ``firmware/flexdigit_board.c``): the microcontroller generates the pulse
  itself on Timer1, one every 20 ms frame (TIMER_FRAME_S), starting TIMER_PULSE_AFTER_TICK_S (1 ms) after the
  control tick at the frame's start; the hardware latches the pulse width at the pulse's start, so a command takes
  effect at the first frame boundary at or after it is issued, 1 ms later. A host loop on a twin with this drive is
  the like-for-like reference for the loop on the board (``tests/firmware/test_board.py``).

The servo's identified model already includes whatever load it carried when identified; the cable tension is not
fed back to it (the S-148 is position-controlled and its 0.297 N m stall torque is ~3x the ~0.1 N m the digit
needs at command 43).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import scipy.linalg

from flexdigit._validation import check_choice, check_int
from flexdigit.models.servo import PotentiometerMap, command_to_angle_rad

__all__ = ["Servo", "SERVO_DRIVES", "TIMER_FRAME_S", "TIMER_PULSE_AFTER_TICK_S"]

#: How a command reaches the servo: the thesis's serial board, or a pulse from the controller's own timer.
SERVO_DRIVES = ("serial", "timer")
#: The timer drive's frame (the firmware's Timer1 TOP: 20 ms, the servo's 50 Hz) and its pulse's start after the
#: control tick at a frame boundary (Timer1 is started 1 ms after the first tick: firmware/flexdigit_board.c), s.
TIMER_FRAME_S = 0.020
TIMER_PULSE_AFTER_TICK_S = 0.001


@lru_cache(maxsize=32)
def _servo_transition(wn: float, zeta: float, h: float) -> np.ndarray:
    a = np.array([[0.0, 1.0, 0.0], [-(wn**2), -2.0 * zeta * wn, wn**2], [0.0, 0.0, 0.0]])
    return scipy.linalg.expm(a * h)


class Servo:
    """Servo state (angle from the servo's 0 deg, rad; rate, rad/s) and its command schedule.

    Parameters
    ----------
    params : RigParams
    command : int
        Initial command, at rest there.
    drive : {"serial", "timer"}
        How commands reach the servo (see the module docstring): the serial board, or the firmware's timer.
    """

    def __init__(self, params, command: int, drive: str = "serial"):
        a = params.actuator
        self.params = params
        self.drive = check_choice(drive, "drive", SERVO_DRIVES, "Servo")
        self.wn = a.servo_wn_rad_s
        self.zeta = a.servo_zeta
        self.angle_min = math.radians(a.angle_min_deg)
        self.angle_max = math.radians(a.angle_max_deg)
        self.pot = PotentiometerMap.from_params(params)
        self.command = self.check_command(command)
        self.angle = float(command_to_angle_rad(self.command, params))
        self.rate = 0.0
        self.pending: list[tuple[float, int]] = []
        #: the timer drive's pulse start after the control tick, s (the firmware's PULSE_DELAY_MS: 1 ms, 5 ms for
        #: a described digit's image; ``sim?servo_drive=timer&pulse_delay_ms=5``)
        self.pulse_after_tick_s = TIMER_PULSE_AFTER_TICK_S
        self._targets: dict[int, float] = {}
        self._transitions: dict[float, np.ndarray] = {}

    def check_command(self, value) -> int:
        """Validate a serial position command (integer in ``command_min..command_max``)."""
        a = self.params.actuator
        return check_int(value, "command", "Twin", low=a.command_min, high=a.command_max)

    def schedule(self, value, issued_s: float, grid_s: float) -> float:
        """Latch ``value`` at the next frame and pulse of the drive; returns the grid time it takes effect (s).

        Examples
        --------
        >>> from flexdigit.params import RigParams
        >>> Servo(RigParams(), 8).schedule(30, 0.005, 0.002)  # frame at 20 ms, the servo's 52 Hz pulse at 38.5 ms
        0.04
        >>> Servo(RigParams(), 8, drive="timer").schedule(30, 0.005, 0.002)  # frame at 20 ms, its pulse at 21 ms
        0.022
        """
        value = self.check_command(value)
        if self.drive == "timer":
            frame = math.ceil(issued_s / TIMER_FRAME_S - 1e-9) * TIMER_FRAME_S
            pulse = frame + self.pulse_after_tick_s
        else:
            a = self.params.actuator
            frame = math.ceil(issued_s / a.serial_period_s - 1e-9) * a.serial_period_s
            pwm = 1.0 / a.pwm_frequency_hz
            pulse = math.ceil(frame / pwm - 1e-9) * pwm
        apply = math.ceil(pulse / grid_s - 1e-9) * grid_s
        self.pending.append((apply, value))
        self.pending.sort(key=lambda item: item[0])
        return apply

    def pulses_carrying(self, issued_s: float) -> int:
        """How many of the servo's pulses carry a command issued at ``issued_s``: 1 on the timer drive; on the serial
        board, its 52 Hz pulses between the command's 20 ms frame and the next (5.2, 3.4.1), 2 for one frame in 25.

        The loop's dither counts them (:meth:`flexdigit.rig.base.Rig.command_pulses`): a command the board reads
        twice turns the servo for twice as long.

        Examples
        --------
        >>> from flexdigit.params import RigParams
        >>> servo = Servo(RigParams(), 8)
        >>> [servo.pulses_carrying(k * 0.02) for k in range(24, 27)]  # frame 25 (0.5 s) starts on pulse 26
        [1, 2, 1]
        """
        if self.drive == "timer":
            return 1
        a = self.params.actuator
        frame = math.ceil(issued_s / a.serial_period_s - 1e-9) * a.serial_period_s
        pwm = 1.0 / a.pwm_frequency_hz
        first, after = (math.ceil(t / pwm - 1e-9) for t in (frame, frame + a.serial_period_s))
        return after - first

    def update_command(self, time_s: float) -> None:
        """Apply every scheduled command whose time has come (the last one wins)."""
        while self.pending and self.pending[0][0] <= time_s + 1e-12:
            self.command = self.pending.pop(0)[1]

    def step(self, h: float) -> None:
        """Advance the servo ``h`` seconds towards the current command's angle (exact for the linear model)."""
        phi = self._transitions.get(h)
        if phi is None:
            phi = self._transitions[h] = _servo_transition(self.wn, self.zeta, h)
        target = self._target(self.command)
        angle = phi[0, 0] * self.angle + phi[0, 1] * self.rate + phi[0, 2] * target
        rate = phi[1, 0] * self.angle + phi[1, 1] * self.rate + phi[1, 2] * target
        if angle > self.angle_max or angle < self.angle_min:  # mechanical stop
            angle = min(max(angle, self.angle_min), self.angle_max)
            rate = 0.0
        self.angle, self.rate = angle, rate

    def _target(self, command: int) -> float:
        # a dict per servo: hashing the frozen RigParams for an lru_cache key costs ~20 us a step
        angle = self._targets.get(command)
        if angle is None:
            angle = self._targets[command] = float(command_to_angle_rad(command, self.params))
        return angle

    def pot_v(self, angle_rad: float) -> float:
        """Potentiometer voltage (V) at a shaft angle (rad)."""
        # PotentiometerMap.voltage_v; np.degrees is math.degrees's x * (180 / pi) for arrays (Twin.read_at)
        degrees = np.degrees(angle_rad) if isinstance(angle_rad, np.ndarray) else math.degrees(angle_rad)
        return (degrees - self.pot.offset_deg) / self.pot.slope_deg_per_v

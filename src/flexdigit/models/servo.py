"""The servo, identified as a closed-loop second-order system, and its potentiometer (thesis 3.2.4, E 3.10).

The thesis identifies ``MT(s) = 421.5 / (s^2 + 23.11 s + 421.5)`` from a step of 51 commands, with the
potentiometer voltage as output, then multiplies it by the potentiometer's 109.1344 deg/V (times pi/180) and
calls the result "rad per serial command" (802.854 / (...)). That product is not in rad per command: MT(s) has
unit DC gain, so its output is in *commands' worth* of potentiometer travel, not volts; the potentiometer moves
(2.4755 - 0.4688)/254 = 0.0079 V per command, and 0.0079 V x 109.1344 deg/V = 0.8622 deg = 0.015048 rad per
command. :func:`servo_tf` gives both: ``form="printed"`` (802.854/...) and ``form="consistent"``
(0.015048 x 421.5/..., rad per command).

The potentiometer line ``theta_M = 109.1344 V - 51.162`` passes through (2.4755 V, 219 deg) and through
(0.4688 V, 0 deg): the "0.46688 V" printed for 0 deg is a transposition of 0.46880 (with 0.46688 the slope
would be 109.03 deg/V). :class:`PotentiometerMap` computes the line from the two end points in ``params`` and
offers the printed one.

Examples
--------
>>> mt = servo_tf(form="printed")
>>> [round(float(c), 1) for c in mt.den[0][0]]
[1.0, 23.1, 421.5]
>>> round(float(servo_tf(form="consistent").dcgain()), 6)     # rad per command
0.015048
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real
from typing import TYPE_CHECKING

import numpy as np

from flexdigit._validation import Interval, check_choice, declare, validate_fields
from flexdigit.errors import ParameterError
from flexdigit.models.polytf import PolyTF
from flexdigit.params import RigParams
from flexdigit.reference import thesis_value

__all__ = [
    "SERVO_FORMS",
    "servo_unit_poly",
    "servo_unit_tf",
    "servo_poly",
    "servo_tf",
    "PotentiometerMap",
    "command_to_angle_rad",
    "angle_to_command",
]

if TYPE_CHECKING:
    import control

SERVO_FORMS = ("unit", "printed", "consistent")


def servo_unit_poly(params: RigParams | None = None) -> PolyTF:
    """``MT(s) = wn^2/(s^2 + 2 zeta wn s + wn^2)`` with unit DC gain (3.2.4): 421.5/(s^2 + 23.11 s + 421.5).

    Built from ``params.actuator.servo_wn_rad_s`` (20.53 rad/s) and ``servo_zeta`` (0.5629), as a ``PolyTF``
    (no python-control import; :func:`servo_unit_tf` gives the ``control.TransferFunction``).
    """
    a = (params or RigParams()).actuator
    wn, z = a.servo_wn_rad_s, a.servo_zeta
    return PolyTF([wn**2], [1.0, 2.0 * z * wn, wn**2])


def servo_unit_tf(params: RigParams | None = None) -> control.TransferFunction:
    """:func:`servo_unit_poly` as a ``control.TransferFunction``: 421.5/(s^2 + 23.11 s + 421.5)."""
    return servo_unit_poly(params).to_control()


def servo_poly(params: RigParams | None = None, *, form: str = "consistent") -> PolyTF:
    """The servo from serial command to shaft angle, as a ``PolyTF`` (see :func:`servo_tf` for ``form``)."""
    params = params or RigParams()
    check_choice(form, "form", SERVO_FORMS, "servo_tf")
    unit = servo_unit_poly(params)
    if form == "unit":
        return unit
    if form == "printed":
        return unit * math.radians(PotentiometerMap.printed().slope_deg_per_v)  # E 3.10 x pi/180
    return unit * params.actuator.rad_per_command


def servo_tf(params: RigParams | None = None, *, form: str = "consistent") -> control.TransferFunction:
    """The servo from serial command to shaft angle.

    Parameters
    ----------
    params : RigParams, optional
        Rig parameters (thesis defaults).
    form : {"unit", "printed", "consistent"}
        ``"unit"``: MT(s) with unit DC gain (pot volts per pot volt of demand, as identified).
        ``"printed"``: MT(s) x 109.1344 pi/180 = 802.854/(s^2 + 23.11 s + 421.5), the thesis's
        "rad per SerialCommand" (off by the 0.0079 V per command the potentiometer moves).
        ``"consistent"``: MT(s) x rad_per_command (0.015048 rad per command), the shaft angle in rad.

    Returns
    -------
    control.TransferFunction
        rad per command for ``printed`` and ``consistent``.
    """
    return servo_poly(params, form=form).to_control()


@declare
@dataclass(frozen=True)
class PotentiometerMap:
    """The servo potentiometer's line, ``theta_M [deg] = slope_deg_per_v * V + offset_deg`` (3.2.4).

    Attributes
    ----------
    slope_deg_per_v : float
        deg per volt: 109.1344 as printed (E 3.10).
    offset_deg : float
        deg at 0 V: -51.162 as printed.

    Examples
    --------
    >>> pot = PotentiometerMap.printed()
    >>> round(pot.angle_deg(2.4755), 2)
    219.0
    >>> round(pot.voltage_v(0.0), 4)          # the 0-degree voltage the printed line implies
    0.4688
    """

    slope_deg_per_v: float
    offset_deg: float

    _parameter_constraints = {"slope_deg_per_v": [Interval(Real)], "offset_deg": [Interval(Real)]}

    def __post_init__(self) -> None:
        validate_fields(self)
        if self.slope_deg_per_v == 0:
            raise ParameterError("The 'slope_deg_per_v' parameter of PotentiometerMap must be non-zero. Got 0.")

    @classmethod
    def printed(cls) -> PotentiometerMap:
        """``theta_M = 109.1344 V - 51.162`` as printed in 3.2.4."""
        fit = thesis_value("actuator.pot_angle_fit_deg")
        return cls(float(fit["slope_per_v"]), float(fit["offset"]))

    @classmethod
    def from_params(cls, params: RigParams | None = None) -> PotentiometerMap:
        """The line through the two end points in ``params.actuator`` (0.46688 V at 0 deg, 2.4755 V at 219 deg).

        With the thesis defaults this gives 109.03 deg/V, not the printed 109.1344: the printed line goes through
        0.46880 V at 0 deg, so the printed end point is a transposed digit.
        """
        a = (params or RigParams()).actuator
        slope = (a.angle_max_deg - a.angle_min_deg) / (a.pot_v_at_max_angle_v - a.pot_v_at_min_angle_v)
        return cls(slope, a.angle_min_deg - slope * a.pot_v_at_min_angle_v)

    def angle_deg(self, voltage_v):
        """Shaft angle (deg) from potentiometer voltage (V); vectorised."""
        out = self.slope_deg_per_v * np.asarray(voltage_v, dtype=float) + self.offset_deg
        return out if out.ndim else float(out)

    def angle_rad(self, voltage_v):
        """Shaft angle (rad) from potentiometer voltage (V); vectorised."""
        return np.radians(self.angle_deg(voltage_v))

    def voltage_v(self, angle_deg):
        """Potentiometer voltage (V) at a shaft angle (deg): the inverse map; vectorised."""
        out = (np.asarray(angle_deg, dtype=float) - self.offset_deg) / self.slope_deg_per_v
        return out if out.ndim else float(out)


def command_to_angle_rad(command, params: RigParams | None = None):
    """Static servo angle (rad) for a serial command: ``(command - command_min) * rad_per_command`` (E 3.15).

    Measured from the servo's 0-degree position (command 0), not from the digit's equilibrium (command 8).
    """
    a = (params or RigParams()).actuator
    out = (np.asarray(command, dtype=float) - a.command_min) * a.rad_per_command + math.radians(a.angle_min_deg)
    return out if out.ndim else float(out)


def angle_to_command(angle_rad, params: RigParams | None = None):
    """Inverse of :func:`command_to_angle_rad` (real-valued commands, not rounded or clipped)."""
    a = (params or RigParams()).actuator
    out = (np.asarray(angle_rad, dtype=float) - math.radians(a.angle_min_deg)) / a.rad_per_command + a.command_min
    return out if out.ndim else float(out)

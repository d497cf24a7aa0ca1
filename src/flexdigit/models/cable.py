"""The cable: servo rotation -> cable shortening -> tip moment -> curvature and deflection (thesis 3.3, 3.4.2).

The cable runs at a constant eccentricity ``e`` from the strip's neutral axis and is inextensible, so shortening
it by ``dl = r_M theta_M`` (E 3.11) bends the digit into an arc of curvature ``1/rho = dl / (l e)`` (pure bending,
small angles). Beam theory then gives the moment and deflections::

    M = E I dl / (l e) = K2 theta_M           K2 = E I r_M / (l e)          (E 3.12, E 3.19)
    y(x) = M x^2 / (2 E I) = x^2 dl / (2 l e) (E 3.13 at x = l: y_max = l dl / (2 e), E 3.14)
    tip rotation = l / rho = dl / e = r_M theta_M / e

K2 from table 3.7 is 0.089427 N m/rad, 0.056 % above the printed 0.089377: the printed figure is reproduced to
all its digits with I = 5.85e-14 m^4, i.e. with the second moment rounded to three figures before multiplying
(table 3.7 prints 5.8532e-14).

Examples
--------
>>> round(k2_nm_per_rad(), 6)
0.089427
>>> round(tip_rotation_per_command_deg(), 3)     # deg of digit tip rotation per serial command
1.735
"""

from __future__ import annotations

import math

import numpy as np

from flexdigit._validation import check_array, check_positive
from flexdigit.params import RigParams

__all__ = [
    "cable_shortening_m",
    "curvature_per_m",
    "k2_nm_per_rad",
    "moment_nm",
    "deflection_m",
    "tip_deflection_m",
    "tip_rotation_rad",
    "tip_rotation_per_command_deg",
    "commands_for_tip_rotation",
    "table_3_4",
    "fit_tip_x_m",
]


def cable_shortening_m(theta_m_rad, params: RigParams | None = None):
    """``dl_M = theta_M r_M`` (E 3.11): cable shortening (m) for a servo rotation (rad); vectorised."""
    r = (params or RigParams()).actuator.cable_m_per_servo_rad
    out = np.asarray(theta_m_rad, dtype=float) * r
    return out if out.ndim else float(out)


def curvature_per_m(shortening_m, params: RigParams | None = None):
    """``1/rho = dl / (l e)`` (3.3): curvature (1/m) of the digit for a cable shortening (m); vectorised."""
    g = (params or RigParams()).geometry
    out = np.asarray(shortening_m, dtype=float) / (g.digit_length_m * g.cable_eccentricity_m)
    return out if out.ndim else float(out)


def k2_nm_per_rad(params: RigParams | None = None, *, second_moment_m4: float | None = None) -> float:
    """``K2 = E I r_M / (l e)``: tip moment per servo radian (N m/rad), E 3.19.

    Parameters
    ----------
    params : RigParams, optional
        Rig parameters (thesis defaults: 0.089427 N m/rad).
    second_moment_m4 : float, optional
        Override ``I``; ``5.85e-14`` reproduces the printed 0.089377.

    Examples
    --------
    >>> round(k2_nm_per_rad(second_moment_m4=5.85e-14), 6)      # the printed E 3.19 figure
    0.089377
    """
    p = params or RigParams()
    i = p.geometry.second_moment_m4 if second_moment_m4 is None else check_positive(second_moment_m4, "I", "K2")
    g = p.geometry
    return (
        p.material.youngs_modulus_pa
        * i
        * p.actuator.cable_m_per_servo_rad
        / (g.digit_length_m * g.cable_eccentricity_m)
    )


def moment_nm(theta_m_rad, params: RigParams | None = None):
    """Tip moment (N m) for a servo rotation (rad): ``M = K2 theta_M`` (E 3.19); vectorised."""
    out = k2_nm_per_rad(params) * np.asarray(theta_m_rad, dtype=float)
    return out if out.ndim else float(out)


def deflection_m(x_m, theta_m_rad, params: RigParams | None = None):
    """Deflection (m) at ``x_m`` from the base for a servo rotation (rad): ``y = theta r_M x^2 / (2 l e)`` (E 3.15).

    Broadcasts ``x_m`` against ``theta_m_rad``.
    """
    p = params or RigParams()
    g = p.geometry
    x = np.asarray(x_m, dtype=float)
    out = (
        np.asarray(theta_m_rad, dtype=float)
        * p.actuator.cable_m_per_servo_rad
        * x**2
        / (2.0 * g.digit_length_m * g.cable_eccentricity_m)
    )
    return out if out.ndim else float(out)


def tip_deflection_m(theta_m_rad, params: RigParams | None = None):
    """``y_max = l dl_M / (2 e)`` (E 3.14): tip deflection (m) at ``x = l``."""
    return deflection_m((params or RigParams()).geometry.digit_length_m, theta_m_rad, params)


def tip_rotation_rad(theta_m_rad, params: RigParams | None = None):
    """Tip rotation (rad) for a servo rotation (rad): ``l / rho = r_M theta_M / e``; vectorised."""
    p = params or RigParams()
    out = np.asarray(theta_m_rad, dtype=float) * p.actuator.cable_m_per_servo_rad / p.geometry.cable_eccentricity_m
    return out if out.ndim else float(out)


def tip_rotation_per_command_deg(params: RigParams | None = None) -> float:
    """Degrees of tip rotation per serial command, ``r_M (pi/180 x 0.8622) / e x 180/pi`` = 1.735 deg."""
    p = params or RigParams()
    return math.degrees(tip_rotation_rad(p.actuator.rad_per_command, p))


def commands_for_tip_rotation(rotation_deg, params: RigParams | None = None):
    """Serial command steps (from the equilibrium command) that rotate the tip by ``rotation_deg`` (cable model).

    30 degrees of tip ("beam") rotation is 17.3 commands (14.9 deg of servo rotation) by the cable model. The
    thesis says two other things: 3.4.1 calls commands 8..43 (35 steps, 30.2 deg of *servo* rotation) "0 to
    30 deg of beam rotation", and 3.6 says "approximately fifteen discrete steps or 12.93 degrees of motor
    rotation" (15 x 0.8622 deg).
    """
    out = np.asarray(rotation_deg, dtype=float) / tip_rotation_per_command_deg(params)
    return out if out.ndim else float(out)


def table_3_4(
    commands=None,
    params: RigParams | None = None,
    *,
    rad_per_command: float | None = None,
    tip_x_m: float | None = None,
) -> dict[str, np.ndarray]:
    """Table 3.4: theoretical deflection (mm) at the three gauges and the tip for commands 8..24 (E 3.15).

    Parameters
    ----------
    commands : array_like of int, optional
        Serial commands (default 8..24); the equilibrium command (8) is zero deflection.
    params : RigParams, optional
        Rig parameters (gauge positions, r_M, l, e, rad per command).
    rad_per_command : float, optional
        Override the servo's rad per command (default 0.8622 pi/180 = 0.015048; the printed "0.0150" does not
        reproduce the last rows of the table).
    tip_x_m : float, optional
        Where the ``y_max`` column is evaluated (default ``l`` = 0.270 m as E 3.14 says; the printed column
        fits 0.241 m, see :func:`fit_tip_x_m`).

    Returns
    -------
    dict
        ``commands``, ``y_sg1_mm``, ``y_sg2_mm``, ``y_sg3_mm`` (one per gauge in ``params``), ``y_max_mm``.
    """
    p = params or RigParams()
    a = p.actuator
    cmds = np.arange(a.equilibrium_command, a.equilibrium_command + 17) if commands is None else commands
    cmds = check_array(cmds, "commands", "table_3_4", ndim=1, low=a.command_min, high=a.command_max)
    rpc = a.rad_per_command if rad_per_command is None else check_positive(rad_per_command, "rad_per_command")
    theta = (cmds - a.equilibrium_command) * rpc
    out: dict[str, np.ndarray] = {"commands": cmds}
    for k, x in enumerate(p.geometry.gauge_positions_m, start=1):
        out[f"y_sg{k}_mm"] = 1e3 * deflection_m(x, theta, p)
    x_tip = p.geometry.digit_length_m if tip_x_m is None else check_positive(tip_x_m, "tip_x_m", "table_3_4")
    out["y_max_mm"] = 1e3 * deflection_m(x_tip, theta, p)
    return out


def fit_tip_x_m(y_max_mm, commands=None, params: RigParams | None = None) -> float:
    """The position x (m) at which E 3.15 gives a column of deflections (least squares on x^2).

    Applied to table 3.4's printed ``y_max`` column it returns 0.2410 m: neither ``l`` = 0.270 m (which gives
    4.09 mm per command) nor the 0.240 m strip (3.23 mm per command) reproduce the column.
    """
    p = params or RigParams()
    a = p.actuator
    y = check_array(y_max_mm, "y_max_mm", "fit_tip_x_m", ndim=1) * 1e-3
    cmds = np.arange(a.equilibrium_command, a.equilibrium_command + y.size) if commands is None else commands
    unit = deflection_m(1.0, (np.asarray(cmds, dtype=float) - a.equilibrium_command) * a.rad_per_command, p)
    x2 = float(np.dot(unit, y) / np.dot(unit, unit))  # y = x^2 * unit: linear least squares in x^2
    return math.sqrt(x2)

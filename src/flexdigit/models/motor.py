"""Armature-controlled DC motor, bare and with gearing and an inertial disc (thesis 3.2.1-3.2.3, E 3.6-3.9).

The rig's servo hides its motor behind its own position loop, so the thesis derives these transfer functions
symbolically only (table 3.3 has no values). :class:`DCMotor` holds the parameters, with example values of a
small geared DC motor (an assumption, in the range of the Maxon alternative of appendix C), so the models can be
evaluated and tested. Motor side::

    w_m / V_a = K_T / ((J_m s + K_D)(L_a s + R_a) + K_E K_T)                                        (E 3.6)
    theta_m / V_a = (E 3.6) / s                                                                      (E 3.7)

With a gearbox of ratio N = N2/N1 = theta_m/theta_2 and efficiency eta driving a load (disc) inertia J_L, the
reflected inertia is J_L / (eta N^2) and, multiplying through by eta N^2::

    w_m / V_a = eta N^2 K_T / ([(eta N^2 J_m + J_L) s + eta N^2 K_D](L_a s + R_a) + eta N^2 K_T K_E)  (E 3.8)
    theta_m / V_a = (E 3.8) / s                                                                      (E 3.9)

Two slips in the print, fixed here: E 3.9's bracket puts the ``s`` on the first factor only (it multiplies the
whole denominator of E 3.8), and table 3.3 gives the torque and back-EMF constants in "Nm/s" (they are N m/A
and V s/rad, equal in SI).

Examples
--------
>>> m = DCMotor()
>>> round(float(motor_speed_tf(m, geared=False).dcgain()), 2)     # K_T / (K_D R + K_T K_E), rad/s per V
70.12
>>> round(float(motor_speed_tf(m).dcgain()), 2)                   # gearing does not change it at the motor shaft
70.12
"""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Real
from typing import TYPE_CHECKING

from flexdigit._validation import Interval, check_choice, declare, validate_fields

__all__ = ["DCMotor", "motor_speed_tf", "motor_angle_tf", "mechanical_time_constant_s"]

if TYPE_CHECKING:
    import control


@declare
@dataclass(frozen=True)
class DCMotor:
    """Parameters of table 3.3, in SI, with example values (the thesis gives none).

    Attributes
    ----------
    torque_constant_nm_per_a : float
        K_TM (N m/A). Example 0.0136.
    back_emf_v_s_per_rad : float
        K_EM (V s/rad); equal to K_TM in SI for an ideal motor. Example 0.0136.
    rotor_inertia_kg_m2 : float
        J_M. Example 1.1e-6.
    resistance_ohm : float
        R_AM. Example 9.0.
    inductance_h : float
        L_AM (H; table 3.3 writes mH). Example 0.5e-3.
    viscous_damping_nm_s_per_rad : float
        K_DM (N m s/rad). Example 1e-6.
    gear_ratio : float
        N = N2/N1 = theta_m/theta_2 (motor turns per output turn). Example 300 (the 300:1 gearbox of 2.4).
    efficiency : float
        eta of the gearbox, in (0, 1]. Example 0.6.
    load_inertia_kg_m2 : float
        J_L = J_disc, the pulley ("inertial disc") on the output shaft. Example 2.0e-6 (an 11.5 mm aluminium disc).
    """

    torque_constant_nm_per_a: float = 0.0136
    back_emf_v_s_per_rad: float = 0.0136
    rotor_inertia_kg_m2: float = 1.1e-6
    resistance_ohm: float = 9.0
    inductance_h: float = 0.5e-3
    viscous_damping_nm_s_per_rad: float = 1e-6
    gear_ratio: float = 300.0
    efficiency: float = 0.6
    load_inertia_kg_m2: float = 2.0e-6

    _parameter_constraints = {
        "torque_constant_nm_per_a": [Interval(Real, 0, None, closed="neither")],
        "back_emf_v_s_per_rad": [Interval(Real, 0, None, closed="neither")],
        "rotor_inertia_kg_m2": [Interval(Real, 0, None, closed="neither")],
        "resistance_ohm": [Interval(Real, 0, None, closed="neither")],
        "inductance_h": [Interval(Real, 0, None)],
        "viscous_damping_nm_s_per_rad": [Interval(Real, 0, None)],
        "gear_ratio": [Interval(Real, 0, None, closed="neither")],
        "efficiency": [Interval(Real, 0, 1, closed="right")],
        "load_inertia_kg_m2": [Interval(Real, 0, None)],
    }

    def __post_init__(self) -> None:
        validate_fields(self)

    @property
    def reflected_inertia_kg_m2(self) -> float:
        """Inertia seen at the motor shaft, ``J_m + J_L / (eta N^2)`` (3.2.3)."""
        return self.rotor_inertia_kg_m2 + self.load_inertia_kg_m2 / (self.efficiency * self.gear_ratio**2)


def motor_speed_tf(motor: DCMotor | None = None, *, geared: bool = True) -> control.TransferFunction:
    """Motor-shaft speed per armature volt, ``w_m/V_a`` (rad/s per V): E 3.8 if ``geared`` else E 3.6."""
    import control  # here, not at the top: it costs 2 s of start-up (see flexdigit.models.polytf)

    m = motor or DCMotor()
    kt, ke, r, ind, kd = (
        m.torque_constant_nm_per_a,
        m.back_emf_v_s_per_rad,
        m.resistance_ohm,
        m.inductance_h,
        m.viscous_damping_nm_s_per_rad,
    )
    if geared:
        g = m.efficiency * m.gear_ratio**2  # eta N^2
        mech = control.tf([g * m.rotor_inertia_kg_m2 + m.load_inertia_kg_m2, g * kd], [1.0])
        elec = control.tf([ind, r], [1.0])
        num, den = g * kt, mech * elec + g * kt * ke  # E 3.8
    else:
        mech = control.tf([m.rotor_inertia_kg_m2, kd], [1.0])
        elec = control.tf([ind, r], [1.0])
        num, den = kt, mech * elec + kt * ke  # E 3.6
    return control.tf([num], den.num[0][0])


def motor_angle_tf(
    motor: DCMotor | None = None, *, geared: bool = True, shaft: str = "motor"
) -> control.TransferFunction:
    """Shaft angle per armature volt (rad per V): E 3.9 if ``geared`` else E 3.7.

    Parameters
    ----------
    shaft : {"motor", "output"}
        ``"motor"``: theta_m as in the thesis; ``"output"``: theta_2 = theta_m / N, the pulley's angle.
    """
    import control

    m = motor or DCMotor()
    check_choice(shaft, "shaft", ("motor", "output"), "motor_angle_tf")
    tf = motor_speed_tf(m, geared=geared) * control.tf([1.0], [1.0, 0.0])
    if shaft == "output":
        tf = tf * (1.0 / m.gear_ratio if geared else 1.0)
    return tf


def mechanical_time_constant_s(motor: DCMotor | None = None, *, geared: bool = True) -> float:
    """``tau_m = J R / (R K_D + K_T K_E)`` with J the (reflected) inertia, ignoring inductance (s)."""
    m = motor or DCMotor()
    j = m.reflected_inertia_kg_m2 if geared else m.rotor_inertia_kg_m2
    return (
        j
        * m.resistance_ohm
        / (m.resistance_ohm * m.viscous_damping_nm_s_per_rad + m.torque_constant_nm_per_a * m.back_emf_v_s_per_rad)
    )

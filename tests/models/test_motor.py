"""DC motor TFs (E 3.6-3.9) against hand-derived complex arithmetic at a few frequencies."""

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.models.motor import DCMotor, mechanical_time_constant_s, motor_angle_tf, motor_speed_tf

MOTOR = DCMotor(
    torque_constant_nm_per_a=0.02,
    back_emf_v_s_per_rad=0.021,
    rotor_inertia_kg_m2=3e-6,
    resistance_ohm=5.0,
    inductance_h=1e-3,
    viscous_damping_nm_s_per_rad=2e-6,
    gear_ratio=50.0,
    efficiency=0.7,
    load_inertia_kg_m2=4e-4,
)
W = np.array([0.3, 7.0, 120.0, 3000.0])  # rad/s

# Tolerances, each with the reason for its size
HAND_DERIVED_RTOL = 1e-10  # E 3.6-3.9 against the transfer functions derived by hand here: rounding only


def _hand_bare(s):
    m = MOTOR  # E 3.6 written out
    return m.torque_constant_nm_per_a / (
        (m.rotor_inertia_kg_m2 * s + m.viscous_damping_nm_s_per_rad) * (m.inductance_h * s + m.resistance_ohm)
        + m.back_emf_v_s_per_rad * m.torque_constant_nm_per_a
    )


def _hand_geared(s):
    # from T_M = (J_m + J_L/(eta N^2)) dw/dt + K_D w, T_M = K_T i, i = (V - K_E w)/(L s + R)
    m = MOTOR
    j = m.rotor_inertia_kg_m2 + m.load_inertia_kg_m2 / (m.efficiency * m.gear_ratio**2)
    return m.torque_constant_nm_per_a / (
        (j * s + m.viscous_damping_nm_s_per_rad) * (m.inductance_h * s + m.resistance_ohm)
        + m.back_emf_v_s_per_rad * m.torque_constant_nm_per_a
    )


@pytest.mark.parametrize("w", W)
def test_speed_tfs_match_hand_derivation(w):
    s = 1j * w
    assert complex(motor_speed_tf(MOTOR, geared=False)(s)) == pytest.approx(_hand_bare(s), rel=HAND_DERIVED_RTOL)
    assert complex(motor_speed_tf(MOTOR)(s)) == pytest.approx(_hand_geared(s), rel=HAND_DERIVED_RTOL)


@pytest.mark.parametrize("w", W)
def test_angle_tfs_are_speed_over_s(w):
    s = 1j * w
    assert complex(motor_angle_tf(MOTOR, geared=False)(s)) == pytest.approx(_hand_bare(s) / s, rel=HAND_DERIVED_RTOL)
    assert complex(motor_angle_tf(MOTOR)(s)) == pytest.approx(_hand_geared(s) / s, rel=HAND_DERIVED_RTOL)
    assert complex(motor_angle_tf(MOTOR, shaft="output")(s)) == pytest.approx(
        _hand_geared(s) / s / 50.0, rel=HAND_DERIVED_RTOL
    )


def test_geared_model_reduces_to_bare_without_load():
    m = DCMotor(gear_ratio=1.0, efficiency=1.0, load_inertia_kg_m2=0.0)
    for w in W:
        assert complex(motor_speed_tf(m)(1j * w)) == pytest.approx(complex(motor_speed_tf(m, geared=False)(1j * w)))


def test_time_constant_and_reflected_inertia():
    m = MOTOR
    j = 3e-6 + 4e-4 / (0.7 * 50.0**2)
    assert m.reflected_inertia_kg_m2 == pytest.approx(j)
    assert mechanical_time_constant_s(m) == pytest.approx(j * 5.0 / (5.0 * 2e-6 + 0.02 * 0.021))


def test_bad_parameters_raise():
    with pytest.raises(ParameterError, match="efficiency"):
        DCMotor(efficiency=1.5)
    with pytest.raises(ParameterError, match="shaft"):
        motor_angle_tf(shaft="pulley")

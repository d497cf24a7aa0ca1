"""Digit, servo, cable and conversion models against the thesis tables (reference/thesis.toml) and closed forms."""

import math

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.models import cable, conversion, second_order, servo
from flexdigit.params import RigParams
from flexdigit.reference import thesis_value

# Tolerances, each with the reason for its size
EXACT_RTOL = 1e-12  # a closed form against the same formula written out here: rounding only
PRINTED_5_DIGITS_RTOL = 1e-4  # a figure printed to 5 significant digits
K1_PRINTED_RTOL = 2e-4  # E 3.16-3.18's K1, printed to 5 digits from a slope printed to 3-4
PRINTED_4_DIGITS_RTOL = 1e-3  # a figure printed to 4 significant digits
ROUNDED_BEFORE_RTOL = 2e-3  # 1.782 = 2 x 0.068 x 13.1: zeta and wn rounded before multiplying (0.16 %)
PRINTED_2_DECIMALS_ATOL = 0.01  # a figure printed to 2 decimals
TABLE_3_2_WN_ATOL = 6e-5  # table 3.2's wn, printed to 4 decimals, from wd and zeta also rounded
K2_PRINTED_ATOL = 5e-7  # K2 = 0.089377, printed to 6 decimals
TIP_X_ATOL = 5e-4  # the tip position the printed y_max column fits, to the mm the thesis rounds to


# --- digit (3.1.2, tables 3.1 and 3.2) -----------------------------------------------------------------------
@pytest.mark.parametrize("table", ["without_housing", "with_housing"])
def test_zeta_from_overshoot_reproduces_tables_3_1_and_3_2_to_4_decimals(table):
    t = thesis_value(f"digit.release_tests_{table}")
    zeta = second_order.zeta_from_overshoot(t["percent_overshoot"])
    printed = np.array(t["zeta"])
    ok = np.isfinite(zeta)
    assert np.array_equal(np.round(zeta[ok], 4), printed[ok])


def test_garbled_overshoot_of_table_3_2_row_2_is_nan_and_its_zeta_implies_80_597():
    t = thesis_value("digit.release_tests_with_housing")
    zeta = second_order.zeta_from_overshoot(t["percent_overshoot"])
    assert math.isnan(zeta[1])
    assert second_order.overshoot_from_zeta(t["zeta"][1]) == pytest.approx(80.597, abs=PRINTED_2_DECIMALS_ATOL)


def test_table_3_2_wn_follows_from_wd_but_table_3_1_does_not():
    with_h = thesis_value("digit.release_tests_with_housing")
    wn = second_order.natural_frequency_from_damped(with_h["wd_rad_s"], with_h["zeta"])
    assert np.allclose(wn, with_h["wn_rad_s"], atol=TABLE_3_2_WN_ATOL)
    bare = thesis_value("digit.release_tests_without_housing")
    wn = second_order.natural_frequency_from_damped(bare["wd_rad_s"], bare["zeta"])
    assert np.all(np.array(bare["wn_rad_s"]) - wn > 2e-3)  # printed wn exceeds wd/sqrt(1-zeta^2) by ~0.003


def test_settling_time_formula_round_trip_and_e_s_of_3_1_2():
    assert second_order.wn_from_settling_time(
        second_order.settling_time_from_wn(13.0995, 0.06791), 0.06791
    ) == pytest.approx(13.0995)
    e = second_order.digit_tf_from_params(RigParams())
    den = e.den[0][0]
    assert den[2] == pytest.approx(171.61, rel=PRINTED_4_DIGITS_RTOL)  # 3.1.2: s^2 + 1.782 s + 171.61
    assert den[1] == pytest.approx(1.782, rel=ROUNDED_BEFORE_RTOL)


def test_overshoot_out_of_range_raises():
    with pytest.raises(ParameterError, match="percent_overshoot"):
        second_order.zeta_from_overshoot([50.0, 120.0])


# --- servo (3.2.4) --------------------------------------------------------------------------------------
def test_mt_coefficients_and_printed_rad_gain():
    mt = servo.servo_tf(form="unit")
    assert mt.den[0][0][1] == pytest.approx(23.11, rel=PRINTED_4_DIGITS_RTOL)
    assert mt.den[0][0][2] == pytest.approx(421.5, rel=PRINTED_4_DIGITS_RTOL)
    printed = servo.servo_tf(form="printed")
    assert printed.num[0][0][-1] == pytest.approx(
        thesis_value("actuator.model.mt_rad_num")[0], rel=PRINTED_4_DIGITS_RTOL
    )


def test_consistent_servo_gain_is_219_over_254_degrees():
    assert float(servo.servo_tf(form="consistent").dcgain()) == pytest.approx(math.radians(219 / 254))


def test_potentiometer_map_and_inverse():
    pot = servo.PotentiometerMap.printed()
    v = np.array([0.5, 1.2, 2.4])
    assert np.allclose(pot.voltage_v(pot.angle_deg(v)), v)
    assert pot.angle_deg(2.4755) == pytest.approx(219.0, abs=PRINTED_2_DECIMALS_ATOL)  # 3.2.4 end point
    # end points from params give a slope 0.1 % below the printed 109.1344 (0.46688 vs 0.46880 V)
    assert servo.PotentiometerMap.from_params().slope_deg_per_v == pytest.approx(219 / (2.4755 - 0.46688))


def test_command_angle_round_trip():
    c = np.array([0.0, 8.0, 254.0])
    assert np.allclose(servo.angle_to_command(servo.command_to_angle_rad(c)), c)
    assert servo.command_to_angle_rad(254) == pytest.approx(math.radians(219))


# --- cable (3.3, 3.4.2, table 3.4) ------------------------------------------------------------------------
def test_k2_within_0p1_percent_and_printed_with_rounded_i():
    k2 = cable.k2_nm_per_rad()
    printed = thesis_value("cable.k2_nm_per_rad")
    assert abs(k2 / printed - 1) < PRINTED_4_DIGITS_RTOL
    assert cable.k2_nm_per_rad(second_moment_m4=5.85e-14) == pytest.approx(printed, abs=K2_PRINTED_ATOL)
    # closed form with table 3.7 values
    assert k2 == pytest.approx(205e9 * 12.7e-3 * 0.381e-3**3 / 12 * 11.5e-3 / (0.270 * 5.715e-3), rel=EXACT_RTOL)


@pytest.mark.parametrize("column", ["y_sg1_mm", "y_sg2_mm", "y_sg3_mm"])
def test_table_3_4_gauge_columns_to_printed_precision(column):
    ours = cable.table_3_4()[column]
    printed = np.array(thesis_value(f"conversion.table_3_4_{column}"))
    assert np.array_equal(np.round(ours, 2), printed)


def test_table_3_4_y_max_column_fits_0p241_m_not_l():
    printed = np.array(thesis_value("conversion.table_3_4_y_max_mm"))
    x = cable.fit_tip_x_m(printed)
    assert x == pytest.approx(0.241, abs=TIP_X_ATOL)
    assert np.array_equal(np.round(cable.table_3_4(tip_x_m=round(x, 3))["y_max_mm"], 2), printed)
    assert not np.array_equal(np.round(cable.table_3_4()["y_max_mm"], 2), printed)  # x = l = 0.27 m


def test_rounded_0p0150_rad_per_command_does_not_reproduce_table_3_4():
    ours = cable.table_3_4(rad_per_command=0.0150)["y_sg1_mm"]
    assert not np.array_equal(np.round(ours, 2), thesis_value("conversion.table_3_4_y_sg1_mm"))


def test_cable_chain_is_consistent():
    theta = 0.2
    p = RigParams()
    kappa = cable.curvature_per_m(cable.cable_shortening_m(theta))
    assert cable.moment_nm(theta) == pytest.approx(kappa * p.bending_stiffness_n_m2)  # E 3.12
    assert cable.tip_deflection_m(theta) == pytest.approx(0.270 * theta * 11.5e-3 / (2 * 5.715e-3))  # E 3.14
    assert cable.tip_rotation_rad(theta) == pytest.approx(kappa * 0.270)
    assert cable.commands_for_tip_rotation(30.0) == pytest.approx(17.29, abs=PRINTED_2_DECIMALS_ATOL)


# --- conversion (3.4.1, 3.4.3) --------------------------------------------------------------------------------
def test_k1_from_printed_fits_reproduces_e_3_16_to_3_18():
    assert np.allclose(
        conversion.k1_printed_command_per_mm(), thesis_value("conversion.k1_command_per_mm"), rtol=K1_PRINTED_RTOL
    )


def test_k3_from_printed_fits_reproduces_e_3_23_to_3_25():
    assert np.allclose(
        conversion.k3_printed_mm_per_v(), thesis_value("conversion.k3_mm_per_v"), rtol=PRINTED_5_DIGITS_RTOL
    )


def test_printed_k3_offsets_leave_out_b():
    d, v = conversion.printed_deflection_fits(), conversion.printed_voltage_fits()
    as_printed = conversion.k3_offsets_as_printed_mm(d, v)
    printed = thesis_value("conversion.k3_offset_mm")
    assert as_printed[1:] == pytest.approx(printed[1:], rel=PRINTED_5_DIGITS_RTOL)
    assert as_printed[0] == pytest.approx(10 * printed[0], rel=PRINTED_4_DIGITS_RTOL)  # gauge 1 printed a tenth of it


def test_printed_fits_pass_through_command_8():
    for f in conversion.printed_deflection_fits():
        assert f.inverse(0.0) == pytest.approx(8.0, abs=PRINTED_2_DECIMALS_ATOL)


def test_least_squares_fit_against_closed_form():
    x = np.arange(8, 25, dtype=float)
    y = 0.7 * x - 3.0
    f = conversion.linear_fit(x, y)
    assert (f.slope, f.intercept) == pytest.approx((0.7, -3.0))
    g = conversion.linear_fit(x, y + 0.01 * (x - 16) ** 2, through=(8.0, 2.6))
    assert g(8.0) == pytest.approx(2.6)
    # closed form of the constrained slope: sum(dx dy) / sum(dx^2)
    dx = x - 8
    assert g.slope == pytest.approx(np.sum(dx * (y + 0.01 * (x - 16) ** 2 - 2.6)) / np.sum(dx**2))


def test_percent_error_is_relative_to_measurement_as_table_3_6():
    theory = cable.table_3_4()["y_sg2_mm"][1]
    assert conversion.percent_error(theory, 3.5) == pytest.approx(70.80, abs=PRINTED_2_DECIMALS_ATOL)  # table 3.6 row 9


def test_fit_length_mismatch_raises():
    with pytest.raises(ParameterError):
        conversion.linear_fit([1, 2, 3], [1, 2])

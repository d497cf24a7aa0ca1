"""Rig parameters: thesis defaults, derived figures, TOML round trip, and the messages of bad files."""

import math

import pytest

from flexdigit.errors import ParameterError
from flexdigit.params import Actuator, Geometry, RigParams, Sensors, load_params, save_params
from flexdigit.reference import thesis_value

# Tolerances, each with the reason for its size
PRINTED_5_DIGITS_RTOL = 1e-4  # a figure printed to 5 significant digits (table 3.7's I, E 3.15's 0.8622)
PRINTED_4_DECIMALS_ATOL = 5e-5  # a figure printed to 4 decimals (0.8622 deg, 0.0079 V per command)


def test_defaults_match_the_thesis_tables():
    p = RigParams()
    # table 3.7: I = 5.8532e-14 m^4 from w t^3 / 12
    assert p.geometry.second_moment_m4 == pytest.approx(
        thesis_value("geometry.second_moment_m4"), rel=PRINTED_5_DIGITS_RTOL
    )
    assert list(p.geometry.gauge_positions_m) == thesis_value("geometry.strain_gauge_positions_from_base_m")
    # E 3.15: 219/254 = 0.8622 degrees per command
    assert p.actuator.deg_per_command == pytest.approx(
        thesis_value("actuator.deg_per_command"), abs=PRINTED_4_DECIMALS_ATOL
    )
    assert p.actuator.rad_per_command == pytest.approx(0.8622 * math.pi / 180, rel=PRINTED_5_DIGITS_RTOL)
    # 3.2.4 / [plant].note: the potentiometer moves 0.0079 V per command
    assert p.actuator.pot_v_per_command == pytest.approx(0.0079, abs=PRINTED_4_DECIMALS_ATOL)
    # 16 bits over 10 V
    assert p.sensors.adc_lsb_v == pytest.approx(10 / 65536)


def test_toml_round_trip(tmp_path):
    p = RigParams().replace(sensors=Sensors(bridge="full", excitation_v=2.5))
    path = save_params(p, tmp_path / "rig.toml")
    assert load_params(path) == p


def test_partial_file_keeps_defaults(tmp_path):
    path = tmp_path / "rig.toml"
    path.write_text("[actuator]\nequilibrium_command = 10\n")
    p = load_params(path)
    assert p.actuator.equilibrium_command == 10
    assert p.geometry == Geometry()


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        (
            "[geometry]\ngauge_positions_m = [0.045, 0.3]\n",
            ["rig.toml", "gauge_positions_m", "0.3", "inside (0, 0.27]"],
        ),
        (
            "[actuator]\nequilibrium_command = 300\n",
            ["rig.toml", "equilibrium_command", "300", "integer inside [0, 254]"],
        ),
        ("[sensors]\nbridge = 'third'\n", ["bridge", "'third'", "'quarter', 'half', 'full'"]),
        ("[sensors]\ngauge_factor = -1.0\n", ["gauge_factor", "-1.0", "inside [0.5, 250]", "semiconductor"]),
        ("[sensors]\ngauge_factor = nan\n", ["gauge_factor", "finite"]),
        ("[geometry]\nlength = 1\n", ["unknown key 'length'", "[geometry]", "digit_length_m"]),
        ("[gemoetry]\n", ["unknown section 'gemoetry'"]),
        ("[actuator]\noperating_commands = 8\n", ["operating_commands", "must be a list"]),
        ("[actuator]\noperating_commands = [43, 8]\n", ["operating_commands", "two increasing"]),
        ("[actuator\n", ["not valid TOML"]),
    ],
)
def test_bad_files_name_the_key_value_and_expectation(tmp_path, text, fragments):
    path = tmp_path / "rig.toml"
    path.write_text(text)
    with pytest.raises(ParameterError) as info:
        load_params(path)
    for fragment in fragments:
        assert fragment in str(info.value)


def test_bad_values_in_code_name_the_owner():
    with pytest.raises(ParameterError, match="The 'command_max' parameter of Actuator"):
        Actuator(command_max=255)  # 255 is the board's sync byte, never a position
    with pytest.raises(ValueError, match="strain_gauge|gauge_positions_m"):
        Geometry(gauge_positions_m=(0.1, 0.05))


def test_write_to_a_missing_directory_says_so(tmp_path, capsys):
    # a write error is about the directory, not "no such file" (the file is what is being created)
    from flexdigit.cli import main
    from flexdigit.errors import DataFileError

    target = tmp_path / "nonexistent" / "rig.toml"
    with pytest.raises(DataFileError, match="the directory .*nonexistent does not exist"):
        save_params(RigParams(), target)
    assert main(["params", "--write", str(target)]) == 2
    err = capsys.readouterr().err
    assert f"cannot write the rig parameters to {target}: the directory {target.parent} does not exist" in err
    assert "no such file" not in err
    assert "Traceback" not in err
    assert not target.parent.exists()


def test_write_onto_a_directory_or_under_a_file_is_refused(tmp_path):
    from flexdigit.errors import DataFileError

    with pytest.raises(DataFileError, match="it is a directory; give a file name"):
        save_params(RigParams(), tmp_path)
    (tmp_path / "plain").write_text("x")
    with pytest.raises(DataFileError, match="plain is not a directory"):
        save_params(RigParams(), tmp_path / "plain" / "rig.toml")


# The unit slips and absurd numbers in a params file: each refused naming the file, the key, the value, the
# plausible range and (where one fits) the slip.
@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ("[geometry]\nstrip_thickness_m = 0.381\n", ["strip_thickness_m", "0.381 m", "did you mean mm (0.000381 m)"]),
        ("[material]\nyoungs_modulus_pa = 205\n", ["youngs_modulus_pa", "did you mean GPa (2.05e+11 Pa)"]),
        ("[actuator]\npulley_radius_m = 11.5\n", ["pulley_radius_m", "did you mean mm (0.0115 m)"]),
        ("[geometry]\ncable_eccentricity_m = 5.715\n", ["cable_eccentricity_m", "did you mean mm (0.005715 m)"]),
        ("[geometry]\nstrip_length_m = 1000.0\n", ["strip_length_m", "1000.0 m", "inside [0.02, 2] m"]),
        ("[geometry]\ndigit_length_m = 10.0\n", ["digit_length_m", "10.0 m", "inside [0.02, 2] m"]),
        ("[sensors]\ngauge_factor = 1e6\n", ["gauge_factor", "1000000.0", "semiconductor gauges"]),
        ("[sensors]\namplifier_gain_v_per_v = 1e308\n", ["amplifier_gain_v_per_v", "1e+308", "inside [1, 100000]"]),
        ("[geometry]\nstrip_thickness_m = 5e-324\n", ["strip_thickness_m", "5e-324"]),
        ("[actuator]\npwm_frequency_hz = 1e308\n", ["pwm_frequency_hz", "1e+308 Hz", "inside [20, 1000] Hz"]),
    ],
)
def test_implausible_values_and_unit_slips_are_refused(tmp_path, text, fragments):
    path = tmp_path / "rig.toml"
    path.write_text(text)
    with pytest.raises(ParameterError) as info:
        load_params(path)
    message = str(info.value)
    assert message.startswith(str(path))
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message, message


def test_a_strip_the_servo_cannot_bend_is_refused():
    # each field inside its own range, together a strip 100 times too stiff for the servo: the derived check
    geometry = Geometry(strip_thickness_m=4e-3, strip_width_m=0.05)
    with pytest.raises(ParameterError, match=r"cannot bend: K2 = E I r_M / \(l e\) = .* N m/rad") as info:
        RigParams(geometry=geometry)
    assert "stalls at 0.297 N m" in str(info.value)


def test_the_thesis_rig_bends_with_room_to_spare():
    # 0.16 N m of servo torque for the full 90 deg (E 3.19 with table 3.7), against the 0.297 N m stall torque
    p = RigParams()
    g, a = p.geometry, p.actuator
    torque = p.bending_stiffness_n_m2 * math.radians(90) / g.strip_length_m * a.pulley_radius_m / g.cable_eccentricity_m
    assert 0.15 < torque < 0.17

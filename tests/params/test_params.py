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
        ("[sensors]\ngauge_factor = -1.0\n", ["gauge_factor", "-1.0", "inside (0, inf)"]),
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
    assert "no such file" not in err and "Traceback" not in err
    assert not target.parent.exists()


def test_write_onto_a_directory_or_under_a_file_is_refused(tmp_path):
    from flexdigit.errors import DataFileError

    with pytest.raises(DataFileError, match="it is a directory; give a file name"):
        save_params(RigParams(), tmp_path)
    (tmp_path / "plain").write_text("x")
    with pytest.raises(DataFileError, match="plain is not a directory"):
        save_params(RigParams(), tmp_path / "plain" / "rig.toml")

"""The twin's calibration file: round trip, strict validation on load (unknown, missing, mistyped, out-of-range
keys each named in one line), explicit partial files, and use_calibration's scoped default.

The fit itself (CalibrationTargets, calibrate) lives in flexdigit.calibrate and is tested in tests/calibrate.
"""

import numpy as np
import pytest

from flexdigit.errors import DataFileError, OutputExistsError, ParameterError
from flexdigit.twin import Twin
from flexdigit.twin.calibration import (
    FIELDS,
    Calibration,
    default_calibration,
    default_calibration_source,
    default_fit_record,
    load_calibration,
    load_calibration_record,
    packaged_calibration,
    save_calibration,
    use_calibration,
)


def _write(tmp_path, text, name="cal.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _full_table(**changes) -> str:
    """A complete [calibration] table written by hand (TOML literals), the packaged values unless changed."""
    values = {**packaged_calibration().to_dict(), **changes}
    lines = ["[calibration]"]
    for key, value in values.items():
        lines.append(f"{key} = {value!r}" if not isinstance(value, str) else f'{key} = "{value}"')
    return "\n".join(lines).replace("'", '"') + "\n"


def test_round_trip_keeps_every_value_and_the_fit_record(tmp_path):
    cal = default_calibration().replace(pot_noise_v=0.001, channel_gain=(0.09, 0.12, 0.1))
    fit = {"source": "test", "residuals": [{"target": "x", "measured": 1.0, "twin": 1.01, "unit": ""}]}
    path = save_calibration(cal, tmp_path / "cal.toml", fit)
    assert load_calibration(path) == cal
    again, record = load_calibration_record(path)
    assert again == cal
    assert record["residuals"][0]["twin"] == 1.01


def test_a_hand_written_complete_file_loads(tmp_path):
    path = _write(tmp_path, _full_table(strip_beta_s=7e-4))
    assert load_calibration(path).strip_beta_s == 7e-4


def test_saving_never_clobbers_without_force(tmp_path):
    path = save_calibration(default_calibration(), tmp_path / "cal.toml")
    before = path.read_text()
    with pytest.raises(OutputExistsError, match="cal.toml.*--force"):
        save_calibration(default_calibration().replace(pot_noise_v=0.0), path)
    assert path.read_text() == before
    save_calibration(default_calibration().replace(pot_noise_v=0.0), path, force=True)
    assert load_calibration(path).pot_noise_v == 0.0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[calibration]\nsuport_mass = 1\n", r"bad\.toml: unknown key 'suport_mass' in \[calibration\]"),
        ("wibble = 1\n[calibration]\nstrip_beta_s = 1e-3\n", r"bad\.toml: unknown key 'wibble'"),
        ("[calibration\n", r"bad\.toml: not valid TOML"),
        ("[fit]\ncost = 1\n", r"bad\.toml: no \[calibration\] table"),
        ('based_on = "thesis"\n[calibration]\n', r"bad\.toml: key 'based_on' must be one of 'default'"),
    ],
)
def test_structural_errors_name_the_file_and_key(tmp_path, text, message):
    with pytest.raises(DataFileError, match=message):
        load_calibration(_write(tmp_path, text, "bad.toml"))


def test_a_missing_key_is_an_error_naming_it_not_a_silent_default(tmp_path):
    text = _full_table().replace("strip_beta_s = 0.00032625951945203024\n", "")
    assert "strip_beta_s" not in text
    with pytest.raises(DataFileError, match=r"bad\.toml: \[calibration\] lacks key 'strip_beta_s'.*based_on"):
        load_calibration(_write(tmp_path, text, "bad.toml"))


def test_an_explicitly_partial_file_takes_the_rest_from_the_packaged_default(tmp_path):
    path = _write(tmp_path, 'based_on = "default"\n[calibration]\nhousing_beta_s = 0.03\n')
    got = load_calibration(path)
    assert got == packaged_calibration().replace(housing_beta_s=0.03)


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("strip_beta_s", '"a lot"', r"key 'strip_beta_s' must be a number \(s\). Got 'a lot'"),
        ("strip_beta_s", "true", r"key 'strip_beta_s' must be a number"),
        ("strip_beta_s", "nan", r"key 'strip_beta_s' must be a finite number"),
        ("strip_beta_s", "[1e-3]", r"key 'strip_beta_s' must be a number"),
        ("channel_gain", "0.1", r"key 'channel_gain' must be a list of numbers, one per gauge"),
        ("channel_gain", '[0.1, "x", 0.1]', r"key 'channel_gain' must be a list of numbers"),
        ("channel_gain", "[]", r"key 'channel_gain' must be a list of numbers"),
        ("support_mass_kg", "[-1.0, 0.01, 0.01]", r"'support_mass_kg' parameter of Calibration"),
        ("support_mass_kg", "[8.4, 8.4, 8.4]", r"'support_mass_kg' .*\[0, 1\]"),  # grams written as kg
        ("cable_friction_ratio", "1.5", r"'cable_friction_ratio' .*\[0, 1\]"),
        ("cable_stiffness_n_m", "0", r"'cable_stiffness_n_m'"),
        ("channel_gain", "[0.1, 0.0, 0.1]", r"'channel_gain'"),  # a dead channel
        ("noise_white_v", "[0.002, 0.002]", r"'noise_white_v' .*3 values, one per gauge"),
        ("housing_ei_n_m2", "[0.005, 0.004]", r"'housing_ei_n_m2' .*3 values, one per section"),
        # the short key read first: both keys named, the values as plain numbers
        ("channel_gain", "[0.1, 0.1]", r"'channel_offset_v' .* has 3 values but 'channel_gain' has 2 .* Got \[-0\.1"),
    ],
)
def test_bad_values_are_one_line_naming_file_and_key(tmp_path, key, value, message):
    text = 'based_on = "default"\n[calibration]\n' + f"{key} = {value}\n"
    with pytest.raises(DataFileError, match=r"^[^\n]*bad\.toml: [^\n]*" + message) as info:
        load_calibration(_write(tmp_path, text, "bad.toml"))
    assert "\n" not in str(info.value)


def test_every_declared_bound_is_enforced():
    # generated from the declarations: just outside each bound is refused, the bound itself (closed) accepted
    for name, (kind, low, high, low_open, _) in FIELDS.items():
        n = 1 if kind == "scalar" else 3

        def value(x, n=n):
            return x if n == 1 else (x,) * n

        for bad in (low - 1e-9 if not low_open else low, high * (1 + 1e-9) + 1e-12):
            with pytest.raises(ParameterError, match=name):
                Calibration(**{name: value(bad)})
        Calibration(**{name: value(high)})
        if not low_open:
            Calibration(**{name: value(low)})


def test_calibration_rejects_nan():
    with pytest.raises(ValueError, match="strip_beta_s"):
        Calibration(strip_beta_s=float("nan"))


def test_use_calibration_sets_the_default_for_a_block_and_restores_it():
    stiff = packaged_calibration().replace(housing_ei_n_m2=(0.01, 0.008, 0.008))
    with use_calibration(stiff, "stiff.toml", fit={"source": "test"}):
        assert default_calibration() is stiff
        assert default_calibration_source() == "stiff.toml"
        assert default_fit_record() == {"source": "test"}
        twin = Twin(seed=0, command=24)
        assert twin.calibration is stiff
        stiff_tip = twin.deflection_m([0.27])[0]
    assert default_calibration() is packaged_calibration()
    assert default_calibration_source() == "packaged"
    assert "residuals" in default_fit_record()
    # a stiffer housing bends less under the same command: the block's twin really was another digit
    assert abs(stiff_tip) < abs(Twin(seed=0, command=24).deflection_m([0.27])[0])
    with pytest.raises(RuntimeError), use_calibration(stiff):
        raise RuntimeError("inside")
    assert default_calibration() is packaged_calibration()
    np.testing.assert_array_equal(default_calibration().housing_ei_n_m2, packaged_calibration().housing_ei_n_m2)


def test_a_directory_given_as_the_calibration_file_is_named(tmp_path):
    (tmp_path / "cal.toml").mkdir()
    with pytest.raises(DataFileError, match=r"cal\.toml: not a file \(a directory\?\); expected a calibration TOML"):
        load_calibration(tmp_path / "cal.toml")

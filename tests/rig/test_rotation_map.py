"""A rotation map a user can trust: settling detected from the readings, rotations from measured deflections,
an uncertainty that means what it says, maps saved and loaded with their provenance.

Oracles: rigs whose response is a closed form (first-order lag, a damped sine of known envelope), digit shapes
integrated numerically here (``scipy.integrate.quad`` of the tangent angle, not the package's arc formula), and
Monte Carlo coverage of the stated uncertainty on synthetic sweeps with known sensitivities.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import quad

from flexdigit.errors import DataFileError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.base import Rig
from flexdigit.rig.rotation import (
    RotationEstimator,
    calibrate_rotation,
    load_rotation_map,
    save_rotation_map,
    wait_until_settled,
)
from flexdigit.rig.rotation_reference import DigitShape, read_reference, rotations_from_deflections

from .helpers import FakeClock

NOISE_V = 0.002


class SignalRig(Rig):
    """Gauges = ``signal(t since the last command, command)`` x (1, 1.4, 1) + seeded white noise, virtual time."""

    name = "signal"

    def __init__(self, signal, noise_v=NOISE_V, seed=0):
        self.clock_ = FakeClock()
        super().__init__(clock=self.clock_, sleep=self.clock_.sleep)
        self.signal, self.noise_v = signal, noise_v
        self.rng = np.random.default_rng(seed)
        self.commanded_at = 0.0

    def _read(self):
        value = self.signal(self.clock_.now - self.commanded_at, self.command)
        return np.array([1.0, 1.4, 1.0]) * value + self.noise_v * self.rng.standard_normal(3), math.nan

    def _send(self, command):
        self.commanded_at = self.clock_.now


def test_settling_of_a_first_order_lag_is_detected_where_its_creep_drops_below_the_noise():
    tau, step = 0.3, 0.2  # V
    rig = SignalRig(lambda t, c: step * (1 - math.exp(-t / tau)) if c != 8 else 0.0)
    rig.write_command(20)
    settled = wait_until_settled(rig, window_s=1.0)
    # the window's mean is within a few noise standard errors of the final value ...
    np.testing.assert_allclose(settled.gauges_v, step * np.array([1.0, 1.4, 1.0]), atol=0.6 * NOISE_V)
    # ... because it waited until the drift across the 1 s window fell to about the noise: step e^{-t/tau} (1 -
    # e^{-1/tau}) = noise at t = tau ln(step (1 - e^{-1/tau}) / noise) after the window's start
    t_drift = tau * math.log(step * (1 - math.exp(-1 / tau)) / NOISE_V) + 1.0
    assert t_drift - 0.5 < settled.waited_s < t_drift + 1.0
    assert settled.noise_v == pytest.approx(NOISE_V * np.ones(3), rel=0.35)  # noise from the second differences


def test_a_ringing_digit_is_read_only_once_the_swing_is_below_the_noise():
    # a lightly damped 2 Hz mode (zeta 0.01): the envelope A e^{-zeta w t} reaches the noise after ln(A/noise)/(zeta w)
    zeta, w, amplitude = 0.01, 2 * math.pi * 2, 0.02
    rig = SignalRig(lambda t, c: 0.1 + amplitude * math.exp(-zeta * w * t) * math.cos(w * t))
    rig.write_command(20)
    settled = wait_until_settled(rig, window_s=1.0, timeout_s=60.0)
    t_quiet = math.log(amplitude / NOISE_V) / (zeta * w)  # 18.3 s: a fixed 2 s wait would read mid-swing
    assert t_quiet - 3.0 < settled.waited_s < t_quiet + 3.0
    np.testing.assert_allclose(settled.gauges_v[0], 0.1, atol=0.001)


def test_a_digit_that_never_settles_is_refused_naming_the_gauge():
    rig = SignalRig(lambda t, c: 0.01 * math.sin(2 * math.pi * 1.5 * t))
    rig.write_command(20)
    with pytest.raises(RigError, match=r"did not settle within 5 s at command 20 \(gauge 2: spread"):
        wait_until_settled(rig, timeout_s=5.0)


# -- the map's uncertainty ---------------------------------------------------------------------------------------
SENS = np.array([5.1e-3, 7.1e-3, 5.2e-3])  # V/deg, the twin's
OFFSET = np.array([-0.12, 0.6, 0.035])


def test_stated_uncertainty_covers_the_error_of_the_held_rotation():
    # reference rotations read with a protractor (sd 0.5 deg) and readings with 1 mV of noise: the error of the
    # rotation the map holds at 30 deg, over many seeded sweeps, has the standard deviation the map states
    angles = np.linspace(0, 40, 9)
    errors, stated = [], []
    for seed in range(150):
        rng = np.random.default_rng(seed)
        X = OFFSET + np.outer(angles, SENS) + 0.001 * rng.standard_normal((9, 3))
        y = angles + 0.5 * rng.standard_normal(9)
        est = RotationEstimator().fit(X, y, rotation_cov_deg2=0.25 * np.eye(9), gauges_sd_v=np.full((9, 3), 0.001))
        held = (30.0 - est.intercept_ - est.coef_ @ OFFSET) / (est.coef_ @ SENS)  # where the map reads 30 deg
        errors.append(held - 30.0)
        stated.append(est.uncertainty_deg(30.0))
    ratio = np.std(errors) / np.mean(stated)
    assert 0.8 < ratio < 1.25
    assert abs(np.mean(errors)) < 3 * np.std(errors) / math.sqrt(len(errors))  # unbiased


# -- deflections -> rotation ----------------------------------------------------------------------------------
def quad_deflection(shape, curvatures, s):
    """Sideways deflection at ``s`` by integrating sin(tangent angle) numerically: an independent oracle."""

    def angle(u):
        return sum(
            k * min(max(u - a, 0.0), b - a)
            for k, a, b in zip(curvatures, shape.flex_start_m, shape.flex_end_m, strict=True)
        )

    return quad(lambda u: math.sin(angle(u)), 0.0, s, points=[*shape.flex_start_m, *shape.flex_end_m], limit=200)[0]


def test_the_shape_model_matches_numerical_integration_at_large_rotation():
    shape = DigitShape.from_params()
    curvatures = [3.0, 4.0, 5.0]  # 1/m: 0.24 + 0.32 + 0.40 rad = 54 deg at the tip
    points = [0.03, 0.045, 0.09, 0.135, 0.2, 0.225, 0.27]
    ours = shape.deflection_m(curvatures, points)
    oracle = [quad_deflection(shape, curvatures, s) for s in points]
    np.testing.assert_allclose(ours, oracle, rtol=1e-9, atol=1e-12)
    assert math.degrees(shape.tip_rotation_rad(curvatures)) == pytest.approx(math.degrees(0.96))


@pytest.mark.parametrize("shares", [(0.36, 0.34, 0.30), (0.30, 0.37, 0.33), (0.40, 0.30, 0.30)])
def test_a_sweep_of_ruler_readings_gives_the_rotations_within_the_stated_uncertainty(shares):
    shape = DigitShape.from_params()
    true = np.linspace(0.0, 40.0, 17)
    points = [0.045, 0.135, 0.225, 0.27]
    Y = np.array(
        [
            [quad_deflection(shape, math.radians(t) * np.array(shares) / shape.flex_length_m, s) for s in points]
            for t in true
        ]
    )
    ruler = np.round(Y * 2000) / 2000  # read to 0.5 mm
    rotation, cov, rms, fitted = rotations_from_deflections(points, ruler)
    sd = np.sqrt(np.diag(cov))
    assert np.all(np.abs(rotation - true) < 3 * sd + 1e-9)
    assert sd[-1] < 0.3  # at 40 deg: 0.75 % (three gauges and the tip, 0.5 mm)
    np.testing.assert_allclose(fitted, shares, atol=0.03)
    assert rms < 0.5e-3 / math.sqrt(12) * 1.5  # residuals of the rounding's size: the model fits


def write(tmp_path, text, name="measured.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_table_3_6_layout_reads_and_states_its_larger_uncertainty_without_the_tip(tmp_path):
    # table 3.6 itself (commands 8-24, 45/135/225 mm to 0.5 mm): no tip reading, so the last section's share rests
    # on the stiffness prior and the rotation's uncertainty is degrees, not tenths
    rows = [(8, 0, 0, 0), (9, 0, 3.5, 5), (10, 0.5, 4, 6), (11, 0.5, 5, 10), (12, 0.5, 6, 14), (13, 0.5, 7, 15.5)]
    rows += [(14, 0.5, 8, 17.5), (15, 0.5, 8.5, 20), (16, 0.5, 9, 22.5), (17, 0.5, 10, 24.5), (18, 0.5, 10.5, 27.5)]
    rows += [(19, 0.5, 11, 29), (20, 0.5, 11.5, 32), (21, 0.5, 13, 36), (22, 1, 14.5, 39), (23, 1, 15.5, 42)]
    rows += [(24, 1, 16, 43.5)]
    text = "# thesis table 3.6\ncommand;deflection_mm_at_45mm;deflection_mm_at_135mm;deflection_mm_at_225mm\n"
    text += "".join(";".join(str(v) for v in row) + "\n" for row in rows)
    ref = read_reference(write(tmp_path, text))
    assert ref.kind == "deflections"
    assert ref.commands.tolist() == list(range(8, 25))
    assert ref.gauges_v is None
    sd = np.sqrt(np.diag(ref.rotation_cov_deg2))
    # y_SG3 = 43.5 mm at 225 mm: a uniform arc through it turns ~2 x 43.5 / 225 rad ~ 22 deg at 225 mm, more at the tip
    assert 20 < ref.rotation_deg[-1] < 35
    assert sd[-1] > 1.0


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("rotation_deg\n1\n", "line 1: no 'command' column"),
        ("command,rotation_deg,angle\n", "unknown column 'angle'"),
        ("command,rotation_deg,deflection_mm_at_45mm\n", "either a rotation_deg column or deflection_mm_at"),
        ("command,deflection_mm_at_300mm\n", r"column 'deflection_mm_at_300mm': the point must be inside \(0, 270\]"),
        ("command,rotation_deg\n8,0\n9,x\n", "line 3, column 'rotation_deg': expected a number, got 'x'"),
        ("command,rotation_deg\n8,0\n9,nan\n", "line 3, column 'rotation_deg': expected a number, got 'nan'"),
        ("command,rotation_deg\n8.5,0\n", r"line 2, column 'command': expected an integer command in 0..254"),
        ("command,rotation_deg\n8,0\n8,1\n", "line 3: command 8 already measured on line 2"),
        ("command,rotation_deg\n8,0\n9,1,2\n", "line 3: 3 cells for 2 columns"),
        ("command,deflection_mm_at_45mm\n8,50\n", "a point 45 mm along the digit cannot move 50 mm sideways"),
        ("command,rotation_deg\n8,0\n9,1\n10,2\n", "3 commands measured; the map needs at least 4"),
        ("command,rotation_deg\n8,1\n9,1\n10,1\n11,1\n", "the measured rotations do not vary"),
        ("command,rotation_deg,gauge1_v\n", "gauge columns must be all three"),
    ],
)
def test_bad_reference_files_name_file_line_and_column(tmp_path, text, match):
    path = write(tmp_path, text)
    with pytest.raises(DataFileError, match=match) as info:
        read_reference(path)
    assert str(path) in str(info.value)


def test_a_spreadsheet_export_with_a_byte_order_mark_reads_and_a_directory_is_named(tmp_path):
    # Excel's "CSV UTF-8": a byte-order mark, CRLF, ';' (a protractor read every 4 commands, 1 deg resolution)
    path = tmp_path / "protractor.csv"
    path.write_bytes(b"\xef\xbb\xbfcommand;rotation_deg\r\n8;0\r\n12;7\r\n16;14\r\n20;21\r\n")
    ref = read_reference(path)
    np.testing.assert_array_equal(ref.commands, [8, 12, 16, 20])
    np.testing.assert_allclose(ref.rotation_deg, [0, 7, 14, 21])
    (tmp_path / "dir.csv").mkdir()
    with pytest.raises(DataFileError, match=r"dir\.csv: a directory, not a file"):
        read_reference(tmp_path / "dir.csv")


def test_measured_gauges_in_the_file_fit_the_map_without_a_sweep(tmp_path):
    angles = np.array([0.0, 10, 20, 30, 40])
    X = OFFSET + np.outer(angles, SENS)
    text = "command,rotation_deg,gauge1_v,gauge2_v,gauge3_v\n" + "".join(
        f"{8 + 6 * i},{a},{g[0]},{g[1]},{g[2]}\n" for i, (a, g) in enumerate(zip(angles, X, strict=True))
    )
    ref = read_reference(write(tmp_path, text), resolution_deg=0.5)

    class NoSweep(SignalRig):
        def _send(self, command):
            raise AssertionError("no sweep was needed")

    est = calibrate_rotation(NoSweep(lambda t, c: 0.0), reference=ref)
    assert est.predict_one(OFFSET + 25 * SENS) == pytest.approx(25.0, abs=1e-9)
    assert est.deg_per_command_ == pytest.approx(10 / 6)
    # 0.5 deg resolution: sd 0.14 deg per reading, 5 readings: about 0.1 deg at the sweep's middle
    assert 0.03 < est.uncertainty_deg(20.0) < 0.2
    assert "measured on the rig" in est.source_


def test_a_map_saves_and_loads_with_its_provenance_and_refuses_to_clobber(tmp_path):
    rig = SignalRig(lambda t, c: (c - 8) * 0.01 * (1 - math.exp(-t / 0.05)))
    est = calibrate_rotation(rig, reference=lambda c: (c - 8) * 1.7, reference_sd_deg=0.2)
    path = save_rotation_map(est, tmp_path / "map.json")
    again = load_rotation_map(path)
    np.testing.assert_array_equal(again.coef_, est.coef_)
    assert again.uncertainty_deg(30.0) == pytest.approx(est.uncertainty_deg(30.0))
    assert again.commands_ == list(range(8, 33, 3))
    assert again.deg_per_command_ == pytest.approx(1.7)
    assert "operator" in again.source_
    assert str(path) in again.source_
    with pytest.raises(FileExistsError, match="pass --force"):
        save_rotation_map(est, path)
    data = json.loads(path.read_text())
    data["coef"] = [0, 0, 0]
    bad = write(tmp_path, json.dumps(data), "zero.json")
    with pytest.raises(DataFileError, match="read no rotation from the gauges"):
        load_rotation_map(bad)
    data["coef"], data["colour"] = [1, 1, 1], "red"
    with pytest.raises(DataFileError, match="unknown key 'colour'"):
        load_rotation_map(write(tmp_path, json.dumps(data), "extra.json"))
    legacy = write(
        tmp_path, json.dumps({"coef": [1, 2, 3], "intercept": 0.5, "gauge_v_per_deg": [0.1, 0.1, 0.1]}), "old.json"
    )
    assert load_rotation_map(legacy).predict_one(np.ones(3)) == pytest.approx(6.5)
    assert RigParams().actuator.equilibrium_command == 8  # the sweep above relaxed to it


def test_make_rotation_map_from_the_operator_or_a_file_and_a_replay_only_from_gauges_in_the_file(tmp_path):
    from flexdigit.errors import ParameterError
    from flexdigit.rig.rotation import make_rotation_map

    rig = SignalRig(lambda t, c: (c - 8) * 0.01 * (1 - math.exp(-t / 0.05)))
    est = make_rotation_map(rig, "operator", ask=lambda c: (c - 8) * 1.7, resolution_deg=1.0)
    assert est.deg_per_command_ == pytest.approx(1.7)
    assert "operator" in est.source_
    # a 1 deg protractor reads with a uniform error: sd 1/sqrt(12) = 0.29 deg (calibrate_rotation's default too)
    same = calibrate_rotation(
        SignalRig(lambda t, c: (c - 8) * 0.01 * (1 - math.exp(-t / 0.05))),
        reference=lambda c: (c - 8) * 1.7,
        reference_sd_deg=1.0 / math.sqrt(12),
    )
    assert est.uncertainty_deg(30.0) == pytest.approx(same.uncertainty_deg(30.0), rel=1e-9)
    with pytest.raises(ParameterError, match="replay cannot be swept"):
        make_rotation_map(rig, "operator", ask=lambda c: 0.0, replay=True)
    with pytest.raises(ParameterError, match="needs ask"):
        make_rotation_map(rig, "operator")
    angles = np.array([0.0, 10, 20, 30, 40])
    no_gauges = write(tmp_path, "command,rotation_deg\n" + "".join(f"{8 + 6 * i},{a}\n" for i, a in enumerate(angles)))
    with pytest.raises(ParameterError, match="gauge1_v"):
        make_rotation_map(rig, no_gauges, replay=True)
    X = OFFSET + np.outer(angles, SENS)
    text = "command,rotation_deg,gauge1_v,gauge2_v,gauge3_v\n" + "".join(
        f"{8 + 6 * i},{a},{g[0]},{g[1]},{g[2]}\n" for i, (a, g) in enumerate(zip(angles, X, strict=True))
    )
    mapped = make_rotation_map(rig, write(tmp_path, text, "gauges.csv"), replay=True)
    assert mapped.predict_one(OFFSET + 25 * SENS) == pytest.approx(25.0, abs=1e-9)

"""``flexdigit calibrate`` end to end on a perturbed twin's records (issue 11's figures), and its bad input.

Reference: the perturbed calibration the records were made with (flexdigit.calibrate.synthetic). Tolerances from
the issue: the perturbed parameters within 3 %, the damping within 5 %; the parameters left as they were must come
back too (the same tolerances), so a fit that trades one for another fails.
"""

import json
import re

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.twin.calibration import load_calibration, load_calibration_record, packaged_calibration

STIFFNESS_RTOL = 0.03  # issue 11: housing stiffness, channel gains
DAMPING_RTOL = 0.05  # issue 11: strip damping
#: the calibrated twin, running the same experiments again (other seeds), reproduces the records' figures:
#: wn to its noise (~0.1 %; the release tests integrate at 10 ms, within 0.03 % of the linear modes), zeta within
#: the scatter of a median over three gauges, the sweep lines within their readings' spread
REPRODUCE_WN_RTOL = 0.005
REPRODUCE_ZETA_RTOL = 0.05
REPRODUCE_SLOPE_RTOL = 0.02
REPRODUCE_OFFSET_V = 0.01


def _calibrate(rig, out, *extra):
    f = rig.files
    return main(
        [
            "calibrate",
            "--release-bare",
            str(f["bare"]),
            "--release-housed",
            str(f["housed"]),
            "--sweep",
            str(f["sweep"]),
            "--deflections",
            str(f["deflections"]),
            "--deflection-resolution-mm",
            "0.1",
            "--actuated-rest",
            str(f["actuated"]),
            "--out",
            str(out),
            "--json",
            *extra,
        ]
    )


@pytest.fixture(scope="module")
def calibrated(perturbed_rig, tmp_path_factory):
    out = tmp_path_factory.mktemp("calibrated") / "rig.toml"
    import contextlib
    import io

    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        code = _calibrate(perturbed_rig, out)
    assert code == 0
    return out, json.loads(buffer.getvalue())


@pytest.mark.slow
def test_calibrate_recovers_a_perturbed_twin(perturbed_rig, calibrated):
    out, report = calibrated
    truth, got = perturbed_rig.truth, load_calibration(out)
    np.testing.assert_allclose(got.housing_ei_n_m2, truth.housing_ei_n_m2, rtol=STIFFNESS_RTOL)  # +15 %
    np.testing.assert_allclose(got.strip_beta_s, truth.strip_beta_s, rtol=DAMPING_RTOL)  # x2
    np.testing.assert_allclose(got.channel_gain, truth.channel_gain, rtol=STIFFNESS_RTOL)  # +-10 %
    # and what was not perturbed stays where it was
    np.testing.assert_allclose(got.support_mass_kg, truth.support_mass_kg, rtol=STIFFNESS_RTOL)
    np.testing.assert_allclose(got.housing_beta_s, truth.housing_beta_s, rtol=DAMPING_RTOL)
    np.testing.assert_allclose(got.cable_stiffness_n_m, truth.cable_stiffness_n_m, rtol=DAMPING_RTOL)
    np.testing.assert_allclose(got.cable_friction_ratio, truth.cable_friction_ratio, rtol=0.1)  # 400 readings
    # the perturbation was real: the packaged calibration is outside those tolerances
    assert abs(packaged_calibration().housing_ei_n_m2[1] / truth.housing_ei_n_m2[1] - 1) > 0.1
    # the report: every target with its residual, what was fitted and what kept
    assert report["out"] == str(out)
    assert report["success"]
    assert {"housing_ei_n_m2", "strip_beta_s", "channel_gain", "cable_friction_ratio"} <= set(report["fitted"])
    assert "noise_white_v" in report["kept"]
    deflections = [r for r in report["residuals"] if r["target"].startswith("deflection")]
    assert len(deflections) == 3 * 8
    assert max(abs(r["residual"]) for r in deflections) <= 0.1  # within the camera's resolution
    _, fit = load_calibration_record(out)
    assert len(fit["residuals"]) == len(report["residuals"])
    assert fit["targets"]["deflection_resolution_mm"] == 0.1


@pytest.mark.slow
def test_the_calibrated_twin_reproduces_the_records(perturbed_rig, calibrated, tmp_path, capsys):
    out, report = calibrated
    capsys.readouterr()
    # the same experiments on the calibrated twin, other seeds, through the CLI a user would run
    for name, flags in (("bare", ["--no-housing", "--duration", "30"]), ("housed", ["--duration", "8"])):
        sim = tmp_path / f"{name}.csv"
        args = ["simulate", "release", *flags, "--rate", "500", "--seed", "21", "--calibration", str(out)]
        assert main([*args, "--out", str(sim), "--json"]) == 0
        again = json.loads(capsys.readouterr().out)["findings"]
        measured = report["release_tests"]["bare" if name == "bare" else "housing"]
        assert again["wn_rad_s"] == pytest.approx(measured["wn_rad_s"], rel=REPRODUCE_WN_RTOL), name
        assert again["zeta"] == pytest.approx(measured["zeta"], rel=REPRODUCE_ZETA_RTOL), name
    sweep = tmp_path / "sweep.csv"
    assert (
        main(
            ["simulate", "sweep", "--settle", "2.5", "--samples", "12", "--seed", "22"]
            + ["--calibration", str(out), "--out", str(sweep), "--json"]
        )
        == 0
    )
    again = json.loads(capsys.readouterr().out)["findings"]
    lines = {r["target"]: r["measured"] for r in report["residuals"]}
    for g in (1, 2, 3):
        slope = lines[f"sweep slope gauge {g} (as E 3.2{g - 1})"]
        offset = lines[f"sweep offset gauge {g} (as E 3.2{g - 1})"]
        assert again[f"gauge{g}"]["slope_v_per_command"] == pytest.approx(slope, rel=REPRODUCE_SLOPE_RTOL)
        assert again[f"gauge{g}"]["offset_v"] == pytest.approx(offset, abs=REPRODUCE_OFFSET_V)


def test_a_sweep_alone_fits_the_gains_and_keeps_the_mechanics(tmp_path, capsys):
    # a sweep the packaged twin's static model makes with known gains and offsets, written in millivolts,
    # ';'-separated with decimal commas: the gains come back exactly, the mechanics are not touched
    from flexdigit.calibrate.synthetic import write_csv
    from flexdigit.calibrate.targets import CalibrationTargets
    from flexdigit.calibrate.twin_fit import model_response
    from flexdigit.params import RigParams

    start = packaged_calibration()
    commands = np.arange(8, 44)
    unit_v = model_response(RigParams(), start, CalibrationTargets(sweep_commands=tuple(commands)))["sweep_unit_v"]
    gains, offsets = np.array([0.095, 0.11, 0.1]), np.array([-0.1, 0.4, 0.02])
    mv = (gains * unit_v + offsets) * 1e3
    rows = [[int(c), *row] for c, row in zip(commands, mv, strict=True)]
    sweep = write_csv(tmp_path / "sweep.csv", ["Command", "SG1_mV", "SG2_mV", "SG3_mV"], rows, ";", ",")
    out = tmp_path / "cal.toml"
    assert main(["calibrate", "--sweep", str(sweep), "--decimal", ",", "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    got = load_calibration(out)
    # through the sweep's straight lines (E 3.20-3.22): the model's volts bend a little over 8..43 (1e-5)
    np.testing.assert_allclose(got.channel_gain, gains, rtol=1e-4)
    np.testing.assert_allclose(got.channel_offset_v, offsets, atol=1e-4)
    assert got.replace(channel_gain=start.channel_gain, channel_offset_v=start.channel_offset_v) == start
    assert report["fitted"] == ["channel_gain", "channel_offset_v"]
    assert "support_mass_kg" in report["kept"]


def _lines(capsys):
    return capsys.readouterr().err.strip().splitlines()


@pytest.mark.parametrize(
    ("files", "flags", "message"),
    [
        ({}, [], "nothing to calibrate"),
        (
            {"sweep.csv": "command,gauge1_v,gauge2_v\n8,0.1,0.2\n9,0.1,0.2\n"},
            ["--sweep"],
            "no gauge-voltage column for gauge 3",
        ),
        (
            {"sweep.csv": "command,gauge1_v,gauge2_v,gauge3_v\n8,0.1,0.2,0.3\n9,0.1,abc,0.3\n"},
            ["--sweep"],
            r"sweep\.csv: line 3, column 'gauge2_v': 'abc' is not a number",
        ),
        (
            {"sweep.csv": "command,gauge1_v,gauge2_v,gauge3_v\n8,0.1,0.2,0.3\n300,0.1,0.2,0.3\n"},
            ["--sweep"],
            r"sweep\.csv: line 3, column 'command': 300 is not a servo command",
        ),
        (
            {"sweep.csv": "command,gauge1_v,gauge2_v,gauge3_v\n8,0.1,0.2,0.3\n9,0.1,nan,0.3\n"},
            ["--sweep"],
            r"line 3, column 'gauge2_v': 'nan' is not a number",
        ),
        (
            {"defl.csv": "command,y1_mm,y2_mm,y3_mm\n8,0,0,0\n8,1,2,3\n"},
            ["--deflections"],
            r"defl\.csv: command 8 appears twice",
        ),
        (
            {"rest.csv": "time,gauge1_v,gauge2_v,gauge3_v\n" + "".join(f"{i},0,0,0\n" for i in range(20))},
            ["--rest"],
            r"rest\.csv: column 'time' has no time unit",
        ),
        (
            {"act.csv": "command,gauge1_v,gauge2_v,gauge3_v\n20,0,0,0\n20,0,0,0\n30,0,0,0\n"},
            ["--actuated-rest"],
            r"act\.csv: an actuated-rest record holds one command",
        ),
        ({"bare.csv": "time_s,pot_v\n0,1\n0.1,2\n"}, ["--release-bare"], r"bare\.csv: no gauge channel"),
    ],
)
def test_bad_records_give_one_line_errors(tmp_path, capsys, files, flags, message):
    args = ["calibrate", "--out", str(tmp_path / "cal.toml")]
    for (name, text), flag in zip(files.items(), flags, strict=True):
        (tmp_path / name).write_text(text)
        args += [flag, str(tmp_path / name)]
    assert main(args) == 2
    lines = _lines(capsys)
    assert len(lines) == 1
    assert lines[0].startswith("flexdigit calibrate: error: ")
    assert re.search(message, lines[0]), lines[0]
    assert not (tmp_path / "cal.toml").exists()


def test_an_existing_output_is_refused_before_any_fit_and_thesis_excludes_records(tmp_path, capsys):
    out = tmp_path / "cal.toml"
    out.write_text("keep me")
    sweep = tmp_path / "sweep.csv"
    sweep.write_text("command,gauge1_v,gauge2_v,gauge3_v\n8,0.1,0.2,0.3\n9,0.11,0.21,0.31\n")
    assert main(["calibrate", "--sweep", str(sweep), "--out", str(out)]) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert out.read_text() == "keep me"
    assert main(["calibrate", "--thesis", "--sweep", str(sweep), "--out", str(tmp_path / "x.toml")]) == 2
    assert "--thesis fits the thesis's figures: give it alone" in capsys.readouterr().err
    assert main(["calibrate", "--sweep", str(sweep), "--out", str(out), "--deflection-resolution-mm", "0"]) == 2
    assert "'--deflection-resolution-mm' parameter of flexdigit calibrate must be" in capsys.readouterr().err


def test_calibrate_thesis_writes_the_packaged_mechanics_and_fits_the_friction_to_the_score(
    tmp_path, capsys, monkeypatch
):
    # the tactile score replaced by a closed form with a known root (corr2 = 1 - 2 ratio: 0.8998 at 0.0501), so
    # the command's path is checked in seconds; the real score's root is tests/calibrate/test_default.py's
    def score(calibration, *, params=None):
        return 1.0 - 2.0 * calibration.cable_friction_ratio

    monkeypatch.setattr("flexdigit.calibrate.twin_fit.actuated_corr2_score", score)  # where calibrate looks it up
    out = tmp_path / "thesis.toml"
    assert main(["calibrate", "--thesis", "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    got, fit = load_calibration_record(out)
    assert got.cable_friction_ratio == pytest.approx((1 - 0.8998) / 2, abs=1e-4)
    default = packaged_calibration()
    np.testing.assert_allclose(got.housing_ei_n_m2, default.housing_ei_n_m2, rtol=1e-5)
    np.testing.assert_allclose(got.channel_gain, default.channel_gain, rtol=1e-5)
    assert report["residuals"][-1]["target"] == "actuated test corr2 (7.5)"
    assert fit["source"].startswith("calibrate(CalibrationTargets.from_thesis()")


@pytest.mark.slow
def test_records_the_twin_cannot_reproduce_together_are_refused_unless_allowed(tmp_path, capsys):
    # a deflection table of the packaged twin at 0.1 mm, then the same with gauge 3 read in the wrong unit (x10,
    # cm taken for mm): the first calibrates cleanly, the second is refused naming the target it misses most
    from flexdigit.calibrate.synthetic import write_csv
    from flexdigit.params import RigParams
    from flexdigit.twin.twin import Twin

    params = RigParams()
    rows = []
    for command in range(8, 44, 5):
        y = Twin(params, packaged_calibration(), command=command).deflection_m(params.geometry.gauge_positions_m)
        rows.append([command, *np.round(y * 1e4) / 10])
    good = write_csv(tmp_path / "good.csv", ["command", "y1_mm", "y2_mm", "y3_mm"], rows)
    slip = write_csv(tmp_path / "slip.csv", ["command", "y1_mm", "y2_mm", "y3_mm"], [r[:3] + [10 * r[3]] for r in rows])
    common = ["--deflection-resolution-mm", "0.1", "--json"]
    assert main(["calibrate", "--deflections", str(good), "--out", str(tmp_path / "good.toml"), *common]) == 0
    assert json.loads(capsys.readouterr().out)["worst"]["times_scale"] < 1.0
    out = tmp_path / "slip.toml"
    assert main(["calibrate", "--deflections", str(slip), "--out", str(out), *common]) == 2
    err = capsys.readouterr().err
    assert re.search(r"misses deflection gauge \d @ \d+ \(as table 3\.6\) by .* cannot reproduce these records", err)
    assert "--allow-poor-fit" in err
    assert not out.exists()
    assert main(["calibrate", "--deflections", str(slip), "--out", str(out), "--allow-poor-fit", *common]) == 0
    assert json.loads(capsys.readouterr().out)["worst"]["times_scale"] > 3.0
    assert out.exists()

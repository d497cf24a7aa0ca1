"""``flexdigit identify``: results on a recording, one-line errors on bad ones (exit 2)."""

import json

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.identify.fit import second_order_response


def _record(path, kind, *, zeta, wn, noise=0.01, seed=0):
    t = np.arange(0, 6 if kind == "release" else 2, 0.002)
    if kind == "release":
        y = second_order_response(t, "release", wn, zeta, 0.1, 1.0, 0.3)
        cols, header = [t, y], "time_s,sg1_v"
    else:
        y = second_order_response(t, "step", wn, zeta, 0.4669, 51 * 0.0079, 0.2)
        cols, header = [t, y, np.where(t >= 0.2, 59.0, 8.0)], "time_s,pot_v,command"
    cols[1] = cols[1] + np.random.default_rng(seed).normal(0, noise, t.size)
    np.savetxt(path, np.column_stack(cols), delimiter=",", header=header, comments="", fmt="%.9g")
    return path


def test_identify_step_json_gives_model_and_gain_per_command(tmp_path, capsys):
    p = _record(tmp_path / "step.csv", "step", zeta=0.5629, wn=20.53, noise=0.004)
    assert main(["identify", "step", str(p), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["wn_rad_s"] == pytest.approx(20.53, rel=0.02)
    assert out["zeta"] == pytest.approx(0.5629, rel=0.02)
    assert out["gain"] == pytest.approx(0.0079, rel=0.02)  # V per command: the 51-command step of 3.2.4
    assert out["t0_s"] == pytest.approx(0.2, abs=1e-3)  # fitted; the command column says 0.199..0.2
    lo, hi = out["confidence_intervals"]["wn_rad_s"]
    assert lo < out["wn_rad_s"] < hi


def test_identify_release_thesis_method_text(tmp_path, capsys):
    p = _record(tmp_path / "rel.csv", "release", zeta=0.068, wn=13.1)
    assert main(["identify", "release", str(p), "--method", "thesis", "--channel", "sg1"]) == 0
    text = capsys.readouterr().out
    assert "method thesis" in text
    assert "wn = 4/(zeta Ts)" in text
    assert "corr2" in text


def test_no_undershoot_in_release_is_a_one_line_error(tmp_path, capsys):
    p = _record(tmp_path / "over.csv", "release", zeta=1.5, wn=13.1)
    assert main(["identify", "release", str(p), "--method", "thesis"]) == 2
    err = capsys.readouterr().err
    assert "over.csv:sg1: no undershoot in this release test" in err
    assert "Traceback" not in err


def test_missing_channel_is_a_one_line_error(tmp_path, capsys):
    p = _record(tmp_path / "rel.csv", "release", zeta=0.068, wn=13.1)
    assert main(["identify", "release", str(p), "--channel", "sg9"]) == 2
    assert "rel.csv: no column 'sg9' (columns: time_s, sg1_v)" in capsys.readouterr().err


def _exponential_decay(path, channel="sg1_v"):
    """A clean overdamped release: held at 1.1 V, then 0.1 + exp(-(t - 0.3)/0.2) V, never below its final value."""
    t = np.arange(0, 6, 0.002)
    y = 0.1 + np.where(t < 0.3, 1.0, np.exp(-(t - 0.3) / 0.2))
    np.savetxt(path, np.column_stack([t, y]), delimiter=",", header=f"time_s,{channel}", comments="", fmt="%.9g")
    return path


@pytest.mark.parametrize("extra", [[], ["--method", "lsq"], ["--method", "arx"], ["--method", "thesis"]])
def test_release_without_undershoot_is_refused_by_every_method(tmp_path, capsys, extra):
    # issue 4: "no overshoot in a release test" is a bad file; the default (lsq) used to fit it (zeta ~ 1.8..5)
    p = _exponential_decay(tmp_path / "decay.csv")
    assert main(["identify", "release", str(p), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "Traceback" not in err
    assert "decay.csv:sg1: no undershoot in this release test" in err
    assert "expected an oscillating decay" in err
    assert "--allow-overdamped" in err


def test_overdamped_release_default_method_refused_also_with_noise(tmp_path, capsys):
    p = _record(tmp_path / "over.csv", "release", zeta=1.5, wn=13.1)  # 1 % noise
    assert main(["identify", "release", str(p)]) == 2
    assert "over.csv:sg1: no undershoot in this release test" in capsys.readouterr().err


def test_allow_overdamped_opts_in_to_the_fit(tmp_path, capsys):
    p = _record(tmp_path / "over.csv", "release", zeta=1.5, wn=13.1, noise=0.002)
    assert main(["identify", "release", str(p), "--allow-overdamped", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["zeta"] == pytest.approx(1.5, rel=0.05)
    assert out["wn_rad_s"] == pytest.approx(13.1, rel=0.05)
    assert "features" not in out  # no %OS to report
    # the thesis method cannot use it even when allowed
    assert main(["identify", "release", str(p), "--allow-overdamped", "--method", "thesis"]) == 2
    assert "the thesis method needs one" in capsys.readouterr().err


def test_oscillating_release_with_the_default_method(tmp_path, capsys):
    # the default method on the digit of 3.1.2 (13.1 rad/s, 0.068), 1 % noise: within 2 %
    p = _record(tmp_path / "rel.csv", "release", zeta=0.068, wn=13.1)
    assert main(["identify", "release", str(p), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "lsq"
    assert out["wn_rad_s"] == pytest.approx(13.1, rel=0.02)
    assert out["zeta"] == pytest.approx(0.068, rel=0.02)


@pytest.mark.parametrize(("column", "asked"), [("gauge1_v", "sg1"), ("gauge1_v", "sg1_v"), ("sg1_v", "gauge1")])
def test_gauge_channels_answer_to_sg_and_gauge(tmp_path, capsys, column, asked):
    # the guide's --channel sg1 on a twin-style file (gauge1_v), and the other way round (--force: a first-order
    # decay gives no second-order wn and zeta to stand behind, and this test is about the channel)
    p = _exponential_decay(tmp_path / "decay.csv", channel=column)
    assert main(["identify", "release", str(p), "--channel", asked, "--allow-overdamped", "--force", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["channel"] == column[:-2]


def test_gauge_alias_that_is_ambiguous_names_the_columns(tmp_path, capsys):
    t = np.arange(0, 1, 0.01)
    p = tmp_path / "two.csv"
    np.savetxt(p, np.column_stack([t, t, t]), delimiter=",", header="time_s,gauge1_v,gauge1_mm", comments="")
    assert main(["identify", "release", str(p), "--channel", "sg1"]) == 2
    assert "channel 'sg1' is ambiguous: it could be any of gauge1_v, gauge1_mm" in capsys.readouterr().err


# --- issue 16: every option is checked, 0 is a value, contradictions are refused --------------------------------
@pytest.mark.parametrize(
    ("extra", "expected"),
    [
        (["--input-step", "inf"], "The '--input-step' parameter of flexdigit identify must be a finite real number"),
        (["--input-step", "nan"], "The '--input-step' parameter of flexdigit identify must be a finite real number"),
        (["--input-step", "0"], "The 'input_step' parameter of identify must not be 0"),
        (["--t0", "-5"], "The 't0_s' parameter of identify (--t0) must be inside the record, 0 .. 1.998 s. Got -5"),
        (["--t0", "2.5"], "must be inside the record, 0 .. 1.998 s. Got 2.5 instead."),
        (["--t0", "nan"], "The '--t0' parameter of flexdigit identify must be a finite real number"),
    ],
)
def test_bad_options_are_one_line_errors(tmp_path, capsys, extra, expected):
    # identify step f.csv --input-step inf was an IndexError; --t0 -5 was accepted
    p = _record(tmp_path / "step.csv", "step", zeta=0.5629, wn=20.53, noise=0.004)
    p.write_text("\n".join(line.rsplit(",", 1)[0] for line in p.read_text().splitlines()) + "\n")  # no command
    assert main(["identify", "step", str(p), *extra]) == 2
    err = capsys.readouterr().err
    assert expected in err
    assert err.count("\n") == 1
    assert "Traceback" not in err


def test_input_step_contradicting_the_command_column_is_refused(tmp_path, capsys):
    p = _record(tmp_path / "step.csv", "step", zeta=0.5629, wn=20.53, noise=0.004)  # command 8 -> 59
    assert main(["identify", "step", str(p), "--input-step", "40"]) == 2
    assert "(40) contradicts the 'command' column" in capsys.readouterr().err
    assert main(["identify", "step", str(p), "--input-step", "51", "--json"]) == 0  # agreeing is fine
    assert json.loads(capsys.readouterr().out)["gain"] == pytest.approx(0.0079, rel=0.02)


def test_time_unit_contradicting_the_column_name_is_refused(tmp_path, capsys):
    # --time-unit ms silently overrode a column named time_s (every time 1000 x too short)
    p = _record(tmp_path / "step.csv", "step", zeta=0.5629, wn=20.53, noise=0.004)
    assert main(["identify", "step", str(p), "--time-unit", "ms"]) == 2
    err = capsys.readouterr().err
    assert "column 'time_s' says its time is in s but --time-unit ms was given" in err
    assert main(["identify", "step", str(p), "--time-unit", "s"]) == 0  # the same unit is no contradiction


def test_t0_zero_is_a_value_not_absent(tmp_path, capsys):
    # a step at the very first sample: --t0 0 is taken as given (0 is a value), not as "find it"
    t = np.arange(0, 2, 0.002)
    y = second_order_response(t, "step", 20.53, 0.5629, 0.4669, 0.4, 0.0)
    y = y + np.random.default_rng(2).normal(0, 0.004, t.size)
    p = tmp_path / "s.csv"
    np.savetxt(p, np.column_stack([t, y]), delimiter=",", header="time_s,pot_v", comments="", fmt="%.9g")
    assert main(["identify", "step", str(p), "--t0", "0", "--delay", "no", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["instant"]["found_from"] == "given"
    assert out["t0_s"] == 0.0
    assert out["wn_rad_s"] == pytest.approx(20.53, rel=0.01)
    assert out["zeta"] == pytest.approx(0.5629, rel=0.02)


def test_text_output_reports_the_instant_and_the_quality(tmp_path, capsys):
    p = _record(tmp_path / "step.csv", "step", zeta=0.5629, wn=20.53, noise=0.004)
    assert main(["identify", "step", str(p)]) == 0
    out = capsys.readouterr().out
    assert "step at t = 0.2" in out
    assert "from the 'command' column" in out
    assert "step up" in out
    assert "quality:" in out
    assert "Ljung-Box" in out
    assert "record: noise" in out


def test_simulate_release_from_no_deflection_is_refused(tmp_path, capsys):
    # issue 16: simulate release --deflection-mm 0 printed a wn fitted to noise
    code = main(["simulate", "release", "--deflection-mm", "0", "--out", str(tmp_path / "r.parquet")])
    assert code == 2
    err = capsys.readouterr().err
    assert "'--deflection-mm' parameter of flexdigit simulate release must not be 0" in err
    assert not (tmp_path / "r.parquet").exists()

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
    assert "method thesis" in text and "wn = 4/(zeta Ts)" in text and "corr2" in text


def test_no_undershoot_in_release_is_a_one_line_error(tmp_path, capsys):
    p = _record(tmp_path / "over.csv", "release", zeta=1.5, wn=13.1)
    assert main(["identify", "release", str(p), "--method", "thesis"]) == 2
    err = capsys.readouterr().err
    assert "over.csv:sg1: no undershoot in this release test" in err and "Traceback" not in err


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
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "decay.csv:sg1: no undershoot in this release test" in err
    assert "expected an oscillating decay" in err and "--allow-overdamped" in err


def test_overdamped_release_default_method_refused_also_with_noise(tmp_path, capsys):
    p = _record(tmp_path / "over.csv", "release", zeta=1.5, wn=13.1)  # 1 % noise
    assert main(["identify", "release", str(p)]) == 2
    assert "over.csv:sg1: no undershoot in this release test" in capsys.readouterr().err


def test_allow_overdamped_opts_in_to_the_fit(tmp_path, capsys):
    p = _record(tmp_path / "over.csv", "release", zeta=1.5, wn=13.1, noise=0.002)
    assert main(["identify", "release", str(p), "--allow-overdamped", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["zeta"] == pytest.approx(1.5, rel=0.05) and out["wn_rad_s"] == pytest.approx(13.1, rel=0.05)
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
    assert out["wn_rad_s"] == pytest.approx(13.1, rel=0.02) and out["zeta"] == pytest.approx(0.068, rel=0.02)


@pytest.mark.parametrize(("column", "asked"), [("gauge1_v", "sg1"), ("gauge1_v", "sg1_v"), ("sg1_v", "gauge1")])
def test_gauge_channels_answer_to_sg_and_gauge(tmp_path, capsys, column, asked):
    # the README's --channel sg1 on a twin-style file (gauge1_v), and the other way round
    p = _exponential_decay(tmp_path / "decay.csv", channel=column)
    assert main(["identify", "release", str(p), "--channel", asked, "--allow-overdamped", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["channel"] == column[:-2]


def test_gauge_alias_that_is_ambiguous_names_the_columns(tmp_path, capsys):
    t = np.arange(0, 1, 0.01)
    p = tmp_path / "two.csv"
    np.savetxt(p, np.column_stack([t, t, t]), delimiter=",", header="time_s,gauge1_v,gauge1_mm", comments="")
    assert main(["identify", "release", str(p), "--channel", "sg1"]) == 2
    assert "channel 'sg1' is ambiguous: it could be any of gauge1_v, gauge1_mm" in capsys.readouterr().err

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

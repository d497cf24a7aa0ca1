"""Logs, recordings and replays of a digit with other than three gauges (issue 24): what the loop and the
collector record carries one voltage per gauge of the digit, and reads back, and replays, as it was taken."""

from __future__ import annotations

import json

import numpy as np

from digits import write_digit
from flexdigit.cli import main
from flexdigit.params import load_params
from flexdigit.rig.base import open_rig
from flexdigit.rig.recording import read_recording_columns
from flexdigit.rig.sample_log import read_log_columns
from flexdigit.tactile.dataset import load_dataset


def _protocol(path, digit_length_m: float) -> None:
    path.write_text(
        'name = "tiny"\nloads_g = [10.0]\n'
        f"positions_from_tip_cm = [0.0, {round(40 * digit_length_m, 1)}]\n"
        "repetitions = 3\nno_load_repetitions = 2\nsettle_s = 0.5\n"
    )


def test_collect_records_and_replays_the_digits_gauges(tmp_path, capsys):
    """``collect --record`` on the 8-gauge digit: the MCAP's samples have 8 voltages, the dataset's readings, and a
    replay of it reads them back."""
    digit = write_digit("five-sections-eight-gauges", tmp_path)
    params = load_params(digit)
    protocol, data, record = tmp_path / "p.toml", tmp_path / "d.parquet", tmp_path / "r.mcap"
    _protocol(protocol, params.geometry.digit_length_m)
    argv = ["collect", str(protocol), "--params", str(digit), "--out", str(data), "--record", str(record)]
    assert main([*argv, "--no-progress"]) == 0
    capsys.readouterr()
    _, columns, _ = read_recording_columns(record)
    dataset = load_dataset(data)
    # every reading is kept: the recording holds the dataset's readings and those read while waiting for the
    # digit to be steady (a protocol TOML's default), in order
    recorded = columns["gauges_v"]
    assert recorded.shape[1] == 8
    assert len(recorded) >= len(dataset)
    match = [np.flatnonzero(np.all(np.abs(recorded - row) <= 1e-12, axis=1)) for row in dataset.gauges_v]
    assert all(m.size for m in match)
    assert np.all(np.diff([m[0] for m in match]) > 0)
    with open_rig(f"replay://{record}", params) as rig:
        assert rig.read().gauges_v.shape == (8,)


def test_the_loop_log_holds_the_digits_gauges(tmp_path, capsys):
    """``palpate --log`` on the one-gauge digit writes a loop log of one voltage a sample, read back as one column."""
    digit = write_digit("one-section", tmp_path)
    tissue, sweep, log = tmp_path / "t.toml", tmp_path / "s.toml", tmp_path / "loop.jsonl"
    tissue.write_text('[tissue]\nside = "cable"\nstart_mm = 88\nend_mm = 240\ngap_mm = 16\nmodulus_n_m2 = 1000.0\n')
    sweep.write_text("[sweep]\ncommands = [8, 16, 20, 24, 28]\nsettle_s = 2.0\nreadings = 10\ntare_command = 8\n")
    argv = ["palpate", "--params", str(digit), "--tissue", str(tissue), "--protocol", str(sweep), "--log", str(log)]
    assert main([*argv, "--backend", "sim?orientation=hanging", "--json"]) == 0
    json.loads(capsys.readouterr().out)
    _, columns, _ = read_log_columns(log)
    assert columns["gauges_v"].shape[1] == 1
    assert np.all(np.isfinite(columns["gauges_v"]))

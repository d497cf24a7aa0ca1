"""Every test digit through the tactile data path from the command line (issue 24): ``params`` -> ``collect`` ->
``train`` -> ``predict`` -> ``shape`` -> ``palpate``, each with ``--params FILE`` and exit 0, the dataset and the
network with one gauge column / input per gauge of the digit; and the trained network within 1.3x of the
localisation Bayes limit on its own test readings.

The Bayes limit (:func:`flexdigit.tactile.localisation.position_bayes_rmse_m`, the thesis rig's
``tactile.bounds.protocol_limits`` of chapter 6's report entries) is the RMS position error of the best estimator
that knows the protocol's positions and their frequencies, on readings drawn from the twin's static gauges and its
white noise and ADC quantisation. The protocol probes 19 positions from the tip with one 10 g load, spaced half the
digit's Cramer-Rao bound there (0.5 to 4 mm): closer together than the gauges resolve, so the limit is the gauges'
resolution and a network's continuous regression can approach it (well-separated positions would put the limit
near zero, where a regression that cannot snap to them has no chance and no ratio means anything).

Tolerances:
- ``BAYES_RATIO_MAX = 1.3``: the issue's. ``BAYES_RATIO_MIN = 0.6``: the limit is a floor on the readings' white
  noise; a setting's offset (the drift, a tare's error), shared by its training and test readings, is something a
  network trained on the same run can use, and a test set of ~130 readings scores an RMSE to ~6 %; below 0.6 the
  limit would be wrong. The protocol (a TOML) reads steady and tares before each position, ``train`` keeping the
  raw or tared readings by validation (docs/digits.md "Tactile data of your digit").
- ``MODULUS_SIGMAS = 3``: palpation's modulus within three of its own standard deviations of the tissue's true
  1000 N/m^2 (the thesis rig's is 997 +- 17; the drawn 2-gauge 0.43 m digit's 1418 +- 237, its chi^2/dof 5),
  and ``MODULUS_SD_MAX = 0.5``: that standard deviation under half the modulus (the estimate says something).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from digits import DIGITS, random_digit, write_digit
from flexdigit.cli import main
from flexdigit.params import load_params
from flexdigit.tactile.dataset import load_dataset

BAYES_RATIO_MAX = 1.3
BAYES_RATIO_MIN = 0.6
MODULUS_SIGMAS = 3.0
MODULUS_SD_MAX = 0.5
#: Seeds of the drawn digits (tests/digits.py::random_digit): 3 is 5 sections, 5 half-bridge gauges, 0.17 m, an
#: antagonistic pair, geared 3.86:1; 5 is 7 sections, 8 quarter-bridge gauges, 0.42 m, a pair; 6 is 5 sections,
#: 2 gauges, 0.43 m, geared 3.97:1. Seeds 1 (5 full-bridge gauges on 0.18 m) and 8 (one 0.39 m section) are left out:
#: the twin's 3 cells per section put a gauge's curvature 10-30 % off there (22 mV on seed 1's gauge 2; 10 cells:
#: 0.01 mV), and the shape estimate rightly finds the twin's readings inconsistent (chi^2 91 and 103).
RANDOM_SEEDS = (3, 5, 6)

CASES = [pytest.param(name, id=name) for name in DIGITS] + [
    pytest.param(f"random-{seed}", id=f"random-{seed}") for seed in RANDOM_SEEDS
]


def _digit_file(case: str, directory):
    if case.startswith("random-"):
        import tomli_w

        path = directory / f"{case}.toml"
        path.write_text(tomli_w.dumps(random_digit(int(case.split("-")[1]))))
        return path
    return write_digit(case, directory)


def _position_step_m(params) -> float:
    """Half the digit's Cramer-Rao bound of a known 10 g load's position over its outer 72 mm (the median of three
    points), 0.5 to 4 mm: positions closer than the gauges resolve, so that the Bayes limit is not the near-zero of
    well-separated positions a continuous regression cannot snap to."""
    from flexdigit.tactile.bounds import cramer_rao
    from flexdigit.tactile.localisation import readings_gauge_model
    from flexdigit.tactile.protocols import RELAXED
    from flexdigit.twin.digit_calibration import twin_calibration

    length = params.geometry.digit_length_m
    model = readings_gauge_model(params, twin_calibration(params))
    bound = cramer_rao(model, [length, length - 0.036, length - 0.072], 0.010, RELAXED).crlb_known_mass_m
    return float(np.clip(round(0.5 * np.median(bound), 4), 0.0005, 0.004))


def _protocol(path, step_m: float = 0.004) -> None:
    tips_cm = [round(100 * step_m * k, 2) for k in range(19)]  # 19 positions from the tip, step_m apart
    path.write_text(
        'name = "digit-outer"\nloads_g = [10.0]\n'
        f"positions_from_tip_cm = {tips_cm}\nrepetitions = 40\nno_load_repetitions = 10\nsettle_s = 10.0\n"
    )


def _palpation_files(directory, params):
    """A tissue beside the outer 45 % of the digit, 0.1 L from it, and a sweep whose commands turn the pulley from the
    digit's straight command as the thesis's 8..30 do (times the gear ratio; a pair's straight command is mid-range),
    each plateau held 20 s per metre of digit (5.4 s on the thesis rig, whose housed digit rings ~3 s; a 0.5 m digit
    rings longer)."""
    length_m, gear = params.geometry.digit_length_m, params.actuator.gear_ratio
    straight = params.actuator.equilibrium_command
    tissue = directory / "tissue.toml"
    tissue.write_text(
        f'[tissue]\nname = "digit-block"\nside = "cable"\nstart_mm = {550 * length_m:.1f}\n'
        f"end_mm = {1000 * length_m + 80:.1f}\ngap_mm = {100 * length_m:.1f}\nmodulus_n_m2 = 1000.0\n"
    )
    top = min(254, int(round(straight + 22 * gear)))
    step = max(1, int(round(2 * gear)))
    sweep = directory / "sweep.toml"
    sweep.write_text(
        f"[sweep]\ncommands = {{ from = {straight}, to = {top}, step = {step} }}\nsettle_s = {20 * length_m:.2f}\n"
        f'readings = 20\ntare_command = {straight}\nmodel = "linear"\n'
    )
    return tissue, sweep


def _json(argv, capsys) -> dict:
    code = main([*argv, "--json"])
    out = capsys.readouterr().out
    assert code == 0, out
    return json.loads(out)


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_digit_through_the_data_path(case, tmp_path, capsys):
    digit = _digit_file(case, tmp_path)
    params = load_params(digit)
    gauges = len(params.geometry.gauge_positions_m)
    columns = [f"gauge{k}_v" for k in range(1, gauges + 1)]
    assert main(["params", str(digit)]) == 0
    capsys.readouterr()

    protocol, data = tmp_path / "protocol.toml", tmp_path / "digit.parquet"
    _protocol(protocol, _position_step_m(params))
    _json(["collect", str(protocol), "--params", str(digit), "--out", str(data), "--no-progress"], capsys)
    dataset = load_dataset(data)
    assert dataset.gauge_columns == tuple(columns)

    model = tmp_path / "digit.model.json"
    train = ["train", str(data), "--hidden", "10", "--tol", "1e-7", "--model", str(model)]
    scores = _json([*train, "--bayes-limit", "--params", str(digit)], capsys)
    assert BAYES_RATIO_MIN < scores["rmse_over_bayes_limit"] < BAYES_RATIO_MAX, scores
    assert json.loads(model.read_text())["inputs"] == columns

    predicted = _json(["predict", str(model), str(data)], capsys)
    assert predicted["scores"]["corr2"] > 0.5

    # one reading of the load at the tip (an average of the 40 would be held to 0.3 mV, below the run's drift)
    tip = np.flatnonzero((dataset["position_index"] == 1) & (dataset["load_kg"] > 0))[-1]
    volts = ",".join(f"{v:.6f}" for v in dataset.gauges_v[tip])
    shape = ["shape", "--params", str(digit), f"--gauges-v={volts}", "--orientation", "horizontal", "--no-cable"]
    assert _json(shape, capsys)["contact"]

    tissue, sweep = _palpation_files(tmp_path, params)
    palpate = ["palpate", "--params", str(digit), "--tissue", str(tissue), "--protocol", str(sweep)]
    result = _json([*palpate, "--backend", "sim?orientation=hanging"], capsys)["result"]
    assert result["modulus_sd_n_m2"] < MODULUS_SD_MAX * 1000.0
    assert abs(result["modulus_n_m2"] - 1000.0) < MODULUS_SIGMAS * result["modulus_sd_n_m2"]


def test_a_rig_reading_other_gauges_than_the_digit_is_refused(tmp_path, capsys):
    """The thesis's three-gauge twin collecting for a two-gauge digit's description: one line naming the count."""
    digit = write_digit("short", tmp_path)
    protocol = tmp_path / "protocol.toml"
    _protocol(protocol)
    from flexdigit.errors import RigError
    from flexdigit.params import RigParams
    from flexdigit.rig.base import open_rig
    from flexdigit.tactile.protocols import load_protocol
    from flexdigit.tactile.runner import collect

    with open_rig("sim", RigParams(), seed=0) as rig, pytest.raises(RigError, match="expected 2 finite"):
        collect(load_protocol(protocol), rig, tmp_path / "x.parquet", params=load_params(digit), settle_s=0.0)
    assert not (tmp_path / "x.parquet").exists()


@pytest.mark.parametrize("count", [1, 5, 8])
def test_a_dataset_keeps_its_gauge_columns_through_parquet_and_csv(count, tmp_path):
    from flexdigit.tactile.dataset import Dataset, dataset_columns, make_meta, save_dataset
    from flexdigit.tactile.protocols import Protocol

    protocol = Protocol("p", loads_kg=(0.01,), positions_from_tip_m=(0.0,), repetitions=2, no_load_repetitions=1)
    plan = protocol.plan(0.27)
    rng = np.random.default_rng(count)
    cols = {name: np.zeros(3, dtype=dtype) for name, dtype in dataset_columns(count).items()}
    cols.update({k: v for k, v in plan.items() if k in cols})
    for k in range(1, count + 1):
        cols[f"gauge{k}_v"] = rng.uniform(-1, 1, 3)
    meta = make_meta(protocol, {"url": "sim"}, 0.27, (-5.0, 5.0), count)
    dataset = Dataset(cols, meta)
    for suffix in ("parquet", "csv"):
        back = load_dataset(save_dataset(dataset, tmp_path / f"d.{suffix}"))
        assert back.gauge_count == count
        np.testing.assert_array_equal(back.gauges_v, dataset.gauges_v)


def test_a_gauge_count_past_eight_in_a_dataset_is_refused_in_one_line(tmp_path):
    from flexdigit.errors import DataFileError
    from flexdigit.tactile.dataset import Dataset, dataset_columns, make_meta, save_dataset
    from flexdigit.tactile.protocols import Protocol

    protocol = Protocol("p", loads_kg=(0.01,), positions_from_tip_m=(0.0,), repetitions=1, no_load_repetitions=0)
    cols = {name: np.zeros(1, dtype=dtype) for name, dtype in dataset_columns(3).items()}
    cols.update({k: v for k, v in protocol.plan(0.27).items() if k in cols})
    meta = make_meta(protocol, {"url": "sim"}, 0.27, (-5.0, 5.0), 3)
    path = save_dataset(Dataset(cols, meta), tmp_path / "d.csv")
    text = path.read_text().replace('"gauge_count": 3', '"gauge_count": 9')
    path.write_text(text)
    with pytest.raises(DataFileError, match=r"'gauge_count' must be an integer 1\.\.8\. Got 9"):
        load_dataset(path)

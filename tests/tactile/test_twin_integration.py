"""The tactile pieces on the real twin (sim rig backend and static model)."""

import numpy as np
import pytest

from flexdigit.tactile.bounds import ZONES, TwinGaugeModel, cramer_rao
from flexdigit.tactile.pipeline import features, run_pipeline, targets
from flexdigit.tactile.protocols import Protocol, load_protocol
from flexdigit.tactile.runner import load_or_collect
from flexdigit.tactile.thesis_experiments import collect_on_twin, static_dataset, twin_rig

TINY = Protocol(
    "tiny", loads_kg=(0.025,), positions_from_tip_m=(0.0, 0.10), repetitions=3, no_load_repetitions=2, settle_s=0.5
)


def test_sim_rig_collection_is_seeded_and_sees_the_load(tmp_path):
    a = collect_on_twin(TINY, tmp_path / "a.parquet", seed=3)
    b = collect_on_twin(TINY, tmp_path / "b.parquet", seed=3)
    c = collect_on_twin(TINY, tmp_path / "c.parquet", seed=4)
    np.testing.assert_array_equal(a.gauges_v, b.gauges_v)  # same seed, same numbers: one path, one machine
    assert not np.array_equal(a.gauges_v, c.gauges_v)
    assert a.meta["rig"]["url"] == "sim"
    assert "orientation='horizontal'" in a.meta["rig"]["repr"]
    # 25 g at the tip of a horizontal cantilever bends gauge 1 far beyond the twin's ~2 mV noise
    tip = a["position_index"] == 1
    assert abs(a.gauges_v[tip, 0].mean() - a.gauges_v[a["load_kg"] == 0, 0].mean()) > 0.02


def test_load_or_collect_closes_the_rig_it_opened_and_then_loads(tmp_path):
    opened = []

    def factory():
        opened.append(twin_rig(TINY, seed=3))
        return opened[-1]

    path = tmp_path / "d.parquet"
    first = load_or_collect(path, TINY, factory)
    assert len(opened) == 1
    assert opened[0].closed  # held by `with`: closed on the way out
    again = load_or_collect(path, TINY, factory)
    assert len(opened) == 1  # the file holds the protocol's dataset: loaded, no rig opened
    np.testing.assert_array_equal(again.gauges_v, first.gauges_v)


def test_twin_cannot_see_a_load_before_gauge_1():
    # table 6.1 position 16 is 24 cm from the tip = 3 cm from the clamp, before gauge 1 (45 mm, table 3.5):
    # with the cable detached no moment reaches a gauge, so nothing can locate it (the thesis does not say so)
    model = TwinGaugeModel()
    b = cramer_rao(model, [0.03, 0.20, 0.26], 0.0125)
    assert b.zone[0] == ZONES[0]
    assert np.isinf(b.crlb_known_mass_m[0])
    assert b.zone[2] == ZONES[2]
    assert b.crlb_known_mass_m[2] < 0.01


def test_thesis_corr2_on_the_static_twin_is_near_the_printed_figure():
    # chapter 6's figure: corr2 0.9823 at 18 nodes, gradient 1e-8 (6.9); the issue's tolerance is +-0.03.
    # Static twin (at rest, white noise only, default calibration), loaded readings, position numbers.
    ds = static_dataset(load_protocol("thesis-6.1"), seed=0)
    ds = ds.subset(ds["load_kg"] > 0)
    _, y = targets(ds, "position_index")
    r = run_pipeline(features(ds), y, seed=0, fixed_hidden=18, fixed_tol=1e-8, epochs=20)
    assert abs(r.corr2 - 0.9823) <= 0.03


@pytest.mark.slow
def test_actuated_corr2_on_held_out_seeds_is_near_the_printed_figure():
    # chapter 7's figure: corr2 0.8998 at 24 nodes, gradient 1e-7 (7.5); the issue's tolerance is +-0.03. The
    # cable-guide friction was fitted on seeds 0-7 (experiments.FRICTION_FIT_SEEDS); seeds 8-15 are new draws of
    # the whole experiment (readings, split, initial weights), so this checks the fit, not one lucky seed.
    from flexdigit.tactile.thesis_experiments import FRICTION_FIT_SEEDS, actuated_corr2_score
    from flexdigit.twin.calibration import default_calibration

    held_out = range(8, 16)
    assert not set(held_out) & set(FRICTION_FIT_SEEDS)
    mean, sd = actuated_corr2_score(default_calibration(), seeds=held_out, spread=True)
    assert abs(mean - 0.8998) <= 0.03
    assert 0.005 < sd < 0.04  # one experiment's scatter: why the calibration averages 8 of them


def test_twin_step_does_not_change_settled_readings(tmp_path):
    # tactile runs use the twin's 20 ms step (experiments.TACTILE_TWIN_DT_S) instead of the sim backend's 2 ms:
    # after settling, the readings of every setting agree to well under the 2 mV gauge noise
    from flexdigit.rig.base import open_rig
    from flexdigit.tactile.runner import collect

    p = Protocol(
        "dt", loads_kg=(0.025,), positions_from_tip_m=(0.0, 0.08), repetitions=2, no_load_repetitions=1, settle_s=15.0
    )
    means = []
    for dt in (0.002, 0.02):
        rig = open_rig("sim", seed=0, orientation="horizontal", cable=False, dt_s=dt)
        ds = collect(p, rig, tmp_path / f"{dt}.parquet")
        means.append([ds.gauges_v[ds["position_index"] == k].mean(axis=0) for k in (0, 1, 2)])
    assert np.max(np.abs(np.array(means[0]) - np.array(means[1]))) < 5e-4


def test_rehang_gives_every_actuated_reading_its_own_friction_state(tmp_path):
    # the thesis repeats "the procedure" for each reading (7.1): re-hung, each reading sees the cable-guide
    # friction afresh, so readings of one setting scatter far beyond the white noise; read after one hang they
    # share a state and scatter as the white noise alone (2 mV, the default calibration)
    from dataclasses import replace

    base = Protocol(
        "actuated-tiny",
        loads_kg=(0.025,),
        positions_from_tip_m=(0.0,),
        actuation_commands=(40,),
        repetitions=40,
        no_load_repetitions=0,
        settle_s=5.0,
    )
    spread = {}
    for rehang in (True, False):
        ds = collect_on_twin(replace(base, name=f"r{rehang}", rehang=rehang), tmp_path / f"{rehang}.parquet", seed=1)
        spread[rehang] = np.std(ds.gauges_v, axis=0)
    white = np.array([0.002, 0.002, 0.002])
    np.testing.assert_allclose(spread[False], white, rtol=0.5)
    assert np.all(spread[True] > 3 * white)

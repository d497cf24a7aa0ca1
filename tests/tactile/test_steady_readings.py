"""Readings taken when the digit is steady (``wait_until_steady``, a protocol TOML's default): the runner keeps
reading after the settle time until every gauge scatters as its noise, so a lightly damped digit's swing stays out
of the dataset, which the localisation Bayes limit (white noise and ADC rounding only) assumes.

References: the ringing rig below is a closed-form decaying sine on the cantilever rig (``tests/cantilever.py``),
so when its swing is below the noise is known exactly; the drawn digit is ``tests/digit_campaign.py``'s seed 0
(6 sections of 0.2 mm strip, 0.166 m, a cable pair), whose tip readings after a fixed 10 s settle scattered 3.5 to
6.6 times the noise (measured, see docs/digits.md) and its network's RMSE was 1.74 x the Bayes limit.

Tolerances: ``SWING_AT_READ_MAX = 1.0`` sigma: the check passes a window whose deviation is within 1.15 sigma of
the noise, i.e. a swing of amplitude 0.80 sigma plus the window's 7 % scatter of a deviation (runner.STEADY_FACTOR);
``SCATTER_MAX = 1.3``: the first loaded setting's readings on the twin, 40 of them, scatter as the noise within
the 11 % a deviation of 40 readings scatters (2.7 sigma of it), where a swing left in shows as 3.5-6.6.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from cantilever import NOISE_V, CantileverRig
from flexdigit.tactile.protocols import BUILTIN, Protocol, load_protocol, protocol_from_toml
from flexdigit.tactile.runner import STEADY_FACTOR, collect, wait_until_steady

SWING_AT_READ_MAX = 1.0
SCATTER_MAX = 1.3
AMPLITUDE_V = 0.2  # a swing 100 sigma high when the load lands
TAU_S = 3.0  # decays by e in 3 s: 100 sigma -> 1 sigma in 13.8 s, longer than the 10 s settle
OMEGA_RAD_S = 11.0


class RingingRig(CantileverRig):
    """The cantilever rig whose gauges ring after every load change: ``A exp(-t / tau) sin(w t)`` on each."""

    def __init__(self, seed=0, noise_scale=1.0):
        super().__init__(seed=seed)
        self.changed_at = -math.inf
        self.noise_scale = noise_scale

    def swing_v(self, t: float) -> float:
        """The swing's amplitude at time ``t`` (V)."""
        return AMPLITUDE_V * math.exp(-(t - self.changed_at) / TAU_S) if t >= self.changed_at else 0.0

    def _apply_load(self, mass_kg, position_from_base_m):
        self.changed_at = self._t

    def _read(self):
        v, pot = super()._read()
        extra = (self.noise_scale - 1.0) * NOISE_V * self.rng.standard_normal(3)
        swing = self.swing_v(self._t)
        ring = swing * math.sin(OMEGA_RAD_S * (self._t - self.changed_at)) if swing else 0.0
        return v + ring + extra, pot


def test_the_check_waits_until_the_swing_is_below_the_noise():
    rig = RingingRig(seed=3)
    rig.place_load(0.0125, 0.2)
    rig.wait(10.0)  # the fixed settle: 3.6 tau, the swing still 2.7 sigma
    assert rig.swing_v(rig._t) > 2.5 * NOISE_V
    waited, steady = wait_until_steady(rig, np.full(3, NOISE_V), 0.02, cap_s=120.0)
    assert steady
    assert rig.swing_v(rig._t) < SWING_AT_READ_MAX * NOISE_V
    # and no longer than the swing needs: it is 0.3 sigma at 10 s + 2.6 s, plus one window read
    assert waited <= TAU_S * math.log(AMPLITUDE_V / (0.3 * NOISE_V)) - 10.0 + 2.0 + 1e-9


def test_a_still_rig_is_read_after_one_window():
    rig = RingingRig(seed=4)
    waited, steady = wait_until_steady(rig, np.full(3, NOISE_V), 0.02, cap_s=60.0)
    assert steady
    assert waited == pytest.approx(2.0)


def test_a_rig_noisier_than_its_model_is_read_after_the_cap_and_said():
    rig = RingingRig(seed=5, noise_scale=2.0)
    waited, steady = wait_until_steady(rig, np.full(3, NOISE_V), 0.02, cap_s=10.0)
    assert not steady
    assert 10.0 <= waited < 12.0
    protocol = Protocol("noisy", (0.0125,), (0.0,), repetitions=2, no_load_repetitions=1, wait_until_steady=True)
    with pytest.warns(UserWarning, match=r"2 of 2 settings were not steady"):
        collect(protocol, RingingRig(seed=6, noise_scale=2.0), _tmp_out())


def _tmp_out():
    import tempfile
    from pathlib import Path

    return Path(tempfile.mkdtemp()) / "noisy.parquet"


def test_collect_takes_the_readings_once_the_swing_has_died():
    """Fixed settle: the loaded readings carry the swing; steady: they scatter as the noise."""
    base = Protocol("ring", (0.0125,), (0.0, 0.05), repetitions=40, no_load_repetitions=5, settle_s=10.0)
    scatter = {}
    for steady in (False, True):
        protocol = Protocol(**{**base.__dict__, "wait_until_steady": steady})
        ds = collect(protocol, RingingRig(seed=7), _tmp_out())
        first = (ds["position_index"] == 1) & (ds["load_kg"] > 0)
        scatter[steady] = float(np.max(ds.gauges_v[first].std(axis=0, ddof=1)) / NOISE_V)
    assert scatter[False] > 1.8  # the 2.7 sigma swing's sine: 1.9 sigma of deviation with the noise
    assert scatter[True] < SCATTER_MAX


def test_toml_protocols_wait_and_the_thesis_protocols_keep_their_fixed_settle():
    toml = 'name = "p"\nloads_g = [10.0]\npositions_from_tip_cm = [0, 1]\n'
    assert protocol_from_toml(toml).wait_until_steady
    assert not protocol_from_toml(toml + "wait_until_steady = false\n").wait_until_steady
    assert not Protocol("p", (0.01,), (0.0,)).wait_until_steady  # the library's default: readings as they were
    # the thesis's protocols: off, their fingerprints the ones main had before the option (so their journals resume)
    assert {name: load_protocol(name).wait_until_steady for name in BUILTIN} == dict.fromkeys(BUILTIN, False)
    assert load_protocol("thesis-6.1").fingerprint == "0e730ba7b109f7ef"
    assert load_protocol("thesis-7.1").fingerprint == "7034351041db8ae7"
    with pytest.raises(Exception, match="wait_until_steady"):
        protocol_from_toml(toml + 'wait_until_steady = "yes"\n')


def test_steady_factor_leaves_a_swing_below_the_noise():
    """The bound the module docstring states: a window passing at 1.15 sigma holds a swing under 0.8 sigma."""
    assert math.sqrt(2 * (STEADY_FACTOR**2 - 1)) < 0.81


@pytest.mark.slow
def test_a_ringing_drawn_digit_is_read_steady(tmp_path):
    """The campaign's seed 0 on its twin: its first loaded setting scatters as the noise when read steady."""
    import tomllib

    from digit_campaign import campaign_digit, to_toml
    from flexdigit.params import load_params
    from flexdigit.tactile.localisation import readings_gauge_model
    from flexdigit.twin.digit_calibration import twin_calibration

    digit = tmp_path / "digit.toml"
    digit.write_text(to_toml(campaign_digit(0)))
    params = load_params(digit)
    assert tomllib.loads(digit.read_text())["cables"]["count"] == 2
    protocol = protocol_from_toml(
        'name = "c"\nloads_g = [10.0]\npositions_from_tip_cm = [0.0, 0.05]\nrepetitions = 40\n'
        "no_load_repetitions = 10\nsettle_s = 10.0\n"
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # steady within the cap
        ds = collect(protocol, out=tmp_path / "d.parquet", params=params, seed=0)
    noise = readings_gauge_model(params, twin_calibration(params)).noise_v  # the Bayes limit's noise
    first = (ds["position_index"] == 1) & (ds["load_kg"] > 0)
    assert np.all(ds.gauges_v[first].std(axis=0, ddof=1) < SCATTER_MAX * noise)


class RoundedRig(CantileverRig):
    """A still rig read through a coarse ADC: white noise a quarter of an LSB, its value on a code boundary, where
    the readings toggle between two codes (a deviation of half an LSB, 1.4 x the average lsb / sqrt(12))."""

    LSB_V = 0.008

    def _read(self):
        _, pot = super()._read()  # its clock; nothing is hung
        return np.round((self.LSB_V / 2 + NOISE_V * self.rng.standard_normal(3)) / self.LSB_V) * self.LSB_V, pot


def test_a_still_gauge_under_an_lsb_is_steady():
    from flexdigit.params import RigParams
    from flexdigit.tactile.runner import still_scatter_v

    lsb = RoundedRig.LSB_V
    still = math.sqrt(NOISE_V**2 + lsb**2 / 4)  # what still_scatter_v says for this chain
    params = RigParams.from_dict({"sensors": {"adc_bits": 10, "adc_range_v": [-4.096, 4.096]}})
    assert params.sensors.adc_lsb_v == pytest.approx(lsb)
    np.testing.assert_allclose(still_scatter_v(None, params), still, rtol=1e-12)
    assert wait_until_steady(RoundedRig(seed=8), np.full(3, still), 0.02, cap_s=20.0) == (pytest.approx(2.0), True)
    # the average rounding noise would call it moving, and wait for the cap
    average = math.sqrt(NOISE_V**2 + lsb**2 / 12)
    assert not wait_until_steady(RoundedRig(seed=8), np.full(3, average), 0.02, cap_s=6.0)[1]


def test_a_tare_before_each_position_plans_and_subtracts_the_readings_just_before():
    """The plan puts the no-load block before every position; ``tare`` subtracts from each reading the blocks
    around it interpolated in time (a closed-form drift, 1 mV per reading, removed exactly), the block before it
    where none follows, and the thesis's layout (one block per test) as before, on that block."""
    from flexdigit.tactile.dataset import Dataset, dataset_columns
    from flexdigit.tactile.localisation import tare

    each = Protocol("e", (0.01,), (0.0, 0.05), repetitions=3, no_load_repetitions=2, tare_each_position=True)
    plan = each.plan(0.27)
    assert each.sample_count == len(plan["sample"]) == 2 * (2 + 3)
    assert plan["position_index"].tolist() == [0, 0, 1, 1, 1, 0, 0, 2, 2, 2]
    with pytest.raises(Exception, match="'no_load_repetitions' is 0"):
        Protocol("e", (0.01,), (0.0,), no_load_repetitions=0, tare_each_position=True)

    n = len(plan["sample"])
    cols = {c: np.zeros(n, dtype=d) for c, d in dataset_columns(1).items()}
    for key in ("sample", "test", "load_kg", "position_index", "position_from_base_m", "command", "repetition"):
        cols[key] = plan[key]
    cols["time_s"] = np.arange(n, dtype=float)
    cols["gauge1_v"] = 1e-3 * np.arange(n) + np.where(plan["load_kg"] > 0, 0.5, 0.0)  # drift + the load's signal
    ds = Dataset(cols, {"gauge_count": 1, "protocol": each.to_dict()})
    tared, since = tare(ds)
    # position 1's readings (samples 2-4) between the blocks 0-1 and 5-6: the two interpolated, the drift gone
    np.testing.assert_allclose(tared.gauges_v[2:5, 0], 0.5, atol=1e-15)
    np.testing.assert_allclose(since[2:5], [1.5, 2.5, 1.5])  # to the nearer block's mean time (0.5 or 5.5)
    # position 2's (samples 7-9), no block after: on the block 5-6, not on the test's first one
    np.testing.assert_allclose(tared.gauges_v[7:10, 0], 0.5 + 1e-3 * (np.arange(7, 10) - 5.5), atol=1e-15)
    # one block at the start (the thesis's layout): every reading on it
    once = {k: np.r_[v[:2], v[2:5], v[7:10]] for k, v in cols.items()}
    once["sample"] = np.arange(8)
    tared_once, _ = tare(Dataset(once, {"gauge_count": 1}))
    np.testing.assert_allclose(tared_once.gauges_v[2:, 0], once["gauge1_v"][2:] - 0.5e-3, atol=1e-15)


def _drifting_dataset(drift_v_per_reading: float, no_load: int, seed: int):
    """One gauge reading 10 mV per cm of a load's position plus 2 mV of white noise and a random-walk drift, the
    no-load block (``no_load`` readings) before each of 12 positions, 20 readings each (closed form)."""
    from flexdigit.tactile.dataset import Dataset, dataset_columns

    protocol = Protocol("d", (0.01,), tuple(0.01 * k for k in range(12)), repetitions=20,
                        no_load_repetitions=no_load, tare_each_position=True)  # fmt: skip
    plan = protocol.plan(0.27)
    n = len(plan["sample"])
    rng = np.random.default_rng(seed)
    drift = np.cumsum(drift_v_per_reading * rng.standard_normal(n))
    signal = np.where(plan["load_kg"] > 0, 1.0 * np.nan_to_num(plan["position_from_tip_m"]), 0.0)
    cols = {c: np.zeros(n, dtype=d) for c, d in dataset_columns(1).items()}
    for key in plan:
        cols[key] = plan[key]
    cols["time_s"] = 0.5 * np.arange(n)
    cols["gauge1_v"] = 0.05 + signal + drift + NOISE_V * rng.standard_normal(n)
    return Dataset(cols, {"gauge_count": 1, "protocol": protocol.to_dict()})


def test_train_keeps_tared_readings_where_drift_weighs_more_and_raw_ones_where_the_tare_does():
    from flexdigit.tactile.localisation import train_network

    # a drift of 2 mV a reading: positions 1 cm apart (10 mV) are scrambled as read, not once tared
    _, _, _, tared = train_network(_drifting_dataset(0.002, 5, seed=1), "position", hidden=5, tol=1e-7, epochs=20)
    assert tared
    # no drift and a one-reading tare: the tare only adds its 2 mV to every reading of a position
    _, _, _, tared = train_network(_drifting_dataset(0.0, 1, seed=2), "position", hidden=5, tol=1e-7, epochs=20)
    assert not tared

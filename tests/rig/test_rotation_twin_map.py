"""The map ``run``, ``live`` and ``export`` make from a separate twin (``make_rotation_map(rig, "twin")``): each hold
of its sweep started at rest (the servo at the command's angle, the digit in its static equilibrium), and made once
per process for one digit, calibration, set of twin options and seed.

Oracles: the map swept the slow way (the swing integrated at 2 ms until the readings show it at rest, an independent
path to rest) on the same digit and seed, both read against the twin's noise-free static equilibria at every command
(:func:`~flexdigit.twin.twin.static_gauges_v`, as tests/rig/test_rotation_sweep.py does); the random walk's closed
form (a drift of ``r`` V/sqrt(s) moves ``r sqrt(T)`` in ``T`` s) for the drift over a hold started at rest.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from digits import DIGITS
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams, load_params
from flexdigit.rig import rotation
from flexdigit.rig.base import open_rig
from flexdigit.rig.rotation import calibrate_rotation, make_rotation_map
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import Twin, static_gauges_v

from .helpers import FirstOrderRig

HANDMADE = "tests/data/handmade_digits"
#: The held rotation of a map (deg, at +-30 deg) against the twin's statics: test_rotation_sweep.py's one-section
#: tolerance (~2 sd of its maps over sweep seeds 1-10, sd 0.072 deg).
HELD_DEG = 0.15
#: A map whose holds start at rest against the slow one of the same twin, their held rotations at +-30 deg: two
#: noise-limited maps (different readings, so different draws), each ~0.072 deg sd on the one-section digit, differ
#: by ~0.1 deg sd; 2.5 sd. Measured: <= 0.062 deg (one-section, seeds 11-16), <= 0.04 deg (five-section, seeds 11-13;
#: seven-section pair, seeds 11-12).
FAST_VS_SLOW_DEG = 0.25
#: Relative tolerance on the drift's spread over holds at rest, 4 sd of a sample sd from 150 increments (5.8 %).
DRIFT_SPREAD_REL = 0.23


def _held_deg(params: RigParams, est, orientation: str, setpoints) -> list[float]:
    """The true rotation (deg) at which ``est``, tared on the clean straight gauges, reads each setpoint, on the
    twin's noise-free static equilibria at every command within 30 of straight."""
    a = params.actuator
    commands = np.arange(max(a.command_min, a.equilibrium_command - 30), min(a.command_max, a.equilibrium_command + 31))
    zeros = np.zeros(commands.size)
    gauges, sol = static_gauges_v(zeros, zeros, commands, params=params, orientation=orientation, adc=False,
                                  return_solution=True)  # fmt: skip
    straight = int(np.flatnonzero(commands == a.equilibrium_command)[0])
    truth = np.degrees(sol.psi_rad[:, -1] - sol.psi_rad[straight, -1])
    read = est.tare(gauges[straight]).predict(gauges)
    return [float(np.interp(s, read, truth)) for s in setpoints]


def _fast_and_slow(params: RigParams, seed: int, orientation: str = "vertical"):
    maps = [
        calibrate_rotation(open_rig("sim", params, seed=seed, orientation=orientation), start_at_rest=at_rest)
        for at_rest in (True, False)
    ]
    setpoints = [30.0, -30.0] if params.cables.count == 2 else [30.0]
    return [_held_deg(params, m, orientation, setpoints) for m in maps], setpoints


@pytest.mark.parametrize("seed", [12, 16])
def test_a_sweep_started_at_rest_holds_what_the_slow_sweep_holds(seed):
    params = RigParams.from_dict(DIGITS["one-section"])
    (fast, slow), setpoints = _fast_and_slow(params, seed)
    assert fast == pytest.approx(setpoints, abs=HELD_DEG)
    assert slow == pytest.approx(setpoints, abs=HELD_DEG)
    assert fast == pytest.approx(slow, abs=FAST_VS_SLOW_DEG)


@pytest.mark.slow
def test_a_lightly_damped_digits_sweep_started_at_rest_holds_what_the_slow_one_holds():
    # five bronze sections, hung (it buckles tip up): its slowest mode decays in 1.04 s, the slow sweep waits ~6 s
    # a visit for its swing to die (most of `run --params`'s start), the sweep at rest ~1 s
    params = load_params(f"{HANDMADE}/five_unequal_bronze_full.toml")
    (fast, slow), setpoints = _fast_and_slow(params, 12, orientation="hanging")
    assert fast == pytest.approx(setpoints, abs=HELD_DEG)
    assert slow == pytest.approx(setpoints, abs=HELD_DEG)
    assert fast == pytest.approx(slow, abs=FAST_VS_SLOW_DEG)


def test_a_hold_at_rest_lets_its_time_pass_for_the_drift():
    """The waits count the time skipped, and the gauges' drift walks over it as over a wait (closed form)."""
    params = RigParams.from_dict(DIGITS["one-section"])
    rig = open_rig("sim", params, seed=3)
    rest_s = 4.0
    steps = []
    for k in range(150):
        before = rig.twin.sensors.drift.copy()
        start = rig.clock()
        rig.write_command(params.actuator.equilibrium_command + (10 if k % 2 else 0))
        rotation._twin_at_rest(rig, rest_s)
        rig.read()
        assert rig.clock() - start >= rest_s
        steps.append((rig.twin.sensors.drift - before) / np.sqrt(rig.clock() - start))
    spread = np.std(steps, axis=0)
    rate = np.asarray(rig.twin.calibration.noise_drift_v_per_sqrt_s, dtype=float)
    np.testing.assert_allclose(spread, rate, rtol=DRIFT_SPREAD_REL)


def test_a_hold_at_rest_is_the_twins_static_equilibrium_at_the_command():
    params = RigParams.from_dict(DIGITS["one-section"])
    rig = open_rig("sim", params, seed=3, compiled=False)
    command = params.actuator.equilibrium_command + 12
    rig.write_command(command)
    rotation._twin_at_rest(rig, 0.5)
    _, sol = static_gauges_v([0.0], [0.0], [command], params=params, orientation="vertical", adc=False,
                             return_solution=True)  # fmt: skip
    # two solves of one equilibrium (the twin's and the batched one), to their Newton tolerance
    assert rig.tip_rotation_deg() == pytest.approx(math.degrees(sol.psi_rad[0, -1]), abs=1e-6)
    rig.wait(0.5)  # and it stays there: nothing left to swing
    assert rig.tip_rotation_deg() == pytest.approx(math.degrees(sol.psi_rad[0, -1]), abs=1e-6)


def test_only_a_twin_in_virtual_time_without_a_fixed_wait_starts_at_rest():
    # a rig in virtual time that is not a twin: nothing to put at rest
    with pytest.raises(ParameterError, match="start_at_rest.*first-order"):
        calibrate_rotation(FirstOrderRig(), reference=lambda command: 0.0, start_at_rest=True)
    with pytest.raises(ParameterError, match="settle_s=1.5"):
        calibrate_rotation(open_rig("sim"), settle_s=1.5, start_at_rest=True)


def test_a_kept_twin_map_is_the_fresh_one_and_another_seed_or_digit_gets_its_own(work_must_not_start):
    params = RigParams.from_dict(DIGITS["one-section"])
    rig = open_rig("sim", params)
    rotation._TWIN_MAPS.clear()
    first = make_rotation_map(rig, "twin", twin_options={"seed": 21})
    fresh = calibrate_rotation(open_rig("sim", params, seed=21), start_at_rest=True)
    other_seed = make_rotation_map(rig, "twin", twin_options={"seed": 22})
    other_digit = make_rotation_map(open_rig("sim", RigParams.from_dict(DIGITS["two-sections"])), "twin",
                                    twin_options={"seed": 21})  # fmt: skip
    first.tare(np.ones(1))  # a caller's tare stays its own
    work_must_not_start(Twin, "advance")  # from here on, no sweep
    kept = make_rotation_map(rig, "twin", twin_options={"seed": 21})
    # the same twin swept the same way twice: one deterministic path, so the same numbers
    np.testing.assert_array_equal(kept.coef_, fresh.coef_)
    assert kept.intercept_ == fresh.intercept_
    assert kept.tare_deg_ == 0.0
    assert not np.array_equal(other_seed.coef_, fresh.coef_)
    assert other_digit.coef_.shape != fresh.coef_.shape or not np.array_equal(other_digit.coef_, fresh.coef_)


def test_the_kept_maps_key_names_everything_the_map_depends_on():
    params = RigParams.from_dict(DIGITS["one-section"])
    calibration = twin_calibration(params)
    base = {"seed": 1, "calibration": calibration}
    noisier = calibration.replace(noise_white_v=tuple(2 * v for v in calibration.noise_white_v))
    key = rotation._twin_map_key(params, base)
    changed = {
        "seed": {**base, "seed": 2},
        "orientation": {**base, "orientation": "hanging"},
        "dt_s": {**base, "dt_s": 0.001},
        "calibration": {**base, "calibration": noisier},
        "params": None,
    }
    for what, options in changed.items():
        other = (
            rotation._twin_map_key(RigParams.from_dict(DIGITS["two-sections"]), base)
            if options is None
            else rotation._twin_map_key(params, options)
        )
        assert other != key, f"a map with another {what} would be handed the same one"
    assert rotation._twin_map_key(params, {**base, "clock": lambda: 0.0}) is None, "a clock is not data: not kept"

"""Force control's estimate follows the contact decision (issue 24): nothing touching reads 0 N, a point contact its
point force, a pressure patch (a classifying estimator) its line load's total. Before, every reading was converted
as a point force at the guessed place: a patch over a gauge read 3.6 % short (5 of its stated sd), and noise with
nothing touching read as a force (the estimate is clipped at zero force: +11 mN on average on the one-gauge digit).

References: the twin's applied loads (``Twin.press``, ``Twin.apply_pressure``: the true contact force is what was
applied, 0 when nothing is) read through its noisy sensor chain (seeds 0-2), tared at the straight command as the
hold tares. Tolerance: ``SIGMAS = 3``, the estimate within 3 of its own stated standard deviations (the Fisher sd
of the decided hypothesis over the averaged readings).
"""

from __future__ import annotations

import numpy as np
import pytest

from digits import DIGITS
from flexdigit.palpation.contact_estimation import ContactEstimator, ContactGaugeModel
from flexdigit.palpation.palpation import ForceController
from flexdigit.params import RigParams
from flexdigit.rig.base import open_rig
from flexdigit.twin.digit_calibration import twin_calibration

SIGMAS = 3.0
READINGS = 25  # readings averaged per estimate, one loop period (20 ms) apart
COMMAND = 20  # the thesis rig bent 12 commands past straight, clear of anything
REGION_M = (0.15, 0.27)  # the soft block's stretch on the thesis rig


def _read(seed: int, load=None, *, params=None, calibration=None, command=COMMAND, readings=READINGS):
    """The tare's offset (readings at the straight command less the model's) and the mean of ``readings`` readings
    at ``command`` with ``load`` (a Twin method and its arguments) on the digit, settled 3 s."""
    model = ContactGaugeModel(params, calibration)
    options = {"calibration": calibration} if calibration is not None else {}
    with open_rig("sim", params, seed=seed, **options) as rig:
        eq = rig.params.actuator.equilibrium_command
        rest = np.array([rig.read().gauges_v for _ in range(readings)]).mean(axis=0)
        rig.write_command(command)
        rig.wait(0.5)
        if load is not None:
            getattr(rig.twin, load[0])(*load[1:])
        rig.wait(3.0)
        values = []
        for _ in range(readings):
            values.append(rig.read().gauges_v)
            rig.wait(0.02)
    return rest - model.free_v([eq])[0], np.mean(values, axis=0)


@pytest.fixture(scope="module")
def classifying():
    return ContactEstimator(ContactGaugeModel(), classify=True, region_m=REGION_M, n_readings=READINGS).fit()


def _estimate(estimator, offset, reading, command=COMMAND):
    controller = ForceController(estimator, offset, average_readings=estimator.n_readings)
    controller.reset(command)
    return controller.estimate(reading, float(command))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_point_press_reads_its_force_as_a_point(classifying, seed):
    offset, reading = _read(seed, ("press", -0.1, 0.25))  # 0.1 N pressing from the cable side at 250 mm
    force, sd, kind = _estimate(classifying, offset, reading)
    assert kind == "point"
    assert abs(force - 0.1) <= SIGMAS * sd, (force, sd)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_pressure_patch_over_a_gauge_reads_its_total_as_a_line_load(classifying, seed):
    offset, reading = _read(seed, ("apply_pressure", -0.1, 0.20, 0.25))  # 0.1 N over 200-250 mm (gauge 3 at 225)
    force, sd, kind = _estimate(classifying, offset, reading)
    assert kind == "distributed"
    assert abs(force - 0.1) <= SIGMAS * sd, (force, sd)


def test_the_point_guess_misreads_that_patch():
    """What the loop read before (the point force whatever the decision): on seed 1, 96.4 mN for 100, 5 of its
    stated sd off; the decided estimate reads 99.5 mN."""
    offset, reading = _read(1, ("apply_pressure", -0.1, 0.20, 0.25))
    point = ContactEstimator(ContactGaugeModel(), classify=False, region_m=REGION_M, n_readings=READINGS).fit()
    guess = point.predict(reading - offset, COMMAND)
    assert abs(-guess.point_force_n[0] - 0.1) > SIGMAS * guess.force_sd_n[0]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nothing_touching_reads_no_force(classifying, seed):
    offset, reading = _read(seed)
    force, sd, kind = _estimate(classifying, offset, reading)
    assert kind == "none"
    assert force == 0.0  # the twin's true contact force: nothing is applied


def test_a_one_gauge_digit_reads_no_force_where_its_point_guess_read_one():
    """The one-gauge digit (36 mN of noise a reading at its contact): one reading's point guess, clipped at zero
    force, reads a force on average with nothing touching; the mean of the loop's 14 readings decides "none", 0 N."""
    one = RigParams.from_dict(DIGITS["one-section"])
    calibration = twin_calibration(one)
    model = ContactGaugeModel(one, calibration)
    region = (0.144, 0.159)  # where force control looks on this digit (palpation.force_region)
    command = one.actuator.equilibrium_command + 4
    averaged = ContactEstimator(model, classify=False, region_m=region, n_readings=14).fit()
    single = ContactEstimator(model, classify=False, region_m=region).fit()
    guesses, decided = [], []
    for seed in range(3):
        offset, reading = _read(seed, params=one, calibration=calibration, command=command, readings=14)
        decided.append(_estimate(averaged, offset, reading, command))
        with open_rig("sim", one, seed=seed + 10, calibration=calibration) as rig:
            rig.write_command(command)
            rig.wait(2.0)
            ones = np.array([rig.read().gauges_v for _ in range(50)])
        guesses.append(np.mean(-single.predict(ones - offset, command).point_force_n))
    assert [kind for _, _, kind in decided] == ["none"] * 3
    assert [force for force, _, _ in decided] == [0.0] * 3
    # the old reading of nothing, one reading's noise clipped at zero force: E max(0, X) = sigma / sqrt(2 pi) = 14 mN
    # for sigma = 36 mN (11 mN here); the mean of 150 such has an sd of ~1.7 mN, so 5 mN is 3 of them above 0
    assert np.mean(guesses) > 0.005


def test_a_hold_tares_long_enough_for_its_noise_and_no_longer_than_10_s():
    """The tare's force error (one reading's force sd over the root of the readings) within a third of 10 % of the
    setpoint: the thesis rig's 3.3 mN a reading keeps its 10 readings; the one-gauge digit's 36 mN needs 118; a
    digit whose gauges barely see the force is capped at 500 (10 s of readings), not left to tare for minutes."""
    from flexdigit.palpation.palpation import MAX_TARE_READINGS, TARE_READINGS, TARE_SHARE, _tare_readings

    assert _tare_readings(0.0033, 0.1) == TARE_READINGS
    n = _tare_readings(0.036, 0.1)
    assert 0.036 / np.sqrt(n) <= TARE_SHARE * 0.1 < 0.036 / np.sqrt(n - 1)
    assert _tare_readings(1.0, 0.1) == MAX_TARE_READINGS

"""Force control reads the servo between two commands at each command's own free shape, holds the contact's place,
and refuses a force its gauges cannot read within 10 % (issue 24: the force loop's misses on ``random_digit(10)``,
``random_digit(12)`` seed 2 and the one-gauge digit).

References: the twin's statics at a fractional command (the chain's ``solve_static`` with the cable shortened as
far as the servo between two commands pulls it, and the sensor chain: no estimator involved) for the reading of a
known point force; the twin's true contact force, logged beside every sample of a hold.

Tolerances: ``STATIC = 0.02``, the loop's reading of a noise-free point force against the force the statics put
there (the estimator's 1 mm grid and force polynomial read the reference press within 0.4 % on every test digit);
``MISREAD = 0.05``: what the old reading of the same force missed by at worst (9.4 % on ``random_digit(10)``);
``HOLD = 0.10``: the issue's 10 % of the setpoint, true force over the last 3 s of a 10 s hold.
"""

from __future__ import annotations

import numpy as np
import pytest

from digits import DIGITS, random_digit
from flexdigit.errors import ParameterError
from flexdigit.palpation.contact_estimation import ContactEstimator, ContactGaugeModel
from flexdigit.palpation.palpation import (
    COMMAND_TOLD,
    HELD_SD_SHARE,
    ForceController,
    force_region,
    hold_force,
    twin_step_s,
)
from flexdigit.params import RigParams
from flexdigit.rig.base import open_rig
from flexdigit.twin.contact import Tissue
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import cable_shortening_m

STATIC = 0.02
MISREAD = 0.05
HOLD = 0.10


def _params(name: str) -> RigParams:
    return RigParams.from_dict(random_digit(int(name[2:])) if name.startswith("rd") else DIGITS[name])


def _model(name: str) -> ContactGaugeModel:
    params = _params(name)
    return ContactGaugeModel(params, twin_calibration(params))


def _region(model) -> tuple[float, float]:
    length = model.length_m
    return (0.55 * length, length)


def _between(model, place_m: float, force_n: float, command: float) -> np.ndarray:
    """The gauges of a point force with the servo at a fractional ``command``, from the twin's statics."""
    sol = model.chain.solve_static(
        np.array([[place_m]]),
        np.array([[[0.0, force_n]]]),
        cable_shortening_m=cable_shortening_m(np.array([command]), model.params),
    )
    return model.sensors.clean_v(sol.curvature_1_m, sol.axial_force_n)[0]


def _reference_press(model) -> tuple[float, int]:
    """Where and at which command the statics first press 0.1 N into force_region's reference body (the thesis's
    soft block laid out beside the region)."""
    start, end = _region(model)
    tissue = Tissue(start, end + 0.08, 0.03 * model.length_m / 0.27, 1000.0)
    commands = np.arange(int(model.params.actuator.equilibrium_command), 255)
    sol, _ = model.tissue_solution(tissue, commands)
    k = int(np.flatnonzero(np.abs(sol.contact_force_n) >= 0.1)[0])
    return float(sol.contact_centroid_m[k]), int(commands[k])


def test_the_thesis_rig_reads_a_reading_alike_at_both_commands():
    """Its loop runs as before (its report's entries): the same reading read at the next command within 0.6 %."""
    region = force_region(ContactGaugeModel(), 0.1, region_m=(0.15, 0.27))
    assert region["command_error"] < COMMAND_TOLD
    assert not region["free_step"]


@pytest.mark.parametrize("name", ["rd10", "one-section"])
def test_a_force_between_two_commands_reads_as_the_statics_put_it(name):
    """0.1 N at the reference contact with the servo between two commands (the loop's sigma-delta sends both; its
    hold sat at 138.33): the reading moved to each command's free shape reads it within STATIC wherever the servo
    is. Before, the same reading was read at both and the two estimates interpolated: on ``random_digit(10)`` up to
    9.4 % high (at a third of a command), where the loop stops pressing (its hold -18 % on seed 2)."""
    model = _model(name)
    region = force_region(model, 0.1, region_m=_region(model))
    assert region["free_step"]
    place, command = _reference_press(model)
    # the noise of a mean of 25 readings (the loop's most): the one gauge's single reading is too noisy to decide a
    # contact of 0.1 N, which the loop's mean of 14 does
    estimator = ContactEstimator(model, classify=False, region_m=region["region_m"], n_readings=25).fit()
    read = {True: [], False: []}
    for frac in (0.1, 0.25, 1 / 3, 0.5, 2 / 3, 0.75, 0.9):
        reading = _between(model, place, -0.1, command + frac)
        for free_step in read:
            controller = ForceController(estimator, np.zeros(reading.size), free_step=free_step, high=254)
            controller.reset(command)
            read[free_step].append(controller.force(reading, command + frac))
    assert np.max(np.abs(np.array(read[True]) - 0.1)) < STATIC * 0.1, read[True]
    if name == "rd10":
        assert np.max(np.array(read[False]) - 0.1) > MISREAD * 0.1, read[False]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["rd10", "rd12"])
def test_the_drawn_digits_that_missed_hold_their_force_within_10_percent(name):
    """Seed 2 (and 0-4 measured: random_digit(10) +1.4, -2.4, -6.8, +0.8, -3.1 %; random_digit(12) +1.2, -0.1, -7.4,
    +0.2, -2.3 %): before, -18.0 and -11.5 % on seed 2, their estimates' place 20 and 10 mm inward of the contact,
    where a reading means more force. The twin's true contact force over the last 3 s."""
    params = _params(name)
    length = params.geometry.digit_length_m
    tissue = Tissue(0.55 * length, length + 0.08, 0.1 * length, 1000.0)
    rig = open_rig("sim", params, seed=2, dt_s=twin_step_s("force", params))
    try:
        rig.place_tissue(tissue)
        held = hold_force(rig, 0.1, duration_s=10.0, region_m=(tissue.start_m, length))
    finally:
        rig.close()
    assert held.region["free_step"]
    assert held.region["place_told"]
    assert abs(held.steady_error) < HOLD, held.steady_error
    assert held.unreached() == ""


def test_a_hold_its_gauges_cannot_read_within_10_percent_is_refused_before_the_digit_moves():
    """The one-gauge digit at 0.1 N: its force read uncertain by 12 mN (1 sd), more than HELD_SD_SHARE of it; the
    rig is never commanded (the twin's clock still at 0) and the line names the least force it holds."""
    params = _params("one-section")
    rig = open_rig("sim", params, seed=0, dt_s=twin_step_s("force", params))
    try:
        with pytest.raises(ParameterError, match=r"cannot hold 0\.1 N within 10 %.*holds 0\.34 N or more") as info:
            hold_force(rig, 0.1, duration_s=10.0, region_m=(0.088, 0.16), refuse_uncertain=True)
        assert rig.twin.time_s == 0.0
    finally:
        rig.close()
    assert "\n" not in str(info.value)
    assert HELD_SD_SHARE == 0.05  # the 10 % at 2 sd


def test_the_least_force_named_is_the_least_the_gauges_read_within_5_percent():
    """The refusal's "it holds F N or more": at F the hold's force sd is within HELD_SD_SHARE of F, at 0.9 F it is
    not (its tare takes fewer readings at a larger force, so the sd is not simply proportional: 0.34 N, not the
    0.25 N that 12 mN at 0.1 N would say); a noiseless twin's gauges hold any force."""
    from flexdigit.palpation.palpation import _held_force_sd, _least_held, _tare_readings

    model = _model("one-section")
    sd = force_region(model, 0.1, region_m=_region(model))["force_sd_n"]
    least = _least_held(model, sd, 10.0)
    assert least == pytest.approx(0.34)
    assert _held_force_sd(model, sd, 10.0, _tare_readings(sd, least)) <= HELD_SD_SHARE * least
    lower = 0.9 * least
    assert _held_force_sd(model, sd, 10.0, _tare_readings(sd, lower)) > HELD_SD_SHARE * lower
    assert _least_held(model, 0.0, 10.0) == 0.0

"""A moving digit with nothing touching is not read as touching (issue 24: thick_stiff_strong_servo's approach).

The force loop decides a contact by the likelihood ratio of the reading against the statics' shape at the servo's
position with nothing touching. A stiff digit's moving shape is not a shape at rest: its modes ring at every command
step the sigma-delta sends, so on its approach thick_stiff_strong_servo read 8-36 mN of "point" contact with nothing
touching, passed the 30 mN contact threshold at 0.78 s and crept in at the force loop's rate (the tissue reached at
4.8 s, the hold 14.9 % short). The hold now measures, on the digit's twin at its tare, the largest chi^2 the free
approach reads (``free_motion_chi2``) and raises the decision's threshold past it where it passes the noise's
(``motion_detect_chi2``); a digit whose free motion stays under it keeps its threshold, its decisions bit for bit.

References: the twin with nothing beside it (the true contact force 0 throughout: no tissue placed), noise-free for
the free approach and through its sensor chain (seed 0) for the hold; ``DETECT_CHI2``, the chi^2(2) 99.9 %
quantile; the closed form of the raised threshold, ``(sqrt(motion) + sqrt(detect))^2``.
Digits: the thesis rig (light; its free approach reads chi^2 4.3), thick_stiff_strong_servo (0.6 mm steel, 350),
and one of this file's own, 0.7 mm steel on two 90 mm sections with the same strong servo (5.8e3).
Tolerances: ``CLOSED_FORM_RTOL = 1e-12`` (one float expression); ``APPROACH_S = 2.5`` s of hold, past the 0.78 s of
the false contact, with the command still short of the stretch a tissue would lie on.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexdigit.palpation.contact_estimation import DETECT_CHI2, ContactEstimator, ContactGaugeModel
from flexdigit.palpation.palpation import (
    ForceController,
    force_gains,
    force_region,
    free_motion_chi2,
    hold_force,
    motion_detect_chi2,
)
from flexdigit.params import RigParams, load_params
from flexdigit.rig.base import open_rig
from flexdigit.twin.digit_calibration import twin_calibration

CLOSED_FORM_RTOL = 1e-12
APPROACH_S = 2.5
SETPOINT_N = 0.1
THICK = "tests/data/handmade_digits2/thick_stiff_strong_servo.toml"
#: This file's own stiff digit: a 0.7 mm steel strip on two 90 mm sections, a 10 mm eccentricity, a 2 N m servo
MINE = {
    "geometry": {
        "section_count": 2,
        "section_length_m": 0.09,
        "strip_thickness_m": 0.0007,
        "strip_width_m": 0.020,
        "cable_eccentricity_m": 0.010,
        "gauge_positions_m": [0.05, 0.15],
    },
    "sensors": {"bridge": "half", "adc_channels": [0, 1]},
    "actuator": {"stall_torque_nm": 2.0},
}


def _params(name: str) -> RigParams:
    return {"thesis": RigParams, "thick": lambda: load_params(THICK), "mine": lambda: RigParams.from_dict(MINE)}[name]()


def _free_chi2(params: RigParams) -> float:
    """The free approach's largest chi^2 for the hold's own controller on ``params``' digit (its region: the soft
    block's stretch, 55 % of the digit to its tip, as `palpate` lays it out)."""
    model = ContactGaugeModel(params, twin_calibration(params))
    length = params.geometry.digit_length_m
    region = (0.555 * length, length)
    gains = force_gains(model, SETPOINT_N, region_m=region)
    decided = force_region(model, SETPOINT_N, region_m=region)
    estimator = ContactEstimator(model, classify=False, region_m=decided["region_m"]).fit()
    act = params.actuator
    controller = ForceController(
        estimator, np.zeros(len(params.geometry.gauge_positions_m)), gain=gains["gain"],
        approach_rate=gains["approach_rate"], low=act.equilibrium_command, high=60,
        servo=(act.servo_wn_rad_s, act.servo_zeta), free_step=decided["free_step"],
    )  # fmt: skip
    return free_motion_chi2(controller, model, act.equilibrium_command)


@pytest.mark.parametrize(("name", "moves_as_contact"), [("thesis", False), ("thick", True), ("mine", True)])
def test_a_stiff_digits_free_approach_reads_as_contact_and_a_light_ones_does_not(name, moves_as_contact):
    """The cause: the statics read a stiff digit's own motion as a contact past the 99.9 % threshold; the thesis
    rig's stays under it (its threshold, and so every decision of its holds, unchanged)."""
    chi2 = _free_chi2(_params(name))
    assert (chi2 > DETECT_CHI2) is moves_as_contact, f"{name}: free approach chi2 {chi2:.3g}"
    raised = motion_detect_chi2(DETECT_CHI2, chi2)
    assert (raised > DETECT_CHI2) is moves_as_contact, f"{name}: threshold {raised:.3g}"


def test_the_raised_threshold_is_the_root_sum_of_the_motions_and_the_noises():
    """Under the noise's threshold nothing changes; over it, ``(sqrt(m) + sqrt(d))^2`` (350 -> 503)."""
    assert motion_detect_chi2(DETECT_CHI2, 4.3) == DETECT_CHI2
    expected = (math.sqrt(350.0) + math.sqrt(DETECT_CHI2)) ** 2
    assert motion_detect_chi2(DETECT_CHI2, 350.0) == pytest.approx(expected, rel=CLOSED_FORM_RTOL)


@pytest.mark.parametrize("name", ["thick", "mine"])
def test_a_stiff_digit_approaching_nothing_reads_no_contact(name):
    """Nothing beside the digit: over the hold's approach every decision is "none", its force 0, and the loop never
    declares a contact (before: thick_stiff_strong_servo's 0.78 s)."""
    params = _params(name)
    length = params.geometry.digit_length_m
    with open_rig("sim", params, seed=0, dt_s=0.005, calibration=twin_calibration(params)) as rig:
        held = hold_force(rig, SETPOINT_N, duration_s=APPROACH_S, region_m=(0.555 * length, length))
    assert list(held.kind).count("point") == 0, f"{name}: read as touching at {held.time_s[held.kind != 'none']}"
    assert not held.touched
    assert np.max(np.abs(held.force_n)) == 0.0
    assert held.region["detect_chi2"] > DETECT_CHI2

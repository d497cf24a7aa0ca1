"""Palpation on digits other than the thesis rig (issue 24; tests/digits.py): the studies the report's palpation
chapter runs, on a digit's own gauge model and twin, G gauges wide.

The references are the library's own independent paths: the hang covariance against readings drawn through the
twin's static path, the stiffness fit against its Cramer-Rao bound, the hang estimator against the Bayes limit of
the same settings (the issue's 1.3x for a trained estimator).
"""

import numpy as np
import pytest

from digits import DIGITS
from flexdigit.palpation import palpation_studies as studies
from flexdigit.palpation.active import simulate_hangs
from flexdigit.palpation.contact_estimation import ContactGaugeModel
from flexdigit.palpation.palpation import PalpationProtocol
from flexdigit.params import RigParams
from flexdigit.tactile.bounds import TwinGaugeModel, hang_readings_model
from flexdigit.twin.contact import Tissue
from flexdigit.twin.digit_calibration import twin_calibration

#: Relative error of an empirical variance of 3000 draws (sd ~ sqrt(2 / 3000) = 2.6 %): 4 sd
VAR_REL = 0.1
#: A stiffness fit is unbiased at its Cramer-Rao bound: within 4 of its sd
BOUND_SIGMAS = 4.0
#: The Bayes estimator of a hang against the Bayes limit of the same settings (issue 24: a trained estimator within
#: 1.3x of its limit); both on 10 draws a setting, so a margin for their Monte Carlo scatter
LIMIT_RATIO = 1.3

PAIR = RigParams.from_dict(DIGITS["four-sections-two-cables"])  # 4 gauges, the antagonistic pair: straight at 127
CAL = twin_calibration(PAIR)  # the thesis's scaled to the digit


def test_a_hang_of_a_four_gauge_digit_has_the_covariance_of_the_twins_readings():
    model = TwinGaugeModel(PAIR, CAL)
    commands = [119, 139, 159]
    mean, chol = hang_readings_model(model, [0.25], [0.0375], commands)
    assert mean.shape == (1, 12)
    v = simulate_hangs(model, [0.25], [0.0375], commands, repetitions=3000, seed=3)
    cov = chol[0] @ chol[0].T
    assert np.all(np.abs(v.mean(axis=0) - mean[0]) < 4 * np.sqrt(np.diag(cov) / len(v)) + 1e-4)
    np.testing.assert_allclose(np.var(v, axis=0), np.diag(cov), rtol=VAR_REL)


def test_a_digits_hang_estimator_reaches_its_bayes_limit():
    length = PAIR.geometry.digit_length_m
    a = studies.active_study(
        commands=(119, 139, 159), samples=300, repetitions=10, seed=1, model=TwinGaugeModel(PAIR, CAL)
    )
    assert a["posterior_position_rmse_m"] < LIMIT_RATIO * a["position_rmse_m"]
    assert a["position_rmse_m"] < 0.05 * length  # the protocol tells a hang's place to a few % of the digit


def test_a_digits_stiffness_fit_is_at_its_bound():
    length = PAIR.geometry.digit_length_m
    straight = PAIR.actuator.equilibrium_command
    s = studies.stiffness_study(
        (300.0, 1500.0),
        seeds=(0,),
        protocol=PalpationProtocol(commands=tuple(range(straight, straight + 23, 2)), tare_command=straight),
        placed=Tissue(0.55 * length, length + 0.08, 0.1 * length, 1000.0),
        model=ContactGaugeModel(PAIR, CAL),
    )
    assert np.all(np.abs(s["rel_error"]) < BOUND_SIGMAS * s["rel_bound"])


def test_a_one_gauge_digit_sees_no_contact_fully():
    # one gauge reads F (s - s_gauge) only: no contact is identifiable, and the study says so without a band
    one = RigParams.from_dict(DIGITS["one-section"])
    cal = twin_calibration(one)
    model = ContactGaugeModel(one, cal)
    c = studies.contact_study(
        positions_m=np.arange(0.0, 0.16, 0.02),
        forces_n=(0.1,),
        repetitions=4,
        estimator_model=model,
        truth_model=ContactGaugeModel(one, cal, cells_per_section=9),
    )
    assert c["zone_counts"]["identifiable"] == 0
    assert "band_m" not in c
    assert "seen_rms_position_m" not in c
    assert c["zone_counts"]["no gauge bends"] >= 1  # before the gauge at 60 mm


@pytest.mark.parametrize("name", ["four-sections-two-cables", "five-sections-eight-gauges"])
def test_a_sweep_of_g_gauges_is_drawn_with_g_noise_columns(name):
    from flexdigit.palpation.palpation import simulate_sweep

    params = RigParams.from_dict(DIGITS[name])
    straight = params.actuator.equilibrium_command
    protocol = PalpationProtocol(commands=(straight, straight + 5, straight + 10), tare_command=straight)
    length = params.geometry.digit_length_m
    record = simulate_sweep(
        ContactGaugeModel(params, twin_calibration(params)),
        Tissue(0.55 * length, length + 0.08, 0.1 * length, 1000.0),
        protocol,
        seed=0,
    )
    assert record.gauges_v.shape == (5, len(params.geometry.gauge_positions_m))


def test_a_geared_digit_holds_the_force_with_the_loops_rates_geared():
    # the force loop's gains are the digit's (palpation.force_gains): with a 4:1 gearing about four times the
    # thesis's (at the thesis's 4 commands/s the geared digit had not reached the tissue after 8 s: -96 % steady
    # error). The figures for the thesis rig: within 10 % steady, < 20 % overshoot (true force, twin)
    geared = RigParams.from_dict(DIGITS["six-gauges-geared"])
    length = geared.geometry.digit_length_m
    f = studies.force_study(
        (1000.0,),
        duration_s=8.0,
        seed=2,
        model=ContactGaugeModel(geared, twin_calibration(geared)),
        placed=Tissue(0.55 * length, length + 0.08, 0.1 * length, 1000.0),
    )
    assert abs(f["steady_error"][0]) < 0.10
    assert f["overshoot"][0] < 0.20

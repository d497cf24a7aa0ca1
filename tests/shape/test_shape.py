"""The shape estimator (tactile.shape) against closed forms and against the twin, a solver it does not share.

References: the circular arc of a constant curvature (exact); a press on a straight, weightless cantilever,
curvature f (s_L - x) / EI at each gauge (Euler-Bernoulli, E 3.12); the twin's static solution (a discrete elastica
solved by Newton, tests/twin/test_physics.py validates it against the elastica) for the shape, the tension and
the gauges; seeded noise from the twin's own noise model for the uncertainty's calibration.

Tolerances (named): integration of a constant curvature 1e-6 relative (1 mm cells, second order); forward model
against the twin's gauge curvature 1 % (the twin's 3 springs per section against a 1 mm grid); noise-free tip
within 0.5 mm of the twin's; the load found within 2 mm where the gauges can see it; at least 85 % of noisy tips
and load positions within two of their own standard deviations (95 % for a calibrated Gaussian; the shortfall is
the model choice, load or not, which the standard deviation does not carry).
"""

import math

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.params import RigParams
from flexdigit.shape.shape import DigitBeam, ShapeEstimator, shape_accuracy, true_centre_line_m
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, cached_digit, static_gauges_v

ARC_RTOL = 1e-6
FORWARD_RTOL = 0.01
NOISE_FREE_TIP_M = 0.5e-3
LOCATE_M = 2e-3
COVERAGE_2SD = 0.85


def test_integrating_a_constant_curvature_gives_the_circular_arc():
    beam = DigitBeam.from_params()
    kappa = 4.0  # 1/m: the tip turns 62 deg over 270 mm
    psi, r, _ = beam.integrate(np.full((1, beam.s_m.size), kappa))
    length = beam.length_m
    expected = np.array([math.sin(kappa * length), 1 - math.cos(kappa * length)]) / kappa
    assert psi[0, -1] == pytest.approx(kappa * length, rel=ARC_RTOL)
    assert r[0, -1] == pytest.approx(expected, rel=1e-5)  # chords of 1 mm: (kappa ds)^2 / 24 = 7e-7


@pytest.mark.parametrize("s_load", [0.10, 0.20, 0.27])
def test_press_on_a_straight_weightless_digit_matches_euler_bernoulli(s_load):
    # weightless strip and supports (upright, the weight of the real ones would amplify the bending like a
    # column's); a small press towards the cable side at command 8 slackens the cable
    params = RigParams().replace(material=RigParams().material.__class__(strip_density_kg_m3=0.0))
    calibration = default_calibration().replace(support_mass_kg=(0.0, 0.0, 0.0))
    est = ShapeEstimator(params, calibration, orientation="vertical", load="press")
    force = 1e-3  # N: small deflection
    kappa, fit, _, _ = est.predict([s_load], [force], command=8)
    beam = est.beam_
    expected = force * np.clip(s_load - beam.gauge_s_m, 0, None) * beam.gauge_inv_ei  # M = f (s_L - x), E 3.12
    assert fit["T"][0] == 0.0
    assert kappa[0] == pytest.approx(expected, rel=1e-3, abs=1e-9)


@pytest.mark.parametrize("orientation", ["vertical", "horizontal"])
def test_forward_model_agrees_with_the_twin(orientation):
    commands = np.array([8, 20, 30, 40])
    masses = np.array([0.0, 0.025, 0.0375, 0.025]) if orientation == "horizontal" else np.zeros(4)
    positions = np.array([0.0, 0.20, 0.25, 0.15])
    _, sol = static_gauges_v(masses, positions, commands, orientation=orientation, adc=False, return_solution=True)
    est = ShapeEstimator(orientation=orientation)
    kappa, fit, r, _ = est.predict(positions, masses * 9.80665, commands)
    assert kappa == pytest.approx(sol.curvature_1_m, rel=FORWARD_RTOL, abs=0.01)
    assert fit["T"] == pytest.approx(sol.tension_n, rel=FORWARD_RTOL)
    chain = cached_digit(RigParams(), default_calibration(), True, orientation, DEFAULT_CELLS_PER_SECTION)
    truth = true_centre_line_m(sol.psi_rad, chain, est.nodes_m_)
    assert np.max(np.linalg.norm(r - truth, axis=-1)) < 1e-3


def test_noise_free_twin_readings_give_its_shape_and_load():
    commands = np.array([8, 8, 20, 20, 8])
    positions = np.array([0.27, 0.20, 0.18, 0.15, 0.16])
    masses = np.full(5, 0.025)
    volts, sol = static_gauges_v(masses, positions, commands, orientation="horizontal", return_solution=True)
    est = ShapeEstimator(orientation="horizontal").estimate(volts, command=commands)
    chain = cached_digit(RigParams(), default_calibration(), True, "horizontal", DEFAULT_CELLS_PER_SECTION)
    truth = true_centre_line_m(sol.psi_rad, chain, est.s_m)
    assert np.all(np.linalg.norm(est.tip_m - truth[:, -1], axis=-1) < NOISE_FREE_TIP_M)
    assert np.all(est.contact)
    assert est.load_position_from_base_m == pytest.approx(positions, abs=LOCATE_M)
    assert est.load_mass_kg == pytest.approx(masses, rel=0.05)
    assert est.tension_n == pytest.approx(sol.tension_n, rel=0.02)


def test_bare_digit_has_no_contact_and_its_tension_follows_the_command():
    commands = np.arange(8, 44, 5)
    volts, sol = static_gauges_v(np.zeros(commands.size), np.zeros(commands.size), commands, orientation="vertical",
                                 seed=3, return_solution=True)  # fmt: skip
    est = ShapeEstimator().estimate(volts, command=commands)
    assert not np.any(est.contact)
    assert est.tension_n == pytest.approx(sol.tension_n, abs=0.1)  # N; 10 N at command 43


def test_locatability_zones_follow_the_gauges():
    # chapter 6: the cable detached, a free digit; the thesis's gauges at 45, 135, 225 mm
    est = ShapeEstimator(orientation="horizontal", cable=False, n_average=10)
    sd = est.locatability([0.03, 0.10, 0.18, 0.26], force_n=0.245)
    assert np.isinf(sd[0])  # before gauge 1 no gauge bends
    assert sd[1] > 0.02  # between gauges 1 and 2 only gauge 1 bends: position and mass trade off
    assert np.all(sd[2:] < 2e-3)  # two or three gauges bend: located to a millimetre or two


def test_uncertainty_is_calibrated_on_seeded_noise():
    acc = shape_accuracy(commands=tuple(range(8, 44, 7)), seed=11)
    bare = np.char.startswith(acc.case.astype(str), "bare")
    assert np.mean(acc.tip_error_m[bare] <= 2 * acc.tip_sd_m[bare]) >= COVERAGE_2SD
    weight = ~bare
    assert np.mean(acc.tip_error_m[weight] <= 2 * acc.tip_sd_m[weight] + 1e-3) >= COVERAGE_2SD
    located = weight & acc.contact
    err = np.abs(acc.load_position_error_m[located])
    assert np.mean(err <= 2 * acc.load_position_sd_m[located]) >= COVERAGE_2SD
    # the bare digit's shape from one noisy reading: within 2 mm at the tip
    assert np.max(acc.tip_error_m[bare]) < 2e-3


def test_live_warm_start_matches_a_cold_estimate():
    volts = static_gauges_v([0.025], [0.22], [15], orientation="horizontal")
    est = ShapeEstimator(orientation="horizontal")
    cold = est.estimate(volts, command=15)
    warm = est.estimate(volts, command=15, start=cold)
    assert warm.centre_line_m == pytest.approx(cold.centre_line_m, abs=1e-6)
    assert warm.load_position_from_base_m == pytest.approx(cold.load_position_from_base_m, abs=1e-4)


@pytest.mark.parametrize("command", [12, 30])
def test_locatability_map_is_the_cold_estimates_own(command):
    # the map starts its estimates from the model's own shape (one fit, the live page computes it per command
    # band): it must say what estimate() says from the straight digit on the same noise-free readings
    est = ShapeEstimator(orientation="horizontal", n_average=5)
    s = np.array([0.03, 0.12, 0.15, 0.19, 0.23, 0.26])
    kappa, _, _, _ = est.predict(s, np.full(s.size, 0.245), command)
    cold = est.estimate(est.volts_from_curvature(kappa), command=command)
    expected = np.where(cold.contact, cold.load_position_sd_m, np.inf)
    assert est.locatability(s, 0.245, command) == pytest.approx(expected, rel=1e-3)


def test_row_is_json_ready():
    import json

    volts = static_gauges_v([0.025], [0.22], [15], orientation="horizontal")
    row = ShapeEstimator(orientation="horizontal").estimate(volts, command=15).row(0, every=10)
    text = json.dumps(row, allow_nan=False)
    assert row["contact"] is True
    assert len(row["s_m"]) == 28  # every 10 mm and the tip
    assert abs(row["load_position_from_base_m"] - 0.22) < LOCATE_M
    assert "NaN" not in text


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda e: e.estimate([[0.1, 0.2]]), "3 gauge columns"),
        (lambda e: e.estimate([0.1, np.nan, 0.2]), "gauges_v"),
        (lambda e: e.estimate([0.1, 0.2, 0.3], command=300), "command"),
        (lambda e: ShapeEstimator(load="poke").estimate([0.1, 0.2, 0.3]), "load"),
        (lambda e: ShapeEstimator(n_average=0).estimate([0.1, 0.2, 0.3]), "n_average"),
        (lambda e: ShapeEstimator(orientation="sideways").estimate([0.1, 0.2, 0.3]), "orientation"),
    ],
)
def test_bad_input_is_named(call, match):
    with pytest.raises(ParameterError, match=match):
        call(ShapeEstimator())


def test_unsettled_lever_arms_warn_in_estimate_but_not_in_the_map():
    import warnings

    from flexdigit.errors import ConvergenceWarning

    # one update of the lever arms cannot settle a free digit sagging under 25 g: estimate says so; the map,
    # which the live page computes in a thread of its own, must not touch the process's warning filters for it
    est = ShapeEstimator(orientation="horizontal", cable=False, max_iterations=1)
    volts = static_gauges_v([0.025], [0.25], None, orientation="horizontal")  # None: the cable detached
    with pytest.warns(ConvergenceWarning, match="not settled"):
        est.estimate(volts)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sd = est.locatability([0.05, 0.25], force_n=0.245)
    assert np.isinf(sd[0]) or sd[0] > 0.01  # before gauge 1: not locatable


@pytest.mark.parametrize(("s_load", "cable"), [(0.15, True), (0.20, True), (0.26, False)])
def test_shape_from_euler_bernoulli_gauges_is_the_closed_form_deflection(s_load, cable):
    # the inverse problem against a closed form it does not share: a weightless digit pressed with f at s_L;
    # the gauges read kappa = f (s_L - x) / EI(x) (E 3.12), the estimator sees only those voltages, and its tip
    # must be the small-deflection cantilever's: y(L) = int_0^L kappa(x) (L - x) dx, theta(L) = int_0^L kappa dx,
    # with EI(x) the strip plus the section's housing on the 80 mm flexible stretches and rigid 10 mm supports
    # (2.2, tables 3.5, 3.7), integrated here by scipy's quad, not by the estimator's 1 mm grid. Beyond gauge 3 with
    # the cable attached and the command unknown the three gauges cannot tell a press there from a tension and a
    # press at gauge 3 (both moments are linear in x over the gauges): that case is the cable-less digit's
    from scipy.integrate import quad

    params = RigParams().replace(material=RigParams().material.__class__(strip_density_kg_m3=0.0))
    calibration = default_calibration().replace(support_mass_kg=(0.0, 0.0, 0.0))
    geo, length, force = params.geometry, params.geometry.digit_length_m, 2e-3  # N: small deflection
    flexible = geo.strip_length_m / geo.section_count
    rigid_half = 0.5 * (geo.section_pitch_m - flexible)
    ei_strip = params.material.youngs_modulus_pa * geo.second_moment_m4

    def kappa(x):
        k = min(int(x // geo.section_pitch_m), geo.section_count - 1)
        local = x - k * geo.section_pitch_m
        if not rigid_half < local < geo.section_pitch_m - rigid_half or x >= s_load:
            return 0.0
        return force * (s_load - x) / (ei_strip + calibration.housing_ei_n_m2[k])

    breaks = sorted({*np.arange(0.0, length, geo.section_pitch_m) + rigid_half, s_load})
    deflection = quad(lambda x: kappa(x) * (length - x), 0, length, points=breaks, limit=200)[0]
    rotation = quad(kappa, 0, length, points=breaks, limit=200)[0]
    gauges = np.array([kappa(x) for x in geo.gauge_positions_m])
    est = ShapeEstimator(params, calibration, orientation="vertical", load="press", cable=cable, contact_chi2=0.0)
    e = est.estimate(est.volts_from_curvature(gauges[None]), command=None)
    assert e.tip_m[0, 1] == pytest.approx(deflection, rel=0.01)  # a 1 mm grid and large rotations: 1 %
    assert e.angle_rad[0, -1] == pytest.approx(rotation, rel=0.01)
    assert e.tip_m[0, 0] == pytest.approx(length, abs=1e-5)  # small deflection: the tip hardly comes back
    assert e.load_position_from_base_m[0] == pytest.approx(s_load, abs=LOCATE_M)


@pytest.mark.parametrize("volts", [(30.0, 40.0, 50.0), (5.01, 0.0, 0.0), (0.0, -1e308, 0.0)])
def test_readings_beyond_the_adc_range_are_refused_naming_the_range(volts, capsys):
    # hostile review: `flexdigit shape --gauges-v=30,40,50` printed 'tip angle 6900.9 deg; cable tension
    # 1445.06 N' as an estimate, from readings the thesis rig's +-5 V ADC cannot give
    with pytest.raises(ParameterError, match=r"gauges_v.*sensors.adc_range_v.*\[-5, 5\]"):
        ShapeEstimator().estimate(np.array(volts))
    from flexdigit.cli import main

    assert main(["shape", f"--gauges-v={','.join(map(str, volts))}"]) == 2
    err = capsys.readouterr().err.strip()
    assert "adc_range_v" in err
    assert "\n" not in err


def test_readings_at_the_adc_rails_are_still_estimated():
    fit = ShapeEstimator().estimate(np.array([[5.0, 5.0, 5.0], [-5.0, -5.0, -5.0]]))
    assert fit.consistent.shape == (2,)  # judged by the fit (chi-square), not refused

"""A twin for a digit nobody has measured (issue 24, part 2): the default calibration scaled from the thesis's fit
(:mod:`flexdigit.twin.digit_calibration`) gives the packaged calibration back on the thesis rig, and each test
digit's twin bends under a tip load and under its cable as the elastica of its geometry does."""

from __future__ import annotations

import math

import numpy as np
import pytest

from digits import DIGITS
from flexdigit.params import RigParams
from flexdigit.twin.calibration import FIELDS, packaged_calibration
from flexdigit.twin.digit import build_digit
from flexdigit.twin.digit_calibration import calibration_for
from oracles import digit_contact_bvp, thesis_digit_segments

# issue 24: the derived calibration gives the packaged one back within 5 % per value on the thesis rig
THESIS_RTOL = 0.05
# issue 24: the twin's static deflection within 0.1 % of the elastica of the same geometry. The twin's chain
# converges as h^2 (tests/twin/test_contact.py): 27 cells per section put the 1-section digit's 150 mm section at
# 3e-4 and the others below 1e-4 (measured), well inside; the BVP is solved to 1e-8, far below.
ELASTICA_RTOL = 1e-3
CELLS = 27
BVP_TOL = 1e-8

# The packaged calibration (src/flexdigit/twin/default_calibration.toml, fitted to the thesis by
# ``flexdigit calibrate --thesis``), written out: the table of docs/ issue 24 asks for.
PACKAGED = {
    "support_mass_kg": [0.008385131361858766] * 3,
    "housing_ei_n_m2": [0.005724216885375177, 0.003888158961855115, 0.003888158961855115],
    "strip_beta_s": 0.00032625951945203024,
    "housing_beta_s": 0.025423373590092415,
    "cable_stiffness_n_m": 56743.12075320454,
    "housing_mass_kg": 0.0,
    "channel_gain": [0.08806706592220574, 0.12196805024924619, 0.10330206878718838],
    "channel_offset_v": [-0.12119506523149039, 0.59678641621704, 0.03525360973234166],
    "noise_white_v": [0.002] * 3,
    "noise_drift_v_per_sqrt_s": [0.0002] * 3,
    "pot_noise_v": 0.005,
    "cable_friction_ratio": 0.05481279307004473,
}


def test_the_table_is_the_packaged_calibration():
    assert set(PACKAGED) == set(FIELDS)
    packaged = packaged_calibration().to_dict()
    for key, value in PACKAGED.items():
        assert np.asarray(packaged[key]) == pytest.approx(np.asarray(value), rel=1e-12), key


@pytest.mark.parametrize("key", list(PACKAGED))
def test_the_thesis_rig_gets_its_packaged_calibration_back(key):
    derived = calibration_for(RigParams()).to_dict()[key]
    assert np.asarray(derived) == pytest.approx(np.asarray(PACKAGED[key]), rel=THESIS_RTOL, abs=0.0)


@pytest.mark.parametrize("name", list(DIGITS))
def test_each_digit_gets_one_value_per_section_and_gauge(name):
    params = RigParams.from_dict(DIGITS[name])
    cal = calibration_for(params)
    n, g = params.geometry.section_count, len(params.geometry.gauge_positions_m)
    assert len(cal.housing_ei_n_m2) == len(cal.support_mass_kg) == n
    assert len(cal.channel_gain) == len(cal.channel_offset_v) == len(cal.noise_white_v) == g
    # the channel factors lie within the thesis's three (interpolated along the digit, held beyond)
    assert min(PACKAGED["channel_gain"]) <= min(cal.channel_gain) <= max(cal.channel_gain)
    assert max(cal.channel_gain) <= max(PACKAGED["channel_gain"])


def test_the_scaling_laws():
    thesis = RigParams()
    g = thesis.geometry
    wide = RigParams.from_dict({"geometry": {"strip_width_m": 2 * g.strip_width_m, "cable_eccentricity_m": 0.008}})
    cal, ref = calibration_for(wide), packaged_calibration()
    ecc = 0.008 / g.cable_eccentricity_m
    # a support block w x 2e x l_s; a housing w (2e)^3
    assert cal.support_mass_kg[0] == pytest.approx(ref.support_mass_kg[0] * 2 * ecc, rel=1e-12)
    assert cal.housing_ei_n_m2[1] == pytest.approx(ref.housing_ei_n_m2[1] * 2 * ecc**3, rel=1e-12)
    long = RigParams.from_dict(DIGITS["five-sections-eight-gauges"])
    # the cable runs the digit's length: k = EA / l
    assert calibration_for(long).cable_stiffness_n_m == pytest.approx(ref.cable_stiffness_n_m * 0.27 / 0.5)
    # a new place along the digit: no offset (a balanced bridge)
    assert calibration_for(RigParams.from_dict(DIGITS["one-section"])).channel_offset_v == (0.0,)


def test_the_thesis_rig_keeps_its_damping_bit_for_bit():
    """The damping factor ``wn1_0 / wn1`` is exactly 1 on the thesis rig (the same chain both times)."""
    cal, ref = calibration_for(RigParams()), packaged_calibration()
    assert (cal.strip_beta_s, cal.housing_beta_s) == (ref.strip_beta_s, ref.housing_beta_s)
    assert cal == ref


def test_the_modal_chain_is_the_thesis_rigs_twin():
    """The law's chain is the thesis rig's own twin resolution, so its factor is exactly 1 there."""
    from flexdigit.twin import default_cells
    from flexdigit.twin.digit_calibration import MODAL_CELLS_PER_SECTION

    assert tuple(default_cells(RigParams().geometry)) == (MODAL_CELLS_PER_SECTION,) * 3


# The modal strain energy method (Ungar and Kerwin 1962; Johnson and Kienholz, AIAA J. 20, 1982): a lightly damped
# mode's zeta is half the loss factors of its materials weighted by the shares of its strain energy they store,
# zeta = sum_m eta_m U_m / U / 2, exact to first order in the damping. The damping law keeps each material's loss
# factor at the thesis rig's first mode, eta_m = beta_m0 wn1_0. The chain's damping (strip and housing in series
# of one spring each) is not proportional, so the modal zeta differs from the MSE's at second order: 1e-4 to 1e-3
# measured on the test digits at zeta 0.06, 0.5 % allowed.
MSE_RTOL = 0.005


def _free_chain(params, cal, housing):
    from flexdigit.twin.digit import Chain, digit_arrays
    from flexdigit.twin.digit_calibration import MODAL_CELLS_PER_SECTION

    arrays = digit_arrays(params, cal, housing=housing, cells_per_section=MODAL_CELLS_PER_SECTION)
    arrays["gravity_ab_m_s2"] = np.zeros(2)
    return Chain(**arrays)


@pytest.mark.parametrize("name", list(DIGITS))
def test_each_digits_first_mode_keeps_the_materials_loss_factors(name):
    import scipy.linalg

    ref = packaged_calibration()
    params = RigParams.from_dict(DIGITS[name])
    cal = calibration_for(params)
    housed, bare = _free_chain(params, cal, True), _free_chain(params, cal, False)
    _, shapes = scipy.linalg.eigh(housed.k_psi, housed.a_mass)  # undamped modes, lowest first
    phi = shapes[:, 0]
    energy, strip = phi @ housed.k_psi @ phi, phi @ bare.k_psi @ phi
    thesis = _free_chain(RigParams(), ref, True)
    wn0 = float(thesis.linear_modes()[0][0])  # wn1_0
    eta_strip, eta_housing = ref.strip_beta_s * wn0, ref.housing_beta_s * wn0
    expected = 0.5 * (eta_strip * strip + eta_housing * (energy - strip)) / energy
    _, zeta = housed.linear_modes()
    assert zeta[0] == pytest.approx(expected, rel=MSE_RTOL)
    # the law's point: a long soft digit is damped like the thesis rig (zeta 0.0595 without gravity), not 3x less
    # (relaxation times kept gave 0.018 on the 0.5 m digit, 0.20 on the 0.15 m one); what moves it is how the
    # first mode's strain energy splits between strip and housing (the strip's share 0.68-0.71 on these digits)
    zeta0 = float(thesis.linear_modes()[1][0])
    assert 0.8 * zeta0 < zeta[0] < 1.2 * zeta0


def _elastica(params, cal, *, tip_force_n=0.0, cable_shortening_m=None):
    pair = params.cables.count == 2
    segments, supports = thesis_digit_segments(params, cal)
    length = params.geometry.digit_length_m
    return digit_contact_bvp(
        segments,
        strip_mass_per_m=params.material.strip_density_kg_m3 * params.geometry.cross_section_m2,
        point_masses=dict(zip(supports, cal.support_mass_kg, strict=True)),
        gravity_ab=(9.80665, 0.0),  # hanging, tip down: every test digit is stable so (a 0.5 m one buckles tip up)
        eccentricity_m=params.geometry.cable_eccentricity_m,
        cable_stiffness_n_m=cal.cable_stiffness_n_m,
        cable_shortening_m=cable_shortening_m,
        cable_pretension_m=params.cables.pretension_n / cal.cable_stiffness_n_m if pair else None,
        point_forces_b={length: tip_force_n} if tip_force_n else {},
        tol=BVP_TOL,
        max_nodes=100_000,
    )


@pytest.mark.parametrize("name", list(DIGITS))
def test_static_deflection_under_a_tip_load_matches_the_elastica(name):
    params = RigParams.from_dict(DIGITS[name])
    cal = calibration_for(params)
    length = params.geometry.digit_length_m
    ei = params.bending_stiffness_n_m2 + min(cal.housing_ei_n_m2)
    force = 1.0 * ei / length**2  # alpha^2 = 1: tip rotation ~ 25-30 deg, well into large deflection
    ref = _elastica(params, cal, tip_force_n=force)
    assert ref.converged, ref.message
    twin = build_digit(params, cal, orientation="hanging", cells_per_section=CELLS).solve_static(
        tip_force_n=[[0.0, force]]
    )
    deflection = ref.tip - np.array([length, 0.0])
    assert abs(deflection[1]) > 0.05 * length  # a real large deflection
    assert np.linalg.norm(twin.tip_m[0] - ref.tip) < ELASTICA_RTOL * np.linalg.norm(deflection)


@pytest.mark.parametrize("name", list(DIGITS))
def test_static_deflection_under_the_cable_matches_the_elastica(name):
    params = RigParams.from_dict(DIGITS[name])
    cal = calibration_for(params)
    g = params.geometry
    shortening = g.cable_eccentricity_m * math.radians(30.0)  # a 30 deg tip rotation if the cable were rigid
    ref = _elastica(params, cal, cable_shortening_m=shortening)
    assert ref.converged, ref.message
    twin = build_digit(params, cal, orientation="hanging", cells_per_section=CELLS).solve_static(
        cable_shortening_m=[shortening]
    )
    deflection = ref.tip - np.array([g.digit_length_m, 0.0])
    assert abs(deflection[1]) > 0.05 * g.digit_length_m
    assert np.linalg.norm(twin.tip_m[0] - ref.tip) < ELASTICA_RTOL * np.linalg.norm(deflection)
    # the strip carries every cable's pull: the pair's T1 + T2 (the oracle's tension is the net T1 - T2)
    pulls = ref.tension_n
    if params.cables.count == 2:
        pre, lead = params.cables.pretension_n, ref.tension_n / 2
        pulls = 2 * pre if abs(lead) < pre else abs(ref.tension_n)
    assert twin.tension_n[0] == pytest.approx(pulls, rel=ELASTICA_RTOL)


def test_a_chain_per_gauge_reads_as_each_gauge_alone():
    """Gauge 1 on a full bridge with GF 2 and a 5000 amplifier, gauge 2 on a quarter bridge: each reads what a
    digit with that chain on every gauge reads (same calibration: gains, offsets)."""
    from flexdigit.twin.sensors import SensorChain

    base = DIGITS["two-sections"]
    mixed = {**base, "sensors": {**base["sensors"], "gauge_bridges": ["full", "quarter"], "gauge_factors": [2.0, 0.8],
                                  "amplifier_gains_v_per_v": [5000.0, 10000.0]}}  # fmt: skip
    params = RigParams.from_dict(mixed)
    cal = calibration_for(params)
    assert cal.noise_white_v[0] == pytest.approx(0.5 * cal.noise_white_v[1], rel=1e-12)  # noise by amplifier gain
    full = RigParams.from_dict({**base, "sensors": {**base["sensors"], "bridge": "full", "gauge_factor": 2.0,
                                                    "amplifier_gain_v_per_v": 5000.0}})  # fmt: skip
    quarter = RigParams.from_dict({**base, "sensors": {**base["sensors"], "bridge": "quarter"}})
    rng = np.random.default_rng(0)
    kappa, axial = np.array([[1.5, -0.7], [0.2, 0.4]]), np.array([[-3.0, -3.0], [0.5, 0.5]])
    volts = SensorChain(params, cal, rng).clean_v(kappa, axial)
    assert volts[:, 0] == pytest.approx(SensorChain(full, cal, rng).clean_v(kappa, axial)[:, 0], rel=1e-12)
    assert volts[:, 1] == pytest.approx(SensorChain(quarter, cal, rng).clean_v(kappa, axial)[:, 1], rel=1e-12)


def test_a_geared_servo_draws_less_cable_per_command():
    """A 4:1 reduction: the same command turns the pulley a quarter as far, so the twin's digit bends as the
    ungeared digit does under a quarter of the shortening (E 3.11 with the gearing)."""
    from flexdigit.twin.twin import cable_shortening_m

    geared = RigParams.from_dict(DIGITS["six-gauges-geared"])
    plain = RigParams.from_dict({k: v for k, v in DIGITS["six-gauges-geared"].items() if k != "actuator"})
    assert float(cable_shortening_m(40, geared)) == pytest.approx(0.25 * float(cable_shortening_m(40, plain)))


# issue 24: the release wn within 1 % of the chain's linear modal analysis (identify's fit of an 8 s record, the
# base gauge: the first mode dominates it on every test digit; higher modes show at the tip gauges of long digits)
RELEASE_WN_RTOL = 0.01


@pytest.mark.parametrize("name", list(DIGITS))
def test_a_release_rings_at_the_digits_first_linear_mode(name):
    from flexdigit.identify.identification import identify
    from flexdigit.identify.timeseries import TimeSeries
    from flexdigit.twin import records

    params = RigParams.from_dict(DIGITS[name])
    cal = calibration_for(params)
    wn = float(build_digit(params, cal, orientation="hanging").linear_modes()[0][0])
    rec = records.release_test(
        duration_s=8.0, sample_rate_hz=500, seed=1, params=params, calibration=cal, orientation="hanging"
    )
    fit = identify(TimeSeries.from_arrays(rec.column("time_s"), rec.column("gauge1_v"), channel="g1"), "release")
    assert fit.wn_rad_s == pytest.approx(wn, rel=RELEASE_WN_RTOL)


def test_a_lightly_damped_digits_sweep_waits_for_its_own_decay():
    """The campaign's seed 3 (0.44 m, 0.5 mm phosphor bronze, a pair): its strip stores most of the strain energy
    and the strip's loss factor is small, so even with the thesis rig's loss factors its slowest vibration decays
    with a 5.3 s time constant (zeta 0.015-0.02): a sweep reading may wait 10 of them, not the thesis rig's 30 s
    (which the map's sweep ran out of, docs/digits.md). ``zeta wn``, the envelope's decay rate, is about ``c / 2m``
    whatever gravity does to the stiffness: the gravity-free value agrees with the chains as mounted, hung and tip
    up (cables taut), within 5 %."""
    from digit_campaign import campaign_digit
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import SETTLE_TIME_CONSTANTS, SETTLE_TIMEOUT_S, settle_timeout_s
    from flexdigit.twin.digit_calibration import decay_time_constant_s

    assert settle_timeout_s(open_rig("sim")) == SETTLE_TIMEOUT_S
    params = RigParams.from_dict(campaign_digit(3))
    cal = calibration_for(params)
    tau = decay_time_constant_s(params, cal)
    assert 4.0 < tau < 7.0
    rig = open_rig("sim", params, calibration=cal)  # as `run --params` opens it
    assert settle_timeout_s(rig) == pytest.approx(SETTLE_TIME_CONSTANTS * tau)
    for orientation in ("vertical", "hanging"):  # gravity stiffens or softens; c / 2m hardly moves
        wn, zeta = build_digit(params, cal, orientation=orientation).linear_modes(cable_taut=2)
        assert 1.0 / float(zeta[0] * wn[0]) == pytest.approx(tau, rel=0.05)

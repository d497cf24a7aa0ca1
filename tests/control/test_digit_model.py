"""A described digit's design model (:mod:`flexdigit.control.digit_model`) against the chain it comes from, and the
weights search of its 20 ms design (:func:`flexdigit.control.design20ms.digit_weights`)."""

from __future__ import annotations

import json

import control as ct
import numpy as np
import pytest
import tomli_w

import flexdigit.control.design20ms as dz
import flexdigit.control.digit_model as digit_model_module
from digit_campaign import campaign_digit
from digits import DIGITS, random_digit
from flexdigit.cli import main
from flexdigit.control.design20ms import (
    COMMAND_NOISE_LIMIT_DEG,
    NOISE_LIMIT_DEG,
    OVERSHOOT_LIMIT_PERCENT,
    STIFFNESS_MARGIN,
    digit_design_20ms,
    stiffness_share,
)
from flexdigit.control.digit_model import digit_model
from flexdigit.errors import DesignError
from flexdigit.models.cable import tip_rotation_per_command_deg
from flexdigit.params import RigParams, twin_cells
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, cable_shortening_m, cached_digit

# The model's rotation per command is the derivative of the chain's static tip rotation at the operating command:
# a central difference over +-1 command of the nonlinear statics agrees to its curvature, ~1e-6 on these digits.
STATICS_RTOL = 1e-4
# Below the servo's bandwidth (20 rad/s) and up to 30 rad/s the truncated model's response is the full chain's
# within 3 % up to 10 rad/s (the truncated modes' dynamics, matched at DC only: 1.8 % at 10 rad/s on the 8-section
# pair) and 6 % at 30 rad/s (5.1 % there: with the damping law's larger beta on a long digit, 2.7 x the thesis's,
# its overdamped cells' real poles sit at 57 rad/s, a cluster of twenty past the model's six modes, and 340-1800
# rad/s, matched at DC; 2.7 % when beta was the thesis's).
RESPONSE_RTOL = {1.0: 0.03, 10.0: 0.03, 30.0: 0.06}
FREQUENCIES_RAD_S = tuple(RESPONSE_RTOL)

EIGHT_SECTIONS = {
    "geometry": {
        "section_count": 8,
        "section_length_m": 0.044125,
        "strip_length_m": 0.353,
        "digit_length_m": 0.433,
        "gauge_positions_m": [0.0727, 0.2246, 0.2842, 0.3174, 0.4074],
    },
    "sensors": {"bridge": "half", "adc_channels": [0, 1, 2, 3, 4]},
    "cables": {"count": 2, "pretension_n": 5.67},
    "actuator": {"gear_ratio": 3.26},
}


def _static_tip_deg(params, command) -> float:
    chain = cached_digit(params, twin_calibration(params), True, "vertical", DEFAULT_CELLS_PER_SECTION)
    shortening = float(cable_shortening_m(command, params))
    return float(np.degrees(chain.solve_static(cable_shortening_m=np.array([shortening])).psi_rad[0, -1]))


@pytest.mark.parametrize("name", ["two-sections", "six-gauges-geared"])
def test_the_models_rotation_per_command_is_the_chains_statics(name):
    params = RigParams.from_dict(DIGITS[name])
    model = digit_model(params)
    command = params.actuator.equilibrium_command + round(15.0 / tip_rotation_per_command_deg(params))
    slope = (_static_tip_deg(params, command + 1) - _static_tip_deg(params, command - 1)) / 2
    dc = np.real(np.asarray(ct.dcgain(model.plant))).reshape(-1)
    assert dc[0] == pytest.approx(slope, rel=STATICS_RTOL)
    assert dc[1] == pytest.approx(dc[0], rel=1e-9)  # the gauges' static map reads the tip's rotation
    assert model.deg_per_command == pytest.approx(slope, rel=STATICS_RTOL)


@pytest.mark.parametrize("digit", [DIGITS["two-sections"], EIGHT_SECTIONS], ids=["two-sections", "eight-sections"])
def test_the_truncated_model_responds_as_the_whole_chain(digit, monkeypatch):
    params = RigParams.from_dict(digit)
    kept = digit_model(params)
    monkeypatch.setattr(digit_model_module, "MAX_MODES", 1000)
    whole = digit_model(params)  # every mode kept: nothing truncated
    assert whole.truncated_wn_rad_s.size == 0
    assert kept.plant.nstates < whole.plant.nstates
    for w in FREQUENCIES_RAD_S:
        ours = np.asarray(ct.evalfr(kept.plant, 1j * w)).reshape(-1)
        full = np.asarray(ct.evalfr(whole.plant, 1j * w)).reshape(-1)
        assert np.all(np.abs(ours / full - 1) < RESPONSE_RTOL[w]), (w, ours, full)


def test_the_long_digits_slow_mode_is_in_its_model():
    """The 0.5 m digit hung: its first mode, 1.5 Hz, is the chain's own about the operating shape (its linear modal
    analysis, :meth:`Chain.linear_modes`), damped as the damping law gives it (the thesis rig's first-mode zeta
    carried over, ``twin.digit_calibration``: 0.07 with the cable taut; 0.02 when relaxation times were kept). The
    chain at the description's cells, as the model builds it (the twin on a derived calibration runs finer)."""
    params = RigParams.from_dict(DIGITS["five-sections-eight-gauges"])
    model = digit_model(params, orientation="hanging")
    chain = cached_digit(params, twin_calibration(params), True, "hanging", twin_cells(params))
    command = params.actuator.equilibrium_command + round(15.0 / tip_rotation_per_command_deg(params))
    psi = chain.solve_static(cable_shortening_m=np.array([float(cable_shortening_m(command, params))])).psi_rad[0]
    wn, zeta = chain.linear_modes(psi, cable_taut=1)
    assert model.modes_wn_rad_s[0] == pytest.approx(wn[0], rel=1e-6)
    assert model.modes_zeta[0] == pytest.approx(zeta[0], rel=1e-6)
    assert model.modes_wn_rad_s[0] / (2 * np.pi) == pytest.approx(1.5, abs=0.1)
    assert model.modes_zeta[0] == pytest.approx(0.07, abs=0.01)


def test_the_search_holds_its_limits_on_the_model():
    d = digit_design_20ms(RigParams.from_dict(EIGHT_SECTIONS), orientation="hanging")  # it keeps 0.55 tip up
    c = d.choice
    assert c.meets
    assert c.failing is None
    assert c.overshoot_percent < OVERSHOOT_LIMIT_PERCENT
    assert c.noise_sd_deg < NOISE_LIMIT_DEG
    assert c.command_noise_deg < COMMAND_NOISE_LIMIT_DEG
    assert c.settling_time_s < 1.0


def test_a_digit_near_buckling_tip_up_is_refused_naming_its_margin():
    """A 0.43 m five-section digit on one geared cable keeps 0.11 of its stiffness tip up: refused vertical,
    designed hung (where gravity stiffens it: a share above 1). The thesis rig keeps 0.77."""
    near = {
        "geometry": {
            "section_count": 5,
            "section_length_m": 0.0764,
            "strip_length_m": 0.382,
            "digit_length_m": 0.432,
            "gauge_positions_m": [0.0779, 0.3541],
        },
        "sensors": {"bridge": "half", "adc_channels": [0, 1]},
        "actuator": {"gear_ratio": 3.97},
    }
    params = RigParams.from_dict(near)
    assert 0 < stiffness_share(params) < STIFFNESS_MARGIN
    with pytest.raises(DesignError, match=r"nearly buckles.*keeps 0\.\d\d of its stiffness"):
        digit_design_20ms(params)
    assert stiffness_share(params, orientation="hanging") > 1.0
    assert digit_design_20ms(params, orientation="hanging").choice.meets
    assert stiffness_share(RigParams()) == pytest.approx(0.77, abs=0.01)


#: The design model against the nonlinear twin on a small step about the operating shape (tip and measured rotation,
#: rms over the first 0.5 s over the step's size): 0.2 % and 0.5 % on random_digit(23), the linearisation's own
#: error. Kept to the modes below the loop's Nyquist frequency (its 200 rad/s third mode matched at DC) the model
#: missed them by 7 % and 25 % (its measured rotation led and outswung the twin's), and the design chosen on it
#: overshot 21 % on the twin. At 3 cells a section (the twin's default then): at today's default (more cells on a
#: long section) its six lowest modes all lie below Nyquist and both rules give one model (0.9 % and 1.8 %).
REPLAY_RTOL = 0.02


def test_the_model_replays_the_twins_step_on_a_long_section():
    """``random_digit(23)`` (one 0.475 m section, 4 gauges, hung, 3 cells): a 4-command step about 15 deg on the twin
    (the nonlinear chain, integrated, no noise read) and on the model, from rest; the step issued at 3 s, where a serial
    frame and a servo pulse coincide, so it reaches the servo without delay on both."""
    from digits import random_digit
    from flexdigit.twin.twin import Twin

    params = RigParams.from_dict(random_digit(23))
    model = digit_model(params, orientation="hanging", cells_per_section=3)
    start = params.actuator.equilibrium_command + round(model.operating_deg / model.deg_per_command) - 2
    twin = Twin(params, seed=0, orientation="hanging", command=start, cells_per_section=3)
    twin.advance(3.0)
    psi0, _ = twin.state()
    twin.command(start + 4)
    t = np.arange(1, 26) * 0.020
    ours = []
    for _ in t:
        twin.advance(0.020)
        psi, _ = twin.state()
        ours.append([np.degrees(psi[-1] - psi0[-1]), model.measured_deg_per_rad @ (psi - psi0)])
    ours = np.asarray(ours)
    response = ct.forced_response(model.plant, np.r_[0.0, t], np.full(t.size + 1, 4.0))
    predicted = np.asarray(response.outputs)[:, 1:].T
    step = 4.0 * model.deg_per_command
    error = np.sqrt(np.mean((predicted - ours) ** 2, axis=0)) / step
    assert np.all(error < REPLAY_RTOL), error


#: How much of a 30 deg step's ringing the setpoint's shaper may leave in the nominal loop's tip: the ZV shaper
#: cancels the tuned mode exactly on the nominal model; what is left is the loop's other poles (1 % of the step).
SHAPED_BAND = 0.01
#: The share of the unshaped step's ringing after 1 s the shaped one may keep: the shaper is tuned to the nominal
#: loop's pole, so it cancels that mode but for the other poles' share.
RINGING_LEFT = 0.25


def _tip_step(design, t):
    loop = dz.closed_loop(design.plant_d, design.controller, output=design.tip_plant_d)
    return np.asarray(ct.forced_response(loop, t, np.full(t.size, 30.0)).outputs).reshape(-1)


LIGHTLY_DAMPED = {"random-18": (random_digit(18), "hanging"), "campaign-3": (campaign_digit(3), "vertical")}


@pytest.mark.parametrize("name", list(LIGHTLY_DAMPED))
def test_a_lightly_damped_digits_setpoint_is_shaped_for_its_mode(name):
    """``random_digit(18)`` (8 sections, 0.47 m, a pair, hung; one gauge near the tip reads its S-shaped 9.6 rad/s
    first mode, zeta 0.07, 20 times the tip) and the campaign's seed 3 (0.44 m of 0.5 mm phosphor bronze, a pair;
    9.7 rad/s, zeta 0.02): the step rings that mode, which the loop leaves under zeta 0.1 (on the twin
    ``random_digit(18)``'s tip rang +-0.5 deg about the 2 % band's edge until 1.1-1.6 s on some seeds, whichever
    weights were chosen; the campaign's rang +-0.3 deg for seconds). The chosen design's setpoint is shaped for
    the loop's pole nearest the mode, and its nominal step then stays in a 1 % band from 0.6 s on, where the same
    design unshaped does not before 0.85 s; the shaper passes a constant setpoint unchanged (its taps sum to 1)."""
    digit, orientation = LIGHTLY_DAMPED[name]
    params = RigParams.from_dict(digit)
    model = digit_model(params, orientation=orientation)
    assert model.modes_zeta[0] < dz.SHAPED_DAMPING
    shaped = digit_design_20ms(params, orientation=orientation)
    wn, zeta = shaped.setpoint_shaper
    assert wn == pytest.approx(model.modes_wn_rad_s[0], rel=0.1)
    assert zeta < dz.SHAPED_DAMPING
    plain = dz._design(model.plant, 0.02, 1, shaped.weights)  # the same design, its setpoint unshaped
    assert plain.setpoint_shaper is None
    t = np.arange(150) * 0.02
    ours, theirs = _tip_step(shaped, t), _tip_step(plain, t)
    settled = t >= 0.6
    assert np.max(np.abs(ours[settled] - 30.0)) < SHAPED_BAND * 30.0
    late = t >= 1.0  # the mode's ringing, after the transient
    assert np.max(np.abs(ours[late] - 30.0)) < RINGING_LEFT * np.max(np.abs(theirs[late] - 30.0))
    assert ours[-1] == pytest.approx(30.0, abs=0.01)
    # a kept design (its weights) is shaped alike: the shaper follows from the model
    kept = digit_design_20ms(params, orientation=orientation, weights=shaped.weights)
    assert kept.setpoint_shaper == pytest.approx(shaped.setpoint_shaper, rel=1e-12)


def test_a_digit_damped_past_the_shapers_limit_is_not_shaped():
    """The one-section digit's modes are all damped past 0.1 (its first 73 rad/s, zeta 0.11): its setpoint is not
    shaped, and its controller is the search's design as it was (no delay line)."""
    params = RigParams.from_dict(DIGITS["one-section"])
    assert np.min(digit_model(params).modes_zeta) >= dz.SHAPED_DAMPING
    d = digit_design_20ms(params)
    assert d.setpoint_shaper is None
    assert d.controller.nstates == dz._design(digit_model(params).plant, 0.02, 1, d.weights).controller.nstates


@pytest.mark.slow
def test_random_digit_18_settles_at_minus_30_deg_on_seed_1(tmp_path, capsys):
    """A run that missed (1.10 s, its tip ringing +-0.5 deg about -30 deg until then) settles within issue 24's
    figures: < 1 s, < 10 % overshoot, the true rotation within 2 %."""
    path = tmp_path / "r18.toml"
    path.write_text(tomli_w.dumps(random_digit(18)))
    argv = ["run", "--params", str(path), "--setpoint-deg=-30", "--duration", "2.5", "--seed", "1", "--json"]
    assert main(argv) == 0
    run = json.loads(capsys.readouterr().out)
    true = run["step_metrics"]["true"]
    assert true["settling_time_s"] is not None
    assert true["settling_time_s"] < 1.0
    assert true["overshoot_percent"] < 10.0
    assert abs(run["true_final_rotation_deg"] + 30.0) < 0.6

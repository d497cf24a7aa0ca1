"""Force control's command rounding (issue 24: the hold's late overshoot on cfrp_strip_four and the like): with
``hold_force(..., integer_band=True)``, where a lone one-frame command step rings the contact force more than the
10 % band, the loop sends the integer near the command it needs instead of the sigma-delta's lone steps; the thesis
rig keeps its sigma-delta. Off by default (docs/guide/palpation.md: it traded two holds over 10 % for two others).

References: a first-order sigma-delta fed a constant ``u = n + e`` sends ``n + 1`` exactly ``round(N e)`` times in
``N`` samples (its residue is ``e`` times the count, closed form); the contact force's response to a small command
step is linear, so a 4:1 geared copy of a digit (a command a quarter of the cable's pull) rings a quarter as much as
the digit, as the force a command presses scales (the twin's statics at the two commands around the press).

Tolerances: ``LINEAR = 0.05``, the ring's ratio against the force per command's between the digit and its geared
copy (the contact's stiffening over one command of the digit against a quarter of one: 1.6 % on LIGHT); ``HOLD =
0.10``, the issue's band on the true contact force's overshoot.
"""

from __future__ import annotations

import pytest

from flexdigit.palpation.contact_estimation import ContactGaugeModel
from flexdigit.palpation.palpation import (
    INTEGER_FORCE_SHARE,
    RING_BAND,
    ForceController,
    digit_tissue,
    force_gains,
    hold_force,
    lone_step_ring,
    quantiser_band,
)
from flexdigit.palpation.palpation_files import load_tissue
from flexdigit.params import RigParams
from flexdigit.rig.base import open_rig
from flexdigit.twin.calibration import packaged_calibration
from flexdigit.twin.digit_calibration import twin_calibration

LINEAR = 0.05
HOLD = 0.10

#: A light digit of our own: three 85 mm sections of a thin glass-fibre-like strip (0.5 x 12 mm, E 120 GPa, 1500
#: kg/m^3), three gauges; its lone one-frame step rings 17 mN at 0.1 N, one command pressing 28 mN.
LIGHT = {
    "geometry": {
        "section_count": 3,
        "section_length_m": 0.085,
        "strip_thickness_m": 0.0005,
        "strip_width_m": 0.012,
        "gauge_positions_m": [0.045, 0.13, 0.215],
    },
    "material": {"youngs_modulus_pa": 120e9, "strip_density_kg_m3": 1500.0},
}


def _model(description: dict) -> ContactGaugeModel:
    params = RigParams.from_dict(description)
    return ContactGaugeModel(params, twin_calibration(params))


def _sent(integer_band: float, u: float, frames: int = 100) -> list[int]:
    """The commands a controller's rounding sends for a constant continuous command ``u``."""
    controller = ForceController(None, [0.0], integer_band=integer_band)
    controller.reset(int(u))
    return [controller._quantise(u) for _ in range(frames)]


def test_the_sigma_delta_sends_a_lone_step_every_1_over_e_frames():
    """u = 19.04: the next command 4 times in 100 frames, each alone (cfrp_strip_four's 19, a 20 one frame in 25)."""
    sent = _sent(0.0, 19.04)
    assert sent.count(20) == 4
    assert sent.count(19) == 96


def test_within_the_integer_band_the_integer_is_sent_alone():
    """u = 19.04 within a band of 0.18: 19 every frame, no lone step."""
    assert set(_sent(0.18, 19.04)) == {19}


def test_outside_the_integer_band_the_sigma_delta_still_averages_to_u():
    """u = 19.3 outside a band of 0.18: 30 of 100 frames at 20, as the sigma-delta sends."""
    assert _sent(0.18, 19.3).count(20) == 30


def test_the_thesis_rig_keeps_its_sigma_delta():
    """Its report's entries: no integer band, its ring not measured."""
    band = quantiser_band(ContactGaugeModel(RigParams(), packaged_calibration()))
    assert band["integer_band"] == 0.0


def test_a_light_digits_lone_step_rings_past_the_band_and_gets_its_integer_band():
    """LIGHT rings more than 10 % of 0.1 N: the integer within half the band's force of the command is sent."""
    model = _model(LIGHT)
    band = quantiser_band(model)
    assert band["lone_step_ring_n"] > RING_BAND * 0.1
    k = force_gains(model)["force_per_command_n"]
    assert band["integer_band"] == pytest.approx(INTEGER_FORCE_SHARE * 0.1 / k, rel=1e-12)


def test_a_geared_copy_rings_as_much_less_as_a_command_presses_less():
    """LIGHT on a 4:1 gearing: a command pulls a quarter as far; the ring and the force a command presses shrink
    alike (the response is linear in a small step), and the geared copy rings inside the band (no integer band)."""
    light, geared = _model(LIGHT), _model({**LIGHT, "actuator": {"gear_ratio": 4.0}})
    ring_ratio = lone_step_ring(geared) / lone_step_ring(light)
    k_ratio = force_gains(geared)["force_per_command_n"] / force_gains(light)["force_per_command_n"]
    assert ring_ratio == pytest.approx(k_ratio, rel=LINEAR)
    assert quantiser_band(geared)["integer_band"] == 0.0


@pytest.mark.slow
def test_a_light_digit_holds_its_force_within_the_band():
    """LIGHT presses the built-in soft block laid out beside it (as `palpate --params` lays it out) and holds 0.1 N
    within 10 % overshoot (seed 0: 9.3 %; the sigma-delta alone held it within too, 6.9 %: on this digit the
    integer band neither needed nor helped, measured with `palpate --params light.toml --protocol hold`)."""
    params = RigParams.from_dict(LIGHT)
    tissue = digit_tissue(load_tissue("soft-block")[0], params)
    with open_rig("sim", params=params, seed=0, dt_s=0.005) as rig:
        rig.place_tissue(tissue)
        region = (tissue.start_m, min(tissue.end_m, params.geometry.digit_length_m))
        held = hold_force(rig, 0.1, region_m=region, integer_band=True)
    assert held.region["integer_band"] > 0.0
    assert held.overshoot < HOLD

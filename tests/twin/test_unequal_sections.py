"""Sections of unequal lengths (issue 24: "sections (count 1-8, lengths, supports)").

``Geometry.section_bounds_m`` and ``support_centres_m`` are the one source of the layout: the twin's chain, the
beam of the shape estimator, the design study's strip stretches and the elastica oracle (``tests/oracles.py``) all
take them. Equal sections must keep the arrays they always had, to the bit (same machine, same code path: no BLAS
or thread ordering is involved in laying out cells); unequal ones put each section's cells, stiffness and housing
mass on its own length. The unequal digit's statics against the elastica and its release against the chain's
linear modes are ``tests/twin/test_digit_calibration.py``'s (``DIGITS["unequal-sections"]``); its CLI path is
``tests/cli/test_simulate_digits.py``, ``tests/cli/test_digit_control.py`` and ``tests/tactile/``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from digits import DIGITS
from flexdigit.params import Geometry, RigParams
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.digit import digit_arrays, uniform_cells
from flexdigit.twin.digit_calibration import calibration_for

EQUAL = [name for name, d in DIGITS.items() if not isinstance(d.get("geometry", {}).get("section_length_m"), list)]
UNEQUAL = RigParams.from_dict(DIGITS["unequal-sections"])
#: lengths from a decimal file, summed: agree to float rounding (m)
LENGTH_ATOL_M = 1e-12


def _equal_pitch_arrays(params: RigParams, calibration, cells: int) -> dict:
    """The layout as flexdigit laid out every digit before unequal sections (commit d2aab89's digit_arrays): pitch
    ``L / n``, free strip ``strip / n``, section ``k`` on ``[k p + h, (k + 1) p - h]``, supports at ``p (k + 1)``."""
    geo = params.geometry
    nsec, pitch = geo.section_count, geo.section_pitch_m
    half = 0.5 * (pitch - geo.strip_length_m / nsec)
    cuts = [uniform_cells(k * pitch + half, (k + 1) * pitch - half, cells) for k in range(nsec)]
    s, h = np.concatenate([c[0] for c in cuts]), np.concatenate([c[1] for c in cuts])
    ei = params.material.youngs_modulus_pa * geo.second_moment_m4
    stiffness = ei / h + np.repeat(np.asarray(calibration.housing_ei_n_m2), cells) / h
    return {
        "joint_s_m": s,
        "cell_length_m": h,
        "joint_stiffness_nm_rad": stiffness,
        "support_s_m": np.minimum(pitch * (np.arange(nsec) + 1.0), geo.digit_length_m),
    }


@pytest.mark.parametrize("name", EQUAL)
@pytest.mark.parametrize("cells", [3, 27])
def test_equal_sections_keep_their_arrays_to_the_bit(name, cells):
    params = RigParams.from_dict(DIGITS[name])
    cal = calibration_for(params) if name != "thesis" else default_calibration()
    old = _equal_pitch_arrays(params, cal, cells)
    new = digit_arrays(params, cal, cells_per_section=cells)
    for key in ("joint_s_m", "cell_length_m", "joint_stiffness_nm_rad"):
        assert np.array_equal(new[key], old[key]), key
    nsec = params.geometry.section_count
    supports = new["mass_s_m"][new["joint_s_m"].size : new["joint_s_m"].size + nsec]
    assert np.array_equal(supports, old["support_s_m"])


@pytest.mark.parametrize("name", EQUAL)
def test_equal_sections_keep_their_rotation_reference_and_stretches_to_the_bit(name):
    from flexdigit.rig.rotation_reference import DigitShape
    from flexdigit.studies.design_study import SUPPORT_CLEARANCE_M, _strip_stretches

    params = RigParams.from_dict(DIGITS[name])
    geo = params.geometry
    pitch, flex = geo.section_pitch_m, geo.strip_length_m / geo.section_count
    half = 0.5 * (pitch - flex)
    starts = tuple(k * pitch + half for k in range(geo.section_count))
    assert DigitShape.from_params(params) == DigitShape(geo.digit_length_m, starts, tuple(a + flex for a in starts))
    clear = SUPPORT_CLEARANCE_M
    old = [(k * pitch + half + clear, (k + 1) * pitch - half - clear) for k in range(geo.section_count)]
    assert _strip_stretches(params) == old


def test_the_thesis_shape_beam_keeps_its_flexible_cells_to_the_bit():
    """DigitBeam (shape/) against its equal-pitch rule: ``x - k p`` strictly inside ``(h, p - h)``."""
    from flexdigit.shape.shape import DigitBeam

    params, cal = RigParams(), default_calibration()
    beam = DigitBeam.from_params(params, cal)
    geo = params.geometry
    pitch = geo.section_pitch_m
    half = 0.5 * (pitch - geo.strip_length_m / geo.section_count)
    k = np.clip(np.floor(beam.s_m / pitch).astype(int), 0, geo.section_count - 1)
    local = beam.s_m - k * pitch
    flexible = (local > half) & (local < pitch - half)
    ei = params.material.youngs_modulus_pa * geo.second_moment_m4 + np.asarray(cal.housing_ei_n_m2)[k]
    assert np.array_equal(beam.inv_ei, np.where(flexible, 1.0 / ei, 0.0))


def test_unequal_bounds_follow_the_lengths_from_the_base():
    # 60, 100, 80 mm of strip, supports of 10, 12, 10 mm after each, half the first at the clamp (2.2's layout)
    g = UNEQUAL.geometry
    expected = [(0.005, 0.065), (0.075, 0.175), (0.187, 0.267)]
    assert np.asarray(g.section_bounds_m) == pytest.approx(np.asarray(expected), abs=LENGTH_ATOL_M)
    assert g.support_centres_m == pytest.approx((0.07, 0.181, 0.272), abs=LENGTH_ATOL_M)
    assert g.support_centres_m[-1] == g.digit_length_m  # the tip support's mass never past the tip
    assert not g.equal_sections
    assert Geometry().equal_sections
    # one support length given for all: the same layout as leaving them out (to rounding)
    same = Geometry(support_lengths_m=(0.01, 0.01, 0.01))
    assert np.asarray(same.section_bounds_m) == pytest.approx(np.asarray(Geometry().section_bounds_m), abs=1e-15)


def test_each_support_weighs_by_its_own_length():
    # calibration_for: a support's mass scales with its length (the block l_s w 2e); the thesis's 10 mm weigh m0
    m0 = float(np.mean(default_calibration().support_mass_kg))
    assert calibration_for(UNEQUAL).support_mass_kg == pytest.approx((m0, 1.2 * m0, m0), rel=1e-12)


def test_unequal_sections_put_cells_stiffness_and_housing_mass_on_their_own_length():
    cells = 5
    cal = calibration_for(UNEQUAL).replace(housing_mass_kg=0.012)
    a = digit_arrays(UNEQUAL, cal, cells_per_section=cells)
    h = a["cell_length_m"].reshape(3, cells)
    assert h.sum(axis=1) == pytest.approx([0.06, 0.10, 0.08], abs=LENGTH_ATOL_M)
    # each cell's rotational stiffness is (EI_strip + EI_housing[k]) / h_k: the 100 mm section's cells are the
    # softest per cell, 60/100 as stiff as the 60 mm section's for the same EI (sections 2 and 3 share EI_housing)
    k = a["joint_stiffness_nm_rad"].reshape(3, cells)
    ei = UNEQUAL.bending_stiffness_n_m2 + np.asarray(cal.housing_ei_n_m2)
    assert k == pytest.approx((ei[:, None] / h), rel=1e-12)
    assert k[1, 0] / k[2, 0] == pytest.approx(0.08 / 0.10, rel=1e-12)
    # the housing's mass spread by length: 12 g over 240 mm of strip, 5 g on the 100 mm section
    n = a["joint_s_m"].size + 3
    housing = a["mass_kg"][n:].reshape(3, cells)
    assert housing.sum() == pytest.approx(0.012, rel=1e-12)
    assert housing.sum(axis=1) == pytest.approx([0.003, 0.005, 0.004], rel=1e-12)
    # the gauges sit midway on each section's cells (odd count: on a spring)
    assert a["joint_s_m"].reshape(3, cells)[:, 2] == pytest.approx(UNEQUAL.geometry.gauge_positions_m, abs=1e-12)


def test_the_design_study_keeps_its_stretches_on_the_unequal_strip():
    from flexdigit.studies.design_study import SUPPORT_CLEARANCE_M, _strip_stretches

    stretches = _strip_stretches(UNEQUAL)
    for (a, b), (lo, hi) in zip(stretches, UNEQUAL.geometry.section_bounds_m, strict=True):
        assert a == pytest.approx(lo + SUPPORT_CLEARANCE_M)
        assert b == pytest.approx(hi - SUPPORT_CLEARANCE_M)


def test_the_shape_beam_bends_only_on_the_unequal_strips():
    from flexdigit.shape.shape import DigitBeam

    beam = DigitBeam.from_params(UNEQUAL, calibration_for(UNEQUAL))
    flexible = beam.inv_ei > 0
    bounds = UNEQUAL.geometry.section_bounds_m
    inside = np.zeros_like(flexible)
    for lo, hi in bounds:
        inside |= (beam.s_m > lo) & (beam.s_m < hi)
    assert np.array_equal(flexible, inside)
    assert flexible.sum() * beam.ds_m == pytest.approx(0.24, abs=2 * beam.ds_m)  # 240 mm of strip on a 1 mm grid


def test_an_unequal_digit_scaled_by_the_design_study_keeps_its_proportions():
    from flexdigit.studies.design_study import _scaled

    scaled = _scaled(UNEQUAL, 1.5).geometry
    assert scaled.section_lengths_m == pytest.approx((0.09, 0.15, 0.12), abs=LENGTH_ATOL_M)
    assert scaled.supports_m == pytest.approx((0.015, 0.018, 0.015), abs=LENGTH_ATOL_M)
    assert scaled.support_centres_m[-1] == scaled.digit_length_m
    assert math.fsum(scaled.section_lengths_m) == pytest.approx(scaled.strip_length_m, abs=LENGTH_ATOL_M)


def test_one_length_keeps_its_unit_slip_hint_and_a_list_its_element_check():
    from flexdigit.errors import ParameterError

    with pytest.raises(ParameterError, match=r"Got 80.0 m instead: did you mean mm \(0.08 m\)\?"):
        Geometry(section_length_m=80.0)
    with pytest.raises(ParameterError, match=r"'section_length_m' parameter of Geometry .*Got \[0.1, 80(\.0)?, 0.1\]"):
        Geometry(section_length_m=[0.1, 80.0, 0.1])

"""One default calibration for any digit (issue 24, part 2): a twin built from Python without a calibration
(``Twin(params)``, ``open_rig("sim", params)``, the twin's record and static helpers) runs on the calibration the
CLI gives it, :func:`~flexdigit.twin.digit_calibration.twin_calibration`: the packaged thesis fit for the thesis
rig, the thesis's scaled to any other digit, even one of 3 sections and 3 gauges like the thesis rig's."""

from __future__ import annotations

import pytest

from flexdigit.params import RigParams
from flexdigit.rig import open_rig
from flexdigit.twin import Twin
from flexdigit.twin.calibration import packaged_calibration, use_calibration
from flexdigit.twin.digit_calibration import calibration_for, twin_calibration
from flexdigit.twin.records import release_orientation
from flexdigit.twin.twin import static_gauges_v

# The scaling laws are products of ratios: a rounding's worth of relative error (flexdigit.twin.digit_calibration)
LAW_RTOL = 1e-12

#: A user's own digit of the thesis rig's counts, 3 sections and 3 gauges, that is not the thesis rig: 0.15 m of
#: phosphor bronze (E 110 GPa, 8800 kg/m^3), 0.3 mm thick, a full bridge. Before issue 24's "one default" its
#: twin ran on the thesis rig's calibration unscaled (the counts matched), silently.
SMALL_3X3 = {
    "geometry": {
        "section_count": 3,
        "section_length_m": 0.04,
        "strip_thickness_m": 0.3e-3,
        "gauge_positions_m": [0.025, 0.075, 0.125],
    },
    "material": {"youngs_modulus_pa": 110e9, "strip_density_kg_m3": 8800.0},
    "sensors": {"bridge": "full"},
}


@pytest.fixture(scope="module")
def small():
    params = RigParams.from_dict(SMALL_3X3)
    assert params.geometry.digit_length_m == pytest.approx(0.15)  # 3 x 40 mm and three 10 mm supports
    return params


def test_a_3x3_digits_twin_runs_on_its_scaled_calibration(small):
    twin = Twin(small)
    assert twin.calibration == twin_calibration(small) == calibration_for(small)
    assert twin.calibration != packaged_calibration()
    # a value that could be wrong: the cable runs the digit's length, k = EA / l (0.27 m -> 0.15 m)
    ref = packaged_calibration()
    assert twin.calibration.cable_stiffness_n_m == pytest.approx(ref.cable_stiffness_n_m * 0.27 / 0.15, rel=LAW_RTOL)


def test_a_3x3_digits_sim_rig_runs_on_its_scaled_calibration(small):
    with open_rig("sim", small, seed=0) as rig:
        assert rig.twin.calibration == calibration_for(small)


def test_the_twins_helpers_take_the_same_default(small):
    """The static solver without a calibration gives the numbers of the scaled calibration, not the packaged."""
    loads = ([0.01], [0.1], [8])
    scaled = static_gauges_v(*loads, params=small, calibration=calibration_for(small), adc=False)
    packaged = static_gauges_v(*loads, params=small, calibration=packaged_calibration(), adc=False)
    assert static_gauges_v(*loads, params=small, adc=False) == pytest.approx(scaled, rel=LAW_RTOL)
    assert abs(scaled - packaged).max() > 1e-3  # V: the two calibrations are told apart by the reading
    assert release_orientation(small) == release_orientation(small, calibration_for(small))


def test_the_thesis_rig_runs_on_the_packaged_calibration():
    assert Twin().calibration == Twin(RigParams()).calibration == packaged_calibration()
    with open_rig("sim", RigParams(), seed=0) as rig:
        assert rig.twin.calibration == packaged_calibration()


def test_a_use_calibration_block_is_every_fitting_twins_default(small):
    """``reproduce --calibration``: a block's calibration is the default of every twin it describes (one value
    per section and gauge); a digit it cannot describe gets its scaled calibration."""
    fitted = calibration_for(small).replace(cable_friction_ratio=0.2)
    with use_calibration(fitted, source="test"):
        assert Twin(small).calibration == fitted
        two = RigParams.from_dict(
            {
                "geometry": {"section_count": 2, "section_length_m": 0.1, "gauge_positions_m": [0.055, 0.165]},
                "sensors": {"adc_channels": [0, 1]},
            }
        )
        assert twin_calibration(two) == calibration_for(two)
    assert Twin(small).calibration == calibration_for(small)


def test_a_batched_twin_takes_each_rigs_default(small):
    from flexdigit.twin.batched import BatchedTwin

    twins = BatchedTwin([RigParams(), small])
    assert twins.calibrations == [packaged_calibration(), calibration_for(small)]

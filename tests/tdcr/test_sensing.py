"""Shape sensing in 3D: gauge readings from the twin's strains, and the shape estimated from them against the twin.

- Readings against a closed form: one tendon at offset ``d`` bends a segment to the constant curvature
  ``T d / EI`` (a pure tendon moment, issue 26); the faces towards and away from the tendon read ``-+ r T d / EI``
  (plus the compression ``-T / EA``), the faces at right angles the compression alone.
- rao2021 with gauges at 3 stations per segment (4 axial faces and a +-45 deg torsion rosette), over 20 seeded
  random tension sets of 0..3 N per tendon: tendons alone bend each segment to a constant curvature (in this
  model), which the estimate represents exactly: tip error below ``TENDON_ONLY_TIP_ATOL_M`` (measured 5e-8 m, the
  twin's own RK4 integration between disks). With a random tip force of up to 50 mN per axis as well, the curvature
  varies along a segment and the rod twists: tip error below ``LOADED_TIP_ATOL_M`` (measured 0.050 mm, the
  quadratic-in-s fit of a curvature that is not quite quadratic); without the rosette it is millimetres (measured
  up to 19 mm), which is why the layout has one.
- Readings with 1 microstrain of white noise (a good strain-gauge amplifier's): tip error below
  ``NOISY_TIP_ATOL_M`` (measured 0.11 mm max over the 20 sets).
"""

import numpy as np
import pytest

import flexdigit.tdcr as tdcr
from flexdigit.errors import ParameterError
from flexdigit.tdcr import ROBOTS, Robot, Segment, Tendon, solve_statics
from flexdigit.tdcr.sensing import GaugeLayout, estimate_shape, gauge_layout, gauge_strains

TENDON_ONLY_TIP_ATOL_M = 1e-6
LOADED_TIP_ATOL_M = 1e-4
NOISY_TIP_ATOL_M = 2.5e-4
CLOSED_FORM_RTOL = 1e-3  # the Cosserat rod's shear and extension couple at ~1e-4 of the bending strain
SETS = 20


def _loads(seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0, 3, (SETS, 6)), rng.uniform(-0.05, 0.05, (SETS, 3))


def test_sensing_is_exported():
    for name in ("GaugeLayout", "ShapeEstimate", "gauge_layout", "gauge_strains", "estimate_shape"):
        assert name in tdcr.__all__
        assert getattr(tdcr, name) is not None


def test_readings_of_a_pure_tendon_moment_match_the_closed_form():
    offset, tension = 0.01, 1.0
    robot = Robot(name="one", segments=(Segment(0.2, 10),), tendons=(Tendon(offset, 90.0, 10),))
    b = robot.backbone
    ei, ea = b.bending_torsion_stiffness[0], b.shear_extension_stiffness[2]
    twin = solve_statics(robot, [tension], nodes_per_disk=4)
    layout = gauge_layout(robot, 2, torsion=False)
    eps = gauge_strains(twin, layout).reshape(2, 4)  # stations x faces 0, 90, 180, 270
    bending = b.radius_m * tension * offset / ei
    for row in eps:
        assert row[1] == pytest.approx(-bending - tension / ea, rel=CLOSED_FORM_RTOL)
        assert row[3] == pytest.approx(bending - tension / ea, rel=CLOSED_FORM_RTOL)
        assert row[0] == pytest.approx(-tension / ea, rel=0.05)  # compression only: its own small number
        assert row[2] == pytest.approx(row[0], abs=1e-9)


def test_tendon_only_shapes_are_recovered_exactly():
    robot = ROBOTS["rao2021"]
    layout = gauge_layout(robot, 3)
    tensions, _ = _loads()
    for t in tensions:
        twin = solve_statics(robot, t)
        assert twin.converged
        shape = estimate_shape(robot, layout, gauge_strains(twin, layout))
        assert np.linalg.norm(shape.tip_position_m - twin.tip_position_m) < TENDON_ONLY_TIP_ATOL_M


def test_tip_pose_under_tip_forces_within_the_bound():
    robot = ROBOTS["rao2021"]
    layout, axial_only = gauge_layout(robot, 3), gauge_layout(robot, 3, torsion=False)
    worst, worst_axial, worst_angle = 0.0, 0.0, 0.0
    for t, f in zip(*_loads(), strict=True):
        twin = solve_statics(robot, t, tip_force_n=f, nodes_per_disk=4)
        assert twin.converged
        shape = estimate_shape(robot, layout, gauge_strains(twin, layout))
        worst = max(worst, np.linalg.norm(shape.tip_position_m - twin.tip_position_m))
        cos = (np.trace(shape.tip_rotation.T @ twin.tip_rotation) - 1) / 2
        worst_angle = max(worst_angle, np.degrees(np.arccos(min(cos, 1.0))))
        along = np.abs(shape.position_at(twin.s_m) - twin.positions_m).max()
        assert along < LOADED_TIP_ATOL_M
        axial = estimate_shape(robot, axial_only, gauge_strains(twin, axial_only))
        worst_axial = max(worst_axial, np.linalg.norm(axial.tip_position_m - twin.tip_position_m))
    assert worst < LOADED_TIP_ATOL_M
    assert worst_angle < 0.1  # deg (measured 0.044)
    assert worst_axial > 20 * LOADED_TIP_ATOL_M  # twist unseen: the rosette matters


def test_noisy_readings_are_seeded_and_within_the_bound():
    robot = ROBOTS["rao2021"]
    layout = gauge_layout(robot, 3)
    worst = 0.0
    for k, (t, f) in enumerate(zip(*_loads(), strict=True)):
        twin = solve_statics(robot, t, tip_force_n=f, nodes_per_disk=4)
        eps = gauge_strains(twin, layout, noise_std=1e-6, seed=k)
        np.testing.assert_array_equal(eps, gauge_strains(twin, layout, noise_std=1e-6, seed=k))
        shape = estimate_shape(robot, layout, eps)
        worst = max(worst, np.linalg.norm(shape.tip_position_m - twin.tip_position_m))
    assert worst < NOISY_TIP_ATOL_M


def test_layouts_that_cannot_see_the_shape_are_refused():
    robot = ROBOTS["rao2021"]
    twin = solve_statics(robot, [1, 0, 0, 0, 1, 0])
    first_only = GaugeLayout(np.array([0.1, 0.1]), np.array([0.0, 90.0]), 0.7e-3)
    with pytest.raises(ParameterError, match="segment 2"):
        estimate_shape(robot, first_only, gauge_strains(twin, first_only))
    opposite = GaugeLayout(np.array([0.1, 0.1, 0.3, 0.3]), np.array([0.0, 180.0, 0.0, 90.0]), 0.7e-3)
    with pytest.raises(ParameterError, match="both bending planes"):
        estimate_shape(robot, opposite, gauge_strains(twin, opposite))
    off = GaugeLayout(np.array([0.5, 0.5]), np.array([0.0, 90.0]), 0.7e-3)
    with pytest.raises(ParameterError, match="on the backbone"):
        gauge_strains(twin, off)
    with pytest.raises(ParameterError, match="strains"):
        estimate_shape(robot, first_only, [0.0])


def _write_readings(path, layout, strains):
    rows = ["s_m,angle_deg,tilt_deg,strain"]
    rows += [
        f"{float(s)!r},{float(a)!r},{float(t)!r},{float(e)!r}"
        for s, a, t, e in zip(layout.s_m, layout.angles_deg, layout.tilts_deg, strains, strict=True)
    ]
    path.write_text("\n".join(rows) + "\n")


def test_sense_shape_from_a_readings_file_is_the_twins_estimate(tmp_path):
    """The readings written to a file and read back give the estimate of the twin's own readings, bit for bit
    (repr round-trips floats), and the twin beside it is the truth they came from."""
    robot = ROBOTS["rao2021"]
    tensions, forces = _loads()
    from_twin = tdcr.sense_shape(robot, tensions_n=tensions[0], tip_force_n=forces[0], noise_std=1e-6, seed=4)
    assert from_twin.tip_error_m < NOISY_TIP_ATOL_M
    assert from_twin.max_error_m >= from_twin.tip_error_m * 0.5
    assert from_twin.tip_angle_error_deg < 0.1
    path = tmp_path / "gauges.csv"
    _write_readings(path, from_twin.layout, from_twin.strains)
    layout, strains = tdcr.read_readings(path, robot)
    from_file = tdcr.sense_shape(robot, strains, layout=layout)
    np.testing.assert_array_equal(from_file.estimate.positions_m, from_twin.estimate.positions_m)
    assert from_file.twin is None
    assert from_file.tip_error_m is None


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("", "empty"),
        ("s_m,angle_deg\n0.1,0\n", "header"),
        ("s_m,angle_deg,strain,volts\n0.1,0,0,1\n", "header"),
        ("s_m,angle_deg,strain\n0.1,0\n", "line 2: 2 cells"),
        ("s_m,angle_deg,strain\n0.1,0,x\n", "line 2: strain 'x' is not a finite number"),
        ("s_m,angle_deg,strain\n0.1,0,nan\n", "line 2: strain 'nan'"),
        ("s_m,angle_deg,strain\n0.1,0,0\n0.5,0,0\n", "line 3: s_m 0.5 is off the backbone"),
        ("s_m,angle_deg,strain\n0.1,0,2000\n", "line 2: strain 2000 is not a strain gauge's reading"),
    ],
)
def test_bad_readings_files_are_refused_in_one_line(tmp_path, text, needle):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match="bad.csv") as info:
        tdcr.read_readings(path, ROBOTS["rao2021"])
    assert needle in str(info.value)
    assert "\n" not in str(info.value)

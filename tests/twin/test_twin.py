"""The stepping API the rig's sim backend builds on, and the batched static solver."""

import math

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.models.servo import command_to_angle_rad
from flexdigit.params import RigParams
from flexdigit.twin import Twin, static_gauges_v


def test_same_seed_same_numbers_different_seed_different_noise():
    def run(seed):
        twin = Twin(seed=seed)
        twin.command(30)
        out = []
        for _ in range(50):
            twin.advance(0.01)
            out.append(np.append(*twin.read()))
        return np.array(out)

    a, b, c = run(3), run(3), run(4)
    np.testing.assert_array_equal(a, b)  # exact: the same code path twice on one machine
    assert not np.array_equal(a, c)


def test_command_takes_effect_on_the_next_serial_frame_and_pwm_pulse():
    twin = Twin(seed=0)
    twin.advance(0.005)
    twin.command(60)
    period = twin.params.actuator.serial_period_s
    pulse = 1 / twin.params.actuator.pwm_frequency_hz
    # issued at 5 ms: frame at 20 ms, next PWM pulse at 2/52 s = 38.5 ms, integration grid 40 ms
    expected = math.ceil(math.ceil(0.005 / period) * period / pulse) * pulse
    twin.advance(0.030)
    assert twin.servo.command == 8
    twin.advance(expected + twin.dt_s - 0.035)
    assert twin.servo.command == 60


@pytest.mark.parametrize(
    "issued_s, applies_s",
    [(0.005, 0.022), (0.020, 0.022), (0.0201, 0.042), (0.038, 0.042), (0.040, 0.042)],
)
def test_timer_drive_latches_at_the_frame_and_pulses_1_ms_later(issued_s, applies_s):
    """The firmware's Timer1 drive (firmware/flexdigit_board.c): a 20 ms frame, the pulse 1 ms after its start,
    the width latched there; on the 2 ms grid the pulse at 21 ms takes effect at 22 ms (worked by hand)."""
    twin = Twin(seed=0, dt_s=0.002, servo_drive="timer")
    twin.advance(issued_s)
    twin.command(60)
    twin.advance(applies_s - issued_s)  # up to the grid point it takes effect at: the steps before it had 8
    assert twin.servo.command == 8
    twin.advance(twin.dt_s)  # the step from it has 60
    assert twin.servo.command == 60


def test_servo_drive_is_one_of_the_two():
    with pytest.raises(ParameterError, match="drive"):
        Twin(servo_drive="usb")


def test_servo_follows_the_identified_second_order_step():
    # 3.2.4: zeta 0.5629, wn 20.53 rad/s -> overshoot 100 exp(-zeta pi / sqrt(1 - zeta^2)) = 11.8 %
    twin = Twin(seed=0, cable=False, command=0)
    twin.command(51)
    twin.advance(0.02)
    start = twin.time_s
    angles = []
    for _ in range(300):
        twin.advance(0.002)
        angles.append(twin.state()[1])
    target = command_to_angle_rad(51)
    zeta = 0.5629
    overshoot = np.exp(-zeta * np.pi / np.sqrt(1 - zeta**2))
    assert max(angles) / target - 1 == pytest.approx(overshoot, abs=0.005)
    assert angles[-1] == pytest.approx(target, rel=1e-3)
    assert start > 0


def test_pot_voltage_follows_the_params_line():
    twin = Twin(seed=0, cable=False, command=200)
    _, pot = twin.read()
    a = twin.params.actuator
    expected = a.pot_v_at_min_angle_v + 200 * (a.pot_v_at_max_angle_v - a.pot_v_at_min_angle_v) / 254
    assert pot == pytest.approx(expected, abs=0.03)  # pot noise 5 mV


@pytest.mark.parametrize("bad", [255, -1, 8.5, float("nan"), "8", True])
def test_bad_commands_raise_parameter_error(bad):
    twin = Twin(seed=0)
    with pytest.raises(ParameterError, match="command"):
        twin.command(bad)


@pytest.mark.parametrize(
    ("mass", "position", "match"),
    [
        (-0.01, 0.1, "mass_kg"),
        (0.0, 0.1, "mass_kg"),
        (0.01, 0.30, "position_from_base_m"),
        (float("nan"), 0.1, "mass_kg"),
        (0.01, float("nan"), "position_from_base_m"),
    ],
)
def test_bad_loads_raise_parameter_error(mass, position, match):
    twin = Twin(seed=0)
    with pytest.raises(ParameterError, match=match):
        twin.place_load(mass, position)


def test_advance_rejects_negative_and_nan_durations():
    twin = Twin(seed=0)
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ParameterError, match="duration_s"):
            twin.advance(bad)


def test_a_settled_twin_reads_what_the_static_solver_predicts():
    params = RigParams()
    twin = Twin(seed=0, orientation="horizontal", command=20)
    twin.place_load(0.025, 0.20)
    twin.advance(6.0)
    dynamic, _ = twin.clean_read()
    static = static_gauges_v([0.025], [0.20], [20], adc=False)[0]
    np.testing.assert_allclose(dynamic, static, atol=2e-4)
    twin.clear_loads()
    twin.advance(6.0)
    np.testing.assert_allclose(twin.clean_read()[0], static_gauges_v([0.0], [0.2], [20], adc=False)[0], atol=2e-4)
    assert params.geometry.digit_length_m == 0.27


def test_static_batch_equals_case_by_case_and_accepts_several_loads_per_case():
    masses = np.array([[0.0125, 0.0], [0.025, 0.0075], [0.0, 0.0]])
    positions = np.array([[0.27, 0.1], [0.2, 0.15], [0.1, 0.1]])
    batch = static_gauges_v(masses, positions, [8, 20, 40], adc=False)
    for k in range(3):
        one = static_gauges_v(masses[k : k + 1], positions[k : k + 1], [[8, 20, 40][k]], adc=False)
        np.testing.assert_allclose(batch[k], one[0], rtol=1e-9, atol=1e-12)


def test_hanging_weight_bends_the_horizontal_digit_more_the_heavier_it_is():
    v = static_gauges_v([0.0, 0.0125, 0.025], [0.27, 0.27, 0.27], None, adc=False)
    assert v[1, 0] < v[0, 0]
    assert v[2, 0] < v[1, 0]  # gauge 1: more weight, more negative (bends away from cable)


def test_spring_moments_balance_the_weights_in_the_deformed_shape():
    # statics check independent of the solver: at every spring, k * phi = moment of the weights beyond it,
    # with lever arms taken from the deformed positions (large deflection, no small-angle approximation)
    from flexdigit.twin.calibration import default_calibration
    from flexdigit.twin.twin import cached_digit

    p = RigParams()
    chain = cached_digit(p, default_calibration(), True, "horizontal", 3)
    load_s, load_m = 0.21, 0.0375
    _, sol = static_gauges_v([load_m], [load_s], None, return_solution=True)
    psi = sol.psi_rad[0]
    phi = np.diff(psi, prepend=0.0)
    s_all = np.append(chain.mass_s_m, load_s)
    m_all = np.append(chain.mass_kg, load_m)
    pos = chain.positions(psi, s_all)
    joints = chain.positions(psi, chain.joint_s_m)
    for j, s_j in enumerate(chain.joint_s_m):
        beyond = s_all > s_j
        arm = pos[beyond] - joints[j]
        force = m_all[beyond, None] * chain.gravity
        moment = np.sum(arm[:, 0] * force[:, 1] - arm[:, 1] * force[:, 0])
        assert chain.stiffness[j] * phi[j] == pytest.approx(moment, rel=1e-8, abs=1e-12)


def test_static_inputs_are_checked():
    with pytest.raises(ParameterError, match="loads_mass_kg"):
        static_gauges_v([-0.01], [0.1])
    with pytest.raises(ParameterError, match="positions_from_base_m"):
        static_gauges_v([0.01], [0.3])
    with pytest.raises(ParameterError, match="commands"):
        static_gauges_v([0.01], [0.1], [300])
    with pytest.raises(ParameterError, match="commands"):
        static_gauges_v([0.01], [0.1], [8.5])
    with pytest.raises(ParameterError, match="loads_mass_kg"):
        static_gauges_v([float("nan")], [0.1])


def test_cable_is_slack_below_the_equilibrium_command():
    # below command 8 the cable is slack, so a vertical digit stays straight: same reading at 0 and 8
    v = static_gauges_v([0.0, 0.0], [0.27, 0.27], [0, 8], orientation="vertical", adc=False)
    np.testing.assert_allclose(v[0], v[1], atol=1e-9)


def test_a_full_range_command_step_settles_on_the_static_equilibrium():
    # the most violent input the rig can get (8 -> 43 in one frame): the adaptive step keeps the dynamics finite
    # and the digit comes to rest where the static solver puts it
    twin = Twin(seed=0, command=8)
    twin.command(43)
    twin.advance(6.0)
    static = static_gauges_v([0.0], [0.27], [43], orientation="vertical", adc=False)[0]
    np.testing.assert_allclose(twin.clean_read()[0], static, atol=5e-4)
    assert np.max(np.abs(twin.dynamics.omega)) < 0.05


def test_default_step_tracks_a_fine_step_after_a_cable_pull():
    # an A-stable but not L-stable method leaves the fast cell modes ringing at the grid rate; the default 20 ms
    # step must follow a 1 ms reference through the transient of a cable pull, gauge by gauge
    coarse, fine = Twin(seed=0, command=8), Twin(seed=0, command=8, dt_s=0.001)
    for twin in (coarse, fine):
        twin.command(30)
    worst = 0.0
    for _ in range(100):
        coarse.advance(0.02)
        fine.advance(0.02)
        worst = max(worst, float(np.max(np.abs(coarse.clean_read()[0] - fine.clean_read()[0]))))
    span = abs(static_gauges_v([0.0], [0.27], [30], orientation="vertical", adc=False)[0, 1] - fine.clean_read()[0][1])
    assert worst < 0.01  # V, against a swing of ~0.2 V on gauge 2
    assert span < 0.01  # and both have settled near the static value


def test_cable_slackening_and_snapping_taut_stays_close_to_a_fine_reference():
    # a large downward step slackens the cable, the next upward one snaps it taut (34 -> 15 -> 30 -> 0 -> 40)
    def run(dt_s):
        twin = Twin(seed=0, command=8, dt_s=dt_s)
        out = []
        for c in (34, 15, 30, 0, 40):
            twin.command(c)
            for _ in range(25):
                twin.advance(0.02)
                out.append(twin.clean_read()[0])
        return np.array(out)

    coarse, fine = run(0.02), run(0.001)
    assert np.all(np.isfinite(coarse))
    assert np.max(np.abs(coarse - fine)) < 0.05  # V, during snaps of ~1 V; settled values agree far closer
    np.testing.assert_allclose(coarse[-1], fine[-1], atol=2e-3)


def _read_one_by_one(twin, times):
    """The loop Twin.read_at replaces: advance to each time, read, note the command, angle and tip."""
    rows = []
    for t in times:
        twin.advance(max(t - twin.time_s, 0.0))
        gauges, pot = twin.read()
        psi, theta = twin.state()
        rows.append((gauges, pot, twin.servo.command, theta, twin.chain.tip(psi)))
    return [np.array(column) for column in zip(*rows, strict=True)]


def _released(twin):
    twin.deflect(0.05)


def _loaded_and_stepped(twin):
    twin.place_load(0.02, 0.2)  # a jolt: the cable-guide friction is in every taut reading
    twin.command(35)


def _on_tissue(twin):
    from flexdigit.twin.contact import Tissue

    twin.set_tissue(Tissue(0.15, 0.27, 0.004, 5000.0))
    twin.command(30)


READ_AT_CASES = {  # (Twin keywords, set-up, times): bare release, taut cable with friction, repeated times, ...
    "release, cable off": (dict(cable=False, dt_s=0.01, seed=3), _released, np.arange(0, 1001) / 500),
    "taut cable, friction": (
        dict(seed=5, command=20),
        _loaded_and_stepped,
        np.sort(np.random.default_rng(1).uniform(0, 2, 500)),
    ),
    "repeated times": (dict(seed=7), lambda tw: tw.command(40), np.repeat(np.arange(0, 60) / 97, 2)),
    "compiled kernel": (dict(seed=9, compiled=True), lambda tw: tw.command(30), np.arange(0, 401) / 1000),
    "tissue contact": (dict(seed=2), _on_tissue, np.arange(0, 41) / 100),
}


@pytest.mark.parametrize("case", READ_AT_CASES)
def test_read_at_gives_the_read_loops_numbers_bit_for_bit(case):
    # Twin.read_at batches the reads between grid points; the loop of advance() + read() is the reference: the
    # same random draws in the same order and the same operations, so every column equal, not just close (both
    # paths in one process: exactness is the property; no stored number is compared)
    kwargs, set_up, times = READ_AT_CASES[case]
    loop_twin, batch_twin = Twin(**kwargs), Twin(**kwargs)
    set_up(loop_twin)
    set_up(batch_twin)
    expected = _read_one_by_one(loop_twin, times)
    got = batch_twin.read_at(times)
    for name, want, have in zip(got._fields, expected, got, strict=True):
        np.testing.assert_array_equal(have, want, err_msg=name)
    # and the twins are left in the same state: the next reads agree too
    assert batch_twin.time_s == loop_twin.time_s
    np.testing.assert_array_equal(batch_twin.read()[0], loop_twin.read()[0])


def test_read_at_refuses_times_that_go_back():
    with pytest.raises(ParameterError, match="'times_s' parameter of Twin.read_at must be non-decreasing"):
        Twin().read_at([0.1, 0.05])

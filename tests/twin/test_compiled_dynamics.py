"""The twin stepped by the compiled kernel (``Twin(compiled=True)``; ``sim+paced``'s and a described digit's
default) against the numpy path it replaces: the same ROS2 step in another arithmetic order, so the oracle is the
numpy twin itself, run side by side on the same seeded, randomly generated commands, loads, presses and advance
lengths."""

import numpy as np
import pytest

from digits import DIGITS
from flexdigit.params import RigParams
from flexdigit.rig.base import open_rig
from flexdigit.twin import Twin
from flexdigit.twin.contact import Tissue

PSI_ATOL = 1e-9  # rad: tests/twin/test_batched.py's tolerance for the same kernel (measured here: < 1e-15)
VOLTS_ATOL = 1e-9  # V, noise-free gauge voltages (a few hundred mV per rad of bending)


def _pair(**kw):
    return Twin(seed=3, dt_s=0.002, **kw), Twin(seed=3, dt_s=0.002, compiled=True, **kw)


def _drive(numpy_twin, compiled_twin, seed, events=60):
    """Random commands, hung weights, presses and advance lengths (0 .. 2.5 frames, off the grid) on both twins;
    returns the largest angle and noise-free voltage differences seen after every advance."""
    rng = np.random.default_rng(seed)
    worst_psi = worst_v = 0.0
    for _ in range(events):
        action = rng.integers(0, 6)
        if action == 0:
            command = int(rng.integers(0, 70))  # slack below 8, a full-range pull at the top
            numpy_twin.command(command)
            compiled_twin.command(command)
        elif action == 1:
            mass, where = float(rng.uniform(0.005, 0.05)), float(rng.uniform(0.02, 0.27))
            numpy_twin.place_load(mass, where)
            compiled_twin.place_load(mass, where)
        elif action == 2:
            force, where = float(rng.uniform(-0.3, 0.3)), float(rng.uniform(0.02, 0.27))
            numpy_twin.press(force, where)
            compiled_twin.press(force, where)
        elif action == 3:
            numpy_twin.clear_loads()
            compiled_twin.clear_loads()
            numpy_twin.clear_presses()
            compiled_twin.clear_presses()
        duration = float(rng.uniform(0.0, 0.05))
        numpy_twin.advance(duration)
        compiled_twin.advance(duration)
        worst_psi = max(worst_psi, float(np.max(np.abs(numpy_twin.state()[0] - compiled_twin.state()[0]))))
        worst_v = max(worst_v, float(np.max(np.abs(numpy_twin.clean_read()[0] - compiled_twin.clean_read()[0]))))
    return worst_psi, worst_v


@pytest.mark.parametrize(
    "options",
    [
        {"orientation": "horizontal"},
        {"orientation": "vertical", "housing": False},  # the bare strip: lightly damped, fast transients
        {"orientation": "hanging", "cable": False},  # detached cable: the kernel's "not finite" shortening
    ],
    ids=["horizontal", "bare-vertical", "no-cable"],
)
def test_compiled_steps_like_the_numpy_twin(options):
    numpy_twin, compiled_twin = _pair(**options)
    assert compiled_twin.dynamics.compiled
    assert not numpy_twin.dynamics.compiled
    worst_psi, worst_v = _drive(numpy_twin, compiled_twin, seed=12)
    assert worst_psi <= PSI_ATOL
    assert worst_v <= VOLTS_ATOL
    # and the digit really moved: the comparison is not of two twins at rest
    assert np.max(np.abs(numpy_twin.state()[0])) > 0.01 or not options.get("cable", True)


def test_halved_steps_and_a_deflection_release():
    # a 0 -> 60 command jump on the bare strip turns links faster than 0.1 rad a step: the step is halved (the
    # compiled kernel counts its steps, more than the grid's); deflect() puts the clock off the grid (a short
    # first step, its own run in the kernel)
    numpy_twin, compiled_twin = _pair(orientation="vertical", housing=False)
    for twin in (numpy_twin, compiled_twin):
        twin.command(60)
        twin.advance(0.5)
        twin.deflect(0.05)
        twin.advance(0.3)
    steps = int(compiled_twin.dynamics._compiled_args[-1][0])
    assert steps > round(0.8 / 0.002)  # halvings happened
    assert np.max(np.abs(numpy_twin.state()[0] - compiled_twin.state()[0])) <= PSI_ATOL
    assert np.max(np.abs(numpy_twin.dynamics.omega - compiled_twin.dynamics.omega)) <= 1e3 * PSI_ATOL


def test_a_body_beside_the_digit_steps_in_numpy_bit_for_bit():
    # the kernel has no contact model: with a tissue the compiled twin takes the numpy path, the same bits
    numpy_twin, compiled_twin = _pair(orientation="horizontal")
    for twin in (numpy_twin, compiled_twin):
        twin.set_tissue(Tissue(0.15, 0.30, 0.004, 5000.0))
        twin.command(30)
        twin.advance(0.4)
    assert np.array_equal(numpy_twin.dynamics.psi, compiled_twin.dynamics.psi)


def test_noisy_readings_match_where_the_adc_does_not_round_across_a_level():
    # the same seed, the same noise: the readings differ only where a 1e-15 V difference crosses an ADC level
    numpy_twin, compiled_twin = _pair(orientation="horizontal")
    same = 0
    for k in range(100):
        for twin in (numpy_twin, compiled_twin):
            if k % 25 == 0:
                twin.command(8 + k // 5)
            twin.advance(0.02)
        (g1, p1), (g2, p2) = numpy_twin.read(), compiled_twin.read()
        same += int(np.array_equal(g1, g2) and p1 == p2)
    assert same >= 98


def test_paced_backend_steps_compiled_by_default_and_virtual_time_does_not():
    paced = open_rig("sim+paced", seed=0)
    try:
        assert paced.compiled
        assert paced.settings()["compiled"] is True
    finally:
        paced.close()
    virtual = open_rig("sim", seed=0)
    try:
        # the report's runs: numpy, bit for bit, and the settings journals were written with (no new key)
        assert not virtual.compiled
        assert not virtual.twin.dynamics.compiled
        assert "compiled" not in virtual.settings()
    finally:
        virtual.close()
    for url, expected in (("sim+paced?compiled=false", False), ("sim?compiled=true", True)):
        rig = open_rig(url, seed=0)
        try:
            assert rig.compiled is expected, url
            assert rig.twin.dynamics.compiled is expected, url
        finally:
            rig.close()


def test_a_described_digit_steps_compiled_by_default_and_the_thesis_rig_does_not():
    # issue 24's suite time: a described digit's twin steps compiled unless told not to; the thesis rig's numbers
    # are the report's (numpy, bit for bit)
    described = RigParams.from_dict(DIGITS["two-sections"])
    for url, params, expected in (
        ("sim", described, True),
        ("sim?compiled=false", described, False),
        ("sim", RigParams(), False),
        ("sim+paced?compiled=false", described, False),
    ):
        rig = open_rig(url, params, seed=0)
        try:
            assert rig.twin.dynamics.compiled is expected, url
            assert rig.compiled is expected, url
        finally:
            rig.close()
    assert Twin(described).dynamics.compiled
    assert not Twin(described, compiled=False).dynamics.compiled


def test_a_described_digits_virtual_time_run_repeats_and_follows_numpy():
    # the compiled default is deterministic on one machine (same seed, same numbers), and within PSI_ATOL of numpy
    described = RigParams.from_dict(DIGITS["four-sections-two-cables"])
    twins = [Twin(described, seed=5, dt_s=0.002, compiled=c) for c in (None, None, False)]
    for twin in twins:
        twin.command(described.actuator.equilibrium_command + 15)
        twin.advance(0.7)
    first, again, numpy_twin = (twin.state()[0] for twin in twins)
    assert np.array_equal(first, again)
    assert np.max(np.abs(first - numpy_twin)) <= PSI_ATOL


def test_the_background_load_switches_a_running_twin_over():
    twin = Twin(seed=0, dt_s=0.002)
    thread = twin.dynamics.use_compiled(background=True)
    twin.command(30)
    twin.advance(0.1)  # numpy steps meanwhile, or compiled ones once loaded: either way the digit moves on
    thread.join(120)
    assert twin.dynamics.compiled
    reference = Twin(seed=0, dt_s=0.002)
    reference.command(30)
    reference.advance(0.1)
    twin.advance(0.4)
    reference.advance(0.4)
    assert np.max(np.abs(twin.state()[0] - reference.state()[0])) <= PSI_ATOL
